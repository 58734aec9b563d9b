//! Design optimisation (`kind = "optimize"`, run by `quadsim optimize`):
//! CMA-ES (the `cmaes` crate) over bounded scenario values, each candidate
//! simulated in full, candidates of a generation run in parallel.
//!
//! ```toml
//! format_version = 1
//! kind = "optimize"
//! base = "trot.toml"
//! duration_s = 3.0
//! [optimize]
//! budget = 40                      # simulations, the start point included
//! population = 6                   # candidates per generation
//! seed = 1
//! step = 0.3                       # initial step, a fraction of each range
//! margin_weight_per_m = 10.0       # λ
//! [parameters]
//! "robots[0].params.thigh.length_m" = { min = 0.25, max = 0.35 }   # start: the base's value
//! ```
//!
//! Objective, minimised (first robot of the scenario):
//! `J = CoT − λ · margin + P_fall + P_speed`, with `CoT = energy_j /
//! (distance_m · total_mass_kg · 9.81)`, `margin` the run's smallest
//! stability margin (m; 0 when none), `P_fall = 10 + 10 · (1 − t_fall / T)`
//! when it fell (a later fall costs less), `P_speed = 10 · (0.9 v_cmd − v) /
//! v_cmd` when the mean speed `v` is below 90 % of the commanded `v_cmd`,
//! and `J = 100` for a run that fails. Candidates outside the bounds are
//! clipped to them and pay 10 per unit of normalised distance.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::Deserialize;
use serde_json::{Value, json};

use super::error::StudyError;
use crate::scenario::spans::path_key;
use crate::scenario::vary::set_path;
use crate::scenario::{Locator, ScenarioError, parse_scenario};
use crate::summary::Summary;

/// `[optimize]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimizeSpec {
    /// Simulations in all, the start point included (≥ 2).
    pub budget: usize,
    /// Candidates per generation (default CMA-ES's 4 + ⌊3 ln n⌋).
    pub population: Option<usize>,
    /// Seed of CMA-ES's sampling (default 0).
    #[serde(default)]
    pub seed: u64,
    /// Initial step as a fraction of each parameter's range (default 0.3).
    pub step: Option<f64>,
    /// λ, the weight of the stability margin (1/m, default 10).
    pub margin_weight_per_m: Option<f64>,
}

/// One bounded parameter.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamSpec {
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// Start value (default: the base scenario's value, else the middle).
    pub start: Option<f64>,
}

/// An optimisation study file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimizeFile {
    /// Must be 1.
    pub format_version: i64,
    /// `optimize`.
    pub kind: String,
    /// Name (default: the file stem).
    pub name: Option<String>,
    /// Base scenario, relative to the file.
    pub base: String,
    /// Simulated duration of each candidate (s).
    pub duration_s: Option<f64>,
    /// Optimiser settings.
    pub optimize: OptimizeSpec,
    /// Path → bounds.
    pub parameters: BTreeMap<String, ParamSpec>,
}

/// A loaded optimisation.
#[derive(Debug)]
pub struct Optimization {
    /// Its name.
    pub name: String,
    /// The file.
    pub file: OptimizeFile,
    /// Base scenario path and text.
    pub base_path: PathBuf,
    /// Base scenario text.
    pub base_source: String,
    /// (path, min, max, start), in path order.
    pub params: Vec<(String, f64, f64, f64)>,
}

/// One simulated candidate.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Generation (0: the start point).
    pub generation: usize,
    /// Parameter values (clipped to the bounds).
    pub values: Vec<f64>,
    /// Objective.
    pub objective: f64,
    /// Summary without timing, or the error.
    pub outcome: Result<Summary, StudyError>,
}

