//! Closed-form leg kinematics of the built-in quadrupeds, derived from the
//! compiled [`Model`] so that parameter overrides (lengths, mounts, leg yaws)
//! are honoured.
//!
//! | leg | joints (q order) | module |
//! |---|---|---|
//! | quad16 (study A) | hip roll (x), hip pitch (y), knee (y), ankle (y) | [`quad16_leg`] |
//! | quad12 (study B) | hip yaw (z), hip pitch (y), knee (y) | [`quad12_leg`] |
//! | any other 3- or 4-DOF serial leg | hip abduction (~x) or yaw (~z), hip pitch (~y), knee (~y), optional ankle (~y), any signs | [`serial_leg`] |
//!
//! The closed forms are fast paths: [`LegKinematics::from_model`] takes
//! them where the chain fits them exactly and the numerical
//! [`SerialLeg`] (damped least squares on the leg's point Jacobian)
//! otherwise; a test shows the two agree where both apply.
//!
//! Each leg gives its foot point in the **base (torso) frame** as a function of
//! its joint angles ([`Quad16Leg::fk`]), the inverse in closed form
//! ([`Quad16Leg::ik`], with a selectable knee branch and, for the 4-DOF leg, a
//! held foot pitch or ankle angle), a clamped inverse that projects an
//! unreachable target onto the workspace ([`Quad16Leg::ik_clamped`]), its
//! Jacobian, and a foot-velocity-to-joint-velocity map for swing PD.
//!
//! # Which point
//! The point the kinematics place is chosen when a leg is built
//! ([`FootPoint`]); by default it is the description's foot contact point
//! (`foot_points`): for quad16 the bottom of the foot sphere, `2·radius` below
//! the ankle in the foot frame; for quad12 the pad's surface one radius past
//! the shank's tip along the shank. [`FootPoint::SphereCentre`] places the
//! centre of the contact sphere instead (what [`crate::contact`] tests
//! against the ground).
//!
//! ```
//! use glam::DVec3;
//! use quadsim_engine::legs::{FootPoint, IkOptions, LegKinematics};
//! use quadsim_engine::model::{BaseKind, Model};
//! use quadsim_engine::robots::builtin_with;
//! let desc = builtin_with("quad16", &[("thigh.length_m", 0.35)]).unwrap();
//! let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
//! let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
//! let LegKinematics::Quad16(lf) = &legs[0] else { unreachable!() };
//! // the foot 0.5 m below the LF hip, level
//! let target = lf.mount().trans - DVec3::new(0.0, 0.0, 0.5);
//! let a = lf.ik(target, &IkOptions::default()).unwrap();
//! assert!((lf.fk(a) - target).length() < 1e-12);
//! assert!(a[2] < 0.0); // the nominal knee branch
//! ```

pub mod ik;
pub mod quad12_leg;
pub mod quad16_leg;
pub mod serial_leg;

pub use ik::{AnkleMode, IkClamped, IkError, IkOptions, KneeBranch, wrap_angle};
pub use quad12_leg::Quad12Leg;
pub use quad16_leg::Quad16Leg;
pub use serial_leg::{HipKind, IkStats, SerialLeg};

use crate::description::{RobotDescription, Shape};
use crate::model::{JointType, Model};
use crate::spatial::Transform;
use glam::{DMat3, DVec3};
use thiserror::Error;

/// Why a leg cannot be built from a model.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LegError {
    /// A frame index the model does not have.
    #[error("frame {index} does not exist (the model has {count})")]
    UnknownFrame {
        /// The index.
        index: usize,
        /// Number of frames.
        count: usize,
    },
    /// The chain from the base to the foot has the wrong number of joints.
    #[error("foot '{foot}': {found} joints from the base, expected {expected}")]
    ChainLength {
        /// Foot frame name.
        foot: String,
        /// Joints found.
        found: usize,
        /// Joints the leg kind has (3 or 4).
        expected: usize,
    },
    /// A joint of the chain does not fit the closed-form structure.
    #[error("joint '{joint}': field '{field}' {why}")]
    Structure {
        /// Joint name.
        joint: String,
        /// The offending field (`type`, `axis`, `origin`).
        field: &'static str,
        /// What the closed form needs.
        why: String,
    },
    /// The chain to a foot is no 3- or 4-DOF serial leg.
    #[error("foot '{foot}': joint '{joint}' {why}")]
    Serial {
        /// Foot frame name.
        foot: String,
        /// The offending joint.
        joint: String,
        /// What a serial leg needs.
        why: String,
    },
}

