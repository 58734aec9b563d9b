//! The sampling behind the log and the live monitor reads the kinematics the
//! step left in each robot's `Data` instead of computing them again
//! (`quadsim_systems::log`, `prepare`), and the monitor writes its frames
//! straight from borrowed views, as records on the thread pool. Over trotting runs, every sample and every
//! frame must equal, bit for bit, one computed afresh at the sampled state
//! (`with_fresh_views`: forward kinematics and contact evaluations in
//! scratch). With semi-implicit Euler the robot's own kinematics must hold
//! the sampled state at every sample (else the saving is lost); with RK4
//! they never do, and the sampler's own forward kinematics is checked.

use std::path::Path;
use std::sync::{Arc, Mutex};

use bevy_ecs::entity::Entity;
use quadsim::cli::bench::herd_scenario;
use quadsim::monitor::RobotFrame;
use quadsim::scenario::parse_scenario;
use quadsim::systems::{
    LogChannel, LogRecord, LogSink, MonitorChannel, Records, RobotSample, SampleView, ViewRecord,
    finish_sampling, start_sampling, with_fresh_views,
};
use quadsim::world::{Overrides, World, build_world};

/// Steps between samples (the controller period at 2 kHz).
const EVERY: u64 = 4;

/// One instant's log record: time (ns) and samples.
type Instant = (u64, Vec<RobotSample>);

/// Keeps the log channel's samples of every instant.
struct Samples(Arc<Mutex<Vec<Instant>>>);
impl LogSink for Samples {
    fn send(&mut self, record: LogRecord) {
        if let LogRecord::Step { t_ns, samples } = record {
            self.0.lock().unwrap().push((t_ns, samples));
        }
    }
}

/// Keeps a frame per robot as its record, written in place from the
/// robot's view on the pool (as the live monitor's sink does), and a copy
/// of each instant's frames.
struct Frames(Arc<Mutex<(u64, Vec<RobotFrame>)>>, f64);
impl LogSink for Frames {
    fn send(&mut self, _: LogRecord) {}
    fn takes_records(&self) -> bool {
        true
    }
    fn new_record(&self) -> ViewRecord {
        Box::new(RobotFrame::default())
    }
    fn write_record(&self, record: &mut ViewRecord, step: u64, view: &SampleView<'_>) {
        let f: &mut RobotFrame = record.downcast_mut().expect("a frame");
        f.set_from_view(view, step, step as f64 * self.1);
    }
    fn send_records(&mut self, _t_ns: u64, step: u64, records: Records<'_>) {
        let mut got = self.0.lock().unwrap();
        got.0 = step;
        got.1.clear();
        got.1
            .extend(records.map(|r| *r.downcast_ref::<RobotFrame>().expect("a frame")));
    }
}

fn trot() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/trot.toml"))
        .expect("scenarios/trot.toml")
}

fn world(src: &str) -> World {
    let scn = parse_scenario(Path::new("test.toml"), src.to_string()).expect("parses");
    build_world(&scn, Overrides::default()).expect("builds")
}

fn state(w: &World, e: Entity) -> (Vec<f64>, Vec<f64>) {
    let sim = w.sim.robot(e).expect("compiled");
    (sim.state.q.clone(), sim.state.v.clone())
}

/// Runs `steps` steps sampling both channels every [`EVERY`] steps and
/// compares each instant with a fresh computation at the state the step
/// started from. Returns how many robot-samples found the robot's own
/// kinematics at that state.
fn check(w: &mut World, steps: u64) -> (usize, usize) {
    let robots: Vec<Entity> = w.robots.iter().map(|(_, e)| *e).collect();
    let followed: Vec<(Entity, bool)> = robots.iter().map(|&e| (e, true)).collect();
    let samples = Arc::new(Mutex::new(Vec::new()));
    let frames = Arc::new(Mutex::new((u64::MAX, Vec::new())));
    start_sampling::<LogChannel>(
        &mut w.sim.world,
        Box::new(Samples(samples.clone())),
        EVERY,
        &followed,
    );
    start_sampling::<MonitorChannel>(
        &mut w.sim.world,
        Box::new(Frames(frames.clone(), w.dt_s)),
        EVERY,
        &followed,
    );
    let (mut checked, mut held) = (0, 0);
    for j in 0..steps {
        let before: Vec<_> = robots.iter().map(|&e| state(w, e)).collect();
        w.sim.run(1);
        if !j.is_multiple_of(EVERY) {
            continue;
        }
        let at: Vec<(Entity, &[f64], &[f64])> = robots
            .iter()
            .zip(&before)
            .map(|(&e, (q, v))| (e, &q[..], &v[..]))
            .collect();
        let logged = samples.lock().unwrap().pop().expect("a sample per instant");
        let published = frames.lock().unwrap().clone();
        assert_eq!(logged.0, (j as f64 * w.dt_s * 1e9).round() as u64);
        assert_eq!(published.0, j);
        with_fresh_views(&w.sim.world, &at, |views| {
            assert_eq!(views.len(), robots.len());
            for (k, view) in views.iter().enumerate() {
                let fresh = view.to_sample(true);
                assert_eq!(
                    format!("{fresh:?}"),
                    format!("{:?}", logged.1[k]),
                    "log sample of robot {k} at step {j}"
                );
                let frame = RobotFrame::from_sample(&fresh, j, j as f64 * w.dt_s);
                assert_eq!(
                    format!("{frame:?}"),
                    format!("{:?}", published.1[k]),
                    "frame of robot {k} at step {j}"
                );
                checked += 1;
                let sim = w.sim.robot(robots[k]).unwrap();
                held += usize::from(sim.data.kinematics_hold(&sim.model, view.q, view.v));
            }
        });
    }
    drop(finish_sampling::<MonitorChannel>(&mut w.sim.world, false));
    drop(finish_sampling::<LogChannel>(&mut w.sim.world, false));
    (checked, held)
}

