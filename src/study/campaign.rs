//! Robustness campaigns: N perturbed copies of one scenario, each run to the
//! end in a world of its own, with the fall rate and the speed tracking over
//! them (`quadsim campaign`, `docs/campaign.md`).
//!
//! A copy is the scenario with one robot perturbed:
//!
//! - **start offset**: the base's start position moved by `(dx, dy)`, each
//!   uniform in `[−start_xy_m, start_xy_m]`, and its start heading turned by
//!   a yaw uniform in `[−start_yaw_deg, start_yaw_deg]` (the heading of the
//!   metrics and of the robot's velocity command turn with it);
//! - **seed**: the world seed (as `quadsim run --seed`), a draw per copy:
//!   sensor noise, biases and offsets, and random terrains (`rough`);
//! - **link masses**: every link of the robot (payloads excepted) scaled by
//!   its own factor uniform in `[1 − link_mass_frac, 1 + link_mass_frac]`,
//!   its rotational inertia with it (the same shape, denser or lighter). The
//!   controller and the state estimator keep the nominal model;
//! - **friction**: one Coulomb μ uniform in `[lo, hi]` for every ground of
//!   the world (the default ground and every terrain's), in place of theirs;
//! - **sensor noise**: every noise, bias and drift figure of the robot's
//!   sensors (as the scenario sets them, or the model's defaults) times a
//!   factor uniform in `[lo, hi]` (1: as written, 0: no noise).
//!
//! Every draw comes from its own ChaCha8 stream seeded by the campaign seed,
//! the copy number and the quantity's name, so the draws of a copy do not
//! depend on the other copies, on which perturbations are on, on the thread
//! count or on the order the copies run in.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::Entity;
use quadsim_components::{BelongsTo, ControlView, Controller, Inertia, Link, Mass};
use quadsim_engine::Data;
use quadsim_engine::contact::GroundMaterial;
use quadsim_engine::metrics::{MetricsAccumulator, MetricsSummary};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::scenario::{Locator, Scenario, parse_scenario};
use crate::world::{Overrides, World, build_world, stream_seed};

/// Version of `campaign.json`'s layout.
pub const SCHEMA_VERSION: u32 = 1;

/// Interval between the samples of a copy's trace (s): its CoM position
/// along the start heading, for the plot; also the longest a fallen copy
/// runs on after its fall.
pub const SAMPLE_S: f64 = 0.01;

/// What is perturbed, and by how much (ranges are closed intervals).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturbations {
    /// Half-width of the start offset along world x and y (m; 0: none).
    pub start_xy_m: f64,
    /// Half-width of the start yaw offset (degrees; 0: none).
    pub start_yaw_deg: f64,
    /// Half-width of the per-link mass factor around 1 (0.1: ±10 %; 0: none).
    pub link_mass_frac: f64,
    /// Range of the ground's Coulomb μ (absolute); `None`: the scenario's grounds.
    pub friction: Option<[f64; 2]>,
    /// Whether each copy draws its world seed (else the scenario's).
    pub world_seed: bool,
    /// Range of the factor on the sensors' noise figures (`[1, 1]`: as written).
    pub noise_scale: [f64; 2],
}

impl Default for Perturbations {
    fn default() -> Self {
        Self {
            start_xy_m: 0.02,
            start_yaw_deg: 3.0,
            link_mass_frac: 0.10,
            friction: Some([0.6, 1.0]),
            world_seed: true,
            noise_scale: [1.0, 1.0],
        }
    }
}

impl Perturbations {
    /// No perturbation at all: every copy is the scenario as written.
    pub const NONE: Perturbations = Perturbations {
        start_xy_m: 0.0,
        start_yaw_deg: 0.0,
        link_mass_frac: 0.0,
        friction: None,
        world_seed: false,
        noise_scale: [1.0, 1.0],
    };

    /// Checks the ranges; the message names the offending one.
    pub fn validate(&self) -> Result<(), String> {
        let nonneg = |name: &str, x: f64, max: f64| {
            if x.is_finite() && (0.0..=max).contains(&x) {
                Ok(())
            } else {
                Err(format!("{name}: {x} is not in [0, {max}]"))
            }
        };
        nonneg("start_xy_m", self.start_xy_m, 1.0)?;
        nonneg("start_yaw_deg", self.start_yaw_deg, 180.0)?;
        nonneg("link_mass_frac", self.link_mass_frac, 0.9)?;
        let range = |name: &str, [lo, hi]: [f64; 2], max: f64| {
            if lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi <= max {
                Ok(())
            } else {
                Err(format!(
                    "{name}: [{lo}, {hi}] is not a range 0 ≤ lo ≤ hi ≤ {max}"
                ))
            }
        };
        if let Some(f) = self.friction {
            range("friction", f, 10.0)?;
        }
        range("noise_scale", self.noise_scale, 100.0)?;
        Ok(())
    }
}

/// A campaign to run.
#[derive(Debug, Clone)]
pub struct CampaignSpec {
    /// The scenario file.
    pub scenario: PathBuf,
    /// Number of copies.
    pub copies: usize,
    /// The campaign seed (every draw derives from it).
    pub seed: u64,
    /// The perturbed robot (default: the scenario's only `[[robots]]` entry).
    pub robot: Option<String>,
    /// Simulated duration of each copy (s; default the scenario's).
    pub duration_s: Option<f64>,
    /// Start of the steady-state window of the speed (s).
    pub steady_from_s: f64,
    /// Start of the window of the torso height's peak-to-peak (s).
    pub height_from_s: f64,
    /// The perturbations.
    pub perturb: Perturbations,
    /// The case's label in the table (default: the scenario's name).
    pub case: Option<String>,
}

