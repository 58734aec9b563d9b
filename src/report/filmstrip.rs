//! Filmstrips: pictures of the robots in `report.md`, drawn from the log.
//!
//! A robot's filmstrip shows its links at [`FRAMES`] instants of one gait
//! cycle (the last whole cycle of its gait clock; of its first foot's
//! contacts without one; the last second of the run for a robot that does
//! not step), side view
//! (x–z) above top view (x–y), each instant centred on the base. Links are
//! drawn as segments between link frame origins (`/tf`), boxes from
//! `/scene`, and feet as discs: filled on the ground, hollow in the air
//! (`/<robot>/feet`). A herd gets a top view of the whole world at its last
//! logged instant. Drawn with plotters into a bitmap with the bundled font
//! ([`super::plots`]), so `quadsim report` draws the same bytes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use plotters::prelude::*;
use serde_json::Value;

use super::input::{ReportError, needs_topic};
use super::plots::{FONT, register_fonts};
use super::series::RobotSeries;
use crate::log::read::{LogContents, LogMessage};

/// Instants per filmstrip.
pub const FRAMES: usize = 8;
/// Robots that get a filmstrip (the first in the summary's order; a herd's
/// worst ones, as its report details them): a herd's report stays bounded.
pub const MAX_ROBOTS: usize = 3;
/// Spacing of the `/tf` messages a report keeps (ns): the instants are
/// picked from these, so a long or large log costs a report little.
pub const TF_SPACING_NS: u64 = 10_000_000;
/// Pixels of one instant's cell (square).
const CELL: u32 = 180;
/// Height of the title band (px).
const TITLE_H: u32 = 34;
/// Label band of each view row (px).
const ROW_LABEL_W: u32 = 64;

const BACKGROUND: RGBColor = WHITE;
const LINK: RGBColor = RGBColor(60, 70, 90);
const BODY: RGBColor = RGBColor(120, 140, 175);
const GROUND: RGBColor = RGBColor(150, 130, 100);
const STANCE: RGBColor = RGBColor(200, 40, 40);
const SWING: RGBColor = RGBColor(40, 90, 200);

/// Whether a report reads a message: everything but `/tf` and `/scene`
/// (the largest part of a log) as before, plus the scene and one `/tf`
/// message per [`TF_SPACING_NS`] for the filmstrips. Stateful (`/tf`
/// messages come in time order), so make one per read.
pub fn report_filter() -> impl Fn(&str, u64) -> bool {
    let last_bucket = std::cell::Cell::new(None::<u64>);
    move |topic, t_ns| match topic {
        "/scene" => true,
        "/tf" => {
            let b = t_ns / TF_SPACING_NS;
            if last_bucket.get() == Some(b) {
                false
            } else {
                last_bucket.set(Some(b));
                true
            }
        }
        _ => needs_topic(topic),
    }
}

/// Every link frame's world pose at one instant, by frame id.
type Poses = BTreeMap<String, (DVec3, DQuat)>;

/// Parent of every frame id (the world has none).
type Parents = BTreeMap<String, String>;

/// The scene's boxes by frame id: (pose in the frame, size (m)).
type Boxes = BTreeMap<String, Vec<((DVec3, DQuat), DVec3)>>;

fn v3(v: &Value) -> DVec3 {
    let g = |k: &str| v[k].as_f64().unwrap_or(0.0);
    DVec3::new(g("x"), g("y"), g("z"))
}

