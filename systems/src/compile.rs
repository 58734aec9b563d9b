//! The compile stage: robot entities → packed engine models, in its own
//! schedule that runs before the step schedule, never inside a step.
//!
//! [`mark_dirty_robots`] finds robots whose description components changed
//! (bevy change detection on the roots, observers of inserts and removals on
//! the parts); [`compile_dirty_robots`] reads their
//! entities back with [`describe_robot_with_links`], compiles a
//! [`Model`] and installs it in the [`RobotBatch`]. A robot that does not
//! compile gets a [`CompileFailure`] and keeps its last valid model.
//!
//! [`crate::Simulation::step`] runs the schedule only when [`CompileGate`]
//! sees something it could act on; otherwise each of its systems would
//! return without a change.

use std::sync::{Arc, Weak};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};
use bevy_ecs::system::SystemState;
use quadsim_components::{
    BelongsTo, CenterOfMass, Collider, ColliderOf, CompileError, CompileFailure, ComputedInertia,
    ControlView, DefaultGroundPlane, EffortLimit, Foot, FootPoint, Ground, Inertia, Joint,
    JointActuators, JointArmature, JointConnection, JointDamping, JointFriction, JointLimits,
    JointPlacement, Link, Mass, PayloadEvents, Robot, RobotBase, RobotBatch, RobotIndex,
    RobotModelName, RobotParts, RobotSim, SimClock, SimConfig, SpringDamper, Terrain,
    VelocityLimit, Visual, VisualOf, describe_robot_with_links,
};
use quadsim_engine::Model;
use quadsim_engine::actuator_model::{ActuatorBank, ActuatorKind, add_reflected_inertia};

/// Label of the schedule that compiles robots; [`crate::Simulation::step`]
/// runs it before [`crate::StepSchedule`].
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct CompileSchedule;

/// Robots waiting for the compile stage.
#[derive(Resource, Debug, Default)]
pub struct DirtyRobots {
    /// Roots whose description changed (may repeat).
    pub robots: Vec<Entity>,
    /// Link, joint and shape entities whose description components were
    /// inserted since the last compile (`note_part_edit`; may repeat).
    pub parts: Vec<Entity>,
    /// Entities that lost an optional description component
    /// (`RemovableParts`) since the last compile (`note_part_removal`;
    /// may repeat).
    pub removed: Vec<Entity>,
    /// A robot was despawned: drop its slot and renumber [`RobotIndex`]
    /// (`note_robot_removal`).
    pub prune: bool,
}

impl DirtyRobots {
    /// Whether anything waits for the compile stage.
    pub fn is_empty(&self) -> bool {
        self.robots.is_empty() && self.parts.is_empty() && self.removed.is_empty() && !self.prune
    }
}

/// The compiled models in use, interned by articulation
/// ([`Model::same_articulation`], which ignores the name): robots of one
/// design share one `Arc<Model>`, so the step can put them in SIMD lanes
/// together and the model's memory is paid once. Holds weak references: a
/// model lives as long as a robot uses it.
#[derive(Resource, Debug, Default)]
pub struct SharedModels {
    /// Models by a cheap key (nq, nv, nbodies, total mass bits); equal keys
    /// are told apart by the full comparison.
    by_key: std::collections::HashMap<(usize, usize, usize, u64), Vec<Weak<Model>>>,
}

impl SharedModels {
    /// The shared model of `model`'s articulation: an existing one if a live
    /// robot uses the same articulation, else `model`, now shared.
    pub fn intern(&mut self, model: Model) -> Arc<Model> {
        let key = (
            model.nq,
            model.nv,
            model.nbodies,
            model.total_mass.to_bits(),
        );
        let bucket = self.by_key.entry(key).or_default();
        bucket.retain(|w| w.strong_count() > 0);
        if let Some(shared) = bucket
            .iter()
            .filter_map(Weak::upgrade)
            .find(|m| m.same_articulation(&model))
        {
            return shared;
        }
        let shared = Arc::new(model);
        bucket.push(Arc::downgrade(&shared));
        shared
    }

