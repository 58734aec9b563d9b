//! World resources: the step settings, the clock, the thread pool and the
//! packed per-robot simulation state.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::DVec3;
use quadsim_engine::integrate::{Integrator, State, StepWorkspace};
use quadsim_engine::model::STANDARD_GRAVITY;
use quadsim_engine::passive::PassiveParams;
use quadsim_engine::{Data, Model};
use thiserror::Error;

use crate::forces::ContactForces;
use crate::robot::RobotIndex;
use crate::run::RobotRun;

/// Settings of the fixed step, shared by every robot of the world.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct SimConfig {
    /// Step length (s).
    pub dt_s: f64,
    /// Integration scheme.
    pub integrator: Integrator,
    /// Gravity (m/s², world frame, z up); copied into each compiled model.
    pub gravity: DVec3,
    /// Passive joint model (damping, friction, soft limits, actuator saturation).
    pub passive: PassiveParams,
}

impl Default for SimConfig {
    /// 0.5 ms semi-implicit Euler steps under standard gravity, all passive effects on.
    fn default() -> Self {
        Self {
            dt_s: 0.0005,
            integrator: Integrator::default(),
            gravity: STANDARD_GRAVITY,
            passive: PassiveParams::default(),
        }
    }
}

/// Simulated time. `time_s = step × dt_s`, computed from the step count rather
/// than accumulated, so it does not drift by round-off over long runs.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct SimClock {
    /// Steps taken since the start.
    pub step: u64,
    /// Time at the end of the last step (s).
    pub time_s: f64,
}

/// Error building the thread pool.
#[derive(Debug, Error)]
#[error("cannot build a simulation thread pool with {threads} threads: {source}")]
pub struct ThreadPoolError {
    /// Requested number of threads.
    pub threads: usize,
    /// rayon's error.
    #[source]
    pub source: rayon::ThreadPoolBuildError,
}

/// Below this many robots a stage runs on the calling thread.
pub const PARALLEL_MIN_ITEMS: usize = 4;

/// The one thread pool robots are stepped on, sized by the `threads` setting
/// (the CLI's `--threads`). Owned by the world rather than global, so each
/// world (and each test) can have its own size.
#[derive(Resource, Debug)]
pub struct SimThreadPool {
    pool: std::sync::Arc<rayon::ThreadPool>,
}

impl SimThreadPool {
    /// A pool of `threads` workers (0: one per core).
    pub fn new(threads: usize) -> Result<Self, ThreadPoolError> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("quadsim-sim-{i}"))
            .build()
            .map(|pool| Self {
                pool: std::sync::Arc::new(pool),
            })
            .map_err(|source| ThreadPoolError { threads, source })
    }

    /// Number of worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Applies `f` to every item: in parallel on the pool's workers when there
    /// are at least [`PARALLEL_MIN_ITEMS`] items and more than one worker,
    /// else in order on the calling thread (waking workers costs more than a
    /// few robots' work). Items are independent, so the result is the same
    /// either way.
    pub fn for_each<T: Send>(&self, items: &mut [T], f: impl Fn(&mut T) + Sync + Send) {
        use rayon::prelude::*;
        if self.threads() <= 1 || items.len() < PARALLEL_MIN_ITEMS {
            items.iter_mut().for_each(f);
        } else {
            self.pool.install(|| items.par_iter_mut().for_each(f));
        }
    }

    /// Applies `f` to every group of consecutive items, group `g` being
    /// `items[ends[g − 1]..ends[g]]` (`ends` strictly increasing, the last
    /// equal to `items.len()`): in parallel on the pool's workers (the groups
    /// halved recursively with `rayon::join`) when there are at least
    /// [`PARALLEL_MIN_ITEMS`] items in two or more groups and more than one
    /// worker, else in order on the calling thread. Groups are independent,
    /// so the result is the same either way. Allocates nothing.
    ///
    /// # Panics
    /// If `ends` does not partition `items` as above.
    pub fn for_each_group<T: Send>(
        &self,
        items: &mut [T],
        ends: &[usize],
        f: impl Fn(&mut [T]) + Sync + Send,
    ) {
        assert_eq!(ends.last().copied().unwrap_or(0), items.len());
        if self.threads() <= 1 || items.len() < PARALLEL_MIN_ITEMS || ends.len() < 2 {
            let mut start = 0;
            for &end in ends {
                f(&mut items[start..end]);
                start = end;
            }
        } else {
            self.pool.install(|| split_groups(items, 0, ends, &f));
        }
    }

    /// The pool itself, shared: a caller that runs many steps runs them all
    /// inside it ([`rayon::ThreadPool::install`]), so the step's parallel
    /// passes start on a worker instead of waking the pool from outside and
    /// waiting to be woken back, twice per pass.
    pub fn shared(&self) -> std::sync::Arc<rayon::ThreadPool> {
        std::sync::Arc::clone(&self.pool)
    }

    /// Runs `f` inside the pool, so rayon's parallel iterators in it use these workers.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }
}

