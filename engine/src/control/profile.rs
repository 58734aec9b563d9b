//! What differs between robots, as data the controllers read: a
//! [`RobotProfile`] built from the compiled model (and a built-in robot's
//! [`crate::robots::BuiltinTuning`] where it states something), so that no
//! controller compares a robot's name.
//!
//! For a robot quadsim does not build in, the profile is found from the
//! model alone:
//! - **stance**: each foot at its zero-angle position moved 20 % of the
//!   leg's length toward the hip (feet under the hips, the leg at 0.8 of its
//!   length), solved by the leg's IK on the nominal knee branch, foot level;
//! - **stance height**: the base height that puts the lowest foot contact on
//!   flat ground there ([`crate::robots::stance_base_height_m`]);
//! - **walk height**: 0.85 of the stance height; **VMC gains**: Study A's
//!   scaled by the mass ratio to quad16's 28 kg; **swing lift**: a fifth of
//!   the walk height;
//! - **placement hips**: above each stance foot (see
//!   [`RobotProfile::placement_hips_m`]);
//! - **stand gains**: a vertical leg stiffness that carries the robot's
//!   weight with the torso sinking 2 % of its stance height, mapped to each
//!   joint through the foot's Jacobian ([`RobotProfile::stand_gains`]).

use crate::data::Data;
use crate::description::RobotDescription;
use crate::dispatch::forward_kinematics_pos;
use crate::legs::{AnkleMode, FootPoint, HipKind, IkOptions, LegKinematics};
use crate::model::Model;
use glam::DVec3;

use super::joint_pd::bandwidth_gains;

/// quad16's total mass (kg): the reference of the VMC gains' mass scaling.
pub const STUDY_A_MASS_KG: f64 = 28.0;
/// Fraction of the leg's length a generic stance draws the foot toward the
/// hip (the leg at 0.8 of its length).
pub const STANCE_CROUCH: f64 = 0.2;
/// Torso sink (fraction of the stance height) under the robot's weight that
/// sets the stand gains' leg stiffness.
pub const STAND_SINK_FRACTION: f64 = 0.02;
/// The stand controller's joint bandwidth (Hz) when the scenario sets none.
pub const STAND_BANDWIDTH_HZ: f64 = 4.0;
/// The swing legs' joint bandwidth (Hz).
pub const SWING_BANDWIDTH_HZ: f64 = 6.0;
/// Swing lift per unit of walking height for a robot without tuning: a
/// fifth (the built-ins' tenth is [`crate::robots::BUILTIN_SWING_LIFT_PER_HEIGHT`]).
/// The Mini-Cheetah-sized fixture (0.25 m walking height) stubbed its feet at
/// a tenth: 10 of 50 perturbed copies fell at 1.0 m/s, 3 of 50 at 5 cm.
pub const SWING_LIFT_PER_HEIGHT: f64 = 0.2;

/// How the stand controller's default joint gains are set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StandGainRule {
    /// Joint bandwidth gains alone ([`bandwidth_gains`]).
    JointBandwidth,
    /// The larger of the bandwidth gains and a leg stiffness that carries
    /// the weight with the torso sinking `sink_fraction` of its stance
    /// height ([`RobotProfile::stand_gains`]).
    LegStiffness {
        /// Sink under the weight, as a fraction of the stance height.
        sink_fraction: f64,
    },
}

/// A robot's controller-relevant data (module docs). Angles in rad, q order
/// of the joints (base excluded); positions in the base frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotProfile {
    /// Nominal standing joint angles (rad, joints only).
    pub stance_rad: Vec<f64>,
    /// Base height (m) at which the stance's lowest foot contact touches
    /// flat ground, base level.
    pub stance_base_height_m: f64,
    /// The walking controller's torso height target (m).
    pub walk_height_m: f64,
    /// Factor on Study A's VMC gains.
    pub vmc_gain_scale: f64,
    /// Mean leg length (m): hip pitch joint to the foot point, leg straight.
    pub leg_length_m: f64,
    /// Total mass (kg).
    pub total_mass_kg: f64,
    /// Per leg, the point whose ground projection is Raibert's "hip"
    /// (`WalkerParams::placement_hips_m`); empty: the legs' mounts. A roll
    /// leg's hip is its mount moved by the leg's lateral offset along the
    /// pitch axis (above the foot of a leg hanging straight; empty when
    /// every offset is zero: quad16). A yaw leg's foot cannot reach its yaw
    /// axis: there the hip is the stance foot at the mount's height (quad12).
    pub placement_hips_m: Vec<DVec3>,
    /// How the stand controller's default gains are set.
    pub stand_gains: StandGainRule,
    /// The swing feet's lift above the line between a swing's ends (m).
    pub swing_lift_m: f64,
    /// The whole-body walker's largest sideways step from the hip (m);
    /// `None`: the placement's default.
    pub whole_body_max_step_y_m: Option<f64>,
}

