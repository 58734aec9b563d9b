//! Cost of live monitoring (docs/monitor.md). Per publish the monitor
//! (1) writes every sampled robot's frame from its view, on the thread pool
//! beside the robot's sampling (`frame_fill`: the frames of every robot,
//! serially on one thread), then (2) runs the publish tick on the simulation
//! thread (`publish_shm`: loan one slice, copy the ready frames into it,
//! send), here with one idle subscriber attached; for 1 and 256 trotting
//! quad16, divide by the robots for the cost per robot per publish. The
//! views' kinematics and contact evaluations are made once beforehand (in a
//! run the step has made them). `herd256`: one controller period (4 steps) of
//! 256 trotting quad16 without and with the monitor (sampling, frames and
//! publishing); the difference over the period is the monitor's share of
//! step time. Run with `cargo bench -p quadsim --bench monitor_publish`.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use quadsim::cli::bench::herd_scenario;
use quadsim::monitor::{FramePublisher, FrameReader, RobotFrame, RunMonitor};
use quadsim::scenario::parse_scenario;
use quadsim::systems::with_fresh_views;
use quadsim::world::{Overrides, World, build_world};

fn world(n: usize) -> World {
    let src = herd_scenario("quad16", n).expect("scenario");
    let scn = parse_scenario(Path::new("bench.toml"), src).expect("parses");
    let mut w = build_world(&scn, Overrides::default()).expect("builds");
    w.sim.run(200); // settle and start trotting
    w
}

fn monitor(c: &mut Criterion) {
    let pid = std::process::id();
    let mut g = c.benchmark_group("monitor");
    for n in [1usize, 256] {
        let w = world(n);
        let states: Vec<_> = w
            .robots
            .iter()
            .map(|(_, e)| {
                let sim = w.sim.robot(*e).expect("compiled");
                (*e, sim.state.q.clone(), sim.state.v.clone())
            })
            .collect();
        let at: Vec<_> = states
            .iter()
            .map(|(e, q, v)| (*e, &q[..], &v[..]))
            .collect();
        let name = format!("bench-shm-{n}-{pid}");
        let publisher = FramePublisher::create(&name, n, w.dt_s, 4, Vec::new()).expect("shm");
        let _idle = FrameReader::open(&name).expect("open").expect("exists");
        let mut tick = 0;
        let mut frames = vec![RobotFrame::default(); n];
        with_fresh_views(&w.sim.world, &at, |views| {
            assert_eq!(views.len(), n);
            g.bench_function(format!("frame_fill/{n}_robots"), |b| {
                b.iter(|| {
                    tick += 4;
                    let time_s = publisher.time_s(tick);
                    for (f, v) in frames.iter_mut().zip(views) {
                        f.set_from_view(v, tick, time_s);
                    }
                })
            });
        });
        g.bench_function(format!("publish_shm/{n}_robots"), |b| {
            b.iter(|| publisher.publish_frames(frames.iter()))
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
