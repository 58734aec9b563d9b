//! A robot's sensors together, and the default sets per robot model.

use glam::{DMat3, DQuat, DVec3};

use super::contact::{ContactSensorParams, ContactSensors};
use super::encoders::{EncoderParams, Encoders, JointVelocityMode};
use super::imu::{Imu, ImuParams};
use super::mocap::{Mocap, MocapParams};
use super::noise::NoiseParams;

/// Which sensors a robot carries and their parameters (`None`: absent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorConfig {
    /// Torso IMU.
    pub imu: Option<ImuParams>,
    /// Joint encoders.
    pub encoders: Option<EncoderParams>,
    /// Foot contact sensors.
    pub contacts: Option<ContactSensorParams>,
    /// Motion capture of the torso.
    pub mocap: Option<MocapParams>,
}

/// Standard gravity (m/s²), to write accelerometer figures given in g.
const G: f64 = 9.806_65;

/// quad16's mass (kg): the reference of [`SensorConfig::defaults_for_robot`]'s
/// scaling of the foot sensors.
const QUAD16_MASS_KG: f64 = 28.0;

impl SensorConfig {
    /// The default sensors of a built-in model (`"quad16"`, `"quad12"`;
    /// anything else gets quad16's), every sensor at `rate_hz` (the
    /// controller rate), mocap off. Figures and sources in `docs/sensors.md`:
    ///
    /// - quad16 (a 28 kg research quadruped): a Bosch BMI088-class IMU
    ///   (±24 g, ±2000 °/s, 16 bit; noise densities 175 µg/√Hz and
    ///   0.014 °/s/√Hz over a bandwidth of rate/2; residual biases after a
    ///   start-up calibration), 14-bit absolute joint encoders with velocity
    ///   by differencing (2 ms filter), foot force sensing with 20/10 N
    ///   thresholds and 2 N noise.
    /// - quad12 (Study B's 12 kg hobby-servo robot): an InvenSense
    ///   MPU-6050-class IMU (±8 g, ±500 °/s, 16 bit; 400 µg/√Hz,
    ///   0.005 °/s/√Hz), 10-bit servo potentiometers over 300° (5.1 mrad) with
    ///   velocity by differencing (10 ms filter), foot switches at 8/4 N.
    pub fn defaults_for(model: &str, rate_hz: f64) -> SensorConfig {
        let bw = (rate_hz / 2.0).sqrt();
        let deg = std::f64::consts::PI / 180.0;
        let (acc_density, gyro_density, acc_range, gyro_range) = if model == "quad12" {
            (400e-6 * G, 0.005 * deg, 8.0 * G, 500.0 * deg)
        } else {
            (175e-6 * G, 0.014 * deg, 24.0 * G, 2000.0 * deg)
        };
        let imu = ImuParams {
            rate_hz,
            accel: NoiseParams {
                white_std: acc_density * bw,
                bias_std: 0.02,
                bias_walk_std_per_sqrt_s: 1e-3,
                saturation: acc_range,
                quantum: 2.0 * acc_range / 65536.0,
            },
            gyro: NoiseParams {
                white_std: gyro_density * bw,
                bias_std: 1e-3,
                bias_walk_std_per_sqrt_s: 1e-4,
                saturation: gyro_range,
                quantum: 2.0 * gyro_range / 65536.0,
            },
        };
        let (encoders, contacts) = if model == "quad12" {
            (
                EncoderParams {
                    rate_hz,
                    resolution_rad: 300.0 * deg / 1024.0,
                    noise_std_rad: 2e-3,
                    offset_std_rad: 0.0,
                    velocity: JointVelocityMode::Differencing {
                        filter_time_constant_s: 0.01,
                    },
                },
                ContactSensorParams {
                    rate_hz,
                    on_threshold_n: 8.0,
                    off_threshold_n: 4.0,
                    noise: NoiseParams::white(1.0),
                    force_output: false,
                },
            )
        } else {
            (
                EncoderParams {
                    rate_hz,
                    resolution_rad: std::f64::consts::TAU / 16384.0,
                    noise_std_rad: 1e-4,
                    offset_std_rad: 0.0,
                    velocity: JointVelocityMode::Differencing {
                        filter_time_constant_s: 0.002,
                    },
                },
                ContactSensorParams {
                    rate_hz,
                    on_threshold_n: 20.0,
                    off_threshold_n: 10.0,
                    noise: NoiseParams::white(2.0),
                    force_output: true,
                },
            )
        };
        SensorConfig {
            imu: Some(imu),
            encoders: Some(encoders),
            contacts: Some(contacts),
            mocap: None,
        }
    }

