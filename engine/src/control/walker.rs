//! The walking controller of Study A: gait scheduler + Virtual Model Control +
//! stance-force QP + swing-leg tracking, composed per control tick.
//!
//! One [`Walker::tick`] (at the controller rate, 500 Hz by default):
//!
//! 1. **Gait**: the scheduler advances with the feet's contact flags
//!    ([`crate::gait::scheduler`]: clock-driven lift-off, contact-driven
//!    touchdown, load ramps).
//! 2. **Placement**: every swinging foot's touchdown target is the hip's
//!    ground projection plus Raibert's offset `v·T_st/2 + k (v − v_des)`
//!    (clipped), on the terrain beneath it.
//! 3. **VMC**: the virtual wrench `W` about the CoM from six spring–dampers
//!    plus gravity compensation ([`super::vmc`]).
//! 4. **Force distribution**: `W` over the loaded stance feet
//!    ([`super::force_qp`], friction pyramids about the terrain normal).
//! 5. **Stance torques** `τ = τ_id − Jᵀ f` (f = the ground's force on the
//!    foot); quad16's ankle, redundant for a point foot, holds the foot level
//!    by PD; a one-sided PD keeps the knee bent on its IK branch.
//! 6. **Swing**: the foot follows a min-jerk swing in the world; its
//!    reference, expressed in the *planned* base frame (level, at the target
//!    height), goes through closed-form leg IK to joint targets tracked by
//!    joint PD about an inverse-dynamics feed-forward `τ_id` (RNEA with the
//!    reference's joint accelerations, base held still).
//!
//! quad16's legs are 18 of its 28 kg, and three feedback paths through them
//! made it fall (each measured with `examples/walk_probe.rs` and its predecessor): swing PD without
//! feed-forward (diverged at ≥ 8 Hz even in place); swing targets in the
//! *measured* base frame (body roll/pitch moved the heavy swing legs, whose
//! reaction rolled the body further: in-place tilt 0.26 → 0.06 rad with the
//! planned frame); stance knees snapping through straight at speed. Feeding
//! the swing legs' reaction wrench (base rows of `τ_id`) to the QP made it
//! worse: during diagonal support the moment about the support line is not
//! realizable within friction.
//!
//! In flight (no stance foot) the stance torques are zero and only the swing
//! legs are driven. Sign conventions: see [`super::force_qp`] (torques) and
//! [`super::vmc`] (wrench).

use super::ground_plane::GroundPlane;
use crate::com::com_and_velocity;
use crate::data::Data;
use crate::description::RobotDescription;
use crate::gait::placement::{PlacementInput, PlacementParams, foot_target_world, raibert_offset};
use crate::gait::scheduler::{GaitScheduler, LegPhase, SchedulerParams};
use crate::gait::swing::ReachDown;
use crate::gait::{Gait, GaitError};
use crate::kernels::legs_x4::{Quad16Legs, legs_ik};
use crate::legs::ik::IkOptions;
use crate::legs::{FootPoint, LegError, LegKinematics};
use crate::model::Model;
use crate::spatial::{Force, yaw_from_rot};
use crate::terrain::{Terrain, TerrainUnion};
use glam::{DMat3, DVec2, DVec3};

use super::force_qp::{FootForces, ForceQp, ForceQpParams, MAX_FEET, StanceFoot, stance_torques};
use super::mpc::{MPC_FEET, Mpc, MpcParams, MpcProblem, NX, composite_inertia_about_com};
use super::profile::RobotProfile;
use super::vmc::{Vmc, VmcCommand, VmcInput, VmcParams};
use super::wbc::{BodyTask, ContactTask, JointTask, PointTask, WbcParams, WholeBody};

/// Everything that configures a [`Walker`].
#[derive(Clone, Debug, PartialEq)]
pub struct WalkerParams {
    /// The gait (Study A's trot by default).
    pub gait: Gait,
    /// Scheduler rules (touchdown, load ramps).
    pub scheduler: SchedulerParams,
    /// VMC gains and targets.
    pub vmc: VmcParams,
    /// Initial velocity command.
    pub command: VmcCommand,
    /// Force-QP weights and bounds.
    pub qp: ForceQpParams,
    /// Fraction of the ground's friction coefficient μ the force plan may
    /// use (in (0, 1]; default 1: the full cone). The planned forces are what
    /// the legs push with, not what the ground gives back: a stance foot's
    /// real normal force swings about the plan (touchdown impacts, a foot
    /// leaving the ground), and a tangential force planned on the cone's
    /// edge slips whenever it falls short. With the full μ, 40 % of quad16's
    /// loaded stance ticks at 0.75 m/s sit on the friction pyramid's corners.
    /// Alone (without [`Self::stance_foot_press`]) a reserve does not make
    /// the 0.75 m/s trot robust: 0.85 → 11 of 27 perturbed starts fall, 0.7
    /// and 0.6 → 1 of 27, and the blind step-up then falls in 27 of 27.
    pub friction_fraction: f64,
    /// The most friction the force plan assumes, whatever the map says
    /// (default 0.8, concrete's μ). On stickier ground a plan that leans on
    /// the full cone asks for sideways forces an unknown mass error turns
    /// into sway: at μ 1.0, with masses ±10 % unknown to the controller, a
    /// 0.5 m/s pace fell in 3 of 20 perturbed copies, none with this cap;
    /// 2 cm rough ground at 1.0 m/s went from 3 of 20 to 0 of 20.
    pub max_friction: f64,
    /// Foot placement.
    pub placement: PlacementParams,
    /// Swing apex above the lift-off/touchdown line (m). Study A: 0.17 m.
    pub lift_height_m: f64,
    /// Reaching down after a late swing.
    pub reach: ReachDown,
    /// Swing-leg joint stiffness per joint (N·m/rad; joints only).
    pub swing_kp_nm_per_rad: Vec<f64>,
    /// Swing-leg joint damping per joint (N·m·s/rad).
    pub swing_kd_nms_per_rad: Vec<f64>,
    /// Stance ankle hold (quad16): stiffness (N·m/rad) and damping (N·m·s/rad).
    pub ankle_hold: (f64, f64),
    /// Stance foot press: stiffness (N/m) and damping (N·s/m) of a one-sided
    /// vertical spring–damper that pushes a stance foot which has lost
    /// contact back down to where it last touched (see
    /// `Walker::press_lost_foot`); default `(0, 0)`: none. Off the ground a
    /// stance leg is otherwise driven only by `τ_id − Jᵀ f`, with `f`
    /// planned as if the foot stood.
    ///
    /// Measured (quad16, 10 s runs from starts perturbed by ±1e-9 in one
    /// coordinate; `engine/tests/walker.rs`, `engine/tests/walking.rs`):
    /// with [`ROUND_OFF_ROBUST`] the 0.75 m/s trot holds from 41 of 41 starts
    /// (defaults: 11 of 41 fall; 0.7 and 0.8 m/s hold too) and the blind
    /// step-up from 41 of 41 (defaults: 10 of 41 fall), with the sparse
    /// force-QP solver and with libm's sin/cos as well. Not the default
    /// because through the pipeline, on quad16's DC motors, it breaks the
    /// fast trots (measured with the sparse QP and libm's sin/cos):
    /// `scenarios/trot_study_mean.toml` (1.2 m/s) falls from 9 of 9
    /// micrometre neighbours of its start (defaults: 0 of 9) and
    /// `scenarios/trot.toml` at 1.0 m/s from 9 of 9 (defaults: 2 of 9); the
    /// 1.2 m/s trot still falls from 8 or 9 of 9 with the press alone, at 3
    /// kN/m, scaled by the leg's load factor, or only while other stance
    /// feet stand. Why is open (at speed the body rises late in each swing
    /// and stance feet leave the ground; pressing them down may lift the
    /// body further).
    pub stance_foot_press: (f64, f64),
    /// Inverse-kinematics options (knee branch, ankle mode).
    pub ik: IkOptions,
    /// Whether swing legs get the inverse-dynamics feed-forward of their
    /// reference's joint acceleration (and the stance feet its reaction).
    pub swing_feedforward: bool,
    /// Time constant (s) of the first-order filter on the CoM velocity used
    /// for foot placement (0: unfiltered). quad16's swing legs make the
    /// body's speed swing by ±0.5 m/s within each step; Raibert's feedback on
    /// the raw speed then places feet on that recoil.
    pub velocity_filter_s: f64,
    /// Largest rate of change of the commanded forward/lateral speed
    /// (m/s²; ≤ 0: steps). A step to 1.5 m/s asks VMC's damper alone for
    /// 450 N, more than friction gives under quad16's 275 N weight.
    pub command_accel_mps2: f64,
    /// Bound on the virtual wrench's horizontal force as a fraction of its
    /// vertical force (≤ 0: none); the rest could only come out of the
    /// moment rows of the QP (the body then pitches and rolls).
    pub max_horizontal_force_ratio: f64,
    /// Whether a stance leg whose foot has lost contact carries no force
    /// (and holds its joint targets by the swing PD) until it touches again;
    /// otherwise `τ = −Jᵀ f` would fling the free leg toward the ground.
    pub stance_needs_contact: bool,
    /// Whether the swing reference goes to IK from the *planned* base (level,
    /// at the target height, measured yaw) instead of the measured base pose:
    /// the swing legs' joint targets then do not follow the body's roll,
    /// pitch and bounce, which through quad16's heavy legs fed back into
    /// the body.
    pub swing_in_level_frame: bool,
    /// Smallest knee bend (rad) a stance leg is held to, on the IK branch
    /// (≤ 0: no guard). See `Walker::guard_knee`.
    pub knee_guard_rad: f64,
    /// Per leg, the point (m, base frame) whose ground projection is the
    /// "hip" of Raibert's foot placement; empty: each leg's mount (the first
    /// joint's origin: quad16's hips). quad12's mount is its hip-yaw axis,
    /// which its foot cannot reach (the leg's 50 mm offset l1 keeps the foot
    /// at least that far from it): there it is the stance foot's position.
    pub placement_hips_m: Vec<DVec3>,
    /// Whether the whole-body layer ([`super::wbc`]) turns the planned forces
    /// and the swing references into torques through the full `M(q)` and
    /// `h(q, v)`; `false`: today's `τ = τ_id − Jᵀ f` with swing-joint PD.
    pub whole_body: bool,
    /// The whole-body layer's weights.
    pub wbc: WbcParams,
    /// Swing-foot task gains of the whole-body layer: stiffness (1/s²) and
    /// damping (1/s) on the foot's position and velocity error (world).
    /// Default: 900 /s² and 60 /s at quad16's 0.5 m height target, times
    /// `0.5 / h` and `√(0.5 / h)` at a height target `h` (dynamic
    /// similarity; [`WalkerParams::from_profile`]). The Mini-Cheetah-sized
    /// robot (h = 0.287 m) at quad16's 900 and 60 tracked its swings late
    /// (its feet landed 7 cm short of the 13.5 cm placement at 1 m/s, its
    /// hind legs stretched straight at the end of stance), and 7 of 8
    /// perturbed starts on μ = 0.95 fell; at the scaled 1567 and 79, 0 of 8.
    pub swing_task_gains: (f64, f64),
    /// Largest acceleration (m/s², world) a swing foot's task asks for (≤ 0:
    /// none). A reference the legs' torque limits cannot follow (quad16's
    /// 4.5 kg legs over Study A's 0.15 s swing) is then tracked late instead
    /// of driving the joints into saturation, which breaks the dynamics the
    /// stance forces were planned with.
    pub swing_max_acc_mps2: f64,
    /// Joint-posture gains (1/s², 1/s) of the whole-body layer for joints the
    /// feet's tasks leave free (a 4-DOF leg's ankle).
    pub posture_gains: (f64, f64),
    /// Which planner chooses the stance feet's forces.
    pub planner: Planner,
    /// Tuning of the [`Planner::Mpc`] planner.
    pub mpc: MpcParams,
    /// Whether the torso follows the ground plane under the feet
    /// ([`super::ground_plane`]): its height target is taken above that
    /// plane, and its roll and pitch targets lie along it. `false`: Study
    /// A's targets, height above the ground beneath the base and a level
    /// torso. On level ground the two agree bit for bit.
    pub follow_ground_plane: bool,
    /// Time constant (s) of the first-order filter on that plane: a swing
    /// foot's target crossing a step's edge moves the fit at once, and the
    /// torso's height spring would throw the body up (0.1 s; 0: none).
    pub ground_plane_filter_s: f64,
}

