//! Gait patterns, the contact-aware scheduler, swing trajectories and foot
//! placement. Contacts are synthesised from the swing references over a
//! ground height, so early and late touchdowns come from geometry, not from
//! hand-placed flags.

use glam::{DVec2, DVec3};
use quadsim_engine::gait::placement::{clip_step, foot_target_world};
use quadsim_engine::gait::swing::{
    DEFAULT_LIFT_HEIGHT_M, MIN_JERK_PEAK_ACC, MIN_JERK_PEAK_VEL, min_jerk,
};
use quadsim_engine::gait::{
    Gait, GaitError, GaitKind, GaitScheduler, LF, LH, LegEvent, LegPhase, MAX_LEGS, Placement,
    PlacementInput, PlacementParams, RF, RH, ReachDown, SchedulerParams, SwingTrajectory,
    TouchdownKind, raibert_offset,
};

/// 500 Hz, the default controller rate.
const DT_S: f64 = 0.002;

// ---------------------------------------------------------------- helpers

/// Lengths (s) of the maximal intervals over `periods` periods (after the
/// first) during which `pred(support)` holds, sampled every `dt_s` from the
/// scheduler driven over flat ground.
fn support_intervals(
    gait: Gait,
    periods: usize,
    pred: impl Fn(&[bool; MAX_LEGS]) -> bool,
) -> Vec<(f64, [bool; MAX_LEGS])> {
    let mut s = GaitScheduler::new(gait, SchedulerParams::default()).unwrap();
    let ticks = (periods as f64 * gait.period_s() / DT_S).round() as usize;
    let skip = (gait.period_s() / DT_S).round() as usize;
    let mut out = Vec::new();
    let mut run: Option<(usize, [bool; MAX_LEGS])> = None;
    let mut feet_z = [0.0; MAX_LEGS];
    for k in 0..ticks {
        step_flat(&mut s, &mut feet_z, 0.0);
        let m = s.stance_mask();
        let on = k >= skip && pred(&m);
        match (&run, on) {
            (None, true) => run = Some((k, m)),
            (Some((k0, m0)), false) => {
                out.push(((k - k0) as f64 * DT_S, *m0));
                run = None;
            }
            _ => {}
        }
    }
    out
}

/// One control tick over flat ground at height `ground_z`: each foot follows
/// its reference exactly; a foot touches when its reference is at or below the
/// ground. `feet_z` holds the feet's heights from the previous tick.
fn step_flat(
    s: &mut GaitScheduler,
    feet_z: &mut [f64; MAX_LEGS],
    ground_z: f64,
) -> [LegEvent; MAX_LEGS] {
    let n = s.gait().legs();
    let mut contacts = [false; MAX_LEGS];
    for i in 0..n {
        contacts[i] = feet_z[i] <= ground_z + 1e-12;
    }
    let ev = s.update(DT_S, &contacts[..n]);
    let reach = ReachDown::default();
    for i in 0..n {
        feet_z[i] = if s.leg(i).is_stance() {
            ground_z
        } else {
            s.leg(i)
                .swing_reference(DEFAULT_LIFT_HEIGHT_M, &reach)
                .pos_m
                .z
        };
    }
    ev
}

// ---------------------------------------------------------------- gaits

/// Study A: T = 0.5 s, four-leg support 0.1 s, diagonal support 0.15 s give
/// duty 0.7 and offsets LF/RH 0, RF/LH 0.5; the pattern's intervals are those
/// times, with LF+RH and RF+LH as the two-leg supports.
#[test]
fn study_a_trot_arithmetic() {
    let g = Gait::trot_from_supports(0.5, 0.1, 0.15).unwrap();
    let a = Gait::study_a_trot();
    assert!((g.duty_factor() - 0.7).abs() < 1e-12);
    assert!((a.duty_factor() - g.duty_factor()).abs() < 1e-12);
    assert_eq!(g.offsets(), &[0.0, 0.5, 0.0, 0.5]);
    assert_eq!(a.offsets(), g.offsets());
    assert!((g.swing_duration_s() - 0.15).abs() < 1e-12);
    assert!((g.stance_duration_s() - 0.35).abs() < 1e-12);

    // The clock's pattern, sampled finely over one period.
    let n = 100_000;
    let (mut four, mut two_diag, mut other) = (0usize, 0usize, 0usize);
    for k in 0..n {
        let m = g.scheduled_support((k as f64 + 0.5) / n as f64);
        let count = m.iter().filter(|&&b| b).count();
        let diag = (m[LF] && m[RH] && !m[RF] && !m[LH]) || (m[RF] && m[LH] && !m[LF] && !m[RH]);
        match count {
            4 => four += 1,
            2 if diag => two_diag += 1,
            _ => other += 1,
        }
    }
    assert_eq!(other, 0, "a trot has only four-leg and diagonal supports");
    // Twice per period each: 2 × 0.1 s and 2 × 0.15 s.
    assert!((four as f64 / n as f64 * 0.5 - 0.2).abs() < 1e-4);
    assert!((two_diag as f64 / n as f64 * 0.5 - 0.3).abs() < 1e-4);

    // The scheduler over flat ground at 500 Hz gives each interval to one tick.
    let fours = support_intervals(g, 4, |m| m.iter().filter(|&&b| b).count() == 4);
    let twos = support_intervals(g, 4, |m| m.iter().filter(|&&b| b).count() == 2);
    assert!(fours.len() >= 4 && twos.len() >= 4, "{fours:?} {twos:?}");
    for (len, _) in fours.iter().skip(1) {
        assert!((len - 0.1).abs() <= DT_S + 1e-9, "four-leg support {len} s");
    }
    for (len, m) in &twos {
        assert!((len - 0.15).abs() <= DT_S + 1e-9, "two-leg support {len} s");
        assert!(
            (m[LF] && m[RH]) || (m[RF] && m[LH]),
            "support {m:?} is not a diagonal"
        );
    }
}

