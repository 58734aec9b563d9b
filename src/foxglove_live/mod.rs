//! The live Foxglove bridge (`quadsim monitor --foxglove`, `quadsim run
//! --foxglove`): subscribes to a running world over shared memory, as the
//! dashboard does, and serves it with the Foxglove WebSocket protocol on the
//! channels and schemas of `log.mcap`, so `docs/foxglove_layout.json` works
//! live and in replay. The simulation process does no network I/O unless
//! `run --foxglove` asks for it (then on threads of its own).
//!
//! - `/tf` (`foxglove.FrameTransforms`): every link, rebuilt from the
//!   frame's base pose and joint angles with each robot's link plan
//!   ([`crate::monitor::RobotPlan`]); the base link's transform is the
//!   frame's pose bit for bit, others as the log computes them;
//! - `/scene` (`foxglove.SceneUpdate`) and `/terrain`: the log's messages,
//!   as the run sent them; sent again when a client subscribes;
//! - `/<robot>/base_pose`, `base_twist`, `attitude`, `com`, `joint_states`,
//!   `joint_commands`, `feet`: the log's encoding of the frame's values
//!   (what a frame does not carry is NaN: the CoM's acceleration, the feet's
//!   penetration, normal force and contact point);
//! - `/<robot>/metrics`: at the end of a run.
//!
//! Not served live: `/<robot>/virtual_wrench` and `/<robot>/sensors` (a
//! frame does not carry them).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, WebSocketServer};
use glam::{DQuat, DVec3};
use quadsim_systems::{FootLog, RobotSample};

use crate::error::{CliError, bad};
use crate::log::encode::{RobotNames, RobotTopic, WORLD_FRAME, encode_robot, encode_transforms};
use crate::log::schema::Schema;
use crate::log::writer::{SCENE_TOPIC, TERRAIN_TOPIC, TF_TOPIC};
use crate::monitor::{
    FrameReader, RobotFrame, RobotPlan, SceneMessage, SceneReader, cleanup_dead_nodes, list_worlds,
};

/// Default port of the Foxglove WebSocket server (Foxglove's own default).
pub const DEFAULT_PORT: u16 = 8765;

/// Default rate of forwarded instants (Hz of simulated time): smooth in
/// Foxglove's 3D panel and plots, and light enough for a herd.
pub const DEFAULT_RATE_HZ: f64 = 100.0;

/// The per-robot channels a frame fills.
const LIVE_TOPICS: [RobotTopic; 7] = [
    RobotTopic::BasePose,
    RobotTopic::BaseTwist,
    RobotTopic::Attitude,
    RobotTopic::Com,
    RobotTopic::JointStates,
    RobotTopic::JointCommands,
    RobotTopic::Feet,
];

/// A quiet world (no instant) is checked for having ended (its frames
/// service has no publisher) after this long: a cheap read of shared
/// memory, often enough to see a world end before the next world of that
/// name starts (which is handled either way, [`Live::on_scene`]).
const QUIET_CHECK: Duration = Duration::from_millis(50);

/// A world quiet for this long is also checked for a dead run (killed, its
/// publisher never removed): dead nodes' resources are cleaned up, so its
/// publisher goes and the world is seen to end.
const DEAD_CHECK: Duration = Duration::from_secs(1);

/// Options of a bridge.
#[derive(Debug, Clone)]
pub struct BridgeOptions {
    /// The world to serve (`None`: the only running one, whichever comes).
    pub world: Option<String>,
    /// Address to bind (127.0.0.1 unless asked otherwise).
    pub host: String,
    /// Port (0: any free port; the one taken is printed).
    pub port: u16,
    /// Instants forwarded per second of simulated time (`None`: all).
    pub rate_hz: Option<f64>,
    /// Exit when the first world served ends (else wait for the next).
    pub once: bool,
}

/// Sets a flag when a client subscribes to a channel that carries rare
/// messages (`/scene`, `/terrain`, metrics), so the bridge sends them again.
#[derive(Debug, Default)]
struct Resend(AtomicBool);

