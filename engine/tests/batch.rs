//! The batched dynamics ([`quadsim_engine::batch`]) against the scalar path:
//! for quad16, quad12 and random trees (non-aligned revolute axes, prismatic
//! and fixed joints, floating and fixed bases), every active lane's `ddq`
//! and body accelerations equal the scalar ABA's **bit for bit**, with and
//! without external forces, in full and partly filled batches, through the
//! runtime-dispatched (AVX2 on this machine) and the generic versions; and a
//! batched call allocates nothing.

mod common;

use glam::DVec3;
use quadsim_engine::aba::{aba, aba_from_kinematics};
use quadsim_engine::batch::{
    BatchData, StepParts, aba_batch, aba_batch_generic, forward_kinematics_batch,
    step_semi_implicit_batch,
};
use quadsim_engine::integrate::{ForceModel, Integrator, State, StepWorkspace, step};
use quadsim_engine::jacobian::add_point_force_jt;
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::BaseKind;
use quadsim_engine::spatial::Force;
use quadsim_engine::{Data, Model};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations_in;

fn builtin(name: &str) -> Model {
    let d = quadsim_engine::robots::builtin(name).expect("built-in robot");
    common::model(&d, BaseKind::Floating)
}

/// One robot's inputs: a random state (any base orientation, joints in
/// ±3 rad, |q̇| ≤ 3 rad/s), torques ≤ 20 N·m and external forces ≤ 80 N,
/// 10 N·m on every body (as contacts would set after kinematics).
struct Robot {
    q: Vec<f64>,
    v: Vec<f64>,
    tau: Vec<f64>,
    f_ext: Vec<Force>,
}

fn robot(model: &Model, seed: u64) -> Robot {
    let (q, v) = common::random_state(model, seed, 3.0, 1.5);
    let tau = common::random_vec(seed + 7000, model.nv, 20.0);
    let f = common::random_vec(seed + 9000, 6 * model.nbodies, 1.0);
    let f_ext = (0..model.nbodies)
        .map(|b| {
            let c = &f[6 * b..6 * b + 6];
            Force::new(
                DVec3::new(c[0], c[1], c[2]) * 80.0,
                DVec3::new(c[3], c[4], c[5]) * 10.0,
            )
        })
        .collect();
    Robot { q, v, tau, f_ext }
}

/// The scalar ABA for one robot: `(ddq, body accelerations as arrays)`.
fn scalar(model: &Model, r: &Robot, external: bool) -> (Vec<f64>, Vec<[f64; 6]>) {
    let mut data = Data::new(model);
    if external {
        forward_kinematics(model, &mut data, &r.q, &r.v);
        data.external_forces_mut().copy_from_slice(&r.f_ext);
        aba_from_kinematics(model, &mut data, &r.v, &r.tau, true);
    } else {
        aba(model, &mut data, &r.q, &r.v, &r.tau);
    }
    let acc = data.acc.iter().map(|a| a.to_array()).collect();
    (data.ddq.clone(), acc)
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|e| e.to_bits()).collect()
}

/// Fills all `L` lanes (so that the unused ones hold other valid robots),
/// activates `active` of them with fresh robots, runs both versions of the
/// batched ABA and compares every active lane with the scalar path.
fn check_lanes<const L: usize>(model: &Model, active: usize, external: bool, seed: u64) {
    let mut bd = BatchData::<L>::new(model);
    for k in 0..L {
        let r = robot(model, seed + 100 + k as u64);
        bd.set_robot(k, &r.q, &r.v, &r.tau);
        bd.set_external_forces(k, &r.f_ext);
    }
    let robots: Vec<Robot> = (0..active).map(|k| robot(model, seed + k as u64)).collect();
    for (k, r) in robots.iter().enumerate() {
        bd.set_robot(k, &r.q, &r.v, &r.tau);
        bd.set_external_forces(k, &r.f_ext);
    }
    bd.set_active(active);
    let mut generic = bd.clone();
    aba_batch(model, &mut bd, external);
    aba_batch_generic(model, &mut generic, external);
    let mut ddq = vec![0.0; model.nv];
    for (k, r) in robots.iter().enumerate() {
        let (want, want_acc) = scalar(model, r, external);
        assert!(want.iter().all(|x| x.is_finite()), "scalar ddq not finite");
        for (name, b) in [("dispatched", &bd), ("generic", &generic)] {
            b.ddq_of(k, &mut ddq);
            assert_eq!(
                bits(&ddq),
                bits(&want),
                "{} {name} L={L} lane {k}/{active} external={external}: ddq {ddq:?} vs {want:?}",
                model.name
            );
            for (i, a) in want_acc.iter().enumerate() {
                assert_eq!(
                    bits(&b.acc[i].lane(k).to_array()),
                    bits(a),
                    "{} {name} lane {k}: acceleration of body {i}",
                    model.name
                );
            }
        }
    }
}

