//! `quadsim optimize`: CMA-ES improves on its starting design within 40
//! simulations of 3 s each, spends no more than its budget, gives the same
//! answer on a second run, and refuses bad bounds by path and line.

use std::process::Command;

#[test]
fn the_optimiser_improves_on_its_start_within_its_budget() {
    let dir = std::env::temp_dir().join(format!("quadsim-opt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let root = env!("CARGO_MANIFEST_DIR");
    let mut runs = Vec::new();
    for k in 0..2 {
        let out = dir.join(format!("run{k}"));
        let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
            .args([
                "optimize",
                &format!("{root}/scenarios/design_opt.toml"),
                "--quiet",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        runs.push(std::fs::read_to_string(out.join("optimize.json")).unwrap());
    }
    assert_eq!(runs[0], runs[1], "not deterministic");
    let v: serde_json::Value = serde_json::from_str(&runs[0]).unwrap();
    let evals = v["evaluations"].as_array().unwrap();
    assert!(
        evals.len() <= 40 && evals.len() >= 30,
        "{} simulations",
        evals.len()
    );
    assert_eq!(evals[0]["generation"], 0);
    assert_eq!(evals[0]["summary"]["sim_time_s"].as_f64().unwrap(), 3.0);
    let start = v["start_objective"].as_f64().unwrap();
    let best = v["best"]["objective"].as_f64().unwrap();
    assert!(best < start, "best {best} vs start {start}");
    // the best is a real simulation's objective, recomputed from its summary
    let i = v["best"]["evaluation"].as_u64().unwrap() as usize;
    // (read back through the typed, versioned summary)
    let summary = quadsim::summary::Summary::from_json(evals[i]["summary"].clone()).unwrap();
    let again = quadsim::study::optimize::objective(&summary, 10.0);
    assert!((again - best).abs() < 1e-12, "{again} vs {best}");
    assert!(dir.join("run0/plots/convergence.png").exists());
    assert!(
        std::fs::read_to_string(dir.join("run0/report.md"))
            .unwrap()
            .contains("improves on the start")
    );

    // bad bounds name the parameter
    let bad = std::fs::read_to_string(format!("{root}/scenarios/design_opt.toml"))
        .unwrap()
        .replace("min = 0.25, max = 0.35", "min = 0.35, max = 0.25")
        .replace(
            "base = \"trot.toml\"",
            &format!("base = \"{root}/scenarios/trot.toml\""),
        );
    std::fs::write(dir.join("bad.toml"), bad).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(["optimize", "--quiet"])
        .arg(dir.join("bad.toml"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("parameters.\"robots[0].params.thigh.length_m\"") && e.contains("empty range"),
        "{e}"
    );
    assert!(!e.contains("bad.toml:0:"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}
