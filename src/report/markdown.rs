//! The text of `report.md`: plain Markdown that reads well in a terminal.
//! Every number comes from `summary.json` (itself the simulation's full-rate
//! metrics, or the log's `metrics` messages), so the run's report and the one
//! `quadsim report` rebuilds from the log are the same text. No wall-clock
//! value appears in it.

use std::fmt::Write as _;

use quadsim_engine::robots::SourceStudy;
use serde_json::Value;

use super::input::{ReportInput, robot_info};

/// A number with `d` decimals, "—" when absent or not finite.
fn num(v: &Value, d: usize) -> String {
    match v.as_f64() {
        Some(x) if x.is_finite() => format!("{x:.d$}"),
        _ => "—".into(),
    }
}

/// `[min, max]` with `d` decimals.
fn range(v: &Value, d: usize) -> String {
    match v.as_array() {
        Some(a) if a.len() == 2 => format!("[{}, {}]", num(&a[0], d), num(&a[1], d)),
        _ => "—".into(),
    }
}

/// `[x, y, z]` scaled by `k` with `d` decimals.
fn triple(v: &Value, k: f64, d: usize) -> String {
    match v.as_array() {
        Some(a) if a.len() == 3 => {
            let f = |x: &Value| {
                x.as_f64()
                    .map_or("—".to_string(), |x| format!("{:.d$}", x * k))
            };
            format!("[{}, {}, {}]", f(&a[0]), f(&a[1]), f(&a[2]))
        }
        _ => "—".into(),
    }
}

/// Footnotes of a section, numbered in order of first use.
#[derive(Default)]
struct Notes(Vec<String>);

impl Notes {
    /// The marker of note `text` (added on first use).
    fn mark(&mut self, text: &str) -> String {
        let k = match self.0.iter().position(|t| t == text) {
            Some(k) => k,
            None => {
                self.0.push(text.to_string());
                self.0.len() - 1
            }
        };
        format!("[^{}]", k + 1)
    }

    /// "—" with a footnote saying why.
    fn missing(&mut self, why: &str) -> String {
        format!("—{}", self.mark(why))
    }

    fn write(&self, out: &mut String, prefix: &str) {
        if self.0.is_empty() {
            return;
        }
        out.push('\n');
        for (k, t) in self.0.iter().enumerate() {
            let _ = writeln!(out, "[^{prefix}{}]: {t}", k + 1);
        }
    }
}

fn table(out: &mut String, header: &[&str], rows: &[Vec<String>]) {
    let _ = writeln!(out, "| {} |", header.join(" | "));
    let _ = writeln!(
        out,
        "|{}",
        header.iter().map(|_| "---|").collect::<String>()
    );
    for r in rows {
        let _ = writeln!(out, "| {} |", r.join(" | "));
    }
}

/// The metrics table rows: (label, key, formatter).
type Fmt = fn(&Value) -> String;
const METRIC_ROWS: [(&str, &str, Fmt); 22] = [
    ("fell", "fell", |v| match v.as_bool() {
        Some(true) => "**yes**".into(),
        Some(false) => "no".into(),
        None => "—".into(),
    }),
    ("fell at (s)", "fell_at_s", |v| num(v, 3)),
    ("mean forward speed (m/s)", "mean_forward_speed_mps", |v| {
        num(v, 3)
    }),
    ("peak forward speed (m/s)", "peak_forward_speed_mps", |v| {
        num(v, 3)
    }),
    ("torso height mean (m)", "base_height_mean_m", |v| num(v, 4)),
    ("torso height peak-to-peak (m)", "base_height_p2p_m", |v| {
        num(v, 4)
    }),
    ("CoM height mean (m)", "com_height_mean_m", |v| num(v, 4)),
    ("CoM height peak-to-peak (m)", "com_height_p2p_m", |v| {
        num(v, 4)
    }),
    ("roll range (rad)", "roll_range_rad", |v| range(v, 3)),
    ("pitch range (rad)", "pitch_range_rad", |v| range(v, 3)),
    ("yaw range (rad)", "yaw_range_rad", |v| range(v, 3)),
    ("joint tracking RMS (rad)", "joint_rms_error_rad", |v| {
        num(v, 4)
    }),
    ("max vertical foot force (N)", "max_foot_force_n", |v| {
        num(v, 1)
    }),
    ("energy (J)", "energy_j", |v| num(v, 1)),
    ("energy per step (J)", "energy_per_step_j", |v| num(v, 2)),
    ("foot touchdowns", "steps", |v| num(v, 0)),
    ("min stability margin (m)", "min_stability_margin_m", |v| {
        num(v, 4)
    }),
    ("distance (m)", "distance_m", |v| num(v, 3)),
    (
        "CoM displacement x, y, z (m, heading frame)",
        "com_displacement_m",
        |v| triple(v, 1.0, 4),
    ),
    (
        "CoM mean velocity x, y, z (m/s)",
        "com_mean_velocity_mps",
        |v| triple(v, 1.0, 4),
    ),
    (
        "CoM oscillation amplitude x, y, z (m)",
        "com_oscillation_m",
        |v| triple(v, 1.0, 4),
    ),
    (
        "largest push recovered from (N·s)",
        "push_recovery",
        push_text,
    ),
];