    /// The default sensors of a robot of `total_mass_kg` called `model`: a
    /// built-in robot's ([`Self::defaults_for`], unchanged); any other robot
    /// gets quad16's set with its foot force sensors sized to the robot:
    /// thresholds and noise times `total_mass_kg / 28` (quad16's 28 kg).
    /// quad16's 20 N threshold is 29 % of its standing load per foot; an
    /// 8.9 kg robot stands on 22 N per foot, so at 20 N its feet flicker in
    /// and out of contact while standing and read as off the ground in
    /// two-foot support's unloading (its trot fell within 0.21 s on the
    /// sensed state; docs/walking.md, "Any quadruped").
    pub fn defaults_for_robot(model: &str, total_mass_kg: f64, rate_hz: f64) -> SensorConfig {
        let mut cfg = Self::defaults_for(model, rate_hz);
        let builtin = crate::robots::builtin_names().contains(&model);
        if !builtin && total_mass_kg.is_finite() && total_mass_kg > 0.0 {
            let r = total_mass_kg / QUAD16_MASS_KG;
            if let Some(c) = cfg.contacts.as_mut() {
                c.on_threshold_n *= r;
                c.off_threshold_n *= r;
                c.noise.white_std *= r;
            }
        }
        cfg
    }

    /// Mocap's defaults when switched on: 120 Hz, 10 ms latency, 0.5 mm and
    /// 2 mrad noise (an optical system such as Vicon or OptiTrack).
    pub fn default_mocap() -> MocapParams {
        MocapParams {
            rate_hz: 120.0,
            latency_s: 0.01,
            position_noise_std_m: 5e-4,
            orientation_noise_std_rad: 2e-3,
        }
    }
}

/// The true state the sensors measure, at one instant.
#[derive(Clone, Copy, Debug)]
pub struct SensorTruth<'a> {
    /// Time (s).
    pub t_s: f64,
    /// Torso position (m, world).
    pub position_m: DVec3,
    /// Torso orientation (torso → world).
    pub orientation: DQuat,
    /// Torso origin velocity (m/s, world).
    pub velocity_world_mps: DVec3,
    /// Torso angular velocity (rad/s, torso frame).
    pub omega_body_radps: DVec3,
    /// Gravity (m/s², world).
    pub gravity_mps2: DVec3,
    /// Joint angles (rad).
    pub q_joints_rad: &'a [f64],
    /// Joint velocities (rad/s).
    pub qd_joints_radps: &'a [f64],
    /// Each foot's ground normal force (N).
    pub foot_normal_force_n: &'a [f64],
}

/// One robot's sensors.
#[derive(Clone, Debug)]
pub struct SensorSuite {
    /// Torso IMU.
    pub imu: Option<Imu>,
    /// Joint encoders.
    pub encoders: Option<Encoders>,
    /// Foot contact sensors.
    pub contacts: Option<ContactSensors>,
    /// Motion capture.
    pub mocap: Option<Mocap>,
}

/// What changed in one [`SensorSuite::update`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SensorUpdates {
    /// A new IMU sample.
    pub imu: bool,
    /// New encoder readings.
    pub encoders: bool,
    /// New contact readings.
    pub contacts: bool,
    /// A mocap sample was delivered.
    pub mocap: bool,
}

impl SensorSuite {
    /// The sensors of `config` for `n_joints` joints and `n_feet` feet,
    /// seeded by the robot seed `seed`, first samples at `t0_s`.
    pub fn new(
        config: &SensorConfig,
        seed: u64,
        n_joints: usize,
        n_feet: usize,
        t0_s: f64,
    ) -> Self {
        SensorSuite {
            imu: config.imu.map(|p| Imu::new(p, seed, t0_s)),
            encoders: config
                .encoders
                .map(|p| Encoders::new(p, n_joints, seed, t0_s)),
            contacts: config
                .contacts
                .map(|p| ContactSensors::new(p, n_feet, seed, t0_s)),
            mocap: config.mocap.map(|p| Mocap::new(p, seed, t0_s)),
        }
    }

    /// Whether some sensor takes a sample at `t_s`. When none does,
    /// [`SensorSuite::update`] changes nothing and returns no update, so a
    /// caller may skip it and the truth it needs.
    pub fn any_due(&self, t_s: f64) -> bool {
        self.imu.as_ref().is_some_and(|s| s.due(t_s))
            || self.encoders.as_ref().is_some_and(|s| s.due(t_s))
            || self.contacts.as_ref().is_some_and(|s| s.due(t_s))
            || self.mocap.as_ref().is_some_and(|s| s.due(t_s))
    }

    /// Call at every simulation step with the truth at that instant.
    pub fn update(&mut self, truth: &SensorTruth<'_>) -> SensorUpdates {
        let rot = DMat3::from_quat(truth.orientation);
        SensorUpdates {
            imu: self.imu.as_mut().is_some_and(|s| {
                s.update(
                    truth.t_s,
                    rot,
                    truth.velocity_world_mps,
                    truth.omega_body_radps,
                    truth.gravity_mps2,
                )
                .is_some()
            }),
            encoders: self
                .encoders
                .as_mut()
                .is_some_and(|s| s.update(truth.t_s, truth.q_joints_rad, truth.qd_joints_radps)),
            contacts: self
                .contacts
                .as_mut()
                .is_some_and(|s| s.update(truth.t_s, truth.foot_normal_force_n)),
            mocap: self.mocap.as_mut().is_some_and(|s| {
                s.update(truth.t_s, truth.position_m, truth.orientation)
                    .is_some()
            }),
        }
    }
}
