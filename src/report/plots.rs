//! The report's plots, drawn with `plotters` as SVG and PNG from a robot's
//! logged series. Text uses the bundled Noto Sans (SIL Open Font License, the
//! `notosans` crate) through plotters' `ab_glyph` feature: no system fonts.
//!
//! Each plot is first described as a [`Figure`] (panels of lines, shaded
//! spans and polygons), then drawn by one renderer on either backend, so the
//! SVG and the PNG show the same thing.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::input::ReportError;
use super::series::RobotSeries;

/// Plot size in pixels (PNG) and SVG user units.
pub const PLOT_SIZE: (u32, u32) = (900, 620);
/// Largest number of points drawn per line: longer series are decimated by a
/// whole stride (the PNG would not show more, and it keeps drawing cheap).
pub const MAX_POINTS: usize = 1500;

/// The bundled font's family name.
pub(crate) const FONT: &str = "sans-serif";

/// Registers the bundled font once (plotters looks fonts up by family name).
pub(crate) fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            // The font is valid TrueType shipped in the crate: failure is a build defect.
            plotters::style::register_font(FONT, style, notosans::REGULAR_TTF)
                .unwrap_or_else(|_| panic!("bundled Noto Sans does not parse"));
        }
    });
}

/// A line of a panel.
#[derive(Debug, Clone)]
pub struct Line {
    /// Legend label.
    pub label: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
    /// Drawn dashed (e.g. a target or a desired value).
    pub dashed: bool,
}

/// One chart of a figure.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Caption.
    pub title: String,
    /// x axis label with unit.
    pub x_label: String,
    /// y axis label with unit.
    pub y_label: String,
    /// Lines.
    pub lines: Vec<Line>,
    /// Shaded x intervals (e.g. stance) with their legend label.
    pub spans: Vec<(f64, f64)>,
    /// Label of the shaded spans.
    pub span_label: Option<String>,
    /// Filled polygons (e.g. a support polygon) with a label each.
    pub polygons: Vec<(String, Vec<(f64, f64)>)>,
    /// Marked points with a label each.
    pub markers: Vec<(String, (f64, f64))>,
    /// Same scale on both axes (top views).
    pub equal_axes: bool,
    /// Unlabelled points (x, y), drawn as small dots (sweeps: one per run).
    pub scatter: Vec<(f64, f64)>,
}

/// A plot: panels stacked in a grid of `columns`.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem (`<robot>_<what>`).
    pub stem: String,
    /// Panels, row by row.
    pub panels: Vec<Panel>,
    /// Grid columns.
    pub columns: usize,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn decimate<T: Copy>(v: &[T]) -> impl Iterator<Item = T> + '_ {
    let stride = v.len().div_ceil(MAX_POINTS).max(1);
    v.iter().step_by(stride).copied()
}

