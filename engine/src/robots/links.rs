//! Link builders the built-in robots share (the torso box, solid links).

use super::params::Values;
use crate::description::{Geometry, LinkDesc, Shape};
use crate::spatial::Transform;
use glam::{DMat3, DVec3};

/// A link with a given mass, CoM and inertia, and one shape used for both
/// collision and display.
pub(crate) fn solid_link(name: String, mass_kg: f64, shape: Shape, at: DVec3) -> LinkDesc {
    let inertia = shape.solid_inertia(mass_kg).unwrap_or(DMat3::ZERO);
    let geom = Geometry {
        origin: Transform::from_translation(at),
        shape,
    };
    LinkDesc {
        name,
        mass_kg,
        com_m: at,
        inertia_kgm2: Some(inertia),
        collision: vec![geom.clone()],
        visual: vec![geom],
    }
}

/// The `torso` link of both robots: a solid box of `torso.size_{x,y,z}_m`
/// centred on the base frame, its mass following the box volume unless
/// `torso.mass_kg` is given.
pub(crate) fn box_torso(p: &Values) -> LinkDesc {
    let size = DVec3::new(
        p.get("torso.size_x_m"),
        p.get("torso.size_y_m"),
        p.get("torso.size_z_m"),
    );
    let volume_ratio =
        p.ratio("torso.size_x_m") * p.ratio("torso.size_y_m") * p.ratio("torso.size_z_m");
    let mass = p.mass_following("torso.mass_kg", volume_ratio);
    solid_link(
        "torso".into(),
        mass,
        Shape::Box { size_m: size },
        DVec3::ZERO,
    )
}
