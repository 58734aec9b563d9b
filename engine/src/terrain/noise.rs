//! Seeded random rough ground. The same `seed` (u64) gives the same terrain on
//! every machine: the random numbers come from ChaCha8 seeded with it.
//!
//! - [`NoiseKind::UniformCell`]: independent heights, uniform in `[−A, A]`, at
//!   the corners of square cells of side `cell_m`, interpolated by the C¹
//!   bicubic [`HeightField`] (white noise at the cell scale, smooth inside).
//! - [`NoiseKind::Perlin`]: fractal gradient noise (Perlin 2002, "Improving
//!   noise", quintic fade, so C²) summed over octaves of doubling frequency and
//!   amplitude ratio `persistence`; normalised so `|h| ≤ A`. Evaluated
//!   analytically with its gradient, any extent (infinite allowed).

use super::{
    HeightField, LocalBounds, LocalShape, SurfacePoint, Terrain, TerrainError, check_positive,
    check_size, closest_on_graph,
};
use glam::{DVec2, DVec3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Tangent-plane refinements in [`Rough::closest`].
const REFINEMENTS: usize = 1;

/// Which random field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NoiseKind {
    /// Uniform random heights at the corners of `cell_m` cells (needs a finite extent).
    UniformCell {
        /// Cell side (m).
        cell_m: f64,
    },
    /// Fractal Perlin noise.
    Perlin {
        /// Wavelength of the first octave (m).
        wavelength_m: f64,
        /// Number of octaves (1..=16).
        octaves: u32,
        /// Amplitude ratio between successive octaves (0..1].
        persistence: f64,
    },
}

#[derive(Clone, Debug, PartialEq)]
enum Field {
    Grid(HeightField),
    Perlin {
        perm: Box<[u8; 512]>,
        inv_wavelength: f64,
        octaves: u32,
        persistence: f64,
        /// `A / (Σ persistenceᵒ · √½)`: maps the octave sum into `[−A, A]`.
        scale: f64,
    },
}

/// Seeded random rough terrain over `size_m`, centred on the local origin.
#[derive(Clone, Debug, PartialEq)]
pub struct Rough {
    kind: NoiseKind,
    amplitude_m: f64,
    seed: u64,
    size_m: DVec2,
    field: Field,
}