fn quat(v: &Value) -> DQuat {
    let g = |k: &str| v[k].as_f64().unwrap_or(0.0);
    let q = DQuat::from_xyzw(g("x"), g("y"), g("z"), g("w"));
    if q.length_squared() > 0.0 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// World poses of the frames in one `/tf` message (transforms in their
/// parents, composed down from `world`), and each frame's parent.
fn world_poses(m: &LogMessage) -> Option<(Poses, Parents)> {
    let v = m.json().ok()?;
    let mut local = BTreeMap::new();
    let mut parents = Parents::new();
    for t in v["transforms"].as_array()? {
        let child = t["child_frame_id"].as_str()?.to_string();
        let parent = t["parent_frame_id"].as_str()?.to_string();
        local.insert(child.clone(), (v3(&t["translation"]), quat(&t["rotation"])));
        parents.insert(child, parent);
    }
    let mut poses = Poses::new();
    for id in local.keys() {
        // walk up to the world (a tree: at most as many steps as frames)
        let mut chain = vec![id.clone()];
        while let Some(p) = parents.get(chain.last()?) {
            if p == "world" || chain.len() > local.len() || poses.contains_key(p) {
                break;
            }
            chain.push(p.clone());
        }
        let top = chain.last()?;
        let mut pose = match parents.get(top).and_then(|p| poses.get(p)) {
            Some(&p) => p,
            None => (DVec3::ZERO, DQuat::IDENTITY),
        };
        for f in chain.iter().rev() {
            if let Some(&done) = poses.get(f) {
                pose = done;
                continue;
            }
            let (t, q) = local[f];
            pose = (pose.0 + pose.1 * t, pose.1 * q);
            poses.insert(f.clone(), pose);
        }
    }
    Some((poses, parents))
}

/// Boxes of the scene by frame id: (pose in the frame, size).
fn scene_boxes(log: &LogContents) -> Boxes {
    let mut out = Boxes::new();
    let Some(scene) = log.topic("/scene").last().and_then(|m| m.json().ok()) else {
        return out;
    };
    for e in scene["entities"].as_array().into_iter().flatten() {
        let Some(frame) = e["frame_id"].as_str() else {
            continue;
        };
        for c in e["cubes"].as_array().into_iter().flatten() {
            let pose = (v3(&c["pose"]["position"]), quat(&c["pose"]["orientation"]));
            out.entry(frame.to_string())
                .or_default()
                .push((pose, v3(&c["size"])));
        }
    }
    out
}

/// The `/tf` messages kept, by time (ns).
fn tf_messages(log: &LogContents) -> Vec<&LogMessage> {
    log.topic("/tf").collect()
}

/// The kept `/tf` message nearest `t_ns`.
fn nearest<'a>(tf: &[&'a LogMessage], t_ns: u64) -> Option<&'a LogMessage> {
    let i = tf.partition_point(|m| m.log_time_ns < t_ns);
    let after = tf.get(i);
    let before = i.checked_sub(1).and_then(|k| tf.get(k));
    match (before, after) {
        (Some(b), Some(a)) => Some(if t_ns - b.log_time_ns <= a.log_time_ns - t_ns {
            b
        } else {
            a
        }),
        (b, a) => b.or(a).copied(),
    }
}

/// A touchdown counts after the foot was in the air this long (s): a foot
/// that bounces or chatters on landing does not start a cycle.
const MIN_SWING_S: f64 = 0.05;

/// The last whole cycle of the gait clock (s): between the last two times
/// the first foot's `gait_phase` wrapped from near 1 to near 0, read from
/// the end of `/<robot>/feet` back; `None` without a gait.
fn gait_clock_cycle(log: &LogContents, robot: &str) -> Option<(f64, f64)> {
    let topic = format!("/{robot}/feet");
    let feet: Vec<&LogMessage> = log.topic(&topic).collect();
    let mut wraps = Vec::new();
    let mut later: Option<f64> = None;
    for m in feet.iter().rev() {
        let v = m.json().ok()?;
        let phase = v["feet"].as_array()?.first()?["gait_phase"].as_f64()?;
        if let Some(p_later) = later
            && p_later < phase - 0.5
        {
            // the phase wrapped between this message and the later one
            wraps.push(m.t_s());
            if wraps.len() == 3 {
                break;
            }
        }
        later = Some(phase);
    }
    // wraps[k] is the last message before a wrap: a cycle starts just after
    match wraps.as_slice() {
        [b, a, ..] if b > a => Some((*a, *b)),
        _ => None,
    }
}

