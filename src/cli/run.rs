//! `quadsim run`, `quadsim check` and `quadsim schema`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::Value;

use crate::divergence::{all_diverged, check_finite, diverged_count};
use crate::error::{CliError, bad};
use crate::scenario::{Scenario, load_scenario};
use crate::summary::Summary;
use crate::world::{Overrides, World, build_world};

/// Arguments of `quadsim run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The scenario file (TOML).
    pub scenario: PathBuf,
    /// Output directory (default `runs/<scenario name>/`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Simulated duration (s), overriding `world.duration_s`.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Worker threads for stepping robots in parallel (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// World seed, overriding `world.seed`.
    #[arg(long)]
    pub seed: Option<u64>,
    /// No progress bar and no metrics table (summary.json is still written).
    #[arg(long)]
    pub quiet: bool,
    /// Write no `log.mcap`: summary.json and report.md (without plots) only,
    /// as `[log] mode = "summary"`.
    #[arg(long, visible_alias = "summary-only")]
    pub no_log: bool,
    /// Write `log.mcap` (`mcap`) or not (`summary`), overriding `[log] mode`.
    #[arg(long, value_name = "mcap|summary")]
    pub log: Option<String>,
    /// Log rate in Hz (dividing the step rate) or `full` (every step),
    /// overriding `world.log_rate_hz` (default: the controller rate);
    /// `PATTERN=RATE` sets the rate of the robots matching a name or glob
    /// pattern instead, over their `[robots.log] rate_hz`. Repeatable.
    #[arg(long, value_name = "[PATTERN=]HZ|full")]
    pub log_rate: Vec<String>,
    /// Log only these robots' per-step channels: names or glob patterns,
    /// comma-separated (`q16-00*,q12-000`), replacing `[log] robots` and
    /// every robot's `log` setting.
    #[arg(long, value_name = "NAME,...")]
    pub log_robots: Option<String>,
    /// After the run, search the largest push each robot recovers from
    /// (as `[robots.analysis] push_search = true` for every robot; the
    /// robot's other `push_*` keys apply). Adds `push_recovery` to summary.json.
    #[arg(long)]
    pub push_search: bool,
    /// Write no `report.md` and `plots/` (for batch runs).
    #[arg(long)]
    pub no_report: bool,
    /// Do not publish live frames over shared memory (see `quadsim monitor`).
    #[arg(long)]
    pub no_monitor: bool,
    /// Publish live frames every N steps (default: the controller period).
    #[arg(long, value_name = "N")]
    pub monitor_every: Option<u64>,
    /// The world's name for `quadsim monitor` (default `<scenario>-<pid>`).
    #[arg(long)]
    pub world_name: Option<String>,
    /// Wait at each controller tick for the command of every robot with
    /// `kind = "external"` (docs/monitor.md); without it the last command holds.
    #[arg(long)]
    pub lockstep: bool,
    /// Seconds to wait for a lockstep command before failing the run.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub lockstep_timeout: f64,
    /// Pace the run to wall-clock time: FACTOR simulated seconds per second
    /// (1 when the flag has no value; 0.5 = half speed). Results are the
    /// same bits as unpaced.
    #[arg(long, value_name = "FACTOR", num_args = 0..=1, default_missing_value = "1.0")]
    pub real_time: Option<f64>,
    /// Serve the run live to Foxglove on this thread's side (as `quadsim
    /// monitor --foxglove`, in-process; the simulation's bits are unchanged).
    #[arg(long)]
    pub foxglove: bool,
    /// Port of `--foxglove`'s WebSocket server (127.0.0.1).
    #[arg(long, default_value_t = crate::foxglove_live::DEFAULT_PORT, requires = "foxglove")]
    pub foxglove_port: u16,
}

/// Arguments of `quadsim check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The scenario file (TOML).
    pub scenario: PathBuf,
}

fn scenario_error(e: crate::scenario::ScenarioError) -> CliError {
    bad(e.to_string())
}

