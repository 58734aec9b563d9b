//! Compliant (sloshing) payloads through the scenario pipeline: quad16
//! trotting at 0.5 m/s with a 4 kg load on springs in the torso's plane
//! walks 10 s, the load sloshes, and the robot moves differently from the
//! same 4 kg bolted down; `attach`/`detach` events add and remove the load's
//! coordinates between steps with the robot's own state carried exactly;
//! bad compliant-payload input names its key.

use std::path::Path;

use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, World, build_world};
use quadsim_components::Controller;

/// `scenarios/trot_slosh.toml`, with its duration replaced.
fn trot_slosh(duration_s: f64) -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/trot_slosh.toml"
    ))
    .unwrap()
    .replace("duration_s = 10.0", &format!("duration_s = {duration_s}"))
}

/// The same load bolted down.
fn rigid(src: &str) -> String {
    src.lines()
        .filter(|l| {
            !["dofs", "stiffness_npm", "damping_nspm"]
                .iter()
                .any(|k| l.starts_with(k))
        })
        .map(|l| l.replace("kind = \"compliant\"", "kind = \"rigid\""))
        .collect::<Vec<_>>()
        .join("\n")
}

fn world(src: &str) -> World {
    let scn = parse_scenario(Path::new("trot_slosh.toml"), src.to_string()).unwrap();
    build_world(&scn, Overrides::with_threads(1)).unwrap()
}

/// What a 10 s trot did: the metrics summary, and the load's largest
/// excursion from its rest offset in the torso's plane (m; 0 when rigid).
fn trot(src: &str) -> (quadsim_engine::metrics::MetricsSummary, f64) {
    let mut w = world(src);
    let rex = w.robots[0].1;
    let mut peak: f64 = 0.0;
    for _ in 0..w.steps {
        w.sim.run(1);
        let r = w.sim.robot(rex).unwrap();
        let n = r.model.actuated_nq();
        let tail = &r.state.q[n..];
        peak = peak.max(tail.iter().map(|x| x * x).sum::<f64>().sqrt());
    }
    (w.sim.robot(rex).unwrap().run.metrics.summary(), peak)
}

/// quad16 at 0.5 m/s carrying 4 kg on x–y springs tuned to 2 Hz (ζ = 0.1)
/// keeps walking for 10 s at ≥ 0.4 m/s; the load sloshes (more than 5 mm
/// from rest, less than 10 cm), and the whole-body CoM's lateral oscillation
/// differs by more than 10 % from the same 4 kg bolted down (the load is
/// part of the CoM and moves against the torso's sway).
#[test]
fn a_trotting_quad16_carries_a_sloshing_load() {
    let src = trot_slosh(10.0);
    let (slosh, excursion) = trot(&src);
    let (bolted, none) = trot(&rigid(&src));
    eprintln!(
        "sloshing: fell {}, {:.3} m/s, CoM oscillation {:?} m, pitch {:?} rad, load excursion \
         {excursion:.4} m\nrigid: fell {}, {:.3} m/s, CoM oscillation {:?} m, pitch {:?} rad",
        slosh.fell,
        slosh.mean_forward_speed_mps,
        slosh.com_oscillation_m,
        slosh.pitch_range_rad,
        bolted.fell,
        bolted.mean_forward_speed_mps,
        bolted.com_oscillation_m,
        bolted.pitch_range_rad
    );
    assert_eq!(none, 0.0);
    assert!(!slosh.fell, "fell at {:?}", slosh.fell_at_s);
    assert!(slosh.mean_forward_speed_mps >= 0.4, "{slosh:?}");
    assert!(
        (0.005..0.1).contains(&excursion),
        "load excursion {excursion} m"
    );
    let (a, b) = (slosh.com_oscillation_m[1], bolted.com_oscillation_m[1]);
    assert!(
        (a - b).abs() > 0.1 * b,
        "lateral CoM oscillation {a} m vs {b} m rigid"
    );
}