fn push_text(v: &Value) -> String {
    if v.is_null() {
        return "—".into();
    }
    format!(
        "{} ({} N for {} s)",
        num(&v["max_impulse_ns"], 2),
        num(&v["force_n"], 1),
        num(&v["duration_s"], 3)
    )
}

/// The joints whose names end in `suffix`.
fn joints_named<'a>(robot: &'a Value, suffix: &str) -> Vec<&'a Value> {
    robot["joints"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|j| j["name"].as_str().is_some_and(|n| n.ends_with(suffix)))
        .collect()
}

/// Largest peak and the mean of the means of |τ| over joints (N·m).
fn peak_and_mean(joints: &[&Value]) -> Option<(f64, f64)> {
    if joints.is_empty() {
        return None;
    }
    let peak = joints
        .iter()
        .filter_map(|j| j["peak_abs_torque_nm"].as_f64())
        .fold(0.0, f64::max);
    let mean = joints
        .iter()
        .filter_map(|j| j["mean_abs_torque_nm"].as_f64())
        .sum::<f64>()
        / joints.len() as f64;
    Some((peak, mean))
}

fn study_a(out: &mut String, r: &Value, notes: &mut Notes, command: &[(f64, f64)]) {
    let cmd = match command {
        [] => "no speed command (not the walking controller)".to_string(),
        [(_, v)] => format!("commanded v_x = {v} m/s"),
        _ => format!(
            "commanded v_x = {} m/s, changed by {} command events",
            command[0].1,
            command.len() - 1
        ),
    };
    let _ = writeln!(
        out,
        "Study A, trot on flat concrete at a 1.5 m/s target (reference.md, \"Experiment A\"); this run: {cmd}.\n"
    );
    let ride = 0.5;
    let p2p = r["base_height_p2p_m"].as_f64();
    let within = |key: &str| range(&r[key], 3);
    let opt = |notes: &mut Notes, v: &Value, d: usize, why: &str| {
        if v.as_f64().is_some() {
            num(v, d)
        } else {
            notes.missing(why)
        }
    };
    let mut rows = vec![
        vec![
            "mean forward speed (m/s)".into(),
            "1.2".into(),
            num(&r["mean_forward_speed_mps"], 3),
        ],
        vec![
            "peak forward speed (m/s)".into(),
            "1.45".into(),
            num(&r["peak_forward_speed_mps"], 3),
        ],
        vec![
            "torso height peak-to-peak (m)".into(),
            "0.007".into(),
            num(&r["base_height_p2p_m"], 4),
        ],
        vec![
            "torso height peak-to-peak, % of 0.5 m".into(),
            "1.4 %".into(),
            p2p.map_or("—".into(), |p| format!("{:.2} %", 100.0 * p / ride)),
        ],
        vec![
            "roll range (rad)".into(),
            "within ±0.2".into(),
            within("roll_range_rad"),
        ],
        vec![
            "pitch range (rad)".into(),
            "within ±0.2".into(),
            within("pitch_range_rad"),
        ],
        vec![
            "yaw range (rad)".into(),
            "within ±0.2".into(),
            within("yaw_range_rad"),
        ],
        vec![
            "joint tracking RMS (rad)".into(),
            "0.05".into(),
            opt(
                notes,
                &r["joint_rms_error_rad"],
                4,
                "the controller set no joint targets (no desired angles to track).",
            ),
        ],
        vec![
            "max vertical foot force (N)".into(),
            "≈ 150".into(),
            num(&r["max_foot_force_n"], 1),
        ],
        vec![
            "energy per step (J)".into(),
            "50".into(),
            opt(
                notes,
                &r["energy_per_step_j"],
                2,
                "no foot touched down in the run (no steps to divide the energy by).",
            ),
        ],
    ];
    push_row(&mut rows, r, notes);
    table(out, &["quantity", "Study A", "quadsim"], &rows);
}