fn overrides(a: &RunArgs) -> Result<Overrides, CliError> {
    if let Some(d) = a.duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(bad(format!(
            "--duration: must be a finite time > 0 (s), got {d}"
        )));
    }
    let (threads, note) = crate::limits::capped_threads(a.threads);
    if let Some(n) = note {
        eprintln!("note: {n}");
    }
    Ok(Overrides {
        duration_s: a.duration,
        seed: a.seed,
        threads,
    })
}

/// Warnings about the scenario that do not stop it: contact stability at this
/// time step on each ground a robot may touch, for two effective masses per
/// robot — its mass shared by its feet (the slow mode) and each foot point's
/// apparent masses at the start pose (normal and lightest tangential; the fast
/// modes, e.g. a foot rolling about its ankle).
pub fn stability_warnings(scn: &Scenario, world: &World) -> Vec<String> {
    use quadsim_engine::contact::stability::{check_stability_split, contact_apparent_masses};
    let mut out = Vec::new();
    let ground = crate::world::ground_of(world);
    let mut materials: Vec<(String, quadsim_engine::contact::GroundMaterial)> = Vec::new();
    if let Some(d) = ground.default_ground() {
        materials.push(("world.default_ground".into(), d.material));
    }
    // the union holds the patches sorted by terrain name (systems' ground
    // compile), not in file order
    let mut names: Vec<&str> = scn.file.terrains.iter().map(|t| t.name.as_str()).collect();
    names.sort_unstable();
    for (i, p) in ground.patches().iter().enumerate() {
        let name = names
            .get(i)
            .map_or_else(|| format!("terrain {i}"), |t| format!("terrain '{t}'"));
        materials.push((name, *p.material()));
    }
    let dt = scn.file.world.dt_s;
    for (name, root) in &world.robots {
        let Some(sim) = world.sim.robot(*root) else {
            continue;
        };
        let n = sim.run.n_feet.max(1) as f64;
        let mut masses = vec![(
            "its weight shared by its feet".to_string(),
            sim.model.total_mass / n,
            sim.model.total_mass / n,
        )];
        let mut data = quadsim_engine::Data::new(&sim.model);
        let (mut mn, mut mt) = (f64::INFINITY, f64::INFINITY);
        quadsim_engine::kinematics::forward_kinematics_pos(&sim.model, &mut data, &sim.state.q);
        for p in sim.contact.points.iter().take(sim.run.n_feet) {
            // the force acts at the sphere's lowest point, not its centre
            let lowest =
                data.body_point_world(p.body, p.point_in_body) - glam::DVec3::Z * p.radius_m;
            let bottom = data.pose[p.body].inverse().transform_point(lowest);
            if let Some((a, b)) = contact_apparent_masses(
                &sim.model,
                &mut data,
                &sim.state.q,
                p.body,
                bottom,
                glam::DVec3::Z,
            ) {
                mn = mn.min(a);
                mt = mt.min(b);
            }
        }
        if mn.is_finite() {
            masses.push((
                format!("a foot's apparent mass ({mn:.3} kg normal, {mt:.3} kg tangential)"),
                mn,
                mt,
            ));
        }
        for (label, mat) in &materials {
            for (what, m_n, m_t) in &masses {
                for w in check_stability_split(mat, dt, *m_n, *m_t) {
                    out.push(format!("robot '{name}' on {label}, {what}: {w}"));
                }
            }
        }
    }
    out
}

