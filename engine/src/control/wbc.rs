//! Whole-body control: task-space inverse dynamics with the full `M(q)` and
//! `h(q, v)`, in the form of whole-body impulse control (Kim et al. 2019,
//! "Highly dynamic quadruped locomotion via whole-body impulse control and
//! model predictive control", §III).
//!
//! Why: quad16's legs are 18 of its 28 kg. A lumped-mass planner's ground
//! forces mapped by `τ = −Jᵀ f` ignore them, so the forces the ground really
//! gives differ from the plan and the swing legs' reactions move the torso.
//! Here the torques come from the equations of motion of the whole tree.
//!
//! # The two passes
//! 1. **Kinematic task hierarchy** (accelerations). With `J̄ = M⁻¹ Jᵀ (J M⁻¹
//!    Jᵀ)⁻¹` the dynamically consistent inverse:
//!    - stance feet do not accelerate: `J_c q̈ = −J̇_c v`;
//!    - then, each in the null space of those before it: torso attitude, torso
//!      position, swing feet, joint postures.
//!
//!    Each task `i` adds `J̄ᵢ|pre (ẍᵢ − J̇ᵢ v − Jᵢ q̈)` and shrinks the null
//!    space: `N ← N (I − J̄ᵢ|pre Jᵢ N)`.
//! 2. **A small QP** over the change `δf` of the planned stance forces and
//!    `δ_b` of the base's acceleration, subject to the floating base's six
//!    equations of motion `M_b (q̈ + [δ_b; 0]) + h_b = J_cbᵀ (f_plan + δf)` and
//!    the friction pyramids and normal-force bounds:
//!    `min w_f ‖δf‖² + ‖δ_b‖²_{W_b}`. The equality is eliminated
//!    (`δ_b = M_bb⁻¹ (r + J_cbᵀ δf)`), leaving ≤ 12 variables and ≤ 24
//!    constraints for the stack solver of [`super::active_set`].
//!
//! Then `τ = (M q̈ + h − J_cᵀ f)` on the joint rows (`f`: the ground's force on
//! the foot, world axes; `M q̈ + h = τ + J_cᵀ f`).
//!
//! Units: accelerations in m/s² and rad/s², forces in N, world axes unless
//! stated; the base's velocity coordinates are the engine's (body frame).

use crate::control::active_set::{ActiveSet, DenseQp, MAX_VARS};
use crate::control::force_qp::{MAX_FEET, tangent_basis};
use crate::control::task_space::TaskSpace;
use crate::data::Data;
use crate::jacobian::point_jacobian;
use crate::linalg::{cholesky_dense, cholesky_dense_solve};
use crate::model::Model;
use glam::{DMat3, DVec3};

/// Weights and damping of the whole-body layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WbcParams {
    /// Weight of a change of the planned stance forces (per N²).
    pub force_weight: f64,
    /// Weight of a change of the base's horizontal acceleration (per (m/s²)²,
    /// the base frame's x and y).
    pub base_linear_weight: f64,
    /// Weight of a change of the base's vertical acceleration (per (m/s²)²,
    /// the base frame's z): the torso's height, which the heavy legs' swing
    /// would otherwise move.
    pub base_vertical_weight: f64,
    /// Weight of a change of the base's angular acceleration (per (rad/s²)²).
    pub base_angular_weight: f64,
    /// Damping `λ` of the task inverses `(J M⁻¹ Jᵀ + λ I)⁻¹` (units of
    /// inverse mass): keeps singular legs (a stretched knee) finite.
    pub damping: f64,
    /// Rate (1/s) at which a stance foot's velocity is driven to zero: the
    /// contact rows ask `J_c q̈ = −J̇_c v − k J_c v`, so that a foot that has
    /// started to slide stops instead of keeping its speed.
    pub contact_velocity_gain: f64,
    /// Smallest and largest normal force of a fully loaded stance foot (N);
    /// both scale with the foot's load factor.
    pub normal_force_n: (f64, f64),
}