impl CampaignSpec {
    /// A campaign of `copies` copies of `scenario` with the default
    /// perturbations and windows, seed 0.
    pub fn new(scenario: impl Into<PathBuf>, copies: usize) -> Self {
        Self {
            scenario: scenario.into(),
            copies,
            seed: 0,
            robot: None,
            duration_s: None,
            steady_from_s: 2.0,
            height_from_s: 1.0,
            perturb: Perturbations::default(),
            case: None,
        }
    }
}

/// One copy's draws.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Draws {
    /// The world seed the copy ran with.
    pub world_seed: u64,
    /// Start offset along world x (m).
    pub start_dx_m: f64,
    /// Start offset along world y (m).
    pub start_dy_m: f64,
    /// Start yaw offset (degrees).
    pub start_dyaw_deg: f64,
    /// The grounds' μ, when friction is perturbed.
    pub friction: Option<f64>,
    /// The factor on the sensors' noise figures.
    pub noise_scale: f64,
    /// Per link (by name): the factor on its mass and inertia.
    pub link_mass_scale: BTreeMap<String, f64>,
}

/// One copy's metrics (SI units, angles in rad; `docs/campaign.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CopyMetrics {
    /// The scenario's fall criteria held at some step.
    pub fell: bool,
    /// When they first held (s).
    pub fell_at_s: Option<f64>,
    /// Simulated time (s): the duration, or a little past the fall.
    pub simulated_s: f64,
    /// The robot's true mass (kg), perturbations included.
    pub total_mass_kg: f64,
    /// Mean CoM speed along the start heading over the steady-state window
    /// (net displacement over time, m/s); `None` for a copy that fell.
    pub mean_speed_mps: Option<f64>,
    /// The walking controller's forward command as ramped, averaged over the
    /// same window (m/s); `None` for other controllers or a fallen copy.
    pub commanded_speed_mps: Option<f64>,
    /// `mean_speed_mps − commanded_speed_mps` (m/s).
    pub speed_error_mps: Option<f64>,
    /// Largest |roll| of the base over the run (rad).
    pub max_abs_roll_rad: f64,
    /// Largest |pitch| of the base over the run (rad).
    pub max_abs_pitch_rad: f64,
    /// Peak-to-peak of the torso origin's height above the terrain from
    /// `height_from_s` on (m); `None` when the run ends before.
    pub height_p2p_m: Option<f64>,
    /// Largest vertical ground reaction force on one foot over the run (N).
    pub peak_foot_force_n: f64,
}

/// One copy's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CopyResult {
    /// Copy number, from 0.
    pub copy: usize,
    /// Its draws.
    pub draws: Draws,
    /// Its metrics, unless it failed.
    pub metrics: Option<CopyMetrics>,
    /// Why it failed (a divergence, a draw the model rejects).
    pub error: Option<String>,
    /// `(t_s, x_m, c_m)` every [`SAMPLE_S`]: the CoM position along the
    /// start heading, and the walking controller's commanded distance
    /// (∫ ramped forward command dt) (for the plot; not in `campaign.json`).
    #[serde(skip)]
    pub trace: Vec<(f64, f64, f64)>,
}

/// A scenario ready for a campaign: its text, the perturbed robot, and what
/// the draws need.
#[derive(Debug)]
pub struct Prepared {
    /// The spec.
    pub spec: CampaignSpec,
    /// The scenario as written.
    pub scenario: Scenario,
    /// Its TOML table.
    table: toml::Table,
    /// Index of the robot in the file's `[[robots]]`.
    robot_index: usize,
    /// The robot's name.
    pub robot: String,
    /// Its links with mass, in name order (payloads excluded).
    pub links: Vec<String>,
    /// The robot's nominal mass (kg, attached payloads included).
    pub nominal_mass_kg: f64,
    /// The walking controller's commanded velocity, if it has one.
    pub command: Option<Command>,
    /// Simulated duration (s).
    pub duration_s: f64,
    /// Step (s).
    pub dt_s: f64,
}

/// A walking robot's velocity command (heading frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Command {
    /// Forward speed (m/s).
    pub v_x_mps: f64,
    /// Lateral speed (m/s).
    pub v_y_mps: f64,
    /// Yaw rate (rad/s).
    pub yaw_rate_radps: f64,
}

/// An error before any copy ran: the message names the file or the setting.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignError(pub String);

impl std::fmt::Display for CampaignError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CampaignError {}

fn err(msg: impl Into<String>) -> CampaignError {
    CampaignError(msg.into())
}

/// The random stream of quantity `what` of copy `copy`.
fn rng(seed: u64, copy: usize, what: &str) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(stream_seed(seed, &format!("campaign/{copy}/{what}")))
}

/// Uniform in `[-h, h]` (exactly 0 when `h` is 0).
fn symmetric(seed: u64, copy: usize, what: &str, h: f64) -> f64 {
    if h == 0.0 {
        return 0.0;
    }
    rng(seed, copy, what).random_range(-h..=h)
}

/// Uniform in `[lo, hi]` (exactly `lo` when they are equal).
fn between(seed: u64, copy: usize, what: &str, [lo, hi]: [f64; 2]) -> f64 {
    if lo == hi {
        return lo;
    }
    rng(seed, copy, what).random_range(lo..=hi)
}

/// The link entities of robot `root` with their names, masses and given inertias.
fn robot_links(world: &mut World, root: Entity) -> Vec<(Entity, String, f64, Option<Inertia>)> {
    let mut q = world
        .sim
        .world
        .query::<(Entity, &Link, &Mass, Option<&Inertia>, &BelongsTo)>();
    let mut out: Vec<_> = q
        .iter(&world.sim.world)
        .filter(|(_, _, _, _, b)| b.0 == root)
        .map(|(e, l, m, i, _)| (e, l.name.clone(), m.0, i.copied()))
        .collect();
    out.sort_by(|a, b| a.1.cmp(&b.1));
    out
}

