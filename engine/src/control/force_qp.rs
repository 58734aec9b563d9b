//! Distribution of a desired body wrench over the stance feet (a QP), and the
//! joint torques that make the ground push with those forces.
//!
//! # The QP
//! For `k` loaded stance feet with contact points `rᵢ` (relative to the CoM,
//! world axes) and ground reaction forces `fᵢ` (the ground's force on the
//! foot, world axes), `A f = [Σ fᵢ; Σ rᵢ × fᵢ]` is the wrench about the CoM.
//! The forces minimise
//!
//! `‖A f − W‖²_S + α ‖f‖²`
//!
//! with `S` a diagonal weight on the wrench rows and a small `α` that picks,
//! among forces producing the same wrench, the least-norm one (no internal
//! squeeze between feet) and makes the QP strictly convex. Subject to, per foot
//! with terrain normal `n`, tangents `t₁, t₂` ([`tangent_basis`]), friction μ
//! and load factor `λ ∈ [0, 1]` (from the gait):
//!
//! - the **inscribed** friction pyramid, 4 facets `|tⱼ·f| ≤ (μ/√2) n·f`: every
//!   force in it lies inside the true cone `|f_t| ≤ μ f_n` (the pyramid's
//!   corners touch the cone), so the foot never needs more friction than the
//!   ground has;
//! - `f_min λ ≤ n·f ≤ f_max λ`: a minimum normal force keeps a loaded foot
//!   from unloading (and slipping), the upper bound makes a foot's force go to
//!   zero smoothly as the gait unloads it. Feet with `λ = 0` get no force.
//!
//! Two solvers give the same minimiser: [`solve_clarabel`], the reference
//! (the `clarabel` interior-point crate; allocates; 64–122 µs per solve at
//! its tightened tolerances), and [`ForceQp::solve`], a dual active-set
//! solver on the stack ([`super::active_set`]; 0.45–1.4 µs, so ≤ 0.35 µs per
//! physics step when the controller runs at a quarter of the step rate),
//! checked against it to 1e-6 in `engine/tests/vmc.rs`
//! (`engine/benches/control.rs` measures both).
//!
//! # Torques: sign convention
//! With `M q̈ + h = τ + Jᵀ f_ext` and `f_ext` the ground's force on the foot,
//! a standing leg makes the ground push with `f` by pushing the ground with
//! `−f`: `τ = −Jᵀ f` ([`stance_torques`]), `J` the foot point's Jacobian.

use crate::control::active_set::{ActiveSet, ActiveSetError, DenseQp, MAX_VARS};
use crate::data::Data;
#[cfg(doc)]
use crate::jacobian::point_jacobian;
use crate::model::{JointType, Model, NO_PARENT};
use crate::spatial::{Force, skew};
use glam::{DMat3, DVec3};

/// Most stance feet the QP takes.
pub const MAX_FEET: usize = 4;

/// Ground reaction force per input foot (N, world; the ground's force on the
/// foot). Entries past the number of feet given, and of unloaded feet, are zero.
pub type FootForces = [DVec3; MAX_FEET];

/// One stance foot as the QP sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StanceFoot {
    /// Contact point relative to the robot's CoM (m, world axes).
    pub position_m: DVec3,
    /// Terrain normal at the contact (world, unit, out of the ground).
    pub normal: DVec3,
    /// Coulomb friction coefficient μ (≥ 0).
    pub friction: f64,
    /// Load factor λ in [0, 1] from the gait: 1 fully loaded, 0 no force.
    pub load: f64,
}

/// Weights and bounds of the force QP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceQpParams {
    /// Diagonal of `S`: force rows (N⁻²) then moment rows ((N·m)⁻²).
    pub wrench_weight: [f64; 6],
    /// Regulariser α (N⁻², > 0).
    pub regularization: f64,
    /// Minimum normal force of a fully loaded foot `f_min` (N, ≥ 0).
    pub min_normal_force_n: f64,
    /// Maximum normal force of a fully loaded foot `f_max` (N, ≥ `f_min`).
    pub max_normal_force_n: f64,
}

