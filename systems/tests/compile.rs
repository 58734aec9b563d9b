//! The compile stage: entities → packed model at spawn and after edits, never
//! inside a step; typed errors for broken edits; slots renumbered on despawn.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};
use quadsim_components::{
    CompileError, CompileFailure, ComputedInertia, Inertia, Link, Mass, RobotIndex, SimConfig,
    spawn_robot,
};
use quadsim_engine::description::{RobotBuilder, RobotDescription, Shape};
use quadsim_engine::nle::generalized_gravity;
use quadsim_engine::spatial::Transform;
use quadsim_engine::{BaseKind, Data, Model, ModelError};
use quadsim_systems::Simulation;

/// A two-link pendulum hanging from a boxy base, built the reference platform's way.
fn pendulum() -> RobotDescription {
    RobotBuilder::new("pendulum")
        .link("base")
        .mass(3.0)
        .shape(
            Transform::IDENTITY,
            Shape::Box {
                size_m: DVec3::new(0.4, 0.2, 0.1),
            },
        )
        .done()
        .link("upper")
        .mass(1.0)
        .com(DVec3::new(0.0, 0.0, -0.25))
        .inertia(DMat3::from_diagonal(DVec3::new(0.02, 0.02, 0.001)))
        .done()
        .link("lower")
        .mass(0.5)
        .com(DVec3::new(0.0, 0.0, -0.2))
        .done()
        .revolute("shoulder", "base", "upper", DVec3::ZERO, DVec3::Y)
        .revolute(
            "elbow",
            "upper",
            "lower",
            DVec3::new(0.0, 0.0, -0.5),
            DVec3::Y,
        )
        .build()
}

fn link_entity(sim: &mut Simulation, name: &str) -> Entity {
    let mut q = sim.world.query::<(Entity, &Link)>();
    q.iter(&sim.world).find(|(_, l)| l.name == name).unwrap().0
}

/// The link entity `name` of the robot `root`.
fn robot_link(sim: &mut Simulation, root: Entity, name: &str) -> Entity {
    let mut q = sim
        .world
        .query::<(Entity, &Link, &quadsim_components::BelongsTo)>();
    q.iter(&sim.world)
        .find(|(_, l, b)| l.name == name && b.0 == root)
        .unwrap()
        .0
}

/// The joint entity `name` of the robot `root`.
fn robot_joint(sim: &mut Simulation, root: Entity, name: &str) -> Entity {
    let mut q = sim.world.query::<(
        Entity,
        &quadsim_components::Joint,
        &quadsim_components::BelongsTo,
    )>();
    q.iter(&sim.world)
        .find(|(_, j, b)| j.name == name && b.0 == root)
        .unwrap()
        .0
}

/// Vertical force (base frame, N) that holds a floating robot still at the neutral pose: M·|g|.
fn holding_force_n(model: &Model) -> f64 {
    let mut data = Data::new(model);
    generalized_gravity(model, &mut data, &model.neutral_q())[2]
}

#[test]
fn spawned_robot_compiles_to_the_description_model() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let quad16 = quadsim_engine::robots::builtin("quad16").unwrap();
    let quad12 = quadsim_engine::robots::builtin("quad12").unwrap();
    for (seed, desc) in [
        (0, pendulum()),
        (1, common::random_tree(7, 9)),
        (2, quad16),
        (3, quad12),
    ] {
        let root = sim.spawn_robot(&desc).unwrap();
        let direct = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let model = &sim.robot(root).unwrap().model;
        assert_eq!(
            (model.nq, model.nv, model.nbodies),
            (direct.nq, direct.nv, direct.nbodies)
        );
        assert_eq!(model.nv, 6 + desc.dof());
        assert_eq!(model.total_mass, desc.total_mass_kg());
        assert_eq!(model.inertia, direct.inertia, "robot {seed}");
        assert_eq!(sim.world.get::<RobotIndex>(root), Some(&RobotIndex(seed)));
    }
}

