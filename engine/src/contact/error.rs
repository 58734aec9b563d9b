//! What can be wrong with a ground material or a contact point.

use thiserror::Error;

/// Errors in contact parameters.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ContactError {
    /// A ground preset name that does not exist.
    #[error("unknown ground preset '{0}' (known: concrete, grass, mud, sand)")]
    UnknownPreset(String),
    /// A number out of its domain.
    #[error("ground material: field '{field}' = {value} is invalid ({why})")]
    InvalidValue {
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
        /// What is wrong.
        why: &'static str,
    },
    /// A contact point on a body the model does not have, or a bad radius.
    #[error("contact point {index}: {why}")]
    InvalidPoint {
        /// Index of the point.
        index: usize,
        /// What is wrong.
        why: String,
    },
}
