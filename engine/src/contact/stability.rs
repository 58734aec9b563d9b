//! Step-size check of a stiff ground contact, for `quadsim check`.
//!
//! An explicit integrator resolves a spring–damper of stiffness `k` and damping
//! `b` on a mass `m` only if the step `dt` is small against both time scales:
//! the period, `ω dt ≤ 0.5` with `ω = √(k/m)` (about 12 steps per oscillation;
//! RK4's stability limit on the imaginary axis is `ω dt ≈ 2.8`, semi-implicit
//! Euler's `ω dt = 2`), and the damping time, `b dt / m ≤ 1` (explicit Euler on
//! `v̇ = −(b/m) v` diverges past 2). Nonlinear laws are checked with their
//! tangent stiffness at the static depth under `m g`, `g` = 9.81 m/s².

use super::presets::GroundMaterial;
use crate::model::STANDARD_GRAVITY;

/// Which time scale the step fails to resolve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StabilityWarning {
    /// `ω dt` of the normal (or, `tangential`, anchor) spring exceeds 0.5.
    Stiffness {
        /// True for the tangential anchor spring.
        tangential: bool,
        /// `ω dt` (rad).
        omega_dt: f64,
    },
    /// `b dt / m` of the normal (or tangential) damper exceeds 1.
    Damping {
        /// True for the tangential damper.
        tangential: bool,
        /// `b dt / m`.
        b_dt_over_m: f64,
    },
}

impl std::fmt::Display for StabilityWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let dir = |t: bool| if t { "tangential" } else { "normal" };
        match *self {
            StabilityWarning::Stiffness {
                tangential,
                omega_dt,
            } => write!(
                f,
                "{} contact stiffness: ω·dt = {omega_dt:.3} > 0.5; reduce dt_s or the stiffness",
                dir(tangential)
            ),
            StabilityWarning::Damping {
                tangential,
                b_dt_over_m,
            } => write!(
                f,
                "{} contact damping: b·dt/m = {b_dt_over_m:.3} > 1; reduce dt_s or the damping",
                dir(tangential)
            ),
        }
    }
}

/// Warnings for `material` integrated with step `dt_s` on an effective mass
/// `m_eff_kg` (the mass a single contact carries, e.g. the robot's mass over
/// its number of stance feet). Empty when the step is fine.
pub fn check_stability(
    material: &GroundMaterial,
    dt_s: f64,
    m_eff_kg: f64,
) -> Vec<StabilityWarning> {
    let mut out = Vec::new();
    let g = STANDARD_GRAVITY.length();
    let depth = material.law.static_depth(material.stiffness, m_eff_kg * g);
    let k_n = material.law.stiffness_at(material.stiffness, depth);
    // Hunt–Crossley damping b δⁿ δ̇ acts with coefficient b δⁿ at that depth.
    let b_n = match material.law {
        super::law::NormalLaw::HuntCrossley { exponent } => material.damping * depth.powf(exponent),
        _ => material.damping,
    };
    let pairs = [
        (false, k_n, b_n),
        (
            true,
            material.tangential_stiffness_npm,
            material.tangential_damping_nspm,
        ),
    ];
    for (tangential, k, b) in pairs {
        let omega_dt = (k / m_eff_kg).sqrt() * dt_s;
        if omega_dt > 0.5 {
            out.push(StabilityWarning::Stiffness {
                tangential,
                omega_dt,
            });
        }
        let b_dt_over_m = b * dt_s / m_eff_kg;
        if b_dt_over_m > 1.0 {
            out.push(StabilityWarning::Damping {
                tangential,
                b_dt_over_m,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::presets::GroundPreset;

    /// Concrete under a 7 kg foot load: ω = √(1e5/7) ≈ 119.5 rad/s, so 1 ms
    /// passes (ω dt ≈ 0.12) and 5 ms fails (≈ 0.60); b dt/m crosses 1 at 7 ms.
    #[test]
    fn thresholds() {
        let c = GroundPreset::Concrete.material();
        assert!(check_stability(&c, 1e-3, 7.0).is_empty());
        let w = check_stability(&c, 5e-3, 7.0);
        assert_eq!(w.len(), 2, "{w:?}"); // normal and tangential stiffness
        assert!(
            matches!(w[0], StabilityWarning::Stiffness { tangential: false, omega_dt } if (omega_dt - 0.5976).abs() < 1e-3)
        );
        let w = check_stability(&c, 8e-3, 7.0);
        assert!(
            w.iter()
                .any(|x| matches!(x, StabilityWarning::Damping { .. }))
        );
    }
}
