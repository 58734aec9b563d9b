//! A small dense strictly convex QP solver: Goldfarb and Idnani's dual
//! active-set method (Goldfarb & Idnani 1983, "A numerically stable dual
//! method for solving strictly convex quadratic programs", Math. Prog. 27),
//! in the product form of QuadProg/QuadProg++ (`J = L⁻ᵀ Q`, active set kept as
//! the upper triangle `R` of `Q ᵀ L⁻¹ N`, updated by Givens rotations).
//!
//! Problem: minimise `½ xᵀ H x + gᵀ x` subject to `cᵢᵀ x ≥ bᵢ` (i < m), with
//! `H` symmetric positive definite. The dual method starts at the
//! unconstrained minimum and adds the most violated constraint until every
//! one holds; there is no phase 1 and no feasible start is needed.
//!
//! Sizes are fixed at compile time ([`MAX_VARS`], [`MAX_CONSTRAINTS`]): the
//! solver lives on the stack and allocates nothing. It exists for the
//! stance-force QP of [`super::force_qp`] (3 variables and 6 constraints per
//! foot, up to 4 feet), where it is checked against `clarabel`.

use multiversion::multiversion;

/// Most variables a problem may have.
pub const MAX_VARS: usize = 12;
/// Most inequality constraints a problem may have.
pub const MAX_CONSTRAINTS: usize = 24;

/// Feet (blocks of three variables) of a [`DenseQp::foot_blocks`] problem.
const FOOT_LANES: usize = MAX_VARS / 3;

/// Why a solve failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ActiveSetError {
    /// `H` is not positive definite (its Cholesky factorisation broke down).
    #[error("the QP's Hessian is not positive definite")]
    NotPositiveDefinite,
    /// The constraints admit no point.
    #[error("the QP's constraints are infeasible")]
    Infeasible,
    /// The iteration limit was reached (cycling from round-off).
    #[error("the active-set iteration did not converge")]
    NoConvergence,
}

/// A QP of `n ≤ MAX_VARS` variables and `m ≤ MAX_CONSTRAINTS` constraints,
/// written by the caller into the public arrays (only the leading `n × n`,
/// `n`, `m × n` and `m` entries are read).
#[derive(Clone, Debug)]
pub struct DenseQp {
    /// Number of variables.
    pub n: usize,
    /// Number of constraints.
    pub m: usize,
    /// Hessian `H` (row-major, symmetric positive definite).
    pub h: [[f64; MAX_VARS]; MAX_VARS],
    /// Linear term `g`.
    pub g: [f64; MAX_VARS],
    /// Constraint rows `cᵢ` of `cᵢᵀ x ≥ bᵢ`.
    pub c: [[f64; MAX_VARS]; MAX_CONSTRAINTS],
    /// Constraint bounds `bᵢ`.
    pub b: [f64; MAX_CONSTRAINTS],
    /// Whether row `i` of `C` is zero outside columns `3⌊i/6⌋..3⌊i/6⌋+3`
    /// (the stance-force QP's shape: six constraints on each foot's force).
    /// Products with a row are then summed over those columns, and over all
    /// `n` only when that sum is zero (see `row_dot`): the same bits.
    pub foot_blocks: bool,
    /// A constraint counts as violated only below `bᵢ − tolerance` (absolute,
    /// in the constraint's units): round-off must not make the method chase
    /// a constraint that holds.
    pub tolerance: f64,
}

impl Default for DenseQp {
    fn default() -> Self {
        DenseQp {
            n: 0,
            m: 0,
            h: [[0.0; MAX_VARS]; MAX_VARS],
            g: [0.0; MAX_VARS],
            c: [[0.0; MAX_VARS]; MAX_CONSTRAINTS],
            b: [0.0; MAX_CONSTRAINTS],
            foot_blocks: false,
            tolerance: 1e-10,
        }
    }
}

