//! Compliant foot–ground contact: spring–damper normal laws and stick–slip
//! Coulomb friction against a [`TerrainUnion`] (study A: infinite-mass ground,
//! spring–damper feet).
//!
//! # Model
//! A [`ContactPoint`] is a sphere (radius ≥ 0) fixed in a body. Its depth is
//! the terrain depth of the sphere's centre plus its radius, along the
//! terrain's closest-point normal `n` (world, out of the ground). The force acts
//! at the sphere's deepest point `c − r n`:
//!
//! - normal: `f_n = law(δ, δ̇) ≥ 0` ([`NormalLaw`]), `δ̇ = −v·n` with `v` the
//!   velocity of the body's material point there;
//! - tangential: stick–slip ([`friction`]): a spring–damper anchored at the
//!   touchdown point while `|f_t| ≤ μ f_n`, else sliding at `μ f_n`.
//!
//! # Two calls per step (RK4-safe)
//! - [`contact_forces`] is a pure function of the stage state (through `data`
//!   after forward kinematics) and the persistent [`ContactState`]s: call it in
//!   every derivative evaluation; it adds the point forces to `data.f_ext` via
//!   [`Data::add_point_force`]. [`ContactForces`] wraps it as an
//!   [`ForceModel`] for [`crate::integrate::step`].
//! - [`update_after_step`] runs once per accepted step, after kinematics at the
//!   new state: it records contact, slip, depth and force, sets the anchor at
//!   touchdown and drags it while slipping. It keeps its terrain query
//!   ([`CachedQuery`]) for the next step's first evaluation at the same state.
//!
//! The tangential displacement is measured at the contact's ground point (the
//! surface point nearest the sphere's centre), the slip velocity at the body's
//! material point; for a rolling foot sphere the spring thus resists rolling
//! until it slips, a small rolling resistance of order `k_t r θ`.

pub mod friction;
pub mod law;
pub mod presets;
pub mod stability;

pub use law::NormalLaw;
pub use presets::{GroundMaterial, GroundPreset};
pub use stability::{StabilityWarning, check_stability};

use crate::data::Data;
use crate::description::{RobotDescription, Shape};
use crate::integrate::ForceModel;
use crate::model::Model;
use crate::terrain::{TerrainHit, TerrainUnion};
use glam::DVec3;
use thiserror::Error;

/// Errors in contact parameters.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ContactError {
    /// A ground preset name that does not exist.
    #[error("unknown ground preset '{0}' (known: concrete, grass, mud, sand)")]
    UnknownPreset(String),
    /// A number out of its domain.
    #[error("ground material: field '{field}' = {value} is invalid ({why})")]
    InvalidValue {
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
        /// What is wrong.
        why: &'static str,
    },
    /// A contact point on a body the model does not have, or a bad radius.
    #[error("contact point {index}: {why}")]
    InvalidPoint {
        /// Index of the point.
        index: usize,
        /// What is wrong.
        why: String,
    },
}

/// What part of the robot a contact point belongs to; a torso or knee
/// touching the ground is a fall.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ContactKind {
    /// A foot (expected to touch).
    #[default]
    Foot,
    /// A knee.
    Knee,
    /// A torso corner or edge.
    Torso,
}

/// A contact sphere fixed in a body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// Body index in the [`Model`].
    pub body: usize,
    /// Sphere centre in the body frame (m).
    pub point_in_body: DVec3,
    /// Sphere radius (m, ≥ 0; 0 for a point).
    pub radius_m: f64,
    /// Foot, knee or torso.
    pub kind: ContactKind,
}

impl ContactPoint {
    /// A sphere of `radius_m` centred at `point_in_body` of `body`.
    pub fn new(body: usize, point_in_body: DVec3, radius_m: f64, kind: ContactKind) -> Self {
        ContactPoint {
            body,
            point_in_body,
            radius_m,
            kind,
        }
    }

    /// One foot contact per foot of `model`: the foot link's first collision
    /// sphere (centre and radius) when it has one, else a point at the foot's
    /// `foot_points` entry (or the link origin).
    pub fn feet(model: &Model, desc: &RobotDescription) -> Vec<ContactPoint> {
        model
            .feet
            .iter()
            .map(|&f| {
                let frame = &model.frames[f];
                let link = desc.link(&frame.name);
                let sphere = link.and_then(|l| {
                    l.collision.iter().find_map(|g| match g.shape {
                        Shape::Sphere { radius_m } => Some((g.origin.trans, radius_m)),
                        _ => None,
                    })
                });
                let (centre, radius_m) = sphere.unwrap_or_else(|| {
                    let p = desc
                        .foot_points
                        .iter()
                        .find(|(n, _)| *n == frame.name)
                        .map_or(DVec3::ZERO, |(_, p)| *p);
                    (p, 0.0)
                });
                ContactPoint::new(
                    frame.body,
                    frame.placement.transform_point(centre),
                    radius_m,
                    ContactKind::Foot,
                )
            })
            .collect()
    }

