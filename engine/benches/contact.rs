//! Criterion benchmarks of ground contact for quad16's four feet (foot
//! spheres r = 0.03 m from the built-in's collision geometry) at its nominal
//! stance, 1 cm into the ground, drifting at 0.2 m/s so damping and friction
//! are exercised. Kinematics are computed outside the timing: what is timed
//! is the contact code the integrator adds.
//!
//! - `eval`: one [`contact_forces`] call that queries the terrain (4 queries
//!   + laws + `f_ext`), as at RK4 stages 2–4;
//! - `step_euler`: what one semi-implicit Euler step costs: [`contact_forces`]
//!   at the step's start state (answered from the force [`update_after_step`]
//!   kept there) and [`update_after_step`] at the new state (4 queries);
//! - `step_rk4`: the same with three more querying evaluations.
//!
//! The two states alternate (the base moves 1 mm), so every update queries.
//! Targets: `step_euler` ≤ 0.2 µs on an analytic terrain, ≤ 1 µs on a
//! 512 × 512 height field. Run with
//! `cargo bench -p quadsim-engine --bench contact`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use quadsim_engine::contact::{
    ContactPoint, ContactState, GroundPreset, contact_forces, update_after_step,
};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::BaseKind;
use quadsim_engine::terrain::{
    Flat, HeightField, Incline, NoiseKind, Rough, Sinusoid, TerrainPatch, TerrainShape,
    TerrainUnion,
};
use quadsim_engine::{Data, Model};
use std::hint::black_box;

fn terrains() -> Vec<(&'static str, TerrainUnion)> {
    let mat = GroundPreset::Grass.material();
    let one = |shape| TerrainUnion::new().with(TerrainPatch::at_origin(shape, mat));
    let size = DVec2::splat(20.0);
    // 512 × 512 samples, 2 cm apart (10.22 m square), ±5 mm of smooth bumps
    let hf = HeightField::from_fn(512, 512, DVec2::splat(0.02), |x, y| {
        0.005 * (7.0 * x).sin() * (5.0 * y).cos()
    })
    .unwrap();
    let perlin = Rough::new(
        NoiseKind::Perlin {
            wavelength_m: 2.0,
            octaves: 4,
            persistence: 0.5,
        },
        0.005,
        1,
        size,
    )
    .unwrap();
    vec![
        ("default_ground", TerrainUnion::flat(0.0, mat)),
        ("flat", one(TerrainShape::Flat(Flat::new(size).unwrap()))),
        (
            "incline",
            one(TerrainShape::Incline(Incline::new(0.001, size).unwrap())),
        ),
        (
            "sinusoid",
            one(TerrainShape::Sinusoid(
                Sinusoid::new(0.005, 1.0, size).unwrap(),
            )),
        ),
        ("perlin4", one(TerrainShape::Rough(perlin))),
        ("heightfield512", one(TerrainShape::HeightField(hf))),
    ]
}

fn contact(c: &mut Criterion) {
    let desc = quadsim_engine::robots::builtin("quad16").expect("built-in quad16");
    let model = Model::from_description(&desc, BaseKind::Floating).expect("quad16 compiles");
    let points = ContactPoint::feet(&model, &desc);
    assert_eq!(points.len(), 4);
    let mut q = quadsim_engine::robots::nominal_q("quad16").expect("quad16 stance");
    q[2] -= 0.01;
    let mut v = vec![0.0; model.nv];
    v[0] = 0.2;
    v[2] = -0.05;
    // two successive states, 1 mm apart
    let mut data = [Data::new(&model), Data::new(&model)];
    forward_kinematics(&model, &mut data[0], &q, &v);
    q[0] += 0.001;
    forward_kinematics(&model, &mut data[1], &q, &v);
    let mut g = c.benchmark_group("contact_quad16");
    for (name, terrain) in terrains() {
        let mut states = vec![ContactState::default(); 4];
        update_after_step(&points, &data[0], &terrain, &mut states);
        assert!(
            states.iter().all(|s| s.in_contact),
            "{name}: all four feet should touch"
        );
        let cold: Vec<ContactState> = states
            .iter()
            .map(|s| ContactState {
                last_query: None,
                ..*s
            })
            .collect();
        g.bench_function(format!("{name}/eval"), |b| {
            b.iter(|| {
                contact_forces(
                    black_box(&points),
                    &model,
                    &mut data[0],
                    &terrain,
                    &cold,
                    None,
                );
                data[0].external_forces()[0].lin.z
            })
        });
        for (label, evals) in [("step_euler", 1), ("step_rk4", 4)] {
            let mut k = 0;
            g.bench_function(format!("{name}/{label}"), |b| {
                b.iter(|| {
                    let (start, end) = data.split_at_mut(1);
                    let (now, next) = if k == 0 {
                        (&mut start[0], &mut end[0])
                    } else {
                        (&mut end[0], &mut start[0])
                    };
                    for _ in 0..evals {
                        // the integrator evaluates at stage states; here all at
                        // `now`, the first from the kept force, the rest queried
                        contact_forces(black_box(&points), &model, now, &terrain, &states, None);
                        if evals > 1 {
                            for s in states.iter_mut() {
                                s.last_query = None;
                            }
                        }
                    }
                    update_after_step(&points, next, &terrain, &mut states);
                    k ^= 1;
                    states[0].normal_force_n
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, contact);
criterion_main!(benches);
