//! Studies: batches of runs of one base scenario with some of its values
//! varied (`kind = "sweep"`), as `quadsim sweep` runs them.
//!
//! ```toml
//! format_version = 1
//! kind = "sweep"
//! base = "trot.toml"                  # relative to this file
//! duration_s = 5.0                    # optional override of world.duration_s
//! [sweep]
//! combine = "grid"                    # grid | cycle | random | lhs
//! [vary]                              # paths in the base scenario
//! "robots[0].controller.v_x_mps" = { from = 0.25, to = 0.75, steps = 3 }
//! "world.default_ground" = ["concrete", "grass"]
//! ```
//!
//! The variation syntax is the herds' ([`crate::scenario::vary`]); paths
//! start at the scenario's top level. Variants are numbered from 0 in a
//! fixed order, so a shard (`--shard I/N`: the I-th of N contiguous slices)
//! and a merge of all shards give the same rows as one whole run.

pub mod analysis;
pub mod campaign;
pub mod campaign_output;
pub mod error;
pub mod optimize;
pub mod output;
pub mod sample;
pub mod variant;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

pub use error::StudyError;
pub use sample::SweepSpec;
pub use variant::{VariantResult, run_source, with_values};

use crate::scenario::spans::path_key;
use crate::scenario::vary::{Variation, set_path};
use crate::scenario::{Locator, ScenarioError, parse_scenario};

/// A study file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Must be 1.
    pub format_version: i64,
    /// `sweep` (run by `quadsim sweep`).
    pub kind: String,
    /// Study name (default: the file stem).
    pub name: Option<String>,
    /// The base scenario, relative to the study file.
    pub base: String,
    /// Simulated duration of each run (s), overriding the base's `world.duration_s`.
    pub duration_s: Option<f64>,
    /// How variants are formed.
    #[serde(default)]
    pub sweep: SweepSpec,
    /// Path in the base scenario → variation.
    pub vary: BTreeMap<String, toml::Value>,
    /// Analyses for `report.md` (correlations, load carrying).
    #[serde(default)]
    pub report: analysis::StudyReportSpec,
}

/// A loaded study: the file, its base scenario's text, and its variants.
#[derive(Debug)]
pub struct Study {
    /// The study file.
    pub path: PathBuf,
    /// Its source (hashed so that shards of different studies are not merged).
    pub source: String,
    /// Its name.
    pub name: String,
    /// The parsed file.
    pub file: StudyFile,
    /// The base scenario's path.
    pub base_path: PathBuf,
    /// The base scenario's source.
    pub base_source: String,
    /// Every variant: path → value, in variant order.
    pub variants: Vec<BTreeMap<String, toml::Value>>,
}

pub use crate::scenario::file_kind;