    /// Number of distinct live models.
    pub fn len(&self) -> usize {
        self.by_key
            .values()
            .flatten()
            .filter(|w| w.strong_count() > 0)
            .count()
    }

    /// True when no live model is interned.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The compile schedule: [`mark_dirty_robots`] then [`compile_dirty_robots`],
/// single-threaded, ambiguity detection as an error.
pub fn build_compile_schedule() -> Schedule {
    let mut schedule = Schedule::new(CompileSchedule);
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.add_systems(
        (
            crate::payload::apply_payload_events,
            mark_dirty_robots,
            compile_dirty_robots,
            crate::ground::compile_ground,
        )
            .chain(),
    );
    schedule
}

/// Components of a robot root whose change triggers a recompile.
type RootChanged = Or<(
    Changed<Robot>,
    Changed<RobotModelName>,
    Changed<RobotBase>,
    Changed<RobotParts>,
    Changed<JointActuators>,
)>;

/// The description components of link, joint and shape entities. They are
/// immutable, so an edit is an insert, which [`note_part_edit`] sees; the
/// compile stage then resolves the edited entities to their robots.
type PartComponents = (
    (Link, Mass, CenterOfMass, Inertia, Foot, FootPoint),
    (
        Joint,
        JointPlacement,
        JointConnection,
        JointLimits,
        EffortLimit,
        VelocityLimit,
        JointDamping,
        JointFriction,
        JointArmature,
        SpringDamper,
    ),
    (Collider, Visual, ColliderOf, VisualOf),
);

/// Observer: a description component of a link, joint, collider or visual
/// entity was inserted (spawned or edited). The entity waits in
/// [`DirtyRobots::parts`] for [`mark_dirty_robots`] (its robot may not be
/// attached yet while it is being spawned).
pub fn note_part_edit(edit: On<Insert<PartComponents>>, mut dirty: ResMut<DirtyRobots>) {
    if dirty.parts.last() != Some(&edit.entity) {
        dirty.parts.push(edit.entity);
    }
}

/// Observer: a collider or visual leaves its link (despawned or moved): the
/// link's robot is marked now, while the shape still points at the link.
pub fn note_shape_detach(
    detach: On<Discard<(ColliderOf, VisualOf)>>,
    shapes: Query<(Option<&ColliderOf>, Option<&VisualOf>)>,
    owners: Query<&BelongsTo>,
    mut dirty: ResMut<DirtyRobots>,
) {
    if let Some(owner) = part_owner(detach.entity, &shapes, &owners) {
        dirty.robots.push(owner);
    }
}

/// Description components whose removal changes the description (the other
/// ones are required by the entity's kind, or their removal detaches the
/// part from its robot, which changes the root's [`RobotParts`]).
pub type RemovableParts = (
    Inertia,
    JointLimits,
    Foot,
    FootPoint,
    Link,
    Joint,
    SpringDamper,
);

/// Observer: one of the [`RemovableParts`] left an entity (removed, or the
/// entity despawned). The entity waits in [`DirtyRobots::removed`] for
/// [`mark_dirty_robots`], which marks its robot if it still belongs to one (a
/// despawned part has no owner any more; its robot's `RobotParts` changed
/// instead).
pub fn note_part_removal(removal: On<Remove<RemovableParts>>, mut dirty: ResMut<DirtyRobots>) {
    if dirty.removed.last() != Some(&removal.entity) {
        dirty.removed.push(removal.entity);
    }
}

/// Observer: a [`Robot`] was removed or despawned: the compile stage drops
/// its slot.
pub fn note_robot_removal(_removal: On<Remove<Robot>>, mut dirty: ResMut<DirtyRobots>) {
    dirty.prune = true;
}

/// Registers `note_part_edit`, `note_shape_detach`, `note_part_removal`
/// and `note_robot_removal` (once per world, before any robot is spawned).
pub fn add_edit_observers(world: &mut World) {
    world.add_observer(note_part_edit);
    world.add_observer(note_shape_detach);
    world.add_observer(note_part_removal);
    world.add_observer(note_robot_removal);
}

/// The robot a link, joint, collider or visual entity belongs to.
fn part_owner(
    e: Entity,
    shapes: &Query<(Option<&ColliderOf>, Option<&VisualOf>)>,
    owners: &Query<&BelongsTo>,
) -> Option<Entity> {
    if let Ok(b) = owners.get(e) {
        return Some(b.0);
    }
    let (collider_of, visual_of) = shapes.get(e).ok()?;
    let link = collider_of.map(|c| c.0).or(visual_of.map(|v| v.0))?;
    owners.get(link).ok().map(|b| b.0)
}

/// Collects the robots whose description changed since the last run: roots
/// by bevy change detection (one entity per robot), parts from the
/// `note_part_edit` and `note_part_removal` observers (despawned robots
/// were flagged by `note_robot_removal`). A changed [`SimConfig`]
/// (gravity, passive model) marks every robot. With nothing edited, this
/// costs a few instructions per robot (the roots' change ticks), not a scan
/// of every part.
pub fn mark_dirty_robots(
    mut dirty: ResMut<DirtyRobots>,
    config: Res<SimConfig>,
    all_roots: Query<Entity, With<Robot>>,
    roots: Query<Entity, (With<Robot>, RootChanged)>,
    shapes: Query<(Option<&ColliderOf>, Option<&VisualOf>)>,
    owners: Query<&BelongsTo>,
) {
    if config.is_changed() {
        dirty.robots.extend(all_roots.iter());
    }
    dirty.robots.extend(roots.iter());
    let DirtyRobots {
        robots,
        parts,
        removed,
        ..
    } = &mut *dirty;
    for e in parts.drain(..) {
        if let Some(owner) = part_owner(e, &shapes, &owners) {
            robots.push(owner);
        }
    }
    for e in removed.drain(..) {
        // A despawned entity has no owner any more; its robot's RobotParts changed instead.
        if let Ok(owner) = owners.get(e) {
            robots.push(owner.0);
        }
    }
}

/// What can give the compile schedule work, read by [`CompileGate`]: each
/// line below is what one of its systems acts on.
type CompileTriggers = (
    // `mark_dirty_robots`: observed edits and removals, the roots' change
    // ticks, the configuration
    Res<'static, DirtyRobots>,
    Query<'static, 'static, (), (With<Robot>, RootChanged)>,
    Res<'static, SimConfig>,
    // `apply_payload_events`: the next payload event and the clock (read
    // only while an event is pending, see `CompileGate::due`)
    Option<Res<'static, PayloadEvents>>,
    // `compile_ground`: the terrains and default plane, and whether every
    // robot uses the current ground
    Res<'static, DefaultGroundPlane>,
    Query<'static, 'static, (), Changed<Terrain>>,
    RemovedComponents<'static, 'static, Terrain>,
    Res<'static, Ground>,
    Res<'static, RobotBatch>,
);

/// Whether the compile schedule can have anything to do, so that
/// [`crate::Simulation::step`] can skip it (its fixed cost is most of the
/// schedules' overhead on a small world). It checks, with its own change
/// ticks (each change is seen once, by the next check), what each system of
/// the schedule acts on: pending observed edits, removals or despawns
/// ([`DirtyRobots`]), a root component changed (the same filter as
/// [`mark_dirty_robots`]), a changed [`SimConfig`], a payload event due
/// ([`crate::apply_payload_events`]), a terrain added, changed or removed, the
/// default plane changed, or a robot not on the current [`Ground`]
/// ([`crate::compile_ground`]). When all are false, every system of the
/// schedule would return without a change, so skipping it changes nothing.
/// A change made by the schedule itself (a payload attach changes the
/// root's `RobotParts`) opens the gate once more, for a run that finds
/// nothing new.
pub struct CompileGate(SystemState<CompileTriggers>);

impl std::fmt::Debug for CompileGate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CompileGate").finish_non_exhaustive()
    }
}

