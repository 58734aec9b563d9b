//! Run metrics, accumulated in the simulation at full rate (every step), not
//! from a decimated log. The exact definition of every metric is written in
//! `scenarios/README.md` ("Metrics"); the doc of each [`MetricsSummary`] field
//! repeats it in short.

use crate::spatial::yaw_from_rot;
use crate::support::stability_margin;
use glam::{DMat3, DVec2, DVec3};

/// Up to this many feet per robot are tracked for touchdowns and margins.
pub const MAX_FEET: usize = 8;

/// One foot's state in a step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootSample {
    /// Whether the foot touches the ground.
    pub in_contact: bool,
    /// Contact point in the world (m).
    pub position_m: DVec3,
    /// Ground reaction force on the foot (N, world).
    pub force_n: DVec3,
}

/// Everything the metrics need from one step (after integration, at time `t_s`).
#[derive(Clone, Copy, Debug)]
pub struct StepSample<'a> {
    /// Simulation time (s).
    pub t_s: f64,
    /// Step length (s): the weight of this sample in time integrals.
    pub dt_s: f64,
    /// Base (torso) origin in the world (m).
    pub base_position_m: DVec3,
    /// Base orientation (base → world).
    pub base_rotation: DMat3,
    /// Height of the base origin above the terrain beneath it (m).
    pub base_height_above_ground_m: f64,
    /// Whole-body centre of mass (m, world).
    pub com_m: DVec3,
    /// Velocity of the centre of mass (m/s, world).
    pub com_velocity_mps: DVec3,
    /// Height of the CoM above the terrain beneath it (m).
    pub com_height_above_ground_m: f64,
    /// Joint angles (rad), joints only.
    pub q_joints: &'a [f64],
    /// Joint velocities (rad/s).
    pub qd_joints: &'a [f64],
    /// Actuator torques applied at the joints (N·m).
    pub tau_joints: &'a [f64],
    /// Desired joint angles from the controller, when it tracks joint targets.
    pub q_desired: Option<&'a [f64]>,
    /// Feet.
    pub feet: &'a [FootSample],
    /// Whether the fall criteria hold in this step (see `scenarios/README.md`).
    pub fallen: bool,
}

/// The metrics of one robot over a run (SI units; angles in rad).
#[derive(Clone, Debug, PartialEq)]
pub struct MetricsSummary {
    /// Whether the robot fell.
    pub fell: bool,
    /// Time of the first fall (s), if any.
    pub fell_at_s: Option<f64>,
    /// Time-mean of the CoM velocity along the start heading (m/s).
    pub mean_forward_speed_mps: f64,
    /// Largest instantaneous CoM velocity along the start heading (m/s).
    pub peak_forward_speed_mps: f64,
    /// Time-mean height of the torso origin above the terrain beneath it (m).
    pub base_height_mean_m: f64,
    /// Peak-to-peak of that height (m).
    pub base_height_p2p_m: f64,
    /// Time-mean height of the whole-body CoM above the terrain beneath it (m).
    pub com_height_mean_m: f64,
    /// Peak-to-peak of that height (m).
    pub com_height_p2p_m: f64,
    /// [min, max] roll (rad).
    pub roll_range_rad: [f64; 2],
    /// [min, max] pitch (rad).
    pub pitch_range_rad: [f64; 2],
    /// [min, max] yaw, unwrapped (rad).
    pub yaw_range_rad: [f64; 2],
    /// √(mean over steps and joints of (θ_des − θ)²) (rad); `None` without joint targets.
    pub joint_rms_error_rad: Option<f64>,
    /// Largest vertical (world z) ground reaction force on one foot (N).
    pub max_foot_force_n: f64,
    /// ∫ Σ_j |τ_j θ̇_j| dt over the actuated joints (J).
    pub energy_j: f64,
    /// `energy_j` per foot touchdown; `None` when no foot touched down.
    pub energy_per_step_j: Option<f64>,
    /// Foot touchdowns (swing → stance transitions).
    pub steps: u64,
    /// Smallest stability margin over the steps with ≥ 3 feet in contact (m); `None` if never.
    pub min_stability_margin_m: Option<f64>,
    /// Net horizontal displacement of the CoM over the window (m).
    pub distance_m: f64,
    /// CoM displacement from the window's first to its last step (m), in the
    /// heading frame: x along the start heading, y to its left, z up.
    pub com_displacement_m: [f64; 3],
    /// `com_displacement_m` divided by the window's duration (m/s): Study B's
    /// "mean speed" per axis.
    pub com_mean_velocity_mps: [f64; 3],
    /// CoM oscillation amplitude per axis (m, heading frame): half the
    /// peak-to-peak of y and of z, and of x after removing the mean-velocity
    /// trend (x minus the straight line from its first to its last value).
    pub com_oscillation_m: [f64; 3],
    /// Largest |τ| per actuated joint (N·m, joint order of the model).
    pub joint_peak_abs_torque_nm: Vec<f64>,
    /// Time-mean of |τ| per actuated joint (N·m).
    pub joint_mean_abs_torque_nm: Vec<f64>,
}

