//! Any 3- or 4-DOF serial leg read from a compiled [`Model`]: hip
//! abduction/roll (about ~x) or hip yaw (about ~z), then hip pitch and knee
//! (and an optional ankle) about parallel ~y axes, with any axis signs and
//! mounts. Inverse kinematics by damped least squares on the leg's point
//! Jacobian, so that robots the closed forms ([`super::Quad16Leg`],
//! [`super::Quad12Leg`]) do not fit can walk.
//!
//! # Frames and signs
//! Positions are in the base (torso) frame, angles in the leg's q order
//! (rad, each joint's own sign: a joint whose URDF axis is `−y` turns the
//! other way from one about `+y`). The kinematics are the engine's: joint k's
//! frame is its parent's composed with the model's placement, then a turn
//! about the model's axis (`crate::kinematics`); the Jacobian's column k is
//! `axis_k × (foot − origin_k)` in the base frame, the base-fixed rows of
//! [`crate::jacobian::point_jacobian`] (tests compare them). They are
//! computed here on the leg's own chain so that a solve reads no `Data` and
//! allocates nothing (the walker solves every leg every tick).
//!
//! # The leg frame
//! A solve starts from a geometric guess made in the *leg frame*: origin at
//! the first joint, `x` along the roll axis (roll legs) or across the
//! pitch axes toward the leg's reach at zero angles (yaw legs), `y` along
//! the pitch axes (pointing left for a roll leg), `z` up. Pitch joint k turns about `s_k·y` with
//! `s_k = ±1`.
//!
//! # Knee branch
//! The knee *bend* is the signed angle, about the knee's own axis, from the
//! thigh (hip pitch joint → knee) to the shank (knee → wrist; the wrist is
//! the ankle joint when the foot pitch is held, else the foot point). Its
//! sign is the [`KneeBranch`] in this leg's joint-angle sense. The nominal
//! branch is the one that puts the knee behind or above the hip–foot line
//! (displaced toward `−x + z` of the base): a dog's knees (Mini Cheetah,
//! A1, quad16) and quad12's raised knees.
//!
//! # Inverse (damped least squares)
//! From the guess, `Δa = Jᵀ(JJᵀ + λ²I)⁻¹ (target − fk(a))` on the 3 × 3
//! Jacobian (for a 4-DOF leg the ankle follows its [`AnkleMode`] rule and
//! its column folds into the others), each step at most
//! [`MAX_STEP_RAD`], the angles wrapped and clamped to the model's joint
//! limits, the knee mirrored back through straight if it crossed to the
//! other branch. It stops when the foot is within [`TOL_M`] of the target,
//! when a step changes no angle by more than 1e-15 rad (an unreachable
//! target: the nearest point the iteration reaches), or after
//! [`MAX_ITERATIONS`].

use super::ik::{
    AnkleMode, IkClamped, IkError, IkOptions, KneeBranch, cmul, dls_solve, planar, two_link,
    wrap_angle,
};
use super::{LegError, foot_point_in_body};
use crate::model::{JointType, Model};
use crate::spatial::Transform;
use glam::{DMat3, DVec2, DVec3};

/// Largest change of any angle in one iteration (rad): keeps a far guess
/// from jumping branches.
pub const MAX_STEP_RAD: f64 = 0.5;
/// Foot position tolerance of a converged solve (m).
pub const TOL_M: f64 = 1e-12;
/// Iteration bound of one solve.
pub const MAX_ITERATIONS: usize = 60;
/// Damping λ (m) of the IK iteration: small against a leg's singular
/// values (≥ 1 cm away from a straight knee) so that it converges in a few
/// steps, nonzero so that a straight knee (an unreachable target) stays
/// bounded.
pub const IK_DAMPING_M: f64 = 1e-4;
/// Largest angle (rad, ~30°) between a joint's axis and the direction its
/// role needs.
const AXIS_TOL_RAD: f64 = 0.52;

/// The hip's first joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HipKind {
    /// Abduction/roll about ~x of the base (Mini Cheetah, A1, ANYmal, quad16).
    Roll,
    /// Yaw about ~z of the base (quad12).
    Yaw,
}

