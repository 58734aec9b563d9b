//! Four-lane f64 spatial algebra on AVX `__m256d` for [`super`]: glam's and
//! [`crate::spatial`]'s formulas operation for operation (same products, same
//! order of sums, the same additions of exact zeros, no fused multiply–add),
//! so each lane is bit-identical to the scalar result.
//!
//! Unlike [`crate::batch::lanes`] (plain `[f64; L]` loops that LLVM has to
//! re-vectorise, and on this code re-packs across components), each value here
//! is one AVX register and each operation one AVX instruction. The functions
//! are `#[target_feature(enable = "avx")]`: safe to call from code compiled
//! for AVX (the x86-64-v3 clones of the dispatched passes), and only from there.

use crate::spatial::{Force, Motion, Transform};
use core::arch::x86_64::{
    __m256d, _CMP_EQ_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ, _CMP_NEQ_OQ, _CMP_NLT_UQ,
    _MM_FROUND_NO_EXC, _MM_FROUND_TO_ZERO, _mm256_add_pd, _mm256_and_pd, _mm256_blendv_pd,
    _mm256_cmp_pd, _mm256_div_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_or_pd,
    _mm256_permute2f128_pd, _mm256_round_pd, _mm256_set1_pd, _mm256_sqrt_pd, _mm256_sub_pd,
    _mm256_unpackhi_pd, _mm256_unpacklo_pd, _mm256_xor_pd,
};
use glam::{DMat3, DVec3};

/// Four f64, one per leg, in one AVX register.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct F4(__m256d);

impl Default for F4 {
    fn default() -> Self {
        F4::from_array([0.0; 4])
    }
}

impl F4 {
    /// The lanes as one vector (a bit cast).
    #[inline(always)]
    pub fn from_array(a: [f64; 4]) -> Self {
        F4(bytemuck::cast(a))
    }

    /// The vector's lanes (a bit cast).
    #[inline(always)]
    pub fn to_array(self) -> [f64; 4] {
        bytemuck::cast(self.0)
    }

    /// Lane `k`, loaded from where `self` is stored (`to_array()[k]`
    /// would copy the whole vector through the stack for a run-time `k`).
    #[inline(always)]
    pub fn lane(&self, k: usize) -> f64 {
        bytemuck::cast_ref::<__m256d, [f64; 4]>(&self.0)[k]
    }

    /// The 4×4 transpose of the rows `r`: lane `k` of result `j` is lane
    /// `j` of `r[k]` (eight shuffles; moves only, the same bits).
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn transpose(r: [F4; 4]) -> [F4; 4] {
        let t0 = _mm256_unpacklo_pd(r[0].0, r[1].0);
        let t1 = _mm256_unpackhi_pd(r[0].0, r[1].0);
        let t2 = _mm256_unpacklo_pd(r[2].0, r[3].0);
        let t3 = _mm256_unpackhi_pd(r[2].0, r[3].0);
        [
            F4(_mm256_permute2f128_pd::<0x20>(t0, t2)),
            F4(_mm256_permute2f128_pd::<0x20>(t1, t3)),
            F4(_mm256_permute2f128_pd::<0x31>(t0, t2)),
            F4(_mm256_permute2f128_pd::<0x31>(t1, t3)),
        ]
    }

