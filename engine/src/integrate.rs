//! Fixed-step time integration of the articulated dynamics.
//!
//! One [`step`] advances a [`State`] `(q, v)` by `dt_s`. Each *derivative
//! evaluation* (one for semi-implicit Euler, four for RK4) runs, at the stage
//! state:
//!
//! 1. [`forward_kinematics`] and cleared external forces ([`Data::clear_external_forces`]);
//! 2. `τ = sat(τ_actuator) + τ_passive(q, v)` ([`crate::passive`]); with an
//!    [`ActuatorBank`], each motor's torque inside its torque–speed envelope
//!    at this `q̇` plus its friction ([`crate::actuator_model`]);
//! 3. the caller's [`ForceModel`], which adds contact/push forces to the bodies'
//!    external forces ([`Data::add_external_force`])
//!    and generalised forces to `τ`;
//! 4. [`crate::aba::aba_from_kinematics`] for `v̇`, or, when the workspace carries
//!    [`ImposedJoints`] (hybrid dynamics), [`hybrid_acceleration`]: the joint
//!    accelerations are imposed and the base's follows from the dynamics.
//!
//! So every state-dependent force is re-evaluated at every RK4 stage, and the
//! method keeps its order with stiff contacts as long as they are smooth.
//!
//! Configuration derivative (Pinocchio conventions, see [`crate::model`]): for
//! a floating base `ṗ = R v_lin` and `q̇uat = ½ quat ⊗ (0, ω)` with `v_lin`, `ω`
//! in the base frame; joints `q̇ = v`.

use crate::actuator_model::ActuatorBank;
use crate::crba::crba_from_kinematics;
use crate::data::Data;
use crate::dispatch::aba_ddq_from_kinematics;
use crate::dispatch::forward_kinematics;
use crate::dispatch::rnea_from_kinematics;
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place};
use crate::model::Model;
use crate::passive::{PassiveParams, add_passive_torques, saturate};
use glam::{DQuat, DVec3};

/// Fixed-step integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// Semi-implicit (symplectic) Euler: `v⁺ = v + dt·a(q, v)`, `q⁺ = q ⊕ dt·v⁺`,
    /// with `⊕` the exact exponential of [`integrate_q`]. First order, one
    /// dynamics evaluation per step, bounded energy error for conservative systems.
    #[default]
    SemiImplicitEuler,
    /// Classical fourth-order Runge–Kutta in the embedded coordinates (the
    /// quaternion as a 4-vector), renormalised once per step. Four dynamics
    /// evaluations per step.
    Rk4,
}

/// Generalised position and velocity (Pinocchio conventions, see [`crate::model`]).
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Configuration (nq): `[x, y, z, qx, qy, qz, qw, joints…]` for a floating base (m, rad).
    pub q: Vec<f64>,
    /// Velocity (nv): `[v_lin, ω (base frame), q̇…]` (m/s, rad/s).
    pub v: Vec<f64>,
}

impl State {
    /// The neutral configuration at rest.
    pub fn neutral(model: &Model) -> State {
        State {
            q: model.neutral_q(),
            v: vec![0.0; model.nv],
        }
    }

    /// A checked state for `model`: sizes nq and nv, finite entries, and a base
    /// quaternion of unit norm to 1e-6 (it is renormalised exactly).
    ///
    /// # Errors
    /// [`StateError`] naming the offending field.
    pub fn from_parts(model: &Model, q: Vec<f64>, v: Vec<f64>) -> Result<State, StateError> {
        for (field, got, expected) in [("q", q.len(), model.nq), ("v", v.len(), model.nv)] {
            if got != expected {
                return Err(StateError::Size {
                    field,
                    expected,
                    got,
                });
            }
        }
        for (field, x) in [("q", &q), ("v", &v)] {
            if let Some(index) = x.iter().position(|e| !e.is_finite()) {
                return Err(StateError::NotFinite { field, index });
            }
        }
        let mut q = q;
        if model.is_floating() {
            let norm = q[3..7].iter().map(|e| e * e).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > 1e-6 {
                return Err(StateError::QuaternionNorm { norm });
            }
            normalize_base_quat(model, &mut q);
        }
        Ok(State { q, v })
    }
}

