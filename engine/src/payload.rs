//! Payloads carried on a robot's torso, attached and detached between steps,
//! never inside one.
//!
//! - A **rigid** payload is a solid body bolted to the torso: one more link on
//!   a fixed joint, which compiling merges into the torso's body (mass, CoM
//!   and inertia tensor by the parallel-axis theorem).
//! - A **compliant** payload (a sloshing or soft load) is a body of its own
//!   on a spring–damper, free along the degrees of freedom declared with it
//!   ([`Compliance`]): a chain of prismatic joints (x, y, z in torso axes),
//!   then revolute ones (roll, pitch, yaw: intrinsic angles about the load's
//!   centre), each with a [`JointSpring`] and no actuator. The load is thus
//!   part of the robot's articulation: ABA, the integrators (at every RK4
//!   stage) and the energies include it, and its coordinates close q and v
//!   (see [`crate::model::Model::load_nv`]), so the controllers keep
//!   addressing the leg joints at their usual indices.
//!
//! Detached, a payload's links and joints are removed again.

use glam::DVec3;

use crate::description::{
    Geometry, JointDesc, JointKind, JointSpring, LinkDesc, RobotDescription, Shape,
};
use crate::spatial::Transform;

/// A payload: a uniform solid of `shape`, centred `offset_m` from the torso
/// (base link) frame's origin, in torso axes; rigid, or compliant with
/// `compliance`.
#[derive(Clone, Debug, PartialEq)]
pub struct Payload {
    /// Name (the load's link is `payload_<name>`).
    pub name: String,
    /// Mass (kg), ≥ 0 (> 0 when compliant).
    pub mass_kg: f64,
    /// Shape (sets the inertia tensor; displayed).
    pub shape: Shape,
    /// Centre of the payload in the torso frame (m); for a compliant payload,
    /// where its centre rests when the springs are relaxed (under gravity it
    /// settles `m g / k` lower along a z DOF).
    pub offset_m: DVec3,
    /// `None`: rigid. `Some`: a body of its own on a spring–damper.
    pub compliance: Option<Compliance>,
}

/// A degree of freedom of a compliant payload relative to the torso.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LoadDof {
    /// Translation along torso x (m).
    X,
    /// Translation along torso y (m).
    Y,
    /// Translation along torso z (m).
    Z,
    /// Rotation about the load's x axis (rad).
    Roll,
    /// Rotation about the load's y axis (rad).
    Pitch,
    /// Rotation about the load's z axis (rad).
    Yaw,
}

impl LoadDof {
    /// Every DOF, in chain order (translations, then intrinsic roll–pitch–yaw).
    pub const ALL: [LoadDof; 6] = [
        LoadDof::X,
        LoadDof::Y,
        LoadDof::Z,
        LoadDof::Roll,
        LoadDof::Pitch,
        LoadDof::Yaw,
    ];

    /// The scenario name: `x`, `y`, `z`, `roll`, `pitch`, `yaw`.
    pub fn name(self) -> &'static str {
        match self {
            LoadDof::X => "x",
            LoadDof::Y => "y",
            LoadDof::Z => "z",
            LoadDof::Roll => "roll",
            LoadDof::Pitch => "pitch",
            LoadDof::Yaw => "yaw",
        }
    }

    /// The DOF of a scenario name.
    pub fn parse(name: &str) -> Option<LoadDof> {
        LoadDof::ALL.into_iter().find(|d| d.name() == name)
    }

    /// True for x, y, z.
    pub fn is_translation(self) -> bool {
        matches!(self, LoadDof::X | LoadDof::Y | LoadDof::Z)
    }

    fn joint_kind(self) -> JointKind {
        match self {
            LoadDof::X => JointKind::Prismatic { axis: DVec3::X },
            LoadDof::Y => JointKind::Prismatic { axis: DVec3::Y },
            LoadDof::Z => JointKind::Prismatic { axis: DVec3::Z },
            LoadDof::Roll => JointKind::Revolute { axis: DVec3::X },
            LoadDof::Pitch => JointKind::Revolute { axis: DVec3::Y },
            LoadDof::Yaw => JointKind::Revolute { axis: DVec3::Z },
        }
    }
}

/// One declared DOF of a compliant payload with its spring–damper.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DofSpring {
    /// The DOF.
    pub dof: LoadDof,
    /// Stiffness (N/m for x, y, z; N·m/rad for roll, pitch, yaw), > 0.
    pub stiffness: f64,
    /// Damping (N·s/m or N·m·s/rad), ≥ 0.
    pub damping: f64,
}

