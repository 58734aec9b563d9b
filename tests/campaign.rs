//! `quadsim campaign`: draws are deterministic and in their ranges, results do
//! not depend on the thread count, a standing robot never falls, a limp one
//! always does (so the fall detector can fail), mass perturbations reach the
//! body and not the controller, and the command line refuses a file as
//! `--out` before running and fails on `--max-falls`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use quadsim::study::campaign::{
    CampaignReport, CampaignSpec, Perturbations, Prepared, Timing, run_copies,
};

/// quad16 with limp joints (no controller): it folds onto the ground well
/// within a second, so every copy falls.
const LIMP: &str = r#"format_version = 1
[world]
name = "limp"
dt_s = 0.0005
duration_s = 1.5
seed = 1
default_ground = "concrete"

[[robots]]
name = "rex"
model = "quad16"
contact_points = ["knees", "torso"]
"#;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-campaign-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn limp(tag: &str) -> (PathBuf, PathBuf) {
    let d = dir(tag);
    let f = d.join("limp.toml");
    std::fs::write(&f, LIMP).unwrap();
    (d, f)
}

fn quadsim(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn stand_spec(copies: usize, seed: u64) -> CampaignSpec {
    let mut s = CampaignSpec::new(root().join("scenarios/stand.toml"), copies);
    s.seed = seed;
    s.duration_s = Some(2.5);
    s
}

fn campaign(spec: CampaignSpec, threads: usize) -> CampaignReport {
    let prep = Prepared::new(spec).expect("a valid campaign");
    let results = run_copies(&prep, threads, &|_| {});
    prep.report(
        results,
        Timing {
            wall_s: 0.0,
            threads,
            sim_s_per_wall_s: 0.0,
            argv: Vec::new(),
        },
    )
}

/// `campaign.json` without `timing`.
fn without_timing(r: &CampaignReport) -> serde_json::Value {
    let mut v = serde_json::to_value(r).unwrap();
    v.as_object_mut().unwrap().remove("timing");
    v
}

#[test]
fn a_standing_robot_never_falls_and_threads_change_nothing() {
    let one = campaign(stand_spec(10, 7), 1);
    let a = &one.aggregates;
    assert_eq!(a.copies, 10);
    assert_eq!(
        a.failed,
        0,
        "{:?}",
        one.runs.iter().map(|r| &r.error).collect::<Vec<_>>()
    );
    assert_eq!(a.falls, 0, "the stand fell in a campaign");
    assert_eq!(a.held, 10);
    // the stand holds its place: a speed near 0, small attitude
    let v = a
        .max_speed_mps
        .unwrap()
        .abs()
        .max(a.min_speed_mps.unwrap().abs());
    assert!(v < 0.02, "standing speed {v} m/s");
    assert!(a.worst_abs_roll_rad.unwrap() < 0.1 && a.worst_abs_pitch_rad.unwrap() < 0.1);
    assert!(
        a.worst_peak_foot_force_n.unwrap() > 50.0,
        "no weight on the feet?"
    );
    assert!(a.fall_rate == 0.0 && a.fall_rate_wilson_95[0] == 0.0);
    assert!(a.fall_rate_wilson_95[1] > 0.2 && a.fall_rate_wilson_95[1] < 0.35);
    // the draws differ between copies and the runs with them
    let speeds: Vec<f64> = one
        .runs
        .iter()
        .map(|r| r.metrics.as_ref().unwrap().mean_speed_mps.unwrap())
        .collect();
    assert!(speeds.windows(2).any(|w| w[0] != w[1]), "identical copies");
    // the same seed on three threads: the same bits, copy by copy
    let three = campaign(stand_spec(10, 7), 3);
    assert_eq!(without_timing(&one), without_timing(&three));
    // another seed: other draws
    let other = Prepared::new(stand_spec(10, 8)).unwrap();
    let prep = Prepared::new(stand_spec(10, 7)).unwrap();
    assert_ne!(other.draws(0), prep.draws(0));
    assert_eq!(prep.draws(3), one.runs[3].draws);
}

#[test]
fn draws_lie_in_their_ranges_and_do_not_depend_on_each_other() {
    let mut spec = stand_spec(1, 42);
    spec.perturb = Perturbations {
        start_xy_m: 0.03,
        start_yaw_deg: 4.0,
        link_mass_frac: 0.1,
        friction: Some([0.6, 1.0]),
        world_seed: true,
        noise_scale: [0.5, 2.0],
    };
    let prep = Prepared::new(spec.clone()).unwrap();
    assert!(prep.links.len() >= 9, "links: {:?}", prep.links);
    let mut seeds = std::collections::BTreeSet::new();
    let (mut lo_mu, mut hi_mu) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut lo_m, mut hi_m) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..500 {
        let d = prep.draws(k);
        assert!(
            d.start_dx_m.abs() <= 0.03 && d.start_dy_m.abs() <= 0.03,
            "{d:?}"
        );
        assert!(d.start_dyaw_deg.abs() <= 4.0, "{d:?}");
        let mu = d.friction.unwrap();
        assert!((0.6..=1.0).contains(&mu), "{d:?}");
        assert!((0.5..=2.0).contains(&d.noise_scale), "{d:?}");
        assert_eq!(
            d.link_mass_scale.keys().cloned().collect::<Vec<_>>(),
            prep.links
        );
        for s in d.link_mass_scale.values() {
            assert!((0.9..=1.1).contains(s), "{d:?}");
            lo_m = lo_m.min(*s);
            hi_m = hi_m.max(*s);
        }
        lo_mu = lo_mu.min(mu);
        hi_mu = hi_mu.max(mu);
        seeds.insert(d.world_seed);
        assert_eq!(d, prep.draws(k), "draws are a function of (seed, copy)");
    }
    // the draws fill their ranges
    assert!(lo_mu < 0.62 && hi_mu > 0.98, "μ in [{lo_mu}, {hi_mu}]");
    assert!(
        lo_m < 0.902 && hi_m > 1.098,
        "mass factors in [{lo_m}, {hi_m}]"
    );
    assert!(seeds.len() > 490, "world seeds repeat: {}", seeds.len());
    // turning one perturbation off leaves the others' draws as they were
    let mut no_mass = spec.clone();
    no_mass.perturb.link_mass_frac = 0.0;
    no_mass.perturb.friction = None;
    let p2 = Prepared::new(no_mass).unwrap();
    for k in 0..20 {
        let (a, b) = (prep.draws(k), p2.draws(k));
        assert!(b.link_mass_scale.is_empty() && b.friction.is_none());
        assert_eq!(
            (
                a.world_seed,
                a.start_dx_m,
                a.start_dy_m,
                a.start_dyaw_deg,
                a.noise_scale
            ),
            (
                b.world_seed,
                b.start_dx_m,
                b.start_dy_m,
                b.start_dyaw_deg,
                b.noise_scale
            )
        );
    }
    // no perturbation: every copy is the scenario as written
    let mut none = spec;
    none.perturb = Perturbations::NONE;
    let p3 = Prepared::new(none).unwrap();
    let d = p3.draws(5);
    assert_eq!(d.world_seed, 1, "stand.toml's seed");
    assert_eq!(
        (d.start_dx_m, d.start_dy_m, d.start_dyaw_deg),
        (0.0, 0.0, 0.0)
    );
    assert_eq!(d.noise_scale, 1.0);
}

