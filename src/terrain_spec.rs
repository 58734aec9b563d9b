//! Scenario terrain and ground specs to engine terrain patches and materials.
//! Errors name the scenario's key path.

use std::path::Path;

use glam::{DVec2, DVec3};
use quadsim_engine::contact::GroundMaterial;
use quadsim_engine::contact::law::NormalLaw;
use quadsim_engine::terrain::{
    BoxObstacles, BoxSpec, Flat, HeightField, Incline, NoiseKind, Rough, Sinusoid, StairDirection,
    Stairs, SteppingStones, TerrainPatch, TerrainShape, Trench,
};

use crate::heightmap::read_heightmap;
use crate::scenario::format::{GroundSpec, TerrainSpec};
use crate::scenario::validate::as_f64;
use crate::scenario::{Locator, ScenarioError};

/// Default horizontal extent of a terrain (m).
pub const DEFAULT_EXTENT_M: [f64; 2] = [20.0, 20.0];

/// A ground material from a preset name or a custom table.
pub fn ground_material(
    loc: &Locator<'_>,
    path: &str,
    g: &GroundSpec,
) -> Result<GroundMaterial, ScenarioError> {
    match g {
        GroundSpec::Preset(name) => {
            GroundMaterial::preset(name).map_err(|e| loc.at(path, e.to_string()))
        }
        GroundSpec::Custom(c) => {
            let base = GroundMaterial::custom(c.stiffness_n_per_m, c.damping_ns_per_m, c.friction)
                .map_err(|e| loc.at(path, e.to_string()))?;
            let law = match c.law.as_deref().unwrap_or("linear") {
                "linear" => NormalLaw::Linear,
                "hunt_crossley" => NormalLaw::HuntCrossley {
                    exponent: c.exponent.unwrap_or(1.5),
                },
                "hybrid" => NormalLaw::Hybrid {
                    depth0_m: c
                        .hybrid_depth_m
                        .ok_or_else(|| loc.at(path, "law 'hybrid' needs hybrid_depth_m (m)"))?,
                    stiffening: c.hybrid_stiffening.unwrap_or(1.0),
                },
                other => {
                    return Err(loc.at(&format!("{path}.law"), format!("unknown law '{other}'")));
                }
            };
            let m = base
                .with_law(law, c.stiffness_n_per_m, c.damping_ns_per_m)
                .map_err(|e| loc.at(path, e.to_string()))?;
            let kt = c
                .tangential_stiffness_n_per_m
                .unwrap_or(m.tangential_stiffness_npm);
            let bt = c
                .tangential_damping_ns_per_m
                .unwrap_or(m.tangential_damping_nspm);
            m.with_tangential(kt, bt)
                .map_err(|e| loc.at(path, e.to_string()))
        }
    }
}

fn num(t: &TerrainSpec, key: &str) -> Option<f64> {
    t.params.get(key).and_then(as_f64)
}

