//! Proof that the hot path allocates nothing once `Data` and `StepWorkspace`
//! exist: a counting global allocator records every allocation made by the
//! measuring thread while the algorithms and both integrators run, with a
//! force model that adds point forces and generalised forces at every stage.

mod common;

use glam::DVec3;
use quadsim_engine::aba::aba;
use quadsim_engine::com::{center_of_mass, momentum_about_com};
use quadsim_engine::crba::crba;
use quadsim_engine::energy::{kinetic_energy, potential_energy};
use quadsim_engine::integrate::{ForceModel, Integrator, State, StepWorkspace, integrate_q, step};
use quadsim_engine::jacobian::{add_point_force_jt, point_jacobian};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::BaseKind;
use quadsim_engine::nle::{generalized_gravity, nonlinear_effects};
use quadsim_engine::rnea::rnea;
use quadsim_engine::{Data, Model};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations_in;

/// A penalty ground under every body origin (through `data.f_ext`) plus a
/// joint-space push on the last body's origin (through `Jᵀ f` into `tau`):
/// state-dependent, evaluated at every stage, like a contact model.
struct Ground {
    height_m: f64,
    stiffness_n_per_m: f64,
    damping_ns_per_m: f64,
    /// Point forces applied so far (proves the model acted).
    contacts: usize,
}

impl ForceModel for Ground {
    fn apply(&mut self, model: &Model, data: &mut Data, _q: &[f64], _v: &[f64], tau: &mut [f64]) {
        for b in 0..model.nbodies {
            let p = data.body_point_world(b, DVec3::ZERO);
            if p.z < self.height_m {
                let vel = data.body_point_velocity(b, DVec3::ZERO);
                let fz = (self.stiffness_n_per_m * (self.height_m - p.z)
                    - self.damping_ns_per_m * vel.z)
                    .max(0.0);
                data.add_point_force(b, p, DVec3::new(-0.1 * vel.x, -0.1 * vel.y, fz));
                self.contacts += 1;
            }
        }
        let last = model.nbodies - 1;
        let p = data.body_point_world(last, DVec3::ZERO);
        add_point_force_jt(model, data, last, p, DVec3::new(1.0, -2.0, 0.5), tau);
    }
}

fn assert_no_allocation(model: &Model) {
    let mut data = Data::new(model);
    let mut ws = StepWorkspace::new(model);
    let (q, v) = common::random_state(model, 3, 2.0, 1.0);
    let mut state = State { q, v };
    // Start low so the ground acts.
    if model.is_floating() {
        state.q[2] = 0.05;
    }
    let tau = common::random_vec(4, model.nv, 2.0);
    let a = common::random_vec(5, model.nv, 2.0);
    let mut q_out = vec![0.0; model.nq];
    let mut ground = Ground {
        // a fixed base sits at the origin: raise the ground so that it acts
        height_m: if model.is_floating() { 0.0 } else { 1.0 },
        stiffness_n_per_m: 1e4,
        damping_ns_per_m: 100.0,
        contacts: 0,
    };
    let mut sink = 0.0;
    let n = allocations_in(|| {
        for _ in 0..10 {
            sink += aba(model, &mut data, &state.q, &state.v, &tau)[0];
            sink += rnea(model, &mut data, &state.q, &state.v, &a)[0];
            sink += crba(model, &mut data, &state.q)[0];
            sink += nonlinear_effects(model, &mut data, &state.q, &state.v)[0];
            sink += generalized_gravity(model, &mut data, &state.q)[0];
            forward_kinematics(model, &mut data, &state.q, &state.v);
            let p = data.body_point_world(model.nbodies - 1, DVec3::X);
            sink += point_jacobian(model, &mut data, model.nbodies - 1, p)[0];
            sink += center_of_mass(model, &data).z + momentum_about_com(model, &data).1.x;
            sink += kinetic_energy(model, &data, &state.v) + potential_energy(model, &data);
            integrate_q(model, &state.q, &state.v, 1e-3, &mut q_out);
            for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
                step(
                    model,
                    &mut data,
                    &mut ws,
                    &mut state,
                    &tau,
                    5e-4,
                    integrator,
                    &mut ground,
                );
            }
        }
    });
    assert!(sink.is_finite() && state.q.iter().all(|x| x.is_finite()));
    assert!(ground.contacts > 0, "the force model never acted");
    assert_eq!(n, 0, "{}: {n} allocations on the hot path", model.name);
}

#[test]
fn counter_sees_allocations() {
    // The instrument works: a Vec allocates once.
    let n = allocations_in(|| {
        std::hint::black_box(vec![1.0f64; 8]);
    });
    assert_eq!(n, 1);
}

#[test]
fn hot_path_does_not_allocate_floating_random_tree() {
    assert_no_allocation(&common::model(
        &common::random_tree(17, 12),
        BaseKind::Floating,
    ));
}

#[test]
fn hot_path_does_not_allocate_fixed_random_tree() {
    assert_no_allocation(&common::model(&common::random_tree(18, 6), BaseKind::Fixed));
}

#[test]
fn hot_path_does_not_allocate_quad16() {
    let d = quadsim_engine::robots::builtin("quad16").expect("built-in quad16");
    assert_no_allocation(&common::model(&d, BaseKind::Floating));
}
