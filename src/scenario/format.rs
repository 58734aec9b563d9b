//! The scenario file format, version 1 (TOML). Every key is documented in
//! `scenarios/README.md`; `quadsim schema` prints the JSON Schema derived from
//! these types. Units are in key names (`mass_kg`, `slope_deg`, `dt_s`); SI
//! elsewhere. World frame: z up, x forward at zero yaw.
//!
//! Kind-specific keys (terrain, controller, event) sit flat beside `kind`; the
//! validator rejects a key that does not belong to the kind, naming it.

use schemars::JsonSchema;
use serde::Deserialize;
use std::collections::BTreeMap;

/// The format version this build reads.
pub const FORMAT_VERSION: i64 = 1;

/// A whole scenario file.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Must be 1.
    pub format_version: i64,
    /// World settings.
    pub world: WorldSpec,
    /// Terrains; their union is the ground. Empty: only the world's default ground.
    #[serde(default)]
    pub terrains: Vec<TerrainSpec>,
    /// Robots, each with a unique name.
    #[serde(default)]
    pub robots: Vec<RobotSpec>,
    /// Timed events (pushes, commands, payloads).
    #[serde(default)]
    pub events: Vec<EventSpec>,
    /// Herds: many robots from one template, appended to `robots` on load
    /// (see [`crate::scenario::herd`]).
    #[serde(default)]
    pub herds: Vec<HerdSpec>,
    /// `[log]`: which robots `quadsim run` logs, and whether it writes a log at all.
    #[serde(default)]
    pub log: LogSpec,
    /// Key path that errors about each robot name (`robots[i]`, or
    /// `herds[h].robot` for a herd's robots); filled on load.
    #[serde(skip)]
    #[schemars(skip)]
    pub robot_key_paths: Vec<String>,
}

impl ScenarioFile {
    /// Key path of robot `i` for error messages.
    pub fn robot_key_path(&self, i: usize) -> String {
        self.robot_key_paths
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("robots[{i}]"))
    }
}

/// `[[herds]]`: `count` robots from the `robot` template, varied by `vary`
/// and placed by `layout`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HerdSpec {
    /// Name prefix: robots are `<name>-000`, `<name>-001`, …
    pub name: String,
    /// Number of robots (default with `combine = "grid"`: the grid's size).
    pub count: Option<usize>,
    /// `cycle` (default: robot k takes value k mod len of each variation) or
    /// `grid` (robot k takes entry k of the Cartesian product).
    pub combine: Option<String>,
    /// Where the robots start.
    #[serde(default)]
    pub layout: HerdLayout,
    /// A `[[robots]]` entry without `name`: every key of a robot.
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub robot: toml::Table,
    /// Per-robot values by path in the template: a list, `{ from, to, steps }`
    /// or `{ uniform = [lo, hi] }`.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub vary: BTreeMap<String, toml::Value>,
}

/// `[herds.layout]`: start positions of a herd's robots.
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HerdLayout {
    /// `grid` (default): rows along x, `columns` along y; `lanes`: robot k in
    /// lane k mod n on terrain `terrains[lane]`, one after another along the lane.
    pub kind: Option<String>,
    /// Grid: [row, column] spacing (m, default [2, 2]); lanes: offset from one
    /// robot to the next in its lane (m, default [2, 0]).
    pub spacing_m: Option<[f64; 2]>,
    /// Grid: robots per row (default ⌈√count⌉).
    pub columns: Option<usize>,
    /// Position of the first robot (m, world; for lanes, from the lane terrain's origin).
    pub origin_m: Option<[f64; 2]>,
    /// Lanes: one terrain name per lane.
    pub terrains: Option<Vec<String>>,
}

/// Integrator choice.
#[derive(Debug, Clone, Copy, Deserialize, JsonSchema, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorSpec {
    /// Semi-implicit (symplectic) Euler: the default.
    #[default]
    SemiImplicitEuler,
    /// Classical 4th-order Runge–Kutta; contact forces are evaluated at every stage.
    Rk4,
}

