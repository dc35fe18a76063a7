//! Level sets of a piecewise-linear field on a triangle mesh, as polylines (the guiding curves
//! of seed 002 §5 are level sets of G).
//!
//! A vertex is "above" the level c when G ≥ c (so a vertex exactly on the level counts as above:
//! a symbolic perturbation that keeps every crossing strictly inside an edge). An edge crosses
//! when its ends differ, at the linear interpolation point; a face holds 0 or 2 crossings, and
//! the segment between them lies in that face. Chains start at edges on the mesh boundary (open
//! curves), then closed loops; every chain is oriented so that it runs along the given
//! direction. Deterministic: edges in sorted order, no hash maps.

use crate::mesh::Surface;
use glam::DVec3;

/// One level-set polyline: `points[k]` on a mesh edge, segment k (from point k to k + 1) inside
/// face `faces[k]`; `arc[k]` the arc length from the first point.
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    pub points: Vec<DVec3>,
    pub faces: Vec<u32>,
    pub arc: Vec<f64>,
    pub closed: bool,
}

impl Polyline {
    pub fn length(&self) -> f64 {
        *self.arc.last().unwrap_or(&0.0)
    }

    /// The point at arc length `s` (clamped), the segment it lies on and the unit tangent there.
    pub fn at(&self, s: f64) -> (DVec3, usize, DVec3) {
        let n = self.points.len();
        let s = s.clamp(0.0, self.length());
        let k = self.arc.partition_point(|&a| a <= s).clamp(1, n - 1) - 1;
        let len = self.arc[k + 1] - self.arc[k];
        let t = if len > 0.0 { (s - self.arc[k]) / len } else { 0.0 };
        let p = self.points[k] + t * (self.points[k + 1] - self.points[k]);
        (p, k, self.tangent(k))
    }

    /// Unit direction of segment `k` (a zero vector for a degenerate segment).
    pub fn tangent(&self, k: usize) -> DVec3 {
        (self.points[k + 1] - self.points[k]).normalize_or_zero()
    }
}

