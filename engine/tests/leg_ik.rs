//! Closed-form leg kinematics (`quadsim_engine::legs`) against the engine's own
//! forward kinematics and point Jacobian, over the reachable workspace of every
//! leg of both built-ins, at default and overridden parameters; the nominal
//! stances; unreachable targets and their projection. Study B's printed
//! inverse formulas against the study's own forward formulas:
//! `validation/tests/study_b_kinematics.rs`.

use glam::{DMat3, DQuat, DVec3};
use quadsim_engine::Data;
use quadsim_engine::description::RobotDescription;
use quadsim_engine::jacobian::point_jacobian;
use quadsim_engine::kinematics::{forward_kinematics_pos, frame_pose};
use quadsim_engine::legs::{
    AnkleMode, FootPoint, IkError, IkOptions, KneeBranch, LegError, LegKinematics, Quad12Leg,
    Quad16Leg, wrap_angle,
};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::robots::{builtin_with, nominal_q, nominal_stance};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

const TOL_M: f64 = 1e-9;
const TOL_RAD: f64 = 1e-9;
const SAMPLES: usize = 1500;

const QUAD16_OVERRIDES: &[(&str, f64)] = &[
    ("thigh.length_m", 0.35),
    ("shank.length_m", 0.2),
    ("foot.radius_m", 0.04),
    ("mount.x_m", 0.3),
    ("mount.z_m", 0.02),
];
const QUAD12_OVERRIDES: &[(&str, f64)] = &[
    ("hip.length_m", 0.07),
    ("thigh.length_m", 0.12),
    ("shank.length_m", 0.06),
    ("foot.radius_m", 0.015),
    ("leg.front_yaw_rad", 0.5),
    ("leg.hind_yaw_rad", 2.0),
    ("mount.z_m", -0.01),
];

fn robot(name: &str, overrides: &[(&str, f64)]) -> (RobotDescription, Model) {
    let desc = builtin_with(name, overrides).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    (desc, model)
}

fn legs16(desc: &RobotDescription, model: &Model, point: FootPoint) -> Vec<Quad16Leg> {
    LegKinematics::for_robot(desc, model, point)
        .unwrap()
        .into_iter()
        .map(|l| match l {
            LegKinematics::Quad16(l) => l,
            other => panic!("expected a quad16 leg, got {other:?}"),
        })
        .collect()
}

fn legs12(desc: &RobotDescription, model: &Model, point: FootPoint) -> Vec<Quad12Leg> {
    LegKinematics::for_robot(desc, model, point)
        .unwrap()
        .into_iter()
        .map(|l| match l {
            LegKinematics::Quad12(l) => l,
            other => panic!("expected a quad12 leg, got {other:?}"),
        })
        .collect()
}

fn angle_diff(a: f64, b: f64) -> f64 {
    wrap_angle(a - b).abs()
}

/// A random floating-base configuration with `leg_angles` at `q_idx`, the
/// rest of the joints random.
fn random_q(model: &Model, rng: &mut ChaCha8Rng, q_idx: &[usize], leg_angles: &[f64]) -> Vec<f64> {
    let mut q = model.neutral_q();
    for k in 0..3 {
        q[k] = rng.random_range(-1.0..1.0);
    }
    let rot = DQuat::from_scaled_axis(DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    ));
    q[3..7].copy_from_slice(&rot.to_array());
    for v in q.iter_mut().skip(7) {
        *v = rng.random_range(-PI..PI);
    }
    for (&i, &a) in q_idx.iter().zip(leg_angles) {
        q[i] = a;
    }
    q
}

/// The engine's foot point in the base frame: forward kinematics at `q`
/// (random base pose), the foot frame's pose, the point, back to the base.
fn engine_foot_in_base(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    frame: usize,
    point: DVec3,
) -> DVec3 {
    forward_kinematics_pos(model, data, q);
    let world = frame_pose(model, data, frame).transform_point(point);
    data.pose[0].inverse().transform_point(world)
}

/// Foot in the rolled hip frame of a quad16 leg: z < 0 is the IK's roll branch.
fn quad16_hip_z(leg: &Quad16Leg, a: [f64; 4]) -> f64 {
    let p = leg.mount().inverse().transform_point(leg.fk(a));
    (DMat3::from_rotation_x(-a[0]) * p).z
}

/// Foot in the yawed hip frame of a quad12 leg: x > 0 is the IK's yaw branch.
fn quad12_hip_x(leg: &Quad12Leg, a: [f64; 3]) -> f64 {
    let p = leg.mount().inverse().transform_point(leg.fk(a));
    (DMat3::from_rotation_z(-a[0]) * p).x
}