/// Accumulates [`MetricsSummary`] step by step, without allocating.
#[derive(Clone, Debug)]
pub struct MetricsAccumulator {
    heading: DVec2,
    window_start_s: f64,
    started: bool,
    t0: f64,
    t_last: f64,
    time_s: f64,
    fell_at_s: Option<f64>,
    speed_integral: f64,
    peak_speed: f64,
    base_h: Stat,
    com_h: Stat,
    roll: RollRange,
    pitch: PitchRange,
    yaw: Range,
    /// The base's heading (its x axis in the horizontal plane) at the last
    /// step, for the yaw's increment ([`yaw_increment`]).
    heading_prev: DVec2,
    yaw_unwrapped: f64,
    err_sq: f64,
    err_n: u64,
    max_force: f64,
    energy: f64,
    touchdowns: u64,
    prev_contact: [bool; MAX_FEET],
    have_prev: bool,
    min_margin: Option<f64>,
    com_start: DVec3,
    com_end: DVec3,
    /// CoM in the heading frame at the window start.
    com_h0: DVec3,
    /// CoM y and z in the heading frame, relative to the window start.
    com_hy: Range,
    com_hz: Range,
    /// Upper and lower convex hulls of the points (t − t0, x_heading − x0): the
    /// extremes of x minus any straight line lie on them (see [`Hulls`]).
    x_hulls: Hulls,
    tau_peak: Vec<f64>,
    tau_abs_integral: Vec<f64>,
}

/// Upper and lower convex hulls of points arriving in increasing abscissa
/// (Andrew's monotone chain, one stack each). The maximum (minimum) of
/// `y − s·x` over all points, for any slope `s` known only at the end, is
/// attained at a vertex of the upper (lower) hull. Amortised O(1) per point;
/// the stacks are pre-sized for tens of gait cycles (a trot adds a few
/// vertices per cycle) and only a longer run grows them, a few times in all
/// (they double), not per step. (8 KiB per robot: herds keep thousands; 512
/// points each took 16 KiB.)
#[derive(Clone, Debug)]
struct Hulls {
    upper: Vec<DVec2>,
    lower: Vec<DVec2>,
}

impl Hulls {
    const CAPACITY: usize = 256;

    fn new() -> Self {
        Self {
            upper: Vec::with_capacity(Self::CAPACITY),
            lower: Vec::with_capacity(Self::CAPACITY),
        }
    }

    fn push(&mut self, p: DVec2) {
        let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
        // upper hull: keep clockwise turns
        while self.upper.len() >= 2
            && cross(
                self.upper[self.upper.len() - 2],
                self.upper[self.upper.len() - 1],
                p,
            ) >= 0.0
        {
            self.upper.pop();
        }
        self.upper.push(p);
        while self.lower.len() >= 2
            && cross(
                self.lower[self.lower.len() - 2],
                self.lower[self.lower.len() - 1],
                p,
            ) <= 0.0
        {
            self.lower.pop();
        }
        self.lower.push(p);
    }

    /// max − min over all points of `y − slope·x`.
    fn detrended_p2p(&self, slope: f64) -> f64 {
        let f = |p: &DVec2| p.y - slope * p.x;
        let hi = self.upper.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
        let lo = self.lower.iter().map(f).fold(f64::INFINITY, f64::min);
        if hi.is_finite() && lo.is_finite() {
            hi - lo
        } else {
            0.0
        }
    }
}

/// A time integral and the range of a sampled value.
#[derive(Clone, Copy, Debug)]
struct Stat {
    sum: f64,
    range: Range,
}

impl Stat {
    const EMPTY: Stat = Stat {
        sum: 0.0,
        range: Range::EMPTY,
    };
    fn add(&mut self, x: f64, w: f64) {
        self.sum += x * w;
        self.range.add(x);
    }
    fn p2p(&self) -> f64 {
        self.range.p2p()
    }
}

