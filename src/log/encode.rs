//! Encoding of log records into channel messages: the per-step channels in
//! protobuf ([`super::proto`]), the scene in JSON (see [`super::schema`] for
//! the shapes; JSON has no non-finite numbers: they are written as `null`).

use glam::{DQuat, DVec3};
use quadsim_engine::description::{Geometry, Shape};
use quadsim_engine::spatial::Transform;
use quadsim_systems::{RobotInfo, RobotSample};
use serde::Serialize;

use super::proto::Pb;

/// `{sec, nsec}` from simulation nanoseconds.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct Time {
    /// Seconds.
    pub sec: u64,
    /// Nanoseconds in the second.
    pub nsec: u32,
}

impl Time {
    /// The time `t_ns` nanoseconds after the start.
    pub fn from_ns(t_ns: u64) -> Self {
        Time {
            sec: t_ns / 1_000_000_000,
            nsec: (t_ns % 1_000_000_000) as u32,
        }
    }
}

/// `{x, y, z}`.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct V3 {
    x: f64,
    y: f64,
    z: f64,
}

impl From<DVec3> for V3 {
    fn from(v: DVec3) -> Self {
        V3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

/// `{x, y, z, w}`.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct Q {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

impl From<DQuat> for Q {
    fn from(q: DQuat) -> Self {
        Q {
            x: q.x,
            y: q.y,
            z: q.z,
            w: q.w,
        }
    }
}

/// `{position, orientation}`.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct Pose {
    position: V3,
    orientation: Q,
}

impl From<&Transform> for Pose {
    fn from(t: &Transform) -> Self {
        Pose {
            position: t.trans.into(),
            orientation: DQuat::from_mat3(&t.rot).normalize().into(),
        }
    }
}

/// Names a robot's messages need, encoded as protobuf fields once per
/// [`RobotInfo`] (the hot path then copies bytes).
#[derive(Debug, Clone)]
pub struct RobotNames {
    /// Robot name.
    pub robot: String,
    /// The actuated joints' names as `JointState.name` fields (velocity order).
    joints: Vec<u8>,
    /// Each foot's name as a `FootContact.name` field (model order).
    feet: Vec<Vec<u8>>,
    /// Per model frame: its `parent_frame_id` and `child_frame_id` fields
    /// (`"<robot>/<link>"`; the base's parent is `"world"`).
    frames: Vec<Vec<u8>>,
}

/// `s` as protobuf string field `field`.
fn string_field(field: u32, s: &str) -> Vec<u8> {
    let mut b = Vec::new();
    Pb(&mut b).string(field, s);
    b
}

impl RobotNames {
    /// The names of `info`'s robot.
    pub fn new(info: &RobotInfo) -> Self {
        let parents = quadsim_systems::frame_parents(&info.model);
        RobotNames {
            robot: info.name.clone(),
            joints: info
                .joint_names()
                .iter()
                .flat_map(|n| string_field(2, n))
                .collect(),
            feet: info
                .foot_names()
                .iter()
                .map(|n| string_field(1, n))
                .collect(),
            frames: info
                .model
                .frames
                .iter()
                .zip(&parents)
                .map(|(f, p)| {
                    let parent = match p {
                        Some(i) => frame_id(&info.name, &info.model.frames[*i].name),
                        None => WORLD.to_string(),
                    };
                    let mut b = string_field(2, &parent);
                    b.extend(string_field(3, &frame_id(&info.name, &f.name)));
                    b
                })
                .collect(),
        }
    }
}

impl RobotNames {
    /// The names of robot `robot` from its joints (velocity order), feet
    /// (model order) and link frames `(parent frame id, link name)`: what
    /// [`Self::new`] takes from a model, for a reader without one (the live
    /// Foxglove bridge).
    pub fn from_parts(
        robot: &str,
        joints: &[String],
        feet: &[String],
        frames: &[(String, String)],
    ) -> Self {
        RobotNames {
            robot: robot.to_string(),
            joints: joints.iter().flat_map(|n| string_field(2, n)).collect(),
            feet: feet.iter().map(|n| string_field(1, n)).collect(),
            frames: frames
                .iter()
                .map(|(parent, link)| {
                    let mut b = string_field(2, parent);
                    b.extend(string_field(3, &frame_id(robot, link)));
                    b
                })
                .collect(),
        }
    }
}

/// The frame id of the world, the base links' parent.
pub const WORLD_FRAME: &str = WORLD;

/// The frame id of a robot's link: `<robot>/<link>`.
pub fn frame_id(robot: &str, link: &str) -> String {
    format!("{robot}/{link}")
}

/// The per-robot channels of one sample, in a fixed order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RobotTopic {
    /// `/<robot>/base_pose`
    BasePose,
    /// `/<robot>/base_twist`
    BaseTwist,
    /// `/<robot>/attitude`
    Attitude,
    /// `/<robot>/com`
    Com,
    /// `/<robot>/joint_states`
    JointStates,
    /// `/<robot>/joint_commands`
    JointCommands,
    /// `/<robot>/feet`
    Feet,
    /// `/<robot>/virtual_wrench`
    VirtualWrench,
    /// `/<robot>/sensors` (robots with sensors only)
    Sensors,
}

