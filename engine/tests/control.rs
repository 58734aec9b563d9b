//! The static stance feed-forward holds the robot: with the feet pushed up by
//! m g / n each and the joints driven by `static_stance_torques`, the whole
//! robot (base included) has zero acceleration.

use glam::DVec3;
use quadsim_engine::Data;
use quadsim_engine::aba::aba_from_kinematics;
use quadsim_engine::control::joint_pd::{JointPd, bandwidth_gains, static_stance_torques};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::robots;

fn foot_points(name: &str, model: &Model) -> Vec<(usize, DVec3)> {
    let desc = robots::builtin(name).unwrap();
    model
        .feet
        .iter()
        .map(|&f| {
            let fr = &model.frames[f];
            let p = desc
                .foot_points
                .iter()
                .find(|(n, _)| *n == fr.name)
                .map_or(DVec3::ZERO, |(_, p)| *p);
            (fr.body, fr.placement.transform_point(p))
        })
        .collect()
}

#[test]
fn static_stance_torques_balance_the_robot() {
    for name in ["quad16", "quad12"] {
        let model =
            Model::from_description(&robots::builtin(name).unwrap(), BaseKind::Floating).unwrap();
        let mut data = Data::new(&model);
        let q = robots::nominal_q(name).unwrap();
        let feet = foot_points(name, &model);
        assert_eq!(feet.len(), 4);
        let tau_j = static_stance_torques(&model, &mut data, &q, &feet);
        let v = vec![0.0; model.nv];
        forward_kinematics(&model, &mut data, &q, &v);
        data.clear_external_forces();
        // the ground forces: vertical, summing to m g, centred under the CoM
        let com = quadsim_engine::com::center_of_mass(&model, &data);
        let pts: Vec<DVec3> = feet
            .iter()
            .map(|&(b, p)| data.body_point_world(b, p))
            .collect();
        let forces = support_forces(&pts, com, -model.gravity.z * model.total_mass);
        for (&(b, _), (pw, fz)) in feet.iter().zip(pts.iter().zip(&forces)) {
            data.add_point_force(b, *pw, DVec3::Z * *fz);
        }
        let mut tau = vec![0.0; model.nv];
        tau[6..].copy_from_slice(&tau_j);
        aba_from_kinematics(&model, &mut data, &v, &tau, true);
        let worst = data.ddq.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        // quad12's 1e-5 kg·m² links amplify round-off: 1e-6 is still 1e3 below an unbalanced stance
        assert!(worst < 1e-6, "{name}: residual acceleration {worst:e}");
        // and without the feed-forward the same robot does accelerate
        tau.fill(0.0);
        aba_from_kinematics(&model, &mut data, &v, &tau, true);
        assert!(
            data.ddq.iter().any(|a| a.abs() > 1e-3),
            "{name}: the test could not fail"
        );
    }
}

#[test]
fn joint_pd_law() {
    let pd = JointPd {
        kp_nm_per_rad: vec![100.0; 2],
        kd_nms_per_rad: vec![2.0; 2],
        target_rad: vec![0.5, -0.5],
        feedforward_nm: vec![1.0, 0.0],
    };
    let mut tau = [0.0; 2];
    pd.compute(&[0.4, -0.5], &[1.0, -2.0], &mut tau);
    assert!((tau[0] - (1.0 + 100.0 * 0.1 - 2.0)).abs() < 1e-12);
    assert!((tau[1] - 4.0).abs() < 1e-12);
}

/// Independent solution of the vertical support forces for four feet at a
/// rectangle's corners: symmetric in y here, so solve the 2-D lever problem
/// per side (front/hind split by the lever rule, left/right equal).
fn support_forces(pts: &[DVec3], com: DVec3, weight: f64) -> Vec<f64> {
    let xf = pts.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
    let xh = pts.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let front_share = (com.x - xh) / (xf - xh);
    pts.iter()
        .map(|p| {
            if (p.x - xf).abs() < 1e-9 {
                weight * front_share / 2.0
            } else {
                weight * (1.0 - front_share) / 2.0
            }
        })
        .collect()
}

#[test]
fn bandwidth_gains_scale_with_the_apparent_inertia() {
    // A single pendulum: the apparent inertia is I_c + m d², and the closed
    // loop kp/M = ω², kd/M = 2ζω.
    use quadsim_engine::description::RobotBuilder;
    let d = RobotBuilder::new("p")
        .link("base")
        .mass(1.0)
        .done()
        .link("arm")
        .mass(2.0)
        .com(DVec3::new(0.0, 0.0, -0.5))
        .inertia(glam::DMat3::from_diagonal(DVec3::splat(0.01)))
        .done()
        .revolute("j", "base", "arm", DVec3::ZERO, DVec3::Y)
        .build();
    let model = Model::from_description(&d, BaseKind::Fixed).unwrap();
    let mut data = Data::new(&model);
    let (kp, kd) = bandwidth_gains(&model, &mut data, &[0.3], 2.0, 0.7);
    let m = 0.01 + 2.0 * 0.25;
    let w = std::f64::consts::TAU * 2.0;
    assert!((kp[0] - m * w * w).abs() < 1e-12 * kp[0]);
    assert!((kd[0] - 2.0 * 0.7 * m * w).abs() < 1e-12 * kd[0]);
}
