//! quadsim's ECS data: robots as entities and the world resources that hold
//! their packed simulation state.
//!
//! A robot is a root entity ([`Robot`], [`RobotModelName`], [`RobotBase`]) with
//! one entity per link ([`Link`], [`Mass`], [`CenterOfMass`], [`Inertia`], …)
//! and per joint ([`Joint`], [`JointPlacement`], [`JointConnection`], limits
//! and passive coefficients), each pointing back with [`BelongsTo`]. Collision
//! and visual shapes are entities attached to their link ([`ColliderOf`],
//! [`VisualOf`]). Components are small and say one thing (avian style); values
//! the user sets ([`Inertia`]) are kept apart from derived ones ([`ComputedInertia`]).
//!
//! The entities are the *editable description*. The compile stage (in
//! `quadsim-systems`) turns them into the engine's packed model when they
//! change, never inside a step; the packed [`RobotBatch`] is the authoritative
//! state, and [`LinkPose`] is only a copy of it for publishing.
//!
//! The description components of links, joints and shapes are immutable
//! (`#[component(immutable)]`): an edit inserts a new value
//! (`world.entity_mut(link).insert(Mass(4.0))`). Every insert fires bevy's
//! lifecycle observers, so the compile stage learns of edits as they happen
//! instead of scanning every part's change ticks on every step (which cost
//! 8 % of a trotting quad16's step).
//!
//! # Examples
//! ```
//! use bevy_ecs::prelude::*;
//! use glam::DVec3;
//! use quadsim_components::{Link, Mass, describe_robot, spawn_robot};
//! use quadsim_engine::description::RobotBuilder;
//!
//! let desc = RobotBuilder::new("pendulum")
//!     .link("base").mass(1.0).done()
//!     .link("arm").mass(2.0).com(DVec3::new(0.0, 0.0, -0.5)).done()
//!     .revolute("swing", "base", "arm", DVec3::ZERO, DVec3::Y)
//!     .build();
//! let mut world = World::new();
//! let root = spawn_robot(&mut world, &desc);
//! assert_eq!(describe_robot(&world, root).unwrap().total_mass_kg(), 3.0);
//!
//! // edit the arm's mass on its entity (description components are
//! // immutable: an edit inserts a new value); the description follows
//! let mut q = world.query::<(Entity, &Link)>();
//! let arm = q.iter(&world).find(|(_, l)| l.name == "arm").unwrap().0;
//! world.entity_mut(arm).insert(Mass(4.0));
//! assert_eq!(describe_robot(&world, root).unwrap().total_mass_kg(), 5.0);
//! ```

mod actuator;
mod build;
mod collider;
mod external;
mod forces;
mod joint;
mod link;
mod payload;
mod resources;
mod robot;
mod run;
mod sensors;

pub use actuator::JointActuators;
pub use build::{
    CompileError, DescribeError, describe_robot, describe_robot_with_links, spawn_joint,
    spawn_link, spawn_robot, spawn_robot_with_base,
};
pub use collider::{
    Collider, ColliderOf, LinkColliders, LinkVisuals, ShapeInterner, Visual, VisualOf,
};
pub use external::ExternalJoint;
pub use forces::{ContactForces, Ground, Push, Terrain};
pub use joint::{
    EffortLimit, Joint, JointArmature, JointConnection, JointDamping, JointFriction, JointLimits,
    JointMotion, JointPlacement, SpringDamper, VelocityLimit,
};
pub use link::{
    CenterOfMass, ComputedInertia, Foot, FootContact, FootPoint, Inertia, Link, LinkPose, Mass,
};
pub use payload::{PayloadAction, PayloadEvent, PayloadEvents};
pub use resources::{
    ControlView, DEFAULT_BLOCK_ROBOTS, LaneBatching, PARALLEL_MIN_ITEMS, PoseSync, RobotBatch,
    RobotSim, SimClock, SimConfig, SimThreadPool, StageLayout, ThreadPoolError,
};
pub use robot::{
    BelongsTo, CompileFailure, Robot, RobotBase, RobotIndex, RobotModelName, RobotParts,
};
pub use run::{
    ControlRate, Controller, DefaultGroundPlane, FallCriteria, Observation, PrescribedRun, RobotRun,
};
pub use sensors::{RobotSensing, StateSource};