/// The body-force planner of a [`Walker`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Planner {
    /// Study A's virtual model control: the virtual wrench of six
    /// spring–dampers, distributed over the stance feet ([`super::vmc`],
    /// [`super::force_qp`]).
    #[default]
    Vmc,
    /// Convex MPC on the single rigid body over the gait's contact plan
    /// ([`super::mpc`]).
    Mpc,
}

impl WalkerParams {
    /// Defaults that work for `model` (compiled from `desc`), from its
    /// [`RobotProfile`] (no robot's name is compared here): Study A's trot
    /// and VMC gains for quad16 (0.5 m height target, its built-in tuning);
    /// other robots get the same gains scaled by their mass ratio to quad16
    /// (28 kg) and a height target at 0.85 of their stance height (quad16:
    /// 0.5 / 0.585).
    /// Swing gains: joint bandwidth gains ([`super::joint_pd::bandwidth_gains`]) at the
    /// nominal stance, 6 Hz, critically damped. Study A's timing (period
    /// 0.5 s, supports 0.1 / 0.15 s) but a 5 cm lift, not 17 cm.
    ///
    /// What these defaults reach (quad16, flat concrete, semi-implicit Euler
    /// at 0.5 ms, controller at 500 Hz, 10 s; `engine/tests/walker.rs`):
    /// in place: tilt ≤ 0.06 rad, height p2p 9 mm; 0.5 m/s: mean 0.50 m/s,
    /// tilt 0.06 rad, p2p 20 mm; 0.75 m/s: mean 0.75 m/s, tilt 0.17 rad,
    /// p2p 38 mm; 1.0 m/s: survives (mean 0.96 m/s, tilt 0.39 rad) but not
    /// robustly (falls with ±0.01 m height target). At 1.25 and 1.5 m/s it
    /// falls within 2–5 s. Lifts of 8–14 cm hold in place and at 0.5 m/s;
    /// 17 cm falls (swing torques at the 100 N·m limit).
    ///
    /// quad12 (12 kg, legs 10 kg of it): the gains scaled by 12/28, height
    /// target 0.119 m, lift 1.2 cm, and Raibert's hips at the stance feet
    /// ([`WalkerParams::placement_hips_m`]; at the hip-yaw axes the feet were
    /// placed where the leg cannot reach and it fell within 2 s even at
    /// 10 N·m). It then trots in place (symmetric: no tilt) and at 0.05 and
    /// 0.1 m/s for 10 s (tilt ≤ 0.08 rad; 0.15 m/s only at 10 N·m, 0.2 m/s
    /// falls) **if the effort limit is raised** to 6 N·m or more
    /// (`engine/tests/quad12_vmc.rs` uses 8): in two-foot
    /// support each stance hip pitch needs 3.85 N·m to hold the body (59 N
    /// on a foot 87 mm out, less the leg's own weight), more than quad12's
    /// default 3 N·m; at 3, 4 and 5 N·m it sinks and falls within 2–10 s.
    pub fn default_for(desc: &RobotDescription, model: &Model) -> WalkerParams {
        Self::from_profile(&RobotProfile::from_model(desc, model), model)
    }

    /// [`Self::default_for`] from a robot's profile: Study A's VMC gains
    /// times [`RobotProfile::vmc_gain_scale`], the torso height target
    /// [`RobotProfile::walk_height_m`], the swing gains
    /// [`RobotProfile::swing_gains`] and the placement hips
    /// [`RobotProfile::placement_hips_m`]; the step limits and lift scale
    /// with the height target (Study A's at 0.5 m), the whole-body layer's
    /// task gains as a dynamically similar robot's
    /// ([`WalkerParams::swing_task_gains`]).
    pub fn from_profile(profile: &RobotProfile, model: &Model) -> WalkerParams {
        let (kp, kd) = profile.swing_gains(model);
        let g = model.gravity.length();
        let mut vmc = VmcParams::for_model(model);
        let r = profile.vmc_gain_scale;
        let gn = &mut vmc.gains;
        gn.stiffness_npm *= r;
        gn.damping_nspm *= r;
        gn.stiffness_nm_per_rad *= r;
        gn.damping_nms_per_rad *= r;
        vmc.base_height_m = profile.walk_height_m;
        let h = vmc.base_height_m;
        let scale = h / 0.5;
        // Task-space gains (1/s², 1/s) for quad16's 0.5 m, scaled to the
        // robot's size as dynamically similar robots' are: time goes as
        // √(h/g), so the stiffness as 1/h and the damping as 1/√h (the same
        // damping ratio). quad16's are unchanged (scale 1).
        let task_gains = |kp: f64, kd: f64| (kp / scale, kd / scale.sqrt());
        WalkerParams {
            gait: Gait::study_a_trot(),
            scheduler: SchedulerParams::default(),
            vmc,
            command: VmcCommand {
                forward_mps: 0.0,
                lateral_mps: 0.0,
                yaw_rate_radps: 0.0,
            },
            qp: ForceQpParams::default(),
            friction_fraction: 1.0,
            max_friction: 0.8,
            placement: PlacementParams {
                gain_s: PlacementParams::capture_point_gain_s(h, g),
                max_step_x_m: 0.25 * scale,
                max_step_y_m: 0.12 * scale,
            },
            lift_height_m: profile.swing_lift_m,
            reach: ReachDown::default(),
            swing_kp_nm_per_rad: kp,
            swing_kd_nms_per_rad: kd,
            ankle_hold: (20.0, 0.3),
            stance_foot_press: (0.0, 0.0),
            ik: IkOptions::default(),
            swing_feedforward: true,
            velocity_filter_s: 0.0,
            command_accel_mps2: 1.0,
            max_horizontal_force_ratio: 0.0,
            stance_needs_contact: false,
            swing_in_level_frame: true,
            knee_guard_rad: 0.5,
            placement_hips_m: profile.placement_hips_m.clone(),
            whole_body: false,
            wbc: WbcParams::default(),
            swing_task_gains: task_gains(900.0, 60.0),
            posture_gains: task_gains(400.0, 40.0),
            planner: Planner::Vmc,
            mpc: MpcParams::default(),
            swing_max_acc_mps2: 0.0,
            follow_ground_plane: false,
            ground_plane_filter_s: 0.1,
        }
    }
}

