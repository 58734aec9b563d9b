//! Actuator load over a run, per joint: the peak torque as a share of the
//! effort limit, and the time spent at the torque and speed limits. These
//! say whether a robot can carry its load (`quadsim`'s load verdict).
//!
//! A joint is *at its torque limit* in a step when the commanded torque's
//! magnitude reaches the effort limit (the applied torque is then clamped
//! to it), and *at its speed limit* when |q̇| reaches the velocity limit.
//! Unlimited joints (infinite limits) are never at a limit, and their share
//! is 0. A *hit* is an entry into a limit (a step at it after a step not at it).
//!
//! Joints driven by a motor model ([`crate::actuator_model`]) are also *at
//! their envelope* in a step when the torque demanded lies outside the
//! torque–speed envelope at the step's start speed ([`ActuatorStats::record_envelope`]).

/// Accumulates [`ActuatorSummary`] step by step, without allocating after
/// construction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ActuatorStats {
    effort_limit: Vec<f64>,
    velocity_limit: Vec<f64>,
    peak_abs_torque: Vec<f64>,
    peak_abs_demand: Vec<f64>,
    at_torque_limit_s: Vec<f64>,
    at_speed_limit_s: Vec<f64>,
    at_envelope_s: Vec<f64>,
    /// Entries into the torque limit, the speed limit and the envelope.
    torque_hits: Vec<u64>,
    speed_hits: Vec<u64>,
    envelope_hits: Vec<u64>,
    /// At the torque limit, the speed limit, the envelope in the last step
    /// (one list each, so that each limit's loop is element-wise).
    was_at_torque: Vec<bool>,
    was_at_speed: Vec<bool>,
    was_at_envelope: Vec<bool>,
    /// Whether any of `was_at_torque` (`was_at_speed`) is set.
    any_was_at_torque: bool,
    any_was_at_speed: bool,
    time_s: f64,
}

/// One joint's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLoad {
    /// Largest applied |τ| (N·m or N): the torque acting at the joint (a
    /// motor's inside its envelope), as recorded by [`ActuatorStats::record`].
    pub peak_torque_nm: f64,
    /// Largest |τ| commanded, before the limit (N·m or N): what the
    /// controller (or a servo's own loop) asked for.
    pub peak_demand_nm: f64,
    /// The torque limit the shares refer to (N·m or N; +∞ when unlimited).
    pub torque_limit_nm: f64,
    /// The speed limit (rad/s or m/s; +∞ when unlimited).
    pub speed_limit: f64,
    /// `peak_torque_nm` / effort limit (0 when unlimited), ≤ 1 when the
    /// applied torque is saturated (`passive.saturation`, the default).
    pub peak_torque_share: f64,
    /// Time with the command at or beyond the effort limit (s).
    pub time_at_torque_limit_s: f64,
    /// Time with |q̇| at or beyond the velocity limit (s).
    pub time_at_speed_limit_s: f64,
    /// Entries into the torque limit.
    pub torque_limit_hits: u64,
    /// Entries into the speed limit.
    pub speed_limit_hits: u64,
    /// Time with the demanded torque outside the motor's torque–speed
    /// envelope (s; 0 for an ideal actuator).
    pub time_at_envelope_limit_s: f64,
    /// Entries into the envelope limit.
    pub envelope_limit_hits: u64,
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
    /// Largest fraction of the run any joint spent at its envelope limit.
    pub max_time_share_at_envelope_limit: f64,
}

impl ActuatorStats {
    /// Statistics for joints with these limits (joint order).
    pub fn new(effort_limit: &[f64], velocity_limit: &[f64]) -> Self {
        let n = effort_limit.len();
        Self {
            effort_limit: effort_limit.to_vec(),
            velocity_limit: velocity_limit.to_vec(),
            peak_abs_torque: vec![0.0; n],
            peak_abs_demand: vec![0.0; n],
            at_torque_limit_s: vec![0.0; n],
            at_speed_limit_s: vec![0.0; n],
            at_envelope_s: vec![0.0; n],
            torque_hits: vec![0; n],
            speed_hits: vec![0; n],
            envelope_hits: vec![0; n],
            was_at_torque: vec![false; n],
            was_at_speed: vec![false; n],
            was_at_envelope: vec![false; n],
            any_was_at_torque: false,
            any_was_at_speed: false,
            time_s: 0.0,
        }
    }

