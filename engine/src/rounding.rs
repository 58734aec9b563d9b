//! Rounding half away from zero without a library call: shared by the
//! sensors' quantisation and the legs' angle wrapping (scalar and in lanes).

/// 2⁵²: from here on every f64 is an integer.
pub(crate) const TWO_52: f64 = 4_503_599_627_370_496.0;

/// The largest f64 below one half, 0.5 − 2⁻⁵⁴.
pub(crate) const HALF_DOWN: f64 = 0.499_999_999_999_999_94;

/// [`f64::round`] (half away from zero), the same bits, without its
/// library call (a generic x86-64 build has no rounding instruction; the
/// call cost ~50 instructions per sample). For `0.5 ≤ |x| < 2⁵²`,
/// `|x| + (0.5 − 2⁻⁵⁴)` truncated is `|x|` rounded half away from zero
/// (the sum rounds up to the next integer exactly when `|x|`'s fraction is
/// at least one half; the lowering compilers use for `round` where the CPU
/// truncates), and the truncation is one conversion to an integer and back.
/// Below one half (an angle's turns within half a turn, the usual case of
/// `legs::wrap_angle`) the answer is
/// the zero of `x`'s sign, without the sum.
#[inline]
pub fn round_half_away(x: f64) -> f64 {
    let a = x.abs();
    if a < 0.5 {
        0.0f64.copysign(x)
    } else if a < TWO_52 {
        // below 2⁵² + 1: the integer and its f64 are exact
        ((a + HALF_DOWN) as i64 as f64).copysign(x)
    } else {
        x
    }
}