/// The solver's workspace (all on the stack, reused between solves).
///
/// `L` and `J` are stored by columns (`lc[p][i] = L[i][p]`, `jt[k][i] =
/// J[i][k]`): the factorisation's updates, the Givens rotations (which mix
/// two columns of `J`) and `z = J₂ d₂` then run along contiguous rows, where
/// the compiler packs independent lanes into SIMD registers.
#[derive(Clone, Debug)]
pub struct ActiveSet {
    /// Lower Cholesky factor of `H`, by columns: `lc[p][i] = L[i][p]` (`i ≥ p`;
    /// the other entries are stale and never read for a result).
    lc: [[f64; MAX_VARS]; MAX_VARS],
    /// `Jᵀ` with `J = L⁻ᵀ Q`: row `k` is column `k` of `J` (columns `0..iq`
    /// span the active constraints' image).
    jt: [[f64; MAX_VARS]; MAX_VARS],
    /// Upper-triangular `R` (first `iq` columns used).
    r: [[f64; MAX_VARS]; MAX_VARS],
    /// Active constraint indices, in order of addition (`iq` of them).
    active: [usize; MAX_VARS + 1],
    /// Lagrange multipliers of the active constraints (and the one being added at `iq`).
    u: [f64; MAX_VARS + 1],
    /// Whether each constraint is in the active set or was found linearly
    /// dependent on it this solve (either way not a candidate to add).
    blocked: [bool; MAX_CONSTRAINTS],
    /// Solution.
    x: [f64; MAX_VARS],
    /// Under [`DenseQp::foot_blocks`] with six rows per block of three
    /// variables (the stance-force QP): `foot_rows[j][c][a] = C[6a + j][3a + c]`,
    /// each foot's rows in a SIMD lane (zero past the last foot), filled at
    /// the start of a solve; step 1 then evaluates all constraints a row of
    /// every foot at a time.
    foot_rows: [[[f64; FOOT_LANES]; 3]; 6],
    /// Active-set size.
    iq: usize,
    /// Iterations of the last solve (constraint additions and drops).
    pub iterations: usize,
}

impl Default for ActiveSet {
    fn default() -> Self {
        ActiveSet {
            lc: [[0.0; MAX_VARS]; MAX_VARS],
            jt: [[0.0; MAX_VARS]; MAX_VARS],
            r: [[0.0; MAX_VARS]; MAX_VARS],
            active: [0; MAX_VARS + 1],
            u: [0.0; MAX_VARS + 1],
            blocked: [false; MAX_CONSTRAINTS],
            x: [0.0; MAX_VARS],
            foot_rows: [[[0.0; FOOT_LANES]; 3]; 6],
            iq: 0,
            iterations: 0,
        }
    }
}

impl ActiveSet {
    /// Solves `qp`; on success the first `qp.n` entries of the returned slice
    /// are the minimiser.
    ///
    /// # Errors
    /// [`ActiveSetError`] when `H` is not positive definite, the constraints
    /// are infeasible, or the iteration limit is hit.
    ///
    /// # Panics
    /// When `qp.n > MAX_VARS` or `qp.m > MAX_CONSTRAINTS`.
    pub fn solve(&mut self, qp: &DenseQp) -> Result<&[f64], ActiveSetError> {
        let (n, m) = (qp.n, qp.m);
        assert!(n <= MAX_VARS && m <= MAX_CONSTRAINTS, "QP too large");
        self.iterations = 0;
        if n == 0 {
            return Ok(&self.x[..0]);
        }
        solve_dispatch(self, qp)?;
        Ok(&self.x[..n])
    }

