//! An inertial measurement unit fixed at the torso (base) frame's origin,
//! axes along the torso frame.
//!
//! - **Accelerometer**: the specific force `f = Rᵀ (a − g)` (m/s², torso
//!   frame), `a` the origin's acceleration in the world, `g` gravity (world,
//!   z up: `(0, 0, −9.81)`). At rest it reads `+9.81` along the world's up
//!   direction; in free fall it reads zero.
//! - **Gyroscope**: the torso's angular velocity `ω` (rad/s, torso frame).
//!
//! The acceleration is the change of the origin's world velocity since the
//! previous sample divided by the time between them: the mean acceleration
//! over the sample period, what an accelerometer's anti-aliasing (averaging)
//! filter reports; ground impacts that last a few simulation steps are
//! averaged, not aliased. The first sample assumes zero acceleration.
//! Samples come at `rate_hz` and are held in between.

use glam::{DMat3, DVec3};
use rand_chacha::ChaCha8Rng;

use super::noise::{NoiseChannel, NoiseParams, channels3, sample3};
use super::{RateGate, SensorStream, sensor_rng};

/// IMU configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuParams {
    /// Output rate (Hz).
    pub rate_hz: f64,
    /// Accelerometer noise per axis (m/s²).
    pub accel: NoiseParams,
    /// Gyroscope noise per axis (rad/s).
    pub gyro: NoiseParams,
}

impl ImuParams {
    /// A perfect IMU at `rate_hz`.
    pub fn ideal(rate_hz: f64) -> ImuParams {
        ImuParams {
            rate_hz,
            accel: NoiseParams::NONE,
            gyro: NoiseParams::NONE,
        }
    }
}

/// One IMU output.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    /// Time of the sample (s).
    pub t_s: f64,
    /// Specific force (m/s², torso frame).
    pub accel_mps2: DVec3,
    /// Angular velocity (rad/s, torso frame).
    pub gyro_radps: DVec3,
}

/// An IMU's state: noise channels, its random stream, the previous velocity.
#[derive(Clone, Debug)]
pub struct Imu {
    /// Configuration.
    pub params: ImuParams,
    accel: [NoiseChannel; 3],
    gyro: [NoiseChannel; 3],
    rng: ChaCha8Rng,
    gate: RateGate,
    prev: Option<(f64, DVec3)>,
    accel_true: DVec3,
    /// The last sample (held between samples), `None` before the first.
    pub last: Option<ImuSample>,
}

impl Imu {
    /// Whether a call at `t_s` would take a sample (see [`super::RateGate::due`]).
    pub fn due(&self, t_s: f64) -> bool {
        self.gate.due(t_s)
    }

    /// An IMU whose noise draws come from the robot seed `seed`, first sample at `t0_s`.
    pub fn new(params: ImuParams, seed: u64, t0_s: f64) -> Imu {
        let mut rng = sensor_rng(seed, SensorStream::Imu);
        let accel = channels3(params.accel, &mut rng);
        let gyro = channels3(params.gyro, &mut rng);
        Imu {
            params,
            accel,
            gyro,
            rng,
            gate: RateGate::new(params.rate_hz, t0_s),
            prev: None,
            accel_true: DVec3::ZERO,
            last: None,
        }
    }

    /// The current biases (accelerometer m/s², gyroscope rad/s; torso frame).
    pub fn biases(&self) -> (DVec3, DVec3) {
        let b = |c: &[NoiseChannel; 3]| DVec3::new(c[0].bias, c[1].bias, c[2].bias);
        (b(&self.accel), b(&self.gyro))
    }

    /// Call at every simulation step with the true state at `t_s`:
    /// `rot` the torso orientation (torso → world), `vel_world_mps` its
    /// origin's world velocity, `omega_body_radps` its angular velocity
    /// (torso frame), `gravity_mps2` (world). Returns the new sample when one
    /// is due.
    pub fn update(
        &mut self,
        t_s: f64,
        rot: DMat3,
        vel_world_mps: DVec3,
        omega_body_radps: DVec3,
        gravity_mps2: DVec3,
    ) -> Option<ImuSample> {
        let dt = self.gate.tick(t_s)?;
        if let Some((t0, v0)) = self.prev
            && t_s > t0
        {
            self.accel_true = (vel_world_mps - v0) / (t_s - t0);
        }
        self.prev = Some((t_s, vel_world_mps));
        let f_true = rot.transpose() * (self.accel_true - gravity_mps2);
        let s = ImuSample {
            t_s,
            accel_mps2: sample3(&mut self.accel, f_true, dt, &mut self.rng),
            gyro_radps: sample3(&mut self.gyro, omega_body_radps, dt, &mut self.rng),
        };
        self.last = Some(s);
        Some(s)
    }
}
