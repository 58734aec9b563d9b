//! Herds: many robots from one template (`[[herds]]`), expanded into
//! ordinary robot entries before validation.
//!
//! ```toml
//! [[herds]]
//! name = "trot"                 # robots trot-000, trot-001, …
//! count = 100
//! layout = { kind = "lanes", terrains = ["flat", "sine", "rough"], spacing_m = [2.5, 0.0] }
//! [herds.robot]                 # a [[robots]] entry without `name`
//! model = "quad16"
//! [herds.robot.controller]
//! kind = "vmc"
//! [herds.vary]                  # per-robot values, by path in the template
//! "model" = ["quad16", "quad12"]
//! "controller.v_x_mps" = { from = 0.3, to = 0.6, steps = 4 }
//! ```
//!
//! Robot `k` of a herd takes value `k mod len` of each list or range
//! (`combine = "cycle"`, the default), or entry `k` of the Cartesian product
//! of all of them (`combine = "grid"`, paths in alphabetical order, the
//! first varying slowest; `count` defaults to the product's size). Random draws derive from `(world.seed, robot name, path)`: the
//! herd's design is part of the file, so `--seed` does not change it.

use serde::Deserialize;

use super::error::{Locator, ScenarioError};
use super::format::{HerdLayout, HerdSpec, RobotSpec, ScenarioFile};
use super::spans::path_key;
use super::vary::{Variation, draw_rng, set_path};

/// The most robots a scenario may hold, herds included (scenarios/README.md).
/// `quadsim check` of 10,000 trotting quad16 takes some 7 s and 1 GB.
pub const MAX_ROBOTS: usize = 10_000;

/// Appends every herd's robots to `file.robots`, recording for each the key
/// path that errors about it should name.
pub fn expand(loc: &Locator<'_>, file: &mut ScenarioFile) -> Result<(), ScenarioError> {
    file.robot_key_paths = (0..file.robots.len())
        .map(|i| format!("robots[{i}]"))
        .collect();
    let seed = file.world.seed;
    // The limit holds for the whole file, checked before anything is expanded.
    let mut total = file.robots.len();
    if total > MAX_ROBOTS {
        return Err(loc.at(
            "robots",
            format!("{total} robots, beyond the {MAX_ROBOTS} a scenario may hold"),
        ));
    }
    for (h, herd) in file.herds.iter().enumerate() {
        total = total.saturating_add(herd.count.unwrap_or(0));
        if total > MAX_ROBOTS {
            return Err(loc.at(
                &format!("herds[{h}].count"),
                format!(
                    "the scenario would hold {total} robots or more, beyond the {MAX_ROBOTS} a scenario may hold"
                ),
            ));
        }
    }
    for (h, herd) in file.herds.iter().enumerate() {
        let hp = format!("herds[{h}]");
        for r in expand_one(loc, &hp, herd, seed, &file.terrains)? {
            file.robots.push(r);
            file.robot_key_paths.push(format!("{hp}.robot"));
        }
        if file.robots.len() > MAX_ROBOTS {
            return Err(loc.at(
                &format!("{hp}.count"),
                format!(
                    "the scenario holds {} robots, beyond the {MAX_ROBOTS} a scenario may hold",
                    file.robots.len()
                ),
            ));
        }
    }
    Ok(())
}

/// Points an error about a herd robot's varied value at its `vary` entry
/// (`herds[0].vary."controller.v_x_mps"`) rather than at the template.
pub fn relocate(loc: &Locator<'_>, file: &ScenarioFile, e: ScenarioError) -> ScenarioError {
    for (h, herd) in file.herds.iter().enumerate() {
        let prefix = format!("herds[{h}].robot.");
        let Some(rest) = e.key_path.strip_prefix(&prefix) else {
            continue;
        };
        let rest = rest.replace('"', "");
        if let Some(path) = herd.vary.keys().find(|p| **p == rest) {
            return loc.at(&format!("herds[{h}].vary.{}", path_key(path)), e.message);
        }
    }
    e
}

