//! quad16's closed-form leg IK ([`Quad16Leg::ik_clamped_angles`]) for its
//! four legs at once, one leg per AVX lane.
//!
//! The walker solves up to eight legs a control tick (every leg's joint
//! targets, the swing legs' feed-forward a step ahead, the stance legs'
//! level ankle). One solve is a short dependent chain of scalar arithmetic
//! around libm calls; four independent chains side by side fill the lanes
//! and let the CPU overlap the libm calls. Each arithmetic operation here
//! is the scalar solve's (`legs::quad16_leg`, `legs::ik::two_link_links`,
//! `linalg::hypot`, `wrap_angle`) in the same order, without fused
//! multiply–add, and `atan2` and `acos` are the very same calls, made per
//! lane: every lane is the scalar solve's result **bit for bit** (unit test
//! below, on targets inside, outside and under the legs' reach).

use crate::kernels::f64x4::{F4, M3, V3};
use crate::legs::Quad16Leg;
use crate::legs::quad16_leg::foot_arg;
use crate::rounding::{HALF_DOWN, TWO_52};
use core::arch::x86_64::{_CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ};
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// A complex number of the pitch plane (`z + i·x`, [`crate::legs::ik`])
/// per lane.
#[derive(Clone, Copy, Debug, Default)]
struct C4 {
    x: F4,
    y: F4,
}

impl C4 {
    /// Lane `k` from `v[k]`.
    fn from_lanes(v: [DVec2; 4]) -> C4 {
        C4 {
            x: F4::from_array(v.map(|c| c.x)),
            y: F4::from_array(v.map(|c| c.y)),
        }
    }

    /// `self − o` (glam's `DVec2 - DVec2`).
    #[inline]
    #[target_feature(enable = "avx")]
    fn sub(self, o: C4) -> C4 {
        C4 {
            x: self.x.sub(o.x),
            y: self.y.sub(o.y),
        }
    }

    /// `self + o`.
    #[inline]
    #[target_feature(enable = "avx")]
    fn add(self, o: C4) -> C4 {
        C4 {
            x: self.x.add(o.x),
            y: self.y.add(o.y),
        }
    }

    /// The complex product, as `ik::cmul` (glam's `DVec2::rotate`) forms it.
    #[inline]
    #[target_feature(enable = "avx")]
    fn mul(self, o: C4) -> C4 {
        C4 {
            x: self.x.mul(o.x).sub(self.y.mul(o.y)),
            y: self.y.mul(o.x).add(self.x.mul(o.y)),
        }
    }

    /// `self · s` (glam's `DVec2 * f64`).
    #[inline]
    #[target_feature(enable = "avx")]
    fn scale(self, s: F4) -> C4 {
        C4 {
            x: self.x.mul(s),
            y: self.y.mul(s),
        }
    }

    /// `|self|` (glam's `length`: `√(x·x + y·y)`).
    #[inline]
    #[target_feature(enable = "avx")]
    fn length(self) -> F4 {
        self.x.mul(self.x).add(self.y.mul(self.y)).sqrt()
    }
}

/// Four quad16 legs' constants in lanes, for [`solve`].
#[derive(Clone, Debug)]
pub(crate) struct Quad16Legs {
    mount_inv_rot: M3,
    mount_inv_trans: V3,
    /// The lateral offset `d` per lane.
    offset: F4,
    w1: C4,
    w4: C4,
    foot_level: C4,
    thigh: C4,
    thigh_len: F4,
    thigh_arg: F4,
    shank_len: F4,
    shank_arg: F4,
}

impl Quad16Legs {
    /// The four legs in lanes; `None` unless every thigh and shank has a
    /// positive finite length (the scalar solve's other branch, a free bend
    /// for a zero-length link, is not laned).
    pub(crate) fn new(legs: [&Quad16Leg; 4]) -> Option<Quad16Legs> {
        let ok = |l: f64| l > 0.0 && l.is_finite();
        if !legs
            .iter()
            .all(|l| ok(l.thigh.length_m) && ok(l.shank.length_m))
        {
            return None;
        }
        let f4 = |f: &dyn Fn(&Quad16Leg) -> f64| F4::from_array(legs.map(f));
        let c4 = |f: &dyn Fn(&Quad16Leg) -> DVec2| C4::from_lanes(legs.map(f));
        Some(Quad16Legs {
            mount_inv_rot: M3::from_lanes(legs.map(|l| l.mount_inv.rot)),
            mount_inv_trans: V3::from_lanes(legs.map(|l| l.mount_inv.trans)),
            offset: f4(&|l| l.offset_m),
            w1: c4(&|l| l.links[0]),
            w4: c4(&|l| l.links[3]),
            foot_level: c4(&|l| l.foot_level),
            thigh: c4(&|l| l.thigh.w),
            thigh_len: f4(&|l| l.thigh.length_m),
            thigh_arg: f4(&|l| l.thigh.arg_rad),
            shank_len: f4(&|l| l.shank.length_m),
            shank_arg: f4(&|l| l.shank.arg_rad),
        })
    }
}

