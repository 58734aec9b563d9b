//! Joint encoders: every joint's angle (rad) with noise and a resolution,
//! and its velocity (rad/s) either by differencing the measured angles
//! through a first-order low-pass filter (what motor drivers do) or as a
//! noisy direct measurement.
//!
//! Differencing: `ω_raw = (θ_k − θ_{k−1}) / Δt`, then
//! `ω_k = ω_{k−1} + α (ω_raw − ω_{k−1})`, `α = 1 − exp(−Δt/τ)` (the exact
//! discretisation of `τ ω̇ + ω = ω_raw`; τ = 0: no filter). The first
//! sample's velocity is zero.

use rand_chacha::ChaCha8Rng;

use super::noise::{NoiseChannel, NoiseParams, gaussian};
use super::{RateGate, SensorStream, sensor_rng};

/// Where joint velocities come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointVelocityMode {
    /// Differences of the measured angles, low-passed with time constant `filter_time_constant_s` (s).
    Differencing {
        /// First-order filter time constant (s; 0: raw differences).
        filter_time_constant_s: f64,
    },
    /// The true velocity plus white noise of standard deviation `noise_std_radps` (rad/s).
    Direct {
        /// White noise (rad/s).
        noise_std_radps: f64,
    },
}

/// Encoder configuration (the same for every joint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderParams {
    /// Output rate (Hz).
    pub rate_hz: f64,
    /// Angle resolution (rad; 0: continuous). A 14-bit encoder: 2π/16384.
    pub resolution_rad: f64,
    /// White noise of the angle (rad).
    pub noise_std_rad: f64,
    /// Constant offset std of the angle (rad; calibration error, drawn once per joint).
    pub offset_std_rad: f64,
    /// How velocities are obtained.
    pub velocity: JointVelocityMode,
}

impl EncoderParams {
    /// Perfect angles and velocities at `rate_hz`.
    pub fn ideal(rate_hz: f64) -> EncoderParams {
        EncoderParams {
            rate_hz,
            resolution_rad: 0.0,
            noise_std_rad: 0.0,
            offset_std_rad: 0.0,
            velocity: JointVelocityMode::Direct {
                noise_std_radps: 0.0,
            },
        }
    }
}

/// The encoders of one robot's joints.
#[derive(Clone, Debug)]
pub struct Encoders {
    /// Configuration.
    pub params: EncoderParams,
    channels: Vec<NoiseChannel>,
    rng: ChaCha8Rng,
    gate: RateGate,
    sampled: bool,
    /// Measured angles (rad), one per joint, held between samples.
    pub position_rad: Vec<f64>,
    /// Measured velocities (rad/s), one per joint.
    pub velocity_radps: Vec<f64>,
}

impl Encoders {
    /// Whether a call at `t_s` would take a sample (see [`super::RateGate::due`]).
    pub fn due(&self, t_s: f64) -> bool {
        self.gate.due(t_s)
    }

    /// Encoders for `n_joints` joints; noise from the robot seed `seed`.
    pub fn new(params: EncoderParams, n_joints: usize, seed: u64, t0_s: f64) -> Encoders {
        let mut rng = sensor_rng(seed, SensorStream::Encoders);
        let np = NoiseParams {
            white_std: params.noise_std_rad,
            bias_std: params.offset_std_rad,
            quantum: params.resolution_rad,
            ..NoiseParams::NONE
        };
        let channels = (0..n_joints)
            .map(|_| NoiseChannel::new(np, &mut rng))
            .collect();
        Encoders {
            params,
            channels,
            rng,
            gate: RateGate::new(params.rate_hz, t0_s),
            sampled: false,
            position_rad: vec![0.0; n_joints],
            velocity_radps: vec![0.0; n_joints],
        }
    }

    /// Call at every simulation step with the true joint angles and
    /// velocities at `t_s`; returns whether a new sample was taken.
    pub fn update(&mut self, t_s: f64, q_rad: &[f64], qd_radps: &[f64]) -> bool {
        // an x86-64-v3 clone (three-operand VEX forms, wider vectors; no
        // fused multiply–add, so the same bits), in a free function:
        // multiversion takes no `self`
        #[multiversion::multiversion(targets("x86_64+avx2+fma"))]
        fn body(this: &mut Encoders, t_s: f64, q_rad: &[f64], qd_radps: &[f64]) -> bool {
            let Some(dt) = this.gate.tick(t_s) else {
                return false;
            };
            // the velocity filter's coefficient, the same for every joint
            let alpha = match this.params.velocity {
                JointVelocityMode::Differencing {
                    filter_time_constant_s,
                } if filter_time_constant_s > 0.0 => 1.0 - (-dt / filter_time_constant_s).exp(),
                _ => 1.0,
            };
            // every joint's slots zipped (no bounds check per joint); a short
            // `q_rad` or `qd_radps` still panics, as indexing did
            let n_joints = this.channels.len();
            let (q_rad, qd_radps) = (&q_rad[..n_joints], &qd_radps[..n_joints]);
            let joints = this
                .channels
                .iter_mut()
                .zip(q_rad.iter().zip(qd_radps))
                .zip(this.position_rad.iter_mut().zip(&mut this.velocity_radps));
            // the velocity's source decided once for every joint
            let velocity = match this.params.velocity {
                JointVelocityMode::Direct { noise_std_radps } => Some(noise_std_radps),
                JointVelocityMode::Differencing { .. } => None,
            };
            let differences = this.sampled && dt > 0.0;
            for ((ch, (&q, &qd)), (pos, vel)) in joints {
                let theta = ch.sample(q, dt, &mut this.rng);
                let n = gaussian(&mut this.rng);
                let w = match velocity {
                    Some(noise_std_radps) => qd + noise_std_radps * n,
                    None if differences => {
                        let raw = (theta - *pos) / dt;
                        *vel + alpha * (raw - *vel)
                    }
                    None => 0.0,
                };
                *pos = theta;
                *vel = w;
            }
            this.sampled = true;
            true
        }
        body(self, t_s, q_rad, qd_radps)
    }
}