/// Runs `quadsim check`.
pub fn check(a: CheckArgs) -> Result<(), CliError> {
    let text = crate::limits::read_text_capped(&a.scenario, crate::limits::MAX_TEXT_FILE_BYTES)
        .map_err(|e| {
            bad(format!(
                "{}: cannot read the scenario: {e}",
                a.scenario.display()
            ))
        })?;
    if let Some(kind) = Some(text).and_then(|s| crate::study::file_kind(&s)) {
        if kind == "optimize" {
            let opt =
                crate::study::optimize::load_optimization(&a.scenario).map_err(scenario_error)?;
            println!(
                "{}: ok (study, kind = \"optimize\", {} parameters of {}, budget {})",
                a.scenario.display(),
                opt.params.len(),
                opt.base_path.display(),
                opt.file.optimize.budget
            );
            return Ok(());
        }
        if kind == "campaign" {
            let f = crate::study::campaign::load_campaign_file(&a.scenario)
                .map_err(|e| CliError::BadInput(e.to_string()))?;
            let (copies, base) = (f.spec.copies, f.spec.scenario.clone());
            crate::study::campaign::Prepared::new(f.spec)
                .map_err(|e| CliError::BadInput(e.to_string()))?;
            println!(
                "{}: ok (campaign, {copies} copies of {})",
                a.scenario.display(),
                base.display()
            );
            return Ok(());
        }
        let study = crate::study::load_study(&a.scenario).map_err(scenario_error)?;
        println!(
            "{}: ok (study, kind = \"{kind}\", {} variants of {})",
            a.scenario.display(),
            study.variants.len(),
            study.base_path.display()
        );
        return Ok(());
    }
    let scn = load_scenario(&a.scenario).map_err(scenario_error)?;
    let world = build_world(&scn, Overrides::default()).map_err(scenario_error)?;
    for w in world
        .warnings
        .iter()
        .chain(stability_warnings(&scn, &world).iter())
    {
        eprintln!("warning: {w}");
    }
    println!(
        "{}: ok ({} robots, {} terrains, {} steps of {} s)",
        a.scenario.display(),
        world.robots.len(),
        scn.file.terrains.len(),
        world.steps,
        world.dt_s
    );
    Ok(())
}

/// Runs `quadsim schema`: the JSON Schema of the scenario format.
pub fn schema() -> Result<(), CliError> {
    let s = schemars::schema_for!(crate::scenario::ScenarioFile);
    println!(
        "{}",
        serde_json::to_string_pretty(&s).expect("schema serialises")
    );
    Ok(())
}

/// The result of a run, for the CLI and for tests.
#[derive(Debug)]
pub struct RunOutput {
    /// `summary.json` as written.
    pub summary: Summary,
    /// Where it was written.
    pub out_dir: PathBuf,
    /// Stopped early by Ctrl-C or SIGTERM (`summary.json` covers the part that ran).
    pub interrupted: bool,
    /// What the log writer did (`None` with `--no-log`).
    pub log: Option<crate::log::WriterStats>,
    /// The report written (`None` with `--no-report`).
    pub report: Option<crate::report::ReportFiles>,
}

/// Steps between log samples: the last bare `--log-rate`, else
/// `world.log_rate_hz`, else the controller rate.
fn log_every_steps(a: &RunArgs, scn: &Scenario) -> Result<u64, CliError> {
    use crate::scenario::format::LogRateSpec;
    let w = &scn.file.world;
    let mut cli = None;
    for arg in &a.log_rate {
        let (pattern, spec) =
            crate::log::select::parse_rate_arg(arg).map_err(|m| bad(format!("--log-rate: {m}")))?;
        if pattern.is_none() {
            cli = Some(spec);
        }
    }
    let spec = match cli {
        Some(s) => s,
        None => w
            .log_rate_hz
            .clone()
            .unwrap_or(LogRateSpec::Hz(w.controller_rate_hz)),
    };
    spec.every_steps(w.dt_s).map_err(|m| {
        if a.log_rate.is_empty() {
            bad(format!("{}: world.log_rate_hz: {m}", a.scenario.display()))
        } else {
            bad(format!("--log-rate: {m}"))
        }
    })
}

/// Whether the run writes `log.mcap`: `--no-log`/`--summary-only`, else
/// `--log`, else `[log] mode`.
fn log_wanted(a: &RunArgs, scn: &Scenario) -> Result<bool, CliError> {
    use crate::scenario::format::LogMode;
    if a.no_log {
        return Ok(false);
    }
    match a.log.as_deref() {
        Some("mcap") => Ok(true),
        Some("summary") => Ok(false),
        Some(other) => Err(bad(format!(
            "--log: unknown mode '{other}': expected mcap or summary"
        ))),
        None => Ok(scn.file.log.mode == LogMode::Mcap),
    }
}

