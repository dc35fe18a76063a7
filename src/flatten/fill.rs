//! Virtual filling of the holes (step 1 of the module docs): each hole becomes a flat,
//! validly triangulated polygon on its rim vertices, so the surface is a disk to BFF.
//!
//! BFF's reference implementation fills a hole with a fan around one virtual vertex. A fan is a
//! triangulation only when the hole is star-shaped from its centre, and staircase rims of tilted
//! slots and ellipses are not: a riser whose outward side faces the centre is seen from behind,
//! and its fan triangle is inverted. Its angles, measured unsigned, then add up to more than the
//! hole has (spurious curvature on the rim) and its cotan weights are those of a triangle that
//! is not there; the harmonic maps of BFF fold the real triangles beside such a riser (issue 34:
//! every "flipped triangles" failure of the generated parts, 5 in 200 at 5k–12k faces, had
//! inverted fan triangles; 143 holes of those 200 parts had some).
//!
//! Decision: the rim is laid out in the plane with the turning angles the real triangles leave
//! free (the hole's own curvature spread over the rim by dual length), closed by the minimal
//! change of lengths (BFF §4.3) and checked to be a simple counter-clockwise polygon. If it is
//! star-shaped from its area centroid (every fan triangle positively oriented), the fill is that
//! fan, as before (bit for bit); otherwise the polygon is triangulated by ear clipping and made
//! constrained Delaunay by Lawson flips ([`crate::flip::lawson`]), with no virtual vertex. Either
//! way every fill triangle is positively oriented and the fill angles at a rim vertex are
//! exactly its polygon angle (the rim vertex is flat but for its share of the hole's curvature),
//! and the triangulation's interior edges have non-negative cotan weights (the Delaunay
//! property). On a developable surface the layout is exactly the hole of the isometric
//! flattening. The fan is kept where it is valid because its centre vertex makes the map of
//! round holes more conformal: qc max 1.0064 against 1.0107 with the triangulation on
//! spherical_cap_hole, 1.0020 against 1.0043 on saddle_2_holes.
//!
//! Fallbacks, in order, when the layout is not a simple polygon (a hole around strong
//! curvature): the rim projected on its Newell plane, triangulated the same way, with the
//! angles and weights of the 3D triangles; then the rim laid out on a circle by arc length and
//! fanned to its centre. (Until the handles of issue 34 the last resort was the fan to the rim's
//! 3D centroid, which inverts where the rim is far from planar: a hole whose rim runs over a
//! bridge and round two holes folded 87 triangles of plate_with_handle.)

use std::f64::consts::PI;

use glam::{DVec2, DVec3};

use crate::num;

/// How a hole was filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fill {
    /// Fan around a virtual vertex at the area centroid of the intrinsic layout of the rim,
    /// which is star-shaped from there.
    Fan,
    /// Constrained Delaunay triangulation of the intrinsic layout (not star-shaped).
    Triangulated,
    /// The same from the rim projected on its plane, with the 3D triangles' angles.
    Projected,
    /// Fan to the centre of the rim laid out on a circle (by arc length): convex, so valid
    /// whatever the rim (a hole whose rim runs over a bridge, issue 34 item 4).
    Circle,
}

/// The filling of one hole: triangles (vertex indices of the filled disk, a fan's centre being
/// the `centre` given to [`fill_hole`]) with their corner angles and cotan half-weights.
pub(crate) struct HoleFill {
    pub kind: Fill,
    pub triangles: Vec<[u32; 3]>,
    /// Angle per corner, in the order of `triangles`.
    pub angles: Vec<[f64; 3]>,
    /// Cotan half-weights `(i, j, w)`, `i < j`, one per triangle edge.
    pub weights: Vec<(u32, u32, f64)>,
}

