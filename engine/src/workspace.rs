//! The algorithms' scratch memory that holds nothing from one call to the
//! next: one per thread, not one per robot, sized by `Data::new` so that
//! stepping allocates nothing (ABA's and CRBA's per-body arrays, the mass
//! matrix). The legs-in-lanes kernels keep theirs in
//! `kernels::legs_x4::workspace`.

use crate::spatial::{Force, Motion, Sym6};

/// ABA's and CRBA's per-body workspace (reference frame, nbodies each): it
/// holds nothing from one call to the next, so it is one per thread, not one
/// per robot's [`Data`]. Sized to the largest model the thread has run
/// (allocating on a thread's first call only).
#[derive(Debug, Default)]
pub(crate) struct BodyScratch {
    /// Articulated (ABA) or composite (CRBA) inertia of each body.
    pub(crate) ia: Vec<Sym6>,
    /// Articulated bias force (ABA).
    pub(crate) pa: Vec<Force>,
    /// `U = Iᴬ S` for each 1-DOF body (ABA).
    pub(crate) u: Vec<Force>,
    /// `1 / D`, `D = Sᵀ U + armature` (ABA).
    pub(crate) d_inv: Vec<f64>,
    /// `u = τ − Sᵀ pᴬ` (ABA).
    pub(crate) u_tau: Vec<f64>,
    /// Velocity-product acceleration `cᵢ = vᵢ ×ₘ Sᵢ q̇ᵢ` (ABA).
    pub(crate) c: Vec<Motion>,
}

thread_local! {
    static BODY_SCRATCH: std::cell::RefCell<BodyScratch> =
        std::cell::RefCell::new(BodyScratch::default());
}

impl BodyScratch {
    /// This thread's workspace with at least `nbodies` entries per array,
    /// lent until [`BodyScratch::give_back`]. Every algorithm writes an entry
    /// before reading it: what it held before does not matter.
    pub(crate) fn take(nbodies: usize) -> BodyScratch {
        let mut s = BODY_SCRATCH.with(std::cell::RefCell::take);
        if s.ia.len() < nbodies {
            s.ia.resize(nbodies, Sym6::ZERO);
            s.pa.resize(nbodies, Force::ZERO);
            s.u.resize(nbodies, Force::ZERO);
            s.d_inv.resize(nbodies, 0.0);
            s.u_tau.resize(nbodies, 0.0);
            s.c.resize(nbodies, Motion::ZERO);
        }
        s
    }

    /// Returns the workspace to this thread.
    pub(crate) fn give_back(self) {
        BODY_SCRATCH.with(|cell| drop(cell.replace(self)));
    }
}

/// The joint-space mass matrix (nv × nv, row-major, full symmetric),
/// armature included on the diagonal. It lives in a buffer of the calling
/// thread, lent while this value lives (it derefs to `[f64]`) and returned
/// when it drops: read it and let it go. A robot's `Data` holds none (most
/// steps need no mass matrix); holding two at once on one thread allocates.
#[derive(Debug)]
pub struct MassMatrix(pub(crate) Vec<f64>);

thread_local! {
    static MASS_MATRIX: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl MassMatrix {
    /// This thread's buffer, `n` zeros.
    pub(crate) fn zeros(n: usize) -> MassMatrix {
        let mut m = MASS_MATRIX.with(std::cell::RefCell::take);
        m.clear();
        m.resize(n, 0.0);
        MassMatrix(m)
    }

    /// Sizes this thread's buffer for `model` (by `Data::new`, so that
    /// stepping on the thread allocates nothing).
    pub(crate) fn reserve(nv: usize) {
        drop(MassMatrix::zeros(nv * nv));
    }
}

impl std::ops::Deref for MassMatrix {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.0
    }
}

impl Drop for MassMatrix {
    fn drop(&mut self) {
        let m = std::mem::take(&mut self.0);
        MASS_MATRIX.with(|cell| {
            let mut held = cell.borrow_mut();
            if held.capacity() < m.capacity() {
                *held = m;
            }
        });
    }
}
