//! External control: tick-stamped per-robot commands on
//! `quadsim/<world>/commands`, received by the run before each controller
//! tick (docs/monitor.md, "External control").

// The ZeroCopySend derive emits an `unsafe impl` (plain old data).
#![allow(unsafe_code)]

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use quadsim_components::{ControlRate, Controller};
use quadsim_engine::control::vmc::VmcCommand;

use super::frame::MAX_DOF;
use super::service::{MonitorError, commands_service, node_name, service_name};
use crate::world::World;

/// Version of [`RobotCommand`]'s layout.
pub const COMMAND_LAYOUT_VERSION: u32 = 1;

/// [`RobotCommand::mode`]: joint targets with gains (and feed-forward torques).
pub const MODE_JOINT: u32 = 1;
/// [`RobotCommand::mode`]: joint torques only (`tau_ff_nm`; gains ignored).
pub const MODE_TORQUE: u32 = 2;
/// [`RobotCommand::mode`]: velocity command for the built-in walker (`kind = "vmc"`).
pub const MODE_VELOCITY: u32 = 3;

/// Commanders that may publish to one world at once.
pub const MAX_COMMANDERS: usize = 4;

/// One robot's command from tick `tick` on (held until the next). Layout in
/// docs/monitor.md; joints in velocity order (the header's `joints`).
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("quadsim.RobotCommand.v1")]
#[repr(C)]
pub struct RobotCommand {
    /// [`COMMAND_LAYOUT_VERSION`].
    pub layout_version: u32,
    /// Index of the robot in the world header's robot list.
    pub robot_index: u32,
    /// First step index the command applies to (a controller tick).
    pub tick: u64,
    /// [`MODE_JOINT`], [`MODE_TORQUE`] or [`MODE_VELOCITY`].
    pub mode: u32,
    /// Joints filled in (must equal the robot's DOF for joint and torque modes).
    pub n_dof: u32,
    /// Target joint angles (rad).
    pub q_target_rad: [f64; MAX_DOF],
    /// Target joint velocities (rad/s).
    pub qd_target_radps: [f64; MAX_DOF],
    /// Proportional gains (N·m/rad).
    pub kp_nm_per_rad: [f64; MAX_DOF],
    /// Derivative gains (N·m·s/rad).
    pub kd_nms_per_rad: [f64; MAX_DOF],
    /// Feed-forward joint torques (N·m).
    pub tau_ff_nm: [f64; MAX_DOF],
    /// Walker velocity command: forward (m/s), lateral (m/s, to the left),
    /// yaw rate (rad/s, counter-clockwise), heading frame.
    pub velocity: [f64; 3],
}

impl Default for RobotCommand {
    /// A zero joint command of the current layout for robot 0 at tick 0.
    fn default() -> Self {
        Self {
            layout_version: COMMAND_LAYOUT_VERSION,
            robot_index: 0,
            tick: 0,
            mode: MODE_JOINT,
            n_dof: 0,
            q_target_rad: [0.0; MAX_DOF],
            qd_target_radps: [0.0; MAX_DOF],
            kp_nm_per_rad: [0.0; MAX_DOF],
            kd_nms_per_rad: [0.0; MAX_DOF],
            tau_ff_nm: [0.0; MAX_DOF],
            velocity: [0.0; 3],
        }
    }
}

type Svc = ipc_threadsafe::Service;

/// Counts of the command receiver.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CommandStats {
    /// Commands applied to a robot.
    pub applied: u64,
    /// Commands rejected (unknown robot, wrong mode for its controller,
    /// wrong DOF, other layout version).
    pub rejected: u64,
}

/// The run's end of the commands service.
pub struct CommandReceiver {
    subscriber: Subscriber<Svc, [RobotCommand], ()>,
    port_factory:
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<Svc, [RobotCommand], ()>,
    _node: Node<Svc>,
    service: String,
    /// Wait for every external robot's command at each controller tick.
    lockstep: Option<Duration>,
    pending: Vec<VecDeque<RobotCommand>>,
    applied_tick: Vec<Option<u64>>,
    stats: CommandStats,
    warned: bool,
}

