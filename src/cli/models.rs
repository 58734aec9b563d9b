//! `quadsim models [--params NAME]`: the built-in robots, or one robot's
//! parameter table (path, default, unit, meaning).

use crate::error::{CliError, bad};
use clap::Args;
use quadsim_engine::robots;

/// Arguments of `quadsim models`.
#[derive(Debug, Args)]
pub struct ModelsArgs {
    /// Print every parameter path of this built-in robot with its default.
    #[arg(long)]
    pub params: Option<String>,
}

/// Runs the command: prints the table to stdout.
pub fn run(a: ModelsArgs) -> Result<(), CliError> {
    print!("{}", render(&a)?);
    Ok(())
}

/// The command's output.
///
/// # Errors
/// [`CliError::BadInput`] for an unknown robot name, listing the valid names.
pub fn render(a: &ModelsArgs) -> Result<String, CliError> {
    match &a.params {
        None => Ok(list_robots()),
        Some(name) => param_table(name),
    }
}

/// Left-aligned columns separated by two spaces; columns listed in `right` are
/// right-aligned (numbers).
fn table(rows: &[Vec<String>], right: &[usize]) -> String {
    let ncol = rows.iter().map(Vec::len).max().unwrap_or(0);
    let width: Vec<usize> = (0..ncol)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for r in rows {
        let cells: Vec<String> = r
            .iter()
            .enumerate()
            .map(|(c, s)| {
                if right.contains(&c) {
                    format!("{s:>w$}", w = width[c])
                } else {
                    format!("{s:<w$}", w = width[c])
                }
            })
            .collect();
        out.push_str(cells.join("  ").trim_end());
        out.push('\n');
    }
    out
}

fn list_robots() -> String {
    let mut rows = vec![vec![
        "name".to_string(),
        "DOF".to_string(),
        "mass (kg)".to_string(),
        "stance height (m)".to_string(),
        "parameters".to_string(),
    ]];
    for &name in robots::builtin_names() {
        let d = robots::builtin(name).expect("built-in names build");
        let height = robots::nominal_base_height_m(name)
            .map_or_else(|| "-".to_string(), |h| format!("{h:.4}"));
        let nparams = robots::params(name).map_or(0, <[_]>::len);
        rows.push(vec![
            name.to_string(),
            d.dof().to_string(),
            format!("{:.3}", d.total_mass_kg()),
            height,
            nparams.to_string(),
        ]);
    }
    table(&rows, &[1, 2, 3, 4])
}

fn param_table(name: &str) -> Result<String, CliError> {
    let specs = robots::params(name).ok_or_else(|| {
        bad(format!(
            "quadsim models --params: unknown built-in robot '{name}' (built-ins: {})",
            robots::builtin_names().join(", ")
        ))
    })?;
    let mut rows = vec![vec![
        "path".to_string(),
        "default".to_string(),
        "unit".to_string(),
        "meaning".to_string(),
    ]];
    for s in specs {
        rows.push(vec![
            s.path.to_string(),
            s.default.to_string(),
            s.unit.to_string(),
            s.doc.to_string(),
        ]);
    }
    Ok(table(&rows, &[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(params: Option<&str>) -> ModelsArgs {
        ModelsArgs {
            params: params.map(str::to_string),
        }
    }

    #[test]
    fn lists_every_builtin_with_dof_and_mass() {
        let out = render(&args(None)).unwrap();
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 1 + robots::builtin_names().len());
        for &name in robots::builtin_names() {
            let line = lines.iter().find(|l| l.starts_with(name)).unwrap();
            let cols: Vec<&str> = line.split_whitespace().collect();
            let d = robots::builtin(name).unwrap();
            assert_eq!(cols[1].parse::<usize>().unwrap(), d.dof());
            let mass: f64 = cols[2].parse().unwrap();
            assert!((mass - d.total_mass_kg()).abs() < 1e-3);
        }
        // the last column is right-aligned: every line ends in the same column
        let ends: Vec<usize> = lines.iter().map(|l| l.chars().count()).collect();
        assert!(ends.windows(2).all(|w| w[0] == w[1]), "{out}");
    }

    #[test]
    fn params_lists_every_path_with_its_default() {
        for &name in robots::builtin_names() {
            let out = render(&args(Some(name))).unwrap();
            let specs = robots::params(name).unwrap();
            assert_eq!(out.lines().count(), 1 + specs.len());
            for (line, s) in out.lines().skip(1).zip(specs) {
                let cols: Vec<&str> = line.split_whitespace().collect();
                assert_eq!(cols[0], s.path);
                assert_eq!(cols[1].parse::<f64>().unwrap(), s.default);
                assert_eq!(cols[2], s.unit);
                assert!(line.ends_with(s.doc));
            }
        }
    }

    #[test]
    fn unknown_robot_is_bad_input_naming_the_valid_ones() {
        let err = render(&args(Some("quad8"))).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        let msg = err.to_string();
        assert!(msg.contains("quad8"), "{msg}");
        for &name in robots::builtin_names() {
            assert!(msg.contains(name), "{msg}");
        }
    }
}
