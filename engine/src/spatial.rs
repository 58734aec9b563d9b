//! f64 spatial algebra on glam (Featherstone 2008, ch. 2), in Pinocchio's ordering.
//!
//! Every 6-vector is stored as a pair of 3-vectors, **linear part first**:
//! a [`Motion`] is `[v; ω]` (m/s, rad/s) and a [`Force`] is `[f; n]` (N, N·m),
//! both expressed in some frame *and about some reference point*. The frame and
//! point are stated wherever a value is stored. The engine's algorithms work in
//! the *reference frame* of a robot: world-aligned axes, about a point fixed in
//! the world that coincides with the base origin at the instant of evaluation
//! (see [`crate::data::Data::origin`]). That keeps lever arms short however far
//! the robot walks, so precision does not degrade with distance.

use glam::{DMat3, DQuat, DVec3};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// Skew-symmetric cross-product matrix: `skew(a) * b == a.cross(b)`.
#[inline]
pub fn skew(a: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, a.z, -a.y),
        DVec3::new(-a.z, 0.0, a.x),
        DVec3::new(a.y, -a.x, 0.0),
    )
}

/// Outer product `a bᵀ`.
#[inline]
pub fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// A spatial motion vector `[v; ω]`: linear velocity of the body point at the
/// reference point (m/s) and angular velocity (rad/s). Also used for spatial
/// accelerations (m/s², rad/s²) and for motion-subspace columns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// Linear part (m/s, or m/s² for accelerations).
    pub lin: DVec3,
    /// Angular part (rad/s, or rad/s²).
    pub ang: DVec3,
}

/// A spatial force vector `[f; n]`: force (N) and moment about the reference point (N·m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Force {
    /// Force (N).
    pub lin: DVec3,
    /// Moment about the reference point (N·m).
    pub ang: DVec3,
}

impl Motion {
    /// The zero motion.
    pub const ZERO: Self = Self {
        lin: DVec3::ZERO,
        ang: DVec3::ZERO,
    };

    /// Builds a motion from its linear and angular parts.
    #[inline]
    pub const fn new(lin: DVec3, ang: DVec3) -> Self {
        Self { lin, ang }
    }

    /// Spatial motion cross product `self ×ₘ m` (Featherstone eq. 2.31).
    #[inline]
    pub fn cross(self, m: Motion) -> Motion {
        Motion {
            lin: self.ang.cross(m.lin) + self.lin.cross(m.ang),
            ang: self.ang.cross(m.ang),
        }
    }

    /// Spatial force cross product `self ×* f` (Featherstone eq. 2.32).
    #[inline]
    pub fn cross_force(self, f: Force) -> Force {
        Force {
            lin: self.ang.cross(f.lin),
            ang: self.ang.cross(f.ang) + self.lin.cross(f.lin),
        }
    }

    /// Power `f · m` (W).
    #[inline]
    pub fn dot(self, f: Force) -> f64 {
        self.lin.dot(f.lin) + self.ang.dot(f.ang)
    }

    /// The same motion about a reference point moved by `r` (m): `v' = v + ω × r`.
    #[inline]
    pub fn shifted(self, r: DVec3) -> Motion {
        Motion {
            lin: self.lin + self.ang.cross(r),
            ang: self.ang,
        }
    }

    /// Velocity (m/s) of the point at `r` from the reference point.
    #[inline]
    pub fn point_velocity(self, r: DVec3) -> DVec3 {
        self.lin + self.ang.cross(r)
    }

    /// Rotates both parts (no change of reference point).
    #[inline]
    pub fn rotated(self, r: DMat3) -> Motion {
        Motion {
            lin: r * self.lin,
            ang: r * self.ang,
        }
    }

    /// The six components `[v; ω]` as an array.
    #[inline]
    pub fn to_array(self) -> [f64; 6] {
        [
            self.lin.x, self.lin.y, self.lin.z, self.ang.x, self.ang.y, self.ang.z,
        ]
    }

    /// Builds a motion from six components `[v; ω]`.
    #[inline]
    pub fn from_slice(s: &[f64]) -> Motion {
        Motion {
            lin: DVec3::new(s[0], s[1], s[2]),
            ang: DVec3::new(s[3], s[4], s[5]),
        }
    }