    /// [`Self::solve`] for `N` variables and `M` constraints (`0`: `qp.n`,
    /// `qp.m`).
    #[inline(always)]
    fn solve_sized<const N: usize, const M: usize>(
        &mut self,
        qp: &DenseQp,
    ) -> Result<(), ActiveSetError> {
        let n = size::<N>(qp.n);
        let m = size::<M>(qp.m);
        self.factor::<N>(qp)?;
        // Unconstrained minimum x = −H⁻¹ g = −J Jᵀ g (J = L⁻ᵀ, upper triangular):
        // jtg[k] = Σ_{i≤k} J[i][k] g[i], then x[i] = −Σ_{k≥i} J[i][k] jtg[k],
        // the latter summed along the rows of Jᵀ (each x[i] its own sum from
        // −0.0, over k in ascending order).
        let mut jtg = [0.0; MAX_VARS];
        for k in 0..n {
            jtg[k] = dot(&self.jt[k][..=k], &qp.g[..=k]);
        }
        let mut xs = [-0.0; MAX_VARS];
        for k in 0..n {
            let (col, w) = (&self.jt[k][..=k], jtg[k]);
            for (acc, &j) in xs.iter_mut().zip(col) {
                *acc += j * w;
            }
        }
        for (x, acc) in self.x[..n].iter_mut().zip(&xs) {
            *x = -*acc;
        }
        self.iq = 0;
        self.blocked[..m].fill(false);
        let feet = qp.foot_blocks && n.is_multiple_of(3) && m == 2 * n;
        if feet {
            self.fill_foot_rows(qp, n / 3);
        }
        let mut r_norm = 1.0f64;
        let max_iter = 20 * (n + m);
        let (mut d, mut rr) = ([0.0; MAX_VARS], [0.0; MAX_VARS + 1]);
        'outer: loop {
            // Step 1: the most violated constraint (values `cᵢᵀ x − bᵢ` of
            // those that may be added).
            let mut worst = -qp.tolerance;
            let mut candidate = None;
            // constraint `i` (not blocked) with value `s`: the new candidate
            // when more violated than every one before it (the first of equals)
            let mut consider = |i: usize, s: f64| {
                if s < worst {
                    worst = s;
                    candidate = Some(i);
                }
            };
            if feet {
                let sums = self.foot_row_dots(n / 3);
                for a in 0..n / 3 {
                    for (j, s) in sums.iter().enumerate() {
                        let i = 6 * a + j;
                        if !self.blocked[i] {
                            // `row_dot`'s three-term sum; its other columns only for −0
                            let s = if s[a].to_bits() == (-0.0f64).to_bits() {
                                row_dot(qp, i, n, &self.x)
                            } else {
                                s[a]
                            } - qp.b[i];
                            consider(i, s);
                        }
                    }
                }
            } else {
                for i in 0..m {
                    if !self.blocked[i] {
                        consider(i, row_dot(qp, i, n, &self.x) - qp.b[i]);
                    }
                }
            }
            let Some(p) = candidate else {
                return Ok(());
            };
            // its value, updated after partial steps
            let mut s_p = worst;
            self.u[self.iq] = 0.0;
            self.active[self.iq] = p;
            loop {
                self.iterations += 1;
                if self.iterations > max_iter {
                    return Err(ActiveSetError::NoConvergence);
                }
                // Step 2a: d = Jᵀ n_p; primal direction z = J₂ d₂; dual r = R⁻¹ d₁.
                let iq = self.iq;
                for k in 0..n {
                    d[k] = row_dot(qp, p, n, &self.jt[k]);
                }
                // z[i] = Σ_{k≥iq} J[i][k] d[k], summed along the rows of Jᵀ
                let mut z = [-0.0; MAX_VARS];
                for k in iq..n {
                    let (col, w) = (&self.jt[k][..n], d[k]);
                    for (acc, &j) in z.iter_mut().zip(col) {
                        *acc += j * w;
                    }
                }
                let (z_all, z) = (&z, &z[..n]);
                for i in (0..iq).rev() {
                    let mut sum = d[i];
                    for k in i + 1..iq {
                        sum -= self.r[i][k] * rr[k];
                    }
                    rr[i] = sum / self.r[i][i];
                }
                // Step 2b: partial (dual) step t1, full (primal) step t2.
                let mut t1 = f64::INFINITY;
                let mut drop = None;
                for k in 0..iq {
                    if rr[k] > 0.0 && self.u[k] / rr[k] < t1 {
                        t1 = self.u[k] / rr[k];
                        drop = Some(self.active[k]);
                    }
                }
                let znp = row_dot(qp, p, n, z_all);
                let t2 = if dot(z, z) > f64::EPSILON * f64::EPSILON {
                    -s_p / znp
                } else {
                    f64::INFINITY
                };
                let t = t1.min(t2);
                if !t.is_finite() {
                    return Err(ActiveSetError::Infeasible);
                }
                if !t2.is_finite() {
                    // Dual step only: the constraint to drop is `drop` (t1 finite).
                    for k in 0..iq {
                        self.u[k] -= t * rr[k];
                    }
                    self.u[iq] += t;
                    self.delete_constraint::<N>(n, drop.expect("t1 finite"));
                    continue;
                }
                for (x, &zi) in self.x[..n].iter_mut().zip(z) {
                    *x += t * zi;
                }
                for k in 0..iq {
                    self.u[k] -= t * rr[k];
                }
                self.u[iq] += t;
                if t2 <= t1 {
                    // Full step: p joins the active set.
                    if self.add_constraint::<N>(n, &mut d, &mut r_norm) {
                        self.blocked[p] = true;
                    } else {
                        // Linearly dependent on the active set within round-off:
                        // take it out again and leave it out for this solve.
                        self.delete_constraint::<N>(n, p);
                        self.blocked[p] = true;
                    }
                    continue 'outer;
                }
                // Partial step: drop the blocking constraint and retry p.
                self.delete_constraint::<N>(n, drop.expect("t1 finite"));
                s_p = row_dot(qp, p, n, &self.x) - qp.b[p];
            }
        }
    }

    /// Fills [`Self::foot_rows`] from `qp`'s rows (`feet` blocks).
    #[inline(always)]
    fn fill_foot_rows(&mut self, qp: &DenseQp, feet: usize) {
        for (j, rows) in self.foot_rows.iter_mut().enumerate() {
            for (c, lanes) in rows.iter_mut().enumerate() {
                for (a, v) in lanes.iter_mut().enumerate() {
                    *v = if a < feet {
                        qp.c[6 * a + j][3 * a + c]
                    } else {
                        0.0
                    };
                }
            }
        }
    }

    /// `row_dot`'s three-term sums `−0 + Σ_c C[6a+j][3a+c] x[3a+c]` (in `c`
    /// order) of every row, as `[j][a]`: the same operations, four feet to a
    /// register.
    #[inline(always)]
    fn foot_row_dots(&self, feet: usize) -> [[f64; FOOT_LANES]; 6] {
        let mut xs = [[0.0; FOOT_LANES]; 3];
        for a in 0..feet {
            for (c, lanes) in xs.iter_mut().enumerate() {
                lanes[a] = self.x[3 * a + c];
            }
        }
        let mut sums = [[-0.0; FOOT_LANES]; 6];
        for (s, row) in sums.iter_mut().zip(&self.foot_rows) {
            for (coef, x) in row.iter().zip(&xs) {
                for a in 0..FOOT_LANES {
                    s[a] += coef[a] * x[a];
                }
            }
        }
        sums
    }

    /// Cholesky `H = L Lᵀ` and `J = L⁻ᵀ` (upper triangular), a row of `L`
    /// and of `L⁻¹` (a column of `J`) at a time.
    ///
    /// Row `i`: `L[i][k] = (H[i][k] − Σ_{p<k} L[i][p] L[k][p]) / L[k][k]` and
    /// `L⁻¹[i][c] = (δᵢ꜀ − Σ_{c≤p<i} L[i][p] L⁻¹[p][c]) / L[i][i]`, each sum
    /// in ascending `p`. Both are accumulated along the row, a step `p` at a
    /// time over all lanes: the lanes `k ≤ p` of the first are spent and those
    /// past `i` unused, and in the second the lanes `c > p` see
    /// `L⁻¹[p][c] = +0`, which leaves their `+0` or `1` unchanged (`L[i][p]`
    /// is finite whenever the factorisation succeeds: otherwise the diagonal
    /// is not finite).
    ///
    /// Two rows at a time ([`Self::factor_rows`]): a row's steps form one
    /// dependent chain through a division each (`L[i][p+1]` waits for the
    /// update by `L[i][p]`), and two rows' chains side by side let the CPU
    /// overlap them. Each row's operations are the one-row form's, in its
    /// order: the same bits.
    #[inline(always)]
    fn factor<const N: usize>(&mut self, qp: &DenseQp) -> Result<(), ActiveSetError> {
        let n = size::<N>(qp.n);
        let mut i = 0;
        while i + 1 < n {
            self.factor_rows::<N, 2>(qp, i)?;
            i += 2;
        }
        if i < n {
            self.factor_rows::<N, 1>(qp, i)?;
        }
        for row in self.r.iter_mut().take(n) {
            row[..n].fill(0.0);
        }
        Ok(())
    }

    /// Rows `i .. i + R` of `L` and of `J` ([`Self::factor`]): their steps
    /// `p < i` side by side (on rows already finished, independent of one
    /// another), then each row in turn its steps on the rows just finished
    /// and its diagonal. A step of a row writes `L[i + r][p]` into `lc[p]`,
    /// whose lane `i + r` the other row's update then reads: a lane past
    /// that row's own, never read for a result (as in the one-row form).
    #[inline(always)]
    fn factor_rows<const N: usize, const R: usize>(
        &mut self,
        qp: &DenseQp,
        i: usize,
    ) -> Result<(), ActiveSetError> {
        let n = size::<N>(qp.n);
        let mut acc = [[0.0; MAX_VARS]; R];
        let mut inv = [[0.0; MAX_VARS]; R];
        for r in 0..R {
            acc[r][..n].copy_from_slice(&qp.h[i + r][..n]);
            inv[r][i + r] = 1.0;
        }
        for p in 0..i {
            let lip: [f64; R] = std::array::from_fn(|r| acc[r][p] / self.lc[p][p]);
            self.lc[p][i..i + R].copy_from_slice(&lip);
            for r in 0..R {
                self.factor_step(n, p, lip[r], &mut acc[r], &mut inv[r]);
            }
        }
        for r in 0..R {
            for p in i..i + r {
                let lip = acc[r][p] / self.lc[p][p];
                self.lc[p][i + r] = lip;
                self.factor_step(n, p, lip, &mut acc[r], &mut inv[r]);
            }
            let row = i + r;
            let sum = acc[r][row];
            if sum <= 0.0 || !sum.is_finite() {
                return Err(ActiveSetError::NotPositiveDefinite);
            }
            let lii = sum.sqrt();
            self.lc[row][row] = lii;
            let out = &mut self.jt[row][..n];
            for (c, (j, &v)) in out.iter_mut().zip(&inv[r]).enumerate() {
                *j = if c <= row { v / lii } else { 0.0 };
            }
        }
        Ok(())
    }

    /// One step `p` of a row of the factor (`lip = L[row][p]`): the row's
    /// sums of `L` and of `L⁻¹` each less `lip` times row `p`.
    #[inline(always)]
    fn factor_step(
        &self,
        n: usize,
        p: usize,
        lip: f64,
        acc: &mut [f64; MAX_VARS],
        inv: &mut [f64; MAX_VARS],
    ) {
        for (a, &l) in acc[..n].iter_mut().zip(&self.lc[p][..n]) {
            *a -= lip * l;
        }
        for (v, &j) in inv[..n].iter_mut().zip(&self.jt[p][..n]) {
            *v -= lip * j;
        }
    }

    /// Adds the constraint with `d = Jᵀ n_p`: Givens rotations zero `d[iq+1..]`
    /// (applied to J's columns), then `d[..=iq]` becomes R's new column.
    /// Returns false when the constraint is linearly dependent on the active set.
    #[inline(always)]
    fn add_constraint<const N: usize>(
        &mut self,
        n: usize,
        d: &mut [f64; MAX_VARS],
        r_norm: &mut f64,
    ) -> bool {
        let n = size::<N>(n);
        let iq = self.iq;
        for jj in (iq + 1..n).rev() {
            let Some((g, h)) = Givens::zeroing(d[jj - 1], d[jj]) else {
                continue;
            };
            (d[jj - 1], d[jj]) = (h, 0.0);
            let (head, tail) = self.jt.split_at_mut(jj);
            g.apply(&mut head[jj - 1][..n], &mut tail[0][..n]);
        }
        self.iq += 1;
        for i in 0..self.iq {
            self.r[i][iq] = d[i];
        }
        if d[iq].abs() <= f64::EPSILON * *r_norm {
            return false;
        }
        *r_norm = r_norm.max(d[iq].abs());
        true
    }

    /// Removes active constraint `l` (its multiplier and R column) and
    /// restores R's triangle with Givens rotations (applied to J's columns).
    #[inline(always)]
    fn delete_constraint<const N: usize>(&mut self, n: usize, l: usize) {
        let n = size::<N>(n);
        let iq = self.iq;
        let qq = (0..iq).find(|&i| self.active[i] == l).expect("l is active");
        self.blocked[l] = false;
        for i in qq..iq - 1 {
            self.active[i] = self.active[i + 1];
            self.u[i] = self.u[i + 1];
            for jj in 0..n {
                self.r[jj][i] = self.r[jj][i + 1];
            }
        }
        self.active[iq - 1] = self.active[iq];
        self.u[iq - 1] = self.u[iq];
        self.active[iq] = 0;
        self.u[iq] = 0.0;
        for jj in 0..iq {
            self.r[jj][iq - 1] = 0.0;
        }
        self.iq -= 1;
        let iq = self.iq;
        if iq == 0 {
            return;
        }
        for jj in qq..iq {
            let Some((g, h)) = Givens::zeroing(self.r[jj][jj], self.r[jj + 1][jj]) else {
                continue;
            };
            (self.r[jj][jj], self.r[jj + 1][jj]) = (h, 0.0);
            let (head, tail) = self.r.split_at_mut(jj + 1);
            g.apply(&mut head[jj][jj + 1..iq], &mut tail[0][jj + 1..iq]);
            let (head, tail) = self.jt.split_at_mut(jj + 1);
            g.apply(&mut head[jj][..n], &mut tail[0][..n]);
        }
    }
}

