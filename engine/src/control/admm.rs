//! A dense QP solver by the alternating direction method of multipliers,
//! in the form of OSQP (Stellato, Banjac, Goulart, Bemporad and Boyd, Math.
//! Prog. Comp. 12, 2020, Algorithm 1), for the MPC's condensed problem:
//!
//! `min ½ xᵀ P x + qᵀ x` subject to `C x ≤ d`,
//!
//! `P` symmetric positive definite (dense), `C` sparse by rows. One
//! iteration, with step `ρ`, regularisation `σ` and relaxation `α`:
//!
//! ```text
//! (P + σI + ρCᵀC) x̃ = σx − q + Cᵀ(ρz − y)      one Cholesky factor per ρ
//! z̃ = C x̃
//! x ← α x̃ + (1 − α) x
//! z⁺ = min(α z̃ + (1 − α) z + y/ρ, d)          projection on z ≤ d
//! y ← y + ρ(α z̃ + (1 − α) z − z⁺),  z ← z⁺
//! ```
//!
//! It stops when the primal residual `‖Cx − z‖∞` and the dual residual
//! `‖Px + q + Cᵀy‖∞` are below their tolerances, and adapts `ρ` to their
//! ratio (OSQP's rule) every [`AdmmSettings::adapt_every`] iterations. The
//! last solution stays in the workspace: a solve of a problem of the same
//! shape starts from it (warm start), which an interior-point method cannot.
//! `engine/tests/mpc.rs` checks it against `clarabel`.

/// Tolerances and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdmmSettings {
    /// Absolute tolerance of both residuals (the problem's units).
    pub eps_abs: f64,
    /// Relative tolerance of both residuals.
    pub eps_rel: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Relaxation α in (0, 2).
    pub alpha: f64,
    /// Iterations between adaptations of ρ (0: never; a multiple of
    /// `check_every`).
    pub adapt_every: usize,
    /// Iterations between residual checks.
    pub check_every: usize,
}

impl Default for AdmmSettings {
    fn default() -> Self {
        AdmmSettings {
            eps_abs: 1e-4,
            eps_rel: 1e-5,
            max_iterations: 4000,
            alpha: 1.6,
            adapt_every: 25,
            check_every: 5,
        }
    }
}

/// Why a solve failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum AdmmError {
    /// The system matrix was not positive definite.
    #[error("ADMM: the system matrix is not positive definite")]
    NotPositiveDefinite,
    /// The iteration limit was reached.
    #[error("ADMM: no convergence within the iteration limit")]
    NoConvergence,
}

/// `C` by rows (`row_start`, `cols`, `vals`).
#[derive(Clone, Copy)]
struct Rows<'a> {
    row_start: &'a [usize],
    cols: &'a [usize],
    vals: &'a [f64],
}

impl Rows<'_> {
    /// `out = C x`.
    fn times(&self, x: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in self.row_start[i]..self.row_start[i + 1] {
                s += self.vals[k] * x[self.cols[k]];
            }
            *o = s;
        }
    }

    /// `out += Cᵀ w`.
    fn transpose_times_add(&self, w: &[f64], out: &mut [f64]) {
        for (i, &wi) in w.iter().enumerate() {
            for k in self.row_start[i]..self.row_start[i + 1] {
                out[self.cols[k]] += self.vals[k] * wi;
            }
        }
    }
}

/// A problem `min ½ xᵀPx + qᵀx, Cx ≤ d` and the solver's workspace (all
/// buffers reused between solves).
#[derive(Clone, Debug, Default)]
pub struct Admm {
    /// Settings.
    pub settings: AdmmSettings,
    /// Variables.
    n: usize,
    /// Constraints.
    m: usize,
    /// `C` by rows: entries `row_start[i]..row_start[i+1]` of `cols`, `vals`.
    row_start: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
    d: Vec<f64>,
    /// Iterates.
    x: Vec<f64>,
    z: Vec<f64>,
    y: Vec<f64>,
    /// Scratch.
    rhs: Vec<f64>,
    zt: Vec<f64>,
    cx: Vec<f64>,
    px: Vec<f64>,
    cty: Vec<f64>,
    /// Cholesky factor (lower, row-major n × n) of `P + σI + ρCᵀC`.
    l: Vec<f64>,
    /// Step of the last solve.
    rho: f64,
    /// Iterations of the last solve.
    pub iterations: usize,
    /// Whether the iterates belong to a problem of the current shape.
    warm: bool,
}