    /// The same value in every lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn splat(x: f64) -> Self {
        F4(_mm256_set1_pd(x))
    }

    /// `self + o` per lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn add(self, o: Self) -> Self {
        F4(_mm256_add_pd(self.0, o.0))
    }

    /// `self − o` per lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn sub(self, o: Self) -> Self {
        F4(_mm256_sub_pd(self.0, o.0))
    }

    /// `self · o` per lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn mul(self, o: Self) -> Self {
        F4(_mm256_mul_pd(self.0, o.0))
    }

    /// `self / o` per lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn div(self, o: Self) -> Self {
        F4(_mm256_div_pd(self.0, o.0))
    }

    /// `√self` per lane (IEEE, correctly rounded: `f64::sqrt`'s bits).
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn sqrt(self) -> Self {
        F4(_mm256_sqrt_pd(self.0))
    }

    /// `self` rounded toward zero per lane (`f64::trunc`'s bits).
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn trunc(self) -> Self {
        F4(_mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(self.0))
    }

    /// `|self|` per lane: the sign bit cleared, as `f64::abs` does.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn abs(self) -> Self {
        self.and(F4::bits(!(1 << 63)))
    }

    /// `−self` per lane: the sign bit flipped, as scalar negation does.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn neg(self) -> Self {
        F4(_mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)))
    }

    /// The bitwise AND of the lanes' bit patterns.
    #[inline]
    #[target_feature(enable = "avx")]
    pub(super) fn and(self, o: Self) -> Self {
        F4(_mm256_and_pd(self.0, o.0))
    }

    /// The bitwise OR of the lanes' bit patterns.
    #[inline]
    #[target_feature(enable = "avx")]
    pub(super) fn or(self, o: Self) -> Self {
        F4(_mm256_or_pd(self.0, o.0))
    }

    /// The bitwise XOR of the lanes' bit patterns.
    #[inline]
    #[target_feature(enable = "avx")]
    fn xor(self, o: Self) -> Self {
        F4(_mm256_xor_pd(self.0, o.0))
    }

    /// A lane mask (all bits set where true) of the comparison `self P o`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub(super) fn cmp<const P: i32>(self, o: Self) -> Self {
        F4(_mm256_cmp_pd::<P>(self.0, o.0))
    }

    /// `mask ? a : b` per lane (`mask` from [`Self::cmp`]).
    #[inline]
    #[target_feature(enable = "avx")]
    pub(super) fn select(mask: Self, a: Self, b: Self) -> Self {
        F4(_mm256_blendv_pd(b.0, a.0, mask.0))
    }

    /// The same bit pattern in every lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub(super) fn bits(b: u64) -> Self {
        F4::splat(f64::from_bits(b))
    }

    /// Sine and cosine per lane, bit for bit [`crate::trig::sin_cos`] (libm's
    /// `sincos`): [`crate::trig::sin_cos_lanes`]' operations, each one AVX
    /// instruction (that function's plain-Rust lane loops do not all
    /// vectorise); lanes that need libm's second reduction round or large
    /// argument path call it. Out of line (LLVM's choice for a body this
    /// large: rustc drops `#[inline(never)]` on `#[target_feature]`
    /// functions), so the pose loops around `avx::rotate_about_axis!` stay
    /// small.
    #[target_feature(enable = "avx")]
    pub fn sin_cos(self) -> (Self, Self) {
        use crate::trig::*;
        let sp = F4::splat;
        let x = self;
        let sign = F4::bits(1 << 63);
        let ax = x.and(F4::bits(!(1 << 63)));
        let one = sp(1.0);
        if _mm256_movemask_pd(ax.cmp::<_CMP_LE_OQ>(sp(PIO4)).0) == 0b1111 {
            return Self::sin_cos_within_pio4(x, ax);
        }
        let gt = |c: f64| ax.cmp::<_CMP_GT_OQ>(sp(c));
        // n as msun picks it (see `trig::sin_cos_lanes`)
        let n_thresholds = gt(PIO4)
            .and(one)
            .add(gt(PIO4_3).and(one))
            .add(gt(PIO4_5).and(one))
            .add(gt(PIO4_7).and(one))
            .or(x.and(sign));
        let n_rounded = x.mul(sp(INV_PIO2)).add(sp(TO_INT)).sub(sp(TO_INT));
        let f_n = F4::select(ax.cmp::<_CMP_LE_OQ>(sp(PIO4_9)), n_thresholds, n_rounded);
        let r = x.sub(f_n.mul(sp(PIO2_1)));
        let w = f_n.mul(sp(PIO2_1T));
        let y0 = r.sub(w);
        let y1 = r.sub(y0).sub(w);
        // lanes for libm itself
        let hi = x.and(F4::bits(0x7fff_ffff_0000_0000));
        let eq = |c: f64| hi.cmp::<_CMP_EQ_OQ>(sp(c));
        let near_multiple = eq(HI_PIO2).or(eq(HI_PI)).or(eq(HI_3PIO2).or(eq(HI_2PI)));
        let pow2 = x.and(F4::bits(0x7ff0_0000_0000_0000));
        let lost = y0
            .and(F4::bits(!(1 << 63)))
            .cmp::<_CMP_LT_OQ>(pow2.mul(sp(TWO_M16)));
        let refined = lost.and(gt(PIO4)).and(gt(PIO4_9).or(near_multiple));
        let fallback = ax.cmp::<_CMP_NLT_UQ>(sp(MEDIUM_END)).or(refined);
        // kernels
        let k = Self::kernels(y0, y1);
        let t = k.z.mul(sp(0.5).mul(y1).sub(k.v.mul(k.rs))).sub(y1);
        let sin_iy1 = y0.sub(t.sub(k.v.mul(sp(S1))));
        let sin_r = F4::select(ax.cmp::<_CMP_LE_OQ>(sp(PIO4)), k.sin_iy0, sin_iy1);
        let cos_r = k.cos;
        // quadrant from the low bits of n + 1.5·2⁵² and n + 1 + 1.5·2⁵²
        let zero = sp(0.0);
        let qa = f_n.add(sp(TO_INT));
        let qb = f_n.add(one).add(sp(TO_INT));
        let odd = qa.and(F4::bits(1)).cmp::<_CMP_NEQ_OQ>(zero);
        let neg_s = qa.and(F4::bits(2)).cmp::<_CMP_NEQ_OQ>(zero).and(sign);
        let neg_c = qb.and(F4::bits(2)).cmp::<_CMP_NEQ_OQ>(zero).and(sign);
        let s = F4::select(odd, cos_r, sin_r).xor(neg_s);
        let c = F4::select(odd, sin_r, cos_r).xor(neg_c);
        let tiny = ax.cmp::<_CMP_LT_OQ>(sp(TINY));
        let s = F4::select(tiny, x, s);
        let c = F4::select(tiny, one, c);
        if _mm256_movemask_pd(fallback.0) == 0 {
            return (s, c);
        }
        let (xa, fb) = (x.to_array(), _mm256_movemask_pd(fallback.0));
        let (mut sa, mut ca) = (s.to_array(), c.to_array());
        for k in 0..4 {
            if fb & (1 << k) != 0 {
                (sa[k], ca[k]) = libm::sincos(xa[k]);
            }
        }
        (F4::from_array(sa), F4::from_array(ca))
    }

    /// [`Self::sin_cos`] when every lane is within ±π/4 (`ax` = |x|): msun
    /// reduces nothing there (n = ±0, so y0 = x − ±0 = x and y1 = +0 in
    /// every lane that is not tiny, and the tiny ones take x and 1 below)
    /// and no lane needs libm, so the general path's operations on y0 = x,
    /// y1 = 0 that it selects, and none of the others: the same bits in
    /// about half the instructions. The legs' hip roll angles always, hip
    /// pitch most of the time.
    #[inline]
    #[target_feature(enable = "avx")]
    fn sin_cos_within_pio4(x: Self, ax: Self) -> (Self, Self) {
        use crate::trig::TINY;
        let k = Self::kernels(x, F4::splat(0.0));
        let tiny = ax.cmp::<_CMP_LT_OQ>(F4::splat(TINY));
        (
            F4::select(tiny, x, k.sin_iy0),
            F4::select(tiny, F4::splat(1.0), k.cos),
        )
    }

    /// msun's `__sin(y0, y1, 0)` and `__cos(y0, y1)` per lane on the reduced
    /// argument `y0 + y1`, with what `__sin(.., 1)` needs besides.
    #[inline]
    #[target_feature(enable = "avx")]
    fn kernels(y0: Self, y1: Self) -> Kernels {
        use crate::trig::*;
        let sp = F4::splat;
        let one = sp(1.0);
        let z = y0.mul(y0);
        let zz = z.mul(z);
        let rs = sp(S2)
            .add(z.mul(sp(S3).add(z.mul(sp(S4)))))
            .add(z.mul(zz).mul(sp(S5).add(z.mul(sp(S6)))));
        let v = z.mul(y0);
        let sin_iy0 = y0.add(v.mul(sp(S1).add(z.mul(rs))));
        let rc = z
            .mul(sp(C1).add(z.mul(sp(C2).add(z.mul(sp(C3))))))
            .add(zz.mul(zz).mul(sp(C4).add(z.mul(sp(C5).add(z.mul(sp(C6)))))));
        let hz = sp(0.5).mul(z);
        let wc = one.sub(hz);
        let tail = z.mul(rc).sub(y0.mul(y1));
        let cos = wc.add(one.sub(wc).sub(hz).add(tail));
        Kernels {
            z,
            rs,
            v,
            sin_iy0,
            cos,
        }
    }
}

