//! Sensor models: statistics of each noise model over many samples, and the
//! IMU, encoders, contact sensors and motion capture on known motion.
//!
//! Statistical bounds: a sample mean of N draws with std σ has standard
//! error σ/√N; a sample variance of N Gaussian draws with variance σ² has
//! standard error σ²√(2/(N−1)). Every check allows 5 standard errors (a
//! false failure about once in 1.7 million runs; the draws are seeded, so a
//! run is reproducible anyway).

use glam::{DMat3, DQuat, DVec3};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model, STANDARD_GRAVITY};
use quadsim_engine::sensors::contact::hysteresis;
use quadsim_engine::sensors::noise::{NoiseChannel, NoiseParams, quantize};
use quadsim_engine::sensors::{
    ContactSensorParams, ContactSensors, EncoderParams, Encoders, Imu, ImuParams,
    JointVelocityMode, Mocap, MocapParams, RateGate, SensorConfig, SensorStream, SensorSuite,
    SensorTruth, sensor_rng,
};
use quadsim_engine::{Data, robots};

fn mean_var(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (n - 1.0);
    (m, v)
}

/// `|got − want| ≤ 5 se`.
fn within_5se(what: &str, got: f64, want: f64, se: f64) {
    assert!(
        (got - want).abs() <= 5.0 * se,
        "{what}: {got} vs {want} (5 se = {})",
        5.0 * se
    );
}

#[test]
fn white_noise_mean_and_variance_within_bounds() {
    let mut rng = sensor_rng(7, SensorStream::Imu);
    let sigma = 0.3;
    let truth = 1.5;
    let mut ch = NoiseChannel::new(NoiseParams::white(sigma), &mut rng);
    let n = 200_000;
    let x: Vec<f64> = (0..n).map(|_| ch.sample(truth, 0.002, &mut rng)).collect();
    let (m, v) = mean_var(&x);
    within_5se("mean", m, truth, sigma / (n as f64).sqrt());
    within_5se(
        "variance",
        v,
        sigma * sigma,
        sigma * sigma * (2.0 / (n as f64 - 1.0)).sqrt(),
    );
}

#[test]
fn turn_on_bias_is_constant_per_channel_and_distributed_over_channels() {
    let mut rng = sensor_rng(11, SensorStream::Imu);
    let sb = 0.2;
    let p = NoiseParams {
        bias_std: sb,
        ..NoiseParams::NONE
    };
    let m = 20_000;
    let mut biases = Vec::with_capacity(m);
    for _ in 0..m {
        let mut ch = NoiseChannel::new(p, &mut rng);
        let a = ch.sample(0.0, 0.01, &mut rng);
        let b = ch.sample(0.0, 0.01, &mut rng);
        assert_eq!(a, b, "no walk, no white noise: the bias holds");
        biases.push(a);
    }
    let (mean, var) = mean_var(&biases);
    within_5se("bias mean", mean, 0.0, sb / (m as f64).sqrt());
    within_5se(
        "bias variance",
        var,
        sb * sb,
        sb * sb * (2.0 / (m as f64 - 1.0)).sqrt(),
    );
}

/// Over an ensemble of channels the bias random walk's variance is
/// `σ_w² t`: its std grows as `√t` (checked at 1, 4 and 16 s).
#[test]
fn bias_random_walk_variance_grows_linearly_in_time() {
    let mut rng = sensor_rng(3, SensorStream::Imu);
    let sw = 0.05;
    let p = NoiseParams {
        bias_walk_std_per_sqrt_s: sw,
        ..NoiseParams::NONE
    };
    let m = 4000;
    let dt = 0.01;
    let checkpoints = [100usize, 400, 1600]; // samples: t = 1, 4, 16 s
    let mut at: Vec<Vec<f64>> = vec![Vec::with_capacity(m); checkpoints.len()];
    for _ in 0..m {
        let mut ch = NoiseChannel::new(p, &mut rng);
        for k in 1..=*checkpoints.last().unwrap() {
            let y = ch.sample(0.0, dt, &mut rng);
            if let Some(c) = checkpoints.iter().position(|&c| c == k) {
                at[c].push(y);
            }
        }
    }
    let mut stds = Vec::new();
    for (c, &k) in checkpoints.iter().enumerate() {
        let t = k as f64 * dt;
        let (mean, var) = mean_var(&at[c]);
        let want = sw * sw * t;
        within_5se(
            &format!("walk mean at {t} s"),
            mean,
            0.0,
            want.sqrt() / (m as f64).sqrt(),
        );
        within_5se(
            &format!("walk variance at {t} s"),
            var,
            want,
            want * (2.0 / (m as f64 - 1.0)).sqrt(),
        );
        stds.push(var.sqrt());
    }
    // std ∝ √t: 4× the time, 2× the std (5 se of a std is 5·σ/√(2(M−1)) relative)
    let rel = 5.0 / (2.0 * (m as f64 - 1.0)).sqrt();
    for w in stds.windows(2) {
        let ratio = w[1] / w[0];
        assert!((ratio - 2.0).abs() <= 2.0 * 2.0 * rel, "std ratio {ratio}");
    }
}

