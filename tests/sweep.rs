//! `quadsim sweep` and `quadsim merge` end to end: the grid runs every
//! variant, shards together equal the whole run with no overlap, a failing
//! variant is recorded and the sweep goes on, bad study files name the path
//! and line, and `quadsim run` turns a study file away.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BASE: &str = r#"format_version = 1
[world]
name = "sweepbase"
dt_s = 0.0005
duration_s = 0.1
seed = 2
controller_rate_hz = 2000
default_ground = "concrete"

[[robots]]
name = "rex"
model = "quad16"
[robots.controller]
kind = "joint_pd"
bandwidth_hz = 3.0
"#;

fn study(vary: &str, extra: &str) -> String {
    format!("format_version = 1\nkind = \"sweep\"\nbase = \"base.toml\"\n{extra}\n[vary]\n{vary}\n")
}

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-sweep-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("base.toml"), BASE).unwrap();
    d
}

fn quadsim(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn rows(d: &Path) -> Vec<serde_json::Value> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("results.json")).unwrap()).unwrap();
    v["rows"].as_array().unwrap().clone()
}

#[test]
fn shards_merge_into_the_whole_sweep() {
    let d = dir("shards");
    let s = study(
        "\"robots[0].controller.bandwidth_hz\" = [2.0, 3.0, 4.0]\n\"robots[0].params.torso.mass_kg\" = { from = 9.0, to = 11.0, steps = 2 }",
        "",
    );
    std::fs::write(d.join("s.toml"), s).unwrap();
    let o = quadsim(
        &[
            "sweep", "s.toml", "--out", "whole", "--jobs", "2", "--quiet",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = rows(&d.join("whole"));
    assert_eq!(whole.len(), 6);
    // every combination once, in grid order, each with its own physics
    let mut combos: Vec<(f64, f64)> = whole
        .iter()
        .map(|r| {
            let p = &r["params"];
            (
                p["robots[0].controller.bandwidth_hz"].as_f64().unwrap(),
                p["robots[0].params.torso.mass_kg"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(combos[0], (2.0, 9.0));
    assert_eq!(combos[1], (2.0, 11.0));
    combos.dedup();
    assert_eq!(combos.len(), 6);
    let sinks: Vec<f64> = whole
        .iter()
        .map(|r| {
            r["summary"]["robots"][0]["base_height_mean_m"]
                .as_f64()
                .unwrap()
        })
        .collect();
    assert!(sinks.windows(2).all(|w| w[0] != w[1]), "{sinks:?}");
    let csv = std::fs::read_to_string(d.join("whole/results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 7);
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("robots[0].controller.bandwidth_hz")
    );
    assert!(d.join("whole/report.md").exists());

    for (i, n) in [(0, 3), (1, 3), (2, 3)] {
        let o = quadsim(
            &[
                "sweep",
                "s.toml",
                "--shard",
                &format!("{i}/{n}"),
                "--out",
                &format!("shard{i}"),
                "--quiet",
            ],
            &d,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(rows(&d.join(format!("shard{i}"))).len(), 2);
    }
    let o = quadsim(
        &["merge", "shard2", "shard0", "shard1", "--out", "merged"],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(rows(&d.join("merged")), whole);
    assert_eq!(
        std::fs::read_to_string(d.join("merged/results.csv")).unwrap(),
        csv
    );
    // plots of the metrics against each varied value, the same from the merge
    for stem in [
        "metrics_vs_robots_0__controller_bandwidth_hz",
        "metrics_vs_robots_0__params_torso_mass_kg",
    ] {
        for ext in ["svg", "png"] {
            let f = format!("plots/{stem}.{ext}");
            let whole_plot = std::fs::read(d.join("whole").join(&f)).unwrap();
            assert!(whole_plot.len() > 1000, "{f}");
            assert_eq!(
                std::fs::read(d.join("merged").join(&f)).unwrap(),
                whole_plot,
                "{f}"
            );
        }
    }
    let md = std::fs::read_to_string(d.join("whole/report.md")).unwrap();
    assert!(
        md.contains("plots/metrics_vs_robots_0__params_torso_mass_kg.png"),
        "{md}"
    );
    // a shard given twice overlaps
    let o = quadsim(&["merge", "shard0", "shard0", "--out", "bad"], &d);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("overlap"));
    // Slurm's environment picks the shard
    let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args([
            "sweep", "s.toml", "--shard", "auto", "--out", "slurm", "--quiet",
        ])
        .env("SLURM_ARRAY_TASK_ID", "2")
        .env("SLURM_ARRAY_TASK_MIN", "1")
        .env("SLURM_ARRAY_TASK_COUNT", "3")
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(rows(&d.join("slurm")), rows(&d.join("shard1")));
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_failing_variant_is_recorded_and_the_sweep_goes_on() {
    let d = dir("fail");
    std::fs::write(
        d.join("s.toml"),
        study(
            "\"robots[0].params.torso.mass_kg\" = [10.0, -1.0, 12.0]",
            "",
        ),
    )
    .unwrap();
    let o = quadsim(&["sweep", "s.toml", "--out", "out", "--quiet"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = rows(&d.join("out"));
    let status: Vec<&str> = r.iter().map(|r| r["status"].as_str().unwrap()).collect();
    assert_eq!(status, ["ok", "failed", "ok"]);
    let e = r[1]["error"].as_str().unwrap();
    assert!(e.contains("torso.mass_kg"), "{e}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn bad_studies_name_the_path_and_line() {
    let d = dir("bad");
    // (dt 1 ms cannot hold the base's 2000 Hz controller: caught before any run)
    for (vary, extra, key) in [
        (
            "\"robots[0].controller.bogus_gain\" = [1.0, 2.0]",
            "",
            "vary.\"robots[0].controller.bogus_gain\"",
        ),
        (
            "\"robots[3].params.torso.mass_kg\" = [1.0, 2.0]",
            "",
            "vary.\"robots[3].params.torso.mass_kg\"",
        ),
        ("\"world.dt_s\" = [0.001]", "", "vary.\"world.dt_s\""),
        (
            "\"world.dt_s\" = { from = 0.001, to = 0.002, steps = 0 }",
            "",
            "vary.\"world.dt_s\"",
        ),
        (
            "\"robots[0].params.torso.mass_kg\" = { uniform = [9.0, 11.0] }",
            "",
            "vary.\"robots[0].params.torso.mass_kg\"",
        ),
        (
            "\"world.dt_s\" = [0.0005]",
            "[sweep]\ncombine = \"spiral\"",
            "sweep.combine",
        ),
    ] {
        std::fs::write(d.join("s.toml"), study(vary, extra)).unwrap();
        let o = quadsim(&["sweep", "s.toml", "--out", "out", "--quiet"], &d);
        assert_eq!(o.status.code(), Some(2), "{vary}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(&format!(": {key}: ")), "{vary}: {e}");
        assert!(e.contains("s.toml:"), "{e}");
        assert!(!e.contains("s.toml:0:"), "no line: {e}");
    }
    // a study is not a scenario
    std::fs::write(d.join("s.toml"), study("\"world.dt_s\" = [0.001]", "")).unwrap();
    let o = quadsim(&["run", "s.toml"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("quadsim sweep"));
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn report_analyses_correlate_and_judge_loads() {
    let d = dir("analyses");
    // correlations: total mass rises with the torso mass (ρ = +1 exactly)
    std::fs::write(
        d.join("c.toml"),
        study(
            "\"robots[0].params.torso.mass_kg\" = [8.0, 10.0, 12.0, 14.0]",
            "[[report.correlations]]\nlabel = \"torso mass\"\nparam = \"robots[0].params.torso.mass_kg\"\nmetric = \"total_mass_kg\"\nexpect = \"positive\"\n\
             [[report.correlations]]\nlabel = \"torso mass, claimed wrong\"\nparam = \"robots[0].params.torso.mass_kg\"\nmetric = \"total_mass_kg\"\nexpect = \"negative\"\n",
        ),
    )
    .unwrap();
    let o = quadsim(&["sweep", "c.toml", "--out", "c", "--quiet"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(d.join("c/report.md")).unwrap();
    assert!(md.contains("| 4 | +1.000 | positive | yes |"), "{md}");
    assert!(md.contains("| 4 | +1.000 | negative | **no** |"), "{md}");
    // load carrying: 60 kg on 40 N·m joints is not carried; 0 and 10 kg are
    // (on ideal sources: 10 kg is near these joints' edge, and quad16's
    // default motors, with their friction and armature, drop it in 1 s)
    let base = BASE
        .replace(
            "model = \"quad16\"\n",
            "model = \"quad16\"\nparams = { \"actuator.effort_limit_nm\" = 40.0 }\n",
        )
        .replace(
            "[robots.controller]",
            "[robots.actuators]\nkind = \"ideal\"\n[robots.controller]",
        )
        + "\n[[robots.payloads]]\nname = \"box\"\nmass_kg = 0.0\nsize_m = [0.3, 0.2, 0.1]\noffset_m = [0.0, 0.0, 0.1]\n";
    std::fs::write(
        d.join("base.toml"),
        base.replace("duration_s = 0.1", "duration_s = 1.0"),
    )
    .unwrap();
    std::fs::write(
        d.join("l.toml"),
        study(
            "\"robots[0].payloads[0].mass_kg\" = [0.0, 10.0, 60.0]",
            "[report.load]\npayload = \"robots[0].payloads[0].mass_kg\"\n",
        ),
    )
    .unwrap();
    let o = quadsim(&["sweep", "l.toml", "--out", "l", "--quiet"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(d.join("l/report.md")).unwrap();
    let row = |m: &str| {
        md.lines()
            .find(|l| l.starts_with(&format!("| {m} |")))
            .unwrap_or_else(|| panic!("no {m} kg row in {md}"))
            .to_string()
    };
    assert!(row("0.0").ends_with("| ok |"), "{}", row("0.0"));
    assert!(row("10.0").ends_with("| ok |"), "{}", row("10.0"));
    let heavy = row("60.0");
    assert!(
        heavy.ends_with("| fell |") || heavy.ends_with("| saturated |"),
        "{heavy}"
    );
    assert!(md.contains("Largest payload carried: **10.0 kg**"), "{md}");
    // an analysis naming a path the study does not vary is refused
    std::fs::write(
        d.join("bad.toml"),
        study(
            "\"robots[0].params.torso.mass_kg\" = [8.0, 10.0]",
            "[report.load]\npayload = \"robots[0].payloads[0].mass_kg\"\n",
        ),
    )
    .unwrap();
    let o = quadsim(&["sweep", "bad.toml", "--out", "bad", "--quiet"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("report.load.payload"));
    let _ = std::fs::remove_dir_all(d);
}
