//! Identities that hold for any model (Pinocchio's test habit): ABA inverts RNEA,
//! CRBA's columns are RNEA differences, M is symmetric positive definite, and
//! repeated calls are bit-identical. Run on seeded random trees; the built-in
//! robots are covered in `robots_identities.rs`.

mod common;

use quadsim_engine::aba::aba;
use quadsim_engine::crba::crba;
use quadsim_engine::linalg::cholesky_dense;
use quadsim_engine::model::BaseKind;
use quadsim_engine::nle::{generalized_gravity, nonlinear_effects};
use quadsim_engine::rnea::rnea;
use quadsim_engine::{Data, Model};

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn check_identities(model: &Model, seed: u64) {
    let mut data = Data::new(model);
    let (q, v) = common::random_state(model, seed, 2.0, 1.0);
    let a = common::random_vec(seed + 1000, model.nv, 3.0);
    let nv = model.nv;

    // ABA(RNEA(a)) = a
    let tau = rnea(model, &mut data, &q, &v, &a).to_vec();
    let a2 = aba(model, &mut data, &q, &v, &tau).to_vec();
    let scale = a.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    assert!(
        max_abs_diff(&a, &a2) <= 1e-9 * scale,
        "ABA(RNEA(a)) != a: {:?} vs {:?}",
        a,
        a2
    );

    // M columns = RNEA(q, 0, e_i) - RNEA(q, 0, 0)
    let m = crba(model, &mut data, &q).to_vec();
    let zero = vec![0.0; nv];
    let g = rnea(model, &mut data, &q, &zero, &zero).to_vec();
    for i in 0..nv {
        let mut e = vec![0.0; nv];
        e[i] = 1.0;
        let col = rnea(model, &mut data, &q, &zero, &e).to_vec();
        for r in 0..nv {
            let d = col[r] - g[r];
            assert!(
                (d - m[r * nv + i]).abs() <= 1e-10 * (1.0 + d.abs()),
                "M[{r}][{i}] = {} vs {d}",
                m[r * nv + i]
            );
        }
    }
    // symmetric and positive definite
    for r in 0..nv {
        for c in 0..nv {
            assert_eq!(m[r * nv + c], m[c * nv + r], "M not symmetric at {r},{c}");
        }
    }
    let mut l = m.clone();
    assert!(cholesky_dense(&mut l, nv), "M is not positive definite");

    // RNEA(a) = M a + nle ; gravity = RNEA(q, 0, 0)
    let nle = nonlinear_effects(model, &mut data, &q, &v).to_vec();
    for r in 0..nv {
        let ma: f64 = (0..nv).map(|c| m[r * nv + c] * a[c]).sum();
        assert!(
            (ma + nle[r] - tau[r]).abs() <= 1e-9 * (1.0 + tau[r].abs()),
            "M a + nle != rnea at {r}"
        );
    }
    let grav = generalized_gravity(model, &mut data, &q).to_vec();
    assert_eq!(grav, g);

    // Repeated calls are bit-identical, also through a fresh workspace.
    let mut data2 = Data::new(model);
    let a3 = aba(model, &mut data2, &q, &v, &tau).to_vec();
    assert_eq!(a2, a3);
    let a4 = aba(model, &mut data2, &q, &v, &tau).to_vec();
    assert_eq!(a3, a4);
}

#[test]
fn identities_on_random_floating_trees() {
    for seed in 0..20 {
        let d = common::random_tree(seed, 3 + (seed as usize % 12));
        check_identities(&common::model(&d, BaseKind::Floating), seed);
    }
}

#[test]
fn identities_on_random_fixed_trees() {
    for seed in 100..120 {
        let d = common::random_tree(seed, 2 + (seed as usize % 10));
        check_identities(&common::model(&d, BaseKind::Fixed), seed);
    }
}
