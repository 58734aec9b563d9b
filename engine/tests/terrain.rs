//! Terrain geometry against independent references: central finite
//! differences of the height function for normals, parry3d ray casts and
//! point distances for heights and signed distances, and closed-form
//! expectations at stair risers and edges.

use glam::{DVec2, DVec3};
use parry3d_f64::math::Pose;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use parry3d_f64::shape::{Cuboid, HeightField as ParryHeightField, TriMesh};
use parry3d_f64::utils::Array2;
use quadsim_engine::contact::{GroundMaterial, GroundPreset};
use quadsim_engine::terrain::{
    BoxObstacles, BoxSpec, Flat, HeightField, Incline, NoiseKind, Rough, Sinusoid, StairDirection,
    Stairs, SteppingStones, Terrain, TerrainError, TerrainPatch, TerrainShape, TerrainUnion,
    Trench,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn concrete() -> GroundMaterial {
    GroundPreset::Concrete.material()
}

fn patch(shape: TerrainShape, origin: DVec3, yaw: f64) -> TerrainPatch {
    TerrainPatch::new(shape, origin, yaw, concrete()).unwrap()
}

/// A smooth test function for the height field.
fn bumps(x: f64, y: f64) -> f64 {
    0.05 * (3.0 * x).sin() * (2.0 * y).cos() + 0.02 * x * y
}

fn rough_perlin() -> Rough {
    let kind = NoiseKind::Perlin {
        wavelength_m: 1.5,
        octaves: 3,
        persistence: 0.4,
    };
    Rough::new(kind, 0.04, 11, DVec2::splat(6.0)).unwrap()
}

fn rough_cells() -> Rough {
    Rough::new(
        NoiseKind::UniformCell { cell_m: 0.25 },
        0.02,
        5,
        DVec2::splat(6.0),
    )
    .unwrap()
}

/// Smooth patches (placed with an offset and a yaw, so the transforms are
/// exercised) and a region of local (x, y) free of discontinuities.
fn smooth_patches() -> Vec<(&'static str, TerrainPatch)> {
    let o = DVec3::new(0.7, -0.4, 0.25);
    let yaw = 0.6;
    vec![
        (
            "flat",
            patch(
                TerrainShape::Flat(Flat::new(DVec2::splat(6.0)).unwrap()),
                o,
                yaw,
            ),
        ),
        (
            "incline +20°",
            patch(
                TerrainShape::Incline(Incline::new(20f64.to_radians(), DVec2::splat(6.0)).unwrap()),
                o,
                yaw,
            ),
        ),
        (
            "incline −35°",
            patch(
                TerrainShape::Incline(
                    Incline::new(-35f64.to_radians(), DVec2::splat(6.0)).unwrap(),
                ),
                o,
                -2.0,
            ),
        ),
        (
            "sinusoid",
            patch(
                TerrainShape::Sinusoid(Sinusoid::new(0.05, 1.0, DVec2::splat(6.0)).unwrap()),
                o,
                yaw,
            ),
        ),
        (
            "rough perlin",
            patch(TerrainShape::Rough(rough_perlin()), o, yaw),
        ),
        (
            "rough cells",
            patch(TerrainShape::Rough(rough_cells()), o, yaw),
        ),
        (
            "heightfield",
            patch(
                TerrainShape::HeightField(
                    HeightField::from_fn(61, 41, DVec2::new(0.1, 0.15), bumps).unwrap(),
                ),
                o,
                yaw,
            ),
        ),
    ]
}

fn world_of(p: &TerrainPatch, local: DVec2) -> DVec2 {
    let (s, c) = p.yaw_rad().sin_cos();
    let o = p.origin_m();
    DVec2::new(
        o.x + c * local.x - s * local.y,
        o.y + s * local.x + c * local.y,
    )
}

/// Unit normal from central differences of `height`: `(−h_x, −h_y, 1)/‖·‖`.
fn fd_normal(t: &impl Terrain, x: f64, y: f64) -> DVec3 {
    let e = 1e-6;
    let h = |x, y| t.height(x, y).unwrap();
    let hx = (h(x + e, y) - h(x - e, y)) / (2.0 * e);
    let hy = (h(x, y + e) - h(x, y - e)) / (2.0 * e);
    DVec3::new(-hx, -hy, 1.0).normalize()
}

/// At points on each smooth surface, `closest` returns zero depth and the
/// normal of the height function's finite-difference gradient.
#[test]
fn normals_match_finite_differences_on_smooth_terrains() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for (name, p) in smooth_patches() {
        for _ in 0..300 {
            let l = DVec2::new(rng.random_range(-2.5..2.5), rng.random_range(-2.5..2.5));
            let w = world_of(&p, l);
            let h = p.height(w.x, w.y).unwrap();
            let s = p.closest(DVec3::new(w.x, w.y, h)).unwrap();
            let n = fd_normal(&p, w.x, w.y);
            assert!(
                s.depth_m.abs() < 1e-10,
                "{name}: depth {} on the surface",
                s.depth_m
            );
            assert!(
                (s.normal - n).length() < 2e-7,
                "{name} at {w}: {} vs fd {}",
                s.normal,
                n
            );
            assert!((s.normal.length() - 1.0).abs() < 1e-12);
        }
    }
}

