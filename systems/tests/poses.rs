//! Link poses copied back from the packed state: equal to the engine's frame
//! poses and to an independent walk down the description, at the chosen rate.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use bevy_ecs::prelude::*;
use glam::{DMat3, DQuat, DVec3};
use quadsim_components::{BelongsTo, Link, LinkPose, PoseSync, SimConfig};
use quadsim_engine::Data;
use quadsim_engine::description::{JointKind, RobotDescription};
use quadsim_engine::integrate::State;
use quadsim_engine::kinematics::{forward_kinematics_pos, frame_pose};
use quadsim_engine::spatial::Transform;
use quadsim_systems::Simulation;

/// World pose of every link of a floating robot at `q`, composing joint
/// placements and joint motions straight from the description (no model).
fn reference_poses(desc: &RobotDescription, q: &[f64]) -> Vec<(String, Transform)> {
    let base = Transform::new(
        DMat3::from_quat(DQuat::from_xyzw(q[3], q[4], q[5], q[6])),
        DVec3::new(q[0], q[1], q[2]),
    );
    let mut poses = vec![(desc.root_link().unwrap().name.clone(), base)];
    let mut rank = 0;
    let q_of: Vec<Option<f64>> = desc
        .joints
        .iter()
        .map(|j| {
            j.is_movable().then(|| {
                rank += 1;
                q[7 + rank - 1]
            })
        })
        .collect();
    while poses.len() < desc.links.len() {
        for (j, qj) in desc.joints.iter().zip(&q_of) {
            if poses.iter().any(|(n, _)| *n == j.child) {
                continue;
            }
            let Some(&(_, parent)) = poses.iter().find(|(n, _)| *n == j.parent) else {
                continue;
            };
            let motion = match j.kind {
                JointKind::Revolute { axis } => Transform::new(
                    DMat3::from_axis_angle(axis.normalize(), qj.unwrap()),
                    DVec3::ZERO,
                ),
                JointKind::Prismatic { axis } => {
                    Transform::from_translation(axis.normalize() * qj.unwrap())
                }
                JointKind::Fixed => Transform::IDENTITY,
            };
            poses.push((
                j.child.clone(),
                parent.compose(&j.placement).compose(&motion),
            ));
        }
    }
    poses
}

fn link_poses(sim: &mut Simulation, root: Entity) -> Vec<(String, Transform)> {
    let mut q = sim.world.query::<(&Link, &LinkPose, &BelongsTo)>();
    q.iter(&sim.world)
        .filter(|(_, _, b)| b.0 == root)
        .map(|(l, p, _)| (l.name.clone(), p.0))
        .collect()
}

fn spawn_moving(sim: &mut Simulation, seed: u64) -> (Entity, RobotDescription) {
    let desc = common::random_tree(seed, 10);
    let root = sim.spawn_robot(&desc).unwrap();
    let r = sim.robot_mut(root).unwrap();
    let (q, v) = common::random_state(&r.model, seed + 50, 2.0, 1.0);
    r.state = State { q, v };
    (root, desc)
}

#[test]
fn copied_poses_equal_engine_frame_poses() {
    let mut sim = Simulation::new(SimConfig::default(), 2).unwrap();
    let robots: Vec<_> = (0..4).map(|s| spawn_moving(&mut sim, s)).collect();
    sim.run(50);
    for (root, desc) in &robots {
        let r = sim.robot(*root).unwrap();
        let (model, q) = (r.model.clone(), r.state.q.clone());
        let mut data = Data::new(&model);
        forward_kinematics_pos(&model, &mut data, &q);
        let reference = reference_poses(desc, &q);
        let copied = link_poses(&mut sim, *root);
        assert_eq!(copied.len(), desc.links.len());
        for (name, pose) in copied {
            let engine = frame_pose(&model, &data, model.frame_index(&name).unwrap());
            assert_eq!(pose, engine, "link {name}");
            let (_, walk) = reference.iter().find(|(n, _)| *n == name).unwrap();
            let err = (pose.trans - walk.trans).length()
                + (pose.rot - walk.rot)
                    .abs()
                    .to_cols_array()
                    .iter()
                    .sum::<f64>();
            assert!(err < 1e-12, "link {name}: {err}");
        }
    }
}

#[test]
fn poses_are_copied_at_the_chosen_rate_or_on_request() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    let (root, _) = spawn_moving(&mut sim, 9);
    *sim.world.resource_mut::<PoseSync>() = PoseSync {
        every_steps: 5,
        requested: false,
    };
    sim.run(5);
    let at5 = link_poses(&mut sim, root);
    assert!(at5.iter().any(|(_, p)| *p != Transform::IDENTITY));
    sim.run(4);
    assert_eq!(
        link_poses(&mut sim, root),
        at5,
        "copied between rate points"
    );
    sim.run(1);
    let at10 = link_poses(&mut sim, root);
    assert_ne!(at10, at5);

    // rate 0: only on request, and the request is served once
    sim.world.resource_mut::<PoseSync>().every_steps = 0;
    sim.run(3);
    assert_eq!(link_poses(&mut sim, root), at10);
    sim.world.resource_mut::<PoseSync>().requested = true;
    sim.run(1);
    let requested = link_poses(&mut sim, root);
    assert_ne!(requested, at10);
    assert!(!sim.world.resource::<PoseSync>().requested);
    sim.run(1);
    assert_eq!(link_poses(&mut sim, root), requested);

    // immediate copy, outside the schedule
    sim.sync_link_poses();
    assert_ne!(link_poses(&mut sim, root), requested);
}
