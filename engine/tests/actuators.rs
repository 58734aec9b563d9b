//! Actuator models against closed-form solutions (`engine/src/actuator_model.rs`):
//! a DC motor spinning up a pure inertia, stall, braking beyond no-load speed,
//! the torque lag's step response, latency in control ticks, friction
//! thresholds, a servo's loop, and no allocation in a step.

use glam::{DMat3, DVec3};
use quadsim_engine::actuator_model::{
    ActuatorBank, ActuatorSpec, MotorParams, ServoParams, add_reflected_inertia,
};
use quadsim_engine::description::RobotBuilder;
use quadsim_engine::integrate::{ForceModel, Integrator, State, StepWorkspace, step};
use quadsim_engine::model::BaseKind;
use quadsim_engine::passive::PassiveParams;
use quadsim_engine::{Data, Model};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations_in;

/// Link inertia about the joint axis (kg·m²).
const I_LINK: f64 = 0.02;

/// A flywheel on a revolute joint about z, fixed base, no gravity: a pure
/// inertia `I_LINK` (+ armature) with no other torque.
fn flywheel() -> Model {
    let d = RobotBuilder::new("flywheel")
        .link("base")
        .mass(1.0)
        .done()
        .link("wheel")
        .mass(2.0)
        .inertia(DMat3::from_diagonal(DVec3::new(0.01, 0.01, I_LINK)))
        .done()
        .revolute("spin", "base", "wheel", DVec3::ZERO, DVec3::Z)
        .build();
    let mut m = Model::from_description(&d, BaseKind::Fixed).unwrap();
    m.gravity = DVec3::ZERO;
    m
}

/// No external forces.
struct NoForces;
impl ForceModel for NoForces {
    fn apply(&mut self, _: &Model, _: &mut Data, _: &[f64], _: &[f64], _: &mut [f64]) {}
}

fn motor(stall_nm: f64, no_load_radps: f64) -> MotorParams {
    MotorParams {
        stall_torque_nm: stall_nm,
        no_load_speed_radps: no_load_radps,
        ..MotorParams::unlimited()
    }
}

/// A flywheel with this actuator: model (with reflected inertia), data, workspace.
fn rig(spec: ActuatorSpec, control_every_steps: u64) -> (Model, Data, StepWorkspace) {
    let mut m = flywheel();
    add_reflected_inertia(&mut m, &[spec]);
    let data = Data::new(&m);
    let mut ws = StepWorkspace::new(&m);
    ws.passive = PassiveParams::none();
    ws.actuators = Some(ActuatorBank::new(&[spec], control_every_steps));
    (m, data, ws)
}

/// Runs `steps` steps under the constant command `tau`, calling `each` after
/// every step with (time at the step's end, state, workspace).
#[expect(clippy::too_many_arguments, reason = "a small test driver")]
fn run(
    m: &Model,
    data: &mut Data,
    ws: &mut StepWorkspace,
    s: &mut State,
    tau: f64,
    dt: f64,
    steps: usize,
    integrator: Integrator,
    mut each: impl FnMut(f64, &State, &StepWorkspace),
) {
    for k in 0..steps {
        step(m, data, ws, s, &[tau], dt, integrator, &mut NoForces);
        each((k + 1) as f64 * dt, s, ws);
    }
}

/// A DC motor at full command spins a pure inertia `J` up along
/// `ω = ω₀ (1 − e^{−t/T})`, `T = J ω₀ / τ_s`, the reflected rotor inertia
/// `J_r N²` counted in `J`. RK4 at 1 ms over 3 T: error < 1e-9 ω₀ (the
/// envelope is linear in q̇ on the way up, so the vector field is smooth).
#[test]
fn motor_spins_an_inertia_up_to_no_load_speed_exponentially() {
    let (stall, w0) = (0.5, 20.0);
    let mut mp = motor(stall, w0);
    mp.gear_ratio = 50.0;
    mp.rotor_inertia_kgm2 = 2e-6; // reflected: 5e-3 kg·m²
    let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(mp), 1);
    let j = I_LINK + 2e-6 * 2500.0;
    assert!((m.armature[0] - 5e-3).abs() < 1e-15);
    let t_c = j * w0 / stall; // 1 s
    let mut s = State::neutral(&m);
    let dt = 1e-3;
    let mut worst = 0.0f64;
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        10.0,
        dt,
        3000,
        Integrator::Rk4,
        |t, s, _| {
            let exact = w0 * (1.0 - (-t / t_c).exp());
            worst = worst.max((s.v[0] - exact).abs());
        },
    );
    assert!(worst < 1e-9 * w0, "worst speed error {worst} rad/s");
    // and the speed never passes ω₀ however long it runs
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        10.0,
        dt,
        20000,
        Integrator::Rk4,
        |_, s, _| {
            assert!(s.v[0] <= w0);
        },
    );
    assert!((s.v[0] - w0).abs() < 1e-6);
    // Semi-implicit Euler, first order: within 1e-3 ω₀ at 1 ms.
    let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(mp), 1);
    let mut s = State::neutral(&m);
    let mut worst = 0.0f64;
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        10.0,
        dt,
        3000,
        Integrator::SemiImplicitEuler,
        |t, s, _| {
            worst = worst.max((s.v[0] - w0 * (1.0 - (-t / t_c).exp())).abs());
        },
    );
    assert!(worst < 1e-3 * w0, "Euler: worst speed error {worst} rad/s");
}

