//! What the facets alone leave: at a concave crease between two flat facets a ball of radius R
//! cannot reach the crease line, whatever the path. Checked before planning so the user learns
//! that a file is too coarse for the asked scallop height before trusting its G-code (issue 34).
//!
//! For two facets whose normals make the angle φ at a concave edge, a ball of radius R touching
//! both stands at R/cos(φ/2) from the crease on the bisector; along either facet's normal at the
//! crease it leaves
//!
//! depth = R·(1 − √(1 − tan²(φ/2)))    (R when φ ≥ 90°),
//!
//! the verifier's measure of a scallop (along the normal), ≈ R·φ²/8 for small φ. An edge is
//! concave when the far corner of one facet lies on the tool's side of the other's plane.
//!
//! Where concave creases meet at a *pit* (a vertex all of whose neighbours lie on the tool's
//! side of its normal plane), the ball is held off by all the facets at once and leaves more
//! than any one crease: its centre is the point x nearest the vertex with nᵢ·x ≥ R for every
//! incident facet (the facets' planes stand for the facets near a pit), found by trying every
//! active set of one to three planes, and the depth is |x| − R.
//!
//! Deterministic: the edges are paired by sorting, and only maxima and sums in edge order are
//! kept.

use super::Surface;

/// The concave creases whose depth exceeds the scallop limit.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FacetValleys {
    /// Interior edges whose crease leaves more than h.
    pub edges: usize,
    /// Their total length, mm.
    pub length_mm: f64,
    /// The deepest crease's depth, mm (0 when there is no concave edge).
    pub max_depth_mm: f64,
    /// Pit vertices (where concave creases meet) that leave more than h.
    pub pits: usize,
    /// The deepest crease's edge, or its pit vertex.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deepest_edge: Option<[u32; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deepest_vertex: Option<u32>,
}

/// The depth a ball of radius `radius_mm` leaves at a concave crease whose facet normals make
/// the angle with cosine `cos_phi`, mm.
pub fn crease_depth_mm(radius_mm: f64, cos_phi: f64) -> f64 {
    let cos_half_sq = (0.5 * (1.0 + cos_phi.clamp(-1.0, 1.0))).max(0.0);
    if cos_half_sq <= 0.5 {
        return radius_mm;
    }
    let tan_half_sq = (1.0 - cos_half_sq) / cos_half_sq;
    radius_mm * (1.0 - (1.0 - tan_half_sq).sqrt())
}

/// The concave creases of `surface` (normals facing the tool) that leave more than
/// `scallop_mm` for a ball of radius `radius_mm`.
pub fn facet_valleys(surface: &Surface, radius_mm: f64, scallop_mm: f64) -> FacetValleys {
    let mut half_edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * surface.triangles.len());
    for (f, t) in surface.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            half_edges.push((a.min(b), a.max(b), f as u32));
        }
    }
    half_edges.sort_unstable();
    let mut out = FacetValleys::default();
    for pair in half_edges.windows(2) {
        let ((a, b, f), (a2, b2, g)) = (pair[0], pair[1]);
        if (a, b) != (a2, b2) {
            continue;
        }
        let (nf, ng) = (surface.face_normals[f as usize], surface.face_normals[g as usize]);
        let far = |face: u32| {
            let t = surface.triangles[face as usize];
            t.into_iter().find(|&v| v != a && v != b).expect("a triangle has a corner off its edge")
        };
        let pa = surface.positions[a as usize];
        // Concave: g's far corner above f's plane (the tool's side).
        if (surface.positions[far(g) as usize] - pa).dot(nf) <= 0.0 {
            continue;
        }
        let depth = crease_depth_mm(radius_mm, nf.dot(ng));
        if depth > out.max_depth_mm {
            out.max_depth_mm = depth;
            out.deepest_edge = Some([a, b]);
        }
        if depth > scallop_mm {
            out.edges += 1;
            out.length_mm += (surface.positions[b as usize] - pa).length();
        }
    }
    for (v, depth) in pit_depths_mm(surface, radius_mm) {
        if depth > out.max_depth_mm {
            out.max_depth_mm = depth;
            out.deepest_edge = None;
            out.deepest_vertex = Some(v);
        }
        if depth > scallop_mm {
            out.pits += 1;
        }
    }
    out
}

