//! Many terrain patches in one world, queried as the union of their solids.
//!
//! Rules:
//! - [`TerrainUnion::closest`] answers with the patch whose surface is deepest
//!   into `p` (the largest signed depth): the surface a point is in contact
//!   with, or, above everything, the nearest one. Where patches overlap, the
//!   highest surface wins.
//! - [`TerrainUnion::height`] is the highest patch surface above `(x, y)`.
//! - Outside every patch's footprint there is no ground, unless a
//!   [`DefaultGround`] is set: an infinite horizontal plane consulted only
//!   where no patch covers `(x, y)` (so it does not fill trenches or gaps a
//!   patch owns; stones and box obstacles own only their own footprints).

use super::{SurfacePoint, Terrain, TerrainPatch};
use crate::material::GroundMaterial;
use glam::DVec3;

/// The infinite plane used where no patch covers the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultGround {
    /// Height of the plane (m, world z).
    pub height_m: f64,
    /// Its material.
    pub material: GroundMaterial,
}

/// A set of terrain patches and an optional default ground.
#[derive(Clone, Debug, Default)]
pub struct TerrainUnion {
    patches: Vec<TerrainPatch>,
    default_ground: Option<DefaultGround>,
}

impl TerrainUnion {
    /// No ground at all.
    pub fn new() -> TerrainUnion {
        TerrainUnion::default()
    }

    /// Only an infinite plane at `height_m` of `material`.
    pub fn flat(height_m: f64, material: GroundMaterial) -> TerrainUnion {
        TerrainUnion {
            patches: Vec::new(),
            default_ground: Some(DefaultGround { height_m, material }),
        }
    }

    /// Adds a patch.
    pub fn push(&mut self, patch: TerrainPatch) -> &mut Self {
        self.patches.push(patch);
        self
    }

    /// Adds a patch (builder style).
    pub fn with(mut self, patch: TerrainPatch) -> Self {
        self.patches.push(patch);
        self
    }

    /// Sets (or clears) the default ground.
    pub fn set_default_ground(&mut self, ground: Option<DefaultGround>) -> &mut Self {
        self.default_ground = ground;
        self
    }

    /// Sets the default ground (builder style).
    pub fn with_default_ground(mut self, height_m: f64, material: GroundMaterial) -> Self {
        self.default_ground = Some(DefaultGround { height_m, material });
        self
    }

    /// The patches.
    pub fn patches(&self) -> &[TerrainPatch] {
        &self.patches
    }

    /// The default ground.
    pub fn default_ground(&self) -> Option<&DefaultGround> {
        self.default_ground.as_ref()
    }

    /// True when some patch covers world `(x, y)`.
    #[inline]
    pub fn covered(&self, x: f64, y: f64) -> bool {
        self.patches.iter().any(|t| t.covers(x, y))
    }

    /// The closest surface point to `p` (world) and the material there.
    #[inline]
    pub fn closest_with_material(&self, p: DVec3) -> Option<(SurfacePoint, &GroundMaterial)> {
        self.closest_hit(p)
            .map(|h| (h.surface, self.material(h.source)))
    }

    /// The closest surface point to `p` (world) and where it comes from.
    /// Patches whose bounds are farther than the best answer so far are skipped.
    ///
    /// Always inlined: on the usual world (a default plane, a few patches) the
    /// query is a handful of comparisons once inlined into its caller, and
    /// three times that when called out of line (its `Option` result goes
    /// through memory). Whether LLVM inlines a plain `#[inline]` copy into
    /// another crate's caller depends on what else shares the caller's codegen
    /// unit, so an unrelated edit could add 600 instructions to a one-robot
    /// step (the fall check's twelve queries in `observe_robot`).
    #[inline(always)]
    pub fn closest_hit(&self, p: DVec3) -> Option<TerrainHit> {
        let mut best: Option<TerrainHit> = None;
        // coverage matters only for the default ground
        let mut covered = self.default_ground.is_none();
        for (source, t) in self.patches.iter().enumerate() {
            let l = t.to_local(p);
            covered = covered || t.covers_local(l);
            // Outside a patch's bounds its depth is at most −(distance to them):
            // skip it when that cannot beat the best depth so far.
            if let Some(b) = &best {
                let d2 = t.distance_bound_squared_local(l);
                let depth = b.surface.depth_m;
                if d2 > 0.0 && (depth >= 0.0 || d2 >= depth * depth) {
                    continue;
                }
            }
            if let Some(surface) = t.closest_local(l)
                && best.is_none_or(|b| surface.depth_m > b.surface.depth_m)
            {
                best = Some(TerrainHit { surface, source });
            }
        }
        if !covered && let Some(g) = &self.default_ground {
            let surface = SurfacePoint {
                depth_m: g.height_m - p.z,
                normal: DVec3::Z,
                point: DVec3::new(p.x, p.y, g.height_m),
            };
            if best.is_none_or(|b| surface.depth_m > b.surface.depth_m) {
                best = Some(TerrainHit {
                    surface,
                    source: TerrainHit::DEFAULT_GROUND,
                });
            }
        }
        best
    }

    /// The material of a [`TerrainHit::source`].
    ///
    /// # Panics
    /// When `source` is neither a patch index nor [`TerrainHit::DEFAULT_GROUND`]
    /// with a default ground set.
    #[inline]
    pub fn material(&self, source: usize) -> &GroundMaterial {
        if source == TerrainHit::DEFAULT_GROUND {
            &self
                .default_ground
                .as_ref()
                .expect("a default ground for TerrainHit::DEFAULT_GROUND")
                .material
        } else {
            self.patches[source].material()
        }
    }
}

/// A surface point found in a [`TerrainUnion`] and its source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainHit {
    /// The closest surface point.
    pub surface: SurfacePoint,
    /// Index of the patch it belongs to, or [`TerrainHit::DEFAULT_GROUND`].
    pub source: usize,
}

impl TerrainHit {
    /// Source index of the default ground.
    pub const DEFAULT_GROUND: usize = usize::MAX;
}

impl Terrain for TerrainUnion {
    #[inline]
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        let mut top: Option<f64> = None;
        let mut covered = false;
        for t in &self.patches {
            if t.covers(x, y) {
                covered = true;
                if let Some(h) = t.height(x, y) {
                    top = Some(top.map_or(h, |c: f64| c.max(h)));
                }
            }
        }
        if !covered {
            return self.default_ground.map(|g| g.height_m);
        }
        top
    }

    #[inline]
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        self.closest_with_material(p).map(|(s, _)| s)
    }
}