#[test]
fn editing_mass_recompiles_outside_the_step() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let root = sim.spawn_robot(&pendulum()).unwrap();
    sim.run(10);
    let before = sim.robot(root).unwrap().model.clone();
    assert!((holding_force_n(&before) - 4.5 * 9.81).abs() < 1e-12);

    let lower = link_entity(&mut sim, "lower");
    sim.world.entity_mut(lower).insert(Mass(2.0));

    // The step schedule alone never compiles: same model, state keeps moving.
    sim.run_step_schedule();
    let r = sim.robot(root).unwrap();
    assert!(Arc::ptr_eq(&r.model, &before));
    let state = r.state.clone();

    // The compile schedule picks the edit up and keeps the state.
    sim.compile();
    let r = sim.robot(root).unwrap();
    assert!(!Arc::ptr_eq(&r.model, &before));
    assert_eq!(r.model.total_mass, 6.0);
    assert!((holding_force_n(&r.model) - 6.0 * 9.81).abs() < 1e-12);
    assert_eq!(r.state, state);

    // Nothing changed since: compiling again keeps the same model.
    let compiled = r.model.clone();
    sim.step();
    assert!(Arc::ptr_eq(&sim.robot(root).unwrap().model, &compiled));
}

#[test]
fn derived_and_user_inertia_stay_apart() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    sim.spawn_robot(&pendulum()).unwrap();
    let base = link_entity(&mut sim, "base");
    let upper = link_entity(&mut sim, "upper");
    // box 0.4 × 0.2 × 0.1 of 3 kg: I = m (b² + c²) / 12 about each axis
    let expect = DVec3::new(
        3.0 * (0.04 + 0.01) / 12.0,
        3.0 * (0.16 + 0.01) / 12.0,
        3.0 * (0.16 + 0.04) / 12.0,
    );
    assert!(sim.world.get::<Inertia>(base).is_none());
    let derived = sim.world.get::<ComputedInertia>(base).unwrap().0;
    assert!((derived.diagonal() - expect).abs().max_element() < 1e-15);
    let given = sim.world.get::<Inertia>(upper).unwrap().0;
    assert_eq!(sim.world.get::<ComputedInertia>(upper).unwrap().0, given);

    // Dropping the user inertia of a shapeless link: derived is zero, and the model follows.
    sim.world.entity_mut(upper).remove::<Inertia>();
    sim.compile();
    assert_eq!(
        sim.world.get::<ComputedInertia>(upper).unwrap().0,
        DMat3::ZERO
    );
}

#[test]
fn invalid_edit_is_reported_and_keeps_the_last_model() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let root = sim.spawn_robot(&pendulum()).unwrap();
    let model = sim.robot(root).unwrap().model.clone();
    let lower = link_entity(&mut sim, "lower");
    sim.world.entity_mut(lower).insert(Mass(-1.0));
    sim.step();
    match sim.world.get::<CompileFailure>(root) {
        Some(CompileFailure(CompileError::Model {
            robot,
            source: ModelError::InvalidValue { item, field, .. },
        })) => {
            assert_eq!(
                (robot.as_str(), item.as_str(), *field),
                ("pendulum", "lower", "mass")
            );
        }
        other => panic!("expected an invalid-mass failure, got {other:?}"),
    }
    assert!(Arc::ptr_eq(&sim.robot(root).unwrap().model, &model));
    assert_eq!(sim.clock().step, 1);

    // fixing the edit clears the failure
    sim.world.entity_mut(lower).insert(Mass(0.7));
    sim.step();
    assert!(sim.world.get::<CompileFailure>(root).is_none());
    assert!((sim.robot(root).unwrap().model.total_mass - 4.7).abs() < 1e-15);

    // a description that never compiles is refused at spawn, leaving nothing behind
    let mut broken = pendulum();
    broken.joints[1].parent = "nowhere".into();
    let err = sim.spawn_robot(&broken).unwrap_err();
    assert!(matches!(err, CompileError::Describe(_)), "{err}");
    assert_eq!(sim.world.query::<&Link>().iter(&sim.world).count(), 3);
}

#[test]
fn despawned_robots_free_their_slots() {
    let mut sim = Simulation::new(SimConfig::default(), 2).unwrap();
    let roots: Vec<Entity> = (0..4)
        .map(|s| sim.spawn_robot(&common::random_tree(s, 4)).unwrap())
        .collect();
    sim.world.despawn(roots[1]);
    sim.step();
    let batch = sim.world.resource::<quadsim_components::RobotBatch>();
    assert_eq!(batch.sims.len(), 3);
    for (i, s) in batch.sims.iter().enumerate() {
        assert_eq!(sim.world.get::<RobotIndex>(s.entity), Some(&RobotIndex(i)));
        assert_ne!(s.entity, roots[1]);
    }
    for &r in [roots[0], roots[2], roots[3]].iter() {
        assert_eq!(sim.robot(r).unwrap().entity, r);
    }
}

