//! Convex model-predictive control of the body on the single-rigid-body
//! model (Di Carlo, Wensing, Katz, Bledt and Kim, IROS 2018, "Dynamic
//! Locomotion in the MIT Cheetah 3 Through Convex Model-Predictive Control").
//!
//! The body is one rigid body of the robot's mass and its composite
//! rotational inertia about the CoM. Over a horizon of `N` steps of `Δt` the
//! ground reaction forces of the feet that the gait plans in stance are
//! chosen to follow a reference state, subject to friction pyramids and
//! normal-force bounds. Linearised about the current yaw ψ and small roll
//! and pitch (the paper's equations 16–17):
//!
//! ```text
//! x  = [Θ, p, ω, ṗ] ∈ ℝ¹²   (roll–pitch–yaw, CoM position, angular velocity
//!                            and CoM velocity; world axes)
//! Θ̇ = R_z(ψ)ᵀ ω            ṗ = ṗ
//! ω̇ = I_w⁻¹ Σᵢ rᵢ × fᵢ      p̈ = Σᵢ fᵢ / m + g
//! ```
//!
//! with `I_w = R_z I_b R_zᵀ` and `rᵢ` the foot relative to the CoM. One step
//! is integrated exactly for constant forces: positions and angles take
//! `½Δt²` of the accelerations, velocities `Δt`. The predictions over the
//! horizon are condensed (`X = A_qp x₀ + B_qp U + c_qp`, gravity in `c`) into
//! a dense QP over the forces of the stance feet only,
//!
//! `min ½ Uᵀ H U + gᵀ U`, `H = 2(B_qpᵀ L B_qp + α I)`, `g = 2 B_qpᵀ L (A_qp x₀ + c_qp − X_ref)`,
//!
//! subject to, per stance foot and step, `|f_x|, |f_y| ≤ μ f_z` (the
//! pyramid in world axes) and `f_min ≤ f_z ≤ f_max`. It is solved by ADMM
//! ([`super::admm`], warm-started from the last solve when the contact
//! plan keeps its shape) or by `clarabel` (interior point, the reference:
//! [`MpcSolver`]). Only the first step's forces are used; the plan is
//! solved again at [`MpcParams::solve_every_s`] and at every touchdown and
//! lift-off.

use super::admm::{Admm, AdmmSettings};
use glam::{DMat3, DVec3};

/// Size of the state (no gravity state: gravity enters the affine term).
pub const NX: usize = 12;
/// Most feet.
pub const MPC_FEET: usize = 4;

/// Tuning of [`Mpc`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MpcParams {
    /// Steps in the horizon (≥ 1).
    pub horizon_steps: usize,
    /// Length of one step (s).
    pub step_s: f64,
    /// Time between solves when no foot touches down or lifts off (s).
    pub solve_every_s: f64,
    /// Weights of the state error: roll, pitch, yaw, x, y, z, ω (3), ṗ (3).
    pub state_weights: [f64; NX],
    /// Weight α of the forces' squared norm (1/N² relative to the state's).
    pub force_weight: f64,
    /// Bounds of a stance foot's normal force (N).
    pub normal_force_n: (f64, f64),
    /// The QP solver.
    pub solver: MpcSolver,
}

/// The solver of the MPC's condensed QP.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MpcSolver {
    /// ADMM on the dense problem, warm-started ([`super::admm`]).
    #[default]
    Admm,
    /// `clarabel`'s interior-point method (allocates; the reference).
    Clarabel,
}

impl Default for MpcParams {
    /// A 0.5 s horizon in 10 steps (one period of the long-swing trot),
    /// solved at 50 Hz, with state weights after MIT's Mini Cheetah's.
    /// The force weight 3e-6 was chosen by campaigns (quad16, sensed state,
    /// DC motors, 20 perturbed copies at 1.25 m/s, `docs/validation.md`):
    /// 1e-5 let 4 of 20 fall, 3e-6 and 1e-6 none (1e-6 tracked speed
    /// worse, 0.10 against 0.07 m/s worst error).
    fn default() -> Self {
        MpcParams {
            horizon_steps: 10,
            step_s: 0.05,
            solve_every_s: 0.02,
            state_weights: [
                25.0, 25.0, 10.0, 2.0, 2.0, 50.0, 1.0, 1.0, 0.3, 2.0, 2.0, 1.0,
            ],
            force_weight: 3e-6,
            normal_force_n: (5.0, 1000.0),
            solver: MpcSolver::Admm,
        }
    }
}

