//! The Python examples against a real run (ignored by default: they need
//! python3 with `pip install iceoryx2`; CI runs them with `--ignored`).
//! stand_external.py holds quad16 up in lockstep; monitor_com.py prints the
//! log's CoM.
//!
//! Each test starts Python only once the run has announced its world on
//! stderr (its services exist by then), runs alone (the two runs never clean
//! up nodes while the other creates its own), and shows the run's stderr
//! beside Python's when anything fails.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::Duration;

use quadsim::log::read::read_log;
use serde_json::Value;

/// One Python test at a time.
static ALONE: Mutex<()> = Mutex::new(());

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-python-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A world name no earlier run (another process with this pid) has used.
fn world_name(prefix: &str) -> String {
    let ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    format!("{prefix}-{}-{ns}", std::process::id())
}

fn python(script: &str, args: &[&str]) -> Command {
    let mut c = Command::new("python3");
    c.arg(root().join("examples").join(script)).args(args);
    c
}

/// A `quadsim run` whose stderr is collected on a thread.
struct Run {
    child: Child,
    stderr: Option<JoinHandle<String>>,
}

impl Run {
    /// Starts `quadsim run scenario args --world-name world --out out` and
    /// waits (up to 60 s) for it to announce its world.
    fn start(scenario: &str, args: &[&str], world: &str, out: &Path) -> Run {
        let mut child = Command::new(env!("CARGO_BIN_EXE_quadsim"))
            .arg("run")
            .arg(root().join("scenarios").join(scenario))
            .args(args)
            .args(["--world-name", world])
            .arg("--out")
            .arg(out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let pipe = child.stderr.take().unwrap();
        let (announced, heard) = mpsc::channel();
        let stderr = std::thread::spawn(move || {
            let mut text = String::new();
            for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                if line.starts_with("monitor: world") {
                    let _ = announced.send(());
                }
                text += &line;
                text.push('\n');
            }
            text
        });
        let mut run = Run {
            child,
            stderr: Some(stderr),
        };
        if heard.recv_timeout(Duration::from_secs(60)).is_err() {
            let (text, _) = run.stop();
            panic!("the run never announced world '{world}'; its stderr:\n{text}");
        }
        run
    }

    /// Ends the run (SIGTERM: it closes its log) and returns its stderr, and
    /// whether the run was still there to be signalled.
    fn stop(&mut self) -> (String, bool) {
        let signalled = Command::new("kill")
            .arg("-TERM")
            .arg(self.child.id().to_string())
            .status()
            .is_ok_and(|s| s.success());
        (self.finish().1, signalled)
    }

    /// Waits for the run to end: its exit status and stderr.
    fn finish(&mut self) -> (std::process::ExitStatus, String) {
        let status = self.child.wait().unwrap();
        let text = self
            .stderr
            .take()
            .map(|h| h.join().unwrap())
            .unwrap_or_default();
        (status, text)
    }
}

#[test]
#[ignore = "needs python3 with `pip install iceoryx2` (CI runs it with --ignored)"]
fn python_external_controller_makes_quad16_stand_in_lockstep() {
    let _alone = ALONE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let out = tmp("stand");
    let world = world_name("py-stand");
    let mut run = Run::start(
        "stand_external.toml",
        &["--threads", "1", "--lockstep"],
        &world,
        &out,
    );
    let py = python("stand_external.py", &[&world]).output().unwrap();
    if !py.status.success() {
        let (text, _) = run.stop();
        panic!(
            "python: {}\nthe run's stderr:\n{text}",
            String::from_utf8_lossy(&py.stderr)
        );
    }
    let (status, text) = run.finish();
    assert!(status.success(), "{text}");
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
    let _alone = ALONE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let out = tmp("com");
    let world = world_name("py-com");
    let mut run = Run::start(
        "trot.toml",
        &["--threads", "1", "--duration", "1000"],
        &world,
        &out,
    );
    let py = python("monitor_com.py", &[&world, "50"]).output().unwrap();
    let (text, signalled) = run.stop();
    assert!(signalled, "the run ended before Python did:\n{text}");
    assert!(
        py.status.success(),
        "python: {}\nthe run's stderr:\n{text}",
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
