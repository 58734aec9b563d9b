//! `quadsim report LOG.mcap [--out DIR]`: rebuilds a run's `summary.json`
//! from its log alone: the metrics come from each robot's final `metrics`
//! message (accumulated at full rate in the simulation, which a decimated log
//! could not recompute), the rest from the log's metadata records
//! (`scenario`, `quadsim`, `run`). Everything but `timing` (wall-clock, never
//! logged) equals the original. Then `report.md` and the plots, from the
//! same summary and the log's per-step channels, exactly as `quadsim run`
//! writes them.

use std::path::PathBuf;

use crate::error::{CliError, bad};
use crate::log::read::read_log_messages;
use crate::summary::Summary;
use clap::Args;

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
        Summary::from_log(&contents).map_err(|e| bad(format!("{}: {e}", a.log.display())))?;
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
    std::fs::write(&path, summary.to_text()).map_err(|e| CliError::Io {
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
