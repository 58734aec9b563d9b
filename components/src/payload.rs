//! Payload events: rigid payloads attached to or detached from robots at set
//! simulation times, applied between steps by the compile stage.

use bevy_ecs::prelude::*;
use quadsim_engine::payload::Payload;

/// Attach or detach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PayloadAction {
    /// Bolt the payload to the robot's torso.
    Attach,
    /// Remove it (it vanishes from the world; it is not left on the ground).
    Detach,
}

/// One payload event.
#[derive(Clone, Debug)]
pub struct PayloadEvent {
    /// Simulation time (s): applied before the first step that starts at or after it.
    pub t_s: f64,
    /// The robot's root entity.
    pub robot: Entity,
    /// The robot's root (torso) link name, which carries the payload.
    pub parent_link: String,
    /// The payload.
    pub payload: Payload,
    /// What happens.
    pub action: PayloadAction,
    /// Whether the walking controller's gravity compensation learns the
    /// mass change (otherwise it goes on compensating the old mass).
    pub known_to_controller: bool,
}

/// Pending payload events, sorted by time, then payload name (robots are
/// independent, so the order between robots changes nothing).
#[derive(Resource, Debug, Default)]
pub struct PayloadEvents {
    /// The events, in application order.
    pub events: Vec<PayloadEvent>,
    /// How many have been applied.
    pub applied: usize,
}

impl PayloadEvents {
    /// Adds an event, keeping the order.
    pub fn push(&mut self, e: PayloadEvent) {
        self.events.push(e);
        self.events.sort_by(|a, b| {
            a.t_s
                .total_cmp(&b.t_s)
                .then_with(|| a.payload.name.cmp(&b.payload.name))
                .then_with(|| a.robot.cmp(&b.robot))
        });
    }
}
