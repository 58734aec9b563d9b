//! The `Control` stage: each robot's controller writes its actuator command at
//! the controller rate ([`ControlRate`]); the command is held in between.

use bevy_ecs::prelude::*;
use quadsim_components::{ControlRate, Controller, RobotBatch, RobotSim, SimClock, SimThreadPool};

/// Runs every robot's controller on controller ticks.
pub fn run_controllers(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    clock: Res<SimClock>,
    rate: Res<ControlRate>,
) {
    if !clock.step.is_multiple_of(rate.every_steps.max(1)) {
        return;
    }
    let sims = &mut batch.sims;
    pool.for_each(sims, control_robot);
}

/// One robot's control law, from its current `(q, v)`.
pub fn control_robot(sim: &mut RobotSim) {
    let nb = sim.model.base_nv();
    let (nq0, nv0) = (sim.model.base_nq(), nb);
    match &sim.run.controller {
        Controller::None => sim.tau_actuator.fill(0.0),
        Controller::JointPd(pd) => {
            sim.tau_actuator[..nb].fill(0.0);
            pd.compute(
                &sim.state.q[nq0..],
                &sim.state.v[nv0..],
                &mut sim.tau_actuator[nb..],
            );
        }
    }
}
