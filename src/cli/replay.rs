//! `quadsim replay LOG.mcap [--speed X] [--signals a,b,...]`: plays a log in
//! the terminal (ratatui): a table of every robot's state at the playback
//! time and moving line charts of the chosen signals. `q` or Esc quits, space
//! pauses, ← and → step back and forth by one second.
//!
//! A signal is a Foxglove-style message path: a topic, then a JSON field
//! path, e.g. `/rex/com.position.z`, `/rex/joint_states.effort[2]`,
//! `/rex/feet.feet[0].force.z`.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use ratatui::Terminal;
use ratatui::backend::{Backend, TestBackend};
use ratatui::layout::{Constraint, Direction, Layout};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Row, Table};
use serde_json::Value;

use crate::error::{CliError, bad};
use crate::log::read::{LogContents, read_log};
use crate::report::series::RobotSeries;

/// Arguments of `quadsim replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The log (`log.mcap` of a run).
    pub log: PathBuf,
    /// Playback speed (simulated seconds per wall-clock second).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Signals to chart, comma-separated message paths (default: the first
    /// robot's CoM height, CoM forward velocity and pitch).
    #[arg(long, value_delimiter = ',')]
    pub signals: Vec<String>,
    /// Seconds of history shown in the charts.
    #[arg(long, default_value_t = 5.0)]
    pub window: f64,
    /// Test mode: render this many frames, evenly spread over the log, to an
    /// in-memory terminal and print the last one (no terminal needed).
    #[arg(long, hide = true)]
    pub headless_frames: Option<u32>,
    /// Width and height of the in-memory terminal of `--headless-frames`.
    #[arg(long, hide = true, num_args = 2, default_values_t = [120, 40])]
    pub headless_size: Vec<u16>,
}

/// A signal's samples.
#[derive(Debug, Clone)]
pub struct Signal {
    /// The message path as given.
    pub path: String,
    /// (t_s, value) in log order; non-numeric values are left out.
    pub points: Vec<(f64, f64)>,
}

/// Splits `/topic.field.path` at the topic's end: the longest prefix that is
/// a topic of the log.
fn split_path<'a>(path: &'a str, topics: &[String]) -> Option<(&'a str, &'a str)> {
    topics
        .iter()
        .filter(|t| path == t.as_str() || path.starts_with(&format!("{t}.")))
        .max_by_key(|t| t.len())
        .map(|t| path.split_at(t.len()))
}

/// The value at a field path (`.a.b[2].c`) of a decoded message.
pub fn resolve<'a>(mut v: &'a Value, field: &str) -> Option<&'a Value> {
    for part in field.split('.').filter(|p| !p.is_empty()) {
        let (key, index) = match part.split_once('[') {
            Some((k, rest)) => (k, Some(rest.trim_end_matches(']').parse::<usize>().ok()?)),
            None => (part, None),
        };
        if !key.is_empty() {
            v = v.get(key)?;
        }
        if let Some(i) = index {
            v = v.get(i)?;
        }
    }
    Some(v)
}

/// Extracts a signal from the log; errors name the path and list the topics.
pub fn signal(c: &LogContents, path: &str) -> Result<Signal, String> {
    let topics = c.topics();
    let (topic, field) = split_path(path, &topics).ok_or_else(|| {
        format!(
            "--signals: '{path}' names no topic of the log (topics: {})",
            topics.join(", ")
        )
    })?;
    let mut points = Vec::new();
    let mut found = false;
    for m in c.topic(topic) {
        let j = m.json().map_err(|e| format!("{topic}: not JSON: {e}"))?;
        if let Some(v) = resolve(&j, field) {
            found = true;
            if let Some(x) = v.as_f64() {
                points.push((m.t_s(), x));
            }
        }
    }
    if !found {
        return Err(format!(
            "--signals: '{path}': topic {topic} has no field '{}'",
            field.trim_start_matches('.')
        ));
    }
    Ok(Signal {
        path: path.to_string(),
        points,
    })
}

/// What is played.
#[derive(Debug)]
pub struct Replay {
    /// Every robot with per-step channels.
    pub robots: Vec<RobotSeries>,
    /// The charted signals.
    pub signals: Vec<Signal>,
    /// Last log time (s).
    pub end_s: f64,
    /// Chart history (s).
    pub window_s: f64,
}

