//! What a report is made of ([`ReportInput`]: the summary, the scenario's
//! text, the log), the robots as the scenario declares them, and the error
//! of a report that could not be written.

use crate::log::read::LogContents;

/// A report could not be written.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ReportError {
    /// The file.
    pub path: String,
    /// What failed.
    pub message: String,
}

/// Whether the report needs a topic's messages (not the 3D scene and
/// transforms, the largest part of a log): the filter for
/// [`read_log_topics`](crate::log::read::read_log_topics).
pub fn needs_topic(topic: &str) -> bool {
    !matches!(topic, "/tf" | "/scene")
}

/// What a report is made of.
#[derive(Debug, Clone, Copy)]
pub struct ReportInput<'a> {
    /// `summary.json` (its `timing` block, if any, is not used).
    pub summary: &'a crate::summary::Summary,
    /// The scenario file's text (robot models, speed commands).
    pub scenario_text: &'a str,
    /// The log, for the plots; `None` for a run without a log (no plots).
    pub log: Option<&'a LogContents>,
}

/// A robot as the scenario declares it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RobotInfo {
    /// `model` (`quad16`, `quad12` or a URDF path).
    pub model: String,
    /// Controller kind.
    pub controller: String,
    /// Commanded forward speed over time for a `vmc` robot: `(t_s, v_x_mps)`
    /// from the controller's `v_x_mps` (default 0) and later `command` events.
    pub speed_command: Vec<(f64, f64)>,
}

/// The robot `name` in the scenario text (defaults when not found).
pub fn robot_info(scenario_text: &str, name: &str) -> RobotInfo {
    let table: toml::Table = scenario_text.parse().unwrap_or_default();
    let num = |v: Option<&toml::Value>| {
        v.and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let robot = table
        .get("robots")
        .and_then(|r| r.as_array())
        .and_then(|a| {
            a.iter()
                .find(|r| r.get("name").and_then(|n| n.as_str()) == Some(name))
        });
    // a herd's robot is not in `robots`: take it from the expanded herds
    let herd_robot;
    let robot = match robot {
        Some(r) => r,
        None => match herd_robot_table(scenario_text, name) {
            Some(t) => {
                herd_robot = toml::Value::Table(t);
                &herd_robot
            }
            None => return RobotInfo::default(),
        },
    };
    let ctrl = robot.get("controller");
    let kind = ctrl
        .and_then(|c| c.get("kind"))
        .and_then(|k| k.as_str())
        .unwrap_or("none")
        .to_string();
    let mut speed = Vec::new();
    if kind == "vmc" {
        speed.push((0.0, num(ctrl.and_then(|c| c.get("v_x_mps"))).unwrap_or(0.0)));
        let mut events: Vec<(f64, f64)> = table
            .get("events")
            .and_then(|e| e.as_array())
            .into_iter()
            .flatten()
            .filter(|e| {
                e.get("robot").and_then(|r| r.as_str()) == Some(name)
                    && e.get("kind").and_then(|k| k.as_str()) == Some("command")
            })
            .filter_map(|e| Some((num(e.get("t_s"))?, num(e.get("v_x_mps"))?)))
            .collect();
        events.sort_by(|a, b| a.0.total_cmp(&b.0));
        speed.extend(events);
    }
    RobotInfo {
        model: robot
            .get("model")
            .and_then(|m| m.as_str())
            .unwrap_or("?")
            .to_string(),
        controller: kind,
        speed_command: speed,
    }
}

/// The model and controller of a herd's robot, from the scenario's herds
/// expanded once per scenario text (a report asks for every robot of a
/// herd of thousands).
fn herd_robot_table(scenario_text: &str, name: &str) -> Option<toml::Table> {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex};
    type Expanded = Arc<HashMap<String, toml::Table>>;
    static CACHE: Mutex<Option<(String, Expanded)>> = Mutex::new(None);
    let expanded = {
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        match cache.as_ref() {
            Some((text, e)) if text == scenario_text => e.clone(),
            _ => {
                let mut map = HashMap::new();
                let mut file: crate::scenario::ScenarioFile = toml::from_str(scenario_text).ok()?;
                let path = std::path::Path::new("scenario.toml");
                let loc = crate::scenario::Locator {
                    path,
                    src: scenario_text,
                };
                crate::scenario::herd::expand(&loc, &mut file).ok()?;
                for r in file.robots {
                    let mut t = toml::Table::new();
                    t.insert("model".into(), toml::Value::String(r.model));
                    let mut c: toml::Table = r.controller.params.into_iter().collect();
                    if let Some(k) = r.controller.kind {
                        c.insert("kind".into(), toml::Value::String(k));
                    }
                    t.insert("controller".into(), toml::Value::Table(c));
                    map.insert(r.name, t);
                }
                let e = Arc::new(map);
                *cache = Some((scenario_text.to_string(), e.clone()));
                e
            }
        }
    };
    expanded.get(name).cloned()
}
