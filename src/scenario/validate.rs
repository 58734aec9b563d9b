//! Validation after parsing: domains of numbers, unique names, references
//! between sections, and the keys each `kind` accepts. Every error names the
//! key path, which [`super::Locator`] turns into a line and column.

use super::error::{Locator, ScenarioError};
use super::format::{GroundSpec, ScenarioFile};
use super::spans::path_key;
use std::collections::BTreeMap;

/// The domain a numeric key must lie in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Domain {
    /// Finite, > 0.
    Positive,
    /// Finite, ≥ 0.
    NonNegative,
    /// Finite.
    Finite,
    /// An integer ≥ 1.
    Count,
    /// A string.
    Text,
    /// An array of three finite numbers.
    Vec3,
    /// An array of tables (checked by the terrain builder).
    Tables,
    /// A number ≥ 0, or an array of them (one per joint; the length is checked when the model is known).
    Gains,
    /// `true` or `false`.
    Bool,
}

/// A key accepted by a `kind`: name, domain, required.
pub type KeySpec = (&'static str, Domain, bool);

/// Keys of each terrain kind beside `name`, `kind`, `origin_m`, `extent_m`, `ground`.
pub const TERRAIN_KINDS: &[(&str, &[KeySpec])] = &[
    ("flat", &[]),
    (
        "incline",
        &[
            ("slope_deg", Domain::Finite, true),
            ("direction_deg", Domain::Finite, false),
        ],
    ),
    (
        "sine",
        &[
            ("amplitude_m", Domain::NonNegative, true),
            ("wavelength_m", Domain::Positive, true),
            ("direction_deg", Domain::Finite, false),
        ],
    ),
    (
        "rough",
        &[
            ("amplitude_m", Domain::NonNegative, true),
            ("cell_m", Domain::Positive, false),
            ("noise", Domain::Text, false),
        ],
    ),
    (
        "trench",
        &[
            ("width_m", Domain::Positive, true),
            ("depth_m", Domain::Positive, true),
            ("direction_deg", Domain::Finite, false),
        ],
    ),
    (
        "stairs",
        &[
            ("rise_m", Domain::Positive, true),
            ("run_m", Domain::Positive, true),
            ("steps", Domain::Count, true),
            ("direction", Domain::Text, false),
        ],
    ),
    ("boxes", &[("boxes", Domain::Tables, true)]),
    (
        "stepping_stones",
        &[
            ("stone_size_m", Domain::Positive, true),
            ("gap_m", Domain::NonNegative, true),
            ("height_m", Domain::Positive, false),
        ],
    ),
    (
        "heightmap",
        &[
            ("file", Domain::Text, true),
            ("horizontal_scale_m", Domain::Positive, true),
            ("vertical_scale_m", Domain::Positive, true),
        ],
    ),
];

/// Keys of each controller kind beside `kind`.
pub const CONTROLLER_KINDS: &[(&str, &[KeySpec])] = &[
    ("none", &[]),
    ("external", &[]),
    (
        "joint_pd",
        &[
            ("kp_nm_per_rad", Domain::Gains, false),
            ("kd_nms_per_rad", Domain::Gains, false),
            ("bandwidth_hz", Domain::Positive, false),
            ("damping_ratio", Domain::NonNegative, false),
            ("gravity_compensation", Domain::Text, false),
        ],
    ),
    (
        "vmc",
        &[
            ("gait", Domain::Text, false),
            ("period_s", Domain::Positive, false),
            ("duty_factor", Domain::Positive, false),
            ("four_leg_support_s", Domain::NonNegative, false),
            ("two_leg_support_s", Domain::Positive, false),
            ("lift_height_m", Domain::NonNegative, false),
            ("v_x_mps", Domain::Finite, false),
            ("v_y_mps", Domain::Finite, false),
            ("yaw_rate_radps", Domain::Finite, false),
            ("height_m", Domain::Positive, false),
            ("payload_mass_kg", Domain::NonNegative, false),
            ("swing_bandwidth_hz", Domain::Positive, false),
            ("placement_gain_s", Domain::NonNegative, false),
            ("position_clip_m", Domain::Positive, false),
            ("whole_body", Domain::Bool, false),
            ("follow_ground", Domain::Bool, false),
            ("planner", Domain::Text, false),
        ],
    ),
    (
        "prescribed",
        &[
            ("mode", Domain::Text, false),
            ("period_s", Domain::Positive, false),
            ("duty_factor", Domain::Positive, false),
            ("step_length_m", Domain::NonNegative, false),
            ("lift_height_m", Domain::NonNegative, false),
            ("body_height_m", Domain::Positive, false),
            ("ramp_s", Domain::NonNegative, false),
            ("hybrid_kp_per_s2", Domain::NonNegative, false),
            ("hybrid_kd_per_s", Domain::NonNegative, false),
            ("kp_nm_per_rad", Domain::Gains, false),
            ("kd_nms_per_rad", Domain::Gains, false),
        ],
    ),
];

/// Keys of each event kind beside `t_s`, `robot`, `kind`.
pub const EVENT_KINDS: &[(&str, &[KeySpec])] = &[
    (
        "push",
        &[
            ("force_n", Domain::Vec3, true),
            ("duration_s", Domain::Positive, true),
            ("body", Domain::Text, false),
            ("point_m", Domain::Vec3, false),
        ],
    ),
    (
        "command",
        &[
            ("v_x_mps", Domain::Finite, false),
            ("v_y_mps", Domain::Finite, false),
            ("yaw_rate_radps", Domain::Finite, false),
        ],
    ),
    ("attach", &[("payload", Domain::Text, true)]),
    ("detach", &[("payload", Domain::Text, true)]),
];

/// The stiffest ground (N/m, or the Hunt–Crossley k).
pub const MAX_STIFFNESS_N_PER_M: f64 = 1.0e12;
/// The most damped ground (N·s/m).
pub const MAX_DAMPING_NS_PER_M: f64 = 1.0e9;
/// The largest friction coefficient.
pub const MAX_FRICTION: f64 = 100.0;

/// The ground presets of Study A.
pub const GROUND_PRESETS: &[&str] = &["concrete", "grass", "mud", "sand"];

/// Validates a parsed scenario.
pub fn validate(loc: &Locator<'_>, f: &ScenarioFile) -> Result<(), ScenarioError> {
    let w = &f.world;
    if let Some(n) = &w.name {
        name(loc, "world.name", n)?;
    }
    positive(loc, "world.dt_s", w.dt_s)?;
    if w.dt_s > 0.01 {
        return Err(loc.at(
            "world.dt_s",
            format!(
                "{} s is too large for contact dynamics (at most 0.01 s)",
                w.dt_s
            ),
        ));
    }
    positive(loc, "world.duration_s", w.duration_s)?;
    let steps = w.duration_s / w.dt_s;
    if steps > crate::limits::MAX_STEPS as f64 {
        return Err(loc.at(
            "world.duration_s",
            format!(
                "{} s at dt {} s is {steps:.3e} steps, beyond the {} a run may take",
                w.duration_s,
                w.dt_s,
                crate::limits::MAX_STEPS
            ),
        ));
    }
    positive(loc, "world.controller_rate_hz", w.controller_rate_hz)?;
    let ratio = 1.0 / (w.dt_s * w.controller_rate_hz);
    if ratio < 1.0 - 1e-9 || (ratio - ratio.round()).abs() > 1e-6 {
        return Err(loc.at(
            "world.controller_rate_hz",
            format!(
                "{} Hz must divide the step rate 1/dt = {} Hz into a whole number of steps",
                w.controller_rate_hz,
                1.0 / w.dt_s
            ),
        ));
    }
    if let Some(rate) = &w.log_rate_hz {
        rate.every_steps(w.dt_s)
            .map_err(|m| loc.at("world.log_rate_hz", m))?;
    }
    if w.gravity_mps2.iter().any(|g| !g.is_finite()) {
        return Err(loc.at("world.gravity_mps2", "must be three finite numbers (m/s²)"));
    }
    bounded_all(loc, "world.gravity_mps2", &w.gravity_mps2)?;
    if !w.default_ground_height_m.is_finite() {
        return Err(loc.at("world.default_ground_height_m", "must be finite (m)"));
    }
    bounded(
        loc,
        "world.default_ground_height_m",
        w.default_ground_height_m,
    )?;
    if let Some(g) = &w.default_ground {
        ground(loc, "world.default_ground", g)?;
    }

    let mut terrain_names: Vec<&str> = Vec::new();
    for (i, t) in f.terrains.iter().enumerate() {
        let p = format!("terrains[{i}]");
        name(loc, &format!("{p}.name"), &t.name)?;
        if terrain_names.contains(&t.name.as_str()) {
            return Err(loc.at(
                &format!("{p}.name"),
                format!("duplicate terrain name '{}'", t.name),
            ));
        }
        terrain_names.push(&t.name);
        if t.origin_m.iter().any(|x| !x.is_finite()) {
            return Err(loc.at(&format!("{p}.origin_m"), "must be three finite numbers (m)"));
        }
        bounded_all(loc, &format!("{p}.origin_m"), &t.origin_m)?;
        if let Some(e) = t.extent_m {
            for x in e {
                if !(x.is_finite() && x > 0.0) {
                    return Err(loc.at(&format!("{p}.extent_m"), "must be two positive sizes (m)"));
                }
            }
            bounded_all(loc, &format!("{p}.extent_m"), &e)?;
        }
        if let Some(g) = &t.ground {
            ground(loc, &format!("{p}.ground"), g)?;
        }
        kind_keys(loc, &p, "terrain", &t.kind, TERRAIN_KINDS, &t.params)?;
    }

    let mut robot_names: Vec<&str> = Vec::new();
    // a set beside the list: a herd of thousands is checked in linear time
    let mut robot_set = std::collections::HashSet::new();
    for (i, r) in f.robots.iter().enumerate() {
        let p = f.robot_key_path(i);
        name(loc, &format!("{p}.name"), &r.name)?;
        if !robot_set.insert(r.name.as_str()) {
            return Err(loc.at(
                &format!("{p}.name"),
                format!("duplicate robot name '{}'", r.name),
            ));
        }
        robot_names.push(&r.name);
        for (k, pl) in r.payloads.iter().enumerate() {
            name(loc, &format!("{p}.payloads[{k}].name"), &pl.name)?;
        }
        if let Some(rate) = &r.log.rate_hz {
            rate.every_steps(w.dt_s)
                .map_err(|m| loc.at(&format!("{p}.log.rate_hz"), m))?;
        }
        for (k, v) in &r.params {
            let kp = format!("{p}.params.{}", path_key(k));
            if !v.is_finite() {
                return Err(loc.at(&kp, "must be a finite number"));
            }
            bounded(loc, &kp, *v)?;
        }
        if let Some(sp) = r.start_position_m {
            if sp.iter().any(|x| !x.is_finite()) {
                return Err(loc.at(
                    &format!("{p}.start_position_m"),
                    "must be three finite numbers (m)",
                ));
            }
            bounded_all(loc, &format!("{p}.start_position_m"), &sp)?;
        }
        if let Some(xy) = r.start_xy_m {
            if xy.iter().any(|x| !x.is_finite()) {
                return Err(loc.at(&format!("{p}.start_xy_m"), "must be two finite numbers (m)"));
            }
            bounded_all(loc, &format!("{p}.start_xy_m"), &xy)?;
        }
        if !r.start_yaw_deg.is_finite() {
            return Err(loc.at(&format!("{p}.start_yaw_deg"), "must be finite (deg)"));
        }
        if let Some(js) = &r.start_joints_rad
            && js.iter().any(|x| !x.is_finite())
        {
            return Err(loc.at(&format!("{p}.start_joints_rad"), "must be finite (rad)"));
        }
        if let Some(t) = &r.terrain
            && !terrain_names.contains(&t.as_str())
        {
            return Err(loc.at(
                &format!("{p}.terrain"),
                format!("unknown terrain '{t}' (terrains: {})", list(&terrain_names)),
            ));
        }
        analysis(loc, &format!("{p}.analysis"), &r.analysis)?;
        for (j, c) in r.contact_points.iter().enumerate() {
            if !["knees", "torso"].contains(&c.as_str()) {
                return Err(loc.at(
                    &format!("{p}.contact_points[{j}]"),
                    format!("unknown contact point set '{c}' (knees, torso)"),
                ));
            }
        }
        let kind = r
            .controller
            .kind
            .clone()
            .unwrap_or_else(|| "none".to_string());
        kind_keys(
            loc,
            &format!("{p}.controller"),
            "controller",
            &kind,
            CONTROLLER_KINDS,
            &r.controller.params,
        )?;
    }

    for (i, e) in f.events.iter().enumerate() {
        let p = format!("events[{i}]");
        if !(e.t_s.is_finite() && e.t_s >= 0.0) {
            return Err(loc.at(&format!("{p}.t_s"), "must be a finite time ≥ 0 (s)"));
        }
        bounded(loc, &format!("{p}.t_s"), e.t_s)?;
        if !robot_set.contains(e.robot.as_str()) {
            return Err(loc.at(
                &format!("{p}.robot"),
                format!(
                    "unknown robot '{}' (robots: {})",
                    e.robot,
                    list(&robot_names)
                ),
            ));
        }
        kind_keys(loc, &p, "event", &e.kind, EVENT_KINDS, &e.params)?;
    }
    if let Some(patterns) = &f.log.robots {
        for (i, pat) in patterns.iter().enumerate() {
            let kp = format!("log.robots[{i}]");
            let m = crate::names::RobotPattern::new(pat).map_err(|e| loc.at(&kp, e))?;
            if !robot_names.iter().any(|n| m.matches(n)) {
                return Err(loc.at(&kp, format!("'{pat}' matches no robot")));
            }
        }
    }
    Ok(())
}

/// `[robots.analysis]`: times, durations and forces > 0, a known direction,
/// 1 to 30 bisection steps.
fn analysis(
    loc: &Locator<'_>,
    p: &str,
    a: &crate::scenario::format::AnalysisSpec,
) -> Result<(), ScenarioError> {
    if let Some(t) = a.push_t_s
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(loc.at(
            &format!("{p}.push_t_s"),
            format!("must be a finite time ≥ 0 (s), got {t}"),
        ));
    }
    for (k, v) in [
        ("push_duration_s", a.push_duration_s),
        ("push_max_force_n", a.push_max_force_n),
        ("push_settle_s", a.push_settle_s),
    ] {
        if let Some(v) = v {
            positive(loc, &format!("{p}.{k}"), v)?;
        }
    }
    if let Some(n) = a.push_iterations
        && !(1..=30).contains(&n)
    {
        return Err(loc.at(
            &format!("{p}.push_iterations"),
            format!("must be 1 to 30, got {n}"),
        ));
    }
    if let Some(d) = &a.push_direction
        && super::push::PushDirection::from_name(d).is_none()
    {
        return Err(loc.at(
            &format!("{p}.push_direction"),
            format!("unknown direction '{d}' (left, right, forward, backward)"),
        ));
    }
    Ok(())
}

fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none defined".to_string()
    } else {
        names.join(", ")
    }
}

/// The largest magnitude of a position, length or size in a scenario (m).
pub const MAX_WORLD_M: f64 = 1.0e4;

/// The documented bound on a numeric key's magnitude, from its unit suffix
/// (scenarios/README.md, "Bounds"): lengths and positions 10 km, times
/// 10⁷ s, speeds 100 m/s, rates 10⁶ Hz, angular speeds 1000 rad/s,
/// forces 10⁷ N, masses 10⁵ kg, angles 10⁴ degrees, gains 10⁹; other numbers 10⁹.
pub fn bound_of(key: &str) -> (f64, &'static str) {
    let last = key.rsplit('.').next().unwrap_or(key);
    let last = last.split('[').next().unwrap_or(last).trim_matches('"');
    const TABLE: &[(&str, f64, &str)] = &[
        ("_mps2", 1.0e3, "m/s²"),
        ("_mps", 100.0, "m/s"),
        ("_radps", 1.0e3, "rad/s"),
        ("_hz", 1.0e6, "Hz"),
        ("_kg", 1.0e5, "kg"),
        ("_deg", 1.0e4, "°"),
        ("_n", 1.0e7, "N"),
        ("_s", 1.0e7, "s"),
        ("_m", MAX_WORLD_M, "m"),
    ];
    for (suffix, b, unit) in TABLE {
        if last.ends_with(suffix) {
            return (*b, unit);
        }
    }
    (1.0e9, "")
}

