//! Parameter tables of the built-in robots: specs, validation of overrides and
//! suggestions for mistyped paths.

use thiserror::Error;

/// The values a parameter may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// Finite and `> 0` (actuator limits, joint range).
    Positive,
    /// Finite and `≥ 0` (lengths, radii, masses: zero is degenerate but well defined).
    NonNegative,
    /// Any finite number (mount offsets, angles).
    Finite,
}

impl Domain {
    /// True when `x` lies in the domain.
    pub fn contains(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Domain::Positive => x > 0.0,
                Domain::NonNegative => x >= 0.0,
                Domain::Finite => true,
            }
    }

    /// The domain in words, for error messages.
    pub fn describe(self) -> &'static str {
        match self {
            Domain::Positive => "must be finite and > 0",
            Domain::NonNegative => "must be finite and ≥ 0",
            Domain::Finite => "must be finite",
        }
    }
}

/// One parameter of a built-in robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// Dotted path, `part.quantity_unit` (e.g. `thigh.length_m`).
    pub path: &'static str,
    /// Default value: the study's figure, or a stated assumption.
    pub default: f64,
    /// SI unit (`m`, `kg`, `rad`, `N·m`, `rad/s`).
    pub unit: &'static str,
    /// What the parameter sets and what follows it when it changes.
    pub doc: &'static str,
    /// Admissible values.
    pub domain: Domain,
}

impl ParamSpec {
    /// A table entry.
    pub const fn new(
        path: &'static str,
        default: f64,
        unit: &'static str,
        doc: &'static str,
        domain: Domain,
    ) -> ParamSpec {
        ParamSpec {
            path,
            default,
            unit,
            doc,
            domain,
        }
    }
}

/// A bad parameter override or an unknown robot.
#[derive(Debug, Error, PartialEq)]
pub enum ParamError {
    /// No built-in robot has this name.
    #[error("unknown built-in robot '{name}' (built-ins: {valid})")]
    UnknownRobot {
        /// The name asked for.
        name: String,
        /// The built-in names, comma separated.
        valid: String,
    },
    /// The robot has no parameter at this path.
    #[error("{robot}: unknown parameter '{path}' ({})", suggestion_text(.close))]
    UnknownPath {
        /// Robot name.
        robot: String,
        /// The path given.
        path: String,
        /// Valid paths close to the one given, closest first (all paths when none is close).
        close: Vec<&'static str>,
    },
    /// The value lies outside the parameter's domain.
    #[error("{robot}: parameter '{path}' = {value} is invalid ({})", .domain.describe())]
    OutOfDomain {
        /// Robot name.
        robot: String,
        /// Parameter path.
        path: &'static str,
        /// The value given.
        value: f64,
        /// The admissible values.
        domain: Domain,
    },
    /// The same path was given twice.
    #[error("{robot}: parameter '{path}' is given more than once")]
    Duplicate {
        /// Robot name.
        robot: String,
        /// Parameter path.
        path: &'static str,
    },
}

fn suggestion_text(close: &[&'static str]) -> String {
    format!("did you mean: {}?", close.join(", "))
}

/// Valid paths close to `path` (Jaro–Winkler similarity ≥ 0.8, at most 3,
/// closest first); all paths when none is close.
fn close_paths(specs: &[ParamSpec], path: &str) -> Vec<&'static str> {
    let mut scored: Vec<(f64, &'static str)> = specs
        .iter()
        .map(|s| (strsim::jaro_winkler(path, s.path), s.path))
        .filter(|(score, _)| *score >= 0.8)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    if scored.is_empty() {
        return specs.iter().map(|s| s.path).collect();
    }
    scored.into_iter().take(3).map(|(_, p)| p).collect()
}

/// Resolved parameter values: defaults with the overrides applied.
#[derive(Clone, Debug)]
pub(crate) struct Values {
    specs: &'static [ParamSpec],
    values: Vec<f64>,
    given: Vec<bool>,
}

impl Values {
    /// Applies `overrides` to the defaults of `specs`, checking paths and domains.
    pub(crate) fn resolve(
        robot: &str,
        specs: &'static [ParamSpec],
        overrides: &[(&str, f64)],
    ) -> Result<Values, ParamError> {
        let mut values: Vec<f64> = specs.iter().map(|s| s.default).collect();
        let mut given = vec![false; specs.len()];
        for &(path, value) in overrides {
            let Some(i) = specs.iter().position(|s| s.path == path) else {
                return Err(ParamError::UnknownPath {
                    robot: robot.to_string(),
                    path: path.to_string(),
                    close: close_paths(specs, path),
                });
            };
            let spec = &specs[i];
            if given[i] {
                return Err(ParamError::Duplicate {
                    robot: robot.to_string(),
                    path: spec.path,
                });
            }
            if !spec.domain.contains(value) {
                return Err(ParamError::OutOfDomain {
                    robot: robot.to_string(),
                    path: spec.path,
                    value,
                    domain: spec.domain,
                });
            }
            values[i] = value;
            given[i] = true;
        }
        Ok(Values {
            specs,
            values,
            given,
        })
    }

    fn index(&self, path: &str) -> usize {
        self.specs
            .iter()
            .position(|s| s.path == path)
            .unwrap_or_else(|| panic!("internal: parameter '{path}' missing from the table"))
    }

    /// The value at `path` (a path of the robot's own table).
    pub(crate) fn get(&self, path: &str) -> f64 {
        self.values[self.index(path)]
    }

    /// The value's default.
    pub(crate) fn default_of(&self, path: &str) -> f64 {
        self.specs[self.index(path)].default
    }

    /// The value relative to its default (the scale factor of a size).
    pub(crate) fn ratio(&self, path: &str) -> f64 {
        self.get(path) / self.default_of(path)
    }

    /// A mass that follows its part's size: the value when the user gave it,
    /// else the default scaled by `volume_ratio` (same density as the study's part).
    pub(crate) fn mass_following(&self, path: &str, volume_ratio: f64) -> f64 {
        let i = self.index(path);
        if self.given[i] {
            self.values[i]
        } else {
            self.specs[i].default * volume_ratio
        }
    }
}
