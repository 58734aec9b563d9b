//! The packed, immutable articulation model (Pinocchio's `Model`, MuJoCo's `mjModel`).
//!
//! Bodies live in flat arrays with `parent[i] < i` (body 0 is the base). Links
//! joined by fixed joints are merged into one body; every link remains reachable
//! as a [`Frame`]. Generalised coordinates follow Pinocchio's conventions:
//!
//! - floating base: `q = [x, y, z, qx, qy, qz, qw, joints…]` (position of the base
//!   origin in the world, unit quaternion rotating base vectors into the world),
//!   `v = [v_lin, ω, q̇…]` with `v_lin` (velocity of the base origin) and `ω` both
//!   in the **base** frame;
//! - fixed base: `q` and `v` hold the joints only.
//!
//! Movable joints appear in q and v in the order of the description's joints
//! (the URDF document order).

use crate::description::{JointKind, RobotDescription};
use crate::plan::{LEGS, LegLanes, Plan};
use crate::spatial::{RigidInertia, Transform};
use glam::{DMat3, DVec3};
use thiserror::Error;

/// Marker for the base's parent.
pub const NO_PARENT: usize = usize::MAX;

/// How a body moves relative to its parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointType {
    /// Six DOF: the floating base (nq 7, nv 6).
    Free,
    /// Welded to the world: a fixed base (nq 0, nv 0).
    Anchored,
    /// One rotational DOF about `axis`.
    Revolute,
    /// One translational DOF along `axis`.
    Prismatic,
}

impl JointType {
    /// Size of the joint's configuration.
    pub fn nq(self) -> usize {
        match self {
            JointType::Free => 7,
            JointType::Anchored => 0,
            _ => 1,
        }
    }

    /// Size of the joint's velocity.
    pub fn nv(self) -> usize {
        match self {
            JointType::Free => 6,
            JointType::Anchored => 0,
            _ => 1,
        }
    }
}

/// Whether the base floats (a free joint) or is welded to the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BaseKind {
    /// The base is a free body (legged robots).
    #[default]
    Floating,
    /// The base is welded to the world at the identity.
    Fixed,
}

/// A named frame (one per link of the description) attached to a body.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Link name.
    pub name: String,
    /// Body the link belongs to (after fixed joints are merged).
    pub body: usize,
    /// Placement of the link frame in the body frame.
    pub placement: Transform,
}

/// Errors found while compiling a description.
#[derive(Debug, Error, PartialEq)]
pub enum ModelError {
    /// No link is free of a parent joint.
    #[error("robot '{robot}': no root link (every link is some joint's child)")]
    NoRoot {
        /// Robot name.
        robot: String,
    },
    /// More than one link is free of a parent joint.
    #[error("robot '{robot}': several root links ({roots}); a robot is one tree")]
    SeveralRoots {
        /// Robot name.
        robot: String,
        /// The roots found.
        roots: String,
    },
    /// A joint names a link that does not exist.
    #[error("joint '{joint}': unknown {role} link '{link}'")]
    UnknownLink {
        /// Joint name.
        joint: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The missing link.
        link: String,
    },
    /// Two links or two joints share a name.
    #[error("duplicate {what} name '{name}'")]
    Duplicate {
        /// `link` or `joint`.
        what: &'static str,
        /// The name.
        name: String,
    },
    /// A link is the child of two joints, or the joints form a loop.
    #[error("link '{link}' is reached twice (a loop or two parent joints); a robot is a tree")]
    NotATree {
        /// The link.
        link: String,
    },
    /// A number is out of its domain.
    #[error("{item}: field '{field}' = {value} is invalid ({why})")]
    InvalidValue {
        /// Link or joint name.
        item: String,
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
        /// What is wrong.
        why: &'static str,
    },
    /// A foot names a link that does not exist.
    #[error("foot '{0}' is not a link of the robot")]
    UnknownFoot(String),
}

