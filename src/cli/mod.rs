//! Command-line interface: `quadsim <command>`.

use clap::{Parser, Subcommand};

pub mod bench;
pub mod campaign;
pub mod dashboard;
pub mod dynamics;
pub mod export;
pub mod models;
pub mod monitor;
pub mod optimize;
pub mod pace;
pub mod replay;
pub mod report;
pub mod run;
pub mod sweep;
pub mod terrain;

/// quadsim: simulate quadruped robots.
#[derive(Debug, Parser)]
#[command(name = "quadsim", version, about, long_about = None)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// quadsim's commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scenario: progress bar, metrics table, `DIR/summary.json`, `log.mcap`, `report.md` and `plots/`.
    Run(run::RunArgs),
    /// Validate a scenario without running it (errors and stability warnings).
    Check(run::CheckArgs),
    /// Print the JSON Schema of the scenario format.
    Schema,
    /// Evaluate dynamics (ABA, RNEA, CRBA, …) on states in the oracle's JSON format.
    Dynamics(dynamics::DynamicsArgs),
    /// List the built-in robots, or one robot's parameters.
    Models(models::ModelsArgs),
    /// Terrain tools: `quadsim terrain export` samples a terrain into a heightmap file.
    Terrain(terrain::TerrainArgs),
    /// Rebuild a run's summary.json, report.md and plots from its log.mcap.
    Report(report::ReportArgs),
    /// Play a log.mcap in the terminal: robot states and moving charts of chosen signals.
    Replay(replay::ReplayArgs),
    /// Export a log.mcap as one CSV per channel (`--csv DIR`).
    Export(export::ExportArgs),
    /// Measure step throughput of herds by robot and thread count, and memory per robot.
    Bench(bench::BenchArgs),
    /// Run a study's variants (`kind = "sweep"`) in parallel, or one shard of them.
    Sweep(sweep::SweepArgs),
    /// Run N perturbed copies of a scenario: fall rate and speed tracking (`campaign.json`, `.csv`, `.md`, plot).
    Campaign(campaign::CampaignArgs),
    /// Join the results of a sweep's shards.
    Merge(sweep::MergeArgs),
    /// Optimise scenario values by CMA-ES (`kind = "optimize"` study files).
    Optimize(optimize::OptimizeArgs),
    /// Watch a running world live (shared memory): `--frames N` prints N plain lines.
    Monitor(monitor::MonitorArgs),
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<(), crate::error::CliError> {
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Check(a) => run::check(a),
        Command::Schema => run::schema(),
        Command::Dynamics(a) => dynamics::run(a),
        Command::Models(a) => models::run(a),
        Command::Terrain(a) => terrain::run(a),
        Command::Report(a) => report::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Export(a) => export::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Sweep(a) => sweep::sweep(a),
        Command::Campaign(a) => campaign::run(a),
        Command::Merge(a) => sweep::merge(a),
        Command::Optimize(a) => optimize::run(a),
        Command::Monitor(a) => monitor::run(a),
    }
}
