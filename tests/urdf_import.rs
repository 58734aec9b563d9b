//! URDF import of vendor-style files: meshes by `package://` and relative paths,
//! continuous joints, `<dynamics>`, effort and velocity limits, fixed joints
//! (merged inertia checked by hand with the parallel-axis theorem), rotated
//! inertial frames, and malformed files that must give errors, not panics.

use std::path::{Path, PathBuf};

use glam::{DMat3, DQuat, DVec3};
use quadsim::engine::description::{JointKind, Shape};
use quadsim::engine::model::{BaseKind, Model};
use quadsim::urdf::{UrdfError, UrdfOptions, load_urdf};

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/models")
}

fn with_packages() -> UrdfOptions {
    UrdfOptions {
        package_paths: vec![models().join("packages")],
    }
}

fn close(a: DMat3, b: DMat3, tol: f64) -> bool {
    (a - b).to_cols_array().iter().all(|x| x.abs() <= tol)
}

/// Bounding box of a mesh's vertices.
fn bbox(v: &[DVec3]) -> (DVec3, DVec3) {
    v.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

#[test]
fn package_mesh_found_through_package_path_has_scaled_vertices() {
    let r = load_urdf(&models().join("vendor_style.urdf"), &with_packages()).unwrap();
    let base = r.description.link("base_link").unwrap();
    let Shape::Mesh {
        uri,
        scale,
        vertices,
    } = &base.collision[0].shape
    else {
        panic!("expected a mesh, got {:?}", base.collision[0].shape);
    };
    assert_eq!(uri, "package://test_pkg/meshes/cube.stl");
    assert_eq!(*scale, DVec3::new(0.4, 0.2, 0.1));
    let v = vertices
        .as_ref()
        .expect("cube.stl was found, so its vertices are loaded");
    // the unit cube scaled per axis: a 0.4 × 0.2 × 0.1 m box centred on the frame
    let (lo, hi) = bbox(v);
    assert!(
        (hi - lo - DVec3::new(0.4, 0.2, 0.1)).abs().max_element() < 1e-7,
        "{lo} {hi}"
    );
    assert!((hi + lo).abs().max_element() < 1e-7);
    // the collision origin is kept beside the shape
    assert_eq!(base.collision[0].origin.trans, DVec3::new(0.0, 0.0, 0.05));
    // the missing package is the only warning, and it names the link and the URI
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    let w = &r.warnings[0];
    assert!(w.contains("vendor_style.urdf"), "{w}");
    assert!(w.contains("link 'plate'"), "{w}");
    assert!(w.contains("package://missing_pkg/meshes/plate.dae"), "{w}");
}

#[test]
fn mesh_not_found_is_kept_as_a_reference_with_a_warning() {
    // without --package-path, neither package:// mesh can be found
    let r = load_urdf(&models().join("vendor_style.urdf"), &UrdfOptions::default()).unwrap();
    let base = r.description.link("base_link").unwrap();
    match &base.collision[0].shape {
        Shape::Mesh { uri, vertices, .. } => {
            assert_eq!(uri, "package://test_pkg/meshes/cube.stl");
            assert!(vertices.is_none());
        }
        other => panic!("expected a mesh, got {other:?}"),
    }
    let about_cube: Vec<&String> = r
        .warnings
        .iter()
        .filter(|w| w.contains("cube.stl"))
        .collect();
    // one for <visual>, one for <collision>
    assert_eq!(about_cube.len(), 2, "{:?}", r.warnings);
    assert!(
        about_cube
            .iter()
            .all(|w| w.contains("link 'base_link'") && w.contains("--package-path"))
    );
    // a package path that lacks the package: still a warning, naming where it looked
    let elsewhere = UrdfOptions {
        package_paths: vec![models().join("meshes")],
    };
    let r = load_urdf(&models().join("vendor_style.urdf"), &elsewhere).unwrap();
    assert!(
        r.warnings
            .iter()
            .any(|w| w.contains("test_pkg") && w.contains("meshes"))
    );
}

#[test]
fn relative_obj_mesh_is_loaded_from_the_urdf_directory() {
    let r = load_urdf(&models().join("vendor_style.urdf"), &with_packages()).unwrap();
    let wheel = r.description.link("wheel").unwrap();
    let Shape::Mesh {
        vertices: Some(v), ..
    } = &wheel.collision[0].shape
    else {
        panic!("tetra.obj should load: {:?}", wheel.collision[0].shape);
    };
    let (lo, hi) = bbox(v);
    assert!((lo - DVec3::ZERO).abs().max_element() < 1e-7, "{lo}");
    assert!((hi - DVec3::splat(0.1)).abs().max_element() < 1e-7, "{hi}");
}

#[test]
fn joint_types_limits_and_dynamics() {
    let d = load_urdf(&models().join("vendor_style.urdf"), &with_packages())
        .unwrap()
        .description;
    // document order is kept
    let names: Vec<&str> = d.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["plate_mount", "wheel_spin", "arm_lift", "slide"]);

    let wheel = d.joint("wheel_spin").unwrap();
    // continuous: revolute, no position limits; the axis "0 0 2" is normalised
    assert_eq!(wheel.kind, JointKind::Revolute { axis: DVec3::Z });
    assert_eq!(wheel.limits, None);
    assert_eq!((wheel.effort_limit, wheel.velocity_limit), (12.5, 30.0));
    assert_eq!((wheel.damping, wheel.friction), (0.05, 0.2));
    // origin rpy: roll −90° maps the child's z axis onto the parent's +y
    let z_in_parent = wheel.placement.rot * DVec3::Z;
    assert!((z_in_parent - DVec3::Y).length() < 1e-12, "{z_in_parent}");
    assert_eq!(wheel.placement.trans, DVec3::new(0.0, 0.15, 0.0));

    let arm = d.joint("arm_lift").unwrap();
    assert_eq!(arm.kind, JointKind::Revolute { axis: DVec3::Y });
    assert_eq!(arm.limits, Some((-0.5, 1.25)));
    // effort="0" means "not given": no effort limit
    assert_eq!(arm.effort_limit, f64::INFINITY);
    assert_eq!(arm.velocity_limit, 4.0);
    assert_eq!((arm.damping, arm.friction), (0.1, 0.0));

    let slide = d.joint("slide").unwrap();
    assert_eq!(slide.kind, JointKind::Prismatic { axis: DVec3::Z });
    assert_eq!(slide.limits, Some((0.0, 0.3)));
    assert_eq!((slide.effort_limit, slide.velocity_limit), (50.0, 0.5));

    assert_eq!(d.joint("plate_mount").unwrap().kind, JointKind::Fixed);
    // a link without <inertial> is massless
    assert_eq!(d.link("arm").unwrap().mass_kg, 0.0);
    // no feet named: the leaf links will be the feet
    assert!(d.feet.is_empty());

    // the engine model carries the same numbers, in v order
    let m = Model::from_description(&d, BaseKind::Fixed).unwrap();
    assert_eq!(m.nv, 3);
    let iv = m.joint_v_index("wheel_spin").unwrap();
    assert_eq!(
        (m.lower_limit[iv], m.upper_limit[iv]),
        (f64::NEG_INFINITY, f64::INFINITY)
    );
    assert_eq!(
        (m.damping[iv], m.friction[iv], m.effort_limit[iv]),
        (0.05, 0.2, 12.5)
    );
    let iv = m.joint_v_index("slide").unwrap();
    assert_eq!((m.lower_limit[iv], m.upper_limit[iv]), (0.0, 0.3));
}

