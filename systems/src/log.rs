//! Logging: samples of every logged robot taken from the simulation in the
//! `Publish` stage and handed to a [`LogSink`] (the root crate's MCAP writer).
//!
//! # What a sample holds, and when
//! A step runs `Control → Contact → … → Integrate → Publish` and takes the
//! state from `t_j = j·dt` to `t_{j+1}`. Everything the simulation used *at*
//! `t_j` is still at hand in that step's `Publish` stage: the state
//! `(q_j, v_j)` (kept here as a snapshot, because integration has overwritten
//! the robot's own copy), the [`Observation`](quadsim_components::Observation)
//! of the `Contact` stage (CoM position and velocity), the contact states the
//! step used, and the actuator command applied over the step. So the sample
//! for `t_j` is written in step `j`'s `Publish` stage. The kinematics at the
//! snapshot (link poses, base twist) are the robot's own, which a
//! semi-implicit Euler step leaves at its start state (its kinematics cache
//! says whether they are; else they are computed again, with the engine's
//! own function); the contact forces are evaluated there again (with the
//! very contact states the step used, so they equal the forces of the step's
//! first derivative evaluation). The state after the last step, `t_N`, is sampled
//! by [`finish_logging`], which runs the `Contact` and `Control` systems once
//! more at that state, exactly as the next step would.
//!
//! A robot is sampled when `j` is a multiple of its own decimation `d` (the
//! logger's [`Logger::every_steps`] unless [`start_sampling_each`] gave it
//! another), so a run of `N` steps logs `⌊N / d⌋ + 1` samples of it, `t = 0`
//! included. Robots of one instant share one [`LogRecord::Step`]; a robot not
//! due at that instant is simply absent from it.
//!
//! The sampling is cheap (a contact evaluation and a few copies, on the steps
//! that sample or snapshot only; a sink keeping its own record per robot,
//! such as the live monitor's frame, writes it from a borrowed
//! [`SampleView`] on the thread pool beside the robot's sampling, with no
//! sample made, [`LogSink::takes_records`]); encoding and compression happen in
//! the sink, off the simulation thread.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use glam::{DQuat, DVec3};
use quadsim_components::{
    ControlRate, Controller, Robot, RobotBatch, RobotIndex, RobotSim, SimClock, SimThreadPool,
    describe_robot,
};
use quadsim_engine::contact::{ContactEval, evaluate};
use quadsim_engine::description::RobotDescription;
use quadsim_engine::dispatch::forward_kinematics;
use quadsim_engine::kinematics::frame_pose;
use quadsim_engine::model::JointType;
use quadsim_engine::spatial::{Transform, rpy_from_rot};
use quadsim_engine::{Data, Model};

use crate::contact::update_contacts;
use crate::control::run_controllers;

/// Where samples go. Implementations must not block for long: `send` runs on
/// the simulation thread (the MCAP sink forwards records to a writer thread).
pub trait LogSink: Send + Sync + 'static {
    /// Takes one record; records arrive in simulation-time order.
    fn send(&mut self, record: LogRecord);

    /// Passes on whatever the sink holds back (the log is about to end).
    fn flush(&mut self) {}

    /// Whether the sink keeps its own record of each robot ([`ViewRecord`],
    /// made once per robot by [`LogSink::new_record`]), written from the
    /// robot's view by [`LogSink::write_record`] on the thread pool right
    /// after the robot is prepared, and handed over per instant by
    /// [`LogSink::send_records`], instead of [`LogRecord::Step`] records.
    fn takes_records(&self) -> bool {
        false
    }

    /// A new record slot for one robot, kept by the logger with the robot
    /// and rewritten in place at each of its samples (its previous content
    /// is the robot's last record). Called once per followed robot when the
    /// logger starts, never per step.
    fn new_record(&self) -> ViewRecord {
        Box::new(())
    }

    /// Writes `record` (one of [`LogSink::new_record`]'s) from the robot's
    /// view at step index `step`. Runs on the world's thread pool, for
    /// different robots at once; it must not block and should not allocate.
    fn write_record(&self, record: &mut ViewRecord, step: u64, view: &SampleView<'_>) {
        let _ = (record, step, view);
    }

    /// One instant's records (those of the robots sampled at step index
    /// `step`, time `t_ns`, freshly written), in the logger's order; called
    /// instead of [`LogSink::send`] with a [`LogRecord::Step`] when
    /// [`LogSink::takes_records`].
    fn send_records(&mut self, t_ns: u64, step: u64, records: Records<'_>) {
        let _ = (t_ns, step, records);
    }

    /// Whether the sink reads only the feet's contacts from its views
    /// ([`SampleView::foot`]; not the other contact points, e.g. knees and
    /// torso corners, which [`RobotSample::com_acceleration_mps2`] sums):
    /// then only the feet are evaluated, and its views'
    /// [`SampleView::evals`] hold the feet only. Applies to sinks that take
    /// records.
    fn feet_contacts_only(&self) -> bool {
        false
    }
}

/// A sink's own record of one robot ([`LogSink::takes_records`]), e.g. the
/// live monitor's shared-memory frame; the sink downcasts it to its type.
pub type ViewRecord = Box<dyn std::any::Any + Send + Sync>;

/// The records of one instant ([`LogSink::send_records`]), in the logger's
/// order: borrowed, no copy and no allocation.
pub struct Records<'a> {
    jobs: std::slice::Iter<'a, SampleJob<'a>>,
}

impl std::fmt::Debug for Records<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Records")
            .field("len", &self.jobs.len())
            .finish()
    }
}

impl<'a> Iterator for Records<'a> {
    type Item = &'a (dyn std::any::Any + Send + Sync);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        self.jobs.next().map(|job| {
            let r: &'a Followed = &*job.robot;
            &**r.record.as_ref().expect("the logger made every record")
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.jobs.size_hint()
    }
}

impl ExactSizeIterator for Records<'_> {}

