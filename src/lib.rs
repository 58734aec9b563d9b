//! quadsim: a data-oriented simulation engine for quadruped robots.
//!
//! The root crate holds the command-line interface and model loading (URDF
//! import, built-in robots by name). The physics core is [`quadsim_engine`],
//! ECS data is [`quadsim_components`], and the fixed-step schedule is
//! [`quadsim_systems`].

pub mod actuators;
pub mod analysis;
pub mod cli;
pub mod divergence;
pub mod error;
pub mod foxglove_live;
pub mod heightmap;
pub mod limits;
pub mod log;
pub mod mem;
pub mod model_source;
pub mod monitor;
pub mod names;
pub mod physical;
pub mod report;
pub mod scenario;
pub mod seed;
pub mod sensing;
pub mod study;
pub mod summary;
pub mod terrain_spec;
pub mod urdf;
pub mod world;

pub use quadsim_components as components;
pub use quadsim_engine as engine;
pub use quadsim_systems as systems;
