//! The subscribing side: list the running worlds, attach to one, receive its
//! instants (one slice of frames each) and its header.

use std::time::{Duration, Instant};

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use serde_json::Value;

use super::frame::{LAYOUT_VERSION, RobotFrame, TYPE_NAME};
use super::scene::SceneMessage;
use super::service::{
    MonitorError, SERVICE_PREFIX, cleanup_dead_nodes, frames_service, header_service, node_name,
    scene_service, service_name,
};

type Svc = ipc_threadsafe::Service;

/// Names of the worlds whose frames service exists, sorted (dead runs'
/// services are cleaned up first).
pub fn list_worlds() -> Result<Vec<String>, MonitorError> {
    cleanup_dead_nodes::<Svc>();
    let mut out = Vec::new();
    Svc::list(Config::global_config(), |s| {
        let name = s.static_details.name().to_string();
        if let Some(world) = name
            .strip_prefix(SERVICE_PREFIX)
            .and_then(|w| w.strip_suffix("/frames"))
        {
            out.push(world.to_string());
        }
        CallbackProgression::Continue
    })
    .map_err(|e| MonitorError {
        message: format!("cannot list the iceoryx2 services: {e:?}"),
    })?;
    out.sort();
    out.dedup();
    Ok(out)
}

/// A subscriber to one world.
pub struct FrameReader {
    frames: Subscriber<Svc, [RobotFrame], ()>,
    frames_service:
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<Svc, [RobotFrame], ()>,
    header: Subscriber<Svc, [u8], ()>,
    _node: Node<Svc>,
    world: String,
    last_header: Option<Value>,
}

impl std::fmt::Debug for FrameReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameReader")
            .field("world", &self.world)
            .finish_non_exhaustive()
    }
}

impl FrameReader {
    /// Attaches to `world`; `Ok(None)` when it does not exist (yet).
    pub fn open(world: &str) -> Result<Option<Self>, MonitorError> {
        let node = NodeBuilder::new()
            .name(&node_name("quadsim-monitor")?)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .map_err(|e| MonitorError {
                message: format!("cannot create an iceoryx2 node: {e:?}"),
            })?;
        let frames = match node
            .service_builder(&service_name(&frames_service(world))?)
            .publish_subscribe::<[RobotFrame]>()
            .open()
        {
            Ok(s) => s,
            Err(PublishSubscribeOpenError::DoesNotExist) => return Ok(None),
            Err(PublishSubscribeOpenError::IncompatibleTypes) => {
                return Err(MonitorError {
                    message: format!(
                        "world '{world}' publishes another frame layout than this reader's \
                         ({TYPE_NAME}, layout version {LAYOUT_VERSION}); use a matching quadsim"
                    ),
                });
            }
            Err(e) => {
                return Err(MonitorError {
                    message: format!("cannot open world '{world}': {e:?}"),
                });
            }
        };
        let header = match node
            .service_builder(&service_name(&header_service(world))?)
            .publish_subscribe::<[u8]>()
            .open()
        {
            Ok(s) => s,
            // the run is between creating its two services, or ending
            Err(PublishSubscribeOpenError::DoesNotExist) => return Ok(None),
            Err(e) => {
                return Err(MonitorError {
                    message: format!("cannot open the header of world '{world}': {e:?}"),
                });
            }
        };
        let frames_service = frames;
        let frames = frames_service
            .subscriber_builder()
            .create()
            .map_err(|e| MonitorError {
                message: format!("cannot subscribe to world '{world}': {e:?}"),
            })?;
        let header = header
            .subscriber_builder()
            .create()
            .map_err(|e| MonitorError {
                message: format!("cannot subscribe to the header of world '{world}': {e:?}"),
            })?;
        Ok(Some(Self {
            frames,
            frames_service,
            header,
            _node: node,
            world: world.to_string(),
            last_header: None,
        }))
    }

