//! The numerical serial leg (`legs::SerialLeg`) on the built-ins' legs: its
//! forward kinematics and Jacobian against the engine's frame kinematics,
//! point Jacobian and finite differences; its damped-least-squares IK
//! against the closed forms over a grid of reachable targets (from the
//! geometric guess and from the nominal stance); flipped joint axes; the
//! error for a leg of the wrong structure; and the robot profile (the
//! walker's defaults for quad16 and quad12 unchanged, values reasonable).

use glam::{DMat3, DQuat, DVec3};
use quadsim_engine::Data;
use quadsim_engine::control::profile::{RobotProfile, StandGainRule};
use quadsim_engine::control::vmc::VmcParams;
use quadsim_engine::control::walker::WalkerParams;
use quadsim_engine::description::{JointKind, RobotDescription};
use quadsim_engine::gait::placement::PlacementParams;
use quadsim_engine::jacobian::point_jacobian;
use quadsim_engine::kinematics::{forward_kinematics_pos, frame_pose};
use quadsim_engine::legs::{
    AnkleMode, FootPoint, HipKind, IkError, IkOptions, LegError, LegKinematics, SerialLeg,
    wrap_angle,
};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::robots::{builtin_with, nominal_stance, stance_base_height_m};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn robot(name: &str, overrides: &[(&str, f64)]) -> (RobotDescription, Model) {
    let desc = builtin_with(name, overrides).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    (desc, model)
}

fn serial_legs(desc: &RobotDescription, model: &Model) -> Vec<SerialLeg> {
    model
        .feet
        .iter()
        .map(|&f| {
            let p = FootPoint::Contact.in_foot(desc, &model.frames[f].name);
            match LegKinematics::serial_from_model(model, f, p).unwrap() {
                LegKinematics::Serial(l) => *l,
                other => panic!("{other:?}"),
            }
        })
        .collect()
}

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
    ("leg.front_yaw_rad", 0.5),
    ("leg.hind_yaw_rad", 2.0),
];

fn random_q(model: &Model, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut q = model.neutral_q();
    for x in &mut q[..3] {
        *x = rng.random_range(-1.0..1.0);
    }
    let rot = DQuat::from_scaled_axis(DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    ));
    q[3..7].copy_from_slice(&rot.to_array());
    for x in &mut q[7..] {
        *x = rng.random_range(-PI..PI);
    }
    q
}

/// FK and the Jacobian of every serial leg against the engine: the foot
/// point of `frame_pose` and the joint columns of `point_jacobian` (world
/// axes, rotated into the base frame) at random configurations, and central
/// finite differences of the leg's own FK.
fn check_fk_and_jacobian(desc: &RobotDescription, model: &Model, seed: u64) {
    let mut data = Data::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let legs = serial_legs(desc, model);
    for _ in 0..200 {
        let q = random_q(model, &mut rng);
        forward_kinematics_pos(model, &mut data, &q);
        let base = data.pose[0];
        for leg in &legs {
            let a: Vec<f64> = leg.q_indices().iter().map(|&i| q[i]).collect();
            let world =
                frame_pose(model, &data, leg.foot_frame()).transform_point(leg.point_in_foot_m());
            let engine = base.inverse().transform_point(world);
            let fk = leg.fk(&a);
            assert!((fk - engine).length() < 1e-12, "fk {fk} vs engine {engine}");
            let body = model.frames[leg.foot_frame()].body;
            let jac = point_jacobian(model, &mut data, body, world).to_vec();
            let nv = model.nv;
            let j = leg.jacobian(&a);
            for (k, &vi) in leg.v_indices().iter().enumerate() {
                let col_world = DVec3::new(jac[vi], jac[nv + vi], jac[2 * nv + vi]);
                let col = base.rot.transpose() * col_world;
                assert!((col - j[k]).length() < 1e-12, "col {k}: {col} vs {}", j[k]);
                let h = 1e-6;
                let mut ap = a.clone();
                let mut am = a.clone();
                ap[k] += h;
                am[k] -= h;
                let fd = (leg.fk(&ap) - leg.fk(&am)) / (2.0 * h);
                assert!((fd - j[k]).length() < 1e-8, "fd col {k}: {fd} vs {}", j[k]);
            }
        }
    }
}

