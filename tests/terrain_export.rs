//! `quadsim terrain export` round trips: analytic terrains sampled into a
//! 16-bit PNG and re-imported through the printed `[[terrains]]` entry match
//! the original at the samples within half a quantisation step, between
//! samples within the stated interpolation bound, and in normal direction
//! within 1°; CSV files round-trip exactly.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use quadsim::cli::terrain::{Export, ExportArgs, export};
use quadsim::heightmap::read_heightmap;
use quadsim::scenario::{Locator, load_scenario};
use quadsim::terrain_spec::terrain_patch;
use quadsim::world::stream_seed;
use quadsim_engine::terrain::{Terrain as _, TerrainPatch};

/// Terrains to export: yawed sine, incline, both rough kinds, stairs, boxes.
const SOURCE: &str = r#"format_version = 1

[world]
duration_s = 0.1
seed = 7
default_ground = "concrete"
default_ground_height_m = -0.05

[[terrains]]
name = "sine"
kind = "sine"
amplitude_m = 0.1
wavelength_m = 2.0
direction_deg = 30.0
origin_m = [1.0, 2.0, 0.5]
extent_m = [4.0, 3.0]
ground = "grass"

[[terrains]]
name = "incline"
kind = "incline"
slope_deg = 15.0
origin_m = [-3.0, 1.0, 0.2]
extent_m = [3.0, 2.0]

[[terrains]]
name = "rough_smooth"
kind = "rough"
amplitude_m = 0.05
cell_m = 0.5
noise = "smooth"
origin_m = [0.0, -6.0, 0.0]
extent_m = [3.0, 3.0]

[[terrains]]
name = "rough_uniform"
kind = "rough"
amplitude_m = 0.03
cell_m = 0.4
noise = "uniform"
origin_m = [5.0, -6.0, 0.0]
extent_m = [3.0, 3.0]

[[terrains]]
name = "stairs"
kind = "stairs"
rise_m = 0.1
run_m = 0.3
steps = 3
origin_m = [10.0, 0.0, 0.0]
extent_m = [2.0, 1.0]

[[terrains]]
name = "boxes"
kind = "boxes"
origin_m = [10.0, 5.0, 0.0]
boxes = [
  { center_m = [0.0, 0.0, 0.05], size_m = [0.4, 0.3, 0.1] },
  { center_m = [0.8, 0.2, 0.1], size_m = [0.3, 0.3, 0.2], yaw_deg = 20.0 },
]
"#;

fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("terrain_export")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The patch of terrain `name` of the scenario file `path`, as `quadsim run` builds it.
fn patch_of(path: &Path, name: &str) -> TerrainPatch {
    let scn = load_scenario(path).unwrap();
    let loc = Locator {
        path: &scn.path,
        src: &scn.source,
    };
    let i = scn
        .file
        .terrains
        .iter()
        .position(|t| t.name == name)
        .unwrap();
    let t = &scn.file.terrains[i];
    terrain_patch(
        &loc,
        &format!("terrains[{i}]"),
        t,
        stream_seed(scn.file.world.seed, &t.name),
        path.parent().unwrap(),
    )
    .unwrap()
}

/// Exports `terrain` of the source scenario to `file` in `d`, writes a
/// scenario holding only the printed entry, and returns the original patch,
/// the re-imported one and the export record.
fn round_trip(d: &Path, terrain: &str, file: &str, r: f64) -> (TerrainPatch, TerrainPatch, Export) {
    let src = d.join("source.toml");
    std::fs::write(&src, SOURCE).unwrap();
    let ex = export(&ExportArgs {
        scenario: src.clone(),
        terrain: terrain.into(),
        out: d.join(file),
        resolution_m: r,
    })
    .unwrap();
    let back = d.join("reimport.toml");
    std::fs::write(
        &back,
        format!(
            "format_version = 1\n[world]\nduration_s = 0.1\n\n{}",
            ex.snippet
        ),
    )
    .unwrap();
    (
        patch_of(&src, terrain),
        patch_of(&back, &format!("{terrain}_heightmap")),
        ex,
    )
}

/// World position of grid point (gi, gj) (fractional indices allowed).
fn grid_xy(ex: &Export, gi: f64, gj: f64) -> (f64, f64) {
    let r = ex.spacing_m;
    (
        ex.origin_m.x + r * (gi - 0.5 * (ex.nx - 1) as f64),
        ex.origin_m.y + r * (gj - 0.5 * (ex.ny - 1) as f64),
    )
}

/// Grid points off the grid's outer rows and columns: those lie on the
/// re-imported field's border, which round-off may put an ulp outside.
fn inner(ex: &Export) -> impl Iterator<Item = (usize, usize)> {
    let (nx, ny) = (ex.nx, ex.ny);
    (1..ny - 1).flat_map(move |j| (1..nx - 1).map(move |i| (i, j)))
}