/// The polylines of the level `c` of `values` (one per vertex), oriented along `direction`.
pub fn level_set(surface: &Surface, values: &[f64], c: f64, direction: DVec3) -> Vec<Polyline> {
    let above = |v: u32| values[v as usize] >= c;
    // (edge, face) for every crossing edge of every face, sorted by edge.
    let mut incidences: Vec<((u32, u32), u32)> = Vec::new();
    for (f, t) in surface.triangles.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            if above(u) != above(v) {
                incidences.push(((u.min(v), u.max(v)), f as u32));
            }
        }
    }
    incidences.sort_unstable();
    // Unique crossing edges with their one or two faces.
    let mut edges: Vec<(u32, u32)> = Vec::new();
    let mut edge_faces: Vec<[u32; 2]> = Vec::new();
    for &(e, f) in &incidences {
        if edges.last() == Some(&e) {
            edge_faces.last_mut().expect("pushed with the edge")[1] = f;
        } else {
            edges.push(e);
            edge_faces.push([f, u32::MAX]);
        }
    }
    let edge_index = |e: (u32, u32)| edges.binary_search(&e).expect("a crossing edge");
    // The other crossing edge of face f (each crossed face has exactly two).
    let other_edge = |f: u32, e: usize| -> usize {
        let t = surface.triangles[f as usize];
        (0..3)
            .map(|k| (t[k], t[(k + 1) % 3]))
            .filter(|&(u, v)| above(u) != above(v))
            .map(|(u, v)| edge_index((u.min(v), u.max(v))))
            .find(|&i| i != e)
            .expect("a face crossed by a level holds two crossing edges")
    };
    let point = |e: usize| {
        let (u, v) = edges[e];
        let (gu, gv) = (values[u as usize], values[v as usize]);
        let t = (c - gu) / (gv - gu);
        surface.positions[u as usize] + t * (surface.positions[v as usize] - surface.positions[u as usize])
    };
    let mut visited = vec![false; edges.len()];
    let mut out = Vec::new();
    // Open chains from boundary edges first (in edge order), then closed loops.
    let starts: Vec<usize> = (0..edges.len())
        .filter(|&e| edge_faces[e][1] == u32::MAX)
        .chain((0..edges.len()).filter(|&e| edge_faces[e][1] != u32::MAX))
        .collect();
    for start in starts {
        if visited[start] {
            continue;
        }
        let closed = edge_faces[start][1] != u32::MAX;
        let (mut points, mut faces) = (vec![point(start)], Vec::new());
        visited[start] = true;
        let (mut e, mut face) = (start, edge_faces[start][0]);
        loop {
            let next = other_edge(face, e);
            faces.push(face);
            points.push(point(next));
            if visited[next] {
                break; // back at the start of a loop
            }
            visited[next] = true;
            let [f0, f1] = edge_faces[next];
            let after = if f0 == face { f1 } else { f0 };
            if after == u32::MAX {
                break; // reached the boundary
            }
            e = next;
            face = after;
        }
        // A level through a vertex puts crossings of several edges on it: drop the repeated
        // points (and their empty segments).
        let mut k = 1;
        while k < points.len() {
            if points[k].distance(points[k - 1]) <= 1e-12 * (1.0 + points[k].abs().max_element()) {
                points.remove(k);
                faces.remove(k - 1);
            } else {
                k += 1;
            }
        }
        if points.len() < 2 {
            continue;
        }
        let along: f64 = points.windows(2).map(|w| (w[1] - w[0]).dot(direction)).sum();
        if along < 0.0 {
            points.reverse();
            faces.reverse();
        }
        let mut arc = Vec::with_capacity(points.len());
        let mut s = 0.0;
        arc.push(0.0);
        for w in points.windows(2) {
            s += w[0].distance(w[1]);
            arc.push(s);
        }
        out.push(Polyline { points, faces, arc, closed });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{from_triangles, MeshOptions};

    #[test]
    fn a_plane_level_is_one_straight_line_along_the_direction() {
        let s =
            from_triangles(&crate::fixtures::flank_plane(40.0, 30.0, 10, 8), &MeshOptions::default()).unwrap().surface;
        let values: Vec<f64> = s.positions.iter().map(|p| p.y).collect();
        for c in [-14.9, -7.3, 0.0, 11.25] {
            let lines = level_set(&s, &values, c, DVec3::X);
            assert_eq!(lines.len(), 1, "level {c}");
            let l = &lines[0];
            assert!(l.points.iter().all(|p| (p.y - c).abs() < 1e-12));
            assert!((l.length() - 40.0).abs() < 1e-9, "{}", l.length());
            assert!(l.points.windows(2).all(|w| w[1].x > w[0].x), "oriented along +X");
            assert_eq!(l.faces.len(), l.points.len() - 1);
            // Each segment lies in its face.
            for (k, &f) in l.faces.iter().enumerate() {
                let t = s.triangles[f as usize];
                let mid = 0.5 * (l.points[k] + l.points[k + 1]);
                let [a, b, cc] = t.map(|v| s.positions[v as usize]);
                let w = crate::mesh::nearest::closest_on_triangle(mid, a, b, cc);
                assert!((a * w[0] + b * w[1] + cc * w[2]).distance(mid) < 1e-12);
            }
        }
        assert!(level_set(&s, &values, 20.0, DVec3::X).is_empty());
    }

    #[test]
    fn a_bump_gives_a_closed_loop() {
        let s = from_triangles(&crate::fixtures::unit_disk(12), &MeshOptions::default()).unwrap().surface;
        let values: Vec<f64> = s.positions.iter().map(|p| p.length()).collect();
        let lines = level_set(&s, &values, 0.5, DVec3::X);
        assert_eq!(lines.len(), 1);
        assert!(lines[0].closed);
        assert!(lines[0].points[0].distance(*lines[0].points.last().unwrap()) < 1e-12);
        assert!((lines[0].length() - std::f64::consts::TAU * 0.5).abs() < 0.05);
    }
}