#[test]
fn serial_fk_and_jacobian_are_the_engines() {
    let (d, m) = robot("quad16", &[]);
    check_fk_and_jacobian(&d, &m, 1);
    let (d, m) = robot("quad16", QUAD16_OVERRIDES);
    check_fk_and_jacobian(&d, &m, 2);
    let (d, m) = robot("quad12", &[]);
    check_fk_and_jacobian(&d, &m, 3);
    let (d, m) = robot("quad12", QUAD12_OVERRIDES);
    check_fk_and_jacobian(&d, &m, 4);
    let (d, m) = flipped_quad16();
    check_fk_and_jacobian(&d, &m, 5);
}

/// Largest iteration count and residual seen, for the report.
#[derive(Default)]
struct Tally {
    solves: usize,
    max_iterations: usize,
    sum_iterations: usize,
    max_residual_m: f64,
    max_foot_diff_m: f64,
    max_angle_diff_rad: f64,
}

impl Tally {
    fn print(&self, what: &str) {
        println!(
            "{what}: {} solves, iterations mean {:.2} max {}, residual max {:.2e} m, \
             foot vs closed form max {:.2e} m, angles max {:.2e} rad",
            self.solves,
            self.sum_iterations as f64 / self.solves.max(1) as f64,
            self.max_iterations,
            self.max_residual_m,
            self.max_foot_diff_m,
            self.max_angle_diff_rad
        );
    }
}

/// Whether the leg is away from its singular poses at `angles` (the 3 × 3
/// Jacobian of its free angles has `|det| ≥ 1e-3 L³`, L the leg's length)
/// and its foot is on the closed form's side of the first joint's axis by
/// 2 cm (below the roll axis, outward of the yaw axis). Near them the
/// angles are ill-conditioned (1e-13 m of foot is 1e-2 rad of hip there)
/// and the closed form switches branch.
fn well_posed(serial: &SerialLeg, angles: &[f64], opts: &IkOptions) -> bool {
    let j = serial.jacobian(angles);
    let m = match (angles.len(), opts.ankle) {
        (4, AnkleMode::FootPitch(_)) => DMat3::from_cols(j[0], j[1] - j[3], j[2] - j[3]),
        _ => DMat3::from_cols(j[0], j[1], j[2]),
    };
    let l = serial.leg_length_m();
    let side = serial.hip_side_m(angles);
    m.determinant().abs() >= 1e-3 * l.powi(3) && side > 0.02
}

/// The damped-least-squares IK against a closed form on one leg: for each
/// angle sample in the branch (foot reachable by construction), both
/// solvers' angles and feet agree; from the guess and from `start`.
/// Returns whether the sample was well posed (and so compared).
fn compare(
    closed: &LegKinematics,
    serial: &SerialLeg,
    angles: &[f64],
    opts: &IkOptions,
    start: &[f64],
    from_guess: &mut Tally,
    from_start: &mut Tally,
) -> bool {
    if !well_posed(serial, angles, opts) {
        return false;
    }
    let n = angles.len();
    let target = closed.fk(angles);
    assert!((serial.fk(angles) - target).length() < 1e-12);
    let mut cf = vec![0.0; n];
    closed.ik_into(target, opts, &mut cf).unwrap();
    for (tally, seed) in [
        (from_guess, serial.guess(target, opts)[..n].to_vec()),
        (from_start, start.to_vec()),
    ] {
        let mut a = seed;
        let stats = serial.solve_from(target, opts, &mut a).unwrap();
        let foot = serial.fk(&a);
        let d_foot = (foot - target).length();
        assert!(
            d_foot < 1e-9,
            "target {target}: foot {foot} after {stats:?} from angles {angles:?}"
        );
        let d_angle = (0..n).fold(0.0_f64, |m, k| m.max(wrap_angle(a[k] - cf[k]).abs()));
        assert!(
            d_angle < 1e-9,
            "target {target}: serial {a:?} vs closed form {cf:?} ({stats:?})"
        );
        tally.solves += 1;
        tally.sum_iterations += stats.iterations;
        tally.max_iterations = tally.max_iterations.max(stats.iterations);
        tally.max_residual_m = tally.max_residual_m.max(stats.residual_m);
        tally.max_foot_diff_m = tally.max_foot_diff_m.max((foot - closed.fk(&cf)).length());
        tally.max_angle_diff_rad = tally.max_angle_diff_rad.max(d_angle);
    }
    true
}

