//! The `Control` stage: each robot's controller writes its actuator command at
//! the controller rate ([`ControlRate`]); the command is held in between.
//! The `prescribed` controller in hybrid mode refreshes its imposed joint
//! motion every step (the integrator follows it exactly).
//!
//! A robot carrying compliant payloads is controlled through its
//! [`ControlView`](quadsim_components::ControlView): the controller reads the
//! actuated prefix of `(q, v)` on the model with the loads frozen at rest,
//! writes the actuated joints' torques, and the loads' joints get none.

use bevy_ecs::prelude::*;
use quadsim_components::{
    ControlRate, Controller, RobotBatch, RobotSensing, RobotSim, SimClock, SimConfig, SimThreadPool,
};
use quadsim_engine::contact::evaluate;
use quadsim_engine::control::prescribed::PrescribedMode;
use quadsim_engine::control::walker::WalkerInput;
use quadsim_engine::dispatch::forward_kinematics;
use quadsim_engine::integrate::State;

use crate::workspace::{WorkerWorkspace, WorkerWorkspaces};

/// Runs every robot's controller on controller ticks: the `Control` stage
/// over the whole herd as a system of its own (the step schedule runs it
/// inside [`step_robot_pass`](crate::step_robot_pass)).
pub fn run_controllers(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    clock: Res<SimClock>,
    rate: Res<ControlRate>,
    config: Res<SimConfig>,
    mut workspaces: Local<WorkerWorkspaces>,
) {
    let tick = is_control_tick(clock.step, &rate);
    let sims = &mut batch.sims;
    let dt = clock_dt(&rate, &config);
    let t = clock.time_s;
    workspaces.fit(pool.threads());
    let workspaces = &*workspaces;
    pool.for_each(sims, |sim| {
        workspaces.with(|ws| control_stage(sim, ws, t, tick, dt))
    });
}

/// One robot's `Control` stage at time `t_s`: the prescribed controller
/// every step, the others on controller ticks (`tick`), each ticking every
/// `control_dt_s`; `ws` is the calling worker's workspace.
pub fn control_stage(
    sim: &mut RobotSim,
    ws: &mut WorkerWorkspace,
    t_s: f64,
    tick: bool,
    control_dt_s: f64,
) {
    if matches!(sim.run.controller, Controller::Prescribed(_)) {
        prescribe(sim, t_s, tick);
    } else if tick {
        control_robot_at(sim, ws, t_s, control_dt_s);
    }
}

/// Whether step `step` is a controller tick.
pub(crate) fn is_control_tick(step: u64, rate: &ControlRate) -> bool {
    step.is_multiple_of(rate.every_steps.max(1))
}

/// The `prescribed` controller at time `t_s` (every step). Hybrid mode: the
/// reference moves to `t_s` and is handed to the integrator (which reports
/// the torques; the `Integrate` stage samples Study B's comparison). PD
/// mode: on controller ticks, the reference at `t_s` and PD torques.
pub fn prescribe(sim: &mut RobotSim, t_s: f64, tick: bool) {
    let RobotSim {
        model,
        state,
        tau_actuator,
        workspace,
        run,
        control,
        sensing,
        ..
    } = sim;
    let Controller::Prescribed(p) = &mut run.controller else {
        return;
    };
    let (nq, nv) = (model.actuated_nq(), model.actuated_nv());
    tau_actuator[nv..].fill(0.0);
    let model = control.as_ref().map_or(&**model, |c| &*c.model);
    let (q, v) = read_state(sensing, state);
    let (q, v, tau_actuator) = (&q[..nq], &v[..nv], &mut tau_actuator[..nv]);
    let nv0 = model.base_nv();
    let nq0 = model.base_nq();
    match p.controller.params.mode {
        PrescribedMode::Hybrid => {
            p.controller.update_reference(model, t_s);
            let imposed = workspace
                .imposed
                .get_or_insert_with(|| p.controller.imposed());
            p.controller.write_imposed(imposed);
        }
        PrescribedMode::Pd => {
            if tick {
                p.controller.update_reference(model, t_s);
                tau_actuator[..nv0].fill(0.0);
                p.controller
                    .pd_torques(model, &q[nq0..], &v[nv0..], &mut tau_actuator[nv0..]);
            }
        }
    }
}

/// The `(q, v)` a controller reads: the sensed state when the robot
/// controls on its estimate, else ground truth.
fn read_state<'a>(
    sensing: &'a Option<Box<RobotSensing>>,
    state: &'a State,
) -> (&'a [f64], &'a [f64]) {
    match sensing.as_deref() {
        Some(s) if s.controls_on_estimate() => (&s.q, &s.v),
        _ => (&state.q, &state.v),
    }
}