/// Why a plan failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MpcError {
    /// No foot is planned in stance anywhere in the horizon.
    #[error("no stance foot in the horizon")]
    NoStance,
    /// An input was not finite.
    #[error("non-finite MPC input")]
    NotFinite,
    /// The solver did not report a solution.
    #[error("MPC solver: {0}")]
    Solver(String),
}

/// The body's state and targets at the start of a plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MpcState {
    /// Roll, pitch, yaw (rad; URDF roll–pitch–yaw of the torso).
    pub rpy: DVec3,
    /// CoM position (m, world).
    pub com_m: DVec3,
    /// Angular velocity (rad/s, world).
    pub omega_world_radps: DVec3,
    /// CoM velocity (m/s, world).
    pub com_velocity_mps: DVec3,
}

/// One step's contact plan: which feet stand and where, relative to the
/// CoM's reference position at that step (m, world), with their friction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MpcStep {
    /// Stance flag per foot.
    pub stance: [bool; MPC_FEET],
    /// Foot position relative to the reference CoM (m, world).
    pub foot_m: [DVec3; MPC_FEET],
    /// Friction coefficient the plan may use per foot.
    pub friction: [f64; MPC_FEET],
}

/// The problem of one solve: the body, its reference and contact plan.
#[derive(Clone, Debug, PartialEq)]
pub struct MpcProblem {
    /// Mass (kg).
    pub mass_kg: f64,
    /// Rotational inertia about the CoM in the heading frame (world axes
    /// turned by yaw; kg·m²).
    pub inertia_heading: DMat3,
    /// Gravity (m/s², world).
    pub gravity: DVec3,
    /// The state now.
    pub state: MpcState,
    /// Reference state after each step (`horizon_steps` of them).
    pub reference: Vec<[f64; NX]>,
    /// Contact plan of each step (`horizon_steps` of them).
    pub steps: Vec<MpcStep>,
}

impl MpcProblem {
    /// A problem for a horizon of `n` steps (all feet in the air, zero state).
    pub fn with_horizon(n: usize) -> Self {
        MpcProblem {
            mass_kg: 1.0,
            inertia_heading: DMat3::IDENTITY,
            gravity: DVec3::new(0.0, 0.0, -9.81),
            state: MpcState {
                rpy: DVec3::ZERO,
                com_m: DVec3::ZERO,
                omega_world_radps: DVec3::ZERO,
                com_velocity_mps: DVec3::ZERO,
            },
            reference: vec![[0.0; NX]; n],
            steps: vec![MpcStep::default(); n],
        }
    }
}

/// The state as the 12-vector of the model.
pub fn state_vector(s: &MpcState) -> [f64; NX] {
    [
        s.rpy.x,
        s.rpy.y,
        s.rpy.z,
        s.com_m.x,
        s.com_m.y,
        s.com_m.z,
        s.omega_world_radps.x,
        s.omega_world_radps.y,
        s.omega_world_radps.z,
        s.com_velocity_mps.x,
        s.com_velocity_mps.y,
        s.com_velocity_mps.z,
    ]
}

/// The planner with its buffers (reused between solves).
#[derive(Clone, Debug)]
pub struct Mpc {
    /// Tuning.
    pub params: MpcParams,
    /// `A` (row-major `NX × NX`).
    a: [[f64; NX]; NX],
    /// Variable of each (step, foot) in stance, `usize::MAX` otherwise.
    var_of: Vec<[usize; MPC_FEET]>,
    /// `B_qp` (row-major, `NX·N × nu`).
    bqp: Vec<f64>,
    /// Free response `A_qp x₀ + c_qp − X_ref` (NX·N).
    free: Vec<f64>,
    /// Condensed Hessian (nu × nu) and gradient.
    h: Vec<f64>,
    g: Vec<f64>,
    /// The first step's forces of the last solve (N, world; ground on foot).
    first: [DVec3; MPC_FEET],
    /// The predicted states of the last solve (after each step).
    predicted: Vec<[f64; NX]>,
    /// Every step's planned forces of the last solve.
    plan: Vec<[DVec3; MPC_FEET]>,
    /// Number of variables of the last solve.
    nu: usize,
    /// The ADMM workspace and the variable layout of its last solve.
    admm: Admm,
    last_var_of: Vec<[usize; MPC_FEET]>,
}

