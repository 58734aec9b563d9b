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

use crate::blocks::PassSteps;
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
    /// Whether the step schedule was handed out ([`Simulation::step_schedule_mut`]):
    /// systems may have been added that look at the world after every step.
    step_schedule_lent: bool,
    /// Runs of the step schedule so far.
    passes: u64,
}

/// The most steps [`Simulation::run`] takes the robots through in one pass
/// ([`PassSteps`]). Each block of robots is then fetched into the core's
/// cache once per pass rather than once per step. On the project machine
/// (`quadsim bench`, quad16 trotting, 1 thread) a robot-step at 1,000
/// robots cost 1.26–1.38× one at 64 with one step per pass, about 1.25×
/// with 8, 1.02–1.07× with 32 and 1.02–1.04× with 64. A herd larger than
/// the cache still fetches each robot's data (about 63 KiB for quad16) from
/// memory once per pass: 256 steps instead of 64 made 256 robots on 2
/// threads 1.9 % faster (median of six alternating pairs). Longer passes
/// would gain little more, and the caller checks for an interrupt between
/// passes (1000 quad16 take about 0.3 s for 256 steps on 2 threads).
pub const MAX_PASS_STEPS: u64 = 256;

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
            step_schedule_lent: false,
            passes: 0,
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
        self.run_pass(1);
    }

    /// Runs `steps` fixed steps, with the same result, bit for bit, as
    /// calling [`Simulation::step`] `steps` times.
    ///
    /// Where nothing outside the robots looks at the world between steps
    /// (no log or monitor sample, pose copy or payload event due, no system
    /// added to the schedule), one run of the step schedule takes the
    /// robots through up to [`MAX_PASS_STEPS`] steps ([`PassSteps`]): each
    /// block of robots stays in the core's cache for all of them, and the
    /// schedules' fixed cost is paid once.
    pub fn run(&mut self, steps: u64) {
        let pool = self.world.resource::<SimThreadPool>().shared();
        pool.install(|| {
            let mut left = steps;
            while left > 0 {
                left -= self.run_pass(left);
            }
        });
    }

    /// One run of the step schedule, after compiling edited robots (the
    /// [`CompileGate`] as in [`Simulation::step`], which is `run_pass(1)`):
    /// up to `max` steps (at least one, at most
    /// [`MAX_PASS_STEPS`]) as far as nothing outside the robots looks at the
    /// world in between; returns how many. The
    /// same bits as that many calls of [`Simulation::step`]. Call it inside
    /// the world's thread pool (as [`Simulation::run`] does) to spare the
    /// pool's entry per call.
    pub fn run_pass(&mut self, max: u64) -> u64 {
        let n = if self.compile_gate.due(&self.world) {
            self.compile.run(&mut self.world);
            1
        } else {
            self.quiet_steps(max.clamp(1, MAX_PASS_STEPS))
        };
        if n > 1 {
            self.world.insert_resource(PassSteps::new(n));
            self.step.run(&mut self.world);
            self.world.insert_resource(PassSteps::ONE);
        } else {
            self.step.run(&mut self.world);
        }
        self.passes += 1;
        n
    }

    /// How many of the next steps (1 to `max`) can run in one pass: the
    /// step schedule holds only its own systems, and after each step but
    /// the last no log or monitor sample ([`Logger`](crate::Logger)), no
    /// pose copy ([`PoseSync`]) and no payload event
    /// ([`PayloadEvents`](quadsim_components::PayloadEvents)) is due; the
    /// caller has checked that no compile is due before the first. Nothing
    /// else outside the robots changes between steps, so a robot meets the
    /// same calls with the same inputs as step by step.
    fn quiet_steps(&self, max: u64) -> u64 {
        if max <= 1 || self.step_schedule_lent {
            return 1;
        }
        let w = &self.world;
        let (Some(clock), Some(config)) =
            (w.get_resource::<SimClock>(), w.get_resource::<SimConfig>())
        else {
            return 1;
        };
        let pose = w.get_resource::<PoseSync>();
        let log = w.get_resource::<crate::Logger<crate::LogChannel>>();
        let monitor = w.get_resource::<crate::Logger<crate::MonitorChannel>>();
        let events = w
            .get_resource::<quadsim_components::PayloadEvents>()
            .filter(|e| e.applied < e.events.len());
        // steps after which the world is looked at (the Publish stage's
        // conditions, then the compile gate before the next step)
        let busy = |step: u64| {
            pose.is_some_and(|p| p.due(step))
                || log.is_some_and(|l| crate::log::logger_due(l, step))
                || monitor.is_some_and(|l| crate::log::logger_due(l, step))
                || events.is_some_and(|e| crate::payload::payload_due(e, step as f64 * config.dt_s))
        };
        let mut n = 1;
        while n < max && !busy(clock.step + n) {
            n += 1;
        }
        n
    }

    /// How many times the step schedule has run: once per
    /// [`Simulation::step`], once per pass of up to [`MAX_PASS_STEPS`] steps
    /// in [`Simulation::run`].
    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// The step schedule, to add systems to the [`crate::SimSystems`] sets.
    /// From then on [`Simulation::run`] runs the schedule once per step, as
    /// such systems may look at the world after every step.
    pub fn step_schedule_mut(&mut self) -> &mut Schedule {
        self.step_schedule_lent = true;
        &mut self.step
    }

    /// Runs the step schedule alone, without compiling first (tests of the
    /// "never compile inside a step" rule).
    pub fn run_step_schedule(&mut self) {
        self.step.run(&mut self.world);
        self.passes += 1;
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
