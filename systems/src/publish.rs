//! Publishing: copying the packed state back to link entities.

use bevy_ecs::prelude::*;
use quadsim_components::{FootContact, LinkPose, PoseSync, RobotBatch, SimClock, SimThreadPool};
use quadsim_engine::dispatch::forward_kinematics_pos;
use quadsim_engine::kinematics::frame_pose;

/// Run condition: poses are due after this step (rate or request, see [`PoseSync`]).
pub fn pose_sync_due(clock: Res<SimClock>, sync: Res<PoseSync>) -> bool {
    sync.due(clock.step)
}

/// Writes every link's world pose at the current state into its [`LinkPose`].
///
/// Kinematics run per robot in parallel (the integrator leaves `data` at its
/// last derivative evaluation, not at the new state); afterwards each robot's
/// `data` holds the kinematics of its current `q`. Foot links also get their
/// [`FootContact`] (the contact state as of the last `Contact` stage). Clears
/// a pending request.
pub fn sync_link_poses(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    mut sync: ResMut<PoseSync>,
    mut poses: Query<&mut LinkPose>,
    mut feet: Query<&mut FootContact>,
) {
    let sims = &mut batch.sims;
    pool.for_each(sims, |s| {
        forward_kinematics_pos(&s.model, &mut s.data, &s.state.q)
    });
    for sim in sims.iter() {
        for (i, &frame) in sim.model.feet.iter().enumerate() {
            let (Some(&link), Some(st)) = (sim.link_entities.get(frame), sim.contact.states.get(i))
            else {
                continue;
            };
            if let Ok(mut fc) = feet.get_mut(link) {
                *fc = FootContact {
                    in_contact: st.in_contact,
                    slipping: st.slipping,
                    penetration_m: st.penetration_m,
                    force_n: st.force_n,
                };
            }
        }
        for (frame, &link) in sim.link_entities.iter().enumerate() {
            if let Ok(mut pose) = poses.get_mut(link) {
                pose.0 = frame_pose(&sim.model, &sim.data, frame);
            }
        }
    }
    if sync.requested {
        sync.requested = false;
    }
}
