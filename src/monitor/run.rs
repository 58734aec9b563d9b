//! [`RunMonitor`]: a run's live publishing, from start to finish.

use std::sync::Arc;

use bevy_ecs::entity::Entity;

use super::publish::{FramePublisher, MonitorSink, MonitorStats, WorldScene};
use super::service::MonitorError;

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
