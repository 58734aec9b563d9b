//! Herds (`[[herds]]`): expansion of the template and its variations, errors
//! that name the varied path, the shipped herd, and determinism of a mixed,
//! trotting herd across thread counts and robot order, down to the bytes of
//! each robot's log channels.

use std::collections::BTreeMap;
use std::path::Path;

use quadsim::log::read::read_log;
use quadsim::log::{RunOutcome, start_run_log};
use quadsim::scenario::{ScenarioError, load_scenario, parse_scenario};
use quadsim::world::{Overrides, build_world};

const WORLD: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 1.0
seed = 3
controller_rate_hz = 500
default_ground = "concrete"

[[terrains]]
name = "flat"
kind = "flat"
origin_m = [0.0, 0.0, 0.0]
extent_m = [10.0, 10.0]

[[terrains]]
name = "sine"
kind = "sine"
amplitude_m = 0.01
wavelength_m = 2.0
origin_m = [0.0, 20.0, 0.0]
extent_m = [10.0, 10.0]
"#;

const TROTTERS: &str = r#"
[[herds]]
name = "trot"
count = 5
layout = { kind = "lanes", terrains = ["flat", "sine"], spacing_m = [0.0, 1.5], origin_m = [0.0, -3.0] }
[herds.robot]
model = "quad16"
[herds.robot.controller]
kind = "vmc"
[herds.vary]
"controller.v_x_mps" = { from = 0.2, to = 0.5, steps = 4 }
"params.torso.mass_kg" = { uniform = [9.5, 10.5] }
"#;

const STANDERS: &str = r#"
[[herds]]
name = "small"
count = 3
layout = { kind = "grid", columns = 3, spacing_m = [1.0, 1.0], origin_m = [-4.0, 3.0] }
[herds.robot]
model = "quad12"
[herds.robot.controller]
kind = "joint_pd"
[herds.vary]
"controller.bandwidth_hz" = [2.5, 3.5]
"#;

fn parse(src: &str) -> Result<quadsim::scenario::Scenario, ScenarioError> {
    parse_scenario(Path::new("herd_test.toml"), src.to_string())
}

#[test]
fn a_herd_expands_into_named_varied_robots_in_lanes() {
    let scn = parse(&format!("{WORLD}{TROTTERS}{STANDERS}")).unwrap();
    let r = &scn.file.robots;
    let names: Vec<&str> = r.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "trot-000",
            "trot-001",
            "trot-002",
            "trot-003",
            "trot-004",
            "small-000",
            "small-001",
            "small-002"
        ]
    );
    // ranges cycle with the robot index; lanes alternate; slots advance per lane
    let v: Vec<f64> = r[..5]
        .iter()
        .map(|r| r.controller.params["v_x_mps"].as_float().unwrap())
        .collect();
    let want = [0.2, 0.3, 0.4, 0.5, 0.2];
    assert!(
        v.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
        "{v:?}"
    );
    let lanes: Vec<&str> = r[..5]
        .iter()
        .map(|r| r.terrain.as_deref().unwrap())
        .collect();
    assert_eq!(lanes, ["flat", "sine", "flat", "sine", "flat"]);
    let xy: Vec<[f64; 2]> = r[..5].iter().map(|r| r.start_xy_m.unwrap()).collect();
    assert_eq!(
        xy,
        [
            [0.0, -3.0],
            [0.0, -3.0],
            [0.0, -1.5],
            [0.0, -1.5],
            [0.0, 0.0]
        ]
    );
    // uniform draws: in range, different per robot, the same on every load
    let m: Vec<f64> = r[..5].iter().map(|r| r.params["torso.mass_kg"]).collect();
    assert!(m.iter().all(|x| (9.5..10.5).contains(x)), "{m:?}");
    assert!(m.windows(2).all(|w| w[0] != w[1]), "{m:?}");
    let again = parse(&format!("{WORLD}{TROTTERS}{STANDERS}")).unwrap();
    let m2: Vec<f64> = again.file.robots[..5]
        .iter()
        .map(|r| r.params["torso.mass_kg"])
        .collect();
    assert_eq!(m, m2);
    // grid layout: 3 columns along y
    let g: Vec<[f64; 2]> = r[5..].iter().map(|r| r.start_xy_m.unwrap()).collect();
    assert_eq!(g, [[-4.0, 3.0], [-4.0, 4.0], [-4.0, 5.0]]);
    let bw: Vec<f64> = r[5..]
        .iter()
        .map(|r| r.controller.params["bandwidth_hz"].as_float().unwrap())
        .collect();
    assert_eq!(bw, [2.5, 3.5, 2.5]);
}

