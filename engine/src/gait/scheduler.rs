//! The gait scheduler: a clock that schedules lift-offs, and per-leg state that
//! follows the feet's contacts for touchdown.
//!
//! # Transition rules (per leg, evaluated once per [`GaitScheduler::update`])
//! 1. **Lift-off is clock-driven.** When the leg's phase crosses the duty
//!    factor (stance → swing window of [`Gait`]) during the tick, the leg
//!    enters swing, whatever its contact says (the controller lifts the foot).
//!    Its swing lasts the gait's `(1 − duty) · T` from that instant.
//! 2. **Early touchdown.** A swinging leg whose foot reports contact once its
//!    swing progress (time since lift-off / swing duration) is at least
//!    [`SchedulerParams::early_touchdown_min_progress`] (default ½) enters
//!    stance at that same tick ([`TouchdownKind::Early`] if the scheduled swing
//!    has not ended). A contact earlier in the swing is taken as the foot
//!    scuffing or the contact state lagging the lift-off, and ignored.
//! 3. **Late touchdown.** A swinging leg whose scheduled swing has ended
//!    without contact stays in swing with progress 1 and counts
//!    [`LegState::late_s`]; the controller keeps reaching down
//!    ([`super::swing::ReachDown`]) until the foot reports contact, and the leg
//!    enters stance at that tick ([`TouchdownKind::Late`]; [`TouchdownKind::OnTime`]
//!    when the contact is reported in the tick the swing ends or the next).
//! 4. A leg still reaching down when its next lift-off comes restarts a swing
//!    from where it is (rule 1), so a leg over a hole does not hang forever.
//! 5. Stance never ends early on a lost contact: the clock alone lifts a foot.
//!
//! So the phase switches within the tick whose `contacts` first report the
//! touch, and the clock (and the other legs) never wait for a late foot: the
//! following stance is shortened by the delay.
//!
//! # Flight
//! With no leg in stance ([`GaitScheduler::in_flight`], e.g. a pronk or a
//! flying trot with duty < ½), the controller must apply **zero stance
//! torques** (no foot can push on the ground) and only track the swing
//! references; the force distribution then returns zero forces.
//!
//! # Loading and unloading
//! Each leg has a load factor in [0, 1] ([`LegState::load`]) for the force
//! distribution's bounds (`f_min · load ≤ f_n ≤ f_max · load`): 0 in swing; in
//! stance `min(r(t_td / w), r(t_lo / w))` with `t_td` the time since touchdown,
//! `t_lo` the time left before the scheduled lift-off, `w` the window
//! [`SchedulerParams::load_ramp_s`] and `r(x) = 3x² − 2x³` on [0, 1] (smoothstep:
//! the load and its rate are continuous at both ends of a ramp). So a foot is
//! fully loaded `w` after touchdown, and fully unloaded at its lift-off.

use super::swing::{ReachDown, SwingSample, SwingTrajectory};
use super::{Gait, GaitError, MAX_LEGS, wrap01};
use glam::DVec3;

/// Default controller rate (Hz) the scheduler is advanced at.
pub const DEFAULT_CONTROL_RATE_HZ: f64 = 500.0;

/// Tunable rules of the scheduler (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SchedulerParams {
    /// Swing progress (dimensionless, [0, 1]) from which a contact ends a swing
    /// (early touchdown). Default ½: before mid-swing the foot is still rising.
    pub early_touchdown_min_progress: f64,
    /// Length (s, ≥ 0) of the load ramps after touchdown and before lift-off.
    /// Default 0.03 s: well inside Study A's 0.1 s four-leg support, so one
    /// diagonal unloads while the other loads, and 15 ticks at 500 Hz.
    pub load_ramp_s: f64,
}

impl Default for SchedulerParams {
    fn default() -> Self {
        SchedulerParams {
            early_touchdown_min_progress: 0.5,
            load_ramp_s: 0.03,
        }
    }
}

