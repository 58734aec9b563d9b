//! The walking controller ([`Walker`]) on terrain and in other gaits, in a
//! single-robot loop of the engine (contacts, semi-implicit Euler at 0.5 ms,
//! controller at 500 Hz = every 4th step): step up and step down with a
//! blind controller (touchdown from the contact state), the gaits other than
//! the trot, flight, and what the swing lift height costs in joint torque.

use glam::{DVec2, DVec3};
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundMaterial, update_after_step,
};
use quadsim_engine::control::vmc::VmcCommand;
use quadsim_engine::control::walker::{ROUND_OFF_ROBUST, Walker, WalkerInput, WalkerParams};
use quadsim_engine::gait::{Gait, GaitKind, LegPhase, LegState};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::spatial::rpy_from_rot;
use quadsim_engine::terrain::{Flat, TerrainPatch, TerrainShape, TerrainUnion};
use quadsim_engine::{Data, robots};

const DT_S: f64 = 0.0005;
/// Physics steps per controller tick (500 Hz).
const EVERY: usize = 4;

fn concrete() -> GroundMaterial {
    GroundMaterial::preset("concrete").unwrap()
}

/// One run's setup.
struct Setup {
    params: WalkerParams,
    /// The ground the physics sees.
    physics: TerrainUnion,
    /// The ground the controller is told about (a blind controller gets a
    /// flat plane at its start level).
    sensed: TerrainUnion,
    /// Start height of the ground under the robot (m).
    start_ground_m: f64,
    /// Offset of the base's start position from the nominal stance (m, world).
    base_offset_m: DVec3,
    duration_s: f64,
}

impl Setup {
    fn flat(params: WalkerParams, duration_s: f64) -> Setup {
        let g = TerrainUnion::flat(0.0, concrete());
        Setup {
            params,
            physics: g.clone(),
            sensed: g,
            start_ground_m: 0.0,
            base_offset_m: DVec3::ZERO,
            duration_s,
        }
    }
}

/// quad16's default walker parameters with a forward speed command.
fn quad16_params(forward_mps: f64) -> WalkerParams {
    let (desc, model) = quad16();
    let mut p = WalkerParams::default_for(&desc, &model);
    p.command = VmcCommand {
        forward_mps,
        lateral_mps: 0.0,
        yaw_rate_radps: 0.0,
    };
    p
}

fn quad16() -> (quadsim_engine::description::RobotDescription, Model) {
    let desc = robots::builtin("quad16").unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    (desc, model)
}

/// What the controller saw and did at one tick.
struct Tick {
    /// Physics step index of the tick.
    step: usize,
    /// Leg states after the tick.
    legs: [LegState; 4],
    /// Joint torques commanded (N·m, joints only).
    tau: Vec<f64>,
}

/// A run's record.
struct Record {
    ticks: Vec<Tick>,
    /// Per physics step: each foot's contact flag (after the step's contact update).
    contact: Vec<[bool; 4]>,
    /// Per physics step: each foot's world position (m).
    feet: Vec<[DVec3; 4]>,
    /// Lowest base height above the start ground (m).
    min_height_m: f64,
    /// Largest roll or pitch magnitude (rad).
    max_tilt_rad: f64,
    /// Mean forward speed over [3 s, end] (m/s).
    mean_speed_mps: f64,
    /// Base x at the end (m).
    end_x_m: f64,
}

impl Record {
    /// The robot stayed up: base above 50 % of its nominal height (the
    /// scenarios' fall criterion) relative to the start ground, tilt below 60°.
    fn upright(&self, nominal_m: f64) -> bool {
        self.min_height_m > 0.5 * nominal_m && self.max_tilt_rad < 60f64.to_radians()
    }
}