impl Admm {
    /// An empty workspace.
    pub fn new(settings: AdmmSettings) -> Self {
        Admm {
            settings,
            ..Default::default()
        }
    }

    /// Starts a problem of `n` variables (constraint rows follow through
    /// [`Self::push_row`]); keeps the last iterates as the warm start when
    /// `same_shape` and the sizes match.
    pub fn begin(&mut self, n: usize, same_shape: bool) {
        self.warm = same_shape && self.n == n && self.warm;
        self.n = n;
        self.m = 0;
        self.row_start.clear();
        self.row_start.push(0);
        self.cols.clear();
        self.vals.clear();
        self.d.clear();
    }

    /// Adds the constraint `Σ vals·x[cols] ≤ bound`.
    pub fn push_row(&mut self, entries: &[(usize, f64)], bound: f64) {
        for &(c, v) in entries {
            self.cols.push(c);
            self.vals.push(v);
        }
        self.row_start.push(self.cols.len());
        self.d.push(bound);
        self.m += 1;
    }

    /// Factors `P + σI + ρCᵀC` (P row-major, only its upper triangle read).
    fn factor(&mut self, p: &[f64], sigma: f64, rho: f64) -> Result<(), AdmmError> {
        let n = self.n;
        self.l.clear();
        self.l.resize(n * n, 0.0);
        for i in 0..n {
            for j in i..n {
                let v = p[i * n + j];
                self.l[j * n + i] = v;
            }
            self.l[i * n + i] += sigma;
        }
        for r in 0..self.m {
            let (a, b) = (self.row_start[r], self.row_start[r + 1]);
            for k1 in a..b {
                for k2 in a..b {
                    let (i, j) = (self.cols[k1], self.cols[k2]);
                    if i >= j {
                        self.l[i * n + j] += rho * self.vals[k1] * self.vals[k2];
                    }
                }
            }
        }
        // in-place Cholesky, lower triangle
        for j in 0..n {
            let mut s = self.l[j * n + j];
            for k in 0..j {
                s -= self.l[j * n + k] * self.l[j * n + k];
            }
            if s <= 0.0 || !s.is_finite() {
                return Err(AdmmError::NotPositiveDefinite);
            }
            let djj = s.sqrt();
            self.l[j * n + j] = djj;
            for i in j + 1..n {
                let mut s = self.l[i * n + j];
                for k in 0..j {
                    s -= self.l[i * n + k] * self.l[j * n + k];
                }
                self.l[i * n + j] = s / djj;
            }
        }
        Ok(())
    }

