//! `Simulation::run` takes the robots through several steps per run of the
//! step schedule where nothing outside the robots looks at the world
//! between steps (`quadsim_systems::PassSteps`). These tests hold it to its
//! promise: the same bits as one `Simulation::step` at a time, with the
//! passes cut where a log sample, a payload event or a timed command falls.

use std::collections::BTreeMap;
use std::path::Path;

use quadsim::log::read::read_log;
use quadsim::log::{RunOutcome, start_run_log};
use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, World, build_world};
use quadsim_systems::MAX_PASS_STEPS;

/// A mixed herd on two terrains, and a quad16 whose box is attached and
/// detached by events at times that are not multiples of a pass, that is
/// pushed, and that is told to turn.
const SCENARIO: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 0.4
seed = 5
controller_rate_hz = 500
default_ground = "concrete"

[[terrains]]
name = "flat"
kind = "flat"
origin_m = [0.0, 0.0, 0.0]
extent_m = [10.0, 10.0]

[[terrains]]
name = "sine"
kind = "sine"
amplitude_m = 0.01
wavelength_m = 2.0
origin_m = [0.0, 20.0, 0.0]
extent_m = [10.0, 10.0]

[[robots]]
name = "rex"
model = "quad16"
[robots.controller]
kind = "vmc"
v_x_mps = 0.5
[[robots.payloads]]
name = "box"
mass_kg = 5.0
size_m = [0.3, 0.2, 0.1]
offset_m = [0.0, 0.0, 0.1]
attached = false

[[events]]
t_s = 0.1003
robot = "rex"
kind = "attach"
payload = "box"

[[events]]
t_s = 0.2511
robot = "rex"
kind = "detach"
payload = "box"

[[events]]
t_s = 0.1502
robot = "rex"
kind = "push"
force_n = [0.0, 40.0, 0.0]
duration_s = 0.05

[[herds]]
name = "trot"
count = 5
layout = { kind = "lanes", terrains = ["flat", "sine"], spacing_m = [0.0, 1.5], origin_m = [0.0, -3.0] }
[herds.robot]
model = "quad16"
[herds.robot.controller]
kind = "vmc"
[herds.vary]
"controller.v_x_mps" = { from = 0.2, to = 0.5, steps = 4 }

[[herds]]
name = "small"
count = 3
layout = { kind = "grid", columns = 3, spacing_m = [1.0, 1.0], origin_m = [-4.0, 3.0] }
[herds.robot]
model = "quad12"
[herds.robot.controller]
kind = "joint_pd"
"#;

/// Per robot name: the final state's bits and the summary metrics.
type Robots = BTreeMap<String, (Vec<u64>, String)>;

/// A log's messages: topic, log time (ns) and payload.
type Messages = Vec<(String, u64, Vec<u8>)>;

fn robots(w: &World) -> Robots {
    w.robots
        .iter()
        .map(|(name, e)| {
            let r = w.sim.robot(*e).unwrap();
            let bits = r
                .state
                .q
                .iter()
                .chain(&r.state.v)
                .chain(&r.tau_actuator)
                .map(|x| x.to_bits())
                .collect();
            (
                name.clone(),
                (bits, format!("{:?}", r.run.metrics.summary())),
            )
        })
        .collect()
}

