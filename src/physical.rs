//! Physical bounds of a robot description, shared by `quadsim check` and
//! `quadsim run` (both build the world through [`crate::world::build_world`],
//! which calls [`check_description`] on every robot, URDF or built-in; the
//! URDF import calls it too, so that its errors name the file's line).
//!
//! The bounds (`docs/reliability.md`):
//!
//! | quantity | bound |
//! |---|---|
//! | link mass | finite, 0 ≤ m ≤ [`MAX_MASS_KG`]; the root body (with what is fixed to it) > 0 |
//! | rotational inertia | finite, entries ≤ [`MAX_INERTIA_KGM2`]; for a link with mass: positive definite, principal moments meeting the triangle inequality (each ≤ the sum of the other two) |
//! | centre of mass, joint origins, shape offsets | every coordinate within ±[`MAX_LENGTH_M`] |
//! | shape sizes | box sides, radii > 0 (lengths ≥ 0) and ≤ [`MAX_LENGTH_M`] |

use glam::{DMat3, DVec3};
use quadsim_engine::description::{RobotDescription, Shape};

/// The heaviest link (kg).
pub const MAX_MASS_KG: f64 = 1.0e5;
/// The largest entry of a rotational inertia (kg·m²).
pub const MAX_INERTIA_KGM2: f64 = 1.0e5;
/// The largest coordinate of a robot's geometry (m).
pub const MAX_LENGTH_M: f64 = 1.0e3;

/// Which part of a description is at fault.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalError {
    /// `link` or `joint`.
    pub kind: &'static str,
    /// The link's or joint's name.
    pub name: String,
    /// The field, in URDF's terms, e.g. `<inertial><inertia>`.
    pub field: String,
    /// What is wrong, with the numbers.
    pub why: String,
}

