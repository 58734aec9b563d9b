//! Validation against the source studies, outside the engine's core: the
//! studies' own models, in their own symbols, that the simulation is
//! compared with. The engine never imports this crate
//! (`engine/tests/import_graph.rs` checks it); the app and the components
//! do, to report the comparisons.
//!
//! - [`study_b`]: Study B's leg kinematics as printed, and the corrected
//!   closed-form inverse (`docs/study_b_kinematics.md`).
//! - [`study_b_dynamics`]: Study B's fixed-base Lagrangian leg model and its
//!   Table 4 torque comparison against a prescribed run
//!   (`docs/study_b_trot.md`).
//!
//! The tests beside this crate (`validation/tests/`) check both against the
//! engine: the printed formulas against quad12's leg, the Lagrangian model
//! against RNEA and the hybrid dynamics.

pub mod study_b;
pub mod study_b_dynamics;
