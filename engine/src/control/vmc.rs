//! Virtual Model Control (study A): six decoupled virtual spring–dampers
//! between the robot's CoM and a moving target give the wrench `W = [F; M]`
//! the stance feet should apply to the robot (see [`super::force_qp`] for
//! its distribution and the joint torques).
//!
//! - `F = k_F (s_des − s) + b_F (v_des − v) + m g ẑ`
//! - `M = k_M (θ_des − θ) + b_M (θ̇_des − θ̇)`
//!
//! # Frames and conventions
//! `W` is in world axes, the moment about the CoM. Orientation errors use
//! the URDF roll–pitch–yaw of the base, `R = Rz(ψ) Ry(θ) Rx(φ)`
//! ([`crate::spatial::rpy_from_rot`]). x/y and roll/pitch act in the
//! *heading frame* (world axes turned by the measured yaw ψ about z): x is
//! the robot's forward direction projected onto the ground, y its left. The
//! roll and pitch moments act about the heading frame's x and y axes, the
//! yaw moment about world z; the damping terms use the base's angular
//! velocity expressed in the same axes.
//!
//! # Targets
//! - Horizontal position: the target advances by `v_des·dt` each tick, and
//!   is **re-anchored to the measured CoM** with the error clipped to
//!   `±max_position_error_m` per heading axis: `s_des ← s + clip(s_des +
//!   v_des dt − s)`. A robot that lags its target speed thus feels at most
//!   `k·e_max + b·(v_des − v)`, not a spring wound up over seconds; speed is
//!   driven through `v_des`.
//! - Height: `base_height_m` above the ground beneath the base; its rate is
//!   the base's vertical velocity (exact on level ground).
//! - Yaw: integrated from the commanded yaw rate, starting at the measured
//!   yaw; the error is wrapped to (−π, π]. Roll and pitch targets are 0
//!   (Study A), or lie along sloped ground ([`Vmc::set_posture`]).

use crate::spatial::{Force, roll_pitch_from_rot, yaw_from_rot};
use glam::{DMat3, DVec3};

/// Stiffness and damping of the six virtual spring–dampers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmcGains {
    /// Translational stiffness along heading x, heading y, z (N/m).
    pub stiffness_npm: DVec3,
    /// Translational damping along heading x, heading y, z (N·s/m).
    pub damping_nspm: DVec3,
    /// Rotational stiffness for roll, pitch, yaw (N·m/rad).
    pub stiffness_nm_per_rad: DVec3,
    /// Rotational damping for roll, pitch, yaw (N·m·s/rad).
    pub damping_nms_per_rad: DVec3,
}

impl Default for VmcGains {
    /// Study A's table: x, y 5000 N/m and 300 N·s/m; z 10000 N/m and 500
    /// N·s/m; roll, pitch, yaw 200 N·m/rad and 50 N·m·s/rad.
    fn default() -> Self {
        VmcGains {
            stiffness_npm: DVec3::new(5000.0, 5000.0, 10_000.0),
            damping_nspm: DVec3::new(300.0, 300.0, 500.0),
            stiffness_nm_per_rad: DVec3::splat(200.0),
            damping_nms_per_rad: DVec3::splat(50.0),
        }
    }
}

/// Everything about the controller that is not a run-time command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmcParams {
    /// Spring–damper gains.
    pub gains: VmcGains,
    /// Target height of the base origin above the ground beneath it (m).
    pub base_height_m: f64,
    /// Clip of the horizontal position error per heading axis (m).
    pub max_position_error_m: f64,
    /// The robot's own mass (kg), for gravity compensation.
    pub robot_mass_kg: f64,
    /// Payload carried on the torso (kg), added to the gravity compensation.
    pub payload_mass_kg: f64,
    /// Magnitude of gravity (m/s²).
    pub gravity_mps2: f64,
}