/// A state that does not fit its model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StateError {
    /// Wrong vector length.
    #[error("state field '{field}' has {got} entries, the model needs {expected}")]
    Size {
        /// `q` or `v`.
        field: &'static str,
        /// The model's size (nq or nv).
        expected: usize,
        /// The given size.
        got: usize,
    },
    /// A NaN or infinite entry.
    #[error("state field '{field}' entry {index} is not finite")]
    NotFinite {
        /// `q` or `v`.
        field: &'static str,
        /// Index of the first bad entry.
        index: usize,
    },
    /// The base quaternion `q[3..7]` is not of unit norm.
    #[error("state field 'q': base quaternion q[3..7] has norm {norm}, not 1")]
    QuaternionNorm {
        /// Its norm.
        norm: f64,
    },
}

/// State-dependent forces evaluated inside **every** derivative evaluation
/// (each RK4 stage).
///
/// Called after `forward_kinematics(model, data, q, v)` at the stage state, with
/// the external forces cleared. It adds spatial forces (world axes, about
/// `data.origin`) with [`Data::add_point_force`] or [`Data::add_external_force`]
/// (read back with [`Data::external_forces`]) and generalised forces to
/// `tau` (nv, pre-filled with saturated actuator and passive torques). It must
/// not mutate persistent contact state (tangential anchors and the like are
/// updated once per step by the caller, after [`step`]).
pub trait ForceModel {
    /// Adds this model's forces at the stage state `(q, v)`.
    fn apply(&mut self, model: &Model, data: &mut Data, q: &[f64], v: &[f64], tau: &mut [f64]);
}

/// No external forces.
impl ForceModel for () {
    #[inline]
    fn apply(&mut self, _: &Model, _: &mut Data, _: &[f64], _: &[f64], _: &mut [f64]) {}
}

impl<F: ForceModel + ?Sized> ForceModel for &mut F {
    #[inline]
    fn apply(&mut self, model: &Model, data: &mut Data, q: &[f64], v: &[f64], tau: &mut [f64]) {
        (**self).apply(model, data, q, v, tau);
    }
}

/// Both force models, in order (e.g. ground contact and a push).
impl<A: ForceModel, B: ForceModel> ForceModel for (A, B) {
    #[inline]
    fn apply(&mut self, model: &Model, data: &mut Data, q: &[f64], v: &[f64], tau: &mut [f64]) {
        self.0.apply(model, data, q, v, tau);
        self.1.apply(model, data, q, v, tau);
    }
}

/// Preallocated buffers of [`step`]; nothing is allocated while stepping.
#[derive(Clone, Debug)]
pub struct StepWorkspace {
    /// Passive joint model applied at every derivative evaluation. Set it to
    /// [`PassiveParams::none`] for ideal joints and unclamped actuators.
    pub passive: PassiveParams,
    /// Saturated actuator torques, constant over a step (nv).
    pub(crate) tau_actuator: Vec<f64>,
    /// Total generalised force of the current stage (nv).
    pub(crate) tau: Vec<f64>,
    /// The integrated configuration (nq), copied into the state.
    pub(crate) q_stage: Vec<f64>,
    /// Acceleration of the step's first derivative evaluation (nv). RK4's
    /// other stage buffers hold nothing between steps: one per thread
    /// ([`Rk4Stages`]).
    pub(crate) dv0: Vec<f64>,
    /// Hybrid dynamics: when set, the joints follow this motion and the
    /// actuator torques are its output, not an input (see [`ImposedJoints`]).
    pub imposed: Option<ImposedJoints>,
    /// Joint actuator models (motor envelopes, lags, latency, servos); `None`:
    /// every joint an ideal torque source (see [`crate::actuator_model`]).
    pub actuators: Option<ActuatorBank>,
}