/// Which point of the foot the leg kinematics place.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FootPoint {
    /// The description's foot contact point (`foot_points`, the link origin
    /// when absent).
    #[default]
    Contact,
    /// The centre of the foot link's first collision sphere (the contact
    /// model's sphere), the contact point when there is none.
    SphereCentre,
}

impl FootPoint {
    /// The point (m, foot link frame) for the foot link `foot`.
    pub fn in_foot(self, desc: &RobotDescription, foot: &str) -> DVec3 {
        let contact = || {
            desc.foot_points
                .iter()
                .find(|(n, _)| n == foot)
                .map_or(DVec3::ZERO, |(_, p)| *p)
        };
        match self {
            FootPoint::Contact => contact(),
            FootPoint::SphereCentre => desc
                .link(foot)
                .and_then(|l| {
                    l.collision.iter().find_map(|g| match g.shape {
                        Shape::Sphere { .. } => Some(g.origin.trans),
                        _ => None,
                    })
                })
                .unwrap_or_else(contact),
        }
    }
}

/// One leg of either kind.
#[derive(Clone, Debug, PartialEq)]
pub enum LegKinematics {
    /// A hip-roll, hip-pitch, knee, ankle leg.
    Quad16(Quad16Leg),
    /// A hip-yaw, hip-pitch, knee leg.
    Quad12(Quad12Leg),
    /// Any other serial leg, solved numerically (boxed: it holds the whole
    /// chain).
    Serial(Box<SerialLeg>),
}

impl LegKinematics {
    /// The leg ending at `foot_frame`: a closed form where the chain fits
    /// one exactly (four joints: [`Quad16Leg`], three: [`Quad12Leg`]), else
    /// a [`SerialLeg`].
    ///
    /// # Errors
    /// [`LegError`] when the chain is no serial leg either (the
    /// [`SerialLeg::from_model`] error, naming the foot and the joint).
    pub fn from_model(
        model: &Model,
        foot_frame: usize,
        point_in_foot_m: DVec3,
    ) -> Result<Self, LegError> {
        let n = chain_bodies(model, foot_frame)?.len();
        let closed = match n {
            3 => Quad12Leg::from_model(model, foot_frame, point_in_foot_m)
                .map(Self::Quad12)
                .ok(),
            4 => Quad16Leg::from_model(model, foot_frame, point_in_foot_m)
                .map(Self::Quad16)
                .ok(),
            _ => None,
        };
        match closed {
            Some(leg) => Ok(leg),
            None => Self::serial_from_model(model, foot_frame, point_in_foot_m),
        }
    }

    /// The leg ending at `foot_frame` as a [`SerialLeg`] whatever its shape
    /// (no closed form): for comparisons with the closed forms.
    ///
    /// # Errors
    /// Those of [`SerialLeg::from_model`].
    pub fn serial_from_model(
        model: &Model,
        foot_frame: usize,
        point_in_foot_m: DVec3,
    ) -> Result<Self, LegError> {
        SerialLeg::from_model(model, foot_frame, point_in_foot_m).map(|l| Self::Serial(Box::new(l)))
    }

    /// One leg per foot of `model` (in `model.feet` order), placing `point`.
    ///
    /// # Errors
    /// The first [`LegError`] of a foot.
    pub fn for_robot(
        desc: &RobotDescription,
        model: &Model,
        point: FootPoint,
    ) -> Result<Vec<Self>, LegError> {
        model
            .feet
            .iter()
            .map(|&f| Self::from_model(model, f, point.in_foot(desc, &model.frames[f].name)))
            .collect()
    }

    /// Number of joints (4 or 3).
    pub fn dof(&self) -> usize {
        self.q_indices().len()
    }

