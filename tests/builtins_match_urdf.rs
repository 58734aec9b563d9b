//! The built-in robots at their defaults are the robots of the shared URDFs
//! (`tests/fixtures/models/quad16.urdf`, `quad12.urdf`, copies of
//! `/work/shared/models`): every link's mass, CoM and inertia, every joint's
//! type, axis, placement, parents and limits, the q/v order, the compiled
//! models and the forward kinematics of every frame agree to 1e-12.
//!
//! One documented exception: the URDFs print the torso's box inertia to ten
//! significant digits (`0.3083333333`), while the built-ins derive it from the
//! box formula exactly (0.308333…); those three entries are compared to the
//! URDF's printed precision (half a unit in the tenth significant digit,
//! ≤ 5·10⁻¹¹ kg·m²). Actuator effort and velocity limits differ on purpose (the
//! URDFs carry placeholders, the built-ins documented assumptions) and are not
//! compared.

use glam::{DMat3, DQuat, DVec3};
use quadsim::engine::Data;
use quadsim::engine::description::{JointKind, RobotDescription};
use quadsim::engine::kinematics::{forward_kinematics_pos, frame_pose};
use quadsim::engine::model::{BaseKind, Model};
use quadsim::engine::robots::builtin;
use quadsim::engine::spatial::RigidInertia;
use quadsim::urdf::{UrdfOptions, load_urdf};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

const TOL: f64 = 1e-12;

fn load(name: &str) -> RobotDescription {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/models/{name}.urdf"));
    load_urdf(&path, &UrdfOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .description
}

/// Half a unit in the tenth significant digit of `x`: the rounding of a value
/// printed with ten significant digits.
fn ten_digit_rounding(x: f64) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    0.5 * 10f64.powf(x.abs().log10().floor() - 9.0)
}

fn close_vec(a: DVec3, b: DVec3, tol: f64, what: &str) {
    assert!((a - b).abs().max_element() <= tol, "{what}: {a} vs {b}");
}

fn close_mat(a: DMat3, b: DMat3, tol: f64, what: &str) {
    let (x, y) = (a.to_cols_array(), b.to_cols_array());
    for k in 0..9 {
        assert!((x[k] - y[k]).abs() <= tol, "{what}: {a} vs {b}");
    }
}

/// Inertia tensors: entry-wise to `TOL`, or for the torso to the URDF's printed precision.
fn close_inertia(built: DMat3, urdf: DMat3, is_torso: bool, what: &str) {
    let (x, y) = (built.to_cols_array(), urdf.to_cols_array());
    for k in 0..9 {
        let tol = if is_torso {
            TOL.max(ten_digit_rounding(y[k]))
        } else {
            TOL
        };
        assert!((x[k] - y[k]).abs() <= tol, "{what}: {built} vs {urdf}");
    }
}

fn close_rigid(a: &RigidInertia, b: &RigidInertia, is_torso: bool, what: &str) {
    assert!(
        (a.mass - b.mass).abs() <= TOL,
        "{what}: mass {} vs {}",
        a.mass,
        b.mass
    );
    close_vec(a.com, b.com, TOL, &format!("{what}: CoM"));
    close_inertia(
        a.inertia_com,
        b.inertia_com,
        is_torso,
        &format!("{what}: inertia"),
    );
}

fn compare_descriptions(built: &RobotDescription, urdf: &RobotDescription) {
    let name = &built.name;
    assert_eq!(built.name, urdf.name);
    let names = |d: &RobotDescription| d.links.iter().map(|l| l.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(built), names(urdf), "{name}: links and their order");
    for (b, u) in built.links.iter().zip(&urdf.links) {
        let what = format!("{name} link {}", b.name);
        close_rigid(
            &b.rigid_inertia(),
            &u.rigid_inertia(),
            b.name == "torso",
            &what,
        );
        // every collision shape of the URDF is in the built-in, at the same place
        for ug in &u.collision {
            let found = b.collision.iter().any(|bg| {
                bg.shape == ug.shape
                    && (bg.origin.trans - ug.origin.trans).abs().max_element() <= TOL
                    && (bg.origin.rot - ug.origin.rot)
                        .abs()
                        .to_cols_array()
                        .iter()
                        .all(|e| *e <= TOL)
            });
            assert!(found, "{what}: URDF collision {ug:?} missing");
        }
    }
    let jnames = |d: &RobotDescription| d.joints.iter().map(|j| j.name.clone()).collect::<Vec<_>>();
    assert_eq!(
        jnames(built),
        jnames(urdf),
        "{name}: joints and their order"
    );
    for (b, u) in built.joints.iter().zip(&urdf.joints) {
        let what = format!("{name} joint {}", b.name);
        assert_eq!(
            (&b.parent, &b.child),
            (&u.parent, &u.child),
            "{what}: links"
        );
        match (b.kind, u.kind) {
            (JointKind::Revolute { axis: a }, JointKind::Revolute { axis: c }) => {
                close_vec(a, c, TOL, &format!("{what}: axis"))
            }
            (JointKind::Fixed, JointKind::Fixed) => {}
            (x, y) => panic!("{what}: kind {x:?} vs {y:?}"),
        }
        close_vec(
            b.placement.trans,
            u.placement.trans,
            TOL,
            &format!("{what}: origin xyz"),
        );
        close_mat(
            b.placement.rot,
            u.placement.rot,
            TOL,
            &format!("{what}: origin rotation"),
        );
        match (b.limits, u.limits) {
            (Some((bl, bh)), Some((ul, uh))) => {
                assert!(
                    (bl - ul).abs() <= TOL && (bh - uh).abs() <= TOL,
                    "{what}: limits"
                )
            }
            (None, None) => {}
            (x, y) => panic!("{what}: limits {x:?} vs {y:?}"),
        }
        for (x, y, field) in [
            (b.damping, u.damping, "damping"),
            (b.friction, u.friction, "friction"),
            (b.armature, u.armature, "armature"),
        ] {
            assert!((x - y).abs() <= TOL, "{what}: {field} {x} vs {y}");
        }
    }
    assert_eq!(built.dof(), urdf.dof());
    assert_eq!(built.foot_names(), urdf.foot_names(), "{name}: feet");
}