/// `f(a[k], b[k])` per lane, for the libm calls.
#[inline(always)]
fn per_lane(a: F4, b: F4, f: impl Fn(f64, f64) -> f64) -> F4 {
    let (a, b) = (a.to_array(), b.to_array());
    F4::from_array(std::array::from_fn(|k| f(a[k], b[k])))
}

/// `f(a[k])` per lane, for the libm calls.
#[inline(always)]
fn per_lane1(a: F4, f: impl Fn(f64) -> f64) -> F4 {
    F4::from_array(a.to_array().map(f))
}

/// `sensors::noise::round_half_away` per lane.
#[inline]
#[target_feature(enable = "avx")]
fn round_half_away(x: F4) -> F4 {
    // `x`'s sign bit alone: the signed zero, and `copysign`'s sign
    let sign = x.and(F4::bits(1 << 63));
    let a = x.abs();
    let whole = a.add(F4::splat(HALF_DOWN)).trunc().or(sign);
    F4::select(
        a.cmp::<_CMP_LT_OQ>(F4::splat(0.5)),
        sign,
        F4::select(a.cmp::<_CMP_LT_OQ>(F4::splat(TWO_52)), whole, x),
    )
}

/// `f64::clamp` per lane (`x < min`: `min`; then `x > max`: `max`; NaN
/// stays).
#[inline]
#[target_feature(enable = "avx")]
fn clamp(x: F4, min: F4, max: F4) -> F4 {
    let x = F4::select(x.cmp::<_CMP_LT_OQ>(min), min, x);
    F4::select(x.cmp::<_CMP_GT_OQ>(max), max, x)
}

/// [`crate::legs::wrap_angle`] per lane.
#[inline]
#[target_feature(enable = "avx")]
fn wrap_angle(a: F4) -> F4 {
    let tau = F4::splat(TAU);
    let w = a.sub(tau.mul(round_half_away(a.div(tau))));
    F4::select(w.cmp::<_CMP_LE_OQ>(F4::splat(-PI)), w.add(tau), w)
}

/// `linalg::hypot` per lane (std's `hypot` in the lanes whose sum of
/// squares is out of its range).
#[inline]
#[target_feature(enable = "avx")]
fn hypot(a: F4, b: F4) -> F4 {
    let s = a.mul(a).add(b.mul(b));
    let in_range = s
        .cmp::<_CMP_GE_OQ>(F4::splat(f64::MIN_POSITIVE))
        .and(s.cmp::<_CMP_LT_OQ>(F4::splat(f64::MAX)));
    let r = s.sqrt();
    if in_range.to_array().iter().all(|m| m.to_bits() != 0) {
        return r;
    }
    per_lane(a, b, crate::linalg::hypot)
}

