//! Criterion benchmarks of the core algorithms and one full integration step
//! on the built-in quad16 (floating base, 16 joints, nv = 22) at a seeded
//! random state. Run with `cargo bench -p quadsim-engine --bench dynamics`.
//!
//! Target on the reference machine: ABA ≤ 1.5 µs per call (Pinocchio's
//! compiled ABA takes 5.4 µs there).

use criterion::{Criterion, criterion_group, criterion_main};
use quadsim_engine::aba::aba;
use quadsim_engine::crba::crba;
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::BaseKind;
use quadsim_engine::rnea::rnea;
use quadsim_engine::{Data, Model};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

/// quad16 with a random state (unit quaternion, |q̇| ≤ 2 rad/s, base ≤ 1 m/s,
/// 1 rad/s), random torques and accelerations.
fn setup() -> (Model, State, Vec<f64>, Vec<f64>) {
    let desc = quadsim_engine::robots::builtin("quad16").expect("built-in quad16");
    let model = Model::from_description(&desc, BaseKind::Floating).expect("quad16 compiles");
    let mut r = ChaCha8Rng::seed_from_u64(42);
    let (q, v, tau) = quadsim_engine::robots::benchmark_state(&model, &mut r);
    let a: Vec<f64> = (0..model.nv).map(|_| r.random_range(-3.0..3.0)).collect();
    (model, State { q, v }, tau, a)
}

fn algorithms(c: &mut Criterion) {
    let (model, s, tau, a) = setup();
    let mut data = Data::new(&model);
    let mut g = c.benchmark_group("quad16");
    g.bench_function("forward_kinematics", |b| {
        b.iter(|| {
            // measure the whole algorithm, not forward kinematics' cache of a repeated state
            data.invalidate_kinematics();
            forward_kinematics(&model, &mut data, black_box(&s.q), black_box(&s.v));
            data.vel[1].lin.x
        })
    });
    g.bench_function("aba", |b| {
        b.iter(|| {
            // measure the whole algorithm, not forward kinematics' cache of a repeated state
            data.invalidate_kinematics();
            aba(
                &model,
                &mut data,
                black_box(&s.q),
                black_box(&s.v),
                black_box(&tau),
            )[0]
        })
    });
    g.bench_function("rnea", |b| {
        b.iter(|| {
            // measure the whole algorithm, not forward kinematics' cache of a repeated state
            data.invalidate_kinematics();
            rnea(
                &model,
                &mut data,
                black_box(&s.q),
                black_box(&s.v),
                black_box(&a),
            )[0]
        })
    });
    g.bench_function("crba", |b| {
        b.iter(|| {
            data.invalidate_kinematics();
            crba(&model, &mut data, black_box(&s.q))[0]
        })
    });
    for (name, integrator) in [
        ("step_semi_implicit_euler", Integrator::SemiImplicitEuler),
        ("step_rk4", Integrator::Rk4),
    ] {
        let mut ws = StepWorkspace::new(&model);
        let mut state = s.clone();
        g.bench_function(name, |b| {
            b.iter(|| {
                // measure the whole algorithm, not forward kinematics' cache of a repeated state
                data.invalidate_kinematics();
                // Restart from the same state so every iteration does the same work.
                state.q.copy_from_slice(&s.q);
                state.v.copy_from_slice(&s.v);
                step(
                    &model,
                    &mut data,
                    &mut ws,
                    &mut state,
                    black_box(&tau),
                    5e-4,
                    integrator,
                    &mut (),
                );
                state.v[0]
            })
        });
    }
    g.finish();
}

criterion_group!(benches, algorithms);
criterion_main!(benches);
