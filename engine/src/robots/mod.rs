//! The built-in parametric robots of the two source studies, by name.
//!
//! | name | study | DOF | mass at defaults | module |
//! |---|---|---|---|---|
//! | `quad16` | A: mammal-like, hip roll/pitch, knee, ankle | 16 | 28 kg | [`quad16`] |
//! | `quad12` | B: small trotter, D-H legs (hip yaw, pitch, knee) | 12 | 12 kg | [`quad12`] |
//!
//! At their defaults both equal the shared reference URDFs
//! (`models/quad16.urdf`, `models/quad12.urdf`) in every link, joint, frame,
//! mass, CoM and inertia, with the same link and joint names and the same q/v
//! order (movable joints in URDF document order: legs LF, RF, RH, LH, and
//! proximal to distal within a leg). Only the actuator limits differ: the URDFs
//! carry placeholders (1000 N·m, 100 rad/s), the built-ins documented
//! assumptions.
//!
//! Every length, radius, mass, mount offset, leg angle and actuator limit is a
//! parameter addressed by a dotted path (`thigh.length_m`); each robot module
//! documents its table (unit, default, meaning) and how dependent quantities
//! follow a change (CoM, inertia, mass). [`params()`] returns the table,
//! [`builtin_with`] applies overrides:
//!
//! ```
//! use quadsim_engine::robots::{builtin, builtin_with};
//! let long = builtin_with("quad16", &[("thigh.length_m", 0.4)]).unwrap();
//! // a longer thigh at the same density weighs more
//! assert!(long.total_mass_kg() > builtin("quad16").unwrap().total_mass_kg());
//! ```
//!
//! Each robot also has a nominal standing configuration ([`nominal_stance`],
//! [`nominal_base_height_m`], [`nominal_q`]): the joint angles of a stable
//! stand and the base height that puts the feet' contact points on the ground.

pub mod links;
pub mod params;
pub mod quad12;
pub mod quad16;

pub use params::{Domain, ParamError, ParamSpec};

use crate::Data;
use crate::actuator_model::ActuatorDefaults;
use crate::description::{RobotDescription, Shape};
use crate::kinematics::{forward_kinematics_pos, frame_pose};
use crate::model::{BaseKind, Model, ModelError};
use crate::sensors::SensorSpec;
use glam::DVec3;
use params::Values;

const NAMES: &[&str] = &[quad16::NAME, quad12::NAME];

/// Names of the built-in robots.
pub fn builtin_names() -> &'static [&'static str] {
    NAMES
}

/// The parameter table of a built-in robot, `None` for an unknown name.
pub fn params(name: &str) -> Option<&'static [ParamSpec]> {
    match name {
        quad16::NAME => Some(quad16::PARAMS),
        quad12::NAME => Some(quad12::PARAMS),
        _ => None,
    }
}

/// A built-in robot at its default parameters, `None` for an unknown name.
pub fn builtin(name: &str) -> Option<RobotDescription> {
    builtin_with(name, &[]).ok()
}

/// A built-in robot with some parameters overridden by path.
///
/// # Errors
/// [`ParamError::UnknownRobot`] for an unknown name, [`ParamError::UnknownPath`]
/// (with the closest valid paths) for a path the robot does not have,
/// [`ParamError::OutOfDomain`] for a value outside the parameter's domain
/// (a negative length or mass, NaN, …), [`ParamError::Duplicate`] for a path
/// given twice.
pub fn builtin_with(name: &str, overrides: &[(&str, f64)]) -> Result<RobotDescription, ParamError> {
    let unknown = || ParamError::UnknownRobot {
        name: name.to_string(),
        valid: NAMES.join(", "),
    };
    let specs = params(name).ok_or_else(unknown)?;
    let values = Values::resolve(name, specs, overrides)?;
    match name {
        quad16::NAME => Ok(quad16::build(&values)),
        quad12::NAME => Ok(quad12::build(&values)),
        _ => Err(unknown()),
    }
}

/// Nominal standing joint angles (rad, q order, one entry per movable joint),
/// `None` for an unknown name. They depend on no parameter.
///
/// - `quad16`: `[0, 0.3, −0.6, 0.3]` per leg (hip roll, hip pitch, knee,
///   ankle), the oracle's `stand_static` state: feet level, about 15 mm behind
///   the hips.
/// - `quad12`: `[0, π/6, π/3]` per leg (hip yaw, hip pitch, knee), the `stand`
///   keyframe of `models/quad12.xml`: a crouch with the thigh 30° below the
///   horizontal and the shank vertical, the foot right below the knee.
pub fn nominal_stance(name: &str) -> Option<Vec<f64>> {
    match name {
        quad16::NAME => Some(quad16::STANCE_LEG_RAD.repeat(4)),
        quad12::NAME => Some(quad12::STANCE_LEG_RAD.repeat(4)),
        _ => None,
    }
}

