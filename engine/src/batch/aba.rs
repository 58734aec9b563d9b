//! Articulated-body algorithm across robots: [`crate::aba`]'s three passes
//! (Featherstone 2008, Table 7.1, fixed-frame form; floating base per §9.2)
//! with one lane per robot, operation for operation.

use super::BatchData;
use super::kinematics::forward_kinematics_lanes;
use super::lanes::{LVec3, Lanes, outer};
use super::spatial::LMotion;
use crate::model::{JointType, Model};
use crate::spatial::{Force, Motion};
use glam::DVec3;
use multiversion::multiversion;

/// Forward dynamics of the active lanes: forward kinematics from `bd.q`,
/// `bd.v`, then ABA under `bd.tau` and, with `use_external`, the forces in
/// `bd.f_ext`. Fills `bd.ddq` (nv per lane; each lane bit-identical to
/// [`crate::aba::aba`] / [`crate::aba::aba_from_kinematics`] on that robot)
/// and leaves `bd.acc` as true spatial accelerations.
///
/// A lane whose floating-base articulated inertia is singular gets NaN base
/// accelerations, as the scalar path does.
///
/// Compiled for x86-64-v3 (AVX2) and the generic target; the CPU picks one
/// at run time (see [the module doc](super)).
///
/// # Panics
/// If `bd` was sized for a model of other sizes.
pub fn aba_batch<const L: usize>(model: &Model, bd: &mut BatchData<L>, use_external: bool) {
    bd.check_model(model);
    aba_dispatch(model, bd, use_external);
}

/// ABA of the active lanes after [`super::forward_kinematics_batch`] on the
/// same `bd.q`, `bd.v` (the batched [`crate::aba::aba_from_kinematics`]):
/// fills `bd.ddq` and `bd.acc` as [`aba_batch`] does.
///
/// # Panics
/// If `bd` was sized for a model of other sizes.
pub fn aba_from_kinematics_batch<const L: usize>(
    model: &Model,
    bd: &mut BatchData<L>,
    use_external: bool,
) {
    bd.check_model(model);
    aba_only_dispatch(model, bd, use_external);
}

#[multiversion(targets("x86_64+avx2+fma"))]
fn aba_only_dispatch<const L: usize>(model: &Model, bd: &mut BatchData<L>, use_external: bool) {
    aba_lanes(model, bd, use_external);
}

/// [`aba_batch`] compiled for the build's generic target only, never the
/// AVX2 version: for tests that the portable code gives the same bits, and
/// for benchmarks of what runtime dispatch gains.
///
/// # Panics
/// If `bd` was sized for a model of other sizes.
#[inline(never)]
pub fn aba_batch_generic<const L: usize>(model: &Model, bd: &mut BatchData<L>, use_external: bool) {
    bd.check_model(model);
    forward_kinematics_lanes(model, bd);
    aba_lanes(model, bd, use_external);
}

#[multiversion(targets("x86_64+avx2+fma"))]
fn aba_dispatch<const L: usize>(model: &Model, bd: &mut BatchData<L>, use_external: bool) {
    forward_kinematics_lanes(model, bd);
    aba_lanes(model, bd, use_external);
}

#[inline(always)]
fn aba_lanes<const L: usize>(model: &Model, bd: &mut BatchData<L>, use_external: bool) {
    let n = model.nbodies;
    let nv = model.nv;
    let (parent, idx_v, armature) = (&model.parent[..n], &model.idx_v[..n], &model.armature[..nv]);
    let (v, tau) = (&bd.v[..nv], &bd.tau[..nv]);
    let inertia_ref = &bd.inertia_ref[..n];
    let vel = &bd.vel[..n];
    let s_all = &bd.s[..n];
    let f_ext = &bd.f_ext[..n];
    let ia_all = &mut bd.ia[..n];
    let pa_all = &mut bd.pa[..n];
    let c_all = &mut bd.c[..n];
    let u_all = &mut bd.u[..n];
    let d_inv_all = &mut bd.d_inv[..n];
    let u_tau_all = &mut bd.u_tau[..n];
    // Pass 1: bias forces and velocity-product accelerations.
    for i in 0..n {
        let inertia = &inertia_ref[i];
        let vi = vel[i];
        ia_all[i] = inertia.to_sym6();
        let mut p = vi.cross_force(inertia.mul_motion(vi));
        if use_external {
            p -= f_ext[i];
        }
        pa_all[i] = p;
        if i > 0 {
            c_all[i] = vi.cross(s_all[i] * v[idx_v[i]]);
        }
    }
    // Pass 2: articulated inertias, leaves to root.
    let one = Lanes::splat(1.0);
    for &i in model.depth_order.iter().rev() {
        let iv = idx_v[i];
        let p = parent[i];
        let s = s_all[i];
        let c = c_all[i];
        let ia = ia_all[i];
        let u = ia.mul_motion(s);
        let d_inv = one / (s.dot(u) + Lanes::splat(armature[iv]));
        let pai = pa_all[i];
        let ut = tau[iv] - s.dot(pai);
        let ia_c = ia.mul_motion(c);
        let ul = u.lin * d_inv;
        let ua = u.ang * d_inv;
        let parent = &mut ia_all[p];
        parent.m += ia.m - outer(ul, u.lin);
        parent.h += ia.h - outer(ua, u.lin);
        parent.i += ia.i - outer(ua, u.ang);
        let pa = pai + ia_c + u * ((ut - c.dot(u)) * d_inv);
        u_all[i] = u;
        d_inv_all[i] = d_inv;
        u_tau_all[i] = ut;
        pa_all[p] += pa;
    }
    // Pass 3: accelerations, root to leaves; gravity as a fictitious upward
    // acceleration of the base.
    let a_grav = LMotion::new(LVec3::splat(model.gravity), LVec3::ZERO);
    let a0 = match model.joint_type[0] {
        JointType::Free => {
            // The 6×6 solve branches on positive definiteness: the scalar
            // `Sym6::solve`, lane by lane (once per robot, not per body).
            let mut a0 = LMotion::ZERO;
            let rot = bd.pose[0].rot;
            for k in 0..bd.active {
                let r = rot.lane(k);
                let t = |j: usize| tau[j].0[k];
                let applied = Force::new(
                    r * DVec3::new(t(0), t(1), t(2)),
                    r * DVec3::new(t(3), t(4), t(5)),
                );
                let rhs = applied - bd.pa[0].lane(k);
                let a = bd.ia[0]
                    .lane(k)
                    .solve(rhs)
                    .unwrap_or(Motion::new(DVec3::NAN, DVec3::NAN));
                a0.set_lane(k, a);
            }
            a0
        }
        _ => -a_grav,
    };
    bd.acc[0] = a0;
    for &i in &model.depth_order {
        let iv = idx_v[i];
        let a = bd.acc[parent[i]] + bd.c[i];
        let u = bd.u[i];
        let qdd = (bd.u_tau[i] - u.lin.dot(a.lin) - u.ang.dot(a.ang)) * bd.d_inv[i];
        bd.ddq[iv] = qdd;
        bd.acc[i] = a + bd.s[i] * qdd;
    }
    if model.joint_type[0] == JointType::Free {
        let rt = bd.pose[0].rot.transpose();
        let a0_true = a0 + a_grav;
        let al = rt * a0_true.lin;
        let aa = rt * a0_true.ang;
        bd.ddq[..6].copy_from_slice(&[al.x, al.y, al.z, aa.x, aa.y, aa.z]);
    }
    for acc in &mut bd.acc[..n] {
        *acc += a_grav;
    }
}
