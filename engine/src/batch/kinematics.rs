//! Forward kinematics across robots: [`crate::kinematics::forward_kinematics`]
//! with one lane per robot (poses, motion subspaces, velocities and inertias
//! in each robot's reference frame), operation for operation.

use super::BatchData;
use super::lanes::{LMat3, LVec3, Lanes};
use super::spatial::{LInertia, LMotion, LTransform};
use crate::kinematics::aligned_axis;
use crate::model::{JointType, Model};
use glam::{DMat3, DVec3};
use multiversion::multiversion;

/// Poses and velocities of every active lane from `bd.q` and `bd.v`: fills
/// `origin`, `pose`, `s`, `inertia_ref` and `vel` of `bd` (the free base's
/// `s_base` of [`crate::Data`] is not needed by ABA and not computed).
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
    let n = model.nbodies;
    bd.vel[0] = base_velocity(model, bd);
    for i in 1..n {
        bd.vel[i] = bd.vel[model.parent[i]] + bd.s[i] * bd.v[model.idx_v[i]];
    }
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

/// glam's `DMat3::from_axis_angle(axis, angle)` with one angle per lane.
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
    let cols = [rot.x_axis, rot.y_axis, rot.z_axis];
    let (a, b) = ((k + 1) % 3, (k + 2) % 3);
    let mut out = cols;
    out[a] = cols[a] * c + cols[b] * s;
    out[b] = cols[b] * c - cols[a] * s;
    LMat3::from_cols(out[0], out[1], out[2])
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
    bd.origin = base.trans;
    bd.pose[0] = base;
    bd.inertia_ref[0] =
        LInertia::transformed(&model.inertia[0], &LTransform::new(base.rot, LVec3::ZERO));
    for i in 1..model.nbodies {
        let p = model.parent[i];
        let jt = model.joint_type[i];
        let axis = model.axis[i];
        let xp = bd.pose[p];
        let pl = &model.placement[i];
        let rot_j = if pl.rot == DMat3::IDENTITY {
            xp.rot
        } else {
            xp.rot * LMat3::splat(pl.rot)
        };
        let trans_j = xp.rot * LVec3::splat(pl.trans) + xp.trans;
        let qi = bd.q[model.idx_q[i]];
        let (x, aw) = match (jt, aligned_axis(axis)) {
            (JointType::Revolute, Some((k, sign))) => (
                LTransform::new(
                    rotate_about_axis(rot_j, k, Lanes::splat(sign) * qi),
                    trans_j,
                ),
                rot_j.col(k) * Lanes::splat(sign),
            ),
            _ => (
                LTransform::new(rot_j, trans_j).compose(&joint_transform(jt, axis, qi)),
                rot_j * LVec3::splat(axis),
            ),
        };
        bd.pose[i] = x;
        let r = x.trans - bd.origin;
        bd.s[i] = match jt {
            JointType::Revolute => LMotion::new(r.cross(aw), aw),
            _ => LMotion::new(aw, LVec3::ZERO),
        };
        bd.inertia_ref[i] = LInertia::transformed(&model.inertia[i], &LTransform::new(x.rot, r));
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