/// Sixteen unit gradient directions.
const GRADIENTS: [(f64, f64); 16] = {
    // cos/sin of k·22.5°, written out (const fn trig is not available)
    [
        (1.0, 0.0),
        (0.923_879_532_511_286_7, 0.382_683_432_365_089_8),
        (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        (0.382_683_432_365_089_8, 0.923_879_532_511_286_7),
        (0.0, 1.0),
        (-0.382_683_432_365_089_8, 0.923_879_532_511_286_7),
        (
            -std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        (-0.923_879_532_511_286_7, 0.382_683_432_365_089_8),
        (-1.0, 0.0),
        (-0.923_879_532_511_286_7, -0.382_683_432_365_089_8),
        (
            -std::f64::consts::FRAC_1_SQRT_2,
            -std::f64::consts::FRAC_1_SQRT_2,
        ),
        (-0.382_683_432_365_089_8, -0.923_879_532_511_286_7),
        (0.0, -1.0),
        (0.382_683_432_365_089_8, -0.923_879_532_511_286_7),
        (
            std::f64::consts::FRAC_1_SQRT_2,
            -std::f64::consts::FRAC_1_SQRT_2,
        ),
        (0.923_879_532_511_286_7, -0.382_683_432_365_089_8),
    ]
};

/// One octave of Perlin noise and its gradient at `(x, y)` (lattice units).
#[inline]
fn perlin(perm: &[u8; 512], x: f64, y: f64) -> (f64, DVec2) {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let xi = (x0 as i64 & 255) as usize;
    let yi = (y0 as i64 & 255) as usize;
    let grad = |i: usize, j: usize| {
        let h = perm[perm[i] as usize + j] as usize;
        GRADIENTS[h & 15]
    };
    let g00 = grad(xi, yi);
    let g10 = grad(xi + 1, yi);
    let g01 = grad(xi, yi + 1);
    let g11 = grad(xi + 1, yi + 1);
    let n00 = g00.0 * fx + g00.1 * fy;
    let n10 = g10.0 * (fx - 1.0) + g10.1 * fy;
    let n01 = g01.0 * fx + g01.1 * (fy - 1.0);
    let n11 = g11.0 * (fx - 1.0) + g11.1 * (fy - 1.0);
    // quintic fade u = 6t⁵ − 15t⁴ + 10t³ and u' = 30t²(t − 1)²
    let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let dfade = |t: f64| 30.0 * t * t * (t - 1.0) * (t - 1.0);
    let (ux, uy) = (fade(fx), fade(fy));
    let (dux, duy) = (dfade(fx), dfade(fy));
    let k1 = n10 - n00;
    let k2 = n01 - n00;
    let k3 = n00 - n10 - n01 + n11;
    let v = n00 + ux * k1 + uy * k2 + ux * uy * k3;
    // d/dx of each corner term is its gradient's x component
    let dk1x = g10.0 - g00.0;
    let dk2x = g01.0 - g00.0;
    let dk3x = g00.0 - g10.0 - g01.0 + g11.0;
    let dk1y = g10.1 - g00.1;
    let dk2y = g01.1 - g00.1;
    let dk3y = g00.1 - g10.1 - g01.1 + g11.1;
    let dx = g00.0 + ux * dk1x + uy * dk2x + ux * uy * dk3x + dux * (k1 + uy * k3);
    let dy = g00.1 + ux * dk1y + uy * dk2y + ux * uy * dk3y + duy * (k2 + ux * k3);
    (v, DVec2::new(dx, dy))
}

impl Rough {
    /// Rough ground of `kind`, amplitude `amplitude_m` (heights within
    /// `[−A, A]`), from `seed`, over `size_m` (infinite only for Perlin noise).
    pub fn new(
        kind: NoiseKind,
        amplitude_m: f64,
        seed: u64,
        size_m: DVec2,
    ) -> Result<Rough, TerrainError> {
        const S: &str = "rough";
        check_positive(S, "amplitude_m", amplitude_m, true)?;
        check_size(S, size_m)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let field = match kind {
            NoiseKind::UniformCell { cell_m } => {
                check_positive(S, "cell_m", cell_m, false)?;
                check_positive(S, "size_m.x", size_m.x, false)?;
                check_positive(S, "size_m.y", size_m.y, false)?;
                let nx = (size_m.x / cell_m).ceil().max(1.0) as usize + 1;
                let ny = (size_m.y / cell_m).ceil().max(1.0) as usize + 1;
                if nx * ny > 1 << 26 {
                    return Err(TerrainError::InvalidValue {
                        shape: S,
                        field: "cell_m",
                        value: cell_m,
                        why: "gives more than 2²⁶ grid points for this size",
                    });
                }
                let h: Vec<f64> = (0..nx * ny)
                    .map(|_| rng.random_range(-amplitude_m..=amplitude_m))
                    .collect();
                Field::Grid(HeightField::new(nx, ny, DVec2::splat(cell_m), 1.0, &h)?)
            }
            NoiseKind::Perlin {
                wavelength_m,
                octaves,
                persistence,
            } => {
                check_positive(S, "wavelength_m", wavelength_m, false)?;
                if !(1..=16).contains(&octaves) {
                    return Err(TerrainError::InvalidValue {
                        shape: S,
                        field: "octaves",
                        value: octaves as f64,
                        why: "must be in 1..=16",
                    });
                }
                if !(persistence > 0.0 && persistence <= 1.0) {
                    return Err(TerrainError::InvalidValue {
                        shape: S,
                        field: "persistence",
                        value: persistence,
                        why: "must be in (0, 1]",
                    });
                }
                let mut p: Vec<u8> = (0..=255u8).collect();
                p.shuffle(&mut rng);
                let mut perm = Box::new([0u8; 512]);
                for i in 0..512 {
                    perm[i] = p[i & 255];
                }
                let sum: f64 = (0..octaves).map(|o| persistence.powi(o as i32)).sum();
                Field::Perlin {
                    perm,
                    inv_wavelength: 1.0 / wavelength_m,
                    octaves,
                    persistence,
                    scale: amplitude_m / (sum * std::f64::consts::FRAC_1_SQRT_2),
                }
            }
        };
        Ok(Rough {
            kind,
            amplitude_m,
            seed,
            size_m,
            field,
        })
    }

    /// The noise parameters.
    pub fn kind(&self) -> NoiseKind {
        self.kind
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Height and gradient at local `(x, y)`.
    #[inline]
    pub fn eval(&self, x: f64, y: f64) -> (f64, DVec2) {
        match &self.field {
            Field::Grid(g) => g.eval(x, y),
            Field::Perlin {
                perm,
                inv_wavelength,
                octaves,
                persistence,
                scale,
            } => {
                let mut h = 0.0;
                let mut g = DVec2::ZERO;
                let mut freq = *inv_wavelength;
                let mut amp = *scale;
                for _ in 0..*octaves {
                    let (v, d) = perlin(perm, x * freq, y * freq);
                    h += amp * v;
                    g += (amp * freq) * d;
                    freq *= 2.0;
                    amp *= persistence;
                }
                (h, g)
            }
        }
    }
}

impl Terrain for Rough {
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

impl LocalShape for Rough {
    fn bounds(&self) -> LocalBounds {
        let top = match &self.field {
            Field::Grid(g) => g.bounds().max.z,
            Field::Perlin { .. } => self.amplitude_m,
        };
        LocalBounds::centred(self.size_m, f64::NEG_INFINITY, top)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Same seed, same ground; another seed, another ground; heights stay in [−A, A].
    #[test]
    fn reproducible_and_bounded() {
        for kind in [
            NoiseKind::UniformCell { cell_m: 0.1 },
            NoiseKind::Perlin {
                wavelength_m: 0.8,
                octaves: 4,
                persistence: 0.5,
            },
        ] {
            let a = Rough::new(kind, 0.05, 7, DVec2::splat(4.0)).unwrap();
            let b = Rough::new(kind, 0.05, 7, DVec2::splat(4.0)).unwrap();
            let c = Rough::new(kind, 0.05, 8, DVec2::splat(4.0)).unwrap();
            let mut differ = false;
            let mut spread: f64 = 0.0;
            for k in 0..400 {
                let (x, y) = (-1.9 + 0.0093 * k as f64, 1.7 - 0.0087 * k as f64);
                let ha = a.height(x, y).unwrap();
                assert_eq!(ha, b.height(x, y).unwrap());
                differ |= (ha - c.height(x, y).unwrap()).abs() > 1e-6;
                spread = spread.max(ha.abs());
                // the bicubic grid may overshoot its samples (≤ 1.5625 A)
                assert!(ha.abs() <= 0.05 * 1.5625, "{kind:?}: {ha}");
            }
            assert!(differ, "{kind:?}: seeds 7 and 8 gave the same ground");
            assert!(spread > 0.01, "{kind:?}: surface is nearly flat ({spread})");
        }
    }
}
