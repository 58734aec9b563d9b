//! Point Jacobians: the map from generalised velocity to the world velocity of a
//! point fixed on a body (Featherstone 2008, §8.1; Pinocchio `getFrameJacobian`,
//! `LOCAL_WORLD_ALIGNED`, linear rows).

use crate::data::Data;
use crate::model::{JointType, Model, NO_PARENT};
use glam::DVec3;

/// Fills `data.jacobian` (3 × nv, row-major, world axes) with `J` such that
/// `ṗ = J v` for the point `point_m` (world coordinates) fixed on `body`.
/// Needs [`crate::kinematics::forward_kinematics_pos`] (or the full one) first.
/// Columns of joints that do not support `body` are zero.
pub fn point_jacobian<'d>(
    model: &Model,
    data: &'d mut Data,
    body: usize,
    point_m: DVec3,
) -> &'d [f64] {
    let nv = model.nv;
    data.jacobian.fill(0.0);
    let r = point_m - data.origin;
    let mut j = body;
    while j != NO_PARENT {
        match model.joint_type[j] {
            JointType::Free => {
                for k in 0..6 {
                    let c = data.base_subspace(k).point_velocity(r);
                    set_col(&mut data.jacobian, nv, k, c);
                }
            }
            JointType::Anchored => {}
            _ => {
                let c = data.subspace(model, j).point_velocity(r);
                set_col(&mut data.jacobian, nv, model.idx_v[j], c);
            }
        }
        j = model.parent[j];
    }
    &data.jacobian
}

#[inline]
fn set_col(jac: &mut [f64], nv: usize, col: usize, c: DVec3) {
    jac[col] = c.x;
    jac[nv + col] = c.y;
    jac[2 * nv + col] = c.z;
}

/// Adds `Jᵀ f` for the point force `force_n` (N, world) at `point_m` on `body` into `tau` (nv),
/// without forming J. This is the generalised force the point force produces.
pub fn add_point_force_jt(
    model: &Model,
    data: &Data,
    body: usize,
    point_m: DVec3,
    force_n: DVec3,
    tau: &mut [f64],
) {
    let r = point_m - data.origin;
    let mut j = body;
    while j != NO_PARENT {
        match model.joint_type[j] {
            JointType::Free => {
                for k in 0..6 {
                    tau[k] += data.base_subspace(k).point_velocity(r).dot(force_n);
                }
            }
            JointType::Anchored => {}
            _ => tau[model.idx_v[j]] += data.subspace(model, j).point_velocity(r).dot(force_n),
        }
        j = model.parent[j];
    }
}
