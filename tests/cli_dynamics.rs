//! `quadsim dynamics` as a user runs it: the built binary on a fixture, and on
//! bad inputs that must exit with code 2 and a message naming file and field,
//! without a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn quadsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .output()
        .expect("the quadsim binary runs")
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Writes `text` to a file of this name in the test's scratch directory.
fn scratch(name: &str, text: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli_dynamics_{name}"));
    std::fs::write(&p, text).unwrap();
    p
}

/// The shared sample states with one edit applied to the first state.
fn edited_states(name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let text = std::fs::read_to_string(fixtures().join("oracle/quad16_states.json")).unwrap();
    let mut doc: Value = serde_json::from_str(&text).unwrap();
    edit(&mut doc["states"][0]);
    scratch(name, &serde_json::to_string(&doc).unwrap())
}

/// Runs a command that must fail on bad input: exit code 2, every needle in
/// stderr, nothing on stdout and no panic.
fn assert_bad_input(args: &[&str], needles: &[&str]) {
    let out = quadsim(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: stderr {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(
        out.stdout.is_empty(),
        "{args:?}: printed results despite the error"
    );
    for n in needles {
        assert!(stderr.contains(n), "{args:?}: stderr lacks {n:?}: {stderr}");
    }
}

fn keys(v: &Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

#[test]
fn prints_the_oracle_keys_and_numbers_for_the_shared_states() {
    let urdf = fixtures().join("models/quad16.urdf");
    let states = fixtures().join("oracle/quad16_states.json");
    let out = quadsim(&["dynamics", path_str(&urdf), path_str(&states)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.is_empty(), "no warnings expected: {stderr}");
    let ours: Value = serde_json::from_slice(&out.stdout).expect("stdout is JSON");
    let text = std::fs::read_to_string(fixtures().join("oracle/quad16_shared.json")).unwrap();
    let oracle: Value = serde_json::from_str(&text).unwrap();

    // the same shape and keys
    assert_eq!(keys(&ours), keys(&oracle));
    let model_keys = |v: &Value| {
        let mut k = keys(v);
        k.retain(|k| k != "pinocchio_version" && k != "engine");
        k
    };
    assert_eq!(model_keys(&ours["model"]), model_keys(&oracle["model"]));
    let (r_ours, r_oracle) = (
        ours["results"].as_array().unwrap(),
        oracle["results"].as_array().unwrap(),
    );
    assert_eq!(r_ours.len(), r_oracle.len());
    for (a, b) in r_ours.iter().zip(r_oracle) {
        assert_eq!(
            keys(a),
            keys(b),
            "rnea_residual present exactly when no `a` was given"
        );
        assert_eq!(keys(&a["frames"]), keys(&b["frames"]));
        assert_eq!(keys(&a["joints"]), keys(&b["joints"]));
        assert_eq!(keys(&a["frames"]["LF_foot"]), keys(&b["frames"]["LF_foot"]));
        // a spot check of the numbers (tests/oracle_agreement.rs checks them all)
        for (x, r) in a["rnea"]
            .as_array()
            .unwrap()
            .iter()
            .zip(b["rnea"].as_array().unwrap())
        {
            let (x, r) = (x.as_f64().unwrap(), r.as_f64().unwrap());
            assert!((x - r).abs() <= 1e-9 * r.abs().max(1.0), "rnea {x} vs {r}");
        }
    }
}

#[test]
fn built_in_name_and_fixed_base_run() {
    let states = scratch(
        "fixed_zero.json",
        &serde_json::json!([{ "q": vec![0.0; 16] }]).to_string(),
    );
    let out = quadsim(&["dynamics", "quad16", path_str(&states), "--fixed-base"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["model"]["nq"], 16);
    assert_eq!(v["model"]["fixed_base"], true);
    // RNEA at ABA's result gives the (zero) torque back
    let r = &v["results"][0];
    assert!(r["rnea_residual"].as_f64().unwrap() < 1e-9);
}

#[test]
fn malformed_urdf_is_refused_naming_file_and_position() {
    let urdf = fixtures().join("models/bad/unclosed.urdf");
    let states = fixtures().join("oracle/quad16_states.json");
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&states)],
        &["unclosed.urdf", "malformed XML", "6:3"],
    );
    let urdf = fixtures().join("models/bad/zero_axis.urdf");
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&states)],
        &[
            "zero_axis.urdf",
            "joint 'LF_knee'",
            "<axis xyz>: zero vector",
        ],
    );
}

#[test]
fn wrong_length_state_is_refused_naming_index_and_field() {
    let urdf = fixtures().join("models/quad16.urdf");
    let states = edited_states("short_v.json", |s| {
        s["v"].as_array_mut().unwrap().pop();
    });
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&states)],
        &[
            "cli_dynamics_short_v.json",
            "states[0].v: expected 22 values, got 21",
        ],
    );
    // a floating-base state given to a fixed-base model
    let states = fixtures().join("oracle/quad16_states.json");
    assert_bad_input(
        &[
            "dynamics",
            path_str(&urdf),
            path_str(&states),
            "--fixed-base",
        ],
        &[
            "quad16_states.json",
            "states[0].q: expected 16 values, got 23",
        ],
    );
}

#[test]
fn non_unit_quaternion_is_refused() {
    let urdf = fixtures().join("models/quad16.urdf");
    let states = edited_states("long_quat.json", |s| {
        s["q"][6] = serde_json::json!(1.001);
    });
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&states)],
        &[
            "cli_dynamics_long_quat.json",
            "states[0].q[3..7]",
            "norm 1.001",
        ],
    );
}

#[test]
fn nan_and_infinity_are_refused_naming_the_entry() {
    let urdf = fixtures().join("models/quad16.urdf");
    // Python's json writes NaN and Infinity as bare tokens
    let states = edited_states("nan_tau.json", |s| {
        s["tau"][3] = serde_json::json!("__NAN__");
    });
    let text = std::fs::read_to_string(&states)
        .unwrap()
        .replace("\"__NAN__\"", "NaN");
    let states = scratch("nan_tau.json", &text);
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&states)],
        &["cli_dynamics_nan_tau.json", "states[0].tau[3]", "NaN"],
    );
    let states = scratch("inf_q.json", r#"[{"q": [0, 0, Infinity, 0, 0, 0, 1]}]"#);
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&states)],
        &["cli_dynamics_inf_q.json", "states[0].q[2]", "inf"],
    );
}

#[test]
fn unreadable_or_unknown_inputs_are_refused() {
    let urdf = fixtures().join("models/quad16.urdf");
    assert_bad_input(
        &["dynamics", path_str(&urdf), "no_such_states.json"],
        &["no_such_states.json", "cannot read"],
    );
    let states = fixtures().join("oracle/quad16_states.json");
    assert_bad_input(
        &["dynamics", "no_such_robot", path_str(&states)],
        &["no_such_robot", "not a URDF file and not a built-in robot"],
    );
    let garbage = scratch("garbage.json", "{\"states\": [1, 2");
    assert_bad_input(
        &["dynamics", path_str(&urdf), path_str(&garbage)],
        &["cli_dynamics_garbage.json", "not valid JSON"],
    );
}
