//! Bad input never harms (issue 29): names that would write outside `--out`
//! are refused where they are read; physical nonsense in URDFs and scenarios
//! is refused by `check` and `run` alike with file, line and field; resources
//! are bounded; a diverging robot ends only its own run; scripted use of
//! `replay` and of a closed stdout ends quietly. Each test fails without its fix.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use quadsim::scenario::{ScenarioError, parse_scenario};
use quadsim::world::{Overrides, build_world};

const GOOD: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.05
default_ground = "concrete"

[[terrains]]
name = "floor"
kind = "flat"

[[robots]]
name = "rex"
model = "quad16"
terrain = "floor"
[robots.controller]
kind = "joint_pd"
kp_nm_per_rad = 300.0
"#;

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-safety-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn quadsim(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn line_of(src: &str, needle: &str) -> usize {
    src[..src.find(needle).expect("needle")]
        .matches('\n')
        .count()
        + 1
}

/// Parses and builds (what `check` and `run` both do); the first error.
fn load_err(src: &str) -> ScenarioError {
    let p = Path::new("bad.toml");
    match parse_scenario(p, src.to_string()) {
        Err(e) => e,
        Ok(s) => build_world(&s, Overrides::default()).expect_err("must be rejected"),
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

// ---- 1. names: no writes outside --out ------------------------------------

#[test]
fn names_that_climb_out_are_refused_with_file_line_and_field() {
    for bad in [
        "../../../X",
        "/tmp/abs",
        "a/b",
        "..",
        "with space",
        &"x".repeat(100_000),
    ] {
        let src = GOOD.replace("name = \"rex\"", &format!("name = \"{bad}\""));
        let e = load_err(&src);
        assert_eq!(e.key_path, "robots[0].name", "{e}");
        assert_eq!(e.line, line_of(&src, &format!("name = \"{bad}\"")), "{e}");
        assert!(e.to_string().len() < 400, "the message is short: {e}");
    }
    // terrains, payloads, herds, worlds
    let src = GOOD.replace("name = \"floor\"", "name = \"../floor\"");
    let src = src.replace("terrain = \"floor\"", "terrain = \"../floor\"");
    assert_eq!(load_err(&src).key_path, "terrains[0].name");
    let src = GOOD.replace("dt_s = 0.0005", "name = \"/etc/x\"\ndt_s = 0.0005");
    let e = load_err(&src);
    assert_eq!((e.key_path.as_str(), e.line), ("world.name", 3), "{e}");
    let src = format!(
        "{GOOD}\n[[robots.payloads]]\nname = \"../box\"\nmass_kg = 1.0\nshape = \"box\"\nsize_m = [0.1, 0.1, 0.1]\n"
    );
    assert_eq!(load_err(&src).key_path, "robots[0].payloads[0].name");
    let herd = "[[herds]]\nname = \"../h\"\ncount = 2\n[herds.robot]\nmodel = \"quad16\"\n";
    let src = GOOD.replace("[[robots]]", &format!("{herd}\n[[robots]]"));
    assert_eq!(load_err(&src).key_path, "herds[0].name");
}

#[test]
fn a_report_never_writes_outside_its_directory() {
    // names in a log are not checked by a scenario: the report's file names
    // are made safe and checked to lie inside the plots directory
    let d = dir("plots");
    let fig = quadsim::report::plots::Figure {
        stem: "../../../X_com".into(),
        panels: Vec::new(),
        columns: 1,
    };
    let plots = d.join("out").join("plots");
    std::fs::create_dir_all(&plots).unwrap();
    let written = quadsim::report::plots::write_figure(&fig, &plots).unwrap();
    for w in &written {
        assert!(quadsim::names::is_inside(&plots, w), "{}", w.display());
        assert!(w.exists());
    }
    assert!(!d.join("X_com.svg").exists() && !Path::new("/X_com.svg").exists());
}

// ---- 2. physical nonsense is refused at load -------------------------------

fn urdf_with(edit: impl Fn(String) -> String) -> (PathBuf, String) {
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/models/quad16.urdf"
    ))
    .unwrap();
    let text = edit(src);
    let d = dir(&format!("urdf{}", text.len()));
    let p = d.join("robot.urdf");
    std::fs::write(&p, &text).unwrap();
    (p, text)
}

fn urdf_err(edit: impl Fn(String) -> String) -> (String, String) {
    let (p, text) = urdf_with(edit);
    let e = quadsim::urdf::load_urdf(&p, &Default::default())
        .expect_err("must be rejected")
        .to_string();
    (e, text)
}

#[test]
fn non_physical_urdfs_are_refused_with_file_line_and_field() {
    // non-positive-definite inertia: ixy = -1 on the torso
    let (e, text) = urdf_err(|s| s.replacen("ixy=\"0\"", "ixy=\"-1\"", 1));
    let line = line_of(&text, "<link name=\"torso\"");
    assert!(e.contains("robot.urdf"), "{e}");
    assert!(e.contains(&format!("link 'torso' (line {line})")), "{e}");
    assert!(
        e.contains("<inertial><inertia>") && e.contains("positive definite"),
        "{e}"
    );
    // a mass of 1e308
    let (e, _) = urdf_err(|s| s.replacen("<mass value=\"10\"/>", "<mass value=\"1e308\"/>", 1));
    assert!(
        e.contains("<inertial><mass value>") && e.contains("torso"),
        "{e}"
    );
    // a joint origin at 1e308
    let (e, _) = urdf_err(|s| s.replacen("xyz=\"0.25 0.15 0\"", "xyz=\"1e308 0.15 0\"", 1));
    assert!(
        e.contains("joint 'LF_hip_roll'") && e.contains("<origin xyz>"),
        "{e}"
    );
    // the triangle inequality: izz > ixx + iyy
    let (e, _) = urdf_err(|s| s.replacen("izz=\"0.375\"", "izz=\"0.5\"", 1));
    assert!(e.contains("triangle inequality"), "{e}");
    // a negative box size
    let (e, _) = urdf_err(|s| s.replace("size=\"0.6 0.3 0.1\"", "size=\"-0.6 0.3 0.1\""));
    assert!(e.contains("box size") && e.contains("><geometry>"), "{e}");
}

#[test]
fn check_refuses_what_run_would_panic_on() {
    // the issue's case: `check` said ok, `run` panicked in the integrator
    let (p, _) = urdf_with(|s| s.replacen("ixy=\"0\"", "ixy=\"-1\"", 1));
    let d = p.parent().unwrap();
    let scn = GOOD.replace("model = \"quad16\"", "model = \"robot.urdf\"");
    std::fs::write(d.join("s.toml"), scn).unwrap();
    for args in [
        &["check", "s.toml"][..],
        &["run", "s.toml", "--no-monitor", "--quiet", "--out", "out"][..],
    ] {
        let (cmd, o) = (args[0], quadsim(args, d));
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        assert!(stderr(&o).contains("positive definite"), "{}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    }
}

#[test]
fn nonsense_scenario_values_are_refused_or_warned() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "duration_s = 0.05",
            "duration_s = 1e300",
            "world.duration_s",
        ),
        (
            "terrain = \"floor\"",
            "terrain = \"floor\"\nstart_position_m = [1e300, 0.0, 0.5]",
            "robots[0].start_position_m",
        ),
        (
            "default_ground = \"concrete\"",
            "default_ground = { stiffness_n_per_m = 1e5, damping_ns_per_m = 1e3, friction = 9.2e18 }",
            "world.default_ground.friction",
        ),
        (
            "kind = \"joint_pd\"\nkp_nm_per_rad = 300.0",
            "kind = \"vmc\"\nv_x_mps = 1e9",
            "robots[0].controller.v_x_mps",
        ),
        (
            "model = \"quad16\"",
            "model = \"quad16\"\nparams = { \"torso.mass_kg\" = 0.0 }",
            "robots[0].params.\"torso.mass_kg\"",
        ),
    ];
    for (from, to, key) in cases {
        let src = GOOD.replace(from, to);
        let e = load_err(&src);
        assert_eq!(&e.key_path, key, "{e}");
        assert!(e.line > 0, "{e}");
    }
    // legal but suspect: a warning with the numbers
    let src = GOOD
        .replace("dt_s = 0.0005", "dt_s = 1e-9\ncontroller_rate_hz = 1e6")
        .replace("duration_s = 0.05", "duration_s = 1e-6");
    let s = parse_scenario(Path::new("w.toml"), src).unwrap();
    let w = build_world(&s, Overrides::default()).unwrap();
    assert!(
        w.warnings
            .iter()
            .any(|m| m.contains("world.dt_s = 0.000000001") || m.contains("1e-9")),
        "{:?}",
        w.warnings
    );
}

