//! Time series of one robot, decoded from its log channels (`/<robot>/com`,
//! `/attitude`, `/joint_states`, `/joint_commands`, `/feet`), the material of
//! the plots and of `quadsim replay`.

use crate::log::read::LogContents;

/// One foot at one sample.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FootPoint {
    /// Whether the foot touches the ground.
    pub in_contact: bool,
    /// Ground reaction force on the foot (N, world).
    pub force_n: [f64; 3],
    /// Foot contact point (m, world).
    pub position_m: [f64; 3],
}

/// A robot's logged samples (each channel with its own times; in a log they
/// coincide, but nothing here relies on it).
#[derive(Debug, Clone, Default)]
pub struct RobotSeries {
    /// Robot name.
    pub name: String,
    /// Times of the `/com` samples (s).
    pub com_t_s: Vec<f64>,
    /// CoM position (m, world).
    pub com_m: Vec<[f64; 3]>,
    /// CoM velocity (m/s, world).
    pub com_velocity_mps: Vec<[f64; 3]>,
    /// Times of the `/attitude` samples (s).
    pub attitude_t_s: Vec<f64>,
    /// Roll, pitch, yaw (rad; yaw unwrapped here, continuous across ±π).
    pub rpy_rad: Vec<[f64; 3]>,
    /// Actuated joint names.
    pub joint_names: Vec<String>,
    /// Times of the `/joint_states` samples (s).
    pub joint_t_s: Vec<f64>,
    /// Joint angles (rad), one row per sample.
    pub q_rad: Vec<Vec<f64>>,
    /// Applied joint torques (N·m).
    pub tau_nm: Vec<Vec<f64>>,
    /// Times of the `/joint_commands` samples (s).
    pub command_t_s: Vec<f64>,
    /// Desired joint angles (rad); `None` where the controller had no targets.
    pub q_desired_rad: Vec<Option<Vec<f64>>>,
    /// Foot names.
    pub foot_names: Vec<String>,
    /// Times of the `/feet` samples (s).
    pub feet_t_s: Vec<f64>,
    /// Feet per sample.
    pub feet: Vec<Vec<FootPoint>>,
}

/// The fields the series need, as typed structs (other fields are skipped).
mod msg {
    use serde::Deserialize;

    #[derive(Deserialize)]
    pub struct V3 {
        pub x: Option<f64>,
        pub y: Option<f64>,
        pub z: Option<f64>,
    }

    impl V3 {
        pub fn get(&self) -> [f64; 3] {
            let f = |v: Option<f64>| v.unwrap_or(f64::NAN);
            [f(self.x), f(self.y), f(self.z)]
        }
    }

    #[derive(Deserialize)]
    pub struct Com {
        pub position: V3,
        pub velocity: V3,
    }

    #[derive(Deserialize)]
    pub struct Attitude {
        pub roll: Option<f64>,
        pub pitch: Option<f64>,
        pub yaw: Option<f64>,
    }

    #[derive(Deserialize)]
    pub struct Joints {
        #[serde(default)]
        pub name: Vec<String>,
        pub position: Option<Vec<Option<f64>>>,
        pub effort: Option<Vec<Option<f64>>>,
    }

    #[derive(Deserialize)]
    pub struct Foot {
        pub name: String,
        pub in_contact: bool,
        pub force: V3,
        pub position: V3,
    }

    #[derive(Deserialize)]
    pub struct Feet {
        pub feet: Vec<Foot>,
    }
}

