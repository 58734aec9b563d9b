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
//! update: no matrix inverse).
//!
//! # One filter per axis
//! Every noise figure is the same on the three world axes and every scalar
//! measurement reads one axis (`p_fi,k − p_k`, `v_k`, `p_fi,z`), so no step
//! couples two axes: from the initial covariance (diagonal, the same on each
//! axis) `P` stays block diagonal over the axes, each block the covariance
//! of one axis's six states `[p_k, v_k, p_f1,k … p_f4,k]`. The filter is
//! therefore run as three 6-state filters, the textbook 18-state one exactly
//! (unit test against the dense 18-state filter in nalgebra). The x and y
//! blocks also see the same measurements (a foot's position on every axis,
//! its velocity on every axis or on none: the gate is one test over the
//! three) and start equal, so they are one matrix, computed once: per foot,
//! two scalar updates of it and three of the z block, against seven of the
//! 18×18 matrix (the update was the estimator's largest cost).

use glam::DVec3;
use multiversion::multiversion;
use nalgebra::{SMatrix, SVector};

/// Number of feet the filter carries.
pub const KF_FEET: usize = 4;
/// State size.
pub const KF_N: usize = 6 + 3 * KF_FEET;
/// States per axis: `[p_k, v_k, p_f1,k … p_f4,k]`.
const AXIS_N: usize = 2 + KF_FEET;
/// Index of the base velocity in an axis's states.
const V: usize = 1;

/// One axis's covariance (symmetric bit for bit).
type AxisCov = [[f64; AXIS_N]; AXIS_N];

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

/// The filter's state and covariance, by axis (module docs).
#[derive(Clone, Debug)]
pub struct BaseKf {
    /// Noise figures.
    pub params: KfParams,
    /// `x[k] = [p_k, v_k, p_f1,k … p_f4,k]` (m, m/s; world axis k).
    x: [[f64; AXIS_N]; 3],
    /// The covariance of the x axis's states, which is also the y axis's.
    p_xy: AxisCov,
    /// The covariance of the z axis's states.
    p_z: AxisCov,
}

impl BaseKf {
    /// A filter at base position `p0`, velocity `v0` and feet `feet` (m,
    /// world), with initial standard deviations 1 cm / 0.1 m/s / 1 cm.
    pub fn new(params: KfParams, p0: DVec3, v0: DVec3, feet: &[DVec3]) -> Self {
        let mut x = [[0.0; AXIS_N]; 3];
        for (k, xk) in x.iter_mut().enumerate() {
            xk[0] = p0[k];
            xk[V] = v0[k];
            for (i, f) in feet.iter().take(KF_FEET).enumerate() {
                xk[2 + i] = f[k];
            }
        }
        let mut p = [[0.0; AXIS_N]; AXIS_N];
        for (j, row) in p.iter_mut().enumerate() {
            row[j] = if j == V { 1e-2 } else { 1e-4 };
        }
        BaseKf {
            params,
            x,
            p_xy: p,
            p_z: p,
        }
    }

    /// Base position estimate (m, world).
    pub fn position_m(&self) -> DVec3 {
        DVec3::new(self.x[0][0], self.x[1][0], self.x[2][0])
    }

    /// Base velocity estimate (m/s, world).
    pub fn velocity_mps(&self) -> DVec3 {
        DVec3::new(self.x[0][V], self.x[1][V], self.x[2][V])
    }

    /// Foot `i`'s position estimate (m, world).
    pub fn foot_m(&self, i: usize) -> DVec3 {
        DVec3::new(self.x[0][2 + i], self.x[1][2 + i], self.x[2][2 + i])
    }

    /// The state in the textbook order `[p, v, p_f1 … p_f4]` (m, m/s; world).
    pub fn state(&self) -> SVector<f64, KF_N> {
        SVector::from_fn(|r, _| {
            let (axis, j) = Self::axis_of(r);
            self.x[axis][j]
        })
    }

