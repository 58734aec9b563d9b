//! `summary.json` is a typed, versioned [`Summary`]: what a run writes reads
//! back to the same value and the same text, and another layout version is
//! refused with the key named.

use quadsim::scenario::load_scenario;
use quadsim::summary::{SUMMARY_FORMAT_VERSION, Summary};
use quadsim::world::{Overrides, build_world};

fn short_trot() -> Summary {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/trot.toml");
    let scn = load_scenario(&path).unwrap();
    let mut w = build_world(
        &scn,
        Overrides {
            duration_s: Some(0.2),
            threads: 1,
            ..Default::default()
        },
    )
    .unwrap();
    let steps = w.steps;
    w.sim.run_pass(steps);
    Summary::of_world(&scn, &w, Some(0.1))
}

/// Written and read back: the same value and byte for byte the same text
/// (the keys sorted, as every earlier `summary.json`).
#[test]
fn a_summary_round_trips_through_its_text() {
    let s = short_trot();
    assert_eq!(s.format_version, SUMMARY_FORMAT_VERSION);
    let text = s.to_text();
    let back = Summary::from_json(serde_json::from_str(&text).unwrap()).unwrap();
    assert_eq!(back, s);
    assert_eq!(back.to_text(), text);
    // keys sorted at every level: `controller_rate_hz` first, `timing` last
    assert!(text.starts_with("{\n  \"controller_rate_hz\""), "{text}");
    assert!(text.contains("\"timing\": {\n    \"real_time_factor\""));
}

/// A summary of another layout version is refused, naming the key.
#[test]
fn another_format_version_is_refused() {
    let mut v = short_trot().to_json();
    v["format_version"] = serde_json::json!(SUMMARY_FORMAT_VERSION + 1);
    let e = Summary::from_json(v).unwrap_err();
    assert!(e.contains("format_version"), "{e}");
}

/// A missing metric is an error naming the key, not a default.
#[test]
fn a_missing_key_is_named() {
    let mut v = short_trot().to_json();
    v["robots"][0].as_object_mut().unwrap().remove("energy_j");
    let e = Summary::from_json(v).unwrap_err();
    assert!(e.contains("energy_j"), "{e}");
}
