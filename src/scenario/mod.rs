//! Scenario files: TOML worlds of terrains, robots, controllers and events.
//!
//! [`load_scenario`] parses and validates a file; every error names the file,
//! the line and column, and the key path of the offending value, also for
//! values that fail validation after parsing (see [`ScenarioError`]).

pub mod format;
pub mod herd;
pub mod sensing;
pub mod spans;
pub mod validate;
pub mod vary;

use std::path::{Path, PathBuf};

pub use format::{FORMAT_VERSION, ScenarioFile};

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

/// A parsed, validated scenario with its source text.
#[derive(Debug)]
pub struct Scenario {
    /// The file it came from.
    pub path: PathBuf,
    /// Its source text (hashed into `summary.json`).
    pub source: String,
    /// The scenario name: `world.name`, else the file stem.
    pub name: String,
    /// The parsed contents.
    pub file: ScenarioFile,
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

/// Reads, parses and validates a scenario file.
pub fn load_scenario(path: &Path) -> Result<Scenario, ScenarioError> {
    let src =
        crate::limits::read_text_capped(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(|e| {
            ScenarioError {
                file: path.to_path_buf(),
                line: 0,
                column: 0,
                key_path: String::new(),
                message: format!("cannot read the scenario: {e}"),
            }
        })?;
    parse_scenario(path, src)
}

/// Parses and validates scenario text (`path` names it in errors and resolves relative paths).
pub fn parse_scenario(path: &Path, src: String) -> Result<Scenario, ScenarioError> {
    let loc = Locator { path, src: &src };
    if let Some(kind) = crate::study::file_kind(&src) {
        return Err(loc.at(
            "kind",
            format!(
                "this is a study file (kind = \"{kind}\"), not a scenario: run it with `quadsim {} {}`",
                match kind.as_str() {
                    "optimize" => "optimize",
                    "campaign" => "campaign",
                    _ => "sweep",
                },
                path.display()
            ),
        ));
    }
    check_format_version(&loc)?;
    let mut file: ScenarioFile =
        toml::from_str(&src).map_err(|e| loc.at_span(e.span(), e.message().trim().to_string()))?;
    herd::expand(&loc, &mut file)?;
    validate::validate(&loc, &file).map_err(|e| herd::relocate(&loc, &file, e))?;
    // world.name was checked; a file stem is made safe to name a directory
    let name = file.world.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| crate::names::safe_file_stem(&s.to_string_lossy()))
            .unwrap_or_else(|| "scenario".into())
    });
    Ok(Scenario {
        path: path.to_path_buf(),
        source: src,
        name,
        file,
    })
}

/// The version is checked before anything else, so that a file written for a
/// future quadsim gets a migration message rather than an unknown-key error.
fn check_format_version(loc: &Locator<'_>) -> Result<(), ScenarioError> {
    let doc = match toml::de::DeTable::parse(loc.src) {
        Ok(d) => d,
        Err(e) => return Err(loc.at_span(e.span(), e.message().trim().to_string())),
    };
    let Some((_, v)) = doc
        .get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == "format_version")
    else {
        return Err(loc.at_span(
            Some(0..0),
            format!("missing `format_version = {FORMAT_VERSION}` at the top of the file"),
        ));
    };
    let version = match v.get_ref() {
        toml::de::DeValue::Integer(i) => i.as_str().parse::<i64>().ok(),
        _ => None,
    };
    match version {
        Some(FORMAT_VERSION) => Ok(()),
        Some(n) if n > FORMAT_VERSION => Err(loc.at(
            "format_version",
            format!(
                "this file is format version {n}, but this quadsim ({}) reads version {FORMAT_VERSION}: \
                 upgrade quadsim, or rewrite the file for version {FORMAT_VERSION} (see scenarios/README.md, \"Versions\")",
                env!("CARGO_PKG_VERSION")
            ),
        )),
        _ => Err(loc.at("format_version", format!("must be the integer {FORMAT_VERSION}"))),
    }
}