/// [`WalkerParams::stance_foot_press`] and [`WalkerParams::friction_fraction`]
/// that make quad16's trot at 0.75 m/s and its blind step-up hold from
/// round-off-sized perturbations of the start (both off in
/// [`WalkerParams::default_for`]: see [`WalkerParams::stance_foot_press`]).
/// The press, 10 kN/m and 200 N·s/m: a stance foot 1 cm off the ground is
/// pushed down with 100 N, about 70 % of its share of quad16's weight in
/// two-foot support; on quad16's vertical effective mass at the foot (3.3
/// kg at the nominal stance, joints driven, base free) an 8.7 Hz spring
/// with damping ratio 0.55, far below the ground's 100 kN/m. The friction
/// fraction 0.85 keeps 15 % of μ in reserve.
pub const ROUND_OFF_ROBUST: ((f64, f64), f64) = ((10_000.0, 200.0), 0.85);

/// Why a walker cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum WalkerError {
    /// The legs could not be identified from the model.
    #[error("walker: {0}")]
    Legs(#[from] LegError),
    /// The gait does not fit the robot.
    #[error("walker: {0}")]
    Gait(#[from] GaitError),
    /// A gain list has the wrong length.
    #[error("walker: {field} has {got} entries, the robot has {expected} joints")]
    GainLength {
        /// The field.
        field: &'static str,
        /// Entries given.
        got: usize,
        /// Joints.
        expected: usize,
    },
    /// More feet than the force QP takes.
    #[error("walker: {0} feet; at most 4 are supported")]
    TooManyFeet(usize),
    /// A parameter out of its domain.
    #[error("walker: {field} = {value} is invalid ({why})")]
    Param {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What is wrong.
        why: &'static str,
    },
}

/// A contact supports its foot only if the ground's normal there is within
/// 60° of vertical ([`Walker::tick`], step 1).
const SUPPORT_MIN_NORMAL_Z: f64 = 0.5;

/// What the walker needs to read each tick besides the model and state.
#[derive(Clone, Copy, Debug)]
pub struct WalkerInput<'a> {
    /// Time since the previous tick (s).
    pub dt_s: f64,
    /// The ground.
    pub terrain: &'a TerrainUnion,
    /// Whether each foot touches the ground (leg order = the model's feet).
    pub contacts: &'a [bool],
    /// Ground normal at each foot (unit, world; +z when unknown).
    pub normals: &'a [DVec3],
}

#[derive(Clone, Copy, Debug)]
struct LegInfo {
    frame: usize,
    body: usize,
    point: DVec3,
    /// Height (m) of `point` above the ground when the foot stands: 0 for a
    /// described contact point, the sphere's radius when the point is a
    /// foot sphere's centre (a URDF robot without `foot_points`).
    standing_height_m: f64,
    qi: [usize; 4],
    vi: [usize; 4],
    dof: usize,
}

/// [`LegInfo::standing_height_m`] of foot `foot`.
fn standing_height_m(desc: &RobotDescription, foot: &str) -> f64 {
    if desc.foot_points.iter().any(|(n, _)| n == foot) {
        return 0.0;
    }
    let placed = FootPoint::Contact.in_foot(desc, foot);
    desc.link(foot)
        .and_then(|l| {
            l.collision.iter().find_map(|g| match g.shape {
                crate::description::Shape::Sphere { radius_m }
                    if (g.origin.trans - placed).length() < 1e-9 =>
                {
                    Some(radius_m)
                }
                _ => None,
            })
        })
        .unwrap_or(0.0)
}

/// quad16's four legs in lanes for the leg IK, when `legs` are four quad16
/// legs.
fn quad16_legs_in_lanes(legs: &[LegKinematics]) -> Option<Quad16Legs> {
    let legs: Vec<_> = legs
        .iter()
        .filter_map(|l| match l {
            LegKinematics::Quad16(l) => Some(l),
            _ => None,
        })
        .collect();
    Quad16Legs::new(legs.try_into().ok()?)
}

/// The walking controller of one robot (see the module docs).
#[derive(Clone, Debug)]
pub struct Walker {
    /// Parameters.
    pub params: WalkerParams,
    legs: Vec<LegKinematics>,
    /// quad16's four legs in SIMD lanes for the tick's leg IK (`None` for
    /// other legs): the same angles as the legs' own solves, bit for bit.
    legs_in_lanes: Option<Box<Quad16Legs>>,
    /// Per leg: foot frame, the placed point in it, joint q and v indices, DOF.
    leg_info: Vec<LegInfo>,
    scheduler: GaitScheduler,
    vmc: Vmc,
    qp: ForceQp,
    /// Joint targets of the last tick (rad, joints only): swing legs their IK
    /// reference, stance legs the angles that would hold the body at its
    /// target height, level, over the current footholds.
    q_des: Vec<f64>,
    wrench: Force,
    forces: FootForces,
    feet_world: [DVec3; MAX_FEET],
    /// Per foot, the height (m, world) of its contact point at the last tick
    /// it touched the ground (NaN before its first contact): where
    /// [`Self::press_lost_foot`] pushes a stance foot back to. Measured, so a
    /// blind controller on a step finds the step's height, not its map's.
    last_contact_z: [f64; MAX_FEET],
    /// Joint velocity targets (rad/s, joints only) of the legs the last tick
    /// drove by PD (swing legs, stance legs without contact under
    /// [`WalkerParams::stance_needs_contact`]); a standing leg's entries are
    /// stale (nothing reads them).
    qd_des: Vec<f64>,
    /// Generalized accelerations for the inverse dynamics (base rows zero).
    acc: Vec<f64>,
    /// Inverse-dynamics joint torques of the last tick (the joint rows).
    tau_id: Vec<f64>,
    leg_q: Vec<f64>,
    leg_qd: Vec<f64>,
    leg_q2: Vec<f64>,
    leg_qd2: Vec<f64>,
    /// The command the operator set; `vmc.command` ramps toward it.
    command_set: VmcCommand,
    /// Low-passed CoM velocity (heading frame) for foot placement.
    v_filt: DVec2,
    v_filt_init: bool,
    /// The ground plane the torso follows this tick (level at the ground
    /// beneath the base unless [`WalkerParams::follow_ground_plane`]).
    ground: GroundPlane,
    /// The filtered plane and the base's ground point it was taken about.
    ground_filtered: Option<(GroundPlane, DVec2)>,
    /// The whole-body layer's workspace (when [`WalkerParams::whole_body`]).
    wbc: Option<Box<WholeBody>>,
    /// Whether the environment variable `WBDEBUG` was set when the walker
    /// was made: each whole-body solve is then printed to stderr (read
    /// once: reading the environment takes a lock, on every tick it showed
    /// in profiles).
    wbc_debug: bool,
    /// The MPC planner and its problem (when [`Planner::Mpc`]).
    mpc: Option<Box<MpcPlan>>,
}

/// The MPC planner's state between ticks.
#[derive(Clone, Debug)]
struct MpcPlan {
    mpc: Mpc,
    problem: MpcProblem,
    /// Time since the last solve (s); ∞ before the first.
    since_solve_s: f64,
    /// The stance feet the last solve planned for.
    stance: [bool; MPC_FEET],
    /// Solves so far.
    solves: usize,
}