fn run(setup: &Setup) -> Record {
    let (desc, model) = quad16();
    let mut data = Data::new(&model);
    let mut walker = Walker::new(&desc, &model, setup.params.clone()).unwrap();
    let points = ContactPoint::feet(&model, &desc);
    let mut states = vec![ContactState::default(); points.len()];
    let mut q = robots::nominal_q("quad16").unwrap();
    q[2] += setup.start_ground_m;
    for k in 0..3 {
        q[k] += setup.base_offset_m[k];
    }
    let mut st = State {
        v: vec![0.0; model.nv],
        q,
    };
    let mut ws = StepWorkspace::new(&model);
    let mut tau = vec![0.0; model.nv];
    let mut tj = vec![0.0; model.nv - 6];
    let steps = (setup.duration_s / DT_S).round() as usize;
    let mut rec = Record {
        ticks: Vec::new(),
        contact: Vec::with_capacity(steps),
        feet: Vec::with_capacity(steps),
        min_height_m: f64::INFINITY,
        max_tilt_rad: 0.0,
        mean_speed_mps: 0.0,
        end_x_m: 0.0,
    };
    let mut x3 = None;
    for k in 0..steps {
        forward_kinematics(&model, &mut data, &st.q, &st.v);
        update_after_step(&points, &data, &setup.physics, &mut states);
        let mut c = [false; 4];
        let mut feet = [DVec3::ZERO; 4];
        for i in 0..4 {
            c[i] = states[i].in_contact;
            feet[i] = data.body_point_world(points[i].body, points[i].point_in_body);
        }
        rec.contact.push(c);
        rec.feet.push(feet);
        if k % EVERY == 0 {
            let normals: Vec<DVec3> = states.iter().map(|s| s.normal).collect();
            let input = WalkerInput {
                dt_s: EVERY as f64 * DT_S,
                terrain: &setup.sensed,
                contacts: &c,
                normals: &normals,
            };
            walker.tick(&model, &mut data, &st.q, &st.v, &input, &mut tj);
            tau[6..].copy_from_slice(&tj);
            let s = walker.scheduler();
            rec.ticks.push(Tick {
                step: k,
                legs: [*s.leg(0), *s.leg(1), *s.leg(2), *s.leg(3)],
                tau: tj.clone(),
            });
        }
        let mut f = ContactForces {
            terrain: &setup.physics,
            points: &points,
            states: &states,
        };
        step(
            &model,
            &mut data,
            &mut ws,
            &mut st,
            &tau,
            DT_S,
            Integrator::SemiImplicitEuler,
            &mut f,
        );
        let rpy = rpy_from_rot(data.pose[0].rot);
        rec.min_height_m = rec.min_height_m.min(st.q[2] - setup.start_ground_m);
        rec.max_tilt_rad = rec.max_tilt_rad.max(rpy.x.abs()).max(rpy.y.abs());
        if k + 1 == (3.0 / DT_S) as usize {
            x3 = Some(st.q[0]);
        }
        if !st.q[2].is_finite() || rec.min_height_m < 0.1 {
            rec.min_height_m = rec.min_height_m.min(0.0);
            break;
        }
    }
    rec.end_x_m = st.q[0];
    rec.mean_speed_mps = x3.map_or(0.0, |x| (st.q[0] - x) / (setup.duration_s - 3.0));
    rec
}

/// How a touchdown related to the scheduled end of its swing, judged from
/// the leg's state at the tick before (as the scheduler's rules 2–3 do).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Timing {
    Early,
    OnTime,
    Late,
}

/// One swing → stance switch of the scheduler.
#[derive(Clone, Copy, Debug)]
struct Touchdown {
    leg: usize,
    /// Physics step of the tick that switched.
    switch_step: usize,
    /// First physics step of the contact run that the switch belongs to.
    onset_step: usize,
    timing: Timing,
    /// Foot position at the switch (m, world).
    foot_m: DVec3,
}

/// Every touchdown of the run, with the contact onset it answers: the first
/// step of the uninterrupted run of contact flags that includes the switch's
/// step. Panics if a switch happens without contact (the scheduler must not
/// touch down on the clock alone).
fn touchdowns(rec: &Record) -> Vec<Touchdown> {
    let mut out = Vec::new();
    for w in rec.ticks.windows(2) {
        let (prev, now) = (&w[0], &w[1]);
        for leg in 0..4 {
            let (a, b) = (prev.legs[leg], now.legs[leg]);
            if !(a.phase == LegPhase::Swing && b.phase == LegPhase::Stance) {
                continue;
            }
            let k = now.step;
            assert!(
                rec.contact[k][leg],
                "leg {leg} touched down at step {k} without contact"
            );
            let mut onset = k;
            while onset > 0 && rec.contact[onset - 1][leg] {
                onset -= 1;
            }
            let tick_s = EVERY as f64 * DT_S;
            let timing = if a.late_s > 0.0 {
                Timing::Late
            } else if a.time_since_liftoff_s + tick_s < a.swing_duration_s - 1e-9 {
                Timing::Early
            } else {
                Timing::OnTime
            };
            out.push(Touchdown {
                leg,
                switch_step: k,
                onset_step: onset,
                timing,
                foot_m: rec.feet[k][leg],
            });
        }
    }
    out
}

