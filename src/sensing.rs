//! Builds a robot's sensors and base estimator from `[robots.sensors]` and
//! `[robots.estimator]` (`scenarios/README.md`, `docs/sensors.md`).

use quadsim_components::{RobotSensing, StateSource};
use quadsim_engine::Model;
use quadsim_engine::contact::ContactPoint;
use quadsim_engine::estimation::{BaseEstimator, EstimatorParams};
use quadsim_engine::robots;
use quadsim_engine::sensors::noise::NoiseParams;
use quadsim_engine::sensors::{JointVelocityMode, SensorConfig, SensorSuite};

use crate::scenario::format::RobotSpec;
use crate::scenario::{Locator, ScenarioError};

/// What the controller reads when `[robots.estimator] state_source` is not given.
pub const DEFAULT_STATE_SOURCE: StateSource = StateSource::Estimated;

/// The random stream name of a robot's sensors: `sensors/<robot name>`
/// (seeded with [`crate::world::stream_seed`], independent of robot order).
pub fn sensor_stream_name(robot: &str) -> String {
    format!("sensors/{robot}")
}

/// A number that must be finite and ≥ 0 (> 0 when `positive`).
fn check(
    loc: &Locator<'_>,
    path: &str,
    v: Option<f64>,
    positive: bool,
) -> Result<(), ScenarioError> {
    match v {
        Some(x) if !x.is_finite() || x < 0.0 || (positive && x == 0.0) => Err(loc.at(
            path,
            format!(
                "{x} is invalid: expected a finite number {}",
                if positive { "> 0" } else { "≥ 0" }
            ),
        )),
        _ => Ok(()),
    }
}

