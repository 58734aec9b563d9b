//! Divergence: whether a robot's state left the finite, physical range,
//! when, and the likely cause from the numbers. Shared by `quadsim run`,
//! studies and campaigns, and `summary.json` (each diverged robot's entry).

use crate::error::RunError;
use crate::world::World;

pub use quadsim_engine::divergence::{
    DIVERGED_ANGULAR_SPEED_RADPS, DIVERGED_LINEAR_SPEED_MPS, DIVERGED_PENETRATION_M,
};

/// Stops with an error naming the robot, time and quantity when a robot
/// has diverged: a state not finite, a speed beyond
/// [`DIVERGED_LINEAR_SPEED_MPS`] or [`DIVERGED_ANGULAR_SPEED_RADPS`], or a
/// contact sunk beyond [`DIVERGED_PENETRATION_M`]. The step's robot pass
/// checks every robot after every step and keeps the first divergence
/// ([`RobotRun::diverged`](quadsim_components::RobotRun::diverged)), so
/// the error names the step it happened at, also after a pass of several
/// steps ([`quadsim_systems::Simulation::run_pass`]).
pub fn check_finite(world: &World) -> Result<(), RunError> {
    for (name, root) in &world.robots {
        let Some(r) = world.sim.robot(*root) else {
            continue;
        };
        if let Some((t_s, what, cause)) = divergence_of(world, r) {
            return Err(RunError::Diverged {
                robot: name.clone(),
                t_s,
                what,
                cause,
            });
        }
    }
    Ok(())
}

/// Whether every robot has diverged (and so the run can stop).
pub fn all_diverged(world: &World) -> bool {
    diverged_count(world) == world.robots.len()
}

/// How many robots have diverged.
pub fn diverged_count(world: &World) -> usize {
    world
        .robots
        .iter()
        .filter(|(_, root)| {
            world
                .sim
                .robot(*root)
                .is_some_and(|r| r.run.diverged.is_some())
        })
        .count()
}

/// Share of the run a joint may spend at its torque limit before a
/// divergence is put down to saturated actuators.
const SATURATION_CAUSE_SHARE: f64 = 0.2;

/// The likely cause of a robot's divergence, from the numbers: a contact
/// too stiff for the time step (the stability limit), a fall followed by a
/// joint spinning free on an ideal torque source, saturated actuators, or
/// none of these.
pub fn divergence_cause(
    world: &World,
    r: &quadsim_components::RobotSim,
    d: &quadsim_engine::divergence::Divergence,
) -> String {
    use quadsim_engine::contact::stability::check_stability_split;
    use quadsim_engine::divergence::Divergence;
    let ground = crate::world::ground_of(world);
    let mut materials = Vec::new();
    if let Some(g) = ground.default_ground() {
        materials.push(g.material);
    }
    materials.extend(ground.patches().iter().map(|p| *p.material()));
    let per_foot = r.model.total_mass / r.run.n_feet.max(1) as f64;
    let unstable = materials
        .iter()
        .flat_map(|m| check_stability_split(m, world.dt_s, per_foot, per_foot))
        .next();
    let m = r.run.metrics.summary();
    let a = r.run.actuators.summary();
    let joint_speed = matches!(d, Divergence::Speed { index, .. } if *index >= r.model.base_nv());
    if let Some(w) = unstable {
        format!(
            "likely cause: the ground contact is unstable at this time step ({w}); \
             a smaller world.dt_s or a softer ground"
        )
    } else if let (Some(t), true) = (m.fell_at_s, joint_speed) {
        format!(
            "likely cause: the robot fell at t = {t:.3} s and a joint then spun up without \
             a speed limit (an ideal torque source); give its joints motors ([robots.actuators])              or velocity limits"
        )
    } else if a.max_time_share_at_torque_limit > SATURATION_CAUSE_SHARE {
        format!(
            "likely cause: actuators saturated ({:.0} % of the run at a torque limit); \
             the controller's demands exceed the joints' ratings",
            100.0 * a.max_time_share_at_torque_limit
        )
    } else if let Some(t) = m.fell_at_s {
        format!(
            "the robot fell at t = {t:.3} s; no unstable contact or saturation was found: \
             check the model's masses and inertias, or try the rk4 integrator"
        )
    } else {
        "no unstable contact, fall or saturation was found: check the model's masses and \
             inertias and the controller's gains, or try a smaller world.dt_s or the rk4 integrator"
            .to_string()
    }
}

/// A diverged robot's time, what diverged and the likely cause.
pub fn divergence_of(
    world: &World,
    r: &quadsim_components::RobotSim,
) -> Option<(f64, String, String)> {
    use quadsim_engine::divergence::Divergence;
    {
        let (t, d) = r.run.diverged?;
        let m = &r.model;
        let (nq0, nv0) = (m.base_nq(), m.base_nv());
        let joint = |vi: usize| m.joint_name[m.v_body[vi]].as_str();
        let what = match d {
            Divergence::Position { index: i } if i < nq0 => {
                format!("q[{i}] (base pose) is not finite")
            }
            Divergence::Position { index: i } => {
                format!("joint '{}' angle is not finite", joint(i - nq0 + nv0))
            }
            Divergence::Velocity { index: i } => {
                format!("v[{i}] ({}) is not finite", velocity_name(m, i))
            }
            Divergence::Speed {
                index: i,
                value: x,
                limit: lim,
            } => {
                let (_, unit) = quadsim_engine::divergence::speed_limit(m, i);
                format!(
                    "v[{i}] ({}) = {x:.4e} {unit} exceeds {lim} {unit}",
                    velocity_name(m, i)
                )
            }
            Divergence::Penetration { point: i, depth_m } => {
                let body = r.contact.points[i].body;
                let link = m
                    .frames
                    .iter()
                    .find(|f| f.body == body)
                    .map_or("?", |f| f.name.as_str());
                format!(
                    "contact point {i} (on link '{link}') penetrates {depth_m:.4} m, beyond {DIVERGED_PENETRATION_M} m"
                )
            }
        };
        Some((t, what, divergence_cause(world, r, &d)))
    }
}

/// What velocity coordinate `i` is.
fn velocity_name(m: &quadsim_engine::Model, i: usize) -> String {
    let nv0 = m.base_nv();
    if m.is_floating() && i < 6 {
        let axis = ["x", "y", "z"][i % 3];
        let kind = if i < 3 { "linear" } else { "angular" };
        format!("base {kind} velocity {axis}, base frame")
    } else if i >= nv0 {
        format!("joint '{}' velocity", m.joint_name[m.v_body[i]])
    } else {
        format!("base velocity {i}")
    }
}
