//! The committed scenarios: every `.toml` under `scenarios/` passes
//! `quadsim check`, and a short run of `terrains.toml` gives finite metrics
//! with every robot still standing (the start poses put all four feet on the
//! ground of each terrain).

use std::path::{Path, PathBuf};
use std::process::Command;

fn scenario_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            scenario_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "toml") {
            out.push(p);
        }
    }
}

#[test]
fn every_scenario_passes_check() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut files = Vec::new();
    scenario_files(&root, &mut files);
    files.sort();
    for must in ["stand.toml", "terrains.toml", "grounds.toml"] {
        assert!(
            files.iter().any(|f| f.ends_with(must)),
            "scenarios/{must} missing"
        );
    }
    for f in &files {
        let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
            .arg("check")
            .arg(f)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "quadsim check {}: {}",
            f.display(),
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn terrains_runs_half_a_second() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("scenario_files_terrains");
    let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .arg("run")
        .arg(root.join("scenarios/terrains.toml"))
        .args(["--duration", "0.5", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!((summary["sim_time_s"].as_f64().unwrap() - 0.5).abs() < 1e-9);
    let robots = summary["robots"].as_array().unwrap();
    let names: Vec<&str> = robots.iter().map(|r| r["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "flat",
            "incline",
            "sine",
            "rough_uniform",
            "rough_smooth",
            "trench",
            "stairs_up",
            "stairs_down",
            "boxes",
            "stepping_stones",
            "heightmap"
        ]
    );
    for r in robots {
        let name = r["name"].as_str().unwrap();
        for (k, v) in r.as_object().unwrap() {
            let nums: Vec<f64> = match v {
                serde_json::Value::Number(n) => vec![n.as_f64().unwrap()],
                serde_json::Value::Array(a) => a.iter().filter_map(|x| x.as_f64()).collect(),
                _ => vec![],
            };
            assert!(nums.iter().all(|x| x.is_finite()), "{name}.{k} = {v}");
        }
        assert_eq!(r["fell"], false, "{name} fell");
        // standing: the base stays 0.5–0.9 m above the ground beneath it
        // (0.55–0.59 m on most terrains, 0.885 m over the trench floor, 0.685 m
        // over the gap between stepping stones) and moves less than 2 cm
        let h = r["base_height_mean_m"].as_f64().unwrap();
        let p2p = r["base_height_p2p_m"].as_f64().unwrap();
        assert!((0.5..0.9).contains(&h), "{name}: base height {h}");
        assert!(p2p < 0.02, "{name}: base height p2p {p2p}");
    }
}
