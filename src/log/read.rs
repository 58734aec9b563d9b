//! Reading a log back: every message in file order with its topic and schema,
//! and the metadata records. The reader streams from the start and does not
//! need the summary section, so a file cut short (a killed process) yields
//! every message of its complete chunks; [`LogContents::error`] then says
//! where reading stopped. Protobuf messages are decoded by the descriptors
//! stored in the log itself ([`LogMessage::json`]).

use std::collections::BTreeMap;
use std::path::Path;

use mcap::read::{LinearReader, Options};
use mcap::records::Record;
use prost_reflect::MessageDescriptor;
use serde_json::Value;

use super::writer::LogError;

/// One message of the log.
#[derive(Debug, Clone)]
pub struct LogMessage {
    /// Its channel's topic.
    pub topic: String,
    /// Its channel's schema name (empty when none).
    pub schema: String,
    /// Log time (ns of simulation time).
    pub log_time_ns: u64,
    /// The encoded message (JSON or protobuf, by its channel's encoding).
    pub data: Vec<u8>,
    /// The message's protobuf descriptor (from the schema in the log) when
    /// its channel is protobuf; `None` for JSON.
    pub descriptor: Option<MessageDescriptor>,
}

/// Equal messages: same topic, schema, time and bytes (descriptors by name:
/// two reads of one log hold equal descriptors in distinct pools).
impl PartialEq for LogMessage {
    fn eq(&self, other: &Self) -> bool {
        self.topic == other.topic
            && self.schema == other.schema
            && self.log_time_ns == other.log_time_ns
            && self.data == other.data
            && self.descriptor.as_ref().map(MessageDescriptor::full_name)
                == other.descriptor.as_ref().map(MessageDescriptor::full_name)
    }
}

impl LogMessage {
    /// Log time in seconds.
    pub fn t_s(&self) -> f64 {
        self.log_time_ns as f64 * 1e-9
    }

    /// The message as JSON: a JSON message parsed, a protobuf message
    /// decoded by its schema into the same shape ([`super::proto::to_json`]:
    /// field names as declared, absent values and non-finite numbers null).
    pub fn json(&self) -> Result<Value, serde_json::Error> {
        match &self.descriptor {
            Some(d) => super::proto::to_json(d, &self.data).map_err(|e| {
                <serde_json::Error as serde::de::Error>::custom(format!(
                    "{}: protobuf {}: {e}",
                    self.topic,
                    d.full_name()
                ))
            }),
            None => serde_json::from_slice(&self.data),
        }
    }
}

/// A schema as stored in the log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSchema {
    /// Schema encoding (`protobuf`, `jsonschema`).
    pub encoding: String,
    /// Schema data (a `FileDescriptorSet`, a JSON Schema's text).
    pub data: Vec<u8>,
}

/// What a log holds.
#[derive(Debug, Clone, Default)]
pub struct LogContents {
    /// Messages in file order.
    pub messages: Vec<LogMessage>,
    /// Metadata records by name (a later record of the same name wins).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Schemas by name.
    pub schemas: BTreeMap<String, LogSchema>,
    /// Why reading stopped early (a truncated or damaged file), if it did.
    pub error: Option<String>,
}

impl LogContents {
    /// Messages on `topic`, in order.
    pub fn topic<'a>(&'a self, topic: &'a str) -> impl Iterator<Item = &'a LogMessage> + 'a {
        self.messages.iter().filter(move |m| m.topic == topic)
    }

    /// Topics in order of first appearance.
    pub fn topics(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for m in &self.messages {
            if !out.iter().any(|t| t == &m.topic) {
                out.push(m.topic.clone());
            }
        }
        out
    }

    /// A metadata value.
    pub fn meta(&self, record: &str, key: &str) -> Option<&str> {
        self.metadata.get(record)?.get(key).map(String::as_str)
    }
}

/// Reads the log at `path`.
pub fn read_log(path: &Path) -> Result<LogContents, LogError> {
    read_log_topics(path, &|_| true)
}

