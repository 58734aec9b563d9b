//! Preallocated state-dependent workspace (Pinocchio's `Data`, MuJoCo's `mjData`).
//!
//! Sized once from a [`Model`]; no algorithm allocates. Spatial quantities are
//! expressed in the robot's *reference frame*: world-aligned axes, about the
//! world-fixed point [`Data::origin`] that coincides with the base origin when
//! [`crate::kinematics::forward_kinematics`] last ran.

use crate::kernels::legs_x4::workspace::{LaneKinematics, reserve_group_aba};
use crate::model::Model;
use crate::spatial::{Force, Motion, RigidInertia, Transform};
use crate::workspace::{BodyScratch, MassMatrix};
use glam::DVec3;

/// Workspace and outputs of the algorithms, grouped by the stage that writes them.
/// What holds nothing from one call to the next (ABA's and CRBA's per-body
/// workspace, the legs-in-lanes ABA's per-group one, the mass matrix, RK4's
/// stages) is one per thread instead ([`crate::workspace`]), not one per
/// robot.
#[derive(Clone, Debug)]
pub struct Data {
    // --- kinematics (forward_kinematics) ---
    /// Reference point of all spatial quantities: the base origin in the world (m).
    pub origin: DVec3,
    /// World placement of each body frame (`oMi`) (nbodies).
    pub pose: Vec<Transform>,
    /// Spatial velocity of each body, reference frame (nbodies).
    pub vel: Vec<Motion>,
    /// Motion subspace column of each 1-DOF body, reference frame (nbodies;
    /// base unused).
    pub(crate) s: Vec<Motion>,
    /// Each body's rigid inertia in the reference frame (CoM relative to `origin`)
    /// (nbodies; empty in a kinematics-only `Data`).
    pub(crate) inertia_ref: Vec<RigidInertia>,

    // --- dynamics (rnea / aba / crba) ---
    /// Spatial acceleration of each body, reference frame (nbodies). ABA and
    /// RNEA fill it; after [`crate::integrate::step`] only the base's entry is
    /// defined (see there).
    pub acc: Vec<Motion>,
    /// Spatial force transmitted by each body's parent joint (RNEA), reference frame (nbodies).
    pub f: Vec<Force>,
    /// External spatial force on each body, world axes about `origin` (nbodies).
    /// Set by the caller (contacts, pushes) after kinematics through
    /// [`Data::add_point_force`], [`Data::add_external_force`] or
    /// [`Data::external_forces_mut`]; read with [`Data::external_forces`].
    pub(crate) f_ext: Vec<Force>,
    /// Which bodies' `f_ext` may be non-zero since the last
    /// [`Data::clear_external_forces`]: bit `min(b, 63)` for body `b`. The
    /// clear then zeroes only those, and ABA in the legs' lanes skips the
    /// groups none of whose bodies has a force (subtracting an exact +0
    /// changes no bit).
    f_ext_touched: u64,

    // --- outputs ---
    /// Generalised acceleration from ABA (nv).
    pub ddq: Vec<f64>,
    /// Generalised force from RNEA (nv).
    pub tau: Vec<f64>,
    /// Nonlinear effects `C(q, v) v + g(q)` (nv).
    pub nle: Vec<f64>,
    /// Generalised gravity `g(q)` (nv).
    pub gravity: Vec<f64>,
    /// Point Jacobian, row-major 3 × nv, world axes (see [`crate::jacobian`]).
    pub jacobian: Vec<f64>,
    /// Scratch of length nv.
    pub scratch_v: Vec<f64>,
    /// What the kinematic fields (`origin`, `pose`, `s`,
    /// `inertia_ref`, `vel`) were computed for, so that a repeated call at
    /// the same state (observation, then the integrator's first stage) is
    /// skipped: see [`crate::kinematics::forward_kinematics`].
    pub(crate) kin: KinematicsKey,
    /// A copy of the legs' `s`, `inertia_ref` and `vel` in lanes, for ABA,
    /// RNEA and the mass sums in lanes ([`crate::kernels::legs_x4`]); the
    /// per-body arrays hold the same values.
    pub(crate) lanes: LaneKinematics,
}