/// What a numerical solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkStats {
    /// Iterations taken (0: the guess was within tolerance).
    pub iterations: usize,
    /// Distance from the foot reached to the target (m).
    pub residual_m: f64,
}

/// A serial leg (see the module docs), derived from a compiled [`Model`].
#[derive(Clone, Debug, PartialEq)]
pub struct SerialLeg {
    foot_frame: usize,
    point_in_foot_m: DVec3,
    dof: usize,
    hip: HipKind,
    /// First joint's frame at zero angle, base frame.
    mount: Transform,
    mount_inv: Transform,
    /// Joint k's placement in joint k−1's body (entry 0 unused).
    placement: [Transform; 4],
    /// Joint axes, each in its own joint frame (unit).
    axis: [DVec3; 4],
    /// Foot point in the last joint's body (m).
    tip_m: DVec3,
    /// Leg frame (columns x, y, z in the base frame; origin the mount's).
    leg_rot: DMat3,
    /// Signs of the joints about the leg frame's axes: `[s0 about x or z,
    /// s1, s2, s3 about y]`.
    sign: [f64; 4],
    /// Pitch-plane links in the leg frame at zero angles (complex `z + i·x`):
    /// first joint → hip pitch, hip pitch → knee, knee → ankle (or foot),
    /// ankle → foot.
    links: [DVec2; 4],
    /// Constant offset of the foot along the pitch axes (m, leg frame y).
    offset_m: f64,
    /// Knee-bend sign of [`KneeBranch::Nominal`].
    nominal_bend: f64,
    lower_rad: [f64; 4],
    upper_rad: [f64; 4],
    q_index: [usize; 4],
    v_index: [usize; 4],
}

/// The rotation about unit `axis` by `angle` (rad).
#[inline]
fn rot(axis: DVec3, angle: f64) -> DMat3 {
    DMat3::from_axis_angle(axis, angle)
}

/// Signed angle (rad) from `a` to `b` about unit `k`, both projected onto
/// the plane normal to `k`.
#[inline]
fn angle_about(k: DVec3, a: DVec3, b: DVec3) -> f64 {
    let a = a - k * a.dot(k);
    let b = b - k * b.dot(k);
    a.cross(b).dot(k).atan2(a.dot(b))
}

/// Joint origins, axes (base frame) and the foot point of one pose.
struct Pose {
    origin: [DVec3; 4],
    axis: [DVec3; 4],
    foot: DVec3,
}