/// A compliant load attached at 0.25 s and detached at 0.5 s: each event
/// is applied before the step that starts at its time; the model gains and
/// loses the load's two coordinates; the robot's own state is carried
/// exactly, the load starting at rest at its offset; total mass and the
/// controller's known payload follow; the controller and metrics go on.
#[test]
fn compliant_attach_and_detach_events_carry_the_state() {
    let src = trot_slosh(0.75).replace(
        "damping_nspm = 10.05",
        "damping_nspm = 10.05\nattached = false",
    ) + "\n[[events]]\nt_s = 0.25\nrobot = \"rex\"\nkind = \"attach\"\npayload = \"tank\"\n\
         \n[[events]]\nt_s = 0.5\nrobot = \"rex\"\nkind = \"detach\"\npayload = \"tank\"\n";
    let mut w = world(&src);
    let rex = w.robots[0].1;
    let look = |w: &World| {
        let r = w.sim.robot(rex).unwrap();
        let Controller::Walker(c) = &r.run.controller else {
            panic!("vmc")
        };
        (
            r.model.nv,
            r.model.total_mass,
            c.payload_mass_kg(),
            r.state.clone(),
            r.run.metrics.summary().steps,
        )
    };
    let (nv0, m0, c0, _, _) = look(&w);
    assert_eq!(nv0, 22);
    w.sim.run(500); // t = 0.25 s, the event due before the next step
    let (_, _, _, before, _) = look(&w);
    w.sim.compile();
    let (nv1, m1, c1, after, steps1) = look(&w);
    assert_eq!(nv1, 24);
    assert_eq!(&after.q[..before.q.len()], &before.q[..]);
    assert_eq!(&after.v[..before.v.len()], &before.v[..]);
    assert_eq!(&after.q[before.q.len()..], &[0.0, 0.0]);
    assert_eq!(&after.v[before.v.len()..], &[0.0, 0.0]);
    assert!((m1 - m0 - 4.0).abs() < 1e-12);
    assert_eq!(c1 - c0, 4.0);
    w.sim.run(500); // t = 0.5 s
    w.sim.compile();
    let (nv2, m2, c2, end, steps2) = look(&w);
    assert_eq!(nv2, 22);
    assert_eq!((m2, c2), (m0, c0));
    assert_eq!(end.q.len(), 23);
    assert!(steps2 > steps1, "touchdowns {steps1} → {steps2}");
    w.sim.run(500);
    let r = w.sim.robot(rex).unwrap();
    assert!(!r.run.metrics.summary().fell);
}

/// A robot on DC motors and sensors keeps both across compliant loads: with
/// the load attached from the start (one motor per actuated joint; the load's
/// joints get none), and through an attach event (the motors' and sensors'
/// states go on, as the controller's do).
#[test]
fn motors_and_sensors_go_on_with_a_compliant_load() {
    let src = trot_slosh(0.5).replace(
        "[robots.controller]",
        "[robots.actuators]\nkind = \"dc_motor\"\n\n[robots.controller]",
    );
    let w = world(&src);
    let rex = w.robots[0].1;
    let r = w.sim.robot(rex).unwrap();
    assert_eq!(r.model.nv, 24, "the load is attached from the start");
    assert!(r.workspace.actuators.is_some(), "motors with the load on");
    let attached_later = src.replace(
        "damping_nspm = 10.05",
        "damping_nspm = 10.05\nattached = false",
    ) + "\n[[events]]\nt_s = 0.25\nrobot = \"rex\"\nkind = \"attach\"\npayload = \"tank\"\n";
    let mut w = world(&attached_later);
    let rex = w.robots[0].1;
    w.sim.run(500); // t = 0.25 s, the attach due before the next step
    let estimate_t = |w: &World| {
        let r = w.sim.robot(rex).unwrap();
        r.sensing
            .as_ref()
            .expect("sensors")
            .estimator
            .as_ref()
            .unwrap()
            .estimate
            .t_s
    };
    let (t_before, bank_before) = {
        let r = w.sim.robot(rex).unwrap();
        (
            estimate_t(&w),
            r.workspace.actuators.clone().expect("motors"),
        )
    };
    assert!(t_before > 0.2, "the estimator ran: {t_before}");
    w.sim.compile();
    let r = w.sim.robot(rex).unwrap();
    assert_eq!(r.model.nv, 24);
    assert_eq!(
        estimate_t(&w),
        t_before,
        "the same sensors and estimator go on"
    );
    assert_eq!(
        r.workspace.actuators.as_ref(),
        Some(&bank_before),
        "the same motors go on, with their states"
    );
    w.sim.run(200);
    assert!(estimate_t(&w) > t_before);
    assert!(!w.sim.robot(rex).unwrap().run.metrics.summary().fell);
}

