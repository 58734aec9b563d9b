//! The linear Kalman filter on base position, base velocity and foot
//! positions of the MIT Cheetah software (Bledt et al., "MIT Cheetah 3",
//! IROS 2018; `LinearKFPositionVelocityEstimator` in the open
//! Cheetah-Software), all in the world frame:
//!
//! ```text
//! x = [p (3), v (3), p_f1 … p_f4 (3 each)]          n = 18
//! predict:  p ← p + v Δt,  v ← v + a Δt,  p_fi ← p_fi
//!           a = R̂ f + g   (IMU specific force rotated by the attitude estimate)
//!           P ← F P Fᵀ + Q,  Q = diag(σ_p² Δt, σ_a² Δt, σ_f² Δt)
//! measure, per foot i (r_i, ṙ_i: foot relative to the base from the
//! encoders and forward kinematics, torso frame):
//!   p_fi − p      = R̂ r_i                           (every foot)
//!   v             = −R̂ (ω × r_i + ṙ_i)              (stance feet: the foot is still)
//!   p_fi,z        = ground height + foot radius      (stance feet)
//! ```
//!
//! A swing foot's process noise is `σ_swing`, so its state follows the
//! kinematics and does not pull on `p`. Measurements are scalar and
//! independent (diagonal R), so they are applied one at a time (sequential
//! update: no matrix inverse). Each scalar update moves `x` at once; its
//! covariance downdate `P ← P − g gᵀ` (`g = P h / √s`) waits, and a foot's
//! up to 7 downdates are applied to `P` in one pass (the next measurement's
//! `P h` is corrected by the waiting ones). `P` stays symmetric bit for bit
//! by construction (prediction and downdate both), so it is never
//! symmetrised.

use glam::DVec3;
use multiversion::multiversion;
use nalgebra::{SMatrix, SVector};

/// Number of feet the filter carries.
pub const KF_FEET: usize = 4;
/// State size.
pub const KF_N: usize = 6 + 3 * KF_FEET;

/// Noise figures of [`BaseKf`] (standard deviations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KfParams {
    /// Base position process noise (m/√s).
    pub position_process_std: f64,
    /// Acceleration input noise (m/s²·√s: velocity random walk).
    pub accel_process_std: f64,
    /// Stance foot drift (slip) (m/√s).
    pub stance_foot_process_std: f64,
    /// Swing foot process noise (m/√s): large, the foot moves freely.
    pub swing_foot_process_std: f64,
    /// Foot position relative to the base (encoders + kinematics) (m).
    pub foot_position_std_m: f64,
    /// Base velocity from a stance foot's kinematics (m/s).
    pub foot_velocity_std_mps: f64,
    /// Stance foot height against the ground (m).
    pub foot_height_std_m: f64,
    /// Gate on a stance foot's velocity innovation (χ², 3 dof; ≤ 0: none):
    /// beyond it the foot is taken to slip and its velocity is not used.
    pub velocity_gate_chi2: f64,
}

impl Default for KfParams {
    /// Cheetah-Software's figures in SI form, widened for quad16's compliant
    /// ground contact (feet sink ~1 cm) and heavier legs; the velocity gate
    /// at χ²₃(0.99) = 11.34.
    fn default() -> Self {
        KfParams {
            position_process_std: 0.02,
            accel_process_std: 0.5,
            stance_foot_process_std: 0.01,
            swing_foot_process_std: 10.0,
            foot_position_std_m: 0.005,
            foot_velocity_std_mps: 0.1,
            foot_height_std_m: 0.01,
            velocity_gate_chi2: 11.34,
        }
    }
}

/// One foot's measurement for [`BaseKf::update`] (world frame, rotated by R̂).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootMeasurement {
    /// `R̂ r_i`: foot position relative to the base (m, world axes).
    pub relative_position_m: DVec3,
    /// `R̂ (ω × r_i + ṙ_i)`: foot velocity relative to the base (m/s, world axes).
    pub relative_velocity_mps: DVec3,
    /// The foot is in stance (contact sensed).
    pub stance: bool,
    /// Height of the foot point when it stands on the ground (m): the
    /// ground under it plus the foot sphere's radius.
    pub ground_height_m: f64,
}

/// The filter's state and covariance.
#[derive(Clone, Debug)]
pub struct BaseKf {
    /// Noise figures.
    pub params: KfParams,
    /// State `[p, v, p_f…]` (m, m/s; world).
    pub x: SVector<f64, KF_N>,
    /// Covariance.
    pub p: SMatrix<f64, KF_N, KF_N>,
}

