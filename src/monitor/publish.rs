//! The publishing side: a [`LogSink`] of the monitor channel that writes each
//! sampled instant as one slice sample of `n_robots` [`RobotFrame`]s into
//! shared memory, and the world header (JSON) on every robot-list record.

use std::any::Any;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use quadsim_systems::{LogRecord, LogSink, Records, RobotInfo, SampleView, ViewRecord};
use serde_json::json;

use super::frame::{LAYOUT_VERSION, MAX_DOF, MAX_FEET, RobotFrame, TYPE_NAME};
use super::service::{
    MAX_SUBSCRIBERS, MonitorError, SUBSCRIBER_BUFFER_FRAMES, cleanup_dead_nodes, frames_service,
    header_service, node_name, service_name,
};

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
    _node: Node<Svc>,
    world: String,
    dt_s: f64,
    every_steps: u64,
    /// Model of each robot by instance name (the scenario's `robots[].model`).
    models: Vec<(String, String)>,
    stats: Arc<MonitorStats>,
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
    /// Creates the services `quadsim/<world>/frames` and `quadsim/<world>/header`
    /// for `n_robots` robots, after removing what dead processes left behind.
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
        let header_name = service_name(&header_service(world))?;
        let header = node
            .service_builder(&header_name)
            .publish_subscribe::<[u8]>()
            .max_publishers(1)
            .max_subscribers(MAX_SUBSCRIBERS)
            .subscriber_max_buffer_size(2)
            .history_size(1)
            .enable_safe_overflow(true)
            .create()
            .map_err(|e| fail("cannot create the header service", &e))?
            .publisher_builder()
            .initial_max_slice_len(4096)
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .create()
            .map_err(|e| fail("cannot create the header publisher", &e))?;
        let frames_name = service_name(&frames_service(world))?;
        let frames = node
            .service_builder(&frames_name)
            .publish_subscribe::<[RobotFrame]>()
            .max_publishers(1)
            .max_subscribers(MAX_SUBSCRIBERS)
            .subscriber_max_buffer_size(SUBSCRIBER_BUFFER_FRAMES)
            .history_size(0)
            .enable_safe_overflow(true)
            .create()
            .map_err(|e| fail("cannot create the frames service", &e))?
            .publisher_builder()
            .initial_max_slice_len(n_robots.max(1))
            .allocation_strategy(AllocationStrategy::Static)
            .max_loaned_samples(1)
            .create()
            .map_err(|e| fail("cannot create the frames publisher", &e))?;
        Ok(Self {
            frames,
            header,
            _node: node,
            world: world.to_string(),
            dt_s,
            every_steps,
            models,
            stats: Arc::default(),
        })
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
            LogRecord::Robots { robots, .. } => self.publisher.publish_header(&robots),
            // never sent: the sink takes records (`send_records`)
            LogRecord::Step { .. } => {}
        }
    }
}