/// Runs the scenario on `threads` workers, with a log sampled every
/// `log_every` steps if any, either with `Simulation::run` or one
/// `Simulation::step` at a time: the robots, the log's messages, and how
/// many times the step schedule ran.
fn simulate(
    threads: usize,
    log_every: Option<u64>,
    stepwise: bool,
    tag: &str,
) -> (Robots, Messages, u64) {
    let dir = std::env::temp_dir().join(format!("quadsim-fused-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scn = parse_scenario(&dir.join("fused.toml"), SCENARIO.to_string()).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(threads)).unwrap();
    let path = dir.join("log.mcap");
    let log = log_every.map(|every| start_run_log(&scn, &mut w, &path, every).unwrap());
    let steps = w.steps;
    if stepwise {
        for _ in 0..steps {
            w.sim.step();
        }
    } else {
        // in uneven pieces, as the CLI's progress chunks would
        let mut done = 0;
        for n in [1, 7, 300].into_iter().cycle() {
            let n = n.min(steps - done);
            w.sim.run(n);
            done += n;
            if done == steps {
                break;
            }
        }
    }
    assert_eq!(w.sim.clock().step, steps);
    let mut messages = Vec::new();
    if let Some(log) = log {
        log.finish(&mut w, &RunOutcome::default()).unwrap();
        let c = read_log(&path).unwrap();
        assert_eq!(c.error, None);
        messages = c
            .messages
            .iter()
            .map(|m| (m.topic.clone(), m.log_time_ns, m.data.clone()))
            .collect();
        assert!(!messages.is_empty());
    }
    let _ = std::fs::remove_dir_all(dir);
    (robots(&w), messages, w.sim.passes())
}

#[test]
fn several_steps_per_pass_give_the_bits_of_one_step_at_a_time() {
    let (reference, _, passes) = simulate(1, None, true, "s1");
    assert_eq!(reference.len(), 9);
    let steps = passes;
    for threads in [1, 2] {
        let (fused, _, passes) = simulate(threads, None, false, &format!("f{threads}"));
        assert!(fused == reference, "{threads} threads: fused passes differ");
        // the passes did take many steps each (cut by the `run` calls, by
        // the two payload events and by the compiles they cause)
        assert!(
            passes * 20 <= steps && passes >= steps / MAX_PASS_STEPS,
            "{passes} passes for {steps} steps"
        );
    }
}

#[test]
fn passes_stop_where_the_log_samples() {
    for every in [1, 6] {
        let (reference, ref_log, _) = simulate(2, Some(every), true, &format!("ls{every}"));
        let (fused, log, passes) = simulate(2, Some(every), false, &format!("lf{every}"));
        assert!(fused == reference, "log every {every}: robots differ");
        assert!(log == ref_log, "log every {every}: messages differ");
        let steps = 800; // 0.4 s at 0.5 ms
        if every == 1 {
            assert_eq!(
                passes, steps,
                "a sample after every step: one step per pass"
            );
        } else {
            // samples after steps ≡ 0 and 1 (mod 6): two passes per 6 steps,
            // plus the cuts at the events and the `run` calls
            assert!(passes < steps / 2, "{passes} passes");
        }
    }
}

/// quad16 under joint PD on ideal torque sources, dropped onto a ground a
/// million times stiffer than concrete: at dt = 0.5 ms the contact's
/// explicit integration is unstable and the run diverges within its first
/// steps of contact (as in `tests/log_recovery.rs`).
const DIVERGING: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 1.0
controller_rate_hz = 500
default_ground = { stiffness_n_per_m = 1.0e11, damping_ns_per_m = 0.0, friction = 0.8 }

[[robots]]
name = "rex"
model = "quad16"
[robots.actuators]
kind = "ideal"
[robots.controller]
kind = "joint_pd"
bandwidth_hz = 3.0
gravity_compensation = "static"
"#;

#[test]
fn a_divergence_is_reported_at_its_step_after_a_pass_of_several() {
    let scn = parse_scenario(Path::new("diverging.toml"), DIVERGING.to_string()).unwrap();
    let check = |w: &World| {
        quadsim::divergence::check_finite(w)
            .err()
            .map(|e| e.to_string())
    };
    // one step at a time, checked after each
    let mut stepwise = build_world(&scn, Overrides::with_threads(1)).unwrap();
    let (stepwise_error, stepwise_at) = loop {
        stepwise.sim.step();
        if let Some(e) = check(&stepwise) {
            break (e, stepwise.sim.clock().step);
        }
        assert!(stepwise.sim.clock().step < stepwise.steps, "no divergence");
    };
    // passes of several steps, checked after each pass
    let mut fused = build_world(&scn, Overrides::with_threads(1)).unwrap();
    let (fused_error, fused_at) = loop {
        fused.sim.run_pass(MAX_PASS_STEPS);
        if let Some(e) = check(&fused) {
            break (e, fused.sim.clock().step);
        }
    };
    println!("{stepwise_error} (step {stepwise_at}; the pass ended at step {fused_at})");
    assert!(
        stepwise_error.contains("robot 'rex' diverged at t = "),
        "{stepwise_error}"
    );
    assert_eq!(fused_error, stepwise_error);
    assert!(
        fused_at > stepwise_at + 1,
        "the pass went on past the divergence"
    );
    // the diverged robot stopped where it diverged: state and metrics as
    // when the run stops one step at a time
    assert!(robots(&fused) == robots(&stepwise));
}