impl std::fmt::Display for PhysicalError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} '{}': {}: {}",
            self.kind, self.name, self.field, self.why
        )
    }
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending (closed form).
pub fn sym_eigenvalues(m: &DMat3) -> [f64; 3] {
    let a = m.to_cols_array_2d();
    let p1 = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
    let mut e = if p1 == 0.0 {
        [a[0][0], a[1][1], a[2][2]]
    } else {
        let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
        let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let b = (*m - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
        let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
        let phi = r.acos() / 3.0;
        let e1 = q + 2.0 * p * phi.cos();
        let e3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
        [e1, e3, 3.0 * q - e1 - e3]
    };
    e.sort_by(f64::total_cmp);
    e
}

/// Why an inertia tensor of a link with mass is not physical, if it is not:
/// entries not finite or beyond the bound, not symmetric, not positive
/// definite, or principal moments breaking the triangle inequality.
pub fn inertia_problem(i: &DMat3, has_mass: bool) -> Option<String> {
    let a = i.to_cols_array();
    if let Some(x) = a
        .iter()
        .find(|x| !x.is_finite() || x.abs() > MAX_INERTIA_KGM2)
    {
        return Some(format!(
            "entry {x} is not a finite number within ±{MAX_INERTIA_KGM2:e} kg·m²"
        ));
    }
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if scale == 0.0 {
        return has_mass.then(|| {
            "a link with mass needs a positive definite inertia, got all zeros".to_string()
        });
    }
    let ev = sym_eigenvalues(i);
    let tol = 1e-9 * scale;
    if ev[0] <= if has_mass { 1e-12 * scale } else { -tol } {
        return Some(format!(
            "not positive definite: principal moments {:.6e}, {:.6e}, {:.6e} kg·m²",
            ev[0], ev[1], ev[2]
        ));
    }
    // each principal moment at most the sum of the other two (a real body)
    if ev[2] > ev[0] + ev[1] + 1e-6 * scale {
        return Some(format!(
            "principal moments {:.6e}, {:.6e}, {:.6e} kg·m² break the triangle inequality \
             ({:.6e} > {:.6e} + {:.6e}): no rigid body has them",
            ev[0], ev[1], ev[2], ev[2], ev[0], ev[1]
        ));
    }
    None
}

fn vec_problem(v: DVec3) -> Option<String> {
    (!v.is_finite() || v.abs().max_element() > MAX_LENGTH_M)
        .then(|| format!("{v} is beyond ±{MAX_LENGTH_M} m (or not finite)"))
}

/// Why a shape's sizes are not usable, if they are not.
pub fn shape_problem(s: &Shape) -> Option<String> {
    let ok = |x: f64, zero_ok: bool| {
        x.is_finite() && x <= MAX_LENGTH_M && if zero_ok { x >= 0.0 } else { x > 0.0 }
    };
    let bad = |what: &str| Some(format!("{what}: must be > 0 and ≤ {MAX_LENGTH_M} m"));
    match s {
        Shape::Box { size_m } => (!size_m.to_array().iter().all(|x| ok(*x, false)))
            .then(|| format!("box size {size_m}: every side must be > 0 and ≤ {MAX_LENGTH_M} m")),
        Shape::Sphere { radius_m } => {
            if ok(*radius_m, false) {
                None
            } else {
                bad(&format!("sphere radius {radius_m}"))
            }
        }
        Shape::Cylinder { radius_m, length_m } | Shape::Capsule { radius_m, length_m } => {
            if ok(*radius_m, false) && ok(*length_m, true) {
                None
            } else {
                Some(format!(
                    "radius {radius_m}, length {length_m}: the radius must be > 0, the length ≥ 0, both ≤ {MAX_LENGTH_M} m"
                ))
            }
        }
        Shape::Mesh { scale, .. } => (!scale.is_finite()
            || scale.abs().max_element() > MAX_LENGTH_M)
            .then(|| format!("mesh scale {scale} is not finite or beyond {MAX_LENGTH_M}")),
    }
}

/// Checks every link and joint of `d` against the bounds above; the first
/// problem found is returned.
pub fn check_description(d: &RobotDescription) -> Result<(), PhysicalError> {
    let link_err = |name: &str, field: &str, why: String| PhysicalError {
        kind: "link",
        name: name.to_string(),
        field: field.to_string(),
        why,
    };
    for l in &d.links {
        let m = l.mass_kg;
        if !(m.is_finite() && (0.0..=MAX_MASS_KG).contains(&m)) {
            return Err(link_err(
                &l.name,
                "<inertial><mass value>",
                format!("{m} kg is not a mass from 0 to {MAX_MASS_KG:e} kg"),
            ));
        }
        if let Some(w) = vec_problem(l.com_m) {
            return Err(link_err(&l.name, "<inertial><origin xyz>", w));
        }
        if let Some(i) = &l.inertia_kgm2
            && let Some(w) = inertia_problem(i, m > 0.0)
        {
            return Err(link_err(&l.name, "<inertial><inertia>", w));
        }
        for (role, gs) in [("collision", &l.collision), ("visual", &l.visual)] {
            for g in gs {
                if let Some(w) = shape_problem(&g.shape) {
                    return Err(link_err(&l.name, &format!("<{role}><geometry>"), w));
                }
                if let Some(w) = vec_problem(g.origin.trans) {
                    return Err(link_err(&l.name, &format!("<{role}><origin xyz>"), w));
                }
            }
        }
    }
    for j in &d.joints {
        if let Some(w) = vec_problem(j.placement.trans) {
            return Err(PhysicalError {
                kind: "joint",
                name: j.name.clone(),
                field: "<origin xyz>".into(),
                why: w,
            });
        }
    }
    // The base body: the root link and everything fixed to it carries mass.
    if let Some(root) = d.root_link() {
        let mut body = vec![root.name.as_str()];
        let mut k = 0;
        while k < body.len() {
            let parent = body[k];
            for j in &d.joints {
                if j.parent == parent && !j.is_movable() && !body.contains(&j.child.as_str()) {
                    body.push(j.child.as_str());
                }
            }
            k += 1;
        }
        let mass: f64 = d
            .links
            .iter()
            .filter(|l| body.contains(&l.name.as_str()))
            .map(|l| l.mass_kg)
            .sum();
        if mass <= 0.0 {
            return Err(link_err(
                &root.name,
                "<inertial><mass value>",
                format!(
                    "the base ('{}' and the links fixed to it) has {mass} kg: a floating base needs mass",
                    root.name
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inertias() {
        let d = DMat3::from_diagonal(DVec3::new(1.0, 2.0, 2.5));
        assert!(inertia_problem(&d, true).is_none());
        // ixy = -1 on a unit diagonal: eigenvalues 0, 1, 2 → not definite
        let mut m = DMat3::IDENTITY;
        m.x_axis.y = -1.0;
        m.y_axis.x = -1.0;
        assert!(
            inertia_problem(&m, true)
                .unwrap()
                .contains("positive definite")
        );
        let t = DMat3::from_diagonal(DVec3::new(1.0, 1.0, 3.0));
        assert!(inertia_problem(&t, true).unwrap().contains("triangle"));
        assert!(inertia_problem(&DMat3::ZERO, false).is_none());
        assert!(inertia_problem(&DMat3::ZERO, true).is_some());
        let ev = sym_eigenvalues(&DMat3::from_cols_array(&[
            2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 5.0,
        ]));
        for (a, b) in ev.iter().zip([1.0, 3.0, 5.0]) {
            assert!((a - b).abs() < 1e-12, "{ev:?}");
        }
    }
}
