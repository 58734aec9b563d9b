//! The publishing side: a [`LogSink`] of the monitor channel that writes each
//! sampled instant as one slice sample of `n_robots` [`RobotFrame`]s into
//! shared memory, and the world header (JSON) on every robot-list record.

use std::any::Any;
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use iceoryx2::port::publisher::{Publisher, PublisherCreateError};
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenOrCreateError;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use quadsim_systems::{LogRecord, LogSink, Records, RobotInfo, SampleView, ViewRecord};
use serde_json::json;

use super::frame::{LAYOUT_VERSION, MAX_DOF, MAX_FEET, RobotFrame, TYPE_NAME};
use super::scene::{RobotPlan, SceneMessage};
use super::service::{
    MAX_SUBSCRIBERS, MonitorError, SUBSCRIBER_BUFFER_FRAMES, cleanup_dead_nodes, frames_service,
    header_service, node_name, scene_service, service_name,
};
use crate::log::encode::{GroundMesh, encode_scene};

/// What a live 3D view shows besides the robots: the ground as a mesh and
/// the scenario's terrain description (the log's `/scene` and `/terrain`).
#[derive(Debug, Clone, Default)]
pub struct WorldScene {
    /// The ground mesh of the log's `/scene`.
    pub ground: GroundMesh,
    /// The log's `/terrain` message (JSON text; empty: none).
    pub terrain: String,
}

/// Counts of a publisher, shared with the run for its report.
#[derive(Debug, Default)]
pub struct MonitorStats {
    /// Instants published (one slice sample each).
    pub published: AtomicU64,
    /// Instants dropped because no sample could be loaned or sent.
    pub dropped: AtomicU64,
}

impl MonitorStats {
    /// Published instants.
    pub fn published(&self) -> u64 {
        self.published.load(Ordering::Relaxed)
    }

    /// Dropped instants.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
}

type Svc = ipc_threadsafe::Service;

/// Publishes one world's frames and header.
pub struct FramePublisher {
    // ports before the node: they must drop first
    frames: Publisher<Svc, [RobotFrame], ()>,
    header: Publisher<Svc, [u8], ()>,
    scene: Publisher<Svc, [u8], ()>,
    frames_service: PortFactory<Svc, [RobotFrame], ()>,
    scene_service: PortFactory<Svc, [u8], ()>,
    _node: Node<Svc>,
    world: String,
    dt_s: f64,
    every_steps: u64,
    /// Model of each robot by instance name (the scenario's `robots[].model`).
    models: Vec<(String, String)>,
    stats: Arc<MonitorStats>,
    world_scene: WorldScene,
    /// The last robot list and its time (ns), kept to send the scene again
    /// to a viewer that subscribes later.
    robots: Mutex<Option<(u64, Vec<RobotInfo>)>>,
    /// Scenes sent.
    scenes: AtomicU64,
    /// Subscribers of the scene service when it was last sent.
    scene_readers: AtomicUsize,
}