impl Mpc {
    /// A planner with `params` (horizon at least one step).
    pub fn new(params: MpcParams) -> Self {
        let n = params.horizon_steps.max(1);
        Mpc {
            params: MpcParams {
                horizon_steps: n,
                ..params
            },
            a: [[0.0; NX]; NX],
            var_of: vec![[usize::MAX; MPC_FEET]; n],
            bqp: Vec::new(),
            free: vec![0.0; NX * n],
            h: Vec::new(),
            g: Vec::new(),
            first: [DVec3::ZERO; MPC_FEET],
            predicted: vec![[0.0; NX]; n],
            plan: vec![[DVec3::ZERO; MPC_FEET]; n],
            nu: 0,
            admm: Admm::new(AdmmSettings::default()),
            last_var_of: vec![[usize::MAX; MPC_FEET]; n],
        }
    }

    /// The first step's planned forces of the last solve (N, world; the
    /// ground's force on each foot; zero for feet not in stance).
    pub fn first_forces(&self) -> &[DVec3; MPC_FEET] {
        &self.first
    }

    /// Every step's planned forces of the last solve (N, world; zero for
    /// feet not in stance at that step).
    pub fn planned_forces(&self) -> &[[DVec3; MPC_FEET]] {
        &self.plan
    }

    /// The states the last solve predicts after each step.
    pub fn predicted(&self) -> &[[f64; NX]] {
        &self.predicted
    }

    /// Number of force variables of the last solve.
    pub fn variables(&self) -> usize {
        self.nu
    }