impl Default for ForceQpParams {
    /// `S = diag(1, 1, 1, 10, 10, 10)`: a 1 N·m moment error counts like a
    /// 3 N force error, about what a foot 0.3 m from the CoM makes it with.
    /// `α = 1e-6`: the wrench of an achievable `W` is reproduced to about
    /// `α / σ²_min(S^½A) ≈ 1e-6` relative while the QP stays well enough
    /// conditioned (`≈ 40/α`) for both solvers to agree to 1e-6.
    /// `f_min = 5 N` (2 % of quad16's weight per foot), `f_max = 1000 N`
    /// (3.6 × quad16's weight: a bound for unloading, not a working limit).
    fn default() -> Self {
        ForceQpParams {
            wrench_weight: [1.0, 1.0, 1.0, 10.0, 10.0, 10.0],
            regularization: 1e-6,
            min_normal_force_n: 5.0,
            max_normal_force_n: 1000.0,
        }
    }
}

/// Bad input to the force QP.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ForceQpError {
    /// More stance feet than [`MAX_FEET`].
    #[error("force QP: {got} stance feet given, at most {MAX_FEET} supported")]
    TooManyFeet {
        /// Number given.
        got: usize,
    },
    /// A foot field out of its domain.
    #[error("force QP: foot {index} field '{field}' = {value} is invalid ({why})")]
    Foot {
        /// Index of the foot.
        index: usize,
        /// Field name.
        field: &'static str,
        /// Offending value (for `normal`, its norm).
        value: f64,
        /// What is wrong.
        why: &'static str,
    },
    /// A parameter out of its domain.
    #[error("force QP: parameter '{field}' = {value} is invalid ({why})")]
    Param {
        /// Field name.
        field: &'static str,
        /// Offending value.
        value: f64,
        /// What is wrong.
        why: &'static str,
    },
    /// A non-finite entry in the desired wrench.
    #[error("force QP: the desired wrench has a non-finite entry")]
    Wrench,
    /// The solver failed (not expected for valid input: the QP is always feasible).
    #[error("force QP: the solver failed ({0})")]
    Solver(String),
}

impl From<ActiveSetError> for ForceQpError {
    fn from(e: ActiveSetError) -> Self {
        ForceQpError::Solver(e.to_string())
    }
}

/// Tangent directions `(t₁, t₂)` of the friction pyramid's facets about the
/// unit normal `n`: `t₁` is world x projected onto the tangent plane (world y
/// when `n` is within ~25° of x), `t₂ = n × t₁`. On level ground the facets
/// face ±x and ±y.
pub fn tangent_basis(n: DVec3) -> (DVec3, DVec3) {
    let seed = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t1 = (seed - seed.dot(n) * n).normalize();
    (t1, n.cross(t1))
}

/// The wrench about the CoM that the forces make: `[Σ fᵢ; Σ rᵢ × fᵢ]` (N, N·m).
pub fn achieved_wrench(feet: &[StanceFoot], forces: &FootForces) -> Force {
    let mut w = Force::ZERO;
    for (foot, f) in feet.iter().zip(forces) {
        w.lin += *f;
        w.ang += foot.position_m.cross(*f);
    }
    w
}

/// Checks the parameters, feet and wrench.
///
/// # Errors
/// [`ForceQpError`] naming the first offending field.
pub fn validate(
    params: &ForceQpParams,
    feet: &[StanceFoot],
    wrench: &Force,
) -> Result<(), ForceQpError> {
    if all_valid(params, feet, wrench) {
        return Ok(());
    }
    first_error(params, feet, wrench)
}

/// [`validate`]'s checks one by one, each with its error: the first that
/// fails (`Ok` if none does).
fn first_error(
    params: &ForceQpParams,
    feet: &[StanceFoot],
    wrench: &Force,
) -> Result<(), ForceQpError> {
    let param = |field, value, why| Err(ForceQpError::Param { field, value, why });
    if let Some(&w) = params
        .wrench_weight
        .iter()
        .find(|w| !(w.is_finite() && **w >= 0.0))
    {
        return param("wrench_weight", w, "must be finite and ≥ 0");
    }
    let a = params.regularization;
    if !(a.is_finite() && a > 0.0) {
        return param("regularization", a, "must be finite and > 0");
    }
    let (lo, hi) = (params.min_normal_force_n, params.max_normal_force_n);
    if !(lo.is_finite() && lo >= 0.0) {
        return param("min_normal_force_n", lo, "must be finite and ≥ 0");
    }
    if !(hi.is_finite() && hi >= lo) {
        return param(
            "max_normal_force_n",
            hi,
            "must be finite and ≥ min_normal_force_n",
        );
    }
    if feet.len() > MAX_FEET {
        return Err(ForceQpError::TooManyFeet { got: feet.len() });
    }
    for (index, foot) in feet.iter().enumerate() {
        let bad = |field, value, why| {
            Err(ForceQpError::Foot {
                index,
                field,
                value,
                why,
            })
        };
        if !foot.position_m.is_finite() {
            return bad("position_m", f64::NAN, "must be finite");
        }
        let norm = foot.normal.length();
        if !(norm.is_finite() && (norm - 1.0).abs() <= 1e-6) {
            return bad("normal", norm, "must be a unit vector");
        }
        if !(foot.friction.is_finite() && foot.friction >= 0.0) {
            return bad("friction", foot.friction, "must be finite and ≥ 0");
        }
        if !(0.0..=1.0).contains(&foot.load) {
            return bad("load", foot.load, "must be in [0, 1]");
        }
    }
    if !(wrench.lin.is_finite() && wrench.ang.is_finite()) {
        return Err(ForceQpError::Wrench);
    }
    Ok(())
}

