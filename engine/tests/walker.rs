//! Closed-loop checks of the walking controller ([`Walker`]) on flat concrete:
//! the full simulation (contacts, semi-implicit Euler at 0.5 ms), the
//! controller at 500 Hz with [`WalkerParams::default_for`].

use glam::DVec3;
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundMaterial, update_after_step,
};
use quadsim_engine::control::vmc::VmcCommand;
use quadsim_engine::control::walker::{ROUND_OFF_ROBUST, Walker, WalkerInput, WalkerParams};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::spatial::rpy_from_rot;
use quadsim_engine::terrain::TerrainUnion;
use quadsim_engine::{Data, robots};

/// What a run did.
struct Run {
    /// Lowest base height over the run (m).
    min_height_m: f64,
    /// Largest roll or pitch magnitude over the run (rad).
    max_tilt_rad: f64,
    /// Mean forward speed over [3 s, end] (m/s).
    mean_speed_mps: f64,
    /// Base x, y drift at the end (m).
    drift_m: f64,
}

fn run(name: &str, forward_mps: f64, duration_s: f64) -> Run {
    run_from(name, forward_mps, duration_s, |_| {}, |_| {})
}

/// [`run`] with the parameters changed by `tune` and the nominal stance by
/// `perturb`.
fn run_from(
    name: &str,
    forward_mps: f64,
    duration_s: f64,
    tune: impl Fn(&mut WalkerParams),
    perturb: impl Fn(&mut State),
) -> Run {
    let desc = robots::builtin(name).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let mut data = Data::new(&model);
    let mut params = WalkerParams::default_for(&desc, &model);
    tune(&mut params);
    params.command = VmcCommand {
        forward_mps,
        lateral_mps: 0.0,
        yaw_rate_radps: 0.0,
    };
    let mut walker = Walker::new(&desc, &model, params).unwrap();
    let terrain = TerrainUnion::flat(0.0, GroundMaterial::preset("concrete").unwrap());
    let points = ContactPoint::feet(&model, &desc);
    let mut states = vec![ContactState::default(); points.len()];
    let mut st = State {
        q: robots::nominal_q(name).unwrap(),
        v: vec![0.0; model.nv],
    };
    perturb(&mut st);
    let mut ws = StepWorkspace::new(&model);
    let mut tau = vec![0.0; model.nv];
    let mut tj = vec![0.0; model.nv - 6];
    let dt_s = 0.0005;
    let every = 4;
    let steps = (duration_s / dt_s).round() as usize;
    let (mut min_h, mut max_tilt) = (f64::INFINITY, 0.0_f64);
    let mut x3 = None;
    for k in 0..steps {
        forward_kinematics(&model, &mut data, &st.q, &st.v);
        update_after_step(&points, &data, &terrain, &mut states);
        if k % every == 0 {
            let contacts: Vec<bool> = states.iter().map(|s| s.in_contact).collect();
            let normals: Vec<DVec3> = states.iter().map(|s| s.normal).collect();
            let input = WalkerInput {
                dt_s: every as f64 * dt_s,
                terrain: &terrain,
                contacts: &contacts,
                normals: &normals,
            };
            walker.tick(&model, &mut data, &st.q, &st.v, &input, &mut tj);
            tau[6..].copy_from_slice(&tj);
        }
        let mut f = ContactForces {
            terrain: &terrain,
            points: &points,
            states: &states,
        };
        let integ = Integrator::SemiImplicitEuler;
        step(
            &model, &mut data, &mut ws, &mut st, &tau, dt_s, integ, &mut f,
        );
        let rpy = rpy_from_rot(data.pose[0].rot);
        min_h = min_h.min(st.q[2]);
        max_tilt = max_tilt.max(rpy.x.abs()).max(rpy.y.abs());
        if k + 1 == (3.0 / dt_s) as usize {
            x3 = Some(st.q[0]);
        }
        if !st.q[2].is_finite() {
            min_h = f64::NEG_INFINITY;
            break;
        }
    }
    let t_avg = duration_s - 3.0;
    Run {
        min_height_m: min_h,
        max_tilt_rad: max_tilt,
        mean_speed_mps: x3.map_or(0.0, |x| (st.q[0] - x) / t_avg),
        drift_m: st.q[0].hypot(st.q[1]),
    }
}

/// quad16 trots in place (Study A's timing: period 0.5 s, supports 0.1 /
/// 0.15 s) for 10 s: the base stays above 80 % of its 0.5 m target, level
/// within 0.1 rad, and within 0.1 m of where it started.
#[test]
fn quad16_trots_in_place_for_10_s() {
    let r = run("quad16", 0.0, 10.0);
    assert!(r.min_height_m > 0.4, "base fell to {} m", r.min_height_m);
    assert!(r.max_tilt_rad < 0.1, "tilt reached {} rad", r.max_tilt_rad);
    assert!(r.drift_m < 0.1, "drifted {} m", r.drift_m);
}

