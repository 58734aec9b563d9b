//! The whole-body layer ([`WholeBody`]) against the engine's forward
//! dynamics: its torques, with its ground forces applied at the feet, must
//! give back (through ABA, an independent algorithm) the accelerations it
//! planned; those keep the stance feet still (checked by finite differences
//! of the feet's velocities, independent of the layer's bias terms) and
//! meet the swing tasks and the torso's commanded accelerations.

mod common;

use glam::DVec3;
use quadsim_engine::aba::aba;
use quadsim_engine::control::wbc::{
    BodyTask, ContactTask, JointTask, PointTask, WbcParams, WholeBody,
};
use quadsim_engine::integrate::integrate_q;
use quadsim_engine::jacobian::add_point_force_jt;
use quadsim_engine::kinematics::{forward_kinematics, frame_pose};
use quadsim_engine::legs::{FootPoint, LegKinematics};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::{Data, robots};

/// quad16 standing near its nominal stance, with a pseudo-random state.
fn state(model: &Model, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let stance = robots::nominal_stance("quad16").unwrap();
    let mut q = vec![0.0, 0.0, 0.55, 0.0, 0.0, 0.0, 1.0];
    q.extend_from_slice(&stance);
    let dq = common::random_vec(seed, model.nq, 0.05);
    for (qi, d) in q.iter_mut().zip(&dq) {
        *qi += d;
    }
    let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
    for x in &mut q[3..7] {
        *x /= n;
    }
    let v = common::random_vec(seed + 100, model.nv, 0.5);
    (q, v)
}

/// World position and velocity of point `p_body` (body frame) of `body`.
fn point_state(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    frame: usize,
    p_local: DVec3,
) -> (DVec3, DVec3) {
    forward_kinematics(model, data, q, v);
    let pose = frame_pose(model, data, frame);
    let p = pose.transform_point(p_local);
    let body = model.frames[frame].body;
    let vel = data.vel[body].point_velocity(p - data.origin);
    (p, vel)
}