/// Each named pattern moves the right legs together, and its flight and
/// minimum support follow from the duty factor.
#[test]
fn named_patterns_pair_the_right_legs() {
    let n = 20_000;
    let pairs = |kind: GaitKind| -> Vec<(usize, usize)> {
        match kind {
            GaitKind::Trot => vec![(LF, RH), (RF, LH)],
            GaitKind::Pace => vec![(LF, LH), (RF, RH)],
            GaitKind::Bound => vec![(LF, RF), (RH, LH)],
            GaitKind::Pronk | GaitKind::Stand => vec![(LF, RF), (RF, RH), (RH, LH)],
            _ => vec![],
        }
    };
    for kind in GaitKind::ALL {
        let g = Gait::default_of(kind).unwrap();
        assert_eq!(g.kind(), kind);
        assert_eq!(GaitKind::from_name(kind.name()), Some(kind));
        let mut min_support = 4;
        let mut flight = 0;
        for k in 0..n {
            let phi = (k as f64 + 0.5) / n as f64;
            let m = g.scheduled_support(phi);
            for &(a, b) in &pairs(kind) {
                assert_eq!(m[a], m[b], "{kind:?}: legs {a} and {b} at phase {phi}");
            }
            let c = m.iter().filter(|&&b| b).count();
            min_support = min_support.min(c);
            flight += usize::from(c == 0);
        }
        let flight_frac = flight as f64 / n as f64;
        match kind {
            GaitKind::Stand => assert_eq!(min_support, 4),
            GaitKind::Walk => assert!(min_support >= 3, "the crawl keeps three feet down"),
            GaitKind::Pronk => assert!((flight_frac - (1.0 - g.duty_factor())).abs() < 1e-3),
            _ => assert_eq!(
                flight,
                0,
                "{kind:?} at duty {} has no flight",
                g.duty_factor()
            ),
        }
        // Each leg stands exactly duty of the time.
        for leg in 0..4 {
            let st = (0..n)
                .filter(|k| g.scheduled_stance(leg, (*k as f64 + 0.5) / n as f64))
                .count();
            assert!((st as f64 / n as f64 - g.duty_factor()).abs() < 1e-3);
        }
    }
    assert_eq!(GaitKind::from_name("crawl"), Some(GaitKind::Walk));
    assert_eq!(GaitKind::from_name("gallop"), None);
}

/// The crawl lifts its legs one at a time in the lateral sequence LH, LF, RH, RF.
#[test]
fn walk_lifts_in_lateral_sequence() {
    let g = Gait::default_of(GaitKind::Walk).unwrap();
    let mut s = GaitScheduler::new(g, SchedulerParams::default()).unwrap();
    let mut feet = [0.0; MAX_LEGS];
    let mut order = Vec::new();
    for _ in 0..(2.0 * g.period_s() / DT_S) as usize {
        let ev = step_flat(&mut s, &mut feet, 0.0);
        for (leg, e) in ev.iter().enumerate() {
            if *e == LegEvent::LiftOff {
                order.push(leg);
            }
        }
        assert!(s.stance_count() >= 3);
    }
    // Lift-offs cycle LH → LF → RH → RF (whichever comes first from phase 0).
    let cycle = [LH, LF, RH, RF];
    let start = cycle.iter().position(|&l| l == order[0]).unwrap();
    for (k, leg) in order.iter().enumerate() {
        assert_eq!(*leg, cycle[(start + k) % 4], "lift-off order {order:?}");
    }
    assert!(order.len() >= 7);
}

