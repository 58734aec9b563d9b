//! One whole-world step (gait, control, contact, dynamics, integration) of
//! 1, 64 and 1,000 quad16 trotting under VMC, on the default thread pool
//! (one worker per core). `quadsim bench` measures the same worlds by thread
//! count, with memory per robot. Run with
//! `cargo bench -p quadsim --bench herd_step`.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use quadsim::cli::bench::herd_scenario;
use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, build_world};

fn herd_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("herd_step");
    g.sample_size(10);
    for n in [1usize, 64, 1000] {
        let src = herd_scenario("quad16", n).expect("scenario");
        let scn = parse_scenario(Path::new("bench.toml"), src).expect("parses");
        let mut w = build_world(&scn, Overrides::default()).expect("builds");
        w.sim.run(200); // settle and start trotting
        g.bench_function(format!("{n}_robots"), |b| b.iter(|| w.sim.run(1)));
    }
    g.finish();
}

criterion_group!(benches, herd_step);
criterion_main!(benches);
