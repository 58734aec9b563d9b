//! Study B's experiment through the whole pipeline: `scenarios/small_trot.toml`
//! (quad12, `prescribed` controller in hybrid mode, 5 s on concrete) walks
//! forward stably. Prints Study B's Table 3 quantities (displacement, mean
//! speed and oscillation of the CoM per axis), the stability margin and the
//! Table 4 torque comparison, which `docs/study_b_trot.md` quotes.

use std::path::Path;

use glam::DVec2;
use quadsim::scenario::load_scenario;
use quadsim::world::{Overrides, build_world};
use quadsim_components::Controller;
use quadsim_engine::spatial::rpy_from_rot;
use quadsim_engine::support::stability_margin;

/// Least-squares line through `(t, x)`: returns (slope, residual half range).
fn trend_and_oscillation(t: &[f64], x: &[f64]) -> (f64, f64) {
    let n = t.len() as f64;
    let (mt, mx) = (t.iter().sum::<f64>() / n, x.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (ti, xi) in t.iter().zip(x) {
        sxy += (ti - mt) * (xi - mx);
        sxx += (ti - mt) * (ti - mt);
    }
    let slope = sxy / sxx;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (ti, xi) in t.iter().zip(x) {
        let r = xi - mx - slope * (ti - mt);
        lo = lo.min(r);
        hi = hi.max(r);
    }
    (slope, 0.5 * (hi - lo))
}

/// quad12 trots forward for 5 s without falling: mean forward speed at
/// least 60 mm/s (Study B: 93 mm/s; the nominal speed of the prescribed
/// stroke is 93.3 mm/s, and feet slip a little at touchdown), roll and pitch
/// within ±0.1 rad, heading within ±0.1 rad, and Study B's torque comparison
/// sampled at every controller tick after the ramp (4 legs × 2249 ticks).
#[test]
fn quad12_trots_forward_as_in_study_b() {
    let scn = load_scenario(Path::new("scenarios/small_trot.toml")).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(1)).unwrap();
    let root = w.robots[0].1;
    let (mut t, mut com) = (Vec::new(), Vec::new());
    let (mut margin3_min, mut margin3_sum, mut margin3_n) = (f64::INFINITY, 0.0, 0);
    let (mut line_max, mut line_sum, mut line_n): (f64, f64, usize) = (0.0, 0.0, 0);
    for _ in 0..w.steps {
        w.sim.step();
        let obs = &w.sim.robot(root).unwrap().run.observation;
        t.push(obs.t_s);
        com.push(obs.com_m);
        let feet: Vec<DVec2> = obs
            .feet
            .iter()
            .filter(|f| f.in_contact)
            .map(|f| f.position_m.truncate())
            .collect();
        let c = obs.com_m.truncate();
        if feet.len() >= 3 {
            if let Some(m) = stability_margin(&feet, c) {
                margin3_min = margin3_min.min(m);
                margin3_sum += m;
                margin3_n += 1;
            }
        } else if feet.len() == 2 {
            // two-foot support: distance of the CoM from the support line
            let d = (feet[1] - feet[0]).normalize();
            let off = (c - feet[0]).perp_dot(d).abs();
            line_max = line_max.max(off);
            line_sum += off;
            line_n += 1;
        }
    }
    let sim = w.sim.robot(root).unwrap();
    let m = sim.run.metrics.summary();
    let axes = ["x", "y", "z"];
    for (k, axis) in axes.iter().enumerate() {
        let x: Vec<f64> = com.iter().map(|p| p[k]).collect();
        let (slope, osc) = trend_and_oscillation(&t, &x);
        let disp = x[x.len() - 1] - x[0];
        eprintln!(
            "CoM {axis}: displacement {:.1} mm, mean speed {:.2} mm/s, oscillation ±{:.2} mm",
            disp * 1e3,
            slope * 1e3,
            osc * 1e3
        );
    }
    eprintln!(
        "stability margin (≥ 3 feet, {margin3_n} steps): min {:.1} mm, mean {:.1} mm; CoM off the support line in two-foot support ({line_n} steps): mean {:.1} mm, max {:.1} mm",
        margin3_min * 1e3,
        margin3_sum / margin3_n.max(1) as f64 * 1e3,
        line_sum / line_n.max(1) as f64 * 1e3,
        line_max * 1e3
    );
    let Controller::Prescribed(p) = &sim.run.controller else {
        panic!("prescribed controller expected");
    };
    let c = p
        .study_b
        .expect("quad12 in hybrid mode compares with Study B");
    eprintln!("Study B torques: {c:#?}");
    eprintln!(
        "peak ratio sim/model (hip, knee) {:?}, mean ratio {:?}",
        c.peak_ratio(),
        c.mean_ratio()
    );
    let rpy = rpy_from_rot(sim.run.observation.base.rot);
    assert!(!m.fell, "fell at {:?}", m.fell_at_s);
    assert!(
        m.mean_forward_speed_mps > 0.06,
        "mean forward speed {} m/s",
        m.mean_forward_speed_mps
    );
    for (what, r) in [("roll", m.roll_range_rad), ("pitch", m.pitch_range_rad)] {
        assert!(r[0] > -0.1 && r[1] < 0.1, "{what} range {r:?}");
    }
    assert!(rpy.z.abs() < 0.1, "heading {} rad", rpy.z);
    // one sample per leg on every 4th step (500 Hz) whose start is after the 0.5 s ramp
    let ticks = (0..w.steps)
        .filter(|k| k % 4 == 0 && *k as f64 * w.dt_s > 0.5)
        .count() as u64;
    assert_eq!(c.sim_hip.samples, 4 * ticks);
}

