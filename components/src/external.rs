//! A controller in another process: the joint command it sent last (see the
//! root crate's `monitor::command` and docs/monitor.md), held until the next.

/// Joint-level command from an external controller, applied at the control
/// rate: `τ = τ_ff + kp (q* − q) + kd (q̇* − q̇)` per joint. Pure torque
/// commands are `kp = kd = 0`. Before the first command every gain and
/// torque is zero (limp joints).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExternalJoint {
    /// Target joint angles (rad), joints only (nv − base).
    pub target_rad: Vec<f64>,
    /// Target joint velocities (rad/s).
    pub target_radps: Vec<f64>,
    /// Proportional gains (N·m/rad).
    pub kp_nm_per_rad: Vec<f64>,
    /// Derivative gains (N·m·s/rad).
    pub kd_nms_per_rad: Vec<f64>,
    /// Feed-forward torques (N·m).
    pub feedforward_nm: Vec<f64>,
    /// Tick of the command in force (`None` before the first).
    pub tick: Option<u64>,
}

impl ExternalJoint {
    /// Limp joints holding targets `q_joints` (rad) until a command arrives.
    pub fn idle(q_joints: &[f64]) -> Self {
        let n = q_joints.len();
        Self {
            target_rad: q_joints.to_vec(),
            target_radps: vec![0.0; n],
            kp_nm_per_rad: vec![0.0; n],
            kd_nms_per_rad: vec![0.0; n],
            feedforward_nm: vec![0.0; n],
            tick: None,
        }
    }

    /// Writes joint torques into `tau_joints` (joints only; q and q̇ joints only).
    pub fn compute(&self, q_joints: &[f64], qd_joints: &[f64], tau_joints: &mut [f64]) {
        for i in 0..tau_joints.len() {
            tau_joints[i] = self.feedforward_nm[i]
                + self.kp_nm_per_rad[i] * (self.target_rad[i] - q_joints[i])
                + self.kd_nms_per_rad[i] * (self.target_radps[i] - qd_joints[i]);
        }
    }
}
