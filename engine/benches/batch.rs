//! Scalar against batched ABA on quad16, per robot, in one criterion run so
//! that the ratios compare like with like on a loaded machine. Run with
//! `cargo bench -p quadsim-engine --bench batch`.
//!
//! Every benchmark handles `ROBOTS` = 8 distinct random robots per iteration
//! (criterion reports the time per robot through its throughput):
//! - `scalar_aba`: [`aba`] on each robot (kinematics cache invalidated);
//! - `batch4_aba` / `batch8_aba`: [`aba_batch`] on 2 batches of 4 or 1 of 8,
//!   runtime-dispatched (AVX2 where the CPU has it), including the copies of
//!   `q`, `v`, `tau` into the lanes and of `ddq` out of them;
//! - `batch4_aba_generic`: the same as `batch4_aba` compiled for the build's
//!   generic target only ([`aba_batch_generic`]).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use quadsim_engine::aba::aba;
use quadsim_engine::batch::{BatchData, aba_batch, aba_batch_generic};
use quadsim_engine::model::BaseKind;
use quadsim_engine::{Data, Model};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

const ROBOTS: usize = 8;

/// Robot inputs `(q, v, tau)`: random unit quaternion, joints ±1.5 rad,
/// |q̇| ≤ 2 rad/s, base ≤ 1 m/s and 1 rad/s, torques ≤ 10 N·m.
type Inputs = (Vec<f64>, Vec<f64>, Vec<f64>);

fn setup() -> (Model, Vec<Inputs>) {
    let desc = quadsim_engine::robots::builtin("quad16").expect("built-in quad16");
    let model = Model::from_description(&desc, BaseKind::Floating).expect("quad16 compiles");
    let mut r = ChaCha8Rng::seed_from_u64(42);
    let robots = (0..ROBOTS)
        .map(|_| quadsim_engine::robots::benchmark_state(&model, &mut r))
        .collect();
    (model, robots)
}

/// Runs `robots` through a batch of `L` lanes, chunk by chunk; `generic`
/// selects the generic-target version.
fn run_batched<const L: usize>(
    model: &Model,
    bd: &mut BatchData<L>,
    robots: &[Inputs],
    ddq: &mut [f64],
    generic: bool,
) -> f64 {
    let mut sink = 0.0;
    for chunk in robots.chunks(L) {
        for (k, (q, v, tau)) in chunk.iter().enumerate() {
            bd.set_robot(k, black_box(q), black_box(v), black_box(tau));
        }
        bd.set_active(chunk.len());
        if generic {
            aba_batch_generic(model, bd, false);
        } else {
            aba_batch(model, bd, false);
        }
        for k in 0..chunk.len() {
            bd.ddq_of(k, ddq);
            sink += ddq[0];
        }
    }
    sink
}

fn batch(c: &mut Criterion) {
    let (model, robots) = setup();
    let mut g = c.benchmark_group("quad16_per_robot");
    g.throughput(Throughput::Elements(ROBOTS as u64));
    let mut data = Data::new(&model);
    g.bench_function("scalar_aba", |b| {
        b.iter(|| {
            let mut sink = 0.0;
            for (q, v, tau) in &robots {
                // the whole algorithm, not the kinematics cache of a repeated state
                data.invalidate_kinematics();
                sink += aba(
                    &model,
                    &mut data,
                    black_box(q),
                    black_box(v),
                    black_box(tau),
                )[0];
            }
            sink
        })
    });
    let mut ddq = vec![0.0; model.nv];
    let mut bd4 = BatchData::<4>::new(&model);
    g.bench_function("batch4_aba", |b| {
        b.iter(|| run_batched(&model, &mut bd4, &robots, &mut ddq, false))
    });
    g.bench_function("batch4_aba_generic", |b| {
        b.iter(|| run_batched(&model, &mut bd4, &robots, &mut ddq, true))
    });
    let mut bd8 = BatchData::<8>::new(&model);
    g.bench_function("batch8_aba", |b| {
        b.iter(|| run_batched(&model, &mut bd8, &robots, &mut ddq, false))
    });
    g.finish();
}

criterion_group!(benches, batch);
criterion_main!(benches);