impl Walker {
    /// A walker for `model` (compiled from `desc`), starting with every leg in
    /// stance at the gait's phase 0.
    pub fn new(
        desc: &RobotDescription,
        model: &Model,
        params: WalkerParams,
    ) -> Result<Walker, WalkerError> {
        let legs = LegKinematics::for_robot(desc, model, FootPoint::Contact)?;
        if legs.len() > MAX_FEET {
            return Err(WalkerError::TooManyFeet(legs.len()));
        }
        let nj = model.nv - model.base_nv();
        for (field, v) in [
            ("swing_kp_nm_per_rad", &params.swing_kp_nm_per_rad),
            ("swing_kd_nms_per_rad", &params.swing_kd_nms_per_rad),
        ] {
            if v.len() != nj {
                return Err(WalkerError::GainLength {
                    field,
                    got: v.len(),
                    expected: nj,
                });
            }
        }
        let ff = params.friction_fraction;
        if !(ff > 0.0 && ff <= 1.0) {
            return Err(WalkerError::Param {
                field: "friction_fraction",
                value: ff,
                why: "must be in (0, 1]",
            });
        }
        if params.max_friction.is_nan() || params.max_friction <= 0.0 {
            return Err(WalkerError::Param {
                field: "max_friction",
                value: params.max_friction,
                why: "must be positive",
            });
        }
        for (field, value) in [
            ("stance_foot_press.0", params.stance_foot_press.0),
            ("stance_foot_press.1", params.stance_foot_press.1),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(WalkerError::Param {
                    field,
                    value,
                    why: "must be finite and >= 0",
                });
            }
        }
        let scheduler = GaitScheduler::new(params.gait, params.scheduler)?;
        let leg_info = legs
            .iter()
            .map(|leg| {
                let frame = leg.foot_frame();
                let (qv, vv) = (leg.q_indices(), leg.v_indices());
                let mut qi = [0; 4];
                let mut vi = [0; 4];
                qi[..qv.len()].copy_from_slice(qv);
                vi[..vv.len()].copy_from_slice(vv);
                LegInfo {
                    frame,
                    body: model.frames[frame].body,
                    point: FootPoint::Contact.in_foot(desc, &model.frames[frame].name),
                    standing_height_m: standing_height_m(desc, &model.frames[frame].name),
                    qi,
                    vi,
                    dof: qv.len(),
                }
            })
            .collect();
        Ok(Walker {
            vmc: Vmc::new(
                params.vmc,
                if params.command_accel_mps2 > 0.0 {
                    VmcCommand {
                        forward_mps: 0.0,
                        lateral_mps: 0.0,
                        ..params.command
                    }
                } else {
                    params.command
                },
            ),
            qp: ForceQp::new(params.qp),
            scheduler,
            legs_in_lanes: quad16_legs_in_lanes(&legs).map(Box::new),
            legs,
            leg_info,
            q_des: vec![0.0; nj],
            wrench: Force::ZERO,
            forces: [DVec3::ZERO; MAX_FEET],
            feet_world: [DVec3::ZERO; MAX_FEET],
            last_contact_z: [f64::NAN; MAX_FEET],
            qd_des: vec![0.0; nj],
            acc: vec![0.0; model.nv],
            tau_id: vec![0.0; nj],
            leg_q: vec![0.0; 4],
            leg_qd: vec![0.0; 4],
            leg_q2: vec![0.0; 4],
            leg_qd2: vec![0.0; 4],
            command_set: params.command,
            v_filt: DVec2::ZERO,
            v_filt_init: false,
            ground: GroundPlane::level(0.0),
            ground_filtered: None,
            wbc: params
                .whole_body
                .then(|| Box::new(WholeBody::new(model, params.wbc))),
            wbc_debug: params.whole_body && std::env::var_os("WBDEBUG").is_some(),
            mpc: (params.planner == Planner::Mpc).then(|| {
                Box::new(MpcPlan {
                    mpc: Mpc::new(params.mpc),
                    problem: MpcProblem::with_horizon(params.mpc.horizon_steps.max(1)),
                    since_solve_s: f64::INFINITY,
                    stance: [false; MPC_FEET],
                    solves: 0,
                })
            }),
            params,
        })
    }

    /// Changes the velocity command (a scenario `command` event).
    /// The speeds ramp toward it at `command_accel_mps2`; the yaw rate
    /// applies at once. A gait without swing (`stand`) ignores the command
    /// and holds its place and heading.
    pub fn set_command(&mut self, command: VmcCommand) {
        self.command_set = command;
        self.vmc.command.yaw_rate_radps = command.yaw_rate_radps;
        if self.params.command_accel_mps2 <= 0.0 {
            self.vmc.command = command;
        }
    }

    /// The current velocity command (as set; see [`Self::active_command`]).
    pub fn command(&self) -> VmcCommand {
        self.command_set
    }

    /// The command in effect this tick (the ramped speeds).
    pub fn active_command(&self) -> VmcCommand {
        self.vmc.command
    }

    /// Joint targets of the last tick (rad, joints only).
    pub fn joint_targets(&self) -> &[f64] {
        &self.q_des
    }

    /// The virtual wrench of the last tick (N, N·m about the CoM, world).
    pub fn wrench(&self) -> Force {
        self.wrench
    }

    /// Ground reaction forces the last tick asked of each foot (N, world).
    pub fn foot_forces(&self) -> &FootForces {
        &self.forces
    }

    /// The gait scheduler.
    pub fn scheduler(&self) -> &GaitScheduler {
        &self.scheduler
    }

    /// Keeps a stance leg's knee (joint 2 of the leg) on the IK branch, at
    /// least `knee_guard_rad` from straight: a stance leg is force-controlled
    /// and, stretched behind the hip at speed, can snap through the straight
    /// knee into the other branch; the next swing then starts with its
    /// targets on the far side (observed at 0.75 m/s: every joint saturated).
    /// A one-sided PD (the swing gains of that joint) toward the margin.
    fn guard_knee(&self, leg: usize, nv0: usize, q: &[f64], v: &[f64], tau_joints: &mut [f64]) {
        let LegInfo { qi, vi, dof, .. } = self.leg_info[leg];
        let margin = self.params.knee_guard_rad;
        if dof < 3 || margin <= 0.0 {
            return;
        }
        let j = vi[2] - nv0;
        let branch = self.q_des[j].signum();
        let qk = q[qi[2]];
        let depth = margin - branch * qk;
        if depth > 0.0 {
            let kp = self.params.swing_kp_nm_per_rad[j];
            let kd = self.params.swing_kd_nms_per_rad[j];
            tau_joints[j] += branch * (kp * depth) - kd * v[vi[2]];
        }
    }

    /// Pushes stance leg `leg`'s foot, which has lost contact, back down to
    /// the ground: the leg applies `F = −max(0, K h + D ż) ẑ` to its foot
    /// (`τ += Jᵀ F`, joint rows), `h` the contact point's height above where
    /// it last touched the ground, `ż` its vertical speed (world) and `(K, D)`
    /// the [`WalkerParams::stance_foot_press`].
    ///
    /// Why: the force QP may give a stance foot only its minimum normal force
    /// (5 N) while it loads the others; quad16's legs weigh 4.5 kg each, so
    /// such a foot drifts off the ground with the leg's momentum (at 0.75 m/s
    /// stance feet were airborne in about 30 % of stance ticks, up to 14 cm
    /// high). When the QP next leans on that foot, the body has support the
    /// plan counts on but the ground does not give: the trot then fell after
    /// tiny perturbations (last-bit changes in the QP or in sin/cos), a knife
    /// edge. Only feet without contact are pressed: the forces of a standing
    /// foot stay exactly the QP's. The press is continuous at touchdown (a
    /// foot arriving at the ground has `h = 0` and `ż ≤ 0`, so `F = 0`) and
    /// only pushes down.
    fn press_lost_foot(
        &self,
        leg: usize,
        model: &Model,
        data: &mut Data,
        v: &[f64],
        tau_joints: &mut [f64],
    ) {
        let (k, d) = self.params.stance_foot_press;
        let ground_z = self.last_contact_z[leg];
        if (k <= 0.0 && d <= 0.0) || ground_z.is_nan() {
            return;
        }
        let p = self.feet_world[leg];
        let (nv, nv0) = (model.nv, model.base_nv());
        let jac = crate::jacobian::point_jacobian(model, data, self.leg_info[leg].body, p);
        let jz = &jac[2 * nv..3 * nv];
        let vz: f64 = jz.iter().zip(v).map(|(j, v)| j * v).sum();
        let fz = -(k * (p.z - ground_z) + d * vz).max(0.0);
        for c in nv0..nv {
            tau_joints[c - nv0] += jz[c] * fz;
        }
    }

    /// One control tick at `(q, v)`; writes the joint torques (N·m, joints
    /// only) into `tau_joints`. Leaves `data` with kinematics (and RNEA
    /// workspaces) at `(q, v)`; overwrites `data.jacobian`.
    ///
    /// Inverse dynamics with the base held still: `τ_id = RNEA(q, v, a)` with
    /// `a = [0; q̈_des]`, where swing legs get the joint acceleration of their
    /// min-jerk reference and stance legs zero. Its joint rows are every
    /// joint's feed-forward (the legs carry their own weight and the swing
    /// legs' inertia: quad16's legs are 18 of its 28 kg, and without it 8 Hz
    /// swing PD diverged even in place). For a stance leg `τ = τ_id − Jᵀ f`
    /// is the exact static hold (`M q̈ + h = τ + Jᵀ f`, q̈ = 0).
    pub fn tick(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        input: &WalkerInput<'_>,
        tau_joints: &mut [f64],
    ) {
        crate::dispatch::forward_kinematics(model, data, q, v);
        self.tick_at_kinematics(model, data, q, v, input, tau_joints);
    }

    /// [`Self::tick`] when `data` already holds the kinematics at `(q, v)`
    /// ([`crate::kinematics::forward_kinematics`] ran on this `data` with
    /// these `q` and `v`, and nothing changed it since): a caller that has
    /// just computed them (the exact-state tick, which evaluates the contacts
    /// first) skips the cache's check of the 45 state entries. The results
    /// are those of [`Self::tick`] bit for bit.
    pub fn tick_at_kinematics(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        input: &WalkerInput<'_>,
        tau_joints: &mut [f64],
    ) {
        debug_assert!(
            data.kinematics_hold(model, q, v),
            "tick_at_kinematics needs data's kinematics at (q, v)"
        );
        let nl = self.legs.len();
        let nv0 = model.base_nv();
        let base = data.pose[0];
        let rot = base.rot;
        let p_base = base.trans;
        let v_base = data.vel[0].lin;
        let w_base = data.vel[0].ang;
        let (com, com_vel) = com_and_velocity(model, data);
        let yaw = yaw_from_rot(rot);
        let heading = DMat3::from_rotation_z(yaw);

        // 0. command ramp
        if self.params.command_accel_mps2 > 0.0 {
            let dv = self.params.command_accel_mps2 * input.dt_s;
            let c = &mut self.vmc.command;
            c.forward_mps += (self.command_set.forward_mps - c.forward_mps).clamp(-dv, dv);
            c.lateral_mps += (self.command_set.lateral_mps - c.lateral_mps).clamp(-dv, dv);
        }
        if !self.scheduler.gait().has_swing() {
            // A stand takes no steps, so it can neither walk nor turn: VMC
            // would only lean the body over its feet until it fell.
            self.vmc.command = VmcCommand::STAND;
        }

        // 1. gait, with the feet's world positions for lift-off/touchdown points
        for (i, li) in self.leg_info.iter().enumerate() {
            let fp = crate::kinematics::frame_pose(model, data, li.frame);
            self.feet_world[i] = fp.transform_point(li.point);
        }
        // Only contacts that can carry the foot count: not a foot against a
        // riser or a wall (a contact normal far from vertical). On open
        // ground every contact counts. (The map's heights do not decide it:
        // a blind walker must land on a step its map does not have.)
        let mut support = [false; MAX_FEET];
        let filtered;
        let input = if input.contacts.len() >= nl {
            for (i, s) in support.iter_mut().enumerate().take(nl) {
                let upward = input
                    .normals
                    .get(i)
                    .is_none_or(|n| n.z >= SUPPORT_MIN_NORMAL_Z);
                *s = input.contacts[i] && upward;
            }
            filtered = WalkerInput {
                contacts: &support[..nl],
                ..*input
            };
            &filtered
        } else {
            input
        };
        self.scheduler
            .update_with_feet(input.dt_s, input.contacts, &self.feet_world[..nl]);
        for i in 0..nl {
            if input.contacts.get(i).copied().unwrap_or(false) {
                self.last_contact_z[i] = self.feet_world[i].z;
            }
        }

        // 2. touchdown targets of swinging legs (Raibert, heading frame)
        let v_now = (heading.transpose() * com_vel).truncate();
        let tf = self.params.velocity_filter_s;
        let alpha = if tf > 0.0 {
            (input.dt_s / tf).min(1.0)
        } else {
            1.0
        };
        if !self.v_filt_init {
            self.v_filt = v_now;
            self.v_filt_init = true;
        }
        self.v_filt += alpha * (v_now - self.v_filt);
        let v_h = self.v_filt;
        let cmd = self.vmc.command;
        let stance_s = self.scheduler.gait().stance_duration_s();
        for i in 0..nl {
            if self.scheduler.leg(i).phase != LegPhase::Swing {
                continue;
            }
            let hip_body = self
                .params
                .placement_hips_m
                .get(i)
                .copied()
                .unwrap_or_else(|| self.legs[i].mount().trans);
            let hip_world = base.transform_point(hip_body);
            let hip_h = (heading.transpose() * (hip_world - com)).truncate();
            let placement = raibert_offset(
                &self.params.placement,
                &PlacementInput {
                    vel_m_s: v_h,
                    vel_des_m_s: DVec2::new(cmd.forward_mps, cmd.lateral_mps),
                    yaw_rate_rad_s: w_base.z,
                    hip_m: hip_h,
                    stance_duration_s: stance_s,
                },
            );
            let o = DVec2::new(
                placement.offset_m.x * yaw.cos() - placement.offset_m.y * yaw.sin(),
                placement.offset_m.x * yaw.sin() + placement.offset_m.y * yaw.cos(),
            );
            let gz = input
                .terrain
                .height(hip_world.x + o.x, hip_world.y + o.y)
                .unwrap_or(self.feet_world[i].z);
            let ground_target = gz;
            let gz = gz + self.leg_info[i].standing_height_m;
            let target = foot_target_world(hip_world, yaw, gz, placement.offset_m);
            let lift = self.scheduler.leg(i).liftoff_pos_m;
            match input.terrain.height(lift.x, lift.y) {
                Some(ground_lift) => {
                    // the ground along the step, against the line between its ends
                    const SAMPLES: usize = 8;
                    let mut obstacle = 0.0_f64;
                    for k in 1..SAMPLES {
                        let u = k as f64 / SAMPLES as f64;
                        let p = lift.truncate().lerp(target.truncate(), u);
                        if let Some(h) = input.terrain.height(p.x, p.y) {
                            let chord = ground_lift + u * (ground_target - ground_lift);
                            obstacle = obstacle.max(h - chord);
                        }
                    }
                    self.scheduler.set_touchdown_target_over(
                        i,
                        target,
                        ground_target - ground_lift,
                        obstacle,
                    )
                }
                None => self.scheduler.set_touchdown_target(i, target),
            }
        }

        // 3. per leg: joint targets (swing: IK of the reference, with joint
        //    velocity and acceleration; stance: the hold at the target height)
        let ground_z = input.terrain.height(p_base.x, p_base.y).unwrap_or(0.0);
        self.ground = GroundPlane::level(ground_z);
        if self.params.follow_ground_plane
            && let Some(g) = self.fit_ground_plane(
                input,
                p_base.truncate(),
                (heading.x_axis.y, heading.x_axis.x),
            )
        {
            let tf = self.params.ground_plane_filter_s;
            let here = p_base.truncate();
            self.ground = match self.ground_filtered {
                Some((f, at)) if tf > 0.0 => {
                    // the filtered plane carried to the base's new ground
                    // point, then moved toward the new fit
                    let d = heading.transpose() * (here - at).extend(0.0);
                    let carried = f.height_m + f.slope.dot(d.truncate());
                    let a = (input.dt_s / tf).min(1.0);
                    GroundPlane {
                        height_m: carried + a * (g.height_m - carried),
                        slope: f.slope + a * (g.slope - f.slope),
                    }
                }
                _ => g,
            };
            self.ground_filtered = Some((self.ground, here));
        }
        let ground_z = self.ground.height_m;
        let target_height = self.vmc.params.base_height_m;
        // the torso's roll and pitch along the plane (none on level ground)
        let along_ground = (self.ground.slope != DVec2::ZERO).then(|| self.ground.roll_pitch_rad());
        let planned_rot = match along_ground {
            None => heading,
            Some((roll, pitch)) => {
                heading * DMat3::from_rotation_y(pitch) * DMat3::from_rotation_x(roll)
            }
        };
        let planned_base = crate::spatial::Transform::new(
            planned_rot,
            DVec3::new(p_base.x, p_base.y, ground_z + target_height),
        );
        self.acc.fill(0.0);
        // Each leg's reference (target, velocity, acceleration; base frame)
        // and the target of its second solve this tick: a swing leg's
        // reference a step ε ahead (the feed-forward's forward difference),
        // a stance leg's foot where it stands (the level ankle, step 8).
        const EPS_S: f64 = 1e-3;
        let mut refs = [(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO); MAX_FEET];
        let mut second = [DVec3::ZERO; MAX_FEET];
        for i in 0..nl {
            let state = self.scheduler.leg(i);
            let swing = state.phase == LegPhase::Swing;
            refs[i] = if swing {
                let r = state.swing_reference(self.params.lift_height_m, &self.params.reach);
                if self.params.swing_in_level_frame {
                    let rel = r.pos_m - planned_base.trans;
                    let v_rel = r.vel_m_s - DVec3::new(v_base.x, v_base.y, 0.0);
                    (
                        heading.transpose() * rel,
                        heading.transpose() * v_rel,
                        heading.transpose() * r.acc_m_s2,
                    )
                } else {
                    let rel = r.pos_m - p_base;
                    let v_rel = r.vel_m_s - v_base - w_base.cross(rel);
                    (
                        rot.transpose() * rel,
                        rot.transpose() * v_rel,
                        rot.transpose() * r.acc_m_s2,
                    )
                }
            } else {
                (
                    planned_base.inverse().transform_point(self.feet_world[i]),
                    DVec3::ZERO,
                    DVec3::ZERO,
                )
            };
            let (target_body, vel_body, acc_body) = refs[i];
            second[i] = if swing {
                target_body + vel_body * EPS_S + 0.5 * acc_body * EPS_S * EPS_S
            } else {
                rot.transpose() * (self.feet_world[i] - p_base)
            };
        }
        // quad16: both solves of the four legs in lanes (the legs' own
        // solves' angles, bit for bit; `None` without lanes). A solve fails
        // only on a target that is not finite.
        let (lanes_first, lanes_second) = match &self.legs_in_lanes {
            Some(lanes) => {
                let first = std::array::from_fn(|i| refs[i].0);
                let second = std::array::from_fn(|i| second[i]);
                (
                    legs_ik(lanes, &first, &self.params.ik),
                    legs_ik(lanes, &second, &self.params.ik),
                )
            }
            None => (None, None),
        };
        let solve = |leg: &LegKinematics,
                     lanes: Option<&[[f64; 4]; 4]>,
                     i: usize,
                     target: DVec3,
                     out: &mut [f64]| {
            match lanes {
                Some(a) if target.is_finite() => {
                    out.copy_from_slice(&a[i][..out.len()]);
                    true
                }
                Some(_) => false,
                None => leg.ik_clamped_into(target, &self.params.ik, out).is_ok(),
            }
        };
        for i in 0..nl {
            let leg = &self.legs[i];
            let LegInfo { qi, vi, dof, .. } = self.leg_info[i];
            let swing = self.scheduler.leg(i).phase == LegPhase::Swing;
            let (target_body, vel_body, acc_body) = refs[i];
            let leg_q = &mut self.leg_q[..dof];
            let leg_qd = &mut self.leg_qd[..dof];
            if !solve(leg, lanes_first.as_ref(), i, target_body, leg_q) {
                for k in 0..dof {
                    leg_q[k] = q[qi[k]];
                }
            }
            for k in 0..dof {
                self.q_des[vi[k] - nv0] = leg_q[k];
            }
            // Only a leg step 8 drives by PD (a free one) reads its velocity
            // target, in this tick: a standing leg's (`J⁻¹·0`) is not formed.
            let touching = input.contacts.get(i).copied().unwrap_or(true);
            if swing || (self.params.stance_needs_contact && !touching) {
                if leg
                    .joint_velocities_into(leg_q, vel_body, &self.params.ik, leg_qd)
                    .is_err()
                {
                    leg_qd.fill(0.0);
                }
                for k in 0..dof {
                    self.qd_des[vi[k] - nv0] = leg_qd[k];
                }
            }
            if swing && self.params.swing_feedforward {
                // q̈ = d/dt J⁻¹ ṗ by a forward difference along the reference
                // (the second solve: the reference at ε)
                let v2 = vel_body + acc_body * EPS_S;
                let q2 = &mut self.leg_q2[..dof];
                let qd2 = &mut self.leg_qd2[..dof];
                let ok = solve(leg, lanes_second.as_ref(), i, second[i], q2)
                    && leg
                        .joint_velocities_into(q2, v2, &self.params.ik, qd2)
                        .is_ok();
                if ok {
                    for k in 0..dof {
                        let a = (qd2[k] - self.leg_qd[k]) / EPS_S;
                        if a.is_finite() {
                            self.acc[vi[k]] = a;
                        }
                    }
                }
            }
        }

        // 4. inverse dynamics with the base held still
        //    (the kinematics at (q, v) are in `data` since the tick began)
        crate::dispatch::rnea_joint_torques_from_kinematics(
            model,
            data,
            v,
            &self.acc,
            &mut self.tau_id,
        );
        // 5. virtual wrench (the swing legs' reaction is not added: feeding
        //    the base rows of τ_id to the QP made quad16 fall even in place —
        //    the moment about the support diagonal is not realizable)
        // (the heading frame's entries are `yaw.sin_cos()`: the same bits
        // VMC would compute)
        let heading_sin_cos = (heading.x_axis.y, heading.x_axis.x);
        match along_ground {
            None => self.vmc.clear_posture(),
            Some((roll, pitch)) => {
                let v_des = DVec2::new(self.vmc.command.forward_mps, self.vmc.command.lateral_mps);
                self.vmc
                    .set_posture(roll, pitch, self.ground.rise_rate_mps(v_des));
            }
        }
        let mut w = self.vmc.update_at_heading(
            &VmcInput {
                base_position_m: p_base,
                base_rotation: rot,
                base_linear_velocity_mps: v_base,
                base_angular_velocity_radps: w_base,
                com_m: com,
                com_velocity_mps: com_vel,
                height_above_ground_m: p_base.z - ground_z,
                dt_s: input.dt_s,
            },
            yaw,
            heading_sin_cos,
        );
        let r = self.params.max_horizontal_force_ratio;
        if r > 0.0 {
            let h = w.lin.truncate();
            let hmax = r * w.lin.z.max(0.0);
            if h.length() > hmax {
                let h = h * (hmax / h.length());
                w.lin.x = h.x;
                w.lin.y = h.y;
            }
        }
        self.wrench = w;

        // 6. force distribution over loaded stance feet
        let mut feet = [StanceFoot {
            position_m: DVec3::ZERO,
            normal: DVec3::Z,
            friction: 0.0,
            load: 0.0,
        }; MAX_FEET];
        for i in 0..nl {
            let leg = self.scheduler.leg(i);
            let touching = input.contacts.get(i).copied().unwrap_or(true);
            let load = if leg.phase == LegPhase::Stance
                && (touching || !self.params.stance_needs_contact)
            {
                leg.load
            } else {
                0.0
            };
            let (friction, n) = self.foot_ground(input, i);
            feet[i] = StanceFoot {
                position_m: self.feet_world[i] - com,
                normal: n,
                friction,
                load,
            };
        }
        self.forces = match self.qp.solve(&feet[..nl], &self.wrench) {
            Ok(f) => f,
            Err(_) => [DVec3::ZERO; MAX_FEET],
        };
        if self.mpc.is_some() {
            let loaded: [bool; MAX_FEET] = std::array::from_fn(|i| i < nl && feet[i].load > 0.0);
            self.plan_by_mpc(model, data, input, com, com_vel, rot, &loaded);
        }

        if self.wbc.is_some() {
            self.whole_body_torques(
                model,
                data,
                q,
                v,
                input,
                &planned_base,
                &lanes_second,
                &second,
                tau_joints,
            );
            return;
        }

        // 7. stance torques τ = −Jᵀ f (zero for unloaded or swinging feet)
        let mut pts = [(0usize, DVec3::ZERO); MAX_FEET];
        for i in 0..nl {
            pts[i] = (self.leg_info[i].body, self.feet_world[i]);
        }
        stance_torques(model, data, &pts[..nl], &self.forces[..nl], tau_joints);

        // 8. swing legs tracked by PD about the feed-forward, the stance ankle held
        for i in 0..nl {
            let LegInfo { qi, vi, dof, .. } = self.leg_info[i];
            let touching = input.contacts.get(i).copied().unwrap_or(true);
            let free = self.scheduler.leg(i).phase == LegPhase::Swing
                || (self.params.stance_needs_contact && !touching);
            if free {
                for k in 0..dof {
                    let j = vi[k] - nv0;
                    let e = self.q_des[j] - q[qi[k]];
                    tau_joints[j] = self.params.swing_kp_nm_per_rad[j] * e
                        + self.params.swing_kd_nms_per_rad[j] * (self.qd_des[j] - v[vi[k]]);
                }
            } else {
                self.guard_knee(i, nv0, q, v, tau_joints);
                if !touching {
                    self.press_lost_foot(i, model, data, v, tau_joints);
                }
            }
            if !free && dof == 4 {
                // quad16's ankle: keep the foot level with the body
                let (kp, kd) = self.params.ankle_hold;
                let j = vi[3] - nv0;
                // (the second solve: the foot where it stands; its ankle
                // angle is `ik_clamped_ankle`'s, bit for bit)
                let level = self.level_ankle(i, &lanes_second, second[i]);
                tau_joints[j] += kp * (level - q[qi[3]]) - kd * v[vi[3]];
            }
        }
        for ((t, lim), h) in tau_joints
            .iter_mut()
            .zip(&model.effort_limit[nv0..])
            .zip(&self.tau_id)
        {
            *t = (*t + h).clamp(-lim, *lim);
        }
    }
}

