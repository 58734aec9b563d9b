//! Robots as entities: spawning from a description and reading it back,
//! colliders built from shapes, and errors for broken entity sets.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};
use parry3d_f64::math::Pose;
use quadsim_components::{
    BelongsTo, Collider, DescribeError, Foot, Joint, JointConnection, Link, LinkColliders, Mass,
    Robot, RobotParts, SimThreadPool, Visual, describe_robot, spawn_robot,
};
use quadsim_engine::description::{Geometry, RobotBuilder, RobotDescription, Shape};
use quadsim_engine::spatial::Transform;

/// A description exercising every component: all shape kinds, explicit and
/// derived inertia, limits and passive coefficients, feet and foot points.
fn rich_description() -> RobotDescription {
    let cube: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -0.1 } else { 0.1 },
                if i & 2 == 0 { -0.1 } else { 0.1 },
                if i & 4 == 0 { -0.1 } else { 0.1 },
            )
        })
        .collect();
    let tilted = Transform::from_xyz_rpy(DVec3::new(0.0, 0.0, -0.1), DVec3::new(0.3, 0.0, 0.1));
    let mut d = RobotBuilder::new("rich")
        .link("torso")
        .mass(10.0)
        .shape(
            Transform::IDENTITY,
            Shape::Box {
                size_m: DVec3::new(0.6, 0.3, 0.1),
            },
        )
        .done()
        .link("thigh")
        .mass(2.5)
        .com(DVec3::new(0.0, 0.0, -0.15))
        .shape(
            tilted,
            Shape::Cylinder {
                radius_m: 0.05,
                length_m: 0.3,
            },
        )
        .done()
        .link("shank")
        .mass(1.5)
        .inertia(DMat3::from_diagonal(DVec3::new(0.01, 0.02, 0.003)))
        .shape(
            Transform::IDENTITY,
            Shape::Capsule {
                radius_m: 0.04,
                length_m: 0.25,
            },
        )
        .visual(
            Transform::IDENTITY,
            Shape::Mesh {
                uri: "package://shank.stl".into(),
                scale: DVec3::ONE,
                vertices: None,
            },
        )
        .done()
        .link("foot")
        .mass(0.5)
        .shape(Transform::IDENTITY, Shape::Sphere { radius_m: 0.03 })
        .shape(
            Transform::IDENTITY,
            Shape::Mesh {
                uri: "cube.obj".into(),
                scale: DVec3::ONE,
                vertices: Some(cube),
            },
        )
        .done()
        .revolute(
            "hip",
            "torso",
            "thigh",
            DVec3::new(0.3, 0.15, 0.0),
            DVec3::X,
        )
        .prismatic(
            "knee",
            "thigh",
            "shank",
            DVec3::new(0.0, 0.0, -0.3),
            DVec3::Z,
        )
        .fixed(
            "ankle",
            "shank",
            "foot",
            Transform::from_translation(DVec3::new(0.0, 0.0, -0.25)),
        )
        .feet(&["foot"])
        .build();
    let hip = d.joint_mut("hip").unwrap();
    hip.limits = Some((-0.5, 0.7));
    hip.effort_limit = 40.0;
    hip.velocity_limit = 12.0;
    hip.damping = 0.1;
    hip.friction = 0.2;
    hip.armature = 0.01;
    d.foot_points
        .push(("foot".into(), DVec3::new(0.0, 0.0, -0.03)));
    d
}

/// The description `describe_robot` returns for `d`: feet listed explicitly
/// (leaf links when none were given), feet and foot points in link order.
fn normalised(d: &RobotDescription) -> RobotDescription {
    let mut n = d.clone();
    let feet = d.foot_names();
    n.feet = d
        .links
        .iter()
        .map(|l| l.name.clone())
        .filter(|l| feet.contains(l))
        .collect();
    n.foot_points = d
        .links
        .iter()
        .filter_map(|l| d.foot_points.iter().find(|(f, _)| *f == l.name).cloned())
        .collect();
    n
}

/// Number of entities that are part of some robot (roots, links, joints, shapes).
fn robot_entities(world: &mut World) -> usize {
    world
        .query_filtered::<(), Or<(
            With<Robot>,
            With<Link>,
            With<Joint>,
            With<Collider>,
            With<Visual>,
        )>>()
        .iter(world)
        .count()
}

#[test]
fn describe_inverts_spawn_for_every_component() {
    let d = rich_description();
    let mut world = World::new();
    let root = spawn_robot(&mut world, &d);
    assert_eq!(describe_robot(&world, root).unwrap(), normalised(&d));
    // one entity per link, joint, collider and visual, plus the root
    let shapes: usize = d
        .links
        .iter()
        .map(|l| l.collision.len() + l.visual.len())
        .sum();
    assert_eq!(
        robot_entities(&mut world),
        1 + d.links.len() + d.joints.len() + shapes
    );
}

