//! Live monitoring between processes: a `quadsim run` publishes, subscribers
//! in this test process (and `quadsim monitor`) receive. Frames arrive in
//! order with the log's values bit for bit; an idle subscriber leaves the log
//! bit-identical; ten subscribers at once; two worlds at once.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use quadsim::log::read::read_log;
use quadsim::monitor::{FrameReader, RobotFrame};
use serde_json::Value;

const WAIT: Duration = Duration::from_secs(30);

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-monitor-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn world_name(tag: &str) -> String {
    format!("test-{tag}-{}", std::process::id())
}

fn quadsim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
}

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

/// Starts `quadsim run` of a built-in scenario in its own process.
fn spawn_run(scn: &str, out: &Path, duration_s: f64, extra: &[&str]) -> Child {
    quadsim()
        .arg("run")
        .arg(scenario(scn))
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .arg("--threads")
        .arg("1")
        .arg("--duration")
        .arg(duration_s.to_string())
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Asks the run to stop (SIGTERM: it finalises its log and summary) and waits.
fn stop(child: Child) {
    let ok = Command::new("kill")
        .arg("-TERM")
        .arg(child.id().to_string())
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "kill -TERM");
    // its exit status is the interrupted run's; the log is what matters
    drop(child.wait_with_output().unwrap());
}

fn wait_done(child: Child) {
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "run failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn open(world: &str, child: &mut Child) -> FrameReader {
    match FrameReader::wait_open(world, WAIT) {
        Ok(r) => r,
        Err(e) => {
            let _ = child.kill();
            panic!("{e}");
        }
    }
}

fn receive(reader: &mut FrameReader, n: usize) -> Vec<Vec<RobotFrame>> {
    (0..n)
        .map(|_| {
            reader
                .next(WAIT)
                .expect("receive")
                .expect("an instant within the wait")
        })
        .collect()
}

/// The log's messages on `topic` by log time (ns).
fn by_time(log: &quadsim::log::read::LogContents, topic: &str) -> Vec<(u64, Value)> {
    log.topic(topic)
        .map(|m| (m.log_time_ns, m.json().unwrap()))
        .collect()
}

