//! `[robots.actuators]` in scenario files: defaults and overrides resolve
//! per joint, bad entries get errors naming file, line and key path, and
//! quad16 with its default DC motors trots `scenarios/trot.toml` (0.5 m/s)
//! and, at 1.0 m/s, where the ideal sources fall.

use std::path::Path;

use quadsim::scenario::{ScenarioError, parse_scenario};
use quadsim::summary::robot_json;
use quadsim::world::{Overrides, World, build_world};
use quadsim_engine::actuator_model::ActuatorKind;

const BASE: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.01
default_ground = "concrete"

[[robots]]
name = "rex"
model = "quad16"
[robots.controller]
kind = "joint_pd"
kp_nm_per_rad = 300.0
"#;

fn with_actuators(table: &str) -> String {
    BASE.replace(
        "[robots.controller]",
        &format!("{table}\n[robots.controller]"),
    )
}

fn build(src: &str) -> Result<World, ScenarioError> {
    let scn = parse_scenario(Path::new("act.toml"), src.to_string())?;
    build_world(&scn, Overrides::with_threads(1))
}

fn line_of(src: &str, needle: &str) -> usize {
    src[..src.find(needle).expect("needle")]
        .matches('\n')
        .count()
        + 1
}

#[test]
fn defaults_and_overrides_resolve_per_joint() {
    let src = with_actuators(
        "[robots.actuators]\nkind = \"dc_motor\"\nbandwidth_hz = 50.0\n\
         [robots.actuators.joints.\"*_knee\"]\nstall_torque_nm = 60.0\n\
         [robots.actuators.joints.LF_knee]\nkind = \"ideal\"\n",
    );
    let mut w = build(&src).unwrap();
    let root = w.robots[0].1;
    let sim = w.sim.robot_mut(root).unwrap();
    let specs = sim.workspace.actuators.as_ref().unwrap().specs().to_vec();
    let names = quadsim::summary::joint_names(&sim.model);
    for (n, s) in names.iter().zip(&specs) {
        if n == "LF_knee" {
            assert_eq!(s.kind, ActuatorKind::Ideal, "{n}");
            continue;
        }
        assert_eq!(s.kind, ActuatorKind::DcMotor, "{n}");
        assert_eq!(s.motor.bandwidth_hz, 50.0);
        // quad16's default set: effort limit 100 N·m, no-load 30/0.75 rad/s
        let stall = if n.ends_with("_knee") { 60.0 } else { 100.0 };
        assert_eq!(s.motor.stall_torque_nm, stall, "{n}");
        assert!((s.motor.no_load_speed_radps - 40.0).abs() < 1e-12);
    }
    // reflected rotor inertia J N² = 1e-4 · 10² on every motor joint
    let nv0 = sim.model.base_nv();
    let lf_knee = names.iter().position(|n| n == "LF_knee").unwrap();
    let rf_knee = names.iter().position(|n| n == "RF_knee").unwrap();
    let d = sim.model.armature[nv0 + rf_knee] - sim.model.armature[nv0 + lf_knee];
    assert!((d - 0.01).abs() < 1e-12, "{d}");
    w.sim.run(w.steps);
}

#[test]
fn bad_entries_name_file_line_and_key() {
    let cases = [
        (
            "[robots.actuators]\nkind = \"dc_motor\"\nstal_torque_nm = 3.0\n",
            "stal_torque_nm",
            "robots[0].actuators.stal_torque_nm",
            "unknown actuator key",
        ),
        (
            "[robots.actuators]\nkind = \"stepper\"\n",
            "kind = \"stepper\"",
            "robots[0].actuators.kind",
            "unknown actuator kind",
        ),
        (
            "[robots.actuators]\nkind = \"dc_motor\"\nstall_torque_nm = -1.0\n",
            "stall_torque_nm",
            "robots[0].actuators.stall_torque_nm",
            "must be > 0",
        ),
        (
            "[robots.actuators]\nkind = \"dc_motor\"\n[robots.actuators.joints.LF_kne]\ncoulomb_nm = 1.0\n",
            "[robots.actuators.joints.LF_kne]",
            "robots[0].actuators.joints.LF_kne",
            "names no joint",
        ),
        (
            "[robots.actuators]\nkind = \"dc_motor\"\n[robots.actuators.joints.LF_knee]\nlatency_ticks = 1.5\n",
            "latency_ticks",
            "robots[0].actuators.joints.LF_knee.latency_ticks",
            "integer",
        ),
        (
            "[robots.actuators]\nkind = \"dc_motor\"\ngear_ratio = 0.5\n",
            "gear_ratio",
            "robots[0].actuators.gear_ratio",
            "≥ 1",
        ),
    ];
    for (table, needle, key, msg) in cases {
        let src = with_actuators(table);
        let e = build(&src).expect_err(table);
        assert_eq!(e.key_path, key, "{e}");
        assert_eq!(e.line, line_of(&src, needle), "{e}");
        assert!(e.message.contains(msg), "{e}");
        assert!(e.to_string().starts_with("act.toml:"), "{e}");
    }
}

