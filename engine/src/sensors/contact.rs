//! Foot contact sensors: a noisy measurement of each foot's normal force
//! (N) and a contact flag from it with hysteresis: the flag turns on when
//! the measured force exceeds `on_threshold_n` and off when it falls below
//! `off_threshold_n` (< on), so noise near one threshold does not chatter.

use rand_chacha::ChaCha8Rng;

use super::noise::{NoiseChannel, NoiseParams};
use super::{RateGate, SensorStream, sensor_rng};

/// Contact sensor configuration (the same for every foot).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSensorParams {
    /// Output rate (Hz).
    pub rate_hz: f64,
    /// Force above which the flag turns on (N).
    pub on_threshold_n: f64,
    /// Force below which the flag turns off (N; ≤ on).
    pub off_threshold_n: f64,
    /// Force noise per sample (N).
    pub noise: NoiseParams,
    /// Whether the measured force is an output (a force sensor) or only the flag (a switch).
    pub force_output: bool,
}

/// The contact sensors of one robot's feet.
#[derive(Clone, Debug)]
pub struct ContactSensors {
    /// Configuration.
    pub params: ContactSensorParams,
    channels: Vec<NoiseChannel>,
    rng: ChaCha8Rng,
    gate: RateGate,
    /// Contact flags, one per foot.
    pub in_contact: Vec<bool>,
    /// Measured normal force (N), one per foot; `NaN` when `force_output` is off.
    pub force_n: Vec<f64>,
}

impl ContactSensors {
    /// Whether a call at `t_s` would take a sample (see [`super::RateGate::due`]).
    pub fn due(&self, t_s: f64) -> bool {
        self.gate.due(t_s)
    }

    /// Sensors on `n_feet` feet, all off; noise from the robot seed `seed`.
    pub fn new(params: ContactSensorParams, n_feet: usize, seed: u64, t0_s: f64) -> ContactSensors {
        let mut rng = sensor_rng(seed, SensorStream::Contacts);
        let channels = (0..n_feet)
            .map(|_| NoiseChannel::new(params.noise, &mut rng))
            .collect();
        ContactSensors {
            params,
            channels,
            rng,
            gate: RateGate::new(params.rate_hz, t0_s),
            in_contact: vec![false; n_feet],
            force_n: vec![if params.force_output { 0.0 } else { f64::NAN }; n_feet],
        }
    }

    /// Call at every simulation step with each foot's true normal force (N)
    /// at `t_s`; returns whether a new sample was taken.
    pub fn update(&mut self, t_s: f64, normal_force_n: &[f64]) -> bool {
        // an x86-64-v3 clone (three-operand VEX forms, wider vectors; no
        // fused multiply–add, so the same bits), in a free function:
        // multiversion takes no `self`
        #[multiversion::multiversion(targets("x86_64+avx2+fma"))]
        fn body(this: &mut ContactSensors, t_s: f64, normal_force_n: &[f64]) -> bool {
            let Some(dt) = this.gate.tick(t_s) else {
                return false;
            };
            let p = this.params;
            for (i, ch) in this.channels.iter_mut().enumerate() {
                let f = ch.sample(normal_force_n[i], dt, &mut this.rng);
                this.in_contact[i] =
                    hysteresis(this.in_contact[i], f, p.on_threshold_n, p.off_threshold_n);
                this.force_n[i] = if p.force_output { f } else { f64::NAN };
            }
            true
        }
        body(self, t_s, normal_force_n)
    }
}

/// The next state of a hysteresis switch at `on` with input `x`: turns on
/// above `on_threshold`, off below `off_threshold`, holds in between.
#[inline]
pub fn hysteresis(on: bool, x: f64, on_threshold: f64, off_threshold: f64) -> bool {
    if on {
        x >= off_threshold
    } else {
        x > on_threshold
    }
}
