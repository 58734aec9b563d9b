//! The `prescribed` controller (Study B's trot by inverse kinematics) under
//! hybrid dynamics. Study B's single-leg Lagrangian model against the
//! engine: `validation/tests/study_b_dynamics.rs`.

use quadsim_engine::aba::aba_from_kinematics;
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundMaterial, update_after_step,
};
use quadsim_engine::control::prescribed::{Prescribed, PrescribedParams, TrotTrajectory};
use quadsim_engine::integrate::{ForceModel, Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::rnea::rnea_from_kinematics;
use quadsim_engine::spatial::rpy_from_rot;
use quadsim_engine::terrain::TerrainUnion;
use quadsim_engine::{Data, robots};

/// A hybrid-dynamics run of quad12 trotting on concrete.
struct Trot {
    model: Model,
    data: Data,
    st: State,
    ws: StepWorkspace,
    ctl: Prescribed,
    terrain: TerrainUnion,
    points: Vec<ContactPoint>,
    states: Vec<ContactState>,
    t_s: f64,
}

const DT_S: f64 = 0.0005;

impl Trot {
    fn new(trot: TrotTrajectory) -> Trot {
        let desc = robots::builtin("quad12").unwrap();
        let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        let q = robots::nominal_q("quad12").unwrap();
        let mut params = PrescribedParams::defaults_for(&model, &q);
        params.trot = trot;
        let ctl = Prescribed::new(&desc, &model, params, &q).unwrap();
        let mut ws = StepWorkspace::new(&model);
        ws.imposed = Some(ctl.imposed());
        let points = ContactPoint::feet(&model, &desc);
        Trot {
            data: Data::new(&model),
            st: State {
                q,
                v: vec![0.0; model.nv],
            },
            ws,
            ctl,
            terrain: TerrainUnion::flat(0.0, GroundMaterial::preset("concrete").unwrap()),
            states: vec![ContactState::default(); points.len()],
            points,
            model,
            t_s: 0.0,
        }
    }

    /// One step; returns the start state `(q, v)`.
    fn step(&mut self) -> (Vec<f64>, Vec<f64>) {
        forward_kinematics(&self.model, &mut self.data, &self.st.q, &self.st.v);
        update_after_step(&self.points, &self.data, &self.terrain, &mut self.states);
        self.ctl.update_reference(&self.model, self.t_s);
        self.ctl.write_imposed(self.ws.imposed.as_mut().unwrap());
        let start = (self.st.q.clone(), self.st.v.clone());
        let mut f = ContactForces {
            terrain: &self.terrain,
            points: &self.points,
            states: &self.states,
        };
        let zero = vec![0.0; self.model.nv];
        step(
            &self.model,
            &mut self.data,
            &mut self.ws,
            &mut self.st,
            &zero,
            DT_S,
            Integrator::SemiImplicitEuler,
            &mut f,
        );
        self.t_s += DT_S;
        start
    }
}

/// Hybrid mode tracks the reference to integration error on the ground too
/// (contacts striking and lifting): over 3 s of trotting, every joint stays
/// within `1.2 · dt · max|q̈_r| · kd/(2 kp)` of the IK reference —
/// semi-implicit Euler's velocity runs `dt/2 · q̈` ahead of the reference,
/// and the correction's damping turns that into a lag of `dt q̈ kd/(2 kp)`.
#[test]
fn hybrid_mode_tracks_the_trajectory() {
    let mut run = Trot::new(TrotTrajectory::default());
    let mut worst: f64 = 0.0;
    let mut range: f64 = 0.0;
    let mut qdd_max: f64 = 0.0;
    for _ in 0..6000 {
        let (q, _) = run.step();
        for j in 0..12 {
            qdd_max = qdd_max.max(run.ctl.qdd_ref()[j].abs());
            worst = worst.max((q[7 + j] - run.ctl.q_ref()[j]).abs());
            range = range.max((q[7 + j] - robots::nominal_stance("quad12").unwrap()[j]).abs());
        }
    }
    let p = &run.ctl.params;
    let bound = 1.2 * DT_S * qdd_max * p.hybrid_kd_per_s / (2.0 * p.hybrid_kp_per_s2);
    eprintln!("tracking error {worst:e} rad, bound {bound:e}, max q̈_r {qdd_max:.1} rad/s²");
    assert!(range > 0.1, "the joints move: {range} rad");
    assert!(
        worst < bound,
        "tracking error {worst:e} rad, bound {bound:e}"
    );
}

/// The torques hybrid mode reports are the inverse dynamics of the motion
/// it realised: at states along a trot, with the contact forces of that
/// state, `RNEA(q, v, a, f_ext)` gives the reported joint torques (1e-9 N·m)
/// and zero base wrench (1e-9), and ABA with those torques gives back `a`.
#[test]
fn hybrid_torques_are_the_inverse_dynamics_of_the_realised_motion() {
    let mut run = Trot::new(TrotTrajectory::default());
    let mut checked = 0;
    let mut worst_tau: f64 = 0.0;
    let mut worst_base: f64 = 0.0;
    let mut worst_acc: f64 = 0.0;
    for k in 0..3000 {
        let (q, v) = run.step();
        if k % 97 != 0 {
            continue;
        }
        checked += 1;
        let a = run.ws.last_acceleration().to_vec();
        let tau_act = run.ws.imposed.as_ref().unwrap().tau_actuator_nm.clone();
        // the total generalised force: actuator + passive + contact (none on joints)
        let model = &run.model;
        let mut data = Data::new(model);
        forward_kinematics(model, &mut data, &q, &v);
        data.clear_external_forces();
        let mut tau_known = vec![0.0; model.nv];
        quadsim_engine::passive::add_passive_torques(
            model,
            &run.ws.passive,
            &q,
            &v,
            &mut tau_known,
        );
        let mut f = ContactForces {
            terrain: &run.terrain,
            points: &run.points,
            states: &run.states,
        };
        f.apply(model, &mut data, &q, &v, &mut tau_known);
        rnea_from_kinematics(model, &mut data, &v, &a, true);
        for i in 0..6 {
            worst_base = worst_base.max((data.tau[i] - tau_known[i]).abs());
        }
        let mut tau_total = tau_known.clone();
        for j in 0..12 {
            worst_tau = worst_tau.max((data.tau[6 + j] - tau_known[6 + j] - tau_act[j]).abs());
            tau_total[6 + j] += tau_act[j];
        }
        aba_from_kinematics(model, &mut data, &v, &tau_total, true);
        for i in 0..model.nv {
            worst_acc = worst_acc.max((data.ddq[i] - a[i]).abs());
        }
    }
    assert!(checked > 20);
    assert!(worst_tau < 1e-9, "joint torques vs RNEA: {worst_tau:e}");
    assert!(worst_base < 1e-9, "base wrench: {worst_base:e}");
    assert!(worst_acc < 1e-7, "ABA round trip: {worst_acc:e}");
}

/// The default trot walks: 5 s on concrete without falling, forward at
/// least half of the nominal 93 mm/s, roll and pitch within 0.2 rad.
#[test]
fn default_trot_walks_forward() {
    let trot = TrotTrajectory::default();
    let nominal = trot.nominal_speed_mps();
    let mut run = Trot::new(trot);
    let mut max_tilt: f64 = 0.0;
    let mut min_h = f64::INFINITY;
    let mut x_at_1 = 0.0;
    for k in 0..10_000 {
        let (q, _) = run.step();
        if k == 2000 {
            x_at_1 = q[0];
        }
        let rot = glam::DQuat::from_xyzw(q[3], q[4], q[5], q[6]);
        let rpy = rpy_from_rot(glam::DMat3::from_quat(rot));
        max_tilt = max_tilt.max(rpy.x.abs()).max(rpy.y.abs());
        min_h = min_h.min(q[2]);
    }
    let speed = (run.st.q[0] - x_at_1) / 4.0;
    eprintln!(
        "trot: mean speed {speed:.4} m/s (nominal {nominal:.4}), tilt {max_tilt:.3} rad, min height {min_h:.4} m, y {:.4}",
        run.st.q[1]
    );
    assert!(min_h > 0.1, "the base stays up: {min_h} m");
    assert!(max_tilt < 0.2, "roll/pitch {max_tilt} rad");
    assert!(speed > 0.5 * nominal, "mean speed {speed} m/s");
}
