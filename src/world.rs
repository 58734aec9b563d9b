//! Builds a simulation world from a validated [`Scenario`]: terrain entities,
//! robot entities with their start state, contact points, controller, fall
//! criteria and metrics, and the scheduled events.
//!
//! Randomness derives from `(world seed, name)` only ([`stream_seed`]), so the
//! order of robots or terrains in the file changes nothing.

use std::path::Path;

use bevy_ecs::prelude::Entity;
use glam::{DQuat, DVec3};
use quadsim_components::{
    ControlRate, Controller, DefaultGroundPlane, FallCriteria, PrescribedRun, Push, SimConfig,
    Terrain,
};
use quadsim_engine::contact::{ContactKind, ContactPoint, ContactState};
use quadsim_engine::control::joint_pd::{JointPd, bandwidth_gains, static_stance_torques};
use quadsim_engine::control::prescribed::{Prescribed, PrescribedMode, PrescribedParams};
use quadsim_engine::control::profile::{RobotProfile, STAND_BANDWIDTH_HZ};
use quadsim_engine::control::vmc::VmcCommand;
use quadsim_engine::control::walker::{Planner, Walker, WalkerParams};
use quadsim_engine::description::{RobotDescription, Shape};
use quadsim_engine::gait::{Gait, GaitKind};
use quadsim_engine::integrate::{Integrator, State};
use quadsim_engine::metrics::MetricsAccumulator;
use quadsim_engine::model::BaseKind;
use quadsim_engine::robots::SourceStudy;
use quadsim_engine::terrain::{DefaultGround, Terrain as _, TerrainUnion};
use quadsim_engine::{Data, Model, robots};
use quadsim_systems::Simulation;
use quadsim_validation::study_b_dynamics::StudyBTorqueComparison;

use crate::scenario::format::IntegratorSpec;
use crate::scenario::spans::path_key;
use crate::scenario::validate::as_f64;
use crate::scenario::{Locator, Scenario, ScenarioError};
use crate::terrain_spec::{ground_material, terrain_patch};
use crate::urdf::{UrdfOptions, load_urdf};

/// The whole-body layer's torso angular weight under a bound (default 10;
/// see where it is set).
const BOUND_BASE_ANGULAR_WEIGHT: f64 = 3.0;

/// A world ready to run.
#[derive(Debug)]
pub struct World {
    /// The simulation.
    pub sim: Simulation,
    /// Robot names and root entities, in file order.
    pub robots: Vec<(String, Entity)>,
    /// Steps to run.
    pub steps: u64,
    /// Step length (s).
    pub dt_s: f64,
    /// The world seed used.
    pub seed: u64,
    /// Warnings found while building (printed by `check` and `run`).
    pub warnings: Vec<String>,
}

pub use crate::seed::stream_seed;

/// Options that override the scenario.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    /// Simulated duration (s).
    pub duration_s: Option<f64>,
    /// World seed.
    pub seed: Option<u64>,
    /// Worker threads (0: one per core).
    pub threads: usize,
}

impl Overrides {
    /// The scenario as written, on `threads` worker threads (0: one per core).
    pub fn with_threads(threads: usize) -> Self {
        Self {
            threads,
            ..Self::default()
        }
    }
}

/// A time step below this is legal but suspect (s).
pub const SUSPECT_DT_S: f64 = 1.0e-5;
/// More steps than this in one run are legal but suspect.
pub const SUSPECT_STEPS: u64 = 100_000_000;
/// A friction coefficient above this is legal but suspect.
pub const SUSPECT_FRICTION: f64 = 2.0;
/// A commanded speed above this is legal but suspect (m/s).
pub const SUSPECT_SPEED_MPS: f64 = 5.0;

/// Warnings for values that are legal but suspect, with the numbers that
/// make them so (`check` and `run` print them).
fn suspect_values(scn: &Scenario, steps: u64) -> Vec<String> {
    use crate::scenario::format::GroundSpec;
    let f = &scn.file;
    let w = &f.world;
    let mut out = Vec::new();
    if w.dt_s < SUSPECT_DT_S {
        out.push(format!(
            "world.dt_s = {} s is below {SUSPECT_DT_S} s: {:.3e} steps per simulated second, \
             far finer than contact needs (0.0005 s is the default)",
            w.dt_s,
            1.0 / w.dt_s
        ));
    }
    if steps > SUSPECT_STEPS {
        out.push(format!(
            "the run takes {steps} steps (more than {SUSPECT_STEPS}): hours of wall time"
        ));
    }
    let mut grounds: Vec<(String, &GroundSpec)> = Vec::new();
    if let Some(g) = &w.default_ground {
        grounds.push(("world.default_ground".into(), g));
    }
    for (i, t) in f.terrains.iter().enumerate() {
        if let Some(g) = &t.ground {
            grounds.push((format!("terrains[{i}].ground"), g));
        }
    }
    for (p, g) in grounds {
        if let GroundSpec::Custom(c) = g
            && c.friction > SUSPECT_FRICTION
        {
            out.push(format!(
                "{p}.friction = {} is above {SUSPECT_FRICTION}: rubber on concrete is about 1",
                c.friction
            ));
        }
    }
    for (i, r) in f.robots.iter().enumerate() {
        for key in ["v_x_mps", "v_y_mps"] {
            if let Some(v) = r.controller.params.get(key).and_then(as_f64)
                && v.abs() > SUSPECT_SPEED_MPS
            {
                out.push(format!(
                    "{}.controller.{key} = {v} m/s is above {SUSPECT_SPEED_MPS} m/s: faster than \
             quadsim's walkers go",
                    f.robot_key_path(i)
                ));
            }
        }
    }
    out
}

