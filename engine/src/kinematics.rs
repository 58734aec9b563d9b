//! Forward kinematics: body poses, motion subspaces, velocities and inertias in
//! the reference frame (Featherstone 2008, §4.1 and §7.3 for the fixed-frame form).

use crate::data::Data;
use crate::model::{JointType, Model, PoseStep};
use crate::spatial::{Motion, RigidInertia, Transform};
use glam::{DMat3, DQuat, DVec3};
use multiversion::multiversion;

/// Base orientation from `q[3..7] = [qx, qy, qz, qw]` (assumed unit).
#[inline]
pub fn base_quat(q: &[f64]) -> DQuat {
    DQuat::from_xyzw(q[3], q[4], q[5], q[6])
}

/// Joint motion of a 1-DOF joint at position `qi`, in the joint frame.
#[inline]
fn joint_transform(jt: JointType, axis: DVec3, qi: f64) -> Transform {
    match jt {
        JointType::Revolute => {
            Transform::new(crate::trig::mat3_from_axis_angle(axis, qi), DVec3::ZERO)
        }
        JointType::Prismatic => Transform::from_translation(axis * qi),
        JointType::Free | JointType::Anchored => Transform::IDENTITY,
    }
}

/// Poses only (no velocities): fills `pose`, `s`, `inertia_ref`
/// (not in a kinematics-only [`Data`]) and sets `origin`.
///
/// After this call, [`Data::origin`] is the base origin and every spatial
/// quantity refers to it. The scalar path, whatever the model's plan
/// ([`crate::dispatch::forward_kinematics_pos`] picks the plan's kernel).
pub fn forward_kinematics_pos(model: &Model, data: &mut Data, q: &[f64]) {
    debug_assert_eq!(q.len(), model.nq);
    data.invalidate_kinematics();
    poses(model, data, q, None);
}

/// Body poses, motion subspaces and inertias in the reference frame and,
/// with `v`, velocities, in one pass from the base to the leaves.
///
/// Compiled for x86-64-v3 (AVX2, FMA) and the generic target; the CPU picks
/// one at the first call. The results are the same bits either way: Rust
/// never fuses `a * b + c`, so the wider target only saves register moves
/// (three-operand instructions) and packs independent operations.
#[multiversion(targets("x86_64+avx2+fma"))]
fn poses(model: &Model, data: &mut Data, q: &[f64], v: Option<&[f64]>) {
    base_kinematics(model, data, q, v);
    body_kinematics(model, data, q, v);
}

/// The base's part of forward kinematics: `origin`, `pose[0]`,
/// `inertia_ref[0]` (with the dynamics arrays) and, with `v`, `vel[0]`.
#[inline(always)]
pub(crate) fn base_kinematics(model: &Model, data: &mut Data, q: &[f64], v: Option<&[f64]>) {
    let base = base_pose(model, q);
    data.origin = base.trans;
    data.pose[0] = base;
    let step = &model.pose_step[..model.nbodies];
    let base_rot = Transform::new(base.rot, DVec3::ZERO);
    // (a kinematics-only `Data` has no reference inertias)
    if let Some(ir) = data.inertia_ref.first_mut() {
        *ir = rigid_inertia_in(&model.inertia[0], step[0], &base_rot);
    }
    if let Some(v) = v {
        data.vel[0] = base_velocity_at(model, base.rot, v);
    }
}