/// The state the kinematic fields of a [`Data`] hold: the model's address,
/// q and v bit for bit, and whether velocities were computed.
#[derive(Clone, Debug, Default)]
pub(crate) struct KinematicsKey {
    pub(crate) model: usize,
    pub(crate) q: Vec<f64>,
    pub(crate) v: Vec<f64>,
    /// 0: nothing valid; 1: poses for `q`; 2: poses for `q` and velocities for `v`.
    pub(crate) level: u8,
}

impl Data {
    /// Allocates the workspace for `model` (and sizes this thread's ABA and
    /// CRBA workspace, `BodyScratch`, and mass-matrix buffer,
    /// [`crate::crba::MassMatrix`], for it, so that stepping on this thread
    /// allocates nothing from the first step).
    pub fn new(model: &Model) -> Data {
        BodyScratch::take(model.nbodies).give_back();
        MassMatrix::reserve(model.nv);
        if let Some(legs) = model.leg_lanes() {
            reserve_group_aba(legs.groups.len());
        }
        Data::allocate(model, true)
    }

    /// A workspace for [`crate::kinematics::forward_kinematics`] and the
    /// point queries on its result only (poses, subspaces, velocities): the
    /// reference inertias and the dynamics arrays are left empty (and not
    /// computed), so neither the dynamics algorithms nor the CoM and energy
    /// functions must be run on it. For state estimators, which need a
    /// second copy of a robot's kinematics and nothing else.
    pub fn for_kinematics(model: &Model) -> Data {
        Data::allocate(model, false)
    }

    /// The kinematic fields always; the dynamics arrays when `dynamics`.
    fn allocate(model: &Model, dynamics: bool) -> Data {
        let nb = model.nbodies;
        let nv = model.nv;
        // `n` elements of `x` with the dynamics, none without
        fn dyn_vec<T: Clone>(dynamics: bool, x: T, n: usize) -> Vec<T> {
            if dynamics { vec![x; n] } else { Vec::new() }
        }
        Data {
            origin: DVec3::ZERO,
            pose: vec![Transform::IDENTITY; nb],
            vel: vec![Motion::ZERO; nb],
            s: vec![Motion::ZERO; nb],
            inertia_ref: dyn_vec(dynamics, RigidInertia::ZERO, nb),
            acc: dyn_vec(dynamics, Motion::ZERO, nb),
            f: dyn_vec(dynamics, Force::ZERO, nb),
            f_ext: dyn_vec(dynamics, Force::ZERO, nb),
            f_ext_touched: 0,
            ddq: dyn_vec(dynamics, 0.0, nv),
            tau: dyn_vec(dynamics, 0.0, nv),
            nle: dyn_vec(dynamics, 0.0, nv),
            gravity: dyn_vec(dynamics, 0.0, nv),
            jacobian: dyn_vec(dynamics, 0.0, 3 * nv),
            scratch_v: dyn_vec(dynamics, 0.0, nv),
            kin: KinematicsKey {
                model: 0,
                q: vec![0.0; model.nq],
                v: vec![0.0; nv],
                level: 0,
            },
            lanes: LaneKinematics::new(match model.leg_lanes() {
                Some(legs) if dynamics => legs.groups.len(),
                _ => 0,
            }),
        }
    }

    /// Whether this is a workspace sized for `model`: a full one when
    /// `dynamics`, else a kinematics-only one.
    fn fits_as(&self, model: &Model, dynamics: bool) -> bool {
        self.pose.len() == model.nbodies
            && self.inertia_ref.len() == if dynamics { model.nbodies } else { 0 }
            && self.kin.q.len() == model.nq
            && self.kin.v.len() == model.nv
    }

    /// Whether the kinematic fields (poses, subspaces, velocities, reference
    /// inertias) hold [`crate::kinematics::forward_kinematics`] at `(q, v)` of
    /// `model`, bit for bit (what its cache checks).
    pub fn kinematics_hold(&self, model: &Model, q: &[f64], v: &[f64]) -> bool {
        kinematics_level(model, self, q, Some(v)) == 2
    }

    /// Body `i`'s rigid inertia in the reference frame (CoM relative to
    /// `origin`), after [`crate::kinematics::forward_kinematics`] on `model`
    /// (with the dynamics arrays: not in a kinematics-only `Data`).
    #[inline(always)]
    pub fn body_inertia(&self, model: &Model, i: usize) -> RigidInertia {
        let _ = model;
        self.inertia_ref[i]
    }

