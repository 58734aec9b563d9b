//! URDF import (urdf-rs) into an engine [`RobotDescription`].
//!
//! [`load_urdf`] takes the URDFs that robot vendors publish:
//!
//! - `revolute` (with `<limit lower upper>`), `continuous` (a revolute without
//!   position limits), `prismatic` and `fixed` joints (merged into their parent
//!   body when the engine compiles the model); `floating`, `planar` and
//!   `spherical` joints are refused with a clear error;
//! - `<dynamics damping friction>` and `<limit effort velocity>`;
//! - `<inertial>` frames that are offset and rotated from the link frame (the
//!   tensor is rotated into link axes, `I_link = R I Rᵀ`, and the CoM is the
//!   origin's `xyz`); a link without `<inertial>` is massless;
//! - mesh geometry by file name, `package://pkg/…` (searched for in each
//!   [`UrdfOptions::package_paths`] entry, ROS style) or `file://`; found files
//!   (STL, OBJ, COLLADA) have their vertices loaded for a convex hull, missing
//!   ones are kept as a reference with a warning naming the link and the URI.
//!
//! Frames and units are URDF's: SI units, each joint's `<origin>` places the
//! child link frame in the parent link frame, the axis is in the child frame.
//! Feet are left empty: the leaf links are the feet unless a scenario names them.
//!
//! urdf-rs reports malformed values without saying where they are, so the file
//! is first read with roxmltree, which gives line numbers, and every number that
//! urdf-rs will read is checked there: errors name the file, the element and the
//! field, e.g. `quad.urdf: joint 'LF_knee' (line 40): <axis xyz>: zero vector`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use quadsim_engine::description::{
    Geometry, JointDesc, JointKind, LinkDesc, RobotDescription, Shape,
};
use quadsim_engine::model::{BaseKind, Model, ModelError};
use quadsim_engine::spatial::{Transform, rot_from_rpy};
use thiserror::Error;

/// The most `<link>` (and the most `<joint>`) elements a URDF may have.
pub const MAX_URDF_ELEMENTS: usize = 1000;

/// Options of [`load_urdf`].
#[derive(Clone, Debug, Default)]
pub struct UrdfOptions {
    /// Directories searched for `package://pkg/…` URIs (the CLI's
    /// `--package-path`): `DIR/pkg/…` is used when `DIR/pkg` exists, or `DIR/…`
    /// when `DIR` itself is named `pkg`.
    pub package_paths: Vec<PathBuf>,
}

/// A robot read from a URDF file.
#[derive(Clone, Debug)]
pub struct UrdfRobot {
    /// The engine description: links and joints in document order.
    pub description: RobotDescription,
    /// Things the import could not honour fully (missing mesh files, ignored
    /// elements), one sentence each, naming the file and element.
    pub warnings: Vec<String>,
}

/// Why a URDF could not be imported. Every message starts with the file name.
#[derive(Debug, Error)]
pub enum UrdfError {
    /// The file cannot be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The URDF path.
        file: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not well-formed XML.
    #[error("{file}: malformed XML: {msg}")]
    Xml {
        /// The URDF path.
        file: String,
        /// Parser message with line and column.
        msg: String,
    },
    /// An element or field has a value that cannot be used.
    #[error("{file}: {element}: {field}: {why}")]
    Invalid {
        /// The URDF path.
        file: String,
        /// The element, e.g. `joint 'LF_knee' (line 40)`.
        element: String,
        /// The field, e.g. `<axis xyz>`.
        field: String,
        /// What is wrong.
        why: String,
    },
    /// A joint type the engine does not model.
    #[error(
        "{file}: {element}: type '{kind}' is not supported (use revolute, continuous, prismatic or fixed; a floating base is added by the simulator)"
    )]
    UnsupportedJoint {
        /// The URDF path.
        file: String,
        /// The joint element.
        element: String,
        /// The URDF joint type.
        kind: String,
    },
    /// A joint names a link that the file does not define.
    #[error("{file}: {element}: <{role} link>: unknown link '{link}'")]
    UnknownLink {
        /// The URDF path.
        file: String,
        /// The joint element.
        element: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The missing link.
        link: String,
    },
    /// urdf-rs refused the file for a reason the checks above did not catch.
    #[error("{file}: invalid URDF: {msg}")]
    Parse {
        /// The URDF path.
        file: String,
        /// urdf-rs's message.
        msg: String,
    },
    /// The links and joints do not form one tree (or another model-level error).
    #[error("{file}: {source}")]
    Model {
        /// The URDF path.
        file: String,
        /// The engine's reason.
        source: ModelError,
    },
}

