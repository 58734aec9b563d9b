//! From an engine [`RobotDescription`] to entities and back.
//!
//! [`spawn_robot`] follows the reference platform's building steps (create a
//! link, set its mass, CoM and inertia, attach its geometry; create a joint,
//! set its centre and axis, connect two links). [`describe_robot`] reads the
//! entities back into a description, so an edited entity set compiles to a new
//! model.

use bevy_ecs::prelude::*;
use quadsim_engine::description::{Geometry, JointDesc, LinkDesc, RobotDescription};
use quadsim_engine::{BaseKind, ModelError};
use thiserror::Error;

use crate::collider::{
    Collider, ColliderOf, LinkColliders, LinkVisuals, ShapeInterner, Visual, VisualOf,
};
use crate::joint::{
    EffortLimit, Joint, JointArmature, JointConnection, JointDamping, JointFriction, JointLimits,
    JointPlacement, SpringDamper, VelocityLimit,
};
use crate::link::{CenterOfMass, Foot, FootPoint, Inertia, Link, Mass};
use crate::robot::{BelongsTo, Robot, RobotBase, RobotModelName, RobotParts};

/// Why a robot's entities do not form a description.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum DescribeError {
    /// The entity does not exist or has no [`Robot`] component.
    #[error("entity {0} is not a robot root")]
    NotARobot(Entity),
    /// A joint's [`JointConnection`] names an entity that is not a link of the same robot.
    #[error(
        "robot '{robot}', joint '{joint}': field '{role}' is entity {entity}, not a link of this robot"
    )]
    ForeignLink {
        /// Robot instance name.
        robot: String,
        /// Joint name.
        joint: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The offending entity.
        entity: Entity,
    },
}

