//! One variant of a study: the base scenario with values set at their
//! paths, run to the end on one thread.

use std::collections::BTreeMap;
use std::path::Path;

use super::error::StudyError;
use crate::scenario::parse_scenario;
use crate::scenario::vary::set_path;
use crate::summary::Summary;

/// The base scenario's text with `values` set at their paths.
pub fn with_values(
    base_source: &str,
    values: &BTreeMap<String, toml::Value>,
) -> Result<String, StudyError> {
    let vary = |message: String| StudyError::Vary { message };
    let mut t: toml::Table = toml::from_str(base_source).map_err(|e| vary(e.to_string()))?;
    for (p, v) in values {
        set_path(&mut t, p, v.clone()).map_err(vary)?;
    }
    toml::to_string(&t).map_err(|e| vary(e.to_string()))
}

/// One variant's outcome.
#[derive(Debug, Clone)]
pub struct VariantResult {
    /// Variant number.
    pub index: usize,
    /// Its varied values.
    pub params: BTreeMap<String, toml::Value>,
    /// `summary.json` of the run without `timing`, or the error that stopped it.
    pub outcome: Result<Summary, StudyError>,
}

/// Runs a scenario text (relative paths resolved from `base_path`) to the
/// end on one thread; `summary.json` without `timing`, or the error that
/// stopped it (a divergence is an error).
pub fn run_source(
    base_path: &Path,
    src: String,
    duration_s: Option<f64>,
) -> Result<Summary, StudyError> {
    let scn = parse_scenario(base_path, src)?;
    let mut world = crate::world::build_world(
        &scn,
        crate::world::Overrides {
            duration_s,
            threads: 1,
            ..Default::default()
        },
    )?;
    let mut done = 0;
    while done < world.steps {
        // passes of several steps (the same bits as one step at a time);
        // a divergence is reported at the step it happened
        done += world.sim.run_pass(world.steps - done);
        crate::divergence::check_finite(&world)?;
    }
    Ok(Summary::of_world(&scn, &world, None))
}