/// On the flat parts of box terrains (treads, banks, trench floor, tops)
/// the normal is vertical and equals the finite-difference one.
#[test]
fn normals_match_finite_differences_on_box_terrains() {
    let stairs = Stairs::new(StairDirection::Up, 0.15, 0.3, 5, 1.2, 0.5).unwrap();
    let down = Stairs::new(StairDirection::Down, 0.12, 0.25, 4, 1.0, 0.3).unwrap();
    let trench = Trench::new(0.4, 0.3, DVec2::new(3.0, 2.0)).unwrap();
    let boxes = BoxObstacles::new(vec![BoxSpec {
        centre_m: DVec3::new(0.0, 0.0, 0.1),
        size_m: DVec3::new(0.8, 0.5, 0.2),
        yaw_rad: 0.4,
    }])
    .unwrap();
    let stones = SteppingStones::new(4, 3, DVec2::new(0.3, 0.25), 0.15, 0.2, 1.0, 0.03, 9).unwrap();
    // local (x, y) points well inside a flat part, with the expected local height
    let mut cases: Vec<(TerrainShape, Vec<(DVec2, f64)>)> = Vec::new();
    cases.push((
        TerrainShape::Stairs(stairs),
        (0..5)
            .map(|i| {
                (
                    DVec2::new(0.3 * i as f64 + 0.15, 0.2),
                    0.15 * (i + 1) as f64,
                )
            })
            .collect(),
    ));
    cases.push((
        TerrainShape::Stairs(down),
        (0..4)
            .map(|i| {
                (
                    DVec2::new(0.3 + 0.25 * i as f64 + 0.1, -0.3),
                    0.12 * (4 - i) as f64,
                )
            })
            .collect(),
    ));
    cases.push((
        TerrainShape::Trench(trench),
        vec![
            (DVec2::new(-1.0, 0.3), 0.0),
            (DVec2::new(0.0, -0.5), -0.3),
            (DVec2::new(1.2, 0.9), 0.0),
        ],
    ));
    cases.push((
        TerrainShape::Boxes(boxes),
        vec![(DVec2::new(0.1, 0.05), 0.2)],
    ));
    let stone_tops: Vec<(DVec2, f64)> = {
        let s = SteppingStones::new(4, 3, DVec2::new(0.3, 0.25), 0.15, 0.2, 1.0, 0.03, 9).unwrap();
        (0..4)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| {
                let c = s.stone_centre_m(i, j);
                (DVec2::new(c.x + 0.05, c.y - 0.05), c.z)
            })
            .collect()
    };
    cases.push((TerrainShape::SteppingStones(stones), stone_tops));
    let origin = DVec3::new(-1.0, 2.0, 0.1);
    let yaw = -0.8;
    for (shape, pts) in cases {
        let name = shape.kind_name();
        let p = patch(shape, origin, yaw);
        for (l, h_local) in pts {
            let w = world_of(&p, l);
            let h = p.height(w.x, w.y).unwrap();
            assert!(
                (h - (h_local + origin.z)).abs() < 1e-12,
                "{name} at {l}: {h}"
            );
            let s = p.closest(DVec3::new(w.x, w.y, h + 0.004)).unwrap();
            assert!(
                (s.depth_m + 0.004).abs() < 1e-12,
                "{name}: depth {}",
                s.depth_m
            );
            assert!(
                (s.normal - fd_normal(&p, w.x, w.y)).length() < 1e-9,
                "{name}: {}",
                s.normal
            );
            assert!((s.normal - DVec3::Z).length() < 1e-12);
        }
    }
}