#[test]
fn quantisation_rounds_to_the_step_with_uniform_error() {
    let q = 0.01;
    let mut rng = sensor_rng(5, SensorStream::Encoders);
    let mut ch = NoiseChannel::new(
        NoiseParams {
            quantum: q,
            ..NoiseParams::NONE
        },
        &mut rng,
    );
    let n = 100_000;
    let mut err = Vec::with_capacity(n);
    for k in 0..n {
        // truths spread over many steps, incommensurate with q
        let x = (k as f64) * 0.000_731_3 - 30.0;
        let y = ch.sample(x, 0.001, &mut rng);
        let steps = y / q;
        assert!(
            (steps - steps.round()).abs() < 1e-9,
            "{y} is a multiple of {q}"
        );
        assert!((y - x).abs() <= 0.5 * q + 1e-12);
        err.push(y - x);
    }
    // uniform on [−q/2, q/2]: mean 0, variance q²/12; standard errors of a
    // uniform sample: mean (q/√12)/√N, variance (q²/12)·√(0.8/N)
    let (m, v) = mean_var(&err);
    let n = n as f64;
    within_5se(
        "quantisation error mean",
        m,
        0.0,
        q / 12f64.sqrt() / n.sqrt(),
    );
    within_5se(
        "quantisation error variance",
        v,
        q * q / 12.0,
        q * q / 12.0 * (0.8 / n).sqrt(),
    );
    assert_eq!(quantize(0.014, 0.01), 0.01);
    assert_eq!(quantize(0.016, 0.01), 0.02);
    assert_eq!(quantize(0.3, 0.0), 0.3);
}

#[test]
fn saturation_clamps_to_the_full_scale() {
    let mut rng = sensor_rng(1, SensorStream::Imu);
    let mut ch = NoiseChannel::new(
        NoiseParams {
            saturation: 2.0,
            ..NoiseParams::NONE
        },
        &mut rng,
    );
    assert_eq!(ch.sample(5.0, 0.01, &mut rng), 2.0);
    assert_eq!(ch.sample(-7.0, 0.01, &mut rng), -2.0);
    assert_eq!(ch.sample(1.25, 0.01, &mut rng), 1.25);
}

#[test]
fn contact_hysteresis_switches_at_its_two_thresholds() {
    let (on, off) = (20.0, 10.0);
    let forces = [0.0, 15.0, 20.0, 25.0, 15.0, 10.0, 9.9, 15.0, 20.1];
    let want = [false, false, false, true, true, true, false, false, true];
    let mut s = false;
    for (f, w) in forces.iter().zip(want) {
        s = hysteresis(s, *f, on, off);
        assert_eq!(s, w, "force {f}");
    }
    // through the sensor, noise-free, at 100 Hz on a 1 kHz clock
    let p = ContactSensorParams {
        rate_hz: 100.0,
        on_threshold_n: on,
        off_threshold_n: off,
        noise: NoiseParams::NONE,
        force_output: true,
    };
    let mut c = ContactSensors::new(p, 1, 9, 0.0);
    let mut samples = 0;
    for (k, f) in forces.iter().enumerate() {
        for j in 0..10 {
            let t = (k * 10 + j) as f64 * 0.001;
            if c.update(t, &[*f]) {
                samples += 1;
                assert_eq!(c.force_n[0], *f);
                assert_eq!(c.in_contact[0], want[k]);
            }
        }
    }
    assert_eq!(samples, forces.len(), "one sample per 10 ms");
}

