//! Composite-rigid-body algorithm: the joint-space mass matrix `M(q)`
//! (Featherstone 2008, §6.2, Table 6.2, in the fixed frame, where composite
//! inertias add without transforms).

use crate::data::Data;
use crate::kinematics::forward_kinematics_pos;
use crate::model::{JointType, Model, NO_PARENT};
use crate::workspace::BodyScratch;

pub use crate::workspace::MassMatrix;

/// The mass matrix at `q` (see [`MassMatrix`]).
pub fn crba(model: &Model, data: &mut Data, q: &[f64]) -> MassMatrix {
    forward_kinematics_pos(model, data, q);
    crba_from_kinematics(model, data)
}

/// CRBA after [`forward_kinematics_pos`] on the same `q`.
pub fn crba_from_kinematics(model: &Model, data: &mut Data) -> MassMatrix {
    let nv = model.nv;
    // entries of bodies on different branches stay zero
    let mut out = MassMatrix::zeros(nv * nv);
    // composite inertias, in this thread's workspace
    let mut w = BodyScratch::take(model.nbodies);
    let ia = &mut w.ia;
    for i in 0..model.nbodies {
        ia[i] = data.body_inertia(model, i).to_sym6();
    }
    for i in (1..model.nbodies).rev() {
        let ic = ia[i];
        ia[model.parent[i]] += ic;
    }
    let mm = &mut out.0;
    for i in (1..model.nbodies).rev() {
        let iv = model.idx_v[i];
        let si = data.subspace(model, i);
        let f = ia[i].mul_motion(si);
        mm[iv * nv + iv] = si.dot(f) + model.armature[iv];
        let mut j = model.parent[i];
        while j != NO_PARENT {
            match model.joint_type[j] {
                JointType::Free => {
                    for k in 0..6 {
                        let x = data.base_subspace(k).dot(f);
                        mm[iv * nv + k] = x;
                        mm[k * nv + iv] = x;
                    }
                }
                JointType::Anchored => {}
                _ => {
                    let jv = model.idx_v[j];
                    let x = data.subspace(model, j).dot(f);
                    mm[iv * nv + jv] = x;
                    mm[jv * nv + iv] = x;
                }
            }
            j = model.parent[j];
        }
    }
    if model.joint_type[0] == JointType::Free {
        for k in 0..6 {
            let f = ia[0].mul_motion(data.base_subspace(k));
            for l in k..6 {
                let x = data.base_subspace(l).dot(f);
                mm[l * nv + k] = x;
                mm[k * nv + l] = x;
            }
        }
    }
    w.give_back();
    out
}
