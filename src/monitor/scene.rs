//! The world's scene for live 3D viewers: `quadsim/<world>/scene`, JSON.
//!
//! A frame carries the base pose and joint angles, not link poses; a viewer
//! needs each link's transform (the log's `/tf`) and shapes (`/scene`). So
//! when the robot list is announced, the run publishes, per robot, how each
//! link frame moves with the joints (the log's transform tree, composed
//! once per model), beside the log's own `/scene` and `/terrain` messages.
//! The bridge (`quadsim monitor --foxglove`) then rebuilds `/tf` from
//! frames without the models. At the end of a run each robot's metrics
//! (the log's `/<robot>/metrics`) follow.

use glam::{DQuat, DVec3};
use quadsim_engine::Model;
use quadsim_engine::model::JointType;
use quadsim_engine::spatial::Transform;
use serde::{Deserialize, Serialize};

use super::frame::RobotFrame;

/// A rigid transform `p_parent = t + r·p_child`: translation (m) and unit
/// quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rigid {
    /// Translation (m).
    pub t: [f64; 3],
    /// Rotation (x, y, z, w).
    pub r: [f64; 4],
}

impl Rigid {
    fn parts(self) -> (DVec3, DQuat) {
        (DVec3::from_array(self.t), DQuat::from_array(self.r))
    }

    fn of(t: DVec3, r: DQuat) -> Self {
        Self {
            t: t.to_array(),
            r: r.to_array(),
        }
    }
}

/// How a link frame's transform in its parent frame follows the state
/// (the log's transform tree, `quadsim_systems::frame_parents`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LinkMotion {
    /// Hangs from the world: the base pose composed with `placement`.
    Root {
        /// The link frame in the base body's frame.
        placement: Rigid,
    },
    /// Fixed in its parent frame (links merged by fixed joints).
    Fixed {
        /// The transform.
        offset: Rigid,
    },
    /// `pre ∘ joint motion ∘ post`.
    Joint {
        /// Parent frame to the joint frame.
        pre: Rigid,
        /// The joint's body to this frame.
        post: Rigid,
        /// Joint axis (joint frame).
        axis: [f64; 3],
        /// A prismatic joint (else revolute).
        prismatic: bool,
        /// The joint's index in the frame's joint arrays (`None`: not
        /// carried, e.g. a payload's coordinate; drawn at rest).
        joint: Option<usize>,
    },
}

/// One link frame of a robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinkPlan {
    /// Link name (frame id `<robot>/<link>`).
    pub name: String,
    /// Index of the parent link frame (`None`: the world).
    pub parent: Option<usize>,
    /// How its transform follows the state.
    pub motion: LinkMotion,
}

/// One robot: its names and link frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotPlan {
    /// Instance name.
    pub name: String,
    /// Actuated joints (velocity order, the frame's order).
    pub joints: Vec<String>,
    /// Feet (the frame's order).
    pub feet: Vec<String>,
    /// Link frames, in the model's frame order.
    pub links: Vec<LinkPlan>,
}

fn quat_of(t: &Transform) -> DQuat {
    if t.rot == glam::DMat3::IDENTITY {
        DQuat::IDENTITY
    } else {
        DQuat::from_mat3(&t.rot).normalize()
    }
}

fn compose((ta, qa): (DVec3, DQuat), (tb, qb): (DVec3, DQuat)) -> (DVec3, DQuat) {
    (ta + qa * tb, qa * qb)
}

fn inverse((t, r): (DVec3, DQuat)) -> (DVec3, DQuat) {
    (-(r.inverse() * t), r.inverse())
}

