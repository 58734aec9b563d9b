//! Actuator load over a run, per joint: the peak torque as a share of the
//! effort limit, and the time spent at the torque and speed limits. These
//! say whether a robot can carry its load (`quadsim`'s load verdict).
//!
//! A joint is *at its torque limit* in a step when the commanded torque's
//! magnitude reaches the effort limit (the applied torque is then clamped
//! to it), and *at its speed limit* when |q̇| reaches the velocity limit.
//! Unlimited joints (infinite limits) are never at a limit, and their share
//! is 0.

/// Accumulates [`ActuatorSummary`] step by step, without allocating after
/// construction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ActuatorStats {
    effort_limit: Vec<f64>,
    velocity_limit: Vec<f64>,
    peak_abs_torque: Vec<f64>,
    at_torque_limit_s: Vec<f64>,
    at_speed_limit_s: Vec<f64>,
    time_s: f64,
}

/// One joint's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLoad {
    /// Largest applied |τ| (N·m or N).
    pub peak_torque_nm: f64,
    /// `peak_torque_nm` / effort limit (0 when unlimited), ≤ 1.
    pub peak_torque_share: f64,
    /// Time with the command at or beyond the effort limit (s).
    pub time_at_torque_limit_s: f64,
    /// Time with |q̇| at or beyond the velocity limit (s).
    pub time_at_speed_limit_s: f64,
}

/// Per-joint figures over the run, and the worst of them.
#[derive(Clone, Debug, PartialEq)]
pub struct ActuatorSummary {
    /// Per joint, in joint order.
    pub joints: Vec<JointLoad>,
    /// Largest `peak_torque_share` over the joints.
    pub max_peak_torque_share: f64,
    /// Largest fraction of the run any joint spent at its torque limit.
    pub max_time_share_at_torque_limit: f64,
    /// Largest fraction of the run any joint spent at its speed limit.
    pub max_time_share_at_speed_limit: f64,
}

impl ActuatorStats {
    /// Statistics for joints with these limits (joint order).
    pub fn new(effort_limit: &[f64], velocity_limit: &[f64]) -> Self {
        let n = effort_limit.len();
        Self {
            effort_limit: effort_limit.to_vec(),
            velocity_limit: velocity_limit.to_vec(),
            peak_abs_torque: vec![0.0; n],
            at_torque_limit_s: vec![0.0; n],
            at_speed_limit_s: vec![0.0; n],
            time_s: 0.0,
        }
    }

    /// Records one step of `dt_s` with commanded torques `tau_cmd` and joint
    /// speeds `qd` (joint order). Extra or missing entries are ignored.
    pub fn record(&mut self, tau_cmd: &[f64], qd: &[f64], dt_s: f64) {
        self.time_s += dt_s;
        for j in 0..self.effort_limit.len().min(tau_cmd.len()) {
            let lim = self.effort_limit[j];
            let t = tau_cmd[j].abs();
            self.peak_abs_torque[j] = self.peak_abs_torque[j].max(t.min(lim));
            if t >= lim {
                self.at_torque_limit_s[j] += dt_s;
            }
            if qd.get(j).is_some_and(|v| v.abs() >= self.velocity_limit[j]) {
                self.at_speed_limit_s[j] += dt_s;
            }
        }
    }

    /// The figures so far.
    pub fn summary(&self) -> ActuatorSummary {
        let share = |x: f64, lim: f64| {
            if lim.is_finite() && lim > 0.0 {
                x / lim
            } else {
                0.0
            }
        };
        let of_run = |t: f64| {
            if self.time_s > 0.0 {
                t / self.time_s
            } else {
                0.0
            }
        };
        let joints: Vec<JointLoad> = (0..self.effort_limit.len())
            .map(|j| JointLoad {
                peak_torque_nm: self.peak_abs_torque[j],
                peak_torque_share: share(self.peak_abs_torque[j], self.effort_limit[j]),
                time_at_torque_limit_s: self.at_torque_limit_s[j],
                time_at_speed_limit_s: self.at_speed_limit_s[j],
            })
            .collect();
        let max = |f: &dyn Fn(&JointLoad) -> f64| joints.iter().map(f).fold(0.0, f64::max);
        ActuatorSummary {
            max_peak_torque_share: max(&|j| j.peak_torque_share),
            max_time_share_at_torque_limit: max(&|j| of_run(j.time_at_torque_limit_s)),
            max_time_share_at_speed_limit: max(&|j| of_run(j.time_at_speed_limit_s)),
            joints,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_at_limits_and_peak_shares_add_up() {
        let mut s = ActuatorStats::new(&[10.0, f64::INFINITY], &[5.0, 5.0]);
        // 3 steps of 0.1 s: joint 0 at 4, 12 (clamped, at limit), -10 (at limit)
        s.record(&[4.0, 100.0], &[1.0, 6.0], 0.1);
        s.record(&[12.0, 0.0], &[-5.0, 0.0], 0.1);
        s.record(&[-10.0, 0.0], &[0.0, 0.0], 0.1);
        let m = s.summary();
        assert_eq!(m.joints[0].peak_torque_nm, 10.0);
        assert_eq!(m.joints[0].peak_torque_share, 1.0);
        assert!((m.joints[0].time_at_torque_limit_s - 0.2).abs() < 1e-12);
        assert!((m.joints[0].time_at_speed_limit_s - 0.1).abs() < 1e-12);
        assert_eq!(m.joints[1].peak_torque_share, 0.0);
        assert_eq!(m.joints[1].time_at_torque_limit_s, 0.0);
        assert!((m.max_time_share_at_torque_limit - 2.0 / 3.0).abs() < 1e-12);
        assert!((m.max_time_share_at_speed_limit - 1.0 / 3.0).abs() < 1e-12);
    }
}