/// Axis range of values, padded by 5 % (and widened when flat).
fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05)
        .max(1e-3 * hi.abs().max(lo.abs()))
        .max(1e-6);
    (lo - pad, hi + pad)
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{e:?}");
    let xs = p
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|q| q.0))
        .chain(p.polygons.iter().flat_map(|(_, q)| q.iter().map(|q| q.0)))
        .chain(p.markers.iter().map(|m| m.1.0))
        .chain(p.scatter.iter().map(|q| q.0));
    let ys = p
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|q| q.1))
        .chain(p.polygons.iter().flat_map(|(_, q)| q.iter().map(|q| q.1)))
        .chain(p.markers.iter().map(|m| m.1.1))
        .chain(p.scatter.iter().map(|q| q.1));
    let (mut x0, mut x1) = range(xs);
    let (mut y0, mut y1) = range(ys);
    if p.equal_axes {
        let (w, h) = area.dim_in_pixel();
        let (pw, ph) = ((w as f64 - 70.0).max(1.0), (h as f64 - 70.0).max(1.0));
        let scale = ((x1 - x0) / pw).max((y1 - y0) / ph);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        (x0, x1) = (cx - 0.5 * scale * pw, cx + 0.5 * scale * pw);
        (y0, y1) = (cy - 0.5 * scale * ph, cy + 0.5 * scale * ph);
    }
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FONT, 16))
        .margin(6)
        .x_label_area_size(34)
        .y_label_area_size(58)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    let shade = RGBColor(120, 120, 120).mix(0.18);
    if !p.spans.is_empty() {
        let a = chart
            .draw_series(
                p.spans
                    .iter()
                    .map(|&(a, b)| Rectangle::new([(a, y0), (b, y1)], shade.filled())),
            )
            .map_err(err)?;
        if let Some(l) = &p.span_label {
            a.label(l.clone()).legend(move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 16, y + 5)], shade.filled())
            });
        }
    }
    for (k, (label, poly)) in p.polygons.iter().enumerate() {
        let c = PALETTE[(k + 2) % PALETTE.len()];
        chart
            .draw_series(std::iter::once(Polygon::new(
                poly.clone(),
                c.mix(0.25).filled(),
            )))
            .map_err(err)?
            .label(label.clone())
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 16, y + 5)], c.mix(0.25).filled())
            });
        let mut closed = poly.clone();
        if let Some(&first) = poly.first() {
            closed.push(first);
        }
        chart
            .draw_series(std::iter::once(PathElement::new(closed, c.stroke_width(2))))
            .map_err(err)?;
    }
    for (k, l) in p.lines.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let style = c.stroke_width(1);
        // a gap (non-finite value) splits the line into pieces
        let mut pieces: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for q in decimate(&l.points) {
            if q.0.is_finite() && q.1.is_finite() {
                pieces.last_mut().expect("one piece").push(q);
            } else if !pieces.last().expect("one piece").is_empty() {
                pieces.push(Vec::new());
            }
        }
        for (i, pts) in pieces.into_iter().enumerate() {
            let a = if l.dashed {
                chart
                    .draw_series(DashedLineSeries::new(pts, 6, 4, style))
                    .map_err(err)?
            } else {
                chart
                    .draw_series(LineSeries::new(pts, style))
                    .map_err(err)?
            };
            if i == 0 {
                a.label(l.label.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                });
            }
        }
    }
    if !p.scatter.is_empty() {
        let c = PALETTE[0];
        chart
            .draw_series(p.scatter.iter().map(|q| Circle::new(*q, 3, c.filled())))
            .map_err(err)?;
    }
    for (k, (label, pt)) in p.markers.iter().enumerate() {
        let c = if k == 0 {
            RGBColor(0, 0, 0)
        } else {
            PALETTE[k % PALETTE.len()]
        };
        chart
            .draw_series(std::iter::once(Circle::new(*pt, 5, c.filled())))
            .map_err(err)?
            .label(label.clone())
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, c.filled()));
    }
    if !(p.lines.is_empty() && p.polygons.is_empty() && p.markers.is_empty()) {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .label_font((FONT, 14))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, f: &Figure) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| format!("{e:?}"))?;
    let cols = f.columns.max(1);
    let rows = f.panels.len().div_ceil(cols).max(1);
    let areas = root.split_evenly((rows, cols));
    for (area, p) in areas.iter().zip(&f.panels) {
        draw_panel(area, p)?;
    }
    root.present().map_err(|e| format!("{e:?}"))
}

