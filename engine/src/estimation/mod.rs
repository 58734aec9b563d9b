//! Base state estimation from the robot's own sensors, as open quadruped
//! stacks do it (MIT Cheetah: Bledt et al. 2018): an attitude filter on
//! the IMU ([`attitude`]) then a linear Kalman filter on base position and
//! velocity with the IMU's acceleration as input and the stance feet's
//! kinematics (encoders + forward kinematics) as measurements ([`kf`]).
//!
//! [`BaseEstimator::update`] runs once per IMU sample. It estimates the
//! torso's orientation, its velocity and its height above the ground; its
//! horizontal position is odometry (it drifts), and so is its yaw, unless
//! motion capture is fused ([`BaseEstimator::fuse_mocap`]: each delayed
//! pose corrects the estimate by its innovation against the estimate at
//! the capture time). [`BaseEstimator::write_state`] assembles the
//! generalised `(q, v)` a controller reads. Equations and tuning:
//! `docs/sensors.md`.

pub mod attitude;
pub mod kf;

use glam::{DMat3, DQuat, DVec3};

use crate::contact::ContactPoint;
use crate::data::{Data, SpareData};
use crate::dispatch::{forward_kinematics, forward_kinematics_unrecorded, leg_end_points};
use crate::kinematics::base_quat;
use crate::model::Model;
use crate::sensors::MocapSample;
use crate::terrain::{Terrain, TerrainUnion};

pub use attitude::{AttitudeFilter, AttitudeParams};
pub use kf::{BaseKf, FootMeasurement, KF_FEET, KfParams};

/// Tuning of the [`BaseEstimator`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimatorParams {
    /// Attitude filter gains.
    pub attitude: AttitudeParams,
    /// Kalman filter noise figures.
    pub kf: KfParams,
    /// Motion-capture fusion (used only when mocap samples are fused).
    pub mocap: MocapFusionParams,
}

/// How [`BaseEstimator::fuse_mocap`] weighs motion capture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapFusionParams {
    /// Whether delivered mocap samples are fused (the simulation's sensing
    /// stage asks; a test may fuse by hand).
    pub enabled: bool,
    /// Position measurement noise per axis (m), the Kalman update's.
    pub position_std_m: f64,
    /// Time constant (s) with which the orientation is pulled toward the
    /// captured one (a complementary filter: the IMU keeps the fast motion,
    /// mocap removes the drift, in yaw above all).
    pub orientation_time_constant_s: f64,
}

impl Default for MocapFusionParams {
    /// On; 2 mm (a few times a typical optical system's noise, for its
    /// jitter and marker placement) and 0.1 s.
    fn default() -> Self {
        MocapFusionParams {
            enabled: true,
            position_std_m: 0.002,
            orientation_time_constant_s: 0.1,
        }
    }
}

/// Estimates kept for delayed measurements: (time, position, orientation).
/// 256 updates: 0.5 s at a 500 Hz IMU.
const HISTORY: usize = 256;

/// The estimated base state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BaseEstimate {
    /// Time of the estimate (s).
    pub t_s: f64,
    /// Torso orientation (torso → world).
    pub orientation: DQuat,
    /// Torso origin position (m, world; x and y are odometry and drift).
    pub position_m: DVec3,
    /// Torso origin velocity (m/s, world).
    pub velocity_world_mps: DVec3,
    /// Bias-corrected angular velocity (rad/s, torso frame).
    pub omega_body_radps: DVec3,
    /// Torso origin height above the ground beneath the estimated position (m).
    pub height_m: f64,
}

/// What one update reads: an IMU sample, the encoders and the contact flags.
#[derive(Clone, Copy, Debug)]
pub struct EstimatorInput<'a> {
    /// Time (s).
    pub t_s: f64,
    /// Time since the previous update (s).
    pub dt_s: f64,
    /// Gyroscope (rad/s, torso frame).
    pub gyro_radps: DVec3,
    /// Accelerometer: specific force (m/s², torso frame).
    pub accel_mps2: DVec3,
    /// Measured joint angles (rad).
    pub q_joints_rad: &'a [f64],
    /// Measured joint velocities (rad/s).
    pub qd_joints_radps: &'a [f64],
    /// Sensed contact per foot.
    pub contacts: &'a [bool],
    /// The ground (the map the robot knows).
    pub terrain: &'a TerrainUnion,
}

