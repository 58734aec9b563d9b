//! Actuator models per joint: what stands between a controller's command and
//! the torque on the joint (see `docs/actuators.md`).
//!
//! Each joint has an [`ActuatorSpec`] of one [`ActuatorKind`]:
//!
//! - `Ideal`: the command is the torque (clamped at the model's effort limit
//!   when saturation is on), as before this module existed;
//! - `DcMotor`: a geared DC motor commanded in torque;
//! - `Servo`: the same motor driven by a position PD inside the servo, at its
//!   own rate, toward the controller's joint target (a hobby servo).
//!
//! The signal path of a motor joint, every quantity at the joint (N·m, rad/s;
//! positive along the joint axis):
//!
//! 1. **Latency**: the command (a torque, or a servo's target angle) is
//!    delayed by `latency_ticks` control ticks (a preallocated ring buffer
//!    advanced once per control tick).
//! 2. **Servo PD** (servo only), every `1/rate_hz`: `u = kp (q* − q) − kd q̇`
//!    from the step's start state, held in between.
//! 3. **Torque lag**: `ẋ = 2πf (u − x)`, discretised exactly for a command
//!    held over the step (zero-order hold): `x⁺ = u + (x − u) e^{−2πf dt}`. The
//!    torque used over the step is the exact mean of `x(t)` over it,
//!    `x̄ = u + (x − u)(1 − e^{−a})/a` with `a = 2πf dt`, so the impulse of
//!    each step is exact.
//! 4. **Effort limit**: `|x̄| ≤ effort_limit` of the model (the gearbox rating)
//!    when the passive saturation is on.
//! 5. **Torque–speed envelope** (at every derivative evaluation, at the stage's
//!    `q̇`): the four-quadrant line of a voltage- and current-limited DC motor,
//!    `τ ∈ [lo(q̇), hi(q̇)]` with `hi = clamp(τ_s (1 − q̇/ω₀), −τ_s, τ_s)` and
//!    `lo = clamp(−τ_s (1 + q̇/ω₀), −τ_s, τ_s)`. For `|q̇| ≤ ω₀` this is
//!    `|τ| ≤ τ_s (1 − sign(τ) q̇/ω₀)` clipped to `[0, τ_s]` per direction: full
//!    stall torque when braking, nothing in the driving direction at `ω₀`.
//!    Beyond `ω₀` the back-EMF exceeds the supply and `hi < 0`: the motor
//!    brakes whatever the command (down to `−τ_s` at `2ω₀`). So a motor cannot
//!    drive its joint beyond its no-load speed.
//! 6. **Friction** (every evaluation): `−b q̇ − f_c tanh(q̇/ε)` with the
//!    passive model's ε.
//!
//! The rotor's inertia reflected through the gear, `J_rotor N²`, is added to
//! the model's armature once, at compile ([`add_reflected_inertia`]).
//!
//! Steps 1–4 run once per step ([`ActuatorBank::begin_step`]); 5–6 depend on
//! `q̇` and run at every derivative evaluation ([`ActuatorBank::apply`]), so
//! RK4 sees a consistent vector field within the step.

use crate::model::Model;
use crate::passive::{PassiveParams, friction_torque};

/// What drives a joint.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ActuatorKind {
    /// Torque source: the command is the torque (clamped at the effort limit).
    #[default]
    Ideal,
    /// Geared DC motor commanded in torque.
    DcMotor,
    /// Position servo: the motor under an internal PD toward the joint target.
    Servo,
}

/// A geared DC motor, every figure at the joint (after the gear).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorParams {
    /// Stall torque τ_s at the joint (N·m): the current limit × torque constant × N.
    pub stall_torque_nm: f64,
    /// No-load speed ω₀ at the joint (rad/s): supply voltage / (k_e N).
    pub no_load_speed_radps: f64,
    /// Gear ratio N (motor turns per joint turn, ≥ 1).
    pub gear_ratio: f64,
    /// Rotor inertia on the motor side (kg·m²); reflected as `J N²`.
    pub rotor_inertia_kgm2: f64,
    /// Viscous friction at the joint (N·m·s/rad).
    pub viscous_nms_per_rad: f64,
    /// Coulomb friction at the joint (N·m).
    pub coulomb_nm: f64,
    /// Torque bandwidth f (Hz) of the first-order lag; `∞` for none.
    pub bandwidth_hz: f64,
    /// Command latency (control ticks).
    pub latency_ticks: usize,
}

