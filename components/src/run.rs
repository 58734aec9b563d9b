//! Per-robot run bookkeeping beside the packed state: the controller, what the
//! `Contact` stage observed at the start of the step, the fall criteria and
//! the metrics accumulated at full rate.

use glam::DVec3;
use quadsim_engine::control::joint_pd::JointPd;
use quadsim_engine::control::prescribed::Prescribed;
use quadsim_engine::control::vmc::VmcCommand;
use quadsim_engine::control::walker::Walker;
use quadsim_engine::metrics::{FootSample, MetricsAccumulator};
use quadsim_engine::spatial::Transform;
use quadsim_validation::study_b_dynamics::StudyBTorqueComparison;

/// How a robot's actuators are commanded (written by the `Control` stage at
/// the controller rate and held between controller ticks).
#[derive(Clone, Debug, Default)]
pub enum Controller {
    /// No actuation: the joints are limp.
    #[default]
    None,
    /// Joint-space PD toward fixed targets.
    JointPd(JointPd),
    /// Study A's walking controller: gait, VMC, force QP, swing legs.
    Walker(Box<Walker>),
    /// Study B's prescribed trot (joint angles from foot-trajectory IK).
    Prescribed(Box<PrescribedRun>),
    /// Joint commands from another process (`kind = "external"`).
    External(crate::ExternalJoint),
}

/// The `prescribed` controller with its run bookkeeping.
#[derive(Clone, Debug)]
pub struct PrescribedRun {
    /// The controller (its reference is refreshed every step in hybrid
    /// mode, at the controller rate in PD mode).
    pub controller: Prescribed,
    /// Study B's Table 4 comparison, accumulated every
    /// `sample_every_steps` steps once the trajectory's ramp is over
    /// (hybrid mode on Study B's robot only; `None` otherwise).
    pub study_b: Option<StudyBTorqueComparison>,
    /// Steps between samples of the comparison (the controller rate).
    pub sample_every_steps: u64,
    /// Steps taken.
    pub steps: u64,
}

impl PrescribedRun {
    /// After a hybrid step: the torques that realised the step (N·m, joints
    /// only) against Study B's leg model on the reference the step started
    /// from, on every `sample_every_steps`-th step after the ramp.
    pub fn record_step(&mut self, model: &quadsim_engine::Model, tau_joints: &[f64]) {
        let due = self.steps.is_multiple_of(self.sample_every_steps.max(1));
        self.steps += 1;
        let c = &self.controller;
        if let Some(cmp) = &mut self.study_b
            && due
            && c.reference_time_s() > c.params.trot.ramp_s
        {
            cmp.sample(c, model, tau_joints);
        }
    }
}

impl Controller {
    /// The joint targets (rad), when the controller tracks some.
    pub fn joint_targets(&self) -> Option<&[f64]> {
        match self {
            Controller::None => None,
            Controller::JointPd(pd) => Some(&pd.target_rad),
            Controller::Walker(w) => Some(w.joint_targets()),
            Controller::Prescribed(p) => Some(p.controller.q_ref()),
            Controller::External(e) => Some(&e.target_rad),
        }
    }
}

/// The robot's state as the `Contact` stage saw it at the start of the step,
/// after updating the contact states.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Observation {
    /// Time of the observation (s).
    pub t_s: f64,
    /// Base placement in the world.
    pub base: Transform,
    /// Height of the base origin above the terrain beneath it (m; +∞ over no ground).
    pub base_height_above_ground_m: f64,
    /// Whole-body centre of mass (m, world).
    pub com_m: DVec3,
    /// CoM velocity (m/s, world).
    pub com_velocity_mps: DVec3,
    /// Height of the CoM above the terrain beneath it (m).
    pub com_height_above_ground_m: f64,
    /// Joint angles (rad) and velocities (rad/s) at the observation.
    pub q_joints: Vec<f64>,
    /// Joint velocities (rad/s).
    pub qd_joints: Vec<f64>,
    /// Feet (the first `n_feet` contact points).
    pub feet: Vec<FootSample>,
    /// The fall criteria hold (see `scenarios/README.md`).
    pub fallen: bool,
}

/// Fall criteria of one robot.
#[derive(Clone, Debug, PartialEq)]
pub struct FallCriteria {
    /// Points checked geometrically every step, whether or not they are
    /// contact points: the torso box's corners and the knees (body index,
    /// point in the body frame, m). One at or below the terrain is a fall.
    pub body_points: Vec<(usize, glam::DVec3)>,
    /// Tilt (angle between base z and world z) beyond which the robot has fallen (rad).
    pub max_tilt_rad: f64,
    /// Base height above ground below which the robot has fallen (m): 50 % of nominal.
    pub min_base_height_m: f64,
}

impl Default for FallCriteria {
    fn default() -> Self {
        Self {
            body_points: Vec::new(),
            max_tilt_rad: 60f64.to_radians(),
            min_base_height_m: 0.0,
        }
    }
}

/// Run bookkeeping of one robot.
#[derive(Clone, Debug)]
pub struct RobotRun {
    /// The actuator command law.
    pub controller: Controller,
    /// How many of the contact points (the first ones) are feet.
    pub n_feet: usize,
    /// Fall criteria.
    pub fall: FallCriteria,
    /// Latest observation.
    pub observation: Observation,
    /// Metrics, recorded every step by the `Publish` stage.
    pub metrics: MetricsAccumulator,
    /// Per-joint actuator load (peak torque share, time at the limits).
    pub actuators: quadsim_engine::actuators::ActuatorStats,
    /// ∫ commanded forward speed dt (m) and the time it covers (s): the
    /// walking command as ramped, against which speed tracking is judged.
    pub commanded_distance_m: (f64, f64),
    /// Scratch: saturated actuator torques of the joints (N·m).
    pub tau_joints: Vec<f64>,
    /// Velocity commands for the walking controller, `(t_s, command)`,
    /// sorted by time; applied at the first controller tick at or after `t_s`.
    pub commands: Vec<(f64, VmcCommand)>,
    /// The first divergence seen after a step (checked by the step's robot
    /// pass after every step): the time after that step (s) and what
    /// diverged. A run stops on it (`quadsim run`), reporting this step
    /// even when it stops a few steps later, at the end of a pass.
    pub diverged: Option<(f64, quadsim_engine::divergence::Divergence)>,
}

impl Default for RobotRun {
    fn default() -> Self {
        Self {
            controller: Controller::None,
            n_feet: 0,
            fall: FallCriteria::default(),
            observation: Observation::default(),
            metrics: MetricsAccumulator::new(0.0, 0.0),
            actuators: Default::default(),
            commanded_distance_m: (0.0, 0.0),
            tau_joints: Vec::new(),
            commands: Vec::new(),
            diverged: None,
        }
    }
}

/// The controller rate as a step divisor: controllers run on steps where
/// `step % every_steps == 0` (500 Hz at dt = 0.5 ms: every 4th step) and their
/// command is held in between.
#[derive(bevy_ecs::prelude::Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct ControlRate {
    /// Steps per controller tick (≥ 1).
    pub every_steps: u64,
}

impl Default for ControlRate {
    fn default() -> Self {
        Self { every_steps: 1 }
    }
}

/// The default ground plane (outside every terrain), kept apart from the
/// terrain entities so that recompiling the union keeps it.
#[derive(bevy_ecs::prelude::Resource, Clone, Debug, Default)]
pub struct DefaultGroundPlane(pub Option<quadsim_engine::terrain::DefaultGround>);