/// Bad `prescribed` keys are named with their line: an unknown mode, a duty
/// factor outside (0, 1), a key of another controller kind, and a gain list
/// of the wrong length.
#[test]
fn prescribed_keys_are_validated_with_line_and_key() {
    use quadsim::scenario::parse_scenario;
    let good = "format_version = 1\n[world]\nduration_s = 0.01\ndefault_ground = \"concrete\"\n[[robots]]\nname = \"bee\"\nmodel = \"quad12\"\n[robots.controller]\nkind = \"prescribed\"\nperiod_s = 0.5\n";
    let build = |src: String| {
        let scn = parse_scenario(Path::new("bad.toml"), src)?;
        build_world(&scn, Overrides::default()).map(|_| ())
    };
    build(good.to_string()).expect("the good file builds");
    for (extra, key, line) in [
        ("mode = \"fast\"\n", "robots[0].controller.mode", 11),
        (
            "duty_factor = 1.5\n",
            "robots[0].controller.duty_factor",
            11,
        ),
        ("v_x_mps = 1.0\n", "robots[0].controller.v_x_mps", 11),
        (
            "kp_nm_per_rad = [1.0, 2.0]\n",
            "robots[0].controller.kp_nm_per_rad",
            11,
        ),
    ] {
        let e = build(format!("{good}{extra}")).expect_err(extra);
        assert_eq!(e.key_path, key, "{e}");
        assert_eq!(e.line, line, "{e}");
        assert!(e.to_string().starts_with("bad.toml:11:"), "{e}");
    }
}

/// PD mode (stiff joint PD toward the same reference, saturated, at a
/// 2 kHz controller rate) also walks the 5 s forward: no fall, mean forward
/// speed above 40 mm/s, roll and pitch within ±0.1 rad. (At 500 Hz the
/// sampled PD excites the stance legs' mode on the contact spring, about
/// 140 Hz, and chatters: see docs/study_b_trot.md.)
#[test]
fn quad12_trots_under_prescribed_pd() {
    use quadsim::scenario::parse_scenario;
    let text = std::fs::read_to_string("scenarios/small_trot.toml")
        .unwrap()
        .replace("mode = \"hybrid\"", "mode = \"pd\"")
        .replace("controller_rate_hz = 500", "controller_rate_hz = 2000");
    let scn = parse_scenario(Path::new("small_trot_pd.toml"), text).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(1)).unwrap();
    w.sim.run(w.steps);
    let m = w.sim.robot(w.robots[0].1).unwrap().run.metrics.summary();
    eprintln!(
        "pd: mean speed {:.4} m/s, joint RMS {:?} rad, roll {:?}, pitch {:?}",
        m.mean_forward_speed_mps, m.joint_rms_error_rad, m.roll_range_rad, m.pitch_range_rad
    );
    assert!(!m.fell, "fell at {:?}", m.fell_at_s);
    assert!(
        m.mean_forward_speed_mps > 0.04,
        "{}",
        m.mean_forward_speed_mps
    );
    for (what, r) in [("roll", m.roll_range_rad), ("pitch", m.pitch_range_rad)] {
        assert!(r[0] > -0.1 && r[1] < 0.1, "{what} range {r:?}");
    }
}
