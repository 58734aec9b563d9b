//! Push directions of `[robots.analysis]` and push events.

use glam::DVec3;

/// Horizontal push directions, in the robot's start heading frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PushDirection {
    /// +y of the heading frame.
    Left,
    /// −y.
    Right,
    /// +x.
    Forward,
    /// −x.
    Backward,
}

impl PushDirection {
    /// Every direction.
    pub const ALL: [PushDirection; 4] = [
        PushDirection::Left,
        PushDirection::Right,
        PushDirection::Forward,
        PushDirection::Backward,
    ];

    /// Lower-case name as the scenario spells it.
    pub fn name(self) -> &'static str {
        match self {
            PushDirection::Left => "left",
            PushDirection::Right => "right",
            PushDirection::Forward => "forward",
            PushDirection::Backward => "backward",
        }
    }

    /// The direction named `name`.
    pub fn from_name(name: &str) -> Option<PushDirection> {
        Self::ALL.into_iter().find(|d| d.name() == name)
    }

    /// Unit vector in the world for a start yaw `yaw_rad`.
    pub fn world(self, yaw_rad: f64) -> DVec3 {
        let (s, c) = yaw_rad.sin_cos();
        let (fwd, left) = (DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0));
        match self {
            PushDirection::Left => left,
            PushDirection::Right => -left,
            PushDirection::Forward => fwd,
            PushDirection::Backward => -fwd,
        }
    }
}
