//! A world with its two schedules: compile, then step.

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use quadsim_components::{
    CompileError, CompileFailure, ControlRate, DefaultGroundPlane, Ground, PoseSync, RobotBatch,
    RobotIndex, RobotSim, SimClock, SimConfig, SimThreadPool, ThreadPoolError,
    spawn_robot_with_base,
};
use quadsim_engine::BaseKind;
use quadsim_engine::description::RobotDescription;

use crate::compile::{
    CompileGate, DirtyRobots, SharedModels, add_edit_observers, build_compile_schedule,
};
use crate::publish::sync_link_poses;
use crate::schedule::build_step_schedule;

/// A simulation world: robots as entities, the packed [`RobotBatch`], and the
/// compile and step schedules. [`Simulation::step`] compiles edited robots,
/// then runs one fixed step.
///
/// # Examples
/// ```
/// use quadsim_components::SimConfig;
/// use quadsim_engine::description::{RobotBuilder, Shape};
/// use quadsim_engine::spatial::Transform;
/// use quadsim_systems::Simulation;
///
/// let ball = RobotBuilder::new("ball")
///     .link("b").mass(1.0).shape(Transform::IDENTITY, Shape::Sphere { radius_m: 0.1 }).done()
///     .build();
/// let mut sim = Simulation::new(SimConfig::default(), 1).unwrap();
/// let root = sim.spawn_robot(&ball).unwrap();
/// sim.run(100);
/// let z = sim.robot(root).unwrap().state.q[2];
/// // free fall from rest: z(t) = −g t²/2 (up to the integrator's O(dt) error)
/// let t = sim.clock().time_s;
/// assert!((z + 0.5 * 9.81 * t * t).abs() < 1e-3);
/// ```
pub struct Simulation {
    /// The ECS world (entities and resources).
    pub world: World,
    compile: Schedule,
    compile_gate: CompileGate,
    step: Schedule,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("world", &self.world)
            .field("clock", &self.clock())
            .finish_non_exhaustive()
    }
}

impl Simulation {
    /// An empty world stepping with `config` on a pool of `threads` workers (0: one per core).
    pub fn new(config: SimConfig, threads: usize) -> Result<Self, ThreadPoolError> {
        let mut world = World::new();
        world.insert_resource(config);
        world.insert_resource(SimThreadPool::new(threads)?);
        world.init_resource::<SimClock>();
        world.init_resource::<RobotBatch>();
        world.init_resource::<PoseSync>();
        world.init_resource::<DirtyRobots>();
        add_edit_observers(&mut world);
        world.init_resource::<SharedModels>();
        world.init_resource::<quadsim_components::LaneBatching>();
        world.init_resource::<quadsim_components::StageLayout>();
        world.init_resource::<Ground>();
        world.init_resource::<DefaultGroundPlane>();
        world.init_resource::<ControlRate>();
        world.init_resource::<quadsim_components::PayloadEvents>();
        let compile_gate = CompileGate::new(&mut world);
        Ok(Self {
            world,
            compile: build_compile_schedule(),
            compile_gate,
            step: build_step_schedule(),
        })
    }

    /// Spawns a floating-base robot and compiles it at once.
    pub fn spawn_robot(&mut self, desc: &RobotDescription) -> Result<Entity, CompileError> {
        self.spawn_robot_with_base(desc, BaseKind::Floating)
    }

    /// Spawns a robot with the given base and compiles it at once. On a compile
    /// error the entities are despawned again and the error returned.
    pub fn spawn_robot_with_base(
        &mut self,
        desc: &RobotDescription,
        base: BaseKind,
    ) -> Result<Entity, CompileError> {
        let root = spawn_robot_with_base(&mut self.world, desc, base);
        self.compile();
        match self.world.entity_mut(root).take::<CompileFailure>() {
            Some(CompileFailure(e)) => {
                self.world.despawn(root);
                self.compile();
                Err(e)
            }
            None => Ok(root),
        }
    }

    /// Runs the compile schedule: robots whose description changed get a new model.
    pub fn compile(&mut self) {
        self.compile.run(&mut self.world);
    }

    /// Compiles edited robots, then runs one fixed step. The compile
    /// schedule is skipped when its [`CompileGate`] sees nothing it could
    /// act on (no edit, removal, configuration or ground change, payload
    /// event due since the last check), the usual case between two steps.
    pub fn step(&mut self) {
        if self.compile_gate.due(&self.world) {
            self.compile.run(&mut self.world);
        }
        self.step.run(&mut self.world);
    }

    /// Runs `steps` fixed steps.
    pub fn run(&mut self, steps: u64) {
        let pool = self.world.resource::<SimThreadPool>().shared();
        pool.install(|| {
            for _ in 0..steps {
                self.step();
            }
        });
    }

    /// The step schedule, to add systems to the [`crate::SimSystems`] sets.
    pub fn step_schedule_mut(&mut self) -> &mut Schedule {
        &mut self.step
    }

    /// Runs the step schedule alone, without compiling first (tests of the
    /// "never compile inside a step" rule).
    pub fn run_step_schedule(&mut self) {
        self.step.run(&mut self.world);
    }

    /// The clock.
    pub fn clock(&self) -> SimClock {
        *self.world.resource::<SimClock>()
    }

    /// The packed state of a compiled robot.
    pub fn robot(&self, root: Entity) -> Option<&RobotSim> {
        let index = *self.world.get::<RobotIndex>(root)?;
        self.world.resource::<RobotBatch>().get(index)
    }

    /// The packed state of a compiled robot, mutably (set `q`, `v`, `tau_actuator`).
    pub fn robot_mut(&mut self, root: Entity) -> Option<&mut RobotSim> {
        let index = *self.world.get::<RobotIndex>(root)?;
        self.world
            .resource_mut::<RobotBatch>()
            .into_inner()
            .get_mut(index)
    }

    /// Copies link poses to the link entities now, whatever the [`PoseSync`] rate.
    pub fn sync_link_poses(&mut self) {
        self.world
            .run_system_once(sync_link_poses)
            .expect("sync_link_poses only needs resources the simulation inserts");
    }
}
