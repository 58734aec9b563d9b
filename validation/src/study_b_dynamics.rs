//! Study B's single-leg dynamics model: a fixed-base 3-DOF leg (hip yaw θ1,
//! thigh θ2, knee θ3) with no ground force, `M(q) q̈ + C(q, q̇) q̇ + G(q) = τ`,
//! derived from the Lagrangian `L = E_k − E_p` as the study does, without the
//! spatial algorithms (no RNEA, CRBA or spatial vectors):
//!
//! - link poses from the D-H chain in plain rotation matrices (the leg's
//!   mount frame: z up, x along the leg at θ = 0): hip `R1 = Rz(θ1)` at the
//!   origin; thigh `R2 = R1 Ry(θ2)` at `R1 (0, l1, 0)`; shank
//!   `R3 = R2 Ry(θ3)` at the thigh origin `+ R2 (l2, 0, 0)`;
//! - `E_k = ½ Σ (m_i v_iᵀ v_i + ω_iᵀ R_i I_i R_iᵀ ω_i)` with the CoM velocity
//!   `v_i = J_i q̇` (J_i the CoM position's derivative, by a five-point
//!   central difference) and `ω_1 = θ̇1 z`, `ω_2 = ω_3 − θ̇3 y₁ = θ̇1 z + θ̇2 y₁`,
//!   `ω_3 = θ̇1 z + (θ̇2 + θ̇3) y₁` (`y₁ = R1 y`, the pitch axes);
//! - `E_p = Σ m_i g z_i`;
//! - `M(q)` is the Hessian of `E_k` in `q̇`: `Σ m JᵀJ + J_ωᵀ R I Rᵀ J_ω`;
//! - `τ = d/dt(∂L/∂q̇) − ∂L/∂q = M q̈ + Ṁ q̇ − ∂E_k/∂q + ∂E_p/∂q`, with
//!   `Ṁ q̇ = (∂/∂ε) M(q + ε q̇) q̇`, `∂E_k/∂q` and `∂E_p/∂q` by five-point
//!   central differences (step 1e-3 rad: truncation ~h⁴, round-off ~1e-13).
//!
//! `engine/tests/prescribed.rs` checks it against RNEA on quad12's fixed-base
//! leg to 1e-9 N·m.

use glam::{DMat3, DVec3};
use quadsim_engine::Model;
use quadsim_engine::control::prescribed::Prescribed;

/// One rigid link: mass, CoM and principal inertia about the CoM, in the
/// link's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegLink {
    /// Mass (kg).
    pub mass_kg: f64,
    /// CoM (m, link frame).
    pub com_m: DVec3,
    /// Inertia about the CoM (kg·m², link axes).
    pub inertia_kgm2: DMat3,
}

/// Study B's leg: lengths and the three links' inertial data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StudyBLegDynamics {
    /// l1: hip-yaw to hip-pitch offset, across the leg (m).
    pub l1_m: f64,
    /// l2: thigh (m).
    pub l2_m: f64,
    /// l3: shank (m).
    pub l3_m: f64,
    /// Hip, thigh, shank.
    pub links: [LegLink; 3],
    /// Gravity's magnitude along −z of the mount frame (m/s²).
    pub gravity_mps2: f64,
}

impl StudyBLegDynamics {
    /// Study B's table (`/work/shared/reference.md`) in quad12's link frames:
    /// hip 0.5 kg, CoM 25 mm along its length (the hip's y), inertia
    /// diag(10, 15, 20) kg·mm²; thigh 1.2 kg, CoM 50 mm along x,
    /// diag(50, 60, 70); shank 0.8 kg, CoM 40 mm along x, diag(30, 40, 50);
    /// g = 9.81 m/s².
    pub const STUDY: StudyBLegDynamics = StudyBLegDynamics {
        l1_m: 0.05,
        l2_m: 0.1,
        l3_m: 0.08,
        links: [
            LegLink {
                mass_kg: 0.5,
                com_m: DVec3::new(0.0, 0.025, 0.0),
                inertia_kgm2: DMat3::from_cols(
                    DVec3::new(1e-5, 0.0, 0.0),
                    DVec3::new(0.0, 1.5e-5, 0.0),
                    DVec3::new(0.0, 0.0, 2e-5),
                ),
            },
            LegLink {
                mass_kg: 1.2,
                com_m: DVec3::new(0.05, 0.0, 0.0),
                inertia_kgm2: DMat3::from_cols(
                    DVec3::new(5e-5, 0.0, 0.0),
                    DVec3::new(0.0, 6e-5, 0.0),
                    DVec3::new(0.0, 0.0, 7e-5),
                ),
            },
            LegLink {
                mass_kg: 0.8,
                com_m: DVec3::new(0.04, 0.0, 0.0),
                inertia_kgm2: DMat3::from_cols(
                    DVec3::new(3e-5, 0.0, 0.0),
                    DVec3::new(0.0, 4e-5, 0.0),
                    DVec3::new(0.0, 0.0, 5e-5),
                ),
            },
        ],
        gravity_mps2: 9.81,
    };

