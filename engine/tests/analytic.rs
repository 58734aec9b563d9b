//! Integrated motion against closed-form solutions: the centre of mass of a
//! free-falling articulated robot follows a parabola whatever its joints do,
//! and a compound pendulum keeps its small-angle period. Plus the passive
//! joint model: damping and friction only dissipate, soft limits act only
//! beyond the limit, and actuator torques saturate at the effort limit.

mod common;

use glam::{DMat3, DVec3};
use quadsim_engine::com::center_of_mass;
use quadsim_engine::description::{JointDesc, JointKind, RobotBuilder};
use quadsim_engine::energy::{kinetic_energy, potential_energy};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::{forward_kinematics, forward_kinematics_pos};
use quadsim_engine::model::BaseKind;
use quadsim_engine::passive::PassiveParams;
use quadsim_engine::spatial::Transform;
use quadsim_engine::{Data, Model};

const G: f64 = 9.81;

// ---------------------------------------------------------------- free fall

/// Largest distance (m) between the simulated CoM and `c0 + v0 t + ½ g t²`
/// over `duration_s`, for a random floating tree whose joints are driven by
/// constant torques and damped (all internal forces).
fn com_parabola_error(integrator: Integrator, dt_s: f64, duration_s: f64) -> f64 {
    let mut m = common::model(&common::random_tree(21, 8), BaseKind::Floating);
    for iv in m.base_nv()..m.nv {
        m.damping[iv] = 0.2;
    }
    let mut data = Data::new(&m);
    let mut ws = StepWorkspace::new(&m);
    let (q, v) = common::random_state(&m, 5, 2.0, 1.0);
    let mut s = State { q, v };
    let mut tau = common::random_vec(9, m.nv, 1.0);
    tau[..6].fill(0.0); // no wrench on the base: only internal forces
    forward_kinematics(&m, &mut data, &s.q, &s.v);
    let c0 = center_of_mass(&m, &data);
    let v0 = quadsim_engine::com::com_velocity(&m, &data);
    let n = (duration_s / dt_s).round() as usize;
    let mut worst: f64 = 0.0;
    for k in 1..=n {
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &tau,
            dt_s,
            integrator,
            &mut (),
        );
        let t = k as f64 * dt_s;
        forward_kinematics_pos(&m, &mut data, &s.q);
        let c = center_of_mass(&m, &data);
        let expect = c0 + v0 * t + 0.5 * m.gravity * t * t;
        worst = worst.max((c - expect).length());
    }
    worst
}

#[test]
fn rk4_com_follows_free_fall_parabola() {
    let e = com_parabola_error(Integrator::Rk4, 5e-4, 1.0);
    eprintln!("RK4 CoM parabola error over 1 s at dt = 0.5 ms: {e:.3e} m");
    assert!(e <= 1e-9, "CoM left the parabola by {e:e} m");
}

/// Semi-implicit Euler is first order: the CoM error is O(dt) and halves with dt.
#[test]
fn euler_com_parabola_error_is_first_order() {
    let a = com_parabola_error(Integrator::SemiImplicitEuler, 1e-3, 1.0);
    let b = com_parabola_error(Integrator::SemiImplicitEuler, 5e-4, 1.0);
    eprintln!("Euler CoM parabola error: {a:.3e} m at 1 ms, {b:.3e} m at 0.5 ms");
    assert!(a < 1e-2, "error {a} m");
    let ratio = a / b;
    assert!(
        (1.7..2.3).contains(&ratio),
        "halving dt changed the error {ratio:.2}×, not ≈2×"
    );
}

// ---------------------------------------------------------------- pendulum

