//! Heightmap terrains from files: PNG and CSV values and orientation land where
//! the documented convention puts them, and every kind of bad file is a
//! scenario error naming the key path and its line (never a panic).

use std::path::{Path, PathBuf};

use glam::DVec3;
use quadsim::heightmap::{HeightmapError, MAX_SAMPLES_PER_AXIS, read_heightmap};
use quadsim::scenario::{Locator, ScenarioError, load_scenario};
use quadsim::terrain_spec::terrain_patch;
use quadsim::world::{Overrides, build_world};
use quadsim_engine::terrain::{Terrain as _, TerrainPatch};

/// A fresh directory for one test.
fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("heightmap")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A scenario with one heightmap terrain; `extra` lines go into its table.
fn scenario(d: &Path, file: &str, extra: &str) -> PathBuf {
    let src = format!(
        "format_version = 1\n\n[world]\nduration_s = 0.1\n\n[[terrains]]\nname = \"map\"\n\
         kind = \"heightmap\"\norigin_m = [1.0, -2.0, 0.5]\nfile = \"{file}\"\n\
         horizontal_scale_m = 0.5\nvertical_scale_m = 2.0\n{extra}"
    );
    let p = d.join("scn.toml");
    std::fs::write(&p, src).unwrap();
    p
}

/// 1-based line of the first line of `path` that starts with `prefix`.
fn line_of(path: &Path, prefix: &str) -> usize {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .position(|l| l.starts_with(prefix))
        .expect("line present")
        + 1
}

fn patch(path: &Path) -> Result<TerrainPatch, ScenarioError> {
    let scn = load_scenario(path)?;
    let loc = Locator {
        path: &scn.path,
        src: &scn.source,
    };
    terrain_patch(
        &loc,
        "terrains[0]",
        &scn.file.terrains[0],
        0,
        path.parent().unwrap(),
    )
}

/// Building the world fails with an error at `key` (on its line) whose message contains `what`.
fn expect_error(path: &Path, key: &str, line_prefix: &str, what: &str) -> String {
    let scn = load_scenario(path).expect("the scenario parses");
    let e = build_world(&scn, Overrides::default()).expect_err("a bad heightmap");
    let msg = e.to_string();
    assert_eq!(e.key_path, key, "{msg}");
    let line = line_of(path, line_prefix);
    assert_eq!(e.line, line, "{msg}");
    assert!(msg.contains(&format!(":{line}:")), "{msg}");
    assert!(msg.contains(key), "{msg}");
    assert!(msg.contains(what), "expected '{what}' in: {msg}");
    msg
}

fn write_png(
    path: &Path,
    w: u32,
    h: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) {
    let f = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w, h);
    enc.set_color(color);
    enc.set_depth(depth);
    let mut wr = enc.write_header().unwrap();
    wr.write_image_data(data).unwrap();
    wr.finish().unwrap();
}

/// Sample (i, j) of a grid of nx × ny every 0.5 m centred on (1, −2): world (x, y).
fn sample_xy(i: usize, j: usize, nx: usize, ny: usize) -> (f64, f64) {
    (
        1.0 + 0.5 * (i as f64 - 0.5 * (nx - 1) as f64),
        -2.0 + 0.5 * (j as f64 - 0.5 * (ny - 1) as f64),
    )
}

/// An 8-bit PNG: the top image row is the largest y, the sample v is
/// v/255 of vertical_scale_m above the origin; the grid is centred on the origin.
#[test]
fn png8_values_and_orientation() {
    let d = dir("png8");
    let (nx, ny) = (4usize, 3usize);
    // image row r, column c
    let px = |r: usize, c: usize| (10 * r + 40 * c + 3) as u8;
    let data: Vec<u8> = (0..ny)
        .flat_map(|r| (0..nx).map(move |c| px(r, c)))
        .collect();
    write_png(
        &d.join("m.png"),
        nx as u32,
        ny as u32,
        png::ColorType::Grayscale,
        png::BitDepth::Eight,
        &data,
    );
    let p = patch(&scenario(&d, "m.png", "")).unwrap();
    for r in 0..ny {
        for c in 0..nx {
            let (x, y) = sample_xy(c, ny - 1 - r, nx, ny);
            let want = 0.5 + 2.0 * px(r, c) as f64 / 255.0;
            let got = p.height(x, y).unwrap();
            assert!(
                (got - want).abs() < 1e-12,
                "row {r} col {c}: {got} vs {want}"
            );
        }
    }
    // the extent is the file's: (nx − 1) × 0.5 by (ny − 1) × 0.5 m
    assert!(p.height(1.0 + 0.76, -2.0).is_none());
    assert!(p.height(1.0 + 0.74, -2.0).is_some());
    // an equal extent_m is accepted
    assert!(patch(&scenario(&d, "m.png", "extent_m = [1.5, 1.0]\n")).is_ok());
}

