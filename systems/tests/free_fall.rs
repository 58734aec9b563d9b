//! Zero-contact free fall through the whole schedule: the centre of mass
//! follows the parabola of the configured gravity, and the momentum about it
//! and the total energy are conserved.

#[path = "../../engine/tests/common/mod.rs"]
mod common;

use glam::DVec3;
use quadsim_components::SimConfig;
use quadsim_engine::com::{center_of_mass, com_velocity, momentum_about_com};
use quadsim_engine::energy::{kinetic_energy, potential_energy};
use quadsim_engine::integrate::{Integrator, State};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::{Data, Model};
use quadsim_systems::Simulation;

/// CoM position and velocity, angular momentum about the CoM and total energy.
fn invariants(model: &Model, s: &State) -> (DVec3, DVec3, DVec3, f64) {
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, &s.q, &s.v);
    let (_, l) = momentum_about_com(model, &data);
    let e = kinetic_energy(model, &data, &s.v) + potential_energy(model, &data);
    (
        center_of_mass(model, &data),
        com_velocity(model, &data),
        l,
        e,
    )
}

#[test]
fn free_fall_follows_the_configured_gravity() {
    let gravity = DVec3::new(0.3, -0.2, -3.7);
    let config = SimConfig {
        integrator: Integrator::Rk4,
        gravity,
        ..SimConfig::default()
    };
    let mut sim = Simulation::new(config, 2).unwrap();
    let roots: Vec<_> = (0..6)
        .map(|seed| {
            let root = sim.spawn_robot(&common::random_tree(seed, 6)).unwrap();
            let r = sim.robot_mut(root).unwrap();
            let (q, v) = common::random_state(&r.model, seed + 7, 1.0, 0.5);
            r.state = State { q, v };
            root
        })
        .collect();
    let start: Vec<_> = roots
        .iter()
        .map(|&r| {
            let s = sim.robot(r).unwrap();
            invariants(&s.model, &s.state)
        })
        .collect();
    sim.run(400);
    let t = sim.clock().time_s;
    assert!((t - 0.2).abs() < 1e-15);
    for (&r, &(c0, vc0, l0, e0)) in roots.iter().zip(&start) {
        let s = sim.robot(r).unwrap();
        let (c, vc, l, e) = invariants(&s.model, &s.state);
        let c_expect = c0 + vc0 * t + gravity * (0.5 * t * t);
        assert!((c - c_expect).length() < 1e-9, "CoM {c} vs {c_expect}");
        assert!((vc - (vc0 + gravity * t)).length() < 1e-9, "CoM velocity");
        assert!(
            (l - l0).length() < 1e-6 * (1.0 + l0.length()),
            "momentum {l} vs {l0}"
        );
        assert!(
            (e - e0).abs() < 1e-6 * (1.0 + e0.abs()),
            "energy {e} vs {e0}"
        );
    }
}

/// On the built-in robots with every passive effect on (damping, friction,
/// soft limits: all internal forces), the CoM still follows the parabola and
/// the momentum about it is still conserved.
#[test]
fn builtin_robots_fall_with_internal_forces() {
    let config = SimConfig {
        integrator: Integrator::Rk4,
        ..SimConfig::default()
    };
    let gravity = config.gravity;
    let mut sim = Simulation::new(config, 2).unwrap();
    let mut robots = Vec::new();
    for (k, name) in ["quad16", "quad12"].into_iter().enumerate() {
        let desc = quadsim_engine::robots::builtin(name).unwrap();
        let root = sim.spawn_robot(&desc).unwrap();
        let r = sim.robot_mut(root).unwrap();
        let (mut q, v) = common::random_state(&r.model, 40 + k as u64, 2.0, 0.5);
        // inside the joint range, where the stance and gait keep the robot
        let m = &r.model;
        for b in 1..m.nbodies {
            let iv = m.idx_v[b];
            q[m.idx_q[b]] = q[m.idx_q[b]].clamp(m.lower_limit[iv], m.upper_limit[iv]);
        }
        r.state = State { q, v };
        let start = invariants(&r.model, &r.state);
        robots.push((root, start));
    }
    sim.run(400);
    let t = sim.clock().time_s;
    for (root, (c0, vc0, l0, _)) in robots {
        let s = sim.robot(root).unwrap();
        let (c, vc, l, _) = invariants(&s.model, &s.state);
        assert!((c - (c0 + vc0 * t + gravity * (0.5 * t * t))).length() < 1e-9);
        assert!((vc - (vc0 + gravity * t)).length() < 1e-9);
        assert!(
            (l - l0).length() < 1e-6 * (1.0 + l0.length()),
            "{l} vs {l0}"
        );
    }
}