/// `[world]`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// Scenario name: names the output directory `runs/<name>/`. Default: the file stem.
    pub name: Option<String>,
    /// Fixed time step (s). Default 0.0005.
    #[serde(default = "default_dt")]
    pub dt_s: f64,
    /// Integrator. Default `semi_implicit_euler`.
    #[serde(default)]
    pub integrator: IntegratorSpec,
    /// Gravity (m/s², world frame). Default [0, 0, −9.81].
    #[serde(default = "default_gravity")]
    pub gravity_mps2: [f64; 3],
    /// Simulated duration (s).
    pub duration_s: f64,
    /// World seed: every random stream derives from (seed, robot or terrain name). Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Controller rate (Hz); must divide the step rate. Default 500.
    #[serde(default = "default_rate")]
    pub controller_rate_hz: f64,
    /// Ground outside every terrain: a preset name or a custom material. Default: none (robots fall).
    pub default_ground: Option<GroundSpec>,
    /// Height of the default ground plane (m). Default 0.
    #[serde(default)]
    pub default_ground_height_m: f64,
    /// Rate of `quadsim run`'s log (Hz, dividing the step rate) or `"full"`
    /// (every step). Default: the controller rate.
    pub log_rate_hz: Option<LogRateSpec>,
}

/// A log rate: a frequency (Hz) that divides the step rate, or `"full"` for every step.
#[derive(Debug, Clone, Deserialize, JsonSchema, PartialEq)]
#[serde(untagged)]
pub enum LogRateSpec {
    /// Samples per second of simulated time.
    Hz(f64),
    /// `"full"`: every step.
    Named(String),
}

impl LogRateSpec {
    /// Steps between two log samples at step length `dt_s`, or a message saying why not.
    pub fn every_steps(&self, dt_s: f64) -> Result<u64, String> {
        match self {
            LogRateSpec::Named(n) if n == "full" => Ok(1),
            LogRateSpec::Named(n) => Err(format!(
                "unknown log rate '{n}': a rate in Hz or \"full\" (every step)"
            )),
            LogRateSpec::Hz(hz) => {
                let ratio = 1.0 / (dt_s * hz);
                if !(hz.is_finite() && *hz > 0.0)
                    || ratio < 1.0 - 1e-9
                    || (ratio - ratio.round()).abs() > 1e-6
                {
                    Err(format!(
                        "{hz} Hz must be > 0 and divide the step rate 1/dt = {} Hz into a whole number of steps",
                        1.0 / dt_s
                    ))
                } else {
                    Ok(ratio.round() as u64)
                }
            }
        }
    }
}

fn default_dt() -> f64 {
    0.0005
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}
fn default_rate() -> f64 {
    500.0
}

/// A ground material: a preset name (`concrete`, `grass`, `mud`, `sand`) or a custom table.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum GroundSpec {
    /// A preset from Study A.
    Preset(String),
    /// A custom material.
    Custom(CustomGround),
}

/// A custom ground material.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CustomGround {
    /// Normal stiffness k (N/m for `linear`; N/mⁿ for `hunt_crossley`).
    pub stiffness_n_per_m: f64,
    /// Normal damping b (N·s/m; N·s/mⁿ⁺¹ for `hunt_crossley`).
    pub damping_ns_per_m: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Contact law: `linear` (default), `hunt_crossley`, `hybrid`.
    pub law: Option<String>,
    /// Hunt–Crossley exponent n (default 1.5).
    pub exponent: Option<f64>,
    /// Hybrid law: depth where stiffening starts (m).
    pub hybrid_depth_m: Option<f64>,
    /// Stiffness of the tangential (stick) spring (N/m, whatever the law).
    /// Default: the normal stiffness (`linear`, `hybrid`); for
    /// `hunt_crossley`, the law's tangent stiffness at the static depth under
    /// a 70 N contact load (`GroundMaterial::default_tangential`).
    pub tangential_stiffness_n_per_m: Option<f64>,
    /// Damping of the tangential (stick) spring (N·s/m, whatever the law).
    /// Default: a quarter of the normal damping (`linear`, `hybrid`); for
    /// `hunt_crossley`, a quarter of `b δⁿ` at that depth.
    pub tangential_damping_ns_per_m: Option<f64>,
    /// Hybrid law: dimensionless stiffening s (default 1; stiffness k (1 + 2 s (δ − δ₀)/δ₀) beyond δ₀).
    pub hybrid_stiffening: Option<f64>,
}

