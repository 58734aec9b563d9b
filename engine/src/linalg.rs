//! Small dense linear algebra on row-major slices: what the algorithms need
//! (a 6×6 base solve, an nv×nv mass-matrix factorisation) without allocating.

/// `√(a² + b²)`, the length of `(a, b)`: `hypot` without its library call
/// (glibc's took ~17 ns in a dependent chain on the project machine, the
/// square root ~9), for the leg IK's roll plane and the force QP's Givens
/// rotations. Where the sum of squares would overflow or lose bits to
/// underflow it is `hypot` itself; elsewhere within 2 ulp of it (unit test).
#[inline]
pub fn hypot(a: f64, b: f64) -> f64 {
    let s = a * a + b * b;
    if (f64::MIN_POSITIVE..f64::MAX).contains(&s) {
        s.sqrt()
    } else {
        a.hypot(b)
    }
}

/// In-place Cholesky factorisation `A = L Lᵀ` of a symmetric positive-definite
/// `N×N` array; the lower triangle receives `L`. Returns `false` when `A` is not
/// positive definite (or has a non-finite entry).
pub fn cholesky_in_place<const N: usize>(a: &mut [[f64; N]; N]) -> bool {
    for j in 0..N {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k];
        }
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let ljj = d.sqrt();
        a[j][j] = ljj;
        for i in j + 1..N {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k];
            }
            a[i][j] = s / ljj;
        }
    }
    true
}

/// Solves `L Lᵀ x = b` in place given the factor from [`cholesky_in_place`].
pub fn cholesky_solve_in_place<const N: usize>(l: &[[f64; N]; N], b: &mut [f64; N]) {
    for i in 0..N {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * b[k];
        }
        b[i] = s / l[i][i];
    }
    for i in (0..N).rev() {
        let mut s = b[i];
        for k in i + 1..N {
            s -= l[k][i] * b[k];
        }
        b[i] = s / l[i][i];
    }
}

/// In-place Cholesky factorisation of a row-major `n×n` matrix in `a`
/// (lower triangle receives `L`). Returns `false` when not positive definite.
pub fn cholesky_dense(a: &mut [f64], n: usize) -> bool {
    debug_assert_eq!(a.len(), n * n);
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let ljj = d.sqrt();
        a[j * n + j] = ljj;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / ljj;
        }
    }
    true
}

/// Solves `L Lᵀ x = b` in place, `l` from [`cholesky_dense`].
pub fn cholesky_dense_solve(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`hypot`] against std's (glibc's) over magnitudes from 1e-150 to
    /// 1e150 and ratios up to 1e12: within 2 ulp; past the squares' range it
    /// is std's, bit for bit.
    #[test]
    fn hypot_is_within_two_ulp_of_std() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let ulps = |x: f64, y: f64| (x.to_bits() as i64 - y.to_bits() as i64).unsigned_abs();
        let mut worst = 0;
        for _ in 0..200_000 {
            let scale = 10f64.powf(rng.random_range(-150.0..150.0));
            let ratio = 10f64.powf(rng.random_range(-12.0..0.0));
            let a = scale * rng.random_range(-1.0..1.0);
            let b = scale * ratio * rng.random_range(-1.0..1.0);
            let got = hypot(a, b);
            worst = worst.max(ulps(got, a.hypot(b)));
            assert!(ulps(got, a.hypot(b)) <= 2, "hypot({a:e}, {b:e}) = {got:e}");
            assert_eq!(hypot(b, a).to_bits(), got.to_bits(), "symmetric");
        }
        assert!(
            worst >= 1,
            "a sample that differs from std exercises the bound"
        );
        for (a, b) in [
            (1e200, 3e199),
            (1e-170, 2e-171),
            (0.0, 0.0),
            (f64::INFINITY, 1.0),
        ] {
            assert_eq!(hypot(a, b).to_bits(), a.hypot(b).to_bits());
        }
        assert!(hypot(f64::NAN, 1.0).is_nan());
    }

    #[test]
    fn dense_solve_recovers_x() {
        let n = 4;
        // A = B Bᵀ + I is SPD
        let b = [
            1.0, 2.0, 0.5, -1.0, 0.0, 1.0, 3.0, 0.2, -0.7, 0.1, 1.0, 0.4, 0.3, -0.2, 0.6, 1.5,
        ];
        let mut a = vec![0.0; 16];
        for i in 0..n {
            for j in 0..n {
                let mut s = if i == j { 1.0 } else { 0.0 };
                for k in 0..n {
                    s += b[i * n + k] * b[j * n + k];
                }
                a[i * n + j] = s;
            }
        }
        let x = [0.3, -1.0, 2.0, 0.5];
        let mut rhs: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum())
            .collect();
        let mut l = a.clone();
        assert!(cholesky_dense(&mut l, n));
        cholesky_dense_solve(&l, n, &mut rhs);
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn rejects_indefinite() {
        let mut a = [[1.0, 2.0], [2.0, 1.0]];
        assert!(!cholesky_in_place(&mut a));
    }
}