/// Smallest and largest value (an angle's range needs no time integral).
#[derive(Clone, Copy, Debug)]
struct Range {
    min: f64,
    max: f64,
}

impl Range {
    const EMPTY: Range = Range {
        min: f64::INFINITY,
        max: f64::NEG_INFINITY,
    };
    /// Adds `x`; returns whether the minimum and the maximum changed (their
    /// bits).
    fn add(&mut self, x: f64) -> (bool, bool) {
        let (min, max) = (self.min.min(x), self.max.max(x));
        let changed = (
            min.to_bits() != self.min.to_bits(),
            max.to_bits() != self.max.to_bits(),
        );
        (self.min, self.max) = (min, max);
        changed
    }
    fn range(&self) -> [f64; 2] {
        if self.min.is_finite() {
            [self.min, self.max]
        } else {
            [0.0, 0.0]
        }
    }
    fn p2p(&self) -> f64 {
        if self.min.is_finite() {
            self.max - self.min
        } else {
            0.0
        }
    }
}

/// Margin by which an argument must lie inside its extremes' arguments for
/// [`RollRange`] and [`PitchRange`] to skip the library call: the angles then
/// differ by more than 5·10⁻¹⁰ rad, some 10⁶ times the error of the
/// library's `atan2` and `asin` (about 1 ulp, < 2.3·10⁻¹⁶ rad below π/2), so
/// the computed angle lies strictly inside the computed extremes too and
/// adding it would change neither.
const INSIDE_MARGIN: f64 = 1e-9;

/// The range of the roll `atan2(y, z)` ([`crate::spatial::rpy_from_rot`]'s:
/// `y`, `z` the rotation's `y_axis.z` and `z_axis.z`), with
/// the arguments `(y, z)` of its extremes, so that a step whose roll
/// provably lies strictly between them skips the `atan2` (two per robot
/// and step otherwise, with the yaw's).
///
/// With `z`, `z_lo` > 0 the angles lie in (−π/2, π/2), their difference
/// `Δ` in (−π, π), and `z_lo·y − y_lo·z = |v|·|v_lo|·sin Δ` with
/// `|v|² = y² + z² ≤ 2` (a rotation's row has norm 1): a cross product above
/// [`INSIDE_MARGIN`] (whose rounding error is ~10⁻¹⁶) gives
/// `sin Δ > INSIDE_MARGIN / 2`, so `Δ > 5·10⁻¹⁰` rad. Likewise for the
/// maximum. Any other case (NaN included) takes the `atan2`.
#[derive(Clone, Copy, Debug)]
struct RollRange {
    range: Range,
    /// `(y, z)` of the minimum and of the maximum (NaN: none usable).
    lo: [f64; 2],
    hi: [f64; 2],
}

impl RollRange {
    const EMPTY: RollRange = RollRange {
        range: Range::EMPTY,
        lo: [f64::NAN; 2],
        hi: [f64::NAN; 2],
    };

    fn add(&mut self, r: &DMat3) {
        let (y, z) = (r.y_axis.z, r.z_axis.z);
        let [y_lo, z_lo] = self.lo;
        let [y_hi, z_hi] = self.hi;
        let inside = z > 0.0
            && z_lo > 0.0
            && z_hi > 0.0
            && y * y + z * z <= 2.0
            && z_lo * y - y_lo * z > INSIDE_MARGIN
            && y_hi * z - z_hi * y > INSIDE_MARGIN;
        if inside {
            return;
        }
        // `rpy_from_rot`'s roll
        let roll = y.atan2(z);
        let (new_min, new_max) = self.range.add(roll);
        // only arguments of norm² ≤ 2 serve as a bound
        let at = if y * y + z * z <= 2.0 {
            [y, z]
        } else {
            [f64::NAN; 2]
        };
        if new_min {
            self.lo = at;
        }
        if new_max {
            self.hi = at;
        }
    }
}

/// The range of the pitch `asin(s)` ([`crate::spatial::rpy_from_rot`]'s: `s`
/// the rotation's `−x_axis.z` clamped to [−1, 1]), with the arguments of its
/// extremes: `asin` increases with slope ≥ 1, so an `s` more than
/// [`INSIDE_MARGIN`] inside them (the difference rounded by < 2.3·10⁻¹⁶) has
/// a pitch more than 5·10⁻¹⁰ rad inside, and skips the `asin`.
#[derive(Clone, Copy, Debug)]
struct PitchRange {
    range: Range,
    /// `s` of the minimum and of the maximum (NaN: none yet).
    lo: f64,
    hi: f64,
}

