//! The facet point nearest to an axis within a slab across it: a cylinder's clearance.
//!
//! A tool's shank or holder is a cylinder of radius R about its axis between two heights
//! h₀ ≤ h ≤ h₁ along it (h measured from an origin on the axis). The part enters it exactly when
//! some point of the mesh in that slab lies nearer than R to the axis line, so its clearance is
//! (the least such distance) − R. [`FaceTree::nearest_to_axis`] computes that least distance
//! exactly: each triangle is clipped to the slab (a convex polygon of up to five corners),
//! projected along the axis onto the plane across it, and the distance from the axis's trace
//! to the projected polygon taken (0 when the axis pierces it; else the nearest edge). The
//! projection keeps the parameters along edges, so the 3D point is found with it.
//!
//! Points beyond the slab do not count: the end faces of the cylinder are the neighbouring
//! parts of the tool (the flutes below a shank, the shank below a holder), checked by their own
//! slabs. Deterministic: ties go to the first face met in the tree's fixed order.

use super::nearest::FaceTree;
use crate::bvh::{Node, Walk};
use glam::{DVec2, DVec3};

/// The facet point nearest to an axis within a slab ([`FaceTree::nearest_to_axis`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxialNearest {
    pub face: usize,
    pub point: DVec3,
    /// Its distance from the axis line, mm.
    pub radial_mm: f64,
}

/// A slab of an axis: the points whose height `(p − origin)·axis` lies in `from..=to`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slab {
    pub origin: DVec3,
    /// Unit vector.
    pub axis: DVec3,
    pub from: f64,
    pub to: f64,
}

impl FaceTree {
    /// The mesh point in `slab` nearest to its axis line, if nearer than `limit` (module docs).
    pub fn nearest_to_axis(&self, slab: &Slab, limit: f64) -> Option<AxialNearest> {
        if slab.to < slab.from || slab.to.is_nan() || slab.from.is_nan() {
            return None;
        }
        let (p, q) = (slab.origin + slab.from * slab.axis, slab.origin + slab.to * slab.axis);
        let mid = 0.5 * (p + q);
        let half = 0.5 * (slab.to - slab.from);
        let mut best: Option<AxialNearest> = None;
        let mut bound = limit;
        let mut walk = Walk::new(&self.nodes);
        // A box farther than bound + half from the segment's midpoint is farther than the bound
        // from the segment, and so from the axis within the slab.
        let far = |node: &Node, bound: f64| node.distance2(mid) > (bound + half) * (bound + half);
        while let Some(slots) = walk.next_leaf(&self.nodes, |node| far(node, bound)) {
            for slot in slots {
                let (m, r) = self.spheres[slot];
                let t = (m - slab.origin).dot(slab.axis);
                // The face's bounding sphere misses the slab, or lies beyond the bound.
                if t + r < slab.from || t - r > slab.to {
                    continue;
                }
                let foot = slab.origin + t.clamp(slab.from, slab.to) * slab.axis;
                if m.distance(foot) - r >= bound {
                    continue;
                }
                let [a, b, c] = self.corners[slot];
                if let Some((radial, point)) = triangle_axis_distance(&[a, b, c], slab) {
                    if radial < bound {
                        bound = radial;
                        best = Some(AxialNearest { face: self.order[slot] as usize, point, radial_mm: radial });
                    }
                }
            }
        }
        best
    }
}