/// A point offset by `d` along the normal from a surface point `s` has `s` as
/// its closest point and depth `−d` (for `|d|` below the radius of curvature):
/// the closest-point query is a true distance, not a vertical one.
#[test]
fn closest_point_is_a_true_distance() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for (name, p) in smooth_patches() {
        // Analytic shapes are exact. Projected ones (one tangent-plane
        // refinement, see `closest_on_graph`) miss the surface point by about
        // κ d² sin α, ≤ d²·(1/m) on these grounds, and the depth by κ·miss².
        let projected = name.starts_with("rough") || name == "heightfield";
        let tol = if projected { 2e-6 } else { 1e-10 };
        let point_tol = |d: f64| if projected { d * d } else { 1e-9 };
        for _ in 0..200 {
            let l = DVec2::new(rng.random_range(-2.3..2.3), rng.random_range(-2.3..2.3));
            let w = world_of(&p, l);
            let h = p.height(w.x, w.y).unwrap();
            let s0 = p.closest(DVec3::new(w.x, w.y, h)).unwrap();
            for d in [-0.03, -0.01, 0.005, 0.02] {
                let q = s0.point + d * s0.normal;
                let s = p.closest(q).unwrap();
                assert!(
                    (s.depth_m + d).abs() < tol,
                    "{name} d={d}: depth {}",
                    s.depth_m
                );
                let miss = (s.point - s0.point).length();
                assert!(miss < point_tol(d), "{name} d={d}: point off by {miss}");
            }
        }
    }
}

fn cast_down(shape: &dyn RayCast, pose: &Pose, x: f64, y: f64) -> Option<f64> {
    let ray = Ray::new(DVec3::new(x, y, 50.0), DVec3::NEG_Z);
    shape.cast_ray(pose, &ray, 100.0, true).map(|t| 50.0 - t)
}

/// A triangle mesh through the terrain's own heights on a grid over the
/// patch (world frame).
fn sample_mesh(p: &TerrainPatch, half: f64, n: usize) -> TriMesh {
    let mut v = Vec::new();
    let mut idx = Vec::new();
    let step = 2.0 * half / (n - 1) as f64;
    for j in 0..n {
        for i in 0..n {
            let w = world_of(
                p,
                DVec2::new(-half + i as f64 * step, -half + j as f64 * step),
            );
            v.push(DVec3::new(w.x, w.y, p.height(w.x, w.y).unwrap()));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            let b = a + 1;
            let c = a + n as u32;
            let d = c + 1;
            idx.push([a, b, d]);
            idx.push([a, d, c]);
        }
    }
    TriMesh::new(v, idx).unwrap()
}

/// Heights of analytic terrains agree with ray casts on a parry triangle mesh
/// sampled from them: exactly for planes, within the linear-interpolation
/// error `(h²/8)·max|h''|·2` for the sinusoid.
#[test]
fn analytic_heights_match_parry_mesh_ray_casts() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let patches = smooth_patches();
    for (name, p) in patches
        .iter()
        .filter(|(n, _)| n.starts_with("flat") || n.starts_with("incline") || *n == "sinusoid")
    {
        let (half, n) = (2.5, 251);
        let mesh = sample_mesh(p, half, n);
        let h = 2.0 * half / (n - 1) as f64;
        let k = 2.0 * PI / 1.0;
        let tol = if *name == "sinusoid" {
            h * h / 8.0 * 0.05 * k * k * 2.0
        } else {
            1e-9
        };
        for _ in 0..300 {
            let l = DVec2::new(rng.random_range(-2.4..2.4), rng.random_range(-2.4..2.4));
            let w = world_of(p, l);
            let z_parry = cast_down(&mesh, &Pose::identity(), w.x, w.y).expect("ray hits the mesh");
            let z = p.height(w.x, w.y).unwrap();
            assert!(
                (z - z_parry).abs() <= tol,
                "{name} at {w}: {z} vs parry {z_parry} (tol {tol})"
            );
        }
    }
}