impl PitchRange {
    const EMPTY: PitchRange = PitchRange {
        range: Range::EMPTY,
        lo: f64::NAN,
        hi: f64::NAN,
    };

    fn add(&mut self, r: &DMat3) {
        let sp = (-r.x_axis.z).clamp(-1.0, 1.0);
        if sp - self.lo > INSIDE_MARGIN && self.hi - sp > INSIDE_MARGIN {
            return;
        }
        // `rpy_from_rot`'s pitch
        let (new_min, new_max) = self.range.add(sp.asin());
        if new_min {
            self.lo = sp;
        }
        if new_max {
            self.hi = sp;
        }
    }
}

/// The yaw turned from heading `a` to heading `b` (the base's x axis in the
/// horizontal plane at two steps; rad, counter-clockwise positive, in
/// (−π, π]): `atan2(a × b, a · b)`. A step turns the base by well under
/// 0.01 rad (20 rad/s at 0.5 ms), where the arctangent's series to `t⁷`
/// is exact to f64 (its remainder `t⁹/9` < 1.2·10⁻¹⁹, below an ulp of
/// `t`): no library call per step, where the yaw's own `atan2` at every
/// step took ~130 instructions. Larger turns, and headings near vertical
/// (`a · b` ≤ 0), take `atan2`.
#[inline]
fn yaw_increment(a: DVec2, b: DVec2) -> f64 {
    let (c, s) = (a.dot(b), a.perp_dot(b));
    if c > 0.0 && s.abs() <= 0.01 * c {
        let t = s / c;
        let t2 = t * t;
        t - t * t2 * (1.0 / 3.0 - t2 * (1.0 / 5.0 - t2 * (1.0 / 7.0)))
    } else {
        s.atan2(c)
    }
}

/// `peak.max(x)` for a peak of absolute values (never NaN, never −0: it
/// starts at +0 and takes non-negative values): `x` when it is larger,
/// else `peak` (a NaN `x` too), the same bits as [`f64::max`] there, in one
/// instruction instead of `max`'s five (its NaN fix-up). The metrics' and
/// the actuator statistics' per-joint peaks, every step.
#[inline(always)]
pub(crate) fn max_of_peak(peak: f64, x: f64) -> f64 {
    if x > peak { x } else { peak }
}

impl MetricsAccumulator {
    /// Starts accumulating. `heading_yaw_rad` sets the forward direction
    /// (world yaw of the robot at the start); samples before `window_start_s`
    /// only update falls and touchdown history.
    pub fn new(heading_yaw_rad: f64, window_start_s: f64) -> Self {
        Self {
            heading: DVec2::new(heading_yaw_rad.cos(), heading_yaw_rad.sin()),
            window_start_s,
            started: false,
            t0: 0.0,
            t_last: 0.0,
            time_s: 0.0,
            fell_at_s: None,
            speed_integral: 0.0,
            peak_speed: f64::NEG_INFINITY,
            base_h: Stat::EMPTY,
            com_h: Stat::EMPTY,
            roll: RollRange::EMPTY,
            pitch: PitchRange::EMPTY,
            yaw: Range::EMPTY,
            heading_prev: DVec2::ZERO,
            yaw_unwrapped: 0.0,
            err_sq: 0.0,
            err_n: 0,
            max_force: 0.0,
            energy: 0.0,
            touchdowns: 0,
            prev_contact: [false; MAX_FEET],
            have_prev: false,
            min_margin: None,
            com_start: DVec3::ZERO,
            com_end: DVec3::ZERO,
            com_h0: DVec3::ZERO,
            com_hy: Range::EMPTY,
            com_hz: Range::EMPTY,
            x_hulls: Hulls::new(),
            tau_peak: Vec::new(),
            tau_abs_integral: Vec::new(),
        }
    }

    /// A world point in the heading frame (x along the start heading, y left, z up).
    fn heading_frame(&self, p: DVec3) -> DVec3 {
        DVec3::new(
            p.truncate().dot(self.heading),
            self.heading.perp_dot(p.truncate()),
            p.z,
        )
    }

