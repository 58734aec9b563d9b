//! `quadsim terrain export`: samples one terrain of a scenario on a grid and
//! writes it as a heightmap file, then prints the `[[terrains]]` entry that
//! re-imports it, so any terrain (analytic ones included) round-trips through
//! a file.
//!
//! Grid: world axes, every `--resolution-m` along x and y, centred on the
//! centre of the terrain's footprint (its world-axis bounding box, so a yawed
//! terrain is exported as seen in the world and the entry needs no yaw). The
//! grid stays inside the footprint: `n = ⌊size / R⌋ + 1` samples per axis.
//! Where the terrain has no ground (between boxes or stepping stones, the
//! corners of a yawed footprint) the sample takes the world's
//! `default_ground_height_m` when the world has a default ground, else the
//! lowest sampled height; the count of such samples is printed.
//!
//! Heights: a 16-bit PNG stores `round((h − min) / (max − min) · 65535)` with
//! `origin_m.z = min` and `vertical_scale_m = max − min` (1 for a flat
//! terrain), so a re-imported sample is within half a step `(max − min) /
//! 65535` of the original. A CSV file stores world heights in metres in
//! Rust's shortest round-trip form with `origin_m.z = 0` and
//! `vertical_scale_m = 1`: exact at the samples. The entry is printed on
//! stdout (and repeated as `#` comment lines at the top of a CSV file);
//! nothing else is written beside the heightmap.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use glam::{DVec2, DVec3};
use quadsim_engine::terrain::{Terrain as _, TerrainPatch};

use crate::error::{CliError, bad};
use crate::heightmap::{HeightmapFormat, MAX_SAMPLES_PER_AXIS, write_csv, write_png16};
use crate::scenario::format::GroundSpec;
use crate::scenario::{Locator, load_scenario};
use crate::terrain_spec::terrain_patch;
use crate::world::stream_seed;

/// Default grid spacing of `quadsim terrain export` (m).
pub const DEFAULT_RESOLUTION_M: f64 = 0.05;

/// Arguments of `quadsim terrain`.
#[derive(Debug, Args)]
pub struct TerrainArgs {
    /// The terrain command.
    #[command(subcommand)]
    pub command: TerrainCommand,
}

/// `quadsim terrain` commands.
#[derive(Debug, Subcommand)]
pub enum TerrainCommand {
    /// Sample a scenario's terrain into a heightmap (16-bit PNG or CSV) and
    /// print the `[[terrains]]` entry that re-imports it.
    Export(ExportArgs),
}

/// Arguments of `quadsim terrain export`.
#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    /// The scenario file (TOML).
    pub scenario: PathBuf,
    /// Name of the terrain to export.
    #[arg(long)]
    pub terrain: String,
    /// Output file: `.png` (16-bit greyscale) or `.csv` (metres).
    #[arg(long)]
    pub out: PathBuf,
    /// Grid spacing along x and y (m).
    #[arg(long, default_value_t = DEFAULT_RESOLUTION_M)]
    pub resolution_m: f64,
}

/// What `quadsim terrain export` wrote.
#[derive(Debug, Clone)]
pub struct Export {
    /// Samples along x and y.
    pub nx: usize,
    /// Samples along y.
    pub ny: usize,
    /// Grid spacing (m).
    pub spacing_m: f64,
    /// `origin_m` of the re-importing entry: the grid centre (m, world) and the
    /// height offset.
    pub origin_m: DVec3,
    /// `vertical_scale_m` of the re-importing entry.
    pub vertical_scale_m: f64,
    /// The sampled world heights (m), row-major by increasing y.
    pub heights_m: Vec<f64>,
    /// Samples where the terrain has no ground (filled, see the module docs).
    pub filled: usize,
    /// The `[[terrains]]` entry that re-imports the file.
    pub snippet: String,
}

/// Runs `quadsim terrain`.
pub fn run(a: TerrainArgs) -> Result<(), CliError> {
    match a.command {
        TerrainCommand::Export(e) => {
            let out = export(&e)?;
            print!("{}", out.snippet);
            Ok(())
        }
    }
}

