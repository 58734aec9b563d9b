//! Sine and cosine of joint angles without branches, so that a loop over
//! several angles (the joints of one robot, or one joint across the lanes of
//! a batch) compiles to SIMD instructions.
//!
//! libm's `sin_cos` is an opaque call per angle (~110 instructions here, a
//! tenth of ABA on quad16); the `libm` crate's port is as long and branches
//! on the argument's size. This is the same FreeBSD/fdlibm algorithm, as
//! the `libm` crate has it: the argument is reduced by π/2 in three
//! Cody–Waite rounds (fdlibm's `__rem_pio2` "medium" case, always taking
//! all three rounds instead of branching), then fdlibm's `__kernel_sin` and
//! `__kernel_cos` polynomials on [−π/4, π/4], and the quadrant is chosen by
//! selects. Accurate to about 1 ulp for |x| ≤ [`REDUCED_RANGE`]; larger or
//! non-finite arguments go to `f64::sin_cos`.
//!
//! The constants and kernels are from fdlibm:
//!
//! > Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
//! > Developed at SunPro, a Sun Microsystems, Inc. business. Permission to
//! > use, copy, modify, and distribute this software is freely granted,
//! > provided that this notice is preserved.

/// Arguments up to this magnitude (rad) are reduced here (fdlibm's medium
/// case holds to 2²⁰·π/2); beyond it, and for non-finite ones, `f64::sin_cos`.
pub const REDUCED_RANGE: f64 = 1.0e5;

const TO_INT: f64 = 1.5 / f64::EPSILON;
const INV_PIO2: f64 = 6.366_197_723_675_813_824_33e-1; // 0x3FE45F30, 0x6DC9C883
const PIO2_1: f64 = 1.570_796_326_734_125_614_17; // 0x3FF921FB, 0x54400000
const PIO2_2: f64 = 6.077_100_506_303_965_976_60e-11; // 0x3DD0B461, 0x1A600000
const PIO2_3: f64 = 2.022_266_248_711_166_455_80e-21; // 0x3BA3198A, 0x2E000000
const PIO2_3T: f64 = 8.478_427_660_368_899_569_97e-32; // 0x397B839A, 0x252049C1

const S1: f64 = -1.666_666_666_666_663_243_48e-1; // 0xBFC55555, 0x55555549
const S2: f64 = 8.333_333_333_322_489_461_24e-3; // 0x3F811111, 0x1110F8A6
const S3: f64 = -1.984_126_982_985_794_931_34e-4; // 0xBF2A01A0, 0x19C161D5
const S4: f64 = 2.755_731_370_707_006_767_89e-6; // 0x3EC71DE3, 0x57B1FE7D
const S5: f64 = -2.505_076_025_340_686_341_95e-8; // 0xBE5AE5E6, 0x8A2B9CEB
const S6: f64 = 1.589_690_995_211_550_102_21e-10; // 0x3DE5D93A, 0x5ACFD57C

const C1: f64 = 4.166_666_666_666_660_190_37e-2; // 0x3FA55555, 0x5555554C
const C2: f64 = -1.388_888_888_887_410_957_49e-3; // 0xBF56C16C, 0x16C15177
const C3: f64 = 2.480_158_728_947_672_941_78e-5; // 0x3EFA01A0, 0x19CB1590
const C4: f64 = -2.755_731_435_139_066_330_35e-7; // 0xBE927E4F, 0x809C52AD
const C5: f64 = 2.087_572_321_298_174_827_90e-9; // 0x3E21EE9E, 0xBDB4B1C4
const C6: f64 = -1.135_964_755_778_819_482_65e-11; // 0xBDA8FAE9, 0xBE8838D4

