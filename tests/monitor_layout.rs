//! The frame and command layouts documented in docs/monitor.md are the
//! compiled ones: every row's byte offset and size equal `offset_of!` and
//! `size_of_val`, no field is missing; and the C header
//! (examples/quadsim_frame.h), compiled with gcc, agrees field by field.

use std::mem::{offset_of, size_of};

use quadsim::monitor::{LAYOUT_VERSION, MAX_DOF, MAX_FEET, RobotCommand, RobotFrame, TYPE_NAME};

/// (field, byte offset, size in bytes) of every field, in declaration order.
fn rust_layout() -> Vec<(&'static str, usize, usize)> {
    let f = RobotFrame::default();
    macro_rules! row {
        ($name:ident) => {
            (
                stringify!($name),
                offset_of!(RobotFrame, $name),
                std::mem::size_of_val(&f.$name),
            )
        };
    }
    vec![
        row!(layout_version),
        row!(robot_index),
        row!(tick),
        row!(time_s),
        row!(n_dof),
        row!(n_feet),
        row!(contact_flags),
        row!(slip_flags),
        row!(base_position_m),
        row!(base_orientation_xyzw),
        row!(base_linear_mps),
        row!(base_angular_radps),
        row!(rpy_rad),
        row!(com_m),
        row!(com_velocity_mps),
        row!(joint_q_rad),
        row!(joint_qd_radps),
        row!(joint_q_desired_rad),
        row!(joint_qd_desired_radps),
        row!(joint_tau_nm),
        row!(joint_tau_desired_nm),
        row!(foot_force_n),
        row!(gait_phase),
    ]
}

/// Size of a documented type: `u32`, `u64`, `f64`, `f64[3]`, `f64[4][3]`.
fn type_size(t: &str) -> usize {
    let t = t.trim().trim_matches('`');
    let (base, dims) = t.split_once('[').map_or((t, ""), |(b, d)| (b, d));
    let scalar = match base {
        "u32" => 4,
        "u64" | "f64" => 8,
        other => panic!("unknown type '{other}' in docs/monitor.md"),
    };
    dims.split('[')
        .map(|d| d.trim_end_matches(']'))
        .filter(|d| !d.is_empty())
        .map(|d| d.parse::<usize>().expect("array length"))
        .product::<usize>()
        * scalar
}

/// Rows `| offset | field | type | … |` of the layout table under the
/// heading starting with `heading` in docs/monitor.md.
fn doc_layout(heading: &str) -> Vec<(String, usize, usize)> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/monitor.md"))
        .expect("docs/monitor.md");
    let section = text
        .split("\n## ")
        .find(|s| s.starts_with(heading))
        .unwrap_or_else(|| panic!("docs/monitor.md has no section '{heading}'"));
    section
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            if cells.len() < 5 {
                return None;
            }
            let offset = cells[1].parse::<usize>().ok()?;
            let name = cells[2].trim_matches('`').to_string();
            Some((name, offset, type_size(cells[3])))
        })
        .collect()
}

#[test]
fn documented_layout_is_the_compiled_layout() {
    let rust = rust_layout();
    let doc = doc_layout("`RobotFrame` layout");
    let actual: Vec<String> = rust
        .iter()
        .map(|(n, o, s)| format!("{o} {n} {s}"))
        .collect();
    let documented: Vec<String> = doc.iter().map(|(n, o, s)| format!("{o} {n} {s}")).collect();
    assert_eq!(
        documented, actual,
        "docs/monitor.md's table (offset field size) differs from RobotFrame"
    );
    // fields tile the struct without padding, and the documented size is right
    let end = rust.last().map(|(_, o, s)| o + s).unwrap();
    assert_eq!(end, size_of::<RobotFrame>());
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/monitor.md")).unwrap();
    assert!(
        text.contains(&format!("{} bytes", size_of::<RobotFrame>())),
        "docs/monitor.md states the frame size"
    );
    for w in rust.windows(2) {
        assert_eq!(w[0].1 + w[0].2, w[1].1, "padding before {}", w[1].0);
    }
    assert_eq!(std::mem::align_of::<RobotFrame>(), 8);
    assert!(TYPE_NAME.ends_with(&format!(".v{LAYOUT_VERSION}")));
    assert_eq!((MAX_DOF, MAX_FEET), (24, 4), "docs/monitor.md's sizes");
}

#[test]
fn documented_command_layout_is_the_compiled_layout() {
    let c = RobotCommand::default();
    macro_rules! row {
        ($name:ident) => {
            format!(
                "{} {} {}",
                offset_of!(RobotCommand, $name),
                stringify!($name),
                std::mem::size_of_val(&c.$name)
            )
        };
    }
    let actual = vec![
        row!(layout_version),
        row!(robot_index),
        row!(tick),
        row!(mode),
        row!(n_dof),
        row!(q_target_rad),
        row!(qd_target_radps),
        row!(kp_nm_per_rad),
        row!(kd_nms_per_rad),
        row!(tau_ff_nm),
        row!(velocity),
    ];
    let documented: Vec<String> = doc_layout("`RobotCommand` layout")
        .iter()
        .map(|(n, o, s)| format!("{o} {n} {s}"))
        .collect();
    assert_eq!(documented, actual);
    let last = documented.last().unwrap();
    let mut it = last.split(' ');
    let (o, _, s) = (it.next().unwrap(), it.next(), it.next().unwrap());
    let end = o.parse::<usize>().unwrap() + s.parse::<usize>().unwrap();
    assert_eq!(end, size_of::<RobotCommand>(), "no tail padding");
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/monitor.md")).unwrap();
    assert!(text.contains(&format!("{} bytes", size_of::<RobotCommand>())));
}

/// `"<c struct>.<field> <offset> <size>"` lines of the Rust structs, as
/// examples/check_frame_layout.c prints them for the C header.
fn rust_c_lines() -> Vec<String> {
    let mut out: Vec<String> = rust_layout()
        .iter()
        .map(|(n, o, s)| format!("quadsim_robot_frame.{n} {o} {s}"))
        .collect();
    out.push(format!("quadsim_robot_frame {}", size_of::<RobotFrame>()));
    let c = RobotCommand::default();
    macro_rules! row {
        ($name:ident) => {
            out.push(format!(
                "quadsim_robot_command.{} {} {}",
                stringify!($name),
                offset_of!(RobotCommand, $name),
                std::mem::size_of_val(&c.$name)
            ))
        };
    }
    row!(layout_version);
    row!(robot_index);
    row!(tick);
    row!(mode);
    row!(n_dof);
    row!(q_target_rad);
    row!(qd_target_radps);
    row!(kp_nm_per_rad);
    row!(kd_nms_per_rad);
    row!(tau_ff_nm);
    row!(velocity);
    out.push(format!(
        "quadsim_robot_command {}",
        size_of::<RobotCommand>()
    ));
    out
}

#[test]
fn c_header_matches_the_rust_structs() {
    let dir = std::env::temp_dir().join(format!("quadsim-c-header-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("check_frame_layout");
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/check_frame_layout.c");
    let status = std::process::Command::new("gcc")
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(src)
        .status()
        .expect("gcc must be installed to check examples/quadsim_frame.h");
    assert!(status.success(), "gcc failed on {src}");
    let out = std::process::Command::new(&exe).output().unwrap();
    assert!(out.status.success());
    let c: Vec<String> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    assert_eq!(
        c,
        rust_c_lines(),
        "examples/quadsim_frame.h differs from Rust"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