fn sample_quad16(rng: &mut ChaCha8Rng, branch: KneeBranch, foot_pitch: bool) -> [f64; 4] {
    let sign = if branch == KneeBranch::Positive {
        1.0
    } else {
        -1.0
    };
    let roll = rng.random_range(-0.8..0.8);
    let pitch = rng.random_range(-1.3..1.3);
    let knee = sign * rng.random_range(0.05..PI - 0.05);
    let ankle = if foot_pitch {
        wrap_angle(rng.random_range(-0.6..0.6) - pitch - knee)
    } else {
        rng.random_range(-1.5..1.5)
    };
    [roll, pitch, knee, ankle]
}

/// Round trip over the workspace of every quad16 leg: angles in the branch →
/// FK (checked against the engine) → IK → FK, and the angles come back.
fn quad16_round_trip(overrides: &[(&str, f64)], point: FootPoint, seed: u64) {
    let (desc, model) = robot("quad16", overrides);
    let mut data = Data::new(&model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for leg in legs16(&desc, &model, point) {
        for branch in [KneeBranch::Negative, KneeBranch::Positive] {
            for foot_pitch in [true, false] {
                let mut tested = 0;
                for _ in 0..SAMPLES {
                    let a = sample_quad16(&mut rng, branch, foot_pitch);
                    let ankle = if foot_pitch {
                        AnkleMode::FootPitch(a[1] + a[2] + a[3])
                    } else {
                        AnkleMode::Angle(a[3])
                    };
                    let bend = leg.knee_bend_rad(a, ankle);
                    let in_branch = quad16_hip_z(&leg, a) < -1e-3
                        && (bend < 0.0) == (branch == KneeBranch::Negative)
                        && bend.abs() > 0.05
                        && bend.abs() < PI - 0.05;
                    if !in_branch {
                        continue;
                    }
                    tested += 1;
                    let p = leg.fk(a);
                    let q = random_q(&model, &mut rng, leg.q_indices(), &a);
                    let engine = engine_foot_in_base(
                        &model,
                        &mut data,
                        &q,
                        leg.foot_frame(),
                        leg.point_in_foot_m(),
                    );
                    assert!((p - engine).length() < TOL_M, "fk {p} vs engine {engine}");
                    let opts = IkOptions {
                        knee: branch,
                        ankle,
                        ..IkOptions::default()
                    };
                    let b = leg.ik(p, &opts).unwrap();
                    assert!((leg.fk(b) - p).length() < TOL_M, "{a:?} -> {b:?}");
                    for k in 0..4 {
                        assert!(angle_diff(a[k], b[k]) < TOL_RAD, "{a:?} -> {b:?}");
                    }
                    let clamped = leg.ik_clamped(p, &opts).unwrap();
                    assert!(!clamped.clamped);
                    assert!((clamped.foot_m - p).length() < TOL_M);
                }
                assert!(tested > SAMPLES / 4, "only {tested} samples in the branch");
            }
        }
    }
}

fn sample_quad12(rng: &mut ChaCha8Rng, branch: KneeBranch) -> [f64; 3] {
    let sign = if branch == KneeBranch::Negative {
        -1.0
    } else {
        1.0
    };
    [
        rng.random_range(-PI..PI),
        rng.random_range(-1.5..1.5),
        sign * rng.random_range(0.05..PI - 0.05),
    ]
}

fn quad12_round_trip(overrides: &[(&str, f64)], point: FootPoint, seed: u64) {
    let (desc, model) = robot("quad12", overrides);
    let mut data = Data::new(&model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for leg in legs12(&desc, &model, point) {
        for branch in [KneeBranch::Negative, KneeBranch::Positive] {
            let mut tested = 0;
            for _ in 0..SAMPLES {
                let a = sample_quad12(&mut rng, branch);
                let bend = leg.knee_bend_rad(a);
                if quad12_hip_x(&leg, a) < 1e-3 || (bend < 0.0) != (branch == KneeBranch::Negative)
                {
                    continue;
                }
                tested += 1;
                let p = leg.fk(a);
                let q = random_q(&model, &mut rng, leg.q_indices(), &a);
                let engine = engine_foot_in_base(
                    &model,
                    &mut data,
                    &q,
                    leg.foot_frame(),
                    leg.point_in_foot_m(),
                );
                assert!((p - engine).length() < TOL_M, "fk {p} vs engine {engine}");
                let opts = IkOptions {
                    knee: branch,
                    ..IkOptions::default()
                };
                let b = leg.ik(p, &opts).unwrap();
                assert!((leg.fk(b) - p).length() < TOL_M, "{a:?} -> {b:?}");
                for k in 0..3 {
                    assert!(angle_diff(a[k], b[k]) < TOL_RAD, "{a:?} -> {b:?}");
                }
            }
            assert!(tested > SAMPLES / 4, "only {tested} samples in the branch");
        }
    }
}

#[test]
fn quad16_round_trip_every_leg_both_branches_both_ankle_modes() {
    quad16_round_trip(&[], FootPoint::Contact, 1);
    quad16_round_trip(&[], FootPoint::SphereCentre, 2);
}

#[test]
fn quad16_round_trip_with_overridden_lengths_and_mounts() {
    quad16_round_trip(QUAD16_OVERRIDES, FootPoint::Contact, 3);
    // the override reaches the leg: straight, the ankle is thigh + shank from the hip
    let (desc, model) = robot("quad16", QUAD16_OVERRIDES);
    for leg in legs16(&desc, &model, FootPoint::Contact) {
        let (lo, hi) = leg.reach_m(AnkleMode::default());
        assert!((hi - 0.55).abs() < 1e-12 && (lo - 0.15).abs() < 1e-12);
        // straight down, foot level: the contact point 0.55 + 2·0.04 below the mount
        let p = leg.fk([0.0; 4]) - leg.mount().trans;
        assert!((p - DVec3::new(0.0, 0.0, -0.63)).length() < 1e-12);
        assert!((leg.mount().trans.x.abs() - 0.3).abs() < 1e-12);
    }
}

#[test]
fn quad12_round_trip_every_leg_both_branches() {
    quad12_round_trip(&[], FootPoint::Contact, 4);
    quad12_round_trip(&[], FootPoint::SphereCentre, 5);
}

#[test]
fn quad12_round_trip_with_overridden_lengths_and_yaws() {
    quad12_round_trip(QUAD12_OVERRIDES, FootPoint::Contact, 6);
    let (desc, model) = robot("quad12", QUAD12_OVERRIDES);
    for leg in legs12(&desc, &model, FootPoint::Contact) {
        assert!((leg.lateral_offset_m() - 0.07).abs() < 1e-12);
        let (lo, hi) = leg.reach_m();
        assert!((hi - (0.12 + 0.06 + 0.015)).abs() < 1e-12);
        assert!((lo - (0.12 - 0.075)).abs() < 1e-12);
    }
}

#[test]
fn nominal_stance_is_the_default_branch() {
    for name in ["quad16", "quad12"] {
        let (desc, model) = robot(name, &[]);
        let mut data = Data::new(&model);
        let q = nominal_q(name).unwrap();
        let stance = nominal_stance(name).unwrap();
        for leg in LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap() {
            let frame = leg.foot_frame();
            let point = FootPoint::Contact.in_foot(&desc, &model.frames[frame].name);
            let foot = engine_foot_in_base(&model, &mut data, &q, frame, point);
            let mut a = vec![0.0; leg.dof()];
            leg.ik_into(foot, &IkOptions::default(), &mut a).unwrap();
            for (k, &i) in leg.q_indices().iter().enumerate() {
                assert!(
                    (a[k] - stance[i - 7]).abs() < 1e-12,
                    "{name} {}: {a:?} vs stance",
                    model.frames[frame].name
                );
            }
        }
    }
}

/// `rᵀ ∂p/∂a_k = 0` along the angles `free` and no small step of them gets
/// closer: the clamped point is a local nearest point to the target among the
/// points those angles reach.
fn assert_local_nearest(fk: impl Fn(&[f64]) -> DVec3, a: &[f64], target: DVec3, free: &[usize]) {
    let p = fk(a);
    let dist = (target - p).length();
    let h = 1e-6;
    for &k in free {
        let mut ap = a.to_vec();
        ap[k] += h;
        let mut am = a.to_vec();
        am[k] -= h;
        let col = (fk(&ap) - fk(&am)) / (2.0 * h);
        let grad = (target - p).dot(col);
        assert!(
            grad.abs() < 1e-6 * dist * col.length().max(1e-3),
            "gradient {grad} along {k}"
        );
    }
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for _ in 0..200 {
        let mut step = a.to_vec();
        for &k in free {
            step[k] += rng.random_range(-1e-3..1e-3);
        }
        assert!((target - fk(&step)).length() >= dist - 1e-12);
    }
}

/// The origin of link `name` (m, base frame) with the leg at `angles`.
fn link_origin(model: &Model, q_idx: &[usize], angles: &[f64], name: &str) -> DVec3 {
    let mut data = Data::new(model);
    let mut q = model.neutral_q();
    for (&i, &a) in q_idx.iter().zip(angles) {
        q[i] = a;
    }
    let frame = model.frame_index(name).unwrap();
    engine_foot_in_base(model, &mut data, &q, frame, DVec3::ZERO)
}

/// `b − a` and `c − a` point the same way.
fn assert_same_direction(a: DVec3, b: DVec3, c: DVec3) {
    let (u, v) = (b - a, c - a);
    assert!(
        u.cross(v).length() < 1e-9 * u.length() * v.length(),
        "{u} vs {v}"
    );
    assert!(u.dot(v) > 0.0, "{u} vs {v}");
}

#[test]
fn unreachable_targets_error_and_clamp_toward_them() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let opts = IkOptions::default();
    let bad = [
        DVec3::new(f64::NAN, 0.0, 0.0),
        DVec3::new(0.0, f64::INFINITY, 0.0),
    ];

    let (desc, model) = robot("quad16", &[]);
    for leg in legs16(&desc, &model, FootPoint::Contact) {
        let hip = leg.mount().trans;
        let (lo, hi) = leg.reach_m(AnkleMode::default());
        for t in bad {
            assert!(matches!(leg.ik(t, &opts), Err(IkError::NonFinite { .. })));
            assert!(matches!(
                leg.ik_clamped(t, &opts),
                Err(IkError::NonFinite { .. })
            ));
        }
        // the free angles with the ankle tied to the foot pitch
        let fk = |a: &[f64]| leg.fk([a[0], a[1], a[2], -a[1] - a[2]]);
        for _ in 0..50 {
            // far below and around the hip, beyond the straight leg
            let dir = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..-0.2),
            )
            .normalize();
            let target = hip + dir * rng.random_range(1.2..3.0) * hi;
            match leg.ik(target, &opts) {
                Err(IkError::OutOfReach {
                    distance_m,
                    min_reach_m,
                    max_reach_m,
                }) => {
                    assert!(distance_m > max_reach_m);
                    assert!((max_reach_m - hi).abs() < 1e-15 && (min_reach_m - lo).abs() < 1e-15);
                }
                other => panic!("{target}: {other:?}"),
            }
            let c = leg.ik_clamped(target, &opts).unwrap();
            assert!(c.clamped && c.foot_m.is_finite());
            // straight knee, foot level, the point reached, and nearest
            assert!(c.angles_rad[2].abs() < 1e-9, "{:?}", c.angles_rad);
            assert!((c.angles_rad[1] + c.angles_rad[2] + c.angles_rad[3]).abs() < 1e-12);
            assert!((leg.fk(c.angles_rad) - c.foot_m).length() < 1e-15);
            // the ankle moved along the line from the hip pitch joint (engine
            // frames) toward where the target puts it; with no lateral offset
            // that is the nearest reachable point
            let name = &model.frames[leg.foot_frame()].name;
            let leg_name = &name[..2];
            let q_idx = leg.q_indices();
            let pitch_joint =
                link_origin(&model, q_idx, &c.angles_rad, &format!("{leg_name}_thigh"));
            let ankle = link_origin(&model, q_idx, &c.angles_rad, name);
            assert_same_direction(pitch_joint, ankle, target - (c.foot_m - ankle));
            assert!(((ankle - pitch_joint).length() - hi).abs() < 1e-12);
            assert_local_nearest(fk, &c.angles_rad[..3], target, &[0, 1, 2]);
        }
        // the ankle closer to the hip pitch joint than the folded leg reaches
        let target = hip + DVec3::new(0.01, 0.0, -0.07);
        assert!(matches!(
            leg.ik(target, &opts),
            Err(IkError::OutOfReach { distance_m, .. }) if distance_m < lo
        ));
        let c = leg.ik_clamped(target, &opts).unwrap();
        assert!(c.clamped && (c.angles_rad[2].abs() - PI).abs() < 1e-9);
        assert_local_nearest(fk, &c.angles_rad[..3], target, &[0, 1, 2]);
    }

    let (desc, model) = robot("quad12", &[]);
    for leg in legs12(&desc, &model, FootPoint::Contact) {
        let hip = leg.mount().trans;
        let (_, hi) = leg.reach_m();
        for t in bad {
            assert!(matches!(leg.ik(t, &opts), Err(IkError::NonFinite { .. })));
        }
        let fk = |a: &[f64]| leg.fk([a[0], a[1], a[2]]);
        for _ in 0..50 {
            // off the yaw axis (|dir.z| < 0.9), beyond the hip offset and the reach
            let dir = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize();
            if dir.z.abs() > 0.9 {
                continue;
            }
            let target = hip + dir * rng.random_range(1.5..4.0) * (hi + 0.05);
            assert!(matches!(
                leg.ik(target, &opts),
                Err(IkError::OutOfReach { .. })
            ));
            let c = leg.ik_clamped(target, &opts).unwrap();
            assert!(c.clamped && c.angles_rad[2].abs() < 1e-9);
            // the straight leg points from the hip pitch joint at the target,
            // in the leg plane through it: the nearest point of that plane
            let name = &model.frames[leg.foot_frame()].name;
            let pitch_joint = link_origin(
                &model,
                leg.q_indices(),
                &c.angles_rad,
                &format!("{}_thigh", &name[..2]),
            );
            assert_same_direction(pitch_joint, c.foot_m, target);
            assert!(((c.foot_m - pitch_joint).length() - hi).abs() < 1e-12);
            assert_local_nearest(fk, &c.angles_rad, target, &[1, 2]);
        }
        // on the yaw axis: inside the hip offset l1
        let target = hip - DVec3::new(0.0, 0.0, 0.1);
        match leg.ik(target, &opts) {
            Err(IkError::InsideOffset {
                distance_m,
                offset_m,
            }) => assert!(distance_m < 1e-15 && (offset_m - 0.05).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        let c = leg.ik_clamped(target, &opts).unwrap();
        assert!(c.clamped && c.foot_m.is_finite());
        // projected onto the offset cylinder: foot right below the pitch joint
        let off_axis = (c.foot_m - hip).truncate().length();
        assert!((off_axis - 0.05).abs() < 1e-12, "{off_axis}");
        assert!((c.foot_m.z - target.z).abs() < 1e-12);
    }
}

#[test]
fn joint_velocities_reproduce_the_foot_velocity_through_the_engine_jacobian() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let exact = IkOptions {
        velocity_damping_m: 0.0,
        ..IkOptions::default()
    };
    for name in ["quad16", "quad12"] {
        let (desc, model) = robot(name, &[]);
        let mut data = Data::new(&model);
        let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
        let mut tested = 0;
        for _ in 0..400 {
            for leg in &legs {
                let n = leg.dof();
                let mut a: Vec<f64> = (0..n).map(|_| rng.random_range(-1.2..1.2)).collect();
                a[2] = rng.random_range(0.3..2.5) * if n == 4 { -1.0 } else { 1.0 };
                let v_foot = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                let mut qd = vec![0.0; n];
                if leg
                    .joint_velocities_into(&a, v_foot, &exact, &mut qd)
                    .is_err()
                {
                    continue;
                }
                if qd.iter().any(|x| x.abs() > 1e3) {
                    continue; // near a singular pose, where round-off dominates
                }
                tested += 1;
                let q = random_q(&model, &mut rng, leg.q_indices(), &a);
                forward_kinematics_pos(&model, &mut data, &q);
                let frame = leg.foot_frame();
                let point = FootPoint::Contact.in_foot(&desc, &model.frames[frame].name);
                let world = frame_pose(&model, &data, frame).transform_point(point);
                let body = model.frames[frame].body;
                let jac = point_jacobian(&model, &mut data, body, world).to_vec();
                let mut v_world = DVec3::ZERO;
                for (k, &iv) in leg.v_indices().iter().enumerate() {
                    let col = DVec3::new(jac[iv], jac[model.nv + iv], jac[2 * model.nv + iv]);
                    v_world += col * qd[k];
                }
                let v_body = data.pose[0].rot.transpose() * v_world;
                assert!(
                    (v_body - v_foot).length() < 1e-9 * (1.0 + v_foot.length()),
                    "{name}: {v_body} vs {v_foot}"
                );
                if n == 4 {
                    // the foot pitch held
                    assert!((qd[1] + qd[2] + qd[3]).abs() < 1e-9);
                }
                // the default damping solves the damped normal equations
                // (AᵀA + λ²I) x = Aᵀ v, A the engine's columns of the free angles
                let opts = IkOptions::default();
                let mut qd_damped = vec![0.0; n];
                leg.joint_velocities_into(&a, v_foot, &opts, &mut qd_damped)
                    .unwrap();
                let col = |k: usize| {
                    let iv = leg.v_indices()[k];
                    data.pose[0].rot.transpose()
                        * DVec3::new(jac[iv], jac[model.nv + iv], jac[2 * model.nv + iv])
                };
                let cols = if n == 4 {
                    [col(0), col(1) - col(3), col(2) - col(3)]
                } else {
                    [col(0), col(1), col(2)]
                };
                let lambda2 = opts.velocity_damping_m.powi(2);
                for i in 0..3 {
                    let lhs: f64 = (0..3)
                        .map(|j| cols[i].dot(cols[j]) * qd_damped[j])
                        .sum::<f64>()
                        + lambda2 * qd_damped[i];
                    let rhs = cols[i].dot(v_foot);
                    assert!(
                        (lhs - rhs).abs() < 1e-9 * (1.0 + rhs.abs()),
                        "{name}: {lhs} vs {rhs}"
                    );
                }
            }
        }
        assert!(tested > 1000, "{name}: only {tested} poses");
    }
}

