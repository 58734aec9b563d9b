//! URDF import (urdf-rs) into an engine [`quadsim_engine::description::RobotDescription`].
