//! Cost of the run log (docs/logs.md, "Cost") for one quad16 trotting
//! (`scenarios/trot.toml`: dt 0.5 ms, log at the controller rate, 500 Hz).
//! Each iteration steps the world 400 steps (0.2 s simulated, 100 samples):
//!
//! - `no_log`: the simulation alone;
//! - `sampling`: with the logger sampling into a sink that drops the
//!   records (what the simulation thread itself does for the log);
//! - `mcap`: with `log.mcap` written (the writer thread encodes and
//!   compresses beside the simulation; on a machine with a core free for it,
//!   this is the cost the simulation sees).
//!
//! After `mcap` the writer thread's CPU time per sample is printed (the share
//! of a core it uses). Run with `cargo bench -p quadsim --bench log_cost`.
//! Wall times on a shared machine are noisy: docs/logs.md also gives
//! instruction counts (callgrind), which are not.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use quadsim::log::{RunOutcome, start_run_log};
use quadsim::scenario::parse_scenario;
use quadsim::systems::{LogChannel, LogRecord, LogSink};
use quadsim::world::{Overrides, World, build_world};

const STEPS: u64 = 400;

fn world() -> World {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/trot.toml");
    let src = std::fs::read_to_string(&path).expect("scenarios/trot.toml");
    let scn = parse_scenario(&path, src).expect("parses");
    let mut w = build_world(&scn, Overrides::default()).expect("builds");
    w.sim.run(200); // settle and start trotting
    w
}

/// Drops every record.
struct Discard;
impl LogSink for Discard {
    fn send(&mut self, record: LogRecord) {
        std::hint::black_box(record);
    }
}

fn log_cost(c: &mut Criterion) {
    let mut g = c.benchmark_group("log_cost");
    g.sample_size(20);
    let mut w = world();
    g.bench_function("no_log", |b| b.iter(|| w.sim.run(STEPS)));

    let mut w = world();
    let robots: Vec<_> = w.robots.iter().map(|(_, e)| (*e, true)).collect();
    quadsim::systems::start_sampling::<LogChannel>(&mut w.sim.world, Box::new(Discard), 4, &robots);
    g.bench_function("sampling", |b| b.iter(|| w.sim.run(STEPS)));
    drop(quadsim::systems::finish_sampling::<LogChannel>(
        &mut w.sim.world,
        false,
    ));

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/trot.toml");
    let scn = parse_scenario(&path, std::fs::read_to_string(&path).unwrap()).unwrap();
    let mut w = world();
    let dir = std::env::temp_dir().join(format!("quadsim-log-cost-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = start_run_log(&scn, &mut w, &dir.join("log.mcap"), 4).expect("log");
    let start_step = w.sim.clock().step;
    g.bench_function("mcap", |b| b.iter(|| w.sim.run(STEPS)));
    let samples = (w.sim.clock().step - start_step) / 4;
    let stats = log.finish(&mut w, &RunOutcome::default()).expect("finish");
    if let Some(cpu) = stats.cpu_s {
        eprintln!(
            "log_cost/mcap: {samples} samples, writer thread {:.3} s CPU, {:.2} µs per sample, {:.0} B per sample",
            cpu,
            cpu * 1e6 / samples as f64,
            stats.file_bytes as f64 / samples as f64
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    g.finish();
}

criterion_group!(benches, log_cost);
criterion_main!(benches);