/// The source study a built-in robot is the robot of
/// (`/work/shared/reference.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceStudy {
    /// Study A: the mammal-like quadruped under virtual model control
    /// ([`quad16`]).
    A,
    /// Study B: the small D-H trotter on hobby servos ([`quad12`]).
    B,
}

/// The study a built-in robot comes from, `None` for an unknown name.
pub fn source_study(name: &str) -> Option<SourceStudy> {
    match name {
        quad16::NAME => Some(SourceStudy::A),
        quad12::NAME => Some(SourceStudy::B),
        _ => None,
    }
}

/// The default actuators a built-in robot states ([`quad16::ACTUATORS`],
/// [`quad12::ACTUATORS`]), `None` for an unknown name: a robot without them
/// gets ideal sources by default, and motors whose stall torque and no-load
/// speed are its joints' limits
/// ([`crate::actuator_model::ActuatorSpec::from_limits`]).
pub fn actuator_defaults(name: &str) -> Option<ActuatorDefaults> {
    match name {
        quad16::NAME => Some(quad16::ACTUATORS),
        quad12::NAME => Some(quad12::ACTUATORS),
        _ => None,
    }
}

/// The default sensors of a robot called `name` of `total_mass_kg`: a
/// built-in robot's own ([`quad16::SENSORS`], [`quad12::SENSORS`]); any
/// other robot gets quad16's with its foot force sensors sized to the robot:
/// thresholds and noise times `total_mass_kg /`
/// [`quad16::SENSOR_REFERENCE_MASS_KG`] (quad16's 28 kg; unscaled for a
/// mass that is not finite and positive). quad16's 20 N threshold is 29 % of
/// its standing load per foot; an 8.9 kg robot stands on 22 N per foot, so
/// at 20 N its feet flicker in and out of contact while standing and read
/// as off the ground in two-foot support's unloading (its trot fell within
/// 0.21 s on the sensed state; docs/walking.md, "Any quadruped").
pub fn default_sensors(name: &str, total_mass_kg: f64) -> SensorSpec {
    match name {
        quad16::NAME => quad16::SENSORS,
        quad12::NAME => quad12::SENSORS,
        _ if total_mass_kg.is_finite() && total_mass_kg > 0.0 => {
            quad16::SENSORS.with_contacts_scaled(total_mass_kg / quad16::SENSOR_REFERENCE_MASS_KG)
        }
        _ => quad16::SENSORS,
    }
}

/// What a built-in robot states for its controllers beyond its model
/// (read through [`crate::control::profile::RobotProfile`]; a robot
/// without an entry gets the profile's rules from its model).
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltinTuning {
    /// Nominal standing joint angles (rad, q order): [`nominal_stance`].
    pub stance_rad: Vec<f64>,
    /// The walking controller's torso height target (m); `None`: the
    /// profile's rule (0.85 of the stance height).
    pub walk_height_m: Option<f64>,
    /// Factor on Study A's VMC gains; `None`: the profile's rule (the mass
    /// ratio to quad16's 28 kg).
    pub vmc_gain_scale: Option<f64>,
    /// Whether the stand controller's default gains are the joint bandwidth
    /// gains alone (the built-ins' tuned rule, their legs a large part of
    /// their mass) rather than the profile's leg-stiffness rule.
    pub stand_gains_by_bandwidth: bool,
    /// The swing's lift as a fraction of the walking height; `None`: the
    /// profile's rule for robots without tuning.
    pub swing_lift_per_height: Option<f64>,
    /// The whole-body walker's largest sideways step from the hip (m);
    /// `None`: the placement's default (0.12 m at quad16's size, scaled).
    pub whole_body_max_step_y_m: Option<f64>,
}

/// The tuning of a built-in robot by its name, `None` for an unknown name.
///
/// - `quad16`: Study A's VMC gains unscaled and its 0.5 m torso height
///   (Study A's table is quad16's own, at any parameter values).
/// - `quad12`: the profile's rules (gains scaled by its mass, height 0.85 of
///   the stance's).
///
/// Both keep the joint bandwidth gains for standing and lift their swing
/// feet a tenth of their walking height (Study A's 5 cm at quad16's 0.5 m).
/// quad16's whole-body walker may step 0.2 m sideways (after 150 N × 0.1 s
/// pushes from 8 directions, 20 perturbed copies each, 51 of 160 fell at
/// 0.12 m and 33 at 0.2 m; docs/validation.md).
pub fn builtin_tuning(name: &str) -> Option<BuiltinTuning> {
    let stance_rad = nominal_stance(name)?;
    let study_a = name == quad16::NAME;
    Some(BuiltinTuning {
        stance_rad,
        walk_height_m: study_a.then_some(0.5),
        vmc_gain_scale: study_a.then_some(1.0),
        stand_gains_by_bandwidth: true,
        swing_lift_per_height: Some(BUILTIN_SWING_LIFT_PER_HEIGHT),
        whole_body_max_step_y_m: study_a.then_some(0.2),
    })
}