    /// Indices of the leg's joints in q.
    pub fn q_indices(&self) -> &[usize] {
        match self {
            Self::Quad16(l) => l.q_indices(),
            Self::Quad12(l) => l.q_indices(),
            Self::Serial(l) => l.q_indices(),
        }
    }

    /// Indices of the leg's joints in v.
    pub fn v_indices(&self) -> &[usize] {
        match self {
            Self::Quad16(l) => l.v_indices(),
            Self::Quad12(l) => l.v_indices(),
            Self::Serial(l) => l.v_indices(),
        }
    }

    /// Frame index of the foot link.
    pub fn foot_frame(&self) -> usize {
        match self {
            Self::Quad16(l) => l.foot_frame(),
            Self::Quad12(l) => l.foot_frame(),
            Self::Serial(l) => l.foot_frame(),
        }
    }

    /// The hip mount (first joint's frame at zero angle, base frame).
    pub fn mount(&self) -> Transform {
        match self {
            Self::Quad16(l) => l.mount(),
            Self::Quad12(l) => l.mount(),
            Self::Serial(l) => l.mount(),
        }
    }

    /// Foot point (m, base frame) at the leg's joint angles `a` (rad).
    ///
    /// # Panics
    /// When `a.len()` is not [`Self::dof`].
    pub fn fk(&self, a: &[f64]) -> DVec3 {
        match self {
            Self::Quad16(l) => l.fk(a.try_into().expect("4 leg angles")),
            Self::Quad12(l) => l.fk(a.try_into().expect("3 leg angles")),
            Self::Serial(l) => {
                assert_eq!(a.len(), l.dof(), "one angle per leg joint");
                l.fk(a)
            }
        }
    }

    /// [`Quad16Leg::ik`] / [`Quad12Leg::ik`] into `out`.
    ///
    /// # Errors
    /// Those of the leg's `ik`.
    ///
    /// # Panics
    /// When `out.len()` is not [`Self::dof`].
    pub fn ik_into(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        out: &mut [f64],
    ) -> Result<(), IkError> {
        match self {
            Self::Quad16(l) => out.copy_from_slice(&l.ik(target_m, opts)?),
            Self::Quad12(l) => out.copy_from_slice(&l.ik(target_m, opts)?),
            Self::Serial(l) => out.copy_from_slice(&l.ik(target_m, opts)?),
        }
        Ok(())
    }

    /// [`Quad16Leg::ik_clamped`] / [`Quad12Leg::ik_clamped`]'s angles into
    /// `out`; returns whether the target was projected (the foot point
    /// reached is not computed: [`Self::fk`] of `out` gives it).
    ///
    /// # Errors
    /// [`IkError::NonFinite`].
    ///
    /// # Panics
    /// When `out.len()` is not [`Self::dof`].
    pub fn ik_clamped_into(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        out: &mut [f64],
    ) -> Result<bool, IkError> {
        let clamped = match self {
            Self::Quad16(l) => {
                let (a, clamped) = l.ik_clamped_angles(target_m, opts)?;
                out.copy_from_slice(&a);
                clamped
            }
            Self::Quad12(l) => {
                let (a, clamped) = l.ik_clamped_angles(target_m, opts)?;
                out.copy_from_slice(&a);
                clamped
            }
            Self::Serial(l) => {
                assert_eq!(out.len(), l.dof(), "one angle per leg joint");
                l.ik_clamped_into(target_m, opts, out)?
            }
        };
        Ok(clamped)
    }

    /// [`Quad16Leg::ik_clamped_ankle`]: the ankle angle of the clamped IK
    /// alone; `None` for a leg without an ankle.
    pub fn ik_clamped_ankle(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
    ) -> Option<Result<f64, IkError>> {
        match self {
            Self::Quad16(l) => Some(l.ik_clamped_ankle(target_m, opts)),
            Self::Quad12(_) => None,
            Self::Serial(l) if l.dof() == 4 => {
                Some(l.ik_clamped(target_m, opts).map(|c| c.angles_rad[3]))
            }
            Self::Serial(_) => None,
        }
    }

