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
//!   ([`CachedQuery`]) and the force the moved state gives there
//!   ([`CachedForce`]) for the next step's first evaluation at the same state.
//!
//! The tangential displacement is measured at the contact's ground point (the
//! surface point nearest the sphere's centre), the slip velocity at the body's
//! material point; for a rolling foot sphere the spring thus resists rolling
//! until it slips, a small rolling resistance of order `k_t r θ`.

pub mod error;
pub mod friction;
pub mod law;
pub mod stability;

pub use crate::material::{GroundMaterial, GroundPreset, NOMINAL_CONTACT_LOAD_N};
pub use error::ContactError;
pub use law::NormalLaw;
pub use stability::{StabilityWarning, check_stability};

use crate::data::Data;
use crate::description::{RobotDescription, Shape};
use crate::integrate::ForceModel;
use crate::model::Model;
use crate::spatial::{Force, Motion};
use crate::terrain::{TerrainHit, TerrainUnion};
use glam::DVec3;

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

/// What [`contact_forces`] adds for one contact at the kinematics
/// [`update_after_step`] saw, against the state the update left: kept by the
/// update, whose own evaluation (against the state before it) already holds
/// most of it, and used by the next [`contact_forces`] call at the same
/// kinematics — the first derivative evaluation of the step. Valid while the
/// evaluation's inputs are bitwise those of the update: the sphere centre
/// (the [`CachedQuery`]'s), the body's spatial velocity, `data.origin`, and
/// the state's anchor and contact flag (the points and terrain the states
/// belong to). The force is then the same, bit for bit, so evaluations stay
/// pure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CachedForce {
    /// The body's spatial velocity (reference frame), `data.vel[body]`.
    pub body_velocity: Motion,
    /// `data.origin` (m).
    pub origin_m: DVec3,
    /// The state's anchor then (m, world).
    pub anchor_m: DVec3,
    /// The state's contact flag then.
    pub in_contact: bool,
    /// What is added to the body's `data.f_ext` (reference frame); `None`:
    /// no contact, nothing added (whatever the velocity and anchor).
    pub force: Option<Force>,
}

/// Whether two vectors hold the same bits (`==` would take −0 for +0).
#[inline]
fn same_bits(a: DVec3, b: DVec3) -> bool {
    (a.x.to_bits() == b.x.to_bits())
        & (a.y.to_bits() == b.y.to_bits())
        & (a.z.to_bits() == b.z.to_bits())
}

/// Persistent state of one contact, updated once per step by [`update_after_step`].
/// Reset it to the default when the terrain changes (its anchor, cached
/// query and cached force refer to the old ground).
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
    /// The force at the last end-of-step kinematics, against this state
    /// (valid with `last_query`, at the same centre).
    pub last_force: Option<CachedForce>,
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
    evaluate_with_parts(point, data, terrain, state).0
}

/// [`evaluate`], and for an active contact what its tangential force came
/// from besides the state: the ground's material and the tangential velocity
/// of the body's material point (m/s), for [`tangential_force`] against
/// another anchor.
#[inline(always)]
fn evaluate_with_parts<'t>(
    point: &ContactPoint,
    data: &Data,
    terrain: &'t TerrainUnion,
    state: &ContactState,
) -> (ContactEval, Option<(&'t GroundMaterial, DVec3)>) {
    let centre = data.body_point_world(point.body, point.point_in_body);
    let hit = match &state.last_query {
        Some(q) if q.centre_m == centre => q.hit,
        _ => terrain.closest_hit(centre),
    };
    let Some(TerrainHit { surface, source }) = hit else {
        let e = ContactEval {
            centre_m: centre,
            ..ContactEval::NONE
        };
        return (e, None);
    };
    let depth_m = surface.depth_m + point.radius_m;
    let n = surface.normal;
    let application_m = centre - point.radius_m * n;
    if depth_m <= 0.0 {
        let e = ContactEval {
            depth_m,
            normal: n,
            application_m,
            ground_point_m: surface.point,
            centre_m: centre,
            hit,
            ..ContactEval::NONE
        };
        return (e, None);
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
    let (tangential_force_n, slipping) =
        tangential_force(material, state, surface.point, n, normal_force_n, v_t);
    let e = ContactEval {
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
    };
    (e, Some((material, v_t)))
}

/// The stick–slip force of an active contact against `state`'s anchor (N,
/// world) and whether it slides: the tangential part of `ground_point_m − anchor`
/// (zero for a contact not yet touching) and the tangential velocity `v_t_mps`.
#[inline(always)]
fn tangential_force(
    material: &GroundMaterial,
    state: &ContactState,
    ground_point_m: DVec3,
    n: DVec3,
    normal_force_n: f64,
    v_t_mps: DVec3,
) -> (DVec3, bool) {
    let e_t = if state.in_contact {
        let e = ground_point_m - state.anchor_m;
        e - e.dot(n) * n
    } else {
        DVec3::ZERO
    };
    friction::stick_slip(
        material.tangential_stiffness_npm,
        material.tangential_damping_nspm,
        material.friction,
        normal_force_n,
        e_t,
        v_t_mps,
    )
}

/// Adds every contact's force to `data.f_ext` at the stage state held in
/// `data` (after [`crate::kinematics::forward_kinematics`]). Pure in the
/// persistent state: call it at every RK4 stage. `out`, when given (same
/// length as `points`), receives each evaluation. (Its x86-64-v3 clone,
/// with `cached_force` forced inline into it, spares register copies; no
/// fused multiply–add, so both give the same bits.)
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
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
        if out.is_none()
            && let Some(f) = cached_force(p, data, s)
        {
            if let Some(f) = f {
                data.add_external_force(p.body, f);
            }
            continue;
        }
        let e = evaluate(p, data, terrain, s);
        if e.active {
            data.add_point_force(p.body, e.application_m, e.force_n());
        }
        if let Some(o) = out.as_deref_mut() {
            o[i] = e;
        }
    }
}

