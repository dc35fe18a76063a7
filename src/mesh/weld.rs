//! Welding: corners closer than a tolerance become one vertex; degenerate and duplicate faces go.
//!
//! O(n log n): corners are bucketed on a grid of cell size `tolerance`, the cells sorted, and each
//! corner compared only with corners of the neighbouring cells (found by binary search in the sorted
//! cell list). Clusters are merged with union–find; a welded vertex takes the position of the
//! cluster's first corner in file order, and vertices are numbered in order of first use, so the
//! result does not depend on anything but the input order.

use super::{MeshError, TriMesh};
use glam::DVec3;

/// The welded mesh and what was dropped on the way.
#[derive(Clone, Debug)]
pub struct Welded {
    pub mesh: TriMesh,
    /// Faces with two equal corners after welding or with zero area.
    pub degenerate_dropped: usize,
    /// Faces with the same three vertices as an earlier face (either winding).
    pub duplicates_dropped: usize,
}

/// Welds `mesh` with a tolerance of `tolerance_rel` × bounding-box diagonal.
pub fn weld(mesh: &TriMesh, tolerance_rel: f64) -> Result<Welded, MeshError> {
    if mesh.triangles.is_empty() {
        return Err(MeshError::NoTriangles);
    }
    let (lo, hi) = bounding_box(&mesh.positions);
    let diagonal = (hi - lo).length();
    let tolerance = tolerance_rel * diagonal;
    let cluster = clusters(&mesh.positions, lo, tolerance);

    // Vertices numbered by first use in face order: the output follows the file order.
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let mut mapped = Vec::with_capacity(mesh.triangles.len());
    for t in &mesh.triangles {
        mapped.push(t.map(|c| {
            let root = cluster[c as usize] as usize;
            if new_index[root] == u32::MAX {
                new_index[root] = positions.len() as u32;
                positions.push(mesh.positions[root]);
            }
            new_index[root]
        }));
    }

    // Twice the area below this is zero for all purposes (relative to the part's size).
    let min_double_area = 1e-14 * diagonal * diagonal;
    let mut degenerate = 0;
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(mapped.len());
    for t in mapped {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || (b - a).cross(c - a).length() <= min_double_area {
            degenerate += 1;
        } else {
            kept.push(t);
        }
    }
    if kept.is_empty() {
        return Err(MeshError::AllDegenerate { dropped: degenerate });
    }

    // Duplicate faces: sort by the sorted vertex triple, keep the first in file order.
    // Keys computed once, not in every comparison.
    let mut order: Vec<([u32; 3], u32)> = kept
        .iter()
        .enumerate()
        .map(|(f, t)| {
            let mut k = *t;
            k.sort_unstable();
            (k, f as u32)
        })
        .collect();
    crate::par::sort_unstable(&mut order);
    let mut duplicate = vec![false; kept.len()];
    for w in order.windows(2) {
        if w[0].0 == w[1].0 {
            duplicate[w[1].1 as usize] = true;
        }
    }
    let duplicates_dropped = duplicate.iter().filter(|&&d| d).count();
    let triangles: Vec<[u32; 3]> = kept.into_iter().zip(&duplicate).filter(|(_, &d)| !d).map(|(t, _)| t).collect();

    Ok(Welded { mesh: compact(&positions, &triangles), degenerate_dropped: degenerate, duplicates_dropped })
}

/// Drops unreferenced vertices, keeping the order of the rest.
pub fn compact(positions: &[DVec3], triangles: &[[u32; 3]]) -> TriMesh {
    let mut used = vec![false; positions.len()];
    for t in triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut remap = vec![u32::MAX; positions.len()];
    let mut out = Vec::new();
    for (v, &u) in used.iter().enumerate() {
        if u {
            remap[v] = out.len() as u32;
            out.push(positions[v]);
        }
    }
    TriMesh { positions: out, triangles: triangles.iter().map(|t| t.map(|v| remap[v as usize])).collect() }
}

