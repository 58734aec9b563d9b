//! One entry point per algorithm, matching on the model's [`Plan`]: the
//! scalar implementation ([`crate::kinematics`], [`crate::aba`],
//! [`crate::rnea`], [`crate::crba`], [`crate::com`]) or the plan's kernel
//! ([`crate::kernels`]), which gives the same bits. Callers on the step path
//! use these; the scalar files stay readable on their own.
//!
//! Each function is compiled for x86-64-v3 (AVX2, FMA) and the generic
//! target; the CPU picks one at the first call. Only the x86-64-v3 clone
//! can run a lane kernel (it needs AVX): on other CPUs every plan runs the
//! scalar path.
//!
//! Forward kinematics records the state `(q, v)` it ran at in the `Data`:
//! a repeated call at the same state (the observation, then the
//! integrator's first stage) returns at once.

use crate::com;
use crate::crba::{self, MassMatrix};
use crate::data::{Data, kinematics_level};
use crate::kernels::avx_call;
#[cfg(target_arch = "x86_64")]
use crate::kernels::legs_x4::passes::{
    RNEA_MAX_GROUPS, aba_passes_legs, leg_end_points as leg_end_points_x4, leg_mass_sums,
    poses_legs, refresh_lane_velocities, rnea_passes_legs,
};
use crate::kinematics::{self, base_kinematics, body_kinematics};
use crate::model::Model;
use crate::plan::Plan;
use crate::{aba as scalar_aba, rnea as scalar_rnea};
use glam::DVec3;
use multiversion::multiversion;

/// Whether `model`'s plan runs a lane kernel on this CPU (its plan is not
/// [`Plan::Scalar`] and the CPU has AVX2 and FMA).
pub fn runs_on(model: &Model) -> bool {
    !matches!(model.plan, Plan::Scalar) && crate::kernels::cpu_has_lanes()
}

/// Forward kinematics, poses only ([`kinematics::forward_kinematics_pos`]'s
/// fields and bits), skipped when `data` holds them for `(model, q)`.
pub fn forward_kinematics_pos(model: &Model, data: &mut Data, q: &[f64]) {
    debug_assert_eq!(q.len(), model.nq);
    if kinematics_level(model, data, q, None) >= 1 {
        return;
    }
    poses(model, data, q, None);
    let k = &mut data.kin;
    k.model = model as *const Model as usize;
    k.q.clear();
    k.q.extend_from_slice(q);
    k.level = 1;
}

/// Forward kinematics with velocities ([`kinematics::forward_kinematics`]'s
/// fields and bits). Repeated calls at the same `(model, q, v)` (bit for
/// bit) return at once; at the same `q` and another `v`, only the
/// velocities are computed again.
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) {
    debug_assert_eq!(q.len(), model.nq);
    debug_assert_eq!(v.len(), model.nv);
    match kinematics_level(model, data, q, Some(v)) {
        2 => return,
        1 => {
            // poses are valid for q: velocities only (the lane cache's
            // subspaces and inertias stay valid; its velocities follow)
            kinematics::body_velocities(model, data, v);
            #[cfg(target_arch = "x86_64")]
            if data.lanes.valid
                && let Plan::LegsX4(plan) = &model.plan
            {
                refresh_lane_velocities(plan, data);
            }
        }
        _ => {
            poses(model, data, q, Some(v));
            let k = &mut data.kin;
            k.model = model as *const Model as usize;
            k.q.clear();
            k.q.extend_from_slice(q);
        }
    }
    let k = &mut data.kin;
    k.v.clear();
    k.v.extend_from_slice(v);
    k.level = 2;
}

/// [`forward_kinematics`] without recording `(q, v)` as the state `data`
/// holds: a later call computes again. For a workspace nothing reads
/// afterwards (the estimator's kinematics-only spare), the two copies of the
/// state are saved.
pub fn forward_kinematics_unrecorded(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) {
    debug_assert_eq!(q.len(), model.nq);
    debug_assert_eq!(v.len(), model.nv);
    poses(model, data, q, Some(v));
    data.kin.level = 0;
}

/// The base, then the other bodies by the plan.
#[multiversion(targets("x86_64+avx2+fma"))]
fn poses(model: &Model, data: &mut Data, q: &[f64], v: Option<&[f64]>) {
    // (set again by the legs in lanes when they fill it)
    data.lanes.valid = false;
    base_kinematics(model, data, q, v);
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Plan::LegsX4(plan) = &model.plan {
            avx_call!(poses_legs(plan, data, q, v));
            return;
        },
        _ => {},
    }
    body_kinematics(model, data, q, v);
}

/// The world position and velocity of one point on the last body of each
/// of the four legs, at `(q, v)`: `points[k]` is in the frame of the legs'
/// last group's body `k`. The same bits as [`Data::body_point_world`] and
/// [`Data::body_point_velocity`] after [`forward_kinematics`], without any
/// other body's pose, subspace or velocity stored (the chains stay in AVX
/// registers). `None` where the legs do not run in lanes (another plan, or
/// a CPU without AVX2 and FMA): the caller then runs the full kinematics.
#[multiversion(targets("x86_64+avx2+fma"))]
pub fn leg_end_points(
    model: &Model,
    q: &[f64],
    v: &[f64],
    points: [DVec3; 4],
) -> Option<([DVec3; 4], [DVec3; 4])> {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Plan::LegsX4(plan) = &model.plan {
            let base = kinematics::base_pose(model, q);
            let vel0 = kinematics::base_velocity_at(model, base.rot, v);
            return Some(avx_call!(leg_end_points_x4(
                plan, &base, base.trans, vel0, q, v, points,
            )));
        },
        _ => {},
    }
    let _ = (model, q, v, points);
    None
}