impl CompileGate {
    /// A gate on `world`, which sees everything as changed at its first check.
    pub fn new(world: &mut World) -> Self {
        Self(SystemState::new(world))
    }

    /// Whether the compile schedule should run now (also when a resource it
    /// reads is missing: the schedule then reports it).
    pub fn due(&mut self, world: &World) -> bool {
        let Ok((dirty, roots, config, events, plane, terrains, mut removed, ground, batch)) =
            self.0.get(world)
        else {
            return true;
        };
        // every check runs (no short-circuit), so that each consumes its changes
        let edits = !dirty.is_empty() | !roots.is_empty() | config.is_changed();
        // The clock only matters while an event waits: fetched then, not
        // every step (a resource fetch is some 80 instructions).
        let payload = events.is_some_and(|e| {
            e.applied < e.events.len()
                && world
                    .get_resource::<SimClock>()
                    .is_none_or(|clock| crate::payload::payload_due(&e, clock.time_s))
        });
        let ground = plane.is_changed()
            | !terrains.is_empty()
            | (removed.read().count() > 0)
            | crate::ground::ground_stale(&batch, &ground);
        edits | payload | ground
    }
}

/// Compiles every robot marked by [`mark_dirty_robots`] (exclusive: it reads
/// whole robots and writes the batch).
///
/// A recompiled robot keeps its state `(q, v)` and actuator command when nq and
/// nv are unchanged, or when only its compliant payloads changed (see
/// `carry_over_loads`); otherwise it restarts at the neutral
/// configuration, at rest.
pub fn compile_dirty_robots(world: &mut World) {
    {
        let dirty = world.resource::<DirtyRobots>();
        if dirty.robots.is_empty() && !dirty.prune {
            return;
        }
    }
    let (mut robots, prune) = {
        let mut dirty = world.resource_mut::<DirtyRobots>();
        (
            std::mem::take(&mut dirty.robots),
            std::mem::take(&mut dirty.prune),
        )
    };
    robots.sort_unstable();
    robots.dedup();
    let config = *world.resource::<SimConfig>();
    world.resource_scope(|world, mut batch: Mut<RobotBatch>| {
        if prune {
            prune_despawned(world, &mut batch);
        }
        for &root in &robots {
            compile_robot(world, &mut batch, root, &config);
        }
    });
    robots.clear();
    world.resource_mut::<DirtyRobots>().robots = robots;
}