/// Why a robot could not be compiled into a packed model.
#[derive(Debug, Error, PartialEq)]
pub enum CompileError {
    /// The entities do not form a description.
    #[error(transparent)]
    Describe(#[from] DescribeError),
    /// The description is not a valid model.
    #[error("robot '{robot}': {source}")]
    Model {
        /// Robot instance name.
        robot: String,
        /// The engine's error (names the link or joint and field).
        #[source]
        source: ModelError,
    },
}

/// Spawns a floating-base robot: one root entity, one entity per link, joint,
/// collider and visual. Returns the root. The model is compiled by the compile
/// stage before the next step.
pub fn spawn_robot(world: &mut World, desc: &RobotDescription) -> Entity {
    spawn_robot_with_base(world, desc, BaseKind::Floating)
}

/// [`spawn_robot`] with a chosen base (fixed for arms and pendulums).
pub fn spawn_robot_with_base(world: &mut World, desc: &RobotDescription, base: BaseKind) -> Entity {
    let root = world
        .spawn((
            Robot {
                name: desc.name.clone(),
            },
            RobotModelName(desc.name.clone()),
            RobotBase(base),
        ))
        .id();
    let feet = desc.foot_names();
    let mut link_entities = Vec::with_capacity(desc.links.len());
    for l in &desc.links {
        let link = spawn_link(world, root, l);
        if feet.contains(&l.name) {
            world.entity_mut(link).insert(Foot);
        }
        if let Some((_, p)) = desc.foot_points.iter().find(|(n, _)| *n == l.name) {
            world.entity_mut(link).insert(FootPoint(*p));
        }
        link_entities.push(link);
    }
    // Joints name their links; a name without a link leaves the joint
    // connected to the root entity, which compiling reports as a foreign link.
    let find = |name: &str| {
        desc.links
            .iter()
            .position(|l| l.name == name)
            .map_or(root, |i| link_entities[i])
    };
    for j in &desc.joints {
        let connection = JointConnection {
            parent: find(&j.parent),
            child: find(&j.child),
        };
        spawn_joint(world, root, j, connection);
    }
    // kept as long as the robot
    if let Some(mut parts) = world.get_mut::<RobotParts>(root) {
        parts.shrink_to_fit();
    }
    root
}

/// Spawns one link entity of `robot` with its colliders and visuals (their
/// shapes shared with equal ones already spawned, see [`ShapeInterner`]).
pub fn spawn_link(world: &mut World, robot: Entity, l: &LinkDesc) -> Entity {
    let mut e = world.spawn((
        Link {
            name: l.name.clone(),
        },
        Mass(l.mass_kg),
        CenterOfMass(l.com_m),
        BelongsTo(robot),
    ));
    if let Some(i) = l.inertia_kgm2 {
        e.insert(Inertia(i));
    }
    let link = e.id();
    let mut shapes = world.get_resource_or_insert_with(ShapeInterner::default);
    let colliders: Vec<Collider> = l.collision.iter().map(|g| shapes.collider(g)).collect();
    let visuals: Vec<Visual> = l.visual.iter().map(|g| shapes.visual(g)).collect();
    for c in colliders {
        world.spawn((c, ColliderOf(link)));
    }
    for v in visuals {
        world.spawn((v, VisualOf(link)));
    }
    link
}

/// Spawns one joint entity of `robot` between two link entities.
pub fn spawn_joint(
    world: &mut World,
    robot: Entity,
    j: &JointDesc,
    connection: JointConnection,
) -> Entity {
    let mut e = world.spawn((
        Joint::from_engine(j.name.clone(), j.kind),
        JointPlacement(j.placement),
        connection,
        EffortLimit(j.effort_limit),
        VelocityLimit(j.velocity_limit),
        JointDamping(j.damping),
        JointFriction(j.friction),
        JointArmature(j.armature),
        BelongsTo(robot),
    ));
    if let Some((lower, upper)) = j.limits {
        e.insert(JointLimits { lower, upper });
    }
    if let Some(s) = j.spring {
        e.insert(SpringDamper(s));
    }
    e.id()
}

/// Reads a robot's entities back into a description, links and joints in
/// [`RobotParts`] order. Also returns the link entities in description order
/// (which is the compiled model's frame order).
pub fn describe_robot_with_links(
    world: &World,
    root: Entity,
) -> Result<(RobotDescription, Vec<Entity>), DescribeError> {
    let robot = world
        .get_entity(root)
        .ok()
        .and_then(|e| e.get::<Robot>())
        .ok_or(DescribeError::NotARobot(root))?;
    let model_name = world
        .get::<RobotModelName>(root)
        .map_or_else(|| robot.name.clone(), |n| n.0.clone());
    let mut desc = RobotDescription::new(model_name);
    let parts: &[Entity] = world
        .get::<RobotParts>(root)
        .map_or(&[], |p| p.collection());
    let mut links = Vec::new();
    for &e in parts {
        let Ok(ent) = world.get_entity(e) else {
            continue;
        };
        let Some(link) = ent.get::<Link>() else {
            continue;
        };
        let geometry_of = |list: Option<&[Entity]>, visual: bool| -> Vec<Geometry> {
            list.unwrap_or(&[])
                .iter()
                .filter_map(|&g| {
                    if visual {
                        world.get::<Visual>(g).map(|v| Geometry::clone(&v.0))
                    } else {
                        world.get::<Collider>(g).map(|c| c.geometry().clone())
                    }
                })
                .collect()
        };
        desc.links.push(LinkDesc {
            name: link.name.clone(),
            mass_kg: ent.get::<Mass>().map_or(0.0, |m| m.0),
            com_m: ent.get::<CenterOfMass>().map_or(glam::DVec3::ZERO, |c| c.0),
            inertia_kgm2: ent.get::<Inertia>().map(|i| i.0),
            collision: geometry_of(
                ent.get::<LinkColliders>()
                    .map(|c| c.collection().as_slice()),
                false,
            ),
            visual: geometry_of(
                ent.get::<LinkVisuals>().map(|c| c.collection().as_slice()),
                true,
            ),
        });
        if ent.contains::<Foot>() {
            desc.feet.push(link.name.clone());
        }
        if let Some(p) = ent.get::<FootPoint>() {
            desc.foot_points.push((link.name.clone(), p.0));
        }
        links.push(e);
    }
    for &e in parts {
        let Ok(ent) = world.get_entity(e) else {
            continue;
        };
        let Some(joint) = ent.get::<Joint>() else {
            continue;
        };
        let link_name = |role: &'static str, entity: Option<Entity>| {
            entity
                .filter(|le| links.contains(le))
                .and_then(|le| world.get::<Link>(le))
                .map(|l| l.name.clone())
                .ok_or_else(|| DescribeError::ForeignLink {
                    robot: robot.name.clone(),
                    joint: joint.name.clone(),
                    role,
                    entity: entity.unwrap_or(Entity::PLACEHOLDER),
                })
        };
        let conn = ent.get::<JointConnection>();
        let mut j = JointDesc::new(
            joint.name.clone(),
            joint.engine_kind(),
            link_name("parent", conn.map(|c| c.parent))?,
            link_name("child", conn.map(|c| c.child))?,
            ent.get::<JointPlacement>().map(|p| p.0).unwrap_or_default(),
        );
        j.limits = ent.get::<JointLimits>().map(|l| (l.lower, l.upper));
        if let Some(v) = ent.get::<EffortLimit>() {
            j.effort_limit = v.0;
        }
        if let Some(v) = ent.get::<VelocityLimit>() {
            j.velocity_limit = v.0;
        }
        if let Some(v) = ent.get::<JointDamping>() {
            j.damping = v.0;
        }
        if let Some(v) = ent.get::<JointFriction>() {
            j.friction = v.0;
        }
        if let Some(v) = ent.get::<JointArmature>() {
            j.armature = v.0;
        }
        j.spring = ent.get::<SpringDamper>().map(|s| s.0);
        desc.joints.push(j);
    }
    // the compiled robot keeps the link list
    links.shrink_to_fit();
    Ok((desc, links))
}

/// Reads a robot's entities back into a description (see [`describe_robot_with_links`]).
pub fn describe_robot(world: &World, root: Entity) -> Result<RobotDescription, DescribeError> {
    describe_robot_with_links(world, root).map(|(d, _)| d)
}
