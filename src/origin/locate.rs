//! Points of the surface and of the flattened plane: nearest surface point of a 3D point, the
//! face of the flattened domain containing a pole, and the 3D point of a pole.

use crate::mesh::nearest::closest_on_triangle;
use crate::mesh::Surface;
use crate::slitmap::{barycentric, PlanarDomain};
use glam::{DVec2, DVec3};

/// Nearest point of the surface to `p`: (face, barycentric coordinates). Brute force, O(faces).
pub(crate) fn nearest_on_surface(surface: &Surface, p: DVec3) -> (usize, [f64; 3]) {
    let mut best = (f64::INFINITY, 0, [1.0, 0.0, 0.0]);
    for (f, t) in surface.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| surface.positions[v as usize]);
        let bary = closest_on_triangle(p, a, b, c);
        let q = a * bary[0] + b * bary[1] + c * bary[2];
        let d = q.distance_squared(p);
        if d < best.0 {
            best = (d, f, bary);
        }
    }
    (best.1, best.2)
}

/// The face of the flattened domain containing `q` (largest minimum barycentric coordinate, so
/// a point on an edge gets a deterministic answer) with its barycentric coordinates. O(faces).
pub(crate) fn face_containing(domain: &PlanarDomain, q: DVec2) -> Option<(usize, [f64; 3])> {
    let mut best: Option<(usize, [f64; 3], f64)> = None;
    for (f, t) in domain.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| domain.positions[v as usize]);
        let bary = barycentric(a, b, c, q);
        let m = bary[0].min(bary[1]).min(bary[2]);
        if m >= -1e-12 && best.map_or(true, |(_, _, bm)| m > bm) {
            best = Some((f, bary, m));
        }
    }
    best.map(|(f, b, _)| (f, b))
}

fn face_centroid(domain: &PlanarDomain, f: usize) -> DVec2 {
    domain.triangles[f].iter().map(|&v| domain.positions[v as usize]).sum::<DVec2>() / 3.0
}

/// Distance from `q` to the nearest boundary edge of the domain.
pub(crate) fn boundary_distance(domain: &PlanarDomain, q: DVec2) -> f64 {
    nearest_boundary_point(domain, q).map_or(f64::INFINITY, |b| b.distance(q))
}

/// The point of the domain's boundary nearest to `q` (the first of equals, in loop order);
/// `None` without a boundary.
pub(crate) fn nearest_boundary_point(domain: &PlanarDomain, q: DVec2) -> Option<DVec2> {
    let mut best: Option<(f64, DVec2)> = None;
    for lp in &domain.loops {
        for k in 0..lp.len() {
            let a = domain.positions[lp[k] as usize];
            let b = domain.positions[lp[(k + 1) % lp.len()] as usize];
            let p = segment_point(q, a, b);
            let d = p.distance(q);
            if best.map_or(true, |(bd, _)| d < bd) {
                best = Some((d, p));
            }
        }
    }
    best.map(|(_, p)| p)
}

/// The point of the segment ab nearest to `q`.
fn segment_point(q: DVec2, a: DVec2, b: DVec2) -> DVec2 {
    let ab = b - a;
    let t = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    let t = if t.is_finite() { t } else { 0.0 };
    a + ab * t
}

/// Poles `count` steps of `step` from `pole` straight away from its nearest boundary point
/// (`pole` + k·`step` along that direction, k = 1…), keeping those inside the domain at least
/// `step`/2 from every boundary: where a centroid beside a hole cannot carry a path, the
/// nearest poles that leave the P1 map room round them.
pub(crate) fn away_from_boundary(domain: &PlanarDomain, pole: DVec2, step: f64, count: usize) -> Vec<DVec2> {
    let Some(b) = nearest_boundary_point(domain, pole) else { return Vec::new() };
    let away = (pole - b).normalize_or_zero();
    if away == DVec2::ZERO {
        return Vec::new();
    }
    (1..=count)
        .map(|k| pole + away * (step * k as f64))
        .filter(|&q| face_containing(domain, q).is_some() && boundary_distance(domain, q) >= 0.5 * step)
        .collect()
}

/// Bounding-box diagonal of the flattened domain.
pub(crate) fn domain_size(domain: &PlanarDomain) -> f64 {
    let lo = domain.positions.iter().copied().fold(DVec2::INFINITY, DVec2::min);
    let hi = domain.positions.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max);
    (hi - lo).length()
}

