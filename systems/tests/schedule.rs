//! The step schedule: seven sets in a fixed order, conflicts refused, the clock.

use bevy_ecs::prelude::*;
use quadsim_components::{SimClock, SimConfig};
use quadsim_systems::{SimSystems, Simulation, build_step_schedule};

/// The order in which the marker systems ran.
#[derive(Resource, Default)]
struct StageLog(Vec<SimSystems>);

fn marker(stage: SimSystems) -> impl FnMut(ResMut<StageLog>) {
    move |mut log: ResMut<StageLog>| log.0.push(stage)
}

#[test]
fn stages_run_in_the_documented_order() {
    let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
    sim.world.init_resource::<StageLog>();
    // Registered in reverse so that only the set chain can put them in order.
    for stage in SimSystems::ALL.into_iter().rev() {
        sim.step_schedule_mut()
            .add_systems(marker(stage).in_set(stage));
    }
    sim.run(3);
    let log = &sim.world.resource::<StageLog>().0;
    let expected: Vec<SimSystems> = std::iter::repeat_n(SimSystems::ALL, 3).flatten().collect();
    assert_eq!(log, &expected);
    assert_eq!(
        SimSystems::ALL,
        [
            SimSystems::Sense,
            SimSystems::Gait,
            SimSystems::Control,
            SimSystems::Contact,
            SimSystems::Dynamics,
            SimSystems::Integrate,
            SimSystems::Publish
        ]
    );
}

#[test]
fn unordered_conflicts_are_build_errors() {
    let mut world = World::new();
    world.init_resource::<StageLog>();
    let mut schedule = build_step_schedule();
    // two writers of the same resource in one set, with no order between them
    schedule.add_systems(
        (marker(SimSystems::Control), marker(SimSystems::Gait)).in_set(SimSystems::Control),
    );
    assert!(schedule.initialize(&mut world).is_err());

    // ordered, they are accepted
    let mut schedule = build_step_schedule();
    schedule.add_systems(
        (marker(SimSystems::Control), marker(SimSystems::Gait))
            .chain()
            .in_set(SimSystems::Control),
    );
    assert!(schedule.initialize(&mut world).is_ok());
}

#[test]
fn clock_is_step_count_times_dt() {
    let config = SimConfig {
        dt_s: 0.1,
        ..SimConfig::default()
    };
    let mut sim = Simulation::new(config, 1).unwrap();
    sim.run(1000);
    // accumulating 0.1 a thousand times drifts; step × dt does not
    let accumulated = (0..1000).fold(0.0, |t: f64, _| t + 0.1);
    assert_ne!(accumulated, 100.0);
    assert_eq!(
        sim.clock(),
        SimClock {
            step: 1000,
            time_s: 1000.0 * 0.1
        }
    );
}
