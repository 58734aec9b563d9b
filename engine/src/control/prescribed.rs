//! Study B's way of walking: joint angles prescribed by the inverse kinematics
//! of a foot trajectory, with no balance feedback.
//!
//! # The foot trajectory (a trot, in the body frame)
//! Each foot moves about its *neutral point* (its position in the base frame
//! at the start configuration, with its height replaced by `−body_height_m`,
//! so that the base stands `body_height_m` above flat ground). Diagonal legs
//! move together: the legs whose mounts lie front-left or hind-right (LF, RH)
//! start at phase 0, the other diagonal half a period later. With the phase
//! `φ ∈ [0, 1)` and duty factor `β`, along the body's x axis:
//! - **stance** (`φ < β`): the foot slides backward at the constant speed
//!   `v = L / (β T)` from `+L/2` to `−L/2` (`L` = `step_length_m`, the stroke);
//!   a foot that does not slip pushes the body forward at `v`;
//! - **swing** (`s = (φ − β)/(1 − β)`): `x = −L/2 + d s + Δ (10s³ − 15s⁴ + 6s⁵)`
//!   with `d = −v (1 − β) T` and `Δ = L − d` (the quintic that joins the
//!   stance at both ends with equal position, velocity and zero
//!   acceleration), and the lift `z = h · 64 s³ (1 − s)³` (apex `h` at
//!   mid-swing, zero velocity and acceleration at lift-off and touchdown).
//!
//! The trajectory is C² (continuous joint accelerations), which hybrid
//! dynamics needs for bounded torques. Stroke and lift ramp in with a
//! smoothstep over `ramp_s` so the robot starts from its standing pose.
//!
//! Joint angles come from the closed-form leg IK ([`crate::legs`]); joint
//! velocities, accelerations and jerks are central differences of the IK
//! along the trajectory (step 0.1 ms: truncation ~1e-8 relative, round-off
//! ~1e-8 rad/s² and ~1e-4 rad/s³, far below the motion's scale).
//!
//! # Applying it
//! - [`PrescribedMode::Hybrid`] (Study B's): the joints follow the reference
//!   exactly (the integrator's [`ImposedJoints`]: joint accelerations
//!   imposed, base free under gravity and contact, torques from the
//!   dynamics; a PD term on acceleration, `kp` 1/s², `kd` 1/s, removes
//!   integration drift). Torques are not limited.
//! - [`PrescribedMode::Pd`]: stiff joint PD toward the reference,
//!   `τ = kp (q_r − q) + kd (q̇_r − q̇)` (N·m/rad, N·m·s/rad), at the
//!   controller rate, saturated at the effort limits like every actuator.
//!   Default gains: each joint at a 15 Hz bandwidth for its apparent inertia
//!   ([`PrescribedParams::defaults_for`]).
//!
//! # Defaults (Study B)
//! Study B trots at 93 mm/s with a stride frequency in its "good" range
//! (1–2 Hz) and gives no stroke, lift or height. quadsim's defaults: period
//! 0.5 s (2 Hz, the top of that range: a 12 kg quad12 on two feet tips about
//! its support diagonal with a time constant `√(h/g)` ≈ 0.12 s, so shorter
//! diagonal supports rock it less), duty factor 0.5, stroke 23.3 mm (so the
//! nominal speed `L/(βT)` is Study B's 93.3 mm/s), lift 20 mm, body height
//! the start height (quad12's stance: 0.14 m), ramp one period.

use crate::data::Data;
use crate::description::RobotDescription;
use crate::integrate::ImposedJoints;
use crate::legs::ik::IkOptions;
use crate::legs::{FootPoint, LegError, LegKinematics};
use crate::model::Model;
use glam::DVec3;

use super::joint_pd::bandwidth_gains;

/// How the prescribed joint motion is applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrescribedMode {
    /// Joint accelerations imposed on the integrator; torques are an output.
    Hybrid,
    /// Joint PD toward the reference; torques are saturated.
    Pd,
}

/// The trot foot trajectory (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrotTrajectory {
    /// Gait period T (s); the stride frequency is 1/T.
    pub period_s: f64,
    /// Fraction β of the period a foot is in stance (0.5: pure trot).
    pub duty_factor: f64,
    /// Stance stroke L of a foot along the body's x axis (m).
    pub step_length_m: f64,
    /// Swing apex h above the stance line (m).
    pub lift_height_m: f64,
    /// Height of the base origin above the feet's stance line (m); `None`:
    /// the start configuration's.
    pub body_height_m: Option<f64>,
    /// Time over which stroke and lift grow from 0 to full (s; 0: none).
    pub ramp_s: f64,
}

