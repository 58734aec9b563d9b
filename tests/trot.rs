//! quad16 trots through the whole pipeline (scenario → ECS world → walking
//! controller → metrics): `scenarios/trot.toml` at 0.5 m/s for 10 s does not
//! fall, keeps its attitude within ±0.1 rad and tracks the commanded speed
//! (the command ramps from rest at 1 m/s², so the 10 s mean lags by ≤ 0.25 s
//! of travel: within 10 %).

use std::path::Path;

use quadsim::scenario::load_scenario;
use quadsim::world::{Overrides, World, build_world};
use quadsim_engine::metrics::MetricsSummary;

/// The scenario file's world, on one thread.
fn world(path: &str) -> World {
    build_world(
        &load_scenario(Path::new(path)).unwrap(),
        Overrides::with_threads(1),
    )
    .unwrap()
}

/// Roll and pitch stayed inside ±`bound_rad`.
fn assert_attitude_within(m: &MetricsSummary, bound_rad: f64) {
    for (what, r) in [("roll", m.roll_range_rad), ("pitch", m.pitch_range_rad)] {
        assert!(r[0] > -bound_rad && r[1] < bound_rad, "{what} range {r:?}");
    }
}

/// Runs the scenario file's whole duration and checks its one robot did
/// not fall, trotted at a mean forward speed within `tol_mps` of `v_mps`,
/// and kept roll and pitch inside ±`attitude_rad`; returns its metrics.
fn trots_whole_run(path: &str, v_mps: f64, tol_mps: f64, attitude_rad: f64) -> MetricsSummary {
    let mut w = world(path);
    w.sim.run(w.steps);
    let m = w.sim.robot(w.robots[0].1).unwrap().run.metrics.summary();
    assert!(!m.fell, "fell at {:?}", m.fell_at_s);
    assert!(
        (m.mean_forward_speed_mps - v_mps).abs() <= tol_mps,
        "mean speed {}",
        m.mean_forward_speed_mps
    );
    assert_attitude_within(&m, attitude_rad);
    m
}

#[test]
fn quad16_trots_at_half_a_metre_per_second() {
    let m = trots_whole_run("scenarios/trot.toml", 0.5, 0.05, 0.1);
    assert!(m.steps > 60, "{} touchdowns in 10 s of trotting", m.steps);
}

/// Study A's *reported* mean speed with Study A's timing, on quad16's default
/// DC motors: `scenarios/trot_study_mean.toml` commands 1.2 m/s with
/// Raibert's speed gain at 0.05 s (the capture-point default, 0.226 s, falls
/// within 5 s at this speed). Over 10 s it does not fall, its mean forward
/// speed (ramped from rest at 1 m/s², so ≤ 0.072 m/s below the command) is
/// within 10 % of 1.2 m/s, and roll and pitch stay inside Study A's ±0.2 rad.
/// In 12 of 13 micrometre neighbours of the start it holds too
/// (docs/walking.md); this checks the nominal start.
#[test]
fn quad16_trots_at_study_a_reported_mean_speed() {
    trots_whole_run("scenarios/trot_study_mean.toml", 1.2, 0.12, 0.2);
}

/// Study A's experiment, `scenarios/trot_flat.toml`: commanded 1.5 m/s with
/// Study A's timing and VMC gains, on quad16's default DC motors and its
/// sensed state. The criterion: no fall over 10 s and a mean forward
/// speed of at least 1.0 m/s over t ∈ [3, 10] s (the CoM's displacement along
/// the start heading, x); roll and pitch inside Study A's ±0.2 rad. It does
/// not reach the 1.5 m/s target: it trots at about 1.2 m/s (Study A reported
/// 1.2 m/s), see docs/walking.md.
#[test]
fn trot_flat_holds_study_a_command_for_ten_seconds() {
    let mut w = world("scenarios/trot_flat.toml");
    let dt_s = w.sim.world.resource::<quadsim_components::SimConfig>().dt_s;
    let steps_3s = (3.0 / dt_s).round() as u64;
    assert!(w.steps > steps_3s, "the scenario runs {} steps", w.steps);
    let id = w.robots[0].1;
    w.sim.run(steps_3s);
    let x3 = w.sim.robot(id).unwrap().run.observation.com_m.x;
    w.sim.run(w.steps - steps_3s);
    let r = &w.sim.robot(id).unwrap().run;
    let x10 = r.observation.com_m.x;
    let m = r.metrics.summary();
    assert!(!m.fell, "fell at {:?}", m.fell_at_s);
    let mean_mps = (x10 - x3) / (w.steps - steps_3s) as f64 / dt_s;
    assert!(mean_mps >= 1.0, "mean speed over [3, 10] s {mean_mps} m/s");
    assert_attitude_within(&m, 0.2);
}