/// Each robot's decimation: the scenario's with `--log-robots` and the
/// robot-pattern `--log-rate` values over it.
fn log_plan(
    a: &RunArgs,
    scn: &Scenario,
    world: &World,
    every: u64,
) -> Result<crate::log::select::LogPlan, CliError> {
    use crate::log::select::{LogOverrides, LogPlan, parse_rate_arg};
    let mut o = LogOverrides::default();
    if let Some(list) = &a.log_robots {
        o.robots =
            Some(LogOverrides::parse_robots(list).map_err(|m| bad(format!("--log-robots: {m}")))?);
    }
    for arg in &a.log_rate {
        if let (Some(p), spec) = parse_rate_arg(arg).map_err(|m| bad(format!("--log-rate: {m}")))? {
            let d = spec
                .every_steps(world.dt_s)
                .map_err(|m| bad(format!("--log-rate {arg}: {m}")))?;
            o.rates.push((p, d));
        }
    }
    o.check_matches(world.robots.iter().map(|(n, _)| n.as_str()))
        .map_err(bad)?;
    Ok(LogPlan::new(scn, world, every, &o))
}

/// Starts the live monitor unless `--no-monitor`; shared memory that cannot
/// be used is a warning, not an error (the run goes on unmonitored).
fn start_monitor(
    a: &RunArgs,
    scn: &Scenario,
    world: &mut World,
) -> Result<Option<crate::monitor::RunMonitor>, CliError> {
    if a.no_monitor {
        return Ok(None);
    }
    let control_every = world
        .sim
        .world
        .get_resource::<quadsim_components::ControlRate>()
        .map_or(1, |c| c.every_steps.max(1));
    let every = match a.monitor_every {
        Some(0) => return Err(bad("--monitor-every: must be ≥ 1 (steps)")),
        Some(n) => n,
        // a lockstep commander answers every controller tick
        None if a.lockstep => control_every,
        None => crate::monitor::default_every_steps(world.dt_s, control_every),
    };
    let name = a
        .world_name
        .clone()
        .unwrap_or_else(|| crate::monitor::default_world_name(&scn.name));
    let robots: Vec<_> = world.robots.iter().map(|(_, e)| *e).collect();
    let models = scn
        .file
        .robots
        .iter()
        .map(|r| (r.name.clone(), r.model.clone()))
        .collect();
    let scene = crate::monitor::WorldScene {
        ground: crate::log::ground_mesh(&crate::world::ground_of(world)),
        terrain: serde_json::to_string(&crate::log::terrain_description(scn)).unwrap_or_default(),
    };
    let (sim, dt_s) = (&mut world.sim.world, world.dt_s);
    // sampled only while watched, except in lockstep (a commander answers frames)
    let always = a.lockstep;
    match crate::monitor::RunMonitor::start_with(
        sim, &name, &robots, models, dt_s, every, scene, always,
    ) {
        Ok(m) => {
            if !a.quiet {
                eprintln!("monitor: world '{name}' (quadsim monitor --world {name})");
            }
            Ok(Some(m))
        }
        Err(e) => {
            eprintln!("warning: {e}; running without live monitoring");
            Ok(None)
        }
    }
}