/// The immutable articulation model. Arrays indexed by body have length
/// `nbodies`; arrays indexed by velocity have length `nv`.
#[derive(Clone, Debug)]
pub struct Model {
    /// Name of the description it was compiled from. Robots of one
    /// articulation may share one model (see [`Model::same_articulation`]),
    /// which then carries the first one's name: a robot's own name is kept
    /// beside the model (its `Robot` component in the ECS).
    pub name: String,
    /// Configuration size.
    pub nq: usize,
    /// Velocity size.
    pub nv: usize,
    /// Number of bodies (after fixed links are merged), including the base.
    pub nbodies: usize,
    /// Parent body of each body, `parent[i] < i`; [`NO_PARENT`] for the base.
    pub parent: Vec<usize>,
    /// Joint type of each body's parent joint.
    pub joint_type: Vec<JointType>,
    /// Name of each body's parent joint (`root_joint` for the base).
    pub joint_name: Vec<String>,
    /// Joint frame in the parent body's frame at zero position (nbodies).
    pub placement: Vec<Transform>,
    /// Unit joint axis in the body frame (nbodies; zero for the base).
    pub axis: Vec<DVec3>,
    /// Inertia of each body in its own frame, fixed children merged (nbodies).
    pub inertia: Vec<RigidInertia>,
    /// First index of each body's joint in q (nbodies).
    pub idx_q: Vec<usize>,
    /// First index of each body's joint in v (nbodies).
    pub idx_v: Vec<usize>,
    /// Body moved by each velocity coordinate (nv).
    pub v_body: Vec<usize>,
    /// Lower position limit (rad or m), −∞ when none (nv; base entries −∞).
    pub lower_limit: Vec<f64>,
    /// Upper position limit (rad or m), +∞ when none (nv).
    pub upper_limit: Vec<f64>,
    /// Effort limit (N·m or N), +∞ when none (nv; base entries +∞).
    pub effort_limit: Vec<f64>,
    /// Velocity limit (rad/s or m/s), +∞ when none (nv).
    pub velocity_limit: Vec<f64>,
    /// Viscous damping (N·m·s/rad or N·s/m) (nv).
    pub damping: Vec<f64>,
    /// Coulomb joint friction (N·m or N) (nv).
    pub friction: Vec<f64>,
    /// Reflected rotor inertia on the diagonal of M (kg·m² or kg) (nv).
    pub armature: Vec<f64>,
    /// One frame per link of the description, in description order.
    pub frames: Vec<Frame>,
    /// Frame index of each foot.
    pub feet: Vec<usize>,
    /// Gravity (m/s², world frame).
    pub gravity: DVec3,
    /// Whole-robot mass (kg).
    pub total_mass: f64,
    /// Joint springs (compliant payloads' force elements), one per sprung coordinate.
    pub springs: Vec<SpringElement>,
    /// Number of trailing coordinates (the last `load_nv` of q and of v, and
    /// the last `load_nv` bodies) that belong to compliant payloads: sprung,
    /// unactuated, not addressed by controllers (see [`Model::actuated_nv`]).
    pub load_nv: usize,
    /// Which shortcuts forward kinematics may take for each body, derived
    /// from `joint_type`, `axis`, `placement` and `inertia` when the model is
    /// compiled (nbodies).
    pub pose_step: Vec<PoseStep>,
    /// Bodies 1.. ordered by depth in the tree, then by index (nbodies − 1):
    /// parents come before children, and consecutive bodies are mostly on
    /// different branches (the legs), so the CPU can overlap their
    /// dependency chains. Walked backwards it visits the children of any
    /// body in decreasing index, as `(1..n).rev()` does, so sums over
    /// children keep their order.
    pub depth_order: Vec<usize>,
    /// How the algorithms run for this model ([`crate::dispatch`]): its
    /// four legs in lanes where its shape allows ([`Plan::LegsX4`]), else
    /// [`Plan::Scalar`]. Decided when the model is compiled.
    pub plan: Plan,
}

/// Whether a diagonal inertia is turned by [`RigidInertia::transformed_diagonal`]
/// (27 products instead of 45). Off: its results differ from the full product
/// in the last bits, and quad16's trot over sine waves (`tests/trot_sine.rs`)
/// and its step-up and in-place pronk (`engine/tests/walking.rs`) fall with
/// last-bit changes to the dynamics; on once those gaits are robust to them.
pub(crate) const DIAGONAL_INERTIA_SHORTCUT: bool = false;