impl SchedulerParams {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`GaitError::SchedulerParam`] naming the field.
    pub fn validate(&self) -> Result<(), GaitError> {
        if !(0.0..=1.0).contains(&self.early_touchdown_min_progress) {
            return Err(GaitError::SchedulerParam {
                field: "early_touchdown_min_progress",
                value: self.early_touchdown_min_progress,
                why: "must be in [0, 1]",
            });
        }
        if !(self.load_ramp_s.is_finite() && self.load_ramp_s >= 0.0) {
            return Err(GaitError::SchedulerParam {
                field: "load_ramp_s",
                value: self.load_ramp_s,
                why: "must be finite and >= 0",
            });
        }
        Ok(())
    }
}

/// Whether a leg carries load or swings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LegPhase {
    /// Foot on the ground (or scheduled to be, see rule 5).
    Stance,
    /// Foot in the air, following a swing trajectory or reaching down.
    Swing,
}

/// How a touchdown related to the scheduled end of the swing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TouchdownKind {
    /// Contact before the scheduled end (e.g. a step up).
    Early,
    /// Contact reported in the tick the scheduled swing ends or in the next
    /// one (a contact flag describes the foot as the previous step left it).
    OnTime,
    /// Contact after the scheduled end, while reaching down (e.g. a step down).
    Late,
}

/// What happened to a leg during one update.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LegEvent {
    /// No phase change.
    None,
    /// Stance → swing (or a restarted swing, rule 4).
    LiftOff,
    /// Swing → stance.
    Touchdown(TouchdownKind),
}

/// One leg's state, written by the scheduler.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegState {
    /// Actual phase (clock plus contacts).
    pub phase: LegPhase,
    /// The leg's clock phase `frac(φ − offset)` in [0, 1): the schedule.
    pub clock_phase: f64,
    /// Swing progress in [0, 1]: time since lift-off / swing duration, held at
    /// 1 while reaching down late; 0 in stance.
    pub swing_progress: f64,
    /// Duration (s) of the current (or last) swing, fixed at its lift-off.
    pub swing_duration_s: f64,
    /// Time (s) since the last lift-off.
    pub time_since_liftoff_s: f64,
    /// Time (s) since the last touchdown (the load ramp's clock).
    pub time_since_touchdown_s: f64,
    /// Time (s) past the scheduled end of the swing while still without
    /// contact (late touchdown); 0 otherwise.
    pub late_s: f64,
    /// Load factor in [0, 1] (see the module docs).
    pub load: f64,
    /// The contact flag given at the last update.
    pub contact: bool,
    /// Foot position at the last lift-off (the caller's frame, z up; recorded
    /// by [`GaitScheduler::update_with_feet`]).
    pub liftoff_pos_m: DVec3,
    /// During a swing: the touchdown target ([`GaitScheduler::set_touchdown_target`]);
    /// in stance: where the foot touched down, if recorded by
    /// [`GaitScheduler::update_with_feet`].
    pub touchdown_pos_m: DVec3,
    /// During a swing: how much the ground rises from under the lift-off
    /// point to under the target and how far it pokes above the line
    /// between them (m), when the caller knows the ground
    /// ([`GaitScheduler::set_touchdown_target_over`]).
    pub ground_rise_m: Option<(f64, f64)>,
}

impl LegState {
    /// Whether the leg is in stance.
    pub fn is_stance(&self) -> bool {
        self.phase == LegPhase::Stance
    }

    /// Time (s) left in the scheduled swing (0 in stance or once late).
    pub fn time_to_touchdown_s(&self) -> f64 {
        match self.phase {
            LegPhase::Swing => (self.swing_duration_s - self.time_since_liftoff_s).max(0.0),
            LegPhase::Stance => 0.0,
        }
    }

    /// This swing's trajectory from [`Self::liftoff_pos_m`] to
    /// [`Self::touchdown_pos_m`] with the given lift height (m).
    pub fn swing_trajectory(&self, lift_height_m: f64) -> SwingTrajectory {
        let t = SwingTrajectory::new(
            self.liftoff_pos_m,
            self.touchdown_pos_m,
            lift_height_m,
            self.swing_duration_s,
        );
        match self.ground_rise_m {
            Some((rise, obstacle)) => t.over_ground(rise, obstacle),
            None => t,
        }
    }