/// True if every sample within ±2 indices of (i, j) exists and lies on the
/// original terrain (not filled): the Catmull–Rom stencils around (i, j) and
/// around the cell (i, j)–(i+1, j+1) see only true samples.
fn interior(ex: &Export, orig: &TerrainPatch, i: usize, j: usize) -> bool {
    if i < 2 || j < 2 || i + 2 >= ex.nx || j + 2 >= ex.ny {
        return false;
    }
    (i - 2..=i + 2).all(|a| {
        (j - 2..=j + 2).all(|b| {
            let (x, y) = grid_xy(ex, a as f64, b as f64);
            orig.height(x, y).is_some()
        })
    })
}

/// Angle between the two terrains' normals at the original's surface above (x, y) (deg).
fn normal_angle_deg(orig: &TerrainPatch, back: &TerrainPatch, x: f64, y: f64) -> f64 {
    let p = DVec3::new(x, y, orig.height(x, y).unwrap());
    let a = orig.closest(p).unwrap().normal;
    let b = back.closest(p).unwrap().normal;
    a.cross(b).length().atan2(a.dot(b)).to_degrees()
}

/// Largest errors over the interior: (height at samples, height mid-cell,
/// normal angle at samples and mid-cell (deg)); also checks every covered
/// sample off the outer rows (interior or not) against half a step.
fn errors(orig: &TerrainPatch, back: &TerrainPatch, ex: &Export, half_step: f64) -> [f64; 3] {
    let mut e = [0.0f64; 3];
    let mut n = 0;
    for (i, j) in inner(ex) {
        let (x, y) = grid_xy(ex, i as f64, j as f64);
        let Some(h) = orig.height(x, y) else {
            continue;
        };
        let d = (back.height(x, y).unwrap() - h).abs();
        assert!(
            d <= half_step,
            "sample ({i}, {j}): error {d} m > {half_step} m"
        );
        if !interior(ex, orig, i, j) {
            continue;
        }
        n += 1;
        e[0] = e[0].max(d);
        let (xm, ym) = grid_xy(ex, i as f64 + 0.5, j as f64 + 0.5);
        e[1] = e[1].max((back.height(xm, ym).unwrap() - orig.height(xm, ym).unwrap()).abs());
        e[2] = e[2]
            .max(normal_angle_deg(orig, back, x, y))
            .max(normal_angle_deg(orig, back, xm, ym));
    }
    assert!(n > 100, "only {n} interior samples");
    e
}

/// One PNG step of the export (m).
fn step(ex: &Export) -> f64 {
    let (lo, hi) = ex
        .heights_m
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(*h), b.max(*h))
        });
    (hi - lo) / 65_535.0
}

/// Catmull–Rom at a cell's midpoint filters a sinusoid of phase step θ = k h / 2
/// per half sample by g(θ) = (9 cos θ − cos 3θ) / 8 (taps −1, 9, 9, −1 over 16).
fn midpoint_gain(theta: f64) -> f64 {
    (9.0 * theta.cos() - (3.0 * theta).cos()) / 8.0
}

/// A sine corrugation at 30° yaw: heights within half a step at the samples;
/// mid-cell within A |1 − g(θx) g(θy)| (the interpolant's exact gain on a
/// plane wave) plus the quantisation error through the midpoint weights
/// (Σ|w| = 1.25 per axis); normals within 1°.
#[test]
fn sine_png_round_trip() {
    let d = dir("sine");
    let r = 0.1;
    let (orig, back, ex) = round_trip(&d, "sine", "sine.png", r);
    // the footprint's corners are outside the yawed terrain: filled
    assert!(ex.filled > 0);
    assert_eq!(ex.origin_m.truncate(), glam::DVec2::new(1.0, 2.0));
    let q = step(&ex);
    // the entry's vertical scale spans the samples, fill (default ground at −0.05 m) included
    assert!((ex.vertical_scale_m - 65_535.0 * q).abs() < 1e-12);
    assert!((ex.origin_m.z + 0.05).abs() < 1e-12);
    let [hs, hm, ang] = errors(&orig, &back, &ex, 0.5 * q + 1e-12);
    let k = std::f64::consts::TAU / 2.0;
    let (tx, ty) = (
        0.5 * k * r * 30f64.to_radians().cos(),
        0.5 * k * r * 30f64.to_radians().sin(),
    );
    let interp = 0.1 * (1.0 - midpoint_gain(tx) * midpoint_gain(ty)).abs();
    let mid_bound = interp + 1.5625 * 0.5 * q + 1e-12;
    println!(
        "sine: step {q:.3e} m, samples {hs:.3e} m, mid-cell {hm:.3e} m (bound {mid_bound:.3e}), normals {ang:.4}°"
    );
    assert!(hm <= mid_bound, "{hm} > {mid_bound}");
    // the bound is not loose by orders of magnitude: the interpolation error shows
    assert!(hm > 0.5 * interp, "{hm} vs {interp}");
    assert!(ang < 1.0, "{ang}°");
}

