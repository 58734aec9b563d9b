//! Filmstrips in `report.md` (issue 30): drawn from the log, not blank,
//! and the same bytes when `quadsim report` draws them again; a herd's
//! report holds at most `MAX_ROBOTS` filmstrips and one world snapshot.

use std::path::{Path, PathBuf};
use std::process::Command;

use quadsim::report::filmstrip::MAX_ROBOTS;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-film-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn quadsim(args: &[&str], extra: &[&Path]) {
    let o = Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "quadsim {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Pixel statistics of an RGB PNG: (share of non-white pixels, distinct
/// colours, pixels that are the stance red, pixels that are the swing blue).
fn pixels(path: &Path) -> (f64, usize, usize, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px: Vec<[u8; 3]> = buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let ink = px.iter().filter(|p| **p != [255, 255, 255]).count();
    let mut colours = px.clone();
    colours.sort_unstable();
    colours.dedup();
    let red = px.iter().filter(|p| **p == [200, 40, 40]).count();
    let blue = px.iter().filter(|p| **p == [40, 90, 200]).count();
    (ink as f64 / px.len() as f64, colours.len(), red, blue)
}

/// trot_flat's report shows rex's filmstrip: a PNG with ink in it (links,
/// feet on the ground and in the air), redrawn byte for byte by `quadsim
/// report` from the log, twice.
#[test]
fn trot_flat_report_has_a_filmstrip_redrawn_identically() {
    let out = tmp("trot");
    let scn = root().join("scenarios/trot_flat.toml");
    quadsim(
        &["run", "--duration", "2", "--quiet", "--no-monitor", "--out"],
        &[&out, &scn],
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("## Motion") && md.contains("![rex_filmstrip](plots/rex_filmstrip.png)"),
        "no filmstrip in report.md"
    );
    let png = out.join("plots/rex_filmstrip.png");
    let (ink, colours, red, blue) = pixels(&png);
    assert!((0.01..0.5).contains(&ink), "ink share {ink}");
    assert!(colours >= 8, "{colours} colours");
    assert!(red > 100 && blue > 100, "stance {red} px, swing {blue} px");
    let first = std::fs::read(&png).unwrap();
    for k in ["r1", "r2"] {
        let again = out.join(k);
        quadsim(
            &["report"],
            &[&out.join("log.mcap"), Path::new("--out"), &again],
        );
        let redrawn = std::fs::read(again.join("plots/rex_filmstrip.png")).unwrap();
        assert!(redrawn == first, "{k}: the filmstrip differs when redrawn");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A herd's report stays bounded: filmstrips of its worst robots only, and
/// one snapshot of the world with ink in it.
#[test]
fn a_herds_report_has_few_filmstrips_and_a_world_snapshot() {
    let out = tmp("herd");
    let scn = root().join("scenarios/herd.toml");
    quadsim(
        &[
            "run",
            "--duration",
            "0.6",
            "--quiet",
            "--no-monitor",
            "--log-robots",
            "q16-00*",
            "--log-rate",
            "50",
            "--out",
        ],
        &[&out, &scn],
    );
    let strips = std::fs::read_dir(out.join("plots"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .ends_with("_filmstrip.png")
        })
        .count();
    assert_eq!(strips, MAX_ROBOTS);
    let (ink, colours, _, _) = pixels(&out.join("plots/world_snapshot.png"));
    assert!(
        ink > 0.001 && colours >= 4,
        "snapshot ink {ink}, {colours} colours"
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    // a herd's report details its worst robots: the filmstrips are theirs
    assert!(md.contains(&format!(
        "Filmstrips of {MAX_ROBOTS} of 102 robots: the worst ones logged"
    )));
    let _ = std::fs::remove_dir_all(&out);
}
