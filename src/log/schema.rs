//! The schemas of every channel of `log.mcap`. The per-step channels are
//! protobuf (message and schema encoding `protobuf`; the schema data is a
//! `FileDescriptorSet`, [`super::proto`]); the rare ones (`/scene`,
//! `/terrain`, `/<robot>/metrics`) are JSON with a JSON Schema (draft 2020-12
//! vocabulary, schema encoding `jsonschema`). [`Schema::json`] also gives a
//! JSON Schema of each protobuf message's decoded JSON form (what
//! [`super::read::LogMessage::json`] returns), for documentation.
//!
//! `foxglove.*` schemas follow the shapes Foxglove publishes for its
//! well-known types (`foxglove.PoseInFrame`, `foxglove.FrameTransforms`,
//! `foxglove.SceneUpdate`), so Foxglove recognises them by name and renders
//! them in its 3D panel; we write only the properties we use. `quadsim.*`
//! schemas are ours, in the same style (a `timestamp` `{sec, nsec}`, `x/y/z`
//! vectors, SI units named in every description).

use serde_json::{Value, json};

/// Topic suffix of the final metrics message of each robot.
pub const METRICS_SUFFIX: &str = "metrics";

/// The topic of robot `robot`'s metrics message.
pub fn metrics_topic(robot: &str) -> String {
    format!("/{robot}/{METRICS_SUFFIX}")
}

/// A schema of the log: its MCAP name and its JSON Schema text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Schema {
    /// `foxglove.PoseInFrame`: the base pose.
    PoseInFrame,
    /// `quadsim.Twist`: the base twist.
    Twist,
    /// `quadsim.Attitude`: roll, pitch, yaw.
    Attitude,
    /// `quadsim.CenterOfMass`: CoM position, velocity, acceleration.
    CenterOfMass,
    /// `quadsim.JointState`: names, positions, velocities, efforts.
    JointState,
    /// `quadsim.FootContacts`: per-foot force, contact and slip.
    FootContacts,
    /// `quadsim.Wrench`: the virtual-model-control wrench.
    Wrench,
    /// `quadsim.Sensors`: what the robot's sensors read and its base estimate.
    Sensors,
    /// `quadsim.RobotMetrics`: the run's metrics (summary.json's robot object).
    RobotMetrics,
    /// `foxglove.FrameTransforms`: every link frame in the world.
    FrameTransforms,
    /// `foxglove.SceneUpdate`: link shapes and the ground.
    SceneUpdate,
    /// `quadsim.TerrainDescription`: the scenario's ground.
    TerrainDescription,
}

impl Schema {
    /// Every schema.
    pub const ALL: [Schema; 12] = [
        Schema::PoseInFrame,
        Schema::Twist,
        Schema::Attitude,
        Schema::CenterOfMass,
        Schema::JointState,
        Schema::FootContacts,
        Schema::Wrench,
        Schema::Sensors,
        Schema::RobotMetrics,
        Schema::FrameTransforms,
        Schema::SceneUpdate,
        Schema::TerrainDescription,
    ];

