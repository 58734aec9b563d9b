//! The built-in robots: sizes and masses against the studies' tables,
//! parameter overrides against the shape formulas and scaling rules they
//! document, typed errors for bad overrides, and the nominal stances against
//! hand-computed forward kinematics (quad16) and the study's D-H formulas
//! (quad12).

mod common;

use glam::{DMat3, DVec3};
use quadsim_engine::Data;
use quadsim_engine::com::center_of_mass;
use quadsim_engine::description::{JointKind, RobotDescription, Shape};
use quadsim_engine::jacobian::add_point_force_jt;
use quadsim_engine::kinematics::{forward_kinematics_pos, frame_pose};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::nle::generalized_gravity;
use quadsim_engine::robots::{
    self, Domain, ParamError, builtin, builtin_names, builtin_with, nominal_base_height_m,
    nominal_q, nominal_stance, params, quad12::stretched_inertia, stance_base_height_m,
};
use rand::Rng;
use std::f64::consts::PI;

const LEGS: [&str; 4] = ["LF", "RF", "RH", "LH"];

fn link_mass(d: &RobotDescription, name: &str) -> f64 {
    d.link(name).unwrap().mass_kg
}

fn assert_mat_close(a: DMat3, b: DMat3, tol: f64, what: &str) {
    let (a, b) = (a.to_cols_array(), b.to_cols_array());
    for k in 0..9 {
        assert!((a[k] - b[k]).abs() <= tol, "{what}: {a:?} vs {b:?}");
    }
}

#[test]
fn dof_and_total_mass_match_the_studies() {
    // Study A: torso 10 + 4 × (thigh 2.5 + shank 1.5 + foot 0.5) = 28 kg, 16 DOF.
    let q16 = builtin("quad16").unwrap();
    assert_eq!(q16.dof(), 16);
    assert!((q16.total_mass_kg() - (10.0 + 4.0 * (2.5 + 1.5 + 0.5))).abs() < 1e-12);
    let m16 = Model::from_description(&q16, BaseKind::Floating).unwrap();
    assert_eq!((m16.nq, m16.nv), (7 + 16, 6 + 16));
    assert!((m16.total_mass - 28.0).abs() < 1e-12);
    // Study B: torso 2 + 4 × (0.5 + 1.2 + 0.8) = 12 kg, 12 DOF.
    let q12 = builtin("quad12").unwrap();
    assert_eq!(q12.dof(), 12);
    assert!((q12.total_mass_kg() - 12.0).abs() < 1e-12);
    let m12 = Model::from_description(&q12, BaseKind::Floating).unwrap();
    assert_eq!((m12.nq, m12.nv), (7 + 12, 6 + 12));
    // q order: legs LF, RF, RH, LH, proximal to distal
    let names = m12.movable_joint_names();
    assert_eq!(&names[..3], ["LF_hip_yaw", "LF_hip_pitch", "LF_knee"]);
    assert_eq!(names[9], "LH_hip_yaw");
    let names = m16.movable_joint_names();
    assert_eq!(
        &names[4..8],
        ["RF_hip_roll", "RF_hip_pitch", "RF_knee", "RF_ankle"]
    );
    // feet are the four foot links, each with a contact point
    for d in [&q16, &q12] {
        let feet: Vec<String> = LEGS.iter().map(|l| format!("{l}_foot")).collect();
        assert_eq!(d.feet, feet);
        assert_eq!(d.foot_points.len(), 4);
    }
}

#[test]
fn every_builtin_has_a_table_a_stance_and_a_model() {
    for &name in builtin_names() {
        let d = builtin(name).unwrap();
        assert_eq!(d.name, name);
        assert!(params(name).is_some_and(|p| !p.is_empty()));
        assert_eq!(nominal_stance(name).unwrap().len(), d.dof());
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            Model::from_description(&d, base).unwrap();
        }
    }
    assert!(builtin("quad8").is_none());
    assert!(params("quad8").is_none());
    assert!(nominal_stance("quad8").is_none());
}

