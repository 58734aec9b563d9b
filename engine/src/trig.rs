//! Sine and cosine of joint angles for every kinematics path: one answer,
//! [`libm::sincos`] (FreeBSD msun / fdlibm, error < 1 ulp), computed one value
//! at a time ([`sin_cos`]) or four at a time in SIMD lanes (`kernels::sin_cos_x4`,
//! [`sin_cos_lanes`]) with **the same bits** in every lane.
//!
//! Why not `f64::sin_cos`: std calls the platform's libm (glibc's `sincos`,
//! ~107 instructions a call through the PLT), one scalar call per lane even
//! where the kinematics run four legs or four robots in AVX lanes; forward
//! kinematics called it ~45 times per robot-step.
//!
//! Why hand-written lanes: no crate gives a vector sine on stable Rust that
//! matches a scalar function bit for bit. `wide`'s `f64x4::sin_cos` is a
//! Cody–Waite reduction with its own polynomial (no scalar twin, accuracy
//! unstated); SLEEF's Rust port needs nightly `core::simd`. So
//! [`sin_cos_lanes`] repeats libm's own algorithm operation for operation —
//! msun's `__rem_pio2` first reduction round (`x − n·π/2` with π/2 in a
//! 33-bit head and a 53-bit tail, `n` chosen by the same high-word
//! thresholds), `__kernel_sin` and `__kernel_cos`, and the quadrant swap —
//! without branches, so that it vectorises. A lane whose argument msun would
//! treat differently (|x| ≥ 2²⁰·π/2, not finite, or a reduction that cancelled
//! more than 16 bits and that msun refines in a second round) is recomputed by
//! [`libm::sincos`] itself. Every lane therefore equals [`libm::sincos`] bit
//! for bit, which the tests check on a dense sample and at the hard points;
//! with no fused multiply–add anywhere, the generic and the AVX2 builds give
//! the same bits too. This is the exception the project's "use the crate"
//! rule allows: the crate's answer, in lanes, checked against the crate, with
//! a benchmark (`cargo bench -p quadsim-engine --bench trig`) showing it
//! faster.
//!
//! Accuracy against std (glibc, correctly rounded in practice): at most
//! 1 ulp apart for |x| ≤ 2²⁰·π/2 ≈ 1.6·10⁶ rad (test
//! `within_one_ulp_of_std`).

// msun's constants by their bits (e_rem_pio2.c, k_sin.c, k_cos.c).
/// 1.5·2⁵²: adding it rounds a double of magnitude < 2⁵¹ to an integer.
pub(crate) const TO_INT: f64 = 1.5 / f64::EPSILON;
/// 2/π.
pub(crate) const INV_PIO2: f64 = f64::from_bits(0x3fe4_5f30_6dc9_c883);
/// The first 33 bits of π/2 (so `n · PIO2_1` is exact for |n| < 2²⁰).
pub(crate) const PIO2_1: f64 = f64::from_bits(0x3ff9_21fb_5440_0000);
/// π/2 − `PIO2_1`.
pub(crate) const PIO2_1T: f64 = f64::from_bits(0x3dd0_b461_1a62_6331);
/// `__kernel_sin`'s polynomial.
pub(crate) const S1: f64 = f64::from_bits(0xbfc5_5555_5555_5549);
pub(crate) const S2: f64 = f64::from_bits(0x3f81_1111_1110_f8a6);
pub(crate) const S3: f64 = f64::from_bits(0xbf2a_01a0_19c1_61d5);
pub(crate) const S4: f64 = f64::from_bits(0x3ec7_1de3_57b1_fe7d);
pub(crate) const S5: f64 = f64::from_bits(0xbe5a_e5e6_8a2b_9ceb);
pub(crate) const S6: f64 = f64::from_bits(0x3de5_d93a_5acf_d57c);
/// `__kernel_cos`'s polynomial.
pub(crate) const C1: f64 = f64::from_bits(0x3fa5_5555_5555_554c);
pub(crate) const C2: f64 = f64::from_bits(0xbf56_c16c_16c1_5177);
pub(crate) const C3: f64 = f64::from_bits(0x3efa_01a0_19cb_1590);
pub(crate) const C4: f64 = f64::from_bits(0xbe92_7e4f_809c_52ad);
pub(crate) const C5: f64 = f64::from_bits(0x3e21_ee9e_bdb4_b1c4);
pub(crate) const C6: f64 = f64::from_bits(0xbda8_fae9_be88_38d4);