    /// The 18 × 18 covariance in the order of [`Self::state`] (zero between
    /// axes).
    pub fn covariance(&self) -> SMatrix<f64, KF_N, KF_N> {
        SMatrix::from_fn(|r, c| {
            let ((ar, i), (ac, j)) = (Self::axis_of(r), Self::axis_of(c));
            match (ar == ac, ar) {
                (false, _) => 0.0,
                (true, 2) => self.p_z[i][j],
                (true, _) => self.p_xy[i][j],
            }
        })
    }

    /// The axis and per-axis index of entry `r` of [`Self::state`].
    fn axis_of(r: usize) -> (usize, usize) {
        match r {
            0..3 => (r, 0),
            3..6 => (r - 3, V),
            _ => ((r - 6) % 3, 2 + (r - 6) / 3),
        }
    }

    /// Prediction over `dt_s` with the world acceleration `accel_world_mps2`
    /// (gravity included); `stance[i]` picks each foot's process noise.
    ///
    /// Per axis, `F = I + Δt E` (E: v → p) changes only the p row and
    /// column: `P'_pp = P_pp + Δt (P_pv + P_vp) + Δt² P_vv` (the sum in the
    /// middle commutes, so it stays symmetric bit for bit) and
    /// `P'_pj = P_pj + Δt P_vj` for every other `j`, mirrored; then `+ Q`.
    pub fn predict(&mut self, accel_world_mps2: DVec3, stance: &[bool], dt_s: f64) {
        let kp = self.params;
        for (xk, a) in self.x.iter_mut().zip(accel_world_mps2.to_array()) {
            xk[0] += xk[V] * dt_s + 0.5 * a * dt_s * dt_s;
            xk[V] += a * dt_s;
        }
        let mut q = [0.0; AXIS_N];
        q[0] = kp.position_process_std.powi(2) * dt_s;
        q[V] = kp.accel_process_std.powi(2) * dt_s;
        for (i, q) in q[2..].iter_mut().enumerate() {
            let s = if stance.get(i).copied().unwrap_or(false) {
                kp.stance_foot_process_std
            } else {
                kp.swing_foot_process_std
            };
            *q = s * s * dt_s;
        }
        for p in [&mut self.p_xy, &mut self.p_z] {
            let pp = p[0][0] + dt_s * (p[0][V] + p[V][0]) + dt_s * dt_s * p[V][V];
            for j in 1..AXIS_N {
                let e = p[0][j] + dt_s * p[V][j];
                p[0][j] = e;
                p[j][0] = e;
            }
            p[0][0] = pp;
            for (j, q) in q.iter().enumerate() {
                p[j][j] += q;
            }
        }
    }

    /// A direct measurement `z` of the base position (m, world), each axis
    /// with standard deviation `std_m` (motion capture).
    pub fn update_position(&mut self, z: DVec3, std_m: f64) {
        let r = std_m * std_m;
        let [x, y, zx] = &mut self.x;
        measure(&mut self.p_xy, [x, y], 0, None, [z.x, z.y], r);
        measure(&mut self.p_z, [zx], 0, None, [z.z], r);
    }

    /// The measurement update with each foot's kinematics: the scalar
    /// measurements one after the other (sequential update), foot by foot:
    /// its position; on a stance foot, the base velocity (unless the gate
    /// rejects it) and its height.
    pub fn update(&mut self, feet: &[FootMeasurement]) {
        update_feet(self, feet);
    }
}

/// [`BaseKf::update`]'s body, compiled for x86-64-v3 (AVX2; the covariance
/// rows four entries to a register) and the generic target, the CPU's
/// choice at the first call; no fused multiply–add, so both give the same
/// bits. A free function: multiversion takes no `self`.
#[multiversion(targets("x86_64+avx2+fma"))]
fn update_feet(kf: &mut BaseKf, feet: &[FootMeasurement]) {
    update_feet_body(kf, feet);
}

/// [`update_feet`] compiled for the build's generic target only: for the
/// test that every clone gives the same bits.
#[cfg(test)]
#[inline(never)]
fn update_feet_generic(kf: &mut BaseKf, feet: &[FootMeasurement]) {
    update_feet_body(kf, feet);
}

