//! `quadsim bench`: throughput of whole-world steps (gait, control, contact,
//! dynamics, integration; no logging) for herds of trotting robots, by robot
//! count and thread count, and the heap bytes each robot costs.
//!
//! Each configuration is a world of `n` robots on a concrete plane (a grid
//! 1.5 m × 1 m apart), warmed up, then timed over `--repeats` blocks of
//! `--steps` steps; the median block is reported. Memory per robot is
//! (live heap bytes with `n` robots − bytes with none) / n, counted by the
//! binary's allocator ([`crate::mem`]); robots of one design share one model,
//! counted once.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, ValueEnum};
use serde_json::{Value, json};

use crate::error::{CliError, bad};
use crate::scenario::parse_scenario;
use crate::world::{Overrides, build_world};

/// Arguments of `quadsim bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Robot counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 64, 256, 1000])]
    pub robots: Vec<usize>,
    /// Thread counts, comma-separated (0: one per core).
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2])]
    pub threads: Vec<usize>,
    /// Timed steps per block (0.5 ms each).
    #[arg(long, default_value_t = 400)]
    pub steps: u64,
    /// Timed simulated time per block (s), instead of `--steps`: 0.2 is
    /// 400 steps of 0.5 ms.
    #[arg(long, conflicts_with = "steps")]
    pub sim_seconds: Option<f64>,
    /// Timed blocks per configuration; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Untimed steps first (the robots settle on their feet and start trotting).
    #[arg(long, default_value_t = 200)]
    pub warmup: u64,
    /// Robot model: `quad16` (trotting under VMC at 0.5 m/s) or `quad12` (standing under joint PD).
    #[arg(long, default_value = "quad16")]
    pub model: String,
    /// SIMD lanes across robots: `auto` (four robots of one model at a
    /// time, unless each robot runs its four legs in lanes, which quad16
    /// and quad12 do on an AVX2 CPU), `across-robots` (always four robots at
    /// a time) or `off` (each robot alone). The results are the same; for
    /// comparing the speed.
    #[arg(long, value_enum, default_value_t = BenchLanes::Auto)]
    pub lanes: BenchLanes,
    /// Robots per block of the step's robot pass (each block goes through
    /// sense, control, contact, integration and metrics while in cache);
    /// 0 runs each stage over every robot in turn instead (the results are
    /// the same; for comparing the speed).
    #[arg(long, default_value_t = quadsim_components::DEFAULT_BLOCK_ROBOTS)]
    pub block_robots: usize,
    /// What the controller reads: `estimated` (the robots' default: noisy
    /// IMU, encoders and contact sensors and the base estimator, as a real
    /// robot) or `ground-truth` (the exact state; no sensors and no
    /// estimator, the "controller, contact and dynamics" alone).
    #[arg(long, value_enum, default_value_t = BenchSensing::Estimated)]
    pub sensing: BenchSensing,
    /// quad16's walker with the whole-body layer and its long-swing trot (the
    /// `vmc` controller's default) instead of Study A's `τ = Jᵀ f` with
    /// Study A's trot, which the performance history measures.
    #[arg(long)]
    pub whole_body: bool,
    /// quad16's body-force planner: `vmc` (Study A's virtual wrench) or
    /// `mpc` (convex MPC; implies `--whole-body`); with `mpc` the output
    /// also gives the median time of one MPC solve on a trot's problem.
    #[arg(long, value_enum, default_value_t = BenchPlanner::Vmc)]
    pub planner: BenchPlanner,
    /// With `--whole-body` or `--planner mpc` (quad16): also time the same
    /// herd under Study A's `τ = Jᵀ f` in the same run, its blocks
    /// alternating with the whole-body herd's (so that both see the same
    /// machine load), and report both and the whole-body herd's throughput
    /// as a fraction of the `τ = Jᵀ f` herd's (issue 27's cost target).
    #[arg(long)]
    pub side_by_side: bool,
    /// Write the figures as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// SIMD lanes across robots (`quadsim bench --lanes`; see
/// [`quadsim_components::LaneBatching`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchLanes {
    /// Across robots unless a robot's legs run in lanes.
    Auto,
    /// Always four robots of one model at a time.
    AcrossRobots,
    /// Each robot alone.
    Off,
}

