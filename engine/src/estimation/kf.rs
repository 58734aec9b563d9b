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
    pub fn predict(&mut self, accel_world_mps2: DVec3, stance: &[bool], dt_s: f64) {
        let kp = self.params;
        for k in 0..3 {
            self.x[k] += self.x[3 + k] * dt_s + 0.5 * accel_world_mps2[k] * dt_s * dt_s;
            self.x[3 + k] += accel_world_mps2[k] * dt_s;
        }
        // P ← F P Fᵀ with F = I + Δt E (E: v → p), as a row then a column
        // operation (F is the identity but for three entries)
        for k in 0..3 {
            for j in 0..KF_N {
                let a = self.p[(3 + k, j)];
                self.p[(k, j)] += dt_s * a;
            }
        }
        for k in 0..3 {
            for i in 0..KF_N {
                let a = self.p[(i, 3 + k)];
                self.p[(i, k)] += dt_s * a;
            }
        }
        for k in 0..3 {
            self.p[(k, k)] += kp.position_process_std.powi(2) * dt_s;
            self.p[(3 + k, 3 + k)] += kp.accel_process_std.powi(2) * dt_s;
        }
        for i in 0..KF_FEET {
            let s = if stance.get(i).copied().unwrap_or(false) {
                kp.stance_foot_process_std
            } else {
                kp.swing_foot_process_std
            };
            for k in 0..3 {
                let j = 6 + 3 * i + k;
                self.p[(j, j)] += s * s * dt_s;
            }
        }
    }

    /// The scalar measurement `z = x[a] − x[b]` (`b = None`: `z = x[a]`) with
    /// variance `r`: one sequential Kalman update.
    ///
    /// In place, without temporaries: `P h` is a column difference (h is
    /// sparse), then `x ← x + K (z − hᵀx)` and the rank-one `P ← P − K (P h)ᵀ`
    /// with `K = P h / s`, entry by entry with the same operations as the
    /// dense form (`k_i = ph_i / s`, `P_ij − k_i ph_j`), so the result is the
    /// same bit for bit (tested against the dense form).
    fn update_scalar(&mut self, a: usize, b: Option<usize>, z: f64, r: f64) {
        let mut ph = [0.0; KF_N];
        ph.copy_from_slice(self.p.column(a).as_slice());
        let mut hx = self.x[a];
        if let Some(b) = b {
            for (v, pb) in ph.iter_mut().zip(self.p.column(b).iter()) {
                *v -= pb;
            }
            hx -= self.x[b];
        }
        let s = ph[a] - b.map_or(0.0, |b| ph[b]) + r;
        if s <= 0.0 || !s.is_finite() {
            return;
        }
        let mut k = [0.0; KF_N];
        for (k, v) in k.iter_mut().zip(&ph) {
            *k = v / s;
        }
        let innovation = z - hx;
        for (x, k) in self.x.iter_mut().zip(&k) {
            *x += k * innovation;
        }
        rank_one_downdate(self.p.as_mut_slice(), &k, &ph);
    }

    /// [`BaseKf::update_scalar`] in nalgebra's dense matrix algebra (the
    /// reference the in-place form is tested against).
    #[cfg(test)]
    fn update_scalar_dense(&mut self, a: usize, b: Option<usize>, z: f64, r: f64) {
        let mut ph = self.p.column(a).into_owned();
        let mut hx = self.x[a];
        if let Some(b) = b {
            ph -= self.p.column(b);
            hx -= self.x[b];
        }
        let s = ph[a] - b.map_or(0.0, |b| ph[b]) + r;
        if s <= 0.0 || !s.is_finite() {
            return;
        }
        let k = ph / s;
        self.x += k * (z - hx);
        self.p -= k * ph.transpose();
    }

    /// `P ← (P + Pᵀ) / 2` in place, against round-off (the same operations
    /// as the dense form: `0.5 (P_ij + P_ji)`, diagonal included).
    fn symmetrise(&mut self) {
        for j in 0..KF_N {
            for i in 0..=j {
                let m = 0.5 * (self.p[(i, j)] + self.p[(j, i)]);
                self.p[(i, j)] = m;
                self.p[(j, i)] = m;
            }
        }
    }

    /// A direct measurement `z` of the base position (m, world), each axis
    /// with standard deviation `std_m` (motion capture).
    pub fn update_position(&mut self, z: DVec3, std_m: f64) {
        let r = std_m * std_m;
        for k in 0..3 {
            self.update_scalar(k, None, z[k], r);
        }
        self.symmetrise();
    }

    /// The measurement update with each foot's kinematics.
    pub fn update(&mut self, feet: &[FootMeasurement]) {
        let kp = self.params;
        let rp = kp.foot_position_std_m.powi(2);
        let rv = kp.foot_velocity_std_mps.powi(2);
        let rh = kp.foot_height_std_m.powi(2);
        for (i, m) in feet.iter().take(KF_FEET).enumerate() {
            let fi = 6 + 3 * i;
            for k in 0..3 {
                self.update_scalar(fi + k, Some(k), m.relative_position_m[k], rp);
            }
            if m.stance {
                // a slipping or still-landing foot moves: reject its velocity
                // when the innovation is beyond the gate (χ² with 3 dof)
                let z = -m.relative_velocity_mps;
                let d = z - self.velocity_mps();
                let mut chi2 = 0.0;
                for k in 0..3 {
                    chi2 += d[k] * d[k] / (self.p[(3 + k, 3 + k)] + rv);
                }
                if kp.velocity_gate_chi2 <= 0.0 || chi2 <= kp.velocity_gate_chi2 {
                    for k in 0..3 {
                        self.update_scalar(3 + k, None, z[k], rv);
                    }
                }
                self.update_scalar(fi + 2, None, m.ground_height_m, rh);
            }
        }
        // symmetrised against round-off
        self.symmetrise();
    }
}

/// `P ← P − k phᵀ` on the column-major `P` (n × n, n = [`KF_N`]), entry by
/// entry (`P_ij − k_i ph_j`: no fused multiply–add, so every build gives the
/// same bits); the x86-64-v3 clone runs four rows per AVX register.
#[multiversion(targets("x86_64+avx2+fma"))]
fn rank_one_downdate(p: &mut [f64], k: &[f64; KF_N], ph: &[f64; KF_N]) {
    for (col, phj) in p.chunks_exact_mut(KF_N).zip(ph) {
        for (p, k) in col.iter_mut().zip(k) {
            *p -= k * phj;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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

    /// The in-place scalar update and symmetrisation equal nalgebra's dense
    /// algebra bit for bit, for position, velocity and height measurements,
    /// on random states and covariances (unsymmetric P between updates too).
    #[test]
    fn in_place_update_equals_dense_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        for _ in 0..200 {
            let mut a = random_kf(&mut rng);
            let mut b = a.clone();
            for _ in 0..12 {
                let i = rng.random_range(0..KF_N);
                let j = rng.random_range(0..KF_N);
                let other = (j != i && rng.random_bool(0.6)).then_some(j);
                let z = rng.random_range(-1.0..1.0);
                let r = rng.random_range(1e-6..1e-1);
                a.update_scalar(i, other, z, r);
                b.update_scalar_dense(i, other, z, r);
                assert!(same_bits(&a.x, &b.x));
                assert!(same_bits(&a.p, &b.p));
            }
            a.symmetrise();
            b.p = 0.5 * (b.p + b.p.transpose());
            assert!(same_bits(&a.p, &b.p));
        }
    }
}