impl Walker {
    /// [`Planner::Mpc`]: the stance forces from the convex MPC (solved again
    /// when due or when the loaded feet change), and the wrench about the
    /// CoM they make (the whole-body layer's body task).
    #[allow(clippy::too_many_arguments)]
    fn plan_by_mpc(
        &mut self,
        model: &Model,
        data: &Data,
        input: &WalkerInput<'_>,
        com: DVec3,
        com_vel: DVec3,
        rot: DMat3,
        loaded: &[bool; MAX_FEET],
    ) {
        let nl = self.legs.len().min(MPC_FEET);
        // taken out for the tick (it reads the walker's other state)
        let Some(mut plan) = self.mpc.take() else {
            return;
        };
        plan.since_solve_s += input.dt_s;
        let changed = loaded[..MPC_FEET] != plan.stance[..];
        if changed || plan.since_solve_s + 1e-12 >= plan.mpc.params.solve_every_s {
            let n = plan.mpc.params.horizon_steps;
            let dt = plan.mpc.params.step_s;
            let gait = *self.scheduler.gait();
            let period = gait.period_s();
            let phase = self.scheduler.phase();
            let cmd = self.vmc.command;
            let rpy = crate::spatial::rpy_from_rot(rot);
            let yaw = rpy.z;
            let heading = DMat3::from_rotation_z(yaw);
            let v_des = heading * DVec3::new(cmd.forward_mps, cmd.lateral_mps, 0.0);
            let base = data.pose[0];
            // the ground under the CoM: on the plane the torso follows
            let ground_z = if self.ground.slope == DVec2::ZERO {
                input.terrain.height(com.x, com.y).unwrap_or(0.0)
            } else {
                let d = heading.transpose() * (com - base.trans);
                self.ground.height_m + self.ground.slope.dot(d.truncate())
            };
            let (roll_ref, pitch_ref) = self.ground.roll_pitch_rad();
            let v_des_h = DVec2::new(cmd.forward_mps, cmd.lateral_mps);
            let rise = self.ground.rise_rate_mps(v_des_h);
            // the CoM's height target: the base's, less the CoM's offset below it
            let z_ref = ground_z + self.vmc.params.base_height_m - (base.trans.z - com.z);
            let (mass, _, inertia_world) = composite_inertia_about_com(model, data);
            let plan = &mut *plan;
            let pb = &mut plan.problem;
            pb.mass_kg = mass + self.vmc.params.payload_mass_kg;
            pb.inertia_heading = heading.transpose() * inertia_world * heading;
            pb.gravity = model.gravity;
            pb.state = super::mpc::MpcState {
                rpy,
                com_m: com,
                omega_world_radps: data.vel[0].ang,
                com_velocity_mps: com_vel,
            };
            let stance_s = gait.stance_duration_s();
            for k in 0..n {
                let t = (k + 1) as f64 * dt;
                let p = com + v_des * t;
                let r = &mut pb.reference[k];
                *r = [0.0; NX];
                if rise != 0.0 || roll_ref != 0.0 || pitch_ref != 0.0 {
                    r[0] = roll_ref;
                    r[1] = pitch_ref;
                    r[11] = rise;
                }
                r[2] = yaw + cmd.yaw_rate_radps * t;
                r[3] = p.x;
                r[4] = p.y;
                r[5] = z_ref + rise * t;
                r[8] = cmd.yaw_rate_radps;
                r[9] = v_des.x;
                r[10] = v_des.y;
                // contact plan over this step (its middle), feet relative
                // to the reference CoM at the step's start
                let t_mid = (k as f64 + 0.5) * dt;
                let c_ref = com + v_des * (k as f64 * dt);
                let step = &mut pb.steps[k];
                for i in 0..MPC_FEET {
                    step.stance[i] = false;
                    if i >= nl {
                        continue;
                    }
                    let leg = self.scheduler.leg(i);
                    let stance = if k == 0 {
                        loaded[i]
                    } else {
                        gait.scheduled_stance(i, phase + t_mid / period)
                    };
                    if !stance {
                        continue;
                    }
                    let foot = if leg.phase == LegPhase::Stance
                        && t_mid < self.scheduler.time_to_liftoff_s(i)
                    {
                        self.feet_world[i]
                    } else if leg.phase == LegPhase::Swing
                        && t_mid < leg.time_to_touchdown_s() + stance_s
                    {
                        leg.touchdown_pos_m
                    } else {
                        // a later stance: under the hip then, half a stance ahead
                        let hip = base.transform_point(self.legs[i].mount().trans);
                        let h = hip + v_des * (t_mid + 0.5 * stance_s);
                        DVec3::new(h.x, h.y, ground_z)
                    };
                    step.stance[i] = true;
                    step.foot_m[i] = foot - c_ref;
                    step.friction[i] = self.foot_ground(input, i).0;
                }
            }
            if plan.mpc.solve(pb).is_ok() {
                plan.since_solve_s = 0.0;
                plan.stance = *loaded;
                plan.solves += 1;
            }
        }
        let f = plan.mpc.first_forces();
        let mut w = Force::ZERO;
        for i in 0..nl {
            self.forces[i] = if loaded[i] && plan.stance[i] {
                f[i]
            } else {
                DVec3::ZERO
            };
            w.lin += self.forces[i];
            w.ang += (self.feet_world[i] - com).cross(self.forces[i]);
        }
        self.wrench = w;
        self.mpc = Some(plan);
    }

