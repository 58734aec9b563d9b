//! `summary.json`: the typed result of a run, written by `quadsim run`,
//! rebuilt from a log by `quadsim report`, embedded in the log's `metrics`
//! messages, and read by sweeps and optimisations. Keys and units are
//! defined in scenarios/README.md ("Metrics").
//!
//! The JSON text is written through [`serde_json::Value`] so that object
//! keys come out sorted: the same bytes as every earlier version of the
//! layout, whatever the order of the struct fields.

use quadsim_engine::metrics::MetricsSummary;
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::divergence::divergence_of;
use crate::log::read::LogContents;
use crate::scenario::Scenario;
use crate::world::World;

/// Version of `summary.json`'s layout; readers refuse another.
pub const SUMMARY_FORMAT_VERSION: u32 = 1;

/// Share of the run a joint may spend at its torque limit before a load
/// counts as not carried ("saturated").
pub const SATURATED_TIME_SHARE: f64 = 0.05;
/// Mean forward speed below this fraction of the walking command's mean (as
/// ramped) counts as "failed to track speed" (above [`TRACKED_COMMAND_MIN_MPS`]).
pub const SPEED_TRACKING_FRACTION: f64 = 0.9;
/// Smallest forward command whose tracking is judged (m/s).
pub const TRACKED_COMMAND_MIN_MPS: f64 = 0.05;

/// `summary.json`: deterministic fields, then `timing` (the only wall-clock part).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// [`SUMMARY_FORMAT_VERSION`].
    pub format_version: u32,
    /// The scenario's name.
    pub scenario: String,
    /// Simulated time at the end (s).
    #[serde(deserialize_with = "de_f64")]
    pub sim_time_s: f64,
    /// Steps run.
    pub steps: u64,
    /// Time step (s).
    #[serde(deserialize_with = "de_f64")]
    pub dt_s: f64,
    /// World seed.
    pub seed: u64,
    /// quadsim's version.
    pub quadsim_version: String,
    /// The commit quadsim was built from.
    pub git_commit: String,
    /// SHA-256 of the scenario file's text (hex).
    pub scenario_sha256: String,
    /// `semi_implicit_euler` or `rk4`.
    pub integrator: String,
    /// Controller rate (Hz).
    #[serde(deserialize_with = "de_f64")]
    pub controller_rate_hz: f64,
    /// One entry per robot, in the world's order.
    pub robots: Vec<RobotSummary>,
    /// The run stopped at a divergence (robot, time and quantity named).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diverged: Option<String>,
    /// The run was stopped by Ctrl-C or SIGTERM.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub interrupted: bool,
    /// The log the summary was rebuilt from ended early: the process was
    /// killed before closing it (`quadsim report` of a killed run).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub log_truncated: bool,
    /// Wall-clock figures (absent where a summary must be reproducible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
}

/// `summary.json`'s `timing`: wall-clock figures, never compared.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// Wall time of the stepping loop (s).
    #[serde(deserialize_with = "de_f64")]
    pub wall_time_s: f64,
    /// Simulated over wall time.
    #[serde(deserialize_with = "de_f64")]
    pub real_time_factor: f64,
    /// Worker threads used.
    pub threads: usize,
    /// Live frames published.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monitor_published: Option<u64>,
    /// Live frames dropped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monitor_dropped: Option<u64>,
    /// The pace `--real-time` asked for (simulated seconds per second).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "de_opt_f64"
    )]
    pub real_time_factor_asked: Option<f64>,
    /// How far the paced run fell behind wall-clock time at most (s).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "de_opt_f64"
    )]
    pub real_time_max_lag_s: Option<f64>,
    /// External commands applied.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub commands_applied: Option<u64>,
    /// External commands rejected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub commands_rejected: Option<u64>,
}

