//! Protobuf for the log's per-step channels: a minimal wire-format writer
//! (the hot path: numbers go in as raw little-endian bytes, no text
//! formatting), the schemas as `FileDescriptorSet`s embedded in the MCAP file
//! (schema encoding `protobuf`, so Foxglove, PlotJuggler and any protobuf
//! library decode the messages without quadsim), and the way back: any
//! protobuf message of a log decoded by its embedded descriptor into the JSON
//! shape the earlier JSON logs had (see [`to_json`]).
//!
//! `foxglove.*` schemas are Foxglove's own descriptors (from the `foxglove`
//! crate); the `quadsim.*` messages are described here, in
//! `quadsim/log.proto` (package `quadsim`), with Foxglove's conventions:
//! a `google.protobuf.Timestamp timestamp = 1`, `x/y/z` vectors, SI units.

use prost::Message as _;
use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, ReflectMessage};
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{
    DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet,
    OneofDescriptorProto,
};
use serde_json::Value;

/// Wire types.
const VARINT: u32 = 0;
const FIXED64: u32 = 1;
const LEN: u32 = 2;

/// A protobuf writer appending to a reused buffer. Fields are written in
/// field-number order, so a message's bytes depend only on its values; a
/// `double` equal to +0.0 is left out (proto3's default: exact zeros, such
/// as those of one-axis rotations in `/tf`, cost nothing).
#[derive(Debug)]
pub struct Pb<'a>(pub &'a mut Vec<u8>);

