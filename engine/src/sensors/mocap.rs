//! Motion capture of the torso pose: position (m, world) and orientation
//! with noise, delivered `latency` after capture.
//!
//! The latency is a whole number of samples, `L = round(latency_s · rate_hz)`:
//! the sample output at capture tick `k` is the one captured at tick `k − L`
//! (nothing is output before `L` captures).

use std::collections::VecDeque;

use glam::{DQuat, DVec3};
use rand_chacha::ChaCha8Rng;

use super::noise::gaussian;
use super::{RateGate, SensorStream, sensor_rng};

/// Motion capture configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapParams {
    /// Capture rate (Hz).
    pub rate_hz: f64,
    /// Latency (s), rounded to whole samples.
    pub latency_s: f64,
    /// Position white noise per axis (m).
    pub position_noise_std_m: f64,
    /// Orientation white noise: std of each component of a small rotation vector (rad).
    pub orientation_noise_std_rad: f64,
}

impl MocapParams {
    /// The latency in samples.
    pub fn latency_samples(&self) -> usize {
        (self.latency_s * self.rate_hz).round().max(0.0) as usize
    }
}

/// One motion-capture output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapSample {
    /// When the pose was captured (s); it is delivered `latency` later.
    pub captured_t_s: f64,
    /// Torso position (m, world).
    pub position_m: DVec3,
    /// Torso orientation (torso → world).
    pub orientation: DQuat,
}

/// A motion-capture system tracking one torso.
#[derive(Clone, Debug)]
pub struct Mocap {
    /// Configuration.
    pub params: MocapParams,
    rng: ChaCha8Rng,
    gate: RateGate,
    queue: VecDeque<MocapSample>,
    /// The latest delivered sample, `None` until the first has come through.
    pub last: Option<MocapSample>,
}

impl Mocap {
    /// Whether a call at `t_s` would take a sample (see [`super::RateGate::due`]).
    pub fn due(&self, t_s: f64) -> bool {
        self.gate.due(t_s)
    }

    /// Mocap with noise from the robot seed `seed`, first capture at `t0_s`.
    pub fn new(params: MocapParams, seed: u64, t0_s: f64) -> Mocap {
        Mocap {
            params,
            rng: sensor_rng(seed, SensorStream::Mocap),
            gate: RateGate::new(params.rate_hz, t0_s),
            queue: VecDeque::with_capacity(params.latency_samples() + 1),
            last: None,
        }
    }

    /// Call at every simulation step with the true torso pose at `t_s`;
    /// returns the sample delivered now, if any.
    pub fn update(
        &mut self,
        t_s: f64,
        position_m: DVec3,
        orientation: DQuat,
    ) -> Option<MocapSample> {
        self.gate.tick(t_s)?;
        let p = self.params;
        let dp = DVec3::new(
            gaussian(&mut self.rng),
            gaussian(&mut self.rng),
            gaussian(&mut self.rng),
        );
        let dr = DVec3::new(
            gaussian(&mut self.rng),
            gaussian(&mut self.rng),
            gaussian(&mut self.rng),
        );
        self.queue.push_back(MocapSample {
            captured_t_s: t_s,
            position_m: position_m + p.position_noise_std_m * dp,
            orientation: (orientation * DQuat::from_scaled_axis(p.orientation_noise_std_rad * dr))
                .normalize(),
        });
        if self.queue.len() > p.latency_samples() {
            self.last = self.queue.pop_front();
            return self.last;
        }
        None
    }
}
