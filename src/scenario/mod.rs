//! Scenario files: TOML worlds of terrains, robots, controllers and events.
//!
//! [`load_scenario`] parses and validates a file; every error names the file,
//! the line and column, and the key path of the offending value, also for
//! values that fail validation after parsing (see [`ScenarioError`]).

pub mod error;
pub mod format;
pub mod herd;
pub mod push;
pub mod sensing;
pub mod spans;
pub mod validate;
pub mod vary;

use std::path::{Path, PathBuf};

pub use error::{Locator, ScenarioError};
pub use format::{FORMAT_VERSION, ScenarioFile};

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
    if let Some(kind) = file_kind(&src) {
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

/// The top-level `kind` of a TOML file, if it has one (studies do, scenarios do not).
pub fn file_kind(src: &str) -> Option<String> {
    let doc = toml::de::DeTable::parse(src).ok()?;
    doc.get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == "kind")
        .and_then(|(_, v)| match v.get_ref() {
            toml::de::DeValue::String(s) => Some(s.to_string()),
            _ => None,
        })
}