/// The terrain patch of one `[[terrains]]` entry; `seed` is its own random
/// stream, `base_dir` resolves heightmap files.
pub fn terrain_patch(
    loc: &Locator<'_>,
    p: &str,
    t: &TerrainSpec,
    seed: u64,
    base_dir: &Path,
) -> Result<TerrainPatch, ScenarioError> {
    let e = t.extent_m.unwrap_or(DEFAULT_EXTENT_M);
    let size = DVec2::new(e[0], e[1]);
    let dir = num(t, "direction_deg").unwrap_or(0.0).to_radians();
    let err = |e: quadsim_engine::terrain::TerrainError| loc.at(p, e.to_string());
    let (shape, yaw) = match t.kind.as_str() {
        "flat" => (TerrainShape::Flat(Flat::new(size).map_err(err)?), 0.0),
        "incline" => {
            let slope = num(t, "slope_deg").unwrap_or(0.0).to_radians();
            (
                TerrainShape::Incline(Incline::new(slope, size).map_err(err)?),
                dir,
            )
        }
        "sine" => {
            let a = num(t, "amplitude_m").unwrap_or(0.0);
            let l = num(t, "wavelength_m").unwrap_or(1.0);
            (
                TerrainShape::Sinusoid(Sinusoid::new(a, l, size).map_err(err)?),
                dir,
            )
        }
        "rough" => {
            let a = num(t, "amplitude_m").unwrap_or(0.0);
            let cell = num(t, "cell_m").unwrap_or(0.2);
            let kind = match t
                .params
                .get("noise")
                .and_then(|v| v.as_str())
                .unwrap_or("smooth")
            {
                "uniform" => NoiseKind::UniformCell { cell_m: cell },
                "smooth" => NoiseKind::Perlin {
                    wavelength_m: 4.0 * cell,
                    octaves: 4,
                    persistence: 0.5,
                },
                other => {
                    return Err(loc.at(
                        &format!("{p}.noise"),
                        format!("unknown noise '{other}' (uniform, smooth)"),
                    ));
                }
            };
            (
                TerrainShape::Rough(Rough::new(kind, a, seed, size).map_err(err)?),
                0.0,
            )
        }
        "trench" => {
            let w = num(t, "width_m").unwrap_or(0.1);
            let d = num(t, "depth_m").unwrap_or(0.1);
            (
                TerrainShape::Trench(Trench::new(w, d, size).map_err(err)?),
                dir,
            )
        }
        "stairs" => {
            let direction = match t
                .params
                .get("direction")
                .and_then(|v| v.as_str())
                .unwrap_or("up")
            {
                "up" => StairDirection::Up,
                "down" => StairDirection::Down,
                other => {
                    return Err(loc.at(
                        &format!("{p}.direction"),
                        format!("unknown direction '{other}' (up, down)"),
                    ));
                }
            };
            let steps = t
                .params
                .get("steps")
                .and_then(|v| v.as_integer())
                .unwrap_or(1)
                .max(1) as usize;
            let rise = num(t, "rise_m").unwrap_or(0.1);
            let run = num(t, "run_m").unwrap_or(0.3);
            let stairs = Stairs::new(
                direction,
                rise,
                run,
                steps,
                size.y,
                (size.x - run * steps as f64).max(0.0),
            )
            .map_err(err)?;
            (TerrainShape::Stairs(stairs), 0.0)
        }
        "boxes" => {
            let list = t
                .params
                .get("boxes")
                .and_then(|v| v.as_array())
                .cloned()
                .unwrap_or_default();
            let mut specs = Vec::new();
            for (k, b) in list.iter().enumerate() {
                let bp = format!("{p}.boxes[{k}]");
                let v3 = |key: &str| -> Result<DVec3, ScenarioError> {
                    let a = b
                        .get(key)
                        .and_then(|v| v.as_array())
                        .ok_or_else(|| loc.at(&bp, format!("needs {key} = [x, y, z]")))?;
                    let v: Vec<f64> = a.iter().filter_map(as_f64).collect();
                    if v.len() == 3 {
                        Ok(DVec3::new(v[0], v[1], v[2]))
                    } else {
                        Err(loc.at(&format!("{bp}.{key}"), "needs three numbers"))
                    }
                };
                let yaw = b.get("yaw_deg").and_then(as_f64).unwrap_or(0.0);
                specs.push(BoxSpec {
                    centre_m: v3("center_m")?,
                    size_m: v3("size_m")?,
                    yaw_rad: yaw.to_radians(),
                });
            }
            (
                TerrainShape::Boxes(BoxObstacles::new(specs).map_err(err)?),
                0.0,
            )
        }
        "stepping_stones" => {
            let stone = num(t, "stone_size_m").unwrap_or(0.3);
            let gap = num(t, "gap_m").unwrap_or(0.1);
            let h = num(t, "height_m").unwrap_or(0.1);
            let pitch = stone + gap;
            let cols = ((size.x + gap) / pitch).floor().max(1.0) as usize;
            let rows = ((size.y + gap) / pitch).floor().max(1.0) as usize;
            let stones = SteppingStones::new(cols, rows, DVec2::splat(stone), gap, h, h, 0.0, seed)
                .map_err(err)?;
            (TerrainShape::SteppingStones(stones), 0.0)
        }
        "heightmap" => (
            TerrainShape::HeightField(heightmap_field(loc, p, t, base_dir)?),
            0.0,
        ),
        other => {
            return Err(loc.at(
                &format!("{p}.kind"),
                format!("unknown terrain kind '{other}'"),
            ));
        }
    };
    let material = match &t.ground {
        Some(g) => ground_material(loc, &format!("{p}.ground"), g)?,
        None => GroundMaterial::preset("concrete").expect("preset"),
    };
    TerrainPatch::new(shape, DVec3::from_array(t.origin_m), yaw, material).map_err(err)
}

