//! [`StudyError`]: why one variant of a study (a sweep's or an
//! optimisation's candidate) produced no summary.

use crate::error::RunError;
use crate::scenario::ScenarioError;

/// A variant that did not run to the end. Recorded in the study's results
/// (`results.json`'s `error`, `optimize.json`), never raised: the other
/// variants go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StudyError {
    /// The variant's scenario is invalid: the key path and what is wrong
    /// (the variant's generated text has no line worth naming).
    #[error("{}", .0.message_with_path())]
    Scenario(ScenarioError),
    /// A varied value could not be set at its path in the base scenario.
    #[error("{message}")]
    Vary {
        /// What failed, naming the path.
        message: String,
    },
    /// A robot diverged.
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
    /// Any other failure of the run, as its message.
    #[error("{0}")]
    Run(String),
}

impl From<ScenarioError> for StudyError {
    fn from(e: ScenarioError) -> Self {
        StudyError::Scenario(e)
    }
}

impl From<RunError> for StudyError {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Scenario(e) => StudyError::Scenario(e),
            RunError::Diverged {
                robot,
                t_s,
                what,
                cause,
            } => StudyError::Diverged {
                robot,
                t_s,
                what,
                cause,
            },
            e @ RunError::Io { .. } => StudyError::Run(e.to_string()),
        }
    }
}

impl ScenarioError {
    /// `key path: message` (the variant's scenario text has no useful line).
    pub fn message_with_path(&self) -> String {
        if self.key_path.is_empty() {
            self.message.clone()
        } else {
            format!("{}: {}", self.key_path, self.message)
        }
    }
}