impl Model {
    /// The legs' grouping when the model runs its four legs in lanes
    /// ([`Plan::LegsX4`]).
    pub fn leg_lanes(&self) -> Option<&LegLanes> {
        match &self.plan {
            Plan::LegsX4(legs) => Some(legs),
            Plan::Scalar => None,
        }
    }
}

/// The grouping of `m`'s legs for [`Plan::LegsX4`], when every body but the
/// base is on one of four unbranched chains from the base, all of one
/// length, and the four joints at each depth are revolute about the same
/// signed unit axis of their joint frames with the same placement shortcuts
/// (quad16, quad12); `None` otherwise, and on other architectures than
/// x86-64 (the scalar path then runs).
fn leg_lanes(m: &Model) -> Option<LegLanes> {
    let n = m.nbodies;
    if !cfg!(target_arch = "x86_64")
        || DIAGONAL_INERTIA_SHORTCUT
        || n < 1 + LEGS
        || !(n - 1).is_multiple_of(LEGS)
        || m.depth_order.len() != n - 1
        || m.pose_step.len() != n
    {
        return None;
    }
    let groups: Vec<[usize; LEGS]> = m
        .depth_order
        .chunks_exact(LEGS)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    for (g, grp) in groups.iter().enumerate() {
        let first = m.pose_step[grp[0]];
        first.aligned_axis?;
        for (k, &i) in grp.iter().enumerate() {
            let want_parent = if g == 0 { 0 } else { groups[g - 1][k] };
            let st = m.pose_step[i];
            if m.parent[i] != want_parent
                || m.joint_type[i] != JointType::Revolute
                || st.aligned_axis != first.aligned_axis
                || st.placement_rotates != first.placement_rotates
                || st.placement_translates != first.placement_translates
            {
                return None;
            }
        }
    }
    // Each body of group g − 1 is then the parent of exactly one body of
    // group g (the same lane), so every chain is unbranched.
    let ng = groups.len();
    let leg_major = groups
        .iter()
        .enumerate()
        .all(|(g, grp)| grp.iter().enumerate().all(|(k, &i)| i == 1 + k * ng + g));
    Some(LegLanes {
        #[cfg(target_arch = "x86_64")]
        steps: groups
            .iter()
            .map(|grp| {
                let st = m.pose_step[grp[0]];
                crate::plan::GroupStep::new(&crate::plan::GroupBodies {
                    placement: grp.map(|i| m.placement[i]),
                    inertia: grp.map(|i| m.inertia[i]),
                    axis: st.aligned_axis.expect("checked above"),
                    rotates: st.placement_rotates,
                    translates: st.placement_translates,
                    idx_q: grp.map(|i| m.idx_q[i]),
                    idx_v: grp.map(|i| m.idx_v[i]),
                })
            })
            .collect(),
        groups,
        leg_major,
    })
}

/// The shortcuts of forward kinematics for one body, decided once per model
/// rather than tested on every call. Each is exact: the shortcut skips only
/// products with exact zeros and ones.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseStep {
    /// The placement's rotation is not exactly the identity (else its product is skipped).
    pub placement_rotates: bool,
    /// The placement's translation is not exactly zero (else its product is skipped).
    pub placement_translates: bool,
    /// A revolute joint about exactly ±(the k-th unit axis): `Some((k, ±1.0))`;
    /// its rotation then changes two columns of the joint frame (no axis–angle matrix).
    pub aligned_axis: Option<(usize, f64)>,
    /// The inertia about the CoM is diagonal in the body frame, so turning it
    /// into the world frame needs no full 3×3 product
    /// ([`RigidInertia::transformed_diagonal`]).
    pub inertia_diagonal: bool,
}

impl PoseStep {
    /// The shortcuts for body `i` of `m`.
    pub fn of(m: &Model, i: usize) -> PoseStep {
        let pl = &m.placement[i];
        let ic = m.inertia[i].inertia_com;
        let aligned_axis = match m.joint_type[i] {
            JointType::Revolute => aligned_axis(m.axis[i]),
            _ => None,
        };
        PoseStep {
            placement_rotates: pl.rot != DMat3::IDENTITY,
            placement_translates: pl.trans != DVec3::ZERO,
            aligned_axis,
            inertia_diagonal: ic.x_axis.y == 0.0
                && ic.x_axis.z == 0.0
                && ic.y_axis.x == 0.0
                && ic.y_axis.z == 0.0
                && ic.z_axis.x == 0.0
                && ic.z_axis.y == 0.0,
        }
    }
}

