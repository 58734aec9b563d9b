//! `quadsim dynamics MODEL STATES.json [--fixed-base] [--package-path DIR]...`
//!
//! Reads states in the format of `../shared/oracle/oracle.py` and prints, for
//! each, the same quantities under the same keys as the oracle (ABA, RNEA, CRBA,
//! NLE, gravity vector, CoM, energies, link and joint poses), so that quadsim and
//! Pinocchio can be compared number for number on any URDF.
//!
//! Conventions are Pinocchio's (see [`quadsim_engine::model`]): floating base
//! `q = [x, y, z, qx, qy, qz, qw, joints…]`, `v = [v_lin, ω, q̇…]` with the base
//! velocities in the base frame, `a = dv/dt` (spatial acceleration of the base in
//! the base frame), joints in URDF document order, gravity `[0, 0, −9.81]` m/s².
//!
//! Unlike the oracle, which normalises the base quaternion silently, a quaternion
//! whose norm is off by more than [`QUAT_NORM_TOL`] is refused: it is a bug in
//! whatever wrote the state.
//!
//! With `--fixed-base`, `com` and `potential_energy` are the whole robot's, root
//! link included. Pinocchio's `centerOfMass` and `computePotentialEnergy` leave
//! out the root link welded to its universe joint, so for a fixed base the
//! oracle's `com` is the CoM of the moving links only (its `total_mass` still
//! counts the root): the two differ by exactly the root link's share
//! (`tests/oracle_agreement.rs` checks that identity). Every other number is
//! defined identically.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use clap::Args;
use quadsim_engine::model::{BaseKind, Model};
use quadsim_engine::{Data, aba, com, crba, energy, kinematics, nle, rnea};
use serde::{Deserialize, Serialize};

use crate::error::{CliError, bad};
use crate::model_source::load_model;
use crate::urdf::UrdfOptions;

/// Largest accepted `|‖quat‖ − 1|` of a floating base's quaternion.
pub const QUAT_NORM_TOL: f64 = 1e-6;

/// Arguments of `quadsim dynamics`.
#[derive(Debug, Args)]
pub struct DynamicsArgs {
    /// A URDF path or a built-in robot name.
    pub model: String,
    /// States in the format of `oracle.py`: a list of {q, v, tau, a?} or {"states": [...]}.
    pub states: PathBuf,
    /// Weld the root link to the world instead of a free joint.
    #[arg(long)]
    pub fixed_base: bool,
    /// Directory searched for `package://NAME/...` mesh URIs (repeatable).
    #[arg(long = "package-path", value_name = "DIR")]
    pub package_path: Vec<PathBuf>,
}

/// One state to evaluate, in Pinocchio's conventions (see the module doc).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    /// Optional label, carried for the reader only.
    pub name: Option<String>,
    /// Configuration (nq).
    pub q: Vec<f64>,
    /// Velocity (nv); base part in the base frame.
    pub v: Vec<f64>,
    /// Generalised force for ABA (nv); base part a wrench in the base frame.
    pub tau: Vec<f64>,
    /// Acceleration for RNEA (nv); `None`: RNEA is evaluated at ABA's result.
    pub a: Option<Vec<f64>>,
}

/// A state that does not fit the model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {why}")]
pub struct StateError {
    /// The field, e.g. `v` or `q[3..7]`.
    pub field: String,
    /// What is wrong.
    pub why: String,
}

/// World placement of a link frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FramePose {
    /// Frame origin in the world (m).
    pub translation: [f64; 3],
    /// Rotation taking link-frame vectors into the world, row-major.
    pub rotation: [[f64; 3]; 3],
    /// The same rotation as a unit quaternion (x, y, z, w), with the sign Eigen
    /// (and so Pinocchio) picks; see [`quat_xyzw`].
    pub quat_xyzw: [f64; 4],
}

/// World placement of a joint frame after the joint's motion (Pinocchio's `oMi`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointPose {
    /// Joint frame origin in the world (m).
    pub translation: [f64; 3],
    /// Rotation taking joint-frame vectors into the world, row-major.
    pub rotation: [[f64; 3]; 3],
}