impl RobotPlan {
    /// The plan of robot `name` with `model`; `joints` and `feet` as the
    /// header names them.
    pub fn new(name: &str, model: &Model, joints: Vec<String>, feet: Vec<String>) -> Self {
        let parents = quadsim_systems::frame_parents(model);
        let in_body = |f: usize| {
            let p = &model.frames[f].placement;
            (p.trans, quat_of(p))
        };
        let links = (0..model.frames.len())
            .map(|f| {
                let b = model.frames[f].body;
                let motion = match parents[f] {
                    None => LinkMotion::Root {
                        placement: {
                            let (t, r) = in_body(f);
                            Rigid::of(t, r)
                        },
                    },
                    Some(pf) if model.frames[pf].body == b => {
                        let (t, r) = compose(inverse(in_body(pf)), in_body(f));
                        LinkMotion::Fixed {
                            offset: Rigid::of(t, r),
                        }
                    }
                    Some(pf) => {
                        let x = &model.placement[b];
                        let (pt, pr) = compose(inverse(in_body(pf)), (x.trans, quat_of(x)));
                        let (qt, qr) = in_body(f);
                        let v = model.idx_v[b];
                        let joint = (v >= model.base_nv() && v < model.actuated_nv())
                            .then(|| v - model.base_nv());
                        let moving = matches!(
                            model.joint_type[b],
                            JointType::Revolute | JointType::Prismatic
                        );
                        LinkMotion::Joint {
                            pre: Rigid::of(pt, pr),
                            post: Rigid::of(qt, qr),
                            axis: model.axis[b].to_array(),
                            prismatic: model.joint_type[b] == JointType::Prismatic,
                            joint: joint.filter(|_| moving),
                        }
                    }
                };
                LinkPlan {
                    name: model.frames[f].name.clone(),
                    parent: parents[f],
                    motion,
                }
            })
            .collect();
        Self {
            name: name.to_string(),
            joints,
            feet,
            links,
        }
    }

    /// Every link frame's transform in its parent frame at `frame`'s state,
    /// into `out` (cleared first): the log's `/tf` of that instant. The
    /// base link's is the frame's base pose, bit for bit the log's.
    pub fn link_transforms(&self, frame: &RobotFrame, out: &mut Vec<(DVec3, DQuat)>) {
        out.clear();
        let base = (
            DVec3::from_array(frame.base_position_m),
            DQuat::from_array(frame.base_orientation_xyzw),
        );
        out.extend(self.links.iter().map(|l| match l.motion {
            LinkMotion::Root { placement } => {
                if placement.t == [0.0; 3] && placement.r == [0.0, 0.0, 0.0, 1.0] {
                    base
                } else {
                    compose(base, placement.parts())
                }
            }
            LinkMotion::Fixed { offset } => offset.parts(),
            LinkMotion::Joint {
                pre,
                post,
                axis,
                prismatic,
                joint,
            } => {
                let qi = joint
                    .filter(|&k| k < frame.dof())
                    .map_or(0.0, |k| frame.joint_q_rad[k]);
                let qi = if qi.is_finite() { qi } else { 0.0 };
                let axis = DVec3::from_array(axis);
                let motion = if prismatic {
                    (axis * qi, DQuat::IDENTITY)
                } else if joint.is_some() {
                    (DVec3::ZERO, DQuat::from_axis_angle(axis, qi))
                } else {
                    (DVec3::ZERO, DQuat::IDENTITY)
                };
                compose(compose(pre.parts(), motion), post.parts())
            }
        }));
    }
}

/// A message of the scene service.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SceneMessage {
    /// The robots and the world's 3D scene, sent with every robot list.
    Scene {
        /// Counts the scenes a run sent (a viewer rebuilds on a new one).
        version: u64,
        /// Simulation time of the robot list (ns).
        t_ns: u64,
        /// The robots, in the header's order.
        robots: Vec<RobotPlan>,
        /// The log's `/scene` message (`foxglove.SceneUpdate`, JSON text).
        scene: String,
        /// The log's `/terrain` message (`quadsim.TerrainDescription`, JSON text).
        terrain: String,
    },
    /// Each robot's final metrics, at the end of a run.
    Metrics {
        /// Simulation time at the end (ns).
        t_ns: u64,
        /// `(robot, the log's /<robot>/metrics message as JSON text)`.
        robots: Vec<(String, String)>,
    },
}
