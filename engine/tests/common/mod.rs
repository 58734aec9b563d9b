//! Shared helpers for the engine's integration tests: seeded random trees and states.
#![allow(dead_code)]

use glam::{DMat3, DQuat, DVec3};
use quadsim_engine::Data;
use quadsim_engine::aba::aba;
use quadsim_engine::crba::crba;
use quadsim_engine::description::{JointDesc, JointKind, LinkDesc, RobotDescription};
use quadsim_engine::linalg::cholesky_dense;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::nle::{generalized_gravity, nonlinear_effects};
use quadsim_engine::rnea::rnea;
use quadsim_engine::spatial::Transform;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn unit(r: &mut ChaCha8Rng) -> DVec3 {
    loop {
        let v = DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        let n = v.length();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

fn rand_rot(r: &mut ChaCha8Rng) -> DMat3 {
    DMat3::from_quat(DQuat::from_axis_angle(unit(r), r.random_range(-3.0..3.0)))
}

fn rand_inertia(r: &mut ChaCha8Rng) -> DMat3 {
    // principal moments satisfying the triangle inequality, rotated
    let a: f64 = r.random_range(0.01..0.2);
    let b: f64 = r.random_range(0.01..0.2);
    let c: f64 = r.random_range((a - b).abs() + 0.005..a + b);
    let rot = rand_rot(r);
    rot * DMat3::from_diagonal(DVec3::new(a, b, c)) * rot.transpose()
}

/// A random tree of `n` moving links (revolute, prismatic and some fixed joints),
/// each joint's parent chosen among the earlier links.
pub fn random_tree(seed: u64, n: usize) -> RobotDescription {
    let mut r = rng(seed);
    let mut d = RobotDescription::new(format!("random{seed}"));
    let mut base = LinkDesc::new("l0");
    base.mass_kg = r.random_range(1.0..5.0);
    base.com_m = unit(&mut r) * 0.1;
    base.inertia_kgm2 = Some(rand_inertia(&mut r));
    d.links.push(base);
    for i in 1..=n {
        let mut l = LinkDesc::new(format!("l{i}"));
        l.mass_kg = r.random_range(0.2..3.0);
        l.com_m = unit(&mut r) * r.random_range(0.0..0.3);
        l.inertia_kgm2 = Some(rand_inertia(&mut r));
        d.links.push(l);
        let parent = r.random_range(0..i);
        let kind = match r.random_range(0..10) {
            0 => JointKind::Prismatic { axis: unit(&mut r) },
            1 => JointKind::Fixed,
            _ => JointKind::Revolute { axis: unit(&mut r) },
        };
        let placement = Transform::new(rand_rot(&mut r), unit(&mut r) * r.random_range(0.05..0.4));
        d.joints.push(JointDesc::new(
            format!("j{i}"),
            kind,
            format!("l{parent}"),
            format!("l{i}"),
            placement,
        ));
    }
    d
}

/// A random state: unit base quaternion, |q̇| ≤ `qd_max`, base velocities ≤ `base_max`.
pub fn random_state(model: &Model, seed: u64, qd_max: f64, base_max: f64) -> (Vec<f64>, Vec<f64>) {
    let mut r = rng(seed);
    let mut q = vec![0.0; model.nq];
    let mut v = vec![0.0; model.nv];
    let (bq, bv) = (model.base_nq(), model.base_nv());
    if model.is_floating() {
        for k in 0..3 {
            q[k] = r.random_range(-1.0..1.0);
        }
        let quat = DQuat::from_axis_angle(unit(&mut r), r.random_range(-3.0..3.0));
        q[3..7].copy_from_slice(&[quat.x, quat.y, quat.z, quat.w]);
        for k in 0..6 {
            v[k] = r.random_range(-base_max..base_max);
        }
    }
    for k in bq..model.nq {
        q[k] = r.random_range(-3.0..3.0);
    }
    for k in bv..model.nv {
        v[k] = r.random_range(-qd_max..qd_max);
    }
    (q, v)
}

pub fn random_vec(seed: u64, n: usize, scale: f64) -> Vec<f64> {
    let mut r = rng(seed);
    (0..n).map(|_| r.random_range(-scale..scale)).collect()
}

pub fn model(desc: &RobotDescription, base: BaseKind) -> Model {
    Model::from_description(desc, base).expect("valid model")
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The model-independent identities at a seeded random state: ABA(RNEA(a)) = a,
/// CRBA's columns are RNEA differences, M is symmetric positive definite,
/// RNEA = M a + nle, gravity = RNEA(q, 0, 0), and repeated calls (also through
/// a fresh workspace) are bit-identical.
pub fn check_identities(model: &Model, seed: u64) {
    let mut data = Data::new(model);
    let (q, v) = random_state(model, seed, 2.0, 1.0);
    let a = random_vec(seed + 1000, model.nv, 3.0);
    let nv = model.nv;
    let name = &model.name;

    // ABA(RNEA(a)) = a
    let tau = rnea(model, &mut data, &q, &v, &a).to_vec();
    let a2 = aba(model, &mut data, &q, &v, &tau).to_vec();
    let scale = a.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let err = max_abs_diff(&a, &a2);
    assert!(
        err <= 1e-9 * scale,
        "{name} seed {seed}: ABA(RNEA(a)) off by {err}"
    );

    // M columns = RNEA(q, 0, e_i) − RNEA(q, 0, 0)
    let m = crba(model, &mut data, &q).to_vec();
    let zero = vec![0.0; nv];
    let g = rnea(model, &mut data, &q, &zero, &zero).to_vec();
    for i in 0..nv {
        let mut e = vec![0.0; nv];
        e[i] = 1.0;
        let col = rnea(model, &mut data, &q, &zero, &e).to_vec();
        for r in 0..nv {
            let d = col[r] - g[r];
            assert!(
                (d - m[r * nv + i]).abs() <= 1e-10 * (1.0 + d.abs()),
                "{name} seed {seed}: M[{r}][{i}] = {} vs {d}",
                m[r * nv + i]
            );
        }
    }
    // symmetric and positive definite
    for r in 0..nv {
        for c in 0..nv {
            assert_eq!(
                m[r * nv + c],
                m[c * nv + r],
                "{name}: M not symmetric at {r},{c}"
            );
        }
    }
    let mut l = m.clone();
    assert!(
        cholesky_dense(&mut l, nv),
        "{name}: M is not positive definite"
    );

    // RNEA(a) = M a + nle; gravity = RNEA(q, 0, 0)
    let nle = nonlinear_effects(model, &mut data, &q, &v).to_vec();
    for r in 0..nv {
        let ma: f64 = (0..nv).map(|c| m[r * nv + c] * a[c]).sum();
        assert!(
            (ma + nle[r] - tau[r]).abs() <= 1e-9 * (1.0 + tau[r].abs()),
            "{name} seed {seed}: M a + nle != rnea at {r}"
        );
    }
    let grav = generalized_gravity(model, &mut data, &q).to_vec();
    assert_eq!(grav, g);

    // Repeated calls are bit-identical, also through a fresh workspace.
    let mut data2 = Data::new(model);
    let a3 = aba(model, &mut data2, &q, &v, &tau).to_vec();
    assert_eq!(a2, a3);
    let a4 = aba(model, &mut data2, &q, &v, &tau).to_vec();
    assert_eq!(a3, a4);
    let m2 = crba(model, &mut data2, &q).to_vec();
    assert_eq!(m, m2);
}