    /// The schema's name (its JSON Schema `title`).
    pub fn name(self) -> &'static str {
        match self {
            Schema::PoseInFrame => "foxglove.PoseInFrame",
            Schema::Twist => "quadsim.Twist",
            Schema::Attitude => "quadsim.Attitude",
            Schema::CenterOfMass => "quadsim.CenterOfMass",
            Schema::JointState => "quadsim.JointState",
            Schema::FootContacts => "quadsim.FootContacts",
            Schema::Wrench => "quadsim.Wrench",
            Schema::Sensors => "quadsim.Sensors",
            Schema::RobotMetrics => "quadsim.RobotMetrics",
            Schema::FrameTransforms => "foxglove.FrameTransforms",
            Schema::SceneUpdate => "foxglove.SceneUpdate",
            Schema::TerrainDescription => "quadsim.TerrainDescription",
        }
    }

    /// Whether the channel is protobuf (else JSON).
    pub fn is_protobuf(self) -> bool {
        !matches!(
            self,
            Schema::RobotMetrics | Schema::SceneUpdate | Schema::TerrainDescription
        )
    }

    /// The MCAP message encoding of the schema's channels.
    pub fn message_encoding(self) -> &'static str {
        if self.is_protobuf() {
            "protobuf"
        } else {
            "json"
        }
    }

    /// The MCAP schema encoding.
    pub fn schema_encoding(self) -> &'static str {
        if self.is_protobuf() {
            "protobuf"
        } else {
            "jsonschema"
        }
    }

    /// The MCAP schema data: a binary `FileDescriptorSet` for protobuf, the
    /// JSON Schema's text for JSON.
    pub fn data(self) -> Vec<u8> {
        match self {
            Schema::PoseInFrame | Schema::FrameTransforms => {
                super::proto::foxglove_descriptor_set(self.name())
            }
            _ if self.is_protobuf() => super::proto::quadsim_descriptor_set(),
            _ => serde_json::to_vec(&self.json()).expect("schema serialises"),
        }
    }

    /// The JSON Schema (of the message's JSON form for a protobuf channel).
    pub fn json(self) -> Value {
        let mut v = match self {
            Schema::PoseInFrame => object(
                "A timestamped pose of the robot's base (root link frame) in the world",
                json!({
                    "timestamp": time("Simulation time of the pose"),
                    "frame_id": string("Frame of the pose: \"world\" (z up)"),
                    "pose": pose("Base pose: position (m) and orientation (base to world)"),
                }),
            ),
            Schema::Twist => object(
                "Velocity of the base origin and angular velocity of the base, world axes",
                json!({
                    "timestamp": time("Simulation time"),
                    "frame_id": string("Axes of the vectors: \"world\""),
                    "linear": vector3("Velocity of the base origin (m/s)"),
                    "angular": vector3("Angular velocity of the base (rad/s)"),
                }),
            ),
            Schema::Attitude => object(
                "Base orientation as roll, pitch, yaw (rad), R = Rz(yaw) Ry(pitch) Rx(roll)",
                json!({
                    "timestamp": time("Simulation time"),
                    "roll": number("Roll about x (rad)"),
                    "pitch": number("Pitch about y (rad), in [-pi/2, pi/2]"),
                    "yaw": number("Yaw about z (rad), in (-pi, pi]"),
                }),
            ),
            Schema::CenterOfMass => object(
                "Whole-body centre of mass in the world",
                json!({
                    "timestamp": time("Simulation time"),
                    "frame_id": string("Frame of the vectors: \"world\""),
                    "position": vector3("CoM position (m)"),
                    "velocity": vector3("CoM velocity (m/s)"),
                    "acceleration": vector3("CoM acceleration (m/s^2): gravity + (sum of ground reaction forces and pushes) / mass, with the forces acting at this instant"),
                }),
            ),
            Schema::JointState => object(
                "Joint states in the model's velocity order, like sensor_msgs/JointState",
                json!({
                    "timestamp": time("Simulation time"),
                    "name": {"type": "array", "items": {"type": "string"}, "description": "Joint names"},
                    "position": numbers_or_null("Joint angles (rad); null when the controller sets none"),
                    "velocity": numbers_or_null("Joint velocities (rad/s); null when the controller sets none"),
                    "effort": numbers_or_null("Joint torques (N m); null when the controller sets none"),
                }),
            ),
            Schema::FootContacts => object(
                "Ground contact of each foot (world frame)",
                json!({
                    "timestamp": time("Simulation time"),
                    "frame_id": string("Frame of the vectors: \"world\""),
                    "feet": {
                        "type": "array",
                        "description": "One entry per foot, in the model's foot order",
                        "items": {
                            "type": "object",
                            "properties": {
                                "name": string("Foot link name"),
                                "in_contact": {"type": "boolean", "description": "The foot touches the ground"},
                                "slipping": {"type": "boolean", "description": "Friction is at the cone's limit"},
                                "penetration_m": number("Penetration depth (m)"),
                                "normal_force_n": number("Normal force magnitude (N)"),
                                "force": vector3("Ground reaction force on the foot (N)"),
                                "position": vector3("Contact point (m)"),
                                "gait_phase": {"type": ["number", "null"], "description": "The leg's gait clock phase in [0, 1) (null: the controller has no gait)"},
                            },
                        },
                    },
                }),
            ),
            Schema::Wrench => object(
                "Virtual wrench on the body requested by virtual model control at its last tick",
                json!({
                    "timestamp": time("Simulation time"),
                    "frame_id": string("Axes of the vectors: \"world\""),
                    "force": vector3_or_null("Force (N); null without virtual model control"),
                    "torque": vector3_or_null("Torque about the centre of mass (N m); null without virtual model control"),
                }),
            ),
            Schema::Sensors => object(
                "What the robot's sensors read at the sample's instant (their latest outputs, with noise) and the base state estimate (docs/sensors.md); null where the robot has no such sensor",
                json!({
                    "timestamp": time("Simulation time"),
                    "imu_accel_mps2": vector3_or_null("IMU specific force (m/s^2, torso frame; +g up at rest)"),
                    "imu_gyro_radps": vector3_or_null("IMU angular velocity (rad/s, torso frame)"),
                    "encoder_position_rad": numbers_or_null("Joint encoder angles (rad), actuated joints in velocity order"),
                    "encoder_velocity_radps": numbers_or_null("Joint velocity estimates (rad/s)"),
                    "contact": {"type": "array", "items": {"type": "boolean"}, "description": "Foot contact sensors' flags (or the true contact where the robot has none), in the model's foot order"},
                    "estimate": {
                        "type": ["object", "null"],
                        "description": "The base state estimator's output (null without an estimator)",
                        "properties": {
                            "position": vector3("Base position (m, world)"),
                            "orientation": quaternion("Base orientation (base to world)"),
                            "velocity": vector3("Base velocity (m/s, world)"),
                            "height_m": number("Base height above the ground under it (m)"),
                        },
                    },
                    "contact_force_n": numbers_or_null("Contact sensors' measured normal forces (N), foot order; null unless the sensors output forces"),
                    "mocap": {
                        "type": ["object", "null"],
                        "description": "The latest delivered motion-capture pose (null without mocap or before its first delivery)",
                        "properties": {
                            "captured": time("When the pose was captured (simulation time; it is delivered the mocap latency later)"),
                            "position": vector3("Torso position (m, world), with noise"),
                            "orientation": quaternion("Torso orientation (torso to world), with noise"),
                        },
                    },
                }),
            ),
            Schema::RobotMetrics => object(
                "The run's metrics of one robot: the keys of summary.json's robot object (see scenarios/README.md)",
                json!({
                    "name": string("Robot name"),
                    "fell": {"type": "boolean"},
                    "fell_at_s": {"type": ["number", "null"]},
                    "mean_forward_speed_mps": {"type": "number"},
                    "peak_forward_speed_mps": {"type": "number"},
                    "base_height_mean_m": {"type": "number"},
                    "base_height_p2p_m": {"type": "number"},
                    "com_height_mean_m": {"type": "number"},
                    "com_height_p2p_m": {"type": "number"},
                    "roll_range_rad": {"type": "array", "items": {"type": "number"}},
                    "pitch_range_rad": {"type": "array", "items": {"type": "number"}},
                    "yaw_range_rad": {"type": "array", "items": {"type": "number"}},
                    "joint_rms_error_rad": {"type": ["number", "null"]},
                    "max_foot_force_n": {"type": "number"},
                    "energy_j": {"type": "number"},
                    "energy_per_step_j": {"type": ["number", "null"]},
                    "steps": {"type": "integer"},
                    "min_stability_margin_m": {"type": ["number", "null"]},
                    "distance_m": {"type": "number"},
                    "study_b": {
                        "type": "object",
                        "description": "Study B's Table 4 comparison (prescribed controller, hybrid mode, quad12 only): per joint the peak and mean |torque| (N m) of the fixed-base Lagrangian leg model on the prescribed trajectory and of the simulation, and their ratios",
                        "properties": {
                            "hip_tau2": study_b_joint(),
                            "knee_tau3": study_b_joint(),
                            "samples": {"type": "integer"},
                        },
                    },
                    "com_displacement_m": {"type": "array", "items": {"type": "number"}, "description": "CoM displacement over the run (m), heading frame x, y, z"},
                    "com_mean_velocity_mps": {"type": "array", "items": {"type": "number"}, "description": "com_displacement_m / duration (m/s)"},
                    "com_oscillation_m": {"type": "array", "items": {"type": "number"}, "description": "CoM oscillation amplitude per axis (m): half peak-to-peak of y, z and of detrended x"},
                    "joints": {
                        "type": "array",
                        "description": "Per actuated joint: peak and time-mean |torque| (N m)",
                        "items": {"type": "object", "properties": {
                            "name": {"type": "string"},
                            "peak_abs_torque_nm": {"type": "number"},
                            "mean_abs_torque_nm": {"type": "number"},
                        }},
                    },
                    "push_recovery": {"type": "object", "description": "Optional: largest push impulse recovered from"},
                    "total_mass_kg": {"type": "number", "description": "the robot's mass with its payloads at the end (kg)"},
                    "commanded_speed_mps": {"type": ["number", "null"], "description": "a walking robot's commanded forward speed as ramped, averaged over the run (m/s); null for other controllers"},
                    "actuators": {"type": "object", "description": "per-joint load: peak_torque_nm, peak_torque_share (of the effort limit), time_at_torque_limit_s, time_at_speed_limit_s; and their maxima over the joints"},
                    "load": {"type": "object", "description": "load verdict: carried (bool) and reason (null, fell, saturated, failed to track speed)"},
                    "sensing": {"type": "object", "description": "state_source (estimated, ground_truth) and estimation: the base estimator's error against ground truth (updates; rms and max of orientation_rad, tilt_rad, velocity_mps, height_m), null without an estimator (docs/sensors.md)"},
                }),
            ),
            Schema::FrameTransforms => object(
                "An array of FrameTransform messages",
                json!({
                    "transforms": {
                        "type": "array",
                        "description": "Array of transforms",
                        "items": {
                            "title": "foxglove.FrameTransform",
                            "description": "A transform between two reference frames in 3D space",
                            "type": "object",
                            "properties": {
                                "timestamp": time("Timestamp of transform"),
                                "parent_frame_id": string("Name of the parent frame"),
                                "child_frame_id": string("Name of the child frame"),
                                "translation": vector3("Translation component of the transform"),
                                "rotation": quaternion("Rotation component of the transform"),
                            },
                        },
                    },
                }),
            ),
            Schema::SceneUpdate => object(
                "An update to the entities displayed in a 3D scene",
                json!({
                    "deletions": {
                        "type": "array",
                        "description": "Scene entities to delete",
                        "items": {
                            "title": "foxglove.SceneEntityDeletion",
                            "type": "object",
                            "properties": {
                                "timestamp": time("Timestamp of the deletion"),
                                "type": {"type": "integer", "description": "0: the entity with `id`; 1: all entities on the topic"},
                                "id": string("Identifier of the entity to delete"),
                            },
                        },
                    },
                    "entities": {
                        "type": "array",
                        "description": "Scene entities to add or replace",
                        "items": {
                            "title": "foxglove.SceneEntity",
                            "type": "object",
                            "properties": {
                                "timestamp": time("Timestamp of the entity"),
                                "frame_id": string("Frame of reference"),
                                "id": string("Identifier for the entity"),
                                "lifetime": duration("Zero: visible until replaced or deleted"),
                                "frame_locked": {"type": "boolean", "description": "Follow the frame `frame_id` as it moves"},
                                "metadata": {"type": "array", "items": {
                                    "title": "foxglove.KeyValuePair",
                                    "type": "object",
                                    "properties": {"key": string("Key"), "value": string("Value")},
                                }},
                                "arrows": primitives("foxglove.ArrowPrimitive", json!({
                                    "pose": pose("Position of the arrow's tail and orientation of the arrow; the arrow points along +x"),
                                    "shaft_length": number("Length of the arrow shaft (m)"),
                                    "shaft_diameter": number("Diameter of the arrow shaft (m)"),
                                    "head_length": number("Length of the arrow head (m)"),
                                    "head_diameter": number("Diameter of the arrow head (m)"),
                                    "color": color(),
                                })),
                                "cubes": primitives("foxglove.CubePrimitive", json!({
                                    "pose": pose("Centre and orientation of the box"),
                                    "size": vector3("Side lengths (m)"),
                                    "color": color(),
                                })),
                                "spheres": primitives("foxglove.SpherePrimitive", json!({
                                    "pose": pose("Centre of the sphere"),
                                    "size": vector3("Diameters along each axis (m)"),
                                    "color": color(),
                                })),
                                "cylinders": primitives("foxglove.CylinderPrimitive", json!({
                                    "pose": pose("Centre of the cylinder; its axis is z"),
                                    "size": vector3("Bounding box size (m)"),
                                    "bottom_scale": number("0-1, radius of the bottom face relative to size"),
                                    "top_scale": number("0-1, radius of the top face relative to size"),
                                    "color": color(),
                                })),
                                "lines": primitives("foxglove.LinePrimitive", json!({
                                    "type": {"type": "integer", "description": "0: line strip; 1: line loop; 2: line list (pairs)"},
                                    "pose": pose("Origin of the points"),
                                    "thickness": number("Line thickness (m, or pixels when scale_invariant)"),
                                    "scale_invariant": {"type": "boolean", "description": "Thickness in screen pixels, whatever the zoom"},
                                    "points": {"type": "array", "items": vector3("Point (m)")},
                                    "color": color(),
                                    "colors": {"type": "array", "items": color()},
                                    "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}},
                                })),
                                "triangles": primitives("foxglove.TriangleListPrimitive", json!({
                                    "pose": pose("Origin of the points"),
                                    "points": {"type": "array", "items": vector3("Vertex (m)")},
                                    "color": color(),
                                    "colors": {"type": "array", "items": color()},
                                    "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}},
                                })),
                                "texts": primitives("foxglove.TextPrimitive", json!({
                                    "pose": pose("Position of the text's centre and its orientation"),
                                    "billboard": {"type": "boolean", "description": "Always face the camera"},
                                    "font_size": number("Font size (m, or pixels when scale_invariant)"),
                                    "scale_invariant": {"type": "boolean", "description": "Font size in screen pixels, whatever the zoom"},
                                    "color": color(),
                                    "text": string("The text"),
                                })),
                                "models": primitives("foxglove.ModelPrimitive", json!({
                                    "pose": pose("Origin of the model"),
                                    "scale": vector3("Scale factor along each axis"),
                                    "color": color(),
                                    "override_color": {"type": "boolean"},
                                    "url": string("URL of the mesh file"),
                                    "media_type": string("Media type of embedded data"),
                                    "data": {"type": "string", "contentEncoding": "base64"},
                                })),
                            },
                        },
                    },
                }),
            ),
            Schema::TerrainDescription => object(
                "The scenario's ground: the default ground and every terrain as written in the scenario file (scenarios/README.md)",
                json!({
                    "timestamp": time("Simulation time"),
                    "default_ground": {"description": "A ground preset name or a custom material table; null: none"},
                    "default_ground_height_m": number("Height of the default ground plane (m)"),
                    "terrains": {"type": "array", "items": {"type": "object"}, "description": "The [[terrains]] tables"},
                }),
            ),
        };
        v["title"] = json!(self.name());
        if self.is_protobuf() {
            protobuf_times(&mut v);
        }
        v
    }
}