#[test]
fn describe_inverts_spawn_on_random_trees() {
    let mut world = World::new();
    for seed in 0..20 {
        let d = common::random_tree(seed, 1 + seed as usize % 12);
        let root = spawn_robot(&mut world, &d);
        assert_eq!(
            describe_robot(&world, root).unwrap(),
            normalised(&d),
            "seed {seed}"
        );
    }
}

#[test]
fn describe_inverts_spawn_on_builtin_robots() {
    let mut world = World::new();
    for name in quadsim_engine::robots::builtin_names() {
        let d = quadsim_engine::robots::builtin(name).unwrap();
        let root = spawn_robot(&mut world, &d);
        assert_eq!(
            describe_robot(&world, root).unwrap(),
            normalised(&d),
            "{name}"
        );
        // every foot link carries the Foot marker
        let feet = world
            .query_filtered::<&BelongsTo, With<Foot>>()
            .iter(&world)
            .filter(|b| b.0 == root)
            .count();
        assert_eq!(feet, d.foot_names().len(), "{name}");
    }
}

#[test]
fn edited_components_change_the_description() {
    let d = rich_description();
    let mut world = World::new();
    let root = spawn_robot(&mut world, &d);
    let mut q = world.query::<(Entity, &Link)>();
    let thigh = q.iter(&world).find(|(_, l)| l.name == "thigh").unwrap().0;
    world.entity_mut(thigh).insert(Mass(4.0));
    let mut feet = world.query_filtered::<Entity, With<Foot>>();
    let foot = feet.single(&world).unwrap();
    world.entity_mut(foot).remove::<Foot>();
    let edited = describe_robot(&world, root).unwrap();
    assert_eq!(edited.link("thigh").unwrap().mass_kg, 4.0);
    assert_eq!(edited.total_mass_kg(), d.total_mass_kg() + 1.5);
    assert!(edited.feet.is_empty());
}

#[test]
fn joint_to_another_robots_link_is_a_typed_error() {
    let d = rich_description();
    let mut world = World::new();
    let a = spawn_robot(&mut world, &d);
    let b = spawn_robot(&mut world, &d);
    let b_link = world.get::<RobotParts>(b).unwrap().iter().next().unwrap();
    let mut joints = world.query::<(Entity, &Joint, &BelongsTo, &JointConnection)>();
    let (knee, conn) = joints
        .iter(&world)
        .find(|(_, joint, owner, _)| owner.0 == a && joint.name == "knee")
        .map(|(e, _, _, c)| (e, *c))
        .unwrap();
    world.entity_mut(knee).insert(JointConnection {
        child: b_link,
        ..conn
    });
    assert_eq!(
        describe_robot(&world, a),
        Err(DescribeError::ForeignLink {
            robot: "rich".into(),
            joint: "knee".into(),
            role: "child",
            entity: b_link,
        })
    );
    assert!(describe_robot(&world, b).is_ok());
    assert_eq!(
        describe_robot(&world, b_link),
        Err(DescribeError::NotARobot(b_link))
    );
}

#[test]
fn despawning_the_root_despawns_the_whole_robot() {
    let mut world = World::new();
    let a = spawn_robot(&mut world, &rich_description());
    let n = robot_entities(&mut world);
    let b = spawn_robot(&mut world, &rich_description());
    assert_eq!(robot_entities(&mut world), 2 * n);
    world.despawn(b);
    assert_eq!(robot_entities(&mut world), n);
    assert!(describe_robot(&world, a).is_ok());
}

/// The collider of `link`'s `k`-th collision shape.
fn collider(world: &World, root: Entity, link: &str, k: usize) -> Collider {
    let parts = world.get::<RobotParts>(root).unwrap();
    let e = parts
        .iter()
        .find(|&e| world.get::<Link>(e).is_some_and(|l| l.name == link))
        .unwrap();
    let c = world
        .get::<LinkColliders>(e)
        .unwrap()
        .iter()
        .nth(k)
        .unwrap();
    world.get::<Collider>(c).unwrap().clone()
}

fn contains(c: &Collider, p_link: DVec3) -> bool {
    let pose: Pose = c.pose();
    c.shape().unwrap().contains_point(&pose, p_link)
}

