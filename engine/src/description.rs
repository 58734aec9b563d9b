//! The editable description of a robot: links and joints by name, as a URDF or a
//! builder states them. [`crate::model::Model::from_description`] compiles it into
//! the packed, immutable articulation model.
//!
//! Frames: each link has its own frame. A joint's `placement` gives the child
//! link's frame in the parent link's frame at zero joint position (URDF
//! `<joint><origin>`); the joint axis is expressed in the child frame.

use crate::spatial::{RigidInertia, Transform};
use glam::{DMat3, DVec3};

/// Collision or visual geometry attached to a link, in the link frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A box with full side lengths (m), centred on its frame.
    Box {
        /// Side lengths along x, y, z (m).
        size_m: DVec3,
    },
    /// A cylinder along its frame's z axis, centred on its frame.
    Cylinder {
        /// Radius (m).
        radius_m: f64,
        /// Length along z (m).
        length_m: f64,
    },
    /// A sphere centred on its frame.
    Sphere {
        /// Radius (m).
        radius_m: f64,
    },
    /// A capsule along z: a cylinder of `length_m` with hemispherical caps.
    Capsule {
        /// Radius (m).
        radius_m: f64,
        /// Length of the cylindrical part along z (m).
        length_m: f64,
    },
    /// A mesh kept by reference; `vertices` holds its points (m, scaled) when
    /// the file was found, for a convex hull.
    Mesh {
        /// The file name or URI as written in the source.
        uri: String,
        /// Per-axis scale.
        scale: DVec3,
        /// Vertices of the mesh in its frame (m), when the file was loaded.
        vertices: Option<Vec<DVec3>>,
    },
}

impl Shape {
    /// Rotational inertia about the shape's centre (kg·m², shape axes) of a solid
    /// of uniform density with total mass `mass_kg`. `None` for meshes, whose
    /// volume distribution is not known here.
    pub fn solid_inertia(&self, mass_kg: f64) -> Option<DMat3> {
        let m = mass_kg;
        let d = match *self {
            Shape::Box { size_m: s } => DVec3::new(
                m * (s.y * s.y + s.z * s.z) / 12.0,
                m * (s.x * s.x + s.z * s.z) / 12.0,
                m * (s.x * s.x + s.y * s.y) / 12.0,
            ),
            Shape::Cylinder {
                radius_m: r,
                length_m: l,
            } => {
                let ixx = m * (3.0 * r * r + l * l) / 12.0;
                DVec3::new(ixx, ixx, 0.5 * m * r * r)
            }
            Shape::Sphere { radius_m: r } => DVec3::splat(0.4 * m * r * r),
            Shape::Capsule {
                radius_m: r,
                length_m: l,
            } => {
                // split the mass by volume between the cylinder and the two caps
                let vc = std::f64::consts::PI * r * r * l;
                let vs = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
                let mc = m * vc / (vc + vs);
                let ms = m - mc;
                let izz = 0.5 * mc * r * r + 0.4 * ms * r * r;
                // hemispheres: own inertia about their centroid shifted to the capsule centre
                let ixx_c = mc * (3.0 * r * r + l * l) / 12.0;
                let ixx_s = ms * (0.4 * r * r + 0.5 * l * l + 0.375 * l * r);
                DVec3::new(ixx_c + ixx_s, ixx_c + ixx_s, izz)
            }
            Shape::Mesh { .. } => return None,
        };
        Some(DMat3::from_diagonal(d))
    }
}

/// A shape placed in its link's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    /// Placement of the shape frame in the link frame.
    pub origin: Transform,
    /// The shape.
    pub shape: Shape,
}

/// One link: its inertia and geometry, in the link frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkDesc {
    /// Unique name.
    pub name: String,
    /// Mass (kg), ≥ 0.
    pub mass_kg: f64,
    /// Centre of mass in the link frame (m).
    pub com_m: DVec3,
    /// Rotational inertia about the centre of mass, link axes (kg·m²). `None`:
    /// derived from the first collision (else visual) shape and the mass.
    pub inertia_kgm2: Option<DMat3>,
    /// Collision geometry (contact, falls).
    pub collision: Vec<Geometry>,
    /// Visual geometry (display only).
    pub visual: Vec<Geometry>,
}

impl LinkDesc {
    /// A massless link with no geometry.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            mass_kg: 0.0,
            com_m: DVec3::ZERO,
            inertia_kgm2: None,
            collision: Vec::new(),
            visual: Vec::new(),
        }
    }

    /// The link's rigid inertia in its frame: the given tensor, or one derived
    /// from its first shape (placed at the shape's origin, which then also sets
    /// the CoM when none was given explicitly).
    pub fn rigid_inertia(&self) -> RigidInertia {
        if let Some(i) = self.inertia_kgm2 {
            return RigidInertia::new(self.mass_kg, self.com_m, i);
        }
        let geom = self.collision.first().or_else(|| self.visual.first());
        match geom.and_then(|g| g.shape.solid_inertia(self.mass_kg).map(|i| (g, i))) {
            Some((g, i)) => RigidInertia::new(
                self.mass_kg,
                self.com_m,
                g.origin.rot * i * g.origin.rot.transpose(),
            ),
            None => RigidInertia::new(self.mass_kg, self.com_m, DMat3::ZERO),
        }
    }
}