/// The most feet a robot may have (a quadruped's; a URDF whose legs end in
/// extra toe or sensor links names its four feet with `feet`).
pub const MAX_FEET: usize = 4;

/// Builds the world. Errors name the scenario file, line and key path (for a
/// herd robot's varied value, its `vary` entry).
pub fn build_world(scn: &Scenario, ov: Overrides) -> Result<World, ScenarioError> {
    let loc = Locator {
        path: &scn.path,
        src: &scn.source,
    };
    build(scn, ov, loc).map_err(|e| crate::scenario::herd::relocate(&loc, &scn.file, e))
}

fn build(scn: &Scenario, ov: Overrides, loc: Locator<'_>) -> Result<World, ScenarioError> {
    let f = &scn.file;
    let w = &f.world;
    let seed = ov.seed.unwrap_or(w.seed);
    let config = SimConfig {
        dt_s: w.dt_s,
        integrator: match w.integrator {
            IntegratorSpec::SemiImplicitEuler => Integrator::SemiImplicitEuler,
            IntegratorSpec::Rk4 => Integrator::Rk4,
        },
        gravity: DVec3::from_array(w.gravity_mps2),
        ..SimConfig::default()
    };
    let mut sim =
        Simulation::new(config, ov.threads).map_err(|e| loc.at("", format!("--threads: {e}")))?;
    let every = (1.0 / (w.dt_s * w.controller_rate_hz)).round().max(1.0) as u64;
    sim.world
        .insert_resource(ControlRate { every_steps: every });
    // Link entities get their poses only on request
    // (`Simulation::sync_link_poses`): nothing in a run reads them (logs,
    // monitors, metrics and fall checks sample the robots' own state), and a
    // copy at the controller rate cost 4 % of a trotting quad16's step.
    sim.world.insert_resource(quadsim_components::PoseSync {
        every_steps: 0,
        requested: false,
    });

    // Terrains (entities) and the default ground, compiled into the union.
    let base_dir = scn.path.parent().unwrap_or(Path::new("."));
    for (i, t) in f.terrains.iter().enumerate() {
        let patch = terrain_patch(
            &loc,
            &format!("terrains[{i}]"),
            t,
            stream_seed(seed, &t.name),
            base_dir,
        )?;
        sim.world.spawn(Terrain {
            name: t.name.clone(),
            patch,
        });
    }
    let plane = match &w.default_ground {
        Some(g) => Some(DefaultGround {
            height_m: w.default_ground_height_m,
            material: ground_material(&loc, "world.default_ground", g)?,
        }),
        None => None,
    };
    sim.world.insert_resource(DefaultGroundPlane(plane));
    sim.compile();
    let ground = sim.world.resource::<quadsim_components::Ground>().0.clone();

    let mut robots_out = Vec::new();
    let mut warnings = Vec::new();
    for (i, r) in f.robots.iter().enumerate() {
        let p = f.robot_key_path(i);
        let (mut desc, warn) = robot_description(&loc, &p, r, base_dir)?;
        warnings.extend(warn.into_iter().map(|w| format!("{p} ('{}'): {w}", r.name)));
        if let Some(feet) = &r.feet {
            desc.feet = feet.clone();
        }
        desc.name = r.name.clone();
        // the bounds `check` and `run` share (a URDF's were checked, with
        // its lines, on import; a built-in's parameters are checked here)
        crate::physical::check_description(&desc).map_err(|e| {
            let prefix = format!("{}.", e.name);
            let key = match r.params.keys().find(|k| k.starts_with(&prefix)) {
                Some(k) => format!("params.{}", path_key(k)),
                None if r.params.is_empty() => "model".to_string(),
                None => "params".to_string(),
            };
            loc.at(&format!("{p}.{key}"), format!("'{}': {e}", r.model))
        })?;
        let model = Model::from_description(&desc, BaseKind::Floating)
            .map_err(|e| loc.at(&format!("{p}.model"), format!("'{}': {e}", r.model)))?;
        if model.feet.is_empty() {
            return Err(loc.at(
                &format!("{p}.model"),
                "the robot has no feet (no leaf links); name them with `feet`",
            ));
        }
        if model.feet.len() > MAX_FEET {
            let names: Vec<&str> = model
                .feet
                .iter()
                .map(|&f| model.frames[f].name.as_str())
                .collect();
            let (key, how) = if r.feet.is_some() {
                ("feet", "name at most four")
            } else {
                ("model", "name the four feet with `feet`")
            };
            return Err(loc.at(
                &format!("{p}.{key}"),
                format!(
                    "'{}' has {} feet ({}): quadsim's sensors, controllers and metrics take at most {MAX_FEET}; {how}",
                    r.model,
                    names.len(),
                    names.join(", ")
                ),
            ));
        }
        let nj = model.nv - 6;
        let joints = match &r.start_joints_rad {
            Some(j) if j.len() != nj => {
                return Err(loc.at(
                    &format!("{p}.start_joints_rad"),
                    format!("expected {nj} angles, got {}", j.len()),
                ));
            }
            Some(j) => j.clone(),
            // the profile's stance: a built-in's nominal one, else found
            // from the model (feet under the hips, knees bent)
            None => {
                let mut named = desc.clone();
                named.name = r.model.clone();
                RobotProfile::from_model(&named, &model).stance_rad
            }
        };
        let stance_height = robots::stance_base_height_m(&desc, &joints)
            .map_err(|e| loc.at(&format!("{p}.model"), e.to_string()))?;
        let origin = r
            .terrain
            .as_ref()
            .and_then(|t| f.terrains.iter().find(|x| &x.name == t))
            .map_or(DVec3::ZERO, |t| DVec3::from_array(t.origin_m));
        let start = match (r.start_position_m, r.start_xy_m) {
            (Some(_), Some(_)) => {
                return Err(loc.at(
                    &format!("{p}.start_xy_m"),
                    "give start_position_m or start_xy_m, not both",
                ));
            }
            (Some(s), None) => DVec3::from_array(s),
            (None, Some([x, y])) => DVec3::new(x, y, stance_height),
            (None, None) => DVec3::new(0.0, 0.0, stance_height),
        };
        let xy = origin.truncate() + start.truncate();
        let ground_z = ground.height(xy.x, xy.y).ok_or_else(|| {
            loc.at(
                &format!("{p}.start_position_m"),
                format!("no ground beneath ({:.3}, {:.3}): add a terrain there or a world.default_ground", xy.x, xy.y),
            )
        })?;
        let yaw = r.start_yaw_deg.to_radians();
        let quat = DQuat::from_rotation_z(yaw);
        let mut q = vec![
            xy.x,
            xy.y,
            ground_z + start.z,
            quat.x,
            quat.y,
            quat.z,
            quat.w,
        ];
        q.extend_from_slice(&joints);

        let points = contact_points(&model, &desc, &r.contact_points);
        let n_feet = model.feet.len();
        let mut model_desc = desc.clone();
        model_desc.name = r.model.clone();
        let mut controller = controller(
            &loc,
            &p,
            every,
            w.dt_s * every as f64,
            r,
            &model_desc,
            &model,
            &q,
            &points[..n_feet],
        )?;
        // Payloads attached at start are part of the spawned robot; the
        // controller was built on the bare robot and is told of the known ones.
        let payloads = payload_specs(&loc, &p, r)?;
        if let Controller::Prescribed(pc) = &controller
            && pc.controller.params.mode == PrescribedMode::Hybrid
            && let Some(k) = payloads.iter().position(|(pl, _)| pl.compliance.is_some())
        {
            return Err(loc.at(
                &format!("{p}.payloads[{k}].kind"),
                "a compliant payload needs a torque-driven controller: the prescribed \
                 controller's hybrid mode imposes every joint's motion (use mode = \"pd\")",
            ));
        }
        let mut spawn_desc = desc.clone();
        for (k, (pl, spec)) in payloads.iter().enumerate() {
            if spec.attached {
                pl.attach_to(&mut spawn_desc)
                    .map_err(|e| loc.at(&format!("{p}.payloads[{k}]"), e.to_string()))?;
                if let (true, Controller::Walker(w)) = (spec.known_to_controller, &mut controller) {
                    w.add_payload_mass_kg(pl.mass_kg);
                }
            }
        }
        let root = sim
            .spawn_robot(&spawn_desc)
            .map_err(|e| loc.at(&format!("{p}.model"), e.to_string()))?;
        let imposed_motion = matches!(&controller, Controller::Prescribed(pc)
            if pc.controller.params.mode == PrescribedMode::Hybrid);
        let actuator_defaults = robots::actuator_defaults(&r.model);
        let actuators = crate::actuators::joint_actuators(
            &loc,
            &p,
            &r.actuators,
            actuator_defaults.as_ref(),
            &model,
            crate::actuators::default_kind(actuator_defaults.as_ref(), imposed_motion),
        )?;
        if let Some(specs) = &actuators {
            if imposed_motion {
                return Err(loc.at(
                    &format!("{p}.actuators"),
                    "motor and servo actuators need a controller that commands them; the prescribed controller's hybrid mode imposes the motion: use mode = \"pd\"",
                ));
            }
            sim.world
                .entity_mut(root)
                .insert(quadsim_components::JointActuators {
                    specs: specs.clone(),
                    control_every_steps: every,
                });
            sim.compile();
        }
        let mut pushes = Vec::new();
        let mut commands = Vec::new();
        for (k, e) in f
            .events
            .iter()
            .enumerate()
            .filter(|(_, e)| e.robot == r.name)
        {
            let ep = format!("events[{k}]");
            match e.kind.as_str() {
                "push" => pushes.push(push_event(&loc, &ep, e, &model)?),
                "command" => {
                    let Controller::Walker(w) = &controller else {
                        return Err(loc.at(
                            &format!("{ep}.kind"),
                            "a command event needs a robot with controller kind \"vmc\"",
                        ));
                    };
                    let num = |key: &str, d: f64| e.params.get(key).and_then(as_f64).unwrap_or(d);
                    let prev = w.command();
                    commands.push((
                        e.t_s,
                        VmcCommand {
                            forward_mps: num("v_x_mps", prev.forward_mps),
                            lateral_mps: num("v_y_mps", prev.lateral_mps),
                            yaw_rate_radps: num("yaw_rate_radps", prev.yaw_rate_radps),
                        },
                    ));
                }
                "attach" | "detach" => {
                    let name = e
                        .params
                        .get("payload")
                        .and_then(|v| v.as_str())
                        .unwrap_or("");
                    let Some((pl, spec)) = payloads.iter().find(|(pl, _)| pl.name == name) else {
                        return Err(loc.at(
                            &format!("{ep}.payload"),
                            format!(
                                "robot '{}' has no payload '{name}' (declare it in [[robots.payloads]])",
                                r.name
                            ),
                        ));
                    };
                    let parent_link = desc.root_link().map(|l| l.name.clone()).unwrap_or_default();
                    sim.world
                        .resource_mut::<quadsim_components::PayloadEvents>()
                        .push(quadsim_components::PayloadEvent {
                            t_s: e.t_s,
                            robot: root,
                            parent_link,
                            payload: pl.clone(),
                            action: if e.kind == "attach" {
                                quadsim_components::PayloadAction::Attach
                            } else {
                                quadsim_components::PayloadAction::Detach
                            },
                            known_to_controller: spec.known_to_controller,
                        });
                }
                _ => {}
            }
        }
        commands.sort_by(|a, b| a.0.total_cmp(&b.0));
        let sim_r = sim.robot_mut(root).expect("compiled");
        // compliant payloads attached at start: their coordinates close q
        // and v, at rest with the springs relaxed
        q.resize(sim_r.model.nq, 0.0);
        sim_r.state = State {
            q,
            v: vec![0.0; sim_r.model.nv],
        };
        sim_r.contact.states = vec![ContactState::default(); points.len()];
        sim_r.contact.points = points;
        sim_r.contact.pushes = pushes;
        if let Controller::Prescribed(p) = &controller
            && p.controller.params.mode == PrescribedMode::Hybrid
        {
            sim_r.workspace.imposed = Some(p.controller.imposed());
        }
        sim_r.sensing = crate::sensing::robot_sensing(
            &loc,
            &p,
            r,
            &model,
            &sim_r.contact.points[..n_feet.min(4)],
            &sim_r.state.q,
            &sim_r.state.v,
            w.controller_rate_hz,
            stream_seed(seed, &crate::sensing::sensor_stream_name(&r.name)),
        )?;
        sim_r.run.controller = controller;
        sim_r.run.commands = commands;
        sim_r.run.n_feet = n_feet;
        sim_r.run.fall = FallCriteria {
            body_points: fall_points(&model, &desc),
            min_base_height_m: 0.5 * stance_height,
            ..FallCriteria::default()
        };
        sim_r.run.metrics = MetricsAccumulator::new(yaw, 0.0);
        // A motor's limits are its stall torque and no-load speed where
        // they are below the joint's ratings.
        let (mut effort, mut velocity) = (
            model.effort_limit[6..].to_vec(),
            model.velocity_limit[6..].to_vec(),
        );
        for (j, s) in actuators.iter().flatten().enumerate() {
            effort[j] = effort[j].min(s.torque_limit_nm());
            velocity[j] = velocity[j].min(s.speed_limit_radps());
        }
        sim_r.run.actuators = quadsim_engine::actuators::ActuatorStats::new(&effort, &velocity);
        robots_out.push((r.name.clone(), root));
    }
    sim.compile();
    let steps_f = (ov.duration_s.unwrap_or(w.duration_s) / w.dt_s).round();
    if steps_f > crate::limits::MAX_STEPS as f64 {
        return Err(loc.at(
            "",
            format!(
                "--duration {} s at dt {} s is {steps_f:.3e} steps, beyond the {} a run may take",
                ov.duration_s.unwrap_or(w.duration_s),
                w.dt_s,
                crate::limits::MAX_STEPS
            ),
        ));
    }
    let steps = steps_f as u64;
    warnings.extend(suspect_values(scn, steps));
    Ok(World {
        sim,
        robots: robots_out,
        steps,
        dt_s: w.dt_s,
        seed,
        warnings,
    })
}

