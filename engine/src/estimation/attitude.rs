//! Attitude from a gyroscope corrected by the accelerometer's tilt: the
//! nonlinear complementary filter of Mahony, Hamel and Pflimlin (IEEE TAC
//! 53(5), 2008, "explicit complementary filter" with bias estimation).
//!
//! With `R̂` the estimate (torso → world), `v̂ = R̂ᵀ e_z` the world's up
//! direction as the estimate sees it in the torso frame and `v = f/|f|` the
//! measured specific force's direction (up on average while the robot is
//! supported):
//!
//! ```text
//! e     = v × v̂                       (tilt error, torso frame)
//! ḃ     = −k_I e                      (gyro bias estimate)
//! ω̂     = ω_gyro − b̂ + k_P e
//! R̂(t+Δt) = R̂ exp(ω̂ Δt)
//! ```
//!
//! The correction is skipped when `| |f| − g |` exceeds `accel_gate_mps2`
//! (strong dynamic acceleration). Yaw is not observable from gravity: it
//! follows the gyro alone (and drifts with its bias about z).

use glam::{DQuat, DVec3};

/// Gains of [`AttitudeFilter`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeParams {
    /// Proportional gain `k_P` (rad/s per unit error; ≈ the crossover
    /// frequency between accelerometer and gyro, 1/time constant).
    pub kp_radps: f64,
    /// Integral gain `k_I` (rad/s² per unit error) of the gyro bias estimate.
    pub ki_radps2: f64,
    /// Correction only when the specific force's magnitude is within this of g (m/s²).
    pub accel_gate_mps2: f64,
}

impl Default for AttitudeParams {
    /// `k_P` = 1 rad/s (1 s time constant: a trot's 2 Hz body accelerations
    /// are filtered, gyro drift is corrected within seconds), `k_I` =
    /// 0.05 rad/s², gate 3 m/s².
    fn default() -> Self {
        AttitudeParams {
            kp_radps: 1.0,
            ki_radps2: 0.05,
            accel_gate_mps2: 3.0,
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
}

impl AttitudeFilter {
    /// A filter starting at `orientation` with zero bias.
    pub fn new(params: AttitudeParams, orientation: DQuat) -> Self {
        AttitudeFilter {
            params,
            orientation,
            gyro_bias_radps: DVec3::ZERO,
            omega_radps: DVec3::ZERO,
        }
    }

    /// One update over `dt_s` with the gyro (rad/s) and accelerometer
    /// (specific force, m/s²) readings, both torso frame; `g_mps2` is |gravity|.
    pub fn update(&mut self, gyro_radps: DVec3, accel_mps2: DVec3, g_mps2: f64, dt_s: f64) {
        let p = self.params;
        let n = accel_mps2.length();
        let mut e = DVec3::ZERO;
        if n > 0.0 && (n - g_mps2).abs() <= p.accel_gate_mps2 {
            let v_hat = self.orientation.inverse() * DVec3::Z;
            e = (accel_mps2 / n).cross(v_hat);
        }
        self.gyro_bias_radps -= p.ki_radps2 * e * dt_s;
        let w = gyro_radps - self.gyro_bias_radps + p.kp_radps * e;
        self.omega_radps = gyro_radps - self.gyro_bias_radps;
        self.orientation = (self.orientation * DQuat::from_scaled_axis(w * dt_s)).normalize();
    }
}