    /// Body `i`'s motion subspace column (reference frame; `i` not the
    /// base), after [`crate::kinematics::forward_kinematics`] on `model`.
    #[inline(always)]
    pub fn subspace(&self, model: &Model, i: usize) -> Motion {
        let _ = model;
        self.s[i]
    }

    /// Column `k` (0..6, for `v[k]`) of the free base's motion subspace,
    /// reference frame: the base's rotation's column `k` as linear (k < 3)
    /// or angular (k ≥ 3) part, the other part zero. Computed from
    /// `pose[0]` where it is read (a few times per control tick) instead of
    /// stored by every forward kinematics (six motions, 288 bytes per robot).
    #[inline(always)]
    pub fn base_subspace(&self, k: usize) -> Motion {
        let r = &self.pose[0].rot;
        if k < 3 {
            Motion::new(r.col(k), DVec3::ZERO)
        } else {
            Motion::new(DVec3::ZERO, r.col(k - 3))
        }
    }

    /// `f(i, inertia)` for every body `i` in increasing order, with
    /// [`Data::body_inertia`]'s inertias: for a sum over the bodies in their
    /// order (centre of mass, momentum) read every step.
    #[inline(always)]
    pub fn for_each_body_inertia(&self, model: &Model, mut f: impl FnMut(usize, RigidInertia)) {
        for i in 0..model.nbodies {
            f(i, self.inertia_ref[i]);
        }
    }

    /// Forgets which state the kinematic fields hold (after writing them by hand).
    pub fn invalidate_kinematics(&mut self) {
        self.kin.level = 0;
        self.lanes.valid = false;
    }

    /// Clears every external force (only the entries written since the
    /// last clear: the others are zero already).
    pub fn clear_external_forces(&mut self) {
        let touched = std::mem::take(&mut self.f_ext_touched);
        if touched & (1 << 63) != 0 {
            self.f_ext.fill(Force::ZERO);
            return;
        }
        let mut bits = touched;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            self.f_ext[b] = Force::ZERO;
            bits &= bits - 1;
        }
    }

    /// The external spatial forces on the bodies, world axes about
    /// [`Data::origin`] (nbodies; empty in a kinematics-only `Data`).
    #[inline]
    pub fn external_forces(&self) -> &[Force] {
        &self.f_ext
    }

    /// The external forces to write directly (every entry counts as
    /// written until the next [`Data::clear_external_forces`]).
    pub fn external_forces_mut(&mut self) -> &mut [Force] {
        self.f_ext_touched = u64::MAX;
        &mut self.f_ext
    }

    /// Adds the spatial force `f` (world axes, about [`Data::origin`]) on `body`.
    #[inline]
    pub fn add_external_force(&mut self, body: usize, f: Force) {
        self.f_ext[body] += f;
        self.f_ext_touched |= body_bit(body);
    }

    /// Whether a body of `bodies` may carry an external force (one written
    /// since the last clear).
    #[inline]
    pub(crate) fn external_force_on_any(&self, bodies: &[usize]) -> bool {
        let mask = bodies.iter().fold(0, |m, &b| m | body_bit(b));
        self.f_ext_touched & mask != 0
    }

    /// Adds a force `force_n` (N, world frame) acting on `body` at the world point `point_m`.
    /// Valid until the next kinematics call moves [`Data::origin`].
    #[inline]
    pub fn add_point_force(&mut self, body: usize, point_m: DVec3, force_n: DVec3) {
        self.add_external_force(body, Force::at_point(force_n, point_m - self.origin));
    }

    /// World position of a point given in a body's frame (after kinematics).
    #[inline]
    pub fn body_point_world(&self, body: usize, point_in_body: DVec3) -> DVec3 {
        self.pose[body].transform_point(point_in_body)
    }

    /// World velocity (m/s) of a point given in a body's frame (after kinematics with velocity).
    #[inline]
    pub fn body_point_velocity(&self, body: usize, point_in_body: DVec3) -> DVec3 {
        let p = self.pose[body].transform_point(point_in_body);
        self.vel[body].point_velocity(p - self.origin)
    }
}

