//! Gaits: which legs stand and which swing, and when ([`Gait`],
//! [`scheduler::GaitScheduler`]); where a swinging foot goes
//! ([`swing::SwingTrajectory`]); where it lands ([`placement`]).
//!
//! Pure data and functions, no ECS and no heap: every type here is `Copy`,
//! with fixed arrays of [`MAX_LEGS`] entries, so a controller ticking at
//! 500 Hz allocates nothing.
//!
//! # Phase convention
//! The gait clock `φ ∈ [0, 1)` advances by `dt / T` (`T` the period). Leg `i`'s
//! own phase is `φᵢ = frac(φ − offsetᵢ)`: its scheduled touchdown is at
//! `φᵢ = 0`, it stands for `φᵢ ∈ [0, duty)` and swings for `φᵢ ∈ [duty, 1)`.
//! So `offsetᵢ` is the gait phase of leg `i`'s scheduled touchdown, and every
//! leg stands for `duty · T` and swings for `(1 − duty) · T`.
//!
//! Legs of the four-legged gaits are in the robots' q order LF, RF, RH, LH
//! ([`LF`], [`RF`], [`RH`], [`LH`]).
//!
//! # Study A's trot (`/work/shared/reference.md`)
//! Period 0.5 s, four-leg support 0.1 s, diagonal two-leg support 0.15 s: each
//! diagonal pair swings while the other stands, so a leg swings 0.15 s of
//! 0.5 s, `duty = 0.7`, offsets LF/RH 0 and RF/LH 0.5. Over one period, in gait
//! phase: four legs on `[0, 0.2)` (0.1 s), LF+RH on `[0.2, 0.5)` (0.15 s, RF and
//! LH swing), four legs on `[0.5, 0.7)`, RF+LH on `[0.7, 1)` (LF and RH swing).
//! See [`Gait::study_a_trot`] and [`Gait::trot_from_supports`].
//!
//! # Examples
//! One control tick: advance the clock with the feet's contacts, place each
//! swinging foot, and read its reference (position, velocity, acceleration).
//! ```
//! use glam::{DVec2, DVec3};
//! use quadsim_engine::gait::swing::DEFAULT_LIFT_HEIGHT_M;
//! use quadsim_engine::gait::{
//!     Gait, GaitScheduler, PlacementInput, PlacementParams, ReachDown, SchedulerParams, raibert_offset,
//! };
//!
//! let gait = Gait::study_a_trot();
//! let mut sched = GaitScheduler::new(gait, SchedulerParams::default()).unwrap();
//! let feet_m = [DVec3::ZERO; 4]; // from kinematics, world frame
//! for _ in 0..200 {
//!     sched.update_with_feet(0.002, &[true; 4], &feet_m);
//! }
//! for leg in 0..4 {
//!     if !sched.leg(leg).is_stance() {
//!         let p = raibert_offset(
//!             &PlacementParams::default(),
//!             &PlacementInput {
//!                 vel_m_s: DVec2::new(1.0, 0.0),
//!                 vel_des_m_s: DVec2::new(1.5, 0.0),
//!                 yaw_rate_rad_s: 0.0,
//!                 hip_m: DVec2::new(0.25, 0.15),
//!                 stance_duration_s: gait.stance_duration_s(),
//!             },
//!         );
//!         sched.set_touchdown_target(leg, DVec3::new(p.offset_m.x, p.offset_m.y, 0.0));
//!         let r = sched.leg(leg).swing_reference(DEFAULT_LIFT_HEIGHT_M, &ReachDown::default());
//!         assert!(r.pos_m.z >= 0.0);
//!     }
//! }
//! // The force distribution bounds each foot's force by its load factor.
//! assert!(sched.loads().iter().all(|l| (0.0..=1.0).contains(l)));
//! ```

pub mod placement;
pub mod scheduler;
pub mod swing;

use thiserror::Error;

pub use placement::{Placement, PlacementInput, PlacementParams, raibert_offset};
pub use scheduler::{GaitScheduler, LegEvent, LegPhase, LegState, SchedulerParams, TouchdownKind};
pub use swing::{ReachDown, SwingSample, SwingTrajectory};

/// Most legs a gait or scheduler handles (fixed arrays, no allocation).
pub const MAX_LEGS: usize = 8;