/// [`F4::kernels`]' results: `z = y0²`, the sine's polynomial `rs`, `v = z
/// y0`, the sine for `y1` = 0 (`__sin(y0, y1, 0)`) and the cosine.
#[derive(Clone, Copy)]
struct Kernels {
    z: F4,
    rs: F4,
    v: F4,
    sin_iy0: F4,
    cos: F4,
}

/// A 3-vector per lane (glam's `DVec3`).
#[derive(Clone, Copy, Debug, Default)]
pub struct V3 {
    /// x components.
    pub x: F4,
    /// y components.
    pub y: F4,
    /// z components.
    pub z: F4,
}

impl V3 {
    /// Builds a vector from its components.
    #[inline(always)]
    pub fn new(x: F4, y: F4, z: F4) -> Self {
        Self { x, y, z }
    }

    /// The same vector in every lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn splat(v: DVec3) -> Self {
        Self::new(F4::splat(v.x), F4::splat(v.y), F4::splat(v.z))
    }

    /// One vector per lane.
    #[inline(always)]
    pub fn from_lanes(v: [DVec3; 4]) -> Self {
        Self::new(
            F4::from_array([v[0].x, v[1].x, v[2].x, v[3].x]),
            F4::from_array([v[0].y, v[1].y, v[2].y, v[3].y]),
            F4::from_array([v[0].z, v[1].z, v[2].z, v[3].z]),
        )
    }

    /// Lane `k`, element by element from memory (no AVX needed).
    #[inline(always)]
    pub fn lane(&self, k: usize) -> DVec3 {
        DVec3::new(self.x.lane(k), self.y.lane(k), self.z.lane(k))
    }

    /// The four lanes.
    #[inline(always)]
    pub fn lanes(&self) -> [DVec3; 4] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        [
            DVec3::new(x[0], y[0], z[0]),
            DVec3::new(x[1], y[1], z[1]),
            DVec3::new(x[2], y[2], z[2]),
            DVec3::new(x[3], y[3], z[3]),
        ]
    }

    /// `self + o`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn add(self, o: Self) -> Self {
        Self::new(self.x.add(o.x), self.y.add(o.y), self.z.add(o.z))
    }

    /// `self − o`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn sub(self, o: Self) -> Self {
        Self::new(self.x.sub(o.x), self.y.sub(o.y), self.z.sub(o.z))
    }

    /// `−self`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn neg(self) -> Self {
        Self::new(self.x.neg(), self.y.neg(), self.z.neg())
    }

    /// Each lane's vector times that lane's scalar.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn scale(self, s: F4) -> Self {
        Self::new(self.x.mul(s), self.y.mul(s), self.z.mul(s))
    }

    /// glam's `dot`: `(x·x') + (y·y') + (z·z')`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn dot(self, o: Self) -> F4 {
        self.x.mul(o.x).add(self.y.mul(o.y)).add(self.z.mul(o.z))
    }

    /// glam's `cross`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y.mul(o.z).sub(o.y.mul(self.z)),
            self.z.mul(o.x).sub(o.z.mul(self.x)),
            self.x.mul(o.y).sub(o.x.mul(self.y)),
        )
    }
}