/// A joint motion imposed on the integrator (*hybrid dynamics*, Featherstone
/// 2008 §9.2 in its simplest form): the joints' accelerations are given, the
/// floating base is free under gravity and the external (contact) forces, and
/// the joint torques that realise the motion are computed.
///
/// At each derivative evaluation, `s` seconds after the step's start (0 for
/// semi-implicit Euler; 0, dt/2, dt/2, dt for RK4), the reference is the
/// third-order expansion `q_r(s) = q_r + s q̇_r + s²/2 q̈_r + s³/6 q⃛_r` (and
/// its derivatives), and the imposed joint acceleration is
/// `a_j = q̈_r(s) + kp (q_r(s) − q_j) + kd (q̇_r(s) − q̇_j)`. The PD term (on
/// acceleration, gains in 1/s² and 1/s) only removes the integrator's drift
/// from the reference. The caller refreshes the reference every step.
/// Without the jerk term a step's end would miss the next step's reference
/// by `q⃛ dt³/6`, a first-order lag `q⃛ dt / (2 kp)` even under RK4.
///
/// Given `a_j`, the rows of `M a + h = τ + Jᵀf` split into base rows
/// `M_bb a_b = τ_b − (M_bj a_j + h_b − (Jᵀf)_b)` (6×6, solved by Cholesky;
/// `τ_b` the known generalised force on the base, normally 0) and joint rows
/// `τ_j = M_jb a_b + M_jj a_j + h_j − (Jᵀf)_j`, computed with one RNEA with
/// external forces (`r = RNEA(q, v, [0; a_j], f_ext)`) and the mass matrix's
/// joint–base block (CRBA). The actuator torque is `τ_j` minus the known
/// joint forces (passive and force-model torques); it is **not** saturated:
/// a prescribed motion gets whatever torque it needs (a motion drive, as in
/// a multibody package).
#[derive(Clone, Debug, PartialEq)]
pub struct ImposedJoints {
    /// Reference joint angles at the step's start (rad, joints only).
    pub q_rad: Vec<f64>,
    /// Reference joint velocities (rad/s).
    pub qd_radps: Vec<f64>,
    /// Reference joint accelerations (rad/s²).
    pub qdd_radps2: Vec<f64>,
    /// Reference joint jerks (rad/s³).
    pub qddd_radps3: Vec<f64>,
    /// Stiffness of the drift correction (1/s²).
    pub kp_per_s2: f64,
    /// Damping of the drift correction (1/s).
    pub kd_per_s: f64,
    /// Output: the actuator torques (N·m, joints only) of the first
    /// derivative evaluation of the last step (the step's start state).
    pub tau_actuator_nm: Vec<f64>,
}

impl ImposedJoints {
    /// A motion holding `q_rad` (joints only) with the given correction gains.
    pub fn hold(q_rad: Vec<f64>, kp_per_s2: f64, kd_per_s: f64) -> ImposedJoints {
        let n = q_rad.len();
        ImposedJoints {
            q_rad,
            qd_radps: vec![0.0; n],
            qdd_radps2: vec![0.0; n],
            qddd_radps3: vec![0.0; n],
            kp_per_s2,
            kd_per_s,
            tau_actuator_nm: vec![0.0; n],
        }
    }
}

impl StepWorkspace {
    /// Buffers for `model`, with the default [`PassiveParams`] (and this
    /// thread's RK4 stage buffers sized for it).
    pub fn new(model: &Model) -> StepWorkspace {
        let (nq, nv) = (model.nq, model.nv);
        Rk4Stages::take(nq, nv).give_back();
        StepWorkspace {
            passive: PassiveParams::default(),
            tau_actuator: vec![0.0; nv],
            tau: vec![0.0; nv],
            q_stage: vec![0.0; nq],
            dv0: vec![0.0; nv],
            imposed: None,
            actuators: None,
        }
    }

    /// The generalised force of the last derivative evaluation (nv): saturated
    /// actuator + passive + the force model's generalised forces. After a
    /// semi-implicit Euler step this is the force at the step's start state.
    pub fn last_tau(&self) -> &[f64] {
        &self.tau
    }

