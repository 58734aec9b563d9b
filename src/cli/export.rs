//! `quadsim export LOG.mcap --csv DIR`: one tidy CSV per channel, for pandas
//! or MATLAB (`pd.read_csv`, `readtable`).
//!
//! Each row is one message: the column `t_s` (log time, s of simulation
//! time), then the message's numbers flattened into columns named by their
//! path (`pose.position.x`). Arrays of named things are keyed by name instead
//! of index: joint arrays by the `name` array beside them
//! (`position.LF_knee`), feet by their `name` (`feet.LF_foot.force.z`),
//! transforms by their `child_frame_id`; a robot's sensor readings, which
//! carry no names, by its joints' and feet's names in the model's order as
//! its `joint_states` and `feet` messages give them
//! (`encoder_position_rad.LF_knee`, `contact.LF_foot`). Booleans become 1/0, null an empty
//! cell; `timestamp` and `frame_id` are left out (the log time is `t_s`, the
//! frame is in `docs/logs.md`). The 3D scene and the terrain description are
//! not time series and are not exported.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::Value;

use crate::error::{CliError, bad};
use crate::log::read::{LogContents, read_log};
use crate::log::schema::Schema;

/// Arguments of `quadsim export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The log (`log.mcap` of a run).
    pub log: PathBuf,
    /// Write one CSV per channel into this directory.
    #[arg(long, value_name = "DIR")]
    pub csv: PathBuf,
}

/// Runs `quadsim export`.
pub fn run(a: ExportArgs) -> Result<(), CliError> {
    let contents = read_log(&a.log).map_err(|e| bad(e.to_string()))?;
    if let Some(e) = &contents.error {
        eprintln!(
            "warning: {}: read up to an unreadable part ({e}); exporting what came before",
            a.log.display()
        );
    } else if !contents.metadata.is_empty() && !contents.metadata.contains_key("run") {
        // a killed run's log reads whole to its last chunk, but has no
        // `run` record (written at the end)
        eprintln!(
            "warning: {}: the log has no 'run' record (the run was killed); exporting what it holds",
            a.log.display()
        );
    }
    let files = export_csv(&contents, &a.csv)?;
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// A cell: a number's text, 1/0, or empty.
type Row = Vec<(String, String)>;

/// Writes one CSV per time-series channel of `contents` into `dir`; returns the files.
pub fn export_csv(contents: &LogContents, dir: &Path) -> Result<Vec<PathBuf>, CliError> {
    std::fs::create_dir_all(dir).map_err(|e| CliError::Io {
        path: dir.display().to_string(),
        source: e,
    })?;
    let skip = [
        Schema::SceneUpdate.name(),
        Schema::TerrainDescription.name(),
    ];
    let mut files = Vec::new();
    for topic in contents.topics() {
        let mut rows: Vec<(f64, Row)> = Vec::new();
        let mut named: Option<Named> = None;
        for m in contents.topic(&topic) {
            if skip.contains(&m.schema.as_str()) {
                continue;
            }
            let v = m.json().map_err(|e| {
                bad(format!(
                    "{topic}: message at t = {} s cannot be decoded: {e}",
                    m.t_s()
                ))
            })?;
            let mut row = Row::new();
            if m.schema == Schema::Sensors.name() {
                let named = named.get_or_insert_with(|| sensor_names(contents, &topic));
                flatten_named(&v, named, &mut row);
            } else {
                flatten(&v, "", &mut row);
            }
            rows.push((m.t_s(), row));
        }
        if rows.is_empty() {
            continue;
        }
        let path = dir.join(csv_name(&topic));
        write_table(&path, &rows)?;
        files.push(path);
    }
    Ok(files)
}

/// Names for a message's top-level arrays that carry none themselves:
/// `(key, names)`.
type Named = Vec<(&'static str, Vec<String>)>;

/// The names of a `/<robot>/sensors` channel's arrays: the encoder readings
/// by the robot's actuated joints (its `joint_states`' `name`, the model's
/// velocity order), the contact flags and forces by its feet (its `feet`'
/// names, the model's foot order). Empty where the log has no such message.
fn sensor_names(contents: &LogContents, topic: &str) -> Named {
    let robot = topic.strip_suffix("/sensors").unwrap_or(topic);
    let first = |channel: &str| {
        contents
            .topic(&format!("{robot}/{channel}"))
            .find_map(|m| m.json().ok())
    };
    let strings = |a: Option<&Value>, key: Option<&str>| -> Vec<String> {
        a.and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(|x| key.map_or(Some(x), |k| x.get(k)))
            .filter_map(|x| x.as_str().map(str::to_string))
            .collect()
    };
    let joints = first("joint_states").map_or_else(Vec::new, |v| strings(v.get("name"), None));
    let feet = first("feet").map_or_else(Vec::new, |v| strings(v.get("feet"), Some("name")));
    vec![
        ("encoder_position_rad", joints.clone()),
        ("encoder_velocity_radps", joints),
        ("contact", feet.clone()),
        ("contact_force_n", feet),
    ]
}

/// [`flatten`] of a message whose top-level arrays `named` lists: an array
/// with as many elements as its names is keyed by them (`contact.LF_foot`),
/// any other by index as before.
fn flatten_named(v: &Value, named: &Named, out: &mut Row) {
    let Value::Object(map) = v else {
        return flatten(v, "", out);
    };
    for (k, x) in map {
        if matches!(k.as_str(), "timestamp" | "frame_id" | "name") {
            continue;
        }
        let names = named
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, n)| n)
            .filter(|n| !n.is_empty());
        match (x, names) {
            (Value::Array(a), Some(n)) if a.len() == n.len() => {
                for (name, e) in n.iter().zip(a) {
                    flatten(e, &join(k, name), out);
                }
            }
            _ => flatten(x, k, out),
        }
    }
}