/// One robot's entry: its metrics (accumulated at every step), total mass,
/// actuator load, load verdict and state estimation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotSummary {
    /// The robot's name.
    pub name: String,
    /// Whether it fell.
    pub fell: bool,
    /// When it fell (s).
    #[serde(deserialize_with = "de_opt_f64")]
    pub fell_at_s: Option<f64>,
    /// Mean forward speed (m/s).
    #[serde(deserialize_with = "de_f64")]
    pub mean_forward_speed_mps: f64,
    /// Peak forward speed (m/s).
    #[serde(deserialize_with = "de_f64")]
    pub peak_forward_speed_mps: f64,
    /// Torso height, mean (m).
    #[serde(deserialize_with = "de_f64")]
    pub base_height_mean_m: f64,
    /// Torso height, peak to peak (m).
    #[serde(deserialize_with = "de_f64")]
    pub base_height_p2p_m: f64,
    /// CoM height, mean (m).
    #[serde(deserialize_with = "de_f64")]
    pub com_height_mean_m: f64,
    /// CoM height, peak to peak (m).
    #[serde(deserialize_with = "de_f64")]
    pub com_height_p2p_m: f64,
    /// Roll, `[min, max]` (rad).
    #[serde(deserialize_with = "de_f64_n")]
    pub roll_range_rad: [f64; 2],
    /// Pitch, `[min, max]` (rad).
    #[serde(deserialize_with = "de_f64_n")]
    pub pitch_range_rad: [f64; 2],
    /// Yaw, `[min, max]` (rad).
    #[serde(deserialize_with = "de_f64_n")]
    pub yaw_range_rad: [f64; 2],
    /// Joint tracking error, RMS over joints and time (rad).
    #[serde(deserialize_with = "de_opt_f64")]
    pub joint_rms_error_rad: Option<f64>,
    /// Largest vertical foot force (N).
    #[serde(deserialize_with = "de_f64")]
    pub max_foot_force_n: f64,
    /// Positive mechanical work of the joints (J).
    #[serde(deserialize_with = "de_f64")]
    pub energy_j: f64,
    /// Energy per gait cycle (J).
    #[serde(deserialize_with = "de_opt_f64")]
    pub energy_per_step_j: Option<f64>,
    /// Gait steps counted.
    pub steps: u64,
    /// Smallest support-polygon stability margin (m).
    #[serde(deserialize_with = "de_opt_f64")]
    pub min_stability_margin_m: Option<f64>,
    /// Forward distance (m).
    #[serde(deserialize_with = "de_f64")]
    pub distance_m: f64,
    /// CoM displacement, world `[x, y, z]` (m).
    #[serde(deserialize_with = "de_f64_n")]
    pub com_displacement_m: [f64; 3],
    /// CoM mean velocity, world `[x, y, z]` (m/s).
    #[serde(deserialize_with = "de_f64_n")]
    pub com_mean_velocity_mps: [f64; 3],
    /// CoM oscillation, world `[x, y, z]` (m).
    #[serde(deserialize_with = "de_f64_n")]
    pub com_oscillation_m: [f64; 3],
    /// Per actuated joint torque figures, in the joint arrays' order.
    pub joints: Vec<JointTorque>,
    /// Total mass (kg).
    #[serde(deserialize_with = "de_f64")]
    pub total_mass_kg: f64,
    /// The walking command as ramped, averaged over the run (m/s).
    #[serde(deserialize_with = "de_opt_f64")]
    pub commanded_speed_mps: Option<f64>,
    /// Actuator load.
    pub actuators: ActuatorsSummary,
    /// Load verdict.
    pub load: LoadVerdict,
    /// State source and estimation errors (`crate::sensing::sensing_json`).
    pub sensing: Value,
    /// Study B's Table 4 torque comparison (prescribed controller on a
    /// robot with Study B's leg).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub study_b: Option<StudyBTorques>,
    /// The largest push recovered from (`crate::analysis`), when searched.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub push_recovery: Option<Value>,
    /// When and why the robot's run ended in a divergence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diverged: Option<RobotDivergence>,
}

/// A joint's torque magnitudes over the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointTorque {
    /// Joint name.
    pub name: String,
    /// Peak |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub peak_abs_torque_nm: f64,
    /// Mean |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub mean_abs_torque_nm: f64,
}

/// A robot's actuator load (definitions: docs/actuators.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActuatorsSummary {
    /// Largest peak torque over rated torque of any joint.
    #[serde(deserialize_with = "de_f64")]
    pub max_peak_torque_share: f64,
    /// Largest share of the run any joint spent at its torque limit.
    #[serde(deserialize_with = "de_f64")]
    pub max_time_share_at_torque_limit: f64,
    /// Largest share of the run any joint spent at its speed limit.
    #[serde(deserialize_with = "de_f64")]
    pub max_time_share_at_speed_limit: f64,
    /// Largest share of the run any joint spent on its torque–speed envelope.
    #[serde(deserialize_with = "de_f64")]
    pub max_time_share_at_envelope_limit: f64,
    /// Per joint.
    pub joints: Vec<JointLoadSummary>,
}