impl SerialLeg {
    /// The leg ending at `foot_frame`, placing `point_in_foot_m` (m, foot
    /// link frame).
    ///
    /// # Errors
    /// [`LegError::UnknownFrame`]; [`LegError::Serial`] (naming the foot and
    /// the joint) when the chain has not 3 or 4 joints, a joint is not
    /// revolute, or an axis is not about the direction its role needs.
    pub fn from_model(
        model: &Model,
        foot_frame: usize,
        point_in_foot_m: DVec3,
    ) -> Result<Self, LegError> {
        let bodies = super::chain_bodies(model, foot_frame)?;
        let foot = model.frames[foot_frame].name.clone();
        let err = |b: usize, why: String| LegError::Serial {
            foot: foot.clone(),
            joint: model.joint_name[b].clone(),
            why,
        };
        let dof = bodies.len();
        if !(dof == 3 || dof == 4) {
            let last = bodies.last().copied().unwrap_or(0);
            return Err(err(
                last,
                format!(
                    "ends a chain of {dof} joints from the base; a serial leg has 3 (hip \
                     abduction, hip pitch, knee) or 4 (and an ankle)"
                ),
            ));
        }
        for &b in &bodies {
            if model.joint_type[b] != JointType::Revolute {
                return Err(err(b, "must be revolute".into()));
            }
        }
        let mut placement = [Transform::default(); 4];
        let mut axis = [DVec3::ZERO; 4];
        let mut q_index = [0; 4];
        let mut v_index = [0; 4];
        let mut lower_rad = [f64::NEG_INFINITY; 4];
        let mut upper_rad = [f64::INFINITY; 4];
        for (k, &b) in bodies.iter().enumerate() {
            placement[k] = model.placement[b];
            axis[k] = model.axis[b].normalize();
            q_index[k] = model.idx_q[b];
            v_index[k] = model.idx_v[b];
            lower_rad[k] = model.lower_limit[model.idx_v[b]];
            upper_rad[k] = model.upper_limit[model.idx_v[b]];
        }
        let mount = placement[0];
        placement[0] = Transform::default();
        let tip_m = foot_point_in_body(model, foot_frame, point_in_foot_m);
        let mut leg = SerialLeg {
            foot_frame,
            point_in_foot_m,
            dof,
            hip: HipKind::Roll,
            mount,
            mount_inv: mount.inverse(),
            placement,
            axis,
            tip_m,
            leg_rot: DMat3::IDENTITY,
            sign: [1.0; 4],
            links: [DVec2::ZERO; 4],
            offset_m: 0.0,
            nominal_bend: -1.0,
            lower_rad,
            upper_rad,
            q_index,
            v_index,
        };
        // classify at zero angles, base frame
        let zero = leg.pose(&[0.0; 4]);
        let cos_tol = AXIS_TOL_RAD.cos();
        let a0 = zero.axis[0];
        let (hip, ex_raw) = if a0.x.abs() >= cos_tol {
            (HipKind::Roll, a0 * a0.x.signum())
        } else if a0.z.abs() >= cos_tol {
            (HipKind::Yaw, DVec3::ZERO)
        } else {
            return Err(err(
                bodies[0],
                format!(
                    "axis is {a0} in the base frame; the hip's first joint turns about ~x \
                     (abduction/roll) or ~z (yaw)"
                ),
            ));
        };
        let pitch = zero.axis[1];
        if pitch.dot(a0).abs() > AXIS_TOL_RAD.sin() {
            return Err(err(
                bodies[1],
                format!("axis is {pitch}, not across the first joint's {a0} (hip pitch)"),
            ));
        }
        for k in 2..dof {
            if zero.axis[k].dot(pitch).abs() < cos_tol {
                return Err(err(
                    bodies[k],
                    format!(
                        "axis is {}, not parallel to the hip pitch axis {pitch} (knee/ankle)",
                        zero.axis[k]
                    ),
                ));
            }
        }
        let (ex, ey, ez) = match hip {
            HipKind::Roll => {
                if pitch.y.abs() < cos_tol {
                    return Err(err(
                        bodies[1],
                        format!("axis is {pitch} in the base frame; the hip pitch turns about ~y"),
                    ));
                }
                let ex = ex_raw.normalize();
                let ey = (pitch - ex * pitch.dot(ex)).normalize();
                let ey = ey * ey.y.signum();
                (ex, ey, ex.cross(ey))
            }
            HipKind::Yaw => {
                // y along the pitch axes, turned so that x points along the
                // leg's reach at zero angles
                let ez = a0 * a0.z.signum();
                let ey = (pitch - ez * pitch.dot(ez)).normalize();
                let ex = ey.cross(ez);
                if ex.dot(zero.foot - zero.origin[0]) >= 0.0 {
                    (ex, ey, ez)
                } else {
                    (-ex, -ey, ez)
                }
            }
        };
        let leg_rot = DMat3::from_cols(ex, ey, ez);
        let mut sign = [1.0; 4];
        sign[0] = match hip {
            HipKind::Roll => a0.dot(ex).signum(),
            HipKind::Yaw => a0.dot(ez).signum(),
        };
        for k in 1..dof {
            sign[k] = zero.axis[k].dot(ey).signum();
        }
        // pitch-plane links at zero angles, in the leg frame
        let to_leg = |v: DVec3| leg_rot.transpose() * v;
        let mut pts = [DVec3::ZERO; 5];
        for k in 0..dof {
            pts[k] = to_leg(zero.origin[k] - zero.origin[0]);
        }
        pts[dof] = to_leg(zero.foot - zero.origin[0]);
        let mut links = [DVec2::ZERO; 4];
        for k in 0..dof {
            links[k] = planar(pts[k + 1] - pts[k]);
        }
        leg.hip = hip;
        leg.leg_rot = leg_rot;
        leg.sign = sign;
        leg.links = links;
        leg.offset_m = pts[dof].y;
        // nominal branch: the knee bent by +0.3 rad displaced toward −x + z
        let mut bent = [0.0; 4];
        bent[2] = 0.3;
        let p = leg.pose(&bent);
        let wrist = if dof == 4 { p.origin[3] } else { p.foot };
        let line = (wrist - p.origin[1]).normalize_or_zero();
        let knee = p.origin[2] - p.origin[1];
        let off = knee - line * knee.dot(line);
        leg.nominal_bend = if off.dot(DVec3::new(-1.0, 0.0, 1.0)) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        Ok(leg)
    }