#[test]
fn gravity_edit_recompiles_every_robot() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let a = sim.spawn_robot(&pendulum()).unwrap();
    let b = spawn_robot(&mut sim.world, &common::random_tree(3, 5));
    sim.world.resource_mut::<SimConfig>().gravity = DVec3::new(0.0, 0.0, -1.62);
    sim.step();
    for r in [a, b] {
        assert_eq!(
            sim.robot(r).unwrap().model.gravity,
            DVec3::new(0.0, 0.0, -1.62)
        );
    }
}

/// Robots of one articulation share one `Arc<Model>` whatever their names
/// (so the step can batch them); a different articulation, or an edit that
/// makes one, gets its own model; the robot's own name stays on its entity.
#[test]
fn robots_of_one_articulation_share_one_model() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let quad16 = quadsim_engine::robots::builtin("quad16").unwrap();
    let mut roots = Vec::new();
    for name in ["a", "b", "c"] {
        let mut d = quad16.clone();
        d.name = name.to_string();
        roots.push(sim.spawn_robot(&d).unwrap());
    }
    let other = sim.spawn_robot(&pendulum()).unwrap();
    let model = |sim: &Simulation, e: Entity| sim.robot(e).unwrap().model.clone();
    let a = model(&sim, roots[0]);
    assert!(Arc::ptr_eq(&a, &model(&sim, roots[1])));
    assert!(Arc::ptr_eq(&a, &model(&sim, roots[2])));
    assert!(!Arc::ptr_eq(&a, &model(&sim, other)));
    assert_eq!(
        sim.world.resource::<quadsim_systems::SharedModels>().len(),
        2
    );
    for (root, name) in roots.iter().zip(["a", "b", "c"]) {
        assert_eq!(
            sim.world
                .get::<quadsim_components::Robot>(*root)
                .unwrap()
                .name,
            name
        );
    }
    // Editing one robot's torso mass gives it its own model; the others keep theirs.
    let torso = robot_link(&mut sim, roots[1], "torso");
    let mass_kg = sim.world.get::<Mass>(torso).unwrap().0;
    sim.world.entity_mut(torso).insert(Mass(mass_kg + 1.0));
    sim.compile();
    let b = model(&sim, roots[1]);
    assert!(!Arc::ptr_eq(&a, &b));
    assert_eq!(b.total_mass, a.total_mass + 1.0);
    assert!(Arc::ptr_eq(&a, &model(&sim, roots[2])));
    drop(b);
    // Setting it back shares the first model again.
    sim.world.entity_mut(torso).insert(Mass(mass_kg));
    sim.compile();
    assert!(Arc::ptr_eq(&a, &model(&sim, roots[1])));
    assert_eq!(
        sim.world.resource::<quadsim_systems::SharedModels>().len(),
        2
    );
}

/// The compile stage learns of part edits from insert observers (the
/// description components are immutable): a joint edit, a shape edit and a
/// shape's despawn each recompile their own robot, and only it.
#[test]
fn joint_and_shape_edits_recompile_only_their_robot() {
    use quadsim_components::{Collider, ColliderOf, JointDamping};
    use quadsim_engine::description::Geometry;

    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let a = sim.spawn_robot(&pendulum()).unwrap();
    let b = sim.spawn_robot(&pendulum()).unwrap();
    sim.run(2);
    let m0 = sim.robot(b).unwrap().model.clone();
    assert!(Arc::ptr_eq(&sim.robot(a).unwrap().model, &m0));

    // a joint edit on robot a
    let elbow_a = robot_joint(&mut sim, a, "elbow");
    sim.world.entity_mut(elbow_a).insert(JointDamping(0.3));
    sim.step();
    let ma = sim.robot(a).unwrap().model.clone();
    assert!(ma.damping.contains(&0.3));
    assert!(Arc::ptr_eq(&sim.robot(b).unwrap().model, &m0));

    // robot b's base box doubled: its derived inertia grows
    let base_b = robot_link(&mut sim, b, "base");
    let mut colliders = sim.world.query::<(Entity, &ColliderOf)>();
    let collider_b = colliders
        .iter(&sim.world)
        .find(|(_, c)| c.0 == base_b)
        .unwrap()
        .0;
    sim.world
        .entity_mut(collider_b)
        .insert(Collider::new(Geometry {
            origin: Transform::IDENTITY,
            shape: Shape::Box {
                size_m: DVec3::new(0.8, 0.4, 0.2),
            },
        }));
    sim.step();
    let mb = sim.robot(b).unwrap().model.clone();
    assert!(mb.inertia[0].inertia_com.x_axis.x > 3.9 * m0.inertia[0].inertia_com.x_axis.x);
    assert!(Arc::ptr_eq(&sim.robot(a).unwrap().model, &ma));

    // its collider despawned: the inertia comes from the visual box again
    sim.world.despawn(collider_b);
    sim.step();
    let mb2 = sim.robot(b).unwrap().model.clone();
    assert!(!Arc::ptr_eq(&mb2, &mb));
    assert_eq!(mb2.inertia, m0.inertia);
    assert!(Arc::ptr_eq(&sim.robot(a).unwrap().model, &ma));
}

