//! Forward kinematics across robots: [`crate::kinematics::forward_kinematics`]
//! with one lane per robot (poses, motion subspaces, velocities and inertias
//! in each robot's reference frame), operation for operation.

use super::BatchData;
use super::lanes::{LMat3, LVec3, Lanes};
use super::spatial::{LInertia, LMotion, LTransform};
use crate::model::{JointType, Model, PoseStep};
use crate::spatial::RigidInertia;
use glam::{DMat3, DVec3};
use multiversion::multiversion;

/// Poses and velocities of every active lane from `bd.q` and `bd.v`: fills
/// `origin`, `pose`, `s`, `inertia_ref` and `vel` of `bd` (the free base's
/// subspace, [`crate::Data::base_subspace`], is not needed by ABA).
///
/// Compiled for x86-64-v3 (AVX2) and the generic target; the CPU picks one
/// at run time (see [the module doc](super)).
///
/// # Panics
/// If `bd` was sized for a model of other sizes.
pub fn forward_kinematics_batch<const L: usize>(model: &Model, bd: &mut BatchData<L>) {
    bd.check_model(model);
    fk_dispatch(model, bd);
}

#[multiversion(targets("x86_64+avx2+fma"))]
fn fk_dispatch<const L: usize>(model: &Model, bd: &mut BatchData<L>) {
    forward_kinematics_lanes(model, bd);
}

/// The body of [`forward_kinematics_batch`], inlined into each CPU version.
#[inline(always)]
pub(super) fn forward_kinematics_lanes<const L: usize>(model: &Model, bd: &mut BatchData<L>) {
    poses(model, bd);
}

/// glam's `DMat3::from_quat(DQuat::from_xyzw(q[3], q[4], q[5], q[6]))` per lane.
#[inline(always)]
fn base_rotation<const L: usize>(q: &[Lanes<L>]) -> LMat3<L> {
    let (x, y, z, w) = (q[3], q[4], q[5], q[6]);
    let one = Lanes::splat(1.0);
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, xy, xz) = (x * x2, x * y2, x * z2);
    let (yy, yz, zz) = (y * y2, y * z2, z * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    LMat3::from_cols(
        LVec3::new(one - (yy + zz), xy + wz, xz - wy),
        LVec3::new(xy - wz, one - (xx + zz), yz + wx),
        LVec3::new(xz + wy, yz - wx, one - (xx + yy)),
    )
}

/// [`crate::trig::mat3_from_axis_angle`] (glam's `DMat3::from_axis_angle`) with one angle per lane.
#[inline(always)]
fn axis_angle<const L: usize>(axis: DVec3, angle: Lanes<L>) -> LMat3<L> {
    let (sin, cos) = angle.sin_cos();
    let sp = Lanes::splat;
    let (xsin, ysin, zsin) = (sp(axis.x) * sin, sp(axis.y) * sin, sp(axis.z) * sin);
    let (x, y, z) = (axis.x, axis.y, axis.z);
    let (x2, y2, z2) = (sp(x * x), sp(y * y), sp(z * z));
    let omc = sp(1.0) - cos;
    let xyomc = sp(x * y) * omc;
    let xzomc = sp(x * z) * omc;
    let yzomc = sp(y * z) * omc;
    LMat3::from_cols(
        LVec3::new(x2 * omc + cos, xyomc + zsin, xzomc - ysin),
        LVec3::new(xyomc - zsin, y2 * omc + cos, yzomc + xsin),
        LVec3::new(xzomc + ysin, yzomc - xsin, z2 * omc + cos),
    )
}

/// `rot · R_k(angle)` as in the scalar fast path: only the two columns across axis `k` change.
#[inline(always)]
fn rotate_about_axis<const L: usize>(rot: LMat3<L>, k: usize, angle: Lanes<L>) -> LMat3<L> {
    let (s, c) = angle.sin_cos();
    let (x, y, z) = (rot.x_axis, rot.y_axis, rot.z_axis);
    match k {
        0 => LMat3::from_cols(x, y * c + z * s, z * c - y * s),
        1 => LMat3::from_cols(x * c - z * s, y, z * c + x * s),
        _ => LMat3::from_cols(x * c + y * s, y * c - x * s, z),
    }
}

