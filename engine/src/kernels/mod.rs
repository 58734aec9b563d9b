//! Specialised kernels: the generic algorithms' passes rewritten for one
//! shape of model in SIMD lanes, chosen by the model's [`crate::plan::Plan`]
//! in [`crate::dispatch`].
//!
//! - [`legs_x4`]: one robot whose base carries four identical unbranched
//!   legs (quad16, quad12), the four bodies at each depth in one AVX
//!   register (`f64x4::F4`).
//! - [`crate::batch`]: four robots of one model side by side, one robot per
//!   lane (`batch::lanes`).
//!
//! **The kernel contract.** Every kernel repeats the scalar algorithm's
//! operations in the same order (same products, same order of sums, the same
//! additions of exact zeros, no fused multiply–add) and calls the same libm
//! functions per lane, so each output is **bit-identical** to the scalar path
//! of [`crate::kinematics`], [`crate::aba`], [`crate::rnea`] and
//! [`crate::com`]. `engine/tests/kernel_contract.rs` checks it on random trees
//! and on the built-in robots.
//!
//! The kernels are compiled for x86-64-v3 (AVX2, FMA) and called only from
//! the x86-64-v3 clones of the dispatch functions; other CPUs run the scalar
//! path, with the same bits.

/// Calls an AVX kernel from a `match_target!` arm for `"x86_64+avx2+fma"`.
/// In the portable build that arm runs inside multiversion's x86-64-v3
/// clone, where the call is safe. A build for a CPU with AVX2 and FMA
/// (`RUSTFLAGS="-C target-cpu=native"` or `x86-64-v3`) skips the dispatch and
/// runs the arm in a function without `#[target_feature]`, where Rust still
/// asks for `unsafe`, although that binary cannot run on a CPU without those
/// features.
macro_rules! avx_call {
    ($call:expr) => {{
        // SAFETY: the build's static target features include AVX2 and FMA,
        // so every CPU it runs on has the AVX these functions need.
        #[cfg(all(target_feature = "avx2", target_feature = "fma"))]
        #[allow(unsafe_code, unused_unsafe)]
        let r = unsafe { $call };
        #[cfg(not(all(target_feature = "avx2", target_feature = "fma")))]
        let r = $call;
        r
    }};
}
pub(crate) use avx_call;

#[cfg(target_arch = "x86_64")]
pub(crate) mod f64x4;
pub mod legs_x4;

/// Whether this CPU has what the lane kernels' clones need (AVX2 and FMA).
#[cfg(target_arch = "x86_64")]
pub fn cpu_has_lanes() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// No lanes off x86-64.
#[cfg(not(target_arch = "x86_64"))]
pub fn cpu_has_lanes() -> bool {
    false
}

/// Sine and cosine of four angles at once, bit for bit
/// [`crate::trig::sin_cos`] of each: on x86-64-v3 one AVX register
/// (`f64x4::F4::sin_cos`, the operations of [`crate::trig::sin_cos_lanes`]
/// as intrinsics), elsewhere [`crate::trig::sin_cos_lanes`]. The CPU picks
/// one at the first call; the same bits either way.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn sin_cos_x4(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    multiversion::target::match_target! {
        "x86_64+avx2+fma" => avx_call!(sin_cos_avx(x)),
        _ => crate::trig::sin_cos_lanes(x),
    }
}

/// [`sin_cos_x4`] on AVX: four sines and cosines in one register.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx")]
fn sin_cos_avx(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    let (s, c) = f64x4::F4::from_array(x).sin_cos();
    (s.to_array(), c.to_array())
}
