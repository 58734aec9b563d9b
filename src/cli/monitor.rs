//! `quadsim monitor`: attach to a running world and show its robots live:
//! the ratatui dashboard ([`super::dashboard`]) on a terminal, plain lines
//! with `--frames N` or when the output is not a terminal (scripts, pipes).

use std::time::{Duration, Instant};

use clap::Args;

use crate::error::{CliError, bad};
use crate::monitor::{FrameReader, RobotFrame, list_worlds};

/// Arguments of `quadsim monitor`.
#[derive(Debug, Args)]
pub struct MonitorArgs {
    /// The world to attach to (default: the only running one).
    #[arg(long)]
    pub world: Option<String>,
    /// Only this robot (its scenario name): the dashboard focuses it.
    #[arg(long)]
    pub robot: Option<String>,
    /// Print this many instants as plain lines and exit (for scripts);
    /// without it, the live dashboard (or, when the output is not a
    /// terminal, plain lines until the world ends).
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Seconds to wait for the world to appear, and for each instant.
    #[arg(long, default_value_t = 10.0)]
    pub timeout: f64,
    /// List the running worlds and exit.
    #[arg(long)]
    pub list: bool,
    /// Serve the world live to Foxglove (WebSocket, the channels and
    /// schemas of log.mcap) instead of the dashboard; worlds that end are
    /// followed by the next without a restart.
    #[arg(long)]
    pub foxglove: bool,
    /// Port of `--foxglove`'s server (0: any free port, printed).
    #[arg(long, default_value_t = crate::foxglove_live::DEFAULT_PORT, requires = "foxglove")]
    pub port: u16,
    /// Address of `--foxglove`'s server (loopback unless you ask otherwise).
    #[arg(long, default_value = "127.0.0.1", requires = "foxglove")]
    pub host: String,
    /// Instants `--foxglove` forwards per second of simulated time, or
    /// `full` (every published instant).
    #[arg(long, value_name = "HZ|full", requires = "foxglove")]
    pub rate: Option<String>,
    /// With `--foxglove`: exit when the world ends.
    #[arg(long, requires = "foxglove")]
    pub once: bool,
}

/// `quadsim monitor --foxglove`: serves worlds until interrupted (or, with
/// `--once`, the first world's end).
fn foxglove(a: &MonitorArgs) -> Result<(), CliError> {
    let rate_hz = match a.rate.as_deref() {
        None => Some(crate::foxglove_live::DEFAULT_RATE_HZ),
        Some("full") => None,
        Some(r) => match r.parse::<f64>() {
            Ok(hz) if hz.is_finite() && hz > 0.0 => Some(hz),
            _ => {
                return Err(bad(format!(
                    "--rate: must be a rate > 0 (Hz) or `full`, got '{r}'"
                )));
            }
        },
    };
    let server = crate::foxglove_live::Server::start(&a.host, a.port)?;
    eprintln!(
        "foxglove: ws://{}:{} (Foxglove: Open connection… → Foxglove WebSocket; layout docs/foxglove_layout.json)",
        a.host, server.port
    );
    let opts = crate::foxglove_live::BridgeOptions {
        world: a.world.clone(),
        host: a.host.clone(),
        port: server.port,
        rate_hz,
        once: a.once,
    };
    let stop = std::sync::atomic::AtomicBool::new(false);
    let r = crate::foxglove_live::serve(&server, &opts, &stop);
    server.stop();
    r
}

fn monitor_error(e: crate::monitor::MonitorError) -> CliError {
    bad(e.to_string())
}

/// One plain line: robot, t, speed, height, attitude, contacts.
pub fn plain_line(name: &str, f: &RobotFrame) -> String {
    let contacts: String = (0..f.feet())
        .map(|i| if f.in_contact(i) { '1' } else { '0' })
        .collect();
    format!(
        "{name} tick={} t={:.4} speed={:.3} height={:.4} roll={:.2} pitch={:.2} yaw={:.2} contacts={}",
        f.tick,
        f.time_s,
        f.speed_mps(),
        f.base_position_m[2],
        f.rpy_rad[0].to_degrees(),
        f.rpy_rad[1].to_degrees(),
        f.rpy_rad[2].to_degrees(),
        if contacts.is_empty() { "-" } else { &contacts }
    )
}

/// Writes one line to stdout and flushes it; `Ok(false)` when stdout is
/// closed (a broken pipe, as after `| head -1`), where Unix tools stop
/// quietly, instead of `println!`'s panic.
pub fn print_line(line: &str) -> Result<bool, CliError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match writeln!(out, "{line}").and_then(|()| out.flush()) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(false),
        Err(e) => Err(CliError::Io {
            path: "stdout".into(),
            source: e,
        }),
    }
}