fn robot_root(world: &World, name: &str) -> Entity {
    world
        .robots
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, e)| *e)
        .expect("the prepared robot is in every copy's world")
}

/// Forward direction of a start yaw (world xy).
fn heading(yaw_deg: f64) -> (f64, f64) {
    let (s, c) = yaw_deg.to_radians().sin_cos();
    (c, s)
}

fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The materials' TOML for one preset or custom ground with μ replaced.
fn ground_with_friction(
    loc: &Locator<'_>,
    path: &str,
    g: Option<&toml::Value>,
    mu: f64,
) -> Result<toml::Value, CampaignError> {
    match g {
        Some(toml::Value::Table(t)) => {
            let mut t = t.clone();
            t.insert("friction".into(), toml::Value::Float(mu));
            Ok(toml::Value::Table(t))
        }
        other => {
            let name = match other {
                None => "concrete".to_string(),
                Some(toml::Value::String(s)) => s.clone(),
                Some(v) => return Err(err(format!("{path}: unexpected ground {v}"))),
            };
            let m = GroundMaterial::preset(&name)
                .map_err(|e| err(loc.at(path, e.to_string()).to_string()))?;
            let mut t = toml::Table::new();
            t.insert("stiffness_n_per_m".into(), toml::Value::Float(m.stiffness));
            t.insert("damping_ns_per_m".into(), toml::Value::Float(m.damping));
            t.insert("friction".into(), toml::Value::Float(mu));
            t.insert(
                "tangential_stiffness_n_per_m".into(),
                toml::Value::Float(m.tangential_stiffness_npm),
            );
            t.insert(
                "tangential_damping_ns_per_m".into(),
                toml::Value::Float(m.tangential_damping_nspm),
            );
            Ok(toml::Value::Table(t))
        }
    }
}

/// A sub-table of `t` (created when absent).
fn sub<'a>(t: &'a mut toml::Table, key: &str) -> &'a mut toml::Table {
    let e = t
        .entry(key.to_string())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if !e.is_table() {
        *e = toml::Value::Table(toml::Table::new());
    }
    e.as_table_mut().expect("a table")
}

impl Prepared {
    /// Reads the scenario, picks the robot, checks the spec, and builds the
    /// first copy's world once, so that a bad setting fails before any run.
    pub fn new(spec: CampaignSpec) -> Result<Prepared, CampaignError> {
        spec.perturb.validate().map_err(err)?;
        if spec.copies == 0 {
            return Err(err("the campaign needs at least one copy (-n 1 or more)"));
        }
        let path = &spec.scenario;
        let src = std::fs::read_to_string(path)
            .map_err(|e| err(format!("{}: cannot read the scenario: {e}", path.display())))?;
        let scenario = parse_scenario(path, src.clone()).map_err(|e| err(e.to_string()))?;
        let table: toml::Table = toml::from_str(&src).expect("parsed above");
        let listed: Vec<String> = table
            .get("robots")
            .and_then(|r| r.as_array())
            .map(|a| {
                a.iter()
                    .map(|r| {
                        r.get("name")
                            .and_then(|n| n.as_str())
                            .unwrap_or_default()
                            .to_string()
                    })
                    .collect()
            })
            .unwrap_or_default();
        let robot_index = match &spec.robot {
            Some(name) => listed.iter().position(|n| n == name).ok_or_else(|| {
                let herd = scenario.file.robots.iter().any(|r| &r.name == name);
                err(if herd {
                    format!(
                        "{}: robot '{name}' belongs to a herd; a campaign perturbs a robot of [[robots]] ({})",
                        path.display(),
                        listed.join(", ")
                    )
                } else {
                    format!(
                        "{}: no robot named '{name}' in [[robots]] ({})",
                        path.display(),
                        listed.join(", ")
                    )
                })
            })?,
            None if listed.len() == 1 => 0,
            None if listed.is_empty() => {
                return Err(err(format!(
                    "{}: a campaign perturbs one robot of [[robots]], and this scenario has none",
                    path.display()
                )));
            }
            None => {
                return Err(err(format!(
                    "{}: {} robots in [[robots]] ({}): name the one to perturb with --robot",
                    path.display(),
                    listed.len(),
                    listed.join(", ")
                )));
            }
        };
        let robot = listed[robot_index].clone();
        let w = &scenario.file.world;
        let duration_s = spec.duration_s.unwrap_or(w.duration_s);
        if !(duration_s.is_finite() && duration_s > 0.0) {
            return Err(err("--duration must be a positive number of seconds"));
        }
        for (name, t) in [
            ("steady-state window start", spec.steady_from_s),
            ("height window start", spec.height_from_s),
        ] {
            if !(t.is_finite() && t >= 0.0) {
                return Err(err(format!("the {name} must be ≥ 0 s, got {t}")));
            }
        }
        if spec.steady_from_s >= duration_s {
            return Err(err(format!(
                "the steady-state window starts at {} s, at or after the end of the run ({duration_s} s): \
                 lower --steady-from or raise --duration",
                spec.steady_from_s
            )));
        }
        let spec_r = scenario
            .file
            .robots
            .iter()
            .find(|r| r.name == robot)
            .expect("listed robots are in the scenario");
        let command = (spec_r.controller.kind.as_deref() == Some("vmc")).then(|| {
            let get = |k: &str| spec_r.controller.params.get(k).and_then(as_f64);
            Command {
                v_x_mps: get("v_x_mps").unwrap_or(0.0),
                v_y_mps: get("v_y_mps").unwrap_or(0.0),
                yaw_rate_radps: get("yaw_rate_radps").unwrap_or(0.0),
            }
        });
        let payload_names: Vec<String> = spec_r.payloads.iter().map(|p| p.name.clone()).collect();
        let dt_s = w.dt_s;
        let mut prep = Prepared {
            spec,
            scenario,
            table,
            robot_index,
            robot,
            links: Vec::new(),
            nominal_mass_kg: 0.0,
            command,
            duration_s,
            dt_s,
        };
        // the nominal world: the robot's links and mass
        let mut world = build_world(
            &prep.scenario,
            Overrides {
                duration_s: Some(duration_s),
                threads: 1,
                ..Default::default()
            },
        )
        .map_err(|e| err(e.to_string()))?;
        let root = robot_root(&world, &prep.robot);
        prep.links = robot_links(&mut world, root)
            .into_iter()
            .filter(|(_, name, m, _)| *m > 0.0 && !payload_names.iter().any(|p| p == name))
            .map(|(_, name, _, _)| name)
            .collect();
        prep.nominal_mass_kg = world.sim.robot(root).expect("compiled").model.total_mass;
        // copy 0 builds: a range the scenario cannot take fails here
        let d = prep.draws(0);
        let scn = prep
            .copy_scenario(&d)
            .map_err(|e| err(format!("copy 0: {e}")))?;
        build_world(&scn, Overrides::with_threads(1))
            .map_err(|e| err(format!("copy 0 (draws {d:?}): {}", e.message_with_path())))?;
        Ok(prep)
    }