/// [`Simulation::step`] skips the compile schedule when its gate sees
/// nothing to do: after a few idle steps (gate closed), every kind of edit
/// made between two steps is still compiled before the next step: a root
/// component changed in place, an optional part component removed, the
/// configuration changed, a robot despawned, the default ground changed, a
/// robot's contact model pointed elsewhere.
#[test]
fn edits_between_idle_steps_are_compiled_by_the_next_step() {
    use quadsim_components::{DefaultGroundPlane, Ground, RobotBase, RobotBatch};
    use quadsim_systems::CompileGate;

    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let root = sim.spawn_robot(&pendulum()).unwrap();
    let other = sim.spawn_robot(&pendulum()).unwrap();
    // a second gate on the same world, to see what the simulation's sees
    let mut gate = CompileGate::new(&mut sim.world);
    assert!(gate.due(&sim.world), "everything is new to a new gate");
    sim.run(3);
    assert!(!gate.due(&sim.world), "idle steps leave nothing to compile");
    let idle = |sim: &mut Simulation, gate: &mut CompileGate| {
        sim.run(3);
        assert!(!gate.due(&sim.world));
    };

    // a root component changed in place (change detection only)
    assert_eq!(sim.robot(root).unwrap().model.nq, 9);
    sim.world.get_mut::<RobotBase>(root).unwrap().0 = BaseKind::Fixed;
    assert!(gate.due(&sim.world));
    sim.step();
    assert_eq!(sim.robot(root).unwrap().model.nq, 2);
    idle(&mut sim, &mut gate);

    // an optional part component removed (observer)
    let upper = robot_link(&mut sim, root, "upper");
    assert_ne!(
        sim.world.get::<ComputedInertia>(upper).unwrap().0,
        DMat3::ZERO
    );
    sim.world.entity_mut(upper).remove::<Inertia>();
    assert!(gate.due(&sim.world));
    sim.step();
    assert_eq!(
        sim.world.get::<ComputedInertia>(upper).unwrap().0,
        DMat3::ZERO
    );
    idle(&mut sim, &mut gate);

    // the configuration changed
    sim.world.resource_mut::<SimConfig>().gravity = DVec3::new(0.0, 0.0, -3.7);
    assert!(gate.due(&sim.world));
    sim.step();
    assert_eq!(sim.robot(root).unwrap().model.gravity.z, -3.7);
    idle(&mut sim, &mut gate);

    // the default ground changed: rebuilt and handed to every robot
    let ground = sim.world.resource::<Ground>().0.clone();
    sim.world.resource_mut::<DefaultGroundPlane>().set_changed();
    assert!(gate.due(&sim.world));
    sim.step();
    let rebuilt = sim.world.resource::<Ground>().0.clone();
    assert!(!Arc::ptr_eq(&ground, &rebuilt));
    assert!(Arc::ptr_eq(
        &sim.robot(other).unwrap().contact.terrain,
        &rebuilt
    ));
    idle(&mut sim, &mut gate);

    // a robot's contact model pointed elsewhere: back on the world's ground
    sim.robot_mut(other).unwrap().contact.terrain = ground.clone();
    assert!(gate.due(&sim.world));
    sim.step();
    assert!(Arc::ptr_eq(
        &sim.robot(other).unwrap().contact.terrain,
        &rebuilt
    ));
    idle(&mut sim, &mut gate);

    // a robot despawned: its slot dropped, the other renumbered
    sim.world.despawn(root);
    assert!(gate.due(&sim.world));
    sim.step();
    assert_eq!(sim.world.resource::<RobotBatch>().sims.len(), 1);
    assert_eq!(sim.world.get::<RobotIndex>(other), Some(&RobotIndex(0)));
    idle(&mut sim, &mut gate);
}
