//! Criterion benchmarks of the sine and cosine of joint angles: std's
//! `f64::sin_cos` (the platform libm), `libm::sincos` (scalar, what
//! [`quadsim_engine::trig::sin_cos`] calls) and the four-lane
//! [`quadsim_engine::kernels::sin_cos_x4`] (bit for bit libm's, per lane), each
//! over the same 64 joint angles in [−π, π]. Run with
//! `cargo bench -p quadsim-engine --bench trig`.

use criterion::{Criterion, criterion_group, criterion_main};
use quadsim_engine::kernels::sin_cos_x4;
use quadsim_engine::trig::{sin_cos, sin_cos_lanes};
use std::hint::black_box;

fn angles() -> Vec<f64> {
    // deterministic, spread over a joint's range
    (0..64)
        .map(|k| std::f64::consts::PI * (((k * 37) % 64) as f64 / 32.0 - 1.0) + 1e-3 * k as f64)
        .collect()
}

fn trig(c: &mut Criterion) {
    let a = angles();
    let mut g = c.benchmark_group("sin_cos_64_angles");
    g.bench_function("std_f64_sin_cos", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &x in black_box(&a) {
                let (s, c) = x.sin_cos();
                acc += s * c;
            }
            acc
        })
    });
    g.bench_function("libm_sincos_scalar", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &x in black_box(&a) {
                let (s, c) = sin_cos(x);
                acc += s * c;
            }
            acc
        })
    });
    g.bench_function("lanes_one_at_a_time", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &x in black_box(&a) {
                let (s, c) = sin_cos_lanes([x]);
                acc += s[0] * c[0];
            }
            acc
        })
    });
    g.bench_function("x4_dispatched", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for x in black_box(&a).chunks_exact(4) {
                let (s, c) = sin_cos_x4([x[0], x[1], x[2], x[3]]);
                acc += s[0] * c[0] + s[1] * c[1] + s[2] * c[2] + s[3] * c[3];
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, trig);
criterion_main!(benches);
