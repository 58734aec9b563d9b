//! The whole-body layer's task-space hierarchy ([`WholeBody::solve`]: the
//! tree's sparse `M = Lᵀ L` and `R × R` task-space matrices) against the
//! dense recursion it replaced ([`WholeBody::solve_reference`]: `M⁻¹` and
//! `nv × nv` null-space projectors): the same torques, accelerations, ground
//! forces and base change to 1e-10 of their size, on random states of
//! quad16, quad12 and random four-legged trees, with random sets of stance
//! feet, swing feet and joint postures (every leg standing, none, and the
//! mixes in between).
//!
//! Those are the walker's problems: each task has room left by the ones
//! before it. When it has none (more task rows than coordinates, or rows
//! that depend on earlier ones), its `Λ⁻¹` is the damping's size (1e-6) and
//! both algorithms' answers carry round-off amplified by 1e6 and more;
//! random trees with random tasks check that case to 1e-3 (they differ by
//! up to 3e-5 there; a different algebra would differ at the answers' size).

mod common;

use glam::{DMat3, DVec3};
use quadsim_engine::control::wbc::{
    BodyTask, ContactTask, JointTask, PointTask, WbcOutput, WbcParams, WholeBody,
};
use quadsim_engine::description::{JointDesc, JointKind, LinkDesc, RobotDescription};
use quadsim_engine::kinematics::{forward_kinematics, frame_pose};
use quadsim_engine::legs::{FootPoint, LegKinematics};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::spatial::Transform;
use quadsim_engine::{Data, robots};
use rand::Rng;

/// Largest difference over `a` and `b`, relative to the larger of 1 and `b`'s largest entry.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

fn flat(out: &WbcOutput) -> Vec<f64> {
    let mut v: Vec<f64> = out.forces_n.iter().flat_map(|f| f.to_array()).collect();
    v.extend_from_slice(&out.base_change);
    v
}

struct Case {
    contacts: Vec<ContactTask>,
    points: Vec<PointTask>,
    joints: Vec<JointTask>,
    body: BodyTask,
}

/// Both solves of one case; panics unless they agree to `tol`.
fn compare(model: &Model, data: &mut Data, v: &[f64], c: &Case, what: &str, tol: f64) {
    let mut fast = WholeBody::new(model, WbcParams::default());
    let mut dense = WholeBody::new(model, WbcParams::default());
    let nb = model.base_nv();
    let mut tau_f = vec![0.0; model.nv - nb];
    let mut tau_d = vec![0.0; model.nv - nb];
    let of = fast.solve(
        model,
        data,
        v,
        &c.contacts,
        &c.body,
        &c.points,
        &c.joints,
        &mut tau_f,
    );
    let od = dense.solve_reference(
        model,
        data,
        v,
        &c.contacts,
        &c.body,
        &c.points,
        &c.joints,
        &mut tau_d,
    );
    let (of, od) = match (of, od) {
        (Ok(a), Ok(b)) => (a, b),
        (a, b) => panic!("{what}: fast {a:?}, dense {b:?}"),
    };
    assert_eq!(of.qp_solved, od.qp_solved, "{what}: QP solved or not");
    let checks = [
        ("torques", rel_diff(&tau_f, &tau_d)),
        (
            "accelerations",
            rel_diff(fast.accelerations(), dense.accelerations()),
        ),
        ("forces and base change", rel_diff(&flat(&of), &flat(&od))),
    ];
    for (name, d) in checks {
        assert!(d < tol, "{what}: {name} differ by {d:e} (relative)");
    }
}