/// One joint's actuator load.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointLoadSummary {
    /// Joint name.
    pub joint: String,
    /// Peak applied |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub peak_torque_nm: f64,
    /// Peak over rated torque.
    #[serde(deserialize_with = "de_f64")]
    pub peak_torque_share: f64,
    /// Time at the torque limit (s).
    #[serde(deserialize_with = "de_f64")]
    pub time_at_torque_limit_s: f64,
    /// Time at the speed limit (s).
    #[serde(deserialize_with = "de_f64")]
    pub time_at_speed_limit_s: f64,
    /// Peak demanded |τ| before limits (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub peak_demand_nm: f64,
    /// Torque limit (N·m; `null`: unlimited).
    #[serde(deserialize_with = "de_opt_f64")]
    pub torque_limit_nm: Option<f64>,
    /// Speed limit (rad/s or m/s; `null`: unlimited).
    #[serde(deserialize_with = "de_opt_f64")]
    pub speed_limit: Option<f64>,
    /// Steps at the torque limit.
    pub torque_limit_hits: u64,
    /// Steps at the speed limit.
    pub speed_limit_hits: u64,
    /// Time on the torque–speed envelope (s).
    #[serde(deserialize_with = "de_f64")]
    pub time_at_envelope_limit_s: f64,
    /// Steps on the torque–speed envelope.
    pub envelope_limit_hits: u64,
    /// `ideal`, `dc_motor` or `servo`.
    pub kind: String,
}

/// Whether a robot carried its load, and if not why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoadVerdict {
    /// Carried: not fallen, not saturated, tracking its speed.
    pub carried: bool,
    /// `fell`, `saturated` or `failed to track speed`.
    pub reason: Option<String>,
}

/// Study B's torque comparison, one joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyBJoint {
    /// The study's model: peak |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub model_peak_nm: f64,
    /// The study's model: mean |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub model_mean_nm: f64,
    /// Simulated peak |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub sim_peak_nm: f64,
    /// Simulated mean |τ| (N·m).
    #[serde(deserialize_with = "de_f64")]
    pub sim_mean_nm: f64,
    /// Simulated over model peak.
    #[serde(deserialize_with = "de_f64")]
    pub peak_ratio_sim_to_model: f64,
    /// Simulated over model mean.
    #[serde(deserialize_with = "de_f64")]
    pub mean_ratio_sim_to_model: f64,
}

/// Study B's Table 4 comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyBTorques {
    /// Hip pitch (τ2).
    pub hip_tau2: StudyBJoint,
    /// Knee (τ3).
    pub knee_tau3: StudyBJoint,
    /// Samples compared.
    pub samples: u64,
}

/// Where a robot diverged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotDivergence {
    /// Simulated time (s).
    #[serde(deserialize_with = "de_f64")]
    pub t_s: f64,
    /// What diverged (the coordinate or contact named).
    pub what: String,
    /// The likely cause from the numbers.
    pub cause: String,
}

/// JSON writes non-finite numbers as `null`: read them back as NaN.
fn de_f64<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// An optional number (`null` is `None`).
fn de_opt_f64<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Option::<f64>::deserialize(d)
}

/// A fixed-size vector whose non-finite entries were written as `null`.
fn de_f64_n<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[f64; N], D::Error> {
    let v = Vec::<Option<f64>>::deserialize(d)?;
    let n = v.len();
    let v: Vec<f64> = v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect();
    v.try_into().map_err(|_| {
        serde::de::Error::invalid_length(n, &format!("an array of {N} numbers").as_str())
    })
}

impl Summary {
    /// The summary of `world` after a run of `scn`; `timing` from the wall
    /// time when given.
    pub fn of_world(scn: &Scenario, world: &World, wall_time_s: Option<f64>) -> Self {
        let clock = world.sim.clock();
        let robots = world
            .robots
            .iter()
            .filter_map(|(name, root)| {
                world
                    .sim
                    .robot(*root)
                    .map(|r| RobotSummary::in_world(world, name, r))
            })
            .collect();
        let sha = Sha256::digest(scn.source.as_bytes());
        let timing = wall_time_s.map(|wall_time_s| Timing {
            wall_time_s,
            real_time_factor: if wall_time_s > 0.0 {
                clock.time_s / wall_time_s
            } else {
                0.0
            },
            threads: world
                .sim
                .world
                .resource::<quadsim_components::SimThreadPool>()
                .threads(),
            monitor_published: None,
            monitor_dropped: None,
            real_time_factor_asked: None,
            real_time_max_lag_s: None,
            commands_applied: None,
            commands_rejected: None,
        });
        Summary {
            format_version: SUMMARY_FORMAT_VERSION,
            scenario: scn.name.clone(),
            sim_time_s: clock.time_s,
            steps: clock.step,
            dt_s: world.dt_s,
            seed: world.seed,
            quadsim_version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: env!("QUADSIM_GIT_COMMIT").to_string(),
            scenario_sha256: format!("{sha:x}"),
            integrator: integrator_name(scn).to_string(),
            controller_rate_hz: scn.file.world.controller_rate_hz,
            robots,
            diverged: None,
            interrupted: false,
            log_truncated: false,
            timing,
        }
    }