fn compare_models(mb: &Model, mu: &Model) {
    let name = &mb.name;
    assert_eq!(
        (mb.nq, mb.nv, mb.nbodies),
        (mu.nq, mu.nv, mu.nbodies),
        "{name}: sizes"
    );
    assert_eq!(
        mb.movable_joint_names(),
        mu.movable_joint_names(),
        "{name}: q/v order"
    );
    assert_eq!(mb.parent, mu.parent);
    assert_eq!(mb.joint_type, mu.joint_type);
    assert_eq!(mb.joint_name, mu.joint_name);
    assert_eq!(mb.idx_q, mu.idx_q);
    assert_eq!(mb.idx_v, mu.idx_v);
    for i in 0..mb.nbodies {
        let what = format!("{name} body {i} ({})", mb.joint_name[i]);
        close_vec(mb.placement[i].trans, mu.placement[i].trans, TOL, &what);
        close_mat(mb.placement[i].rot, mu.placement[i].rot, TOL, &what);
        close_vec(mb.axis[i], mu.axis[i], TOL, &what);
        close_rigid(&mb.inertia[i], &mu.inertia[i], i == 0, &what);
    }
    for k in 0..mb.nv {
        assert_eq!(
            mb.lower_limit[k], mu.lower_limit[k],
            "{name}: lower limit {k}"
        );
        assert_eq!(
            mb.upper_limit[k], mu.upper_limit[k],
            "{name}: upper limit {k}"
        );
    }
    assert_eq!(mb.frames.len(), mu.frames.len());
    for (fb, fu) in mb.frames.iter().zip(&mu.frames) {
        assert_eq!((&fb.name, fb.body), (&fu.name, fu.body));
        close_vec(fb.placement.trans, fu.placement.trans, TOL, &fb.name);
        close_mat(fb.placement.rot, fu.placement.rot, TOL, &fb.name);
    }
    assert_eq!(mb.feet, mu.feet);
    assert!((mb.total_mass - mu.total_mass).abs() <= TOL);
}

/// Forward kinematics of every frame agree at random configurations.
fn compare_kinematics(mb: &Model, mu: &Model, seed: u64) {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let (mut db, mut du) = (Data::new(mb), Data::new(mu));
    for _ in 0..20 {
        let mut q = vec![0.0; mb.nq];
        let mut first = 0;
        if mb.is_floating() {
            for x in &mut q[..3] {
                *x = r.random_range(-2.0..2.0);
            }
            let axis = DVec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            )
            .normalize();
            let quat = DQuat::from_axis_angle(axis, r.random_range(-3.0..3.0));
            q[3..7].copy_from_slice(&[quat.x, quat.y, quat.z, quat.w]);
            first = 7;
        }
        for x in &mut q[first..] {
            *x = r.random_range(-3.0..3.0);
        }
        forward_kinematics_pos(mb, &mut db, &q);
        forward_kinematics_pos(mu, &mut du, &q);
        for f in 0..mb.frames.len() {
            let (pb, pu) = (frame_pose(mb, &db, f), frame_pose(mu, &du, f));
            let what = format!("{}: frame {}", mb.name, mb.frames[f].name);
            close_vec(pb.trans, pu.trans, TOL, &what);
            close_mat(pb.rot, pu.rot, TOL, &what);
        }
    }
}

fn check(name: &str) {
    let built = builtin(name).unwrap();
    let urdf = load(name);
    compare_descriptions(&built, &urdf);
    for (k, base) in [BaseKind::Floating, BaseKind::Fixed]
        .into_iter()
        .enumerate()
    {
        let mb = Model::from_description(&built, base).unwrap();
        let mu = Model::from_description(&urdf, base).unwrap();
        compare_models(&mb, &mu);
        compare_kinematics(&mb, &mu, 40 + k as u64);
    }
}

#[test]
fn quad16_builtin_equals_its_urdf() {
    check("quad16");
}

#[test]
fn quad12_builtin_equals_its_urdf() {
    check("quad12");
}

/// The torso exception is as small as the URDF's printing explains, and no
/// larger: the exact box formula rounds to the URDF's ten digits.
#[test]
fn torso_inertia_differs_only_by_the_urdf_rounding() {
    for name in ["quad16", "quad12"] {
        let b = builtin(name)
            .unwrap()
            .link("torso")
            .unwrap()
            .rigid_inertia();
        let u = load(name).link("torso").unwrap().rigid_inertia();
        for k in 0..3 {
            let (x, y) = (b.inertia_com.col(k)[k], u.inertia_com.col(k)[k]);
            let printed: f64 = format!("{:.9e}", x).parse().unwrap();
            assert_eq!(
                printed, y,
                "{name}: I[{k}][{k}] = {x} prints as {printed}, URDF {y}"
            );
        }
    }
}