/// quad16 or quad12 near its stance with a random state and a random mix
/// of stance and swing feet.
fn robot_cases(name: &str, seeds: std::ops::Range<u64>) {
    let desc = robots::builtin(name).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
    let mut data = Data::new(&model);
    let stance = robots::nominal_stance(name).unwrap();
    for seed in seeds {
        let mut r = common::rng(seed);
        let mut q = vec![0.0, 0.0, 0.45, 0.0, 0.0, 0.0, 1.0];
        q.extend_from_slice(&stance);
        for x in &mut q {
            *x += r.random_range(-0.1..0.1);
        }
        let n = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
        q[3..7].iter_mut().for_each(|x| *x /= n);
        let v: Vec<f64> = (0..model.nv).map(|_| r.random_range(-1.0..1.0)).collect();
        forward_kinematics(&model, &mut data, &q, &v);
        // legs standing: bit k of the seed's pattern (all 16 patterns)
        let pattern = seed % 16;
        let mut case = Case {
            contacts: Vec::new(),
            points: Vec::new(),
            joints: Vec::new(),
            body: BodyTask {
                force_n: DVec3::new(
                    r.random_range(-50.0..50.0),
                    r.random_range(-50.0..50.0),
                    model.total_mass * 9.81 + r.random_range(-50.0..50.0),
                ),
                torque_nm: DVec3::new(
                    r.random_range(-5.0..5.0),
                    r.random_range(-5.0..5.0),
                    r.random_range(-5.0..5.0),
                ),
            },
        };
        for (i, leg) in legs.iter().enumerate() {
            let frame = leg.foot_frame();
            let local = FootPoint::Contact.in_foot(&desc, &model.frames[frame].name);
            let p = frame_pose(&model, &data, frame).transform_point(local);
            let body = model.frames[frame].body;
            if pattern >> i & 1 == 1 {
                case.contacts.push(ContactTask {
                    body,
                    point_m: p,
                    normal: DVec3::new(r.random_range(-0.2..0.2), 0.0, 1.0).normalize(),
                    friction: r.random_range(0.4..1.0),
                    load: r.random_range(0.3..1.0),
                    force_plan_n: DVec3::new(
                        r.random_range(-20.0..20.0),
                        r.random_range(-20.0..20.0),
                        r.random_range(0.0..200.0),
                    ),
                });
            } else {
                case.points.push(PointTask {
                    body,
                    point_m: p,
                    acc_mps2: DVec3::new(
                        r.random_range(-20.0..20.0),
                        r.random_range(-20.0..20.0),
                        r.random_range(-20.0..20.0),
                    ),
                });
            }
            // a posture on a 4-DOF leg's last joint (quad16's ankle), on
            // some legs, as the walker asks
            if leg.v_indices().len() == 4 && r.random_bool(0.75) {
                let vi = *leg.v_indices().last().unwrap();
                case.joints.push(JointTask {
                    v_index: vi,
                    acc_radps2: r.random_range(-10.0..10.0),
                });
            }
        }
        compare(
            &model,
            &mut data,
            &v,
            &case,
            &format!("{name} seed {seed} (stance pattern {pattern:04b})"),
            1e-10,
        );
    }
}

#[test]
fn quad16_task_space_hierarchy_gives_the_dense_answer() {
    robot_cases("quad16", 0..96);
}

#[test]
fn quad12_task_space_hierarchy_gives_the_dense_answer() {
    robot_cases("quad12", 0..64);
}

/// A random four-legged tree: a base and four legs of three or four
/// revolute joints with random axes, placements, masses and inertias. With
/// `breadth_first` the links are listed joint by joint across the legs
/// (all hips, then all thighs, …), so that a leg's coordinates are not
/// contiguous in `v`.
fn random_quadruped(seed: u64, breadth_first: bool) -> (RobotDescription, Vec<Vec<String>>) {
    let mut r = common::rng(seed);
    let mut d = RobotDescription::new(format!("quadruped{seed}"));
    let mut base = LinkDesc::new("base");
    base.mass_kg = r.random_range(5.0..20.0);
    base.inertia_kgm2 = Some(DMat3::from_diagonal(DVec3::new(0.1, 0.3, 0.35)));
    d.links.push(base);
    let dofs: Vec<usize> = (0..4).map(|_| r.random_range(3..=4)).collect();
    let mut legs = vec![Vec::new(); 4];
    let mut order = Vec::new();
    if breadth_first {
        for j in 0..4 {
            for (leg, &n) in dofs.iter().enumerate() {
                if j < n {
                    order.push((leg, j));
                }
            }
        }
    } else {
        for (leg, &n) in dofs.iter().enumerate() {
            for j in 0..n {
                order.push((leg, j));
            }
        }
    }
    for (leg, j) in order {
        let name = format!("leg{leg}_{j}");
        let mut l = LinkDesc::new(name.clone());
        l.mass_kg = r.random_range(0.3..3.0);
        l.com_m = DVec3::new(0.0, 0.0, -r.random_range(0.05..0.15));
        l.inertia_kgm2 = Some(DMat3::from_diagonal(DVec3::new(
            r.random_range(0.005..0.03),
            r.random_range(0.005..0.03),
            r.random_range(0.002..0.01),
        )));
        d.links.push(l);
        let (parent, offset) = if j == 0 {
            let (sx, sy) = [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)][leg];
            ("base".to_string(), DVec3::new(0.3 * sx, 0.15 * sy, 0.0))
        } else {
            (
                format!("leg{leg}_{}", j - 1),
                DVec3::new(0.0, 0.0, -r.random_range(0.15..0.3)),
            )
        };
        let axis = (DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        ) + [DVec3::X, DVec3::Y, DVec3::Y, DVec3::Y][j])
            .normalize();
        d.joints.push(JointDesc::new(
            format!("j{leg}_{j}"),
            JointKind::Revolute { axis },
            parent,
            name.clone(),
            Transform::from_translation(offset),
        ));
        legs[leg].push(name);
    }
    (d, legs)
}