/// Every body but the base, parents first (after [`base_kinematics`]):
/// `pose`, `s`, `inertia_ref` (with the dynamics arrays) and, with `v`,
/// `vel` (Featherstone 2008, §4.1; the fixed-frame form of §7.3).
#[inline(always)]
pub(crate) fn body_kinematics(model: &Model, data: &mut Data, q: &[f64], v: Option<&[f64]>) {
    let n = model.nbodies;
    let origin = data.origin;
    let step = &model.pose_step[..n];
    // Slices of known length up front, so that the loop indexes without
    // bounds checks (the body arrays all have `n` entries, `parent[i] < i`).
    let (parent, idx_q, idx_v) = (&model.parent[..n], &model.idx_q[..n], &model.idx_v[..n]);
    let (joint_type, axis_all) = (&model.joint_type[..n], &model.axis[..n]);
    let (placement, inertia) = (&model.placement[..n], &model.inertia[..n]);
    let pose = &mut data.pose[..n];
    let s_all = &mut data.s[..n];
    let mut inertia_ref = (!data.inertia_ref.is_empty()).then(|| &mut data.inertia_ref[..n]);
    let vel = &mut data.vel[..n];
    for &i in &model.depth_order {
        let p = parent[i];
        let jt = joint_type[i];
        let st = step[i];
        let xp = pose[p];
        let pl = &placement[i];
        // The joint frame: parent pose ∘ placement, skipping the products
        // with an identity rotation or a zero translation.
        let rot_j = if st.placement_rotates {
            xp.rot * pl.rot
        } else {
            xp.rot
        };
        let trans_j = if st.placement_translates {
            xp.rot * pl.trans + xp.trans
        } else {
            xp.trans
        };
        let qi = q[idx_q[i]];
        // World axis: a joint's own motion leaves its axis fixed, so it is
        // the joint frame's axis.
        let (x, aw) = match st.aligned_axis {
            Some((k, sign)) => {
                let col = rot_j.col(k);
                (
                    Transform::new(rotate_about_axis(rot_j, k, sign * qi), trans_j),
                    if sign > 0.0 { col } else { -col },
                )
            }
            None => (
                Transform::new(rot_j, trans_j).compose(&joint_transform(jt, axis_all[i], qi)),
                rot_j * axis_all[i],
            ),
        };
        pose[i] = x;
        let r = x.trans - origin;
        let s = match jt {
            JointType::Revolute => Motion::new(r.cross(aw), aw),
            _ => Motion::new(aw, DVec3::ZERO),
        };
        s_all[i] = s;
        if let Some(ir) = inertia_ref.as_deref_mut() {
            ir[i] = rigid_inertia_in(&inertia[i], st, &Transform::new(x.rot, r));
        }
        if let Some(v) = v {
            vel[i] = vel[p] + s * v[idx_v[i]];
        }
    }
}

/// The base's pose from `q` (the identity for a fixed base).
#[inline(always)]
pub(crate) fn base_pose(model: &Model, q: &[f64]) -> Transform {
    match model.joint_type[0] {
        JointType::Free => {
            let r = DMat3::from_quat(base_quat(q));
            Transform::new(r, DVec3::new(q[0], q[1], q[2]))
        }
        _ => Transform::IDENTITY,
    }
}

/// A body's inertia seen through `x`, by the shortcut its [`PoseStep`] allows.
#[inline(always)]
fn rigid_inertia_in(inertia: &RigidInertia, step: PoseStep, x: &Transform) -> RigidInertia {
    if crate::model::DIAGONAL_INERTIA_SHORTCUT && step.inertia_diagonal {
        inertia.transformed_diagonal(x)
    } else {
        inertia.transformed(x)
    }
}

/// `rot · R_k(angle)`, where `R_k` turns about the k-th unit axis: only the
/// two columns across the axis change (12 products instead of 27, and no
/// axis–angle matrix).
/// One arm per axis, so that no column is picked by a run-time index.
#[inline(always)]
fn rotate_about_axis(rot: DMat3, k: usize, angle: f64) -> DMat3 {
    let (s, c) = crate::trig::kinematics_sin_cos(angle);
    let (x, y, z) = (rot.x_axis, rot.y_axis, rot.z_axis);
    match k {
        0 => DMat3::from_cols(x, y * c + z * s, z * c - y * s),
        1 => DMat3::from_cols(x * c - z * s, y, z * c + x * s),
        _ => DMat3::from_cols(x * c + y * s, y * c - x * s, z),
    }
}