impl MotorParams {
    /// An unlimited motor: infinite stall torque and speed, no gear inertia,
    /// no friction, no lag, no latency.
    pub fn unlimited() -> Self {
        Self {
            stall_torque_nm: f64::INFINITY,
            no_load_speed_radps: f64::INFINITY,
            gear_ratio: 1.0,
            rotor_inertia_kgm2: 0.0,
            viscous_nms_per_rad: 0.0,
            coulomb_nm: 0.0,
            bandwidth_hz: f64::INFINITY,
            latency_ticks: 0,
        }
    }

    /// The envelope `[lo, hi]` of available torque at joint speed `qd` (see
    /// the module docs): `hi = clamp(τ_s (1 − q̇/ω₀), −τ_s, τ_s)`,
    /// `lo = clamp(−τ_s (1 + q̇/ω₀), −τ_s, τ_s)`.
    #[inline]
    pub fn envelope(&self, qd: f64) -> (f64, f64) {
        envelope(self.stall_torque_nm, self.no_load_speed_radps, qd)
    }
}

/// The torque–speed envelope `[lo, hi]` of a motor with stall torque `stall`
/// (N·m) and no-load speed `no_load` (rad/s) at joint speed `qd` (rad/s).
#[inline]
pub fn envelope(stall: f64, no_load: f64, qd: f64) -> (f64, f64) {
    if stall.is_infinite() {
        return (f64::NEG_INFINITY, f64::INFINITY);
    }
    let r = qd / no_load;
    (
        (-stall * (1.0 + r)).clamp(-stall, stall),
        (stall * (1.0 - r)).clamp(-stall, stall),
    )
}

/// A servo's internal position loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoParams {
    /// Proportional gain (N·m/rad).
    pub kp_nm_per_rad: f64,
    /// Derivative gain on the measured joint speed (N·m·s/rad).
    pub kd_nms_per_rad: f64,
    /// Rate of the internal loop (Hz); `∞`: every step.
    pub rate_hz: f64,
}

impl Default for ServoParams {
    fn default() -> Self {
        Self {
            kp_nm_per_rad: 0.0,
            kd_nms_per_rad: 0.0,
            rate_hz: f64::INFINITY,
        }
    }
}

/// One joint's actuator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActuatorSpec {
    /// Kind.
    pub kind: ActuatorKind,
    /// Motor (unused by `Ideal`).
    pub motor: MotorParams,
    /// Servo loop (used by `Servo` only).
    pub servo: ServoParams,
}

impl ActuatorSpec {
    /// An ideal torque source.
    pub fn ideal() -> Self {
        Self {
            kind: ActuatorKind::Ideal,
            motor: MotorParams::unlimited(),
            servo: ServoParams::default(),
        }
    }

    /// A torque-commanded DC motor.
    pub fn dc_motor(motor: MotorParams) -> Self {
        Self {
            kind: ActuatorKind::DcMotor,
            motor,
            servo: ServoParams::default(),
        }
    }

    /// A position servo.
    pub fn servo(motor: MotorParams, servo: ServoParams) -> Self {
        Self {
            kind: ActuatorKind::Servo,
            motor,
            servo,
        }
    }

    /// The torque limit the actuator can reach at the joint (N·m): the stall
    /// torque of a motor, +∞ for an ideal source.
    pub fn torque_limit_nm(&self) -> f64 {
        match self.kind {
            ActuatorKind::Ideal => f64::INFINITY,
            _ => self.motor.stall_torque_nm,
        }
    }

    /// The speed the actuator can drive its joint to (rad/s): the no-load
    /// speed of a motor, +∞ for an ideal source.
    pub fn speed_limit_radps(&self) -> f64 {
        match self.kind {
            ActuatorKind::Ideal => f64::INFINITY,
            _ => self.motor.no_load_speed_radps,
        }
    }