    /// The case's label: `--case`, else the scenario's name.
    pub fn case(&self) -> String {
        self.spec
            .case
            .clone()
            .unwrap_or_else(|| self.scenario.name.clone())
    }

    /// SHA-256 of the scenario's text.
    pub fn scenario_sha256(&self) -> String {
        format!("{:x}", Sha256::digest(self.scenario.source.as_bytes()))
    }

    /// Copy `k`'s draws (a function of the campaign seed, `k` and the
    /// perturbation ranges only).
    pub fn draws(&self, k: usize) -> Draws {
        let p = &self.spec.perturb;
        let s = self.spec.seed;
        Draws {
            world_seed: if p.world_seed {
                u64::from(rng(s, k, "world_seed").random::<u32>())
            } else {
                self.scenario.file.world.seed
            },
            start_dx_m: symmetric(s, k, "start_x", p.start_xy_m),
            start_dy_m: symmetric(s, k, "start_y", p.start_xy_m),
            start_dyaw_deg: symmetric(s, k, "start_yaw", p.start_yaw_deg),
            friction: p.friction.map(|r| between(s, k, "friction", r)),
            noise_scale: between(s, k, "noise_scale", p.noise_scale),
            link_mass_scale: if p.link_mass_frac > 0.0 {
                self.links
                    .iter()
                    .map(|l| {
                        let h = p.link_mass_frac;
                        (l.clone(), 1.0 + symmetric(s, k, &format!("mass/{l}"), h))
                    })
                    .collect()
            } else {
                BTreeMap::new()
            },
        }
    }

    /// The robot's start yaw in copy `d` (degrees).
    fn start_yaw_deg(&self, d: &Draws) -> f64 {
        let r = self
            .scenario
            .file
            .robots
            .iter()
            .find(|r| r.name == self.robot)
            .expect("the robot");
        r.start_yaw_deg + d.start_dyaw_deg
    }

    /// The scenario of one copy: the start, grounds and sensors of the
    /// draws written into the scenario's text (masses and seed are applied
    /// to the built world, [`Self::run_copy`]).
    pub fn copy_scenario(&self, d: &Draws) -> Result<Scenario, String> {
        let mut t = self.table.clone();
        let loc = Locator {
            path: &self.scenario.path,
            src: &self.scenario.source,
        };
        {
            let robots = t
                .get_mut("robots")
                .and_then(|r| r.as_array_mut())
                .expect("robots listed");
            let r = robots[self.robot_index]
                .as_table_mut()
                .expect("a robot is a table");
            if d.start_dx_m != 0.0 || d.start_dy_m != 0.0 {
                let shift = |a: &mut toml::Value| {
                    if let Some(a) = a.as_array_mut() {
                        for (i, dv) in [d.start_dx_m, d.start_dy_m].into_iter().enumerate() {
                            let x = a.get(i).and_then(as_f64).unwrap_or(0.0);
                            a[i] = toml::Value::Float(x + dv);
                        }
                    }
                };
                if let Some(a) = r.get_mut("start_position_m") {
                    shift(a);
                } else if let Some(a) = r.get_mut("start_xy_m") {
                    shift(a);
                } else {
                    r.insert(
                        "start_xy_m".into(),
                        toml::Value::Array(vec![
                            toml::Value::Float(d.start_dx_m),
                            toml::Value::Float(d.start_dy_m),
                        ]),
                    );
                }
            }
            if d.start_dyaw_deg != 0.0 {
                r.insert(
                    "start_yaw_deg".into(),
                    toml::Value::Float(self.start_yaw_deg(d)),
                );
            }
            if d.noise_scale != 1.0 {
                self.scale_noise(&loc, r, d.noise_scale)?;
            }
        }
        if let Some(mu) = d.friction {
            let w = sub(&mut t, "world");
            if w.contains_key("default_ground") {
                let g =
                    ground_with_friction(&loc, "world.default_ground", w.get("default_ground"), mu)
                        .map_err(|e| e.0)?;
                w.insert("default_ground".into(), g);
            }
            if let Some(ts) = t.get_mut("terrains").and_then(|x| x.as_array_mut()) {
                for (i, tr) in ts.iter_mut().enumerate() {
                    if let Some(tr) = tr.as_table_mut() {
                        let g = ground_with_friction(
                            &loc,
                            &format!("terrains[{i}].ground"),
                            tr.get("ground"),
                            mu,
                        )
                        .map_err(|e| e.0)?;
                        tr.insert("ground".into(), g);
                    }
                }
            }
        }
        let src = toml::to_string(&t).map_err(|e| e.to_string())?;
        parse_scenario(&self.scenario.path, src).map_err(|e| e.message_with_path())
    }

