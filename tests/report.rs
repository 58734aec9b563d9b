//! `report.md` and `plots/`: written by `quadsim run`, rebuilt identically by
//! `quadsim report LOG` from the log alone; valid SVG and PNG; the numbers in
//! the text are the summary's; Study A's rows for quad16, Study B's for quad12.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-report-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn quadsim(args: &[&str]) -> std::process::Output {
    let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "quadsim {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const PLOTS: [&str; 8] = [
    "com",
    "speed",
    "attitude",
    "joints",
    "torques",
    "foot_forces",
    "foot_paths",
    "support",
];

/// Decodes a PNG; returns (width, height, number of distinct RGB colours).
fn decode_png(p: &Path) -> (u32, u32, usize) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", p.display());
    let mut colours = std::collections::BTreeSet::new();
    for px in buf[..info.buffer_size()].chunks(3) {
        colours.insert((px[0], px[1], px[2]));
    }
    (info.width, info.height, colours.len())
}

#[test]
fn a_trot_run_writes_report_and_plots_that_report_rebuilds_from_the_log() {
    let dir = tmp("trot");
    let out = dir.join("run");
    let scn = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/trot.toml");
    quadsim(&["run", scn, "--duration", "1", "--out", s(&out), "--quiet"]);
    let summary = read_json(&out.join("summary.json"));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();

    // the plots: valid SVG and PNG of the stated size, with drawn content
    for p in PLOTS {
        let svg = std::fs::read_to_string(out.join(format!("plots/rex_{p}.svg"))).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{p}"
        );
        assert!(
            svg.contains("<polyline") || svg.contains("<path"),
            "{p}: no line"
        );
        let (w, h, colours) = decode_png(&out.join(format!("plots/rex_{p}.png")));
        assert_eq!((w, h), quadsim::report::plots::PLOT_SIZE, "{p}");
        assert!(colours > 10, "{p}: {colours} colours: a blank image?");
        assert!(
            report.contains(&format!("(plots/rex_{p}.svg)")),
            "{p} not linked"
        );
    }
    // the captions are drawn with the bundled font: axis text appears in the SVG
    let speed = std::fs::read_to_string(out.join("plots/rex_speed.svg")).unwrap();
    assert!(speed.contains("commanded v_x") && speed.contains("t (s)"));

    // the numbers in the text are the summary's
    let r = &summary["robots"][0];
    let f3 = |k: &str| format!("{:.3}", r[k].as_f64().unwrap());
    assert!(
        report.contains(&format!(
            "| mean forward speed (m/s) | 1.2 | {} |",
            f3("mean_forward_speed_mps")
        )),
        "{report}"
    );
    assert!(report.contains(&format!(
        "| max vertical foot force (N) | ≈ 150 | {:.1} |",
        r["max_foot_force_n"].as_f64().unwrap()
    )));
    let p2p = r["base_height_p2p_m"].as_f64().unwrap();
    assert!(report.contains(&format!("| {:.2} % |", 100.0 * p2p / 0.5)));
    assert!(report.contains(&format!(
        "| joint tracking RMS (rad) | 0.05 | {:.4} |",
        r["joint_rms_error_rad"].as_f64().unwrap()
    )));
    assert!(report.contains("commanded v_x = 0.5 m/s"));
    let knee = r["joints"]
        .as_array()
        .unwrap()
        .iter()
        .find(|j| j["name"] == "LF_knee")
        .unwrap();
    assert!(report.contains(&format!(
        "| `LF_knee` | {:.2} | {:.2} |",
        knee["peak_abs_torque_nm"].as_f64().unwrap(),
        knee["mean_abs_torque_nm"].as_f64().unwrap()
    )));
    assert!(!report.contains("wall"), "no wall-clock value in report.md");

    // `quadsim report` rebuilds the same summary (but timing), text and plots
    let rebuilt = dir.join("rebuilt");
    quadsim(&["report", s(&out.join("log.mcap")), "--out", s(&rebuilt)]);
    let mut expected = summary.clone();
    expected.as_object_mut().unwrap().remove("timing");
    assert_eq!(read_json(&rebuilt.join("summary.json")), expected);
    assert_eq!(
        std::fs::read_to_string(rebuilt.join("report.md")).unwrap(),
        report
    );
    for p in PLOTS {
        for ext in ["svg", "png"] {
            let name = format!("plots/rex_{p}.{ext}");
            assert!(
                std::fs::read(out.join(&name)).unwrap()
                    == std::fs::read(rebuilt.join(&name)).unwrap(),
                "{name} differs"
            );
        }
    }

    // --no-report writes none
    let bare = dir.join("bare");
    quadsim(&[
        "run",
        scn,
        "--duration",
        "0.1",
        "--out",
        s(&bare),
        "--quiet",
        "--no-report",
    ]);
    assert!(bare.join("summary.json").exists());
    assert!(!bare.join("report.md").exists() && !bare.join("plots").exists());
}

