//! `log.mcap`: the run log that robotics tools open (Foxglove, PlotJuggler,
//! the `mcap` libraries). See `docs/logs.md` for the channels and how to open
//! a log.
//!
//! - [`schema`]: the schemas of every channel (protobuf or JSON);
//! - [`proto`]: protobuf encoding, descriptors and decoding;
//! - [`encode`]: encoding of the simulation's samples;
//! - [`writer`]: the MCAP writer thread;
//! - [`read`]: reading a log back (tolerates a truncated file);
//! - [`interrupt`]: Ctrl-C / SIGTERM as a flag the run loop polls;
//! - [`select`]: which robots are logged, and at which decimation.
//!
//! [`start_run_log`] and [`RunLog::finish`] tie them to a `quadsim run`.

pub mod encode;
pub mod interrupt;
pub mod proto;
pub mod read;
pub mod schema;
pub mod select;
pub mod writer;

use std::collections::BTreeMap;
use std::path::Path;

use glam::DVec3;
use quadsim_engine::terrain::{Terrain as _, TerrainUnion};
use quadsim_systems::{finish_logging, start_sampling_each, step_time_ns};
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

use crate::scenario::Scenario;
use crate::world::World;
use encode::GroundMesh;
use schema::Schema;
pub use schema::{METRICS_SUFFIX, metrics_topic};
pub use writer::{LogError, McapLog, WriterStats};

/// File name of the log in a run's output directory.
pub const LOG_FILE: &str = "log.mcap";
/// How a run ended, as recorded in the log's `run` metadata.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOutcome {
    /// Stopped by Ctrl-C or SIGTERM.
    pub interrupted: bool,
    /// Stopped by a divergence (the message names robot, time and quantity).
    pub diverged: Option<String>,
}

/// A log attached to a running world.
#[derive(Debug)]
pub struct RunLog {
    log: McapLog,
    /// Steps between samples.
    pub every_steps: u64,
}

/// A JSON value as text, the way `summary.json` writes it (so that reading it
/// back and writing it again gives the same text).
fn json_text(v: Value) -> String {
    serde_json::to_string(&v).expect("json")
}

/// Creates `path`, writes the metadata and the terrain description, and
/// attaches a logger sampling every `every_steps` steps to the world (robots
/// with a rate of their own, `[robots.log] rate_hz`, at theirs; robots
/// deselected by `[log] robots` or `log = false` not at all).
pub fn start_run_log(
    scn: &Scenario,
    world: &mut World,
    path: &Path,
    every_steps: u64,
) -> Result<RunLog, LogError> {
    let plan = select::LogPlan::new(scn, world, every_steps, &Default::default());
    start_run_log_with(scn, world, path, &plan)
}

/// [`start_run_log`] with each robot's decimation given by `plan`.
pub fn start_run_log_with(
    scn: &Scenario,
    world: &mut World,
    path: &Path,
    plan: &select::LogPlan,
) -> Result<RunLog, LogError> {
    let every_steps = plan.every_steps;
    let sha = Sha256::digest(scn.source.as_bytes());
    let w = &scn.file.world;
    let mut scenario = BTreeMap::new();
    scenario.insert("name".to_string(), scn.name.clone());
    scenario.insert("text".to_string(), scn.source.clone());
    scenario.insert("sha256".to_string(), format!("{sha:x}"));
    // strings as they are; numbers as JSON text (read back to the same value)
    let mut quadsim = BTreeMap::new();
    quadsim.insert("version".to_string(), env!("CARGO_PKG_VERSION").to_string());
    quadsim.insert(
        "git_commit".to_string(),
        env!("QUADSIM_GIT_COMMIT").to_string(),
    );
    quadsim.insert(
        "integrator".to_string(),
        crate::summary::integrator_name(scn).to_string(),
    );
    for (k, v) in [
        ("seed", json!(world.seed)),
        ("dt_s", json!(world.dt_s)),
        ("controller_rate_hz", json!(w.controller_rate_hz)),
        ("log_every_steps", json!(every_steps)),
        (
            "log_rate_hz",
            json!(1.0 / (world.dt_s * every_steps as f64)),
        ),
        (
            "summary_format_version",
            json!(crate::summary::SUMMARY_FORMAT_VERSION),
        ),
    ] {
        quadsim.insert(k.to_string(), json_text(v));
    }
    if !plan.is_uniform() {
        // robots at their own decimation (steps; null: not logged)
        let each: serde_json::Map<String, Value> = plan
            .robots
            .iter()
            .map(|(_, name, d)| (name.clone(), json!(d)))
            .collect();
        quadsim.insert(
            "robot_log_every_steps".to_string(),
            json_text(Value::Object(each)),
        );
    }
    let union = crate::world::ground_of(world);
    let log = McapLog::create(
        path,
        vec![("scenario".into(), scenario), ("quadsim".into(), quadsim)],
        ground_mesh(&union),
    )?;
    log.write_json(
        writer::TERRAIN_TOPIC,
        Schema::TerrainDescription,
        0,
        &terrain_description(scn),
    );
    let robots: Vec<_> = plan.robots.iter().map(|(e, _, d)| (*e, *d)).collect();
    start_sampling_each::<quadsim_systems::LogChannel>(
        &mut world.sim.world,
        log.sink(),
        every_steps,
        &robots,
    );
    Ok(RunLog { log, every_steps })
}