/// Index of the left-front leg in the four-legged gaits (q order).
pub const LF: usize = 0;
/// Index of the right-front leg.
pub const RF: usize = 1;
/// Index of the right-hind leg.
pub const RH: usize = 2;
/// Index of the left-hind leg.
pub const LH: usize = 3;
/// Names of the four legs, in q order.
pub const LEG_NAMES: [&str; 4] = ["LF", "RF", "RH", "LH"];

/// The named gait patterns. Offsets (gait phase of each leg's touchdown, legs
/// LF, RF, RH, LH) of the four-legged patterns:
///
/// | kind | offsets | default duty | default period | support |
/// |---|---|---|---|---|
/// | `stand` | 0, 0, 0, 0 | 1 | 1 s | always four feet |
/// | `trot` | 0, ½, 0, ½ | 0.7 | 0.5 s | diagonals together (Study A) |
/// | `walk` | ¼, ¾, ½, 0 | 0.8 | 1 s | crawl, lift-offs LH → LF → RH → RF, ≥ 3 feet when duty ≥ ¾ |
/// | `pace` | 0, ½, ½, 0 | 0.6 | 0.5 s | lateral pairs together |
/// | `bound` | 0, 0, ½, ½ | 0.6 | 0.4 s | front pair, then hind pair |
/// | `pronk` | 0, 0, 0, 0 | 0.4 | 0.4 s | all four together, flight for `1 − duty` |
///
/// The default duties and periods other than the trot's (Study A's) are
/// assumptions: duty above ½ for the two-beat gaits (an overlap of the pairs'
/// stances, no flight), above ¾ for the crawl (statically stable), below 1
/// for the pronk (it must fly).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GaitKind {
    /// All legs always in stance.
    Stand,
    /// Diagonal pairs (LF+RH, RF+LH) in phase, pairs half a period apart.
    Trot,
    /// Crawl: one leg at a time, lateral sequence LH, LF, RH, RF.
    Walk,
    /// Lateral pairs (LF+LH, RF+RH) in phase.
    Pace,
    /// Front pair and hind pair in phase, half a period apart.
    Bound,
    /// All legs in phase.
    Pronk,
    /// Offsets given by the caller ([`Gait::new`]).
    Custom,
}

impl GaitKind {
    /// Every named kind (not `Custom`).
    pub const ALL: [GaitKind; 6] = [
        GaitKind::Stand,
        GaitKind::Trot,
        GaitKind::Walk,
        GaitKind::Pace,
        GaitKind::Bound,
        GaitKind::Pronk,
    ];

    /// Lower-case name (`"trot"`, …) as scenario files spell it.
    pub fn name(self) -> &'static str {
        match self {
            GaitKind::Stand => "stand",
            GaitKind::Trot => "trot",
            GaitKind::Walk => "walk",
            GaitKind::Pace => "pace",
            GaitKind::Bound => "bound",
            GaitKind::Pronk => "pronk",
            GaitKind::Custom => "custom",
        }
    }

    /// The kind named `name` (`"crawl"` is accepted for `walk`), `None` if unknown.
    pub fn from_name(name: &str) -> Option<GaitKind> {
        match name {
            "crawl" => Some(GaitKind::Walk),
            _ => GaitKind::ALL.into_iter().find(|k| k.name() == name),
        }
    }

    /// Touchdown phase offsets of the four legs (LF, RF, RH, LH); `None` for `Custom`.
    pub fn offsets(self) -> Option<[f64; 4]> {
        match self {
            GaitKind::Stand | GaitKind::Pronk => Some([0.0; 4]),
            GaitKind::Trot => Some([0.0, 0.5, 0.0, 0.5]),
            GaitKind::Walk => Some([0.25, 0.75, 0.5, 0.0]),
            GaitKind::Pace => Some([0.0, 0.5, 0.5, 0.0]),
            GaitKind::Bound => Some([0.0, 0.0, 0.5, 0.5]),
            GaitKind::Custom => None,
        }
    }

    /// Default duty factor (see the table on [`GaitKind`]).
    pub fn default_duty(self) -> f64 {
        match self {
            GaitKind::Stand => 1.0,
            GaitKind::Trot => STUDY_A_TROT_DUTY,
            GaitKind::Walk => 0.8,
            GaitKind::Pace | GaitKind::Bound => 0.6,
            GaitKind::Pronk => 0.4,
            GaitKind::Custom => 0.5,
        }
    }

    /// Default period (s) (see the table on [`GaitKind`]).
    pub fn default_period_s(self) -> f64 {
        match self {
            GaitKind::Stand | GaitKind::Walk => 1.0,
            GaitKind::Trot | GaitKind::Pace | GaitKind::Custom => STUDY_A_TROT_PERIOD_S,
            GaitKind::Bound | GaitKind::Pronk => 0.4,
        }
    }
}

