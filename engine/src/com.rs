//! Centre of mass and total momentum of the whole robot.

use crate::data::Data;
use crate::model::Model;
use crate::plan::{LEGS, LegLanes};
use crate::spatial::{Force, Motion, RigidInertia};
use glam::DVec3;

/// Centre of mass of the whole robot in the world (m). Needs kinematics (positions) first.
pub fn center_of_mass(model: &Model, data: &Data) -> DVec3 {
    let mut mc = DVec3::ZERO;
    let mut m = 0.0;
    for i in 0..model.nbodies {
        let ri = &data.body_inertia(model, i);
        mc += ri.com * ri.mass;
        m += ri.mass;
    }
    if m > 0.0 {
        data.origin + mc / m
    } else {
        data.origin
    }
}

/// Total spatial momentum `Σ Iᵢ vᵢ`: linear momentum (kg·m/s, world) and angular
/// momentum about [`Data::origin`] (kg·m²/s, world axes). Needs kinematics with velocities.
pub fn spatial_momentum(model: &Model, data: &Data) -> Force {
    let mut h = Force::ZERO;
    for i in 0..model.nbodies {
        h += data.body_inertia(model, i).mul_motion(data.vel[i]);
    }
    h
}

/// Linear momentum (kg·m/s, world) and angular momentum about the centre of mass
/// (kg·m²/s, world axes). Needs kinematics with velocities.
pub fn momentum_about_com(model: &Model, data: &Data) -> (DVec3, DVec3) {
    let h = spatial_momentum(model, data);
    let c = center_of_mass(model, data) - data.origin;
    (h.lin, h.ang - c.cross(h.lin))
}

/// Velocity of the centre of mass (m/s, world). Needs kinematics with velocities.
pub fn com_velocity(model: &Model, data: &Data) -> DVec3 {
    let m: f64 = (0..model.nbodies)
        .map(|i| data.body_inertia(model, i).mass)
        .sum();
    if m > 0.0 {
        linear_momentum(model, data) / m
    } else {
        DVec3::ZERO
    }
}

/// [`center_of_mass`] and [`com_velocity`] in one pass over the bodies (each
/// sum in the same order, so the same bits), for a caller that reads both
/// every step. Its x86-64-v3 clone's three-operand (VEX) instructions
/// spare the register copies of the generic build's loop; no fused
/// multiply–add, so both give the same bits.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn com_and_velocity(model: &Model, data: &Data) -> (DVec3, DVec3) {
    let n = model.nbodies;
    let mut mc = DVec3::ZERO;
    let mut p = DVec3::ZERO;
    // `center_of_mass` sums the masses from 0.0, `com_velocity` from −0.0:
    // the same value after the first mass, and both only divide by a positive one
    let mut m = 0.0;
    let vel = &data.vel[..n];
    data.for_each_body_inertia(model, |i, ri| {
        let (mci, pi) = com_terms(&ri, &vel[i]);
        mc += mci;
        m += ri.mass;
        p += pi;
    });
    if m > 0.0 {
        (data.origin + mc / m, p / m)
    } else {
        (data.origin, DVec3::ZERO)
    }
}

/// [`com_and_velocity`] for readers of outputs only (the observation behind
/// the metrics, logs and fall check), summed leg by leg where the robot's
/// four legs run in lanes (`Model::leg_lanes`): each leg's bodies in group
/// order in its own lane, then the base, leg 0, …, leg 3. That is another
/// order of the same sums (the values agree within round-off, not to the
/// bit, with [`com_and_velocity`], which the controller reads), and every
/// path gives its bits: the lanes' sums where `data` holds them, otherwise the
/// same sums in scalar code (`leg_mass_sums_scalar`), whatever filled the
/// kinematics (robot batches, either build). Other models: [`com_and_velocity`].
pub fn com_and_velocity_by_legs(model: &Model, data: &Data) -> (DVec3, DVec3) {
    if let Some(plan) = by_legs(model) {
        return add_base(model, data, &leg_mass_sums_scalar(model, data, plan));
    }
    com_and_velocity(model, data)
}

/// The legs' grouping when [`com_and_velocity_by_legs`] sums leg by leg:
/// the four legs run in lanes and each leg's bodies are consecutive.
#[inline]
pub(crate) fn by_legs(model: &Model) -> Option<&LegLanes> {
    model
        .leg_lanes()
        .filter(|plan| plan.leg_major && model.nbodies == 1 + LEGS * plan.groups.len())
}

/// The legs-in-lanes kernel's mass sums (`kernels::legs_x4`) leg by leg in scalar code, the same
/// operations in the same order: per leg `k`, over its bodies in group
/// order from `0.0`, `Σ m`, `Σ m c` and `Σ m (v + ω × c)`, as
/// `[m, mc.x, mc.y, mc.z, p.x, p.y, p.z][k]`.
pub(crate) fn leg_mass_sums_scalar(
    model: &Model,
    data: &Data,
    plan: &LegLanes,
) -> [[f64; LEGS]; 7] {
    let mut out = [[0.0; LEGS]; 7];
    for k in 0..LEGS {
        let (mut m, mut mc, mut p) = (0.0, DVec3::ZERO, DVec3::ZERO);
        for grp in &plan.groups {
            let i = grp[k];
            let ri = data.body_inertia(model, i);
            let (mci, pi) = com_terms(&ri, &data.vel[i]);
            mc += mci;
            m += ri.mass;
            p += pi;
        }
        for (o, x) in out.iter_mut().zip([m, mc.x, mc.y, mc.z, p.x, p.y, p.z]) {
            o[k] = x;
        }
    }
    out
}

