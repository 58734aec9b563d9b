//! The `Sense` stage: every robot's sensors sample the true state at the
//! step's start (each at its own rate), the base estimator runs on every new
//! IMU sample, and the sensed state the controller reads is assembled.
//! Estimation errors against ground truth are accumulated here for the
//! summary. On steps where no sensor is due and the whole sensed state is
//! held between samples, a robot costs nothing here.

use bevy_ecs::prelude::*;
use glam::DVec3;
use quadsim_components::{RobotBatch, RobotSim, SimClock, SimThreadPool};
use quadsim_engine::contact::update_after_step;
use quadsim_engine::dispatch::forward_kinematics;
use quadsim_engine::estimation::EstimatorInput;
use quadsim_engine::kinematics::base_quat;
use quadsim_engine::sensors::{SensorTruth, SensorUpdates};
use quadsim_engine::terrain::Terrain as _;

use crate::workspace::{WorkerWorkspace, WorkerWorkspaces};

/// Samples every robot's sensors and runs its estimator, in parallel: the
/// `Sense` stage over the whole herd as a system of its own (the step
/// schedule runs it inside [`step_robot_pass`](crate::step_robot_pass)).
pub fn sense_robots(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    clock: Res<SimClock>,
    mut workspaces: Local<WorkerWorkspaces>,
) {
    let t = clock.time_s;
    workspaces.fit(pool.threads());
    let workspaces = &*workspaces;
    pool.for_each(&mut batch.sims, |sim| {
        workspaces.with(|ws| sense_robot(sim, ws, t))
    });
}

/// One robot's sensors and estimator at time `t_s` (the step's start state);
/// `ws` is the calling worker's workspace.
pub fn sense_robot(sim: &mut RobotSim, ws: &mut WorkerWorkspace, t_s: f64) {
    let RobotSim {
        model,
        data,
        state,
        contact,
        run,
        sensing,
        control,
        ..
    } = sim;
    let Some(s) = sensing.as_deref_mut() else {
        return;
    };
    s.contacts_at_state = false;
    // Between samples: when every part of the sensed state is sampled (joint
    // encoders, contact sensors, and the base from the estimator, which runs
    // on IMU samples), none of it changes until a sensor is due, so the
    // kinematics, the contact evaluation and the rest are skipped. The
    // result is the same, bit for bit, as running them.
    if s.suite.encoders.is_some()
        && s.suite.contacts.is_some()
        && s.estimator.is_some()
        && !s.suite.any_due(t_s)
    {
        s.updates = SensorUpdates::default();
        return;
    }
    forward_kinematics(model, data, &state.q, &state.v);
    let n_feet = run.n_feet.min(contact.points.len());
    s.foot_force_n.resize(n_feet, 0.0);
    s.contacts.resize(n_feet, false);
    // True normal forces at this instant. The `Contact` stage's update of
    // the contact states, due later in this step at this same state and
    // with these same states, is done here instead: its evaluation is the
    // one the forces are read from (a normal force does not depend on the
    // anchor; the state of a contact off the ground holds 0 N, as its
    // evaluation does), and the `Contact` stage skips it. Nothing between
    // the two stages reads what the update changes (the controller's
    // contact flags and normals do not depend on the anchors either).
    update_after_step(&contact.points, data, &contact.terrain, &mut contact.states);
    s.contacts_at_state = true;
    for (f, c) in s.foot_force_n.iter_mut().zip(&contact.states[..n_feet]) {
        *f = c.normal_force_n;
    }
    let (nq0, nv0) = (model.base_nq(), model.base_nv());
    // the actuated joints only: a compliant load's coordinates are not sensed
    let (nq, nv) = (model.actuated_nq(), model.actuated_nv());
    // The estimator works on the robot as its controller sees it: a compliant
    // load frozen at rest (the control view), else the model itself.
    let est_model = control.as_ref().map_or(&**model, |c| &*c.model);
    let orientation = base_quat(&state.q);
    let truth = SensorTruth {
        t_s,
        position_m: DVec3::new(state.q[0], state.q[1], state.q[2]),
        orientation,
        velocity_world_mps: data.vel[0].lin,
        omega_body_radps: DVec3::new(state.v[3], state.v[4], state.v[5]),
        gravity_mps2: model.gravity,
        q_joints_rad: &state.q[nq0..nq],
        qd_joints_radps: &state.v[nv0..nv],
        foot_normal_force_n: &s.foot_force_n,
    };
    s.updates = s.suite.update(&truth);

    // sensed joints and contacts (ground truth where a sensor is missing)
    let (qj, vj): (&[f64], &[f64]) = match &s.suite.encoders {
        Some(e) => (&e.position_rad, &e.velocity_radps),
        None => (&state.q[nq0..nq], &state.v[nv0..nv]),
    };
    match &s.suite.contacts {
        Some(c) => {
            // the sensors cover at most the first four feet
            let n = n_feet.min(c.in_contact.len());
            s.contacts[..n].copy_from_slice(&c.in_contact[..n]);
        }
        None => {
            for (f, c) in s.foot_force_n.iter().zip(s.contacts.iter_mut()) {
                *c = *f > 0.0;
            }
        }
    }
    // a delivered motion-capture pose corrects the estimate (delayed fusion)
    if s.updates.mocap
        && let (Some(est), Some(m)) = (
            s.estimator.as_mut(),
            s.suite.mocap.as_ref().and_then(|m| m.last),
        )
        && est.params.mocap.enabled
    {
        est.fuse_mocap(&contact.terrain, &m);
    }
    if let (Some(est), Some(imu)) = (s.estimator.as_mut(), s.suite.imu.as_ref())
        && s.updates.imu
        && let Some(sample) = imu.last
    {
        let dt = est.estimate.t_s;
        est.update(
            est_model,
            &EstimatorInput {
                t_s,
                dt_s: (t_s - dt).max(0.0),
                gyro_radps: sample.gyro_radps,
                accel_mps2: sample.accel_mps2,
                q_joints_rad: qj,
                qd_joints_radps: vj,
                contacts: &s.contacts,
                terrain: &contact.terrain,
            },
            &mut ws.spare_kinematics,
        );
        let ground = contact
            .terrain
            .height(state.q[0], state.q[1])
            .unwrap_or(f64::NAN);
        s.errors.record(
            &est.estimate,
            orientation,
            data.vel[0].lin,
            state.q[2] - ground,
        );
    }
    match &s.estimator {
        Some(est) => est.write_state(est_model, qj, vj, &mut s.q, &mut s.v),
        None => {
            s.q[..nq0].copy_from_slice(&state.q[..nq0]);
            s.v[..nv0].copy_from_slice(&state.v[..nv0]);
            s.q[nq0..nq].copy_from_slice(qj);
            s.v[nv0..nv].copy_from_slice(vj);
        }
    }
}