    /// The ground plane under the feet ([`super::ground_plane`]): through
    /// the terrain's heights where the stance feet stand and where the
    /// swing feet will touch down, about the base's ground point `origin`.
    fn fit_ground_plane(
        &self,
        input: &WalkerInput<'_>,
        origin: DVec2,
        heading_sin_cos: (f64, f64),
    ) -> Option<GroundPlane> {
        let nl = self.legs.len();
        let mut pts = [DVec3::ZERO; MAX_FEET];
        for (i, p) in pts.iter_mut().enumerate().take(nl) {
            let leg = self.scheduler.leg(i);
            let xy = if leg.phase == LegPhase::Swing {
                leg.touchdown_pos_m.truncate()
            } else {
                self.feet_world[i].truncate()
            };
            let z = input.terrain.height(xy.x, xy.y)?;
            *p = xy.extend(z);
        }
        GroundPlane::fit(&pts[..nl], origin, heading_sin_cos)
    }

    /// The friction the force plan may use at foot `i` (the ground's μ under
    /// it, at most [`WalkerParams::max_friction`], times
    /// [`WalkerParams::friction_fraction`]; 0.5 off every terrain)
    /// and the ground's normal there (unit, world; +z when unknown).
    fn foot_ground(&self, input: &WalkerInput<'_>, i: usize) -> (f64, DVec3) {
        let friction = input
            .terrain
            .closest_with_material(self.feet_world[i])
            .map_or(0.5, |(_, m)| m.friction.min(self.params.max_friction))
            * self.params.friction_fraction;
        let n = input
            .normals
            .get(i)
            .copied()
            .filter(|n| n.length_squared() > 0.5)
            .unwrap_or(DVec3::Z);
        (friction, n)
    }