/// One robot's static description, sent before its first sample and again
/// whenever its model is recompiled.
#[derive(Clone, Debug)]
pub struct RobotInfo {
    /// Instance name (the scenario's `robots[].name`).
    pub name: String,
    /// The compiled model (joint, link and foot names; sizes).
    pub model: Arc<Model>,
    /// The description (link shapes for a 3D scene).
    pub description: RobotDescription,
    /// Whether per-step samples are logged for this robot.
    pub logged: bool,
}

impl RobotInfo {
    /// Names of the actuated joints, in velocity order (nv − base − the
    /// compliant payloads' trailing coordinates).
    pub fn joint_names(&self) -> Vec<String> {
        let m = &self.model;
        (m.base_nv()..m.actuated_nv())
            .map(|i| m.joint_name[m.v_body[i]].clone())
            .collect()
    }

    /// Names of the feet, in the model's foot order.
    pub fn foot_names(&self) -> Vec<String> {
        self.model
            .feet
            .iter()
            .map(|&f| self.model.frames[f].name.clone())
            .collect()
    }
}

/// What a robot's sensors read at a sample: their latest outputs (noise
/// included) and the base estimate (`docs/sensors.md`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensingLog {
    /// IMU specific force (m/s²) and angular velocity (rad/s), torso frame.
    pub imu: Option<(DVec3, DVec3)>,
    /// Encoder angles (rad), actuated joints.
    pub encoder_position_rad: Option<Vec<f64>>,
    /// Encoder velocity estimates (rad/s).
    pub encoder_velocity_radps: Option<Vec<f64>>,
    /// Contact flags the controller reads (sensed, else true), foot order.
    pub contact: Vec<bool>,
    /// The base state estimate.
    pub estimate: Option<quadsim_engine::estimation::BaseEstimate>,
    /// Contact sensors' measured normal forces (N), foot order, when the
    /// sensors output forces (`force_output`).
    pub contact_force_n: Option<Vec<f64>>,
    /// The latest delivered motion-capture pose (captured `latency` before
    /// it was delivered), when mocap is on and has delivered one.
    pub mocap: Option<quadsim_engine::sensors::MocapSample>,
}

/// One foot at the sample's instant (world frame, SI).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootLog {
    /// The foot sphere touches the ground.
    pub in_contact: bool,
    /// Friction is at the cone's limit (the foot slides).
    pub slipping: bool,
    /// Penetration depth (m, ≥ 0).
    pub penetration_m: f64,
    /// Normal force magnitude (N, ≥ 0).
    pub normal_force_n: f64,
    /// Ground reaction force on the foot (N, world).
    pub force_n: DVec3,
    /// Where the ground force acts: the sphere's deepest point in contact,
    /// else its lowest point (m, world).
    pub position_m: DVec3,
    /// The leg's gait clock phase in [0, 1) from the walking controller's
    /// scheduler (`None` without a gait).
    pub gait_phase: Option<f64>,
}

/// One robot at one instant `t_j`. Frames: `world` is z up; "base" quantities
/// are the root link's frame origin; twists are of that origin, in world axes.
#[derive(Clone, Debug)]
pub struct RobotSample {
    /// Index of the robot in the last [`LogRecord::Robots`] list.
    pub robot: usize,
    /// Generalised position (Pinocchio conventions, nq).
    pub q: Vec<f64>,
    /// Generalised velocity (nv): base twist in the base frame, then joints.
    pub v: Vec<f64>,
    /// Base pose in the world.
    pub base_position_m: DVec3,
    /// Base orientation (base → world, unit quaternion).
    pub base_orientation: DQuat,
    /// Velocity of the base origin (m/s, world axes).
    pub base_linear_mps: DVec3,
    /// Angular velocity of the base (rad/s, world axes).
    pub base_angular_radps: DVec3,
    /// Roll, pitch, yaw of the base (rad; `R = Rz(yaw) Ry(pitch) Rx(roll)`).
    pub rpy_rad: DVec3,
    /// Whole-body centre of mass (m, world).
    pub com_m: DVec3,
    /// CoM velocity (m/s, world).
    pub com_velocity_mps: DVec3,
    /// CoM acceleration (m/s², world): Newton's law with the external forces
    /// evaluated at this instant, `g + (Σ contact forces + Σ active pushes) / m`.
    pub com_acceleration_mps2: DVec3,
    /// Joint angles (rad) and velocities (rad/s), velocity order.
    pub joint_position: Vec<f64>,
    /// Joint velocities (rad/s).
    pub joint_velocity: Vec<f64>,
    /// Actuator torques that act over the step (N·m): the motors' torques
    /// inside their envelopes, or the command after saturation ([`SampleView::joint_effort`]).
    pub joint_effort: Vec<f64>,
    /// The controller's command before saturation (N·m).
    pub joint_effort_command: Vec<f64>,
    /// Joint targets of the controller (rad), when it tracks some.
    pub joint_position_desired: Option<Vec<f64>>,
    /// Desired joint velocities (rad/s), when the controller has targets.
    pub joint_velocity_desired: Option<Vec<f64>>,
    /// Feet in the model's foot order.
    pub feet: Vec<FootLog>,
    /// The virtual wrench of virtual model control at its last tick: force
    /// (N) and torque about the CoM (N·m), world axes; `None` without VMC.
    pub virtual_wrench: Option<(DVec3, DVec3)>,
    /// The robot's sensors and estimate; `None` for a robot without sensors.
    pub sensing: Option<SensingLog>,
    /// Every link frame (one per `model.frames` entry) in its parent frame
    /// ([`frame_parents`]; the world for the base link): translation (m) and
    /// rotation, exact from the joint angles, so fixed offsets and the zero
    /// components of one-axis rotations are exactly constant. Empty for a
    /// channel without them ([`SampleChannel::LINK_TRANSFORMS`]).
    pub link_transforms: Vec<(DVec3, DQuat)>,
}

