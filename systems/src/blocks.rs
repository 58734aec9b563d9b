//! The robot pass: a step's per-robot stages, run block by block
//! ([`StageLayout::RobotBlocks`], the default) or stage by stage
//! ([`StageLayout::StageMajor`]).
//!
//! Stage by stage, each of the five per-robot stages walks the whole herd,
//! so a herd larger than a core's cache is fetched from memory five times a
//! step, and the thread pool is woken five times. Robots do not interact,
//! so nothing requires a stage to finish for every robot before the next
//! starts: here each worker takes a block of consecutive robots (by default
//! one lane group: one robot whose legs run in lanes) through all of them,
//! in the schedule's order, while the block is in its cache.
//! Each robot meets exactly the calls, inputs and order of the stage-major
//! layout, so both layouts give the same bits
//! (`tests/batch_step.rs`).

use bevy_ecs::prelude::*;
use quadsim_components::{
    ControlRate, LaneBatching, RobotBatch, SimClock, SimConfig, SimThreadPool, StageLayout,
};

use crate::contact::observe_robot;
use crate::control::{clock_dt, control_stage, is_control_tick};
use crate::metrics::{check_divergence, record_robot};
use crate::sense::sense_robot;
use crate::step::{count_step, for_each_lane_group, lanes_on, live, plan_groups, step_group};
use crate::workspace::WorkerWorkspaces;

/// How many consecutive steps one run of the step schedule takes every robot
/// through (at least 1; absent means 1). [`Simulation::run`](crate::Simulation::run)
/// sets it for runs of steps at which nothing outside the robots looks at the
/// world (no compile due, no log or monitor sample, no pose copy, no payload
/// event, no system added to the schedule), so that each block of robots goes
/// through several steps while its data is in the core's cache; it is 1
/// between such runs.
///
/// Robots do not interact, so a robot meets the same calls with the same
/// inputs either way, and the bits are the same
/// (`tests/fused_steps.rs`).
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassSteps(u64);

impl PassSteps {
    /// One step per pass.
    pub const ONE: Self = Self(1);

    /// `steps` per pass (at least 1).
    pub(crate) fn new(steps: u64) -> Self {
        Self(steps.max(1))
    }

    /// Steps per pass.
    pub fn get(self) -> u64 {
        self.0
    }
}