/// With noise near a threshold, hysteresis chatters far less than a single threshold.
#[test]
fn hysteresis_suppresses_chatter_under_noise() {
    let mut rng = sensor_rng(2, SensorStream::Contacts);
    let mut ch = NoiseChannel::new(NoiseParams::white(2.0), &mut rng);
    let (mut s1, mut s2) = (false, false);
    let (mut sw1, mut sw2) = (0, 0);
    for _ in 0..10_000 {
        let f = ch.sample(20.0, 0.002, &mut rng);
        let n1 = f > 20.0;
        let n2 = hysteresis(s2, f, 20.0, 10.0);
        sw1 += usize::from(n1 != s1);
        sw2 += usize::from(n2 != s2);
        s1 = n1;
        s2 = n2;
    }
    assert!(sw1 > 1000, "a single threshold at the mean chatters: {sw1}");
    assert_eq!(sw2, 1, "hysteresis 5σ wide switches once: {sw2}");
}

#[test]
fn mocap_latency_is_exact_in_samples() {
    let p = MocapParams {
        rate_hz: 100.0,
        latency_s: 0.03,
        position_noise_std_m: 0.0,
        orientation_noise_std_rad: 0.0,
    };
    assert_eq!(p.latency_samples(), 3);
    let mut m = Mocap::new(p, 4, 0.0);
    let dt = 0.001;
    let mut delivered = Vec::new();
    for k in 0..200 {
        let t = k as f64 * dt;
        let pos = DVec3::new(t, 2.0 * t, 0.5);
        let rot = DQuat::from_rotation_z(t);
        if let Some(s) = m.update(t, pos, rot) {
            delivered.push((t, s));
        }
    }
    // captures at 0, 10, 20 … ms; the first delivery is the 4th capture (30 ms)
    assert_eq!(delivered.len(), 20 - 3);
    for (t, s) in &delivered {
        assert!(
            (t - s.captured_t_s - 0.03).abs() < 1e-12,
            "delay {}",
            t - s.captured_t_s
        );
        assert_eq!(
            s.position_m,
            DVec3::new(s.captured_t_s, 2.0 * s.captured_t_s, 0.5)
        );
        assert!(
            s.orientation
                .angle_between(DQuat::from_rotation_z(s.captured_t_s))
                < 1e-7
        );
    }
}

#[test]
fn mocap_noise_has_its_standard_deviation() {
    let sigma = 1e-3;
    let p = MocapParams {
        rate_hz: 1000.0,
        latency_s: 0.0,
        position_noise_std_m: sigma,
        orientation_noise_std_rad: 0.0,
    };
    let mut m = Mocap::new(p, 8, 0.0);
    let n = 50_000;
    let xs: Vec<f64> = (0..n)
        .map(|k| {
            m.update(k as f64 * 1e-3, DVec3::ZERO, DQuat::IDENTITY)
                .unwrap()
                .position_m
                .x
        })
        .collect();
    let (mean, var) = mean_var(&xs);
    within_5se("mocap mean", mean, 0.0, sigma / (n as f64).sqrt());
    within_5se(
        "mocap var",
        var,
        sigma * sigma,
        sigma * sigma * (2.0 / (n as f64 - 1.0)).sqrt(),
    );
}

#[test]
fn rate_gate_samples_every_fourth_step_at_a_quarter_rate() {
    let mut g = RateGate::new(500.0, 0.0);
    let due: Vec<usize> = (0..20)
        .filter(|k| g.tick(*k as f64 * 0.0005).is_some())
        .collect();
    assert_eq!(due, vec![0, 4, 8, 12, 16]);
}

