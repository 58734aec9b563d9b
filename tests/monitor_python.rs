//! The Python examples against a real run (ignored by default: they need
//! python3 with `pip install iceoryx2`; CI runs them with `--ignored`).
//! stand_external.py holds quad16 up in lockstep; monitor_com.py prints the
//! log's CoM.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use quadsim::log::read::read_log;
use serde_json::Value;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-python-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn python(script: &str, args: &[&str]) -> Command {
    let mut c = Command::new("python3");
    c.arg(root().join("examples").join(script)).args(args);
    c
}

#[test]
#[ignore = "needs python3 with `pip install iceoryx2` (CI runs it with --ignored)"]
fn python_external_controller_makes_quad16_stand_in_lockstep() {
    let out = tmp("stand");
    let world = format!("py-stand-{}", std::process::id());
    let run = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .arg("run")
        .arg(root().join("scenarios/stand_external.toml"))
        .args([
            "--quiet",
            "--threads",
            "1",
            "--lockstep",
            "--world-name",
            &world,
        ])
        .arg("--out")
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let py = python("stand_external.py", &[&world]).output().unwrap();
    let run = run.wait_with_output().unwrap();
    assert!(
        py.status.success(),
        "{}",
        String::from_utf8_lossy(&py.stderr)
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // 2 s at 2000 Hz: every controller tick got the Python command
    assert_eq!(s["timing"]["commands_applied"], 4000, "{s}");
    assert_eq!(s["timing"]["commands_rejected"], 0);
    assert_eq!(s["robots"][0]["fell"], false);
    let z: Vec<f64> = read_log(&out.join("log.mcap"))
        .unwrap()
        .topic("/rex/base_pose")
        .map(|m| m.json().unwrap()["pose"]["position"]["z"].as_f64().unwrap())
        .collect();
    let (z0, z1) = (z[0], *z.last().unwrap());
    assert!((z1 - z0).abs() < 0.03, "torso height {z0} → {z1}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
#[ignore = "needs python3 with `pip install iceoryx2` (CI runs it with --ignored)"]
fn python_reader_prints_the_logs_com() {
    let out = tmp("com");
    let world = format!("py-com-{}", std::process::id());
    let mut run = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .arg("run")
        .arg(root().join("scenarios/trot.toml"))
        .args([
            "--quiet",
            "--threads",
            "1",
            "--duration",
            "1000",
            "--world-name",
            &world,
        ])
        .arg("--out")
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let py = python("monitor_com.py", &[&world, "50"]).output().unwrap();
    let ok = Command::new("kill")
        .arg("-TERM")
        .arg(run.id().to_string())
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok);
    let _ = run.wait();
    assert!(
        py.status.success(),
        "{}",
        String::from_utf8_lossy(&py.stderr)
    );
    let text = String::from_utf8(py.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 50, "{text}");
    let log = read_log(&out.join("log.mcap")).unwrap();
    let com: Vec<(u64, Value)> = log
        .topic("/rex/com")
        .map(|m| (m.log_time_ns, m.json().unwrap()))
        .collect();
    let mut compared = 0;
    for l in lines {
        let v: Vec<&str> = l.split(' ').collect();
        assert_eq!(v[0], "rex");
        let t_ns = (v[1].parse::<f64>().unwrap() * 1e9).round() as u64;
        let Some((_, c)) = com.iter().find(|(t, _)| *t == t_ns) else {
            continue; // after the log's last complete chunk
        };
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let printed: f64 = v[2 + k].parse().unwrap();
            let logged = c["position"][axis].as_f64().unwrap();
            assert!((printed - logged).abs() <= 5e-7, "{l}: {axis} {logged}");
        }
        compared += 1;
    }
    assert!(compared >= 40, "only {compared} lines in the log");
    let _ = std::fs::remove_dir_all(&out);
}