    /// Rotation and origin of each link frame in the mount frame.
    fn frames(&self, q: [f64; 3]) -> [(DMat3, DVec3); 3] {
        let r1 = DMat3::from_rotation_z(q[0]);
        let r2 = r1 * DMat3::from_rotation_y(q[1]);
        let r3 = r2 * DMat3::from_rotation_y(q[2]);
        let o2 = r1 * DVec3::new(0.0, self.l1_m, 0.0);
        let o3 = o2 + r2 * DVec3::new(self.l2_m, 0.0, 0.0);
        [(r1, DVec3::ZERO), (r2, o2), (r3, o3)]
    }

    /// CoM positions of the three links (m, mount frame).
    pub fn com_positions(&self, q: [f64; 3]) -> [DVec3; 3] {
        let f = self.frames(q);
        std::array::from_fn(|i| f[i].1 + f[i].0 * self.links[i].com_m)
    }

    /// The foot (shank tip) in the mount frame (m): Study B's forward
    /// kinematics with a = b = c = 0.
    pub fn foot(&self, q: [f64; 3]) -> DVec3 {
        let f = self.frames(q);
        f[2].1 + f[2].0 * DVec3::new(self.l3_m, 0.0, 0.0)
    }

    /// CoM Jacobians (columns ∂p_i/∂q_k, m/rad), five-point differences.
    fn com_jacobians(&self, q: [f64; 3]) -> [[DVec3; 3]; 3] {
        let mut jac = [[DVec3::ZERO; 3]; 3];
        for k in 0..3 {
            let d = diff5(|e| {
                let mut qq = q;
                qq[k] += e;
                self.com_positions(qq)
            });
            for i in 0..3 {
                jac[i][k] = d[i];
            }
        }
        jac
    }

    /// Angular-velocity Jacobians (columns ∂ω_i/∂q̇_k, mount frame).
    fn angular_jacobians(q: [f64; 3]) -> [[DVec3; 3]; 3] {
        let y1 = DMat3::from_rotation_z(q[0]) * DVec3::Y;
        let z = DVec3::Z;
        [
            [z, DVec3::ZERO, DVec3::ZERO],
            [z, y1, DVec3::ZERO],
            [z, y1, y1],
        ]
    }

    /// The mass matrix `M(q)` (3×3, kg·m²): the Hessian of `E_k` in `q̇`.
    pub fn mass_matrix(&self, q: [f64; 3]) -> [[f64; 3]; 3] {
        let f = self.frames(q);
        let jv = self.com_jacobians(q);
        let jw = Self::angular_jacobians(q);
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            let link = &self.links[i];
            let iw = f[i].0 * link.inertia_kgm2 * f[i].0.transpose();
            for a in 0..3 {
                for b in 0..3 {
                    m[a][b] += link.mass_kg * jv[i][a].dot(jv[i][b]) + jw[i][a].dot(iw * jw[i][b]);
                }
            }
        }
        m
    }

    /// Kinetic energy `E_k(q, q̇)` (J).
    pub fn kinetic_energy(&self, q: [f64; 3], qd: [f64; 3]) -> f64 {
        let m = self.mass_matrix(q);
        let mut e = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                e += 0.5 * qd[a] * m[a][b] * qd[b];
            }
        }
        e
    }

    /// Potential energy `E_p(q) = Σ m g z` (J, zero at the mount's height).
    pub fn potential_energy(&self, q: [f64; 3]) -> f64 {
        let p = self.com_positions(q);
        (0..3)
            .map(|i| self.links[i].mass_kg * self.gravity_mps2 * p[i].z)
            .sum()
    }

    /// Joint torques `τ = M q̈ + C q̇ + G` (N·m) from the Euler–Lagrange
    /// equations (see the module docs).
    pub fn torques(&self, q: [f64; 3], qd: [f64; 3], qdd: [f64; 3]) -> [f64; 3] {
        let m = self.mass_matrix(q);
        // Ṁ q̇ = |q̇| · (∂/∂ε) M(q + ε u) q̇ at ε = 0, u = q̇/|q̇| (a unit
        // direction keeps the difference's truncation error independent of |q̇|)
        let speed = (qd[0] * qd[0] + qd[1] * qd[1] + qd[2] * qd[2]).sqrt();
        let mdot_qd = if speed > 0.0 {
            let u = qd.map(|x| x / speed);
            diff5(|e| {
                let qq = [q[0] + e * u[0], q[1] + e * u[1], q[2] + e * u[2]];
                let me = self.mass_matrix(qq);
                [0, 1, 2].map(|a| speed * (0..3).map(|b| me[a][b] * qd[b]).sum::<f64>())
            })
        } else {
            [0.0; 3]
        };
        let mut tau = [0.0; 3];
        for k in 0..3 {
            let shifted = |e: f64| {
                let mut qq = q;
                qq[k] += e;
                qq
            };
            let dek = diff5(|e| [self.kinetic_energy(shifted(e), qd)])[0];
            let dep = diff5(|e| [self.potential_energy(shifted(e))])[0];
            let inertial: f64 = (0..3).map(|b| m[k][b] * qdd[b]).sum();
            tau[k] = inertial + mdot_qd[k] - dek + dep;
        }
        tau
    }
}