/// `x` within its key's documented bound ([`bound_of`]).
pub fn bounded(loc: &Locator<'_>, path: &str, x: f64) -> Result<(), ScenarioError> {
    let (b, unit) = bound_of(path);
    if x.abs() > b {
        return Err(loc.at(
            path,
            format!("{x:e} is beyond the bound ±{b:e} {unit} (scenarios/README.md, \"Bounds\")"),
        ));
    }
    Ok(())
}

fn bounded_all(loc: &Locator<'_>, path: &str, xs: &[f64]) -> Result<(), ScenarioError> {
    xs.iter().try_for_each(|x| bounded(loc, path, *x))
}

/// A name used in file names and channels: [`crate::names::check_name`].
pub fn name(loc: &Locator<'_>, path: &str, n: &str) -> Result<(), ScenarioError> {
    crate::names::check_name(n).map_err(|m| loc.at(path, m))
}

fn positive(loc: &Locator<'_>, path: &str, v: f64) -> Result<(), ScenarioError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(loc.at(path, format!("must be a finite number > 0, got {v}")))
    }
}

fn ground(loc: &Locator<'_>, path: &str, g: &GroundSpec) -> Result<(), ScenarioError> {
    match g {
        GroundSpec::Preset(name) => {
            if GROUND_PRESETS.contains(&name.as_str()) {
                Ok(())
            } else {
                Err(loc.at(
                    path,
                    format!(
                        "unknown ground preset '{name}' (presets: {})",
                        GROUND_PRESETS.join(", ")
                    ),
                ))
            }
        }
        GroundSpec::Custom(c) => {
            positive(
                loc,
                &format!("{path}.stiffness_n_per_m"),
                c.stiffness_n_per_m,
            )?;
            if !(c.damping_ns_per_m.is_finite() && c.damping_ns_per_m >= 0.0) {
                return Err(loc.at(
                    &format!("{path}.damping_ns_per_m"),
                    "must be finite and ≥ 0",
                ));
            }
            if !(c.friction.is_finite() && c.friction >= 0.0) {
                return Err(loc.at(&format!("{path}.friction"), "must be finite and ≥ 0"));
            }
            for (k, v, max) in [
                (
                    "stiffness_n_per_m",
                    c.stiffness_n_per_m,
                    MAX_STIFFNESS_N_PER_M,
                ),
                ("damping_ns_per_m", c.damping_ns_per_m, MAX_DAMPING_NS_PER_M),
                ("friction", c.friction, MAX_FRICTION),
            ] {
                if v > max {
                    return Err(loc.at(
                        &format!("{path}.{k}"),
                        format!(
                            "{v:e} is beyond the bound {max:e} (scenarios/README.md, \"Bounds\")"
                        ),
                    ));
                }
            }
            if let Some(law) = &c.law
                && !["linear", "hunt_crossley", "hybrid"].contains(&law.as_str())
            {
                return Err(loc.at(
                    &format!("{path}.law"),
                    format!("unknown law '{law}' (linear, hunt_crossley, hybrid)"),
                ));
            }
            if let Some(n) = c.exponent
                && !(n.is_finite() && (1.0..=4.0).contains(&n))
            {
                return Err(loc.at(&format!("{path}.exponent"), "must be from 1 to 4"));
            }
            if let Some(d) = c.hybrid_depth_m {
                positive(loc, &format!("{path}.hybrid_depth_m"), d)?;
                bounded(loc, &format!("{path}.hybrid_depth_m"), d)?;
            }
            Ok(())
        }
    }
}