/// Runs `quadsim monitor`.
pub fn run(a: MonitorArgs) -> Result<(), CliError> {
    if !(a.timeout.is_finite() && a.timeout >= 0.0) {
        return Err(bad(format!(
            "--timeout: must be a finite time ≥ 0 (s), got {}",
            a.timeout
        )));
    }
    let timeout = Duration::from_secs_f64(a.timeout);
    if a.foxglove {
        return foxglove(&a);
    }
    if a.list {
        for w in list_worlds().map_err(monitor_error)? {
            if !print_line(&w)? {
                return Ok(());
            }
        }
        return Ok(());
    }
    let world = match &a.world {
        Some(w) => w.clone(),
        None => pick_world(timeout)?,
    };
    let mut reader = match FrameReader::open(&world).map_err(monitor_error)? {
        Some(r) => r,
        None => {
            eprintln!(
                "waiting up to {:.1} s for world '{world}' to start…",
                a.timeout
            );
            FrameReader::wait_open(&world, timeout).map_err(monitor_error)?
        }
    };
    let header = reader.wait_header(timeout).map_err(monitor_error)?;
    let names: Vec<String> = header["robots"]
        .as_array()
        .map(|r| {
            r.iter()
                .map(|x| x["name"].as_str().unwrap_or("?").to_string())
                .collect()
        })
        .unwrap_or_default();
    let only = match &a.robot {
        Some(r) => Some(names.iter().position(|n| n == r).ok_or_else(|| {
            bad(format!(
                "--robot: world '{world}' has no robot '{r}' (robots: {})",
                names.join(", ")
            ))
        })?),
        None => None,
    };
    if a.frames.is_none() && std::io::IsTerminal::is_terminal(&std::io::stdout()) {
        let mut board = super::dashboard::Dashboard::new(&world, names, only);
        let mut term = ratatui::try_init().map_err(|e| CliError::Io {
            path: "terminal".into(),
            source: e,
        })?;
        let res = live(&mut term, &mut reader, &mut board, timeout);
        ratatui::restore();
        return res;
    }
    let limit = a.frames.unwrap_or(u64::MAX);
    let mut printed = 0;
    while printed < limit {
        let Some(frames) = reader.next(timeout).map_err(monitor_error)? else {
            return Err(bad(format!(
                "world '{world}' sent nothing for {:.1} s (it ended?) after {printed} instants",
                a.timeout
            )));
        };
        for f in &frames {
            let i = f.robot_index as usize;
            if only.is_some_and(|o| o != i) {
                continue;
            }
            let name = names.get(i).map_or("?", String::as_str);
            if !print_line(&plain_line(name, f))? {
                // the reader went away (`| head -1`): a quiet, successful end
                return Ok(());
            }
        }
        printed += 1;
    }
    Ok(())
}

/// The dashboard's loop: drains the instants that arrived, redraws at most
/// 30 times a second, handles keys; fails when no instant came for `timeout`.
fn live<B: ratatui::backend::Backend>(
    term: &mut ratatui::Terminal<B>,
    reader: &mut FrameReader,
    board: &mut super::dashboard::Dashboard,
    timeout: Duration,
) -> Result<(), CliError>
where
    B::Error: Into<std::io::Error>,
{
    use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind};
    let io = |e: std::io::Error| CliError::Io {
        path: "terminal".into(),
        source: e,
    };
    let mut last_instant = Instant::now();
    loop {
        while let Some(frames) = reader.try_next().map_err(monitor_error)? {
            board.update(&frames);
            last_instant = Instant::now();
        }
        let quiet = last_instant.elapsed();
        if quiet >= timeout {
            return Err(bad(format!(
                "world '{}' sent nothing for {:.1} s (it ended?) after {} instants",
                reader.world(),
                timeout.as_secs_f64(),
                board.instants
            )));
        }
        if quiet >= Duration::from_secs(1) {
            board.status = Some(format!("no instant for {:.1} s", quiet.as_secs_f64()));
        }
        term.draw(|f| board.draw(f)).map_err(|e| io(e.into()))?;
        if event::poll(Duration::from_millis(33)).map_err(io)?
            && let Event::Key(k) = event::read().map_err(io)?
            && k.kind == KeyEventKind::Press
        {
            match k.code {
                KeyCode::Char('q') | KeyCode::Esc => return Ok(()),
                KeyCode::Up => board.scroll(-1),
                KeyCode::Down => board.scroll(1),
                KeyCode::PageUp => board.scroll(-20),
                KeyCode::PageDown => board.scroll(20),
                KeyCode::Enter => board.focus = Some(board.selected),
                KeyCode::Backspace => board.focus = None,
                _ => {}
            }
        }
    }
}

/// The only running world, waiting up to `timeout` for one to appear.
fn pick_world(timeout: Duration) -> Result<String, CliError> {
    let start = Instant::now();
    let mut said = false;
    loop {
        let worlds = list_worlds().map_err(monitor_error)?;
        match worlds.len() {
            1 => return Ok(worlds[0].clone()),
            0 => {}
            _ => {
                return Err(bad(format!(
                    "several worlds are running, choose one with --world: {}",
                    worlds.join(", ")
                )));
            }
        }
        if start.elapsed() >= timeout {
            return Err(bad(format!(
                "no world is running (waited {:.1} s); start one with `quadsim run`",
                timeout.as_secs_f64()
            )));
        }
        if !said {
            eprintln!("no world is running yet; waiting…");
            said = true;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}