impl RobotProfile {
    /// The profile of `model` (compiled from `desc`; a built-in robot is
    /// recognised by `desc.name` at the robot-definition level,
    /// [`crate::robots::builtin_tuning`]). Never fails: a robot whose legs
    /// the kinematics cannot read gets zero stance angles and no hips.
    pub fn from_model(desc: &RobotDescription, model: &Model) -> RobotProfile {
        let nj = model.nv - model.base_nv();
        let tuning = crate::robots::builtin_tuning(&desc.name);
        let legs = LegKinematics::for_robot(desc, model, FootPoint::Contact).ok();
        let leg_length_m = legs.as_ref().map_or(0.0, |l| mean_leg_length_m(l));
        let stance_rad = match (&tuning, &legs) {
            (Some(t), _) if t.stance_rad.len() == nj => t.stance_rad.clone(),
            (Some(_), _) => vec![0.0; nj],
            (None, Some(legs)) => generic_stance(model, legs),
            (None, None) => vec![0.0; nj],
        };
        let stance_base_height_m =
            crate::robots::stance_base_height_m(desc, &stance_rad).unwrap_or(0.585);
        let walk_height_m = tuning
            .as_ref()
            .and_then(|t| t.walk_height_m)
            .unwrap_or(0.85 * stance_base_height_m);
        let vmc_gain_scale = tuning
            .as_ref()
            .and_then(|t| t.vmc_gain_scale)
            .unwrap_or(model.total_mass / STUDY_A_MASS_KG);
        let stand_gains = if tuning.as_ref().is_some_and(|t| t.stand_gains_by_bandwidth) {
            StandGainRule::JointBandwidth
        } else {
            StandGainRule::LegStiffness {
                sink_fraction: STAND_SINK_FRACTION,
            }
        };
        let placement_hips_m = legs
            .as_ref()
            .map_or_else(Vec::new, |l| placement_hips(model, l, &stance_rad));
        let lift_per_height = tuning
            .as_ref()
            .and_then(|t| t.swing_lift_per_height)
            .unwrap_or(SWING_LIFT_PER_HEIGHT);
        // written as 0.05 m at quad16's 0.5 m, scaled, for the built-ins' bits
        let swing_lift_m = 0.5 * lift_per_height * (walk_height_m / 0.5);
        RobotProfile {
            stance_rad,
            stance_base_height_m,
            walk_height_m,
            vmc_gain_scale,
            leg_length_m,
            total_mass_kg: model.total_mass,
            placement_hips_m,
            stand_gains,
            swing_lift_m,
            whole_body_max_step_y_m: tuning.as_ref().and_then(|t| t.whole_body_max_step_y_m),
        }
    }

    /// The floating-base configuration of the stance: `[0, 0, height, 0, 0,
    /// 0, 1, stance…]` (Pinocchio order, base level), `model.nq` long.
    pub fn stance_q(&self, model: &Model) -> Vec<f64> {
        let mut q = vec![0.0, 0.0, self.stance_base_height_m, 0.0, 0.0, 0.0, 1.0];
        q.extend_from_slice(&self.stance_rad);
        q.resize(model.nq, 0.0);
        q
    }

    /// Swing-leg joint gains (N·m/rad, N·m·s/rad; joints only): joint
    /// bandwidth gains at the stance, [`SWING_BANDWIDTH_HZ`], critically
    /// damped.
    pub fn swing_gains(&self, model: &Model) -> (Vec<f64>, Vec<f64>) {
        let q = self.stance_q(model);
        let mut data = Data::new(model);
        bandwidth_gains(model, &mut data, &q, SWING_BANDWIDTH_HZ, 1.0)
    }