/// A compound pendulum: one revolute joint about y at an arbitrary pivot, the
/// bob's CoM `d_m` below the joint, inertia `i_c` about its CoM's y axis.
fn pendulum(mass_kg: f64, d_m: f64, i_c: f64, joint: impl FnOnce(JointDesc) -> JointDesc) -> Model {
    let pivot = DVec3::new(0.1, -0.2, 1.0);
    let j = JointDesc::new(
        "hinge",
        JointKind::Revolute { axis: DVec3::Y },
        "support",
        "bob",
        Transform::from_translation(pivot),
    );
    let d = RobotBuilder::new("pendulum")
        .link("support")
        .done()
        .link("bob")
        .mass(mass_kg)
        .com(DVec3::new(0.0, 0.0, -d_m))
        .inertia(DMat3::from_diagonal(DVec3::new(0.05, i_c, 0.03)))
        .done()
        .joint(joint(j))
        .build();
    common::model(&d, BaseKind::Fixed)
}

/// Period (s) from upward zero crossings of θ, linearly interpolated.
fn measure_period(
    m: &Model,
    integrator: Integrator,
    dt_s: f64,
    theta0: f64,
    periods: f64,
    t_ref: f64,
) -> f64 {
    let mut data = Data::new(m);
    let mut ws = StepWorkspace::new(m);
    let mut s = State {
        q: vec![theta0],
        v: vec![0.0],
    };
    let tau = [0.0];
    let n = (periods * t_ref / dt_s).ceil() as usize;
    let mut crossings = Vec::new();
    for k in 0..n {
        let before = s.q[0];
        step(
            m,
            &mut data,
            &mut ws,
            &mut s,
            &tau,
            dt_s,
            integrator,
            &mut (),
        );
        let after = s.q[0];
        if before < 0.0 && after >= 0.0 {
            crossings.push((k as f64 + before / (before - after)) * dt_s);
        }
    }
    assert!(crossings.len() >= 3, "too few crossings: {crossings:?}");
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

#[test]
fn compound_pendulum_keeps_small_angle_period() {
    let (mass, d, i_c) = (2.0, 0.3, 0.02);
    let m = pendulum(mass, d, i_c, |j| j);
    let t_ref = 2.0 * std::f64::consts::PI * ((i_c + mass * d * d) / (mass * G * d)).sqrt();
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        let t = measure_period(&m, integrator, 1e-3, 0.01, 12.0, t_ref);
        let rel = (t - t_ref).abs() / t_ref;
        eprintln!("{integrator:?}: period {t:.9} s vs {t_ref:.9} s (rel {rel:.2e})");
        assert!(rel <= 1e-4, "{integrator:?}: period {t} s vs {t_ref} s");
    }
}

// ---------------------------------------------------------------- passive

fn total_energy(m: &Model, data: &mut Data, s: &State) -> f64 {
    forward_kinematics(m, data, &s.q, &s.v);
    kinetic_energy(m, data, &s.v) + potential_energy(m, data)
}

/// Viscous damping and Coulomb friction only remove energy: with RK4 the total
/// energy of a free random tree never rises from one step to the next, and
/// most of it is gone after a while.
#[test]
fn damping_and_friction_dissipate_monotonically() {
    let mut m = common::model(&common::random_tree(3, 8), BaseKind::Floating);
    m.gravity = DVec3::ZERO;
    for iv in m.base_nv()..m.nv {
        m.damping[iv] = 0.3;
        m.friction[iv] = 0.1;
    }
    let mut data = Data::new(&m);
    let mut ws = StepWorkspace::new(&m);
    let (q, v) = common::random_state(&m, 8, 2.0, 1.0);
    let mut s = State { q, v };
    let tau = vec![0.0; m.nv];
    let e0 = total_energy(&m, &mut data, &s);
    let mut prev = e0;
    for k in 0..10_000 {
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &tau,
            5e-4,
            Integrator::Rk4,
            &mut (),
        );
        let e = total_energy(&m, &mut data, &s);
        assert!(
            e <= prev + 1e-12 * e0,
            "energy rose at step {k}: {prev} -> {e}"
        );
        prev = e;
    }
    eprintln!("energy {e0:.6} J -> {prev:.6} J over 5 s");
    // The base's rigid-body motion keeps its share; the joints' relative motion decays.
    assert!(prev < 0.9 * e0, "energy barely dissipated: {e0} -> {prev}");
}