/// The CoM and its velocity from the legs' sums (`leg_mass_sums`' layout):
/// the base's terms, then leg 0, …, leg 3 added in turn.
#[inline]
pub(crate) fn add_base(model: &Model, data: &Data, legs: &[[f64; LEGS]; 7]) -> (DVec3, DVec3) {
    let ri = data.body_inertia(model, 0);
    let mut m = ri.mass;
    let (mut mc, mut p) = com_terms(&ri, &data.vel[0]);
    for k in 0..LEGS {
        m += legs[0][k];
        mc += DVec3::new(legs[1][k], legs[2][k], legs[3][k]);
        p += DVec3::new(legs[4][k], legs[5][k], legs[6][k]);
    }
    if m > 0.0 {
        (data.origin + mc / m, p / m)
    } else {
        (data.origin, DVec3::ZERO)
    }
}

/// One body's terms of the CoM sums: its first moment `m c` and linear
/// momentum `m (v + ω × c)` (`c` its CoM relative to the reference point;
/// the lanes' `leg_mass_sums` forms them operation for operation).
#[inline]
fn com_terms(ri: &RigidInertia, v: &Motion) -> (DVec3, DVec3) {
    (ri.com * ri.mass, (v.lin + v.ang.cross(ri.com)) * ri.mass)
}

/// Linear momentum `Σ mᵢ (vᵢ + ωᵢ × cᵢ)` (kg·m/s, world): the linear part of
/// [`spatial_momentum`], the same sum in the same order without the angular
/// part's inertia products (the CoM velocity is read every step).
pub fn linear_momentum(model: &Model, data: &Data) -> DVec3 {
    let mut p = DVec3::ZERO;
    for i in 0..model.nbodies {
        p += com_terms(&data.body_inertia(model, i), &data.vel[i]).1;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dispatch::forward_kinematics;
    use crate::model::BaseKind;
    use crate::robots::builtin;

    /// quad16 moved off the origin, with joint and base speeds `speed(i)`,
    /// after forward kinematics.
    fn moving_quad16(speed: impl Fn(f64) -> f64) -> (Model, Data) {
        let desc = builtin("quad16").unwrap();
        let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let mut data = Data::new(&model);
        let mut q = crate::robots::nominal_q("quad16").unwrap();
        q[0] = 0.3;
        let v: Vec<f64> = (0..model.nv).map(|i| speed(i as f64)).collect();
        forward_kinematics(&model, &mut data, &q, &v);
        (model, data)
    }

    /// The linear momentum on its own is the linear part of the spatial
    /// momentum bit for bit (same terms, same order), on a moving quad16.
    #[test]
    fn linear_momentum_is_the_spatial_momentums_linear_part() {
        let (model, data) = moving_quad16(|i| (i * 0.7).sin() * 1.5);
        let p = linear_momentum(&model, &data);
        assert!(p.length() > 0.1, "the state moves: {p}");
        assert_eq!(p.to_array(), spatial_momentum(&model, &data).lin.to_array());
    }

    /// The one-pass CoM and CoM velocity are the separate functions' bits.
    #[test]
    fn com_and_velocity_is_both_functions() {
        let (model, data) = moving_quad16(|i| (i * 0.9).cos() * 1.2);
        let (c, vc) = com_and_velocity(&model, &data);
        assert_eq!(c.to_array(), center_of_mass(&model, &data).to_array());
        assert_eq!(vc.to_array(), com_velocity(&model, &data).to_array());
    }

    /// The leg-by-leg sums: within round-off of the body-order ones, and on
    /// x86-64 the lanes' bits equal the scalar sums' in the same order
    /// (the path a robot batch or the generic build takes).
    #[test]
    fn com_and_velocity_by_legs_is_the_same_sums_in_leg_order() {
        let (model, data) = moving_quad16(|i| (i * 0.9).cos() * 1.2);
        let (c, vc) = crate::dispatch::com_and_velocity_by_legs(&model, &data);
        let (c0, vc0) = com_and_velocity(&model, &data);
        assert!(vc0.length() > 0.1, "the state moves: {vc0}");
        assert!((c - c0).length() <= 1e-14 * c0.length(), "{c} vs {c0}");
        assert!((vc - vc0).length() <= 1e-13 * vc0.length(), "{vc} vs {vc0}");
        #[cfg(target_arch = "x86_64")]
        {
            let plan = model.leg_lanes().expect("quad16's legs in lanes");
            let (cs, vcs) = add_base(&model, &data, &leg_mass_sums_scalar(&model, &data, plan));
            assert_eq!(c.to_array(), cs.to_array());
            assert_eq!(vc.to_array(), vcs.to_array());
            // the lanes were there to read, on a CPU with them
            assert_eq!(data.lanes.valid, crate::dispatch::runs_on(&model));
        }
    }
}
