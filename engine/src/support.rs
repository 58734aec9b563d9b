//! Support polygon and static stability margin.
//!
//! The support polygon is the convex hull of the contact feet projected on the
//! horizontal plane (world x, y). The stability margin is the signed distance
//! from the CoM's ground projection to the polygon's nearest edge: positive
//! inside, negative outside (Study B: "least distance from the CoM's ground
//! projection to the support polygon's edge").

use glam::DVec2;

/// Convex hull of up to `N` points (Andrew's monotone chain), counter-clockwise,
/// written into `hull`; returns the number of hull vertices. No allocation.
pub fn convex_hull<const N: usize>(points: &[DVec2], hull: &mut [DVec2; N]) -> usize {
    convex_hull_with(points, hull, &mut [DVec2::ZERO; 64])
}

/// [`convex_hull`] with the chain's work space given (at least `2 N`
/// points), so that a small hull fills a small one.
fn convex_hull_with<const N: usize, const T: usize>(
    points: &[DVec2],
    hull: &mut [DVec2; N],
    tmp: &mut [DVec2; T],
) -> usize {
    let n = points.len().min(N);
    let mut pts = [DVec2::ZERO; N];
    pts[..n].copy_from_slice(&points[..n]);
    let pts = &mut pts[..n];
    pts.sort_by(by_x_then_y);
    monotone_chain(pts, hull, tmp)
}

/// The order the hull's chain walks the points in: by `x`, then `y`
/// (IEEE total order: a total order, whose ties are equal points).
#[inline]
fn by_x_then_y(a: &DVec2, b: &DVec2) -> std::cmp::Ordering {
    a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))
}

/// [`convex_hull`] of up to four points (the metrics' support polygon,
/// every step with three or four feet down): sorted by compare–exchanges
/// (five for four points) into the general sort's order, then the same
/// chain, in fixed buffers: the same hull, without the general sort's
/// loop and the buffers' library copies (about half its instructions).
fn small_hull(points: &[DVec2], hull: &mut [DVec2; 4]) -> usize {
    let n = points.len().min(4);
    let mut pts = [DVec2::ZERO; 4];
    for (d, s) in pts.iter_mut().zip(&points[..n]) {
        *d = *s;
    }
    let mut exchange = |i: usize, j: usize| {
        if by_x_then_y(&pts[i], &pts[j]).is_gt() {
            pts.swap(i, j);
        }
    };
    match n {
        2 => exchange(0, 1),
        3 => {
            exchange(0, 1);
            exchange(1, 2);
            exchange(0, 1);
        }
        4 => {
            exchange(0, 1);
            exchange(2, 3);
            exchange(0, 2);
            exchange(1, 3);
            exchange(1, 2);
        }
        _ => {}
    }
    monotone_chain(&pts[..n], hull, &mut [DVec2::ZERO; 8])
}

/// Andrew's monotone chain over `pts` sorted [`by_x_then_y`]: the hull,
/// counter-clockwise, into `hull` (its vertex count returned), with `tmp`
/// (at least `2 N` points) as the chain's stack.
fn monotone_chain<const N: usize, const T: usize>(
    pts: &[DVec2],
    hull: &mut [DVec2; N],
    tmp: &mut [DVec2; T],
) -> usize {
    let n = pts.len();
    if n < 3 {
        hull[..n].copy_from_slice(pts);
        return n;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    assert!(2 * N <= T, "convex_hull supports up to {} points", T / 2);
    let mut k = 0;
    for &p in pts.iter() {
        while k >= 2 && cross(tmp[k - 2], tmp[k - 1], p) <= 0.0 {
            k -= 1;
        }
        tmp[k] = p;
        k += 1;
    }
    let lower = k + 1;
    for &p in pts.iter().rev().skip(1) {
        while k >= lower && cross(tmp[k - 2], tmp[k - 1], p) <= 0.0 {
            k -= 1;
        }
        tmp[k] = p;
        k += 1;
    }
    let m = (k - 1).min(N);
    for (h, t) in hull.iter_mut().zip(&tmp[..m]) {
        *h = *t;
    }
    m
}

/// Signed distance (m) from `p` to the boundary of the convex polygon `poly`
/// (counter-clockwise): positive inside, negative outside. `None` for fewer
/// than three vertices (no area: no static support).
pub fn signed_margin(poly: &[DVec2], p: DVec2) -> Option<f64> {
    let n = poly.len();
    if n < 3 {
        return None;
    }
    let mut inside = true;
    let mut min_edge = f64::INFINITY;
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        let e = b - a;
        let len = e.length();
        if len == 0.0 {
            continue;
        }
        // signed distance to the edge's line, positive on the inner (left) side
        let d_line = e.perp_dot(p - a) / len;
        if d_line < 0.0 {
            inside = false;
        }
        // distance to the segment
        let t = ((p - a).dot(e) / (len * len)).clamp(0.0, 1.0);
        let d_seg = (a + e * t - p).length();
        min_edge = min_edge.min(d_seg);
    }
    Some(if inside { min_edge } else { -min_edge })
}

