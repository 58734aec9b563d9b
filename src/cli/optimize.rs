//! `quadsim optimize FILE`: design optimisation by CMA-ES over a scenario's
//! values (see [`crate::study::optimize`]).

use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::Value;

use crate::error::{CliError, bad};
use crate::study::optimize::{Evaluation, best_index, load_optimization, results_json};
use crate::study::output::io;

/// Arguments of `quadsim optimize`.
#[derive(Debug, Args)]
pub struct OptimizeArgs {
    /// The study file (`kind = "optimize"`).
    pub study: PathBuf,
    /// Output directory (default `runs/<study name>/`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `quadsim optimize`.
pub fn run(a: OptimizeArgs) -> Result<(), CliError> {
    let opt = load_optimization(&a.study).map_err(|e| bad(e.to_string()))?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs").join(&opt.name));
    crate::study::output::prepare_out_dir(&out)?;
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(opt.file.optimize.budget as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {pos}/{len} simulations, eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_message(opt.name.clone());
    let history = opt.run(&|n| bar.set_position(n as u64)).map_err(bad)?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&out).map_err(|e| io(&out, e))?;
    let json = results_json(&opt, &history);
    let p = out.join("optimize.json");
    std::fs::write(
        &p,
        serde_json::to_string_pretty(&json).expect("json") + "\n",
    )
    .map_err(|e| io(&p, e))?;
    // history.csv: one row per simulation
    let p = out.join("history.csv");
    let mut w = csv::Writer::from_path(&p).map_err(|e| io(&p, std::io::Error::other(e)))?;
    let mut head = vec!["evaluation".to_string(), "generation".into()];
    head.extend(opt.params.iter().map(|(p, ..)| p.clone()));
    head.extend(["objective".into(), "error".into()]);
    w.write_record(&head)
        .map_err(|e| io(&p, std::io::Error::other(e)))?;
    for (i, e) in history.iter().enumerate() {
        let mut rec = vec![i.to_string(), e.generation.to_string()];
        rec.extend(e.values.iter().map(|v| v.to_string()));
        rec.push(e.objective.to_string());
        rec.push(
            e.outcome
                .as_ref()
                .err()
                .map(ToString::to_string)
                .unwrap_or_default(),
        );
        w.write_record(&rec)
            .map_err(|e| io(&p, std::io::Error::other(e)))?;
    }
    w.flush().map_err(|e| io(&p, e))?;
    write_convergence_plot(&out, &history)?;
    let md = report_md(&opt, &history);
    let p = out.join("report.md");
    std::fs::write(&p, md).map_err(|e| io(&p, e))?;
    let best = best_index(&history).expect("at least the start point");
    println!(
        "{}: {} simulations; objective {:.4} at the start, best {:.4} (simulation {best}); wrote {}/optimize.json, history.csv, report.md",
        opt.name,
        history.len(),
        history[0].objective,
        history[best].objective,
        out.display()
    );
    Ok(())
}

fn write_convergence_plot(out: &Path, history: &[Evaluation]) -> Result<(), CliError> {
    use crate::report::plots::{Figure, Line, Panel, write_figure};
    let mut best = f64::INFINITY;
    let best_line: Vec<(f64, f64)> = history
        .iter()
        .enumerate()
        .map(|(i, e)| {
            best = best.min(e.objective);
            (i as f64, best)
        })
        .collect();
    let dots: Vec<(f64, f64)> = history
        .iter()
        .enumerate()
        .map(|(i, e)| (i as f64, e.objective))
        .collect();
    let dir = out.join("plots");
    std::fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
    write_figure(
        &Figure {
            stem: "convergence".into(),
            panels: vec![Panel {
                title: "Objective per simulation (dots) and best so far".into(),
                x_label: "simulation".into(),
                y_label: "objective J".into(),
                lines: vec![Line {
                    label: "best so far".into(),
                    points: best_line,
                    dashed: false,
                }],
                scatter: dots,
                ..Default::default()
            }],
            columns: 1,
        },
        &dir,
    )
    .map_err(|e| io(Path::new(&e.path), std::io::Error::other(e.message)))?;
    Ok(())
}

fn report_md(opt: &crate::study::optimize::Optimization, history: &[Evaluation]) -> String {
    let best = best_index(history).expect("start point");
    let (s0, sb) = (&history[0], &history[best]);
    let metric = |e: &Evaluation, k: &str| -> String {
        match e
            .outcome
            .as_ref()
            .ok()
            .map(|s| s.to_json()["robots"][0][k].clone())
        {
            Some(Value::Number(n)) => format!("{:.4}", n.as_f64().unwrap_or(f64::NAN)),
            Some(Value::Bool(b)) => b.to_string(),
            _ => "—".into(),
        }
    };
    let mut s = format!(
        "# Optimisation `{}`\n\nCMA-ES (the `cmaes` crate), {} simulations (budget {}), seed {}, \
         objective J = CoT − λ·margin + penalties with λ = {} 1/m (definition: docs/sweeps.md, \
         \"Optimisation\").\n\n",
        opt.name,
        history.len(),
        opt.file.optimize.budget,
        opt.file.optimize.seed,
        opt.file.optimize.margin_weight_per_m.unwrap_or(10.0)
    );
    s += "| | start | best |\n|---|---|---|\n";
    for (i, (p, ..)) in opt.params.iter().enumerate() {
        s += &format!("| `{p}` | {:.4} | {:.4} |\n", s0.values[i], sb.values[i]);
    }
    s += &format!(
        "| objective J | {:.4} | {:.4} |\n",
        s0.objective, sb.objective
    );
    for k in [
        "fell",
        "mean_forward_speed_mps",
        "energy_j",
        "distance_m",
        "min_stability_margin_m",
    ] {
        s += &format!("| `{k}` | {} | {} |\n", metric(s0, k), metric(sb, k));
    }
    s += &format!(
        "\nBest: simulation {best} (generation {}). {}\n\n![convergence](plots/convergence.png)\n\n\
         Every simulation is in `history.csv` and, with its summary, in `optimize.json`.\n",
        sb.generation,
        if sb.objective < s0.objective {
            format!(
                "It improves on the start by {:.4}.",
                s0.objective - sb.objective
            )
        } else {
            "No candidate improved on the start.".to_string()
        }
    );
    s
}