/// Study B's rows for a quad12: the per-axis CoM figures and the torque
/// ratios are the summary's numbers; a run without a log has no plots.
#[test]
fn a_quad12_gets_study_b_rows() {
    let dir = tmp("quad12");
    let scn = dir.join("s.toml");
    std::fs::write(
        &scn,
        r#"format_version = 1
[world]
name = "small"
dt_s = 0.0005
duration_s = 0.5
default_ground = "concrete"

[[robots]]
name = "bee"
model = "quad12"
[robots.controller]
kind = "joint_pd"
bandwidth_hz = 3.0
gravity_compensation = "static"
"#,
    )
    .unwrap();
    let out = dir.join("run");
    quadsim(&["run", s(&scn), "--out", s(&out), "--quiet", "--no-log"]);
    let summary = read_json(&out.join("summary.json"));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(!out.join("plots").exists());
    assert!(report.contains("wrote no log"), "{report}");
    assert!(report.contains("Study B") && !report.contains("| quantity | Study A |"));
    let r = &summary["robots"][0];
    let mm = |k: &str, a: usize| format!("{:.2}", r[k][a].as_f64().unwrap() * 1e3);
    assert!(report.contains(&format!(
        "| forward x displacement (mm) | 466.7 | {} |",
        mm("com_displacement_m", 0)
    )));
    assert!(report.contains(&format!(
        "| vertical z oscillation amplitude (mm) | ±1.17 | ±{} |",
        mm("com_oscillation_m", 2)
    )));
    // knee / hip peak ratio from the per-joint peaks
    let peak = |suffix: &str| {
        r["joints"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|j| j["name"].as_str().unwrap().ends_with(suffix))
            .map(|j| j["peak_abs_torque_nm"].as_f64().unwrap())
            .fold(0.0, f64::max)
    };
    let ratio = peak("knee") / peak("hip_pitch");
    assert!(ratio.is_finite() && ratio > 0.0);
    assert!(
        report.contains(&format!("| knee / hip, peaks | 3.53 | {ratio:.2} |")),
        "{report}"
    );
    // standing on four feet: a support polygon, a positive margin
    let m = r["min_stability_margin_m"].as_f64().unwrap();
    assert!(m > 0.0);
    assert!(report.contains(&format!(
        "| least stability margin (mm) | > 20 | {:.1} |",
        m * 1e3
    )));
}