/// A pronk flies: with no stance foot the scheduler reports flight, and every
/// load is zero so the force distribution (and the stance torques) are zero.
#[test]
fn pronk_flight_is_representable() {
    let g = Gait::of_kind(GaitKind::Pronk, 0.4, 0.4).unwrap();
    let mut s = GaitScheduler::new(g, SchedulerParams::default()).unwrap();
    let mut feet = [0.0; MAX_LEGS];
    let ticks = (5.0 * g.period_s() / DT_S).round() as usize;
    let mut flight_ticks = 0;
    for _ in 0..ticks {
        step_flat(&mut s, &mut feet, 0.0);
        if s.in_flight() {
            flight_ticks += 1;
            assert_eq!(s.stance_count(), 0);
            assert!(s.loads().iter().all(|&l| l == 0.0));
        }
    }
    let frac = flight_ticks as f64 / ticks as f64;
    assert!((frac - 0.6).abs() < 0.01, "flight fraction {frac}");
}

/// A stand never lifts a foot and keeps every foot loaded.
#[test]
fn stand_never_swings() {
    let mut s = GaitScheduler::new(Gait::stand(), SchedulerParams::default()).unwrap();
    for _ in 0..2000 {
        let ev = s.update(DT_S, &[false; 4]);
        assert!(ev.iter().all(|e| *e == LegEvent::None));
        assert_eq!(s.stance_count(), 4);
        assert!(s.loads()[..4].iter().all(|&l| l == 1.0));
    }
    assert!(s.time_to_liftoff_s(LF).is_infinite());
}

/// Bad gait and scheduler parameters are typed errors naming the field.
#[test]
fn bad_parameters_are_typed_errors() {
    for p in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = Gait::new(p, 0.5, &[0.0; 4]).unwrap_err();
        assert!(matches!(e, GaitError::Period { .. }));
        assert!(e.to_string().contains("period_s"));
    }
    for d in [0.0, -0.1, 1.01, f64::NAN] {
        let e = Gait::new(0.5, d, &[0.0; 4]).unwrap_err();
        assert!(matches!(e, GaitError::DutyFactor { .. }), "{e}");
        assert!(e.to_string().contains("duty_factor"));
    }
    let e = Gait::new(0.5, 0.5, &[0.0, 1.0]).unwrap_err();
    assert_eq!(
        e,
        GaitError::Offset {
            leg: 1,
            offset: 1.0
        }
    );
    assert!(e.to_string().contains("offsets[1]"));
    assert!(matches!(
        Gait::new(0.5, 0.5, &[]),
        Err(GaitError::LegCount { legs: 0, .. })
    ));
    assert!(matches!(
        Gait::new(0.5, 0.5, &[0.0; 9]),
        Err(GaitError::LegCount { legs: 9, .. })
    ));
    assert!(Gait::new(0.5, 0.5, &[0.0; 8]).is_ok());
    // 2 × (0.1 + 0.1) ≠ 0.5.
    let e = Gait::trot_from_supports(0.5, 0.1, 0.1).unwrap_err();
    assert!(matches!(e, GaitError::TrotSupports { .. }));
    assert!(Gait::trot_from_supports(0.3, 0.0, 0.15).is_ok());
    assert!(Gait::trot_from_supports(0.5, 0.25, 0.0).is_err());
    assert!(matches!(
        Gait::of_kind(GaitKind::Stand, 1.0, 0.5),
        Err(GaitError::StandDuty { .. })
    ));
    assert!(Gait::of_kind(GaitKind::Custom, 1.0, 0.5).is_err());
    let bad = SchedulerParams {
        early_touchdown_min_progress: 1.5,
        ..SchedulerParams::default()
    };
    let e = GaitScheduler::new(Gait::study_a_trot(), bad).unwrap_err();
    assert!(e.to_string().contains("early_touchdown_min_progress"));
    let bad = SchedulerParams {
        load_ramp_s: -0.01,
        ..SchedulerParams::default()
    };
    assert!(GaitScheduler::new(Gait::study_a_trot(), bad).is_err());
    let mut s = GaitScheduler::new(Gait::study_a_trot(), SchedulerParams::default()).unwrap();
    let three = Gait::new(0.5, 0.5, &[0.0; 3]).unwrap();
    assert_eq!(
        s.set_gait(three),
        Err(GaitError::LegCountChange {
            expected: 4,
            got: 3
        })
    );
}

// ---------------------------------------------------------------- touchdown