/// World-axis bounding box `[min, max]` of a patch's footprint (m).
fn footprint(patch: &TerrainPatch) -> (DVec2, DVec2) {
    let b = patch.shape().local_bounds();
    let (c, s) = (patch.yaw_rad().cos(), patch.yaw_rad().sin());
    let o = patch.origin_m().truncate();
    let mut lo = DVec2::INFINITY;
    let mut hi = DVec2::NEG_INFINITY;
    for (x, y) in [
        (b.min.x, b.min.y),
        (b.max.x, b.min.y),
        (b.min.x, b.max.y),
        (b.max.x, b.max.y),
    ] {
        let w = o + DVec2::new(c * x - s * y, s * x + c * y);
        lo = lo.min(w);
        hi = hi.max(w);
    }
    (lo, hi)
}

/// Samples the terrain, writes the file and returns what was written.
pub fn export(a: &ExportArgs) -> Result<Export, CliError> {
    let r = a.resolution_m;
    if !(r.is_finite() && r > 0.0) {
        return Err(bad(format!(
            "--resolution-m: must be a finite spacing > 0 (m), got {r}"
        )));
    }
    let format = HeightmapFormat::of(&a.out).ok_or_else(|| {
        bad(format!(
            "--out {}: the file must end in .png (16-bit greyscale) or .csv",
            a.out.display()
        ))
    })?;
    let scn = load_scenario(&a.scenario).map_err(|e| bad(e.to_string()))?;
    let f = &scn.file;
    let Some(i) = f.terrains.iter().position(|t| t.name == a.terrain) else {
        let names: Vec<&str> = f.terrains.iter().map(|t| t.name.as_str()).collect();
        return Err(bad(format!(
            "--terrain: {} has no terrain '{}' (terrains: {})",
            a.scenario.display(),
            a.terrain,
            if names.is_empty() {
                "none defined".to_string()
            } else {
                names.join(", ")
            }
        )));
    };
    let t = &f.terrains[i];
    let loc = Locator {
        path: &scn.path,
        src: &scn.source,
    };
    let base_dir = scn.path.parent().unwrap_or(Path::new("."));
    let patch = terrain_patch(
        &loc,
        &format!("terrains[{i}]"),
        t,
        stream_seed(f.world.seed, &t.name),
        base_dir,
    )
    .map_err(|e| bad(e.to_string()))?;

    let (lo, hi) = footprint(&patch);
    let size = hi - lo;
    if !size.is_finite() {
        return Err(bad(format!(
            "--terrain {}: the terrain has an infinite extent; give it a finite extent_m",
            a.terrain
        )));
    }
    let count = |len: f64| (len / r + 1e-9).floor() + 1.0;
    let (cx, cy) = (count(size.x), count(size.y));
    let too_large = |n: f64| n > MAX_SAMPLES_PER_AXIS as f64;
    if too_large(cx) || too_large(cy) {
        return Err(bad(format!(
            "--resolution-m {r}: {cx} × {cy} samples over [{}, {}] m; a heightmap holds at most \
             {MAX_SAMPLES_PER_AXIS} per axis (use a coarser resolution)",
            size.x, size.y
        )));
    }
    let (nx, ny) = (cx as usize, cy as usize);
    if nx < 2 || ny < 2 {
        return Err(bad(format!(
            "--resolution-m {r}: coarser than the terrain's extent [{}, {}] m (a heightmap needs at least 2 × 2 samples)",
            size.x, size.y
        )));
    }
    let centre = 0.5 * (lo + hi);
    let first = centre - 0.5 * r * DVec2::new((nx - 1) as f64, (ny - 1) as f64);
    let mut sampled: Vec<Option<f64>> = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let p = first + r * DVec2::new(i as f64, j as f64);
            sampled.push(patch.height(p.x, p.y));
        }
    }
    let lowest = sampled
        .iter()
        .flatten()
        .copied()
        .fold(f64::INFINITY, f64::min);
    if !lowest.is_finite() {
        return Err(bad(format!(
            "--terrain {}: no ground at any sample point (resolution {r} m)",
            a.terrain
        )));
    }
    let fill = if f.world.default_ground.is_some() {
        f.world.default_ground_height_m
    } else {
        lowest
    };
    let filled = sampled.iter().filter(|h| h.is_none()).count();
    let heights_m: Vec<f64> = sampled.into_iter().map(|h| h.unwrap_or(fill)).collect();
    let min = heights_m.iter().copied().fold(f64::INFINITY, f64::min);
    let max = heights_m.iter().copied().fold(f64::NEG_INFINITY, f64::max);

    let (z0, vertical) = match format {
        HeightmapFormat::Png => (min, if max > min { max - min } else { 1.0 }),
        HeightmapFormat::Csv => (0.0, 1.0),
    };
    let origin_m = DVec3::new(centre.x, centre.y, z0);
    let file_key = entry_path(&a.out, base_dir);
    let ground = match &t.ground {
        None => String::new(),
        Some(GroundSpec::Preset(name)) => format!("ground = \"{name}\"\n"),
        Some(GroundSpec::Custom(_)) => format!(
            "# ground: copy the custom ground table of terrain '{}'\n",
            t.name
        ),
    };
    let mut notes = vec![
        format!(
            "quadsim terrain export: terrain '{}' of {}",
            t.name,
            a.scenario.display()
        ),
        format!(
            "{nx} × {ny} samples every {r:?} m (world axes) over x [{:?}, {:?}], y [{:?}, {:?}] m; heights {min:?} to {max:?} m",
            first.x,
            first.x + r * (nx - 1) as f64,
            first.y,
            first.y + r * (ny - 1) as f64,
        ),
    ];
    if format == HeightmapFormat::Png {
        notes.push(format!(
            "16-bit PNG: one step is {:?} m",
            (max - min) / 65_535.0
        ));
    }
    if filled > 0 {
        notes.push(format!(
            "{filled} samples where the terrain has no ground take {fill:?} m ({})",
            if f.world.default_ground.is_some() {
                "the world's default ground"
            } else {
                "the lowest sampled height"
            }
        ));
    }
    notes.push("file is relative to the scenario that includes this entry".to_string());
    let mut snippet: String = notes.iter().map(|n| format!("# {n}\n")).collect();
    snippet += &format!(
        "[[terrains]]\nname = \"{}_heightmap\"\nkind = \"heightmap\"\nfile = \"{}\"\n\
         origin_m = [{:?}, {:?}, {:?}]\nhorizontal_scale_m = {r:?}\nvertical_scale_m = {vertical:?}\n{ground}",
        t.name,
        file_key.replace('\\', "/"),
        origin_m.x,
        origin_m.y,
        origin_m.z,
    );

    match format {
        HeightmapFormat::Png => {
            let span = max - min;
            let samples: Vec<u16> = heights_m
                .iter()
                .map(|h| {
                    if span > 0.0 {
                        ((h - min) / span * 65_535.0).round().clamp(0.0, 65_535.0) as u16
                    } else {
                        0
                    }
                })
                .collect();
            write_png16(&a.out, nx, ny, &samples)
        }
        HeightmapFormat::Csv => {
            let header: Vec<String> = snippet
                .lines()
                .map(|l| l.strip_prefix("# ").unwrap_or(l).to_string())
                .collect();
            write_csv(&a.out, nx, ny, &heights_m, &header)
        }
    }
    .map_err(|e| bad(e.to_string()))?;

    Ok(Export {
        nx,
        ny,
        spacing_m: r,
        origin_m,
        vertical_scale_m: vertical,
        heights_m,
        filled,
        snippet,
    })
}

/// `out` relative to the scenario's directory when it lies below it, else as given.
fn entry_path(out: &Path, base_dir: &Path) -> String {
    let abs = |p: &Path| {
        std::fs::canonicalize(if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        })
        .ok()
    };
    let out_dir = out.parent().unwrap_or(Path::new("."));
    if let (Some(d), Some(b), Some(name)) = (abs(out_dir), abs(base_dir), out.file_name())
        && let Ok(rel) = d.strip_prefix(&b)
    {
        return rel.join(name).to_string_lossy().into_owned();
    }
    out.to_string_lossy().into_owned()
}