/// The base state estimator of one robot.
#[derive(Clone, Debug)]
pub struct BaseEstimator {
    /// Attitude filter.
    pub attitude: AttitudeFilter,
    /// Position/velocity filter.
    pub kf: BaseKf,
    /// Tuning.
    pub params: EstimatorParams,
    /// The latest estimate.
    pub estimate: BaseEstimate,
    feet: Vec<ContactPoint>,
    gravity_mps2: DVec3,
    q_fk: Vec<f64>,
    v_fk: Vec<f64>,
    meas: [FootMeasurement; KF_FEET],
    stance: [bool; KF_FEET],
    /// The last [`HISTORY`] estimates, oldest first once full (a ring at
    /// `history_head`): delayed measurements are compared with the estimate
    /// of their capture time.
    history: Vec<(f64, DVec3, DQuat)>,
    history_head: usize,
    /// Time of the last fused mocap capture (s).
    last_mocap_t_s: Option<f64>,
    /// The position filter's velocity at the previous update (m/s, world),
    /// whose change is the base acceleration the attitude filter removes.
    previous_velocity_mps: DVec3,
    /// That acceleration (m/s², world), from the last two updates.
    base_accel_world_mps2: DVec3,
}

impl BaseEstimator {
    /// An estimator for `model` whose feet are the contact spheres `feet`
    /// (at most [`KF_FEET`]; a stance foot's sphere centre is taken to be
    /// one radius above the ground), started at the state
    /// `(q0, v0)` at `t0_s` (the start pose is known: the odometry frame is
    /// the world frame at the start).
    pub fn new(
        model: &Model,
        feet: &[ContactPoint],
        params: EstimatorParams,
        q0: &[f64],
        v0: &[f64],
        t0_s: f64,
    ) -> Self {
        let mut data = Data::for_kinematics(model);
        forward_kinematics(model, &mut data, q0, v0);
        let feet: Vec<ContactPoint> = feet.iter().take(KF_FEET).copied().collect();
        let feet_world: Vec<DVec3> = feet
            .iter()
            .map(|f| data.body_point_world(f.body, f.point_in_body))
            .collect();
        let rot = data.pose[0].rot;
        let orientation = base_quat(q0);
        let p0 = DVec3::new(q0[0], q0[1], q0[2]);
        let v_world = rot * DVec3::new(v0[0], v0[1], v0[2]);
        let mut q_fk = q0.to_vec();
        q_fk[..7].copy_from_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        BaseEstimator {
            attitude: AttitudeFilter::new(params.attitude, orientation),
            kf: BaseKf::new(params.kf, p0, v_world, &feet_world),
            estimate: BaseEstimate {
                t_s: t0_s,
                orientation,
                position_m: p0,
                velocity_world_mps: v_world,
                omega_body_radps: DVec3::new(v0[3], v0[4], v0[5]),
                height_m: f64::NAN,
            },
            feet,
            gravity_mps2: model.gravity,
            q_fk,
            v_fk: vec![0.0; model.nv],
            meas: [FootMeasurement::default(); KF_FEET],
            stance: [false; KF_FEET],
            // only mocap fusion reads the history: without it, none is kept
            history: Vec::with_capacity(if params.mocap.enabled { HISTORY } else { 0 }),
            history_head: 0,
            last_mocap_t_s: None,
            previous_velocity_mps: v_world,
            base_accel_world_mps2: DVec3::ZERO,
            params,
        }
    }