    /// True when every component is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.lin.is_finite() && self.ang.is_finite()
    }
}

impl Force {
    /// The zero force.
    pub const ZERO: Self = Self {
        lin: DVec3::ZERO,
        ang: DVec3::ZERO,
    };

    /// Builds a force from force and moment.
    #[inline]
    pub const fn new(lin: DVec3, ang: DVec3) -> Self {
        Self { lin, ang }
    }

    /// A pure force `f` (N) acting at point `p` (m, from the reference point).
    #[inline]
    pub fn at_point(f: DVec3, p: DVec3) -> Force {
        Force {
            lin: f,
            ang: p.cross(f),
        }
    }

    /// The same force about a reference point moved by `r` (m): `n' = n − r × f`.
    #[inline]
    pub fn shifted(self, r: DVec3) -> Force {
        Force {
            lin: self.lin,
            ang: self.ang - r.cross(self.lin),
        }
    }

    /// Rotates both parts (no change of reference point).
    #[inline]
    pub fn rotated(self, r: DMat3) -> Force {
        Force {
            lin: r * self.lin,
            ang: r * self.ang,
        }
    }

    /// The six components `[f; n]` as an array.
    #[inline]
    pub fn to_array(self) -> [f64; 6] {
        [
            self.lin.x, self.lin.y, self.lin.z, self.ang.x, self.ang.y, self.ang.z,
        ]
    }
}

macro_rules! impl_vec_ops {
    ($t:ty) => {
        impl Add for $t {
            type Output = $t;
            #[inline]
            fn add(self, o: $t) -> $t {
                Self {
                    lin: self.lin + o.lin,
                    ang: self.ang + o.ang,
                }
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline]
            fn sub(self, o: $t) -> $t {
                Self {
                    lin: self.lin - o.lin,
                    ang: self.ang - o.ang,
                }
            }
        }
        impl AddAssign for $t {
            #[inline]
            fn add_assign(&mut self, o: $t) {
                self.lin += o.lin;
                self.ang += o.ang;
            }
        }
        impl SubAssign for $t {
            #[inline]
            fn sub_assign(&mut self, o: $t) {
                self.lin -= o.lin;
                self.ang -= o.ang;
            }
        }
        impl Neg for $t {
            type Output = $t;
            #[inline]
            fn neg(self) -> $t {
                Self {
                    lin: -self.lin,
                    ang: -self.ang,
                }
            }
        }
        impl Mul<f64> for $t {
            type Output = $t;
            #[inline]
            fn mul(self, s: f64) -> $t {
                Self {
                    lin: self.lin * s,
                    ang: self.ang * s,
                }
            }
        }
    };
}
impl_vec_ops!(Motion);
impl_vec_ops!(Force);

