//! The 3-DOF D-H leg of Study B's `quad12`: hip yaw about z, then hip pitch
//! and knee about parallel y axes, solved in closed form.
//!
//! # Geometry (read from the model)
//! The yaw joint's frame at zero angle (the *mount*: the torso corner turned
//! outward by the leg yaw) may be any rigid transform. Two pitch joints about
//! `+y` follow, each placed by a pure translation (`o₁` yaw→pitch, `o₂`
//! pitch→knee), and the foot point `o₃` is fixed in the shank's body. In the
//! yawed hip frame the foot is `h = (X, d, Z)` with the constant offset
//! `d = o₁ʸ + o₂ʸ + o₃ʸ` and `Z + iX = w₁ + e^{iθ₂}(w₂ + e^{iθ₃}w₃)`,
//! `w_k = o_kᶻ + i o_kˣ`; in the mount frame it is `R_z(θ₁) h`. For quad12
//! `o₁ = (0, l1, 0)`, `o₂ = (l2, 0, 0)`, `o₃ = (l3 + pad radius, 0, 0)` for the
//! contact point, which is Study B's forward kinematics with the mount yaw
//! added.
//!
//! # Inverse (closed form)
//! 1. Mount frame: `p = mount⁻¹(target)`.
//! 2. Yaw: in the complex `x + iy` plane, `p_x + i p_y = e^{iθ₁}(X + id)`, so
//!    `X = +√(p_x² + p_y² − d²)` (the foot outward of the yaw axis, the
//!    nominal branch) and `θ₁ = atan2(p_y, p_x) − atan2(d, X)`; `Z = p_z`.
//! 3. Thigh and shank: `D = (Z + iX) − w₁`, `cos γ = (|D|² − |w₂|² − |w₃|²) /
//!    (2|w₂||w₃|)` with the knee bend `γ = θ₃ + arg w₃ − arg w₂` (= θ₃ for
//!    quad12) on the chosen branch, and `θ₂ = arg D − arg(w₂ + e^{iθ₃}w₃)`.
//!
//! `docs/study_b_kinematics.md` compares this with the study's printed inverse.

use super::ik::{
    IkClamped, IkError, IkOptions, Link, cis4, cmul, dls_solve, knee_bend, planar, rotation_z,
    two_link_links, wrap_angle,
};
use super::{LegError, chain_of, foot_point_in_body};
use crate::model::Model;
use crate::spatial::Transform;
use glam::{DMat3, DVec2, DVec3};

/// Knee-bend sign of quad12's nominal stance (knee π/3).
const NOMINAL_BEND: f64 = 1.0;

/// A yaw–pitch–pitch leg (quad12), derived from a compiled [`Model`].
///
/// Positions are in the base (torso) frame, angles in the leg's q order
/// `[hip_yaw, hip_pitch, knee]` (rad).
#[derive(Clone, Debug, PartialEq)]
pub struct Quad12Leg {
    foot_frame: usize,
    point_in_foot_m: DVec3,
    mount: Transform,
    mount_inv: Transform,
    offset_m: f64,
    links: [DVec2; 3],
    /// `links[1]` (thigh) and `links[2]` (shank) with their lengths and
    /// arguments, for the two-link solve.
    thigh: Link,
    shank: Link,
    q_index: [usize; 3],
    v_index: [usize; 3],
}

impl Quad12Leg {
    /// The leg ending at `foot_frame`, placing `point_in_foot_m` (m, foot
    /// link frame).
    ///
    /// # Errors
    /// [`LegError`] when the chain from the base to the frame is not a hip
    /// yaw about z followed by two translated pitch joints about y.
    pub fn from_model(
        model: &Model,
        foot_frame: usize,
        point_in_foot_m: DVec3,
    ) -> Result<Self, LegError> {
        let chain = chain_of(model, foot_frame, &[DVec3::Z, DVec3::Y, DVec3::Y])?;
        let o3 = foot_point_in_body(model, foot_frame, point_in_foot_m);
        let o = [chain[1].placement.trans, chain[2].placement.trans, o3];
        let mount = chain[0].placement;
        let links = o.map(planar);
        Ok(Quad12Leg {
            foot_frame,
            point_in_foot_m,
            mount,
            mount_inv: mount.inverse(),
            offset_m: o.iter().map(|v| v.y).sum(),
            links,
            thigh: Link::new(links[1]),
            shank: Link::new(links[2]),
            q_index: std::array::from_fn(|k| chain[k].q_index),
            v_index: std::array::from_fn(|k| chain[k].v_index),
        })
    }

    /// Frame index of the foot link.
    pub fn foot_frame(&self) -> usize {
        self.foot_frame
    }

    /// The point the kinematics place (m, foot link frame).
    pub fn point_in_foot_m(&self) -> DVec3 {
        self.point_in_foot_m
    }

    /// The hip mount: the yaw joint's frame at zero angle, in the base frame.
    pub fn mount(&self) -> Transform {
        self.mount
    }

    /// Indices of the leg's joints in q.
    pub fn q_indices(&self) -> &[usize; 3] {
        &self.q_index
    }

    /// Indices of the leg's joints in v.
    pub fn v_indices(&self) -> &[usize; 3] {
        &self.v_index
    }

    /// The leg's angles gathered from a full configuration `q`.
    ///
    /// # Panics
    /// When `q` is shorter than the model's.
    pub fn angles_from_q(&self, q: &[f64]) -> [f64; 3] {
        self.q_index.map(|i| q[i])
    }

    /// Constant offset of the foot along the pitch axes from the yaw axis
    /// (m; Study B's l1 for the built-in).
    pub fn lateral_offset_m(&self) -> f64 {
        self.offset_m
    }