/// Runs Study A's trot until leg LF has lifted off, then one full swing over
/// `ground_z` under the touchdown target; returns (tick of the first contact
/// reported to the scheduler, tick of the touchdown, its kind, the swing's
/// progress at touchdown, the time from the scheduled end to the touchdown).
/// Contacts from the previous tick's foot height: the foot follows its
/// reference exactly, so the switch must come in the tick that reports contact.
fn swing_over_step(ground_z: f64) -> (usize, usize, TouchdownKind, f64, f64) {
    let g = Gait::study_a_trot();
    let mut s = GaitScheduler::new(g, SchedulerParams::default()).unwrap();
    let mut feet = [0.0; MAX_LEGS];
    // Flat ground until LF lifts off.
    loop {
        let ev = step_flat(&mut s, &mut feet, 0.0);
        if ev[LF] == LegEvent::LiftOff {
            break;
        }
    }
    let reach = ReachDown::default();
    let mut first_contact = None;
    // The step's edge is half-way along LF's swing: the ground under LF is at
    // `ground_z` from mid-swing on; the other legs stay on flat ground.
    let mut ground = [0.0; 4];
    let mut past_edge = false;
    for k in 0..1000 {
        let mut contacts = [false; 4];
        for i in 0..4 {
            contacts[i] = feet[i] <= ground[i] + 1e-12;
        }
        // (At lift-off the foot still touches: the scheduler ignores that.)
        if contacts[LF] && past_edge && first_contact.is_none() {
            first_contact = Some(k);
        }
        let prev_late = s.leg(LF).late_s;
        let ev = s.update(DT_S, &contacts);
        if let LegEvent::Touchdown(kind) = ev[LF] {
            let leg = s.leg(LF);
            let progress = leg.time_since_liftoff_s / leg.swing_duration_s;
            return (first_contact.unwrap(), k, kind, progress, prev_late);
        }
        if s.leg(LF).swing_progress >= 0.5 {
            ground[LF] = ground_z;
            past_edge = true;
        }
        for i in 0..4 {
            feet[i] = if s.leg(i).is_stance() {
                ground[i]
            } else {
                s.leg(i)
                    .swing_reference(DEFAULT_LIFT_HEIGHT_M, &reach)
                    .pos_m
                    .z
            };
        }
        // The clock never waits for LF: RH keeps its diagonal partner's clock,
        // and swings with it until the scheduled end.
        assert_eq!(s.leg(RH).clock_phase, s.leg(LF).clock_phase, "tick {k}");
        if s.leg(LF).swing_progress < 1.0 && !s.leg(LF).is_stance() {
            assert_eq!(s.leg(RH).phase, LegPhase::Swing, "tick {k}");
        }
    }
    panic!("no touchdown");
}

/// A 5 cm step up: the falling foot meets the raised ground before the
/// scheduled end and the leg switches to stance in the tick that reports it.
#[test]
fn step_up_touches_down_early_within_one_tick() {
    let (contact, touchdown, kind, progress, _) = swing_over_step(0.05);
    assert_eq!(kind, TouchdownKind::Early);
    assert_eq!(touchdown, contact, "switch in the tick of first contact");
    assert!(progress > 0.5 && progress < 1.0, "progress {progress}");
    // Independent check: the descent reaches 5 cm where the min-jerk fall
    // 0.17·(1 − b(u)) = 0.05, i.e. b(u) = 12/17.
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if min_jerk(mid).0 < 12.0 / 17.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let s_hit = 0.5 + 0.5 * lo;
    let tick_progress = DT_S / Gait::study_a_trot().swing_duration_s();
    assert!(
        progress >= s_hit && progress <= s_hit + 2.0 * tick_progress,
        "touchdown at progress {progress}, the foot meets the step at {s_hit}"
    );
}

/// A 5 cm step down: the scheduled swing ends in the air; the foot keeps
/// reaching down and the leg switches in the tick that reports contact.
#[test]
fn step_down_touches_down_late_within_one_tick() {
    let (contact, touchdown, kind, _, late_s) = swing_over_step(-0.05);
    assert_eq!(kind, TouchdownKind::Late);
    assert_eq!(touchdown, contact, "switch in the tick of first contact");
    // Independent check: the reach-down profile is 5 cm deep after
    // t = ramp + (0.05 − ½·v·ramp)/v.
    let r = ReachDown::default();
    let t_hit = r.ramp_s + (0.05 - 0.5 * r.speed_m_s * r.ramp_s) / r.speed_m_s;
    assert!(
        (late_s - t_hit).abs() <= 2.0 * DT_S,
        "late by {late_s} s, the reach meets the ground after {t_hit} s"
    );
}

/// Flat ground: the foot arrives at the scheduled end (on time, never early).
#[test]
fn flat_ground_touches_down_on_time() {
    let (contact, touchdown, kind, progress, _) = swing_over_step(0.0);
    assert_eq!(kind, TouchdownKind::OnTime);
    assert_eq!(touchdown, contact);
    // The foot reaches the ground at the scheduled end; the flag says so one tick later.
    let tick = DT_S / Gait::study_a_trot().swing_duration_s();
    assert!(
        progress >= 1.0 - 1e-9 && progress <= 1.0 + tick + 1e-9,
        "progress {progress}"
    );
}