    /// The acceleration of the first derivative evaluation of the last step,
    /// i.e. `a(q, v)` at the step's start state (nv).
    pub fn last_acceleration(&self) -> &[f64] {
        &self.dv0
    }
}

/// RK4's stage buffers but the first acceleration: they hold nothing from
/// one step to the next, so they are one per thread, not one per robot's
/// [`StepWorkspace`]; sized to the largest model the thread has stepped
/// (by [`StepWorkspace::new`] on the thread that makes the workspace).
#[derive(Debug, Default)]
struct Rk4Stages {
    /// Stage velocity (nv).
    v_stage: Vec<f64>,
    /// The stage configuration's unit-quaternion copy used for dynamics (nq).
    q_eval: Vec<f64>,
    /// Configuration derivatives of the four stages, embedded coordinates (4 × nq).
    dq: [Vec<f64>; 4],
    /// Accelerations of stages 2 to 4 (3 × nv; the first is `StepWorkspace::dv0`).
    dv: [Vec<f64>; 3],
}

thread_local! {
    static RK4_STAGES: std::cell::RefCell<Rk4Stages> = std::cell::RefCell::new(Rk4Stages::default());
}

impl Rk4Stages {
    /// This thread's buffers, at least `nq` and `nv` long (every entry is
    /// written before it is read), lent until [`Rk4Stages::give_back`].
    fn take(nq: usize, nv: usize) -> Rk4Stages {
        let mut s = RK4_STAGES.with(std::cell::RefCell::take);
        let fit = |x: &mut Vec<f64>, n: usize| {
            if x.len() < n {
                x.resize(n, 0.0);
            }
        };
        fit(&mut s.v_stage, nv);
        fit(&mut s.q_eval, nq);
        s.dq.iter_mut().for_each(|x| fit(x, nq));
        s.dv.iter_mut().for_each(|x| fit(x, nv));
        s
    }

    /// Returns the buffers to this thread.
    fn give_back(self) {
        RK4_STAGES.with(|cell| drop(cell.replace(self)));
    }
}

/// Advances `state` by `dt_s` seconds under the saturated `tau_actuator` (nv;
/// base entries are a wrench on the base in the base frame, normally zero),
/// passive joint torques (`ws.passive`) and `forces`.
///
/// Afterwards `data` holds the kinematics and dynamics of the last derivative
/// evaluation (not of the new state): run kinematics again before reading it.
/// The bodies' accelerations `data.acc` but the base's are not among them
/// (ABA there fills only what the integrator needs, `ddq`; the legs-in-lanes
/// path leaves the legs' entries as they were): run
/// [`crate::aba::aba_from_kinematics`] or RNEA for them.
pub fn step<F: ForceModel>(
    model: &Model,
    data: &mut Data,
    ws: &mut StepWorkspace,
    state: &mut State,
    tau_actuator: &[f64],
    dt_s: f64,
    integrator: Integrator,
    forces: &mut F,
) {
    debug_assert_eq!(state.q.len(), model.nq);
    debug_assert_eq!(state.v.len(), model.nv);
    debug_assert_eq!(tau_actuator.len(), model.nv);
    match &mut ws.actuators {
        Some(bank) => bank.begin_step(
            model,
            &ws.passive,
            &state.q,
            &state.v,
            tau_actuator,
            dt_s,
            &mut ws.tau_actuator,
        ),
        None => saturate(model, &ws.passive, tau_actuator, &mut ws.tau_actuator),
    }
    match integrator {
        Integrator::SemiImplicitEuler => {
            let StepWorkspace {
                passive,
                tau_actuator,
                tau,
                q_stage,
                dv0: a,
                imposed,
                actuators,
                ..
            } = ws;
            acceleration(
                model,
                data,
                passive,
                tau_actuator,
                &state.q,
                &state.v,
                forces,
                tau,
                a,
                imposed.as_mut().map(|m| (m, 0.0)),
                actuators.as_ref(),
            );
            for (vi, ai) in state.v.iter_mut().zip(a.iter()) {
                *vi += dt_s * ai;
            }
            integrate_q(model, &state.q, &state.v, dt_s, q_stage);
            state.q.copy_from_slice(q_stage);
        }
        Integrator::Rk4 => rk4(model, data, ws, state, dt_s, forces),
    }
}

