//! Virtual Model Control and the stance-force QP: the QP's constraints and
//! optimality (against closed forms and `clarabel`), the VMC spring–dampers
//! (against hand-computed wrenches), the `τ = −Jᵀ f` sign convention (static
//! balance through ABA) and quad16 standing on concrete under VMC.
//! Run with `--release`.

use glam::{DMat3, DQuat, DVec3};
use quadsim_engine::Data;
use quadsim_engine::aba::aba_from_kinematics;
use quadsim_engine::com::{center_of_mass, com_velocity};
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundPreset, update_after_step,
};
use quadsim_engine::control::force_qp::{
    FootForces, ForceQp, ForceQpError, ForceQpParams, MAX_FEET, StanceFoot, achieved_wrench,
    solve_clarabel, stance_torques, tangent_basis,
};
use quadsim_engine::control::vmc::{Vmc, VmcCommand, VmcInput, VmcParams};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::jacobian::{add_point_force_jt, point_jacobian};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::nle::generalized_gravity;
use quadsim_engine::robots;
use quadsim_engine::spatial::{Force, rot_from_rpy, rpy_from_rot};
use quadsim_engine::terrain::TerrainUnion;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations_in;

// ---------------------------------------------------------------- force QP

/// A random stance: each of four feet near a 0.6 × 0.3 m rectangle 0.5 m
/// below the CoM present with probability 0.8, terrain tilted up to 0.4 rad,
/// μ in [0.2, 1.2], load 1 (half), 0 (quarter) or random.
fn random_stance(rng: &mut ChaCha8Rng) -> Vec<StanceFoot> {
    let corners = [(0.3, 0.15), (0.3, -0.15), (-0.3, -0.15), (-0.3, 0.15)];
    let mut feet = Vec::new();
    for &(x, y) in &corners {
        if rng.random_bool(0.8) {
            let tilt: f64 = rng.random_range(0.0..0.4);
            let az: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let load = match rng.random_range(0..4) {
                0 => rng.random_range(0.0..1.0),
                1 => 0.0,
                _ => 1.0,
            };
            feet.push(StanceFoot {
                position_m: DVec3::new(
                    x + rng.random_range(-0.1..0.1),
                    y + rng.random_range(-0.1..0.1),
                    -0.5 + rng.random_range(-0.1..0.1),
                ),
                normal: DVec3::new(tilt.sin() * az.cos(), tilt.sin() * az.sin(), tilt.cos()),
                friction: rng.random_range(0.2..1.2),
                load,
            });
        }
    }
    feet
}

/// A random force inside the foot's pyramid and normal bounds (normal force
/// up to 300 N at full load).
fn random_feasible_force(rng: &mut ChaCha8Rng, p: &ForceQpParams, foot: &StanceFoot) -> DVec3 {
    let (t1, t2) = tangent_basis(foot.normal);
    let lo = p.min_normal_force_n * foot.load;
    let hi = 300.0f64.min(p.max_normal_force_n) * foot.load;
    let fn_ = if hi > lo {
        rng.random_range(lo..hi)
    } else {
        lo
    };
    let lim = foot.friction / 2f64.sqrt() * fn_;
    let tangential = |rng: &mut ChaCha8Rng| {
        if lim > 0.0 {
            rng.random_range(-lim..lim)
        } else {
            0.0
        }
    };
    foot.normal * fn_ + t1 * tangential(rng) + t2 * tangential(rng)
}

/// A random wrench up to 300 N sideways, 800 N up and 60 N·m.
fn random_wrench(rng: &mut ChaCha8Rng) -> Force {
    Force {
        lin: DVec3::new(
            rng.random_range(-300.0..300.0),
            rng.random_range(-300.0..300.0),
            rng.random_range(0.0..800.0),
        ),
        ang: DVec3::new(
            rng.random_range(-60.0..60.0),
            rng.random_range(-60.0..60.0),
            rng.random_range(-60.0..60.0),
        ),
    }
}

/// The QP's objective `‖A f − W‖²_S + α‖f‖²`, evaluated from its definition.
fn objective(p: &ForceQpParams, feet: &[StanceFoot], w: &Force, f: &FootForces) -> f64 {
    let aw = achieved_wrench(feet, f);
    let (e, em) = (aw.lin - w.lin, aw.ang - w.ang);
    let s = p.wrench_weight;
    let err = [e.x, e.y, e.z, em.x, em.y, em.z];
    (0..6).map(|i| s[i] * err[i] * err[i]).sum::<f64>()
        + p.regularization * f.iter().map(|x| x.length_squared()).sum::<f64>()
}