impl Default for TrotTrajectory {
    /// Study B: 93.3 mm/s at 2 Hz (see the module docs).
    fn default() -> Self {
        TrotTrajectory {
            period_s: 0.5,
            duty_factor: 0.5,
            step_length_m: 0.09334 * 0.5 * 0.5,
            lift_height_m: 0.02,
            body_height_m: None,
            ramp_s: 0.5,
        }
    }
}

impl TrotTrajectory {
    /// The body speed a non-slipping stance foot gives, `L / (β T)` (m/s).
    pub fn nominal_speed_mps(&self) -> f64 {
        self.step_length_m / (self.duty_factor * self.period_s)
    }

    /// Checks the numbers; the error names the field.
    ///
    /// # Errors
    /// A message naming the bad field.
    pub fn validate(&self) -> Result<(), String> {
        let finite_pos = |x: f64| x.is_finite() && x > 0.0;
        if !finite_pos(self.period_s) {
            return Err(format!("period_s must be > 0, got {}", self.period_s));
        }
        if !(self.duty_factor > 0.0 && self.duty_factor < 1.0) {
            return Err(format!(
                "duty_factor must lie in (0, 1), got {}",
                self.duty_factor
            ));
        }
        for (name, x) in [
            ("step_length_m", self.step_length_m),
            ("lift_height_m", self.lift_height_m),
            ("ramp_s", self.ramp_s),
        ] {
            if !(x.is_finite() && x >= 0.0) {
                return Err(format!("{name} must be ≥ 0, got {x}"));
            }
        }
        if let Some(h) = self.body_height_m
            && !finite_pos(h)
        {
            return Err(format!("body_height_m must be > 0, got {h}"));
        }
        Ok(())
    }

    /// Ramp factor in [0, 1] at `t_s`: the quintic smoothstep, C² so the
    /// reference accelerations stay continuous.
    fn ramp(&self, t_s: f64) -> f64 {
        if self.ramp_s <= 0.0 {
            return 1.0;
        }
        let x = (t_s / self.ramp_s).clamp(0.0, 1.0);
        x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
    }

    /// Offset of a foot from its neutral point (m, body frame: x forward,
    /// z up) at `t_s`, for a leg whose phase lags by `phase_offset` periods.
    pub fn foot_offset_m(&self, t_s: f64, phase_offset: f64) -> DVec3 {
        let r = self.ramp(t_s);
        let big_t = self.period_s;
        let beta = self.duty_factor;
        let l = self.step_length_m * r;
        let phi = (t_s / big_t - phase_offset).rem_euclid(1.0);
        if phi < beta {
            DVec3::new(0.5 * l - l * phi / beta, 0.0, 0.0)
        } else {
            let s = (phi - beta) / (1.0 - beta);
            let d = -l * (1.0 - beta) / beta;
            let delta = l - d;
            let x = -0.5 * l + d * s + delta * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
            let u = s * (1.0 - s);
            let z = self.lift_height_m * r * 64.0 * u * u * u;
            DVec3::new(x, 0.0, z)
        }
    }

    /// Whether the leg with `phase_offset` is in stance at `t_s`.
    pub fn in_stance(&self, t_s: f64, phase_offset: f64) -> bool {
        (t_s / self.period_s - phase_offset).rem_euclid(1.0) < self.duty_factor
    }
}

/// Everything that configures a [`Prescribed`] controller.
#[derive(Clone, Debug, PartialEq)]
pub struct PrescribedParams {
    /// Hybrid dynamics or joint PD.
    pub mode: PrescribedMode,
    /// The foot trajectory.
    pub trot: TrotTrajectory,
    /// Hybrid mode: drift-correction stiffness (1/s²). Default (2π·20 Hz)².
    pub hybrid_kp_per_s2: f64,
    /// Hybrid mode: drift-correction damping (1/s). Default 2·2π·20 Hz
    /// (critical).
    pub hybrid_kd_per_s: f64,
    /// PD mode: stiffness per joint (N·m/rad); see [`PrescribedParams::defaults_for`].
    pub pd_kp_nm_per_rad: Vec<f64>,
    /// PD mode: damping per joint (N·m·s/rad).
    pub pd_kd_nms_per_rad: Vec<f64>,
}

impl PrescribedParams {
    /// Defaults for `model` at the start configuration `q` (nq): hybrid
    /// mode, Study B's trot, drift correction at 20 Hz critically damped,
    /// PD gains from [`bandwidth_gains`] at `q`, 15 Hz, critically damped
    /// (`kp = M_ii ω²`, `kd = 2 M_ii ω`: quad12's stance gives about 11 N·m/rad
    /// and 0.24 N·m·s/rad at the knee, 0.2–0.3 N·m·s/rad per 0.01 kg·m² of
    /// apparent inertia elsewhere). Uniform stiff gains (100 N·m/rad,
    /// 2 N·m·s/rad) went unstable on quad12's light knee under the 500 Hz
    /// sampled controller (`kd T / M_ii` ≈ 3 > 2).
    pub fn defaults_for(model: &Model, q: &[f64]) -> PrescribedParams {
        let w = std::f64::consts::TAU * 20.0;
        let mut data = Data::new(model);
        let (kp, kd) = bandwidth_gains(model, &mut data, q, PD_BANDWIDTH_HZ, 1.0);
        PrescribedParams {
            mode: PrescribedMode::Hybrid,
            trot: TrotTrajectory::default(),
            hybrid_kp_per_s2: w * w,
            hybrid_kd_per_s: 2.0 * w,
            pd_kp_nm_per_rad: kp,
            pd_kd_nms_per_rad: kd,
        }
    }
}