impl BaseKf {
    /// A filter at base position `p0`, velocity `v0` and feet `feet` (m,
    /// world), with initial standard deviations 1 cm / 0.1 m/s / 1 cm.
    pub fn new(params: KfParams, p0: DVec3, v0: DVec3, feet: &[DVec3]) -> Self {
        let mut x = SVector::<f64, KF_N>::zeros();
        let mut pd = SVector::<f64, KF_N>::from_element(1e-4);
        for k in 0..3 {
            x[k] = p0[k];
            x[3 + k] = v0[k];
            pd[3 + k] = 1e-2;
        }
        for (i, f) in feet.iter().take(KF_FEET).enumerate() {
            for k in 0..3 {
                x[6 + 3 * i + k] = f[k];
            }
        }
        BaseKf {
            params,
            x,
            p: SMatrix::from_diagonal(&pd),
        }
    }

    /// Base position estimate (m, world).
    pub fn position_m(&self) -> DVec3 {
        DVec3::new(self.x[0], self.x[1], self.x[2])
    }

    /// Base velocity estimate (m/s, world).
    pub fn velocity_mps(&self) -> DVec3 {
        DVec3::new(self.x[3], self.x[4], self.x[5])
    }

    /// Foot `i`'s position estimate (m, world).
    pub fn foot_m(&self, i: usize) -> DVec3 {
        DVec3::new(self.x[6 + 3 * i], self.x[7 + 3 * i], self.x[8 + 3 * i])
    }

    /// Prediction over `dt_s` with the world acceleration `accel_world_mps2`
    /// (gravity included); `stance[i]` picks each foot's process noise.
    ///
    /// `P ← F P Fᵀ` is written entry by entry so that it stays symmetric bit
    /// for bit: with F = I + Δt E (E: v → p) only the p rows and columns
    /// change, `P'_pp = P_pp + Δt (P_pv + P_vp) + Δt² P_vv` (the sum in the
    /// middle commutes, so `P'_km` and `P'_mk` are the same bits) and
    /// `P'_pj = P_pj + Δt P_vj` for every other `j`, mirrored.
    pub fn predict(&mut self, accel_world_mps2: DVec3, stance: &[bool], dt_s: f64) {
        let kp = self.params;
        for k in 0..3 {
            self.x[k] += self.x[3 + k] * dt_s + 0.5 * accel_world_mps2[k] * dt_s * dt_s;
            self.x[3 + k] += accel_world_mps2[k] * dt_s;
        }
        let dt2 = dt_s * dt_s;
        // on the column-major array: P(r, c) = p[c n + r]; column j's rows
        // 0..6 are contiguous, so its p rows are updated as one short vector
        let (_, p) = self.parts();
        let at = |r: usize, c: usize| c * KF_N + r;
        let mut pp = [[0.0; 3]; 3];
        for (k, row) in pp.iter_mut().enumerate() {
            for (m, e) in row.iter_mut().enumerate() {
                *e = p[at(k, m)]
                    + dt_s * (p[at(k, 3 + m)] + p[at(3 + k, m)])
                    + dt2 * p[at(3 + k, 3 + m)];
            }
        }
        for j in 3..KF_N {
            let col: &mut [f64; 6] = (&mut p[at(0, j)..at(6, j)]).try_into().expect("six rows");
            let e = [
                col[0] + dt_s * col[3],
                col[1] + dt_s * col[4],
                col[2] + dt_s * col[5],
            ];
            col[..3].copy_from_slice(&e);
            for (k, e) in e.into_iter().enumerate() {
                p[at(j, k)] = e;
            }
        }
        for (k, row) in pp.iter().enumerate() {
            for (m, e) in row.iter().enumerate() {
                p[at(k, m)] = *e;
            }
        }
        for k in 0..3 {
            p[at(k, k)] += kp.position_process_std.powi(2) * dt_s;
            p[at(3 + k, 3 + k)] += kp.accel_process_std.powi(2) * dt_s;
        }
        for i in 0..KF_FEET {
            let s = if stance.get(i).copied().unwrap_or(false) {
                kp.stance_foot_process_std
            } else {
                kp.swing_foot_process_std
            };
            for k in 0..3 {
                let j = 6 + 3 * i + k;
                p[at(j, j)] += s * s * dt_s;
            }
        }
    }

    /// One scalar measurement into `block` (see [`measure`]).
    fn measure(&mut self, block: &mut Downdates, a: usize, b: Option<usize>, z: f64, r: f64) {
        let (x, p) = self.parts();
        measure(x, p, block, a, b, z, r);
    }

    /// Applies the block's downdates to `P` and empties it.
    fn apply(&mut self, block: &mut Downdates) {
        let (_, p) = self.parts();
        apply(p, block);
    }

    /// The state and the covariance (column-major) as arrays.
    fn parts(&mut self) -> (&mut [f64; KF_N], &mut Cov) {
        (
            self.x.as_mut_slice().try_into().expect("x has n entries"),
            self.p.as_mut_slice().try_into().expect("P is n × n"),
        )
    }

