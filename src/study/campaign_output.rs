//! A campaign's files: `campaign.json`, `campaign.csv`, `campaign.md` and
//! `plots/campaign_speed.svg|png` (`docs/campaign.md`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::campaign::{CampaignReport, CopyResult};

/// The files written, in the order written.
pub const FILES: [&str; 5] = [
    "campaign.json",
    "campaign.csv",
    "campaign.md",
    "plots/campaign_speed.svg",
    "plots/campaign_speed.png",
];

/// Bin of the speed curves in the plot (s): the mean speed over each bin
/// (the CoM's displacement along the start heading over the bin).
pub const PLOT_BIN_S: f64 = 0.25;

fn io(path: &Path, e: impl std::fmt::Display) -> String {
    format!("{}: {e}", path.display())
}

/// Writes every file into `dir` (created if needed; nothing outside it).
pub fn write_all(dir: &Path, report: &CampaignReport) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(dir.join("plots")).map_err(|e| io(dir, e))?;
    let json = dir.join("campaign.json");
    let text = serde_json::to_string_pretty(report).map_err(|e| io(&json, e))?;
    std::fs::write(&json, text + "\n").map_err(|e| io(&json, e))?;
    let csv = dir.join("campaign.csv");
    std::fs::write(&csv, csv_text(report)).map_err(|e| io(&csv, e))?;
    let md = dir.join("campaign.md");
    std::fs::write(&md, markdown(report)).map_err(|e| io(&md, e))?;
    let [svg, png] = write_plot(&dir.join("plots"), report)?;
    Ok(vec![json, csv, md, svg, png])
}

fn opt(x: Option<f64>) -> String {
    x.map_or(String::new(), |x| format!("{x}"))
}