/// The spring–damper force element of a compliant payload: its declared
/// DOFs (each once; the chain follows [`LoadDof::ALL`]'s order whatever the
/// declaration's).
#[derive(Clone, Debug, PartialEq)]
pub struct Compliance {
    /// The declared DOFs.
    pub dofs: Vec<DofSpring>,
}

/// Why a payload cannot be attached.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PayloadError {
    /// Negative or non-finite mass, or a degenerate shape.
    #[error("payload '{name}': {what}")]
    Invalid {
        /// The payload.
        name: String,
        /// What is wrong.
        what: String,
    },
    /// The robot has no base link to carry it.
    #[error("payload '{0}': the robot has no root link")]
    NoRoot(String),
    /// A link of the same name exists.
    #[error("payload '{0}': the robot already has a link '{1}'")]
    Duplicate(String, String),
}

impl Payload {
    /// Name of the payload's (load) link.
    pub fn link_name(&self) -> String {
        format!("payload_{}", self.name)
    }

    /// The declared DOFs in chain order (empty for a rigid payload).
    pub fn chain(&self) -> Vec<DofSpring> {
        let mut dofs = self
            .compliance
            .as_ref()
            .map_or_else(Vec::new, |c| c.dofs.clone());
        dofs.sort_by_key(|d| d.dof);
        dofs
    }

    /// Names of every link the payload adds: for a compliant one the
    /// massless links between its DOFs' joints, then the load's.
    pub fn link_names(&self) -> Vec<String> {
        let chain = self.chain();
        let mut out: Vec<String> = chain
            .iter()
            .take(chain.len().saturating_sub(1))
            .map(|d| format!("{}_{}_link", self.link_name(), d.dof.name()))
            .collect();
        out.push(self.link_name());
        out
    }

    /// The payload's links and joints under `parent`: the load's link
    /// (uniform solid, inertia from the shape) on a fixed joint (rigid) or at
    /// the end of a chain of sprung joints, one per declared DOF (compliant;
    /// joints `payload_<name>_<dof>`, no actuator: effort limit 0).
    pub fn parts(&self, parent: &str) -> Result<(Vec<LinkDesc>, Vec<JointDesc>), PayloadError> {
        let invalid = |what: String| PayloadError::Invalid {
            name: self.name.clone(),
            what,
        };
        if !(self.mass_kg.is_finite() && self.mass_kg >= 0.0) {
            return Err(invalid(format!(
                "mass {} kg must be finite and ≥ 0",
                self.mass_kg
            )));
        }
        if !self.offset_m.is_finite() {
            return Err(invalid("offset must be finite".into()));
        }
        let inertia = self
            .shape
            .solid_inertia(self.mass_kg)
            .filter(|i| i.is_finite())
            .ok_or_else(|| invalid(format!("shape {:?} has no finite inertia", self.shape)))?;
        let mut load = LinkDesc::new(self.link_name());
        load.mass_kg = self.mass_kg;
        load.com_m = DVec3::ZERO;
        load.inertia_kgm2 = Some(inertia);
        load.visual.push(Geometry {
            origin: Transform::IDENTITY,
            shape: self.shape.clone(),
        });
        let mount = Transform::from_translation(self.offset_m);
        let Some(compliance) = &self.compliance else {
            let joint = JointDesc::new(
                format!("{}_mount", self.link_name()),
                JointKind::Fixed,
                parent,
                self.link_name(),
                mount,
            );
            return Ok((vec![load], vec![joint]));
        };
        if compliance.dofs.is_empty() {
            return Err(invalid(
                "a compliant payload needs at least one DOF (or make it rigid)".into(),
            ));
        }
        if self.mass_kg <= 0.0 {
            return Err(invalid("a compliant payload needs a mass > 0 kg".into()));
        }
        let chain = self.chain();
        for w in chain.windows(2) {
            if w[0].dof == w[1].dof {
                return Err(invalid(format!("DOF '{}' declared twice", w[0].dof.name())));
            }
        }
        for d in &chain {
            if !(d.stiffness.is_finite() && d.stiffness > 0.0) {
                return Err(invalid(format!(
                    "DOF '{}': stiffness {} must be finite and > 0 (a free load would leave the robot)",
                    d.dof.name(),
                    d.stiffness
                )));
            }
            if !(d.damping.is_finite() && d.damping >= 0.0) {
                return Err(invalid(format!(
                    "DOF '{}': damping {} must be finite and ≥ 0",
                    d.dof.name(),
                    d.damping
                )));
            }
        }
        let names = self.link_names();
        let mut links: Vec<LinkDesc> = names[..names.len() - 1]
            .iter()
            .map(|n| LinkDesc::new(n.clone()))
            .collect();
        links.push(load);
        let mut joints = Vec::with_capacity(chain.len());
        for (k, d) in chain.iter().enumerate() {
            let mut j = JointDesc::new(
                format!("{}_{}", self.link_name(), d.dof.name()),
                d.dof.joint_kind(),
                if k == 0 { parent } else { &names[k - 1] },
                names[k].clone(),
                if k == 0 { mount } else { Transform::IDENTITY },
            );
            j.effort_limit = 0.0;
            j.spring = Some(JointSpring {
                stiffness: d.stiffness,
                damping: d.damping,
            });
            joints.push(j);
        }
        Ok((links, joints))
    }