/// `[[terrains]]`: one terrain entity. Keys beside `kind` depend on the kind.
#[derive(Debug, Deserialize, JsonSchema)]
pub struct TerrainSpec {
    /// Unique name (robots refer to it with `terrain`).
    pub name: String,
    /// `flat`, `incline`, `sine`, `rough`, `trench`, `stairs`, `boxes`, `stepping_stones`, `heightmap`.
    pub kind: String,
    /// Origin of the terrain (m, world): its reference corner/centre, kind-specific.
    #[serde(default)]
    pub origin_m: [f64; 3],
    /// Horizontal extent [x, y] (m), centred on the origin. Default [20, 20].
    pub extent_m: Option<[f64; 2]>,
    /// Ground material. Default `concrete`.
    pub ground: Option<GroundSpec>,
    /// Every other key, checked against the kind by the validator.
    #[serde(flatten)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub params: BTreeMap<String, toml::Value>,
}

/// `[[robots]]`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Unique name; also seeds the robot's random streams.
    pub name: String,
    /// A built-in model (`quad16`, `quad12`) or a path to a URDF (relative to the scenario file).
    pub model: String,
    /// Parameter overrides by path (see `quadsim models --params NAME`).
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// Foot link names (default: the model's feet, or the URDF's leaf links).
    pub feet: Option<Vec<String>>,
    /// Start position of the base origin (m, world). z is above the terrain under it
    /// when `start_on_ground` is true. Default: the model's nominal standing height.
    pub start_position_m: Option<[f64; 3]>,
    /// Start position of the base origin in the horizontal plane only (m,
    /// world; relative to `terrain`'s origin when given); the height is the
    /// model's nominal standing height above the ground there. Excludes
    /// `start_position_m`.
    pub start_xy_m: Option<[f64; 2]>,
    /// Start yaw (deg, about world z).
    #[serde(default)]
    pub start_yaw_deg: f64,
    /// Start joint angles (rad, joint order of the model). Default: the nominal stance.
    pub start_joints_rad: Option<Vec<f64>>,
    /// Terrain the robot starts on: its origin is added to `start_position_m`.
    pub terrain: Option<String>,
    /// Extra contact points beside the feet: `knees`, `torso` (for fall detection).
    #[serde(default)]
    pub contact_points: Vec<String>,
    /// The controller.
    #[serde(default)]
    pub controller: ControllerSpec,
    /// This robot's per-step channels in `quadsim run`'s log: `true`/`false`,
    /// or a table `{ enabled = true, rate_hz = 50 }` with its own rate.
    /// Default: logged at the world's log rate.
    #[serde(default)]
    #[schemars(with = "RobotLogToml")]
    pub log: RobotLogSpec,
    /// Payloads on the torso, rigid or compliant (attached at start, or by `attach` events).
    #[serde(default)]
    pub payloads: Vec<PayloadSpec>,
    /// Analyses run after the main run (`[robots.analysis]`).
    #[serde(default)]
    pub analysis: AnalysisSpec,
    /// Joint actuators (`[robots.actuators]`; see `docs/actuators.md`).
    /// Default: ideal torque sources.
    #[serde(default)]
    pub actuators: ActuatorsSpec,
    /// Sensors (`[robots.sensors]`; `scenarios/README.md`, `docs/sensors.md`).
    #[serde(default)]
    pub sensors: super::sensing::SensorsSpec,
    /// Base state estimator and the controller's state source (`[robots.estimator]`).
    #[serde(default)]
    pub estimator: super::sensing::EstimatorSpec,
}