    /// A direct measurement `z` of the base position (m, world), each axis
    /// with standard deviation `std_m` (motion capture).
    pub fn update_position(&mut self, z: DVec3, std_m: f64) {
        let r = std_m * std_m;
        let mut block = Downdates::new();
        for k in 0..3 {
            self.measure(&mut block, k, None, z[k], r);
        }
        self.apply(&mut block);
    }

    /// The measurement update with each foot's kinematics: the scalar
    /// measurements one after the other (sequential update), each foot's
    /// covariance downdates applied together.
    pub fn update(&mut self, feet: &[FootMeasurement]) {
        let kp = self.params;
        let (x, p) = self.parts();
        DOWNDATES.with_borrow_mut(|block| update_feet(&kp, x, p, feet, block));
    }
}

thread_local! {
    /// [`BaseKf::update`]'s block of downdates: this thread's, so that each
    /// update does not zero a new one on its stack (1 KiB); each downdate
    /// is written before it is read.
    static DOWNDATES: std::cell::RefCell<Downdates> =
        const { std::cell::RefCell::new(Downdates::new()) };
}

/// The covariance, column-major.
type Cov = [f64; KF_N * KF_N];

/// [`BaseKf::update`] on the state and covariance arrays. Its x86-64-v3
/// clone runs the vector loops of [`measure`] and [`apply`] (inlined) four
/// rows per AVX register; no fused multiply–add, so both give the same bits.
/// (An AVX-512 clone, tried, was no faster here: 0.83–1.09 µs per update
/// against 0.94–1.03 µs; the generic code takes 1.5–1.6 µs.)
#[multiversion(targets("x86_64+avx2+fma"))]
fn update_feet(
    kp: &KfParams,
    x: &mut [f64; KF_N],
    p: &mut Cov,
    feet: &[FootMeasurement],
    block: &mut Downdates,
) {
    update_feet_body(kp, x, p, feet, block);
}

/// [`update_feet`] compiled for the build's generic target only: for the
/// test that every clone gives the same bits.
#[cfg(test)]
#[inline(never)]
fn update_feet_generic(kp: &KfParams, x: &mut [f64; KF_N], p: &mut Cov, feet: &[FootMeasurement]) {
    update_feet_body(kp, x, p, feet, &mut Downdates::new());
}

#[inline(always)]
fn update_feet_body(
    kp: &KfParams,
    x: &mut [f64; KF_N],
    p: &mut Cov,
    feet: &[FootMeasurement],
    block: &mut Downdates,
) {
    let rp = kp.foot_position_std_m.powi(2);
    let rv = kp.foot_velocity_std_mps.powi(2);
    let rh = kp.foot_height_std_m.powi(2);
    // (empty unless an earlier update unwound mid-foot)
    block.n = 0;
    let n_feet = feet.len().min(KF_FEET);
    // whether some of P's lower triangle is behind the upper (see below)
    let mut lower_behind = false;
    for (i, m) in feet.iter().take(KF_FEET).enumerate() {
        let fi = 6 + 3 * i;
        for k in 0..3 {
            measure(x, p, block, fi + k, Some(k), m.relative_position_m[k], rp);
        }
        if m.stance {
            // a slipping or still-landing foot moves: reject its velocity
            // when the innovation is beyond the gate (χ² with 3 dof)
            let z = -m.relative_velocity_mps;
            let var = velocity_variances(p, block);
            let mut chi2 = 0.0;
            for k in 0..3 {
                let d = z[k] - x[3 + k];
                chi2 += d * d / (var[k] + rv);
            }
            if kp.velocity_gate_chi2 <= 0.0 || chi2 <= kp.velocity_gate_chi2 {
                for k in 0..3 {
                    measure(x, p, block, 3 + k, None, z[k], rv);
                }
            }
            measure(x, p, block, fi + 2, None, m.ground_height_m, rh);
        }
        // Between feet, the lower triangle is brought up to date only in the
        // columns the next foot's measurements read (the base's and its
        // own); the last foot's block completes it, so that P is whole
        // again when the update returns.
        let next = (i + 1 < n_feet).then_some(i + 1);
        lower_behind = apply_then_mirror(p, block, lower_behind, next);
    }
}