/// The sensor configuration of robot `r` (key path `p`, total mass
/// `total_mass_kg`: a robot that is not built in gets foot sensors sized to
/// it, [`robots::default_sensors`]), or `None` for `preset = "none"`.
pub fn sensor_config(
    loc: &Locator<'_>,
    p: &str,
    r: &RobotSpec,
    controller_rate_hz: f64,
    total_mass_kg: f64,
) -> Result<Option<SensorConfig>, ScenarioError> {
    let s = &r.sensors;
    let sp = format!("{p}.sensors");
    check(loc, &format!("{sp}.rate_hz"), s.rate_hz, true)?;
    let rate = s.rate_hz.unwrap_or(controller_rate_hz);
    let mut cfg = match s.preset.as_deref().unwrap_or("default") {
        "default" => {
            SensorConfig::from_spec(&robots::default_sensors(&r.model, total_mass_kg), rate)
        }
        "ideal" => {
            let d =
                SensorConfig::from_spec(&robots::default_sensors(&r.model, total_mass_kg), rate);
            SensorConfig {
                imu: d
                    .imu
                    .map(|i| quadsim_engine::sensors::ImuParams::ideal(i.rate_hz)),
                encoders: d
                    .encoders
                    .map(|e| quadsim_engine::sensors::EncoderParams::ideal(e.rate_hz)),
                contacts: d
                    .contacts
                    .map(|c| quadsim_engine::sensors::ContactSensorParams {
                        noise: NoiseParams::NONE,
                        ..c
                    }),
                mocap: None,
            }
        }
        "none" => return Ok(None),
        other => {
            return Err(loc.at(
                &format!("{sp}.preset"),
                format!("unknown preset '{other}': expected \"default\", \"ideal\" or \"none\""),
            ));
        }
    };
    if let Some(i) = &s.imu {
        let ip = format!("{sp}.imu");
        for (k, v, pos) in [
            ("rate_hz", i.rate_hz, true),
            ("accel_noise_std_mps2", i.accel_noise_std_mps2, false),
            ("accel_bias_std_mps2", i.accel_bias_std_mps2, false),
            (
                "accel_bias_walk_mps2_per_sqrt_s",
                i.accel_bias_walk_mps2_per_sqrt_s,
                false,
            ),
            ("accel_range_mps2", i.accel_range_mps2, true),
            ("accel_resolution_mps2", i.accel_resolution_mps2, false),
            ("gyro_noise_std_radps", i.gyro_noise_std_radps, false),
            ("gyro_bias_std_radps", i.gyro_bias_std_radps, false),
            (
                "gyro_bias_walk_radps_per_sqrt_s",
                i.gyro_bias_walk_radps_per_sqrt_s,
                false,
            ),
            ("gyro_range_radps", i.gyro_range_radps, true),
            ("gyro_resolution_radps", i.gyro_resolution_radps, false),
        ] {
            check(loc, &format!("{ip}.{k}"), v, pos)?;
        }
        if i.enabled == Some(false) {
            cfg.imu = None;
        } else if let Some(m) = cfg.imu.as_mut() {
            let set = |n: &mut NoiseParams,
                       w: Option<f64>,
                       b: Option<f64>,
                       bw: Option<f64>,
                       r: Option<f64>,
                       q: Option<f64>| {
                n.white_std = w.unwrap_or(n.white_std);
                n.bias_std = b.unwrap_or(n.bias_std);
                n.bias_walk_std_per_sqrt_s = bw.unwrap_or(n.bias_walk_std_per_sqrt_s);
                n.saturation = r.unwrap_or(n.saturation);
                n.quantum = q.unwrap_or(n.quantum);
            };
            m.rate_hz = i.rate_hz.unwrap_or(m.rate_hz);
            set(
                &mut m.accel,
                i.accel_noise_std_mps2,
                i.accel_bias_std_mps2,
                i.accel_bias_walk_mps2_per_sqrt_s,
                i.accel_range_mps2,
                i.accel_resolution_mps2,
            );
            set(
                &mut m.gyro,
                i.gyro_noise_std_radps,
                i.gyro_bias_std_radps,
                i.gyro_bias_walk_radps_per_sqrt_s,
                i.gyro_range_radps,
                i.gyro_resolution_radps,
            );
        }
    }
    if let Some(e) = &s.encoders {
        let ep = format!("{sp}.encoders");
        for (k, v, pos) in [
            ("rate_hz", e.rate_hz, true),
            ("resolution_rad", e.resolution_rad, false),
            ("noise_std_rad", e.noise_std_rad, false),
            ("offset_std_rad", e.offset_std_rad, false),
            ("velocity_filter_s", e.velocity_filter_s, false),
            (
                "velocity_noise_std_radps",
                e.velocity_noise_std_radps,
                false,
            ),
        ] {
            check(loc, &format!("{ep}.{k}"), v, pos)?;
        }
        if e.enabled == Some(false) {
            cfg.encoders = None;
        } else if let Some(m) = cfg.encoders.as_mut() {
            m.rate_hz = e.rate_hz.unwrap_or(m.rate_hz);
            m.resolution_rad = e.resolution_rad.unwrap_or(m.resolution_rad);
            m.noise_std_rad = e.noise_std_rad.unwrap_or(m.noise_std_rad);
            m.offset_std_rad = e.offset_std_rad.unwrap_or(m.offset_std_rad);
            let (filter, noise) = match m.velocity {
                JointVelocityMode::Differencing {
                    filter_time_constant_s,
                } => (filter_time_constant_s, 0.0),
                JointVelocityMode::Direct { noise_std_radps } => (0.002, noise_std_radps),
            };
            let kind = match e.velocity.as_deref() {
                None => match m.velocity {
                    JointVelocityMode::Differencing { .. } => "differencing",
                    JointVelocityMode::Direct { .. } => "direct",
                },
                Some(k @ ("differencing" | "direct")) => k,
                Some(other) => {
                    return Err(loc.at(
                        &format!("{ep}.velocity"),
                        format!("unknown velocity source '{other}': expected \"differencing\" or \"direct\""),
                    ));
                }
            };
            m.velocity = if kind == "differencing" {
                JointVelocityMode::Differencing {
                    filter_time_constant_s: e.velocity_filter_s.unwrap_or(filter),
                }
            } else {
                JointVelocityMode::Direct {
                    noise_std_radps: e.velocity_noise_std_radps.unwrap_or(noise),
                }
            };
        }
    }
    if let Some(c) = &s.contacts {
        let cp = format!("{sp}.contacts");
        for (k, v, pos) in [
            ("rate_hz", c.rate_hz, true),
            ("on_threshold_n", c.on_threshold_n, false),
            ("off_threshold_n", c.off_threshold_n, false),
            ("noise_std_n", c.noise_std_n, false),
        ] {
            check(loc, &format!("{cp}.{k}"), v, pos)?;
        }
        if c.enabled == Some(false) {
            cfg.contacts = None;
        } else if let Some(m) = cfg.contacts.as_mut() {
            m.rate_hz = c.rate_hz.unwrap_or(m.rate_hz);
            m.on_threshold_n = c.on_threshold_n.unwrap_or(m.on_threshold_n);
            m.off_threshold_n = c.off_threshold_n.unwrap_or(m.off_threshold_n);
            m.noise.white_std = c.noise_std_n.unwrap_or(m.noise.white_std);
            m.force_output = c.force_output.unwrap_or(m.force_output);
            if m.off_threshold_n > m.on_threshold_n {
                return Err(loc.at(
                    &format!("{cp}.off_threshold_n"),
                    format!(
                        "{} N is above on_threshold_n = {} N: hysteresis needs off ≤ on",
                        m.off_threshold_n, m.on_threshold_n
                    ),
                ));
            }
        }
    }
    if let Some(m) = &s.mocap {
        let mp = format!("{sp}.mocap");
        for (k, v, pos) in [
            ("rate_hz", m.rate_hz, true),
            ("latency_s", m.latency_s, false),
            ("position_noise_std_m", m.position_noise_std_m, false),
            (
                "orientation_noise_std_rad",
                m.orientation_noise_std_rad,
                false,
            ),
        ] {
            check(loc, &format!("{mp}.{k}"), v, pos)?;
        }
        if m.enabled != Some(false) {
            let d = SensorConfig::default_mocap();
            cfg.mocap = Some(quadsim_engine::sensors::MocapParams {
                rate_hz: m.rate_hz.unwrap_or(d.rate_hz),
                latency_s: m.latency_s.unwrap_or(d.latency_s),
                position_noise_std_m: m.position_noise_std_m.unwrap_or(d.position_noise_std_m),
                orientation_noise_std_rad: m
                    .orientation_noise_std_rad
                    .unwrap_or(d.orientation_noise_std_rad),
            });
        }
    }
    Ok(Some(cfg))
}

