//! Joint entities: type and axis, placement, the two links they connect, and
//! their limits and passive coefficients, one component each.

use bevy_ecs::prelude::*;
use glam::DVec3;
use quadsim_engine::description::JointKind;
use quadsim_engine::spatial::Transform;

/// How a joint moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointMotion {
    /// Rotation about the axis (URDF `revolute`/`continuous`).
    Revolute,
    /// Translation along the axis.
    Prismatic,
    /// No motion: the child is merged into the parent body at compile time.
    Fixed,
}

/// A joint between two links of a robot (see [`JointConnection`]).
#[derive(Component, Clone, Debug, PartialEq)]
#[component(immutable)]
#[require(
    JointPlacement,
    EffortLimit,
    VelocityLimit,
    JointDamping,
    JointFriction,
    JointArmature
)]
pub struct Joint {
    /// Unique name within the robot (URDF `<joint name>`).
    pub name: String,
    /// Type of motion.
    pub kind: JointMotion,
    /// Unit axis in the child (= joint) frame; ignored for [`JointMotion::Fixed`].
    pub axis: DVec3,
}

impl Joint {
    /// The joint as the engine's description states it.
    pub fn engine_kind(&self) -> JointKind {
        match self.kind {
            JointMotion::Revolute => JointKind::Revolute { axis: self.axis },
            JointMotion::Prismatic => JointKind::Prismatic { axis: self.axis },
            JointMotion::Fixed => JointKind::Fixed,
        }
    }

    /// A joint from the engine's description type.
    pub fn from_engine(name: impl Into<String>, kind: JointKind) -> Self {
        let (kind, axis) = match kind {
            JointKind::Revolute { axis } => (JointMotion::Revolute, axis),
            JointKind::Prismatic { axis } => (JointMotion::Prismatic, axis),
            JointKind::Fixed => (JointMotion::Fixed, DVec3::ZERO),
        };
        Self {
            name: name.into(),
            kind,
            axis,
        }
    }
}

/// Child link frame in the parent link frame at zero joint position: the
/// joint's centre and orientation (URDF `<joint><origin>`).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct JointPlacement(pub Transform);

/// The two link entities a joint connects.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[component(immutable)]
pub struct JointConnection {
    /// Parent link entity.
    pub parent: Entity,
    /// Child link entity.
    pub child: Entity,
}

/// Position limits (rad or m, `lower ≤ upper`); absent: unlimited.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[component(immutable)]
pub struct JointLimits {
    /// Lower limit (rad or m).
    pub lower: f64,
    /// Upper limit (rad or m).
    pub upper: f64,
}

/// Actuator effort limit (N·m or N, ≥ 0; `f64::INFINITY` when none): actuator
/// torques are clamped to it.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[component(immutable)]
pub struct EffortLimit(pub f64);

impl Default for EffortLimit {
    fn default() -> Self {
        Self(f64::INFINITY)
    }
}

/// Velocity limit (rad/s or m/s, ≥ 0; `f64::INFINITY` when none).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[component(immutable)]
pub struct VelocityLimit(pub f64);

impl Default for VelocityLimit {
    fn default() -> Self {
        Self(f64::INFINITY)
    }
}

/// Viscous joint damping (N·m·s/rad or N·s/m, ≥ 0).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct JointDamping(pub f64);

/// Coulomb joint friction (N·m or N, ≥ 0).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct JointFriction(pub f64);

/// Reflected rotor inertia added to the joint's diagonal of M (kg·m² or kg, ≥ 0).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
#[component(immutable)]
pub struct JointArmature(pub f64);

/// A spring–damper on the joint's coordinate, at rest at zero (a compliant
/// payload's force element); absent on ordinary joints.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[component(immutable)]
pub struct SpringDamper(pub quadsim_engine::description::JointSpring);