/// The parent of every link frame of `model` for a transform tree: a body's
/// first frame hangs from the first frame of its parent body (`None`: the
/// base's, whose parent is the world); other frames of a body (links merged
/// by fixed joints) hang from its first frame.
pub fn frame_parents(model: &Model) -> Vec<Option<usize>> {
    let primary = |b: usize| model.frames.iter().position(|f| f.body == b);
    model
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let first = primary(f.body);
            if first != Some(i) {
                first
            } else if f.body == 0 {
                None
            } else {
                primary(model.parent[f.body])
            }
        })
        .collect()
}

/// A rigid transform as (translation, rotation): `p_parent = t + r·p_child`.
type Rigid = (DVec3, DQuat);

/// How one link frame's transform in its parent frame is made (see
/// [`tf_plan`]): the parts that do not depend on the state are composed
/// once per model, so a sample composes at most three transforms per frame.
#[derive(Clone, Copy, Debug)]
enum TfFrame {
    /// A frame hanging from the world: its world pose from the kinematics.
    Root,
    /// A frame fixed in its parent frame (links merged by fixed joints).
    Fixed(Rigid),
    /// `pre ∘ joint motion(q) ∘ post`: `pre` = parent frame → joint frame,
    /// `post` = joint body → this frame.
    Joint {
        /// Parent frame to the joint frame.
        pre: Rigid,
        /// The joint's body to this frame.
        post: Rigid,
    },
}

fn quat_of(t: &Transform) -> DQuat {
    if t.rot == glam::DMat3::IDENTITY {
        DQuat::IDENTITY
    } else {
        DQuat::from_mat3(&t.rot).normalize()
    }
}

fn compose((ta, qa): Rigid, (tb, qb): Rigid) -> Rigid {
    (ta + qa * tb, qa * qb)
}

/// The state-independent parts of every link frame's transform in its
/// parent frame ([`frame_parents`]), computed once per model.
fn tf_plan(model: &Model, parents: &[Option<usize>]) -> Vec<TfFrame> {
    let in_body = |f: usize| {
        let p = &model.frames[f].placement;
        (p.trans, quat_of(p))
    };
    let inverse = |(t, r): Rigid| (-(r.inverse() * t), r.inverse());
    (0..model.frames.len())
        .map(|f| {
            let b = model.frames[f].body;
            match parents[f] {
                None => TfFrame::Root,
                Some(pf) if model.frames[pf].body == b => {
                    TfFrame::Fixed(compose(inverse(in_body(pf)), in_body(f)))
                }
                Some(pf) => {
                    let x = &model.placement[b];
                    TfFrame::Joint {
                        pre: compose(inverse(in_body(pf)), (x.trans, quat_of(x))),
                        post: in_body(f),
                    }
                }
            }
        })
        .collect()
}

/// The transforms of [`RobotSample::link_transforms`] at joint angles `q`
/// (world poses in `data` for the base link and for frames without a parent body frame).
fn link_transforms(
    model: &Model,
    data: &Data,
    q: &[f64],
    base: DQuat,
    plan: &[TfFrame],
) -> Vec<(DVec3, DQuat)> {
    plan.iter()
        .enumerate()
        .map(|(f, how)| match *how {
            TfFrame::Root => {
                let pose = frame_pose(model, data, f);
                if f == 0 && model.frames[f].placement == Transform::IDENTITY {
                    (pose.trans, base)
                } else {
                    (pose.trans, quat_of(&pose))
                }
            }
            TfFrame::Fixed(t) => t,
            TfFrame::Joint { pre, post } => {
                let b = model.frames[f].body;
                let qi = q[model.idx_q[b]];
                let axis = model.axis[b];
                let motion = match model.joint_type[b] {
                    JointType::Revolute => (DVec3::ZERO, DQuat::from_axis_angle(axis, qi)),
                    JointType::Prismatic => (axis * qi, DQuat::IDENTITY),
                    JointType::Free | JointType::Anchored => (DVec3::ZERO, DQuat::IDENTITY),
                };
                compose(compose(pre, motion), post)
            }
        })
        .collect()
}

/// What the logger hands to its sink.
#[derive(Clone, Debug)]
pub enum LogRecord {
    /// Every robot of the world (logged or not) in the logger's order.
    Robots {
        /// Simulation time (ns).
        t_ns: u64,
        /// The robots.
        robots: Vec<RobotInfo>,
    },
    /// Samples of every logged robot at one instant.
    Step {
        /// Simulation time (ns).
        t_ns: u64,
        /// One sample per logged robot, in the logger's order.
        samples: Vec<RobotSample>,
    },
}

/// A robot the logger follows.
#[derive(Debug)]
struct Followed {
    entity: Entity,
    logged: bool,
    /// Steps between this robot's samples (≥ 1; a multiple of the logger's tick).
    every: u64,
    /// Model the snapshot belongs to.
    model: Option<Arc<Model>>,
    /// Model of the last [`LogRecord::Robots`] record (a robot sampled less
    /// often than others may be recompiled between its snapshots).
    announced: Option<Arc<Model>>,
    /// Kinematics scratch for the snapshot, made when first needed: the
    /// robot's own `data` usually holds them ([`prepare`]).
    data: Option<Data>,
    /// Contact evaluations at the snapshot (one per contact point).
    evals: Vec<ContactEval>,
    /// [`tf_plan`] of the model.
    tf: Vec<TfFrame>,
    /// `(q, v)` at the start of the current step.
    q: Vec<f64>,
    v: Vec<f64>,
    /// The sink's record of this robot, when it [takes records](LogSink::takes_records).
    record: Option<ViewRecord>,
}

impl Followed {
    /// Whether the per-model parts (scratch, transform plan) are `model`'s.
    fn follows(&self, model: &Arc<Model>) -> bool {
        self.model.as_ref().is_some_and(|m| Arc::ptr_eq(m, model))
    }