/// The robot's payloads from `[[robots.payloads]]`, checked (shape, size,
/// mass, unique names).
fn payload_specs<'a>(
    loc: &Locator<'_>,
    p: &str,
    r: &'a crate::scenario::format::RobotSpec,
) -> Result<
    Vec<(
        quadsim_engine::payload::Payload,
        &'a crate::scenario::format::PayloadSpec,
    )>,
    ScenarioError,
> {
    use quadsim_engine::payload::Payload;
    let mut out: Vec<(Payload, &crate::scenario::format::PayloadSpec)> = Vec::new();
    for (k, s) in r.payloads.iter().enumerate() {
        let kp = format!("{p}.payloads[{k}]");
        if s.name.is_empty() || out.iter().any(|(pl, _)| pl.name == s.name) {
            return Err(loc.at(
                &format!("{kp}.name"),
                format!("payload names must be unique and non-empty ('{}')", s.name),
            ));
        }
        if !(s.mass_kg.is_finite() && s.mass_kg >= 0.0) {
            return Err(loc.at(&format!("{kp}.mass_kg"), "must be a finite mass ≥ 0 kg"));
        }
        let dims_ok = s.size_m.iter().all(|x| x.is_finite() && *x > 0.0);
        let kind = s.shape.as_deref().unwrap_or("box");
        let shape = match (kind, s.size_m.as_slice()) {
            ("box", [x, y, z]) if dims_ok => Shape::Box {
                size_m: DVec3::new(*x, *y, *z),
            },
            ("sphere", [r]) if dims_ok => Shape::Sphere { radius_m: *r },
            ("cylinder", [r, l]) if dims_ok => Shape::Cylinder {
                radius_m: *r,
                length_m: *l,
            },
            ("box" | "sphere" | "cylinder", _) => {
                return Err(loc.at(
                    &format!("{kp}.size_m"),
                    format!(
                        "a {kind} takes {} positive lengths (m)",
                        match kind {
                            "box" => "[x, y, z]: three",
                            "sphere" => "[radius]: one",
                            _ => "[radius, length]: two",
                        }
                    ),
                ));
            }
            (other, _) => {
                return Err(loc.at(
                    &format!("{kp}.shape"),
                    format!("unknown shape '{other}': expected box, sphere or cylinder"),
                ));
            }
        };
        let offset = DVec3::from_array(s.offset_m);
        if !offset.is_finite() {
            return Err(loc.at(&format!("{kp}.offset_m"), "must be finite"));
        }
        let compliance = compliance_spec(loc, &kp, s)?;
        out.push((
            Payload {
                name: s.name.clone(),
                mass_kg: s.mass_kg,
                shape,
                offset_m: offset,
                compliance,
            },
            s,
        ));
    }
    Ok(out)
}

