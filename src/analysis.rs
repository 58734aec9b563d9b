//! Analyses that re-run a scenario: the largest push a walking robot recovers
//! from ([`push_search`]), and the traces they read ([`run_trace`]).
//!
//! Each trial builds the world afresh from the scenario (same seed, so the
//! trials differ only in the push), adds one push to one robot and steps the
//! whole pipeline (contact, controller, dynamics, fall check) to the end of a
//! window after the push.
//!
//! # Definitions
//! - **Lateral displacement**: the CoM's horizontal position projected on
//!   the robot's start heading's left axis (world xy, `(−sin ψ₀, cos ψ₀)`
//!   with ψ₀ = `start_yaw_deg`), in m, left positive.
//! - **Lateral drift** of a pushed run: the largest `|y_pushed(t) −
//!   y_unpushed(t)|` over the steps from the push's start to the end of the
//!   trial, where `y` is the lateral displacement and the unpushed run is the
//!   same scenario without the push (deterministic: it differs from the
//!   pushed one only through the push). Referring to the unpushed run rather
//!   than the start line removes whatever drift the gait has on its own.
//! - **Recovered**: the robot has not fallen (the scenario's fall criteria,
//!   `scenarios/README.md`) by the end of the trial window.
//!
//! The search ([`push_search`]) bisects the force magnitude at a fixed
//! duration and direction: it assumes one threshold (recovered below, fallen
//! above). A robot may recover from some force above one it falls from; the
//! bisection then reports one boundary, not necessarily the largest.

use bevy_ecs::prelude::Entity;
use glam::DVec3;
use quadsim_components::Push;

use crate::scenario::{Scenario, ScenarioError};
use crate::world::{Overrides, World, build_world};

/// One robot's trace through a run, sampled every step.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// Time at the end of each step (s).
    pub t_s: Vec<f64>,
    /// CoM lateral displacement (m; module docs).
    pub lateral_m: Vec<f64>,
    /// CoM forward displacement along the start heading (m).
    pub forward_m: Vec<f64>,
    /// Base yaw (rad, unwrapped).
    pub yaw_rad: Vec<f64>,
    /// First time the fall criteria held (s), if they did.
    pub fell_at_s: Option<f64>,
}

impl Trace {
    /// Largest `|self.lateral − other.lateral|` over the samples at or after
    /// `from_s` that both traces have (m).
    pub fn max_lateral_gap_m(&self, other: &Trace, from_s: f64) -> f64 {
        self.t_s
            .iter()
            .zip(&self.lateral_m)
            .zip(&other.lateral_m)
            .filter(|((t, _), _)| **t >= from_s - 1e-12)
            .map(|((_, a), b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    /// The yaw at the first sample at or after `t_s` (rad), if any.
    pub fn yaw_at(&self, t_s: f64) -> Option<f64> {
        let i = self.t_s.iter().position(|t| *t >= t_s - 1e-12)?;
        Some(self.yaw_rad[i])
    }
}

/// A push of one robot's base, for [`run_trace`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BasePush {
    /// Start (s).
    pub t_s: f64,
    /// Duration (s).
    pub duration_s: f64,
    /// Force (N, world), applied at the base origin.
    pub force_n: DVec3,
}

fn robot_root(world: &World, name: &str) -> Option<Entity> {
    world
        .robots
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, e)| *e)
}

