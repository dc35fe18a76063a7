//! Delaunay refinement of the part's flat regions: Steiner points until no triangle of a flat
//! region has an angle below a bound (Ruppert 1995; Shewchuk, "Delaunay refinement algorithms
//! for triangular mesh generation", 2002).
//!
//! Why: CAD parts are flat regions tessellated as fans of needles, and holes a few hundredths of
//! a millimetre from the outer edge leave bridges no wider than that. A P1 map folds needles
//! whatever the pole, since their image's orientation is decided by the discretisation error
//! across their tiny height (featuretype folded 62 faces at the centroid pole after the
//! coplanar flips, every one a needle at a bridge or at a corner of its pocket). Ruppert's
//! refinement removes the needles and grades the triangles to the local feature size, so a
//! bridge gets triangles as small as its width and the rest of the part stays coarse.
//!
//! # What it does
//! A flat region (a "patch") is a maximal edge-connected set of at least two coplanar faces
//! (the tolerances of [`super::refine::coplanar`]; [`super::refine::flip_coplanar`] must have
//! run first, so each patch is a constrained Delaunay triangulation) that holds a needle (an
//! angle below [`NEEDLE_DEG`]) and covers at least [`MIN_REGION_FRACTION`] of the part. Its
//! constrained edges are the mesh boundary ("segments", which may be split at their midpoints)
//! and the edges it shares with other faces (kept as they are, so the faces beyond are untouched
//! and the mesh stays conforming). Then, as in Ruppert's algorithm, a triangle with an angle
//! below the bound gets its circumcentre inserted (edges flipped back to Delaunay inside the
//! patch), unless that point would encroach a segment (lie in its diametral circle) or lies
//! beyond one, which is split instead. Ruppert's other rule, splitting every segment a vertex
//! encroaches, is left out: only bad triangles drive the refinement, and on a curved part's
//! small patches that rule split without end. Angles between two constrained edges cannot be
//! improved and are left; so are triangles whose fix would need a point across an edge that may
//! not be split, or a triangle smaller than [`MIN_SIZE_REL`] of the part.
//!
//! # Invariants
//! Exact: every new vertex lies in its patch's plane (or at a boundary edge's midpoint), so the
//! piecewise-flat surface is the same point set. Original vertices keep their indices (new ones
//! are appended), loops gain the split points in order, faces keep their winding and normal,
//! and a face takes the curvature tensor of an original face of its region. Faces outside
//! flat regions are not touched. Deterministic: queues in a fixed order, hash maps for lookup
//! only. At most [`MAX_NEW_PER_FACE`] new vertices per face of a flat region.

use super::Surface;
use crate::flip::third;
use crate::hash::{edge_map, EdgeMap};
use glam::{DVec2, DVec3};
use std::collections::{BTreeMap, VecDeque};

/// No point is inserted for a triangle whose circumradius is below this fraction of the part's
/// bounding-box diagonal: Ruppert's algorithm needs no such floor on valid input, but rounding
/// does near input angles.
pub const MIN_SIZE_REL: f64 = 1e-6;
/// A flat region is refined only when one of its triangles has an angle below this (degrees):
/// a needle, which folds under a P1 map. Well-shaped tessellations (the fixtures, quad meshes
/// split into coplanar pairs) are left exactly as they are: refining their few triangles just
/// under the bound changed the planned paths without folding fewer faces.
pub const NEEDLE_DEG: f64 = 5.0;
/// A flat region is refined only when it covers at least this fraction of the part's area: a
/// face of the CAD model, not a few coplanar triangles of a tessellated curved surface
/// (wavy_mesh_with_hole has hundreds of those, with needles at its rim; splitting five of them
/// moved its optimal pole onto one where the spacing leaves 2.6 h at a slit tip, see issue 4).
pub const MIN_REGION_FRACTION: f64 = 0.01;
/// The budget of new vertices, per face of the flat regions (plus a constant): a bound on the
/// work whatever the input angles are.
pub const MAX_NEW_PER_FACE: usize = 8;