#[test]
fn colliders_follow_the_description_frames() {
    let d = rich_description();
    let mut world = World::new();
    let root = spawn_robot(&mut world, &d);

    // box 0.6 × 0.3 × 0.1 centred on the torso frame
    let torso = collider(&world, root, "torso", 0);
    assert!(contains(&torso, DVec3::new(0.29, 0.14, 0.04)));
    assert!(!contains(&torso, DVec3::new(0.0, 0.0, 0.06)));

    // the cylinder's axis is the shape frame's z (URDF), not parry's y
    let thigh = collider(&world, root, "thigh", 0);
    let origin = d.link("thigh").unwrap().collision[0].origin;
    let along_z = origin.transform_point(DVec3::new(0.0, 0.0, 0.14));
    let along_y = origin.transform_point(DVec3::new(0.0, 0.14, 0.0));
    assert!(contains(&thigh, along_z));
    assert!(!contains(&thigh, along_y));

    // capsule: cylinder of 0.25 plus caps of 0.04 along z
    let shank = collider(&world, root, "shank", 0);
    assert!(contains(&shank, DVec3::new(0.0, 0.0, 0.125 + 0.039)));
    assert!(!contains(&shank, DVec3::new(0.0, 0.0, 0.125 + 0.041)));

    // the mesh with vertices became their convex hull (a 0.2 m cube)
    let hull = collider(&world, root, "foot", 1);
    assert!(contains(&hull, DVec3::splat(0.099)));
    assert!(!contains(&hull, DVec3::new(0.101, 0.0, 0.0)));
    let volume = hull.shape().unwrap().mass_properties(1.0).mass();
    assert!((volume - 0.008).abs() < 1e-12, "{volume}");
}

#[test]
fn mesh_without_vertices_stays_a_reference() {
    let g = Geometry {
        origin: Transform::IDENTITY,
        shape: Shape::Mesh {
            uri: "missing.stl".into(),
            scale: DVec3::ONE,
            vertices: None,
        },
    };
    let c = Collider::new(g.clone());
    assert!(c.shape().is_none());
    assert_eq!(c.geometry(), &g);
    // and a mesh whose file held no vertices has no hull either
    let empty = Shape::Mesh {
        uri: "empty.stl".into(),
        scale: DVec3::ONE,
        vertices: Some(vec![]),
    };
    assert!(
        Collider::new(Geometry {
            origin: Transform::IDENTITY,
            shape: empty
        })
        .shape()
        .is_none()
    );
    let mut world = World::new();
    let d = rich_description();
    let root = spawn_robot(&mut world, &d);
    let visuals: Vec<&Visual> = world.query::<&Visual>().iter(&world).collect();
    assert_eq!(
        visuals.len(),
        d.links.iter().map(|l| l.visual.len()).sum::<usize>()
    );
    assert!(describe_robot(&world, root).is_ok());
}

#[test]
fn thread_pool_has_the_requested_size() {
    for n in [1, 2, 3] {
        let pool = SimThreadPool::new(n).unwrap();
        assert_eq!(pool.threads(), n);
        let seen = pool.install(rayon::current_num_threads);
        assert_eq!(seen, n);
    }
}

/// Robots of one design share each collider's shape (the convex hull
/// included) and each visual; a geometry that differs, if only in the sign
/// of a zero, gets its own, and the shared ones read back as the description.
#[test]
fn robots_of_one_design_share_their_shapes() {
    let d = rich_description();
    let mut world = World::new();
    let a = spawn_robot(&mut world, &d);
    let b = spawn_robot(&mut world, &d);
    let (ha, hb) = (
        collider(&world, a, "foot", 1),
        collider(&world, b, "foot", 1),
    );
    let same_shape = |x: &Collider, y: &Collider| {
        std::ptr::eq(
            std::ptr::from_ref(x.shape().unwrap().as_ref()).cast::<u8>(),
            std::ptr::from_ref(y.shape().unwrap().as_ref()).cast::<u8>(),
        )
    };
    assert!(same_shape(&ha, &hb), "one hull for both robots");
    let visuals: Vec<&Visual> = world.query::<&Visual>().iter(&world).collect();
    let n = visuals.len() / 2;
    for k in 0..n {
        assert!(std::sync::Arc::ptr_eq(&visuals[k].0, &visuals[n + k].0));
    }
    // −0.0 for 0.0 in the torso box's origin: equal by `==`, not by bits
    let mut e = d.clone();
    let torso = e.links.iter_mut().find(|l| l.name == "torso").unwrap();
    torso.collision[0].origin.trans.x = -0.0;
    let c = spawn_robot(&mut world, &e);
    let tc = collider(&world, c, "torso", 0);
    assert!(!same_shape(&collider(&world, a, "torso", 0), &tc));
    assert_eq!(tc.geometry().origin.trans.x.to_bits(), (-0.0f64).to_bits());
    assert!(same_shape(
        &collider(&world, a, "foot", 1),
        &collider(&world, c, "foot", 1)
    ));
    assert_eq!(describe_robot(&world, b).unwrap(), d);
    assert_eq!(describe_robot(&world, c).unwrap(), e);
}