    /// Takes `model` (the robot was spawned or recompiled): its transform
    /// plan, and a scratch made again when first needed.
    fn follow(&mut self, model: &Arc<Model>) {
        self.data = None;
        self.tf = tf_plan(model, &frame_parents(model));
        self.model = Some(model.clone());
    }
}

/// Tells apart independent samplers of the same kind: the MCAP log
/// ([`LogChannel`]) and e.g. the live monitor. Each channel has its own
/// [`Logger`] resource, rate and snapshot, so one never changes what the
/// other samples or when.
pub trait SampleChannel: Send + Sync + 'static {
    /// Whether samples carry [`RobotSample::link_transforms`] (the log's
    /// `/tf`); a channel without a use for them skips their cost.
    const LINK_TRANSFORMS: bool = true;
}

/// The run's log (`log.mcap`).
#[derive(Debug, Clone, Copy, Default)]
pub struct LogChannel;
impl SampleChannel for LogChannel {}

/// The live monitor (the root crate publishes its samples over shared
/// memory, docs/monitor.md). Sampled after the log in the `Publish` stage.
#[derive(Debug, Clone, Copy, Default)]
pub struct MonitorChannel;
impl SampleChannel for MonitorChannel {
    /// Frames carry no link transforms.
    const LINK_TRANSFORMS: bool = false;
}

/// The logging resource: which robots, how often, and the sink. Present only
/// while a log is being written ([`start_logging`] … [`finish_logging`], or
/// [`start_sampling`] … [`finish_sampling`] for another channel).
#[derive(Resource)]
pub struct Logger<C: SampleChannel = LogChannel> {
    /// The logger's tick (≥ 1): every robot's decimation is a multiple of it
    /// (their greatest common divisor), so the `Publish` stage runs only on
    /// steps that some robot samples or snapshots.
    pub every_steps: u64,
    robots: Vec<Followed>,
    sink: Box<dyn LogSink>,
    /// Step index of the last sample written.
    last_sampled: Option<u64>,
    channel: std::marker::PhantomData<fn() -> C>,
}

impl<C: SampleChannel> std::fmt::Debug for Logger<C> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Logger")
            .field("every_steps", &self.every_steps)
            .field("robots", &self.robots.len())
            .field("last_sampled", &self.last_sampled)
            .finish_non_exhaustive()
    }
}

/// Simulation time of step index `j` (ns), from the step count so it does not drift.
pub fn step_time_ns(step: u64, dt_s: f64) -> u64 {
    (step as f64 * dt_s * 1e9).round() as u64
}

/// Starts a log: snapshots every robot's state, sends the [`LogRecord::Robots`]
/// record and inserts the [`Logger`]. `robots` lists root entities in the
/// order the log should follow, each with whether per-step samples are taken.
pub fn start_logging(
    world: &mut World,
    sink: Box<dyn LogSink>,
    every_steps: u64,
    robots: &[(Entity, bool)],
) {
    start_sampling::<LogChannel>(world, sink, every_steps, robots);
}

/// [`start_logging`] for channel `C` (its own rate, snapshot and sink).
pub fn start_sampling<C: SampleChannel>(
    world: &mut World,
    sink: Box<dyn LogSink>,
    every_steps: u64,
    robots: &[(Entity, bool)],
) {
    let each: Vec<(Entity, Option<u64>)> = robots
        .iter()
        .map(|&(e, logged)| (e, logged.then_some(every_steps)))
        .collect();
    start_sampling_each::<C>(world, sink, every_steps, &each);
}

/// [`start_sampling`] with a decimation per robot: `Some(d)` samples the
/// robot every `d` steps (`d ≥ 1`), `None` takes no per-step samples of it
/// (it is still listed in [`LogRecord::Robots`]). `every_steps` is the
/// decimation of the record only when no robot is sampled.
pub fn start_sampling_each<C: SampleChannel>(
    world: &mut World,
    sink: Box<dyn LogSink>,
    every_steps: u64,
    robots: &[(Entity, Option<u64>)],
) {
    let tick = robots
        .iter()
        .filter_map(|&(_, d)| d.map(|d| d.max(1)))
        .reduce(gcd)
        .unwrap_or(every_steps.max(1));
    let mut logger = Logger::<C> {
        every_steps: tick,
        robots: robots
            .iter()
            .map(|&(entity, every)| Followed {
                entity,
                logged: every.is_some(),
                every: every.map_or(tick, |d| d.max(1)),
                model: None,
                announced: None,
                data: None,
                evals: Vec::new(),
                tf: Vec::new(),
                q: Vec::new(),
                v: Vec::new(),
                record: sink.takes_records().then(|| sink.new_record()),
            })
            .collect(),
        sink,
        last_sampled: None,
        channel: std::marker::PhantomData,
    };
    let step = world.resource::<SimClock>().step;
    announce_if_changed(world, &mut logger, true, step);
    snapshot(world, &mut logger, None);
    world.insert_resource(logger);
}

/// Greatest common divisor (Euclid).
fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// Ends the log: when `final_sample` is set and the current step index is a
/// multiple of the rate, samples the current state (running the `Contact` and
/// `Control` systems at it first, as the next step would; the state itself is
/// not changed). Removes the [`Logger`] and returns its sink.
pub fn finish_logging(world: &mut World, final_sample: bool) -> Option<Box<dyn LogSink>> {
    finish_sampling::<LogChannel>(world, final_sample)
}