    /// Foot point in the base frame (m) at joint angles `a` (rad).
    pub fn fk(&self, a: [f64; 3]) -> DVec3 {
        let [w1, w2, w3] = self.links;
        let [e0, e1, e2, _] = cis4([a[0], a[1], a[2], 0.0]);
        let w = w1 + cmul(e1, w2 + cmul(e2, w3));
        let hip = DVec3::new(w.y, self.offset_m, w.x);
        self.mount.transform_point(rotation_z(e0) * hip)
    }

    /// Knee bend (rad): the signed angle from the thigh to the shank (knee →
    /// foot point), 0 for a straight leg; its sign is the [`super::KneeBranch`].
    pub fn knee_bend_rad(&self, a: [f64; 3]) -> f64 {
        knee_bend(self.links[1], self.links[2], a[2])
    }

    /// Joint angles (rad, each in (−π, π]) that put the foot point at
    /// `target_m` (base frame), with the foot outward of the yaw axis.
    /// `opts.ankle` is ignored.
    ///
    /// # Errors
    /// [`IkError::NonFinite`], [`IkError::InsideOffset`],
    /// [`IkError::OutOfReach`].
    pub fn ik(&self, target_m: DVec3, opts: &IkOptions) -> Result<[f64; 3], IkError> {
        self.solve(target_m, opts, false).map(|(a, _)| a)
    }

    /// Like [`Self::ik`], but an unreachable target is projected onto the
    /// reachable workspace: onto the offset cylinder about the yaw axis, then,
    /// in the leg plane through the target, radially about the hip pitch
    /// joint onto the annulus the foot reaches. A target beyond the straight
    /// leg thus gets the straight leg pointing at it from the hip pitch joint
    /// (the nearest point of that plane; with the lateral offset l1 the
    /// nearest point in space turns the leg a little further toward it).
    ///
    /// # Errors
    /// [`IkError::NonFinite`] only.
    pub fn ik_clamped(&self, target_m: DVec3, opts: &IkOptions) -> Result<IkClamped<3>, IkError> {
        let (angles_rad, clamped) = self.ik_clamped_angles(target_m, opts)?;
        Ok(IkClamped {
            angles_rad,
            foot_m: self.fk(angles_rad),
            clamped,
        })
    }

    /// [`Self::ik_clamped`]'s angles and whether the target was projected,
    /// without the forward kinematics of the foot point reached (the
    /// controllers' per-tick IK reads only the angles).
    ///
    /// # Errors
    /// [`IkError::NonFinite`] only.
    pub fn ik_clamped_angles(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
    ) -> Result<([f64; 3], bool), IkError> {
        self.solve(target_m, opts, true)
    }

    fn solve(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        clamp: bool,
    ) -> Result<([f64; 3], bool), IkError> {
        if !target_m.is_finite() {
            return Err(IkError::NonFinite { target_m });
        }
        let p = self.mount_inv.transform_point(target_m);
        let d = self.offset_m;
        let rho = crate::linalg::hypot(p.x, p.y);
        let inside = rho < d.abs();
        if inside && !clamp {
            return Err(IkError::InsideOffset {
                distance_m: rho,
                offset_m: d.abs(),
            });
        }
        // foot outward of the yaw axis: X ≥ 0
        let x = if inside {
            0.0
        } else {
            ((rho - d.abs()) * (rho + d.abs())).sqrt()
        };
        let yaw = wrap_angle(p.y.atan2(p.x) - d.atan2(x));
        let target = DVec2::new(p.z, x) - self.links[0];
        let sign = opts.knee.sign(NOMINAL_BEND);
        let (pitch, knee, out) = two_link_links(&self.thigh, &self.shank, target, sign, clamp)?;
        Ok(([yaw, pitch, knee], inside || out))
    }

    /// The leg's Jacobian (m/rad, base frame): column k is `∂ foot / ∂ a[k]`.
    pub fn jacobian(&self, a: [f64; 3]) -> [DVec3; 3] {
        let [w1, w2, w3] = self.links;
        let [e0, e1, e12, _] = cis4([a[0], a[1], a[1] + a[2], 0.0]);
        let t3 = cmul(e12, w3);
        let t2 = cmul(e1, w2) + t3;
        let w = w1 + t2;
        let hip = DVec3::new(w.y, self.offset_m, w.x);
        let yaw = rotation_z(e0);
        let r = self.mount.rot * yaw;
        let pitch_col = |t: DVec2| {
            let dt = t.perp();
            r * DVec3::new(dt.y, 0.0, dt.x)
        };
        [
            self.mount.rot * DVec3::Z.cross(yaw * hip),
            pitch_col(t2),
            pitch_col(t3),
        ]
    }

    /// Joint velocities (rad/s) that move the foot point at `foot_velocity`
    /// (m/s, base frame), by damped least squares on [`Self::jacobian`] (see
    /// [`IkOptions::velocity_damping_m`]). For swing-leg PD.
    ///
    /// # Errors
    /// [`IkError::Singular`] for the exact map (damping 0) at a singular pose.
    pub fn joint_velocities(
        &self,
        a: [f64; 3],
        foot_velocity: DVec3,
        opts: &IkOptions,
    ) -> Result<[f64; 3], IkError> {
        let [j1, j2, j3] = self.jacobian(a);
        let x = dls_solve(
            DMat3::from_cols(j1, j2, j3),
            foot_velocity,
            opts.velocity_damping_m,
        )?;
        Ok(x.to_array())
    }

    /// Shortest and longest hip-pitch-to-foot reach (m).
    pub fn reach_m(&self) -> (f64, f64) {
        let (la, lb) = (self.links[1].length(), self.links[2].length());
        ((la - lb).abs(), la + lb)
    }
}
