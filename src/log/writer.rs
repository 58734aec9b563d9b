//! The MCAP writer: a thread that owns the file, encodes records (protobuf
//! for the per-step channels, JSON for the rest) and writes them into
//! compressed chunks. The simulation thread only sends
//! owned records over a bounded channel ([`McapLog::sink`]), so encoding and
//! compression run beside the simulation; when the writer falls behind, the
//! channel fills and the simulation waits (nothing is dropped).
//!
//! Determinism: the file depends only on the sequence of records. The header
//! holds fixed strings (no library version, no wall-clock time anywhere),
//! compression is single-threaded LZ4 at a fixed level, and channel ids are
//! given in first-use order. Two runs of one scenario write identical bytes.
//!
//! Durability: each chunk is written whole, once complete, in one write
//! followed by a provisional end (a DataEnd record, a Footer without a
//! summary, the magic) that the next chunk, or the real end, overwrites
//! (`LogFile`). So after every chunk the file on disk is a complete MCAP
//! file: a killed process leaves a log that any reader reads, in streaming
//! or seeking mode, up to its last chunk (see [`super::read`]; issue 29,
//! item 7). A finished log's bytes are the same as with chunks written in
//! place (mcap's default, a placeholder header patched when the chunk ends).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use mcap::records::Metadata;
use mcap::{Compression, WriteOptions, Writer};
use quadsim_systems::{LogRecord, LogSink, RobotInfo};

use super::encode::{
    GroundMesh, RobotNames, RobotTopic, encode_robot, encode_scene, encode_transforms,
};
use super::schema::Schema;

/// The MCAP profile string written in the header (fixed, for byte-identical files).
pub const PROFILE: &str = "";
/// The library string written in the header (fixed, for byte-identical files).
pub const LIBRARY: &str = "quadsim";
/// Uncompressed chunk size (bytes): what a killed process can lose at most.
pub const CHUNK_SIZE_BYTES: u64 = 512 * 1024;
/// LZ4 level of the chunks: 0, LZ4's fast mode. (LZ4 rather than zstd:
/// zstd level 1 writes a log about 17 % smaller but takes about 1.5 times
/// the instructions to compress it, most of the writer's work; readers
/// decompress both.)
pub const LZ4_LEVEL: u32 = 0;
/// Batches in flight between the simulation and the writer thread.
pub const CHANNEL_CAPACITY: usize = 16;
/// Topic of the link transforms.
pub const TF_TOPIC: &str = "/tf";
/// Topic of the 3D scene.
pub const SCENE_TOPIC: &str = "/scene";
/// Topic of the terrain description.
pub const TERRAIN_TOPIC: &str = "/terrain";

/// A log I/O or encoding failure, naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct LogError {
    /// The log file.
    pub path: String,
    /// What failed.
    pub message: String,
}

impl From<LogError> for crate::error::CliError {
    /// A failure to write the log is an I/O failure on the log file (exit status 1).
    fn from(e: LogError) -> Self {
        crate::error::CliError::Io {
            path: e.path,
            source: std::io::Error::other(e.message),
        }
    }
}

/// What the writer thread did, for the run's report and the docs' cost figures.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WriterStats {
    /// Messages written.
    pub messages: u64,
    /// Bytes of the finished file.
    pub file_bytes: u64,
    /// Wall time the writer thread spent encoding and writing (s); waiting
    /// for records is not counted, time the OS gave to other threads is.
    pub busy_s: f64,
    /// CPU time of the writer thread (s), where the OS reports it (Linux's
    /// `/proc/thread-self/schedstat`): the share of a core logging takes.
    pub cpu_s: Option<f64>,
}

/// CPU time of the calling thread (s), on Linux.
fn thread_cpu_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

enum Cmd {
    Records(Vec<LogRecord>),
    Json {
        topic: String,
        schema: Schema,
        t_ns: u64,
        data: Vec<u8>,
    },
    Metadata(String, BTreeMap<String, String>),
    Finish,
}

/// Records sent to the writer thread together: one wake-up of the writer
/// per batch rather than per sample.
pub const BATCH_RECORDS: usize = 16;

/// The sink handed to the simulation's [`quadsim_systems::Logger`].
struct ChannelSink {
    tx: SyncSender<Cmd>,
    pending: Vec<LogRecord>,
}

impl ChannelSink {
    fn send_pending(&mut self) {
        if !self.pending.is_empty() {
            let batch = std::mem::replace(&mut self.pending, Vec::with_capacity(BATCH_RECORDS));
            // A send fails only when the writer thread stopped on an error;
            // the error is reported by `McapLog::finish`.
            let _ = self.tx.send(Cmd::Records(batch));
        }
    }
}

