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

/// A run that could not be built or did not finish: the scenario error
/// names file, line and key path; a divergence the robot, time and quantity.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scenario is invalid (file, line, column and key path).
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// A robot's state left the finite, physical range.
    #[error("robot '{robot}' diverged at t = {t_s:.4} s: {what} ({cause})")]
    Diverged {
        /// The robot.
        robot: String,
        /// Simulated time (s).
        t_s: f64,
        /// The coordinate or contact that diverged.
        what: String,
        /// The likely cause from the numbers.
        cause: String,
    },
    /// An I/O failure on a named path.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
}

impl From<RunError> for CliError {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Scenario(e) => CliError::BadInput(e.to_string()),
            e @ RunError::Diverged { .. } => CliError::Diverged(e.to_string()),
            RunError::Io { path, source } => CliError::Io { path, source },
        }
    }
}
