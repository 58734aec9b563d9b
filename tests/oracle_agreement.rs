//! Agreement with Pinocchio 4.1 on quad16 and quad12, floating and fixed base,
//! and on a small vendor-style URDF with odd inertial frames.
//!
//! The references in `tests/fixtures/oracle/` were made by `tests/oracle/generate.sh`
//! (`../shared/oracle/oracle.py`, pin==4.1.0). Each state is evaluated here by
//! [`quadsim::cli::dynamics::evaluate`], the same function `quadsim dynamics`
//! runs, on the model [`quadsim::urdf::load_urdf`] reads from the same URDF.
//!
//! Bound: |x − ref| ≤ 1e-9 · max(1, |ref|) for RNEA, CRBA, NLE, gravity, CoM,
//! energies and every link and joint pose; for ABA (and the acceleration RNEA
//! was given when the state had none) the bound is multiplied by cond₂(M),
//! since a solve with M amplifies relative perturbations by up to that factor.
//!
//! One convention differs, for a fixed base only: Pinocchio welds the root link
//! to its "universe" joint, and its `centerOfMass` and `computePotentialEnergy`
//! sum over joints 1.. only, leaving the root link's mass out (the oracle's
//! `total_mass` does count it). quadsim's CoM and potential energy are those of
//! the whole robot, root link included, as the oracle's docstring describes
//! them. The fixed-base reference is therefore put on quadsim's footing with
//! the exact identities `c = (M_moving c_pin + m_root c_root) / M` and
//! `V = V_pin − m_root g·c_root`, then compared at the same 1e-9 bound;
//! [`pinocchio_fixed_base_com_leaves_out_the_root_link`] shows the difference is real.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use quadsim::cli::dynamics::{Report, State, StateResult, evaluate, model_info};
use quadsim::engine::Data;
use quadsim::engine::model::{BaseKind, Model};
use quadsim::urdf::{UrdfOptions, load_urdf};

const TOL: f64 = 1e-9;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Worst error of one quantity, as a fraction of its bound.
#[derive(Default, Debug, Clone)]
struct Worst {
    /// max over entries of |x − ref| / max(1, |ref|)
    rel: f64,
    /// the largest bound scale used (cond(M) for ABA, 1 otherwise)
    scale: f64,
    /// max of rel / (TOL · scale): must be ≤ 1
    ratio: f64,
    /// where the worst entry was
    at: String,
}

#[derive(Default)]
struct Checker {
    worst: BTreeMap<&'static str, Worst>,
}

impl Checker {
    fn check(&mut self, what: &'static str, ours: &[f64], reference: &[f64], scale: f64, at: &str) {
        assert_eq!(
            ours.len(),
            reference.len(),
            "{what} at {at}: lengths differ"
        );
        let w = self.worst.entry(what).or_default();
        for (k, (x, r)) in ours.iter().zip(reference).enumerate() {
            let rel = (x - r).abs() / r.abs().max(1.0);
            let ratio = rel / (TOL * scale);
            // a NaN anywhere must fail: once recorded as the worst, it stays
            if !w.ratio.is_nan() && (ratio.is_nan() || ratio > w.ratio) {
                *w = Worst {
                    rel,
                    scale: w.scale.max(scale),
                    ratio,
                    at: format!("{at}[{k}]: ours {x:e}, Pinocchio {r:e}"),
                };
            } else {
                w.scale = w.scale.max(scale);
            }
        }
    }

    fn report_and_assert(&self, label: &str) {
        println!("{label}: worst |x − ref| / max(1, |ref|) per quantity (bound 1e-9 × scale)");
        for (what, w) in &self.worst {
            println!(
                "  {what:<18} {:9.2e}  (scale {:9.3e}, {:5.1}% of bound)  {}",
                w.rel,
                w.scale,
                100.0 * w.ratio,
                w.at
            );
        }
        let bad: Vec<String> = self
            .worst
            .iter()
            .filter(|(_, w)| w.ratio.is_nan() || w.ratio > 1.0)
            .map(|(what, w)| format!("{what}: {:e} > 1e-9 × {:e} at {}", w.rel, w.scale, w.at))
            .collect();
        assert!(
            bad.is_empty(),
            "{label}: disagreement with Pinocchio:\n{}",
            bad.join("\n")
        );
    }
}

