//! Attitude from a gyroscope corrected by the accelerometer's tilt: the
//! nonlinear complementary filter of Mahony, Hamel and Pflimlin (IEEE TAC
//! 53(5), 2008, "explicit complementary filter" with bias estimation).
//!
//! With `R̂` the estimate (torso → world) and `f` the measured specific
//! force (torso frame), the reference direction is the specific force
//! rotated into the world and low-passed there, `f̄` (time constant
//! `accel_filter_s`): on average over a gait cycle the body does not
//! accelerate, so `f̄` points up, whereas a trotting quad16's torso sees
//! instantaneous specific forces of 0–3 g at up to 60° off vertical
//! (measured), which Mahony's per-sample correction rectifies into a
//! 0.1 rad bias. Then, in the torso frame:
//!
//! ```text
//! e     = R̂ᵀ ( f̄/|f̄| × e_z )          (tilt error; = v × v̂ of Mahony with v = R̂ᵀ f̄/|f̄|)
//! ḃ     = −k_I e                      (gyro bias estimate)
//! ω̂     = ω_gyro − b̂ + k_P e
//! R̂(t+Δt) = R̂ exp(ω̂ Δt)
//! ```
//!
//! A torso that speeds up for longer than the filter's time constant (a
//! commanded ramp, a trot's surge at 4 Hz that the low-pass only halves)
//! would still tilt `f̄` by `a/g`: each update may therefore subtract the
//! base's own world acceleration, as the position filter estimates it
//! ([`AttitudeFilter::update`]'s `base_accel_world_mps2`; MIT Cheetah's
//! and Pronto's estimators feed their velocity back the same way), so that
//! `f̄` is the low-passed `f − a` = gravity's reaction alone.
//!
//! The correction is skipped when `| |f̄| − g |` exceeds `accel_gate_mps2`.
//! Yaw is not observable from gravity: it follows the gyro alone (and drifts
//! with its bias about z).

use glam::{DQuat, DVec3};

/// Gains of [`AttitudeFilter`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeParams {
    /// Proportional gain `k_P` (rad/s per unit error; ≈ the crossover
    /// frequency between accelerometer and gyro, 1/time constant).
    pub kp_radps: f64,
    /// Integral gain `k_I` (rad/s² per unit error) of the gyro bias estimate.
    pub ki_radps2: f64,
    /// Correction only when the filtered specific force's magnitude is within this of g (m/s²).
    pub accel_gate_mps2: f64,
    /// Time constant of the low-pass on the world-frame specific force (s; 0: none).
    pub accel_filter_s: f64,
    /// Whether the base estimator removes the base's own estimated
    /// acceleration from the specific force ([`AttitudeFilter::update_compensated`]).
    pub compensate_base_acceleration: bool,
}

impl Default for AttitudeParams {
    /// `k_P` = 1 rad/s (gyro drift corrected within seconds), `k_I` =
    /// 0.05 rad/s², gate 3 m/s², and a 0.25 s filter (half of Study A's
    /// 0.5 s gait period; slower than `1/k_P` would let the loop ring),
    /// with the base's acceleration compensated.
    fn default() -> Self {
        AttitudeParams {
            kp_radps: 1.0,
            ki_radps2: 0.05,
            accel_gate_mps2: 3.0,
            accel_filter_s: 0.25,
            compensate_base_acceleration: true,
        }
    }
}

/// Orientation estimate with gyro-bias estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeFilter {
    /// Gains.
    pub params: AttitudeParams,
    /// Orientation estimate (torso → world).
    pub orientation: DQuat,
    /// Gyro bias estimate (rad/s, torso frame).
    pub gyro_bias_radps: DVec3,
    /// Bias-corrected angular velocity of the last update (rad/s, torso frame).
    pub omega_radps: DVec3,
    /// Low-passed specific force (m/s², world), `None` before the first update.
    pub accel_world_filtered_mps2: Option<DVec3>,
}

impl AttitudeFilter {
    /// A filter starting at `orientation` with zero bias.
    pub fn new(params: AttitudeParams, orientation: DQuat) -> Self {
        AttitudeFilter {
            params,
            orientation,
            gyro_bias_radps: DVec3::ZERO,
            omega_radps: DVec3::ZERO,
            accel_world_filtered_mps2: None,
        }
    }

    /// One update over `dt_s` with the gyro (rad/s) and accelerometer
    /// (specific force, m/s²) readings, both torso frame; `g_mps2` is |gravity|.
    pub fn update(&mut self, gyro_radps: DVec3, accel_mps2: DVec3, g_mps2: f64, dt_s: f64) {
        self.update_compensated(gyro_radps, accel_mps2, DVec3::ZERO, g_mps2, dt_s);
    }

    /// [`Self::update`] with the base's own acceleration (m/s², world)
    /// removed from the specific force before the low-pass: the reference
    /// direction is then gravity's even while the torso speeds up.
    pub fn update_compensated(
        &mut self,
        gyro_radps: DVec3,
        accel_mps2: DVec3,
        base_accel_world_mps2: DVec3,
        g_mps2: f64,
        dt_s: f64,
    ) {
        // an x86-64-v3 clone (three-operand VEX forms, wider vectors; no
        // fused multiply–add, so the same bits), in a free function:
        // multiversion takes no `self`
        #[multiversion::multiversion(targets("x86_64+avx2+fma"))]
        fn body(
            this: &mut AttitudeFilter,
            gyro_radps: DVec3,
            accel_mps2: DVec3,
            base_accel_world_mps2: DVec3,
            g_mps2: f64,
            dt_s: f64,
        ) {
            let p = this.params;
            let f_w = this.orientation * accel_mps2 - base_accel_world_mps2;
            let alpha = if p.accel_filter_s > 0.0 {
                1.0 - (-dt_s / p.accel_filter_s).exp()
            } else {
                1.0
            };
            let f_bar = match this.accel_world_filtered_mps2 {
                Some(f) => f + alpha * (f_w - f),
                None => f_w,
            };
            this.accel_world_filtered_mps2 = Some(f_bar);
            let n = f_bar.length();
            let mut e = DVec3::ZERO;
            if n > 0.0 && (n - g_mps2).abs() <= p.accel_gate_mps2 {
                e = this.orientation.inverse() * (f_bar / n).cross(DVec3::Z);
            }
            this.gyro_bias_radps -= p.ki_radps2 * e * dt_s;
            let w = gyro_radps - this.gyro_bias_radps + p.kp_radps * e;
            this.omega_radps = gyro_radps - this.gyro_bias_radps;
            this.orientation = (this.orientation * DQuat::from_scaled_axis(w * dt_s)).normalize();
        }
        body(
            self,
            gyro_radps,
            accel_mps2,
            base_accel_world_mps2,
            g_mps2,
            dt_s,
        )
    }
}