/// A contact before the early-touchdown threshold (a scuff, a lagging contact
/// flag) does not end the swing; the first contact at or past it does.
#[test]
fn contact_before_mid_swing_is_ignored() {
    let g = Gait::study_a_trot();
    let mut s = GaitScheduler::new(g, SchedulerParams::default()).unwrap();
    while s.update(DT_S, &[true; 4])[LF] != LegEvent::LiftOff {}
    let mut switched_at = None;
    for _ in 0..200 {
        let before = s.leg(LF).time_since_liftoff_s + DT_S;
        let ev = s.update(DT_S, &[true; 4]);
        if let LegEvent::Touchdown(kind) = ev[LF] {
            switched_at = Some((before / g.swing_duration_s(), kind));
            break;
        }
        assert!(s.leg(LF).swing_progress < 0.5);
    }
    let (progress, kind) = switched_at.unwrap();
    assert_eq!(kind, TouchdownKind::Early);
    assert!(progress >= 0.5 && progress < 0.5 + DT_S / g.swing_duration_s() + 1e-9);
}

/// A foot that never finds ground restarts its swing at its next lift-off
/// instead of hanging; the clock never waits for it.
#[test]
fn lost_foot_restarts_at_next_liftoff() {
    let g = Gait::study_a_trot();
    let mut s = GaitScheduler::new(g, SchedulerParams::default()).unwrap();
    let mut lifts = 0;
    let mut contacts = [true; 4];
    contacts[LF] = false;
    for _ in 0..(3.0 * g.period_s() / DT_S) as usize {
        if s.update(DT_S, &contacts)[LF] == LegEvent::LiftOff {
            lifts += 1;
        }
    }
    assert!(s.leg(LF).phase == LegPhase::Swing);
    assert_eq!(lifts, 3, "one lift-off per period");
}

// ---------------------------------------------------------------- loading

/// Loads stay in [0, 1], vanish in swing, rise from 0 to 1 within the window
/// after touchdown and fall to 0 at lift-off, never faster than the
/// smoothstep's peak rate 1.5 / window.
#[test]
fn load_ramps_smoothly() {
    let params = SchedulerParams::default();
    let w = params.load_ramp_s;
    let g = Gait::study_a_trot();
    let mut s = GaitScheduler::new(g, params).unwrap();
    let mut feet = [0.0; MAX_LEGS];
    let mut prev = s.loads();
    let mut touchdowns = 0;
    let mut since_td = [f64::INFINITY; 4];
    for _ in 0..(4.0 * g.period_s() / DT_S) as usize {
        let ev = step_flat(&mut s, &mut feet, 0.0);
        let l = s.loads();
        for i in 0..4 {
            assert!((0.0..=1.0).contains(&l[i]));
            since_td[i] += DT_S;
            match ev[i] {
                LegEvent::Touchdown(_) => {
                    touchdowns += 1;
                    since_td[i] = 0.0;
                    assert_eq!(l[i], 0.0);
                }
                LegEvent::LiftOff => {
                    // The tick before lift-off was nearly unloaded.
                    assert!(
                        prev[i] <= 1.5 * DT_S / w,
                        "load {} before lift-off",
                        prev[i]
                    );
                }
                LegEvent::None => {}
            }
            if !s.leg(i).is_stance() {
                assert_eq!(l[i], 0.0);
            } else {
                assert!((l[i] - prev[i]).abs() <= 1.5 * DT_S / w + 1e-12, "leg {i}");
                if since_td[i] >= w && s.time_to_liftoff_s(i) >= w {
                    assert!((l[i] - 1.0).abs() < 1e-12, "fully loaded between the ramps");
                }
            }
        }
        prev = l;
    }
    assert!(touchdowns >= 12);
}

// ---------------------------------------------------------------- swing

fn traj() -> SwingTrajectory {
    SwingTrajectory::new(
        DVec3::new(-0.1, 0.02, 0.0),
        DVec3::new(0.15, -0.03, 0.0),
        0.17,
        0.15,
    )
}

/// Ends at the lift-off and target points, at rest (velocity and
/// acceleration zero) at both.
#[test]
fn swing_boundaries() {
    for t in [
        traj(),
        SwingTrajectory::new(DVec3::ZERO, DVec3::new(0.1, 0.0, 0.05), 0.17, 0.15),
    ] {
        let a = t.sample(0.0);
        let b = t.sample(1.0);
        assert!((a.pos_m - t.start_m).length() < 1e-15);
        assert!((b.pos_m - t.end_m).length() < 1e-15);
        for smp in [a, b] {
            assert!(smp.vel_m_s.length() < 1e-15);
            assert!(smp.acc_m_s2.length() < 1e-12);
        }
        // Clamped outside [0, 1].
        assert_eq!(t.sample(-0.3), a);
        assert_eq!(t.sample(1.7), b);
    }
}

