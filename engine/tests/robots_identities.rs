//! The model-independent identities of `identities.rs` on the real robots:
//! ABA inverts RNEA, CRBA's columns are RNEA differences, M is symmetric
//! positive definite, RNEA = M a + nle, and repeated calls are bit-identical.
//! Run on both built-ins (defaults and a reshaped variant), floating and fixed
//! base, at seeded random states.

mod common;

use quadsim_engine::aba::aba;
use quadsim_engine::crba::crba;
use quadsim_engine::linalg::cholesky_dense;
use quadsim_engine::model::BaseKind;
use quadsim_engine::nle::{generalized_gravity, nonlinear_effects};
use quadsim_engine::rnea::rnea;
use quadsim_engine::robots::{builtin, builtin_with};
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
    let name = &model.name;

    // ABA(RNEA(a)) = a
    let tau = rnea(model, &mut data, &q, &v, &a).to_vec();
    let a2 = aba(model, &mut data, &q, &v, &tau).to_vec();
    let scale = a.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let err = max_abs_diff(&a, &a2);
    assert!(
        err <= 1e-9 * scale,
        "{name} seed {seed}: ABA(RNEA(a)) off by {err}"
    );

    // M columns = RNEA(q, 0, e_i) − RNEA(q, 0, 0)
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
                "{name} seed {seed}: M[{r}][{i}] = {} vs {d}",
                m[r * nv + i]
            );
        }
    }
    // symmetric and positive definite
    for r in 0..nv {
        for c in 0..nv {
            assert_eq!(
                m[r * nv + c],
                m[c * nv + r],
                "{name}: M not symmetric at {r},{c}"
            );
        }
    }
    let mut l = m.clone();
    assert!(
        cholesky_dense(&mut l, nv),
        "{name}: M is not positive definite"
    );

    // RNEA(a) = M a + nle; gravity = RNEA(q, 0, 0)
    let nle = nonlinear_effects(model, &mut data, &q, &v).to_vec();
    for r in 0..nv {
        let ma: f64 = (0..nv).map(|c| m[r * nv + c] * a[c]).sum();
        assert!(
            (ma + nle[r] - tau[r]).abs() <= 1e-9 * (1.0 + tau[r].abs()),
            "{name} seed {seed}: M a + nle != rnea at {r}"
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
    let m2 = crba(model, &mut data2, &q).to_vec();
    assert_eq!(m, m2);
}

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
            check_identities(&model, 500 + 20 * k as u64 + seed);
        }
    }
}

#[test]
fn identities_on_builtins_fixed_base() {
    for (k, d) in robots().iter().enumerate() {
        let model = common::model(d, BaseKind::Fixed);
        for seed in 0..10 {
            check_identities(&model, 700 + 20 * k as u64 + seed);
        }
    }
}