/// At stall (q̇ = 0) an over-large command gives exactly τ_s either way; a
/// joint held at rest by an opposing load sees τ_s; at ω₀ the drive gives 0.
#[test]
fn stall_torque_at_rest_and_nothing_at_no_load_speed() {
    let (stall, w0) = (0.3, 5.0);
    let spec = ActuatorSpec::dc_motor(motor(stall, w0));
    for (cmd, expect) in [(5.0, stall), (-5.0, -stall), (0.1, 0.1)] {
        let (m, mut data, mut ws) = rig(spec, 1);
        let mut s = State::neutral(&m);
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &[cmd],
            1e-4,
            Integrator::SemiImplicitEuler,
            &mut NoForces,
        );
        let bank = ws.actuators.as_ref().unwrap();
        assert_eq!(bank.applied()[0], expect);
        assert_eq!(bank.at_envelope()[0], cmd.abs() > stall);
        assert!((ws.last_acceleration()[0] - expect / I_LINK).abs() < 1e-12);
    }
    // Blocked joint: a load torque of exactly τ_s holds the motor at rest.
    struct Load(f64);
    impl ForceModel for Load {
        fn apply(&mut self, _: &Model, _: &mut Data, _: &[f64], _: &[f64], tau: &mut [f64]) {
            tau[0] -= self.0;
        }
    }
    let (m, mut data, mut ws) = rig(spec, 1);
    let mut s = State::neutral(&m);
    for _ in 0..1000 {
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &[10.0],
            1e-3,
            Integrator::Rk4,
            &mut Load(stall),
        );
    }
    assert!(s.v[0].abs() < 1e-12 && s.q[0].abs() < 1e-12, "{:?}", s);
    // At ω₀ a full forward command gives no torque; reverse gives −τ_s.
    let (m, mut data, mut ws) = rig(spec, 1);
    for (cmd, acc) in [(10.0, 0.0), (-10.0, -stall / I_LINK)] {
        let mut s = State {
            q: vec![0.0],
            v: vec![w0],
        };
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &[cmd],
            1e-4,
            Integrator::SemiImplicitEuler,
            &mut NoForces,
        );
        assert!((ws.last_acceleration()[0] - acc).abs() < 1e-12);
    }
}

/// Spun to 1.5 ω₀ with full forward command the motor brakes (back-EMF above
/// the supply): `ω = ω₀ + ½ω₀ e^{−t/T}` back down to ω₀.
#[test]
fn beyond_no_load_speed_the_motor_brakes() {
    let (stall, w0) = (0.4, 10.0);
    let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(motor(stall, w0)), 1);
    let t_c = I_LINK * w0 / stall;
    let mut s = State {
        q: vec![0.0],
        v: vec![1.5 * w0],
    };
    let dt = 1e-3;
    let mut worst = 0.0f64;
    let mut first = true;
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        10.0,
        dt,
        2000,
        Integrator::Rk4,
        |t, s, ws| {
            if first {
                // braking torque −τ_s/2 at the start
                assert!((ws.actuators.as_ref().unwrap().applied()[0] + 0.5 * stall).abs() < 1e-12);
                first = false;
            }
            worst = worst.max((s.v[0] - (w0 + 0.5 * w0 * (-t / t_c).exp())).abs());
        },
    );
    assert!(worst < 1e-9 * w0, "worst {worst}");
}