/// Drops the slots of despawned robots and renumbers the others' [`RobotIndex`].
fn prune_despawned(world: &mut World, batch: &mut RobotBatch) {
    let before = batch.sims.len();
    batch
        .sims
        .retain(|s| world.get::<Robot>(s.entity).is_some());
    if batch.sims.len() != before {
        for (i, sim) in batch.sims.iter().enumerate() {
            world.entity_mut(sim.entity).insert(RobotIndex(i));
        }
    }
}

/// Compiles one robot and installs it in the batch, or records why it failed.
fn compile_robot(world: &mut World, batch: &mut RobotBatch, root: Entity, config: &SimConfig) {
    let Some(robot) = world.get::<Robot>(root) else {
        return; // despawned since it was marked
    };
    let robot_name = robot.name.clone();
    let base = world.get::<RobotBase>(root).copied().unwrap_or_default().0;
    let compiled = describe_robot_with_links(world, root)
        .map_err(CompileError::from)
        .and_then(|(desc, links)| {
            Model::from_description(&desc, base)
                .map(|model| (desc, links, model))
                .map_err(|source| CompileError::Model {
                    robot: robot_name,
                    source,
                })
        });
    let (desc, links, mut model) = match compiled {
        Ok(c) => c,
        Err(e) => {
            world.entity_mut(root).insert(CompileFailure(e));
            return;
        }
    };
    model.gravity = config.gravity;
    let actuators = world
        .get::<JointActuators>(root)
        // one actuator per actuated joint (a compliant load's joints, after
        // them, have none)
        .filter(|a| a.specs.len() == model.actuated_nv() - model.base_nv())
        .cloned();
    if let Some(a) = &actuators {
        add_reflected_inertia(&mut model, &a.specs);
    }
    for (link, &e) in desc.links.iter().zip(&links) {
        if let Some(mut c) = world.get_mut::<ComputedInertia>(e) {
            c.0 = link.rigid_inertia().inertia_com;
        }
    }
    world.entity_mut(root).remove::<CompileFailure>();
    let control = ControlView::of(&desc, &model, base);
    let model = world.get_resource_or_init::<SharedModels>().intern(model);
    let mut sim = RobotSim::new(root, model, links, config.passive);
    sim.control = control;
    sim.workspace.actuators = actuators
        .filter(|a| !a.specs.iter().all(|s| s.kind == ActuatorKind::Ideal))
        .map(|a| ActuatorBank::new(&a.specs, a.control_every_steps));
    let slot = world
        .get::<RobotIndex>(root)
        .map(|i| i.0)
        .filter(|&i| batch.sims.get(i).is_some_and(|s| s.entity == root));
    match slot {
        Some(i) => {
            let old = &mut batch.sims[i];
            // Whether the robot's own structure is unchanged, so that its
            // controller, metrics, contact points (by body) and sensors stay
            // valid and go on: the same bodies (a rigid payload or an inertia
            // edit), or only compliant payloads attached or detached.
            let same_size = old.model.nq == sim.model.nq && old.model.nv == sim.model.nv;
            let goes_on = if same_size {
                std::mem::swap(&mut sim.state, &mut old.state);
                std::mem::swap(&mut sim.tau_actuator, &mut old.tau_actuator);
                old.model.nbodies == sim.model.nbodies && old.model.parent == sim.model.parent
            } else {
                carry_over_loads(old, &mut sim)
            };
            if goes_on {
                std::mem::swap(&mut sim.run, &mut old.run);
                std::mem::swap(&mut sim.contact, &mut old.contact);
                std::mem::swap(&mut sim.sensing, &mut old.sensing);
            }
            // The same actuators on the same joint state go on with their
            // lag, latency and servo states.
            if let (Some(new), Some(prev)) = (&sim.workspace.actuators, &old.workspace.actuators)
                && new.specs() == prev.specs()
                && (same_size || goes_on)
            {
                std::mem::swap(&mut sim.workspace.actuators, &mut old.workspace.actuators);
            }
            sim.last_worker = old.last_worker;
            *old = sim;
        }
        None => {
            batch.sims.push(sim);
            world
                .entity_mut(root)
                .insert(RobotIndex(batch.sims.len() - 1));
        }
    }
}