#[test]
fn a_grid_combination_takes_every_pair_once() {
    let src = format!(
        "{WORLD}
[[herds]]
name = \"g\"
combine = \"grid\"
[herds.robot]
model = \"quad16\"
[herds.robot.controller]
kind = \"vmc\"
[herds.vary]
\"controller.v_x_mps\" = [0.1, 0.2]
\"controller.height_m\" = {{ from = 0.45, to = 0.55, steps = 3 }}
"
    );
    let scn = parse(&src).unwrap();
    let pairs: Vec<(f64, f64)> = scn
        .file
        .robots
        .iter()
        .map(|r| {
            let p = &r.controller.params;
            (
                p["v_x_mps"].as_float().unwrap(),
                (p["height_m"].as_float().unwrap() * 100.0).round() / 100.0,
            )
        })
        .collect();
    assert_eq!(
        pairs,
        // paths in alphabetical order, the first varying slowest
        [
            (0.1, 0.45),
            (0.2, 0.45),
            (0.1, 0.5),
            (0.2, 0.5),
            (0.1, 0.55),
            (0.2, 0.55)
        ]
    );
}

#[test]
fn herd_errors_name_the_varied_path_and_its_line() {
    let cases: [(&str, &str, &str); 6] = [
        (
            "\"controller.bogus_gain\" = [1.0, 2.0]",
            "herds[0].vary.\"controller.bogus_gain\"",
            "bogus_gain",
        ),
        (
            "\"controller.v_x_mps\" = { from = 0.1, to = 0.5, steps = 0 }",
            "herds[0].vary.\"controller.v_x_mps\"",
            "empty range",
        ),
        (
            "\"params.torso.mass_kg\" = { uniform = [12.0, 9.0] }",
            "herds[0].vary.\"params.torso.mass_kg\"",
            "empty range",
        ),
        (
            "\"model.size\" = [1.0]",
            "herds[0].vary.\"model.size\"",
            "not a table",
        ),
        (
            "\"params.torso.mass_kg\" = [-3.0, 10.0]",
            "herds[0].vary.\"params.torso.mass_kg\"",
            "",
        ),
        (
            "\"name\" = [\"a\", \"b\"]",
            "herds[0].vary.name",
            "cannot vary",
        ),
    ];
    for (vary, key_path, msg) in cases {
        let src = format!(
            "{WORLD}
[[herds]]
name = \"h\"
count = 2
[herds.robot]
model = \"quad16\"
[herds.robot.controller]
kind = \"vmc\"
[herds.vary]
{vary}
"
        );
        let e = match parse(&src) {
            Err(e) => e,
            // values only the model can judge fail when the world is built
            Ok(scn) => build_world(&scn, Overrides::default()).unwrap_err(),
        };
        assert_eq!(e.key_path, key_path, "{vary}: {e}");
        assert!(e.line > 0, "{vary}: no line in {e}");
        assert!(e.to_string().contains(msg), "{vary}: {e}");
    }
    for (extra, key_path) in [
        (
            "layout = { kind = \"lanes\", terrains = [\"moon\"] }",
            "herds[0].layout.terrains[0]",
        ),
        ("layout = { kind = \"spiral\" }", "herds[0].layout.kind"),
        ("count = 0", "herds[0].count"),
    ] {
        let src = format!(
            "{WORLD}
[[herds]]
name = \"h\"
{extra}
[herds.robot]
model = \"quad16\"
"
        );
        let src = if extra.starts_with("count") {
            src
        } else {
            src.replace("name = \"h\"\n", "name = \"h\"\ncount = 2\n")
        };
        let e = parse(&src).unwrap_err();
        assert_eq!(e.key_path, key_path, "{e}");
        assert!(e.line > 0, "{e}");
    }
}

#[test]
fn the_shipped_herd_mixes_both_robots_on_three_terrains() {
    let scn = load_scenario(Path::new("scenarios/herd.toml")).unwrap();
    let r = &scn.file.robots;
    assert!(r.len() >= 100, "{} robots", r.len());
    for model in ["quad16", "quad12"] {
        assert!(r.iter().any(|r| r.model == model), "no {model}");
    }
    let mut terrains: Vec<&str> = r.iter().filter_map(|r| r.terrain.as_deref()).collect();
    terrains.sort();
    terrains.dedup();
    assert!(terrains.len() >= 3, "{terrains:?}");
    build_world(&scn, Overrides::default()).unwrap();
}

