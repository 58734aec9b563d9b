//! Step-size check of a stiff ground contact, for `quadsim check`.
//!
//! An explicit integrator resolves a spring–damper of stiffness `k` and damping
//! `b` on a mass `m` only if the step `dt` is small against both time scales:
//! the period, `ω dt ≤ 0.5` with `ω = √(k/m)` (about 12 steps per oscillation;
//! RK4's stability limit on the imaginary axis is `ω dt ≈ 2.8`, semi-implicit
//! Euler's `ω dt = 2`), and the damping time, `b dt / m ≤ 1` (explicit Euler on
//! `v̇ = −(b/m) v` diverges past 2). Nonlinear laws are checked with their
//! tangent stiffness at the static depth under `m g`, `g` = 9.81 m/s².

use crate::material::GroundMaterial;
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
    check_stability_split(material, dt_s, m_eff_kg, m_eff_kg)
}

/// As [`check_stability`], with separate effective masses for the normal and
/// the tangential direction (see [`contact_apparent_masses`]): the normal
/// spring's static depth is still taken under `m_normal_kg · g`.
pub fn check_stability_split(
    material: &GroundMaterial,
    dt_s: f64,
    m_normal_kg: f64,
    m_tangential_kg: f64,
) -> Vec<StabilityWarning> {
    let m_eff_kg = m_normal_kg;
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
        let m_eff_kg = if tangential {
            m_tangential_kg
        } else {
            m_normal_kg
        };
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

/// Apparent masses (kg) of a contact point of a free robot at configuration
/// `q`: along the ground normal `m_n = 1 / (nᵀ Λ⁻¹ n)` and the lightest one in
/// the tangent plane `m_t = 1 / λ_max(Tᵀ Λ⁻¹ T)`, where `Λ⁻¹ = J M⁻¹ Jᵀ` is
/// the inverse operational-space inertia of the point (`J` its point
/// Jacobian). These are the masses a contact spring–damper actually drives:
/// quad16's foot, free to roll about its ankle, is only ~0.2 kg sideways.
/// Allocates (a check, not a step).
pub fn contact_apparent_masses(
    model: &crate::Model,
    data: &mut crate::Data,
    q: &[f64],
    body: usize,
    point_in_body: glam::DVec3,
    normal: glam::DVec3,
) -> Option<(f64, f64)> {
    use glam::{DMat2, DVec2, DVec3};
    let nv = model.nv;
    let mut m = crate::crba::crba(model, data, q).to_vec();
    if !crate::linalg::cholesky_dense(&mut m, nv) {
        return None;
    }
    let p = data.body_point_world(body, point_in_body);
    let jac = crate::jacobian::point_jacobian(model, data, body, p).to_vec();
    // Λ⁻¹ = J M⁻¹ Jᵀ, column by column
    let mut cols = [DVec3::ZERO; 3];
    for (c, col) in cols.iter_mut().enumerate() {
        let mut x: Vec<f64> = (0..nv).map(|i| jac[c * nv + i]).collect();
        crate::linalg::cholesky_dense_solve(&m, nv, &mut x);
        let y: [f64; 3] = std::array::from_fn(|r| (0..nv).map(|i| jac[r * nv + i] * x[i]).sum());
        *col = DVec3::from_array(y);
    }
    let inv_lambda = glam::DMat3::from_cols(cols[0], cols[1], cols[2]);
    let n = normal.normalize();
    let t1 = n.any_orthonormal_vector();
    let t2 = n.cross(t1);
    let m_n = 1.0 / n.dot(inv_lambda * n);
    let (a, b, d) = (
        t1.dot(inv_lambda * t1),
        t1.dot(inv_lambda * t2),
        t2.dot(inv_lambda * t2),
    );
    let block = DMat2::from_cols(DVec2::new(a, b), DVec2::new(b, d));
    // largest eigenvalue of a symmetric 2×2
    let tr = block.x_axis.x + block.y_axis.y;
    let det = block.determinant();
    let lmax = 0.5 * tr + (0.25 * tr * tr - det).max(0.0).sqrt();
    Some((m_n, 1.0 / lmax))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::GroundPreset;

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

#[cfg(test)]
mod apparent_mass_tests {
    use super::*;
    use crate::description::{RobotBuilder, Shape};
    use crate::model::{BaseKind, Model};
    use crate::spatial::Transform;
    use glam::DVec3;

    /// A free sphere of mass m: every direction at its centre has mass m.
    #[test]
    fn free_body_centre_has_its_own_mass() {
        let d = RobotBuilder::new("ball")
            .link("b")
            .mass(3.0)
            .shape(Transform::IDENTITY, Shape::Sphere { radius_m: 0.1 })
            .done()
            .build();
        let model = Model::from_description(&d, BaseKind::Floating).unwrap();
        let mut data = crate::Data::new(&model);
        let (mn, mt) = contact_apparent_masses(
            &model,
            &mut data,
            &model.neutral_q(),
            0,
            DVec3::ZERO,
            DVec3::Z,
        )
        .unwrap();
        assert!((mn - 3.0).abs() < 1e-12 && (mt - 3.0).abs() < 1e-12);
        // at the surface point below the centre, sideways motion can also roll
        // the sphere: 1/m_t = 1/m + r²/I = 1/3 + 0.01/(0.4·3·0.01)
        let (mn, mt) = contact_apparent_masses(
            &model,
            &mut data,
            &model.neutral_q(),
            0,
            DVec3::new(0.0, 0.0, -0.1),
            DVec3::Z,
        )
        .unwrap();
        assert!((mn - 3.0).abs() < 1e-12);
        let expect = 1.0 / (1.0 / 3.0 + 0.01 / (0.4 * 3.0 * 0.01));
        assert!((mt - expect).abs() < 1e-12, "{mt} vs {expect}");
    }
}
