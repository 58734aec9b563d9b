//! Terrains with closed-form heights and exact closest points: flat, incline,
//! sinusoid. Each extends over `size_m` (local x, y; may be infinite) centred
//! on its local origin.

use super::{
    LocalBounds, LocalShape, SurfacePoint, Terrain, TerrainError, check_positive, check_size,
};
use glam::{DVec2, DVec3};
use std::f64::consts::{FRAC_PI_2, TAU};

/// The plane `z = 0` (local).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flat {
    size_m: DVec2,
}

impl Flat {
    /// A flat patch of `size_m` (m, local x × y; infinite allowed).
    pub fn new(size_m: DVec2) -> Result<Flat, TerrainError> {
        check_size("flat", size_m)?;
        Ok(Flat { size_m })
    }

    /// An infinite plane.
    pub fn infinite() -> Flat {
        Flat {
            size_m: DVec2::INFINITY,
        }
    }
}

impl Terrain for Flat {
    #[inline]
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.bounds().covers(x, y).then_some(0.0)
    }

    #[inline]
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        self.bounds().covers(p.x, p.y).then(|| SurfacePoint {
            depth_m: -p.z,
            normal: DVec3::Z,
            point: DVec3::new(p.x, p.y, 0.0),
        })
    }
}

impl LocalShape for Flat {
    fn bounds(&self) -> LocalBounds {
        LocalBounds::centred(self.size_m, f64::NEG_INFINITY, 0.0)
    }
}

/// The plane `z = tan(θ) x` (local): it rises along local +x; turn the patch
/// (its yaw) to point the slope anywhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incline {
    slope_rad: f64,
    tan: f64,
    normal: DVec3,
    size_m: DVec2,
}

impl Incline {
    /// An incline of `slope_rad` (|θ| < π/2; negative descends along +x) over `size_m`.
    pub fn new(slope_rad: f64, size_m: DVec2) -> Result<Incline, TerrainError> {
        check_size("incline", size_m)?;
        if !slope_rad.is_finite() || slope_rad.abs() >= FRAC_PI_2 {
            return Err(TerrainError::InvalidValue {
                shape: "incline",
                field: "slope_rad",
                value: slope_rad,
                why: "must be finite with |slope| < π/2",
            });
        }
        Ok(Incline {
            slope_rad,
            tan: slope_rad.tan(),
            normal: DVec3::new(-slope_rad.sin(), 0.0, slope_rad.cos()),
            size_m,
        })
    }

    /// Slope angle (rad).
    pub fn slope_rad(&self) -> f64 {
        self.slope_rad
    }
}

impl Terrain for Incline {
    #[inline]
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.bounds().covers(x, y).then_some(self.tan * x)
    }

    /// Exact: the plane passes through the origin with unit normal `n`, so the
    /// depth is `−p·n` and the surface point `p + depth n`.
    #[inline]
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        if !self.bounds().covers(p.x, p.y) {
            return None;
        }
        let depth_m = -p.dot(self.normal);
        Some(SurfacePoint {
            depth_m,
            normal: self.normal,
            point: p + depth_m * self.normal,
        })
    }
}

impl LocalShape for Incline {
    fn bounds(&self) -> LocalBounds {
        let hx = 0.5 * self.size_m.x;
        let top = if self.tan == 0.0 {
            0.0
        } else {
            (self.tan * hx).abs()
        };
        LocalBounds::centred(self.size_m, f64::NEG_INFINITY, top)
    }
}

/// The corrugation `z = A sin(2π x / λ)` (local), crests parallel to local y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sinusoid {
    amplitude_m: f64,
    wavelength_m: f64,
    wavenumber: f64,
    size_m: DVec2,
}

impl Sinusoid {
    /// A sinusoid of amplitude `amplitude_m` (≥ 0) and wavelength `wavelength_m` (> 0) over `size_m`.
    pub fn new(
        amplitude_m: f64,
        wavelength_m: f64,
        size_m: DVec2,
    ) -> Result<Sinusoid, TerrainError> {
        check_positive("sinusoid", "amplitude_m", amplitude_m, true)?;
        check_positive("sinusoid", "wavelength_m", wavelength_m, false)?;
        check_size("sinusoid", size_m)?;
        Ok(Sinusoid {
            amplitude_m,
            wavelength_m,
            wavenumber: TAU / wavelength_m,
            size_m,
        })
    }

    /// Wavelength (m).
    pub fn wavelength_m(&self) -> f64 {
        self.wavelength_m
    }

    /// `(h, h', h'')` at local `x`.
    #[inline]
    fn eval(&self, x: f64) -> (f64, f64, f64) {
        let (s, c) = (self.wavenumber * x).sin_cos();
        let a = self.amplitude_m;
        let k = self.wavenumber;
        (a * s, a * k * c, -a * k * k * s)
    }
}

impl Terrain for Sinusoid {
    #[inline]
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.bounds().covers(x, y).then(|| self.eval(x).0)
    }

    /// Exact to round-off: the surface is a cylinder along y, so the closest
    /// point solves the 1-D stationarity condition
    /// `g(x) = (x − pₓ) + (h(x) − p_z) h'(x) = 0` by Newton's method from
    /// `x = pₓ` (falling back to the tangent-plane step where `g' ≤ ½`, i.e.
    /// beyond the local centre of curvature). Near the surface it converges
    /// in two iterations, the second rotating the first's sine and cosine by
    /// the small step instead of calling `sin_cos` again.
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        let b = self.bounds();
        if !b.covers(p.x, p.y) {
            return None;
        }
        let (a, k) = (self.amplitude_m, self.wavenumber);
        let mut x = p.x;
        let (mut sin, mut cos) = (k * x).sin_cos();
        let mut converged = None;
        for _ in 0..16 {
            let (h, h1, h2) = (a * sin, a * k * cos, -a * k * k * sin);
            let g = (x - p.x) + (h - p.z) * h1;
            let gp = 1.0 + h1 * h1 + (h - p.z) * h2;
            let step = if gp > 0.5 {
                g / gp
            } else {
                g / (1.0 + h1 * h1)
            };
            if step.abs() <= 1e-9 {
                // Converged: after Newton's last step x is exact to O(step²),
                // and so are h and h' updated to first order (≈ 1e-18 m),
                // so no further evaluation is needed.
                converged = Some((x - step, h - h1 * step, h1 - h2 * step));
                break;
            }
            let next = (x - step).clamp(b.min.x, b.max.x);
            let d = k * (next - x);
            if d.abs() < 1e-3 {
                // rotate (sin, cos) by d: Taylor terms to d⁵ (error < d⁶/720 ≈ 1e-21)
                let d2 = d * d;
                let cd = 1.0 - d2 / 2.0 + d2 * d2 / 24.0;
                let sd = d * (1.0 - d2 / 6.0 + d2 * d2 / 120.0);
                (sin, cos) = (sin * cd + cos * sd, cos * cd - sin * sd);
            } else {
                (sin, cos) = (k * next).sin_cos();
            }
            x = next;
        }
        let (x, h, h1) = converged.unwrap_or((x, a * sin, a * k * cos));
        let normal = DVec3::new(-h1, 0.0, 1.0).normalize();
        let point = DVec3::new(x, p.y, h);
        Some(SurfacePoint {
            depth_m: -(p - point).dot(normal),
            normal,
            point,
        })
    }
}

impl LocalShape for Sinusoid {
    fn bounds(&self) -> LocalBounds {
        LocalBounds::centred(self.size_m, f64::NEG_INFINITY, self.amplitude_m)
    }
}
