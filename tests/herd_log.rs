//! Logging that scales with the herd (issue 6): each robot at its own
//! decimation (`[robots.log] rate_hz`, varied over a herd; `--log-rate
//! PATTERN=RATE`), selected robots only (`[log] robots`, `--log-robots`,
//! glob patterns) and a summary-only mode. A logged per-step channel carries
//! ⌊N / d⌋ + 1 messages at t = j·d·dt (t = 0 included) for the robot's own
//! decimation d; a robot not selected has no per-step channel; files stay
//! byte-identical across thread counts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use quadsim::log::read::{LogContents, read_log};
use quadsim::log::select::{LogOverrides, LogPlan, RobotPattern};
use quadsim::log::{RunOutcome, start_run_log, start_run_log_with};
use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, build_world};

/// The per-step topics of one robot.
const PER_STEP: [&str; 8] = [
    "base_pose",
    "base_twist",
    "attitude",
    "com",
    "joint_states",
    "joint_commands",
    "feet",
    "virtual_wrench",
];

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-herdlog-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// 210 steps of 0.5 ms (not a multiple of 4, 8 or 20, so the final state is
/// sampled only at the decimations dividing 210). Herd `a`: four quad16 at
/// 500 Hz, 250 Hz, 100 Hz and every step (d = 4, 8, 20, 1); herd `b`: three
/// quad12 at the world's 500 Hz; `c-000` has `log = false`; `[log] robots`
/// leaves out `b-002`.
const DURATION: &str = "0.105";
const STEPS: u64 = 210;

fn herd_src(first: &str, second: &str) -> String {
    format!(
        r#"format_version = 1
[world]
name = "herdlog"
dt_s = 0.0005
duration_s = {DURATION}
controller_rate_hz = 500
seed = 5
default_ground = "concrete"

[log]
robots = ["a-*", "b-00[01]", "c-*"]
{first}{second}
[[robots]]
name = "c-000"
model = "quad12"
start_position_m = [0.0, 6.0, 0.5]
log = false
"#
    )
}

const HERD_A: &str = r#"
[[herds]]
name = "a"
count = 4
layout = { kind = "grid", columns = 4, spacing_m = [1.0, 1.0] }
[herds.robot]
model = "quad16"
[herds.robot.controller]
kind = "vmc"
[herds.vary]
"log.rate_hz" = [500.0, 250.0, 100.0, "full"]
"controller.v_x_mps" = [0.2, 0.3]
"#;

const HERD_B: &str = r#"
[[herds]]
name = "b"
count = 3
layout = { kind = "grid", columns = 3, spacing_m = [1.0, 1.0], origin_m = [0.0, 3.0] }
[herds.robot]
model = "quad12"
[herds.robot.controller]
kind = "joint_pd"
"#;