/// A rigid transform (SE(3)): `p_parent = rot * p_child + trans`.
///
/// As a placement it gives the child frame's axes (`rot`, columns) and origin
/// (`trans`, m) in the parent frame, Pinocchio's `liMi` convention.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Rotation taking child-frame vectors into the parent frame.
    pub rot: DMat3,
    /// Child origin in the parent frame (m).
    pub trans: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        rot: DMat3::IDENTITY,
        trans: DVec3::ZERO,
    };

    /// Builds a transform from a rotation and a translation.
    #[inline]
    pub const fn new(rot: DMat3, trans: DVec3) -> Self {
        Self { rot, trans }
    }

    /// A pure translation (m).
    #[inline]
    pub fn from_translation(trans: DVec3) -> Self {
        Self {
            rot: DMat3::IDENTITY,
            trans,
        }
    }

    /// URDF `<origin xyz rpy>`: rotation `Rz(yaw) Ry(pitch) Rx(roll)` (fixed axes X, Y, Z).
    pub fn from_xyz_rpy(xyz: DVec3, rpy: DVec3) -> Self {
        Self {
            rot: rot_from_rpy(rpy),
            trans: xyz,
        }
    }

    /// Composition `self ∘ other`: `other` maps c→b, `self` maps b→a; the result maps c→a.
    #[inline]
    pub fn compose(&self, other: &Transform) -> Transform {
        Transform {
            rot: self.rot * other.rot,
            trans: self.rot * other.trans + self.trans,
        }
    }

    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Transform {
        let rt = self.rot.transpose();
        Transform {
            rot: rt,
            trans: -(rt * self.trans),
        }
    }

    /// Maps a point from the child frame to the parent frame.
    #[inline]
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.rot * p + self.trans
    }

    /// Maps a free vector (direction) from the child frame to the parent frame.
    #[inline]
    pub fn transform_vector(&self, v: DVec3) -> DVec3 {
        self.rot * v
    }

    /// Unit quaternion of the rotation.
    pub fn quat(&self) -> DQuat {
        DQuat::from_mat3(&self.rot).normalize()
    }

    /// Maps a motion expressed in the child frame about the child origin into the
    /// parent frame about the parent origin (Pinocchio's `act`).
    #[inline]
    pub fn act_motion(&self, m: Motion) -> Motion {
        let ang = self.rot * m.ang;
        Motion {
            lin: self.rot * m.lin + self.trans.cross(ang),
            ang,
        }
    }

    /// Maps a force expressed in the child frame about the child origin into the
    /// parent frame about the parent origin.
    #[inline]
    pub fn act_force(&self, f: Force) -> Force {
        let lin = self.rot * f.lin;
        Force {
            lin,
            ang: self.rot * f.ang + self.trans.cross(lin),
        }
    }

    /// True when every entry is finite and the rotation is orthonormal to `tol`.
    pub fn is_valid(&self, tol: f64) -> bool {
        if !(self.rot.is_finite() && self.trans.is_finite()) {
            return false;
        }
        let e = self.rot.transpose() * self.rot - DMat3::IDENTITY;
        e.to_cols_array().iter().all(|x| x.abs() <= tol)
            && (self.rot.determinant() - 1.0).abs() <= tol
    }
}

/// URDF roll-pitch-yaw (rad) to a rotation matrix: `Rz(yaw) · Ry(pitch) · Rx(roll)`.
pub fn rot_from_rpy(rpy: DVec3) -> DMat3 {
    DMat3::from_rotation_z(rpy.z) * DMat3::from_rotation_y(rpy.y) * DMat3::from_rotation_x(rpy.x)
}

/// Rotation matrix to roll-pitch-yaw (rad), the inverse of [`rot_from_rpy`]
/// (pitch in [−π/2, π/2]).
pub fn rpy_from_rot(r: DMat3) -> DVec3 {
    let (roll, pitch) = roll_pitch_from_rot(r);
    DVec3::new(roll, pitch, yaw_from_rot(r))
}

/// [`rpy_from_rot`]'s roll and pitch alone (the same bits).
#[inline]
pub fn roll_pitch_from_rot(r: DMat3) -> (f64, f64) {
    // r = Rz(y) Ry(p) Rx(r): r[0][2] (row 2, col 0) = -sin p
    let sp = (-r.x_axis.z).clamp(-1.0, 1.0);
    let pitch = sp.asin();
    let roll = r.y_axis.z.atan2(r.z_axis.z);
    (roll, pitch)
}

/// [`rpy_from_rot`]'s yaw alone (the same bits): a heading needs neither
/// roll's `atan2` nor pitch's `asin`.
#[inline]
pub fn yaw_from_rot(r: DMat3) -> f64 {
    r.x_axis.y.atan2(r.x_axis.x)
}

/// Inertia of one rigid body: mass (kg), centre of mass (m) and rotational
/// inertia about the centre of mass (kg·m²), all in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidInertia {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the frame (m).
    pub com: DVec3,
    /// Rotational inertia about the centre of mass, frame axes (kg·m²).
    pub inertia_com: DMat3,
}

impl Default for RigidInertia {
    fn default() -> Self {
        Self::ZERO
    }
}

impl RigidInertia {
    /// A massless body.
    pub const ZERO: Self = Self {
        mass: 0.0,
        com: DVec3::ZERO,
        inertia_com: DMat3::ZERO,
    };