/// `f` on each group of `items` (which starts at index `offset` of the whole),
/// halving the groups into two `rayon::join` tasks until one is left.
fn split_groups<T: Send, F: Fn(&mut [T]) + Sync>(
    items: &mut [T],
    offset: usize,
    ends: &[usize],
    f: &F,
) {
    if let [_] = ends {
        f(items);
        return;
    }
    let mid = ends.len() / 2;
    let cut = ends[mid - 1] - offset;
    let (left, right) = items.split_at_mut(cut);
    rayon::join(
        || split_groups(left, offset, &ends[..mid], f),
        || split_groups(right, offset + cut, &ends[mid..], f),
    );
}

/// Whether the step puts robots of one model into SIMD lanes across
/// robots, four at a time ([`quadsim_engine::batch`]). The batched dynamics
/// are bit-identical to the scalar step, so this changes speed only.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LaneBatching {
    /// Every robot stepped alone (comparisons and tests).
    Off,
    /// Robots in lanes across robots, except those whose model runs its
    /// four legs in lanes within the robot on this CPU
    /// ([`quadsim_engine::dispatch::runs_on`]): quad16 and quad12 step
    /// faster alone that way (docs/batch.md, "Lanes across robots or across
    /// legs"). The default.
    #[default]
    Auto,
    /// Robots of one model always in lanes across robots.
    AcrossRobots,
}

impl LaneBatching {
    /// Whether robots of `model` go into lanes across robots.
    pub fn across_robots(self, model: &quadsim_engine::Model) -> bool {
        match self {
            Self::Off => false,
            Self::Auto => !quadsim_engine::dispatch::runs_on(model),
            Self::AcrossRobots => true,
        }
    }
}

/// How a step lays the per-robot stages (sense, control, contact, integrate,
/// metrics) over the robots. Robots do not interact, so both layouts give
/// the same bits; they differ in memory traffic and in how often the thread
/// pool is woken.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StageLayout {
    /// Each stage runs over every robot before the next stage
    /// starts: one parallel pass per stage. A herd larger than the cache is
    /// read from memory once per stage.
    StageMajor,
    /// The per-robot stages run block by block, in stage order inside each
    /// block of up to `robots` consecutive robots: one parallel pass per
    /// step, and a block's data stays in the core's cache from one stage to
    /// the next.
    RobotBlocks {
        /// Robots per block (≥ 1; rounded up to whole lane groups).
        robots: usize,
    },
}

/// Robots per block by default: one lane group (one robot whose legs run in
/// lanes, else four robots in lanes across robots). A pass takes a block
/// through up to 256 steps, so one robot's data (about 63 KiB, less of it
/// touched in a step) stays in the core's L1 and L2 through them; blocks of
/// eight (about 0.5 MiB, in L2 only) were 2.5 % slower at 256 robots on one
/// thread (paired runs, `quadsim bench --block-robots 1` vs `8`).
pub const DEFAULT_BLOCK_ROBOTS: usize = 1;

impl Default for StageLayout {
    /// Blocks of [`DEFAULT_BLOCK_ROBOTS`].
    fn default() -> Self {
        Self::RobotBlocks {
            robots: DEFAULT_BLOCK_ROBOTS,
        }
    }
}