impl Replay {
    /// Loads the robots and `signals` (default ones when empty) from a log.
    pub fn new(c: &LogContents, signals: &[String], window_s: f64) -> Result<Self, String> {
        let mut robots = Vec::new();
        for t in c.topics() {
            if let Some(name) = t.strip_prefix('/').and_then(|t| t.strip_suffix("/com")) {
                robots.push(RobotSeries::from_log(c, name)?);
            }
        }
        let paths: Vec<String> = if signals.is_empty() {
            robots
                .first()
                .map(|r| {
                    ["com.position.z", "com.velocity.x", "attitude.pitch"]
                        .iter()
                        .map(|f| format!("/{}/{f}", r.name))
                        .collect()
                })
                .unwrap_or_default()
        } else {
            signals.to_vec()
        };
        let signals = paths
            .iter()
            .map(|p| signal(c, p))
            .collect::<Result<Vec<_>, _>>()?;
        let end_s = c.messages.iter().map(|m| m.t_s()).fold(0.0, f64::max);
        Ok(Replay {
            robots,
            signals,
            end_s,
            window_s,
        })
    }

    /// Draws the frame at playback time `t_s`.
    pub fn draw(&self, f: &mut ratatui::Frame<'_>, t_s: f64, paused: bool) {
        let n = self.signals.len().max(1) as u32;
        let mut constraints = vec![Constraint::Length(self.robots.len() as u16 + 4)];
        constraints.extend((0..n).map(|_| Constraint::Ratio(1, n)));
        let areas = Layout::default()
            .direction(Direction::Vertical)
            .constraints(constraints)
            .split(f.area());
        let rows: Vec<Row> = self
            .robots
            .iter()
            .map(|r| {
                let k = upto(&r.com_t_s, t_s);
                let com = k.map_or([f64::NAN; 3], |k| r.com_m[k]);
                let v = k.map_or([f64::NAN; 3], |k| r.com_velocity_mps[k]);
                let rpy = upto(&r.attitude_t_s, t_s).map_or([f64::NAN; 3], |k| r.rpy_rad[k]);
                let feet = upto(&r.feet_t_s, t_s).map_or(String::new(), |k| {
                    r.foot_names
                        .iter()
                        .zip(&r.feet[k])
                        .map(|(n, f)| {
                            let short = n.split_once('_').map_or(n.as_str(), |p| p.0);
                            format!("{short}{}", if f.in_contact { "●" } else { "○" })
                        })
                        .collect::<Vec<_>>()
                        .join(" ")
                });
                Row::new(vec![
                    r.name.clone(),
                    format!("{:.3} {:.3} {:.3}", com[0], com[1], com[2]),
                    format!("{:.3} {:.3}", v[0], v[1]),
                    format!("{:.3} {:.3} {:.3}", rpy[0], rpy[1], rpy[2]),
                    feet,
                ])
            })
            .collect();
        let title = format!(
            " quadsim replay  t = {t_s:.3} / {:.3} s{}  (q quit, space pause, ←/→ ±1 s) ",
            self.end_s,
            if paused { "  [paused]" } else { "" }
        );
        let table = Table::new(
            rows,
            [
                Constraint::Length(10),
                Constraint::Length(22),
                Constraint::Length(16),
                Constraint::Length(22),
                Constraint::Min(20),
            ],
        )
        .header(
            Row::new(vec![
                "robot",
                "CoM x y z (m)",
                "CoM vx vy (m/s)",
                "roll pitch yaw (rad)",
                "feet (● contact)",
            ])
            .style(Style::default().fg(Color::Yellow)),
        )
        .block(Block::bordered().title(title));
        f.render_widget(table, areas[0]);

        let t0 = (t_s - self.window_s).max(0.0);
        for (i, s) in self.signals.iter().enumerate() {
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.0 >= t0 && p.0 <= t_s && p.1.is_finite())
                .collect();
            let now = pts.last().map_or(f64::NAN, |p| p.1);
            let (mut lo, mut hi) = pts
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.1), b.max(p.1))
                });
            if !lo.is_finite() {
                (lo, hi) = (0.0, 1.0);
            }
            if hi - lo < 1e-9 {
                (lo, hi) = (lo - 0.5, hi + 0.5);
            }
            let ds = Dataset::default()
                .name(s.path.clone())
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::default().fg(Color::Cyan))
                .data(&pts);
            let x1 = t0 + self.window_s;
            let chart = Chart::new(vec![ds])
                .block(Block::bordered().title(format!(" {} = {now:.4} ", s.path)))
                .x_axis(
                    Axis::default()
                        .bounds([t0, x1])
                        .labels(vec![format!("{t0:.1} s"), format!("{x1:.1} s")]),
                )
                .y_axis(
                    Axis::default()
                        .bounds([lo, hi])
                        .labels(vec![format!("{lo:.3}"), format!("{hi:.3}")]),
                );
            f.render_widget(chart, areas[i + 1]);
        }
    }
}