/// The instants (s) of the robot's filmstrip: [`FRAMES`] evenly over the
/// last whole cycle of its gait clock, else its first foot's last whole
/// cycle of contacts (touchdown to touchdown after a swing of at least
/// [`MIN_SWING_S`]), else the last second logged.
fn cycle_instants(log: &LogContents, s: &RobotSeries) -> Vec<f64> {
    if let Some((t0, t1)) = gait_clock_cycle(log, &s.name) {
        return (0..FRAMES)
            .map(|k| t0 + (t1 - t0) * k as f64 / FRAMES as f64)
            .collect();
    }
    let mut touchdowns = Vec::new();
    let mut lifted: Option<f64> = None;
    for (f, &t) in s.feet.iter().zip(&s.feet_t_s) {
        let on = f.first().is_some_and(|p| p.in_contact);
        match (on, lifted) {
            (false, None) => lifted = Some(t),
            (true, Some(t_off)) => {
                if t - t_off >= MIN_SWING_S {
                    touchdowns.push(t);
                }
                lifted = None;
            }
            _ => {}
        }
    }
    let end = s
        .feet_t_s
        .last()
        .or(s.com_t_s.last())
        .copied()
        .unwrap_or(0.0);
    let (t0, t1) = match touchdowns.as_slice() {
        [.., a, b] if b > a => (*a, *b),
        _ => ((end - 1.0).max(0.0), end),
    };
    (0..FRAMES)
        .map(|k| t0 + (t1 - t0) * k as f64 / FRAMES as f64)
        .collect()
}

/// The feet at the `/feet` sample nearest `t_s`: (position, on the ground).
fn feet_at(s: &RobotSeries, t_s: f64) -> Vec<(DVec3, bool)> {
    let i = s.feet_t_s.partition_point(|&t| t < t_s);
    let k = match (i.checked_sub(1), s.feet_t_s.get(i)) {
        (Some(b), Some(&a)) if t_s - s.feet_t_s[b] <= a - t_s => b,
        (Some(b), None) => b,
        _ => i,
    };
    s.feet
        .get(k)
        .map(|f| {
            f.iter()
                .map(|p| (DVec3::from_array(p.position_m), p.in_contact))
                .collect()
        })
        .unwrap_or_default()
}

/// One robot at one instant, in world coordinates: link segments, box
/// edges, feet.
#[derive(Debug, Default, Clone)]
struct Pose3 {
    base: DVec3,
    segments: Vec<(DVec3, DVec3)>,
    boxes: Vec<(DVec3, DVec3)>,
    feet: Vec<(DVec3, bool)>,
}

/// The 12 edges of a box of `size` at `pose` (world).
fn box_edges(pose: (DVec3, DQuat), size: DVec3) -> Vec<(DVec3, DVec3)> {
    let h = size * 0.5;
    let corner = |i: usize| {
        let c = DVec3::new(
            if i & 1 == 0 { -h.x } else { h.x },
            if i & 2 == 0 { -h.y } else { h.y },
            if i & 4 == 0 { -h.z } else { h.z },
        );
        pose.0 + pose.1 * c
    };
    let mut out = Vec::with_capacity(12);
    for i in 0..8 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                out.push((corner(i), corner(i | bit)));
            }
        }
    }
    out
}

/// Robot `robot`'s pose from one `/tf` message's world poses.
fn robot_pose(robot: &str, poses: &Poses, parents: &Parents, boxes: &Boxes) -> Option<Pose3> {
    let prefix = format!("{robot}/");
    let mut p = Pose3::default();
    let mut found = false;
    for (id, &(t, q)) in poses.range(prefix.clone()..) {
        if !id.starts_with(&prefix) {
            break;
        }
        match parents.get(id) {
            Some(parent) if parent == "world" => {
                p.base = t;
                found = true;
            }
            Some(parent) => {
                // a link drawn as a box (the torso) needs no spokes to its children
                if let Some(&(pt, _)) = poses.get(parent)
                    && pt != t
                    && !boxes.contains_key(parent)
                {
                    p.segments.push((pt, t));
                }
            }
            None => {}
        }
        for &(local, size) in boxes.get(id).into_iter().flatten() {
            let world = (t + q * local.0, q * local.1);
            p.boxes.extend(box_edges(world, size));
        }
    }
    found.then_some(p)
}