impl ServerListener for Resend {
    fn on_subscribe(&self, _client: Client, channel: ChannelView) {
        let t = channel.topic();
        if t == SCENE_TOPIC || t == TERRAIN_TOPIC || t.ends_with("/metrics") {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

/// A running WebSocket server and its channels.
pub struct Server {
    ctx: Arc<Context>,
    handle: Option<foxglove::WebSocketServerHandle>,
    runtime: Option<tokio::runtime::Runtime>,
    resend: Arc<Resend>,
    /// The port listened on.
    pub port: u16,
}

impl std::fmt::Debug for Server {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Server")
            .field("port", &self.port)
            .finish_non_exhaustive()
    }
}

impl Server {
    /// Starts the server on `host:port`, on a runtime of one worker thread
    /// (the machine's cores belong to the simulation). A port in use or an
    /// address that cannot be bound is a clear error.
    pub fn start(host: &str, port: u16) -> Result<Self, CliError> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("quadsim-foxglove")
            .enable_all()
            .build()
            .map_err(|e| bad(format!("foxglove: cannot start its runtime: {e}")))?;
        let ctx = Context::new();
        let resend = Arc::new(Resend::default());
        let handle = WebSocketServer::new()
            .name(format!("quadsim {}", env!("CARGO_PKG_VERSION")))
            .context(&ctx)
            .bind(host, port)
            .listener(resend.clone())
            .tokio_runtime(runtime.handle())
            .start_blocking()
            .map_err(|e| {
                bad(format!(
                    "foxglove: cannot serve on {host}:{port}: {e} (is the port in use? choose another with --port)"
                ))
            })?;
        let port = handle.port();
        Ok(Self {
            ctx,
            handle: Some(handle),
            runtime: Some(runtime),
            resend,
            port,
        })
    }

    /// Stops the server and its runtime.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        if let Some(h) = self.handle.take() {
            drop(h.stop());
        }
        if let Some(rt) = self.runtime.take() {
            rt.shutdown_timeout(Duration::from_millis(200));
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// One robot being served.
struct LiveRobot {
    plan: RobotPlan,
    names: RobotNames,
    topics: Vec<Arc<RawChannel>>,
    tf: Vec<(DVec3, DQuat)>,
}

/// What the bridge serves: channels by topic, the robots of the current
/// scene, the last rare messages.
struct Live {
    ctx: Arc<Context>,
    channels: BTreeMap<String, Arc<RawChannel>>,
    robots: Vec<LiveRobot>,
    scene: Option<(u64, String)>,
    terrain: Option<String>,
    metrics: Vec<(u64, String, String)>,
    /// A world was shown before: a new world's scene deletes its entities first.
    shown_before: bool,
    buf: Vec<u8>,
    period_ns: Option<u64>,
    next_ns: u64,
    /// Instants forwarded.
    pub forwarded: u64,
}

impl Live {
    fn new(ctx: Arc<Context>, rate_hz: Option<f64>) -> Self {
        Self {
            ctx,
            channels: BTreeMap::new(),
            robots: Vec::new(),
            scene: None,
            terrain: None,
            metrics: Vec::new(),
            shown_before: false,
            buf: Vec::with_capacity(64 * 1024),
            period_ns: rate_hz.map(|hz| (1e9 / hz).round() as u64),
            next_ns: 0,
            forwarded: 0,
        }
    }

    /// The channel of `topic` (made on first use with `schema`).
    fn channel(&mut self, topic: &str, schema: Schema) -> Option<Arc<RawChannel>> {
        if let Some(c) = self.channels.get(topic) {
            return Some(c.clone());
        }
        let c = ChannelBuilder::new(topic)
            .context(&self.ctx)
            .message_encoding(schema.message_encoding())
            .schema(foxglove::Schema::new(
                schema.name(),
                schema.schema_encoding(),
                schema.data(),
            ))
            .build_raw()
            .ok()?;
        self.channels.insert(topic.to_string(), c.clone());
        Some(c)
    }

    fn log(channel: &RawChannel, data: &[u8], t_ns: u64) {
        channel.log_with_meta(
            data,
            PartialMetadata {
                log_time: Some(t_ns),
            },
        );
    }

    /// Closes every channel not in `keep` (robots that left).
    fn close_others(&mut self, keep: &std::collections::BTreeSet<String>) {
        self.channels.retain(|topic, c| {
            let k = keep.contains(topic);
            if !k {
                c.close();
            }
            k
        });
    }

    /// The world ended: its robots' channels are unadvertised (pose,
    /// twist, …, metrics); `/tf`, `/scene` and `/terrain` stay, the scene
    /// showing the last instant until the next world's replaces it.
    fn end_world(&mut self) {
        let keep = [SCENE_TOPIC, TERRAIN_TOPIC, TF_TOPIC]
            .iter()
            .map(|s| s.to_string())
            .collect();
        self.close_others(&keep);
        self.robots.clear();
        self.metrics.clear();
    }

    /// A new world: its robots and scene replace the previous world's.
    fn new_world(&mut self) {
        if self.scene.is_some() {
            self.shown_before = true;
        }
        self.scene = None;
        self.terrain = None;
        self.metrics.clear();
        self.next_ns = 0;
    }

    /// Takes a scene message; true when it began another world under the
    /// same services (a new run whose predecessor's end went unseen).
    fn on_scene(&mut self, msg: SceneMessage) -> bool {
        let mut began = false;
        match msg {
            SceneMessage::Scene {
                version,
                t_ns,
                robots,
                scene,
                terrain,
            } => {
                if version == 0 && self.scene.is_some() {
                    // another world under this name, whose predecessor's end
                    // went unseen (the services passed from one run to the
                    // next while held open): the old robots' channels close
                    // below, and the old entities are deleted
                    self.new_world();
                    began = true;
                }
                let mut keep: std::collections::BTreeSet<String> =
                    [SCENE_TOPIC, TERRAIN_TOPIC, TF_TOPIC]
                        .iter()
                        .map(|s| s.to_string())
                        .collect();
                for r in &robots {
                    for t in LIVE_TOPICS {
                        keep.insert(t.topic(&r.name));
                    }
                    keep.insert(crate::log::metrics_topic(&r.name));
                }
                self.close_others(&keep);
                self.robots = robots
                    .into_iter()
                    .map(|plan| {
                        let frames: Vec<(String, String)> = plan
                            .links
                            .iter()
                            .map(|l| {
                                let parent = match l.parent {
                                    Some(p) => crate::log::encode::frame_id(
                                        &plan.name,
                                        &plan.links[p].name,
                                    ),
                                    None => WORLD_FRAME.to_string(),
                                };
                                (parent, l.name.clone())
                            })
                            .collect();
                        let names =
                            RobotNames::from_parts(&plan.name, &plan.joints, &plan.feet, &frames);
                        let topics = LIVE_TOPICS
                            .iter()
                            .filter_map(|t| self.channel(&t.topic(&plan.name), t.schema()))
                            .collect();
                        LiveRobot {
                            plan,
                            names,
                            topics,
                            tf: Vec::new(),
                        }
                    })
                    .collect();
                if version == 0 && self.shown_before {
                    // the previous world's entities go first
                    let clear = r#"{"deletions":[{"timestamp":{"sec":0,"nsec":0},"type":1,"id":""}],"entities":[]}"#;
                    if let Some(c) = self.channel(SCENE_TOPIC, Schema::SceneUpdate) {
                        Self::log(&c, clear.as_bytes(), t_ns);
                    }
                }
                self.scene = Some((t_ns, scene));
                self.terrain = (!terrain.is_empty()).then_some(terrain);
                self.send_rare();
            }
            SceneMessage::Metrics { t_ns, robots } => {
                for (name, text) in robots {
                    if let Some(c) =
                        self.channel(&crate::log::metrics_topic(&name), Schema::RobotMetrics)
                    {
                        Self::log(&c, text.as_bytes(), t_ns);
                    }
                    self.metrics.push((t_ns, name, text));
                }
            }
        }
        began
    }

    /// Sends the scene, the terrain and any metrics (again).
    fn send_rare(&mut self) {
        if let Some((t_ns, scene)) = self.scene.clone()
            && let Some(c) = self.channel(SCENE_TOPIC, Schema::SceneUpdate)
        {
            Self::log(&c, scene.as_bytes(), t_ns);
        }
        if let Some(terrain) = self.terrain.clone()
            && let Some(c) = self.channel(TERRAIN_TOPIC, Schema::TerrainDescription)
        {
            Self::log(&c, terrain.as_bytes(), 0);
        }
        for (t_ns, name, text) in self.metrics.clone() {
            if let Some(c) = self.channel(&crate::log::metrics_topic(&name), Schema::RobotMetrics) {
                Self::log(&c, text.as_bytes(), t_ns);
            }
        }
    }

    /// Forwards one instant (one frame per robot), at most at the bridge's rate.
    fn on_frames(&mut self, frames: &[RobotFrame]) {
        let Some(first) = frames.first() else {
            return;
        };
        // the log's time of the instant: step_time_ns(tick, dt) = round(tick·dt·1e9)
        let t_ns = (first.time_s * 1e9).round().max(0.0) as u64;
        if let Some(p) = self.period_ns.map(|p| p.max(1)) {
            // on the rate's grid of simulated time; a world whose time went
            // back (restarted) starts the grid again
            if t_ns < self.next_ns && t_ns + p >= self.next_ns {
                return;
            }
            self.next_ns = (t_ns / p + 1) * p;
        }
        self.forwarded += 1;
        let mut samples = Vec::with_capacity(frames.len());
        for f in frames {
            let Some(r) = self.robots.get_mut(f.robot_index as usize) else {
                continue;
            };
            r.plan.link_transforms(f, &mut r.tf);
            let s = sample_of(f, std::mem::take(&mut r.tf));
            for (t, c) in LIVE_TOPICS.iter().zip(&r.topics) {
                if c.has_sinks() {
                    encode_robot(*t, &r.names, &s, t_ns, &mut self.buf);
                    Self::log(c, &self.buf, t_ns);
                }
            }
            samples.push((f.robot_index as usize, s));
        }
        if samples.is_empty() {
            // no scene yet: the robots are not known
            return;
        }
        if let Some(tf) = self.channel(TF_TOPIC, Schema::FrameTransforms)
            && tf.has_sinks()
        {
            let with_names: Vec<_> = samples
                .iter()
                .filter_map(|(i, s)| self.robots.get(*i).map(|r| (&r.names, s)))
                .collect();
            encode_transforms(&with_names, t_ns, &mut self.buf);
            Self::log(&tf, &self.buf, t_ns);
        }
        // give the transform buffers back
        for (i, s) in samples {
            if let Some(r) = self.robots.get_mut(i) {
                r.tf = s.link_transforms;
            }
        }
    }
}

/// A frame's values as a log sample (what a frame lacks is NaN; the
/// controller's targets are absent when the frame has none).
fn sample_of(f: &RobotFrame, link_transforms: Vec<(DVec3, DQuat)>) -> RobotSample {
    let n = f.dof();
    let v3 = DVec3::from_array;
    let nan = DVec3::NAN;
    let targets = |x: &[f64]| {
        let x = &x[..n];
        (!x.iter().all(|v| v.is_nan())).then(|| x.to_vec())
    };
    RobotSample {
        robot: f.robot_index as usize,
        q: Vec::new(),
        v: Vec::new(),
        base_position_m: v3(f.base_position_m),
        base_orientation: DQuat::from_array(f.base_orientation_xyzw),
        base_linear_mps: v3(f.base_linear_mps),
        base_angular_radps: v3(f.base_angular_radps),
        rpy_rad: v3(f.rpy_rad),
        com_m: v3(f.com_m),
        com_velocity_mps: v3(f.com_velocity_mps),
        com_acceleration_mps2: nan,
        joint_position: f.joint_q_rad[..n].to_vec(),
        joint_velocity: f.joint_qd_radps[..n].to_vec(),
        joint_effort: f.joint_tau_nm[..n].to_vec(),
        joint_effort_command: f.joint_tau_desired_nm[..n].to_vec(),
        joint_position_desired: targets(&f.joint_q_desired_rad),
        joint_velocity_desired: targets(&f.joint_qd_desired_radps),
        feet: (0..f.feet())
            .map(|i| FootLog {
                in_contact: f.in_contact(i),
                slipping: i < 32 && f.slip_flags & (1 << i) != 0,
                penetration_m: f64::NAN,
                normal_force_n: f64::NAN,
                force_n: v3(f.foot_force_n[i]),
                position_m: nan,
                gait_phase: Some(f.gait_phase[i]).filter(|p| !p.is_nan()),
            })
            .collect(),
        virtual_wrench: None,
        sensing: None,
        link_transforms,
    }
}

/// Waits for a world to serve: `name`, or the only running one. `stop`
/// ends the wait (`Ok(None)`).
fn wait_world(name: Option<&str>, stop: &AtomicBool) -> Result<Option<String>, CliError> {
    let mut said = false;
    loop {
        if stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        let worlds = list_worlds().map_err(|e| bad(e.to_string()))?;
        match name {
            Some(n) if worlds.iter().any(|w| w == n) => return Ok(Some(n.to_string())),
            None if worlds.len() == 1 => return Ok(Some(worlds[0].clone())),
            None if worlds.len() > 1 && !said => {
                eprintln!(
                    "foxglove: several worlds are running ({}); waiting for one, or choose with --world",
                    worlds.join(", ")
                );
                said = true;
            }
            _ if !said => {
                eprintln!(
                    "foxglove: waiting for world {}…",
                    name.map_or("(any)".to_string(), |n| format!("'{n}'"))
                );
                said = true;
            }
            _ => {}
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Serves worlds until `stop` is set (or, with `once`, until the first
/// world ends): attaches, forwards, and on the world's end waits for the
/// next one, without a restart.
pub fn serve(server: &Server, opts: &BridgeOptions, stop: &AtomicBool) -> Result<(), CliError> {
    let mut live = Live::new(server.ctx.clone(), opts.rate_hz);
    let err = |e: crate::monitor::MonitorError| bad(e.to_string());
    loop {
        let Some(world) = wait_world(opts.world.as_deref(), stop)? else {
            return Ok(());
        };
        // the scene before the frames: the run sees a viewer when sampling starts
        let (Some(mut scene), Some(mut frames)) = (
            SceneReader::open(&world).map_err(err)?,
            FrameReader::open(&world).map_err(err)?,
        ) else {
            // between services (starting or ending): try again
            std::thread::sleep(Duration::from_millis(20));
            continue;
        };
        if frames.ended() {
            // the services of a run that just ended, not yet removed
            std::thread::sleep(Duration::from_millis(100));
            continue;
        }
        eprintln!("foxglove: serving world '{world}'");
        live.new_world();
        let (mut last, mut last_dead_check) = (Instant::now(), Instant::now());
        loop {
            if stop.load(Ordering::Relaxed) {
                // the last instants and messages, then stop
                while let Some(m) = scene.try_next().map_err(err)? {
                    let _ = live.on_scene(m);
                }
                while let Some(f) = frames.try_next().map_err(err)? {
                    live.on_frames(&f);
                }
                return Ok(());
            }
            while let Some(m) = scene.try_next().map_err(err)? {
                if live.on_scene(m) {
                    eprintln!("foxglove: a new run of world '{world}'");
                }
            }
            if server.resend.0.swap(false, Ordering::Relaxed) {
                live.send_rare();
            }
            let mut got = false;
            while let Some(f) = frames.try_next().map_err(err)? {
                live.on_frames(&f);
                got = true;
            }
            if got {
                last = Instant::now();
                continue;
            }
            if last.elapsed() >= QUIET_CHECK {
                if last_dead_check.elapsed() >= DEAD_CHECK {
                    cleanup_dead_nodes::<iceoryx2::prelude::ipc_threadsafe::Service>();
                    last_dead_check = Instant::now();
                }
                if frames.ended() {
                    // the last messages (the metrics); the scene first: the
                    // frames were drained before the quiet, so any queued
                    // now are a next run's, which its scene precedes
                    let mut began = false;
                    while let Some(m) = scene.try_next().map_err(err)? {
                        began |= live.on_scene(m);
                    }
                    while let Some(f) = frames.try_next().map_err(err)? {
                        live.on_frames(&f);
                    }
                    if began || !frames.ended() {
                        // the next run of this name took the services over
                        // meanwhile (its scene may come next): serve it, its
                        // channels already advertised stay
                        if began {
                            eprintln!("foxglove: a new run of world '{world}'");
                        }
                        last = Instant::now();
                        continue;
                    }
                    // the world's channels go, and its services are let go
                    // (dropping the readers) so that nothing of it is held
                    live.end_world();
                    break;
                }
                last = Instant::now();
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        eprintln!(
            "foxglove: world '{world}' ended ({} instants forwarded){}",
            live.forwarded,
            if opts.once {
                ""
            } else {
                "; waiting for the next"
            }
        );
        if opts.once {
            return Ok(());
        }
    }
}

/// A bridge serving one world from inside `quadsim run --foxglove`.
#[derive(Debug)]
pub struct BridgeThread {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<Result<(), CliError>>>,
}

/// Starts the server on 127.0.0.1:`port` (errors at once: a port in use)
/// and serves `world` on a thread of its own.
pub fn spawn_bridge(world: String, port: u16) -> Result<BridgeThread, CliError> {
    let server = Server::start("127.0.0.1", port)?;
    eprintln!(
        "foxglove: ws://127.0.0.1:{} (Foxglove: Open connection… → Foxglove WebSocket)",
        server.port
    );
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let opts = BridgeOptions {
        world: Some(world),
        host: "127.0.0.1".into(),
        port,
        rate_hz: Some(DEFAULT_RATE_HZ),
        once: true,
    };
    let thread = std::thread::Builder::new()
        .name("quadsim-foxglove-bridge".into())
        .spawn(move || {
            let r = serve(&server, &opts, &flag);
            server.stop();
            r
        })
        .map_err(|e| bad(format!("foxglove: cannot start the bridge thread: {e}")))?;
    Ok(BridgeThread {
        stop,
        thread: Some(thread),
    })
}

impl BridgeThread {
    /// Stops the bridge after the world's last messages; an error the
    /// bridge met is printed (the run's results stand).
    pub fn finish(mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            match t.join() {
                Ok(Ok(())) => {}
                Ok(Err(e)) => eprintln!("warning: {e}"),
                Err(_) => eprintln!("warning: foxglove: the bridge thread failed"),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(version: u64, robot: &str) -> SceneMessage {
        SceneMessage::Scene {
            version,
            t_ns: 0,
            robots: vec![RobotPlan {
                name: robot.into(),
                joints: Vec::new(),
                feet: Vec::new(),
                links: Vec::new(),
            }],
            scene: r#"{"deletions":[],"entities":[]}"#.into(),
            terrain: String::new(),
        }
    }

    fn topics(live: &Live) -> Vec<&str> {
        live.channels.keys().map(String::as_str).collect()
    }

    /// A world that ends unadvertises its robots' channels; a new run
    /// under the same services (its predecessor's end unseen) replaces the
    /// robots' channels and deletes the old scene's entities.
    #[test]
    fn a_new_world_replaces_the_last_ones_channels() {
        let mut live = Live::new(Context::new(), None);
        live.new_world();
        assert!(!live.on_scene(scene(0, "rex")));
        assert!(
            topics(&live).contains(&"/rex/base_pose"),
            "{:?}",
            topics(&live)
        );
        // a later robot list of the same run is no new world
        assert!(!live.on_scene(scene(1, "rex")));
        assert!(!live.shown_before);
        // the next run's first scene, the end unseen
        assert!(live.on_scene(scene(0, "max")));
        assert!(live.shown_before);
        let t = topics(&live);
        assert!(t.contains(&"/max/base_pose"), "{t:?}");
        assert!(!t.iter().any(|t| t.starts_with("/rex/")), "{t:?}");
        // the world ends: only the world's channels stay
        live.end_world();
        assert!(live.robots.is_empty());
        let t = topics(&live);
        assert!(
            t.iter()
                .all(|t| [SCENE_TOPIC, TERRAIN_TOPIC, TF_TOPIC].contains(t)),
            "{t:?}"
        );
    }
}