impl RunLog {
    /// Ends the log: the final state's sample (unless the run diverged), each
    /// robot's `metrics` message, the `run` metadata, then the summary
    /// section and index.
    pub fn finish(self, world: &mut World, outcome: &RunOutcome) -> Result<WriterStats, LogError> {
        drop(finish_logging(
            &mut world.sim.world,
            outcome.diverged.is_none(),
        ));
        let clock = world.sim.clock();
        let t_ns = step_time_ns(clock.step, world.dt_s);
        for (name, root) in &world.robots {
            if let Some(r) = world.sim.robot(*root) {
                let m = crate::summary::RobotSummary::in_world(world, name, r).to_json();
                self.log
                    .write_json(&metrics_topic(name), Schema::RobotMetrics, t_ns, &m);
            }
        }
        let mut run = BTreeMap::new();
        run.insert("steps".to_string(), json_text(json!(clock.step)));
        run.insert("sim_time_s".to_string(), json_text(json!(clock.time_s)));
        run.insert(
            "interrupted".to_string(),
            json_text(json!(outcome.interrupted)),
        );
        if let Some(d) = &outcome.diverged {
            run.insert("diverged".to_string(), d.clone());
        }
        self.log.write_metadata("run", run);
        self.log.finish()
    }
}

/// The `/terrain` message: the scenario's ground as written in the file.
pub fn terrain_description(scn: &Scenario) -> Value {
    let table: toml::Table = scn.source.parse().unwrap_or_default();
    let world = table.get("world");
    let to_json = |v: Option<&toml::Value>| {
        v.and_then(|v| serde_json::to_value(v).ok())
            .unwrap_or(Value::Null)
    };
    json!({
        "timestamp": {"sec": 0, "nsec": 0},
        "default_ground": to_json(world.and_then(|w| w.get("default_ground"))),
        "default_ground_height_m": scn.file.world.default_ground_height_m,
        "terrains": to_json(table.get("terrains")).as_array().cloned().unwrap_or_default(),
    })
}

/// Cells per side of a terrain patch's mesh at most.
const MAX_CELLS: usize = 96;
/// Half-width of the default ground's square around the world origin (m).
const DEFAULT_GROUND_HALF_M: f64 = 10.0;

/// A triangle mesh of the ground for the 3D scene: each terrain patch sampled
/// on a grid of its bounding box (the union's height, so overlaps show the
/// top surface; holes are left open), and the default ground as a square.
pub fn ground_mesh(union: &TerrainUnion) -> GroundMesh {
    let mut mesh = GroundMesh::default();
    let (mut lo, mut hi) = (
        DVec3::splat(-DEFAULT_GROUND_HALF_M),
        DVec3::splat(DEFAULT_GROUND_HALF_M),
    );
    for p in union.patches() {
        let b = p.shape().local_bounds();
        let (c, s) = (p.yaw_rad().cos(), p.yaw_rad().sin());
        let o = p.origin_m();
        let (mut plo, mut phi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for x in [b.min.x, b.max.x] {
            for y in [b.min.y, b.max.y] {
                let w = DVec3::new(o.x + c * x - s * y, o.y + s * x + c * y, 0.0);
                plo = plo.min(w);
                phi = phi.max(w);
            }
        }
        if !(plo.is_finite() && phi.is_finite()) {
            continue;
        }
        lo = lo.min(plo);
        hi = hi.max(phi);
        let size = phi - plo;
        let n = |len: f64| ((len / 0.05).ceil() as usize).clamp(1, MAX_CELLS);
        let (nx, ny) = (n(size.x), n(size.y));
        let base = mesh.points.len() as u32;
        let mut ok = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                let x = plo.x + size.x * i as f64 / nx as f64;
                let y = plo.y + size.y * j as f64 / ny as f64;
                let h = if p.covers(x, y) {
                    union.height(x, y)
                } else {
                    None
                };
                ok.push(h.is_some());
                mesh.points.push(DVec3::new(x, y, h.unwrap_or(0.0)));
            }
        }
        let at = |i: usize, j: usize| j * (nx + 1) + i;
        for j in 0..ny {
            for i in 0..nx {
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                if q.iter().all(|&k| ok[k]) {
                    for k in [q[0], q[1], q[2], q[0], q[2], q[3]] {
                        mesh.indices.push(base + k as u32);
                    }
                }
            }
        }
    }
    if let Some(g) = union.default_ground() {
        let z = g.height_m - 1e-3; // just below patches lying on it
        let base = mesh.points.len() as u32;
        for (x, y) in [(lo.x, lo.y), (hi.x, lo.y), (hi.x, hi.y), (lo.x, hi.y)] {
            mesh.points.push(DVec3::new(x, y, z));
        }
        mesh.indices
            .extend([0, 1, 2, 0, 2, 3].iter().map(|k| base + k));
    }
    mesh
}