impl LogSink for ChannelSink {
    fn send(&mut self, record: LogRecord) {
        self.pending.push(record);
        if self.pending.len() >= BATCH_RECORDS {
            self.send_pending();
        }
    }

    fn flush(&mut self) {
        self.send_pending();
    }
}

impl Drop for ChannelSink {
    fn drop(&mut self) {
        self.send_pending();
    }
}

/// An MCAP log being written.
#[derive(Debug)]
pub struct McapLog {
    tx: SyncSender<Cmd>,
    thread: Option<JoinHandle<Result<WriterStats, String>>>,
    path: PathBuf,
}

impl McapLog {
    /// Creates `path` and starts the writer thread. `metadata` records are
    /// written first (outside chunks, so a truncated file keeps them);
    /// `ground` is drawn in the 3D scene.
    pub fn create(
        path: &Path,
        metadata: Vec<(String, BTreeMap<String, String>)>,
        ground: GroundMesh,
    ) -> Result<McapLog, LogError> {
        let err = |message: String| LogError {
            path: path.display().to_string(),
            message,
        };
        let file = LogFile::new(File::create(path).map_err(|e| err(e.to_string()))?);
        let mut writer = WriteOptions::new()
            .profile(PROFILE)
            .library(LIBRARY)
            .compression(Some(Compression::Lz4))
            .compression_level(LZ4_LEVEL)
            .compression_threads(0)
            .chunk_size(Some(CHUNK_SIZE_BYTES))
            // chunks built whole in memory, not patched in place
            .disable_seeking(true)
            .create(file.clone())
            .map_err(|e| err(e.to_string()))?;
        for (name, map) in metadata {
            writer
                .write_metadata(&Metadata {
                    name,
                    metadata: map,
                })
                .map_err(|e| err(e.to_string()))?;
        }
        // the header and the metadata on disk at once, as a complete file
        file.commit(true).map_err(|e| err(e.to_string()))?;
        let (tx, rx) = sync_channel(CHANNEL_CAPACITY);
        let thread = std::thread::Builder::new()
            .name("quadsim-log".into())
            .spawn(move || write_loop(writer, file, rx, ground))
            .map_err(|e| err(e.to_string()))?;
        Ok(McapLog {
            tx,
            thread: Some(thread),
            path: path.to_path_buf(),
        })
    }

    /// A sink for the simulation's logger.
    pub fn sink(&self) -> Box<dyn LogSink> {
        Box::new(ChannelSink {
            tx: self.tx.clone(),
            pending: Vec::with_capacity(BATCH_RECORDS),
        })
    }

    /// Writes one JSON message on `topic` (registered on first use with `schema`).
    pub fn write_json(&self, topic: &str, schema: Schema, t_ns: u64, value: &serde_json::Value) {
        let data = serde_json::to_vec(value).expect("serialising to memory cannot fail");
        let _ = self.tx.send(Cmd::Json {
            topic: topic.to_string(),
            schema,
            t_ns,
            data,
        });
    }

    /// Writes a metadata record.
    pub fn write_metadata(&self, name: &str, map: BTreeMap<String, String>) {
        let _ = self.tx.send(Cmd::Metadata(name.to_string(), map));
    }

    /// Finishes the file (summary section and index) and waits for the thread.
    pub fn finish(mut self) -> Result<WriterStats, LogError> {
        let _ = self.tx.send(Cmd::Finish);
        let thread = self.thread.take().expect("finish runs once");
        thread
            .join()
            .map_err(|_| "the log writer thread panicked".to_string())
            .and_then(|r| r)
            .map_err(|message| LogError {
                path: self.path.display().to_string(),
                message,
            })
    }
}

/// Channel ids by topic, registering schemas and channels on first use.
struct Channels {
    schemas: BTreeMap<Schema, u16>,
    topics: BTreeMap<String, u16>,
}

impl Channels {
    fn id(&mut self, w: &mut Writer<LogFile>, topic: &str, schema: Schema) -> Result<u16, String> {
        if let Some(&id) = self.topics.get(topic) {
            return Ok(id);
        }
        let schema_id = match self.schemas.get(&schema) {
            Some(&id) => id,
            None => {
                let id = w
                    .add_schema(schema.name(), schema.schema_encoding(), &schema.data())
                    .map_err(|e| e.to_string())?;
                self.schemas.insert(schema, id);
                id
            }
        };
        let id = w
            .add_channel(
                schema_id,
                topic,
                schema.message_encoding(),
                &BTreeMap::new(),
            )
            .map_err(|e| e.to_string())?;
        self.topics.insert(topic.to_string(), id);
        Ok(id)
    }
}