/// The scalar measurement `z = x[a] − x[b]` (`b = None`: `z = x[a]`) with
/// variance `r`: one sequential Kalman update of `x` now, its covariance
/// downdate held in `block` (applied by [`apply`]).
///
/// With `P` the covariance when the block started and `g_l` the block's
/// earlier downdates (`P_now = P − Σ g_l g_lᵀ`), `u = P_now h` is a column
/// difference of `P` (h is sparse) corrected by each `g_l (g_lᵀ h)`; then
/// `s = hᵀu + r`, `x ← x + u (z − hᵀx) / s` and `g = u / √s` joins the
/// block: the same update as the dense `K = P hᵀ / s`, `P ← P − K h P`.
#[inline(always)]
fn measure(
    x: &mut [f64; KF_N],
    p: &Cov,
    block: &mut Downdates,
    a: usize,
    b: Option<usize>,
    z: f64,
    r: f64,
) {
    let col = |j: usize| -> &[f64; KF_N] {
        p[j * KF_N..(j + 1) * KF_N]
            .try_into()
            .expect("a column of P")
    };
    // `u[a]` and `u[b]` are also carried as scalars (`ua`, `ub`: the same
    // operations in the same order, so the same bits): read at a run-time
    // index, `u` would live in memory instead of registers (about 60
    // instructions more per measurement).
    let pa = col(a);
    let mut u = *pa;
    let mut ua = pa[a];
    let mut ub = b.map_or(0.0, |b| pa[b]);
    let mut hx = x[a];
    if let Some(b) = b {
        let pb = col(b);
        for (u, pb) in u.iter_mut().zip(pb) {
            *u -= pb;
        }
        ua -= pb[a];
        ub -= pb[b];
        hx -= x[b];
    }
    for g in &block.g[..block.n] {
        let c = g[a] - b.map_or(0.0, |b| g[b]);
        for (u, g) in u.iter_mut().zip(g) {
            *u -= g * c;
        }
        ua -= g[a] * c;
        if let Some(b) = b {
            ub -= g[b] * c;
        }
    }
    let s = ua - ub + r;
    // (a block holds at most a foot's 7 measurements: [`update_feet`] applies
    // it after each foot)
    if s <= 0.0 || !s.is_finite() || block.n >= BLOCK {
        return;
    }
    let gain = (z - hx) / s;
    for (x, u) in x.iter_mut().zip(&u) {
        *x += u * gain;
    }
    let scale = 1.0 / s.sqrt();
    for (g, u) in block.g[block.n].iter_mut().zip(&u) {
        *g = u * scale;
    }
    block.n += 1;
}

/// The variances of the base velocity `x[3..6]` now, the block's
/// downdates included: one pass over the block for the three (each is
/// still `P_jj − g_0j² − g_1j² − …` in that order).
#[inline(always)]
fn velocity_variances(p: &Cov, block: &Downdates) -> [f64; 3] {
    let mut v: [f64; 3] = std::array::from_fn(|k| p[(3 + k) * KF_N + 3 + k]);
    for g in &block.g[..block.n] {
        for (v, g) in v.iter_mut().zip(&g[3..6]) {
            *v -= g * g;
        }
    }
    v
}

/// `P ← P − Σ_l g_l g_lᵀ` (the block's downdates, in order) on the
/// column-major `P`, entry by entry as `P_ij − g_l,i g_l,j`: the product
/// commutes, so a symmetric `P` stays symmetric bit for bit (no
/// symmetrisation needed). A column stays in registers over the block.
/// Empties the block.
///
/// From [`TRIANGLE_FROM`] downdates on (every foot's block), only the upper
/// triangle is computed (each column's rows down to the diagonal, rounded
/// up to whole groups of four rows, the vector width) and the rest copied
/// from the mirrored entries: the same bits as computing them, as `P` is
/// symmetric bit for bit, with about 45% fewer products for 128 copies.
#[inline(always)]
fn apply(p: &mut Cov, block: &mut Downdates) {
    apply_then_mirror(p, block, false, None);
}

/// [`apply`], where the rows below the computed ones may be behind in some
/// columns (`lower_behind`; the square is then mirrored first) and, with
/// `next_foot`, the mirrored rows are brought up to date only in the
/// columns that foot's measurements read: the base's position and
/// velocity (0..6) and the foot's own three. Returns whether some lower
/// rows are left behind. (In update_feet: 512 entries mirrored per quad16
/// update before, 382 now.)
#[inline(always)]
fn apply_then_mirror(
    p: &mut Cov,
    block: &mut Downdates,
    lower_behind: bool,
    next_foot: Option<usize>,
) -> bool {
    let g = &block.g[..block.n.min(BLOCK)];
    let behind = if g.len() >= TRIANGLE_FROM {
        const _: () = assert!(KF_N == 18, "the column groups below cover 18 rows");
        apply_upper::<0, 4, 4>(p, g);
        apply_upper::<4, 8, 8>(p, g);
        apply_upper::<8, 12, 12>(p, g);
        apply_upper::<12, 16, 16>(p, g);
        apply_upper::<16, 18, 18>(p, g);
        mirror_lower::<0, 4, 4>(p);
        mirror_lower::<4, 6, 8>(p);
        match next_foot {
            // the foot's columns 6 + 3i.. (rows from the group's end on)
            Some(1) => mirror_lower::<9, 12, 12>(p),
            Some(2) => mirror_lower::<12, 15, 16>(p),
            Some(3) => mirror_lower::<15, 16, 16>(p),
            _ => {
                mirror_lower::<6, 8, 8>(p);
                mirror_lower::<8, 12, 12>(p);
                mirror_lower::<12, 16, 16>(p);
            }
        }
        matches!(next_foot, Some(1..=3))
    } else {
        // the whole square is read: every lower row up to date first
        if lower_behind {
            mirror_lower::<0, 4, 4>(p);
            mirror_lower::<4, 8, 8>(p);
            mirror_lower::<8, 12, 12>(p);
            mirror_lower::<12, 16, 16>(p);
        }
        apply_upper::<0, KF_N, KF_N>(p, g);
        false
    };
    block.n = 0;
    behind
}