    /// Writes the robot's sensor noise figures times `f` into its table.
    fn scale_noise(&self, loc: &Locator<'_>, r: &mut toml::Table, f: f64) -> Result<(), String> {
        let spec_r = self
            .scenario
            .file
            .robots
            .iter()
            .find(|x| x.name == self.robot)
            .expect("the robot");
        let rate = self.scenario.file.world.controller_rate_hz;
        let p = self.scenario.file.robot_key_path(self.robot_index);
        let Some(cfg) = crate::sensing::sensor_config(loc, &p, spec_r, rate, self.nominal_mass_kg)
            .map_err(|e| e.message_with_path())?
        else {
            return Ok(()); // no sensors
        };
        let sensors = sub(r, "sensors");
        let set = |t: &mut toml::Table, k: &str, v: f64| {
            t.insert(k.into(), toml::Value::Float(v * f));
        };
        if let Some(i) = cfg.imu {
            let t = sub(sensors, "imu");
            set(t, "accel_noise_std_mps2", i.accel.white_std);
            set(t, "accel_bias_std_mps2", i.accel.bias_std);
            set(
                t,
                "accel_bias_walk_mps2_per_sqrt_s",
                i.accel.bias_walk_std_per_sqrt_s,
            );
            set(t, "gyro_noise_std_radps", i.gyro.white_std);
            set(t, "gyro_bias_std_radps", i.gyro.bias_std);
            set(
                t,
                "gyro_bias_walk_radps_per_sqrt_s",
                i.gyro.bias_walk_std_per_sqrt_s,
            );
        }
        if let Some(e) = cfg.encoders {
            let t = sub(sensors, "encoders");
            set(t, "noise_std_rad", e.noise_std_rad);
            set(t, "offset_std_rad", e.offset_std_rad);
            if let quadsim_engine::sensors::JointVelocityMode::Direct { noise_std_radps } =
                e.velocity
            {
                set(t, "velocity_noise_std_radps", noise_std_radps);
            }
        }
        if let Some(c) = cfg.contacts {
            set(sub(sensors, "contacts"), "noise_std_n", c.noise.white_std);
        }
        if let Some(m) = cfg.mocap {
            let t = sub(sensors, "mocap");
            set(t, "position_noise_std_m", m.position_noise_std_m);
            set(t, "orientation_noise_std_rad", m.orientation_noise_std_rad);
        }
        Ok(())
    }

    /// Runs copy `k` to the end (or a little past a fall) on one thread.
    pub fn run_copy(&self, k: usize) -> CopyResult {
        let draws = self.draws(k);
        let mut trace = Vec::new();
        let outcome = self.simulate(&draws, &mut trace);
        let (metrics, error) = match outcome {
            Ok(m) => (Some(m), None),
            Err(e) => (None, Some(e)),
        };
        CopyResult {
            copy: k,
            draws,
            metrics,
            error,
            trace,
        }
    }

    /// The world of a copy with draws `d`, ready for its first step (on one
    /// thread), and the perturbed robot's root entity.
    pub fn build_copy(&self, d: &Draws) -> Result<(World, Entity), String> {
        let scn = self.copy_scenario(d)?;
        let mut world = build_world(
            &scn,
            Overrides {
                duration_s: Some(self.duration_s),
                seed: Some(d.world_seed),
                threads: 1,
            },
        )
        .map_err(|e| e.message_with_path())?;
        let root = robot_root(&world, &self.robot);
        if !d.link_mass_scale.is_empty() {
            scale_masses(&mut world, root, &d.link_mass_scale);
        }
        Ok((world, root))
    }

