//! The walker's RNEA pass over the legs in lanes: only the joint torques.

use super::LEGS;
use super::LegLanes;
use super::avx::{RNEA_MAX_GROUPS, gather, group_kinematics};
use super::x4::{Force4, Motion4};
use crate::data::Data;
use crate::model::Model;
use crate::spatial::Motion;

/// The joint torques of [`super::rnea_passes_legs`] without external
/// forces, for a caller that reads nothing else (the walker's
/// feed-forward): the same operations in the same order on the legs'
/// forces, but no body's `acc` or `f` is stored and the hips' forces are
/// not summed into the base's. `a0` is the base's acceleration
/// (`data.acc[0]` of the full pass); each leg joint `j`'s torque goes to
/// `tau_joints[j − base_nv]`.
#[target_feature(enable = "avx")]
pub(crate) fn rnea_joint_torques_legs(
    model: &Model,
    plan: &LegLanes,
    data: &Data,
    v: &[f64],
    a: &[f64],
    a0: Motion,
    tau_joints: &mut [f64],
) {
    let nv = model.nv;
    let nv0 = model.base_nv();
    let groups = &plan.groups[..];
    let ng = groups.len();
    assert!(ng <= RNEA_MAX_GROUPS, "legs within RNEA's lane workspace");
    let armature = &model.armature[..nv];
    let (v, a) = (&v[..nv], &a[..nv]);
    let tau_joints = &mut tau_joints[..nv - nv0];
    let mut fs = [Force4::default(); RNEA_MAX_GROUPS];
    let mut ss = [Motion4::default(); RNEA_MAX_GROUPS];
    // Pass 1, hips to feet: acc = acc_p + S q̈ + v × S q̇, f = I acc + v ×* I v.
    let mut a_parent = Motion4::splat(a0);
    for (g, (grp, st)) in groups.iter().zip(&plan.steps).enumerate() {
        let (s, inertia, vi) = group_kinematics(g, grp, data);
        let acc = a_parent
            .add(s.scale(gather(a, &st.idx_v)))
            .add(vi.cross(s.scale(gather(v, &st.idx_v))));
        fs[g] = inertia
            .mul_motion(acc)
            .add(vi.cross_force(inertia.mul_motion(vi)));
        ss[g] = s;
        a_parent = acc;
    }
    // Pass 2, feet to hips: each body's force with its one child's added,
    // then τ = Sᵀ f + armature · q̈.
    let mut child: Option<Force4> = None;
    for g in (0..ng).rev() {
        let idx_v = &plan.steps[g].idx_v;
        let mut f = fs[g];
        if let Some(c) = child {
            f = f.add(c);
        }
        let tau = ss[g]
            .dot(f)
            .add(gather(armature, idx_v).mul(gather(a, idx_v)));
        let taus = tau.to_array();
        for k in 0..LEGS {
            tau_joints[idx_v[k] - nv0] = taus[k];
        }
        child = Some(f);
    }
}
