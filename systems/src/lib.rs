//! quadsim's bevy_ecs systems: the compile stage that turns robot entities into
//! packed engine models, and the fixed-step schedule that advances them.
//!
//! Each [`Simulation::step`] runs two schedules:
//!
//! 1. [`CompileSchedule`]: robots whose description components changed are
//!    recompiled (never inside a step); skipped when its [`CompileGate`]
//!    sees nothing it could act on;
//! 2. [`StepSchedule`]: the [`SimSystems`] stages `Sense → Gait → Control → Contact →
//!    Dynamics → Integrate → Publish`, with robots stepped in parallel on
//!    the world's [`SimThreadPool`](quadsim_components::SimThreadPool), block
//!    by block through all their stages by default ([`step_robot_pass`]).

mod blocks;
mod compile;
mod contact;
mod control;
mod ground;
mod log;
mod metrics;
mod payload;
mod publish;
mod schedule;
mod sense;
mod simulation;
mod step;
mod workspace;

pub use blocks::{PassSteps, plan_blocks, step_robot_pass};
pub use compile::{
    CompileGate, CompileSchedule, DirtyRobots, SharedModels, add_edit_observers,
    build_compile_schedule, compile_dirty_robots, mark_dirty_robots,
};
pub use contact::{height_above_ground, observe_robot, update_contacts};
pub use control::{control_robot, control_robot_at, control_stage, run_controllers};
pub use ground::compile_ground;
pub use log::{
    FootLog, LogChannel, LogRecord, LogSink, Logger, MonitorChannel, PARALLEL_SAMPLING_MIN_ROBOTS,
    Records, RobotInfo, RobotSample, SampleChannel, SampleView, SensingLog, VelocityTargets,
    ViewRecord, finish_logging, finish_sampling, frame_parents, log_due, log_step, log_steps,
    logs_due, start_logging, start_sampling, start_sampling_each, step_time_ns, with_fresh_views,
};
pub use metrics::{check_divergence, record_metrics, record_robot};
pub use payload::apply_payload_events;
pub use publish::{pose_sync_due, sync_link_poses};
pub use schedule::{
    SimSystems, StepSchedule, build_step_schedule, register_contact, register_control,
    register_dynamics, register_gait, register_integrate, register_publish, register_sense,
};
pub use sense::{sense_robot, sense_robots};
pub use simulation::{MAX_PASS_STEPS, Simulation};
pub use step::{advance_clock, plan_groups, step_robot, step_robots};
pub use workspace::{WorkerWorkspace, WorkerWorkspaces};
