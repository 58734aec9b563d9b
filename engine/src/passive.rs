//! Passive joint effects and actuator saturation (MuJoCo's `engine_passive`):
//! viscous damping, regularised Coulomb friction and soft position limits, plus
//! clamping of actuator torques at the joints' effort limits.
//!
//! Every term is a generalised force on a joint coordinate (N·m for revolute,
//! N for prismatic joints), positive along the joint axis, and acts on the
//! free base not at all. The per-joint coefficients (damping, friction, limits,
//! effort limits) come from the [`Model`]; the global switches and the limit
//! spring–damper come from [`PassiveParams`]. All terms are smooth or at least
//! continuous in `(q, q̇)` so that RK4 keeps its order away from the limits.

use crate::model::Model;

/// Switches and constants of the passive joint model.
///
/// Explicit integrators stay stable while `√(k/I)·dt ≲ 1` and `b·dt/I < 1`
/// for the smallest joint inertia `I` (the limit spring `k`, the limit damper
/// `b`, and the friction slope `f/ε` all count as a `b`); the defaults keep
/// quad16 and quad12 stable at dt = 0.5 ms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassiveParams {
    /// Apply the model's viscous joint damping `τ = −b q̇`.
    pub damping: bool,
    /// Apply the model's Coulomb joint friction, regularised as `τ = −f tanh(q̇/ε)`.
    pub friction: bool,
    /// Velocity scale ε of the friction regularisation (rad/s or m/s): friction
    /// reaches 76 % of `f` at `q̇ = ε`, and acts as a damper of slope `f/ε` near rest.
    pub friction_epsilon: f64,
    /// Apply soft position limits beyond the model's `lower_limit`/`upper_limit`.
    pub limits: bool,
    /// Stiffness of the limit spring (N·m/rad or N/m), acting only beyond the limit.
    pub limit_stiffness: f64,
    /// Damping of the limit spring (N·m·s/rad or N·s/m), acting only beyond the limit.
    pub limit_damping: f64,
    /// Clamp actuator torques to `|τ| ≤ effort_limit`.
    pub saturation: bool,
}

impl Default for PassiveParams {
    /// Everything on; limit spring 200 N·m/rad with 0.5 N·m·s/rad, friction ε = 0.1 rad/s.
    ///
    /// The limit gains are bounded by the lightest joint they must hold at the
    /// default 0.5 ms step: quad16's ankle drives only the 0.5 kg foot
    /// (I ≈ 6.3e-4 kg·m²), so `√(k/I)·dt = 0.28` and `b·dt/I = 0.40`. With
    /// 5 N·m·s/rad the damper alone gave `b·dt/I = 4`: a foot spinning into its
    /// limit came out 5× faster the other way (regression test
    /// `limit_damper_is_stable_on_a_light_foot` in `engine/tests/analytic.rs`).
    fn default() -> Self {
        Self {
            damping: true,
            friction: true,
            friction_epsilon: 0.1,
            limits: true,
            limit_stiffness: 200.0,
            limit_damping: 0.5,
            saturation: true,
        }
    }
}

impl PassiveParams {
    /// Every passive effect and the saturation off: the joints are ideal and
    /// the actuator torques pass through (conservation tests).
    pub fn none() -> Self {
        Self {
            damping: false,
            friction: false,
            limits: false,
            saturation: false,
            ..Self::default()
        }
    }
}

/// Viscous damping torque `−b q̇`.
#[inline]
pub fn damping_torque(damping: f64, qd: f64) -> f64 {
    -damping * qd
}

/// Regularised Coulomb friction `−f tanh(q̇/ε)`: smooth, odd, bounded by `f`.
#[inline]
pub fn friction_torque(friction: f64, qd: f64, epsilon: f64) -> f64 {
    if friction == 0.0 {
        return 0.0;
    }
    -friction * (qd / epsilon).tanh()
}