    /// Adds one step.
    pub fn record(&mut self, s: &StepSample<'_>) {
        // an x86-64-v3 clone (three-operand VEX forms, wider vectors; no
        // fused multiply–add, so the same bits), in a free function:
        // multiversion takes no `self`
        #[multiversion::multiversion(targets("x86_64+avx2+fma"))]
        fn body(this: &mut MetricsAccumulator, s: &StepSample<'_>) {
            if s.fallen && this.fell_at_s.is_none() {
                this.fell_at_s = Some(s.t_s);
            }
            // roll and pitch only count in the window (below)
            let heading = s.base_rotation.x_axis.truncate();
            if !this.have_prev {
                this.yaw_unwrapped = yaw_from_rot(s.base_rotation);
            } else {
                this.yaw_unwrapped += yaw_increment(this.heading_prev, heading);
            }
            this.heading_prev = heading;
            let in_window = s.t_s >= this.window_start_s - 1e-12;
            let mut touchdowns = 0;
            for (i, f) in s.feet.iter().take(MAX_FEET).enumerate() {
                if this.have_prev && f.in_contact && !this.prev_contact[i] {
                    touchdowns += 1;
                }
                this.prev_contact[i] = f.in_contact;
            }
            this.have_prev = true;
            if !in_window {
                return;
            }
            if !this.started {
                this.started = true;
                this.t0 = s.t_s;
                this.com_start = s.com_m;
                this.com_h0 = this.heading_frame(s.com_m);
            }
            this.touchdowns += touchdowns;
            this.t_last = s.t_s;
            this.time_s += s.dt_s;
            this.com_end = s.com_m;
            let ch = this.heading_frame(s.com_m) - this.com_h0;
            this.com_hy.add(ch.y);
            this.com_hz.add(ch.z);
            this.x_hulls.push(DVec2::new(s.t_s - this.t0, ch.x));
            if this.tau_peak.len() != s.tau_joints.len() {
                // only when the robot's joint count changes (first step, recompile)
                this.tau_peak = vec![0.0; s.tau_joints.len()];
                this.tau_abs_integral = vec![0.0; s.tau_joints.len()];
            }
            // zipped slices of one length: no bounds checks, and the
            // element-wise loop vectorises (the same operations per joint)
            for ((peak, integral), tau) in this
                .tau_peak
                .iter_mut()
                .zip(this.tau_abs_integral.iter_mut())
                .zip(s.tau_joints)
            {
                let a = tau.abs();
                *peak = max_of_peak(*peak, a);
                *integral += a * s.dt_s;
            }
            let v_fwd = s.com_velocity_mps.truncate().dot(this.heading);
            this.speed_integral += v_fwd * s.dt_s;
            this.peak_speed = this.peak_speed.max(v_fwd);
            this.base_h.add(s.base_height_above_ground_m, s.dt_s);
            this.com_h.add(s.com_height_above_ground_m, s.dt_s);
            this.roll.add(&s.base_rotation);
            this.pitch.add(&s.base_rotation);
            this.yaw.add(this.yaw_unwrapped);
            // the sums in locals, in the same order: written back once, not
            // stored at every term
            if let Some(qd) = s.q_desired {
                let mut err_sq = this.err_sq;
                for (d, q) in qd.iter().zip(s.q_joints) {
                    err_sq += (d - q) * (d - q);
                }
                this.err_sq = err_sq;
                this.err_n += qd.len().min(s.q_joints.len()) as u64;
            }
            let mut energy = this.energy;
            for (tau, qd) in s.tau_joints.iter().zip(s.qd_joints) {
                energy += (tau * qd).abs() * s.dt_s;
            }
            this.energy = energy;
            let mut pts = [DVec2::ZERO; MAX_FEET];
            let mut n = 0;
            for f in s.feet.iter().take(MAX_FEET) {
                this.max_force = this.max_force.max(f.force_n.z);
                if f.in_contact {
                    pts[n] = f.position_m.truncate();
                    n += 1;
                }
            }
            if let Some(m) = stability_margin(&pts[..n], s.com_m.truncate()) {
                this.min_margin = Some(this.min_margin.map_or(m, |x: f64| x.min(m)));
            }
        }
        body(self, s)
    }