/// `Some((k, ±1))` when `axis` is ±(the k-th unit vector) exactly.
#[inline]
pub fn aligned_axis(axis: DVec3) -> Option<(usize, f64)> {
    match (axis.x == 0.0, axis.y == 0.0, axis.z == 0.0) {
        (false, true, true) => Some((0, axis.x.signum())),
        (true, false, true) => Some((1, axis.y.signum())),
        (true, true, false) => Some((2, axis.z.signum())),
        _ => None,
    }
}

/// A linear spring–damper on one joint coordinate, at rest at q = 0:
/// `τ = −k q − b q̇` (from the description's [`crate::description::JointSpring`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringElement {
    /// Index of the coordinate in q.
    pub iq: usize,
    /// Index of the coordinate in v.
    pub iv: usize,
    /// Stiffness (N/m or N·m/rad).
    pub stiffness: f64,
    /// Damping (N·s/m or N·m·s/rad).
    pub damping: f64,
}

/// Standard gravity used by default (m/s², world z up).
pub const STANDARD_GRAVITY: DVec3 = DVec3::new(0.0, 0.0, -9.81);

impl Model {
    /// Compiles a description. The root link becomes body 0 with a free joint
    /// ([`BaseKind::Floating`]) or welded to the world ([`BaseKind::Fixed`]).
    pub fn from_description(desc: &RobotDescription, base: BaseKind) -> Result<Model, ModelError> {
        validate(desc)?;
        // Lookups by name in hash maps, so that compiling is linear in the
        // number of links (a 5,000-joint URDF chain took 18 s with scans).
        let children: std::collections::HashSet<&str> =
            desc.joints.iter().map(|j| j.child.as_str()).collect();
        let mut by_name: std::collections::HashMap<&str, usize> =
            std::collections::HashMap::with_capacity(desc.links.len());
        for (i, l) in desc.links.iter().enumerate() {
            by_name.entry(l.name.as_str()).or_insert(i);
        }
        let roots: Vec<&str> = desc
            .links
            .iter()
            .filter(|l| !children.contains(l.name.as_str()))
            .map(|l| l.name.as_str())
            .collect();
        let root = match roots.as_slice() {
            [] => {
                return Err(ModelError::NoRoot {
                    robot: desc.name.clone(),
                });
            }
            [r] => *r,
            _ => {
                return Err(ModelError::SeveralRoots {
                    robot: desc.name.clone(),
                    roots: roots.join(", "),
                });
            }
        };
        let link_index = |name: &str| by_name.get(name).copied();

        // link -> (body, placement in body), filled as the tree is walked
        let mut link_body: Vec<Option<(usize, Transform)>> = vec![None; desc.links.len()];
        let root_idx = link_index(root).expect("root exists");
        link_body[root_idx] = Some((0, Transform::IDENTITY));

        let base_type = match base {
            BaseKind::Floating => JointType::Free,
            BaseKind::Fixed => JointType::Anchored,
        };
        let mut m = Model {
            name: desc.name.clone(),
            nq: base_type.nq(),
            nv: base_type.nv(),
            nbodies: 1,
            parent: vec![NO_PARENT],
            joint_type: vec![base_type],
            joint_name: vec!["root_joint".to_string()],
            placement: vec![Transform::IDENTITY],
            axis: vec![DVec3::ZERO],
            inertia: vec![RigidInertia::ZERO],
            idx_q: vec![0],
            idx_v: vec![0],
            v_body: vec![0; base_type.nv()],
            lower_limit: vec![f64::NEG_INFINITY; base_type.nv()],
            upper_limit: vec![f64::INFINITY; base_type.nv()],
            effort_limit: vec![f64::INFINITY; base_type.nv()],
            velocity_limit: vec![f64::INFINITY; base_type.nv()],
            damping: vec![0.0; base_type.nv()],
            friction: vec![0.0; base_type.nv()],
            armature: vec![0.0; base_type.nv()],
            frames: Vec::new(),
            feet: Vec::new(),
            gravity: STANDARD_GRAVITY,
            total_mass: 0.0,
            springs: Vec::new(),
            load_nv: 0,
            pose_step: Vec::new(),
            depth_order: Vec::new(),
            plan: Plan::Scalar,
        };

        // Movable joints take q/v slots in document order, whatever the body order.
        let mut movable_rank = vec![usize::MAX; desc.joints.len()];
        let mut k = 0;
        for (ji, j) in desc.joints.iter().enumerate() {
            if j.is_movable() {
                movable_rank[ji] = k;
                k += 1;
            }
        }
        let (q0, v0) = (m.nq, m.nv);
        m.nq += k;
        m.nv += k;
        for v in [
            &mut m.lower_limit,
            &mut m.upper_limit,
            &mut m.effort_limit,
            &mut m.velocity_limit,
        ] {
            v.resize(m.nv, 0.0);
        }
        m.damping.resize(m.nv, 0.0);
        m.friction.resize(m.nv, 0.0);
        m.armature.resize(m.nv, 0.0);
        m.v_body.resize(m.nv, 0);

        // Place joints parents-first, keeping document order where the document allows.
        let mut placed = vec![false; desc.joints.len()];
        let mut remaining = desc.joints.len();
        while remaining > 0 {
            let mut progress = false;
            for (ji, j) in desc.joints.iter().enumerate() {
                if placed[ji] {
                    continue;
                }
                let pi = link_index(&j.parent).expect("validated");
                let Some((pbody, p_in_body)) = link_body[pi] else {
                    continue;
                };
                let ci = link_index(&j.child).expect("validated");
                if link_body[ci].is_some() {
                    return Err(ModelError::NotATree {
                        link: j.child.clone(),
                    });
                }
                let joint_in_body = p_in_body.compose(&j.placement);
                match j.kind {
                    JointKind::Fixed => {
                        link_body[ci] = Some((pbody, joint_in_body));
                    }
                    JointKind::Revolute { axis } | JointKind::Prismatic { axis } => {
                        let b = m.nbodies;
                        m.nbodies += 1;
                        m.parent.push(pbody);
                        m.joint_type
                            .push(if matches!(j.kind, JointKind::Revolute { .. }) {
                                JointType::Revolute
                            } else {
                                JointType::Prismatic
                            });
                        m.joint_name.push(j.name.clone());
                        m.placement.push(joint_in_body);
                        m.axis.push(axis.normalize());
                        m.inertia.push(RigidInertia::ZERO);
                        let r = movable_rank[ji];
                        m.idx_q.push(q0 + r);
                        let iv = v0 + r;
                        m.idx_v.push(iv);
                        m.v_body[iv] = b;
                        let (lo, hi) = j.limits.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                        m.lower_limit[iv] = lo;
                        m.upper_limit[iv] = hi;
                        m.effort_limit[iv] = j.effort_limit;
                        m.velocity_limit[iv] = j.velocity_limit;
                        m.damping[iv] = j.damping;
                        m.friction[iv] = j.friction;
                        m.armature[iv] = j.armature;
                        if let Some(sp) = j.spring {
                            m.springs.push(SpringElement {
                                iq: q0 + r,
                                iv,
                                stiffness: sp.stiffness,
                                damping: sp.damping,
                            });
                        }
                        link_body[ci] = Some((b, Transform::IDENTITY));
                    }
                }
                placed[ji] = true;
                remaining -= 1;
                progress = true;
            }
            if !progress {
                let j = desc
                    .joints
                    .iter()
                    .enumerate()
                    .find(|(i, _)| !placed[*i])
                    .map(|(_, j)| j)
                    .expect("remaining");
                return Err(ModelError::NotATree {
                    link: j.child.clone(),
                });
            }
        }

        // Merge link inertias into their bodies; one frame per link.
        for (li, l) in desc.links.iter().enumerate() {
            let (body, x) = link_body[li].ok_or_else(|| ModelError::NotATree {
                link: l.name.clone(),
            })?;
            let ri = l.rigid_inertia().transformed(&x);
            m.inertia[body] = m.inertia[body].combined(&ri);
            m.frames.push(crate::model::Frame {
                name: l.name.clone(),
                body,
                placement: x,
            });
        }
        m.total_mass = desc.links.iter().map(|l| l.mass_kg).sum();
        // frames are one per link, in link order: a frame's index is its link's
        for f in desc.foot_names() {
            let fi = by_name
                .get(f.as_str())
                .copied()
                .ok_or(ModelError::UnknownFoot(f.clone()))?;
            m.feet.push(fi);
        }
        // Compliant payloads' coordinates and bodies must close the model, so
        // that the actuated joints and the bodies controllers address keep
        // their indices when a load is attached or detached.
        m.springs.sort_by_key(|s| s.iv);
        m.load_nv = m.springs.len();
        let first_load_v = m.nv - m.load_nv;
        let first_load_body = m.nbodies - m.load_nv;
        for (k, s) in m.springs.iter().enumerate() {
            let body = m.v_body[s.iv];
            if s.iv != first_load_v + k || body < first_load_body {
                return Err(ModelError::InvalidValue {
                    item: m.joint_name[body].clone(),
                    field: "spring",
                    value: s.iv as f64,
                    why: "a sprung (compliant payload) joint must come after every other \
                          joint, parents first, in the description",
                });
            }
        }
        m.pose_step = (0..m.nbodies).map(|i| PoseStep::of(&m, i)).collect();
        let mut depth = vec![0usize; m.nbodies];
        for i in 1..m.nbodies {
            depth[i] = depth[m.parent[i]] + 1;
        }
        m.depth_order = (1..m.nbodies).collect();
        m.depth_order.sort_by_key(|&i| (depth[i], i));
        m.plan = match leg_lanes(&m) {
            Some(legs) => Plan::LegsX4(legs),
            None => Plan::Scalar,
        };
        Ok(m)
    }