/// The bicubic height field passes through its samples: a parry `HeightField`
/// built from the same grid (y-up, turned to z-up) gives the same heights at
/// every sample under a ray cast, and stays within the interpolation error of
/// the smooth function in between.
#[test]
fn heightfield_matches_parry_heightfield() {
    let (nx, ny, dx, dy) = (41usize, 31usize, 0.1, 0.12);
    let hf = HeightField::from_fn(nx, ny, DVec2::new(dx, dy), bumps).unwrap();
    let (sx, sy) = ((nx - 1) as f64 * dx, (ny - 1) as f64 * dy);
    // parry: row i along its z, column j along its x, column-major storage;
    // rotating +90° about x maps its y (up) to our z and its z to our −y.
    let mut data = vec![0.0; nx * ny];
    for i in 0..ny {
        for j in 0..nx {
            data[i + j * ny] = hf.sample(j, ny - 1 - i);
        }
    }
    let phf = ParryHeightField::new(Array2::new(ny, nx, data), DVec3::new(sx, 1.0, sy));
    let pose = Pose::rotation(DVec3::X * (PI / 2.0));
    let origin = DVec3::new(0.3, 0.2, -0.1);
    let p = patch(TerrainShape::HeightField(hf.clone()), origin, 0.0);
    let parry_pose = Pose::from_translation(origin) * pose;
    for j in 1..ny - 1 {
        for i in 1..nx - 1 {
            let s = hf.sample_xy(i, j);
            assert!((hf.sample(i, j) - bumps(s.x, s.y)).abs() < 1e-15);
            // a hair off the vertex, where parry's triangle test is well posed
            let (x, y) = (s.x + origin.x + 1e-10, s.y + origin.y + 2e-10);
            let z = p.height(x, y).unwrap();
            let zp =
                cast_down(&phf, &parry_pose, x, y).unwrap_or_else(|| panic!("miss at ({i},{j})"));
            assert!((z - zp).abs() < 1e-9, "sample ({i},{j}): {z} vs {zp}");
            assert!((z - origin.z - bumps(s.x, s.y)).abs() < 1e-9);
        }
    }
    // Between samples: both within the interpolation error of `bumps`
    // (|∂²f| ≤ 0.05·9 + 0.05·4 + 0.02 ⇒ linear error ≤ (dx² + dy²)/8 · 0.67 · 2).
    let tol = (dx * dx + dy * dy) / 8.0 * 0.67 * 2.0;
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for _ in 0..500 {
        let l = DVec2::new(
            rng.random_range(-0.45 * sx..0.45 * sx),
            rng.random_range(-0.45 * sy..0.45 * sy),
        );
        let (x, y) = (l.x + origin.x, l.y + origin.y);
        let z = p.height(x, y).unwrap();
        let zp = cast_down(&phf, &parry_pose, x, y).unwrap();
        assert!((z - zp).abs() < tol, "{l}: {z} vs parry {zp}");
    }
}

/// Parry cuboids for a staircase described step by step (step `i` only over
/// its own run, from the ground up) — a different decomposition from the
/// engine's nested boxes — placed like the patch.
fn parry_stairs(
    dir: StairDirection,
    rise: f64,
    run: f64,
    count: usize,
    width: f64,
    landing: f64,
    origin: DVec3,
    yaw: f64,
) -> Vec<(Cuboid, Pose)> {
    let total = count as f64 * run + landing;
    let mut solids = Vec::new();
    for i in 0..count {
        let top = (i + 1) as f64 * rise;
        let (mut x0, mut x1) = (i as f64 * run, (i + 1) as f64 * run);
        if i + 1 == count {
            x1 += landing;
        }
        if dir == StairDirection::Down {
            (x0, x1) = (total - x1, total - x0);
        }
        solids.push((
            DVec3::new(0.5 * (x0 + x1), 0.0, 0.5 * (top - 1.0)),
            DVec3::new(0.5 * (x1 - x0), 0.5 * width, 0.5 * (top + 1.0)),
        ));
    }
    solids
        .into_iter()
        .map(|(c, h)| {
            let (s, co) = yaw.sin_cos();
            let cw = origin + DVec3::new(co * c.x - s * c.y, s * c.x + co * c.y, c.z);
            (Cuboid::new(h), Pose::new(cw, DVec3::Z * yaw))
        })
        .collect()
}