impl VmcParams {
    /// Study A's gains and targets (height 0.5 m, error clip ±0.05 m) for a
    /// robot of `robot_mass_kg` with no payload under standard gravity.
    pub fn study_a(robot_mass_kg: f64) -> Self {
        VmcParams {
            gains: VmcGains::default(),
            base_height_m: 0.5,
            max_position_error_m: 0.05,
            robot_mass_kg,
            payload_mass_kg: 0.0,
            gravity_mps2: 9.81,
        }
    }

    /// [`VmcParams::study_a`] with the model's total mass and gravity.
    pub fn for_model(model: &crate::model::Model) -> Self {
        VmcParams {
            gravity_mps2: model.gravity.length(),
            ..VmcParams::study_a(model.total_mass)
        }
    }

    /// The weight the feet carry: `(m_robot + m_payload) g` (N).
    pub fn weight_n(&self) -> f64 {
        (self.robot_mass_kg + self.payload_mass_kg) * self.gravity_mps2
    }
}

/// Velocity commands, changeable at run time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmcCommand {
    /// Forward speed along the heading x axis (m/s).
    pub forward_mps: f64,
    /// Lateral speed along the heading y axis, positive to the left (m/s).
    pub lateral_mps: f64,
    /// Yaw rate about world z, positive counter-clockwise (rad/s).
    pub yaw_rate_radps: f64,
}

impl Default for VmcCommand {
    /// Study A's experiment: 1.5 m/s forward, no lateral speed or turning.
    fn default() -> Self {
        VmcCommand {
            forward_mps: 1.5,
            lateral_mps: 0.0,
            yaw_rate_radps: 0.0,
        }
    }
}

impl VmcCommand {
    /// Stand still.
    pub const STAND: VmcCommand = VmcCommand {
        forward_mps: 0.0,
        lateral_mps: 0.0,
        yaw_rate_radps: 0.0,
    };
}

/// The measured state the controller reads (world frame unless stated).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmcInput {
    /// Base origin (m). The springs read the CoM horizontally and
    /// `height_above_ground_m` vertically; this completes the base pose for
    /// callers and logs.
    pub base_position_m: DVec3,
    /// Base orientation (world from base).
    pub base_rotation: DMat3,
    /// Base origin's linear velocity (m/s, world).
    pub base_linear_velocity_mps: DVec3,
    /// Base angular velocity (rad/s, world axes).
    pub base_angular_velocity_radps: DVec3,
    /// Whole-robot CoM (m).
    pub com_m: DVec3,
    /// Whole-robot CoM velocity (m/s).
    pub com_velocity_mps: DVec3,
    /// Height of the base origin above the ground beneath it (m).
    pub height_above_ground_m: f64,
    /// Time since the previous update (s).
    pub dt_s: f64,
}

/// The controller: parameters, command and the moving targets.
#[derive(Clone, Debug, PartialEq)]
pub struct Vmc {
    /// Gains and targets.
    pub params: VmcParams,
    /// Current velocity command.
    pub command: VmcCommand,
    /// Horizontal target of the CoM (m, world x/y); `None` before the first update.
    target_xy_m: Option<glam::DVec2>,
    /// Yaw target (rad, unwrapped).
    target_yaw_rad: f64,
    /// Roll and pitch targets (rad) and the target's vertical velocity
    /// (m/s): a torso that follows sloped ground ([`Self::set_posture`]).
    posture: Option<(f64, f64, f64)>,
}

impl Vmc {
    /// A controller that anchors its targets at the first update.
    pub fn new(params: VmcParams, command: VmcCommand) -> Self {
        Vmc {
            params,
            command,
            target_xy_m: None,
            target_yaw_rad: 0.0,
            posture: None,
        }
    }

    /// Roll and pitch targets (rad, module doc's convention) and the rate
    /// at which the height target rises (m/s), for a torso that lies along
    /// sloped ground; until [`Self::clear_posture`], they replace Study A's
    /// level torso and still height.
    pub fn set_posture(&mut self, roll_rad: f64, pitch_rad: f64, rise_mps: f64) {
        self.posture = Some((roll_rad, pitch_rad, rise_mps));
    }

    /// Back to Study A's level torso (roll and pitch targets 0).
    pub fn clear_posture(&mut self) {
        self.posture = None;
    }

