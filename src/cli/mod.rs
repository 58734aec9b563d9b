//! Command-line interface: `quadsim <command>`.

use clap::{Parser, Subcommand};

pub mod dynamics;
pub mod models;

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
    /// Evaluate dynamics (ABA, RNEA, CRBA, …) on states in the oracle's JSON format.
    Dynamics(dynamics::DynamicsArgs),
    /// List the built-in robots, or one robot's parameters.
    Models(models::ModelsArgs),
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<(), crate::error::CliError> {
    match cli.command {
        Command::Dynamics(a) => dynamics::run(a),
        Command::Models(a) => models::run(a),
    }
}