/// msun compares the high 32 bits of |x| against these words; |x| ≤ the
/// largest double with high word `hw` is the same test.
const fn hw_max(hw: u64) -> f64 {
    f64::from_bits((hw << 32) | 0xffff_ffff)
}
/// |x| ~≤ π/4: no reduction, `__kernel_sin` with `iy = 0`.
pub(crate) const PIO4: f64 = hw_max(0x3fe9_21fb);
/// |x| ~≤ 3π/4, 5π/4, 7π/4, 9π/4: `n` = 1, 2, 3, 4 (times the sign of x).
pub(crate) const PIO4_3: f64 = hw_max(0x4002_d97c);
pub(crate) const PIO4_5: f64 = hw_max(0x400f_6a7a);
pub(crate) const PIO4_7: f64 = hw_max(0x4015_fdbc);
pub(crate) const PIO4_9: f64 = hw_max(0x401c_463b);
/// Above |x| ~≥ 2²⁰·π/2 msun reduces with its multi-word π/2: [`libm::sincos`].
pub(crate) const MEDIUM_END: f64 = f64::from_bits(0x4139_21fb_u64 << 32);
/// |x| < 2⁻²⁷·√2: (sin, cos) = (x, 1).
pub(crate) const TINY: f64 = f64::from_bits(0x3e46_a09e_u64 << 32);
/// x with its low word cleared at π/2, π, 3π/2, 2π: where msun's reduction
/// below 9π/4 goes to `medium` (which may refine).
pub(crate) const HI_PIO2: f64 = f64::from_bits(0x3ff9_21fb_u64 << 32);
pub(crate) const HI_PI: f64 = f64::from_bits(0x4009_21fb_u64 << 32);
pub(crate) const HI_3PIO2: f64 = f64::from_bits(0x4012_d97c_u64 << 32);
pub(crate) const HI_2PI: f64 = f64::from_bits(0x4019_21fb_u64 << 32);
/// 2⁻¹⁶.
pub(crate) const TWO_M16: f64 = 1.0 / 65536.0;

/// Lane-wise arithmetic on `[f64; L]`: each call is one plain loop, which
/// LLVM turns into SIMD instructions (as in [`crate::batch::lanes`]); no
/// branch inside, so that the loops stay vectorisable.
#[inline(always)]
fn map<const L: usize>(a: [f64; L], f: impl Fn(f64) -> f64) -> [f64; L] {
    let mut out = a;
    for k in 0..L {
        out[k] = f(a[k]);
    }
    out
}

#[inline(always)]
fn zip<const L: usize>(a: [f64; L], b: [f64; L], f: impl Fn(f64, f64) -> f64) -> [f64; L] {
    let mut out = a;
    for k in 0..L {
        out[k] = f(a[k], b[k]);
    }
    out
}

#[inline(always)]
fn zip3<const L: usize>(
    a: [f64; L],
    b: [f64; L],
    c: [f64; L],
    f: impl Fn(f64, f64, f64) -> f64,
) -> [f64; L] {
    let mut out = a;
    for k in 0..L {
        out[k] = f(a[k], b[k], c[k]);
    }
    out
}

/// Lane-wise [`and`].
#[inline(always)]
fn and2<const L: usize>(a: [f64; L], b: [f64; L]) -> [f64; L] {
    zip(a, b, and)
}

/// A lane mask as a double: all bits set (a NaN) where `b`, else +0.
#[inline(always)]
fn mask(b: bool) -> f64 {
    f64::from_bits(if b { u64::MAX } else { 0 })
}

/// Bitwise AND of two masks.
#[inline(always)]
fn and(a: f64, b: f64) -> f64 {
    f64::from_bits(a.to_bits() & b.to_bits())
}