#[inline(always)]
fn update_feet_body(kf: &mut BaseKf, feet: &[FootMeasurement]) {
    let kp = kf.params;
    let rp = kp.foot_position_std_m.powi(2);
    let rv = kp.foot_velocity_std_mps.powi(2);
    let rh = kp.foot_height_std_m.powi(2);
    let (p_xy, p_z) = (&mut kf.p_xy, &mut kf.p_z);
    let [x, y, z] = &mut kf.x;
    for (i, m) in feet.iter().take(KF_FEET).enumerate() {
        let f = 2 + i;
        let r = m.relative_position_m;
        measure(p_xy, [&mut *x, &mut *y], f, Some(0), [r.x, r.y], rp);
        measure(p_z, [&mut *z], f, Some(0), [r.z], rp);
        if m.stance {
            // a slipping or still-landing foot moves: reject its velocity
            // when the innovation is beyond the gate (χ² with 3 dof)
            let zv = -m.relative_velocity_mps;
            let var = [p_xy[V][V], p_xy[V][V], p_z[V][V]];
            let v = [x[V], y[V], z[V]];
            let mut chi2 = 0.0;
            for k in 0..3 {
                let d = zv[k] - v[k];
                chi2 += d * d / (var[k] + rv);
            }
            if kp.velocity_gate_chi2 <= 0.0 || chi2 <= kp.velocity_gate_chi2 {
                measure(p_xy, [&mut *x, &mut *y], V, None, [zv.x, zv.y], rv);
                measure(p_z, [&mut *z], V, None, [zv.z], rv);
            }
            measure(p_z, [&mut *z], f, None, [m.ground_height_m], rh);
        }
    }
}