    /// Solves with Hessian `p` (row-major n × n, symmetric) and linear term
    /// `q`; returns the solution.
    pub fn solve(&mut self, p: &[f64], q: &[f64]) -> Result<&[f64], AdmmError> {
        let (n, m) = (self.n, self.m);
        let st = self.settings;
        if !self.warm {
            self.x.clear();
            self.x.resize(n, 0.0);
            self.z.clear();
            self.z.resize(m, 0.0);
            self.y.clear();
            self.y.resize(m, 0.0);
            let mean_diag = (0..n).map(|i| p[i * n + i]).sum::<f64>() / n.max(1) as f64;
            self.rho = if mean_diag > 0.0 { mean_diag } else { 1.0 };
        }
        for v in [&mut self.rhs, &mut self.px, &mut self.cty] {
            v.clear();
            v.resize(n, 0.0);
        }
        for v in [&mut self.zt, &mut self.cx] {
            v.clear();
            v.resize(m, 0.0);
        }
        let mut rho = self.rho;
        let sigma = 1e-6 * rho;
        self.factor(p, sigma, rho)?;
        for it in 1..=st.max_iterations {
            let rows = Rows {
                row_start: &self.row_start,
                cols: &self.cols,
                vals: &self.vals,
            };
            // x̃ = (P + σI + ρCᵀC)⁻¹ (σx − q + Cᵀ(ρz − y))
            for i in 0..n {
                self.rhs[i] = sigma * self.x[i] - q[i];
            }
            for i in 0..m {
                self.zt[i] = rho * self.z[i] - self.y[i];
            }
            rows.transpose_times_add(&self.zt, &mut self.rhs);
            back_substitute(&self.l, n, &mut self.rhs);
            // z̃ = C x̃, then the relaxed updates
            rows.times(&self.rhs, &mut self.zt);
            let a = st.alpha;
            for i in 0..n {
                self.x[i] = a * self.rhs[i] + (1.0 - a) * self.x[i];
            }
            for i in 0..m {
                let zr = a * self.zt[i] + (1.0 - a) * self.z[i];
                let zn = (zr + self.y[i] / rho).min(self.d[i]);
                self.y[i] += rho * (zr - zn);
                self.z[i] = zn;
            }
            // residuals, every `check_every` iterations
            if it % st.check_every.max(1) != 0 && it < st.max_iterations {
                continue;
            }
            rows.times(&self.x, &mut self.cx);
            let (mut r_prim, mut n_cx, mut n_z) = (0.0f64, 0.0f64, 0.0f64);
            for i in 0..m {
                r_prim = r_prim.max((self.cx[i] - self.z[i]).abs());
                n_cx = n_cx.max(self.cx[i].abs());
                n_z = n_z.max(self.z[i].abs());
            }
            for i in 0..n {
                let mut s = 0.0;
                for j in 0..n {
                    s += p[i * n + j] * self.x[j];
                }
                self.px[i] = s;
                self.cty[i] = 0.0;
            }
            rows.transpose_times_add(&self.y, &mut self.cty);
            let (mut r_dual, mut n_px, mut n_cty, mut n_q) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for i in 0..n {
                r_dual = r_dual.max((self.px[i] + q[i] + self.cty[i]).abs());
                n_px = n_px.max(self.px[i].abs());
                n_cty = n_cty.max(self.cty[i].abs());
                n_q = n_q.max(q[i].abs());
            }
            let scale_p = n_cx.max(n_z);
            let scale_d = n_px.max(n_cty).max(n_q);
            let eps_p = st.eps_abs + st.eps_rel * scale_p;
            let eps_d = st.eps_abs * 1e-3 + st.eps_rel * scale_d;
            if r_prim <= eps_p && r_dual <= eps_d {
                self.iterations = it;
                self.rho = rho;
                self.warm = true;
                return Ok(&self.x);
            }
            if st.adapt_every > 0 && it % st.adapt_every == 0 {
                let sp = r_prim / scale_p.max(1e-30);
                let sd = r_dual / scale_d.max(1e-30);
                let ratio = (sp / sd.max(1e-30)).sqrt();
                if !(0.2..=5.0).contains(&ratio) {
                    rho = (rho * ratio).clamp(1e-12, 1e12);
                    self.factor(p, sigma, rho)?;
                }
            }
        }
        self.iterations = st.max_iterations;
        self.warm = false;
        Err(AdmmError::NoConvergence)
    }
}

/// Solves `L Lᵀ x = b` in place (`l` lower, row-major n × n).
fn back_substitute(l: &[f64], n: usize, x: &mut [f64]) {
    for i in 0..n {
        let mut s = x[i];
        for k in 0..i {
            s -= l[i * n + k] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in i + 1..n {
            s -= l[k * n + i] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
}
