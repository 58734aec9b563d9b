//! Geometry attached to links: collision shapes (parry3d) and visual shapes,
//! each on its own entity pointing at its link, as avian's `ColliderOf` does.

use bevy_ecs::prelude::*;
use glam::DQuat;
use parry3d_f64::math::Pose;
use parry3d_f64::shape::SharedShape;
use quadsim_engine::description::{Geometry, Shape};

/// A collision shape of a link: the description's [`Geometry`] and the parry3d
/// shape built from it. Meshes become the convex hull of their vertices; a mesh
/// whose vertices were not loaded (or whose hull cannot be built) stays a
/// reference with no parry shape. Replace the whole component to edit it, so
/// the two cannot disagree.
#[derive(Component, Clone, Debug)]
#[component(immutable)]
pub struct Collider {
    geometry: Geometry,
    shape: Option<SharedShape>,
    pose: Pose,
}

impl Collider {
    /// Builds the parry3d shape for `geometry`.
    pub fn new(geometry: Geometry) -> Self {
        let origin = &geometry.origin;
        let placement = Pose::from_parts(origin.trans, origin.quat());
        let (shape, pose) = match &geometry.shape {
            Shape::Box { size_m } => (
                Some(SharedShape::cuboid(
                    size_m.x / 2.0,
                    size_m.y / 2.0,
                    size_m.z / 2.0,
                )),
                placement,
            ),
            Shape::Cylinder { radius_m, length_m } => {
                // parry's cylinder runs along its y axis, the description's along z:
                // a quarter turn about x takes y to z.
                let y_to_z =
                    Pose::from_rotation(DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2));
                (
                    Some(SharedShape::cylinder(length_m / 2.0, *radius_m)),
                    placement * y_to_z,
                )
            }
            Shape::Sphere { radius_m } => (Some(SharedShape::ball(*radius_m)), placement),
            Shape::Capsule { radius_m, length_m } => (
                Some(SharedShape::capsule_z(length_m / 2.0, *radius_m)),
                placement,
            ),
            Shape::Mesh { vertices, .. } => (
                vertices.as_deref().and_then(SharedShape::convex_hull),
                placement,
            ),
        };
        Self {
            geometry,
            shape,
            pose,
        }
    }

    /// The description this collider was built from (shape frame in the link frame).
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The parry3d shape, `None` for a mesh kept by reference.
    pub fn shape(&self) -> Option<&SharedShape> {
        self.shape.as_ref()
    }

    /// Pose of the parry3d shape in the link frame (includes the cylinder's
    /// y-to-z quarter turn, so it can differ from the geometry's origin).
    pub fn pose(&self) -> Pose {
        self.pose
    }
}

impl PartialEq for Collider {
    /// Colliders are equal when their descriptions are (the parry shape follows from it).
    fn eq(&self, other: &Self) -> bool {
        self.geometry == other.geometry
    }
}

/// On a collider entity: the link it is attached to.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = LinkColliders)]
pub struct ColliderOf(pub Entity);

/// On a link: its collider entities in order (the first one sets a derived inertia).
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = ColliderOf, linked_spawn)]
pub struct LinkColliders(Vec<Entity>);

/// A display-only shape of a link (shape frame in the link frame).
#[derive(Component, Clone, Debug, PartialEq)]
#[component(immutable)]
pub struct Visual(pub Geometry);

/// On a visual entity: the link it is attached to.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = LinkVisuals)]
pub struct VisualOf(pub Entity);

/// On a link: its visual entities in order.
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = VisualOf, linked_spawn)]
pub struct LinkVisuals(Vec<Entity>);
