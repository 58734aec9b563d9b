//! Study B's leg kinematics in the study's own symbols
//! (`quadsim_validation::study_b`): its printed forward formulas are quad12's
//! leg, the corrected inverse round-trips them, and the printed inverse fails
//! as `docs/study_b_kinematics.md` reports. (Moved from
//! `engine/tests/leg_ik.rs`.)

use quadsim_engine::description::RobotDescription;
use quadsim_engine::legs::{FootPoint, KneeBranch, LegKinematics, Quad12Leg, wrap_angle};
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::robots::builtin_with;
use quadsim_validation::study_b::StudyBLeg;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};

const TOL_RAD: f64 = 1e-9;

fn robot(name: &str, overrides: &[(&str, f64)]) -> (RobotDescription, Model) {
    let desc = builtin_with(name, overrides).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    (desc, model)
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

// ---------------------------------------------------------------- Study B

/// Study B's forward formulas are quad12's left-front leg when the leg is not
/// turned outward and the foot point is the shank's tip (the pad centre).
#[test]
fn study_b_forward_formulas_are_the_quad12_leg() {
    let (desc, model) = robot(
        "quad12",
        &[("leg.front_yaw_rad", 0.0), ("leg.hind_yaw_rad", 0.0)],
    );
    let lf = &legs12(&desc, &model, FootPoint::SphereCentre)[0];
    let study = StudyBLeg::STUDY;
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..1000 {
        let a = [
            rng.random_range(-PI..PI),
            rng.random_range(-PI..PI),
            rng.random_range(-PI..PI),
        ];
        assert!((lf.fk(a) - study.fk(a)).length() < 1e-15);
    }
}

/// Joint angles of Study B's workspace in the nominal branch: the foot
/// outward (`R > 0`), the knee bent positively, away from the singular poses.
fn study_b_samples(n: usize) -> Vec<[f64; 3]> {
    let study = StudyBLeg::STUDY;
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let mut out = Vec::new();
    while out.len() < n {
        let t = [
            rng.random_range(-PI..PI),
            rng.random_range(-FRAC_PI_2..FRAC_PI_2),
            rng.random_range(0.05..PI - 0.05),
        ];
        let reach = t[1].cos() * study.l2_m + (t[1] + t[2]).cos() * study.l3_m;
        if reach > 1e-3 {
            out.push(t);
        }
    }
    out
}

#[test]
fn study_b_corrected_inverse_round_trips_the_printed_forward() {
    let study = StudyBLeg::STUDY;
    for t in study_b_samples(20_000) {
        let p = study.fk(t);
        let s = study.ik(p, KneeBranch::Nominal).unwrap();
        for k in 0..3 {
            assert!(angle_diff(s[k], t[k]) < TOL_RAD, "{t:?} -> {s:?}");
        }
    }
    // and it is the leg's: the nominal stance
    let p = study.fk([0.0, PI / 6.0, PI / 3.0]);
    let s = study.ik(p, KneeBranch::Nominal).unwrap();
    assert!(angle_diff(s[1], PI / 6.0) < 1e-12 && angle_diff(s[2], PI / 3.0) < 1e-12);
}

/// The failures of Study B's printed inverse that `docs/study_b_kinematics.md`
/// reports; each assertion is a sentence of the doc.
#[test]
fn study_b_printed_inverse_fails_as_documented() {
    let study = StudyBLeg::STUDY;
    let (l1, l2, l3) = (study.l1_m, study.l2_m, study.l3_m);

    // 1. Full horizontal extension θ = 0: θ1 printed = atan(l1/(l2+l3)) − atan(l1/ρ)
    //    ≈ 0.0094 rad, θ2 printed ≈ −0.642 rad (−36.8°) instead of 0.
    let p0 = study.fk([0.0; 3]);
    let printed = study.printed_ik(p0);
    let rho = (l2 + l3).hypot(l1);
    assert!((printed[0] - ((l1 / (l2 + l3)).atan() - (l1 / rho).atan())).abs() < 1e-15);
    assert!((printed[0] - 0.0094).abs() < 5e-5, "{printed:?}");
    assert!((printed[1] + 0.642).abs() < 5e-4, "{printed:?}");

    // 2. The nominal stance (0, π/6, π/3): printed θ2 ≈ −1.85 rad instead of +0.524.
    let stance = [0.0, PI / 6.0, PI / 3.0];
    let printed = study.printed_ik(study.fk(stance));
    assert!((printed[1] + 1.853).abs() < 1e-3, "{printed:?}");

    let samples = study_b_samples(20_000);
    let mut theta1_err_ahead = Vec::new();
    let mut theta3_err = Vec::new();
    let mut theta2_err = Vec::new();
    let mut foot_err = Vec::new();
    for &t in &samples {
        let p = study.fk(t);
        let (u, v) = (p.x - study.a_m, p.y - study.b_m);
        let rho = u.hypot(v);
        let r = (rho * rho - l1 * l1).sqrt();
        let printed = study.printed_ik(p);

        // 3. θ1: where the foot is ahead of the mount (u > 0), the printed θ1 is
        //    off by exactly atan(l1/R) − atan(l1/ρ) (atan(l1/ρ) should be
        //    atan(l1/R) = asin(l1/ρ)); behind it (u < 0) the one-argument atan
        //    also loses π.
        let expected = wrap_angle(t[0] + ((l1 / r).atan() - (l1 / rho).atan()));
        if u > 0.0 {
            assert!(angle_diff(printed[0], expected) < 1e-9, "{t:?}");
            theta1_err_ahead.push(angle_diff(printed[0], t[0]));
        } else {
            assert!(angle_diff(printed[0] + PI, expected) < 1e-9, "{t:?}");
        }

        // 4. θ3 given the TRUE θ1, θ2 is θ3 − π/2 modulo π (numerator and
        //    denominator are l3 cos θ3 and −l3 sin θ3: the fraction is inverted)
        let t3 = study.printed_theta3(p, t[0], t[1]);
        let off = wrap_angle(t3 - (t[2] - FRAC_PI_2));
        assert!(
            off.abs() < 1e-9 || (off.abs() - PI).abs() < 1e-9,
            "{t:?}: {t3}"
        );
        //    and atan2(−denominator, numerator) is θ3
        let (s2, c2) = t[1].sin_cos();
        let a = p.z - study.c_m;
        let fixed = (-(s2 * r + c2 * a)).atan2(c2 * r - s2 * a - l2);
        assert!(angle_diff(fixed, t[2]) < 1e-9, "{t:?}: {fixed}");
        theta3_err.push(angle_diff(printed[2], t[2]));

        theta2_err.push(angle_diff(printed[1], t[1]));
        foot_err.push((study.fk(printed) - p).length());
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let theta1_median = median(&mut theta1_err_ahead);
    let (theta1_min, theta1_max) = (
        theta1_err_ahead[0],
        theta1_err_ahead[theta1_err_ahead.len() - 1],
    );
    let theta3_median = median(&mut theta3_err);
    let theta2_right = theta2_err.iter().filter(|&&e| e < 0.01).count();
    let theta2_median = median(&mut theta2_err);
    let foot_median = median(&mut foot_err);
    let (foot_min, foot_max) = (foot_err[0], foot_err[foot_err.len() - 1]);
    eprintln!(
        "study B printed inverse over {} poses: θ1 error ahead of the mount \
         {theta1_min:.4}..{theta1_max:.3} rad, median {theta1_median:.3}; θ2 median error \
         {theta2_median:.3} rad, within 0.01 rad at {theta2_right} poses; θ3 median error \
         {theta3_median:.3} rad; foot error {foot_min:.3}..{foot_max:.3} m, median \
         {foot_median:.3} m",
        samples.len()
    );
    // θ1 is never right while l1 > 0 (its smallest error is at full extension)
    assert!((theta1_min - 0.0094).abs() < 1e-4 && (0.7..0.8).contains(&theta1_max));
    assert!((0.06..0.07).contains(&theta1_median));
    // chained after the printed θ1, θ2, θ3 is off by 1.7 rad in the median
    assert!((1.6..1.8).contains(&theta3_median));
    // 5. θ2 is right only on a thin curve of the workspace (< 1 % of poses)
    assert!(theta2_median > 1.0 && theta2_right < samples.len() / 100);
    // 6. the printed chain never puts the foot within 5 cm of the target
    //    (80 to 300 mm off; the whole leg is 18 cm long)
    assert!(
        foot_min > 0.05 && foot_median > 0.15,
        "{foot_min} {foot_median}"
    );
    assert!((0.075..0.085).contains(&foot_min) && (0.29..0.31).contains(&foot_max));
}
