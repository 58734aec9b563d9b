//! Criterion benchmarks of the stance-force QP (`control::force_qp`) on
//! quad16-like stances (feet at the corners of a 0.6 × 0.3 m rectangle
//! 0.5 m below the CoM, μ = 0.8):
//!
//! - `four_feet`: standing, a wrench with sideways force and moments;
//! - `trot_pair`: two diagonal feet carrying a trot's wrench, with friction
//!   facets binding;
//! - `tilted`: four feet on ground tilted 0.3 rad, one unloading (λ = 0.3).
//!
//! Each case is solved by the dedicated active-set solver (`active_set`) and
//! by clarabel (`clarabel`, the reference), plus one VMC update (`vmc`). The
//! controller runs at 500 Hz against a 2 kHz physics step, so its cost per
//! robot-step is the solve cost / 4; target ≤ 1 µs amortised.
//!
//! `wbc/trot_pair`: one solve of the whole-body layer (`control::wbc`) on
//! quad16 in diagonal support (two contacts, two swing feet, four ankle
//! postures), kinematics already computed; `wbc/trot_pair/dense_reference`
//! the same solve with the dense null-space recursion it replaced
//! ([`WholeBody::solve_reference`]). Run with
//! `cargo bench -p quadsim-engine --bench control`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DMat3, DVec3};
use quadsim_engine::control::force_qp::{ForceQp, ForceQpParams, StanceFoot, solve_clarabel};
use quadsim_engine::control::vmc::{Vmc, VmcCommand, VmcInput, VmcParams};
use quadsim_engine::spatial::Force;
use std::hint::black_box;

fn feet(normal: DVec3) -> Vec<StanceFoot> {
    [(0.3, 0.15), (0.3, -0.15), (-0.3, -0.15), (-0.3, 0.15)]
        .iter()
        .map(|&(x, y)| StanceFoot {
            position_m: DVec3::new(x, y, -0.5),
            normal,
            friction: 0.8,
            load: 1.0,
        })
        .collect()
}

fn cases() -> Vec<(&'static str, Vec<StanceFoot>, Force)> {
    let mg = 28.0 * 9.81;
    let four = feet(DVec3::Z);
    let mut pair = feet(DVec3::Z);
    pair[1].load = 0.0;
    pair[3].load = 0.0;
    let tilt = 0.3f64;
    let mut tilted = feet(DVec3::new(tilt.sin(), 0.0, tilt.cos()));
    tilted[2].load = 0.3;
    vec![
        (
            "four_feet",
            four,
            Force {
                lin: DVec3::new(40.0, -10.0, mg + 30.0),
                ang: DVec3::new(3.0, -5.0, 2.0),
            },
        ),
        (
            "trot_pair",
            pair,
            Force {
                lin: DVec3::new(300.0, 20.0, mg),
                ang: DVec3::new(10.0, 8.0, -4.0),
            },
        ),
        (
            "tilted",
            tilted,
            Force {
                lin: DVec3::new(-60.0, 0.0, mg),
                ang: DVec3::new(0.0, 6.0, 0.0),
            },
        ),
    ]
}

fn bench(c: &mut Criterion) {
    let params = ForceQpParams::default();
    let mut qp = ForceQp::new(params);
    let mut group = c.benchmark_group("force_qp");
    for (name, feet, w) in cases() {
        group.bench_function(format!("{name}/active_set"), |b| {
            b.iter(|| qp.solve(black_box(&feet), black_box(&w)).unwrap())
        });
        group.bench_function(format!("{name}/clarabel"), |b| {
            b.iter(|| solve_clarabel(&params, black_box(&feet), black_box(&w)).unwrap())
        });
    }
    group.finish();
    let mut vmc = Vmc::new(VmcParams::study_a(28.0), VmcCommand::default());
    let input = VmcInput {
        base_position_m: DVec3::new(0.0, 0.0, 0.5),
        base_rotation: DMat3::from_rotation_z(0.2),
        base_linear_velocity_mps: DVec3::new(1.2, 0.0, 0.01),
        base_angular_velocity_radps: DVec3::new(0.1, -0.1, 0.05),
        com_m: DVec3::new(0.0, 0.0, 0.42),
        com_velocity_mps: DVec3::new(1.2, 0.05, 0.01),
        height_above_ground_m: 0.49,
        dt_s: 0.002,
    };
    c.bench_function("vmc/update", |b| b.iter(|| vmc.update(black_box(&input))));
    bench_wbc(c);
    bench_mpc(c);
}

