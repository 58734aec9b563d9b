//! JSON encoding of log records into channel messages (see [`super::schema`]
//! for the shapes). Non-finite numbers are written as `null` (JSON has none).

use glam::{DQuat, DVec3};
use quadsim_engine::description::{Geometry, Shape};
use quadsim_engine::spatial::Transform;
use quadsim_systems::{RobotInfo, RobotSample};
use serde::Serialize;

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

/// A minimal JSON writer for the per-step messages, the hot path of the log:
/// keys are literals, names are escaped once per robot, numbers are printed
/// with `zmij` (shortest text that reads back to the same number, as
/// `serde_json` prints them); non-finite numbers become `null`.
struct Json<'a>(&'a mut Vec<u8>);

impl Json<'_> {
    #[inline]
    fn raw(&mut self, s: &str) {
        self.0.extend_from_slice(s.as_bytes());
    }

    #[inline]
    fn num(&mut self, x: f64) {
        if x.is_finite() {
            let mut b = zmij::Buffer::new();
            self.raw(b.format_finite(x));
        } else {
            self.raw("null");
        }
    }

    #[inline]
    fn num32(&mut self, x: f32) {
        if x.is_finite() {
            let mut b = zmij::Buffer::new();
            self.raw(b.format_finite(x));
        } else {
            self.raw("null");
        }
    }

    fn int(&mut self, x: u64) {
        use std::io::Write as _;
        let _ = write!(self.0, "{x}");
    }

    fn time(&mut self, t: Time) {
        self.raw("{\"sec\":");
        self.int(t.sec);
        self.raw(",\"nsec\":");
        self.int(u64::from(t.nsec));
        self.raw("}");
    }

    fn v3(&mut self, v: DVec3) {
        self.raw("{\"x\":");
        self.num(v.x);
        self.raw(",\"y\":");
        self.num(v.y);
        self.raw(",\"z\":");
        self.num(v.z);
        self.raw("}");
    }

    fn quat(&mut self, q: DQuat) {
        self.raw("{\"x\":");
        self.num(q.x);
        self.raw(",\"y\":");
        self.num(q.y);
        self.raw(",\"z\":");
        self.num(q.z);
        self.raw(",\"w\":");
        self.num(q.w);
        self.raw("}");
    }

    fn nums(&mut self, xs: Option<&[f64]>) {
        let Some(xs) = xs else {
            self.raw("null");
            return;
        };
        self.raw("[");
        for (i, &x) in xs.iter().enumerate() {
            if i > 0 {
                self.raw(",");
            }
            self.num(x);
        }
        self.raw("]");
    }

    fn bool(&mut self, b: bool) {
        self.raw(if b { "true" } else { "false" });
    }

    /// `{"timestamp":…` (an object's first key).
    fn start(&mut self, t_ns: u64) {
        self.raw("{\"timestamp\":");
        self.time(Time::from_ns(t_ns));
    }
}

/// A string as a JSON string literal (quotes included).
fn quoted(s: &str) -> String {
    serde_json::to_string(s).expect("strings serialise")
}

/// Names a robot's messages need, escaped as JSON once per [`RobotInfo`].
#[derive(Debug, Clone)]
pub struct RobotNames {
    /// Robot name.
    pub robot: String,
    /// The actuated joints' names as a JSON array (velocity order).
    joints: String,
    /// Each foot's name as a JSON string (model order).
    feet: Vec<String>,
    /// `"<robot>/<link>"` of every model frame as a JSON string.
    frames: Vec<String>,
    /// The parent frame of every model frame as a JSON string (`"world"` for the base).
    parents: Vec<String>,
}

impl RobotNames {
    /// The names of `info`'s robot.
    pub fn new(info: &RobotInfo) -> Self {
        RobotNames {
            robot: info.name.clone(),
            joints: serde_json::to_string(&info.joint_names()).expect("strings serialise"),
            feet: info.foot_names().iter().map(|n| quoted(n)).collect(),
            frames: info
                .model
                .frames
                .iter()
                .map(|f| quoted(&frame_id(&info.name, &f.name)))
                .collect(),
            parents: quadsim_systems::frame_parents(&info.model)
                .iter()
                .map(|p| match p {
                    Some(i) => quoted(&frame_id(&info.name, &info.model.frames[*i].name)),
                    None => quoted(WORLD),
                })
                .collect(),
        }
    }
}

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