/// Stability margin of a CoM projection over the given contact points (x, y):
/// `None` with fewer than three points in contact.
// (an x86-64-v3 clone: three-operand VEX forms; no fused multiply–add,
// so the same bits)
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn stability_margin(contacts: &[DVec2], com_xy: DVec2) -> Option<f64> {
    if contacts.len() < 3 {
        return None;
    }
    if contacts.len() <= 4 {
        // four feet or fewer (the metrics' case every step with three or
        // four in contact): the same hull from a sorting network
        let mut hull = [DVec2::ZERO; 4];
        let n = small_hull(contacts, &mut hull);
        return signed_margin(&hull[..n], com_xy);
    }
    if contacts.len() <= 8 {
        // up to 8 feet: buffers of 8 and 16 points to fill, not 16 and 64
        // (the same hull: `convex_hull` keeps all the points either way)
        let mut hull = [DVec2::ZERO; 8];
        let n = convex_hull_with(contacts, &mut hull, &mut [DVec2::ZERO; 16]);
        return signed_margin(&hull[..n], com_xy);
    }
    let mut hull = [DVec2::ZERO; 16];
    let n = convex_hull(contacts, &mut hull);
    signed_margin(&hull[..n], com_xy)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The small hull (sorting network) is the general hull, vertex for
    /// vertex, on sets of two to four points with repeated points,
    /// collinear ones, signed zeros and one point inside the others.
    #[test]
    fn small_hull_is_the_general_hull() {
        let grid = [-0.3, -0.0, 0.0, 0.25, 0.25, 0.7];
        let mut sets = 0;
        for i in 0..4000u64 {
            let n = 2 + (i % 3) as usize;
            let mut pts = [DVec2::ZERO; 4];
            let mut r = i.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            for p in pts.iter_mut().take(n) {
                let (a, b) = ((r % 6) as usize, ((r / 6) % 6) as usize);
                *p = DVec2::new(grid[a], grid[b]);
                r /= 36;
            }
            if i % 7 == 0 {
                // a point inside the triangle of the others
                pts[..4].copy_from_slice(&[
                    DVec2::new(0.0, 0.0),
                    DVec2::new(1.0, 0.0),
                    DVec2::new(0.0, 1.0),
                    DVec2::new(0.2, 0.3),
                ]);
            }
            let pts = &pts[..if i % 7 == 0 { 4 } else { n }];
            let (mut small, mut general) = ([DVec2::ZERO; 4], [DVec2::ZERO; 4]);
            let ns = small_hull(pts, &mut small);
            let ng = convex_hull_with(pts, &mut general, &mut [DVec2::ZERO; 8]);
            let bits = |h: &[DVec2]| {
                h.iter()
                    .map(|p| [p.x.to_bits(), p.y.to_bits()])
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&small[..ns]), bits(&general[..ng]), "{pts:?}");
            sets += usize::from(ns >= 3);
        }
        assert!(sets > 500, "proper polygons among the sets: {sets}");
    }

    #[test]
    fn rectangle_margin_is_distance_to_nearest_edge() {
        let feet = [
            DVec2::new(0.25, 0.15),
            DVec2::new(0.25, -0.15),
            DVec2::new(-0.25, -0.15),
            DVec2::new(-0.25, 0.15),
        ];
        assert!((stability_margin(&feet, DVec2::ZERO).unwrap() - 0.15).abs() < 1e-15);
        assert!((stability_margin(&feet, DVec2::new(0.2, 0.0)).unwrap() - 0.05).abs() < 1e-15);
        // outside: negative
        assert!((stability_margin(&feet, DVec2::new(0.0, 0.25)).unwrap() + 0.10).abs() < 1e-15);
    }

    #[test]
    fn triangle_margin_matches_inradius() {
        // equilateral triangle of side s: inradius s / (2√3)
        let s = 0.4;
        let h = s * 3f64.sqrt() / 2.0;
        let tri = [
            DVec2::new(0.0, 0.0),
            DVec2::new(s, 0.0),
            DVec2::new(s / 2.0, h),
        ];
        let centroid = DVec2::new(s / 2.0, h / 3.0);
        let m = stability_margin(&tri, centroid).unwrap();
        assert!((m - s / (2.0 * 3f64.sqrt())).abs() < 1e-14);
    }

    #[test]
    fn two_feet_give_no_margin() {
        assert!(stability_margin(&[DVec2::ZERO, DVec2::X], DVec2::ZERO).is_none());
    }

    #[test]
    fn hull_drops_interior_points() {
        let pts = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.5, 0.2),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let mut hull = [DVec2::ZERO; 8];
        assert_eq!(convex_hull(&pts, &mut hull), 4);
    }
}
