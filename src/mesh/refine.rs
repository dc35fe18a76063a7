//! Rim refinement: more triangles around every hole vertex, so the slit map can open each hole
//! into a slit without folding a triangle, and no face with all its corners on the boundary.
//!
//! Why (seed 000 §2.1, DESIGN.md "slitmap"): the slit map sends a hole's boundary onto a
//! two-sided arc. Near the point that becomes the arc's tip the map behaves like `(z − z₀)²`: the
//! interior angle of about π at that boundary vertex opens to 2π. A P1 map sends each triangle to
//! a triangle, so a vertex whose fan has only two faces cannot open to 2π without folding one
//! of them, and three faces barely can. Which vertex becomes a tip depends on the pole, so the
//! refinement is pole-independent: every hole vertex gets at least
//! [`RefineOptions::min_hole_valence`] faces, and the factorisations stay one per mesh.
//!
//! How: the edges opposite a hole vertex in its faces (its link) are split at their midpoints;
//! each split adds one face to that vertex's fan. Faces with one, two or three split edges are
//! cut into two, three or four (a conforming red–green split), so the mesh stays manifold.
//!
//! Long edges: first faces with an edge longer than a fraction of the part's size are bisected
//! through their longest edges until none is left, so that no face spans a large part of the
//! slit domain, where its straight image could not follow the map (see
//! [`RefineOptions::max_edge_fraction`]).
//!
//! Flat regions: then every edge between two coplanar faces that is not locally Delaunay is
//! flipped ([`flip_coplanar`]), and flat regions that still hold needles are remeshed
//! ([`super::quality`], Delaunay refinement). Both are exact on a plane. CAD parts are flat faces
//! tessellated as fans, and the long-edge bisection leaves needles there whose images fold under
//! any P1 map (featuretype folded 226 faces at its centroid pole, wheel_in_box 19).
//!
//! Ears: a face with all three corners on the boundary (typically the triangle at a corner of the
//! outer loop) has its whole image on |w| = 1 (or on a slit) in the log-polar strip the later
//! stages locate points in, a sliver of zero height: no ring can be tested against its interior
//! (panel_6_holes kept a 1.16 h scallop in the ear at a corner). Its interior edges are split
//! too, so every face has a corner off the boundary.
//!
//! Invariants: the refined surface is the same piecewise-flat surface — every child face lies in
//! its parent's plane, keeps its parent's normal and curvature tensor (a remeshed face: those of
//! the face it was cut from), and faces keep their winding. Original vertices keep their indices (new ones are appended), boundary loops gain
//! the midpoints of split boundary edges in order. Deterministic: splits are numbered in edge
//! order.

use super::Surface;
use glam::DVec3;
use std::collections::{BTreeMap, BTreeSet};

/// Options of the rim refinement. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct RefineOptions {
    /// Edges longer than this fraction of the bounding-box diagonal are split first (repeatedly,
    /// at midpoints), `None` to keep them. Default 1/40: a P1 map cannot follow the slit map
    /// across a face that spans much of the part. CAD meshes (fans of faces up to 0.7 of the
    /// diagonal long) folded in the log-polar strip and broke the spiral; sliver_mesh's 10 mm
    /// rows made a ring near the outer circle jump 2 mm.
    pub max_edge_fraction: Option<f64>,
    /// Every hole vertex ends with at least this many faces, as far as `max_rounds` allows.
    /// Default 6 (each face then opens by at most about 60° at a slit tip).
    pub min_hole_valence: usize,
    /// Rounds of link splitting; each round at most doubles a vertex's face count. Default 1:
    /// further rounds pile thin triangles against the rims of coarse CAD parts and fold more
    /// than they fix (featuretype, centroid pole: 0 folds after one round, 178 after two).
    pub max_rounds: usize,
    /// Split the interior edges of faces with all three corners on the boundary. Default true.
    pub split_ears: bool,
    /// After the long-edge splits, flip every edge between two coplanar faces that is not
    /// locally Delaunay (see [`flip_coplanar`]). Default true: CAD parts are flat regions
    /// tessellated as fans, and the splits leave needles whose images fold under any P1 map
    /// (featuretype: 226 folded faces at the centroid pole without).
    pub coplanar_flips: bool,
    /// Then refine every flat region until its triangles have no angle below this many degrees
    /// (Delaunay refinement, [`super::quality`]), `None` to skip. Default 25°. Needs
    /// `coplanar_flips`.
    pub flat_min_angle_deg: Option<f64>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            max_edge_fraction: Some(1.0 / 40.0),
            min_hole_valence: 6,
            max_rounds: 1,
            split_ears: true,
            coplanar_flips: true,
            flat_min_angle_deg: Some(20.0),
        }
    }
}