/// A Givens rotation in QuadProg++'s form: `c`, `s` and `xny = s / (1 + c)`,
/// with `c ≥ 0`.
#[derive(Clone, Copy)]
struct Givens {
    c: f64,
    s: f64,
    xny: f64,
}

impl Givens {
    /// The rotation taking `(a, b)` to `(h, 0)`, and `h` (`±|(a, b)|`, the
    /// sign making `c ≥ 0`); `None` when both are zero (nothing to rotate).
    #[inline(always)]
    fn zeroing(a: f64, b: f64) -> Option<(Givens, f64)> {
        let h = crate::linalg::hypot(a, b);
        if h == 0.0 {
            return None;
        }
        let (c, s) = (a / h, b / h);
        let (c, s, h) = if c < 0.0 { (-c, -s, -h) } else { (c, s, h) };
        Some((
            Givens {
                c,
                s,
                xny: s / (1.0 + c),
            },
            h,
        ))
    }

    /// Rotates the pairs `(x[k], y[k])`: `x' = c x + s y`, `y' = xny (x + x') − y`
    /// (QuadProg++'s update, one product fewer than `s x − c y`).
    #[inline(always)]
    fn apply(self, x: &mut [f64], y: &mut [f64]) {
        for (xk, yk) in x.iter_mut().zip(y.iter_mut()) {
            let (t1, t2) = (*xk, *yk);
            *xk = t1 * self.c + t2 * self.s;
            *yk = self.xny * (t1 + *xk) - t2;
        }
    }
}