    /// Whether `other` describes the same articulation: every field equal
    /// (numbers compared as `f64`, so `+0 = −0`) except [`Model::name`].
    /// Robots whose models are the same articulation can share one model and
    /// be stepped together in SIMD lanes ([`crate::batch`]); the name is the
    /// only per-robot field (it is the robot's own name after a scenario
    /// build, which keeps it beside the model).
    pub fn same_articulation(&self, other: &Model) -> bool {
        // Destructured in full, so that a new field cannot be forgotten here.
        let Model {
            name: _,
            nq,
            nv,
            nbodies,
            parent,
            joint_type,
            joint_name,
            placement,
            axis,
            inertia,
            idx_q,
            idx_v,
            v_body,
            lower_limit,
            upper_limit,
            effort_limit,
            velocity_limit,
            damping,
            friction,
            armature,
            frames,
            feet,
            gravity,
            total_mass,
            springs,
            load_nv,
            // derived from the fields above when the model is compiled
            pose_step: _,
            depth_order: _,
            plan: _,
        } = self;
        *nq == other.nq
            && *nv == other.nv
            && *nbodies == other.nbodies
            && *load_nv == other.load_nv
            && *parent == other.parent
            && *joint_type == other.joint_type
            && *joint_name == other.joint_name
            && *placement == other.placement
            && *axis == other.axis
            && *inertia == other.inertia
            && *idx_q == other.idx_q
            && *idx_v == other.idx_v
            && *v_body == other.v_body
            && *lower_limit == other.lower_limit
            && *upper_limit == other.upper_limit
            && *effort_limit == other.effort_limit
            && *velocity_limit == other.velocity_limit
            && *damping == other.damping
            && *friction == other.friction
            && *armature == other.armature
            && *frames == other.frames
            && *feet == other.feet
            && *gravity == other.gravity
            && *total_mass == other.total_mass
            && *springs == other.springs
    }

