//! Terrains built from solid boxes: trench, stairs, box obstacles, stepping
//! stones. Distances come from parry's exact point projection on a
//! [`Cuboid`], so a foot beside a riser or a stone gets the horizontal normal
//! and the true (signed) distance, and a sphere rounding an edge sees the
//! rounded Minkowski surface.
//!
//! A set of boxes answers with its *deepest* penetration (the largest signed
//! depth). The sets are laid out so that a face lying inside another box of
//! the set is never the answer near the surface: stair steps are nested (each
//! step's box runs to the far end of the flight), and a trench's floor box spans
//! the whole width under both banks. Solids reach [`SOLID_THICKNESS_M`] below
//! their lowest surface.

use super::{LocalBounds, LocalShape, SurfacePoint, Terrain, TerrainError, check_positive};
use glam::{DVec2, DVec3};
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{Cuboid, FeatureId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Thickness of the solids below their lowest surface (m).
pub const SOLID_THICKNESS_M: f64 = 1.0;

/// A box in a shape's local frame, turned by a yaw about its centre.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SolidBox {
    centre: DVec3,
    cuboid: Cuboid,
    cos: f64,
    sin: f64,
}

impl SolidBox {
    fn new(min: DVec3, max: DVec3) -> SolidBox {
        SolidBox {
            centre: 0.5 * (min + max),
            cuboid: Cuboid::new(0.5 * (max - min)),
            cos: 1.0,
            sin: 0.0,
        }
    }

    fn rotated(centre: DVec3, half: DVec3, yaw: f64) -> SolidBox {
        SolidBox {
            centre,
            cuboid: Cuboid::new(half),
            cos: yaw.cos(),
            sin: yaw.sin(),
        }
    }

    #[inline]
    fn box_local(&self, p: DVec3) -> DVec3 {
        let d = p - self.centre;
        DVec3::new(
            self.cos * d.x + self.sin * d.y,
            -self.sin * d.x + self.cos * d.y,
            d.z,
        )
    }

    #[inline]
    fn vec_from_box(&self, v: DVec3) -> DVec3 {
        DVec3::new(
            self.cos * v.x - self.sin * v.y,
            self.sin * v.x + self.cos * v.y,
            v.z,
        )
    }

    #[inline]
    fn top(&self) -> f64 {
        self.centre.z + self.cuboid.half_extents.z
    }

    #[inline]
    fn covers(&self, x: f64, y: f64) -> bool {
        let l = self.box_local(DVec3::new(x, y, self.centre.z));
        let h = self.cuboid.half_extents;
        l.x.abs() <= h.x && l.y.abs() <= h.y
    }

    /// Signed distance (> 0 inside), outward normal and surface point.
    #[inline]
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let l = self.box_local(p);
        let proj = self.cuboid.project_local_point(l, false);
        let diff = proj.point - l;
        let dist = diff.length();
        let (depth_m, n) = if dist > 1e-12 {
            if proj.is_inside {
                (dist, diff / dist)
            } else {
                (-dist, -diff / dist)
            }
        } else {
            // On the surface: the normal of the face it lies on.
            let (_, feature) = self.cuboid.project_local_point_and_get_feature(l);
            let n = match feature {
                FeatureId::Face(i) if i < 3 => DVec3::AXES[i as usize],
                FeatureId::Face(i) if i < 6 => -DVec3::AXES[i as usize - 3],
                _ => DVec3::Z,
            };
            (0.0, n)
        };
        SurfacePoint {
            depth_m,
            normal: self.vec_from_box(n),
            point: self.centre + self.vec_from_box(proj.point),
        }
    }
}

/// Deepest penetration over `boxes`.
#[inline]
fn deepest<'a>(boxes: impl Iterator<Item = &'a SolidBox>, p: DVec3) -> Option<SurfacePoint> {
    let mut best: Option<SurfacePoint> = None;
    for b in boxes {
        let s = b.closest(p);
        if best.is_none_or(|c| s.depth_m > c.depth_m) {
            best = Some(s);
        }
    }
    best
}

/// Highest top over the boxes covering `(x, y)`.
#[inline]
fn highest<'a>(boxes: impl Iterator<Item = &'a SolidBox>, x: f64, y: f64) -> Option<f64> {
    boxes
        .filter(|b| b.covers(x, y))
        .map(SolidBox::top)
        .reduce(f64::max)
}