/// Classical RK4 on `(q, v)` in embedded coordinates.
fn rk4<F: ForceModel>(
    model: &Model,
    data: &mut Data,
    ws: &mut StepWorkspace,
    state: &mut State,
    dt_s: f64,
    forces: &mut F,
) {
    let StepWorkspace {
        passive,
        tau_actuator,
        tau,
        q_stage,
        dv0,
        imposed,
        actuators,
    } = ws;
    let (nq, nv) = (model.nq, model.nv);
    let mut stages = Rk4Stages::take(nq, nv);
    let Rk4Stages {
        v_stage,
        q_eval,
        dq,
        dv: dv_rest,
    } = &mut stages;
    let (v_stage, q_eval) = (&mut v_stage[..nv], &mut q_eval[..nq]);
    let [dv1, dv2, dv3] = dv_rest;
    let dv: [&mut [f64]; 4] = [dv0, &mut dv1[..nv], &mut dv2[..nv], &mut dv3[..nv]];
    // Stage k is evaluated at y0 + c_k·dt·k_{k−1}, c = (0, ½, ½, 1).
    let c = [0.0, 0.5 * dt_s, 0.5 * dt_s, dt_s];
    for k in 0..4 {
        if k == 0 {
            q_stage.copy_from_slice(&state.q);
            v_stage.copy_from_slice(&state.v);
        } else {
            for i in 0..nq {
                q_stage[i] = state.q[i] + c[k] * dq[k - 1][i];
            }
            for i in 0..nv {
                v_stage[i] = state.v[i] + c[k] * dv[k - 1][i];
            }
        }
        // The vector field is evaluated at the unit-quaternion copy: smooth near
        // the unit sphere and equal to the true field on it.
        q_eval.copy_from_slice(q_stage);
        normalize_base_quat(model, q_eval);
        q_derivative(model, q_eval, v_stage, &mut dq[k][..nq]);
        acceleration(
            model,
            data,
            passive,
            tau_actuator,
            q_eval,
            v_stage,
            forces,
            tau,
            dv[k],
            imposed.as_mut().map(|m| (m, c[k])),
            actuators.as_ref(),
        );
    }
    let w = dt_s / 6.0;
    for i in 0..nq {
        state.q[i] += w * (dq[0][i] + 2.0 * dq[1][i] + 2.0 * dq[2][i] + dq[3][i]);
    }
    for i in 0..nv {
        state.v[i] += w * (dv[0][i] + 2.0 * dv[1][i] + 2.0 * dv[2][i] + dv[3][i]);
    }
    stages.give_back();
    // The exact flow keeps |quat| = 1, so this is an O(dt⁵) correction.
    normalize_base_quat(model, &mut state.q);
}