    /// The summary so far.
    pub fn summary(&self) -> MetricsSummary {
        let t = self.time_s;
        let mean = |st: &Stat| if t > 0.0 { st.sum / t } else { 0.0 };
        let disp = if self.started {
            self.heading_frame(self.com_end) - self.com_h0
        } else {
            DVec3::ZERO
        };
        let span_s = self.t_last - self.t0;
        let x_slope = if span_s > 0.0 { disp.x / span_s } else { 0.0 };
        MetricsSummary {
            fell: self.fell_at_s.is_some(),
            fell_at_s: self.fell_at_s,
            mean_forward_speed_mps: if t > 0.0 {
                self.speed_integral / t
            } else {
                0.0
            },
            peak_forward_speed_mps: if self.peak_speed.is_finite() {
                self.peak_speed
            } else {
                0.0
            },
            base_height_mean_m: mean(&self.base_h),
            base_height_p2p_m: self.base_h.p2p(),
            com_height_mean_m: mean(&self.com_h),
            com_height_p2p_m: self.com_h.p2p(),
            roll_range_rad: self.roll.range.range(),
            pitch_range_rad: self.pitch.range.range(),
            yaw_range_rad: self.yaw.range(),
            joint_rms_error_rad: (self.err_n > 0).then(|| (self.err_sq / self.err_n as f64).sqrt()),
            max_foot_force_n: self.max_force,
            energy_j: self.energy,
            energy_per_step_j: (self.touchdowns > 0).then(|| self.energy / self.touchdowns as f64),
            steps: self.touchdowns,
            min_stability_margin_m: self.min_margin,
            distance_m: (self.com_end - self.com_start).truncate().length(),
            com_displacement_m: disp.to_array(),
            com_mean_velocity_mps: if t > 0.0 {
                (disp / t).to_array()
            } else {
                [0.0; 3]
            },
            com_oscillation_m: [
                0.5 * self.x_hulls.detrended_p2p(x_slope),
                0.5 * self.com_hy.p2p(),
                0.5 * self.com_hz.p2p(),
            ],
            joint_peak_abs_torque_nm: self.tau_peak.clone(),
            joint_mean_abs_torque_nm: self
                .tau_abs_integral
                .iter()
                .map(|i| if t > 0.0 { i / t } else { 0.0 })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample<'a>(
        t: f64,
        dt: f64,
        com: DVec3,
        vel: DVec3,
        feet: &'a [FootSample],
        tau: &'a [f64],
        qd: &'a [f64],
    ) -> StepSample<'a> {
        StepSample {
            t_s: t,
            dt_s: dt,
            base_position_m: com,
            base_rotation: DMat3::IDENTITY,
            base_height_above_ground_m: com.z,
            com_m: com,
            com_velocity_mps: vel,
            com_height_above_ground_m: com.z,
            q_joints: qd,
            qd_joints: qd,
            tau_joints: tau,
            q_desired: None,
            feet,
            fallen: false,
        }
    }

    /// The yaw increment is the wrapped difference of the headings' yaws
    /// (atan2) within 1.5e-15 rad (the reference's own rounding: two angles
    /// up to π, each within an ulp, 4.4e-16), on its series (turns up to 0.01 rad) and
    /// on `atan2` (larger turns, across ±π too), with headings of norms
    /// from 0.3 to 1 (a pitched base).
    #[test]
    fn yaw_increment_is_the_wrapped_yaw_difference() {
        let tau = std::f64::consts::TAU;
        let mut worst = 0.0f64;
        for i in 0..2000 {
            let yaw = -3.2 + 6.4 * (i as f64 * 0.618_033_988_749_895).fract();
            let turn = [1e-12, -3e-7, 2e-4, -0.004, 0.0099, -0.0101, 0.3, -2.9][i % 8];
            let (ra, rb) = (0.3 + 0.7 * ((i * 7) % 11) as f64 / 10.0, 1.0);
            let a = DVec2::new(yaw.cos(), yaw.sin()) * ra;
            let b = DVec2::new((yaw + turn).cos(), (yaw + turn).sin()) * rb;
            let mut d = b.y.atan2(b.x) - a.y.atan2(a.x);
            d -= (d / tau).round() * tau;
            worst = worst.max((yaw_increment(a, b) - d).abs());
        }
        assert!(worst < 1.5e-15, "worst {worst:e} rad");
    }

