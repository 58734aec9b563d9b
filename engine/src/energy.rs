//! Kinetic and potential energy.

use crate::data::Data;
use crate::model::Model;

/// Kinetic energy `½ Σ vᵢᵀ Iᵢ vᵢ + ½ Σ armature·q̇²` (J). Needs kinematics with velocities.
pub fn kinetic_energy(model: &Model, data: &Data, v: &[f64]) -> f64 {
    let mut t = 0.0;
    for i in 0..model.nbodies {
        t += data.body_inertia(model, i).kinetic_energy(data.vel[i]);
    }
    for (k, a) in model.armature.iter().enumerate() {
        t += 0.5 * a * v[k] * v[k];
    }
    t
}

/// Gravitational potential energy `−Σ mᵢ g·cᵢ` (J), zero at the world origin
/// (Pinocchio's convention: `+m·9.81·z_com` for standard gravity).
pub fn potential_energy(model: &Model, data: &Data) -> f64 {
    let c = crate::com::center_of_mass(model, data);
    let m: f64 = (0..model.nbodies)
        .map(|i| data.body_inertia(model, i).mass)
        .sum();
    -m * model.gravity.dot(c)
}

/// Elastic energy of the model's joint springs `½ Σ k q²` (J): with the
/// kinetic and gravitational energies, the total that an undamped, unforced
/// model conserves.
pub fn spring_energy(model: &Model, q: &[f64]) -> f64 {
    model
        .springs
        .iter()
        .map(|s| 0.5 * s.stiffness * q[s.iq] * q[s.iq])
        .sum()
}