/// One derivative evaluation: `a = ABA(q, v, sat(τ_act) + τ_passive + τ_forces, f_ext)`,
/// or with an imposed joint motion (at `s` seconds into the step) the hybrid
/// dynamics of [`hybrid_acceleration`] (`tau` then holds the total force that
/// realises it). `q` must hold a unit quaternion.
#[expect(
    clippy::too_many_arguments,
    reason = "one derivative evaluation reads every buffer of the step"
)]
fn acceleration<F: ForceModel>(
    model: &Model,
    data: &mut Data,
    passive: &PassiveParams,
    tau_actuator: &[f64],
    q: &[f64],
    v: &[f64],
    forces: &mut F,
    tau: &mut [f64],
    a_out: &mut [f64],
    imposed: Option<(&mut ImposedJoints, f64)>,
    actuators: Option<&ActuatorBank>,
) {
    forward_kinematics(model, data, q, v);
    data.clear_external_forces();
    tau.copy_from_slice(tau_actuator);
    if let Some(bank) = actuators {
        bank.apply(model, passive, v, tau);
    }
    add_passive_torques(model, passive, q, v, tau);
    forces.apply(model, data, q, v, tau);
    match imposed {
        None => {
            aba_ddq_from_kinematics(model, data, v, tau, true);
            a_out.copy_from_slice(&data.ddq);
        }
        Some((m, s)) => {
            let (nq0, nv0) = (model.base_nq(), model.base_nv());
            for j in 0..model.nv - nv0 {
                let (jerk, s2) = (m.qddd_radps3[j], 0.5 * s * s);
                let q_r =
                    m.q_rad[j] + s * m.qd_radps[j] + s2 * m.qdd_radps2[j] + s2 * s / 3.0 * jerk;
                let qd_r = m.qd_radps[j] + s * m.qdd_radps2[j] + s2 * jerk;
                a_out[nv0 + j] = m.qdd_radps2[j]
                    + s * jerk
                    + m.kp_per_s2 * (q_r - q[nq0 + j])
                    + m.kd_per_s * (qd_r - v[nv0 + j]);
            }
            // At the step's start state (Euler; RK4's first stage) record the
            // actuator torque: the total joint force minus the passive and
            // force-model parts (`tau − τ_act,in` before the solve).
            let record = s == 0.0;
            if record {
                for (j, t) in m.tau_actuator_nm.iter_mut().enumerate() {
                    *t = tau[nv0 + j] - tau_actuator[nv0 + j];
                }
            }
            hybrid_acceleration(model, data, v, tau, a_out);
            if record {
                for (j, t) in m.tau_actuator_nm.iter_mut().enumerate() {
                    *t = tau[nv0 + j] - *t;
                }
            }
        }
    }
}

/// Hybrid dynamics after [`forward_kinematics`] at `(q, v)` with the external
/// forces in `data.f_ext`: given the joint rows of `a` (nv; the base rows are
/// outputs) and the known generalised forces `tau` (nv), solves the base
/// rows of `M a + h = τ + Jᵀ f_ext` for the base acceleration and writes into
/// the joint rows of `tau` the total joint force that realises `a` (see
/// [`ImposedJoints`]). Computes the mass matrix; leaves `data.tau` with
/// `RNEA(q, v, [0; a_j], f_ext)`.
///
/// When the base's composite inertia is not positive definite (a massless
/// robot) the accelerations are NaN, which the divergence check catches.
pub fn hybrid_acceleration(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    tau: &mut [f64],
    a: &mut [f64],
) {
    let (nv, nv0) = (model.nv, model.base_nv());
    a[..nv0].fill(0.0);
    rnea_from_kinematics(model, data, v, a, true);
    if nv0 == 6 {
        let mm = crba_from_kinematics(model, data);
        let mut mbb = [[0.0; 6]; 6];
        let mut rhs = [0.0; 6];
        for k in 0..6 {
            for l in 0..6 {
                mbb[k][l] = mm[k * nv + l];
            }
            rhs[k] = tau[k] - data.tau[k];
        }
        if !cholesky_in_place(&mut mbb) {
            // A singular composite inertia (a massless or non-physical
            // robot): no acceleration exists. NaN accelerations make the
            // state not finite, which the divergence check reports as this
            // robot's failure instead of ending the process.
            a.fill(f64::NAN);
            return;
        }
        cholesky_solve_in_place(&mbb, &mut rhs);
        a[..6].copy_from_slice(&rhs);
        for j in 6..nv {
            let mut t = data.tau[j];
            for k in 0..6 {
                t += mm[j * nv + k] * rhs[k];
            }
            tau[j] = t;
        }
    } else {
        tau[nv0..].copy_from_slice(&data.tau[nv0..]);
    }
}

/// Time derivative of the configuration in embedded coordinates (nq):
/// `ṗ = R v_lin`, `q̇uat = ½ quat ⊗ (0, ω)`, joints `q̇ = v`.
pub fn q_derivative(model: &Model, q: &[f64], v: &[f64], dq_out: &mut [f64]) {
    let (bq, bv) = (model.base_nq(), model.base_nv());
    if model.is_floating() {
        let quat = DQuat::from_xyzw(q[3], q[4], q[5], q[6]);
        let pd = quat * DVec3::new(v[0], v[1], v[2]);
        let w = DVec3::new(v[3], v[4], v[5]);
        let qd = quat * DQuat::from_xyzw(w.x, w.y, w.z, 0.0) * 0.5;
        dq_out[..7].copy_from_slice(&[pd.x, pd.y, pd.z, qd.x, qd.y, qd.z, qd.w]);
    }
    dq_out[bq..].copy_from_slice(&v[bv..]);
}