#[test]
fn dls_agrees_with_the_quad16_closed_form() {
    for overrides in [&[][..], QUAD16_OVERRIDES] {
        let (desc, model) = robot("quad16", overrides);
        let closed = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
        let serial = serial_legs(&desc, &model);
        let (mut g, mut s) = (Tally::default(), Tally::default());
        let (mut tried, mut compared) = (0, 0);
        let stance = [0.0, 0.3, -0.6, 0.3];
        for (c, l) in closed.iter().zip(&serial) {
            assert!(matches!(c, LegKinematics::Quad16(_)));
            assert_eq!(
                l.nominal_bend(),
                -1.0,
                "quad16's knee behind the hip-foot line"
            );
            // a grid over roll, hip pitch and knee bend on the nominal branch
            for roll in [-0.5, -0.2, 0.0, 0.25, 0.5] {
                for pitch in [-0.9, -0.4, 0.0, 0.3, 0.8, 1.2] {
                    for knee in [-2.4, -1.6, -1.0, -0.6, -0.3] {
                        for psi in [0.0, 0.3] {
                            let a = [roll, pitch, knee, psi - pitch - knee];
                            let opts = IkOptions {
                                ankle: AnkleMode::FootPitch(psi),
                                ..IkOptions::default()
                            };
                            tried += 2;
                            compared +=
                                usize::from(compare(c, l, &a, &opts, &stance, &mut g, &mut s));
                            let opts = IkOptions {
                                ankle: AnkleMode::Angle(a[3]),
                                ..IkOptions::default()
                            };
                            compared +=
                                usize::from(compare(c, l, &a, &opts, &stance, &mut g, &mut s));
                        }
                    }
                }
            }
        }
        println!("quad16: {compared} of {tried} grid targets well posed");
        assert!(compared * 4 > tried * 3, "{compared} of {tried}");
        g.print("quad16 from the guess");
        s.print("quad16 from the nominal stance");
        assert!(g.max_iterations <= 3 && s.max_iterations <= 40);
    }
}

#[test]
fn dls_agrees_with_the_quad12_closed_form() {
    for overrides in [&[][..], QUAD12_OVERRIDES] {
        let (desc, model) = robot("quad12", overrides);
        let closed = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
        let serial = serial_legs(&desc, &model);
        let (mut g, mut s) = (Tally::default(), Tally::default());
        let (mut tried, mut compared) = (0, 0);
        let stance = [0.0, PI / 6.0, PI / 3.0];
        for (c, l) in closed.iter().zip(&serial) {
            assert!(matches!(c, LegKinematics::Quad12(_)));
            assert_eq!(l.hip_kind(), HipKind::Yaw);
            assert_eq!(
                l.nominal_bend(),
                1.0,
                "quad12's knee above the hip-foot line"
            );
            for yaw in [-0.6, -0.2, 0.0, 0.3, 0.6] {
                for pitch in [-0.6, -0.2, 0.0, 0.5, 1.0] {
                    for knee in [0.3, 0.8, 1.2, 1.8, 2.4] {
                        let a = [yaw, pitch, knee];
                        tried += 1;
                        compared += usize::from(compare(
                            c,
                            l,
                            &a,
                            &IkOptions::default(),
                            &stance,
                            &mut g,
                            &mut s,
                        ));
                    }
                }
            }
        }
        println!("quad12: {compared} of {tried} grid targets well posed");
        assert!(compared * 2 > tried, "{compared} of {tried}");
        g.print("quad12 from the guess");
        s.print("quad12 from the nominal stance");
        assert!(g.max_iterations <= 3 && s.max_iterations <= 40);
    }
}