fn bounds_of(boxes: &[SolidBox]) -> LocalBounds {
    let mut min = DVec3::INFINITY;
    let mut max = DVec3::NEG_INFINITY;
    for b in boxes {
        let h = b.cuboid.half_extents;
        // the yawed box's horizontal reach
        let r = DVec3::new(
            b.cos.abs() * h.x + b.sin.abs() * h.y,
            b.sin.abs() * h.x + b.cos.abs() * h.y,
            h.z,
        );
        min = min.min(b.centre - r);
        max = max.max(b.centre + r);
    }
    LocalBounds { min, max }
}

/// A trench across local x: ground at `z = 0` on both banks, a gap of
/// `width_m` centred on the local y axis with its floor at `z = −depth_m`,
/// over `size_m` (finite).
#[derive(Clone, Debug, PartialEq)]
pub struct Trench {
    width_m: f64,
    depth_m: f64,
    size_m: DVec2,
    boxes: [SolidBox; 3],
}

impl Trench {
    /// A trench of `width_m` and `depth_m` in a patch of `size_m` (`size_m.x > width_m`).
    pub fn new(width_m: f64, depth_m: f64, size_m: DVec2) -> Result<Trench, TerrainError> {
        const S: &str = "trench";
        check_positive(S, "width_m", width_m, false)?;
        check_positive(S, "depth_m", depth_m, false)?;
        check_positive(S, "size_m.x", size_m.x, false)?;
        check_positive(S, "size_m.y", size_m.y, false)?;
        if size_m.x <= width_m {
            return Err(TerrainError::InvalidValue {
                shape: S,
                field: "size_m.x",
                value: size_m.x,
                why: "must exceed width_m",
            });
        }
        let (hx, hy, hw) = (0.5 * size_m.x, 0.5 * size_m.y, 0.5 * width_m);
        let bottom = -depth_m - SOLID_THICKNESS_M;
        let boxes = [
            SolidBox::new(DVec3::new(-hx, -hy, bottom), DVec3::new(-hw, hy, 0.0)),
            SolidBox::new(DVec3::new(hw, -hy, bottom), DVec3::new(hx, hy, 0.0)),
            // the floor spans both banks so its sides never face the trench
            SolidBox::new(DVec3::new(-hx, -hy, bottom), DVec3::new(hx, hy, -depth_m)),
        ];
        Ok(Trench {
            width_m,
            depth_m,
            size_m,
            boxes,
        })
    }

    /// Width (m) and depth (m).
    pub fn width_depth_m(&self) -> (f64, f64) {
        (self.width_m, self.depth_m)
    }
}

impl Terrain for Trench {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        highest(self.boxes.iter(), x, y)
    }
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        deepest(self.boxes.iter(), p)
    }
}

impl LocalShape for Trench {
    fn bounds(&self) -> LocalBounds {
        LocalBounds::centred(self.size_m, -self.depth_m - SOLID_THICKNESS_M, 0.0)
    }
}

/// Whether a flight climbs or descends along local +x.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StairDirection {
    /// From `z = 0` at `x = 0` up `count` steps to a top landing.
    Up,
    /// The mirror image: a top landing from `x = 0`, then `count` steps down to `z = 0`.
    Down,
}

/// A flight of `count` steps along local +x, `width_m` wide (centred on local
/// y), standing on `z = 0`. Up: step `i` (0-based) covers
/// `x ∈ [i run, (i + 1) run]` with its tread at `(i + 1) rise`, then a landing
/// of `landing_m` at `count · rise`. Down is the mirror image about the middle
/// of the flight, so both stand on the ground they start or end at.
#[derive(Clone, Debug, PartialEq)]
pub struct Stairs {
    direction: StairDirection,
    rise_m: f64,
    run_m: f64,
    count: usize,
    width_m: f64,
    landing_m: f64,
    boxes: Vec<SolidBox>,
}