    /// Builds a rigid inertia.
    pub const fn new(mass: f64, com: DVec3, inertia_com: DMat3) -> Self {
        Self {
            mass,
            com,
            inertia_com,
        }
    }

    /// The same body seen from the parent frame of `x` (`x` maps this frame into it).
    #[inline]
    pub fn transformed(&self, x: &Transform) -> RigidInertia {
        // R I Rᵀ is symmetric: form At = I Rᵀ = (R I)ᵀ, then only the six
        // distinct entries (R I Rᵀ)ⱼₖ = colⱼ(At) · colₖ(Rᵀ).
        let rt = x.rot.transpose();
        let at = self.inertia_com * rt;
        let (a0, a1, a2) = (at.x_axis, at.y_axis, at.z_axis);
        let (r0, r1, r2) = (rt.x_axis, rt.y_axis, rt.z_axis);
        let (xx, yy, zz) = (a0.dot(r0), a1.dot(r1), a2.dot(r2));
        let (xy, xz, yz) = (a0.dot(r1), a0.dot(r2), a1.dot(r2));
        RigidInertia {
            mass: self.mass,
            com: x.transform_point(self.com),
            inertia_com: DMat3::from_cols(
                DVec3::new(xx, xy, xz),
                DVec3::new(xy, yy, yz),
                DVec3::new(xz, yz, zz),
            ),
        }
    }

    /// [`Self::transformed`] for an inertia about the CoM that is diagonal,
    /// `diag(d)`: then `R diag(d) Rᵀ = Σₗ dₗ cₗ cₗᵀ` over the columns `cₗ` of
    /// `R`, 27 products instead of 45 (the off-diagonal entries are ignored).
    #[inline]
    pub fn transformed_diagonal(&self, x: &Transform) -> RigidInertia {
        let ic = &self.inertia_com;
        let (c0, c1, c2) = (x.rot.x_axis, x.rot.y_axis, x.rot.z_axis);
        let (e0, e1, e2) = (c0 * ic.x_axis.x, c1 * ic.y_axis.y, c2 * ic.z_axis.z);
        // diagonal entries (xx, yy, zz) and the upper ones (xy, xz, yz)
        let diag = e0 * c0 + e1 * c1 + e2 * c2;
        let up = |e: DVec3, c: DVec3| DVec3::new(e.x, e.x, e.y) * DVec3::new(c.y, c.z, c.z);
        let off = up(e0, c0) + up(e1, c1) + up(e2, c2);
        RigidInertia {
            mass: self.mass,
            com: x.transform_point(self.com),
            inertia_com: DMat3::from_cols(
                DVec3::new(diag.x, off.x, off.y),
                DVec3::new(off.x, diag.y, off.z),
                DVec3::new(off.y, off.z, diag.z),
            ),
        }
    }

    /// Sum of two bodies rigidly joined, both given in the same frame (parallel-axis theorem).
    pub fn combined(&self, o: &RigidInertia) -> RigidInertia {
        let m = self.mass + o.mass;
        if m <= 0.0 {
            return RigidInertia::ZERO;
        }
        let c = (self.com * self.mass + o.com * o.mass) / m;
        let shift = |ri: &RigidInertia| {
            let d = ri.com - c;
            ri.inertia_com
                + (DMat3::from_diagonal(DVec3::splat(d.length_squared())) - outer(d, d)) * ri.mass
        };
        RigidInertia {
            mass: m,
            com: c,
            inertia_com: shift(self) + shift(o),
        }
    }

    /// The 6×6 spatial inertia about the frame origin.
    #[inline]
    pub fn to_sym6(&self) -> Sym6 {
        // i = I_c − m [c]×[c]× = I_c + m (|c|² 1 − c cᵀ), without a 3×3 product.
        let c = self.com;
        let mc = c * self.mass;
        Sym6 {
            m: DMat3::from_diagonal(DVec3::splat(self.mass)),
            h: skew(mc),
            i: self.inertia_com + DMat3::from_diagonal(DVec3::splat(mc.dot(c))) - outer(mc, c),
        }
    }

