//! The fixed-step schedule: seven named stages, chained in an explicit order.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};

use crate::blocks::step_robot_pass;
use crate::log::{log_steps, logs_due};
use crate::publish::{pose_sync_due, sync_link_poses};

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
/// metrics) and the clock are one system, [`step_robot_pass`], in
/// `Integrate`: it takes each robot through all of them in the order above,
/// laid over the robots by the
/// [`StageLayout`](quadsim_components::StageLayout) resource (block by
/// block by default, or stage by stage), then counts the step. Robots do
/// not interact, so both layouts give the same bits; world-level systems
/// added to the sets before `Integrate` run before the robot pass in either
/// layout.
///
/// The schedule holds only the systems a step needs (the robot pass,
/// publishing), because its executor pays for every system and run
/// condition in it on every step, whether they run or not: a skipped
/// system costs its turn in the executor's loop, every run condition (of a
/// system, or of a set, even one whose systems are all skipped) is
/// evaluated each step, a system call that fetches its resources, and a
/// system that runs fetches its own.
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

/// The step schedule: the seven [`SimSystems`] chained, the built-in systems
/// registered, ambiguity detection as an error (every data conflict must be
/// ordered on purpose).
///
/// It runs on bevy's single-threaded executor: the stages are strictly
/// sequential anyway, and the parallelism is across robots inside
/// [`step_robot_pass`], on the world's own thread pool (bevy's global task pool can
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
    register_sense(&mut schedule);
    register_gait(&mut schedule);
    register_control(&mut schedule);
    register_contact(&mut schedule);
    register_dynamics(&mut schedule);
    register_integrate(&mut schedule);
    register_publish(&mut schedule);
    schedule
}

/// Registers the sensing systems (none: each robot's sensors, estimator and
/// sensed state are the first stage of [`step_robot_pass`]).
pub fn register_sense(_schedule: &mut Schedule) {}

/// Registers the gait systems (none yet: the gait planner comes in a later issue).
pub fn register_gait(_schedule: &mut Schedule) {}

/// Registers the control systems (none: each robot's controller is a stage
/// of [`step_robot_pass`]).
pub fn register_control(_schedule: &mut Schedule) {}

/// Registers the contact systems (none: each robot's contact states and
/// observations are a stage of [`step_robot_pass`]).
pub fn register_contact(_schedule: &mut Schedule) {}

/// Registers the dynamics systems (none: see [`SimSystems::Dynamics`]).
pub fn register_dynamics(_schedule: &mut Schedule) {}

/// Registers [`step_robot_pass`]: every robot's stages, integration
/// included, then the clock.
pub fn register_integrate(schedule: &mut Schedule) {
    schedule.add_systems(step_robot_pass.in_set(SimSystems::Integrate));
}

/// Registers [`sync_link_poses`] (gated by [`pose_sync_due`]) and
/// [`log_steps`] (while a [`Logger`](crate::Logger) of either channel
/// exists, on the steps it samples or snapshots, [`logs_due`]). Each
/// robot's metrics are recorded by [`step_robot_pass`].
pub fn register_publish(schedule: &mut Schedule) {
    schedule.add_systems(
        sync_link_poses
            .run_if(pose_sync_due)
            .in_set(SimSystems::Publish),
    );
    // Logging and the live monitor (only while a `Logger` of either exists):
    // samples the state the step started from. It only reads the simulation
    // (and writes its own sinks), so its order against systems users add to
    // `Publish` does not matter: declared ambiguous with them, so that such
    // hooks do not fail the schedule build.
    schedule.add_systems(
        log_steps
            .run_if(logs_due)
            .in_set(SimSystems::Publish)
            .after(sync_link_poses)
            .ambiguous_with_all(),
    );
}