/// An incline is linear, which Catmull–Rom reproduces exactly: mid-cell
/// errors are quantisation only.
#[test]
fn incline_png_round_trip() {
    let d = dir("incline");
    let (orig, back, ex) = round_trip(&d, "incline", "incline.png", 0.05);
    assert_eq!(ex.filled, 0);
    let q = step(&ex);
    let [hs, hm, ang] = errors(&orig, &back, &ex, 0.5 * q + 1e-12);
    println!("incline: step {q:.3e} m, samples {hs:.3e} m, mid-cell {hm:.3e} m, normals {ang:.5}°");
    assert!(hm <= 1.5625 * 0.5 * q + 1e-12, "{hm}");
    assert!(ang < 1.0, "{ang}°");
}

/// Rough ground, both kinds: samples within half a step, normals within 1°
/// at a resolution of a tenth of the smallest Perlin wavelength (0.25 m) and
/// of a sixteenth of the uniform cell.
#[test]
fn rough_png_round_trip() {
    for (name, r) in [("rough_smooth", 0.025), ("rough_uniform", 0.025)] {
        let d = dir(name);
        let (orig, back, ex) = round_trip(&d, name, "rough.png", r);
        let q = step(&ex);
        let [hs, hm, ang] = errors(&orig, &back, &ex, 0.5 * q + 1e-12);
        println!(
            "{name}: step {q:.3e} m, samples {hs:.3e} m, mid-cell {hm:.3e} m, normals {ang:.4}°"
        );
        assert!(ang < 1.0, "{name}: {ang}°");
    }
}

/// CSV: every number reads back to the f64 that was sampled, and the
/// re-imported terrain equals the original at every sample, also across the
/// discontinuities of stairs and boxes; holes take the default ground height.
#[test]
fn csv_round_trip_is_exact() {
    for (name, r) in [("sine", 0.1), ("stairs", 0.05), ("boxes", 0.05)] {
        let d = dir(&format!("csv_{name}"));
        let (orig, back, ex) = round_trip(&d, name, "map.csv", r);
        let grid = read_heightmap(&d.join("map.csv")).unwrap();
        assert_eq!((grid.nx, grid.ny), (ex.nx, ex.ny));
        assert_eq!(grid.values, ex.heights_m, "{name}: CSV numbers differ");
        let mut filled = 0;
        for (i, j) in inner(&ex) {
            let (x, y) = grid_xy(&ex, i as f64, j as f64);
            let b = back.height(x, y).unwrap();
            match orig.height(x, y) {
                Some(h) => assert!((b - h).abs() <= 1e-12, "{name} ({i}, {j}): {b} vs {h}"),
                None => {
                    filled += 1;
                    assert!((b + 0.05).abs() <= 1e-12, "fill {b}");
                }
            }
        }
        assert!(filled <= ex.filled, "{name}");
        if name == "boxes" {
            assert!(filled > 0);
        }
    }
}

/// The binary prints an entry that `quadsim check` accepts in a new scenario.
#[test]
fn cli_export_then_check() {
    let d = dir("cli");
    let src = d.join("source.toml");
    std::fs::write(&src, SOURCE).unwrap();
    let bin = env!("CARGO_BIN_EXE_quadsim");
    let out = Command::new(bin)
        .args(["terrain", "export"])
        .arg(&src)
        .args(["--terrain", "sine", "--out"])
        .arg(d.join("sine.png"))
        .args(["--resolution-m", "0.1"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let snippet = String::from_utf8(out.stdout).unwrap();
    assert!(snippet.contains("file = \"sine.png\""), "{snippet}");
    assert!(snippet.contains("ground = \"grass\""), "{snippet}");
    let back = d.join("back.toml");
    std::fs::write(
        &back,
        format!("format_version = 1\n[world]\nduration_s = 0.1\n\n{snippet}"),
    )
    .unwrap();
    let check = Command::new(bin).arg("check").arg(&back).output().unwrap();
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );

    // bad requests are errors naming the option, exit code 2
    for (args, what) in [
        (
            vec!["--terrain", "nope", "--out", "x.png"],
            "no terrain 'nope'",
        ),
        (vec!["--terrain", "sine", "--out", "x.bmp"], ".png"),
        (
            vec!["--terrain", "sine", "--out", "x.png", "--resolution-m", "0"],
            "--resolution-m",
        ),
        (
            vec![
                "--terrain",
                "sine",
                "--out",
                "x.png",
                "--resolution-m",
                "1e-4",
            ],
            "at most 16384",
        ),
    ] {
        let o = Command::new(bin)
            .args(["terrain", "export"])
            .arg(&src)
            .args(&args)
            .current_dir(&d)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(what), "{what}: {err}");
    }
}