/// Reads the log at `path`, keeping only the messages of topics for which
/// `keep` holds (the others are still decompressed, but not copied).
pub fn read_log_topics(path: &Path, keep: &dyn Fn(&str) -> bool) -> Result<LogContents, LogError> {
    read_log_messages(path, &|topic, _| keep(topic))
}

/// Reads the log at `path`, keeping only the messages for which
/// `keep(topic, log_time_ns)` holds (called in file order).
pub fn read_log_messages(
    path: &Path,
    keep: &dyn Fn(&str, u64) -> bool,
) -> Result<LogContents, LogError> {
    let buf = std::fs::read(path).map_err(|e| LogError {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    let c = read_log_bytes_messages(&buf, keep);
    if c.messages.is_empty()
        && c.metadata.is_empty()
        && let Some(e) = &c.error
    {
        return Err(LogError {
            path: path.display().to_string(),
            message: format!("not a readable MCAP log: {e}"),
        });
    }
    Ok(c)
}

/// Reads a log from memory, tolerating a missing end (summary, footer, magic).
pub fn read_log_bytes(buf: &[u8]) -> LogContents {
    read_log_bytes_topics(buf, &|_| true)
}

/// [`read_log_bytes`], keeping only the messages of topics for which `keep` holds.
pub fn read_log_bytes_topics(buf: &[u8], keep: &dyn Fn(&str) -> bool) -> LogContents {
    read_log_bytes_messages(buf, &|topic, _| keep(topic))
}

/// [`read_log_bytes`], keeping only the messages for which
/// `keep(topic, log_time_ns)` holds (called in file order).
pub fn read_log_bytes_messages(buf: &[u8], keep: &dyn Fn(&str, u64) -> bool) -> LogContents {
    let mut out = LogContents::default();
    let mut descriptors: BTreeMap<String, Option<MessageDescriptor>> = BTreeMap::new();
    match mcap::MessageStream::new_with_options(buf, Options::IgnoreEndMagic.into()) {
        Ok(stream) => {
            for m in stream {
                match m {
                    Ok(m) if !keep(&m.channel.topic, m.log_time) => {}
                    Ok(m) => {
                        let schema = m.channel.schema.as_ref();
                        let name = schema.map_or_else(String::new, |s| s.name.clone());
                        if let Some(s) = schema
                            && !out.schemas.contains_key(&name)
                        {
                            out.schemas.insert(
                                name.clone(),
                                LogSchema {
                                    encoding: s.encoding.clone(),
                                    data: s.data.to_vec(),
                                },
                            );
                        }
                        let descriptor = if m.channel.message_encoding == "protobuf" {
                            let d = descriptors.entry(name.clone()).or_insert_with(|| {
                                schema.and_then(|s| {
                                    super::proto::message_descriptor(&s.data, &s.name).ok()
                                })
                            });
                            match d {
                                Some(d) => Some(d.clone()),
                                None => {
                                    out.error = Some(format!(
                                        "{}: no usable protobuf schema {name}",
                                        m.channel.topic
                                    ));
                                    break;
                                }
                            }
                        } else {
                            None
                        };
                        out.messages.push(LogMessage {
                            topic: m.channel.topic.clone(),
                            schema: name,
                            log_time_ns: m.log_time,
                            data: m.data.into_owned(),
                            descriptor,
                        });
                    }
                    Err(e) => {
                        out.error = Some(e.to_string());
                        break;
                    }
                }
            }
        }
        Err(e) => out.error = Some(e.to_string()),
    }
    // Metadata records sit between chunks; read them with the record reader.
    if let Ok(records) = LinearReader::new_with_options(buf, Options::IgnoreEndMagic.into()) {
        for r in records {
            match r {
                Ok(Record::Metadata(m)) => {
                    out.metadata.insert(m.name, m.metadata);
                }
                Ok(_) => {}
                Err(e) => {
                    out.error.get_or_insert_with(|| e.to_string());
                    break;
                }
            }
        }
    }
    out
}
