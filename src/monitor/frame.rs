//! The shared-memory frame: one robot at one published instant, a fixed
//! `#[repr(C)]` layout that Rust, Python (ctypes) and C readers share. The
//! layout, field by field with byte offsets, units and frames, is in
//! `docs/monitor.md` (a test checks the table against `offset_of!`).

// The ZeroCopySend derive emits an `unsafe impl` (the type is plain old data:
// fixed size, no pointers, no Drop); nothing else here is unsafe.
#![allow(unsafe_code)]

use iceoryx2::prelude::ZeroCopySend;
use quadsim_systems::{FootLog, RobotSample, SampleView, VelocityTargets};

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
    /// Actuator torques acting over the step (N·m): a motor's inside its
    /// envelope, else the command after saturation (the log's joint effort).
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

/// Copies `src` into the head of `dst` and sets `dst[src.len()..old_len]`
/// to NaN (entries a previous, longer value left behind).
#[inline]
fn fill(dst: &mut [f64], src: &[f64], old_len: usize) {
    let n = src.len().min(dst.len());
    dst[..n].copy_from_slice(&src[..n]);
    clear_tail(dst, n, old_len);
}

/// Sets `dst[n..old_len]` to NaN.
#[inline]
fn clear_tail(dst: &mut [f64], n: usize, old_len: usize) {
    let end = old_len.min(dst.len());
    if end > n {
        dst[n..end].fill(f64::NAN);
    }
}

impl RobotFrame {
    /// The frame of a log sample taken at step `tick`, time `time_s`.
    pub fn from_sample(s: &RobotSample, tick: u64, time_s: f64) -> Self {
        let mut f = Self::default();
        f.set_from_sample(s, tick, time_s);
        f
    }

    /// Joints and feet a previous frame in `self` may have set: its counts,
    /// or all entries when `self` holds no frame of this layout.
    fn old_counts(&self) -> (usize, usize) {
        if self.layout_version == LAYOUT_VERSION {
            (self.dof(), self.feet())
        } else {
            (MAX_DOF, MAX_FEET)
        }
    }

    /// Writes the feet's contact and slip flags, forces and gait phases
    /// (at most [`MAX_FEET`]), and NaN in the slots beyond them that the
    /// previous frame (`old_feet` feet) used.
    #[inline]
    fn set_feet(&mut self, feet: impl Iterator<Item = FootLog>, old_feet: usize) {
        self.contact_flags = 0;
        self.slip_flags = 0;
        let mut n_feet = 0;
        for (i, foot) in feet.enumerate() {
            if foot.in_contact {
                self.contact_flags |= 1 << i;
            }
            if foot.slipping {
                self.slip_flags |= 1 << i;
            }
            self.foot_force_n[i] = foot.force_n.to_array();
            self.gait_phase[i] = foot.gait_phase.unwrap_or(f64::NAN);
            n_feet = i + 1;
        }
        for i in n_feet..old_feet.max(n_feet).min(MAX_FEET) {
            self.foot_force_n[i] = [f64::NAN; 3];
            self.gait_phase[i] = f64::NAN;
        }
    }

    /// Makes `self` the frame of the sampled instant `view` (step `tick`,
    /// time `time_s`) in place, whatever frame it held (of this robot or
    /// another), writing only what the frame carries: equal bit for bit to
    /// [`Self::from_sample`] of the log's sample of that instant
    /// ([`SampleView::to_sample`]), without making that sample.
    #[inline]
    pub fn set_from_view(&mut self, s: &SampleView<'_>, tick: u64, time_s: f64) {
        let (old_dof, old_feet) = self.old_counts();
        let q = s.joint_position();
        let n_feet = s.feet();
        self.layout_version = LAYOUT_VERSION;
        self.robot_index = s.robot as u32;
        self.tick = tick;
        self.time_s = time_s;
        self.n_dof = q.len() as u32;
        self.n_feet = n_feet as u32;
        self.base_position_m = s.base_position_m().to_array();
        self.base_orientation_xyzw = s.base_orientation().to_array();
        self.base_linear_mps = s.base_linear_mps().to_array();
        self.base_angular_radps = s.base_angular_radps().to_array();
        self.rpy_rad = s.rpy_rad().to_array();
        self.com_m = s.com_m().to_array();
        self.com_velocity_mps = s.com_velocity_mps().to_array();
        fill(&mut self.joint_q_rad, q, old_dof);
        fill(&mut self.joint_qd_radps, s.joint_velocity(), old_dof);
        // a missing target is NaN over every joint (the previous frame may
        // have had one)
        let targets = s.joint_position_desired();
        fill(
            &mut self.joint_q_desired_rad,
            targets.unwrap_or(&[]),
            MAX_DOF,
        );
        match s.joint_velocity_desired() {
            Some(VelocityTargets::Given(v)) => fill(&mut self.joint_qd_desired_radps, v, MAX_DOF),
            Some(VelocityTargets::Zero(n)) => {
                let n = n.min(MAX_DOF);
                self.joint_qd_desired_radps[..n].fill(0.0);
                clear_tail(&mut self.joint_qd_desired_radps, n, MAX_DOF);
            }
            None => clear_tail(&mut self.joint_qd_desired_radps, 0, MAX_DOF),
        }
        let mut n = 0;
        for (dst, tau) in self.joint_tau_nm.iter_mut().zip(s.joint_effort()) {
            *dst = tau;
            n += 1;
        }
        clear_tail(&mut self.joint_tau_nm, n, old_dof);
        fill(
            &mut self.joint_tau_desired_nm,
            s.joint_effort_command(),
            old_dof,
        );
        let n_feet = n_feet.min(MAX_FEET);
        self.set_feet((0..n_feet).map(|i| s.foot(i)), old_feet);
    }