/// Index of the last time ≤ `t`.
fn upto(ts: &[f64], t: f64) -> Option<usize> {
    let k = ts.partition_point(|&x| x <= t + 1e-12);
    k.checked_sub(1)
}

/// Renders `frames` frames, evenly spread over the log, to an in-memory
/// terminal of `w × h` cells; returns the last one as text.
pub fn headless(r: &Replay, frames: u32, w: u16, h: u16) -> String {
    let mut term = Terminal::new(TestBackend::new(w, h)).expect("in-memory terminal");
    for k in 1..=frames.max(1) {
        let t = r.end_s * k as f64 / frames.max(1) as f64;
        term.draw(|f| r.draw(f, t, false))
            .expect("in-memory terminal");
    }
    super::dashboard::buffer_text(term.backend().buffer())
}

fn play<B: Backend>(term: &mut Terminal<B>, r: &Replay, speed: f64) -> std::io::Result<()>
where
    B::Error: Into<std::io::Error>,
{
    use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind};
    let mut t = 0.0;
    let mut paused = false;
    let mut last = Instant::now();
    loop {
        let now = Instant::now();
        if !paused {
            t = (t + speed * (now - last).as_secs_f64()).min(r.end_s);
        }
        last = now;
        term.draw(|f| r.draw(f, t, paused)).map_err(Into::into)?;
        if event::poll(Duration::from_millis(33))?
            && let Event::Key(k) = event::read()?
            && k.kind == KeyEventKind::Press
        {
            match k.code {
                KeyCode::Char('q') | KeyCode::Esc => return Ok(()),
                KeyCode::Char(' ') => paused = !paused,
                KeyCode::Left => t = (t - 1.0).max(0.0),
                KeyCode::Right => t = (t + 1.0).min(r.end_s),
                _ => {}
            }
        }
    }
}

/// Runs `quadsim replay`.
pub fn run(a: ReplayArgs) -> Result<(), CliError> {
    if !(a.speed.is_finite() && a.speed > 0.0) {
        return Err(bad(format!("--speed: must be > 0, got {}", a.speed)));
    }
    if !(a.window.is_finite() && a.window > 0.0) {
        return Err(bad(format!("--window: must be > 0 s, got {}", a.window)));
    }
    let c = read_log(&a.log).map_err(|e| bad(e.to_string()))?;
    let r = Replay::new(&c, &a.signals, a.window)
        .map_err(|e| bad(format!("{}: {e}", a.log.display())))?;
    if r.robots.is_empty() && r.signals.is_empty() {
        return Err(bad(format!(
            "{}: no robot channels to replay",
            a.log.display()
        )));
    }
    if let Some(n) = a.headless_frames {
        print!(
            "{}",
            headless(&r, n, a.headless_size[0], a.headless_size[1])
        );
        return Ok(());
    }
    // No terminal (a script, `</dev/null`, a pipe): the last frame as plain text.
    if !std::io::IsTerminal::is_terminal(&std::io::stdin())
        || !std::io::IsTerminal::is_terminal(&std::io::stdout())
    {
        eprintln!(
            "replay: not a terminal; printing the last frame as text (--headless-frames N for more)"
        );
        let text = headless(&r, 1, a.headless_size[0], a.headless_size[1]);
        for line in text.lines() {
            if !super::monitor::print_line(line)? {
                break;
            }
        }
        return Ok(());
    }
    let mut term = ratatui::try_init().map_err(|e| CliError::Io {
        path: "terminal".into(),
        source: e,
    })?;
    let res = play(&mut term, &r, a.speed);
    ratatui::restore();
    res.map_err(|e| CliError::Io {
        path: "terminal".into(),
        source: e,
    })
}