fn push_row(rows: &mut Vec<Vec<String>>, r: &Value, notes: &mut Notes) {
    if r.get("push_recovery").is_some_and(|p| !p.is_null()) {
        rows.push(vec![
            "largest push impulse recovered from (N·s)".into(),
            notes.missing("the study reports no push experiment."),
            push_text(&r["push_recovery"]),
        ]);
    }
}

fn study_b(out: &mut String, r: &Value, notes: &mut Notes) {
    let _ = writeln!(
        out,
        "Study B, 5 s trot with prescribed joint angles (reference.md, \"Experiment B\"). Table 3, CoM per axis; its start and end values are in an unknown frame and are left out. quadsim's values are signed, in the heading frame (x along the start heading, y to its left, z up); Study B's are magnitudes.\n"
    );
    let axis = ["forward x", "lateral y", "vertical z"];
    let disp = [466.7, 18.5, 2.34];
    let speed = [93.34, 3.7, 0.468];
    let osc = [5.2, 9.25, 1.17];
    let mm = |key: &str, a: usize| {
        r[key]
            .as_array()
            .and_then(|v| v.get(a))
            .and_then(Value::as_f64)
            .map_or("—".to_string(), |x| format!("{:.2}", x * 1e3))
    };
    let mut rows = Vec::new();
    for a in 0..3 {
        rows.push(vec![
            format!("{} displacement (mm)", axis[a]),
            format!("{}", disp[a]),
            mm("com_displacement_m", a),
        ]);
    }
    for a in 0..3 {
        rows.push(vec![
            format!("{} mean speed (mm/s)", axis[a]),
            format!("{}", speed[a]),
            mm("com_mean_velocity_mps", a),
        ]);
    }
    for a in 0..3 {
        rows.push(vec![
            format!("{} oscillation amplitude (mm)", axis[a]),
            format!("±{}", osc[a]),
            format!("±{}", mm("com_oscillation_m", a)),
        ]);
    }
    table(out, &["quantity", "Study B", "quadsim"], &rows);
    let _ = writeln!(
        out,
        "\nTable 4, joint torques: Study B prints N·mm (its knee peak, 300 N·mm, is the Futaba S3003's rating), far below what the legs' own weight needs, so the ratios are the comparison. quadsim: peak = the largest |τ| over the four legs, mean = the legs' average time-mean |τ|; hip τ2 is `*_hip_pitch`, knee τ3 is `*_knee`.\n"
    );
    let hip = peak_and_mean(&joints_named(r, "hip_pitch"));
    let knee = peak_and_mean(&joints_named(r, "knee"));
    let no_joint = "the robot has no joint named `*_hip_pitch` or `*_knee`.";
    let val = |v: Option<f64>, d: usize, notes: &mut Notes| {
        v.filter(|x| x.is_finite())
            .map_or_else(|| notes.missing(no_joint), |x| format!("{x:.d$}"))
    };
    let zero = "undefined: the torque in the denominator is zero (no actuator torque was applied).";
    let ratio = |a: Option<f64>, b: Option<f64>, notes: &mut Notes| match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
        (Some(_), Some(_)) => notes.missing(zero),
        _ => notes.missing(no_joint),
    };
    let (hp, hm) = (hip.map(|h| h.0), hip.map(|h| h.1));
    let (kp, km) = (knee.map(|k| k.0), knee.map(|k| k.1));
    let mut rows = vec![
        vec![
            "hip τ2 peak (N·m)".into(),
            "0.085".into(),
            val(hp, 3, notes),
        ],
        vec![
            "hip τ2 mean (N·m)".into(),
            "0.025".into(),
            val(hm, 3, notes),
        ],
        vec![
            "knee τ3 peak (N·m)".into(),
            "0.300".into(),
            val(kp, 3, notes),
        ],
        vec![
            "knee τ3 mean (N·m)".into(),
            "0.080".into(),
            val(km, 3, notes),
        ],
        vec![
            "knee / hip, peaks".into(),
            format!("{:.2}", 300.0 / 85.0),
            ratio(kp, hp, notes),
        ],
        vec![
            "knee / hip, means".into(),
            format!("{:.2}", 80.0 / 25.0),
            ratio(km, hm, notes),
        ],
        vec![
            "hip peak / mean".into(),
            format!("{:.2}", 85.0 / 25.0),
            ratio(hp, hm, notes),
        ],
        vec![
            "knee peak / mean".into(),
            format!("{:.2}", 300.0 / 80.0),
            ratio(kp, km, notes),
        ],
    ];
    let margin = r["min_stability_margin_m"].as_f64();
    rows.push(vec![
        "least stability margin (mm)".into(),
        "> 20".into(),
        margin.map_or_else(
            || {
                notes.missing(
                    "fewer than three feet were ever in contact together (no support polygon).",
                )
            },
            |m| format!("{:.1}", m * 1e3),
        ),
    ]);
    push_row(&mut rows, r, notes);
    table(out, &["quantity", "Study B", "quadsim"], &rows);
}

