//! A robot's sensors together, and a robot's default set from its sensor
//! hardware ([`SensorSpec`]).

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

/// Standard gravity, one g (m/s²), to write accelerometer figures given in g.
pub const ONE_G_MPS2: f64 = 9.806_65;

/// A robot's sensor hardware: the datasheet figures its default
/// [`SensorConfig`] is built from ([`SensorConfig::from_spec`]). A robot
/// states its own: the built-ins in `robots::quad16::SENSORS` and
/// `robots::quad12::SENSORS`, any other robot quad16's sized to its mass
/// (`robots::default_sensors`). Figures and sources in `docs/sensors.md`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorSpec {
    /// Accelerometer noise density ((m/s²)/√Hz), over a bandwidth of half
    /// the sensor rate.
    pub accel_noise_density: f64,
    /// Gyroscope noise density ((rad/s)/√Hz).
    pub gyro_noise_density: f64,
    /// Accelerometer full scale (± m/s², over 16 bits).
    pub accel_range_mps2: f64,
    /// Gyroscope full scale (± rad/s, over 16 bits).
    pub gyro_range_radps: f64,
    /// Joint encoder quantum (rad).
    pub encoder_resolution_rad: f64,
    /// Joint encoder white noise (rad).
    pub encoder_noise_std_rad: f64,
    /// Time constant of the filter on the encoders' differenced velocity (s).
    pub encoder_velocity_filter_s: f64,
    /// Foot contact: force above which a foot is on the ground (N).
    pub contact_on_threshold_n: f64,
    /// Foot contact: force below which a foot is off the ground (N).
    pub contact_off_threshold_n: f64,
    /// Foot contact: white noise on the measured force (N).
    pub contact_noise_std_n: f64,
    /// Whether the foot sensors report the force (else contact only).
    pub contact_force_output: bool,
}

impl SensorSpec {
    /// The same sensors with the foot sensors' thresholds and noise times
    /// `factor` (a robot's mass over the mass they were chosen for).
    pub fn with_contacts_scaled(self, factor: f64) -> SensorSpec {
        SensorSpec {
            contact_on_threshold_n: self.contact_on_threshold_n * factor,
            contact_off_threshold_n: self.contact_off_threshold_n * factor,
            contact_noise_std_n: self.contact_noise_std_n * factor,
            ..self
        }
    }
}

impl SensorConfig {
    /// The sensors of `spec`, every sensor at `rate_hz` (the controller
    /// rate), mocap off: an IMU with residual biases after a start-up
    /// calibration and the white noise of its densities over a bandwidth of
    /// `rate_hz / 2`, 16-bit quanta over its ranges; joint encoders with
    /// velocity by differencing; foot contact sensors.
    pub fn from_spec(spec: &SensorSpec, rate_hz: f64) -> SensorConfig {
        let bw = (rate_hz / 2.0).sqrt();
        let (acc_range, gyro_range) = (spec.accel_range_mps2, spec.gyro_range_radps);
        let imu = ImuParams {
            rate_hz,
            accel: NoiseParams {
                white_std: spec.accel_noise_density * bw,
                bias_std: 0.02,
                bias_walk_std_per_sqrt_s: 1e-3,
                saturation: acc_range,
                quantum: 2.0 * acc_range / 65536.0,
            },
            gyro: NoiseParams {
                white_std: spec.gyro_noise_density * bw,
                bias_std: 1e-3,
                bias_walk_std_per_sqrt_s: 1e-4,
                saturation: gyro_range,
                quantum: 2.0 * gyro_range / 65536.0,
            },
        };
        let encoders = EncoderParams {
            rate_hz,
            resolution_rad: spec.encoder_resolution_rad,
            noise_std_rad: spec.encoder_noise_std_rad,
            offset_std_rad: 0.0,
            velocity: JointVelocityMode::Differencing {
                filter_time_constant_s: spec.encoder_velocity_filter_s,
            },
        };
        let contacts = ContactSensorParams {
            rate_hz,
            on_threshold_n: spec.contact_on_threshold_n,
            off_threshold_n: spec.contact_off_threshold_n,
            noise: NoiseParams::white(spec.contact_noise_std_n),
            force_output: spec.contact_force_output,
        };
        SensorConfig {
            imu: Some(imu),
            encoders: Some(encoders),
            contacts: Some(contacts),
            mocap: None,
        }
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
