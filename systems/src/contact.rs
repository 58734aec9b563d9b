//! The `Contact` stage: once per step, at the state the step starts from,
//! update every contact's persistent state (touchdown anchors, slip, force)
//! and record what the robot looks like (the [`Observation`](quadsim_components::Observation) that controllers,
//! fall detection and metrics read).

use bevy_ecs::prelude::*;
use glam::DVec3;
use quadsim_components::{RobotBatch, RobotSim, SimClock, SimThreadPool};
use quadsim_engine::Data;
use quadsim_engine::contact::{ContactKind, update_after_step};
use quadsim_engine::dispatch::com_and_velocity_by_legs;
use quadsim_engine::dispatch::forward_kinematics;
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

/// One robot: kinematics at `(q, v)`, contact update (unless the `Sense` stage did it,
/// [`RobotSensing::contacts_at_state`](quadsim_components::RobotSensing::contacts_at_state)),
/// observation, fall check.
pub fn observe_robot(sim: &mut RobotSim, t_s: f64) {
    let RobotSim {
        model,
        data,
        state,
        contact,
        run,
        sensing,
        ..
    } = sim;
    // On sensor steps the `Sense` stage computed these kinematics (a hit
    // of `data`'s kinematics cache, unless a controller used `data` since)
    // and updated the contacts at this state.
    let updated = sensing
        .as_deref_mut()
        .is_some_and(|s| std::mem::take(&mut s.contacts_at_state));
    forward_kinematics(model, data, &state.q, &state.v);
    if !updated {
        update_after_step(&contact.points, data, &contact.terrain, &mut contact.states);
    }
    contact.time_s = t_s;
    let obs = &mut run.observation;
    obs.t_s = t_s;
    obs.base = data.pose[0];
    (obs.com_m, obs.com_velocity_mps) = com_and_velocity_by_legs(model, data);
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
    // slices of one length: no bounds checks in the loop
    let n = obs.feet.len();
    let feet = contact.points[..n].iter().zip(&contact.states[..n]);
    for (foot, (p, s)) in obs.feet.iter_mut().zip(feet) {
        // The update above queried the terrain at this very centre.
        let centre = s.last_query.as_ref().map_or_else(
            || data.body_point_world(p.body, p.point_in_body),
            |q| q.centre_m,
        );
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
        || any_point_in_ground(&contact.terrain, data, &run.fall.body_points);
    obs.fallen = body_touch
        || tilted(obs.base.rot.z_axis.z, run.fall.max_tilt_rad)
        || obs.base_height_above_ground_m < run.fall.min_base_height_m;
}

/// Whether one of the body points (body index, point in the body frame) is
/// at or below the terrain: its closest surface point's depth is ≥ 0.
fn any_point_in_ground(terrain: &TerrainUnion, data: &Data, points: &[(usize, DVec3)]) -> bool {
    points.iter().any(|&(b, p)| {
        terrain
            .closest(data.body_point_world(b, p))
            .is_some_and(|sp| sp.depth_m >= 0.0)
    })
}

/// The tilt test `acos(z) > max_tilt_rad`, with `z` the world z component
/// of the base's z axis (clamped to [−1, 1]).
///
/// When `max_tilt_rad` is at least π/3 − 10⁻⁶ rad (just under the default
/// 60°) and `z ≥ 0.5 + 10⁻⁶`, the answer is false without the acos (one
/// per robot and step otherwise): acos is decreasing and acos(0.5 + 10⁻⁶)
/// = 1.0471964 rad, below that limit by 1.5·10⁻⁷ rad, some 10⁸ times the
/// error of the library's acos (< 1 ulp), so the computed acos is below
/// the limit too, and the answer is the same. Any other `z` (NaN
/// included) or limit takes the exact test.
fn tilted(z: f64, max_tilt_rad: f64) -> bool {
    const FAST_FROM_RAD: f64 = std::f64::consts::FRAC_PI_3 - 1e-6;
    if max_tilt_rad >= FAST_FROM_RAD && z >= 0.5 + 1e-6 {
        return false;
    }
    z.clamp(-1.0, 1.0).acos() > max_tilt_rad
}