/// [`finish_logging`] for channel `C`. With `final_sample`, the `Contact` and
/// `Control` systems run once more, so finish at most one channel that way.
pub fn finish_sampling<C: SampleChannel>(
    world: &mut World,
    final_sample: bool,
) -> Option<Box<dyn LogSink>> {
    let n = world.resource::<SimClock>().step;
    let due = world
        .get_resource::<Logger<C>>()
        .map(|l| n.is_multiple_of(l.every_steps) && l.last_sampled != Some(n))?;
    if final_sample && due {
        world
            .run_system_once(update_contacts)
            .expect("the simulation's resources exist");
        if world.contains_resource::<ControlRate>() {
            world
                .run_system_once(run_controllers)
                .expect("the simulation's resources exist");
        }
        world.resource_scope(|world, mut logger: Mut<Logger<C>>| {
            sample_all(world, &mut logger, n);
        });
    }
    world.remove_resource::<Logger<C>>().map(|mut l| {
        l.sink.flush();
        l.sink
    })
}

/// Run condition of [`log_step`]: a [`Logger`] exists and this step either
/// samples (the step started at a multiple of the rate) or must snapshot its
/// end state for the next step's sample. Other steps skip the system.
pub fn log_due<C: SampleChannel>(clock: Res<SimClock>, logger: Option<Res<Logger<C>>>) -> bool {
    logger.is_some_and(|l| logger_due(&l, clock.step))
}

/// Whether `logger` samples or snapshots at step `step` (see [`log_due`]).
pub(crate) fn logger_due<C: SampleChannel>(logger: &Logger<C>, step: u64) -> bool {
    let every = logger.every_steps;
    step.is_multiple_of(every) || (step > 0 && (step - 1).is_multiple_of(every))
}

/// Run condition of [`log_steps`]: [`log_due`] for the log or the live
/// monitor. One condition for both channels, because the step schedule
/// evaluates every run condition it holds on every step.
pub fn logs_due(
    clock: Res<SimClock>,
    log: Option<Res<Logger<LogChannel>>>,
    monitor: Option<Res<Logger<MonitorChannel>>>,
) -> bool {
    let step = clock.step;
    log.is_some_and(|l| logger_due(&l, step)) || monitor.is_some_and(|l| logger_due(&l, step))
}

/// The `Publish`-stage logging system: [`log_step`] for the log, then for
/// the live monitor (at its own rate, after the log's), each on the steps
/// its [`Logger`] is due ([`log_due`]).
pub fn log_steps(world: &mut World) {
    let step = world.resource::<SimClock>().step;
    if world
        .get_resource::<Logger<LogChannel>>()
        .is_some_and(|l| logger_due(l, step))
    {
        log_step::<LogChannel>(world);
    }
    if world
        .get_resource::<Logger<MonitorChannel>>()
        .is_some_and(|l| logger_due(l, step))
    {
        log_step::<MonitorChannel>(world);
    }
}

/// The `Publish`-stage system: samples the state the step started from when
/// its index is due, and snapshots the new state when the next step's is.
pub fn log_step<C: SampleChannel>(world: &mut World) {
    world.resource_scope(|world, mut logger: Mut<Logger<C>>| {
        let step = world.resource::<SimClock>().step;
        let j = step.saturating_sub(1);
        if step > 0 && j.is_multiple_of(logger.every_steps) && logger.last_sampled != Some(j) {
            // a model recompiled since the last sample: its names and shapes first
            announce_if_changed(world, &mut logger, false, j);
            sample_all(world, &mut logger, j);
        }
        if step.is_multiple_of(logger.every_steps) {
            snapshot(world, &mut logger, Some(step));
        }
    });
}

fn robot_sim(world: &World, entity: Entity) -> Option<&RobotSim> {
    let index = *world.get::<RobotIndex>(entity)?;
    world.resource::<RobotBatch>().get(index)
}

/// Sends the robot list when it is new or a model was recompiled.
fn announce_if_changed<C: SampleChannel>(
    world: &World,
    logger: &mut Logger<C>,
    force: bool,
    step: u64,
) {
    let changed = logger.robots.iter().any(|r| {
        let now = robot_sim(world, r.entity).map(|s| &s.model);
        match (now, &r.announced) {
            (Some(a), Some(b)) => !Arc::ptr_eq(a, b),
            (None, None) => false,
            _ => true,
        }
    });
    if !(force || changed) {
        return;
    }
    for r in &mut logger.robots {
        r.announced = robot_sim(world, r.entity).map(|s| s.model.clone());
    }
    let dt = world
        .get_resource::<quadsim_components::SimConfig>()
        .map_or(0.0, |c| c.dt_s);
    let t_ns = step_time_ns(step, dt);
    let robots = logger
        .robots
        .iter()
        .filter_map(|r| {
            let sim = robot_sim(world, r.entity)?;
            let name = world.get::<Robot>(r.entity).map_or_else(
                // (not the model's: robots of one design share it)
                || {
                    world
                        .get::<quadsim_components::RobotModelName>(r.entity)
                        .map_or_else(String::new, |n| n.0.clone())
                },
                |x| x.name.clone(),
            );
            Some(RobotInfo {
                name,
                model: sim.model.clone(),
                description: describe_robot(world, r.entity).unwrap_or_default(),
                logged: r.logged,
            })
        })
        .collect();
    logger.sink.send(LogRecord::Robots { t_ns, robots });
}

/// Copies the `(q, v)` (and model) of every followed robot that samples at
/// step index `due` (every robot with `None`) for its next sample.
fn snapshot<C: SampleChannel>(world: &World, logger: &mut Logger<C>, due: Option<u64>) {
    for r in &mut logger.robots {
        if due.is_some_and(|s| !(r.logged && s.is_multiple_of(r.every))) {
            continue;
        }
        let Some(sim) = robot_sim(world, r.entity) else {
            r.model = None;
            continue;
        };
        if !r.follows(&sim.model) {
            r.follow(&sim.model);
        }
        r.q.clear();
        r.q.extend_from_slice(&sim.state.q);
        r.v.clear();
        r.v.extend_from_slice(&sim.state.v);
    }
}

/// Robots sampled at one instant from which the sampling runs on the
/// world's thread pool (fewer: serially, where a fork–join costs more).
pub const PARALLEL_SAMPLING_MIN_ROBOTS: usize = 16;