/// One convex-MPC solve (ADMM, warm-started) over a trot's sequence of
/// problems 0.02 s apart, as the walker asks at 50 Hz
/// ([`quadsim_engine::control::mpc::trot_benchmark_problem_at`]).
fn bench_mpc(c: &mut Criterion) {
    use quadsim_engine::control::mpc::{Mpc, MpcParams, trot_benchmark_problem_at};
    let params = MpcParams::default();
    let problems: Vec<_> = (0..50)
        .map(|s| trot_benchmark_problem_at(&params, 0.02 * s as f64))
        .collect();
    let mut mpc = Mpc::new(params);
    let mut s = 0;
    c.bench_function("mpc/trot_horizon10", |b| {
        b.iter(|| {
            s = (s + 1) % problems.len();
            black_box(mpc.solve(black_box(&problems[s])).unwrap())
        })
    });
}

fn bench_wbc(c: &mut Criterion) {
    use quadsim_engine::control::wbc::{
        BodyTask, ContactTask, JointTask, PointTask, WbcParams, WholeBody,
    };
    use quadsim_engine::kinematics::{forward_kinematics, frame_pose};
    use quadsim_engine::legs::{FootPoint, LegKinematics};
    use quadsim_engine::model::{BaseKind, Model};
    use quadsim_engine::{Data, robots};
    let desc = robots::builtin("quad16").unwrap();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let legs = LegKinematics::for_robot(&desc, &model, FootPoint::Contact).unwrap();
    let mut data = Data::new(&model);
    let mut q = vec![0.0, 0.0, 0.55, 0.0, 0.0, 0.0, 1.0];
    q.extend_from_slice(&robots::nominal_stance("quad16").unwrap());
    let v: Vec<f64> = (0..model.nv)
        .map(|i| 0.1 * ((i as f64) * 0.7).sin())
        .collect();
    forward_kinematics(&model, &mut data, &q, &v);
    let mut contacts = Vec::new();
    let mut points = Vec::new();
    let mut joints = Vec::new();
    for (i, leg) in legs.iter().enumerate() {
        let frame = leg.foot_frame();
        let local = FootPoint::Contact.in_foot(&desc, &model.frames[frame].name);
        let p = frame_pose(&model, &data, frame).transform_point(local);
        let body = model.frames[frame].body;
        if i % 2 == 0 {
            contacts.push(ContactTask {
                body,
                point_m: p,
                normal: DVec3::Z,
                friction: 0.8,
                load: 1.0,
                force_plan_n: DVec3::new(10.0, 0.0, 137.0),
            });
        } else {
            points.push(PointTask {
                body,
                point_m: p,
                acc_mps2: DVec3::new(20.0, 0.0, 5.0),
            });
        }
        joints.push(JointTask {
            v_index: leg.v_indices()[3],
            acc_radps2: 1.0,
        });
    }
    let body = BodyTask {
        force_n: DVec3::new(30.0, 0.0, 280.0),
        torque_nm: DVec3::new(0.0, 2.0, 0.0),
    };
    let mut wbc = WholeBody::new(&model, WbcParams::default());
    let mut tau = vec![0.0; model.nv - 6];
    let mut group = c.benchmark_group("wbc");
    group.bench_function("trot_pair", |b| {
        b.iter(|| {
            wbc.solve(
                &model,
                &mut data,
                black_box(&v),
                &contacts,
                &body,
                &points,
                &joints,
                &mut tau,
            )
            .unwrap();
            black_box(&tau);
        })
    });
    group.bench_function("trot_pair/dense_reference", |b| {
        b.iter(|| {
            wbc.solve_reference(
                &model,
                &mut data,
                black_box(&v),
                &contacts,
                &body,
                &points,
                &joints,
                &mut tau,
            )
            .unwrap();
            black_box(&tau);
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
