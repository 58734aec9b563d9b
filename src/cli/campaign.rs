//! `quadsim campaign SCENARIO`: N perturbed copies of a scenario, run in
//! parallel; fall rate and speed tracking in `campaign.json`, `.csv`, `.md`
//! and a plot (`docs/campaign.md`).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::Args;

use crate::error::{CliError, bad};
use crate::study::campaign::{
    CampaignSpec, Perturbations, Prepared, Timing, load_campaign_file, run_copies,
};
use crate::study::campaign_output::{TABLE_HEADER, table_row, write_all};

/// Arguments of `quadsim campaign`.
#[derive(Debug, Args)]
pub struct CampaignArgs {
    /// The scenario file, or a campaign file (`kind = "campaign"`: a base
    /// scenario and these settings; the flags override it).
    pub scenario: PathBuf,
    /// Number of perturbed copies (default 20).
    #[arg(short = 'n', long = "copies", value_name = "N")]
    pub copies: Option<usize>,
    /// Output directory (default `runs/<scenario name>-campaign/`); created
    /// if needed; an existing file is refused.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Campaign seed: every copy's draws derive from it and the copy number (default 0).
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Copies run at once, one thread each (0: one per core). Results do not depend on it.
    #[arg(long, default_value_t = 0, value_name = "T")]
    pub threads: usize,
    /// The robot to perturb and measure (default: the scenario's only `[[robots]]` entry).
    #[arg(long, value_name = "NAME")]
    pub robot: Option<String>,
    /// Simulated duration of each copy (s; default the scenario's `world.duration_s`).
    #[arg(long, value_name = "S")]
    pub duration: Option<f64>,
    /// Start of the steady-state speed window (s, default 2); it ends with the run.
    #[arg(long, value_name = "S")]
    pub steady_from: Option<f64>,
    /// Start of the torso height peak-to-peak window (s, default 1).
    #[arg(long, value_name = "S")]
    pub height_from: Option<f64>,
    /// Exit with code 3 when more than K copies fell or failed (for CI).
    #[arg(long, value_name = "K")]
    pub max_falls: Option<usize>,
    /// The case's label in the table (default: the scenario's name).
    #[arg(long, value_name = "TEXT")]
    pub case: Option<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Turn every perturbation off (the flags below turn single ones back on).
    #[arg(long)]
    pub no_perturb: bool,
    /// Start offset: x and y each uniform in ±M metres (default 0.02; 0 or `off`: none).
    #[arg(long, value_name = "M|off")]
    pub start_xy_m: Option<String>,
    /// Start yaw offset: uniform in ±DEG degrees (default 3; 0 or `off`: none).
    #[arg(long, value_name = "DEG|off")]
    pub start_yaw_deg: Option<String>,
    /// Link masses: each link's mass (and inertia) × uniform [1 − F, 1 + F] (default 0.1; 0 or `off`: none).
    #[arg(long, value_name = "F|off")]
    pub mass_frac: Option<String>,
    /// Ground friction: μ uniform in [LO, HI] for every ground, or one MU (default 0.6,1.0; `off`: the scenario's).
    #[arg(long, value_name = "LO,HI|MU|off")]
    pub friction: Option<String>,
    /// World seed: a draw per copy (`on`, default) or the scenario's (`off`).
    #[arg(long, value_name = "on|off")]
    pub world_seed: Option<String>,
    /// Sensor noise: every noise figure × X, or × uniform [LO, HI] (default 1: as the scenario sets them; `off`: 0).
    #[arg(long, value_name = "X|LO,HI|off")]
    pub noise_scale: Option<String>,
}

fn number(flag: &str, s: &str) -> Result<f64, CliError> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| bad(format!("--{flag} {s}: expected a number or `off`")))
}

/// `X`, `off` (→ `off_value`) as a number.
fn half_width(flag: &str, s: &str) -> Result<f64, CliError> {
    if s.trim() == "off" {
        Ok(0.0)
    } else {
        number(flag, s)
    }
}

/// `LO,HI` or `X` (→ `[X, X]`).
fn range(flag: &str, s: &str) -> Result<[f64; 2], CliError> {
    match s.split_once(',') {
        Some((a, b)) => Ok([number(flag, a)?, number(flag, b)?]),
        None => {
            let x = number(flag, s)?;
            Ok([x, x])
        }
    }
}

/// The perturbations: `base` (a campaign file's, or the defaults), or none
/// with `--no-perturb`, then the flags.
pub fn perturbations(a: &CampaignArgs, base: Perturbations) -> Result<Perturbations, CliError> {
    let mut p = if a.no_perturb {
        Perturbations::NONE
    } else {
        base
    };
    if let Some(s) = &a.start_xy_m {
        p.start_xy_m = half_width("start-xy-m", s)?;
    }
    if let Some(s) = &a.start_yaw_deg {
        p.start_yaw_deg = half_width("start-yaw-deg", s)?;
    }
    if let Some(s) = &a.mass_frac {
        p.link_mass_frac = half_width("mass-frac", s)?;
    }
    if let Some(s) = &a.friction {
        p.friction = if s.trim() == "off" {
            None
        } else {
            Some(range("friction", s)?)
        };
    }
    if let Some(s) = &a.world_seed {
        p.world_seed = match s.trim() {
            "on" => true,
            "off" => false,
            other => return Err(bad(format!("--world-seed {other}: expected on or off"))),
        };
    }
    if let Some(s) = &a.noise_scale {
        p.noise_scale = if s.trim() == "off" {
            [0.0, 0.0]
        } else {
            range("noise-scale", s)?
        };
    }
    p.validate().map_err(|e| bad(format!("perturbation {e}")))?;
    Ok(p)
}