impl RobotTopic {
    /// Every per-step topic, in write order.
    pub const ALL: [RobotTopic; 9] = [
        RobotTopic::BasePose,
        RobotTopic::BaseTwist,
        RobotTopic::Attitude,
        RobotTopic::Com,
        RobotTopic::JointStates,
        RobotTopic::JointCommands,
        RobotTopic::Feet,
        RobotTopic::VirtualWrench,
        RobotTopic::Sensors,
    ];

    /// The topic's last path element.
    pub fn suffix(self) -> &'static str {
        match self {
            RobotTopic::BasePose => "base_pose",
            RobotTopic::BaseTwist => "base_twist",
            RobotTopic::Attitude => "attitude",
            RobotTopic::Com => "com",
            RobotTopic::JointStates => "joint_states",
            RobotTopic::JointCommands => "joint_commands",
            RobotTopic::Feet => "feet",
            RobotTopic::VirtualWrench => "virtual_wrench",
            RobotTopic::Sensors => "sensors",
        }
    }

    /// The topic of robot `robot`.
    pub fn topic(self, robot: &str) -> String {
        format!("/{robot}/{}", self.suffix())
    }

    /// The topic's schema.
    pub fn schema(self) -> super::schema::Schema {
        use super::schema::Schema;
        match self {
            RobotTopic::BasePose => Schema::PoseInFrame,
            RobotTopic::BaseTwist => Schema::Twist,
            RobotTopic::Attitude => Schema::Attitude,
            RobotTopic::Com => Schema::CenterOfMass,
            RobotTopic::JointStates | RobotTopic::JointCommands => Schema::JointState,
            RobotTopic::Feet => Schema::FootContacts,
            RobotTopic::VirtualWrench => Schema::Wrench,
            RobotTopic::Sensors => Schema::Sensors,
        }
    }
}

const WORLD: &str = "world";