/// The depth the ball leaves at every pit vertex of `surface`, mm.
fn pit_depths_mm(surface: &Surface, radius_mm: f64) -> Vec<(u32, f64)> {
    let mut faces_of: Vec<Vec<u32>> = vec![Vec::new(); surface.positions.len()];
    for (f, t) in surface.triangles.iter().enumerate() {
        for &v in t {
            faces_of[v as usize].push(f as u32);
        }
    }
    let mut boundary = vec![false; surface.positions.len()];
    for l in &surface.loops {
        for &v in l {
            boundary[v as usize] = true;
        }
    }
    let mut out = Vec::new();
    for (v, faces) in faces_of.iter().enumerate() {
        if boundary[v] || faces.len() < 3 {
            continue;
        }
        let (p, n) = (surface.positions[v], surface.vertex_normals[v]);
        let pit = faces.iter().all(|&f| {
            surface.triangles[f as usize]
                .iter()
                .all(|&u| u as usize == v || (surface.positions[u as usize] - p).dot(n) > 0.0)
        });
        if !pit {
            continue;
        }
        let normals: Vec<glam::DVec3> = faces.iter().map(|&f| surface.face_normals[f as usize]).collect();
        if let Some(x) = nearest_centre(&normals, radius_mm) {
            out.push((v as u32, (x.length() - radius_mm).max(0.0)));
        }
    }
    out
}

/// The point x of least norm with nᵢ·x ≥ r for every i: the minimum-norm solution of each
/// active set of one to three planes, the feasible one of least norm.
fn nearest_centre(normals: &[glam::DVec3], r: f64) -> Option<glam::DVec3> {
    let feasible = |x: glam::DVec3| normals.iter().all(|n| n.dot(x) >= r * (1.0 - 1e-9));
    let mut best: Option<glam::DVec3> = None;
    let mut consider = |x: glam::DVec3| {
        if x.is_finite() && feasible(x) && best.map_or(true, |b| x.length_squared() < b.length_squared()) {
            best = Some(x);
        }
    };
    let k = normals.len();
    for i in 0..k {
        consider(normals[i] * r);
        for j in i + 1..k {
            // x = a·nᵢ + b·nⱼ with nᵢ·x = nⱼ·x = r: a = b = r / (1 + nᵢ·nⱼ).
            let c = normals[i].dot(normals[j]);
            if c > -1.0 + 1e-12 {
                consider((normals[i] + normals[j]) * (r / (1.0 + c)));
            }
            for l in j + 1..k {
                let m = glam::DMat3::from_cols(normals[i], normals[j], normals[l]).transpose();
                if m.determinant().abs() > 1e-12 {
                    consider(m.inverse() * glam::DVec3::splat(r));
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_depth_matches_a_ball_in_a_v_groove() {
        // A 90° groove (normals 90° apart): the ball's centre at R·√2 from the crease, its
        // surface along a facet normal at R·(1 − √(1 − 1)) = R from the crease.
        assert!((crease_depth_mm(3.0, 0.0) - 3.0).abs() < 1e-12);
        assert_eq!(crease_depth_mm(3.0, 1.0), 0.0);
        // Brute force: the smallest t with |t·n1 − C| = R along the normal n1 of a facet.
        for phi_deg in [1.0_f64, 5.0, 20.0, 60.0] {
            let (phi, r) = (phi_deg.to_radians(), 2.0);
            let b = glam::DVec2::new(0.0, 1.0); // bisector
            let n1 = glam::DVec2::new(-(phi / 2.0).sin(), (phi / 2.0).cos());
            let c = b * (r / (phi / 2.0).cos());
            let mut lo = 0.0;
            let mut hi = r;
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if (n1 * mid - c).length() > r {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let depth = crease_depth_mm(r, phi.cos());
            assert!((depth - lo).abs() < 1e-9, "φ {phi_deg}°: {depth} against {lo}");
        }
    }
}
