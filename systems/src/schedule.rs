//! The fixed-step schedule: seven named stages, chained in an explicit order.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};

use crate::blocks::{stage_major, step_robot_blocks};
use crate::contact::update_contacts;
use crate::control::run_controllers;
use crate::log::{LogChannel, MonitorChannel, log_due, log_step};
use crate::metrics::record_metrics;
use crate::publish::{pose_sync_due, sync_link_poses};
use crate::sense::sense_robots;
use crate::step::{advance_clock, step_robots};

/// Label of the schedule that advances the world by one fixed step.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct StepSchedule;

/// The stages of one fixed step, run in this order (each set exists even
/// while empty, as a hook for later systems):
///
/// 0. [`Sense`](SimSystems::Sense): responsible for what the robots see:
///    each robot's sensors sample the state the step starts from (each at
///    its own rate), its base estimator runs on new IMU samples, and the
///    sensed state is assembled ([`RobotSensing`](quadsim_components::RobotSensing)).
///    First, so that the gait and the controllers of this step read it.
/// 1. [`Gait`](SimSystems::Gait): responsible for the gait clock and phase:
///    which feet are in stance or swing, and the swing-foot and body targets.
/// 2. [`Control`](SimSystems::Control): responsible for the actuator command:
///    controllers (VMC, joint PD) read the state and write each robot's
///    `tau_actuator` (N·m, nv).
/// 3. [`Contact`](SimSystems::Contact): responsible for preparing contacts:
///    ground queries and contact parameters put into each robot's
///    [`ContactForces`](quadsim_components::ContactForces), the force model
///    the integrator evaluates.
/// 4. [`Dynamics`](SimSystems::Dynamics): responsible for anything the
///    dynamics need fixed over the step before integrating. Forward dynamics
///    itself (passive torques, saturated actuator torques, contact forces, ABA)
///    runs *inside* the integrator, once per derivative evaluation, because
///    RK4 needs it at every stage; so this set is empty today.
/// 5. [`Integrate`](SimSystems::Integrate): responsible for advancing every
///    robot's `(q, v)` by one `dt` with the engine's integrator, robots in
///    parallel on the [`SimThreadPool`](quadsim_components::SimThreadPool), then
///    the [`SimClock`](quadsim_components::SimClock).
/// 6. [`Publish`](SimSystems::Publish): responsible for publishing and logging:
///    each step's metrics, copying link poses back to
///    [`LinkPose`](quadsim_components::LinkPose) at the
///    [`PoseSync`](quadsim_components::PoseSync) rate, streaming and logging.
///
/// The per-robot work of these stages (sense, control, contact, integrate,
/// metrics) is laid over the robots by the
/// [`StageLayout`](quadsim_components::StageLayout) resource. By default
/// ([`RobotBlocks`](quadsim_components::StageLayout::RobotBlocks)) one system,
/// [`step_robot_blocks`], at the start of `Integrate`, takes each block of a
/// few robots through all of them in the order above while the block is in
/// the core's cache; the stage-major systems ([`sense_robots`],
/// [`run_controllers`], [`update_contacts`], [`step_robots`],
/// [`record_metrics`]) run instead under
/// [`StageMajor`](quadsim_components::StageLayout::StageMajor). Robots do not
/// interact, so both give the same bits; world-level systems added to the
/// sets before `Integrate` run before the robot pass in either layout. The
/// stage-major systems are also in the [`StageMajorPass`] set, whose one run
/// condition ([`stage_major`]) is evaluated once per step, when its first
/// system (`sense_robots`) comes up, instead of once per system.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SimSystems {
    /// Sensors and state estimation.
    Sense,
    /// Gait clock and phase.
    Gait,
    /// Actuator commands.
    Control,
    /// Contact preparation.
    Contact,
    /// Step-constant dynamics inputs.
    Dynamics,
    /// Time integration and the clock.
    Integrate,
    /// Publishing and logging.
    Publish,
}

impl SimSystems {
    /// All stages in run order.
    pub const ALL: [SimSystems; 7] = [
        SimSystems::Sense,
        SimSystems::Gait,
        SimSystems::Control,
        SimSystems::Contact,
        SimSystems::Dynamics,
        SimSystems::Integrate,
        SimSystems::Publish,
    ];
}

/// The stage-major systems ([`sense_robots`], [`run_controllers`],
/// [`update_contacts`], [`step_robots`], [`record_metrics`]), which run only
/// under [`StageLayout::StageMajor`](quadsim_components::StageLayout::StageMajor).
/// [`build_step_schedule`] gives the set its run condition, [`stage_major`];
/// the `register_*` functions put the systems in it. A set condition is
/// evaluated once per schedule run (at the set's first system; if false,
/// bevy skips the whole set), where a condition on each system would be
/// evaluated five times per step.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StageMajorPass;