/// The least distance from the axis line of `slab` to the part of triangle `tri` within the
/// slab, and the point where it is reached; `None` when the triangle misses the slab.
pub fn triangle_axis_distance(tri: &[DVec3; 3], slab: &Slab) -> Option<(f64, DVec3)> {
    let height = |p: DVec3| (p - slab.origin).dot(slab.axis);
    // Sutherland–Hodgman against h ≥ from, then h ≤ to.
    let mut poly: Vec<DVec3> = tri.to_vec();
    for (level, keep_above) in [(slab.from, true), (slab.to, false)] {
        let inside = |p: DVec3| if keep_above { height(p) >= level } else { height(p) <= level };
        let mut out = Vec::with_capacity(poly.len() + 1);
        for k in 0..poly.len() {
            let (s, e) = (poly[k], poly[(k + 1) % poly.len()]);
            let (si, ei) = (inside(s), inside(e));
            if si {
                out.push(s);
            }
            if si != ei {
                let (hs, he) = (height(s), height(e));
                out.push(s + (e - s) * ((level - hs) / (he - hs)));
            }
        }
        poly = out;
        if poly.is_empty() {
            return None;
        }
    }
    // Projection onto the plane across the axis, the axis's trace at the origin.
    let u = slab.axis.any_orthonormal_vector();
    let v = slab.axis.cross(u);
    let flat: Vec<DVec2> =
        poly.iter().map(|&p| DVec2::new((p - slab.origin).dot(u), (p - slab.origin).dot(v))).collect();
    let n = flat.len();
    let mut best = (f64::INFINITY, poly[0]);
    let (mut positive, mut negative) = (false, false);
    for k in 0..n {
        let (a, b) = (flat[k], flat[(k + 1) % n]);
        let e = b - a;
        let len2 = e.length_squared();
        let t = if len2 > 0.0 { (-a.dot(e) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let d = (a + t * e).length();
        if d < best.0 {
            best = (d, poly[k] + t * (poly[(k + 1) % n] - poly[k]));
        }
        let cross = a.perp_dot(b);
        positive |= cross > 0.0;
        negative |= cross < 0.0;
    }
    // The trace inside the projected polygon (convex, so every edge turns the same way round
    // it): the axis pierces the clipped triangle.
    if n >= 3 && positive != negative {
        let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let along = normal.dot(slab.axis);
        if along != 0.0 {
            let s = normal.dot(tri[0] - slab.origin) / along;
            return Some((0.0, slab.origin + s * slab.axis));
        }
    }
    Some(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), uniform in [-1, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        fn vec(&mut self, scale: f64) -> DVec3 {
            DVec3::new(self.next(), self.next(), self.next()) * scale
        }
    }

    /// The oracle: a fine barycentric grid of the triangle, points within the slab, least
    /// distance from the axis line. It can only overestimate, by at most the grid's spacing.
    fn brute(tri: &[DVec3; 3], slab: &Slab, n: usize) -> Option<f64> {
        let mut best: Option<f64> = None;
        for i in 0..=n {
            for j in 0..=n - i {
                let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                let p = tri[0] + s * (tri[1] - tri[0]) + t * (tri[2] - tri[0]);
                let h = (p - slab.origin).dot(slab.axis);
                if h < slab.from || h > slab.to {
                    continue;
                }
                let r = (p - slab.origin - h * slab.axis).length();
                best = Some(best.map_or(r, |b: f64| b.min(r)));
            }
        }
        best
    }

    #[test]
    fn triangle_distance_matches_a_brute_force_oracle() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let n = 400;
        let (mut compared, mut pierced) = (0, 0);
        for case in 0..300 {
            let tri = [rng.vec(3.0), rng.vec(3.0), rng.vec(3.0)];
            let axis = rng.vec(1.0).normalize();
            let slab = Slab { origin: rng.vec(1.0), axis, from: -1.0 + 0.5 * rng.next(), to: 0.5 + rng.next().abs() };
            let exact = triangle_axis_distance(&tri, &slab);
            let spacing = (0..3).map(|k| tri[k].distance(tri[(k + 1) % 3])).fold(0.0, f64::max) / n as f64;
            match (exact, brute(&tri, &slab, n)) {
                (Some((d, p)), Some(b)) => {
                    compared += 1;
                    pierced += usize::from(d == 0.0);
                    assert!(d <= b + 1e-12, "case {case}: exact {d} above the oracle {b}");
                    assert!(b - d <= 2.0 * spacing, "case {case}: exact {d}, oracle {b}, spacing {spacing}");
                    // The point is on the triangle's plane, in the slab, at that distance.
                    let h = (p - slab.origin).dot(axis);
                    assert!(h >= slab.from - 1e-9 && h <= slab.to + 1e-9, "case {case}: height {h}");
                    assert!(((p - slab.origin - h * axis).length() - d).abs() < 1e-9, "case {case}");
                    let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                    assert!(normal.dot(p - tri[0]).abs() < 1e-9, "case {case}: off the plane");
                }
                // The grid can miss a sliver of the triangle in the slab, never the reverse.
                (Some(_), None) => {}
                (None, Some(b)) => panic!("case {case}: missed a triangle the oracle finds at {b}"),
                (None, None) => {}
            }
        }
        assert!(compared > 150 && pierced > 5, "compared {compared}, pierced {pierced}");
    }

    /// The tree's query equals the least over every face, on a random soup.
    #[test]
    fn tree_query_equals_the_least_over_all_faces() {
        let mut rng = Rng(42);
        let positions: Vec<DVec3> = (0..300).map(|_| rng.vec(20.0)).collect();
        let triangles: Vec<[u32; 3]> = (0..100).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let tree = FaceTree::new(&positions, &triangles);
        let mut hits = 0;
        for case in 0..50 {
            let slab =
                Slab { origin: rng.vec(20.0), axis: rng.vec(1.0).normalize(), from: 0.0, to: 10.0 + 10.0 * rng.next() };
            let limit = 4.0 + 4.0 * rng.next();
            let all = triangles
                .iter()
                .filter_map(|t| triangle_axis_distance(&t.map(|v| positions[v as usize]), &slab))
                .map(|(d, _)| d)
                .fold(f64::INFINITY, f64::min);
            match tree.nearest_to_axis(&slab, limit) {
                Some(hit) => {
                    hits += 1;
                    assert!((hit.radial_mm - all).abs() < 1e-12 && all < limit, "case {case}");
                }
                None => assert!(all >= limit, "case {case}: tree missed {all} < {limit}"),
            }
        }
        assert!(hits > 10 && hits < 50, "both outcomes are exercised: {hits} hits");
    }
}