impl std::fmt::Debug for CommandReceiver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CommandReceiver")
            .field("service", &self.service)
            .field("lockstep", &self.lockstep)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl CommandReceiver {
    /// Creates (or opens, when readers of an ended world of the same name
    /// hold it) `quadsim/<world>/commands` for `n_robots` robots; with
    /// `lockstep`, [`Self::before_step`] waits up to that long per tick.
    pub fn create(
        world: &str,
        n_robots: usize,
        lockstep: Option<Duration>,
    ) -> Result<Self, MonitorError> {
        let service = commands_service(world);
        let fail = |what: &str, e: &dyn std::fmt::Debug| MonitorError {
            message: format!("{service}: {what}: {e:?}"),
        };
        let node = NodeBuilder::new()
            .name(&node_name("quadsim-run-commands")?)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .map_err(|e| fail("cannot create an iceoryx2 node", &e))?;
        let port_factory = node
            .service_builder(&service_name(&service)?)
            .publish_subscribe::<[RobotCommand]>()
            .max_publishers(MAX_COMMANDERS)
            .max_subscribers(1)
            .subscriber_max_buffer_size(256)
            .history_size(0)
            .enable_safe_overflow(true)
            // a commander of an ended world of the same name may still hold
            // the service: it is opened, as the monitor's are (issue 30)
            .open_or_create()
            .map_err(|e| fail("cannot open or create the service", &e))?;
        let subscriber = port_factory
            .subscriber_builder()
            .create()
            .map_err(|e| match e {
                iceoryx2::port::subscriber::SubscriberCreateError::ExceedsMaxSupportedSubscribers => {
                    MonitorError::new(format!(
                        "{service}: another running quadsim takes this world's commands; \
                         choose another --world-name"
                    ))
                }
                e => fail("cannot create the subscriber", &e),
            })?;
        Ok(Self {
            subscriber,
            port_factory,
            _node: node,
            service,
            lockstep,
            pending: vec![VecDeque::new(); n_robots],
            applied_tick: vec![None; n_robots],
            stats: CommandStats::default(),
            warned: false,
        })
    }

    /// Whether commands must be looked for before every step: in
    /// lockstep, or while a commander is connected. Otherwise the run
    /// steps in passes of several steps (stepping one at a time for
    /// commands nobody sends cost a herd half its speed, issue 29 item 8).
    pub fn active(&self) -> bool {
        use iceoryx2::service::port_factory::PortFactory as _;
        self.lockstep.is_some() || self.port_factory.dynamic_config().number_of_publishers() > 0
    }

    /// Counts so far.
    pub fn stats(&self) -> CommandStats {
        self.stats
    }

    fn reject(&mut self, why: String) {
        self.stats.rejected += 1;
        if !self.warned {
            eprintln!(
                "warning: {}: command rejected: {why} (further rejections are only counted)",
                self.service
            );
            self.warned = true;
        }
    }

    /// Queues every command received so far.
    fn drain(&mut self) -> Result<(), MonitorError> {
        loop {
            let sample = self.subscriber.receive().map_err(|e| MonitorError {
                message: format!("{}: receive: {e:?}", self.service),
            })?;
            let Some(sample) = sample else {
                return Ok(());
            };
            for c in sample.payload() {
                if c.layout_version != COMMAND_LAYOUT_VERSION {
                    self.reject(format!(
                        "layout version {} (this run reads {COMMAND_LAYOUT_VERSION})",
                        c.layout_version
                    ));
                } else if let Some(q) = self.pending.get_mut(c.robot_index as usize) {
                    q.push_back(*c);
                } else {
                    self.reject(format!("no robot with index {}", c.robot_index));
                }
            }
        }
    }

    /// Before the step starting at the current tick: on controller ticks,
    /// applies each robot's latest command stamped at or before the tick
    /// (later ones wait); in lockstep, first waits until every robot with
    /// `kind = "external"` has one stamped exactly at this tick.
    pub fn before_step(
        &mut self,
        world: &mut World,
        monitor: Option<&super::run::RunMonitor>,
    ) -> Result<(), MonitorError> {
        let k = world.sim.clock().step;
        let every = world
            .sim
            .world
            .get_resource::<ControlRate>()
            .map_or(1, |c| c.every_steps.max(1));
        if !k.is_multiple_of(every) {
            return Ok(());
        }
        let start = Instant::now();
        let mut spins = 0u32;
        loop {
            self.drain()?;
            self.apply_due(world, k);
            let Some(timeout) = self.lockstep else {
                return Ok(());
            };
            let missing = world.robots.iter().enumerate().find(|(i, (_, e))| {
                world
                    .sim
                    .robot(*e)
                    .is_some_and(|r| matches!(r.run.controller, Controller::External(_)))
                    && self.applied_tick[*i] != Some(k)
            });
            let Some((i, (name, _))) = missing else {
                return Ok(());
            };
            if start.elapsed() >= timeout {
                return Err(MonitorError {
                    message: format!(
                        "lockstep: no command for robot '{name}' (index {i}) at tick {k} \
                         (t = {} s) within {:.3} s on {}",
                        k as f64 * world.dt_s,
                        timeout.as_secs_f64(),
                        self.service
                    ),
                });
            }
            // a commander attaching now needs the header to answer
            if let Some(m) = monitor {
                m.refresh();
            }
            // a commander answers within microseconds: spin briefly, then sleep
            spins += 1;
            if spins < 200 {
                std::thread::yield_now();
            } else {
                std::thread::sleep(Duration::from_micros(50));
            }
        }
    }

    fn apply_due(&mut self, world: &mut World, k: u64) {
        for i in 0..self.pending.len() {
            let mut latest = None;
            while self.pending[i].front().is_some_and(|c| c.tick <= k) {
                latest = self.pending[i].pop_front();
            }
            let Some(c) = latest else { continue };
            let Some(&(ref name, entity)) = world.robots.get(i) else {
                continue;
            };
            let name = name.clone();
            let Some(sim) = world.sim.robot_mut(entity) else {
                continue;
            };
            let nj = sim.model.actuated_nv() - sim.model.base_nv();
            let result = match (&mut sim.run.controller, c.mode) {
                (Controller::External(e), MODE_JOINT | MODE_TORQUE) => {
                    if c.n_dof as usize != nj {
                        Err(format!(
                            "robot '{name}' has {nj} joints, the command {}",
                            c.n_dof
                        ))
                    } else {
                        let torque = c.mode == MODE_TORQUE;
                        e.target_rad.copy_from_slice(&c.q_target_rad[..nj]);
                        e.target_radps.copy_from_slice(&c.qd_target_radps[..nj]);
                        e.feedforward_nm.copy_from_slice(&c.tau_ff_nm[..nj]);
                        for j in 0..nj {
                            e.kp_nm_per_rad[j] = if torque { 0.0 } else { c.kp_nm_per_rad[j] };
                            e.kd_nms_per_rad[j] = if torque { 0.0 } else { c.kd_nms_per_rad[j] };
                        }
                        e.tick = Some(c.tick);
                        Ok(())
                    }
                }
                (Controller::Walker(w), MODE_VELOCITY) => {
                    w.set_command(VmcCommand {
                        forward_mps: c.velocity[0],
                        lateral_mps: c.velocity[1],
                        yaw_rate_radps: c.velocity[2],
                    });
                    Ok(())
                }
                (_, m) => Err(format!(
                    "mode {m} does not fit robot '{name}''s controller (joint and torque \
                     commands need kind = \"external\", velocity commands kind = \"vmc\")"
                )),
            };
            match result {
                Ok(()) => {
                    self.applied_tick[i] = Some(c.tick);
                    self.stats.applied += 1;
                }
                Err(why) => self.reject(why),
            }
        }
    }
}

