//! A structure-aware fuzzing campaign over quadsim's inputs (issue 29):
//! scenario TOML, URDF and heightmap files, made by mutating the valid files
//! in `scenarios/` and `tests/fixtures/` (keys, types, extreme numbers,
//! names, sizes), each run through `quadsim check` and, when it passes, a
//! short `quadsim run` in process. Every case must end without a panic,
//! within [`CASE_LIMIT`] and [`MEMORY_LIMIT_BYTES`] of heap, and write no
//! file outside its output directory.
//!
//! Mutations are drawn with `arbitrary::Unstructured` from bytes of a
//! ChaCha stream seeded by (campaign seed, case number), so any case is
//! reproduced by its number. `docs/reliability.md` gives the campaign's
//! figures and how to run a long one:
//!
//! ```sh
//! QUADSIM_FUZZ_CASES=50000 QUADSIM_FUZZ_SECONDS=36000 QUADSIM_FUZZ_SEED=7
//!   cargo test --release --test fuzz_inputs -- --nocapture
//! QUADSIM_FUZZ_ONLY=1234 cargo test --release --test fuzz_inputs -- --nocapture   # one case
//! ```
//!
//! A failing case's inputs are kept in `target/fuzz-failures/<seed>-<case>/`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicIsize, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use arbitrary::Unstructured;
use rand::{RngCore, SeedableRng};

// ---- memory: live and peak heap bytes ------------------------------------

static LIVE: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);

struct PeakAlloc;