/// Velocity and acceleration are the time derivatives of position and
/// velocity (central finite differences), and one-sided differences at the
/// ends vanish.
#[test]
fn swing_derivatives_match_finite_differences() {
    let t = traj();
    let h = 1e-7;
    // At the apex z is C² but not C³: the acceleration's central difference is
    // off by O(h · jerk) there, hence a tolerance on the peak's scale.
    let a_tol = 1e-5 * t.peak_vertical_acceleration_m_s2();
    for k in 1..200 {
        let s = k as f64 / 200.0;
        let c = t.sample(s);
        let (p, m) = (t.sample(s + h), t.sample(s - h));
        let v_fd = (p.pos_m - m.pos_m) / (2.0 * h * t.duration_s);
        let a_fd = (p.vel_m_s - m.vel_m_s) / (2.0 * h * t.duration_s);
        assert!(
            (v_fd - c.vel_m_s).length() < 1e-6 * (1.0 + c.vel_m_s.length()),
            "s = {s}"
        );
        assert!((a_fd - c.acc_m_s2).length() < a_tol, "s = {s}");
    }
    for (s0, s1) in [(0.0, h), (1.0 - h, 1.0)] {
        let v = (t.sample(s1).pos_m - t.sample(s0).pos_m) / (h * t.duration_s);
        assert!(v.length() < 1e-3, "end velocity by finite difference {v}");
    }
}

/// The apex is at mid-swing, `lift` above the higher end, and it is the top.
#[test]
fn swing_apex_height() {
    for (z0, z1) in [(0.0, 0.0), (0.0, 0.05), (0.05, -0.02)] {
        let t = SwingTrajectory::new(
            DVec3::new(0.0, 0.0, z0),
            DVec3::new(0.1, 0.0, z1),
            0.17,
            0.15,
        );
        let apex = z0.max(z1) + 0.17;
        assert!((t.sample(0.5).pos_m.z - apex).abs() < 1e-15);
        let top = (0..=10_000)
            .map(|k| t.sample(k as f64 / 1e4).pos_m.z)
            .fold(f64::MIN, f64::max);
        assert!((top - apex).abs() < 1e-12);
        // Horizontal motion stays between the ends (no overshoot).
        for k in 0..=100 {
            let x = t.sample(k as f64 / 100.0).pos_m.x;
            assert!((-1e-15..=0.1 + 1e-15).contains(&x));
        }
    }
    let flat = SwingTrajectory::new(
        DVec3::ZERO,
        DVec3::new(0.05, 0.0, 0.0),
        DEFAULT_LIFT_HEIGHT_M,
        0.15,
    );
    assert!((flat.sample(0.5).pos_m.z - 0.17).abs() < 1e-15);
}

/// The analytic peaks (the cost of a lift height) equal the sampled maxima.
#[test]
fn swing_peaks_match_samples() {
    let t = traj();
    let (mut vz, mut az, mut ah) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..=100_000 {
        let smp = t.sample(k as f64 / 1e5);
        vz = vz.max(smp.vel_m_s.z.abs());
        az = az.max(smp.acc_m_s2.z.abs());
        ah = ah.max(smp.acc_m_s2.truncate().length());
    }
    assert!((vz - t.peak_vertical_speed_m_s()).abs() < 1e-6 * vz);
    assert!((az - t.peak_vertical_acceleration_m_s2()).abs() < 1e-4 * az);
    assert!((ah - t.peak_horizontal_acceleration_m_s2()).abs() < 1e-4 * ah);
    // The min-jerk constants themselves.
    assert!((MIN_JERK_PEAK_ACC - 10.0 / 3f64.sqrt()).abs() < 1e-14);
    assert!((min_jerk(0.5).1 - MIN_JERK_PEAK_VEL).abs() < 1e-15);
    // Study A's lift, 0.17 m in 0.15 s: 4.25 m/s and about 174.5 m/s² peak.
    assert!((t.peak_vertical_speed_m_s() - 4.25).abs() < 1e-12);
    assert!((t.peak_vertical_acceleration_m_s2() - 174.5).abs() < 0.1);
}