/// Whether [`validate`] finds nothing wrong: every check of [`first_error`],
/// as one branch-free conjunction (it runs before every solve; the checks
/// one by one, each with its error, only when one fails). A unit test keeps
/// the two in step.
fn all_valid(params: &ForceQpParams, feet: &[StanceFoot], wrench: &Force) -> bool {
    // `x.is_finite() && x >= 0.0`
    let finite_nonneg = |x: f64| (0.0..=f64::MAX).contains(&x);
    let (a, lo, hi) = (
        params.regularization,
        params.min_normal_force_n,
        params.max_normal_force_n,
    );
    let mut ok = params
        .wrench_weight
        .iter()
        .fold(true, |ok, &w| ok & finite_nonneg(w));
    ok &= a.is_finite() & (a > 0.0);
    ok &= finite_nonneg(lo) & hi.is_finite() & (hi >= lo);
    ok &= feet.len() <= MAX_FEET;
    for foot in feet {
        let norm = foot.normal.length();
        ok &= foot.position_m.is_finite()
            & norm.is_finite()
            & ((norm - 1.0).abs() <= 1e-6)
            & finite_nonneg(foot.friction)
            & (0.0..=1.0).contains(&foot.load);
    }
    ok & wrench.lin.is_finite() & wrench.ang.is_finite()
}

/// Writes the QP in the form `min ½ xᵀHx + gᵀx, C x ≥ b` for the loaded feet
/// (`x` their stacked forces, world axes) and returns which input foot each
/// 3-block of `x` belongs to (and how many).
fn build(
    params: &ForceQpParams,
    feet: &[StanceFoot],
    wrench: &Force,
    qp: &mut DenseQp,
) -> ([usize; MAX_FEET], usize) {
    let mut map = [0; MAX_FEET];
    let mut k = 0;
    for (i, foot) in feet.iter().enumerate() {
        if foot.load > 0.0 {
            map[k] = i;
            k += 1;
        }
    }
    let n = 3 * k;
    qp.n = n;
    qp.m = 6 * k;
    qp.foot_blocks = true;
    let sw = params.wrench_weight;
    let s_f = DMat3::from_diagonal(DVec3::new(sw[0], sw[1], sw[2]));
    let s_m = DMat3::from_diagonal(DVec3::new(sw[3], sw[4], sw[5]));
    let (f_w, m_w) = (s_f * wrench.lin, s_m * wrench.ang);
    // H = 2 (AᵀSA + αI): block (a, b) = 2 (S_F + [r_a]×ᵀ S_M [r_b]×) (+ 2α I on the diagonal);
    // g = −2 AᵀSW: block a = −2 (S_F F + [r_a]×ᵀ S_M M).
    for a in 0..k {
        let ra = skew(feet[map[a]].position_m);
        let rat_sm = ra.transpose() * s_m;
        let ga = -2.0 * (f_w + ra.transpose() * m_w);
        for (r, g) in qp.g[3 * a..3 * a + 3].iter_mut().zip(ga.to_array()) {
            *r = g;
        }
        for b in a..k {
            let mut blk = (s_f + rat_sm * skew(feet[map[b]].position_m)) * 2.0;
            if a == b {
                blk += DMat3::IDENTITY * (2.0 * params.regularization);
            }
            for r in 0..3 {
                for c in 0..3 {
                    let v = blk.col(c)[r];
                    qp.h[3 * a + r][3 * b + c] = v;
                    qp.h[3 * b + c][3 * a + r] = v;
                }
            }
        }
        // constraints of foot a: rows 6a..6a+6, nonzero only in columns 3a..3a+3
        for (j, (c, b)) in foot_constraints(params, &feet[map[a]])
            .into_iter()
            .enumerate()
        {
            // the whole row (a constant length: stores, not a `memset` call
            // per row); the solver reads its first `n` entries
            let row = &mut qp.c[6 * a + j];
            *row = [0.0; MAX_VARS];
            row[3 * a..3 * a + 3].copy_from_slice(&c.to_array());
            qp.b[6 * a + j] = b;
        }
    }
    (map, k)
}