impl std::fmt::Debug for FramePublisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FramePublisher")
            .field("world", &self.world)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl FramePublisher {
    /// Creates the services `quadsim/<world>/frames`, `…/header` and
    /// `…/scene` for `n_robots` robots, after removing what dead processes
    /// left behind, and their publishers.
    ///
    /// A service that already exists is opened: readers of an ended world
    /// of the same name (a dashboard, a Foxglove bridge) still hold its
    /// services, and they keep them across worlds (issue 30); they see the
    /// new world's header and scene. A world of that name that is still
    /// running is an error naming it (each service takes one publisher).
    pub fn create(
        world: &str,
        n_robots: usize,
        dt_s: f64,
        every_steps: u64,
        models: Vec<(String, String)>,
    ) -> Result<Self, MonitorError> {
        let fail = |what: &str, e: &dyn std::fmt::Debug| MonitorError {
            message: format!("world '{world}': {what}: {e:?}"),
        };
        let node = NodeBuilder::new()
            .name(&node_name("quadsim-run")?)
            // quadsim handles Ctrl-C itself (log/interrupt.rs)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .map_err(|e| fail("cannot create an iceoryx2 node", &e))?;
        cleanup_dead_nodes::<Svc>();
        // the header first: a reader that sees the frames service finds it
        let header = node
            .service_builder(&service_name(&header_service(world))?)
            .publish_subscribe::<[u8]>()
            .max_publishers(1)
            .max_subscribers(MAX_SUBSCRIBERS)
            .subscriber_max_buffer_size(2)
            .history_size(1)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| open_or_create_error(world, "header", e))?
            .publisher_builder()
            .initial_max_slice_len(4096)
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .create()
            .map_err(|e| publisher_error(world, "header", e))?;
        let scene_service = node
            .service_builder(&service_name(&scene_service(world))?)
            .publish_subscribe::<[u8]>()
            .max_publishers(1)
            .max_subscribers(MAX_SUBSCRIBERS)
            .subscriber_max_buffer_size(4)
            .history_size(2)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| open_or_create_error(world, "scene", e))?;
        let scene = scene_service
            .publisher_builder()
            .initial_max_slice_len(64 * 1024)
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .create()
            .map_err(|e| publisher_error(world, "scene", e))?;
        let frames_service = node
            .service_builder(&service_name(&frames_service(world))?)
            .publish_subscribe::<[RobotFrame]>()
            .max_publishers(1)
            .max_subscribers(MAX_SUBSCRIBERS)
            .subscriber_max_buffer_size(SUBSCRIBER_BUFFER_FRAMES)
            .history_size(0)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| open_or_create_error(world, "frames", e))?;
        let frames = frames_service
            .publisher_builder()
            .initial_max_slice_len(n_robots.max(1))
            .allocation_strategy(AllocationStrategy::Static)
            .max_loaned_samples(1)
            .create()
            .map_err(|e| publisher_error(world, "frames", e))?;
        Ok(Self {
            frames,
            header,
            scene,
            frames_service,
            scene_service,
            _node: node,
            world: world.to_string(),
            dt_s,
            every_steps,
            models,
            stats: Arc::default(),
            world_scene: WorldScene::default(),
            robots: Mutex::new(None),
            scenes: AtomicU64::new(0),
            scene_readers: AtomicUsize::new(0),
        })
    }

    /// Shows `scene` (ground, terrain) to live 3D viewers.
    pub fn with_scene(mut self, scene: WorldScene) -> Self {
        self.world_scene = scene;
        self
    }

    /// Subscribers of the frames service now (readers, dashboards, bridges,
    /// lockstep commanders).
    pub fn frame_subscribers(&self) -> usize {
        self.frames_service.dynamic_config().number_of_subscribers()
    }

    /// Sends the scene again when a viewer subscribed since it was last sent.
    pub fn refresh_scene(&self) {
        let readers = self.scene_service.dynamic_config().number_of_subscribers();
        let before = self.scene_readers.swap(readers, Ordering::Relaxed);
        if readers > before {
            let _ = self.scene.update_connections();
            let robots = self.robots.lock().map(|r| r.clone()).unwrap_or(None);
            if let Some((t_ns, robots)) = robots {
                self.publish_scene(t_ns, &robots);
            }
        }
    }

    /// Sends the scene of `robots` (the robot list at `t_ns`) to viewers:
    /// each robot's link plan, the log's `/scene` and `/terrain` messages.
    /// Encoded only when a viewer is subscribed.
    fn publish_scene(&self, t_ns: u64, robots: &[RobotInfo]) {
        let readers = self.scene_service.dynamic_config().number_of_subscribers();
        self.scene_readers.store(readers, Ordering::Relaxed);
        if readers == 0 {
            return;
        }
        let version = self.scenes.fetch_add(1, Ordering::Relaxed);
        let mut scene = Vec::new();
        encode_scene(
            robots,
            &self.world_scene.ground,
            t_ns,
            version > 0,
            &mut scene,
        );
        let msg = SceneMessage::Scene {
            version,
            t_ns,
            robots: robots
                .iter()
                .map(|r| RobotPlan::new(&r.name, &r.model, r.joint_names(), r.foot_names()))
                .collect(),
            scene: String::from_utf8(scene).unwrap_or_default(),
            terrain: self.world_scene.terrain.clone(),
        };
        self.send_scene_message(&msg);
    }

    /// Sends each robot's final metrics (`(robot, JSON text)`, made by
    /// `robots` only when a viewer is subscribed) to viewers.
    pub fn publish_metrics(&self, t_ns: u64, robots: impl FnOnce() -> Vec<(String, String)>) {
        let _ = self.scene.update_connections();
        if self.scene_service.dynamic_config().number_of_subscribers() == 0 {
            return;
        }
        let robots = robots();
        self.send_scene_message(&SceneMessage::Metrics { t_ns, robots });
    }

    fn send_scene_message(&self, msg: &SceneMessage) {
        let Ok(bytes) = serde_json::to_vec(msg) else {
            return;
        };
        let _ = self.scene.update_connections();
        let Ok(sample) = self.scene.loan_slice_uninit(bytes.len()) else {
            self.stats.dropped.fetch_add(1, Ordering::Relaxed);
            return;
        };
        if sample.write_from_slice(&bytes).send().is_err() {
            self.stats.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// The counters (shared).
    pub fn stats(&self) -> Arc<MonitorStats> {
        self.stats.clone()
    }

    /// The monitor's publish tick: sends the instant `frames` (one per
    /// robot, written beforehand, [`RobotFrame::set_from_view`]) as one
    /// slice sample: one loan, each frame copied into it (the one write into
    /// shared memory), one send. A failed loan or send drops the instant and
    /// counts it.
    pub fn publish_frames<'a>(&self, frames: impl ExactSizeIterator<Item = &'a RobotFrame>) {
        // late subscribers of the header get its last sample (history 1)
        let _ = self.header.update_connections();
        let Ok(sample) = self.frames.loan_slice_uninit(frames.len()) else {
            self.stats.dropped.fetch_add(1, Ordering::Relaxed);
            return;
        };
        let mut frames = frames.copied();
        let sample = sample.write_from_fn(|_| frames.next().expect("as many frames as loaned"));
        match sample.send() {
            Ok(_) => self.stats.published.fetch_add(1, Ordering::Relaxed),
            Err(_) => self.stats.dropped.fetch_add(1, Ordering::Relaxed),
        };
    }

    /// Simulation time of step index `tick` (s), as frames carry it.
    #[inline]
    pub fn time_s(&self, tick: u64) -> f64 {
        tick as f64 * self.dt_s
    }

    /// Publishes the header describing `robots` (JSON, see docs/monitor.md),
    /// and their scene to live 3D viewers (when one is subscribed).
    pub fn publish_header_at(&self, t_ns: u64, robots: &[RobotInfo]) {
        self.publish_header(robots);
        if let Ok(mut last) = self.robots.lock() {
            *last = Some((t_ns, robots.to_vec()));
        }
        self.publish_scene(t_ns, robots);
    }

    /// Publishes the header describing `robots` (JSON, see docs/monitor.md).
    pub fn publish_header(&self, robots: &[RobotInfo]) {
        let header = json!({
            "layout_version": LAYOUT_VERSION,
            "type_name": TYPE_NAME,
            "frame_size_bytes": std::mem::size_of::<RobotFrame>(),
            "max_dof": MAX_DOF,
            "max_feet": MAX_FEET,
            "world": self.world,
            "dt_s": self.dt_s,
            "every_steps": self.every_steps,
            "pid": std::process::id(),
            "robots": robots.iter().enumerate().map(|(i, r)| json!({
                "index": i,
                "name": r.name,
                "model": self.models.iter().find(|(n, _)| n == &r.name)
                    .map_or(r.description.name.as_str(), |(_, m)| m.as_str()),
                "dof": r.model.actuated_nv() - r.model.base_nv(),
                "joints": r.joint_names(),
                "feet": r.foot_names(),
            })).collect::<Vec<_>>(),
        });
        let bytes = serde_json::to_vec(&header).expect("json");
        let Ok(sample) = self.header.loan_slice_uninit(bytes.len()) else {
            self.stats.dropped.fetch_add(1, Ordering::Relaxed);
            return;
        };
        let sample = sample.write_from_slice(&bytes);
        if sample.send().is_err() {
            self.stats.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Connects subscribers that came since the last publish tick (a late
    /// subscriber then gets the header at once, e.g. while a lockstep run
    /// waits for its first command).
    pub fn refresh(&self) {
        let _ = self.header.update_connections();
    }
}

/// The error of opening or creating one of `world`'s services (`what`:
/// frames, header, scene).
fn open_or_create_error(
    world: &str,
    what: &str,
    e: PublishSubscribeOpenOrCreateError,
) -> MonitorError {
    use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError as Open;
    MonitorError::new(match e {
        PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(Open::IncompatibleTypes) => {
            format!(
                "world '{world}': its {what} service exists with another payload type \
                 (a world of another quadsim version, layout {TYPE_NAME} v{LAYOUT_VERSION} here); \
                 choose another --world-name"
            )
        }
        PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(e) => format!(
            "world '{world}': its {what} service exists with other settings ({e:?}); \
             choose another --world-name"
        ),
        e => format!("world '{world}': cannot create the {what} service: {e:?}"),
    })
}

/// The error of creating the publisher of one of `world`'s services.
fn publisher_error(world: &str, what: &str, e: PublisherCreateError) -> MonitorError {
    MonitorError::new(match e {
        PublisherCreateError::ExceedsMaxSupportedPublishers => format!(
            "world '{world}' is being published by another running quadsim \
             (its {what} service has its one publisher); choose another --world-name"
        ),
        e => format!("world '{world}': cannot create the {what} publisher: {e:?}"),
    })
}

/// The monitor channel's sink (see [`quadsim_systems::MonitorChannel`]). It
/// keeps one [`RobotFrame`] per robot as its record
/// ([`LogSink::takes_records`]): the sampling writes each robot's frame in
/// place from its view on the thread pool, right after preparing the robot,
/// and the publish tick ([`FramePublisher::publish_frames`]) only copies the
/// ready frames into shared memory.
#[derive(Debug)]
pub struct MonitorSink {
    publisher: Arc<FramePublisher>,
}

impl MonitorSink {
    /// A sink publishing through `publisher`.
    pub fn new(publisher: Arc<FramePublisher>) -> Self {
        Self { publisher }
    }
}

/// The frame in a record the sink made.
fn frame_of(record: &(dyn Any + Send + Sync)) -> &RobotFrame {
    record
        .downcast_ref()
        .expect("MonitorSink::new_record made a RobotFrame")
}

impl LogSink for MonitorSink {
    fn takes_records(&self) -> bool {
        true
    }

    fn new_record(&self) -> ViewRecord {
        Box::new(RobotFrame::default())
    }

    #[inline]
    fn write_record(&self, record: &mut ViewRecord, step: u64, view: &SampleView<'_>) {
        let frame: &mut RobotFrame = record
            .downcast_mut()
            .expect("MonitorSink::new_record made a RobotFrame");
        frame.set_from_view(view, step, self.publisher.time_s(step));
    }

    fn send_records(&mut self, _t_ns: u64, _step: u64, records: Records<'_>) {
        self.publisher.publish_frames(records.map(frame_of));
    }

    /// Frames carry the feet's contacts only.
    fn feet_contacts_only(&self) -> bool {
        true
    }

    fn send(&mut self, record: LogRecord) {
        match record {
            LogRecord::Robots { robots, t_ns } => self.publisher.publish_header_at(t_ns, &robots),
            // never sent: the sink takes records (`send_records`)
            LogRecord::Step { .. } => {}
        }
    }
}