/// [`ActiveSet::solve`] past its checks, compiled for x86-64-v3 (AVX2, FMA)
/// and the generic target with the CPU's choice at the first call; the same
/// bits either way (Rust never fuses `a * b + c`: the wider target packs
/// independent lanes, four to a register).
///
/// The stance-force QP's shapes (3 variables and 6 constraints per foot)
/// get loops of known length, which the compiler unrolls; the same
/// operations in the same order, so the same bits as any size.
#[multiversion(targets("x86_64+avx2+fma"))]
fn solve_dispatch(s: &mut ActiveSet, qp: &DenseQp) -> Result<(), ActiveSetError> {
    match (qp.n, qp.m) {
        (3, 6) => s.solve_sized::<3, 6>(qp),
        (6, 12) => s.solve_sized::<6, 12>(qp),
        (9, 18) => s.solve_sized::<9, 18>(qp),
        (12, 24) => s.solve_sized::<12, 24>(qp),
        _ => s.solve_sized::<0, 0>(qp),
    }
}

/// A size known at compile time (`N > 0`) or given at run time (`N == 0`):
/// [`ActiveSet::solve`]'s fixed-size paths and its general one share one body.
#[inline(always)]
fn size<const N: usize>(runtime: usize) -> usize {
    if N == 0 { runtime } else { N }
}