    /// Size of the actuated part of v: the base and the joints, without
    /// compliant payloads' trailing coordinates.
    pub fn actuated_nv(&self) -> usize {
        self.nv - self.load_nv
    }

    /// Size of the actuated part of q (the base and the joints).
    pub fn actuated_nq(&self) -> usize {
        self.nq - self.load_nv
    }

    /// Index of the frame (link) with this name.
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }

    /// Index in v of the movable joint with this name.
    pub fn joint_v_index(&self, name: &str) -> Option<usize> {
        (1..self.nbodies)
            .find(|&b| self.joint_name[b] == name)
            .map(|b| self.idx_v[b])
    }

    /// Names of the velocity coordinates' joints, in v order (movable joints only).
    pub fn movable_joint_names(&self) -> Vec<&str> {
        let mut out = vec![""; self.nv - self.base_nv()];
        for b in 1..self.nbodies {
            out[self.idx_v[b] - self.base_nv()] = &self.joint_name[b];
        }
        out
    }

    /// True for a floating base.
    pub fn is_floating(&self) -> bool {
        self.joint_type[0] == JointType::Free
    }

    /// Size of the base's velocity (6 floating, 0 fixed).
    pub fn base_nv(&self) -> usize {
        self.joint_type[0].nv()
    }

    /// Size of the base's configuration (7 floating, 0 fixed).
    pub fn base_nq(&self) -> usize {
        self.joint_type[0].nq()
    }

    /// The neutral configuration: base at the origin with identity orientation, joints at zero.
    pub fn neutral_q(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.nq];
        if self.is_floating() {
            q[6] = 1.0;
        }
        q
    }
}