/// A payload's compliance: `None` for `kind = "rigid"`; for `"compliant"`
/// its DOFs, each with the stiffness and damping of its family.
fn compliance_spec(
    loc: &Locator<'_>,
    kp: &str,
    s: &crate::scenario::format::PayloadSpec,
) -> Result<Option<quadsim_engine::payload::Compliance>, ScenarioError> {
    use quadsim_engine::payload::{Compliance, DofSpring, LoadDof};
    let compliant_keys = [
        ("dofs", !s.dofs.is_empty()),
        ("stiffness_npm", s.stiffness_npm.is_some()),
        ("damping_nspm", s.damping_nspm.is_some()),
        ("stiffness_nm_per_rad", s.stiffness_nm_per_rad.is_some()),
        ("damping_nms_per_rad", s.damping_nms_per_rad.is_some()),
    ];
    match s.kind.as_deref().unwrap_or("rigid") {
        "rigid" => {
            if let Some((key, _)) = compliant_keys.iter().find(|(_, set)| *set) {
                return Err(loc.at(
                    &format!("{kp}.{key}"),
                    "only a payload of kind = \"compliant\" takes it",
                ));
            }
            return Ok(None);
        }
        "compliant" => {}
        other => {
            return Err(loc.at(
                &format!("{kp}.kind"),
                format!("unknown payload kind '{other}': expected rigid or compliant"),
            ));
        }
    }
    if s.dofs.is_empty() {
        return Err(loc.at(
            &format!("{kp}.dofs"),
            "a compliant payload declares its DOFs, e.g. dofs = [\"x\", \"y\", \"z\"]",
        ));
    }
    if s.mass_kg <= 0.0 {
        return Err(loc.at(
            &format!("{kp}.mass_kg"),
            "a compliant payload needs a mass > 0 kg",
        ));
    }
    let mut dofs: Vec<DofSpring> = Vec::new();
    for (i, name) in s.dofs.iter().enumerate() {
        let Some(dof) = LoadDof::parse(name) else {
            return Err(loc.at(
                &format!("{kp}.dofs[{i}]"),
                format!("unknown DOF '{name}': expected x, y, z, roll, pitch or yaw"),
            ));
        };
        if dofs.iter().any(|d| d.dof == dof) {
            return Err(loc.at(
                &format!("{kp}.dofs[{i}]"),
                format!("DOF '{name}' declared twice"),
            ));
        }
        let (k_key, k, b_key, b) = if dof.is_translation() {
            (
                "stiffness_npm",
                s.stiffness_npm,
                "damping_nspm",
                s.damping_nspm,
            )
        } else {
            (
                "stiffness_nm_per_rad",
                s.stiffness_nm_per_rad,
                "damping_nms_per_rad",
                s.damping_nms_per_rad,
            )
        };
        let Some(k) = k else {
            return Err(loc.at(
                &format!("{kp}.dofs[{i}]"),
                format!("DOF '{name}' needs a spring: give {k_key}"),
            ));
        };
        if !(k.is_finite() && k > 0.0) {
            return Err(loc.at(
                &format!("{kp}.{k_key}"),
                "must be a finite stiffness > 0 (a free load would leave the robot)",
            ));
        }
        let b = b.unwrap_or(0.0);
        if !(b.is_finite() && b >= 0.0) {
            return Err(loc.at(&format!("{kp}.{b_key}"), "must be a finite damping ≥ 0"));
        }
        dofs.push(DofSpring {
            dof,
            stiffness: k,
            damping: b,
        });
    }
    Ok(Some(Compliance { dofs }))
}