    /// One estimator update (call on every new IMU sample). A robot whose
    /// legs do not run in lanes computes its leg kinematics in a
    /// kinematics-only spare of `spares` ([`SpareData::kinematics_only`]).
    pub fn update(&mut self, model: &Model, input: &EstimatorInput<'_>, spares: &mut SpareData) {
        let dt = input.dt_s.max(0.0);
        // 1. attitude, with the base's acceleration of the last update
        //    (from the position filter: leg odometry pins its velocity)
        let base_accel = if self.params.attitude.compensate_base_acceleration {
            self.base_accel_world_mps2
        } else {
            DVec3::ZERO
        };
        self.attitude.update_compensated(
            input.gyro_radps,
            input.accel_mps2,
            base_accel,
            self.gravity_mps2.length(),
            dt,
        );
        let rot = DMat3::from_quat(self.attitude.orientation);
        let omega = self.attitude.omega_radps;
        // 2. prediction with the IMU acceleration
        for (i, s) in self.stance.iter_mut().enumerate() {
            *s = input.contacts.get(i).copied().unwrap_or(false);
        }
        let a_world = rot * input.accel_mps2 + self.gravity_mps2;
        self.kf.predict(a_world, &self.stance, dt);
        // 3. leg kinematics in the torso frame (base at the origin, at rest)
        let nq0 = model.base_nq();
        let nv0 = model.base_nv();
        // The actuated joints; a compliant load's coordinates (after them)
        // stay at rest: the estimator sees the load frozen, as controllers do.
        let (nj_q, nj_v) = (input.q_joints_rad.len(), input.qd_joints_radps.len());
        self.q_fk[nq0..nq0 + nj_q].copy_from_slice(input.q_joints_rad);
        self.v_fk[nv0..nv0 + nj_v].copy_from_slice(input.qd_joints_radps);
        // each foot's position and velocity (torso frame)
        let mut ends = [(DVec3::ZERO, DVec3::ZERO); KF_FEET];
        let n = self.feet.len();
        let lane_ends = self.lanes_of_feet(model).and_then(|(lane, points)| {
            leg_end_points(model, &self.q_fk, &self.v_fk, points).map(|e| (lane, e))
        });
        if let Some((lane, (r, rd))) = lane_ends {
            // the feet are the legs' last bodies: their chains only
            for (e, &k) in ends.iter_mut().zip(&lane) {
                *e = (r[k], rd[k]);
            }
        } else {
            // on a kinematics-only spare: nothing reads it later
            spares.with(model, |data| {
                forward_kinematics_unrecorded(model, data, &self.q_fk, &self.v_fk);
                for (e, foot) in ends.iter_mut().zip(&self.feet) {
                    *e = (
                        data.body_point_world(foot.body, foot.point_in_body),
                        data.body_point_velocity(foot.body, foot.point_in_body),
                    );
                }
            });
        }
        for (i, (foot, &(r, rd))) in self.feet.iter().zip(&ends[..n]).enumerate() {
            let rel = rot * r;
            let foot_guess = self.kf.position_m() + rel;
            self.meas[i] = FootMeasurement {
                relative_position_m: rel,
                relative_velocity_mps: rot * (omega.cross(r) + rd),
                stance: self.stance[i],
                ground_height_m: input
                    .terrain
                    .height(foot_guess.x, foot_guess.y)
                    .map_or(foot_guess.z, |h| h + foot.radius_m),
            };
        }
        // 4. measurement update
        self.kf.update(&self.meas[..n]);
        let v = self.kf.velocity_mps();
        if dt > 0.0 {
            self.base_accel_world_mps2 = (v - self.previous_velocity_mps) / dt;
        }
        self.previous_velocity_mps = v;
        self.set_estimate(input.t_s, omega, input.terrain);
        self.remember();
    }

    /// Where the feet are on `model`'s legs in lanes: when each of the
    /// [`KF_FEET`] feet is on the last body of a different leg of
    /// [`Model::leg_lanes`], the lane of each foot and each lane's foot
    /// point (in its body's frame), for [`leg_end_points`].
    fn lanes_of_feet(&self, model: &Model) -> Option<([usize; KF_FEET], [DVec3; KF_FEET])> {
        let last = model.leg_lanes()?.groups.last()?;
        if self.feet.len() != KF_FEET {
            return None;
        }
        let mut lane = [0; KF_FEET];
        let mut points = [DVec3::ZERO; KF_FEET];
        let mut taken = [false; KF_FEET];
        for (l, foot) in lane.iter_mut().zip(&self.feet) {
            let k = last.iter().position(|&b| b == foot.body)?;
            if std::mem::replace(&mut taken[k], true) {
                return None;
            }
            *l = k;
            points[k] = foot.point_in_body;
        }
        Some((lane, points))
    }

    /// The estimate from the filters' state at `t_s`, with the angular
    /// velocity `omega` (torso frame) and the height above `terrain`.
    fn set_estimate(&mut self, t_s: f64, omega: DVec3, terrain: &TerrainUnion) {
        let p = self.kf.position_m();
        let ground = terrain.height(p.x, p.y).unwrap_or(0.0);
        self.estimate = BaseEstimate {
            t_s,
            orientation: self.attitude.orientation,
            position_m: p,
            velocity_world_mps: self.kf.velocity_mps(),
            omega_body_radps: omega,
            height_m: p.z - ground,
        };
    }

    /// Records the latest estimate in the history ring (kept only while
    /// mocap fusion is enabled: an estimator built without it keeps none).
    fn remember(&mut self) {
        if !self.params.mocap.enabled {
            return;
        }
        let e = (
            self.estimate.t_s,
            self.estimate.position_m,
            self.estimate.orientation,
        );
        if self.history.len() < HISTORY {
            self.history.push(e);
        } else {
            self.history[self.history_head] = e;
            self.history_head = (self.history_head + 1) % HISTORY;
        }
    }

