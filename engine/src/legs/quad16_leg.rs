//! The 4-DOF leg of Study A's `quad16`: hip roll about x, then hip pitch, knee
//! and ankle about parallel y axes, solved in closed form.
//!
//! # Geometry (read from the model)
//! The roll joint's frame at zero angle (the *mount*, placement in the base
//! frame) may be any rigid transform. After the roll, three pitch joints
//! about `+y` follow, each placed by a pure translation (`o₁` roll→pitch,
//! `o₂` pitch→knee, `o₃` knee→ankle), and the foot point `o₄` is fixed in the
//! ankle's body. In the rolled hip frame the foot is
//! `h = (X, d, Z)`: `d = o₁ʸ + o₂ʸ + o₃ʸ + o₄ʸ` is a constant lateral offset
//! and `Z + iX = w₁ + e^{iθ₂}(w₂ + e^{iθ₃}(w₃ + e^{iθ₄}w₄))` with
//! `w_k = o_kᶻ + i o_kˣ` (see [`super::ik`]); in the mount frame the foot is
//! `R_x(θ₁) h`. For quad16 `o₁ = 0`, `o₂ = (0, 0, −thigh)`,
//! `o₃ = (0, 0, −shank)`, `o₄ = (0, 0, −2·foot radius)` for the contact point.
//!
//! # Inverse (closed form)
//! 1. Mount frame: `p = mount⁻¹(target)`.
//! 2. Roll: in the complex `y + iz` plane, `p_y + i p_z = e^{iθ₁}(d + iZ)`, so
//!    `Z = −√(p_y² + p_z² − d²)` (the foot below the roll axis, the nominal
//!    branch) and `θ₁ = atan2(p_z, p_y) − atan2(Z, d)`; `X = p_x`.
//! 3. Ankle held at foot pitch `ψ` (`θ₂ + θ₃ + θ₄ = ψ`): the ankle must sit at
//!    `D = (Z + iX) − w₁ − e^{iψ}w₄`; the thigh and shank reach it by the law
//!    of cosines, `cos γ = (|D|² − |w₂|² − |w₃|²) / (2|w₂||w₃|)` with the
//!    knee bend `γ = θ₃ + arg w₃ − arg w₂` (= θ₃ for quad16) on the chosen
//!    branch, then `θ₂ = arg D − arg(w₂ + e^{iθ₃}w₃)` and `θ₄ = ψ − θ₂ − θ₃`.
//!    Ankle held at `θ₄ = a`: the shank and foot are one link
//!    `u₃ = w₃ + e^{ia}w₄` and the same two-link solve places the foot point.

use super::ik::{
    AnkleMode, IkClamped, IkError, IkOptions, Link, cis, cis4, cmul, dls_solve, knee_bend, planar,
    rotation_x, two_link, two_link_links, wrap_angle,
};
use super::{LegError, chain_of, foot_point_in_body};
use crate::model::Model;
use crate::spatial::Transform;
use glam::{DMat3, DVec2, DVec3};

/// Knee-bend sign of quad16's nominal stance (knee −0.6 rad).
pub(crate) const NOMINAL_BEND: f64 = -1.0;

/// A roll–pitch–pitch–pitch leg (quad16), derived from a compiled [`Model`].
///
/// Positions are in the base (torso) frame, angles in the leg's q order
/// `[hip_roll, hip_pitch, knee, ankle]` (rad).
#[derive(Clone, Debug, PartialEq)]
pub struct Quad16Leg {
    foot_frame: usize,
    point_in_foot_m: DVec3,
    mount: Transform,
    pub(crate) mount_inv: Transform,
    pub(crate) offset_m: f64,
    pub(crate) links: [DVec2; 4],
    /// `links[1]` (thigh) and `links[2]` (shank) with their lengths and
    /// arguments, the two-link solve's fixed links under
    /// [`AnkleMode::FootPitch`].
    pub(crate) thigh: Link,
    pub(crate) shank: Link,
    /// `e^{i·0} w₄`: the foot link held level ([`AnkleMode::FootPitch`]`(0)`,
    /// the default), computed once as [`Self::pitch_chain`] would at every
    /// solve (the same bits; saves a `sin_cos` call per solve).
    pub(crate) foot_level: DVec2,
    q_index: [usize; 4],
    v_index: [usize; 4],
}

