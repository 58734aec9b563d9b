//! `quadsim run --real-time [FACTOR]`: paces the stepping loop to wall-clock
//! time so a person can watch (a single robot otherwise runs ~30× faster
//! than real time). Pacing only sleeps between passes of steps, and a pass
//! of k steps gives the same bits as k passes of one, so results do not
//! depend on it.

use std::time::{Duration, Instant};

use crate::error::{CliError, bad};

/// Wall time a pass of steps covers at most (s): short enough that a
/// viewer sees smooth motion, long enough that sleeping costs little.
pub const PASS_WALL_S: f64 = 0.005;

/// Lag behind the schedule (s) past which the run warns once that the
/// machine cannot keep up.
pub const BEHIND_WARN_S: f64 = 0.25;

/// Paces simulation time to `factor` × wall-clock time.
#[derive(Debug)]
pub struct Pacer {
    /// Simulated seconds per wall-clock second (1.0 = real time).
    pub factor: f64,
    /// Steps of one pass.
    pub pass_steps: u64,
    dt_s: f64,
    start: Instant,
    /// The largest lag behind the schedule seen (s).
    pub max_lag_s: f64,
    warned: bool,
}

impl Pacer {
    /// A pacer for steps of `dt_s`, starting now; refuses a factor that is
    /// not finite and > 0.
    pub fn new(factor: f64, dt_s: f64) -> Result<Self, CliError> {
        if !(factor.is_finite() && factor > 0.0 && factor <= 1e6) {
            return Err(bad(format!(
                "--real-time: must be a factor > 0 and ≤ 1e6 (1 = real time, 0.5 = half speed), got {factor}"
            )));
        }
        let pass_steps = ((PASS_WALL_S * factor / dt_s).floor() as u64).max(1);
        Ok(Self {
            factor,
            pass_steps,
            dt_s,
            start: Instant::now(),
            max_lag_s: 0.0,
            warned: false,
        })
    }

    /// Restarts the schedule now (call right before the first step).
    pub fn restart(&mut self) {
        self.start = Instant::now();
    }

    /// Sleeps until `steps` steps are due on the wall clock; warns once
    /// when the run is more than [`BEHIND_WARN_S`] behind.
    pub fn wait(&mut self, steps: u64) {
        let due = Duration::from_secs_f64(steps as f64 * self.dt_s / self.factor);
        let now = self.start.elapsed();
        if let Some(ahead) = due.checked_sub(now) {
            std::thread::sleep(ahead);
            return;
        }
        let lag = (now - due).as_secs_f64();
        self.max_lag_s = self.max_lag_s.max(lag);
        if lag > BEHIND_WARN_S && !self.warned {
            self.warned = true;
            eprintln!(
                "warning: --real-time {}: the machine cannot keep up ({:.2} s behind at t = {:.2} s); \
                 the run goes on as fast as it can",
                self.factor,
                lag,
                steps as f64 * self.dt_s
            );
        }
    }

    /// Simulated time per wall time achieved over `steps` steps, since
    /// [`Self::restart`].
    pub fn achieved(&self, steps: u64) -> f64 {
        let wall = self.start.elapsed().as_secs_f64();
        if wall > 0.0 {
            steps as f64 * self.dt_s / wall
        } else {
            0.0
        }
    }

    /// Whether the run fell behind enough to warn.
    pub fn fell_behind(&self) -> bool {
        self.warned
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_factors_that_cannot_pace() {
        for f in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e7] {
            assert!(Pacer::new(f, 5e-4).is_err(), "{f}");
        }
        // 5 ms at real time and dt = 0.5 ms: passes of 10 steps; at most
        // one step when slowed down a lot
        assert_eq!(Pacer::new(1.0, 5e-4).unwrap().pass_steps, 10);
        assert_eq!(Pacer::new(0.01, 5e-4).unwrap().pass_steps, 1);
    }
}