    /// Poses of the chain's joints and foot at angles `a` (base frame).
    #[inline]
    fn pose(&self, a: &[f64]) -> Pose {
        let mut t = self.mount;
        let mut origin = [DVec3::ZERO; 4];
        let mut axis = [DVec3::ZERO; 4];
        for k in 0..self.dof {
            if k > 0 {
                t = t.compose(&self.placement[k]);
            }
            origin[k] = t.trans;
            axis[k] = t.rot * self.axis[k];
            t.rot *= rot(self.axis[k], a[k]);
        }
        Pose {
            origin,
            axis,
            foot: t.transform_point(self.tip_m),
        }
    }

    /// Number of joints (3 or 4).
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// The hip's first joint.
    pub fn hip_kind(&self) -> HipKind {
        self.hip
    }

    /// Frame index of the foot link.
    pub fn foot_frame(&self) -> usize {
        self.foot_frame
    }

    /// The point the kinematics place (m, foot link frame).
    pub fn point_in_foot_m(&self) -> DVec3 {
        self.point_in_foot_m
    }

    /// The hip mount: the first joint's frame at zero angle, base frame.
    pub fn mount(&self) -> Transform {
        self.mount
    }

    /// Indices of the leg's joints in q.
    pub fn q_indices(&self) -> &[usize] {
        &self.q_index[..self.dof]
    }

    /// Indices of the leg's joints in v.
    pub fn v_indices(&self) -> &[usize] {
        &self.v_index[..self.dof]
    }

    /// Signs of the joints about the leg frame's axes (`±1`: roll about x
    /// or yaw about z, then pitch joints about y).
    pub fn axis_signs(&self) -> &[f64] {
        &self.sign[..self.dof]
    }

    /// The leg frame (columns x, y, z in the base frame; module docs).
    pub fn leg_frame(&self) -> DMat3 {
        self.leg_rot
    }

    /// Constant offset of the foot along the pitch axes (m, leg frame y).
    pub fn lateral_offset_m(&self) -> f64 {
        self.offset_m
    }

    /// Thigh (hip pitch → knee) and shank (knee → wrist, the ankle for a
    /// 4-DOF leg, else the foot point) lengths (m).
    pub fn segment_lengths_m(&self) -> (f64, f64) {
        (self.links[1].length(), self.links[2].length())
    }

    /// Longest hip-pitch-to-foot distance (m): the straight leg (with a
    /// 4-DOF leg's foot link in line).
    pub fn leg_length_m(&self) -> f64 {
        self.links[1..self.dof].iter().map(|l| l.length()).sum()
    }

    /// The nominal knee-bend sign (module docs).
    pub fn nominal_bend(&self) -> f64 {
        self.nominal_bend
    }

    /// Position limits (rad) of the leg's joints.
    pub fn limits_rad(&self) -> (&[f64], &[f64]) {
        (&self.lower_rad[..self.dof], &self.upper_rad[..self.dof])
    }

    /// Foot point in the base frame (m) at joint angles `a` (rad).
    ///
    /// # Panics
    /// When `a` has fewer than [`Self::dof`] angles.
    pub fn fk(&self, a: &[f64]) -> DVec3 {
        self.pose(&a[..self.dof]).foot
    }