/// `atan2(z, d)`: the argument of the foot's `d + iZ` in the roll plane.
/// With no lateral offset (`d = ±0`, quad16's contact point) and the foot
/// below the roll axis (`Z < 0`), `atan2` answers exactly `−π/2` (C's
/// `atan2(y < 0, ±0)`, checked by a unit test): one `atan2` call of four
/// per leg solve skipped, the same bits.
#[inline]
pub(crate) fn foot_arg(z: f64, d: f64) -> f64 {
    if d == 0.0 && z < 0.0 {
        -std::f64::consts::FRAC_PI_2
    } else {
        z.atan2(d)
    }
}

impl Quad16Leg {
    /// The leg ending at `foot_frame`, placing `point_in_foot_m` (m, foot
    /// link frame).
    ///
    /// # Errors
    /// [`LegError`] when the chain from the base to the frame is not a hip
    /// roll about x followed by three translated pitch joints about y.
    pub fn from_model(
        model: &Model,
        foot_frame: usize,
        point_in_foot_m: DVec3,
    ) -> Result<Self, LegError> {
        let chain = chain_of(model, foot_frame, &[DVec3::X, DVec3::Y, DVec3::Y, DVec3::Y])?;
        let o4 = foot_point_in_body(model, foot_frame, point_in_foot_m);
        let o = [
            chain[1].placement.trans,
            chain[2].placement.trans,
            chain[3].placement.trans,
            o4,
        ];
        let mount = chain[0].placement;
        let links = o.map(planar);
        Ok(Quad16Leg {
            foot_frame,
            point_in_foot_m,
            mount,
            mount_inv: mount.inverse(),
            offset_m: o.iter().map(|v| v.y).sum(),
            links,
            thigh: Link::new(links[1]),
            shank: Link::new(links[2]),
            foot_level: cmul(cis(0.0), links[3]),
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

    /// The hip mount: the roll joint's frame at zero angle, in the base frame.
    pub fn mount(&self) -> Transform {
        self.mount
    }

    /// Indices of the leg's joints in q.
    pub fn q_indices(&self) -> &[usize; 4] {
        &self.q_index
    }

    /// Indices of the leg's joints in v.
    pub fn v_indices(&self) -> &[usize; 4] {
        &self.v_index
    }

    /// The leg's angles gathered from a full configuration `q`.
    ///
    /// # Panics
    /// When `q` is shorter than the model's.
    pub fn angles_from_q(&self, q: &[f64]) -> [f64; 4] {
        self.q_index.map(|i| q[i])
    }

    /// Constant offset of the foot along the pitch axes from the roll axis (m).
    pub fn lateral_offset_m(&self) -> f64 {
        self.offset_m
    }

    /// Foot point in the base frame (m) at joint angles `a` (rad).
    pub fn fk(&self, a: [f64; 4]) -> DVec3 {
        let [w1, w2, w3, w4] = self.links;
        let [e0, e1, e2, e3] = cis4(a);
        let w = w1 + cmul(e1, w2 + cmul(e2, w3 + cmul(e3, w4)));
        let hip = DVec3::new(w.y, self.offset_m, w.x);
        self.mount.transform_point(rotation_x(e0) * hip)
    }

    /// Knee bend (rad): the signed angle from the thigh to the knee→wrist
    /// segment (wrist: the ankle under [`AnkleMode::FootPitch`], the foot point
    /// under [`AnkleMode::Angle`], which uses `a[3]`); 0 is a straight leg. Its
    /// sign is the [`super::KneeBranch`].
    pub fn knee_bend_rad(&self, a: [f64; 4], ankle: AnkleMode) -> f64 {
        let [_, w2, w3, w4] = self.links;
        match ankle {
            AnkleMode::FootPitch(_) => knee_bend(w2, w3, a[2]),
            AnkleMode::Angle(_) => knee_bend(w2, w3 + cmul(cis(a[3]), w4), a[2]),
        }
    }

    /// Joint angles (rad, each in (−π, π]) that put the foot point at
    /// `target_m` (base frame), with the foot below the roll axis.
    ///
    /// # Errors
    /// [`IkError::NonFinite`], [`IkError::InsideOffset`],
    /// [`IkError::OutOfReach`].
    pub fn ik(&self, target_m: DVec3, opts: &IkOptions) -> Result<[f64; 4], IkError> {
        self.solve(target_m, opts, false).map(|(a, _)| a)
    }

    /// Like [`Self::ik`], but an unreachable target is projected onto the
    /// reachable workspace (for the chosen branch and ankle mode): onto the
    /// offset circle about the roll axis, then, in the leg plane through the
    /// target, radially about the hip pitch joint onto the annulus the wrist
    /// reaches. A target beyond the straight leg gets the straight leg
    /// pointing the wrist at it; a target inside the folded leg's reach gets
    /// the folded knee. With no lateral offset (the built-in) the workspace is
    /// a solid of revolution about the roll axis and this is the nearest
    /// reachable point.
    ///
    /// # Errors
    /// [`IkError::NonFinite`] only.
    pub fn ik_clamped(&self, target_m: DVec3, opts: &IkOptions) -> Result<IkClamped<4>, IkError> {
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
    ) -> Result<([f64; 4], bool), IkError> {
        self.solve(target_m, opts, true)
    }

    fn solve(
        &self,
        target_m: DVec3,
        opts: &IkOptions,
        clamp: bool,
    ) -> Result<([f64; 4], bool), IkError> {
        let (p, z, inside) = self.roll_plane(target_m, clamp)?;
        let roll = wrap_angle(p.z.atan2(p.y) - foot_arg(z, self.offset_m));
        let (pitch, knee, ankle, out) = self.pitch_chain(DVec2::new(z, p.x), opts, clamp)?;
        Ok(([roll, pitch, knee, ankle], inside || out))
    }

    /// [`Self::ik_clamped_angles`]' ankle angle alone (the same bits),
    /// without the roll angle's two `atan2`: what a stance foot held level
    /// needs.
    ///
    /// # Errors
    /// [`IkError::NonFinite`] only.
    pub fn ik_clamped_ankle(&self, target_m: DVec3, opts: &IkOptions) -> Result<f64, IkError> {
        let (p, z, _) = self.roll_plane(target_m, true)?;
        let (_, _, ankle, _) = self.pitch_chain(DVec2::new(z, p.x), opts, true)?;
        Ok(ankle)
    }

    /// Steps 1–2 of the inverse (module docs): the target in the mount frame
    /// `p`, the foot's height `Z` below the roll axis in the rolled hip frame,
    /// and whether the target was inside the offset circle.
    #[inline]
    fn roll_plane(&self, target_m: DVec3, clamp: bool) -> Result<(DVec3, f64, bool), IkError> {
        if !target_m.is_finite() {
            return Err(IkError::NonFinite { target_m });
        }
        let p = self.mount_inv.transform_point(target_m);
        let d = self.offset_m;
        let r = crate::linalg::hypot(p.y, p.z);
        let inside = r < d.abs();
        if inside && !clamp {
            return Err(IkError::InsideOffset {
                distance_m: r,
                offset_m: d.abs(),
            });
        }
        // foot below the roll axis: Z ≤ 0
        let z = if inside {
            0.0
        } else {
            -((r - d.abs()) * (r + d.abs())).sqrt()
        };
        Ok((p, z, inside))
    }

    /// Step 3 of the inverse (module docs): hip pitch, knee and ankle that
    /// put the foot at `w` (complex form, rolled hip frame), and whether the
    /// wrist was projected onto the reachable annulus.
    #[inline]
    fn pitch_chain(
        &self,
        w: DVec2,
        opts: &IkOptions,
        clamp: bool,
    ) -> Result<(f64, f64, f64, bool), IkError> {
        let sign = opts.knee.sign(NOMINAL_BEND);
        let [w1, w2, w3, w4] = self.links;
        Ok(match opts.ankle {
            AnkleMode::FootPitch(psi) => {
                let foot = if psi.to_bits() == 0.0f64.to_bits() {
                    self.foot_level
                } else {
                    cmul(cis(psi), w4)
                };
                let wrist = w - w1 - foot;
                let (t2, t3, out) = two_link_links(&self.thigh, &self.shank, wrist, sign, clamp)?;
                (t2, t3, wrap_angle(psi - t2 - t3), out)
            }
            AnkleMode::Angle(a4) => {
                let u3 = w3 + cmul(cis(a4), w4);
                let (t2, t3, out) = two_link(w2, u3, w - w1, sign, clamp)?;
                (t2, t3, a4, out)
            }
        })
    }

    /// The leg's Jacobian (m/rad, base frame): column k is `∂ foot / ∂ a[k]`.
    pub fn jacobian(&self, a: [f64; 4]) -> [DVec3; 4] {
        let [w1, w2, w3, w4] = self.links;
        // tip relative to the ankle, the knee and the hip pitch joint
        let [e0, e1, e12, e123] = cis4([a[0], a[1], a[1] + a[2], a[1] + a[2] + a[3]]);
        let t4 = cmul(e123, w4);
        let t3 = cmul(e12, w3) + t4;
        let t2 = cmul(e1, w2) + t3;
        let w = w1 + t2;
        let hip = DVec3::new(w.y, self.offset_m, w.x);
        let roll = rotation_x(e0);
        let r = self.mount.rot * roll;
        // d(t)/dθ = i·t in the plane; back to (x, 0, z)
        let pitch_col = |t: DVec2| {
            let dt = t.perp();
            r * DVec3::new(dt.y, 0.0, dt.x)
        };
        [
            self.mount.rot * DVec3::X.cross(roll * hip),
            pitch_col(t2),
            pitch_col(t3),
            pitch_col(t4),
        ]
    }

    /// Joint velocities (rad/s) that move the foot point at `foot_velocity`
    /// (m/s, base frame) while the ankle holds `opts.ankle` (foot pitch
    /// constant: ankle rate = −(hip pitch rate + knee rate); ankle angle
    /// constant: ankle rate 0), by damped least squares on [`Self::jacobian`]
    /// (see [`IkOptions::velocity_damping_m`]). For swing-leg PD.
    ///
    /// # Errors
    /// [`IkError::Singular`] for the exact map (damping 0) at a singular pose.
    pub fn joint_velocities(
        &self,
        a: [f64; 4],
        foot_velocity: DVec3,
        opts: &IkOptions,
    ) -> Result<[f64; 4], IkError> {
        let [j1, j2, j3, j4] = self.jacobian(a);
        let foot_pitch = matches!(opts.ankle, AnkleMode::FootPitch(_));
        let m = if foot_pitch {
            DMat3::from_cols(j1, j2 - j4, j3 - j4)
        } else {
            DMat3::from_cols(j1, j2, j3)
        };
        let x = dls_solve(m, foot_velocity, opts.velocity_damping_m)?;
        let ankle = if foot_pitch { -x.y - x.z } else { 0.0 };
        Ok([x.x, x.y, x.z, ankle])
    }

    /// Shortest and longest hip-pitch-to-wrist reach (m) under `ankle`.
    pub fn reach_m(&self, ankle: AnkleMode) -> (f64, f64) {
        let [_, w2, w3, w4] = self.links;
        let lb = match ankle {
            AnkleMode::FootPitch(_) => w3.length(),
            AnkleMode::Angle(a4) => (w3 + cmul(cis(a4), w4)).length(),
        };
        let la = w2.length();
        ((la - lb).abs(), la + lb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`foot_arg`] is `atan2` bit for bit, on its shortcut (no offset, foot
    /// below the axis: magnitudes from subnormal to infinite, both zeros of
    /// `d`) and off it.
    #[test]
    fn foot_arg_equals_atan2() {
        let mut zs = vec![
            f64::MIN_POSITIVE / 4.0,
            f64::MAX,
            f64::INFINITY,
            0.0,
            f64::NAN,
        ];
        zs.extend((-1074..1024).map(|k| 2f64.powi(k) * 1.3));
        for z in zs {
            for z in [z, -z] {
                for d in [0.0, -0.0, 0.02, -0.02] {
                    let (got, want) = (foot_arg(z, d), z.atan2(d));
                    assert!(
                        got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                        "z {z:e} d {d}: {got:e} != {want:e}"
                    );
                }
            }
        }
    }
}