/// A commander's end of `quadsim/<world>/commands` (for Rust programs and tests).
pub struct CommandSender {
    publisher: Publisher<Svc, [RobotCommand], ()>,
    _node: Node<Svc>,
}

impl std::fmt::Debug for CommandSender {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CommandSender").finish_non_exhaustive()
    }
}

impl CommandSender {
    /// Opens the commands service of a running `world` (`Ok(None)`: not there).
    pub fn open(world: &str, max_robots: usize) -> Result<Option<Self>, MonitorError> {
        use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
        let node = NodeBuilder::new()
            .name(&node_name("quadsim-commander")?)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .map_err(|e| MonitorError {
                message: format!("cannot create an iceoryx2 node: {e:?}"),
            })?;
        let service = match node
            .service_builder(&service_name(&commands_service(world))?)
            .publish_subscribe::<[RobotCommand]>()
            .open()
        {
            Ok(s) => s,
            Err(PublishSubscribeOpenError::DoesNotExist) => return Ok(None),
            Err(e) => {
                return Err(MonitorError {
                    message: format!("cannot open the commands of world '{world}': {e:?}"),
                });
            }
        };
        let publisher = service
            .publisher_builder()
            .initial_max_slice_len(max_robots.max(1))
            .create()
            .map_err(|e| MonitorError {
                message: format!("cannot publish commands to world '{world}': {e:?}"),
            })?;
        Ok(Some(Self {
            publisher,
            _node: node,
        }))
    }

    /// Sends commands (one sample).
    pub fn send(&self, commands: &[RobotCommand]) -> Result<(), MonitorError> {
        let sample = self
            .publisher
            .loan_slice_uninit(commands.len())
            .map_err(|e| MonitorError {
                message: format!("cannot loan a command sample: {e:?}"),
            })?;
        sample
            .write_from_slice(commands)
            .send()
            .map(|_| ())
            .map_err(|e| MonitorError {
                message: format!("cannot send commands: {e:?}"),
            })
    }
}