fn kind_keys(
    loc: &Locator<'_>,
    path: &str,
    what: &str,
    kind: &str,
    kinds: &[(&str, &[KeySpec])],
    params: &BTreeMap<String, toml::Value>,
) -> Result<(), ScenarioError> {
    let Some((_, keys)) = kinds.iter().find(|(k, _)| *k == kind) else {
        let names: Vec<&str> = kinds.iter().map(|(k, _)| *k).collect();
        return Err(loc.at(
            &format!("{path}.kind"),
            format!("unknown {what} kind '{kind}' (kinds: {})", names.join(", ")),
        ));
    };
    for (k, v) in params {
        let kp = format!("{path}.{}", path_key(k));
        let Some((_, dom, _)) = keys.iter().find(|(name, _, _)| name == k) else {
            let names: Vec<&str> = keys.iter().map(|(n, _, _)| *n).collect();
            return Err(loc.at(
                &kp,
                format!(
                    "unknown key '{k}' for {what} kind '{kind}' (its keys: {})",
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        };
        check_domain(loc, &kp, *dom, v)?;
    }
    for (name, _, required) in keys.iter() {
        if *required && !params.contains_key(*name) {
            return Err(loc.at(path, format!("{what} kind '{kind}' needs the key '{name}'")));
        }
    }
    Ok(())
}

/// A TOML number (float or integer) as f64.
pub fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn check_domain(
    loc: &Locator<'_>,
    path: &str,
    dom: Domain,
    v: &toml::Value,
) -> Result<(), ScenarioError> {
    let bad = |msg: &str| Err(loc.at(path, msg.to_string()));
    match dom {
        Domain::Text => match v {
            toml::Value::String(_) => Ok(()),
            _ => bad("must be a string"),
        },
        Domain::Bool => match v {
            toml::Value::Boolean(_) => Ok(()),
            _ => bad("must be true or false"),
        },
        Domain::Tables => match v {
            toml::Value::Array(a) if a.iter().all(|x| x.is_table()) => Ok(()),
            _ => bad("must be an array of tables"),
        },
        Domain::Vec3 => match v {
            toml::Value::Array(a)
                if a.len() == 3 && a.iter().all(|x| as_f64(x).is_some_and(f64::is_finite)) =>
            {
                a.iter()
                    .try_for_each(|x| bounded(loc, path, as_f64(x).unwrap_or(0.0)))
            }
            _ => bad("must be an array of three finite numbers"),
        },
        Domain::Gains => match v {
            toml::Value::Array(a) => {
                if a.iter()
                    .all(|x| as_f64(x).is_some_and(|g| g.is_finite() && g >= 0.0))
                {
                    a.iter()
                        .try_for_each(|x| bounded(loc, path, as_f64(x).unwrap_or(0.0)))
                } else {
                    bad("must be numbers ≥ 0")
                }
            }
            _ => check_domain(loc, path, Domain::NonNegative, v),
        },
        Domain::Count => match v {
            toml::Value::Integer(i) if *i >= 1 => Ok(()),
            _ => bad("must be an integer ≥ 1"),
        },
        Domain::Positive | Domain::NonNegative | Domain::Finite => {
            let Some(x) = as_f64(v) else {
                return bad("must be a number");
            };
            let ok = x.is_finite()
                && match dom {
                    Domain::Positive => x > 0.0,
                    Domain::NonNegative => x >= 0.0,
                    _ => true,
                };
            if ok {
                bounded(loc, path, x)
            } else {
                Err(loc.at(
                    path,
                    format!(
                        "must be a finite number{}, got {x}",
                        match dom {
                            Domain::Positive => " > 0",
                            Domain::NonNegative => " ≥ 0",
                            _ => "",
                        }
                    ),
                ))
            }
        }
    }
}