/// Runs `src` with its own plan (`overrides` over the scenario) at `threads`;
/// returns the log read back, its bytes and each robot's decimation.
fn run(
    src: &str,
    threads: usize,
    overrides: &LogOverrides,
    tag: &str,
) -> (LogContents, Vec<u8>, LogPlan) {
    let dir = tmp(tag);
    let scn = parse_scenario(&dir.join("herdlog.toml"), src.to_string()).unwrap();
    let mut w = build_world(
        &scn,
        Overrides {
            threads,
            ..Default::default()
        },
    )
    .unwrap();
    let plan = LogPlan::new(&scn, &w, 4, overrides);
    let path = dir.join("log.mcap");
    let log = start_run_log_with(&scn, &mut w, &path, &plan).unwrap();
    w.sim.run(w.steps);
    assert_eq!(w.sim.clock().step, STEPS);
    log.finish(&mut w, &RunOutcome::default()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let c = read_log(&path).unwrap();
    assert_eq!(c.error, None);
    let _ = std::fs::remove_dir_all(dir);
    (c, bytes, plan)
}

/// Asserts every logged robot's per-step channels hold ⌊N/d⌋ + 1 messages
/// at t = k·d·dt, unlogged robots have none, every robot has its metrics,
/// and `/tf` has one message per instant at which any robot was due.
fn check_counts(c: &LogContents, plan: &LogPlan) {
    let dt_ns = 500_000u64;
    let mut instants = std::collections::BTreeSet::new();
    for (_, name, every) in &plan.robots {
        for topic in PER_STEP {
            let t = format!("/{name}/{topic}");
            let times: Vec<u64> = c.topic(&t).map(|m| m.log_time_ns).collect();
            match every {
                Some(d) => {
                    let want: Vec<u64> = (0..=STEPS / d).map(|k| k * d * dt_ns).collect();
                    assert_eq!(times, want, "{t} at d = {d}");
                    instants.extend(want);
                }
                None => assert!(times.is_empty(), "{t}: {} messages", times.len()),
            }
        }
        assert_eq!(c.topic(&format!("/{name}/metrics")).count(), 1, "{name}");
    }
    let tf: Vec<u64> = c.topic("/tf").map(|m| m.log_time_ns).collect();
    assert_eq!(tf, instants.into_iter().collect::<Vec<_>>());
}

#[test]
fn each_robot_logs_at_its_own_decimation_and_only_selected_robots_log() {
    let src = herd_src(HERD_A, HERD_B);
    let (c, _, plan) = run(&src, 2, &LogOverrides::default(), "scn");
    let every: BTreeMap<&str, Option<u64>> = plan
        .robots
        .iter()
        .map(|(_, n, d)| (n.as_str(), *d))
        .collect();
    assert_eq!(
        every,
        BTreeMap::from([
            ("a-000", Some(4)),
            ("a-001", Some(8)),
            ("a-002", Some(20)),
            ("a-003", Some(1)),
            ("b-000", Some(4)),
            ("b-001", Some(4)),
            ("b-002", None),
            ("c-000", None),
        ])
    );
    check_counts(&c, &plan);
    // 210 = 52·4 + 2: counts are ⌊N/d⌋ + 1 = 53, 27, 11, 211
    assert_eq!(c.topic("/a-000/com").count(), 53);
    assert_eq!(c.topic("/a-001/com").count(), 27);
    assert_eq!(c.topic("/a-002/com").count(), 11);
    assert_eq!(c.topic("/a-003/com").count(), 211);
    // the unselected robots have no channel but their metrics, and no link shapes
    for name in ["b-002", "c-000"] {
        let prefix = format!("/{name}/");
        let topics: Vec<String> = c
            .topics()
            .into_iter()
            .filter(|t| t.starts_with(&prefix))
            .collect();
        assert_eq!(topics, [format!("/{name}/metrics")]);
        let scene = String::from_utf8(c.topic("/scene").next().unwrap().data.clone()).unwrap();
        assert!(!scene.contains(&format!("\"{name}/")), "{name} in /scene");
        let tf = c.topic("/tf").next().unwrap().json().unwrap().to_string();
        assert!(!tf.contains(&format!("\"{name}/")), "{name} in /tf");
    }
    // the decimations are recorded for readers of the log
    let each: serde_json::Value =
        serde_json::from_str(c.meta("quadsim", "robot_log_every_steps").unwrap()).unwrap();
    assert_eq!(each["a-002"], 20);
    assert_eq!(each["c-000"], serde_json::Value::Null);
    assert_eq!(c.meta("quadsim", "log_every_steps"), Some("4"));
}

#[test]
fn command_line_patterns_replace_the_selection_and_set_rates() {
    let src = herd_src(HERD_A, HERD_B);
    let o = LogOverrides {
        robots: Some(LogOverrides::parse_robots("b-*,c-000").unwrap()),
        rates: vec![
            (RobotPattern::new("b-*").unwrap(), 10),
            (RobotPattern::new("b-001").unwrap(), 7),
        ],
    };
    let (c, _, plan) = run(&src, 1, &o, "cli");
    let every: BTreeMap<&str, Option<u64>> = plan
        .robots
        .iter()
        .map(|(_, n, d)| (n.as_str(), *d))
        .collect();
    // a-* deselected; b-002 and c-000 (log = false in the file) selected;
    // the later pattern wins for b-001
    assert_eq!(
        every,
        BTreeMap::from([
            ("a-000", None),
            ("a-001", None),
            ("a-002", None),
            ("a-003", None),
            ("b-000", Some(10)),
            ("b-001", Some(7)),
            ("b-002", Some(10)),
            ("c-000", Some(4)),
        ])
    );
    check_counts(&c, &plan);
}

/// Sixteen more quad12 at the world rate: instants with ≥ 16 robots due are
/// sampled on the thread pool (`PARALLEL_SAMPLING_MIN_ROBOTS`).
const HERD_D: &str = r#"
[[herds]]
name = "d"
count = 16
layout = { kind = "grid", columns = 8, spacing_m = [1.0, 1.0], origin_m = [-4.0, -4.0] }
[herds.robot]
model = "quad12"
[herds.robot.controller]
kind = "joint_pd"
"#;

#[test]
fn a_decimated_selective_log_is_byte_identical_across_threads_and_per_robot_across_order() {
    let with_d = |src: String| src.replace("\"c-*\"]", "\"c-*\", \"d-*\"]");
    let src = with_d(herd_src(HERD_A, &format!("{HERD_B}{HERD_D}")));
    // the instants at multiples of 4 steps must sample in parallel
    const { assert!(16 + 3 >= quadsim::systems::PARALLEL_SAMPLING_MIN_ROBOTS) };
    let o = LogOverrides::default();
    let (c1, one, plan) = run(&src, 1, &o, "t1");
    check_counts(&c1, &plan);
    let (_, two, _) = run(&src, 2, &o, "t2");
    assert!(one == two, "1 and 2 threads write different files");
    let (_, again, _) = run(&src, 2, &o, "t2b");
    assert!(two == again, "repeated runs differ");
    // herds swapped in the file: each robot's messages are the same bytes
    let (c3, _, _) = run(
        &with_d(herd_src(&format!("{HERD_D}{HERD_B}"), HERD_A)),
        2,
        &o,
        "swap",
    );
    let by_robot = |c: &LogContents| {
        let mut m: BTreeMap<String, Vec<(u64, Vec<u8>)>> = BTreeMap::new();
        for msg in &c.messages {
            if let Some(rest) = msg.topic.strip_prefix('/')
                && let Some((robot, _)) = rest.split_once('/')
            {
                m.entry(format!("{robot} {}", msg.topic))
                    .or_default()
                    .push((msg.log_time_ns, msg.data.clone()));
            }
        }
        m
    };
    let (a, b) = (by_robot(&c1), by_robot(&c3));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    assert!(a == b, "robot order changes a robot's log messages");
}

#[test]
fn the_default_plan_equals_the_uniform_log_of_before() {
    // no rates, no selection: start_run_log's plan is every robot at d
    let src = herd_src(HERD_A, HERD_B)
        .replace("\"log.rate_hz\" = [500.0, 250.0, 100.0, \"full\"]\n", "")
        .replace("robots = [\"a-*\", \"b-00[01]\", \"c-*\"]\n", "");
    let dir = tmp("uniform");
    let scn = parse_scenario(&dir.join("u.toml"), src).unwrap();
    let mut w = build_world(&scn, Overrides::default()).unwrap();
    let path = dir.join("log.mcap");
    let log = start_run_log(&scn, &mut w, &path, 8).unwrap();
    w.sim.run(w.steps);
    log.finish(&mut w, &RunOutcome::default()).unwrap();
    let c = read_log(&path).unwrap();
    let plan = LogPlan::new(&scn, &w, 8, &LogOverrides::default());
    assert!(!plan.is_uniform(), "c-000 has log = false");
    let each: serde_json::Value =
        serde_json::from_str(c.meta("quadsim", "robot_log_every_steps").unwrap()).unwrap();
    let obj = each.as_object().unwrap();
    assert_eq!(obj.len(), 8);
    assert!(
        obj.iter()
            .all(|(n, d)| if n == "c-000" { d.is_null() } else { d == 8 }),
        "{each}"
    );
    check_counts(&c, &plan);
    let _ = std::fs::remove_dir_all(dir);
}

fn quadsim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
}