/// Every force lies in the true friction cone `|f_t| ≤ μ f_n` and between
/// the normal-force bounds scaled by the load; unloaded and absent feet carry
/// nothing.
fn assert_feasible(p: &ForceQpParams, feet: &[StanceFoot], f: &FootForces, tol_n: f64) {
    for (i, foot) in feet.iter().enumerate() {
        let fn_ = f[i].dot(foot.normal);
        let ft = (f[i] - fn_ * foot.normal).length();
        assert!(f[i].is_finite(), "foot {i}: {:?}", f[i]);
        assert!(
            ft <= foot.friction * fn_ + tol_n,
            "foot {i}: |f_t| {ft} > μ f_n {}",
            foot.friction * fn_
        );
        assert!(
            fn_ >= p.min_normal_force_n * foot.load - tol_n,
            "foot {i}: f_n {fn_} below bound"
        );
        assert!(
            fn_ <= p.max_normal_force_n * foot.load + tol_n,
            "foot {i}: f_n {fn_} above bound"
        );
        if foot.load == 0.0 {
            assert_eq!(f[i], DVec3::ZERO, "unloaded foot {i}");
        }
    }
    for fi in &f[feet.len()..] {
        assert_eq!(*fi, DVec3::ZERO);
    }
}

/// The dedicated active-set solver and clarabel (an interior-point method on
/// an independently built, lifted formulation) agree to 1e-6 of the force
/// scale on 1000 random feasible cases: random stances with a wrench that
/// some feasible forces produce (`W = A f` for random forces inside the
/// constraints). Both solutions are feasible and reproduce W. The minimum-norm
/// forces the QP picks differ from the random ones, so constraints bind in
/// many cases.
#[test]
fn active_set_matches_clarabel_on_random_feasible_cases() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let (mut worst, mut constrained) = (0.0f64, 0);
    for case in 0..1000 {
        let feet = random_stance(&mut rng);
        let mut f_rand = [DVec3::ZERO; MAX_FEET];
        for (fr, foot) in f_rand.iter_mut().zip(&feet) {
            if foot.load > 0.0 {
                *fr = random_feasible_force(&mut rng, &params, foot);
            }
        }
        let w = if feet.iter().any(|f| f.load > 0.0) {
            achieved_wrench(&feet, &f_rand)
        } else {
            random_wrench(&mut rng)
        };
        let a = qp.solve(&feet, &w).unwrap();
        constrained += usize::from(qp.last_iterations() > 0);
        let b = solve_clarabel(&params, &feet, &w).unwrap();
        assert_feasible(&params, &feet, &a, 1e-7);
        assert_feasible(&params, &feet, &b, 1e-7);
        let scale = a
            .iter()
            .map(|f| f.abs().max_element())
            .fold(1.0f64, f64::max);
        let d = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (*x - *y).abs().max_element())
            .fold(0.0f64, f64::max);
        assert!(
            d <= 1e-6 * scale,
            "case {case}: differ by {d} N (scale {scale} N)"
        );
        worst = worst.max(d / scale);
        if w.lin.length() > 0.0 && feet.iter().any(|f| f.load > 0.0) {
            let e = rel_err(&achieved_wrench(&feet, &a), &w);
            assert!(e < 1e-4, "case {case}: W reproduced to {e:e} only");
        }
    }
    assert!(constrained > 200, "only {constrained} constrained cases");
    println!("worst relative difference {worst:e}, {constrained} constrained cases");
}

/// Arbitrary (mostly unachievable) wrenches: both solvers return feasible
/// forces with the same objective to 1e-9 relative. The forces themselves
/// are compared only to 1e-4: with a residual of ~10⁵ N² in the objective,
/// f64 resolves it to ~10⁻¹¹, and the directions fixed only by α = 1e-6 then
/// to ~√(10⁻¹¹/α) ≈ 3 mN in an interior-point method's stopping test.
#[test]
fn active_set_matches_clarabel_on_unachievable_wrenches() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let mut worst = 0.0f64;
    for case in 0..1000 {
        let feet = random_stance(&mut rng);
        let w = random_wrench(&mut rng);
        let a = qp.solve(&feet, &w).unwrap();
        let b = solve_clarabel(&params, &feet, &w).unwrap();
        assert_feasible(&params, &feet, &a, 1e-7);
        assert_feasible(&params, &feet, &b, 1e-7);
        let (ja, jb) = (
            objective(&params, &feet, &w, &a),
            objective(&params, &feet, &w, &b),
        );
        assert!(
            ja <= jb * (1.0 + 1e-9) + 1e-12,
            "case {case}: objective {ja} vs clarabel {jb}"
        );
        assert!(
            (ja - jb).abs() <= 1e-9 * jb.max(1.0),
            "case {case}: {ja} vs {jb}"
        );
        let scale = a
            .iter()
            .map(|f| f.abs().max_element())
            .fold(1.0f64, f64::max);
        let d = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (*x - *y).abs().max_element())
            .fold(0.0f64, f64::max);
        assert!(
            d <= 1e-4 * scale,
            "case {case}: differ by {d} N (scale {scale} N)"
        );
        worst = worst.max(d / scale);
    }
    println!("worst relative difference {worst:e}");
}

