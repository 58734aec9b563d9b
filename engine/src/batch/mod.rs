//! Batched dynamics: forward kinematics and ABA for `L` robots of the **same
//! model** at once, one SIMD lane per robot.
//!
//! The per-robot algorithms ([`crate::kinematics`], [`crate::aba`]) spend their
//! time in short dependent chains of 3-vector and 3×3 arithmetic that leave
//! most of a SIMD unit idle. Here every number is a [`Lanes<L>`](lanes::Lanes),
//! one value per robot, in a structure-of-arrays workspace
//! ([`BatchData`]): the same instruction stream serves `L` robots, and LLVM
//! emits `f64x4` (AVX2) or `f64x2` (SSE2) instructions for each lane operation.
//!
//! **Bit-identical to the scalar path.** Each lane repeats the scalar
//! algorithm's arithmetic operation for operation (glam's formulas, the same
//! sums in the same order, no fused multiply–add, the scalar kinematics' sine and cosine per lane,
//! and the floating base's 6×6 solve by the scalar [`Sym6::solve`](crate::spatial::Sym6::solve)
//! per lane), so every robot's `ddq` equals what [`crate::aba::aba`] returns
//! for it, bit for bit, on any build: the tests in this module check it on
//! quad16, quad12 and random trees with non-aligned revolute and prismatic joints.
//!
//! **Runtime CPU dispatch.** [`forward_kinematics_batch`] and [`aba_batch`]
//! are compiled twice by the `multiversion` crate: for x86-64 with AVX2 and
//! FMA (x86-64-v3; FMA is enabled but never used for `a * b + c`, which Rust
//! does not contract) and for the build's generic target, and pick one at the
//! first call from the CPU's features. A generic x86-64 build thus runs AVX2
//! code on a CPU that has it, and stays correct on one that does not.
//!
//! Usage: fill the lanes with [`BatchData::set_robot`] (and optionally
//! [`BatchData::set_external_forces`]), set how many lanes are in use with
//! [`BatchData::set_active`], call [`aba_batch`], read each robot's
//! acceleration with [`BatchData::ddq_of`]. Nothing allocates after
//! [`BatchData::new`].

pub mod aba;
pub mod kinematics;
pub mod lanes;
pub mod spatial;
pub mod step;

pub use aba::{aba_batch, aba_batch_generic, aba_from_kinematics_batch};
pub use kinematics::forward_kinematics_batch;
pub use step::{StepParts, step_semi_implicit_batch};

use crate::model::Model;
use crate::spatial::Force;
use lanes::{LVec3, Lanes};
use spatial::{LForce, LInertia, LMotion, LSym6, LTransform};

/// Robots per batch in the engine's own uses: four f64 lanes fill one AVX2 register.
pub const LANES: usize = 4;

/// The structure-of-arrays workspace of `L` robots of one model: inputs
/// (`q`, `v`, `tau`, `f_ext`), the kinematics and ABA fields of
/// [`crate::Data`] with one lane per robot, and the output `ddq`.
///
/// Spatial quantities of lane `k` are in robot `k`'s reference frame (world
/// axes, about its own base origin `origin`), as in [`crate::Data`].
#[derive(Clone, Debug)]
pub struct BatchData<const L: usize = LANES> {
    /// Lanes in use (1..=L); the others keep their last (valid) inputs and
    /// their outputs are meaningless.
    active: usize,
    // --- inputs ---
    /// Configuration per lane (nq).
    pub q: Vec<Lanes<L>>,
    /// Velocity per lane (nv).
    pub v: Vec<Lanes<L>>,
    /// Generalised force per lane (nv; base entries a wrench in the base frame).
    pub tau: Vec<Lanes<L>>,
    /// External spatial force on each body, world axes about each lane's
    /// `origin` (nbodies); used when [`aba_batch`] is asked to.
    pub f_ext: Vec<LForce<L>>,
    // --- kinematics ---
    /// Base origin in the world, the reference point of lane `k` (m).
    pub origin: LVec3<L>,
    /// World placement of each body (nbodies).
    pub pose: Vec<LTransform<L>>,
    /// Spatial velocity of each body, reference frame (nbodies).
    pub vel: Vec<LMotion<L>>,
    /// Motion subspace column of each 1-DOF body, reference frame (nbodies).
    pub s: Vec<LMotion<L>>,
    /// Each body's rigid inertia in the reference frame (nbodies).
    pub inertia_ref: Vec<LInertia<L>>,
    // --- ABA ---
    /// Articulated inertia (nbodies).
    pub ia: Vec<LSym6<L>>,
    /// Articulated bias force (nbodies).
    pub pa: Vec<LForce<L>>,
    /// `U = Iᴬ S` (nbodies).
    pub u: Vec<LForce<L>>,
    /// `1 / D` (nbodies).
    pub d_inv: Vec<Lanes<L>>,
    /// `u = τ − Sᵀ pᴬ` (nbodies).
    pub u_tau: Vec<Lanes<L>>,
    /// Velocity-product acceleration (nbodies).
    pub c: Vec<LMotion<L>>,
    /// Spatial acceleration of each body (true, gravity included), reference frame (nbodies).
    pub acc: Vec<LMotion<L>>,
    // --- output ---
    /// Generalised acceleration per lane (nv), as [`crate::aba::aba`] defines it.
    pub ddq: Vec<Lanes<L>>,
}

