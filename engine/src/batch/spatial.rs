//! Spatial algebra across robots: [`crate::spatial`]'s motions, forces,
//! transforms and inertias with one lane per robot, formula for formula (and
//! in the same order of operations) as the scalar types, so that every lane
//! is bit-identical to the scalar result.

use super::lanes::{LMat3, LVec3, Lanes, outer, skew};
use crate::spatial::{Force, Motion, RigidInertia, Sym6, Transform};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A spatial motion `[v; ω]` per lane ([`Motion`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LMotion<const L: usize> {
    /// Linear part (m/s or m/s²).
    pub lin: LVec3<L>,
    /// Angular part (rad/s or rad/s²).
    pub ang: LVec3<L>,
}

/// A spatial force `[f; n]` per lane ([`Force`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LForce<const L: usize> {
    /// Force (N).
    pub lin: LVec3<L>,
    /// Moment about the reference point (N·m).
    pub ang: LVec3<L>,
}

impl<const L: usize> LMotion<L> {
    /// The zero motion.
    pub const ZERO: Self = Self::new(LVec3::ZERO, LVec3::ZERO);

    /// Builds a motion from its parts.
    #[inline(always)]
    pub const fn new(lin: LVec3<L>, ang: LVec3<L>) -> Self {
        Self { lin, ang }
    }

    /// Lane `k` as a scalar motion.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> Motion {
        Motion::new(self.lin.lane(k), self.ang.lane(k))
    }

    /// Writes lane `k`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, m: Motion) {
        self.lin.set_lane(k, m.lin);
        self.ang.set_lane(k, m.ang);
    }

    /// [`Motion::cross`].
    #[inline(always)]
    pub fn cross(self, m: Self) -> Self {
        Self {
            lin: self.ang.cross(m.lin) + self.lin.cross(m.ang),
            ang: self.ang.cross(m.ang),
        }
    }

    /// [`Motion::cross_force`].
    #[inline(always)]
    pub fn cross_force(self, f: LForce<L>) -> LForce<L> {
        LForce {
            lin: self.ang.cross(f.lin),
            ang: self.ang.cross(f.ang) + self.lin.cross(f.lin),
        }
    }

    /// [`Motion::dot`].
    #[inline(always)]
    pub fn dot(self, f: LForce<L>) -> Lanes<L> {
        self.lin.dot(f.lin) + self.ang.dot(f.ang)
    }
}

impl<const L: usize> LForce<L> {
    /// The zero force.
    pub const ZERO: Self = Self::new(LVec3::ZERO, LVec3::ZERO);

    /// Builds a force from its parts.
    #[inline(always)]
    pub const fn new(lin: LVec3<L>, ang: LVec3<L>) -> Self {
        Self { lin, ang }
    }

    /// Lane `k` as a scalar force.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> Force {
        Force::new(self.lin.lane(k), self.ang.lane(k))
    }

    /// Writes lane `k`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, f: Force) {
        self.lin.set_lane(k, f.lin);
        self.ang.set_lane(k, f.ang);
    }
}

macro_rules! impl_lane_vec_ops {
    ($t:ident) => {
        impl<const L: usize> Add for $t<L> {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                Self::new(self.lin + o.lin, self.ang + o.ang)
            }
        }
        impl<const L: usize> Sub for $t<L> {
            type Output = Self;
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                Self::new(self.lin - o.lin, self.ang - o.ang)
            }
        }
        impl<const L: usize> AddAssign for $t<L> {
            #[inline(always)]
            fn add_assign(&mut self, o: Self) {
                self.lin += o.lin;
                self.ang += o.ang;
            }
        }
        impl<const L: usize> SubAssign for $t<L> {
            #[inline(always)]
            fn sub_assign(&mut self, o: Self) {
                self.lin -= o.lin;
                self.ang -= o.ang;
            }
        }
        impl<const L: usize> Neg for $t<L> {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                Self::new(-self.lin, -self.ang)
            }
        }
        impl<const L: usize> Mul<Lanes<L>> for $t<L> {
            type Output = Self;
            #[inline(always)]
            fn mul(self, s: Lanes<L>) -> Self {
                Self::new(self.lin * s, self.ang * s)
            }
        }
    };
}
impl_lane_vec_ops!(LMotion);
impl_lane_vec_ops!(LForce);

/// A rigid transform per lane ([`Transform`]): `p_parent = rot * p_child + trans`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LTransform<const L: usize> {
    /// Rotation taking child-frame vectors into the parent frame.
    pub rot: LMat3<L>,
    /// Child origin in the parent frame (m).
    pub trans: LVec3<L>,
}

impl<const L: usize> LTransform<L> {
    /// Builds a transform.
    #[inline(always)]
    pub const fn new(rot: LMat3<L>, trans: LVec3<L>) -> Self {
        Self { rot, trans }
    }

    /// Lane `k` as a scalar transform.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> Transform {
        Transform::new(self.rot.lane(k), self.trans.lane(k))
    }

    /// [`Transform::compose`].
    #[inline(always)]
    pub fn compose(&self, o: &Self) -> Self {
        Self {
            rot: self.rot * o.rot,
            trans: self.rot * o.trans + self.trans,
        }
    }

    /// [`Transform::transform_point`].
    #[inline(always)]
    pub fn transform_point(&self, p: LVec3<L>) -> LVec3<L> {
        self.rot * p + self.trans
    }
}