/// A 3×3 matrix per lane, by columns (glam's `DMat3`).
#[derive(Clone, Copy, Debug, Default)]
pub struct M3 {
    /// First column.
    pub x_axis: V3,
    /// Second column.
    pub y_axis: V3,
    /// Third column.
    pub z_axis: V3,
}

impl M3 {
    /// Builds a matrix from its columns.
    #[inline(always)]
    pub fn from_cols(x_axis: V3, y_axis: V3, z_axis: V3) -> Self {
        Self {
            x_axis,
            y_axis,
            z_axis,
        }
    }

    /// The same matrix in every lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn splat(m: DMat3) -> Self {
        Self::from_cols(
            V3::splat(m.x_axis),
            V3::splat(m.y_axis),
            V3::splat(m.z_axis),
        )
    }

    /// One matrix per lane.
    #[inline(always)]
    pub fn from_lanes(m: [DMat3; 4]) -> Self {
        Self::from_cols(
            V3::from_lanes(m.map(|x| x.x_axis)),
            V3::from_lanes(m.map(|x| x.y_axis)),
            V3::from_lanes(m.map(|x| x.z_axis)),
        )
    }

    /// The four lanes.
    #[inline(always)]
    pub fn lanes(&self) -> [DMat3; 4] {
        let (x, y, z) = (
            self.x_axis.lanes(),
            self.y_axis.lanes(),
            self.z_axis.lanes(),
        );
        [
            DMat3::from_cols(x[0], y[0], z[0]),
            DMat3::from_cols(x[1], y[1], z[1]),
            DMat3::from_cols(x[2], y[2], z[2]),
            DMat3::from_cols(x[3], y[3], z[3]),
        ]
    }

    /// Column `k` (0, 1 or 2).
    #[inline(always)]
    pub fn col(&self, k: usize) -> V3 {
        match k {
            0 => self.x_axis,
            1 => self.y_axis,
            _ => self.z_axis,
        }
    }

    /// glam's `from_diagonal` (off-diagonal entries +0).
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn from_diagonal(d: V3) -> Self {
        let z = F4::splat(0.0);
        Self::from_cols(V3::new(d.x, z, z), V3::new(z, d.y, z), V3::new(z, z, d.z))
    }

    /// glam's `transpose`.
    #[inline(always)]
    pub fn transpose(&self) -> Self {
        let (a, b, c) = (self.x_axis, self.y_axis, self.z_axis);
        Self::from_cols(
            V3::new(a.x, b.x, c.x),
            V3::new(a.y, b.y, c.y),
            V3::new(a.z, b.z, c.z),
        )
    }

    /// `self + o`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn add(self, o: Self) -> Self {
        Self::from_cols(
            self.x_axis.add(o.x_axis),
            self.y_axis.add(o.y_axis),
            self.z_axis.add(o.z_axis),
        )
    }

    /// `self − o`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn sub(self, o: Self) -> Self {
        Self::from_cols(
            self.x_axis.sub(o.x_axis),
            self.y_axis.sub(o.y_axis),
            self.z_axis.sub(o.z_axis),
        )
    }

    /// glam's `mul_vec3`: `((x_axis·v.x) + y_axis·v.y) + z_axis·v.z`.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn mul_vec3(self, v: V3) -> V3 {
        self.x_axis
            .scale(v.x)
            .add(self.y_axis.scale(v.y))
            .add(self.z_axis.scale(v.z))
    }

    /// glam's `DMat3 * DMat3`: each column of `o` through [`Self::mul_vec3`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn mul_mat3(self, o: Self) -> Self {
        Self::from_cols(
            self.mul_vec3(o.x_axis),
            self.mul_vec3(o.y_axis),
            self.mul_vec3(o.z_axis),
        )
    }
}