/// Study A's trot period (s).
pub const STUDY_A_TROT_PERIOD_S: f64 = 0.5;
/// Study A's four-leg support time (s), twice per period.
pub const STUDY_A_FOUR_LEG_SUPPORT_S: f64 = 0.1;
/// Study A's diagonal two-leg support time (s), twice per period.
pub const STUDY_A_TWO_LEG_SUPPORT_S: f64 = 0.15;
/// Study A's trot duty factor: 1 − 0.15 / 0.5.
pub const STUDY_A_TROT_DUTY: f64 = 0.7;

/// Invalid gait or scheduler parameters. Each variant names the offending field.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum GaitError {
    /// The period must be finite and positive.
    #[error("gait field 'period_s' = {period_s} must be finite and > 0")]
    Period { period_s: f64 },
    /// The duty factor (stance fraction) must be in (0, 1].
    #[error("gait field 'duty_factor' = {duty_factor} must be in (0, 1] (1 = always in stance)")]
    DutyFactor { duty_factor: f64 },
    /// A stand keeps every leg in stance: its duty factor is 1.
    #[error("gait field 'duty_factor' = {duty_factor}: a stand keeps every leg in stance (duty 1)")]
    StandDuty { duty_factor: f64 },
    /// A phase offset must be in [0, 1).
    #[error("gait field 'offsets[{leg}]' = {offset} must be in [0, 1)")]
    Offset { leg: usize, offset: f64 },
    /// One to [`MAX_LEGS`] legs.
    #[error("gait field 'offsets' has {legs} legs; 1 to {max} are supported")]
    LegCount { legs: usize, max: usize },
    /// A trot alternates four-leg and two-leg support twice per period.
    #[error(
        "trot: 'period_s' = {period_s} must equal 2 × ('four_leg_support_s' = {four_leg_support_s} + \
         'two_leg_support_s' = {two_leg_support_s}), both ≥ 0 and the two-leg support > 0"
    )]
    TrotSupports {
        period_s: f64,
        four_leg_support_s: f64,
        two_leg_support_s: f64,
    },
    /// A scheduler parameter is out of its range.
    #[error("gait scheduler field '{field}' = {value} is invalid ({why})")]
    SchedulerParam {
        field: &'static str,
        value: f64,
        why: &'static str,
    },
    /// A new gait must keep the scheduler's number of legs.
    #[error("gait has {got} legs but the scheduler runs {expected}")]
    LegCountChange { expected: usize, got: usize },
}

/// A periodic gait: period, duty factor (stance fraction of the period, the
/// same for every leg) and per-leg touchdown phase offsets (see the module's
/// phase convention). Validated on construction; `Copy`, no heap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gait {
    kind: GaitKind,
    period_s: f64,
    duty_factor: f64,
    offsets: [f64; MAX_LEGS],
    legs: usize,
}

impl Gait {
    /// A gait with the given period (s), duty factor in (0, 1] and one touchdown
    /// phase offset in [0, 1) per leg (1 to [`MAX_LEGS`] legs).
    ///
    /// # Errors
    /// [`GaitError::Period`], [`GaitError::DutyFactor`], [`GaitError::Offset`],
    /// [`GaitError::LegCount`].
    pub fn new(period_s: f64, duty_factor: f64, offsets: &[f64]) -> Result<Gait, GaitError> {
        Self::build(GaitKind::Custom, period_s, duty_factor, offsets)
    }