#[test]
fn straight_leg_is_singular_and_damping_keeps_velocities_bounded() {
    let exact = IkOptions {
        velocity_damping_m: 0.0,
        ..IkOptions::default()
    };
    let opts = IkOptions::default();
    let bound = 1.0 / (2.0 * opts.velocity_damping_m);
    let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();

    // quad16: straight leg along −z, the foot level; no joint rate moves the foot along z
    let (desc, model) = robot("quad16", &[]);
    let leg = &legs16(&desc, &model, FootPoint::Contact)[0];
    let v = DVec3::new(0.3, 0.0, 1.0).normalize();
    assert_eq!(
        leg.joint_velocities([0.0; 4], v, &exact),
        Err(IkError::Singular)
    );
    // 10 µrad short of straight: the exact map explodes, the damped one stays
    // within |v|/(2λ) (hip roll, pitch, knee; the ankle follows)
    let near = [0.0, 0.0, -1e-5, 1e-5];
    let qd = leg.joint_velocities(near, v, &exact).unwrap();
    assert!(norm(&qd) > 1e4, "{qd:?}");
    for a in [[0.0; 4], near] {
        let qd = leg.joint_velocities(a, v, &opts).unwrap();
        assert!(qd.iter().all(|x| x.is_finite()));
        assert!(norm(&qd[..3]) <= bound, "{qd:?}");
    }

    // quad12: straight leg along the leg's x, moving the foot along it
    let (desc, model) = robot("quad12", &[]);
    let leg = &legs12(&desc, &model, FootPoint::Contact)[0];
    let v = (leg.mount().rot * DVec3::new(1.0, 0.0, 0.3)).normalize();
    assert_eq!(
        leg.joint_velocities([0.0; 3], v, &exact),
        Err(IkError::Singular)
    );
    let near = [0.0, 0.0, 1e-5];
    let qd = leg.joint_velocities(near, v, &exact).unwrap();
    assert!(norm(&qd) > 1e4, "{qd:?}");
    for a in [[0.0; 3], near] {
        let qd = leg.joint_velocities(a, v, &opts).unwrap();
        assert!(
            qd.iter().all(|x| x.is_finite()) && norm(&qd) <= bound,
            "{qd:?}"
        );
    }
}

#[test]
fn legs_of_other_shapes_are_typed_errors() {
    let (desc, model) = robot("quad12", &[]);
    let foot = model.frame_index("LF_foot").unwrap();
    assert!(matches!(
        Quad16Leg::from_model(&model, foot, DVec3::ZERO),
        Err(LegError::ChainLength {
            found: 3,
            expected: 4,
            ..
        })
    ));
    assert!(matches!(
        LegKinematics::from_model(&model, 999, DVec3::ZERO),
        Err(LegError::UnknownFrame { index: 999, .. })
    ));
    // a quad12 leg whose hip pitch turns about x is no longer the closed form's
    let mut d = desc.clone();
    let j = d
        .joints
        .iter_mut()
        .find(|j| j.name == "LF_hip_pitch")
        .unwrap();
    j.kind = quadsim_engine::description::JointKind::Revolute { axis: DVec3::X };
    let m = Model::from_description(&d, BaseKind::Floating).unwrap();
    match Quad12Leg::from_model(&m, foot, DVec3::ZERO) {
        Err(LegError::Structure { joint, field, .. }) => {
            assert_eq!((joint.as_str(), field), ("LF_hip_pitch", "axis"));
        }
        other => panic!("{other:?}"),
    }
}
