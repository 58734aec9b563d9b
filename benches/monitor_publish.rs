//! Cost of live monitoring (docs/monitor.md). `publish_shm`: one publish tick
//! of ready samples into shared memory (loan one slice, write every robot's
//! frame, send) with one idle subscriber attached, for 1 and 256 quad16;
//! divide by the robots for the cost per robot per publish. `herd256`: one
//! controller period (4 steps) of 256 trotting quad16 without and with the
//! monitor (sampling + publishing); the difference over the period is the
//! monitor's share of step time. Run with
//! `cargo bench -p quadsim --bench monitor_publish`.

use std::path::Path;
use std::sync::{Arc, Mutex};

use criterion::{Criterion, criterion_group, criterion_main};
use quadsim::cli::bench::herd_scenario;
use quadsim::monitor::{FramePublisher, FrameReader, RunMonitor};
use quadsim::scenario::parse_scenario;
use quadsim::systems::{LogRecord, LogSink, MonitorChannel, RobotSample};
use quadsim::world::{Overrides, World, build_world};

fn world(n: usize) -> World {
    let src = herd_scenario("quad16", n).expect("scenario");
    let scn = parse_scenario(Path::new("bench.toml"), src).expect("parses");
    let mut w = build_world(&scn, Overrides::default()).expect("builds");
    w.sim.run(200); // settle and start trotting
    w
}

/// Keeps the last instant's samples.
struct Capture(Arc<Mutex<Vec<RobotSample>>>);
impl LogSink for Capture {
    fn send(&mut self, record: LogRecord) {
        if let LogRecord::Step { samples, .. } = record {
            *self.0.lock().unwrap() = samples;
        }
    }
}

fn samples(w: &mut World) -> Vec<RobotSample> {
    let got = Arc::new(Mutex::new(Vec::new()));
    let robots: Vec<_> = w.robots.iter().map(|(_, e)| (*e, true)).collect();
    quadsim::systems::start_sampling::<MonitorChannel>(
        &mut w.sim.world,
        Box::new(Capture(got.clone())),
        4,
        &robots,
    );
    w.sim.run(8);
    drop(quadsim::systems::finish_sampling::<MonitorChannel>(
        &mut w.sim.world,
        false,
    ));
    let s = got.lock().unwrap().clone();
    assert_eq!(s.len(), w.robots.len());
    s
}

fn monitor(c: &mut Criterion) {
    let pid = std::process::id();
    let mut g = c.benchmark_group("monitor");
    for n in [1usize, 256] {
        let mut w = world(n);
        let s = samples(&mut w);
        let name = format!("bench-shm-{n}-{pid}");
        let publisher = FramePublisher::create(&name, n, w.dt_s, 4, Vec::new()).expect("shm");
        let _idle = FrameReader::open(&name).expect("open").expect("exists");
        let mut tick = 0;
        g.bench_function(format!("publish_shm/{n}_robots"), |b| {
            b.iter(|| {
                tick += 4;
                publisher.publish(tick, &s)
            })
        });
        assert_eq!(publisher.stats().dropped(), 0);
    }
    g.sample_size(10);
    let mut w = world(256);
    g.bench_function("herd256/4_steps_off", |b| b.iter(|| w.sim.run(4)));
    let robots: Vec<_> = w.robots.iter().map(|(_, e)| *e).collect();
    let name = format!("bench-herd-{pid}");
    let dt = w.dt_s;
    let m = RunMonitor::start(&mut w.sim.world, &name, &robots, Vec::new(), dt, 4).expect("shm");
    let _idle = FrameReader::open(&name).expect("open").expect("exists");
    g.bench_function("herd256/4_steps_on", |b| b.iter(|| w.sim.run(4)));
    let stats = m.finish(&mut w.sim.world);
    assert_eq!(stats.dropped(), 0);
    g.finish();
}

criterion_group!(benches, monitor);
criterion_main!(benches);
