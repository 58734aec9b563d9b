//! `quadsim monitor`'s dashboard drawn on ratatui's in-memory `TestBackend`
//! from known frames (no terminal, no running world): the numbers shown are
//! the frames' speed, height, attitude and contacts; the speed sparkline
//! follows the history on a fixed simulated-time scale; `--robot` focuses one.

use quadsim::cli::dashboard::{
    Dashboard, ROW_SPARK_CHARS, SPARK_DT_S, buffer_text, text_sparkline,
};
use quadsim::monitor::RobotFrame;
use ratatui::Terminal;
use ratatui::backend::TestBackend;

/// A frame of robot `index` at `tick` (dt = 0.5 ms), moving at `vx, vy`.
fn frame(index: u32, tick: u64, vx: f64, vy: f64) -> RobotFrame {
    RobotFrame {
        robot_index: index,
        tick,
        time_s: tick as f64 * 0.0005,
        n_dof: 16,
        n_feet: 4,
        contact_flags: 0b1001,
        base_position_m: [1.0, 2.0, 0.5127],
        base_linear_mps: [vx, vy, 0.01],
        rpy_rad: [0.1, -0.05, 1.0],
        com_m: [1.01, 2.02, 0.4321],
        foot_force_n: [
            [0.0, 0.0, 101.5],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 98.3],
        ],
        ..RobotFrame::default()
    }
}

fn draw(board: &Dashboard, w: u16, h: u16) -> String {
    let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
    term.draw(|f| board.draw(f)).unwrap();
    buffer_text(term.backend().buffer())
}

fn line_of<'a>(text: &'a str, name: &str) -> &'a str {
    text.lines()
        .find(|l| l.contains(name))
        .unwrap_or_else(|| panic!("no line for {name} in\n{text}"))
}

#[test]
fn the_list_shows_each_robots_values_from_its_frame() {
    let mut board = Dashboard::new("w-1", vec!["rex".into(), "max".into()], None);
    // before any frame: dashes
    assert!(line_of(&draw(&board, 110, 12), "rex").contains(" - "));
    // rex at (0.3, 0.4) m/s: 0.5 m/s horizontal; max standing still; a frame
    // of an index the header does not list is ignored
    board.update(&[
        frame(0, 400, 0.3, 0.4),
        frame(1, 400, 0.0, 0.0),
        frame(7, 400, 9.0, 0.0),
    ]);
    let text = draw(&board, 110, 12);
    assert!(text.contains("world w-1"), "{text}");
    assert!(
        text.contains("tick 400") && text.contains("t = 0.200 s"),
        "{text}"
    );
    let rex = line_of(&text, "rex");
    for want in ["0.500", "0.5127", "+5.7 -2.9 +57.3", "●○○●"] {
        assert!(rex.contains(want), "'{want}' missing in: {rex}");
    }
    let max = line_of(&text, "max");
    assert!(max.contains("0.000"), "{max}");
    assert!(!text.contains("9.000"), "{text}");
}

#[test]
fn the_speed_sparkline_follows_the_history_in_simulated_time() {
    let mut board = Dashboard::new("w", vec!["rex".into()], None);
    // an instant every 10 ms of simulated time (20 steps), speed rising
    // 0.01 m/s per instant: a sparkline point every 50 ms takes every 5th
    let mut points = Vec::new();
    for k in 0..200u64 {
        let v = 0.01 * k as f64;
        let f = frame(0, 20 * k, v, 0.0);
        if k % 5 == 0 {
            points.push(v);
        }
        board.update(&[f]);
    }
    assert!((SPARK_DT_S - 0.05).abs() < 1e-12);
    assert_eq!(board.instants, 200);
    let text = draw(&board, 110, 8);
    let rex = line_of(&text, "rex");
    // the row ends with the last ROW_SPARK_CHARS points scaled to the largest
    let want = text_sparkline(points.iter().copied(), ROW_SPARK_CHARS, 1.95);
    assert!(rex.contains(&format!(" {want}")), "{rex}\nwant …{want}");
    // a rising speed draws a rising line that ends at the top level
    let levels: Vec<char> = want.chars().collect();
    assert!(levels.windows(2).all(|w| w[0] <= w[1]), "{want}");
    assert_eq!(*levels.last().unwrap(), '█');
    assert_eq!(text_sparkline([0.0, 0.5, 1.0].into_iter(), 3, 1.0), "▁▅█");
    assert_eq!(text_sparkline([f64::NAN, 2.0].into_iter(), 5, 1.0), " █");
}

#[test]
fn focusing_a_robot_shows_its_details_and_a_full_width_sparkline() {
    let names = vec!["rex".into(), "max".into()];
    let mut board = Dashboard::new("w", names, Some(1));
    for k in 0..50u64 {
        board.update(&[frame(0, 100 * k, 0.6, 0.8), frame(1, 100 * k, 0.3, 0.4)]);
    }
    let text = draw(&board, 100, 24);
    assert!(text.contains(" max "), "{text}");
    assert!(!text.contains("rex"), "{text}");
    assert!(text.contains("speed      0.500 m/s"), "{text}");
    assert!(text.contains("height     0.5127 m"), "{text}");
    assert!(text.contains("attitude   +5.7 -2.9 +57.3"), "{text}");
    assert!(text.contains("contacts   ●○○●"), "{text}");
    assert!(text.contains("CoM        1.010 2.020 0.432 m"), "{text}");
    assert!(text.contains("foot Fz    101.5 0.0 0.0 98.3 N"), "{text}");
    // 50 instants 50 ms apart: 50 points of a constant speed, 2.5 s
    assert!(text.contains("last 2.5 s"), "{text}");
    assert!(text.contains(&"█".repeat(50)), "{text}");
    // Backspace returns to the list; ↓ selects the next row
    board.focus = None;
    board.scroll(1);
    assert_eq!(board.selected, 1);
    board.scroll(5);
    assert_eq!(board.selected, 1);
    assert!(draw(&board, 110, 8).contains("rex"));
}
