//! A probe of the walking controller: quad16 (or `ROBOT`) on flat concrete
//! under `WalkerParams::default_for`, with overrides from the environment,
//! printing a timeline and the run's figures. For tuning and diagnosis only.
//!
//! `cargo run --release -p quadsim-engine --example walk_probe -- [v_mps] [seconds]`
//! Overrides: ELIM (effort limit, N·m), LIFT (m), HT (height target, m),
//! KG (Raibert gain, s), CLIP (VMC position-error clip, m), MSX (max step x, m), VF (velocity filter, s),
//! CA (command accel, m/s²), HR (max horizontal force ratio), SNC (stance
//! needs contact), KGU (knee guard, rad), ETD (early-touchdown minimum swing
//! progress), BW (swing bandwidth, Hz), KX/KXD (scale of the x
//! stiffness/damping), KR/KRD (rotational), PERIOD and FOUR (a trot's period
//! and four-leg support, s), EVERY (steps per tick), PRINT (timeline
//! interval, s; 0: none), LEGMASS (scale of quad16's thigh, shank and foot
//! masses), GAIT (trot, walk, pace, bound, pronk, stand), PERT and SEED
//! (joint angles at the start moved by up to PERT rad, pseudo-randomly by
//! SEED), PERTX (the start moved along x by SEED × PERTX m), STEPUP (a 5 cm
//! platform from that x, m), SINE (trot_sine's waves from that x, m).
//!
//! MOTOR: the robot's default DC motors (as the pipeline's default
//! actuators; the walker's defaults come from the model without their
//! reflected inertia, as in the pipeline) instead of ideal torque sources.
//! On the motors a joint offset (PERT) of 1e-6 rad is damped out while the
//! robot settles (their Coulomb friction): neighbours so made fall at the
//! same instant; PERTX (a start moved by micrometres, whose rounding never
//! decays) gives independent samples, as `start_xy_m` does in the pipeline.
//!
//! Diagnostics: TD (a line per touchdown: leg, swing progress), SWINGDIAG
//! (mean swing-foot error against its reference per quarter of the swing,
//! front and hind legs, over DIAGFROM..DIAGTO s), SHOWPARAMS, PRECISE (base
//! position, first joint torques and targets at every timeline line), LEGS
//! (per-leg forces, torques, knee angle, load). The RESULT line counts
//! touchdowns, early ones (swing progress < 0.95) and controller ticks at
//! which a loaded stance foot (load > 0.5) had no contact.
use glam::{DVec2, DVec3};
use quadsim_engine::actuator_model::{
    ActuatorBank, ActuatorKind, ActuatorSpec, add_reflected_inertia,
};
use quadsim_engine::contact::{
    ContactForces, ContactPoint, ContactState, GroundMaterial, update_after_step,
};
use quadsim_engine::control::joint_pd::bandwidth_gains;
use quadsim_engine::control::walker::{Walker, WalkerInput, WalkerParams};
use quadsim_engine::gait::scheduler::LegPhase;
use quadsim_engine::gait::{Gait, GaitKind};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::spatial::rpy_from_rot;
use quadsim_engine::terrain::{Flat, Sinusoid, TerrainPatch, TerrainShape, TerrainUnion};
use quadsim_engine::{Data, robots};