    /// As a JSON value (object keys sorted).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).expect("a summary serialises")
    }

    /// `summary.json`'s text: pretty JSON, keys sorted, a final newline.
    pub fn to_text(&self) -> String {
        serde_json::to_string_pretty(&self.to_json()).expect("json") + "\n"
    }

    /// Reads a summary from JSON, refusing another layout version.
    pub fn from_json(v: Value) -> Result<Self, String> {
        let version = v["format_version"].as_u64();
        if version != Some(u64::from(SUMMARY_FORMAT_VERSION)) {
            return Err(format!(
                "format_version: expected {SUMMARY_FORMAT_VERSION}, got {}",
                v["format_version"]
            ));
        }
        serde_json::from_value(v).map_err(|e| e.to_string())
    }

    /// `summary.json` without `timing`, from a log: the metrics from each
    /// robot's final `metrics` message (accumulated at full rate in the
    /// simulation, which a decimated log could not recompute), the rest from
    /// the log's metadata records (`scenario`, `quadsim`, `run`). A killed
    /// run's log has no `run` record and no metrics: its summary covers the
    /// messages recovered, with `log_truncated` set. Errors name the missing
    /// record, or the topic and key of a bad message.
    pub fn from_log(c: &LogContents) -> Result<Self, String> {
        let meta = |record: &str, key: &str| {
            c.meta(record, key)
                .ok_or_else(|| format!("the log has no metadata '{record}.{key}'"))
        };
        fn number<T: serde::de::DeserializeOwned>(
            text: Result<&str, String>,
            record: &str,
            key: &str,
        ) -> Result<T, String> {
            let text = text?;
            serde_json::from_str(text)
                .map_err(|e| format!("metadata '{record}.{key}' = {text:?}: {e}"))
        }
        let num = |record: &str, key: &str| -> Result<f64, String> {
            let v: Value = number(meta(record, key), record, key)?;
            Ok(v.as_f64().unwrap_or(f64::NAN))
        };
        let text = meta("scenario", "text")?;
        let sha = Sha256::digest(text.as_bytes());
        let mut robots = Vec::new();
        for m in &c.messages {
            let is_metrics = m
                .topic
                .rsplit_once('/')
                .is_some_and(|(_, last)| last == crate::log::schema::METRICS_SUFFIX);
            if is_metrics {
                let v = m
                    .json()
                    .map_err(|e| format!("{}: not JSON: {e}", m.topic))?;
                robots.push(serde_json::from_value(v).map_err(|e| format!("{}: {e}", m.topic))?);
            }
        }
        let format_version: u32 = number(
            meta("quadsim", "summary_format_version"),
            "quadsim",
            "summary_format_version",
        )?;
        if format_version != SUMMARY_FORMAT_VERSION {
            return Err(format!(
                "metadata 'quadsim.summary_format_version' = {format_version}: this quadsim reads {SUMMARY_FORMAT_VERSION}"
            ));
        }
        let dt_s = num("quadsim", "dt_s")?;
        // A killed run wrote no `run` record (nor the metrics, written at
        // the end): the summary then covers the messages recovered, up to
        // the last one, and says the log was truncated.
        let truncated = !c.metadata.contains_key("run");
        let (interrupted, sim_time_s, steps) = if truncated {
            let last_ns = c.messages.iter().map(|m| m.log_time_ns).max().unwrap_or(0);
            let t = last_ns as f64 * 1e-9;
            let steps = if dt_s > 0.0 {
                (t / dt_s).round() as u64
            } else {
                0
            };
            (false, t, steps)
        } else {
            (
                number(meta("run", "interrupted"), "run", "interrupted")?,
                num("run", "sim_time_s")?,
                number(meta("run", "steps"), "run", "steps")?,
            )
        };
        Ok(Summary {
            format_version,
            scenario: meta("scenario", "name")?.to_string(),
            sim_time_s,
            steps,
            dt_s,
            seed: number(meta("quadsim", "seed"), "quadsim", "seed")?,
            quadsim_version: meta("quadsim", "version")?.to_string(),
            git_commit: meta("quadsim", "git_commit")?.to_string(),
            scenario_sha256: format!("{sha:x}"),
            integrator: meta("quadsim", "integrator")?.to_string(),
            controller_rate_hz: num("quadsim", "controller_rate_hz")?,
            robots,
            diverged: None,
            interrupted,
            log_truncated: truncated,
            timing: None,
        })
    }

    /// The robot named `name`.
    pub fn robot_mut(&mut self, name: &str) -> Option<&mut RobotSummary> {
        self.robots.iter_mut().find(|r| r.name == name)
    }
}