    /// Why the parameters are unusable, naming the field (as the scenario
    /// key `[robots.actuators]` spells it).
    ///
    /// # Errors
    /// `(field, message)`.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        if self.kind == ActuatorKind::Ideal {
            return Ok(());
        }
        let m = &self.motor;
        let pos = |name: &'static str, x: f64| {
            if x > 0.0 && !x.is_nan() {
                Ok(())
            } else {
                Err((name, format!("must be > 0 (got {x})")))
            }
        };
        let nonneg = |name: &'static str, x: f64| {
            if x >= 0.0 && x.is_finite() {
                Ok(())
            } else {
                Err((name, format!("must be finite and ≥ 0 (got {x})")))
            }
        };
        pos("stall_torque_nm", m.stall_torque_nm)?;
        pos("no_load_speed_radps", m.no_load_speed_radps)?;
        pos("bandwidth_hz", m.bandwidth_hz)?;
        if !(m.gear_ratio >= 1.0 && m.gear_ratio.is_finite()) {
            return Err((
                "gear_ratio",
                format!("must be finite and ≥ 1 (got {})", m.gear_ratio),
            ));
        }
        nonneg("rotor_inertia_kgm2", m.rotor_inertia_kgm2)?;
        nonneg("viscous_nms_per_rad", m.viscous_nms_per_rad)?;
        nonneg("coulomb_nm", m.coulomb_nm)?;
        if self.kind == ActuatorKind::Servo {
            let s = &self.servo;
            pos("servo_kp_nm_per_rad", s.kp_nm_per_rad)?;
            nonneg("servo_kd_nms_per_rad", s.kd_nms_per_rad)?;
            pos("servo_rate_hz", s.rate_hz)?;
        }
        Ok(())
    }
}

/// Adds each motor's reflected rotor inertia `J_rotor N²` (kg·m²) to the
/// model's armature of its joint (`specs` in joint order). Call once, when
/// the model is compiled.
pub fn add_reflected_inertia(model: &mut Model, specs: &[ActuatorSpec]) {
    let nv0 = model.base_nv();
    for (j, s) in specs.iter().enumerate().take(model.nv - nv0) {
        if s.kind != ActuatorKind::Ideal {
            model.armature[nv0 + j] += s.motor.rotor_inertia_kgm2 * s.motor.gear_ratio.powi(2);
        }
    }
}

/// The actuators of one robot's joints with their state (latency buffers,
/// lag states, servo outputs). Preallocated: stepping allocates nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct ActuatorBank {
    specs: Vec<ActuatorSpec>,
    /// Steps per control tick: the latency buffer advances on steps
    /// `k·control_every_steps` (the `Control` stage's ticks).
    control_every_steps: u64,
    steps: u64,
    /// Ring buffers of the last `ring_len` commands, joint-major per slot
    /// (`ring_len × nj`): torques and servo targets.
    ring_len: usize,
    ring_tau: Vec<f64>,
    ring_target: Vec<f64>,
    /// Slot of the newest command.
    head: usize,
    primed: bool,
    /// Servo targets (rad, joints), written by the caller before each step.
    targets_rad: Vec<f64>,
    targets_set: bool,
    /// Servo PD output (N·m), held between servo ticks.
    servo_tau: Vec<f64>,
    /// Lag filter state `x` (N·m).
    lag: Vec<f64>,
    /// Torque demanded over the current step, before the envelope (N·m).
    demand: Vec<f64>,
    /// Torque applied at the step's start state, after the envelope (N·m).
    applied: Vec<f64>,
    /// The demand lay outside the envelope at the step's start state.
    at_envelope: Vec<bool>,
}