    fn simulate(&self, d: &Draws, trace: &mut Vec<(f64, f64, f64)>) -> Result<CopyMetrics, String> {
        let (mut world, root) = self.build_copy(d)?;
        let total_mass_kg = world.sim.robot(root).expect("compiled").model.total_mass;
        let (hx, hy) = heading(self.start_yaw_deg(d));
        let forward = |w: &World| {
            let o = &w.sim.robot(root).expect("compiled").run.observation;
            (o.t_s, o.com_m.x * hx + o.com_m.y * hy)
        };
        let dt = world.dt_s;
        let steps = world.steps;
        // step indices of the windows' starts (none past the end)
        let at = |t: f64| Some((t / dt).round() as u64).filter(|&k| k < steps);
        let k_height = at(self.spec.height_from_s);
        let k_steady = at(self.spec.steady_from_s);
        let every = ((SAMPLE_S / dt).round() as u64).max(1);
        let yaw0 = self.start_yaw_deg(d).to_radians();

        // the metrics from 0 to k_height (the run's own accumulator, then
        // replaced by a fresh one that covers k_height to the end)
        let mut before: Option<MetricsSummary> = None;
        // at k_steady: (t, x) and the commanded distance (Σ v_cmd dt, Σ dt)
        let mut steady: Option<((f64, f64), (f64, f64))> = None;
        let mut fell_at_s: Option<f64> = None;
        let mut step = 0;
        while step < steps {
            let next = [k_height, k_steady]
                .into_iter()
                .flatten()
                .filter(|&m| m > step)
                .fold(((step / every + 1) * every).min(steps), u64::min);
            while world.sim.clock().step < next {
                let left = next - world.sim.clock().step;
                world.sim.run_pass(left);
            }
            step = next;
            crate::divergence::check_finite(&world).map_err(|e| e.to_string())?;
            let (t, x) = forward(&world);
            let r = world.sim.robot_mut(root).expect("compiled");
            trace.push((t, x, r.run.commanded_distance_m.0));
            let now = r.run.metrics.summary();
            if let Some(t) = now.fell_at_s.or(before.as_ref().and_then(|f| f.fell_at_s)) {
                fell_at_s = Some(t);
                break;
            }
            if Some(step) == k_height {
                before = Some(now);
                r.run.metrics = MetricsAccumulator::new(yaw0, 0.0);
            }
            if Some(step) == k_steady {
                let o = &r.run.observation;
                steady = Some((
                    (o.t_s, o.com_m.x * hx + o.com_m.y * hy),
                    r.run.commanded_distance_m,
                ));
            }
        }
        let r = world.sim.robot(root).expect("compiled");
        let last = r.run.metrics.summary();
        // the whole run in one or two parts; the height window's part
        let (parts, height): (Vec<&MetricsSummary>, Option<&MetricsSummary>) = match &before {
            Some(b) => (vec![b, &last], Some(&last)),
            None if k_height == Some(0) => (vec![&last], Some(&last)),
            None => (vec![&last], None),
        };
        let max_abs = |f: fn(&MetricsSummary) -> [f64; 2]| {
            parts
                .iter()
                .map(|m| {
                    let [lo, hi] = f(m);
                    lo.abs().max(hi.abs())
                })
                .fold(0.0, f64::max)
        };
        let fell = fell_at_s.is_some();
        let (mean_speed_mps, commanded_speed_mps) = match steady {
            Some(((t0, x0), (c0, s0))) if !fell => {
                let (t1, x1) = forward(&world);
                let (c1, s1) = r.run.commanded_distance_m;
                let v = (t1 > t0).then(|| (x1 - x0) / (t1 - t0));
                let c = (matches!(r.run.controller, Controller::Walker(_)) && s1 > s0)
                    .then(|| (c1 - c0) / (s1 - s0));
                (v, c)
            }
            _ => (None, None),
        };
        Ok(CopyMetrics {
            fell,
            fell_at_s,
            simulated_s: world.sim.clock().time_s,
            total_mass_kg,
            mean_speed_mps,
            commanded_speed_mps,
            speed_error_mps: mean_speed_mps.zip(commanded_speed_mps).map(|(v, c)| v - c),
            max_abs_roll_rad: max_abs(|m| m.roll_range_rad),
            max_abs_pitch_rad: max_abs(|m| m.pitch_range_rad),
            height_p2p_m: height.map(|m| m.base_height_p2p_m),
            peak_foot_force_n: parts.iter().map(|m| m.max_foot_force_n).fold(0.0, f64::max),
        })
    }
}

/// Scales the mass (and a given inertia) of robot `root`'s links by their
/// factors, recompiles, and gives the controller the nominal model: the
/// body is heavier or lighter, the controller and estimator do not know.
fn scale_masses(world: &mut World, root: Entity, scale: &BTreeMap<String, f64>) {
    let nominal = {
        let r = world.sim.robot(root).expect("compiled");
        r.control
            .as_ref()
            .map_or_else(|| r.model.clone(), |c| c.model.clone())
    };
    for (e, name, m, inertia) in robot_links(world, root) {
        let Some(&s) = scale.get(&name) else {
            continue;
        };
        let mut ent = world.sim.world.entity_mut(e);
        ent.insert(Mass(m * s));
        if let Some(i) = inertia {
            ent.insert(Inertia(i.0 * s));
        }
    }
    world.sim.compile();
    let r = world.sim.robot_mut(root).expect("compiled");
    r.control = Some(ControlView {
        data: Data::new(&nominal),
        model: nominal,
    });
}

/// Wilson score interval of a proportion `k` of `n` at 95 % (z = 1.96).
pub fn wilson_95(k: usize, n: usize) -> [f64; 2] {
    if n == 0 {
        return [0.0, 1.0];
    }
    let z = 1.96f64;
    let n_f = n as f64;
    let p = k as f64 / n_f;
    let z2n = z * z / n_f;
    let centre = (p + 0.5 * z2n) / (1.0 + z2n);
    let half = z / (1.0 + z2n) * (p * (1.0 - p) / n_f + z * z / (4.0 * n_f * n_f)).sqrt();
    [(centre - half).max(0.0), (centre + half).min(1.0)]
}

/// The campaign's aggregates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Aggregates {
    /// Copies run.
    pub copies: usize,
    /// Copies that failed to run (an error; not counted below).
    pub failed: usize,
    /// Copies that fell.
    pub falls: usize,
    /// `falls / (copies − failed)`.
    pub fall_rate: f64,
    /// 95 % Wilson score interval of the fall rate.
    pub fall_rate_wilson_95: [f64; 2],
    /// Copies that held (neither fell nor failed): the figures below are over them.
    pub held: usize,
    /// Mean, min and max of the held copies' steady-state speed (m/s).
    pub mean_speed_mps: Option<f64>,
    /// Smallest steady-state speed (m/s).
    pub min_speed_mps: Option<f64>,
    /// Largest steady-state speed (m/s).
    pub max_speed_mps: Option<f64>,
    /// Mean speed tracking error (m/s).
    pub mean_speed_error_mps: Option<f64>,
    /// Largest |speed tracking error| (m/s).
    pub max_abs_speed_error_mps: Option<f64>,
    /// Largest |roll| (rad).
    pub worst_abs_roll_rad: Option<f64>,
    /// Largest |pitch| (rad).
    pub worst_abs_pitch_rad: Option<f64>,
    /// Largest torso height peak-to-peak (m).
    pub worst_height_p2p_m: Option<f64>,
    /// Largest peak foot force (N).
    pub worst_peak_foot_force_n: Option<f64>,
}

