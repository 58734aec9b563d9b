//! Stick–slip Coulomb friction with a tangential anchor spring.
//!
//! While a contact sticks, the ground holds it with a spring–damper anchored at
//! the touchdown point `a` (world, on the ground):
//! `f_trial = −k_t e − b_t v_t`, with `e` the tangential part of
//! `x − a` (`x`: the contact's current ground point) and `v_t` the tangential
//! velocity of the body's material point at the contact.
//! Past the cone, `|f_trial| > μ f_n`, the contact slides: the force is
//! `μ f_n` along `f_trial`, and [`dragged_anchor`] moves the anchor so that the
//! spring alone sits at the friction limit. While sliding steadily the anchor
//! trails the contact along its path, so `e ∥ v_t` and the force is
//! `−μ f_n v_t/|v_t|`, Coulomb's law; taking the direction from `f_trial`
//! rather than from `v_t` keeps the force a continuous function of the state
//! where `v_t` passes through zero (stick ↔ slip), which RK4 needs.

use glam::DVec3;

/// Tangential force (N, world) and whether the contact slides.
#[inline]
pub fn stick_slip(
    k_t: f64,
    b_t: f64,
    mu: f64,
    normal_force_n: f64,
    displacement_t_m: DVec3,
    velocity_t_mps: DVec3,
) -> (DVec3, bool) {
    let trial = -k_t * displacement_t_m - b_t * velocity_t_mps;
    let limit = mu * normal_force_n;
    let t2 = trial.length_squared();
    if t2 <= limit * limit {
        (trial, false)
    } else {
        (trial * (limit / t2.sqrt()), true)
    }
}

/// Anchor (world) that puts the tangential spring exactly at `force_t_n`:
/// `−k_t (x − a) = f_t`, i.e. `a = x + f_t / k_t`. Used once per step after a
/// slipping evaluation, with `f_t` the capped force, so the spring sits at the
/// friction limit.
#[inline]
pub fn dragged_anchor(ground_point_m: DVec3, force_t_n: DVec3, k_t: f64) -> DVec3 {
    ground_point_m + force_t_n / k_t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inside the cone the trial force passes unchanged; outside it is capped
    /// at μ f_n along the trial direction, and the dragged anchor reproduces
    /// exactly the capped force from the spring alone.
    #[test]
    fn cone_and_anchor() {
        let (f, slip) = stick_slip(
            1e4,
            0.0,
            0.5,
            100.0,
            DVec3::new(0.001, 0.0, 0.0),
            DVec3::ZERO,
        );
        assert!(!slip);
        assert_eq!(f, DVec3::new(-10.0, 0.0, 0.0));
        let e = DVec3::new(0.01, 0.02, 0.0);
        let (f, slip) = stick_slip(1e4, 0.0, 0.5, 100.0, e, DVec3::ZERO);
        assert!(slip);
        assert!((f.length() - 50.0).abs() < 1e-12);
        assert!(f.normalize().dot(-e.normalize()) > 1.0 - 1e-12);
        let x = DVec3::new(1.0, 2.0, 0.0);
        let a = dragged_anchor(x, f, 1e4);
        let (f2, _) = stick_slip(1e4, 0.0, 0.5, 100.0, x - a, DVec3::ZERO);
        assert!((f2 - f).length() < 1e-9);
    }
}