    /// Forget the targets: the next update anchors them at the measured state.
    pub fn reset(&mut self) {
        self.target_xy_m = None;
    }

    /// The yaw target (rad), once anchored.
    pub fn target_yaw_rad(&self) -> Option<f64> {
        self.target_xy_m.map(|_| self.target_yaw_rad)
    }

    /// Advances the targets by `input.dt_s` and returns the wrench `W` the
    /// ground should apply to the robot: force (N, world) and moment about the
    /// CoM (N·m, world axes), gravity compensation included.
    pub fn update(&mut self, input: &VmcInput) -> Force {
        let yaw = yaw_from_rot(input.base_rotation);
        self.update_at_heading(input, yaw, yaw.sin_cos())
    }

    /// [`Self::update`] given the base's yaw, `yaw_from_rot(input.base_rotation)`,
    /// and its `yaw.sin_cos()` (the same bits as [`Self::update`]): the
    /// walker has both already (its heading frame).
    pub(crate) fn update_at_heading(
        &mut self,
        input: &VmcInput,
        yaw: f64,
        (sy, cy): (f64, f64),
    ) -> Force {
        let p = &self.params;
        let g = &p.gains;
        let (roll, pitch) = roll_pitch_from_rot(input.base_rotation);
        // heading frame → world: rotation by ψ about z
        let to_world = |v: glam::DVec2| glam::DVec2::new(cy * v.x - sy * v.y, sy * v.x + cy * v.y);
        let to_heading =
            |v: glam::DVec2| glam::DVec2::new(cy * v.x + sy * v.y, -sy * v.x + cy * v.y);
        let s = input.com_m.truncate();
        let cmd = &self.command;
        let v_des_h = glam::DVec2::new(cmd.forward_mps, cmd.lateral_mps);
        let (target, yaw_target) = match self.target_xy_m {
            None => (s, yaw),
            Some(t) => (
                t + to_world(v_des_h) * input.dt_s,
                self.target_yaw_rad + cmd.yaw_rate_radps * input.dt_s,
            ),
        };
        let e_max = p.max_position_error_m;
        let e_h =
            to_heading(target - s).clamp(glam::DVec2::splat(-e_max), glam::DVec2::splat(e_max));
        self.target_xy_m = Some(s + to_world(e_h));
        self.target_yaw_rad = yaw_target;

        let v_h = to_heading(input.com_velocity_mps.truncate());
        let f_h = glam::DVec2::new(g.stiffness_npm.x, g.stiffness_npm.y) * e_h
            + glam::DVec2::new(g.damping_nspm.x, g.damping_nspm.y) * (v_des_h - v_h);
        let f_xy = to_world(f_h);
        // (Study A's still height: a rise of 0, `b (0 − v) = −(b v)` exactly)
        let (roll_des, pitch_des, rise) = self.posture.unwrap_or((0.0, 0.0, 0.0));
        let f_z = g.stiffness_npm.z * (p.base_height_m - input.height_above_ground_m)
            + g.damping_nspm.z * (rise - input.base_linear_velocity_mps.z)
            + p.weight_n();

        let w = input.base_angular_velocity_radps;
        let w_h = to_heading(w.truncate());
        let yaw_err = wrap_pi(yaw_target - yaw);
        let kr = g.stiffness_nm_per_rad;
        let br = g.damping_nms_per_rad;
        let m_h = glam::DVec2::new(
            kr.x * (roll_des - roll) + br.x * (0.0 - w_h.x),
            kr.y * (pitch_des - pitch) + br.y * (0.0 - w_h.y),
        );
        let m_xy = to_world(m_h);
        let m_z = kr.z * yaw_err + br.z * (cmd.yaw_rate_radps - w.z);
        Force {
            lin: DVec3::new(f_xy.x, f_xy.y, f_z),
            ang: DVec3::new(m_xy.x, m_xy.y, m_z),
        }
    }
}

/// `a` wrapped to (−π, π].
fn wrap_pi(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = a.rem_euclid(TAU);
    if r > PI { r - TAU } else { r }
}
