//! `quadsim dynamics MODEL STATES.json [--fixed-base]`.

use clap::Args;

/// Arguments of `quadsim dynamics`.
#[derive(Debug, Args)]
pub struct DynamicsArgs {
    /// A URDF path or a built-in robot name.
    pub model: String,
    /// States in the format of `oracle.py`.
    pub states: std::path::PathBuf,
    /// Weld the root link to the world instead of a free joint.
    #[arg(long)]
    pub fixed_base: bool,
}

/// Runs the command.
pub fn run(_a: DynamicsArgs) -> Result<(), crate::error::CliError> {
    Err(crate::error::bad("quadsim dynamics: not implemented yet"))
}
