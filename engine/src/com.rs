//! Centre of mass and total momentum of the whole robot.

use crate::data::Data;
use crate::model::Model;
use crate::spatial::Force;
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
        let v = &vel[i];
        mc += ri.com * ri.mass;
        m += ri.mass;
        p += (v.lin + v.ang.cross(ri.com)) * ri.mass;
    });
    if m > 0.0 {
        (data.origin + mc / m, p / m)
    } else {
        (data.origin, DVec3::ZERO)
    }
}

/// Linear momentum `Σ mᵢ (vᵢ + ωᵢ × cᵢ)` (kg·m/s, world): the linear part of
/// [`spatial_momentum`], the same sum in the same order without the angular
/// part's inertia products (the CoM velocity is read every step).
pub fn linear_momentum(model: &Model, data: &Data) -> DVec3 {
    let mut p = DVec3::ZERO;
    for i in 0..model.nbodies {
        let (inertia, v) = (&data.body_inertia(model, i), data.vel[i]);
        p += (v.lin + v.ang.cross(inertia.com)) * inertia.mass;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward_kinematics;
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
}