/// Reads a URDF file into an engine description plus warnings.
///
/// Effort and velocity limits of `0` (or absent) are taken as "no limit"
/// (`f64::INFINITY`): URDF requires the attributes and vendors write `0` when
/// they have no figure, and a zero limit would freeze the joint. Absent `lower`
/// or `upper` attributes leave that side unbounded (URDF 1.2's rule).
///
/// # Errors
/// [`UrdfError`] naming the file, element and field; never panics on bad input.
pub fn load_urdf(path: &Path, opts: &UrdfOptions) -> Result<UrdfRobot, UrdfError> {
    let file = path.display().to_string();
    let text = crate::limits::read_text_capped(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(
        |source| UrdfError::Io {
            file: file.clone(),
            source,
        },
    )?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    parse_urdf(&text, &file, base_dir, opts)
}

/// Parses URDF text; `file` names it in messages and `base_dir` resolves relative mesh paths.
///
/// # Errors
/// As [`load_urdf`].
pub fn parse_urdf(
    text: &str,
    file: &str,
    base_dir: &Path,
    opts: &UrdfOptions,
) -> Result<UrdfRobot, UrdfError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| UrdfError::Xml {
        file: file.to_string(),
        msg: e.to_string(),
    })?;
    let facts = precheck(&doc, file)?;
    let robot = urdf_rs::read_from_string(text).map_err(|e| UrdfError::Parse {
        file: file.to_string(),
        msg: e.to_string(),
    })?;
    let mut warnings = Vec::new();
    let label = |kind: &str, name: &str| -> String {
        match facts.lines.get(&(kind.to_string(), name.to_string())) {
            Some(line) => format!("{kind} '{name}' (line {line})"),
            None => format!("{kind} '{name}'"),
        }
    };
    let invalid = |element: String, field: &str, why: String| UrdfError::Invalid {
        file: file.to_string(),
        element,
        field: field.to_string(),
        why,
    };

    let mut desc = RobotDescription::new(robot.name.clone());
    for l in &robot.links {
        let el = label("link", &l.name);
        let mass = l.inertial.mass.value;
        if !(mass.is_finite() && mass >= 0.0) {
            return Err(invalid(
                el,
                "<inertial><mass value>",
                format!("{mass} is not a finite mass ≥ 0 kg"),
            ));
        }
        let i = &l.inertial.inertia;
        let tensor = DMat3::from_cols_array(&[
            i.ixx, i.ixy, i.ixz, //
            i.ixy, i.iyy, i.iyz, //
            i.ixz, i.iyz, i.izz,
        ]);
        for (field, v) in [("ixx", i.ixx), ("iyy", i.iyy), ("izz", i.izz)] {
            if v < 0.0 {
                return Err(invalid(
                    el,
                    &format!("<inertial><inertia {field}>"),
                    format!("{v} is negative"),
                ));
            }
        }
        // The inertial frame may be rotated: bring the tensor into link axes.
        let r = rot_from_rpy(vec3(l.inertial.origin.rpy));
        let mut link = LinkDesc::new(l.name.clone());
        link.mass_kg = mass;
        link.com_m = vec3(l.inertial.origin.xyz);
        link.inertia_kgm2 = Some(r * tensor * r.transpose());
        let where_ = format!("{file}: {el}");
        for c in &l.collision {
            let shape = convert_shape(
                &c.geometry,
                &where_,
                "collision",
                base_dir,
                opts,
                &mut warnings,
            );
            link.collision.push(Geometry {
                origin: pose(&c.origin),
                shape,
            });
        }
        for v in &l.visual {
            let shape = convert_shape(
                &v.geometry,
                &where_,
                "visual",
                base_dir,
                opts,
                &mut warnings,
            );
            link.visual.push(Geometry {
                origin: pose(&v.origin),
                shape,
            });
        }
        desc.links.push(link);
    }

    let link_names: std::collections::HashSet<&str> =
        robot.links.iter().map(|l| l.name.as_str()).collect();
    for j in &robot.joints {
        let el = label("joint", &j.name);
        for (role, link) in [("parent", &j.parent.link), ("child", &j.child.link)] {
            if !link_names.contains(link.as_str()) {
                return Err(UrdfError::UnknownLink {
                    file: file.to_string(),
                    element: el,
                    role,
                    link: link.clone(),
                });
            }
        }
        let axis = vec3(j.axis.xyz);
        let unit_axis = || -> Result<DVec3, UrdfError> {
            let n = axis.length();
            if !(n.is_finite() && n > 1e-12) {
                return Err(invalid(el.clone(), "<axis xyz>", "zero vector".to_string()));
            }
            Ok(axis / n)
        };
        use urdf_rs::JointType as U;
        let (kind, limited) = match j.joint_type {
            U::Revolute => (JointKind::Revolute { axis: unit_axis()? }, true),
            U::Continuous => (JointKind::Revolute { axis: unit_axis()? }, false),
            U::Prismatic => (JointKind::Prismatic { axis: unit_axis()? }, true),
            U::Fixed => (JointKind::Fixed, false),
            U::Floating | U::Planar | U::Spherical => {
                return Err(UrdfError::UnsupportedJoint {
                    file: file.to_string(),
                    element: el,
                    kind: format!("{:?}", j.joint_type).to_lowercase(),
                });
            }
        };
        let mut jd = JointDesc::new(
            j.name.clone(),
            kind,
            j.parent.link.clone(),
            j.child.link.clone(),
            pose(&j.origin),
        );
        let lf = facts.limits.get(&j.name).cloned().unwrap_or_default();
        if limited {
            let lo = if lf.lower {
                j.limit.lower
            } else {
                f64::NEG_INFINITY
            };
            let hi = if lf.upper {
                j.limit.upper
            } else {
                f64::INFINITY
            };
            if lo > hi {
                return Err(invalid(
                    el,
                    "<limit lower upper>",
                    format!("lower {lo} > upper {hi}"),
                ));
            }
            if lo.is_finite() || hi.is_finite() {
                jd.limits = Some((lo, hi));
            } else {
                warnings.push(format!(
                    "{file}: {el}: no <limit lower upper>: the joint has no position limits"
                ));
            }
        }
        if jd.is_movable() {
            for (field, v, slot) in [
                ("<limit effort>", j.limit.effort, &mut jd.effort_limit),
                ("<limit velocity>", j.limit.velocity, &mut jd.velocity_limit),
            ] {
                if v.is_nan() || v < 0.0 {
                    return Err(invalid(el, field, format!("{v} is negative")));
                }
                // 0 conventionally means "not given" (see the function doc).
                *slot = if v == 0.0 { f64::INFINITY } else { v };
            }
            if let Some(d) = &j.dynamics {
                for (field, v, slot) in [
                    ("<dynamics damping>", d.damping, &mut jd.damping),
                    ("<dynamics friction>", d.friction, &mut jd.friction),
                ] {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(invalid(el, field, format!("{v} is not a finite value ≥ 0")));
                    }
                    *slot = v;
                }
            }
        }
        if j.mimic.is_some() {
            warnings.push(format!(
                "{file}: {el}: <mimic> is ignored: the joint moves independently"
            ));
        }
        desc.joints.push(jd);
    }

    // Names, roots and loops: the engine's own checks, reported against the file.
    Model::from_description(&desc, BaseKind::Floating).map_err(|source| UrdfError::Model {
        file: file.to_string(),
        source,
    })?;
    // Physical bounds (masses, inertias, lengths, shapes), as `check` and
    // `run` apply them to every robot, reported against the file's line.
    crate::physical::check_description(&desc)
        .map_err(|e| invalid(label(e.kind, &e.name), &e.field, e.why))?;
    Ok(UrdfRobot {
        description: desc,
        warnings,
    })
}