/// `[robots.actuators]`: the actuator kind and parameters of every joint,
/// with per-joint overrides in `[robots.actuators.joints.NAME]` (NAME a
/// joint name, or `*suffix` for every joint whose name ends so). Keys are
/// checked by `quadsim::actuators`.
#[derive(Debug, Default, Deserialize, JsonSchema)]
pub struct ActuatorsSpec {
    /// Per-joint overrides, by joint name or `*suffix`; the same keys.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, BTreeMap<String, serde_json::Value>>")]
    pub joints: BTreeMap<String, BTreeMap<String, toml::Value>>,
    /// `kind` and parameters for every joint.
    #[serde(flatten)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub params: BTreeMap<String, toml::Value>,
}

/// `[[robots.payloads]]`: a uniform solid bolted to the torso (`kind =
/// "rigid"`), or on a spring–damper along declared DOFs (`kind = "compliant"`).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PayloadSpec {
    /// Name, unique on the robot; `attach`/`detach` events name it.
    pub name: String,
    /// Mass (kg).
    pub mass_kg: f64,
    /// `box` (default), `sphere` or `cylinder` (axis along torso z).
    pub shape: Option<String>,
    /// Box: `[x, y, z]` side lengths; sphere: `[radius]`; cylinder: `[radius, length]` (m).
    pub size_m: Vec<f64>,
    /// Centre of the payload from the torso centre, torso axes (m).
    #[serde(default)]
    pub offset_m: [f64; 3],
    /// Attached at t = 0 (default true); otherwise at its `attach` event.
    #[serde(default = "default_true")]
    pub attached: bool,
    /// Whether the walking controller's gravity compensation knows the mass (default true).
    #[serde(default = "default_true")]
    pub known_to_controller: bool,
    /// `rigid` (default) or `compliant` (a sloshing or soft load: a body of
    /// its own on a spring–damper, free along `dofs`).
    pub kind: Option<String>,
    /// Compliant: the load's DOFs relative to the torso, any of `x`, `y`,
    /// `z` (translations in torso axes) and `roll`, `pitch`, `yaw`
    /// (intrinsic rotations about the load's centre).
    #[serde(default)]
    pub dofs: Vec<String>,
    /// Compliant: spring stiffness of each translation DOF (N/m).
    pub stiffness_npm: Option<f64>,
    /// Compliant: damping of each translation DOF (N·s/m, default 0).
    pub damping_nspm: Option<f64>,
    /// Compliant: spring stiffness of each rotation DOF (N·m/rad).
    pub stiffness_nm_per_rad: Option<f64>,
    /// Compliant: damping of each rotation DOF (N·m·s/rad, default 0).
    pub damping_nms_per_rad: Option<f64>,
}

/// `[robots.analysis]`: analyses that re-run the scenario after the main run
/// and add their result to `summary.json` (see `scenarios/README.md`).
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisSpec {
    /// Search the largest push the robot recovers from (`push_recovery` in
    /// `summary.json`). Default false; `quadsim run --push-search` turns it on
    /// for every robot.
    #[serde(default)]
    pub push_search: bool,
    /// Push start (s). Default 5.
    pub push_t_s: Option<f64>,
    /// Push duration (s), fixed during the search. Default 0.1.
    pub push_duration_s: Option<f64>,
    /// `left` (default), `right`, `forward` or `backward`, in the start heading frame.
    pub push_direction: Option<String>,
    /// Upper end of the searched forces (N). Default 1000.
    pub push_max_force_n: Option<f64>,
    /// Bisection steps. Default 6.
    pub push_iterations: Option<u32>,
    /// Length of each trial after the push's start (s). Default 3.
    pub push_settle_s: Option<f64>,
}

