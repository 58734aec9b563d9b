//! A semi-implicit Euler step of up to `L` robots of one model, with the
//! dynamics in SIMD lanes and everything else (actuator saturation, passive
//! joint torques, the force model: contact, pushes) per robot.
//!
//! It repeats [`crate::integrate::step`] with [`Integrator::SemiImplicitEuler`](crate::integrate::Integrator)
//! stage for stage: (1) forward kinematics (batched) copied into each robot's
//! `Data`, or, when every robot's `Data` already holds them for its state,
//! copied from there into the lanes; (2) `τ = sat(τ_actuator) + τ_passive` (with an
//! [`ActuatorBank`](crate::actuator_model::ActuatorBank): its step start, then
//! each motor's torque in its envelope plus friction); (3) the robot's
//! [`ForceModel`] on its own `Data`; (4) ABA with the external forces
//! (batched); (5) `v⁺ = v + dt·a`, `q⁺ = q ⊕ dt·v⁺`. Since the batched
//! kinematics and ABA are bit-identical to the scalar ones, each robot ends
//! in exactly the state the scalar step gives it, whichever robots share
//! its batch.

use super::{BatchData, aba_from_kinematics_batch, forward_kinematics_batch};
use crate::data::Data;
use crate::integrate::{ForceModel, State, StepWorkspace, integrate_q};
use crate::model::Model;
use crate::passive::{add_passive_torques, saturate};

/// One robot's buffers for [`step_semi_implicit_batch`]: what
/// [`crate::integrate::step`] takes for it.
#[derive(Debug)]
pub struct StepParts<'a, F> {
    /// Its kinematics/dynamics workspace.
    pub data: &'a mut Data,
    /// Its integrator buffers, passive joint model and actuator models (no imposed motion).
    pub ws: &'a mut StepWorkspace,
    /// Its state, advanced in place.
    pub state: &'a mut State,
    /// Its actuator command (nv), saturated inside the step.
    pub tau_actuator: &'a [f64],
    /// Its state-dependent forces (contact, pushes).
    pub forces: &'a mut F,
}

/// Advances each of `robots` (1 ≤ len ≤ L, all of `model`) by one
/// semi-implicit Euler step of `dt_s`, bit-identical to
/// [`crate::integrate::step`] on each robot alone. `parts` lends one robot's
/// buffers at a time.
///
/// Afterwards each robot's `data` holds the kinematics, external forces,
/// `ddq` and `acc` of the step's derivative evaluation; the ABA
/// intermediates (`ia`, `pa`, `u`, …) are in `bd`, not in `data`.
///
/// # Panics
/// If `robots` is empty or longer than `L`, a robot carries an imposed joint
/// motion (hybrid dynamics has no batched form), or `bd` does not fit `model`.
pub fn step_semi_implicit_batch<T, F: ForceModel, const L: usize>(
    model: &Model,
    bd: &mut BatchData<L>,
    robots: &mut [T],
    parts: impl for<'a> Fn(&'a mut T) -> StepParts<'a, F>,
    dt_s: f64,
) {
    let n = robots.len();
    bd.set_active(n);
    for (k, robot) in robots.iter_mut().enumerate() {
        let p = parts(robot);
        assert!(
            p.ws.imposed.is_none(),
            "an imposed joint motion cannot be stepped in a batch"
        );
        let StepWorkspace {
            passive,
            tau_actuator,
            actuators,
            ..
        } = p.ws;
        match actuators {
            Some(bank) => bank.begin_step(
                model,
                passive,
                &p.state.q,
                &p.state.v,
                p.tau_actuator,
                dt_s,
                tau_actuator,
            ),
            None => saturate(model, passive, p.tau_actuator, tau_actuator),
        }
        bd.set_state(k, &p.state.q, &p.state.v);
    }
    // The kinematics at the step's start state are usually in every robot's
    // `Data` already (the caller observed the robots there): reuse them.
    let mut held = true;
    for robot in robots.iter_mut() {
        let p = parts(robot);
        held &= p.data.kinematics_hold(model, &p.state.q, &p.state.v);
    }
    if held {
        for (k, robot) in robots.iter_mut().enumerate() {
            bd.kinematics_from(k, model, parts(robot).data);
        }
    } else {
        forward_kinematics_batch(model, bd);
    }
    for (k, robot) in robots.iter_mut().enumerate() {
        let StepParts {
            data,
            ws,
            state,
            forces,
            ..
        } = parts(robot);
        let (q, v) = (&state.q[..], &state.v[..]);
        if !held {
            bd.kinematics_into(k, model, data, q, v);
        }
        data.clear_external_forces();
        ws.tau.copy_from_slice(&ws.tau_actuator);
        if let Some(bank) = &ws.actuators {
            bank.apply(model, &ws.passive, v, &mut ws.tau);
        }
        add_passive_torques(model, &ws.passive, q, v, &mut ws.tau);
        forces.apply(model, data, q, v, &mut ws.tau);
        bd.set_tau(k, &ws.tau);
        bd.set_external_forces(k, &data.f_ext);
    }
    aba_from_kinematics_batch(model, bd, true);
    for (k, robot) in robots.iter_mut().enumerate() {
        let StepParts {
            data, ws, state, ..
        } = parts(robot);
        let a = &mut ws.dv0;
        bd.ddq_of(k, a);
        data.ddq.copy_from_slice(a);
        for (dst, src) in data.acc.iter_mut().zip(&bd.acc) {
            *dst = src.lane(k);
        }
        for (vi, ai) in state.v.iter_mut().zip(a.iter()) {
            *vi += dt_s * ai;
        }
        integrate_q(model, &state.q, &state.v, dt_s, &mut ws.q_stage);
        state.q.copy_from_slice(&ws.q_stage);
    }
}