/// [`crate::spatial::skew`] per lane.
#[inline]
#[target_feature(enable = "avx")]
pub fn skew(a: V3) -> M3 {
    let z = F4::splat(0.0);
    M3::from_cols(
        V3::new(z, a.z, a.y.neg()),
        V3::new(a.z.neg(), z, a.x),
        V3::new(a.y, a.x.neg(), z),
    )
}

/// [`crate::spatial::outer`] per lane: `a bᵀ`.
#[inline]
#[target_feature(enable = "avx")]
pub fn outer(a: V3, b: V3) -> M3 {
    M3::from_cols(a.scale(b.x), a.scale(b.y), a.scale(b.z))
}

/// A spatial motion `[v; ω]` per lane ([`Motion`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Motion4 {
    /// Linear part.
    pub lin: V3,
    /// Angular part.
    pub ang: V3,
}

/// A spatial force `[f; n]` per lane ([`Force`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Force4 {
    /// Force.
    pub lin: V3,
    /// Moment.
    pub ang: V3,
}

macro_rules! spatial_ops {
    ($t:ident, $scalar:ident) => {
        // (each pair uses only some of these)
        #[allow(dead_code)]
        impl $t {
            /// Builds the pair from its parts.
            #[inline(always)]
            pub fn new(lin: V3, ang: V3) -> Self {
                Self { lin, ang }
            }

            /// The same value in every lane.
            #[inline]
            #[target_feature(enable = "avx")]
            pub fn splat(m: $scalar) -> Self {
                Self::new(V3::splat(m.lin), V3::splat(m.ang))
            }

            /// Lane `k`, element by element from memory (no AVX needed).
            #[inline(always)]
            pub fn lane(&self, k: usize) -> $scalar {
                $scalar::new(self.lin.lane(k), self.ang.lane(k))
            }

            /// One value per lane.
            #[inline(always)]
            pub fn from_lanes(f: [$scalar; 4]) -> Self {
                Self::new(
                    V3::from_lanes(f.map(|x| x.lin)),
                    V3::from_lanes(f.map(|x| x.ang)),
                )
            }

            /// The four lanes.
            #[inline(always)]
            pub fn lanes(&self) -> [$scalar; 4] {
                let (l, a) = (self.lin.lanes(), self.ang.lanes());
                [
                    $scalar::new(l[0], a[0]),
                    $scalar::new(l[1], a[1]),
                    $scalar::new(l[2], a[2]),
                    $scalar::new(l[3], a[3]),
                ]
            }

            /// `self + o`.
            #[inline]
            #[target_feature(enable = "avx")]
            pub fn add(self, o: Self) -> Self {
                Self::new(self.lin.add(o.lin), self.ang.add(o.ang))
            }

            /// `self − o`.
            #[inline]
            #[target_feature(enable = "avx")]
            pub fn sub(self, o: Self) -> Self {
                Self::new(self.lin.sub(o.lin), self.ang.sub(o.ang))
            }

            /// Each lane's value times that lane's scalar.
            #[inline]
            #[target_feature(enable = "avx")]
            pub fn scale(self, s: F4) -> Self {
                Self::new(self.lin.scale(s), self.ang.scale(s))
            }
        }
    };
}
spatial_ops!(Motion4, Motion);
spatial_ops!(Force4, Force);

