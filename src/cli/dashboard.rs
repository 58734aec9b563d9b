//! The live terminal dashboard of `quadsim monitor` (ratatui): per robot its
//! horizontal speed, base height, attitude, foot contacts and a speed
//! sparkline over the last seconds of simulated time; `--robot NAME` (or
//! Enter on a row) focuses one robot with larger panels. `q` or Esc quits,
//! ↑/↓ move through a herd, Enter focuses, Backspace returns to the list.
//!
//! [`Dashboard`] holds what is drawn and is fed the frames of each instant;
//! [`Dashboard::draw`] renders into any ratatui backend, so tests draw it on
//! a `TestBackend` from known frames.

use std::collections::VecDeque;

use ratatui::layout::{Constraint, Direction, Layout};
use ratatui::style::{Color, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Paragraph, Row, Sparkline, Table, TableState};

use crate::monitor::RobotFrame;

/// Simulated time between two points of a speed sparkline (s).
pub const SPARK_DT_S: f64 = 0.05;
/// Points a sparkline keeps: 200 × 0.05 s = the last 10 s of simulated time.
pub const SPARK_POINTS: usize = 200;
/// Characters of a table row's sparkline (the last 1.5 s).
pub const ROW_SPARK_CHARS: usize = 30;
/// The eight levels of a text sparkline, lowest first.
const LEVELS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];

/// One robot's latest frame and its speed history.
#[derive(Debug, Clone)]
struct RobotView {
    name: String,
    last: Option<RobotFrame>,
    /// Horizontal base speed (m/s), one point per [`SPARK_DT_S`] of sim time.
    speed: VecDeque<f64>,
}

/// What the dashboard shows.
#[derive(Debug, Clone)]
pub struct Dashboard {
    world: String,
    robots: Vec<RobotView>,
    /// The focused robot's index (`--robot`, or Enter on a row).
    pub focus: Option<usize>,
    /// The selected row of the list.
    pub selected: usize,
    /// Instants received.
    pub instants: u64,
    /// Simulation time of the latest instant (s).
    time_s: f64,
    tick: u64,
    /// Time of the last sparkline point (s).
    last_point_s: f64,
    /// A status line (e.g. "no instant for 2.0 s").
    pub status: Option<String>,
}

impl Dashboard {
    /// A dashboard of world `world` whose header lists `names` (robot
    /// index order); `focus` is a robot index.
    pub fn new(world: &str, names: Vec<String>, focus: Option<usize>) -> Self {
        Self {
            world: world.to_string(),
            robots: names
                .into_iter()
                .map(|name| RobotView {
                    name,
                    last: None,
                    speed: VecDeque::with_capacity(SPARK_POINTS),
                })
                .collect(),
            focus,
            selected: focus.unwrap_or(0),
            instants: 0,
            time_s: f64::NAN,
            tick: 0,
            last_point_s: f64::NEG_INFINITY,
            status: None,
        }
    }

    /// Takes one instant's frames (indexed by `robot_index`). A sparkline
    /// point is added when at least [`SPARK_DT_S`] of simulated time passed
    /// since the last one (a subscriber may miss instants; the sparkline
    /// keeps its time scale).
    pub fn update(&mut self, frames: &[RobotFrame]) {
        let Some(first) = frames.first() else {
            return;
        };
        self.instants += 1;
        self.time_s = first.time_s;
        self.tick = first.tick;
        if first.time_s < self.last_point_s {
            // a new run under the same name started over: forget the history
            self.last_point_s = f64::NEG_INFINITY;
            for r in &mut self.robots {
                r.speed.clear();
            }
        }
        let point = first.time_s >= self.last_point_s + SPARK_DT_S - 1e-9;
        if point {
            self.last_point_s = first.time_s;
        }
        for f in frames {
            let Some(r) = self.robots.get_mut(f.robot_index as usize) else {
                continue;
            };
            r.last = Some(*f);
            if point {
                if r.speed.len() == SPARK_POINTS {
                    r.speed.pop_front();
                }
                r.speed.push_back(f.speed_mps());
            }
        }
        self.status = None;
    }

    /// Moves the list selection by `delta` rows.
    pub fn scroll(&mut self, delta: isize) {
        let n = self.robots.len();
        if n > 0 {
            self.selected = self.selected.saturating_add_signed(delta).min(n - 1);
        }
    }

    /// Renders the dashboard into `f`'s whole area.
    pub fn draw(&self, f: &mut ratatui::Frame<'_>) {
        let areas = Layout::default()
            .direction(Direction::Vertical)
            .constraints([Constraint::Length(3), Constraint::Min(4)])
            .split(f.area());
        let mode = if self.focus.is_some() {
            "q quit, Backspace list"
        } else {
            "q quit, ↑/↓ select, Enter focus"
        };
        let header = Paragraph::new(Line::from(format!(
            "world {}  tick {}  t = {:.3} s  {} robots  {} instants{}",
            self.world,
            self.tick,
            self.time_s,
            self.robots.len(),
            self.instants,
            self.status
                .as_ref()
                .map_or(String::new(), |s| format!("  [{s}]"))
        )))
        .block(Block::bordered().title(format!(" quadsim monitor ({mode}) ")));
        f.render_widget(header, areas[0]);
        match self.focus.and_then(|i| self.robots.get(i)) {
            Some(r) => draw_focus(f, areas[1], r),
            None => self.draw_list(f, areas[1]),
        }
    }