    /// Plans the forces over the horizon; the first step's are returned.
    pub fn solve(&mut self, pb: &MpcProblem) -> Result<[DVec3; MPC_FEET], MpcError> {
        let n = self.params.horizon_steps;
        if pb.reference.len() < n || pb.steps.len() < n {
            return Err(MpcError::Solver("horizon longer than the problem".into()));
        }
        let x0 = state_vector(&pb.state);
        if x0.iter().any(|x| !x.is_finite())
            || !pb.mass_kg.is_finite()
            || pb.mass_kg <= 0.0
            || !pb.inertia_heading.is_finite()
        {
            return Err(MpcError::NotFinite);
        }
        // variables: 3 per (step, stance foot)
        let mut nu = 0;
        for (k, step) in pb.steps[..n].iter().enumerate() {
            for f in 0..MPC_FEET {
                self.var_of[k][f] = if step.stance[f] {
                    nu += 3;
                    nu - 3
                } else {
                    usize::MAX
                };
            }
        }
        if nu == 0 {
            return Err(MpcError::NoStance);
        }
        self.nu = nu;
        let dt = self.params.step_s;
        let yaw = pb.state.rpy.z;
        let (s, c) = yaw.sin_cos();
        // R_z(ψ)ᵀ, mapping world ω to rpy rates (small roll and pitch)
        let rzt = DMat3::from_cols(
            DVec3::new(c, -s, 0.0),
            DVec3::new(s, c, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        );
        let rz = rzt.transpose();
        let i_world = rz * pb.inertia_heading * rz.transpose();
        let i_inv = i_world.inverse();
        // A: x⁺ = A x (+ B u + c): Θ += Δt Rzᵀ ω, p += Δt ṗ
        let a = &mut self.a;
        *a = [[0.0; NX]; NX];
        for (i, row) in a.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        for r in 0..3 {
            for k in 0..3 {
                a[r][6 + k] = dt * rzt.col(k)[r];
            }
            a[3 + r][9 + r] = dt;
        }
        // affine (gravity): p += ½Δt² g, ṗ += Δt g
        let mut cvec = [0.0; NX];
        for r in 0..3 {
            cvec[3 + r] = 0.5 * dt * dt * pb.gravity[r];
            cvec[9 + r] = dt * pb.gravity[r];
        }
        // B_qp by columns of each step's B: block (k, j) = A^{k−j} B_j (k ≥ j)
        let rows = NX * n;
        self.bqp.clear();
        self.bqp.resize(rows * nu, 0.0);
        let mut next = [0.0; NX];
        for j in 0..n {
            for f in 0..MPC_FEET {
                let v0 = self.var_of[j][f];
                if v0 == usize::MAX {
                    continue;
                }
                let r = pb.steps[j].foot_m[f];
                for axis in 0..3 {
                    // B_j's column for force component `axis` of foot f
                    let e = DVec3::new(
                        (axis == 0) as u8 as f64,
                        (axis == 1) as u8 as f64,
                        (axis == 2) as u8 as f64,
                    );
                    let wdot = i_inv * r.cross(e);
                    let pdd = e / pb.mass_kg;
                    let mut col = [0.0; NX];
                    let rate = rzt * wdot;
                    for q in 0..3 {
                        col[q] = 0.5 * dt * dt * rate[q];
                        col[3 + q] = 0.5 * dt * dt * pdd[q];
                        col[6 + q] = dt * wdot[q];
                        col[9 + q] = dt * pdd[q];
                    }
                    let v = v0 + axis;
                    for k in j..n {
                        for q in 0..NX {
                            self.bqp[(k * NX + q) * nu + v] = col[q];
                        }
                        // advance one step: col ← A col
                        for q in 0..NX {
                            let mut acc = 0.0;
                            for m in 0..NX {
                                acc += self.a[q][m] * col[m];
                            }
                            next[q] = acc;
                        }
                        col = next;
                    }
                }
            }
        }
        // free response: x_{k+1} = A x_k + c, minus the reference
        let mut x = x0;
        for k in 0..n {
            for q in 0..NX {
                let mut acc = cvec[q];
                for m in 0..NX {
                    acc += self.a[q][m] * x[m];
                }
                next[q] = acc;
            }
            x = next;
            for q in 0..NX {
                self.free[k * NX + q] = x[q] - pb.reference[k][q];
            }
        }
        // H = 2(BᵀLB + αI), g = 2 BᵀL free
        let w = &self.params.state_weights;
        self.h.clear();
        self.h.resize(nu * nu, 0.0);
        self.g.clear();
        self.g.resize(nu, 0.0);
        // variables of steps ≤ k end at `ends[k]`: later forces do not act earlier
        let mut ends = [0usize; 64];
        let mut count = 0;
        for k in 0..n.min(64) {
            for f in 0..MPC_FEET {
                if self.var_of[k][f] != usize::MAX {
                    count = self.var_of[k][f] + 3;
                }
            }
            ends[k] = count;
        }
        for row in 0..rows {
            let l = w[row % NX];
            if l == 0.0 {
                continue;
            }
            let end = if row / NX < 64 { ends[row / NX] } else { nu };
            let b = &self.bqp[row * nu..row * nu + end];
            let lf = l * self.free[row];
            for i in 0..end {
                let bi = b[i];
                if bi == 0.0 {
                    continue;
                }
                self.g[i] += 2.0 * bi * lf;
                let lbi = 2.0 * l * bi;
                for jj in i..end {
                    self.h[i * nu + jj] += lbi * b[jj];
                }
            }
        }
        for i in 0..nu {
            self.h[i * nu + i] += 2.0 * self.params.force_weight;
        }
        let u = match self.params.solver {
            MpcSolver::Admm => self.solve_admm(pb, n, nu)?,
            MpcSolver::Clarabel => self.solve_qp(pb, n, nu)?,
        };
        // every step's forces and the predicted states
        for k in 0..n {
            for f in 0..MPC_FEET {
                let v = self.var_of[k][f];
                self.plan[k][f] = if v != usize::MAX {
                    DVec3::new(u[v], u[v + 1], u[v + 2])
                } else {
                    DVec3::ZERO
                };
            }
        }
        self.first = self.plan[0];
        for k in 0..n {
            for q in 0..NX {
                let mut acc = self.free[k * NX + q] + pb.reference[k][q];
                let b = &self.bqp[(k * NX + q) * nu..(k * NX + q + 1) * nu];
                for (bi, ui) in b.iter().zip(&u) {
                    acc += bi * ui;
                }
                self.predicted[k][q] = acc;
            }
        }
        Ok(self.first)
    }

    /// The condensed QP by ADMM, warm-started when the variables are those
    /// of the last solve (the same feet at the same steps).
    fn solve_admm(&mut self, pb: &MpcProblem, n: usize, nu: usize) -> Result<Vec<f64>, MpcError> {
        let same = self.last_var_of[..n] == self.var_of[..n];
        self.last_var_of[..n].copy_from_slice(&self.var_of[..n]);
        self.admm.begin(nu, same);
        let admm = &mut self.admm;
        constraint_rows(
            &self.var_of[..n],
            &pb.steps[..n],
            self.params.normal_force_n,
            |entries, bound| admm.push_row(entries, bound),
        );
        // P is filled in its upper triangle: mirror it for the solver
        for i in 0..nu {
            for j in 0..i {
                self.h[i * nu + j] = self.h[j * nu + i];
            }
        }
        match self.admm.solve(&self.h, &self.g) {
            Ok(x) => Ok(x.to_vec()),
            Err(e) => {
                self.last_var_of[..n].fill([usize::MAX; MPC_FEET]);
                Err(MpcError::Solver(e.to_string()))
            }
        }
    }

    /// Iterations of the last ADMM solve.
    pub fn admm_iterations(&self) -> usize {
        self.admm.iterations
    }

    /// The condensed QP by `clarabel`: returns the forces `U`.
    fn solve_qp(&self, pb: &MpcProblem, n: usize, nu: usize) -> Result<Vec<f64>, MpcError> {
        use clarabel::algebra::CscMatrix;
        use clarabel::solver::{
            DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
        };
        // P: upper triangle by columns
        let mut colptr = Vec::with_capacity(nu + 1);
        let mut rowval = Vec::with_capacity(nu * (nu + 1) / 2);
        let mut nzval = Vec::with_capacity(nu * (nu + 1) / 2);
        colptr.push(0);
        for j in 0..nu {
            for i in 0..=j {
                rowval.push(i);
                nzval.push(self.h[i * nu + j]);
            }
            colptr.push(rowval.len());
        }
        let p = CscMatrix::new(nu, nu, colptr, rowval, nzval);
        // constraints A u ≤ b: six rows per (step, stance foot)
        let mut a_cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nu];
        let mut b = Vec::with_capacity(2 * nu);
        constraint_rows(
            &self.var_of[..n],
            &pb.steps[..n],
            self.params.normal_force_n,
            |entries, bound| {
                for &(col, x) in entries {
                    a_cols[col].push((b.len(), x));
                }
                b.push(bound);
            },
        );
        let m = b.len();
        let mut colptr = Vec::with_capacity(nu + 1);
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        colptr.push(0);
        for c in &mut a_cols {
            c.sort_by_key(|e| e.0);
            for &(r, x) in c.iter() {
                rowval.push(r);
                nzval.push(x);
            }
            colptr.push(rowval.len());
        }
        let a = CscMatrix::new(m, nu, colptr, rowval, nzval);
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .build()
            .map_err(|e| MpcError::Solver(format!("{e:?}")))?;
        let cones = [NonnegativeConeT(m)];
        let mut solver = DefaultSolver::new(&p, &self.g, &a, &b, &cones, settings)
            .map_err(|e| MpcError::Solver(format!("{e:?}")))?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(solver.solution.x.clone()),
            s => Err(MpcError::Solver(format!("{s:?}"))),
        }
    }
}

