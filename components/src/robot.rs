//! The robot root entity and the relationship that ties links and joints to it.

use bevy_ecs::prelude::*;
use quadsim_engine::BaseKind;

/// Root entity of one robot. Its links and joints are separate entities that
/// point back here with [`BelongsTo`]; their order in [`RobotParts`] is the
/// description's document order (joint order sets the order of q and v).
#[derive(Component, Clone, Debug, PartialEq)]
#[require(RobotModelName, RobotBase)]
pub struct Robot {
    /// Instance name (unique per scenario, e.g. `"quad16_0"`).
    pub name: String,
}

/// Name of the model the robot was built from (the description's name, e.g. `"quad16"`).
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct RobotModelName(pub String);

/// Whether the root link floats (legged robots) or is welded to the world.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RobotBase(pub BaseKind);

/// On a link or joint entity: the robot root it belongs to.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = RobotParts)]
pub struct BelongsTo(pub Entity);

/// On a robot root: its link and joint entities in insertion (document) order.
/// Kept by bevy from the [`BelongsTo`] components; despawning the robot despawns them.
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = BelongsTo, linked_spawn)]
pub struct RobotParts(Vec<Entity>);

impl RobotParts {
    /// Frees the list's spare capacity (it grows by doubling while the robot spawns).
    pub(crate) fn shrink_to_fit(&mut self) {
        self.0.shrink_to_fit();
    }
}

/// On a compiled robot root: its slot in [`crate::RobotBatch::sims`]. Written
/// by the compile stage only; slots are renumbered when robots are despawned.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct RobotIndex(pub usize);

/// On a robot root whose description does not compile: why. The robot keeps
/// its last valid model (or is not simulated at all) until the error is fixed.
#[derive(Component, Debug, PartialEq)]
pub struct CompileFailure(pub crate::CompileError);