/// The step's robot pass: every robot's per-robot stages of this step, in
/// the schedule's stage order, laid over the robots by [`StageLayout`] on
/// the world's thread pool; then the clock counts the step (as
/// [`advance_clock`](crate::advance_clock) does). Runs in the `Integrate`
/// set; world-level systems in the earlier sets run before it in either
/// layout, those in `Publish` after the clock has moved. With
/// [`PassSteps`] above 1 it takes every robot through that many steps
/// (each step's stages in order, block by block or stage by stage) and
/// counts them all.
///
/// - [`StageLayout::RobotBlocks`] (the default, also for a world without
///   the resource): each block of consecutive robots goes through all
///   stages while it is in the core's cache: `Sense` ([`sense_robot`]),
///   `Control` ([`control_stage`]), `Contact` ([`observe_robot`]),
///   `Integrate` (each lane group stepped, as in
///   [`step_robots`](crate::step_robots)) and the `Publish` stage's metrics
///   ([`record_robot`]) and divergence check ([`check_divergence`]).
/// - [`StageLayout::StageMajor`]: each stage walks the whole herd before
///   the next starts, one parallel pass per stage: what the standalone
///   stage systems [`sense_robots`](crate::sense_robots),
///   [`run_controllers`](crate::run_controllers),
///   [`update_contacts`](crate::update_contacts),
///   [`step_robots`](crate::step_robots) and
///   [`record_metrics`](crate::record_metrics) do, one after the other.
///
/// In both, a robot that has diverged (its first divergence recorded by
/// [`check_divergence`]) is skipped by every stage; the standalone stage
/// systems do not skip it, as [`finish_sampling`](crate::finish_sampling)
/// uses them to bring every robot's contacts and command to its current
/// state for a last sample.
///
/// Both layouts and the clock are this one system, rather than separate
/// systems behind run conditions, because the schedule's executor costs a
/// few hundred instructions per step for every system and condition it
/// holds, run or skipped (a set's condition and every skipped system's own
/// are still evaluated each step), and every system fetches its resources
/// again: on a one-robot world the five stage-major systems with their
/// set's condition, and a clock system of its own, cost about 1,500
/// instructions a step (of 42,400, under callgrind), while the robot work
/// ran in none of them.
#[allow(clippy::too_many_arguments)] // a system's parameters are its data access
pub fn step_robot_pass(
    mut batch: ResMut<RobotBatch>,
    pool: Res<SimThreadPool>,
    mut clock: ResMut<SimClock>,
    rate: Res<ControlRate>,
    config: Res<SimConfig>,
    batching: Option<Res<LaneBatching>>,
    layout: Option<Res<StageLayout>>,
    pass: Option<Res<PassSteps>>,
    mut groups: Local<Vec<usize>>,
    mut blocks: Local<Vec<usize>>,
    mut workspaces: Local<WorkerWorkspaces>,
) {
    let steps = pass.map_or(1, |p| p.get());
    let (step0, t0_s) = (clock.step, clock.time_s);
    let control_dt_s = clock_dt(&rate, &config);
    let rate = *rate;
    let (dt_s, integrator) = (config.dt_s, config.integrator);
    let saturate = config.passive.saturation;
    let lanes = lanes_on(&config, batching.as_deref());
    let sims = &mut batch.sims;
    plan_groups(sims, lanes, &mut groups);
    // each worker's workspace, lent to the worker for a block (or a robot)
    workspaces.fit(pool.threads());
    let workspaces = &*workspaces;
    match layout.as_deref().copied().unwrap_or_default() {
        StageLayout::RobotBlocks { robots } => {
            plan_blocks(&groups, robots, &mut blocks);
            pool.for_each_group(sims, &blocks, |block| {
                workspaces.with(|ws| {
                    for j in 0..steps {
                        let (t_s, tick) = step_time(step0, t0_s, j, dt_s, &rate);
                        for sim in block.iter_mut().filter(|s| live(s)) {
                            sense_robot(sim, ws, t_s);
                        }
                        for sim in block.iter_mut().filter(|s| live(s)) {
                            control_stage(sim, ws, t_s, tick, control_dt_s);
                        }
                        for sim in block.iter_mut().filter(|s| live(s)) {
                            observe_robot(sim, t_s);
                        }
                        for_each_lane_group(block, lanes, |group| {
                            step_group(group, ws, dt_s, integrator)
                        });
                        let (t_after_s, _) = step_time(step0, t0_s, j + 1, dt_s, &rate);
                        for sim in block.iter_mut().filter(|s| live(s)) {
                            record_robot(sim, dt_s, saturate);
                            check_divergence(sim, t_after_s);
                        }
                    }
                })
            });
        }
        StageLayout::StageMajor => {
            for j in 0..steps {
                let (t_s, tick) = step_time(step0, t0_s, j, dt_s, &rate);
                pool.for_each(sims, |sim| {
                    if live(sim) {
                        workspaces.with(|ws| sense_robot(sim, ws, t_s))
                    }
                });
                pool.for_each(sims, |sim| {
                    if live(sim) {
                        workspaces.with(|ws| control_stage(sim, ws, t_s, tick, control_dt_s))
                    }
                });
                pool.for_each(sims, |sim| {
                    if live(sim) {
                        observe_robot(sim, t_s)
                    }
                });
                pool.for_each_group(sims, &groups, |group| {
                    workspaces.with(|ws| step_group(group, ws, dt_s, integrator))
                });
                let (t_after_s, _) = step_time(step0, t0_s, j + 1, dt_s, &rate);
                pool.for_each(sims, |sim| {
                    if live(sim) {
                        record_robot(sim, dt_s, saturate);
                        check_divergence(sim, t_after_s);
                    }
                });
            }
        }
    }
    for _ in 0..steps {
        count_step(&mut clock, dt_s);
    }
}

/// The time (s) and controller tick of the `j`-th step of a pass that starts
/// at clock step `step0` and time `t0_s`: the clock's values had it counted
/// the `j` steps before ([`count_step`]).
fn step_time(step0: u64, t0_s: f64, j: u64, dt_s: f64, rate: &ControlRate) -> (f64, bool) {
    let step = step0 + j;
    let t_s = if j == 0 { t0_s } else { step as f64 * dt_s };
    (t_s, is_control_tick(step, rate))
}

/// Merges consecutive lane groups (exclusive `group_ends`) into blocks of at
/// most `max_robots` robots (a group larger than that is a block of its
/// own), written as exclusive `block_ends`. Blocks start and end on group
/// boundaries, so a block's groups are the herd's.
pub fn plan_blocks(group_ends: &[usize], max_robots: usize, block_ends: &mut Vec<usize>) {
    block_ends.clear();
    let (mut start, mut last) = (0, 0);
    for &end in group_ends {
        if end - start > max_robots && last > start {
            block_ends.push(last);
            start = last;
        }
        last = end;
    }
    if last > start {
        block_ends.push(last);
    }
}

#[cfg(test)]
mod tests {
    use super::plan_blocks;

    fn blocks(groups: &[usize], max: usize) -> Vec<usize> {
        let mut b = Vec::new();
        plan_blocks(groups, max, &mut b);
        b
    }

    #[test]
    fn blocks_gather_whole_groups_up_to_the_size() {
        assert_eq!(blocks(&[4, 8, 12, 13], 8), [8, 13]);
        assert_eq!(blocks(&[4, 8, 12, 13], 4), [4, 8, 12, 13]);
        assert_eq!(blocks(&[4, 8, 12, 13], 100), [13]);
        // a group larger than a block is a block of its own
        assert_eq!(blocks(&[4, 5, 9], 2), [4, 5, 9]);
        assert_eq!(blocks(&[1, 2, 3, 4, 5], 2), [2, 4, 5]);
        assert!(blocks(&[], 8).is_empty());
    }
}
