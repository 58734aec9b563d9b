//! Live monitoring over shared memory (iceoryx2): a running `quadsim run`
//! publishes every robot's [`RobotFrame`] per publish tick and a JSON header
//! describing the world; `quadsim monitor` and other processes (Python, C)
//! subscribe. See `docs/monitor.md`.

pub mod command;
pub mod frame;
pub mod publish;
pub mod scene;
pub mod subscribe;

use std::sync::Arc;

use bevy_ecs::entity::Entity;
use iceoryx2::prelude::*;
use thiserror::Error;

pub use command::{CommandReceiver, CommandSender, CommandStats, RobotCommand};
pub use frame::{LAYOUT_VERSION, MAX_DOF, MAX_FEET, RobotFrame, TYPE_NAME};
pub use publish::{FramePublisher, MonitorSink, MonitorStats, WorldScene};
pub use scene::{RobotPlan, SceneMessage};
pub use subscribe::{FrameReader, SceneReader, list_worlds};

/// Subscribers a world's services accept at once.
pub const MAX_SUBSCRIBERS: usize = 16;

/// Instants a subscriber's queue holds; when full, the oldest is discarded
/// (safe overflow): a slow or idle subscriber never blocks the simulation.
pub const SUBSCRIBER_BUFFER_FRAMES: usize = 8;

/// Service-name prefix of every world.
pub const SERVICE_PREFIX: &str = "quadsim/";

/// An error of the monitor's shared-memory services.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("monitor: {message}")]
pub struct MonitorError {
    /// What went wrong.
    pub message: String,
}

impl MonitorError {
    fn new(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
        }
    }
}

/// `quadsim/<world>/frames`.
pub fn frames_service(world: &str) -> String {
    format!("{SERVICE_PREFIX}{world}/frames")
}

/// `quadsim/<world>/commands`.
pub fn commands_service(world: &str) -> String {
    format!("{SERVICE_PREFIX}{world}/commands")
}

/// `quadsim/<world>/scene` (JSON [`SceneMessage`]s for live 3D viewers).
pub fn scene_service(world: &str) -> String {
    format!("{SERVICE_PREFIX}{world}/scene")
}

/// `quadsim/<world>/header`.
pub fn header_service(world: &str) -> String {
    format!("{SERVICE_PREFIX}{world}/header")
}

fn service_name(s: &str) -> Result<ServiceName, MonitorError> {
    ServiceName::new(s).map_err(|e| MonitorError::new(format!("invalid service name '{s}': {e:?}")))
}

fn node_name(s: &str) -> Result<NodeName, MonitorError> {
    NodeName::new(s).map_err(|e| MonitorError::new(format!("invalid node name '{s}': {e:?}")))
}

/// Removes the shared-memory resources of nodes whose process died (a
/// crashed run), so their worlds are not listed and their names are free.
pub fn cleanup_dead_nodes<S: iceoryx2::service::Service>() {
    let _ = Node::<S>::list(Config::global_config(), |state| {
        if let NodeState::Dead(view) = state {
            let _ = view.try_remove_stale_resources();
        }
        CallbackProgression::Continue
    });
}

/// Highest rate a monitor publishes at by default (Hz): enough for eyes,
/// plots and the Foxglove bridge; each instant costs the run a sample of
/// every robot (docs/monitor.md, "Cost").
pub const DEFAULT_RATE_HZ: f64 = 100.0;

/// Steps between published instants by default: the smallest multiple of
/// the controller period `control_every` (steps of `dt_s`) at or below
/// [`DEFAULT_RATE_HZ`] (20 steps at dt = 0.5 ms with a 500 Hz controller),
/// so every instant is a controller tick the log also samples.
pub fn default_every_steps(dt_s: f64, control_every: u64) -> u64 {
    let control_every = control_every.max(1);
    let period_s = dt_s * control_every as f64;
    let k = if period_s > 0.0 && period_s.is_finite() {
        (1.0 / (DEFAULT_RATE_HZ * period_s)).ceil().max(1.0) as u64
    } else {
        1
    };
    control_every.saturating_mul(k)
}

/// The default world name: `<scenario>-<pid>`.
pub fn default_world_name(scenario: &str) -> String {
    format!("{scenario}-{}", std::process::id())
}

/// A run's monitor: the sink lives in the simulation's
/// `Logger<MonitorChannel>` while someone watches; this keeps the counters.
///
/// Frames are sampled only while the frames service has a subscriber
/// ([`Self::poll`]): sampling costs the stepping loop its fused passes, so
/// a world nobody watches runs at `--no-monitor` speed (issue 29, item 8).
/// The header and the robot list are sent at the start either way.
#[derive(Debug)]
pub struct RunMonitor {
    /// World name.
    pub world: String,
    /// Steps between published instants.
    pub every_steps: u64,
    stats: Arc<MonitorStats>,
    publisher: Arc<FramePublisher>,
    followed: Vec<(Entity, bool)>,
    /// Whether the monitor's sampler is attached to the simulation.
    sampling: bool,
    /// Sample whether watched or not (lockstep: a commander answers frames).
    always: bool,
}