#[test]
fn batch_aba_equals_scalar_bit_for_bit_on_quad16() {
    let m = builtin("quad16");
    for seed in [1, 20, 300] {
        check_lanes::<4>(&m, 4, false, seed);
        check_lanes::<4>(&m, 4, true, seed);
    }
}

#[test]
fn batch_aba_equals_scalar_bit_for_bit_on_quad12() {
    let m = builtin("quad12");
    for seed in [2, 30, 400] {
        check_lanes::<4>(&m, 4, false, seed);
        check_lanes::<4>(&m, 4, true, seed);
    }
}

#[test]
fn batch_partly_filled_batches_of_one_to_three_robots() {
    for m in [builtin("quad16"), builtin("quad12")] {
        for active in 1..=3 {
            check_lanes::<4>(&m, active, false, 50 + active as u64);
            check_lanes::<4>(&m, active, true, 60 + active as u64);
        }
    }
}

#[test]
fn batch_random_trees_with_oblique_axes_and_prismatic_joints() {
    // random_tree draws oblique axes, rotated placements and ~10 % prismatic
    // joints: the general joint path, not only the axis-aligned fast path.
    for seed in [5, 6, 7] {
        let d = common::random_tree(seed, 12);
        for base in [BaseKind::Floating, BaseKind::Fixed] {
            let m = common::model(&d, base);
            check_lanes::<4>(&m, 4, true, seed * 10);
            check_lanes::<4>(&m, 3, false, seed * 10 + 1);
        }
    }
}

#[test]
fn batch_of_eight_lanes_and_of_one_lane() {
    let m = builtin("quad16");
    check_lanes::<8>(&m, 8, true, 70);
    check_lanes::<8>(&m, 5, false, 71);
    check_lanes::<1>(&m, 1, true, 72);
}

#[test]
fn batch_kinematics_equals_scalar_poses_and_velocities() {
    let m = builtin("quad12");
    let mut bd = BatchData::<4>::new(&m);
    let robots: Vec<Robot> = (0..4).map(|k| robot(&m, 80 + k)).collect();
    for (k, r) in robots.iter().enumerate() {
        bd.set_robot(k, &r.q, &r.v, &r.tau);
    }
    forward_kinematics_batch(&m, &mut bd);
    for (k, r) in robots.iter().enumerate() {
        let mut data = Data::new(&m);
        forward_kinematics(&m, &mut data, &r.q, &r.v);
        assert_eq!(bd.origin.lane(k), data.origin);
        for i in 0..m.nbodies {
            assert_eq!(bd.pose[i].lane(k), data.pose[i], "pose of body {i}");
            assert_eq!(bd.vel[i].lane(k), data.vel[i], "velocity of body {i}");
            assert_eq!(
                bd.s[i].lane(k),
                data.subspace(&m, i),
                "subspace of body {i}"
            );
        }
    }
}

#[test]
fn batch_degenerate_lane_leaves_the_other_lanes_alone() {
    // A zero base quaternion (a zero rotation matrix) in lane 2: that lane
    // gives whatever the scalar path gives for it (NaN-aware), and the other
    // lanes are exactly their own robots' results.
    let m = builtin("quad16");
    let mut bd = BatchData::<4>::new(&m);
    let good = robot(&m, 90);
    for k in 0..4 {
        bd.set_robot(k, &good.q, &good.v, &good.tau);
    }
    let mut bad = robot(&m, 90);
    bad.q[3..7].fill(0.0);
    bd.set_robot(2, &bad.q, &bad.v, &bad.tau);
    aba_batch(&m, &mut bd, false);
    let mut ddq = vec![0.0; m.nv];
    bd.ddq_of(2, &mut ddq);
    let (want_bad, _) = scalar(&m, &bad, false);
    for (x, y) in ddq.iter().zip(&want_bad) {
        assert!(
            x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
            "{x} vs {y}"
        );
    }
    let (want, _) = scalar(&m, &good, false);
    for k in [0, 1, 3] {
        bd.ddq_of(k, &mut ddq);
        assert_eq!(bits(&ddq), bits(&want), "lane {k}");
    }
}

#[test]
fn batch_call_allocates_nothing() {
    let m = builtin("quad16");
    let mut bd = BatchData::<4>::new(&m);
    let r = robot(&m, 95);
    let mut ddq = vec![0.0; m.nv];
    let mut sink = 0.0;
    let n = allocations_in(|| {
        for k in 0..4 {
            bd.set_robot(k, &r.q, &r.v, &r.tau);
            bd.set_external_forces(k, &r.f_ext);
        }
        bd.set_active(3);
        for external in [false, true] {
            aba_batch(&m, &mut bd, external);
            aba_batch_generic(&m, &mut bd, external);
            forward_kinematics_batch(&m, &mut bd);
        }
        bd.ddq_of(1, &mut ddq);
        sink += ddq[0];
    });
    assert!(sink.is_finite());
    assert_eq!(n, 0, "{n} allocations in batched calls");
}