/// Soft-limit torque: zero inside `[lower, upper]`; beyond it a spring–damper
/// `−k·(q − limit) − b·q̇` that only ever pushes back into the range (the
/// damper never pulls the joint outward, so the limit is not sticky).
/// Both sides are formed and one picked, without branches, so that a loop
/// over the joints vectorises.
#[inline]
pub fn limit_torque(q: f64, qd: f64, lower: f64, upper: f64, stiffness: f64, damping: f64) -> f64 {
    let above = (-stiffness * (q - upper) - damping * qd).min(0.0);
    let below = (stiffness * (lower - q) - damping * qd).max(0.0);
    if q > upper {
        above
    } else if q < lower {
        below
    } else {
        0.0
    }
}

/// Writes the actuator torques clamped to the model's effort limits into
/// `tau_out` (nv). Entries with an infinite limit (the free base) pass through;
/// with `params.saturation` off every entry passes through.
pub fn saturate(model: &Model, params: &PassiveParams, tau_actuator: &[f64], tau_out: &mut [f64]) {
    debug_assert_eq!(tau_actuator.len(), model.nv);
    debug_assert_eq!(tau_out.len(), model.nv);
    if !params.saturation {
        tau_out.copy_from_slice(tau_actuator);
        return;
    }
    for ((out, &t), &lim) in tau_out
        .iter_mut()
        .zip(tau_actuator)
        .zip(&model.effort_limit)
    {
        // `t.clamp(-lim, lim)`'s value, without its `min <= max` assertion
        // (a panic path per entry that keeps the loop from vectorising)
        let low = if t < -lim { -lim } else { t };
        *out = if low > lim { lim } else { low };
    }
}

/// Adds the passive joint torques at `(q, v)` into `tau` (nv): damping,
/// friction and soft limits as switched on in `params`, and always the
/// model's joint springs (compliant payloads' spring–dampers, see
/// [`spring_torques`]). The base is untouched. (An x86-64-v3 clone: no
/// fused multiply–add, so the same bits.)
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn add_passive_torques(
    model: &Model,
    params: &PassiveParams,
    q: &[f64],
    v: &[f64],
    tau: &mut [f64],
) {
    debug_assert_eq!(tau.len(), model.nv);
    // Each movable joint (body 1..nbodies) has one coordinate in q and in v,
    // at the same rank after the base's: joint j is q[bq + j] and v[bv + j].
    // Walking the joints in that order (each writes only its own entry, so
    // the order does not matter) over slices of one length needs no index
    // tables and no bounds checks.
    let (bq, bv, nv) = (model.base_nq(), model.base_nv(), model.nv);
    let nj = nv - bv;
    debug_assert!((1..model.nbodies).all(|b| model.idx_q[b] - bq == model.idx_v[b] - bv));
    let (q_j, v_j, tau_j) = (&q[bq..bq + nj], &v[bv..nv], &mut tau[bv..nv]);
    let (damping, friction) = (&model.damping[bv..nv], &model.friction[bv..nv]);
    let (lower, upper) = (&model.lower_limit[bv..nv], &model.upper_limit[bv..nv]);
    // Without friction (off, or zero on every joint, the usual model), the
    // loop without its branches, which vectorises: each joint's terms as
    // below (a zero friction term added to `0.0 + damping`, never −0.0,
    // changes nothing).
    if !params.friction || friction.iter().all(|&f| f == 0.0) {
        let (k, b) = (params.limit_stiffness, params.limit_damping);
        for (((((tau, &q), &qd), &d), &lo), &hi) in tau_j
            .iter_mut()
            .zip(q_j)
            .zip(v_j)
            .zip(damping)
            .zip(lower)
            .zip(upper)
        {
            let mut t = 0.0
                + if params.damping {
                    damping_torque(d, qd)
                } else {
                    0.0
                };
            if params.limits {
                t += limit_torque(q, qd, lo, hi, k, b);
            }
            *tau += t;
        }
        spring_torques(model, q, v, tau);
        return;
    }
    for j in 0..nj {
        let qd = v_j[j];
        let mut t = 0.0;
        if params.damping {
            t += damping_torque(damping[j], qd);
        }
        if params.friction {
            t += friction_torque(friction[j], qd, params.friction_epsilon);
        }
        if params.limits {
            t += limit_torque(
                q_j[j],
                qd,
                lower[j],
                upper[j],
                params.limit_stiffness,
                params.limit_damping,
            );
        }
        tau_j[j] += t;
    }
    spring_torques(model, q, v, tau);
}