    /// A base turning at 3 rad/s about the vertical for 5 s (across ±π
    /// twice) has the yaw range [yaw₀, yaw₀ + 15 rad], unwrapped.
    #[test]
    fn yaw_range_unwraps_a_steady_turn() {
        let (yaw0, rate, dt) = (2.5, 3.0, 0.0005);
        let mut m = MetricsAccumulator::new(yaw0, 0.0);
        for k in 0..=10_000 {
            let t = k as f64 * dt;
            let mut s = sample(t, dt, DVec3::Z * 0.5, DVec3::ZERO, &[], &[], &[]);
            s.base_rotation = DMat3::from_rotation_z(yaw0 + rate * t);
            m.record(&s);
        }
        let [lo, hi] = m.summary().yaw_range_rad;
        assert!((lo - yaw0).abs() < 1e-12, "{lo}");
        assert!((hi - (yaw0 + 15.0)).abs() < 1e-12, "{hi}");
    }

    #[test]
    fn body_driven_at_one_metre_per_second() {
        // A body moved at exactly 1 m/s along its heading (yaw 30°) for 2 s.
        let yaw = 30f64.to_radians();
        let dir = DVec3::new(yaw.cos(), yaw.sin(), 0.0);
        let mut m = MetricsAccumulator::new(yaw, 0.0);
        let dt = 0.001;
        for k in 1..=2000 {
            let t = k as f64 * dt;
            m.record(&sample(t, dt, dir * t + DVec3::Z * 0.5, dir, &[], &[], &[]));
        }
        let s = m.summary();
        assert!(
            (s.mean_forward_speed_mps - 1.0).abs() < 1e-12,
            "{}",
            s.mean_forward_speed_mps
        );
        assert!((s.peak_forward_speed_mps - 1.0).abs() < 1e-12);
        assert!((s.distance_m - 1.999).abs() < 1e-9, "{}", s.distance_m);
        assert_eq!(s.base_height_p2p_m, 0.0);
    }

    #[test]
    fn joint_energy_is_the_analytic_integral() {
        // τ = 2 N·m at θ̇ = −3 rad/s on one joint and 1 N·m at 1 rad/s on another for 1.5 s:
        // E = (|2·(−3)| + |1·1|)·1.5 = 10.5 J
        let mut m = MetricsAccumulator::new(0.0, 0.0);
        let dt = 0.0005;
        for k in 1..=3000 {
            m.record(&sample(
                k as f64 * dt,
                dt,
                DVec3::Z,
                DVec3::ZERO,
                &[],
                &[2.0, 1.0],
                &[-3.0, 1.0],
            ));
        }
        assert!((m.summary().energy_j - 10.5).abs() < 1e-9);
    }

    #[test]
    fn touchdowns_and_margin() {
        let mut feet = [
            FootSample {
                in_contact: true,
                position_m: DVec3::new(0.25, 0.15, 0.0),
                force_n: DVec3::Z * 70.0,
            },
            FootSample {
                in_contact: true,
                position_m: DVec3::new(0.25, -0.15, 0.0),
                force_n: DVec3::Z * 70.0,
            },
            FootSample {
                in_contact: true,
                position_m: DVec3::new(-0.25, -0.15, 0.0),
                force_n: DVec3::Z * 70.0,
            },
            FootSample {
                in_contact: true,
                position_m: DVec3::new(-0.25, 0.15, 0.0),
                force_n: DVec3::Z * 70.0,
            },
        ];
        let mut m = MetricsAccumulator::new(0.0, 0.0);
        m.record(&sample(
            0.001,
            0.001,
            DVec3::new(-0.05, 0.0, 0.5),
            DVec3::ZERO,
            &feet,
            &[],
            &[],
        ));
        feet[0].in_contact = false;
        m.record(&sample(
            0.002,
            0.001,
            DVec3::new(-0.05, 0.0, 0.5),
            DVec3::ZERO,
            &feet,
            &[],
            &[],
        ));
        feet[0].in_contact = true;
        feet[0].force_n.z = 150.0;
        m.record(&sample(
            0.003,
            0.001,
            DVec3::new(-0.05, 0.0, 0.5),
            DVec3::ZERO,
            &feet,
            &[],
            &[],
        ));
        let s = m.summary();
        assert_eq!(s.steps, 1);
        assert_eq!(s.max_foot_force_n, 150.0);
        // with foot 0 lifted, the CoM projection (−0.05, 0) is nearest to the
        // diagonal y = −0.6 x: distance |0.3·(−0.05) − (−0.5)·0| / √(0.5² + 0.3²)
        let diag = (0.5f64 * 0.5 + 0.3 * 0.3).sqrt();
        let tri_margin = 0.015 / diag;
        assert!((s.min_stability_margin_m.unwrap() - tri_margin).abs() < 1e-12);
    }