/// The joint's own motion at `qi` in the joint frame (the scalar `joint_transform`).
#[inline(always)]
fn joint_transform<const L: usize>(jt: JointType, axis: DVec3, qi: Lanes<L>) -> LTransform<L> {
    match jt {
        JointType::Revolute => LTransform::new(axis_angle(axis, qi), LVec3::ZERO),
        JointType::Prismatic => LTransform::new(
            LMat3::splat(DMat3::IDENTITY),
            LVec3::new(
                Lanes::splat(axis.x) * qi,
                Lanes::splat(axis.y) * qi,
                Lanes::splat(axis.z) * qi,
            ),
        ),
        JointType::Free | JointType::Anchored => {
            LTransform::new(LMat3::splat(DMat3::IDENTITY), LVec3::ZERO)
        }
    }
}

#[inline(always)]
fn poses<const L: usize>(model: &Model, bd: &mut BatchData<L>) {
    let base = match model.joint_type[0] {
        JointType::Free => {
            LTransform::new(base_rotation(&bd.q), LVec3::new(bd.q[0], bd.q[1], bd.q[2]))
        }
        _ => LTransform::new(LMat3::splat(DMat3::IDENTITY), LVec3::ZERO),
    };
    let n = model.nbodies;
    let origin = base.trans;
    bd.origin = origin;
    bd.pose[0] = base;
    let step = &model.pose_step[..n];
    let base_rot = LTransform::new(base.rot, LVec3::ZERO);
    bd.inertia_ref[0] = rigid_inertia_in(&model.inertia[0], step[0], &base_rot);
    bd.vel[0] = base_velocity(model, bd);
    let (parent, idx_q, idx_v) = (&model.parent[..n], &model.idx_q[..n], &model.idx_v[..n]);
    let (joint_type, axis_all) = (&model.joint_type[..n], &model.axis[..n]);
    let (placement, inertia) = (&model.placement[..n], &model.inertia[..n]);
    let (q, v) = (&bd.q[..], &bd.v[..]);
    let pose = &mut bd.pose[..n];
    let s_all = &mut bd.s[..n];
    let inertia_ref = &mut bd.inertia_ref[..n];
    let vel = &mut bd.vel[..n];
    for &i in &model.depth_order {
        let p = parent[i];
        let jt = joint_type[i];
        let st = step[i];
        let xp = pose[p];
        let pl = &placement[i];
        let rot_j = if st.placement_rotates {
            xp.rot * LMat3::splat(pl.rot)
        } else {
            xp.rot
        };
        let trans_j = if st.placement_translates {
            xp.rot * LVec3::splat(pl.trans) + xp.trans
        } else {
            xp.trans
        };
        let qi = q[idx_q[i]];
        let (x, aw) = match st.aligned_axis {
            Some((k, sign)) => {
                let col = rot_j.col(k);
                (
                    LTransform::new(
                        rotate_about_axis(rot_j, k, Lanes::splat(sign) * qi),
                        trans_j,
                    ),
                    if sign > 0.0 { col } else { -col },
                )
            }
            None => (
                LTransform::new(rot_j, trans_j).compose(&joint_transform(jt, axis_all[i], qi)),
                rot_j * LVec3::splat(axis_all[i]),
            ),
        };
        pose[i] = x;
        let r = x.trans - origin;
        let s = match jt {
            JointType::Revolute => LMotion::new(r.cross(aw), aw),
            _ => LMotion::new(aw, LVec3::ZERO),
        };
        s_all[i] = s;
        inertia_ref[i] = rigid_inertia_in(&inertia[i], st, &LTransform::new(x.rot, r));
        vel[i] = vel[p] + s * v[idx_v[i]];
    }
}

/// The scalar `rigid_inertia_in`: a body's inertia through `x`, by its shortcut.
#[inline(always)]
fn rigid_inertia_in<const L: usize>(
    inertia: &RigidInertia,
    step: PoseStep,
    x: &LTransform<L>,
) -> LInertia<L> {
    if crate::model::DIAGONAL_INERTIA_SHORTCUT && step.inertia_diagonal {
        LInertia::transformed_diagonal(inertia, x)
    } else {
        LInertia::transformed(inertia, x)
    }
}

/// The scalar `base_velocity` per lane: `[R v_lin; R ω]`, zero for a fixed base.
#[inline(always)]
fn base_velocity<const L: usize>(model: &Model, bd: &BatchData<L>) -> LMotion<L> {
    if model.joint_type[0] == JointType::Free {
        let r = bd.pose[0].rot;
        let v = &bd.v;
        LMotion::new(
            r * LVec3::new(v[0], v[1], v[2]),
            r * LVec3::new(v[3], v[4], v[5]),
        )
    } else {
        LMotion::ZERO
    }
}
