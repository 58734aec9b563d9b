//! Nonlinear effects `C(q, v) v + g(q)` and the generalised gravity `g(q)`, by RNEA
//! with zero acceleration (Featherstone 2008, §5.3).

use crate::data::Data;
use crate::rnea::rnea;

/// Fills and returns `data.nle = C(q, v) v + g(q)` (nv).
pub fn nonlinear_effects<'d>(
    model: &crate::model::Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
) -> &'d [f64] {
    let mut zeros = std::mem::take(&mut data.scratch_v);
    zeros.fill(0.0);
    rnea(model, data, q, v, &zeros);
    data.nle.copy_from_slice(&data.tau);
    data.scratch_v = zeros;
    &data.nle
}

/// Fills and returns `data.gravity = g(q)` (nv): the generalised force that holds the robot still.
pub fn generalized_gravity<'d>(
    model: &crate::model::Model,
    data: &'d mut Data,
    q: &[f64],
) -> &'d [f64] {
    let mut zeros = std::mem::take(&mut data.scratch_v);
    zeros.fill(0.0);
    rnea(model, data, q, &zeros, &zeros);
    data.gravity.copy_from_slice(&data.tau);
    data.scratch_v = zeros;
    &data.gravity
}