#[test]
fn hybrid_prescribed_rejects_motor_actuators() {
    let src = std::fs::read_to_string("scenarios/small_trot.toml")
        .unwrap()
        .replace(
            "[robots.controller]",
            "[robots.actuators]\nkind = \"servo\"\n\n[robots.controller]",
        );
    let e = build(&src).expect_err("hybrid + servo");
    assert_eq!(e.key_path, "robots[0].actuators");
    assert!(e.message.contains("mode = \"pd\""), "{e}");
}

/// quad16's default DC motors (100 N·m stall, 40 rad/s no-load, reflected
/// rotor inertia, friction, 100 Hz lag) carry `trot.toml`'s 0.5 m/s trot
/// for 10 s as the ideal sources do: no fall, the same speed within 5 %,
/// the motors applied torques inside their envelopes.
#[test]
fn quad16_trots_on_its_default_dc_motors() {
    let base = std::fs::read_to_string("scenarios/trot.toml").unwrap();
    let mut out = Vec::new();
    for kind in ["ideal", "dc_motor"] {
        let src = base.replace(
            "[robots.controller]",
            &format!("[robots.actuators]\nkind = \"{kind}\"\n\n[robots.controller]"),
        );
        let mut w = build(&src).unwrap();
        w.sim.run(w.steps);
        let (name, root) = w.robots[0].clone();
        out.push(robot_json(&name, w.sim.robot(root).unwrap()));
    }
    let (ideal, dc) = (&out[0], &out[1]);
    let (vi, vd) = (
        ideal["mean_forward_speed_mps"].as_f64().unwrap(),
        dc["mean_forward_speed_mps"].as_f64().unwrap(),
    );
    println!("trot.toml: ideal {vi:.4} m/s, dc_motor {vd:.4} m/s");
    assert_eq!(dc["fell"], false);
    assert!((vd - vi).abs() < 0.05 * vi, "{vi} vs {vd}");
    for j in dc["actuators"]["joints"].as_array().unwrap() {
        assert_eq!(j["kind"], "dc_motor");
        assert!(j["peak_torque_nm"].as_f64().unwrap() <= 100.0 + 1e-9);
    }
}

/// The kinds a scenario gets without `[robots.actuators]`: quad16 its DC
/// motors, quad12 (and any model) ideal sources, and quad16 under the
/// prescribed controller's hybrid mode (which imposes the motion) ideal.
#[test]
fn default_kind_is_per_model() {
    let kinds = |src: &str| -> Option<Vec<ActuatorKind>> {
        let mut w = build(src).unwrap();
        let root = w.robots[0].1;
        let sim = w.sim.robot_mut(root).unwrap();
        sim.workspace
            .actuators
            .as_ref()
            .map(|a| a.specs().iter().map(|s| s.kind).collect())
    };
    let q16 = kinds(BASE).expect("quad16 gets motors");
    assert_eq!(q16.len(), 16);
    assert!(q16.iter().all(|k| *k == ActuatorKind::DcMotor), "{q16:?}");
    assert_eq!(
        kinds(&with_actuators("[robots.actuators]\nkind = \"ideal\"\n")),
        None
    );
    let q12 = BASE
        .replace("model = \"quad16\"", "model = \"quad12\"")
        .replace("kp_nm_per_rad = 300.0", "kp_nm_per_rad = 3.0");
    assert_eq!(kinds(&q12), None);
    let hybrid = std::fs::read_to_string("scenarios/small_trot.toml")
        .unwrap()
        .replace("model = \"quad12\"", "model = \"quad16\"");
    assert_eq!(kinds(&hybrid), None);
}