/// The plate (1 kg, CoM 0.1 m along its x, I = diag(0.01, 0.02, 0.03)) is
/// welded at x = 0.5 m, turned 90° about z, to the base (2 kg, CoM at the
/// origin, I = diag(0.1, 0.2, 0.3)). By hand:
/// - the plate's x axis is the base's y axis, so its CoM is at (0.5, 0.1, 0) and
///   its tensor in base axes is diag(0.02, 0.01, 0.03);
/// - total 3 kg, CoM c = (0.5, 0.1, 0) / 3 = (1/6, 1/30, 0);
/// - parallel axis, d₁ = −c for the base, d₂ = (1/3, 1/15, 0) for the plate:
///   Ixx = 0.1 + 2·(1/30)² + 0.02 + 1·(1/15)²,
///   Iyy = 0.2 + 2·(1/6)² + 0.01 + 1·(1/3)²,
///   Izz = 0.3 + 2·((1/6)² + (1/30)²) + 0.03 + 1·((1/3)² + (1/15)²),
///   Ixy = −2·(1/6)(1/30) − 1·(1/3)(1/15).
#[test]
fn fixed_joint_merges_inertia_by_the_parallel_axis_theorem() {
    let d = load_urdf(&models().join("vendor_style.urdf"), &with_packages())
        .unwrap()
        .description;
    let m = Model::from_description(&d, BaseKind::Floating).unwrap();
    let plate = m.frame_index("plate").unwrap();
    assert_eq!(
        m.frames[plate].body, 0,
        "the plate is merged into the base body"
    );
    let body = m.inertia[0];
    assert!((body.mass - 3.0).abs() < 1e-15);
    let c = DVec3::new(1.0 / 6.0, 1.0 / 30.0, 0.0);
    assert!((body.com - c).length() < 1e-15, "{}", body.com);
    let ixx = 0.1 + 2.0 * (1.0f64 / 30.0).powi(2) + 0.02 + (1.0f64 / 15.0).powi(2);
    let iyy = 0.2 + 2.0 * (1.0f64 / 6.0).powi(2) + 0.01 + (1.0f64 / 3.0).powi(2);
    let izz = 0.3
        + 2.0 * ((1.0f64 / 6.0).powi(2) + (1.0f64 / 30.0).powi(2))
        + 0.03
        + ((1.0f64 / 3.0).powi(2) + (1.0f64 / 15.0).powi(2));
    let ixy = -2.0 * (1.0 / 6.0) * (1.0 / 30.0) - (1.0 / 3.0) * (1.0 / 15.0);
    let hand = DMat3::from_cols_array(&[ixx, ixy, 0.0, ixy, iyy, 0.0, 0.0, 0.0, izz]);
    assert!(
        close(body.inertia_com, hand, 1e-14),
        "{}\nvs\n{hand}",
        body.inertia_com
    );
    // the plate stays reachable as a frame at its placement
    assert!((m.frames[plate].placement.trans - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-15);
    assert!((m.total_mass - (2.0 + 1.0 + 0.8 + 0.3)).abs() < 1e-15);
}

/// `<inertial><origin rpy>` rotates the given tensor into link axes: I_link = R I Rᵀ,
/// with R built here independently from URDF's quaternion formula
/// (urdfdom's `Rotation::setFromRPY`). The principal moments, and so the
/// invariants trace, second invariant and determinant, do not change.
#[test]
fn rotated_inertial_frame_is_rotated_into_link_axes() {
    let d = load_urdf(&models().join("vendor_style.urdf"), &with_packages())
        .unwrap()
        .description;
    let wheel = d.link("wheel").unwrap();
    let (r, p, y) = (0.3f64, -0.7f64, 1.1f64);
    let (sr, cr) = (r / 2.0).sin_cos();
    let (sp, cp) = (p / 2.0).sin_cos();
    let (sy, cy) = (y / 2.0).sin_cos();
    let quat = DQuat::from_xyzw(
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    );
    let rot = DMat3::from_quat(quat);
    let given = DMat3::from_cols_array(&[
        0.004, 0.0005, -0.0003, //
        0.0005, 0.006, 0.0002, //
        -0.0003, 0.0002, 0.009,
    ]);
    let expect = rot * given * rot.transpose();
    let got = wheel.inertia_kgm2.unwrap();
    assert!(close(got, expect, 1e-15), "{got}\nvs\n{expect}");
    assert!(!close(got, given, 1e-4), "the rotation must matter here");
    let inv = |i: DMat3| {
        let a = i.to_cols_array_2d();
        let second = a[0][0] * a[1][1] + a[1][1] * a[2][2] + a[0][0] * a[2][2]
            - a[0][1] * a[1][0]
            - a[1][2] * a[2][1]
            - a[0][2] * a[2][0];
        [a[0][0] + a[1][1] + a[2][2], second, i.determinant()]
    };
    for (a, b) in inv(got).iter().zip(inv(given)) {
        assert!((a - b).abs() <= 1e-15 * b.abs().max(1e-6), "{a} vs {b}");
    }
    assert_eq!(wheel.com_m, DVec3::new(0.01, -0.02, 0.03));
    assert_eq!(wheel.mass_kg, 0.8);
}

/// Each malformed file gives an error naming the file and the element and field.
#[test]
fn malformed_files_give_errors_naming_file_and_field() {
    let cases: &[(&str, &[&str])] = &[
        (
            "unclosed.urdf",
            &["unclosed.urdf", "malformed XML", "at 6:3"],
        ),
        (
            "zero_axis.urdf",
            &[
                "zero_axis.urdf",
                "joint 'LF_knee' (line 4)",
                "<axis xyz>: zero vector",
            ],
        ),
        (
            "unknown_link.urdf",
            &[
                "unknown_link.urdf",
                "joint 'LF_hip_roll'",
                "<child link>",
                "'LF_thigh'",
            ],
        ),
        (
            "negative_mass.urdf",
            &[
                "negative_mass.urdf",
                "link 'torso'",
                "<inertial><mass value>",
                "-2",
            ],
        ),
        (
            "nan_mass.urdf",
            &[
                "nan_mass.urdf",
                "link 'torso'",
                "<inertial><mass value>",
                "NaN",
            ],
        ),
        (
            "bad_number.urdf",
            &[
                "bad_number.urdf",
                "joint 'hip'",
                "<origin xyz>",
                "'zero' is not a number",
            ],
        ),
        (
            "floating_joint.urdf",
            &[
                "floating_joint.urdf",
                "joint 'free'",
                "'floating' is not supported",
            ],
        ),
        (
            "limits_reversed.urdf",
            &["limits_reversed.urdf", "joint 'hip'", "<limit lower upper>"],
        ),
        ("two_roots.urdf", &["two_roots.urdf", "several root links"]),
        ("not_a_robot.urdf", &["not_a_robot.urdf", "<robot>"]),
        (
            "missing_velocity.urdf",
            &[
                "missing_velocity.urdf",
                "joint 'hip'",
                "<limit velocity>",
                "missing",
            ],
        ),
        (
            "negative_damping.urdf",
            &["negative_damping.urdf", "joint 'hip'", "<dynamics damping>"],
        ),
        (
            "does_not_exist.urdf",
            &["does_not_exist.urdf", "cannot read"],
        ),
    ];
    for (file, needles) in cases {
        let path = models().join("bad").join(file);
        let err: UrdfError = match load_urdf(&path, &UrdfOptions::default()) {
            Ok(_) => panic!("{file}: loaded without error"),
            Err(e) => e,
        };
        let msg = err.to_string();
        println!("{msg}");
        for n in *needles {
            assert!(msg.contains(n), "{file}: message lacks {n:?}: {msg}");
        }
    }
}

/// Every truncation of a valid file, and every number in it replaced by a bad
/// one, gives `Ok` or an error, never a panic.
#[test]
fn damaged_files_never_panic() {
    let path = models().join("vendor_style.urdf");
    let text = std::fs::read_to_string(&path).unwrap();
    let dir = models();
    let opts = with_packages();
    let mut errors = 0;
    for end in (0..text.len()).filter(|&i| text.is_char_boundary(i)) {
        if quadsim::urdf::parse_urdf(&text[..end], "cut.urdf", &dir, &opts).is_err() {
            errors += 1;
        }
    }
    // only the whole file (and cuts inside the trailing newline) parse
    assert!(errors >= text.len() - 2, "{errors} of {}", text.len());
    let numbers: Vec<(usize, usize)> = text
        .match_indices(|c: char| c.is_ascii_digit())
        .map(|(i, _)| (i, i + 1))
        .collect();
    for (k, (a, b)) in numbers.iter().enumerate().step_by(3) {
        let bad = ["nan", "-1e400", "x", ""][k % 4];
        let damaged = format!("{}{bad}{}", &text[..*a], &text[*b..]);
        let _ = quadsim::urdf::parse_urdf(&damaged, "damaged.urdf", &dir, &opts);
    }
}