/// Bitwise OR of two masks.
#[inline(always)]
fn or(a: f64, b: f64) -> f64 {
    f64::from_bits(a.to_bits() | b.to_bits())
}

/// `m ? a : b` by bits, `m` from [`mask`].
#[inline(always)]
fn select(m: f64, a: f64, b: f64) -> f64 {
    let m = m.to_bits();
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// Sine and cosine of each lane, bit for bit [`libm::sincos`] of that lane
/// (see [the module doc](self)): msun's `sincos` without branches for
/// |x| < 2²⁰·π/2 where it needs no second reduction round, [`libm::sincos`]
/// itself for the other lanes. Inlined into its caller: in an AVX2 function
/// LLVM turns the arithmetic into `f64x4` instructions but leaves parts of the
/// lane-mask logic scalar, so `kernels::sin_cos_x4` and the legs' lanes run the same
/// operations as AVX intrinsics instead (`kernels::f64x4`'s `F4::sin_cos`, 134
/// instructions for four angles; glibc's `sincos` takes ~110 for one). This
/// plain-Rust form serves the robot-lanes batch, the generic build and, with
/// `L` = 1, as the reference the tests hold every path to.
#[inline(always)]
pub fn sin_cos_lanes<const L: usize>(x: [f64; L]) -> ([f64; L], [f64; L]) {
    let ax = map(x, f64::abs);
    // n = rint(x·2/π), as msun picks it: by high-word thresholds up to 9π/4,
    // by rounding (`medium`) above; ±0 below π/4.
    let n_thresholds = zip(x, ax, |x, ax| {
        let one = |b: bool| select(mask(b), 1.0, 0.0);
        let n = one(ax > PIO4) + one(ax > PIO4_3) + one(ax > PIO4_5) + one(ax > PIO4_7);
        n.copysign(x)
    });
    let n_rounded = map(x, |x| (x * INV_PIO2 + TO_INT) - TO_INT);
    let f_n = zip3(ax, n_thresholds, n_rounded, |ax, t, r| {
        select(mask(ax <= PIO4_9), t, r)
    });
    // First round of `__rem_pio2`: y0 + y1 = x − n·π/2 to ~85 bits.
    let r = zip(x, f_n, |x, n| x - n * PIO2_1);
    let w = map(f_n, |n| n * PIO2_1T);
    let y0 = zip(r, w, |r, w| r - w);
    let y1 = zip3(r, y0, w, |r, y0, w| (r - y0) - w);
    // Lanes for libm itself: |x| ≥ 2²⁰·π/2 or not finite, or where msun's
    // `medium` refines (the first round lost more than 16 bits: |y0| <
    // 2^(exponent of x − 16)); below 9π/4 msun goes there only for the high
    // words of π/2, π, 3π/2, 2π.
    let hi = map(x, |x| f64::from_bits(x.to_bits() & 0x7fff_ffff_0000_0000));
    let near_multiple = map(hi, |hi| {
        or(
            or(mask(hi == HI_PIO2), mask(hi == HI_PI)),
            or(mask(hi == HI_3PIO2), mask(hi == HI_2PI)),
        )
    });
    let pow2 = map(x, |x| f64::from_bits(x.to_bits() & 0x7ff0_0000_0000_0000));
    let lost = zip(y0, pow2, |y0, p| mask(y0.abs() < p * TWO_M16));
    let reduced = map(ax, |ax| mask(ax > PIO4));
    let medium = map(ax, |ax| mask(ax > PIO4_9));
    let refined = zip3(and2(lost, reduced), medium, near_multiple, |a, m, n| {
        and(a, or(m, n))
    });
    // (NaN: not below the bound either)
    let out_of_range = map(ax, |ax| mask(ax >= MEDIUM_END || ax.is_nan()));
    let fallback = zip(out_of_range, refined, or);
    // `__kernel_sin(y0, y1, iy)` and `__kernel_cos(y0, y1)`.
    let z = map(y0, |y| y * y);
    let zz = map(z, |z| z * z);
    let rs = zip(z, zz, |z, zz| {
        S2 + z * (S3 + z * S4) + z * zz * (S5 + z * S6)
    });
    let v = zip(z, y0, |z, y0| z * y0);
    let sin_iy0 = zip3(y0, v, zip(z, rs, |z, rs| S1 + z * rs), |y0, v, p| {
        y0 + v * p
    });
    let t = zip3(z, y1, zip(v, rs, |v, rs| v * rs), |z, y1, vr| {
        z * (0.5 * y1 - vr) - y1
    });
    let sin_iy1 = zip3(y0, t, v, |y0, t, v| y0 - (t - v * S1));
    let sin_r = zip3(ax, sin_iy0, sin_iy1, |ax, a, b| {
        select(mask(ax <= PIO4), a, b)
    });
    let rc = zip(z, zz, |z, zz| {
        z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6))
    });
    let hz = map(z, |z| 0.5 * z);
    let wc = map(hz, |hz| 1.0 - hz);
    let yy = zip(y0, y1, |y0, y1| y0 * y1);
    let tail = zip3(z, rc, yy, |z, rc, yy| z * rc - yy);
    let cos_r = zip3(wc, hz, tail, |wc, hz, tail| wc + (((1.0 - wc) - hz) + tail));
    // Quadrant n & 3 (two's complement, in the low bits of n + 1.5·2⁵²): odd
    // swaps sine and cosine; 2, 3 negate the sine; 1, 2 the cosine.
    let q = map(f_n, |n| f64::from_bits((n + TO_INT).to_bits() & 3));
    let odd = map(q, |q| mask(q.to_bits() & 1 != 0));
    let s = zip3(odd, cos_r, sin_r, select);
    let c = zip3(odd, sin_r, cos_r, select);
    let s = zip(s, q, |s, q| {
        f64::from_bits(s.to_bits() ^ ((q.to_bits() & 2) << 62))
    });
    let c = zip(c, q, |c, q| {
        f64::from_bits(c.to_bits() ^ (((q.to_bits() + 1) & 2) << 62))
    });
    // |x| < 2⁻²⁷·√2: (x, 1).
    let tiny = map(ax, |ax| mask(ax < TINY));
    let mut s = zip3(tiny, x, s, select);
    let mut c = zip(tiny, c, |m, c| select(m, 1.0, c));
    if fallback.iter().any(|m| m.to_bits() != 0) {
        for k in 0..L {
            if fallback[k].to_bits() != 0 {
                (s[k], c[k]) = libm::sincos(x[k]);
            }
        }
    }
    (s, c)
}