/// The robot's description: a built-in with parameter overrides, or a URDF
/// (relative to the scenario file).
fn robot_description(
    loc: &Locator<'_>,
    p: &str,
    r: &crate::scenario::format::RobotSpec,
    base_dir: &Path,
) -> Result<(RobotDescription, Vec<String>), ScenarioError> {
    if robots::builtin_names().contains(&r.model.as_str()) {
        let overrides: Vec<(&str, f64)> = r.params.iter().map(|(k, v)| (k.as_str(), *v)).collect();
        return robots::builtin_with(&r.model, &overrides)
            .map(|d| (d, Vec::new()))
            .map_err(|e| {
                let key = r.params.keys().find(|k| e.to_string().contains(k.as_str()));
                match key {
                    Some(k) => loc.at(&format!("{p}.params.{}", path_key(k)), e.to_string()),
                    None => loc.at(&format!("{p}.params"), e.to_string()),
                }
            });
    }
    let path = base_dir.join(&r.model);
    if !path.is_file() {
        return Err(loc.at(
            &format!("{p}.model"),
            format!(
                "unknown model '{}': not a built-in ({}) and no file {}",
                r.model,
                robots::builtin_names().join(", "),
                path.display()
            ),
        ));
    }
    if !r.params.is_empty() {
        return Err(loc.at(
            &format!("{p}.params"),
            "parameter overrides apply to built-in models only",
        ));
    }
    let robot = load_urdf(&path, &UrdfOptions::default())
        .map_err(|e| loc.at(&format!("{p}.model"), e.to_string()))?;
    Ok((robot.description, robot.warnings))
}