/// One robot's sampling work at an instant (see [`sample_all`]).
struct SampleJob<'a> {
    robot: &'a mut Followed,
    sim: &'a RobotSim,
    index: usize,
    /// The robot's own `Data` holds the kinematics at the snapshot (else the
    /// follower's scratch does).
    cached: bool,
    out: Option<RobotSample>,
}

impl SampleJob<'_> {
    fn view(&self) -> SampleView<'_> {
        let r = &*self.robot;
        view_of(
            self.index,
            self.sim,
            self.cached,
            &r.q,
            &r.v,
            &r.data,
            &r.evals,
        )
    }
}

/// The view of a prepared robot (see [`SampleJob`]) from the follower's
/// parts, so its record can be borrowed mutably beside it.
fn view_of<'a>(
    robot: usize,
    sim: &'a RobotSim,
    cached: bool,
    q: &'a [f64],
    v: &'a [f64],
    scratch: &'a Option<Data>,
    evals: &'a [ContactEval],
) -> SampleView<'a> {
    SampleView {
        robot,
        q,
        v,
        sim,
        data: if cached {
            &sim.data
        } else {
            scratch.as_ref().expect("prepare made the scratch")
        },
        evals,
    }
}

/// Samples every logged robot due at step index `j` and sends one record
/// (or, to a sink that [takes records](LogSink::takes_records), its
/// records, each written right after its robot is prepared, on the same
/// worker).
/// Robots are prepared independently (each from its own snapshot and
/// scratch), in parallel on the world's [`SimThreadPool`] for a herd, and
/// collected in the logger's order, so the record does not depend on the
/// thread count.
fn sample_all<C: SampleChannel>(world: &World, logger: &mut Logger<C>, j: u64) {
    let dt = world.resource::<quadsim_components::SimConfig>().dt_s;
    let takes_records = logger.sink.takes_records();
    let feet_only = takes_records && logger.sink.feet_contacts_only();
    let mut jobs = Vec::new();
    // indices follow the `Robots` record, which lists robots that have a sim
    let mut index = 0;
    for r in &mut logger.robots {
        let Some(sim) = robot_sim(world, r.entity) else {
            continue;
        };
        let i = index;
        index += 1;
        if !(r.logged && j.is_multiple_of(r.every)) {
            continue;
        }
        if !r.follows(&sim.model) {
            // recompiled before this step: the step ran with the new model,
            // whose state sizes must match the snapshot's to sample it
            if r.q.len() != sim.model.nq || r.v.len() != sim.model.nv {
                continue;
            }
            r.follow(&sim.model);
        }
        jobs.push(SampleJob {
            robot: r,
            sim,
            index: i,
            cached: false,
            out: None,
        });
    }
    let sink = &*logger.sink;
    let work = |job: &mut SampleJob<'_>| {
        let r = &mut *job.robot;
        job.cached = prepare(job.sim, &r.q, &r.v, &mut r.data, &mut r.evals, feet_only);
        if takes_records {
            // the sink's record, written while this robot's data is in cache
            let Followed {
                q,
                v,
                data,
                evals,
                record,
                ..
            } = r;
            let view = view_of(job.index, job.sim, job.cached, q, v, data, evals);
            let record = record.as_mut().expect("the logger made every record");
            sink.write_record(record, j, &view);
        } else {
            let tf = C::LINK_TRANSFORMS.then_some(&job.robot.tf[..]);
            let sample = job.view().sample(tf);
            job.out = Some(sample);
        }
    };
    match world.get_resource::<SimThreadPool>() {
        Some(pool) if jobs.len() >= PARALLEL_SAMPLING_MIN_ROBOTS => pool.for_each(&mut jobs, work),
        _ => jobs.iter_mut().for_each(work),
    }
    logger.last_sampled = Some(j);
    let t_ns = step_time_ns(j, dt);
    if takes_records {
        let records = Records { jobs: jobs.iter() };
        logger.sink.send_records(t_ns, j, records);
        return;
    }
    let samples = jobs.into_iter().filter_map(|job| job.out).collect();
    logger.sink.send(LogRecord::Step { t_ns, samples });
}

/// Makes the kinematics (with velocities) at the snapshot `(q, v)` available
/// and evaluates every contact (the feet only with `feet_only`) there into
/// `evals`, with the contact states the step used. Returns whether the
/// robot's own `Data` holds those kinematics: a semi-implicit Euler step
/// leaves in it the kinematics of its only derivative evaluation, at its
/// start state, which is the snapshot (the kinematics cache's key, `q` and
/// `v` bit for bit, says whether it does). Otherwise (RK4's last stage; a state changed between the snapshot
/// and the step) forward kinematics runs in `scratch`. Either way the values
/// are the same bit for bit: the same function at the same state.
///
/// The contact evaluations are the very forces of the step's first
/// derivative evaluation (the only one for semi-implicit Euler, RK4's first
/// stage), not the states' own `force_n`, which the `Contact` stage computed
/// before moving the anchors of slipping feet.
fn prepare(
    sim: &RobotSim,
    q: &[f64],
    v: &[f64],
    scratch: &mut Option<Data>,
    evals: &mut Vec<ContactEval>,
    feet_only: bool,
) -> bool {
    let model = &sim.model;
    let cached = sim.data.kinematics_hold(model, q, v);
    let data = if cached {
        &sim.data
    } else {
        let d = scratch.get_or_insert_with(|| Data::new(model));
        forward_kinematics(model, d, q, v);
        &*d
    };
    let points = if feet_only {
        sim.run.n_feet.min(sim.contact.points.len())
    } else {
        sim.contact.points.len()
    };
    evaluate_contacts(sim, data, points, evals);
    cached
}