/// `/rex/joint_states` → `rex.joint_states.csv`.
pub fn csv_name(topic: &str) -> String {
    let stem: String = topic
        .trim_start_matches('/')
        .chars()
        .map(|c| if c == '/' { '.' } else { c })
        .collect();
    format!("{stem}.csv")
}

fn write_table(path: &Path, rows: &[(f64, Row)]) -> Result<(), CliError> {
    let io = |e: std::io::Error| CliError::Io {
        path: path.display().to_string(),
        source: e,
    };
    // columns: the union over rows, in first-seen order
    let mut columns: Vec<String> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for (_, row) in rows {
        for (k, _) in row {
            if !index.contains_key(k) {
                index.insert(k.clone(), columns.len());
                columns.push(k.clone());
            }
        }
    }
    let mut w = csv::Writer::from_path(path).map_err(|e| io(e.into()))?;
    let mut header = vec!["t_s".to_string()];
    header.extend(columns.iter().cloned());
    w.write_record(&header).map_err(|e| io(e.into()))?;
    let mut record = vec![String::new(); columns.len() + 1];
    for (t, row) in rows {
        record.iter_mut().for_each(String::clear);
        record[0] = format!("{t}");
        for (k, v) in row {
            record[index[k] + 1].clone_from(v);
        }
        w.write_record(&record).map_err(|e| io(e.into()))?;
    }
    w.flush().map_err(io)
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// A name for an array element that is an object with an identifying string.
fn element_name(v: &Value) -> Option<&str> {
    ["name", "child_frame_id", "id"]
        .iter()
        .find_map(|k| v.get(*k).and_then(Value::as_str))
}

/// Flattens `v` into `(column, cell)` pairs (see the module doc).
pub fn flatten(v: &Value, prefix: &str, out: &mut Row) {
    match v {
        Value::Object(map) => {
            // joint-state style: a `name` array keys its sibling arrays of the same length
            let names: Option<Vec<&str>> = map
                .get("name")
                .and_then(Value::as_array)
                .and_then(|a| a.iter().map(Value::as_str).collect::<Option<Vec<_>>>());
            for (k, x) in map {
                if matches!(k.as_str(), "timestamp" | "frame_id" | "name") {
                    continue;
                }
                match (x, &names) {
                    (Value::Array(a), Some(n)) if a.len() == n.len() => {
                        for (name, e) in n.iter().zip(a) {
                            flatten(e, &join(&join(prefix, k), name), out);
                        }
                    }
                    _ => flatten(x, &join(prefix, k), out),
                }
            }
        }
        Value::Array(a) => {
            for (i, e) in a.iter().enumerate() {
                let key = element_name(e).map_or_else(|| i.to_string(), str::to_string);
                flatten(e, &join(prefix, &key), out);
            }
        }
        Value::Number(n) => out.push((prefix.to_string(), n.to_string())),
        Value::Bool(b) => out.push((prefix.to_string(), if *b { "1" } else { "0" }.into())),
        Value::Null => out.push((prefix.to_string(), String::new())),
        Value::String(_) => {}
    }
}