    /// The swing foot's reference now: the trajectory at the current progress,
    /// or, once late, the touchdown target lowered by `reach` (rule 3).
    /// Meaningless in stance (returns the trajectory's end, at rest).
    pub fn swing_reference(&self, lift_height_m: f64, reach: &ReachDown) -> SwingSample {
        let traj = self.swing_trajectory(lift_height_m);
        match self.phase {
            LegPhase::Swing if self.late_s > 0.0 => traj.sample_late(self.late_s, reach),
            LegPhase::Swing => traj.sample(self.swing_progress),
            LegPhase::Stance => traj.sample(1.0),
        }
    }
}

/// Schedules a [`Gait`] for up to [`MAX_LEGS`] legs. Advance it once per
/// control tick with [`Self::update`]; no allocation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitScheduler {
    gait: Gait,
    params: SchedulerParams,
    phase: f64,
    time_s: f64,
    legs: [LegState; MAX_LEGS],
}

/// Slack (in periods) on "the scheduled swing has ended", so that summing
/// `dt` does not push the end one tick late through rounding.
const END_SLACK_PERIODS: f64 = 1e-9;

impl GaitScheduler {
    /// A scheduler at gait phase 0; see [`Self::new_at_phase`].
    ///
    /// # Errors
    /// Those of [`SchedulerParams::validate`].
    pub fn new(gait: Gait, params: SchedulerParams) -> Result<GaitScheduler, GaitError> {
        Self::new_at_phase(gait, params, 0.0)
    }

    /// A scheduler at gait phase `phase` (wrapped into [0, 1)). The robot
    /// starts standing: every leg in stance and fully loaded; a leg whose clock
    /// starts inside its swing window waits for its next lift-off.
    ///
    /// # Errors
    /// Those of [`SchedulerParams::validate`].
    pub fn new_at_phase(
        gait: Gait,
        params: SchedulerParams,
        phase: f64,
    ) -> Result<GaitScheduler, GaitError> {
        params.validate()?;
        let phase = wrap01(phase);
        let mut legs = [LegState {
            phase: LegPhase::Stance,
            clock_phase: 0.0,
            swing_progress: 0.0,
            swing_duration_s: gait.swing_duration_s(),
            time_since_liftoff_s: 0.0,
            time_since_touchdown_s: params.load_ramp_s,
            late_s: 0.0,
            load: 1.0,
            contact: true,
            liftoff_pos_m: DVec3::ZERO,
            touchdown_pos_m: DVec3::ZERO,
            ground_rise_m: None,
        }; MAX_LEGS];
        for (i, leg) in legs.iter_mut().enumerate().take(gait.legs()) {
            leg.clock_phase = gait.leg_phase(i, phase);
        }
        Ok(GaitScheduler {
            gait,
            params,
            phase,
            time_s: 0.0,
            legs,
        })
    }