/// quad16 in free fall (no ground, limp joints, released at rest): every
/// body falls with g, so the accelerometer reads zero specific force.
#[test]
fn imu_in_free_fall_reads_zero_specific_force() {
    let desc = robots::builtin("quad16").unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let mut data = Data::new(&model);
    let mut ws = StepWorkspace::new(&model);
    ws.passive = Default::default();
    let mut st = State {
        q: robots::nominal_q("quad16").unwrap(),
        v: vec![0.0; model.nv],
    };
    // a tilted start, so the torso frame is not the world's
    let rq = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.5);
    st.q[3..7].copy_from_slice(&[rq.x, rq.y, rq.z, rq.w]);
    let tau = vec![0.0; model.nv];
    let mut imu = Imu::new(ImuParams::ideal(2000.0), 1, 0.0);
    let dt = 0.0005;
    let mut n = 0;
    for k in 0..400 {
        forward_kinematics(&model, &mut data, &st.q, &st.v);
        let rot = data.pose[0].rot;
        let v_world = data.vel[0].lin;
        let w_body = DVec3::new(st.v[3], st.v[4], st.v[5]);
        let s = imu.update(k as f64 * dt, rot, v_world, w_body, STANDARD_GRAVITY);
        if k > 0 {
            let s = s.expect("2 kHz on a 2 kHz clock: every step");
            assert!(
                s.accel_mps2.length() < 1e-9,
                "free fall: {:?}",
                s.accel_mps2
            );
            assert!(s.gyro_radps.length() < 1e-9);
            n += 1;
        }
        step(
            &model,
            &mut data,
            &mut ws,
            &mut st,
            &tau,
            dt,
            Integrator::SemiImplicitEuler,
            &mut (),
        );
    }
    assert_eq!(n, 399);
    assert!(st.v[2].abs() > 1.0, "it did fall");
}

/// At rest the accelerometer reads g upward (in the torso frame: Rᵀ (0, 0, g));
/// rotating at a constant ω about a fixed point it reads ω on the gyro.
#[test]
fn imu_at_rest_reads_g_up_and_gyro_reads_omega() {
    let g = STANDARD_GRAVITY;
    let mut imu = Imu::new(ImuParams::ideal(500.0), 1, 0.0);
    let omega = DVec3::new(0.3, -0.7, 1.1);
    let q0 = DQuat::from_rotation_x(0.4);
    for k in 0..50 {
        let t = k as f64 * 0.002;
        let q = q0 * DQuat::from_scaled_axis(omega * t);
        let r = DMat3::from_quat(q);
        let s = imu.update(t, r, DVec3::ZERO, omega, g).unwrap();
        let want = r.transpose() * -g;
        assert!(
            (s.accel_mps2 - want).length() < 1e-12,
            "{:?} vs {want:?}",
            s.accel_mps2
        );
        assert_eq!(s.gyro_radps, omega);
        // level: the specific force is straight up, +g
        if k == 0 {
            let up = q * s.accel_mps2.normalize();
            assert!((up - DVec3::Z).length() < 1e-12);
        }
    }
}

#[test]
fn encoders_quantise_and_difference_velocity_through_the_filter() {
    let res = std::f64::consts::TAU / 16384.0;
    let p = EncoderParams {
        rate_hz: 1000.0,
        resolution_rad: res,
        noise_std_rad: 0.0,
        offset_std_rad: 0.0,
        velocity: JointVelocityMode::Differencing {
            filter_time_constant_s: 0.0,
        },
    };
    let mut e = Encoders::new(p, 1, 3, 0.0);
    e.update(0.0, &[0.123_456], &[0.0]);
    let steps = e.position_rad[0] / res;
    assert!((steps - steps.round()).abs() < 1e-9);
    assert!((e.position_rad[0] - 0.123_456).abs() <= 0.5 * res);

    // a ramp θ = ω t through a τ = 5 ms filter, no quantisation:
    // v_k = ω (1 − (1 − α)^(k−1)), α = 1 − e^(−Δt/τ), v_0 = 0
    let (w, dt, tau) = (2.0, 0.001, 0.005);
    let p = EncoderParams {
        resolution_rad: 0.0,
        velocity: JointVelocityMode::Differencing {
            filter_time_constant_s: tau,
        },
        ..p
    };
    let mut e = Encoders::new(p, 1, 3, 0.0);
    let alpha = 1.0 - (-dt / tau).exp();
    for k in 0..100 {
        let t = k as f64 * dt;
        assert!(e.update(t, &[w * t], &[w]));
        let want = if k == 0 {
            0.0
        } else {
            w * (1.0 - (1.0 - alpha).powi(k - 1 + 1))
        };
        assert!(
            (e.velocity_radps[0] - want).abs() < 1e-9,
            "k {k}: {} vs {want}",
            e.velocity_radps[0]
        );
    }
}