/// `Σ_{j<n} c_ij x_j` for constraint row `i` of `qp`: the bits of
/// `dot(&qp.c[i][..n], &x[..n])`. Under [`DenseQp::foot_blocks`] the sum runs
/// over the row's three columns, and over all `n` only when that gives
/// `−0`: before its first nonzero partial sum a sum is a (signed) zero and
/// after it a zero product changes it in no bit, so a nonzero three-term
/// sum is the full one (finite `x`). A `+0` three-term sum is the full one
/// too: it had a `+0` term or a nonzero partial sum that cancelled (exactly
/// `+0`), and from `+0` a sum of zeros stays `+0`; only `−0` (all three
/// terms `−0`) depends on the other columns' zeros' signs. (`x` starts as
/// `J`'s upper triangle, so most rows' three columns are zero at first.)
#[inline(always)]
fn row_dot(qp: &DenseQp, i: usize, n: usize, x: &[f64; MAX_VARS]) -> f64 {
    if qp.foot_blocks {
        let lo = 3 * (i / 6);
        if lo + 3 <= n {
            let (c, y) = (&qp.c[i], x);
            let s = -0.0 + c[lo] * y[lo] + c[lo + 1] * y[lo + 1] + c[lo + 2] * y[lo + 2];
            if s.to_bits() != (-0.0f64).to_bits() {
                return s;
            }
        }
    }
    dot(&qp.c[i][..n], &x[..n])
}