    /// Records one step of `dt_s` with commanded torques `tau_cmd`, the
    /// torques `applied` at the joints over the step (the motor's torque
    /// inside its envelope, or the command after saturation: the quantity
    /// the metrics' `joint_peak_abs_torque_nm` and the log's joint effort
    /// hold) and joint speeds `qd` (joint order). Extra or missing entries
    /// are ignored.
    pub fn record(&mut self, tau_cmd: &[f64], applied: &[f64], qd: &[f64], dt_s: f64) {
        // an x86-64-v3 clone (three-operand VEX forms, wider vectors; no
        // fused multiply–add, so the same bits), in a free function:
        // multiversion takes no `self`
        #[multiversion::multiversion(targets("x86_64+avx2+fma"))]
        fn body(this: &mut ActuatorStats, tau_cmd: &[f64], applied: &[f64], qd: &[f64], dt_s: f64) {
            this.time_s += dt_s;
            // every per-joint list as a slice of one length, so that the loop
            // indexes without bounds checks
            let n = this
                .effort_limit
                .len()
                .min(tau_cmd.len())
                .min(applied.len());
            let (effort, velocity) = (&this.effort_limit[..n], &this.velocity_limit[..n]);
            let (peak_torque, peak_demand) = (
                &mut this.peak_abs_torque[..n],
                &mut this.peak_abs_demand[..n],
            );
            let (at_torque_s, at_speed_s) = (
                &mut this.at_torque_limit_s[..n],
                &mut this.at_speed_limit_s[..n],
            );
            let (torque_hits, speed_hits) = (&mut this.torque_hits[..n], &mut this.speed_hits[..n]);
            let (tau_cmd, applied) = (&tau_cmd[..n], &applied[..n]);
            // the peaks on their own, and whether any joint is at its torque
            // limit: an element-wise loop without branches, which vectorises
            // (the same operations per joint)
            let mut any_at_torque = false;
            for ((((peak_t, peak_d), tau), a), lim) in peak_torque
                .iter_mut()
                .zip(peak_demand.iter_mut())
                .zip(tau_cmd)
                .zip(applied)
                .zip(effort)
            {
                let t = tau.abs();
                *peak_t = crate::metrics::max_of_peak(*peak_t, a.abs());
                *peak_d = crate::metrics::max_of_peak(*peak_d, t);
                any_at_torque |= t >= *lim;
            }
            // joints without a speed (a short `qd`) are not at their speed limit
            let m = n.min(qd.len());
            let any_at_speed = qd[..m]
                .iter()
                .zip(&velocity[..m])
                .fold(false, |any, (v, lim)| any | (v.abs() >= *lim));
            // A step with no joint at a limit, after one with none either (the
            // usual step), changes no time, hit or flag: the loops below run
            // only when a joint is at a limit now or was in the last step.
            if any_at_torque || this.any_was_at_torque {
                let was = &mut this.was_at_torque[..n];
                for j in 0..n {
                    let at = tau_cmd[j].abs() >= effort[j];
                    if at {
                        at_torque_s[j] += dt_s;
                        torque_hits[j] += u64::from(!was[j]);
                    }
                    was[j] = at;
                }
                this.any_was_at_torque = this.was_at_torque.contains(&true);
            }
            if any_at_speed || this.any_was_at_speed {
                let was = &mut this.was_at_speed[..n];
                for j in 0..n {
                    let at = j < m && qd[j].abs() >= velocity[j];
                    if at {
                        at_speed_s[j] += dt_s;
                        speed_hits[j] += u64::from(!was[j]);
                    }
                    was[j] = at;
                }
                this.any_was_at_speed = this.was_at_speed.contains(&true);
            }
        }
        body(self, tau_cmd, applied, qd, dt_s)
    }

