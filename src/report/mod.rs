//! A run's `report.md` and `plots/`, built from what the log holds (the
//! per-step channels for the plots, the `metrics` messages through
//! `summary.json` for the numbers), so that `quadsim run` and
//! `quadsim report LOG` write the same files.
//!
//! - [`series`]: a robot's time series decoded from its log channels;
//! - [`plots`]: the figures (SVG and PNG, plotters with a bundled font);
//! - [`markdown`]: the text: run header, metrics, plots, the studies side by side.

pub mod actuators;
pub mod filmstrip;
pub mod markdown;
pub mod plots;
pub mod series;

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::log::read::LogContents;

/// File name of the report in a run's output directory.
pub const REPORT_FILE: &str = "report.md";
/// Directory of the plots beside it.
pub const PLOTS_DIR: &str = "plots";

/// A report could not be written.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ReportError {
    /// The file.
    pub path: String,
    /// What failed.
    pub message: String,
}

/// What a report is made of.
#[derive(Debug, Clone, Copy)]
pub struct ReportInput<'a> {
    /// `summary.json` (its `timing` block, if any, is not used).
    pub summary: &'a Value,
    /// The scenario file's text (robot models, speed commands).
    pub scenario_text: &'a str,
    /// The log, for the plots; `None` for a run without a log (no plots).
    pub log: Option<&'a LogContents>,
}

/// What [`write_report`] wrote.
#[derive(Debug, Clone)]
pub struct ReportFiles {
    /// `report.md`.
    pub markdown: PathBuf,
    /// Every plot file (SVG and PNG).
    pub plots: Vec<PathBuf>,
}

/// A robot as the scenario declares it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RobotInfo {
    /// `model` (`quad16`, `quad12` or a URDF path).
    pub model: String,
    /// Controller kind.
    pub controller: String,
    /// Commanded forward speed over time for a `vmc` robot: `(t_s, v_x_mps)`
    /// from the controller's `v_x_mps` (default 0) and later `command` events.
    pub speed_command: Vec<(f64, f64)>,
}

/// The robot `name` in the scenario text (defaults when not found).
pub fn robot_info(scenario_text: &str, name: &str) -> RobotInfo {
    let table: toml::Table = scenario_text.parse().unwrap_or_default();
    let num = |v: Option<&toml::Value>| {
        v.and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let robot = table
        .get("robots")
        .and_then(|r| r.as_array())
        .and_then(|a| {
            a.iter()
                .find(|r| r.get("name").and_then(|n| n.as_str()) == Some(name))
        });
    // a herd's robot is not in `robots`: take it from the expanded herds
    let herd_robot;
    let robot = match robot {
        Some(r) => r,
        None => match herd_robot_table(scenario_text, name) {
            Some(t) => {
                herd_robot = toml::Value::Table(t);
                &herd_robot
            }
            None => return RobotInfo::default(),
        },
    };
    let ctrl = robot.get("controller");
    let kind = ctrl
        .and_then(|c| c.get("kind"))
        .and_then(|k| k.as_str())
        .unwrap_or("none")
        .to_string();
    let mut speed = Vec::new();
    if kind == "vmc" {
        speed.push((0.0, num(ctrl.and_then(|c| c.get("v_x_mps"))).unwrap_or(0.0)));
        let mut events: Vec<(f64, f64)> = table
            .get("events")
            .and_then(|e| e.as_array())
            .into_iter()
            .flatten()
            .filter(|e| {
                e.get("robot").and_then(|r| r.as_str()) == Some(name)
                    && e.get("kind").and_then(|k| k.as_str()) == Some("command")
            })
            .filter_map(|e| Some((num(e.get("t_s"))?, num(e.get("v_x_mps"))?)))
            .collect();
        events.sort_by(|a, b| a.0.total_cmp(&b.0));
        speed.extend(events);
    }
    RobotInfo {
        model: robot
            .get("model")
            .and_then(|m| m.as_str())
            .unwrap_or("?")
            .to_string(),
        controller: kind,
        speed_command: speed,
    }
}

/// The model and controller of a herd's robot, from the scenario's herds
/// expanded once per scenario text (a report asks for every robot of a
/// herd of thousands).
fn herd_robot_table(scenario_text: &str, name: &str) -> Option<toml::Table> {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex};
    type Expanded = Arc<HashMap<String, toml::Table>>;
    static CACHE: Mutex<Option<(String, Expanded)>> = Mutex::new(None);
    let expanded = {
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        match cache.as_ref() {
            Some((text, e)) if text == scenario_text => e.clone(),
            _ => {
                let mut map = HashMap::new();
                let mut file: crate::scenario::ScenarioFile = toml::from_str(scenario_text).ok()?;
                let path = std::path::Path::new("scenario.toml");
                let loc = crate::scenario::Locator {
                    path,
                    src: scenario_text,
                };
                crate::scenario::herd::expand(&loc, &mut file).ok()?;
                for r in file.robots {
                    let mut t = toml::Table::new();
                    t.insert("model".into(), toml::Value::String(r.model));
                    let mut c: toml::Table = r.controller.params.into_iter().collect();
                    if let Some(k) = r.controller.kind {
                        c.insert("kind".into(), toml::Value::String(k));
                    }
                    t.insert("controller".into(), toml::Value::Table(c));
                    map.insert(r.name, t);
                }
                let e = Arc::new(map);
                *cache = Some((scenario_text.to_string(), e.clone()));
                e
            }
        }
    };
    expanded.get(name).cloned()
}