    /// The ankle angle that keeps 4-DOF leg `i`'s foot level where it stands
    /// (`foot_body`: its point in the measured base frame, the tick's second
    /// solve): the lanes' angle when quad16's legs run in lanes,
    /// `ik_clamped_ankle`'s otherwise (the same bits); 0 when unsolvable.
    fn level_ankle(&self, i: usize, lanes_second: &Option<[[f64; 4]; 4]>, foot_body: DVec3) -> f64 {
        match lanes_second {
            Some(a) if foot_body.is_finite() => a[i][3],
            Some(_) => 0.0,
            None => match self.legs[i].ik_clamped_ankle(foot_body, &self.params.ik) {
                Some(Ok(a)) => a,
                _ => 0.0,
            },
        }
    }

    /// Steps 7–8 under the whole-body layer: stance feet that touch carry the
    /// planned forces as contacts; swing feet (and planned stance feet off
    /// the ground, pressed back down) track their references as point tasks;
    /// a 4-DOF leg's ankle keeps its level angle as a posture task. The
    /// torques are clamped to the effort limits.
    #[allow(clippy::too_many_arguments)]
    fn whole_body_torques(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        input: &WalkerInput<'_>,
        planned_base: &crate::spatial::Transform,
        lanes_second: &Option<[[f64; 4]; 4]>,
        second: &[DVec3; MAX_FEET],
        tau_joints: &mut [f64],
    ) {
        let nl = self.legs.len();
        let nv0 = model.base_nv();
        let (kp, kd) = self.params.swing_task_gains;
        let (pkp, pkd) = self.params.posture_gains;
        let empty = ContactTask {
            body: 0,
            point_m: DVec3::ZERO,
            normal: DVec3::Z,
            friction: 0.0,
            load: 0.0,
            force_plan_n: DVec3::ZERO,
        };
        let mut contacts = [empty; MAX_FEET];
        let mut contact_leg = [0usize; MAX_FEET];
        let mut nc = 0;
        let mut points = [PointTask {
            body: 0,
            point_m: DVec3::ZERO,
            acc_mps2: DVec3::ZERO,
        }; MAX_FEET];
        let mut np = 0;
        let mut joints = [JointTask {
            v_index: 0,
            acc_radps2: 0.0,
        }; MAX_FEET];
        let mut nj = 0;
        for i in 0..nl {
            let li = self.leg_info[i];
            let leg = self.scheduler.leg(i);
            let touching = input.contacts.get(i).copied().unwrap_or(true);
            let p = self.feet_world[i];
            let vel = data.vel[li.body].point_velocity(p - data.origin);
            let stance = leg.phase == LegPhase::Stance;
            if stance && touching {
                let (friction, normal) = self.foot_ground(input, i);
                contacts[nc] = ContactTask {
                    body: li.body,
                    point_m: p,
                    normal,
                    friction,
                    load: leg.load,
                    force_plan_n: self.forces[i],
                };
                contact_leg[nc] = i;
                nc += 1;
            } else {
                let acc = if stance {
                    // planned support off the ground: back down where it last stood
                    let z = if self.last_contact_z[i].is_finite() {
                        self.last_contact_z[i]
                    } else {
                        p.z
                    };
                    let target = DVec3::new(p.x, p.y, z - 0.02);
                    kp * (target - p) - kd * vel
                } else {
                    // The reference relative to the planned base (level, at
                    // the target height), tracked relative to the measured
                    // torso, as the Jᵀ path's IK does: the foot's place
                    // under the torso comes from the encoders, so errors of
                    // the estimated base pose do not move it.
                    let r = leg.swing_reference(self.params.lift_height_m, &self.params.reach);
                    let base = data.pose[0];
                    let vb = data.vel[0].point_velocity(base.trans - data.origin);
                    let wb = data.vel[0].ang;
                    let rpl = planned_base.rot;
                    let target_rel = base.rot * (rpl.transpose() * (r.pos_m - planned_base.trans));
                    let v_pl = DVec3::new(vb.x, vb.y, 0.0);
                    let vel_target_rel = base.rot * (rpl.transpose() * (r.vel_m_s - v_pl));
                    let rel = p - base.trans;
                    let vel_rel = vel - vb - wb.cross(rel);
                    let a = r.acc_m_s2 + kp * (target_rel - rel) + kd * (vel_target_rel - vel_rel);
                    let amax = self.params.swing_max_acc_mps2;
                    if amax > 0.0 && a.length() > amax {
                        a * (amax / a.length())
                    } else {
                        a
                    }
                };
                points[np] = PointTask {
                    body: li.body,
                    point_m: p,
                    acc_mps2: acc,
                };
                np += 1;
            }
            if li.dof == 4 {
                let j = li.vi[3] - nv0;
                let level = if stance {
                    self.level_ankle(i, lanes_second, second[i])
                } else {
                    self.q_des[j]
                };
                joints[nj] = JointTask {
                    v_index: li.vi[3],
                    acc_radps2: pkp * (level - q[li.qi[3]]) - pkd * v[li.vi[3]],
                };
                nj += 1;
            }
        }
        let body = BodyTask {
            force_n: self.wrench.lin,
            torque_nm: self.wrench.ang,
        };
        let wbc = self.wbc.as_mut().expect("whole-body workspace");
        match wbc.solve(
            model,
            data,
            v,
            &contacts[..nc],
            &body,
            &points[..np],
            &joints[..nj],
            tau_joints,
        ) {
            Ok(out) => {
                if self.wbc_debug {
                    eprintln!(
                        "nc {nc} np {np} qp {} db {:?} f {:?} tau {:?}",
                        out.qp_solved,
                        out.base_change.map(|x| (x * 10.0).round() / 10.0),
                        out.forces_n[..nc]
                            .iter()
                            .map(|f| f.round())
                            .collect::<Vec<_>>(),
                        tau_joints.iter().map(|x| x.round()).collect::<Vec<_>>()
                    );
                }
                self.forces = [DVec3::ZERO; MAX_FEET];
                for k in 0..nc {
                    self.forces[contact_leg[k]] = out.forces_n[k];
                }
            }
            Err(_) => tau_joints.fill(0.0),
        }
        for (t, lim) in tau_joints.iter_mut().zip(&model.effort_limit[nv0..]) {
            *t = t.clamp(-lim, *lim);
        }
    }