    /// Records, for the step of `dt_s` just recorded by [`Self::record`],
    /// which joints' demand lay outside their motor's envelope (joint order).
    pub fn record_envelope(&mut self, at_envelope: &[bool], dt_s: f64) {
        for (j, &at) in at_envelope.iter().enumerate().take(self.effort_limit.len()) {
            if at {
                self.at_envelope_s[j] += dt_s;
                self.envelope_hits[j] += u64::from(!self.was_at_envelope[j]);
            }
            self.was_at_envelope[j] = at;
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
                peak_demand_nm: self.peak_abs_demand[j],
                torque_limit_nm: self.effort_limit[j],
                speed_limit: self.velocity_limit[j],
                peak_torque_share: share(self.peak_abs_torque[j], self.effort_limit[j]),
                time_at_torque_limit_s: self.at_torque_limit_s[j],
                time_at_speed_limit_s: self.at_speed_limit_s[j],
                torque_limit_hits: self.torque_hits[j],
                speed_limit_hits: self.speed_hits[j],
                time_at_envelope_limit_s: self.at_envelope_s[j],
                envelope_limit_hits: self.envelope_hits[j],
            })
            .collect();
        let max = |f: &dyn Fn(&JointLoad) -> f64| joints.iter().map(f).fold(0.0, f64::max);
        ActuatorSummary {
            max_peak_torque_share: max(&|j| j.peak_torque_share),
            max_time_share_at_torque_limit: max(&|j| of_run(j.time_at_torque_limit_s)),
            max_time_share_at_speed_limit: max(&|j| of_run(j.time_at_speed_limit_s)),
            max_time_share_at_envelope_limit: max(&|j| of_run(j.time_at_envelope_limit_s)),
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
        s.record(&[4.0, 100.0], &[4.0, 100.0], &[1.0, 6.0], 0.1);
        s.record(&[12.0, 0.0], &[10.0, 0.0], &[-5.0, 0.0], 0.1);
        s.record(&[-10.0, 0.0], &[-10.0, 0.0], &[0.0, 0.0], 0.1);
        let m = s.summary();
        assert_eq!(m.joints[0].peak_torque_nm, 10.0);
        assert_eq!(m.joints[0].peak_demand_nm, 12.0);
        assert_eq!(m.joints[0].peak_torque_share, 1.0);
        assert!((m.joints[0].time_at_torque_limit_s - 0.2).abs() < 1e-12);
        assert!((m.joints[0].time_at_speed_limit_s - 0.1).abs() < 1e-12);
        assert_eq!(m.joints[1].peak_torque_share, 0.0);
        assert_eq!(m.joints[1].time_at_torque_limit_s, 0.0);
        assert!((m.max_time_share_at_torque_limit - 2.0 / 3.0).abs() < 1e-12);
        assert!((m.max_time_share_at_speed_limit - 1.0 / 3.0).abs() < 1e-12);
        // steps 2 and 3 are one stay at the torque limit: one hit
        assert_eq!(m.joints[0].torque_limit_hits, 1);
        assert_eq!(m.joints[0].speed_limit_hits, 1);
        assert_eq!(m.joints[1].speed_limit_hits, 1);
    }

    #[test]
    fn envelope_hits_count_entries() {
        let mut s = ActuatorStats::new(&[1.0], &[1.0]);
        for at in [true, true, false, true, false] {
            s.record(&[0.0], &[0.0], &[0.0], 0.5);
            s.record_envelope(&[at], 0.5);
        }
        let m = s.summary();
        assert_eq!(m.joints[0].envelope_limit_hits, 2);
        assert!((m.joints[0].time_at_envelope_limit_s - 1.5).abs() < 1e-12);
        assert!((m.max_time_share_at_envelope_limit - 0.6).abs() < 1e-12);
    }

    #[test]
    fn the_peak_torque_is_the_applied_torques_not_the_clamped_demand() {
        // a motor whose envelope holds the applied torque below a demand
        // that is itself under the limit (a joint at speed)
        let mut s = ActuatorStats::new(&[100.0], &[30.0]);
        s.record(&[96.0], &[91.5], &[10.0], 0.1);
        s.record(&[-20.0], &[-20.0], &[0.0], 0.1);
        let m = s.summary();
        assert_eq!(m.joints[0].peak_torque_nm, 91.5);
        assert_eq!(m.joints[0].peak_demand_nm, 96.0);
        assert!((m.joints[0].peak_torque_share - 0.915).abs() < 1e-12);
        assert_eq!(m.joints[0].time_at_torque_limit_s, 0.0);
    }
}
