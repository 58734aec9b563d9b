//! `quadsim report LOG.mcap [--out DIR]`: rebuilds a run's `summary.json`
//! from its log alone: the metrics come from each robot's final `metrics`
//! message (accumulated at full rate in the simulation, which a decimated log
//! could not recompute), the rest from the log's metadata records
//! (`scenario`, `quadsim`, `run`). Everything but `timing` (wall-clock, never
//! logged) equals the original. Then `report.md` and the plots, from the
//! same summary and the log's per-step channels, exactly as `quadsim run`
//! writes them.

use std::path::PathBuf;

use clap::Args;
use serde_json::{Map, Value, json};
use sha2::{Digest, Sha256};

use crate::error::{CliError, bad};
use crate::log::METRICS_SUFFIX;
use crate::log::read::{LogContents, read_log_messages};

/// Arguments of `quadsim report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// The log (`log.mcap` of a run).
    pub log: PathBuf,
    /// Output directory for `summary.json`, `report.md` and `plots/` (default: `report/` beside the log).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `quadsim report`.
pub fn run(a: ReportArgs) -> Result<(), CliError> {
    let contents = read_log_messages(&a.log, &crate::report::filmstrip::report_filter())
        .map_err(|e| bad(e.to_string()))?;
    let summary =
        summary_from_log(&contents).map_err(|e| bad(format!("{}: {e}", a.log.display())))?;
    let out = a.out.clone().unwrap_or_else(|| {
        a.log
            .parent()
            .unwrap_or(std::path::Path::new("."))
            .join("report")
    });
    std::fs::create_dir_all(&out).map_err(|e| CliError::Io {
        path: out.display().to_string(),
        source: e,
    })?;
    let path = out.join("summary.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&summary).expect("json") + "\n",
    )
    .map_err(|e| CliError::Io {
        path: path.display().to_string(),
        source: e,
    })?;
    println!("wrote {}", path.display());
    let text = contents.meta("scenario", "text").ok_or_else(|| {
        bad(format!(
            "{}: the log has no metadata 'scenario.text'",
            a.log.display()
        ))
    })?;
    let files = crate::report::write_report(
        &crate::report::ReportInput {
            summary: &summary,
            scenario_text: text,
            log: Some(&contents),
        },
        &out,
    )
    .map_err(crate::cli::run::report_error)?;
    println!(
        "wrote {} ({} plot files in {})",
        files.markdown.display(),
        files.plots.len(),
        out.join(crate::report::PLOTS_DIR).display()
    );
    Ok(())
}

/// `summary.json` without `timing`, from a log. Errors name the missing record or key.
pub fn summary_from_log(c: &LogContents) -> Result<Value, String> {
    let meta = |record: &str, key: &str| {
        c.meta(record, key).ok_or_else(|| {
            let why = if record == "run" && !c.metadata.contains_key("run") {
                " (the run did not finish: the process was killed before closing the log)"
            } else {
                ""
            };
            format!("the log has no metadata '{record}.{key}'{why}")
        })
    };
    let number = |record: &str, key: &str| -> Result<Value, String> {
        let text = meta(record, key)?;
        serde_json::from_str(text).map_err(|e| format!("metadata '{record}.{key}' = {text:?}: {e}"))
    };
    let text = meta("scenario", "text")?;
    let sha = Sha256::digest(text.as_bytes());
    let mut robots = Vec::new();
    for m in &c.messages {
        let is_metrics = m
            .topic
            .rsplit_once('/')
            .is_some_and(|(_, last)| last == METRICS_SUFFIX);
        if is_metrics {
            robots.push(
                m.json()
                    .map_err(|e| format!("{}: not JSON: {e}", m.topic))?,
            );
        }
    }
    let mut s = Map::new();
    s.insert(
        "format_version".into(),
        number("quadsim", "summary_format_version")?,
    );
    s.insert("scenario".into(), json!(meta("scenario", "name")?));
    s.insert("sim_time_s".into(), number("run", "sim_time_s")?);
    s.insert("steps".into(), number("run", "steps")?);
    s.insert("dt_s".into(), number("quadsim", "dt_s")?);
    s.insert("seed".into(), number("quadsim", "seed")?);
    s.insert("quadsim_version".into(), json!(meta("quadsim", "version")?));
    s.insert("git_commit".into(), json!(meta("quadsim", "git_commit")?));
    s.insert("scenario_sha256".into(), json!(format!("{sha:x}")));
    s.insert("integrator".into(), json!(meta("quadsim", "integrator")?));
    s.insert(
        "controller_rate_hz".into(),
        number("quadsim", "controller_rate_hz")?,
    );
    s.insert("robots".into(), Value::Array(robots));
    if number("run", "interrupted")? == json!(true) {
        s.insert("interrupted".into(), json!(true));
    }
    Ok(Value::Object(s))
}
