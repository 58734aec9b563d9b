//! `quadsim replay --headless-frames N` renders frames of a log to an
//! in-memory terminal: the chosen signals are charted under their names with
//! the value at the playback time, and the state table shows the robot's
//! logged state at that time.

use std::process::Command;

use quadsim::log::read::read_log;

fn quadsim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn replay_shows_the_logged_values_at_the_end_of_a_trot() {
    let dir = std::env::temp_dir().join(format!("quadsim-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scn = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/trot.toml");
    let o = quadsim(&[
        "run",
        scn,
        "--duration",
        "0.6",
        "--quiet",
        "--no-report",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let log = dir.join("log.mcap");
    let o = quadsim(&[
        "replay",
        log.to_str().unwrap(),
        "--signals",
        "/rex/com.position.z,/rex/joint_states.effort[2]",
        "--headless-frames",
        "4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let screen = String::from_utf8(o.stdout).unwrap();

    // the values at the last frame (t = end of the log) are the last samples
    let c = read_log(&log).unwrap();
    let com = c.topic("/rex/com").last().unwrap().json().unwrap();
    let z = com["position"]["z"].as_f64().unwrap();
    let joints = c.topic("/rex/joint_states").last().unwrap().json().unwrap();
    let tau = joints["effort"][2].as_f64().unwrap();
    assert!(
        screen.contains(&format!("/rex/com.position.z = {z:.4}")),
        "{screen}"
    );
    assert!(
        screen.contains(&format!("/rex/joint_states.effort[2] = {tau:.4}")),
        "{screen}"
    );
    let x = com["position"]["x"].as_f64().unwrap();
    assert!(
        screen.contains(&format!("rex        {x:.3} ")),
        "state table row: {screen}"
    );
    assert!(screen.contains("t = 0.600 / 0.600 s"), "{screen}");

    // an unknown signal is refused with the log's topics listed
    let o = quadsim(&[
        "replay",
        log.to_str().unwrap(),
        "--signals",
        "/rex/nope.z",
        "--headless-frames",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("'/rex/nope.z' names no topic") && err.contains("/rex/com"),
        "{err}"
    );
}
