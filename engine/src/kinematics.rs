//! Forward kinematics: body poses, motion subspaces, velocities and inertias in
//! the reference frame (Featherstone 2008, §4.1 and §7.3 for the fixed-frame form).

use crate::data::Data;
use crate::model::{JointType, Model};
use crate::spatial::{Motion, Transform};
use glam::{DMat3, DQuat, DVec3};

/// Base orientation from `q[3..7] = [qx, qy, qz, qw]` (assumed unit).
#[inline]
pub fn base_quat(q: &[f64]) -> DQuat {
    DQuat::from_xyzw(q[3], q[4], q[5], q[6])
}

/// Joint motion of a 1-DOF joint at position `qi`, in the joint frame.
#[inline]
fn joint_transform(jt: JointType, axis: DVec3, qi: f64) -> Transform {
    match jt {
        JointType::Revolute => Transform::new(DMat3::from_axis_angle(axis, qi), DVec3::ZERO),
        JointType::Prismatic => Transform::from_translation(axis * qi),
        JointType::Free | JointType::Anchored => Transform::IDENTITY,
    }
}

/// Poses only (no velocities): fills `pose`, `s`, `s_base`, `inertia_ref` and sets `origin`.
///
/// After this call, [`Data::origin`] is the base origin and every spatial
/// quantity refers to it.
pub fn forward_kinematics_pos(model: &Model, data: &mut Data, q: &[f64]) {
    debug_assert_eq!(q.len(), model.nq);
    let base = match model.joint_type[0] {
        JointType::Free => {
            let r = DMat3::from_quat(base_quat(q));
            Transform::new(r, DVec3::new(q[0], q[1], q[2]))
        }
        _ => Transform::IDENTITY,
    };
    data.origin = base.trans;
    data.pose[0] = base;
    if model.joint_type[0] == JointType::Free {
        let r = base.rot;
        for k in 0..3 {
            data.s_base[k] = Motion::new(r.col(k), DVec3::ZERO);
            data.s_base[k + 3] = Motion::new(DVec3::ZERO, r.col(k));
        }
    }
    data.inertia_ref[0] = model.inertia[0].transformed(&Transform::new(base.rot, DVec3::ZERO));
    for i in 1..model.nbodies {
        let p = model.parent[i];
        let jt = model.joint_type[i];
        let axis = model.axis[i];
        let x = data.pose[p]
            .compose(&model.placement[i])
            .compose(&joint_transform(jt, axis, q[model.idx_q[i]]));
        data.pose[i] = x;
        let aw = x.rot * axis;
        let r = x.trans - data.origin;
        data.s[i] = match jt {
            JointType::Revolute => Motion::new(r.cross(aw), aw),
            _ => Motion::new(aw, DVec3::ZERO),
        };
        data.inertia_ref[i] = model.inertia[i].transformed(&Transform::new(x.rot, r));
    }
}

/// Poses and velocities: [`forward_kinematics_pos`] plus `vel` (reference frame).
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) {
    debug_assert_eq!(v.len(), model.nv);
    forward_kinematics_pos(model, data, q);
    data.vel[0] = base_velocity(model, data, v);
    for i in 1..model.nbodies {
        data.vel[i] = data.vel[model.parent[i]] + data.s[i] * v[model.idx_v[i]];
    }
}

/// The base's spatial velocity in the reference frame from `v[0..6]` (zero for a fixed base).
#[inline]
pub fn base_velocity(model: &Model, data: &Data, v: &[f64]) -> Motion {
    if model.joint_type[0] == JointType::Free {
        let r = data.pose[0].rot;
        Motion::new(
            r * DVec3::new(v[0], v[1], v[2]),
            r * DVec3::new(v[3], v[4], v[5]),
        )
    } else {
        Motion::ZERO
    }
}

/// World placement of a frame (link), after kinematics.
#[inline]
pub fn frame_pose(model: &Model, data: &Data, frame: usize) -> Transform {
    let f = &model.frames[frame];
    data.pose[f.body].compose(&f.placement)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::RobotBuilder;
    use crate::model::BaseKind;

    #[test]
    fn two_link_arm_tip_position() {
        // planar arm in the x-z plane, joints about y
        let d = RobotBuilder::new("arm")
            .link("base")
            .mass(1.0)
            .done()
            .link("l1")
            .mass(1.0)
            .done()
            .link("l2")
            .mass(1.0)
            .done()
            .revolute("j1", "base", "l1", DVec3::ZERO, DVec3::Y)
            .revolute("j2", "l1", "l2", DVec3::new(1.0, 0.0, 0.0), DVec3::Y)
            .build();
        let m = Model::from_description(&d, BaseKind::Fixed).unwrap();
        let mut data = Data::new(&m);
        let q = [0.3, -0.8];
        forward_kinematics(&m, &mut data, &q, &[0.0, 0.0]);
        let tip = data.body_point_world(2, DVec3::new(0.5, 0.0, 0.0));
        // rotation about +y by θ maps x̂ to (cos θ, 0, −sin θ)
        let a1 = q[0];
        let a2 = q[0] + q[1];
        let expect = DVec3::new(a1.cos() + 0.5 * a2.cos(), 0.0, -(a1.sin() + 0.5 * a2.sin()));
        assert!((tip - expect).length() < 1e-14, "{tip} vs {expect}");
    }
}
