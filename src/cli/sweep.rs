//! `quadsim sweep FILE` (run a study's variants in parallel, or one shard of
//! them) and `quadsim merge DIR…` (join shards).

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::Args;
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::error::{CliError, bad};
use crate::study::output::{ResultsHeader, row_json, write_results};
use crate::study::{Study, load_study, run_variant};

/// Arguments of `quadsim sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The study file (`kind = "sweep"`).
    pub study: PathBuf,
    /// Output directory (default `runs/<study name>/`, or `runs/<study name>/shard-I-of-N/`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Variants run at once, one thread each (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub jobs: usize,
    /// Run only slice I of N (0 ≤ I < N, contiguous slices), or `auto`: from
    /// Slurm's `SLURM_ARRAY_TASK_ID`/`_MIN`/`_COUNT`, or Kubernetes'
    /// `JOB_COMPLETION_INDEX` with `QUADSIM_SHARDS` (the job's completions).
    #[arg(long, value_name = "I/N|auto")]
    pub shard: Option<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `quadsim merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Shard output directories (each holding a `results.json`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Where to write the merged results.
    #[arg(long)]
    pub out: PathBuf,
}

/// Parses `I/N` or resolves `auto` from the environment.
pub fn parse_shard(
    s: &str,
    env: impl Fn(&str) -> Option<String>,
) -> Result<(usize, usize), CliError> {
    let num = |k: &str, v: &str| {
        v.trim()
            .parse::<i64>()
            .map_err(|_| bad(format!("--shard auto: {k}={v} is not an integer")))
    };
    let (i, n) = if s == "auto" {
        if let Some(id) = env("SLURM_ARRAY_TASK_ID") {
            let id = num("SLURM_ARRAY_TASK_ID", &id)?;
            let min = match env("SLURM_ARRAY_TASK_MIN") {
                Some(m) => num("SLURM_ARRAY_TASK_MIN", &m)?,
                None => 0,
            };
            let count = env("SLURM_ARRAY_TASK_COUNT").ok_or_else(|| {
                bad("--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")
            })?;
            (id - min, num("SLURM_ARRAY_TASK_COUNT", &count)?)
        } else if let Some(idx) = env("JOB_COMPLETION_INDEX") {
            let count = env("QUADSIM_SHARDS").ok_or_else(|| {
                bad("--shard auto: JOB_COMPLETION_INDEX is set; set QUADSIM_SHARDS to the job's completions")
            })?;
            (
                num("JOB_COMPLETION_INDEX", &idx)?,
                num("QUADSIM_SHARDS", &count)?,
            )
        } else {
            return Err(bad(
                "--shard auto: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set",
            ));
        }
    } else {
        let (a, b) = s
            .split_once('/')
            .ok_or_else(|| bad(format!("--shard {s}: expected I/N (e.g. 0/4) or auto")))?;
        let p = |x: &str| {
            x.trim()
                .parse::<i64>()
                .map_err(|_| bad(format!("--shard {s}: expected I/N with integers")))
        };
        (p(a)?, p(b)?)
    };
    if n < 1 || i < 0 || i >= n {
        return Err(bad(format!(
            "--shard {s}: shard {i} of {n} does not exist (0 ≤ I < N)"
        )));
    }
    Ok((i as usize, n as usize))
}

/// The variants of shard `i` of `n`: a contiguous slice.
pub fn shard_range(total: usize, i: usize, n: usize) -> std::ops::Range<usize> {
    (i * total / n)..((i + 1) * total / n)
}

fn header(study: &Study) -> ResultsHeader {
    let mut h = Sha256::new();
    h.update(study.source.as_bytes());
    h.update([0u8]);
    h.update(study.base_source.as_bytes());
    ResultsHeader {
        study: study.name.clone(),
        study_sha256: format!("{:x}", h.finalize()),
        variants_total: study.variants.len(),
        paths: study.file.vary.keys().cloned().collect(),
        analyses: study.file.report.clone(),
    }
}

/// Runs `quadsim sweep`.
pub fn sweep(a: SweepArgs) -> Result<(), CliError> {
    let study = load_study(&a.study).map_err(|e| bad(e.to_string()))?;
    let shard = match &a.shard {
        Some(s) => Some(parse_shard(s, |k| std::env::var(k).ok())?),
        None => None,
    };
    let range = shard.map_or(0..study.variants.len(), |(i, n)| {
        shard_range(study.variants.len(), i, n)
    });
    let out = a.out.clone().unwrap_or_else(|| {
        let d = Path::new("runs").join(&study.name);
        match shard {
            Some((i, n)) => d.join(format!("shard-{i}-of-{n}")),
            None => d,
        }
    });
    crate::study::output::prepare_out_dir(&out)?;
    let jobs = if a.jobs == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        a.jobs
    };
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(range.len() as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} variants, eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(study.name.clone());
    let next = AtomicUsize::new(range.start);
    let results = Mutex::new(Vec::with_capacity(range.len()));
    std::thread::scope(|s| {
        for _ in 0..jobs.min(range.len()).max(1) {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= range.end {
                        break;
                    }
                    let r = run_variant(&study, k);
                    bar.inc(1);
                    results.lock().expect("no panics hold the lock").push(r);
                }
            });
        }
    });
    bar.finish_and_clear();
    let mut results = results.into_inner().expect("no panics hold the lock");
    results.sort_by_key(|r| r.index);
    let rows: Vec<Value> = results.iter().map(row_json).collect();
    let failed = results.iter().filter(|r| r.outcome.is_err()).count();
    write_results(&out, &header(&study), shard, &rows)?;
    for r in results.iter().filter(|r| r.outcome.is_err()) {
        eprintln!(
            "variant {} failed: {}",
            r.index,
            r.outcome
                .as_ref()
                .err()
                .map_or(String::new(), |e| e.to_string())
        );
    }
    println!(
        "{}: {} variants{}, {} ok, {failed} failed; wrote {}/results.csv, results.json, report.md",
        study.name,
        rows.len(),
        shard.map_or(String::new(), |(i, n)| format!(
            " (shard {i}/{n} of {})",
            study.variants.len()
        )),
        rows.len() - failed,
        out.display()
    );
    Ok(())
}

/// Runs `quadsim merge`: the shards' rows, checked to come from one study
/// without overlap, in variant order.
pub fn merge(a: MergeArgs) -> Result<(), CliError> {
    let mut head: Option<(ResultsHeader, PathBuf)> = None;
    let mut rows: Vec<Value> = Vec::new();
    let mut seen: std::collections::BTreeMap<u64, PathBuf> = Default::default();
    for d in &a.dirs {
        let p = d.join("results.json");
        let text = std::fs::read_to_string(&p).map_err(|e| CliError::Io {
            path: p.display().to_string(),
            source: e,
        })?;
        let v: Value = serde_json::from_str(&text)
            .map_err(|e| bad(format!("{}: not a results file: {e}", p.display())))?;
        let h = ResultsHeader {
            study: v["study"].as_str().unwrap_or_default().to_string(),
            study_sha256: v["study_sha256"].as_str().unwrap_or_default().to_string(),
            variants_total: v["variants_total"].as_u64().unwrap_or(0) as usize,
            paths: v["paths"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|x| x.as_str().map(String::from))
                        .collect()
                })
                .unwrap_or_default(),
            analyses: serde_json::from_value(v["report"].clone()).unwrap_or_default(),
        };
        match &head {
            None => head = Some((h, p.clone())),
            Some((h0, p0)) if *h0 != h => {
                return Err(bad(format!(
                    "{} and {} come from different studies (or different versions of one): \
                     study_sha256 {} vs {}",
                    p0.display(),
                    p.display(),
                    h0.study_sha256,
                    h.study_sha256
                )));
            }
            Some(_) => {}
        }
        for r in v["rows"].as_array().cloned().unwrap_or_default() {
            let k = r["variant"]
                .as_u64()
                .ok_or_else(|| bad(format!("{}: a row without a variant number", p.display())))?;
            if let Some(prev) = seen.insert(k, p.clone()) {
                return Err(bad(format!(
                    "variant {k} is in both {} and {}: shards overlap",
                    prev.display(),
                    p.display()
                )));
            }
            rows.push(r);
        }
    }
    let (h, _) = head.expect("at least one dir (clap)");
    rows.sort_by_key(|r| r["variant"].as_u64());
    let missing: Vec<usize> = (0..h.variants_total)
        .filter(|k| !seen.contains_key(&(*k as u64)))
        .collect();
    write_results(&a.out, &h, None, &rows)?;
    if !missing.is_empty() {
        eprintln!(
            "warning: {} of {} variants missing (first: {:?}); a shard has not run or not been merged",
            missing.len(),
            h.variants_total,
            &missing[..missing.len().min(10)]
        );
    }
    println!(
        "merged {} shards: {} of {} variants; wrote {}/results.csv, results.json, report.md",
        a.dirs.len(),
        rows.len(),
        h.variants_total,
        a.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_variants() {
        for total in [0, 1, 7, 10, 101] {
            for n in 1..=8 {
                let mut all: Vec<usize> = (0..n).flat_map(|i| shard_range(total, i, n)).collect();
                all.sort();
                assert_eq!(all, (0..total).collect::<Vec<_>>(), "{total} in {n}");
            }
        }
    }

    #[test]
    fn shard_specs_parse_from_flags_and_schedulers() {
        let none = |_: &str| None;
        assert_eq!(parse_shard("2/5", none).unwrap(), (2, 5));
        assert!(parse_shard("5/5", none).is_err());
        assert!(parse_shard("x", none).is_err());
        assert!(parse_shard("auto", none).is_err());
        let slurm = |k: &str| match k {
            "SLURM_ARRAY_TASK_ID" => Some("4".to_string()),
            "SLURM_ARRAY_TASK_MIN" => Some("1".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("8".to_string()),
            _ => None,
        };
        assert_eq!(parse_shard("auto", slurm).unwrap(), (3, 8));
        let k8s = |k: &str| match k {
            "JOB_COMPLETION_INDEX" => Some("0".to_string()),
            "QUADSIM_SHARDS" => Some("3".to_string()),
            _ => None,
        };
        assert_eq!(parse_shard("auto", k8s).unwrap(), (0, 3));
        let k8s_no_count = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        let e = parse_shard("auto", k8s_no_count).unwrap_err().to_string();
        assert!(e.contains("QUADSIM_SHARDS"), "{e}");
    }
}