/// Every parameter of a table appears in its module's documentation table with
/// the same default and unit: the docs cannot drift from the code.
#[test]
fn parameter_docs_match_the_tables() {
    let sources = [
        ("quad16", include_str!("../src/robots/quad16.rs")),
        ("quad12", include_str!("../src/robots/quad12.rs")),
    ];
    for (name, src) in sources {
        let specs = params(name).unwrap();
        let rows: Vec<Vec<String>> = src
            .lines()
            .filter(|l| l.starts_with("//! | `"))
            .map(|l| {
                l.trim_start_matches("//!")
                    .split('|')
                    .map(|c| c.trim().to_string())
                    .filter(|c| !c.is_empty())
                    .collect()
            })
            .collect();
        assert_eq!(rows.len(), specs.len(), "{name}: doc rows vs parameters");
        for s in specs {
            let row = rows
                .iter()
                .find(|r| r[0] == format!("`{}`", s.path))
                .unwrap_or_else(|| panic!("{name}: {} undocumented", s.path));
            assert_eq!(row[1].parse::<f64>().unwrap(), s.default, "{}", s.path);
            assert_eq!(row[2], s.unit, "{}", s.path);
            assert!(!s.doc.is_empty());
            assert!(
                s.domain.contains(s.default),
                "{}: default out of domain",
                s.path
            );
        }
    }
}

#[test]
fn quad16_thigh_length_moves_the_knee_and_keeps_the_density() {
    let base = builtin("quad16").unwrap();
    let long = builtin_with("quad16", &[("thigh.length_m", 0.4)]).unwrap();
    for leg in LEGS {
        let knee = long.joint(&format!("{leg}_knee")).unwrap();
        assert_eq!(knee.placement.trans, DVec3::new(0.0, 0.0, -0.4));
        let ankle = long.joint(&format!("{leg}_ankle")).unwrap();
        assert_eq!(ankle, base.joint(&format!("{leg}_ankle")).unwrap());
        let thigh = long.link(&format!("{leg}_thigh")).unwrap();
        // same density: mass / (π r² L) unchanged
        let density = |m: f64, l: f64| m / (PI * 0.05 * 0.05 * l);
        assert!((density(thigh.mass_kg, 0.4) - density(2.5, 0.3)).abs() < 1e-9);
        assert!((thigh.mass_kg - 2.5 * 4.0 / 3.0).abs() < 1e-12);
        assert_eq!(thigh.com_m, DVec3::new(0.0, 0.0, -0.2));
        // solid cylinder about its centre: (m(3r² + L²)/12, same, m r²/2)
        let m = thigh.mass_kg;
        let ixx = m * (3.0 * 0.05 * 0.05 + 0.16) / 12.0;
        let expect = DMat3::from_diagonal(DVec3::new(ixx, ixx, 0.5 * m * 0.05 * 0.05));
        assert_mat_close(thigh.inertia_kgm2.unwrap(), expect, 1e-15, "thigh inertia");
        // the geometry follows: the cylinder is 0.4 long, centred at mid-length
        let g = &thigh.collision[0];
        assert_eq!(
            g.shape,
            Shape::Cylinder {
                radius_m: 0.05,
                length_m: 0.4
            }
        );
        assert_eq!(g.origin.trans, DVec3::new(0.0, 0.0, -0.2));
    }
    let added = 4.0 * (2.5 * 4.0 / 3.0 - 2.5);
    assert!((long.total_mass_kg() - base.total_mass_kg() - added).abs() < 1e-12);
}

#[test]
fn quad16_given_mass_wins_over_the_density_rule() {
    let d = builtin_with("quad16", &[("thigh.length_m", 0.4), ("thigh.mass_kg", 3.0)]).unwrap();
    assert_eq!(link_mass(&d, "LF_thigh"), 3.0);
    // foot radius doubles: volume ×8, contact point at the new sphere bottom
    let d = builtin_with("quad16", &[("foot.radius_m", 0.06)]).unwrap();
    assert!((link_mass(&d, "RH_foot") - 4.0).abs() < 1e-12);
    let (_, p) = d.foot_points.iter().find(|(n, _)| n == "RH_foot").unwrap();
    assert_eq!(*p, DVec3::new(0.0, 0.0, -0.12));
    // mounts move the hip-roll joints
    let d = builtin_with("quad16", &[("mount.x_m", 0.3), ("mount.y_m", 0.1)]).unwrap();
    let rh = d.joint("RH_hip_roll").unwrap().placement.trans;
    assert_eq!(rh, DVec3::new(-0.3, -0.1, 0.0));
    // actuator limits reach every joint
    let d = builtin_with("quad16", &[("actuator.effort_limit_nm", 50.0)]).unwrap();
    assert!(d.joints.iter().all(|j| j.effort_limit == 50.0));
}