/// Fills hole `rim` (surface on its left) given the angle sums of the real triangles at its
/// vertices (`angle_sum`, indexed by vertex). `centre` is the index a fan's virtual vertex gets
/// (used only if `triangles` refer to it). `None` if every filling is degenerate.
pub(crate) fn fill_hole(positions: &[DVec3], rim: &[u32], angle_sum: &[f64], centre: u32) -> Option<HoleFill> {
    let n = rim.len();
    // Reverse the rim so the fill is on the left (counter-clockwise around the hole).
    let q: Vec<u32> = (0..n).map(|m| rim[(n - m) % n]).collect();
    let p3: Vec<DVec3> = q.iter().map(|&v| positions[v as usize]).collect();
    if let Some(pts) = intrinsic_layout(&p3, &q.iter().map(|&v| angle_sum[v as usize]).collect::<Vec<_>>()) {
        if let Some(c) = star_centre(&pts) {
            let corners: Vec<[DVec3; 3]> =
                (0..n).map(|m| [pts[m].extend(0.0), pts[(m + 1) % n].extend(0.0), c.extend(0.0)]).collect();
            return Some(assemble(Fill::Fan, &with_centre(&q, centre), &fan(n), &corners));
        }
        if let Some(tris) = triangulate(&pts) {
            let corners: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(|k| pts[k as usize].extend(0.0))).collect();
            return Some(assemble(Fill::Triangulated, &q, &tris, &corners));
        }
    }
    if let Some(tris) = triangulate(&project(&p3)) {
        let corners: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(|k| p3[k as usize])).collect();
        if corners.iter().all(triangle_ok) {
            return Some(assemble(Fill::Projected, &q, &tris, &corners));
        }
    }
    // Last resort: the rim on a circle (by arc length, or evenly where an edge would span half
    // of it) and the fan to its centre (local index n): convex, so never inverted.
    let len: Vec<f64> = (0..n).map(|m| (p3[(m + 1) % n] - p3[m]).length()).collect();
    let total: f64 = len.iter().sum();
    if !(total > 0.0) || n < 3 {
        return None;
    }
    let even = len.iter().any(|&l| l > 0.25 * total);
    let mut s = 0.0;
    let pts: Vec<DVec2> = (0..n)
        .map(|m| {
            let t = if even { m as f64 / n as f64 } else { s / total };
            s += len[m];
            DVec2::new(num::cos(2.0 * PI * t), num::sin(2.0 * PI * t)) * (0.5 * total / PI)
        })
        .collect();
    let corners: Vec<[DVec3; 3]> =
        (0..n).map(|m| [pts[m].extend(0.0), pts[(m + 1) % n].extend(0.0), DVec3::ZERO]).collect();
    if !corners.iter().all(triangle_ok) {
        return None;
    }
    Some(assemble(Fill::Circle, &with_centre(&q, centre), &fan(n), &corners))
}

/// The fan of `n` rim vertices (local indices) around local vertex `n`.
fn fan(n: usize) -> Vec<[u32; 3]> {
    (0..n as u32).map(|m| [m, (m + 1) % n as u32, n as u32]).collect()
}

fn with_centre(q: &[u32], centre: u32) -> Vec<u32> {
    let mut ids = q.to_vec();
    ids.push(centre);
    ids
}

/// The rim laid out with the turning angles `π − (2π − Σθ)` the real triangles leave, the
/// mismatch to 2π spread by dual length, closed as in BFF §4.3; `None` unless the result is a
/// simple counter-clockwise polygon.
fn intrinsic_layout(p3: &[DVec3], angle_sum: &[f64]) -> Option<Vec<DVec2>> {
    let n = p3.len();
    let len: Vec<f64> = (0..n).map(|m| (p3[(m + 1) % n] - p3[m]).length()).collect();
    let total: f64 = len.iter().sum();
    let mut turn: Vec<f64> = angle_sum.iter().map(|&s| s - PI).collect();
    let defect = 2.0 * PI - turn.iter().sum::<f64>();
    for m in 0..n {
        turn[m] += defect * 0.5 * (len[(m + n - 1) % n] + len[m]) / total;
    }
    let mut phi = 0.0;
    let tangents: Vec<DVec2> = (0..n)
        .map(|m| {
            if m > 0 {
                phi += turn[m];
            }
            DVec2::new(num::cos(phi), num::sin(phi))
        })
        .collect();
    let pts = super::bff::close_polygon(&tangents, &len, &len).ok()?;
    (signed_area(&pts) > 0.0 && is_simple(&pts)).then_some(pts)
}