/// 2-norm condition number of a symmetric positive definite matrix.
fn condition_number(m: &[Vec<f64>]) -> f64 {
    let n = m.len();
    let mat = nalgebra::DMatrix::from_fn(n, n, |i, j| m[i][j]);
    let eig = nalgebra::SymmetricEigen::new(mat).eigenvalues;
    let max = eig.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min = eig.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        min > 0.0,
        "Pinocchio's M is not positive definite (λmin = {min})"
    );
    max / min
}

fn agree(robot: &str, set: &str, base: BaseKind) {
    let label = format!("{robot}_{set}");
    let fixture = format!("{}_{set}", robot.trim_end_matches("_revolute"));
    let path = fixtures().join(format!("oracle/{fixture}.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reference: Report = serde_json::from_str(&text).expect("fixture parses");
    let urdf = fixtures().join(format!("models/{robot}.urdf"));
    let opts = UrdfOptions {
        package_paths: vec![fixtures().join("models/packages")],
    };
    let robot_desc = load_urdf(&urdf, &opts).expect("URDF loads");
    // only vendor_style's deliberately missing plate mesh may warn
    assert!(
        robot_desc
            .warnings
            .iter()
            .all(|w| w.contains("missing_pkg")),
        "{:?}",
        robot_desc.warnings
    );
    let model = Model::from_description(&robot_desc.description, base).expect("model compiles");
    let mut data = Data::new(&model);

    // Same sizes, joint order and links.
    let info = model_info(&model);
    let rinfo = &reference.model;
    assert_eq!(info.fixed_base, rinfo.fixed_base);
    assert_eq!((info.nq, info.nv), (rinfo.nq, rinfo.nv));
    assert_eq!(info.joint_names, rinfo.joint_names, "q/v order");
    let mut ours_links = info.link_names.clone();
    let mut ref_links = rinfo.link_names.clone();
    ours_links.sort();
    ref_links.sort();
    assert_eq!(ours_links, ref_links);
    assert!(!reference.results.is_empty());

    // Fixed base: the root link, welded at the identity, is outside Pinocchio's CoM.
    let (m_root, c_root) = match base {
        BaseKind::Fixed => {
            let root = robot_desc.description.root_link().expect("root link");
            (root.mass_kg, root.com_m.to_array())
        }
        BaseKind::Floating => (0.0, [0.0; 3]),
    };
    let m_total = rinfo.total_mass;
    let m_moving = m_total - m_root;

    let mut c = Checker::default();
    c.check(
        "total_mass",
        &[info.total_mass],
        &[rinfo.total_mass],
        1.0,
        "model",
    );
    c.check(
        "gravity_vector",
        &info.gravity,
        &rinfo.gravity,
        1.0,
        "model",
    );
    for (i, r) in reference.results.iter().enumerate() {
        let given_a = r.rnea_residual.is_none();
        let state = State {
            name: None,
            q: r.q_used.clone(),
            v: r.v.clone(),
            tau: r.tau.clone(),
            a: given_a.then(|| r.a_used.clone()),
        };
        let ours: StateResult = evaluate(&model, &mut data, &state).expect("state fits the model");
        let cond = condition_number(&r.crba);
        let at = |f: &str| format!("results[{i}].{f}");
        c.check("q_used", &ours.q_used, &r.q_used, 1.0, &at("q_used"));
        c.check("aba", &ours.aba, &r.aba, cond, &at("aba"));
        // with no `a` given, RNEA ran at each engine's own ABA result
        let a_scale = if given_a { 1.0 } else { cond };
        c.check("a_used", &ours.a_used, &r.a_used, a_scale, &at("a_used"));
        c.check("rnea", &ours.rnea, &r.rnea, 1.0, &at("rnea"));
        let flat = |m: &[Vec<f64>]| m.iter().flatten().copied().collect::<Vec<f64>>();
        c.check("crba", &flat(&ours.crba), &flat(&r.crba), 1.0, &at("crba"));
        c.check("nle", &ours.nle, &r.nle, 1.0, &at("nle"));
        c.check("gravity", &ours.gravity, &r.gravity, 1.0, &at("gravity"));
        let com_ref: Vec<f64> = (0..3)
            .map(|k| (m_moving * r.com[k] + m_root * c_root[k]) / m_total)
            .collect();
        c.check("com", &ours.com, &com_ref, 1.0, &at("com"));
        c.check(
            "kinetic_energy",
            &[ours.kinetic_energy],
            &[r.kinetic_energy],
            1.0,
            &at("kinetic_energy"),
        );
        c.check(
            "potential_energy",
            &[ours.potential_energy],
            &[r.potential_energy - m_root * info.gravity[2] * c_root[2]],
            1.0,
            &at("potential_energy"),
        );
        if let (Some(a), Some(b)) = (ours.rnea_residual, r.rnea_residual) {
            // both engines must give τ back from their own ABA result
            c.check("rnea_residual", &[a], &[b], 1.0, &at("rnea_residual"));
        }
        assert_eq!(ours.frames.len(), r.frames.len(), "{}", at("frames"));
        for (name, rf) in &r.frames {
            let of = ours
                .frames
                .get(name)
                .unwrap_or_else(|| panic!("no frame {name}"));
            let f = at(&format!("frames.{name}"));
            c.check(
                "frame_translation",
                &of.translation,
                &rf.translation,
                1.0,
                &f,
            );
            c.check(
                "frame_rotation",
                &flat(&of.rotation.map(Vec::from)),
                &flat(&rf.rotation.map(Vec::from)),
                1.0,
                &f,
            );
            // the sign too follows Eigen's convention (see `quat_xyzw`)
            c.check("frame_quat", &of.quat_xyzw, &rf.quat_xyzw, 1.0, &f);
        }
        assert_eq!(ours.joints.len(), r.joints.len(), "{}", at("joints"));
        for (name, rj) in &r.joints {
            let oj = ours
                .joints
                .get(name)
                .unwrap_or_else(|| panic!("no joint {name}"));
            let f = at(&format!("joints.{name}"));
            c.check(
                "joint_translation",
                &oj.translation,
                &rj.translation,
                1.0,
                &f,
            );
            c.check(
                "joint_rotation",
                &flat(&oj.rotation.map(Vec::from)),
                &flat(&rj.rotation.map(Vec::from)),
                1.0,
                &f,
            );
        }
    }
    c.report_and_assert(&label);
}

#[test]
fn quad16_shared_states_agree_with_pinocchio() {
    agree("quad16", "shared", BaseKind::Floating);
}

#[test]
fn quad16_random_states_agree_with_pinocchio() {
    agree("quad16", "random", BaseKind::Floating);
}

#[test]
fn quad16_fixed_base_agrees_with_pinocchio() {
    agree("quad16", "fixed", BaseKind::Fixed);
}

#[test]
fn quad12_random_states_agree_with_pinocchio() {
    agree("quad12", "random", BaseKind::Floating);
}

#[test]
fn quad12_fixed_base_agrees_with_pinocchio() {
    agree("quad12", "fixed", BaseKind::Fixed);
}

/// Offset and rotated inertial frames, a fixed child turned 90°, an axis given
/// as "0 0 2", a prismatic joint: the URDF conventions Pinocchio reads too.
#[test]
fn vendor_style_inertial_frames_agree_with_pinocchio() {
    agree("vendor_style_revolute", "random", BaseKind::Floating);
}

/// Pinocchio's fixed-base CoM is that of the moving bodies only: with the
/// quad16 torso (10 of 28 kg) welded at the origin, its CoM is farther from the
/// origin than the whole robot's by exactly the factor M / M_moving.
#[test]
fn pinocchio_fixed_base_com_leaves_out_the_root_link() {
    let path = fixtures().join("oracle/quad16_fixed.json");
    let reference: Report = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let urdf = fixtures().join("models/quad16.urdf");
    let desc = load_urdf(&urdf, &UrdfOptions::default())
        .unwrap()
        .description;
    let root = desc.root_link().unwrap();
    assert_eq!(
        root.com_m,
        glam::DVec3::ZERO,
        "the identity below assumes the torso CoM at the origin"
    );
    let model = Model::from_description(&desc, BaseKind::Fixed).unwrap();
    let mut data = Data::new(&model);
    let m_total = reference.model.total_mass;
    let ratio = m_total / (m_total - root.mass_kg);
    let mut largest_gap: f64 = 0.0;
    for r in &reference.results {
        let state = State {
            name: None,
            q: r.q_used.clone(),
            v: r.v.clone(),
            tau: r.tau.clone(),
            a: None,
        };
        let ours = evaluate(&model, &mut data, &state).unwrap();
        for k in 0..3 {
            assert!((ours.com[k] * ratio - r.com[k]).abs() <= TOL * r.com[k].abs().max(1.0));
            largest_gap = largest_gap.max((ours.com[k] - r.com[k]).abs());
        }
    }
    // the two definitions really differ on these states
    assert!(largest_gap > 1e-2, "largest CoM gap {largest_gap} m");
}