/// `(sin x, cos x)`: [`libm::sincos`], the value every lane of
/// `kernels::sin_cos_x4` and [`sin_cos_lanes`] gives for `x`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// Whether the dynamics' forward kinematics — the general path
/// ([`crate::kinematics`]), the legs in AVX lanes (`kernels::legs_x4`) and
/// the robots in lanes ([`crate::batch`]), all alike — and the integrator's
/// base rotation ([`crate::integrate::integrate_q`]) take their sines and
/// cosines from this module (libm's bits) instead of std's `f64::sin_cos`
/// (glibc). With [`LEGS_USE_LIBM`], 2,570 fewer instructions per robot-step
/// of 64 trotting quad16 (43,609 → 41,038, callgrind, 2026-11-26).
///
/// On since 2026-11-26. The two differ by at most 1 ulp, but quad16's trot
/// is chaotic at some tested operating points (`docs/walking.md`,
/// "Round-off sensitivity"), so switching changes every trajectory's last
/// bits and, at those points, whether one start falls. The switch stayed
/// off while a test of the blind step-up relied on its one start with the
/// default parameters (which fall from 10 of 41 perturbed starts); that test
/// now runs with [`crate::control::walker::ROUND_OFF_ROBUST`]. Either way the
/// scalar and lane paths agree bit for bit.
pub const DYNAMICS_USE_LIBM: bool = true;