/// Reads and checks an optimisation file: bounds, budget, and that the base
/// with each start value is a valid scenario.
pub fn load_optimization(path: &Path) -> Result<Optimization, ScenarioError> {
    let src = super::read_study_text(path)?;
    let loc = Locator { path, src: &src };
    let file: OptimizeFile =
        toml::from_str(&src).map_err(|e| loc.at_span(e.span(), e.message().trim().to_string()))?;
    if file.kind != "optimize" {
        return Err(loc.at(
            "kind",
            "must be \"optimize\" (run sweeps with `quadsim sweep`)",
        ));
    }
    if file.optimize.budget < 2 {
        return Err(loc.at("optimize.budget", "must be at least 2 simulations"));
    }
    if file.optimize.population.is_some_and(|p| p < 2) {
        return Err(loc.at("optimize.population", "must be at least 2"));
    }
    if file.parameters.is_empty() {
        return Err(loc.at("parameters", "names no parameter to optimise"));
    }
    let (base_path, base_source, base) = super::read_base(&loc, path, &file.base)?;
    let mut params = Vec::new();
    for (p, b) in &file.parameters {
        let kp = format!("parameters.{}", path_key(p));
        if !(b.min.is_finite() && b.max.is_finite() && b.min < b.max) {
            return Err(loc.at(
                &kp,
                format!("'{p}': min must be below max (an empty range)"),
            ));
        }
        let start = b
            .start
            .or_else(|| current_value(&base, p))
            .unwrap_or(0.5 * (b.min + b.max));
        if !(b.min..=b.max).contains(&start) {
            return Err(loc.at(
                &kp,
                format!(
                    "'{p}': the start value {start} is outside [{}, {}]",
                    b.min, b.max
                ),
            ));
        }
        let mut probe = base.clone();
        set_path(&mut probe, p, toml::Value::Float(start))
            .map_err(|e| loc.at(&kp, format!("'{p}': {e}")))?;
        let text = toml::to_string(&probe).map_err(|e| loc.at(&kp, e.to_string()))?;
        let scn = parse_scenario(&base_path, text)
            .map_err(|e| loc.at(&kp, format!("'{p}': {}", e.message_with_path())))?;
        crate::world::build_world(&scn, crate::world::Overrides::default())
            .map_err(|e| loc.at(&kp, format!("'{p}': {}", e.message_with_path())))?;
        params.push((p.clone(), b.min, b.max, start));
    }
    if let Some(n) = &file.name {
        crate::scenario::validate::name(&loc, "name", n)?;
    }
    let name = file.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| crate::names::safe_file_stem(&s.to_string_lossy()))
            .unwrap_or_else(|| "optimize".into())
    });
    Ok(Optimization {
        name,
        file,
        base_path,
        base_source,
        params,
    })
}

/// The base's number at `path` (a built-in's `params.X` is not in the file,
/// so it is `None` there and the middle of the range is used).
fn current_value(base: &toml::Table, path: &str) -> Option<f64> {
    crate::scenario::vary::get_path(base, path).and_then(crate::scenario::validate::as_f64)
}

/// The objective of a finished run (see the module docs).
pub fn objective(summary: &Summary, margin_weight_per_m: f64) -> f64 {
    let Some(r) = summary.robots.first() else {
        return FAILED_OBJECTIVE;
    };
    let (e, d, m) = (r.energy_j, r.distance_m, r.total_mass_kg);
    if !(e.is_finite() && d.is_finite() && m.is_finite()) {
        return FAILED_OBJECTIVE;
    }
    let cot = e / (d.max(1e-3) * m * 9.81);
    let margin = r.min_stability_margin_m.unwrap_or(0.0);
    let mut j = cot - margin_weight_per_m * margin;
    if r.fell {
        let t = if summary.sim_time_s.is_finite() {
            summary.sim_time_s
        } else {
            1.0
        }
        .max(1e-9);
        let tf = r.fell_at_s.unwrap_or(0.0);
        j += 10.0 + 10.0 * (1.0 - tf / t).clamp(0.0, 1.0);
    }
    let v = r.mean_forward_speed_mps;
    if let Some(c) = r.commanded_speed_mps
        && v.is_finite()
        && c > 0.05
        && v < 0.9 * c
    {
        j += 10.0 * (0.9 * c - v) / c;
    }
    if j.is_finite() { j } else { FAILED_OBJECTIVE }
}

/// The objective of a run that failed (an error, a divergence).
pub const FAILED_OBJECTIVE: f64 = 100.0;

impl Optimization {
    fn values_at(&self, u: &[f64]) -> (Vec<f64>, f64) {
        let mut outside = 0.0;
        let values = self
            .params
            .iter()
            .zip(u)
            .map(|((_, lo, hi, _), &ui)| {
                let c = ui.clamp(0.0, 1.0);
                outside += (ui - c).abs();
                lo + (hi - lo) * c
            })
            .collect();
        (values, outside)
    }