fn nums(v: Option<Vec<Option<f64>>>) -> Option<Vec<f64>> {
    v.map(|a| a.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
}

impl RobotSeries {
    /// Decodes robot `name`'s channels. A robot logged with `log = false` has
    /// none: the series are then empty.
    pub fn from_log(c: &LogContents, name: &str) -> Result<Self, String> {
        let mut s = RobotSeries {
            name: name.to_string(),
            ..Default::default()
        };
        fn decode<T: serde::de::DeserializeOwned>(
            c: &LogContents,
            topic: &str,
        ) -> Result<Vec<(f64, T)>, String> {
            c.topic(topic)
                .map(|m| {
                    m.json()
                        .and_then(serde_json::from_value)
                        .map(|j| (m.t_s(), j))
                        .map_err(|e| format!("{topic}: {e}"))
                })
                .collect()
        }
        for (t, j) in decode::<msg::Com>(c, &format!("/{name}/com"))? {
            s.com_t_s.push(t);
            s.com_m.push(j.position.get());
            s.com_velocity_mps.push(j.velocity.get());
        }
        let mut yaw_prev: Option<(f64, f64)> = None;
        for (t, j) in decode::<msg::Attitude>(c, &format!("/{name}/attitude"))? {
            let yaw = j.yaw.unwrap_or(f64::NAN);
            let unwrapped = match yaw_prev {
                None => yaw,
                Some((raw, un)) => {
                    let mut d = yaw - raw;
                    d -= (d / std::f64::consts::TAU).round() * std::f64::consts::TAU;
                    un + d
                }
            };
            yaw_prev = Some((yaw, unwrapped));
            s.attitude_t_s.push(t);
            s.rpy_rad.push([
                j.roll.unwrap_or(f64::NAN),
                j.pitch.unwrap_or(f64::NAN),
                unwrapped,
            ]);
        }
        for (t, j) in decode::<msg::Joints>(c, &format!("/{name}/joint_states"))? {
            if s.joint_names.is_empty() {
                s.joint_names = j.name;
            }
            s.joint_t_s.push(t);
            s.q_rad.push(nums(j.position).unwrap_or_default());
            s.tau_nm.push(nums(j.effort).unwrap_or_default());
        }
        for (t, j) in decode::<msg::Joints>(c, &format!("/{name}/joint_commands"))? {
            s.command_t_s.push(t);
            s.q_desired_rad.push(nums(j.position));
        }
        for (t, j) in decode::<msg::Feet>(c, &format!("/{name}/feet"))? {
            if s.foot_names.is_empty() {
                s.foot_names = j.feet.iter().map(|f| f.name.clone()).collect();
            }
            s.feet_t_s.push(t);
            s.feet.push(
                j.feet
                    .iter()
                    .map(|f| FootPoint {
                        in_contact: f.in_contact,
                        force_n: f.force.get(),
                        position_m: f.position.get(),
                    })
                    .collect(),
            );
        }
        Ok(s)
    }

    /// Whether the robot has per-step channels in the log.
    pub fn is_empty(&self) -> bool {
        self.com_t_s.is_empty()
    }

    /// The joints of one leg: those named with the first foot's prefix (the
    /// part before the first `_`, e.g. `LF`), else the first `nj / nfeet`.
    pub fn first_leg_joints(&self) -> Vec<usize> {
        let prefix = self
            .foot_names
            .first()
            .and_then(|f| f.split_once('_'))
            .map(|(p, _)| format!("{p}_"));
        if let Some(p) = prefix {
            let idx: Vec<usize> = (0..self.joint_names.len())
                .filter(|&j| self.joint_names[j].starts_with(&p))
                .collect();
            if !idx.is_empty() {
                return idx;
            }
        }
        let per_leg = self.joint_names.len() / self.foot_names.len().max(1);
        (0..per_leg.max(1).min(self.joint_names.len())).collect()
    }

    /// The stability margin at each `/feet` sample (m; `None` with fewer than
    /// three feet in contact), the CoM taken at the same index of `/com`.
    pub fn stability_margins(&self) -> Vec<Option<f64>> {
        self.feet
            .iter()
            .zip(&self.com_m)
            .map(|(feet, com)| {
                let pts: Vec<glam::DVec2> = feet
                    .iter()
                    .filter(|f| f.in_contact)
                    .map(|f| glam::DVec2::new(f.position_m[0], f.position_m[1]))
                    .collect();
                quadsim_engine::support::stability_margin(&pts, glam::DVec2::new(com[0], com[1]))
            })
            .collect()
    }
}