/// The step schedule: the seven [`SimSystems`] chained, the built-in systems
/// registered, ambiguity detection as an error (every data conflict must be
/// ordered on purpose).
///
/// It runs on bevy's single-threaded executor: the stages are strictly
/// sequential anyway, and the parallelism is across robots inside
/// [`step_robots`], on the world's own thread pool (bevy's global task pool can
/// only be sized once per process).
pub fn build_step_schedule() -> Schedule {
    let mut schedule = Schedule::new(StepSchedule);
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.configure_sets(
        (
            SimSystems::Sense,
            SimSystems::Gait,
            SimSystems::Control,
            SimSystems::Contact,
            SimSystems::Dynamics,
            SimSystems::Integrate,
            SimSystems::Publish,
        )
            .chain(),
    );
    schedule.configure_sets(StageMajorPass.run_if(stage_major));
    register_sense(&mut schedule);
    register_gait(&mut schedule);
    register_control(&mut schedule);
    register_contact(&mut schedule);
    register_dynamics(&mut schedule);
    register_integrate(&mut schedule);
    register_publish(&mut schedule);
    schedule
}

/// Registers [`sense_robots`]: sensors, estimator, sensed state (in
/// [`StageMajorPass`]).
pub fn register_sense(schedule: &mut Schedule) {
    schedule.add_systems(
        sense_robots
            .in_set(StageMajorPass)
            .in_set(SimSystems::Sense),
    );
}

/// Registers the gait systems (none yet: the gait planner comes in a later issue).
pub fn register_gait(_schedule: &mut Schedule) {}

/// Registers [`run_controllers`] (joint PD; VMC comes with the walking issue;
/// in [`StageMajorPass`]).
pub fn register_control(schedule: &mut Schedule) {
    schedule.add_systems(
        run_controllers
            .in_set(StageMajorPass)
            .in_set(SimSystems::Control),
    );
}

/// Registers [`update_contacts`]: contact states (anchors) and observations,
/// once per step at the step's start state (in [`StageMajorPass`]).
pub fn register_contact(schedule: &mut Schedule) {
    schedule.add_systems(
        update_contacts
            .in_set(StageMajorPass)
            .in_set(SimSystems::Contact),
    );
}

/// Registers the dynamics systems (none: see [`SimSystems::Dynamics`]).
pub fn register_dynamics(_schedule: &mut Schedule) {}

/// Registers [`step_robot_blocks`] (which returns at once unless the layout is
/// [`RobotBlocks`](quadsim_components::StageLayout::RobotBlocks), so it needs
/// no run condition of its own: evaluating one every step costs more than
/// the system's own check) or [`step_robots`] (in [`StageMajorPass`]), then
/// [`advance_clock`].
pub fn register_integrate(schedule: &mut Schedule) {
    schedule.add_systems(
        (
            step_robot_blocks,
            step_robots.in_set(StageMajorPass),
            advance_clock,
        )
            .chain()
            .in_set(SimSystems::Integrate),
    );
}

/// Registers [`record_metrics`] (in [`StageMajorPass`]), [`sync_link_poses`] (gated by [`pose_sync_due`])
/// and [`log_step`] (while a [`Logger`](crate::Logger) exists, on the steps it samples or snapshots).
pub fn register_publish(schedule: &mut Schedule) {
    schedule.add_systems(
        record_metrics
            .in_set(StageMajorPass)
            .in_set(SimSystems::Publish),
    );
    schedule.add_systems(
        sync_link_poses
            .run_if(pose_sync_due)
            .in_set(SimSystems::Publish)
            .after(record_metrics),
    );
    // Logging (only while a `Logger` exists): samples the state the step started from.
    // It only reads the simulation (and writes its own sink), so its order
    // against systems users add to `Publish` does not matter: declared
    // ambiguous with them, so that such hooks do not fail the schedule build.
    schedule.add_systems(
        log_step::<LogChannel>
            .run_if(log_due::<LogChannel>)
            .in_set(SimSystems::Publish)
            .after(sync_link_poses)
            .ambiguous_with_all(),
    );
    // The live monitor (only while a `Logger<MonitorChannel>` exists): the
    // same sampling at its own rate, after the log's.
    schedule.add_systems(
        log_step::<MonitorChannel>
            .run_if(log_due::<MonitorChannel>)
            .in_set(SimSystems::Publish)
            .after(log_step::<LogChannel>)
            .ambiguous_with_all(),
    );
}