    /// Momentum `I v` of the body moving with spatial velocity `v` (about the frame origin).
    #[inline]
    pub fn mul_motion(&self, v: Motion) -> Force {
        // f = m (v + ω × c) ; n = I_c ω + c × f
        let f = (v.lin + v.ang.cross(self.com)) * self.mass;
        Force {
            lin: f,
            ang: self.inertia_com * v.ang + self.com.cross(f),
        }
    }

    /// Kinetic energy ½ vᵀ I v (J).
    #[inline]
    pub fn kinetic_energy(&self, v: Motion) -> f64 {
        0.5 * v.dot(self.mul_motion(v))
    }
}

/// A symmetric 6×6 spatial inertia (rigid or articulated) about a reference point, in blocks:
/// `[f; n] = [[m, hᵀ], [h, i]] · [v; ω]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sym6 {
    /// Linear–linear block (kg), symmetric.
    pub m: DMat3,
    /// Angular–linear coupling block (kg·m).
    pub h: DMat3,
    /// Angular–angular block (kg·m²), symmetric.
    pub i: DMat3,
}

impl Default for Sym6 {
    fn default() -> Self {
        Self::ZERO
    }
}

impl Sym6 {
    /// The zero matrix.
    pub const ZERO: Self = Self {
        m: DMat3::ZERO,
        h: DMat3::ZERO,
        i: DMat3::ZERO,
    };

    /// `I · v`.
    #[inline]
    pub fn mul_motion(&self, v: Motion) -> Force {
        // hᵀ ω as three column dot products, without forming hᵀ.
        let ht_w = DVec3::new(
            self.h.x_axis.dot(v.ang),
            self.h.y_axis.dot(v.ang),
            self.h.z_axis.dot(v.ang),
        );
        Force {
            lin: self.m * v.lin + ht_w,
            ang: self.h * v.lin + self.i * v.ang,
        }
    }

    /// Rank-one downdate `self −= u uᵀ / d`, where `u` is a force-like column.
    #[inline]
    pub fn sub_outer(&mut self, u: Force, inv_d: f64) {
        let ul = u.lin * inv_d;
        let ua = u.ang * inv_d;
        self.m -= outer(ul, u.lin);
        self.h -= outer(ua, u.lin);
        self.i -= outer(ua, u.ang);
    }

    /// Dense row-major 6×6 matrix.
    pub fn to_dense(&self) -> [[f64; 6]; 6] {
        let mut out = [[0.0; 6]; 6];
        let ht = self.h.transpose();
        for r in 0..3 {
            for c in 0..3 {
                out[r][c] = self.m.col(c)[r];
                out[r][c + 3] = ht.col(c)[r];
                out[r + 3][c] = self.h.col(c)[r];
                out[r + 3][c + 3] = self.i.col(c)[r];
            }
        }
        out
    }

    /// Solves `self · a = f` for `a` (the matrix must be positive definite).
    /// Returns `None` when it is not.
    pub fn solve(&self, f: Force) -> Option<Motion> {
        // Block elimination through the Schur complement of `m`:
        //   S = i − h m⁻¹ hᵀ,  ω = S⁻¹ (n − h m⁻¹ f),  v = m⁻¹ (f − hᵀ ω).
        // The matrix is positive definite iff `m` and `S` are (Sylvester's
        // criterion on each). Two 3×3 inverses and no square roots: a much
        // shorter dependency chain than a 6×6 Cholesky, on the path of every
        // floating-base ABA call.
        let m_inv = spd_inverse(self.m)?;
        let b = self.h * m_inv;
        let schur = self.i - b * self.h.transpose();
        let s_inv = spd_inverse(schur)?;
        let ang = s_inv * (f.ang - b * f.lin);
        let lin = m_inv * (f.lin - self.h.transpose() * ang);
        Some(Motion::new(lin, ang))
    }
}

/// Inverse of a symmetric 3×3 matrix, `None` unless it is positive definite
/// (all leading principal minors positive and finite).
#[inline]
fn spd_inverse(a: DMat3) -> Option<DMat3> {
    let m1 = a.x_axis.x;
    let m2 = a.x_axis.x * a.y_axis.y - a.x_axis.y * a.y_axis.x;
    let det = a.determinant();
    if m1 > 0.0 && m2 > 0.0 && det > 0.0 && det.is_finite() {
        Some(a.inverse())
    } else {
        None
    }
}