#[allow(
    unsafe_code,
    reason = "a GlobalAlloc impl is unsafe by definition; it forwards to System"
)]
unsafe impl GlobalAlloc for PeakAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now =
            LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed) + layout.size() as isize;
        PEAK.fetch_max(now, Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let now =
            LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed) + layout.size() as isize;
        PEAK.fetch_max(now, Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let d = new_size as isize - layout.size() as isize;
        let now = LIVE.fetch_add(d, Ordering::Relaxed) + d;
        PEAK.fetch_max(now, Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOC: PeakAlloc = PeakAlloc;

/// The longest a case may take.
const CASE_LIMIT: Duration = Duration::from_secs(20);
/// The most heap a case may add.
const MEMORY_LIMIT_BYTES: isize = 1 << 30;
/// A case still running after this is a hang: the process stops with its number.
const HANG_ABORT: Duration = Duration::from_secs(120);
/// Robot-steps a short run may take (more is skipped: `check` still ran).
const RUN_ROBOT_STEPS: f64 = 40_000.0;

fn env_u64(k: &str, d: u64) -> u64 {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

// ---- seeds ------------------------------------------------------------------

struct Seeds {
    scenarios: Vec<(String, toml::Table)>,
    urdfs: Vec<(String, String)>,
    png: Vec<u8>,
}

fn seeds() -> Seeds {
    let mut scenarios = Vec::new();
    let mut names: Vec<PathBuf> = std::fs::read_dir(repo().join("scenarios"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    for p in names {
        let text = std::fs::read_to_string(&p).unwrap();
        if quadsim::study::file_kind(&text).is_some() || text.contains("heightmap") {
            continue;
        }
        let t: toml::Table = text.parse().unwrap();
        scenarios.push((p.file_name().unwrap().to_string_lossy().into_owned(), t));
    }
    let urdfs = [
        "quad16.urdf",
        "quad12.urdf",
        "vendor_style.urdf",
        "vendor_style_revolute.urdf",
    ]
    .iter()
    .map(|n| {
        let p = repo().join("tests/fixtures/models").join(n);
        (n.to_string(), std::fs::read_to_string(p).unwrap())
    })
    .collect();
    let png = std::fs::read(repo().join("scenarios/assets/hills.png")).unwrap();
    Seeds {
        scenarios,
        urdfs,
        png,
    }
}

// ---- mutations ----------------------------------------------------------------

const FLOATS: &[f64] = &[
    0.0,
    -0.0,
    -1.0,
    1e-300,
    1e-9,
    1e-5,
    0.5,
    2.0,
    100.0,
    1e9,
    1e18,
    1e300,
    1e308,
    f64::MAX,
    f64::MIN_POSITIVE,
    -1e308,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
];
const INTS: &[i64] = &[
    0,
    -1,
    1,
    2,
    3,
    7,
    64,
    1000,
    10_001,
    100_000,
    i64::MAX,
    i64::MIN,
];

/// Directory an absolute name would write into: it must never appear.
const ABS_PROBE: &str = "/tmp/quadsim-fuzz-abs";

fn hostile_name(u: &mut Unstructured<'_>) -> arbitrary::Result<String> {
    Ok(match u.int_in_range(0..=11)? {
        0 => "../../../X".into(),
        1 => format!("{ABS_PROBE}/X"),
        2 => "a/b".into(),
        3 => "..".into(),
        4 => String::new(),
        5 => " ".into(),
        6 => "x".repeat(u.int_in_range(60..=100_000)?),
        7 => "é\u{0}\n".into(),
        8 => "rex".into(),
        9 => "*".into(),
        10 => "..\\..\\X".into(),
        _ => "q16-000".into(),
    })
}

fn number(u: &mut Unstructured<'_>) -> arbitrary::Result<toml::Value> {
    Ok(if u.ratio(1, 3)? {
        toml::Value::Integer(*u.choose(INTS)?)
    } else {
        toml::Value::Float(*u.choose(FLOATS)?)
    })
}

fn wrong_type(u: &mut Unstructured<'_>) -> arbitrary::Result<toml::Value> {
    Ok(match u.int_in_range(0..=4)? {
        0 => toml::Value::String("quad16".into()),
        1 => toml::Value::Boolean(u.arbitrary()?),
        2 => toml::Value::Array(vec![]),
        3 => toml::Value::Table(toml::Table::new()),
        _ => toml::Value::Array(vec![number(u)?, number(u)?, number(u)?]),
    })
}

#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    Index(usize),
}

fn paths(v: &toml::Value, here: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>) {
    out.push(here.clone());
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                here.push(Seg::Key(k.clone()));
                paths(x, here, out);
                here.pop();
            }
        }
        toml::Value::Array(a) => {
            for (i, x) in a.iter().enumerate().take(8) {
                here.push(Seg::Index(i));
                paths(x, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

fn at<'a>(v: &'a mut toml::Value, path: &[Seg]) -> Option<&'a mut toml::Value> {
    let mut cur = v;
    for s in path {
        cur = match (s, cur) {
            (Seg::Key(k), toml::Value::Table(t)) => t.get_mut(k)?,
            (Seg::Index(i), toml::Value::Array(a)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(cur)
}

fn mutate_toml(u: &mut Unstructured<'_>, root: &mut toml::Value) -> arbitrary::Result<()> {
    let mut all = Vec::new();
    paths(root, &mut Vec::new(), &mut all);
    // names are favoured: they reach file names
    let named: Vec<&Vec<Seg>> = all
        .iter()
        .filter(|p| matches!(p.last(), Some(Seg::Key(k)) if k == "name" || k == "model" || k == "terrain"))
        .collect();
    let path = if !named.is_empty() && u.ratio(1, 4)? {
        (*u.choose(&named)?).clone()
    } else {
        u.choose(&all)?.clone()
    };
    let op = u.int_in_range(0..=9)?;
    let Some(target) = at(root, &path) else {
        return Ok(());
    };
    match op {
        0 | 1 => *target = number(u)?,
        2 => *target = wrong_type(u)?,
        3 => *target = toml::Value::String(hostile_name(u)?),
        4 => {
            // delete the key or element
            if let Some((last, parent)) = path.split_last()
                && let Some(p) = at(root, parent)
            {
                match (last, p) {
                    (Seg::Key(k), toml::Value::Table(t)) => {
                        t.remove(k);
                    }
                    (Seg::Index(i), toml::Value::Array(a)) if *i < a.len() => {
                        a.remove(*i);
                    }
                    _ => {}
                }
            }
        }
        5 => {
            if let toml::Value::Table(t) = target {
                let k = if u.arbitrary()? {
                    "unknown_key".to_string()
                } else {
                    "count".to_string()
                };
                t.insert(k, number(u)?);
            } else {
                *target = number(u)?;
            }
        }
        6 => {
            // grow an array (more robots, terrains, boxes, joints' gains)
            if let toml::Value::Array(a) = target
                && let Some(last) = a.last().cloned()
            {
                let n = u.int_in_range(1..=40)?;
                a.extend(std::iter::repeat_n(last, n));
            } else if let Some(x) = target.as_float() {
                *target = toml::Value::Float(x * u.choose(&[-1.0, 1e-9, 1e9, 1e300])?);
            } else {
                *target = number(u)?;
            }
        }
        8 | 9 => {
            // a mild change that often stays valid, so that runs are reached
            if let Some(x) = target.as_float() {
                *target = toml::Value::Float(x * u.choose(&[0.5, 0.9, 1.1, 2.0])?);
            } else if let toml::Value::String(s) = target {
                s.push_str("_b");
            }
        }
        _ => {
            if let Some(x) = target.as_float().or(target.as_integer().map(|i| i as f64)) {
                *target = toml::Value::Float(x * u.choose(&[0.0, -1.0, 1e-6, 1e6, 1e300])?);
            } else {
                *target = number(u)?;
            }
        }
    }
    Ok(())
}

/// Attribute values of an XML text: byte ranges between `="` and `"`.
fn attr_ranges(text: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i + 1 < b.len() {
        if b[i] == b'=' && b[i + 1] == b'"' {
            let start = i + 2;
            if let Some(len) = text[start..].find('"') {
                out.push((start, start + len));
                i = start + len;
            }
        }
        i += 1;
    }
    out
}

fn mutate_urdf(u: &mut Unstructured<'_>, text: &mut String) -> arbitrary::Result<()> {
    match u.int_in_range(0..=9)? {
        0..=5 => {
            let r = attr_ranges(text);
            if r.is_empty() {
                return Ok(());
            }
            let (a, b) = *u.choose(&r)?;
            let old = text[a..b].to_string();
            let n = old.split_whitespace().count().max(1);
            let new = match u.int_in_range(0..=5)? {
                0 => hostile_name(u)?,
                1 => String::new(),
                2 => "nan".into(),
                _ => (0..n)
                    .map(|_| {
                        let x = *u.choose(FLOATS).unwrap_or(&1.0);
                        format!("{x:e}")
                    })
                    .collect::<Vec<_>>()
                    .join(" "),
            };
            let new = new.replace('"', "'").replace(['<', '&'], "_");
            text.replace_range(a..b, &new);
        }
        6 => {
            // drop or duplicate a line
            let lines: Vec<&str> = text.lines().collect();
            let k = u.choose_index(lines.len().max(1))?;
            let mut v: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            if u.arbitrary()? {
                v.remove(k.min(v.len().saturating_sub(1)));
            } else if let Some(l) = v.get(k).cloned() {
                v.insert(k, l);
            }
            *text = v.join("\n");
        }
        7 => {
            // extra leaf links (toes, sensors) under random links
            let n = u.int_in_range(1..=6)?;
            let mut extra = String::new();
            let links: Vec<String> = text
                .match_indices("<link name=\"")
                .filter_map(|(i, m)| text[i + m.len()..].split('"').next().map(str::to_string))
                .collect();
            for k in 0..n {
                let parent = u.choose(&links).cloned().unwrap_or_else(|_| "torso".into());
                extra += &format!(
                    "<link name=\"fz{k}\"/><joint name=\"fzj{k}\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"fz{k}\"/></joint>\n"
                );
            }
            *text = text.replace("</robot>", &format!("{extra}</robot>"));
        }
        8 => {
            // a long chain hung under the first link
            let n = u.int_in_range(10..=3000)?;
            let mut extra = String::new();
            let first = text
                .split("<link name=\"")
                .nth(1)
                .and_then(|s| s.split('"').next())
                .unwrap_or("torso")
                .to_string();
            let mut parent = first;
            for k in 0..n {
                extra += &format!(
                    "<link name=\"c{k}\"><inertial><mass value=\"0.1\"/><inertia ixx=\"1e-3\" ixy=\"0\" ixz=\"0\" iyy=\"1e-3\" iyz=\"0\" izz=\"1e-3\"/></inertial></link><joint name=\"cj{k}\" type=\"continuous\"><parent link=\"{parent}\"/><child link=\"c{k}\"/><axis xyz=\"0 0 1\"/></joint>\n"
                );
                parent = format!("c{k}");
            }
            *text = text.replace("</robot>", &format!("{extra}</robot>"));
        }
        _ => {
            // cut the file
            let k = u.choose_index(text.len().max(1))?;
            let mut k = k.min(text.len());
            while !text.is_char_boundary(k) {
                k -= 1;
            }
            text.truncate(k);
        }
    }
    Ok(())
}

fn heightmap_csv(u: &mut Unstructured<'_>) -> arbitrary::Result<String> {
    let nx = u.int_in_range(1..=40)?;
    let ny = u.int_in_range(1..=40)?;
    let mut s = String::from("# fuzz\n");
    for j in 0..ny {
        let cols = if u.ratio(1, 20)? { nx + 1 } else { nx };
        let row: Vec<String> = (0..cols)
            .map(|i| {
                if u.ratio(1, 30).unwrap_or(false) {
                    let x = *u.choose(FLOATS).unwrap_or(&0.0);
                    format!("{x}")
                } else if u.ratio(1, 200).unwrap_or(false) {
                    "abc".into()
                } else {
                    format!("{}", ((i * 7 + j * 3) % 11) as f64 * 0.01)
                }
            })
            .collect();
        s += &row.join(",");
        s += "\n";
    }
    Ok(s)
}

fn heightmap_png(u: &mut Unstructured<'_>, seed_png: &[u8]) -> arbitrary::Result<Vec<u8>> {
    let mut b = seed_png.to_vec();
    match u.int_in_range(0..=2)? {
        0 => {
            for _ in 0..u.int_in_range(1..=8)? {
                let k = u.choose_index(b.len())?;
                b[k] = u.arbitrary()?;
            }
        }
        1 => {
            let k = u.choose_index(b.len())?;
            b.truncate(k);
        }
        _ => {
            // a small image of another kind or size
            let (w, h) = (u.int_in_range(1..=64)?, u.int_in_range(1..=64)?);
            let color = *u.choose(&[png::ColorType::Grayscale, png::ColorType::Rgb])?;
            let depth = *u.choose(&[png::BitDepth::Eight, png::BitDepth::Sixteen])?;
            let ch = if color == png::ColorType::Rgb { 3 } else { 1 };
            let bytes = if depth == png::BitDepth::Sixteen {
                2
            } else {
                1
            };
            let mut data = vec![0u8; (w * h * ch * bytes) as usize];
            for (i, x) in data.iter_mut().enumerate() {
                *x = (i * 31 % 251) as u8;
            }
            let mut out = Vec::new();
            {
                let mut enc = png::Encoder::new(&mut out, w, h);
                enc.set_color(color);
                enc.set_depth(depth);
                let mut wr = enc
                    .write_header()
                    .map_err(|_| arbitrary::Error::IncorrectFormat)?;
                wr.write_image_data(&data)
                    .map_err(|_| arbitrary::Error::IncorrectFormat)?;
            }
            b = out;
        }
    }
    Ok(b)
}

const URDF_SCENARIO: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.05
default_ground = "concrete"

[[robots]]
name = "rex"
model = "robot.urdf"
[robots.controller]
kind = "joint_pd"
kp_nm_per_rad = 50.0
"#;

fn heightmap_scenario(file: &str, h: f64, v: f64) -> String {
    format!(
        r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.05
default_ground = "concrete"

[[terrains]]
name = "hm"
kind = "heightmap"
file = "{file}"
horizontal_scale_m = {h:?}
vertical_scale_m = {v:?}

[[robots]]
name = "rex"
model = "quad16"
terrain = "hm"
[robots.controller]
kind = "joint_pd"
kp_nm_per_rad = 300.0
"#
    )
}

/// Which kind of input a case mutates.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Target {
    Scenario,
    Urdf,
    Heightmap,
}

/// Writes case `k`'s inputs into `dir`; returns the scenario's path.
fn make_case(seeds: &Seeds, seed: u64, k: u64, dir: &Path) -> (Target, PathBuf) {
    let mut rng =
        rand_chacha::ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9).wrapping_add(k));
    let mut bytes = vec![0u8; 4096];
    rng.fill_bytes(&mut bytes);
    let mut u = Unstructured::new(&bytes);
    let target = match k % 10 {
        0..=5 => Target::Scenario,
        6..=8 => Target::Urdf,
        _ => Target::Heightmap,
    };
    let scn = dir.join("s.toml");
    match target {
        Target::Scenario => {
            let (_, t) = u.choose(&seeds.scenarios).unwrap_or(&seeds.scenarios[0]);
            let mut v = toml::Value::Table(t.clone());
            for _ in 0..u
                .int_in_range(0..=env_u64("QUADSIM_FUZZ_MUTATIONS", 3))
                .unwrap_or(1)
            {
                let _ = mutate_toml(&mut u, &mut v);
            }
            let text = toml::to_string(&v).unwrap_or_else(|_| "format_version = 1\n".into());
            std::fs::write(&scn, text).unwrap();
        }
        Target::Urdf => {
            let (_, t) = u.choose(&seeds.urdfs).unwrap_or(&seeds.urdfs[0]);
            let mut text = t.clone();
            for _ in 0..u.int_in_range(1..=3).unwrap_or(1) {
                let _ = mutate_urdf(&mut u, &mut text);
            }
            std::fs::write(dir.join("robot.urdf"), text).unwrap();
            let mut s = URDF_SCENARIO.to_string();
            if u.ratio(1, 4).unwrap_or(false) {
                s = s.replace("model = \"robot.urdf\"", "model = \"robot.urdf\"\nfeet = [\"LF_foot\", \"RF_foot\", \"LH_foot\", \"RH_foot\"]");
            }
            std::fs::write(&scn, s).unwrap();
        }
        Target::Heightmap => {
            let h = if u.ratio(1, 5).unwrap_or(false) {
                *u.choose(FLOATS).unwrap_or(&0.1)
            } else {
                0.1
            };
            let v = if u.ratio(1, 5).unwrap_or(false) {
                *u.choose(FLOATS).unwrap_or(&1.0)
            } else {
                0.05
            };
            let file = if u.arbitrary().unwrap_or(false) {
                let c = heightmap_csv(&mut u).unwrap_or_default();
                std::fs::write(dir.join("h.csv"), c).unwrap();
                "h.csv"
            } else {
                let p = heightmap_png(&mut u, &seeds.png).unwrap_or_default();
                std::fs::write(dir.join("h.png"), p).unwrap();
                "h.png"
            };
            std::fs::write(&scn, heightmap_scenario(file, h, v)).unwrap();
        }
    }
    (target, scn)
}

#[derive(Debug, Default)]
struct Stats {
    cases: u64,
    by_target: [u64; 3],
    check_ok: u64,
    runs: u64,
    run_ok: u64,
    skipped_long: u64,
    failures: Vec<String>,
    slowest: (Duration, u64),
    peak_bytes: (isize, u64),
}

/// How far a case went.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Reached {
    /// `check` refused it (with an error message).
    Refused,
    /// `check` passed; the run would be too long for the campaign.
    CheckedOnly,
    /// `check` passed and the short run ran (to an error or to the end).
    Ran,
}

/// `check`, then a short run when it passed.
fn run_case(scn: &Path, out: &Path, report: bool) -> Reached {
    let check = quadsim::cli::run::check(quadsim::cli::run::CheckArgs {
        scenario: scn.to_path_buf(),
    });
    if check.is_err() {
        return Reached::Refused;
    }
    let Ok(s) = quadsim::scenario::load_scenario(scn) else {
        panic!("check passed but the scenario does not load");
    };
    let duration = 0.02f64.min(s.file.world.duration_s);
    let robots = s.file.robots.len().max(1) as f64;
    if duration / s.file.world.dt_s * robots > RUN_ROBOT_STEPS {
        return Reached::CheckedOnly;
    }
    let mut args = vec![
        "quadsim".to_string(),
        "run".into(),
        scn.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--quiet".into(),
        "--no-monitor".into(),
        "--threads".into(),
        "1".into(),
        "--duration".into(),
        format!("{duration}"),
    ];
    if !report {
        args.push("--no-report".into());
    }
    let cli = <quadsim::cli::Cli as clap::Parser>::try_parse_from(args).expect("arguments");
    let quadsim::cli::Command::Run(a) = cli.command else {
        unreachable!()
    };
    let _ = quadsim::cli::run::run_scenario(&a);
    Reached::Ran
}

/// Files and directories under `root` (relative), sorted.
fn listing(root: &Path) -> Vec<String> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(root) {
        for e in rd.flatten() {
            out.push(e.file_name().to_string_lossy().into_owned());
        }
    }
    out.sort();
    out
}

#[test]
fn fuzz_campaign_finds_no_panic_hang_memory_blowup_or_stray_write() {
    let seed = env_u64("QUADSIM_FUZZ_SEED", 29);
    let cases = env_u64("QUADSIM_FUZZ_CASES", 3000);
    let budget = Duration::from_secs(env_u64("QUADSIM_FUZZ_SECONDS", 170));
    let only = std::env::var("QUADSIM_FUZZ_ONLY")
        .ok()
        .and_then(|v| v.parse::<u64>().ok());
    let seeds = seeds();
    let root = std::env::temp_dir().join(format!("quadsim-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let failures_dir = repo().join("target/fuzz-failures");

    // a watchdog: a case that never ends stops the campaign, naming it
    static CURRENT: AtomicU64 = AtomicU64::new(u64::MAX);
    static STARTED_MS: AtomicU64 = AtomicU64::new(0);
    let t0 = Instant::now();
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_secs(1));
            let k = CURRENT.load(Ordering::Relaxed);
            let since = (t0.elapsed().as_millis() as u64)
                .saturating_sub(STARTED_MS.load(Ordering::Relaxed));
            if k != u64::MAX && since > HANG_ABORT.as_millis() as u64 {
                eprintln!(
                    "fuzz: case {k} (seed {seed}) hangs past {HANG_ABORT:?}: QUADSIM_FUZZ_ONLY={k}"
                );
                std::process::exit(3);
            }
        }
    });

    let mut stats = Stats::default();
    let range: Vec<u64> = match only {
        Some(k) => vec![k],
        None => (0..cases).collect(),
    };
    for k in range {
        if t0.elapsed() > budget {
            println!(
                "fuzz: time budget {budget:?} reached after {} cases",
                stats.cases
            );
            break;
        }
        let case = root.join(format!("c{k}"));
        let (inp, out) = (case.join("in"), case.join("out"));
        std::fs::create_dir_all(&inp).unwrap();
        let (target, scn) = make_case(&seeds, seed, k, &inp);
        stats.cases += 1;
        stats.by_target[target as usize] += 1;
        let base = LIVE.load(Ordering::Relaxed);
        PEAK.store(base, Ordering::Relaxed);
        STARTED_MS.store(t0.elapsed().as_millis() as u64, Ordering::Relaxed);
        CURRENT.store(k, Ordering::Relaxed);
        let start = Instant::now();
        let report = k % 8 == 0;
        let res = std::panic::catch_unwind(|| run_case(&scn, &out, report));
        let took = start.elapsed();
        CURRENT.store(u64::MAX, Ordering::Relaxed);
        let peak = PEAK.load(Ordering::Relaxed) - base;
        if took > stats.slowest.0 {
            stats.slowest = (took, k);
        }
        if peak > stats.peak_bytes.0 {
            stats.peak_bytes = (peak, k);
        }
        let mut why = Vec::new();
        match res {
            Err(_) => why.push("panic".to_string()),
            Ok(r) => {
                stats.check_ok += (r != Reached::Refused) as u64;
                stats.skipped_long += (r == Reached::CheckedOnly) as u64;
                stats.runs += (r == Reached::Ran) as u64;
                stats.run_ok += (r == Reached::Ran && out.join("summary.json").exists()) as u64;
            }
        }
        if took > CASE_LIMIT {
            why.push(format!("took {took:?}"));
        }
        if peak > MEMORY_LIMIT_BYTES {
            why.push(format!("{peak} bytes of heap"));
        }
        // nothing written beside the case's own `in` and `out`, nor above it
        let beside: Vec<String> = listing(&case)
            .into_iter()
            .filter(|n| n != "in" && n != "out")
            .collect();
        let above: Vec<String> = listing(&root)
            .into_iter()
            .filter(|n| n != &format!("c{k}"))
            .collect();
        if !beside.is_empty() || !above.is_empty() || Path::new(ABS_PROBE).exists() {
            why.push(format!("wrote outside --out: {beside:?} {above:?}"));
        }
        if why.is_empty() {
            let _ = std::fs::remove_dir_all(&case);
        } else {
            let keep = failures_dir.join(format!("{seed}-{k}"));
            let _ = std::fs::create_dir_all(&keep);
            for f in listing(&inp) {
                let _ = std::fs::copy(inp.join(&f), keep.join(&f));
            }
            let msg = format!(
                "case {k} ({target:?}): {} — inputs in {}",
                why.join(", "),
                keep.display()
            );
            eprintln!("fuzz: {msg}");
            stats.failures.push(msg);
            let _ = std::fs::remove_dir_all(&case);
            for n in listing(&root) {
                let _ = std::fs::remove_dir_all(root.join(&n));
                let _ = std::fs::remove_file(root.join(&n));
            }
        }
        if stats.cases % 250 == 0 {
            println!(
                "fuzz: {} cases, {} failures, {:.0} s",
                stats.cases,
                stats.failures.len(),
                t0.elapsed().as_secs_f64()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&root);
    println!(
        "fuzz campaign (seed {seed}): {} cases (scenario {}, URDF {}, heightmap {}) in {:.1} s; \
         check passed {}; short runs {} ({} wrote summary.json); skipped long runs {}; \
         slowest case {:.2} s (#{}); largest heap {:.1} MB (#{}); failures {}",
        stats.cases,
        stats.by_target[0],
        stats.by_target[1],
        stats.by_target[2],
        t0.elapsed().as_secs_f64(),
        stats.check_ok,
        stats.runs,
        stats.run_ok,
        stats.skipped_long,
        stats.slowest.0.as_secs_f64(),
        stats.slowest.1,
        stats.peak_bytes.0 as f64 / 1e6,
        stats.peak_bytes.1,
        stats.failures.len()
    );
    assert!(stats.failures.is_empty(), "{:#?}", stats.failures);
}