/// The points whose touching the ground is a fall, checked geometrically
/// every step: the knees (origins of bodies moved by a joint named `*knee*`)
/// and the corners of the root link's first collision box.
fn fall_points(model: &Model, desc: &RobotDescription) -> Vec<(usize, DVec3)> {
    contact_points(model, desc, &["knees".to_string(), "torso".to_string()])
        .into_iter()
        .filter(|p| p.kind != ContactKind::Foot)
        .map(|p| (p.body, p.point_in_body))
        .collect()
}

/// Feet first (in the model's foot order), then knees and torso corners when asked.
fn contact_points(model: &Model, desc: &RobotDescription, extra: &[String]) -> Vec<ContactPoint> {
    let mut points = ContactPoint::feet(model, desc);
    if extra.iter().any(|e| e == "knees") {
        for b in 1..model.nbodies {
            if model.joint_name[b].contains("knee") {
                points.push(ContactPoint::new(b, DVec3::ZERO, 0.0, ContactKind::Knee));
            }
        }
    }
    if extra.iter().any(|e| e == "torso") {
        let root = desc.root_link();
        let cuboid = root.and_then(|l| {
            l.collision.iter().find_map(|g| match g.shape {
                Shape::Box { size_m } => Some((g.origin, size_m)),
                _ => None,
            })
        });
        if let Some((origin, size)) = cuboid {
            for sx in [-0.5, 0.5] {
                for sy in [-0.5, 0.5] {
                    for sz in [-0.5, 0.5] {
                        let c = origin.transform_point(DVec3::new(
                            sx * size.x,
                            sy * size.y,
                            sz * size.z,
                        ));
                        points.push(ContactPoint::new(0, c, 0.0, ContactKind::Torso));
                    }
                }
            }
        }
    }
    // kept for the whole run, one per robot
    points.shrink_to_fit();
    points
}