pub(crate) fn clock_dt(rate: &ControlRate, config: &SimConfig) -> f64 {
    rate.every_steps.max(1) as f64 * config.dt_s
}

/// One robot's control law at time `t_s`, ticking every `dt_s`; a walker
/// on the estimated state computes its kinematics in the worker's spare
/// `Data` (`ws`).
pub fn control_robot_at(sim: &mut RobotSim, ws: &mut WorkerWorkspace, t_s: f64, dt_s: f64) {
    if let Controller::Walker(w) = &mut sim.run.controller {
        while let Some(&(tc, cmd)) = sim.run.commands.first() {
            if tc > t_s + 1e-12 {
                break;
            }
            w.set_command(cmd);
            sim.run.commands.remove(0);
        }
        let RobotSim {
            model,
            data,
            state,
            tau_actuator,
            contact,
            run,
            control,
            sensing,
            ..
        } = sim;
        let Controller::Walker(w) = &mut run.controller else {
            unreachable!()
        };
        let (nq, nv) = (model.actuated_nq(), model.actuated_nv());
        tau_actuator[nv..].fill(0.0);
        // With compliant payloads the controller has its own view; otherwise
        // it shares the robot's `data`, unless it controls on the estimate.
        let own_view = control.is_some();
        let (model, data) = match control {
            Some(c) => (&*c.model, &mut c.data),
            None => (&**model, data),
        };
        let tau_actuator = &mut tau_actuator[..nv];
        let n = run.n_feet.min(4);
        let mut contacts = [false; 4];
        let mut normals = [glam::DVec3::Z; 4];
        let (q, v) = read_state(sensing, state);
        let (q, v) = (&q[..nq], &v[..nv]);
        let estimating = sensing.as_deref().filter(|s| s.controls_on_estimate());
        let on_estimate = estimating.is_some();
        if let Some(s) = estimating {
            // Sensed contacts; the ground normal under each foot is taken
            // as vertical (the estimator knows no contact geometry).
            let m = n.min(s.contacts.len());
            contacts[..m].copy_from_slice(&s.contacts[..m]);
        } else {
            // Ground truth: contact flags at the controller's own instant
            // (the `Contact` stage updates the persistent states later in
            // this step): a pure evaluation, no anchor is moved.
            forward_kinematics(model, data, &state.q[..nq], &state.v[..nv]);
            for i in 0..n {
                let e = evaluate(
                    &contact.points[i],
                    data,
                    &contact.terrain,
                    &contact.states[i],
                );
                contacts[i] = e.active;
                if e.active {
                    normals[i] = e.normal;
                }
            }
        }
        let nb = model.base_nv();
        tau_actuator[..nb].fill(0.0);
        let input = WalkerInput {
            dt_s,
            terrain: &contact.terrain,
            contacts: &contacts[..n],
            normals: &normals[..n],
        };
        let tau_joints = &mut tau_actuator[nb..];
        if on_estimate && !own_view {
            // The kinematics at the estimated state go to a spare workspace:
            // the robot's `data` keeps the true state's, which the `Contact`
            // stage would otherwise compute again (same results either way).
            ws.spare_data.with(model, |spare| {
                w.tick(model, spare, q, v, &input, tau_joints)
            });
        } else if on_estimate {
            w.tick(model, data, q, v, &input, tau_joints);
        } else {
            // the contacts' evaluation above left `data` at this very state
            w.tick_at_kinematics(model, data, q, v, &input, tau_joints);
        }
        return;
    }
    control_robot(sim);
}

/// One robot's joint-space control law, from its current `(q, v)`.
pub fn control_robot(sim: &mut RobotSim) {
    let nb = sim.model.base_nv();
    let (nq0, nv0) = (sim.model.base_nq(), nb);
    // the actuated joints only: compliant payloads' joints have no actuator
    let (nq, nv) = (sim.model.actuated_nq(), sim.model.actuated_nv());
    let (q, v) = read_state(&sim.sensing, &sim.state);
    match &sim.run.controller {
        Controller::None | Controller::Walker(_) | Controller::Prescribed(_) => {
            sim.tau_actuator.fill(0.0)
        }
        Controller::JointPd(pd) => {
            sim.tau_actuator.fill(0.0);
            pd.compute(&q[nq0..nq], &v[nv0..nv], &mut sim.tau_actuator[nb..nv]);
        }
        Controller::External(e) => {
            sim.tau_actuator.fill(0.0);
            e.compute(&q[nq0..nq], &v[nv0..nv], &mut sim.tau_actuator[nb..nv]);
        }
    }
}