/// The reach-down depth is continuous, its rate is its derivative, and it
/// stops at the maximum depth.
#[test]
fn reach_down_profile() {
    let r = ReachDown::default();
    let h = 1e-7;
    let mut prev = 0.0;
    for k in 1..3000 {
        let t = k as f64 * 1e-4;
        let (d, v, _) = r.depth(t);
        assert!(d >= prev && d - prev <= r.speed_m_s * 1e-4 + 1e-12);
        prev = d;
        if d < r.max_depth_m - 1e-9 && (t - r.ramp_s).abs() > 2.0 * h {
            let fd = (r.depth(t + h).0 - r.depth(t - h).0) / (2.0 * h);
            assert!((fd - v).abs() < 1e-6, "t = {t}");
        }
    }
    assert_eq!(r.depth(10.0), (r.max_depth_m, 0.0, 0.0));
    assert_eq!(r.depth(0.0).0, 0.0);
    let t = traj();
    let late = t.sample_late(0.05, &r);
    assert!((late.pos_m.truncate() - t.end_m.truncate()).length() < 1e-15);
    assert!((t.end_m.z - late.pos_m.z - r.depth(0.05).0).abs() < 1e-15);
}

// ---------------------------------------------------------------- placement

/// The formula term by term against an independent evaluation.
#[test]
fn raibert_formula() {
    let params = PlacementParams {
        gain_s: 0.08,
        max_step_x_m: 10.0,
        max_step_y_m: 10.0,
    };
    let input = PlacementInput {
        vel_m_s: DVec2::new(0.9, 0.1),
        vel_des_m_s: DVec2::new(1.2, -0.1),
        yaw_rate_rad_s: 0.4,
        hip_m: DVec2::new(0.25, 0.15),
        stance_duration_s: 0.35,
    };
    let p = raibert_offset(&params, &input);
    let half: f64 = 0.35 / 2.0;
    let th = 0.4 * half;
    let (c, s) = (th.cos(), th.sin());
    let yaw = DVec2::new(c * 0.25 - s * 0.15 - 0.25, s * 0.25 + c * 0.15 - 0.15);
    let expect = DVec2::new(
        0.9 * half + 0.08 * (0.9 - 1.2),
        0.1 * half + 0.08 * (0.1 + 0.1),
    ) + yaw;
    assert!((p.offset_m - expect).length() < 1e-15);
    assert!(!p.clipped);
    // For small yaw rates the yaw term is ω ẑ × r · T/2.
    let small = PlacementInput {
        yaw_rate_rad_s: 1e-4,
        vel_m_s: DVec2::ZERO,
        vel_des_m_s: DVec2::ZERO,
        ..input
    };
    let q = raibert_offset(&params, &small).offset_m;
    let th = 1e-4 * half;
    let cross = DVec2::new(-0.15, 0.25) * th;
    // (R(θ) − I) r = θ ẑ × r − (1 − cos θ) r + O(θ³).
    assert!((q - cross).length() <= 0.5 * th * th * input.hip_m.length() * 1.001);
}

/// At the commanded speed the foot is the midpoint of the hip's stance travel
/// (straight and turning), so the stance is symmetric about the foot.
#[test]
fn neutral_point_makes_the_stance_symmetric() {
    let params = PlacementParams {
        gain_s: 0.2,
        max_step_x_m: 10.0,
        max_step_y_m: 10.0,
    };
    let t_st = 0.35;
    // Straight: hip at touchdown x = 0, at lift-off v·T.
    let v = DVec2::new(1.1, -0.2);
    let p = raibert_offset(
        &params,
        &PlacementInput {
            vel_m_s: v,
            vel_des_m_s: v,
            yaw_rate_rad_s: 0.0,
            hip_m: DVec2::new(0.25, -0.15),
            stance_duration_s: t_st,
        },
    )
    .offset_m;
    let (hip_td, hip_lo) = (DVec2::ZERO, v * t_st);
    assert!(((p - hip_td) + (p - hip_lo)).length() < 1e-15);
    // Turning in place: the hip circles the body centre; the foot (hip
    // projection at touchdown + offset) is as far from the hip at touchdown as
    // from the hip at lift-off, and on the circle.
    let (w, r) = (1.3, DVec2::new(0.25, 0.15));
    let p = raibert_offset(
        &params,
        &PlacementInput {
            vel_m_s: DVec2::ZERO,
            vel_des_m_s: DVec2::ZERO,
            yaw_rate_rad_s: w,
            hip_m: r,
            stance_duration_s: t_st,
        },
    )
    .offset_m;
    let foot = r + p;
    let hip_lo = glam::DMat2::from_angle(w * t_st) * r;
    assert!(((foot - r).length() - (foot - hip_lo).length()).abs() < 1e-15);
    assert!((foot.length() - r.length()).abs() < 1e-15);
}