#[expect(
    clippy::too_many_arguments,
    reason = "everything a controller is built from"
)]
fn controller(
    loc: &Locator<'_>,
    p: &str,
    every_steps: u64,
    control_period_s: f64,
    r: &crate::scenario::format::RobotSpec,
    desc: &RobotDescription,
    model: &Model,
    q: &[f64],
    feet: &[ContactPoint],
) -> Result<Controller, ScenarioError> {
    let c = &r.controller;
    let get = |k: &str, d: f64| c.params.get(k).and_then(as_f64).unwrap_or(d);
    match c.kind.as_deref().unwrap_or("none") {
        "none" => Ok(Controller::None),
        // joint commands from another process (docs/monitor.md)
        "external" => Ok(Controller::External(
            quadsim_components::ExternalJoint::idle(&q[model.base_nq()..]),
        )),
        "joint_pd" => {
            let nj = model.nv - 6;
            let ff = match c
                .params
                .get("gravity_compensation")
                .and_then(|v| v.as_str())
                .unwrap_or("none")
            {
                "none" => vec![0.0; nj],
                "static" => {
                    let mut data = Data::new(model);
                    let pts: Vec<(usize, DVec3)> =
                        feet.iter().map(|f| (f.body, f.point_in_body)).collect();
                    static_stance_torques(model, &mut data, q, &pts)
                }
                other => {
                    return Err(loc.at(
                        &format!("{p}.controller.gravity_compensation"),
                        format!("unknown value '{other}' (none, static)"),
                    ));
                }
            };
            let (bkp, bkd) = RobotProfile::from_model(desc, model).stand_gains(
                desc,
                model,
                q,
                get("bandwidth_hz", STAND_BANDWIDTH_HZ),
                get("damping_ratio", 1.0),
                control_period_s,
            );
            let kp = per_joint(
                loc,
                &format!("{p}.controller.kp_nm_per_rad"),
                c.params.get("kp_nm_per_rad"),
                bkp,
            )?;
            let kd = per_joint(
                loc,
                &format!("{p}.controller.kd_nms_per_rad"),
                c.params.get("kd_nms_per_rad"),
                bkd,
            )?;
            Ok(Controller::JointPd(JointPd {
                kp_nm_per_rad: kp,
                kd_nms_per_rad: kd,
                target_rad: q[7..].to_vec(),
                feedforward_nm: ff,
            }))
        }
        "vmc" => {
            let profile = RobotProfile::from_model(desc, model);
            let mut wp = WalkerParams::from_profile(&profile, model);
            let has = |k: &str| c.params.contains_key(k);
            // the whole-body layer, with its trot, unless the scenario asks
            // for Study A's τ = Jᵀ f mapping
            wp.whole_body = c
                .params
                .get("whole_body")
                .and_then(|v| v.as_bool())
                .unwrap_or(true);
            if wp.whole_body {
                wp.gait = Gait::long_swing_trot();
                // room to step sideways after a push, where the robot's
                // profile gives it (quad16: 0.2 m, robots::builtin_tuning)
                if let Some(y) = profile.whole_body_max_step_y_m {
                    wp.placement.max_step_y_m = y;
                }
            }
            // the torso follows the ground plane under the feet (on slopes
            // and steps), unless asked not to; Study A's mapping keeps its
            // level torso
            wp.follow_ground_plane = c
                .params
                .get("follow_ground")
                .and_then(|v| v.as_bool())
                .unwrap_or(wp.whole_body);
            wp.planner = match c.params.get("planner").and_then(|v| v.as_str()) {
                None | Some("vmc") => Planner::Vmc,
                Some("mpc") if wp.whole_body => Planner::Mpc,
                Some("mpc") => {
                    return Err(loc.at(
                        &format!("{p}.controller.planner"),
                        "the \"mpc\" planner needs the whole-body layer (whole_body = true)"
                            .to_string(),
                    ));
                }
                Some(other) => {
                    return Err(loc.at(
                        &format!("{p}.controller.planner"),
                        format!("unknown planner '{other}' (vmc, mpc)"),
                    ));
                }
            };
            let kp = format!("{p}.controller");
            if let Some(name) = c.params.get("gait").and_then(|v| v.as_str()) {
                let kind = GaitKind::from_name(name).ok_or_else(|| {
                    loc.at(
                        &format!("{kp}.gait"),
                        format!("unknown gait '{name}' (trot, walk, pace, bound, pronk, stand)"),
                    )
                })?;
                // the whole-body walker walks with a shorter stride than the
                // walk's default timing (Gait::whole_body_walk says why)
                let (period, duty) = if wp.whole_body && kind == GaitKind::Walk {
                    let walk = Gait::whole_body_walk();
                    (walk.period_s(), walk.duty_factor())
                } else {
                    (kind.default_period_s(), kind.default_duty())
                };
                let period = get("period_s", period);
                let duty = get("duty_factor", duty);
                wp.gait =
                    Gait::of_kind(kind, period, duty).map_err(|e| loc.at(&kp, e.to_string()))?;
            }
            if has("four_leg_support_s") || has("two_leg_support_s") {
                wp.gait = Gait::trot_from_supports(
                    get("period_s", wp.gait.period_s()),
                    get("four_leg_support_s", 0.1),
                    get("two_leg_support_s", 0.15),
                )
                .map_err(|e| loc.at(&kp, e.to_string()))?;
            } else if has("period_s") && !has("gait") {
                wp.gait = Gait::of_kind(
                    wp.gait.kind(),
                    get("period_s", 0.5),
                    get("duty_factor", wp.gait.duty_factor()),
                )
                .map_err(|e| loc.at(&kp, e.to_string()))?;
            }
            wp.lift_height_m = get("lift_height_m", wp.lift_height_m);
            wp.command = VmcCommand {
                forward_mps: get("v_x_mps", wp.command.forward_mps),
                lateral_mps: get("v_y_mps", wp.command.lateral_mps),
                yaw_rate_radps: get("yaw_rate_radps", wp.command.yaw_rate_radps),
            };
            wp.vmc.base_height_m = get("height_m", wp.vmc.base_height_m);
            wp.vmc.payload_mass_kg = get("payload_mass_kg", 0.0);
            wp.vmc.max_position_error_m = get("position_clip_m", wp.vmc.max_position_error_m);
            wp.placement.gain_s = get("placement_gain_s", wp.placement.gain_s);
            if has("swing_bandwidth_hz") {
                let mut data = Data::new(model);
                let (kps, kds) =
                    bandwidth_gains(model, &mut data, q, get("swing_bandwidth_hz", 4.0), 1.0);
                wp.swing_kp_nm_per_rad = kps;
                wp.swing_kd_nms_per_rad = kds;
            }
            // A pronk flies between its stances: without a planner asked for,
            // it gets the MPC, which plans through the flight (quad16 at
            // 0.5 m/s, 10 perturbed copies: VMC 10 fall, MPC 0;
            // docs/validation.md, "Gaits").
            if !has("planner") && wp.whole_body && wp.gait.kind() == GaitKind::Pronk {
                wp.planner = Planner::Mpc;
            }
            // A bound's stance pairs share an end, so its pitch swings with
            // every stride: the torso's angular task, weighted lower, leaves
            // the planned forces more say (quad16 at 0.5 m/s, 24 perturbed
            // copies: worst pitch 0.205 rad at 10, 0.131 at 3; the other
            // gaits, payloads and pushes fare worse at 3; docs/validation.md,
            // "Gaits").
            if wp.whole_body && wp.gait.kind() == GaitKind::Bound {
                wp.wbc.base_angular_weight = BOUND_BASE_ANGULAR_WEIGHT;
            }
            let w = Walker::new(desc, model, wp)
                .map_err(|e| loc.at(&format!("{p}.model"), e.to_string()))?;
            Ok(Controller::Walker(Box::new(w)))
        }
        "prescribed" => {
            let kp = format!("{p}.controller");
            let mut pp = PrescribedParams::defaults_for(model, q);
            pp.mode = match c.params.get("mode").and_then(|v| v.as_str()) {
                None | Some("hybrid") => PrescribedMode::Hybrid,
                Some("pd") => PrescribedMode::Pd,
                Some(other) => {
                    return Err(loc.at(
                        &format!("{kp}.mode"),
                        format!("unknown mode '{other}' (hybrid, pd)"),
                    ));
                }
            };
            let t = &mut pp.trot;
            t.period_s = get("period_s", t.period_s);
            t.duty_factor = get("duty_factor", t.duty_factor);
            t.step_length_m = get("step_length_m", t.step_length_m);
            t.lift_height_m = get("lift_height_m", t.lift_height_m);
            t.ramp_s = get("ramp_s", t.period_s);
            t.body_height_m = c.params.get("body_height_m").and_then(as_f64);
            if let Err(msg) = t.validate() {
                let field = msg.split_whitespace().next().unwrap_or("");
                return Err(loc.at(&format!("{kp}.{field}"), msg));
            }
            pp.hybrid_kp_per_s2 = get("hybrid_kp_per_s2", pp.hybrid_kp_per_s2);
            pp.hybrid_kd_per_s = get("hybrid_kd_per_s", pp.hybrid_kd_per_s);
            pp.pd_kp_nm_per_rad = per_joint(
                loc,
                &format!("{kp}.kp_nm_per_rad"),
                c.params.get("kp_nm_per_rad"),
                pp.pd_kp_nm_per_rad,
            )?;
            pp.pd_kd_nms_per_rad = per_joint(
                loc,
                &format!("{kp}.kd_nms_per_rad"),
                c.params.get("kd_nms_per_rad"),
                pp.pd_kd_nms_per_rad,
            )?;
            let hybrid = pp.mode == PrescribedMode::Hybrid;
            let ctl = Prescribed::new(desc, model, pp, q)
                .map_err(|e| loc.at(&format!("{p}.model"), e.to_string()))?;
            // Study B's Table 4 comparison: its leg model is Study B's robot's leg
            let study_b = (hybrid && robots::source_study(&desc.name) == Some(SourceStudy::B))
                .then(StudyBTorqueComparison::default);
            Ok(Controller::Prescribed(Box::new(PrescribedRun {
                controller: ctl,
                study_b,
                sample_every_steps: every_steps,
                steps: 0,
            })))
        }
        other => Err(loc.at(
            &format!("{p}.controller.kind"),
            format!("controller kind '{other}' is not available"),
        )),
    }
}

