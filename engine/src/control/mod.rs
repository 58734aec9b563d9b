//! Controllers as pure functions on plain data. Sign convention for every
//! controller here: a positive joint torque τ accelerates the joint positively
//! about its axis (the same τ that enters `M q̈ + C q̇ + g = τ + Jᵀ f_ext`).

pub mod active_set;
pub mod admm;
pub mod force_qp;
pub mod ground_plane;
pub mod joint_pd;
pub mod mpc;
pub mod prescribed;
pub mod profile;
mod task_space;
pub mod vmc;
pub mod walker;
pub mod wbc;
