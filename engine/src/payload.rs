//! Rigid payloads: a solid body bolted to a robot's torso. Attached, it is one
//! more link on a fixed joint, which compiling merges into the torso's body
//! (mass, CoM and inertia tensor by the parallel-axis theorem); detached, the
//! link is removed again. Both happen between steps, never inside one.

use glam::DVec3;

use crate::description::{Geometry, JointDesc, JointKind, LinkDesc, RobotDescription, Shape};
use crate::spatial::Transform;

/// A rigid payload: a uniform solid of `shape`, centred `offset_m` from the
/// torso (base link) frame's origin, in torso axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Payload {
    /// Name (the link is `payload_<name>`, its joint `payload_<name>_mount`).
    pub name: String,
    /// Mass (kg), ≥ 0.
    pub mass_kg: f64,
    /// Shape (sets the inertia tensor; displayed).
    pub shape: Shape,
    /// Centre of the payload in the torso frame (m).
    pub offset_m: DVec3,
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
    /// Name of the payload's link.
    pub fn link_name(&self) -> String {
        format!("payload_{}", self.name)
    }

    /// The payload's link (uniform solid, inertia from the shape) and the
    /// fixed joint that mounts it on `parent`.
    pub fn parts(&self, parent: &str) -> Result<(LinkDesc, JointDesc), PayloadError> {
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
        let mut link = LinkDesc::new(self.link_name());
        link.mass_kg = self.mass_kg;
        link.com_m = DVec3::ZERO;
        link.inertia_kgm2 = Some(inertia);
        link.visual.push(Geometry {
            origin: Transform::IDENTITY,
            shape: self.shape.clone(),
        });
        let joint = JointDesc::new(
            format!("{}_mount", self.link_name()),
            JointKind::Fixed,
            parent,
            self.link_name(),
            Transform::from_translation(self.offset_m),
        );
        Ok((link, joint))
    }

    /// Adds the payload to a description, on its root (torso) link.
    pub fn attach_to(&self, desc: &mut RobotDescription) -> Result<(), PayloadError> {
        let root = desc
            .root_link()
            .ok_or_else(|| PayloadError::NoRoot(self.name.clone()))?
            .name
            .clone();
        if desc.link(&self.link_name()).is_some() {
            return Err(PayloadError::Duplicate(self.name.clone(), self.link_name()));
        }
        let (link, joint) = self.parts(&root)?;
        desc.links.push(link);
        desc.joints.push(joint);
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
