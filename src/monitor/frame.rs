//! The shared-memory frame: one robot at one published instant, a fixed
//! `#[repr(C)]` layout that Rust, Python (ctypes) and C readers share. The
//! layout, field by field with byte offsets, units and frames, is in
//! `docs/monitor.md` (a test checks the table against `offset_of!`).

// The ZeroCopySend derive emits an `unsafe impl` (the type is plain old data:
// fixed size, no pointers, no Drop); nothing else here is unsafe.
#![allow(unsafe_code)]

use iceoryx2::prelude::ZeroCopySend;
use quadsim_systems::RobotSample;

/// Version of [`RobotFrame`]'s layout; bump it (and the type name's `v1`)
/// on any change of field, order or size.
pub const LAYOUT_VERSION: u32 = 1;

/// The type name iceoryx2 checks when a reader opens the service: a reader
/// built for another layout cannot connect.
pub const TYPE_NAME: &str = "quadsim.RobotFrame.v1";

/// Joints a frame has room for; entries past the robot's DOF are NaN.
pub const MAX_DOF: usize = 24;

/// Feet a frame has room for; entries past the robot's feet are NaN (forces,
/// gait phase) and 0 (flags).
pub const MAX_FEET: usize = 4;

/// One robot at one instant `t = tick · dt`, with the very values the log
/// holds for that instant (the same sampling code, `quadsim_systems::log`).
/// Frames: `world` is z up; "base" is the root link's frame origin; twists
/// are of that origin, in world axes. Missing values (no controller target,
/// no gait, joints or feet past the robot's count) are NaN.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("quadsim.RobotFrame.v1")]
#[repr(C)]
pub struct RobotFrame {
    /// [`LAYOUT_VERSION`].
    pub layout_version: u32,
    /// Index of the robot in the world header's robot list.
    pub robot_index: u32,
    /// Step index of the instant (`time_s = tick · dt_s`).
    pub tick: u64,
    /// Simulation time (s).
    pub time_s: f64,
    /// Actuated joints of the robot (≤ [`MAX_DOF`] are carried).
    pub n_dof: u32,
    /// Feet of the robot (≤ [`MAX_FEET`] are carried).
    pub n_feet: u32,
    /// Bit `i` set: foot `i` touches the ground.
    pub contact_flags: u32,
    /// Bit `i` set: foot `i` slips (friction at the cone's limit).
    pub slip_flags: u32,
    /// Base position (m, world).
    pub base_position_m: [f64; 3],
    /// Base orientation, base → world unit quaternion (x, y, z, w).
    pub base_orientation_xyzw: [f64; 4],
    /// Velocity of the base origin (m/s, world axes).
    pub base_linear_mps: [f64; 3],
    /// Angular velocity of the base (rad/s, world axes).
    pub base_angular_radps: [f64; 3],
    /// Roll, pitch, yaw of the base (rad; `R = Rz(yaw) Ry(pitch) Rx(roll)`).
    pub rpy_rad: [f64; 3],
    /// Whole-body centre of mass (m, world).
    pub com_m: [f64; 3],
    /// CoM velocity (m/s, world).
    pub com_velocity_mps: [f64; 3],
    /// Joint angles (rad), velocity order.
    pub joint_q_rad: [f64; MAX_DOF],
    /// Joint velocities (rad/s).
    pub joint_qd_radps: [f64; MAX_DOF],
    /// Controller's joint targets (rad).
    pub joint_q_desired_rad: [f64; MAX_DOF],
    /// Controller's desired joint velocities (rad/s).
    pub joint_qd_desired_radps: [f64; MAX_DOF],
    /// Actuator torques acting over the step, after saturation (N·m).
    pub joint_tau_nm: [f64; MAX_DOF],
    /// Controller's torque command before saturation (N·m).
    pub joint_tau_desired_nm: [f64; MAX_DOF],
    /// Ground reaction force on each foot (N, world; zero off the ground).
    pub foot_force_n: [[f64; 3]; MAX_FEET],
    /// Each leg's gait clock phase in [0, 1) (NaN without a gait).
    pub gait_phase: [f64; MAX_FEET],
}