fn write_scenario(dir: &Path, src: &str) -> PathBuf {
    let p = dir.join("herdlog.toml");
    std::fs::write(&p, src).unwrap();
    p
}

#[test]
fn the_cli_selects_robots_sets_rates_and_runs_summary_only() {
    let dir = tmp("cmd");
    let scn = write_scenario(&dir, &herd_src(HERD_A, HERD_B));
    let out = dir.join("out");
    let o = quadsim()
        .arg("run")
        .arg(&scn)
        .args(["--quiet", "--no-monitor", "--no-report", "--threads", "1"])
        .args([
            "--log-robots",
            "a-00[01],b-000",
            "--log-rate",
            "250",
            "--log-rate",
        ])
        .arg("a-001=full")
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = read_log(&out.join("log.mcap")).unwrap();
    // a-000 keeps its own 500 Hz over the world rate; b-000 takes the
    // command line's world rate (250 Hz); a-001's pattern rate beats its own
    assert_eq!(c.topic("/a-000/com").count() as u64, STEPS / 4 + 1);
    assert_eq!(c.topic("/b-000/com").count() as u64, STEPS / 8 + 1);
    assert_eq!(c.topic("/a-001/com").count() as u64, STEPS + 1);
    assert_eq!(c.topic("/a-002/com").count(), 0);
    assert_eq!(c.topic("/b-001/com").count(), 0);

    // summary only: summary.json and report.md, no log
    for flag in [["--summary-only", ""], ["--log", "summary"]] {
        let out = dir.join(format!("summary{}", flag[0].len()));
        let o = quadsim()
            .arg("run")
            .arg(&scn)
            .args(["--quiet", "--no-monitor"])
            .args(flag.iter().filter(|a| !a.is_empty()))
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(!out.join("log.mcap").exists());
        assert!(out.join("report.md").exists());
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(s["robots"].as_array().unwrap().len(), 8);
    }
    // `[log] mode = "summary"` in the file
    let scn2 = dir.join("summary.toml");
    std::fs::write(
        &scn2,
        herd_src(HERD_A, HERD_B).replace("[log]\n", "[log]\nmode = \"summary\"\n"),
    )
    .unwrap();
    let out2 = dir.join("mode");
    let o = quadsim()
        .arg("run")
        .arg(&scn2)
        .args(["--quiet", "--no-monitor", "--no-report", "--out"])
        .arg(&out2)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out2.join("summary.json").exists() && !out2.join("log.mcap").exists());

    // a pattern matching no robot is an error naming the flag
    let o = quadsim()
        .arg("run")
        .arg(&scn)
        .args(["--quiet", "--no-monitor", "--log-robots", "zz*", "--out"])
        .arg(dir.join("bad"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--log-robots") && err.contains("zz*"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn scenario_log_errors_name_the_key_and_line() {
    let dir = Path::new("herdlog.toml");
    for (from, to, key) in [
        (
            "robots = [\"a-*\", \"b-00[01]\", \"c-*\"]",
            "robots = [\"a-*\", \"nobody-*\"]",
            "log.robots[1]",
        ),
        (
            "\"log.rate_hz\" = [500.0, 250.0, 100.0, \"full\"]",
            "\"log.rate_hz\" = [500.0, 300.0]",
            "herds[0].vary.\"log.rate_hz\"",
        ),
        ("log = false", "log = { enabled = false, rte_hz = 5 }", ""),
    ] {
        let src = herd_src(HERD_A, HERD_B).replace(from, to);
        let e = parse_scenario(dir, src).unwrap_err();
        assert!(e.line > 0, "{e}");
        if key.is_empty() {
            assert!(e.to_string().contains("rte_hz"), "{e}");
        } else {
            assert_eq!(e.key_path, key, "{e}");
        }
    }
}
