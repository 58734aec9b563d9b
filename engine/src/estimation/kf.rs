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
    fn update_scalar(&mut self, a: usize, b: Option<usize>, z: f64, r: f64) {
        // P h and hᵀ P h for the sparse h = e_a − e_b
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
        // P ← P − K (P h)ᵀ
        self.p -= k * ph.transpose();
    }

    /// A direct measurement `z` of the base position (m, world), each axis
    /// with standard deviation `std_m` (motion capture).
    pub fn update_position(&mut self, z: DVec3, std_m: f64) {
        let r = std_m * std_m;
        for k in 0..3 {
            self.update_scalar(k, None, z[k], r);
        }
        self.p = 0.5 * (self.p + self.p.transpose());
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
        self.p = 0.5 * (self.p + self.p.transpose());
    }
}
