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

/// `quadsim/<world>/scene` (JSON [`SceneMessage`](super::scene::SceneMessage)s
/// for live 3D viewers).
pub fn scene_service(world: &str) -> String {
    format!("{SERVICE_PREFIX}{world}/scene")
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
