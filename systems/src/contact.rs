//! The `Contact` stage: once per step, at the state the step starts from,
//! update every contact's persistent state (touchdown anchors, slip, force)
//! and record what the robot looks like (the [`Observation`](quadsim_components::Observation) that controllers,
//! fall detection and metrics read).

use bevy_ecs::prelude::*;
use glam::DVec3;
use quadsim_components::{RobotBatch, RobotSim, SimClock, SimThreadPool};
use quadsim_engine::com::{center_of_mass, com_velocity};
use quadsim_engine::contact::{ContactKind, update_after_step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::metrics::FootSample;
use quadsim_engine::terrain::{Terrain as _, TerrainUnion};

/// Updates contacts and observations of every robot, in parallel: the
/// `Contact` stage over the whole herd as a system of its own (the step
/// schedule runs it inside [`step_robot_pass`](crate::step_robot_pass)).
pub fn update_contacts(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    clock: Res<SimClock>,
) {
    let t = clock.time_s;
    let sims = &mut batch.sims;
    pool.for_each(sims, |sim| observe_robot(sim, t));
}

/// Height of `p` above the ground beneath it (m); +∞ over no ground.
pub fn height_above_ground(terrain: &TerrainUnion, p: DVec3) -> f64 {
    terrain.height(p.x, p.y).map_or(f64::INFINITY, |h| p.z - h)
}

/// One robot: kinematics at `(q, v)`, contact update, observation, fall check.
pub fn observe_robot(sim: &mut RobotSim, t_s: f64) {
    let RobotSim {
        model,
        data,
        state,
        contact,
        run,
        ..
    } = sim;
    forward_kinematics(model, data, &state.q, &state.v);
    update_after_step(&contact.points, data, &contact.terrain, &mut contact.states);
    contact.time_s = t_s;
    let obs = &mut run.observation;
    obs.t_s = t_s;
    obs.base = data.pose[0];
    obs.com_m = center_of_mass(model, data);
    obs.com_velocity_mps = com_velocity(model, data);
    obs.base_height_above_ground_m = height_above_ground(&contact.terrain, obs.base.trans);
    obs.com_height_above_ground_m = height_above_ground(&contact.terrain, obs.com_m);
    // the actuated joints (compliant payloads' coordinates close q and v)
    let (nq0, nv0) = (model.base_nq(), model.base_nv());
    let (nq, nv) = (model.actuated_nq(), model.actuated_nv());
    obs.q_joints.clear();
    obs.q_joints.extend_from_slice(&state.q[nq0..nq]);
    obs.qd_joints.clear();
    obs.qd_joints.extend_from_slice(&state.v[nv0..nv]);
    obs.feet.resize(run.n_feet, FootSample::default());
    for (i, foot) in obs.feet.iter_mut().enumerate() {
        let (p, s) = (&contact.points[i], &contact.states[i]);
        let centre = data.body_point_world(p.body, p.point_in_body);
        *foot = FootSample {
            in_contact: s.in_contact,
            position_m: if s.in_contact {
                centre - s.normal * p.radius_m
            } else {
                centre - DVec3::Z * p.radius_m
            },
            force_n: s.force_n,
        };
    }
    // Falls: a knee or torso point touches the ground, the base tilts too far,
    // or it sinks below half its nominal height.
    let body_touch = contact
        .points
        .iter()
        .zip(&contact.states)
        .any(|(p, s)| s.in_contact && matches!(p.kind, ContactKind::Knee | ContactKind::Torso))
        || run.fall.body_points.iter().any(|&(b, p)| {
            let w = data.body_point_world(b, p);
            contact
                .terrain
                .closest(w)
                .is_some_and(|sp| sp.depth_m >= 0.0)
        });
    let tilt = obs.base.rot.z_axis.z.clamp(-1.0, 1.0).acos();
    obs.fallen = body_touch
        || tilt > run.fall.max_tilt_rad
        || obs.base_height_above_ground_m < run.fall.min_base_height_m;
}