/// Whether the report needs a topic's messages (not the 3D scene and
/// transforms, the largest part of a log): the filter for
/// [`read_log_topics`](crate::log::read::read_log_topics).
pub fn needs_topic(topic: &str) -> bool {
    !matches!(topic, "/tf" | "/scene")
}

/// Writes `out_dir/report.md` and `out_dir/plots/<robot>_<plot>.{svg,png}`.
pub fn write_report(input: &ReportInput<'_>, out_dir: &Path) -> Result<ReportFiles, ReportError> {
    let robots: Vec<String> = input.summary["robots"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|r| r["name"].as_str().map(str::to_string))
        .collect();
    let end_s = input.summary["sim_time_s"].as_f64().unwrap_or(0.0);
    let plots_dir = out_dir.join(PLOTS_DIR);
    let mut plot_files = Vec::new();
    let mut figures: Vec<(String, Vec<(String, String)>)> = Vec::new();
    let mut pictures = Vec::new();
    let mut filmstrips = 0;
    if let Some(log) = input.log {
        for name in &robots {
            let s = series::RobotSeries::from_log(log, name).map_err(|m| ReportError {
                path: "log".into(),
                message: m,
            })?;
            if s.is_empty() {
                continue;
            }
            std::fs::create_dir_all(&plots_dir).map_err(|e| ReportError {
                path: plots_dir.display().to_string(),
                message: e.to_string(),
            })?;
            let ctx = plots::PlotContext {
                speed_target: robot_info(input.scenario_text, name).speed_command,
                end_s,
            };
            let figs = plots::robot_figures(&s, &ctx);
            // figures are independent files: draw them on a few threads
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
            let per = figs.len().div_ceil(threads).max(1);
            let written: Vec<Result<[PathBuf; 2], ReportError>> = std::thread::scope(|sc| {
                let handles: Vec<_> = figs
                    .chunks(per)
                    .map(|chunk| {
                        let dir = &plots_dir;
                        sc.spawn(move || {
                            chunk
                                .iter()
                                .map(|(_, f)| plots::write_figure(f, dir))
                                .collect::<Vec<_>>()
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .flat_map(|h| h.join().expect("plot thread"))
                    .collect()
            });
            for w in written {
                plot_files.extend(w?);
            }
            let links = figs
                .iter()
                .map(|(caption, f)| (caption.clone(), crate::names::safe_file_stem(&f.stem)))
                .collect();
            figures.push((name.clone(), links));
            if filmstrips < filmstrip::MAX_ROBOTS
                && let Some((picture, file)) = filmstrip::robot_filmstrip(log, &s, &plots_dir)?
            {
                pictures.push(picture);
                plot_files.push(file);
                filmstrips += 1;
            }
        }
        if robots.len() > 1
            && std::fs::create_dir_all(&plots_dir).is_ok()
            && let Some((picture, file)) = filmstrip::world_snapshot(log, &robots, &plots_dir)?
        {
            pictures.push(picture);
            plot_files.push(file);
        }
    }
    let mut text = markdown::report_markdown(input, &figures);
    if input.log.is_some() {
        // the pictures before the plots
        let motion = filmstrip::markdown(&pictures, robots.len(), filmstrips);
        match text.find("\n## Plots\n") {
            Some(at) => text.insert_str(at, &motion),
            None => text.push_str(&motion),
        }
    }
    let path = out_dir.join(REPORT_FILE);
    std::fs::write(&path, text).map_err(|e| ReportError {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    Ok(ReportFiles {
        markdown: path,
        plots: plot_files,
    })
}