/// Long-edge splitting stops after this many rounds (each halves the longest edge: 2^-12 of
/// the diagonal is far below any sensible fraction).
const MAX_LONG_EDGE_ROUNDS: usize = 12;

/// The surface with its long edges split ([`RefineOptions::max_edge_fraction`]), every hole
/// vertex's fan refined and, with [`RefineOptions::split_ears`], its ears split (a clone when
/// nothing needs splitting). `loops[1..]` are the holes; the outer loop's vertices map onto a
/// circle and need no fan refinement.
pub fn refine_hole_rims(surface: &Surface, options: &RefineOptions) -> Surface {
    let mut s = surface.clone();
    if let Some(fraction) = options.max_edge_fraction {
        let (lo, hi) = super::weld::bounding_box(&s.positions);
        let max_len = fraction * (hi - lo).length();
        for _ in 0..MAX_LONG_EDGE_ROUNDS {
            let edges = long_edges(&s, max_len);
            if edges.is_empty() {
                break;
            }
            s = split_edges(&s, &edges);
        }
    }
    if options.coplanar_flips {
        s = flip_coplanar(&s);
        if let Some(angle) = options.flat_min_angle_deg {
            s = super::quality::refine_flat_regions(&s, angle);
        }
    }
    for _ in 0..options.max_rounds {
        let edges = link_edges_to_split(&s, options.min_hole_valence);
        if edges.is_empty() {
            break;
        }
        s = split_edges(&s, &edges);
    }
    if options.split_ears {
        let edges = ear_edges(&s);
        if !edges.is_empty() {
            s = split_edges(&s, &edges);
        }
    }
    s
}

/// The edges to split in one round of long-edge refinement, sorted: the longest edge of every
/// face whose longest edge exceeds `max_len`, closed so that every face with a split edge has
/// its longest edge split too. A face is then cut through its longest edge (bisected, or cut
/// in three or four), which keeps its angles away from zero (Rivara's longest-edge
/// bisection), where splitting every long edge makes needles of CAD fans. Known cost:
/// featuretype's map folds more after it (13 faces at the centroid pole without, 226 with, 243
/// with plain splits).
fn long_edges(s: &Surface, max_len: f64) -> Vec<Edge> {
    let len = |(a, b): Edge| s.positions[a as usize].distance(s.positions[b as usize]);
    let longest: Vec<Edge> = s
        .triangles
        .iter()
        .map(|t| {
            let edges = [0, 1, 2].map(|k| key(t[k], t[(k + 1) % 3]));
            // Ties broken by the vertex numbers, so the choice is deterministic.
            edges.into_iter().max_by(|&x, &y| len(x).total_cmp(&len(y)).then(x.cmp(&y))).unwrap_or_default()
        })
        .collect();
    let mut split: BTreeSet<Edge> = longest.iter().copied().filter(|&e| len(e) > max_len).collect();
    if split.is_empty() {
        return Vec::new();
    }
    loop {
        let before = split.len();
        for (t, &l) in s.triangles.iter().zip(&longest) {
            if !split.contains(&l) && (0..3).any(|k| split.contains(&key(t[k], t[(k + 1) % 3]))) {
                split.insert(l);
            }
        }
        if split.len() == before {
            return split.into_iter().collect();
        }
    }
}