/// A study file's text; an unreadable file is an error naming it.
pub fn read_study_text(path: &Path) -> Result<String, ScenarioError> {
    crate::limits::read_text_capped(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(|e| {
        ScenarioError {
            file: path.to_path_buf(),
            line: 0,
            column: 0,
            key_path: String::new(),
            message: format!("cannot read the study: {e}"),
        }
    })
}

/// A study's base scenario (relative to the study file): its path, its text
/// and its table, checked to be a valid scenario on its own.
pub fn read_base(
    loc: &Locator<'_>,
    study_path: &Path,
    base: &str,
) -> Result<(PathBuf, String, toml::Table), ScenarioError> {
    let base_path = study_path.parent().unwrap_or(Path::new(".")).join(base);
    let base_source =
        crate::limits::read_text_capped(&base_path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(
            |e| {
                loc.at(
                    "base",
                    format!("cannot read the base scenario {}: {e}", base_path.display()),
                )
            },
        )?;
    parse_scenario(&base_path, base_source.clone())?;
    let table: toml::Table = toml::from_str(&base_source).expect("parsed above");
    Ok((base_path, base_source, table))
}

/// Reads a study file and its base scenario, and forms its variants. Errors
/// name the file, line and key path (`vary."robots[0].params.thigh.length_m"`).
pub fn load_study(path: &Path) -> Result<Study, ScenarioError> {
    let src = read_study_text(path)?;
    let loc = Locator { path, src: &src };
    let file: StudyFile =
        toml::from_str(&src).map_err(|e| loc.at_span(e.span(), e.message().trim().to_string()))?;
    if file.format_version != crate::scenario::FORMAT_VERSION {
        return Err(loc.at(
            "format_version",
            format!("must be {}", crate::scenario::FORMAT_VERSION),
        ));
    }
    match file.kind.as_str() {
        "sweep" => {}
        "optimize" => {
            return Err(loc.at(
                "kind",
                "this is an optimisation study: run it with `quadsim optimize`",
            ));
        }
        "campaign" => {
            return Err(loc.at("kind", "this is a campaign: run it with `quadsim campaign`"));
        }
        other => {
            return Err(loc.at(
                "kind",
                format!("unknown study kind '{other}': expected \"sweep\""),
            ));
        }
    }
    if let Some(d) = file.duration_s
        && !(d.is_finite() && d > 0.0)
    {
        return Err(loc.at("duration_s", "must be a positive number of seconds"));
    }
    if file.vary.is_empty() {
        return Err(loc.at("vary", "varies nothing: name at least one path"));
    }
    let (base_path, base_source, base_table) = read_base(&loc, path, &file.base)?;
    let mut vary = Vec::new();
    for (p, v) in &file.vary {
        let kp = format!("vary.{}", path_key(p));
        let var = Variation::parse(v).map_err(|e| loc.at(&kp, format!("'{p}': {e}")))?;
        check_path(&base_path, &base_table, p, &var)
            .map_err(|e| loc.at(&kp, format!("'{p}': {e}")))?;
        vary.push((p.clone(), var));
    }
    for (k, c) in file.report.correlations.iter().enumerate() {
        if !file.vary.contains_key(&c.param) {
            return Err(loc.at(
                &format!("report.correlations[{k}].param"),
                format!("'{}' is not a varied path of this study", c.param),
            ));
        }
        if !["positive", "negative"].contains(&c.expect.as_str()) {
            return Err(loc.at(
                &format!("report.correlations[{k}].expect"),
                "must be \"positive\" or \"negative\"",
            ));
        }
    }
    if let Some(l) = &file.report.load
        && !file.vary.contains_key(&l.payload)
    {
        return Err(loc.at(
            "report.load.payload",
            format!("'{}' is not a varied path of this study", l.payload),
        ));
    }
    let variants = sample::variants(&loc, &file.sweep, &vary)?;
    if let Some(n) = &file.name {
        crate::scenario::validate::name(&loc, "name", n)?;
    }
    let name = file.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| crate::names::safe_file_stem(&s.to_string_lossy()))
            .unwrap_or_else(|| "study".into())
    });
    Ok(Study {
        path: path.to_path_buf(),
        source: src.clone(),
        name,
        file,
        base_path,
        base_source,
        variants,
    })
}

/// A path must be settable in the base, and the base with the path's first
/// value must still be a valid scenario: a typo (`wrld.dt_s`, `robots[3]`
/// in a one-robot file, an unknown controller key) fails before any run.
fn check_path(
    base_path: &Path,
    base: &toml::Table,
    path: &str,
    var: &Variation,
) -> Result<(), String> {
    let mut probe = base.clone();
    let first = match var {
        Variation::Uniform { lo, .. } => toml::Value::Float(*lo),
        v => v.value(0, &mut crate::scenario::vary::draw_rng(0, "", "")),
    };
    set_path(&mut probe, path, first)?;
    let src = toml::to_string(&probe).map_err(|e| e.to_string())?;
    let scn = parse_scenario(base_path, src).map_err(|e| e.message_with_path())?;
    crate::world::build_world(&scn, crate::world::Overrides::default())
        .map_err(|e| e.message_with_path())?;
    Ok(())
}

/// The scenario text of variant `k`: the base with the variant's values set.
pub fn variant_source(study: &Study, k: usize) -> Result<String, StudyError> {
    with_values(&study.base_source, &study.variants[k])
}

/// Runs variant `k` to the end on one thread (errors are recorded, not raised).
pub fn run_variant(study: &Study, k: usize) -> VariantResult {
    let params = study.variants[k].clone();
    let outcome = variant_source(study, k)
        .and_then(|src| run_source(&study.base_path, src, study.file.duration_s));
    VariantResult {
        index: k,
        params,
        outcome,
    }
}