/// The lag's state follows `1 − e^{−2πf t}` exactly at the step times (exact
/// discretisation), and the torque of each step is its exact mean over the step.
#[test]
fn lag_step_response_is_exact() {
    let f = 25.0;
    let mut mp = motor(100.0, 1e6);
    mp.bandwidth_hz = f;
    let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(mp), 1);
    let mut s = State::neutral(&m);
    let dt = 5e-4;
    let a = 2.0 * std::f64::consts::PI * f;
    let mut worst: f64 = 0.0;
    let mut k = 0usize;
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        1.0,
        dt,
        400,
        Integrator::SemiImplicitEuler,
        |t, _, ws| {
            let bank = ws.actuators.as_ref().unwrap();
            let t0 = k as f64 * dt;
            let state_exact = 1.0 - (-a * t).exp();
            // mean of 1 − e^{−a t} over [t0, t0 + dt]
            let mean_exact = 1.0 - ((-a * t0).exp() - (-a * t).exp()) / (a * dt);
            worst = worst
                .max((bank.lag_state()[0] - state_exact).abs())
                .max((bank.demand()[0] - mean_exact).abs());
            k += 1;
        },
    );
    assert!(worst < 1e-12, "worst {worst}");
    // after 5 time constants the torque is within e^{−5} of the command
    assert!((1.0 - ws.actuators.as_ref().unwrap().demand()[0]) < (-5.0f64).exp());
}

/// With a latency of N control ticks (4 steps per tick), a command change at
/// tick k reaches the joint at tick k + N, not a step earlier or later.
#[test]
fn latency_delays_by_exactly_n_ticks() {
    for n in [0usize, 1, 3] {
        let mut mp = motor(100.0, 1e6);
        mp.latency_ticks = n;
        let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(mp), 4);
        let mut s = State::neutral(&m);
        let mut first_step_with_new = None;
        for k in 0..40u64 {
            // the command changes from 1 to 2 at step 8 (tick 2) and is then held
            let cmd = if k >= 8 { 2.0 } else { 1.0 };
            step(
                &m,
                &mut data,
                &mut ws,
                &mut s,
                &[cmd],
                1e-3,
                Integrator::SemiImplicitEuler,
                &mut NoForces,
            );
            let applied = ws.actuators.as_ref().unwrap().applied()[0];
            assert!(applied == 1.0 || applied == 2.0, "{applied}");
            if applied == 2.0 && first_step_with_new.is_none() {
                first_step_with_new = Some(k);
            }
        }
        assert_eq!(first_step_with_new, Some(8 + 4 * n as u64), "latency {n}");
    }
}

/// Coulomb friction f_c (regularised, ε) with viscous b under a motor: below
/// the threshold the joint only creeps at `ε·atanh(τ/f_c)` (no viscous), above
/// it the terminal speed solves `τ_s (1 − ω/ω₀) − b ω − f_c = 0` (tanh = 1).
#[test]
fn friction_threshold_and_terminal_speed() {
    let eps = PassiveParams::default().friction_epsilon;
    let fc = 0.2;
    // below the threshold: command 0.1 N·m against f_c = 0.2 N·m
    let mut mp = motor(1.0, 1e9);
    mp.coulomb_nm = fc;
    let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(mp), 1);
    ws.passive.friction_epsilon = eps;
    let mut s = State::neutral(&m);
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        0.1,
        1e-3,
        5000,
        Integrator::Rk4,
        |_, _, _| {},
    );
    let creep = eps * (0.5f64).atanh();
    assert!((s.v[0] - creep).abs() < 1e-9, "creep {} vs {creep}", s.v[0]);
    // above: full command, with viscous friction and the envelope
    let (stall, w0, b) = (1.0, 30.0, 0.02);
    let mut mp = motor(stall, w0);
    mp.coulomb_nm = fc;
    mp.viscous_nms_per_rad = b;
    let (m, mut data, mut ws) = rig(ActuatorSpec::dc_motor(mp), 1);
    ws.passive.friction_epsilon = eps;
    let mut s = State::neutral(&m);
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        5.0,
        1e-3,
        10000,
        Integrator::Rk4,
        |_, _, _| {},
    );
    let terminal = (stall - fc) / (b + stall / w0);
    assert!((s.v[0] - terminal).abs() < 1e-6, "{} vs {terminal}", s.v[0]);
}