/// Several robots: one set of plots per robot, named after it, a metrics
/// column and a studies section each; a robot logged with `log = false` has
/// its metrics but no plots.
#[test]
fn several_robots_get_plots_named_per_robot() {
    let dir = tmp("grounds");
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/grounds.toml"
    ))
    .unwrap();
    // the last robot is not logged
    let pos = src.rfind("[[robots]]").unwrap();
    let (a, b) = src.split_at(pos);
    let edited = format!(
        "{a}{}",
        b.replacen("[[robots]]\n", "[[robots]]\nlog = false\n", 1)
    );
    let scn = dir.join("grounds.toml");
    std::fs::write(&scn, edited).unwrap();
    let out = dir.join("run");
    quadsim(&[
        "run",
        s(&scn),
        "--duration",
        "0.1",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let summary = read_json(&out.join("summary.json"));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    let names: Vec<&str> = summary["robots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap())
        .collect();
    assert_eq!(names.len(), 4);
    let header = report
        .lines()
        .find(|l| l.starts_with("| metric |"))
        .unwrap();
    for (k, n) in names.iter().enumerate() {
        assert!(header.contains(n), "{header}");
        assert!(report.contains(&format!("### `{n}` (quad16)")), "{n}");
        let logged = k < 3;
        for p in PLOTS {
            assert_eq!(
                out.join(format!("plots/{n}_{p}.png")).exists(),
                logged,
                "{n}_{p}"
            );
        }
    }
}

/// A herd's report (issue 29, item 9) keeps every robot's model and
/// aggregates across robots: one mean/min/max table instead of a column per
/// robot, the worst robots named with their model, and the per-robot detail
/// and plots capped at four robots, however many were logged. `quadsim
/// report` rebuilds the same text from the log.
#[test]
fn a_herd_report_aggregates_across_robots_and_keeps_their_models() {
    let dir = tmp("herd");
    let herd = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/herd.toml");
    quadsim(&[
        "run",
        s(&herd),
        "--out",
        s(&dir),
        "--duration",
        "0.3",
        "--log-robots",
        "q16-00*,q12-00*",
        "--log-rate",
        "50",
        "--quiet",
        "--no-monitor",
    ]);
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let summary = read_json(&dir.join("summary.json"));
    let n = summary["robots"].as_array().unwrap().len();
    assert_eq!(n, 102);
    // no table has a column per robot: every table row has at most 7 cells
    let widest = md
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| l.matches('|').count() - 1)
        .max()
        .unwrap();
    assert!(widest <= 7, "a table with {widest} columns");
    assert!(
        md.contains("| metric | mean | min | max | min at | max at |"),
        "{md}"
    );
    assert!(md.contains(&format!("across the herd's {n} robots")));
    // the aggregate is the summary's: the mean forward speed across robots
    let speeds: Vec<f64> = summary["robots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["mean_forward_speed_mps"].as_f64().unwrap())
        .collect();
    let mean = speeds.iter().sum::<f64>() / n as f64;
    let max = speeds.iter().cloned().fold(f64::MIN, f64::max);
    assert!(
        md.contains(&format!("| mean forward speed (m/s) | {mean:.3} |")),
        "{md}"
    );
    assert!(md.contains(&format!(" | {max:.3} | `")), "{md}");
    // the detail and the plots: four robots, each with its model
    let detailed: Vec<&str> = md
        .lines()
        .filter(|l| l.starts_with("### `"))
        .filter(|l| l.ends_with(')'))
        .collect();
    assert_eq!(detailed.len(), 4, "{detailed:?}");
    for l in &detailed {
        assert!(l.ends_with("(quad16)") || l.ends_with("(quad12)"), "{l}");
    }
    assert!(!md.contains("()"), "a robot without its model");
    assert!(!md.contains("Neither study's robot"), "{md}");
    // and the Motion section's pictures: filmstrips of the first detailed
    // robots and one world snapshot
    let plots = std::fs::read_dir(dir.join("plots")).unwrap().count();
    assert_eq!(
        plots,
        4 * 2 * PLOTS.len() + quadsim::report::filmstrip::MAX_ROBOTS + 1,
        "plot files"
    );
    // the worst robots' table names a model in every row
    let worst = md.split("### Worst robots").nth(1).unwrap();
    let rows: Vec<&str> = worst
        .lines()
        .filter(|l| l.starts_with("| `"))
        .take(4)
        .collect();
    assert_eq!(rows.len(), 4);
    for r in rows {
        assert!(r.contains("| quad16 |") || r.contains("| quad12 |"), "{r}");
    }
    // rebuilt from the log: the same text
    let rebuilt = dir.join("rebuilt");
    quadsim(&["report", s(&dir.join("log.mcap")), "--out", s(&rebuilt)]);
    assert_eq!(
        std::fs::read_to_string(rebuilt.join("report.md")).unwrap(),
        md
    );
}

/// The peak of each joint's `|effort|` column in an exported CSV.
fn csv_peaks(path: &Path, prefix: &str) -> std::collections::BTreeMap<String, f64> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    let mut peaks = std::collections::BTreeMap::new();
    for row in r.records() {
        let row = row.unwrap();
        for (h, x) in header.iter().zip(row.iter()) {
            if let Some(joint) = h.strip_prefix(prefix)
                && let Ok(x) = x.parse::<f64>()
            {
                let p = peaks.entry(joint.to_string()).or_insert(0.0_f64);
                *p = p.max(x.abs());
            }
        }
    }
    peaks
}

/// The rows `| `name` | a | b | … |` of the first table after `heading`.
fn table_after<'a>(md: &'a str, heading: &str) -> Vec<Vec<&'a str>> {
    md.split(heading)
        .nth(1)
        .unwrap_or_else(|| panic!("no {heading:?} in report.md"))
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter(|l| l.starts_with("| `"))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect()
}