#[test]
fn the_masses_change_the_body_not_the_controller() {
    let mut spec = stand_spec(3, 3);
    spec.duration_s = Some(2.2);
    spec.perturb = Perturbations {
        link_mass_frac: 0.1,
        ..Perturbations::NONE
    };
    // the built copy: the body has the drawn masses, the controller's
    // view (and the estimator's) the nominal ones
    let prep = Prepared::new(spec.clone()).unwrap();
    let d = prep.draws(1);
    let (world, root) = prep.build_copy(&d).unwrap();
    let sim = world.sim.robot(root).unwrap();
    let view = sim
        .control
        .as_ref()
        .expect("a nominal view for the controller");
    assert_eq!(view.model.total_mass, prep.nominal_mass_kg);
    assert!((sim.model.total_mass - prep.nominal_mass_kg).abs() > 1e-6);
    let torso = sim.model.frames[sim.model.frame_index("torso").unwrap()].body;
    let s = d.link_mass_scale["torso"];
    let (m, m0) = (
        sim.model.inertia[torso].mass,
        view.model.inertia[torso].mass,
    );
    assert!((m - s * m0).abs() < 1e-9, "torso: {m} kg for {s} × {m0} kg");
    let r = campaign(spec, 2);
    let nominal = r.scenario.nominal_mass_kg;
    assert_eq!(nominal, prep.nominal_mass_kg);
    assert!((nominal - 28.0).abs() < 1.0, "quad16 nominal {nominal} kg");
    for c in &r.runs {
        let m = c.metrics.as_ref().expect("ran");
        assert!(!c.draws.link_mass_scale.is_empty());
        assert!(
            (m.total_mass_kg - nominal).abs() > 1e-6
                && (m.total_mass_kg - nominal).abs() < 0.1 * nominal + 1e-9,
            "copy {}: {} kg against {nominal} kg nominal",
            c.copy,
            m.total_mass_kg
        );
        assert!(!m.fell);
    }
    // without mass draws the true mass is the nominal one
    let mut spec = stand_spec(1, 3);
    spec.duration_s = Some(2.1);
    spec.perturb = Perturbations::NONE;
    let r0 = campaign(spec, 1);
    assert_eq!(r0.runs[0].metrics.as_ref().unwrap().total_mass_kg, nominal);
}