impl From<BenchLanes> for quadsim_components::LaneBatching {
    fn from(l: BenchLanes) -> Self {
        match l {
            BenchLanes::Auto => Self::Auto,
            BenchLanes::AcrossRobots => Self::AcrossRobots,
            BenchLanes::Off => Self::Off,
        }
    }
}

/// quad16's body-force planner in the benchmark (`quadsim bench --planner`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchPlanner {
    /// Study A's virtual model control.
    Vmc,
    /// Convex MPC on the single rigid body (with the whole-body layer).
    Mpc,
}

/// Median wall time (µs) of `solves` solves of the MPC's trot problem, 0.02 s
/// apart as the walker asks at 50 Hz
/// ([`quadsim_engine::control::mpc::trot_benchmark_problem_at`]).
pub fn mpc_solve_median_us(solves: usize) -> f64 {
    use quadsim_engine::control::mpc::{Mpc, MpcParams, trot_benchmark_problem_at};
    let params = MpcParams::default();
    let mut mpc = Mpc::new(params);
    let mut times: Vec<f64> = (0..solves.max(1))
        .map(|s| {
            let pb = trot_benchmark_problem_at(&params, 0.02 * s as f64);
            let t = std::time::Instant::now();
            let ok = mpc.solve(&pb).is_ok();
            std::hint::black_box(ok);
            t.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// What the benchmarked controllers read (`quadsim bench --sensing`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchSensing {
    /// The robots' default sensors and base estimator; the controller reads the estimate.
    Estimated,
    /// No sensors, no estimator: the controller reads the exact state.
    GroundTruth,
}

impl BenchSensing {
    /// The name in the output (`estimated`, `ground_truth`, as `state_source`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Estimated => "estimated",
            Self::GroundTruth => "ground_truth",
        }
    }
}

/// What a benchmark robot does: the herd scenario's two halves
/// (`scenarios/herd.toml`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum BenchWorkload {
    /// Trotting at 0.5 m/s under VMC.
    Trot,
    /// Standing under joint PD.
    Stand,
}

/// The models `quadsim bench` runs and what each does: quad16 trots,
/// quad12 stands (it does not trot under VMC yet).
const BENCH_MODELS: &[(&str, BenchWorkload)] = &[
    ("quad16", BenchWorkload::Trot),
    ("quad12", BenchWorkload::Stand),
];

/// The workload of `--model`.
fn workload(model: &str) -> Result<BenchWorkload, CliError> {
    BENCH_MODELS
        .iter()
        .find(|(m, _)| *m == model)
        .map(|&(_, w)| w)
        .ok_or_else(|| {
            let names: Vec<&str> = BENCH_MODELS.iter().map(|(m, _)| *m).collect();
            bad(format!("--model {model}: expected {}", names.join(" or ")))
        })
}

/// The scenario of one configuration. quad16 runs on ideal torque sources
/// (not its default DC motors), like MuJoCo's `motor` actuators in the
/// side-by-side model, so the figures compare with it and with earlier runs.
pub fn herd_scenario(model: &str, robots: usize) -> Result<String, CliError> {
    bench_scenario(model, robots, BenchSensing::Estimated)
}

/// [`herd_scenario`] with the controllers reading what `sensing` says.
pub fn bench_scenario(
    model: &str,
    robots: usize,
    sensing: BenchSensing,
) -> Result<String, CliError> {
    bench_scenario_with(model, robots, sensing, false, BenchPlanner::Vmc)
}

