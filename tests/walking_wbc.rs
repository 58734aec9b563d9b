//! The default walker (whole-body layer, quadsim's long-swing trot) through
//! the whole pipeline, on the sensed state (estimator, encoders, contact
//! sensors) and quad16's default DC motors, from perturbed neighbours of one
//! start: each case moves the start (±3 cm in x and y, ±3° of yaw), scales
//! the torso's, thighs' and shanks' masses by 0.9–1.1 (known to the
//! controller: the model is built from them) and draws its own sensor-noise
//! seed. Every neighbour must hold: no fall, the mean forward speed over
//! [3 s, 8 s] within 5 % of the command, roll and pitch inside ±0.15 rad over
//! the whole run (the command's ramp from rest included). The same holds
//! for the convex-MPC planner (`planner = "mpc"`), at 1.0 and 1.25 m/s,
//! for the default walker's walk, pace, bound and pronk at 0.5 m/s, and for the
//! default walker carrying a 10 kg box unknown to it and a 15 kg box it knows.

use std::path::Path;

use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, build_world};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Neighbours per speed.
const NEIGHBOURS: u64 = 12;

/// One neighbour's scenario: `v_mps` commanded, perturbations drawn from `case`.
fn scenario(v_mps: f64, case: u64, controller: &str) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0000 + case);
    let mut u = |a: f64| rng.random_range(-a..=a);
    let (x, y, yaw) = (u(0.03), u(0.03), u(3.0));
    let (mt, mth, msh) = (1.0 + u(0.1), 1.0 + u(0.1), 1.0 + u(0.1));
    format!(
        r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 8.0
seed = {seed}
controller_rate_hz = 500
default_ground = "concrete"

[[robots]]
name = "rex"
model = "quad16"
start_xy_m = [{x}, {y}]
start_yaw_deg = {yaw}
contact_points = ["knees", "torso"]
[robots.params]
"torso.mass_kg" = {torso}
"thigh.mass_kg" = {thigh}
"shank.mass_kg" = {shank}
[robots.controller]
kind = "vmc"
v_x_mps = {v_mps}
{controller}
"#,
        seed = case + 1,
        torso = 10.0 * mt,
        thigh = 2.5 * mth,
        shank = 1.5 * msh,
    )
}

/// Runs one neighbour; returns (fell at, mean speed along the start heading
/// over [3, 8] s, worst |roll| or |pitch|).
fn run(v_mps: f64, case: u64, controller: &str) -> (Option<f64>, f64, f64) {
    let src = scenario(v_mps, case, controller);
    let scn = parse_scenario(Path::new("walking_wbc.toml"), src).unwrap();
    let mut w = build_world(&scn, Overrides::with_threads(1)).unwrap();
    let id = w.robots[0].1;
    let steps_3s = (3.0 / 0.0005) as u64;
    w.sim.run(steps_3s);
    let q3 = w.sim.robot(id).unwrap().state.q[..2].to_vec();
    w.sim.run(w.steps - steps_3s);
    let r = w.sim.robot(id).unwrap();
    let q8 = &r.state.q[..2];
    let m = r.run.metrics.summary();
    let yaw0 = scn.file.robots[0].start_yaw_deg.to_radians();
    let along = (q8[0] - q3[0]) * yaw0.cos() + (q8[1] - q3[1]) * yaw0.sin();
    let tilt = [m.roll_range_rad, m.pitch_range_rad]
        .iter()
        .flat_map(|r| [r[0].abs(), r[1].abs()])
        .fold(0.0, f64::max);
    (m.fell_at_s.filter(|_| m.fell), along / 5.0, tilt)
}

/// `controller`: extra `[robots.controller]` keys.
fn all_neighbours_hold(v_mps: f64, controller: &str) {
    let mut bad = Vec::new();
    for case in 0..NEIGHBOURS {
        let (fell, speed, tilt) = run(v_mps, case, controller);
        let ok = fell.is_none() && (speed - v_mps).abs() <= 0.05 * v_mps && tilt < 0.15;
        if !ok {
            bad.push((case, fell, speed, tilt));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {NEIGHBOURS} neighbours failed at {v_mps} m/s with {controller:?} (case, fell at, speed, tilt): {bad:?}",
        bad.len()
    );
}

#[test]
fn default_walker_trots_half_a_metre_per_second_from_every_neighbour() {
    all_neighbours_hold(0.5, "");
}

#[test]
fn default_walker_trots_one_metre_per_second_from_every_neighbour() {
    all_neighbours_hold(1.0, "");
}

#[test]
fn mpc_planner_trots_one_metre_per_second_from_every_neighbour() {
    all_neighbours_hold(1.0, "planner = \"mpc\"");
}

#[test]
fn mpc_planner_trots_one_and_a_quarter_metres_per_second_from_every_neighbour() {
    all_neighbours_hold(1.25, "planner = \"mpc\"");
}

#[test]
fn default_walker_walks_paces_bounds_and_pronks_half_a_metre_per_second_from_every_neighbour() {
    for gait in ["walk", "pace", "bound", "pronk"] {
        all_neighbours_hold(0.5, &format!("gait = \"{gait}\""));
    }
}

/// A box on the torso (0.3 × 0.2 × 0.1 m, 10 cm above the base origin).
fn payload(mass_kg: f64, known: bool) -> String {
    format!(
        "\n[[robots.payloads]]\nname = \"box\"\nmass_kg = {mass_kg}\nsize_m = [0.3, 0.2, 0.1]\noffset_m = [0.0, 0.0, 0.1]\nknown_to_controller = {known}\n"
    )
}

#[test]
fn default_walker_carries_payloads_at_one_metre_per_second_from_every_neighbour() {
    // issue 27's payload target is 0–15 kg known and unknown; 15 kg unknown
    // to the controller does not hold yet (docs/validation.md)
    for (mass_kg, known) in [(10.0, false), (15.0, true)] {
        all_neighbours_hold(1.0, &payload(mass_kg, known));
    }
}