/// Everything computed for one state; keys and meaning as in `oracle.py`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StateResult {
    /// The configuration used (base quaternion normalised) (nq).
    pub q_used: Vec<f64>,
    /// Velocity (nv).
    pub v: Vec<f64>,
    /// Generalised force given to ABA (nv).
    pub tau: Vec<f64>,
    /// Acceleration given to RNEA: the state's `a`, else ABA's result (nv).
    pub a_used: Vec<f64>,
    /// Forward dynamics `q̈ = M⁻¹ (τ − nle)` (nv).
    pub aba: Vec<f64>,
    /// Inverse dynamics `τ = M a_used + nle` (nv).
    pub rnea: Vec<f64>,
    /// Joint-space mass matrix, full symmetric (nv × nv).
    pub crba: Vec<Vec<f64>>,
    /// Nonlinear effects `C(q, v) v + g(q)` (nv).
    pub nle: Vec<f64>,
    /// Generalised gravity `g(q)` (nv).
    pub gravity: Vec<f64>,
    /// Whole-robot centre of mass in the world (m).
    pub com: [f64; 3],
    /// Kinetic energy (J).
    pub kinetic_energy: f64,
    /// Potential energy `−m g·c` (J), zero at the world origin.
    pub potential_energy: f64,
    /// World placement of every link, by name.
    pub frames: BTreeMap<String, FramePose>,
    /// World placement of every joint frame (`root_joint` for a floating base), by name.
    pub joints: BTreeMap<String, JointPose>,
    /// `max |rnea(aba(τ)) − τ|`, only when the state gave no `a`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rnea_residual: Option<f64>,
}

/// The model summary printed beside the results (`oracle.py --info`'s keys).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelInfo {
    /// Configuration size.
    pub nq: usize,
    /// Velocity size.
    pub nv: usize,
    /// Joint names in q/v order (`root_joint` first for a floating base).
    pub joint_names: Vec<String>,
    /// Link names.
    pub link_names: Vec<String>,
    /// Total mass (kg).
    pub total_mass: f64,
    /// Gravity (m/s², world).
    pub gravity: [f64; 3],
    /// Whether the root link is welded to the world.
    pub fixed_base: bool,
    /// The conventions, in words.
    pub conventions: String,
    /// The program that produced the numbers.
    #[serde(default)]
    pub engine: Option<String>,
}

/// The whole output: model summary and one result per state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Model summary.
    pub model: ModelInfo,
    /// One result per input state, in order.
    pub results: Vec<StateResult>,
}

/// Runs the command.
pub fn run(a: DynamicsArgs) -> Result<(), CliError> {
    let opts = UrdfOptions {
        package_paths: a.package_path.clone(),
    };
    let desc = load_model(&a.model, &opts)?;
    let base = if a.fixed_base {
        BaseKind::Fixed
    } else {
        BaseKind::Floating
    };
    let model = Model::from_description(&desc, base)
        .map_err(|e| bad(format!("model '{}': {e}", a.model)))?;
    let file = a.states.display().to_string();
    let text = crate::limits::read_text_capped(&a.states, crate::limits::MAX_TEXT_FILE_BYTES)
        .map_err(|e| bad(format!("{file}: cannot read: {e}")))?;
    let states = parse_states(&text, model.nv).map_err(|e| bad(format!("{file}: {e}")))?;
    let mut data = Data::new(&model);
    let mut results = Vec::with_capacity(states.len());
    for (i, s) in states.iter().enumerate() {
        let r =
            evaluate(&model, &mut data, s).map_err(|e| bad(format!("{file}: states[{i}].{e}")))?;
        results.push(r);
    }
    let report = Report {
        model: model_info(&model),
        results,
    };
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let io_err = |source| CliError::Io {
        path: "<stdout>".to_string(),
        source,
    };
    serde_json::to_writer(&mut out, &report).map_err(|e| io_err(e.into()))?;
    writeln!(out).map_err(io_err)?;
    Ok(())
}