    /// Changes the payload mass that gravity compensation carries (kg; a
    /// payload attached or detached and known to the controller).
    pub fn add_payload_mass_kg(&mut self, delta_kg: f64) {
        let m = (self.vmc.params.payload_mass_kg + delta_kg).max(0.0);
        self.vmc.params.payload_mass_kg = m;
        self.params.vmc.payload_mass_kg = m;
    }

    /// The payload mass gravity compensation carries (kg).
    pub fn payload_mass_kg(&self) -> f64 {
        self.vmc.params.payload_mass_kg
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{ContactForces, ContactPoint, ContactState, GroundMaterial};
    use crate::integrate::{Integrator, State, StepWorkspace, step};
    use crate::model::BaseKind;
    use crate::robots;
    use crate::terrain::TerrainUnion;

    /// quad16's walker with its legs' IK in lanes and the same walker
    /// solving leg by leg give the same joint torques bit for bit, tick
    /// after tick, over 2 s of a closed-loop trot at 0.5 m/s (swing and
    /// stance, feed-forward and level ankle; each walker drives its own
    /// robot, so the states stay equal only while every torque does).
    #[test]
    fn legs_in_lanes_give_the_leg_by_leg_torques() {
        let desc = robots::builtin("quad16").unwrap();
        let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let mut params = WalkerParams::default_for(&desc, &model);
        params.command.forward_mps = 0.5;
        let lanes = Walker::new(&desc, &model, params).unwrap();
        if legs_ik(
            lanes
                .legs_in_lanes
                .as_deref()
                .expect("quad16's legs in lanes"),
            &[DVec3::NEG_Z; 4],
            &lanes.params.ik,
        )
        .is_none()
        {
            return; // no AVX2 on this CPU: the lanes never run
        }
        let mut by_leg = lanes.clone();
        by_leg.legs_in_lanes = None;
        let terrain = TerrainUnion::flat(0.0, GroundMaterial::preset("concrete").unwrap());
        let points = ContactPoint::feet(&model, &desc);
        let dt_s = 0.0005;
        let mut robots = [lanes, by_leg].map(|w| {
            let st = State {
                q: robots::nominal_q("quad16").unwrap(),
                v: vec![0.0; model.nv],
            };
            let states = vec![ContactState::default(); points.len()];
            (w, st, states, Data::new(&model), StepWorkspace::new(&model))
        });
        let mut tau = [vec![0.0; model.nv], vec![0.0; model.nv]];
        for k in 0..4_000 {
            for (r, (walker, st, states, data, ws)) in robots.iter_mut().enumerate() {
                crate::dispatch::forward_kinematics(&model, data, &st.q, &st.v);
                crate::contact::update_after_step(&points, data, &terrain, states);
                if k % 4 == 0 {
                    let contacts: Vec<bool> = states.iter().map(|s| s.in_contact).collect();
                    let normals: Vec<DVec3> = states.iter().map(|s| s.normal).collect();
                    let input = WalkerInput {
                        dt_s: 4.0 * dt_s,
                        terrain: &terrain,
                        contacts: &contacts,
                        normals: &normals,
                    };
                    let mut tj = vec![0.0; model.nv - 6];
                    walker.tick(&model, data, &st.q, &st.v, &input, &mut tj);
                    tau[r][6..].copy_from_slice(&tj);
                }
                let mut f = ContactForces {
                    terrain: &terrain,
                    points: &points,
                    states,
                };
                let integ = Integrator::SemiImplicitEuler;
                step(&model, data, ws, st, &tau[r], dt_s, integ, &mut f);
            }
            assert_eq!(
                tau[0].iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
                tau[1].iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
                "step {k}"
            );
        }
        assert!(robots[0].1.q[0] > 0.5, "the robot walked");
    }
}
