//! Closed-loop checks of the walking controller ([`Walker`]) on flat concrete:
//! the full simulation (contacts, semi-implicit Euler at 0.5 ms), the
//! controller at 500 Hz with [`WalkerParams::default_for`].

use glam::DVec3;
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundMaterial, update_after_step,
};
use quadsim_engine::control::vmc::VmcCommand;
use quadsim_engine::control::walker::{Walker, WalkerInput, WalkerParams};
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
    let desc = robots::builtin(name).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let mut data = Data::new(&model);
    let mut params = WalkerParams::default_for(&desc, &model);
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
    let r = run("quad16", 0.75, 10.0);
    assert!(r.min_height_m > 0.4, "base fell to {} m", r.min_height_m);
    assert!(r.max_tilt_rad < 0.3, "tilt reached {} rad", r.max_tilt_rad);
    assert!(
        (r.mean_speed_mps - 0.75).abs() < 0.05,
        "mean speed {} m/s",
        r.mean_speed_mps
    );
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
