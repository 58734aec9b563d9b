//! quadsim's physics and control core: reduced-coordinate rigid-body dynamics in
//! f64 on plain data, with no ECS in it.
//!
//! The immutable [`model::Model`] (topology, placements, inertias, joint axes and
//! limits) lives beside the preallocated [`data::Data`] workspace, as Pinocchio's
//! `Model`/`Data` do. Each algorithm has its own file and fills named fields of
//! `Data`:
//!
//! | algorithm | file | fills |
//! |---|---|---|
//! | forward kinematics | [`kinematics`] | `pose`, `vel`, `s`, `inertia_ref` |
//! | RNEA (inverse dynamics) | [`rnea`] | `tau` |
//! | CRBA (mass matrix) | [`crba`] | returns it ([`crba::MassMatrix`]) |
//! | nonlinear effects, gravity | [`nle`] | `nle`, `gravity` |
//! | ABA (forward dynamics) | [`aba`] | `ddq` |
//! | kinematics + ABA for 4 robots of one model in SIMD lanes | [`batch`] | `BatchData::ddq` |
//! | kinematics, ABA and RNEA of one robot with its 4 legs in AVX lanes (same bits), for the model's [`plan::Plan::LegsX4`] | [`kernels::legs_x4`] | the same fields |
//! | one entry point per algorithm, matching on the model's plan | [`dispatch`] | the same fields |
//! | point Jacobians | [`jacobian`] | `jacobian` |
//! | CoM, momentum | [`com`] | (returns) |
//! | energies | [`energy`] | (returns) |
//! | sine and cosine of joint angles, one value or four in SIMD lanes (libm's bits) | [`trig`] | (returns) |

pub mod aba;
pub mod actuator_model;
pub mod actuators;
pub mod batch;
pub mod com;
pub mod contact;
pub mod control;
pub mod crba;
pub mod data;
pub mod description;
pub mod dispatch;
pub mod divergence;
pub mod energy;
pub mod estimation;
pub mod gait;
pub mod integrate;
pub mod jacobian;
pub mod kernels;
pub mod kinematics;
pub mod legs;
pub mod linalg;
pub mod material;
pub mod metrics;
pub mod model;
pub mod nle;
pub mod passive;
pub mod payload;
pub mod plan;
pub mod rnea;
pub mod robots;
pub mod rounding;
pub mod sensors;
pub mod spatial;
pub mod support;
pub mod terrain;
pub mod trig;
pub mod workspace;

pub use data::{Data, SpareData};
pub use model::{BaseKind, Model, ModelError};