    /// The leg's joint velocities (rad/s) for a foot velocity (m/s, base
    /// frame), into `out` (see [`Quad16Leg::joint_velocities`]).
    ///
    /// # Errors
    /// [`IkError::Singular`] for the exact map at a singular pose.
    ///
    /// # Panics
    /// When `a.len()` or `out.len()` is not [`Self::dof`].
    pub fn joint_velocities_into(
        &self,
        a: &[f64],
        foot_velocity: DVec3,
        opts: &IkOptions,
        out: &mut [f64],
    ) -> Result<(), IkError> {
        match self {
            Self::Quad16(l) => out.copy_from_slice(&l.joint_velocities(
                a.try_into().expect("4 leg angles"),
                foot_velocity,
                opts,
            )?),
            Self::Quad12(l) => out.copy_from_slice(&l.joint_velocities(
                a.try_into().expect("3 leg angles"),
                foot_velocity,
                opts,
            )?),
            Self::Serial(l) => {
                assert!(
                    a.len() == l.dof() && out.len() == l.dof(),
                    "one angle per leg joint"
                );
                l.joint_velocities_into(a, foot_velocity, opts, out)?
            }
        }
        Ok(())
    }
}

/// A movable joint of a leg chain.
#[derive(Clone, Debug)]
pub(crate) struct ChainJoint {
    /// Joint frame at zero angle in the parent body's frame.
    pub placement: Transform,
    /// Index in q.
    pub q_index: usize,
    /// Index in v.
    pub v_index: usize,
}

/// Bodies from the base's child to the foot frame's body, proximal first.
fn chain_bodies(model: &Model, foot_frame: usize) -> Result<Vec<usize>, LegError> {
    let frame = model.frames.get(foot_frame).ok_or(LegError::UnknownFrame {
        index: foot_frame,
        count: model.frames.len(),
    })?;
    let mut bodies = Vec::new();
    let mut b = frame.body;
    while b != 0 && b < model.nbodies {
        bodies.push(b);
        b = model.parent[b];
    }
    bodies.reverse();
    Ok(bodies)
}

/// The chain to `foot_frame`, checked against the closed form's structure:
/// revolute joints with these axes (joint frame), all but the first placed
/// by a pure translation.
pub(crate) fn chain_of(
    model: &Model,
    foot_frame: usize,
    axes: &[DVec3],
) -> Result<Vec<ChainJoint>, LegError> {
    const TOL: f64 = 1e-9;
    let bodies = chain_bodies(model, foot_frame)?;
    if bodies.len() != axes.len() {
        return Err(LegError::ChainLength {
            foot: model.frames[foot_frame].name.clone(),
            found: bodies.len(),
            expected: axes.len(),
        });
    }
    let mut chain = Vec::with_capacity(axes.len());
    for (k, (&b, &axis)) in bodies.iter().zip(axes).enumerate() {
        let structure = |field, why: String| LegError::Structure {
            joint: model.joint_name[b].clone(),
            field,
            why,
        };
        if model.joint_type[b] != JointType::Revolute {
            return Err(structure("type", "must be revolute".into()));
        }
        if (model.axis[b] - axis).length() > TOL {
            return Err(structure(
                "axis",
                format!("is {}, the closed form needs {axis}", model.axis[b]),
            ));
        }
        let placement = model.placement[b];
        if k > 0 && !placement.rot.abs_diff_eq(DMat3::IDENTITY, TOL) {
            return Err(structure(
                "origin",
                "must be a pure translation (parallel pitch axes)".into(),
            ));
        }
        chain.push(ChainJoint {
            placement,
            q_index: model.idx_q[b],
            v_index: model.idx_v[b],
        });
    }
    Ok(chain)
}

/// A point of the foot link (m, link frame) in the frame of the body it is
/// merged into.
pub(crate) fn foot_point_in_body(
    model: &Model,
    foot_frame: usize,
    point_in_foot_m: DVec3,
) -> DVec3 {
    model.frames[foot_frame]
        .placement
        .transform_point(point_in_foot_m)
}
