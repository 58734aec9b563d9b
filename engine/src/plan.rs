//! What compiling a [`crate::Model`] decides about how its algorithms run:
//! the plan ([`Plan::Scalar`], [`Plan::LegsX4`]) that each dispatch function
//! of [`crate::dispatch`] matches on, and the constants its kernel needs.
//! Data only: the kernels live in [`crate::kernels`], the choice in
//! [`crate::model`].

#[cfg(target_arch = "x86_64")]
use crate::kernels::f64x4::{F4, Inertia4, M3, Transform4, V3};
#[cfg(target_arch = "x86_64")]
use crate::spatial::{RigidInertia, Transform};

/// Legs per group: four f64 lanes fill one AVX register.
pub const LEGS: usize = 4;

/// How a model's algorithms run. Every plan gives the scalar path's bits
/// (the kernel contract, [`crate::kernels`]).
#[derive(Clone, Debug, Default)]
pub enum Plan {
    /// The generic algorithms, one body after another.
    #[default]
    Scalar,
    /// Four identical unbranched legs on the base, the four bodies at each
    /// depth in one AVX register ([`crate::kernels::legs_x4`]), where the
    /// CPU has AVX2 and FMA (else the scalar path).
    LegsX4(LegLanes),
}

/// The legs' bodies grouped by depth, decided once per model when the model
/// is compiled, with what forward kinematics needs of each group in lanes.
#[derive(Clone, Debug)]
pub struct LegLanes {
    /// `groups[g][k]`: the body at depth `g + 1` of leg `k`; legs in
    /// increasing index of their first body, as `Model::depth_order` has them.
    pub groups: Vec<[usize; LEGS]>,
    /// Per group: the joints' placements, axis and the bodies' inertias in lanes.
    #[cfg(target_arch = "x86_64")]
    pub(crate) steps: Vec<GroupStep>,
    /// Whether each leg's bodies are consecutive: body `1 + k·G + g` is
    /// group `g`'s lane `k` (`G` groups).
    pub leg_major: bool,
}

/// One group's constants (the same `model::PoseStep` shortcuts hold for its
/// four bodies).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Debug)]
pub(crate) struct GroupStep {
    /// Joint placements in the parent bodies.
    pub(crate) placement: Transform4,
    /// The placements' rotations are not the identity (else their product is skipped).
    pub(crate) rotates: bool,
    /// The placements' translations are not zero (else their product is skipped).
    pub(crate) translates: bool,
    /// The joints turn about ±(this unit axis) of their joint frames...
    pub(crate) axis: usize,
    /// ...with this sign.
    pub(crate) sign: f64,
    /// Each body's inertia in its own frame.
    pub(crate) inertia: Inertia4,
    /// Each joint's index in q.
    pub(crate) idx_q: [usize; LEGS],
    /// Each joint's index in v.
    pub(crate) idx_v: [usize; LEGS],
}

/// One group's bodies as the model describes them, for [`GroupStep::new`].
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct GroupBodies {
    pub(crate) placement: [Transform; LEGS],
    pub(crate) inertia: [RigidInertia; LEGS],
    /// The joints' common axis `k` and its sign.
    pub(crate) axis: (usize, f64),
    pub(crate) rotates: bool,
    pub(crate) translates: bool,
    pub(crate) idx_q: [usize; LEGS],
    pub(crate) idx_v: [usize; LEGS],
}

#[cfg(target_arch = "x86_64")]
impl GroupStep {
    /// The group's constants in lanes.
    pub(crate) fn new(b: &GroupBodies) -> GroupStep {
        let (pl, ri) = (b.placement, b.inertia);
        GroupStep {
            placement: Transform4::new(
                M3::from_lanes(pl.map(|t| t.rot)),
                V3::from_lanes(pl.map(|t| t.trans)),
            ),
            rotates: b.rotates,
            translates: b.translates,
            axis: b.axis.0,
            sign: b.axis.1,
            inertia: Inertia4 {
                mass: F4::from_array(ri.map(|r| r.mass)),
                com: V3::from_lanes(ri.map(|r| r.com)),
                inertia_com: M3::from_lanes(ri.map(|r| r.inertia_com)),
            },
            idx_q: b.idx_q,
            idx_v: b.idx_v,
        }
    }
}