    /// The stand controller's default joint gains at configuration `q`
    /// (floating base; joints only), by [`Self::stand_gains`]'s rule:
    /// bandwidth gains at `bandwidth_hz` and `damping_ratio`, and under
    /// [`StandGainRule::LegStiffness`] at least, per joint j of a leg,
    /// `kp_j = k |J_j|²` with the leg stiffness `k = (m g / n_feet) / (s h)`
    /// (`s` the sink fraction, `h` the stance height) and `J_j` the foot
    /// point's velocity per unit rate of joint j (the engine's point
    /// Jacobian at `q`), and `kd_j = 2 ζ √(kp_j (M_jj + (m / n_feet) |J_j|²))`:
    /// critically damped on the joint's share of the body it carries, but
    /// at most `M_jj / T` for the control period `T` (s): a sampled damper
    /// on a light link alone (a foot off the ground) is unstable past
    /// `kd T / M_jj = 2`. Never below the bandwidth gains.
    pub fn stand_gains(
        &self,
        desc: &RobotDescription,
        model: &Model,
        q: &[f64],
        bandwidth_hz: f64,
        damping_ratio: f64,
        control_period_s: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let mut data = Data::new(model);
        let (mut kp, mut kd) = bandwidth_gains(model, &mut data, q, bandwidth_hz, damping_ratio);
        let StandGainRule::LegStiffness { sink_fraction } = self.stand_gains else {
            return (kp, kd);
        };
        let nf = model.feet.len();
        if nf == 0 || self.stance_base_height_m.is_nan() || self.stance_base_height_m <= 0.0 {
            return (kp, kd);
        }
        let nv = model.nv;
        let b = model.base_nv();
        let mass = self.total_mass_kg / nf as f64;
        let k_leg = mass * model.gravity.length() / (sink_fraction * self.stance_base_height_m);
        let diag: Vec<f64> = {
            let m = crate::dispatch::crba(model, &mut data, q);
            (b..nv).map(|i| m[i * nv + i]).collect()
        };
        forward_kinematics_pos(model, &mut data, q);
        let points: Vec<(usize, DVec3)> = crate::contact::ContactPoint::feet(model, desc)
            .iter()
            .map(|c| (c.body, c.point_in_body))
            .collect();
        for (body, p) in points {
            let pw = data.body_point_world(body, p);
            let jac = crate::jacobian::point_jacobian(model, &mut data, body, pw).to_vec();
            for j in b..nv {
                let col = DVec3::new(jac[j], jac[nv + j], jac[2 * nv + j]);
                let lever2 = col.length_squared();
                if lever2 == 0.0 {
                    continue;
                }
                let kpj = k_leg * lever2;
                let kdj = (2.0 * damping_ratio * (kpj * (diag[j - b] + mass * lever2)).sqrt())
                    .min(diag[j - b] / control_period_s);
                kp[j - b] = kp[j - b].max(kpj);
                kd[j - b] = kd[j - b].max(kdj);
            }
        }
        (kp, kd)
    }
}

/// Mean over legs of the straight leg's hip-pitch-to-foot length (m).
fn mean_leg_length_m(legs: &[LegKinematics]) -> f64 {
    if legs.is_empty() {
        return 0.0;
    }
    let sum: f64 = legs.iter().map(leg_length_m).sum();
    sum / legs.len() as f64
}

/// The straight leg's hip-pitch-to-foot length (m).
pub fn leg_length_m(leg: &LegKinematics) -> f64 {
    match leg {
        LegKinematics::Quad16(l) => l.reach_m(AnkleMode::Angle(0.0)).1,
        LegKinematics::Quad12(l) => l.reach_m().1,
        LegKinematics::Serial(l) => l.leg_length_m(),
    }
}

/// The generic stance (module docs), joints only.
fn generic_stance(model: &Model, legs: &[LegKinematics]) -> Vec<f64> {
    let nq0 = model.base_nq();
    let mut stance = vec![0.0; model.nq - nq0];
    let opts = IkOptions::default();
    let mut a = [0.0; 4];
    for leg in legs {
        let n = leg.dof();
        let zero = leg.fk(&a[..n]);
        let hip = leg.mount().trans;
        let len = leg_length_m(leg);
        let below = hip.z - zero.z;
        let target = if below > 0.5 * len {
            // a leg hanging at zero angles: straight down by 0.8 of it
            DVec3::new(zero.x, zero.y, zero.z + STANCE_CROUCH * below)
        } else {
            zero + (hip - zero).normalize_or_zero() * (STANCE_CROUCH * len)
        };
        if leg.ik_clamped_into(target, &opts, &mut a[..n]).is_err() {
            a = [0.0; 4];
        }
        for (k, &qi) in leg.q_indices().iter().enumerate() {
            stance[qi - nq0] = a[k];
        }
        a = [0.0; 4];
    }
    stance
}

/// [`RobotProfile::placement_hips_m`] at `stance` (joints only).
fn placement_hips(model: &Model, legs: &[LegKinematics], stance: &[f64]) -> Vec<DVec3> {
    let nq0 = model.base_nq();
    let hip_kind = |leg: &LegKinematics| match leg {
        LegKinematics::Quad16(_) => HipKind::Roll,
        LegKinematics::Quad12(_) => HipKind::Yaw,
        LegKinematics::Serial(l) => l.hip_kind(),
    };
    if legs.iter().all(|l| hip_kind(l) == HipKind::Roll) {
        let offset = |leg: &LegKinematics| match leg {
            LegKinematics::Quad16(l) => l.mount().rot * DVec3::new(0.0, l.lateral_offset_m(), 0.0),
            LegKinematics::Serial(l) => l.leg_frame() * DVec3::new(0.0, l.lateral_offset_m(), 0.0),
            LegKinematics::Quad12(_) => DVec3::ZERO,
        };
        if legs.iter().all(|l| offset(l) == DVec3::ZERO) {
            return Vec::new();
        }
        return legs.iter().map(|l| l.mount().trans + offset(l)).collect();
    }
    legs.iter()
        .map(|leg| {
            if hip_kind(leg) == HipKind::Roll {
                return leg.mount().trans;
            }
            let a: Vec<f64> = leg.q_indices().iter().map(|&i| stance[i - nq0]).collect();
            let mut p = leg.fk(&a);
            p.z = leg.mount().trans.z;
            p
        })
        .collect()
}