/// A damped pendulum in gravity: the total energy decreases monotonically
/// under RK4 (semi-implicit Euler's energy oscillates by O(dt) even without
/// damping, so monotonicity is not meaningful for it).
#[test]
fn damped_pendulum_loses_energy_monotonically() {
    let m = pendulum(2.0, 0.3, 0.02, |mut j| {
        j.damping = 0.2;
        j
    });
    {
        let integrator = Integrator::Rk4;
        let mut data = Data::new(&m);
        let mut ws = StepWorkspace::new(&m);
        let mut s = State {
            q: vec![1.0],
            v: vec![0.0],
        };
        let e_rest = {
            let r = State {
                q: vec![0.0],
                v: vec![0.0],
            };
            total_energy(&m, &mut data, &r)
        };
        let e0 = total_energy(&m, &mut data, &s) - e_rest;
        let mut prev = e0;
        for k in 0..20_000 {
            step(
                &m,
                &mut data,
                &mut ws,
                &mut s,
                &[0.0],
                5e-4,
                integrator,
                &mut (),
            );
            let e = total_energy(&m, &mut data, &s) - e_rest;
            assert!(
                e <= prev + 1e-12 * e0,
                "{integrator:?}: energy rose at step {k}"
            );
            prev = e;
        }
        assert!(prev < 0.1 * e0, "{integrator:?}: {e0} -> {prev}");
    }
}

/// A free joint (zero gravity) coasting at 1 rad/s into a ±0.2 rad limit:
/// no torque at all inside the range, a restoring torque only beyond it, a
/// penetration bounded by the undamped spring's `v·√(I/k)`, and a rebound.
#[test]
fn soft_limit_acts_only_beyond_the_limit() {
    let (mass, d, i_c) = (2.0, 0.3, 0.02);
    let mut m = pendulum(mass, d, i_c, |mut j| {
        j.limits = Some((-0.2, 0.2));
        j
    });
    m.gravity = DVec3::ZERO;
    let inertia = i_c + mass * d * d;
    let params = PassiveParams::default();
    let x_undamped = 1.0 * (inertia / params.limit_stiffness).sqrt();
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        for dir in [1.0, -1.0] {
            let mut data = Data::new(&m);
            let mut ws = StepWorkspace::new(&m);
            let mut s = State {
                q: vec![0.0],
                v: vec![dir],
            };
            let mut deepest: f64 = 0.0;
            for _ in 0..1200 {
                let (q, v) = (s.q[0], s.v[0]);
                step(
                    &m,
                    &mut data,
                    &mut ws,
                    &mut s,
                    &[0.0],
                    5e-4,
                    integrator,
                    &mut (),
                );
                let a = ws.last_acceleration()[0];
                if q.abs() <= 0.2 {
                    // zero up to ABA's round-off; the limit's push is ~5 rad/s² at 1 mrad
                    assert!(
                        a.abs() <= 1e-12,
                        "torque inside the range at q = {q}: a = {a}"
                    );
                } else {
                    // beyond: never pulls outward, and pushes back while moving outward
                    let side = q.signum();
                    assert!(a * side <= 1e-12, "pulled outward at q = {q}, q̇ = {v}");
                    if v * side >= 0.0 {
                        assert!(a * side < 0.0, "no push back at q = {q}, q̇ = {v}");
                    }
                }
                deepest = deepest.max(q.abs() - 0.2);
            }
            eprintln!(
                "{integrator:?} dir {dir}: penetration {deepest:.5} rad (undamped {x_undamped:.5})"
            );
            assert!(
                deepest > 0.5 * x_undamped && deepest <= x_undamped,
                "{deepest}"
            );
            // Rebounded: back inside, moving away from the limit, slower than it came.
            assert!(s.q[0].abs() < 0.2 && s.v[0] * dir < 0.0 && s.v[0].abs() < 1.0);

            // With limits off the joint coasts straight through.
            ws.passive.limits = false;
            let mut s = State {
                q: vec![0.0],
                v: vec![dir],
            };
            for _ in 0..1000 {
                step(
                    &m,
                    &mut data,
                    &mut ws,
                    &mut s,
                    &[0.0],
                    5e-4,
                    integrator,
                    &mut (),
                );
            }
            assert!((s.q[0] - 0.5 * dir).abs() < 1e-9 && s.v[0] == dir);
        }
    }
}

