//! `[robots.actuators]` → one [`ActuatorSpec`] per joint (see
//! `docs/actuators.md` and `scenarios/README.md`).
//!
//! Resolution per joint: the kind (the joint's own `kind`, else the table's,
//! else the robot's default kind, [`default_kind`]), then the robot's default set for that kind
//! ([`ActuatorDefaults`], which a built-in robot states; other robots: the joint's effort and velocity limits
//! as stall torque and no-load speed), then the table's parameters, then the
//! joint's overrides (`joints.NAME`: first the `*suffix` patterns, in name
//! order, then the exact name, so the most specific entry wins).

use std::collections::BTreeMap;

use quadsim_engine::Model;
use quadsim_engine::actuator_model::{ActuatorDefaults, ActuatorKind, ActuatorSpec};

use crate::scenario::format::ActuatorsSpec;
use crate::scenario::spans::path_key;
use crate::scenario::validate::as_f64;
use crate::scenario::{Locator, ScenarioError};

/// The keys of an actuator table beside `kind` (and `joints` at the top).
pub const ACTUATOR_KEYS: &[&str] = &[
    "stall_torque_nm",
    "no_load_speed_radps",
    "gear_ratio",
    "rotor_inertia_kgm2",
    "viscous_nms_per_rad",
    "coulomb_nm",
    "bandwidth_hz",
    "latency_ticks",
    "servo_kp_nm_per_rad",
    "servo_kd_nms_per_rad",
    "servo_rate_hz",
];

fn parse_kind(loc: &Locator<'_>, kp: &str, v: &toml::Value) -> Result<ActuatorKind, ScenarioError> {
    match v.as_str() {
        Some("ideal") => Ok(ActuatorKind::Ideal),
        Some("dc_motor") => Ok(ActuatorKind::DcMotor),
        Some("servo") => Ok(ActuatorKind::Servo),
        _ => Err(loc.at(
            kp,
            format!("unknown actuator kind {v}: expected \"ideal\", \"dc_motor\" or \"servo\""),
        )),
    }
}