/// `campaign.csv`: one row per copy, its draws then its metrics.
pub fn csv_text(r: &CampaignReport) -> String {
    let links: Vec<String> = r
        .runs
        .first()
        .map(|c| c.draws.link_mass_scale.keys().cloned().collect())
        .unwrap_or_default();
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> = [
        "copy",
        "status",
        "error",
        "fell",
        "fell_at_s",
        "mean_speed_mps",
        "commanded_speed_mps",
        "speed_error_mps",
        "max_abs_roll_rad",
        "max_abs_pitch_rad",
        "height_p2p_m",
        "peak_foot_force_n",
        "simulated_s",
        "total_mass_kg",
        "world_seed",
        "start_dx_m",
        "start_dy_m",
        "start_dyaw_deg",
        "friction",
        "noise_scale",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    head.extend(links.iter().map(|l| format!("mass_scale.{l}")));
    w.write_record(&head).expect("in memory");
    for c in &r.runs {
        let d = &c.draws;
        let m = c.metrics.as_ref();
        let status = match (m, &c.error) {
            (Some(m), _) if m.fell => "fell",
            (Some(_), _) => "held",
            _ => "failed",
        };
        let mut row = vec![
            c.copy.to_string(),
            status.to_string(),
            c.error.clone().unwrap_or_default(),
            m.map_or(String::new(), |m| m.fell.to_string()),
            opt(m.and_then(|m| m.fell_at_s)),
            opt(m.and_then(|m| m.mean_speed_mps)),
            opt(m.and_then(|m| m.commanded_speed_mps)),
            opt(m.and_then(|m| m.speed_error_mps)),
            opt(m.map(|m| m.max_abs_roll_rad)),
            opt(m.map(|m| m.max_abs_pitch_rad)),
            opt(m.and_then(|m| m.height_p2p_m)),
            opt(m.map(|m| m.peak_foot_force_n)),
            opt(m.map(|m| m.simulated_s)),
            opt(m.map(|m| m.total_mass_kg)),
            d.world_seed.to_string(),
            d.start_dx_m.to_string(),
            d.start_dy_m.to_string(),
            d.start_dyaw_deg.to_string(),
            opt(d.friction),
            d.noise_scale.to_string(),
        ];
        row.extend(links.iter().map(|l| opt(d.link_mass_scale.get(l).copied())));
        w.write_record(&row).expect("in memory");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("utf-8")
}

fn f(x: Option<f64>, digits: usize) -> String {
    x.map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// The command column: `v_x` (and the lateral and yaw commands when set).
pub fn command_text(r: &CampaignReport) -> String {
    match r.command {
        None => "–".into(),
        Some(c) => {
            let mut s = format!("{:.2} m/s", c.v_x_mps);
            if c.v_y_mps != 0.0 {
                let _ = write!(s, ", v_y {:.2} m/s", c.v_y_mps);
            }
            if c.yaw_rate_radps != 0.0 {
                let _ = write!(s, ", yaw {:.2} rad/s", c.yaw_rate_radps);
            }
            s
        }
    }
}

/// The table row of the campaign (`docs/validation.md`'s columns).
pub fn table_row(r: &CampaignReport) -> String {
    let a = &r.aggregates;
    let [lo, hi] = a.fall_rate_wilson_95;
    let att = match (a.worst_abs_roll_rad, a.worst_abs_pitch_rad) {
        (Some(x), Some(y)) => format!("{x:.3} / {y:.3}"),
        _ => "–".into(),
    };
    format!(
        "| {} | {} | {} | {}{} ({:.0}–{:.0} %) | {} ({} – {}) | {} | {} | {} | {} |",
        command_text(r),
        r.case,
        a.copies,
        a.falls,
        if a.failed > 0 {
            format!(" + {} failed", a.failed)
        } else {
            String::new()
        },
        100.0 * lo,
        100.0 * hi,
        f(a.mean_speed_mps, 3),
        f(a.min_speed_mps, 3),
        f(a.max_speed_mps, 3),
        f(a.max_abs_speed_error_mps, 3),
        att,
        f(a.worst_height_p2p_m.map(|x| 1000.0 * x), 1),
        f(a.worst_peak_foot_force_n, 0),
    )
}

/// The table's header (with [`table_row`]).
pub const TABLE_HEADER: &str = "| command | case | N | falls (95 % CI of the rate) | mean speed, m/s (min – max) | max \\|speed error\\|, m/s | max \\|roll\\| / \\|pitch\\|, rad | torso height p2p, mm | peak foot force, N |\n|---|---|---|---|---|---|---|---|---|";

/// `campaign.md`.
pub fn markdown(r: &CampaignReport) -> String {
    let mut s = String::new();
    let p = &r.perturbations;
    let _ = writeln!(s, "# Campaign: {}\n", r.case);
    let _ = writeln!(
        s,
        "Scenario `{}` (robot `{}`, {:.2} kg nominal), {} copies of {} s, campaign seed {}. \
         Speed over {} s to the end; torso height peak-to-peak from {} s; speed, attitude, \
         height and force figures over the {} copies that held.\n",
        r.scenario.path,
        r.scenario.robot,
        r.scenario.nominal_mass_kg,
        r.n,
        r.scenario.duration_s,
        r.seed,
        r.windows.steady_state_from_s,
        r.windows.height_from_s,
        r.aggregates.held,
    );
    let _ = writeln!(s, "{TABLE_HEADER}\n{}\n", table_row(r));
    let _ = writeln!(s, "Perturbations (uniform draws per copy):\n");
    let onoff = |on: bool, txt: String| if on { txt } else { "off".into() };
    let _ = writeln!(
        s,
        "- start offset: x and y each in ±{} m, yaw in ±{}°",
        p.start_xy_m, p.start_yaw_deg
    );
    let _ = writeln!(
        s,
        "- world seed: {}",
        onoff(
            p.world_seed,
            "a draw per copy (sensor noise, random terrain)".into()
        )
    );
    let _ = writeln!(
        s,
        "- link masses: {}",
        onoff(
            p.link_mass_frac > 0.0,
            format!(
                "each link × [{}, {}], inertia with it; the controller keeps the nominal model",
                1.0 - p.link_mass_frac,
                1.0 + p.link_mass_frac
            )
        )
    );
    let _ = writeln!(
        s,
        "- ground friction: {}",
        p.friction
            .map_or("the scenario's".into(), |[lo, hi]| format!(
                "μ in [{lo}, {hi}] for every ground"
            ))
    );
    let _ = writeln!(
        s,
        "- sensor noise: × [{}, {}]\n",
        p.noise_scale[0], p.noise_scale[1]
    );
    let _ = writeln!(
        s,
        "![speed of every copy](plots/campaign_speed.svg)\n\n## Copies\n"
    );
    let _ = writeln!(
        s,
        "| copy | outcome | mean speed, m/s | speed error, m/s | max \\|roll\\|, rad | max \\|pitch\\|, rad | height p2p, mm | peak foot force, N | mass, kg | μ | Δx, Δy, mm | Δyaw, ° | seed |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for c in &r.runs {
        let d = &c.draws;
        let outcome = match (&c.metrics, &c.error) {
            (Some(m), _) if m.fell => format!("fell at {:.2} s", m.fell_at_s.unwrap_or(0.0)),
            (Some(_), _) => "held".into(),
            (None, e) => format!("failed: {}", e.as_deref().unwrap_or("")),
        };
        let m = c.metrics.as_ref();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1}, {:.1} | {:.2} | {} |",
            c.copy,
            outcome,
            f(m.and_then(|m| m.mean_speed_mps), 3),
            f(m.and_then(|m| m.speed_error_mps), 3),
            f(m.map(|m| m.max_abs_roll_rad), 3),
            f(m.map(|m| m.max_abs_pitch_rad), 3),
            f(m.and_then(|m| m.height_p2p_m).map(|x| 1000.0 * x), 1),
            f(m.map(|m| m.peak_foot_force_n), 0),
            f(m.map(|m| m.total_mass_kg), 2),
            f(d.friction, 3),
            1000.0 * d.start_dx_m,
            1000.0 * d.start_dy_m,
            d.start_dyaw_deg,
            d.world_seed,
        );
    }
    s
}

/// Mean rate of change over consecutive bins of [`PLOT_BIN_S`] from a
/// `(t, x)` trace (a speed from positions or distances).
pub fn binned_speed(trace: impl IntoIterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut it = trace.into_iter();
    let Some((mut t0, mut x0)) = it.next() else {
        return out;
    };
    for (t, x) in it {
        if t - t0 >= PLOT_BIN_S - 1e-9 {
            out.push((0.5 * (t0 + t), (x - x0) / (t - t0)));
            (t0, x0) = (t, x);
        }
    }
    out
}

const FONT: &str = "sans-serif";

fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            plotters::style::register_font(FONT, style, notosans::REGULAR_TTF)
                .unwrap_or_else(|_| panic!("bundled Noto Sans does not parse"));
        }
    });
}