fn validate(desc: &RobotDescription) -> Result<(), ModelError> {
    let bad =
        |item: &str, field: &'static str, value: f64, why: &'static str| ModelError::InvalidValue {
            item: item.to_string(),
            field,
            value,
            why,
        };
    let mut links = std::collections::HashSet::with_capacity(desc.links.len());
    for l in &desc.links {
        if !links.insert(l.name.as_str()) {
            return Err(ModelError::Duplicate {
                what: "link",
                name: l.name.clone(),
            });
        }
        if !(l.mass_kg.is_finite() && l.mass_kg >= 0.0) {
            return Err(bad(&l.name, "mass", l.mass_kg, "must be finite and ≥ 0"));
        }
        if !l.com_m.is_finite() {
            return Err(bad(&l.name, "com", f64::NAN, "must be finite"));
        }
        if let Some(ii) = l.inertia_kgm2 {
            if !ii.is_finite() {
                return Err(bad(&l.name, "inertia", f64::NAN, "must be finite"));
            }
            let d = ii.diagonal();
            for v in [d.x, d.y, d.z] {
                if v < 0.0 {
                    return Err(bad(&l.name, "inertia", v, "diagonal must be ≥ 0"));
                }
            }
        }
    }
    let mut joints = std::collections::HashSet::with_capacity(desc.joints.len());
    for j in &desc.joints {
        if !joints.insert(j.name.as_str()) {
            return Err(ModelError::Duplicate {
                what: "joint",
                name: j.name.clone(),
            });
        }
        for (role, link) in [("parent", &j.parent), ("child", &j.child)] {
            if !links.contains(link.as_str()) {
                return Err(ModelError::UnknownLink {
                    joint: j.name.clone(),
                    role,
                    link: link.clone(),
                });
            }
        }
        if !j.placement.is_valid(1e-6) {
            return Err(bad(
                &j.name,
                "origin",
                f64::NAN,
                "must be finite with an orthonormal rotation",
            ));
        }
        if let JointKind::Revolute { axis } | JointKind::Prismatic { axis } = j.kind {
            let n = axis.length();
            if !(n.is_finite() && n > 1e-9) {
                return Err(bad(&j.name, "axis", n, "must be a non-zero finite vector"));
            }
        }
        if let Some((lo, hi)) = j.limits
            && (lo.is_nan() || hi.is_nan() || lo > hi)
        {
            return Err(bad(&j.name, "limit", hi - lo, "lower must be ≤ upper"));
        }
        for (field, v) in [
            ("effort", j.effort_limit),
            ("velocity", j.velocity_limit),
            ("damping", j.damping),
            ("friction", j.friction),
            ("armature", j.armature),
        ] {
            if v.is_nan() || v < 0.0 {
                return Err(bad(&j.name, field, v, "must be ≥ 0"));
            }
        }
        if let Some(sp) = j.spring {
            for (field, v) in [
                ("spring stiffness", sp.stiffness),
                ("spring damping", sp.damping),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(bad(&j.name, field, v, "must be finite and ≥ 0"));
                }
            }
            if !j.is_movable() {
                return Err(bad(
                    &j.name,
                    "spring",
                    0.0,
                    "a fixed joint cannot carry a spring",
                ));
            }
        }
    }
    Ok(())
}