/// The estimator's tuning from `[robots.estimator]`.
fn estimator_params(
    loc: &Locator<'_>,
    p: &str,
    r: &RobotSpec,
) -> Result<EstimatorParams, ScenarioError> {
    let e = &r.estimator;
    let ep = format!("{p}.estimator");
    for (k, v) in [
        ("attitude_kp_radps", e.attitude_kp_radps),
        ("attitude_ki_radps2", e.attitude_ki_radps2),
        ("accel_filter_s", e.accel_filter_s),
        ("accel_process_std", e.accel_process_std),
        ("foot_position_std_m", e.foot_position_std_m),
        ("foot_velocity_std_mps", e.foot_velocity_std_mps),
        ("foot_height_std_m", e.foot_height_std_m),
        ("velocity_gate_chi2", e.velocity_gate_chi2),
        (
            "mocap_orientation_time_constant_s",
            e.mocap_orientation_time_constant_s,
        ),
    ] {
        check(loc, &format!("{ep}.{k}"), v, false)?;
    }
    check(
        loc,
        &format!("{ep}.mocap_position_std_m"),
        e.mocap_position_std_m,
        true,
    )?;
    let mut params = EstimatorParams::default();
    let a = &mut params.attitude;
    a.kp_radps = e.attitude_kp_radps.unwrap_or(a.kp_radps);
    a.ki_radps2 = e.attitude_ki_radps2.unwrap_or(a.ki_radps2);
    a.accel_filter_s = e.accel_filter_s.unwrap_or(a.accel_filter_s);
    a.compensate_base_acceleration = e
        .compensate_base_acceleration
        .unwrap_or(a.compensate_base_acceleration);
    let k = &mut params.kf;
    k.accel_process_std = e.accel_process_std.unwrap_or(k.accel_process_std);
    k.foot_position_std_m = e.foot_position_std_m.unwrap_or(k.foot_position_std_m);
    k.foot_velocity_std_mps = e.foot_velocity_std_mps.unwrap_or(k.foot_velocity_std_mps);
    k.foot_height_std_m = e.foot_height_std_m.unwrap_or(k.foot_height_std_m);
    k.velocity_gate_chi2 = e.velocity_gate_chi2.unwrap_or(k.velocity_gate_chi2);
    let m = &mut params.mocap;
    m.enabled = e.fuse_mocap.unwrap_or(m.enabled);
    m.position_std_m = e.mocap_position_std_m.unwrap_or(m.position_std_m);
    m.orientation_time_constant_s = e
        .mocap_orientation_time_constant_s
        .unwrap_or(m.orientation_time_constant_s);
    Ok(params)
}

