//! One robot's forward kinematics, ABA, RNEA and leg IK with its **legs in
//! SIMD lanes** ([`crate::plan::Plan::LegsX4`]): for a base carrying four
//! unbranched chains of identical shape — quad16's and quad12's legs — the
//! four bodies at each depth are one group of four f64 lanes in an AVX
//! register (`kernels::f64x4`), and the base stays scalar.
//!
//! The per-robot passes spend their time in short dependent chains of
//! 3-vector and 3×3 arithmetic, one body after another; the four legs' chains
//! are independent, so one AVX instruction can do the same operation for all
//! four. Every output is **bit-identical** to the scalar path (the kernel
//! contract, [`crate::kernels`]): the lane types repeat the scalar formulas
//! operation for operation, each lane gets the bits of the scalar
//! kinematics' sine and cosine, and the base receives its children's terms in
//! the scalar order (decreasing body index).
//!
//! Called from the x86-64-v3 clones of [`crate::dispatch`]'s functions only
//! (the lane code needs AVX); other CPUs and architectures run the scalar
//! path, with the same bits.

#[cfg(target_arch = "x86_64")]
mod ik;
#[cfg(target_arch = "x86_64")]
pub(crate) mod passes;
pub(crate) mod workspace;

/// quad16's four legs in lanes for the closed-form IK ([`legs_ik`]); an
/// empty stand-in off x86-64.
#[cfg(target_arch = "x86_64")]
pub(crate) use ik::Quad16Legs;

/// The stand-in for `ik::Quad16Legs` off x86-64, where the IK has no lanes.
#[cfg(not(target_arch = "x86_64"))]
#[derive(Clone, Debug)]
pub(crate) struct Quad16Legs;

#[cfg(not(target_arch = "x86_64"))]
impl Quad16Legs {
    /// No lanes off x86-64.
    pub(crate) fn new(_: [&crate::legs::Quad16Leg; 4]) -> Option<Quad16Legs> {
        None
    }
}

