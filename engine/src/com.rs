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
        let ri = &data.inertia_ref[i];
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
        h += data.inertia_ref[i].mul_motion(data.vel[i]);
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
    let m: f64 = (0..model.nbodies).map(|i| data.inertia_ref[i].mass).sum();
    if m > 0.0 {
        spatial_momentum(model, data).lin / m
    } else {
        DVec3::ZERO
    }
}