/// Which state each robot's controller read, and for robots with a base
/// estimator how far its estimate was from the simulator's ground truth
/// (`summary.json`'s `sensing`; definitions in scenarios/README.md).
fn sensing(out: &mut String, robots: &[&Value]) {
    let _ = writeln!(
        out,
        "\n## Sensing and state estimation\n\nThe state each controller read: `estimated` (the base estimator, encoders and contact sensors) or `ground_truth` (the simulator's exact state, which no real robot has). Estimation error: the estimate against ground truth at each estimator update.\n"
    );
    let rows: Vec<Vec<String>> = robots
        .iter()
        .map(|r| {
            let s = &r["sensing"];
            let source = s["state_source"].as_str().unwrap_or("?");
            let mut row = vec![
                format!("`{}`", r["name"].as_str().unwrap_or("?")),
                if source == "ground_truth" {
                    "**ground truth**".to_string()
                } else {
                    source.to_string()
                },
            ];
            let e = &s["estimation"];
            for (key, d) in [
                ("tilt_rad", 4),
                ("orientation_rad", 4),
                ("velocity_mps", 3),
                ("height_m", 4),
            ] {
                row.push(if e.is_null() {
                    "–".into()
                } else {
                    format!("{} / {}", num(&e[key]["rms"], d), num(&e[key]["max"], d))
                });
            }
            row
        })
        .collect();
    table(
        out,
        &[
            "robot",
            "controller read",
            "tilt error RMS / max (rad)",
            "orientation error RMS / max (rad)",
            "velocity error RMS / max (m/s)",
            "height error RMS / max (m)",
        ],
        &rows,
    );
}

/// More robots than this make a herd: its report aggregates across robots
/// (mean, min, max; the worst robots) instead of one column per robot.
pub const HERD_MIN_ROBOTS: usize = 7;
/// A herd's report details (joint torques, sensing, plots, the studies) this
/// many robots: the worst ones (see [`herd_detail_order`]).
pub const HERD_DETAIL_ROBOTS: usize = 4;

