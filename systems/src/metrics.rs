//! Metrics recorded every step (full rate) in the `Publish` stage, from the
//! step's [`Observation`](quadsim_components::Observation) and the actuator
//! torques applied during the step.

use bevy_ecs::prelude::*;
use quadsim_components::{RobotBatch, RobotSim, SimConfig, SimThreadPool};
use quadsim_engine::divergence;
use quadsim_engine::metrics::StepSample;

/// Records one step of metrics for every robot: as a system of its own (the
/// step schedule records them inside [`step_robot_pass`](crate::step_robot_pass)).
pub fn record_metrics(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    config: Res<SimConfig>,
) {
    let dt = config.dt_s;
    let saturate = config.passive.saturation;
    let sims = &mut batch.sims;
    pool.for_each(sims, |sim| record_robot(sim, dt, saturate));
}

/// One robot's sample: the state at the step's start and the (saturated)
/// actuator torques that acted over the step. Its x86-64-v3 clone
/// (three-operand VEX forms, wider vectors) runs shorter; no fused
/// multiply–add, so both give the same bits.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn record_robot(sim: &mut RobotSim, dt_s: f64, saturate: bool) {
    let RobotSim {
        model,
        tau_actuator,
        run,
        workspace,
        ..
    } = sim;
    let nv0 = model.base_nv();
    // the actuated joints (not compliant payloads')
    let nj = model.actuated_nv() - nv0;
    run.tau_joints.resize(nj, 0.0);
    // With actuator models: the motors' torques at the step's start, inside
    // their envelopes, and the envelope record.
    let bank = workspace.actuators.as_ref();
    match bank {
        Some(b) => run.tau_joints.copy_from_slice(&b.applied()[..nj]),
        None => {
            let tau = &tau_actuator[nv0..nv0 + nj];
            if saturate {
                // zipped slices of one length: no bounds checks; and
                // `clamp`'s value without its `min ≤ max` assertion, whose
                // branch kept the loop from vectorising (the step's
                // `passive::saturate` asserts it on these same limits)
                let limits = &model.effort_limit[nv0..nv0 + nj];
                for ((out, &tau), &lim) in run.tau_joints.iter_mut().zip(tau).zip(limits) {
                    *out = if tau < -lim {
                        -lim
                    } else if tau > lim {
                        lim
                    } else {
                        tau
                    };
                }
            } else {
                // clamped to ±∞: the torques themselves
                run.tau_joints.copy_from_slice(tau);
            }
        }
    }
    let obs = &run.observation;
    let sample = StepSample {
        t_s: obs.t_s,
        dt_s,
        base_position_m: obs.base.trans,
        base_rotation: obs.base.rot,
        base_height_above_ground_m: obs.base_height_above_ground_m,
        com_m: obs.com_m,
        com_velocity_mps: obs.com_velocity_mps,
        com_height_above_ground_m: obs.com_height_above_ground_m,
        q_joints: &obs.q_joints,
        qd_joints: &obs.qd_joints,
        tau_joints: &run.tau_joints,
        q_desired: run.controller.joint_targets(),
        feet: &obs.feet,
        fallen: obs.fallen,
    };
    run.metrics.record(&sample);
    match bank {
        Some(b) => {
            run.actuators
                .record(&b.demand()[..nj], &run.tau_joints, &obs.qd_joints, dt_s);
            run.actuators.record_envelope(b.at_envelope(), dt_s);
        }
        // the peak applied torque is the metrics' (`run.tau_joints`): one
        // definition for report.md's tables, summary.json and the log
        None => run.actuators.record(
            &tau_actuator[nv0..nv0 + nj],
            &run.tau_joints,
            &obs.qd_joints,
            dt_s,
        ),
    }
    if let quadsim_components::Controller::Walker(w) = &run.controller {
        run.commanded_distance_m.0 += w.active_command().forward_mps * dt_s;
        run.commanded_distance_m.1 += dt_s;
    }
}

/// Records the robot's first divergence ([`RobotRun::diverged`](quadsim_components::RobotRun::diverged)),
/// if it has none yet: its state after the step at `t_s`, then its contacts'
/// penetration (as of the step's `Contact` stage).
pub fn check_divergence(sim: &mut RobotSim, t_s: f64) {
    if sim.run.diverged.is_some() {
        return;
    }
    let found =
        divergence::state_divergence(&sim.model, &sim.state.q, &sim.state.v).or_else(|| {
            divergence::penetration_divergence(sim.contact.states.iter().map(|s| s.penetration_m))
        });
    if let Some(d) = found {
        sim.run.diverged = Some((t_s, d));
    }
}