impl Default for WbcParams {
    /// Forces follow the plan loosely (1 N of change costs like 0.1 m/s² of
    /// the base); the torso's attitude outweighs its position.
    fn default() -> Self {
        WbcParams {
            force_weight: 1.0,
            base_linear_weight: 1e-3,
            base_vertical_weight: 1e-3,
            base_angular_weight: 10.0,
            damping: 1e-6,
            contact_velocity_gain: 30.0,
            normal_force_n: (2.0, 1000.0),
        }
    }
}

/// A stance foot: a point that must not accelerate, with the force planned
/// for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactTask {
    /// The body the foot point is fixed on.
    pub body: usize,
    /// The contact point (m, world).
    pub point_m: DVec3,
    /// The ground's normal there (unit, world).
    pub normal: DVec3,
    /// Friction coefficient the forces may use (already reduced by any margin).
    pub friction: f64,
    /// Load factor in [0, 1] from the gait (scales the normal-force bounds).
    pub load: f64,
    /// The planned ground force on the foot (N, world).
    pub force_plan_n: DVec3,
}

/// A point on a body that tracks a reference (a swing foot).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTask {
    /// The body the point is fixed on.
    pub body: usize,
    /// The point now (m, world).
    pub point_m: DVec3,
    /// The commanded acceleration (m/s², world): the reference's feed-forward
    /// plus the caller's feedback on position and velocity.
    pub acc_mps2: DVec3,
}

/// A joint posture: a commanded joint acceleration (rad/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointTask {
    /// The joint's velocity index in `v`.
    pub v_index: usize,
    /// The commanded acceleration (rad/s²).
    pub acc_radps2: f64,
}

/// The torso's task: a virtual wrench about the whole robot's CoM (world
/// axes, gravity compensation included), turned into the accelerations a
/// rigid body of the robot's mass and centroidal inertia (now) would take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyTask {
    /// Force (N).
    pub force_n: DVec3,
    /// Moment about the CoM (N·m).
    pub torque_nm: DVec3,
}

/// What one solve produced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WbcOutput {
    /// The ground forces the torques are computed with (N, world), per contact
    /// in the order given.
    pub forces_n: [DVec3; MAX_FEET],
    /// The base's acceleration change the QP chose (body frame: linear, angular).
    pub base_change: [f64; 6],
    /// Whether the QP was solved (otherwise the plan was used unchanged; in
    /// flight there is none).
    pub qp_solved: bool,
}

/// Why a solve failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WbcError {
    /// `M(q)` was not positive definite (a non-finite state).
    #[error("whole-body control: the mass matrix is not positive definite")]
    MassMatrix,
    /// More contacts than [`MAX_FEET`].
    #[error("whole-body control: more than {MAX_FEET} contacts")]
    TooManyContacts,
}

/// The whole-body layer's workspace: every buffer a solve needs, sized for the
/// model once (the solve allocates nothing; [`WholeBody::solve_reference`]
/// allocates its dense buffers on its first call).
///
/// # How the hierarchy is computed
/// The tasks' rows are stacked into one `J` (`R × nv`: stance feet, torso,
/// swing feet, joint postures; `R` = 22 for quad16) with their targets `x`.
/// Every quantity of the module docs' recursion lies in the span of `J`'s
/// rows mapped by `M⁻¹`: by induction, `N_i = I − M⁻¹ Jᵀ C_i J` and `q̈ =
/// M⁻¹ Jᵀ β`, where with `G = J M⁻¹ Jᵀ` (`R × R`) and `E_i` the rows of task
/// `i`,
///
/// - `J_i N_{i−1} = A_i J` with `A_i = E_i (I − G C_{i−1})`;
/// - `Λ_i⁻¹ = A_i G A_iᵀ + λ I`, `e_i = x_i − E_i G β`;
/// - `β ← β + A_iᵀ Λ_i e_i`, `C_i = C_{i−1} + (I − C_{i−1} G) A_iᵀ Λ_i A_i`.
///
/// This is the same algebra (damping included), so the same answer up to
/// round-off, in `R`-dimensional task space instead of with dense `nv × nv`
/// projectors and `M⁻¹`. `G` comes from the floating-base tree's sparse
/// factor `M = Lᵀ L` (Featherstone 2008, §6.5, "LTL"; `L` has the tree's
/// sparsity, no fill-in): `G = Wᵀ W` with `W = L⁻ᵀ Jᵀ`, whose column for a
/// foot is non-zero only on the base and that foot's leg, so entries
/// between two legs are six-term sums. `C_i` is zero past the rows of tasks
/// `1..i`, so each task works on the leading block. At the end, `q̈ = L⁻¹ (W
/// β)`. [`WholeBody::solve_reference`] keeps the dense recursion as the
/// reference the tests compare with.
#[derive(Clone, Debug)]
pub struct WholeBody {
    /// Parameters.
    pub params: WbcParams,
    nv: usize,
    zeros: Vec<f64>,
    h: Vec<f64>,
    m: Vec<f64>,
    qdd: Vec<f64>,
    /// The stacked task rows `J` (`R × nv`) and their targets (bias subtracted).
    rows: Vec<f64>,
    target: Vec<f64>,
    /// First row and row count of each task, in order of priority.
    tasks: [(usize, usize); 4],
    /// First row of the swing feet's task.
    swing_row: usize,
    /// The hierarchy in task space.
    ts: TaskSpace,
    /// `Z` (nv × 6): how q̈ changes with the base's acceleration change `δ_b`
    /// when every foot keeps its task (`J Z = 0` on each leg).
    z: Vec<f64>,
    qp: Box<DenseQp>,
    solver: Box<ActiveSet>,
    /// The dense reference's buffers ([`WholeBody::solve_reference`]).
    dense: Option<Box<DenseHierarchy>>,
}