/// Checks the keys of one table (`path` its key path) and returns its kind.
fn check_table(
    loc: &Locator<'_>,
    path: &str,
    t: &BTreeMap<String, toml::Value>,
) -> Result<Option<ActuatorKind>, ScenarioError> {
    for (k, v) in t {
        let kp = format!("{path}.{}", path_key(k));
        if k == "kind" {
            continue;
        }
        if !ACTUATOR_KEYS.contains(&k.as_str()) {
            return Err(loc.at(
                &kp,
                format!(
                    "unknown actuator key '{k}' (keys: kind, {}{})",
                    ACTUATOR_KEYS.join(", "),
                    if path.ends_with(".actuators") {
                        ", joints"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let ok = match k.as_str() {
            "latency_ticks" => v.as_integer().is_some_and(|n| (0..=10_000).contains(&n)),
            _ => as_f64(v).is_some_and(|x| !x.is_nan()),
        };
        if !ok {
            return Err(loc.at(
                &kp,
                if k == "latency_ticks" {
                    "must be an integer number of control ticks in 0..=10000".to_string()
                } else {
                    format!("must be a number (got {v})")
                },
            ));
        }
    }
    t.get("kind")
        .map(|v| parse_kind(loc, &format!("{path}.kind"), v))
        .transpose()
}

/// Writes the table's parameters into `spec`.
fn apply(spec: &mut ActuatorSpec, t: &BTreeMap<String, toml::Value>) {
    for (k, v) in t {
        let x = as_f64(v).unwrap_or(0.0);
        let (m, s) = (&mut spec.motor, &mut spec.servo);
        match k.as_str() {
            "stall_torque_nm" => m.stall_torque_nm = x,
            "no_load_speed_radps" => m.no_load_speed_radps = x,
            "gear_ratio" => m.gear_ratio = x,
            "rotor_inertia_kgm2" => m.rotor_inertia_kgm2 = x,
            "viscous_nms_per_rad" => m.viscous_nms_per_rad = x,
            "coulomb_nm" => m.coulomb_nm = x,
            "bandwidth_hz" => m.bandwidth_hz = x,
            "latency_ticks" => m.latency_ticks = v.as_integer().unwrap_or(0) as usize,
            "servo_kp_nm_per_rad" => s.kp_nm_per_rad = x,
            "servo_kd_nms_per_rad" => s.kd_nms_per_rad = x,
            "servo_rate_hz" => s.rate_hz = x,
            _ => {}
        }
    }
}

fn matches(pattern: &str, name: &str) -> bool {
    match pattern.strip_prefix('*') {
        Some(suffix) => name.ends_with(suffix),
        None => pattern == name,
    }
}

/// The kind a joint gets when the scenario names none: the robot's default
/// kind (`defaults`: quad16's DC motors, `docs/actuators.md`; quad12's ideal
/// sources), `ideal` for a robot that states none, and `ideal` whenever the
/// controller imposes the motion instead of commanding torques
/// (`imposed_motion`: the prescribed controller's hybrid mode, Study B's way
/// of walking quad12).
pub fn default_kind(defaults: Option<&ActuatorDefaults>, imposed_motion: bool) -> ActuatorKind {
    match defaults {
        Some(d) if !imposed_motion => d.kind,
        _ => ActuatorKind::Ideal,
    }
}

/// The actuator of each joint of `model` (its robot's default actuators
/// `defaults`, [`quadsim_engine::robots::actuator_defaults`]) from
/// the robot's `[robots.actuators]` at key path `p.actuators`, joints of no
/// stated kind taking `default` ([`default_kind`]); `None` when every joint
/// is ideal. Errors name the key path of the offending entry.
///
/// # Errors
/// Unknown keys or kinds, non-numbers, a `joints` entry matching no joint,
/// or parameters a motor cannot have (e.g. a zero stall torque).
pub fn joint_actuators(
    loc: &Locator<'_>,
    p: &str,
    spec: &ActuatorsSpec,
    defaults: Option<&ActuatorDefaults>,
    model: &Model,
    default: ActuatorKind,
) -> Result<Option<Vec<ActuatorSpec>>, ScenarioError> {
    let path = format!("{p}.actuators");
    let all_kind = check_table(loc, &path, &spec.params)?.unwrap_or(default);
    let names: Vec<String> = (model.base_nv()..model.nv)
        .map(|vi| model.joint_name[model.v_body[vi]].clone())
        .collect();
    let mut overrides = Vec::new();
    for (pat, t) in &spec.joints {
        let jp = format!("{path}.joints.{}", path_key(pat));
        let kind = check_table(loc, &jp, t)?;
        if !names.iter().any(|n| matches(pat, n)) {
            return Err(loc.at(
                &jp,
                format!(
                    "'{pat}' names no joint of this robot (joints: {}; '*suffix' matches by the name's end)",
                    names.join(", ")
                ),
            ));
        }
        overrides.push((pat, jp, kind, t));
    }
    // Exact names after patterns, so they win.
    overrides.sort_by_key(|(pat, ..)| !pat.starts_with('*'));
    let mut out = Vec::with_capacity(names.len());
    for (j, name) in names.iter().enumerate() {
        let mine: Vec<_> = overrides
            .iter()
            .filter(|(pat, ..)| matches(pat, name))
            .collect();
        let kind = mine.iter().rev().find_map(|o| o.2).unwrap_or(all_kind);
        let iv = model.base_nv() + j;
        let (effort, velocity) = (model.effort_limit[iv], model.velocity_limit[iv]);
        let mut s = defaults.map_or_else(
            || ActuatorSpec::from_limits(kind, effort, velocity),
            |d| d.spec(kind, effort, velocity),
        );
        apply(&mut s, &spec.params);
        for o in &mine {
            apply(&mut s, o.3);
        }
        if let Err((field, msg)) = s.check() {
            let origin = mine
                .iter()
                .rev()
                .find(|o| o.3.contains_key(field))
                .map(|o| format!("{}.{field}", o.1))
                .unwrap_or_else(|| {
                    if spec.params.contains_key(field) {
                        format!("{path}.{field}")
                    } else {
                        path.clone()
                    }
                });
            return Err(loc.at(
                &origin,
                format!("joint '{name}' ({kind:?} actuator): {field} {msg}"),
            ));
        }
        out.push(s);
    }
    Ok((!out.iter().all(|s| s.kind == ActuatorKind::Ideal)).then_some(out))
}