/// A servo (PD at 200 Hz inside it) turns a flywheel to its target: it
/// settles there, its torque never exceeds τ_s, and the joint never exceeds
/// ω₀ (the loop's damping ratio is 0.6 on the flywheel; the move starts at
/// the envelope, as a hobby servo's does).
#[test]
fn servo_reaches_its_target_within_its_envelope() {
    let (stall, w0) = (0.3, 6.0);
    let servo = ServoParams {
        kp_nm_per_rad: 3.0,
        kd_nms_per_rad: 0.3,
        rate_hz: 200.0,
    };
    let (m, mut data, mut ws) = rig(ActuatorSpec::servo(motor(stall, w0), servo), 4);
    ws.actuators.as_mut().unwrap().set_targets(&[1.0]);
    let mut s = State::neutral(&m);
    let (mut peak_tau, mut peak_speed) = (0.0f64, 0.0f64);
    run(
        &m,
        &mut data,
        &mut ws,
        &mut s,
        0.0,
        5e-4,
        8000,
        Integrator::Rk4,
        |_, s, ws| {
            let b = ws.actuators.as_ref().unwrap();
            peak_tau = peak_tau.max(b.applied()[0].abs());
            peak_speed = peak_speed.max(s.v[0].abs());
        },
    );
    assert!(peak_tau <= stall, "{peak_tau}");
    assert!(peak_speed <= w0 * (1.0 + 1e-9), "{peak_speed}");
    // the target is reached (no load: no steady error)
    assert!((s.q[0] - 1.0).abs() < 1e-3, "q = {}", s.q[0]);
    // the first half of the move ran at the envelope (command ≫ stall)
    assert!(peak_tau == stall);
}

/// A servo never given a target holds its start angle: under a constant
/// load τ_L its steady error is τ_L / kp (the angle does not drift).
#[test]
fn servo_without_target_holds_its_start_angle() {
    struct Load(f64);
    impl ForceModel for Load {
        fn apply(&mut self, _: &Model, _: &mut Data, _: &[f64], _: &[f64], tau: &mut [f64]) {
            tau[0] -= self.0;
        }
    }
    let servo = ServoParams {
        kp_nm_per_rad: 2.0,
        kd_nms_per_rad: 0.3,
        rate_hz: 1000.0,
    };
    let (m, mut data, mut ws) = rig(ActuatorSpec::servo(motor(0.3, 6.0), servo), 1);
    let mut s = State {
        q: vec![0.5],
        v: vec![0.0],
    };
    for _ in 0..10000 {
        step(
            &m,
            &mut data,
            &mut ws,
            &mut s,
            &[0.0],
            5e-4,
            Integrator::Rk4,
            &mut Load(0.1),
        );
    }
    let expected = 0.5 - 0.1 / 2.0;
    assert!((s.q[0] - expected).abs() < 1e-6, "q = {}", s.q[0]);
}

/// A step with motors, a lag, latency and a servo allocates nothing.
#[test]
fn no_allocation_in_a_step_with_actuators() {
    let d = RobotBuilder::new("two")
        .link("base")
        .mass(1.0)
        .done()
        .link("a")
        .mass(1.0)
        .com(DVec3::new(0.1, 0.0, 0.0))
        .inertia(DMat3::from_diagonal(DVec3::splat(0.01)))
        .done()
        .link("b")
        .mass(1.0)
        .com(DVec3::new(0.1, 0.0, 0.0))
        .inertia(DMat3::from_diagonal(DVec3::splat(0.01)))
        .done()
        .revolute("j0", "base", "a", DVec3::ZERO, DVec3::Y)
        .revolute("j1", "a", "b", DVec3::new(0.2, 0.0, 0.0), DVec3::Y)
        .build();
    let mut m = Model::from_description(&d, BaseKind::Fixed).unwrap();
    let mut mp = motor(2.0, 10.0);
    mp.bandwidth_hz = 50.0;
    mp.latency_ticks = 2;
    mp.coulomb_nm = 0.05;
    let specs = [
        ActuatorSpec::dc_motor(mp),
        ActuatorSpec::servo(
            mp,
            ServoParams {
                kp_nm_per_rad: 5.0,
                kd_nms_per_rad: 0.1,
                rate_hz: 500.0,
            },
        ),
    ];
    add_reflected_inertia(&mut m, &specs);
    let mut data = Data::new(&m);
    let mut ws = StepWorkspace::new(&m);
    ws.actuators = Some(ActuatorBank::new(&specs, 4));
    let mut s = State::neutral(&m);
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        let n = allocations_in(|| {
            for k in 0..200 {
                ws.actuators.as_mut().unwrap().set_targets(&[0.0, 0.5]);
                let tau = [(k as f64 * 0.01).sin(), 0.0];
                step(
                    &m,
                    &mut data,
                    &mut ws,
                    &mut s,
                    &tau,
                    5e-4,
                    integrator,
                    &mut NoForces,
                );
            }
        });
        assert_eq!(n, 0, "{integrator:?}");
    }
    assert!(s.q.iter().all(|x| x.is_finite()));
}
