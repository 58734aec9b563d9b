//! Per-worker workspaces, owned by the system that steps the robots and
//! passed explicitly down to the stages that use them (the pattern of
//! rapier's pipeline, which owns its solver's buffers), instead of
//! thread-local statics.

use std::sync::Mutex;

use quadsim_engine::SpareData;
use quadsim_engine::batch::{BatchData, LANES};

/// One worker's scratch for the robot pass: what the stages need beside a
/// robot's own data and hold nothing a result depends on from one use to
/// the next, kept so that nothing is allocated once every model size has
/// been met.
#[derive(Debug)]
pub struct WorkerWorkspace {
    /// The `Integrate` stage's lane workspaces (robots in SIMD lanes), one
    /// per model size met (sizes are all a [`BatchData`] depends on).
    pub(crate) lanes: Vec<BatchData<LANES>>,
    /// The `Control` stage's spare `Data` for a controller at the estimated
    /// state.
    pub(crate) spare_data: SpareData,
    /// The `Sense` stage's kinematics-only spare for the base estimator's
    /// leg kinematics (a robot whose legs do not run in lanes).
    pub(crate) spare_kinematics: SpareData,
}

impl Default for WorkerWorkspace {
    fn default() -> Self {
        Self {
            lanes: Vec::new(),
            spare_data: SpareData::default(),
            spare_kinematics: SpareData::kinematics_only(),
        }
    }
}

impl WorkerWorkspace {
    /// The lane workspace for robots of `model`'s size, made at the first
    /// robot of that size.
    pub(crate) fn lanes_for(&mut self, model: &quadsim_engine::Model) -> &mut BatchData<LANES> {
        let fits = |bd: &BatchData<LANES>| {
            bd.q.len() == model.nq && bd.v.len() == model.nv && bd.pose.len() == model.nbodies
        };
        let k = match self.lanes.iter().position(fits) {
            Some(k) => k,
            None => {
                self.lanes.push(BatchData::new(model));
                self.lanes.len() - 1
            }
        };
        &mut self.lanes[k]
    }
}

/// A [`WorkerWorkspace`] per worker of the thread pool that steps the
/// robots, and one for a thread outside it: held by the system that runs
/// the robot pass (a `Local`) and lent to the worker that runs a block of
/// robots, by the worker's index in the pool. Each worker only ever takes
/// its own, so the locks are never contended (the slot of threads outside
/// the pool may be shared, and its lock then serialises them).
#[derive(Debug, Default)]
pub struct WorkerWorkspaces {
    slots: Vec<Slot>,
}

/// One worker's workspace behind its lock, alone in its cache lines: two
/// workers' locks in one line would bounce it between their cores at
/// every block (false sharing; 128 bytes, as crossbeam's `CachePadded`
/// on x86-64, whose prefetcher pulls lines in pairs).
#[derive(Debug, Default)]
#[repr(align(128))]
struct Slot(Mutex<WorkerWorkspace>);

impl WorkerWorkspaces {
    /// One workspace per worker of a pool of `workers` threads, and one for
    /// a thread outside it (kept when already so many).
    pub fn fit(&mut self, workers: usize) {
        if self.slots.len() != workers + 1 {
            self.slots = (0..=workers).map(|_| Slot::default()).collect();
        }
    }

    /// Runs `f` on the calling worker's workspace.
    ///
    /// # Panics
    /// Before [`Self::fit`].
    pub fn with<R>(&self, f: impl FnOnce(&mut WorkerWorkspace) -> R) -> R {
        let outside = self.slots.len() - 1;
        let i = rayon::current_thread_index().map_or(outside, |i| i.min(outside));
        let mut ws = self.slots[i].0.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut ws)
    }
}