impl Motion4 {
    /// [`Motion::cross`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn cross(self, m: Self) -> Self {
        Self {
            lin: self.ang.cross(m.lin).add(self.lin.cross(m.ang)),
            ang: self.ang.cross(m.ang),
        }
    }

    /// [`Motion::cross_force`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn cross_force(self, f: Force4) -> Force4 {
        Force4 {
            lin: self.ang.cross(f.lin),
            ang: self.ang.cross(f.ang).add(self.lin.cross(f.lin)),
        }
    }

    /// [`Motion::dot`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn dot(self, f: Force4) -> F4 {
        self.lin.dot(f.lin).add(self.ang.dot(f.ang))
    }
}

/// A rigid transform per lane ([`Transform`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Transform4 {
    /// Rotation.
    pub rot: M3,
    /// Translation (m).
    pub trans: V3,
}

impl Transform4 {
    /// Builds a transform.
    #[inline(always)]
    pub fn new(rot: M3, trans: V3) -> Self {
        Self { rot, trans }
    }

    /// The four lanes.
    #[inline(always)]
    pub fn lanes(&self) -> [Transform; 4] {
        let (r, t) = (self.rot.lanes(), self.trans.lanes());
        [
            Transform::new(r[0], t[0]),
            Transform::new(r[1], t[1]),
            Transform::new(r[2], t[2]),
            Transform::new(r[3], t[3]),
        ]
    }

