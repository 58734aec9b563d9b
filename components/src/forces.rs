//! The ground and the external forces on a robot during a step.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::DVec3;
use quadsim_engine::contact::{ContactPoint, ContactState, contact_forces};
use quadsim_engine::integrate::ForceModel;
use quadsim_engine::terrain::{TerrainPatch, TerrainUnion};
use quadsim_engine::{Data, Model};

/// A terrain entity: one patch of ground (shape, placement, material).
/// Terrain entities are compiled into the [`Ground`] union at spawn or when
/// they change, never inside a step.
#[derive(Component, Clone, Debug)]
pub struct Terrain {
    /// Unique name (scenario `terrains[].name`).
    pub name: String,
    /// The patch.
    pub patch: TerrainPatch,
}

/// The world's ground: the union of every [`Terrain`] (highest surface wins)
/// plus an optional default plane. Shared by every robot's [`ContactForces`].
#[derive(Resource, Clone, Debug, Default)]
pub struct Ground(pub Arc<TerrainUnion>);

/// A force applied to a body point over a time window (a scenario `push` event).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Push {
    /// Start time (s); the force acts on steps starting in `[start_s, end_s)`.
    pub start_s: f64,
    /// End time (s).
    pub end_s: f64,
    /// Body index in the model.
    pub body: usize,
    /// Application point in the body frame (m).
    pub point_in_body_m: DVec3,
    /// Force (N, world frame).
    pub force_n: DVec3,
}

/// External forces on one robot during a step: ground contacts and pushes.
/// It is the [`ForceModel`] the integrator evaluates at every derivative
/// evaluation (every RK4 stage); the contact *states* (anchors) are only
/// updated once per step, by the `Contact` stage.
#[derive(Clone, Debug, Default)]
pub struct ContactForces {
    /// The ground (shared with every robot of the world).
    pub terrain: Arc<TerrainUnion>,
    /// Contact spheres: feet first, then optional knees and torso corners.
    pub points: Vec<ContactPoint>,
    /// Persistent state of each point, as of the step's start.
    pub states: Vec<ContactState>,
    /// Scheduled pushes.
    pub pushes: Vec<Push>,
    /// Time at the start of the current step (s): selects the active pushes.
    pub time_s: f64,
}

impl ForceModel for ContactForces {
    #[inline]
    fn apply(&mut self, model: &Model, data: &mut Data, _q: &[f64], _v: &[f64], _tau: &mut [f64]) {
        if !self.points.is_empty() {
            contact_forces(&self.points, model, data, &self.terrain, &self.states, None);
        }
        for p in &self.pushes {
            if self.time_s >= p.start_s && self.time_s < p.end_s {
                let at = data.body_point_world(p.body, p.point_in_body_m);
                data.add_point_force(p.body, at, p.force_n);
            }
        }
    }
}