/// A compliant payload attached or detached: the two models differ only in
/// their trailing load coordinates and bodies (the robot's own bodies, q and
/// v keep their indices). Then the new state takes the old one's actuated
/// part, each load coordinate the old value of the joint of the same name
/// (a newly attached load starts at rest relative to the torso, springs
/// relaxed: it moves with the torso), and the actuator command its actuated
/// part; the controller, metrics and contact states go on. Returns false
/// (nothing carried) when the robot's own structure changed.
pub fn carry_over_loads(old: &RobotSim, new: &mut RobotSim) -> bool {
    let (a, b) = (&old.model, &new.model);
    let nb = a.nbodies - a.load_nv;
    if a.actuated_nq() != b.actuated_nq()
        || a.actuated_nv() != b.actuated_nv()
        || b.nbodies - b.load_nv != nb
        || a.parent[..nb] != b.parent[..nb]
        || a.joint_name[..nb] != b.joint_name[..nb]
    {
        return false;
    }
    let (nq, nv) = (a.actuated_nq(), a.actuated_nv());
    new.state.q[..nq].copy_from_slice(&old.state.q[..nq]);
    new.state.v[..nv].copy_from_slice(&old.state.v[..nv]);
    new.tau_actuator[..nv].copy_from_slice(&old.tau_actuator[..nv]);
    for body in nb..b.nbodies {
        if let Some(ob) = (nb..a.nbodies).find(|&ob| a.joint_name[ob] == b.joint_name[body]) {
            new.state.q[b.idx_q[body]] = old.state.q[a.idx_q[ob]];
            new.state.v[b.idx_v[body]] = old.state.v[a.idx_v[ob]];
        }
    }
    true
}