/// The commands service, beside the monitor; `--lockstep` needs both and
/// an external robot, and the monitor publishing at the controller rate (a
/// lockstep commander answers each frame).
fn start_commands(
    a: &RunArgs,
    world: &World,
    monitor: Option<&crate::monitor::RunMonitor>,
) -> Result<Option<crate::monitor::CommandReceiver>, CliError> {
    use quadsim_components::{ControlRate, Controller};
    let control_every = world
        .sim
        .world
        .get_resource::<ControlRate>()
        .map_or(1, |c| c.every_steps.max(1));
    let lockstep = if a.lockstep {
        if !(a.lockstep_timeout.is_finite() && a.lockstep_timeout > 0.0) {
            return Err(bad(format!(
                "--lockstep-timeout: must be a finite time > 0 (s), got {}",
                a.lockstep_timeout
            )));
        }
        let Some(m) = monitor else {
            return Err(bad(
                "--lockstep: needs the live monitor (no --no-monitor, and shared memory)",
            ));
        };
        if m.every_steps != control_every {
            return Err(bad(format!(
                "--lockstep: the monitor must publish every controller tick \
                 (--monitor-every {control_every}), not every {} steps",
                m.every_steps
            )));
        }
        let external = world.robots.iter().any(|(_, e)| {
            world
                .sim
                .robot(*e)
                .is_some_and(|r| matches!(r.run.controller, Controller::External(_)))
        });
        if !external {
            return Err(bad(
                "--lockstep: no robot has [robots.controller] kind = \"external\"",
            ));
        }
        Some(std::time::Duration::from_secs_f64(a.lockstep_timeout))
    } else {
        None
    };
    let Some(m) = monitor else {
        return Ok(None);
    };
    match crate::monitor::CommandReceiver::create(&m.world, world.robots.len(), lockstep) {
        Ok(c) => Ok(Some(c)),
        Err(e) if lockstep.is_some() => Err(bad(e.to_string())),
        Err(e) => {
            eprintln!("warning: {e}; running without external commands");
            Ok(None)
        }
    }
}

/// Runs `quadsim run`.
pub fn run(a: RunArgs) -> Result<(), CliError> {
    let out = run_scenario(&a)?;
    if !a.quiet {
        print_table(&out.summary.to_json());
        println!("wrote {}", out.out_dir.join("summary.json").display());
        if let Some(r) = &out.report {
            println!(
                "wrote {} ({} plot files in {})",
                r.markdown.display(),
                r.plots.len(),
                out.out_dir.join(crate::report::PLOTS_DIR).display()
            );
        }
        if let Some(l) = &out.log {
            println!(
                "wrote {} ({} messages, {:.1} MB; log writer thread: {:.3} s CPU)",
                out.out_dir.join(crate::log::LOG_FILE).display(),
                l.messages,
                l.file_bytes as f64 / 1e6,
                l.cpu_s.unwrap_or(l.busy_s)
            );
        }
    }
    if out.interrupted {
        eprintln!(
            "interrupted at t = {} s: log and summary.json cover the part that ran",
            out.summary.sim_time_s
        );
        std::process::exit(130);
    }
    Ok(())
}