/// Encodes `topic` of sample `s` at `t_ns` into `out` (cleared first).
pub fn encode_robot(
    topic: RobotTopic,
    names: &RobotNames,
    s: &RobotSample,
    t_ns: u64,
    out: &mut Vec<u8>,
) {
    out.clear();
    let mut j = Json(out);
    j.start(t_ns);
    match topic {
        RobotTopic::BasePose => {
            j.raw(",\"frame_id\":\"world\",\"pose\":{\"position\":");
            j.v3(s.base_position_m);
            j.raw(",\"orientation\":");
            j.quat(s.base_orientation);
            j.raw("}");
        }
        RobotTopic::BaseTwist => {
            j.raw(",\"frame_id\":\"world\",\"linear\":");
            j.v3(s.base_linear_mps);
            j.raw(",\"angular\":");
            j.v3(s.base_angular_radps);
        }
        RobotTopic::Attitude => {
            j.raw(",\"roll\":");
            j.num(s.rpy_rad.x);
            j.raw(",\"pitch\":");
            j.num(s.rpy_rad.y);
            j.raw(",\"yaw\":");
            j.num(s.rpy_rad.z);
        }
        RobotTopic::Com => {
            j.raw(",\"frame_id\":\"world\",\"position\":");
            j.v3(s.com_m);
            j.raw(",\"velocity\":");
            j.v3(s.com_velocity_mps);
            j.raw(",\"acceleration\":");
            j.v3(s.com_acceleration_mps2);
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
            j.raw(",\"name\":");
            j.raw(&names.joints);
            j.raw(",\"position\":");
            j.nums(p);
            j.raw(",\"velocity\":");
            j.nums(v);
            j.raw(",\"effort\":");
            j.nums(Some(e));
        }
        RobotTopic::Feet => {
            j.raw(",\"frame_id\":\"world\",\"feet\":[");
            for (i, (f, name)) in s.feet.iter().zip(&names.feet).enumerate() {
                if i > 0 {
                    j.raw(",");
                }
                j.raw("{\"name\":");
                j.raw(name);
                j.raw(",\"in_contact\":");
                j.bool(f.in_contact);
                j.raw(",\"slipping\":");
                j.bool(f.slipping);
                j.raw(",\"penetration_m\":");
                j.num(f.penetration_m);
                j.raw(",\"normal_force_n\":");
                j.num(f.normal_force_n);
                j.raw(",\"force\":");
                j.v3(f.force_n);
                j.raw(",\"position\":");
                j.v3(f.position_m);
                j.raw(",\"gait_phase\":");
                match f.gait_phase {
                    Some(x) => j.num(x),
                    None => j.raw("null"),
                }
                j.raw("}");
            }
            j.raw("]");
        }
        RobotTopic::VirtualWrench => {
            j.raw(",\"frame_id\":\"world\",\"force\":");
            match s.virtual_wrench {
                Some((f, t)) => {
                    j.v3(f);
                    j.raw(",\"torque\":");
                    j.v3(t);
                }
                None => j.raw("null,\"torque\":null"),
            }
        }
        RobotTopic::Sensors => {
            // (the writer writes this topic only for robots with sensors)
            let Some(x) = &s.sensing else {
                j.raw("}");
                return;
            };
            j.raw(",\"imu_accel_mps2\":");
            match x.imu {
                Some((a, _)) => j.v3(a),
                None => j.raw("null"),
            }
            j.raw(",\"imu_gyro_radps\":");
            match x.imu {
                Some((_, g)) => j.v3(g),
                None => j.raw("null"),
            }
            j.raw(",\"encoder_position_rad\":");
            j.nums(x.encoder_position_rad.as_deref());
            j.raw(",\"encoder_velocity_radps\":");
            j.nums(x.encoder_velocity_radps.as_deref());
            j.raw(",\"contact\":[");
            for (i, &c) in x.contact.iter().enumerate() {
                if i > 0 {
                    j.raw(",");
                }
                j.bool(c);
            }
            j.raw("],\"estimate\":");
            match &x.estimate {
                Some(e) => {
                    j.raw("{\"position\":");
                    j.v3(e.position_m);
                    j.raw(",\"orientation\":");
                    j.quat(e.orientation);
                    j.raw(",\"velocity\":");
                    j.v3(e.velocity_world_mps);
                    j.raw(",\"height_m\":");
                    j.num(e.height_m);
                    j.raw("}");
                }
                None => j.raw("null"),
            }
        }
    }
    j.raw("}");
}

/// Encodes the `/tf` message: every link frame of every sampled robot in its
/// parent link's frame (the base link in `world`), a tree like ROS's
/// `robot_state_publisher` publishes. Single precision (about 1e-7 relative:
/// display only; the robot channels carry full precision).
pub fn encode_transforms(samples: &[(&RobotNames, &RobotSample)], t_ns: u64, out: &mut Vec<u8>) {
    out.clear();
    let mut j = Json(out);
    let time = Time::from_ns(t_ns);
    j.raw("{\"transforms\":[");
    let mut first = true;
    for (names, s) in samples {
        for ((pose, child), parent) in s
            .link_transforms
            .iter()
            .zip(&names.frames)
            .zip(&names.parents)
        {
            if !first {
                j.raw(",");
            }
            first = false;
            j.raw("{\"timestamp\":");
            j.time(time);
            j.raw(",\"parent_frame_id\":");
            j.raw(parent);
            j.raw(",\"child_frame_id\":");
            j.raw(child);
            let t = pose.0.as_vec3();
            j.raw(",\"translation\":{\"x\":");
            j.num32(t.x);
            j.raw(",\"y\":");
            j.num32(t.y);
            j.raw(",\"z\":");
            j.num32(t.z);
            let q = pose.1.as_quat();
            j.raw("},\"rotation\":{\"x\":");
            j.num32(q.x);
            j.raw(",\"y\":");
            j.num32(q.y);
            j.raw(",\"z\":");
            j.num32(q.z);
            j.raw(",\"w\":");
            j.num32(q.w);
            j.raw("}}");
        }
    }
    j.raw("]}");
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

#[derive(Serialize, Default)]
struct Entity<'a> {
    timestamp: Option<Time>,
    frame_id: String,
    id: String,
    lifetime: Option<Time>,
    frame_locked: bool,
    metadata: Vec<KeyValue<'a>>,
    cubes: Vec<serde_json::Value>,
    spheres: Vec<serde_json::Value>,
    cylinders: Vec<serde_json::Value>,
    triangles: Vec<serde_json::Value>,
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