/// The QP's constraints `Σ x·u[col] ≤ bound`, six per stance foot and
/// step (the variables of `var_of`), given to `row` in order:
/// `±f_x − μ f_z ≤ 0`, `±f_y − μ f_z ≤ 0`, `f_z ≤ f_max`, `−f_z ≤ −f_min`.
fn constraint_rows(
    var_of: &[[usize; MPC_FEET]],
    steps: &[MpcStep],
    (fmin, fmax): (f64, f64),
    mut row: impl FnMut(&[(usize, f64)], f64),
) {
    for (vars, step) in var_of.iter().zip(steps) {
        for (f, &v) in vars.iter().enumerate() {
            if v == usize::MAX {
                continue;
            }
            let mu = step.friction[f].max(0.0);
            for (axis, sign) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)] {
                row(&[(v + axis, sign), (v + 2, -mu)], 0.0);
            }
            row(&[(v + 2, 1.0)], fmax);
            row(&[(v + 2, -1.0)], -fmin);
        }
    }
}

/// A trot's problem for timing a solve (criterion's `mpc/trot_horizon10`
/// and `quadsim bench --planner mpc`): quad16's mass and an inertia of its
/// size at 0.45 m, moving at 0.9 m/s toward a 1 m/s reference, the
/// diagonal pairs swapping every 0.25 s (about 60 force variables), at
/// time `t_s` of the gait (a sequence of solves 0.02 s apart is what the
/// walker asks at 50 Hz: the plan shifts, and keeps its shape between the
/// pairs' swaps).
pub fn trot_benchmark_problem_at(params: &MpcParams, t_s: f64) -> MpcProblem {
    let n = params.horizon_steps.max(1);
    let mut pb = MpcProblem::with_horizon(n);
    pb.mass_kg = 28.0;
    pb.inertia_heading = DMat3::from_diagonal(DVec3::new(0.5, 1.6, 1.8));
    let wobble = (t_s * std::f64::consts::TAU * 4.0).sin();
    pb.state = MpcState {
        rpy: DVec3::new(0.01 * wobble, -0.02, 0.1),
        com_m: DVec3::new(0.9 * t_s, 0.0, 0.45 + 0.01 * wobble),
        omega_world_radps: DVec3::new(0.1 * wobble, -0.05, 0.0),
        com_velocity_mps: DVec3::new(0.9 + 0.2 * wobble, 0.05, -0.1 * wobble),
    };
    let x0 = state_vector(&pb.state);
    for k in 0..n {
        let mut r = x0;
        r[0] = 0.0;
        r[1] = 0.0;
        r[3] += params.step_s * (k + 1) as f64;
        r[9] = 1.0;
        pb.reference[k] = r;
        let t_mid = t_s + params.step_s * (k as f64 + 0.5);
        let a = ((t_mid / 0.25).floor() as i64) % 2 == 0;
        pb.steps[k] = MpcStep {
            stance: [a, !a, !a, a],
            foot_m: [
                DVec3::new(0.25, 0.15, -0.45),
                DVec3::new(0.25, -0.15, -0.45),
                DVec3::new(-0.25, 0.15, -0.45),
                DVec3::new(-0.25, -0.15, -0.45),
            ],
            friction: [0.8; MPC_FEET],
        };
    }
    pb
}

/// [`trot_benchmark_problem_at`] at time 0.
pub fn trot_benchmark_problem(params: &MpcParams) -> MpcProblem {
    trot_benchmark_problem_at(params, 0.0)
}

/// The rotational inertia of the whole robot about its CoM (kg·m², world
/// axes), from the bodies' inertias at the kinematics in `data`.
pub fn composite_inertia_about_com(
    model: &crate::model::Model,
    data: &crate::data::Data,
) -> (f64, DVec3, DMat3) {
    let mut m = 0.0;
    let mut mc = DVec3::ZERO;
    for i in 0..model.nbodies {
        let ri = data.body_inertia(model, i);
        m += ri.mass;
        mc += ri.com * ri.mass;
    }
    if m <= 0.0 {
        return (0.0, data.origin, DMat3::ZERO);
    }
    let c = mc / m;
    let mut inertia = DMat3::ZERO;
    for i in 0..model.nbodies {
        let ri = data.body_inertia(model, i);
        let d = ri.com - c;
        let shift = (DMat3::IDENTITY * d.length_squared()
            - DMat3::from_cols(d * d.x, d * d.y, d * d.z))
            * ri.mass;
        inertia += ri.inertia_com + shift;
    }
    (m, data.origin + c, inertia)
}