    /// Fuses one motion-capture sample (captured at `s.captured_t_s`,
    /// delivered now): the innovation is taken against the estimate of the
    /// capture time from the history, then applied to the current estimate
    /// (position: a Kalman update of `p̂_now` with `z = p̂_now + (p_mocap −
    /// p̂(t_c))`; orientation: a fraction `1 − exp(−Δt/τ)` of the rotation
    /// from `R̂(t_c)` to the captured one, Δt the time since the previous
    /// capture); the estimates kept since the capture are shifted by the
    /// same correction, so the next sample's innovation does not count it
    /// twice. A capture newer than the latest estimate is compared with the
    /// latest. Returns false (and changes nothing) when the capture is older
    /// than the history.
    pub fn fuse_mocap(&mut self, terrain: &TerrainUnion, s: &MocapSample) -> bool {
        let n = self.history.len();
        let at = |k: usize| (self.history_head + k) % n.max(1);
        // the newest estimate at or before the capture
        let Some(k_c) = (0..n)
            .rev()
            .find(|&k| self.history[at(k)].0 <= s.captured_t_s + 1e-9)
        else {
            return false;
        };
        let (_, p_c, q_c) = self.history[at(k_c)];
        let mp = self.params.mocap;
        // position
        let p_before = self.kf.position_m();
        self.kf
            .update_position(p_before + (s.position_m - p_c), mp.position_std_m);
        let dp = self.kf.position_m() - p_before;
        // orientation
        let dt = self
            .last_mocap_t_s
            .map_or(0.0, |t| (s.captured_t_s - t).max(0.0));
        self.last_mocap_t_s = Some(s.captured_t_s);
        let tau = mp.orientation_time_constant_s;
        let alpha = if tau > 0.0 {
            1.0 - (-dt / tau).exp()
        } else {
            1.0
        };
        let err = (s.orientation * q_c.inverse()).normalize();
        let dq = DQuat::IDENTITY.slerp(err, alpha).normalize();
        self.attitude.orientation = (dq * self.attitude.orientation).normalize();
        // the estimates since the capture carry the same correction
        for k in k_c..n {
            let i = at(k);
            let (t, p, q) = self.history[i];
            self.history[i] = (t, p + dp, (dq * q).normalize());
        }
        let (t_s, omega) = (self.estimate.t_s, self.estimate.omega_body_radps);
        self.set_estimate(t_s, omega, terrain);
        true
    }

    /// The generalised state a controller reads: base from the estimate,
    /// joints from `q_joints_rad`/`qd_joints_radps` (Pinocchio's layout:
    /// base linear and angular velocity in the torso frame).
    pub fn write_state(
        &self,
        model: &Model,
        q_joints_rad: &[f64],
        qd_joints_radps: &[f64],
        q_out: &mut [f64],
        v_out: &mut [f64],
    ) {
        let e = &self.estimate;
        let o = e.orientation;
        q_out[..7].copy_from_slice(&[
            e.position_m.x,
            e.position_m.y,
            e.position_m.z,
            o.x,
            o.y,
            o.z,
            o.w,
        ]);
        let v_body = o.inverse() * e.velocity_world_mps;
        v_out[..3].copy_from_slice(&v_body.to_array());
        v_out[3..6].copy_from_slice(&e.omega_body_radps.to_array());
        let (nq0, nv0) = (model.base_nq(), model.base_nv());
        q_out[nq0..nq0 + q_joints_rad.len()].copy_from_slice(q_joints_rad);
        v_out[nv0..nv0 + qd_joints_radps.len()].copy_from_slice(qd_joints_radps);
    }
}

/// RMS and maximum of one error signal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStat {
    /// Samples.
    pub n: u64,
    /// Σ e².
    pub sum_sq: f64,
    /// max |e|.
    pub max: f64,
}

impl ErrorStat {
    /// Adds one error sample.
    pub fn record(&mut self, e: f64) {
        self.n += 1;
        self.sum_sq += e * e;
        self.max = self.max.max(e.abs());
    }

    /// Root mean square (NaN before any sample).
    pub fn rms(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            (self.sum_sq / self.n as f64).sqrt()
        }
    }
}

/// Estimation error against ground truth, accumulated per estimator update.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimationErrors {
    /// Orientation: angle of `R̂ᵀ R` (rad).
    pub orientation_rad: ErrorStat,
    /// Tilt only: angle between the estimated and true torso z axes (rad).
    pub tilt_rad: ErrorStat,
    /// Base velocity: `|v̂ − v|` (m/s, world).
    pub velocity_mps: ErrorStat,
    /// Height above ground: `|ĥ − h|` (m).
    pub height_m: ErrorStat,
}

impl EstimationErrors {
    /// Adds the error of `est` against the true orientation, world velocity
    /// and height above ground.
    pub fn record(
        &mut self,
        est: &BaseEstimate,
        orientation: DQuat,
        velocity_world_mps: DVec3,
        height_m: f64,
    ) {
        self.orientation_rad
            .record(est.orientation.angle_between(orientation));
        let z_hat = est.orientation * DVec3::Z;
        let z = orientation * DVec3::Z;
        self.tilt_rad.record(z_hat.angle_between(z));
        self.velocity_mps
            .record((est.velocity_world_mps - velocity_world_mps).length());
        self.height_m.record(est.height_m - height_m);
    }
}