/// Robot `r`'s sensing, started at `(q, v)`: its sensors seeded with
/// `seed` (see [`sensor_stream_name`]), the estimator on its `feet`, the
/// state source; `None` with `preset = "none"` (ground truth).
pub fn robot_sensing(
    loc: &Locator<'_>,
    p: &str,
    r: &RobotSpec,
    model: &Model,
    feet: &[ContactPoint],
    q: &[f64],
    v: &[f64],
    controller_rate_hz: f64,
    seed: u64,
) -> Result<Option<Box<RobotSensing>>, ScenarioError> {
    let source_path = format!("{p}.estimator.state_source");
    let source = match r.estimator.state_source.as_deref() {
        None => None,
        Some("estimated") => Some(StateSource::Estimated),
        Some("ground_truth") => Some(StateSource::GroundTruth),
        Some(other) => {
            return Err(loc.at(
                &source_path,
                format!(
                    "unknown state source '{other}': expected \"estimated\" or \"ground_truth\""
                ),
            ));
        }
    };
    let params = estimator_params(loc, p, r)?;
    let Some(cfg) = sensor_config(loc, p, r, controller_rate_hz, model.total_mass)? else {
        if source == Some(StateSource::Estimated) {
            return Err(loc.at(
                &source_path,
                "\"estimated\" needs sensors: [robots.sensors] preset is \"none\"",
            ));
        }
        return Ok(None);
    };
    // An external controller is sent ground-truth frames (docs/monitor.md);
    // its in-process PD reads the same state unless told otherwise.
    let external = r.controller.kind.as_deref() == Some("external");
    let source = source.unwrap_or(if external {
        StateSource::GroundTruth
    } else {
        DEFAULT_STATE_SOURCE
    });
    if source == StateSource::Estimated && cfg.imu.is_none() {
        return Err(loc.at(
            &format!("{p}.sensors.imu.enabled"),
            "\"estimated\" needs the IMU (the estimator runs on it): enable [robots.sensors.imu] or read \"ground_truth\"",
        ));
    }
    let nj = model.nv - model.base_nv();
    let suite = SensorSuite::new(&cfg, seed, nj, feet.len(), 0.0);
    // without a mocap sensor nothing is fused, so no history is kept for it
    let mut params = params;
    params.mocap.enabled &= cfg.mocap.is_some();
    let estimator = cfg
        .imu
        .is_some()
        .then(|| BaseEstimator::new(model, feet, params, q, v, 0.0));
    Ok(Some(Box::new(RobotSensing::new(
        suite,
        estimator,
        source,
        q,
        v,
        feet.len(),
    ))))
}

/// A robot's `sensing` object in `summary.json`: what the controller read
/// and the estimation error against ground truth (RMS and maximum over the
/// estimator's updates): orientation (rad, the whole rotation), tilt (rad,
/// torso z axis only), base velocity (m/s, world) and height above ground
/// (m). `{"state_source": "ground_truth", "estimation": null}` without sensors.
pub fn sensing_json(s: Option<&RobotSensing>) -> serde_json::Value {
    use serde_json::json;
    let Some(s) = s else {
        return json!({"state_source": StateSource::GroundTruth.as_str(), "estimation": null});
    };
    let stat = |e: &quadsim_engine::estimation::ErrorStat| json!({"rms": e.rms(), "max": e.max});
    let est = s.estimator.as_ref().map(|_| {
        let e = &s.errors;
        json!({
            "updates": e.orientation_rad.n,
            "orientation_rad": stat(&e.orientation_rad),
            "tilt_rad": stat(&e.tilt_rad),
            "velocity_mps": stat(&e.velocity_mps),
            "height_m": stat(&e.height_m),
        })
    });
    json!({"state_source": s.state_source.as_str(), "estimation": est})
}