/// An actuator torque beyond the effort limit acts as the limit itself:
/// from rest in zero gravity, one step gives `v = dt·τ_limit/I`.
#[test]
fn actuator_torque_saturates_at_effort_limit() {
    let (mass, d, i_c) = (2.0, 0.3, 0.02);
    let mut m = pendulum(mass, d, i_c, |mut j| {
        j.effort_limit = 10.0;
        j
    });
    m.gravity = DVec3::ZERO;
    let inertia = i_c + mass * d * d;
    let dt = 1e-3;
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        let mut data = Data::new(&m);
        let mut ws = StepWorkspace::new(&m);
        for (cmd, applied) in [(1e4, 10.0), (-250.0, -10.0), (4.0, 4.0)] {
            let mut s = State {
                q: vec![0.0],
                v: vec![0.0],
            };
            step(
                &m,
                &mut data,
                &mut ws,
                &mut s,
                &[cmd],
                dt,
                integrator,
                &mut (),
            );
            let expect = dt * applied / inertia;
            assert!(
                (s.v[0] - expect).abs() <= 1e-12 * expect.abs(),
                "{integrator:?}: command {cmd} gave v = {}, expected {expect}",
                s.v[0]
            );
        }
        // Saturation off: the command passes through.
        ws.passive.saturation = false;
        let mut s = State {
            q: vec![0.0],
            v: vec![0.0],
        };
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &[100.0],
            dt,
            integrator,
            &mut (),
        );
        assert!((s.v[0] - dt * 100.0 / inertia).abs() <= 1e-12 * s.v[0]);
    }
}

/// Regression: the soft limit's damper must not pump energy into a light
/// link. quad16's foot (0.5 kg, I ≈ 6.3e-4 kg·m² about the ankle) spinning into
/// its ±π limit at 40 rad/s used to leave it at ~195 rad/s the other way with
/// the old 5 N·m·s/rad default (b·dt/I = 4 at dt = 0.5 ms). Invariant: with
/// the default passive model, a free spin into the limit never comes out
/// faster than it went in.
#[test]
fn limit_damper_is_stable_on_a_light_foot() {
    use quadsim_engine::Data;
    use quadsim_engine::description::{JointDesc, JointKind, RobotBuilder};
    use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
    use quadsim_engine::model::{BaseKind, Model};
    use quadsim_engine::spatial::Transform;
    let mut joint = JointDesc::new(
        "ankle",
        JointKind::Revolute {
            axis: glam::DVec3::Y,
        },
        "shank",
        "foot",
        Transform::IDENTITY,
    );
    joint.limits = Some((-std::f64::consts::PI, std::f64::consts::PI));
    let d = RobotBuilder::new("foot")
        .link("shank")
        .mass(1.0)
        .done()
        .link("foot")
        .mass(0.5)
        .com(glam::DVec3::new(0.0, 0.0, -0.03))
        .inertia(glam::DMat3::from_diagonal(glam::DVec3::splat(0.00018)))
        .done()
        .joint(joint)
        .build();
    let mut model = Model::from_description(&d, BaseKind::Fixed).unwrap();
    model.gravity = glam::DVec3::ZERO;
    let mut data = Data::new(&model);
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        let mut ws = StepWorkspace::new(&model);
        let mut state = State {
            q: vec![3.0],
            v: vec![40.0],
        };
        let mut peak: f64 = 0.0;
        for _ in 0..400 {
            step(
                &model,
                &mut data,
                &mut ws,
                &mut state,
                &[0.0],
                0.0005,
                integrator,
                &mut (),
            );
            peak = peak.max(state.v[0].abs());
        }
        assert!(
            state.v[0] < 0.0,
            "{integrator:?}: the limit turned the foot back"
        );
        assert!(
            peak <= 40.0 + 1e-9,
            "{integrator:?}: came out at {peak} rad/s from 40"
        );
    }
}