/// Most spare workspaces a [`SpareData`] keeps.
const MAX_SPARES: usize = 8;

/// Spare workspaces ([`Data`]), one per model shape (bodies, nq, nv) in
/// use, lent by [`SpareData::with`]. Full ones ([`SpareData::default`]): for
/// a second kinematic state beside a robot's own `Data` (a controller at the
/// estimated state), so that the robot's kinematics at the true state
/// survive for the stages after it instead of being recomputed.
/// Kinematics-only ones ([`SpareData::kinematics_only`],
/// [`Data::for_kinematics`]): a state estimator's leg kinematics, which
/// nothing reads after the update that computes them, so that they need not
/// live (and be fetched from memory) in every robot. A value owned by
/// whatever steps the robots, one per worker (`systems`'
/// `WorkerWorkspace`), and passed explicitly: it holds nothing a result
/// depends on from one loan to the next.
#[derive(Debug)]
pub struct SpareData {
    /// Full workspaces ([`Data::new`]), else kinematics-only ones.
    dynamics: bool,
    /// Boxed: taking one out and putting it back moves a pointer, not the
    /// `Data` (about 700 bytes of vector headers and the base's subspace,
    /// copied twice per control tick).
    #[allow(clippy::vec_box)]
    spares: Vec<Box<Data>>,
}

impl Default for SpareData {
    /// A pool of full workspaces.
    fn default() -> Self {
        Self {
            dynamics: true,
            spares: Vec::new(),
        }
    }
}

impl SpareData {
    /// A pool of kinematics-only workspaces ([`Data::for_kinematics`]).
    pub fn kinematics_only() -> Self {
        Self {
            dynamics: false,
            spares: Vec::new(),
        }
    }

    /// Runs `f` on a spare workspace for a model of `model`'s shape,
    /// allocated at its first use. The spare's kinematics cache is cleared
    /// before `f`: what it held for another robot is never reused, so `f`'s
    /// results do not depend on which robot used the spare before (every
    /// field a computation reads it writes first, as with a fresh `Data`).
    pub fn with<R>(&mut self, model: &Model, f: impl FnOnce(&mut Data) -> R) -> R {
        let taken = take_fitting(&mut self.spares, model, self.dynamics);
        let (result, data) = lend(taken, model, self.dynamics, f);
        keep(&mut self.spares, data);
        result
    }
}

/// Takes out of `spares` one that fits `model` (full when `dynamics`).
#[allow(clippy::vec_box)] // boxed spares: lending one moves a pointer
fn take_fitting(spares: &mut Vec<Box<Data>>, model: &Model, dynamics: bool) -> Option<Box<Data>> {
    let i = spares.iter().position(|d| d.fits_as(model, dynamics))?;
    Some(spares.swap_remove(i))
}

/// `taken` (or a new workspace for `model`), its cache cleared, lent to `f`.
fn lend<R>(
    taken: Option<Box<Data>>,
    model: &Model,
    dynamics: bool,
    f: impl FnOnce(&mut Data) -> R,
) -> (R, Box<Data>) {
    let mut data = taken.unwrap_or_else(|| {
        Box::new(if dynamics {
            Data::new(model)
        } else {
            Data::for_kinematics(model)
        })
    });
    data.invalidate_kinematics();
    (f(&mut data), data)
}

/// Puts `data` back among `spares`: one per shape in use; a pool that meets
/// many shapes keeps the latest.
#[allow(clippy::vec_box)] // boxed spares: lending one moves a pointer
fn keep(spares: &mut Vec<Box<Data>>, data: Box<Data>) {
    if spares.len() >= MAX_SPARES {
        spares.remove(0);
    }
    spares.push(data);
}

/// How much of `data`'s kinematics is valid for `(model, q, v)`: 2 poses and
/// velocities, 1 poses only, 0 nothing. States compare bit for bit, so a
/// skipped call gives exactly what computing again would.
#[inline]
pub(crate) fn kinematics_level(model: &Model, data: &Data, q: &[f64], v: Option<&[f64]>) -> u8 {
    let k = &data.kin;
    let same = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    };
    if k.level == 0 || k.model != model as *const Model as usize || !same(&k.q, q) {
        return 0;
    }
    match v {
        Some(v) if k.level == 2 && same(&k.v, v) => 2,
        _ => 1,
    }
}

