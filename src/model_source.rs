//! Resolves a MODEL argument: a built-in robot's name or the path of a URDF file.

use std::path::Path;

use quadsim_engine::description::RobotDescription;

use crate::error::{CliError, bad};
use crate::urdf::{UrdfOptions, load_urdf};

/// Loads `spec`: a path to a `.urdf` file, or a built-in robot's name
/// ([`quadsim_engine::robots::builtin`]). URDF warnings go to stderr.
///
/// # Errors
/// [`CliError::BadInput`] naming the file and field, or the unknown name.
pub fn load_model(spec: &str, opts: &UrdfOptions) -> Result<RobotDescription, CliError> {
    let (desc, warnings) = load_model_with_warnings(spec, opts)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    Ok(desc)
}

/// As [`load_model`], returning the URDF import's warnings instead of printing them.
///
/// A spec that names an existing file, ends in `.urdf` or contains a path
/// separator is a URDF path; anything else is looked up among the built-ins.
///
/// # Errors
/// As [`load_model`].
pub fn load_model_with_warnings(
    spec: &str,
    opts: &UrdfOptions,
) -> Result<(RobotDescription, Vec<String>), CliError> {
    let path = Path::new(spec);
    let looks_like_path = path.is_file()
        || spec.to_ascii_lowercase().ends_with(".urdf")
        || spec.contains('/')
        || spec.contains(std::path::MAIN_SEPARATOR);
    if looks_like_path {
        let robot = load_urdf(path, opts).map_err(|e| bad(e.to_string()))?;
        return Ok((robot.description, robot.warnings));
    }
    match quadsim_engine::robots::builtin(spec) {
        Some(desc) => Ok((desc, Vec::new())),
        None => Err(bad(format!(
            "model '{spec}': not a URDF file and not a built-in robot ({})",
            quadsim_engine::robots::builtin_names().join(", ")
        ))),
    }
}
