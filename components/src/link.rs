//! Link entities: mass properties, feet and the world pose copied back from the simulation.

use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};
use quadsim_engine::spatial::Transform;

/// A rigid link of a robot. Its geometry lives on separate [`crate::Collider`]
/// and [`crate::Visual`] entities attached to it.
#[derive(Component, Clone, Debug, PartialEq)]
#[component(immutable)]
#[require(Mass, CenterOfMass, ComputedInertia, LinkPose)]
pub struct Link {
    /// Unique name within the robot (URDF `<link name>`).
    pub name: String,
}

/// Mass of a link (kg, ≥ 0).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct Mass(pub f64);

/// Centre of mass (m, link frame).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct CenterOfMass(pub DVec3);

/// Rotational inertia set by the user or the URDF (kg·m², about the CoM, link
/// axes). Absent: the compile stage derives one from the first collision (else
/// visual) shape and the mass into [`ComputedInertia`].
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[component(immutable)]
pub struct Inertia(pub DMat3);

/// The rotational inertia the compiled model uses (kg·m², about the CoM, link
/// axes): [`Inertia`] when given, else derived from shape and mass (zero for a
/// link without a solid shape). Written by the compile stage; edits are overwritten.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct ComputedInertia(pub DMat3);

impl Default for ComputedInertia {
    fn default() -> Self {
        Self(DMat3::ZERO)
    }
}

/// Marks a foot link (a contact point for the ground model and the gait).
/// Brings its [`FootContact`] along.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[component(immutable)]
#[require(FootContact)]
pub struct Foot;

/// A foot's contact state, copied from the packed simulation with the link
/// poses (publish rate or on request). Output only.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct FootContact {
    /// The foot touches the ground.
    pub in_contact: bool,
    /// The contact slid (friction at the cone's limit) in the last step.
    pub slipping: bool,
    /// Penetration depth (m, ≥ 0).
    pub penetration_m: f64,
    /// Ground reaction force on the foot (N, world).
    pub force_n: DVec3,
}

/// Contact point of a foot (m, link frame); absent: the link origin.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct FootPoint(pub DVec3);

/// World pose of the link frame (`p_world = rot · p_link + trans`), copied
/// back from the packed simulation state at the publish rate or on request.
/// Output only: the simulation never reads it.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct LinkPose(pub Transform);