/// Encodes `topic` of sample `s` at `t_ns` into `out` (cleared first), as
/// protobuf (`foxglove.PoseInFrame`, `quadsim.*`: [`super::proto`]). Field
/// numbers follow the schemas' declarations; an absent optional value
/// (no joint targets, no virtual wrench, no such sensor) is left out.
pub fn encode_robot(
    topic: RobotTopic,
    names: &RobotNames,
    s: &RobotSample,
    t_ns: u64,
    out: &mut Vec<u8>,
) {
    out.clear();
    let mut m = Pb(out);
    m.time(1, t_ns);
    match topic {
        RobotTopic::BasePose => {
            m.string(2, WORLD);
            m.message(3, |p| {
                p.v3(1, s.base_position_m);
                p.quat(2, s.base_orientation);
            });
        }
        RobotTopic::BaseTwist => {
            m.string(2, WORLD);
            m.v3(3, s.base_linear_mps);
            m.v3(4, s.base_angular_radps);
        }
        RobotTopic::Attitude => {
            m.double(2, s.rpy_rad.x);
            m.double(3, s.rpy_rad.y);
            m.double(4, s.rpy_rad.z);
        }
        RobotTopic::Com => {
            m.string(2, WORLD);
            m.v3(3, s.com_m);
            m.v3(4, s.com_velocity_mps);
            m.v3(5, s.com_acceleration_mps2);
        }
        RobotTopic::JointStates | RobotTopic::JointCommands => {
            let (p, v, e) = if topic == RobotTopic::JointStates {
                (
                    Some(&s.joint_position[..]),
                    Some(&s.joint_velocity[..]),
                    &s.joint_effort,
                )
            } else {
                (
                    s.joint_position_desired.as_deref(),
                    s.joint_velocity_desired.as_deref(),
                    &s.joint_effort_command,
                )
            };
            m.0.extend_from_slice(&names.joints);
            m.doubles(3, p.unwrap_or_default());
            m.doubles(4, v.unwrap_or_default());
            m.doubles(5, e);
        }
        RobotTopic::Feet => {
            m.string(2, WORLD);
            for (f, name) in s.feet.iter().zip(&names.feet) {
                m.message(3, |c| {
                    c.0.extend_from_slice(name);
                    c.bool(2, f.in_contact);
                    c.bool(3, f.slipping);
                    c.double(4, f.penetration_m);
                    c.double(5, f.normal_force_n);
                    c.v3(6, f.force_n);
                    c.v3(7, f.position_m);
                    if let Some(x) = f.gait_phase {
                        c.double(8, x);
                    }
                });
            }
        }
        RobotTopic::VirtualWrench => {
            m.string(2, WORLD);
            if let Some((f, t)) = s.virtual_wrench {
                m.v3(3, f);
                m.v3(4, t);
            }
        }
        RobotTopic::Sensors => {
            // (the writer writes this topic only for robots with sensors)
            let Some(x) = &s.sensing else {
                return;
            };
            if let Some((a, g)) = x.imu {
                m.v3(2, a);
                m.v3(3, g);
            }
            m.doubles(4, x.encoder_position_rad.as_deref().unwrap_or_default());
            m.doubles(5, x.encoder_velocity_radps.as_deref().unwrap_or_default());
            m.bools(6, &x.contact);
            if let Some(e) = &x.estimate {
                m.message(7, |b| {
                    b.v3(1, e.position_m);
                    b.quat(2, e.orientation);
                    b.v3(3, e.velocity_world_mps);
                    b.double(4, e.height_m);
                });
            }
            m.doubles(8, x.contact_force_n.as_deref().unwrap_or_default());
            if let Some(c) = &x.mocap {
                m.message(9, |b| {
                    b.time(1, (c.captured_t_s * 1e9).round().max(0.0) as u64);
                    b.v3(2, c.position_m);
                    b.quat(3, c.orientation);
                });
            }
        }
    }
}

/// Encodes the `/tf` message (`foxglove.FrameTransforms`, protobuf): every
/// link frame of every sampled robot in its parent link's frame (the base
/// link in `world`), a tree like ROS's `robot_state_publisher` publishes, in
/// full precision.
pub fn encode_transforms(samples: &[(&RobotNames, &RobotSample)], t_ns: u64, out: &mut Vec<u8>) {
    out.clear();
    // the timestamp field, the same in every transform
    let mut time = Vec::with_capacity(16);
    Pb(&mut time).time(1, t_ns);
    let mut m = Pb(out);
    for (names, s) in samples {
        for (pose, frames) in s.link_transforms.iter().zip(&names.frames) {
            m.message(1, |f| {
                f.0.extend_from_slice(&time);
                f.0.extend_from_slice(frames);
                f.v3(4, pose.0);
                f.quat(5, pose.1);
            });
        }
    }
}

/// RGBA in 0–1.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct Color {
    r: f64,
    g: f64,
    b: f64,
    a: f64,
}

const LINK_COLOR: Color = Color {
    r: 0.55,
    g: 0.6,
    b: 0.7,
    a: 1.0,
};
const GROUND_COLOR: Color = Color {
    r: 0.55,
    g: 0.5,
    b: 0.42,
    a: 1.0,
};

/// A `foxglove.SceneEntity` with every field of Foxglove's schema, in its
/// order (unused primitive lists empty), so that a reader holding to the
/// schema finds them all.
#[derive(Serialize, Default)]
struct Entity<'a> {
    timestamp: Option<Time>,
    frame_id: String,
    id: String,
    lifetime: Option<Time>,
    frame_locked: bool,
    metadata: Vec<KeyValue<'a>>,
    arrows: Vec<serde_json::Value>,
    cubes: Vec<serde_json::Value>,
    spheres: Vec<serde_json::Value>,
    cylinders: Vec<serde_json::Value>,
    lines: Vec<serde_json::Value>,
    triangles: Vec<serde_json::Value>,
    texts: Vec<serde_json::Value>,
    models: Vec<serde_json::Value>,
}

#[derive(Serialize)]
struct KeyValue<'a> {
    key: &'a str,
    value: String,
}

#[derive(Serialize)]
struct Deletion {
    timestamp: Time,
    #[serde(rename = "type")]
    kind: u8,
    id: String,
}

#[derive(Serialize)]
struct SceneUpdate<'a> {
    deletions: Vec<Deletion>,
    entities: Vec<Entity<'a>>,
}

