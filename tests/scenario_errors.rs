//! Bad scenario files get errors naming the file, line, column and key path
//! (issue 3, "Bad input"). Each case asserts where the error points.

use quadsim::scenario::{ScenarioError, parse_scenario};
use std::path::Path;

const GOOD: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 1.0
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

fn err(src: &str) -> ScenarioError {
    parse_scenario(Path::new("bad.toml"), src.to_string()).expect_err("must be rejected")
}

fn line_of(src: &str, needle: &str) -> usize {
    src[..src.find(needle).expect("needle")]
        .matches('\n')
        .count()
        + 1
}

#[test]
fn the_good_file_parses() {
    let s = parse_scenario(Path::new("good.toml"), GOOD.to_string()).unwrap();
    assert_eq!(s.name, "good");
    assert_eq!(s.file.robots.len(), 1);
}

#[test]
fn syntax_error_has_line_and_column() {
    let src = GOOD.replace("duration_s = 1.0", "duration_s = = 1.0");
    let e = err(&src);
    assert_eq!(e.line, line_of(&src, "duration_s"));
    assert!(e.column > 1);
    assert!(e.to_string().starts_with("bad.toml:"), "{e}");
}

#[test]
fn unknown_key_names_its_path() {
    let src = GOOD.replace("dt_s = 0.0005", "dt_s = 0.0005\ntime_step = 0.001");
    let e = err(&src);
    assert_eq!(e.line, line_of(&src, "time_step"));
    assert!(e.message.contains("time_step"), "{e}");
    assert!(e.key_path.starts_with("world"), "{e}");
}

#[test]
fn wrong_type_names_its_path() {
    let src = GOOD.replace("duration_s = 1.0", "duration_s = \"long\"");
    let e = err(&src);
    assert_eq!(e.key_path, "world.duration_s", "{e}");
    assert_eq!(e.line, line_of(&src, "duration_s"));
}

#[test]
fn nan_and_negative_values_are_rejected_after_parsing() {
    let src = GOOD.replace("dt_s = 0.0005", "dt_s = nan");
    let e = err(&src);
    assert_eq!(e.key_path, "world.dt_s");
    assert_eq!(e.line, line_of(&src, "dt_s"));
    let src = GOOD.replace("dt_s = 0.0005", "dt_s = -0.001");
    assert_eq!(err(&src).key_path, "world.dt_s");
    let src = GOOD.replace(
        "default_ground = \"concrete\"",
        "default_ground = { stiffness_n_per_m = -5.0, damping_ns_per_m = 10.0, friction = 0.5 }",
    );
    let e = err(&src);
    assert_eq!(e.key_path, "world.default_ground.stiffness_n_per_m", "{e}");
    let src = GOOD.replace("kp_nm_per_rad = 300.0", "kp_nm_per_rad = -300.0");
    let e = err(&src);
    assert_eq!(e.key_path, "robots[0].controller.kp_nm_per_rad", "{e}");
    assert_eq!(e.line, line_of(&src, "kp_nm_per_rad"));
}

#[test]
fn unknown_terrain_and_kinds_are_named() {
    let src = GOOD.replace("terrain = \"floor\"", "terrain = \"moon\"");
    let e = err(&src);
    assert_eq!(e.key_path, "robots[0].terrain");
    assert!(
        e.message.contains("moon") && e.message.contains("floor"),
        "{e}"
    );
    let src = GOOD.replace("kind = \"flat\"", "kind = \"lava\"");
    let e = err(&src);
    assert_eq!(e.key_path, "terrains[0].kind");
    assert_eq!(e.line, line_of(&src, "\"lava\""));
    let src = GOOD.replace("default_ground = \"concrete\"", "default_ground = \"ice\"");
    assert_eq!(err(&src).key_path, "world.default_ground");
}

#[test]
fn duplicate_robot_name_points_at_the_second() {
    let src = format!("{GOOD}\n[[robots]]\nname = \"rex\"\nmodel = \"quad12\"\n");
    let e = err(&src);
    assert_eq!(e.key_path, "robots[1].name");
    assert_eq!(e.line, src.matches('\n').count() - 1);
    assert!(e.message.contains("duplicate"), "{e}");
}

#[test]
fn format_version_is_checked_first() {
    let src = GOOD.replace("format_version = 1", "format_version = 2\n[future]\nx = 1");
    let e = err(&src);
    assert_eq!(e.key_path, "format_version");
    assert!(
        e.message.contains("version 2") && e.message.contains("upgrade"),
        "{e}"
    );
    let src = GOOD.replace("format_version = 1\n", "");
    assert!(err(&src).message.contains("format_version"));
}

#[test]
fn controller_rate_must_divide_the_step_rate() {
    let src = GOOD.replace("dt_s = 0.0005", "dt_s = 0.0005\ncontroller_rate_hz = 300");
    assert_eq!(err(&src).key_path, "world.controller_rate_hz");
}

#[test]
fn keys_of_another_kind_are_rejected() {
    let src = GOOD.replace("kind = \"flat\"", "kind = \"flat\"\nslope_deg = 5.0");
    let e = err(&src);
    assert_eq!(e.key_path, "terrains[0].slope_deg");
    assert!(e.message.contains("flat"), "{e}");
    let src = GOOD.replace("kind = \"flat\"", "kind = \"incline\"");
    let e = err(&src);
    assert!(e.message.contains("slope_deg"), "{e}");
}
