//! A sweep's results: `results.json` (everything, the input of `quadsim
//! merge`), `results.csv` (one row per run: the varied values, then every
//! summary metric) and `report.md`.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{Map, Value, json};

use super::analysis::metric_number;
use super::variant::VariantResult;
use crate::error::CliError;

/// Version of `results.json`'s layout.
pub const RESULTS_FORMAT_VERSION: u32 = 1;

/// The header of a results file: which study, which slice.
#[derive(Debug, Clone, PartialEq)]
pub struct ResultsHeader {
    /// Study name.
    pub study: String,
    /// SHA-256 of the study file and the base scenario's text.
    pub study_sha256: String,
    /// Variants the whole study has.
    pub variants_total: usize,
    /// Varied paths, in column order.
    pub paths: Vec<String>,
    /// The study's `[report]` analyses (kept in results.json for `merge`).
    pub analyses: super::analysis::StudyReportSpec,
}

/// One row of `results.json`.
pub fn row_json(r: &VariantResult) -> Value {
    let params: Map<String, Value> = r
        .params
        .iter()
        .map(|(k, v)| (k.clone(), toml_to_json(v)))
        .collect();
    match &r.outcome {
        Ok(s) => {
            json!({"variant": r.index, "params": params, "status": "ok", "error": null, "summary": s.to_json()})
        }
        Err(e) => {
            json!({"variant": r.index, "params": params, "status": "failed", "error": e.to_string(), "summary": null})
        }
    }
}

fn toml_to_json(v: &toml::Value) -> Value {
    match v {
        toml::Value::String(s) => json!(s),
        toml::Value::Integer(i) => json!(i),
        toml::Value::Float(f) => json!(f),
        toml::Value::Boolean(b) => json!(b),
        other => json!(other.to_string()),
    }
}

/// Scalar metrics of a summary, flattened: `metric` for a one-robot run,
/// `robot/metric` otherwise; `[min, max]` ranges become `_min`/`_max`,
/// `[x, y, z]` vectors `_x`/`_y`/`_z`, and an object's scalars `object.key`.
pub fn flat_metrics(summary: &Value) -> Vec<(String, Value)> {
    let robots = summary["robots"].as_array().cloned().unwrap_or_default();
    let single = robots.len() == 1;
    let mut out = Vec::new();
    for r in &robots {
        let name = r["name"].as_str().unwrap_or("?");
        let Some(obj) = r.as_object() else { continue };
        for (k, v) in obj {
            if k == "name" {
                continue;
            }
            let col = if single {
                k.clone()
            } else {
                format!("{name}/{k}")
            };
            match v {
                Value::Array(a) if a.len() == 2 && a.iter().all(Value::is_number) => {
                    out.push((format!("{col}_min"), a[0].clone()));
                    out.push((format!("{col}_max"), a[1].clone()));
                }
                Value::Array(a) if a.len() == 3 && a.iter().all(Value::is_number) => {
                    for (axis, x) in ["x", "y", "z"].iter().zip(a) {
                        out.push((format!("{col}_{axis}"), x.clone()));
                    }
                }
                Value::Number(_) | Value::Bool(_) | Value::Null => out.push((col, v.clone())),
                // one level of objects (`load`, `actuators`, `push_recovery`): their scalars
                Value::Object(o) => {
                    for (k2, v2) in o {
                        if matches!(
                            v2,
                            Value::Number(_) | Value::Bool(_) | Value::Null | Value::String(_)
                        ) {
                            out.push((format!("{col}.{k2}"), v2.clone()));
                        }
                    }
                }
                _ => {}
            }
        }
    }
    out
}