/// Joint type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// Rotation about a unit axis (child frame). URDF `continuous` is a revolute without limits.
    Revolute {
        /// Unit axis in the child (= joint) frame.
        axis: DVec3,
    },
    /// Translation along a unit axis (child frame).
    Prismatic {
        /// Unit axis in the child (= joint) frame.
        axis: DVec3,
    },
    /// No motion: the child is merged into its parent at compile time.
    Fixed,
}

/// One joint between two links.
#[derive(Clone, Debug, PartialEq)]
pub struct JointDesc {
    /// Unique name.
    pub name: String,
    /// Type and axis.
    pub kind: JointKind,
    /// Parent link name.
    pub parent: String,
    /// Child link name.
    pub child: String,
    /// Child frame in the parent frame at zero position (the joint's centre and orientation).
    pub placement: Transform,
    /// Position limits (rad or m), `None` when unlimited.
    pub limits: Option<(f64, f64)>,
    /// Effort limit (N·m or N), `f64::INFINITY` when none.
    pub effort_limit: f64,
    /// Velocity limit (rad/s or m/s), `f64::INFINITY` when none.
    pub velocity_limit: f64,
    /// Viscous damping (N·m·s/rad or N·s/m).
    pub damping: f64,
    /// Coulomb friction (N·m or N).
    pub friction: f64,
    /// Reflected rotor inertia added to the joint's diagonal (kg·m² or kg).
    pub armature: f64,
    /// A spring–damper force element on the joint's coordinate (a compliant
    /// payload's), `None` for an ordinary joint.
    pub spring: Option<JointSpring>,
}

/// A linear spring–damper acting on one joint coordinate, at rest at q = 0:
/// `τ = −k q − b q̇` (the force element of a compliant payload). Unlike the
/// joint's `damping`, it is part of the load, not a joint imperfection, so
/// no passive-model switch turns it off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointSpring {
    /// Stiffness k (N/m for a prismatic joint, N·m/rad for a revolute one), ≥ 0.
    pub stiffness: f64,
    /// Damping b (N·s/m or N·m·s/rad), ≥ 0.
    pub damping: f64,
}

impl JointDesc {
    /// A joint with no limits, damping, friction or armature.
    pub fn new(
        name: impl Into<String>,
        kind: JointKind,
        parent: impl Into<String>,
        child: impl Into<String>,
        placement: Transform,
    ) -> Self {
        Self {
            name: name.into(),
            kind,
            parent: parent.into(),
            child: child.into(),
            placement,
            limits: None,
            effort_limit: f64::INFINITY,
            velocity_limit: f64::INFINITY,
            damping: 0.0,
            friction: 0.0,
            armature: 0.0,
            spring: None,
        }
    }

    /// True for joints that move (revolute and prismatic).
    pub fn is_movable(&self) -> bool {
        !matches!(self.kind, JointKind::Fixed)
    }
}

/// A whole robot: links and joints as a tree rooted at the one link that is no
/// joint's child. Movable joints appear in q and v in the order of `joints`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotDescription {
    /// Robot (model) name.
    pub name: String,
    /// Links.
    pub links: Vec<LinkDesc>,
    /// Joints, in document order.
    pub joints: Vec<JointDesc>,
    /// Names of the foot links; empty: the leaf links are the feet.
    pub feet: Vec<String>,
    /// Foot contact point in each foot link's frame (m), by foot name; a foot
    /// missing here makes contact at the link origin.
    pub foot_points: Vec<(String, DVec3)>,
}

impl RobotDescription {
    /// An empty description.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            ..Default::default()
        }
    }

    /// The link with this name.
    pub fn link(&self, name: &str) -> Option<&LinkDesc> {
        self.links.iter().find(|l| l.name == name)
    }

    /// The link with this name, mutably.
    pub fn link_mut(&mut self, name: &str) -> Option<&mut LinkDesc> {
        self.links.iter_mut().find(|l| l.name == name)
    }

    /// The joint with this name.
    pub fn joint(&self, name: &str) -> Option<&JointDesc> {
        self.joints.iter().find(|j| j.name == name)
    }

    /// The joint with this name, mutably.
    pub fn joint_mut(&mut self, name: &str) -> Option<&mut JointDesc> {
        self.joints.iter_mut().find(|j| j.name == name)
    }

    /// The root link: the one that is no joint's child.
    pub fn root_link(&self) -> Option<&LinkDesc> {
        self.links
            .iter()
            .find(|l| !self.joints.iter().any(|j| j.child == l.name))
    }

    /// Total mass (kg).
    pub fn total_mass_kg(&self) -> f64 {
        self.links.iter().map(|l| l.mass_kg).sum()
    }

    /// Number of movable joints.
    pub fn dof(&self) -> usize {
        self.joints.iter().filter(|j| j.is_movable()).count()
    }

    /// Names of the feet: those given, else the leaf links (links with no child joint).
    pub fn foot_names(&self) -> Vec<String> {
        if !self.feet.is_empty() {
            return self.feet.clone();
        }
        // sets, not scans: a long chain is linear (issue 29)
        let parents: std::collections::HashSet<&str> =
            self.joints.iter().map(|j| j.parent.as_str()).collect();
        let children: std::collections::HashSet<&str> =
            self.joints.iter().map(|j| j.child.as_str()).collect();
        self.links
            .iter()
            .filter(|l| !parents.contains(l.name.as_str()))
            .filter(|l| children.contains(l.name.as_str()))
            .map(|l| l.name.clone())
            .collect()
    }
}

