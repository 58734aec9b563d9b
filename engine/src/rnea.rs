//! Recursive Newton–Euler algorithm: inverse dynamics `τ = M(q) a + C(q, v) v + g(q) − Jᵀ f_ext`
//! (Featherstone 2008, §5.3, Table 5.1, in the fixed-frame form of §5.3 eq. 5.9–5.12).

use crate::data::Data;
use crate::kinematics::forward_kinematics;
use crate::model::{JointType, Model};
use crate::spatial::Motion;
use multiversion::multiversion;

/// Inverse dynamics without external forces. Fills and returns `data.tau` (nv):
/// for a floating base, `tau[0..6]` is the wrench (force, torque; base frame)
/// that the base would need. Joint entries include `armature · a`.
pub fn rnea<'d>(model: &Model, data: &'d mut Data, q: &[f64], v: &[f64], a: &[f64]) -> &'d [f64] {
    forward_kinematics(model, data, q, v);
    rnea_from_kinematics(model, data, v, a, false);
    &data.tau
}

/// RNEA after [`forward_kinematics`] has run on the same `(q, v)`. With
/// `use_external`, the forces in `data.f_ext` act on the bodies (subtracted).
pub fn rnea_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    use_external: bool,
) {
    let a0 = base_acceleration(model, data, a);
    data.acc[0] = a0;
    data.f[0] = data.inertia_ref[0].mul_motion(a0)
        + data.vel[0].cross_force(data.inertia_ref[0].mul_motion(data.vel[0]));
    if use_external {
        data.f[0] -= data.f_ext[0];
    }
    rnea_bodies(model, data, v, a, use_external);
    if model.joint_type[0] == JointType::Free {
        for k in 0..6 {
            data.tau[k] = data.base_subspace(k).dot(data.f[0]);
        }
    }
}

/// The base's spatial acceleration RNEA starts from: gravity as a
/// fictitious upward acceleration (Featherstone §5.3) plus, on a free base,
/// its own acceleration `a[..6]` through the base's motion subspace.
#[inline]
fn base_acceleration(model: &Model, data: &Data, a: &[f64]) -> Motion {
    let mut a0 = Motion::new(-model.gravity, glam::DVec3::ZERO);
    if model.joint_type[0] == JointType::Free {
        for k in 0..6 {
            a0 += data.base_subspace(k) * a[k];
        }
    }
    a0
}

/// The joint rows of [`rnea_from_kinematics`] without external forces,
/// `tau_joints[j − base_nv] = tau[j]` bit for bit, for a caller that reads
/// only them (the walker's feed-forward): with the legs in lanes, neither
/// the base's force and rows nor the legs' `acc` and `f` are formed or
/// stored (about 40% of the pass). Otherwise the full RNEA runs. `data`'s
/// `acc` (but the base's, which is the full RNEA's), `f` and `tau` are then
/// unspecified (not those of the full RNEA).
pub fn rnea_joint_torques_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    tau_joints: &mut [f64],
) {
    let nv0 = model.base_nv();
    assert_eq!(tau_joints.len(), model.nv - nv0, "one torque per joint");
    data.acc[0] = base_acceleration(model, data, a);
    if !rnea_joint_torques_in_lanes(model, data, v, a, tau_joints) {
        rnea_from_kinematics(model, data, v, a, false);
        tau_joints.copy_from_slice(&data.tau[nv0..]);
    }
}

/// [`rnea_joint_torques_from_kinematics`]'s legs in lanes, after the base's
/// acceleration `data.acc[0]` is set, where the model's shape and the CPU
/// allow (then `true`), as [`rnea_bodies`] dispatches.
#[multiversion(targets("x86_64+avx2+fma"))]
fn rnea_joint_torques_in_lanes(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    tau_joints: &mut [f64],
) -> bool {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Some(plan) = &model.leg_lanes
            && plan.groups.len() <= crate::leg_lanes::RNEA_MAX_GROUPS
        {
            crate::leg_lanes::avx_call!(crate::leg_lanes::rnea_passes_legs::<false>(model, plan, data, v, a, false, tau_joints));
            return true;
        },
        _ => {},
    }
    let _ = (model, data, v, a, tau_joints);
    false
}

/// RNEA's two passes over the bodies after the base's (its acceleration and
/// own force set; the children's forces are added to it here), compiled for
/// x86-64-v3 (AVX2, FMA) and the generic target with the CPU's choice at the
/// first call. quad16's shape with AVX runs the four legs in SIMD lanes
/// ([`crate::leg_lanes`]); the same bits either way (the same operations in
/// the same order, nothing fused into an FMA).
#[multiversion(targets("x86_64+avx2+fma"))]
fn rnea_bodies(model: &Model, data: &mut Data, v: &[f64], a: &[f64], use_external: bool) {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Some(plan) = &model.leg_lanes
            && plan.groups.len() <= crate::leg_lanes::RNEA_MAX_GROUPS
        {
            return crate::leg_lanes::avx_call!(crate::leg_lanes::rnea_passes_legs::<true>(model, plan, data, v, a, use_external, &mut []));
        },
        _ => {},
    }
    for i in 1..model.nbodies {
        let p = model.parent[i];
        let iv = model.idx_v[i];
        let vi = data.vel[i];
        let acc = data.acc[p] + data.s[i] * a[iv] + vi.cross(data.s[i] * v[iv]);
        data.acc[i] = acc;
        let inertia = &data.inertia_ref[i];
        let mut f = inertia.mul_motion(acc) + vi.cross_force(inertia.mul_motion(vi));
        if use_external {
            f -= data.f_ext[i];
        }
        data.f[i] = f;
    }
    for i in (1..model.nbodies).rev() {
        let iv = model.idx_v[i];
        data.tau[iv] = data.s[i].dot(data.f[i]) + model.armature[iv] * a[iv];
        let p = model.parent[i];
        let fi = data.f[i];
        data.f[p] += fi;
    }
}