/// The update's [`CachedForce`] of `state` when `data` holds the inputs it
/// was found at: `Some(None)` no contact, `Some(Some(f))` add `f`.
#[inline(always)]
fn cached_force(point: &ContactPoint, data: &Data, state: &ContactState) -> Option<Option<Force>> {
    let (Some(q), Some(c)) = (&state.last_query, &state.last_force) else {
        return None;
    };
    let centre = data.body_point_world(point.body, point.point_in_body);
    if !same_bits(q.centre_m, centre) {
        return None;
    }
    if c.force.is_none() {
        return Some(None);
    }
    let vel = &data.vel[point.body];
    let same = same_bits(vel.lin, c.body_velocity.lin)
        & same_bits(vel.ang, c.body_velocity.ang)
        & same_bits(data.origin, c.origin_m)
        & same_bits(state.anchor_m, c.anchor_m)
        & (state.in_contact == c.in_contact);
    same.then_some(c.force)
}

/// Once per accepted step, with `data` holding kinematics (with velocities)
/// at the new state: evaluates every contact and updates its state. At
/// touchdown the anchor is set to the ground point; while slipping it is
/// dragged so the spring sits at the friction limit; on lift-off the contact
/// is cleared. (Its x86-64-v3 clone's three-operand instructions spare
/// register copies; no fused multiply–add, so both give the same bits.)
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn update_after_step(
    points: &[ContactPoint],
    data: &Data,
    terrain: &TerrainUnion,
    states: &mut [ContactState],
) {
    debug_assert_eq!(points.len(), states.len());
    for (p, s) in points.iter().zip(states.iter_mut()) {
        let (e, parts) = evaluate_with_parts(p, data, terrain, s);
        s.last_query = Some(CachedQuery {
            centre_m: e.centre_m,
            hit: e.hit,
        });
        // `parts` is there exactly when `e.active`.
        let Some((material, v_t_mps)) = parts else {
            // At this centre the evaluation is inactive whatever the state.
            *s = ContactState {
                last_query: s.last_query,
                last_force: Some(CachedForce {
                    body_velocity: Motion::ZERO,
                    origin_m: DVec3::ZERO,
                    anchor_m: DVec3::ZERO,
                    in_contact: false,
                    force: None,
                }),
                ..ContactState::default()
            };
            continue;
        };
        // The anchor stays where it is only in a sticking contact that was
        // already touching: then the state's inputs to `evaluate` are
        // unchanged and the evaluation against the new state is `e`.
        let anchor_moves = !s.in_contact || e.slipping;
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
        // What `contact_forces` finds next at this kinematics: `evaluate`
        // against the new state, in which only the tangential force can
        // differ (the same centre, query, depth and velocity).
        let next_force_n = if anchor_moves {
            let (t, _) = tangential_force(
                material,
                s,
                e.ground_point_m,
                e.normal,
                e.normal_force_n,
                v_t_mps,
            );
            ContactEval {
                tangential_force_n: t,
                ..e
            }
            .force_n()
        } else {
            s.force_n
        };
        s.last_force = Some(CachedForce {
            body_velocity: data.vel[p.body],
            origin_m: data.origin,
            anchor_m: s.anchor_m,
            in_contact: s.in_contact,
            force: Some(Force::at_point(next_force_n, e.application_m - data.origin)),
        });
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