/// In a protobuf message's JSON form a `timestamp` is a
/// `google.protobuf.Timestamp`: `{seconds, nanos}`.
fn protobuf_times(v: &mut Value) {
    match v {
        Value::Object(map) => {
            for (k, x) in map.iter_mut() {
                if k == "timestamp" && x.get("title") == Some(&json!("time")) {
                    let d = x["description"].clone();
                    *x = json!({
                        "type": "object",
                        "title": "google.protobuf.Timestamp",
                        "description": d,
                        "properties": {
                            "seconds": {"type": "integer", "minimum": 0},
                            "nanos": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
                        },
                    });
                } else {
                    protobuf_times(x);
                }
            }
        }
        Value::Array(a) => a.iter_mut().for_each(protobuf_times),
        _ => {}
    }
}

/// One joint of the `study_b` block of [`Schema::RobotMetrics`].
fn study_b_joint() -> Value {
    json!({
        "type": "object",
        "properties": {
            "model_peak_nm": {"type": "number"},
            "model_mean_nm": {"type": "number"},
            "sim_peak_nm": {"type": "number"},
            "sim_mean_nm": {"type": "number"},
            "peak_ratio_sim_to_model": {"type": "number"},
            "mean_ratio_sim_to_model": {"type": "number"},
        },
    })
}

