use glam::DVec3;
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundMaterial, update_after_step,
};
use quadsim_engine::control::force_qp::ForceQpParams;
use quadsim_engine::control::joint_pd::bandwidth_gains;
use quadsim_engine::control::vmc::{VmcCommand, VmcParams};
use quadsim_engine::control::walker::{Walker, WalkerInput, WalkerParams};
use quadsim_engine::gait::Gait;
use quadsim_engine::gait::placement::PlacementParams;
use quadsim_engine::gait::scheduler::SchedulerParams;
use quadsim_engine::gait::swing::ReachDown;
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::legs::ik::IkOptions;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::terrain::TerrainUnion;
use quadsim_engine::{Data, robots};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let vx = args.first().copied().unwrap_or(1.5);
    let bw = args.get(1).copied().unwrap_or(8.0);
    let robot = std::env::var("ROBOT").unwrap_or_else(|_| "quad16".into());
    let desc = robots::builtin(&robot).unwrap();
    let mut model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    if let Some(l) = std::env::var("ELIM")
        .ok()
        .and_then(|x| x.parse::<f64>().ok())
    {
        for e in model.effort_limit[6..].iter_mut() {
            *e = l;
        }
    }
    let mut data = Data::new(&model);
    let mut q = robots::nominal_q(&robot).unwrap();
    let (kp, kd) = bandwidth_gains(&model, &mut data, &q, bw, 1.0);
    let params = WalkerParams {
        gait: if args.get(2).copied().unwrap_or(1.0) == 0.0 {
            Gait::stand()
        } else {
            Gait::study_a_trot()
        },
        scheduler: SchedulerParams::default(),
        vmc: {
            let mut p = VmcParams::for_model(&model);
            let env = |k: &str, d: f64| {
                std::env::var(k)
                    .ok()
                    .and_then(|x| x.parse().ok())
                    .unwrap_or(d)
            };
            p.gains.stiffness_nm_per_rad *= env("KR", 1.0);
            p.gains.damping_nms_per_rad *= env("KRD", 1.0);
            p.gains.damping_nspm *= env("KD", 1.0);
            p.base_height_m = env("HT", p.base_height_m);
            p
        },
        command: VmcCommand {
            forward_mps: vx,
            lateral_mps: 0.0,
            yaw_rate_radps: 0.0,
        },
        qp: {
            let mut p = ForceQpParams::default();
            let env = |k: &str, d: f64| {
                std::env::var(k)
                    .ok()
                    .and_then(|x| x.parse().ok())
                    .unwrap_or(d)
            };
            let (wh, wm) = (env("WH", 1.0), env("WM", 10.0));
            p.wrench_weight = [wh, wh, 1.0, wm, wm, env("WY", 10.0)];
            p.min_normal_force_n = env("FMIN", p.min_normal_force_n);
            p
        },
        placement: {
            let env = |k: &str, d: f64| {
                std::env::var(k)
                    .ok()
                    .and_then(|x| x.parse().ok())
                    .unwrap_or(d)
            };
            let mut p = PlacementParams::default();
            p.gain_s = env("KG", p.gain_s);
            p.max_step_x_m = env("MSX", p.max_step_x_m);
            p
        },
        lift_height_m: args.get(3).copied().unwrap_or(0.17),
        reach: ReachDown::default(),
        swing_kp_nm_per_rad: kp,
        swing_kd_nms_per_rad: kd,
        ankle_hold: (20.0, 0.3),
        ik: IkOptions::default(),
        swing_feedforward: std::env::var("NOFF").is_err(),
        command_accel_mps2: std::env::var("CA")
            .ok()
            .and_then(|x| x.parse().ok())
            .unwrap_or(1.0),
        max_horizontal_force_ratio: std::env::var("HR")
            .ok()
            .and_then(|x| x.parse().ok())
            .unwrap_or(0.0),
        stance_needs_contact: std::env::var("SNC").is_ok(),
        swing_in_level_frame: std::env::var("NOLVL").is_err(),
        knee_guard_rad: std::env::var("KGU")
            .ok()
            .and_then(|x| x.parse().ok())
            .unwrap_or(0.5),
        velocity_filter_s: std::env::var("VF")
            .ok()
            .and_then(|x| x.parse().ok())
            .unwrap_or(0.0),
        // the legs' mounts, as before placement hips existed
        placement_hips_m: Vec::new(),
    };
    let params = if std::env::var("DEF").is_ok() {
        let mut d = WalkerParams::default_for(&desc, &model);
        d.command.forward_mps = vx;
        if args.get(2) == Some(&0.0) {
            d.gait = Gait::stand();
        }
        if let Some(l) = args.get(3) {
            d.lift_height_m = *l;
        }
        if let Some(h) = std::env::var("HT").ok().and_then(|x| x.parse().ok()) {
            d.vmc.base_height_m = h;
        }
        d
    } else {
        params
    };
    let mut walker = Walker::new(&desc, &model, params).unwrap();
    let terrain = TerrainUnion::flat(0.0, GroundMaterial::preset("concrete").unwrap());
    let points = ContactPoint::feet(&model, &desc);
    let mut states = vec![ContactState::default(); points.len()];
    q[2] += 0.0;
    let mut st = State {
        q,
        v: vec![0.0; model.nv],
    };
    let mut ws = StepWorkspace::new(&model);
    let mut tau = vec![0.0; model.nv];
    let dt = 0.0005;
    let mut tj = vec![0.0; model.nv - 6];
    let quiet = std::env::var("QUIET").is_ok();
    let (mut max_tilt, mut x3, mut zmin, mut zmax) = (0.0_f64, 0.0, f64::INFINITY, 0.0_f64);
    let mut fell = None;
    let z_start = st.q[2];
    let mut peak_swing_tau = 0.0_f64;
    let mut swing_taus: Vec<f64> = Vec::new();
    for k in 0..(10.0 / dt) as usize {
        let rpy =
            quadsim_engine::spatial::rpy_from_rot(quadsim_engine::spatial::Transform::IDENTITY.rot);
        let _ = rpy;
        {
            let qq = glam::DQuat::from_xyzw(st.q[3], st.q[4], st.q[5], st.q[6]);
            let (r, p, _) = {
                let e = quadsim_engine::spatial::rpy_from_rot(glam::DMat3::from_quat(qq));
                (e.x, e.y, e.z)
            };
            max_tilt = max_tilt.max(r.abs()).max(p.abs());
            if k == 6000 {
                x3 = st.q[0];
            }
            if k >= 6000 {
                zmin = zmin.min(st.q[2]);
                zmax = zmax.max(st.q[2]);
            }
        }
        forward_kinematics(&model, &mut data, &st.q, &st.v);
        update_after_step(&points, &data, &terrain, &mut states);
        let every: usize = std::env::var("EVERY")
            .ok()
            .and_then(|x| x.parse().ok())
            .unwrap_or(4);
        if k % every == 0 {
            let contacts: Vec<bool> = states.iter().map(|s| s.in_contact).collect();
            let normals: Vec<DVec3> = states.iter().map(|s| s.normal).collect();
            walker.tick(
                &model,
                &mut data,
                &st.q,
                &st.v,
                &WalkerInput {
                    dt_s: every as f64 * dt,
                    terrain: &terrain,
                    contacts: &contacts,
                    normals: &normals,
                },
                &mut tj,
            );
            tau[6..].copy_from_slice(&tj);
            for leg in 0..4 {
                if walker.scheduler().leg(leg).phase
                    == quadsim_engine::gait::scheduler::LegPhase::Swing
                {
                    let d = tj.len() / 4;
                    for j in leg * d..(leg + 1) * d {
                        peak_swing_tau = peak_swing_tau.max(tj[j].abs());
                        swing_taus.push(tj[j].abs());
                        if std::env::var("SAT").is_ok() && tj[j].abs() > 95.0 {
                            let l = walker.scheduler().leg(leg);
                            println!(
                                "  SAT t={:.3} leg{} joint{} tau={:.0} prog={:.2} late={:.3} q={:.2} qdes={:.2}",
                                k as f64 * dt,
                                leg,
                                j - leg * d,
                                tj[j],
                                l.swing_progress,
                                l.late_s,
                                st.q[7 + j],
                                walker.joint_targets()[j]
                            );
                        }
                    }
                }
            }
        }
        let mut f = ContactForces {
            terrain: &terrain,
            points: &points,
            states: &states,
        };
        step(
            &model,
            &mut data,
            &mut ws,
            &mut st,
            &tau,
            dt,
            Integrator::SemiImplicitEuler,
            &mut f,
        );
        if std::env::var("TD").is_ok() && k % 4 == 0 {
            let sc = walker.scheduler();
            for i in 0..4 {
                let l = sc.leg(i);
                if l.phase == quadsim_engine::gait::scheduler::LegPhase::Swing
                    && l.swing_progress > 0.97
                {
                    println!(
                        "  t={:.3} leg{} x_base={:.3} vx={:.2} prog={:.2} td_target=({:.3},{:.3}) liftoff=({:.3},{:.3})",
                        k as f64 * dt,
                        i,
                        st.q[0],
                        st.v[0],
                        l.swing_progress,
                        l.touchdown_pos_m.x,
                        l.touchdown_pos_m.y,
                        l.liftoff_pos_m.x,
                        l.liftoff_pos_m.y
                    );
                }
            }
        }
        if std::env::var("LEGS").is_ok() && (1700..1950).contains(&k) && k % 8 == 0 {
            let sc = walker.scheduler();
            let l0 = sc.leg(0);
            let l1 = sc.leg(1);
            println!(
                "  t={:.3} vx={:.2} pitch={:.3} L0 {:?} c={} prog={:.2} L1 {:?} c={} fz={:.0?} contact={:.0?}",
                k as f64 * dt,
                st.v[0],
                2.0 * st.q[4],
                l0.phase,
                states[0].in_contact,
                l0.swing_progress,
                l1.phase,
                states[1].in_contact,
                walker.foot_forces().iter().map(|f| f.z).collect::<Vec<_>>(),
                states
                    .iter()
                    .map(|s| s.in_contact as u8)
                    .collect::<Vec<_>>(),
            );
        }
        if std::env::var("FINE").is_ok() && (680..760).contains(&k) && k % 4 == 0 {
            let qd = walker.joint_targets();
            println!(
                "  t={:.3} LF q={:.3?} qdes={:.3?} tau={:.1?} roll={:.3} f={:.0?}",
                k as f64 * dt,
                &st.q[7..11],
                &qd[0..4],
                &tj[0..4],
                2.0 * st.q[3],
                walker.foot_forces().iter().map(|f| f.z).collect::<Vec<_>>()
            );
        }
        if !quiet
            && k % std::env::var("PR")
                .ok()
                .and_then(|x| x.parse().ok())
                .unwrap_or(500)
                == 0
        {
            let w = walker.wrench();
            println!(
                "t={:.2} x={:.3} z={:.3} vx={:.2} rpy=({:.3},{:.3}) stance={:?} W=({:.0},{:.0},{:.0}) tau0={:.1?}",
                k as f64 * dt,
                st.q[0],
                st.q[2],
                st.v[0],
                2.0 * st.q[3],
                2.0 * st.q[4],
                walker
                    .scheduler()
                    .stance_mask()
                    .iter()
                    .take(4)
                    .map(|&b| b as u8)
                    .collect::<Vec<_>>(),
                w.lin.x,
                w.lin.z,
                w.ang.y,
                &tj[0..4]
            );
        }
        if !st.q[2].is_finite() || st.q[2] < 0.5 * z_start {
            if !quiet {
                println!("fell at {k}");
            }
            fell = Some(k as f64 * dt);
            break;
        }
    }
    swing_taus.sort_by(|a, b| a.total_cmp(b));
    let p99 = swing_taus
        .get((swing_taus.len() as f64 * 0.99) as usize)
        .copied()
        .unwrap_or(0.0);
    let sat =
        swing_taus.iter().filter(|t| **t > 99.0).count() as f64 / swing_taus.len().max(1) as f64;
    println!("SWING_TAU p99={p99:.1} saturated_fraction={sat:.4}");
    println!(
        "SUMMARY fell={:?} mean_v={:.3} max_tilt={:.3} z_p2p={:.4} peak_swing_tau={:.1}",
        fell,
        (st.q[0] - x3) / 7.0,
        max_tilt,
        zmax - zmin,
        peak_swing_tau
    );
}