impl Add for Sym6 {
    type Output = Sym6;
    #[inline]
    fn add(self, o: Sym6) -> Sym6 {
        Sym6 {
            m: self.m + o.m,
            h: self.h + o.h,
            i: self.i + o.i,
        }
    }
}

impl AddAssign for Sym6 {
    #[inline]
    fn add_assign(&mut self, o: Sym6) {
        self.m += o.m;
        self.h += o.h;
        self.i += o.i;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn approx(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn rpy_round_trip() {
        let rpy = DVec3::new(0.3, -0.7, 2.1);
        assert!(approx(rpy_from_rot(rot_from_rpy(rpy)), rpy));
    }

    #[test]
    fn sym6_matches_rigid_mul() {
        let ri = RigidInertia::new(
            2.0,
            DVec3::new(0.1, -0.2, 0.3),
            DMat3::from_diagonal(DVec3::new(0.1, 0.2, 0.3)),
        );
        let v = Motion::new(DVec3::new(1.0, 2.0, -1.0), DVec3::new(0.5, -0.3, 0.9));
        let a = ri.mul_motion(v);
        let b = ri.to_sym6().mul_motion(v);
        assert!(approx(a.lin, b.lin) && approx(a.ang, b.ang));
    }

    #[test]
    fn transforms_preserve_power() {
        let x = Transform::from_xyz_rpy(DVec3::new(0.3, -1.0, 2.0), DVec3::new(0.2, 0.4, -1.2));
        let m = Motion::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(-0.5, 0.1, 0.7));
        let f = Force::new(DVec3::new(3.0, -2.0, 1.0), DVec3::new(0.2, 0.3, -0.9));
        let p0 = m.dot(f);
        let p1 = x.act_motion(m).dot(x.act_force(f));
        assert!((p0 - p1).abs() < 1e-12);
        // inverse undoes
        let back = x.inverse().act_motion(x.act_motion(m));
        assert!(approx(back.lin, m.lin) && approx(back.ang, m.ang));
    }

    #[test]
    fn combined_inertia_is_additive_in_momentum() {
        let a = RigidInertia::new(
            1.0,
            DVec3::new(0.1, 0.0, 0.0),
            DMat3::from_diagonal(DVec3::new(0.01, 0.02, 0.03)),
        );
        let b = RigidInertia::new(
            3.0,
            DVec3::new(0.0, -0.2, 0.4),
            DMat3::from_diagonal(DVec3::new(0.04, 0.05, 0.06)),
        );
        let v = Motion::new(DVec3::new(0.3, 0.2, 0.1), DVec3::new(1.0, -2.0, 0.5));
        let s = a.mul_motion(v) + b.mul_motion(v);
        let c = a.combined(&b).mul_motion(v);
        assert!(approx(s.lin, c.lin) && approx(s.ang, c.ang));
    }

    #[test]
    fn sym6_solve_rejects_indefinite() {
        // a rigid inertia with a negative principal moment is not positive definite
        let ri = RigidInertia::new(
            2.0,
            DVec3::new(0.1, -0.2, 0.3),
            DMat3::from_diagonal(DVec3::new(0.1, -0.5, 0.3)),
        );
        let f = Force::new(DVec3::X, DVec3::Y);
        assert!(ri.to_sym6().solve(f).is_none());
        assert!(RigidInertia::ZERO.to_sym6().solve(f).is_none());
    }

    #[test]
    fn sym6_solve_inverts_mul() {
        let ri = RigidInertia::new(
            2.0,
            DVec3::new(0.1, -0.2, 0.3),
            DMat3::from_diagonal(DVec3::new(0.1, 0.2, 0.3)),
        );
        let s = ri.to_sym6();
        let v = Motion::new(DVec3::new(1.0, 2.0, -1.0), DVec3::new(0.5, -0.3, 0.9));
        let back = s.solve(s.mul_motion(v)).unwrap();
        assert!((back.lin - v.lin).length() < 1e-10 && (back.ang - v.ang).length() < 1e-10);
    }
}
