//! Geometry attached to links: collision shapes (parry3d) and visual shapes,
//! each on its own entity pointing at its link, as avian's `ColliderOf` does.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Weak};

use bevy_ecs::prelude::*;
use glam::DQuat;
use parry3d_f64::math::Pose;
use parry3d_f64::shape::SharedShape;
use quadsim_engine::description::{Geometry, Shape};

/// A collision shape of a link: the description's [`Geometry`] and the parry3d
/// shape built from it. Meshes become the convex hull of their vertices; a mesh
/// whose vertices were not loaded (or whose hull cannot be built) stays a
/// reference with no parry shape. Replace the whole component to edit it, so
/// the two cannot disagree. Immutable and shared: spawning takes colliders of
/// the same geometry (bit for bit) from the world's [`ShapeInterner`], so the
/// robots of one design hold one copy of each shape (and convex hull).
#[derive(Component, Clone, Debug)]
#[component(immutable)]
pub struct Collider(Arc<ColliderShape>);

/// What a [`Collider`] shares.
#[derive(Debug)]
struct ColliderShape {
    geometry: Geometry,
    shape: Option<SharedShape>,
    pose: Pose,
}

impl Collider {
    /// Builds the parry3d shape for `geometry` (not shared; see [`ShapeInterner::collider`]).
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
        Self(Arc::new(ColliderShape {
            geometry,
            shape,
            pose,
        }))
    }

    /// The description this collider was built from (shape frame in the link frame).
    pub fn geometry(&self) -> &Geometry {
        &self.0.geometry
    }

    /// The parry3d shape, `None` for a mesh kept by reference.
    pub fn shape(&self) -> Option<&SharedShape> {
        self.0.shape.as_ref()
    }

    /// Pose of the parry3d shape in the link frame (includes the cylinder's
    /// y-to-z quarter turn, so it can differ from the geometry's origin).
    pub fn pose(&self) -> Pose {
        self.0.pose
    }
}

impl PartialEq for Collider {
    /// Colliders are equal when their descriptions are (the parry shape follows from it).
    fn eq(&self, other: &Self) -> bool {
        self.geometry() == other.geometry()
    }
}

/// Shares the [`Collider`] and [`Visual`] of equal geometries (bit for bit)
/// between the links that spawn them, so that a herd of one design holds one
/// copy of each shape: a resource that [`crate::spawn_link`] creates on first
/// use. It holds weak references only (a shape lives as long as an entity
/// uses it) and forgets dead ones as it grows.
#[derive(Resource, Debug, Default)]
pub struct ShapeInterner {
    colliders: HashMap<u64, Vec<Weak<ColliderShape>>>,
    visuals: HashMap<u64, Vec<Weak<Geometry>>>,
    /// Entries added since dead ones were last dropped.
    added: usize,
}

impl ShapeInterner {
    /// A collider for `geometry`: a live one of the same geometry, else a new one.
    pub fn collider(&mut self, geometry: &Geometry) -> Collider {
        let (c, added) = intern(
            &mut self.colliders,
            geometry,
            |c| &c.geometry,
            |g| Collider::new(g).0,
        );
        if added {
            self.note_added();
        }
        Collider(c)
    }

    /// A visual for `geometry`: a live one of the same geometry, else a new one.
    pub fn visual(&mut self, geometry: &Geometry) -> Visual {
        let (g, added) = intern(&mut self.visuals, geometry, |g| g, Arc::new);
        if added {
            self.note_added();
        }
        Visual(g)
    }

    /// Drops the dead entries once as many were added as the interner holds.
    fn note_added(&mut self) {
        self.added += 1;
        if self.added > self.colliders.len() + self.visuals.len() {
            drop_dead(&mut self.colliders);
            drop_dead(&mut self.visuals);
            self.added = 0;
        }
    }
}

/// The live entry of `table` whose geometry (`geometry_of`) has the bits of
/// `geometry`, else a new one (`make`) entered there; and whether it is new.
fn intern<T>(
    table: &mut HashMap<u64, Vec<Weak<T>>>,
    geometry: &Geometry,
    geometry_of: impl Fn(&T) -> &Geometry,
    make: impl FnOnce(Geometry) -> Arc<T>,
) -> (Arc<T>, bool) {
    let key = geometry_bits(geometry);
    let h = hash_bits(&key);
    let found = table.get(&h).and_then(|list| {
        list.iter()
            .filter_map(Weak::upgrade)
            .find(|t| geometry_bits(geometry_of(t)) == key)
    });
    if let Some(t) = found {
        return (t, false);
    }
    let t = make(geometry.clone());
    table.entry(h).or_default().push(Arc::downgrade(&t));
    (t, true)
}

/// Forgets `table`'s entries whose shapes no entity uses any more.
fn drop_dead<T>(table: &mut HashMap<u64, Vec<Weak<T>>>) {
    table.retain(|_, l| {
        l.retain(|w| w.strong_count() > 0);
        !l.is_empty()
    });
}

/// Every number of a geometry as its bits (and the mesh URI's bytes), so that
/// only identical geometries share a shape (`==` would join 0.0 and −0.0).
fn geometry_bits(g: &Geometry) -> Vec<u64> {
    let mut k: Vec<u64> = g.origin.rot.to_cols_array().map(f64::to_bits).to_vec();
    let v3 = |k: &mut Vec<u64>, v: glam::DVec3| k.extend(v.to_array().map(f64::to_bits));
    v3(&mut k, g.origin.trans);
    match &g.shape {
        Shape::Box { size_m } => {
            k.push(0);
            v3(&mut k, *size_m);
        }
        Shape::Cylinder { radius_m, length_m } => {
            k.extend([1, radius_m.to_bits(), length_m.to_bits()]);
        }
        Shape::Sphere { radius_m } => k.extend([2, radius_m.to_bits()]),
        Shape::Capsule { radius_m, length_m } => {
            k.extend([3, radius_m.to_bits(), length_m.to_bits()]);
        }
        Shape::Mesh {
            uri,
            scale,
            vertices,
        } => {
            k.extend([4, uri.len() as u64]);
            k.extend(uri.bytes().map(u64::from));
            v3(&mut k, *scale);
            match vertices {
                None => k.push(0),
                Some(vs) => {
                    k.extend([1, vs.len() as u64]);
                    for &p in vs {
                        v3(&mut k, p);
                    }
                }
            }
        }
    }
    k
}

fn hash_bits(key: &[u64]) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    key.hash(&mut h);
    h.finish()
}

/// On a collider entity: the link it is attached to.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = LinkColliders)]
pub struct ColliderOf(pub Entity);

/// On a link: its collider entities in order (the first one sets a derived inertia).
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = ColliderOf, linked_spawn)]
pub struct LinkColliders(Vec<Entity>);

/// A display-only shape of a link (shape frame in the link frame). Shared
/// between links of equal geometry (see [`ShapeInterner`]).
#[derive(Component, Clone, Debug, PartialEq)]
#[component(immutable)]
pub struct Visual(pub Arc<Geometry>);

/// On a visual entity: the link it is attached to.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = LinkVisuals)]
pub struct VisualOf(pub Entity);

/// On a link: its visual entities in order.
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = VisualOf, linked_spawn)]
pub struct LinkVisuals(Vec<Entity>);