/// The four legs' clamped IK ([`crate::legs::Quad16Leg::ik_clamped_angles`]'
/// angles, leg by leg, bit for bit) with the legs in AVX lanes, where the
/// CPU has AVX2 and the ankle holds a foot pitch; `None` otherwise (the
/// caller then solves leg by leg). A leg whose target is not finite gets
/// meaningless angles: the caller checks (the scalar solve's
/// [`crate::legs::IkError::NonFinite`]).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(crate) fn legs_ik(
    legs: &Quad16Legs,
    targets: &[glam::DVec3; 4],
    opts: &crate::legs::IkOptions,
) -> Option<[[f64; 4]; 4]> {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => if let crate::legs::AnkleMode::FootPitch(psi) = opts.ankle {
            let sign = opts.knee.sign(crate::legs::quad16_leg::NOMINAL_BEND);
            return Some(crate::kernels::avx_call!(ik::solve(legs, targets, psi, sign)));
        },
        _ => {},
    }
    let _ = (legs, targets, opts);
    None
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use crate::dispatch::{aba, aba_from_kinematics, forward_kinematics};
    use crate::model::BaseKind;
    use crate::plan::{LEGS, Plan};
    use crate::{Data, Model};
    use glam::{DQuat, DVec3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn bits(x: &[f64]) -> Vec<u64> {
        x.iter().map(|e| e.to_bits()).collect()
    }

    /// A random floating-base pose in `q[..7]`: position within ±5 m
    /// (height 0–1 m), any orientation up to ±3 rad about a random axis.
    fn random_base_pose(r: &mut ChaCha8Rng, q: &mut [f64]) {
        let axis = DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        )
        .normalize();
        let quat = DQuat::from_axis_angle(axis, r.random_range(-3.0..3.0));
        q[..7].copy_from_slice(&[
            r.random_range(-5.0..5.0),
            r.random_range(-5.0..5.0),
            r.random_range(0.0..1.0),
            quat.x,
            quat.y,
            quat.z,
            quat.w,
        ]);
    }

    /// `model`'s neutral `q` with every joint within ±3 rad and, on a
    /// floating base, the base at a random x within ±5 m (y 0.3, z 0.5 m).
    fn random_joints_and_x(model: &Model, r: &mut ChaCha8Rng) -> Vec<f64> {
        let mut q = model.neutral_q();
        let nb = model.base_nq();
        for x in &mut q[nb..] {
            *x = r.random_range(-3.0..3.0);
        }
        if model.is_floating() {
            q[..3].copy_from_slice(&[r.random_range(-5.0..5.0), 0.3, 0.5]);
        }
        q
    }

    /// The built-in `name` on `base` (legs in lanes where its shape allows)
    /// and the same model on the general path (`Plan::Scalar`).
    fn fast_and_general(name: &str, base: BaseKind) -> (Model, Model) {
        let desc = crate::robots::builtin(name).unwrap();
        let fast = Model::from_description(&desc, base).unwrap();
        let mut general = fast.clone();
        general.plan = Plan::Scalar;
        (fast, general)
    }

    /// Distinct external forces on every body (after kinematics).
    fn set_external_forces(d: &mut Data) {
        for (i, f) in d.external_forces_mut().iter_mut().enumerate() {
            let k = i as f64;
            f.lin = DVec3::new(3.0 * k - 10.0, 0.5 * k, 40.0 - k);
            f.ang = DVec3::new(0.1 * k, -0.2, 0.3 * k - 1.0);
        }
    }

    /// Every output of kinematics and ABA, legs in lanes against the general
    /// path (the same model with `Plan::Scalar`), bit for bit, at random
    /// states with and without external forces, on quad16 (floating and
    /// fixed base) and quad12.
    #[test]
    fn legs_in_lanes_give_the_general_paths_bits() {
        for (name, base) in [
            ("quad16", BaseKind::Floating),
            ("quad16", BaseKind::Fixed),
            ("quad12", BaseKind::Floating),
        ] {
            let (fast, general) = fast_and_general(name, base);
            // both built-ins are four identical legs on a base: the plan
            // is the model's shape, not its name
            assert!(fast.leg_lanes().is_some(), "{name} has its legs in lanes");
            let mut r = ChaCha8Rng::seed_from_u64(7);
            for trial in 0..50 {
                let mut q = fast.neutral_q();
                let nb = fast.base_nq();
                if fast.is_floating() {
                    random_base_pose(&mut r, &mut q);
                }
                for x in &mut q[nb..] {
                    *x = r.random_range(-3.0..3.0);
                }
                let v: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-4.0..4.0)).collect();
                let tau: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-50.0..50.0)).collect();
                let external = trial % 2 == 1;
                let mut outs = Vec::new();
                for m in [&fast, &general] {
                    let mut d = Data::new(m);
                    if external {
                        forward_kinematics(m, &mut d, &q, &v);
                        set_external_forces(&mut d);
                        aba_from_kinematics(m, &mut d, &v, &tau, true);
                    } else {
                        aba(m, &mut d, &q, &v, &tau);
                    }
                    let mut all = d.ddq.clone();
                    for i in 0..m.nbodies {
                        all.extend(d.pose[i].rot.to_cols_array());
                        all.extend(d.pose[i].trans.to_array());
                        all.extend(d.vel[i].to_array());
                        all.extend(d.subspace(m, i).to_array());
                        all.extend(d.acc[i].to_array());
                        let ri = d.body_inertia(m, i);
                        all.push(ri.mass);
                        all.extend(ri.com.to_array());
                        all.extend(ri.inertia_com.to_cols_array());
                    }
                    outs.push(all);
                }
                assert_eq!(
                    bits(&outs[0]),
                    bits(&outs[1]),
                    "{name} {base:?} trial {trial}"
                );
            }
        }
    }

    /// [`crate::dispatch::leg_end_points`] gives the bits of
    /// `Data::body_point_world` and `Data::body_point_velocity` after the
    /// full kinematics on the general path, at random states and points,
    /// floating and fixed base (the estimator's feet, base at rest, among
    /// them); a model without the leg plan gets `None`.
    /// The integrator's ABA (no legs' `acc`) gives `aba_from_kinematics`'s
    /// `ddq` and base acceleration, bit for bit.
    #[test]
    fn ddq_only_aba_gives_the_same_ddq() {
        use crate::dispatch::aba_ddq_from_kinematics;
        let (fast, _) = fast_and_general("quad16", BaseKind::Floating);
        let mut r = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..20 {
            let mut q = fast.neutral_q();
            for x in &mut q[7..] {
                *x = r.random_range(-3.0..3.0);
            }
            let v: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-4.0..4.0)).collect();
            let tau: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-50.0..50.0)).collect();
            let mut outs = Vec::new();
            for ddq_only in [false, true] {
                let mut d = Data::new(&fast);
                forward_kinematics(&fast, &mut d, &q, &v);
                set_external_forces(&mut d);
                if ddq_only {
                    aba_ddq_from_kinematics(&fast, &mut d, &v, &tau, true);
                } else {
                    aba_from_kinematics(&fast, &mut d, &v, &tau, true);
                }
                let mut all = d.ddq.clone();
                all.extend(d.acc[0].to_array());
                outs.push(bits(&all));
            }
            assert_eq!(outs[0], outs[1]);
        }
    }

    #[test]
    fn leg_end_points_give_the_full_kinematics_bits() {
        use crate::dispatch::leg_end_points;
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            let (fast, general) = fast_and_general("quad16", base);
            let plan = fast.leg_lanes().expect("quad16's legs in lanes");
            let last = *plan.groups.last().unwrap();
            let mut r = ChaCha8Rng::seed_from_u64(11);
            for trial in 0..100 {
                let mut q = fast.neutral_q();
                let nb = fast.base_nq();
                let mut v: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-4.0..4.0)).collect();
                if fast.is_floating() && trial % 2 == 0 {
                    random_base_pose(&mut r, &mut q);
                } else if fast.is_floating() {
                    // the estimator's case: the base at the origin, at rest
                    v[..6].fill(0.0);
                }
                for x in &mut q[nb..] {
                    *x = r.random_range(-3.0..3.0);
                }
                let points: [DVec3; LEGS] = std::array::from_fn(|_| {
                    DVec3::new(
                        r.random_range(-0.1..0.1),
                        r.random_range(-0.1..0.1),
                        r.random_range(-0.3..0.0),
                    )
                });
                let (p, pv) = leg_end_points(&fast, &q, &v, points).expect("lanes on this CPU");
                let mut d = Data::for_kinematics(&general);
                forward_kinematics(&general, &mut d, &q, &v);
                for k in 0..LEGS {
                    let want = (
                        d.body_point_world(last[k], points[k]),
                        d.body_point_velocity(last[k], points[k]),
                    );
                    let got = [p[k].to_array(), pv[k].to_array()].concat();
                    let want = [want.0.to_array(), want.1.to_array()].concat();
                    assert_eq!(bits(&got), bits(&want), "{base:?} trial {trial} leg {k}");
                }
            }
            let none = leg_end_points(
                &general,
                &fast.neutral_q(),
                &vec![0.0; fast.nv],
                [DVec3::ZERO; LEGS],
            );
            assert!(none.is_none());
        }
    }

    /// RNEA with the legs in lanes against the general path, bit for bit:
    /// every `tau`, `acc` and `f` entry at random states and accelerations,
    /// with and without external forces, on quad16 (floating and fixed base).
    #[test]
    fn rnea_in_lanes_gives_the_general_paths_bits() {
        use crate::dispatch::rnea_from_kinematics;
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            let (fast, general) = fast_and_general("quad16", base);
            assert!(fast.leg_lanes().is_some());
            let mut r = ChaCha8Rng::seed_from_u64(11);
            for trial in 0..50 {
                let q = random_joints_and_x(&fast, &mut r);
                let v: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-4.0..4.0)).collect();
                // zeros in some rows, as the walker's base and stance legs have
                let a: Vec<f64> = (0..fast.nv)
                    .map(|k| {
                        if k % 3 == 0 {
                            0.0
                        } else {
                            r.random_range(-40.0..40.0)
                        }
                    })
                    .collect();
                let external = trial % 2 == 1;
                let mut outs = Vec::new();
                for m in [&fast, &general] {
                    let mut d = Data::new(m);
                    forward_kinematics(m, &mut d, &q, &v);
                    set_external_forces(&mut d);
                    rnea_from_kinematics(m, &mut d, &v, &a, external);
                    let mut all = d.tau.clone();
                    for i in 0..m.nbodies {
                        all.extend(d.acc[i].to_array());
                        all.extend(d.f[i].to_array());
                    }
                    outs.push(all);
                }
                assert_eq!(bits(&outs[0]), bits(&outs[1]), "{base:?} trial {trial}");
            }
        }
    }

    /// The joint-torque-only RNEA (the walker's) against the full RNEA's
    /// joint rows, bit for bit, on the lanes' model and the general one, at
    /// random states and accelerations (base rows zero, as the walker's, or
    /// not).
    #[test]
    fn rnea_joint_torques_give_the_full_rneas_bits() {
        use crate::dispatch::{rnea_from_kinematics, rnea_joint_torques_from_kinematics};
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            let (fast, general) = fast_and_general("quad16", base);
            let mut r = ChaCha8Rng::seed_from_u64(12);
            for trial in 0..100 {
                let mut q = random_joints_and_x(&fast, &mut r);
                if fast.is_floating() {
                    let rot = DQuat::from_euler(
                        glam::EulerRot::ZYX,
                        r.random_range(-3.0..3.0),
                        r.random_range(-0.5..0.5),
                        r.random_range(-0.5..0.5),
                    );
                    q[3..7].copy_from_slice(&[rot.x, rot.y, rot.z, rot.w]);
                }
                let v: Vec<f64> = (0..fast.nv).map(|_| r.random_range(-4.0..4.0)).collect();
                let base_rows_zero = trial % 2 == 0;
                let nv0 = fast.base_nv();
                let a: Vec<f64> = (0..fast.nv)
                    .map(|k| {
                        if (base_rows_zero && k < nv0) || k % 3 == 0 {
                            0.0
                        } else {
                            r.random_range(-40.0..40.0)
                        }
                    })
                    .collect();
                for m in [&fast, &general] {
                    let mut d = Data::new(m);
                    forward_kinematics(m, &mut d, &q, &v);
                    rnea_from_kinematics(m, &mut d, &v, &a, false);
                    let full = d.tau[nv0..].to_vec();
                    let mut d = Data::new(m);
                    forward_kinematics(m, &mut d, &q, &v);
                    let mut joints = vec![f64::NAN; m.nv - nv0];
                    rnea_joint_torques_from_kinematics(m, &mut d, &v, &a, &mut joints);
                    assert_eq!(bits(&joints), bits(&full), "{base:?} trial {trial}");
                }
            }
        }
    }

    /// The AVX lanes' sine and cosine, where this CPU runs them.
    #[multiversion::multiversion(targets("x86_64+avx2+fma"))]
    fn f4_sin_cos(x: [f64; 4]) -> Option<([f64; 4], [f64; 4])> {
        multiversion::target::match_target! {
            "x86_64+avx2+fma" => {
                let (s, c) = crate::kernels::f64x4::F4::from_array(x).sin_cos();
                Some((s.to_array(), c.to_array()))
            },
            _ => {
                let _ = x;
                None
            },
        }
    }

    /// `F4::sin_cos` (the legs' lanes) gives `libm::sincos`'s bits in every
    /// lane, as `trig::sin_cos_lanes` does, on the trig tests' dense and hard
    /// sample.
    #[test]
    fn avx_sin_cos_gives_libm_bits() {
        if f4_sin_cos([0.0; 4]).is_none() {
            return; // no AVX2 on this CPU: the lanes never run
        }
        for x in crate::trig::tests::sample().chunks_exact(4) {
            let x = [x[0], x[1], x[2], x[3]];
            let (s, c) = f4_sin_cos(x).unwrap();
            crate::trig::tests::assert_libm_bits(x, s, c);
        }
        // every lane within ±π/4 (`F4::sin_cos_within_pio4`): zeros,
        // subnormals, tiny arguments and both sides of the bounds
        use crate::trig::{PIO4, TINY};
        let below = |x: f64| f64::from_bits(x.to_bits() - 1);
        for x in [
            [0.0, -0.0, 5e-324, -5e-324],
            [f64::MIN_POSITIVE, TINY, below(TINY), -TINY],
            [1e-9, -1e-5, 2e-8, -1e-300],
            [PIO4, -PIO4, below(PIO4), -below(PIO4)],
            [0.3, -0.6, 0.785, -0.1],
        ] {
            let (s, c) = f4_sin_cos(x).unwrap();
            crate::trig::tests::assert_libm_bits(x, s, c);
        }
    }

    /// A repeated velocity at new joint rates (forward kinematics' velocity-only
    /// path) leaves the lanes' velocities consistent with the per-body ones.
    #[test]
    fn velocity_only_update_keeps_the_lanes_current() {
        let (fast, general) = fast_and_general("quad16", BaseKind::Floating);
        let q = fast.neutral_q();
        let v0 = vec![0.3; fast.nv];
        let v1: Vec<f64> = (0..fast.nv).map(|k| 0.1 * k as f64 - 1.0).collect();
        let tau = vec![1.0; fast.nv];
        let mut outs = Vec::new();
        for m in [&fast, &general] {
            let mut d = Data::new(m);
            forward_kinematics(m, &mut d, &q, &v0);
            // same q, new v: velocities only
            forward_kinematics(m, &mut d, &q, &v1);
            aba_from_kinematics(m, &mut d, &v1, &tau, false);
            outs.push(d.ddq.clone());
        }
        assert_eq!(bits(&outs[0]), bits(&outs[1]));
    }

    /// A kinematics-only `Data` (no reference inertias) gets the same poses, subspaces and velocities as a full
    /// one, on the full and the velocity-only path, in lanes and not.
    #[test]
    fn kinematics_only_data_gets_the_same_kinematics() {
        let (lanes, general) = fast_and_general("quad16", BaseKind::Floating);
        assert!(lanes.leg_lanes().is_some());
        for m in [lanes, general] {
            kinematics_only_matches(&m);
        }
    }

    fn kinematics_only_matches(m: &Model) {
        let mut q = m.neutral_q();
        for (k, x) in q[m.base_nq()..].iter_mut().enumerate() {
            *x = 0.2 * k as f64 - 1.3;
        }
        let v0: Vec<f64> = (0..m.nv).map(|k| 0.05 * k as f64 - 0.4).collect();
        let v1 = vec![0.7; m.nv];
        let kin = |d: &Data| {
            let mut all = Vec::new();
            for i in 0..m.nbodies {
                all.extend(d.pose[i].rot.to_cols_array());
                all.extend(d.pose[i].trans.to_array());
                all.extend(d.vel[i].to_array());
                all.extend(d.subspace(m, i).to_array());
            }
            bits(&all)
        };
        let (mut full, mut light) = (Data::new(m), Data::for_kinematics(m));
        assert!(light.inertia_ref.is_empty());
        for v in [&v0, &v1] {
            forward_kinematics(m, &mut full, &q, v);
            forward_kinematics(m, &mut light, &q, v);
            assert_eq!(kin(&full), kin(&light));
        }
    }
}