impl<const L: usize> BatchData<L> {
    /// Allocates the workspace for `L` robots of `model`, every lane at the
    /// neutral configuration at rest, all lanes active.
    ///
    /// # Panics
    /// If `L` is 0.
    pub fn new(model: &Model) -> Self {
        assert!(L > 0, "a batch needs at least one lane");
        let (nb, nv) = (model.nbodies, model.nv);
        let q = model.neutral_q().iter().map(|&x| Lanes::splat(x)).collect();
        BatchData {
            active: L,
            q,
            v: vec![Lanes::ZERO; nv],
            tau: vec![Lanes::ZERO; nv],
            f_ext: vec![LForce::ZERO; nb],
            origin: LVec3::ZERO,
            pose: vec![LTransform::default(); nb],
            vel: vec![LMotion::ZERO; nb],
            s: vec![LMotion::ZERO; nb],
            inertia_ref: vec![LInertia::default(); nb],
            ia: vec![LSym6::default(); nb],
            pa: vec![LForce::ZERO; nb],
            u: vec![LForce::ZERO; nb],
            d_inv: vec![Lanes::ZERO; nb],
            u_tau: vec![Lanes::ZERO; nb],
            c: vec![LMotion::ZERO; nb],
            acc: vec![LMotion::ZERO; nb],
            ddq: vec![Lanes::ZERO; nv],
        }
    }

    /// Number of lanes in use.
    pub fn active(&self) -> usize {
        self.active
    }

    /// Uses lanes `0..n` (a partly filled batch when `n < L`).
    ///
    /// # Panics
    /// Unless `1 ≤ n ≤ L`.
    pub fn set_active(&mut self, n: usize) {
        assert!((1..=L).contains(&n), "active lanes {n} not in 1..={L}");
        self.active = n;
    }

    /// Writes robot `lane`'s state `(q, v)` and generalised force `tau` (nq, nv, nv).
    ///
    /// # Panics
    /// If a length is wrong or `lane ≥ L`.
    pub fn set_robot(&mut self, lane: usize, q: &[f64], v: &[f64], tau: &[f64]) {
        assert!(lane < L, "lane {lane} ≥ {L}");
        assert_eq!(q.len(), self.q.len(), "q length");
        assert_eq!(v.len(), self.v.len(), "v length");
        assert_eq!(tau.len(), self.tau.len(), "tau length");
        for (dst, &x) in self.q.iter_mut().zip(q) {
            dst.0[lane] = x;
        }
        for (dst, &x) in self.v.iter_mut().zip(v) {
            dst.0[lane] = x;
        }
        for (dst, &x) in self.tau.iter_mut().zip(tau) {
            dst.0[lane] = x;
        }
    }

    /// Writes robot `lane`'s state `(q, v)` only (nq, nv).
    ///
    /// # Panics
    /// If a length is wrong or `lane ≥ L`.
    pub fn set_state(&mut self, lane: usize, q: &[f64], v: &[f64]) {
        assert!(lane < L, "lane {lane} ≥ {L}");
        assert_eq!(q.len(), self.q.len(), "q length");
        assert_eq!(v.len(), self.v.len(), "v length");
        for (dst, &x) in self.q.iter_mut().zip(q) {
            dst.0[lane] = x;
        }
        for (dst, &x) in self.v.iter_mut().zip(v) {
            dst.0[lane] = x;
        }
    }

    /// Writes robot `lane`'s generalised force (nv).
    ///
    /// # Panics
    /// If the length is wrong or `lane ≥ L`.
    pub fn set_tau(&mut self, lane: usize, tau: &[f64]) {
        assert!(lane < L, "lane {lane} ≥ {L}");
        assert_eq!(tau.len(), self.tau.len(), "tau length");
        for (dst, &x) in self.tau.iter_mut().zip(tau) {
            dst.0[lane] = x;
        }
    }