/// A flat region's plane: origin and orthonormal in-plane axes.
#[derive(Clone, Copy)]
struct Plane {
    o: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Plane {
    fn new(o: DVec3, n: DVec3) -> Self {
        let e1 = n.any_orthonormal_vector();
        Self { o, e1, e2: n.cross(e1) }
    }
    fn to_2d(self, p: DVec3) -> DVec2 {
        let d = p - self.o;
        DVec2::new(d.dot(self.e1), d.dot(self.e2))
    }
    fn to_3d(self, q: DVec2) -> DVec3 {
        self.o + self.e1 * q.x + self.e2 * q.y
    }
}

/// What a walk towards a point found.
enum Walk {
    Face(usize),
    /// The point lies beyond this constrained edge (a → b as in the face the walk stood in).
    Blocked(u32, u32),
    Lost,
}

struct Refiner {
    positions: Vec<DVec3>,
    vertex_normals: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    /// Patch of each face; `None` for faces in no flat region (never touched).
    patch: Vec<Option<u32>>,
    /// An original face of each face's flat region (its slot's, through splits and flips): where
    /// its normal and curvature tensor come from.
    origin: Vec<u32>,
    planes: Vec<Plane>,
    half: EdgeMap<usize>,
    /// Boundary edge (sorted) ↦ the vertex it was split at.
    split: BTreeMap<(u32, u32), u32>,
    min_sin: f64,
    min_size: f64,
}

/// `s` with every flat region refined (see the module docs); `s` itself when it has no flat
/// region with a triangle below `min_angle_deg`.
pub fn refine_flat_regions(s: &Surface, min_angle_deg: f64) -> Surface {
    let (mut patch, planes) = flat_patches(s);
    // Only faces of the CAD model with a needle: a well-shaped tessellation, or coplanar pairs
    // of a tessellated curved surface, plan as they are.
    let needle = NEEDLE_DEG.to_radians().sin();
    let total_area: f64 = s.face_areas.iter().sum();
    let mut has_needle = vec![false; planes.len()];
    let mut area = vec![0.0; planes.len()];
    for (f, t) in s.triangles.iter().enumerate() {
        if let Some(pa) = patch[f] {
            has_needle[pa as usize] |= min_sin(t.map(|v| s.positions[v as usize])) < needle;
            area[pa as usize] += s.face_areas[f];
        }
    }
    let refined: Vec<bool> =
        has_needle.iter().zip(&area).map(|(&n, &a)| n && a >= MIN_REGION_FRACTION * total_area).collect();
    for pa in patch.iter_mut() {
        if pa.is_some_and(|p| !refined[p as usize]) {
            *pa = None;
        }
    }
    if !refined.iter().any(|&n| n) {
        return s.clone();
    }
    let (lo, hi) = super::weld::bounding_box(&s.positions);
    let mut r = Refiner {
        positions: s.positions.clone(),
        vertex_normals: s.vertex_normals.clone(),
        tris: s.triangles.clone(),
        origin: (0..s.triangles.len() as u32).collect(),
        half: edge_map(3 * s.triangles.len()),
        split: BTreeMap::new(),
        min_sin: min_angle_deg.to_radians().sin(),
        min_size: MIN_SIZE_REL * (hi - lo).length(),
        patch,
        planes,
    };
    for (f, t) in r.tris.iter().enumerate() {
        for k in 0..3 {
            r.half.insert((t[k], t[(k + 1) % 3]), f);
        }
    }
    let flat_faces = r.patch.iter().filter(|p| p.is_some()).count();
    let budget = r.positions.len() + MAX_NEW_PER_FACE * flat_faces + 1000;
    let mut bad: VecDeque<usize> = (0..r.tris.len()).filter(|&f| r.bad_circumcentre(f).is_some()).collect();
    while r.positions.len() < budget {
        let Some(f) = bad.pop_front() else { break };
        let Some(c) = r.bad_circumcentre(f) else { continue };
        let touched = match r.walk(f, c) {
            Walk::Lost => continue,
            Walk::Blocked(a, b) => {
                if !r.is_segment(a, b) {
                    continue;
                }
                let t = r.split_segment(a, b);
                bad.push_back(f);
                t
            }
            Walk::Face(g) => {
                let Some(enc) = r.encroached_by(g, c) else { continue };
                if enc.is_empty() {
                    match r.insert_in_face(g, c) {
                        Some(t) => t,
                        None => continue,
                    }
                } else {
                    let mut t = Vec::new();
                    for (a, b) in enc {
                        if r.half.contains_key(&(a, b)) {
                            t.extend(r.split_segment(a, b));
                        }
                    }
                    bad.push_back(f);
                    t
                }
            }
        };
        r.queue_bad(touched, &mut bad);
    }
    if r.positions.len() == s.positions.len() && r.tris == s.triangles {
        return s.clone();
    }
    r.into_surface(s)
}

/// The flat regions of `s`: per face its patch (None for faces in no flat region of two or more
/// faces) and each patch's plane.
fn flat_patches(s: &Surface) -> (Vec<Option<u32>>, Vec<Plane>) {
    let mut half: EdgeMap<usize> = edge_map(3 * s.triangles.len());
    for (f, t) in s.triangles.iter().enumerate() {
        for k in 0..3 {
            half.insert((t[k], t[(k + 1) % 3]), f);
        }
    }
    let p = |v: u32| s.positions[v as usize];
    let mut patch: Vec<Option<u32>> = vec![None; s.triangles.len()];
    let mut planes = Vec::new();
    for seed in 0..s.triangles.len() {
        if patch[seed].is_some() {
            continue;
        }
        let id = planes.len() as u32;
        let mut members = vec![seed];
        patch[seed] = Some(id);
        let mut i = 0;
        while i < members.len() {
            let f = members[i];
            i += 1;
            let t = s.triangles[f];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let Some(&g) = half.get(&(b, a)) else { continue };
                if patch[g].is_none()
                    && super::refine::coplanar(p(a), p(b), p(t[(k + 2) % 3]), p(third(&s.triangles[g], a, b)))
                {
                    patch[g] = Some(id);
                    members.push(g);
                }
            }
        }
        if members.len() < 2 {
            patch[seed] = None;
            continue;
        }
        let t = s.triangles[seed];
        planes.push(Plane::new(p(t[0]), s.face_normals[seed]));
    }
    (patch, planes)
}