    /// Adds the payload to a description, on its root (torso) link. A
    /// compliant payload's joints go last, so its coordinates close q and v.
    pub fn attach_to(&self, desc: &mut RobotDescription) -> Result<(), PayloadError> {
        let root = desc
            .root_link()
            .ok_or_else(|| PayloadError::NoRoot(self.name.clone()))?
            .name
            .clone();
        for n in self.link_names() {
            if desc.link(&n).is_some() {
                return Err(PayloadError::Duplicate(self.name.clone(), n));
            }
        }
        let (links, joints) = self.parts(&root)?;
        desc.links.extend(links);
        desc.joints.extend(joints);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::center_of_mass;
    use crate::kinematics::forward_kinematics_pos;
    use crate::model::{BaseKind, Model};
    use crate::{Data, robots};

    #[test]
    fn attaching_changes_total_mass_and_com_exactly() {
        let bare_desc = robots::builtin("quad16").unwrap();
        let bare = Model::from_description(&bare_desc, BaseKind::Floating).unwrap();
        let p = Payload {
            name: "box".into(),
            mass_kg: 10.0,
            shape: Shape::Box {
                size_m: DVec3::new(0.3, 0.2, 0.1),
            },
            offset_m: DVec3::new(0.05, -0.02, 0.1),
            compliance: None,
        };
        let mut desc = bare_desc.clone();
        p.attach_to(&mut desc).unwrap();
        let loaded = Model::from_description(&desc, BaseKind::Floating).unwrap();
        assert_eq!(
            (loaded.nq, loaded.nv, loaded.nbodies),
            (bare.nq, bare.nv, bare.nbodies)
        );
        assert!((loaded.total_mass - (bare.total_mass + 10.0)).abs() < 1e-12);
        // at a tilted, displaced pose: CoM = (M c + m p) / (M + m), p the
        // payload centre in the world
        let mut q = bare.neutral_q();
        let rot = glam::DQuat::from_euler(glam::EulerRot::ZYX, 0.4, -0.2, 0.3);
        q[..7].copy_from_slice(&[1.0, -2.0, 0.6, rot.x, rot.y, rot.z, rot.w]);
        for (k, x) in q[7..].iter_mut().enumerate() {
            *x = 0.1 * (k as f64) - 0.5;
        }
        let (mut d0, mut d1) = (Data::new(&bare), Data::new(&loaded));
        forward_kinematics_pos(&bare, &mut d0, &q);
        forward_kinematics_pos(&loaded, &mut d1, &q);
        let c0 = center_of_mass(&bare, &d0);
        let c1 = center_of_mass(&loaded, &d1);
        let pw = DVec3::new(1.0, -2.0, 0.6) + rot * p.offset_m;
        let want = (c0 * bare.total_mass + pw * 10.0) / (bare.total_mass + 10.0);
        assert!((c1 - want).length() < 1e-12, "{c1} vs {want}");
        // the torso body's rotational inertia about the payload centre grew by
        // the box's own: m (b² + c²) / 12 about x
        let ix = |m: &Model| {
            let i = m.inertia[0];
            let d = i.com - p.offset_m;
            i.inertia_com.x_axis.x + i.mass * (d.y * d.y + d.z * d.z)
        };
        let own = 10.0 * (0.2f64.powi(2) + 0.1f64.powi(2)) / 12.0;
        assert!((ix(&loaded) - ix(&bare) - own).abs() < 1e-12);
    }

    #[test]
    fn bad_payloads_say_why() {
        let mut desc = robots::builtin("quad16").unwrap();
        let mut p = Payload {
            name: "x".into(),
            mass_kg: -1.0,
            shape: Shape::Sphere { radius_m: 0.1 },
            offset_m: DVec3::ZERO,
            compliance: None,
        };
        assert!(
            p.attach_to(&mut desc)
                .unwrap_err()
                .to_string()
                .contains("mass")
        );
        p.mass_kg = 1.0;
        p.attach_to(&mut desc).unwrap();
        assert!(matches!(
            p.attach_to(&mut desc),
            Err(PayloadError::Duplicate(..))
        ));
    }
}
