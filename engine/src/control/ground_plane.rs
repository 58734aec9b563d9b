//! The ground plane under the feet: a least-squares plane through the
//! terrain's heights at the stance feet and the swing feet's touchdown
//! targets. The torso follows it, as legged controllers do on slopes and
//! steps (Bledt et al. 2018, MIT Cheetah 3, "terrain-adapted body pose"): it
//! keeps its height above the plane rather than above the one point beneath
//! it, and pitches and rolls with it, so that uphill and downhill legs keep
//! their reach.
//!
//! # Frames and signs
//! Slopes are taken in the *heading frame* (world axes turned by the base's
//! yaw about z): `slope.x = ∂z/∂x_heading` (> 0 rising ahead), `slope.y =
//! ∂z/∂y_heading` (> 0 rising to the left). In the base's URDF roll–pitch–yaw
//! (`R = Rz(ψ) Ry(θ) Rx(φ)`, positive pitch is nose down, positive roll is
//! left side up) the plane's attitude is `θ = −atan(slope.x)`, `φ =
//! atan(slope.y)`.

use glam::{DVec2, DVec3};

/// A ground plane `z = height_m + slope · (p − origin)` in heading axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundPlane {
    /// Ground height under the origin of the fit (m, world z).
    pub height_m: f64,
    /// Rise per metre along heading x and heading y (dimensionless).
    pub slope: DVec2,
}

impl GroundPlane {
    /// Level ground at `height_m`.
    pub fn level(height_m: f64) -> Self {
        GroundPlane {
            height_m,
            slope: DVec2::ZERO,
        }
    }

    /// The plane through `points` (world; z the ground's height there) by
    /// least squares, about `origin` (world x, y), its slopes in the heading
    /// frame of yaw `(sin ψ, cos ψ)`. Heights are taken relative to the
    /// first point's, so ground that is level at the points gives exactly
    /// that height and zero slopes. `None` with fewer than three points or
    /// when they are (nearly) collinear.
    pub fn fit(points: &[DVec3], origin: DVec2, (sy, cy): (f64, f64)) -> Option<Self> {
        let first = points.first()?;
        if points.len() < 3 {
            return None;
        }
        let z0 = first.z;
        // normal equations of z − z0 = a + b·x_h + c·y_h, coordinates in
        // heading axes about the origin
        let mut m = [[0.0_f64; 3]; 3];
        let mut r = [0.0_f64; 3];
        let mut scale = 0.0_f64;
        for p in points {
            let d = p.truncate() - origin;
            let x = cy * d.x + sy * d.y;
            let y = -sy * d.x + cy * d.y;
            let row = [1.0, x, y];
            let dz = p.z - z0;
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += row[i] * row[j];
                }
                r[i] += row[i] * dz;
            }
            scale = scale.max(x.abs()).max(y.abs());
        }
        let det = det3(&m);
        // collinear (or coincident) points: the determinant vanishes
        // against the spread of the points (its units are m⁴)
        let tiny = 1e-9 * scale.powi(4).max(1e-12);
        if det.is_nan() || det.abs() <= tiny {
            return None;
        }
        let sol = solve3(&m, &r, det);
        if !sol.iter().all(|s| s.is_finite()) {
            return None;
        }
        Some(GroundPlane {
            height_m: z0 + sol[0],
            slope: DVec2::new(sol[1], sol[2]),
        })
    }

    /// The base attitude that lies along the plane: (roll, pitch) in rad, in
    /// the URDF convention (module doc).
    pub fn roll_pitch_rad(&self) -> (f64, f64) {
        (self.slope.y.atan(), -self.slope.x.atan())
    }

    /// The rate at which the ground under a point moving at `velocity`
    /// (heading axes, m/s) rises (m/s).
    pub fn rise_rate_mps(&self, velocity: DVec2) -> f64 {
        self.slope.dot(velocity)
    }
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Cramer's rule for the 3 × 3 normal equations (`det` is `det3(m)`).
fn solve3(m: &[[f64; 3]; 3], r: &[f64; 3], det: f64) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut mk = *m;
        for i in 0..3 {
            mk[i][k] = r[i];
        }
        *o = det3(&mk) / det;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect() -> Vec<DVec2> {
        vec![
            DVec2::new(0.25, 0.15),
            DVec2::new(0.25, -0.15),
            DVec2::new(-0.25, -0.15),
            DVec2::new(-0.25, 0.15),
        ]
    }

    #[test]
    fn level_ground_gives_its_height_exactly() {
        for h in [0.0, 0.1, -0.37, 1.0 / 3.0] {
            let pts: Vec<DVec3> = rect().iter().map(|p| p.extend(h)).collect();
            let g = GroundPlane::fit(
                &pts,
                DVec2::new(0.01, -0.02),
                (0.3_f64.sin(), 0.3_f64.cos()),
            )
            .unwrap();
            assert_eq!(g.height_m, h);
            assert_eq!(g.slope, DVec2::ZERO);
        }
    }

    #[test]
    fn an_incline_is_recovered_in_heading_axes() {
        // ground z = 0.2 + tan(15°)·x_world − 0.1·y_world, robot yawed by 30°
        let (a, b) = (15f64.to_radians().tan(), -0.1);
        let yaw = 30f64.to_radians();
        let origin = DVec2::new(1.0, 2.0);
        let ground = |p: DVec2| 0.2 + a * p.x + b * p.y;
        let pts: Vec<DVec3> = rect()
            .iter()
            .map(|p| {
                let w = origin
                    + DVec2::new(
                        yaw.cos() * p.x - yaw.sin() * p.y,
                        yaw.sin() * p.x + yaw.cos() * p.y,
                    );
                w.extend(ground(w))
            })
            .collect();
        let g = GroundPlane::fit(&pts, origin, yaw.sin_cos()).unwrap();
        assert!((g.height_m - ground(origin)).abs() < 1e-12);
        // the world gradient (a, b) seen along the heading axes
        let sx = a * yaw.cos() + b * yaw.sin();
        let sy = -a * yaw.sin() + b * yaw.cos();
        assert!((g.slope.x - sx).abs() < 1e-12, "{} vs {sx}", g.slope.x);
        assert!((g.slope.y - sy).abs() < 1e-12);
        // uphill ahead: nose up (negative pitch)
        let (_, pitch) = g.roll_pitch_rad();
        assert!(pitch < 0.0);
    }

    #[test]
    fn a_step_under_the_front_feet_tilts_the_plane_by_least_squares() {
        // front feet on a 0.1 m step: the best plane rises 0.1 m over the
        // 0.5 m between front and hind feet, and passes 0.05 m up midway
        let pts: Vec<DVec3> = rect()
            .iter()
            .map(|p| p.extend(if p.x > 0.0 { 0.1 } else { 0.0 }))
            .collect();
        let g = GroundPlane::fit(&pts, DVec2::ZERO, (0.0, 1.0)).unwrap();
        assert!((g.height_m - 0.05).abs() < 1e-15);
        assert!((g.slope.x - 0.2).abs() < 1e-14);
        assert!(g.slope.y.abs() < 1e-15);
        assert!((g.rise_rate_mps(DVec2::new(1.0, 0.0)) - 0.2).abs() < 1e-14);
    }

    #[test]
    fn collinear_points_have_no_plane() {
        let pts = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.1),
            DVec3::new(2.0, 0.0, 0.2),
        ];
        assert!(GroundPlane::fit(&pts, DVec2::ZERO, (0.0, 1.0)).is_none());
        assert!(GroundPlane::fit(&pts[..2], DVec2::ZERO, (0.0, 1.0)).is_none());
    }
}