/// Aggregates over the copies.
pub fn aggregate(results: &[CopyResult]) -> Aggregates {
    let ok: Vec<&CopyMetrics> = results.iter().filter_map(|r| r.metrics.as_ref()).collect();
    let falls = ok.iter().filter(|m| m.fell).count();
    let held: Vec<&&CopyMetrics> = ok.iter().filter(|m| !m.fell).collect();
    let vals = |f: &dyn Fn(&CopyMetrics) -> Option<f64>| -> Vec<f64> {
        held.iter().filter_map(|m| f(m)).collect()
    };
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    let min = |v: &[f64]| v.iter().copied().reduce(f64::min);
    let max = |v: &[f64]| v.iter().copied().reduce(f64::max);
    let speeds = vals(&|m| m.mean_speed_mps);
    let errors = vals(&|m| m.speed_error_mps);
    Aggregates {
        copies: results.len(),
        failed: results.len() - ok.len(),
        falls,
        fall_rate: if ok.is_empty() {
            0.0
        } else {
            falls as f64 / ok.len() as f64
        },
        fall_rate_wilson_95: wilson_95(falls, ok.len()),
        held: held.len(),
        mean_speed_mps: mean(&speeds),
        min_speed_mps: min(&speeds),
        max_speed_mps: max(&speeds),
        mean_speed_error_mps: mean(&errors),
        max_abs_speed_error_mps: max(&errors.iter().map(|e| e.abs()).collect::<Vec<_>>()),
        worst_abs_roll_rad: max(&vals(&|m| Some(m.max_abs_roll_rad))),
        worst_abs_pitch_rad: max(&vals(&|m| Some(m.max_abs_pitch_rad))),
        worst_height_p2p_m: max(&vals(&|m| m.height_p2p_m)),
        worst_peak_foot_force_n: max(&vals(&|m| Some(m.peak_foot_force_n))),
    }
}

/// The scenario a campaign ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioInfo {
    /// Its path as given.
    pub path: String,
    /// Its name.
    pub name: String,
    /// SHA-256 of its text.
    pub sha256: String,
    /// The perturbed robot.
    pub robot: String,
    /// Its nominal mass (kg).
    pub nominal_mass_kg: f64,
    /// Simulated duration of each copy (s).
    pub duration_s: f64,
    /// Step (s).
    pub dt_s: f64,
}

/// The metrics' windows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Windows {
    /// Start of the steady-state speed window (s); it ends with the run.
    pub steady_state_from_s: f64,
    /// Start of the torso height peak-to-peak window (s).
    pub height_from_s: f64,
}

/// Wall-clock figures: the only part of `campaign.json` that changes between
/// identical runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// Wall-clock time of the copies (s).
    pub wall_s: f64,
    /// Copies run at once.
    pub threads: usize,
    /// Simulated robot-seconds per wall-clock second.
    pub sim_s_per_wall_s: f64,
    /// The command line.
    pub argv: Vec<String>,
}

/// `campaign.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The case's label.
    pub case: String,
    /// The walking robot's commanded velocity (null for other controllers).
    pub command: Option<Command>,
    /// The scenario.
    pub scenario: ScenarioInfo,
    /// Copies.
    pub n: usize,
    /// Campaign seed.
    pub seed: u64,
    /// The perturbations' ranges.
    pub perturbations: Perturbations,
    /// The windows.
    pub windows: Windows,
    /// Aggregates.
    pub aggregates: Aggregates,
    /// Every copy, in copy order.
    pub runs: Vec<CopyResult>,
    /// Wall-clock figures.
    pub timing: Timing,
}

impl Prepared {
    /// The report of `results` (sorted by copy).
    pub fn report(&self, results: Vec<CopyResult>, timing: Timing) -> CampaignReport {
        CampaignReport {
            schema_version: SCHEMA_VERSION,
            case: self.case(),
            command: self.command,
            scenario: ScenarioInfo {
                path: self.scenario.path.display().to_string(),
                name: self.scenario.name.clone(),
                sha256: self.scenario_sha256(),
                robot: self.robot.clone(),
                nominal_mass_kg: self.nominal_mass_kg,
                duration_s: self.duration_s,
                dt_s: self.dt_s,
            },
            n: self.spec.copies,
            seed: self.spec.seed,
            perturbations: self.spec.perturb,
            windows: Windows {
                steady_state_from_s: self.spec.steady_from_s,
                height_from_s: self.spec.height_from_s,
            },
            aggregates: aggregate(&results),
            runs: results,
            timing,
        }
    }
}

/// Runs copies `0..n` on `threads` threads (each copy's world on one); the
/// results in copy order, whatever order they finished in. `done` is called
/// after each copy (the progress bar).
pub fn run_copies(
    prep: &Prepared,
    threads: usize,
    done: &(dyn Fn(&CopyResult) + Sync),
) -> Vec<CopyResult> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let n = prep.spec.copies;
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::with_capacity(n));
    std::thread::scope(|s| {
        for _ in 0..threads.clamp(1, n.max(1)) {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= n {
                        break;
                    }
                    let r = prep.run_copy(k);
                    done(&r);
                    results.lock().expect("no panic holds the lock").push(r);
                }
            });
        }
    });
    let mut results = results.into_inner().expect("no panic holds the lock");
    results.sort_by_key(|r| r.copy);
    results
}