/// Runs `scn` for `duration_s` (or its own duration) with an optional extra
/// push on robot `robot`'s base, and returns that robot's trace. Stops early
/// `stop_after_fall_s` after a fall (the rest of the trace is then missing).
///
/// # Errors
/// The scenario's build errors; an unknown robot name (as a scenario error
/// on `robots`).
pub fn run_trace(
    scn: &Scenario,
    robot: &str,
    push: Option<BasePush>,
    duration_s: Option<f64>,
    stop_after_fall_s: f64,
) -> Result<Trace, ScenarioError> {
    let mut world = build_world(
        scn,
        Overrides {
            duration_s,
            threads: 1,
            ..Default::default()
        },
    )?;
    let root = robot_root(&world, robot).ok_or_else(|| {
        crate::scenario::Locator {
            path: &scn.path,
            src: &scn.source,
        }
        .at("robots", format!("no robot named '{robot}'"))
    })?;
    let yaw0 = scn
        .file
        .robots
        .iter()
        .find(|r| r.name == robot)
        .map_or(0.0, |r| r.start_yaw_deg.to_radians());
    let (s, c) = yaw0.sin_cos();
    if let Some(p) = push {
        let sim = world.sim.robot_mut(root).expect("compiled robot");
        sim.contact.pushes.push(Push {
            start_s: p.t_s,
            end_s: p.t_s + p.duration_s,
            body: 0,
            point_in_body_m: DVec3::ZERO,
            force_n: p.force_n,
        });
    }
    let n = world.steps as usize;
    let mut tr = Trace {
        t_s: Vec::with_capacity(n),
        lateral_m: Vec::with_capacity(n),
        forward_m: Vec::with_capacity(n),
        yaw_rad: Vec::with_capacity(n),
        fell_at_s: None,
    };
    let mut yaw_prev: Option<f64> = None;
    let mut yaw_unwrapped = 0.0;
    for _ in 0..world.steps {
        world.sim.step();
        let t = world.sim.clock().time_s;
        let sim = world.sim.robot(root).expect("compiled robot");
        let obs = &sim.run.observation;
        let com = obs.com_m;
        let yaw = quadsim_engine::spatial::rpy_from_rot(obs.base.rot).z;
        yaw_unwrapped = match yaw_prev {
            None => yaw,
            Some(p) => yaw_unwrapped + wrap_pi(yaw - p),
        };
        yaw_prev = Some(yaw);
        tr.t_s.push(t);
        tr.lateral_m.push(-s * com.x + c * com.y);
        tr.forward_m.push(c * com.x + s * com.y);
        tr.yaw_rad.push(yaw_unwrapped);
        if obs.fallen && tr.fell_at_s.is_none() {
            tr.fell_at_s = Some(obs.t_s);
        }
        if let Some(tf) = tr.fell_at_s
            && t >= tf + stop_after_fall_s
        {
            break;
        }
    }
    Ok(tr)
}

fn wrap_pi(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = a.rem_euclid(TAU);
    if r > PI { r - TAU } else { r }
}

pub use crate::scenario::push::PushDirection;

/// Settings of [`push_search`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PushSearchOptions {
    /// Push start (s).
    pub t_s: f64,
    /// Push duration (s), fixed during the search.
    pub duration_s: f64,
    /// Direction (start heading frame).
    pub direction: PushDirection,
    /// Upper end of the bracket (N). If the robot recovers from it, the search
    /// reports it as a lower bound (`bracketed = false`).
    pub max_force_n: f64,
    /// Bisection steps after the bracket check: the force is found to
    /// `max_force_n / 2^iterations`.
    pub iterations: u32,
    /// Length of each trial after the push's start (s).
    pub settle_s: f64,
}

impl Default for PushSearchOptions {
    /// A lateral (left) push of 0.1 s at t = 5 s, forces up to 1000 N (100
    /// N·s), bisected 6 times (to 16 N), 3 s trials after the push.
    fn default() -> Self {
        PushSearchOptions {
            t_s: 5.0,
            duration_s: 0.1,
            direction: PushDirection::Left,
            max_force_n: 1000.0,
            iterations: 6,
            settle_s: 3.0,
        }
    }
}

impl PushSearchOptions {
    /// The options of a robot's `[robots.analysis]` table (defaults for the
    /// keys it leaves out; the table is validated when the scenario loads).
    pub fn from_spec(a: &crate::scenario::format::AnalysisSpec) -> PushSearchOptions {
        let d = PushSearchOptions::default();
        PushSearchOptions {
            t_s: a.push_t_s.unwrap_or(d.t_s),
            duration_s: a.push_duration_s.unwrap_or(d.duration_s),
            direction: a
                .push_direction
                .as_deref()
                .and_then(PushDirection::from_name)
                .unwrap_or(d.direction),
            max_force_n: a.push_max_force_n.unwrap_or(d.max_force_n),
            iterations: a.push_iterations.unwrap_or(d.iterations),
            settle_s: a.push_settle_s.unwrap_or(d.settle_s),
        }
    }
}

/// One trial of the search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PushTrial {
    /// Force magnitude (N).
    pub force_n: f64,
    /// Recovered (module docs).
    pub recovered: bool,
    /// Lateral drift over the trial (m; module docs), up to the fall if it fell.
    pub lateral_drift_m: f64,
}