/// [`bench_scenario`]; quad16 under the whole-body layer when `whole_body`
/// (otherwise Study A's `τ = Jᵀ f` and trot timing, as the history
/// measured), and with the MPC planner (and the whole-body layer) when
/// `planner` is [`BenchPlanner::Mpc`].
pub fn bench_scenario_with(
    model: &str,
    robots: usize,
    sensing: BenchSensing,
    whole_body: bool,
    planner: BenchPlanner,
) -> Result<String, CliError> {
    let mpc = planner == BenchPlanner::Mpc;
    let controller = match (workload(model)?, whole_body || mpc) {
        (BenchWorkload::Trot, true) if mpc => {
            "kind = \"vmc\"\nplanner = \"mpc\"\nv_x_mps = 0.5\n[herds.robot.actuators]\nkind = \"ideal\""
        }
        (BenchWorkload::Trot, false) => {
            "kind = \"vmc\"\nwhole_body = false\nv_x_mps = 0.5\n[herds.robot.actuators]\nkind = \"ideal\""
        }
        (BenchWorkload::Trot, true) => {
            "kind = \"vmc\"\nv_x_mps = 0.5\n[herds.robot.actuators]\nkind = \"ideal\""
        }
        (BenchWorkload::Stand, _) => "kind = \"joint_pd\"",
    };
    let mut s = String::from(
        "format_version = 1\n[world]\nname = \"bench\"\ndt_s = 0.0005\nduration_s = 1.0\n\
         seed = 1\ncontroller_rate_hz = 500\ndefault_ground = \"concrete\"\n",
    );
    if robots > 0 {
        let cols = (robots as f64).sqrt().ceil() as usize;
        s += &format!(
            "[[herds]]\nname = \"r\"\ncount = {robots}\n\
             layout = {{ kind = \"grid\", columns = {cols}, spacing_m = [1.5, 1.0] }}\n\
             [herds.robot]\nmodel = \"{model}\"\nlog = false\n[herds.robot.controller]\n{controller}\n"
        );
        if sensing == BenchSensing::GroundTruth {
            s += "[herds.robot.sensors]\npreset = \"none\"\n\
                  [herds.robot.estimator]\nstate_source = \"ground_truth\"\n";
        }
    }
    Ok(s)
}

/// One configuration's figures.
#[derive(Debug, Clone)]
pub struct BenchPoint {
    /// Robots in the world.
    pub robots: usize,
    /// Worker threads.
    pub threads: usize,
    /// Median wall time of one block (s).
    pub block_wall_s: f64,
    /// Steps per block.
    pub steps: u64,
    /// Live heap bytes per robot, if counted.
    pub bytes_per_robot: Option<f64>,
}

impl BenchPoint {
    /// Robot-steps per wall-clock second.
    pub fn robot_steps_per_s(&self) -> f64 {
        (self.robots as u64 * self.steps) as f64 / self.block_wall_s
    }
    /// Wall time per robot-step (µs).
    pub fn us_per_robot_step(&self) -> f64 {
        1e6 / self.robot_steps_per_s()
    }
}

/// One configuration's world, built, warmed up and ready to time.
struct Prepared {
    world: crate::world::World,
    robots: usize,
    threads: usize,
    bytes_per_robot: Option<f64>,
}

impl Prepared {
    /// Builds and warms up `robots` robots on `threads` threads, the
    /// controller layer chosen by `whole_body` and `planner`.
    fn new(
        a: &BenchArgs,
        robots: usize,
        threads: usize,
        whole_body: bool,
        planner: BenchPlanner,
    ) -> Result<Prepared, CliError> {
        let build = |n: usize| {
            let src = bench_scenario_with(&a.model, n, a.sensing, whole_body, planner)?;
            let scn =
                parse_scenario(Path::new("bench.toml"), src).map_err(|e| bad(e.to_string()))?;
            build_world(
                &scn,
                Overrides {
                    threads,
                    ..Default::default()
                },
            )
            .map_err(|e| bad(e.to_string()))
        };
        let before = crate::mem::live_bytes();
        let empty = build(0)?;
        let base = crate::mem::live_bytes().zip(before).map(|(a, b)| a - b);
        drop(empty);
        let before = crate::mem::live_bytes();
        let mut w = build(robots)?;
        w.sim
            .world
            .insert_resource(quadsim_components::LaneBatching::from(a.lanes));
        w.sim.world.insert_resource(match a.block_robots {
            0 => quadsim_components::StageLayout::StageMajor,
            n => quadsim_components::StageLayout::RobotBlocks { robots: n },
        });
        w.sim.run(a.warmup.max(1));
        let with = crate::mem::live_bytes().zip(before).map(|(a, b)| a - b);
        let bytes_per_robot = match (with, base) {
            (Some(w), Some(b)) if robots > 0 => Some((w - b) as f64 / robots as f64),
            _ => None,
        };
        Ok(Prepared {
            world: w,
            robots,
            threads,
            bytes_per_robot,
        })
    }