/// The path of a file in the output directory.
pub fn out_file(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

/// A campaign file (`kind = "campaign"`): a base scenario and the
/// campaign's settings, so that a campaign can be kept beside the scenarios
/// and run again (`docs/campaign.md`). Every key but `base` is optional;
/// the command line's flags override them.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignFile {
    /// Must be 1.
    pub format_version: i64,
    /// `campaign`.
    pub kind: String,
    /// The case's label (default: the file's stem).
    pub name: Option<String>,
    /// The scenario, relative to this file.
    pub base: String,
    /// Number of copies (default 20).
    pub copies: Option<usize>,
    /// Campaign seed (default 0).
    pub seed: Option<u64>,
    /// The perturbed robot.
    pub robot: Option<String>,
    /// Simulated duration of each copy (s).
    pub duration_s: Option<f64>,
    /// Start of the steady-state speed window (s, default 2).
    pub steady_from_s: Option<f64>,
    /// Start of the torso height window (s, default 1).
    pub height_from_s: Option<f64>,
    /// Most copies allowed to fall (`--max-falls`).
    pub max_falls: Option<usize>,
    /// The perturbations (each default as the command line's).
    #[serde(default)]
    pub perturbations: PerturbationsFile,
}

/// `[perturbations]` of a campaign file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerturbationsFile {
    /// Half-width of the start offset along x and y (m; 0: none).
    pub start_xy_m: Option<f64>,
    /// Half-width of the start yaw offset (degrees; 0: none).
    pub start_yaw_deg: Option<f64>,
    /// Half-width of the link mass factor (0: none).
    pub link_mass_frac: Option<f64>,
    /// `[lo, hi]`, one μ, or `false` (the scenario's grounds).
    pub friction: Option<toml::Value>,
    /// Whether each copy draws its world seed.
    pub world_seed: Option<bool>,
    /// One factor or `[lo, hi]` on the sensors' noise figures.
    pub noise_scale: Option<toml::Value>,
}

/// A campaign file's settings.
#[derive(Debug, Clone)]
pub struct LoadedCampaignFile {
    /// The campaign (scenario: the base, relative to the file).
    pub spec: CampaignSpec,
    /// `max_falls`.
    pub max_falls: Option<usize>,
}

/// `[lo, hi]` or one number `x` (`[x, x]`).
fn value_range(v: &toml::Value) -> Option<[f64; 2]> {
    match v {
        toml::Value::Array(a) if a.len() == 2 => Some([as_f64(&a[0])?, as_f64(&a[1])?]),
        x => as_f64(x).map(|x| [x, x]),
    }
}

/// Reads a campaign file. Errors name the file, line and key.
pub fn load_campaign_file(path: &Path) -> Result<LoadedCampaignFile, CampaignError> {
    let src = std::fs::read_to_string(path).map_err(|e| {
        err(format!(
            "{}: cannot read the campaign file: {e}",
            path.display()
        ))
    })?;
    let loc = Locator { path, src: &src };
    let at = |k: &str, m: String| err(loc.at(k, m).to_string());
    let f: CampaignFile = toml::from_str(&src).map_err(|e| {
        err(loc
            .at_span(e.span(), e.message().trim().to_string())
            .to_string())
    })?;
    if f.format_version != crate::scenario::FORMAT_VERSION {
        return Err(at(
            "format_version",
            format!("must be {}", crate::scenario::FORMAT_VERSION),
        ));
    }
    if f.kind != "campaign" {
        return Err(at(
            "kind",
            format!("'{}': a campaign file has kind = \"campaign\"", f.kind),
        ));
    }
    let base = path.parent().unwrap_or(Path::new(".")).join(&f.base);
    let mut spec = CampaignSpec::new(base, f.copies.unwrap_or(20));
    spec.seed = f.seed.unwrap_or(0);
    spec.robot = f.robot;
    spec.duration_s = f.duration_s;
    spec.steady_from_s = f.steady_from_s.unwrap_or(spec.steady_from_s);
    spec.height_from_s = f.height_from_s.unwrap_or(spec.height_from_s);
    spec.case = Some(f.name.unwrap_or_else(|| {
        path.file_stem()
            .map_or("campaign".into(), |s| s.to_string_lossy().into_owned())
    }));
    let p = &f.perturbations;
    let q = &mut spec.perturb;
    q.start_xy_m = p.start_xy_m.unwrap_or(q.start_xy_m);
    q.start_yaw_deg = p.start_yaw_deg.unwrap_or(q.start_yaw_deg);
    q.link_mass_frac = p.link_mass_frac.unwrap_or(q.link_mass_frac);
    q.world_seed = p.world_seed.unwrap_or(q.world_seed);
    match &p.friction {
        None => {}
        Some(toml::Value::Boolean(false)) => q.friction = None,
        Some(v) => {
            q.friction = Some(value_range(v).ok_or_else(|| {
                at(
                    "perturbations.friction",
                    "expected [lo, hi], one μ, or false (the scenario's grounds)".into(),
                )
            })?);
        }
    }
    if let Some(v) = &p.noise_scale {
        q.noise_scale = value_range(v).ok_or_else(|| {
            at(
                "perturbations.noise_scale",
                "expected one factor or [lo, hi]".into(),
            )
        })?;
    }
    if let Err(e) = q.validate() {
        let key = e.split(':').next().unwrap_or("").to_string();
        return Err(at(&format!("perturbations.{key}"), e));
    }
    Ok(LoadedCampaignFile {
        spec,
        max_falls: f.max_falls,
    })
}