/// One quad16 trotting (`scenarios/trot.toml`, semi-implicit Euler) for
/// 0.5 s: every sample reads the step's own kinematics and equals a fresh one.
#[test]
fn trot_samples_from_the_step_equal_fresh_ones() {
    let src = trot();
    let mut w = world(&src);
    let (checked, held) = check(&mut w, 1000);
    assert_eq!(checked, 250);
    assert_eq!(
        held, checked,
        "the step's kinematics hold every sampled state"
    );
}

/// Eight trotting quad16 stepped four at a time in SIMD lanes.
#[test]
fn herd_in_lanes_samples_equal_fresh_ones() {
    let mut w = world(&herd_scenario("quad16", 8).unwrap());
    let (checked, held) = check(&mut w, 300);
    assert_eq!(checked, 8 * 75);
    assert_eq!(held, checked);
}

/// RK4 leaves its last stage's kinematics in `Data`: the sampler computes
/// them itself, and still equals a fresh computation.
#[test]
fn rk4_samples_computed_again_equal_fresh_ones() {
    let src = trot();
    let src = src.replace(
        "integrator = \"semi_implicit_euler\"",
        "integrator = \"rk4\"",
    );
    assert!(src.contains("\"rk4\""));
    let mut w = world(&src);
    let (checked, held) = check(&mut w, 400);
    assert_eq!(checked, 100);
    assert_eq!(held, 0, "RK4's last stage is not the sampled state");
}

/// The live monitor's frames as published: [`RunMonitor`]'s sink writes each
/// robot's frame on the thread pool right after preparing it (its record),
/// and the publish tick copies the frames into shared memory. Over a herd of
/// 32 trotting quad16 (enough for the parallel sampling,
/// `PARALLEL_SAMPLING_MIN_ROBOTS`) with knee and torso contact points beside
/// the feet (the monitor evaluates the feet only), every frame received in this process
/// equals, bit for bit, the frame of a fresh sample at the sampled state,
/// with one worker thread and with two; so the two runs' frames are equal.
#[test]
fn frames_written_on_the_pool_equal_fresh_ones_with_1_and_2_threads() {
    use quadsim::monitor::{FrameReader, RunMonitor};
    use quadsim::systems::PARALLEL_SAMPLING_MIN_ROBOTS;
    use std::time::Duration;

    const ROBOTS: usize = 32;
    const STEPS: u64 = 200;
    const { assert!(ROBOTS >= PARALLEL_SAMPLING_MIN_ROBOTS) };
    let src = herd_scenario("quad16", ROBOTS).unwrap().replace(
        "log = false\n",
        "log = false\ncontact_points = [\"knees\", \"torso\"]\n",
    );
    assert!(src.contains("contact_points"));
    let run = |threads: usize| -> Vec<String> {
        let scn = parse_scenario(Path::new("test.toml"), src.clone()).expect("parses");
        let ov = Overrides {
            threads,
            ..Overrides::default()
        };
        let mut w = build_world(&scn, ov).expect("builds");
        let pool = w.sim.world.resource::<quadsim::components::SimThreadPool>();
        assert_eq!(pool.threads(), threads);
        let robots: Vec<Entity> = w.robots.iter().map(|(_, e)| *e).collect();
        let sim = w.sim.robot(robots[0]).expect("compiled");
        assert!(sim.contact.points.len() > sim.run.n_feet, "knees and torso");
        let name = format!("test-pool-frames-{threads}-{}", std::process::id());
        let (dt, sim) = (w.dt_s, &mut w.sim.world);
        let monitor = RunMonitor::start(sim, &name, &robots, Vec::new(), dt, EVERY).expect("shm");
        let mut reader = FrameReader::open(&name).expect("opens").expect("exists");
        let mut got = Vec::new();
        for j in 0..STEPS {
            let before: Vec<_> = robots.iter().map(|&e| state(&w, e)).collect();
            w.sim.run(1);
            if !j.is_multiple_of(EVERY) {
                continue;
            }
            let frames = reader
                .next(Duration::from_secs(10))
                .expect("reads")
                .expect("a published instant per sample");
            assert_eq!(frames.len(), ROBOTS);
            let at: Vec<(Entity, &[f64], &[f64])> = robots
                .iter()
                .zip(&before)
                .map(|(&e, (q, v))| (e, &q[..], &v[..]))
                .collect();
            with_fresh_views(&w.sim.world, &at, |views| {
                for (k, (view, frame)) in views.iter().zip(&frames).enumerate() {
                    let fresh = RobotFrame::from_sample(&view.to_sample(false), j, j as f64 * dt);
                    let frame = format!("{frame:?}");
                    assert_eq!(
                        format!("{fresh:?}"),
                        frame,
                        "frame of robot {k} at step {j}, {threads} thread(s)"
                    );
                    got.push(frame);
                }
            });
        }
        let stats = monitor.finish(&mut w.sim.world);
        assert_eq!(stats.dropped(), 0);
        assert_eq!(stats.published(), STEPS / EVERY);
        got
    };
    let one = run(1);
    assert_eq!(one.len(), ROBOTS * (STEPS / EVERY) as usize);
    assert!(one == run(2), "the frames depend on the thread count");
}
