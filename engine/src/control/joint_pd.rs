//! Joint-space PD control toward fixed targets, with an optional static
//! feed-forward that carries the robot's weight on its feet.

use crate::data::Data;
use crate::dispatch::forward_kinematics_pos;
use crate::jacobian::add_point_force_jt;
use crate::model::Model;
use crate::nle::generalized_gravity;
use glam::DVec3;

/// Joint PD: `τᵢ = τ_ffᵢ + kpᵢ (q_targetᵢ − qᵢ) − kdᵢ q̇ᵢ` on every actuated joint.
#[derive(Clone, Debug, PartialEq)]
pub struct JointPd {
    /// Proportional gain per joint (N·m/rad).
    pub kp_nm_per_rad: Vec<f64>,
    /// Derivative gain per joint (N·m·s/rad).
    pub kd_nms_per_rad: Vec<f64>,
    /// Target joint angles (rad), joints only (nv − base).
    pub target_rad: Vec<f64>,
    /// Feed-forward torques (N·m), joints only.
    pub feedforward_nm: Vec<f64>,
}

impl JointPd {
    /// Writes joint torques into `tau_joints` (joints only; q and q̇ joints only).
    pub fn compute(&self, q_joints: &[f64], qd_joints: &[f64], tau_joints: &mut [f64]) {
        for i in 0..tau_joints.len() {
            tau_joints[i] = self.feedforward_nm[i]
                + self.kp_nm_per_rad[i] * (self.target_rad[i] - q_joints[i])
                - self.kd_nms_per_rad[i] * qd_joints[i];
        }
    }
}

/// Gains that give every joint the same closed-loop bandwidth: `kpᵢ = Mᵢᵢ ω²`,
/// `kdᵢ = 2 ζ Mᵢᵢ ω` with `ω = 2π·bandwidth_hz` and `Mᵢᵢ` the joint's apparent
/// inertia (its diagonal entry of the mass matrix at `q`: the subtree's inertia
/// about the axis with the rest of the robot held). Uniform gains would be
/// unstable on a light distal link (quad16's foot: Mᵢᵢ ≈ 6e-4 kg·m²) under a
/// sampled controller; scaling by Mᵢᵢ keeps `kd·T/Mᵢᵢ = 2ζωT` the same for all.
pub fn bandwidth_gains(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    bandwidth_hz: f64,
    damping_ratio: f64,
) -> (Vec<f64>, Vec<f64>) {
    let m = crate::dispatch::crba(model, data, q);
    let w = std::f64::consts::TAU * bandwidth_hz;
    let nv = model.nv;
    let b = model.base_nv();
    let diag: Vec<f64> = (b..nv).map(|i| m[i * nv + i]).collect();
    (
        diag.iter().map(|mi| mi * w * w).collect(),
        diag.iter().map(|mi| 2.0 * damping_ratio * mi * w).collect(),
    )
}

/// Joint torques that hold a floating-base robot still at configuration `q`
/// with its weight carried by the given foot points (`(body, point in body
/// frame)`), each pushed straight up by the ground: `τ = g(q) − Jᵀ f` (joint
/// rows). The vertical forces are the least-norm solution of force and moment
/// balance about the CoM (Σ fᵢ = m g, Σ fᵢ (xᵢ, yᵢ) = m g (x_c, y_c)), so the base
/// is balanced too whenever the CoM projects inside the feet's polygon; with
/// fewer than three feet they are shared equally.
pub fn static_stance_torques(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    feet: &[(usize, DVec3)],
) -> Vec<f64> {
    let mut tau = generalized_gravity(model, data, q).to_vec();
    forward_kinematics_pos(model, data, q);
    let weight = -model.gravity.z * model.total_mass;
    let n = feet.len();
    if n > 0 {
        let com = crate::com::center_of_mass(model, data);
        let pts: Vec<DVec3> = feet
            .iter()
            .map(|&(b, p)| data.body_point_world(b, p))
            .collect();
        let forces = vertical_support_forces(&pts, com, weight);
        let mut jt_f = vec![0.0; model.nv];
        for (&(body, _), (pw, fz)) in feet.iter().zip(pts.iter().zip(&forces)) {
            add_point_force_jt(model, data, body, *pw, DVec3::Z * *fz, &mut jt_f);
        }
        for (t, j) in tau.iter_mut().zip(&jt_f) {
            *t -= j;
        }
    }
    tau[model.base_nv()..].to_vec()
}

/// Least-norm vertical forces (N) at `points` that carry `weight_n` with zero
/// moment about the CoM's vertical: rows A = [1; x; y], f = Aᵀ (A Aᵀ)⁻¹ b.
fn vertical_support_forces(points: &[DVec3], com: DVec3, weight_n: f64) -> Vec<f64> {
    let n = points.len();
    let equal = vec![weight_n / n as f64; n];
    if n < 3 {
        return equal;
    }
    let mut aat = glam::DMat3::ZERO;
    for p in points {
        let a = DVec3::new(1.0, p.x, p.y);
        aat += crate::spatial::outer(a, a);
    }
    if aat.determinant().abs() < 1e-12 {
        return equal;
    }
    let y = aat.inverse() * (DVec3::new(1.0, com.x, com.y) * weight_n);
    points
        .iter()
        .map(|p| DVec3::new(1.0, p.x, p.y).dot(y))
        .collect()
}