    /// Advances the clock by `dt_s` and applies the transition rules (module
    /// docs) with `contacts[i]` = whether leg `i`'s foot touches the ground now.
    /// Returns each leg's event (entries past `legs()` are `None`).
    ///
    /// # Panics
    /// When `contacts` has fewer entries than the gait has legs.
    pub fn update(&mut self, dt_s: f64, contacts: &[bool]) -> [LegEvent; MAX_LEGS] {
        let n = self.gait.legs();
        assert!(
            contacts.len() >= n,
            "{} contact flags for {n} legs",
            contacts.len()
        );
        let period = self.gait.period_s();
        let duty = self.gait.duty_factor();
        let dphi = dt_s / period;
        let swings = self.gait.has_swing();
        self.time_s += dt_s;
        self.phase = wrap01(self.phase + dphi);
        let mut events = [LegEvent::None; MAX_LEGS];
        for i in 0..n {
            let leg = &mut self.legs[i];
            let prev = leg.clock_phase;
            let next = prev + dphi;
            // The phase crossed `duty` (mod 1) in (prev, next].
            let lift = swings && (next - duty).floor() > (prev - duty).floor();
            leg.clock_phase = wrap01(next);
            leg.contact = contacts[i];
            leg.time_since_liftoff_s += dt_s;
            leg.time_since_touchdown_s += dt_s;
            if lift {
                leg.phase = LegPhase::Swing;
                // Time since the crossing itself, so progress matches the clock.
                leg.time_since_liftoff_s = wrap01(next - duty) * period;
                leg.swing_duration_s = self.gait.swing_duration_s();
                leg.late_s = 0.0;
                events[i] = LegEvent::LiftOff;
            }
            let progress = if leg.swing_duration_s > 0.0 {
                leg.time_since_liftoff_s / leg.swing_duration_s
            } else {
                1.0
            };
            let ended =
                leg.time_since_liftoff_s >= leg.swing_duration_s - END_SLACK_PERIODS * period;
            // Touchdown: rules 2 and 3 (not in the tick of a lift-off).
            if !lift
                && leg.phase == LegPhase::Swing
                && leg.contact
                && progress >= self.params.early_touchdown_min_progress
            {
                // `leg.late_s` is still the previous tick's: below one
                // tick, the contact is the first report after the end.
                let kind = if !ended {
                    TouchdownKind::Early
                } else if leg.late_s >= dt_s - END_SLACK_PERIODS * period {
                    TouchdownKind::Late
                } else {
                    TouchdownKind::OnTime
                };
                leg.phase = LegPhase::Stance;
                leg.time_since_touchdown_s = 0.0;
                events[i] = LegEvent::Touchdown(kind);
            }
            match leg.phase {
                LegPhase::Swing => {
                    leg.swing_progress = if ended { 1.0 } else { progress };
                    leg.late_s = if ended {
                        // Positive from the first tick the swing has ended.
                        (leg.time_since_liftoff_s - leg.swing_duration_s).max(f64::MIN_POSITIVE)
                    } else {
                        0.0
                    };
                    leg.load = 0.0;
                }
                LegPhase::Stance => {
                    leg.swing_progress = 0.0;
                    leg.late_s = 0.0;
                    let to_liftoff_s = if swings {
                        wrap01(duty - leg.clock_phase) * period
                    } else {
                        f64::INFINITY
                    };
                    let w = self.params.load_ramp_s;
                    leg.load = if w > 0.0 {
                        smoothstep(leg.time_since_touchdown_s / w).min(smoothstep(to_liftoff_s / w))
                    } else {
                        1.0
                    };
                }
            }
        }
        events
    }

    /// [`Self::update`], then records foot positions (`feet_m[i]`, the caller's
    /// frame, z up): at a lift-off both [`LegState::liftoff_pos_m`] and
    /// [`LegState::touchdown_pos_m`] (a swing steps in place until a target is
    /// set), at a touchdown [`LegState::touchdown_pos_m`].
    ///
    /// # Panics
    /// When `contacts` or `feet_m` has fewer entries than the gait has legs.
    pub fn update_with_feet(
        &mut self,
        dt_s: f64,
        contacts: &[bool],
        feet_m: &[DVec3],
    ) -> [LegEvent; MAX_LEGS] {
        let n = self.gait.legs();
        assert!(
            feet_m.len() >= n,
            "{} foot positions for {n} legs",
            feet_m.len()
        );
        let events = self.update(dt_s, contacts);
        for i in 0..n {
            match events[i] {
                LegEvent::LiftOff => {
                    self.legs[i].liftoff_pos_m = feet_m[i];
                    self.legs[i].touchdown_pos_m = feet_m[i];
                }
                LegEvent::Touchdown(_) => self.legs[i].touchdown_pos_m = feet_m[i],
                LegEvent::None => {}
            }
        }
        events
    }