impl ActuatorBank {
    /// A bank for joints with these actuators (joint order), whose commands
    /// change every `control_every_steps` steps.
    pub fn new(specs: &[ActuatorSpec], control_every_steps: u64) -> Self {
        let nj = specs.len();
        let ring_len = specs
            .iter()
            .map(|s| s.motor.latency_ticks)
            .max()
            .unwrap_or(0)
            + 1;
        Self {
            specs: specs.to_vec(),
            control_every_steps: control_every_steps.max(1),
            steps: 0,
            ring_len,
            ring_tau: vec![0.0; ring_len * nj],
            ring_target: vec![0.0; ring_len * nj],
            head: 0,
            primed: false,
            targets_rad: vec![0.0; nj],
            targets_set: false,
            servo_tau: vec![0.0; nj],
            lag: vec![0.0; nj],
            demand: vec![0.0; nj],
            applied: vec![0.0; nj],
            at_envelope: vec![false; nj],
        }
    }

    /// The actuators (joint order).
    pub fn specs(&self) -> &[ActuatorSpec] {
        &self.specs
    }

    /// True when every joint is ideal (the bank changes nothing).
    pub fn all_ideal(&self) -> bool {
        self.specs.iter().all(|s| s.kind == ActuatorKind::Ideal)
    }

    /// True when some joint is a servo (it needs [`Self::set_targets`]).
    pub fn has_servos(&self) -> bool {
        self.specs.iter().any(|s| s.kind == ActuatorKind::Servo)
    }

    /// Sets the servo targets (rad, joint order; extra entries ignored). They
    /// enter the latency buffer at the next control tick. Until they are first
    /// set, a servo holds the angle it starts at.
    pub fn set_targets(&mut self, targets_rad: &[f64]) {
        let n = self.targets_rad.len().min(targets_rad.len());
        self.targets_rad[..n].copy_from_slice(&targets_rad[..n]);
        self.targets_set = true;
    }

    /// Lag filter states (N·m, joints).
    pub fn lag_state(&self) -> &[f64] {
        &self.lag
    }

    /// Torque demanded over the last step, before the envelope (N·m, joints):
    /// the lagged, delayed command (a servo's PD output), at the effort limit.
    pub fn demand(&self) -> &[f64] {
        &self.demand
    }

    /// Motor torque at the last step's start state, after the envelope and
    /// without friction (N·m, joints). Ideal joints: their (saturated) command.
    pub fn applied(&self) -> &[f64] {
        &self.applied
    }

    /// Per joint: the demand lay outside the envelope at the last step's start.
    pub fn at_envelope(&self) -> &[bool] {
        &self.at_envelope
    }