/// Sine of the smallest angle of a 3D triangle (opposite its shortest edge).
fn min_sin([a, b, c]: [DVec3; 3]) -> f64 {
    let l = [(c - b).length(), (a - c).length(), (b - a).length()];
    let k = (0..3).min_by(|&i, &j| l[i].total_cmp(&l[j])).unwrap_or(0);
    let area2 = (b - a).cross(c - a).length();
    area2 / (l[(k + 1) % 3] * l[(k + 2) % 3])
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

fn circumcentre(a: DVec2, b: DVec2, c: DVec2) -> DVec2 {
    let (u, v) = (b - a, c - a);
    let d = 2.0 * u.perp_dot(v);
    a + DVec2::new(
        v.y * u.length_squared() - u.y * v.length_squared(),
        u.x * v.length_squared() - v.x * u.length_squared(),
    ) / d
}

impl Refiner {
    fn p2(&self, v: u32, patch: u32) -> DVec2 {
        self.planes[patch as usize].to_2d(self.positions[v as usize])
    }

    fn corners(&self, f: usize) -> Option<(u32, [DVec2; 3])> {
        let pa = self.patch[f]?;
        Some((pa, self.tris[f].map(|v| self.p2(v, pa))))
    }

    /// A constrained edge: the mesh boundary, or the border of a flat region.
    fn is_constrained(&self, a: u32, b: u32) -> bool {
        match (self.half.get(&(a, b)), self.half.get(&(b, a))) {
            (Some(&f), Some(&g)) => self.patch[f].is_none() || self.patch[f] != self.patch[g],
            _ => true,
        }
    }

    /// A segment: a boundary edge of a flat region's face, which may be split.
    fn is_segment(&self, a: u32, b: u32) -> bool {
        !self.half.contains_key(&(b, a)) && self.half.get(&(a, b)).is_some_and(|&f| self.patch[f].is_some())
    }

    /// The circumcentre of face `f` if it has an angle below the bound that can be improved.
    fn bad_circumcentre(&self, f: usize) -> Option<DVec2> {
        let (_, z) = self.corners(f)?;
        let t = self.tris[f];
        let l2 = [0, 1, 2].map(|k| (z[(k + 2) % 3] - z[(k + 1) % 3]).length_squared());
        // The smallest angle is opposite the shortest edge; sin = 2A / (product of its sides).
        let k = (0..3).min_by(|&i, &j| l2[i].total_cmp(&l2[j])).unwrap_or(0);
        let area2 = orient(z[0], z[1], z[2]);
        let sin = area2 / (l2[(k + 1) % 3] * l2[(k + 2) % 3]).sqrt();
        // NaN (a degenerate face) is not bad: nothing can be done with it.
        if sin.is_nan() || sin >= self.min_sin || area2 <= 0.0 {
            return None;
        }
        // An angle between two constrained edges is the input's; nothing inside can open it.
        let (v, u, w) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        if self.is_constrained(v, u) && self.is_constrained(w, v) {
            return None;
        }
        let c = circumcentre(z[0], z[1], z[2]);
        let radius = (z[0] - c).length();
        (c.is_finite() && radius > self.min_size).then_some(c)
    }

    /// Walks from face `f` towards `q` (a point of f's plane) through unconstrained edges.
    fn walk(&self, mut f: usize, q: DVec2) -> Walk {
        let Some(pa) = self.patch[f] else { return Walk::Lost };
        for _ in 0..self.tris.len() {
            let t = self.tris[f];
            let z = t.map(|v| self.p2(v, pa));
            // The edge q lies most clearly beyond (deterministic; a walk cannot cycle in a
            // Delaunay triangulation).
            let mut worst = (0.0, 3);
            for k in 0..3 {
                let o = orient(z[k], z[(k + 1) % 3], q) / (z[(k + 1) % 3] - z[k]).length();
                if o < worst.0 {
                    worst = (o, k);
                }
            }
            if worst.1 == 3 {
                return Walk::Face(f);
            }
            let (a, b) = (t[worst.1], t[(worst.1 + 1) % 3]);
            if self.is_constrained(a, b) {
                return Walk::Blocked(a, b);
            }
            f = self.half[&(b, a)];
        }
        Walk::Lost
    }

    /// Segments a new vertex at `q` (in face `g`) would encroach: the constrained edges of its
    /// Delaunay cavity whose diametral circle holds q. None when one of them may not be split
    /// (the border with faces outside the flat region): no point goes there.
    fn encroached_by(&self, g: usize, q: DVec2) -> Option<Vec<(u32, u32)>> {
        let pa = self.patch[g]?;
        let mut out = Vec::new();
        let mut seen = vec![g];
        let mut i = 0;
        while i < seen.len() && seen.len() < 256 {
            let f = seen[i];
            i += 1;
            let t = self.tris[f];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if self.is_constrained(a, b) {
                    let (za, zb) = (self.p2(a, pa), self.p2(b, pa));
                    if (za - q).dot(zb - q) < 0.0 {
                        if !self.is_segment(a, b) {
                            return None;
                        }
                        out.push((a, b));
                    }
                    continue;
                }
                let h = self.half[&(b, a)];
                if !seen.contains(&h) && self.in_circumcircle(h, pa, q) {
                    seen.push(h);
                }
            }
        }
        Some(out)
    }

    fn in_circumcircle(&self, f: usize, pa: u32, q: DVec2) -> bool {
        let z = self.tris[f].map(|v| self.p2(v, pa));
        let c = circumcentre(z[0], z[1], z[2]);
        (q - c).length_squared() < (z[0] - c).length_squared()
    }

    fn set_face(&mut self, f: usize, t: [u32; 3]) {
        for k in 0..3 {
            self.half.insert((t[k], t[(k + 1) % 3]), f);
        }
        self.tris[f] = t;
    }

    fn new_face(&mut self, t: [u32; 3], like: usize) -> usize {
        let f = self.tris.len();
        self.tris.push(t);
        self.patch.push(self.patch[like]);
        self.origin.push(self.origin[like]);
        self.set_face(f, t);
        f
    }

    /// Inserts the point `q` of face f's plane into f (1 → 3) and flips back to Delaunay; the
    /// faces changed. None when q is too close to an edge of f to make three proper faces.
    fn insert_in_face(&mut self, f: usize, q: DVec2) -> Option<Vec<usize>> {
        let (pa, z) = self.corners(f)?;
        let area2 = orient(z[0], z[1], z[2]);
        for k in 0..3 {
            if orient(z[k], z[(k + 1) % 3], q) <= 1e-9 * area2 {
                return None;
            }
        }
        let [a, b, c] = self.tris[f];
        let v = self.positions.len() as u32;
        self.positions.push(self.planes[pa as usize].to_3d(q));
        self.vertex_normals.push(self.plane_normal(f));
        self.set_face(f, [a, b, v]);
        let g = self.new_face([b, c, v], f);
        let h = self.new_face([c, a, v], f);
        let mut touched = vec![f, g, h];
        self.legalise(&[(a, b), (b, c), (c, a)], &mut touched);
        Some(touched)
    }

    fn plane_normal(&self, f: usize) -> DVec3 {
        let p = &self.planes[self.patch[f].unwrap_or(0) as usize];
        p.e1.cross(p.e2)
    }

    /// Splits boundary edge a → b at its midpoint (its face cut in two) and flips back to
    /// Delaunay; the faces changed.
    fn split_segment(&mut self, a: u32, b: u32) -> Vec<usize> {
        let Some(&f) = self.half.get(&(a, b)) else { return Vec::new() };
        let c = third(&self.tris[f], a, b);
        let m = self.positions.len() as u32;
        self.positions.push(0.5 * (self.positions[a as usize] + self.positions[b as usize]));
        let n = (self.vertex_normals[a as usize] + self.vertex_normals[b as usize]).normalize_or_zero();
        self.vertex_normals.push(n);
        self.split.insert((a.min(b), a.max(b)), m);
        self.half.remove(&(a, b));
        self.set_face(f, [a, m, c]);
        let g = self.new_face([m, b, c], f);
        let mut touched = vec![f, g];
        self.legalise(&[(c, a), (b, c)], &mut touched);
        touched
    }

    /// Lawson flips inside the flat region from the given edges on.
    fn legalise(&mut self, edges: &[(u32, u32)], touched: &mut Vec<usize>) {
        let mut stack: Vec<(u32, u32)> = edges.to_vec();
        let mut flips = 0;
        while let Some((a, b)) = stack.pop() {
            if flips > 10_000 || self.is_constrained(a, b) {
                continue;
            }
            let (f1, f2) = (self.half[&(a, b)], self.half[&(b, a)]);
            let Some(pa) = self.patch[f1] else { continue };
            let c = third(&self.tris[f1], a, b);
            let d = third(&self.tris[f2], b, a);
            if c == d || self.half.contains_key(&(c, d)) {
                continue;
            }
            let [za, zb, zc, zd] = [a, b, c, d].map(|v| self.p2(v, pa));
            // d inside the circumcircle of a b c, and the quad convex.
            if !self.in_circumcircle(f1, pa, zd) || orient(zc, za, zd) <= 0.0 || orient(zd, zb, zc) <= 0.0 {
                continue;
            }
            self.half.remove(&(a, b));
            self.half.remove(&(b, a));
            self.set_face(f1, [c, a, d]);
            self.set_face(f2, [d, b, c]);
            flips += 1;
            touched.extend([f1, f2]);
            stack.extend([(a, d), (d, b), (b, c), (c, a)]);
        }
    }

    /// Queues the faces of `touched` that are still bad (each once, in slot order).
    fn queue_bad(&self, mut touched: Vec<usize>, bad: &mut VecDeque<usize>) {
        touched.sort_unstable();
        touched.dedup();
        bad.extend(touched.into_iter().filter(|&f| self.bad_circumcentre(f).is_some()));
    }

    fn into_surface(self, s: &Surface) -> Surface {
        let loops = super::refine::loops_through(&s.loops, &self.split);
        let face_areas = self
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.positions[v as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .collect();
        Surface {
            face_normals: self.origin.iter().map(|&f| s.face_normals[f as usize]).collect(),
            curvature: self.origin.iter().map(|&f| s.curvature[f as usize]).collect(),
            face_areas,
            positions: self.positions,
            triangles: self.tris,
            loops,
            vertex_normals: self.vertex_normals,
            corner_normals: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures;
    use crate::mesh::refine::flip_coplanar;
    use crate::mesh::{self, MeshOptions, TriMesh};
    use std::collections::BTreeMap;

    fn surface(tri: &TriMesh) -> Surface {
        mesh::from_triangles(tri, &MeshOptions::default()).expect("a valid mesh").surface
    }

    /// A CAD-style flat strip 10 × 1 mm: 21 points along the bottom, the two top corners, every
    /// bottom edge fanned to the top-left corner (needles of under 3° at the far end).
    fn fan_strip() -> TriMesh {
        let mut positions: Vec<DVec3> = (0..=20).map(|i| DVec3::new(0.5 * i as f64, 0.0, 0.0)).collect();
        positions.push(DVec3::new(0.0, 1.0, 0.0)); // 21
        positions.push(DVec3::new(10.0, 1.0, 0.0)); // 22
        let mut triangles: Vec<[u32; 3]> = (0..20).map(|i| [i, i + 1, 21]).collect();
        triangles.push([20, 22, 21]);
        TriMesh { positions, triangles }
    }

    fn min_angle_deg(s: &Surface, t: &[u32; 3]) -> f64 {
        min_sin(t.map(|v| s.positions[v as usize])).asin().to_degrees()
    }

    #[test]
    fn a_fan_of_needles_is_remeshed_to_the_angle_bound_on_the_same_surface() {
        let before = surface(&fan_strip());
        let worst_before = before.triangles.iter().map(|t| min_angle_deg(&before, t)).fold(90.0, f64::min);
        assert!(worst_before < 3.0, "the fixture has needles ({worst_before}°)");
        let r = refine_flat_regions(&flip_coplanar(&before), 20.0);
        // No angle of the strip is below 90° at its corners, so the bound holds everywhere.
        for t in &r.triangles {
            assert!(min_angle_deg(&r, t) >= 20.0 - 1e-9, "{t:?}: {}°", min_angle_deg(&r, t));
        }
        // The same surface: area, plane, winding, original vertices first and unmoved.
        let area = |s: &Surface| s.face_areas.iter().sum::<f64>();
        assert!((area(&r) - 10.0).abs() < 1e-12 && (area(&before) - 10.0).abs() < 1e-12);
        assert_eq!(&r.positions[..before.positions.len()], &before.positions[..]);
        assert!(r.positions.iter().all(|p| p.z == 0.0 && (0.0..=10.0).contains(&p.x) && (0.0..=1.0).contains(&p.y)));
        for (f, t) in r.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| r.positions[v as usize]);
            assert!((b - a).cross(c - a).dot(r.face_normals[f]) > 0.0, "face {f} is not counter-clockwise");
        }
        // A manifold whose boundary edges are exactly the loop's, in order.
        let mut count: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        for t in &r.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *count.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(count.values().all(|&c| c <= 2));
        let boundary: Vec<(u32, u32)> = count.iter().filter(|e| *e.1 == 1).map(|e| *e.0).collect();
        assert_eq!(r.loops.len(), 1);
        let l = &r.loops[0];
        assert_eq!(l.len(), boundary.len());
        for (i, &a) in l.iter().enumerate() {
            let b = l[(i + 1) % l.len()];
            assert!(boundary.binary_search(&(a.min(b), a.max(b))).is_ok(), "loop edge {a}–{b} is not a boundary edge");
        }
        assert_eq!(r.euler_characteristic(), before.euler_characteristic());
        // Deterministic.
        assert_eq!(refine_flat_regions(&flip_coplanar(&before), 20.0).triangles, r.triangles);
    }

    #[test]
    fn curved_and_well_shaped_surfaces_are_left_exactly_as_they_are() {
        // No coplanar faces at all, and a flat fixture without needles.
        for name in ["spherical_cap_hole", "plate_3_holes"] {
            let s = surface(&fixtures::by_name(name).expect("a fixture"));
            let r = refine_flat_regions(&s, 20.0);
            assert_eq!(r.triangles, s.triangles, "{name}");
            assert_eq!(r.positions, s.positions, "{name}");
        }
    }

    #[test]
    fn a_few_coplanar_needles_on_a_curved_part_are_not_a_flat_region() {
        // The fan strip (10 mm²) on the edge of a 10 000 mm² ramp whose 10 × 10 mm rows all turn
        // (so every coplanar patch of the part is below MIN_REGION_FRACTION): its needles stay.
        let mut tri = fan_strip();
        let (left, right) = (21u32, 22u32);
        let mut prev = (left, right);
        for j in 1..=100 {
            let (y, z) = (1.0 + 10.0 * j as f64, 0.02 * (j * j) as f64);
            let n = tri.positions.len() as u32;
            tri.positions.push(DVec3::new(0.0, y, z));
            tri.positions.push(DVec3::new(10.0, y, z));
            let (a, b, c, d) = (prev.0, prev.1, n + 1, n);
            tri.triangles.push([a, b, c]);
            tri.triangles.push([a, c, d]);
            prev = (n, n + 1);
        }
        let s = surface(&tri);
        assert_eq!(s.triangles.len(), tri.triangles.len(), "one surface");
        let r = refine_flat_regions(&flip_coplanar(&s), 20.0);
        assert_eq!(r.positions.len(), s.positions.len());
        // Alone, the same strip is refined (the first test).
        let strip = surface(&fan_strip());
        assert!(refine_flat_regions(&flip_coplanar(&strip), 20.0).positions.len() > strip.positions.len());
    }
}