fn expand_one(
    loc: &Locator<'_>,
    hp: &str,
    herd: &HerdSpec,
    seed: u64,
    terrains: &[super::format::TerrainSpec],
) -> Result<Vec<RobotSpec>, ScenarioError> {
    super::validate::name(loc, &format!("{hp}.name"), &herd.name)?;
    if herd.robot.contains_key("name") {
        return Err(loc.at(
            &format!("{hp}.robot.name"),
            format!(
                "herd robots are named from the herd: '{}-000', '{}-001', …",
                herd.name, herd.name
            ),
        ));
    }
    let mut vary = Vec::new();
    for (path, v) in &herd.vary {
        let kp = format!("{hp}.vary.{}", path_key(path));
        if path == "name" || path.starts_with("name.") {
            return Err(loc.at(&kp, "the name cannot vary"));
        }
        let var = Variation::parse(v).map_err(|e| loc.at(&kp, format!("'{path}': {e}")))?;
        // Try the path on the template, so that a typo fails here, named.
        let mut probe = herd.robot.clone();
        set_path(&mut probe, path, toml::Value::Float(0.0))
            .map_err(|e| loc.at(&kp, format!("'{path}': {e}")))?;
        vary.push((path.clone(), kp, var));
    }
    let product: Option<usize> = vary.iter().try_fold(1usize, |acc, (_, _, v)| {
        v.count().map(|n| acc.saturating_mul(n))
    });
    let grid = match herd.combine.as_deref().unwrap_or("cycle") {
        "cycle" => false,
        "grid" => true,
        other => {
            return Err(loc.at(
                &format!("{hp}.combine"),
                format!("unknown combine '{other}': expected \"cycle\" or \"grid\""),
            ));
        }
    };
    let count = match (herd.count, grid, product) {
        (Some(0), ..) => return Err(loc.at(&format!("{hp}.count"), "must be at least 1")),
        (Some(n), ..) => n,
        (None, true, Some(n)) => n,
        (None, true, None) => {
            return Err(loc.at(
                &format!("{hp}.count"),
                "a grid with random draws needs a `count`",
            ));
        }
        (None, false, _) => {
            return Err(loc.at(&format!("{hp}.count"), "missing: how many robots?"));
        }
    };
    if count > MAX_ROBOTS {
        return Err(loc.at(
            &format!("{hp}.count"),
            format!("{count} robots is more than the {MAX_ROBOTS} a scenario may hold"),
        ));
    }
    let width = count.saturating_sub(1).to_string().len().max(3);
    if herd.name.len() + 1 + width > crate::names::NAME_MAX_CHARS {
        return Err(loc.at(
            &format!("{hp}.name"),
            format!(
                "'{}' is too long for its robots' names ('{}-{:0width$}' has more than {} characters)",
                herd.name,
                herd.name,
                0,
                crate::names::NAME_MAX_CHARS
            ),
        ));
    }
    let positions = layout(loc, hp, &herd.layout, count, terrains)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let name = format!("{}-{k:0width$}", herd.name);
        let mut t = herd.robot.clone();
        t.insert("name".into(), toml::Value::String(name.clone()));
        // Grid: mixed-radix digits of k, the first path varying slowest.
        let mut rest = k;
        let mut digits = vec![0usize; vary.len()];
        if grid {
            for (d, (_, _, v)) in digits.iter_mut().zip(&vary).rev() {
                let n = v.count().unwrap_or(1);
                *d = rest % n;
                rest /= n;
            }
        }
        for (j, (path, kp, v)) in vary.iter().enumerate() {
            let idx = if grid { digits[j] } else { k };
            let value = v.value(idx, &mut draw_rng(seed, &name, path));
            set_path(&mut t, path, value).map_err(|e| loc.at(kp, format!("'{path}': {e}")))?;
        }
        let (xy, terrain) = &positions[k];
        if !t.contains_key("start_position_m") {
            t.insert(
                "start_xy_m".into(),
                toml::Value::Array(vec![toml::Value::Float(xy[0]), toml::Value::Float(xy[1])]),
            );
        }
        if let Some(tn) = terrain {
            t.insert("terrain".into(), toml::Value::String(tn.clone()));
        }
        let r = RobotSpec::deserialize(toml::Value::Table(t)).map_err(|e| {
            loc.at(
                &format!("{hp}.robot"),
                format!("robot '{name}': {}", e.message().trim()),
            )
        })?;
        out.push(r);
    }
    Ok(out)
}

/// Horizontal start positions (relative to the lane's terrain origin, if any) and terrains.
#[allow(clippy::type_complexity)]
fn layout(
    loc: &Locator<'_>,
    hp: &str,
    l: &HerdLayout,
    count: usize,
    terrains: &[super::format::TerrainSpec],
) -> Result<Vec<([f64; 2], Option<String>)>, ScenarioError> {
    let lp = format!("{hp}.layout");
    let origin = l.origin_m.unwrap_or([0.0, 0.0]);
    let lanes = l.kind.as_deref() == Some("lanes");
    // Grid: 2 m between rows (x) and columns (y); lanes: 2 m along the lane.
    let spacing = l
        .spacing_m
        .unwrap_or(if lanes { [2.0, 0.0] } else { [2.0, 2.0] });
    if spacing.iter().any(|s| !s.is_finite() || *s < 0.0) || origin.iter().any(|o| !o.is_finite()) {
        return Err(loc.at(&lp, "spacing_m and origin_m must be finite (spacing ≥ 0)"));
    }
    match l.kind.as_deref().unwrap_or("grid") {
        "grid" => {
            if l.terrains.is_some() {
                return Err(loc.at(
                    &format!("{lp}.terrains"),
                    "terrains belong to a \"lanes\" layout; a grid uses the template's `terrain`",
                ));
            }
            let cols = match l.columns {
                Some(0) => return Err(loc.at(&format!("{lp}.columns"), "must be at least 1")),
                Some(c) => c,
                None => (count as f64).sqrt().ceil() as usize,
            };
            Ok((0..count)
                .map(|k| {
                    let (row, col) = (k / cols, k % cols);
                    (
                        [
                            origin[0] + row as f64 * spacing[0],
                            origin[1] + col as f64 * spacing[1],
                        ],
                        None,
                    )
                })
                .collect())
        }
        "lanes" => {
            if l.columns.is_some() {
                return Err(loc.at(
                    &format!("{lp}.columns"),
                    "columns belong to a \"grid\" layout; lanes take `terrains`",
                ));
            }
            let names = l.terrains.clone().unwrap_or_default();
            if names.is_empty() {
                return Err(loc.at(
                    &format!("{lp}.terrains"),
                    "a \"lanes\" layout needs one terrain name per lane",
                ));
            }
            for (j, n) in names.iter().enumerate() {
                if !terrains.iter().any(|t| &t.name == n) {
                    return Err(loc.at(
                        &format!("{lp}.terrains[{j}]"),
                        format!("no terrain named '{n}'"),
                    ));
                }
            }
            let lanes = names.len();
            Ok((0..count)
                .map(|k| {
                    let (lane, slot) = (k % lanes, k / lanes);
                    (
                        [
                            origin[0] + slot as f64 * spacing[0],
                            origin[1] + slot as f64 * spacing[1],
                        ],
                        Some(names[lane].clone()),
                    )
                })
                .collect())
        }
        other => Err(loc.at(
            &format!("{lp}.kind"),
            format!("unknown layout '{other}': expected \"grid\" or \"lanes\""),
        )),
    }
}
