//! Payloads through the scenario pipeline: attached at start, the model
//! carries the extra mass exactly; `attach`/`detach` events change it between
//! steps at their times, and the walking controller's gravity compensation
//! follows when the payload is known to it; a trotting quad16 carrying 10 kg
//! keeps walking; bad payload input names its key.

use std::path::Path;

use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, build_world};
use quadsim_components::Controller;

const TROT: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = DURATION
seed = 1
controller_rate_hz = 500
default_ground = "concrete"

[[robots]]
name = "rex"
model = "quad16"
contact_points = ["knees", "torso"]
[robots.controller]
kind = "vmc"
period_s = 0.5
four_leg_support_s = 0.1
two_leg_support_s = 0.15
v_x_mps = 0.5
height_m = 0.5
"#;

fn scenario(duration_s: f64, extra: &str) -> String {
    TROT.replace("DURATION", &duration_s.to_string()) + extra
}

const BOX: &str = r#"
[[robots.payloads]]
name = "box"
mass_kg = 10.0
size_m = [0.3, 0.2, 0.1]
offset_m = [0.0, 0.0, 0.1]
"#;

#[test]
fn a_trotting_quad16_carrying_ten_kilograms_keeps_walking() {
    let scn = parse_scenario(Path::new("p.toml"), scenario(10.0, BOX)).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(1)).unwrap();
    let rex = w.robots[0].1;
    let bare = quadsim_engine::robots::builtin("quad16").unwrap();
    let bare =
        quadsim_engine::Model::from_description(&bare, quadsim_engine::model::BaseKind::Floating)
            .unwrap();
    let r = w.sim.robot(rex).unwrap();
    assert!((r.model.total_mass - bare.total_mass - 10.0).abs() < 1e-12);
    let Controller::Walker(walker) = &r.run.controller else {
        panic!("vmc")
    };
    assert_eq!(walker.payload_mass_kg(), 10.0);
    w.sim.run(w.steps);
    let m = w.sim.robot(rex).unwrap().run.metrics.summary();
    assert!(!m.fell, "fell at {:?}", m.fell_at_s);
    assert!(
        m.mean_forward_speed_mps >= 0.4,
        "mean speed {}",
        m.mean_forward_speed_mps
    );
}

#[test]
fn attach_and_detach_events_change_the_model_at_their_times() {
    for known in [true, false] {
        let payload = BOX.replace(
            "offset_m = [0.0, 0.0, 0.1]",
            &format!("offset_m = [0.0, 0.0, 0.1]\nattached = false\nknown_to_controller = {known}"),
        );
        let events = "\n[[events]]\nt_s = 0.25\nrobot = \"rex\"\nkind = \"attach\"\npayload = \"box\"\n\
                      \n[[events]]\nt_s = 0.5\nrobot = \"rex\"\nkind = \"detach\"\npayload = \"box\"\n";
        let src = scenario(0.75, &(payload + events));
        let scn = parse_scenario(Path::new("p.toml"), src).unwrap();
        let mut w = build_world(&scn, Overrides::with_threads(1)).unwrap();
        let rex = w.robots[0].1;
        let mass = |w: &quadsim::world::World| {
            let r = w.sim.robot(rex).unwrap();
            let Controller::Walker(c) = &r.run.controller else {
                panic!("vmc")
            };
            (
                r.model.total_mass,
                c.payload_mass_kg(),
                r.run.metrics.summary().steps,
            )
        };
        let (m0, c0, _) = mass(&w);
        w.sim.run(499); // t = 0.2495 s: not yet
        assert_eq!(mass(&w).0, m0);
        w.sim.run(2); // the step starting at 0.25 s carries it
        let (m1, c1, steps1) = mass(&w);
        assert!((m1 - m0 - 10.0).abs() < 1e-12, "{m1} vs {m0}");
        assert_eq!(c1 - c0, if known { 10.0 } else { 0.0 });
        w.sim.run(500);
        let (m2, c2, steps2) = mass(&w);
        assert_eq!(m2, m0);
        assert_eq!(c2, c0);
        // the controller and metrics went on across both recompiles
        assert!(steps2 > steps1, "touchdowns {steps1} → {steps2}");
    }
}

#[test]
fn bad_payloads_name_their_key() {
    for (payload, key) in [
        (
            BOX.replace("size_m = [0.3, 0.2, 0.1]", "size_m = [0.3, 0.2]"),
            "robots[0].payloads[0].size_m",
        ),
        (
            BOX.replace("mass_kg = 10.0", "mass_kg = -2.0"),
            "robots[0].payloads[0].mass_kg",
        ),
        (
            BOX.replace("name = \"box\"", "name = \"box\"\nshape = \"torus\""),
            "robots[0].payloads[0].shape",
        ),
        (
            BOX.to_string()
                + "\n[[events]]\nt_s = 1.0\nrobot = \"rex\"\nkind = \"detach\"\npayload = \"crate\"\n",
            "events[0].payload",
        ),
    ] {
        let scn = parse_scenario(Path::new("p.toml"), scenario(1.0, &payload)).unwrap();
        let e = build_world(&scn, Overrides::default()).unwrap_err();
        assert_eq!(e.key_path, key, "{e}");
        assert!(e.line > 0, "{e}");
    }
}

#[test]
fn an_impossible_load_is_reported_not_carried_with_its_reason() {
    // 60 kg on a 28 kg robot whose joints give at most 40 N·m
    let dir = std::env::temp_dir().join(format!("quadsim-payload-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = scenario(3.0, &BOX.replace("mass_kg = 10.0", "mass_kg = 60.0")).replace(
        "model = \"quad16\"\n",
        "model = \"quad16\"\nparams = { \"actuator.effort_limit_nm\" = 40.0 }\n",
    );
    std::fs::write(dir.join("heavy.toml"), src).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(["run", "heavy.toml", "--quiet", "--no-log", "--out", "out"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    let r = &s["robots"][0];
    assert_eq!(r["load"]["carried"], false, "{}", r["load"]);
    let reason = r["load"]["reason"].as_str().unwrap();
    assert!(["fell", "saturated"].contains(&reason), "{reason}");
    assert!((r["total_mass_kg"].as_f64().unwrap() - 88.0).abs() < 1e-9);
    // quad16's default DC motors: the demand meets their torque–speed
    // envelope (the stall torque, 40 N·m, at zero speed) before it reaches
    // the effort limit, and their lag lets the applied torque approach the
    // limit without quite reaching it
    let a = &r["actuators"];
    let at_limit = a["max_time_share_at_torque_limit"].as_f64().unwrap()
        + a["max_time_share_at_envelope_limit"].as_f64().unwrap();
    assert!(at_limit > 0.05, "{a}");
    assert!(
        a["max_peak_torque_share"].as_f64().unwrap() > 1.0 - 1e-9,
        "{a}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