/// A penalty ground under every body origin (through `data.f_ext`) and a
/// joint-space push on the last body (through `Jᵀ f` into `tau`, which reads
/// the motion subspaces): a state-dependent force model like contact.
#[derive(Clone)]
struct Ground {
    contacts: usize,
}

impl ForceModel for Ground {
    fn apply(&mut self, model: &Model, data: &mut Data, _q: &[f64], _v: &[f64], tau: &mut [f64]) {
        for b in 0..model.nbodies {
            let p = data.body_point_world(b, DVec3::ZERO);
            if p.z < 0.0 {
                let vel = data.body_point_velocity(b, DVec3::ZERO);
                let fz = (1e4 * -p.z - 100.0 * vel.z).max(0.0);
                data.add_point_force(b, p, DVec3::new(-0.1 * vel.x, -0.1 * vel.y, fz));
                self.contacts += 1;
            }
        }
        let last = model.nbodies - 1;
        let p = data.body_point_world(last, DVec3::ZERO);
        add_point_force_jt(model, data, last, p, DVec3::new(1.0, -2.0, 0.5), tau);
    }
}

struct Sim {
    data: Data,
    ws: StepWorkspace,
    state: State,
    tau: Vec<f64>,
    ground: Ground,
}

fn parts(s: &mut Sim) -> StepParts<'_, Ground> {
    StepParts {
        data: &mut s.data,
        ws: &mut s.ws,
        state: &mut s.state,
        tau_actuator: &s.tau,
        forces: &mut s.ground,
    }
}

fn sims(model: &Model, n: usize, seed: u64) -> Vec<Sim> {
    (0..n)
        .map(|k| {
            let r = robot(model, seed + k as u64);
            let mut state = State { q: r.q, v: r.v };
            state.q[2] = 0.05; // low, so that the ground acts
            Sim {
                data: Data::new(model),
                ws: StepWorkspace::new(model),
                state,
                tau: r.tau,
                ground: Ground { contacts: 0 },
            }
        })
        .collect()
}

#[test]
fn batch_step_equals_scalar_step_bit_for_bit() {
    for m in [builtin("quad16"), builtin("quad12")] {
        for n in [4, 3, 1] {
            let mut scalar_sims = sims(&m, n, 500);
            let mut batch_sims = sims(&m, n, 500);
            let mut bd = BatchData::<4>::new(&m);
            for _ in 0..40 {
                for s in &mut scalar_sims {
                    step(
                        &m,
                        &mut s.data,
                        &mut s.ws,
                        &mut s.state,
                        &s.tau,
                        5e-4,
                        Integrator::SemiImplicitEuler,
                        &mut s.ground,
                    );
                }
                step_semi_implicit_batch(&m, &mut bd, &mut batch_sims, parts, 5e-4);
            }
            for (k, (a, b)) in scalar_sims.iter().zip(&batch_sims).enumerate() {
                assert!(a.ground.contacts > 0, "the ground never acted");
                assert_eq!(a.ground.contacts, b.ground.contacts);
                assert_eq!(
                    bits(&a.state.q),
                    bits(&b.state.q),
                    "{} robot {k}/{n}: q",
                    m.name
                );
                assert_eq!(
                    bits(&a.state.v),
                    bits(&b.state.v),
                    "{} robot {k}/{n}: v",
                    m.name
                );
                assert_eq!(
                    bits(a.ws.last_acceleration()),
                    bits(b.ws.last_acceleration())
                );
                assert_eq!(bits(a.ws.last_tau()), bits(b.ws.last_tau()));
            }
        }
    }
}

#[test]
fn batch_step_allocates_nothing() {
    let m = builtin("quad16");
    let mut batch_sims = sims(&m, 4, 600);
    let mut bd = BatchData::<4>::new(&m);
    step_semi_implicit_batch(&m, &mut bd, &mut batch_sims, parts, 5e-4);
    let n = allocations_in(|| {
        for _ in 0..5 {
            step_semi_implicit_batch(&m, &mut bd, &mut batch_sims, parts, 5e-4);
            step_semi_implicit_batch(&m, &mut bd, &mut batch_sims[..2], parts, 5e-4);
        }
    });
    assert!(
        batch_sims
            .iter()
            .all(|s| s.state.q.iter().all(|x| x.is_finite()))
    );
    assert_eq!(n, 0, "{n} allocations in batched steps");
}