    /// Wall time (s) of one block of `steps` steps.
    fn time_block(&mut self, steps: u64) -> f64 {
        let t = Instant::now();
        self.world.sim.run(steps);
        t.elapsed().as_secs_f64()
    }

    /// Warns on stderr when robots fell during the benchmark.
    fn warn_falls(&self, what: &str) {
        let w = &self.world;
        let fell = w
            .robots
            .iter()
            .filter(|(_, e)| {
                w.sim
                    .robot(*e)
                    .is_some_and(|r| r.run.metrics.summary().fell)
            })
            .count();
        if fell > 0 {
            eprintln!(
                "warning: {fell} of {} robots fell during the benchmark{what}",
                self.robots
            );
        }
    }

    fn point(&self, blocks: &mut [f64], steps: u64) -> BenchPoint {
        BenchPoint {
            robots: self.robots,
            threads: self.threads,
            block_wall_s: median(blocks),
            steps,
            bytes_per_robot: self.bytes_per_robot,
        }
    }
}

/// The median of `x` (sorted in place; the upper one of an even count).
fn median(x: &mut [f64]) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

/// Builds, warms up and times one configuration.
pub fn measure(a: &BenchArgs, robots: usize, threads: usize) -> Result<BenchPoint, CliError> {
    let mut p = Prepared::new(a, robots, threads, a.whole_body, a.planner)?;
    let mut blocks: Vec<f64> = (0..a.repeats.max(1))
        .map(|_| p.time_block(a.steps))
        .collect();
    p.warn_falls("");
    Ok(p.point(&mut blocks, a.steps))
}

/// A configuration under the whole-body layer and the same herd under
/// Study A's `τ = Jᵀ f`, timed side by side (`quadsim bench --side-by-side`).
#[derive(Debug, Clone)]
pub struct SideBySide {
    /// The whole-body herd (with the chosen planner).
    pub whole_body: BenchPoint,
    /// The `τ = Jᵀ f` herd.
    pub jt: BenchPoint,
    /// The median over the pairs of blocks of the whole-body herd's
    /// throughput over the `τ = Jᵀ f` herd's in the block just before.
    pub pair_ratio_median: f64,
}

impl SideBySide {
    /// The whole-body herd's throughput as a fraction of the `τ = Jᵀ f`
    /// herd's (the medians' ratio).
    pub fn ratio(&self) -> f64 {
        self.whole_body.robot_steps_per_s() / self.jt.robot_steps_per_s()
    }
}

/// Builds both herds, warms them up, then times `--repeats` pairs of
/// blocks, a `τ = Jᵀ f` block then a whole-body block.
pub fn measure_side_by_side(
    a: &BenchArgs,
    robots: usize,
    threads: usize,
) -> Result<SideBySide, CliError> {
    let mut wb = Prepared::new(a, robots, threads, true, a.planner)?;
    let mut jt = Prepared::new(a, robots, threads, false, BenchPlanner::Vmc)?;
    let n = a.repeats.max(1);
    let (mut tj, mut tw, mut pairs) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..n {
        let j = jt.time_block(a.steps);
        let w = wb.time_block(a.steps);
        tj.push(j);
        tw.push(w);
        pairs.push(j / w);
    }
    jt.warn_falls(" (τ = Jᵀ f)");
    wb.warn_falls(" (whole body)");
    Ok(SideBySide {
        whole_body: wb.point(&mut tw, a.steps),
        jt: jt.point(&mut tj, a.steps),
        pair_ratio_median: median(&mut pairs),
    })
}

/// The benchmark's step (s).
pub const BENCH_DT_S: f64 = 0.0005;