/// The polygon's area centroid if every fan triangle to it is positively oriented (not slim).
fn star_centre(pts: &[DVec2]) -> Option<DVec2> {
    let n = pts.len();
    let (mut area, mut moment) = (0.0, DVec2::ZERO);
    for m in 0..n {
        let (a, b) = (pts[m], pts[(m + 1) % n]);
        let cr = a.perp_dot(b);
        area += 0.5 * cr;
        moment += cr * (a + b) / 6.0;
    }
    let c = moment / area;
    (0..n)
        .all(|m| {
            let (a, b) = (pts[m], pts[(m + 1) % n]);
            orient(a, b, c) > 1e-9 * (b - a).length_squared().max((c - a).length_squared())
        })
        .then_some(c)
}

/// The rim projected on the plane of its Newell normal (counter-clockwise seen from it).
fn project(p3: &[DVec3]) -> Vec<DVec2> {
    let n = p3.len();
    let mut normal = DVec3::ZERO;
    for m in 0..n {
        normal += p3[m].cross(p3[(m + 1) % n]);
    }
    let normal = normal.normalize_or(DVec3::Z);
    let e1 = normal.any_orthonormal_vector();
    let e2 = normal.cross(e1);
    p3.iter().map(|p| DVec2::new(p.dot(e1), p.dot(e2))).collect()
}

/// Twice the signed area of the polygon.
fn signed_area(pts: &[DVec2]) -> f64 {
    let n = pts.len();
    (0..n).map(|m| pts[m].perp_dot(pts[(m + 1) % n])).sum()
}

/// Whether the closed polygon has no two non-adjacent edges touching and no adjacent edges
/// folding back onto each other. Segments are swept in order of their smallest x.
fn is_simple(pts: &[DVec2]) -> bool {
    let n = pts.len();
    let seg = |m: usize| (pts[m], pts[(m + 1) % n]);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        let (xa, xb) = (seg(a).0.x.min(seg(a).1.x), seg(b).0.x.min(seg(b).1.x));
        xa.total_cmp(&xb).then(a.cmp(&b))
    });
    for (k, &a) in order.iter().enumerate() {
        let (a0, a1) = seg(a);
        let max_x = a0.x.max(a1.x);
        for &b in &order[k + 1..] {
            let (b0, b1) = seg(b);
            if b0.x.min(b1.x) > max_x {
                break;
            }
            let adjacent = b == (a + 1) % n || a == (b + 1) % n;
            if adjacent {
                // Consecutive edges meet at one vertex; they must not overlap along a line.
                let (shared, pa, pb) = if b == (a + 1) % n { (a1, a0, b1) } else { (a0, a1, b0) };
                let (u, v) = (pa - shared, pb - shared);
                if u.perp_dot(v) == 0.0 && u.dot(v) > 0.0 {
                    return false;
                }
            } else if segments_touch(a0, a1, b0, b1) {
                return false;
            }
        }
    }
    true
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Closed segments ab and cd share a point.
fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2, o3, o4) = (orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b));
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    (o1 == 0.0 && on(a, b, c)) || (o2 == 0.0 && on(a, b, d)) || (o3 == 0.0 && on(c, d, a)) || (o4 == 0.0 && on(c, d, b))
}