/// The six constraints `cᵀf ≥ b` of one foot (world axes): normal force
/// bounds, then the inscribed pyramid's facets `(μ/√2) n·f ∓ tⱼ·f ≥ 0`.
fn foot_constraints(params: &ForceQpParams, foot: &StanceFoot) -> [(DVec3, f64); 6] {
    let nrm = foot.normal;
    let (t1, t2) = tangent_basis(nrm);
    let mu = foot.friction * std::f64::consts::FRAC_1_SQRT_2;
    [
        (nrm, params.min_normal_force_n * foot.load),
        (-nrm, -params.max_normal_force_n * foot.load),
        (mu * nrm - t1, 0.0),
        (mu * nrm + t1, 0.0),
        (mu * nrm - t2, 0.0),
        (mu * nrm + t2, 0.0),
    ]
}

/// The stance-force QP with its dedicated solver; allocates nothing after
/// construction. The QP's arrays and the solver's workspace (7.6 KiB, sized
/// for four feet) hold nothing from one solve to the next (every entry a
/// solve reads, it first writes), so one per thread serves every robot
/// stepped on that thread instead of one per robot (`WORKSPACE`).
#[derive(Clone, Debug)]
pub struct ForceQp {
    /// Weights and bounds.
    pub params: ForceQpParams,
    /// Active-set iterations of the last solve that ran the solver.
    iterations: usize,
}

thread_local! {
    /// The QP and solver workspace of the solves run on this thread (made
    /// on a thread's first solve; a solve borrows it for its duration only).
    static WORKSPACE: std::cell::RefCell<(DenseQp, ActiveSet)> = std::cell::RefCell::new((
        DenseQp {
            // constraints in N: 1e-9 N is far below any force that matters
            tolerance: 1e-9,
            ..DenseQp::default()
        },
        ActiveSet::default(),
    ));
}

impl ForceQp {
    /// A solver with the given parameters.
    pub fn new(params: ForceQpParams) -> Self {
        ForceQp {
            params,
            iterations: 0,
        }
    }

    /// The forces minimising the QP (module docs) for the desired wrench `W`
    /// about the CoM (N, N·m, world axes); zero forces with no loaded foot.
    ///
    /// # Errors
    /// [`ForceQpError`] for invalid input ([`validate`]).
    pub fn solve(
        &mut self,
        feet: &[StanceFoot],
        wrench: &Force,
    ) -> Result<FootForces, ForceQpError> {
        validate(&self.params, feet, wrench)?;
        WORKSPACE.with_borrow_mut(|(qp, solver)| {
            let (map, k) = build(&self.params, feet, wrench, qp);
            let mut out = [DVec3::ZERO; MAX_FEET];
            if k == 0 {
                return Ok(out);
            }
            let solved = solver.solve(qp).map(|x| {
                for a in 0..k {
                    out[map[a]] = DVec3::new(x[3 * a], x[3 * a + 1], x[3 * a + 2]);
                }
            });
            self.iterations = solver.iterations;
            solved?;
            Ok(out)
        })
    }

    /// Active-set iterations (constraint additions and drops) of the last solve.
    pub fn last_iterations(&self) -> usize {
        self.iterations
    }
}

impl Default for ForceQp {
    fn default() -> Self {
        ForceQp::new(ForceQpParams::default())
    }
}