    /// The leg's Jacobian (m/rad, base frame): column k is `∂ foot / ∂ a[k]`
    /// (entries past [`Self::dof`] zero).
    pub fn jacobian(&self, a: &[f64]) -> [DVec3; 4] {
        let p = self.pose(&a[..self.dof]);
        let mut j = [DVec3::ZERO; 4];
        for k in 0..self.dof {
            j[k] = p.axis[k].cross(p.foot - p.origin[k]);
        }
        j
    }

    /// Knee bend (rad; module docs) at angles `a` under `ankle`.
    pub fn knee_bend_rad(&self, a: &[f64], ankle: AnkleMode) -> f64 {
        let p = self.pose(&a[..self.dof]);
        self.bend_of(&p, ankle)
    }

    #[inline]
    fn bend_of(&self, p: &Pose, ankle: AnkleMode) -> f64 {
        let wrist = if self.dof == 4 && matches!(ankle, AnkleMode::FootPitch(_)) {
            p.origin[3]
        } else {
            p.foot
        };
        angle_about(p.axis[2], p.origin[2] - p.origin[1], wrist - p.origin[2])
    }

    /// The ankle angle the rule `ankle` gives for hip pitch and knee `a`.
    #[inline]
    fn ankle_angle(&self, a: &[f64], ankle: AnkleMode) -> f64 {
        match ankle {
            // foot pitch about the leg's y: Σ s_k a_k = ψ
            AnkleMode::FootPitch(psi) => {
                self.sign[3] * (psi - self.sign[1] * a[1] - self.sign[2] * a[2])
            }
            AnkleMode::Angle(x) => x,
        }
    }

    /// The 3 × 3 Jacobian of the leg's free angles (roll/yaw, hip pitch,
    /// knee), the ankle following its rule.
    #[inline]
    fn reduced(&self, j: &[DVec3; 4], ankle: AnkleMode) -> DMat3 {
        if self.dof == 4 && matches!(ankle, AnkleMode::FootPitch(_)) {
            let (s1, s2, s3) = (self.sign[1], self.sign[2], self.sign[3]);
            DMat3::from_cols(j[0], j[1] - j[3] * (s3 * s1), j[2] - j[3] * (s3 * s2))
        } else {
            DMat3::from_cols(j[0], j[1], j[2])
        }
    }

    /// A geometric first guess (module docs): exact for a leg whose axes are
    /// the leg frame's and whose pitch joints are placed by translations,
    /// close otherwise. The knee on `bend_sign`'s branch.
    pub fn guess(&self, target_m: DVec3, opts: &IkOptions) -> [f64; 4] {
        let p = self.leg_rot.transpose() * (target_m - self.mount.trans);
        let d = self.offset_m;
        let (first, h) = match self.hip {
            HipKind::Roll => {
                let r = p.y.hypot(p.z);
                let z = -((r - d.abs()).max(0.0) * (r + d.abs())).sqrt();
                let phi = p.z.atan2(p.y) - z.atan2(d);
                (phi, DVec2::new(z, p.x))
            }
            HipKind::Yaw => {
                let rho = p.x.hypot(p.y);
                let x = ((rho - d.abs()).max(0.0) * (rho + d.abs())).sqrt();
                let psi = p.y.atan2(p.x) - d.atan2(x);
                (psi, DVec2::new(p.z, x))
            }
        };
        let s = self.sign;
        let bend = self.bend_sign(opts.knee);
        // the branch in the leg frame's +y sense
        let plane_bend = bend * s[2];
        let [w1, w2, w3, w4] = self.links;
        let mut a = [0.0; 4];
        a[0] = s[0] * wrap_angle(first);
        let (t1, t2, t3) = if self.dof == 4 {
            match opts.ankle {
                AnkleMode::FootPitch(psi) => {
                    let wrist = h - w1 - cmul(super::ik::cis(psi), w4);
                    let (t1, t2, _) =
                        two_link(w2, w3, wrist, plane_bend, true).unwrap_or((0.0, 0.0, true));
                    (t1, t2, psi - t1 - t2)
                }
                AnkleMode::Angle(x) => {
                    let u3 = w3 + cmul(super::ik::cis(s[3] * x), w4);
                    let (t1, t2, _) =
                        two_link(w2, u3, h - w1, plane_bend, true).unwrap_or((0.0, 0.0, true));
                    (t1, t2, s[3] * x)
                }
            }
        } else {
            let (t1, t2, _) =
                two_link(w2, w3, h - w1, plane_bend, true).unwrap_or((0.0, 0.0, true));
            (t1, t2, 0.0)
        };
        a[1] = s[1] * t1;
        a[2] = s[2] * t2;
        if self.dof == 4 {
            a[3] = s[3] * t3;
            a[3] = self.ankle_angle(&a, opts.ankle);
        }
        for k in 0..self.dof {
            a[k] = wrap_angle(a[k]).clamp(self.lower_rad[k], self.upper_rad[k]);
        }
        a
    }

