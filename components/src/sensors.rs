//! Per-robot sensing: the robot's sensors, its base state estimator and the
//! sensed state its controller reads, written by the `Sense` stage.

use quadsim_engine::estimation::{BaseEstimator, EstimationErrors};
use quadsim_engine::sensors::SensorSuite;
use quadsim_engine::sensors::suite::SensorUpdates;

/// Which state a robot's controller reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StateSource {
    /// What a real robot sees: base from the estimator, joints from the
    /// encoders, contacts from the contact sensors.
    #[default]
    Estimated,
    /// The simulator's exact state (**ground truth**: no real robot has it).
    GroundTruth,
}

impl StateSource {
    /// The scenario spelling (`"estimated"`, `"ground_truth"`).
    pub fn as_str(self) -> &'static str {
        match self {
            StateSource::Estimated => "estimated",
            StateSource::GroundTruth => "ground_truth",
        }
    }
}

/// One robot's sensors, estimator and sensed state.
#[derive(Clone, Debug)]
pub struct RobotSensing {
    /// The sensors (each at its own rate).
    pub suite: SensorSuite,
    /// The base estimator (runs on every IMU sample; needs the IMU).
    pub estimator: Option<BaseEstimator>,
    /// What the controller reads.
    pub state_source: StateSource,
    /// Sensed generalised position (nq): estimated base, encoder joints
    /// (ground truth where a sensor is missing).
    pub q: Vec<f64>,
    /// Sensed generalised velocity (nv; base twist in the torso frame).
    pub v: Vec<f64>,
    /// Sensed contact flag per foot (the contact sensors; ground truth without them).
    pub contacts: Vec<bool>,
    /// Estimation error against ground truth, per estimator update.
    pub errors: EstimationErrors,
    /// What the last `Sense` stage sampled.
    pub updates: SensorUpdates,
    /// Scratch: each foot's true normal force (N).
    pub foot_force_n: Vec<f64>,
    /// Whether the `Sense` stage has already updated the robot's contact
    /// states ([`update_after_step`](quadsim_engine::contact::update_after_step))
    /// at its current `(q, v)` this step, so that the `Contact` stage must
    /// not update them again. Set by the `Sense` stage, cleared by the
    /// `Contact` stage.
    pub contacts_at_state: bool,
}

impl RobotSensing {
    /// Sensing with the given parts; the sensed state starts at `(q, v)`.
    pub fn new(
        suite: SensorSuite,
        estimator: Option<BaseEstimator>,
        state_source: StateSource,
        q: &[f64],
        v: &[f64],
        n_feet: usize,
    ) -> Self {
        RobotSensing {
            suite,
            estimator,
            state_source,
            q: q.to_vec(),
            v: v.to_vec(),
            contacts: vec![false; n_feet],
            errors: EstimationErrors::default(),
            updates: SensorUpdates::default(),
            contacts_at_state: false,
            foot_force_n: vec![0.0; n_feet],
        }
    }

    /// Whether the controller reads the sensed state.
    pub fn controls_on_estimate(&self) -> bool {
        self.state_source == StateSource::Estimated
    }
}