    /// Once per step, before the derivative evaluations: advances latency
    /// (on control ticks), servo loops (on servo ticks) and lags, and writes
    /// the step's actuator torques (nv; base entries copied from `tau_cmd`,
    /// ideal joints their command) into `tau_out`, at the effort limit when
    /// `passive.saturation` is on. `q`, `v` are the step's start state.
    #[expect(
        clippy::too_many_arguments,
        reason = "the step's inputs and the one output buffer"
    )]
    pub fn begin_step(
        &mut self,
        model: &Model,
        passive: &PassiveParams,
        q: &[f64],
        v: &[f64],
        tau_cmd: &[f64],
        dt_s: f64,
        tau_out: &mut [f64],
    ) {
        let (nq0, nv0) = (model.base_nq(), model.base_nv());
        let nj = self.specs.len().min(model.nv - nv0);
        tau_out.copy_from_slice(tau_cmd);
        if !self.targets_set {
            // No target yet: a servo holds the angle it starts at.
            self.targets_rad[..nj].copy_from_slice(&q[nq0..nq0 + nj]);
            self.targets_set = true;
        }
        if self.steps.is_multiple_of(self.control_every_steps) {
            self.push_command(&tau_cmd[nv0..nv0 + nj]);
        }
        for j in 0..nj {
            let spec = self.specs[j];
            let (qj, qdj) = (q[nq0 + j], v[nv0 + j]);
            let lim = if passive.saturation {
                model.effort_limit[nv0 + j]
            } else {
                f64::INFINITY
            };
            if spec.kind == ActuatorKind::Ideal {
                let t = tau_cmd[nv0 + j].clamp(-lim, lim);
                tau_out[nv0 + j] = t;
                self.demand[j] = t;
                self.applied[j] = t;
                self.at_envelope[j] = false;
                continue;
            }
            let slot = (self.head + self.ring_len - spec.motor.latency_ticks) % self.ring_len;
            let u = match spec.kind {
                ActuatorKind::Servo => {
                    let every = if spec.servo.rate_hz.is_finite() {
                        ((1.0 / (spec.servo.rate_hz * dt_s)).round() as u64).max(1)
                    } else {
                        1
                    };
                    if self.steps.is_multiple_of(every) {
                        let target = self.ring_target[slot * self.specs.len() + j];
                        self.servo_tau[j] = spec.servo.kp_nm_per_rad * (target - qj)
                            - spec.servo.kd_nms_per_rad * qdj;
                    }
                    self.servo_tau[j]
                }
                _ => self.ring_tau[slot * self.specs.len() + j],
            };
            let x = self.lag[j];
            let (mean, next) = if spec.motor.bandwidth_hz.is_finite() {
                let a = 2.0 * std::f64::consts::PI * spec.motor.bandwidth_hz * dt_s;
                let e = (-a).exp();
                // (1 − e^{−a})/a, by its series where the subtraction cancels.
                let g = if a < 1e-6 {
                    1.0 - 0.5 * a
                } else {
                    -(-a).exp_m1() / a
                };
                (u + (x - u) * g, u + (x - u) * e)
            } else {
                (u, u)
            };
            self.lag[j] = next;
            let t = mean.clamp(-lim, lim);
            tau_out[nv0 + j] = t;
            self.demand[j] = t;
            let (lo, hi) = spec.motor.envelope(qdj);
            self.applied[j] = t.clamp(lo, hi);
            self.at_envelope[j] = t < lo || t > hi;
        }
        self.steps += 1;
    }

    /// The latency buffer's new slot: this tick's torque command and targets.
    fn push_command(&mut self, tau_joints: &[f64]) {
        let nj = self.specs.len();
        let n = nj.min(tau_joints.len());
        self.head = (self.head + 1) % self.ring_len;
        let s = self.head * nj;
        self.ring_tau[s..s + n].copy_from_slice(&tau_joints[..n]);
        self.ring_target[s..s + nj].copy_from_slice(&self.targets_rad);
        if !self.primed {
            // Before the first command there was none: the buffer starts full of it.
            for k in 0..self.ring_len {
                if k != self.head {
                    self.ring_tau.copy_within(s..s + nj, k * nj);
                    self.ring_target.copy_within(s..s + nj, k * nj);
                }
            }
            self.primed = true;
        }
    }

    /// At every derivative evaluation: replaces each motor joint's torque in
    /// `tau` (nv, holding the step's torques from [`Self::begin_step`]) by its
    /// value inside the envelope at the stage's speed `v`, plus the motor's
    /// friction (ε from `passive`). Ideal joints are untouched.
    #[inline]
    pub fn apply(&self, model: &Model, passive: &PassiveParams, v: &[f64], tau: &mut [f64]) {
        let nv0 = model.base_nv();
        for (j, spec) in self.specs.iter().enumerate().take(model.nv - nv0) {
            if spec.kind == ActuatorKind::Ideal {
                continue;
            }
            let m = &spec.motor;
            let qd = v[nv0 + j];
            let (lo, hi) = m.envelope(qd);
            tau[nv0 + j] = tau[nv0 + j].clamp(lo, hi) - m.viscous_nms_per_rad * qd
                + friction_torque(m.coulomb_nm, qd, passive.friction_epsilon);
        }
    }
}

/// The joint's rated speed (its velocity limit) as a share of the default
/// motor's no-load speed: a motor is rated below its no-load speed.
pub const RATED_OVER_NO_LOAD_SPEED: f64 = 0.75;

/// A motor's gear train and losses: the figures of [`MotorParams`] beside
/// its stall torque and no-load speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorGear {
    /// Gear ratio N (motor turns per joint turn).
    pub gear_ratio: f64,
    /// Rotor inertia at the motor (kg·m²).
    pub rotor_inertia_kgm2: f64,
    /// Viscous friction at the joint (N·m·s/rad).
    pub viscous_nms_per_rad: f64,
    /// Coulomb friction at the joint (N·m).
    pub coulomb_nm: f64,
    /// Torque bandwidth (Hz).
    pub bandwidth_hz: f64,
    /// Latency (control ticks).
    pub latency_ticks: usize,
}