/// The integrator's name as in `summary.json`.
pub fn integrator_name(scn: &Scenario) -> &'static str {
    match scn.file.world.integrator {
        crate::scenario::format::IntegratorSpec::SemiImplicitEuler => "semi_implicit_euler",
        crate::scenario::format::IntegratorSpec::Rk4 => "rk4",
    }
}

/// The actuated joints' names, in the order of the joint arrays.
pub fn joint_names(model: &quadsim_engine::Model) -> Vec<String> {
    (model.base_nv()..model.actuated_nv())
        .map(|vi| model.joint_name[model.v_body[vi]].clone())
        .collect()
}

/// A limit for JSON: `None` when unlimited (JSON has no infinity).
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// The actuator kind of joint `j` as `[robots.actuators]` spells it.
fn actuator_kind(r: &quadsim_components::RobotSim, j: usize) -> &'static str {
    use quadsim_engine::actuator_model::ActuatorKind;
    match r
        .workspace
        .actuators
        .as_ref()
        .and_then(|b| b.specs().get(j))
        .map(|s| s.kind)
    {
        Some(ActuatorKind::DcMotor) => "dc_motor",
        Some(ActuatorKind::Servo) => "servo",
        _ => "ideal",
    }
}

impl RobotSummary {
    /// One robot's metrics only (no actuator load, verdict or sensing:
    /// those fields hold their empty values); `joint_names` name the
    /// per-joint entries.
    fn metrics(name: &str, joint_names: &[String], m: &MetricsSummary) -> Self {
        let joints = joint_names
            .iter()
            .enumerate()
            .map(|(j, n)| JointTorque {
                name: n.clone(),
                peak_abs_torque_nm: m.joint_peak_abs_torque_nm.get(j).copied().unwrap_or(0.0),
                mean_abs_torque_nm: m.joint_mean_abs_torque_nm.get(j).copied().unwrap_or(0.0),
            })
            .collect();
        RobotSummary {
            name: name.to_string(),
            fell: m.fell,
            fell_at_s: m.fell_at_s,
            mean_forward_speed_mps: m.mean_forward_speed_mps,
            peak_forward_speed_mps: m.peak_forward_speed_mps,
            base_height_mean_m: m.base_height_mean_m,
            base_height_p2p_m: m.base_height_p2p_m,
            com_height_mean_m: m.com_height_mean_m,
            com_height_p2p_m: m.com_height_p2p_m,
            roll_range_rad: m.roll_range_rad,
            pitch_range_rad: m.pitch_range_rad,
            yaw_range_rad: m.yaw_range_rad,
            joint_rms_error_rad: m.joint_rms_error_rad,
            max_foot_force_n: m.max_foot_force_n,
            energy_j: m.energy_j,
            energy_per_step_j: m.energy_per_step_j,
            steps: m.steps,
            min_stability_margin_m: m.min_stability_margin_m,
            distance_m: m.distance_m,
            com_displacement_m: m.com_displacement_m,
            com_mean_velocity_mps: m.com_mean_velocity_mps,
            com_oscillation_m: m.com_oscillation_m,
            joints,
            total_mass_kg: 0.0,
            commanded_speed_mps: None,
            actuators: ActuatorsSummary {
                max_peak_torque_share: 0.0,
                max_time_share_at_torque_limit: 0.0,
                max_time_share_at_speed_limit: 0.0,
                max_time_share_at_envelope_limit: 0.0,
                joints: Vec::new(),
            },
            load: LoadVerdict {
                carried: true,
                reason: None,
            },
            sensing: Value::Null,
            study_b: None,
            push_recovery: None,
            diverged: None,
        }
    }

