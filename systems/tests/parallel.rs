//! Robots stepped in parallel on the world's pool: the work really is spread
//! over the workers, and the result is bit-identical whatever their number —
//! and to the engine stepped directly, without the ECS.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use std::collections::BTreeSet;

use bevy_ecs::prelude::*;
use quadsim_components::{ContactForces, SimConfig};
use quadsim_engine::integrate::{self, Integrator, State, StepWorkspace};
use quadsim_engine::{BaseKind, Data, Model};
use quadsim_systems::Simulation;

/// `count` floating random trees (`shapes` different models) in random states.
fn spawn_fleet(sim: &mut Simulation, count: u64, shapes: u64, links: usize) -> Vec<Entity> {
    (0..count)
        .map(|i| {
            let root = sim
                .spawn_robot(&common::random_tree(i % shapes, links))
                .unwrap();
            let r = sim.robot_mut(root).unwrap();
            let (q, v) = common::random_state(&r.model, 1000 + i, 2.0, 1.0);
            r.state = State { q, v };
            root
        })
        .collect()
}

#[test]
fn both_workers_step_robots() {
    let config = SimConfig {
        integrator: Integrator::Rk4,
        ..SimConfig::default()
    };
    let mut sim = Simulation::new(config, 2).unwrap();
    let roots = spawn_fleet(&mut sim, 64, 8, 12);
    let mut workers = BTreeSet::new();
    // Rayon steals work: on a loaded machine the second worker can stay
    // asleep for a few steps while the first clears the whole batch, so the
    // test steps until both have worked (normally the first step), with a
    // cap far beyond any scheduling delay.
    for _ in 0..5000 {
        sim.step();
        for &r in &roots {
            let w = sim.robot(r).unwrap().last_worker;
            assert!(matches!(w, Some(0 | 1)), "stepped outside the pool: {w:?}");
            workers.insert(w);
        }
        if workers.len() == 2 {
            break;
        }
    }
    assert_eq!(workers, BTreeSet::from([Some(0), Some(1)]));
}

/// The fleet's `(q, v)` after `steps` steps on `threads` workers, as bits.
fn fleet_bits(threads: usize, integrator: Integrator, steps: u64) -> Vec<u64> {
    let config = SimConfig {
        integrator,
        ..SimConfig::default()
    };
    let mut sim = Simulation::new(config, threads).unwrap();
    let roots = spawn_fleet(&mut sim, 16, 4, 8);
    sim.run(steps);
    roots
        .iter()
        .flat_map(|&r| {
            let s = &sim.robot(r).unwrap().state;
            s.q.iter()
                .chain(&s.v)
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The same fleet stepped by calling the engine directly, one robot after the other.
fn engine_bits(integrator: Integrator, steps: u64) -> Vec<u64> {
    let config = SimConfig::default();
    let mut out = Vec::new();
    for i in 0..16 {
        let model =
            Model::from_description(&common::random_tree(i % 4, 8), BaseKind::Floating).unwrap();
        let (q, v) = common::random_state(&model, 1000 + i, 2.0, 1.0);
        let mut state = State { q, v };
        let mut data = Data::new(&model);
        let mut ws = StepWorkspace::new(&model);
        ws.passive = config.passive;
        let tau = vec![0.0; model.nv];
        for _ in 0..steps {
            integrate::step(
                &model,
                &mut data,
                &mut ws,
                &mut state,
                &tau,
                config.dt_s,
                integrator,
                &mut ContactForces::default(),
            );
        }
        out.extend(state.q.iter().chain(&state.v).map(|x| x.to_bits()));
    }
    out
}

#[test]
fn results_are_bit_identical_for_any_thread_count() {
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        let one = fleet_bits(1, integrator, 200);
        assert_eq!(
            one,
            fleet_bits(2, integrator, 200),
            "{integrator:?}, 2 threads"
        );
        assert_eq!(
            one,
            fleet_bits(4, integrator, 200),
            "{integrator:?}, 4 threads"
        );
        assert_eq!(
            one,
            engine_bits(integrator, 200),
            "{integrator:?}, engine alone"
        );
        // the robots did move: free fall from random states
        assert_ne!(one, fleet_bits(1, integrator, 0));
    }
}