    /// Makes `self` equal to [`Self::from_sample`]`(s, tick, time_s)` in
    /// place, whatever frame it held (of this robot or another), as
    /// [`Self::set_from_view`] does from a view.
    pub fn set_from_sample(&mut self, s: &RobotSample, tick: u64, time_s: f64) {
        let (old_dof, old_feet) = self.old_counts();
        let all_dof = MAX_DOF;
        self.layout_version = LAYOUT_VERSION;
        self.robot_index = s.robot as u32;
        self.tick = tick;
        self.time_s = time_s;
        self.n_dof = s.joint_position.len() as u32;
        self.n_feet = s.feet.len() as u32;
        self.base_position_m = s.base_position_m.to_array();
        self.base_orientation_xyzw = s.base_orientation.to_array();
        self.base_linear_mps = s.base_linear_mps.to_array();
        self.base_angular_radps = s.base_angular_radps.to_array();
        self.rpy_rad = s.rpy_rad.to_array();
        self.com_m = s.com_m.to_array();
        self.com_velocity_mps = s.com_velocity_mps.to_array();
        fill(&mut self.joint_q_rad, &s.joint_position, old_dof);
        fill(&mut self.joint_qd_radps, &s.joint_velocity, old_dof);
        // a missing target is NaN over every joint (the previous frame may
        // have had one)
        let targets = s.joint_position_desired.as_deref();
        fill(
            &mut self.joint_q_desired_rad,
            targets.unwrap_or(&[]),
            all_dof,
        );
        let targets = s.joint_velocity_desired.as_deref();
        fill(
            &mut self.joint_qd_desired_radps,
            targets.unwrap_or(&[]),
            all_dof,
        );
        fill(&mut self.joint_tau_nm, &s.joint_effort, old_dof);
        fill(
            &mut self.joint_tau_desired_nm,
            &s.joint_effort_command,
            old_dof,
        );
        self.set_feet(s.feet.iter().take(MAX_FEET).cloned(), old_feet);
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DQuat, DVec3};
    use quadsim_systems::FootLog;

    /// A sample with `dof` joints and `feet` feet, values from `seed`.
    fn sample(dof: usize, feet: usize, targets: bool, seed: f64) -> RobotSample {
        let v = |k: f64| (0..dof).map(|i| seed + k + i as f64).collect::<Vec<_>>();
        RobotSample {
            robot: 3,
            q: v(0.0),
            v: v(1.0),
            base_position_m: DVec3::splat(seed),
            base_orientation: DQuat::from_rotation_z(seed),
            base_linear_mps: DVec3::splat(seed + 1.0),
            base_angular_radps: DVec3::splat(seed + 2.0),
            rpy_rad: DVec3::splat(seed + 3.0),
            com_m: DVec3::splat(seed + 4.0),
            com_velocity_mps: DVec3::splat(seed + 5.0),
            com_acceleration_mps2: DVec3::ZERO,
            joint_position: v(10.0),
            joint_velocity: v(20.0),
            joint_effort: v(30.0),
            joint_effort_command: v(40.0),
            joint_position_desired: targets.then(|| v(50.0)),
            joint_velocity_desired: targets.then(|| v(60.0)),
            feet: (0..feet)
                .map(|i| FootLog {
                    in_contact: i % 2 == 0,
                    slipping: i == 1,
                    penetration_m: 0.0,
                    normal_force_n: 0.0,
                    force_n: DVec3::splat(seed + i as f64),
                    position_m: DVec3::ZERO,
                    gait_phase: targets.then_some(0.25 * i as f64),
                })
                .collect(),
            virtual_wrench: None,
            sensing: None,
            link_transforms: Vec::new(),
        }
    }

    /// Rewriting a frame in place gives the fresh frame bit for bit (NaN
    /// included), whatever it held before: a longer robot with targets and
    /// more feet, a shorter one, or the same robot again.
    #[test]
    fn rewriting_in_place_equals_a_fresh_frame() {
        let bits = |f: &RobotFrame| format!("{f:?}");
        let cases = [
            (sample(16, 4, true, 1.0), sample(12, 2, false, 2.0)),
            (sample(12, 2, false, 2.0), sample(16, 4, true, 1.0)),
            (sample(16, 4, true, 1.0), sample(16, 4, true, 5.0)),
            (sample(30, 6, true, 1.0), sample(3, 1, false, 7.0)),
        ];
        for (before, after) in &cases {
            let mut f = RobotFrame::from_sample(before, 8, 0.004);
            f.set_from_sample(after, 12, 0.006);
            let fresh = RobotFrame::from_sample(after, 12, 0.006);
            assert_eq!(bits(&f), bits(&fresh));
        }
        // and the fresh frame has NaN past the robot's joints and feet
        let f = RobotFrame::from_sample(&sample(12, 2, false, 2.0), 0, 0.0);
        assert!(f.joint_q_rad[12..].iter().all(|x| x.is_nan()));
        assert!(f.joint_q_desired_rad.iter().all(|x| x.is_nan()));
        assert!(f.foot_force_n[2..].iter().flatten().all(|x| x.is_nan()));
        assert_eq!(f.joint_q_rad[11], 2.0 + 10.0 + 11.0);
    }
}