/// Bad compliant payloads name their key (file, line and key path).
#[test]
fn bad_compliant_payloads_name_their_key() {
    let src = trot_slosh(1.0);
    for (from, to, key) in [
        (
            "kind = \"compliant\"",
            "kind = \"squishy\"",
            "robots[0].payloads[0].kind",
        ),
        (
            "dofs = [\"x\", \"y\"]",
            "dofs = [\"x\", \"w\"]",
            "robots[0].payloads[0].dofs[1]",
        ),
        (
            "dofs = [\"x\", \"y\"]",
            "dofs = [\"x\", \"x\"]",
            "robots[0].payloads[0].dofs[1]",
        ),
        (
            "dofs = [\"x\", \"y\"]",
            "dofs = [\"x\", \"pitch\"]",
            "robots[0].payloads[0].dofs[1]",
        ),
        (
            "dofs = [\"x\", \"y\"]",
            "dofs = []",
            "robots[0].payloads[0].dofs",
        ),
        (
            "stiffness_npm = 631.7",
            "stiffness_npm = 0.0",
            "robots[0].payloads[0].stiffness_npm",
        ),
        (
            "damping_nspm = 10.05",
            "damping_nspm = -1.0",
            "robots[0].payloads[0].damping_nspm",
        ),
        (
            "kind = \"compliant\"",
            "kind = \"rigid\"",
            "robots[0].payloads[0].dofs",
        ),
    ] {
        let bad = src.replace(from, to);
        assert_ne!(bad, src, "{from}");
        let scn = parse_scenario(Path::new("p.toml"), bad).unwrap();
        let e = build_world(&scn, Overrides::default()).unwrap_err();
        assert_eq!(e.key_path, key, "{e}");
        assert!(e.line > 0, "{e}");
    }
}

/// The `prescribed` controller's hybrid mode imposes every joint's motion,
/// so it refuses a compliant payload (naming the payload's `kind`); its PD
/// mode drives the legs through the frozen-load view while the load moves.
#[test]
fn prescribed_hybrid_refuses_a_compliant_load_and_pd_carries_it() {
    let small = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/small_trot.toml"
    ))
    .unwrap()
    .replace("duration_s = 5.0", "duration_s = 0.5");
    let load = "\n[[robots.payloads]]\nname = \"cup\"\nkind = \"compliant\"\nmass_kg = 0.5\n\
                size_m = [0.05]\nshape = \"sphere\"\noffset_m = [0.0, 0.0, 0.05]\n\
                dofs = [\"x\", \"y\"]\nstiffness_npm = 80.0\ndamping_nspm = 0.5\n";
    let hybrid = small.clone() + load;
    assert!(hybrid.contains("mode = \"hybrid\""));
    let scn = parse_scenario(Path::new("p.toml"), hybrid.clone()).unwrap();
    let e = build_world(&scn, Overrides::default()).unwrap_err();
    assert_eq!(e.key_path, "robots[0].payloads[0].kind", "{e}");
    let mut w = world(&hybrid.replace("mode = \"hybrid\"", "mode = \"pd\""));
    let bee = w.robots[0].1;
    assert_eq!(w.sim.robot(bee).unwrap().model.nv, 6 + 12 + 2);
    w.sim.run(w.steps);
    let r = w.sim.robot(bee).unwrap();
    let load_q = &r.state.q[r.model.actuated_nq()..];
    assert!(
        load_q.iter().all(|x| x.is_finite() && x.abs() < 0.05),
        "{load_q:?}"
    );
    assert!(
        load_q.iter().any(|x| x.abs() > 1e-5),
        "the load did not move"
    );
    assert!(!r.run.metrics.summary().fell);
}
