//! The names of a world's shared-memory services, their limits, and the
//! monitor's error.

use iceoryx2::prelude::*;
use thiserror::Error;

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
    pub(crate) fn new(message: impl Into<String>) -> Self {
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

pub(crate) fn service_name(s: &str) -> Result<ServiceName, MonitorError> {
    ServiceName::new(s).map_err(|e| MonitorError::new(format!("invalid service name '{s}': {e:?}")))
}

pub(crate) fn node_name(s: &str) -> Result<NodeName, MonitorError> {
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