/// From this many downdates in a block [`apply`] computes the upper
/// triangle only: a swing foot's 3 and a stance foot's 7 (measured at 64
/// robots: `update_feet` 2,292 instructions per robot-step with the full
/// square, 2,021 with the triangle from 5 downdates, 1,945 from 3; 2,324
/// with the triangle for every block and no branch, the compiler laying
/// the loops out otherwise).
const TRIANGLE_FROM: usize = 3;

/// [`apply`]'s downdates of the first `R` rows of the columns `J0..J1`.
#[inline(always)]
fn apply_upper<const J0: usize, const J1: usize, const R: usize>(p: &mut Cov, g: &[[f64; KF_N]]) {
    for j in J0..J1 {
        let col = &mut p[j * KF_N..j * KF_N + R];
        let mut c: [f64; R] = (&*col).try_into().expect("R rows");
        for g in g {
            let gj = g[j];
            for (c, gi) in c.iter_mut().zip(&g[..R]) {
                *c -= gi * gj;
            }
        }
        col.copy_from_slice(&c);
    }
}

/// Rows `R..` of the columns `J0..J1` from the mirrored entries (rows
/// `J0..J1` of the columns `R..`, computed by [`apply_upper`]).
#[inline(always)]
fn mirror_lower<const J0: usize, const J1: usize, const R: usize>(p: &mut Cov) {
    for j in J0..J1 {
        for i in R..KF_N {
            p[j * KF_N + i] = p[i * KF_N + j];
        }
    }
}

/// Most scalar measurements of one block: a stance foot's 3 positions, 3
/// velocities and its height.
const BLOCK: usize = 7;

/// Covariance downdates not yet applied: `P_now = P − Σ g_l g_lᵀ` (l < n).
/// On the stack, once per update (nothing per robot is kept).
struct Downdates {
    g: [[f64; KF_N]; BLOCK],
    n: usize,
}