/// The log file as the MCAP writer sees it. What the writer hands over
/// (with `disable_seeking`, each chunk whole once it is complete, then its
/// message indexes; metadata records; at the end the summary section)
/// collects in memory and reaches the file at a [`Self::commit`], in one
/// write at the end of what was committed before. A commit that is not the
/// last appends a provisional end: a DataEnd record (no data-section CRC),
/// a Footer without a summary (`summary_start` 0) and the magic, which the
/// next commit overwrites. So the file on disk is a complete MCAP file
/// after every commit.
///
/// The one failure left: a SIGKILL that lands inside a commit's write (tens
/// of microseconds per chunk) can make the kernel stop that write at a page
/// boundary, leaving a torn last chunk and no end; quadsim's own reader
/// still recovers every complete chunk of such a file.
#[derive(Clone)]
struct LogFile(Arc<Mutex<LogFileState>>);

struct LogFileState {
    file: File,
    /// Bytes handed over since the last commit.
    pending: Vec<u8>,
    /// Bytes committed (the provisional end, if any, lies after them).
    committed: u64,
}

/// The provisional end: DataEnd (data-section CRC 0: none), Footer
/// (summary_start 0, summary_offset_start 0, summary CRC 0), magic.
const PROVISIONAL_END: [u8; 50] = {
    let mut end = [0u8; 50];
    end[0] = mcap::records::op::DATA_END;
    end[1] = 4; // record length, u64 LE; the u32 CRC (0) follows
    end[13] = mcap::records::op::FOOTER;
    end[14] = 20; // record length: two u64 offsets and a u32 CRC, all 0
    let mut i = 0;
    while i < 8 {
        end[42 + i] = mcap::MAGIC[i];
        i += 1;
    }
    end
};

impl LogFile {
    fn new(file: File) -> Self {
        Self(Arc::new(Mutex::new(LogFileState {
            file,
            pending: Vec::with_capacity(1 << 20),
            committed: 0,
        })))
    }

    fn state(&self) -> std::sync::MutexGuard<'_, LogFileState> {
        // the state stays consistent between calls: a poisoned lock is usable
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Writes what was handed over since the last commit, in one write,
    /// followed by the provisional end unless this is the `last` commit
    /// (then the file is cut to what was committed).
    fn commit(&self, provisional_end: bool) -> std::io::Result<()> {
        let mut guard = self.state();
        let s = &mut *guard;
        if s.pending.is_empty() && provisional_end {
            return Ok(());
        }
        let n = s.pending.len() as u64;
        if provisional_end {
            s.pending.extend_from_slice(&PROVISIONAL_END);
        }
        s.file.seek(SeekFrom::Start(s.committed))?;
        s.file.write_all(&s.pending)?;
        s.committed += n;
        s.pending.clear();
        if !provisional_end {
            s.file.set_len(s.committed)?;
        }
        Ok(())
    }

    /// The file's size on disk.
    fn len(&self) -> u64 {
        self.state().file.metadata().map_or(0, |m| m.len())
    }
}

impl Write for LogFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.state().pending.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for LogFile {
    /// Only asks for the position: the writer appends (`disable_seeking`).
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        let s = self.state();
        let end = s.committed + s.pending.len() as u64;
        match pos {
            SeekFrom::Current(0) | SeekFrom::End(0) => Ok(end),
            SeekFrom::Start(p) if p == end => Ok(end),
            _ => Err(std::io::Error::new(
                std::io::ErrorKind::Unsupported,
                "the log is written in order",
            )),
        }
    }
}

/// The writer thread's state.
struct Output {
    w: Writer<LogFile>,
    channels: Channels,
    names: Vec<RobotNames>,
    topics: Vec<Vec<String>>,
    /// Channel ids of each robot's topics, once registered.
    ids: Vec<[Option<u16>; RobotTopic::ALL.len()]>,
    ground: GroundMesh,
    scenes: u32,
    seq: u32,
    buf: Vec<u8>,
    stats: WriterStats,
}

impl Output {
    /// Writes `self.buf` (or `data`) as one message on `topic`.
    fn put(
        &mut self,
        topic: &str,
        schema: Schema,
        t_ns: u64,
        data: Option<&[u8]>,
    ) -> Result<(), String> {
        let id = self.channels.id(&mut self.w, topic, schema)?;
        self.put_id(id, t_ns, data)
    }