fn object(description: &str, properties: Value) -> Value {
    json!({
        "title": "",
        "description": description,
        "type": "object",
        "properties": properties,
    })
}

fn string(description: &str) -> Value {
    json!({"type": "string", "description": description})
}

fn number(description: &str) -> Value {
    json!({"type": "number", "description": description})
}

fn numbers_or_null(description: &str) -> Value {
    json!({"type": ["array", "null"], "items": {"type": ["number", "null"]}, "description": description})
}

fn time(description: &str) -> Value {
    json!({
        "type": "object",
        "title": "time",
        "description": description,
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
    })
}

fn duration(description: &str) -> Value {
    json!({
        "type": "object",
        "title": "duration",
        "description": description,
        "properties": {
            "sec": {"type": "integer"},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
    })
}

fn vector3(description: &str) -> Value {
    json!({
        "title": "foxglove.Vector3",
        "description": description,
        "type": "object",
        "properties": {
            "x": {"type": "number"},
            "y": {"type": "number"},
            "z": {"type": "number"},
        },
    })
}

fn vector3_or_null(description: &str) -> Value {
    let mut v = vector3(description);
    v["type"] = json!(["object", "null"]);
    v
}

fn quaternion(description: &str) -> Value {
    json!({
        "title": "foxglove.Quaternion",
        "description": description,
        "type": "object",
        "properties": {
            "x": {"type": "number"},
            "y": {"type": "number"},
            "z": {"type": "number"},
            "w": {"type": "number"},
        },
    })
}

fn pose(description: &str) -> Value {
    json!({
        "title": "foxglove.Pose",
        "description": description,
        "type": "object",
        "properties": {
            "position": vector3("Position (m)"),
            "orientation": quaternion("Orientation"),
        },
    })
}

fn color() -> Value {
    json!({
        "title": "foxglove.Color",
        "type": "object",
        "properties": {
            "r": {"type": "number"},
            "g": {"type": "number"},
            "b": {"type": "number"},
            "a": {"type": "number"},
        },
    })
}

fn primitives(title: &str, properties: Value) -> Value {
    json!({
        "type": "array",
        "items": {"title": title, "type": "object", "properties": properties},
    })
}
