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

/// Most variables a problem may have.
pub const MAX_VARS: usize = 12;
/// Most inequality constraints a problem may have.
pub const MAX_CONSTRAINTS: usize = 24;

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
            tolerance: 1e-10,
        }
    }
}

/// The solver's workspace (all on the stack, reused between solves).
#[derive(Clone, Debug)]
pub struct ActiveSet {
    /// Lower Cholesky factor of `H`.
    l: [[f64; MAX_VARS]; MAX_VARS],
    /// `J = L⁻ᵀ Q` (columns `0..iq` span the active constraints' image).
    j: [[f64; MAX_VARS]; MAX_VARS],
    /// Upper-triangular `R` (first `iq` columns used).
    r: [[f64; MAX_VARS]; MAX_VARS],
    /// Active constraint indices, in order of addition (`iq` of them).
    active: [usize; MAX_VARS + 1],
    /// Lagrange multipliers of the active constraints (and the one being added at `iq`).
    u: [f64; MAX_VARS + 1],
    /// Whether each constraint is in the active set.
    is_active: [bool; MAX_CONSTRAINTS],
    /// Constraints found linearly dependent on the active set this solve.
    excluded: [bool; MAX_CONSTRAINTS],
    /// Constraint values `cᵢᵀ x − bᵢ`.
    s: [f64; MAX_CONSTRAINTS],
    /// Solution.
    x: [f64; MAX_VARS],
    /// Active-set size.
    iq: usize,
    /// Iterations of the last solve (constraint additions and drops).
    pub iterations: usize,
}

