//! Swing foot trajectories: from the lift-off point to the touchdown target,
//! at rest at both ends, with a given apex height.
//!
//! Every axis follows the minimum-jerk step `b(u) = 10u³ − 15u⁴ + 6u⁵`, which
//! is the quintic Bézier curve with control points `(0, 0, 0, 1, 1, 1)`:
//! velocity **and acceleration** are zero at both ends, so the references a
//! controller tracks (and their feed-forward) start and end smoothly.
//!
//! - Horizontal (x, y): one step from lift-off to target over the whole swing.
//! - Vertical (z): a rise from the lift-off height to the apex over the first
//!   half of the swing, then a fall to the target height over the second half.
//!   Each half is monotone, so the apex (at progress ½) is the highest point,
//!   and z is C² at the apex (both halves end with zero velocity and acceleration).
//!
//! The apex is `max(z_liftoff, z_target) + lift_height`: the lift height is the
//! clearance above the higher end (Study A: 0.17 m on flat ground, quad16's
//! default [`DEFAULT_LIFT_HEIGHT_M`]). Points are in any frame whose z is up
//! (world, or the heading frame); time derivatives are per second of the
//! swing's duration.

use glam::DVec3;

/// Study A's swing lift height (m), quad16's default.
pub const DEFAULT_LIFT_HEIGHT_M: f64 = 0.17;

/// Peak of `|b''(u)|` for the minimum-jerk step on `u ∈ [0, 1]`: `10/√3`, at
/// `u = (3 ± √3)/6`.
pub const MIN_JERK_PEAK_ACC: f64 = 5.773_502_691_896_258;
/// Peak of `b'(u)`: `15/8`, at `u = ½`.
pub const MIN_JERK_PEAK_VEL: f64 = 1.875;

/// The minimum-jerk step and its first two derivatives `(b, b', b'')` at `u`
/// clamped to [0, 1].
pub fn min_jerk(u: f64) -> (f64, f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let v = 1.0 - u;
    (
        u * u * u * (10.0 - 15.0 * u + 6.0 * u * u),
        30.0 * u * u * v * v,
        60.0 * u * v * (1.0 - 2.0 * u),
    )
}

/// A foot reference: position (m), velocity (m/s) and acceleration (m/s²),
/// in the trajectory's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwingSample {
    /// Position (m).
    pub pos_m: DVec3,
    /// Velocity (m/s).
    pub vel_m_s: DVec3,
    /// Acceleration (m/s²): for a feed-forward `τ = M(q) J⁺ (a − J̇ q̇) + h`.
    pub acc_m_s2: DVec3,
}

/// One swing (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwingTrajectory {
    /// Lift-off point (m).
    pub start_m: DVec3,
    /// Touchdown target (m).
    pub end_m: DVec3,
    /// Apex height (m, same frame's z).
    pub apex_z_m: f64,
    /// Swing duration (s); zero or negative gives positions with zero derivatives.
    pub duration_s: f64,
}

impl SwingTrajectory {
    /// A swing from `start_m` to `end_m` in `duration_s` with its apex
    /// `lift_height_m` above the higher of the two.
    pub fn new(
        start_m: DVec3,
        end_m: DVec3,
        lift_height_m: f64,
        duration_s: f64,
    ) -> SwingTrajectory {
        SwingTrajectory {
            start_m,
            end_m,
            apex_z_m: start_m.z.max(end_m.z) + lift_height_m,
            duration_s,
        }
    }

    /// The reference at swing progress `progress` (time since lift-off over
    /// duration, clamped to [0, 1]).
    pub fn sample(&self, progress: f64) -> SwingSample {
        let s = progress.clamp(0.0, 1.0);
        let (inv_t, inv_t2) = if self.duration_s > 0.0 {
            (
                1.0 / self.duration_s,
                1.0 / (self.duration_s * self.duration_s),
            )
        } else {
            (0.0, 0.0)
        };
        let (b, db, ddb) = min_jerk(s);
        let d = self.end_m - self.start_m;
        // Each vertical half runs on u = 2s (resp. 2s − 1): du/dt = 2/T.
        let (z0, z1, u) = if s < 0.5 {
            (self.start_m.z, self.apex_z_m, 2.0 * s)
        } else {
            (self.apex_z_m, self.end_m.z, 2.0 * s - 1.0)
        };
        let (bz, dbz, ddbz) = min_jerk(u);
        let dz = z1 - z0;
        SwingSample {
            pos_m: DVec3::new(
                self.start_m.x + d.x * b,
                self.start_m.y + d.y * b,
                z0 + dz * bz,
            ),
            vel_m_s: DVec3::new(d.x * db * inv_t, d.y * db * inv_t, dz * dbz * 2.0 * inv_t),
            acc_m_s2: DVec3::new(
                d.x * ddb * inv_t2,
                d.y * ddb * inv_t2,
                dz * ddbz * 4.0 * inv_t2,
            ),
        }
    }