#[test]
fn a_limp_robot_always_falls() {
    let (_d, f) = limp("limp");
    let mut spec = CampaignSpec::new(&f, 4);
    spec.steady_from_s = 1.0;
    let r = campaign(spec, 2);
    assert_eq!(r.aggregates.failed, 0);
    assert_eq!(r.aggregates.falls, 4, "a limp robot stood up?");
    assert_eq!(r.aggregates.fall_rate, 1.0);
    assert!(r.aggregates.fall_rate_wilson_95[0] > 0.4);
    assert_eq!(r.aggregates.held, 0);
    assert_eq!(r.aggregates.mean_speed_mps, None);
    for c in &r.runs {
        let m = c.metrics.as_ref().unwrap();
        let t = m.fell_at_s.unwrap();
        assert!(t > 0.0 && t < 1.5, "fell at {t}");
        // the copy stops within one sample of its fall
        assert!(
            m.simulated_s <= t + 0.0105,
            "{} s for a fall at {t} s",
            m.simulated_s
        );
        assert_eq!(m.mean_speed_mps, None);
    }
}

#[test]
fn the_command_line_writes_its_files_and_keeps_to_its_limits() {
    let (d, f) = limp("cli");
    let f = f.to_str().unwrap();
    // a file as --out is refused before anything runs
    let file = d.join("taken");
    std::fs::write(&file, "keep me").unwrap();
    let o = quadsim(
        &[
            "campaign",
            f,
            "-n",
            "2",
            "--out",
            file.to_str().unwrap(),
            "--steady-from",
            "1",
        ],
        &d,
    );
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("existing file"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    // bad values name their flag
    let o = quadsim(&["campaign", f, "--friction", "1.0,0.6", "--out", "x"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("friction"));
    assert!(
        !d.join("x").exists(),
        "a refused campaign wrote its directory"
    );
    // every copy falls: fine without --max-falls ...
    let out = d.join("out");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "campaign",
            f,
            "-n",
            "2",
            "--quiet",
            "--steady-from",
            "1",
            "--seed",
            "5",
        ];
        a.extend_from_slice(&["--out", out.to_str().unwrap()]);
        a.extend_from_slice(extra);
        quadsim(&a, &d)
    };
    let o = run(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in quadsim::study::campaign_output::FILES {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("campaign.json")).unwrap()).unwrap();
    assert_eq!(v["schema_version"], 1);
    assert_eq!(v["n"], 2);
    assert_eq!(v["seed"], 5);
    assert_eq!(v["aggregates"]["falls"], 2);
    assert!(v["timing"]["wall_s"].as_f64().unwrap() > 0.0);
    let csv = std::fs::read_to_string(out.join("campaign.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(csv.lines().nth(1).unwrap().starts_with("0,fell,"), "{csv}");
    let md = std::fs::read_to_string(out.join("campaign.md")).unwrap();
    assert!(md.contains("| command | case | N | falls"), "{md}");
    // ... and a failure past --max-falls, with a message
    let o = run(&["--max-falls", "1"]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("2 of 2 copies fell"));
    let o = run(&["--max-falls", "2"]);
    assert!(o.status.success());
    // the same command twice: the same campaign.json but for its timing
    let first = std::fs::read_to_string(out.join("campaign.json")).unwrap();
    let o = run(&["--threads", "1"]);
    assert!(o.status.success());
    let second = std::fs::read_to_string(out.join("campaign.json")).unwrap();
    let strip = |s: &str| {
        let mut v: serde_json::Value = serde_json::from_str(s).unwrap();
        v.as_object_mut().unwrap().remove("timing");
        v
    };
    assert_eq!(strip(&first), strip(&second));
}

#[test]
fn friction_noise_and_start_reach_the_copy() {
    use quadsim::scenario::format::GroundSpec;
    let mut spec = CampaignSpec::new(root().join("scenarios/trot.toml"), 1);
    spec.seed = 11;
    spec.perturb.noise_scale = [0.5, 2.0];
    let prep = Prepared::new(spec).unwrap();
    let d = prep.draws(0);
    let scn = prep.copy_scenario(&d).unwrap();
    let w = &scn.file.world;
    match &w.default_ground {
        Some(GroundSpec::Custom(c)) => {
            assert_eq!(c.friction, d.friction.unwrap());
            // concrete's normal law kept
            assert_eq!(
                (c.stiffness_n_per_m, c.damping_ns_per_m),
                (100000.0, 1000.0)
            );
        }
        other => panic!("default ground {other:?}"),
    }
    let r = &scn.file.robots[0];
    assert_eq!(r.start_xy_m, Some([d.start_dx_m, d.start_dy_m]));
    assert_eq!(r.start_yaw_deg, d.start_dyaw_deg);
    // quad16's default IMU figures, scaled
    let cfg = quadsim::engine::sensors::SensorConfig::from_spec(
        &quadsim::engine::robots::quad16::SENSORS,
        500.0,
    );
    let imu = r.sensors.imu.as_ref().expect("scaled IMU figures written");
    let gyro = cfg.imu.unwrap().gyro.white_std;
    assert!(gyro > 0.0);
    assert_eq!(imu.gyro_noise_std_radps, Some(gyro * d.noise_scale));
    assert!(d.noise_scale != 1.0);
    // the copy builds and runs with them
    let (world, _) = prep.build_copy(&d).unwrap();
    assert!(world.steps > 0);
}

#[test]
fn a_campaign_file_sets_the_campaign_and_flags_override_it() {
    let (d, _) = limp("file");
    let write = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let f = write(
        "c.toml",
        "format_version = 1\nkind = \"campaign\"\nbase = \"limp.toml\"\nname = \"limp case\"\n\
         copies = 3\nseed = 9\nsteady_from_s = 1.0\nmax_falls = 2\n\
         [perturbations]\nfriction = false\nnoise_scale = [0.5, 0.5]\nlink_mass_frac = 0.0\n",
    );
    let out = d.join("out");
    let o = quadsim(
        &["campaign", &f, "--quiet", "--out", out.to_str().unwrap()],
        &d,
    );
    // three copies fall, two are allowed: exit 3
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("campaign.json")).unwrap()).unwrap();
    assert_eq!(v["n"], 3);
    assert_eq!(v["seed"], 9);
    assert_eq!(v["case"], "limp case");
    assert_eq!(v["perturbations"]["friction"], serde_json::Value::Null);
    assert_eq!(
        v["perturbations"]["noise_scale"],
        serde_json::json!([0.5, 0.5])
    );
    assert_eq!(v["perturbations"]["link_mass_frac"], 0.0);
    assert_eq!(v["perturbations"]["start_xy_m"], 0.02, "a default kept");
    assert!(
        v["scenario"]["path"]
            .as_str()
            .unwrap()
            .ends_with("limp.toml")
    );
    // flags override the file
    let o = quadsim(
        &[
            "campaign",
            &f,
            "--quiet",
            "-n",
            "2",
            "--seed",
            "4",
            "--out",
            out.to_str().unwrap(),
        ],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("campaign.json")).unwrap()).unwrap();
    assert_eq!((v["n"].as_u64(), v["seed"].as_u64()), (Some(2), Some(4)));
    // check validates it; run points to campaign
    let o = quadsim(&["check", &f], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("campaign, 3 copies"));
    let o = quadsim(&["run", &f], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("quadsim campaign"));
    // an unknown key and a bad range name their line and key
    let bad = write(
        "bad.toml",
        "format_version = 1\nkind = \"campaign\"\nbase = \"limp.toml\"\n[perturbations]\nfrction = [0.6, 1.0]\n",
    );
    let o = quadsim(&["campaign", &bad, "--out", "y"], &d);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("bad.toml:5") && e.contains("frction"), "{e}");
    let bad = write(
        "bad2.toml",
        "format_version = 1\nkind = \"campaign\"\nbase = \"limp.toml\"\n[perturbations]\nfriction = [1.0, 0.6]\n",
    );
    let o = quadsim(&["campaign", &bad, "--out", "y"], &d);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("bad2.toml:5") && e.contains("perturbations.friction"),
        "{e}"
    );
    assert!(!d.join("y").exists());
}

#[test]
fn the_fall_rate_interval_is_wilsons() {
    use quadsim::study::campaign::wilson_95;
    // reference values of the Wilson score interval at z = 1.96
    let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 5e-4 && (a[1] - b[1]).abs() < 5e-4;
    assert!(
        close(wilson_95(0, 10), [0.0, 0.2775]),
        "{:?}",
        wilson_95(0, 10)
    );
    assert!(
        close(wilson_95(5, 20), [0.1119, 0.4687]),
        "{:?}",
        wilson_95(5, 20)
    );
    assert!(
        close(wilson_95(7, 50), [0.0695, 0.2619]),
        "{:?}",
        wilson_95(7, 50)
    );
    assert!(
        close(wilson_95(10, 10), [0.7225, 1.0]),
        "{:?}",
        wilson_95(10, 10)
    );
}