/// `trot.toml` commanded `v_x_mps`, with the start moved `dx_m` along x and
/// `table` (TOML lines) as its `[robots.actuators]`: (fell, mean forward speed).
fn trot_at(v_x_mps: f64, dx_m: f64, table: &str) -> (bool, f64) {
    let src = std::fs::read_to_string("scenarios/trot.toml")
        .unwrap()
        .replace("v_x_mps = 0.5", &format!("v_x_mps = {v_x_mps}"))
        .replace(
            "model = \"quad16\"",
            &format!("model = \"quad16\"\nstart_xy_m = [{dx_m}, 0.0]"),
        )
        .replace(
            "[robots.controller]",
            &format!("[robots.actuators]\n{table}\n\n[robots.controller]"),
        );
    let mut w = build(&src).unwrap();
    w.sim.run(w.steps);
    let (name, root) = w.robots[0].clone();
    let j = robot_json(&name, w.sim.robot(root).unwrap());
    (
        j["fell"].as_bool().unwrap(),
        j["mean_forward_speed_mps"].as_f64().unwrap(),
    )
}

/// Why quad16's default is its DC motor: at 1.0 m/s Study A's trot holds on
/// the motors, and falls at least as often on ideal sources. The runs are
/// chaotic, so three micrometre neighbours of the start stand for the
/// scenario (measured before the estimator compensated the base's
/// acceleration: ideal 6 of 6 fall, motors 1 of 6; after, 2026-11-29:
/// ideal 1 of 3, motors 0 of 3; `docs/actuators.md`); asserted: at most
/// one of three falls on the motors, the others within 10 % of the
/// command, and no more motor runs fall than ideal ones.
#[test]
fn quad16_trots_at_one_metre_per_second_on_its_motors_at_least_as_well_as_on_ideal_sources() {
    let dxs = [3e-6, 6e-6, 9e-6];
    let motor: Vec<_> = dxs
        .iter()
        .map(|dx| trot_at(1.0, *dx, "kind = \"dc_motor\""))
        .collect();
    let ideal: Vec<_> = dxs
        .iter()
        .map(|dx| trot_at(1.0, *dx, "kind = \"ideal\""))
        .collect();
    println!("1.0 m/s, (fell, mean speed): motors {motor:?}, ideal {ideal:?}");
    let falls = |runs: &[(bool, f64)]| runs.iter().filter(|r| r.0).count();
    assert!(falls(&motor) <= 1, "{motor:?}");
    for r in motor.iter().filter(|r| !r.0) {
        assert!((r.1 - 1.0).abs() < 0.1, "{motor:?}");
    }
    assert!(
        falls(&motor) <= falls(&ideal),
        "motors {motor:?}, ideal {ideal:?}"
    );
}

/// The table of `docs/actuators.md` ("Defaults"): falls out of six
/// neighbours, per actuator variant, at 1.0 m/s.
/// `cargo test --release --test actuator_scenarios motor_robustness_table -- --ignored --nocapture`
#[test]
#[ignore = "prints the table of docs/actuators.md (60 runs of 10 s)"]
fn motor_robustness_table() {
    for (label, table) in [
        ("ideal", "kind = \"ideal\""),
        ("default motors", "kind = \"dc_motor\""),
        ("no rotor inertia", "rotor_inertia_kgm2 = 0.0"),
        ("no viscous friction", "viscous_nms_per_rad = 0.0"),
        ("no Coulomb friction", "coulomb_nm = 0.0"),
        ("no torque lag", "bandwidth_hz = 100000.0"),
        ("no speed envelope", "no_load_speed_radps = 100000.0"),
    ] {
        let falls = (1..=6)
            .filter(|d| trot_at(1.0, 3e-6 * *d as f64, table).0)
            .count();
        println!("| {label} | {falls} of 6 fall |");
    }
}