/// A flat platform 5 cm high (concrete) over x ∈ [x0, x0 + 20] m on a concrete plane at 0.
fn platform(x0_m: f64, height_m: f64) -> TerrainPatch {
    TerrainPatch::new(
        TerrainShape::Flat(Flat::new(DVec2::new(20.0, 20.0)).unwrap()),
        DVec3::new(x0_m + 10.0, 0.0, height_m),
        0.0,
        concrete(),
    )
    .unwrap()
}

const STEP_M: f64 = 0.05;

/// Checks the touchdown rule on every touchdown of a run and returns those
/// of each leg's first touchdown beyond the step edge `edge_x_m`.
fn check_touchdowns(rec: &Record, edge_x_m: f64) -> Vec<Touchdown> {
    let tds = touchdowns(rec);
    assert!(tds.len() > 20, "{} touchdowns", tds.len());
    for td in &tds {
        // The switch comes at the first controller tick at or after the
        // contact onset: within one tick (4 steps, 2 ms).
        assert!(
            td.switch_step - td.onset_step < EVERY,
            "{td:?}: switched {} steps after contact onset",
            td.switch_step - td.onset_step
        );
    }
    let r: Vec<Touchdown> = (0..4)
        .map(|leg| {
            *tds.iter()
                .find(|t| t.leg == leg && t.foot_m.x > edge_x_m + 0.03)
                .unwrap_or_else(|| panic!("leg {leg} never crossed the step"))
        })
        .collect();
    r
}

/// Issue 4, step up: quad16 trots at 0.5 m/s onto a 5 cm platform whose edge
/// is 1 m ahead, with a blind controller (told the ground is flat at 0), so
/// only the contact state can end a swing early. Every touchdown of the run
/// switches the leg to stance within one control tick (2 ms) of its contact
/// onset, and each leg's first touchdown on the platform is early (before
/// the scheduled end of its swing), at the platform's height. Lift 10 cm:
/// a 5 cm apex over a 5 cm riser would scuff its edge. With the stance foot
/// press and friction reserve ([`ROUND_OFF_ROBUST`]): with the defaults the
/// blind step-up falls from 10 of 41 starts moved by 1e-9 m, so whether its
/// one start stands would hang on the last bits of every computation
/// (`docs/walking.md`, "Round-off sensitivity").
#[test]
fn step_up_touchdown_is_early_and_within_one_tick_of_contact() {
    let edge = 1.0;
    let mut setup = step_up(edge, DVec3::ZERO);
    (
        setup.params.stance_foot_press,
        setup.params.friction_fraction,
    ) = ROUND_OFF_ROBUST;
    let rec = run(&setup);
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    assert!(
        rec.upright(nominal),
        "fell: min height {}",
        rec.min_height_m
    );
    assert!(rec.end_x_m > edge + 0.8, "only reached x = {}", rec.end_x_m);
    for td in check_touchdowns(&rec, edge) {
        assert_eq!(td.timing, Timing::Early, "{td:?}");
        assert!(td.foot_m.z > STEP_M, "{td:?}");
    }
}

/// The step-up run of [`step_up_touchdown_is_early_and_within_one_tick_of_contact`]
/// with the base's start moved by `base_offset_m`.
fn step_up(edge_m: f64, base_offset_m: DVec3) -> Setup {
    let mut params = quad16_params(0.5);
    params.lift_height_m = 0.10;
    Setup {
        params,
        physics: TerrainUnion::flat(0.0, concrete()).with(platform(edge_m, STEP_M)),
        sensed: TerrainUnion::flat(0.0, concrete()),
        start_ground_m: 0.0,
        base_offset_m,
        duration_s: 7.0,
    }
}