impl Stairs {
    /// A flight of `count` (1..=1000) steps of `rise_m` × `run_m`, `width_m`
    /// wide, with a landing of `landing_m` (≥ 0) at the top.
    pub fn new(
        direction: StairDirection,
        rise_m: f64,
        run_m: f64,
        count: usize,
        width_m: f64,
        landing_m: f64,
    ) -> Result<Stairs, TerrainError> {
        const S: &str = "stairs";
        check_positive(S, "rise_m", rise_m, false)?;
        check_positive(S, "run_m", run_m, false)?;
        check_positive(S, "width_m", width_m, false)?;
        check_positive(S, "landing_m", landing_m, true)?;
        if !(1..=1000).contains(&count) {
            return Err(TerrainError::InvalidValue {
                shape: S,
                field: "count",
                value: count as f64,
                why: "must be in 1..=1000",
            });
        }
        let length = count as f64 * run_m + landing_m;
        let hy = 0.5 * width_m;
        let bottom = -SOLID_THICKNESS_M;
        let boxes = (0..count)
            .map(|i| {
                let top = (i + 1) as f64 * rise_m;
                let (x0, x1) = match direction {
                    StairDirection::Up => (i as f64 * run_m, length),
                    StairDirection::Down => (0.0, length - i as f64 * run_m),
                };
                SolidBox::new(DVec3::new(x0, -hy, bottom), DVec3::new(x1, hy, top))
            })
            .collect();
        Ok(Stairs {
            direction,
            rise_m,
            run_m,
            count,
            width_m,
            landing_m,
            boxes,
        })
    }

    /// Direction, rise (m), run (m), count.
    pub fn steps(&self) -> (StairDirection, f64, f64, usize) {
        (self.direction, self.rise_m, self.run_m, self.count)
    }

    /// Flight length including the landing (m).
    pub fn length_m(&self) -> f64 {
        self.count as f64 * self.run_m + self.landing_m
    }

    /// Width (m).
    pub fn width_m(&self) -> f64 {
        self.width_m
    }
}

impl Terrain for Stairs {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        highest(self.boxes.iter(), x, y)
    }
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        deepest(self.boxes.iter(), p)
    }
}

impl LocalShape for Stairs {
    fn bounds(&self) -> LocalBounds {
        bounds_of(&self.boxes)
    }
}

/// One obstacle of [`BoxObstacles`], in the patch's local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxSpec {
    /// Centre (m).
    pub centre_m: DVec3,
    /// Full side lengths (m, > 0).
    pub size_m: DVec3,
    /// Yaw about local z (rad).
    pub yaw_rad: f64,
}

/// Solid boxes (rocks, kerbs, platforms). Each covers only its own footprint,
/// so the default ground shows between them.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxObstacles {
    specs: Vec<BoxSpec>,
    boxes: Vec<SolidBox>,
}

impl BoxObstacles {
    /// Boxes from their specs (at least one).
    pub fn new(specs: Vec<BoxSpec>) -> Result<BoxObstacles, TerrainError> {
        const S: &str = "boxes";
        if specs.is_empty() {
            return Err(TerrainError::InvalidValue {
                shape: S,
                field: "boxes",
                value: 0.0,
                why: "needs at least one box",
            });
        }
        for s in &specs {
            for (field, v) in [
                ("size_m.x", s.size_m.x),
                ("size_m.y", s.size_m.y),
                ("size_m.z", s.size_m.z),
            ] {
                check_positive(S, field, v, false)?;
            }
            for (field, v) in [
                ("centre_m.x", s.centre_m.x),
                ("centre_m.y", s.centre_m.y),
                ("centre_m.z", s.centre_m.z),
                ("yaw_rad", s.yaw_rad),
            ] {
                if !v.is_finite() {
                    return Err(TerrainError::InvalidValue {
                        shape: S,
                        field,
                        value: v,
                        why: "must be finite",
                    });
                }
            }
        }
        let boxes = specs
            .iter()
            .map(|s| SolidBox::rotated(s.centre_m, 0.5 * s.size_m, s.yaw_rad))
            .collect();
        Ok(BoxObstacles { specs, boxes })
    }

    /// The boxes as given.
    pub fn specs(&self) -> &[BoxSpec] {
        &self.specs
    }
}

impl Terrain for BoxObstacles {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        highest(self.boxes.iter(), x, y)
    }
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        deepest(self.boxes.iter(), p)
    }
}

impl LocalShape for BoxObstacles {
    fn bounds(&self) -> LocalBounds {
        bounds_of(&self.boxes)
    }
    fn covers(&self, x: f64, y: f64) -> bool {
        self.boxes.iter().any(|b| b.covers(x, y))
    }
}