/// The same QP solved by `clarabel` (interior point; allocates): the
/// reference for [`ForceQp::solve`], built independently of its `H` and `g`.
///
/// The residual is lifted into variables, `e = S^½ (A f − W)`, so the
/// objective is `‖e‖² + α‖f‖²` over `(f, e)` with `e` tied by 6 equalities.
/// Written directly as `‖A f − W‖²_S` the objective carries a constant
/// `−WᵀSW` (~10⁵), and the gap tolerances, relative to it, stop the solver
/// several newtons from the minimiser along the directions only `α` fixes.
/// Tolerances are tightened (gap 1e-13 absolute, 1e-14 relative; feasibility
/// 1e-12; about 20 iterations; tighter, it stops on insufficient progress)
/// and the KKT regularisation lowered to 1e-12.
///
/// # Errors
/// [`ForceQpError`] for invalid input, or when clarabel does not report
/// `Solved`/`AlmostSolved`.
pub fn solve_clarabel(
    params: &ForceQpParams,
    feet: &[StanceFoot],
    wrench: &Force,
) -> Result<FootForces, ForceQpError> {
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{
        DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
    };
    validate(params, feet, wrench)?;
    let loaded: Vec<usize> = (0..feet.len()).filter(|&i| feet[i].load > 0.0).collect();
    let mut out = [DVec3::ZERO; MAX_FEET];
    if loaded.is_empty() {
        return Ok(out);
    }
    let nf = 3 * loaded.len();
    let n = nf + 6;
    let m = 6 + 6 * loaded.len();
    // dense constraint matrix (rows: 6 equalities, then 6 inequalities per foot)
    let mut a = vec![vec![0.0; n]; m];
    let mut b = vec![0.0; m];
    let sq: Vec<f64> = params.wrench_weight.iter().map(|w| w.sqrt()).collect();
    let w6 = [
        wrench.lin.x,
        wrench.lin.y,
        wrench.lin.z,
        wrench.ang.x,
        wrench.ang.y,
        wrench.ang.z,
    ];
    for (k, &i) in loaded.iter().enumerate() {
        let r = feet[i].position_m;
        for c in 0..3 {
            let e = DVec3::AXES[c];
            let moment = r.cross(e); // wrench of a unit force along axis c
            let col = [e.x, e.y, e.z, moment.x, moment.y, moment.z];
            for row in 0..6 {
                a[row][3 * k + c] = sq[row] * col[row];
            }
        }
        // C x ≥ b  ⇔  −C x + s = −b, s ≥ 0
        for (j, (cr, lo)) in foot_constraints(params, &feet[i]).into_iter().enumerate() {
            let row = 6 + 6 * k + j;
            a[row][3 * k..3 * k + 3].copy_from_slice(&(-cr).to_array());
            b[row] = -lo;
        }
    }
    for row in 0..6 {
        a[row][nf + row] = -1.0;
        b[row] = sq[row] * w6[row];
    }
    let (mut colptr, mut rowval, mut nzval) = (vec![0], Vec::new(), Vec::new());
    for c in 0..n {
        for (r, arow) in a.iter().enumerate() {
            if arow[c] != 0.0 {
                rowval.push(r);
                nzval.push(arow[c]);
            }
        }
        colptr.push(rowval.len());
    }
    let a = CscMatrix::new(m, n, colptr, rowval, nzval);
    // P = 2 diag(α I, I): objective ‖e‖² + α‖f‖²
    let diag: Vec<f64> = (0..n)
        .map(|i| {
            if i < nf {
                2.0 * params.regularization
            } else {
                2.0
            }
        })
        .collect();
    let p = CscMatrix::new(n, n, (0..=n).collect(), (0..n).collect(), diag);
    let q = vec![0.0; n];
    let settings = DefaultSettings {
        verbose: false,
        tol_gap_abs: 1e-13,
        tol_gap_rel: 1e-14,
        tol_feas: 1e-12,
        // the default 1e-8 is 0.5 % of the curvature 2α along the directions
        // only α fixes, and biased them by up to 0.04 N
        static_regularization_constant: 1e-12,
        ..DefaultSettings::default()
    };
    let cones = [ZeroConeT(6), NonnegativeConeT(m - 6)];
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| ForceQpError::Solver(e.to_string()))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        s => return Err(ForceQpError::Solver(format!("clarabel: {s:?}"))),
    }
    let x = &solver.solution.x;
    for (k, &i) in loaded.iter().enumerate() {
        out[i] = DVec3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
    }
    Ok(out)
}