/// With the stance foot press and the friction reserve ([`ROUND_OFF_ROBUST`])
/// the blind step up does not hang on the last bits of its start: from 5
/// starts whose base is moved by up to 1e-9 m along each axis (seeded), the
/// robot stays upright and crosses onto the platform. Such perturbations
/// are what a faithful numeric change (a QP solver, libm's sin/cos) makes
/// within a few ticks; with the defaults 10 of 41 starts perturbed by ±1e-9
/// in one coordinate fall. Still close to the edge in its parameters: on
/// the platform the blind trot leans (roll 0.15–0.2 rad) under a lateral
/// virtual force at VMC's position-error clip, and with a friction fraction
/// of 0.8 instead of 0.85 29 of 41 starts fall (0.875: 6, 0.9: 1).
#[test]
fn step_up_with_foot_press_survives_round_off_sized_perturbations() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let edge = 1.0;
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    for start in 0..5 {
        let offset = DVec3::new(
            rng.random_range(-1e-9..1e-9),
            rng.random_range(-1e-9..1e-9),
            rng.random_range(-1e-9..1e-9),
        );
        let mut setup = step_up(edge, offset);
        (
            setup.params.stance_foot_press,
            setup.params.friction_fraction,
        ) = ROUND_OFF_ROBUST;
        let rec = run(&setup);
        assert!(
            rec.upright(nominal),
            "start {start}: fell: min height {}, tilt {} rad",
            rec.min_height_m,
            rec.max_tilt_rad
        );
        assert!(
            rec.end_x_m > edge + 0.8,
            "start {start}: only reached x = {}",
            rec.end_x_m
        );
    }
}

/// Issue 4, step down: quad16 trots at 0.5 m/s off a 5 cm platform (it
/// starts on it; the edge 1 m ahead) with a blind controller (told the
/// ground is flat at the platform's height). Every touchdown switches within
/// one control tick of its contact onset, and each leg's first touchdown
/// below the edge is late: the swing ended in the air and the foot reached
/// down until it touched.
#[test]
fn step_down_touchdown_is_late_and_within_one_tick_of_contact() {
    let edge = 1.0;
    // the platform covers x < edge: a 20 m patch ending at the edge
    let high = TerrainPatch::new(
        TerrainShape::Flat(Flat::new(DVec2::new(20.0, 20.0)).unwrap()),
        DVec3::new(edge - 10.0, 0.0, STEP_M),
        0.0,
        concrete(),
    )
    .unwrap();
    let setup = Setup {
        params: quad16_params(0.5),
        physics: TerrainUnion::flat(0.0, concrete()).with(high),
        sensed: TerrainUnion::flat(STEP_M, concrete()),
        start_ground_m: STEP_M,
        base_offset_m: DVec3::ZERO,
        duration_s: 7.0,
    };
    let rec = run(&setup);
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    assert!(
        rec.min_height_m + STEP_M > 0.5 * nominal,
        "fell: min height {}",
        rec.min_height_m
    );
    assert!(rec.end_x_m > edge + 0.8, "only reached x = {}", rec.end_x_m);
    for td in check_touchdowns(&rec, edge) {
        assert_eq!(td.timing, Timing::Late, "{td:?}");
        assert!(td.foot_m.z < STEP_M, "{td:?}");
    }
}

/// One gait for 10 s on flat concrete at `forward_mps`: upright by the
/// scenarios' fall criteria and, when moving, the mean speed over [3, 10] s
/// within 0.05 m/s of the command.
fn gait_holds(kind: GaitKind, forward_mps: f64) -> Result<(), String> {
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    let mut p = quad16_params(forward_mps);
    p.gait = Gait::default_of(kind).unwrap();
    let rec = run(&Setup::flat(p, 10.0));
    if !rec.upright(nominal) {
        return Err(format!(
            "{kind:?} at {forward_mps} m/s fell: min height {:.3} m, tilt {:.3} rad",
            rec.min_height_m, rec.max_tilt_rad
        ));
    }
    if (rec.mean_speed_mps - forward_mps).abs() > 0.05 {
        return Err(format!(
            "{kind:?} at {forward_mps} m/s: mean speed {:.3} m/s",
            rec.mean_speed_mps
        ));
    }
    Ok(())
}