/// A herd's robots, worst first: fallen ones by time of fall, then by speed
/// tracked (mean forward speed over the mean command, or the speed alone
/// without a command), then by name. The detail of a herd's report follows
/// this order.
pub fn herd_detail_order(summary: &Value) -> Vec<String> {
    let mut robots: Vec<&Value> = summary["robots"].as_array().into_iter().flatten().collect();
    let key = |r: &Value| {
        let fell = r["fell_at_s"].as_f64().unwrap_or(f64::INFINITY);
        let v = r["mean_forward_speed_mps"].as_f64().unwrap_or(f64::NAN);
        let tracked = match r["commanded_speed_mps"].as_f64() {
            Some(c) if c > 0.0 => v / c,
            _ => v,
        };
        (
            fell,
            if tracked.is_finite() {
                tracked
            } else {
                f64::NEG_INFINITY
            },
        )
    };
    robots.sort_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.total_cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then_with(|| a["name"].as_str().cmp(&b["name"].as_str()))
    });
    robots
        .iter()
        .filter_map(|r| r["name"].as_str().map(str::to_string))
        .collect()
}

/// A herd's metrics: per metric the mean, min and max across its robots
/// and which robots hold the min and max; then the worst robots.
fn herd_metrics(out: &mut String, robots: &[&Value], worst: &[&Value], scenario_text: &str) {
    let n = robots.len();
    let _ = writeln!(
        out,
        "\n## Metrics\n\nAccumulated at every simulation step (definitions: scenarios/README.md, \"Metrics\"), across the herd's {n} robots; every robot's own values are in `summary.json`.\n"
    );
    let fallen = robots
        .iter()
        .filter(|r| r["fell"] == Value::Bool(true))
        .count();
    let mut rows = vec![vec![
        "fell".to_string(),
        format!("{fallen} of {n}"),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
    ]];
    for (label, key, f) in METRIC_ROWS.iter() {
        // scalar metrics only; ranges by their extremes
        let (lo_hi, scalar): (Vec<(f64, f64, &str)>, bool) = match *key {
            "roll_range_rad" | "pitch_range_rad" | "yaw_range_rad" => (
                robots
                    .iter()
                    .filter_map(|r| {
                        let a = r[*key].as_array()?;
                        Some((
                            a.first()?.as_f64()?,
                            a.get(1)?.as_f64()?,
                            r["name"].as_str()?,
                        ))
                    })
                    .collect(),
                false,
            ),
            "fell"
            | "push_recovery"
            | "com_displacement_m"
            | "com_mean_velocity_mps"
            | "com_oscillation_m" => continue,
            _ => (
                robots
                    .iter()
                    .filter_map(|r| {
                        let x = r[*key].as_f64().filter(|x| x.is_finite())?;
                        Some((x, x, r["name"].as_str()?))
                    })
                    .collect(),
                true,
            ),
        };
        if lo_hi.is_empty() {
            rows.push(vec![
                label.to_string(),
                "—".into(),
                "—".into(),
                "—".into(),
                String::new(),
                String::new(),
            ]);
            continue;
        }
        let lo = lo_hi
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("not empty");
        let hi = lo_hi
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("not empty");
        let mean = if scalar {
            f(&serde_json::json!(
                lo_hi.iter().map(|x| x.0).sum::<f64>() / lo_hi.len() as f64
            ))
        } else {
            "—".into()
        };
        let fmt = |x: f64| {
            if scalar {
                f(&serde_json::json!(x))
            } else {
                num(&serde_json::json!(x), 3)
            }
        };
        let counted = if lo_hi.len() < n {
            format!(" ({} of {n} robots)", lo_hi.len())
        } else {
            String::new()
        };
        rows.push(vec![
            format!("{label}{counted}"),
            mean,
            fmt(lo.0),
            fmt(hi.1),
            format!("`{}`", lo.2),
            format!("`{}`", hi.2),
        ]);
    }
    table(
        out,
        &["metric", "mean", "min", "max", "min at", "max at"],
        &rows,
    );
    let _ = writeln!(
        out,
        "\nRange rows give the smallest lower and the largest upper end across robots.\n\n### Worst robots\n\nFallen robots first (earliest fall), then the lowest speed over its command.\n"
    );
    let rows: Vec<Vec<String>> = worst
        .iter()
        .map(|r| {
            let name = r["name"].as_str().unwrap_or("?");
            vec![
                format!("`{name}`"),
                robot_info(scenario_text, name).model,
                match r["fell_at_s"].as_f64() {
                    Some(t) => format!("**yes**, at {t:.3} s"),
                    None => "no".into(),
                },
                num(&r["mean_forward_speed_mps"], 3),
                num(&r["commanded_speed_mps"], 3),
                num(&r["min_stability_margin_m"], 4),
            ]
        })
        .collect();
    table(
        out,
        &[
            "robot",
            "model",
            "fell",
            "mean forward speed (m/s)",
            "mean command (m/s)",
            "min stability margin (m)",
        ],
        &rows,
    );
}