    /// Writes `self.buf` (or `data`) as one message on channel `id`.
    fn put_id(&mut self, id: u16, t_ns: u64, data: Option<&[u8]>) -> Result<(), String> {
        self.seq = self.seq.wrapping_add(1);
        self.w
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: self.seq,
                    log_time: t_ns,
                    publish_time: t_ns,
                },
                data.unwrap_or(&self.buf),
            )
            .map_err(|e| e.to_string())?;
        self.stats.messages += 1;
        Ok(())
    }

    fn record(&mut self, record: LogRecord) -> Result<(), String> {
        match record {
            LogRecord::Robots { t_ns, robots } => {
                self.names = robots.iter().map(RobotNames::new).collect();
                self.topics = robots
                    .iter()
                    .map(|r| RobotTopic::ALL.iter().map(|t| t.topic(&r.name)).collect())
                    .collect();
                self.ids = vec![[None; RobotTopic::ALL.len()]; robots.len()];
                // robots without per-step channels have no `/tf` to place their links
                let shown: Vec<RobotInfo> = robots.iter().filter(|r| r.logged).cloned().collect();
                encode_scene(&shown, &self.ground, t_ns, self.scenes > 0, &mut self.buf);
                self.scenes += 1;
                self.put(SCENE_TOPIC, Schema::SceneUpdate, t_ns, None)
            }
            LogRecord::Step { t_ns, samples } => {
                for s in &samples {
                    for (k, topic) in RobotTopic::ALL.iter().enumerate() {
                        let (Some(n), Some(tp)) =
                            (self.names.get(s.robot), self.topics.get(s.robot))
                        else {
                            break;
                        };
                        if *topic == RobotTopic::Sensors && s.sensing.is_none() {
                            continue;
                        }
                        encode_robot(*topic, n, s, t_ns, &mut self.buf);
                        let id = match self.ids[s.robot][k] {
                            Some(id) => id,
                            None => {
                                let id = self.channels.id(&mut self.w, &tp[k], topic.schema())?;
                                self.ids[s.robot][k] = Some(id);
                                id
                            }
                        };
                        self.put_id(id, t_ns, None)?;
                    }
                }
                let with_names: Vec<_> = samples
                    .iter()
                    .filter_map(|s| self.names.get(s.robot).map(|n| (n, s)))
                    .collect();
                if with_names.is_empty() {
                    return Ok(());
                }
                encode_transforms(&with_names, t_ns, &mut self.buf);
                self.put(TF_TOPIC, Schema::FrameTransforms, t_ns, None)
            }
        }
    }
}

fn write_loop(
    w: Writer<LogFile>,
    file: LogFile,
    rx: Receiver<Cmd>,
    ground: GroundMesh,
) -> Result<WriterStats, String> {
    let mut out = Output {
        w,
        channels: Channels {
            schemas: BTreeMap::new(),
            topics: BTreeMap::new(),
        },
        names: Vec::new(),
        topics: Vec::new(),
        ids: Vec::new(),
        ground,
        scenes: 0,
        seq: 0,
        buf: Vec::with_capacity(16 * 1024),
        stats: WriterStats::default(),
    };
    let mut busy = Duration::ZERO;
    let finish = |mut out: Output, busy: Duration| -> Result<WriterStats, String> {
        out.w.finish().map_err(|e| e.to_string())?;
        let file = out.w.into_inner();
        file.commit(false).map_err(|e| e.to_string())?;
        out.stats.file_bytes = file.len();
        out.stats.busy_s = busy.as_secs_f64();
        out.stats.cpu_s = thread_cpu_s();
        Ok(out.stats)
    };
    while let Ok(cmd) = rx.recv() {
        let start = Instant::now();
        match cmd {
            Cmd::Records(records) => {
                for r in records {
                    out.record(r)?;
                }
            }
            Cmd::Json {
                topic,
                schema,
                t_ns,
                data,
            } => out.put(&topic, schema, t_ns, Some(&data))?,
            Cmd::Metadata(name, metadata) => out
                .w
                .write_metadata(&Metadata { name, metadata })
                .map_err(|e| e.to_string())?,
            Cmd::Finish => {
                busy += start.elapsed();
                return finish(out, busy);
            }
        }
        // a chunk completed by these records goes to disk whole
        file.commit(true).map_err(|e| e.to_string())?;
        busy += start.elapsed();
    }
    // every sender dropped without `Finish`: still close the file properly
    finish(out, busy)
}
