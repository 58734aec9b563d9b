//! The report's actuator section: for a robot with motor or servo actuators
//! (`[robots.actuators]`), each joint's capacity (stall torque) against the
//! torque its controller or servo loop demanded, as Study B sizes its knee
//! against the Futaba S3003 (reference.md, Table 4).

use std::fmt::Write as _;

use serde_json::Value;

/// Peak demand over capacity above which a joint counts as short of torque.
const SHORT: f64 = 1.0;

/// Writes the section when some joint of `robot` (its `summary.json`
/// object) has a motor or servo; nothing otherwise.
pub fn actuator_capacity(out: &mut String, robot: &Value) {
    let joints: Vec<&Value> = robot["actuators"]["joints"]
        .as_array()
        .into_iter()
        .flatten()
        .collect();
    let motors: Vec<&Value> = joints
        .iter()
        .copied()
        .filter(|j| j["kind"].as_str().is_some_and(|k| k != "ideal"))
        .collect();
    if motors.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nActuators (`docs/actuators.md`): capacity is the stall torque τ_s at the joint; *applied* is the motor's torque inside its torque–speed envelope; *demanded* is what the controller or the servo's own loop asked for (before the envelope, at most the joint's effort limit).\n"
    );
    let _ = writeln!(
        out,
        "| joint | kind | capacity (N·m) | peak applied (N·m) | peak demanded (N·m) | demanded / capacity | time at envelope (s) | envelope hits |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|");
    let f = |v: &Value, d: usize| v.as_f64().map_or("—".into(), |x| format!("{x:.d$}"));
    for j in &motors {
        let ratio = match (j["peak_demand_nm"].as_f64(), j["torque_limit_nm"].as_f64()) {
            (Some(d), Some(c)) if c > 0.0 => format!("{:.2}", d / c),
            _ => "—".into(),
        };
        let _ = writeln!(
            out,
            "| `{}` | {} | {} | {} | {} | {} | {} | {} |",
            j["joint"].as_str().unwrap_or("?"),
            j["kind"].as_str().unwrap_or("?"),
            f(&j["torque_limit_nm"], 3),
            f(&j["peak_torque_nm"], 3),
            f(&j["peak_demand_nm"], 3),
            ratio,
            f(&j["time_at_envelope_limit_s"], 3),
            j["envelope_limit_hits"].as_u64().unwrap_or(0),
        );
    }
    let knees: Vec<&&Value> = motors
        .iter()
        .filter(|j| j["joint"].as_str().is_some_and(|n| n.ends_with("knee")))
        .collect();
    let peak = |key: &str| {
        knees
            .iter()
            .filter_map(|j| j[key].as_f64())
            .fold(f64::NAN, f64::max)
    };
    let (demand, capacity) = (peak("peak_demand_nm"), peak("torque_limit_nm"));
    if demand.is_finite() && capacity.is_finite() && capacity > 0.0 {
        let verdict = if demand / capacity > SHORT {
            format!(
                "falls short of the peak demand, {demand:.3} N·m, by a factor of {:.1}",
                demand / capacity
            )
        } else {
            format!("covers the peak demand, {demand:.3} N·m")
        };
        let fell = if robot["fell"].as_bool() == Some(true) {
            format!(
                " The robot fell at {} s.",
                robot["fell_at_s"]
                    .as_f64()
                    .map_or("?".into(), |t| format!("{t:.2}"))
            )
        } else {
            String::new()
        };
        let at_envelope = knees
            .iter()
            .filter_map(|j| j["time_at_envelope_limit_s"].as_f64())
            .fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "\nKnees: the actuators' capacity, {capacity:.3} N·m, {verdict}; a knee spent up to {at_envelope:.2} s at its envelope.{fell} Study B sizes its knee against the Futaba S3003's 300 N·mm at 6 V, which its own knee peak (300 N·mm at foot strike) just reaches."
        );
    }
}