/// `q ⊕ v·dt` on the configuration manifold, written to `q_out` (nq).
///
/// The floating base moves along the exact SE(3) exponential of the constant
/// body twist `(v_lin, ω)·dt` (Pinocchio's `integrate` for a free flyer):
/// `R⁺ = R·exp(ω dt)` (as `quat ⊗ exp(ω dt/2)`), `p⁺ = p + R·V(ω dt)·v_lin dt`
/// with `V(φ) = I + (1 − cos θ)/θ²·[φ]× + (θ − sin θ)/θ³·[φ]×²`, `θ = |φ|`.
/// The quaternion is renormalised. Joints: `q⁺ = q + v dt`.
/// Its x86-64-v3 clone (three-operand VEX forms) runs shorter; no fused
/// multiply–add, so both give the same bits.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn integrate_q(model: &Model, q: &[f64], v: &[f64], dt_s: f64, q_out: &mut [f64]) {
    let (bq, bv) = (model.base_nq(), model.base_nv());
    if model.is_floating() {
        let quat = DQuat::from_xyzw(q[3], q[4], q[5], q[6]).normalize();
        let rho = DVec3::new(v[0], v[1], v[2]) * dt_s;
        let phi = DVec3::new(v[3], v[4], v[5]) * dt_s;
        let theta2 = phi.length_squared();
        let theta = theta2.sqrt();
        // Series below θ = 1e-2: the truncation (θ⁶ terms) is below f64 round-off.
        let (a, b) = if theta < 1e-2 {
            (
                0.5 - theta2 / 24.0 + theta2 * theta2 / 720.0,
                1.0 / 6.0 - theta2 / 120.0 + theta2 * theta2 / 5040.0,
            )
        } else {
            let s = (0.5 * theta).sin();
            (
                2.0 * s * s / theta2,
                (theta - theta.sin()) / (theta2 * theta),
            )
        };
        let pxr = phi.cross(rho);
        let dp = rho + pxr * a + phi.cross(pxr) * b;
        let p = DVec3::new(q[0], q[1], q[2]) + quat * dp;
        let quat_new = (quat * quat_from_scaled_axis(phi)).normalize();
        q_out[..7].copy_from_slice(&[
            p.x, p.y, p.z, quat_new.x, quat_new.y, quat_new.z, quat_new.w,
        ]);
    }
    let nj = q_out.len() - bq;
    let (q_j, v_j) = (&q[bq..bq + nj], &v[bv..bv + nj]);
    for ((qo, &qi), &vi) in q_out[bq..].iter_mut().zip(q_j).zip(v_j) {
        *qo = qi + vi * dt_s;
    }
}

/// glam's `DQuat::from_scaled_axis` (rotation by `|φ|` rad about `φ/|φ|`)
/// with `trig::kinematics_sin_cos` ([`crate::trig::DYNAMICS_USE_LIBM`]),
/// operation for operation.
#[inline]
fn quat_from_scaled_axis(phi: DVec3) -> DQuat {
    let length = phi.length();
    if length == 0.0 {
        return DQuat::IDENTITY;
    }
    let (s, c) = crate::trig::kinematics_sin_cos(length * 0.5);
    let v = (phi / length) * s;
    DQuat::from_xyzw(v.x, v.y, v.z, c)
}