/// Issue 4, gaits: quad16 with its default walker and each gait's default
/// timing (`GaitKind`'s table) does not fall in 10 s on flat concrete (0.5 ms
/// steps, controller at 500 Hz): walk (crawl), pace and bound at 0.3 m/s
/// (tracking the speed), stand and pronk in place. (The trot has its own
/// tests in `walker.rs`.) The pronk at 0.3 m/s falls: it is experimental
/// (scenarios/README.md) and kept as an
/// ignored test ([`pronk_moves_forward`]).
#[test]
fn gaits_hold_ten_seconds_on_flat_ground() {
    let mut errors = Vec::new();
    for (kind, v) in [
        (GaitKind::Walk, 0.3),
        (GaitKind::Pace, 0.3),
        (GaitKind::Bound, 0.3),
        (GaitKind::Stand, 0.0),
        (GaitKind::Pronk, 0.0),
    ] {
        if let Err(e) = gait_holds(kind, v) {
            errors.push(e);
        }
    }
    assert!(errors.is_empty(), "{errors:#?}");
}

/// A stand ignores a speed command (it takes no steps): commanded 0.3 m/s,
/// it stays upright where it is; a stand that obeyed VMC's speed target
/// leaned over its feet and fell in 1.7 s.
#[test]
fn stand_ignores_speed_commands() {
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    let mut p = quad16_params(0.3);
    p.gait = Gait::stand();
    let rec = run(&Setup::flat(p, 5.0));
    assert!(rec.upright(nominal), "min height {}", rec.min_height_m);
    assert!(rec.end_x_m.abs() < 0.05, "moved to x = {}", rec.end_x_m);
}

/// Not reached: the pronk commanded forward (0.3 m/s) falls within about
/// 1 s, so the pronk is experimental (scenarios/README.md).
#[test]
#[ignore = "not reached: the pronk at 0.3 m/s falls within ~1 s"]
fn pronk_moves_forward() {
    gait_holds(GaitKind::Pronk, 0.3).unwrap();
}

/// Issue 4, flight: when no leg is in stance (a pronk's flight phase), the
/// stance torques are zero and only swing control runs: the joint torques do
/// not depend on the virtual wrench. Two walkers that differ only in the
/// payload their gravity compensation carries (0 and 50 kg: a 490 N
/// difference in W) get the same state (quad16 at its nominal pose in the
/// air, no contacts) tick after tick; at every flight tick their torques are
/// bit-identical and the foot forces zero, while at the stance ticks before
/// the first lift-off the torques differ (so the comparison can see W).
#[test]
fn flight_runs_only_swing_control() {
    let (desc, model) = quad16();
    let make = |payload: f64| {
        let mut p = quad16_params(0.0);
        p.gait = Gait::default_of(GaitKind::Pronk).unwrap();
        p.vmc.payload_mass_kg = payload;
        Walker::new(&desc, &model, p).unwrap()
    };
    let (mut a, mut b) = (make(0.0), make(50.0));
    let (mut da, mut db) = (Data::new(&model), Data::new(&model));
    let q = robots::nominal_q("quad16").unwrap();
    let v = vec![0.0; model.nv];
    let terrain = TerrainUnion::flat(0.0, concrete());
    let contacts = [false; 4];
    let normals = [DVec3::Z; 4];
    let input = WalkerInput {
        dt_s: EVERY as f64 * DT_S,
        terrain: &terrain,
        contacts: &contacts,
        normals: &normals,
    };
    let nj = model.nv - 6;
    let (mut ta, mut tb) = (vec![0.0; nj], vec![0.0; nj]);
    let (mut flight, mut stance_differ) = (0, 0);
    for _ in 0..400 {
        a.tick(&model, &mut da, &q, &v, &input, &mut ta);
        b.tick(&model, &mut db, &q, &v, &input, &mut tb);
        if a.scheduler().in_flight() {
            assert!(b.scheduler().in_flight());
            flight += 1;
            assert_eq!(ta, tb, "flight torques depend on the virtual wrench");
            assert!(a.foot_forces().iter().all(|f| *f == DVec3::ZERO));
        } else if a.scheduler().stance_count() == 4 && ta != tb {
            stance_differ += 1;
        }
    }
    assert!(flight > 100, "{flight} flight ticks");
    assert!(
        stance_differ > 10,
        "{stance_differ} stance ticks with different torques"
    );
}