/// The finest heightmap sample spacing (m).
pub const MIN_HEIGHTMAP_SPACING_M: f64 = 1.0e-4;
/// The coarsest heightmap sample spacing (m).
pub const MAX_HEIGHTMAP_SPACING_M: f64 = 1.0e3;

/// The height field of a `kind = "heightmap"` entry: the file (relative to
/// the scenario's directory, see [`crate::heightmap`] for formats and
/// orientation) sampled every `horizontal_scale_m` along x and y and centred
/// on the terrain's origin, heights `vertical_scale_m` times the file's values
/// (PNG: times `v / (2^bits − 1)`). The file's size sets the extent, so an
/// `extent_m` that disagrees with it is an error.
fn heightmap_field(
    loc: &Locator<'_>,
    p: &str,
    t: &TerrainSpec,
    base_dir: &Path,
) -> Result<HeightField, ScenarioError> {
    let file = t
        .params
        .get("file")
        .and_then(|v| v.as_str())
        .ok_or_else(|| loc.at(p, "terrain kind 'heightmap' needs the key 'file'"))?;
    let spacing = num(t, "horizontal_scale_m")
        .ok_or_else(|| loc.at(p, "terrain kind 'heightmap' needs 'horizontal_scale_m'"))?;
    let vertical = num(t, "vertical_scale_m")
        .ok_or_else(|| loc.at(p, "terrain kind 'heightmap' needs 'vertical_scale_m'"))?;
    if !(MIN_HEIGHTMAP_SPACING_M..=MAX_HEIGHTMAP_SPACING_M).contains(&spacing) {
        return Err(loc.at(
            &format!("{p}.horizontal_scale_m"),
            format!(
                "{spacing:e} m is outside [{MIN_HEIGHTMAP_SPACING_M}, {MAX_HEIGHTMAP_SPACING_M}] m"
            ),
        ));
    }
    let path = base_dir.join(file);
    let grid = read_heightmap(&path).map_err(|e| loc.at(&format!("{p}.file"), e.to_string()))?;
    // every height (the file's values times the vertical scale) within bounds
    let max_abs = grid.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let top = max_abs * vertical;
    if !(top.is_finite() && top <= crate::scenario::validate::MAX_WORLD_M) {
        return Err(loc.at(
            &format!("{p}.file"),
            format!(
                "heights up to {top:e} m (the file's largest |value| {max_abs:e} × vertical_scale_m {vertical:e}) \
             are beyond ±{:e} m",
                crate::scenario::validate::MAX_WORLD_M
            ),
        ));
    }
    let size = [
        (grid.nx - 1) as f64 * spacing,
        (grid.ny - 1) as f64 * spacing,
    ];
    if let Some(e) = t.extent_m
        && (0..2).any(|k| (e[k] - size[k]).abs() > 1e-6 * size[k].max(1.0))
    {
        return Err(loc.at(
            &format!("{p}.extent_m"),
            format!(
                "a heightmap's extent is set by its file: {} × {} samples every {spacing} m \
                 span [{}, {}] m, not [{}, {}] m; remove extent_m or make it [{}, {}]",
                grid.nx, grid.ny, size[0], size[1], e[0], e[1], size[0], size[1]
            ),
        ));
    }
    HeightField::new(
        grid.nx,
        grid.ny,
        DVec2::splat(spacing),
        vertical,
        &grid.values,
    )
    .map_err(|e| loc.at(p, e.to_string()))
}
