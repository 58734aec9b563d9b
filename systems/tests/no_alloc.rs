//! A steady-state step allocates nothing of its own: the compile check, the
//! parallel integration of every robot, the clock and the pose copy all run on
//! preallocated memory. Measured with a counting global allocator (this test
//! binary only). The one allocation left is rayon's job-injection queue, which
//! takes a new block of 63 slots every 63 jobs sent into the pool (five per
//! step: control, contact, integration, metrics and pose copy), so about one
//! per 13 steps (5/63 ≈ 0.079); anything per robot or per step would show up
//! as ≥ 1 per step. Without the pose copy, `Simulation::run` takes the
//! robots through many steps per pass, and those passes allocate nothing
//! either.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use std::alloc::System;

use quadsim_components::{PoseSync, SimConfig};
use quadsim_engine::integrate::{Integrator, State};
use quadsim_systems::Simulation;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

#[test]
fn steady_state_steps_do_not_allocate() {
    for (threads, integrator, poses) in [
        (1, Integrator::SemiImplicitEuler, true),
        (2, Integrator::Rk4, true),
        (2, Integrator::SemiImplicitEuler, false),
    ] {
        let config = SimConfig {
            integrator,
            ..SimConfig::default()
        };
        let mut sim = Simulation::new(config, threads).unwrap();
        for seed in 0..32 {
            let root = sim.spawn_robot(&common::random_tree(seed, 8)).unwrap();
            let r = sim.robot_mut(root).unwrap();
            let (q, v) = common::random_state(&r.model, seed, 1.0, 0.5);
            r.state = State { q, v };
        }
        if !poses {
            sim.world.insert_resource(PoseSync {
                every_steps: 0,
                requested: false,
            });
        }
        sim.run(20); // schedules built, pools warm
        let steps = 1000;
        let passes = sim.passes();
        let region = Region::new(GLOBAL);
        sim.run(steps);
        let stats = region.change();
        let passes = sim.passes() - passes;
        assert_eq!(passes < steps, !poses, "{passes} passes");
        let per_step = (stats.allocations + stats.reallocations) as f64 / steps as f64;
        println!("{threads} threads, {integrator:?}: {per_step} allocations per step");
        assert!(per_step < 0.1, "{per_step} allocations per step");
    }
}
