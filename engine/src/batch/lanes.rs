//! f64 lanes across robots and the 3-vectors and 3×3 matrices built on them.
//!
//! A [`Lanes<L>`] holds one number for each of `L` robots; every operation is
//! elementwise, written as a plain loop over `[f64; L]` that LLVM turns into
//! SIMD instructions (two `f64x2` for L = 4 on a generic x86-64 build, one
//! `f64x4` on AVX2). [`LVec3`] and [`LMat3`] repeat glam's `DVec3` and `DMat3`
//! formulas **operation for operation** (same products, same order of sums,
//! no fused multiply–add: Rust never contracts `a * b + c` on its own), so each
//! lane is bit-identical to the scalar glam result.

use glam::{DMat3, DVec3};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// One f64 for each of `L` robots.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct Lanes<const L: usize>(pub [f64; L]);

impl<const L: usize> Default for Lanes<L> {
    fn default() -> Self {
        Self::ZERO
    }
}

impl<const L: usize> Lanes<L> {
    /// Every lane zero.
    pub const ZERO: Self = Self([0.0; L]);

    /// The same value in every lane.
    #[inline(always)]
    pub const fn splat(x: f64) -> Self {
        Self([x; L])
    }

    /// `f` applied to each lane (a scalar call per lane, e.g. libm's `sin`).
    #[inline(always)]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        let mut out = self.0;
        for x in &mut out {
            *x = f(*x);
        }
        Self(out)
    }

    /// Sine and cosine per lane, bit for bit the scalar kinematics' of each
    /// lane (`trig::kinematics_sin_cos`).
    #[inline(always)]
    pub fn sin_cos(self) -> (Self, Self) {
        let (s, c) = crate::trig::kinematics_sin_cos_lanes(self.0);
        (Self(s), Self(c))
    }
}

macro_rules! lanes_binop {
    ($tr:ident, $f:ident, $op:tt, $tra:ident, $fa:ident) => {
        impl<const L: usize> $tr for Lanes<L> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                let mut out = self.0;
                for k in 0..L {
                    out[k] = self.0[k] $op o.0[k];
                }
                Self(out)
            }
        }
        impl<const L: usize> $tra for Lanes<L> {
            #[inline(always)]
            fn $fa(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}
lanes_binop!(Add, add, +, AddAssign, add_assign);
lanes_binop!(Sub, sub, -, SubAssign, sub_assign);
lanes_binop!(Mul, mul, *, MulAssign, mul_assign);
lanes_binop!(Div, div, /, DivAssign, div_assign);

impl<const L: usize> Neg for Lanes<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut out = self.0;
        for x in &mut out {
            *x = -*x;
        }
        Self(out)
    }
}

/// A 3-vector per lane (glam's `DVec3` across robots).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LVec3<const L: usize> {
    /// x components.
    pub x: Lanes<L>,
    /// y components.
    pub y: Lanes<L>,
    /// z components.
    pub z: Lanes<L>,
}

impl<const L: usize> LVec3<L> {
    /// The zero vector in every lane.
    pub const ZERO: Self = Self::splat(DVec3::ZERO);

    /// Builds a vector from its components.
    #[inline(always)]
    pub const fn new(x: Lanes<L>, y: Lanes<L>, z: Lanes<L>) -> Self {
        Self { x, y, z }
    }

    /// The same vector in every lane.
    #[inline(always)]
    pub const fn splat(v: DVec3) -> Self {
        Self::new(Lanes::splat(v.x), Lanes::splat(v.y), Lanes::splat(v.z))
    }

    /// Lane `k` as a glam vector.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> DVec3 {
        DVec3::new(self.x.0[k], self.y.0[k], self.z.0[k])
    }

    /// Writes a glam vector into lane `k`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, v: DVec3) {
        (self.x.0[k], self.y.0[k], self.z.0[k]) = (v.x, v.y, v.z);
    }

    /// glam's `DVec3::dot`: `(x·x') + (y·y') + (z·z')`, summed left to right.
    #[inline(always)]
    pub fn dot(self, o: Self) -> Lanes<L> {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }

    /// glam's `DVec3::cross`.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - o.y * self.z,
            self.z * o.x - o.z * self.x,
            self.x * o.y - o.x * self.y,
        )
    }
}

impl<const L: usize> Add for LVec3<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<const L: usize> Sub for LVec3<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<const L: usize> AddAssign for LVec3<L> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<const L: usize> SubAssign for LVec3<L> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<const L: usize> Neg for LVec3<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}
/// Each lane's vector times that lane's scalar.
impl<const L: usize> Mul<Lanes<L>> for LVec3<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: Lanes<L>) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

/// A 3×3 matrix per lane, by columns (glam's `DMat3` across robots).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LMat3<const L: usize> {
    /// First column.
    pub x_axis: LVec3<L>,
    /// Second column.
    pub y_axis: LVec3<L>,
    /// Third column.
    pub z_axis: LVec3<L>,
}

impl<const L: usize> LMat3<L> {
    /// The zero matrix in every lane.
    pub const ZERO: Self = Self::splat(DMat3::ZERO);

    /// Builds a matrix from its columns.
    #[inline(always)]
    pub const fn from_cols(x_axis: LVec3<L>, y_axis: LVec3<L>, z_axis: LVec3<L>) -> Self {
        Self {
            x_axis,
            y_axis,
            z_axis,
        }
    }

    /// The same matrix in every lane.
    #[inline(always)]
    pub const fn splat(m: DMat3) -> Self {
        Self::from_cols(
            LVec3::splat(m.x_axis),
            LVec3::splat(m.y_axis),
            LVec3::splat(m.z_axis),
        )
    }

