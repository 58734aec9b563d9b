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
pub mod input;
pub mod markdown;
pub mod plots;
pub mod series;

use std::path::{Path, PathBuf};

pub use input::{ReportError, ReportInput, RobotInfo, needs_topic, robot_info};

/// File name of the report in a run's output directory.
pub const REPORT_FILE: &str = "report.md";
/// Directory of the plots beside it.
pub const PLOTS_DIR: &str = "plots";

/// What [`write_report`] wrote.
#[derive(Debug, Clone)]
pub struct ReportFiles {
    /// `report.md`.
    pub markdown: PathBuf,
    /// Every plot file (SVG and PNG).
    pub plots: Vec<PathBuf>,
}

/// Writes `out_dir/report.md` and `out_dir/plots/<robot>_<plot>.{svg,png}`.
pub fn write_report(input: &ReportInput<'_>, out_dir: &Path) -> Result<ReportFiles, ReportError> {
    let mut robots: Vec<String> = input
        .summary
        .robots
        .iter()
        .map(|r| r.name.clone())
        .collect();
    if input.summary.log_truncated
        && robots.is_empty()
        && let Some(log) = input.log
    {
        // a killed run's log has no metrics messages: its robots are those
        // with per-step channels (`/<robot>/com`), in order of appearance
        for m in &log.messages {
            if let Some(name) = m
                .topic
                .strip_prefix('/')
                .and_then(|t| t.strip_suffix("/com"))
                && !robots.iter().any(|r| r == name)
            {
                robots.push(name.to_string());
            }
        }
    }
    let end_s = input.summary.sim_time_s;
    let plots_dir = out_dir.join(PLOTS_DIR);
    let mut plot_files = Vec::new();
    let mut figures: Vec<(String, Vec<(String, String)>)> = Vec::new();
    let mut pictures = Vec::new();
    let mut filmstrips = 0;
    if let Some(log) = input.log {
        // a herd's plots: its worst robots that were logged, at most
        // `HERD_DETAIL_ROBOTS` of them
        let herd = robots.len() >= markdown::HERD_MIN_ROBOTS;
        let mut drawn = 0;
        let order = if herd {
            markdown::herd_detail_order(&input.summary.to_json())
        } else {
            robots.clone()
        };
        for name in &order {
            if herd && drawn == markdown::HERD_DETAIL_ROBOTS {
                break;
            }
            let s = series::RobotSeries::from_log(log, name).map_err(|m| ReportError {
                path: "log".into(),
                message: m,
            })?;
            if s.is_empty() {
                continue;
            }
            drawn += 1;
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
        let herd = robots.len() >= markdown::HERD_MIN_ROBOTS;
        let motion = filmstrip::markdown(&pictures, robots.len(), filmstrips, herd);
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