#[test]
fn sensor_streams_follow_the_seed_only() {
    let cfg = SensorConfig::from_spec(&quadsim_engine::robots::quad16::SENSORS, 500.0);
    let q = [0.1; 16];
    let qd = [0.2; 16];
    let f = [100.0; 4];
    let run = |seed: u64, with_mocap: bool| {
        let mut cfg = cfg;
        if with_mocap {
            cfg.mocap = Some(SensorConfig::default_mocap());
        }
        let mut s = SensorSuite::new(&cfg, seed, 16, 4, 0.0);
        let mut out = Vec::new();
        for k in 0..20 {
            let truth = SensorTruth {
                t_s: k as f64 * 0.002,
                position_m: DVec3::new(0.0, 0.0, 0.5),
                orientation: DQuat::IDENTITY,
                velocity_world_mps: DVec3::ZERO,
                omega_body_radps: DVec3::ZERO,
                gravity_mps2: STANDARD_GRAVITY,
                q_joints_rad: &q,
                qd_joints_radps: &qd,
                foot_normal_force_n: &f,
            };
            s.update(&truth);
            out.push(s.imu.as_ref().unwrap().last.unwrap().accel_mps2);
            out.push(DVec3::new(
                s.encoders.as_ref().unwrap().position_rad[3],
                s.contacts.as_ref().unwrap().force_n[2],
                0.0,
            ));
        }
        out
    };
    assert_eq!(run(42, false), run(42, false), "same seed, same readings");
    assert_eq!(
        run(42, false),
        run(42, true),
        "mocap on draws from its own stream"
    );
    assert_ne!(
        run(42, false),
        run(43, false),
        "another seed, other readings"
    );
}

/// `due` predicts `update` without advancing: over a 2 kHz clock, sensors at
/// 500 Hz, 333 Hz (not a divisor of the clock) and 2 kHz, with mocap, each
/// sensor is due exactly when its update samples, and `any_due` is false
/// exactly on the steps where `update` reports nothing (which the `Sense`
/// stage skips).
#[test]
fn due_predicts_a_sample_without_taking_it() {
    for rate_hz in [500.0, 333.0, 2000.0] {
        let mut cfg = SensorConfig::from_spec(&quadsim_engine::robots::quad16::SENSORS, rate_hz);
        cfg.mocap = Some(SensorConfig::default_mocap());
        let mut s = SensorSuite::new(&cfg, 7, 16, 4, 0.0);
        let (q, qd, f) = ([0.1; 16], [0.2; 16], [100.0; 4]);
        let mut quiet = 0;
        for k in 0..400 {
            let t_s = k as f64 * 0.0005;
            let due = [
                s.imu.as_ref().unwrap().due(t_s),
                s.encoders.as_ref().unwrap().due(t_s),
                s.contacts.as_ref().unwrap().due(t_s),
                s.mocap.as_ref().unwrap().due(t_s),
            ];
            let any = s.any_due(t_s);
            let before = format!("{s:?}");
            let u = s.update(&SensorTruth {
                t_s,
                position_m: DVec3::new(0.0, 0.0, 0.5),
                orientation: DQuat::IDENTITY,
                velocity_world_mps: DVec3::X,
                omega_body_radps: DVec3::ZERO,
                gravity_mps2: STANDARD_GRAVITY,
                q_joints_rad: &q,
                qd_joints_radps: &qd,
                foot_normal_force_n: &f,
            });
            assert_eq!(
                due[..3],
                [u.imu, u.encoders, u.contacts],
                "{rate_hz} Hz, step {k}"
            );
            assert_eq!(any, due.iter().any(|&d| d), "{rate_hz} Hz, step {k}");
            if !any {
                quiet += 1;
                assert_eq!(
                    before,
                    format!("{s:?}"),
                    "an update with nothing due changed the suite"
                );
            }
        }
        if rate_hz < 2000.0 {
            assert!(quiet > 200, "{rate_hz} Hz: {quiet} quiet steps of 400");
        }
    }
}
