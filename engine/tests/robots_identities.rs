//! The model-independent identities of `identities.rs` on the real robots:
//! ABA inverts RNEA, CRBA's columns are RNEA differences, M is symmetric
//! positive definite, RNEA = M a + nle, and repeated calls are bit-identical.
//! Run on both built-ins (defaults and a reshaped variant), floating and fixed
//! base, at seeded random states.

mod common;

use quadsim_engine::model::BaseKind;
use quadsim_engine::robots::{builtin, builtin_with};

fn robots() -> Vec<quadsim_engine::description::RobotDescription> {
    vec![
        builtin("quad16").unwrap(),
        builtin("quad12").unwrap(),
        // reshaped variants: the identities hold for any parameters
        builtin_with(
            "quad16",
            &[
                ("thigh.length_m", 0.42),
                ("foot.radius_m", 0.05),
                ("mount.z_m", -0.03),
            ],
        )
        .unwrap(),
        builtin_with(
            "quad12",
            &[
                ("shank.length_m", 0.12),
                ("hip.mass_kg", 0.2),
                ("leg.front_yaw_rad", 0.3),
            ],
        )
        .unwrap(),
    ]
}

#[test]
fn identities_on_builtins_floating_base() {
    for (k, d) in robots().iter().enumerate() {
        let model = common::model(d, BaseKind::Floating);
        for seed in 0..10 {
            common::check_identities(&model, 500 + 20 * k as u64 + seed);
        }
    }
}

#[test]
fn identities_on_builtins_fixed_base() {
    for (k, d) in robots().iter().enumerate() {
        let model = common::model(d, BaseKind::Fixed);
        for seed in 0..10 {
            common::check_identities(&model, 700 + 20 * k as u64 + seed);
        }
    }
}