/// quad16 with every leg axis flipped (roll about −x, pitch joints about
/// −y): no closed form fits it, so its legs are serial.
fn flipped_quad16() -> (RobotDescription, Model) {
    let mut desc = builtin_with("quad16", &[]).unwrap();
    for j in &mut desc.joints {
        if let JointKind::Revolute { axis } = &mut j.kind {
            *axis = -*axis;
            if let Some((lo, hi)) = j.limits {
                j.limits = Some((-hi, -lo));
            }
        }
    }
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    (desc, model)
}

#[test]
fn flipped_axes_give_the_same_foot_motions() {
    let (desc, model) = robot("quad16", &[]);
    let (fdesc, fmodel) = flipped_quad16();
    let plain = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
    let flipped = LegKinematics::for_robot(&fdesc, &fmodel, FootPoint::Contact).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (p, f) in plain.iter().zip(&flipped) {
        let LegKinematics::Serial(fs) = f else {
            panic!("a flipped leg is no closed form's: {f:?}");
        };
        assert_eq!(fs.axis_signs(), &[-1.0, -1.0, -1.0, -1.0]);
        assert_eq!(fs.nominal_bend(), 1.0, "the knee behind: positive about −y");
        for _ in 0..300 {
            let a = [
                rng.random_range(-0.5..0.5),
                rng.random_range(-1.0..1.0),
                rng.random_range(-2.4..-0.2),
                rng.random_range(-0.5..0.5),
            ];
            let neg = a.map(|x| -x);
            // the same foot at negated angles
            assert!((p.fk(&a) - f.fk(&neg)).length() < 1e-12);
            // and the same motion back from the IK, foot level
            let target = p.fk(&[a[0], a[1], a[2], -a[1] - a[2]]);
            let opts = IkOptions::default();
            let (mut x, mut y) = ([0.0; 4], [0.0; 4]);
            p.ik_clamped_into(target, &opts, &mut x).unwrap();
            f.ik_clamped_into(target, &opts, &mut y).unwrap();
            for k in 0..4 {
                assert!(wrap_angle(x[k] + y[k]).abs() < 1e-9, "{x:?} vs {y:?}");
            }
            // velocities map the same way
            let v = DVec3::new(0.3, -0.2, 0.5);
            let (mut qx, mut qy) = ([0.0; 4], [0.0; 4]);
            p.joint_velocities_into(&x, v, &opts, &mut qx).unwrap();
            f.joint_velocities_into(&y, v, &opts, &mut qy).unwrap();
            for k in 0..4 {
                assert!((qx[k] + qy[k]).abs() < 1e-9, "{qx:?} vs {qy:?}");
            }
        }
    }
}

#[test]
fn serial_ik_bounds_and_errors() {
    let (desc, model) = robot("quad16", &[]);
    let leg = &serial_legs(&desc, &model)[0];
    let opts = IkOptions::default();
    let nan = DVec3::new(f64::NAN, 0.0, 0.0);
    assert!(matches!(
        leg.ik_clamped(nan, &opts),
        Err(IkError::NonFinite { .. })
    ));
    let mut a = [0.0; 4];
    assert!(matches!(
        leg.solve_from(DVec3::new(0.0, f64::INFINITY, 0.0), &opts, &mut a),
        Err(IkError::NonFinite { .. })
    ));
    // a target 2 m below the hip: out of reach, the leg straightens toward
    // it within the iteration bound and says so
    let far = leg.mount().trans - DVec3::new(0.0, 0.0, 2.0);
    let c = leg.ik_clamped(far, &opts).unwrap();
    assert!(c.clamped);
    assert!(c.angles_rad.iter().all(|x| x.is_finite()));
    assert!(
        leg.knee_bend_rad(&c.angles_rad, opts.ankle) <= 0.0,
        "kept its branch"
    );
    assert!((far - c.foot_m).length() < 2.0 - 0.55 + 1e-3);
    assert!(matches!(
        leg.ik(far, &opts),
        Err(IkError::OutOfReach { .. })
    ));
    let mut start = [0.0, 0.3, -0.6, 0.3];
    let stats = leg.solve_from(far, &opts, &mut start).unwrap();
    assert!(stats.iterations <= quadsim_engine::legs::serial_leg::MAX_ITERATIONS);
}