/// Random four-legged trees in random states: each leg stands or swings,
/// a 4-DOF leg's last joint may hold a posture.
#[test]
fn random_quadrupeds_task_space_hierarchy_gives_the_dense_answer() {
    for seed in 0..48u64 {
        let (desc, legs) = random_quadruped(seed, seed % 2 == 1);
        let model = common::model(&desc, BaseKind::Floating);
        let mut data = Data::new(&model);
        let (mut q, v) = common::random_state(&model, seed + 500, 2.0, 1.0);
        let mut r = common::rng(seed + 900);
        for x in &mut q[7..] {
            *x = r.random_range(-0.8..0.8); // legs away from straight
        }
        forward_kinematics(&model, &mut data, &q, &v);
        let pattern = seed % 16;
        let mut case = Case {
            contacts: Vec::new(),
            points: Vec::new(),
            joints: Vec::new(),
            body: BodyTask {
                force_n: DVec3::new(3.0, -1.0, model.total_mass * 9.81),
                torque_nm: DVec3::new(0.5, 0.2, -0.3),
            },
        };
        for (i, leg) in legs.iter().enumerate() {
            let frame = model.frame_index(leg.last().unwrap()).unwrap();
            let body = model.frames[frame].body;
            let p = data.pose[body].transform_point(DVec3::new(0.0, 0.0, -0.2));
            if pattern >> i & 1 == 1 {
                case.contacts.push(ContactTask {
                    body,
                    point_m: p,
                    normal: DVec3::Z,
                    friction: 0.8,
                    load: 1.0,
                    force_plan_n: DVec3::new(1.0, -2.0, 60.0),
                });
            } else {
                case.points.push(PointTask {
                    body,
                    point_m: p,
                    acc_mps2: DVec3::new(r.random_range(-9.0..9.0), 2.0, -3.0),
                });
            }
            if leg.len() == 4 && r.random_bool(0.75) {
                let vi = model.joint_v_index(&format!("j{i}_3")).unwrap();
                case.joints.push(JointTask {
                    v_index: vi,
                    acc_radps2: r.random_range(-5.0..5.0),
                });
            }
        }
        compare(
            &model,
            &mut data,
            &v,
            &case,
            &format!("random quadruped {seed} (stance pattern {pattern:04b})"),
            1e-10,
        );
    }
}

/// Random floating-base trees (branches of any depth, prismatic and fixed
/// joints): contacts, points and postures on random bodies and joints, so
/// that tasks may have no room left (the module docs: checked to 1e-3).
#[test]
fn random_trees_task_space_hierarchy_gives_the_dense_answer_when_ill_conditioned() {
    for seed in 0..40u64 {
        let desc = common::random_tree(seed, 14);
        let model = common::model(&desc, BaseKind::Floating);
        let mut data = Data::new(&model);
        let (q, v) = common::random_state(&model, seed + 500, 2.0, 1.0);
        forward_kinematics(&model, &mut data, &q, &v);
        let mut r = common::rng(seed + 900);
        let nbodies = model.nbodies;
        let pick = |r: &mut rand_chacha::ChaCha8Rng| {
            let b = r.random_range(1..nbodies);
            let p = data.pose[b].transform_point(DVec3::new(
                r.random_range(-0.1..0.1),
                r.random_range(-0.1..0.1),
                r.random_range(-0.1..0.1),
            ));
            (b, p)
        };
        let nc = r.random_range(0..=4);
        let np = r.random_range(0..=4);
        let contacts = (0..nc)
            .map(|_| {
                let (body, point_m) = pick(&mut r);
                ContactTask {
                    body,
                    point_m,
                    normal: DVec3::Z,
                    friction: 0.8,
                    load: 1.0,
                    force_plan_n: DVec3::new(1.0, -2.0, 30.0),
                }
            })
            .collect();
        let points = (0..np)
            .map(|_| {
                let (body, point_m) = pick(&mut r);
                PointTask {
                    body,
                    point_m,
                    acc_mps2: DVec3::new(1.0, 2.0, -3.0),
                }
            })
            .collect();
        let nj = r.random_range(0..=4);
        let joints = (0..nj)
            .map(|_| JointTask {
                v_index: r.random_range(6..model.nv),
                acc_radps2: r.random_range(-5.0..5.0),
            })
            .collect();
        let case = Case {
            contacts,
            points,
            joints,
            body: BodyTask {
                force_n: DVec3::new(3.0, -1.0, model.total_mass * 9.81),
                torque_nm: DVec3::new(0.5, 0.2, -0.3),
            },
        };
        compare(
            &model,
            &mut data,
            &v,
            &case,
            &format!("random tree {seed} ({nc} contacts, {np} points, {nj} postures)"),
            1e-3,
        );
    }
}