    /// [`Transform::transform_point`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn transform_point(&self, p: V3) -> V3 {
        self.rot.mul_vec3(p).add(self.trans)
    }
}

/// A rigid-body inertia per lane ([`crate::spatial::RigidInertia`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Inertia4 {
    /// Mass (kg).
    pub mass: F4,
    /// Centre of mass (m).
    pub com: V3,
    /// Rotational inertia about the centre of mass (kg·m²).
    pub inertia_com: M3,
}

impl Inertia4 {
    /// [`crate::spatial::RigidInertia::transformed`], each lane through its transform.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn transformed(&self, x: &Transform4) -> Self {
        let rt = x.rot.transpose();
        let at = self.inertia_com.mul_mat3(rt);
        let (a0, a1, a2) = (at.x_axis, at.y_axis, at.z_axis);
        let (r0, r1, r2) = (rt.x_axis, rt.y_axis, rt.z_axis);
        let (xx, yy, zz) = (a0.dot(r0), a1.dot(r1), a2.dot(r2));
        let (xy, xz, yz) = (a0.dot(r1), a0.dot(r2), a1.dot(r2));
        Self {
            mass: self.mass,
            com: x.transform_point(self.com),
            inertia_com: M3::from_cols(
                V3::new(xx, xy, xz),
                V3::new(xy, yy, yz),
                V3::new(xz, yz, zz),
            ),
        }
    }

    /// [`crate::spatial::RigidInertia::to_sym6`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn to_sym6(self) -> Sym6x4 {
        let c = self.com;
        let mc = c.scale(self.mass);
        let d = mc.dot(c);
        Sym6x4 {
            m: M3::from_diagonal(V3::new(self.mass, self.mass, self.mass)),
            h: skew(mc),
            i: self
                .inertia_com
                .add(M3::from_diagonal(V3::new(d, d, d)))
                .sub(outer(mc, c)),
        }
    }

    /// [`crate::spatial::RigidInertia::mul_motion`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn mul_motion(&self, v: Motion4) -> Force4 {
        let f = v.lin.add(v.ang.cross(self.com)).scale(self.mass);
        Force4 {
            lin: f,
            ang: self.inertia_com.mul_vec3(v.ang).add(self.com.cross(f)),
        }
    }
}

/// A symmetric 6×6 spatial inertia per lane, in blocks ([`crate::spatial::Sym6`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Sym6x4 {
    /// Linear–linear block.
    pub m: M3,
    /// Angular–linear block.
    pub h: M3,
    /// Angular–angular block.
    pub i: M3,
}

impl Sym6x4 {
    /// `self + o`, block by block.
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn add(self, o: Self) -> Self {
        Self {
            m: self.m.add(o.m),
            h: self.h.add(o.h),
            i: self.i.add(o.i),
        }
    }

    /// [`crate::spatial::Sym6::mul_motion`].
    #[inline]
    #[target_feature(enable = "avx")]
    pub fn mul_motion(&self, v: Motion4) -> Force4 {
        let ht_w = V3::new(
            self.h.x_axis.dot(v.ang),
            self.h.y_axis.dot(v.ang),
            self.h.z_axis.dot(v.ang),
        );
        Force4 {
            lin: self.m.mul_vec3(v.lin).add(ht_w),
            ang: self.h.mul_vec3(v.lin).add(self.i.mul_vec3(v.ang)),
        }
    }
}
