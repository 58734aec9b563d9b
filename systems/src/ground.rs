//! Compiles the terrain entities into the world's [`Ground`] union, at spawn
//! or when a terrain changes (never inside a step), and hands it to every robot.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use quadsim_components::{DefaultGroundPlane, Ground, RobotBatch, Terrain};
use quadsim_engine::terrain::TerrainUnion;

/// Rebuilds [`Ground`] when a [`Terrain`] was added, changed or removed, or the
/// default plane changed; then points every robot's contact model at it.
/// Terrains are added in entity order of their `name` so that the union (and
/// so every query tie) does not depend on spawn order.
pub fn compile_ground(
    terrains: Query<Ref<Terrain>>,
    mut removed: RemovedComponents<Terrain>,
    plane: Res<DefaultGroundPlane>,
    mut ground: ResMut<Ground>,
    mut batch: ResMut<RobotBatch>,
) {
    let changed =
        plane.is_changed() || removed.read().count() > 0 || terrains.iter().any(|t| t.is_changed());
    let stale = ground_stale(&batch, &ground);
    if changed {
        let mut list: Vec<&Terrain> = terrains.iter().map(|t| t.into_inner()).collect();
        list.sort_by(|a, b| a.name.cmp(&b.name));
        let mut union = TerrainUnion::new();
        for t in list {
            union.push(t.patch.clone());
        }
        union.set_default_ground(plane.0);
        ground.0 = Arc::new(union);
    }
    if changed || stale {
        for sim in batch.sims.iter_mut() {
            sim.contact.terrain = ground.0.clone();
        }
    }
}

/// Whether a robot's contact model is not on the current [`Ground`] (a robot
/// compiled since, or the ground replaced).
pub(crate) fn ground_stale(batch: &RobotBatch, ground: &Ground) -> bool {
    batch
        .sims
        .iter()
        .any(|s| !Arc::ptr_eq(&s.contact.terrain, &ground.0))
}