/// Each axis is clipped to its maximum step independently, sign kept.
#[test]
fn placement_clipping() {
    let params = PlacementParams {
        gain_s: 0.2,
        max_step_x_m: 0.25,
        max_step_y_m: 0.12,
    };
    let base = PlacementInput {
        vel_m_s: DVec2::new(3.0, 0.05),
        vel_des_m_s: DVec2::new(1.5, 0.0),
        yaw_rate_rad_s: 0.0,
        hip_m: DVec2::ZERO,
        stance_duration_s: 0.35,
    };
    let Placement {
        offset_m,
        unclipped_m,
        clipped,
    } = raibert_offset(&params, &base);
    assert!(clipped);
    assert!(unclipped_m.x > 0.25);
    assert_eq!(offset_m.x, 0.25);
    assert_eq!(
        offset_m.y, unclipped_m.y,
        "y is inside its limit and untouched"
    );
    let back = raibert_offset(
        &params,
        &PlacementInput {
            vel_m_s: DVec2::new(-3.0, -2.0),
            ..base
        },
    );
    assert_eq!(back.offset_m, DVec2::new(-0.25, -0.12));
    // Idempotent, and the identity inside the limits.
    assert_eq!(clip_step(back.offset_m, 0.25, 0.12), back.offset_m);
    assert_eq!(
        clip_step(DVec2::new(0.1, -0.05), 0.25, 0.12),
        DVec2::new(0.1, -0.05)
    );
    // World target: the heading-frame offset turned by the yaw.
    let w = foot_target_world(
        DVec3::new(1.0, 2.0, 0.5),
        std::f64::consts::FRAC_PI_2,
        0.03,
        DVec2::new(0.1, 0.0),
    );
    assert!((w - DVec3::new(1.0, 2.1, 0.03)).length() < 1e-15);
}

/// The capture-point gain brings a linear inverted pendulum to rest over the
/// foot (integrated with RK4, independent of the closed form): the default
/// speed feedback is a physically grounded one.
#[test]
fn capture_point_gain_stops_an_inverted_pendulum() {
    let (h, g) = (0.5, 9.81);
    let k = PlacementParams::capture_point_gain_s(h, g);
    let v0 = 0.8;
    let foot = k * v0;
    let w2 = g / h;
    let f = |x: f64, v: f64| (v, w2 * (x - foot));
    let (mut x, mut v) = (0.0, v0);
    let dt = 1e-4;
    for _ in 0..30_000 {
        let (a1, b1) = f(x, v);
        let (a2, b2) = f(x + 0.5 * dt * a1, v + 0.5 * dt * b1);
        let (a3, b3) = f(x + 0.5 * dt * a2, v + 0.5 * dt * b2);
        let (a4, b4) = f(x + dt * a3, v + dt * b3);
        x += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        v += dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
    }
    assert!(
        v.abs() < 1e-3 * v0 && (x - foot).abs() < 1e-3,
        "x = {x}, v = {v}"
    );
    // A foot 10 % short lets it fall over forward.
    let foot_short = 0.9 * foot;
    let (mut x, mut v) = (0.0, v0);
    for _ in 0..15_000 {
        let a = w2 * (x - foot_short);
        v += a * dt;
        x += v * dt;
    }
    assert!(x > foot_short + 0.1);
}

// ---------------------------------------------------------------- no heap

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations_in;

/// A controller tick (scheduler update with feet, placement, swing reference)
/// allocates nothing.
#[test]
fn control_tick_allocates_nothing() {
    let g = Gait::study_a_trot();
    let mut s = GaitScheduler::new(g, SchedulerParams::default()).unwrap();
    let params = PlacementParams::default();
    let reach = ReachDown::default();
    let mut feet = [DVec3::ZERO; 4];
    let mut sink = 0.0;
    let n = allocations_in(|| {
        for k in 0..2000 {
            let contacts = [k % 7 != 0, true, k % 5 != 0, true];
            s.update_with_feet(DT_S, &contacts, &feet);
            for i in 0..4 {
                let p = raibert_offset(
                    &params,
                    &PlacementInput {
                        vel_m_s: DVec2::new(1.0, 0.0),
                        vel_des_m_s: DVec2::new(1.5, 0.0),
                        yaw_rate_rad_s: 0.1,
                        hip_m: DVec2::new(0.25, 0.15),
                        stance_duration_s: g.stance_duration_s(),
                    },
                );
                s.set_touchdown_target(i, DVec3::new(p.offset_m.x, p.offset_m.y, 0.0));
                let r = s.leg(i).swing_reference(DEFAULT_LIFT_HEIGHT_M, &reach);
                feet[i] = r.pos_m;
                sink += r.acc_m_s2.z + s.loads()[i];
            }
        }
    });
    assert!(sink.is_finite());
    assert_eq!(n, 0, "allocations during control ticks");
}