/// A motor's rating at the joint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorRating {
    /// Stall torque (N·m).
    pub stall_torque_nm: f64,
    /// No-load speed (rad/s).
    pub no_load_speed_radps: f64,
}

/// A robot's default actuators (`docs/actuators.md` gives the sources and
/// assumptions): the kind a joint gets when the scenario names none, and
/// the figures of each kind beside the joint's limits. A robot states its
/// own (`robots::quad16::ACTUATORS`, `robots::quad12::ACTUATORS`); a robot
/// without them gets motors whose stall torque and no-load speed are the
/// joints' limits ([`ActuatorSpec::from_limits`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActuatorDefaults {
    /// The kind of a joint whose scenario names none, when the controller
    /// commands torques (an imposed motion takes ideal sources).
    pub kind: ActuatorKind,
    /// The DC motor's gear train and losses. It stalls at the joint's effort
    /// limit and runs free at its velocity limit /
    /// [`RATED_OVER_NO_LOAD_SPEED`].
    pub gear: MotorGear,
    /// The servo's motor rating; `None`: the DC motor's, from the joint's
    /// limits.
    pub servo_rating: Option<MotorRating>,
    /// The servo's internal PD.
    pub servo: ServoParams,
}

impl ActuatorDefaults {
    /// The default actuator of kind `kind` of a joint with these effort and
    /// velocity limits.
    pub fn spec(&self, kind: ActuatorKind, effort_limit: f64, velocity_limit: f64) -> ActuatorSpec {
        let g = &self.gear;
        let motor = MotorParams {
            stall_torque_nm: effort_limit,
            no_load_speed_radps: velocity_limit / RATED_OVER_NO_LOAD_SPEED,
            gear_ratio: g.gear_ratio,
            rotor_inertia_kgm2: g.rotor_inertia_kgm2,
            viscous_nms_per_rad: g.viscous_nms_per_rad,
            coulomb_nm: g.coulomb_nm,
            bandwidth_hz: g.bandwidth_hz,
            latency_ticks: g.latency_ticks,
        };
        match kind {
            ActuatorKind::Ideal => ActuatorSpec::ideal(),
            ActuatorKind::DcMotor => ActuatorSpec::dc_motor(motor),
            ActuatorKind::Servo => ActuatorSpec::servo(
                match self.servo_rating {
                    Some(r) => MotorParams {
                        stall_torque_nm: r.stall_torque_nm,
                        no_load_speed_radps: r.no_load_speed_radps,
                        ..motor
                    },
                    None => motor,
                },
                self.servo,
            ),
        }
    }
}

impl ActuatorSpec {
    /// A motor of this kind whose stall torque and no-load speed are a
    /// joint's effort and velocity limits; no gear inertia, friction, lag or
    /// latency; a servo's gains zero (to be given).
    pub fn from_limits(kind: ActuatorKind, effort_limit: f64, velocity_limit: f64) -> Self {
        Self {
            kind,
            motor: MotorParams {
                stall_torque_nm: effort_limit,
                no_load_speed_radps: velocity_limit,
                ..MotorParams::unlimited()
            },
            servo: ServoParams::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_is_the_four_quadrant_line() {
        let (s, w) = (2.0, 10.0);
        assert_eq!(envelope(s, w, 0.0), (-2.0, 2.0));
        // driving forward at half speed: half the torque forward, full braking
        assert_eq!(envelope(s, w, 5.0), (-2.0, 1.0));
        assert_eq!(envelope(s, w, -5.0), (-1.0, 2.0));
        assert_eq!(envelope(s, w, 10.0), (-2.0, 0.0));
        // beyond no-load speed: the motor can only brake
        assert_eq!(envelope(s, w, 15.0), (-2.0, -1.0));
        assert_eq!(envelope(s, w, 30.0), (-2.0, -2.0));
        assert_eq!(envelope(s, w, -30.0), (2.0, 2.0));
    }
}
