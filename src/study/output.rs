//! A sweep's results: `results.json` (everything, the input of `quadsim
//! merge`), `results.csv` (one row per run: the varied values, then every
//! summary metric) and `report.md`.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{Map, Value, json};

use super::VariantResult;
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
            json!({"variant": r.index, "params": params, "status": "ok", "error": null, "summary": s})
        }
        Err(e) => {
            json!({"variant": r.index, "params": params, "status": "failed", "error": e, "summary": null})
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

    let p = dir.join("report.md");
    std::fs::write(&p, report_md(header, shard, rows, &flats)).map_err(|e| io(&p, e))?;
    Ok(())
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

fn io(p: &Path, e: std::io::Error) -> CliError {
    CliError::Io {
        path: p.display().to_string(),
        source: e,
    }
}