/// The model summary for [`Report::model`].
pub fn model_info(model: &Model) -> ModelInfo {
    let mut joint_names = Vec::new();
    if model.is_floating() {
        joint_names.push("root_joint".to_string());
    }
    joint_names.extend(model.movable_joint_names().iter().map(|s| s.to_string()));
    ModelInfo {
        nq: model.nq,
        nv: model.nv,
        joint_names,
        link_names: model.frames.iter().map(|f| f.name.clone()).collect(),
        total_mass: model.total_mass,
        gravity: model.gravity.to_array(),
        fixed_base: !model.is_floating(),
        conventions: "q=[x,y,z,qx,qy,qz,qw,joints]; v=[v_lin(base frame), w(base frame), qdot]; \
                      a = d/dt v (spatial, base frame); joints in URDF document order"
            .to_string(),
        engine: Some(format!("quadsim {}", env!("CARGO_PKG_VERSION"))),
    }
}

/// Checks a state against the model: sizes, finite numbers, a unit quaternion.
///
/// # Errors
/// [`StateError`] naming the field (`q`, `v[4]`, `q[3..7]`, …).
pub fn check_state(model: &Model, s: &State) -> Result<(), StateError> {
    let err = |field: String, why: String| StateError { field, why };
    let mut fields = vec![
        ("q", &s.q, model.nq),
        ("v", &s.v, model.nv),
        ("tau", &s.tau, model.nv),
    ];
    if let Some(a) = &s.a {
        fields.push(("a", a, model.nv));
    }
    for (name, x, n) in fields {
        if x.len() != n {
            return Err(err(
                name.to_string(),
                format!("expected {n} values, got {}", x.len()),
            ));
        }
        if let Some(k) = x.iter().position(|v| !v.is_finite()) {
            return Err(err(
                format!("{name}[{k}]"),
                format!("{} is not finite", x[k]),
            ));
        }
    }
    if model.is_floating() {
        let norm = base_quat_norm(&s.q);
        if (norm - 1.0).abs() > QUAT_NORM_TOL {
            return Err(err(
                "q[3..7]".to_string(),
                format!(
                    "base quaternion has norm {norm}, not 1 (tolerance {QUAT_NORM_TOL}); \
                     quadsim does not normalise it silently"
                ),
            ));
        }
    }
    Ok(())
}