pub fn bounding_box(positions: &[DVec3]) -> (DVec3, DVec3) {
    positions
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

/// For every corner, the lowest-index corner of its cluster.
fn clusters(positions: &[DVec3], origin: DVec3, tolerance: f64) -> Vec<u32> {
    let n = positions.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    if tolerance <= 0.0 {
        // Exact equality only: sort by coordinates and merge equal runs.
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&a, &b| {
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            pa.to_array().partial_cmp(&pb.to_array()).expect("finite").then(a.cmp(&b))
        });
        for w in order.windows(2) {
            if positions[w[0] as usize] == positions[w[1] as usize] {
                union(&mut parent, w[0], w[1]);
            }
        }
    } else {
        let key = |p: DVec3| ((p - origin) / tolerance).floor().as_i64vec3().to_array();
        let mut sorted: Vec<([i64; 3], u32)> = positions.iter().enumerate().map(|(i, &p)| (key(p), i as u32)).collect();
        crate::par::sort_unstable(&mut sorted);
        let tol2 = tolerance * tolerance;
        // Half of the 3×3 column neighbourhood, so every unordered pair of cells is seen once.
        // Offsetting a key preserves the lexicographic order, so each column's lower bound only
        // moves forward while the sorted corners are visited: one pointer per column, O(n).
        const COLUMNS: [(i64, i64); 5] = [(0, 0), (0, 1), (1, -1), (1, 0), (1, 1)];
        let mut cursor = [0usize; 5];
        for &(k, i) in &sorted {
            let p = positions[i as usize];
            for (c, (dx, dy)) in COLUMNS.into_iter().enumerate() {
                let lo_key = [k[0] + dx, k[1] + dy, if (dx, dy) == (0, 0) { k[2] } else { k[2] - 1 }];
                let hi_key = [k[0] + dx, k[1] + dy, k[2] + 1];
                while cursor[c] < sorted.len() && sorted[cursor[c]].0 < lo_key {
                    cursor[c] += 1;
                }
                for &(_, j) in sorted[cursor[c]..].iter().take_while(|(kk, _)| *kk <= hi_key) {
                    if j != i && positions[j as usize].distance_squared(p) <= tol2 {
                        union(&mut parent, i, j);
                    }
                }
            }
        }
    }
    (0..n as u32).map(|i| find(&mut parent, i)).collect()
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let grand = parent[parent[i as usize] as usize];
        parent[i as usize] = grand;
        i = grand;
    }
    i
}

/// Union keeping the lowest index as root, so the representative is the first corner.
fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_within_tolerance_only() {
        let eps = 1e-9;
        let soup = TriMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::new(1.0 + eps, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0 - eps, 0.0),
            ],
            triangles: vec![[0, 1, 2], [3, 4, 5]],
        };
        let w = weld(&soup, 1e-6).unwrap();
        assert_eq!(w.mesh.positions.len(), 4);
        assert_eq!(w.mesh.triangles, vec![[0, 1, 2], [1, 3, 2]]);
        // A tolerance far below the gap keeps the corners apart.
        let w = weld(&soup, 1e-12).unwrap();
        assert_eq!(w.mesh.positions.len(), 6);
    }

    #[test]
    fn drops_degenerate_and_duplicate_faces() {
        let soup = TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(2.0, 0.0, 0.0)],
            triangles: vec![[0, 1, 2], [0, 1, 3], [2, 1, 0], [0, 0, 2]],
        };
        let w = weld(&soup, 1e-6).unwrap();
        assert_eq!(w.degenerate_dropped, 2); // collinear 0-1-3 and repeated corner
        assert_eq!(w.duplicates_dropped, 1);
        assert_eq!(w.mesh.triangles.len(), 1);
        assert_eq!(w.mesh.positions.len(), 3);
    }

    #[test]
    fn all_degenerate_is_an_error() {
        let soup =
            TriMesh { positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)], triangles: vec![[0, 1, 2]] };
        assert_eq!(weld(&soup, 1e-6).unwrap_err(), MeshError::AllDegenerate { dropped: 1 });
    }

    /// Brute-force oracle: every pair closer than the tolerance ends in one cluster.
    #[test]
    fn clusters_match_brute_force() {
        let mut s = 12345u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pts: Vec<DVec3> = (0..400).map(|_| DVec3::new(next(), next(), next())).collect();
        for i in 0..200 {
            let p = pts[i] + DVec3::new(next(), next(), next()) * 1e-3;
            pts.push(p);
        }
        let tol = 1.2e-3;
        let c = clusters(&pts, DVec3::ZERO, tol);
        for i in 0..pts.len() {
            for j in 0..pts.len() {
                if pts[i].distance(pts[j]) <= tol {
                    assert_eq!(c[i], c[j], "{i} {j}");
                }
            }
        }
    }
}