fn v3(v: &Value) -> [f64; 3] {
    [
        v["x"].as_f64().unwrap(),
        v["y"].as_f64().unwrap(),
        v["z"].as_f64().unwrap(),
    ]
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn frames_arrive_in_order_with_the_logs_values() {
    let out = tmp("equal");
    let world = world_name("equal");
    let mut child = spawn_run("trot.toml", &out, 1000.0, &["--world-name", &world]);
    let mut reader = open(&world, &mut child);
    let header = reader.wait_header(WAIT).unwrap();
    let instants = receive(&mut reader, 150);
    stop(child);

    assert_eq!(header["world"], world.as_str());
    assert_eq!(header["robots"][0]["name"], "rex");
    assert_eq!(header["robots"][0]["model"], "quad16");
    let every = header["every_steps"].as_u64().unwrap();
    let dt = header["dt_s"].as_f64().unwrap();
    assert_eq!(
        every, 20,
        "default: 100 Hz, five controller periods (500 Hz at 0.5 ms)"
    );
    // in order: strictly increasing ticks on the publishing grid
    for w in instants.windows(2) {
        assert!(w[1][0].tick > w[0][0].tick, "ticks must increase");
    }
    for i in &instants {
        assert_eq!(i.len(), 1);
        assert_eq!(i[0].tick % every, 0);
        assert_eq!(i[0].time_s, i[0].tick as f64 * dt);
    }

    let log = read_log(&out.join("log.mcap")).unwrap();
    let com = by_time(&log, "/rex/com");
    let joints = by_time(&log, "/rex/joint_states");
    let cmds = by_time(&log, "/rex/joint_commands");
    let twist = by_time(&log, "/rex/base_twist");
    let att = by_time(&log, "/rex/attitude");
    let pose = by_time(&log, "/rex/base_pose");
    let feet = by_time(&log, "/rex/feet");
    let mut compared = 0;
    for i in &instants {
        let f = &i[0];
        let t_ns = quadsim::systems::step_time_ns(f.tick, dt);
        let at = |msgs: &[(u64, Value)]| msgs.iter().find(|(t, _)| *t == t_ns).map(|m| m.1.clone());
        let Some(c) = at(&com) else {
            // the log stopped (SIGTERM) before this instant's chunk was written
            continue;
        };
        compared += 1;
        assert_eq!(f.com_m, v3(&c["position"]), "CoM at tick {}", f.tick);
        assert_eq!(f.com_velocity_mps, v3(&c["velocity"]));
        let j = at(&joints).unwrap();
        let n = f.dof();
        assert_eq!(n, 16);
        assert_eq!(f.joint_q_rad[..n], floats(&j["position"])[..]);
        assert_eq!(f.joint_qd_radps[..n], floats(&j["velocity"])[..]);
        assert_eq!(f.joint_tau_nm[..n], floats(&j["effort"])[..]);
        let k = at(&cmds).unwrap();
        assert_eq!(f.joint_q_desired_rad[..n], floats(&k["position"])[..]);
        assert_eq!(f.joint_tau_desired_nm[..n], floats(&k["effort"])[..]);
        let tw = at(&twist).unwrap();
        assert_eq!(f.base_linear_mps, v3(&tw["linear"]));
        assert_eq!(f.base_angular_radps, v3(&tw["angular"]));
        let a = at(&att).unwrap();
        assert_eq!(
            f.rpy_rad,
            [
                a["roll"].as_f64().unwrap(),
                a["pitch"].as_f64().unwrap(),
                a["yaw"].as_f64().unwrap()
            ]
        );
        let p = at(&pose).unwrap();
        assert_eq!(f.base_position_m, v3(&p["pose"]["position"]));
        let fe = at(&feet).unwrap();
        let fe = fe["feet"].as_array().unwrap();
        assert_eq!(f.feet(), fe.len());
        for (k, foot) in fe.iter().enumerate() {
            assert_eq!(f.in_contact(k), foot["in_contact"].as_bool().unwrap());
            assert_eq!(f.foot_force_n[k], v3(&foot["force"]));
            assert_eq!(f.gait_phase[k], foot["gait_phase"].as_f64().unwrap());
        }
    }
    assert!(
        compared >= 100,
        "only {compared} of {} instants were in the log",
        instants.len()
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn an_idle_subscriber_leaves_the_log_bit_identical() {
    let (a, b) = (tmp("idle-a"), tmp("idle-b"));
    // reference: no monitoring at all
    wait_done(spawn_run("trot.toml", &a, 20.0, &["--no-monitor"]));
    let world = world_name("idle");
    let mut child = spawn_run("trot.toml", &b, 20.0, &["--world-name", &world]);
    // attach and never read while the run lasts
    let mut idle = open(&world, &mut child);
    wait_done(child);
    // it was connected: its queue holds instants it never read
    assert!(
        idle.try_next().unwrap().is_some(),
        "the idle subscriber received nothing"
    );
    let la = std::fs::read(a.join("log.mcap")).unwrap();
    let lb = std::fs::read(b.join("log.mcap")).unwrap();
    assert!(la.len() > 100_000);
    assert!(la == lb, "logs differ with an idle subscriber");
    let sa: Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("summary.json")).unwrap()).unwrap();
    let sb: Value =
        serde_json::from_str(&std::fs::read_to_string(b.join("summary.json")).unwrap()).unwrap();
    assert_eq!(sa["robots"], sb["robots"]);
    assert!(sb["timing"]["monitor_published"].as_u64().unwrap() > 0);
    assert!(sa["timing"].get("monitor_published").is_none());
    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn ten_subscribers_at_once_all_receive() {
    let out = tmp("ten");
    let world = world_name("ten");
    let mut child = spawn_run(
        "trot.toml",
        &out,
        1000.0,
        &["--world-name", &world, "--no-log"],
    );
    let mut readers: Vec<FrameReader> = (0..10).map(|_| open(&world, &mut child)).collect();
    let got: Vec<Vec<Vec<RobotFrame>>> = readers.iter_mut().map(|r| receive(r, 20)).collect();
    stop(child);
    for g in &got {
        assert_eq!(g.len(), 20);
        for w in g.windows(2) {
            assert!(w[1][0].tick > w[0][0].tick);
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn two_worlds_at_once_do_not_collide() {
    let (oa, ob) = (tmp("two-a"), tmp("two-b"));
    let (wa, wb) = (world_name("two-a"), world_name("two-b"));
    // a trotting robot (walker: gait phases) and a standing one (joint PD: none)
    let mut ca = spawn_run("trot.toml", &oa, 1000.0, &["--world-name", &wa, "--no-log"]);
    let mut cb = spawn_run(
        "stand.toml",
        &ob,
        1000.0,
        &["--world-name", &wb, "--no-log"],
    );
    let mut ra = open(&wa, &mut ca);
    let mut rb = open(&wb, &mut cb);
    let worlds = quadsim::monitor::list_worlds().unwrap();
    assert!(worlds.contains(&wa) && worlds.contains(&wb), "{worlds:?}");
    let ha = ra.wait_header(WAIT).unwrap();
    let hb = rb.wait_header(WAIT).unwrap();
    let fa = receive(&mut ra, 20);
    let fb = receive(&mut rb, 20);
    stop(ca);
    stop(cb);
    assert_eq!(ha["world"], wa.as_str());
    assert_eq!(hb["world"], wb.as_str());
    assert_ne!(ha["pid"], hb["pid"]);
    assert!(
        fa.iter()
            .all(|i| i[0].gait_phase.iter().all(|p| p.is_finite()))
    );
    assert!(
        fb.iter()
            .all(|i| i[0].gait_phase.iter().all(|p| p.is_nan()))
    );
    let _ = std::fs::remove_dir_all(&oa);
    let _ = std::fs::remove_dir_all(&ob);
}

/// Stops a run (SIGTERM) and gives its stderr.
fn stop_stderr(child: Child) -> String {
    let ok = Command::new("kill")
        .arg("-TERM")
        .arg(child.id().to_string())
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "kill -TERM");
    String::from_utf8_lossy(&child.wait_with_output().unwrap().stderr).into_owned()
}

/// A reader that stays attached while its world ends keeps the world's
/// services alive; the next run under that name opens them and publishes
/// to it (issue 30: it failed with "cannot create the header service:
/// AlreadyExists" and ran unmonitored). A run whose name is taken by a
/// world still running gets a clear warning instead.
#[test]
fn a_reader_held_across_two_worlds_of_one_name_sees_the_second() {
    let (oa, ob, oc) = (tmp("held-a"), tmp("held-b"), tmp("held-c"));
    let world = world_name("held");
    let args = ["--world-name", world.as_str(), "--no-log"];
    let mut ca = spawn_run("trot.toml", &oa, 1000.0, &args);
    let mut reader = open(&world, &mut ca);
    let ha = reader.wait_header(WAIT).unwrap();
    let fa = receive(&mut reader, 5);
    assert!(fa.iter().all(|i| i[0].gait_phase[0].is_finite()));
    let ea = stop_stderr(ca);
    let start = Instant::now();
    while !reader.ended() {
        assert!(start.elapsed() < WAIT, "the world did not end");
        std::thread::sleep(Duration::from_millis(10));
    }
    while reader.try_next().unwrap().is_some() {}
    // the reader still holds the services: the world is listed
    assert!(quadsim::monitor::list_worlds().unwrap().contains(&world));
    // a standing robot (joint PD: no gait phase) under the same name
    let mut cb = spawn_run("stand.toml", &ob, 1000.0, &args);
    let pid_b = cb.id();
    let start = Instant::now();
    let hb = loop {
        let h = reader.header().unwrap().cloned();
        if let Some(h) = h.filter(|h| h["pid"] != ha["pid"]) {
            break h;
        }
        if start.elapsed() >= WAIT || cb.try_wait().unwrap().is_some() {
            let _ = cb.kill();
            let e = cb.wait_with_output().unwrap().stderr;
            panic!(
                "no header from the second world: {}",
                String::from_utf8_lossy(&e)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let fb = receive(&mut reader, 5);
    // a third run under the name while the second runs: a clear warning,
    // and it runs on unmonitored
    let cc = quadsim()
        .arg("run")
        .arg(scenario("stand.toml"))
        .args([
            "--out",
            oc.to_str().unwrap(),
            "--duration",
            "0.05",
            "--no-report",
        ])
        .args(args)
        .output()
        .unwrap();
    let ec = String::from_utf8_lossy(&cc.stderr);
    let eb = stop_stderr(cb);
    assert_eq!(hb["world"], world.as_str());
    assert_eq!(hb["pid"], pid_b);
    assert!(
        fb.iter()
            .all(|i| i[0].gait_phase.iter().all(|p| p.is_nan())),
        "the second world's frames are the standing robot's"
    );
    for e in [&ea, &eb] {
        assert!(!e.contains("without live monitoring"), "{e}");
    }
    assert!(cc.status.success(), "{ec}");
    assert!(
        ec.contains("another running quadsim") && ec.contains("without live monitoring"),
        "{ec}"
    );
    for d in [oa, ob, oc] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn monitor_cli_prints_frames_and_times_out_on_a_missing_world() {
    let out = tmp("cli");
    let world = world_name("cli");
    let mut child = spawn_run(
        "trot.toml",
        &out,
        1000.0,
        &["--world-name", &world, "--no-log"],
    );
    let _ = open(&world, &mut child);
    let o = quadsim()
        .args([
            "monitor", "--world", &world, "--frames", "5", "--robot", "rex",
        ])
        .output()
        .unwrap();
    stop(child);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 5, "{text}");
    assert!(
        lines
            .iter()
            .all(|l| l.starts_with("rex tick=") && l.contains("contacts="))
    );

    let start = Instant::now();
    let o = quadsim()
        .args(["monitor", "--world", "no-such-world", "--timeout", "0.5"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("waiting") && err.contains("did not appear within 0.5 s"),
        "{err}"
    );
    assert!(start.elapsed() < Duration::from_secs(10));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn monitor_ends_quietly_when_its_reader_goes_away() {
    // `quadsim monitor … | head -1`: stdout closes after one line; the
    // monitor stops at its next line with exit 0, not a broken-pipe panic
    use std::io::BufRead;
    let out = tmp("pipe");
    let world = world_name("pipe");
    let mut child = spawn_run(
        "trot.toml",
        &out,
        1000.0,
        &["--world-name", &world, "--no-log"],
    );
    let _ = open(&world, &mut child);
    let mut mon = quadsim()
        .args(["monitor", "--world", &world, "--frames", "100000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    {
        let mut r = std::io::BufReader::new(mon.stdout.take().unwrap());
        r.read_line(&mut first).unwrap();
    } // the read end closes here, as `head -1` exits
    let o = mon.wait_with_output().unwrap();
    stop(child);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(first.starts_with("rex tick="), "{first}");
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}