fn env(k: &str) -> Option<f64> {
    std::env::var(k).ok().and_then(|x| x.parse().ok())
}

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let vx = args.first().copied().unwrap_or(1.5);
    let dur = args.get(1).copied().unwrap_or(10.0);
    let robot = std::env::var("ROBOT").unwrap_or_else(|_| "quad16".into());
    let desc = match env("LEGMASS") {
        Some(k) if robot == "quad16" => robots::builtin_with(
            &robot,
            &[
                ("thigh.mass_kg", 2.5 * k),
                ("shank.mass_kg", 1.5 * k),
                ("foot.mass_kg", 0.5 * k),
            ],
        )
        .unwrap(),
        _ => robots::builtin(&robot).unwrap(),
    };
    let mut model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    if let Some(l) = env("ELIM") {
        for e in model.effort_limit[6..].iter_mut() {
            *e = l;
        }
    }
    let mut data = Data::new(&model);
    let q0 = robots::nominal_q(&robot).unwrap();
    let mut p = WalkerParams::default_for(&desc, &model);
    if std::env::var("SHOWPARAMS").is_ok() {
        println!(
            "params: height {:.4} placement {:?} lift {:.4} kp {:?} kd {:?}",
            p.vmc.base_height_m,
            p.placement,
            p.lift_height_m,
            &p.swing_kp_nm_per_rad[..4],
            &p.swing_kd_nms_per_rad[..4]
        );
    }
    p.command.forward_mps = vx;
    if let (Some(per), Some(four)) = (env("PERIOD"), env("FOUR")) {
        p.gait =
            quadsim_engine::gait::Gait::trot_from_supports(per, four, per / 2.0 - four).unwrap();
    }
    if let (Some(per), Some(duty)) = (env("PERIOD"), env("DUTY")) {
        p.gait = Gait::of_kind(GaitKind::Trot, per, duty).unwrap();
    }
    if let Some(x) = env("LIFT") {
        p.lift_height_m = x;
    }
    if let Some(x) = env("HT") {
        p.vmc.base_height_m = x;
    }
    if let Some(x) = env("KG") {
        p.placement.gain_s = x;
    }
    if let Some(x) = env("MSX") {
        p.placement.max_step_x_m = x;
    }
    if let Some(x) = env("VF") {
        p.velocity_filter_s = x;
    }
    if let Some(x) = env("CA") {
        p.command_accel_mps2 = x;
    }
    if let Some(x) = env("HR") {
        p.max_horizontal_force_ratio = x;
    }
    if std::env::var("SNC").is_ok() {
        p.stance_needs_contact = true;
    }
    if let Some(x) = env("CLIP") {
        p.vmc.max_position_error_m = x;
    }
    if let Some(x) = env("ETD") {
        p.scheduler.early_touchdown_min_progress = x;
    }
    if let Some(x) = env("KGU") {
        p.knee_guard_rad = x;
    }
    if let Some(bw) = env("BW") {
        let (kp, kd) = bandwidth_gains(&model, &mut data, &q0, bw, 1.0);
        p.swing_kp_nm_per_rad = kp;
        p.swing_kd_nms_per_rad = kd;
    }
    if let Some(x) = env("KX") {
        p.vmc.gains.stiffness_npm *= x;
    }
    if let Some(x) = env("KXD") {
        p.vmc.gains.damping_nspm *= x;
    }
    if let Some(x) = env("KR") {
        p.vmc.gains.stiffness_nm_per_rad *= x;
    }
    if let Some(x) = env("KRD") {
        p.vmc.gains.damping_nms_per_rad *= x;
    }
    if std::env::var("WB").is_ok() {
        p.whole_body = true;
        p.follow_ground_plane = std::env::var("NOPLANE").is_err();
    }
    if std::env::var("MPC").is_ok() {
        p.whole_body = true;
        p.follow_ground_plane = std::env::var("NOPLANE").is_err();
        p.planner = quadsim_engine::control::walker::Planner::Mpc;
    }
    if let Some(x) = env("MPCF") {
        p.mpc.force_weight = x;
    }
    if let Some(x) = env("MPCDT") {
        p.mpc.step_s = x;
    }
    if let Ok(w) = std::env::var("MPCW") {
        for (k, x) in w.split(',').enumerate().take(12) {
            p.mpc.state_weights[k] = x.parse().unwrap();
        }
    }
    if let Some(x) = env("MPCEVERY") {
        p.mpc.solve_every_s = x;
    }
    if let Some(x) = env("MPCN") {
        p.mpc.horizon_steps = x as usize;
    }
    if let Some(x) = env("WBF") {
        p.wbc.force_weight = x;
    }
    if let Some(x) = env("WBL") {
        p.wbc.base_linear_weight = x;
    }
    if let Some(x) = env("AMAX") {
        p.swing_max_acc_mps2 = x;
    }
    if let Some(x) = env("PKP") {
        p.posture_gains = (x, 2.0 * x.sqrt());
    }
    if let Some(x) = env("WBZ") {
        p.wbc.base_vertical_weight = x;
    }
    if let Some(x) = env("WBC") {
        p.wbc.contact_velocity_gain = x;
    }
    if let Some(x) = env("WBA") {
        p.wbc.base_angular_weight = x;
    }
    if let Some(x) = env("SKP") {
        p.swing_task_gains.0 = x;
        p.swing_task_gains.1 = env("SKD").unwrap_or(2.0 * x.sqrt());
    }
    if let Ok(g) = std::env::var("GAIT") {
        let kind = match g.as_str() {
            "walk" => GaitKind::Walk,
            "pace" => GaitKind::Pace,
            "bound" => GaitKind::Bound,
            "pronk" => GaitKind::Pronk,
            "stand" => GaitKind::Stand,
            _ => GaitKind::Trot,
        };
        p.gait = Gait::default_of(kind).unwrap();
    }
    let mut ws_actuators = None;
    let every = env("EVERY").map_or(4, |e| e as usize);
    if std::env::var("MOTOR").is_ok() {
        // quad16's default DC motors, as the pipeline's default actuators
        let nv0 = model.base_nv();
        let specs: Vec<ActuatorSpec> = (nv0..model.nv)
            .map(|j| {
                quadsim_engine::robots::actuator_defaults(&robot)
                    .unwrap()
                    .spec(
                        ActuatorKind::DcMotor,
                        model.effort_limit[j],
                        model.velocity_limit[j],
                    )
            })
            .collect();
        add_reflected_inertia(&mut model, &specs);
        ws_actuators = Some(ActuatorBank::new(&specs, every as u64));
    }
    let model = model;
    let mut q0 = q0;
    if let Some(eps) = env("PERT") {
        // a deterministic perturbation of the joint angles, ±eps rad
        let seed = env("SEED").unwrap_or(1.0);
        for (j, qj) in q0[7..].iter_mut().enumerate() {
            *qj += eps * (seed * 12.9898 + j as f64 * 78.233).sin();
        }
    }
    if let Some(dx) = env("PERTX") {
        // the start moved along x by SEED × PERTX (m): on flat ground only the
        // rounding changes, which (unlike joint offsets, damped out while the
        // robot settles on its motors' friction) never decays
        q0[0] += env("SEED").unwrap_or(1.0) * dx;
    }
    let mut walker = Walker::new(&desc, &model, p).unwrap();
    let mut st_q_lift = 0.0;
    let mut concrete = GroundMaterial::preset("concrete").unwrap();
    if let Some(mu) = env("MU") {
        concrete.friction = mu;
    }
    let concrete = concrete;
    let mut terrain = TerrainUnion::flat(0.0, concrete);
    if let Some(x0) = env("SINE") {
        // trot_sine's waves: amplitude 5 cm, wavelength 2 m, 40 m long from x = SINE
        terrain = terrain.with(
            TerrainPatch::new(
                TerrainShape::Sinusoid(Sinusoid::new(0.05, 2.0, DVec2::new(40.0, 20.0)).unwrap()),
                DVec3::new(x0 + 20.0, 0.0, 0.0),
                0.0,
                concrete,
            )
            .unwrap(),
        );
    }
    if let Some(edge) = env("STEPUP") {
        // a platform (STEPH m, default 5 cm) from x = edge on, 3 m long
        let h = env("STEPH").unwrap_or(0.05);
        let len = env("STEPLEN").unwrap_or(20.0);
        terrain = terrain.with(
            TerrainPatch::new(
                TerrainShape::Flat(Flat::new(DVec2::new(len, 20.0)).unwrap()),
                DVec3::new(edge + len / 2.0, 0.0, h),
                0.0,
                concrete,
            )
            .unwrap(),
        );
    }
    if let Some(edge) = env("BOXUP") {
        // a 3 m long box platform (BOXH m, default 0.1) from x = edge: risers up and down
        let h = env("BOXH").unwrap_or(0.1);
        use quadsim_engine::terrain::{BoxObstacles, BoxSpec};
        terrain = terrain.with(
            TerrainPatch::new(
                TerrainShape::Boxes(
                    BoxObstacles::new(vec![BoxSpec {
                        centre_m: DVec3::new(edge + 1.5, 0.0, h / 2.0),
                        size_m: DVec3::new(3.0, 4.0, h),
                        yaw_rad: 0.0,
                    }])
                    .unwrap(),
                ),
                DVec3::ZERO,
                0.0,
                concrete,
            )
            .unwrap(),
        );
    }
    if let Some(deg) = env("SLOPE") {
        // an incline of SLOPE degrees rising along +x from x = SLOPEX (default 1.5), 14 m long
        // (downhill: from a 2 m high platform that the robot starts on)
        let x0 = env("SLOPEX").unwrap_or(1.5);
        let a = deg.to_radians();
        let top = if deg < 0.0 { 2.0 } else { 0.0 };
        if deg < 0.0 {
            terrain = terrain.with(
                TerrainPatch::new(
                    TerrainShape::Flat(Flat::new(DVec2::new(20.0, 20.0)).unwrap()),
                    DVec3::new(x0 - 10.0, 0.0, top),
                    0.0,
                    concrete,
                )
                .unwrap(),
            );
        }
        terrain = terrain.with(
            TerrainPatch::new(
                TerrainShape::Incline(
                    quadsim_engine::terrain::Incline::new(a, DVec2::new(14.0, 20.0)).unwrap(),
                ),
                DVec3::new(x0 + 7.0, 0.0, top + 7.0 * a.tan()),
                0.0,
                concrete,
            )
            .unwrap(),
        );
    }
    let points = ContactPoint::feet(&model, &desc);
    if env("SLOPE").is_some_and(|d| d < 0.0) {
        st_q_lift = 2.0;
    }
    let mut states = vec![ContactState::default(); points.len()];
    q0[2] += st_q_lift;
    let mut st = State {
        q: q0,
        v: vec![0.0; model.nv],
    };
    let mut ws = StepWorkspace::new(&model);
    ws.actuators = ws_actuators;
    let mut tau = vec![0.0; model.nv];
    let mut tj = vec![0.0; model.nv - 6];
    let dt = 0.0005;
    let print_s = env("PRINT").unwrap_or(0.1);
    let print_every = ((print_s / dt).round() as usize).max(1);
    let steps = (dur / dt).round() as usize;
    let (mut max_tilt, mut x3, mut zmin, mut zmax) = (0.0_f64, None, f64::INFINITY, 0.0_f64);
    let mut fell = None;
    let mut x_prev = st.q[0];
    let mut tau_peak = vec![0.0_f64; model.nv - 6];
    let mut sat = 0usize;
    // saturated controller ticks per joint, in swing and in stance
    let mut sat_j = vec![(0usize, 0usize); model.nv - 6];
    // peak normal foot force after the first second (N) and when (s)
    let mut fpk = (0.0f64, 0.0f64, 0usize);
    let mut slip = 0usize;
    let mut nflight = 0usize;
    let (mut touchdowns, mut early_td, mut unloaded_stance) = (0usize, 0usize, 0usize);
    let td_print = std::env::var("TD").is_ok();
    let swing_diag = std::env::var("SWINGDIAG").is_ok();
    let diag_from = (env("DIAGFROM").unwrap_or(1.0) / dt) as usize;
    let diag_to = (env("DIAGTO").unwrap_or(1e9) / dt) as usize;
    let mut sw_acc = [DVec3::ZERO; 8];
    let mut sw_n = [0.0_f64; 8];
    forward_kinematics(&model, &mut data, &st.q, &st.v);
    let c0 = quadsim_engine::com::center_of_mass(&model, &data);
    println!("base above CoM at start: {:.4} m", st.q[2] - c0.z);
    for k in 0..steps {
        forward_kinematics(&model, &mut data, &st.q, &st.v);
        update_after_step(&points, &data, &terrain, &mut states);
        if k % every == 0 {
            let contacts: Vec<bool> = states.iter().map(|s| s.in_contact).collect();
            let normals: Vec<DVec3> = states.iter().map(|s| s.normal).collect();
            let before: Vec<(LegPhase, f64)> = (0..points.len())
                .map(|i| {
                    let l = walker.scheduler().leg(i);
                    (
                        l.phase,
                        l.time_since_liftoff_s / l.swing_duration_s.max(1e-9),
                    )
                })
                .collect();
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
            for (i, &(ph, prog)) in before.iter().enumerate() {
                let l = walker.scheduler().leg(i);
                if ph == LegPhase::Swing && l.phase == LegPhase::Stance {
                    touchdowns += 1;
                    if prog < 0.95 {
                        early_td += 1;
                    }
                    if td_print {
                        println!(
                            "TD t {:.3} leg {i} progress {prog:.2} base vx {:.2} z {:.3}",
                            k as f64 * dt,
                            st.v[0],
                            st.q[2],
                        );
                    }
                }
                if l.phase == LegPhase::Stance && l.load > 0.5 && !contacts[i] {
                    unloaded_stance += 1;
                }
            }
            if swing_diag {
                for i in 0..points.len() {
                    let l = walker.scheduler().leg(i);
                    if l.phase != LegPhase::Swing || l.late_s > 0.0 || k < diag_from || k > diag_to
                    {
                        continue;
                    }
                    let r = l.swing_reference(walker.params.lift_height_m, &walker.params.reach);
                    let pt = &points[i];
                    let c = data.pose[pt.body].transform_point(pt.point_in_body)
                        - DVec3::Z * pt.radius_m;
                    let b = ((l.swing_progress * 4.0) as usize).min(3) + 4 * (i / 2);
                    sw_acc[b] += c - r.pos_m;
                    sw_n[b] += 1.0;
                }
            }
            tau[6..].copy_from_slice(&tj);
            for (j, t) in tj.iter().enumerate() {
                tau_peak[j] = tau_peak[j].max(t.abs());
                if t.abs() >= model.effort_limit[6 + j] - 1e-9 {
                    sat += 1;
                    let nj = (model.nv - 6) / 4;
                    if walker.scheduler().leg(j / nj).phase == LegPhase::Swing {
                        sat_j[j].0 += 1;
                    } else {
                        sat_j[j].1 += 1;
                    }
                }
            }
            if !contacts.iter().any(|&c| c) {
                nflight += 1;
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
        let t_now = (k + 1) as f64 * dt;
        for (i, s) in states.iter().enumerate() {
            if t_now > 1.0 && s.normal_force_n > fpk.0 {
                fpk = (s.normal_force_n, t_now, i);
            }
        }
        for (i, s) in states.iter().enumerate() {
            if s.in_contact && s.slipping {
                let l = walker.scheduler().leg(i);
                if l.phase == LegPhase::Stance && l.load > 0.99 {
                    slip += 1;
                }
            }
        }
        let rpy = rpy_from_rot(data.pose[0].rot);
        let t = (k + 1) as f64 * dt;
        max_tilt = max_tilt.max(rpy.x.abs()).max(rpy.y.abs());
        if k + 1 == (3.0 / dt) as usize {
            x3 = Some(st.q[0]);
        }
        if t >= 3.0 {
            zmin = zmin.min(st.q[2]);
            zmax = zmax.max(st.q[2]);
        }
        if fell.is_none() && (st.q[2] < 0.3 || rpy.x.abs().max(rpy.y.abs()) > 1.0) {
            fell = Some(t);
        }
        if print_s > 0.0 && (k + 1) % print_every == 0 {
            let ph: String = (0..4)
                .map(|i| {
                    let leg = walker.scheduler().leg(i);
                    match (leg.phase, states[i].in_contact) {
                        (LegPhase::Swing, false) => '-',
                        (LegPhase::Swing, true) => 's',
                        (_, true) => 'X',
                        (_, false) => 'o',
                    }
                })
                .collect();
            let w = walker.wrench();
            println!(
                "t {t:5.2} x {:6.3} vx {:5.2} cmd {:4.2} z {:.3} r {:+.3} p {:+.3} y {:+.3} {ph} Fx {:6.0} Fz {:5.0} My {:+5.0}",
                st.q[0],
                (st.q[0] - x_prev) / print_s,
                walker.active_command().forward_mps,
                st.q[2],
                rpy.x,
                rpy.y,
                rpy.z,
                w.lin.x,
                w.lin.z,
                w.ang.y
            );
            x_prev = st.q[0];
            if std::env::var("PRECISE").is_ok() {
                println!(
                    "  q[0..3] {:.15e} {:.15e} {:.15e}",
                    st.q[0], st.q[1], st.q[2]
                );
                println!("  tau {:?}", &tj[..8]);
                println!("  q_des {:?}", &walker.joint_targets()[..8]);
            }
            if std::env::var("LEGS").is_ok() {
                // per leg: normal force (N), hip-pitch and knee torque (N·m), knee angle (rad), load
                let nj = 4; // joints per leg (quad16)
                let mut line = String::from("      ");
                for i in 0..4 {
                    let l = walker.scheduler().leg(i);
                    line += &format!(
                        " | Fn {:4.0} th {:+4.0} tk {:+4.0} qk {:+.2} ld {:.1}",
                        states[i].normal_force_n,
                        tj[i * nj + 1],
                        tj[i * nj + 2],
                        st.q[7 + i * nj + 2],
                        l.load
                    );
                }
                println!("{line}");
            }
        }
        if !st.q[2].is_finite() || st.q[2] < 0.1 {
            break;
        }
    }
    let mean = x3.map_or(f64::NAN, |x| (st.q[0] - x) / (dur - 3.0));
    println!(
        "RESULT v {vx} fell {:?} mean[3,{dur}] {mean:.3} tilt {max_tilt:.3} p2p {:.4} sat_ticks {sat} loaded_slip_steps {slip} flight_ticks {nflight} touchdowns {touchdowns} early(<0.95) {early_td} loaded_stance_ticks_without_contact {unloaded_stance}",
        fell,
        zmax - zmin
    );
    println!(
        "peak foot force after 1 s: {:.0} N at {:.3} s (foot {})",
        fpk.0, fpk.1, fpk.2
    );
    if swing_diag {
        for (b, (a, n)) in sw_acc.iter().zip(&sw_n).enumerate() {
            let m = *a / (*n).max(1.0);
            println!(
                "swing error (actual − reference, world, m) {} legs, progress {:.2}–{:.2}: dx {:+.3} dy {:+.3} dz {:+.3} ({n} ticks)",
                if b < 4 { "front" } else { "hind" },
                (b % 4) as f64 / 4.0,
                (b % 4 + 1) as f64 / 4.0,
                m.x,
                m.y,
                m.z
            );
        }
    }
    println!("saturated ticks per joint (swing, stance): {sat_j:?}");
    println!(
        "peak |tau| per joint (N·m): {:?}",
        tau_peak.iter().map(|t| t.round()).collect::<Vec<_>>()
    );
}