/// `Σ aᵢ bᵢ` in index order from `−0.0` (as `Iterator::sum`).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box-constrained separable QP has the clamped unconstrained minimum.
    #[test]
    fn box_constrained_separable_qp_clamps() {
        let mut qp = DenseQp {
            n: 3,
            m: 6,
            ..DenseQp::default()
        };
        let target = [2.0, -3.0, 0.5];
        for i in 0..3 {
            qp.h[i][i] = 1.0 + i as f64;
            qp.g[i] = -qp.h[i][i] * target[i];
            qp.c[2 * i][i] = 1.0; // x ≥ −1
            qp.b[2 * i] = -1.0;
            qp.c[2 * i + 1][i] = -1.0; // x ≤ 1
            qp.b[2 * i + 1] = -1.0;
        }
        let mut s = ActiveSet::default();
        let x = s.solve(&qp).unwrap();
        for i in 0..3 {
            assert!((x[i] - target[i].clamp(-1.0, 1.0)).abs() < 1e-14, "{x:?}");
        }
    }

    /// Projection of a point onto a half-plane: x = p − (min(0, aᵀp − b)/|a|²) a.
    #[test]
    fn projection_onto_a_half_plane() {
        let mut qp = DenseQp {
            n: 2,
            m: 1,
            ..DenseQp::default()
        };
        let p = [3.0, 1.0];
        let a = [1.0, -2.0];
        qp.h[0][0] = 1.0;
        qp.h[1][1] = 1.0;
        qp.g = [
            -p[0], -p[1], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        ];
        qp.c[0][..2].copy_from_slice(&a);
        qp.b[0] = 4.0;
        let mut s = ActiveSet::default();
        let x = s.solve(&qp).unwrap().to_vec();
        let lam = (qp.b[0] - (a[0] * p[0] + a[1] * p[1])) / 5.0;
        assert!((x[0] - (p[0] + lam * a[0])).abs() < 1e-14);
        assert!((x[1] - (p[1] + lam * a[1])).abs() < 1e-14);
    }

    /// The fixed-size paths of the stance-force QP's shapes give the bits of
    /// the general one, and so do the products over the feet's blocks
    /// ([`DenseQp::foot_blocks`]): random problems of that shape (1 to 4 blocks of 3
    /// variables, 6 constraint rows each over its own block, a dense SPD
    /// Hessian) solved both ways have the same minimiser bits, errors and
    /// iteration counts. The sized solves run in a workspace filled with NaN
    /// first: no result depends on what a previous solve left (the
    /// factorisation's unused lanes included).
    #[test]
    fn sized_paths_give_the_general_bits() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut solved, mut iterations) = (0, 0);
        for trial in 0..2000 {
            let k = 1 + trial % 4;
            let (n, m) = (3 * k, 6 * k);
            let mut qp = DenseQp {
                n,
                m,
                ..DenseQp::default()
            };
            // H = AᵀA + αI with a random 6 × n map A (as the wrench map)
            let a: Vec<[f64; MAX_VARS]> = (0..6)
                .map(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0)))
                .collect();
            let alpha = 10f64.powf(rng.random_range(-4.0..0.0));
            for i in 0..n {
                for j in 0..n {
                    qp.h[i][j] = a.iter().map(|r| r[i] * r[j]).sum::<f64>();
                }
                qp.h[i][i] += alpha;
                qp.g[i] = rng.random_range(-50.0..50.0);
            }
            for f in 0..k {
                for r in 0..6 {
                    for c in 0..3 {
                        qp.c[6 * f + r][3 * f + c] = rng.random_range(-1.0..1.0);
                    }
                    qp.b[6 * f + r] = rng.random_range(-2.0..3.0);
                }
            }
            let (mut sized, mut general) = (ActiveSet::default(), ActiveSet::default());
            let nan = [[f64::NAN; MAX_VARS]; MAX_VARS];
            (sized.lc, sized.jt, sized.r) = (nan, nan, nan);
            (sized.u, sized.x) = ([f64::NAN; MAX_VARS + 1], [f64::NAN; MAX_VARS]);
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let r1 = sized.solve(&qp).map(bits);
            let r2 = general
                .solve_sized::<0, 0>(&qp)
                .map(|()| bits(&general.x[..n]));
            assert_eq!(r1, r2, "trial {trial}");
            assert_eq!(sized.iterations, general.iterations, "trial {trial}");
            // the rows' products over their foot's block only: the same bits
            let mut blocks = ActiveSet::default();
            let r3 = blocks
                .solve(&DenseQp {
                    foot_blocks: true,
                    ..qp.clone()
                })
                .map(bits);
            assert_eq!(r1, r3, "trial {trial}");
            assert_eq!(sized.iterations, blocks.iterations, "trial {trial}");
            if r1.is_ok() {
                solved += 1;
                iterations += sized.iterations;
            }
        }
        // the problems exercise the active-set iterations, not only x = −H⁻¹g
        assert!(
            solved > 500 && iterations > 5 * solved,
            "{solved} solved, {iterations} iterations"
        );
    }

    /// `row_dot` over a foot's block gives `dot`'s bits on rows and vectors
    /// full of signed zeros (the cases where the three-term sum is zero:
    /// all `−0`, a `+0` term, a cancellation), other columns' zeros of
    /// either sign.
    #[test]
    fn row_dot_keeps_the_signs_of_zeros() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let pick = |rng: &mut rand_chacha::ChaCha8Rng| {
            [0.0, -0.0, 1.0, -1.0, 0.5][rng.random_range(0..5usize)]
        };
        for trial in 0..20_000 {
            let k = 1 + trial % 4;
            let n = 3 * k;
            let mut qp = DenseQp {
                n,
                m: 6 * k,
                foot_blocks: true,
                ..DenseQp::default()
            };
            let i = rng.random_range(0..6 * k);
            let lo = 3 * (i / 6);
            for c in 0..n {
                qp.c[i][c] = if (lo..lo + 3).contains(&c) {
                    pick(&mut rng)
                } else if rng.random_bool(0.5) {
                    -0.0
                } else {
                    0.0
                };
            }
            let x: [f64; MAX_VARS] = std::array::from_fn(|_| pick(&mut rng));
            let (got, want) = (row_dot(&qp, i, n, &x), dot(&qp.c[i][..n], &x[..n]));
            assert_eq!(got.to_bits(), want.to_bits(), "trial {trial}");
        }
    }

    #[test]
    fn infeasible_and_indefinite_are_errors() {
        let mut qp = DenseQp {
            n: 1,
            m: 2,
            ..DenseQp::default()
        };
        qp.h[0][0] = 1.0;
        qp.c[0][0] = 1.0; // x ≥ 1
        qp.b[0] = 1.0;
        qp.c[1][0] = -1.0; // x ≤ −1
        qp.b[1] = 1.0;
        let mut s = ActiveSet::default();
        assert_eq!(s.solve(&qp), Err(ActiveSetError::Infeasible));
        qp.h[0][0] = -1.0;
        assert_eq!(s.solve(&qp), Err(ActiveSetError::NotPositiveDefinite));
    }
}
