//! Swing foot trajectories: from the lift-off point to the touchdown target,
//! at rest at both ends, with a given apex height.
//!
//! Every axis follows the minimum-jerk step `b(u) = 10u³ − 15u⁴ + 6u⁵`, which
//! is the quintic Bézier curve with control points `(0, 0, 0, 1, 1, 1)`:
//! velocity **and acceleration** are zero at both ends, so the references a
//! controller tracks (and their feed-forward) start and end smoothly.
//!
//! - Horizontal (x, y): one step from lift-off to target over the whole
//!   swing; onto a step or a stair the foot first rises, and off one it first
//!   moves over ([`SwingTrajectory::horizontal_window`]).
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
    /// How much the ground rises from under the lift-off point to under the
    /// target (m): `end_m.z − start_m.z` unless the caller knows the ground
    /// ([`Self::over_ground`]); a foot that has sunk into soft ground lifts
    /// off below the surface without there being a step.
    pub ground_rise_m: f64,
    /// How far the ground between the two pokes above the straight line
    /// from the ground under the lift-off point to the ground under the
    /// target (m): a step's edge does, a smooth wave hardly. Without
    /// knowledge of the ground, `|ground_rise_m|` (as if it were a step).
    pub ground_obstacle_m: f64,
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
            ground_rise_m: end_m.z - start_m.z,
            ground_obstacle_m: (end_m.z - start_m.z).abs(),
        }
    }

    /// This swing over ground that rises by `rise_m` (m) from under its
    /// lift-off point to under its target, with an obstacle `obstacle_m`
    /// (m) above the line between them ([`Self::ground_obstacle_m`]).
    pub fn over_ground(self, rise_m: f64, obstacle_m: f64) -> Self {
        SwingTrajectory {
            ground_rise_m: rise_m,
            ground_obstacle_m: obstacle_m,
            ..self
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
        let d = self.end_m - self.start_m;
        let (h0, h1) = self.horizontal_window();
        let (b, db, ddb) = if (h0, h1) == (0.0, 1.0) {
            min_jerk(s)
        } else {
            // the horizontal step runs on (s − h0)/(h1 − h0)
            let w = 1.0 / (h1 - h0);
            let (b, db, ddb) = min_jerk((s - h0) * w);
            (b, db * w, ddb * w * w)
        };
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

    /// Where in the swing (progress from, to) the horizontal step is made.
    /// Over the whole swing, unless the ground between the ends pokes more
    /// than half the lift height above the line between them (a step or a
    /// stair's edge, not a smooth wave):
    /// then, stepping up, the foot rises before it moves over (up to 30 %
    /// of the swing, reached at a rise of one lift height) so that it
    /// clears the riser it starts in front of; stepping down, it moves over
    /// first, so that it clears the edge it leaves before it descends.
    pub fn horizontal_window(&self) -> (f64, f64) {
        const DELAY: f64 = 0.3;
        let lift = self.apex_z_m - self.start_m.z.max(self.end_m.z);
        if lift <= 0.0 {
            return (0.0, 1.0);
        }
        let obstacle = self.ground_obstacle_m;
        if obstacle <= 0.5 * lift {
            return (0.0, 1.0);
        }
        let share = DELAY * ((obstacle / lift - 0.5) / 0.5).clamp(0.0, 1.0);
        if self.ground_rise_m >= 0.0 {
            (share, 1.0)
        } else {
            (0.0, 1.0 - share)
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
        let (h0, h1) = self.horizontal_window();
        let t = (h1 - h0) * self.duration_s;
        MIN_JERK_PEAK_ACC * d.truncate().length() / (t * t)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Lowest height of the foot (its sphere's bottom) over the swing while
    /// it is horizontally within a foot radius (3 cm) of an edge at `edge_x`.
    fn lowest_near(t: &SwingTrajectory, edge_x: f64) -> f64 {
        (0..=4000)
            .map(|k| t.sample(k as f64 / 4000.0).pos_m)
            .filter(|p| (p.x - edge_x).abs() <= 0.03)
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_foot_clears_the_riser_it_steps_up_and_the_edge_it_steps_down() {
        // a 0.1 m step at x = 0.05, the foot lifting 5 cm in front of it
        // for a 0.4 m step, lift height 5 cm
        let up = SwingTrajectory::new(DVec3::ZERO, DVec3::new(0.4, 0.0, 0.1), 0.05, 0.23);
        assert_eq!(up.horizontal_window(), (0.3, 1.0));
        assert!(
            lowest_near(&up, 0.05) > 0.1 + 0.02,
            "over the riser at {:.3} m",
            lowest_near(&up, 0.05)
        );
        // the same step made over the whole swing would hit the riser
        let plain = SwingTrajectory {
            apex_z_m: 0.15,
            ..SwingTrajectory::new(DVec3::ZERO, DVec3::new(0.4, 0.0, 0.0), 0.15, 0.23)
        };
        assert!(lowest_near(&plain, 0.05) < 0.1);
        // stepping down off an edge 5 cm before the target
        let down = SwingTrajectory::new(
            DVec3::new(0.0, 0.0, 0.1),
            DVec3::new(0.4, 0.0, 0.0),
            0.05,
            0.23,
        );
        assert_eq!(down.horizontal_window(), (0.0, 0.7));
        assert!(
            lowest_near(&down, 0.35) > 0.1 + 0.02,
            "{}",
            lowest_near(&down, 0.35)
        );
        // ends and derivatives: at rest at both ends, the acceleration
        // bounded by the compressed step's peak
        for t in [up, down] {
            let (a, b) = (t.sample(0.0), t.sample(1.0));
            assert_eq!(a.pos_m, t.start_m);
            assert!((b.pos_m - t.end_m).length() < 1e-15);
            assert_eq!(a.vel_m_s, DVec3::ZERO);
            assert!(b.vel_m_s.length() < 1e-12);
            let peak = (0..=4000)
                .map(|k| t.sample(k as f64 / 4000.0).acc_m_s2.x.abs())
                .fold(0.0, f64::max);
            assert!(peak <= t.peak_horizontal_acceleration_m_s2() * (1.0 + 1e-9));
            assert!(peak > 0.99 * t.peak_horizontal_acceleration_m_s2());
        }
    }

    #[test]
    fn level_and_gently_sloped_swings_step_over_the_whole_swing() {
        for dz in [0.0, 0.02, -0.025] {
            let t = SwingTrajectory::new(DVec3::ZERO, DVec3::new(0.4, 0.1, dz), 0.05, 0.23);
            assert_eq!(t.horizontal_window(), (0.0, 1.0));
            // the same bits as the plain minimum-jerk step
            for k in 0..=10 {
                let s = k as f64 / 10.0;
                let (b, _, _) = min_jerk(s);
                assert_eq!(t.sample(s).pos_m.x, 0.4 * b);
            }
        }
    }

    #[test]
    fn the_velocity_is_the_derivative_of_the_position_in_a_windowed_step() {
        let t = SwingTrajectory::new(DVec3::ZERO, DVec3::new(0.4, 0.0, 0.035), 0.05, 0.25);
        let (h0, _) = t.horizontal_window();
        assert!(h0 > 0.0 && h0 < 0.3);
        let eps = 1e-6;
        // (off the apex, s = ½, where the vertical jerk jumps)
        for k in 0..20 {
            let s = (k as f64 + 0.5) / 20.0;
            let fd =
                (t.sample(s + eps).pos_m - t.sample(s - eps).pos_m) / (2.0 * eps * t.duration_s);
            assert!(
                (fd - t.sample(s).vel_m_s).length() < 1e-6,
                "at {s}: {fd} vs {}",
                t.sample(s).vel_m_s
            );
            let fa = (t.sample(s + eps).vel_m_s - t.sample(s - eps).vel_m_s)
                / (2.0 * eps * t.duration_s);
            assert!(
                (fa - t.sample(s).acc_m_s2).length() < 1e-4,
                "at {s}: {fa} vs {}",
                t.sample(s).acc_m_s2
            );
        }
    }
}