/// Loads, builds, runs and summarises a scenario; writes `summary.json`.
pub fn run_scenario(a: &RunArgs) -> Result<RunOutput, CliError> {
    let scn = load_scenario(&a.scenario).map_err(scenario_error)?;
    let mut world = build_world(&scn, overrides(a)?).map_err(scenario_error)?;
    for w in world
        .warnings
        .iter()
        .chain(stability_warnings(&scn, &world).iter())
    {
        eprintln!("warning: {w}");
    }
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs").join(&scn.name));
    std::fs::create_dir_all(&out_dir).map_err(|e| CliError::Io {
        path: out_dir.display().to_string(),
        source: e,
    })?;

    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(world.steps);
        b.set_style(
            ProgressStyle::with_template(
                "{msg} [{bar:40}] {pos}/{len} steps, {per_sec}, eta {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        b.set_message(scn.name.clone());
        b
    };
    let log = if log_wanted(a, &scn)? {
        let every = log_every_steps(a, &scn)?;
        let plan = log_plan(a, &scn, &world, every)?;
        let path = out_dir.join(crate::log::LOG_FILE);
        Some(crate::log::start_run_log_with(
            &scn, &mut world, &path, &plan,
        )?)
    } else {
        None
    };
    let mut monitor = start_monitor(a, &scn, &mut world)?;
    let foxglove = if a.foxglove {
        let world_name = monitor.as_ref().map(|m| m.world.clone()).ok_or_else(|| {
            bad("--foxglove: needs the live monitor (no --no-monitor, and shared memory)")
        })?;
        Some(crate::foxglove_live::spawn_bridge(
            world_name,
            a.foxglove_port,
        )?)
    } else {
        None
    };
    let mut last_poll = Instant::now();
    let mut commands = start_commands(a, &world, monitor.as_ref())?;
    let mut commanded = commands.as_ref().is_some_and(|c| c.active());
    let mut command_error = None;
    crate::log::interrupt::arm().map_err(bad)?;
    let mut pacer = match a.real_time {
        Some(f) => Some(super::pace::Pacer::new(f, world.dt_s)?),
        None => None,
    };
    let start = Instant::now();
    if let Some(p) = &mut pacer {
        p.restart();
    }
    let chunk = (world.steps / 200).max(1);
    let mut done = 0;
    let mut outcome = crate::log::RunOutcome::default();
    // The steps run inside the thread pool (see `SimThreadPool::shared`).
    let pool = world
        .sim
        .world
        .resource::<quadsim_components::SimThreadPool>()
        .shared();
    while done < world.steps {
        let n = chunk.min(world.steps - done);
        let stop = pool.install(|| {
            let mut left = n;
            while left > 0 {
                // External commands arrive between steps: one step at a
                // time then; otherwise passes of several steps where the
                // log and the monitor allow (the same bits either way).
                let max = if let Some(c) = &mut commands
                    && commanded
                {
                    if let Err(e) = c.before_step(&mut world, monitor.as_ref()) {
                        command_error = Some(e.to_string());
                        return true;
                    }
                    1
                } else {
                    left
                };
                let max = pacer.as_ref().map_or(max, |p| max.min(p.pass_steps));
                let k = world.sim.run_pass(max);
                left -= k;
                done += k;
                if let Some(p) = &mut pacer {
                    p.wait(done);
                }
                // someone started or stopped watching (a cheap check, at most every 20 ms)
                if let Some(m) = &mut monitor
                    && last_poll.elapsed() >= std::time::Duration::from_millis(20)
                {
                    m.poll(&mut world.sim.world);
                    commanded = commands.as_ref().is_some_and(|c| c.active());
                    last_poll = Instant::now();
                }
                // A diverged robot is no longer stepped and the others go
                // on; the run stops early only when every robot diverged.
                if all_diverged(&world)
                    && let Err(e) = check_finite(&world)
                {
                    outcome.diverged = Some(e.to_string());
                    return true;
                }
                if crate::log::interrupt::requested() {
                    outcome.interrupted = true;
                    return true;
                }
            }
            false
        });
        bar.set_position(done);
        if stop {
            break;
        }
    }
    bar.finish_and_clear();
    crate::log::interrupt::clear();
    let wall = start.elapsed().as_secs_f64();
    if let Some(p) = &pacer {
        let got = p.achieved(done);
        if !a.quiet || p.fell_behind() {
            eprintln!(
                "real time: {got:.3}× achieved ({}× asked{})",
                p.factor,
                if p.fell_behind() {
                    format!(", up to {:.2} s behind", p.max_lag_s)
                } else {
                    String::new()
                }
            );
        }
    }
    let log_stats = match log {
        Some(log) => Some(log.finish(&mut world, &outcome)?),
        None => None,
    };
    if let Some(m) = &monitor {
        let t_ns = quadsim_systems::step_time_ns(world.sim.clock().step, world.dt_s);
        m.publish_metrics(t_ns, || {
            world
                .robots
                .iter()
                .filter_map(|(name, root)| {
                    let r = world.sim.robot(*root)?;
                    let m = crate::summary::RobotSummary::in_world(&world, name, r).to_json();
                    Some((name.clone(), serde_json::to_string(&m).ok()?))
                })
                .collect()
        });
    }
    let monitor_stats = monitor.map(|m| m.finish(&mut world.sim.world));
    if let Some(f) = foxglove {
        f.finish();
    }
    if let Some(e) = command_error {
        return Err(bad(e));
    }
    let mut summary = Summary::of_world(&scn, &world, Some(wall));
    // Some robots diverged and the others ran to the end: each diverged
    // robot's entry says when and why, and the run's error names the first.
    let partly_diverged = match (&outcome.diverged, check_finite(&world)) {
        (None, Err(e)) => Some(format!(
            "{e}; the other {} robot(s) ran to the end",
            world.robots.len() - diverged_count(&world)
        )),
        _ => None,
    };
    if let Some(d) = outcome.diverged.as_ref().or(partly_diverged.as_ref()) {
        // What was computed up to the divergence is kept: the summary (and
        // the report) cover the run until then; the error follows below.
        summary.diverged = Some(d.clone());
    } else if outcome.interrupted {
        summary.interrupted = true;
    } else {
        add_push_searches(a, &scn, &mut summary)?;
    }
    if let Some(t) = summary.timing.as_mut() {
        if let Some(m) = &monitor_stats {
            t.monitor_published = Some(m.published());
            t.monitor_dropped = Some(m.dropped());
        }
        if let Some(p) = &pacer {
            t.real_time_factor_asked = Some(p.factor);
            t.real_time_max_lag_s = Some(p.max_lag_s);
        }
        if let Some(c) = &commands {
            t.commands_applied = Some(c.stats().applied);
            t.commands_rejected = Some(c.stats().rejected);
        }
    }
    let path = out_dir.join("summary.json");
    std::fs::write(&path, summary.to_text()).map_err(|e| CliError::Io {
        path: path.display().to_string(),
        source: e,
    })?;
    let report = if a.no_report {
        None
    } else {
        Some(write_run_report(
            &scn,
            &summary,
            &out_dir,
            log_stats.is_some(),
        )?)
    };
    if let Some(d) = outcome.diverged.or(partly_diverged) {
        return Err(CliError::Diverged(d));
    }
    Ok(RunOutput {
        summary,
        out_dir,
        interrupted: outcome.interrupted,
        log: log_stats,
        report,
    })
}

/// Runs the push searches the scenario (`[robots.analysis] push_search`) or
/// `--push-search` asks for and adds each result to its robot's entry in
/// `summary` as `push_recovery` (see `crate::analysis`).
fn add_push_searches(a: &RunArgs, scn: &Scenario, summary: &mut Summary) -> Result<(), CliError> {
    use crate::analysis::{PushSearchOptions, push_search};
    for r in &scn.file.robots {
        if !(a.push_search || r.analysis.push_search) {
            continue;
        }
        let opts = PushSearchOptions::from_spec(&r.analysis);
        let found = push_search(scn, &r.name, &opts).map_err(scenario_error)?;
        if !a.quiet {
            println!(
                "push search '{}': largest recovered {:.1} N·s ({:.0} N for {} s, {}) in {} trials{}",
                r.name,
                found.max_impulse_ns,
                found.force_n,
                found.duration_s,
                found.direction.name(),
                found.trials.len(),
                match (found.reference_fell_at_s, found.bracketed) {
                    (Some(t), _) => format!("; the unpushed run fell at {t:.3} s"),
                    (None, false) => " (no fall up to the largest force: a lower bound)".into(),
                    _ => String::new(),
                }
            );
        }
        if let Some(entry) = summary.robot_mut(&r.name) {
            entry.push_recovery = Some(found.to_json());
        }
    }
    Ok(())
}

/// `report.md` and the plots of a finished run, from its log read back (the
/// same input `quadsim report` has, so both write the same files).
fn write_run_report(
    scn: &Scenario,
    summary: &Summary,
    out_dir: &Path,
    logged: bool,
) -> Result<crate::report::ReportFiles, CliError> {
    let contents = if logged {
        Some(
            crate::log::read::read_log_messages(
                &out_dir.join(crate::log::LOG_FILE),
                &crate::report::filmstrip::report_filter(),
            )
            .map_err(|e| bad(e.to_string()))?,
        )
    } else {
        None
    };
    let mut summary = summary.clone();
    summary.timing = None;
    crate::report::write_report(
        &crate::report::ReportInput {
            summary: &summary,
            scenario_text: &scn.source,
            log: contents.as_ref(),
        },
        out_dir,
    )
    .map_err(report_error)
}

/// A report that could not be written is an I/O failure on the named file.
pub fn report_error(e: crate::report::ReportError) -> CliError {
    CliError::Io {
        path: e.path,
        source: std::io::Error::other(e.message),
    }
}

/// Prints the metrics table (one column per robot).
/// Up to this many robots, the table has one column per robot.
const WIDE_TABLE_MAX_ROBOTS: usize = 6;
/// A herd's table lists this many robots (and every fallen one).
const HERD_TABLE_ROWS: usize = 20;

/// Many robots: one row each (the first [`HERD_TABLE_ROWS`] and every fallen
/// one), the main metrics, and a count.
fn print_herd_table(robots: &[Value]) {
    let num = |r: &Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    let abs_max = |r: &Value, k: &str| {
        r[k].as_array()
            .map(|a| {
                a.iter()
                    .filter_map(Value::as_f64)
                    .fold(0.0f64, |m, x| m.max(x.abs()))
            })
            .unwrap_or(f64::NAN)
    };
    println!(
        "{:<16} {:>5} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "robot", "fell", "speed m/s", "dist m", "p2p z m", "|roll| rad", "|pitch|", "margin m"
    );
    let fallen = robots
        .iter()
        .filter(|r| r["fell"] == Value::Bool(true))
        .count();
    let mut shown = 0;
    for (i, r) in robots.iter().enumerate() {
        let fell = r["fell"] == Value::Bool(true);
        if i >= HERD_TABLE_ROWS && !fell {
            continue;
        }
        shown += 1;
        println!(
            "{:<16} {:>5} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10}",
            r["name"].as_str().unwrap_or("?"),
            fell,
            num(r, "mean_forward_speed_mps"),
            num(r, "distance_m"),
            num(r, "base_height_p2p_m"),
            abs_max(r, "roll_range_rad"),
            abs_max(r, "pitch_range_rad"),
            r["min_stability_margin_m"]
                .as_f64()
                .map_or("-".to_string(), |m| format!("{m:.4}")),
        );
    }
    if shown < robots.len() {
        println!("… {} more robots in summary.json", robots.len() - shown);
    }
    println!("{} robots, {fallen} fell", robots.len());
}

pub fn print_table(summary: &Value) {
    let robots = summary["robots"].as_array().cloned().unwrap_or_default();
    let rows: [(&str, &str); 14] = [
        ("fell", "fell"),
        ("mean forward speed (m/s)", "mean_forward_speed_mps"),
        ("peak forward speed (m/s)", "peak_forward_speed_mps"),
        ("base height mean (m)", "base_height_mean_m"),
        ("base height p2p (m)", "base_height_p2p_m"),
        ("CoM height mean (m)", "com_height_mean_m"),
        ("CoM height p2p (m)", "com_height_p2p_m"),
        ("roll range (rad)", "roll_range_rad"),
        ("pitch range (rad)", "pitch_range_rad"),
        ("joint RMS error (rad)", "joint_rms_error_rad"),
        ("max foot force (N)", "max_foot_force_n"),
        ("energy (J)", "energy_j"),
        ("min stability margin (m)", "min_stability_margin_m"),
        ("distance (m)", "distance_m"),
    ];
    let fmt = |v: &Value| match v {
        Value::Null => "-".to_string(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => format!("{:.4}", n.as_f64().unwrap_or(f64::NAN)),
        Value::Array(a) => format!(
            "[{}]",
            a.iter()
                .map(|x| format!("{:.3}", x.as_f64().unwrap_or(f64::NAN)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        other => other.to_string(),
    };
    if robots.len() <= WIDE_TABLE_MAX_ROBOTS {
        print!("{:<26}", "metric");
        for r in &robots {
            print!(" {:>18}", r["name"].as_str().unwrap_or("?"));
        }
        println!();
        for (label, key) in rows {
            print!("{label:<26}");
            for r in &robots {
                print!(" {:>18}", fmt(&r[key]));
            }
            println!();
        }
    } else {
        print_herd_table(&robots);
    }
    let t = &summary["timing"];
    println!(
        "simulated {:.3} s in {:.3} s wall ({:.1}x real time, {} threads)",
        summary["sim_time_s"].as_f64().unwrap_or(0.0),
        t["wall_time_s"].as_f64().unwrap_or(0.0),
        t["real_time_factor"].as_f64().unwrap_or(0.0),
        t["threads"]
    );
}
