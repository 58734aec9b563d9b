//! Study-level analyses written into a sweep's `report.md`: rank
//! correlations of a metric against a varied value (Study B's stability
//! factors), and the load-carrying table (speed, cost of transport, margin,
//! torque share and verdict per payload mass).
//!
//! ```toml
//! [[report.correlations]]
//! label = "stride frequency → CoM z oscillation"
//! param = "robots[0].controller.period_s"
//! metric = "com_oscillation_m_z"
//! expect = "negative"        # the study's claim, as a sign (period ↑ = frequency ↓)
//!
//! [report.load]
//! payload = "robots[0].payloads[0].mass_kg"
//! ```

use serde::{Deserialize, Serialize};
use serde_json::Value;

/// Standard gravity for the cost of transport (m/s²).
const G_MPS2: f64 = 9.81;

/// `[report]` of a study file.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StudyReportSpec {
    /// Rank correlations to report.
    #[serde(default)]
    pub correlations: Vec<CorrelationSpec>,
    /// The load-carrying table.
    pub load: Option<LoadSpec>,
}

/// One correlation: `metric` against the varied value at `param`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CorrelationSpec {
    /// What it shows.
    pub label: String,
    /// A varied path of the study.
    pub param: String,
    /// A column of `results.csv` (a metric).
    pub metric: String,
    /// The claimed direction: `positive` or `negative`.
    pub expect: String,
}

/// The load-carrying table's input.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// The varied payload mass path.
    pub payload: String,
}

/// Spearman's rank correlation of two equally long samples (average ranks
/// for ties); `None` with fewer than 3 points or a constant sample.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 3 {
        return None;
    }
    let (rx, ry) = (ranks(x), ranks(y));
    let n = x.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let avg = (i + j) as f64 / 2.0 + 1.0;
        for k in i..=j {
            r[idx[k]] = avg;
        }
        i = j + 1;
    }
    r
}

/// The numbers of `path` (a varied value) and `metric` (a flattened metric)
/// over the successful rows that have both.
fn pairs(
    rows: &[Value],
    flats: &[std::collections::BTreeMap<String, Value>],
    path: &str,
    metric: &str,
) -> Vec<(f64, f64)> {
    rows.iter()
        .zip(flats)
        .filter(|(r, _)| r["status"] == "ok")
        .filter_map(|(r, f)| {
            let x = r["params"][path].as_f64()?;
            let y = metric_number(f.get(metric)?)?;
            (x.is_finite() && y.is_finite()).then_some((x, y))
        })
        .collect()
}

/// The analyses' markdown sections.
pub fn sections(
    spec: &StudyReportSpec,
    rows: &[Value],
    flats: &[std::collections::BTreeMap<String, Value>],
) -> String {
    let mut s = String::new();
    if !spec.correlations.is_empty() {
        s += "\n## Correlations\n\nSpearman's rank correlation ρ of each metric with its \
              varied value over the runs that finished. *Agrees* means the sign of ρ is the \
              one claimed.\n\n| factor | metric | runs | ρ | claimed | agrees |\n|---|---|---|---|---|---|\n";
        for c in &spec.correlations {
            let p = pairs(rows, flats, &c.param, &c.metric);
            let (x, y): (Vec<f64>, Vec<f64>) = p.iter().copied().unzip();
            let rho = spearman(&x, &y);
            let want = if c.expect == "positive" { 1.0 } else { -1.0 };
            s += &format!(
                "| {} (`{}`) | `{}` | {} | {} | {} | {} |\n",
                c.label,
                c.param,
                c.metric,
                p.len(),
                rho.map_or("—".into(), |r| format!("{r:+.3}")),
                c.expect,
                match rho {
                    Some(r) if r * want > 0.0 => "yes",
                    Some(_) => "**no**",
                    None => "— (too few runs, or a constant)",
                }
            );
        }
    }
    if let Some(l) = &spec.load {
        s += &load_section(l, rows, flats);
    }
    s
}

