//! Scalar noise models shared by every sensor: white Gaussian noise, a
//! turn-on bias, a bias random walk, saturation and quantisation.
//!
//! One [`NoiseChannel`] is one measured scalar (one accelerometer axis, one
//! encoder). A sample of a true value `x` at a sample interval `Δt` is
//!
//! ```text
//! b ← b + σ_w √Δt · n₁            (bias random walk, σ_w in unit/√s)
//! y = x + b + σ · n₂              (white noise, σ in unit)
//! y ← clamp(y, −s, s)             (saturation at the full-scale range s)
//! y ← Δ · round(y / Δ)            (quantisation to the resolution Δ)
//! ```
//!
//! with `n₁, n₂ ~ N(0, 1)` independent and `b(0) ~ N(0, σ_b²)`. The walk's
//! variance therefore grows as `σ_w² t` (std as `√t`), the usual model of a
//! MEMS bias instability (IEEE Std 952 "rate random walk" for a gyro).

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Parameters of one [`NoiseChannel`]; every value is in the unit of the
/// measured quantity (m/s², rad/s, rad, N…).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseParams {
    /// Standard deviation of the white noise of one sample.
    pub white_std: f64,
    /// Standard deviation of the turn-on bias, drawn once when the channel is made.
    pub bias_std: f64,
    /// Bias random walk: the bias's standard deviation after 1 s (unit/√s).
    pub bias_walk_std_per_sqrt_s: f64,
    /// Full-scale range: outputs are clamped to `[-saturation, saturation]` (∞: none).
    pub saturation: f64,
    /// Resolution: outputs are rounded to multiples of it (0: continuous).
    pub quantum: f64,
}

impl NoiseParams {
    /// A perfect channel: output = truth.
    pub const NONE: NoiseParams = NoiseParams {
        white_std: 0.0,
        bias_std: 0.0,
        bias_walk_std_per_sqrt_s: 0.0,
        saturation: f64::INFINITY,
        quantum: 0.0,
    };

    /// Only white noise of standard deviation `std`.
    pub fn white(std: f64) -> NoiseParams {
        NoiseParams {
            white_std: std,
            ..NoiseParams::NONE
        }
    }
}

impl Default for NoiseParams {
    fn default() -> Self {
        NoiseParams::NONE
    }
}

/// One standard normal draw.
#[inline]
pub fn gaussian<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// `x` rounded to the nearest multiple of `quantum` (`quantum ≤ 0`: `x`).
#[inline]
pub fn quantize(x: f64, quantum: f64) -> f64 {
    if quantum > 0.0 {
        round_half_away(x / quantum) * quantum
    } else {
        x
    }
}

#[cfg(test)]
use crate::rounding::TWO_52;
pub use crate::rounding::round_half_away;

/// `x` clamped to `[-limit, limit]` (`limit` = ∞: `x`).
#[inline]
pub fn saturate(x: f64, limit: f64) -> f64 {
    x.clamp(-limit, limit)
}

/// State of one noisy scalar measurement: its parameters and current bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseChannel {
    /// The noise model.
    pub params: NoiseParams,
    /// Current bias (unit of the quantity).
    pub bias: f64,
}

impl NoiseChannel {
    /// A channel whose turn-on bias is drawn from `rng` (one draw, even when
    /// `bias_std` is zero, so every channel consumes the same number of draws).
    pub fn new<R: Rng + ?Sized>(params: NoiseParams, rng: &mut R) -> NoiseChannel {
        let bias = params.bias_std * gaussian(rng);
        NoiseChannel { params, bias }
    }

    /// The measurement of `truth` taken `dt_s` after the previous one: walks
    /// the bias, adds it and white noise, saturates, quantises. Always two
    /// draws, so streams stay aligned whatever the parameters.
    ///
    /// Inlined into each sensor's loop: the call cost (register saves, the
    /// random stream's state reloaded) was about a third of a sample's
    /// ~140 instructions (−420 instructions per quad16 sensor update).
    #[inline(always)]
    pub fn sample<R: Rng + ?Sized>(&mut self, truth: f64, dt_s: f64, rng: &mut R) -> f64 {
        let p = &self.params;
        let n_walk = gaussian(rng);
        let n_white = gaussian(rng);
        self.bias += p.bias_walk_std_per_sqrt_s * dt_s.max(0.0).sqrt() * n_walk;
        let y = truth + self.bias + p.white_std * n_white;
        quantize(saturate(y, p.saturation), p.quantum)
    }
}

/// Three channels with the same parameters (the axes of a vector sensor).
pub fn channels3<R: Rng + ?Sized>(params: NoiseParams, rng: &mut R) -> [NoiseChannel; 3] {
    [
        NoiseChannel::new(params, rng),
        NoiseChannel::new(params, rng),
        NoiseChannel::new(params, rng),
    ]
}

/// A vector measured by three channels.
pub fn sample3<R: Rng + ?Sized>(
    ch: &mut [NoiseChannel; 3],
    truth: glam::DVec3,
    dt_s: f64,
    rng: &mut R,
) -> glam::DVec3 {
    glam::DVec3::new(
        ch[0].sample(truth.x, dt_s, rng),
        ch[1].sample(truth.y, dt_s, rng),
        ch[2].sample(truth.z, dt_s, rng),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// [`round_half_away`] equals [`f64::round`] bit for bit: ties, values
    /// next to ties, signed zeros, large values, non-finite ones and random
    /// values over many magnitudes.
    #[test]
    fn round_half_away_equals_std_round() {
        let mut cases = vec![
            0.0,
            -0.0,
            0.5,
            1.5,
            2.5,
            0.49999999999999994,
            TWO_52 - 0.5,
            TWO_52,
            2.0 * TWO_52 + 2.0,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::INFINITY,
            f64::NAN,
        ];
        for k in -60..60 {
            let t = 2f64.powi(k) + 0.5;
            cases.extend([t, t.next_up(), t.next_down(), 2f64.powi(k)]);
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100_000 {
            let m: f64 = rng.random_range(-1.0..1.0);
            let e: i32 = rng.random_range(-20..60);
            cases.push(m * 2f64.powi(e));
        }
        for x in cases {
            for x in [x, -x] {
                assert_eq!(round_half_away(x).to_bits(), x.round().to_bits(), "{x:e}");
            }
        }
    }
}