/// Norm of a floating base's quaternion `q[3..7]`.
fn base_quat_norm(q: &[f64]) -> f64 {
    q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Evaluates every quantity of [`StateResult`] for one state. This is the
/// function the CLI runs and the Pinocchio agreement test checks.
///
/// # Errors
/// [`StateError`] from [`check_state`]; nothing is computed then.
pub fn evaluate(model: &Model, data: &mut Data, s: &State) -> Result<StateResult, StateError> {
    check_state(model, s)?;
    let mut q = s.q.clone();
    if model.is_floating() {
        let norm = base_quat_norm(&q);
        q[3..7].iter_mut().for_each(|x| *x /= norm);
    }
    let (v, tau) = (&s.v, &s.tau);
    let nv = model.nv;
    let ddq = aba::aba(model, data, &q, v, tau).to_vec();
    let a_used = s.a.clone().unwrap_or_else(|| ddq.clone());
    let tau_rnea = rnea::rnea(model, data, &q, v, &a_used).to_vec();
    let m = crba::crba(model, data, &q);
    let crba_rows = m.chunks(nv).map(|r| r.to_vec()).collect();
    let nle_v = nle::nonlinear_effects(model, data, &q, v).to_vec();
    let grav = nle::generalized_gravity(model, data, &q).to_vec();
    kinematics::forward_kinematics(model, data, &q, v);
    let c = com::center_of_mass(model, data);
    let ke = energy::kinetic_energy(model, data, v);
    let pe = energy::potential_energy(model, data);
    let rows = |r: glam::DMat3| {
        let t = r.transpose(); // columns of the transpose are the rows
        [
            t.x_axis.to_array(),
            t.y_axis.to_array(),
            t.z_axis.to_array(),
        ]
    };
    let frames = (0..model.frames.len())
        .map(|fi| {
            let x = kinematics::frame_pose(model, data, fi);
            let pose = FramePose {
                translation: x.trans.to_array(),
                rotation: rows(x.rot),
                quat_xyzw: quat_xyzw(x.rot),
            };
            (model.frames[fi].name.clone(), pose)
        })
        .collect();
    let first = if model.is_floating() { 0 } else { 1 };
    let joints = (first..model.nbodies)
        .map(|b| {
            let x = data.pose[b];
            let pose = JointPose {
                translation: x.trans.to_array(),
                rotation: rows(x.rot),
            };
            (model.joint_name[b].clone(), pose)
        })
        .collect();
    let rnea_residual = s.a.is_none().then(|| {
        tau_rnea
            .iter()
            .zip(tau)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    });
    Ok(StateResult {
        q_used: q,
        v: v.clone(),
        tau: tau.clone(),
        a_used,
        aba: ddq,
        rnea: tau_rnea,
        crba: crba_rows,
        nle: nle_v,
        gravity: grav,
        com: c.to_array(),
        kinetic_energy: ke,
        potential_energy: pe,
        frames,
        joints,
        rnea_residual,
    })
}

/// The unit quaternion (x, y, z, w) of a rotation, with Eigen's sign: `q` and
/// `−q` are the same rotation, and Eigen's matrix-to-quaternion conversion
/// (which Pinocchio's output uses) makes `w` positive when the trace is
/// positive, else the component of the largest diagonal entry. That component
/// is at least ½ in size, so the choice is robust to rounding.
pub fn quat_xyzw(rot: glam::DMat3) -> [f64; 4] {
    let q = glam::DQuat::from_mat3(&rot).normalize().to_array();
    let d = [rot.x_axis.x, rot.y_axis.y, rot.z_axis.z];
    let pivot = if d[0] + d[1] + d[2] > 0.0 {
        3
    } else {
        let mut i = 0;
        if d[1] > d[0] {
            i = 1;
        }
        if d[2] > d[i] {
            i = 2;
        }
        i
    };
    if q[pivot] < 0.0 { q.map(|x| -x) } else { q }
}

/// Reads the states of a states file: a list of states, `{"states": [...]}`,
/// or one state object. Missing `v` and `tau` are `nv` zeros (as in `oracle.py`);
/// sizes are checked later against the model by [`check_state`].
///
/// The text is read as JSON5, a superset of JSON, so that the `NaN` and
/// `Infinity` tokens Python's `json` writes are reported by field, not as a
/// syntax error.
///
/// # Errors
/// A message naming the field, e.g. `states[2].q[4]: expected a number, got a string`.
pub fn parse_states(text: &str, nv: usize) -> Result<Vec<State>, String> {
    let doc: Json = json5::from_str(text).map_err(|e| format!("not valid JSON: {e}"))?;
    let list = match &doc {
        Json::Arr(items) => items.as_slice(),
        Json::Obj(fields) => match fields.iter().find(|(k, _)| k == "states") {
            Some((_, Json::Arr(items))) => items.as_slice(),
            Some((_, other)) => {
                return Err(format!("states: expected a list, got {}", other.kind()));
            }
            None => std::slice::from_ref(&doc),
        },
        other => {
            return Err(format!(
                "expected a list of states or {{\"states\": [...]}}, got {}",
                other.kind()
            ));
        }
    };
    list.iter()
        .enumerate()
        .map(|(i, st)| parse_state(st, nv).map_err(|e| format!("states[{i}].{e}")))
        .collect()
}

fn parse_state(st: &Json, nv: usize) -> Result<State, String> {
    let Json::Obj(fields) = st else {
        return Err(format!(
            "q: expected a state object {{q, v, tau, a?}}, got {}",
            st.kind()
        ));
    };
    let get = |k: &str| fields.iter().find(|(n, _)| n == k).map(|(_, v)| v);
    let numbers = |k: &str, j: &Json| -> Result<Vec<f64>, String> {
        let Json::Arr(items) = j else {
            return Err(format!("{k}: expected a list of numbers, got {}", j.kind()));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, x)| match x {
                Json::Num(v) if v.is_finite() => Ok(*v),
                Json::Num(v) => Err(format!("{k}[{i}]: {v} is not a finite number")),
                other => Err(format!("{k}[{i}]: expected a number, got {}", other.kind())),
            })
            .collect()
    };
    let q = match get("q") {
        Some(j) => numbers("q", j)?,
        None => return Err("q: missing".to_string()),
    };
    let optional = |k: &str| -> Result<Option<Vec<f64>>, String> {
        match get(k) {
            None | Some(Json::Null) => Ok(None),
            Some(j) => numbers(k, j).map(Some),
        }
    };
    let name = match get("name") {
        Some(Json::Str(s)) => Some(s.clone()),
        _ => None,
    };
    Ok(State {
        name,
        v: optional("v")?.unwrap_or_else(|| vec![0.0; nv]),
        tau: optional("tau")?.unwrap_or_else(|| vec![0.0; nv]),
        q,
        a: optional("a")?,
    })
}