/// Closed-loop bandwidth of the default PD gains (Hz).
pub const PD_BANDWIDTH_HZ: f64 = 15.0;

/// Why a prescribed controller cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PrescribedError {
    /// The legs could not be identified from the model.
    #[error("prescribed: {0}")]
    Legs(#[from] LegError),
    /// A trajectory parameter is out of range.
    #[error("prescribed: {0}")]
    Trajectory(String),
    /// A gain list has the wrong length.
    #[error("prescribed: {field} has {got} entries, the robot has {expected} joints")]
    GainLength {
        /// The field.
        field: &'static str,
        /// Entries given.
        got: usize,
        /// Joints.
        expected: usize,
    },
    /// The start configuration does not have a floating base and joints.
    #[error("prescribed: the start configuration has {got} entries, the model needs {expected}")]
    StartSize {
        /// Entries given.
        got: usize,
        /// nq.
        expected: usize,
    },
}

/// The prescribed-trajectory controller of one robot (see the module docs).
#[derive(Clone, Debug)]
pub struct Prescribed {
    /// Parameters.
    pub params: PrescribedParams,
    legs: Vec<LegKinematics>,
    /// Neutral foot point of each leg (m, base frame).
    neutral_m: Vec<DVec3>,
    /// Phase lag of each leg (periods).
    phase_offset: Vec<f64>,
    /// Reference of the last update (joints only): angles, velocities,
    /// accelerations.
    q_ref: Vec<f64>,
    qd_ref: Vec<f64>,
    qdd_ref: Vec<f64>,
    qddd_ref: Vec<f64>,
    scratch: [Vec<f64>; 5],
    ik: IkOptions,
    /// Time of the last update (s).
    t_ref_s: f64,
}

/// Central-difference step of the reference's derivatives (s).
const DIFF_STEP_S: f64 = 1e-4;

impl Prescribed {
    /// A controller for `model` (compiled from `desc`) starting at the
    /// configuration `q_start` (nq): the feet's neutral points are their
    /// positions there, at `body_height_m` below the base when given.
    ///
    /// # Errors
    /// [`PrescribedError`] for a robot whose legs have no closed-form IK,
    /// bad trajectory numbers or gain lengths.
    pub fn new(
        desc: &RobotDescription,
        model: &Model,
        params: PrescribedParams,
        q_start: &[f64],
    ) -> Result<Prescribed, PrescribedError> {
        params
            .trot
            .validate()
            .map_err(PrescribedError::Trajectory)?;
        if q_start.len() != model.nq {
            return Err(PrescribedError::StartSize {
                got: q_start.len(),
                expected: model.nq,
            });
        }
        let nj = model.nv - model.base_nv();
        for (field, v) in [
            ("pd_kp_nm_per_rad", &params.pd_kp_nm_per_rad),
            ("pd_kd_nms_per_rad", &params.pd_kd_nms_per_rad),
        ] {
            if v.len() != nj {
                return Err(PrescribedError::GainLength {
                    field,
                    got: v.len(),
                    expected: nj,
                });
            }
        }
        let legs = LegKinematics::for_robot(desc, model, FootPoint::Contact)?;
        let mut neutral_m = Vec::with_capacity(legs.len());
        let mut phase_offset = Vec::with_capacity(legs.len());
        for leg in &legs {
            let a: Vec<f64> = leg.q_indices().iter().map(|&i| q_start[i]).collect();
            let mut p = leg.fk(&a);
            if let Some(h) = params.trot.body_height_m {
                p.z = -h;
            }
            neutral_m.push(p);
            let m = leg.mount().trans;
            // diagonal pairs: front-left with hind-right at phase 0
            phase_offset.push(if m.x * m.y >= 0.0 { 0.0 } else { 0.5 });
        }
        let mut c = Prescribed {
            params,
            legs,
            neutral_m,
            phase_offset,
            q_ref: vec![0.0; nj],
            qd_ref: vec![0.0; nj],
            qdd_ref: vec![0.0; nj],
            qddd_ref: vec![0.0; nj],
            scratch: std::array::from_fn(|_| vec![0.0; nj]),
            ik: IkOptions::default(),
            t_ref_s: 0.0,
        };
        c.update_reference(model, 0.0);
        Ok(c)
    }