fn vec3(v: urdf_rs::Vec3) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

fn pose(p: &urdf_rs::Pose) -> Transform {
    Transform::from_xyz_rpy(vec3(p.xyz), vec3(p.rpy))
}

fn convert_shape(
    g: &urdf_rs::Geometry,
    element: &str,
    role: &str,
    base_dir: &Path,
    opts: &UrdfOptions,
    warnings: &mut Vec<String>,
) -> Shape {
    match g {
        urdf_rs::Geometry::Box { size } => Shape::Box {
            size_m: vec3(*size),
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
            radius_m: *radius,
            length_m: *length,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
            radius_m: *radius,
            length_m: *length,
        },
        urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius_m: *radius },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let scale = scale.map(vec3).unwrap_or(DVec3::ONE);
            let vertices = match resolve_mesh(filename, base_dir, &opts.package_paths) {
                Ok(path) => match read_mesh_vertices(&path) {
                    Ok(v) if !v.is_empty() => Some(v.into_iter().map(|p| p * scale).collect()),
                    Ok(_) => {
                        warnings.push(format!(
                            "{element}: <{role}> mesh '{filename}' ({}) has no vertices; kept as a reference",
                            path.display()
                        ));
                        None
                    }
                    Err(e) => {
                        warnings.push(format!(
                            "{element}: <{role}> mesh '{filename}' ({}) cannot be read ({e}); kept as a reference",
                            path.display()
                        ));
                        None
                    }
                },
                Err(why) => {
                    warnings.push(format!(
                        "{element}: <{role}> mesh '{filename}' not found ({why}); kept as a reference without vertices"
                    ));
                    None
                }
            };
            Shape::Mesh {
                uri: filename.clone(),
                scale,
                vertices,
            }
        }
    }
}