/// The interior edges of the faces whose three corners are all on the boundary, sorted.
fn ear_edges(s: &Surface) -> Vec<Edge> {
    let mut on_boundary = vec![false; s.positions.len()];
    let mut boundary_edges = BTreeSet::new();
    for l in &s.loops {
        for (i, &v) in l.iter().enumerate() {
            on_boundary[v as usize] = true;
            boundary_edges.insert(key(v, l[(i + 1) % l.len()]));
        }
    }
    let mut edges: Vec<Edge> = Vec::new();
    for t in &s.triangles {
        if t.iter().all(|&v| on_boundary[v as usize]) {
            for k in 0..3 {
                let e = key(t[k], t[(k + 1) % 3]);
                if !boundary_edges.contains(&e) {
                    edges.push(e);
                }
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges
}

type Edge = (u32, u32);

fn key(a: u32, b: u32) -> Edge {
    (a.min(b), a.max(b))
}

/// The link edges of every hole vertex with fewer than `min_valence` faces, sorted.
fn link_edges_to_split(s: &Surface, min_valence: usize) -> Vec<Edge> {
    let n = s.positions.len();
    let mut on_hole = vec![false; n];
    for l in s.loops.iter().skip(1) {
        for &v in l {
            on_hole[v as usize] = true;
        }
    }
    let valence = face_counts(n, &s.triangles);
    let mut edges: Vec<Edge> = Vec::new();
    for t in &s.triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            if on_hole[v] && valence[v] < min_valence {
                edges.push(key(t[(k + 1) % 3], t[(k + 2) % 3]));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Number of faces around each vertex.
fn face_counts(n: usize, triangles: &[[u32; 3]]) -> Vec<usize> {
    let mut count = vec![0usize; n];
    for t in triangles {
        for &v in t {
            count[v as usize] += 1;
        }
    }
    count
}

/// Coplanarity tolerances of [`flip_coplanar`]: the two faces' unit normals agree to
/// 1 − cos ≤ `COPLANAR_COS`, and the far corner lies within `COPLANAR_REL` × the shared edge's
/// length of the other face's plane (CAD flats are coplanar to rounding).
const COPLANAR_COS: f64 = 1e-12;
const COPLANAR_REL: f64 = 1e-9;

/// Faces (a, b, c) and (b, a, d) lie in one plane, facing the same way (within
/// [`COPLANAR_COS`] and [`COPLANAR_REL`]).
pub(super) fn coplanar(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
    let n1 = (b - a).cross(c - a);
    let n2 = (a - b).cross(d - b);
    let (l1, l2) = (n1.length(), n2.length());
    l1 > 0.0
        && l2 > 0.0
        && n1.dot(n2) >= (1.0 - COPLANAR_COS) * l1 * l2
        && (d - a).dot(n1).abs() <= COPLANAR_REL * l1 * (b - a).length()
}

/// `s` with every edge between two coplanar faces flipped while it is not locally Delaunay
/// (the angles opposite it sum to more than π) and the flip keeps both faces' winding: the
/// Delaunay triangulation of each flat region of the part, on the same vertices. Exact — a flip
/// inside a plane changes no point of the surface — so positions, loops and vertex normals are
/// kept (the angle a flat region makes at a vertex does not change); face slots keep their
/// normal and curvature tensor (both faces of a flip lie in one plane).
pub fn flip_coplanar(s: &Surface) -> Surface {
    let p = |v: u32| s.positions[v as usize];
    let (triangles, flips) = crate::flip::lawson(&s.triangles, |a, b, c, d| {
        let (a, b, c, d) = (p(a), p(b), p(c), p(d));
        if !coplanar(a, b, c, d) {
            return false;
        }
        let cot = |o: DVec3, u: DVec3, v: DVec3| (u - o).dot(v - o) / (u - o).cross(v - o).length();
        let sum = cot(c, a, b) + cot(d, a, b);
        if sum.is_nan() || sum >= -1e-9 {
            return false;
        }
        // Both new faces wound like the old ones, with some area (the quad is strictly convex).
        let n1 = (b - a).cross(c - a);
        let l1 = n1.length();
        let floor = 1e-9 * l1;
        (a - c).cross(d - c).dot(n1) / l1 > floor && (b - d).cross(c - d).dot(n1) / l1 > floor
    });
    if flips == 0 {
        return s.clone();
    }
    let face_areas = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(p);
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    Surface { triangles, face_areas, corner_normals: Vec::new(), ..s.clone() }
}

/// Splits `edges` (sorted) at their midpoints with a conforming red–green subdivision.
fn split_edges(s: &Surface, edges: &[Edge]) -> Surface {
    let mut positions = s.positions.clone();
    let mut vertex_normals = s.vertex_normals.clone();
    let mut mid: BTreeMap<Edge, u32> = BTreeMap::new();
    for &(a, b) in edges {
        mid.insert((a, b), positions.len() as u32);
        positions.push(0.5 * (s.positions[a as usize] + s.positions[b as usize]));
        vertex_normals.push((s.vertex_normals[a as usize] + s.vertex_normals[b as usize]).normalize_or_zero());
    }
    let mut triangles = Vec::with_capacity(s.triangles.len() + 3 * edges.len());
    let mut parent = Vec::with_capacity(triangles.capacity());
    for (f, t) in s.triangles.iter().enumerate() {
        let m = [0, 1, 2].map(|k| mid.get(&key(t[k], t[(k + 1) % 3])).copied());
        for child in subdivide(*t, m, &positions) {
            triangles.push(child);
            parent.push(f);
        }
    }
    let loops = loops_through(&s.loops, &mid);
    let face_areas = triangles
        .iter()
        .map(|t: &[u32; 3]| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    Surface {
        face_normals: parent.iter().map(|&f| s.face_normals[f]).collect(),
        curvature: parent.iter().map(|&f| s.curvature[f]).collect(),
        face_areas,
        positions,
        triangles,
        loops,
        vertex_normals,
        corner_normals: Vec::new(),
    }
}

/// `loops` with the points their edges were split at (`split`: sorted edge ↦ its split point,
/// which may itself be split again) inserted in order.
pub(super) fn loops_through(loops: &[Vec<u32>], split: &BTreeMap<Edge, u32>) -> Vec<Vec<u32>> {
    let mut stack = Vec::new();
    loops
        .iter()
        .map(|l| {
            let mut out = Vec::with_capacity(l.len());
            for (i, &a) in l.iter().enumerate() {
                // Edge a → b: its points in order, a included, b not.
                stack.push((a, l[(i + 1) % l.len()]));
                while let Some((u, v)) = stack.pop() {
                    match split.get(&key(u, v)) {
                        Some(&m) => {
                            stack.push((m, v));
                            stack.push((u, m));
                        }
                        None => out.push(u),
                    }
                }
            }
            out
        })
        .collect()
}

/// The children of face `t` (corners `t[k]`, `m[k]` the midpoint of edge `t[k] → t[k+1]` when it
/// is split), wound like `t`.
fn subdivide(t: [u32; 3], m: [Option<u32>; 3], positions: &[DVec3]) -> Vec<[u32; 3]> {
    match m.iter().filter(|x| x.is_some()).count() {
        0 => vec![t],
        1 => {
            let k = m.iter().position(|x| x.is_some()).unwrap_or(0);
            let (a, b, c, x) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3], m[k].unwrap_or(0));
            vec![[a, x, c], [x, b, c]]
        }
        2 => {
            // The unsplit edge is c → a; the split ones are a → b (x) and b → c (y).
            let k = (m.iter().position(|x| x.is_none()).unwrap_or(0) + 1) % 3;
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (x, y) = (m[k].unwrap_or(0), m[(k + 1) % 3].unwrap_or(0));
            let p = |v: u32| positions[v as usize];
            // The quad a x y c is cut along its shorter diagonal.
            if p(a).distance_squared(p(y)) <= p(x).distance_squared(p(c)) {
                vec![[x, b, y], [a, x, y], [a, y, c]]
            } else {
                vec![[x, b, y], [a, x, c], [x, y, c]]
            }
        }
        _ => {
            let [a, b, c] = t;
            let [x, y, z] = m.map(|v| v.unwrap_or(0));
            vec![[a, x, z], [x, b, y], [z, y, c], [x, y, z]]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures;
    use crate::mesh::{self, MeshOptions};

    fn load(name: &str) -> Surface {
        let tri = fixtures::by_name(name).expect("a fixture");
        mesh::from_triangles(&tri, &MeshOptions::default()).expect("a valid fixture").surface
    }

    #[test]
    fn every_hole_vertex_reaches_the_valence_and_the_surface_is_unchanged() {
        let surface = load("plate_3_holes");
        let r = refine_hole_rims(&surface, &RefineOptions { max_rounds: 3, ..RefineOptions::default() });
        let val = face_counts(r.positions.len(), &r.triangles);
        for l in r.loops.iter().skip(1) {
            for &v in l {
                assert!(val[v as usize] >= 6, "hole vertex {v} has {} faces", val[v as usize]);
            }
        }
        let area = |s: &Surface| s.face_areas.iter().sum::<f64>();
        assert!((area(&r) - area(&surface)).abs() < 1e-9 * area(&surface));
        assert_eq!(r.euler_characteristic(), surface.euler_characteristic());
        assert_eq!(r.loops.len(), surface.loops.len());
        assert_eq!(&r.positions[..surface.positions.len()], &surface.positions[..]);
        // Winding kept: every child's geometric normal agrees with its stored (parent's) normal.
        for (t, n) in r.triangles.iter().zip(&r.face_normals) {
            let [a, b, c] = t.map(|v| r.positions[v as usize]);
            assert!((b - a).cross(c - a).normalize().dot(*n) > 1.0 - 1e-9);
        }
        // A manifold: every edge has one or two faces, boundary edges are exactly the loops'.
        let mut count: BTreeMap<Edge, usize> = BTreeMap::new();
        for t in &r.triangles {
            for k in 0..3 {
                *count.entry(key(t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(count.values().all(|&c| c <= 2));
        let boundary = count.values().filter(|&&c| c == 1).count();
        assert_eq!(boundary, r.loops.iter().map(Vec::len).sum::<usize>());
    }

    #[test]
    fn ears_are_split_so_every_face_has_a_corner_off_the_boundary() {
        // Issue 4 (panel_6_holes): the ear at a corner of the outer loop kept a 1.16 h scallop.
        // A 2 × 2 grid of squares cut along diagonals away from the centre: four corner ears.
        let positions = (0..9).map(|i| DVec3::new((i % 3) as f64, (i / 3) as f64, 0.0)).collect();
        let triangles = vec![[0, 1, 3], [1, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 7], [5, 8, 7]];
        let tri = mesh::TriMesh { positions, triangles };
        let surface = mesh::from_triangles(&tri, &MeshOptions::default()).expect("a valid grid").surface;
        let ears = |s: &Surface| {
            let mut on = vec![false; s.positions.len()];
            s.loops.iter().flatten().for_each(|&v| on[v as usize] = true);
            s.triangles.iter().filter(|t| t.iter().all(|&v| on[v as usize])).count()
        };
        assert!(ears(&surface) > 0, "the fixture has ears at its corners");
        let only_ears = RefineOptions { max_edge_fraction: None, ..RefineOptions::default() };
        let r = refine_hole_rims(&surface, &only_ears);
        assert_eq!(ears(&r), 0);
        let area = |s: &Surface| s.face_areas.iter().sum::<f64>();
        assert!((area(&r) - area(&surface)).abs() < 1e-9 * area(&surface));
        assert_eq!(r.euler_characteristic(), surface.euler_characteristic());
        let without = refine_hole_rims(&surface, &RefineOptions { split_ears: false, ..only_ears });
        assert!(ears(&without) > 0 && without.triangles.len() < r.triangles.len());
    }

    #[test]
    fn coplanar_faces_get_the_delaunay_diagonal_and_creased_ones_keep_theirs() {
        // A thin rhombus cut along its long diagonal (both opposite angles near 180°), flat and
        // then folded along that diagonal.
        for (lift, flips) in [(0.0, true), (0.05, false)] {
            let positions = vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(4.0, 0.0, 0.0),
                DVec3::new(2.0, 0.3, lift),
                DVec3::new(2.0, -0.3, lift),
            ];
            let tri = mesh::TriMesh { positions, triangles: vec![[0, 1, 2], [1, 0, 3]] };
            let s = mesh::from_triangles(&tri, &MeshOptions::default()).expect("a valid rhombus").surface;
            let r = flip_coplanar(&s);
            let has_long = r.triangles.iter().any(|t| t.contains(&0) && t.contains(&1));
            assert_eq!(has_long, !flips, "lift {lift}");
            assert_eq!(r.positions, s.positions);
            assert_eq!(r.loops, s.loops);
            for (t, n) in r.triangles.iter().zip(&r.face_normals) {
                let [a, b, c] = t.map(|v| r.positions[v as usize]);
                assert!((b - a).cross(c - a).normalize().dot(*n) > 1.0 - 1e-6, "lift {lift}: {t:?}");
            }
        }
    }

    #[test]
    fn a_surface_without_holes_is_left_alone() {
        // The rim refinement alone (the unit disk is flat: the flat-region passes are tested in
        // `quality`).
        let surface = load("unit_disk");
        let rims_only = RefineOptions { max_edge_fraction: None, coplanar_flips: false, ..RefineOptions::default() };
        let r = refine_hole_rims(&surface, &rims_only);
        assert_eq!(r.triangles, surface.triangles);
    }

    #[test]
    fn long_edges_are_split_until_none_is_longer_than_the_fraction() {
        // sliver_mesh: 10 mm rows on a 117 mm part, and 2 µm needles beside them.
        let surface = load("sliver_mesh");
        let (lo, hi) = crate::mesh::weld::bounding_box(&surface.positions);
        let max_len = (hi - lo).length() / 40.0;
        let longest = |s: &Surface| {
            s.triangles
                .iter()
                .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .map(|(a, b)| s.positions[a as usize].distance(s.positions[b as usize]))
                .fold(0.0, f64::max)
        };
        assert!(longest(&surface) > 3.0 * max_len);
        let r = refine_hole_rims(
            &surface,
            &RefineOptions { min_hole_valence: 0, split_ears: false, ..RefineOptions::default() },
        );
        assert!(longest(&r) <= max_len, "longest edge {} mm > {max_len} mm", longest(&r));
        let area = |s: &Surface| s.face_areas.iter().sum::<f64>();
        assert!((area(&r) - area(&surface)).abs() < 1e-9 * area(&surface));
        assert_eq!(r.euler_characteristic(), surface.euler_characteristic());
        assert_eq!(&r.positions[..surface.positions.len()], &surface.positions[..]);
        // The loops keep their vertices, in order, with the midpoints of split edges between.
        for (a, b) in surface.loops.iter().zip(&r.loops) {
            let kept: Vec<u32> = b.iter().copied().filter(|&v| (v as usize) < surface.positions.len()).collect();
            assert_eq!(&kept, a);
        }
    }
}
