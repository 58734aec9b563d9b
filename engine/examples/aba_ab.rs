//! A/B timing of ABA on quad16 that holds up on a loaded machine: the
//! legs-in-lanes path and the general path (the same model with
//! `Plan::Scalar`) in alternating batches of calls in one process,
//! each side's time the minimum (and 10th percentile) over the batches,
//! so time slices lost to other processes drop out. Also checks that both
//! give the same bits. `cargo run --release -p quadsim-engine --example aba_ab`
use quadsim_engine::dispatch::aba;
use quadsim_engine::model::BaseKind;
use quadsim_engine::{Data, Model};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let desc = quadsim_engine::robots::builtin("quad16").expect("built-in quad16");
    let fast = Model::from_description(&desc, BaseKind::Floating).expect("quad16 compiles");
    assert!(fast.leg_lanes().is_some(), "quad16 has four legs in lanes");
    let mut general = fast.clone();
    general.plan = quadsim_engine::plan::Plan::Scalar;
    // the benchmark's state (engine/benches/dynamics.rs)
    let mut r = ChaCha8Rng::seed_from_u64(42);
    let (q, v, tau) = quadsim_engine::robots::benchmark_state(&fast, &mut r);
    let mut df = Data::new(&fast);
    let mut dg = Data::new(&general);
    let a = aba(&fast, &mut df, &q, &v, &tau).to_vec();
    let b = aba(&general, &mut dg, &q, &v, &tau).to_vec();
    assert!(
        a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
        "bits differ"
    );
    let batches: usize = std::env::args().nth(1).map_or(400, |s| s.parse().unwrap());
    let per = 200;
    let mut tf = Vec::new();
    let mut tg = Vec::new();
    for _ in 0..batches {
        for (m, d, t) in [(&fast, &mut df, &mut tf), (&general, &mut dg, &mut tg)] {
            let t0 = Instant::now();
            for _ in 0..per {
                d.invalidate_kinematics();
                black_box(aba(m, d, black_box(&q), black_box(&v), black_box(&tau))[0]);
            }
            t.push(t0.elapsed().as_secs_f64() * 1e6 / per as f64);
        }
    }
    for t in [&mut tf, &mut tg] {
        t.sort_by(|a, b| a.total_cmp(b));
    }
    let p = |t: &Vec<f64>, f: f64| t[((t.len() - 1) as f64 * f) as usize];
    println!(
        "legs in lanes: min {:.3} µs p10 {:.3} median {:.3}",
        tf[0],
        p(&tf, 0.1),
        p(&tf, 0.5)
    );
    println!(
        "general path:  min {:.3} µs p10 {:.3} median {:.3}",
        tg[0],
        p(&tg, 0.1),
        p(&tg, 0.5)
    );
    println!(
        "ratio (min) {:.3}  (p10) {:.3}",
        tf[0] / tg[0],
        p(&tf, 0.1) / p(&tg, 0.1)
    );
}