/// The whole `report.md`. `figures` lists, per robot, the plots written
/// (caption, file stem under `plots/`).
pub fn report_markdown(
    input: &ReportInput<'_>,
    figures: &[(String, Vec<(String, String)>)],
) -> String {
    render(
        &input.summary.to_json(),
        input.scenario_text,
        input.log.is_some(),
        figures,
    )
}

/// [`report_markdown`] over the summary's JSON view: the metric rows are
/// listed by key (`METRIC_ROWS`), as `summary.json` names them.
fn render(
    s: &Value,
    scenario_text: &str,
    logged: bool,
    figures: &[(String, Vec<(String, String)>)],
) -> String {
    let robots: Vec<&Value> = s["robots"].as_array().into_iter().flatten().collect();
    let mut out = String::new();
    let name = s["scenario"].as_str().unwrap_or("?");
    let _ = writeln!(out, "# quadsim run report: `{name}`\n");
    if s["log_truncated"].as_bool().unwrap_or(false) {
        let _ = writeln!(
            out,
            "**Log truncated**: the run was killed before it closed its log, so the metrics (written at the end) are missing; the plots cover the part recovered, up to t = {} s.\n",
            num(&s["sim_time_s"], 3)
        );
    }
    let interrupted = s["interrupted"].as_bool().unwrap_or(false);
    if interrupted {
        let _ = writeln!(
            out,
            "**Interrupted** (Ctrl-C or SIGTERM): everything below covers the part that ran.\n"
        );
    }
    let herd = robots.len() >= HERD_MIN_ROBOTS;
    // a herd's detail: its worst robots only
    let order = if herd {
        herd_detail_order(s)
    } else {
        Vec::new()
    };
    let detail: Vec<&Value> = if herd {
        order
            .iter()
            .take(HERD_DETAIL_ROBOTS)
            .filter_map(|n| {
                robots
                    .iter()
                    .find(|r| r["name"].as_str() == Some(n))
                    .copied()
            })
            .collect()
    } else {
        robots.clone()
    };
    let fell: Vec<String> = if herd {
        let fallen: Vec<&str> = robots
            .iter()
            .filter(|r| r["fell"] == Value::Bool(true))
            .filter_map(|r| r["name"].as_str())
            .collect();
        let shown = fallen
            .iter()
            .take(10)
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>();
        let more = if fallen.len() > shown.len() {
            format!(", … {} more", fallen.len() - shown.len())
        } else {
            String::new()
        };
        vec![if fallen.is_empty() {
            format!("none of {}", robots.len())
        } else {
            format!(
                "{} of {}: {}{more}",
                fallen.len(),
                robots.len(),
                shown.join(", ")
            )
        }]
    } else {
        robots
            .iter()
            .map(|r| {
                let n = r["name"].as_str().unwrap_or("?");
                match r["fell_at_s"].as_f64() {
                    Some(t) => format!("{n}: **yes**, at t = {t:.3} s"),
                    None => format!("{n}: no"),
                }
            })
            .collect()
    };
    let sha = s["scenario_sha256"].as_str().unwrap_or("?");
    let rows = vec![
        vec![
            "scenario".into(),
            format!("`{name}` (sha256 `{}…`)", &sha[..sha.len().min(16)]),
        ],
        vec!["seed".into(), s["seed"].to_string()],
        vec![
            "quadsim".into(),
            format!(
                "{}, commit `{}`",
                s["quadsim_version"].as_str().unwrap_or("?"),
                s["git_commit"].as_str().unwrap_or("?")
            ),
        ],
        vec![
            "simulated".into(),
            format!(
                "{} s: {} steps of {} s, {}, controller at {} Hz",
                num(&s["sim_time_s"], 3),
                s["steps"],
                s["dt_s"],
                s["integrator"].as_str().unwrap_or("?"),
                s["controller_rate_hz"]
            ),
        ],
        vec![
            "interrupted".into(),
            if interrupted { "**yes**" } else { "no" }.into(),
        ],
        vec!["fell".into(), fell.join("; ")],
    ];
    table(&mut out, &["run", ""], &rows);

    if herd {
        herd_metrics(&mut out, &robots, &detail, scenario_text);
    } else {
        // metrics, one column per robot
        let _ = writeln!(
            out,
            "\n## Metrics\n\nAccumulated at every simulation step (definitions: scenarios/README.md, \"Metrics\").\n"
        );
        let mut header = vec!["metric"];
        header.extend(robots.iter().map(|r| r["name"].as_str().unwrap_or("?")));
        let any_push = robots
            .iter()
            .any(|r| r.get("push_recovery").is_some_and(|p| !p.is_null()));
        let rows: Vec<Vec<String>> = METRIC_ROWS
            .iter()
            .filter(|(_, key, _)| *key != "push_recovery" || any_push)
            .map(|(label, key, f)| {
                let mut row = vec![label.to_string()];
                row.extend(robots.iter().map(|r| f(&r[*key])));
                row
            })
            .collect();
        table(&mut out, &header, &rows);
    }
    if herd {
        let _ = writeln!(
            out,
            "\nThe detail below (joint torques, sensing, plots, the studies) covers the {} worst robots; the other {} are in `summary.json`.",
            detail.len(),
            robots.len() - detail.len()
        );
    }
    for r in &detail {
        let joints = r["joints"].as_array().cloned().unwrap_or_default();
        if joints.is_empty() {
            continue;
        }
        let _ = writeln!(
            out,
            "\nJoint torques of `{}` (applied |τ|, N·m):\n",
            r["name"].as_str().unwrap_or("?")
        );
        let rows: Vec<Vec<String>> = joints
            .iter()
            .map(|j| {
                vec![
                    format!("`{}`", j["name"].as_str().unwrap_or("?")),
                    num(&j["peak_abs_torque_nm"], 2),
                    num(&j["mean_abs_torque_nm"], 2),
                ]
            })
            .collect();
        table(&mut out, &["joint", "peak", "time-mean"], &rows);
    }

    sensing(&mut out, &detail);

    let _ = writeln!(out, "\n## Plots\n");
    if !logged {
        let _ = writeln!(
            out,
            "None: the run wrote no log (`--no-log`), and the plots are drawn from the log.\n"
        );
    } else if figures.is_empty() {
        let _ = writeln!(out, "None: no robot has per-step channels in the log.\n");
    }
    for (robot, figs) in figures {
        let _ = writeln!(out, "### `{robot}`\n");
        for (caption, stem) in figs {
            let _ = writeln!(
                out,
                "**{caption}** ([SVG](plots/{stem}.svg), [PNG](plots/{stem}.png))\n\n![{caption}](plots/{stem}.svg)\n"
            );
        }
    }

    let _ = writeln!(
        out,
        "## Studies side by side\n\nThe studies' reported figures (as restated in the project's `shared/reference.md`) beside this run's. They are what the studies printed, not targets to force; where this run's conditions differ (speed command, terrain, controller), the numbers are not like for like.\n"
    );
    for (k, r) in detail.iter().enumerate() {
        let n = r["name"].as_str().unwrap_or("?");
        let info = robot_info(scenario_text, n);
        let _ = writeln!(out, "### `{n}` ({})\n", info.model);
        let mut notes = Notes::default();
        let mut body = String::new();
        match quadsim_engine::robots::source_study(&info.model) {
            Some(SourceStudy::A) => study_a(&mut body, r, &mut notes, &info.speed_command),
            Some(SourceStudy::B) => study_b(&mut body, r, &mut notes),
            None => {
                let _ = writeln!(
                    body,
                    "Neither study's robot (Study A is `quad16`, Study B `quad12`): no rows."
                );
            }
        }
        crate::report::actuators::actuator_capacity(&mut body, r);
        // footnote labels are made unique per robot: `[^k-n]`
        let prefix = format!("{}-", k + 1);
        out.push_str(&body.replace("[^", &format!("[^{prefix}")));
        notes.write(&mut out, &prefix);
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn summary(robot: Value) -> Value {
        json!({"scenario": "t", "seed": 1, "sim_time_s": 1.0, "steps": 2000, "dt_s": 0.0005,
               "integrator": "semi_implicit_euler", "controller_rate_hz": 500.0,
               "quadsim_version": "0", "git_commit": "x", "scenario_sha256": "ab",
               "robots": [robot]})
    }

    const SCN: &str = "format_version = 1\n[[robots]]\nname = \"rex\"\nmodel = \"quad16\"\n";

    /// The report of `summary` for [`SCN`], without a log or figures.
    fn md_of(summary: &Value) -> String {
        render(summary, SCN, false, &[])
    }

    #[test]
    fn push_recovery_is_a_row_when_present_and_absent_otherwise() {
        let with = summary(json!({"name": "rex", "energy_per_step_j": 12.0,
            "push_recovery": {"max_impulse_ns": 15.0, "force_n": 150.0, "duration_s": 0.1}}));
        let md = md_of(&with);
        assert!(
            md.contains("| largest push recovered from (N·s) | 15.00 (150.0 N for 0.100 s) |"),
            "{md}"
        );
        assert!(
            md.contains("| largest push impulse recovered from (N·s) | —[^1-"),
            "{md}"
        );
        assert!(md.contains("the study reports no push experiment"));
        let without = summary(json!({"name": "rex", "energy_per_step_j": 12.0}));
        assert!(!md_of(&without).contains("push"));
    }

    #[test]
    fn the_state_read_and_the_estimation_error_are_reported() {
        let err = |rms: f64, max: f64| json!({"rms": rms, "max": max});
        let s = json!({"scenario": "t", "robots": [
            {"name": "est", "sensing": {"state_source": "estimated", "estimation": {
                "updates": 10, "tilt_rad": err(0.0277, 0.0759),
                "orientation_rad": err(0.0278, 0.076), "velocity_mps": err(0.113, 0.572),
                "height_m": err(0.0057, 0.0221)}}},
            {"name": "gt", "sensing": {"state_source": "ground_truth", "estimation": null}},
        ]});
        let md = md_of(&s);
        assert!(
            md.contains(
                "| `est` | estimated | 0.0277 / 0.0759 | 0.0278 / 0.0760 | 0.113 / 0.572 | 0.0057 / 0.0221 |"
            ),
            "{md}"
        );
        assert!(
            md.contains("| `gt` | **ground truth** | – | – | – | – |"),
            "{md}"
        );
    }

    #[test]
    fn a_missing_value_is_a_dash_with_a_footnote_saying_why() {
        let s =
            summary(json!({"name": "rex", "joint_rms_error_rad": null, "energy_per_step_j": null}));
        let md = md_of(&s);
        assert!(
            md.contains("| joint tracking RMS (rad) | 0.05 | —[^1-1] |"),
            "{md}"
        );
        assert!(
            md.contains("| energy per step (J) | 50 | —[^1-2] |"),
            "{md}"
        );
        assert!(
            md.contains("[^1-1]: the controller set no joint targets"),
            "{md}"
        );
        assert!(md.contains("[^1-2]: no foot touched down"), "{md}");
    }
}
