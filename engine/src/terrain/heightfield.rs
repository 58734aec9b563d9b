//! A grid of heights, interpolated bicubically so the surface and its normal
//! are continuous across cells.
//!
//! Grid: `nx × ny` samples, sample `(i, j)` at local
//! `(x₀ + i dx, y₀ + j dy)` with the grid centred on the local origin
//! (`x₀ = −(nx − 1) dx / 2`), stored row-major by y: `heights[j nx + i]`. Its
//! height is `vertical_scale · heights[j nx + i]`.
//!
//! Interpolation: Catmull–Rom cubic along each axis (tensor product). It passes
//! through the samples, and its first derivatives are continuous across cell
//! borders (C¹), so contact normals do not jump; the gradient is evaluated
//! analytically from the same polynomial. Outside the last row/column the
//! samples are clamped (repeated edge values).

use super::{
    LocalBounds, LocalShape, SurfacePoint, Terrain, TerrainError, check_positive, closest_on_graph,
};
use glam::{DVec2, DVec3};

/// Tangent-plane refinements in [`HeightField::closest`] (2 evaluations in all;
/// see [`super::closest_on_graph`] for the error).
const REFINEMENTS: usize = 1;

/// A bicubic height field.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    nx: usize,
    ny: usize,
    spacing_m: DVec2,
    inv_spacing: DVec2,
    origin: DVec2,
    /// Scaled heights (m), row-major by y.
    heights_m: Vec<f64>,
    min_m: f64,
    max_m: f64,
}

/// Catmull–Rom weights `w(t)` and their derivatives `w'(t)` for the four
/// samples `p₋₁, p₀, p₁, p₂` at `t ∈ [0, 1]` between `p₀` and `p₁`.
#[inline]
fn catmull_rom(t: f64) -> ([f64; 4], [f64; 4]) {
    let t2 = t * t;
    let t3 = t2 * t;
    (
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ],
        [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ],
    )
}

impl HeightField {
    /// A grid of `nx × ny` (≥ 2 each) raw heights, sample spacing `spacing_m`
    /// (m, > 0 along local x and y), heights multiplied by `vertical_scale`.
    pub fn new(
        nx: usize,
        ny: usize,
        spacing_m: DVec2,
        vertical_scale: f64,
        heights: &[f64],
    ) -> Result<HeightField, TerrainError> {
        const S: &str = "heightfield";
        for (field, n) in [("nx", nx), ("ny", ny)] {
            if n < 2 {
                return Err(TerrainError::InvalidValue {
                    shape: S,
                    field,
                    value: n as f64,
                    why: "needs at least 2 samples",
                });
            }
        }
        check_positive(S, "spacing_m.x", spacing_m.x, false)?;
        check_positive(S, "spacing_m.y", spacing_m.y, false)?;
        if !vertical_scale.is_finite() {
            return Err(TerrainError::InvalidValue {
                shape: S,
                field: "vertical_scale",
                value: vertical_scale,
                why: "must be finite",
            });
        }
        if heights.len() != nx * ny {
            return Err(TerrainError::GridSize {
                shape: S,
                expected: nx * ny,
                got: heights.len(),
            });
        }
        if let Some(bad) = heights.iter().find(|h| !h.is_finite()) {
            return Err(TerrainError::InvalidValue {
                shape: S,
                field: "heights",
                value: *bad,
                why: "must be finite",
            });
        }
        let heights_m: Vec<f64> = heights.iter().map(|h| h * vertical_scale).collect();
        let min_m = heights_m.iter().copied().fold(f64::INFINITY, f64::min);
        let max_m = heights_m.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let size = DVec2::new((nx - 1) as f64, (ny - 1) as f64) * spacing_m;
        Ok(HeightField {
            nx,
            ny,
            spacing_m,
            inv_spacing: DVec2::ONE / spacing_m,
            origin: -0.5 * size,
            heights_m,
            min_m,
            max_m,
        })
    }