/// A JSON value that keeps non-finite numbers (`serde_json::Value` cannot).
#[derive(Clone, Debug, PartialEq)]
enum Json {
    Null,
    Bool,
    Num(f64),
    Str(String),
    Arr(Vec<Json>),
    Obj(Vec<(String, Json)>),
}

impl Json {
    fn kind(&self) -> &'static str {
        match self {
            Json::Null => "null",
            Json::Bool => "a boolean",
            Json::Num(_) => "a number",
            Json::Str(_) => "a string",
            Json::Arr(_) => "a list",
            Json::Obj(_) => "an object",
        }
    }
}

impl<'de> Deserialize<'de> for Json {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Json;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a JSON value")
            }
            fn visit_bool<E>(self, _: bool) -> Result<Json, E> {
                Ok(Json::Bool)
            }
            fn visit_i64<E>(self, v: i64) -> Result<Json, E> {
                Ok(Json::Num(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Json, E> {
                Ok(Json::Num(v as f64))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Json, E> {
                Ok(Json::Num(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<Json, E> {
                Ok(Json::Str(v.to_string()))
            }
            fn visit_unit<E>(self) -> Result<Json, E> {
                Ok(Json::Null)
            }
            fn visit_none<E>(self) -> Result<Json, E> {
                Ok(Json::Null)
            }
            fn visit_some<D: serde::Deserializer<'de>>(self, d: D) -> Result<Json, D::Error> {
                Json::deserialize(d)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Json, A::Error> {
                let mut out = Vec::new();
                while let Some(x) = a.next_element()? {
                    out.push(x);
                }
                Ok(Json::Arr(out))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<Json, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = a.next_entry::<String, Json>()? {
                    out.push((k, v));
                }
                Ok(Json::Obj(out))
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_token_is_reported_by_field() {
        let e = parse_states(r#"[{"q": [0, NaN], "v": [], "tau": []}]"#, 0).unwrap_err();
        assert_eq!(e, "states[0].q[1]: NaN is not a finite number");
        let e = parse_states(
            r#"{"states": [{"q": [0]}, {"q": [1], "v": [-Infinity]}]}"#,
            1,
        )
        .unwrap_err();
        assert_eq!(e, "states[1].v[0]: -inf is not a finite number");
    }

    #[test]
    fn accepts_the_three_layouts_and_defaults_v_tau_to_zero() {
        let one = parse_states(r#"{"q": [1, 2], "v": [3]}"#, 1).unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].tau, vec![0.0]);
        let list = parse_states(r#"[{"q": [1]}, {"q": [2], "a": null}]"#, 1).unwrap();
        assert_eq!(list.len(), 2);
        assert_eq!(list[0].v, vec![0.0]);
        assert!(list[1].a.is_none());
        let wrapped = parse_states(r#"{"states": [{"q": [1], "a": [0.5]}]}"#, 1).unwrap();
        assert_eq!(wrapped[0].a, Some(vec![0.5]));
    }

    #[test]
    fn wrong_types_name_the_field() {
        let e = parse_states(r#"[{"q": [0, "x"]}]"#, 1).unwrap_err();
        assert_eq!(e, "states[0].q[1]: expected a number, got a string");
        let e = parse_states(r#"[{"v": [0]}]"#, 1).unwrap_err();
        assert_eq!(e, "states[0].q: missing");
        assert!(
            parse_states("[{", 1)
                .unwrap_err()
                .starts_with("not valid JSON")
        );
    }
}