    /// Checks the body index and radius against `model`.
    pub fn validate(points: &[ContactPoint], model: &Model) -> Result<(), ContactError> {
        for (index, p) in points.iter().enumerate() {
            if p.body >= model.nbodies {
                return Err(ContactError::InvalidPoint {
                    index,
                    why: format!(
                        "body {} does not exist (model has {})",
                        p.body, model.nbodies
                    ),
                });
            }
            if !(p.radius_m.is_finite() && p.radius_m >= 0.0) {
                return Err(ContactError::InvalidPoint {
                    index,
                    why: format!("radius_m = {} must be finite and ≥ 0", p.radius_m),
                });
            }
            if !p.point_in_body.is_finite() {
                return Err(ContactError::InvalidPoint {
                    index,
                    why: "point_in_body must be finite".into(),
                });
            }
        }
        Ok(())
    }
}

/// A terrain query kept by [`update_after_step`]: the next evaluation at the
/// same sphere centre (bitwise) — the first derivative evaluation of the next
/// step, at the state the update saw — reuses it instead of querying again.
/// The answer is the same either way, so evaluations stay pure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CachedQuery {
    /// Sphere centre queried (m, world).
    pub centre_m: DVec3,
    /// The terrain's answer (`None`: no ground).
    pub hit: Option<TerrainHit>,
}

/// Persistent state of one contact, updated once per step by [`update_after_step`].
/// Reset it to the default when the terrain changes (its anchor and cached
/// query refer to the old ground).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactState {
    /// The sphere overlaps the ground (depth > 0).
    pub in_contact: bool,
    /// The contact slid (friction at the cone's limit) in the last update.
    pub slipping: bool,
    /// Tangential anchor (m, world, on the ground): the touchdown point, dragged while slipping.
    pub anchor_m: DVec3,
    /// Penetration depth (m, ≥ 0).
    pub penetration_m: f64,
    /// Ground normal at the contact (world, unit; zero when not in contact).
    pub normal: DVec3,
    /// Normal force magnitude (N, ≥ 0).
    pub normal_force_n: f64,
    /// Total force of the ground on the body (N, world).
    pub force_n: DVec3,
    /// The last end-of-step terrain query.
    pub last_query: Option<CachedQuery>,
}

/// Everything one contact evaluation finds (world frame).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactEval {
    /// Depth > 0: the sphere overlaps the ground.
    pub active: bool,
    /// Penetration depth (m; ≤ 0 when not touching, −∞ with no ground at all).
    pub depth_m: f64,
    /// Penetration rate (m/s, > 0 sinking).
    pub depth_rate_mps: f64,
    /// Ground normal (unit, out of the ground).
    pub normal: DVec3,
    /// Where the force acts: the sphere's deepest point (m).
    pub application_m: DVec3,
    /// The ground point nearest the sphere's centre (m).
    pub ground_point_m: DVec3,
    /// Normal force (N, ≥ 0).
    pub normal_force_n: f64,
    /// Tangential force (N).
    pub tangential_force_n: DVec3,
    /// Friction at the cone's limit.
    pub slipping: bool,
    /// Tangential stiffness of the ground touched (N/m), for the anchor drag.
    pub tangential_stiffness_npm: f64,
    /// Sphere centre (m, world).
    pub centre_m: DVec3,
    /// The terrain query's answer at `centre_m`.
    pub hit: Option<TerrainHit>,
}

impl ContactEval {
    /// No contact.
    pub const NONE: ContactEval = ContactEval {
        active: false,
        depth_m: f64::NEG_INFINITY,
        depth_rate_mps: 0.0,
        normal: DVec3::ZERO,
        application_m: DVec3::ZERO,
        ground_point_m: DVec3::ZERO,
        normal_force_n: 0.0,
        tangential_force_n: DVec3::ZERO,
        slipping: false,
        tangential_stiffness_npm: 0.0,
        centre_m: DVec3::ZERO,
        hit: None,
    };

    /// Total force on the body (N, world).
    #[inline]
    pub fn force_n(&self) -> DVec3 {
        self.normal * self.normal_force_n + self.tangential_force_n
    }
}