/// Triangulates the simple counter-clockwise polygon `pts` (local indices) by ear clipping, then
/// makes it constrained Delaunay by Lawson flips. `None` if no ear is found (numerically
/// degenerate input) or a triangle comes out degenerate.
fn triangulate(pts: &[DVec2]) -> Option<Vec<[u32; 3]>> {
    let n = pts.len();
    if n < 3 || !(signed_area(pts) > 0.0) {
        return None;
    }
    let scale = pts.iter().fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs())).max(f64::MIN_POSITIVE);
    let eps = 1e-12 * scale * scale;
    let mut prev: Vec<usize> = (0..n).map(|m| (m + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|m| (m + 1) % n).collect();
    let mut tris = Vec::with_capacity(n - 2);
    let mut left = n;
    let mut i = 0;
    let mut since_ear = 0;
    while left > 3 {
        let (a, b) = (prev[i], next[i]);
        if is_ear(pts, &next, a, i, b, eps) {
            tris.push([a as u32, i as u32, b as u32]);
            next[a] = b;
            prev[b] = a;
            left -= 1;
            since_ear = 0;
            // Step back: the previous vertex may have just become an ear.
            i = a;
        } else {
            since_ear += 1;
            if since_ear > left {
                return None;
            }
            i = b;
        }
    }
    let (a, b) = (prev[i], next[i]);
    if !(orient(pts[a], pts[i], pts[b]) > eps) {
        return None;
    }
    tris.push([a as u32, i as u32, b as u32]);
    // Constrained Delaunay: flip an interior edge while its two opposite angles exceed π, i.e.
    // cot γ_c + cot γ_d < 0, and the quadrilateral is strictly convex.
    let (tris, _) = crate::flip::lawson(&tris, |a, b, c, d| {
        let [pa, pb, pc, pd] = [a, b, c, d].map(|v| pts[v as usize]);
        let cot = |p: DVec2, u: DVec2, v: DVec2| (u - p).dot(v - p) / (u - p).perp_dot(v - p).abs();
        let convex = orient(pc, pd, pa) * orient(pc, pd, pb) < 0.0
            && orient(pc, pd, pb).abs() > eps
            && orient(pc, pd, pa).abs() > eps;
        convex && cot(pc, pa, pb) + cot(pd, pa, pb) < -1e-12
    });
    tris.iter().all(|t| orient(pts[t[0] as usize], pts[t[1] as usize], pts[t[2] as usize]) > eps).then_some(tris)
}

/// Vertex `i` between `a` and `b` is an ear: strictly convex, and no other remaining vertex lies
/// in or on the triangle (a, i, b).
fn is_ear(pts: &[DVec2], next: &[usize], a: usize, i: usize, b: usize, eps: f64) -> bool {
    let (pa, pi, pb) = (pts[a], pts[i], pts[b]);
    if !(orient(pa, pi, pb) > eps) {
        return false;
    }
    let mut v = next[b];
    while v != a {
        let p = pts[v];
        // On the triangle counts as inside, with a tolerance: a vertex of a (nearly) straight
        // run lying on the diagonal a–b would leave a sliver.
        if orient(pa, pi, p) >= -eps && orient(pi, pb, p) >= -eps && orient(pb, pa, p) >= -eps {
            return false;
        }
        v = next[v];
    }
    true
}

fn triangle_ok(t: &[DVec3; 3]) -> bool {
    let lmax = (0..3).map(|k| (t[(k + 1) % 3] - t[k]).length_squared()).fold(0.0, f64::max);
    let cross = (t[1] - t[0]).cross(t[2] - t[0]).length();
    cross.is_finite() && cross > 1e-12 * lmax
}

