//! Live monitoring over shared memory (iceoryx2): a running `quadsim run`
//! publishes every robot's [`RobotFrame`] per publish tick and a JSON header
//! describing the world; `quadsim monitor` and other processes (Python, C)
//! subscribe. See `docs/monitor.md`.

pub mod command;
pub mod frame;
pub mod publish;
pub mod subscribe;

use std::sync::Arc;

use bevy_ecs::entity::Entity;
use iceoryx2::prelude::*;
use thiserror::Error;

pub use command::{CommandReceiver, CommandSender, CommandStats, RobotCommand};
pub use frame::{LAYOUT_VERSION, MAX_DOF, MAX_FEET, RobotFrame, TYPE_NAME};
pub use publish::{FramePublisher, MonitorSink, MonitorStats};
pub use subscribe::{FrameReader, list_worlds};

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

/// The default world name: `<scenario>-<pid>`.
pub fn default_world_name(scenario: &str) -> String {
    format!("{scenario}-{}", std::process::id())
}

/// A run's monitor: the sink lives in the simulation's
/// `Logger<MonitorChannel>`; this keeps the counters.
#[derive(Debug)]
pub struct RunMonitor {
    /// World name.
    pub world: String,
    /// Steps between published instants.
    pub every_steps: u64,
    stats: Arc<MonitorStats>,
    publisher: Arc<FramePublisher>,
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
        let publisher = FramePublisher::create(world, robots.len(), dt_s, every_steps, models)?;
        let stats = publisher.stats();
        let publisher = Arc::new(publisher);
        let followed: Vec<(Entity, bool)> = robots.iter().map(|&e| (e, true)).collect();
        quadsim_systems::start_sampling::<quadsim_systems::MonitorChannel>(
            sim,
            Box::new(MonitorSink::new(publisher.clone())),
            every_steps,
            &followed,
        );
        Ok(Self {
            world: world.to_string(),
            every_steps,
            stats,
            publisher,
        })
    }

    /// Serves subscribers that came since the last publish tick.
    pub fn refresh(&self) {
        self.publisher.refresh();
    }

    /// Stops publishing (no final sample: the log's final sample runs the
    /// controllers once more, which must happen once) and removes the services.
    pub fn finish(self, sim: &mut bevy_ecs::world::World) -> Arc<MonitorStats> {
        drop(self.publisher);
        drop(quadsim_systems::finish_sampling::<
            quadsim_systems::MonitorChannel,
        >(sim, false));
        self.stats
    }

    /// The counters so far.
    pub fn stats(&self) -> &MonitorStats {
        &self.stats
    }
}
