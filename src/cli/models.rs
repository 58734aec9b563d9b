//! `quadsim models [--params NAME]`.

use clap::Args;

/// Arguments of `quadsim models`.
#[derive(Debug, Args)]
pub struct ModelsArgs {
    /// Print every parameter path of this built-in robot with its default.
    #[arg(long)]
    pub params: Option<String>,
}

/// Runs the command.
pub fn run(_a: ModelsArgs) -> Result<(), crate::error::CliError> {
    Err(crate::error::bad("quadsim models: not implemented yet"))
}