#[test]
fn heightmaps_out_of_bounds_are_refused() {
    let d = dir("hm");
    std::fs::write(d.join("h.csv"), "0,0,0\n0,1e308,0\n0,0,0\n").unwrap();
    let terrain = "[[terrains]]\nname = \"hm\"\nkind = \"heightmap\"\nfile = \"h.csv\"\nhorizontal_scale_m = 0.5\nvertical_scale_m = 1.0\n";
    let src = GOOD.replace("[[robots]]", &format!("{terrain}\n[[robots]]"));
    let p = d.join("s.toml");
    let s = parse_scenario(&p, src.clone()).unwrap();
    let e = build_world(&s, Overrides::default()).unwrap_err();
    assert_eq!(e.key_path, "terrains[1].file", "{e}");
    std::fs::write(d.join("h.csv"), "0,0,0\n0,1,0\n0,0,0\n").unwrap();
    let src = src.replace("horizontal_scale_m = 0.5", "horizontal_scale_m = 1e-300");
    let s = parse_scenario(&p, src).unwrap();
    let e = build_world(&s, Overrides::default()).unwrap_err();
    assert_eq!(e.key_path, "terrains[1].horizontal_scale_m", "{e}");
}

#[test]
fn extra_leaf_links_without_feet_are_an_error_not_a_panic() {
    // a toe link below each foot's shank plus a sensor link on the torso:
    // more leaf links than a quadruped's four feet
    let (p, _) = urdf_with(|s| {
        s.replace(
            "</robot>",
            r#"  <link name="imu"/>
  <joint name="imu_mount" type="fixed"><parent link="torso"/><child link="imu"/></joint>
</robot>"#,
        )
    });
    let d = p.parent().unwrap();
    let scn = GOOD.replace("model = \"quad16\"", "model = \"robot.urdf\"");
    std::fs::write(d.join("s.toml"), &scn).unwrap();
    let o = quadsim(&["check", "s.toml"], d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("feet") && stderr(&o).contains("imu"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_singular_model_in_hybrid_dynamics_is_nan_not_a_panic() {
    use quadsim::engine::description::{JointDesc, JointKind, LinkDesc, RobotDescription};
    use quadsim::engine::model::{BaseKind, Model};
    use quadsim::engine::spatial::Transform;
    let mut d = RobotDescription::new("massless");
    d.links.push(LinkDesc::new("base"));
    d.links.push(LinkDesc::new("leg"));
    d.joints.push(JointDesc::new(
        "j",
        JointKind::Revolute {
            axis: glam::DVec3::X,
        },
        "base",
        "leg",
        Transform::default(),
    ));
    let m = Model::from_description(&d, BaseKind::Floating).unwrap();
    let mut data = quadsim::engine::Data::new(&m);
    let q = m.neutral_q();
    let v = vec![0.0; m.nv];
    quadsim::engine::kinematics::forward_kinematics(&m, &mut data, &q, &v);
    let mut tau = vec![0.0; m.nv];
    let mut a = vec![0.0; m.nv];
    quadsim::engine::integrate::hybrid_acceleration(&m, &mut data, &v, &mut tau, &mut a);
    assert!(a[..6].iter().all(|x| x.is_nan()), "{a:?}");
}

// ---- 3. no lost results -----------------------------------------------------

#[test]
fn a_sweep_into_a_file_fails_before_running_anything() {
    let d = dir("sweepout");
    std::fs::write(d.join("base.toml"), GOOD).unwrap();
    std::fs::write(
        d.join("s.toml"),
        "format_version = 1\nkind = \"sweep\"\nbase = \"base.toml\"\nduration_s = 30.0\n[vary]\n\"robots[0].controller.kp_nm_per_rad\" = [200.0, 300.0, 400.0, 500.0]\n",
    )
    .unwrap();
    std::fs::write(d.join("taken"), "a file").unwrap();
    let t = Instant::now();
    let o = quadsim(&["sweep", "s.toml", "--out", "taken", "--quiet"], &d);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("taken"), "{}", stderr(&o));
    // four 30 s variants would take minutes
    assert!(t.elapsed() < Duration::from_secs(20), "{:?}", t.elapsed());
}

#[test]
fn one_diverging_robot_ends_only_its_own_run() {
    // rex stands on a ground a million times stiffer than concrete (its
    // contact explodes at this dt); bee stands on concrete beside it
    let src = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.3
default_ground = "concrete"

[[terrains]]
name = "hard"
kind = "flat"
origin_m = [0.0, 0.0, 0.0]
extent_m = [2.0, 2.0]
ground = { stiffness_n_per_m = 1.0e11, damping_ns_per_m = 0.0, friction = 0.8 }

[[terrains]]
name = "soft"
kind = "flat"
origin_m = [10.0, 0.0, 0.0]
extent_m = [2.0, 2.0]

[[robots]]
name = "rex"
model = "quad16"
terrain = "hard"
[robots.actuators]
kind = "ideal"
[robots.controller]
kind = "joint_pd"
kp_nm_per_rad = 300.0

[[robots]]
name = "bee"
model = "quad16"
terrain = "soft"
[robots.controller]
kind = "joint_pd"
kp_nm_per_rad = 300.0
"#;
    let d = dir("diverge");
    std::fs::write(d.join("s.toml"), src).unwrap();
    let o = quadsim(
        &["run", "s.toml", "--out", "out", "--quiet", "--no-monitor"],
        &d,
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("robot 'rex' diverged"), "{err}");
    assert!(
        err.contains("likely cause: the ground contact is unstable"),
        "{err}"
    );
    assert!(err.contains("the other 1 robot(s) ran to the end"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["steps"], 600, "the run went on to the end");
    let robots = summary["robots"].as_array().unwrap();
    let rex = robots.iter().find(|r| r["name"] == "rex").unwrap();
    let bee = robots.iter().find(|r| r["name"] == "bee").unwrap();
    assert!(rex["diverged"]["t_s"].as_f64().unwrap() < 0.3, "{rex}");
    assert!(
        rex["diverged"]["cause"]
            .as_str()
            .unwrap()
            .contains("unstable")
    );
    assert!(bee.get("diverged").is_none(), "{bee}");
    // the log is finalised and readable
    let c = quadsim::log::read::read_log(&d.join("out/log.mcap")).unwrap();
    assert_eq!(c.error, None);
}

// ---- 4. bounded resources ----------------------------------------------------

#[test]
fn endless_and_huge_inputs_are_refused_at_once() {
    let d = dir("bounded");
    let t = Instant::now();
    let o = quadsim(&["check", "/dev/zero"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("MiB"), "{}", stderr(&o));
    // a herd of 100000: refused before it is expanded
    let herd = "[[herds]]\nname = \"h\"\ncount = 100000\n[herds.robot]\nmodel = \"quad16\"\n";
    std::fs::write(
        d.join("herd.toml"),
        GOOD.replace("[[robots]]", &format!("{herd}\n[[robots]]")),
    )
    .unwrap();
    let o = quadsim(&["check", "herd.toml"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("herds[0].count"), "{}", stderr(&o));
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
}

#[test]
fn threads_beyond_the_machine_are_capped_with_a_message() {
    let d = dir("threads");
    std::fs::write(d.join("s.toml"), GOOD).unwrap();
    let o = quadsim(
        &[
            "run",
            "s.toml",
            "--out",
            "out",
            "--quiet",
            "--no-monitor",
            "--no-log",
            "--threads",
            "100000",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--threads 100000"), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/summary.json")).unwrap())
            .unwrap();
    let n = std::thread::available_parallelism().unwrap().get() as u64;
    assert!(
        summary["timing"]["threads"].as_u64().unwrap() <= n,
        "{summary}"
    );
}

#[test]
fn a_long_urdf_chain_is_rejected_quickly() {
    let n = 5000;
    let mut s = String::from("<robot name=\"chain\">\n<link name=\"l0\"/>\n");
    for i in 1..=n {
        s += &format!(
            "<link name=\"l{i}\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>\n<joint name=\"j{i}\" type=\"continuous\"><parent link=\"l{}\"/><child link=\"l{i}\"/><axis xyz=\"0 0 1\"/></joint>\n",
            i - 1
        );
    }
    s += "</robot>\n";
    let t = Instant::now();
    let e = quadsim::urdf::parse_urdf(&s, "chain.urdf", Path::new("."), &Default::default())
        .unwrap_err()
        .to_string();
    let took = t.elapsed();
    assert!(
        e.contains("5000 <link>") || e.contains("5001 <link>"),
        "{e}"
    );
    assert!(took < Duration::from_secs(1), "{took:?} for {n} joints");
    // below the limit, compiling the model is linear: 1,000 joints in well
    // under a second (the name lookups were scans: quadratic)
    let n = 999;
    let mut s = String::from(
        "<robot name=\"chain\">\n<link name=\"l0\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>\n",
    );
    for i in 1..=n {
        s += &format!(
            "<link name=\"l{i}\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>\n<joint name=\"j{i}\" type=\"continuous\"><parent link=\"l{}\"/><child link=\"l{i}\"/><axis xyz=\"0 0 1\"/></joint>\n",
            i - 1
        );
    }
    s += "</robot>\n";
    let t = Instant::now();
    quadsim::urdf::parse_urdf(&s, "chain.urdf", Path::new("."), &Default::default()).unwrap();
    assert!(
        t.elapsed() < Duration::from_secs(1),
        "{:?} for {n} joints",
        t.elapsed()
    );
}

// ---- scripted use -------------------------------------------------------------

#[test]
fn replay_without_a_terminal_prints_text() {
    let d = dir("replay");
    std::fs::write(d.join("s.toml"), GOOD).unwrap();
    let o = quadsim(
        &[
            "run",
            "s.toml",
            "--out",
            "out",
            "--quiet",
            "--no-monitor",
            "--no-report",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = quadsim(&["replay", "out/log.mcap"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("rex"));
}

#[test]
fn stability_warnings_name_the_terrain_that_is_stiff() {
    // the file lists the soft terrain first; the ground keeps its patches
    // sorted by name, and the warning must still name the stiff one
    let src = GOOD.replace(
        "[[terrains]]\nname = \"floor\"\nkind = \"flat\"\n",
        "[[terrains]]\nname = \"floor\"\nkind = \"flat\"\n\n[[terrains]]\nname = \"a_hard\"\nkind = \"flat\"\norigin_m = [30.0, 0.0, 0.0]\nground = { stiffness_n_per_m = 1.0e11, damping_ns_per_m = 0.0, friction = 0.8 }\n",
    );
    let s = parse_scenario(Path::new("w.toml"), src).unwrap();
    let w = build_world(&s, Overrides::default()).unwrap();
    let warnings = quadsim::cli::run::stability_warnings(&s, &w);
    assert!(!warnings.is_empty());
    for m in &warnings {
        assert!(m.contains("terrain 'a_hard'"), "{m}");
    }
}

#[test]
fn a_herd_robot_keeps_its_model_in_the_report() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/herd.toml"))
        .unwrap();
    let q16 = quadsim::report::robot_info(&text, "q16-000");
    assert_eq!(q16.model, "quad16");
    assert_eq!(q16.controller, "vmc");
    assert_eq!(
        quadsim::report::robot_info(&text, "q12-029").model,
        "quad12"
    );
    assert_eq!(quadsim::report::robot_info(&text, "nobody").model, "");
}

/// The fuzzing campaign's reproducers from main (4ea6321): a robot named
/// `../../../X` wrote its plots above `--out` (case 672); URDFs with extra
/// leaf links panicked in `sense` (1327, 1648); long chains took 20–55 s
/// (96, 1648). Each now ends with a result or an error, quickly, in place.
#[test]
fn fuzz_reproducers_from_main_end_cleanly() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fuzz");
    for case in ["case-672", "case-1327", "case-96", "case-1648"] {
        let root = dir(&format!("repro-{case}"));
        let inp = root.join("in");
        std::fs::create_dir_all(&inp).unwrap();
        for f in std::fs::read_dir(fixtures.join(case)).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, inp.join(f.file_name().unwrap())).unwrap();
        }
        let t = Instant::now();
        for args in [
            &["check", "s.toml"][..],
            &[
                "run",
                "s.toml",
                "--out",
                "../out",
                "--quiet",
                "--no-monitor",
                "--threads",
                "1",
                "--duration",
                "0.02",
            ][..],
        ] {
            let o = quadsim(args, &inp);
            let err = stderr(&o);
            assert!(!err.contains("panicked"), "{case} {args:?}: {err}");
            assert!(matches!(o.status.code(), Some(0..=2)), "{case}: {err}");
        }
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "{case}: {:?}",
            t.elapsed()
        );
        let mut beside: Vec<String> = std::fs::read_dir(&root)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n != "in" && n != "out")
            .collect();
        beside.sort();
        assert!(beside.is_empty(), "{case} wrote outside --out: {beside:?}");
        let above: Vec<_> = std::fs::read_dir(root.parent().unwrap())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with("X_"))
            .collect();
        assert!(above.is_empty(), "{case} wrote above its directory");
    }
}