/// How far the drawing reaches from the base (m), over `poses`.
fn reach(poses: &[Pose3]) -> f64 {
    let mut r: f64 = 0.05;
    for p in poses {
        for &(a, b) in p.segments.iter().chain(&p.boxes) {
            r = r.max((a - p.base).abs().max_element());
            r = r.max((b - p.base).abs().max_element());
        }
        for &(f, _) in &p.feet {
            r = r.max((f - p.base).abs().max_element());
        }
    }
    r
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// Draws `pose` into the cell at (`x0`, `y0`) of `root`: `side` projects
/// onto x–z (z up, the base's height kept), else onto x–y; `scale` px/m.
fn draw_pose(
    root: &Area<'_>,
    (x0, y0): (i32, i32),
    pose: &Pose3,
    side: bool,
    scale: f64,
    origin: DVec3,
) -> Result<(), String> {
    let c = CELL as i32;
    let project = |p: DVec3| -> (i32, i32) {
        let d = p - origin;
        let (u, v) = if side { (d.x, d.z) } else { (d.x, d.y) };
        (
            x0 + c / 2 + (u * scale).round() as i32,
            y0 + c / 2 - (v * scale).round() as i32,
        )
    };
    let err = |e: DrawingAreaErrorKind<_>| format!("{e:?}");
    root.draw(&Rectangle::new(
        [(x0 + 1, y0 + 1), (x0 + c - 2, y0 + c - 2)],
        RGBColor(225, 225, 225).stroke_width(1),
    ))
    .map_err(err)?;
    if side {
        // the ground under the feet on it (their contact points' lowest z)
        let ground = pose
            .feet
            .iter()
            .filter(|f| f.1)
            .map(|f| f.0.z)
            .fold(f64::INFINITY, f64::min);
        if ground.is_finite() {
            let (_, gy) = project(DVec3::new(origin.x, 0.0, ground));
            root.draw(&PathElement::new(
                vec![(x0 + 4, gy), (x0 + c - 5, gy)],
                GROUND.stroke_width(2),
            ))
            .map_err(err)?;
        }
    }
    for &(a, b) in &pose.boxes {
        root.draw(&PathElement::new(
            vec![project(a), project(b)],
            BODY.stroke_width(1),
        ))
        .map_err(err)?;
    }
    for &(a, b) in &pose.segments {
        root.draw(&PathElement::new(
            vec![project(a), project(b)],
            LINK.stroke_width(3),
        ))
        .map_err(err)?;
    }
    for &(f, on) in &pose.feet {
        let style = if on {
            STANCE.filled()
        } else {
            SWING.stroke_width(2)
        };
        root.draw(&Circle::new(project(f), 5, style)).map_err(err)?;
    }
    Ok(())
}

/// Writes an RGB buffer as PNG (fixed settings: the same pixels give the
/// same bytes).
fn write_png(path: &Path, rgb: &[u8], (w, h): (u32, u32)) -> Result<(), ReportError> {
    let fail = |m: String| ReportError {
        path: path.display().to_string(),
        message: m,
    };
    let file = std::fs::File::create(path).map_err(|e| fail(e.to_string()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    enc.write_header()
        .and_then(|mut wr| wr.write_image_data(rgb))
        .map_err(|e| fail(e.to_string()))
}

/// A picture written: (caption, file name under `plots/`).
pub type Picture = (String, String);

/// Draws robot `s`'s filmstrip into `dir/<robot>_filmstrip.png`; `None`
/// when the log has no `/tf` of it.
pub fn robot_filmstrip(
    log: &LogContents,
    s: &RobotSeries,
    dir: &Path,
) -> Result<Option<(Picture, PathBuf)>, ReportError> {
    let tf = tf_messages(log);
    let boxes = scene_boxes(log);
    let instants = cycle_instants(log, s);
    let mut poses = Vec::new();
    let mut times = Vec::new();
    for &t in &instants {
        let Some(m) = nearest(&tf, (t * 1e9).round().max(0.0) as u64) else {
            return Ok(None);
        };
        let Some((world, parents)) = world_poses(m) else {
            return Ok(None);
        };
        let Some(mut p) = robot_pose(&s.name, &world, &parents, &boxes) else {
            return Ok(None);
        };
        p.feet = feet_at(s, m.t_s());
        poses.push(p);
        times.push(m.t_s());
    }
    let scale = (CELL as f64 * 0.45) / reach(&poses);
    let (w, h) = (ROW_LABEL_W + CELL * FRAMES as u32, TITLE_H + 2 * CELL + 18);
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    let stem = crate::names::safe_file_stem(&format!("{}_filmstrip", s.name));
    let path = crate::names::join_inside(dir, &format!("{stem}.png")).map_err(|m| ReportError {
        path: dir.display().to_string(),
        message: m,
    })?;
    let caption = format!(
        "`{}`, one gait cycle, t = {:.2}–{:.2} s: side view (x–z) above top view (x–y), each instant centred on the base; feet filled on the ground, hollow in the air",
        s.name,
        times.first().copied().unwrap_or(0.0),
        times.last().copied().unwrap_or(0.0)
    );
    register_fonts();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let fail = |m: String| ReportError {
            path: path.display().to_string(),
            message: m,
        };
        root.fill(&BACKGROUND).map_err(|e| fail(format!("{e:?}")))?;
        let title = format!("{}: one gait cycle (side, top)", s.name);
        root.draw(&Text::new(title, (8, 8), (FONT, 18).into_font()))
            .map_err(|e| fail(format!("{e:?}")))?;
        for (row, side) in [(0, true), (1, false)] {
            let y0 = (TITLE_H + row * CELL) as i32;
            let label = if side { "side" } else { "top" };
            root.draw(&Text::new(
                label,
                (8, y0 + CELL as i32 / 2 - 7),
                (FONT, 14).into_font(),
            ))
            .map_err(|e| fail(format!("{e:?}")))?;
            for (k, p) in poses.iter().enumerate() {
                let x0 = (ROW_LABEL_W + k as u32 * CELL) as i32;
                let origin = if side {
                    DVec3::new(p.base.x, p.base.y, p.base.z)
                } else {
                    p.base
                };
                draw_pose(&root, (x0, y0), p, side, scale, origin).map_err(fail)?;
            }
        }
        for (k, t) in times.iter().enumerate() {
            let x0 = (ROW_LABEL_W + k as u32 * CELL) as i32;
            root.draw(&Text::new(
                format!("t = {t:.3} s"),
                (x0 + 8, (TITLE_H + 2 * CELL) as i32),
                (FONT, 13).into_font(),
            ))
            .map_err(|e| fail(format!("{e:?}")))?;
        }
        root.present().map_err(|e| fail(format!("{e:?}")))?;
    }
    write_png(&path, &rgb, (w, h))?;
    Ok(Some(((caption, format!("{stem}.png")), path)))
}

/// A top view of every robot in the log's last kept `/tf` message (a
/// herd's world), into `dir/world_snapshot.png`; `None` without one.
pub fn world_snapshot(
    log: &LogContents,
    robots: &[String],
    dir: &Path,
) -> Result<Option<(Picture, PathBuf)>, ReportError> {
    let Some(m) = log.topic("/tf").last() else {
        return Ok(None);
    };
    let Some((world, parents)) = world_poses(m) else {
        return Ok(None);
    };
    let boxes = scene_boxes(log);
    let poses: Vec<Pose3> = robots
        .iter()
        .filter_map(|r| robot_pose(r, &world, &parents, &boxes))
        .collect();
    if poses.is_empty() {
        return Ok(None);
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in &poses {
        for &(a, b) in p.segments.iter().chain(&p.boxes) {
            lo = lo.min(a.min(b));
            hi = hi.max(a.max(b));
        }
        lo = lo.min(p.base);
        hi = hi.max(p.base);
    }
    let (w, h) = (1200u32, 520u32);
    let span = (hi - lo).max(DVec3::splat(0.5));
    // the world's longer side across the picture: x to the right, or x up
    // (then y to the left) for a herd spread along y
    let x_up = span.y > span.x;
    let (su, sv) = if x_up {
        (span.y, span.x)
    } else {
        (span.x, span.y)
    };
    let scale = ((w - 40) as f64 / su).min((h - TITLE_H - 40) as f64 / sv);
    let centre = (lo + hi) * 0.5;
    let stem = "world_snapshot";
    let path = crate::names::join_inside(dir, &format!("{stem}.png")).map_err(|m| ReportError {
        path: dir.display().to_string(),
        message: m,
    })?;
    let fail = |m: String| ReportError {
        path: path.display().to_string(),
        message: m,
    };
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    register_fonts();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&BACKGROUND).map_err(|e| fail(format!("{e:?}")))?;
        let title = format!(
            "the world at t = {:.2} s from above ({}): {} robots with link transforms in the log",
            m.t_s(),
            if x_up {
                "x up, y to the left"
            } else {
                "x to the right, y up"
            },
            poses.len()
        );
        root.draw(&Text::new(title, (8, 8), (FONT, 18).into_font()))
            .map_err(|e| fail(format!("{e:?}")))?;
        let project = |p: DVec3| -> (i32, i32) {
            let d = p - centre;
            let (u, v) = if x_up { (-d.y, d.x) } else { (d.x, d.y) };
            (
                (w / 2) as i32 + (u * scale).round() as i32,
                ((h + TITLE_H) / 2) as i32 - (v * scale).round() as i32,
            )
        };
        for p in &poses {
            for &(a, b) in &p.boxes {
                root.draw(&PathElement::new(
                    vec![project(a), project(b)],
                    BODY.stroke_width(1),
                ))
                .map_err(|e| fail(format!("{e:?}")))?;
            }
            for &(a, b) in &p.segments {
                root.draw(&PathElement::new(
                    vec![project(a), project(b)],
                    LINK.stroke_width(2),
                ))
                .map_err(|e| fail(format!("{e:?}")))?;
            }
            // every robot visible however small the scale
            root.draw(&Circle::new(project(p.base), 3, STANCE.filled()))
                .map_err(|e| fail(format!("{e:?}")))?;
        }
        root.present().map_err(|e| fail(format!("{e:?}")))?;
    }
    write_png(&path, &rgb, (w, h))?;
    let caption = format!(
        "The world at t = {:.2} s from above: the {} robots with link transforms in the log",
        m.t_s(),
        poses.len()
    );
    Ok(Some(((caption, format!("{stem}.png")), path)))
}

/// The report's "Motion" section: each picture under its caption. A herd's
/// report (`herd`: [`super::markdown::HERD_MIN_ROBOTS`] robots or more)
/// draws the filmstrips of the robots it details, its worst ones.
pub fn markdown(pictures: &[Picture], robots_total: usize, drawn: usize, herd: bool) -> String {
    let mut out = String::from("\n## Motion\n\n");
    if pictures.is_empty() {
        out.push_str("None: the log has no link transforms (`/tf`) to draw.\n");
        return out;
    }
    out.push_str(
        "Drawn from the log: link frames (`/tf`), boxes (`/scene`) and foot contacts (`/<robot>/feet`).",
    );
    if herd {
        out.push_str(&format!(
            " Filmstrips of {drawn} of {robots_total} robots: the worst ones logged, in the order of the detail below."
        ));
    } else if robots_total > drawn {
        out.push_str(&format!(
            " Filmstrips of the first {drawn} of {robots_total} robots."
        ));
    }
    out.push_str("\n\n");
    for (caption, file) in pictures {
        let alt = file.trim_end_matches(".png");
        out.push_str(&format!("{caption}\n\n![{alt}](plots/{file})\n\n"));
    }
    out
}