/// Per robot name: the final state's bits, the summary metrics and every
/// message of the robot's own log channels.
type Outcome = BTreeMap<String, (Vec<u64>, String, Vec<(String, u64, Vec<u8>)>)>;

fn run(src: &str, threads: usize, tag: &str) -> Outcome {
    let dir = std::env::temp_dir().join(format!("quadsim-herd-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scn = parse_scenario(&dir.join("herd.toml"), src.to_string()).unwrap();
    let mut w = build_world(
        &scn,
        Overrides {
            threads,
            ..Default::default()
        },
    )
    .unwrap();
    let path = dir.join("log.mcap");
    let log = start_run_log(&scn, &mut w, &path, 4).unwrap();
    w.sim.run(w.steps);
    log.finish(&mut w, &RunOutcome::default()).unwrap();
    let c = read_log(&path).unwrap();
    assert_eq!(c.error, None);
    let mut out = Outcome::new();
    for (name, e) in &w.robots {
        let r = w.sim.robot(*e).unwrap();
        let bits = r
            .state
            .q
            .iter()
            .chain(&r.state.v)
            .map(|x| x.to_bits())
            .collect();
        let metrics = format!("{:?}", r.run.metrics.summary());
        let prefix = format!("/{name}/");
        let msgs: Vec<(String, u64, Vec<u8>)> = c
            .messages
            .iter()
            .filter(|m| m.topic.starts_with(&prefix))
            .map(|m| (m.topic.clone(), m.log_time_ns, m.data.clone()))
            .collect();
        assert!(!msgs.is_empty(), "no log channels for {name}");
        out.insert(name.clone(), (bits, metrics, msgs));
    }
    let _ = std::fs::remove_dir_all(dir);
    out
}

#[test]
fn a_mixed_trotting_herd_is_bit_identical_across_threads_and_order() {
    let src =
        format!("{WORLD}{TROTTERS}{STANDERS}").replace("duration_s = 1.0", "duration_s = 0.6");
    let reference = run(&src, 1, "t1");
    assert_eq!(reference.len(), 8);
    let two = run(&src, 2, "t2");
    assert!(two == reference, "2 threads differ");
    let swapped =
        format!("{WORLD}{STANDERS}{TROTTERS}").replace("duration_s = 1.0", "duration_s = 0.6");
    let swapped = run(&swapped, 2, "swap");
    assert!(swapped == reference, "herd order changes results");
}

#[test]
fn a_hundred_trotting_robots_on_flat_ground_do_not_fall() {
    // 100 quad16 at 0.3–0.5 m/s with torso masses 9–11 kg, 10 s, 2 threads
    // (at 0.6 m/s, 3 of 100 fell between 4.5 and 7.5 s: CHANGELOG.md, the README's former status)
    let src = format!(
        "{}
[[herds]]
name = \"flat\"
count = 100
layout = {{ kind = \"grid\", columns = 10, spacing_m = [1.5, 1.0], origin_m = [-4.0, -4.5] }}
[herds.robot]
model = \"quad16\"
contact_points = [\"knees\", \"torso\"]
[herds.robot.controller]
kind = \"vmc\"
[herds.vary]
\"controller.v_x_mps\" = {{ from = 0.3, to = 0.5, steps = 5 }}
\"params.torso.mass_kg\" = {{ uniform = [9.0, 11.0] }}
",
        WORLD
            .replace("duration_s = 1.0", "duration_s = 10.0")
            .replace("extent_m = [10.0, 10.0]", "extent_m = [30.0, 12.0]")
    );
    let scn = parse(&src).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(2)).unwrap();
    assert_eq!(w.robots.len(), 100);
    w.sim.run(w.steps);
    let mut fallen = Vec::new();
    for (name, e) in &w.robots {
        let m = w.sim.robot(*e).unwrap().run.metrics.summary();
        if m.fell {
            fallen.push((name.clone(), m.fell_at_s));
        }
        assert!(m.distance_m > 2.0, "{name} walked {} m", m.distance_m);
    }
    assert!(fallen.is_empty(), "fell: {fallen:?}");
}