    fn bend_sign(&self, knee: KneeBranch) -> f64 {
        knee.sign(self.nominal_bend)
    }

    /// How far (m) the foot at angles `a` is on the hip's nominal side of
    /// the first joint's axis (negative: the other side): below the roll
    /// axis for a roll hip, outward of the yaw axis for a yaw hip (the
    /// closed forms' branches).
    pub fn hip_side_m(&self, a: &[f64]) -> f64 {
        let p = self.leg_rot.transpose() * (self.fk(a) - self.mount.trans);
        let t = -self.sign[0] * a[0];
        match self.hip {
            HipKind::Roll => -(DMat3::from_rotation_x(t) * p).z,
            HipKind::Yaw => (DMat3::from_rotation_z(t) * p).x,
        }
    }

    /// Damped least squares from the angles in `a` (module docs), in place.
    /// A solution that ends on the other side of the hip's first axis
    /// ([`Self::hip_side_m`] < 0, where the guess would not) is solved again
    /// from [`Self::guess`] (iterations add up).
    ///
    /// # Errors
    /// [`IkError::NonFinite`] for a target with a NaN or infinite coordinate.
    ///
    /// # Panics
    /// When `a` has fewer than [`Self::dof`] angles.
    pub fn solve_from(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        a: &mut [f64],
    ) -> Result<IkStats, IkError> {
        let stats = self.iterate(target_m, opts, a)?;
        if self.hip_side_m(a) >= 0.0 {
            return Ok(stats);
        }
        let guess = self.guess(target_m, opts);
        if self.hip_side_m(&guess) < 0.0 {
            return Ok(stats);
        }
        a[..self.dof].copy_from_slice(&guess[..self.dof]);
        let again = self.iterate(target_m, opts, a)?;
        Ok(IkStats {
            iterations: stats.iterations + again.iterations,
            residual_m: again.residual_m,
        })
    }

    /// The iteration of [`Self::solve_from`].
    fn iterate(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        a: &mut [f64],
    ) -> Result<IkStats, IkError> {
        if !target_m.is_finite() {
            return Err(IkError::NonFinite { target_m });
        }
        let n = self.dof;
        let bend = self.bend_sign(opts.knee);
        let mut x = [0.0; 4];
        x[..n].copy_from_slice(&a[..n]);
        if n == 4 {
            x[3] = self.ankle_angle(&x, opts.ankle);
        }
        let mut iterations = 0;
        let mut residual;
        loop {
            let p = self.pose(&x);
            let e = target_m - p.foot;
            residual = e.length();
            if !residual.is_finite() {
                return Err(IkError::NonFinite { target_m });
            }
            if residual <= TOL_M || iterations >= MAX_ITERATIONS {
                break;
            }
            let mut j = [DVec3::ZERO; 4];
            for k in 0..n {
                j[k] = p.axis[k].cross(p.foot - p.origin[k]);
            }
            let m = self.reduced(&j, opts.ankle);
            let Ok(step) = dls_solve(m, e, IK_DAMPING_M) else {
                break;
            };
            let step = step.to_array();
            let big = step.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
            let scale = if big > MAX_STEP_RAD {
                MAX_STEP_RAD / big
            } else {
                1.0
            };
            let before = x;
            for k in 0..3 {
                x[k] =
                    wrap_angle(x[k] + scale * step[k]).clamp(self.lower_rad[k], self.upper_rad[k]);
            }
            // the knee back through straight onto its branch
            let b = self.bend_of(&self.pose(&x), opts.ankle);
            if b * bend < 0.0 {
                x[2] = wrap_angle(x[2] - 2.0 * b).clamp(self.lower_rad[2], self.upper_rad[2]);
            }
            if n == 4 {
                x[3] = wrap_angle(self.ankle_angle(&x, opts.ankle))
                    .clamp(self.lower_rad[3], self.upper_rad[3]);
            }
            iterations += 1;
            let moved = (0..n).fold(0.0_f64, |m, k| m.max((x[k] - before[k]).abs()));
            if moved <= 1e-15 {
                residual = (target_m - self.pose(&x).foot).length();
                break;
            }
        }
        a[..n].copy_from_slice(&x[..n]);
        Ok(IkStats {
            iterations,
            residual_m: residual,
        })
    }