/// Whether the controller's closed-form leg kinematics ([`crate::legs`]:
/// foot positions, Jacobians, inverse kinematics) take their sines and
/// cosines from this module (four at a time where it can) instead of std's;
/// on, as [`DYNAMICS_USE_LIBM`].
pub const LEGS_USE_LIBM: bool = true;

/// Forward kinematics' `(sin x, cos x)`: [`sin_cos`] or std's, by
/// [`DYNAMICS_USE_LIBM`].
#[inline(always)]
pub(crate) fn kinematics_sin_cos(x: f64) -> (f64, f64) {
    if DYNAMICS_USE_LIBM {
        sin_cos(x)
    } else {
        x.sin_cos()
    }
}

/// [`kinematics_sin_cos`] per lane, the same bits as it gives each lane.
#[inline(always)]
pub(crate) fn kinematics_sin_cos_lanes<const L: usize>(x: [f64; L]) -> ([f64; L], [f64; L]) {
    if DYNAMICS_USE_LIBM {
        sin_cos_lanes(x)
    } else {
        let (mut s, mut c) = ([0.0; L], [0.0; L]);
        for k in 0..L {
            (s[k], c[k]) = x[k].sin_cos();
        }
        (s, c)
    }
}

/// glam's `DMat3::from_axis_angle` with `kinematics_sin_cos`: the rotation
/// by `angle` (rad) about the unit `axis`, operation for operation as glam
/// computes it (so glam's own matrix while [`DYNAMICS_USE_LIBM`] is off).
#[inline]
pub fn mat3_from_axis_angle(axis: glam::DVec3, angle: f64) -> glam::DMat3 {
    let (sin, cos) = kinematics_sin_cos(angle);
    let (xsin, ysin, zsin) = (axis.x * sin, axis.y * sin, axis.z * sin);
    let (x, y, z) = (axis.x, axis.y, axis.z);
    let (x2, y2, z2) = (x * x, y * y, z * z);
    let omc = 1.0 - cos;
    let xyomc = x * y * omc;
    let xzomc = x * z * omc;
    let yzomc = y * z * omc;
    glam::DMat3::from_cols(
        glam::DVec3::new(x2 * omc + cos, xyomc + zsin, xzomc - ysin),
        glam::DVec3::new(xyomc - zsin, y2 * omc + cos, yzomc + xsin),
        glam::DVec3::new(xzomc + ysin, yzomc - xsin, z2 * omc + cos),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    /// Distance in units in the last place between two finite doubles of the
    /// same sign (or both near zero), from their ordered bit patterns.
    fn ulps(a: f64, b: f64) -> u64 {
        let key = |x: f64| {
            let b = x.to_bits() as i64;
            if b < 0 { i64::MIN - b } else { b }
        };
        key(a).abs_diff(key(b))
    }

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Asserts that lanes' sines `s` and cosines `c` of `x` are libm's bits.
    pub(crate) fn assert_libm_bits(x: [f64; 4], s: [f64; 4], c: [f64; 4]) {
        for k in 0..4 {
            let (ls, lc) = libm::sincos(x[k]);
            assert!(
                same(s[k], ls) && same(c[k], lc),
                "x = {:e} ({:#x}): lanes ({:e}, {:e}), libm ({ls:e}, {lc:e})",
                x[k],
                x[k].to_bits(),
                s[k],
                c[k]
            );
        }
    }

    /// Checks four lanes against libm, by the inlined lanes and the
    /// dispatched x4 version.
    fn check4(x: [f64; 4]) {
        let (s, c) = sin_cos_lanes(x);
        let (s4, c4) = crate::kernels::sin_cos_x4(x);
        let (s1, c1) = sin_cos_lanes([x[0]]);
        assert_libm_bits(x, s, c);
        for k in 0..4 {
            let (ls, lc) = libm::sincos(x[k]);
            assert!(same(s4[k], ls) && same(c4[k], lc), "x4 at {:e}", x[k]);
        }
        assert!(
            same(s1[0], s[0]) && same(c1[0], c[0]),
            "one lane at {:e}",
            x[0]
        );
    }

    /// A dense deterministic sample of |x| ≤ 64 rad (joint angles and
    /// beyond; 2·10⁶ points), a sparser one up to and past the lane path's
    /// range (2²⁰·π/2), and the hard points: msun's threshold words,
    /// multiples of π/2 and their neighbours (where the reduction cancels),
    /// msun's special high words with low words across their range, tiny and
    /// subnormal values, ±0, ±∞, NaN. A multiple of 4 long.
    pub(crate) fn sample() -> Vec<f64> {
        let n = 2_000_000;
        let mut xs = Vec::with_capacity(n + 300_000);
        for i in 0..n {
            // an irrational offset, so that the sample does not align with π/2
            let t = (i as f64 + 0.5) / n as f64 * 2.0 - 1.0;
            xs.push(64.0 * t + 1e-7 * (i as f64 * 0.618_033_988_749_895).fract());
        }
        for i in 0..200_000 {
            let t = (i as f64 + 0.5) / 200_000.0;
            xs.push(1.8e6 * t * t * if i % 2 == 0 { 1.0 } else { -1.0 });
        }
        xs.extend([0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN]);
        xs.extend([
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            TINY,
            f64::from_bits(TINY.to_bits() - 1),
            1e-9,
            -1e-5,
            MEDIUM_END,
            f64::from_bits(MEDIUM_END.to_bits() - 1),
            1e300,
        ]);
        for t in [PIO4, PIO4_3, PIO4_5, PIO4_7, PIO4_9] {
            for d in 0..3u64 {
                xs.extend([
                    f64::from_bits(t.to_bits() + d),
                    f64::from_bits(t.to_bits() - d),
                ]);
            }
        }
        for k in 1..2000 {
            let m = k as f64 * FRAC_PI_2;
            for d in 0..4u64 {
                for x in [
                    f64::from_bits(m.to_bits() + d),
                    f64::from_bits(m.to_bits() - d),
                ] {
                    xs.extend([x, -x]);
                }
            }
            let hw = m.to_bits() >> 32;
            for lo in [0u64, 1, 0x5444_2d18, 0xffff_ffff] {
                xs.push(f64::from_bits((hw << 32) | lo));
            }
        }
        while xs.len() % 4 != 0 {
            xs.push(0.3);
        }
        xs
    }

    /// Every lane gives libm's bits on [`sample`].
    #[test]
    fn lanes_give_libm_bits() {
        for x in sample().chunks_exact(4) {
            check4([x[0], x[1], x[2], x[3]]);
        }
    }

    /// The lane path and std agree to 1 ulp on a dense sample of
    /// |x| ≤ 2²⁰·π/2 (2·10⁶ points; denser near zero), and exactly at 0.
    #[test]
    fn within_one_ulp_of_std() {
        let n = 2_000_000;
        let mut worst = (0u64, 0.0);
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 * 2.0 - 1.0;
            let x = MEDIUM_END * t * t * t;
            let xs = [x, x * 1e-3, x * 1e-6, -x * 1e-4];
            let (s, c) = sin_cos_lanes(xs);
            for k in 0..4 {
                let (ss, cs) = xs[k].sin_cos();
                let d = ulps(s[k], ss).max(ulps(c[k], cs));
                if d > worst.0 {
                    worst = (d, xs[k]);
                }
            }
        }
        assert!(worst.0 <= 1, "{} ulp at x = {:e}", worst.0, worst.1);
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
    }

    /// glam's formula with our sine: equal to glam's own rotation wherever
    /// the two sines agree, and a rotation to round-off everywhere.
    #[test]
    fn axis_angle_matrix_is_glams() {
        let axis = glam::DVec3::new(0.3, -0.5, 0.8).normalize();
        for k in -50..50 {
            let angle = 0.13 * k as f64;
            let m = mat3_from_axis_angle(axis, angle);
            let g = glam::DMat3::from_axis_angle(axis, angle);
            assert!((m - g).abs().to_cols_array().iter().all(|e| *e <= 4e-16));
            if kinematics_sin_cos(angle) == angle.sin_cos() {
                assert_eq!(m, g);
            }
        }
    }
}
