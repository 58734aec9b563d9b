//! `[robots.sensors]` and `[robots.estimator]`: a robot's sensors and base
//! state estimator (documented in `scenarios/README.md` and `docs/sensors.md`).
//! Every number left out takes the robot's default (`robots::default_sensors`,
//! built by `SensorConfig::from_spec`).

use schemars::JsonSchema;
use serde::Deserialize;

/// `[robots.sensors]`.
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensorsSpec {
    /// `default` (the model's datasheet-like noise set), `ideal` (no noise,
    /// no quantisation, no saturation) or `none` (no sensors: the controller
    /// reads ground truth). Default `default`.
    pub preset: Option<String>,
    /// Rate of every sensor (Hz). Default: the controller rate.
    pub rate_hz: Option<f64>,
    /// `[robots.sensors.imu]`.
    pub imu: Option<ImuSpec>,
    /// `[robots.sensors.encoders]`.
    pub encoders: Option<EncodersSpec>,
    /// `[robots.sensors.contacts]`.
    pub contacts: Option<ContactsSpec>,
    /// `[robots.sensors.mocap]` (off unless given).
    pub mocap: Option<MocapSpec>,
}

/// `[robots.sensors.imu]`: torso IMU (torso frame).
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImuSpec {
    /// Default true.
    pub enabled: Option<bool>,
    /// Output rate (Hz).
    pub rate_hz: Option<f64>,
    /// Accelerometer white noise per sample (m/s²).
    pub accel_noise_std_mps2: Option<f64>,
    /// Accelerometer turn-on bias std (m/s²).
    pub accel_bias_std_mps2: Option<f64>,
    /// Accelerometer bias random walk (m/s² per √s).
    pub accel_bias_walk_mps2_per_sqrt_s: Option<f64>,
    /// Accelerometer full-scale range (m/s²).
    pub accel_range_mps2: Option<f64>,
    /// Accelerometer resolution (m/s²; 0: continuous).
    pub accel_resolution_mps2: Option<f64>,
    /// Gyroscope white noise per sample (rad/s).
    pub gyro_noise_std_radps: Option<f64>,
    /// Gyroscope turn-on bias std (rad/s).
    pub gyro_bias_std_radps: Option<f64>,
    /// Gyroscope bias random walk (rad/s per √s).
    pub gyro_bias_walk_radps_per_sqrt_s: Option<f64>,
    /// Gyroscope full-scale range (rad/s).
    pub gyro_range_radps: Option<f64>,
    /// Gyroscope resolution (rad/s; 0: continuous).
    pub gyro_resolution_radps: Option<f64>,
}

/// `[robots.sensors.encoders]`: one per joint.
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EncodersSpec {
    /// Default true.
    pub enabled: Option<bool>,
    /// Output rate (Hz).
    pub rate_hz: Option<f64>,
    /// Angle resolution (rad; 0: continuous).
    pub resolution_rad: Option<f64>,
    /// Angle white noise (rad).
    pub noise_std_rad: Option<f64>,
    /// Calibration offset std per joint (rad), drawn once.
    pub offset_std_rad: Option<f64>,
    /// `differencing` (of the measured angles, low-passed) or `direct` (true velocity + noise).
    pub velocity: Option<String>,
    /// Differencing: first-order filter time constant (s).
    pub velocity_filter_s: Option<f64>,
    /// Direct: white noise (rad/s).
    pub velocity_noise_std_radps: Option<f64>,
}

/// `[robots.sensors.contacts]`: one per foot.
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactsSpec {
    /// Default true.
    pub enabled: Option<bool>,
    /// Output rate (Hz).
    pub rate_hz: Option<f64>,
    /// Force above which contact turns on (N).
    pub on_threshold_n: Option<f64>,
    /// Force below which contact turns off (N; ≤ on).
    pub off_threshold_n: Option<f64>,
    /// Force white noise (N).
    pub noise_std_n: Option<f64>,
    /// Whether the measured force is an output (a force sensor) or only the flag.
    pub force_output: Option<bool>,
}

/// `[robots.sensors.mocap]`: torso pose from motion capture.
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MocapSpec {
    /// Default true when the table is given.
    pub enabled: Option<bool>,
    /// Capture rate (Hz). Default 120.
    pub rate_hz: Option<f64>,
    /// Latency (s; rounded to whole samples). Default 0.01.
    pub latency_s: Option<f64>,
    /// Position noise per axis (m). Default 0.0005.
    pub position_noise_std_m: Option<f64>,
    /// Orientation noise per axis (rad). Default 0.002.
    pub orientation_noise_std_rad: Option<f64>,
}

/// `[robots.estimator]`: the base state estimator and what the controller reads.
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EstimatorSpec {
    /// `estimated` (base from the estimator, joints from the encoders,
    /// contacts from the contact sensors) or `ground_truth` (the
    /// simulator's exact state). Default: see `scenarios/README.md`.
    pub state_source: Option<String>,
    /// Attitude filter proportional gain (rad/s).
    pub attitude_kp_radps: Option<f64>,
    /// Attitude filter integral (gyro bias) gain (rad/s²).
    pub attitude_ki_radps2: Option<f64>,
    /// Low-pass time constant of the world-frame specific force (s).
    pub accel_filter_s: Option<f64>,
    /// Whether the attitude filter removes the base's estimated
    /// acceleration from the specific force. Default true.
    pub compensate_base_acceleration: Option<bool>,
    /// Kalman filter: acceleration input noise (m/s² √s).
    pub accel_process_std: Option<f64>,
    /// Kalman filter: foot position from kinematics (m).
    pub foot_position_std_m: Option<f64>,
    /// Kalman filter: base velocity from a stance foot (m/s).
    pub foot_velocity_std_mps: Option<f64>,
    /// Kalman filter: stance foot height (m).
    pub foot_height_std_m: Option<f64>,
    /// Kalman filter: χ² gate on a stance foot's velocity (≤ 0: none).
    pub velocity_gate_chi2: Option<f64>,
    /// Whether motion capture (when on) is fused into the estimate. Default true.
    pub fuse_mocap: Option<bool>,
    /// Mocap position noise the fusion assumes, per axis (m). Default 0.002.
    pub mocap_position_std_m: Option<f64>,
    /// Time constant of the orientation's pull toward mocap (s). Default 0.1.
    pub mocap_orientation_time_constant_s: Option<f64>,
}