/// Refuses an output path that is an existing file, then creates the directory.
pub fn prepare_out(out: &Path) -> Result<(), CliError> {
    if out.exists() && !out.is_dir() {
        return Err(bad(format!(
            "--out {}: is an existing file, not a directory; nothing was run",
            out.display()
        )));
    }
    std::fs::create_dir_all(out).map_err(|e| CliError::Io {
        path: out.display().to_string(),
        source: e,
    })
}

/// The campaign of the arguments: a campaign file's settings (when the
/// file is one) overridden by the flags; and the most falls allowed.
pub fn spec(a: &CampaignArgs) -> Result<(CampaignSpec, Option<usize>), CliError> {
    let is_file = std::fs::read_to_string(&a.scenario)
        .ok()
        .and_then(|s| crate::study::file_kind(&s))
        .is_some_and(|k| k == "campaign");
    let (mut spec, max_falls) = if is_file {
        let f = load_campaign_file(&a.scenario).map_err(|e| bad(e.to_string()))?;
        (f.spec, f.max_falls)
    } else {
        (CampaignSpec::new(&a.scenario, 20), None)
    };
    spec.perturb = perturbations(a, spec.perturb)?;
    spec.copies = a.copies.unwrap_or(spec.copies);
    spec.seed = a.seed.unwrap_or(spec.seed);
    if a.robot.is_some() {
        spec.robot = a.robot.clone();
    }
    if a.duration.is_some() {
        spec.duration_s = a.duration;
    }
    spec.steady_from_s = a.steady_from.unwrap_or(spec.steady_from_s);
    spec.height_from_s = a.height_from.unwrap_or(spec.height_from_s);
    if a.case.is_some() {
        spec.case = a.case.clone();
    }
    Ok((spec, a.max_falls.or(max_falls)))
}

/// Runs `quadsim campaign`.
pub fn run(a: CampaignArgs) -> Result<(), CliError> {
    let (spec, max_falls) = spec(&a)?;
    if let Some(out) = &a.out {
        prepare_out(out)?;
    }
    let copies = spec.copies;
    let prep = Prepared::new(spec).map_err(|e| bad(e.to_string()))?;
    let out = match &a.out {
        Some(o) => o.clone(),
        None => {
            let o = Path::new("runs").join(format!("{}-campaign", prep.scenario.name));
            prepare_out(&o)?;
            o
        }
    };
    let threads = if a.threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        a.threads
    };
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(copies as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {pos}/{len} copies, {elapsed} elapsed, eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let case = prep.case();
    bar.set_message(format!("{case}: 0 fell"));
    let falls = AtomicUsize::new(0);
    let t0 = std::time::Instant::now();
    let results = run_copies(&prep, threads, &|r| {
        if r.metrics.as_ref().is_some_and(|m| m.fell) {
            let f = falls.fetch_add(1, Ordering::Relaxed) + 1;
            bar.set_message(format!("{case}: {f} fell"));
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    let wall_s = t0.elapsed().as_secs_f64();
    let simulated: f64 = results
        .iter()
        .filter_map(|r| r.metrics.as_ref().map(|m| m.simulated_s))
        .sum();
    let report = prep.report(
        results,
        Timing {
            wall_s,
            threads,
            sim_s_per_wall_s: if wall_s > 0.0 {
                simulated / wall_s
            } else {
                0.0
            },
            argv: std::env::args().collect(),
        },
    );
    let files = write_all(&out, &report).map_err(bad)?;
    for r in report.runs.iter().filter(|r| r.error.is_some()) {
        eprintln!(
            "copy {} failed: {}",
            r.copy,
            r.error.as_deref().unwrap_or_default()
        );
    }
    let ag = &report.aggregates;
    println!("{TABLE_HEADER}\n{}", table_row(&report));
    println!(
        "{}: {} copies, {} fell ({:.1} %), {} failed; {:.1} s wall clock on {threads} threads; wrote {}",
        case,
        ag.copies,
        ag.falls,
        100.0 * ag.fall_rate,
        ag.failed,
        wall_s,
        files
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(k) = max_falls
        && ag.falls + ag.failed > k
    {
        return Err(CliError::Threshold(format!(
            "{} of {} copies fell{} (--max-falls {k})",
            ag.falls,
            ag.copies,
            if ag.failed > 0 {
                format!(" and {} failed", ag.failed)
            } else {
                String::new()
            }
        )));
    }
    Ok(())
}