    /// True when this workspace has `model`'s sizes (it holds nothing else
    /// of a model, so any model of these sizes may use it).
    pub fn fits(&self, model: &Model) -> bool {
        self.pose.len() == model.nbodies && self.q.len() == model.nq && self.v.len() == model.nv
    }

    /// The reverse of [`BatchData::kinematics_into`]: fills lane `lane`'s
    /// `origin`, `pose`, `vel`, `s` and `inertia_ref` from a `data` whose
    /// kinematics hold for that lane's `(q, v)` (see [`crate::Data::kinematics_hold`]),
    /// so that [`aba_from_kinematics_batch`] can run without recomputing them.
    /// Since the batched kinematics equal the scalar ones bit for bit, the
    /// lane ends as [`forward_kinematics_batch`] would leave it.
    pub fn kinematics_from(&mut self, lane: usize, model: &Model, data: &crate::Data) {
        let set_mat = |m: &mut lanes::LMat3<L>, v: glam::DMat3| {
            m.x_axis.set_lane(lane, v.x_axis);
            m.y_axis.set_lane(lane, v.y_axis);
            m.z_axis.set_lane(lane, v.z_axis);
        };
        self.origin.set_lane(lane, data.origin);
        for i in 0..model.nbodies {
            let (p, ri) = (&data.pose[i], &data.body_inertia(model, i));
            set_mat(&mut self.pose[i].rot, p.rot);
            self.pose[i].trans.set_lane(lane, p.trans);
            self.vel[i].set_lane(lane, data.vel[i]);
            self.s[i].set_lane(lane, data.subspace(model, i));
            let li = &mut self.inertia_ref[i];
            li.mass.0[lane] = ri.mass;
            li.com.set_lane(lane, ri.com);
            set_mat(&mut li.inertia_com, ri.inertia_com);
        }
    }

    /// Copies lane `lane`'s kinematics (after [`forward_kinematics_batch`] on
    /// `(q, v)`, which must be that lane's state) into a scalar `data`:
    /// `origin`, `pose`, `s`, `inertia_ref`, `vel`, and marks them
    /// valid for `(model, q, v)`, exactly as [`crate::kinematics::forward_kinematics`]
    /// would have left them.
    pub fn kinematics_into(
        &self,
        lane: usize,
        model: &Model,
        data: &mut crate::Data,
        q: &[f64],
        v: &[f64],
    ) {
        use crate::spatial::RigidInertia;
        let n = model.nbodies;
        data.origin = self.origin.lane(lane);
        for i in 0..n {
            data.pose[i] = self.pose[i].lane(lane);
            data.vel[i] = self.vel[i].lane(lane);
            let ri = &self.inertia_ref[i];
            data.inertia_ref[i] = RigidInertia::new(
                ri.mass.0[lane],
                ri.com.lane(lane),
                ri.inertia_com.lane(lane),
            );
        }
        for i in 1..n {
            data.s[i] = self.s[i].lane(lane);
        }
        // the per-body arrays hold every body now, the legs' lane cache an older state
        data.lanes.valid = false;
        let key = &mut data.kin;
        key.model = model as *const Model as usize;
        key.q.clear();
        key.q.extend_from_slice(q);
        key.v.clear();
        key.v.extend_from_slice(v);
        key.level = 2;
    }

    /// Writes robot `lane`'s external forces (nbodies; world axes about its
    /// base origin, as [`crate::Data::external_forces`] after kinematics).
    ///
    /// # Panics
    /// If the length is wrong or `lane ≥ L`.
    pub fn set_external_forces(&mut self, lane: usize, f_ext: &[Force]) {
        assert!(lane < L, "lane {lane} ≥ {L}");
        assert_eq!(f_ext.len(), self.f_ext.len(), "f_ext length");
        for (dst, &f) in self.f_ext.iter_mut().zip(f_ext) {
            dst.set_lane(lane, f);
        }
    }

    /// Copies robot `lane`'s generalised acceleration (nv) into `out`.
    ///
    /// # Panics
    /// If the length is wrong or `lane ≥ L`.
    pub fn ddq_of(&self, lane: usize, out: &mut [f64]) {
        assert!(lane < L, "lane {lane} ≥ {L}");
        assert_eq!(out.len(), self.ddq.len(), "ddq length");
        for (dst, x) in out.iter_mut().zip(&self.ddq) {
            *dst = x.0[lane];
        }
    }

    /// Checks that `model` has the sizes this workspace was made for.
    #[inline]
    fn check_model(&self, model: &Model) {
        assert_eq!(
            self.pose.len(),
            model.nbodies,
            "BatchData sized for another model"
        );
        assert_eq!(self.v.len(), model.nv, "BatchData sized for another model");
    }
}