/// A 16-bit PNG reads as v / 65535.
#[test]
fn png16_values() {
    let d = dir("png16");
    let vals: [u16; 4] = [0, 65535, 12345, 40000];
    let data: Vec<u8> = vals.iter().flat_map(|v| v.to_be_bytes()).collect();
    write_png(
        &d.join("m.png"),
        2,
        2,
        png::ColorType::Grayscale,
        png::BitDepth::Sixteen,
        &data,
    );
    let p = patch(&scenario(&d, "m.png", "")).unwrap();
    for (k, v) in vals.iter().enumerate() {
        let (r, c) = (k / 2, k % 2);
        let (x, y) = sample_xy(c, 1 - r, 2, 2);
        let want = 0.5 + 2.0 * *v as f64 / 65535.0;
        assert!((p.height(x, y).unwrap() - want).abs() < 1e-12);
    }
}

/// CSV numbers are multiples of vertical_scale_m; the first line is the
/// largest y; comments, blanks and spaces around numbers are allowed.
#[test]
fn csv_values_and_orientation() {
    let d = dir("csv");
    std::fs::write(d.join("m.csv"), "# a map\n0.1, 0.2, -0.3\n\n1.5,2,2.5e-1\n").unwrap();
    let p = patch(&scenario(&d, "m.csv", "")).unwrap();
    let rows = [[0.1, 0.2, -0.3], [1.5, 2.0, 0.25]];
    for (r, row) in rows.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            let (x, y) = sample_xy(c, 1 - r, 3, 2);
            let got = p.height(x, y).unwrap();
            assert!((got - (0.5 + 2.0 * v)).abs() < 1e-12, "{r} {c}: {got}");
        }
    }
}

#[test]
fn missing_file_names_the_resolved_path() {
    let d = dir("missing");
    let path = scenario(&d, "nope/absent.png", "");
    let msg = expect_error(&path, "terrains[0].file", "file =", "cannot read heightmap");
    assert!(
        msg.contains(&d.join("nope/absent.png").display().to_string()),
        "{msg}"
    );
}

#[test]
fn empty_files() {
    let d = dir("empty");
    std::fs::write(d.join("e.png"), b"").unwrap();
    std::fs::write(d.join("e.csv"), b"").unwrap();
    std::fs::write(d.join("c.csv"), b"# only a comment\n\n").unwrap();
    for f in ["e.png", "e.csv", "c.csv"] {
        expect_error(
            &scenario(&d, f, ""),
            "terrains[0].file",
            "file =",
            "is empty",
        );
    }
}

#[test]
fn not_an_image() {
    let d = dir("not_png");
    std::fs::write(d.join("m.png"), b"1,2\n3,4\n").unwrap();
    expect_error(
        &scenario(&d, "m.png", ""),
        "terrains[0].file",
        "file =",
        "is not a PNG image",
    );
    // a PNG cut short after its header
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, 3, 3);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[7; 9]).unwrap();
    }
    std::fs::write(d.join("cut.png"), &bytes[..bytes.len() - 20]).unwrap();
    expect_error(
        &scenario(&d, "cut.png", ""),
        "terrains[0].file",
        "file =",
        "is not a PNG image",
    );
}

#[test]
fn colour_pngs_are_refused() {
    let d = dir("rgb");
    write_png(
        &d.join("m.png"),
        2,
        2,
        png::ColorType::Rgb,
        png::BitDepth::Eight,
        &[0; 12],
    );
    expect_error(
        &scenario(&d, "m.png", ""),
        "terrains[0].file",
        "file =",
        "8- or 16-bit greyscale",
    );
    write_png(
        &d.join("g4.png"),
        2,
        2,
        png::ColorType::Grayscale,
        png::BitDepth::Four,
        &[0; 2],
    );
    expect_error(
        &scenario(&d, "g4.png", ""),
        "terrains[0].file",
        "file =",
        "4-bit",
    );
}

#[test]
fn unknown_extension() {
    let d = dir("ext");
    std::fs::write(d.join("m.txt"), b"1,2\n3,4\n").unwrap();
    expect_error(
        &scenario(&d, "m.txt", ""),
        "terrains[0].file",
        "file =",
        "unknown file type",
    );
}