/// Peak swing torques of one run: per joint of a leg (hip roll, hip pitch,
/// knee, ankle), the largest commanded |τ| (N·m, after saturation) over every
/// leg while it swings, from t = 1 s to the end or the fall.
struct SwingPeaks {
    /// Over the whole swing.
    whole: [f64; 4],
    /// Over swing progress ≥ 0.1: without the lift-off transition, where the
    /// leg's torques jump from the stance law to the swing PD.
    after_liftoff: [f64; 4],
    /// When it fell (s), if it did.
    fell_at_s: Option<f64>,
}

fn peak_swing_torques(lift_m: f64, forward_mps: f64, duration_s: f64) -> SwingPeaks {
    let nominal = robots::nominal_base_height_m("quad16").unwrap();
    let mut p = quad16_params(forward_mps);
    p.lift_height_m = lift_m;
    let rec = run(&Setup::flat(p, duration_s));
    let mut out = SwingPeaks {
        whole: [0.0; 4],
        after_liftoff: [0.0; 4],
        fell_at_s: (!rec.upright(nominal)).then(|| rec.ticks.last().unwrap().step as f64 * DT_S),
    };
    for t in rec.ticks.iter().filter(|t| t.step as f64 * DT_S >= 1.0) {
        for leg in 0..4 {
            let l = t.legs[leg];
            if l.phase == LegPhase::Swing {
                for j in 0..4 {
                    let tau = t.tau[4 * leg + j].abs();
                    out.whole[j] = out.whole[j].max(tau);
                    if l.swing_progress >= 0.1 {
                        out.after_liftoff[j] = out.after_liftoff[j].max(tau);
                    }
                }
            }
        }
    }
    out
}

/// Issue 4, the lift height's cost: Study A's trot at 0.5 m/s, swing legs
/// lifting 5, 10 and 14 cm (5 s each): the peak swing torque (after the
/// lift-off transition) of the hip pitch and of the knee grows with the
/// lift, each lift at least 5 % above the one below, and none of these runs
/// falls. The min-jerk swing's vertical acceleration grows in proportion to
/// the lift (peak `5.77 h / (T_sw/2)²`, 1030 m/s² per metre of lift at
/// Study A's 0.15 s swing). The table for 5–17 cm is [`lift_height_torque_table`].
#[test]
fn peak_swing_torque_grows_with_lift_height() {
    let runs: Vec<SwingPeaks> = [0.05, 0.10, 0.14]
        .iter()
        .map(|&h| peak_swing_torques(h, 0.5, 5.0))
        .collect();
    let show: Vec<([f64; 4], Option<f64>)> = runs
        .iter()
        .map(|r| (r.after_liftoff, r.fell_at_s))
        .collect();
    for w in runs.windows(2) {
        let (lo, hi) = (&w[0], &w[1]);
        assert!(lo.fell_at_s.is_none() && hi.fell_at_s.is_none(), "{show:?}");
        for j in [1, 2] {
            assert!(
                hi.after_liftoff[j] > 1.05 * lo.after_liftoff[j],
                "joint {j}: {show:?}"
            );
        }
    }
}

/// Prints the peak swing torques per joint at lifts of 5, 10, 14 and 17 cm
/// (in place and at 0.5 m/s, 10 s) for docs/walking.md:
/// `cargo test --release -p quadsim-engine --test walking lift_height_torque_table -- --ignored --nocapture`.
#[test]
#[ignore = "prints the table of docs/walking.md"]
fn lift_height_torque_table() {
    let (_, model) = quad16();
    println!("effort limit {} N·m", model.effort_limit[6]);
    println!("| lift (cm) | speed (m/s) | hip roll | hip pitch | knee | ankle | fell at (s) |");
    println!("|---|---|---|---|---|---|---|");
    for v in [0.0, 0.5] {
        for h in [0.05, 0.10, 0.14, 0.17] {
            let r = peak_swing_torques(h, v, 10.0);
            let cell = |j: usize| format!("{:.0} ({:.0})", r.after_liftoff[j], r.whole[j]);
            println!(
                "| {:.0} | {v} | {} | {} | {} | {} | {} |",
                h * 100.0,
                cell(0),
                cell(1),
                cell(2),
                cell(3),
                r.fell_at_s.map_or("—".to_string(), |t| format!("{t:.2}"))
            );
        }
    }
}
