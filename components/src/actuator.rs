//! The actuator of each joint of a robot (`[robots.actuators]`), on its root
//! entity. The compile stage adds each motor's reflected rotor inertia to the
//! model's armature and gives the robot an
//! [`ActuatorBank`](quadsim_engine::actuator_model::ActuatorBank).

use bevy_ecs::prelude::*;
use quadsim_engine::actuator_model::ActuatorSpec;

/// One [`ActuatorSpec`] per joint (the model's joint order), and the number
/// of steps per control tick (the latency buffer's clock). A robot without
/// this component has ideal torque sources.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct JointActuators {
    /// Per joint, in joint order.
    pub specs: Vec<ActuatorSpec>,
    /// Steps per control tick (≥ 1).
    pub control_every_steps: u64,
}