fn quad_feet(normal: DVec3, mu: f64) -> Vec<StanceFoot> {
    [(0.3, 0.15), (0.3, -0.15), (-0.3, -0.15), (-0.3, 0.15)]
        .iter()
        .map(|&(x, y)| StanceFoot {
            position_m: DVec3::new(x, y, -0.5),
            normal,
            friction: mu,
            load: 1.0,
        })
        .collect()
}

fn rel_err(a: &Force, b: &Force) -> f64 {
    let d = ((a.lin - b.lin).length_squared() + (a.ang - b.ang).length_squared()).sqrt();
    d / (b.lin.length_squared() + b.ang.length_squared()).sqrt()
}

/// An achievable wrench is reproduced to 1e-6: pure weight support on four
/// feet (split equally, by symmetry and least norm), and wrenches with
/// moments and sideways forces well inside the friction cones on four and
/// three feet.
#[test]
fn feasible_wrench_is_reproduced() {
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let mg = 28.0 * 9.81;
    let feet = quad_feet(DVec3::Z, 0.8);
    let weight = Force {
        lin: DVec3::new(0.0, 0.0, mg),
        ang: DVec3::ZERO,
    };
    for f in [
        qp.solve(&feet, &weight).unwrap(),
        solve_clarabel(&params, &feet, &weight).unwrap(),
    ] {
        assert!(rel_err(&achieved_wrench(&feet, &f), &weight) < 1e-6);
        for fi in &f {
            assert!((*fi - DVec3::new(0.0, 0.0, mg / 4.0)).length() < 1e-6 * mg);
        }
    }
    let w = Force {
        lin: DVec3::new(20.0, -15.0, mg),
        ang: DVec3::new(4.0, -6.0, 3.0),
    };
    // three feet around the CoM's projection: two front, one hind centre
    let mut tripod = feet[..3].to_vec();
    tripod[2].position_m = DVec3::new(-0.3, 0.0, -0.5);
    for stance in [&feet[..], &tripod[..]] {
        let f = qp.solve(stance, &w).unwrap();
        assert_feasible(&params, stance, &f, 1e-9);
        let e = rel_err(&achieved_wrench(stance, &f), &w);
        assert!(
            e < 1e-6,
            "{} feet: relative wrench error {e:e}",
            stance.len()
        );
    }
}

/// A wrench beyond friction gives the nearest feasible one. Closed form: a
/// single foot at the CoM (no moment arm, S_F = 1) minimises
/// `|f − F|² + α|f|² = (1 + α)|f − F/(1 + α)|² + const`, so `f` is the
/// projection of `F/(1 + α)` onto the pyramid: onto the facet `f_x = μ' f_z`
/// for a force leaning too far along +x.
#[test]
fn infeasible_wrench_is_projected_onto_the_pyramid() {
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let mu = 0.8;
    let feet = [StanceFoot {
        position_m: DVec3::ZERO,
        normal: DVec3::Z,
        friction: mu,
        load: 1.0,
    }];
    let w = Force {
        lin: DVec3::new(400.0, 0.0, 100.0),
        ang: DVec3::ZERO,
    };
    let p = w.lin / (1.0 + params.regularization);
    let d = DVec3::new(mu / 2f64.sqrt(), 0.0, 1.0).normalize();
    let expected = d * p.dot(d);
    for f in [
        qp.solve(&feet, &w).unwrap(),
        solve_clarabel(&params, &feet, &w).unwrap(),
    ] {
        assert!(
            (f[0] - expected).length() < 1e-7,
            "{:?} vs {expected:?}",
            f[0]
        );
    }
    // Far beyond friction on four feet: finite, feasible, and no feasible
    // point nearby does better (the solution is the constrained minimum).
    let feet = quad_feet(DVec3::new(0.2, 0.0, 1.0).normalize(), 0.5);
    let w = Force {
        lin: DVec3::new(5000.0, -3000.0, 200.0),
        ang: DVec3::new(300.0, 0.0, -400.0),
    };
    let f = qp.solve(&feet, &w).unwrap();
    assert_feasible(&params, &feet, &f, 1e-9);
    let best = objective(&params, &feet, &w, &f);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..2000 {
        // random feasible forces, and points on the segment toward them
        let mut g = [DVec3::ZERO; MAX_FEET];
        for (gi, foot) in g.iter_mut().zip(&feet) {
            let (t1, t2) = tangent_basis(foot.normal);
            let fn_ = rng.random_range(params.min_normal_force_n..params.max_normal_force_n);
            let lim = foot.friction / 2f64.sqrt() * fn_;
            *gi = foot.normal * fn_
                + t1 * rng.random_range(-lim..lim)
                + t2 * rng.random_range(-lim..lim);
        }
        for t in [1e-4, 1e-2, 1.0] {
            let h: FootForces = std::array::from_fn(|i| f[i] + (g[i] - f[i]) * t);
            assert!(objective(&params, &feet, &w, &h) >= best * (1.0 - 1e-12));
        }
    }
}