#[test]
fn ragged_csv_names_the_row() {
    let d = dir("ragged");
    std::fs::write(d.join("m.csv"), "1,2,3\n4,5,6\n7,8\n").unwrap();
    expect_error(
        &scenario(&d, "m.csv", ""),
        "terrains[0].file",
        "file =",
        "row 3 has 2 columns but the first row has 3",
    );
}

#[test]
fn non_numbers_name_row_and_column() {
    let d = dir("nan");
    for (text, bad) in [
        ("1,2,3\n4,five,6\n", "row 2, column 2: 'five'"),
        ("# header\n1,2\nNaN,3\n", "row 3, column 1: 'NaN'"),
        ("1,2,\n3,4,5\n", "row 1, column 3: ''"),
    ] {
        std::fs::write(d.join("m.csv"), text).unwrap();
        expect_error(
            &scenario(&d, "m.csv", ""),
            "terrains[0].file",
            "file =",
            bad,
        );
    }
}

/// Too large: refused from the PNG header / while the CSV streams, before
/// the grid is allocated.
#[test]
fn absurdly_large_is_refused() {
    let d = dir("large");
    let w = MAX_SAMPLES_PER_AXIS as u32 + 1;
    write_png(
        &d.join("wide.png"),
        w,
        2,
        png::ColorType::Grayscale,
        png::BitDepth::Eight,
        &vec![0; 2 * w as usize],
    );
    expect_error(
        &scenario(&d, "wide.png", ""),
        "terrains[0].file",
        "file =",
        "16385 × 2 samples is too large",
    );
    let row = vec!["0"; MAX_SAMPLES_PER_AXIS + 1].join(",");
    std::fs::write(d.join("wide.csv"), format!("{row}\n{row}\n")).unwrap();
    expect_error(
        &scenario(&d, "wide.csv", ""),
        "terrains[0].file",
        "file =",
        "too large",
    );
    // a tall CSV stops at row 16385
    std::fs::write(d.join("tall.csv"), "0,0\n".repeat(MAX_SAMPLES_PER_AXIS + 5)).unwrap();
    let e = read_heightmap(&d.join("tall.csv")).unwrap_err();
    assert!(
        matches!(e, HeightmapError::TooLarge { nx: 2, ny, .. } if ny == MAX_SAMPLES_PER_AXIS + 1),
        "{e}"
    );
}

#[test]
fn fewer_than_two_by_two_is_refused() {
    let d = dir("small");
    write_png(
        &d.join("m.png"),
        1,
        5,
        png::ColorType::Grayscale,
        png::BitDepth::Eight,
        &[0; 5],
    );
    expect_error(
        &scenario(&d, "m.png", ""),
        "terrains[0].file",
        "file =",
        "1 × 5 samples; a heightmap needs at least 2 × 2",
    );
    std::fs::write(d.join("m.csv"), "1,2,3\n").unwrap();
    expect_error(
        &scenario(&d, "m.csv", ""),
        "terrains[0].file",
        "file =",
        "3 × 1 samples",
    );
}

#[test]
fn conflicting_extent_is_refused() {
    let d = dir("extent");
    std::fs::write(d.join("m.csv"), "0,0,0\n0,1,0\n").unwrap();
    expect_error(
        &scenario(&d, "m.csv", "extent_m = [20.0, 20.0]\n"),
        "terrains[0].extent_m",
        "extent_m",
        "span [1, 0.5] m",
    );
}

/// A robot can stand on a heightmap: its start height follows the file.
#[test]
fn robot_starts_on_the_heightmap() {
    let d = dir("robot");
    let rows = ["0.1,0.1,0.1,0.1,0.1"; 5].join("\n");
    std::fs::write(d.join("m.csv"), rows).unwrap();
    let path = scenario(&d, "m.csv", "");
    let mut src = std::fs::read_to_string(&path).unwrap();
    src += "\n[[robots]]\nname = \"rex\"\nmodel = \"quad16\"\nterrain = \"map\"\nstart_position_m = [0.0, 0.0, 0.6]\n";
    std::fs::write(&path, src).unwrap();
    let scn = load_scenario(&path).unwrap();
    let w = build_world(&scn, Overrides::default()).unwrap();
    let r = w.sim.robot(w.robots[0].1).unwrap();
    // base at the terrain's origin (1, −2), 0.6 m above 0.5 + 2 × 0.1
    let base = DVec3::new(r.state.q[0], r.state.q[1], r.state.q[2]);
    assert!(
        (base - DVec3::new(1.0, -2.0, 0.7 + 0.6)).length() < 1e-12,
        "{base}"
    );
}
