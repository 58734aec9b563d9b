//! [`RunMonitor`]: a run's live publishing, from start to finish.

use std::sync::Arc;

use bevy_ecs::entity::Entity;

use super::publish::{FramePublisher, MonitorSink, MonitorStats};
use super::service::MonitorError;

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
