//! Sensor models: what a real robot's controller sees instead of the
//! simulator's ground truth. Pure functions of the true state and a seeded
//! random stream; no ECS.
//!
//! | sensor | file | measures (frame) |
//! |---|---|---|
//! | IMU | [`imu`] | specific force (m/s²) and angular velocity (rad/s), torso frame |
//! | joint encoders | [`encoders`] | joint angles (rad), velocities by differencing (rad/s) |
//! | foot contact sensors | [`contact`] | contact flags (hysteresis), normal force (N) |
//! | motion capture | [`mocap`] | torso position (m, world) and orientation, delayed |
//!
//! Every sensor samples at its own rate ([`RateGate`]) and holds its last
//! sample in between. Randomness: every sensor of a robot draws from its own
//! ChaCha8 stream ([`sensor_rng`]) of the robot's seed, which the caller
//! derives from the scenario seed and the robot's *name*; so the outputs do
//! not depend on robot order, thread count or which other sensors are on.
//! Noise models: [`noise`]. Units and defaults: `docs/sensors.md`.

pub mod contact;
pub mod encoders;
pub mod imu;
pub mod mocap;
pub mod noise;
pub mod suite;

pub use contact::{ContactSensorParams, ContactSensors};
pub use encoders::{EncoderParams, Encoders, JointVelocityMode};
pub use imu::{Imu, ImuParams, ImuSample};
pub use mocap::{Mocap, MocapParams, MocapSample};
pub use noise::{NoiseChannel, NoiseParams};
pub use suite::{ONE_G_MPS2, SensorConfig, SensorSpec, SensorSuite, SensorTruth, SensorUpdates};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The random stream of each sensor kind (ChaCha's stream number).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorStream {
    /// The IMU's accelerometer and gyroscope.
    Imu = 1,
    /// The joint encoders.
    Encoders = 2,
    /// The foot contact sensors.
    Contacts = 3,
    /// Motion capture.
    Mocap = 4,
}

/// The random stream of sensor kind `stream` of the robot seeded `seed`:
/// ChaCha8 (portable, the same numbers on every machine) keyed by the seed,
/// on its own stream number, so sensors never share draws.
pub fn sensor_rng(seed: u64, stream: SensorStream) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream as u64);
    rng
}

/// Decides the sample instants of a sensor at `rate_hz` on a simulation
/// clock: the `n`-th sample is due at `t ≥ t0 + n·period − ε` (times are
/// computed from the count, not accumulated, so they do not drift; the phase
/// is kept, so a 500 Hz sensor on a 2 kHz clock samples exactly every 4th
/// step). A rate at or above the clock's samples at every call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateGate {
    /// Sample period (s; 0: every call).
    pub period_s: f64,
    /// Time of the first sample (s).
    pub t0_s: f64,
    /// Index of the next sample.
    pub next: u64,
    /// Time of the last sample (s; `None` before the first).
    pub last_t_s: Option<f64>,
}

impl RateGate {
    /// A gate at `rate_hz` (≤ 0 or ∞: every call) whose first sample is at `t0_s`.
    pub fn new(rate_hz: f64, t0_s: f64) -> RateGate {
        let period_s = if rate_hz > 0.0 && rate_hz.is_finite() {
            1.0 / rate_hz
        } else {
            0.0
        };
        RateGate {
            period_s,
            t0_s,
            next: 0,
            last_t_s: None,
        }
    }

    fn next_t_s(&self) -> f64 {
        self.t0_s + self.next as f64 * self.period_s
    }

    /// Whether [`RateGate::tick`] at `t_s` would sample (it does not advance).
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "exactly the negation of tick's test, NaN included"
    )]
    pub fn due(&self, t_s: f64) -> bool {
        let eps = 1e-6 * self.period_s.max(1e-6);
        !(t_s + eps < self.next_t_s())
    }

    /// Whether a sample is due at `t_s`; if so, returns the time since the
    /// last sample (the period before the first) and advances.
    pub fn tick(&mut self, t_s: f64) -> Option<f64> {
        let eps = 1e-6 * self.period_s.max(1e-6);
        if t_s + eps < self.next_t_s() {
            return None;
        }
        let dt = match self.last_t_s {
            Some(t0) => t_s - t0,
            None => self.period_s,
        };
        self.last_t_s = Some(t_s);
        if self.period_s > 0.0 {
            while self.next_t_s() <= t_s + eps {
                self.next += 1;
            }
        }
        Some(dt)
    }
}