/// Builds a [`RobotDescription`] step by step, in the reference platform's
/// order: create a link, set its mass, CoM and inertia, attach its geometry;
/// create a joint, set its centre and axis, connect two links.
///
/// # Examples
/// ```
/// use quadsim_engine::description::{RobotBuilder, Shape};
/// use quadsim_engine::spatial::Transform;
/// use glam::DVec3;
/// let robot = RobotBuilder::new("pendulum")
///     .link("base").mass(1.0).shape(Transform::IDENTITY, Shape::Box { size_m: DVec3::splat(0.1) }).done()
///     .link("arm").mass(2.0).com(DVec3::new(0.0, 0.0, -0.5)).done()
///     .revolute("swing", "base", "arm", DVec3::ZERO, DVec3::Y)
///     .build();
/// assert_eq!(robot.dof(), 1);
/// ```
#[derive(Debug, Default)]
pub struct RobotBuilder {
    desc: RobotDescription,
}

/// Builder of one link, returned by [`RobotBuilder::link`]; finish with [`LinkBuilder::done`].
#[derive(Debug)]
pub struct LinkBuilder {
    parent: RobotBuilder,
    link: LinkDesc,
}

impl RobotBuilder {
    /// Starts a robot.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            desc: RobotDescription::new(name),
        }
    }

    /// Creates a link.
    pub fn link(self, name: impl Into<String>) -> LinkBuilder {
        LinkBuilder {
            parent: self,
            link: LinkDesc::new(name),
        }
    }

    /// Adds a fully specified joint.
    pub fn joint(mut self, joint: JointDesc) -> Self {
        self.desc.joints.push(joint);
        self
    }

    /// Connects `parent` to `child` with a revolute joint centred at `centre_m`
    /// (parent frame) turning about `axis` (normalised).
    pub fn revolute(
        self,
        name: &str,
        parent: &str,
        child: &str,
        centre_m: DVec3,
        axis: DVec3,
    ) -> Self {
        let kind = JointKind::Revolute {
            axis: axis.normalize(),
        };
        self.joint(JointDesc::new(
            name,
            kind,
            parent,
            child,
            Transform::from_translation(centre_m),
        ))
    }

    /// Connects `parent` to `child` with a prismatic joint at `centre_m` sliding along `axis`.
    pub fn prismatic(
        self,
        name: &str,
        parent: &str,
        child: &str,
        centre_m: DVec3,
        axis: DVec3,
    ) -> Self {
        let kind = JointKind::Prismatic {
            axis: axis.normalize(),
        };
        self.joint(JointDesc::new(
            name,
            kind,
            parent,
            child,
            Transform::from_translation(centre_m),
        ))
    }

    /// Rigidly attaches `child` to `parent` at `placement`.
    pub fn fixed(self, name: &str, parent: &str, child: &str, placement: Transform) -> Self {
        self.joint(JointDesc::new(
            name,
            JointKind::Fixed,
            parent,
            child,
            placement,
        ))
    }

    /// Names the feet (otherwise the leaf links are the feet).
    pub fn feet(mut self, feet: &[&str]) -> Self {
        self.desc.feet = feet.iter().map(|s| s.to_string()).collect();
        self
    }

    /// Finishes the description.
    pub fn build(self) -> RobotDescription {
        self.desc
    }
}

impl LinkBuilder {
    /// Sets the mass (kg).
    pub fn mass(mut self, mass_kg: f64) -> Self {
        self.link.mass_kg = mass_kg;
        self
    }

    /// Sets the centre of mass in the link frame (m).
    pub fn com(mut self, com_m: DVec3) -> Self {
        self.link.com_m = com_m;
        self
    }

    /// Sets the rotational inertia about the CoM (kg·m², link axes).
    pub fn inertia(mut self, inertia_kgm2: DMat3) -> Self {
        self.link.inertia_kgm2 = Some(inertia_kgm2);
        self
    }

    /// Attaches a collision shape (also drawn).
    pub fn shape(mut self, origin: Transform, shape: Shape) -> Self {
        self.link.collision.push(Geometry {
            origin,
            shape: shape.clone(),
        });
        self.link.visual.push(Geometry { origin, shape });
        self
    }

    /// Attaches a visual-only shape.
    pub fn visual(mut self, origin: Transform, shape: Shape) -> Self {
        self.link.visual.push(Geometry { origin, shape });
        self
    }

    /// Finishes the link.
    pub fn done(mut self) -> RobotBuilder {
        self.parent.desc.links.push(self.link);
        self.parent
    }
}