/// The first `points` contact points of `sim` (feet first) evaluated at the
/// kinematics in `data`, with the contact states the step used, into
/// `evals` (in point order).
fn evaluate_contacts(sim: &RobotSim, data: &Data, points: usize, evals: &mut Vec<ContactEval>) {
    let c = &sim.contact;
    evals.clear();
    evals.extend(
        c.points[..points]
            .iter()
            .zip(&c.states)
            .map(|(p, s)| evaluate(p, data, &c.terrain, s)),
    );
}

/// Calls `f` with views of `robots` (root entities, each with the `(q, v)`
/// to view it at; a view's `robot` is its position in the list), their
/// kinematics and contact evaluations computed afresh in scratch, never read
/// from the robots' kinematics caches; the rest (observation, contact
/// states, command, controller) is the robot's as it stands. A reference for
/// checks of the sampling (call it after the step from `(q, v)`), and views
/// for benchmarks. Robots without a simulation are left out.
pub fn with_fresh_views<R>(
    world: &World,
    robots: &[(Entity, &[f64], &[f64])],
    f: impl FnOnce(&[SampleView<'_>]) -> R,
) -> R {
    let prepared: Vec<_> = robots
        .iter()
        .enumerate()
        .filter_map(|(i, &(entity, q, v))| {
            let sim = robot_sim(world, entity)?;
            let mut data = Data::new(&sim.model);
            forward_kinematics(&sim.model, &mut data, q, v);
            let mut evals = Vec::new();
            evaluate_contacts(sim, &data, sim.contact.points.len(), &mut evals);
            Some((i, q, v, sim, data, evals))
        })
        .collect();
    let views: Vec<_> = prepared
        .iter()
        .map(|(i, q, v, sim, data, evals)| SampleView {
            robot: *i,
            q,
            v,
            sim,
            data,
            evals,
        })
        .collect();
    f(&views)
}

/// One robot at the instant `t_j` of a sample, borrowed from the simulation
/// and the sampler: everything a [`RobotSample`] holds, without a copy or an
/// allocation. The log's sample is made from it ([`SampleView::to_sample`]);
/// the live monitor writes its frames straight from views
/// ([`LogSink::write_record`]), so both carry the same values bit for bit.
/// Frames as in [`RobotSample`].
#[derive(Clone, Copy, Debug)]
pub struct SampleView<'a> {
    /// Index of the robot in the last [`LogRecord::Robots`] list.
    pub robot: usize,
    /// Generalised position at `t_j` (the sampler's snapshot, nq).
    pub q: &'a [f64],
    /// Generalised velocity at `t_j` (nv).
    pub v: &'a [f64],
    /// The robot as the step from `t_j` left it: model, observation (CoM),
    /// contact states, actuator command, controller, sensors.
    pub sim: &'a RobotSim,
    /// Kinematics with velocities at `(q, v)`.
    pub data: &'a Data,
    /// Every contact point's evaluation at `(q, v)` with the states the step
    /// used (the feet's only, for a sink that reads only them:
    /// [`LogSink::feet_contacts_only`]).
    pub evals: &'a [ContactEval],
}

/// Desired joint velocities of a controller with joint targets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VelocityTargets<'a> {
    /// The external controller's (rad/s).
    Given(&'a [f64]),
    /// Zero for each of this many joint targets (the target is held still).
    Zero(usize),
}

impl VelocityTargets<'_> {
    /// As a vector (rad/s).
    pub fn to_vec(&self) -> Vec<f64> {
        match *self {
            VelocityTargets::Given(v) => v.to_vec(),
            VelocityTargets::Zero(n) => vec![0.0; n],
        }
    }
}