/// `Data::f_ext_touched`'s bit for `body`: its own below 63, bit 63 for
/// every body from 63 on.
#[inline]
fn body_bit(body: usize) -> u64 {
    1 << body.min(63)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dispatch::forward_kinematics;
    use crate::dispatch::rnea;
    use crate::model::BaseKind;
    use crate::robots::{builtin, nominal_q};

    fn model(name: &str, scale_mass: f64) -> Model {
        let mut desc = builtin(name).unwrap();
        for link in &mut desc.links {
            link.mass_kg *= scale_mass;
            link.inertia_kgm2 = link.inertia_kgm2.map(|i| i * scale_mass);
        }
        Model::from_description(&desc, BaseKind::Floating).unwrap()
    }

    /// Clearing the external forces zeroes every entry written since the
    /// last clear, by any route (a point force, a spatial force, direct
    /// writes), and `external_force_on_any` sees exactly the written bodies.
    #[test]
    fn clearing_external_forces_zeroes_what_was_written() {
        let m = model("quad16", 1.0);
        let mut d = Data::new(&m);
        let f = Force::new(DVec3::new(1.0, -2.0, 3.0), DVec3::new(0.5, 0.0, -0.25));
        d.add_point_force(3, DVec3::new(0.1, 0.2, 0.3), DVec3::Z);
        d.add_external_force(7, f);
        assert!(d.external_force_on_any(&[1, 3]) && d.external_force_on_any(&[7]));
        assert!(!d.external_force_on_any(&[0, 1, 2, 4, 5, 6, 8]));
        d.clear_external_forces();
        assert!(d.external_forces().iter().all(|&x| x == Force::ZERO));
        assert!(!d.external_force_on_any(&[3, 7]));
        for x in d.external_forces_mut() {
            *x = f;
        }
        assert!(d.external_force_on_any(&[0]));
        d.clear_external_forces();
        assert!(d.external_forces().iter().all(|&x| x == Force::ZERO));
        // bodies from 63 on share one bit, which clears them all
        assert_eq!(
            (body_bit(62), body_bit(63), body_bit(200)),
            (1 << 62, 1 << 63, 1 << 63)
        );
    }

    /// Inverse dynamics on a spare equal a fresh workspace's bit for bit,
    /// whatever the spare held before: another model of the same shape at
    /// the same state, a model of another shape, a nested second spare.
    #[test]
    fn a_spare_workspace_computes_what_a_fresh_one_does() {
        let (light, heavy, quad12) = (
            model("quad16", 1.0),
            model("quad16", 1.5),
            model("quad12", 1.0),
        );
        let q = nominal_q("quad16").unwrap();
        let v: Vec<f64> = (0..light.nv).map(|i| (i as f64 * 0.3).cos()).collect();
        let a: Vec<f64> = (0..light.nv).map(|i| (i as f64 * 0.5).sin()).collect();
        let fresh = |m: &Model| rnea(m, &mut Data::new(m), &q, &v, &a).to_vec();
        let spare =
            |pool: &mut SpareData, m: &Model| pool.with(m, |d| rnea(m, d, &q, &v, &a).to_vec());
        assert_ne!(fresh(&light), fresh(&heavy), "the two models differ");
        let mut spares = SpareData::default();
        let q12 = nominal_q("quad12").unwrap();
        spares.with(&quad12, |d| {
            forward_kinematics(&quad12, d, &q12, &vec![0.0; quad12.nv])
        });
        for m in [&light, &heavy, &light] {
            assert_eq!(spare(&mut spares, m), fresh(m));
        }
        // a spare lent while another pool's is out is another workspace (one
        // pool cannot lend twice at once: it is borrowed while lending)
        let mut other = SpareData::default();
        other.with(&light, |outer| {
            rnea(&light, outer, &q, &v, &a);
            assert_eq!(
                spare(&mut spares, &heavy),
                fresh(&heavy),
                "a nested spare is another workspace"
            );
            assert_eq!(outer.tau, fresh(&light), "and leaves the outer one alone");
        });
    }
}