    /// Samples `f(x, y)` (m, local) at the grid points of an `nx × ny` grid.
    pub fn from_fn(
        nx: usize,
        ny: usize,
        spacing_m: DVec2,
        f: impl Fn(f64, f64) -> f64,
    ) -> Result<HeightField, TerrainError> {
        let size = DVec2::new(nx.saturating_sub(1) as f64, ny.saturating_sub(1) as f64) * spacing_m;
        let o = -0.5 * size;
        let mut h = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                h.push(f(
                    o.x + i as f64 * spacing_m.x,
                    o.y + j as f64 * spacing_m.y,
                ));
            }
        }
        Self::new(nx, ny, spacing_m, 1.0, &h)
    }

    /// Samples along x and y.
    pub fn dims(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// Sample spacing (m).
    pub fn spacing_m(&self) -> DVec2 {
        self.spacing_m
    }

    /// Local position of sample `(i, j)` (m).
    pub fn sample_xy(&self, i: usize, j: usize) -> DVec2 {
        self.origin + DVec2::new(i as f64, j as f64) * self.spacing_m
    }

    /// Scaled height of sample `(i, j)` (m).
    pub fn sample(&self, i: usize, j: usize) -> f64 {
        self.heights_m[j * self.nx + i]
    }

    /// Lowest and highest sample (m).
    pub fn range_m(&self) -> (f64, f64) {
        (self.min_m, self.max_m)
    }

    /// Height and gradient `(∂h/∂x, ∂h/∂y)` at local `(x, y)` (clamped into the grid).
    #[inline]
    pub fn eval(&self, x: f64, y: f64) -> (f64, DVec2) {
        let gx = ((x - self.origin.x) * self.inv_spacing.x).clamp(0.0, (self.nx - 1) as f64);
        let gy = ((y - self.origin.y) * self.inv_spacing.y).clamp(0.0, (self.ny - 1) as f64);
        // cell index, the last cell closed on its far side
        let i = (gx as usize).min(self.nx - 2);
        let j = (gy as usize).min(self.ny - 2);
        let (wx, dwx) = catmull_rom(gx - i as f64);
        let (wy, dwy) = catmull_rom(gy - j as f64);
        // the 4 × 4 samples around the cell, rows along y
        let mut v = [[0.0; 4]; 4];
        if i >= 1 && i + 2 < self.nx && j >= 1 && j + 2 < self.ny {
            // interior: four contiguous samples per row
            let base = (j - 1) * self.nx + i - 1;
            for (b, vb) in v.iter_mut().enumerate() {
                let s = base + b * self.nx;
                vb.copy_from_slice(&self.heights_m[s..s + 4]);
            }
        } else {
            // border: indices clamped into the grid (repeated edge samples)
            let xs = [i.saturating_sub(1), i, i + 1, (i + 2).min(self.nx - 1)];
            let ys = [j.saturating_sub(1), j, j + 1, (j + 2).min(self.ny - 1)];
            for (vb, jj) in v.iter_mut().zip(ys) {
                for (va, ii) in vb.iter_mut().zip(xs) {
                    *va = self.heights_m[jj * self.nx + ii];
                }
            }
        }
        // contract along x (value and x-derivative per row), then along y
        let mut r = [0.0; 4];
        let mut rx = [0.0; 4];
        for b in 0..4 {
            let s = &v[b];
            r[b] = wx[0] * s[0] + wx[1] * s[1] + wx[2] * s[2] + wx[3] * s[3];
            rx[b] = dwx[0] * s[0] + dwx[1] * s[1] + dwx[2] * s[2] + dwx[3] * s[3];
        }
        let h = wy[0] * r[0] + wy[1] * r[1] + wy[2] * r[2] + wy[3] * r[3];
        let hx = wy[0] * rx[0] + wy[1] * rx[1] + wy[2] * rx[2] + wy[3] * rx[3];
        let hy = dwy[0] * r[0] + dwy[1] * r[1] + dwy[2] * r[2] + dwy[3] * r[3];
        (
            h,
            DVec2::new(hx * self.inv_spacing.x, hy * self.inv_spacing.y),
        )
    }
}

impl Terrain for HeightField {
    #[inline]
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.bounds().covers(x, y).then(|| self.eval(x, y).0)
    }

    #[inline]
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        let b = self.bounds();
        if !b.covers(p.x, p.y) {
            return None;
        }
        Some(closest_on_graph(p, &b, REFINEMENTS, |x, y| self.eval(x, y)))
    }
}

impl LocalShape for HeightField {
    fn bounds(&self) -> LocalBounds {
        let size = DVec2::new((self.nx - 1) as f64, (self.ny - 1) as f64) * self.spacing_m;
        // Catmull–Rom overshoots: the positive tensor weights sum to at most
        // 1.28125, so h ≤ min + 1.28125 (max − min).
        let top = self.max_m + 0.28125 * (self.max_m - self.min_m);
        LocalBounds::centred(size, f64::NEG_INFINITY, top)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Catmull–Rom reproduces quadratics exactly between interior samples
    /// (it is exact for polynomials of degree ≤ 2), heights and gradients.
    #[test]
    fn reproduces_quadratics() {
        let f = |x: f64, y: f64| 0.3 * x * x - 0.2 * x * y + 0.1 * y + 0.05;
        let hf = HeightField::from_fn(9, 7, DVec2::new(0.25, 0.3), f).unwrap();
        for &(x, y) in &[(0.1, 0.2), (-0.33, 0.41), (0.6, -0.5)] {
            let (h, g) = hf.eval(x, y);
            assert!((h - f(x, y)).abs() < 1e-12, "{h} {}", f(x, y));
            assert!((g.x - (0.6 * x - 0.2 * y)).abs() < 1e-12);
            assert!((g.y - (-0.2 * x + 0.1)).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_grid_is_a_typed_error() {
        let e = HeightField::new(3, 3, DVec2::ONE, 1.0, &[0.0; 8]).unwrap_err();
        assert_eq!(
            e,
            TerrainError::GridSize {
                shape: "heightfield",
                expected: 9,
                got: 8
            }
        );
        let e = HeightField::new(1, 3, DVec2::ONE, 1.0, &[0.0; 3]).unwrap_err();
        assert!(matches!(e, TerrainError::InvalidValue { field: "nx", .. }));
    }
}