fn cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Writes `results.json`, `results.csv` and `report.md` into `dir`.
pub fn write_results(
    dir: &Path,
    header: &ResultsHeader,
    shard: Option<(usize, usize)>,
    rows: &[Value],
) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let results = json!({
        "format_version": RESULTS_FORMAT_VERSION,
        "study": header.study,
        "study_sha256": header.study_sha256,
        "variants_total": header.variants_total,
        "paths": header.paths,
        "report": serde_json::to_value(&header.analyses).expect("serialisable"),
        "shard": shard.map(|(i, n)| json!({"index": i, "count": n})),
        "rows": rows,
    });
    let p = dir.join("results.json");
    std::fs::write(
        &p,
        serde_json::to_string_pretty(&results).expect("json") + "\n",
    )
    .map_err(|e| io(&p, e))?;

    // CSV: metric columns in first-appearance order over the rows.
    let mut metric_cols: Vec<String> = Vec::new();
    let mut flats: Vec<BTreeMap<String, Value>> = Vec::new();
    for r in rows {
        let f = flat_metrics(&r["summary"]);
        for (k, _) in &f {
            if !metric_cols.contains(k) {
                metric_cols.push(k.clone());
            }
        }
        flats.push(f.into_iter().collect());
    }
    let p = dir.join("results.csv");
    let mut w = csv::Writer::from_path(&p).map_err(|e| io(&p, std::io::Error::other(e)))?;
    let mut head = vec!["variant".to_string(), "status".into(), "error".into()];
    head.extend(header.paths.iter().cloned());
    head.extend(metric_cols.iter().cloned());
    w.write_record(&head)
        .map_err(|e| io(&p, std::io::Error::other(e)))?;
    for (r, f) in rows.iter().zip(&flats) {
        let mut rec = vec![cell(&r["variant"]), cell(&r["status"]), cell(&r["error"])];
        rec.extend(header.paths.iter().map(|k| cell(&r["params"][k])));
        rec.extend(
            metric_cols
                .iter()
                .map(|k| f.get(k).map(cell).unwrap_or_default()),
        );
        w.write_record(&rec)
            .map_err(|e| io(&p, std::io::Error::other(e)))?;
    }
    w.flush().map_err(|e| io(&p, e))?;

    let plots = write_plots(dir, header, rows, &flats)?;
    let p = dir.join("report.md");
    let mut md = report_md(header, shard, rows, &flats);
    if !plots.is_empty() {
        md += "\n## Plots\n\nThe main metrics against each varied value, one dot per run \
               (every metric is in `results.csv`):\n\n";
        for (path, stem) in &plots {
            md += &format!("- `{path}`: [SVG](plots/{stem}.svg), ![{path}](plots/{stem}.png)\n");
        }
    }
    std::fs::write(&p, md).map_err(|e| io(&p, e))?;
    Ok(())
}

/// Metrics plotted against each varied value (when present).
const PLOTTED_METRICS: [(&str, &str); 9] = [
    ("fell", "fell (1 = yes)"),
    ("mean_forward_speed_mps", "mean forward speed (m/s)"),
    ("distance_m", "distance (m)"),
    ("energy_j", "energy (J)"),
    ("min_stability_margin_m", "min stability margin (m)"),
    ("base_height_p2p_m", "torso height p2p (m)"),
    ("max_foot_force_n", "max foot force (N)"),
    ("joint_rms_error_rad", "joint RMS error (rad)"),
    ("actuators.max_peak_torque_share", "peak torque share"),
];

/// `plots/metrics_vs_<path>.svg|png` for each numeric varied path: one panel
/// per main metric (the first robot's, for several robots). Returns (path, stem).
fn write_plots(
    dir: &Path,
    header: &ResultsHeader,
    rows: &[Value],
    flats: &[BTreeMap<String, Value>],
) -> Result<Vec<(String, String)>, CliError> {
    use crate::report::plots::{Figure, Panel, write_figure};
    let ok: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i]["status"] == "ok")
        .collect();
    let mut out = Vec::new();
    let plot_dir = dir.join("plots");
    for path in &header.paths {
        let xs: Vec<Option<f64>> = ok
            .iter()
            .map(|&i| rows[i]["params"][path].as_f64())
            .collect();
        if ok.is_empty() || xs.iter().any(Option::is_none) {
            continue; // names or tables: no axis
        }
        let mut panels = Vec::new();
        for (metric, label) in PLOTTED_METRICS {
            let pts: Vec<(f64, f64)> = ok
                .iter()
                .zip(&xs)
                .filter_map(|(&i, x)| {
                    let f = &flats[i];
                    let key = f
                        .keys()
                        .find(|k| *k == metric || k.ends_with(&format!("/{metric}")))?;
                    Some(((*x)?, metric_number(&f[key])?))
                })
                .collect();
            if pts.is_empty() {
                continue;
            }
            panels.push(Panel {
                title: label.to_string(),
                x_label: path.clone(),
                y_label: label.to_string(),
                scatter: pts,
                ..Default::default()
            });
        }
        if panels.is_empty() {
            continue;
        }
        std::fs::create_dir_all(&plot_dir).map_err(|e| io(&plot_dir, e))?;
        let stem = format!(
            "metrics_vs_{}",
            path.chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect::<String>()
        );
        write_figure(
            &Figure {
                stem: stem.clone(),
                panels,
                columns: 3,
            },
            &plot_dir,
        )
        .map_err(|e| io(Path::new(&e.path), std::io::Error::other(e.message)))?;
        out.push((path.clone(), crate::names::safe_file_stem(&stem)));
    }
    Ok(out)
}