/// Runs `quadsim bench`.
pub fn run(mut a: BenchArgs) -> Result<(), CliError> {
    if let Some(s) = a.sim_seconds {
        if !(s.is_finite() && s >= BENCH_DT_S) {
            return Err(bad(format!(
                "--sim-seconds {s}: expected at least one step, {BENCH_DT_S} s"
            )));
        }
        a.steps = (s / BENCH_DT_S).round() as u64;
    }
    if a.steps == 0 || a.robots.contains(&0) {
        return Err(bad("--steps and every --robots count must be at least 1"));
    }
    herd_scenario(&a.model, 1)?;
    let side = a.side_by_side;
    if side && !(a.model == "quad16" && (a.whole_body || a.planner == BenchPlanner::Mpc)) {
        return Err(bad(
            "--side-by-side compares quad16's whole-body layer with τ = Jᵀ f: give --whole-body or --planner mpc",
        ));
    }
    let total = (a.robots.len() * a.threads.len()) as u64;
    let bar = indicatif::ProgressBar::new(total);
    let mut points = Vec::new();
    let mut pairs = Vec::new();
    for &n in &a.robots {
        for &t in &a.threads {
            bar.set_message(format!("{n} robots, {t} threads"));
            if side {
                let sbs = measure_side_by_side(&a, n, t)?;
                points.push(sbs.whole_body.clone());
                pairs.push(sbs);
            } else {
                points.push(measure(&a, n, t)?);
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let build = Build::of_this_binary();
    println!("build: {}", build.describe());
    println!(
        "{} ({}; controller on the {} state), dt 0.5 ms, median of {} blocks of {} steps after {} warm-up steps",
        a.model,
        match workload(&a.model)? {
            BenchWorkload::Trot if a.planner == BenchPlanner::Mpc => {
                "trotting at 0.5 m/s under MPC and the whole-body layer"
            }
            BenchWorkload::Trot if a.whole_body => {
                "trotting at 0.5 m/s under VMC and the whole-body layer"
            }
            BenchWorkload::Trot => "trotting at 0.5 m/s under VMC, Study A's τ = Jᵀ f",
            BenchWorkload::Stand => "standing under joint PD",
        },
        match a.sensing {
            BenchSensing::Estimated => "estimated",
            BenchSensing::GroundTruth => "exact",
        },
        a.repeats,
        a.steps,
        a.warmup
    );
    println!(
        "{:>7} {:>7} {:>16} {:>14} {:>12} {:>10} {:>14}",
        "robots",
        "threads",
        "robot-steps/s",
        "µs/robot-step",
        "× real time",
        "speedup",
        "KiB/robot"
    );
    let mut rows = Vec::new();
    for p in &points {
        let one = points
            .iter()
            .find(|q| q.robots == p.robots && q.threads == 1)
            .map(|q| q.block_wall_s / p.block_wall_s);
        let rt = p.steps as f64 * BENCH_DT_S / p.block_wall_s;
        println!(
            "{:>7} {:>7} {:>16.0} {:>14.3} {:>12.2} {:>10} {:>14}",
            p.robots,
            p.threads,
            p.robot_steps_per_s(),
            p.us_per_robot_step(),
            rt,
            one.map_or("-".into(), |s| format!("{s:.2}×")),
            p.bytes_per_robot
                .map_or("-".into(), |b| format!("{:.1}", b / 1024.0)),
        );
        let mut row = json!({
            "robots": p.robots,
            "threads": p.threads,
            "robot_steps_per_s": p.robot_steps_per_s(),
            "us_per_robot_step": p.us_per_robot_step(),
            "ns_per_robot_step": 1e3 * p.us_per_robot_step(),
            "real_time_factor": rt,
            "speedup_vs_1_thread": one,
            "bytes_per_robot": p.bytes_per_robot,
        });
        if let Some(sbs) = pairs
            .iter()
            .find(|s| s.whole_body.robots == p.robots && s.whole_body.threads == p.threads)
        {
            row["jt_robot_steps_per_s"] = json!(sbs.jt.robot_steps_per_s());
            row["whole_body_over_jt"] = json!(sbs.ratio());
            row["whole_body_over_jt_pair_median"] = json!(sbs.pair_ratio_median);
        }
        rows.push(row);
    }
    if side {
        println!(
            "side by side in this run, blocks alternating (τ = Jᵀ f, then the whole-body layer):"
        );
        println!(
            "{:>7} {:>7} {:>18} {:>18} {:>10} {:>16}",
            "robots", "threads", "τ = Jᵀ f steps/s", "whole-body steps/s", "ratio", "pairs' median"
        );
        for s in &pairs {
            println!(
                "{:>7} {:>7} {:>18.0} {:>18.0} {:>9.1}% {:>15.1}%",
                s.jt.robots,
                s.jt.threads,
                s.jt.robot_steps_per_s(),
                s.whole_body.robot_steps_per_s(),
                100.0 * s.ratio(),
                100.0 * s.pair_ratio_median,
            );
        }
    }
    if let Some(path) = &a.json {
        let v: Value = json!({
            "model": a.model,
            "sensing": a.sensing.name(),
            "build": build.name(),
            "static_features": build.static_features,
            "steps_per_block": a.steps,
            "repeats": a.repeats,
            "warmup_steps": a.warmup,
            "points": rows.clone(),
        });
        std::fs::write(path, serde_json::to_string_pretty(&v).expect("json") + "\n").map_err(
            |e| CliError::Io {
                path: path.display().to_string(),
                source: e,
            },
        )?;
        println!("wrote {}", path.display());
    }
    let mpc_us = (a.planner == BenchPlanner::Mpc).then(|| mpc_solve_median_us(200));
    if let Some(us) = mpc_us {
        println!(
            "MPC solve (a trot's sequence at 50 Hz, 10 steps, about 60 force variables, ADMM): median {us:.1} µs of 200"
        );
    }
    // The last line: the last configuration as one line of JSON (the issue's
    // keys), with every configuration under `points`.
    let mut last = rows.last().cloned().unwrap_or_else(|| json!({}));
    if let Some(us) = mpc_us {
        last["mpc_solve_median_us"] = json!(us);
    }
    last["sensing"] = json!(a.sensing.name());
    last["build"] = json!(build.name());
    last["points"] = Value::Array(rows);
    println!("{last}");
    Ok(())
}

/// Which build of quadsim the figures are of (docs/performance.md, "The build for the
/// CPU"): both give the same bits, not the same speed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Build {
    /// The SIMD features this binary was compiled to require (`avx2`, `fma`,
    /// `avx512f`, `avx512vl`; empty for baseline x86-64 or another
    /// architecture).
    pub static_features: Vec<&'static str>,
    /// Whether this CPU has what the dispatched passes' AVX2 clones need
    /// (AVX2 and FMA), so that quad16's legs run in SIMD lanes.
    pub lanes_on_this_cpu: bool,
}

impl Build {
    /// This binary's build, on the CPU it runs on.
    pub fn of_this_binary() -> Build {
        let mut static_features = Vec::new();
        for (on, name) in [
            (cfg!(target_feature = "avx2"), "avx2"),
            (cfg!(target_feature = "fma"), "fma"),
            (cfg!(target_feature = "avx512f"), "avx512f"),
            (cfg!(target_feature = "avx512vl"), "avx512vl"),
        ] {
            if on {
                static_features.push(name);
            }
        }
        Build {
            static_features,
            lanes_on_this_cpu: quadsim_engine::kernels::cpu_has_lanes(),
        }
    }

    /// `"cpu"` for a build that requires AVX2 and FMA (such as
    /// `RUSTFLAGS="-C target-cpu=native"` on this machine), else
    /// `"portable"` (the default build, which picks its AVX2 clones at run
    /// time).
    pub fn name(&self) -> &'static str {
        let needs = |f| self.static_features.contains(&f);
        if needs("avx2") && needs("fma") {
            "cpu"
        } else {
            "portable"
        }
    }

    /// One line for the table's header.
    pub fn describe(&self) -> String {
        match self.name() {
            "cpu" => format!(
                "for the CPU (requires {}; the portable build's bits)",
                self.static_features.join(", ")
            ),
            _ => format!(
                "portable ({}; `benches/cpu_build.sh` builds one for this CPU)",
                if self.lanes_on_this_cpu {
                    "AVX2 clones chosen at run time on this CPU"
                } else {
                    "this CPU has no AVX2 and FMA: the scalar paths"
                }
            ),
        }
    }
}