#[test]
fn quad16_foot_contact_point_is_the_sphere_bottom() {
    let d = builtin("quad16").unwrap();
    for leg in LEGS {
        let foot = d.link(&format!("{leg}_foot")).unwrap();
        let sphere = &foot.collision[0];
        let Shape::Sphere { radius_m } = sphere.shape else {
            panic!("foot is a sphere")
        };
        let (_, p) = d.foot_points.iter().find(|(n, _)| *n == foot.name).unwrap();
        assert_eq!(*p, sphere.origin.trans - DVec3::Z * radius_m);
        // thigh and shank collide too (knee and fall detection)
        for part in ["thigh", "shank"] {
            let l = d.link(&format!("{leg}_{part}")).unwrap();
            assert!(matches!(l.collision[0].shape, Shape::Cylinder { .. }));
        }
    }
}

/// A body of point masses stretched along one axis has exactly the inertia the
/// quad12 scaling rule predicts: six point masses on the principal axes
/// reproduce the study's tensor, are stretched and re-weighed, and their
/// inertia is summed directly.
#[test]
fn quad12_stretch_rule_matches_a_stretched_point_mass_body() {
    let cases = [
        (DVec3::new(1e-5, 1.5e-5, 2e-5), 1, 0.5),
        (DVec3::new(5e-5, 6e-5, 7e-5), 0, 1.2),
        (DVec3::new(3e-5, 4e-5, 5e-5), 0, 0.8),
    ];
    for (i0, axis, mass) in cases {
        // second moments P_kk = Σ m x_k², from I = tr(P) − P
        let p = DVec3::splat(0.5 * i0.element_sum()) - i0;
        // two masses m/6 at ±d_k on each axis k give P_kk = m d_k² / 3
        let d = DVec3::new(
            (3.0 * p.x / mass).sqrt(),
            (3.0 * p.y / mass).sqrt(),
            (3.0 * p.z / mass).sqrt(),
        );
        for (s, mass_ratio) in [(1.0, 1.0), (1.5, 1.5), (0.5, 0.5), (2.0, 1.0), (1.0, 3.0)] {
            let mut stretch = DVec3::ONE;
            stretch[axis] = s;
            let mut inertia = DMat3::ZERO;
            for k in 0..3 {
                for sign in [-1.0, 1.0] {
                    let mut x = DVec3::ZERO;
                    x[k] = sign * d[k] * stretch[k];
                    let m = mass * mass_ratio / 6.0;
                    inertia += (DMat3::from_diagonal(DVec3::splat(x.length_squared()))
                        - DMat3::from_cols(x * x.x, x * x.y, x * x.z))
                        * m;
                }
            }
            let rule = stretched_inertia(i0, axis, s, mass_ratio);
            assert_mat_close(rule, inertia, 1e-18, "stretched inertia");
        }
    }
}