/// The packed, authoritative simulation state of one robot.
#[derive(Debug)]
pub struct RobotSim {
    /// The robot's root entity.
    pub entity: Entity,
    /// The compiled articulation (shared, immutable; replaced on recompile).
    pub model: Arc<Model>,
    /// Kinematics/dynamics workspace; after a step it holds the last
    /// derivative evaluation, not the new state.
    pub data: Data,
    /// Generalised position and velocity (Pinocchio conventions, nq and nv).
    pub state: State,
    /// Actuator torque command (N·m or N, nv; base entries normally zero),
    /// written by the `Control` stage and saturated inside the step.
    pub tau_actuator: Vec<f64>,
    /// Integrator buffers and the passive joint model.
    pub workspace: StepWorkspace,
    /// Ground contacts and pushes, evaluated inside the integrator (see [`ContactForces`]).
    pub contact: ContactForces,
    /// Controller, observation, fall criteria and metrics.
    pub run: RobotRun,
    /// Link entity of each frame of the model (frame `i` ↔ `link_entities[i]`).
    pub link_entities: Vec<Entity>,
    /// Sensors, estimator and sensed state (`None`: the controller reads ground truth).
    pub sensing: Option<Box<crate::RobotSensing>>,
    /// Debug counter: the pool worker (`rayon::current_thread_index`) that ran
    /// this robot's last step, `None` before the first.
    pub last_worker: Option<usize>,
    /// What the controller sees when the robot carries compliant payloads
    /// (`model.load_nv > 0`): the robot with its loads frozen at rest;
    /// `None` otherwise (the controller reads `model` and `data`).
    pub control: Option<ControlView>,
}

/// The controller's view of a robot that carries compliant payloads: the
/// model with each load frozen at its rest offset (its sprung joints made
/// fixed, so the load is a rigid payload), whose q and v are the actuated
/// prefix of the robot's (`Model::actuated_nq`, `Model::actuated_nv`) and
/// whose bodies are the robot's first ones. A controller measures no load
/// coordinate and commands no load joint (they have no actuator).
#[derive(Debug)]
pub struct ControlView {
    /// The frozen model.
    pub model: Arc<Model>,
    /// Its workspace.
    pub data: Data,
}

impl ControlView {
    /// The view of `model` (with `desc` it was compiled from), or `None`
    /// without compliant payloads.
    pub fn of(
        desc: &quadsim_engine::description::RobotDescription,
        model: &Model,
        base: quadsim_engine::BaseKind,
    ) -> Option<Self> {
        if model.load_nv == 0 {
            return None;
        }
        let mut frozen = desc.clone();
        for j in &mut frozen.joints {
            if j.spring.take().is_some() {
                j.kind = quadsim_engine::description::JointKind::Fixed;
            }
        }
        let mut m = Model::from_description(&frozen, base).ok()?;
        m.gravity = model.gravity;
        debug_assert_eq!(m.nv, model.actuated_nv());
        Some(Self {
            data: Data::new(&m),
            model: Arc::new(m),
        })
    }
}

impl RobotSim {
    /// A robot at the model's neutral configuration, at rest, with no actuator torque.
    pub fn new(
        entity: Entity,
        model: Arc<Model>,
        link_entities: Vec<Entity>,
        passive: PassiveParams,
    ) -> Self {
        let mut workspace = StepWorkspace::new(&model);
        workspace.passive = passive;
        Self {
            entity,
            data: Data::new(&model),
            state: State::neutral(&model),
            tau_actuator: vec![0.0; model.nv],
            workspace,
            contact: ContactForces::default(),
            run: RobotRun::default(),
            link_entities,
            sensing: None,
            last_worker: None,
            control: None,
            model,
        }
    }
}

/// Every compiled robot's simulation state, contiguous so the step can sweep
/// them in parallel without locks. Indexed by [`RobotIndex`].
#[derive(Resource, Debug, Default)]
pub struct RobotBatch {
    /// One entry per compiled robot.
    pub sims: Vec<RobotSim>,
}

impl RobotBatch {
    /// The robot in slot `index`.
    pub fn get(&self, index: RobotIndex) -> Option<&RobotSim> {
        self.sims.get(index.0)
    }

    /// The robot in slot `index`, mutably.
    pub fn get_mut(&mut self, index: RobotIndex) -> Option<&mut RobotSim> {
        self.sims.get_mut(index.0)
    }
}

/// When link poses are copied back to the [`crate::LinkPose`] components.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoseSync {
    /// Copy after every `every_steps`-th step (0: only on request).
    pub every_steps: u64,
    /// Copy after the next step regardless of the rate; cleared when done.
    pub requested: bool,
}

impl Default for PoseSync {
    /// After every step.
    fn default() -> Self {
        Self {
            every_steps: 1,
            requested: false,
        }
    }
}

impl PoseSync {
    /// True when poses are due after step number `step` (1-based, as in [`SimClock::step`]).
    pub fn due(&self, step: u64) -> bool {
        self.requested || (self.every_steps > 0 && step.is_multiple_of(self.every_steps))
    }
}