/// Angles and cotan half-weights of the fill triangles `tris` (local indices into `ids`) with
/// corner positions `corners` (planar ones are positively oriented by construction, so the
/// unsigned area is their area).
fn assemble(kind: Fill, ids: &[u32], tris: &[[u32; 3]], corners: &[[DVec3; 3]]) -> HoleFill {
    let mut fill = HoleFill {
        kind,
        triangles: Vec::with_capacity(tris.len()),
        angles: Vec::with_capacity(tris.len()),
        weights: Vec::with_capacity(3 * tris.len()),
    };
    for (t, c) in tris.iter().zip(corners) {
        let v = t.map(|k| ids[k as usize]);
        let cross = (c[1] - c[0]).cross(c[2] - c[0]).length();
        let mut angles = [0.0; 3];
        for k in 0..3 {
            let (e1, e2) = (c[(k + 1) % 3] - c[k], c[(k + 2) % 3] - c[k]);
            angles[k] = num::atan2(cross, e1.dot(e2));
            let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            fill.weights.push((a.min(b), a.max(b), 0.5 * e1.dot(e2) / cross));
        }
        fill.triangles.push(v);
        fill.angles.push(angles);
    }
    fill
}

#[cfg(test)]
mod tests {
    use super::*;

    fn staircase_slot() -> Vec<DVec2> {
        // A "tilted" staircase: steps rising one unit every four along x on the top side and
        // falling back along the bottom, counter-clockwise; not star-shaped from its centroid.
        let mut pts = Vec::new();
        for s in 0..4 {
            let y = s as f64;
            pts.push(DVec2::new(4.0 * s as f64, y - 3.0));
            pts.push(DVec2::new(4.0 * s as f64 + 4.0, y - 3.0));
        }
        for s in (0..4).rev() {
            let y = s as f64 + 1.0;
            pts.push(DVec2::new(4.0 * s as f64 + 4.0, y));
            pts.push(DVec2::new(4.0 * s as f64, y));
        }
        pts.dedup();
        pts
    }

    #[test]
    fn staircase_polygon_is_triangulated_validly_and_delaunay() {
        let pts = staircase_slot();
        assert!(is_simple(&pts) && signed_area(&pts) > 0.0);
        let tris = triangulate(&pts).expect("triangulation");
        assert_eq!(tris.len(), pts.len() - 2);
        let area: f64 = tris.iter().map(|t| orient(pts[t[0] as usize], pts[t[1] as usize], pts[t[2] as usize])).sum();
        assert!((area - signed_area(&pts)).abs() < 1e-9);
        // Angle sums at each vertex equal the polygon's interior angle.
        let ids: Vec<u32> = (0..pts.len() as u32).collect();
        let corners: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(|k| pts[k as usize].extend(0.0))).collect();
        let fill = assemble(Fill::Triangulated, &ids, &tris, &corners);
        let mut sum = vec![0.0; pts.len()];
        for (t, a) in fill.triangles.iter().zip(&fill.angles) {
            for k in 0..3 {
                sum[t[k] as usize] += a[k];
            }
        }
        let n = pts.len();
        for m in 0..n {
            let (u, v) = (pts[(m + 1) % n] - pts[m], pts[(m + n - 1) % n] - pts[m]);
            let mut interior = num::atan2(u.perp_dot(v), u.dot(v));
            if interior < 0.0 {
                interior += 2.0 * PI;
            }
            assert!((sum[m] - interior).abs() < 1e-12, "vertex {m}: {} vs {interior}", sum[m]);
        }
        // Interior edges (appearing twice) have non-negative weights.
        let mut w = fill.weights.clone();
        w.sort_by_key(|e| (e.0, e.1));
        for pair in w.windows(2) {
            if (pair[0].0, pair[0].1) == (pair[1].0, pair[1].1) {
                assert!(pair[0].2 + pair[1].2 > -1e-12, "{pair:?}");
            }
        }
    }

    #[test]
    fn self_intersecting_polygons_are_not_simple() {
        let bow = [DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
        assert!(!is_simple(&bow));
        let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        assert!(is_simple(&square));
        // A spike folding back on its own edge.
        let spike = [DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0)];
        assert!(!is_simple(&spike));
    }
}