fn pose_json(t: &Transform) -> serde_json::Value {
    serde_json::to_value(Pose::from(t)).expect("pose")
}

/// Adds one link geometry to an entity's primitives (shapes in the link frame).
fn add_geometry(e: &mut Entity<'_>, g: &Geometry, color: Color) {
    use serde_json::json;
    let pose = pose_json(&g.origin);
    match &g.shape {
        Shape::Box { size_m } => e.cubes.push(json!({
            "pose": pose, "size": V3::from(*size_m), "color": color,
        })),
        Shape::Sphere { radius_m } => e.spheres.push(json!({
            "pose": pose, "size": V3::from(DVec3::splat(2.0 * radius_m)), "color": color,
        })),
        Shape::Cylinder { radius_m, length_m } => e.cylinders.push(json!({
            "pose": pose,
            "size": V3::from(DVec3::new(2.0 * radius_m, 2.0 * radius_m, *length_m)),
            "bottom_scale": 1.0, "top_scale": 1.0, "color": color,
        })),
        Shape::Capsule { radius_m, length_m } => {
            e.cylinders.push(json!({
                "pose": pose,
                "size": V3::from(DVec3::new(2.0 * radius_m, 2.0 * radius_m, *length_m)),
                "bottom_scale": 1.0, "top_scale": 1.0, "color": color,
            }));
            for end in [-0.5, 0.5] {
                let cap = g.origin.compose(&Transform {
                    rot: glam::DMat3::IDENTITY,
                    trans: DVec3::new(0.0, 0.0, end * length_m),
                });
                e.spheres.push(json!({
                    "pose": pose_json(&cap),
                    "size": V3::from(DVec3::splat(2.0 * radius_m)), "color": color,
                }));
            }
        }
        Shape::Mesh { uri, scale, .. } => e.models.push(json!({
            "pose": pose,
            "scale": V3::from(*scale),
            "color": color,
            "override_color": false,
            "url": uri,
            "media_type": "",
            "data": "",
        })),
    }
}

/// A ground surface for the 3D scene: a triangle mesh (world frame).
#[derive(Debug, Clone, Default)]
pub struct GroundMesh {
    /// Vertices (m, world).
    pub points: Vec<DVec3>,
    /// Triangles as vertex index triples.
    pub indices: Vec<u32>,
}

/// Encodes a `/scene` update: the ground and every robot's link shapes
/// (visual shapes, else collision shapes), each link an entity in its own
/// frame `<robot>/<link>` that follows `/tf`. With `replace_all`, a deletion
/// of every earlier entity comes first (after a model change).
pub fn encode_scene(
    robots: &[RobotInfo],
    ground: &GroundMesh,
    t_ns: u64,
    replace_all: bool,
    out: &mut Vec<u8>,
) {
    out.clear();
    let timestamp = Time::from_ns(t_ns);
    let mut entities = Vec::new();
    if !ground.indices.is_empty() {
        let mut e = Entity {
            timestamp: Some(timestamp),
            frame_id: WORLD.into(),
            id: "ground".into(),
            lifetime: Some(Time { sec: 0, nsec: 0 }),
            ..Default::default()
        };
        e.triangles.push(serde_json::json!({
            "pose": pose_json(&Transform::IDENTITY),
            "points": ground.points.iter().map(|p| V3::from(*p)).collect::<Vec<_>>(),
            "color": GROUND_COLOR,
            "colors": [],
            "indices": ground.indices,
        }));
        entities.push(e);
    }
    for r in robots {
        for link in &r.description.links {
            let shapes = if link.visual.is_empty() {
                &link.collision
            } else {
                &link.visual
            };
            if shapes.is_empty() {
                continue;
            }
            let frame = frame_id(&r.name, &link.name);
            let mut e = Entity {
                timestamp: Some(timestamp),
                frame_id: frame.clone(),
                id: frame,
                lifetime: Some(Time { sec: 0, nsec: 0 }),
                frame_locked: true,
                metadata: vec![KeyValue {
                    key: "robot",
                    value: r.name.clone(),
                }],
                ..Default::default()
            };
            for g in shapes {
                add_geometry(&mut e, g, LINK_COLOR);
            }
            entities.push(e);
        }
    }
    let deletions = if replace_all {
        vec![Deletion {
            timestamp,
            kind: 1,
            id: String::new(),
        }]
    } else {
        Vec::new()
    };
    serde_json::to_writer(
        &mut *out,
        &SceneUpdate {
            deletions,
            entities,
        },
    )
    .expect("serialising to memory cannot fail");
}
