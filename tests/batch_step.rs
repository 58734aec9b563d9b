//! The world's step with robots in SIMD lanes (`quadsim_engine::batch`)
//! equals the step robot by robot, bit for bit: trotting quad16 under VMC,
//! quad12 on servo motors (actuator models) and quad16 carrying a compliant
//! (sloshing) payload, stepped four at a time on two threads against one
//! by one on one thread.

use std::path::Path;

use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, World, build_world};
use quadsim_components::{LaneBatching, RobotBatch, StageLayout};

/// Three herds of five, one per feature the lanes must keep: each fills one
/// batch of four and leaves one robot to the scalar step.
const HERDS: &str = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 1.0
seed = 7
controller_rate_hz = 500
default_ground = "concrete"

[[herds]]
name = "trot"
count = 5
layout = { kind = "grid", columns = 5, spacing_m = [1.5, 1.0], origin_m = [0.0, 0.0] }
[herds.robot]
model = "quad16"
contact_points = ["knees", "torso"]
[herds.robot.controller]
kind = "vmc"
v_x_mps = 0.5

[[herds]]
name = "servo"
count = 5
layout = { kind = "grid", columns = 5, spacing_m = [1.0, 1.0], origin_m = [0.0, 3.0] }
[herds.robot]
model = "quad12"
params = { "actuator.effort_limit_nm" = 20.0 }
[herds.robot.actuators]
kind = "servo"
[herds.robot.controller]
kind = "prescribed"
mode = "pd"
period_s = 0.5
duty_factor = 0.5
step_length_m = 0.023335
lift_height_m = 0.02

[[herds]]
name = "slosh"
count = 5
layout = { kind = "grid", columns = 5, spacing_m = [1.5, 1.0], origin_m = [0.0, 6.0] }
[herds.robot]
model = "quad16"
[herds.robot.controller]
kind = "vmc"
v_x_mps = 0.5
[[herds.robot.payloads]]
name = "tank"
kind = "compliant"
mass_kg = 4.0
shape = "cylinder"
size_m = [0.1, 0.15]
offset_m = [0.0, 0.0, 0.15]
dofs = ["x", "y"]
stiffness_npm = 631.7
damping_nspm = 10.05
"#;

fn world(threads: usize, lanes: LaneBatching) -> World {
    let scn = parse_scenario(Path::new("batch_step.toml"), HERDS.to_string()).unwrap();
    let mut w = build_world(
        &scn,
        Overrides {
            threads,
            ..Default::default()
        },
    )
    .unwrap();
    w.sim.world.insert_resource(lanes);
    w
}

/// Every robot's state, actuator command and last acceleration, as bits.
fn fingerprint(w: &World) -> Vec<(String, Vec<u64>)> {
    w.robots
        .iter()
        .map(|(name, root)| {
            let r = w.sim.robot(*root).unwrap();
            let bits = r
                .state
                .q
                .iter()
                .chain(&r.state.v)
                .chain(&r.tau_actuator)
                .chain(r.workspace.last_acceleration())
                .chain(r.workspace.last_tau())
                .map(|x| x.to_bits())
                .collect();
            (name.clone(), bits)
        })
        .collect()
}

/// The sizes of the groups whose exclusive ends `plan_groups` wrote.
fn group_sizes(ends: &[usize]) -> Vec<usize> {
    std::iter::once(0)
        .chain(ends.iter().copied())
        .collect::<Vec<_>>()
        .windows(2)
        .map(|w| w[1] - w[0])
        .collect()
}

#[test]
fn herd_stepped_in_lanes_equals_herd_stepped_robot_by_robot_bit_for_bit() {
    let mut lanes = world(2, LaneBatching::AcrossRobots);
    let mut scalar = world(1, LaneBatching::Off);
    // The lanes are really used: each herd makes one group of four.
    let mut ends = Vec::new();
    let batch = lanes.sim.world.resource::<RobotBatch>();
    quadsim_systems::plan_groups(&batch.sims, LaneBatching::AcrossRobots, &mut ends);
    let sizes = group_sizes(&ends);
    assert_eq!(sizes, [4, 1, 4, 1, 4, 1], "groups by model");
    // By default a robot whose legs run in lanes on this CPU steps alone.
    let mut auto = world(2, LaneBatching::Auto);
    let batch = auto.sim.world.resource::<RobotBatch>();
    quadsim_systems::plan_groups(&batch.sims, LaneBatching::Auto, &mut ends);
    let mut expected = Vec::new();
    let mut start = 0;
    for size in sizes {
        let legs = quadsim_engine::dispatch::runs_on(&batch.sims[start].model);
        let alone = [1].repeat(size);
        expected.extend(if legs { alone } else { vec![size] });
        start += size;
    }
    let auto_sizes = group_sizes(&ends);
    println!("groups with LaneBatching::Auto: {auto_sizes:?}");
    assert_eq!(auto_sizes, expected, "groups by model, legs in lanes alone");
    let steps = 600;
    for step in 0..steps {
        lanes.sim.step();
        scalar.sim.step();
        auto.sim.step();
        if step % 100 == 99 {
            assert_eq!(fingerprint(&lanes), fingerprint(&scalar), "step {step}");
            assert_eq!(fingerprint(&auto), fingerprint(&scalar), "step {step}");
        }
    }
    // The robots moved (the comparison is not of robots at rest): the
    // trotters walked forward, the servo-driven quad12 moved its joints.
    for (name, root) in &lanes.robots {
        let r = lanes.sim.robot(*root).unwrap();
        let speed: f64 = r.state.v[6..].iter().map(|v| v.abs()).sum();
        assert!(speed > 1e-3, "{name} at rest: joint speeds sum {speed}");
    }
}

/// Every robot's metrics so far (energy, distance, margins, ...), as text
/// with every float's bits.
fn metrics(w: &World) -> Vec<(String, String)> {
    w.robots
        .iter()
        .map(|(name, root)| {
            let r = w.sim.robot(*root).unwrap();
            (name.clone(), format!("{:?}", r.run.metrics.summary()))
        })
        .collect()
}

#[test]
fn herd_stepped_block_by_block_equals_herd_stepped_stage_by_stage_bit_for_bit() {
    // blocks of 4 (the lane groups) and 8 on two threads against the
    // stage-major layout on one; and blocks of one lane group (the default)
    // with each robot whose legs run in lanes alone. The herds have noisy
    // sensors and the estimator on (the defaults), so the Sense stage is in
    // the comparison
    let mut stages = world(1, LaneBatching::AcrossRobots);
    stages.sim.world.insert_resource(StageLayout::StageMajor);
    let mut blocks: Vec<World> = [
        (4, LaneBatching::AcrossRobots),
        (8, LaneBatching::AcrossRobots),
        (1, LaneBatching::Auto),
    ]
    .map(|(robots, lanes)| {
        let mut w = world(2, lanes);
        w.sim
            .world
            .insert_resource(StageLayout::RobotBlocks { robots });
        w
    })
    .into();
    for step in 0..600 {
        stages.sim.step();
        for b in &mut blocks {
            b.sim.step();
        }
        if step % 100 == 99 {
            for b in &blocks {
                assert_eq!(fingerprint(b), fingerprint(&stages), "step {step}");
                assert_eq!(metrics(b), metrics(&stages), "step {step}");
            }
        }
    }
    // the Sense stage did work: the robots read their sensors
    let batch = stages.sim.world.resource::<RobotBatch>();
    assert!(batch.sims.iter().all(|s| s.sensing.is_some()));
}
