//! `log.mcap` read back with the `mcap` crate: channels, schemas, message
//! counts (⌊steps / decimation⌋ + 1, t = 0 included), decoded values against
//! the simulation's state, Newton's law for the logged CoM acceleration,
//! byte-identical files across runs, `quadsim report` and `quadsim export`.

use std::path::{Path, PathBuf};
use std::process::Command;

use quadsim::log::read::{LogContents, read_log};
use quadsim::log::schema::Schema;
use quadsim::log::{RunOutcome, start_run_log};
use quadsim::scenario::parse_scenario;
use quadsim::world::{Overrides, build_world};
use serde_json::Value;

const PER_STEP: [&str; 8] = [
    "base_pose",
    "base_twist",
    "attitude",
    "com",
    "joint_states",
    "joint_commands",
    "feet",
    "virtual_wrench",
];

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadsim-log-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Two quad16s on concrete under joint PD; `quiet` is not logged per step.
fn scenario(duration_s: f64, extra_world: &str) -> String {
    format!(
        r#"format_version = 1
[world]
name = "logtest"
dt_s = 0.0005
duration_s = {duration_s}
controller_rate_hz = 500
seed = 3
default_ground = "concrete"
{extra_world}

[[robots]]
name = "rex"
model = "quad16"
start_position_m = [0.0, 0.0, 0.62]
[robots.controller]
kind = "joint_pd"
bandwidth_hz = 3.0

[[robots]]
name = "quiet"
model = "quad12"
start_position_m = [3.0, 0.0, 0.5]
log = false
"#
    )
}

/// Checks `v` against a JSON Schema's `type`, `properties` (every key of an
/// object must be declared) and `items`, recursively. Returns the path of the
/// first mismatch.
fn conforms(v: &Value, schema: &Value, path: &str) -> Result<(), String> {
    let types: Vec<&str> = match &schema["type"] {
        Value::String(s) => vec![s.as_str()],
        Value::Array(a) => a.iter().filter_map(Value::as_str).collect(),
        _ => vec![],
    };
    let kind = match v {
        Value::Null => "null",
        Value::Bool(_) => "boolean",
        Value::Number(n) if n.is_u64() || n.is_i64() => "integer",
        Value::Number(_) => "number",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    };
    let ok = types.is_empty()
        || types.contains(&kind)
        || (kind == "integer" && types.contains(&"number"));
    if !ok {
        return Err(format!("{path}: {kind} where the schema says {types:?}"));
    }
    match v {
        Value::Object(map) => {
            if let Some(props) = schema["properties"].as_object() {
                for (k, x) in map {
                    let sub = props
                        .get(k)
                        .ok_or_else(|| format!("{path}.{k}: not in the schema"))?;
                    conforms(x, sub, &format!("{path}.{k}"))?;
                }
            }
        }
        Value::Array(a) if schema.get("items").is_some() => {
            for (i, x) in a.iter().enumerate() {
                conforms(x, &schema["items"], &format!("{path}[{i}]"))?;
            }
        }
        _ => {}
    }
    Ok(())
}

fn last(c: &LogContents, topic: &str) -> Value {
    c.topic(topic).last().unwrap().json().unwrap()
}

fn v3(v: &Value) -> [f64; 3] {
    [
        v["x"].as_f64().unwrap(),
        v["y"].as_f64().unwrap(),
        v["z"].as_f64().unwrap(),
    ]
}