/// The area centroid of the flattened domain (holes excluded, as they carry no triangles). When
/// it is outside the domain, in a hole or within 1e-6 of the domain size of a boundary, the
/// centroid of the face nearest to it instead: a point safely inside, so always a disk pole.
/// NaN for an empty domain.
pub fn centroid_pole(domain: &PlanarDomain) -> DVec2 {
    let mut area = 0.0;
    let mut c = DVec2::ZERO;
    for t in &domain.triangles {
        let [a, b, p] = t.map(|v| domain.positions[v as usize]);
        let ar = 0.5 * (b - a).perp_dot(p - a);
        area += ar;
        c += (a + b + p) / 3.0 * ar;
    }
    if domain.triangles.is_empty() || area == 0.0 {
        return DVec2::NAN;
    }
    let c = c / area;
    if face_containing(domain, c).is_some() && boundary_distance(domain, c) > 1e-6 * domain_size(domain) {
        return c;
    }
    let face = (0..domain.triangles.len())
        .min_by(|&a, &b| face_centroid(domain, a).distance(c).total_cmp(&face_centroid(domain, b).distance(c)))
        .expect("the domain has triangles");
    face_centroid(domain, face)
}

/// The pole of a point `p` in the part's coordinates: the nearest surface point (barycentric on
/// the nearest 3D triangle) carried to the flattened plane with the same barycentric
/// coordinates. `domain` must be the flattening of `surface` (same vertices). A point beyond the
/// part's edge lands on the boundary, which the slit map refuses
/// ([`crate::slitmap::SlitMapError::PoleOnBoundary`]). NaN when `p` is not finite or the surface
/// has no triangles.
pub fn pole_from_3d(surface: &Surface, domain: &PlanarDomain, p: DVec3) -> DVec2 {
    if !p.is_finite() || surface.triangles.is_empty() {
        return DVec2::NAN;
    }
    let (face, bary) = nearest_on_surface(surface, p);
    let t = surface.triangles[face];
    let mut uv = DVec2::ZERO;
    for k in 0..3 {
        let Some(&z) = domain.positions.get(t[k] as usize) else { return DVec2::NAN };
        uv += z * bary[k];
    }
    uv
}

/// The 3D surface point of a pole: the barycentric image of the flattened face containing it
/// (disk pole), or the centroid of hole `hole`'s rim (annulus pole, loop index ≥ 1; edge-length
/// weighted), or for a disk pole that no face contains (between faces by rounding) the nearest
/// face centre. `domain` must be the flattening of `surface`; NaN when it is empty.
pub fn pole_to_3d(surface: &Surface, domain: &PlanarDomain, pole: DVec2, hole: Option<usize>) -> DVec3 {
    if let Some(lp) = hole.and_then(|h| surface.loops.get(h)) {
        return rim_centroid(surface, lp);
    }
    let face = match face_containing(domain, pole) {
        Some((f, bary)) => {
            if let Some(t) = surface.triangles.get(f) {
                return (0..3).map(|k| surface.positions[t[k] as usize] * bary[k]).sum();
            }
            None
        }
        None => (0..domain.triangles.len()).min_by(|&a, &b| {
            face_centroid(domain, a).distance(pole).total_cmp(&face_centroid(domain, b).distance(pole))
        }),
    };
    match face.and_then(|f| surface.triangles.get(f)) {
        Some(t) => t.iter().map(|&v| surface.positions[v as usize]).sum::<DVec3>() / 3.0,
        None => DVec3::NAN,
    }
}

/// Edge-length weighted centroid of a closed 3D polyline.
fn rim_centroid(surface: &Surface, lp: &[u32]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    let mut len = 0.0;
    for k in 0..lp.len() {
        let a = surface.positions[lp[k] as usize];
        let b = surface.positions[lp[(k + 1) % lp.len()] as usize];
        let l = a.distance(b);
        sum += (a + b) * (0.5 * l);
        len += l;
    }
    if len > 0.0 {
        sum / len
    } else {
        lp.iter().map(|&v| surface.positions[v as usize]).sum::<DVec3>() / lp.len().max(1) as f64
    }
}
