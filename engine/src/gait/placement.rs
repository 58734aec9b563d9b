//! Raibert-style foot placement.
//!
//! Inputs are in the heading frame (x forward, y left, z up, yawed with the
//! body but level); the output is the touchdown point's horizontal offset from
//! the hip's ground projection, same frame:
//!
//! `p = v T_st / 2 + k (v − v_des) + (R_z(ω T_st / 2) − I) r_hip`,
//!
//! then each axis clipped to `±max_step` ([`PlacementParams::max_step_x_m`],
//! [`PlacementParams::max_step_y_m`]), independently.
//!
//! - `v T_st / 2`: the neutral point. The hip travels `v T_st` during a stance;
//!   placing the foot half of that ahead makes the stance symmetric about the
//!   foot, so gravity's moment about the foot averages to zero.
//! - `k (v − v_des)`: speed feedback; a foot placed further ahead than the
//!   neutral point brakes, behind it accelerates.
//! - The yaw term: where the hip (at `r_hip` from the body centre) will be
//!   after turning at `ω` for half a stance, so a turning body also stands
//!   symmetrically (for small `ω T_st`, `≈ ω ẑ × r_hip · T_st / 2`).
//!
//! The hip to use is the hip's ground projection at the touchdown instant
//! (e.g. now plus `v ·` [`super::LegState::time_to_touchdown_s`]); convert to
//! world with [`foot_target_world`].

use glam::{DMat2, DVec2, DVec3};

/// Gains and limits of [`raibert_offset`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacementParams {
    /// Speed feedback gain `k` (s).
    pub gain_s: f64,
    /// Largest forward/backward offset from the hip (m, ≥ 0).
    pub max_step_x_m: f64,
    /// Largest sideways offset from the hip (m, ≥ 0).
    pub max_step_y_m: f64,
}

impl PlacementParams {
    /// The capture-point gain of a linear inverted pendulum of height `h`:
    /// `k = √(h / g)`: a foot placed `k·v` ahead of the CoM brings it to rest.
    pub fn capture_point_gain_s(height_m: f64, gravity_m_s2: f64) -> f64 {
        (height_m / gravity_m_s2).sqrt()
    }
}

impl Default for PlacementParams {
    /// quad16 at Study A's 0.5 m height: `k = √(0.5 / 9.81) ≈ 0.226 s`; steps of
    /// at most 0.25 m forward/back (the hip-to-sole length 0.61 m reaches about
    /// 0.35 m ahead at 0.5 m height; the rest is margin for the bent knee) and
    /// 0.12 m sideways (hip roll).
    fn default() -> Self {
        PlacementParams {
            gain_s: Self::capture_point_gain_s(0.5, 9.81),
            max_step_x_m: 0.25,
            max_step_y_m: 0.12,
        }
    }
}

/// Inputs of [`raibert_offset`], all in the heading frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacementInput {
    /// Body (CoM) horizontal velocity (m/s).
    pub vel_m_s: DVec2,
    /// Commanded horizontal velocity (m/s).
    pub vel_des_m_s: DVec2,
    /// Yaw rate about z (rad/s, counter-clockwise positive), measured.
    pub yaw_rate_rad_s: f64,
    /// Hip position from the body centre, horizontal (m).
    pub hip_m: DVec2,
    /// Stance duration `T_st` (s), e.g. [`super::Gait::stance_duration_s`].
    pub stance_duration_s: f64,
}

/// Foot placement offset from the hip's ground projection (m, heading frame),
/// and whether the clip was active.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Offset after clipping (m).
    pub offset_m: DVec2,
    /// The offset before clipping (m).
    pub unclipped_m: DVec2,
    /// Whether either axis was clipped.
    pub clipped: bool,
}

/// Raibert's placement with the yaw term and per-axis clipping (module docs).
pub fn raibert_offset(params: &PlacementParams, input: &PlacementInput) -> Placement {
    let half = 0.5 * input.stance_duration_s;
    let neutral = input.vel_m_s * half;
    let feedback = params.gain_s * (input.vel_m_s - input.vel_des_m_s);
    let yaw = DMat2::from_angle(input.yaw_rate_rad_s * half) * input.hip_m - input.hip_m;
    let raw = neutral + feedback + yaw;
    let offset_m = clip_step(raw, params.max_step_x_m, params.max_step_y_m);
    Placement {
        offset_m,
        unclipped_m: raw,
        clipped: offset_m != raw,
    }
}

/// `offset` with x clamped to `±max_x_m` and y to `±max_y_m` (limits taken as
/// magnitudes).
pub fn clip_step(offset: DVec2, max_x_m: f64, max_y_m: f64) -> DVec2 {
    let (mx, my) = (max_x_m.abs(), max_y_m.abs());
    DVec2::new(offset.x.clamp(-mx, mx), offset.y.clamp(-my, my))
}

/// World touchdown point: the hip's ground projection (`hip_world_m` x, y at
/// height `ground_z_m`, e.g. the terrain height there) plus the heading-frame
/// `offset_m` turned by the body's yaw `yaw_rad` about world z.
pub fn foot_target_world(
    hip_world_m: DVec3,
    yaw_rad: f64,
    ground_z_m: f64,
    offset_m: DVec2,
) -> DVec3 {
    let o = DMat2::from_angle(yaw_rad) * offset_m;
    DVec3::new(hip_world_m.x + o.x, hip_world_m.y + o.y, ground_z_m)
}