#[test]
fn channels_counts_schemas_and_values_match_the_simulation() {
    let dir = tmp("roundtrip");
    // 403 steps at a decimation of 4: ⌊403/4⌋ + 1 = 101 samples, the last at step 400
    let src = scenario(0.2015, "");
    let scn = parse_scenario(&dir.join("logtest.toml"), src.clone()).unwrap();
    let mut world = build_world(&scn, Overrides::default()).unwrap();
    let rex = world.robots[0].1;
    let q0 = world.sim.robot(rex).unwrap().state.q.clone();
    let path = dir.join("log.mcap");
    let log = start_run_log(&scn, &mut world, &path, 4).unwrap();
    assert_eq!(world.steps, 403);
    world.sim.run(400);
    let q400 = world.sim.robot(rex).unwrap().state.q.clone();
    world.sim.run(3);
    log.finish(&mut world, &RunOutcome::default()).unwrap();
    let c = read_log(&path).unwrap();
    assert_eq!(c.error, None);

    // per-step channels of the logged robot only, with their schemas
    for s in PER_STEP {
        let topic = format!("/rex/{s}");
        let msgs: Vec<_> = c.topic(&topic).collect();
        assert_eq!(msgs.len(), 403 / 4 + 1, "{topic}");
        for (k, m) in msgs.iter().enumerate() {
            assert_eq!(m.log_time_ns, k as u64 * 4 * 500_000, "{topic} #{k}");
        }
        assert_eq!(c.topic(&format!("/quiet/{s}")).count(), 0);
    }
    assert_eq!(c.topic("/tf").count(), 403 / 4 + 1);
    assert_eq!(c.topic("/scene").count(), 1);
    assert_eq!(c.topic("/terrain").count(), 1);
    assert_eq!(c.topic("/rex/metrics").count(), 1);
    assert_eq!(c.topic("/quiet/metrics").count(), 1);
    // the schemas stored are ours (protobuf descriptor sets for the per-step
    // channels, JSON Schemas for the rest), and every message, decoded by the
    // schema stored in the log, has the shape its JSON Schema documents
    for schema in Schema::ALL {
        let stored = &c.schemas[schema.name()];
        assert_eq!(
            stored.encoding,
            schema.schema_encoding(),
            "{}",
            schema.name()
        );
        assert_eq!(stored.data, schema.data(), "{}", schema.name());
    }
    for m in &c.messages {
        let schema = Schema::ALL.iter().find(|s| s.name() == m.schema).unwrap();
        assert_eq!(m.descriptor.is_some(), schema.is_protobuf(), "{}", m.topic);
        conforms(&m.json().unwrap(), &schema.json(), &m.topic).unwrap();
    }
    // Foxglove's own types (the `foxglove` crate's prost structs, not our
    // decoder) read the foxglove.* channels to the same values
    {
        use prost::Message as _;
        let m = c.topic("/rex/base_pose").last().unwrap();
        let p = foxglove::schemas::PoseInFrame::decode(&m.data[..]).unwrap();
        let j = m.json().unwrap();
        let pos = p.pose.unwrap().position.unwrap();
        assert_eq!([pos.x, pos.y, pos.z], v3(&j["pose"]["position"]));
        assert_eq!(p.frame_id, "world");
        let t = p.timestamp.unwrap();
        assert_eq!(
            u64::from(t.sec()) * 1_000_000_000 + u64::from(t.nsec()),
            m.log_time_ns
        );
        let m = c.topic("/tf").last().unwrap();
        let tf = foxglove::schemas::FrameTransforms::decode(&m.data[..]).unwrap();
        let j = m.json().unwrap();
        assert_eq!(
            tf.transforms.len(),
            j["transforms"].as_array().unwrap().len()
        );
        for (a, b) in tf
            .transforms
            .iter()
            .zip(j["transforms"].as_array().unwrap())
        {
            assert_eq!(a.child_frame_id, b["child_frame_id"].as_str().unwrap());
            assert_eq!(a.parent_frame_id, b["parent_frame_id"].as_str().unwrap());
            let r = a.rotation.unwrap();
            assert_eq!(r.w, b["rotation"]["w"].as_f64().unwrap());
        }
    }

    // the first sample is the start state, the last the final state, exactly
    let sim = world.sim.robot(rex).unwrap();
    for (k, qk) in [(0usize, &q0), (100, &q400)] {
        let m = c.topic("/rex/base_pose").nth(k).unwrap().json().unwrap();
        let p = v3(&m["pose"]["position"]);
        assert_eq!(p, [qk[0], qk[1], qk[2]], "base position at sample {k}");
        let o = &m["pose"]["orientation"];
        for (i, key) in ["x", "y", "z", "w"].iter().enumerate() {
            assert!((o[key].as_f64().unwrap() - qk[3 + i]).abs() < 1e-15);
        }
    }
    // step 403 is not a multiple of 4: no sample of the final state
    assert_eq!(world.sim.clock().step, 403);
    let js = last(&c, "/rex/joint_states");
    let names: Vec<&str> = js["name"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(names.len(), sim.model.nv - 6);
    assert_eq!(names[2], sim.model.joint_name[sim.model.v_body[8]]);
    let cmd = last(&c, "/rex/joint_commands");
    let targets = sim.run.controller.joint_targets().unwrap();
    let logged: Vec<f64> = cmd["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(logged, targets);
    // feet carry the robot: the normal forces of a standing robot add up to its weight (±30 %, it still settles)
    let feet = last(&c, "/rex/feet");
    let fz: f64 = feet["feet"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["force"]["z"].as_f64().unwrap())
        .sum();
    let weight = sim.model.total_mass * 9.81;
    assert!(
        (fz - weight).abs() < 0.3 * weight,
        "Σfz {fz} vs weight {weight}"
    );
    assert!(feet["feet"][0]["gait_phase"].is_null());
    assert!(last(&c, "/rex/virtual_wrench")["force"].is_null());
    // /tf holds every link of the logged robot only, as a tree whose chains
    // compose to the links' world poses (double precision)
    let tf = last(&c, "/tf");
    let tfs = tf["transforms"].as_array().unwrap();
    assert_eq!(tfs.len(), sim.model.frames.len());
    let mut data = quadsim_engine::Data::new(&sim.model);
    quadsim_engine::kinematics::forward_kinematics_pos(&sim.model, &mut data, &q400);
    let find = |child: &str| tfs.iter().find(|t| t["child_frame_id"] == child).unwrap();
    for (f, frame) in sim.model.frames.iter().enumerate() {
        let (mut p, mut r) = (glam::DVec3::ZERO, glam::DQuat::IDENTITY);
        let mut at = format!("rex/{}", frame.name);
        let mut depth = 0;
        while at != "world" {
            let t = find(&at);
            let o = &t["rotation"];
            let q = glam::DQuat::from_xyzw(
                o["x"].as_f64().unwrap(),
                o["y"].as_f64().unwrap(),
                o["z"].as_f64().unwrap(),
                o["w"].as_f64().unwrap(),
            );
            let tr = glam::DVec3::from_array(v3(&t["translation"]));
            // parent_from_frame = parent_from_child ∘ child_from_frame
            p = tr + q * p;
            r = q * r;
            at = t["parent_frame_id"].as_str().unwrap().to_string();
            depth += 1;
            assert!(depth < 20, "cycle in /tf");
        }
        let want = quadsim_engine::kinematics::frame_pose(&sim.model, &data, f);
        assert!(
            (p - want.trans).length() < 1e-12,
            "{}: {p} vs {}",
            frame.name,
            want.trans
        );
        let err = (glam::DMat3::from_quat(r) - want.rot).abs().to_cols_array();
        assert!(err.iter().all(|e| *e < 1e-12), "{}", frame.name);
    }

    // metadata
    assert_eq!(c.meta("scenario", "text"), Some(src.as_str()));
    assert_eq!(c.meta("quadsim", "seed"), Some("3"));
    assert_eq!(c.meta("quadsim", "log_every_steps"), Some("4"));
    assert_eq!(c.meta("run", "steps"), Some("403"));
    assert_eq!(c.meta("run", "interrupted"), Some("false"));
    let metrics = last(&c, "/rex/metrics");
    let expected = quadsim::summary::robot_json("rex", sim);
    assert_eq!(metrics, expected);
}

#[test]
fn logged_com_acceleration_obeys_newton_and_integrates_to_the_logged_velocity() {
    // A quad16 dropped 3 cm onto concrete, logged every step: the CoM
    // acceleration is g + Σf/m with the contact forces of that instant, so its
    // integral over the landing must equal the change of the logged CoM velocity.
    let dir = tmp("newton");
    let src = scenario(0.25, "").replace("[0.0, 0.0, 0.62]", "[0.0, 0.0, 0.65]");
    let scn = parse_scenario(&dir.join("drop.toml"), src).unwrap();
    let mut world = build_world(&scn, Overrides::default()).unwrap();
    let path = dir.join("log.mcap");
    let log = start_run_log(&scn, &mut world, &path, 1).unwrap();
    world.sim.run(world.steps);
    log.finish(&mut world, &RunOutcome::default()).unwrap();
    let c = read_log(&path).unwrap();
    let com: Vec<Value> = c.topic("/rex/com").map(|m| m.json().unwrap()).collect();
    assert_eq!(com.len(), 501);
    // the last sample is the final state (500 steps, a multiple of the rate)
    let q = &world.sim.robot(world.robots[0].1).unwrap().state.q;
    let pose = last(&c, "/rex/base_pose");
    assert_eq!(v3(&pose["pose"]["position"]), [q[0], q[1], q[2]]);
    let js = last(&c, "/rex/joint_states");
    let joints: Vec<f64> = js["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(joints, q[7..]);
    let dt = 0.0005;
    let (mut integral, mut peak) = ([0.0; 3], 0.0f64);
    for m in &com[..500] {
        let a = v3(&m["acceleration"]);
        for i in 0..3 {
            integral[i] += a[i] * dt;
        }
        peak = peak.max(a[2]);
    }
    let dv: Vec<f64> = (0..3)
        .map(|i| v3(&com[500]["velocity"])[i] - v3(&com[0]["velocity"])[i])
        .collect();
    // free fall first (a = g exactly), then a landing that stops the fall
    assert_eq!(v3(&com[0]["acceleration"]), [0.0, 0.0, -9.81]);
    assert!(peak > 9.81, "landing decelerates: peak a_z {peak}");
    let scale = 9.81 * 0.25;
    for i in 0..3 {
        assert!(
            (integral[i] - dv[i]).abs() < 0.02 * scale,
            "axis {i}: ∫a dt = {} vs Δv = {}",
            integral[i],
            dv[i]
        );
    }
}

fn quadsim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_quadsim"))
}

fn run_cli(scn: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let o = quadsim()
        .arg("run")
        .arg(scn)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

#[test]
fn two_runs_write_byte_identical_logs() {
    let dir = tmp("determinism");
    let scn = dir.join("logtest.toml");
    std::fs::write(&scn, scenario(0.3, "log_rate_hz = 250")).unwrap();
    run_cli(&scn, &dir.join("a"), &["--threads", "1"]);
    run_cli(&scn, &dir.join("b"), &["--threads", "2"]);
    let a = std::fs::read(dir.join("a/log.mcap")).unwrap();
    let b = std::fs::read(dir.join("b/log.mcap")).unwrap();
    assert!(a.len() > 10_000);
    assert!(a == b, "logs differ ({} vs {} bytes)", a.len(), b.len());
    // log_rate_hz = 250 at 2 kHz steps: every 8th step, 600 steps
    let c = read_log(&dir.join("a/log.mcap")).unwrap();
    assert_eq!(c.topic("/rex/com").count(), 600 / 8 + 1);
    // --log-rate overrides it; --no-log writes none
    run_cli(&scn, &dir.join("c"), &["--log-rate", "full"]);
    let c = read_log(&dir.join("c/log.mcap")).unwrap();
    assert_eq!(c.topic("/rex/com").count(), 601);
    run_cli(&scn, &dir.join("d"), &["--no-log"]);
    assert!(!dir.join("d/log.mcap").exists());
    assert!(dir.join("d/summary.json").exists());
}

#[test]
fn bad_log_rates_are_rejected_naming_the_key() {
    let dir = tmp("badrate");
    let scn = dir.join("bad.toml");
    std::fs::write(&scn, scenario(0.1, "log_rate_hz = 300")).unwrap();
    let o = quadsim().arg("check").arg(&scn).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("world.log_rate_hz") && err.contains("300"),
        "{err}"
    );
    std::fs::write(&scn, scenario(0.1, "")).unwrap();
    let o = quadsim()
        .args([
            "run",
            scn.to_str().unwrap(),
            "--quiet",
            "--log-rate",
            "often",
            "--out",
        ])
        .arg(dir.join("o"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--log-rate") && err.contains("often"), "{err}");
}

fn without_timing(mut v: Value) -> Value {
    v.as_object_mut().unwrap().remove("timing");
    v
}

#[test]
fn report_rebuilds_the_summary_and_export_writes_tidy_csv() {
    let dir = tmp("report");
    let scn = dir.join("logtest.toml");
    std::fs::write(&scn, scenario(0.25, "")).unwrap();
    let out = dir.join("run");
    run_cli(&scn, &out, &[]);
    let o = quadsim()
        .arg("report")
        .arg(out.join("log.mcap"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read =
        |p: &Path| -> Value { serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap() };
    let original = read(&out.join("summary.json"));
    let rebuilt = read(&out.join("report/summary.json"));
    assert_eq!(rebuilt, without_timing(original.clone()));
    assert_eq!(rebuilt["robots"].as_array().unwrap().len(), 2);

    let csv_dir = dir.join("csv");
    let o = quadsim()
        .arg("export")
        .arg(out.join("log.mcap"))
        .arg("--csv")
        .arg(&csv_dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = read_log(&out.join("log.mcap")).unwrap();
    let text = std::fs::read_to_string(csv_dir.join("rex.joint_states.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[0], "t_s");
    let knee = header
        .iter()
        .position(|h| *h == "position.LF_knee")
        .expect("joint columns are named by joint");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), c.topic("/rex/joint_states").count());
    let js = last(&c, "/rex/joint_states");
    let i = js["name"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| n == "LF_knee")
        .unwrap();
    let last_row = rows.last().unwrap();
    assert_eq!(
        last_row[knee].parse::<f64>().unwrap(),
        js["position"][i].as_f64().unwrap()
    );
    assert_eq!(last_row[0].parse::<f64>().unwrap(), 0.25);
    // feet by name, booleans as 1/0
    let feet = std::fs::read_to_string(csv_dir.join("rex.feet.csv")).unwrap();
    let h = feet.lines().next().unwrap();
    assert!(h.contains("feet.LF_foot.force.z") && h.contains("feet.LF_foot.in_contact"));
    assert!(csv_dir.join("tf.csv").exists());
    assert!(!csv_dir.join("scene.csv").exists());
}

#[test]
fn a_recompiled_robot_is_drawn_again_and_keeps_being_logged() {
    let dir = tmp("recompile");
    let scn = parse_scenario(&dir.join("logtest.toml"), scenario(0.1, "")).unwrap();
    let mut world = build_world(&scn, Overrides::default()).unwrap();
    let path = dir.join("log.mcap");
    let log = start_run_log(&scn, &mut world, &path, 4).unwrap();
    world.sim.run(100);
    // a heavier torso: the robot is recompiled before the next step
    // (description components are immutable: an edit inserts a new value)
    let mut links = world.sim.world.query::<(
        bevy_ecs::entity::Entity,
        &quadsim_components::Link,
        &quadsim_components::Mass,
    )>();
    let (torso, mass) = links
        .iter(&world.sim.world)
        .find(|(_, link, _)| link.name == "torso")
        .map(|(e, _, m)| (e, m.0))
        .unwrap();
    world
        .sim
        .world
        .entity_mut(torso)
        .insert(quadsim_components::Mass(mass + 1.0));
    world.sim.run(100);
    let mass = world.sim.robot(world.robots[0].1).unwrap().model.total_mass;
    log.finish(&mut world, &RunOutcome::default()).unwrap();
    let c = read_log(&path).unwrap();
    let scenes: Vec<Value> = c.topic("/scene").map(|m| m.json().unwrap()).collect();
    assert_eq!(scenes.len(), 2, "drawn at the start and after the change");
    assert_eq!(c.topic("/scene").nth(1).unwrap().log_time_ns, 100 * 500_000);
    assert!(scenes[0]["deletions"].as_array().unwrap().is_empty());
    assert_eq!(scenes[1]["deletions"][0]["type"], 1);
    assert_eq!(
        scenes[1]["entities"].as_array().unwrap().len(),
        scenes[0]["entities"].as_array().unwrap().len()
    );
    assert!(scenes[0]["entities"].as_array().unwrap().len() > 10);
    assert_eq!(c.topic("/rex/com").count(), 200 / 4 + 1);
    // the CoM acceleration after the change uses the new mass: at rest-ish
    // on the ground, Σf_z/m + g stays near 0 only with the right mass
    let com = last(&c, "/rex/com");
    let feet = last(&c, "/rex/feet");
    let fz: f64 = feet["feet"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["force"]["z"].as_f64().unwrap())
        .sum();
    let az = com["acceleration"]["z"].as_f64().unwrap();
    assert!(
        (az - (fz / mass - 9.81)).abs() < 1e-9,
        "{az} vs {fz}/{mass} - g"
    );
}

#[test]
fn a_trotting_robot_logs_its_virtual_wrench_and_gait_phases() {
    // Study A's trot under virtual model control for 1 s: the wrench logged
    // last is the controller's, and the gait phases of a trot pair the
    // diagonal legs, half a period apart from the other pair.
    let dir = tmp("trot");
    let src = r#"format_version = 1
[world]
dt_s = 0.0005
duration_s = 1.0
controller_rate_hz = 500
default_ground = "concrete"

[[robots]]
name = "rex"
model = "quad16"
[robots.controller]
kind = "vmc"
period_s = 0.5
whole_body = false
four_leg_support_s = 0.1
two_leg_support_s = 0.15
v_x_mps = 0.5
height_m = 0.5
"#;
    let scn = parse_scenario(&dir.join("trot.toml"), src.to_string()).unwrap();
    let mut world = build_world(&scn, Overrides::default()).unwrap();
    let path = dir.join("log.mcap");
    let log = start_run_log(&scn, &mut world, &path, 4).unwrap();
    world.sim.run(world.steps);
    let sim = world.sim.robot(world.robots[0].1).unwrap();
    let foot_names: Vec<String> = sim
        .model
        .feet
        .iter()
        .map(|&f| sim.model.frames[f].name.clone())
        .collect();
    log.finish(&mut world, &RunOutcome::default()).unwrap();
    let c = read_log(&path).unwrap();
    let wrenches: Vec<Value> = c
        .topic("/rex/virtual_wrench")
        .map(|m| m.json().unwrap())
        .collect();
    assert_eq!(wrenches.len(), 2000 / 4 + 1);
    // the final sample ran the controller at the final state: its wrench now
    let sim = world.sim.robot(world.robots[0].1).unwrap();
    let quadsim_components::Controller::Walker(w) = &sim.run.controller else {
        panic!("a vmc robot has the walking controller");
    };
    let last_w = wrenches.last().unwrap();
    assert_eq!(v3(&last_w["force"]), w.wrench().lin.to_array());
    assert_eq!(v3(&last_w["torque"]), w.wrench().ang.to_array());
    // it carries (most of) the weight: upward, of the order of m·g
    let fz = v3(&last_w["force"])[2];
    let weight = sim.model.total_mass * 9.81;
    assert!(
        fz > 0.5 * weight && fz < 1.5 * weight,
        "{fz} N vs {weight} N"
    );
    // gait phases: in [0, 1); diagonal pairs (LF, RH) and (RF, LH) in phase,
    // the two pairs half a period apart
    let feet = last(&c, "/rex/feet");
    let phase = |name: &str| {
        let i = foot_names.iter().position(|n| n == name).unwrap();
        feet["feet"][i]["gait_phase"].as_f64().unwrap()
    };
    let circ = |a: f64, b: f64| {
        let d = (a - b).rem_euclid(1.0);
        d.min(1.0 - d)
    };
    for name in &foot_names {
        let p = phase(name);
        assert!((0.0..1.0).contains(&p), "{name}: {p}");
    }
    assert!(circ(phase("LF_foot"), phase("RH_foot")) < 1e-9);
    assert!(circ(phase("RF_foot"), phase("LH_foot")) < 1e-9);
    assert!((circ(phase("LF_foot"), phase("RF_foot")) - 0.5).abs() < 1e-9);
}

#[test]
fn a_file_that_is_not_a_log_is_named_in_the_error() {
    let dir = tmp("notalog");
    let path = dir.join("notes.mcap");
    std::fs::write(&path, "not an mcap file\n").unwrap();
    for cmd in [vec!["report"], vec!["export", "--csv", "out"]] {
        let o = quadsim()
            .arg(cmd[0])
            .arg(&path)
            .args(&cmd[1..])
            .current_dir(&dir)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("notes.mcap") && err.contains("not a readable MCAP log"),
            "{err}"
        );
    }
}

/// Issue 29, item 9: `quadsim export` keys a robot's sensor readings by its
/// joints' and feet's names (the model's, as `joint_states` and `feet` carry
/// them), not by index: `encoder_position_rad.LF_knee`, `contact.LF_foot`;
/// each column holds that joint's or foot's reading. Two models (quad16's
/// `*_hip_roll`, quad12's `*_hip_yaw`) get their own names.
#[test]
fn export_names_sensor_columns_by_joint_and_foot() {
    let dir = tmp("sensor_csv");
    let scn = dir.join("logtest.toml");
    std::fs::write(&scn, scenario(0.05, "").replace("log = false\n", "")).unwrap();
    let out = dir.join("run");
    run_cli(&scn, &out, &["--no-report", "--no-monitor"]);
    let csv_dir = dir.join("csv");
    let o = quadsim()
        .arg("export")
        .arg(out.join("log.mcap"))
        .arg("--csv")
        .arg(&csv_dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = read_log(&out.join("log.mcap")).unwrap();
    let names = |v: &Value, key: &str, field: Option<&str>| -> Vec<String> {
        v[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| field.map_or(x, |f| &x[f]).as_str().unwrap().to_string())
            .collect()
    };
    for (robot, hip) in [("rex", "LF_hip_roll"), ("quiet", "LF_hip_yaw")] {
        let joints = names(&last(&c, &format!("/{robot}/joint_states")), "name", None);
        let feet = names(&last(&c, &format!("/{robot}/feet")), "feet", Some("name"));
        assert!(joints.iter().any(|j| j == hip), "{robot}: {joints:?}");
        assert_eq!(feet.len(), 4);
        let sensors: Vec<Value> = c
            .topic(&format!("/{robot}/sensors"))
            .map(|m| m.json().unwrap())
            .collect();
        assert!(!sensors.is_empty(), "{robot} has sensors");
        let mut r = csv::Reader::from_path(csv_dir.join(format!("{robot}.sensors.csv"))).unwrap();
        let header: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
        assert!(
            !header
                .iter()
                .any(|h| h.ends_with(".0") || h.ends_with(".1")),
            "{robot}: an indexed column in {header:?}"
        );
        let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
        assert_eq!(rows.len(), sensors.len());
        let column = |name: &str| {
            header
                .iter()
                .position(|h| h == name)
                .unwrap_or_else(|| panic!("{robot}: no column {name} in {header:?}"))
        };
        let (last_row, last_msg) = (rows.last().unwrap(), sensors.last().unwrap());
        for (key, list) in [
            ("encoder_position_rad", &joints),
            ("encoder_velocity_radps", &joints),
            ("contact", &feet),
        ] {
            for (i, name) in list.iter().enumerate() {
                let cell = &last_row[column(&format!("{key}.{name}"))];
                let x = &last_msg[key][i];
                let want = match x {
                    Value::Bool(b) => if *b { "1" } else { "0" }.to_string(),
                    v => v.as_f64().unwrap().to_string(),
                };
                let got = match x {
                    Value::Bool(_) => cell.to_string(),
                    _ => cell.parse::<f64>().unwrap().to_string(),
                };
                assert_eq!(got, want, "{robot}: {key}.{name}");
            }
        }
        // model order: the columns follow the joints' order
        let first = column(&format!("encoder_position_rad.{}", joints[0]));
        let lastj = column(&format!(
            "encoder_position_rad.{}",
            joints[joints.len() - 1]
        ));
        assert_eq!(lastj - first, joints.len() - 1, "{robot}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 29, item 9: `/scene`'s entities carry every field of Foxglove's
/// `foxglove.SceneEntity` (its own schema, from the `foxglove` crate),
/// unused primitive lists as empty arrays, and every primitive every field
/// of its type; the JSON Schema the log stores declares them all. The live
/// bridge serves the same message (`monitor::publish` encodes it with the
/// log's `encode_scene`).
#[test]
fn scene_entities_carry_foxgloves_full_schema() {
    use foxglove::Encode;
    use prost_reflect::{DescriptorPool, Kind, MessageDescriptor};
    let dir = tmp("scene_schema");
    let scn = dir.join("logtest.toml");
    std::fs::write(&scn, scenario(0.01, "")).unwrap();
    let out = dir.join("run");
    run_cli(&scn, &out, &["--no-report", "--no-monitor"]);
    let c = read_log(&out.join("log.mcap")).unwrap();
    let scene = c.topic("/scene").next().unwrap().json().unwrap();
    let schema = foxglove::schemas::SceneEntity::get_schema().unwrap();
    let pool = DescriptorPool::decode(&schema.data[..]).unwrap();
    let entity = pool.get_message_by_name("foxglove.SceneEntity").unwrap();
    let fields = |d: &MessageDescriptor| -> Vec<String> {
        d.fields().map(|f| f.name().to_string()).collect()
    };
    let entity_fields = fields(&entity);
    for f in [
        "arrows",
        "cubes",
        "spheres",
        "cylinders",
        "lines",
        "triangles",
        "texts",
        "models",
        "metadata",
        "frame_locked",
        "lifetime",
        "timestamp",
        "id",
        "frame_id",
    ] {
        assert!(
            entity_fields.iter().any(|x| x == f),
            "{f} in Foxglove's schema"
        );
    }
    let entities = scene["entities"].as_array().unwrap();
    assert!(entities.len() > 10);
    let mut seen_primitives = std::collections::BTreeSet::new();
    for e in entities {
        let keys: Vec<&String> = e.as_object().unwrap().keys().collect();
        for f in &entity_fields {
            assert!(
                e.get(f).is_some(),
                "entity {}: no {f} (has {keys:?})",
                e["id"]
            );
        }
        assert_eq!(keys.len(), entity_fields.len(), "{keys:?}");
        // each primitive has every field of its message type
        for field in entity.fields().filter(|f| f.is_list()) {
            let Kind::Message(prim) = field.kind() else {
                continue;
            };
            for p in e[field.name()].as_array().unwrap() {
                seen_primitives.insert(field.name().to_string());
                for f in fields(&prim) {
                    assert!(p.get(&f).is_some(), "{}: {f} missing in {p}", field.name());
                }
            }
        }
    }
    assert!(seen_primitives.contains("cubes") && seen_primitives.contains("triangles"));
    // and the log's JSON Schema for /scene declares every field
    let stored: Value =
        serde_json::from_slice(&c.schemas[Schema::SceneUpdate.name()].data).unwrap();
    let declared = &stored["properties"]["entities"]["items"]["properties"];
    for field in entity.fields() {
        let d = &declared[field.name()];
        assert!(d.is_object(), "schema lacks {}", field.name());
        if let (true, Kind::Message(prim)) = (field.is_list(), field.kind())
            && prim.name() != "KeyValuePair"
        {
            for f in fields(&prim) {
                assert!(
                    d["items"]["properties"][&f].is_object(),
                    "schema lacks {}.{f}",
                    field.name()
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}