/// The built-in robots' swing lift per unit of walking height.
pub const BUILTIN_SWING_LIFT_PER_HEIGHT: f64 = 0.1;

/// The lowest point (m, body frame of the foot's body) and its sphere's
/// radius of each foot of `model`, as the contact model sees it: the
/// description's foot point when it names one, else the centre and radius of
/// the foot link's first collision sphere, else the link origin.
fn foot_contacts(desc: &RobotDescription, model: &Model) -> Vec<(usize, DVec3, f64)> {
    model
        .feet
        .iter()
        .map(|&f| {
            let frame = &model.frames[f];
            let named = desc.foot_points.iter().find(|(n, _)| *n == frame.name);
            let sphere = desc.link(&frame.name).and_then(|l| {
                l.collision.iter().find_map(|g| match g.shape {
                    Shape::Sphere { radius_m } => Some((g.origin.trans, radius_m)),
                    _ => None,
                })
            });
            match (named, sphere) {
                (Some((_, p)), _) => (f, *p, 0.0),
                (None, Some((c, r))) => (f, c, r),
                (None, None) => (f, DVec3::ZERO, 0.0),
            }
        })
        .collect()
}

/// Height of the base origin above flat ground (m) at which the lowest foot
/// contact point of `desc` touches the ground with the base level and the
/// joints at `joints_rad` (q order). A foot the description gives no
/// contact point but a collision sphere touches with the sphere's bottom.
///
/// # Errors
/// Those of [`Model::from_description`].
///
/// # Panics
/// When `joints_rad` does not hold one angle per movable joint.
pub fn stance_base_height_m(
    desc: &RobotDescription,
    joints_rad: &[f64],
) -> Result<f64, ModelError> {
    let model = Model::from_description(desc, BaseKind::Fixed)?;
    assert_eq!(joints_rad.len(), model.nq, "one angle per movable joint");
    let mut data = Data::new(&model);
    forward_kinematics_pos(&model, &mut data, joints_rad);
    let lowest = foot_contacts(desc, &model)
        .into_iter()
        .map(|(f, point, radius_m)| {
            frame_pose(&model, &data, f).transform_point(point).z - radius_m
        })
        .fold(f64::INFINITY, f64::min);
    Ok(-lowest)
}

/// Nominal base height (m) of a built-in at its defaults: the feet' contact
/// points on the ground at [`nominal_stance`]. quad16: 0.55 · cos 0.3 + 0.06 ≈
/// 0.58543 m (the oracle's `stand_static` rounds it to 0.5854); quad12: 0.13 +
/// 0.01 (pad) = 0.14 m.
pub fn nominal_base_height_m(name: &str) -> Option<f64> {
    let desc = builtin(name)?;
    let stance = nominal_stance(name)?;
    stance_base_height_m(&desc, &stance).ok()
}

/// The nominal floating-base configuration of a built-in at its defaults:
/// `[0, 0, height, 0, 0, 0, 1, stance…]` (Pinocchio order, base level).
pub fn nominal_q(name: &str) -> Option<Vec<f64>> {
    let h = nominal_base_height_m(name)?;
    let mut q = vec![0.0, 0.0, h, 0.0, 0.0, 0.0, 1.0];
    q.extend(nominal_stance(name)?);
    Some(q)
}

/// The benchmarks' random state of a floating-base `model` (its `q`, `v`
/// and joint-space `τ`): base at (0.1, −0.2, 0.5) m with a random unit
/// quaternion, joints in ±1.5 rad, base velocities in ±1 m/s and ±1 rad/s,
/// joint velocities in ±2 rad/s, torques in ±10 N·m. One definition, so the
/// criterion benches and the A/B example time the same states, drawn from
/// `r` in this order.
pub fn benchmark_state(model: &Model, r: &mut impl rand::Rng) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut q = model.neutral_q();
    let axis = DVec3::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    )
    .normalize();
    let quat = glam::DQuat::from_axis_angle(axis, r.random_range(-3.0..3.0));
    q[..7].copy_from_slice(&[0.1, -0.2, 0.5, quat.x, quat.y, quat.z, quat.w]);
    for x in &mut q[7..] {
        *x = r.random_range(-1.5..1.5);
    }
    let v: Vec<f64> = (0..model.nv)
        .map(|k| r.random_range(-1.0..1.0) * if k < 6 { 1.0 } else { 2.0 })
        .collect();
    let tau: Vec<f64> = (0..model.nv).map(|_| r.random_range(-10.0..10.0)).collect();
    (q, v, tau)
}
