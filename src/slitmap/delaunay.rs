//! Lawson edge flips of the flattened triangulation until every interior edge is locally
//! Delaunay, for the slit map's Laplacian.
//!
//! Why: the cotan weight of an edge is negative when its two opposite angles sum to more than π.
//! Negative weights break the discrete maximum principle, and the harmonic h and its conjugate
//! then fold image triangles (CAD meshes are full of such obtuse pairs). On a Delaunay
//! triangulation of the same vertices every weight is non-negative (Bobenko & Springborn 2007;
//! in the plane the intrinsic Delaunay triangulation is the ordinary one). The vertices and the
//! boundary edges are unchanged, so the solution is still one value per vertex of the part and
//! the map is still read on the part's own triangles.
//!
//! Precondition: a planar triangulation with counter-clockwise, non-degenerate triangles (the
//! slit-map solver checks it first). A non-locally-Delaunay interior edge of such a
//! triangulation always has a strictly convex quadrilateral, so each flip keeps the triangles
//! counter-clockwise; Lawson's algorithm terminates in O(n²) flips and in practice in O(n).
//! Deterministic: edges are visited in a fixed order.

use glam::DVec2;

/// The Delaunay triangulation of `positions` reached by flipping interior edges of `triangles`
/// (same vertices, same boundary edges, counter-clockwise), and the number of flips.
pub fn delaunay_flip(positions: &[DVec2], triangles: &[[u32; 3]]) -> (Vec<[u32; 3]>, usize) {
    let p = |v: u32| positions[v as usize];
    crate::flip::lawson(triangles, |a, b, c, d| needs_flip(p(a), p(b), p(c), p(d)))
}

/// Edge a–b with c on its left and d on its right is not locally Delaunay: the angles at c and
/// d sum to more than π (cot c + cot d < 0), with a relative margin so rounding cannot cycle,
/// and the quadrilateral a d b c is strictly convex.
fn needs_flip(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let cot = |o: DVec2, u: DVec2, v: DVec2| {
        let (e1, e2) = (u - o, v - o);
        e1.dot(e2) / e1.perp_dot(e2).abs()
    };
    let s = cot(c, a, b) + cot(d, a, b);
    if s >= -1e-9 || s.is_nan() {
        return false;
    }
    // Convex: c and d on opposite sides of a–b (given), and a and b on opposite sides of c–d.
    let side = |o: DVec2, u: DVec2, q: DVec2| (u - o).perp_dot(q - o);
    side(c, d, a) < 0.0 && side(c, d, b) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thin_quad_gets_the_short_diagonal() {
        // a b on the long diagonal; c and d close to it: both angles near π.
        let p = [DVec2::new(0.0, 0.0), DVec2::new(4.0, 0.0), DVec2::new(2.0, 0.3), DVec2::new(2.0, -0.3)];
        let (t, flips) = delaunay_flip(&p, &[[0, 1, 2], [1, 0, 3]]);
        assert_eq!(flips, 1);
        assert_eq!(t, vec![[2, 0, 3], [3, 1, 2]]);
        for tri in &t {
            let [a, b, c] = tri.map(|v| p[v as usize]);
            assert!((b - a).perp_dot(c - a) > 0.0);
        }
    }

    #[test]
    fn a_delaunay_mesh_is_left_alone_and_every_weight_is_non_negative_after() {
        // A jittered grid: some obtuse pairs, every weight ≥ 0 after the flips.
        let n = 12;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let jitter = if i > 0 && i < n && j > 0 && j < n {
                    0.35 * (((i * 7 + j * 13) % 11) as f64 / 11.0 - 0.5)
                } else {
                    0.0
                };
                p.push(DVec2::new(i as f64 + jitter, j as f64 - jitter));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let (d, _) = delaunay_flip(&p, &t);
        let w = crate::linalg::cotan_weights_2d(&p, &d);
        let boundary = |v: u32| {
            let (i, j) = (v as usize % (n + 1), v as usize / (n + 1));
            i == 0 || j == 0 || i == n || j == n
        };
        for &(i, j, wt) in &w {
            if !(boundary(i) && boundary(j)) {
                assert!(wt >= -1e-9, "edge {i}-{j} has weight {wt}");
            }
        }
        let (again, flips) = delaunay_flip(&p, &d);
        assert_eq!(flips, 0);
        assert_eq!(again, d);
    }
}