    /// The leg kinematics, in the model's foot order.
    pub fn legs(&self) -> &[LegKinematics] {
        &self.legs
    }

    /// Phase lag of each leg (periods; 0 or 0.5).
    pub fn phase_offsets(&self) -> &[f64] {
        &self.phase_offset
    }

    /// Reference foot point of leg `i` at `t_s` (m, base frame).
    pub fn foot_reference_m(&self, i: usize, t_s: f64) -> DVec3 {
        self.neutral_m[i] + self.params.trot.foot_offset_m(t_s, self.phase_offset[i])
    }

    /// Joint angles (rad, joints only) of the reference at `t_s`, into `out`.
    pub fn joints_at(&self, model: &Model, t_s: f64, out: &mut [f64]) {
        let nv0 = model.base_nv();
        let mut a = [0.0; 4];
        for (i, leg) in self.legs.iter().enumerate() {
            let dof = leg.dof();
            let target = self.foot_reference_m(i, t_s);
            // the trajectory stays inside the workspace for sane parameters;
            // a target outside is projected onto it
            let _ = leg.ik_clamped_into(target, &self.ik, &mut a[..dof]);
            for (k, &vi) in leg.v_indices().iter().enumerate() {
                out[vi - nv0] = a[k];
            }
        }
    }

    /// Recomputes the reference (angles, velocities, accelerations) at `t_s`.
    pub fn update_reference(&mut self, model: &Model, t_s: f64) {
        let h = DIFF_STEP_S;
        self.t_ref_s = t_s;
        let mut s = std::mem::take(&mut self.scratch);
        self.joints_at(model, t_s, &mut s[0]);
        self.joints_at(model, t_s - h, &mut s[1]);
        self.joints_at(model, t_s + h, &mut s[2]);
        self.joints_at(model, t_s - 2.0 * h, &mut s[3]);
        self.joints_at(model, t_s + 2.0 * h, &mut s[4]);
        for j in 0..self.q_ref.len() {
            self.q_ref[j] = s[0][j];
            self.qd_ref[j] = (s[2][j] - s[1][j]) / (2.0 * h);
            self.qdd_ref[j] = (s[2][j] - 2.0 * s[0][j] + s[1][j]) / (h * h);
            self.qddd_ref[j] =
                (s[4][j] - 2.0 * s[2][j] + 2.0 * s[1][j] - s[3][j]) / (2.0 * h * h * h);
        }
        self.scratch = s;
    }

    /// Time of the last update (s).
    pub fn reference_time_s(&self) -> f64 {
        self.t_ref_s
    }

    /// Reference joint angles of the last update (rad, joints only).
    pub fn q_ref(&self) -> &[f64] {
        &self.q_ref
    }

    /// Reference joint velocities of the last update (rad/s).
    pub fn qd_ref(&self) -> &[f64] {
        &self.qd_ref
    }

    /// Reference joint accelerations of the last update (rad/s²).
    pub fn qdd_ref(&self) -> &[f64] {
        &self.qdd_ref
    }

    /// The imposed motion for the integrator (hybrid mode), from the last
    /// update, with no torque recorded yet.
    pub fn imposed(&self) -> ImposedJoints {
        let mut m = ImposedJoints::hold(
            self.q_ref.clone(),
            self.params.hybrid_kp_per_s2,
            self.params.hybrid_kd_per_s,
        );
        self.write_imposed(&mut m);
        m
    }

    /// Copies the last update's reference into `m` (no allocation).
    pub fn write_imposed(&self, m: &mut ImposedJoints) {
        m.q_rad.copy_from_slice(&self.q_ref);
        m.qd_radps.copy_from_slice(&self.qd_ref);
        m.qdd_radps2.copy_from_slice(&self.qdd_ref);
        m.qddd_radps3.copy_from_slice(&self.qddd_ref);
        m.kp_per_s2 = self.params.hybrid_kp_per_s2;
        m.kd_per_s = self.params.hybrid_kd_per_s;
    }

    /// PD mode: joint torques (N·m, joints only) toward the last update's
    /// reference from the joint angles `q_j` and velocities `qd_j`,
    /// saturated at the model's effort limits.
    pub fn pd_torques(&self, model: &Model, q_j: &[f64], qd_j: &[f64], tau_joints: &mut [f64]) {
        let nv0 = model.base_nv();
        for j in 0..tau_joints.len() {
            let t = self.params.pd_kp_nm_per_rad[j] * (self.q_ref[j] - q_j[j])
                + self.params.pd_kd_nms_per_rad[j] * (self.qd_ref[j] - qd_j[j]);
            let lim = model.effort_limit[nv0 + j];
            tau_joints[j] = t.clamp(-lim, lim);
        }
    }
}