impl RunMonitor {
    /// Starts publishing `robots` of `world` every `every_steps` steps;
    /// `models` names each robot's model by instance name for the header.
    /// Errors (no shared memory, a name in use) leave the world untouched.
    pub fn start(
        sim: &mut bevy_ecs::world::World,
        world: &str,
        robots: &[Entity],
        models: Vec<(String, String)>,
        dt_s: f64,
        every_steps: u64,
    ) -> Result<Self, MonitorError> {
        Self::start_with(
            sim,
            world,
            robots,
            models,
            dt_s,
            every_steps,
            WorldScene::default(),
            true,
        )
    }

    /// [`Self::start`] showing `scene` to live 3D viewers; with `always`
    /// frames are sampled whether anyone watches or not, otherwise only
    /// while the frames service has a subscriber (checked by [`Self::poll`]).
    pub fn start_with(
        sim: &mut bevy_ecs::world::World,
        world: &str,
        robots: &[Entity],
        models: Vec<(String, String)>,
        dt_s: f64,
        every_steps: u64,
        scene: WorldScene,
        always: bool,
    ) -> Result<Self, MonitorError> {
        let publisher = FramePublisher::create(world, robots.len(), dt_s, every_steps, models)?
            .with_scene(scene);
        let stats = publisher.stats();
        let mut m = Self {
            world: world.to_string(),
            every_steps,
            stats,
            publisher: Arc::new(publisher),
            followed: robots.iter().map(|&e| (e, true)).collect(),
            sampling: false,
            always,
        };
        // the header (and robot list) goes out at once, watched or not
        m.attach(sim);
        m.poll(sim);
        Ok(m)
    }

    fn attach(&mut self, sim: &mut bevy_ecs::world::World) {
        quadsim_systems::start_sampling::<quadsim_systems::MonitorChannel>(
            sim,
            Box::new(MonitorSink::new(self.publisher.clone())),
            self.every_steps,
            &self.followed,
        );
        self.sampling = true;
    }

    /// Between steps: samples frames while someone subscribes to them
    /// (attaching the sampler when the first subscriber comes, detaching it
    /// when the last goes), and sends the scene to a viewer that subscribed
    /// since. Neither changes the simulation's bits.
    pub fn poll(&mut self, sim: &mut bevy_ecs::world::World) {
        let watched = self.always || self.publisher.frame_subscribers() > 0;
        if watched && !self.sampling {
            self.attach(sim);
        } else if !watched && self.sampling {
            drop(quadsim_systems::finish_sampling::<
                quadsim_systems::MonitorChannel,
            >(sim, false));
            self.sampling = false;
        }
        self.publisher.refresh_scene();
    }

    /// Serves subscribers that came since the last publish tick.
    pub fn refresh(&self) {
        self.publisher.refresh();
    }

    /// Sends each robot's final metrics (`(robot, JSON text)`, the log's
    /// `/<robot>/metrics`, made by `robots` only when a viewer is
    /// subscribed) to live viewers.
    pub fn publish_metrics(&self, t_ns: u64, robots: impl FnOnce() -> Vec<(String, String)>) {
        self.publisher.publish_metrics(t_ns, robots);
    }

    /// Stops publishing (no final sample: the log's final sample runs the
    /// controllers once more, which must happen once) and removes the services.
    pub fn finish(self, sim: &mut bevy_ecs::world::World) -> Arc<MonitorStats> {
        drop(self.publisher);
        if self.sampling {
            drop(quadsim_systems::finish_sampling::<
                quadsim_systems::MonitorChannel,
            >(sim, false));
        }
        self.stats
    }

    /// The counters so far.
    pub fn stats(&self) -> &MonitorStats {
        &self.stats
    }
}

#[cfg(test)]
mod rate_tests {
    use super::default_every_steps;

    #[test]
    fn the_default_rate_is_a_multiple_of_the_controller_period_at_most_100_hz() {
        // 500 Hz controller at 0.5 ms: every 4 steps; 100 Hz = every 20
        assert_eq!(default_every_steps(5e-4, 4), 20);
        // a 2 kHz controller (every step): 20 steps, 100 Hz
        assert_eq!(default_every_steps(5e-4, 1), 20);
        assert_eq!(default_every_steps(1e-3, 1), 10);
        // a controller slower than 100 Hz: its own period
        assert_eq!(default_every_steps(5e-4, 40), 40);
        // a 300 Hz controller: every third tick, 100 Hz
        assert_eq!(default_every_steps(1.0 / 3000.0, 10), 30);
    }
}
