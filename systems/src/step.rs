//! Time integration of every robot, in parallel, and the clock.

use bevy_ecs::prelude::*;
use quadsim_components::{Controller, RobotBatch, RobotSim, SimClock, SimConfig, SimThreadPool};
use quadsim_engine::integrate::{self, Integrator};

/// Advances every compiled robot by one `dt` on the world's thread pool.
///
/// Robots are independent, so each is stepped start to finish by one worker
/// with its own model, data and workspace: no lock, no allocation, and the
/// result does not depend on the number of threads.
pub fn step_robots(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    config: Res<SimConfig>,
) {
    let (dt_s, integrator) = (config.dt_s, config.integrator);
    let sims = &mut batch.sims;
    pool.for_each(sims, |sim| step_robot(sim, dt_s, integrator));
}

/// One robot's step: the engine's integrator with the robot's actuator command
/// and its contact force model; records the worker that ran it.
pub fn step_robot(sim: &mut RobotSim, dt_s: f64, integrator: Integrator) {
    let RobotSim {
        model,
        data,
        state,
        tau_actuator,
        workspace,
        contact,
        last_worker,
        run,
        ..
    } = sim;
    // Servos track the controller's joint targets.
    if let Some(bank) = &mut workspace.actuators
        && bank.has_servos()
        && let Some(targets) = run.controller.joint_targets()
    {
        bank.set_targets(targets);
    }
    integrate::step(
        model,
        data,
        workspace,
        state,
        tau_actuator,
        dt_s,
        integrator,
        contact,
    );
    // Hybrid dynamics: the torques that realised the imposed joint motion
    // (at the step's start state) are what the actuators applied.
    if let Some(m) = &workspace.imposed {
        let nv0 = model.base_nv();
        tau_actuator[nv0..].copy_from_slice(&m.tau_actuator_nm);
        if let Controller::Prescribed(p) = &mut run.controller {
            p.record_step(model, &tau_actuator[nv0..]);
        }
    }
    *last_worker = rayon::current_thread_index();
}

/// Counts the step and sets `time_s = step × dt_s`.
pub fn advance_clock(mut clock: ResMut<SimClock>, config: Res<SimConfig>) {
    clock.step += 1;
    clock.time_s = clock.step as f64 * config.dt_s;
}
