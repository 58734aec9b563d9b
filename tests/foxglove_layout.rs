//! `docs/foxglove_layout.json` is a JSON layout whose every topic exists in a
//! freshly written log of `scenarios/trot.toml`, every plotted message path
//! resolves to a number in that topic's messages, and the 3D panel follows a
//! frame that `/tf` publishes.

use std::process::Command;

use quadsim::log::read::read_log;
use serde_json::Value;

/// Resolves a Foxglove message path's field part (`.a.b[2].c`) in `v`.
fn resolve<'a>(mut v: &'a Value, path: &str) -> Option<&'a Value> {
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let (key, index) = match part.split_once('[') {
            Some((k, rest)) => (k, Some(rest.trim_end_matches(']').parse::<usize>().ok()?)),
            None => (part, None),
        };
        v = v.get(key)?;
        if let Some(i) = index {
            v = v.get(i)?;
        }
    }
    Some(v)
}

#[test]
fn every_topic_and_path_of_the_layout_is_in_a_trot_log() {
    let layout: Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/docs/foxglove_layout.json"
        ))
        .unwrap(),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("quadsim-foxglove-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args([
            "run",
            concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/trot.toml"),
        ])
        .args(["--duration", "0.3", "--quiet", "--no-report", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let log = read_log(&dir.join("log.mcap")).unwrap();
    let topics = log.topics();

    let configs = layout["configById"].as_object().unwrap();
    // every panel placed in the layout tree has a config
    fn leaves(v: &Value, out: &mut Vec<String>) {
        match v {
            Value::String(s) => out.push(s.clone()),
            Value::Object(o) => {
                for k in ["first", "second"] {
                    leaves(&o[k], out);
                }
            }
            _ => panic!("bad layout node {v}"),
        }
    }
    let mut placed = Vec::new();
    leaves(&layout["layout"], &mut placed);
    for p in &placed {
        assert!(configs.contains_key(p), "panel {p} has no config");
    }
    assert!(placed.iter().any(|p| p.starts_with("3D!")), "a 3D panel");

    let mut checked = 0;
    for (id, cfg) in configs {
        let mut paths: Vec<String> = cfg["paths"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|p| p["value"].as_str().unwrap().to_string())
            .collect();
        paths.extend(cfg["topicPath"].as_str().map(str::to_string));
        for t in cfg["topics"].as_object().into_iter().flat_map(|o| o.keys()) {
            paths.push(t.clone());
        }
        for path in paths {
            let (topic, field) = match path.find('.') {
                Some(i) => path.split_at(i),
                None => (path.as_str(), ""),
            };
            assert!(
                topics.iter().any(|t| t == topic),
                "{id}: topic {topic} not in the log"
            );
            if cfg.get("paths").is_some() {
                let m = log.topic(topic).nth(1).unwrap().json().unwrap();
                let v = resolve(&m, field).unwrap_or_else(|| panic!("{id}: {path} not in {m}"));
                assert!(v.is_number(), "{id}: {path} = {v} is not a number");
            }
            checked += 1;
        }
    }
    assert!(checked >= 20, "{checked} paths checked");
    // the 3D panel follows the robot's base frame, which /tf publishes
    let follow = configs["3D!quadsim"]["followTf"].as_str().unwrap();
    let tf = log.topic("/tf").next().unwrap().json().unwrap();
    assert!(
        tf["transforms"]
            .as_array()
            .unwrap()
            .iter()
            .any(|t| t["child_frame_id"] == follow),
        "{follow} not in /tf"
    );
}