    /// Simulates one candidate.
    pub fn evaluate(&self, generation: usize, values: &[f64]) -> Evaluation {
        let map: BTreeMap<String, toml::Value> = self
            .params
            .iter()
            .zip(values)
            .map(|((p, ..), v)| (p.clone(), toml::Value::Float(*v)))
            .collect();
        let outcome = super::with_values(&self.base_source, &map)
            .and_then(|src| super::run_source(&self.base_path, src, self.file.duration_s));
        let lambda = self.file.optimize.margin_weight_per_m.unwrap_or(10.0);
        let objective = outcome
            .as_ref()
            .map_or(FAILED_OBJECTIVE, |s| objective(s, lambda));
        Evaluation {
            generation,
            values: values.to_vec(),
            objective,
            outcome,
        }
    }

    /// Runs the optimisation: the start point, then CMA-ES generations until
    /// the budget is spent. Deterministic for a seed: a generation's
    /// candidates are recorded in the order of their values, whatever order
    /// the threads finish in. `progress` is called after each simulation.
    pub fn run(&self, progress: &(dyn Fn(usize) + Sync)) -> Result<Vec<Evaluation>, String> {
        let n = self.params.len();
        let start_u: Vec<f64> = self
            .params
            .iter()
            .map(|(_, lo, hi, s)| (s - lo) / (hi - lo))
            .collect();
        let mut history = vec![self.evaluate(0, &self.values_at(&start_u).0)];
        progress(1);
        let budget = self.file.optimize.budget;
        let generation_records: Mutex<Vec<Evaluation>> = Mutex::new(Vec::new());
        let done = std::sync::atomic::AtomicUsize::new(1);
        let gen_counter = std::sync::atomic::AtomicUsize::new(1);
        let f = |u: &cmaes::DVector<f64>| -> f64 {
            let (values, outside) = self.values_at(u.as_slice());
            let g = gen_counter.load(std::sync::atomic::Ordering::Relaxed);
            let mut e = self.evaluate(g, &values);
            e.objective += 10.0 * outside;
            let j = e.objective;
            generation_records.lock().expect("no panics").push(e);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            j
        };
        // Whole generations within the budget (CMA-ES finishes a generation
        // it has started): population × generations ≤ budget − 1.
        let population = self
            .file
            .optimize
            .population
            .unwrap_or(4 + (3.0 * (n as f64).ln()).floor() as usize);
        let generations = (budget - 1) / population;
        if generations == 0 {
            return Err(format!(
                "a budget of {budget} simulations leaves no room for one generation of {population} after the start point"
            ));
        }
        let opts = cmaes::CMAESOptions::new(start_u, self.file.optimize.step.unwrap_or(0.3))
            .seed(self.file.optimize.seed)
            .population_size(population)
            .max_generations(generations);
        let mut state = opts.build(&f).map_err(|e| format!("CMA-ES: {e:?}"))?;
        loop {
            let stop = state.next_parallel();
            let mut generation =
                std::mem::take(&mut *generation_records.lock().expect("no panics"));
            generation.sort_by(|a, b| {
                a.values
                    .iter()
                    .zip(&b.values)
                    .map(|(x, y)| x.total_cmp(y))
                    .find(|o| o.is_ne())
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            history.extend(generation);
            gen_counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if stop.is_some() || history.len() >= budget {
                break;
            }
        }
        Ok(history)
    }
}

/// `optimize.json`: the parameters, every evaluation and the best one.
pub fn results_json(opt: &Optimization, history: &[Evaluation]) -> Value {
    let best = best_index(history);
    let eval = |e: &Evaluation| {
        json!({
            "generation": e.generation,
            "values": opt.params.iter().zip(&e.values).map(|((p, ..), v)| (p.clone(), json!(v))).collect::<serde_json::Map<String, Value>>(),
            "objective": e.objective,
            "error": e.outcome.as_ref().err().map(ToString::to_string),
            "summary": e.outcome.as_ref().ok().map(Summary::to_json),
        })
    };
    json!({
        "study": opt.name,
        "parameters": opt.params.iter().map(|(p, lo, hi, s)| json!({"path": p, "min": lo, "max": hi, "start": s})).collect::<Vec<_>>(),
        "evaluations": history.iter().map(eval).collect::<Vec<_>>(),
        "best": best.map(|i| json!({"evaluation": i, "objective": history[i].objective})),
        "start_objective": history.first().map(|e| e.objective),
    })
}

/// Index of the lowest objective (the first of equals).
pub fn best_index(history: &[Evaluation]) -> Option<usize> {
    (0..history.len()).min_by(|&a, &b| history[a].objective.total_cmp(&history[b].objective))
}