impl Default for RobotFrame {
    /// Every value NaN, counts and flags zero, the current layout version.
    fn default() -> Self {
        let nan = f64::NAN;
        Self {
            layout_version: LAYOUT_VERSION,
            robot_index: 0,
            tick: 0,
            time_s: nan,
            n_dof: 0,
            n_feet: 0,
            contact_flags: 0,
            slip_flags: 0,
            base_position_m: [nan; 3],
            base_orientation_xyzw: [nan; 4],
            base_linear_mps: [nan; 3],
            base_angular_radps: [nan; 3],
            rpy_rad: [nan; 3],
            com_m: [nan; 3],
            com_velocity_mps: [nan; 3],
            joint_q_rad: [nan; MAX_DOF],
            joint_qd_radps: [nan; MAX_DOF],
            joint_q_desired_rad: [nan; MAX_DOF],
            joint_qd_desired_radps: [nan; MAX_DOF],
            joint_tau_nm: [nan; MAX_DOF],
            joint_tau_desired_nm: [nan; MAX_DOF],
            foot_force_n: [[nan; 3]; MAX_FEET],
            gait_phase: [nan; MAX_FEET],
        }
    }
}

fn fill(dst: &mut [f64], src: &[f64]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

impl RobotFrame {
    /// The frame of a log sample taken at step `tick`, time `time_s`.
    pub fn from_sample(s: &RobotSample, tick: u64, time_s: f64) -> Self {
        let mut f = Self {
            robot_index: s.robot as u32,
            tick,
            time_s,
            n_dof: s.joint_position.len() as u32,
            n_feet: s.feet.len() as u32,
            base_position_m: s.base_position_m.to_array(),
            base_orientation_xyzw: s.base_orientation.to_array(),
            base_linear_mps: s.base_linear_mps.to_array(),
            base_angular_radps: s.base_angular_radps.to_array(),
            rpy_rad: s.rpy_rad.to_array(),
            com_m: s.com_m.to_array(),
            com_velocity_mps: s.com_velocity_mps.to_array(),
            ..Self::default()
        };
        fill(&mut f.joint_q_rad, &s.joint_position);
        fill(&mut f.joint_qd_radps, &s.joint_velocity);
        if let Some(t) = &s.joint_position_desired {
            fill(&mut f.joint_q_desired_rad, t);
        }
        if let Some(t) = &s.joint_velocity_desired {
            fill(&mut f.joint_qd_desired_radps, t);
        }
        fill(&mut f.joint_tau_nm, &s.joint_effort);
        fill(&mut f.joint_tau_desired_nm, &s.joint_effort_command);
        for (i, foot) in s.feet.iter().take(MAX_FEET).enumerate() {
            if foot.in_contact {
                f.contact_flags |= 1 << i;
            }
            if foot.slipping {
                f.slip_flags |= 1 << i;
            }
            f.foot_force_n[i] = foot.force_n.to_array();
            f.gait_phase[i] = foot.gait_phase.unwrap_or(f64::NAN);
        }
        f
    }

    /// The joints carried (`min(n_dof, MAX_DOF)`).
    pub fn dof(&self) -> usize {
        (self.n_dof as usize).min(MAX_DOF)
    }

    /// The feet carried (`min(n_feet, MAX_FEET)`).
    pub fn feet(&self) -> usize {
        (self.n_feet as usize).min(MAX_FEET)
    }

    /// Foot `i` touches the ground.
    pub fn in_contact(&self, i: usize) -> bool {
        i < 32 && self.contact_flags & (1 << i) != 0
    }

    /// Horizontal speed of the base origin (m/s).
    pub fn speed_mps(&self) -> f64 {
        self.base_linear_mps[0].hypot(self.base_linear_mps[1])
    }
}