impl Default for ActiveSet {
    fn default() -> Self {
        ActiveSet {
            l: [[0.0; MAX_VARS]; MAX_VARS],
            j: [[0.0; MAX_VARS]; MAX_VARS],
            r: [[0.0; MAX_VARS]; MAX_VARS],
            active: [0; MAX_VARS + 1],
            u: [0.0; MAX_VARS + 1],
            is_active: [false; MAX_CONSTRAINTS],
            excluded: [false; MAX_CONSTRAINTS],
            s: [0.0; MAX_CONSTRAINTS],
            x: [0.0; MAX_VARS],
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
        // The stance-force QP's shapes (3 variables and 6 constraints per
        // foot) get loops of known length, which the compiler unrolls; the
        // same operations in the same order, so the same bits as any size.
        match (n, m) {
            (3, 6) => self.solve_sized::<3, 6>(qp)?,
            (6, 12) => self.solve_sized::<6, 12>(qp)?,
            (9, 18) => self.solve_sized::<9, 18>(qp)?,
            (12, 24) => self.solve_sized::<12, 24>(qp)?,
            _ => self.solve_sized::<0, 0>(qp)?,
        }
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
        // Unconstrained minimum x = −H⁻¹ g = −J Jᵀ g (J = L⁻ᵀ).
        let mut jtg = [0.0; MAX_VARS];
        for k in 0..n {
            jtg[k] = (0..=k).map(|i| self.j[i][k] * qp.g[i]).sum();
        }
        for i in 0..n {
            self.x[i] = -(i..n).map(|k| self.j[i][k] * jtg[k]).sum::<f64>();
        }
        self.iq = 0;
        self.is_active[..m].fill(false);
        self.excluded[..m].fill(false);
        let mut r_norm = 1.0f64;
        let max_iter = 20 * (n + m);
        let (mut d, mut z, mut rr) = ([0.0; MAX_VARS], [0.0; MAX_VARS], [0.0; MAX_VARS + 1]);
        'outer: loop {
            // Step 1: constraint values; pick the most violated one.
            for i in 0..m {
                self.s[i] = dot(&qp.c[i][..n], &self.x[..n]) - qp.b[i];
            }
            let Some(p) = self.most_violated(m, qp.tolerance) else {
                return Ok(());
            };
            self.u[self.iq] = 0.0;
            self.active[self.iq] = p;
            let np = &qp.c[p];
            loop {
                self.iterations += 1;
                if self.iterations > max_iter {
                    return Err(ActiveSetError::NoConvergence);
                }
                // Step 2a: d = Jᵀ n_p; primal direction z = J₂ d₂; dual r = R⁻¹ d₁.
                let iq = self.iq;
                for k in 0..n {
                    d[k] = (0..n).map(|i| self.j[i][k] * np[i]).sum();
                }
                for i in 0..n {
                    z[i] = (iq..n).map(|k| self.j[i][k] * d[k]).sum();
                }
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
                let znp = dot(&z[..n], &np[..n]);
                let t2 = if dot(&z[..n], &z[..n]) > f64::EPSILON * f64::EPSILON {
                    -self.s[p] / znp
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
                for i in 0..n {
                    self.x[i] += t * z[i];
                }
                for k in 0..iq {
                    self.u[k] -= t * rr[k];
                }
                self.u[iq] += t;
                if t2 <= t1 {
                    // Full step: p joins the active set.
                    if self.add_constraint::<N>(n, &mut d, &mut r_norm) {
                        self.is_active[p] = true;
                    } else {
                        // Linearly dependent on the active set within round-off:
                        // take it out again and leave it out for this solve.
                        self.delete_constraint::<N>(n, p);
                        self.excluded[p] = true;
                    }
                    continue 'outer;
                }
                // Partial step: drop the blocking constraint and retry p.
                self.delete_constraint::<N>(n, drop.expect("t1 finite"));
                self.s[p] = dot(&qp.c[p][..n], &self.x[..n]) - qp.b[p];
            }
        }
    }

    /// Cholesky `H = L Lᵀ` and `J = L⁻ᵀ` (upper triangular).
    #[inline(always)]
    fn factor<const N: usize>(&mut self, qp: &DenseQp) -> Result<(), ActiveSetError> {
        let n = size::<N>(qp.n);
        let l = &mut self.l;
        for i in 0..n {
            for k in 0..=i {
                let mut sum = qp.h[i][k];
                for p in 0..k {
                    sum -= l[i][p] * l[k][p];
                }
                if i == k {
                    if sum <= 0.0 || !sum.is_finite() {
                        return Err(ActiveSetError::NotPositiveDefinite);
                    }
                    l[i][i] = sum.sqrt();
                } else {
                    l[i][k] = sum / l[k][k];
                }
            }
        }
        // L⁻¹ by forward substitution (lower), then J = (L⁻¹)ᵀ.
        for c in 0..n {
            for i in 0..n {
                self.j[i][c] = 0.0;
            }
        }
        for c in 0..n {
            // column c of L⁻¹: solve L y = e_c; y[i] = 0 for i < c.
            for i in c..n {
                let mut sum = if i == c { 1.0 } else { 0.0 };
                for p in c..i {
                    sum -= l[i][p] * self.j[c][p];
                }
                self.j[c][i] = sum / l[i][i];
            }
        }
        for row in self.r.iter_mut().take(n) {
            row[..n].fill(0.0);
        }
        Ok(())
    }

    fn most_violated(&self, m: usize, tol: f64) -> Option<usize> {
        let mut worst = -tol;
        let mut p = None;
        for i in 0..m {
            if !self.is_active[i] && !self.excluded[i] && self.s[i] < worst {
                worst = self.s[i];
                p = Some(i);
            }
        }
        p
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
            let (mut cc, mut ss) = (d[jj - 1], d[jj]);
            let h = cc.hypot(ss);
            if h == 0.0 {
                continue;
            }
            d[jj] = 0.0;
            ss /= h;
            cc /= h;
            if cc < 0.0 {
                cc = -cc;
                ss = -ss;
                d[jj - 1] = -h;
            } else {
                d[jj - 1] = h;
            }
            let xny = ss / (1.0 + cc);
            for k in 0..n {
                let t1 = self.j[k][jj - 1];
                let t2 = self.j[k][jj];
                self.j[k][jj - 1] = t1 * cc + t2 * ss;
                self.j[k][jj] = xny * (t1 + self.j[k][jj - 1]) - t2;
            }
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
        self.is_active[l] = false;
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
            let (mut cc, mut ss) = (self.r[jj][jj], self.r[jj + 1][jj]);
            let h = cc.hypot(ss);
            if h == 0.0 {
                continue;
            }
            cc /= h;
            ss /= h;
            self.r[jj + 1][jj] = 0.0;
            if cc < 0.0 {
                self.r[jj][jj] = -h;
                cc = -cc;
                ss = -ss;
            } else {
                self.r[jj][jj] = h;
            }
            let xny = ss / (1.0 + cc);
            for k in jj + 1..iq {
                let t1 = self.r[jj][k];
                let t2 = self.r[jj + 1][k];
                self.r[jj][k] = t1 * cc + t2 * ss;
                self.r[jj + 1][k] = xny * (t1 + self.r[jj][k]) - t2;
            }
            for k in 0..n {
                let t1 = self.j[k][jj];
                let t2 = self.j[k][jj + 1];
                self.j[k][jj] = t1 * cc + t2 * ss;
                self.j[k][jj + 1] = xny * (self.j[k][jj] + t1) - t2;
            }
        }
    }
}

/// A size known at compile time (`N > 0`) or given at run time (`N == 0`):
/// [`ActiveSet::solve`]'s fixed-size paths and its general one share one body.
#[inline(always)]
fn size<const N: usize>(runtime: usize) -> usize {
    if N == 0 { runtime } else { N }
}

#[inline]
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
    /// the general one: random problems of that shape (1 to 4 blocks of 3
    /// variables, 6 constraint rows each over its own block, a dense SPD
    /// Hessian) solved both ways have the same minimiser bits, errors and
    /// iteration counts.
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
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let r1 = sized.solve(&qp).map(bits);
            let r2 = general
                .solve_sized::<0, 0>(&qp)
                .map(|()| bits(&general.x[..n]));
            assert_eq!(r1, r2, "trial {trial}");
            assert_eq!(sized.iterations, general.iterations, "trial {trial}");
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