/// What [`push_search`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct PushRecovery {
    /// Largest impulse recovered from, `force_n × duration_s` (N·s).
    pub max_impulse_ns: f64,
    /// Its force (N); 0 when even the smallest trial fell.
    pub force_n: f64,
    /// Push duration (s).
    pub duration_s: f64,
    /// Push start (s).
    pub t_s: f64,
    /// Direction (start heading frame).
    pub direction: PushDirection,
    /// Unit direction in the world.
    pub direction_world: DVec3,
    /// The lateral drift at the reported force (m).
    pub lateral_drift_m: f64,
    /// Whether a fall was found at `max_force_n` (else the result is only a
    /// lower bound).
    pub bracketed: bool,
    /// When the unpushed reference run itself fell (s): then no trial is run
    /// and the result is zero.
    pub reference_fell_at_s: Option<f64>,
    /// Every trial, in order.
    pub trials: Vec<PushTrial>,
}

impl PushRecovery {
    /// The `push_recovery` object of `summary.json`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "max_impulse_ns": self.max_impulse_ns,
            "force_n": self.force_n,
            "duration_s": self.duration_s,
            "t_s": self.t_s,
            "direction": self.direction.name(),
            "direction_world": self.direction_world.to_array(),
            "lateral_drift_m": self.lateral_drift_m,
            "bracketed": self.bracketed,
            "reference_fell_at_s": self.reference_fell_at_s,
            "trials": self.trials.iter().map(|t| serde_json::json!({
                "force_n": t.force_n,
                "recovered": t.recovered,
                "lateral_drift_m": t.lateral_drift_m,
            })).collect::<Vec<_>>(),
        })
    }
}

/// Bisection on a force magnitude in `[0, max_force_n]`: `trial(f)` says
/// whether the robot recovers from `f`. First tries `max_force_n` (if it
/// recovers, the search ends: a lower bound), then bisects `iterations`
/// times between the largest force recovered from and the smallest fallen
/// from. Returns the largest recovered force (0 if none was tried) and
/// whether the bracket held.
pub fn bisect_force<E>(
    max_force_n: f64,
    iterations: u32,
    mut trial: impl FnMut(f64) -> Result<bool, E>,
) -> Result<(f64, bool), E> {
    if trial(max_force_n)? {
        return Ok((max_force_n, false));
    }
    let (mut lo, mut hi) = (0.0, max_force_n);
    for _ in 0..iterations {
        let mid = 0.5 * (lo + hi);
        if trial(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((lo, true))
}

/// The largest push robot `robot` of `scn` recovers from: bisection on the
/// force at `opts.duration_s` in `opts.direction` (module docs). Costs
/// `iterations + 2` runs of `opts.t_s + opts.settle_s` simulated seconds
/// (the unpushed reference, the bracket, the bisection).
///
/// # Errors
/// Those of [`run_trace`].
pub fn push_search(
    scn: &Scenario,
    robot: &str,
    opts: &PushSearchOptions,
) -> Result<PushRecovery, ScenarioError> {
    let yaw0 = scn
        .file
        .robots
        .iter()
        .find(|r| r.name == robot)
        .map_or(0.0, |r| r.start_yaw_deg.to_radians());
    // + 0: no negative zeros in summary.json
    let dir = opts.direction.world(yaw0) + DVec3::ZERO;
    let window = Some(opts.t_s + opts.settle_s);
    let reference = run_trace(scn, robot, None, window, 0.0)?;
    let mut trials = Vec::new();
    if reference.fell_at_s.is_some() {
        return Ok(PushRecovery {
            max_impulse_ns: 0.0,
            force_n: 0.0,
            duration_s: opts.duration_s,
            t_s: opts.t_s,
            direction: opts.direction,
            direction_world: dir,
            lateral_drift_m: 0.0,
            bracketed: false,
            reference_fell_at_s: reference.fell_at_s,
            trials,
        });
    }
    let (force, bracketed) = bisect_force(opts.max_force_n, opts.iterations, |f| {
        let tr = run_trace(
            scn,
            robot,
            Some(BasePush {
                t_s: opts.t_s,
                duration_s: opts.duration_s,
                force_n: dir * f,
            }),
            window,
            0.0,
        )?;
        let recovered = tr.fell_at_s.is_none();
        trials.push(PushTrial {
            force_n: f,
            recovered,
            lateral_drift_m: tr.max_lateral_gap_m(&reference, opts.t_s),
        });
        Ok(recovered)
    })?;
    let drift = trials
        .iter()
        .find(|t| t.force_n == force && t.recovered)
        .map_or(0.0, |t| t.lateral_drift_m);
    Ok(PushRecovery {
        max_impulse_ns: force * opts.duration_s,
        force_n: force,
        duration_s: opts.duration_s,
        t_s: opts.t_s,
        direction: opts.direction,
        direction_world: dir,
        lateral_drift_m: drift,
        bracketed,
        reference_fell_at_s: None,
        trials,
    })
}