fn default_true() -> bool {
    true
}

/// `[robots.log]`: whether and how often a robot's per-step channels are
/// logged. Written as a bool (`log = false`) or as a table.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotLogSpec {
    /// Per-step channels are written. Default true.
    pub enabled: bool,
    /// The robot's own log rate (Hz dividing the step rate, or `"full"`);
    /// default: the world's (`world.log_rate_hz`, `--log-rate`).
    pub rate_hz: Option<LogRateSpec>,
}

impl Default for RobotLogSpec {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: None,
        }
    }
}

/// The table form of [`RobotLogSpec`].
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotLogTable {
    /// Per-step channels are written. Default true.
    #[serde(default = "default_true")]
    pub enabled: bool,
    /// The robot's log rate (Hz dividing the step rate, or `"full"`).
    pub rate_hz: Option<LogRateSpec>,
}

/// What a robot's `log` may be written as (for the JSON Schema).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
#[expect(
    dead_code,
    reason = "only describes the accepted shapes in the JSON Schema"
)]
enum RobotLogToml {
    /// `log = false` / `log = true`.
    Flag(bool),
    /// `[robots.log]` with `enabled` and `rate_hz`.
    Table(RobotLogTable),
}

impl<'de> Deserialize<'de> for RobotLogSpec {
    /// A bool or a [`RobotLogTable`], with the table's own errors (unknown
    /// key, bad rate) located at its keys.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RobotLogSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("true, false or a table { enabled, rate_hz }")
            }
            fn visit_bool<E: serde::de::Error>(self, b: bool) -> Result<RobotLogSpec, E> {
                Ok(RobotLogSpec {
                    enabled: b,
                    rate_hz: None,
                })
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<RobotLogSpec, A::Error> {
                let t =
                    RobotLogTable::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(RobotLogSpec {
                    enabled: t.enabled,
                    rate_hz: t.rate_hz,
                })
            }
        }
        d.deserialize_any(V)
    }
}

/// `[log]`: what `quadsim run` logs (`quadsim run`'s `--log-robots`,
/// `--summary-only` override it).
#[derive(Debug, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LogSpec {
    /// Robots whose per-step channels are logged: names or glob patterns
    /// (`*`, `?`, `[abc]`; e.g. `"q16-00*"`). Default: every robot whose
    /// `log` is on. A robot must match one and have `log` on.
    pub robots: Option<Vec<String>>,
    /// `"mcap"` (default): write `log.mcap`; `"summary"`: no log,
    /// `summary.json` and `report.md` (without plots) only.
    #[serde(default)]
    pub mode: LogMode,
}

/// [`LogSpec::mode`].
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LogMode {
    /// Write `log.mcap`.
    #[default]
    Mcap,
    /// Summary only: no `log.mcap`.
    Summary,
}

/// `[robots.controller]`. Keys beside `kind` depend on the kind.
#[derive(Debug, Default, Deserialize, JsonSchema)]
pub struct ControllerSpec {
    /// `none`, `joint_pd`, `vmc`, `prescribed`. Default `none`.
    pub kind: Option<String>,
    /// Every other key (gains, targets), checked against the kind by the validator.
    #[serde(flatten)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub params: BTreeMap<String, toml::Value>,
}

/// `[[events]]`.
#[derive(Debug, Deserialize, JsonSchema)]
pub struct EventSpec {
    /// Simulation time of the event (s).
    pub t_s: f64,
    /// Robot name.
    pub robot: String,
    /// `push`, `command`, `attach`, `detach`.
    pub kind: String,
    /// Every other key, checked against the kind by the validator.
    #[serde(flatten)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub params: BTreeMap<String, toml::Value>,
}
