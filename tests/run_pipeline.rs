//! The scenario → world → run pipeline: determinism (thread count, robot order,
//! repeated runs), metrics through the whole pipeline on known answers, and
//! errors that name the key path for values only the model can judge.

use std::path::Path;
use std::process::Command;

use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, build_world};

fn herd(order: &[&str], threads: usize) -> Vec<(String, Vec<u64>)> {
    let mut src = String::from(
        r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.5
controller_rate_hz = 2000
seed = 7
default_ground = "grass"

[[terrains]]
name = "bumps"
kind = "rough"
amplitude_m = 0.02
cell_m = 0.3
noise = "smooth"
extent_m = [30.0, 30.0]
"#,
    );
    for name in order {
        let x = match *name {
            "a" => 0.0,
            "b" => 2.0,
            "c" => 4.0,
            "d" => 6.0,
            "e" => 8.0,
            _ => 10.0,
        };
        src += &format!(
            "\n[[robots]]\nname = \"{name}\"\nmodel = \"quad16\"\nterrain = \"bumps\"\nstart_position_m = [{x}, 0.0, 0.62]\n[robots.controller]\nkind = \"joint_pd\"\nbandwidth_hz = 3.0\n"
        );
    }
    let scn = parse_scenario(Path::new("herd.toml"), src).unwrap();
    let mut w = build_world(
        &scn,
        Overrides {
            threads,
            ..Default::default()
        },
    )
    .unwrap();
    w.sim.run(w.steps);
    let mut out: Vec<(String, Vec<u64>)> = w
        .robots
        .iter()
        .map(|(n, e)| {
            let r = w.sim.robot(*e).unwrap();
            let bits = r
                .state
                .q
                .iter()
                .chain(&r.state.v)
                .map(|x| x.to_bits())
                .collect();
            (n.clone(), bits)
        })
        .collect();
    out.sort();
    out
}

#[test]
fn results_do_not_depend_on_threads_or_robot_order() {
    let names = ["a", "b", "c", "d", "e", "f"];
    let reference = herd(&names, 1);
    assert_eq!(herd(&names, 2), reference, "2 threads");
    assert_eq!(herd(&names, 3), reference, "3 threads");
    let reversed: Vec<&str> = names.iter().rev().copied().collect();
    assert_eq!(herd(&reversed, 2), reference, "reversed order");
}

#[test]
fn summary_is_identical_across_runs_but_timing() {
    let exe = env!("CARGO_BIN_EXE_quadsim");
    let dir = std::env::temp_dir().join(format!("quadsim-det-{}", std::process::id()));
    let mut outs = Vec::new();
    for (k, threads) in [(0, "1"), (1, "2")] {
        let out = dir.join(format!("run{k}"));
        let st = Command::new(exe)
            .args([
                "run",
                "scenarios/stand.toml",
                "--duration",
                "1",
                "--quiet",
                "--threads",
                threads,
                "--out",
            ])
            .arg(&out)
            .status()
            .unwrap();
        assert!(st.success());
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert!(v["timing"]["wall_time_s"].as_f64().unwrap() > 0.0);
        v.as_object_mut().unwrap().remove("timing");
        outs.push(v);
    }
    assert_eq!(outs[0], outs[1]);
    assert_eq!(outs[0]["steps"], 2000);
    assert_eq!(outs[0]["scenario_sha256"].as_str().unwrap().len(), 64);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_body_moving_at_one_metre_per_second_reports_speed_one() {
    // Zero gravity, no ground: the robot coasts; its CoM moves at exactly the
    // start velocity along the start heading (30°), whatever its limp joints do.
    let src = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 2.0
gravity_mps2 = [0.0, 0.0, 0.0]
default_ground = "concrete"
default_ground_height_m = -100.0

[[robots]]
name = "coaster"
model = "quad16"
start_yaw_deg = 30.0
start_position_m = [0.0, 0.0, 100.6]
"#;
    let scn = parse_scenario(Path::new("coast.toml"), src.to_string()).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(1)).unwrap();
    let root = w.robots[0].1;
    {
        // base velocity in the base frame: 1 m/s along the base's own x (= heading)
        let r = w.sim.robot_mut(root).unwrap();
        r.state.v[0] = 1.0;
    }
    w.sim.run(w.steps);
    let m = w.sim.robot(root).unwrap().run.metrics.summary();
    assert!(
        (m.mean_forward_speed_mps - 1.0).abs() < 1e-9,
        "{}",
        m.mean_forward_speed_mps
    );
    assert!(
        (m.distance_m - (2.0 - 0.0005)).abs() < 1e-6,
        "{}",
        m.distance_m
    );
}

#[test]
fn model_errors_name_the_key_path() {
    let base = "format_version = 1\n[world]\nduration_s = 1.0\ndefault_ground = \"concrete\"\n[[robots]]\nname = \"r\"\n";
    let err = |extra: &str| {
        let scn = parse_scenario(Path::new("m.toml"), format!("{base}{extra}")).unwrap();
        build_world(&scn, Overrides::default()).unwrap_err()
    };
    let e = err("model = \"quad99\"\n");
    assert_eq!(e.key_path, "robots[0].model");
    assert!(
        e.message.contains("quad99") && e.message.contains("quad16"),
        "{e}"
    );
    let e = err("model = \"quad16\"\nparams = { \"torso.mass_kg\" = -3.0 }\n");
    assert_eq!(e.key_path, "robots[0].params.\"torso.mass_kg\"", "{e}");
    assert_eq!(e.line, 8, "{e}");
    let e = err("model = \"quad16\"\nparams = { \"thigh.lenght_m\" = 0.3 }\n");
    assert!(
        e.message.contains("thigh.length_m"),
        "suggests the right path: {e}"
    );
    let e = err("model = \"quad16\"\nstart_joints_rad = [0.0, 0.1]\n");
    assert_eq!(e.key_path, "robots[0].start_joints_rad");
}

#[test]
fn check_accepts_shipped_scenarios_and_rejects_bad_ones() {
    let exe = env!("CARGO_BIN_EXE_quadsim");
    let ok = Command::new(exe)
        .args(["check", "scenarios/stand.toml"])
        .output()
        .unwrap();
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let dir = std::env::temp_dir().join(format!("quadsim-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "format_version = 1\n[world]\nduration_s = -1.0\n").unwrap();
    let out = Command::new(exe).arg("check").arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("bad.toml:3:14: world.duration_s"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn check_warns_about_unstable_contact_at_a_large_step() {
    // mud is soft; at dt = 5 ms the normal spring's ω·dt on a foot's share of
    // the robot exceeds the explicit-integration bound
    let exe = env!("CARGO_BIN_EXE_quadsim");
    let dir = std::env::temp_dir().join(format!("quadsim-warn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("coarse.toml");
    std::fs::write(
        &f,
        "format_version = 1\n[world]\ndt_s = 0.005\ncontroller_rate_hz = 200\nduration_s = 1.0\ndefault_ground = \"concrete\"\n[[robots]]\nname = \"r\"\nmodel = \"quad16\"\n",
    )
    .unwrap();
    let out = Command::new(exe).arg("check").arg(&f).output().unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}
