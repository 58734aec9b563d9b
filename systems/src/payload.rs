//! Applies due payload events between steps: an attach spawns the payload's
//! links and joints under the robot's torso link (one link on a fixed joint
//! when rigid; a chain of sprung joints when compliant), a detach despawns
//! them; the compile stage that follows merges the change into the robot's
//! model (and maps the state across a compliant payload's coordinates, see
//! [`crate::compile::carry_over_loads`]).

use bevy_ecs::prelude::*;
use bevy_ecs::relationship::RelationshipTarget;
use quadsim_components::{
    BelongsTo, Controller, JointConnection, Link, PayloadAction, PayloadEvent, PayloadEvents,
    RobotBatch, RobotParts, SimClock, spawn_joint, spawn_link,
};

/// Half a step's worth of slack on event times (s): an event at t is applied
/// before the step that starts at t, whatever the rounding of the clock.
const TIME_SLACK_S: f64 = 1e-9;

/// The events not yet applied whose time has come at `now_s` (what
/// [`apply_payload_events`] applies), in order.
fn due_events(events: &PayloadEvents, now_s: f64) -> &[PayloadEvent] {
    let pending = &events.events[events.applied..];
    let n = pending
        .iter()
        .take_while(|e| e.t_s <= now_s + TIME_SLACK_S)
        .count();
    &pending[..n]
}

/// Whether a payload event is due at `now_s` ([`CompileGate`](crate::CompileGate)).
pub(crate) fn payload_due(events: &PayloadEvents, now_s: f64) -> bool {
    !due_events(events, now_s).is_empty()
}

/// The compile stage's first system: applies every payload event due at
/// the current time. Errors (an unknown link) are reported on stderr and the
/// event is skipped; scenario loading checks names beforehand.
pub fn apply_payload_events(world: &mut World) {
    let Some(events) = world.get_resource::<PayloadEvents>() else {
        return;
    };
    let now = world.resource::<SimClock>().time_s;
    let due = due_events(events, now).to_vec();
    if due.is_empty() {
        return;
    }
    world.resource_mut::<PayloadEvents>().applied += due.len();
    for e in due {
        let link_name = e.payload.link_name();
        let find = |world: &World, name: &str| {
            world.get::<RobotParts>(e.robot).and_then(|parts| {
                parts
                    .iter()
                    .find(|p| world.get::<Link>(*p).is_some_and(|l| l.name == name))
            })
        };
        let mass_change = match e.action {
            PayloadAction::Attach => {
                let Some(parent) = find(world, &e.parent_link) else {
                    eprintln!("payload '{}': no link '{}'", e.payload.name, e.parent_link);
                    continue;
                };
                if find(world, &link_name).is_some() {
                    continue; // already attached
                }
                let (links, joints) = match e.payload.parts(&e.parent_link) {
                    Ok(p) => p,
                    Err(err) => {
                        eprintln!("{err}");
                        continue;
                    }
                };
                let spawned: Vec<(String, Entity)> = links
                    .iter()
                    .map(|l| (l.name.clone(), spawn_link(world, e.robot, l)))
                    .collect();
                let entity = |name: &str| {
                    spawned
                        .iter()
                        .find(|(n, _)| n == name)
                        .map_or(parent, |(_, e)| *e)
                };
                for j in &joints {
                    let connection = JointConnection {
                        parent: entity(&j.parent),
                        child: entity(&j.child),
                    };
                    spawn_joint(world, e.robot, j, connection);
                }
                e.payload.mass_kg
            }
            PayloadAction::Detach => {
                if find(world, &link_name).is_none() {
                    continue; // not attached
                }
                let links: Vec<Entity> = e
                    .payload
                    .link_names()
                    .iter()
                    .filter_map(|n| find(world, n))
                    .collect();
                let mut joints = world.query::<(Entity, &JointConnection, &BelongsTo)>();
                let mounts: Vec<Entity> = joints
                    .iter(world)
                    .filter(|(_, c, b)| links.contains(&c.child) && b.0 == e.robot)
                    .map(|(j, ..)| j)
                    .collect();
                for j in mounts {
                    world.despawn(j);
                }
                for l in links {
                    world.despawn(l);
                }
                -e.payload.mass_kg
            }
        };
        if e.known_to_controller {
            let mut batch = world.resource_mut::<RobotBatch>();
            if let Some(sim) = batch.sims.iter_mut().find(|s| s.entity == e.robot)
                && let Controller::Walker(w) = &mut sim.run.controller
            {
                w.add_payload_mass_kg(mass_change);
            }
        }
    }
}