/// Most rows of one task (four feet × 3).
const MAX_ROWS: usize = 3 * MAX_FEET;

/// Most rows of all tasks: stance and swing feet, the torso, joint postures.
const MAX_TASK_ROWS: usize = 2 * MAX_ROWS + 6 + MAX_ROWS;

impl WholeBody {
    /// A workspace for `model`.
    pub fn new(model: &Model, params: WbcParams) -> WholeBody {
        let nv = model.nv;
        WholeBody {
            params,
            nv,
            zeros: vec![0.0; nv],
            h: vec![0.0; nv],
            m: vec![0.0; nv * nv],
            qdd: vec![0.0; nv],
            rows: vec![0.0; MAX_TASK_ROWS * nv],
            target: vec![0.0; MAX_TASK_ROWS],
            tasks: [(0, 0); 4],
            swing_row: 0,
            ts: TaskSpace::new(model),
            z: vec![0.0; nv * 6],
            qp: Box::default(),
            solver: Box::new(ActiveSet::default()),
            dense: None,
        }
    }

    /// The generalized accelerations of the last solve (nv).
    pub fn accelerations(&self) -> &[f64] {
        &self.qdd
    }

    /// Joint torques (`tau_joints`, nv − 6) that realise the tasks, for the
    /// state `(q, v)` whose kinematics `data` holds
    /// ([`crate::kinematics::forward_kinematics`]). Torques are not clamped.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        model: &Model,
        data: &mut Data,
        v: &[f64],
        contacts: &[ContactTask],
        body: &BodyTask,
        points: &[PointTask],
        joints: &[JointTask],
        tau_joints: &mut [f64],
    ) -> Result<WbcOutput, WbcError> {
        self.solve_with(
            model, data, v, contacts, body, points, joints, tau_joints, false,
        )
    }

    /// [`WholeBody::solve`] with the task hierarchy computed as the module
    /// docs write it, with dense `nv × nv` null-space projectors and `M⁻¹`
    /// (the algorithm the task-space form replaced, kept as the reference
    /// its tests compare with). Allocates its buffers on the first call.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_reference(
        &mut self,
        model: &Model,
        data: &mut Data,
        v: &[f64],
        contacts: &[ContactTask],
        body: &BodyTask,
        points: &[PointTask],
        joints: &[JointTask],
        tau_joints: &mut [f64],
    ) -> Result<WbcOutput, WbcError> {
        self.solve_with(
            model, data, v, contacts, body, points, joints, tau_joints, true,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn solve_with(
        &mut self,
        model: &Model,
        data: &mut Data,
        v: &[f64],
        contacts: &[ContactTask],
        body: &BodyTask,
        points: &[PointTask],
        joints: &[JointTask],
        tau_joints: &mut [f64],
        dense: bool,
    ) -> Result<WbcOutput, WbcError> {
        let nv = self.nv;
        let nb = model.base_nv();
        let nc = contacts.len();
        if nc > MAX_FEET || points.len() > MAX_FEET {
            return Err(WbcError::TooManyContacts);
        }
        // h(q, v) and the bodies' bias accelerations (q̈ = 0): one RNEA pass.
        crate::dispatch::rnea_from_kinematics(model, data, v, &self.zeros, false);
        self.h.copy_from_slice(&data.tau);
        // M(q)
        {
            let mm = crate::crba::crba_from_kinematics(model, data);
            self.m.copy_from_slice(&mm);
        }

        // the tasks' rows, stacked in order of priority
        // 1. contacts: J_c q̈ = −J̇_c v − k J_c v
        let kc = self.params.contact_velocity_gain;
        for (k, c) in contacts.iter().enumerate() {
            let bias = point_bias(model, data, c.body, c.point_m);
            let vel = data.vel[c.body].point_velocity(c.point_m - data.origin);
            let j = point_jacobian(model, data, c.body, c.point_m);
            self.rows[3 * k * nv..3 * (k + 1) * nv].copy_from_slice(j);
            for r in 0..3 {
                self.target[3 * k + r] = -bias[r] - kc * vel[r];
            }
        }
        let mut row = 3 * nc;
        self.tasks[0] = (0, row);
        // 2. the torso: attitude (ω̇ world = R ω̇_b, no bias) and the base
        //    origin's acceleration, one task of six rows
        self.tasks[1] = (row, 0);
        if nb == 6 {
            let rot = data.pose[0].rot;
            let (lin, ang) = self.body_accelerations(model, data, rot, body);
            let p0 = data.pose[0].trans;
            let bias = point_bias(model, data, 0, p0);
            let j = point_jacobian(model, data, 0, p0);
            let t = &mut self.rows[row * nv..(row + 6) * nv];
            t[3 * nv..].copy_from_slice(j);
            t[..3 * nv].fill(0.0);
            for r in 0..3 {
                for k in 0..3 {
                    t[r * nv + 3 + k] = rot.col(k)[r];
                }
                self.target[row + r] = ang[r];
                self.target[row + 3 + r] = lin[r] - bias[r];
            }
            self.tasks[1] = (row, 6);
            row += 6;
        }
        // 3. swing feet, one task
        self.swing_row = row;
        for (k, p) in points.iter().enumerate() {
            let bias = point_bias(model, data, p.body, p.point_m);
            let j = point_jacobian(model, data, p.body, p.point_m);
            let r0 = row + 3 * k;
            self.rows[r0 * nv..(r0 + 3) * nv].copy_from_slice(j);
            for r in 0..3 {
                self.target[r0 + r] = p.acc_mps2[r] - bias[r];
            }
        }
        let np = points.len();
        self.tasks[2] = (row, 3 * np);
        row += 3 * np;
        // 4. joint postures, one task
        let nj = joints.len().min(MAX_ROWS);
        self.rows[row * nv..(row + nj) * nv].fill(0.0);
        for (r, jtk) in joints[..nj].iter().enumerate() {
            self.rows[(row + r) * nv + jtk.v_index] = 1.0;
            self.target[row + r] = jtk.acc_radps2;
        }
        self.tasks[3] = (row, nj);

        // 5. the accelerations the hierarchy gives
        if dense {
            let d = self
                .dense
                .get_or_insert_with(|| Box::new(DenseHierarchy::new(nv)));
            if !d.solve(
                &self.m,
                &self.rows,
                &self.target,
                &self.tasks,
                self.params.damping,
                &mut self.qdd,
            ) {
                return Err(WbcError::MassMatrix);
            }
        } else {
            if !self.ts.factor(&self.m) {
                return Err(WbcError::MassMatrix);
            }
            self.ts.solve(
                &self.rows,
                &self.target,
                &self.tasks,
                self.params.damping,
                &mut self.qdd,
            );
        }

        // 6. the QP over δf (δ_b eliminated through the base's rows)
        let mut out = WbcOutput {
            forces_n: [DVec3::ZERO; MAX_FEET],
            base_change: [0.0; 6],
            qp_solved: false,
        };
        for (k, c) in contacts.iter().enumerate() {
            out.forces_n[k] = c.force_plan_n;
        }
        if nb == 6 {
            self.base_change_map(nc, points.len());
            self.reaction_qp(contacts, &mut out);
            for i in 0..nv {
                let mut s = 0.0;
                for k in 0..6 {
                    s += self.z[i * 6 + k] * out.base_change[k];
                }
                self.qdd[i] += s;
            }
        }

        // 7. τ = M q̈ + h − J_cᵀ f (joint rows)
        let jc = &self.rows[..3 * nc * nv];
        for (t, i) in tau_joints.iter_mut().zip(nb..nv) {
            let mut s = self.h[i];
            let row = &self.m[i * nv..(i + 1) * nv];
            for (mij, a) in row.iter().zip(&self.qdd) {
                s += mij * a;
            }
            for (k, f) in out.forces_n[..nc].iter().enumerate() {
                let base = 3 * k * nv;
                s -= jc[base + i] * f.x + jc[base + nv + i] * f.y + jc[base + 2 * nv + i] * f.z;
            }
            *t = s;
        }
        Ok(out)
    }

    /// The accelerations (linear, angular; world) the body task asks for:
    /// the whole robot's mass `m` and rotational inertia about its CoM,
    /// `I_com = I_o − m (|c|² I − c cᵀ)` (parallel axes), from `M_bb`'s
    /// rotational block `I_o` (base frame, about the base origin) and the CoM
    /// `c` in the base frame.
    fn body_accelerations(
        &self,
        model: &Model,
        data: &Data,
        rot: DMat3,
        body: &BodyTask,
    ) -> (DVec3, DVec3) {
        let nv = self.nv;
        let mb = |i: usize, k: usize| self.m[i * nv + k];
        let mass = model.total_mass;
        let com = crate::com::center_of_mass(model, data);
        let c = rot.transpose() * (com - data.pose[0].trans);
        let io = DMat3::from_cols(
            DVec3::new(mb(3, 3), mb(4, 3), mb(5, 3)),
            DVec3::new(mb(3, 4), mb(4, 4), mb(5, 4)),
            DVec3::new(mb(3, 5), mb(4, 5), mb(5, 5)),
        );
        let shift = (DMat3::IDENTITY * c.length_squared()
            - DMat3::from_cols(c * c.x, c * c.y, c * c.z))
            * mass;
        let i_world = rot * (io - shift) * rot.transpose();
        let lin = body.force_n / mass + model.gravity;
        let ang = i_world.inverse() * body.torque_nm;
        (lin, ang)
    }

    /// Fills `Z` (nv × 6): the base's rows the identity, each foot's leg
    /// `−J_j⁺ J_b` (its joint columns `J_j`, the base's `J_b`, damped
    /// least-squares inverse), so that changing the base's acceleration by
    /// `δ_b` and the legs' by `Z δ_b` leaves every foot's acceleration as its
    /// task set it (stance feet stay still). Other joints do not change.
    fn base_change_map(&mut self, nc: usize, np: usize) {
        let nv = self.nv;
        self.z.fill(0.0);
        for k in 0..6 {
            self.z[k * 6 + k] = 1.0;
        }
        for foot in 0..nc + np {
            let rows = if foot < nc {
                &self.rows[3 * foot * nv..3 * (foot + 1) * nv]
            } else {
                let f = foot - nc;
                let r0 = self.swing_row + 3 * f;
                &self.rows[r0 * nv..(r0 + 3) * nv]
            };
            // the leg's joint columns (the chain's, past the base)
            let mut cols = [0usize; 8];
            let mut nj = 0;
            for c in 6..nv {
                if nj < cols.len()
                    && (rows[c] != 0.0 || rows[nv + c] != 0.0 || rows[2 * nv + c] != 0.0)
                {
                    cols[nj] = c;
                    nj += 1;
                }
            }
            // G = J_j J_jᵀ + λ I (3 × 3)
            let mut g = DMat3::ZERO;
            for a in 0..3 {
                for b in 0..3 {
                    let mut s = 0.0;
                    for &c in &cols[..nj] {
                        s += rows[a * nv + c] * rows[b * nv + c];
                    }
                    g.col_mut(b)[a] = s + if a == b { 1e-9 } else { 0.0 };
                }
            }
            let gi = g.inverse();
            if !gi.is_finite() {
                continue;
            }
            // Z_j = −J_jᵀ G⁻¹ J_b
            for k in 0..6 {
                let jb = DVec3::new(rows[k], rows[nv + k], rows[2 * nv + k]);
                let y = gi * jb;
                for &c in &cols[..nj] {
                    let jj = DVec3::new(rows[c], rows[nv + c], rows[2 * nv + c]);
                    self.z[c * 6 + k] = -jj.dot(y);
                }
            }
        }
    }

    /// The reaction-force QP (module docs, pass 2); fills `out.forces_n` and
    /// `out.base_change`, or leaves the plan when the QP fails.
    fn reaction_qp(&mut self, contacts: &[ContactTask], out: &mut WbcOutput) {
        let nv = self.nv;
        let nc = contacts.len();
        let n = 3 * nc;
        // r = J_cbᵀ f_plan − h_b − (M q̈)_b
        let mut r = [0.0; 6];
        for (i, ri) in r.iter_mut().enumerate() {
            let mut s = -self.h[i];
            for k in 0..nv {
                s -= self.m[i * nv + k] * self.qdd[k];
            }
            for (c, ct) in contacts.iter().enumerate() {
                let f = ct.force_plan_n;
                let base = 3 * c * nv;
                s += self.rows[base + i] * f.x
                    + self.rows[base + nv + i] * f.y
                    + self.rows[base + 2 * nv + i] * f.z;
            }
            *ri = s;
        }
        // M_b Z (6 × 6): each row a sum of Z's rows
        let mut mbz = [[0.0; 6]; 6];
        for (i, acc) in mbz.iter_mut().enumerate() {
            for (c, &mic) in self.m[i * nv..(i + 1) * nv].iter().enumerate() {
                let zc = &self.z[c * 6..c * 6 + 6];
                for k in 0..6 {
                    acc[k] += mic * zc[k];
                }
            }
        }
        // d0 = (M_b Z)⁻¹ r; A = (M_b Z)⁻¹ J_cbᵀ (6 × n): one elimination
        // for the n + 1 right-hand sides
        let mut rhs = [[0.0; 6]; MAX_VARS + 1];
        rhs[0] = r;
        for x in 0..n {
            for i in 0..6 {
                rhs[1 + x][i] = self.rows[x * nv + i];
            }
        }
        if !solve6(mbz, &mut rhs[..n + 1]) {
            return;
        }
        let d0 = rhs[0];
        if n == 0 {
            // in flight the base's rows decide its acceleration alone
            out.base_change = d0;
            return;
        }
        let mut amat = [[0.0; MAX_VARS]; 6];
        for x in 0..n {
            for i in 0..6 {
                amat[i][x] = rhs[1 + x][i];
            }
        }
        let p = &self.params;
        let w = [
            p.base_linear_weight,
            p.base_linear_weight,
            p.base_vertical_weight,
            p.base_angular_weight,
            p.base_angular_weight,
            p.base_angular_weight,
        ];
        let qp = &mut *self.qp;
        qp.n = n;
        qp.m = 6 * nc;
        qp.foot_blocks = true;
        for x in 0..n {
            let mut g = 0.0;
            for i in 0..6 {
                g += amat[i][x] * w[i] * d0[i];
            }
            qp.g[x] = g;
            for y in 0..n {
                let mut s = if x == y { p.force_weight } else { 0.0 };
                for i in 0..6 {
                    s += amat[i][x] * w[i] * amat[i][y];
                }
                qp.h[x][y] = s;
            }
        }
        let (fmin, fmax) = p.normal_force_n;
        for (c, ct) in contacts.iter().enumerate() {
            let nrm = ct.normal;
            let (t1, t2) = tangent_basis(nrm);
            let mu = ct.friction * std::f64::consts::FRAC_1_SQRT_2;
            let rows: [(DVec3, f64); 6] = [
                (nrm, fmin * ct.load),
                (-nrm, -fmax * ct.load),
                (mu * nrm - t1, 0.0),
                (mu * nrm + t1, 0.0),
                (mu * nrm - t2, 0.0),
                (mu * nrm + t2, 0.0),
            ];
            for (j, (cv, b)) in rows.into_iter().enumerate() {
                let row = &mut qp.c[6 * c + j];
                *row = [0.0; MAX_VARS];
                row[3 * c..3 * c + 3].copy_from_slice(&cv.to_array());
                // cᵀ(f_plan + δf) ≥ b
                qp.b[6 * c + j] = b - cv.dot(ct.force_plan_n);
            }
        }
        let Ok(x) = self.solver.solve(qp) else {
            return;
        };
        for (c, ct) in contacts.iter().enumerate() {
            out.forces_n[c] = ct.force_plan_n + DVec3::new(x[3 * c], x[3 * c + 1], x[3 * c + 2]);
        }
        for i in 0..6 {
            let mut s = d0[i];
            for y in 0..n {
                s += amat[i][y] * x[y];
            }
            out.base_change[i] = s;
        }
        out.qp_solved = true;
    }
}

/// Solves `a x = b` for each `b` in `rhs` (in place) by Gaussian elimination
/// with partial pivoting; `false` when a pivot is zero (`a` singular).
fn solve6(mut a: [[f64; 6]; 6], rhs: &mut [[f64; 6]]) -> bool {
    for p in 0..6 {
        let mut piv = p;
        for i in p + 1..6 {
            if a[i][p].abs() > a[piv][p].abs() {
                piv = i;
            }
        }
        if a[piv][p] == 0.0 {
            return false;
        }
        if piv != p {
            a.swap(piv, p);
            for b in rhs.iter_mut() {
                b.swap(piv, p);
            }
        }
        let inv = 1.0 / a[p][p];
        for i in p + 1..6 {
            let f = a[i][p] * inv;
            if f == 0.0 {
                continue;
            }
            for k in p + 1..6 {
                a[i][k] -= f * a[p][k];
            }
            for b in rhs.iter_mut() {
                b[i] -= f * b[p];
            }
        }
    }
    for b in rhs.iter_mut() {
        for i in (0..6).rev() {
            let mut s = b[i];
            for k in i + 1..6 {
                s -= a[i][k] * b[k];
            }
            b[i] = s / a[i][i];
        }
    }
    true
}

/// The classical acceleration (m/s², world) of the point `point_m` fixed on
/// `body` when `q̈ = 0`: `J̇ v`. Reads the bodies' spatial accelerations of an
/// RNEA pass run with zero acceleration (which start from gravity's
/// fictitious upward acceleration, removed here).
fn point_bias(model: &Model, data: &Data, body: usize, point_m: DVec3) -> DVec3 {
    let r = point_m - data.origin;
    let acc = data.acc[body];
    let vel = data.vel[body];
    acc.point_velocity(r) + vel.ang.cross(vel.point_velocity(r)) + model.gravity
}

/// The dense recursion of the module docs (the reference for the task-space
/// form): `M⁻¹` and the null-space projector `N` as `nv × nv` matrices.
#[derive(Clone, Debug)]
struct DenseHierarchy {
    l: Vec<f64>,
    minv: Vec<f64>,
    null: Vec<f64>,
    c: Vec<f64>,
    jn: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
    lam: Vec<f64>,
    col: Vec<f64>,
}

impl DenseHierarchy {
    fn new(nv: usize) -> DenseHierarchy {
        DenseHierarchy {
            l: vec![0.0; nv * nv],
            minv: vec![0.0; nv * nv],
            null: vec![0.0; nv * nv],
            c: vec![0.0; nv * nv],
            jn: vec![0.0; MAX_ROWS * nv],
            a: vec![0.0; MAX_ROWS * nv],
            b: vec![0.0; nv * MAX_ROWS],
            lam: vec![0.0; MAX_ROWS * MAX_ROWS],
            col: vec![0.0; nv.max(MAX_ROWS)],
        }
    }

    /// `qdd` from the stacked `rows` and `target` of `tasks`; `false` when
    /// `m` is not positive definite.
    fn solve(
        &mut self,
        m: &[f64],
        rows: &[f64],
        target: &[f64],
        tasks: &[(usize, usize); 4],
        damping: f64,
        qdd: &mut [f64],
    ) -> bool {
        let nv = qdd.len();
        self.l.copy_from_slice(m);
        if !cholesky_dense(&mut self.l, nv) {
            return false;
        }
        for i in 0..nv {
            self.col.fill(0.0);
            self.col[i] = 1.0;
            cholesky_dense_solve(&self.l, nv, &mut self.col[..nv]);
            for r in 0..nv {
                self.minv[r * nv + i] = self.col[r];
            }
        }
        qdd.fill(0.0);
        self.null.fill(0.0);
        for i in 0..nv {
            self.null[i * nv + i] = 1.0;
        }
        let last = tasks.iter().rposition(|&(_, n)| n > 0).unwrap_or(0);
        for (t, &(o, n)) in tasks.iter().enumerate() {
            self.task(
                &rows[o * nv..(o + n) * nv],
                &target[o..o + n],
                n,
                t == last,
                damping,
                qdd,
            );
        }
        true
    }

    /// Adds the task in `jt` (`rows × nv`; target in `target`, bias
    /// already subtracted) to `qdd` in the null space of the tasks before it,
    /// and shrinks that null space (unless it is the `last`).
    fn task(
        &mut self,
        jt: &[f64],
        target: &[f64],
        rows: usize,
        last: bool,
        damping: f64,
        qdd: &mut [f64],
    ) {
        if rows == 0 {
            return;
        }
        let nv = qdd.len();
        // JN = J N
        for r in 0..rows {
            for c in 0..nv {
                let mut s = 0.0;
                for k in 0..nv {
                    s += jt[r * nv + k] * self.null[k * nv + c];
                }
                self.jn[r * nv + c] = s;
            }
        }
        // B = M⁻¹ (JN)ᵀ (nv × rows)
        for i in 0..nv {
            for r in 0..rows {
                let mut s = 0.0;
                for k in 0..nv {
                    s += self.minv[i * nv + k] * self.jn[r * nv + k];
                }
                self.b[i * rows + r] = s;
            }
        }
        // Λ⁻¹ = JN B + λ I (rows × rows), factored
        for r in 0..rows {
            for c in 0..rows {
                let mut s = 0.0;
                for k in 0..nv {
                    s += self.jn[r * nv + k] * self.b[k * rows + c];
                }
                self.lam[r * rows + c] = s + if r == c { damping } else { 0.0 };
            }
        }
        if !cholesky_dense(&mut self.lam[..rows * rows], rows) {
            return; // the task has no room left in the null space
        }
        // e = target − J q̈
        for r in 0..rows {
            let mut s = target[r];
            for k in 0..nv {
                s -= jt[r * nv + k] * qdd[k];
            }
            self.col[r] = s;
        }
        cholesky_dense_solve(&self.lam[..rows * rows], rows, &mut self.col[..rows]);
        // q̈ += B Λ e
        for i in 0..nv {
            let mut s = 0.0;
            for r in 0..rows {
                s += self.b[i * rows + r] * self.col[r];
            }
            qdd[i] += s;
        }
        if last {
            return;
        }
        // J̄ = B Λ (nv × rows): solve Λ⁻¹ X = Bᵀ column by column
        for i in 0..nv {
            for r in 0..rows {
                self.col[r] = self.b[i * rows + r];
            }
            cholesky_dense_solve(&self.lam[..rows * rows], rows, &mut self.col[..rows]);
            for r in 0..rows {
                self.a[i * rows + r] = self.col[r];
            }
        }
        // N ← N (I − J̄ JN) = N − (N J̄) JN
        for i in 0..nv {
            // row i of N J̄ (rows entries) into col
            for r in 0..rows {
                let mut s = 0.0;
                for k in 0..nv {
                    s += self.null[i * nv + k] * self.a[k * rows + r];
                }
                self.col[r] = s;
            }
            for c in 0..nv {
                let mut s = 0.0;
                for r in 0..rows {
                    s += self.col[r] * self.jn[r * nv + c];
                }
                self.c[i * nv + c] = self.null[i * nv + c] - s;
            }
        }
        std::mem::swap(&mut self.null, &mut self.c);
    }
}