/// Evaluates one contact at the state in `data` (after forward kinematics
/// with velocities). Pure: reads `state`, writes nothing.
#[inline]
pub fn evaluate(
    point: &ContactPoint,
    data: &Data,
    terrain: &TerrainUnion,
    state: &ContactState,
) -> ContactEval {
    let centre = data.body_point_world(point.body, point.point_in_body);
    let hit = match &state.last_query {
        Some(q) if q.centre_m == centre => q.hit,
        _ => terrain.closest_hit(centre),
    };
    let Some(TerrainHit { surface, source }) = hit else {
        return ContactEval {
            centre_m: centre,
            ..ContactEval::NONE
        };
    };
    let depth_m = surface.depth_m + point.radius_m;
    let n = surface.normal;
    let application_m = centre - point.radius_m * n;
    if depth_m <= 0.0 {
        return ContactEval {
            depth_m,
            normal: n,
            application_m,
            ground_point_m: surface.point,
            centre_m: centre,
            hit,
            ..ContactEval::NONE
        };
    }
    let material = terrain.material(source);
    let v = data.vel[point.body].point_velocity(application_m - data.origin);
    let vn = v.dot(n);
    let depth_rate_mps = -vn;
    let normal_force_n = material.law.normal_force(
        material.stiffness,
        material.damping,
        depth_m,
        depth_rate_mps,
    );
    let v_t = v - vn * n;
    let e_t = if state.in_contact {
        let e = surface.point - state.anchor_m;
        e - e.dot(n) * n
    } else {
        DVec3::ZERO
    };
    let (tangential_force_n, slipping) = friction::stick_slip(
        material.tangential_stiffness_npm,
        material.tangential_damping_nspm,
        material.friction,
        normal_force_n,
        e_t,
        v_t,
    );
    ContactEval {
        active: true,
        depth_m,
        depth_rate_mps,
        normal: n,
        application_m,
        ground_point_m: surface.point,
        normal_force_n,
        tangential_force_n,
        slipping,
        tangential_stiffness_npm: material.tangential_stiffness_npm,
        centre_m: centre,
        hit,
    }
}

/// Adds every contact's force to `data.f_ext` at the stage state held in
/// `data` (after [`crate::kinematics::forward_kinematics`]). Pure in the
/// persistent state: call it at every RK4 stage. `out`, when given (same
/// length as `points`), receives each evaluation.
pub fn contact_forces(
    points: &[ContactPoint],
    model: &Model,
    data: &mut Data,
    terrain: &TerrainUnion,
    states: &[ContactState],
    mut out: Option<&mut [ContactEval]>,
) {
    debug_assert_eq!(points.len(), states.len());
    debug_assert!(points.iter().all(|p| p.body < model.nbodies));
    for (i, (p, s)) in points.iter().zip(states).enumerate() {
        let e = evaluate(p, data, terrain, s);
        if e.active {
            data.add_point_force(p.body, e.application_m, e.force_n());
        }
        if let Some(o) = out.as_deref_mut() {
            o[i] = e;
        }
    }
}

/// Once per accepted step, with `data` holding kinematics (with velocities)
/// at the new state: evaluates every contact and updates its state. At
/// touchdown the anchor is set to the ground point; while slipping it is
/// dragged so the spring sits at the friction limit; on lift-off the contact
/// is cleared.
pub fn update_after_step(
    points: &[ContactPoint],
    data: &Data,
    terrain: &TerrainUnion,
    states: &mut [ContactState],
) {
    debug_assert_eq!(points.len(), states.len());
    for (p, s) in points.iter().zip(states.iter_mut()) {
        let e = evaluate(p, data, terrain, s);
        s.last_query = Some(CachedQuery {
            centre_m: e.centre_m,
            hit: e.hit,
        });
        if !e.active {
            *s = ContactState {
                last_query: s.last_query,
                ..ContactState::default()
            };
            continue;
        }
        if !s.in_contact {
            s.anchor_m = e.ground_point_m;
        }
        if e.slipping {
            s.anchor_m = friction::dragged_anchor(
                e.ground_point_m,
                e.tangential_force_n,
                e.tangential_stiffness_npm,
            );
        }
        s.in_contact = true;
        s.slipping = e.slipping;
        s.penetration_m = e.depth_m;
        s.normal = e.normal;
        s.normal_force_n = e.normal_force_n;
        s.force_n = e.force_n();
    }
}

/// Contacts as a [`ForceModel`] for [`crate::integrate::step`]: evaluates
/// [`contact_forces`] at every derivative evaluation against fixed
/// persistent states. Call [`update_after_step`] after each step.
#[derive(Debug, Clone, Copy)]
pub struct ContactForces<'a> {
    /// The ground.
    pub terrain: &'a TerrainUnion,
    /// The contact spheres.
    pub points: &'a [ContactPoint],
    /// Their persistent states (anchors), as of the step's start.
    pub states: &'a [ContactState],
}

impl ForceModel for ContactForces<'_> {
    #[inline]
    fn apply(&mut self, model: &Model, data: &mut Data, _q: &[f64], _v: &[f64], _tau: &mut [f64]) {
        contact_forces(self.points, model, data, self.terrain, self.states, None);
    }
}