/// A gain given as one number for every joint or one per joint; `default`
/// (one per joint) when absent.
fn per_joint(
    loc: &Locator<'_>,
    path: &str,
    v: Option<&toml::Value>,
    default: Vec<f64>,
) -> Result<Vec<f64>, ScenarioError> {
    let n = default.len();
    match v {
        None => Ok(default),
        Some(toml::Value::Array(a)) => {
            let vals: Vec<f64> = a.iter().filter_map(as_f64).collect();
            if vals.len() != n || a.len() != n {
                return Err(loc.at(
                    path,
                    format!(
                        "expected one number or {n} numbers (one per joint), got {}",
                        a.len()
                    ),
                ));
            }
            if vals.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(loc.at(path, "gains must be finite and ≥ 0"));
            }
            Ok(vals)
        }
        Some(x) => match as_f64(x) {
            Some(g) if g.is_finite() && g >= 0.0 => Ok(vec![g; n]),
            _ => Err(loc.at(path, "must be a number ≥ 0 or an array of them")),
        },
    }
}

fn push_event(
    loc: &Locator<'_>,
    p: &str,
    e: &crate::scenario::format::EventSpec,
    model: &Model,
) -> Result<Push, ScenarioError> {
    let vec3 = |k: &str| -> Option<DVec3> {
        let a = e.params.get(k)?.as_array()?;
        let v: Vec<f64> = a.iter().filter_map(as_f64).collect();
        (v.len() == 3).then(|| DVec3::new(v[0], v[1], v[2]))
    };
    let force = vec3("force_n")
        .ok_or_else(|| loc.at(&format!("{p}.force_n"), "needs three numbers (N)"))?;
    let duration = e.params.get("duration_s").and_then(as_f64).unwrap_or(0.0);
    let (body, placement) = match e.params.get("body").and_then(|v| v.as_str()) {
        None => (0, quadsim_engine::spatial::Transform::IDENTITY),
        Some(name) => {
            let fi = model
                .frame_index(name)
                .ok_or_else(|| loc.at(&format!("{p}.body"), format!("unknown link '{name}'")))?;
            (model.frames[fi].body, model.frames[fi].placement)
        }
    };
    let point = placement.transform_point(vec3("point_m").unwrap_or(DVec3::ZERO));
    Ok(Push {
        start_s: e.t_s,
        end_s: e.t_s + duration,
        body,
        point_in_body_m: point,
        force_n: force,
    })
}

/// The world's ground union for checks (`quadsim check`).
pub fn ground_of(world: &World) -> std::sync::Arc<TerrainUnion> {
    world
        .sim
        .world
        .resource::<quadsim_components::Ground>()
        .0
        .clone()
}
