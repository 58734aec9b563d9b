//! What the closed-form leg solvers share: options, errors, and the planar
//! two-link solve in complex form.
//!
//! # The pitch plane as the complex plane
//! Every leg here has a chain of joints about parallel `y` axes (hip pitch,
//! knee, and for quad16 the ankle). A point `(x, z)` of their common plane is
//! written as the complex number `w = z + i·x` (a [`DVec2`] `(z, x)`): a
//! rotation about `+y` by `θ`, `(x, z) ↦ (x cos θ + z sin θ, −x sin θ + z cos θ)`,
//! is then the product `w·e^{iθ}`. A pitch chain with link vectors `w₁, w₂, …`
//! (each in its parent's frame) places its tip at
//! `W = w₁ + e^{iθ₂}(w₂ + e^{iθ₃}(w₃ + …))`, and the `y` components of the links
//! add up to a constant lateral offset.

use glam::{DMat3, DVec2, DVec3};
use thiserror::Error;

/// Which of the two knee solutions to take, by the sign of the knee bend
/// (see [`knee_bend`]): the signed angle from the thigh to the segment from the
/// knee to the wrist point, zero for a straight leg. For the built-ins' joint
/// chains (links along the leg at zero angle) and a held foot pitch, the bend
/// is the knee angle itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum KneeBranch {
    /// The branch of the robot's nominal stance: negative for quad16 (knee
    /// angle −0.6 rad, the knee behind the hip–ankle line), positive for
    /// quad12 (knee angle π/3, the knee above the hip–foot line).
    #[default]
    Nominal,
    /// Negative bend.
    Negative,
    /// Positive bend.
    Positive,
}

impl KneeBranch {
    /// `±1`, with `nominal` standing for [`KneeBranch::Nominal`].
    pub(crate) fn sign(self, nominal: f64) -> f64 {
        match self {
            KneeBranch::Nominal => nominal,
            KneeBranch::Negative => -1.0,
            KneeBranch::Positive => 1.0,
        }
    }
}

/// What a 4-DOF leg's ankle does (the 3-DOF leg has no ankle and ignores it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnkleMode {
    /// Hold the foot's pitch in the leg plane: hip pitch + knee + ankle = this
    /// angle (rad); 0 keeps the foot level with the torso's x axis.
    FootPitch(f64),
    /// Hold the ankle joint at this angle (rad).
    Angle(f64),
}

impl Default for AnkleMode {
    fn default() -> Self {
        AnkleMode::FootPitch(0.0)
    }
}

/// Options of the inverse kinematics and of the velocity map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkOptions {
    /// Knee branch (default: the nominal stance's).
    pub knee: KneeBranch,
    /// Ankle of a 4-DOF leg (default: foot level).
    pub ankle: AnkleMode,
    /// Damping λ (m) of the damped least-squares velocity map
    /// `q̇ = Jᵀ(JJᵀ + λ²I)⁻¹ v`: the joint speed stays below `|v| / (2λ)` at a
    /// straight or folded knee, and a well-conditioned leg (smallest singular
    /// value σ) sees a relative error of about `(λ/σ)²`. 0 gives the exact
    /// inverse, which fails ([`IkError::Singular`]) where the singular values
    /// of the leg Jacobian differ by more than about 10⁶. Default 1 mm.
    pub velocity_damping_m: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            knee: KneeBranch::Nominal,
            ankle: AnkleMode::default(),
            velocity_damping_m: 1e-3,
        }
    }
}

/// Why a foot target has no solution.
#[derive(Debug, Error, Clone, Copy, PartialEq)]
pub enum IkError {
    /// The target has a NaN or infinite coordinate.
    #[error("foot target ({x}, {y}, {z}) m is not finite", x = target_m.x, y = target_m.y, z = target_m.z)]
    NonFinite {
        /// The target (m, body frame).
        target_m: DVec3,
    },
    /// The wrist point (the ankle for a foot-pitch-holding 4-DOF leg, else the
    /// foot point) would have to be `distance_m` from the hip pitch joint, in
    /// the leg plane; the thigh and shank reach from `min_reach_m` (knee fully
    /// folded) to `max_reach_m` (knee straight).
    #[error(
        "foot target out of reach: wrist point {distance_m:.4} m from the hip pitch joint, reach {min_reach_m:.4}..{max_reach_m:.4} m"
    )]
    OutOfReach {
        /// Hip-pitch-joint-to-wrist distance needed (m).
        distance_m: f64,
        /// Shortest reach (m).
        min_reach_m: f64,
        /// Longest reach (m).
        max_reach_m: f64,
    },
    /// The target is closer to the first joint's axis (hip roll or yaw) than
    /// the leg's constant offset along the pitch axes, which no angle removes.
    #[error(
        "foot target {distance_m:.4} m from the hip's first joint axis, inside the leg's lateral offset {offset_m:.4} m"
    )]
    InsideOffset {
        /// Distance of the target from the axis (m).
        distance_m: f64,
        /// The leg's lateral offset (m).
        offset_m: f64,
    },
    /// The exact velocity map (`velocity_damping_m` = 0) at a singular pose.
    #[error("leg Jacobian is singular (straight or folded knee); use a damping > 0")]
    Singular,
}