impl Downdates {
    const fn new() -> Self {
        Downdates {
            g: [[0.0; KF_N]; BLOCK],
            n: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use rand::{Rng, SeedableRng};

    /// A filter with a random state and a random symmetric positive definite
    /// covariance `A Aᵀ + 1e-3 I`.
    fn random_kf(rng: &mut rand_chacha::ChaCha8Rng) -> BaseKf {
        let mut kf = BaseKf::new(KfParams::default(), DVec3::ZERO, DVec3::ZERO, &[]);
        let a = SMatrix::<f64, KF_N, KF_N>::from_fn(|_, _| rng.random_range(-0.1..0.1));
        kf.p = a * a.transpose() + SMatrix::identity() * 1e-3;
        kf.x = SVector::from_fn(|_, _| rng.random_range(-1.0..1.0));
        kf
    }

    fn same_bits<const R: usize, const C: usize>(
        a: &SMatrix<f64, R, C>,
        b: &SMatrix<f64, R, C>,
    ) -> bool {
        a.iter()
            .zip(b.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    }

    /// `P` is symmetric bit for bit.
    fn bit_symmetric(p: &SMatrix<f64, KF_N, KF_N>) -> bool {
        (0..KF_N).all(|i| (0..KF_N).all(|j| p[(i, j)].to_bits() == p[(j, i)].to_bits()))
    }

    /// Largest |a − b| over the largest |b| (1 at least for small b).
    fn rel_diff<const R: usize, const C: usize>(
        a: &SMatrix<f64, R, C>,
        b: &SMatrix<f64, R, C>,
    ) -> f64 {
        (a - b).amax() / b.amax().max(1e-300)
    }

    /// One scalar measurement `z = x[a] − x[b]` with variance `r`.
    #[derive(Clone, Copy)]
    struct Scalar {
        a: usize,
        b: Option<usize>,
        z: f64,
        r: f64,
    }

    /// The textbook Kalman update in nalgebra's dense algebra, all the
    /// measurements at once: `S = H P Hᵀ + R`, `K = P Hᵀ S⁻¹`,
    /// `x ← x + K (z − H x)`, `P ← P − K H P`.
    fn dense_batch(kf: &mut BaseKf, ms: &[Scalar]) {
        let m = ms.len();
        let mut h = DMatrix::<f64>::zeros(m, KF_N);
        let mut z = DVector::<f64>::zeros(m);
        let mut r = DMatrix::<f64>::zeros(m, m);
        for (i, s) in ms.iter().enumerate() {
            h[(i, s.a)] = 1.0;
            if let Some(b) = s.b {
                h[(i, b)] = -1.0;
            }
            z[i] = s.z;
            r[(i, i)] = s.r;
        }
        let p = DMatrix::from_column_slice(KF_N, KF_N, kf.p.as_slice());
        let x = DVector::from_column_slice(kf.x.as_slice());
        let s = &h * &p * h.transpose() + r;
        let s_inv = s.try_inverse().expect("S is invertible");
        let k = &p * h.transpose() * s_inv;
        let x_new = &x + &k * (z - &h * &x);
        let p_new = &p - &k * &h * &p;
        kf.x.copy_from_slice(x_new.as_slice());
        kf.p.copy_from_slice(p_new.as_slice());
    }

    /// One scalar update in dense form, `P ← P − K h P`.
    fn dense_scalar(kf: &mut BaseKf, s: Scalar) {
        let mut h = SMatrix::<f64, 1, KF_N>::zeros();
        h[s.a] = 1.0;
        if let Some(b) = s.b {
            h[b] = -1.0;
        }
        let sv = (h * kf.p * h.transpose())[0] + s.r;
        let k = kf.p * h.transpose() / sv;
        kf.x += k * (s.z - (h * kf.x)[0]);
        kf.p -= k * h * kf.p;
    }

    /// [`BaseKf::update`] with dense scalar updates (the gate read from the
    /// dense `P` after the foot's position updates).
    /// Returns how many stance feet's velocities passed and failed the gate.
    fn dense_update(kf: &mut BaseKf, feet: &[FootMeasurement]) -> [u32; 2] {
        let mut gate = [0; 2];
        let kp = kf.params;
        let rp = kp.foot_position_std_m.powi(2);
        let rv = kp.foot_velocity_std_mps.powi(2);
        let rh = kp.foot_height_std_m.powi(2);
        for (i, m) in feet.iter().enumerate() {
            let fi = 6 + 3 * i;
            for k in 0..3 {
                let (a, b, z, r) = (fi + k, Some(k), m.relative_position_m[k], rp);
                dense_scalar(kf, Scalar { a, b, z, r });
            }
            if m.stance {
                let z = -m.relative_velocity_mps;
                let d = z - kf.velocity_mps();
                let chi2: f64 = (0..3)
                    .map(|k| d[k] * d[k] / (kf.p[(3 + k, 3 + k)] + rv))
                    .sum();
                if chi2 <= kp.velocity_gate_chi2 {
                    gate[0] += 1;
                    for k in 0..3 {
                        let (a, b, z, r) = (3 + k, None, z[k], rv);
                        dense_scalar(kf, Scalar { a, b, z, r });
                    }
                } else {
                    gate[1] += 1;
                }
                let (a, b, z, r) = (fi + 2, None, m.ground_height_m, rh);
                dense_scalar(kf, Scalar { a, b, z, r });
            }
        }
        gate
    }

    /// Random foot measurements around the filter's own state (so that
    /// some velocities pass the gate and some do not).
    fn random_feet(rng: &mut rand_chacha::ChaCha8Rng, kf: &BaseKf) -> [FootMeasurement; KF_FEET] {
        let mut feet = [FootMeasurement::default(); KF_FEET];
        for (i, f) in feet.iter_mut().enumerate() {
            let mut v = || {
                DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            };
            let (e_p, e_v) = (v(), v());
            *f = FootMeasurement {
                relative_position_m: kf.foot_m(i) - kf.position_m() + 0.01 * e_p,
                relative_velocity_mps: -kf.velocity_mps() + 0.3 * e_v,
                stance: rng.random_bool(0.5),
                ground_height_m: kf.foot_m(i).z + rng.random_range(-0.01..0.01),
            };
        }
        feet
    }

    /// A block of up to 7 scalar measurements with its downdates applied
    /// together equals the dense batch Kalman update (`P − K H P`,
    /// `K = P Hᵀ (H P Hᵀ + R)⁻¹`) to 1e-12 relative, on random states and
    /// covariances; `P` stays symmetric bit for bit.
    #[test]
    fn block_update_equals_dense_kalman_update() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let mut worst: f64 = 0.0;
        for _ in 0..300 {
            let mut a = random_kf(&mut rng);
            let mut b = a.clone();
            let m = rng.random_range(1..=BLOCK);
            let mut ms = Vec::new();
            let mut block = Downdates::new();
            for _ in 0..m {
                let i = rng.random_range(0..KF_N);
                let j = rng.random_range(0..KF_N);
                let s = Scalar {
                    a: i,
                    b: (j != i && rng.random_bool(0.6)).then_some(j),
                    z: rng.random_range(-1.0..1.0),
                    r: rng.random_range(1e-6..1e-1),
                };
                a.measure(&mut block, s.a, s.b, s.z, s.r);
                ms.push(s);
            }
            a.apply(&mut block);
            dense_batch(&mut b, &ms);
            worst = worst.max(rel_diff(&a.x, &b.x)).max(rel_diff(&a.p, &b.p));
            assert!(bit_symmetric(&a.p));
        }
        assert!(worst < 1e-12, "worst relative difference {worst:e}");
    }

    /// [`BaseKf::update`] (velocity gate included) and the mocap position
    /// update equal dense scalar Kalman updates to 1e-12 relative.
    #[test]
    fn foot_update_equals_dense_sequential_updates() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut worst: f64 = 0.0;
        let mut gate = [0u32; 2];
        for _ in 0..300 {
            let mut kf = random_kf(&mut rng);
            let mut reference = kf.clone();
            let feet = random_feet(&mut rng, &kf);
            kf.update(&feet);
            let passed = dense_update(&mut reference, &feet);
            for (g, n) in gate.iter_mut().zip(passed) {
                *g += n;
            }
            worst = worst
                .max(rel_diff(&kf.x, &reference.x))
                .max(rel_diff(&kf.p, &reference.p));
            assert!(bit_symmetric(&kf.p));
            let z = kf.position_m() + DVec3::new(0.01, -0.02, 0.005);
            kf.update_position(z, 0.002);
            for k in 0..3 {
                let s = Scalar {
                    a: k,
                    b: None,
                    z: z[k],
                    r: 0.002 * 0.002,
                };
                dense_scalar(&mut reference, s);
            }
            worst = worst
                .max(rel_diff(&kf.x, &reference.x))
                .max(rel_diff(&kf.p, &reference.p));
        }
        // the cases exercise both sides of the gate
        assert!(
            gate[0] > 10 && gate[1] > 10,
            "gate passed/rejected {gate:?}"
        );
        assert!(worst < 1e-12, "worst relative difference {worst:e}");
    }

    /// The generic build and the clone the machine dispatches to (x86-64-v3
    /// where the CPU has AVX2) give the same bits.
    #[test]
    fn every_clone_gives_the_same_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..200 {
            let mut kf = random_kf(&mut rng);
            let feet = random_feet(&mut rng, &kf);
            let kp = kf.params;
            let mut generic = kf.clone();
            let (x, p) = generic.parts();
            update_feet_generic(&kp, x, p, &feet);
            kf.update(&feet);
            assert!(same_bits(&kf.x, &generic.x) && same_bits(&kf.p, &generic.p));
        }
    }