    /// Sets leg `leg`'s touchdown target (the caller's frame, z up), e.g. the
    /// hip's ground projection plus [`super::placement::raibert_offset`].
    ///
    /// # Panics
    /// When `leg >= legs()`.
    pub fn set_touchdown_target(&mut self, leg: usize, target_m: DVec3) {
        assert!(leg < self.gait.legs(), "leg {leg} of {}", self.gait.legs());
        self.legs[leg].touchdown_pos_m = target_m;
        self.legs[leg].ground_rise_m = None;
    }

    /// [`Self::set_touchdown_target`] over ground that rises by `rise_m`
    /// (m) from under the leg's lift-off point to under `target_m`, poking
    /// `obstacle_m` (m) above the line between them (for the swing's shape
    /// over steps, [`SwingTrajectory::horizontal_window`]).
    pub fn set_touchdown_target_over(
        &mut self,
        leg: usize,
        target_m: DVec3,
        rise_m: f64,
        obstacle_m: f64,
    ) {
        self.set_touchdown_target(leg, target_m);
        self.legs[leg].ground_rise_m = Some((rise_m, obstacle_m));
    }

    /// Switches to another gait with the same number of legs, keeping the gait
    /// clock's phase and every leg's actual phase: a swing in progress keeps its
    /// duration and touches down by the rules; each leg's clock phase becomes
    /// the new gait's, and a stance leg whose new clock lies inside its swing
    /// window waits for its next lift-off.
    ///
    /// # Errors
    /// [`GaitError::LegCountChange`].
    pub fn set_gait(&mut self, gait: Gait) -> Result<(), GaitError> {
        if gait.legs() != self.gait.legs() {
            return Err(GaitError::LegCountChange {
                expected: self.gait.legs(),
                got: gait.legs(),
            });
        }
        self.gait = gait;
        for i in 0..gait.legs() {
            self.legs[i].clock_phase = gait.leg_phase(i, self.phase);
        }
        Ok(())
    }

    /// The gait being scheduled.
    pub fn gait(&self) -> &Gait {
        &self.gait
    }
    /// The rules' parameters.
    pub fn params(&self) -> &SchedulerParams {
        &self.params
    }
    /// Gait clock phase in [0, 1).
    pub fn phase(&self) -> f64 {
        self.phase
    }
    /// Time (s) advanced since construction.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }
    /// Every leg's state (one per gait leg).
    pub fn legs(&self) -> &[LegState] {
        &self.legs[..self.gait.legs()]
    }
    /// Leg `leg`'s state.
    ///
    /// # Panics
    /// When `leg >= legs().len()`.
    pub fn leg(&self, leg: usize) -> &LegState {
        &self.legs()[leg]
    }
    /// Whether each leg is in stance (entries past `legs()` are `false`).
    pub fn stance_mask(&self) -> [bool; MAX_LEGS] {
        let mut m = [false; MAX_LEGS];
        for (mi, leg) in m.iter_mut().zip(self.legs()) {
            *mi = leg.is_stance();
        }
        m
    }
    /// Each leg's load factor (entries past `legs()` are 0).
    pub fn loads(&self) -> [f64; MAX_LEGS] {
        let mut l = [0.0; MAX_LEGS];
        for (li, leg) in l.iter_mut().zip(self.legs()) {
            *li = leg.load;
        }
        l
    }
    /// Number of legs in stance.
    pub fn stance_count(&self) -> usize {
        self.legs().iter().filter(|l| l.is_stance()).count()
    }
    /// No leg in stance: a flight phase. The controller then applies zero
    /// stance torques (module docs).
    pub fn in_flight(&self) -> bool {
        self.stance_count() == 0
    }
    /// Time (s) until leg `leg`'s next scheduled lift-off (∞ for a gait without swing).
    ///
    /// # Panics
    /// When `leg >= legs().len()`.
    pub fn time_to_liftoff_s(&self, leg: usize) -> f64 {
        if !self.gait.has_swing() {
            return f64::INFINITY;
        }
        let clock = self.leg(leg).clock_phase;
        wrap01(self.gait.duty_factor() - clock) * self.gait.period_s()
    }
}

/// `3x² − 2x³` on `x` clamped to [0, 1].
fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}