/// Stairs, up and down: heights equal the highest parry cuboid hit by a
/// vertical ray, and above the solid the (negative) depth equals minus
/// parry's distance to the nearest cuboid.
#[test]
fn stairs_match_parry_cuboids() {
    let origin = DVec3::new(1.0, -0.5, 0.05);
    let yaw = 0.9;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for dir in [StairDirection::Up, StairDirection::Down] {
        let (rise, run, count, width, landing) = (0.15, 0.3, 6, 1.2, 0.6);
        let p = patch(
            TerrainShape::Stairs(Stairs::new(dir, rise, run, count, width, landing).unwrap()),
            origin,
            yaw,
        );
        let solids = parry_stairs(dir, rise, run, count, width, landing, origin, yaw);
        let total = count as f64 * run + landing;
        let mut outside = 0;
        for _ in 0..2000 {
            let l = DVec3::new(
                rng.random_range(-0.3..total + 0.3),
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.1..1.2),
            );
            let w2 = world_of(&p, DVec2::new(l.x, l.y));
            let w = DVec3::new(w2.x, w2.y, l.z + origin.z);
            let zp = solids
                .iter()
                .filter_map(|(c, pose)| cast_down(c, pose, w.x, w.y))
                .reduce(f64::max);
            let z = p.height(w.x, w.y);
            match (z, zp) {
                (Some(z), Some(zp)) => {
                    assert!((z - zp).abs() < 1e-9, "{dir:?} at {l}: {z} vs {zp}")
                }
                (None, None) => {}
                _ => panic!("{dir:?} at {l}: height {z:?}, parry {zp:?}"),
            }
            let dist = solids
                .iter()
                .map(|(c, pose)| c.distance_to_point(pose, w, true))
                .fold(f64::INFINITY, f64::min);
            let s = p.closest(w).unwrap();
            if dist > 1e-9 {
                outside += 1;
                assert!(
                    (s.depth_m + dist).abs() < 1e-9,
                    "{dir:?} at {l}: depth {} vs −{dist}",
                    s.depth_m
                );
            } else {
                assert!(
                    s.depth_m >= -1e-12,
                    "{dir:?} at {l}: inside parry but depth {}",
                    s.depth_m
                );
            }
        }
        assert!(outside > 500);
    }
}

