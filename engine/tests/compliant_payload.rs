//! Compliant (sloshing) payloads: a load on a spring–damper, with its DOFs
//! appended to the robot's articulation. Checked against the analytic
//! damped oscillator, the conservation of energy (robot + load + spring) and
//! of momentum (the spring is an internal force).

mod common;

use glam::DVec3;
use quadsim_engine::com::momentum_about_com;
use quadsim_engine::description::{LinkDesc, RobotDescription, Shape};
use quadsim_engine::energy::{kinetic_energy, potential_energy, spring_energy};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::BaseKind;
use quadsim_engine::passive::PassiveParams;
use quadsim_engine::payload::{Compliance, DofSpring, LoadDof, Payload};
use quadsim_engine::{Data, Model, robots};

const LOAD_KG: f64 = 3.0;
const BOX_M: DVec3 = DVec3::new(0.2, 0.2, 0.1);

fn load(dofs: &[(LoadDof, f64, f64)]) -> Payload {
    Payload {
        name: "tank".into(),
        mass_kg: LOAD_KG,
        shape: Shape::Box { size_m: BOX_M },
        offset_m: DVec3::new(0.05, 0.0, 0.12),
        compliance: Some(Compliance {
            dofs: dofs
                .iter()
                .map(|&(dof, stiffness, damping)| DofSpring {
                    dof,
                    stiffness,
                    damping,
                })
                .collect(),
        }),
    }
}

/// A 20 kg torso welded to the world, carrying `p`.
fn held_torso(p: &Payload) -> Model {
    let mut desc = RobotDescription::new("torso");
    let mut torso = LinkDesc::new("torso");
    torso.mass_kg = 20.0;
    torso.inertia_kgm2 = Shape::Box {
        size_m: DVec3::new(0.6, 0.3, 0.15),
    }
    .solid_inertia(20.0);
    desc.links.push(torso);
    p.attach_to(&mut desc).unwrap();
    Model::from_description(&desc, BaseKind::Fixed).unwrap()
}

/// Damped oscillator from rest at displacement `x0`:
/// `x = x0 e^{−ζωt} (cos ω_d t + ζω/ω_d sin ω_d t)`.
fn oscillator(x0: f64, omega: f64, zeta: f64, t: f64) -> f64 {
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    x0 * (-zeta * omega * t).exp() * ((wd * t).cos() + zeta * omega / wd * (wd * t).sin())
}

/// Integrates the held-torso model with RK4 at `dt_s` for `duration_s`,
/// returning the trajectories of every load coordinate.
fn simulate(model: &Model, q0: &[f64], dt_s: f64, duration_s: f64) -> Vec<Vec<f64>> {
    let mut data = Data::new(model);
    let mut ws = StepWorkspace::new(model);
    ws.passive = PassiveParams::none();
    let mut s = State {
        q: q0.to_vec(),
        v: vec![0.0; model.nv],
    };
    let tau = vec![0.0; model.nv];
    let n = (duration_s / dt_s).round() as usize;
    let mut out = vec![s.q.clone()];
    for _ in 0..n {
        step(
            model,
            &mut data,
            &mut ws,
            &mut s,
            &tau,
            dt_s,
            Integrator::Rk4,
            &mut (),
        );
        out.push(s.q.clone());
    }
    out
}

