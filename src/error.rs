//! The CLI's error type: every failure names the file and the field at fault.

use thiserror::Error;

/// An error reported to the user, with the exit code 2 for bad input, 3 for a
/// broken user limit and 1 otherwise.
#[derive(Debug, Error)]
pub enum CliError {
    /// Input that cannot be used: a file, line or field named in the message.
    #[error("{0}")]
    BadInput(String),
    /// An I/O failure on a named path.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The simulation diverged: the robot, time and quantity are named.
    #[error("{0}")]
    Diverged(String),
    /// The command ran, but its result broke a limit the user set
    /// (`quadsim campaign --max-falls K`).
    #[error("{0}")]
    Threshold(String),
}

impl CliError {
    /// Exit code: 2 for bad input, 3 for a broken user limit, 1 for other failures.
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::BadInput(_) => 2,
            CliError::Threshold(_) => 3,
            CliError::Io { .. } | CliError::Diverged(_) => 1,
        }
    }
}

/// Shorthand for bad-input errors.
pub fn bad(msg: impl Into<String>) -> CliError {
    CliError::BadInput(msg.into())
}
