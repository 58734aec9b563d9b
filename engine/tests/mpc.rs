//! The convex MPC planner (`control::mpc`): its condensed predictions
//! against a step-by-step integration of the single-rigid-body model, the
//! balance of a standing body, and its constraints.

use glam::{DMat3, DVec3};
use quadsim_engine::control::mpc::{
    MPC_FEET, Mpc, MpcParams, MpcProblem, MpcState, MpcStep, NX, state_vector,
};

const MASS: f64 = 28.0;

fn inertia() -> DMat3 {
    DMat3::from_diagonal(DVec3::new(0.4, 1.2, 1.4))
}

/// A body at rest at 0.45 m on four feet at (±0.25, ±0.15), its reference
/// where it is.
fn standing(n: usize, mu: f64) -> MpcProblem {
    let mut pb = MpcProblem::with_horizon(n);
    pb.mass_kg = MASS;
    pb.inertia_heading = inertia();
    pb.state = MpcState {
        rpy: DVec3::ZERO,
        com_m: DVec3::new(0.0, 0.0, 0.45),
        omega_world_radps: DVec3::ZERO,
        com_velocity_mps: DVec3::ZERO,
    };
    let x0 = state_vector(&pb.state);
    for k in 0..n {
        pb.reference[k] = x0;
        pb.steps[k] = MpcStep {
            stance: [true; MPC_FEET],
            foot_m: [
                DVec3::new(0.25, 0.15, -0.45),
                DVec3::new(0.25, -0.15, -0.45),
                DVec3::new(-0.25, 0.15, -0.45),
                DVec3::new(-0.25, -0.15, -0.45),
            ],
            friction: [mu; MPC_FEET],
        };
    }
    pb
}

/// Standing still, the plan holds the weight: the first forces sum to m g
/// up (1 %), with no moment about the CoM (0.5 N·m), and the predicted
/// states stay near the reference (5 mm, 5 mrad: the force weight α‖f‖²
/// buys a little less than m g with a sag the state weight allows; 2.2 mm
/// at the horizon's end with the defaults).
#[test]
fn a_standing_body_is_held_up() {
    let pb = standing(10, 0.8);
    let mut mpc = Mpc::new(MpcParams::default());
    let f = mpc.solve(&pb).unwrap();
    let total: DVec3 = f.iter().copied().sum();
    let weight = MASS * 9.81;
    assert!((total.z - weight).abs() < 0.01 * weight, "{total:?}");
    assert!(total.truncate().length() < 0.01 * weight, "{total:?}");
    let moment: DVec3 = f
        .iter()
        .zip(&pb.steps[0].foot_m)
        .map(|(f, r)| r.cross(*f))
        .sum();
    assert!(moment.length() < 0.5, "{moment:?}");
    for (k, x) in mpc.predicted().iter().enumerate() {
        for q in 0..6 {
            assert!(
                (x[q] - pb.reference[k][q]).abs() < 5e-3,
                "step {k}, state {q}: {} against {}",
                x[q],
                pb.reference[k][q]
            );
        }
    }
}

