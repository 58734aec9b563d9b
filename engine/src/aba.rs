//! Articulated-body algorithm: forward dynamics `q̈ = M⁻¹ (τ + Jᵀ f_ext − C v − g)`
//! in O(n) (Featherstone 2008, §7.3, Table 7.1, in the fixed-frame form where
//! articulated inertias add without transforms; floating base per §9.2).

use crate::data::Data;
use crate::kinematics::forward_kinematics;
use crate::model::{JointType, Model};
use crate::spatial::{Force, Motion, outer};
use crate::workspace::BodyScratch;
use glam::DVec3;
use multiversion::multiversion;

/// Forward dynamics without external forces. Fills and returns `data.ddq` (nv).
/// For a floating base, `ddq[0..6]` is the base's spatial acceleration in the
/// base frame (Pinocchio's convention) and `tau[0..6]` a wrench applied to the
/// base (base frame). Returns an all-NaN result if the base inertia is singular.
pub fn aba<'d>(model: &Model, data: &'d mut Data, q: &[f64], v: &[f64], tau: &[f64]) -> &'d [f64] {
    forward_kinematics(model, data, q, v);
    aba_from_kinematics(model, data, v, tau, false);
    &data.ddq
}

/// ABA after the scalar [`forward_kinematics`] on the same `(q, v)`. With
/// `use_external`, the forces in `data.f_ext` (world axes, about
/// `data.origin`) act on the bodies. The scalar path, whatever the model's
/// plan ([`crate::dispatch::aba_from_kinematics`] picks the plan's kernel).
pub fn aba_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    tau: &[f64],
    use_external: bool,
) {
    aba_compiled(model, data, v, tau, use_external);
}

/// [`aba_passes`] compiled for x86-64-v3 (AVX2, FMA) and the generic target
/// with the CPU's choice at the first call; the same bits either way
/// (nothing is fused into an FMA).
#[multiversion(targets("x86_64+avx2+fma"))]
fn aba_compiled(model: &Model, data: &mut Data, v: &[f64], tau: &[f64], use_external: bool) {
    aba_passes(model, data, v, tau, use_external);
}

/// ABA's three passes (Featherstone 2008, Table 7.1): fills `ddq` and the
/// bodies' `acc` (true spatial accelerations).
#[inline(always)]
pub(crate) fn aba_passes(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    tau: &[f64],
    use_external: bool,
) {
    let n = model.nbodies;
    let nv = model.nv;
    // Slices of known length up front, so that the loops below index
    // without bounds checks (the body arrays all have `n` entries).
    let (parent, idx_v, armature) = (&model.parent[..n], &model.idx_v[..n], &model.armature[..nv]);
    let (v, tau) = (&v[..nv], &tau[..nv]);
    let inertia_ref = &data.inertia_ref[..n];
    let vel = &data.vel[..n];
    let s_all = &data.s[..n];
    let f_ext = &data.f_ext[..n];
    let mut w = BodyScratch::take(n);
    let ia_all = &mut w.ia[..n];
    let pa_all = &mut w.pa[..n];
    let c_all = &mut w.c[..n];
    let u_all = &mut w.u[..n];
    let d_inv_all = &mut w.d_inv[..n];
    let u_tau_all = &mut w.u_tau[..n];
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
    // Pass 2: articulated inertias, leaves to root. The downdated inertia
    // Iᴬ − U Uᵀ/D is added to the parent block by block, never stored whole
    // (a 6×6 does not fit the registers), and Iᴬ_a c = Iᴬ c − U (Uᵀc)/D.
    for &i in model.depth_order.iter().rev() {
        let iv = idx_v[i];
        let p = parent[i];
        let s = s_all[i];
        let c = c_all[i];
        let ia = ia_all[i];
        let u = ia.mul_motion(s);
        let d_inv = 1.0 / (s.dot(u) + armature[iv]);
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
    // Pass 3: accelerations, root to leaves. Gravity is a fictitious upward
    // acceleration of the base; true accelerations are a' + a_grav.
    let a_grav = Motion::new(model.gravity, DVec3::ZERO);
    let a0 = match model.joint_type[0] {
        JointType::Free => {
            let r = data.pose[0].rot;
            let applied = Force::new(
                r * DVec3::new(tau[0], tau[1], tau[2]),
                r * DVec3::new(tau[3], tau[4], tau[5]),
            );
            let rhs = applied - pa_all[0];
            match ia_all[0].solve(rhs) {
                Some(a) => a,
                None => Motion::new(DVec3::NAN, DVec3::NAN),
            }
        }
        _ => -a_grav,
    };
    data.acc[0] = a0;
    for &i in &model.depth_order {
        let iv = model.idx_v[i];
        let a = data.acc[model.parent[i]] + c_all[i];
        let qdd = (u_tau_all[i] - u_all[i].lin.dot(a.lin) - u_all[i].ang.dot(a.ang)) * d_inv_all[i];
        data.ddq[iv] = qdd;
        data.acc[i] = a + data.s[i] * qdd;
    }
    if model.joint_type[0] == JointType::Free {
        let rt = data.pose[0].rot.transpose();
        let a0_true = a0 + a_grav;
        let al = rt * a0_true.lin;
        let aa = rt * a0_true.ang;
        data.ddq[..6].copy_from_slice(&[al.x, al.y, al.z, aa.x, aa.y, aa.z]);
    }
    w.give_back();
    // Leave `acc` as true spatial accelerations for callers.
    for i in 0..model.nbodies {
        data.acc[i] += a_grav;
    }
}