#[test]
fn quad12_length_change_moves_frames_and_follows_the_rule() {
    let d = builtin_with("quad12", &[("thigh.length_m", 0.15)]).unwrap();
    for leg in LEGS {
        let knee = d.joint(&format!("{leg}_knee")).unwrap();
        assert_eq!(knee.placement.trans, DVec3::new(0.15, 0.0, 0.0));
        let thigh = d.link(&format!("{leg}_thigh")).unwrap();
        assert!((thigh.mass_kg - 1.8).abs() < 1e-12, "mass follows l2");
        assert!((thigh.com_m - DVec3::new(0.075, 0.0, 0.0)).length() < 1e-15);
        // along the length axis (x) only the mass ratio acts
        let i = thigh.inertia_kgm2.unwrap();
        assert!((i.x_axis.x - 5e-5 * 1.5).abs() < 1e-18);
        assert!(i.y_axis.y > 6e-5 * 1.5 && i.z_axis.z > 7e-5 * 1.5);
    }
    // a given mass at unchanged length scales the whole tensor
    let d = builtin_with("quad12", &[("hip.mass_kg", 1.0)]).unwrap();
    let i = d.link("RF_hip").unwrap().inertia_kgm2.unwrap();
    assert_mat_close(
        i,
        DMat3::from_diagonal(DVec3::new(2e-5, 3e-5, 4e-5)),
        1e-18,
        "hip inertia",
    );
    // l1 moves the hip-pitch joint across the leg; leg yaws turn the mounts
    let d = builtin_with(
        "quad12",
        &[("hip.length_m", 0.07), ("leg.hind_yaw_rad", PI / 2.0)],
    )
    .unwrap();
    let pitch = d.joint("LH_hip_pitch").unwrap().placement.trans;
    assert_eq!(pitch, DVec3::new(0.0, 0.07, 0.0));
    let rh = d.joint("RH_hip_yaw").unwrap().placement.rot;
    assert!((rh * DVec3::X - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-15);
}

#[test]
fn bad_overrides_give_typed_errors_naming_the_path() {
    let err = builtin_with("quad16", &[("thigh.lenght_m", 0.4)]).unwrap_err();
    let ParamError::UnknownPath { robot, path, close } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(
        (robot.as_str(), path.as_str()),
        ("quad16", "thigh.lenght_m")
    );
    assert_eq!(close[0], "thigh.length_m");
    assert!(err.to_string().contains("thigh.length_m"), "{err}");

    let err = builtin_with("quad16", &[("shank.length_m", -0.1)]).unwrap_err();
    assert_eq!(
        err,
        ParamError::OutOfDomain {
            robot: "quad16".into(),
            path: "shank.length_m",
            value: -0.1,
            domain: Domain::NonNegative
        }
    );
    assert!(err.to_string().contains("shank.length_m"));

    let err = builtin_with("quad12", &[("thigh.mass_kg", f64::NAN)]).unwrap_err();
    assert!(matches!(
        err,
        ParamError::OutOfDomain {
            path: "thigh.mass_kg",
            ..
        }
    ));
    let err = builtin_with("quad12", &[("actuator.effort_limit_nm", 0.0)]).unwrap_err();
    assert!(matches!(err, ParamError::OutOfDomain { .. }));
    let err = builtin_with("quad12", &[("mount.x_m", f64::INFINITY)]).unwrap_err();
    assert!(matches!(err, ParamError::OutOfDomain { .. }));
    // quad16 paths are not quad12 paths
    let err = builtin_with("quad12", &[("foot.mass_kg", 0.1)]).unwrap_err();
    assert!(matches!(err, ParamError::UnknownPath { .. }));
    let err = builtin_with("quad12", &[("hip.length_m", 0.1), ("hip.length_m", 0.2)]).unwrap_err();
    assert!(matches!(
        err,
        ParamError::Duplicate {
            path: "hip.length_m",
            ..
        }
    ));
    let err = builtin_with("quad8", &[]).unwrap_err();
    assert!(err.to_string().contains("quad16") && err.to_string().contains("quad12"));
    // a path close to nothing lists every path
    let ParamError::UnknownPath { close, .. } =
        builtin_with("quad12", &[("zzz", 1.0)]).unwrap_err()
    else {
        panic!()
    };
    assert_eq!(close.len(), params("quad12").unwrap().len());
}

/// World position of each foot's contact point at configuration `q`.
fn foot_points_world(d: &RobotDescription, model: &Model, q: &[f64]) -> Vec<(usize, DVec3)> {
    let mut data = Data::new(model);
    forward_kinematics_pos(model, &mut data, q);
    model
        .feet
        .iter()
        .map(|&f| {
            let name = &model.frames[f].name;
            let (_, p) = d.foot_points.iter().find(|(n, _)| n == name).unwrap();
            (f, frame_pose(model, &data, f).transform_point(*p))
        })
        .collect()
}

#[test]
fn quad16_stance_matches_hand_forward_kinematics() {
    let d = builtin("quad16").unwrap();
    let model = Model::from_description(&d, BaseKind::Floating).unwrap();
    let q = nominal_q("quad16").unwrap();
    let h = q[2];
    // thigh pitched 0.3 rad, shank −0.3 rad, foot level: the foot bottom lies
    // (0.3 + 0.25) cos 0.3 + 2 · 0.03 below the hip, 0.05 sin 0.3 behind it
    let below = 0.55 * 0.3f64.cos() + 0.06;
    assert!((h - below).abs() < 1e-12, "base height {h}");
    assert!(
        (h - 0.5854).abs() < 5e-5,
        "oracle stand_static base z 0.5854"
    );
    assert!((nominal_base_height_m("quad16").unwrap() - h).abs() == 0.0);
    let signs = [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)];
    for ((_, p), (sx, sy)) in foot_points_world(&d, &model, &q).into_iter().zip(signs) {
        let hip = DVec3::new(0.25 * sx, 0.15 * sy, h);
        let expect = hip + DVec3::new(-0.05 * 0.3f64.sin(), 0.0, -below);
        assert!((p - expect).length() < 1e-12, "{p} vs {expect}");
        assert!(p.z < hip.z);
        assert!(p.z.abs() < 1e-12, "foot on the ground");
    }
    // a longer thigh raises the stance by 0.1 cos 0.3
    let long = builtin_with("quad16", &[("thigh.length_m", 0.4)]).unwrap();
    let h2 = stance_base_height_m(&long, &nominal_stance("quad16").unwrap()).unwrap();
    assert!((h2 - h - 0.1 * 0.3f64.cos()).abs() < 1e-12);
}

