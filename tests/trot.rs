//! quad16 trots through the whole pipeline (scenario → ECS world → walking
//! controller → metrics): `scenarios/trot.toml` at 0.5 m/s for 10 s does not
//! fall, keeps its attitude within ±0.1 rad and tracks the commanded speed
//! (the command ramps from rest at 1 m/s², so the 10 s mean lags by ≤ 0.25 s
//! of travel: within 10 %).

use std::path::Path;

use quadsim::scenario::load_scenario;
use quadsim::world::{Overrides, build_world};

#[test]
fn quad16_trots_at_half_a_metre_per_second() {
    let scn = load_scenario(Path::new("scenarios/trot.toml")).unwrap();
    let mut w = build_world(
        &scn,
        Overrides {
            threads: 1,
            ..Default::default()
        },
    )
    .unwrap();
    w.sim.run(w.steps);
    let m = w.sim.robot(w.robots[0].1).unwrap().run.metrics.summary();
    assert!(!m.fell, "fell at {:?}", m.fell_at_s);
    assert!(
        (m.mean_forward_speed_mps - 0.5).abs() <= 0.05,
        "mean speed {}",
        m.mean_forward_speed_mps
    );
    for (what, r) in [("roll", m.roll_range_rad), ("pitch", m.pitch_range_rad)] {
        assert!(r[0] > -0.1 && r[1] < 0.1, "{what} range {r:?}");
    }
    assert!(m.steps > 60, "{} touchdowns in 10 s of trotting", m.steps);
}