/// Joint torques (N·m, joints only: `nv − base_nv` entries, overwritten) that
/// make the ground push each stance foot with its force: `τ = −Σᵢ Jᵢᵀ fᵢ`
/// (joint rows), clamped to the model's effort limits.
///
/// `feet[i]` is `(body, contact point in world coordinates)`, `forces[i]` the
/// desired ground reaction force on that foot (N, world). `J` is
/// [`point_jacobian`] of the contact point: with `M q̈ + h = τ + Jᵀ f_ext` and
/// `f_ext` the ground's force on the foot, the leg pushes the ground with
/// `−f` so that the ground pushes back with `f`. Needs kinematics at the
/// current state in `data`. Each foot's `Jᵀ f` is summed over its own
/// chain's columns only (the joints from its body to the base), without
/// forming `J`: the other columns of `J` are exact zeros, whose products
/// would leave the sums unchanged (the torques start at `+0` and never
/// become `−0`), so the bits are those of the dense product (a unit test
/// checks them against [`point_jacobian`]); for the same reason a foot
/// whose force is zero (a swinging or unloaded foot) is skipped.
///
/// The legs' own weight is not in `τ`; add the joint rows of
/// [`crate::nle::generalized_gravity`] for a static hold (`τ = g(q) − Jᵀ f`,
/// as [`super::joint_pd::static_stance_torques`] does). Without them part of
/// each leg's weight reaches the ground through the leg on top of the
/// wrench's `m g`: quad16 under VMC then stands 9 mm high, pitched 0.028 rad
/// and 11 mm back; with them, within 5 µm and 1e-4 rad.
#[inline] // one caller per tick (the walker): its feet loop fused there
pub fn stance_torques(
    model: &Model,
    data: &mut Data,
    feet: &[(usize, DVec3)],
    forces: &[DVec3],
    tau_joints: &mut [f64],
) {
    let (nv, b) = (model.nv, model.base_nv());
    debug_assert_eq!(tau_joints.len(), nv - b);
    tau_joints.fill(0.0);
    for (&(body, point), f) in feet.iter().zip(forces) {
        // A foot without force (swinging, unloaded) would subtract only
        // zeros from torques that are never −0: nothing to sum (finite
        // kinematics).
        if *f == DVec3::ZERO {
            continue;
        }
        // `point_jacobian`'s nonzero joint columns, in its arithmetic
        let r = point - data.origin;
        let mut j = body;
        while j != NO_PARENT {
            if !matches!(model.joint_type[j], JointType::Free | JointType::Anchored) {
                let c = data.subspace(model, j).point_velocity(r);
                tau_joints[model.idx_v[j] - b] -= c.x * f.x + c.y * f.y + c.z * f.z;
            }
            j = model.parent[j];
        }
    }
    for (t, lim) in tau_joints.iter_mut().zip(&model.effort_limit[b..]) {
        *t = t.clamp(-lim, *lim);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`all_valid`] answers as [`first_error`] does, on valid inputs and
    /// with each field in turn set to a boundary or an invalid value: a check
    /// added to one but not the other fails here.
    #[test]
    fn all_valid_is_first_error_ok() {
        let params = ForceQpParams::default();
        let foot = |x: f64| StanceFoot {
            position_m: DVec3::new(x, 0.1, -0.4),
            normal: DVec3::Z,
            friction: 0.6,
            load: 1.0,
        };
        let feet = [foot(0.3), foot(-0.3), foot(0.2), foot(-0.2)];
        let wrench = Force::new(DVec3::new(0.0, 0.0, 270.0), DVec3::ZERO);
        let values = [
            0.0,
            -0.0,
            1.0,
            0.5,
            -1e-300,
            -1.0,
            1.5,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut cases = vec![(params, feet.to_vec(), wrench)];
        for &x in &values {
            for k in 0..6 {
                let mut p = params;
                p.wrench_weight[k] = x;
                cases.push((p, feet.to_vec(), wrench));
            }
            for set in [
                |p: &mut ForceQpParams, x| p.regularization = x,
                |p: &mut ForceQpParams, x| p.min_normal_force_n = x,
                |p: &mut ForceQpParams, x| p.max_normal_force_n = x,
            ] {
                let mut p = params;
                set(&mut p, x);
                cases.push((p, feet.to_vec(), wrench));
            }
            for set in [
                |f: &mut StanceFoot, x| f.position_m.y = x,
                |f: &mut StanceFoot, x| f.normal = DVec3::new(0.0, 0.0, x),
                |f: &mut StanceFoot, x| f.friction = x,
                |f: &mut StanceFoot, x| f.load = x,
            ] {
                let mut f = feet.to_vec();
                set(&mut f[2], x);
                cases.push((params, f, wrench));
            }
            let mut w = wrench;
            w.ang.x = x;
            cases.push((params, feet.to_vec(), w));
        }
        let mut five = feet.to_vec();
        five.push(foot(0.0));
        cases.push((params, five, wrench));
        let mut failing = 0;
        for (p, f, w) in &cases {
            let ok = first_error(p, f, w).is_ok();
            assert_eq!(all_valid(p, f, w), ok, "{p:?} {f:?} {w:?}");
            failing += usize::from(!ok);
        }
        // the cases reach both answers, most of them errors
        assert!(failing > cases.len() / 2, "{failing} of {}", cases.len());
    }
}