/// A trench against parry cuboids (banks and a floor only under the gap):
/// heights by ray cast and, outside the solid, signed distances.
#[test]
fn trench_matches_parry_cuboids() {
    let (w, d, size) = (0.5, 0.3, DVec2::new(3.0, 2.0));
    let origin = DVec3::new(0.0, 1.0, 0.2);
    let yaw = -0.3;
    let p = patch(
        TerrainShape::Trench(Trench::new(w, d, size).unwrap()),
        origin,
        yaw,
    );
    let (s, c) = yaw.sin_cos();
    let place = |x: f64, y: f64, z: f64| origin + DVec3::new(c * x - s * y, s * x + c * y, z);
    let hx = 0.5 * size.x;
    let bank = 0.5 * (hx - 0.5 * w);
    let solids = [
        (
            Cuboid::new(DVec3::new(bank, 0.5 * size.y, 0.5 * (d + 1.0))),
            Pose::new(
                place(-0.5 * w - bank, 0.0, -0.5 * (d + 1.0)),
                DVec3::Z * yaw,
            ),
        ),
        (
            Cuboid::new(DVec3::new(bank, 0.5 * size.y, 0.5 * (d + 1.0))),
            Pose::new(place(0.5 * w + bank, 0.0, -0.5 * (d + 1.0)), DVec3::Z * yaw),
        ),
        (
            Cuboid::new(DVec3::new(0.5 * w, 0.5 * size.y, 0.5)),
            Pose::new(place(0.0, 0.0, -d - 0.5), DVec3::Z * yaw),
        ),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    for _ in 0..2000 {
        let l = DVec3::new(
            rng.random_range(-1.4..1.4),
            rng.random_range(-0.9..0.9),
            rng.random_range(-0.35..0.3),
        );
        let pw = place(l.x, l.y, l.z);
        let z = p.height(pw.x, pw.y).unwrap();
        let zp = solids
            .iter()
            .filter_map(|(c, pose)| cast_down(c, pose, pw.x, pw.y))
            .reduce(f64::max)
            .unwrap();
        assert!((z - zp).abs() < 1e-9, "{l}: {z} vs {zp}");
        let dist = solids
            .iter()
            .map(|(c, pose)| c.distance_to_point(pose, pw, true))
            .fold(f64::INFINITY, f64::min);
        let sp = p.closest(pw).unwrap();
        if dist > 1e-9 {
            assert!(
                (sp.depth_m + dist).abs() < 1e-9,
                "{l}: {} vs −{dist}",
                sp.depth_m
            );
        }
    }
}

/// A foot sphere against a stair riser gets the riser's horizontal normal
/// and the riser's penetration, not the 15 cm height of the step; around the
/// step's nosing the normal turns with the sphere.
#[test]
fn stair_riser_contact_is_horizontal() {
    let (rise, run, r) = (0.15, 0.3, 0.03);
    let yaw = PI / 6.0;
    let origin = DVec3::new(2.0, 1.0, 0.0);
    let (s, c) = yaw.sin_cos();
    let place = |x: f64, z: f64| origin + DVec3::new(c * x, s * x, z);
    let forward = DVec3::new(c, s, 0.0);
    let up = patch(
        TerrainShape::Stairs(Stairs::new(StairDirection::Up, rise, run, 4, 1.0, 0.3).unwrap()),
        origin,
        yaw,
    );
    // The riser of step 1 is at local x = run, from z = rise to 2 rise.
    for gap in [0.02, 0.01, -0.004] {
        let centre = place(run - gap, rise + 0.07);
        let sp = up.closest(centre).unwrap();
        let depth = sp.depth_m + r;
        assert!(sp.normal.z.abs() < 1e-12, "normal {}", sp.normal);
        assert!(
            (sp.normal + forward).length() < 1e-12,
            "normal {}",
            sp.normal
        );
        assert!(
            (depth - (r - gap)).abs() < 1e-12,
            "gap {gap}: depth {depth}"
        );
        assert!((sp.point - place(run, rise + 0.07)).length() < 1e-12);
    }
    // Over the nosing (the edge at x = run, z = 2 rise), the normal points
    // from the edge to the centre.
    let centre = place(run - 0.02, 2.0 * rise + 0.02);
    let sp = up.closest(centre).unwrap();
    let expect = (-0.02 * forward + 0.02 * DVec3::Z).normalize();
    assert!((sp.normal - expect).length() < 1e-12, "{}", sp.normal);
    assert!((sp.depth_m + 0.02 * 2f64.sqrt()).abs() < 1e-12);
    // Going down, risers face forward (+x local).
    let down = patch(
        TerrainShape::Stairs(Stairs::new(StairDirection::Down, rise, run, 4, 1.0, 0.3).unwrap()),
        origin,
        yaw,
    );
    // the first riser down is at local x = landing + run = 0.6, below z = 4 rise
    let centre = place(0.6 + 0.01, 3.0 * rise + 0.05);
    let sp = down.closest(centre).unwrap();
    assert!((sp.normal - forward).length() < 1e-12, "{}", sp.normal);
    assert!((sp.depth_m + 0.01).abs() < 1e-12);
}

/// The union answers with the highest surface; outside every patch there is
/// no ground unless a default ground is set, which a trench or a stone field
/// does not fill.
#[test]
fn union_highest_surface_wins() {
    let mud = GroundPreset::Mud.material();
    let low = TerrainPatch::new(
        TerrainShape::Flat(Flat::new(DVec2::splat(4.0)).unwrap()),
        DVec3::ZERO,
        0.0,
        mud,
    )
    .unwrap();
    let high = patch(
        TerrainShape::Flat(Flat::new(DVec2::new(1.0, 1.0)).unwrap()),
        DVec3::new(1.0, 0.0, 0.2),
        0.3,
    );
    let block = patch(
        TerrainShape::Boxes(
            BoxObstacles::new(vec![BoxSpec {
                centre_m: DVec3::new(0.0, 0.0, 0.25),
                size_m: DVec3::new(0.4, 0.4, 0.5),
                yaw_rad: 0.0,
            }])
            .unwrap(),
        ),
        DVec3::new(-1.0, -1.0, 0.0),
        0.0,
    );
    let mut u = TerrainUnion::new().with(low).with(high).with(block);
    assert_eq!(u.height(-1.5, 1.5), Some(0.0));
    assert_eq!(u.height(1.0, 0.0), Some(0.2));
    assert_eq!(u.height(-1.0, -1.0), Some(0.5));
    // between the two flats, the upper one is the surface a point is in
    let (s, m) = u.closest_with_material(DVec3::new(1.1, 0.1, 0.1)).unwrap();
    assert!((s.depth_m - 0.1).abs() < 1e-12 && s.normal == DVec3::Z);
    assert_eq!(m.preset, Some(GroundPreset::Concrete));
    // next to the block on the low ground: the ground, not the block's side
    let (s, m) = u
        .closest_with_material(DVec3::new(-0.75, -1.0, 0.01))
        .unwrap();
    assert!((s.depth_m + 0.01).abs() < 1e-12, "{}", s.depth_m);
    assert_eq!(m.preset, Some(GroundPreset::Mud));
    // pressed into the block's side at its mid-height: the side wins
    let s = u.closest(DVec3::new(-0.805, -1.0, 0.25)).unwrap();
    assert!((s.depth_m - 0.005).abs() < 1e-12 && (s.normal - DVec3::X).length() < 1e-12);
    // outside every patch: no ground. Height-function patches have no
    // surface there; a solid (the block) still has a distance, metres away.
    assert_eq!(u.height(5.0, 5.0), None);
    let far = DVec3::new(5.0, 5.0, 0.0);
    let s = u.closest(far).unwrap();
    assert!((s.depth_m + (far - DVec3::new(-0.8, -0.8, 0.0)).length()).abs() < 1e-12);
    let only_flat = TerrainUnion::new().with(u.patches()[0].clone());
    assert!(only_flat.closest(far).is_none());
    // with a default ground
    u.set_default_ground(Some(quadsim_engine::terrain::DefaultGround {
        height_m: -0.1,
        material: mud,
    }));
    assert_eq!(u.height(5.0, 5.0), Some(-0.1));
    assert!((u.closest(DVec3::new(5.0, 5.0, 0.0)).unwrap().depth_m + 0.1).abs() < 1e-12);
    // a trench is not filled by the default ground; stones show it in their gaps
    let trench = patch(
        TerrainShape::Trench(Trench::new(0.4, 0.3, DVec2::splat(2.0)).unwrap()),
        DVec3::ZERO,
        0.0,
    );
    let stones = patch(
        TerrainShape::SteppingStones(
            SteppingStones::new(3, 3, DVec2::splat(0.3), 0.2, 0.25, 1.0, 0.0, 1).unwrap(),
        ),
        DVec3::new(5.0, 0.0, 0.0),
        0.0,
    );
    let g = TerrainUnion::flat(0.0, concrete())
        .with(trench)
        .with(stones);
    let close = |h: Option<f64>, e: f64| h.is_some_and(|h| (h - e).abs() < 1e-12);
    assert!(close(g.height(0.0, 0.0), -0.3), "{:?}", g.height(0.0, 0.0));
    assert!(close(g.height(0.5, 0.0), 0.0));
    assert!(close(g.height(5.0, 0.0), 0.25));
    assert!(close(g.height(5.25, 0.0), 0.0));
    assert!(close(g.height(9.0, 9.0), 0.0));
    let s = g.closest(DVec3::new(0.0, 0.0, -0.29)).unwrap();
    assert!(
        (s.depth_m + 0.01).abs() < 1e-12,
        "trench floor: {}",
        s.depth_m
    );
}

/// The union's bound-based culling never changes the answer: it equals the
/// brute-force deepest surface over all patches (and the default ground where
/// no patch covers the point).
#[test]
fn union_culling_matches_brute_force() {
    let patches = vec![
        patch(
            TerrainShape::Sinusoid(Sinusoid::new(0.05, 0.8, DVec2::new(3.0, 2.0)).unwrap()),
            DVec3::new(0.0, 0.0, 0.1),
            0.2,
        ),
        patch(
            TerrainShape::Stairs(Stairs::new(StairDirection::Up, 0.1, 0.25, 5, 1.0, 0.2).unwrap()),
            DVec3::new(-1.0, 0.5, 0.0),
            -0.4,
        ),
        patch(
            TerrainShape::Rough(rough_perlin()),
            DVec3::new(2.0, -1.0, -0.05),
            1.0,
        ),
        patch(
            TerrainShape::SteppingStones(
                SteppingStones::new(5, 4, DVec2::splat(0.2), 0.1, 0.2, 0.5, 0.05, 3).unwrap(),
            ),
            DVec3::new(0.5, 1.5, 0.0),
            0.0,
        ),
        patch(
            TerrainShape::Boxes(
                BoxObstacles::new(vec![
                    BoxSpec {
                        centre_m: DVec3::new(0.0, 0.0, 0.1),
                        size_m: DVec3::new(0.3, 0.2, 0.2),
                        yaw_rad: 0.5,
                    },
                    BoxSpec {
                        centre_m: DVec3::new(1.0, 0.4, 0.3),
                        size_m: DVec3::new(0.2, 0.2, 0.6),
                        yaw_rad: -1.0,
                    },
                ])
                .unwrap(),
            ),
            DVec3::new(-2.0, -1.5, 0.0),
            0.0,
        ),
    ];
    let mut u = TerrainUnion::flat(-0.02, concrete());
    for p in &patches {
        u.push(p.clone());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..5000 {
        let q = DVec3::new(
            rng.random_range(-4.0..4.0),
            rng.random_range(-4.0..4.0),
            rng.random_range(-0.3..0.8),
        );
        let mut best: Option<f64> = None;
        for p in &patches {
            if let Some(s) = p.closest(q) {
                best = Some(best.map_or(s.depth_m, |b| b.max(s.depth_m)));
            }
        }
        if !patches.iter().any(|p| p.covers(q.x, q.y)) {
            let d = -0.02 - q.z;
            best = Some(best.map_or(d, |b| b.max(d)));
        }
        let got = u.closest(q).map(|s| s.depth_m);
        assert_eq!(got, best, "at {q}");
    }
}

/// Bad parameters give typed errors naming the shape and field.
#[test]
fn bad_parameters_are_typed_errors() {
    let e = Stairs::new(StairDirection::Up, -0.1, 0.3, 3, 1.0, 0.0).unwrap_err();
    assert_eq!(
        e,
        TerrainError::InvalidValue {
            shape: "stairs",
            field: "rise_m",
            value: -0.1,
            why: "must be finite and > 0"
        }
    );
    assert!(e.to_string().contains("rise_m"));
    let e = Incline::new(2.0, DVec2::ONE).unwrap_err();
    assert!(matches!(
        e,
        TerrainError::InvalidValue {
            shape: "incline",
            field: "slope_rad",
            ..
        }
    ));
    let e = Trench::new(2.0, 0.2, DVec2::new(1.5, 1.0)).unwrap_err();
    assert!(matches!(
        e,
        TerrainError::InvalidValue {
            field: "size_m.x",
            ..
        }
    ));
    let e = Rough::new(
        NoiseKind::UniformCell { cell_m: 0.1 },
        0.02,
        1,
        DVec2::INFINITY,
    )
    .unwrap_err();
    assert!(matches!(
        e,
        TerrainError::InvalidValue {
            field: "size_m.x",
            ..
        }
    ));
    let e = TerrainPatch::new(
        TerrainShape::Flat(Flat::infinite()),
        DVec3::new(f64::NAN, 0.0, 0.0),
        0.0,
        concrete(),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        TerrainError::InvalidValue {
            shape: "flat",
            field: "origin_m.x",
            ..
        }
    ));
}