/// quad16 trots at 0.5 m/s commanded for 10 s: upright (tilt < 0.15 rad),
/// above 80 % of its height target, and the mean speed over [3, 10] s within
/// 0.05 m/s of the command.
#[test]
fn quad16_trots_at_half_a_metre_per_second() {
    let r = run("quad16", 0.5, 10.0);
    assert!(r.min_height_m > 0.4, "base fell to {} m", r.min_height_m);
    assert!(r.max_tilt_rad < 0.15, "tilt reached {} rad", r.max_tilt_rad);
    assert!(
        (r.mean_speed_mps - 0.5).abs() < 0.05,
        "mean speed {} m/s",
        r.mean_speed_mps
    );
}

/// quad16 trots at 0.75 m/s commanded for 10 s: upright (tilt < 0.3 rad),
/// above 80 % of its height target, mean speed over [3, 10] s within 0.05
/// m/s of the command.
#[test]
fn quad16_trots_at_three_quarters_of_a_metre_per_second() {
    check_three_quarters(&run("quad16", 0.75, 10.0), "nominal start");
}

/// The 0.75 m/s trot's bounds: above 80 % of the height target, tilt < 0.3
/// rad, mean speed over [3, 10] s within 0.05 m/s of the command.
fn check_three_quarters(r: &Run, start: &str) {
    assert!(
        r.min_height_m > 0.4,
        "{start}: base fell to {} m",
        r.min_height_m
    );
    assert!(
        r.max_tilt_rad < 0.3,
        "{start}: tilt reached {} rad",
        r.max_tilt_rad
    );
    assert!(
        (r.mean_speed_mps - 0.75).abs() < 0.05,
        "{start}: mean speed {} m/s",
        r.mean_speed_mps
    );
}

/// Runs the 0.75 m/s trot with the parameters changed by `tune` from 8
/// starts whose base is moved by up to 1e-9 m along each axis and turned by
/// 1e-9 rad about a random axis (seeded), and checks each run against the
/// 0.75 m/s test's bounds. Such perturbations are what a faithful numeric
/// change (a QP solver, libm's sin/cos) makes within a few ticks.
fn three_quarters_from_perturbed_starts(tune: impl Fn(&mut WalkerParams)) {
    use glam::DQuat;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for start in 0..8 {
        let dp = DVec3::new(
            rng.random_range(-1e-9..1e-9),
            rng.random_range(-1e-9..1e-9),
            rng.random_range(-1e-9..1e-9),
        );
        let axis = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let r = run_from("quad16", 0.75, 10.0, &tune, |st| {
            for k in 0..3 {
                st.q[k] += dp[k];
            }
            // q[3..7] = base quaternion (x, y, z, w), turned in the world
            let q0 = DQuat::from_xyzw(st.q[3], st.q[4], st.q[5], st.q[6]);
            let q1 = (DQuat::from_axis_angle(axis, 1e-9) * q0).normalize();
            st.q[3..7].copy_from_slice(&q1.to_array());
        });
        check_three_quarters(&r, &format!("start {start}"));
    }
}

/// With the stance foot press and the friction reserve
/// ([`ROUND_OFF_ROBUST`]) the 0.75 m/s trot does not hang on the last bits
/// of its start: all 8 perturbed starts hold (see
/// [`three_quarters_from_perturbed_starts`]).
#[test]
fn quad16_trot_at_three_quarters_with_foot_press_survives_round_off_sized_perturbations() {
    three_quarters_from_perturbed_starts(|p| {
        (p.stance_foot_press, p.friction_fraction) = ROUND_OFF_ROBUST;
    });
}

/// The default trot at 0.75 m/s is not robust to round-off: its nominal start
/// holds, but 11 of 41 starts perturbed by ±1e-9 in one coordinate fall,
/// and 18 (glibc's sin/cos) or 23 (libm's, the default since 2026-11-26)
/// of another 41 moved by up to 7e-9 m (`docs/walking.md`, "Round-off
/// sensitivity"). See `WalkerParams::stance_foot_press` for the diagnosis
/// and why the fix is not the default.
#[test]
#[ignore = "not reached: the default 0.75 m/s trot falls from a quarter to a half of perturbed starts"]
fn quad16_trot_at_three_quarters_survives_round_off_sized_perturbations() {
    three_quarters_from_perturbed_starts(|_| {});
}

/// Study A's target, not reached yet: quad16 falls within about 2–4 s at a
/// 1.5 m/s command (see `WalkerParams::default_for`), here on ideal torque
/// sources with the default position clip and Raibert gain. Through the
/// pipeline, `scenarios/trot_flat.toml` (DC motors, 5 mm clip, k = 0.05 s)
/// holds that command for 10 s at about 1.2 m/s (`tests/trot.rs`).
#[test]
#[ignore = "not reached: quad16 falls within ~2-4 s at 1.5 m/s"]
fn quad16_trots_at_study_a_speed() {
    let r = run("quad16", 1.5, 10.0);
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    assert!(
        r.min_height_m > 0.5 * nominal,
        "base fell to {} m",
        r.min_height_m
    );
    assert!(
        r.max_tilt_rad < 60f64.to_radians(),
        "tilt {} rad",
        r.max_tilt_rad
    );
    assert!(
        r.mean_speed_mps >= 1.0,
        "mean speed {} m/s",
        r.mean_speed_mps
    );
}