/// A `cols × rows` grid of columns (local x × y) centred on the local origin,
/// tops `stone_size_m` wide with `gap_m` between them, at `height_m` plus a
/// seeded uniform jitter in `[−jitter, jitter]`, each `column_m` tall. Each
/// stone covers only its own footprint: the gaps show the default ground (or
/// nothing, a pit). Queries look at the 3 × 3 stones around the point, exact
/// within a pitch of the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct SteppingStones {
    cols: usize,
    rows: usize,
    pitch: DVec2,
    first: DVec2,
    boxes: Vec<SolidBox>,
}

impl SteppingStones {
    /// See the type's doc; `cols`, `rows` in 1..=10000.
    pub fn new(
        cols: usize,
        rows: usize,
        stone_size_m: DVec2,
        gap_m: f64,
        height_m: f64,
        column_m: f64,
        height_jitter_m: f64,
        seed: u64,
    ) -> Result<SteppingStones, TerrainError> {
        const S: &str = "stepping_stones";
        for (field, n) in [("cols", cols), ("rows", rows)] {
            if !(1..=10_000).contains(&n) {
                return Err(TerrainError::InvalidValue {
                    shape: S,
                    field,
                    value: n as f64,
                    why: "must be in 1..=10000",
                });
            }
        }
        check_positive(S, "stone_size_m.x", stone_size_m.x, false)?;
        check_positive(S, "stone_size_m.y", stone_size_m.y, false)?;
        check_positive(S, "gap_m", gap_m, true)?;
        check_positive(S, "column_m", column_m, false)?;
        check_positive(S, "height_jitter_m", height_jitter_m, true)?;
        if !height_m.is_finite() {
            return Err(TerrainError::InvalidValue {
                shape: S,
                field: "height_m",
                value: height_m,
                why: "must be finite",
            });
        }
        let pitch = stone_size_m + DVec2::splat(gap_m);
        let first = -0.5 * DVec2::new((cols - 1) as f64, (rows - 1) as f64) * pitch;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut boxes = Vec::with_capacity(cols * rows);
        for j in 0..rows {
            for i in 0..cols {
                let jitter = if height_jitter_m > 0.0 {
                    rng.random_range(-height_jitter_m..=height_jitter_m)
                } else {
                    0.0
                };
                let c = first + DVec2::new(i as f64, j as f64) * pitch;
                let top = height_m + jitter;
                let h = 0.5 * stone_size_m;
                boxes.push(SolidBox::new(
                    DVec3::new(c.x - h.x, c.y - h.y, top - column_m),
                    DVec3::new(c.x + h.x, c.y + h.y, top),
                ));
            }
        }
        Ok(SteppingStones {
            cols,
            rows,
            pitch,
            first,
            boxes,
        })
    }

    /// The stones within one pitch of `(x, y)`.
    #[inline]
    fn near(&self, x: f64, y: f64) -> impl Iterator<Item = &SolidBox> {
        let ci = ((x - self.first.x) / self.pitch.x).round();
        let cj = ((y - self.first.y) / self.pitch.y).round();
        let clampi = |v: f64, n: usize| v.clamp(0.0, (n - 1) as f64) as usize;
        let (i0, i1) = (clampi(ci - 1.0, self.cols), clampi(ci + 1.0, self.cols));
        let (j0, j1) = (clampi(cj - 1.0, self.rows), clampi(cj + 1.0, self.rows));
        (j0..=j1).flat_map(move |j| (i0..=i1).map(move |i| &self.boxes[j * self.cols + i]))
    }

    /// Top height of stone `(i, j)` (m, local).
    pub fn top_m(&self, i: usize, j: usize) -> f64 {
        self.boxes[j * self.cols + i].top()
    }

    /// Centre of stone `(i, j)`'s top face (m, local).
    pub fn stone_centre_m(&self, i: usize, j: usize) -> DVec3 {
        let b = &self.boxes[j * self.cols + i];
        DVec3::new(b.centre.x, b.centre.y, b.top())
    }
}

impl Terrain for SteppingStones {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        highest(self.near(x, y), x, y)
    }
    fn closest(&self, p: DVec3) -> Option<SurfacePoint> {
        deepest(self.near(p.x, p.y), p)
    }
}

impl LocalShape for SteppingStones {
    fn bounds(&self) -> LocalBounds {
        bounds_of(&self.boxes)
    }
    fn covers(&self, x: f64, y: f64) -> bool {
        self.near(x, y).any(|b| b.covers(x, y))
    }
}