    /// [`update_feet`] as it was before the lower triangle was mirrored
    /// lazily between feet: every block applied with the whole mirror.
    fn update_feet_whole_mirror(
        kp: &KfParams,
        x: &mut [f64; KF_N],
        p: &mut Cov,
        feet: &[FootMeasurement],
    ) {
        let (rp, rv, rh) = (
            kp.foot_position_std_m.powi(2),
            kp.foot_velocity_std_mps.powi(2),
            kp.foot_height_std_m.powi(2),
        );
        let mut block = Downdates::new();
        for (i, m) in feet.iter().take(KF_FEET).enumerate() {
            let fi = 6 + 3 * i;
            for k in 0..3 {
                let z = m.relative_position_m[k];
                measure(x, p, &mut block, fi + k, Some(k), z, rp);
            }
            if m.stance {
                let z = -m.relative_velocity_mps;
                let var = velocity_variances(p, &block);
                let mut chi2 = 0.0;
                for k in 0..3 {
                    let d = z[k] - x[3 + k];
                    chi2 += d * d / (var[k] + rv);
                }
                if kp.velocity_gate_chi2 <= 0.0 || chi2 <= kp.velocity_gate_chi2 {
                    for k in 0..3 {
                        measure(x, p, &mut block, 3 + k, None, z[k], rv);
                    }
                }
                measure(x, p, &mut block, fi + 2, None, m.ground_height_m, rh);
            }
            apply(p, &mut block);
        }
    }