/// The condensed prediction is the model stepped one step at a time: with
/// the solved forces held over each step, integrating `ω̇ = I⁻¹ Σ r × f`,
/// `p̈ = Σ f / m + g` exactly for constant accelerations (angles through
/// `R_z(ψ)ᵀ`) gives the planner's predicted states to 1e-9.
#[test]
fn predictions_are_the_model_integrated_step_by_step() {
    let n = 8;
    let mut pb = standing(n, 0.8);
    pb.state.rpy = DVec3::new(0.05, -0.03, 0.7);
    pb.state.com_velocity_mps = DVec3::new(0.6, -0.1, 0.05);
    pb.state.omega_world_radps = DVec3::new(0.2, -0.1, 0.3);
    for (k, r) in pb.reference.iter_mut().enumerate() {
        r[3] = 0.1 * (k + 1) as f64;
        r[9] = 1.0;
    }
    // a trot: diagonal pairs alternate every other step
    for (k, s) in pb.steps.iter_mut().enumerate() {
        let a = (k / 2) % 2 == 0;
        s.stance = [a, !a, !a, a];
    }
    let params = MpcParams {
        horizon_steps: n,
        ..MpcParams::default()
    };
    let mut mpc = Mpc::new(params);
    mpc.solve(&pb).unwrap();
    let u = mpc.planned_forces();
    let dt = params.step_s;
    let (s, c) = pb.state.rpy.z.sin_cos();
    let rz = DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z);
    let i_inv = (rz * pb.inertia_heading * rz.transpose()).inverse();
    let mut x = state_vector(&pb.state);
    for k in 0..n {
        let mut force = DVec3::ZERO;
        let mut moment = DVec3::ZERO;
        for f in 0..MPC_FEET {
            let fk = u[k][f];
            force += fk;
            moment += pb.steps[k].foot_m[f].cross(fk);
        }
        let wdot = i_inv * moment;
        let pdd = force / pb.mass_kg + pb.gravity;
        let w = DVec3::new(x[6], x[7], x[8]);
        let v = DVec3::new(x[9], x[10], x[11]);
        let rate = rz.transpose() * (w * dt + 0.5 * wdot * dt * dt);
        let dp = v * dt + 0.5 * pdd * dt * dt;
        let mut next = x;
        for q in 0..3 {
            next[q] += rate[q];
            next[3 + q] += dp[q];
            next[6 + q] += wdot[q] * dt;
            next[9 + q] += pdd[q] * dt;
        }
        x = next;
        for q in 0..NX {
            let p = mpc.predicted()[k][q];
            assert!(
                (x[q] - p).abs() < 1e-9,
                "step {k}, state {q}: {} against {p}",
                x[q]
            );
        }
    }
}

/// Asked to speed up hard on slippery ground, every planned force keeps to
/// the friction pyramid and the normal-force bounds (to the solver's
/// tolerance), and feet planned in the air carry nothing.
#[test]
fn forces_keep_to_friction_and_bounds() {
    let mu = 0.3;
    let mut pb = standing(10, mu);
    for (k, r) in pb.reference.iter_mut().enumerate() {
        let t = 0.05 * (k + 1) as f64;
        r[3] = 2.0 * t;
        r[9] = 4.0;
    }
    for (k, s) in pb.steps.iter_mut().enumerate() {
        s.stance[0] = k % 3 != 1;
    }
    let params = MpcParams::default();
    let mut mpc = Mpc::new(params);
    mpc.solve(&pb).unwrap();
    let (fmin, fmax) = params.normal_force_n;
    let tol = 1e-3;
    let mut pushed = 0.0f64;
    for (k, step) in mpc.planned_forces().iter().enumerate() {
        for (f, force) in step.iter().enumerate() {
            if !pb.steps[k].stance[f] {
                assert_eq!(*force, DVec3::ZERO, "step {k}, foot {f}");
                continue;
            }
            assert!(force.z >= fmin - tol && force.z <= fmax + tol, "{force:?}");
            assert!(force.x.abs() <= mu * force.z + tol, "{force:?}");
            assert!(force.y.abs() <= mu * force.z + tol, "{force:?}");
            pushed = pushed.max(force.x / force.z);
        }
    }
    // the plan uses the friction it has: some foot pushes at the pyramid's edge
    assert!(pushed > 0.9 * mu, "largest fx/fz {pushed}");
}

/// ADMM (the default, warm-started) gives clarabel's plan: over 100 solves
/// of a trot's sequence 0.02 s apart, every planned force of every step
/// within 0.5 N (a stance foot carries 130–200 N; measured worst 0.15 N).
#[test]
fn admm_gives_clarabels_plan() {
    use quadsim_engine::control::mpc::{MpcSolver, trot_benchmark_problem_at};
    let params = MpcParams::default();
    let mut admm = Mpc::new(params);
    let mut clarabel = Mpc::new(MpcParams {
        solver: MpcSolver::Clarabel,
        ..params
    });
    let mut worst = 0.0f64;
    for s in 0..100 {
        let pb = trot_benchmark_problem_at(&params, 0.02 * s as f64);
        admm.solve(&pb).unwrap();
        clarabel.solve(&pb).unwrap();
        for (a, c) in admm.planned_forces().iter().zip(clarabel.planned_forces()) {
            for f in 0..MPC_FEET {
                worst = worst.max((a[f] - c[f]).length());
            }
        }
    }
    assert!(worst < 0.5, "worst force difference {worst} N");
}