/// Adds the model's joint springs `τ = −k q − b q̇` into `tau` (nv): the force
/// elements of compliant payloads, part of the load, so no switch of
/// [`PassiveParams`] turns them off. Their potential is
/// [`crate::energy::spring_energy`].
pub fn spring_torques(model: &Model, q: &[f64], v: &[f64], tau: &mut [f64]) {
    for s in &model.springs {
        tau[s.iv] -= s.stiffness * q[s.iq] + s.damping * v[s.iv];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_is_odd_and_bounded() {
        for qd in [-10.0, -0.3, -1e-3, 0.0, 1e-3, 0.3, 10.0] {
            let t = friction_torque(2.0, qd, 0.1);
            assert_eq!(t, -friction_torque(2.0, -qd, 0.1));
            assert!(t.abs() <= 2.0 && t * qd <= 0.0);
        }
    }

    /// Without friction, the branch-free loop gives each joint the bits of
    /// `0.0 + damping_torque + limit_torque` (the general loop's terms), on
    /// quad16 with joints inside, above and below their limits, moving
    /// either way, with each switch on and off.
    #[test]
    fn frictionless_loop_is_the_terms_sum() {
        use crate::model::{BaseKind, Model};
        let desc = crate::robots::builtin("quad16").unwrap();
        let mut model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let (bq, bv) = (model.base_nq(), model.base_nv());
        // (quad16's joints have no damping of their own)
        for (j, d) in model.damping[bv..].iter_mut().enumerate() {
            *d = 0.05 * (j as f64 + 1.0);
        }
        let mut q = crate::robots::nominal_q("quad16").unwrap();
        let v: Vec<f64> = (0..model.nv)
            .map(|i| (i as f64 * 0.9).sin() * 3.0)
            .collect();
        for j in 0..model.nv - bv {
            let (lo, hi) = (model.lower_limit[bv + j], model.upper_limit[bv + j]);
            q[bq + j] = match j % 3 {
                0 => hi + 0.01 * (j as f64 + 1.0),
                1 => lo - 0.02 * (j as f64 + 1.0),
                _ => 0.5 * (lo + hi),
            };
        }
        for (damping, limits) in [(true, true), (true, false), (false, true)] {
            let params = PassiveParams {
                damping,
                friction: false,
                limits,
                ..PassiveParams::default()
            };
            let mut tau = vec![0.25; model.nv];
            add_passive_torques(&model, &params, &q, &v, &mut tau);
            let acting = tau[bv..].iter().filter(|&&t| t != 0.25).count();
            assert!(
                acting >= (model.nv - bv) / 2,
                "terms act on the joints: {acting}"
            );
            for j in 0..model.nv - bv {
                let (qj, qd) = (q[bq + j], v[bv + j]);
                let mut t = 0.0;
                if damping {
                    t += damping_torque(model.damping[bv + j], qd);
                }
                if limits {
                    t += limit_torque(
                        qj,
                        qd,
                        model.lower_limit[bv + j],
                        model.upper_limit[bv + j],
                        params.limit_stiffness,
                        params.limit_damping,
                    );
                }
                assert_eq!(tau[bv + j].to_bits(), (0.25 + t).to_bits(), "joint {j}");
            }
        }
    }

    #[test]
    fn limit_never_pulls_outward() {
        // beyond the upper limit but moving back fast: the damper would pull outward
        assert_eq!(limit_torque(1.01, -100.0, -1.0, 1.0, 1000.0, 5.0), 0.0);
        assert!(limit_torque(1.01, 0.0, -1.0, 1.0, 1000.0, 5.0) < 0.0);
        assert!(limit_torque(-1.01, 0.0, -1.0, 1.0, 1000.0, 5.0) > 0.0);
    }
}