#[test]
fn joint_limits_are_respected() {
    let (mut desc, _) = robot("quad16", &[]);
    for j in &mut desc.joints {
        if j.name.ends_with("knee") {
            j.limits = Some((-1.0, -0.2));
        }
    }
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let leg = &serial_legs(&desc, &model)[0];
    // a crouch that needs the knee at −2 rad
    let target = leg.fk(&[0.0, 1.0, -2.0, 1.0]);
    let c = leg.ik_clamped(target, &IkOptions::default()).unwrap();
    assert!(c.clamped);
    assert!(
        c.angles_rad[2] >= -1.0 && c.angles_rad[2] <= -0.2,
        "{:?}",
        c.angles_rad
    );
}

#[test]
fn a_leg_of_the_wrong_structure_names_its_foot_and_joint() {
    // quad16 with the LF knee turning about z
    let mut desc = builtin_with("quad16", &[]).unwrap();
    desc.joint_mut("LF_knee").unwrap().kind = JointKind::Revolute { axis: DVec3::Z };
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let err = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap_err();
    match &err {
        LegError::Serial { foot, joint, .. } => {
            assert_eq!((foot.as_str(), joint.as_str()), ("LF_foot", "LF_knee"));
        }
        other => panic!("{other:?}"),
    }
    let msg = err.to_string();
    assert!(msg.contains("LF_foot") && msg.contains("LF_knee"), "{msg}");
    // the walker refuses it with that message
    let params = WalkerParams::default_for(&desc, &model);
    let w = quadsim_engine::control::walker::Walker::new(&desc, &model, params).unwrap_err();
    assert!(w.to_string().contains("LF_knee"), "{w}");
    // a hip whose first joint turns about y
    let mut desc = builtin_with("quad12", &[]).unwrap();
    desc.joint_mut("RH_hip_yaw").unwrap().kind = JointKind::Revolute { axis: DVec3::Y };
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    match LegKinematics::for_robot(&desc, &model, FootPoint::Contact) {
        Err(LegError::Serial { foot, joint, why }) => {
            assert_eq!((foot.as_str(), joint.as_str()), ("RH_foot", "RH_hip_yaw"));
            assert!(why.contains("~x") && why.contains("~z"), "{why}");
        }
        other => panic!("{other:?}"),
    }
}