/// Study B's D-H foot position (reference.md) relative to the leg's mount, with
/// the leg's fixed yaw ψ added to θ1 (the study's legs all face +x).
fn dh_foot(l: [f64; 3], psi: f64, th: [f64; 3]) -> DVec3 {
    let (s1, c1) = (th[0] + psi).sin_cos();
    let (s2, c2) = th[1].sin_cos();
    let (s23, c23) = (th[1] + th[2]).sin_cos();
    let [l1, l2, l3] = l;
    DVec3::new(
        c1 * c23 * l3 + c1 * c2 * l2 - l1 * s1,
        s1 * c23 * l3 + s1 * c2 * l2 + l1 * c1,
        -s23 * l3 - s2 * l2,
    )
}

#[test]
fn quad12_legs_follow_the_study_dh_kinematics() {
    let d = builtin("quad12").unwrap();
    let model = Model::from_description(&d, BaseKind::Fixed).unwrap();
    let mut data = Data::new(&model);
    // the leg yaws as the parameter table sets them (π/4, 3π/4 to the URDF's digits)
    let yaw = |path: &str| {
        let specs = params("quad12").unwrap();
        specs.iter().find(|s| s.path == path).unwrap().default
    };
    let (front, hind) = (yaw("leg.front_yaw_rad"), yaw("leg.hind_yaw_rad"));
    assert!((front - PI / 4.0).abs() < 1e-10 && (hind - 3.0 * PI / 4.0).abs() < 1e-9);
    let psi = [front, -front, -hind, hind];
    let mounts = [
        (0.15, 0.075),
        (0.15, -0.075),
        (-0.15, -0.075),
        (-0.15, 0.075),
    ];
    let mut r = common::rng(7);
    for _ in 0..50 {
        let q: Vec<f64> = (0..12).map(|_| r.random_range(-3.0..3.0)).collect();
        forward_kinematics_pos(&model, &mut data, &q);
        for (k, leg) in LEGS.iter().enumerate() {
            let f = model.frame_index(&format!("{leg}_foot")).unwrap();
            let p = frame_pose(&model, &data, f).trans;
            let th = [q[3 * k], q[3 * k + 1], q[3 * k + 2]];
            let expect =
                DVec3::new(mounts[k].0, mounts[k].1, 0.0) + dh_foot([0.05, 0.1, 0.08], psi[k], th);
            assert!((p - expect).length() < 1e-15, "{leg}: {p} vs {expect}");
        }
    }
}