    /// Attaches to `world`, waiting up to `timeout` for it to appear.
    pub fn wait_open(world: &str, timeout: Duration) -> Result<Self, MonitorError> {
        let start = Instant::now();
        loop {
            if let Some(r) = Self::open(world)? {
                return Ok(r);
            }
            if start.elapsed() >= timeout {
                return Err(MonitorError {
                    message: format!(
                        "world '{world}' did not appear within {:.1} s (running worlds: {})",
                        timeout.as_secs_f64(),
                        list_worlds()
                            .map(|w| if w.is_empty() {
                                "none".into()
                            } else {
                                w.join(", ")
                            })
                            .unwrap_or_else(|e| e.to_string())
                    ),
                });
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Whether the world's run is gone (its frames service has no
    /// publisher; the service itself lives on while readers hold it).
    pub fn ended(&self) -> bool {
        use iceoryx2::service::port_factory::PortFactory as _;
        self.frames_service.dynamic_config().number_of_publishers() == 0
    }

    /// The world's name.
    pub fn world(&self) -> &str {
        &self.world
    }

    /// The next instant's frames, if one is queued; rejects frames of
    /// another layout version.
    pub fn try_next(&mut self) -> Result<Option<Vec<RobotFrame>>, MonitorError> {
        let sample = self.frames.receive().map_err(|e| MonitorError {
            message: format!("receiving from world '{}': {e:?}", self.world),
        })?;
        let Some(sample) = sample else {
            return Ok(None);
        };
        let frames = sample.payload().to_vec();
        if let Some(f) = frames.iter().find(|f| f.layout_version != LAYOUT_VERSION) {
            return Err(MonitorError {
                message: format!(
                    "world '{}' sent a frame of layout version {}, this reader knows {}",
                    self.world, f.layout_version, LAYOUT_VERSION
                ),
            });
        }
        Ok(Some(frames))
    }

    /// The next instant, waiting up to `timeout` (`Ok(None)` on timeout).
    pub fn next(&mut self, timeout: Duration) -> Result<Option<Vec<RobotFrame>>, MonitorError> {
        let start = Instant::now();
        loop {
            if let Some(f) = self.try_next()? {
                return Ok(Some(f));
            }
            if start.elapsed() >= timeout {
                return Ok(None);
            }
            std::thread::sleep(Duration::from_micros(500));
        }
    }

    /// The latest header received (JSON, docs/monitor.md), polling for a new one.
    pub fn header(&mut self) -> Result<Option<&Value>, MonitorError> {
        while let Some(s) = self.header.receive().map_err(|e| MonitorError {
            message: format!("receiving the header of world '{}': {e:?}", self.world),
        })? {
            let v: Value = serde_json::from_slice(s.payload()).map_err(|e| MonitorError {
                message: format!("world '{}' sent a header that is not JSON: {e}", self.world),
            })?;
            self.last_header = Some(v);
        }
        Ok(self.last_header.as_ref())
    }

    /// Waits up to `timeout` for the header.
    pub fn wait_header(&mut self, timeout: Duration) -> Result<Value, MonitorError> {
        let start = Instant::now();
        loop {
            if let Some(h) = self.header()? {
                return Ok(h.clone());
            }
            if start.elapsed() >= timeout {
                return Err(MonitorError {
                    message: format!(
                        "world '{}' sent no header within {:.1} s",
                        self.world,
                        timeout.as_secs_f64()
                    ),
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

/// A subscriber to one world's scene service (live 3D viewers): the robots'
/// link plans and the scene, then the final metrics. Open it before the
/// frames (a [`FrameReader`]), so the run sees the viewer when sampling
/// starts.
pub struct SceneReader {
    scene: Subscriber<Svc, [u8], ()>,
    _node: Node<Svc>,
    world: String,
}

impl std::fmt::Debug for SceneReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneReader")
            .field("world", &self.world)
            .finish_non_exhaustive()
    }
}

impl SceneReader {
    /// Attaches to `world`'s scene; `Ok(None)` when it does not exist (yet).
    pub fn open(world: &str) -> Result<Option<Self>, MonitorError> {
        let node = NodeBuilder::new()
            .name(&node_name("quadsim-viewer")?)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .map_err(|e| MonitorError {
                message: format!("cannot create an iceoryx2 node: {e:?}"),
            })?;
        let service = match node
            .service_builder(&service_name(&scene_service(world))?)
            .publish_subscribe::<[u8]>()
            .open()
        {
            Ok(s) => s,
            Err(PublishSubscribeOpenError::DoesNotExist) => return Ok(None),
            Err(e) => {
                return Err(MonitorError {
                    message: format!("cannot open the scene of world '{world}': {e:?}"),
                });
            }
        };
        let scene = service
            .subscriber_builder()
            .create()
            .map_err(|e| MonitorError {
                message: format!("cannot subscribe to the scene of world '{world}': {e:?}"),
            })?;
        Ok(Some(Self {
            scene,
            _node: node,
            world: world.to_string(),
        }))
    }

    /// The next scene message, if one is queued.
    pub fn try_next(&mut self) -> Result<Option<SceneMessage>, MonitorError> {
        let Some(s) = self.scene.receive().map_err(|e| MonitorError {
            message: format!("receiving the scene of world '{}': {e:?}", self.world),
        })?
        else {
            return Ok(None);
        };
        serde_json::from_slice(s.payload())
            .map(Some)
            .map_err(|e| MonitorError {
                message: format!(
                    "world '{}' sent a scene that does not parse: {e}",
                    self.world
                ),
            })
    }
}
