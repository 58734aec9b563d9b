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
    rnea_base(model, data, a, use_external);
    rnea_bodies(model, data, v, a, use_external);
    rnea_base_wrench(model, data);
}

/// The base's acceleration `acc[0]` (gravity as a fictitious upward
/// acceleration) and its own force `f[0]`, before the bodies' passes.
#[inline]
pub(crate) fn rnea_base(model: &Model, data: &mut Data, a: &[f64], use_external: bool) {
    let a0 = base_acceleration(model, data, a);
    data.acc[0] = a0;
    data.f[0] = data.inertia_ref[0].mul_motion(a0)
        + data.vel[0].cross_force(data.inertia_ref[0].mul_motion(data.vel[0]));
    if use_external {
        data.f[0] -= data.f_ext[0];
    }
}

/// A floating base's `tau[0..6]` from its total force `f[0]`, after the
/// bodies' passes.
#[inline]
pub(crate) fn rnea_base_wrench(model: &Model, data: &mut Data) {
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
pub(crate) fn base_acceleration(model: &Model, data: &Data, a: &[f64]) -> Motion {
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
    rnea_from_kinematics(model, data, v, a, false);
    tau_joints.copy_from_slice(&data.tau[nv0..]);
}

#[multiversion(targets("x86_64+avx2+fma"))]
pub(crate) fn rnea_bodies(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    use_external: bool,
) {
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
