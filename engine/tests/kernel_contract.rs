//! The kernel contract (docs/architecture.md): every kernel a model's plan
//! picks gives the scalar path's bits. Checked on seeded random four-legged
//! trees (random depths, axes, placements, masses and inertias, so that the
//! plan is `LegsX4`), on random general trees (plan `Scalar`: the dispatch
//! is the scalar path) and on the built-in robots, at random states with
//! external forces.

mod common;

use common::{random_state, random_tree, random_vec, rng};
use glam::{DMat3, DQuat, DVec3};
use quadsim_engine::description::{JointDesc, JointKind, LinkDesc, RobotDescription};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::plan::Plan;
use quadsim_engine::spatial::{Force, Transform};
use quadsim_engine::{Data, aba, com, crba, dispatch, kinematics, rnea};
use rand::Rng;

/// A random base with four legs of `depth` bodies: at each depth the four
/// joints turn about one signed unit axis, and their placements all rotate
/// or none does (what `Plan::LegsX4` asks); everything else is random.
fn random_legged(seed: u64, depth: usize) -> RobotDescription {
    let mut r = rng(seed);
    let mut d = RobotDescription::new(format!("legged{seed}"));
    let mut base = LinkDesc::new("base");
    base.mass_kg = r.random_range(2.0..10.0);
    base.com_m = DVec3::new(
        r.random_range(-0.05..0.05),
        0.0,
        r.random_range(-0.05..0.05),
    );
    base.inertia_kgm2 = Some(DMat3::from_diagonal(DVec3::new(0.1, 0.3, 0.35)));
    d.links.push(base);
    let axes = [
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ];
    let depth_axis: Vec<DVec3> = (0..depth).map(|_| axes[r.random_range(0..6)]).collect();
    let depth_rotates: Vec<bool> = (0..depth).map(|_| r.random_bool(0.5)).collect();
    for leg in 0..4 {
        for g in 0..depth {
            let name = format!("l{leg}_{g}");
            let mut l = LinkDesc::new(name.clone());
            l.mass_kg = r.random_range(0.1..2.0);
            l.com_m = DVec3::new(
                r.random_range(-0.1..0.1),
                r.random_range(-0.1..0.1),
                r.random_range(-0.2..0.0),
            );
            let (a, b): (f64, f64) = (r.random_range(0.001..0.02), r.random_range(0.001..0.02));
            let c = r.random_range((a - b).abs() + 0.0005..a + b);
            l.inertia_kgm2 = Some(DMat3::from_diagonal(DVec3::new(a, b, c)));
            d.links.push(l);
            let rot = if depth_rotates[g] {
                DMat3::from_quat(DQuat::from_euler(
                    glam::EulerRot::ZYX,
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                ))
            } else {
                DMat3::IDENTITY
            };
            let at = DVec3::new(
                r.random_range(-0.3..0.3),
                r.random_range(-0.3..0.3),
                r.random_range(-0.3..-0.05),
            );
            let parent = if g == 0 {
                "base".to_string()
            } else {
                format!("l{leg}_{}", g - 1)
            };
            d.joints.push(JointDesc::new(
                format!("j{leg}_{g}"),
                JointKind::Revolute {
                    axis: depth_axis[g],
                },
                parent,
                name,
                Transform::new(rot, at),
            ));
        }
    }
    d
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// Every field each dispatch function fills, against the scalar path, bit
/// for bit, at `trials` random states of `model` with external forces.
fn check_contract(model: &Model, seed: u64, trials: u64) {
    let nb = model.nbodies;
    for t in 0..trials {
        let (q, v) = random_state(model, seed * 1000 + t, 4.0, 1.0);
        let tau = random_vec(seed * 2000 + t, model.nv, 30.0);
        let a = random_vec(seed * 3000 + t, model.nv, 5.0);
        let (mut fast, mut slow) = (Data::new(model), Data::new(model));
        dispatch::forward_kinematics(model, &mut fast, &q, &v);
        kinematics::forward_kinematics(model, &mut slow, &q, &v);
        for i in 0..nb {
            let what = format!("{} trial {t} body {i}", model.name);
            assert_eq!(fast.pose[i], slow.pose[i], "pose, {what}");
            assert_eq!(fast.vel[i], slow.vel[i], "vel, {what}");
            assert_eq!(
                fast.body_inertia(model, i),
                slow.body_inertia(model, i),
                "inertia, {what}"
            );
            if i > 0 {
                assert_eq!(
                    fast.subspace(model, i),
                    slow.subspace(model, i),
                    "s, {what}"
                );
            }
        }
        let com_fast = dispatch::com_and_velocity_by_legs(model, &fast);
        let com_slow = com::com_and_velocity_by_legs(model, &slow);
        assert_eq!(com_fast, com_slow, "CoM by legs, {} trial {t}", model.name);
        for d in [&mut fast, &mut slow] {
            for (i, f) in d.external_forces_mut().iter_mut().enumerate() {
                let k = (i as f64 + t as f64) * 0.37;
                *f = Force::new(
                    DVec3::new(k.sin() * 20.0, k.cos() * 5.0, 30.0 - k),
                    DVec3::new(0.1 * k, -0.2, k.cos()),
                );
            }
        }
        dispatch::aba_from_kinematics(model, &mut fast, &v, &tau, true);
        aba::aba_from_kinematics(model, &mut slow, &v, &tau, true);
        assert_eq!(
            bits(&fast.ddq),
            bits(&slow.ddq),
            "ABA ddq, {} trial {t}",
            model.name
        );
        assert_eq!(fast.acc, slow.acc, "ABA acc, {} trial {t}", model.name);
        dispatch::rnea_from_kinematics(model, &mut fast, &v, &a, true);
        rnea::rnea_from_kinematics(model, &mut slow, &v, &a, true);
        assert_eq!(
            bits(&fast.tau),
            bits(&slow.tau),
            "RNEA tau, {} trial {t}",
            model.name
        );
        assert_eq!(fast.f, slow.f, "RNEA f, {} trial {t}", model.name);
        let nv0 = model.base_nv();
        let mut joints = vec![0.0; model.nv - nv0];
        dispatch::rnea_joint_torques_from_kinematics(model, &mut fast, &v, &a, &mut joints);
        rnea::rnea_from_kinematics(model, &mut slow, &v, &a, false);
        assert_eq!(
            bits(&joints),
            bits(&slow.tau[nv0..]),
            "RNEA joints, {} trial {t}",
            model.name
        );
        let m_fast = dispatch::crba(model, &mut fast, &q).to_vec();
        let m_slow = crba::crba(model, &mut slow, &q).to_vec();
        assert_eq!(
            bits(&m_fast),
            bits(&m_slow),
            "CRBA, {} trial {t}",
            model.name
        );
    }
}

#[test]
fn lane_kernels_give_the_scalar_bits_on_random_legged_trees() {
    for seed in 0..12 {
        let depth = 1 + (seed as usize % 4);
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            let model = Model::from_description(&random_legged(seed, depth), base).unwrap();
            if cfg!(target_arch = "x86_64") {
                assert!(
                    matches!(model.plan, Plan::LegsX4(_)),
                    "seed {seed}: four identical legs run in lanes"
                );
            }
            check_contract(&model, seed, 6);
        }
    }
}

#[test]
fn dispatch_is_the_scalar_path_on_random_general_trees() {
    for seed in 0..8 {
        let model = Model::from_description(&random_tree(seed, 9), BaseKind::Floating).unwrap();
        assert!(
            matches!(model.plan, Plan::Scalar),
            "seed {seed}: a general tree"
        );
        check_contract(&model, seed, 4);
    }
}

#[test]
fn lane_kernels_give_the_scalar_bits_on_the_built_in_robots() {
    for name in quadsim_engine::robots::builtin_names() {
        let desc = quadsim_engine::robots::builtin(name).unwrap();
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            let model = Model::from_description(&desc, base).unwrap();
            check_contract(&model, 77, 8);
        }
    }
}