impl<'a> SampleView<'a> {
    /// The robot's model.
    #[inline]
    pub fn model(&self) -> &'a Model {
        &self.sim.model
    }

    /// Base position in the world (m).
    #[inline]
    pub fn base_position_m(&self) -> DVec3 {
        self.data.pose[0].trans
    }

    /// Base orientation (base → world, unit quaternion).
    #[inline]
    pub fn base_orientation(&self) -> DQuat {
        let q = self.q;
        if self.model().is_floating() {
            DQuat::from_xyzw(q[3], q[4], q[5], q[6]).normalize()
        } else {
            DQuat::from_mat3(&self.data.pose[0].rot)
        }
    }

    /// Velocity of the base origin (m/s, world axes).
    #[inline]
    pub fn base_linear_mps(&self) -> DVec3 {
        self.data.vel[0].lin
    }

    /// Angular velocity of the base (rad/s, world axes).
    #[inline]
    pub fn base_angular_radps(&self) -> DVec3 {
        self.data.vel[0].ang
    }

    /// Roll, pitch, yaw of the base (rad; `R = Rz(yaw) Ry(pitch) Rx(roll)`).
    #[inline]
    pub fn rpy_rad(&self) -> DVec3 {
        rpy_from_rot(self.data.pose[0].rot)
    }

    /// Whole-body centre of mass (m, world), as the `Contact` stage observed it.
    #[inline]
    pub fn com_m(&self) -> DVec3 {
        self.sim.run.observation.com_m
    }

    /// CoM velocity (m/s, world).
    #[inline]
    pub fn com_velocity_mps(&self) -> DVec3 {
        self.sim.run.observation.com_velocity_mps
    }

    /// Joint angles (rad), actuated joints in velocity order.
    #[inline]
    pub fn joint_position(&self) -> &'a [f64] {
        let m = self.model();
        &self.q[m.base_nq()..m.actuated_nq()]
    }

    /// Joint velocities (rad/s).
    #[inline]
    pub fn joint_velocity(&self) -> &'a [f64] {
        let m = self.model();
        &self.v[m.base_nv()..m.actuated_nv()]
    }

    /// The controller's command before saturation (N·m).
    #[inline]
    pub fn joint_effort_command(&self) -> &'a [f64] {
        let m = self.model();
        &self.sim.tau_actuator[m.base_nv()..m.actuated_nv()]
    }

    /// Actuator torques that act over the step (N·m): with actuator models
    /// the motors' torques inside their envelopes
    /// ([`ActuatorBank::applied`](quadsim_engine::actuator_model::ActuatorBank::applied)),
    /// otherwise the command after saturation; the same torques as the
    /// metrics' (`summary.json`'s `peak_abs_torque_nm`, `peak_torque_nm`).
    #[inline]
    pub fn joint_effort(&self) -> impl ExactSizeIterator<Item = f64> + 'a {
        let m = self.model();
        let saturate = self.sim.workspace.passive.saturation;
        let applied = self.sim.workspace.actuators.as_ref().map(|b| b.applied());
        self.joint_effort_command()
            .iter()
            .zip(&m.effort_limit[m.base_nv()..])
            .enumerate()
            .map(move |(j, (&t, &lim))| match applied {
                Some(a) if j < a.len() => a[j],
                _ if saturate => t.clamp(-lim, lim),
                _ => t,
            })
    }

    /// Joint targets of the controller (rad), when it tracks some.
    #[inline]
    pub fn joint_position_desired(&self) -> Option<&'a [f64]> {
        self.sim.run.controller.joint_targets()
    }

    /// Desired joint velocities, when the controller has joint targets.
    #[inline]
    pub fn joint_velocity_desired(&self) -> Option<VelocityTargets<'a>> {
        match &self.sim.run.controller {
            Controller::External(e) => Some(VelocityTargets::Given(&e.target_radps)),
            _ => self
                .joint_position_desired()
                .map(|t| VelocityTargets::Zero(t.len())),
        }
    }

    /// Feet sampled (the model's first feet).
    #[inline]
    pub fn feet(&self) -> usize {
        self.sim.run.n_feet.min(self.evals.len())
    }

    /// Foot `i < feet()` (world frame).
    #[inline]
    pub fn foot(&self, i: usize) -> FootLog {
        let e = &self.evals[i];
        let p = &self.sim.contact.points[i];
        FootLog {
            in_contact: e.active,
            slipping: e.active && e.slipping,
            penetration_m: if e.active { e.depth_m } else { 0.0 },
            normal_force_n: if e.active { e.normal_force_n } else { 0.0 },
            force_n: if e.active { e.force_n() } else { DVec3::ZERO },
            position_m: if e.active {
                e.application_m
            } else {
                self.data.body_point_world(p.body, p.point_in_body) - DVec3::Z * p.radius_m
            },
            // the walker has one leg per foot, in the model's foot order
            gait_phase: self
                .walker()
                .and_then(|w| w.scheduler().legs().get(i))
                .map(|l| l.clock_phase),
        }
    }

    #[inline]
    fn walker(&self) -> Option<&'a quadsim_engine::control::walker::Walker> {
        match &self.sim.run.controller {
            Controller::Walker(w) => Some(w),
            _ => None,
        }
    }

    /// The log's sample (with every link frame's transform when
    /// `link_transforms`).
    pub fn to_sample(&self, link_transforms: bool) -> RobotSample {
        let plan = link_transforms.then(|| {
            let m = self.model();
            tf_plan(m, &frame_parents(m))
        });
        self.sample(plan.as_deref())
    }

    fn sample(&self, tf: Option<&[TfFrame]>) -> RobotSample {
        let (model, sim, q, v) = (self.model(), self.sim, self.q, self.v);
        let base_orientation = self.base_orientation();
        let virtual_wrench = self.walker().map(|w| {
            let f = w.wrench();
            (f.lin, f.ang)
        });
        // Newton's second law for the CoM with the forces acting at this instant.
        let mut f_ext = DVec3::ZERO;
        for e in self.evals.iter().filter(|e| e.active) {
            f_ext += e.force_n();
        }
        let t = sim.contact.time_s;
        for p in &sim.contact.pushes {
            if t >= p.start_s && t < p.end_s {
                f_ext += p.force_n;
            }
        }
        let com_acc = model.gravity + f_ext / model.total_mass;
        RobotSample {
            robot: self.robot,
            q: q.to_vec(),
            v: v.to_vec(),
            base_position_m: self.base_position_m(),
            base_orientation,
            base_linear_mps: self.base_linear_mps(),
            base_angular_radps: self.base_angular_radps(),
            rpy_rad: self.rpy_rad(),
            com_m: self.com_m(),
            com_velocity_mps: self.com_velocity_mps(),
            com_acceleration_mps2: com_acc,
            joint_position: self.joint_position().to_vec(),
            joint_velocity: self.joint_velocity().to_vec(),
            joint_effort: self.joint_effort().collect(),
            joint_effort_command: self.joint_effort_command().to_vec(),
            joint_position_desired: self.joint_position_desired().map(<[f64]>::to_vec),
            joint_velocity_desired: self.joint_velocity_desired().map(|t| t.to_vec()),
            feet: (0..self.feet()).map(|i| self.foot(i)).collect(),
            virtual_wrench,
            sensing: sim.sensing.as_deref().map(|x| SensingLog {
                imu: x
                    .suite
                    .imu
                    .as_ref()
                    .and_then(|i| i.last)
                    .map(|m| (m.accel_mps2, m.gyro_radps)),
                encoder_position_rad: x.suite.encoders.as_ref().map(|e| e.position_rad.clone()),
                encoder_velocity_radps: x.suite.encoders.as_ref().map(|e| e.velocity_radps.clone()),
                contact: x.contacts.clone(),
                estimate: x.estimator.as_ref().map(|e| e.estimate),
                contact_force_n: x
                    .suite
                    .contacts
                    .as_ref()
                    .filter(|c| c.params.force_output)
                    .map(|c| c.force_n.clone()),
                mocap: x.suite.mocap.as_ref().and_then(|m| m.last),
            }),
            link_transforms: tf.map_or_else(Vec::new, |p| {
                link_transforms(model, self.data, q, base_orientation, p)
            }),
        }
    }
}