/// Flight (no feet, or no loaded foot) gives zero forces; an unloading foot's
/// force shrinks with its load factor and is exactly zero at load 0.
#[test]
fn flight_and_unloading_feet_carry_nothing() {
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let w = Force {
        lin: DVec3::new(10.0, 0.0, 300.0),
        ang: DVec3::new(0.0, 5.0, 0.0),
    };
    assert_eq!(qp.solve(&[], &w).unwrap(), [DVec3::ZERO; MAX_FEET]);
    assert_eq!(
        solve_clarabel(&params, &[], &w).unwrap(),
        [DVec3::ZERO; MAX_FEET]
    );
    let mut feet = quad_feet(DVec3::Z, 0.8);
    for f in &mut feet {
        f.load = 0.0;
    }
    assert_eq!(qp.solve(&feet, &w).unwrap(), [DVec3::ZERO; MAX_FEET]);
    let mut feet = quad_feet(DVec3::Z, 0.8);
    let mut previous = f64::INFINITY;
    for load in [1.0, 0.1, 0.01, 0.001, 0.0] {
        feet[2].load = load;
        let f = qp.solve(&feet, &w).unwrap();
        assert_feasible(&params, &feet, &f, 1e-9);
        let mag = f[2].length();
        // bounded by the load-scaled pyramid: |f| ≤ f_max λ √(1 + μ²)
        assert!(mag <= params.max_normal_force_n * load * (1.0 + 0.64f64).sqrt() + 1e-9);
        assert!(mag <= previous + 1e-9);
        previous = mag;
        if load == 0.0 {
            assert_eq!(f[2], DVec3::ZERO);
            // the other three carry the weight
            assert!((f.iter().map(|x| x.z).sum::<f64>() - w.lin.z).abs() < 1e-3);
        }
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let w = Force {
        lin: DVec3::Z * 100.0,
        ang: DVec3::ZERO,
    };
    let mut feet = quad_feet(DVec3::Z, 0.8);
    feet[1].normal = DVec3::new(0.0, 0.0, 2.0);
    assert!(matches!(
        qp.solve(&feet, &w),
        Err(ForceQpError::Foot {
            index: 1,
            field: "normal",
            ..
        })
    ));
    let mut feet = quad_feet(DVec3::Z, 0.8);
    feet[3].load = 1.5;
    assert!(matches!(
        solve_clarabel(&params, &feet, &w),
        Err(ForceQpError::Foot {
            index: 3,
            field: "load",
            ..
        })
    ));
    feet[3].load = 1.0;
    feet[0].friction = f64::NAN;
    assert!(matches!(
        qp.solve(&feet, &w),
        Err(ForceQpError::Foot {
            index: 0,
            field: "friction",
            ..
        })
    ));
    let mut five = quad_feet(DVec3::Z, 0.8);
    five.push(five[0]);
    assert_eq!(
        qp.solve(&five, &w),
        Err(ForceQpError::TooManyFeet { got: 5 })
    );
    let nan = Force {
        lin: DVec3::new(f64::NAN, 0.0, 0.0),
        ang: DVec3::ZERO,
    };
    assert_eq!(
        qp.solve(&quad_feet(DVec3::Z, 0.8), &nan),
        Err(ForceQpError::Wrench)
    );
    qp.params.max_normal_force_n = 1.0;
    assert!(matches!(
        qp.solve(&quad_feet(DVec3::Z, 0.8), &w),
        Err(ForceQpError::Param {
            field: "max_normal_force_n",
            ..
        })
    ));
}

// ---------------------------------------------------------------- VMC

/// A level, still robot at the target height with its CoM at `com`.
fn still_input(com: DVec3, dt_s: f64) -> VmcInput {
    VmcInput {
        base_position_m: com + DVec3::Z * 0.1,
        base_rotation: DMat3::IDENTITY,
        base_linear_velocity_mps: DVec3::ZERO,
        base_angular_velocity_radps: DVec3::ZERO,
        com_m: com,
        com_velocity_mps: DVec3::ZERO,
        height_above_ground_m: 0.5,
        dt_s,
    }
}

/// A robot stuck at zero speed under `v_des = 1.5 m/s` feels a forward force
/// that grows while the target runs ahead, then stays at `k·0.05 + b·1.5`
/// (700 N) however long it stays stuck: the target is re-anchored and the
/// error clipped. Turned 90° in yaw, the same force points along world y.
#[test]
fn position_error_is_reanchored_and_clipped() {
    let params = VmcParams::study_a(28.0);
    let (k, b) = (params.gains.stiffness_npm.x, params.gains.damping_nspm.x);
    let dt = 0.002;
    let mut vmc = Vmc::new(params, VmcCommand::default());
    let input = still_input(DVec3::new(1.0, 2.0, 0.4), dt);
    let first = vmc.update(&input);
    assert!(
        (first.lin.x - b * 1.5).abs() < 1e-9,
        "no position error at anchoring"
    );
    let mut fx = Vec::new();
    for _ in 0..5000 {
        fx.push(vmc.update(&input).lin.x);
    }
    // before the clip: the target ran ahead by 1.5 m/s · n · dt
    assert!((fx[4] - (k * 1.5 * 5.0 * dt + b * 1.5)).abs() < 1e-9);
    let bound = k * 0.05 + b * 1.5;
    assert!(fx.iter().all(|&f| f <= bound + 1e-9));
    assert!(
        fx[20..].iter().all(|&f| (f - bound).abs() < 1e-9),
        "{}",
        fx[20]
    );
    // a robot that catches up finds the target within 5 cm, not kilometres ahead
    let moved = still_input(DVec3::new(1.0 + 0.05, 2.0, 0.4), dt);
    assert!((vmc.update(&moved).lin.x - (k * 1.5 * dt + b * 1.5)).abs() < 1e-6);
    // heading frame: yawed by 90°, "forward" is world +y
    let mut vmc = Vmc::new(params, VmcCommand::default());
    let mut turned = still_input(DVec3::ZERO, dt);
    turned.base_rotation = DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let mut w = Force::ZERO;
    for _ in 0..100 {
        w = vmc.update(&turned);
    }
    assert!(
        (w.lin.y - bound).abs() < 1e-6 && w.lin.x.abs() < 1e-6,
        "{:?}",
        w.lin
    );
}

/// Study A's gains and targets on a hand-made state, computed by hand in the
/// heading frame (yaw 0.7 rad) and turned to the world.
#[test]
fn gains_and_targets_give_the_expected_wrench() {
    let mut params = VmcParams::study_a(28.0);
    params.payload_mass_kg = 5.0;
    let cmd = VmcCommand {
        forward_mps: 1.0,
        lateral_mps: 0.2,
        yaw_rate_radps: 0.4,
    };
    let mut vmc = Vmc::new(params, cmd);
    let (roll, pitch, yaw) = (0.05, -0.03, 0.7);
    let rz = DMat3::from_rotation_z(yaw);
    let input = VmcInput {
        base_position_m: DVec3::new(3.0, 1.0, 0.48),
        base_rotation: rot_from_rpy(DVec3::new(roll, pitch, yaw)),
        base_linear_velocity_mps: DVec3::new(0.0, 0.0, -0.1),
        base_angular_velocity_radps: rz * DVec3::new(0.2, -0.1, 0.0) + DVec3::Z * 0.3,
        com_m: DVec3::new(3.0, 1.0, 0.4),
        com_velocity_mps: rz * DVec3::new(0.5, 0.1, 0.0),
        height_above_ground_m: 0.48,
        dt_s: 0.002,
    };
    let w = vmc.update(&input);
    let g = 9.81;
    // heading frame, first tick (no position or yaw error yet):
    let f_h = DVec3::new(
        300.0 * (1.0 - 0.5),
        300.0 * (0.2 - 0.1),
        10_000.0 * (0.5 - 0.48) + 500.0 * 0.1 + 33.0 * g,
    );
    let m_h = DVec3::new(
        200.0 * -roll + 50.0 * -0.2,
        200.0 * -pitch + 50.0 * 0.1,
        50.0 * (0.4 - 0.3),
    );
    assert!(
        (w.lin - rz * f_h).length() < 1e-9,
        "{:?} vs {:?}",
        w.lin,
        rz * f_h
    );
    assert!(
        (w.ang - rz * m_h).length() < 1e-9,
        "{:?} vs {:?}",
        w.ang,
        rz * m_h
    );
    // second tick at the same state: the targets moved by v_des·dt and ψ̇_des·dt
    let w2 = vmc.update(&input);
    let df = rz * DVec3::new(5000.0 * 1.0 * 0.002, 5000.0 * 0.2 * 0.002, 0.0);
    assert!((w2.lin - w.lin - df).length() < 1e-9);
    assert!((w2.ang.z - w.ang.z - 200.0 * 0.4 * 0.002).abs() < 1e-9);
    assert!((w2.ang.truncate() - w.ang.truncate()).length() < 1e-12);
    // yaw error wraps: target just below π, measured just above −π
    let mut vmc = Vmc::new(params, VmcCommand::STAND);
    let mut s = still_input(DVec3::ZERO, 0.002);
    s.base_rotation = DMat3::from_rotation_z(std::f64::consts::PI - 0.01);
    vmc.update(&s);
    s.base_rotation = DMat3::from_rotation_z(-std::f64::consts::PI + 0.01);
    let m = vmc.update(&s).ang.z;
    assert!((m - 200.0 * -0.02).abs() < 1e-9, "{m}");
}

// ---------------------------------------------------------------- torques

/// quad16's foot contact points: (body, sphere centre in body, radius).
fn quad16() -> (Model, Vec<ContactPoint>) {
    let desc = robots::builtin("quad16").unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let points = ContactPoint::feet(&model, &desc);
    (model, points)
}

/// Bottom points of the foot spheres on level ground (m, world).
fn foot_points(data: &Data, points: &[ContactPoint]) -> Vec<(usize, DVec3)> {
    points
        .iter()
        .map(|p| {
            (
                p.body,
                data.body_point_world(p.body, p.point_in_body) - DVec3::Z * p.radius_m,
            )
        })
        .collect()
}

/// The sign convention through the dynamics: with the QP's weight-support
/// forces applied as ground forces and `τ = g(q) − Jᵀ f` (gravity of the
/// legs plus [`stance_torques`]), quad16 at its stance does not accelerate;
/// with the opposite sign it does. `stance_torques` equals `−Jᵀ f` formed
/// another way (`add_point_force_jt`), and saturates at the effort limits.
#[test]
fn stance_torques_hold_the_robot_statically() {
    let (model, points) = quad16();
    let mut data = Data::new(&model);
    let q = robots::nominal_q("quad16").unwrap();
    let v = vec![0.0; model.nv];
    forward_kinematics(&model, &mut data, &q, &v);
    let com = center_of_mass(&model, &data);
    let pts = foot_points(&data, &points);
    let feet: Vec<StanceFoot> = pts
        .iter()
        .map(|&(_, p)| StanceFoot {
            position_m: p - com,
            normal: DVec3::Z,
            friction: 0.8,
            load: 1.0,
        })
        .collect();
    let w = Force {
        lin: DVec3::Z * model.total_mass * 9.81,
        ang: DVec3::ZERO,
    };
    // α = 1e-9: the default's 1e-6 leaves a 2.5e-7 relative wrench residual
    // that shows as 6e-5 rad/s² on the light feet
    let f = ForceQp::new(ForceQpParams {
        regularization: 1e-9,
        ..ForceQpParams::default()
    })
    .solve(&feet, &w)
    .unwrap();
    let nj = model.nv - 6;
    let mut tau_j = vec![0.0; nj];
    stance_torques(&model, &mut data, &pts, &f, &mut tau_j);
    // the same −Jᵀ f without forming J
    let mut jtf = vec![0.0; model.nv];
    for (&(body, p), fi) in pts.iter().zip(&f) {
        add_point_force_jt(&model, &data, body, p, -*fi, &mut jtf);
    }
    for j in 0..nj {
        assert!((tau_j[j] - jtf[6 + j]).abs() < 1e-10);
    }
    // bit for bit the dense −Jᵀ f over every joint column of `point_jacobian`
    let nv = model.nv;
    let mut dense = vec![0.0; nj];
    for (&(body, p), fi) in pts.iter().zip(&f) {
        let jac = point_jacobian(&model, &mut data, body, p);
        for c in 6..nv {
            dense[c - 6] -= jac[c] * fi.x + jac[nv + c] * fi.y + jac[2 * nv + c] * fi.z;
        }
    }
    for (d, lim) in dense.iter_mut().zip(&model.effort_limit[6..]) {
        *d = d.clamp(-lim, *lim);
    }
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&tau_j), bits(&dense));
    let grav = generalized_gravity(&model, &mut data, &q).to_vec();
    let mut residual = |sign: f64| {
        forward_kinematics(&model, &mut data, &q, &v);
        data.clear_external_forces();
        for (&(body, p), fi) in pts.iter().zip(&f) {
            data.add_point_force(body, p, *fi);
        }
        let mut tau = vec![0.0; model.nv];
        for j in 0..nj {
            tau[6 + j] = grav[6 + j] + sign * tau_j[j];
        }
        aba_from_kinematics(&model, &mut data, &v, &tau, true);
        data.ddq.iter().fold(0.0f64, |m, a| m.max(a.abs()))
    };
    let held = residual(1.0);
    assert!(held < 1e-6, "residual acceleration {held:e}");
    assert!(
        residual(-1.0) > 1.0,
        "the opposite sign must not hold the robot"
    );
    // saturation at the effort limit
    let big = [DVec3::Z * 1e5; 4];
    stance_torques(&model, &mut data, &pts, &big, &mut tau_j);
    let lim = model.effort_limit[6];
    assert!(tau_j.iter().all(|t| t.abs() <= lim) && tau_j.iter().any(|t| t.abs() == lim));
}