/// A rigid-body inertia per lane ([`RigidInertia`]): mass (kg), CoM (m),
/// rotational inertia about the CoM (kg·m²), all in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LInertia<const L: usize> {
    /// Mass (kg).
    pub mass: Lanes<L>,
    /// Centre of mass (m).
    pub com: LVec3<L>,
    /// Rotational inertia about the centre of mass (kg·m²).
    pub inertia_com: LMat3<L>,
}

impl<const L: usize> LInertia<L> {
    /// The same body in every lane.
    #[inline(always)]
    pub fn splat(ri: &RigidInertia) -> Self {
        Self {
            mass: Lanes::splat(ri.mass),
            com: LVec3::splat(ri.com),
            inertia_com: LMat3::splat(ri.inertia_com),
        }
    }

    /// [`RigidInertia::transformed`], one body model seen through each lane's transform.
    #[inline(always)]
    pub fn transformed(ri: &RigidInertia, x: &LTransform<L>) -> Self {
        let rt = x.rot.transpose();
        let at = LMat3::splat(ri.inertia_com) * rt;
        let (a0, a1, a2) = (at.x_axis, at.y_axis, at.z_axis);
        let (r0, r1, r2) = (rt.x_axis, rt.y_axis, rt.z_axis);
        let (xx, yy, zz) = (a0.dot(r0), a1.dot(r1), a2.dot(r2));
        let (xy, xz, yz) = (a0.dot(r1), a0.dot(r2), a1.dot(r2));
        Self {
            mass: Lanes::splat(ri.mass),
            com: x.transform_point(LVec3::splat(ri.com)),
            inertia_com: LMat3::from_cols(
                LVec3::new(xx, xy, xz),
                LVec3::new(xy, yy, yz),
                LVec3::new(xz, yz, zz),
            ),
        }
    }

    /// [`RigidInertia::transformed_diagonal`], one body model seen through each lane's transform.
    #[inline(always)]
    pub fn transformed_diagonal(ri: &RigidInertia, x: &LTransform<L>) -> Self {
        let ic = &ri.inertia_com;
        let (c0, c1, c2) = (x.rot.x_axis, x.rot.y_axis, x.rot.z_axis);
        let (e0, e1, e2) = (
            c0 * Lanes::splat(ic.x_axis.x),
            c1 * Lanes::splat(ic.y_axis.y),
            c2 * Lanes::splat(ic.z_axis.z),
        );
        let mulc = |a: LVec3<L>, b: LVec3<L>| LVec3::new(a.x * b.x, a.y * b.y, a.z * b.z);
        let diag = mulc(e0, c0) + mulc(e1, c1) + mulc(e2, c2);
        let up =
            |e: LVec3<L>, c: LVec3<L>| mulc(LVec3::new(e.x, e.x, e.y), LVec3::new(c.y, c.z, c.z));
        let off = up(e0, c0) + up(e1, c1) + up(e2, c2);
        Self {
            mass: Lanes::splat(ri.mass),
            com: x.transform_point(LVec3::splat(ri.com)),
            inertia_com: LMat3::from_cols(
                LVec3::new(diag.x, off.x, off.y),
                LVec3::new(off.x, diag.y, off.z),
                LVec3::new(off.y, off.z, diag.z),
            ),
        }
    }

    /// [`RigidInertia::to_sym6`].
    #[inline(always)]
    pub fn to_sym6(&self) -> LSym6<L> {
        let c = self.com;
        let mc = c * self.mass;
        LSym6 {
            m: LMat3::from_diagonal(LVec3::new(self.mass, self.mass, self.mass)),
            h: skew(mc),
            i: self.inertia_com + LMat3::from_diagonal(LVec3::new(mc.dot(c), mc.dot(c), mc.dot(c)))
                - outer(mc, c),
        }
    }

    /// [`RigidInertia::mul_motion`].
    #[inline(always)]
    pub fn mul_motion(&self, v: LMotion<L>) -> LForce<L> {
        let f = (v.lin + v.ang.cross(self.com)) * self.mass;
        LForce {
            lin: f,
            ang: self.inertia_com * v.ang + self.com.cross(f),
        }
    }
}

/// A symmetric 6×6 spatial inertia per lane, in blocks ([`Sym6`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LSym6<const L: usize> {
    /// Linear–linear block (kg).
    pub m: LMat3<L>,
    /// Angular–linear block (kg·m).
    pub h: LMat3<L>,
    /// Angular–angular block (kg·m²).
    pub i: LMat3<L>,
}

impl<const L: usize> LSym6<L> {
    /// Lane `k` as a scalar block matrix.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> Sym6 {
        Sym6 {
            m: self.m.lane(k),
            h: self.h.lane(k),
            i: self.i.lane(k),
        }
    }

    /// [`Sym6::mul_motion`].
    #[inline(always)]
    pub fn mul_motion(&self, v: LMotion<L>) -> LForce<L> {
        let ht_w = LVec3::new(
            self.h.x_axis.dot(v.ang),
            self.h.y_axis.dot(v.ang),
            self.h.z_axis.dot(v.ang),
        );
        LForce {
            lin: self.m * v.lin + ht_w,
            ang: self.h * v.lin + self.i * v.ang,
        }
    }
}
