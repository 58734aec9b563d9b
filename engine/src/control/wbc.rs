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
use crate::data::Data;
use crate::jacobian::point_jacobian;
use crate::linalg::{cholesky_dense, cholesky_dense_solve};
use crate::model::{Model, NO_PARENT};
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
    /// The velocity coordinates' tree.
    tree: DofTree,
    zeros: Vec<f64>,
    h: Vec<f64>,
    m: Vec<f64>,
    /// `L` of `M = Lᵀ L` (row-major; row `i` at `i`'s ancestors and `i`)
    /// and `1 / L_ii`.
    l: Vec<f64>,
    inv_diag: Vec<f64>,
    qdd: Vec<f64>,
    /// The stacked task rows `J` (`R × nv`) and their targets (bias subtracted).
    rows: Vec<f64>,
    target: Vec<f64>,
    /// First row and row count of each task, in order of priority.
    tasks: [(usize, usize); 4],
    /// First row of the swing feet's task.
    swing_row: usize,
    /// `W` (as rows: row `r` is `L⁻ᵀ J_rᵀ`, `R × nv`) and, per row, the
    /// range past the base outside which it is zero.
    w: Vec<f64>,
    span: Vec<(usize, usize)>,
    /// `G` and `C` (`R × R`, row stride `R`), `β` (`R`).
    g: Vec<f64>,
    cm: Vec<f64>,
    beta: Vec<f64>,
    /// One task's `A`, `T = A G`, `Dᵀ = A (I − C G)ᵀ` and `X = Λ A` (rows × R).
    am: Vec<f64>,
    tm: Vec<f64>,
    dm: Vec<f64>,
    xm: Vec<f64>,
    /// `E_last G C` for the last task (its rows × R).
    qm: Vec<f64>,
    /// `Λ⁻¹` of one task, factored (rows × rows), and its right-hand side.
    kk: Vec<f64>,
    y: Vec<f64>,
    col: Vec<f64>,
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
            tree: DofTree::of(model),
            zeros: vec![0.0; nv],
            h: vec![0.0; nv],
            m: vec![0.0; nv * nv],
            l: vec![0.0; nv * nv],
            inv_diag: vec![0.0; nv],
            qdd: vec![0.0; nv],
            rows: vec![0.0; MAX_TASK_ROWS * nv],
            target: vec![0.0; MAX_TASK_ROWS],
            tasks: [(0, 0); 4],
            swing_row: 0,
            w: vec![0.0; MAX_TASK_ROWS * nv],
            span: vec![(0, 0); MAX_TASK_ROWS],
            g: vec![0.0; MAX_TASK_ROWS * MAX_TASK_ROWS],
            cm: vec![0.0; MAX_TASK_ROWS * MAX_TASK_ROWS],
            beta: vec![0.0; MAX_TASK_ROWS],
            am: vec![0.0; MAX_ROWS * MAX_TASK_ROWS],
            tm: vec![0.0; MAX_ROWS * MAX_TASK_ROWS],
            dm: vec![0.0; MAX_ROWS * MAX_TASK_ROWS],
            xm: vec![0.0; MAX_ROWS * MAX_TASK_ROWS],
            qm: vec![0.0; MAX_ROWS * MAX_TASK_ROWS],
            kk: vec![0.0; MAX_ROWS * MAX_ROWS],
            y: vec![0.0; MAX_ROWS],
            col: vec![0.0; nv],
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
            self.l.copy_from_slice(&self.m);
            if !ltl_factor(&mut self.l, &self.tree, nv, &mut self.inv_diag) {
                return Err(WbcError::MassMatrix);
            }
            self.task_space_hierarchy(nb);
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

    /// The task hierarchy in task space (the type's docs): fills `qdd` from
    /// the stacked rows, their targets and `L` of `M = Lᵀ L`.
    fn task_space_hierarchy(&mut self, nb: usize) {
        let nv = self.nv;
        let (last_row, last_n) = self.tasks[3];
        let rt = last_row + last_n;
        // W = L⁻ᵀ Jᵀ, row by row, and where each row is non-zero past the base
        for r in 0..rt {
            let w = &mut self.w[r * nv..(r + 1) * nv];
            w.copy_from_slice(&self.rows[r * nv..(r + 1) * nv]);
            solve_lt(&self.l, &self.inv_diag, &self.tree, nv, w);
            let lo = (nb..nv).find(|&i| w[i] != 0.0).unwrap_or(nv);
            let hi = (lo..nv).rev().find(|&i| w[i] != 0.0).map_or(lo, |i| i + 1);
            self.span[r] = (lo, hi);
        }
        // G = W Wᵀ: the base's terms and those of the legs both rows move
        let g = &mut self.g[..rt * rt];
        for a in 0..rt {
            let wa = &self.w[a * nv..(a + 1) * nv];
            let (alo, ahi) = self.span[a];
            for b in 0..=a {
                let wb = &self.w[b * nv..(b + 1) * nv];
                let (blo, bhi) = self.span[b];
                let mut s = if nb == 6 {
                    dot6(&wa[..6], &wb[..6])
                } else {
                    dot(&wa[..nb], &wb[..nb])
                };
                for i in alo.max(blo)..ahi.min(bhi) {
                    s += wa[i] * wb[i];
                }
                g[a * rt + b] = s;
                g[b * rt + a] = s;
            }
        }
        // the tasks with rows, in order; the one before the last computes
        // what the last needs of C instead of C itself
        let mut order = [(0usize, 0usize); 4];
        let mut n = 0;
        for &(o, r) in &self.tasks {
            if r > 0 {
                order[n] = (o, r);
                n += 1;
            }
        }
        self.cm[..rt * rt].fill(0.0);
        self.beta[..rt].fill(0.0);
        for k in 0..n {
            let (o, r) = order[k];
            hierarchy_task(
                &self.g[..rt * rt],
                &mut self.cm[..rt * rt],
                &mut self.beta[..rt],
                &self.target[o..o + r],
                TaskShape {
                    rt,
                    o,
                    r,
                    last: k + 1 == n,
                    a_from_q: k + 1 == n && k > 0,
                    next_last: (k + 2 == n).then(|| order[k + 1]),
                },
                self.params.damping,
                TaskScratch {
                    am: &mut self.am,
                    tm: &mut self.tm,
                    dm: &mut self.dm,
                    xm: &mut self.xm,
                    qm: &mut self.qm,
                    kk: &mut self.kk[..r * r],
                    y: &mut self.y[..r],
                },
            );
        }
        // q̈ = M⁻¹ Jᵀ β = L⁻¹ (W β)
        let x = &mut self.col;
        x.fill(0.0);
        for r in 0..rt {
            let b = self.beta[r];
            if b == 0.0 {
                continue;
            }
            let w = &self.w[r * nv..(r + 1) * nv];
            axpy(&mut x[..nb], b, &w[..nb]);
            let (lo, hi) = self.span[r];
            axpy(&mut x[lo..hi], b, &w[lo..hi]);
        }
        solve_l(&self.l, &self.inv_diag, &self.tree, nv, x);
        self.qdd.copy_from_slice(x);
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
        // M_b Z (6 × 6), factored by LU
        let mut mbz = nalgebra::Matrix6::<f64>::zeros();
        for i in 0..6 {
            for k in 0..6 {
                let mut s = 0.0;
                for c in 0..nv {
                    s += self.m[i * nv + c] * self.z[c * 6 + k];
                }
                mbz[(i, k)] = s;
            }
        }
        let lu = mbz.lu();
        // d0 = (M_b Z)⁻¹ r; A = (M_b Z)⁻¹ J_cbᵀ (6 × n)
        let Some(d0v) = lu.solve(&nalgebra::Vector6::from_column_slice(&r)) else {
            return;
        };
        let d0: [f64; 6] = d0v.into();
        if n == 0 {
            // in flight the base's rows decide its acceleration alone
            out.base_change = d0;
            return;
        }
        let mut amat = [[0.0; MAX_VARS]; 6];
        for x in 0..n {
            let (c, axis) = (x / 3, x % 3);
            let mut colv = nalgebra::Vector6::<f64>::zeros();
            for i in 0..6 {
                colv[i] = self.rows[(3 * c + axis) * nv + i];
            }
            let Some(sol) = lu.solve(&colv) else {
                return;
            };
            for i in 0..6 {
                amat[i][x] = sol[i];
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

/// The velocity coordinates' tree (Featherstone's `λ(i)`: the coordinate
/// each one's motion is carried by; the free base's six form a chain), kept
/// as each coordinate's ancestors, nearest first, in one array: the sparse
/// factor's loops then read their indices instead of chasing parents.
#[derive(Clone, Debug)]
struct DofTree {
    /// Ancestors of coordinate `i`: `anc[start[i]..start[i + 1]]`, nearest first.
    anc: Vec<usize>,
    start: Vec<usize>,
}

impl DofTree {
    fn of(model: &Model) -> DofTree {
        let mut parent = vec![usize::MAX; model.nv];
        for (i, p) in parent.iter_mut().enumerate() {
            let b = model.v_body[i];
            if i > model.idx_v[b] {
                *p = i - 1; // within a multi-DOF joint (the free base)
                continue;
            }
            let mut j = model.parent[b];
            while j != NO_PARENT {
                let n = model.joint_type[j].nv();
                if n > 0 {
                    *p = model.idx_v[j] + n - 1;
                    break;
                }
                j = model.parent[j];
            }
        }
        let mut anc = Vec::new();
        let mut start = vec![0];
        for i in 0..model.nv {
            let mut j = parent[i];
            while j != usize::MAX {
                anc.push(j);
                j = parent[j];
            }
            start.push(anc.len());
        }
        DofTree { anc, start }
    }

    /// Ancestors of coordinate `i`, nearest first.
    #[inline]
    fn ancestors(&self, i: usize) -> &[usize] {
        &self.anc[self.start[i]..self.start[i + 1]]
    }
}

/// Factors `M = Lᵀ L` in place (Featherstone 2008, Table 6.3, "LTL"):
/// `L` lower triangular with row `i` non-zero only at `i`'s ancestors in the
/// DOF tree and at `i`, so there is no fill-in; `inv_diag` gets `1 / L_ii`.
/// Returns `false` when `M` is not positive definite.
fn ltl_factor(h: &mut [f64], tree: &DofTree, n: usize, inv_diag: &mut [f64]) -> bool {
    for k in (0..n).rev() {
        let d = h[k * n + k];
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        h[k * n + k] = d;
        inv_diag[k] = 1.0 / d;
        let anc = tree.ancestors(k);
        for &i in anc {
            h[k * n + i] /= d;
        }
        // the ancestors of ancestor i are the rest of k's list
        for (p, &i) in anc.iter().enumerate() {
            let lki = h[k * n + i];
            for &j in &anc[p..] {
                h[i * n + j] -= lki * h[k * n + j];
            }
        }
    }
    true
}

/// `x ← L⁻ᵀ x` for `L` from [`ltl_factor`] (leaves to root).
fn solve_lt(l: &[f64], inv_diag: &[f64], tree: &DofTree, n: usize, x: &mut [f64]) {
    for i in (0..n).rev() {
        if x[i] == 0.0 {
            continue; // nothing to carry to the ancestors
        }
        let xi = x[i] * inv_diag[i];
        x[i] = xi;
        let row = &l[i * n..(i + 1) * n];
        for &j in tree.ancestors(i) {
            x[j] -= row[j] * xi;
        }
    }
}

/// `x ← L⁻¹ x` for `L` from [`ltl_factor`] (root to leaves).
fn solve_l(l: &[f64], inv_diag: &[f64], tree: &DofTree, n: usize, x: &mut [f64]) {
    for i in 0..n {
        let row = &l[i * n..(i + 1) * n];
        let mut s = x[i];
        for &j in tree.ancestors(i) {
            s -= row[j] * x[j];
        }
        x[i] = s * inv_diag[i];
    }
}

/// `a · b` in four interleaved partial sums (independent lanes the compiler
/// can keep in one SIMD register).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 4];
    let ca = a.chunks_exact(4);
    let cb = b.chunks_exact(4);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// `a · b` for six entries (the base's coordinates).
#[inline]
fn dot6(a: &[f64], b: &[f64]) -> f64 {
    let (a, b) = (&a[..6], &b[..6]);
    (a[0] * b[0] + a[1] * b[1]) + (a[2] * b[2] + a[3] * b[3]) + (a[4] * b[4] + a[5] * b[5])
}

/// `y ← y + a x`.
#[inline]
fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// One task's buffers for [`hierarchy_task`] (rows × R, row stride R).
struct TaskScratch<'a> {
    am: &'a mut [f64],
    tm: &'a mut [f64],
    dm: &'a mut [f64],
    xm: &'a mut [f64],
    qm: &'a mut [f64],
    kk: &'a mut [f64],
    y: &'a mut [f64],
}

/// Where a task sits in the hierarchy ([`hierarchy_task`]).
#[derive(Clone, Copy)]
struct TaskShape {
    /// Rows of all tasks (the stride of `G` and `C`).
    rt: usize,
    /// The task's first row and its row count.
    o: usize,
    r: usize,
    /// The last task: no `C` to update.
    last: bool,
    /// `E_i G C_{i−1}` is in `qm` (the task before computed it).
    a_from_q: bool,
    /// The next task's rows when it is the last: compute its `E G C_i`
    /// into `qm` instead of `C_i`.
    next_last: Option<(usize, usize)>,
}

/// Task `i` of the hierarchy in task space ([`WholeBody`]'s docs): `g` is
/// `G`, `cm` is `C_{i−1}` (zero past `o`), updated to `C_i` unless the task
/// is the last or the one before it; `beta` gains `A_iᵀ Λ_i e_i`. A task
/// whose `Λ_i⁻¹` does not factor is skipped, as the dense recursion skips it.
fn hierarchy_task(
    g: &[f64],
    cm: &mut [f64],
    beta: &mut [f64],
    target: &[f64],
    shape: TaskShape,
    damping: f64,
    ws: TaskScratch<'_>,
) {
    let TaskShape { rt, o, r, .. } = shape;
    let s = o + r;
    let TaskScratch {
        am,
        tm,
        dm,
        xm,
        qm,
        kk,
        y,
    } = ws;
    // A = E_i (I − G C): [−G_io C_oo, I] (r × s)
    for a in 0..r {
        let arow = &mut am[a * rt..a * rt + s];
        if shape.a_from_q {
            for (x, q) in arow[..o].iter_mut().zip(&qm[a * rt..a * rt + o]) {
                *x = -q;
            }
        } else {
            arow[..o].fill(0.0);
            let grow = &g[(o + a) * rt..(o + a) * rt + o];
            for (c, &gc) in grow.iter().enumerate() {
                axpy(&mut arow[..o], -gc, &cm[c * rt..c * rt + o]);
            }
        }
        arow[o..s].fill(0.0);
        arow[o + a] = 1.0;
    }
    // T = A G (r × s); row a: G's row o + a plus A's first o entries times G's rows
    for a in 0..r {
        let trow = &mut tm[a * rt..a * rt + s];
        trow.copy_from_slice(&g[(o + a) * rt..(o + a) * rt + s]);
        for d in 0..o {
            let ad = am[a * rt + d];
            axpy(trow, ad, &g[d * rt..d * rt + s]);
        }
    }
    // Λ⁻¹ = T Aᵀ + λ I (lower triangle), factored
    for a in 0..r {
        for b in 0..=a {
            let v = dot(&tm[a * rt..a * rt + o], &am[b * rt..b * rt + o]) + tm[a * rt + o + b];
            kk[a * r + b] = v + if a == b { damping } else { 0.0 };
        }
    }
    if !cholesky_dense(kk, r) {
        // the task has no room left in the null space: C stays, and the
        // last task's E G C is that of C
        if let Some((ol, rl)) = shape.next_last {
            for a in 0..rl {
                let qrow = &mut qm[a * rt..a * rt + o];
                qrow.fill(0.0);
                let grow = &g[(ol + a) * rt..(ol + a) * rt + o];
                for (c, &gc) in grow.iter().enumerate() {
                    axpy(qrow, gc, &cm[c * rt..c * rt + o]);
                }
                qm[a * rt + o..a * rt + ol].fill(0.0);
            }
        }
        return;
    }
    // e = x − E_i G β (β is zero past o); β += Aᵀ Λ e
    for a in 0..r {
        y[a] = target[a] - dot(&g[(o + a) * rt..(o + a) * rt + o], &beta[..o]);
    }
    cholesky_dense_solve(kk, r, y);
    for a in 0..r {
        axpy(&mut beta[..s], y[a], &am[a * rt..a * rt + s]);
    }
    if shape.last {
        return;
    }
    // Dᵀ = A − T Cᵀ (C is zero past o)
    for a in 0..r {
        let (arow, trow) = (&am[a * rt..a * rt + s], &tm[a * rt..a * rt + o]);
        let drow = &mut dm[a * rt..a * rt + s];
        for c in 0..o {
            drow[c] = arow[c] - dot(&cm[c * rt..c * rt + o], trow);
        }
        drow[o..s].copy_from_slice(&arow[o..s]);
    }
    // X = Λ A: the factor's two triangular solves, a whole row at a time
    for a in 0..r {
        let (done, rest) = xm.split_at_mut(a * rt);
        let xrow = &mut rest[..s];
        xrow.copy_from_slice(&am[a * rt..a * rt + s]);
        for b in 0..a {
            axpy(xrow, -kk[a * r + b], &done[b * rt..b * rt + s]);
        }
        let inv = 1.0 / kk[a * r + a];
        xrow.iter_mut().for_each(|x| *x *= inv);
    }
    for a in (0..r).rev() {
        let (head, tail) = xm.split_at_mut((a + 1) * rt);
        let xrow = &mut head[a * rt..a * rt + s];
        for b in a + 1..r {
            axpy(
                xrow,
                -kk[b * r + a],
                &tail[(b - a - 1) * rt..(b - a - 1) * rt + s],
            );
        }
        let inv = 1.0 / kk[a * r + a];
        xrow.iter_mut().for_each(|x| *x *= inv);
    }
    if let Some((ol, rl)) = shape.next_last {
        // the last task's E G C_i = E G C_{i−1} + (E G D) X, over the first
        // s columns (the last task's o; its rows start right after)
        for a in 0..rl {
            let gl = &g[(ol + a) * rt..(ol + a) * rt + s];
            let qrow = &mut qm[a * rt..a * rt + s];
            qrow.fill(0.0);
            for (c, &gc) in gl[..o].iter().enumerate() {
                axpy(&mut qrow[..o], gc, &cm[c * rt..c * rt + o]);
            }
            for b in 0..r {
                let gd = dot(gl, &dm[b * rt..b * rt + s]);
                axpy(qrow, gd, &xm[b * rt..b * rt + s]);
            }
            qm[a * rt + s..a * rt + ol].fill(0.0);
        }
        return;
    }
    // C += D X
    for c in 0..s {
        let crow = &mut cm[c * rt..c * rt + s];
        for a in 0..r {
            axpy(crow, dm[a * rt + c], &xm[a * rt..a * rt + s]);
        }
    }
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