    /// The reference `late_s` seconds after the scheduled end while still
    /// without contact: the target lowered along −z by [`ReachDown::depth`].
    pub fn sample_late(&self, late_s: f64, reach: &ReachDown) -> SwingSample {
        let (d, v, a) = reach.depth(late_s);
        SwingSample {
            pos_m: self.end_m - DVec3::Z * d,
            vel_m_s: -DVec3::Z * v,
            acc_m_s2: -DVec3::Z * a,
        }
    }

    /// Largest vertical rise or fall of a half swing (m).
    fn vertical_travel_m(&self) -> f64 {
        (self.apex_z_m - self.start_m.z)
            .abs()
            .max((self.apex_z_m - self.end_m.z).abs())
    }

    /// Peak vertical foot speed (m/s): `15/8 · Δz / (T/2)`. Study A's 0.17 m in
    /// a 0.15 s swing: 4.25 m/s.
    pub fn peak_vertical_speed_m_s(&self) -> f64 {
        MIN_JERK_PEAK_VEL * self.vertical_travel_m() * 2.0 / self.duration_s
    }

    /// Peak vertical foot acceleration (m/s²): `10/√3 · Δz / (T/2)²`, the
    /// inertial load a lift height costs the swing leg. Study A's 0.17 m in a
    /// 0.15 s swing: about 174.5 m/s² (18 g).
    pub fn peak_vertical_acceleration_m_s2(&self) -> f64 {
        MIN_JERK_PEAK_ACC * self.vertical_travel_m() * 4.0 / (self.duration_s * self.duration_s)
    }

    /// Peak horizontal foot acceleration (m/s²): `10/√3 · |Δxy| / T²`.
    pub fn peak_horizontal_acceleration_m_s2(&self) -> f64 {
        let d = self.end_m - self.start_m;
        MIN_JERK_PEAK_ACC * d.truncate().length() / (self.duration_s * self.duration_s)
    }
}

/// How a late foot reaches down for the ground (scheduler rule 3): the depth
/// below the touchdown target grows with constant acceleration for `ramp_s`
/// up to `speed_m_s`, then at that speed, and stops at `max_depth_m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReachDown {
    /// Descent speed after the ramp (m/s). Default 0.5 m/s: a 5 cm step down
    /// is found in about 0.11 s.
    pub speed_m_s: f64,
    /// Time to reach that speed from rest (s). Default 0.02 s.
    pub ramp_s: f64,
    /// Deepest reach below the target (m). Default 0.15 m.
    pub max_depth_m: f64,
}

impl Default for ReachDown {
    fn default() -> Self {
        ReachDown {
            speed_m_s: 0.5,
            ramp_s: 0.02,
            max_depth_m: 0.15,
        }
    }
}

impl ReachDown {
    /// Depth (m, ≥ 0, downward), its rate (m/s) and acceleration (m/s²)
    /// `late_s` seconds after the scheduled end of the swing.
    pub fn depth(&self, late_s: f64) -> (f64, f64, f64) {
        let t = late_s.max(0.0);
        let (d, v, a) = if self.ramp_s > 0.0 && t < self.ramp_s {
            let acc = self.speed_m_s / self.ramp_s;
            (0.5 * acc * t * t, acc * t, acc)
        } else {
            (
                self.speed_m_s * (t - 0.5 * self.ramp_s.max(0.0)),
                self.speed_m_s,
                0.0,
            )
        };
        if d >= self.max_depth_m {
            (self.max_depth_m, 0.0, 0.0)
        } else {
            (d, v, a)
        }
    }
}
