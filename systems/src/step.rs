//! Time integration of every robot, in parallel, and the clock.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use quadsim_components::{
    ContactForces, Controller, LaneBatching, RobotBatch, RobotSim, SimClock, SimConfig,
    SimThreadPool,
};
use quadsim_engine::batch::{LANES, StepParts, step_semi_implicit_batch};
use quadsim_engine::integrate::{self, Integrator};

use crate::workspace::{WorkerWorkspace, WorkerWorkspaces};

/// Advances every compiled robot by one `dt` on the world's thread pool: the
/// integration over the whole herd as a system of its own (the step
/// schedule integrates inside [`step_robot_pass`](crate::step_robot_pass)).
///
/// Consecutive robots of one shared model (see
/// [`SharedModels`](crate::SharedModels)) are stepped [`LANES`] at a time with
/// their dynamics in SIMD lanes ([`step_semi_implicit_batch`]); robots the
/// batch cannot take (RK4, an imposed joint motion, a group of one) are
/// stepped alone with [`step_robot`]. Each group is stepped start to finish
/// by one worker with its own data and its worker's workspace (the system's
/// [`WorkerWorkspaces`]): no contended lock, no allocation after the first
/// steps. The batched step is bit-identical to the scalar
/// one, so the result depends neither on the grouping nor on the number of
/// threads.
pub fn step_robots(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    config: Res<SimConfig>,
    batching: Option<Res<LaneBatching>>,
    mut ends: Local<Vec<usize>>,
    mut workspaces: Local<WorkerWorkspaces>,
) {
    let (dt_s, integrator) = (config.dt_s, config.integrator);
    let lanes = lanes_on(&config, batching.as_deref());
    let sims = &mut batch.sims;
    plan_groups(sims, lanes, &mut ends);
    workspaces.fit(pool.threads());
    let workspaces = &*workspaces;
    pool.for_each_group(sims, &ends, |group| {
        workspaces.with(|ws| step_group(group, ws, dt_s, integrator))
    });
}

/// Which robots go into SIMD lanes across robots: with semi-implicit Euler,
/// as [`LaneBatching`] says (its default without the resource); none with RK4.
pub(crate) fn lanes_on(config: &SimConfig, batching: Option<&LaneBatching>) -> LaneBatching {
    if config.integrator == Integrator::SemiImplicitEuler {
        batching.copied().unwrap_or_default()
    } else {
        LaneBatching::Off
    }
}

/// Steps one group of [`plan_groups`]: in lanes when it has several robots
/// (robot by robot, the same bits, once one of them has diverged); a robot
/// that has diverged is not stepped. `ws`: the calling worker's workspace.
pub(crate) fn step_group(
    group: &mut [RobotSim],
    ws: &mut WorkerWorkspace,
    dt_s: f64,
    integrator: Integrator,
) {
    if group.len() > 1 && group.iter().all(live) {
        step_in_lanes(group, ws, dt_s);
    } else {
        for sim in group.iter_mut().filter(|s| live(s)) {
            step_robot(sim, dt_s, integrator);
        }
    }
}

/// Whether a robot is still stepped: one that has diverged
/// ([`RobotRun::diverged`](quadsim_components::RobotRun::diverged)) stays
/// as it was then, so that its state, metrics and log end at the step it
/// diverged at, and no stage meets the exploding or non-finite numbers
/// that would follow.
pub(crate) fn live(sim: &RobotSim) -> bool {
    sim.run.diverged.is_none()
}

/// Whether a robot can be stepped in SIMD lanes (with semi-implicit Euler):
/// hybrid dynamics (an imposed joint motion) has no batched form.
fn lane_ready(sim: &RobotSim) -> bool {
    sim.workspace.imposed.is_none() && live(sim)
}

/// Splits `sims` into groups (written as exclusive `ends`): runs of up to
/// [`LANES`] consecutive lane-ready robots of one model that `lanes` puts in
/// lanes across robots ([`LaneBatching::across_robots`]), every other robot
/// alone.
pub fn plan_groups(sims: &[RobotSim], lanes: LaneBatching, ends: &mut Vec<usize>) {
    ends.clear();
    let mut start = 0;
    while start < sims.len() {
        start += group_len(&sims[start..], lanes);
        ends.push(start);
    }
}

/// Length of the group [`plan_groups`] starts at `sims[0]` (`sims` not empty).
fn group_len(sims: &[RobotSim], lanes: LaneBatching) -> usize {
    let first = &sims[0];
    if !(lane_ready(first) && lanes.across_robots(&first.model)) {
        return 1;
    }
    let joins = |sim: &RobotSim| lane_ready(sim) && Arc::ptr_eq(&first.model, &sim.model);
    1 + sims[1..sims.len().min(LANES)]
        .iter()
        .take_while(|s| joins(s))
        .count()
}

/// `f` on each group [`plan_groups`] would make of `sims`, in order,
/// without a list of groups (nothing allocated).
pub(crate) fn for_each_lane_group(
    sims: &mut [RobotSim],
    lanes: LaneBatching,
    mut f: impl FnMut(&mut [RobotSim]),
) {
    let mut rest = sims;
    while !rest.is_empty() {
        let n = group_len(rest, lanes);
        let (group, tail) = rest.split_at_mut(n);
        f(group);
        rest = tail;
    }
}

/// One robot's buffers for the batched step.
fn step_parts(sim: &mut RobotSim) -> StepParts<'_, ContactForces> {
    StepParts {
        data: &mut sim.data,
        ws: &mut sim.workspace,
        state: &mut sim.state,
        tau_actuator: &sim.tau_actuator,
        forces: &mut sim.contact,
    }
}

/// Steps 2..=[`LANES`] lane-ready robots of one model with semi-implicit Euler,
/// their dynamics in SIMD lanes; each ends exactly as [`step_robot`] leaves it.
/// The lanes' workspace is the worker's (`ws`), one per model size.
fn step_in_lanes(group: &mut [RobotSim], ws: &mut WorkerWorkspace, dt_s: f64) {
    for sim in group.iter_mut() {
        set_servo_targets(sim);
    }
    let model = Arc::clone(&group[0].model);
    step_semi_implicit_batch(&model, ws.lanes_for(&model), group, step_parts, dt_s);
    let worker = rayon::current_thread_index();
    for sim in group {
        sim.last_worker = worker;
    }
}

/// Servos track the controller's joint targets.
fn set_servo_targets(sim: &mut RobotSim) {
    if let Some(bank) = &mut sim.workspace.actuators
        && bank.has_servos()
        && let Some(targets) = sim.run.controller.joint_targets()
    {
        bank.set_targets(targets);
    }
}

/// One robot's step: the engine's integrator with the robot's actuator command
/// and its contact force model; records the worker that ran it.
pub fn step_robot(sim: &mut RobotSim, dt_s: f64, integrator: Integrator) {
    set_servo_targets(sim);
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

/// Counts the step and sets `time_s = step × dt_s`: the end of a step's
/// `Integrate` stage, as a system of its own (the step schedule advances the
/// clock at the end of [`step_robot_pass`](crate::step_robot_pass)).
pub fn advance_clock(mut clock: ResMut<SimClock>, config: Res<SimConfig>) {
    count_step(&mut clock, config.dt_s);
}

/// Counts one step of `dt_s` on `clock` (see [`advance_clock`]).
pub(crate) fn count_step(clock: &mut SimClock, dt_s: f64) {
    clock.step += 1;
    clock.time_s = clock.step as f64 * dt_s;
}