/// Finds a mesh file: `package://pkg/rest` in the package paths, `file://path`,
/// or a path relative to the URDF's directory. `Err` says where it looked.
pub fn resolve_mesh(
    uri: &str,
    base_dir: &Path,
    package_paths: &[PathBuf],
) -> Result<PathBuf, String> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
        if package_paths.is_empty() {
            return Err(format!(
                "no package path given to find package '{pkg}' (use --package-path DIR)"
            ));
        }
        for dir in package_paths {
            let candidates = [
                Some(dir.join(pkg).join(rel)),
                (dir.file_name().and_then(|n| n.to_str()) == Some(pkg)).then(|| dir.join(rel)),
            ];
            if let Some(p) = candidates.into_iter().flatten().find(|p| p.is_file()) {
                return Ok(p);
            }
        }
        let searched: Vec<String> = package_paths
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        return Err(format!(
            "package '{pkg}' has no '{rel}' in {}",
            searched.join(", ")
        ));
    }
    let p = match uri.strip_prefix("file://") {
        Some(rest) => PathBuf::from(rest),
        None if uri.contains("://") => return Err("unsupported URI scheme".to_string()),
        None => PathBuf::from(uri),
    };
    let p = if p.is_absolute() { p } else { base_dir.join(p) };
    if p.is_file() {
        Ok(p)
    } else {
        Err(format!("no file {}", p.display()))
    }
}

/// All vertices of a mesh file (STL, OBJ or COLLADA), unscaled, in the file's units.
pub fn read_mesh_vertices(path: &Path) -> std::io::Result<Vec<DVec3>> {
    let scene = mesh_loader::Loader::default().load(path)?;
    Ok(scene
        .meshes
        .iter()
        .flat_map(|m| m.vertices.iter())
        .map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
        .filter(|v| v.is_finite())
        .collect())
}

/// Which `<limit>` attributes a joint states (urdf-rs fills absent ones with 0).
#[derive(Clone, Debug, Default)]
struct LimitFacts {
    lower: bool,
    upper: bool,
}

/// What the XML pre-pass learns: element lines and the limit attributes present.
#[derive(Debug, Default)]
struct Facts {
    lines: HashMap<(String, String), u32>,
    limits: HashMap<String, LimitFacts>,
}