    /// Lane `k` as a glam matrix.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> DMat3 {
        DMat3::from_cols(
            self.x_axis.lane(k),
            self.y_axis.lane(k),
            self.z_axis.lane(k),
        )
    }

    /// Column `k` (0, 1 or 2).
    #[inline(always)]
    pub fn col(&self, k: usize) -> LVec3<L> {
        match k {
            0 => self.x_axis,
            1 => self.y_axis,
            _ => self.z_axis,
        }
    }

    /// glam's `DMat3::from_diagonal` (off-diagonal entries +0).
    #[inline(always)]
    pub fn from_diagonal(d: LVec3<L>) -> Self {
        let z = Lanes::ZERO;
        Self::from_cols(
            LVec3::new(d.x, z, z),
            LVec3::new(z, d.y, z),
            LVec3::new(z, z, d.z),
        )
    }

    /// glam's `DMat3::transpose`.
    #[inline(always)]
    pub fn transpose(&self) -> Self {
        let (a, b, c) = (self.x_axis, self.y_axis, self.z_axis);
        Self::from_cols(
            LVec3::new(a.x, b.x, c.x),
            LVec3::new(a.y, b.y, c.y),
            LVec3::new(a.z, b.z, c.z),
        )
    }

    /// glam's `DMat3::mul_vec3`: `((x_axis·v.x) + y_axis·v.y) + z_axis·v.z`.
    #[inline(always)]
    pub fn mul_vec3(&self, v: LVec3<L>) -> LVec3<L> {
        let mut res = self.x_axis * v.x;
        res += self.y_axis * v.y;
        res += self.z_axis * v.z;
        res
    }

    /// glam's `DMat3 * DMat3`: each column of `o` through [`Self::mul_vec3`].
    #[inline(always)]
    pub fn mul_mat3(&self, o: &Self) -> Self {
        Self::from_cols(
            self.mul_vec3(o.x_axis),
            self.mul_vec3(o.y_axis),
            self.mul_vec3(o.z_axis),
        )
    }
}

impl<const L: usize> Add for LMat3<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::from_cols(
            self.x_axis + o.x_axis,
            self.y_axis + o.y_axis,
            self.z_axis + o.z_axis,
        )
    }
}
impl<const L: usize> Sub for LMat3<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::from_cols(
            self.x_axis - o.x_axis,
            self.y_axis - o.y_axis,
            self.z_axis - o.z_axis,
        )
    }
}
impl<const L: usize> AddAssign for LMat3<L> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<const L: usize> Mul<LVec3<L>> for LMat3<L> {
    type Output = LVec3<L>;
    #[inline(always)]
    fn mul(self, v: LVec3<L>) -> LVec3<L> {
        self.mul_vec3(v)
    }
}
impl<const L: usize> Mul for LMat3<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.mul_mat3(&o)
    }
}

/// glam's `spatial::skew`: `skew(a) * b == a × b`.
#[inline(always)]
pub fn skew<const L: usize>(a: LVec3<L>) -> LMat3<L> {
    let z = Lanes::ZERO;
    LMat3::from_cols(
        LVec3::new(z, a.z, -a.y),
        LVec3::new(-a.z, z, a.x),
        LVec3::new(a.y, -a.x, z),
    )
}

/// Outer product `a bᵀ`, as [`crate::spatial::outer`].
#[inline(always)]
pub fn outer<const L: usize>(a: LVec3<L>, b: LVec3<L>) -> LMat3<L> {
    LMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each lane of every vector and matrix operation equals glam's result bit for bit.
    #[test]
    fn batch_lane_ops_match_glam_bit_for_bit() {
        let a = [
            DVec3::new(0.3, -1.7, 2.9),
            DVec3::new(1e-3, 4.1, -0.2),
            DVec3::new(-5.5, 0.25, 1.0 / 3.0),
            DVec3::new(7.0, -0.0, 0.1),
        ];
        let b = [a[2], a[0], a[3], a[1]];
        let m = [
            DMat3::from_cols(a[0], a[1], a[2]),
            DMat3::from_cols(a[3], a[0], a[1]),
            DMat3::from_cols(a[1], a[2], a[3]),
            DMat3::from_cols(a[2], a[3], a[0]),
        ];
        let pack_v = |v: [DVec3; 4]| {
            let mut out = LVec3::<4>::ZERO;
            for k in 0..4 {
                out.set_lane(k, v[k]);
            }
            out
        };
        let pack_m = |m: [DMat3; 4]| {
            LMat3::from_cols(
                pack_v(m.map(|x| x.x_axis)),
                pack_v(m.map(|x| x.y_axis)),
                pack_v(m.map(|x| x.z_axis)),
            )
        };
        let (la, lb, lm) = (pack_v(a), pack_v(b), pack_m(m));
        let lmt = pack_m([m[1], m[2], m[3], m[0]]);
        for k in 0..4 {
            let bits = |v: DVec3| v.to_array().map(f64::to_bits);
            let mbits = |x: DMat3| x.to_cols_array().map(f64::to_bits);
            assert_eq!(bits(la.cross(lb).lane(k)), bits(a[k].cross(b[k])));
            assert_eq!(la.dot(lb).0[k].to_bits(), a[k].dot(b[k]).to_bits());
            assert_eq!(bits((lm * la).lane(k)), bits(m[k] * a[k]));
            let mt = [m[1], m[2], m[3], m[0]];
            assert_eq!(mbits((lm * lmt).lane(k)), mbits(m[k] * mt[k]));
            assert_eq!(mbits(lm.transpose().lane(k)), mbits(m[k].transpose()));
            assert_eq!(
                mbits(outer(la, lb).lane(k)),
                mbits(crate::spatial::outer(a[k], b[k]))
            );
            assert_eq!(mbits(skew(la).lane(k)), mbits(crate::spatial::skew(a[k])));
        }
    }
}