/// Forward dynamics without external forces ([`scalar_aba::aba`]'s bits).
/// Fills and returns `data.ddq` (nv).
pub fn aba<'d>(model: &Model, data: &'d mut Data, q: &[f64], v: &[f64], tau: &[f64]) -> &'d [f64] {
    forward_kinematics(model, data, q, v);
    aba_from_kinematics(model, data, v, tau, false);
    &data.ddq
}

/// ABA after [`forward_kinematics`] on the same `(q, v)`
/// ([`scalar_aba::aba_from_kinematics`]'s fields and bits).
pub fn aba_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    tau: &[f64],
    use_external: bool,
) {
    aba_passes(model, data, v, tau, use_external, true);
}

/// [`aba_from_kinematics`] for the integrator, which needs `ddq` only: the
/// bodies' accelerations `data.acc` but the base's are left unspecified
/// (the legs-in-lanes kernel does not store them; nothing on the step path
/// reads them, and [`crate::integrate::step`] documents it).
pub(crate) fn aba_ddq_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    tau: &[f64],
    use_external: bool,
) {
    aba_passes(model, data, v, tau, use_external, false);
}

/// ABA's passes by the plan. Without `body_acc` the lane kernel skips the
/// legs' `acc` (the scalar path needs them as it goes and fills them anyway).
#[multiversion(targets("x86_64+avx2+fma"))]
fn aba_passes(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    tau: &[f64],
    use_external: bool,
    body_acc: bool,
) {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Plan::LegsX4(plan) = &model.plan {
            return avx_call!(aba_passes_legs(
                model, plan, data, v, tau, use_external, body_acc,
            ));
        },
        _ => {},
    }
    let _ = body_acc;
    scalar_aba::aba_passes(model, data, v, tau, use_external);
}

/// Inverse dynamics without external forces ([`scalar_rnea::rnea`]'s bits).
/// Fills and returns `data.tau` (nv).
pub fn rnea<'d>(model: &Model, data: &'d mut Data, q: &[f64], v: &[f64], a: &[f64]) -> &'d [f64] {
    forward_kinematics(model, data, q, v);
    rnea_from_kinematics(model, data, v, a, false);
    &data.tau
}

/// RNEA after [`forward_kinematics`] on the same `(q, v)`
/// ([`scalar_rnea::rnea_from_kinematics`]'s fields and bits).
pub fn rnea_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    use_external: bool,
) {
    scalar_rnea::rnea_base(model, data, a, use_external);
    rnea_bodies(model, data, v, a, use_external);
    scalar_rnea::rnea_base_wrench(model, data);
}

/// RNEA's passes over the bodies by the plan.
#[multiversion(targets("x86_64+avx2+fma"))]
fn rnea_bodies(model: &Model, data: &mut Data, v: &[f64], a: &[f64], use_external: bool) {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Plan::LegsX4(plan) = &model.plan
            && plan.groups.len() <= RNEA_MAX_GROUPS
        {
            return avx_call!(rnea_passes_legs::<true>(model, plan, data, v, a, use_external, &mut []));
        },
        _ => {},
    }
    scalar_rnea::rnea_bodies(model, data, v, a, use_external);
}

/// The joint rows of [`rnea_from_kinematics`] without external forces,
/// `tau_joints[j − base_nv] = tau[j]` bit for bit, for a caller that reads
/// only them (the walker's feed-forward): with the legs in lanes, neither
/// the base's force and rows nor the legs' `acc` and `f` are formed or
/// stored (about 40% of the pass). Otherwise the full RNEA runs. `data`'s
/// `acc` (but the base's, which is the full RNEA's), `f` and `tau` are then
/// unspecified.
pub fn rnea_joint_torques_from_kinematics(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    tau_joints: &mut [f64],
) {
    let nv0 = model.base_nv();
    assert_eq!(tau_joints.len(), model.nv - nv0, "one torque per joint");
    data.acc[0] = scalar_rnea::base_acceleration(model, data, a);
    if !rnea_joint_torques_in_lanes(model, data, v, a, tau_joints) {
        rnea_from_kinematics(model, data, v, a, false);
        tau_joints.copy_from_slice(&data.tau[nv0..]);
    }
}

/// The joint torques by the lane kernel where the plan has one; `false`
/// (nothing done) otherwise.
#[multiversion(targets("x86_64+avx2+fma"))]
fn rnea_joint_torques_in_lanes(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    tau_joints: &mut [f64],
) -> bool {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let Plan::LegsX4(plan) = &model.plan
            && plan.groups.len() <= RNEA_MAX_GROUPS
        {
            avx_call!(rnea_passes_legs::<false>(model, plan, data, v, a, false, tau_joints));
            return true;
        },
        _ => {},
    }
    let _ = (model, data, v, a, tau_joints);
    false
}

/// The mass matrix at `q` ([`crba::crba`]'s bits), after
/// [`forward_kinematics_pos`] (skipped when `data` holds `q`'s poses).
pub fn crba(model: &Model, data: &mut Data, q: &[f64]) -> MassMatrix {
    forward_kinematics_pos(model, data, q);
    crba::crba_from_kinematics(model, data)
}

/// [`com::com_and_velocity_by_legs`]'s bits: the legs' sums in lanes from
/// the lane cache where `data` holds it, else in scalar code.
#[multiversion(targets("x86_64+avx2+fma"))]
pub fn com_and_velocity_by_legs(model: &Model, data: &Data) -> (DVec3, DVec3) {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if data.lanes.valid && let Some(plan) = com::by_legs(model) {
            let _ = plan;
            let sums = avx_call!(leg_mass_sums(data));
            return com::add_base(model, data, &sums);
        },
        _ => {},
    }
    com::com_and_velocity_by_legs(model, data)
}