    fn draw_list(&self, f: &mut ratatui::Frame<'_>, area: ratatui::layout::Rect) {
        let rows: Vec<Row> = self
            .robots
            .iter()
            .map(|r| {
                let mut cells = values(r.last.as_ref());
                cells.insert(0, r.name.clone());
                cells.push(text_sparkline(
                    r.speed.iter().copied(),
                    ROW_SPARK_CHARS,
                    speed_scale(&r.speed),
                ));
                Row::new(cells)
            })
            .collect();
        let table = Table::new(
            rows,
            [
                Constraint::Length(12),
                Constraint::Length(9),
                Constraint::Length(9),
                Constraint::Length(22),
                Constraint::Length(9),
                Constraint::Min(ROW_SPARK_CHARS as u16),
            ],
        )
        .header(
            Row::new(vec![
                "robot",
                "speed m/s",
                "height m",
                "roll pitch yaw °",
                "contacts",
                "speed (last 1.5 s)",
            ])
            .style(Style::default().fg(Color::Yellow)),
        )
        .row_highlight_style(Style::default().bg(Color::DarkGray))
        .block(Block::bordered());
        let mut state = TableState::default().with_selected(Some(self.selected));
        f.render_stateful_widget(table, area, &mut state);
    }
}

/// Speed, height, attitude (degrees) and contacts of a frame as text;
/// dashes before the first frame.
pub fn values(f: Option<&RobotFrame>) -> Vec<String> {
    let Some(f) = f else {
        return vec!["-".into(); 4];
    };
    let deg = |x: f64| x.to_degrees();
    vec![
        format!("{:.3}", f.speed_mps()),
        format!("{:.4}", f.base_position_m[2]),
        format!(
            "{:+.1} {:+.1} {:+.1}",
            deg(f.rpy_rad[0]),
            deg(f.rpy_rad[1]),
            deg(f.rpy_rad[2])
        ),
        contacts(f),
    ]
}

/// One character per foot: `●` in contact, `○` not.
pub fn contacts(f: &RobotFrame) -> String {
    let s: String = (0..f.feet())
        .map(|i| if f.in_contact(i) { '●' } else { '○' })
        .collect();
    if s.is_empty() { "-".into() } else { s }
}

/// The top of a sparkline's scale: the history's largest speed, at least 0.1 m/s.
fn speed_scale(speed: &VecDeque<f64>) -> f64 {
    speed
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.1, f64::max)
}

/// The last `width` values as a text sparkline scaled to `[0, max]`: level
/// `round(7 v / max)` of `▁…█`; non-finite values are blanks.
pub fn text_sparkline(
    values: impl DoubleEndedIterator<Item = f64>,
    width: usize,
    max: f64,
) -> String {
    let mut last: Vec<f64> = values.rev().take(width).collect();
    last.reverse();
    last.iter()
        .map(|&v| {
            if v.is_finite() && max > 0.0 {
                let k = (7.0 * (v / max).clamp(0.0, 1.0)).round() as usize;
                LEVELS[k]
            } else {
                ' '
            }
        })
        .collect()
}

/// One robot in detail: its values, foot forces and a full-width speed sparkline.
fn draw_focus(f: &mut ratatui::Frame<'_>, area: ratatui::layout::Rect, r: &RobotView) {
    let areas = Layout::default()
        .direction(Direction::Vertical)
        .constraints([Constraint::Length(9), Constraint::Min(4)])
        .split(area);
    let v = values(r.last.as_ref());
    let mut lines = vec![
        Line::from(format!("speed      {} m/s (horizontal, base origin)", v[0])),
        Line::from(format!("height     {} m (base origin z, world)", v[1])),
        Line::from(format!("attitude   {} (roll pitch yaw, deg)", v[2])),
        Line::from(format!("contacts   {}", v[3])),
    ];
    if let Some(fr) = &r.last {
        lines.push(Line::from(format!(
            "CoM        {:.3} {:.3} {:.3} m",
            fr.com_m[0], fr.com_m[1], fr.com_m[2]
        )));
        let fz: Vec<String> = (0..fr.feet())
            .map(|i| format!("{:.1}", fr.foot_force_n[i][2]))
            .collect();
        lines.push(Line::from(format!("foot Fz    {} N", fz.join(" "))));
    }
    let details = Paragraph::new(lines).block(Block::bordered().title(format!(" {} ", r.name)));
    f.render_widget(details, areas[0]);
    let max = speed_scale(&r.speed);
    // millimetres per second as integers: the widget's data are u64
    let data: Vec<u64> = r
        .speed
        .iter()
        .map(|&x| {
            if x.is_finite() {
                (x.max(0.0) * 1000.0).round() as u64
            } else {
                0
            }
        })
        .collect();
    let width = areas[1].width.saturating_sub(2) as usize;
    let shown = &data[data.len().saturating_sub(width)..];
    let spark = Sparkline::default()
        .block(Block::bordered().title(format!(
            " speed, last {:.1} s (0 … {max:.2} m/s) ",
            shown.len() as f64 * SPARK_DT_S
        )))
        .data(shown)
        .max((max * 1000.0).round() as u64)
        .style(Style::default().fg(Color::Cyan));
    f.render_widget(spark, areas[1]);
}

/// The text of a backend's buffer, one line per row, trailing blanks cut.
pub fn buffer_text(buf: &ratatui::buffer::Buffer) -> String {
    let mut out = String::new();
    for y in 0..buf.area.height {
        let line: String = (0..buf.area.width)
            .map(|x| buf[(x, y)].symbol().to_string())
            .collect();
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}