    /// The lazy mirror between feet gives the bits of the whole mirror
    /// after every foot, for 1 to 4 feet, also when a foot's measurements
    /// are rejected (a negative variance: the block then takes the square
    /// path, which reads the lower rows).
    #[test]
    fn lazy_mirror_gives_the_whole_mirrors_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(10);
        for trial in 0..400 {
            let mut kf = random_kf(&mut rng);
            if trial % 3 == 0 {
                // one foot's variances negative: its position updates fail
                let f = 6 + 3 * rng.random_range(0..KF_FEET);
                for j in f..f + 3 {
                    kf.p[(j, j)] = -1.0;
                }
            }
            let feet = random_feet(&mut rng, &kf);
            let n = 1 + trial % KF_FEET;
            let kp = kf.params;
            let mut whole = kf.clone();
            let (x, p) = whole.parts();
            update_feet_whole_mirror(&kp, x, p, &feet[..n]);
            kf.update(&feet[..n]);
            assert!(
                same_bits(&kf.x, &whole.x) && same_bits(&kf.p, &whole.p),
                "trial {trial}"
            );
        }
    }

    /// [`BaseKf::predict`] gives the bits of the entry-by-entry form on
    /// nalgebra's indexing it replaced, also for an asymmetric `P` (the
    /// same entries are read).
    #[test]
    fn predict_gives_the_entrywise_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        for trial in 0..200 {
            let mut kf = random_kf(&mut rng);
            if trial % 2 == 0 {
                kf.p[(4, 1)] += 1e-3;
                kf.p[(0, 9)] -= 2e-3;
            }
            let a = DVec3::new(rng.random_range(-9.0..9.0), 0.3, -9.8);
            let stance: Vec<bool> = (0..KF_FEET).map(|_| rng.random_bool(0.5)).collect();
            let dt = rng.random_range(0.0..0.01);
            let mut want = kf.clone();
            kf.predict(a, &stance, dt);
            let kp = want.params;
            for k in 0..3 {
                want.x[k] += want.x[3 + k] * dt + 0.5 * a[k] * dt * dt;
                want.x[3 + k] += a[k] * dt;
            }
            let p = &mut want.p;
            let mut pp = [[0.0; 3]; 3];
            for (k, row) in pp.iter_mut().enumerate() {
                for (m, e) in row.iter_mut().enumerate() {
                    *e = p[(k, m)]
                        + dt * (p[(k, 3 + m)] + p[(3 + k, m)])
                        + dt * dt * p[(3 + k, 3 + m)];
                }
            }
            for j in 3..KF_N {
                for k in 0..3 {
                    let e = p[(k, j)] + dt * p[(3 + k, j)];
                    p[(k, j)] = e;
                    p[(j, k)] = e;
                }
            }
            for (k, row) in pp.iter().enumerate() {
                for (m, e) in row.iter().enumerate() {
                    p[(k, m)] = *e;
                }
            }
            for k in 0..3 {
                p[(k, k)] += kp.position_process_std.powi(2) * dt;
                p[(3 + k, 3 + k)] += kp.accel_process_std.powi(2) * dt;
            }
            for (i, &st) in stance.iter().enumerate() {
                let s = if st {
                    kp.stance_foot_process_std
                } else {
                    kp.swing_foot_process_std
                };
                for k in 0..3 {
                    let j = 6 + 3 * i + k;
                    p[(j, j)] += s * s * dt;
                }
            }
            assert!(
                same_bits(&kf.x, &want.x) && same_bits(&kf.p, &want.p),
                "trial {trial}"
            );
        }
    }

    /// Over a long run of predictions and updates (random stance patterns
    /// and measurements, 2 ms steps), `P` stays symmetric bit for bit and
    /// positive definite (Cholesky succeeds), and the state stays finite.
    #[test]
    fn covariance_stays_symmetric_positive_definite() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let mut kf = BaseKf::new(
            KfParams::default(),
            DVec3::new(0.0, 0.0, 0.5),
            DVec3::ZERO,
            &[
                DVec3::new(0.3, 0.2, 0.0),
                DVec3::new(0.3, -0.2, 0.0),
                DVec3::new(-0.3, 0.2, 0.0),
                DVec3::new(-0.3, -0.2, 0.0),
            ],
        );
        for step in 0..20_000 {
            let feet = random_feet(&mut rng, &kf);
            let stance: Vec<bool> = feet.iter().map(|f| f.stance).collect();
            let a = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            kf.predict(a, &stance, 0.002);
            assert!(
                bit_symmetric(&kf.p),
                "step {step}: P not symmetric after predict"
            );
            kf.update(&feet);
            assert!(
                bit_symmetric(&kf.p),
                "step {step}: P not symmetric after update"
            );
            if step % 100 == 0 {
                assert!(
                    kf.p.cholesky().is_some(),
                    "step {step}: P not positive definite"
                );
            }
        }
        assert!(kf.x.iter().all(|x| x.is_finite()));
        assert!(kf.p.cholesky().is_some());
    }
}