/// The child elements of `n` named `tag`.
fn children<'a, 'i>(
    n: roxmltree::Node<'a, 'i>,
    tag: &'static str,
) -> impl Iterator<Item = roxmltree::Node<'a, 'i>> {
    n.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// Checks every attribute urdf-rs will read, naming element and field, and
/// records line numbers and which limit attributes are present.
fn precheck(doc: &roxmltree::Document<'_>, file: &str) -> Result<Facts, UrdfError> {
    let root = doc.root_element();
    let line = |n: roxmltree::Node<'_, '_>| doc.text_pos_at(n.range().start).row;
    let invalid = |element: &str, field: String, why: String| UrdfError::Invalid {
        file: file.to_string(),
        element: element.to_string(),
        field,
        why,
    };
    if root.tag_name().name() != "robot" {
        return Err(invalid(
            &format!("<{}> (line {})", root.tag_name().name(), line(root)),
            "root element".into(),
            "a URDF's root element must be <robot>".into(),
        ));
    }
    let version = root
        .attribute("version")
        .and_then(|v| v.trim().split_once('.'))
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)))
        .unwrap_or((1, 0));
    // A size limit first, before any per-element work (a robot has tens of
    // links; a 5,000-joint chain is refused here at once).
    for tag in ["link", "joint"] {
        let n = children(root, tag).count();
        if n > MAX_URDF_ELEMENTS {
            return Err(invalid(
                &format!("<robot> (line {})", line(root)),
                format!("<{tag}>"),
                format!("{n} <{tag}> elements, more than the {MAX_URDF_ELEMENTS} quadsim imports"),
            ));
        }
    }
    let mut facts = Facts::default();
    // `path` is the field as shown in messages, e.g. "<inertial><mass value>".
    let check_nums = |el: &str,
                      node: roxmltree::Node<'_, '_>,
                      path: &str,
                      attr: &str,
                      count: usize,
                      required: bool,
                      allow_inf: bool|
     -> Result<(), UrdfError> {
        let field = format!("<{path} {attr}>");
        let Some(s) = node.attribute(attr) else {
            if required {
                return Err(invalid(el, field, "required attribute is missing".into()));
            }
            return Ok(());
        };
        let parts: Vec<&str> = s.split_whitespace().collect();
        if parts.len() != count {
            return Err(invalid(
                el,
                field,
                format!("expected {count} number(s), got '{s}'"),
            ));
        }
        for p in parts {
            match p.parse::<f64>() {
                Ok(x) if x.is_nan() => return Err(invalid(el, field, "NaN is not allowed".into())),
                Ok(x) if x.is_infinite() && !allow_inf => {
                    return Err(invalid(el, field, format!("'{p}' is not finite")));
                }
                Ok(_) => {}
                Err(_) => return Err(invalid(el, field, format!("'{p}' is not a number"))),
            }
        }
        Ok(())
    };
    let check_origin = |el: &str, parent: roxmltree::Node<'_, '_>, prefix: &str| {
        for o in children(parent, "origin") {
            let path = format!("{prefix}origin");
            check_nums(el, o, &path, "xyz", 3, false, false)?;
            check_nums(el, o, &path, "rpy", 3, false, false)?;
        }
        Ok::<(), UrdfError>(())
    };
    let name_of = |n: roxmltree::Node<'_, '_>, kind: &str| -> Result<String, UrdfError> {
        match n.attribute("name") {
            Some(s) if !s.trim().is_empty() => Ok(s.to_string()),
            _ => Err(invalid(
                &format!("<{kind}> (line {})", line(n)),
                format!("<{kind} name>"),
                "required attribute is missing or empty".into(),
            )),
        }
    };

    for link in children(root, "link") {
        let name = name_of(link, "link")?;
        let el = format!("link '{name}' (line {})", line(link));
        facts.lines.insert(("link".into(), name), line(link));
        for inertial in children(link, "inertial") {
            check_origin(&el, inertial, "inertial><")?;
            let mass = children(inertial, "mass").next();
            match mass {
                Some(m) => check_nums(&el, m, "inertial><mass", "value", 1, true, false)?,
                None => {
                    return Err(invalid(
                        &el,
                        "<inertial><mass>".into(),
                        "required element is missing".into(),
                    ));
                }
            }
            match children(inertial, "inertia").next() {
                Some(i) => {
                    for a in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"] {
                        check_nums(&el, i, "inertial><inertia", a, 1, true, false)?;
                    }
                }
                None => {
                    return Err(invalid(
                        &el,
                        "<inertial><inertia>".into(),
                        "required element is missing".into(),
                    ));
                }
            }
        }
        for role in ["visual", "collision"] {
            for g in children(link, role) {
                check_origin(&el, g, &format!("{role}><"))?;
                let Some(geom) = children(g, "geometry").next() else {
                    return Err(invalid(
                        &el,
                        format!("<{role}><geometry>"),
                        "required element is missing".into(),
                    ));
                };
                let Some(shape) = geom.children().find(|c| c.is_element()) else {
                    return Err(invalid(
                        &el,
                        format!("<{role}><geometry>"),
                        "no shape inside".into(),
                    ));
                };
                let tag = shape.tag_name().name();
                let path = format!("{role}><geometry><{tag}");
                match tag {
                    "box" => check_nums(&el, shape, &path, "size", 3, true, false)?,
                    "sphere" => check_nums(&el, shape, &path, "radius", 1, true, false)?,
                    "cylinder" | "capsule" => {
                        check_nums(&el, shape, &path, "radius", 1, true, false)?;
                        check_nums(&el, shape, &path, "length", 1, true, false)?;
                    }
                    "mesh" => {
                        if shape.attribute("filename").is_none() {
                            return Err(invalid(
                                &el,
                                format!("<{path} filename>"),
                                "required attribute is missing".into(),
                            ));
                        }
                        check_nums(&el, shape, &path, "scale", 3, false, false)?;
                    }
                    other => {
                        return Err(invalid(
                            &el,
                            format!("<{role}><geometry>"),
                            format!("unknown shape <{other}>"),
                        ));
                    }
                }
            }
        }
    }

    for joint in children(root, "joint") {
        let name = name_of(joint, "joint")?;
        let el = format!("joint '{name}' (line {})", line(joint));
        facts
            .lines
            .insert(("joint".into(), name.clone()), line(joint));
        const TYPES: [&str; 7] = [
            "revolute",
            "continuous",
            "prismatic",
            "fixed",
            "floating",
            "planar",
            "spherical",
        ];
        match joint.attribute("type") {
            Some(t) if TYPES.contains(&t) => {}
            Some(t) => {
                return Err(invalid(
                    &el,
                    "<joint type>".into(),
                    format!("unknown type '{t}' (expected one of {})", TYPES.join(", ")),
                ));
            }
            None => {
                return Err(invalid(
                    &el,
                    "<joint type>".into(),
                    "required attribute is missing".into(),
                ));
            }
        }
        for role in ["parent", "child"] {
            match children(joint, role)
                .next()
                .and_then(|n| n.attribute("link"))
            {
                Some(_) => {}
                None => {
                    return Err(invalid(
                        &el,
                        format!("<{role} link>"),
                        "required element or attribute is missing".into(),
                    ));
                }
            }
        }
        check_origin(&el, joint, "")?;
        for a in children(joint, "axis") {
            check_nums(&el, a, "axis", "xyz", 3, true, false)?;
        }
        let mut lf = LimitFacts::default();
        for l in children(joint, "limit") {
            for attr in ["lower", "upper", "effort", "velocity"] {
                // velocity is required before URDF 1.2
                let required = attr == "velocity" && version < (1, 2);
                check_nums(&el, l, "limit", attr, 1, required, true)?;
            }
            lf.lower = l.attribute("lower").is_some();
            lf.upper = l.attribute("upper").is_some();
        }
        facts.limits.insert(name, lf);
        for d in children(joint, "dynamics") {
            check_nums(&el, d, "dynamics", "damping", 1, false, false)?;
            check_nums(&el, d, "dynamics", "friction", 1, false, false)?;
        }
    }
    Ok(facts)
}