/// A clamped solution: the joint angles and the foot point they reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkClamped<const N: usize> {
    /// Joint angles (rad, leg order).
    pub angles_rad: [f64; N],
    /// The foot point these angles place (m, body frame): the target when it
    /// is reachable, else its projection onto the reachable workspace.
    pub foot_m: DVec3,
    /// Whether the target was out of reach and was projected.
    pub clamped: bool,
}

/// `e^{iθ}` (glam's `DVec2::from_angle`, by [`crate::trig::sin_cos`] or,
/// with [`crate::trig::LEGS_USE_LIBM`] off, std's).
#[inline]
pub(crate) fn cis(theta: f64) -> DVec2 {
    let (s, c) = if crate::trig::LEGS_USE_LIBM {
        crate::trig::sin_cos(theta)
    } else {
        theta.sin_cos()
    };
    DVec2::new(c, s)
}

/// `e^{iθ}` of four angles at once ([`crate::kernels::sin_cos_x4`]; the same
/// bits as [`cis`] of each).
#[inline]
pub(crate) fn cis4(theta: [f64; 4]) -> [DVec2; 4] {
    if crate::trig::LEGS_USE_LIBM {
        let (s, c) = crate::kernels::sin_cos_x4(theta);
        [0, 1, 2, 3].map(|k| DVec2::new(c[k], s[k]))
    } else {
        theta.map(cis)
    }
}

/// The rotation about `+x` by the angle whose `e^{iθ}` is `cs` (glam's
/// `DMat3::from_rotation_x`).
#[inline]
pub(crate) fn rotation_x(cs: DVec2) -> DMat3 {
    DMat3::from_cols(
        DVec3::X,
        DVec3::new(0.0, cs.x, cs.y),
        DVec3::new(0.0, -cs.y, cs.x),
    )
}

/// The rotation about `+z` by the angle whose `e^{iθ}` is `cs` (glam's
/// `DMat3::from_rotation_z`).
#[inline]
pub(crate) fn rotation_z(cs: DVec2) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(cs.x, cs.y, 0.0),
        DVec3::new(-cs.y, cs.x, 0.0),
        DVec3::Z,
    )
}

/// Complex product.
#[inline]
pub(crate) fn cmul(a: DVec2, b: DVec2) -> DVec2 {
    a.rotate(b)
}

/// Argument of a complex number in (−π, π].
#[inline]
pub(crate) fn arg(a: DVec2) -> f64 {
    a.y.atan2(a.x)
}

/// The pitch-plane complex number `z + i·x` of a 3-vector's x and z.
#[inline]
pub(crate) fn planar(v: DVec3) -> DVec2 {
    DVec2::new(v.z, v.x)
}

/// An angle wrapped to (−π, π].
#[inline]
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    // `round` without its library call on the baseline x86-64 target
    // (three to four per leg IK): the same bits for every input
    let w = a - TAU * crate::rounding::round_half_away(a / TAU);
    if w <= -PI { w + TAU } else { w }
}

/// The bend `γ` (rad, in (−π, π]) of a two-link chain `wa + e^{iθb} ub`: the
/// angle from the first link to the second, 0 when straight.
#[inline]
pub fn knee_bend(wa: DVec2, ub: DVec2, theta_b: f64) -> f64 {
    wrap_angle(theta_b + arg(ub) - arg(wa))
}

/// A link of a two-link chain with its length and argument, which
/// [`two_link_links`] reads: a leg's fixed links are measured once when the
/// leg is built instead of at every solve (two `atan2` and two square roots
/// of four `atan2` and three square roots per solve; the same values, so the
/// same bits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Link {
    /// The link (complex form).
    pub w: DVec2,
    /// `|w|` (m).
    pub length_m: f64,
    /// `arg w` (rad).
    pub arg_rad: f64,
}

impl Link {
    /// `w` with its length and argument.
    #[inline]
    pub(crate) fn new(w: DVec2) -> Link {
        Link {
            w,
            length_m: w.length(),
            arg_rad: arg(w),
        }
    }
}

