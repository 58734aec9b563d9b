//! External control in lockstep: a commander thread in this process answers
//! every frame of a `quadsim run` (another process) with joint PD commands
//! for quad16; the run applies each at its tick, the log's torques are that
//! PD law at the logged state, the robot stands, and two runs give
//! bit-identical logs. Without a commander, lockstep fails clearly.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use quadsim::log::read::read_log;
use quadsim::monitor::command::{MODE_JOINT, MODE_TORQUE};
use quadsim::monitor::{CommandSender, FrameReader, MAX_DOF, RobotCommand};
use serde_json::Value;

const WAIT: Duration = Duration::from_secs(30);

/// stand.toml's gains (leg by leg: hip roll, hip pitch, knee, ankle).
const KP: [f64; 4] = [300.0, 300.0, 300.0, 100.0];
const KD: [f64; 4] = [5.0, 5.0, 5.0, 0.5];

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-control-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// scenarios/stand.toml with the joint PD moved into another process.
fn external_stand(dir: &Path, duration_s: f64) -> PathBuf {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/stand.toml"))
            .unwrap();
    let head = text.split("[robots.controller]").next().unwrap();
    let scn = format!(
        "{}[robots.controller]\nkind = \"external\"\n",
        head.replace("duration_s = 10.0", &format!("duration_s = {duration_s}"))
    );
    let p = dir.join("stand_external.toml");
    std::fs::write(&p, scn).unwrap();
    p
}

fn run(scn: &Path, out: &Path, world: &str, extra: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .arg("run")
        .arg(scn)
        .args([
            "--quiet",
            "--threads",
            "1",
            "--world-name",
            world,
            "--lockstep",
        ])
        .arg("--out")
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// The commander: a limp command for tick 0, then for each frame at tick t
/// the PD command holding the first frame's joint angles from tick t + N.
/// Returns the number of commands sent.
fn commander(world: String) -> u64 {
    let mut reader = FrameReader::wait_open(&world, WAIT).unwrap();
    let header = reader.wait_header(WAIT).unwrap();
    let every = header["every_steps"].as_u64().unwrap();
    let nj = header["robots"][0]["dof"].as_u64().unwrap() as usize;
    assert_eq!(nj, 16);
    let start = Instant::now();
    let sender = loop {
        if let Some(s) = CommandSender::open(&world, 1).unwrap() {
            break s;
        }
        assert!(start.elapsed() < WAIT, "no commands service");
        thread::sleep(Duration::from_millis(5));
    };
    let mut cmd = RobotCommand {
        mode: MODE_TORQUE,
        n_dof: nj as u32,
        ..RobotCommand::default()
    };
    sender.send(&[cmd]).unwrap();
    let mut sent = 1;
    let mut target: Option<[f64; MAX_DOF]> = None;
    // the run ends when its last frame went out; then nothing more arrives
    while let Some(frames) = reader.next(Duration::from_secs(2)).unwrap() {
        let f = frames[0];
        let t = *target.get_or_insert(f.joint_q_rad);
        cmd.mode = MODE_JOINT;
        cmd.tick = f.tick + every;
        cmd.q_target_rad = t;
        for j in 0..nj {
            cmd.kp_nm_per_rad[j] = KP[j % 4];
            cmd.kd_nms_per_rad[j] = KD[j % 4];
        }
        sender.send(&[cmd]).unwrap();
        sent += 1;
    }
    sent
}

fn finish(child: std::process::Child) -> Output {
    child.wait_with_output().unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// One lockstep run with its commander; returns the log bytes and summary.
fn lockstep_run(tag: &str) -> (PathBuf, Value, u64) {
    let dir = tmp(tag);
    let scn = external_stand(&dir, 1.0);
    let world = format!("control-{tag}-{}", std::process::id());
    let child = run(&scn, &dir.join("out"), &world, &[]);
    let w = world.clone();
    let cmdr = thread::spawn(move || commander(w));
    let out = finish(child);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sent = cmdr.join().unwrap();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    (dir, summary, sent)
}

#[test]
fn lockstep_external_pd_stands_quad16_and_is_deterministic() {
    let (dir, summary, sent) = lockstep_run("a");
    // 1 s at 2000 Hz control: ticks 0..1999 each got exactly its command
    assert_eq!(summary["timing"]["commands_applied"], 2000, "{summary}");
    assert_eq!(summary["timing"]["commands_rejected"], 0);
    assert_eq!(sent, 2001, "one per frame (ticks 0..1999) plus tick 0's");
    let r = &summary["robots"][0];
    assert_eq!(r["fell"], false, "{r}");

    // the log's torque command at each tick is the PD law at the logged state
    let log = read_log(&dir.join("out/log.mcap")).unwrap();
    let states: Vec<Value> = log
        .topic("/rex/joint_states")
        .map(|m| m.json().unwrap())
        .collect();
    let cmds: Vec<Value> = log
        .topic("/rex/joint_commands")
        .map(|m| m.json().unwrap())
        .collect();
    assert!(states.len() > 1000);
    let target = floats(&cmds[1]["position"]);
    let first_q = floats(&states[0]["position"]);
    assert_eq!(target, first_q, "targets: the first frame's joint angles");
    assert_eq!(floats(&cmds[0]["effort"]), vec![0.0; 16], "tick 0: limp");
    for (s, c) in states.iter().zip(&cmds).skip(1) {
        let (q, qd) = (floats(&s["position"]), floats(&s["velocity"]));
        let effort = floats(&c["effort"]);
        for j in 0..16 {
            let law = 0.0 + KP[j % 4] * (target[j] - q[j]) + KD[j % 4] * (0.0 - qd[j]);
            assert_eq!(effort[j], law, "joint {j}");
        }
    }
    // it stands: the torso stays within 3 cm of its start height
    let z: Vec<f64> = log
        .topic("/rex/base_pose")
        .map(|m| m.json().unwrap()["pose"]["position"]["z"].as_f64().unwrap())
        .collect();
    let (z0, z1) = (z[0], *z.last().unwrap());
    assert!((z1 - z0).abs() < 0.03, "torso height {z0} → {z1}");

    // the same commands give the same run, whatever the commander's timing
    let (dir_b, _, _) = lockstep_run("b");
    let la = std::fs::read(dir.join("out/log.mcap")).unwrap();
    let lb = std::fs::read(dir_b.join("out/log.mcap")).unwrap();
    assert!(la == lb, "lockstep runs differ");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&dir_b);
}

#[test]
fn lockstep_without_a_commander_fails_clearly() {
    let dir = tmp("timeout");
    let scn = external_stand(&dir, 1.0);
    let world = format!("control-timeout-{}", std::process::id());
    let start = Instant::now();
    let out = finish(run(
        &scn,
        &dir.join("out"),
        &world,
        &["--lockstep-timeout", "0.3"],
    ));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("lockstep: no command for robot 'rex' (index 0) at tick 0")
            && err.contains("within 0.300 s")
            && err.contains(&format!("quadsim/{world}/commands")),
        "{err}"
    );
    assert!(start.elapsed() < Duration::from_secs(10));
    let _ = std::fs::remove_dir_all(&dir);
}