fn load_section(
    l: &LoadSpec,
    rows: &[Value],
    flats: &[std::collections::BTreeMap<String, Value>],
) -> String {
    let mut s = format!(
        "\n## Load carrying\n\nPer payload mass (`{}`): mean forward speed, cost of transport \
         (energy / (distance × total weight), dimensionless), smallest stability margin, largest \
         peak torque as a share of its joint's limit, and whether the load was carried \
         (`load` in summary.json: fell, saturated or failed to track speed).\n\n\
         | payload (kg) | speed (m/s) | cost of transport | min margin (m) | peak torque share | verdict |\n\
         |---|---|---|---|---|---|\n",
        l.payload
    );
    let mut table: Vec<(f64, f64, bool)> = Vec::new();
    let num = |f: &std::collections::BTreeMap<String, Value>, k: &str| {
        f.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN)
    };
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by(|&a, &b| {
        let m = |i: usize| rows[i]["params"][&l.payload].as_f64().unwrap_or(f64::NAN);
        m(a).total_cmp(&m(b))
    });
    for i in order {
        let (r, f) = (&rows[i], &flats[i]);
        let mass = r["params"][&l.payload].as_f64().unwrap_or(f64::NAN);
        if r["status"] != "ok" {
            s += &format!(
                "| {mass:.1} | — | — | — | — | failed: {} |\n",
                r["error"].as_str().unwrap_or("?")
            );
            continue;
        }
        let speed = num(f, "mean_forward_speed_mps");
        let cot = num(f, "energy_j") / (num(f, "distance_m") * num(f, "total_mass_kg") * G_MPS2);
        let carried = f.get("load.carried") == Some(&Value::Bool(true));
        let verdict = if carried {
            "ok".to_string()
        } else {
            f.get("load.reason")
                .and_then(Value::as_str)
                .unwrap_or("not carried")
                .to_string()
        };
        s += &format!(
            "| {mass:.1} | {speed:.3} | {cot:.2} | {} | {:.2} | {verdict} |\n",
            f.get("min_stability_margin_m")
                .and_then(Value::as_f64)
                .map_or("—".into(), |m| format!("{m:.3}")),
            num(f, "actuators.max_peak_torque_share"),
        );
        table.push((mass, speed, carried));
    }
    let unloaded = table.iter().find(|(m, ..)| *m == 0.0).map(|t| t.1);
    s += "\n";
    let carried_max = table
        .iter()
        .filter(|(.., c)| *c)
        .map(|t| t.0)
        .fold(None, |a: Option<f64>, m| Some(a.map_or(m, |a| a.max(m))));
    match unloaded {
        Some(v0) if v0 <= 0.05 => {
            s += &format!(
                "The unloaded robot does not walk forward ({v0:.3} m/s), so speeds are not compared. {}\n",
                carried_max.map_or("No payload was carried.".to_string(), |m| format!(
                    "Largest payload carried: **{m:.1} kg**."
                ))
            );
        }
        Some(v0) => {
            let best = table
                .iter()
                .filter(|(_, v, c)| *c && *v >= 0.9 * v0)
                .map(|t| t.0)
                .fold(None, |a: Option<f64>, m| Some(a.map_or(m, |a| a.max(m))));
            s += &match best {
                Some(m) => format!(
                    "Largest payload carried at ≥ 90 % of the unloaded speed ({v0:.3} m/s): **{m:.1} kg**.\n"
                ),
                None => format!(
                    "No payload was carried at ≥ 90 % of the unloaded speed ({v0:.3} m/s).\n"
                ),
            };
        }
        None => s += "No unloaded (0 kg) run to compare with.\n",
    }
    s
}

/// A flattened metric as a number for plots and correlations (`true` = 1).
pub fn metric_number(v: &Value) -> Option<f64> {
    match v {
        Value::Bool(b) => Some(f64::from(u8::from(*b))),
        v => v.as_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spearman_matches_known_values() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(spearman(&x, &[2.0, 4.0, 8.0, 16.0, 32.0]), Some(1.0));
        assert_eq!(spearman(&x, &[5.0, 4.0, 3.0, 2.0, 1.0]), Some(-1.0));
        // ties: ranks 1, 2.5, 2.5, 4, 5 against 1..5 → ρ = 0.975 (Pearson of ranks)
        let r = spearman(&x, &[1.0, 3.0, 3.0, 4.0, 5.0]).unwrap();
        assert!((r - 0.974_679_434_480_896_4).abs() < 1e-12, "{r}");
        assert_eq!(spearman(&x, &[1.0; 5]), None);
        assert_eq!(spearman(&[1.0, 2.0], &[1.0, 2.0]), None);
    }
}