    /// Joint angles (rad) that put the foot point at `target_m` (base
    /// frame), from [`Self::guess`] by damped least squares.
    ///
    /// # Errors
    /// [`IkError::NonFinite`]; [`IkError::OutOfReach`] when the iteration
    /// ends more than 1e-9 m from the target (`distance_m` is then that
    /// residual, the reach bounds the thigh and shank's).
    pub fn ik(&self, target_m: DVec3, opts: &IkOptions) -> Result<Vec<f64>, IkError> {
        let c = self.ik_clamped(target_m, opts)?;
        if c.clamped {
            let (la, lb) = self.segment_lengths_m();
            return Err(IkError::OutOfReach {
                distance_m: (c.foot_m - target_m).length(),
                min_reach_m: (la - lb).abs(),
                max_reach_m: la + lb,
            });
        }
        Ok(c.angles_rad[..self.dof].to_vec())
    }

    /// Like [`Self::ik`], but a target the leg cannot reach gives the angles
    /// the iteration ends at (the foot as near the target as it gets, within
    /// the joint limits) with `clamped` set.
    ///
    /// # Errors
    /// [`IkError::NonFinite`] only.
    pub fn ik_clamped(&self, target_m: DVec3, opts: &IkOptions) -> Result<IkClamped<4>, IkError> {
        let mut a = [0.0; 4];
        let clamped = self.ik_clamped_into(target_m, opts, &mut a)?;
        Ok(IkClamped {
            angles_rad: a,
            foot_m: self.fk(&a),
            clamped,
        })
    }

    /// [`Self::ik_clamped`]'s angles into `out` (at least [`Self::dof`]
    /// long); returns whether the target was out of reach.
    ///
    /// # Errors
    /// [`IkError::NonFinite`] only.
    pub fn ik_clamped_into(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        out: &mut [f64],
    ) -> Result<bool, IkError> {
        if !target_m.is_finite() {
            return Err(IkError::NonFinite { target_m });
        }
        let mut a = self.guess(target_m, opts);
        let stats = self.iterate(target_m, opts, &mut a)?;
        out[..self.dof].copy_from_slice(&a[..self.dof]);
        Ok(stats.residual_m > 1e-9)
    }

    /// Joint velocities (rad/s) that move the foot point at `foot_velocity`
    /// (m/s, base frame) while a 4-DOF leg's ankle follows `opts.ankle`, by
    /// damped least squares on [`Self::jacobian`] (see
    /// [`IkOptions::velocity_damping_m`]). For swing-leg PD.
    ///
    /// # Errors
    /// [`IkError::Singular`] for the exact map (damping 0) at a singular pose.
    pub fn joint_velocities_into(
        &self,
        a: &[f64],
        foot_velocity: DVec3,
        opts: &IkOptions,
        out: &mut [f64],
    ) -> Result<(), IkError> {
        let j = self.jacobian(a);
        let m = self.reduced(&j, opts.ankle);
        let x = dls_solve(m, foot_velocity, opts.velocity_damping_m)?;
        out[..3].copy_from_slice(&x.to_array());
        if self.dof == 4 {
            out[3] = match opts.ankle {
                AnkleMode::FootPitch(_) => {
                    -self.sign[3] * (self.sign[1] * x.y + self.sign[2] * x.z)
                }
                AnkleMode::Angle(_) => 0.0,
            };
        }
        Ok(())
    }
}