/// The metrics the report's table shows, per robot, when present.
const REPORT_METRICS: [&str; 5] = [
    "fell",
    "mean_forward_speed_mps",
    "distance_m",
    "energy_j",
    "min_stability_margin_m",
];

fn report_md(
    h: &ResultsHeader,
    shard: Option<(usize, usize)>,
    rows: &[Value],
    flats: &[BTreeMap<String, Value>],
) -> String {
    let ok = rows.iter().filter(|r| r["status"] == "ok").count();
    let mut s = format!("# Sweep `{}`\n\n", h.study);
    s += &format!(
        "{} of {} variants in this file{}; {} ran to the end, {} failed.\n\n",
        rows.len(),
        h.variants_total,
        shard.map_or(String::new(), |(i, n)| format!(" (shard {i}/{n})")),
        ok,
        rows.len() - ok
    );
    s += &format!(
        "Varied: {}.\n\n",
        h.paths
            .iter()
            .map(|p| format!("`{p}`"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    s += "Every metric of every run is in `results.csv` and `results.json` \
          (definitions: scenarios/README.md, \"Metrics\").\n\n";
    let mut cols: Vec<String> = Vec::new();
    for f in flats {
        for k in f.keys() {
            let base = k.rsplit('/').next().unwrap_or(k);
            if REPORT_METRICS.contains(&base) && !cols.contains(k) {
                cols.push(k.clone());
            }
        }
    }
    cols.sort_by_key(|k| {
        let base = k.rsplit('/').next().unwrap_or(k);
        (
            k.rsplit_once('/').map(|x| x.0.to_string()),
            REPORT_METRICS.iter().position(|m| *m == base),
        )
    });
    s += "| variant | ";
    s += &h
        .paths
        .iter()
        .chain(&cols)
        .map(|c| format!("`{c}`"))
        .collect::<Vec<_>>()
        .join(" | ");
    s += " | status |\n|---|";
    s += &"---|".repeat(h.paths.len() + cols.len() + 1);
    s += "\n";
    for (r, f) in rows.iter().zip(flats) {
        s += &format!("| {} | ", cell(&r["variant"]));
        let mut cells: Vec<String> = h.paths.iter().map(|k| short(&r["params"][k])).collect();
        cells.extend(cols.iter().map(|k| f.get(k).map(short).unwrap_or_default()));
        s += &cells.join(" | ");
        let status = match r["error"].as_str() {
            Some(e) => format!("failed: {}", e.replace('|', "\\|").replace('\n', " ")),
            None => "ok".into(),
        };
        s += &format!(" | {status} |\n");
    }
    s += &super::analysis::sections(&h.analyses, rows, flats);
    s
}

fn short(v: &Value) -> String {
    match v {
        Value::Number(n) if n.is_f64() => format!("{:.4}", n.as_f64().unwrap_or(f64::NAN)),
        other => cell(other),
    }
}

/// An I/O failure on a named path.
pub(crate) fn io(p: &Path, e: std::io::Error) -> CliError {
    CliError::Io {
        path: p.display().to_string(),
        source: e,
    }
}

/// Makes sure results can be written to `dir` before anything runs: it is
/// created (with its parents) if missing, must be a directory, and must take
/// a file (a probe is written and removed). A study that would only find
/// this out after its last simulation loses every result.
///
/// # Errors
/// [`CliError::Io`] naming `dir` and why it cannot be used.
pub fn prepare_out_dir(dir: &Path) -> Result<(), CliError> {
    if dir.exists() && !dir.is_dir() {
        return Err(io(
            dir,
            std::io::Error::other("--out: exists and is not a directory; nothing was run"),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let probe = dir.join(format!(".quadsim-write-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| io(dir, e))?;
    std::fs::remove_file(&probe).map_err(|e| io(&probe, e))?;
    Ok(())
}