const HELD: RGBColor = RGBColor(31, 119, 180);
const FELL: RGBColor = RGBColor(214, 39, 40);

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    r: &CampaignReport,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{e:?}");
    root.fill(&WHITE).map_err(e)?;
    let (top, bottom) = root.split_vertically(470);
    // speed over time
    let curves: Vec<(&CopyResult, Vec<(f64, f64)>)> = r
        .runs
        .iter()
        .map(|c| (c, binned_speed(c.trace.iter().map(|p| (p.0, p.1)))))
        .collect();
    // the command as ramped, from the copy that ran longest
    let command: Vec<(f64, f64)> = if r.command.is_some() {
        r.runs
            .iter()
            .max_by_key(|c| c.trace.len())
            .map(|c| binned_speed(c.trace.iter().map(|p| (p.0, p.2))))
            .unwrap_or_default()
    } else {
        Vec::new()
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (_, pts) in &curves {
        for &(_, v) in pts {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    for &(_, v) in &command {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(0.05);
    let t_end = r.scenario.duration_s;
    let mut chart = ChartBuilder::on(&top)
        .caption(
            format!(
                "{}: forward speed of {} copies ({} fell, red; {} s bins)",
                r.case, r.aggregates.copies, r.aggregates.falls, PLOT_BIN_S
            ),
            (FONT, 16),
        )
        .margin(8)
        .x_label_area_size(34)
        .y_label_area_size(58)
        .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("CoM speed along the start heading (m/s)")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(e)?;
    let w = r.windows.steady_state_from_s;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(w, lo - pad), (t_end, hi + pad)],
            RGBColor(120, 120, 120).mix(0.12).filled(),
        )))
        .map_err(e)?
        .label("steady-state window")
        .legend(|(x, y)| {
            Rectangle::new(
                [(x, y - 5), (x + 16, y + 5)],
                RGBColor(120, 120, 120).mix(0.3).filled(),
            )
        });
    // held copies first, fallen ones on top
    for fallen in [false, true] {
        let mut labelled = false;
        for (c, pts) in &curves {
            let fell = c.metrics.as_ref().is_some_and(|m| m.fell);
            if fell != fallen || pts.is_empty() {
                continue;
            }
            let col = if fell { FELL } else { HELD };
            let a = chart
                .draw_series(LineSeries::new(
                    pts.iter().copied(),
                    col.mix(if fell { 0.9 } else { 0.45 }).stroke_width(1),
                ))
                .map_err(e)?;
            if !labelled {
                labelled = true;
                a.label(if fell { "fell" } else { "held" })
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], col.stroke_width(2))
                    });
            }
            let at = c.metrics.as_ref().and_then(|m| m.fell_at_s);
            if let (Some(&(_, v)), Some(t)) = (pts.last(), at) {
                chart
                    .draw_series(std::iter::once(Cross::new((t, v), 5, FELL.stroke_width(2))))
                    .map_err(e)?;
            }
        }
    }
    if !command.is_empty() {
        chart
            .draw_series(DashedLineSeries::new(
                command.iter().copied(),
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(e)?
            .label("command (as ramped)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(1)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font((FONT, 13))
        .draw()
        .map_err(e)?;

    // histogram of the held copies' steady-state speeds
    let speeds: Vec<f64> = r
        .runs
        .iter()
        .filter_map(|c| c.metrics.as_ref().and_then(|m| m.mean_speed_mps))
        .collect();
    let (mut s0, mut s1) = speeds
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !s0.is_finite() {
        (s0, s1) = (0.0, 1.0);
    }
    if s1 - s0 < 1e-3 {
        (s0, s1) = (s0 - 0.01, s1 + 0.01);
    }
    let bins = 20usize;
    let width = (s1 - s0) / bins as f64;
    let mut counts = vec![0u32; bins];
    for v in &speeds {
        counts[(((v - s0) / width) as usize).min(bins - 1)] += 1;
    }
    let top_count = counts.iter().copied().max().unwrap_or(1).max(1);
    let mut hist = ChartBuilder::on(&bottom)
        .caption(
            format!(
                "steady-state mean speed of the {} copies that held",
                speeds.len()
            ),
            (FONT, 15),
        )
        .margin(8)
        .x_label_area_size(34)
        .y_label_area_size(58)
        .build_cartesian_2d(s0..s1, 0u32..top_count + 1)
        .map_err(e)?;
    hist.configure_mesh()
        .x_desc("mean speed (m/s)")
        .y_desc("copies")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(e)?;
    hist.draw_series(
        counts
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(i, &n)| {
                let x0 = s0 + i as f64 * width;
                Rectangle::new([(x0, 0), (x0 + width, n)], HELD.mix(0.7).filled())
            }),
    )
    .map_err(e)?;
    root.present().map_err(e)
}

/// Draws the plot as `dir/campaign_speed.svg` and `.png`.
pub fn write_plot(dir: &Path, r: &CampaignReport) -> Result<[PathBuf; 2], String> {
    register_fonts();
    let (w, h) = (900u32, 760u32);
    let svg_path = dir.join("campaign_speed.svg");
    let png_path = dir.join("campaign_speed.png");
    let mut svg = String::new();
    draw(
        SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
        r,
    )
    .map_err(|m| io(&svg_path, m))?;
    std::fs::write(&svg_path, svg).map_err(|e| io(&svg_path, e))?;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area(),
        r,
    )
    .map_err(|m| io(&png_path, m))?;
    let file = std::fs::File::create(&png_path).map_err(|e| io(&png_path, e))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    enc.write_header()
        .and_then(|mut wr| wr.write_image_data(&rgb))
        .map_err(|e| io(&png_path, e))?;
    Ok([svg_path, png_path])
}