/// `(sin x, cos x)` for |x| ≤ [`REDUCED_RANGE`], without branches (the
/// result is meaningless beyond; see [`sin_cos`]).
#[inline(always)]
pub fn sin_cos_reduced(x: f64) -> (f64, f64) {
    // x = n·π/2 + (y0 + y1), n rounded to nearest; three rounds good to 151 bits.
    let t = x * INV_PIO2 + TO_INT;
    let quadrant = t.to_bits(); // n in the low mantissa bits (mod 4 also for n < 0)
    let f_n = t - TO_INT;
    // (the tail of each round but the last is not needed: fdlibm drops it too)
    let r1 = x - f_n * PIO2_1;
    let r2 = r1 - f_n * PIO2_2;
    let w = f_n * PIO2_3;
    let r3 = r2 - w;
    let w3 = f_n * PIO2_3T - ((r2 - r3) - w);
    let y0 = r3 - w3;
    let y1 = (r3 - y0) - w3;
    // __kernel_sin(y0, y1, 1)
    let z = y0 * y0;
    let zz = z * z;
    let rs = S2 + z * (S3 + z * S4) + z * zz * (S5 + z * S6);
    let v = z * y0;
    let s = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * S1);
    // __kernel_cos(y0, y1)
    let rc = z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let wc = 1.0 - hz;
    let c = wc + (((1.0 - wc) - hz) + (z * rc - y0 * y1));
    // quadrant n mod 4: (s, c), (c, −s), (−s, −c), (−c, s)
    let swap = quadrant & 1 == 1;
    let (sin, cos) = if swap { (c, s) } else { (s, c) };
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 62;
    (
        f64::from_bits(sin.to_bits() ^ sin_sign),
        f64::from_bits(cos.to_bits() ^ cos_sign),
    )
}

/// `(sin x, cos x)`: [`sin_cos_reduced`] within [`REDUCED_RANGE`], `f64::sin_cos` beyond.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.abs() <= REDUCED_RANGE {
        sin_cos_reduced(x)
    } else {
        x.sin_cos()
    }
}

/// `sin[k], cos[k] = sin_cos(x[k])` for every k: one vectorisable pass, then
/// the rare arguments outside [`REDUCED_RANGE`] (or not finite) again by `f64::sin_cos`.
///
/// # Panics
/// If the three slices differ in length.
#[inline(always)]
pub fn sin_cos_slice(x: &[f64], sin: &mut [f64], cos: &mut [f64]) {
    let n = x.len();
    let (sin, cos) = (&mut sin[..n], &mut cos[..n]);
    for k in 0..n {
        (sin[k], cos[k]) = sin_cos_reduced(x[k]);
    }
    for k in 0..n {
        if !(x[k].abs() <= REDUCED_RANGE) {
            (sin[k], cos[k]) = x[k].sin_cos();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place.
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let (a, b) = (a.to_bits() as i64, b.to_bits() as i64);
        // both of one sign here away from zero; compare magnitudes
        (a - b).unsigned_abs()
    }

    #[test]
    fn agrees_with_libm_within_one_ulp_or_1e16_absolute() {
        // joint-sized angles densely, multiples of π/2 (cancellation), and
        // the far end of the reduced range
        let mut xs: Vec<f64> = (-200_000..=200_000).map(|k| k as f64 * 1.7e-4).collect();
        for k in -64..=64 {
            let m = k as f64 * std::f64::consts::FRAC_PI_2;
            xs.extend([m, m.next_up(), m.next_down(), m + 1e-9, m - 1e-12]);
        }
        xs.extend([
            1e-300, -1e-300, 0.0, -0.0, 9.99e4, -9.99e4, 1.0e5, 12_345.678,
        ]);
        for &x in &xs {
            let (s, c) = sin_cos(x);
            let (rs, rc) = x.sin_cos();
            for (got, want) in [(s, rs), (c, rc)] {
                assert!(
                    ulps(got, want) <= 1 || (got - want).abs() <= 1e-16,
                    "x = {x:e}: {got:e} vs libm {want:e}"
                );
            }
        }
    }

    #[test]
    fn signs_of_zero_and_special_values() {
        assert_eq!(sin_cos(0.0).0.to_bits(), 0.0f64.to_bits());
        assert_eq!(sin_cos(-0.0).0.to_bits(), (-0.0f64).to_bits());
        assert_eq!(sin_cos(0.0).1, 1.0);
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan(), "{x}");
        }
        // beyond the reduced range: libm's own values
        assert_eq!(sin_cos(3.0e7), 3.0e7f64.sin_cos());
    }

    #[test]
    fn slice_matches_one_by_one_bit_for_bit() {
        let xs = [0.3, -1.2, 2.9, -3.3, 4.0e5, f64::NAN, 1.0e-8, 7.0];
        let (mut s, mut c) = ([0.0; 8], [0.0; 8]);
        sin_cos_slice(&xs, &mut s, &mut c);
        for k in 0..xs.len() {
            let (es, ec) = sin_cos(xs[k]);
            assert_eq!(s[k].to_bits(), es.to_bits(), "{}", xs[k]);
            assert_eq!(c[k].to_bits(), ec.to_bits(), "{}", xs[k]);
        }
    }
}