/// Solves `e^{iθa}(wa + e^{iθb} ub) = target` for `(θa, θb)` on the branch
/// `sign(γ) = bend_sign` (law of cosines for `γ`, then the direction).
///
/// With `clamp`, a target out of the annulus `| |wa| − |ub| | ≤ |target| ≤
/// |wa| + |ub|` is moved radially onto it (the nearest point of the
/// annulus); the returned flag says so. Without, such a target is
/// [`IkError::OutOfReach`].
pub(crate) fn two_link(
    wa: DVec2,
    ub: DVec2,
    target: DVec2,
    bend_sign: f64,
    clamp: bool,
) -> Result<(f64, f64, bool), IkError> {
    two_link_links(&Link::new(wa), &Link::new(ub), target, bend_sign, clamp)
}

/// [`two_link`] with the links' lengths and arguments given. Always inlined:
/// the leg IK's hot path, which the compiler's heuristic left out of line
/// once `wrap_angle`'s rounding became a call it inlines (+76 instructions
/// a robot-step).
#[inline(always)]
pub(crate) fn two_link_links(
    a: &Link,
    b: &Link,
    target: DVec2,
    bend_sign: f64,
    clamp: bool,
) -> Result<(f64, f64, bool), IkError> {
    let (wa, ub) = (a.w, b.w);
    let (la, lb) = (a.length_m, b.length_m);
    let r = target.length();
    let (min_reach, max_reach) = ((la - lb).abs(), la + lb);
    // round-off allowance: the target of an exact FK may land a few ulps outside
    let tol = 1e-12 * max_reach;
    let out = r > max_reach + tol || r < min_reach - tol;
    if out && !clamp {
        return Err(IkError::OutOfReach {
            distance_m: r,
            min_reach_m: min_reach,
            max_reach_m: max_reach,
        });
    }
    // a zero-length link leaves the bend free: take the straight leg
    let denom = 2.0 * la * lb;
    let cos_g = if denom > 0.0 {
        ((r * r - la * la - lb * lb) / denom).clamp(-1.0, 1.0)
    } else {
        1.0
    };
    let gamma = bend_sign * cos_g.acos();
    let theta_b = wrap_angle(gamma - b.arg_rad + a.arg_rad);
    // The wrist the bent chain reaches, `wa + e^{iθb} ub`. With both links
    // of nonzero length `e^{iθb} ub = e^{iγ} (wa/|wa|) |ub|`, and `e^{iγ}`
    // is `(cos γ, sin γ)` from the law of cosines itself: no sine and cosine
    // of θb (one libm call fewer per solve).
    let reach = if denom > 0.0 {
        let sin_g = bend_sign * ((1.0 - cos_g) * (1.0 + cos_g)).sqrt();
        wa + cmul(DVec2::new(cos_g, sin_g), wa) * (lb / la)
    } else {
        wa + cmul(cis(theta_b), ub)
    };
    // θa = arg target − arg reach, as one argument: `arg(target · conj(reach))`
    // (one `atan2` fewer per solve)
    let theta_a = wrap_angle(arg(cmul(target, DVec2::new(reach.x, -reach.y))));
    Ok((theta_a, theta_b, out))
}

/// Damped least squares `x = Aᵀ(AAᵀ + λ²I)⁻¹ b` (λ = 0: `A⁻¹ b`).
pub(crate) fn dls_solve(a: DMat3, b: DVec3, lambda_m: f64) -> Result<DVec3, IkError> {
    let m = a * a.transpose() + DMat3::from_diagonal(DVec3::splat(lambda_m * lambda_m));
    let det = m.determinant();
    // scale-aware singularity test: det against the cube of the mean
    // eigenvalue (fails when the singular values of J differ by ~10⁶)
    let scale = (m.x_axis.x + m.y_axis.y + m.z_axis.z) / 3.0;
    if !(det.is_finite() && det > 1e-12 * scale.powi(3)) {
        return Err(IkError::Singular);
    }
    Ok(a.transpose() * (m.inverse() * b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        use std::f64::consts::PI;
        for a in [-7.0, -PI, -3.0, 0.0, 3.0, PI, 7.0, 100.0] {
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            assert!(((a - w) / (2.0 * PI) - ((a - w) / (2.0 * PI)).round()).abs() < 1e-12);
        }
    }

    #[test]
    fn complex_product_is_a_rotation_about_y() {
        let (x, z, t) = (0.3, -0.7, 0.9_f64);
        let rotated = DMat3::from_rotation_y(t) * DVec3::new(x, 0.0, z);
        let w = cmul(planar(DVec3::new(x, 0.0, z)), cis(t));
        assert!((w - planar(rotated)).length() < 1e-15);
    }
}