/// Five-point central difference `f'(0) ≈ (f(−2h) − 8f(−h) + 8f(h) − f(2h)) / 12h`
/// of a vector-valued function, h = 1e-3.
fn diff5<const N: usize, T>(f: impl Fn(f64) -> [T; N]) -> [T; N]
where
    T: Copy
        + std::ops::Sub<Output = T>
        + std::ops::Add<Output = T>
        + std::ops::Mul<f64, Output = T>,
{
    const H: f64 = 1e-3;
    let (m2, m1, p1, p2) = (f(-2.0 * H), f(-H), f(H), f(2.0 * H));
    std::array::from_fn(|i| (m2[i] - p2[i] + (p1[i] - m1[i]) * 8.0) * (1.0 / (12.0 * H)))
}

/// Peak and mean of `|τ|` over a run (N·m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TorqueStats {
    /// Largest `|τ|` (N·m).
    pub peak_nm: f64,
    /// Mean `|τ|` (N·m).
    pub mean_abs_nm: f64,
    /// Samples.
    pub samples: u64,
    sum: f64,
}

impl TorqueStats {
    /// Adds one sample.
    pub fn add(&mut self, tau_nm: f64) {
        let a = tau_nm.abs();
        self.peak_nm = self.peak_nm.max(a);
        self.sum += a;
        self.samples += 1;
        self.mean_abs_nm = self.sum / self.samples as f64;
    }
}

/// Study B's Table 4 quantities, model against simulation: hip (thigh,
/// τ2) and knee (τ3) torques of all four legs, pooled.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StudyBTorqueComparison {
    /// The fixed-base Lagrangian model on the prescribed trajectory: hip τ2.
    pub model_hip: TorqueStats,
    /// The model's knee τ3.
    pub model_knee: TorqueStats,
    /// The simulation (hybrid dynamics, ground forces included): hip τ2.
    pub sim_hip: TorqueStats,
    /// The simulation's knee τ3.
    pub sim_knee: TorqueStats,
}

impl StudyBTorqueComparison {
    /// Adds one leg's sample: model and simulated `[τ1, τ2, τ3]` (N·m).
    pub fn add(&mut self, model_nm: [f64; 3], sim_nm: [f64; 3]) {
        self.model_hip.add(model_nm[1]);
        self.model_knee.add(model_nm[2]);
        self.sim_hip.add(sim_nm[1]);
        self.sim_knee.add(sim_nm[2]);
    }

    /// Adds one sample of the comparison at the prescribed controller's last
    /// reference: for every 3-DOF leg of `controller`, Study B's fixed-base
    /// Lagrangian leg model ([`StudyBLegDynamics::STUDY`], no ground force)
    /// on the reference against the simulated joint torques `tau_joints`
    /// (N·m, joints only) at that instant.
    pub fn sample(&mut self, controller: &Prescribed, model: &Model, tau_joints: &[f64]) {
        let nv0 = model.base_nv();
        let (q_ref, qd_ref, qdd_ref) = (
            controller.q_ref(),
            controller.qd_ref(),
            controller.qdd_ref(),
        );
        for leg in controller.legs() {
            let vi = leg.v_indices();
            if vi.len() != 3 {
                continue;
            }
            let j = [vi[0] - nv0, vi[1] - nv0, vi[2] - nv0];
            let m = StudyBLegDynamics::STUDY.torques(
                j.map(|k| q_ref[k]),
                j.map(|k| qd_ref[k]),
                j.map(|k| qdd_ref[k]),
            );
            self.add(m, j.map(|k| tau_joints[k]));
        }
    }

    /// Simulated peak over model peak: (hip, knee).
    pub fn peak_ratio(&self) -> (f64, f64) {
        (
            self.sim_hip.peak_nm / self.model_hip.peak_nm,
            self.sim_knee.peak_nm / self.model_knee.peak_nm,
        )
    }

    /// Simulated mean over model mean: (hip, knee).
    pub fn mean_ratio(&self) -> (f64, f64) {
        (
            self.sim_hip.mean_abs_nm / self.model_hip.mean_abs_nm,
            self.sim_knee.mean_abs_nm / self.model_knee.mean_abs_nm,
        )
    }
}