// ---------------------------------------------------------------- standing

/// Per-leg angles `[0, a, −2a, a]` (level foot, knee bent) that put quad16's
/// base `height_m` above its feet' contact points, by bisection on `a`.
fn crouch_for_height(height_m: f64) -> Vec<f64> {
    let desc = robots::builtin("quad16").unwrap();
    let h = |a: f64| robots::stance_base_height_m(&desc, &[0.0, a, -2.0 * a, a].repeat(4)).unwrap();
    let (mut lo, mut hi) = (0.0, 1.2);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if h(mid) > height_m {
            lo = mid
        } else {
            hi = mid
        }
    }
    [0.0, lo, -2.0 * lo, lo].repeat(4)
}

/// "A standing robot on four feet holds its height": quad16 on flat concrete
/// under VMC (`v_des = 0`, target 0.5 m) at 500 Hz, the QP's forces mapped by
/// `τ = −Jᵀ f` plus the legs' joint gravity torques `g(q)` (see
/// [`stance_torques`]), and a small ankle PD toward a level foot (the ankle is
/// each leg's redundant DOF), integrated at 0.5 ms for 3 s from a crouch
/// 2 cm low. The torso rises to 0.5 m and holds it within a few mm (from
/// 1 s on), stays level, and no foot lifts or slides.
#[test]
fn standing_robot_on_four_feet_holds_its_height() {
    let (model, points) = quad16();
    let mut data = Data::new(&model);
    let mut ws = StepWorkspace::new(&model);
    let terrain = TerrainUnion::flat(0.0, GroundPreset::Concrete.material());
    let mu = GroundPreset::Concrete.material().friction;
    // start 2 cm low: VMC must lift the torso to its target, not just stay put
    let mut q = vec![0.0, 0.0, 0.48, 0.0, 0.0, 0.0, 1.0];
    q.extend(crouch_for_height(0.48));
    let mut state = State::from_parts(&model, q, vec![0.0; model.nv]).unwrap();
    let mut contacts = vec![ContactState::default(); points.len()];
    forward_kinematics(&model, &mut data, &state.q, &state.v);
    update_after_step(&points, &data, &terrain, &mut contacts);

    let com_start = center_of_mass(&model, &data);
    let mut vmc = Vmc::new(VmcParams::for_model(&model), VmcCommand::STAND);
    let mut qp = ForceQp::default();
    let nj = model.nv - 6;
    let (mut tau, mut tau_j) = (vec![0.0; model.nv], vec![0.0; nj]);
    let (dt, substeps) = (0.0005, 4);
    let (mut worst_h, mut worst_tilt) = (0.0f64, 0.0f64);
    for i in 0..6000 {
        if i % substeps == 0 {
            let grav = generalized_gravity(&model, &mut data, &state.q);
            tau[6..].copy_from_slice(&grav[6..]);
            forward_kinematics(&model, &mut data, &state.q, &state.v);
            let rot = DMat3::from_quat(DQuat::from_slice(&state.q[3..7]));
            let com = center_of_mass(&model, &data);
            let input = VmcInput {
                base_position_m: DVec3::from_slice(&state.q[0..3]),
                base_rotation: rot,
                base_linear_velocity_mps: rot * DVec3::from_slice(&state.v[0..3]),
                base_angular_velocity_radps: rot * DVec3::from_slice(&state.v[3..6]),
                com_m: com,
                com_velocity_mps: com_velocity(&model, &data),
                height_above_ground_m: state.q[2],
                dt_s: dt * substeps as f64,
            };
            let w = vmc.update(&input);
            let pts = foot_points(&data, &points);
            let feet: Vec<StanceFoot> = pts
                .iter()
                .map(|&(_, p)| StanceFoot {
                    position_m: p - com,
                    normal: DVec3::Z,
                    friction: mu,
                    load: 1.0,
                })
                .collect();
            let f = qp.solve(&feet, &w).unwrap();
            stance_torques(&model, &mut data, &pts, &f, &mut tau_j);
            for leg in 0..4 {
                // ankle PD toward a level foot: ankle = −(hip pitch + knee)
                let (qi, vi) = (7 + 4 * leg, 6 + 4 * leg);
                let target = -(state.q[qi + 1] + state.q[qi + 2]);
                tau_j[4 * leg + 3] += 10.0 * (target - state.q[qi + 3]) - 0.1 * state.v[vi + 3];
            }
            for (t, tj) in tau[6..].iter_mut().zip(&tau_j) {
                *t += tj;
            }
        }
        let mut forces = ContactForces {
            terrain: &terrain,
            points: &points,
            states: &contacts,
        };
        step(
            &model,
            &mut data,
            &mut ws,
            &mut state,
            &tau,
            dt,
            Integrator::SemiImplicitEuler,
            &mut forces,
        );
        forward_kinematics(&model, &mut data, &state.q, &state.v);
        update_after_step(&points, &data, &terrain, &mut contacts);
        let rpy = rpy_from_rot(DMat3::from_quat(DQuat::from_slice(&state.q[3..7])));
        worst_tilt = worst_tilt.max(rpy.x.abs()).max(rpy.y.abs());
        if i as f64 * dt >= 1.0 {
            worst_h = worst_h.max((state.q[2] - 0.5).abs());
        }
        for c in &contacts {
            assert!(
                c.in_contact && !c.slipping,
                "a foot lifted or slid at step {i}"
            );
        }
    }
    forward_kinematics(&model, &mut data, &state.q, &state.v);
    let drift = (center_of_mass(&model, &data) - com_start)
        .truncate()
        .length();
    println!("height error {worst_h:.2e} m, tilt {worst_tilt:.2e} rad, CoM drift {drift:.2e} m");
    assert!(worst_h < 0.003, "height error {worst_h} m");
    assert!(worst_tilt < 0.02, "tilt {worst_tilt} rad");
    // v_des = 0 holds the CoM over its starting point
    assert!(drift < 0.003, "the CoM drifted {drift} m");
}