/// The legs' angles `[hip roll, hip pitch, knee, ankle]` (rad) that put leg
/// `k`'s foot point at `targets[k]` (base frame), each clamped onto its
/// reach: lane `k` is [`Quad16Leg::ik_clamped_angles`]' answer under
/// [`crate::legs::AnkleMode::FootPitch`]`(psi)` with knee sign
/// `bend_sign`, bit for bit. A lane whose target is not finite holds
/// meaningless angles (the scalar solve's [`crate::legs::IkError::NonFinite`]):
/// the caller checks.
#[target_feature(enable = "avx")]
pub(crate) fn solve(
    legs: &Quad16Legs,
    targets: &[DVec3; 4],
    psi: f64,
    bend_sign: f64,
) -> [[f64; 4]; 4] {
    // 1–2. the roll plane (`Quad16Leg::roll_plane`)
    let p = legs
        .mount_inv_rot
        .mul_vec3(V3::from_lanes(*targets))
        .add(legs.mount_inv_trans);
    let d_abs = legs.offset.abs();
    let r = hypot(p.y, p.z);
    let inside = r.cmp::<_CMP_LT_OQ>(d_abs);
    let z = F4::select(
        inside,
        F4::splat(0.0),
        r.sub(d_abs).mul(r.add(d_abs)).sqrt().neg(),
    );
    let (zs, offsets) = (z.to_array(), legs.offset.to_array());
    let roll_arg = per_lane(p.z, p.y, f64::atan2);
    let roll = wrap_angle(roll_arg.sub(F4::from_array(std::array::from_fn(|k| {
        foot_arg(zs[k], offsets[k])
    }))));
    // 3. the pitch chain (`Quad16Leg::pitch_chain`, `ik::two_link_links`)
    let foot = if psi.to_bits() == 0.0f64.to_bits() {
        legs.foot_level
    } else {
        let c = crate::legs::ik::cis(psi);
        C4 {
            x: F4::splat(c.x),
            y: F4::splat(c.y),
        }
        .mul(legs.w4)
    };
    let wrist = C4 { x: z, y: p.x }.sub(legs.w1).sub(foot);
    let (la, lb) = (legs.thigh_len, legs.shank_len);
    let r = wrist.length();
    let denom = F4::splat(2.0).mul(la).mul(lb);
    let cos_g = clamp(
        r.mul(r).sub(la.mul(la)).sub(lb.mul(lb)).div(denom),
        F4::splat(-1.0),
        F4::splat(1.0),
    );
    let sign = F4::splat(bend_sign);
    let gamma = sign.mul(per_lane1(cos_g, f64::acos));
    let theta_b = wrap_angle(gamma.sub(legs.shank_arg).add(legs.thigh_arg));
    let one = F4::splat(1.0);
    let sin_g = sign.mul(one.sub(cos_g).mul(one.add(cos_g)).sqrt());
    let wa = legs.thigh;
    let reach = wa.add(C4 { x: cos_g, y: sin_g }.mul(wa).scale(lb.div(la)));
    let rel = wrist.mul(C4 {
        x: reach.x,
        y: reach.y.neg(),
    });
    let theta_a = wrap_angle(per_lane(rel.y, rel.x, f64::atan2));
    let ankle = wrap_angle(F4::splat(psi).sub(theta_a).sub(theta_b));
    let (roll, pitch, knee, ankle) = (
        roll.to_array(),
        theta_a.to_array(),
        theta_b.to_array(),
        ankle.to_array(),
    );
    std::array::from_fn(|k| [roll[k], pitch[k], knee[k], ankle[k]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::legs::{AnkleMode, FootPoint, IkOptions, KneeBranch, LegKinematics};
    use crate::model::{BaseKind, Model};
    use rand::{Rng, SeedableRng};

    /// quad16's four legs placing `point(leg)` (foot frame).
    fn quad16_legs(shift_m: DVec3) -> [Quad16Leg; 4] {
        let desc = crate::robots::builtin("quad16").unwrap();
        let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
        std::array::from_fn(|k| {
            let LegKinematics::Quad16(l) = &legs[k] else {
                panic!("quad16's legs")
            };
            Quad16Leg::from_model(&model, l.foot_frame(), l.point_in_foot_m() + shift_m).unwrap()
        })
    }

    /// Every lane of [`solve`] is the scalar clamped solve's angles bit for
    /// bit: quad16's contact point (no lateral offset) and a point moved
    /// sideways (an offset, whose circle some targets fall inside), targets
    /// within, beyond and under each leg's reach, all three knee branches,
    /// a level foot and two foot pitches.
    #[test]
    fn lanes_give_the_scalar_solves_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut checked = 0;
        for shift in [DVec3::ZERO, DVec3::new(0.01, 0.04, -0.02)] {
            let legs = quad16_legs(shift);
            let lanes = Quad16Legs::new(std::array::from_fn(|k| &legs[k])).unwrap();
            for trial in 0..3_000 {
                let knee = [
                    KneeBranch::Nominal,
                    KneeBranch::Negative,
                    KneeBranch::Positive,
                ][trial % 3];
                let psi = [0.0, 0.3, -0.2][(trial / 3) % 3];
                let opts = IkOptions {
                    knee,
                    ankle: AnkleMode::FootPitch(psi),
                    ..IkOptions::default()
                };
                let scale = [0.05, 0.4, 0.8, 3.0][trial % 4];
                let targets: [DVec3; 4] = std::array::from_fn(|k| {
                    legs[k].mount().trans
                        + scale
                            * DVec3::new(
                                rng.random_range(-1.0..1.0),
                                rng.random_range(-1.0..1.0),
                                rng.random_range(-1.0..0.3),
                            )
                });
                let Some(got) = super::super::legs_ik(&lanes, &targets, &opts) else {
                    return; // no AVX2 on this CPU: the lanes never run
                };
                for k in 0..4 {
                    let (want, _) = legs[k].ik_clamped_angles(targets[k], &opts).unwrap();
                    assert_eq!(
                        got[k].map(f64::to_bits),
                        want.map(f64::to_bits),
                        "leg {k}, target {}, {opts:?}: {:?} against {want:?}",
                        targets[k],
                        got[k]
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 24_000);
    }
}
