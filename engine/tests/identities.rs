//! Identities that hold for any model (Pinocchio's test habit): ABA inverts RNEA,
//! CRBA's columns are RNEA differences, M is symmetric positive definite, and
//! repeated calls are bit-identical. Run on seeded random trees; the built-in
//! robots are covered in `robots_identities.rs`.

mod common;

use quadsim_engine::model::BaseKind;

#[test]
fn identities_on_random_floating_trees() {
    for seed in 0..20 {
        let d = common::random_tree(seed, 3 + (seed as usize % 12));
        common::check_identities(&common::model(&d, BaseKind::Floating), seed);
    }
}

#[test]
fn identities_on_random_fixed_trees() {
    for seed in 100..120 {
        let d = common::random_tree(seed, 2 + (seed as usize % 10));
        common::check_identities(&common::model(&d, BaseKind::Fixed), seed);
    }
}