/// One controller tick (VMC update, the active-set QP on four and on two
/// feet, `τ = −Jᵀ f`) allocates nothing once its buffers exist; the counting
/// allocator sees the allocations clarabel makes, so the test can fail.
#[test]
fn controller_tick_allocates_nothing() {
    let (model, points) = quad16();
    let mut data = Data::new(&model);
    let q = robots::nominal_q("quad16").unwrap();
    let v = vec![0.0; model.nv];
    forward_kinematics(&model, &mut data, &q, &v);
    let com = center_of_mass(&model, &data);
    let pts: [(usize, DVec3); 4] = std::array::from_fn(|i| {
        let p = &points[i];
        (
            p.body,
            data.body_point_world(p.body, p.point_in_body) - DVec3::Z * p.radius_m,
        )
    });
    let mut feet: [StanceFoot; 4] = std::array::from_fn(|i| StanceFoot {
        position_m: pts[i].1 - com,
        normal: DVec3::Z,
        friction: 0.8,
        load: 1.0,
    });
    let mut vmc = Vmc::new(VmcParams::for_model(&model), VmcCommand::default());
    let mut qp = ForceQp::default();
    let mut tau_j = vec![0.0; model.nv - 6];
    let input = still_input(com, 0.002);
    let mut tick = |feet: &[StanceFoot]| {
        let w = vmc.update(&input);
        let f = qp.solve(feet, &w).unwrap();
        stance_torques(&model, &mut data, &pts, &f, &mut tau_j);
    };
    tick(&feet);
    assert_eq!(allocations_in(|| tick(&feet)), 0);
    feet[1].load = 0.0;
    feet[3].load = 0.0;
    assert_eq!(allocations_in(|| tick(&feet)), 0);
    let w = Force {
        lin: DVec3::Z * 200.0,
        ang: DVec3::ZERO,
    };
    let n = allocations_in(|| {
        solve_clarabel(&ForceQpParams::default(), &feet, &w).unwrap();
    });
    assert!(n > 0, "the counter must see clarabel's allocations");
}