#[test]
fn torques_and_forces_reproduce_the_planned_accelerations() {
    let desc = robots::builtin("quad16").unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
    let mut data = Data::new(&model);
    let nv = model.nv;
    for seed in 1..=6u64 {
        let (q, v) = state(&model, seed);
        forward_kinematics(&model, &mut data, &q, &v);
        // legs 0 and 2 stand (a trot's diagonal), 1 and 3 swing
        let mut contacts = Vec::new();
        let mut points = Vec::new();
        let mut feet = Vec::new();
        for (i, leg) in legs.iter().enumerate() {
            let frame = leg.foot_frame();
            let local = FootPoint::Contact.in_foot(&desc, &model.frames[frame].name);
            let p = frame_pose(&model, &data, frame).transform_point(local);
            let body = model.frames[frame].body;
            feet.push((frame, local, body));
            if i % 2 == 0 {
                contacts.push(ContactTask {
                    body,
                    point_m: p,
                    normal: DVec3::Z,
                    friction: 0.8,
                    load: 1.0,
                    force_plan_n: DVec3::new(5.0, -3.0, 140.0),
                });
            } else {
                points.push(PointTask {
                    body,
                    point_m: p,
                    acc_mps2: DVec3::new(2.0, 0.5 * seed as f64, -3.0),
                });
            }
        }
        let joints = [JointTask {
            v_index: legs[1].v_indices()[3],
            acc_radps2: 1.5,
        }];
        let body = BodyTask {
            force_n: DVec3::new(20.0, 0.0, 28.0 * 9.81),
            torque_nm: DVec3::new(1.0, -2.0, 0.5),
        };
        let mut wbc = WholeBody::new(&model, WbcParams::default());
        let mut tau = vec![0.0; nv - 6];
        let out = wbc
            .solve(
                &model, &mut data, &v, &contacts, &body, &points, &joints, &mut tau,
            )
            .unwrap();
        assert!(out.qp_solved, "seed {seed}: the reaction QP failed");
        let qdd_plan = wbc.accelerations().to_vec();

        // forward dynamics with the torques and the forces
        forward_kinematics(&model, &mut data, &q, &v);
        let mut tau_all = vec![0.0; nv];
        tau_all[6..].copy_from_slice(&tau);
        for (k, c) in contacts.iter().enumerate() {
            add_point_force_jt(
                &model,
                &data,
                c.body,
                c.point_m,
                out.forces_n[k],
                &mut tau_all,
            );
        }
        let qdd = aba(&model, &mut data, &q, &v, &tau_all).to_vec();
        for (a, b) in qdd.iter().zip(&qdd_plan) {
            assert!(
                (a - b).abs() < 1e-7 * (1.0 + b.abs()),
                "seed {seed}: ABA {a} vs plan {b}"
            );
        }
        // friction pyramid and normal bounds of the forces
        for (k, f) in out.forces_n[..contacts.len()].iter().enumerate() {
            let mu = 0.8 / 2f64.sqrt();
            assert!(
                f.z >= 2.0 - 1e-9,
                "seed {seed}: foot {k} normal force {}",
                f.z
            );
            assert!(f.x.abs() <= mu * f.z + 1e-9 && f.y.abs() <= mu * f.z + 1e-9);
        }

        // the feet's accelerations by central differences of their velocities
        let eps = 1e-6;
        let accel = |frame: usize, local: DVec3, data: &mut Data| {
            let mut qp = vec![0.0; model.nq];
            let mut qm = vec![0.0; model.nq];
            integrate_q(&model, &q, &v, eps, &mut qp);
            integrate_q(&model, &q, &v, -eps, &mut qm);
            let vp: Vec<f64> = v.iter().zip(&qdd).map(|(a, b)| a + eps * b).collect();
            let vm: Vec<f64> = v.iter().zip(&qdd).map(|(a, b)| a - eps * b).collect();
            let (_, v1) = point_state(&model, data, &qp, &vp, frame, local);
            let (_, v0) = point_state(&model, data, &qm, &vm, frame, local);
            (v1 - v0) / (2.0 * eps)
        };
        let kc = WbcParams::default().contact_velocity_gain;
        for (i, &(frame, local, _)) in feet.iter().enumerate() {
            let a = accel(frame, local, &mut data);
            if i % 2 == 0 {
                // a stance foot's velocity decays at the contact rate: a = −k v
                let (_, vel) = point_state(&model, &mut data, &q, &v, frame, local);
                let want = -kc * vel;
                assert!(
                    (a - want).length() < 1e-4,
                    "seed {seed}: stance foot {i} accelerates {a}, expected {want}"
                );
            } else {
                let want = points[i / 2].acc_mps2;
                assert!(
                    (a - want).length() < 1e-4,
                    "seed {seed}: swing foot {i} accelerates {a}, task {want}"
                );
            }
        }
    }
}

/// Without contacts (a robot in flight) the base's equations leave nothing
/// to choose: there is no QP, the base takes what the legs' motion makes it,
/// and ABA gives back the plan.
#[test]
fn flight_gives_the_swing_tasks() {
    let desc = robots::builtin("quad16").unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
    let mut data = Data::new(&model);
    let (q, v) = state(&model, 7);
    forward_kinematics(&model, &mut data, &q, &v);
    let points: Vec<PointTask> = legs
        .iter()
        .map(|leg| {
            let frame = leg.foot_frame();
            let local = FootPoint::Contact.in_foot(&desc, &model.frames[frame].name);
            PointTask {
                body: model.frames[frame].body,
                point_m: frame_pose(&model, &data, frame).transform_point(local),
                acc_mps2: DVec3::new(0.0, 0.0, 1.0),
            }
        })
        .collect();
    let body = BodyTask {
        force_n: DVec3::ZERO,
        torque_nm: DVec3::ZERO,
    };
    let mut wbc = WholeBody::new(&model, WbcParams::default());
    let mut tau = vec![0.0; model.nv - 6];
    let out = wbc
        .solve(&model, &mut data, &v, &[], &body, &points, &[], &mut tau)
        .unwrap();
    assert!(!out.qp_solved);
    let plan = wbc.accelerations().to_vec();
    let mut tau_all = vec![0.0; model.nv];
    tau_all[6..].copy_from_slice(&tau);
    let qdd = aba(&model, &mut data, &q, &v, &tau_all).to_vec();
    for (a, b) in qdd.iter().zip(&plan) {
        assert!(
            (a - b).abs() < 1e-7 * (1.0 + b.abs()),
            "ABA {a} vs plan {b}"
        );
    }
}