#[test]
fn quad12_stance_is_crouched_with_feet_below_the_hips() {
    let d = builtin("quad12").unwrap();
    let model = Model::from_description(&d, BaseKind::Floating).unwrap();
    let q = nominal_q("quad12").unwrap();
    // D-H at θ = (0, π/6, π/3): foot origin 0.1 sin 30° + 0.08 = 0.13 m below
    // the hip, plus the 0.01 m pad
    assert!((q[2] - 0.14).abs() < 1e-12, "base height {}", q[2]);
    for (_, p) in foot_points_world(&d, &model, &q) {
        assert!(p.z.abs() < 1e-12, "foot on the ground: {p}");
        // out from the hip corner by at most l1 + l2 cos 30°
        let corner = DVec3::new(0.15 * p.x.signum(), 0.075 * p.y.signum(), q[2]);
        let reach = (p - corner).truncate().length();
        assert!(reach <= 0.05 + 0.1 * (PI / 6.0).cos() + 1e-12, "{reach}");
    }
    // crouched: hips 0.14 m up on 0.18 m of leg
    assert!(q[2] < 0.1 + 0.08);
}

/// Joint torques that hold the robot still at its nominal stance, the weight
/// shared among the four feet by vertical forces (minimum-norm split that
/// balances force and moments about the CoM). Returns (base residual, joint torques).
fn static_stance_torques(name: &str) -> (f64, Vec<f64>) {
    let d = builtin(name).unwrap();
    let model = Model::from_description(&d, BaseKind::Floating).unwrap();
    let mut data = Data::new(&model);
    let q = nominal_q(name).unwrap();
    let feet = foot_points_world(&d, &model, &q);
    forward_kinematics_pos(&model, &mut data, &q);
    let com = center_of_mass(&model, &data);
    let weight = model.total_mass * 9.81;
    // A f = [W, 0, 0]: rows Σ f, Σ f (y − y_c), Σ f (x − x_c); f = Aᵀ (A Aᵀ)⁻¹ b
    let rows: Vec<DVec3> = feet
        .iter()
        .map(|(_, p)| DVec3::new(1.0, p.y - com.y, p.x - com.x))
        .collect();
    let aat = rows.iter().fold(DMat3::ZERO, |m, a| {
        m + DMat3::from_cols(*a * a.x, *a * a.y, *a * a.z)
    });
    let lambda = aat.inverse() * DVec3::new(weight, 0.0, 0.0);
    let g = generalized_gravity(&model, &mut data, &q).to_vec();
    let mut jtf = vec![0.0; model.nv];
    for ((f, p), a) in feet.iter().zip(&rows) {
        let body = model.frames[*f].body;
        let fz = a.dot(lambda);
        assert!(fz > 0.0, "{name}: a foot pulls");
        add_point_force_jt(&model, &data, body, *p, DVec3::Z * fz, &mut jtf);
    }
    let tau: Vec<f64> = g.iter().zip(&jtf).map(|(g, f)| g - f).collect();
    let residual = tau[..6].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    (residual, tau[6..].to_vec())
}

/// The nominal stances can be held by the default actuators with a margin:
/// the largest static joint torque, doubled for a trot's two-foot support,
/// stays within the effort limit.
#[test]
fn nominal_stances_are_held_within_the_actuator_limits() {
    for name in ["quad16", "quad12"] {
        let (residual, tau) = static_stance_torques(name);
        assert!(
            residual < 1e-9,
            "{name}: base not in equilibrium ({residual})"
        );
        let limit = builtin(name).unwrap().joints[0].effort_limit;
        let max = tau.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        println!("{name}: static stance torques (N·m) {tau:.4?}, max {max:.4}, limit {limit}");
        assert!(2.0 * max <= limit, "{name}: {max} N·m × 2 > {limit} N·m");
    }
}

#[test]
fn robots_module_lists_both_builtins() {
    assert_eq!(builtin_names(), ["quad16", "quad12"]);
    // and the robots module docs name their parameter tables
    assert!(robots::quad16::PARAMS.len() >= 17 && robots::quad12::PARAMS.len() >= 17);
    // joint kinds: all revolute in quad16; quad12 adds one fixed foot joint per leg
    let q12 = builtin("quad12").unwrap();
    let fixed = q12
        .joints
        .iter()
        .filter(|j| j.kind == JointKind::Fixed)
        .count();
    assert_eq!(fixed, 4);
}