/// Draws `f` as `dir/<stem>.svg` and `dir/<stem>.png`; returns both paths.
pub fn write_figure(f: &Figure, dir: &Path) -> Result<[PathBuf; 2], ReportError> {
    register_fonts();
    let (w, h) = PLOT_SIZE;
    let fail = |p: &Path, m: String| ReportError {
        path: p.display().to_string(),
        message: m,
    };
    // the stem holds a robot's name: made safe, and the files checked to
    // lie in `dir` (crate::names)
    let stem = crate::names::safe_file_stem(&f.stem);
    let inside = |ext: &str| {
        crate::names::join_inside(dir, &format!("{stem}.{ext}")).map_err(|m| fail(dir, m))
    };
    let (svg_path, png_path) = (inside("svg")?, inside("png")?);
    let mut svg = String::new();
    draw_figure(
        SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
        f,
    )
    .map_err(|m| fail(&svg_path, m))?;
    std::fs::write(&svg_path, svg).map_err(|e| fail(&svg_path, e.to_string()))?;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    draw_figure(
        BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area(),
        f,
    )
    .map_err(|m| fail(&png_path, m))?;
    let file = std::fs::File::create(&png_path).map_err(|e| fail(&png_path, e.to_string()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    enc.write_header()
        .and_then(|mut wr| wr.write_image_data(&rgb))
        .map_err(|e| fail(&png_path, e.to_string()))?;
    Ok([svg_path, png_path])
}

fn line(label: impl Into<String>, t: &[f64], y: impl Iterator<Item = f64>) -> Line {
    Line {
        label: label.into(),
        points: t.iter().copied().zip(y).collect(),
        dashed: false,
    }
}

fn panel(title: impl Into<String>, x: &str, y: &str, lines: Vec<Line>) -> Panel {
    Panel {
        title: title.into(),
        x_label: x.into(),
        y_label: y.into(),
        lines,
        ..Default::default()
    }
}

/// Intervals of `t` where `flag` holds (from a sample to the next).
fn spans(t: &[f64], flag: impl Iterator<Item = bool>) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut start: Option<f64> = None;
    let mut last = 0.0;
    for (k, f) in flag.enumerate() {
        let tk = t[k];
        match (f, start) {
            (true, None) => start = Some(tk),
            (false, Some(s)) => {
                out.push((s, tk));
                start = None;
            }
            _ => {}
        }
        last = tk;
    }
    if let Some(s) = start {
        out.push((s, last));
    }
    out
}

/// What the report needs beside the series to draw a robot's plots.
#[derive(Debug, Clone)]
pub struct PlotContext {
    /// The commanded forward speed over time, `(t_s, v_mps)` steps (empty: none).
    pub speed_target: Vec<(f64, f64)>,
    /// End of the run (s).
    pub end_s: f64,
}

/// The figures of one robot, in report order, with a caption each.
pub fn robot_figures(s: &RobotSeries, ctx: &PlotContext) -> Vec<(String, Figure)> {
    let n = &s.name;
    let time = "t (s)";
    let mut out = Vec::new();
    let axes = ["x", "y", "z"];
    out.push((
        "CoM position".to_string(),
        Figure {
            stem: format!("{n}_com"),
            columns: 1,
            panels: (0..3)
                .map(|a| {
                    panel(
                        format!("CoM {} (world)", axes[a]),
                        time,
                        &format!("{} (m)", axes[a]),
                        vec![line(
                            format!("CoM {}", axes[a]),
                            &s.com_t_s,
                            s.com_m.iter().map(|p| p[a]),
                        )],
                    )
                })
                .collect(),
        },
    ));
    // forward speed along the start heading (the metric's projection)
    let yaw0 = s.rpy_rad.first().map_or(0.0, |r| r[2]);
    let (c, sn) = (yaw0.cos(), yaw0.sin());
    let mut speed = panel(
        "Forward CoM speed (along the start heading) and its command",
        time,
        "v (m/s)",
        vec![line(
            "CoM forward speed",
            &s.com_t_s,
            s.com_velocity_mps.iter().map(|v| v[0] * c + v[1] * sn),
        )],
    );
    if !ctx.speed_target.is_empty() {
        let mut pts = Vec::new();
        for (k, &(t, v)) in ctx.speed_target.iter().enumerate() {
            if k > 0 {
                pts.push((t, ctx.speed_target[k - 1].1));
            }
            pts.push((t, v));
        }
        pts.push((ctx.end_s, ctx.speed_target.last().map_or(0.0, |p| p.1)));
        speed.lines.push(Line {
            label: "commanded v_x".into(),
            points: pts,
            dashed: true,
        });
    }
    out.push((
        "Forward speed against its target".to_string(),
        Figure {
            stem: format!("{n}_speed"),
            columns: 1,
            panels: vec![speed],
        },
    ));
    let rpy = ["roll", "pitch", "yaw"];
    out.push((
        "Roll, pitch and yaw".to_string(),
        Figure {
            stem: format!("{n}_attitude"),
            columns: 1,
            panels: vec![panel(
                "Base attitude (R = Rz(yaw) Ry(pitch) Rx(roll); yaw unwrapped)",
                time,
                "angle (rad)",
                (0..3)
                    .map(|a| line(rpy[a], &s.attitude_t_s, s.rpy_rad.iter().map(|r| r[a])))
                    .collect(),
            )],
        },
    ));
    let leg = s.first_leg_joints();
    let leg_name = s
        .foot_names
        .first()
        .and_then(|f| f.split_once('_'))
        .map_or("first leg".to_string(), |(p, _)| format!("leg {p}"));
    let panels: Vec<Panel> = leg
        .iter()
        .map(|&j| {
            let jn = s.joint_names.get(j).cloned().unwrap_or_default();
            let mut lines = vec![line(
                "actual",
                &s.joint_t_s,
                s.q_rad
                    .iter()
                    .map(|q| q.get(j).copied().unwrap_or(f64::NAN)),
            )];
            if s.q_desired_rad.iter().any(Option::is_some) {
                let mut l = line(
                    "desired",
                    &s.command_t_s,
                    s.q_desired_rad.iter().map(|q| {
                        q.as_ref()
                            .and_then(|q| q.get(j).copied())
                            .unwrap_or(f64::NAN)
                    }),
                );
                l.dashed = true;
                lines.push(l);
            }
            panel(jn, time, "angle (rad)", lines)
        })
        .collect();
    out.push((
        format!("Joint angles of {leg_name}, desired against actual"),
        Figure {
            stem: format!("{n}_joints"),
            columns: if panels.len() > 2 { 2 } else { 1 },
            panels,
        },
    ));
    // torques: one panel per leg
    let per_leg = leg.len().max(1);
    let nj = s.joint_names.len();
    let panels: Vec<Panel> = (0..nj.div_ceil(per_leg))
        .map(|l| {
            let js: Vec<usize> = (l * per_leg..((l + 1) * per_leg).min(nj)).collect();
            let title = s
                .foot_names
                .get(l)
                .map_or(format!("joints {}–{}", js[0], js[js.len() - 1]), |f| {
                    format!("{} leg", f.split_once('_').map_or(f.as_str(), |p| p.0))
                });
            panel(
                format!("Joint torques, {title}"),
                time,
                "τ (N·m)",
                js.iter()
                    .map(|&j| {
                        line(
                            s.joint_names[j].clone(),
                            &s.joint_t_s,
                            s.tau_nm
                                .iter()
                                .map(|t| t.get(j).copied().unwrap_or(f64::NAN)),
                        )
                    })
                    .collect(),
            )
        })
        .collect();
    out.push((
        "Joint torques (applied, after saturation)".to_string(),
        Figure {
            stem: format!("{n}_torques"),
            columns: if panels.len() > 2 { 2 } else { 1 },
            panels,
        },
    ));
    let panels: Vec<Panel> = s
        .foot_names
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut p = panel(
                format!("{f}: vertical ground force"),
                time,
                "f_z (N)",
                vec![line(
                    "f_z",
                    &s.feet_t_s,
                    s.feet
                        .iter()
                        .map(|x| x.get(i).map_or(f64::NAN, |x| x.force_n[2])),
                )],
            );
            p.spans = spans(
                &s.feet_t_s,
                s.feet
                    .iter()
                    .map(|x| x.get(i).is_some_and(|x| x.in_contact)),
            );
            p.span_label = Some("stance (in contact)".into());
            p
        })
        .collect();
    out.push((
        "Foot forces, stance shaded".to_string(),
        Figure {
            stem: format!("{n}_foot_forces"),
            columns: if panels.len() > 2 { 2 } else { 1 },
            panels,
        },
    ));
    let foot_line = |i: usize, a: usize, b: usize| Line {
        label: s.foot_names[i].clone(),
        points: s
            .feet
            .iter()
            .filter_map(|x| x.get(i).map(|x| (x.position_m[a], x.position_m[b])))
            .collect(),
        dashed: false,
    };
    out.push((
        "Foot trajectories".to_string(),
        Figure {
            stem: format!("{n}_foot_paths"),
            columns: 1,
            panels: vec![
                panel(
                    "Feet, side view (world x–z)",
                    "x (m)",
                    "z (m)",
                    (0..s.foot_names.len())
                        .map(|i| foot_line(i, 0, 2))
                        .collect(),
                ),
                Panel {
                    equal_axes: true,
                    ..panel(
                        "Feet, top view (world x–y)",
                        "x (m)",
                        "y (m)",
                        (0..s.foot_names.len())
                            .map(|i| foot_line(i, 0, 1))
                            .collect(),
                    )
                },
            ],
        },
    ));
    // support polygon at the logged sample of least margin, and the margin over time
    let margins = s.stability_margins();
    let mut margin_panel = panel(
        "Stability margin (≥ 3 feet in contact; logged samples)",
        time,
        "margin (m)",
        vec![Line {
            label: "margin".into(),
            points: s
                .feet_t_s
                .iter()
                .zip(&margins)
                .map(|(&t, m)| (t, m.unwrap_or(f64::NAN)))
                .collect(),
            dashed: false,
        }],
    );
    margin_panel.spans = spans(&s.feet_t_s, margins.iter().map(Option::is_none));
    margin_panel.span_label = Some("fewer than 3 feet down".into());
    let worst = margins
        .iter()
        .enumerate()
        .filter_map(|(k, m)| m.map(|m| (k, m)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let mut top = panel(
        "Support polygon at the least margin",
        "x (m)",
        "y (m)",
        vec![],
    );
    top.equal_axes = true;
    if let Some((k, m)) = worst {
        let pts: Vec<glam::DVec2> = s.feet[k]
            .iter()
            .filter(|f| f.in_contact)
            .map(|f| glam::DVec2::new(f.position_m[0], f.position_m[1]))
            .collect();
        let mut hull = [glam::DVec2::ZERO; 16];
        let nh = quadsim_engine::support::convex_hull(&pts, &mut hull);
        top.title = format!(
            "Support polygon at t = {:.3} s (margin {:.1} mm)",
            s.feet_t_s[k],
            m * 1e3
        );
        top.polygons.push((
            "support polygon".into(),
            hull[..nh].iter().map(|p| (p.x, p.y)).collect(),
        ));
        let com = s.com_m[k];
        top.markers
            .push(("CoM ground projection".into(), (com[0], com[1])));
    }
    out.push((
        "Support polygon and stability margin".to_string(),
        Figure {
            stem: format!("{n}_support"),
            columns: 2,
            panels: vec![margin_panel, top],
        },
    ));
    out
}