/// On a torso held fixed, the load's z and pitch coordinates are two
/// independent oscillators (the load's centre is on the pitch axis, so
/// gravity only shifts z's equilibrium to −m g / k): undamped at
/// ω = √(k/m) and √(k/I_yy), damped with ω_d = ω √(1 − ζ²). The simulated
/// trajectory matches the closed form to 1e-6 of the amplitude; the period
/// from zero crossings matches 2π/ω to 0.1 %, and the ratio of successive
/// peaks matches e^{−2πζ/√(1−ζ²)} to 0.5 %.
#[test]
fn held_load_oscillates_at_the_analytic_frequency_and_decay() {
    let (kz, kp) = (500.0, 20.0);
    let iyy = LOAD_KG * (BOX_M.x * BOX_M.x + BOX_M.z * BOX_M.z) / 12.0;
    let (wz, wp) = ((kz / LOAD_KG).sqrt(), (kp / iyy).sqrt());
    for zeta in [0.0, 0.1] {
        let (bz, bp) = (
            2.0 * zeta * (kz * LOAD_KG).sqrt(),
            2.0 * zeta * (kp * iyy).sqrt(),
        );
        let p = load(&[(LoadDof::Pitch, kp, bp), (LoadDof::Z, kz, bz)]);
        let model = held_torso(&p);
        assert_eq!((model.nq, model.nv, model.load_nv), (2, 2, 2));
        assert_eq!(model.actuated_nv(), 0);
        let z_eq = -LOAD_KG * 9.81 / kz;
        let (dz, dp) = (0.02, 0.1);
        let dt = 1e-4;
        let traj = simulate(&model, &[z_eq + dz, dp], dt, 2.0);
        let mut err: f64 = 0.0;
        for (i, q) in traj.iter().enumerate() {
            let t = i as f64 * dt;
            err = err
                .max((q[0] - z_eq - oscillator(dz, wz, zeta, t)).abs() / dz)
                .max((q[1] - oscillator(dp, wp, zeta, t)).abs() / dp);
        }
        // zero crossings of z about its equilibrium: mean half period
        let x: Vec<f64> = traj.iter().map(|q| q[0] - z_eq).collect();
        let crossings: Vec<f64> = (1..x.len())
            .filter(|&i| x[i - 1].signum() != x[i].signum())
            .map(|i| (i as f64 - 1.0 + x[i - 1] / (x[i - 1] - x[i])) * dt)
            .collect();
        let half = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let wd = wz * (1.0 - zeta * zeta).sqrt();
        let period_err = (2.0 * half - 2.0 * std::f64::consts::PI / wd).abs() * wd
            / (2.0 * std::f64::consts::PI);
        // peaks of z (local maxima above equilibrium): ratio of successive ones
        let peaks: Vec<f64> = (1..x.len() - 1)
            .filter(|&i| x[i] > x[i - 1] && x[i] >= x[i + 1] && x[i] > 0.0)
            .map(|i| x[i])
            .collect();
        let ratio = peaks[2] / peaks[1];
        let want_ratio = (-2.0 * std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        eprintln!(
            "ζ = {zeta}: ω_z = {wz:.4} rad/s, ω_pitch = {wp:.4} rad/s; max error {err:.2e} \
             of amplitude; period error {:.4} %; peak ratio {ratio:.5} (analytic {want_ratio:.5})",
            period_err * 100.0
        );
        assert!(err < 1e-6, "trajectory error {err:.3e} of amplitude");
        assert!(period_err < 1e-3, "period error {period_err:.3e}");
        assert!(
            (ratio / want_ratio - 1.0).abs() < 5e-3,
            "peak ratio {ratio} vs {want_ratio}"
        );
    }
}

/// quad16 floating with a load free in all six DOFs (springs, no damping),
/// under gravity, no ground, no actuation, ideal joints: RK4 at 0.5 ms over
/// 2 s conserves the total energy T + V_gravity + V_spring to 1e-7 of the
/// energy that sloshes (the initial kinetic plus spring energy), while the
/// spring's own energy swings by much more than that.
#[test]
fn robot_load_and_spring_conserve_energy_without_damping() {
    let p = load(&[
        (LoadDof::X, 400.0, 0.0),
        (LoadDof::Y, 300.0, 0.0),
        (LoadDof::Z, 600.0, 0.0),
        (LoadDof::Roll, 15.0, 0.0),
        (LoadDof::Pitch, 20.0, 0.0),
        (LoadDof::Yaw, 10.0, 0.0),
    ]);
    let mut desc = robots::builtin("quad16").unwrap();
    let bare = Model::from_description(&desc, BaseKind::Floating).unwrap();
    p.attach_to(&mut desc).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    assert_eq!(model.nv, bare.nv + 6);
    assert_eq!(model.actuated_nv(), bare.nv);
    assert_eq!(model.nbodies, bare.nbodies + 6);
    assert_eq!(&model.parent[..bare.nbodies], &bare.parent[..]);
    let (mut q, mut v) = common::random_state(&model, 11, 1.0, 0.5);
    let nl = model.actuated_nq();
    for (k, x) in [0.03, -0.02, 0.04, 0.2, -0.15, 0.1].into_iter().enumerate() {
        q[nl + k] = x;
        v[model.actuated_nv() + k] = -x;
    }
    let mut s = State { q, v };
    let mut data = Data::new(&model);
    let mut ws = StepWorkspace::new(&model);
    ws.passive = PassiveParams::none();
    let tau = vec![0.0; model.nv];
    let energies = |s: &State, data: &mut Data| {
        forward_kinematics(&model, data, &s.q, &s.v);
        let t = kinetic_energy(&model, data, &s.v);
        let es = spring_energy(&model, &s.q);
        (t + potential_energy(&model, data) + es, t, es)
    };
    let (e0, t0, es0) = energies(&s, &mut data);
    let scale = t0 + es0;
    let (mut drift, mut es_min, mut es_max) = (0.0f64, es0, es0);
    for _ in 0..4000 {
        step(
            &model,
            &mut data,
            &mut ws,
            &mut s,
            &tau,
            5e-4,
            Integrator::Rk4,
            &mut (),
        );
        let (e, _, es) = energies(&s, &mut data);
        drift = drift.max((e - e0).abs());
        es_min = es_min.min(es);
        es_max = es_max.max(es);
    }
    eprintln!(
        "E0 = {e0:.4} J, sloshing energy {scale:.4} J, max |E − E0| = {drift:.3e} J \
         ({:.2e} of it); spring energy {es_min:.4}–{es_max:.4} J",
        drift / scale
    );
    assert!(drift < 1e-7 * scale, "energy drift {drift:.3e} J");
    assert!(es_max - es_min > 0.1 * scale, "the load hardly sloshed");
}

/// In zero gravity a floating quad16 with a sloshing, damped load keeps its
/// total linear momentum and its angular momentum about the CoM (the
/// spring–damper is an internal force): the torso's velocity swings as it
/// trades momentum with the load, the total does not move. Energy falls
/// (the damper dissipates).
#[test]
fn load_and_robot_exchange_momentum_consistently() {
    let p = load(&[
        (LoadDof::X, 400.0, 5.0),
        (LoadDof::Y, 300.0, 5.0),
        (LoadDof::Z, 600.0, 5.0),
        (LoadDof::Pitch, 20.0, 0.2),
    ]);
    let mut desc = robots::builtin("quad16").unwrap();
    p.attach_to(&mut desc).unwrap();
    let mut model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    model.gravity = DVec3::ZERO;
    let mut q = model.neutral_q();
    let mut v = vec![0.0; model.nv];
    let nl = model.actuated_nv();
    // the load thrown forward and up relative to the torso
    v[nl] = 1.0;
    v[nl + 2] = 0.5;
    q[nl + 1] = 0.03;
    let mut s = State { q, v };
    let mut data = Data::new(&model);
    let mut ws = StepWorkspace::new(&model);
    ws.passive = PassiveParams::none();
    let tau = vec![0.0; model.nv];
    forward_kinematics(&model, &mut data, &s.q, &s.v);
    let (p0, l0) = momentum_about_com(&model, &data);
    let t0 = kinetic_energy(&model, &data, &s.v) + spring_energy(&model, &s.q);
    let (mut dp, mut dl) = (0.0f64, 0.0f64);
    let (mut vx_min, mut vx_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for _ in 0..4000 {
        step(
            &model,
            &mut data,
            &mut ws,
            &mut s,
            &tau,
            5e-4,
            Integrator::Rk4,
            &mut (),
        );
        forward_kinematics(&model, &mut data, &s.q, &s.v);
        let (p, l) = momentum_about_com(&model, &data);
        dp = dp.max((p - p0).length());
        dl = dl.max((l - l0).length());
        let vx = data.vel[0].lin.x;
        vx_min = vx_min.min(vx);
        vx_max = vx_max.max(vx);
    }
    let t1 = kinetic_energy(&model, &data, &s.v) + spring_energy(&model, &s.q);
    eprintln!(
        "|p0| = {:.4} kg·m/s, max |Δp| = {dp:.2e}; max |ΔL| = {dl:.2e}; torso vx \
         {vx_min:.4}…{vx_max:.4} m/s; energy {t0:.4} → {t1:.4} J",
        p0.length()
    );
    assert!(p0.length() > 3.0);
    assert!(dp < 1e-9 * p0.length(), "linear momentum drift {dp:.3e}");
    assert!(
        dl < 1e-9 * p0.length().max(1.0),
        "angular momentum drift {dl:.3e}"
    );
    assert!(vx_max - vx_min > 0.05, "the torso did not trade momentum");
    assert!(t1 < 0.9 * t0, "the damper dissipated nothing: {t0} → {t1}");
}

/// Bad compliant payloads say why; a sprung joint that does not close the
/// description is refused by the model compiler.
#[test]
fn bad_compliant_payloads_say_why() {
    let mut desc = robots::builtin("quad16").unwrap();
    let err = |p: Payload, desc: &mut RobotDescription| p.attach_to(desc).unwrap_err().to_string();
    assert!(err(load(&[]), &mut desc).contains("at least one DOF"));
    assert!(err(load(&[(LoadDof::Z, 0.0, 0.0)]), &mut desc).contains("stiffness"));
    assert!(err(load(&[(LoadDof::Z, 10.0, -1.0)]), &mut desc).contains("damping"));
    assert!(
        err(
            load(&[(LoadDof::Z, 10.0, 0.0), (LoadDof::Z, 5.0, 0.0)]),
            &mut desc
        )
        .contains("twice")
    );
    let mut p = load(&[(LoadDof::Z, 10.0, 0.0)]);
    p.mass_kg = 0.0;
    assert!(err(p, &mut desc).contains("mass"));
    // a load attached, then a leg joint moved after it: refused
    load(&[(LoadDof::Z, 10.0, 0.0)])
        .attach_to(&mut desc)
        .unwrap();
    let j = desc.joints.remove(0);
    desc.joints.push(j);
    let e = Model::from_description(&desc, BaseKind::Floating).unwrap_err();
    assert!(e.to_string().contains("spring"), "{e}");
}