/// Poses and velocities: [`forward_kinematics_pos`] plus `vel` (reference
/// frame). The scalar path ([`crate::dispatch::forward_kinematics`] picks
/// the plan's kernel and skips a repeated call at the same state).
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) {
    debug_assert_eq!(q.len(), model.nq);
    debug_assert_eq!(v.len(), model.nv);
    data.invalidate_kinematics();
    poses(model, data, q, Some(v));
}

/// Velocities only, after the poses at the same `q`: `vel` from `v` and the
/// subspaces already in `data`.
#[inline]
pub(crate) fn body_velocities(model: &Model, data: &mut Data, v: &[f64]) {
    data.vel[0] = base_velocity(model, data, v);
    for i in 1..model.nbodies {
        data.vel[i] = data.vel[model.parent[i]] + data.subspace(model, i) * v[model.idx_v[i]];
    }
}

/// The base's spatial velocity in the reference frame from `v[0..6]` (zero for a fixed base).
#[inline]
pub fn base_velocity(model: &Model, data: &Data, v: &[f64]) -> Motion {
    base_velocity_at(model, data.pose[0].rot, v)
}

/// [`base_velocity`] with the base's orientation `r`.
#[inline]
pub(crate) fn base_velocity_at(model: &Model, r: DMat3, v: &[f64]) -> Motion {
    if model.joint_type[0] == JointType::Free {
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
    use crate::model::aligned_axis;

    #[test]
    fn axis_aligned_fast_path_matches_axis_angle_rotation() {
        // every signed unit axis and one oblique axis, behind a rotated placement
        let axes = [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
            DVec3::new(1.0, 2.0, -0.5).normalize(),
        ];
        let parent = Transform::new(
            DMat3::from_euler(glam::EulerRot::ZYX, 0.3, -0.7, 1.1),
            DVec3::new(0.1, -0.2, 0.3),
        );
        for axis in axes {
            for angle in [-2.5, -0.4, 0.0, 0.9, 3.0] {
                let fast = match aligned_axis(axis) {
                    Some((k, sign)) => rotate_about_axis(parent.rot, k, sign * angle),
                    None => continue,
                };
                let slow = parent.rot * DMat3::from_axis_angle(axis, angle);
                assert!(
                    (fast - slow)
                        .to_cols_array()
                        .iter()
                        .all(|e| e.abs() < 1e-15),
                    "axis {axis} angle {angle}"
                );
            }
        }
        assert_eq!(aligned_axis(axes[6]), None);
    }

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

    /// Forward kinematics at the same `q` and another `v` updates only the
    /// velocities; whatever reads them afterwards (ABA in the legs' lanes,
    /// which reads the lane cache's velocities on an AVX2 CPU, and the
    /// observation's CoM velocity) gives a fresh `Data`'s bits.
    #[test]
    fn velocities_only_update_gives_a_fresh_evaluations_bits() {
        let desc = crate::robots::builtin("quad16").unwrap();
        let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let mut q = crate::robots::nominal_q("quad16").unwrap();
        q[0] = 0.2;
        let v1: Vec<f64> = (0..model.nv).map(|i| (i as f64 * 0.7).sin()).collect();
        let v2: Vec<f64> = (0..model.nv).map(|i| (i as f64 * 1.3).cos()).collect();
        let tau: Vec<f64> = (0..model.nv)
            .map(|i| (i as f64 * 0.4).sin() * 3.0)
            .collect();
        let mut reused = Data::new(&model);
        forward_kinematics(&model, &mut reused, &q, &v1);
        forward_kinematics(&model, &mut reused, &q, &v2);
        let mut fresh = Data::new(&model);
        forward_kinematics(&model, &mut fresh, &q, &v2);
        let c = |d: &Data| crate::com::com_and_velocity_by_legs(&model, d);
        assert_eq!(c(&reused).1.to_array(), c(&fresh).1.to_array());
        let a_reused = crate::aba::aba(&model, &mut reused, &q, &v2, &tau).to_vec();
        let a_fresh = crate::aba::aba(&model, &mut fresh, &q, &v2, &tau).to_vec();
        assert_eq!(a_reused, a_fresh);
    }
}
