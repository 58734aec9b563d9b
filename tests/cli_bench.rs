//! `quadsim bench` end to end: a tiny configuration writes its figures as
//! JSON, with throughput and the counted memory per robot.

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs `quadsim bench ARGS --json FILE` in a fresh temporary directory
/// named after `tag`, and asserts it succeeded: (the directory, the JSON
/// file, the output).
fn bench(tag: &str, args: &[&str]) -> (PathBuf, PathBuf, Output) {
    let dir = std::env::temp_dir().join(format!("quadsim-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("bench.json");
    let out = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .arg("bench")
        .args(args)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (dir, json, out)
}

#[test]
fn bench_reports_throughput_and_memory_per_robot() {
    let (dir, json, out) = bench(
        "bench",
        &[
            "--robots",
            "1,4",
            "--threads",
            "1,2",
            "--steps",
            "20",
            "--repeats",
            "1",
            "--warmup",
            "10",
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("robot-steps/s"), "{stdout}");
    // the last line is JSON with the keys, for the last configuration
    let last: serde_json::Value =
        serde_json::from_str(stdout.lines().last().unwrap()).expect("last line is JSON");
    assert_eq!(last["robots"], 4, "{last}");
    assert_eq!(last["threads"], 2, "{last}");
    let rate = last["robot_steps_per_s"].as_f64().unwrap();
    let ns = last["ns_per_robot_step"].as_f64().unwrap();
    assert!(
        rate > 0.0 && (rate * ns * 1e-9 - 1.0).abs() < 1e-9,
        "{last}"
    );
    // real time: 0.5 ms of simulated time per step, robots stepped together
    let rtf = last["real_time_factor"].as_f64().unwrap();
    assert!((rtf - rate / 4.0 * 0.0005).abs() < 1e-9 * rtf, "{last}");
    assert_eq!(last["points"].as_array().unwrap().len(), 4, "{last}");
    // the build the figures are of: this test is compiled with the binary's
    // flags, so a build for the CPU (target-cpu with AVX2 and FMA) is "cpu"
    let build = if cfg!(all(target_feature = "avx2", target_feature = "fma")) {
        "cpu"
    } else {
        "portable"
    };
    assert_eq!(last["build"], build, "{last}");
    assert!(stdout.starts_with("build: "), "{stdout}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(v["build"], build, "{v}");
    let points = v["points"].as_array().unwrap();
    assert_eq!(points.len(), 4);
    for p in points {
        assert!(p["robot_steps_per_s"].as_f64().unwrap() > 0.0, "{p}");
        // a robot's model, data, controller and entities: kilobytes, not bytes or megabytes
        let b = p["bytes_per_robot"].as_f64().unwrap();
        assert!((4096.0..4.0 * 1024.0 * 1024.0).contains(&b), "{p}");
    }
    let e = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(["bench", "--model", "quad99", "--robots", "1"])
        .output()
        .unwrap();
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("quad99"));
    let _ = std::fs::remove_dir_all(dir);
}

/// `--sim-seconds` times that much simulated time per block (0.01 s: 20
/// steps of 0.5 ms), and refuses less than one step.
#[test]
fn bench_sim_seconds_sets_the_timed_steps() {
    let (dir, json, _) = bench(
        "bench-s",
        &[
            "--robots",
            "1",
            "--threads",
            "1",
            "--sim-seconds",
            "0.01",
            "--repeats",
            "1",
            "--warmup",
            "1",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(v["steps_per_block"], 20, "{v}");
    for bad in [["--sim-seconds", "0"], ["--sim-seconds", "NaN"]] {
        let e = Command::new(env!("CARGO_BIN_EXE_quadsim"))
            .args(["bench", "--robots", "1"])
            .args(bad)
            .output()
            .unwrap();
        assert!(!e.status.success(), "{bad:?}");
        assert!(
            String::from_utf8_lossy(&e.stderr).contains("--sim-seconds"),
            "{}",
            String::from_utf8_lossy(&e.stderr)
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// `--sensing ground-truth` takes the sensors and the estimator out of the
/// benchmarked robots (the controller reads the exact state); the default
/// keeps the robots' own: noisy sensors and the estimate.
#[test]
fn bench_sensing_chooses_what_the_controller_reads() {
    use quadsim::cli::bench::{BenchSensing, bench_scenario};
    use quadsim::scenario::parse_scenario;
    use quadsim::world::{Overrides, build_world};
    for sensing in [BenchSensing::Estimated, BenchSensing::GroundTruth] {
        let src = bench_scenario("quad16", 2, sensing).unwrap();
        let scn = parse_scenario(std::path::Path::new("bench.toml"), src).unwrap();
        let mut w = build_world(&scn, Overrides::default()).unwrap();
        w.sim.run(200);
        for (name, e) in &w.robots {
            let sim = w.sim.robot(*e).unwrap();
            let on_estimate = sim
                .sensing
                .as_deref()
                .is_some_and(|s| s.controls_on_estimate());
            assert_eq!(on_estimate, sensing == BenchSensing::Estimated, "{name}");
            if sensing == BenchSensing::GroundTruth {
                assert!(sim.sensing.is_none(), "{name}: no sensors, no estimator");
            }
        }
    }
}

/// `--whole-body` benchmarks quad16 under the whole-body layer; without it
/// the bench keeps Study A's `τ = Jᵀ f` (the performance history's figures).
#[test]
fn bench_whole_body_chooses_the_torque_layer() {
    use quadsim::cli::bench::{BenchPlanner, BenchSensing, bench_scenario_with};
    use quadsim::scenario::parse_scenario;
    use quadsim::world::{Overrides, build_world};
    use quadsim_components::Controller;
    for whole_body in [false, true] {
        let src = bench_scenario_with(
            "quad16",
            2,
            BenchSensing::Estimated,
            whole_body,
            BenchPlanner::Vmc,
        )
        .unwrap();
        let scn = parse_scenario(std::path::Path::new("bench.toml"), src).unwrap();
        let w = build_world(&scn, Overrides::default()).unwrap();
        for (name, e) in &w.robots {
            let Controller::Walker(walker) = &w.sim.robot(*e).unwrap().run.controller else {
                panic!("{name}: quad16 trots under the walker");
            };
            assert_eq!(walker.params.whole_body, whole_body, "{name}");
        }
    }
    let src = bench_scenario_with(
        "quad16",
        2,
        BenchSensing::Estimated,
        false,
        BenchPlanner::Mpc,
    )
    .unwrap();
    let scn = parse_scenario(std::path::Path::new("bench.toml"), src).unwrap();
    let w = build_world(&scn, Overrides::default()).unwrap();
    for (name, e) in &w.robots {
        let Controller::Walker(walker) = &w.sim.robot(*e).unwrap().run.controller else {
            panic!("{name}: quad16 trots under the walker");
        };
        assert!(
            walker.params.whole_body,
            "{name}: MPC needs the whole-body layer"
        );
        assert_eq!(
            walker.params.planner,
            quadsim_engine::control::walker::Planner::Mpc,
            "{name}"
        );
    }
}

/// `--side-by-side` times the whole-body herd and the `τ = Jᵀ f` herd in
/// one run and reports both and their ratio (issue 27's cost target); it
/// needs a whole-body layer to compare.
#[test]
fn bench_side_by_side_reports_both_layers_and_the_ratio() {
    let (dir, _json, out) = bench(
        "bench-side",
        &[
            "--robots",
            "2",
            "--threads",
            "1",
            "--steps",
            "10",
            "--repeats",
            "3",
            "--warmup",
            "10",
            "--whole-body",
            "--side-by-side",
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("side by side"), "{stdout}");
    let last: serde_json::Value =
        serde_json::from_str(stdout.lines().last().unwrap()).expect("last line is JSON");
    let wb = last["robot_steps_per_s"].as_f64().unwrap();
    let jt = last["jt_robot_steps_per_s"].as_f64().unwrap();
    let ratio = last["whole_body_over_jt"].as_f64().unwrap();
    assert!(wb > 0.0 && jt > 0.0, "{last}");
    assert!((ratio - wb / jt).abs() < 1e-12, "{last}");
    assert!(last["whole_body_over_jt_pair_median"].as_f64().unwrap() > 0.0);
    std::fs::remove_dir_all(dir).ok();

    let out = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(["bench", "--robots", "2", "--side-by-side"])
        .output()
        .unwrap();
    assert!(
        !out.status.success(),
        "--side-by-side without a whole-body layer"
    );
}
