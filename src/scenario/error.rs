//! [`ScenarioError`] and the [`Locator`] that places one at a line, column
//! and key path of a source text.

use std::path::{Path, PathBuf};

use super::spans;

/// An error in a scenario file, located by line, column and key path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}:{line}:{column}: {}{message}", file.display(), if key_path.is_empty() { String::new() } else { format!("{key_path}: ") })]
pub struct ScenarioError {
    /// The scenario file.
    pub file: PathBuf,
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// 1-based column (0 when unknown).
    pub column: usize,
    /// Key path of the value, e.g. `robots[0].controller.kind`.
    pub key_path: String,
    /// What is wrong.
    pub message: String,
}

/// Locates errors in one source text.
#[derive(Debug, Clone, Copy)]
pub struct Locator<'a> {
    /// The file name to report.
    pub path: &'a Path,
    /// The source text.
    pub src: &'a str,
}

impl Locator<'_> {
    /// An error at a key path (its span is looked up in the source).
    pub fn at(&self, key_path: &str, message: impl Into<String>) -> ScenarioError {
        let (line, column) = spans::span_of_path(self.src, key_path)
            .map_or((0, 0), |s| spans::line_col(self.src, s.start));
        ScenarioError {
            file: self.path.to_path_buf(),
            line,
            column,
            key_path: key_path.to_string(),
            message: message.into(),
        }
    }

    /// An error at a byte span (parse errors).
    pub fn at_span(
        &self,
        span: Option<std::ops::Range<usize>>,
        message: impl Into<String>,
    ) -> ScenarioError {
        let (line, column, key_path) = match span {
            Some(s) => {
                let (l, c) = spans::line_col(self.src, s.start);
                (l, c, spans::key_path_at(self.src, s.start))
            }
            None => (0, 0, String::new()),
        };
        ScenarioError {
            file: self.path.to_path_buf(),
            line,
            column,
            key_path,
            message: message.into(),
        }
    }
}