    /// One robot's entry (definitions in scenarios/README.md, "Metrics"),
    /// with `study_b` for a robot run by the `prescribed` controller in
    /// hybrid mode on Study B's leg.
    pub fn of(name: &str, r: &quadsim_components::RobotSim) -> Self {
        let m = r.run.metrics.summary();
        let names = joint_names(&r.model);
        let mut s = Self::metrics(name, &names, &m);
        let a = r.run.actuators.summary();
        let joints = a
            .joints
            .iter()
            .enumerate()
            .map(|(j, l)| JointLoadSummary {
                joint: names.get(j).cloned().unwrap_or_default(),
                peak_torque_nm: l.peak_torque_nm,
                peak_torque_share: l.peak_torque_share,
                time_at_torque_limit_s: l.time_at_torque_limit_s,
                time_at_speed_limit_s: l.time_at_speed_limit_s,
                peak_demand_nm: l.peak_demand_nm,
                torque_limit_nm: finite(l.torque_limit_nm),
                speed_limit: finite(l.speed_limit),
                torque_limit_hits: l.torque_limit_hits,
                speed_limit_hits: l.speed_limit_hits,
                time_at_envelope_limit_s: l.time_at_envelope_limit_s,
                envelope_limit_hits: l.envelope_limit_hits,
                kind: actuator_kind(r, j).to_string(),
            })
            .collect();
        // The walking command as ramped, averaged over the run.
        let (dist, t) = r.run.commanded_distance_m;
        let command = (t > 0.0).then(|| dist / t);
        let reason = if m.fell {
            Some("fell")
        } else if a
            .max_time_share_at_torque_limit
            .max(a.max_time_share_at_envelope_limit)
            > SATURATED_TIME_SHARE
        {
            Some("saturated")
        } else if command.is_some_and(|c| {
            c > TRACKED_COMMAND_MIN_MPS && m.mean_forward_speed_mps < SPEED_TRACKING_FRACTION * c
        }) {
            Some("failed to track speed")
        } else {
            None
        };
        s.total_mass_kg = r.model.total_mass;
        s.commanded_speed_mps = command;
        s.actuators = ActuatorsSummary {
            max_peak_torque_share: a.max_peak_torque_share,
            max_time_share_at_torque_limit: a.max_time_share_at_torque_limit,
            max_time_share_at_speed_limit: a.max_time_share_at_speed_limit,
            max_time_share_at_envelope_limit: a.max_time_share_at_envelope_limit,
            joints,
        };
        s.load = LoadVerdict {
            carried: reason.is_none(),
            reason: reason.map(str::to_string),
        };
        s.sensing = crate::sensing::sensing_json(r.sensing.as_deref());
        if let quadsim_components::Controller::Prescribed(p) = &r.run.controller
            && let Some(c) = &p.study_b
            && c.sim_hip.samples > 0
        {
            let joint =
                |m: &quadsim_validation::study_b_dynamics::TorqueStats,
                 s: &quadsim_validation::study_b_dynamics::TorqueStats| {
                    StudyBJoint {
                        model_peak_nm: m.peak_nm,
                        model_mean_nm: m.mean_abs_nm,
                        sim_peak_nm: s.peak_nm,
                        sim_mean_nm: s.mean_abs_nm,
                        peak_ratio_sim_to_model: s.peak_nm / m.peak_nm,
                        mean_ratio_sim_to_model: s.mean_abs_nm / m.mean_abs_nm,
                    }
                };
            s.study_b = Some(StudyBTorques {
                hip_tau2: joint(&c.model_hip, &c.sim_hip),
                knee_tau3: joint(&c.model_knee, &c.sim_knee),
                samples: c.sim_hip.samples,
            });
        }
        s
    }

    /// [`RobotSummary::of`], with `diverged` for a robot whose run ended in
    /// a divergence (the others ran on).
    pub fn in_world(world: &World, name: &str, r: &quadsim_components::RobotSim) -> Self {
        let mut s = Self::of(name, r);
        if let Some((t_s, what, cause)) = divergence_of(world, r) {
            s.diverged = Some(RobotDivergence { t_s, what, cause });
        }
        s
    }

    /// As a JSON value (object keys sorted), as `summary.json` and the log's
    /// `metrics` message hold it.
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).expect("a robot summary serialises")
    }
}

/// [`RobotSummary::of`] as JSON, for tests and tools that index by key.
pub fn robot_json(name: &str, r: &quadsim_components::RobotSim) -> Value {
    RobotSummary::of(name, r).to_json()
}