impl Pb<'_> {
    #[inline]
    fn varint(&mut self, mut x: u64) {
        while x >= 0x80 {
            self.0.push((x as u8) | 0x80);
            x >>= 7;
        }
        self.0.push(x as u8);
    }

    #[inline]
    fn key(&mut self, field: u32, wire: u32) {
        self.varint(u64::from(field << 3 | wire));
    }

    /// A `double` field; nothing for +0.0, proto3's default, which a reader
    /// decodes back to the same +0.0 (−0.0 is written: it differs in its bits).
    #[inline]
    pub fn double(&mut self, field: u32, x: f64) {
        if x.to_bits() == 0 {
            return;
        }
        self.key(field, FIXED64);
        self.0.extend_from_slice(&x.to_le_bytes());
    }

    /// A `bool` field.
    #[inline]
    pub fn bool(&mut self, field: u32, b: bool) {
        self.key(field, VARINT);
        self.0.push(u8::from(b));
    }

    /// An `int64`/`int32`/`uint32` field holding `x ≥ 0`.
    #[inline]
    pub fn uint(&mut self, field: u32, x: u64) {
        self.key(field, VARINT);
        self.varint(x);
    }

    /// A `string` field.
    #[inline]
    pub fn string(&mut self, field: u32, s: &str) {
        self.bytes(field, s.as_bytes());
    }

    /// A `bytes` field, or an already encoded message.
    #[inline]
    pub fn bytes(&mut self, field: u32, b: &[u8]) {
        self.key(field, LEN);
        self.varint(b.len() as u64);
        self.0.extend_from_slice(b);
    }

    /// A packed `repeated double` field (nothing when empty).
    #[inline]
    pub fn doubles(&mut self, field: u32, xs: &[f64]) {
        if xs.is_empty() {
            return;
        }
        self.key(field, LEN);
        self.varint(8 * xs.len() as u64);
        for x in xs {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// A packed `repeated bool` field (nothing when empty).
    pub fn bools(&mut self, field: u32, bs: &[bool]) {
        if bs.is_empty() {
            return;
        }
        self.key(field, LEN);
        self.varint(bs.len() as u64);
        self.0.extend(bs.iter().map(|&b| u8::from(b)));
    }

    /// A nested message field written by `body`.
    #[inline]
    pub fn message(&mut self, field: u32, body: impl FnOnce(&mut Pb<'_>)) {
        self.key(field, LEN);
        let at = self.0.len();
        self.0.push(0); // the length, one byte when below 128
        body(&mut Pb(self.0));
        let len = self.0.len() - at - 1;
        if len < 0x80 {
            self.0[at] = len as u8;
        } else {
            // a longer length: move the body up to make room
            let (mut tmp, mut k, mut x) = ([0u8; 10], 0, len);
            while x >= 0x80 {
                tmp[k] = (x as u8) | 0x80;
                x >>= 7;
                k += 1;
            }
            tmp[k] = x as u8;
            k += 1;
            self.0.resize(self.0.len() + k - 1, 0);
            self.0.copy_within(at + 1..at + 1 + len, at + k);
            self.0[at..at + k].copy_from_slice(&tmp[..k]);
        }
    }

    /// A `google.protobuf.Timestamp` field from simulation nanoseconds.
    #[inline]
    pub fn time(&mut self, field: u32, t_ns: u64) {
        self.message(field, |m| {
            m.uint(1, t_ns / 1_000_000_000);
            m.uint(2, t_ns % 1_000_000_000);
        });
    }

    /// A `Vector3 {x, y, z}` field.
    #[inline]
    pub fn v3(&mut self, field: u32, v: glam::DVec3) {
        self.message(field, |m| {
            m.double(1, v.x);
            m.double(2, v.y);
            m.double(3, v.z);
        });
    }

    /// A `Quaternion {x, y, z, w}` field.
    #[inline]
    pub fn quat(&mut self, field: u32, q: glam::DQuat) {
        self.message(field, |m| {
            m.double(1, q.x);
            m.double(2, q.y);
            m.double(3, q.z);
            m.double(4, q.w);
        });
    }
}

/// Field kinds of the `quadsim.*` messages.
#[derive(Clone, Copy)]
enum K {
    Double,
    Bool,
    Str,
    Int64,
    Int32,
    Msg(&'static str),
}

/// How a field repeats or may be absent.
#[derive(Clone, Copy, PartialEq)]
enum L {
    /// One value (a message field may be absent: decoded as null).
    One,
    /// proto3 `optional` scalar (absent: decoded as null).
    Opt,
    /// `repeated` (empty: decoded as null, see [`to_json`]).
    Rep,
}

/// The `quadsim/log.proto` messages: (name, fields as (name, number, kind, label)).
#[allow(clippy::type_complexity)]
const MESSAGES: &[(&str, &[(&str, i32, K, L)])] = {
    use K::*;
    use L::*;
    const T: K = Msg(".google.protobuf.Timestamp");
    const V: K = Msg(".quadsim.Vector3");
    const Q: K = Msg(".quadsim.Quaternion");
    &[
        (
            "Vector3",
            &[
                ("x", 1, Double, One),
                ("y", 2, Double, One),
                ("z", 3, Double, One),
            ],
        ),
        (
            "Quaternion",
            &[
                ("x", 1, Double, One),
                ("y", 2, Double, One),
                ("z", 3, Double, One),
                ("w", 4, Double, One),
            ],
        ),
        (
            "Twist",
            &[
                ("timestamp", 1, T, One),
                ("frame_id", 2, Str, One),
                ("linear", 3, V, One),
                ("angular", 4, V, One),
            ],
        ),
        (
            "Attitude",
            &[
                ("timestamp", 1, T, One),
                ("roll", 2, Double, One),
                ("pitch", 3, Double, One),
                ("yaw", 4, Double, One),
            ],
        ),
        (
            "CenterOfMass",
            &[
                ("timestamp", 1, T, One),
                ("frame_id", 2, Str, One),
                ("position", 3, V, One),
                ("velocity", 4, V, One),
                ("acceleration", 5, V, One),
            ],
        ),
        (
            "JointState",
            &[
                ("timestamp", 1, T, One),
                ("name", 2, Str, Rep),
                ("position", 3, Double, Rep),
                ("velocity", 4, Double, Rep),
                ("effort", 5, Double, Rep),
            ],
        ),
        (
            "FootContact",
            &[
                ("name", 1, Str, One),
                ("in_contact", 2, Bool, One),
                ("slipping", 3, Bool, One),
                ("penetration_m", 4, Double, One),
                ("normal_force_n", 5, Double, One),
                ("force", 6, V, One),
                ("position", 7, V, One),
                ("gait_phase", 8, Double, Opt),
            ],
        ),
        (
            "FootContacts",
            &[
                ("timestamp", 1, T, One),
                ("frame_id", 2, Str, One),
                ("feet", 3, Msg(".quadsim.FootContact"), Rep),
            ],
        ),
        (
            "Wrench",
            &[
                ("timestamp", 1, T, One),
                ("frame_id", 2, Str, One),
                ("force", 3, V, One),
                ("torque", 4, V, One),
            ],
        ),
        (
            "BaseEstimate",
            &[
                ("position", 1, V, One),
                ("orientation", 2, Q, One),
                ("velocity", 3, V, One),
                ("height_m", 4, Double, One),
            ],
        ),
        (
            "Sensors",
            &[
                ("timestamp", 1, T, One),
                ("imu_accel_mps2", 2, V, One),
                ("imu_gyro_radps", 3, V, One),
                ("encoder_position_rad", 4, Double, Rep),
                ("encoder_velocity_radps", 5, Double, Rep),
                ("contact", 6, Bool, Rep),
                ("estimate", 7, Msg(".quadsim.BaseEstimate"), One),
                ("contact_force_n", 8, Double, Rep),
                ("mocap", 9, Msg(".quadsim.MocapPose"), One),
            ],
        ),
        (
            "MocapPose",
            &[
                ("captured", 1, T, One),
                ("position", 2, V, One),
                ("orientation", 3, Q, One),
            ],
        ),
    ]
};

/// `google/protobuf/timestamp.proto`.
fn timestamp_file() -> FileDescriptorProto {
    FileDescriptorProto {
        name: Some("google/protobuf/timestamp.proto".into()),
        package: Some("google.protobuf".into()),
        syntax: Some("proto3".into()),
        message_type: vec![DescriptorProto {
            name: Some("Timestamp".into()),
            field: vec![
                field("seconds", 1, K::Int64, L::One, None),
                field("nanos", 2, K::Int32, L::One, None),
            ],
            ..Default::default()
        }],
        ..Default::default()
    }
}

fn field(name: &str, number: i32, kind: K, label: L, oneof: Option<i32>) -> FieldDescriptorProto {
    let (ty, type_name) = match kind {
        K::Double => (Type::Double, None),
        K::Bool => (Type::Bool, None),
        K::Str => (Type::String, None),
        K::Int64 => (Type::Int64, None),
        K::Int32 => (Type::Int32, None),
        K::Msg(t) => (Type::Message, Some(t.to_string())),
    };
    FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        label: Some(if label == L::Rep {
            Label::Repeated
        } else {
            Label::Optional
        } as i32),
        r#type: Some(ty as i32),
        type_name,
        json_name: Some(name.into()),
        oneof_index: oneof,
        proto3_optional: (label == L::Opt).then_some(true),
        ..Default::default()
    }
}

/// `quadsim/log.proto`.
fn quadsim_file() -> FileDescriptorProto {
    let message_type = MESSAGES
        .iter()
        .map(|(name, fields)| {
            let mut oneofs = Vec::new();
            let field = fields
                .iter()
                .map(|&(f, n, k, l)| {
                    // a proto3 `optional` lives in a synthetic oneof `_<name>`
                    let oneof = (l == L::Opt).then(|| {
                        oneofs.push(OneofDescriptorProto {
                            name: Some(format!("_{f}")),
                            options: None,
                        });
                        oneofs.len() as i32 - 1
                    });
                    field(f, n, k, l, oneof)
                })
                .collect();
            DescriptorProto {
                name: Some(name.to_string()),
                field,
                oneof_decl: oneofs,
                ..Default::default()
            }
        })
        .collect();
    FileDescriptorProto {
        name: Some("quadsim/log.proto".into()),
        package: Some("quadsim".into()),
        dependency: vec!["google/protobuf/timestamp.proto".into()],
        syntax: Some("proto3".into()),
        message_type,
        ..Default::default()
    }
}

/// The `FileDescriptorSet` (binary) of the `quadsim.*` messages: the MCAP
/// schema data of every `quadsim.*` protobuf channel.
pub fn quadsim_descriptor_set() -> Vec<u8> {
    FileDescriptorSet {
        file: vec![timestamp_file(), quadsim_file()],
    }
    .encode_to_vec()
}

/// Foxglove's `FileDescriptorSet` of `foxglove.<name>` (its MCAP schema data).
pub fn foxglove_descriptor_set(name: &str) -> Vec<u8> {
    use foxglove::Encode;
    let schema = match name {
        "foxglove.FrameTransforms" => foxglove::schemas::FrameTransforms::get_schema(),
        "foxglove.PoseInFrame" => foxglove::schemas::PoseInFrame::get_schema(),
        _ => None,
    };
    schema
        .map(|s| s.data.into_owned())
        .unwrap_or_else(|| panic!("no Foxglove protobuf schema {name} here"))
}

/// The descriptor of message `name` from a schema's `FileDescriptorSet`.
pub fn message_descriptor(set: &[u8], name: &str) -> Result<MessageDescriptor, String> {
    let pool = DescriptorPool::decode(set).map_err(|e| format!("schema {name}: {e}"))?;
    pool.get_message_by_name(name)
        .ok_or_else(|| format!("schema {name}: no such message in its descriptor set"))
}

/// Decodes one protobuf message into JSON, with the shapes of the earlier
/// JSON logs: fields by their proto names in field order; an absent message
/// field or `optional` scalar is null; a non-finite double is null (as JSON
/// wrote it); an empty repeated field is null (no log message has an empty
/// list otherwise: a robot has joints and feet, so an empty list is "none",
/// e.g. a controller without joint targets).
pub fn to_json(desc: &MessageDescriptor, data: &[u8]) -> Result<Value, String> {
    let m = DynamicMessage::decode(desc.clone(), data).map_err(|e| e.to_string())?;
    Ok(message_json(&m))
}

fn message_json(m: &DynamicMessage) -> Value {
    let mut out = serde_json::Map::new();
    for f in m.descriptor().fields() {
        let v = if f.supports_presence() && !m.has_field(&f) {
            Value::Null
        } else {
            let v = m.get_field(&f);
            match v.as_list() {
                Some([]) => Value::Null,
                _ => value_json(&v),
            }
        };
        out.insert(f.name().to_string(), v);
    }
    Value::Object(out)
}

fn value_json(v: &prost_reflect::Value) -> Value {
    use prost_reflect::Value as P;
    let num = |x: f64| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number);
    match v {
        P::Bool(b) => Value::Bool(*b),
        P::I32(x) => Value::from(*x),
        P::I64(x) => Value::from(*x),
        P::U32(x) => Value::from(*x),
        P::U64(x) => Value::from(*x),
        P::F32(x) => num(f64::from(*x)),
        P::F64(x) => num(*x),
        P::String(s) => Value::String(s.clone()),
        P::Bytes(b) => Value::Array(b.iter().map(|&x| Value::from(x)).collect()),
        P::EnumNumber(n) => Value::from(*n),
        P::Message(m) => message_json(m),
        P::List(xs) => Value::Array(xs.iter().map(value_json).collect()),
        P::Map(m) => Value::Object(
            m.iter()
                .map(|(k, v)| (format!("{k:?}"), value_json(v)))
                .collect(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptor_sets_decode() {
        let set = quadsim_descriptor_set();
        for (name, _) in MESSAGES {
            message_descriptor(&set, &format!("quadsim.{name}")).unwrap();
        }
        for name in ["foxglove.FrameTransforms", "foxglove.PoseInFrame"] {
            message_descriptor(&foxglove_descriptor_set(name), name).unwrap();
        }
    }

    #[test]
    fn long_nested_messages_get_a_longer_length() {
        // a 200-byte nested string: its length needs two varint bytes
        let mut buf = Vec::new();
        let s = "x".repeat(200);
        Pb(&mut buf).message(1, |m| m.string(1, &s));
        let mut inner = Vec::new();
        Pb(&mut inner).string(1, &s);
        assert_eq!(buf[0], 1 << 3 | LEN as u8);
        assert_eq!(&buf[1..3], &[0xcb, 0x01]); // 203 = 1 + 2 + 200
        assert_eq!(&buf[3..], &inner[..]);
    }
}