/// The walker's defaults as `WalkerParams::default_for` computed them
/// before the profile (commit 4ea6321), field by field where they depend on
/// the robot.
fn previous_defaults(desc: &RobotDescription, model: &Model) -> WalkerParams {
    let nj = model.nv - model.base_nv();
    let stance = nominal_stance(&desc.name)
        .filter(|s| s.len() == nj)
        .unwrap_or_else(|| vec![0.0; nj]);
    let stance_h = stance_base_height_m(desc, &stance).unwrap_or(0.585);
    let mut q = vec![0.0, 0.0, stance_h, 0.0, 0.0, 0.0, 1.0];
    q.extend_from_slice(&stance);
    q.resize(model.nq, 0.0);
    let mut data = Data::new(model);
    let (kp, kd) =
        quadsim_engine::control::joint_pd::bandwidth_gains(model, &mut data, &q, 6.0, 1.0);
    let g = model.gravity.length();
    let mut vmc = VmcParams::for_model(model);
    if desc.name != "quad16" {
        let r = model.total_mass / 28.0;
        let gn = &mut vmc.gains;
        gn.stiffness_npm *= r;
        gn.damping_nspm *= r;
        gn.stiffness_nm_per_rad *= r;
        gn.damping_nms_per_rad *= r;
        vmc.base_height_m = 0.85 * stance_h;
    }
    let h = vmc.base_height_m;
    let scale = h / 0.5;
    let placement_hips_m = if desc.name == "quad12" {
        let legs = LegKinematics::for_robot(desc, model, FootPoint::Contact).unwrap();
        legs.iter()
            .map(|leg| {
                let a: Vec<f64> = leg.q_indices().iter().map(|&i| stance[i - 7]).collect();
                let mut p = leg.fk(&a);
                p.z = leg.mount().trans.z;
                p
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut p = WalkerParams::default_for(desc, model);
    p.vmc = vmc;
    p.placement = PlacementParams {
        gain_s: PlacementParams::capture_point_gain_s(h, g),
        max_step_x_m: 0.25 * scale,
        max_step_y_m: 0.12 * scale,
    };
    p.lift_height_m = 0.05 * scale;
    p.swing_kp_nm_per_rad = kp;
    p.swing_kd_nms_per_rad = kd;
    p.placement_hips_m = placement_hips_m;
    p
}

#[test]
fn the_profile_keeps_the_built_ins_walker_defaults() {
    for (name, overrides) in [
        ("quad16", &[][..]),
        ("quad16", QUAD16_OVERRIDES),
        ("quad12", &[][..]),
        ("quad12", QUAD12_OVERRIDES),
    ] {
        let (desc, model) = robot(name, overrides);
        let before = previous_defaults(&desc, &model);
        let after = WalkerParams::default_for(&desc, &model);
        // bit for bit
        assert_eq!(
            format!("{before:?}"),
            format!("{after:?}"),
            "{name} {overrides:?}"
        );
        assert_eq!(before, after, "{name} {overrides:?}");
    }
}

#[test]
fn built_in_profiles_are_reasonable() {
    let (desc, model) = robot("quad16", &[]);
    let p = RobotProfile::from_model(&desc, &model);
    assert_eq!(p.stance_rad, nominal_stance("quad16").unwrap());
    assert!((p.stance_base_height_m - 0.58543).abs() < 1e-4);
    assert!((p.leg_length_m - 0.61).abs() < 1e-12);
    assert!((p.total_mass_kg - 28.0).abs() < 1e-9);
    assert_eq!(p.walk_height_m, 0.5);
    assert_eq!(p.vmc_gain_scale, 1.0);
    assert!(p.placement_hips_m.is_empty());
    assert_eq!(p.stand_gains, StandGainRule::JointBandwidth);
    let (desc, model) = robot("quad12", &[]);
    let p = RobotProfile::from_model(&desc, &model);
    assert!((p.stance_base_height_m - 0.14).abs() < 1e-9);
    assert!((p.walk_height_m - 0.119).abs() < 1e-9);
    assert!((p.vmc_gain_scale - model.total_mass / 28.0).abs() < 1e-15);
    assert_eq!(p.placement_hips_m.len(), 4);
    // quad16 under another name: a generic profile, found from its model
    let (mut desc, model) = robot("quad16", &[]);
    desc.name = "unnamed".into();
    let p = RobotProfile::from_model(&desc, &model);
    assert!(matches!(p.stand_gains, StandGainRule::LegStiffness { .. }));
    let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
    for leg in &legs {
        let a: Vec<f64> = leg
            .q_indices()
            .iter()
            .map(|&i| p.stance_rad[i - 7])
            .collect();
        let foot = leg.fk(&a);
        let hip = leg.mount().trans;
        // under the hip, at 0.8 of the 0.61 m leg, knee bent backward
        assert!(
            (foot.x - hip.x).abs() < 1e-9 && (foot.y - hip.y).abs() < 1e-9,
            "{foot}"
        );
        assert!((hip.z - foot.z - 0.8 * 0.61).abs() < 1e-9, "{foot}");
        assert!(a[2] < -0.3, "{a:?}");
    }
    assert!((p.stance_base_height_m - 0.8 * 0.61).abs() < 1e-9);
    assert!((p.walk_height_m - 0.85 * 0.8 * 0.61).abs() < 1e-9);
}
