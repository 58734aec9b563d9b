//! What the legs-in-lanes kernels keep between their passes: the lane
//! cache of one robot's kinematics (in its [`crate::Data`]) and ABA's
//! per-group workspace (per thread).

#[cfg(target_arch = "x86_64")]
use crate::kernels::f64x4::{F4, Force4, Inertia4, Motion4};

/// One group's motion subspace, reference inertia and velocity as the
/// lanes' forward kinematics computed them (kept in `Data`'s lane cache).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct GroupKinematics {
    pub(crate) s: Motion4,
    pub(crate) inertia: Inertia4,
    /// The velocities (for the legs' mass sums; 768 bytes a quad16).
    pub(crate) v: Motion4,
}

/// The legs' motion subspaces, reference inertias and velocities in lanes,
/// as the lanes' forward kinematics left them, for ABA, RNEA and the mass
/// sums in lanes (no gather). A copy: the per-body arrays of the same
/// `Data` hold the same values.
#[derive(Clone, Debug, Default)]
pub(crate) struct LaneKinematics {
    /// The entries hold the kinematics the per-body arrays hold: set by a
    /// forward kinematics with velocities and inertias in lanes, cleared by
    /// every other write of the kinematics.
    pub(crate) valid: bool,
    /// One per group of the model's legs (none in a kinematics-only `Data`
    /// or without lanes).
    #[cfg(target_arch = "x86_64")]
    pub(crate) groups: Vec<GroupKinematics>,
}

impl LaneKinematics {
    /// Room for `groups` groups.
    pub(crate) fn new(groups: usize) -> LaneKinematics {
        let _ = groups;
        LaneKinematics {
            valid: false,
            #[cfg(target_arch = "x86_64")]
            groups: vec![GroupKinematics::default(); groups],
        }
    }
}

/// What ABA's last pass needs of one group, kept from the inward pass (one
/// per thread: it holds nothing between calls).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct GroupAba {
    /// `U = Iᴬ S`.
    pub(crate) u: Force4,
    /// `1 / D`.
    pub(crate) d_inv: F4,
    /// `u = τ − Sᵀ pᴬ`.
    pub(crate) u_tau: F4,
    /// Velocity-product acceleration.
    pub(crate) c: Motion4,
}

/// A thread's ABA workspace: the groups' terms from pass 2 to pass 3, and
/// room for their kinematics when the lane cache does not hold them.
#[cfg(target_arch = "x86_64")]
pub(crate) type AbaWorkspace = (Vec<GroupAba>, Vec<GroupKinematics>);

#[cfg(target_arch = "x86_64")]
thread_local! {
    static GROUP_ABA: std::cell::RefCell<AbaWorkspace> = const {
        std::cell::RefCell::new((Vec::new(), Vec::new()))
    };
}

/// This thread's ABA workspace of `ng` groups (every entry is written
/// before it is read), lent until [`give_back_group_aba`].
#[cfg(target_arch = "x86_64")]
pub(crate) fn take_group_aba(ng: usize) -> AbaWorkspace {
    let (mut w, mut k) = GROUP_ABA.with(std::cell::RefCell::take);
    if w.len() < ng {
        w.resize(ng, GroupAba::default());
    }
    if k.len() < ng {
        k.resize(ng, GroupKinematics::default());
    }
    (w, k)
}

/// Returns the workspace to this thread.
#[cfg(target_arch = "x86_64")]
pub(crate) fn give_back_group_aba(w: AbaWorkspace) {
    GROUP_ABA.with(|cell| drop(cell.replace(w)));
}

/// Sizes this thread's ABA workspace for `groups` groups (by `Data::new`,
/// so that stepping on the thread allocates nothing).
pub(crate) fn reserve_group_aba(groups: usize) {
    #[cfg(target_arch = "x86_64")]
    give_back_group_aba(take_group_aba(groups));
    #[cfg(not(target_arch = "x86_64"))]
    let _ = groups;
}