/// Renormalises the base quaternion `q[3..7]` of a floating base in place.
#[inline]
pub fn normalize_base_quat(model: &Model, q: &mut [f64]) {
    if model.is_floating() {
        let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
        for x in &mut q[3..7] {
            *x /= n;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::RobotBuilder;
    use crate::model::BaseKind;

    fn free_body() -> Model {
        let d = RobotBuilder::new("body")
            .link("b")
            .mass(2.0)
            .inertia(glam::DMat3::from_diagonal(DVec3::new(0.1, 0.2, 0.3)))
            .done()
            .build();
        Model::from_description(&d, BaseKind::Floating).unwrap()
    }

    #[test]
    fn from_parts_names_the_bad_field() {
        let m = free_body();
        let ok = State::from_parts(&m, m.neutral_q(), vec![0.0; 6]).unwrap();
        assert_eq!(ok, State::neutral(&m));
        assert_eq!(
            State::from_parts(&m, vec![0.0; 6], vec![0.0; 6]),
            Err(StateError::Size {
                field: "q",
                expected: 7,
                got: 6
            })
        );
        let mut v = vec![0.0; 6];
        v[4] = f64::NAN;
        assert_eq!(
            State::from_parts(&m, m.neutral_q(), v),
            Err(StateError::NotFinite {
                field: "v",
                index: 4
            })
        );
        let mut q = m.neutral_q();
        q[6] = 2.0;
        assert!(matches!(
            State::from_parts(&m, q, vec![0.0; 6]),
            Err(StateError::QuaternionNorm { .. })
        ));
    }

    /// The per-thread buffers (RK4's stages, ABA's and CRBA's workspace, the
    /// mass matrix) carry nothing from one robot to the next: two models of
    /// different sizes stepped in turn on one thread get the bits each gets
    /// alone, with either integrator.
    #[test]
    fn robots_stepped_in_turn_get_the_bits_they_get_alone() {
        let models: Vec<Model> = ["quad16", "quad12"]
            .iter()
            .map(|n| {
                let d = crate::robots::builtin(n).unwrap();
                Model::from_description(&d, BaseKind::Floating).unwrap()
            })
            .collect();
        let start = |m: &Model| {
            let mut s = State::neutral(m);
            for (k, v) in s.v.iter_mut().enumerate() {
                *v = 0.3 * (k as f64).sin();
            }
            s
        };
        let run = |order: &[usize], integrator: Integrator| {
            let mut robots: Vec<_> = models
                .iter()
                .map(|m| (Data::new(m), StepWorkspace::new(m), start(m)))
                .collect();
            for _ in 0..20 {
                for &i in order {
                    let (m, (data, ws, state)) = (&models[i], &mut robots[i]);
                    let tau: Vec<f64> = (0..m.nv).map(|k| 0.1 * k as f64).collect();
                    step(m, data, ws, state, &tau, 1e-3, integrator, &mut ());
                }
            }
            robots
                .iter()
                .map(|(_, _, s)| s.q.iter().chain(&s.v).map(|x| x.to_bits()).collect())
                .collect::<Vec<Vec<u64>>>()
        };
        for integrator in [Integrator::Rk4, Integrator::SemiImplicitEuler] {
            let together = run(&[0, 1], integrator);
            assert_eq!(together[0], run(&[0], integrator)[0], "{integrator:?}");
            assert_eq!(together[1], run(&[1], integrator)[1], "{integrator:?}");
        }
    }

    /// Integrating a constant twist in n small steps equals one big step: the
    /// SE(3) exponential is exact for constant body twists.
    #[test]
    fn exponential_composes() {
        let m = free_body();
        let mut q = m.neutral_q();
        q[0] = 0.3;
        let v = [0.4, -0.2, 0.7, 1.1, -0.6, 2.3];
        let mut big = vec![0.0; 7];
        integrate_q(&m, &q, &v, 1.0, &mut big);
        let mut small = q.clone();
        let mut tmp = vec![0.0; 7];
        for _ in 0..1000 {
            integrate_q(&m, &small, &v, 1e-3, &mut tmp);
            small.copy_from_slice(&tmp);
        }
        let sign = if big[6] * small[6] < 0.0 { -1.0 } else { 1.0 };
        for i in 0..7 {
            let s = if i >= 3 { sign } else { 1.0 };
            assert!(
                (big[i] - s * small[i]).abs() < 1e-12,
                "{big:?} vs {small:?}"
            );
        }
    }
}
