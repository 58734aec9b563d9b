//! Live monitoring over shared memory (iceoryx2): a running `quadsim run`
//! publishes every robot's [`RobotFrame`] per publish tick and a JSON header
//! describing the world; `quadsim monitor` and other processes (Python, C)
//! subscribe. See `docs/monitor.md`.

pub mod command;
pub mod frame;
pub mod publish;
pub mod run;
pub mod scene;
pub mod service;
pub mod subscribe;

pub use command::{CommandReceiver, CommandSender, CommandStats, RobotCommand};
pub use frame::{LAYOUT_VERSION, MAX_DOF, MAX_FEET, RobotFrame, TYPE_NAME};
pub use publish::{FramePublisher, MonitorSink, MonitorStats, WorldScene};
pub use run::RunMonitor;
pub use scene::{RobotPlan, SceneMessage};
pub use service::{
    DEFAULT_RATE_HZ, MAX_SUBSCRIBERS, MonitorError, SERVICE_PREFIX, SUBSCRIBER_BUFFER_FRAMES,
    cleanup_dead_nodes, commands_service, default_every_steps, default_world_name, frames_service,
    header_service, scene_service,
};
pub use subscribe::{FrameReader, SceneReader, list_worlds};