/// The scalar measurement `z = x[a] − x[b]` (`b = None`: `z = x[a]`) with
/// variance `r`, on the `L` axes whose states `xs` share the covariance `p`
/// (each axis with its own `z`): one sequential Kalman update, `u = P h`,
/// `s = hᵀu + r`, `x ← x + u (z − hᵀx) / s` per axis and `P ← P − g gᵀ`
/// with `g = u / √s` (the dense `P − K h P`; entry by entry `P_ij − g_i g_j`,
/// whose product commutes, so `P` stays symmetric bit for bit). Skipped
/// when `s` is not a positive finite number.
#[inline(always)]
fn measure<const L: usize>(
    p: &mut AxisCov,
    xs: [&mut [f64; AXIS_N]; L],
    a: usize,
    b: Option<usize>,
    z: [f64; L],
    r: f64,
) {
    // `hᵀv`: `v[a] − v[b]` (or `v[a]`)
    let h = |v: &[f64; AXIS_N]| match b {
        Some(b) => v[a] - v[b],
        None => v[a],
    };
    // `u = P h`, row by row (`P` is symmetric)
    let mut u = [0.0; AXIS_N];
    for (u, row) in u.iter_mut().zip(p.iter()) {
        *u = h(row);
    }
    let s = h(&u) + r;
    if s <= 0.0 || !s.is_finite() {
        return;
    }
    for (x, z) in xs.into_iter().zip(z) {
        let gain = (z - h(x)) / s;
        for (x, u) in x.iter_mut().zip(&u) {
            *x += u * gain;
        }
    }
    let scale = 1.0 / s.sqrt();
    let g = u.map(|u| u * scale);
    for (row, gi) in p.iter_mut().zip(&g) {
        for (e, gj) in row.iter_mut().zip(&g) {
            *e -= gi * gj;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    type Dense = (SVector<f64, KF_N>, SMatrix<f64, KF_N, KF_N>);

    /// Largest |a − b| over the largest |b|.
    fn rel_diff<const R: usize, const C: usize>(
        a: &SMatrix<f64, R, C>,
        b: &SMatrix<f64, R, C>,
    ) -> f64 {
        (a - b).amax() / b.amax().max(1e-300)
    }

    /// The textbook prediction on the 18 states: `x ← F x + B a`,
    /// `P ← F P Fᵀ + Q` with `F = I + Δt E` (E: v → p).
    fn dense_predict((x, p): &mut Dense, kp: &KfParams, a: DVec3, stance: &[bool], dt: f64) {
        let mut f = SMatrix::<f64, KF_N, KF_N>::identity();
        for k in 0..3 {
            f[(k, 3 + k)] = dt;
            x[k] += x[3 + k] * dt + 0.5 * a[k] * dt * dt;
            x[3 + k] += a[k] * dt;
        }
        let mut q = SVector::<f64, KF_N>::zeros();
        for k in 0..3 {
            q[k] = kp.position_process_std.powi(2) * dt;
            q[3 + k] = kp.accel_process_std.powi(2) * dt;
            for (i, &st) in stance.iter().enumerate() {
                let s = if st {
                    kp.stance_foot_process_std
                } else {
                    kp.swing_foot_process_std
                };
                q[6 + 3 * i + k] = s * s * dt;
            }
        }
        *p = f * *p * f.transpose() + SMatrix::from_diagonal(&q);
    }

    /// One scalar update `z = x[a] − x[b]` in dense form: `K = P hᵀ / s`,
    /// `x ← x + K (z − h x)`, `P ← P − K h P`.
    fn dense_scalar((x, p): &mut Dense, a: usize, b: Option<usize>, z: f64, r: f64) {
        let mut h = SMatrix::<f64, 1, KF_N>::zeros();
        h[a] = 1.0;
        if let Some(b) = b {
            h[b] = -1.0;
        }
        let sv = (h * *p * h.transpose())[0] + r;
        let k = *p * h.transpose() / sv;
        *x += k * (z - (h * *x)[0]);
        *p -= k * h * *p;
    }

    /// [`BaseKf::update`] as dense scalar updates on the 18 states, in the
    /// textbook order (each foot's position x, y, z; velocity x, y, z;
    /// height), the gate read from the dense `P`. Returns how many stance
    /// feet's velocities passed and failed the gate.
    fn dense_update(d: &mut Dense, kp: &KfParams, feet: &[FootMeasurement]) -> [u32; 2] {
        let mut gate = [0; 2];
        let rp = kp.foot_position_std_m.powi(2);
        let rv = kp.foot_velocity_std_mps.powi(2);
        let rh = kp.foot_height_std_m.powi(2);
        for (i, m) in feet.iter().enumerate() {
            let fi = 6 + 3 * i;
            for k in 0..3 {
                dense_scalar(d, fi + k, Some(k), m.relative_position_m[k], rp);
            }
            if m.stance {
                let z = -m.relative_velocity_mps;
                let chi2: f64 = (0..3)
                    .map(|k| (z[k] - d.0[3 + k]).powi(2) / (d.1[(3 + k, 3 + k)] + rv))
                    .sum();
                if chi2 <= kp.velocity_gate_chi2 {
                    gate[0] += 1;
                    for k in 0..3 {
                        dense_scalar(d, 3 + k, None, z[k], rv);
                    }
                } else {
                    gate[1] += 1;
                }
                dense_scalar(d, fi + 2, None, m.ground_height_m, rh);
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

    fn quad_feet() -> [DVec3; KF_FEET] {
        [
            DVec3::new(0.3, 0.2, 0.0),
            DVec3::new(0.3, -0.2, 0.0),
            DVec3::new(-0.3, 0.2, 0.0),
            DVec3::new(-0.3, -0.2, 0.0),
        ]
    }

    /// The per-axis filters (x and y sharing one covariance) are the
    /// textbook 18-state filter: over 4,000 steps of predictions, foot
    /// updates (velocity gate on both sides) and motion-capture updates,
    /// the state and the whole 18 × 18 covariance of the dense filter in
    /// nalgebra agree to 1e-10 relative.
    #[test]
    fn axis_filters_equal_the_dense_18_state_filter() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let kp = KfParams::default();
        let mut kf = BaseKf::new(
            kp,
            DVec3::new(0.1, -0.2, 0.5),
            DVec3::new(0.3, 0.0, 0.0),
            &quad_feet(),
        );
        let mut dense = (kf.state(), kf.covariance());
        let (mut worst, mut gate) = (0.0f64, [0u32; 2]);
        for step in 0..4_000 {
            let a = DVec3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
            );
            let stance: Vec<bool> = (0..KF_FEET).map(|_| rng.random_bool(0.5)).collect();
            kf.predict(a, &stance, 0.002);
            dense_predict(&mut dense, &kp, a, &stance, 0.002);
            let feet = random_feet(&mut rng, &kf);
            kf.update(&feet);
            for (g, n) in gate.iter_mut().zip(dense_update(&mut dense, &kp, &feet)) {
                *g += n;
            }
            if step % 10 == 0 {
                let z = kf.position_m() + DVec3::new(0.01, -0.02, 0.005);
                kf.update_position(z, 0.002);
                for k in 0..3 {
                    dense_scalar(&mut dense, k, None, z[k], 0.002 * 0.002);
                }
            }
            worst = worst
                .max(rel_diff(&kf.state(), &dense.0))
                .max(rel_diff(&kf.covariance(), &dense.1));
        }
        assert!(
            gate[0] > 100 && gate[1] > 100,
            "gate passed/rejected {gate:?}"
        );
        assert!(worst < 1e-10, "worst relative difference {worst:e}");
    }

    /// Over a long run of predictions and updates (random stance patterns
    /// and measurements, 2 ms steps), each axis's covariance stays
    /// symmetric bit for bit and the whole one positive definite
    /// (Cholesky succeeds), and the state stays finite.
    #[test]
    fn covariance_stays_symmetric_positive_definite() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let mut kf = BaseKf::new(
            KfParams::default(),
            DVec3::new(0.0, 0.0, 0.5),
            DVec3::ZERO,
            &quad_feet(),
        );
        let symmetric = |p: &AxisCov| {
            (0..AXIS_N).all(|i| (0..AXIS_N).all(|j| p[i][j].to_bits() == p[j][i].to_bits()))
        };
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
                symmetric(&kf.p_xy) && symmetric(&kf.p_z),
                "step {step}: after predict"
            );
            kf.update(&feet);
            assert!(
                symmetric(&kf.p_xy) && symmetric(&kf.p_z),
                "step {step}: after update"
            );
            if step % 100 == 0 {
                assert!(
                    kf.covariance().cholesky().is_some(),
                    "step {step}: P not positive definite"
                );
            }
        }
        assert!(kf.state().iter().all(|x| x.is_finite()));
    }

    /// The generic build and the clone the machine dispatches to (x86-64-v3
    /// where the CPU has AVX2) give the same bits, over a run of
    /// predictions and updates.
    #[test]
    fn every_clone_gives_the_same_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let mut kf = BaseKf::new(KfParams::default(), DVec3::ZERO, DVec3::ZERO, &quad_feet());
        let mut generic = kf.clone();
        for step in 0..2_000 {
            let feet = random_feet(&mut rng, &kf);
            let stance: Vec<bool> = feet.iter().map(|f| f.stance).collect();
            let a = DVec3::new(0.3, -0.2, rng.random_range(-1.0..1.0));
            kf.predict(a, &stance, 0.002);
            generic.predict(a, &stance, 0.002);
            kf.update(&feet);
            update_feet_generic(&mut generic, &feet);
            let bits = |k: &BaseKf| -> Vec<u64> {
                k.state()
                    .iter()
                    .chain(k.covariance().iter())
                    .map(|v| v.to_bits())
                    .collect()
            };
            assert_eq!(bits(&kf), bits(&generic), "step {step}");
        }
    }

    /// A measurement whose innovation variance is not positive (a broken
    /// covariance) changes nothing.
    #[test]
    fn a_non_positive_innovation_variance_is_skipped() {
        let mut kf = BaseKf::new(KfParams::default(), DVec3::ZERO, DVec3::ZERO, &quad_feet());
        kf.p_z[0][0] = -1.0;
        let before = (kf.state(), kf.covariance());
        kf.update_position(DVec3::new(0.1, 0.1, 0.3), 0.001);
        assert_eq!(kf.position_m().z, 0.0);
        assert_eq!(kf.covariance()[(2, 2)], before.1[(2, 2)]);
        // the x and y axes still take theirs
        assert!(kf.position_m().x > 0.09 && kf.position_m().y > 0.09);
    }
}
