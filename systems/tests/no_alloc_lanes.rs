//! A steady-state step with robots of one model, stepped four at a time in
//! SIMD lanes, allocates nothing of its own: each worker's lane workspace is
//! made once, then reused. (Its own test binary: the counting allocator
//! counts every thread of the process, so it cannot run beside
//! `no_alloc.rs`'s test.) rayon's job queues allocate a block every 63
//! jobs, as explained in `no_alloc.rs`: about 0.13 per step here.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use std::alloc::System;

use quadsim_components::{LaneBatching, SimConfig};
use quadsim_engine::integrate::State;
use quadsim_systems::Simulation;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// 30 quad16 in random states on two threads: groups of 4, …, 4, 2.
#[test]
fn steady_state_steps_in_lanes_do_not_allocate() {
    let mut sim = Simulation::new(SimConfig::default(), 2).unwrap();
    // quad16 steps alone (its legs in lanes) unless told otherwise
    sim.world.insert_resource(LaneBatching::AcrossRobots);
    let quad16 = quadsim_engine::robots::builtin("quad16").unwrap();
    for seed in 0..30 {
        let mut d = quad16.clone();
        d.name = format!("q{seed}");
        let root = sim.spawn_robot(&d).unwrap();
        let r = sim.robot_mut(root).unwrap();
        let (q, v) = common::random_state(&r.model, seed, 1.0, 0.5);
        r.state = State { q, v };
    }
    let mut ends = Vec::new();
    let batch = sim.world.resource::<quadsim_components::RobotBatch>();
    quadsim_systems::plan_groups(&batch.sims, LaneBatching::AcrossRobots, &mut ends);
    assert_eq!(ends.len(), 8, "groups of 4, 4, …, 2: {ends:?}");
    sim.run(20);
    let steps = 1000;
    let region = Region::new(GLOBAL);
    sim.run(steps);
    let stats = region.change();
    let per_step = (stats.allocations + stats.reallocations) as f64 / steps as f64;
    println!("lanes, 2 threads: {per_step} allocations per step");
    // Measured 0.13 with the lanes on and off alike (rayon's queue blocks):
    // anything per robot or per step would be ≥ 1.
    assert!(per_step < 0.5, "{per_step} allocations per step");
}
