//! quad12 under Study A's walking controller (VMC) with its own defaults
//! ([`WalkerParams::default_for`]): gains scaled to its mass, height target
//! and lift scaled to its size, Raibert's hips at its stance feet. Flat
//! concrete, semi-implicit Euler at 0.5 ms, the controller at 500 Hz, 10 s.
//!
//! ASSUMPTION: the effort limit is raised from quad12's default 3 N·m to
//! 8 N·m. In two-foot support a stance hip pitch needs 3.85 N·m just to hold
//! the body; at 3–5 N·m quad12 sinks and falls (see `default_for`'s docs).
//! Measured (this harness): in place, 0.05 and 0.1 m/s hold at 6, 8 and
//! 10 N·m (tilt ≤ 0.08 rad); 0.15 m/s only at 10 N·m; 0.2 m/s falls.

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

/// What a run did: lowest base height (m), largest roll or pitch (rad),
/// mean forward speed over [3, 10] s (m/s), the height target (m).
fn run(effort_nm: f64, forward_mps: f64) -> (f64, f64, f64, f64) {
    let desc = robots::builtin_with("quad12", &[("actuator.effort_limit_nm", effort_nm)]).unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let mut data = Data::new(&model);
    let mut params = WalkerParams::default_for(&desc, &model);
    params.command = VmcCommand {
        forward_mps,
        lateral_mps: 0.0,
        yaw_rate_radps: 0.0,
    };
    let target = params.vmc.base_height_m;
    let mut walker = Walker::new(&desc, &model, params).unwrap();
    let terrain = TerrainUnion::flat(0.0, GroundMaterial::preset("concrete").unwrap());
    let points = ContactPoint::feet(&model, &desc);
    let mut states = vec![ContactState::default(); points.len()];
    let mut st = State {
        q: robots::nominal_q("quad12").unwrap(),
        v: vec![0.0; model.nv],
    };
    let mut ws = StepWorkspace::new(&model);
    let mut tau = vec![0.0; model.nv];
    let mut tj = vec![0.0; model.nv - 6];
    let dt_s = 0.0005;
    let (mut min_h, mut max_tilt, mut x3) = (f64::INFINITY, 0.0_f64, 0.0);
    for k in 0..20_000 {
        forward_kinematics(&model, &mut data, &st.q, &st.v);
        update_after_step(&points, &data, &terrain, &mut states);
        if k % 4 == 0 {
            let contacts: Vec<bool> = states.iter().map(|s| s.in_contact).collect();
            let normals: Vec<DVec3> = states.iter().map(|s| s.normal).collect();
            let input = WalkerInput {
                dt_s: 4.0 * dt_s,
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
        step(
            &model,
            &mut data,
            &mut ws,
            &mut st,
            &tau,
            dt_s,
            Integrator::SemiImplicitEuler,
            &mut f,
        );
        let rpy = rpy_from_rot(data.pose[0].rot);
        min_h = min_h.min(st.q[2]);
        max_tilt = max_tilt.max(rpy.x.abs()).max(rpy.y.abs());
        if k + 1 == 6000 {
            x3 = st.q[0];
        }
        if !st.q[2].is_finite() {
            return (f64::NEG_INFINITY, max_tilt, 0.0, target);
        }
    }
    (min_h, max_tilt, (st.q[0] - x3) / 7.0, target)
}

/// quad12 trots at 0.1 m/s (Study B's walking speed) for 10 s: the base
/// stays above 80 % of its height target, roll and pitch within 0.15 rad,
/// mean speed over [3, 10] s within 0.02 m/s of the command.
#[test]
fn quad12_trots_at_a_tenth_of_a_metre_per_second() {
    let (min_h, tilt, speed, target) = run(8.0, 0.1);
    assert!(min_h > 0.8 * target, "base fell to {min_h} m");
    assert!(tilt < 0.15, "tilt reached {tilt} rad");
    assert!((speed - 0.1).abs() < 0.02, "mean speed {speed} m/s");
}

/// quad12 trots in place for 10 s: the half-turn symmetry of its legs keeps
/// it level (roll and pitch below 0.01 rad) and it stays within 0.02 m of
/// its start.
#[test]
fn quad12_trots_in_place() {
    let (min_h, tilt, speed, target) = run(8.0, 0.0);
    assert!(min_h > 0.8 * target, "base fell to {min_h} m");
    assert!(tilt < 0.01, "tilt reached {tilt} rad");
    assert!(speed.abs() < 0.02 / 7.0, "drift speed {speed} m/s");
}

/// Not reached at quad12's default 3 N·m limit: the stance hip pitch needs
/// 3.85 N·m in two-foot support and the robot sinks and falls.
#[test]
#[ignore = "not reached: at the default 3 N·m effort limit quad12 sinks and falls within ~4 s"]
fn quad12_trots_at_its_default_effort_limit() {
    let (min_h, tilt, _, target) = run(3.0, 0.1);
    assert!(min_h > 0.8 * target, "base fell to {min_h} m");
    assert!(tilt < 0.15, "tilt reached {tilt} rad");
}