    #[test]
    fn oscillation_amplitudes_and_per_axis_speeds() {
        // Heading 90° (world +y is forward). In the heading frame the CoM moves
        // x = 0.1 t + 0.005 sin(4πt), y = 0.009 sin(2πt), z = 0.3 + 0.001 cos(4πt)
        // for 5 s (whole periods): amplitudes 5, 9, 1 mm; mean speed 0.1 m/s forward.
        let yaw = std::f64::consts::FRAC_PI_2;
        let mut m = MetricsAccumulator::new(yaw, 0.0);
        let dt = 0.0005;
        let tau = std::f64::consts::TAU;
        for k in 0..=10_000 {
            let t = k as f64 * dt;
            let (x, y) = (
                0.1 * t + 0.005 * (2.0 * tau * t).sin(),
                0.009 * (tau * t).sin(),
            );
            let z = 0.3 + 0.001 * (2.0 * tau * t).cos();
            // heading frame → world: x along +y, y (left) along −x
            let com = DVec3::new(-y, x, z);
            m.record(&sample(t, dt, com, DVec3::ZERO, &[], &[], &[]));
        }
        let s = m.summary();
        let o = s.com_oscillation_m;
        assert!((o[0] - 0.005).abs() < 1e-6, "{o:?}");
        assert!((o[1] - 0.009).abs() < 1e-6, "{o:?}");
        assert!((o[2] - 0.001).abs() < 1e-6, "{o:?}");
        let d = s.com_displacement_m;
        assert!(
            (d[0] - 0.5).abs() < 1e-9 && d[1].abs() < 1e-9 && d[2].abs() < 1e-9,
            "{d:?}"
        );
        let v = s.com_mean_velocity_mps;
        assert!((v[0] - 0.5 / (10_001.0 * dt)).abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn per_joint_peak_and_mean_torque() {
        // τ0 = 2 sin(2πt), τ1 = −3 over one second: peak 2 and 3 N·m, mean |τ| 4/π and 3 N·m.
        let mut m = MetricsAccumulator::new(0.0, 0.0);
        let n = 100_000;
        let dt = 1.0 / n as f64;
        for k in 0..n {
            let t = (k as f64 + 0.5) * dt;
            let tau = [2.0 * (std::f64::consts::TAU * t).sin(), -3.0];
            m.record(&sample(
                t,
                dt,
                DVec3::Z,
                DVec3::ZERO,
                &[],
                &tau,
                &[0.0, 0.0],
            ));
        }
        let s = m.summary();
        assert!((s.joint_peak_abs_torque_nm[0] - 2.0).abs() < 1e-6);
        assert_eq!(s.joint_peak_abs_torque_nm[1], 3.0);
        assert!((s.joint_mean_abs_torque_nm[0] - 4.0 / std::f64::consts::PI).abs() < 1e-6);
        assert!((s.joint_mean_abs_torque_nm[1] - 3.0).abs() < 1e-9);
    }
    /// The roll and pitch ranges that skip the library calls are those of
    /// `rpy_from_rot` over every sample, bit for bit: on a wobbling base
    /// (extremes reached again and again, and samples near them), tilted
    /// past the vertical too (z ≤ 0: the exact path).
    #[test]
    fn roll_and_pitch_ranges_are_rpy_from_rots() {
        use crate::spatial::{rot_from_rpy, rpy_from_rot};
        let mut roll = RollRange::EMPTY;
        let mut pitch = PitchRange::EMPTY;
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for k in 0..20_000 {
            let t = k as f64 * 0.0005;
            let amp = if k > 15_000 { 2.0 } else { 0.2 };
            let rpy = DVec3::new(
                amp * (7.0 * t).sin() + 1e-10 * (k % 3) as f64,
                0.15 * (5.0 * t).cos() * (1.0 + 0.1 * (0.3 * t).sin()),
                0.4 * t,
            );
            let r = rot_from_rpy(rpy);
            roll.add(&r);
            pitch.add(&r);
            let e = rpy_from_rot(r);
            (lo, hi) = (lo.min(e), hi.max(e));
            assert_eq!(roll.range.range(), [lo.x, hi.x], "roll at {k}");
            assert_eq!(pitch.range.range(), [lo.y, hi.y], "pitch at {k}");
        }
    }
}