/// Issue 29, item 9: one applied peak torque per joint. quad16 trotting at
/// 1 m/s on its DC motors meets their torque–speed envelope below the stall
/// torque (the demand near 100 N·m, the motor giving about 97 N·m at
/// speed): the report's joint-torque table, its actuator table's "peak
/// applied", summary.json's `peak_abs_torque_nm` and `peak_torque_nm`, and
/// the log's joint effort (exported CSV, every step) all hold the motor's
/// torque. (The actuator figures held the demand clamped at the stall
/// torque, and the log the controller's command clamped at the effort
/// limit.)
#[test]
fn the_peak_applied_torque_agrees_across_report_summary_and_csv() {
    let dir = tmp("torques");
    let trot =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/trot.toml"))
            .unwrap()
            .replace("v_x_mps = 0.5", "v_x_mps = 1.0");
    let scenario = dir.join("fast_trot.toml");
    std::fs::write(&scenario, trot).unwrap();
    let out = dir.join("out");
    quadsim(&[
        "run",
        s(&scenario),
        "--out",
        s(&out),
        "--duration",
        "3",
        "--log-rate",
        "full",
        "--quiet",
        "--no-monitor",
    ]);
    let summary = read_json(&out.join("summary.json"));
    let r = &summary["robots"][0];
    let joints = r["joints"].as_array().unwrap();
    let actuators = r["actuators"]["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 16);
    assert_eq!(actuators.len(), 16);
    // the case in point: a motor's envelope held its torque well below a
    // demand that was itself within the stall torque
    // (the demand's peak against the metrics' applied peak)
    let held = actuators
        .iter()
        .zip(joints)
        .map(|(a, j)| {
            a["peak_demand_nm"].as_f64().unwrap() - j["peak_abs_torque_nm"].as_f64().unwrap()
        })
        .fold(0.0, f64::max);
    assert!(
        held > 1.0,
        "no joint's envelope held its torque: {held} N·m"
    );
    csv_dir_export(&out);
    let efforts = csv_peaks(&out.join("csv/rex.joint_states.csv"), "effort.");
    assert_eq!(efforts.len(), 16, "{efforts:?}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let torque_rows = table_after(&md, "Joint torques of `rex`");
    let actuator_rows = table_after(&md, "| joint | kind | capacity (N·m) | peak applied (N·m)");
    assert_eq!(torque_rows.len(), 16);
    assert_eq!(actuator_rows.len(), 16);
    for (k, (j, a)) in joints.iter().zip(actuators).enumerate() {
        let name = j["name"].as_str().unwrap();
        assert_eq!(a["joint"].as_str(), Some(name));
        let peak = j["peak_abs_torque_nm"].as_f64().unwrap();
        // summary.json: one quantity under both keys
        assert_eq!(a["peak_torque_nm"].as_f64().unwrap(), peak, "{name}");
        assert!(
            (a["peak_torque_share"].as_f64().unwrap() - peak / 100.0).abs() < 1e-12,
            "{name}"
        );
        // the log's effort at every step reaches the same peak
        assert!(
            (efforts[name] - peak).abs() <= 1e-9 * peak.max(1.0),
            "{name}: log {} against summary {peak}",
            efforts[name]
        );
        // report.md: the two tables print it (2 and 3 decimals)
        assert_eq!(torque_rows[k][0], format!("`{name}`"));
        assert_eq!(torque_rows[k][1], format!("{peak:.2}"), "{name}");
        assert_eq!(actuator_rows[k][0], format!("`{name}`"));
        assert_eq!(actuator_rows[k][3], format!("{peak:.3}"), "{name}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

fn csv_dir_export(out: &Path) {
    quadsim(&[
        "export",
        s(&out.join("log.mcap")),
        "--csv",
        s(&out.join("csv")),
    ]);
}

/// A servo robot's logged joint effort is the servo's torque, within its
/// 0.3 N·m capacity, not its controller's unused command clamped at the
/// joint's 20 N·m effort limit; its peak is summary.json's.
#[test]
fn a_servos_logged_effort_is_the_servos_torque() {
    let dir = tmp("servo_effort");
    let servo = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/small_trot_servo.toml");
    quadsim(&[
        "run",
        s(&servo),
        "--out",
        s(&dir),
        "--duration",
        "0.5",
        "--log-rate",
        "full",
        "--quiet",
        "--no-monitor",
        "--no-report",
    ]);
    csv_dir_export(&dir);
    let efforts = csv_peaks(&dir.join("csv/bee.joint_states.csv"), "effort.");
    let commands = csv_peaks(&dir.join("csv/bee.joint_commands.csv"), "effort.");
    let summary = read_json(&dir.join("summary.json"));
    let joints = summary["robots"][0]["joints"].as_array().unwrap();
    assert_eq!(efforts.len(), 12, "{efforts:?}");
    for j in joints {
        let name = j["name"].as_str().unwrap();
        let peak = j["peak_abs_torque_nm"].as_f64().unwrap();
        assert!(efforts[name] <= 0.3 + 1e-12, "{name}: {}", efforts[name]);
        assert!((efforts[name] - peak).abs() <= 1e-12, "{name}");
    }
    // the controller's command (joint_commands) is what it is: far beyond
    assert!(commands.values().any(|&c| c > 1.0), "{commands:?}");
    let _ = std::fs::remove_dir_all(dir);
}