    fn build(
        kind: GaitKind,
        period_s: f64,
        duty_factor: f64,
        offsets: &[f64],
    ) -> Result<Gait, GaitError> {
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(GaitError::Period { period_s });
        }
        if !(duty_factor > 0.0 && duty_factor <= 1.0) {
            return Err(GaitError::DutyFactor { duty_factor });
        }
        if offsets.is_empty() || offsets.len() > MAX_LEGS {
            return Err(GaitError::LegCount {
                legs: offsets.len(),
                max: MAX_LEGS,
            });
        }
        let mut o = [0.0; MAX_LEGS];
        for (leg, &offset) in offsets.iter().enumerate() {
            if !(0.0..1.0).contains(&offset) {
                return Err(GaitError::Offset { leg, offset });
            }
            o[leg] = offset;
        }
        Ok(Gait {
            kind,
            period_s,
            duty_factor,
            offsets: o,
            legs: offsets.len(),
        })
    }

    /// A named four-legged pattern (offsets from [`GaitKind::offsets`]) with the
    /// given period and duty factor.
    ///
    /// # Errors
    /// As [`Gait::new`]; [`GaitError::StandDuty`] for a stand with duty ≠ 1;
    /// [`GaitError::LegCount`] for `Custom` (it has no offsets of its own).
    pub fn of_kind(kind: GaitKind, period_s: f64, duty_factor: f64) -> Result<Gait, GaitError> {
        if kind == GaitKind::Stand && duty_factor != 1.0 {
            return Err(GaitError::StandDuty { duty_factor });
        }
        let offsets = kind.offsets().ok_or(GaitError::LegCount {
            legs: 0,
            max: MAX_LEGS,
        })?;
        Self::build(kind, period_s, duty_factor, &offsets)
    }

    /// A named four-legged pattern at its default period and duty ([`GaitKind`]'s
    /// table). `None` for `Custom`.
    pub fn default_of(kind: GaitKind) -> Option<Gait> {
        Self::of_kind(kind, kind.default_period_s(), kind.default_duty()).ok()
    }

    /// Four legs always in stance (duty 1); the period only paces the clock.
    pub fn stand() -> Gait {
        Gait {
            kind: GaitKind::Stand,
            period_s: GaitKind::Stand.default_period_s(),
            duty_factor: 1.0,
            offsets: [0.0; MAX_LEGS],
            legs: 4,
        }
    }

    /// Study A's trot, quad16's default: period 0.5 s, duty 0.7, offsets
    /// LF/RH 0, RF/LH 0.5 (four-leg support 0.1 s, diagonal support 0.15 s).
    pub fn study_a_trot() -> Gait {
        let mut offsets = [0.0; MAX_LEGS];
        offsets[..4].copy_from_slice(&[0.0, 0.5, 0.0, 0.5]);
        Gait {
            kind: GaitKind::Trot,
            period_s: STUDY_A_TROT_PERIOD_S,
            duty_factor: STUDY_A_TROT_DUTY,
            offsets,
            legs: 4,
        }
    }

    /// The whole-body walker's trot: period 0.5 s, four-leg support 0.02 s,
    /// each leg swinging for 0.23 s (duty 0.54).
    ///
    /// Why not Study A's 0.15 s swing: a swing foot must cover the body's
    /// advance over a whole period while it is in the air, so its
    /// acceleration grows as `v T / T_swing²`. quad16's legs are 4.5 kg each;
    /// over 0.15 s its hip pitch reaches the 100 N·m limit at about 0.7 m/s
    /// (measured under the whole-body layer), and a saturated swing breaks
    /// the dynamics the stance forces were planned with. Over 0.23 s the same
    /// torque carries the trot past 1.25 m/s.
    pub fn long_swing_trot() -> Gait {
        Self::trot_from_supports(0.5, 0.02, 0.23).expect("consistent supports")
    }

    /// The whole-body walker's walk: period 0.7 s, duty 0.7 (each leg swings
    /// for 0.21 s; two or three legs on the ground).
    ///
    /// The walk's default timing (period 1.0 s, duty 0.8) swings a leg over
    /// the body's advance of a whole second in 0.2 s: at 0.5 m/s that is
    /// 0.5 m, about 72 m/s² of minimum-jerk acceleration, and quad16's hips
    /// saturate in swing. Here the stride is 0.35 m and the acceleration
    /// about 46 m/s² (quad16 at 0.5 m/s, 24 perturbed copies: 2 falls at the
    /// default timing, 0 at this one; docs/validation.md, "Gaits"). A duty of
    /// exactly 0.75 is avoided: every lift-off then falls on another leg's
    /// touchdown, and 16 of 24 copies fell at period 0.8 s.
    pub fn whole_body_walk() -> Gait {
        Self::of_kind(GaitKind::Walk, 0.7, 0.7).expect("a valid walk")
    }

    /// A trot from its support times, as Study A gives it. Over one period the
    /// support sequence is: four legs (`four_leg_support_s`), one diagonal
    /// (`two_leg_support_s`), four legs, the other diagonal; so
    /// `period = 2 (four + two)` (checked to 1e-9 relative), each leg swings
    /// for `two_leg_support_s` and `duty = 1 − two / period`.
    ///
    /// # Errors
    /// [`GaitError::TrotSupports`] when the three times disagree, a support is
    /// negative, or the two-leg support is zero (no swing); then those of
    /// [`Gait::of_kind`].
    pub fn trot_from_supports(
        period_s: f64,
        four_leg_support_s: f64,
        two_leg_support_s: f64,
    ) -> Result<Gait, GaitError> {
        let err = GaitError::TrotSupports {
            period_s,
            four_leg_support_s,
            two_leg_support_s,
        };
        let sum = 2.0 * (four_leg_support_s + two_leg_support_s);
        let consistent = (sum - period_s).abs() <= 1e-9 * period_s.abs().max(1e-9);
        if !(four_leg_support_s >= 0.0 && two_leg_support_s > 0.0 && consistent) {
            return Err(err);
        }
        Self::of_kind(GaitKind::Trot, period_s, 1.0 - two_leg_support_s / period_s)
    }

    /// The named pattern, or `Custom`.
    pub fn kind(&self) -> GaitKind {
        self.kind
    }
    /// Period (s).
    pub fn period_s(&self) -> f64 {
        self.period_s
    }
    /// Duty factor: stance fraction of the period, in (0, 1].
    pub fn duty_factor(&self) -> f64 {
        self.duty_factor
    }
    /// Touchdown phase offsets, one per leg.
    pub fn offsets(&self) -> &[f64] {
        &self.offsets[..self.legs]
    }
    /// Number of legs.
    pub fn legs(&self) -> usize {
        self.legs
    }
    /// Scheduled stance time of one leg per period (s): `duty · T`.
    pub fn stance_duration_s(&self) -> f64 {
        self.duty_factor * self.period_s
    }
    /// Scheduled swing time of one leg per period (s): `(1 − duty) · T`; 0 for a stand.
    pub fn swing_duration_s(&self) -> f64 {
        (1.0 - self.duty_factor) * self.period_s
    }
    /// Whether legs ever swing (duty < 1).
    pub fn has_swing(&self) -> bool {
        self.duty_factor < 1.0
    }

    /// Leg `leg`'s own phase `frac(φ − offset)` at gait phase `gait_phase`.
    ///
    /// # Panics
    /// When `leg >= self.legs()`.
    pub fn leg_phase(&self, leg: usize, gait_phase: f64) -> f64 {
        assert!(leg < self.legs, "leg {leg} of a {}-legged gait", self.legs);
        wrap01(gait_phase - self.offsets[leg])
    }

    /// Whether the clock schedules leg `leg` in stance at gait phase `gait_phase`.
    ///
    /// # Panics
    /// When `leg >= self.legs()`.
    pub fn scheduled_stance(&self, leg: usize, gait_phase: f64) -> bool {
        self.leg_phase(leg, gait_phase) < self.duty_factor
    }

    /// Scheduled stance of every leg at gait phase `gait_phase` (entries past
    /// `legs()` are `false`).
    pub fn scheduled_support(&self, gait_phase: f64) -> [bool; MAX_LEGS] {
        let mut s = [false; MAX_LEGS];
        for (leg, st) in s.iter_mut().enumerate().take(self.legs) {
            *st = self.scheduled_stance(leg, gait_phase);
        }
        s
    }
}

/// `x` wrapped into [0, 1).
pub(crate) fn wrap01(x: f64) -> f64 {
    let w = x - x.floor();
    // `x − floor(x)` rounds to 1.0 for tiny negative x.
    if w >= 1.0 { 0.0 } else { w }
}
