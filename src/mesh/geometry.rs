//! Differential geometry of the surface: face normals and areas, angle-weighted vertex normals and
//! the per-face curvature tensor of Rusinkiewicz, "Estimating curvatures and their derivatives on
//! triangle meshes" (3DPVT 2004; seed 000 ref. [39]).
//!
//! The tensor is the second fundamental form `II = dn/dp` fitted per face by least squares to the
//! change of vertex normal along the three edges. With normals towards the tool, `II` is positive
//! where the surface is convex seen from the tool (a sphere seen from outside: `1/r`), which is
//! the sign seed 000 eq. 13 uses for κ_n.

use super::topology::Component;
use super::{MeshError, Surface};
use glam::DVec3;

/// Second fundamental form of one face in the orthonormal face frame (`u`, `v`):
/// `II = [[e, f], [f, g]]`, 1/mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaceCurvature {
    pub u: DVec3,
    pub v: DVec3,
    pub e: f64,
    pub f: f64,
    pub g: f64,
}

impl FaceCurvature {
    /// Normal curvature `κ_n = tᵀ II t` along the tangent direction of `dir` (projected onto the
    /// face plane and normalised). Zero for a direction along the normal.
    pub fn normal_curvature(&self, dir: DVec3) -> f64 {
        let (a, b) = (dir.dot(self.u), dir.dot(self.v));
        let len2 = a * a + b * b;
        if len2 == 0.0 {
            return 0.0;
        }
        (self.e * a * a + 2.0 * self.f * a * b + self.g * b * b) / len2
    }

    /// Principal curvatures `(κ1, κ2)` with `κ1 ≥ κ2`, and the direction of `κ1`.
    pub fn principal(&self) -> (f64, f64, DVec3) {
        let mean = 0.5 * (self.e + self.g);
        let r = (0.25 * (self.e - self.g).powi(2) + self.f * self.f).sqrt();
        let angle = 0.5 * crate::num::atan2(2.0 * self.f, self.e - self.g);
        (mean + r, mean - r, self.u * crate::num::cos(angle) + self.v * crate::num::sin(angle))
    }
}

/// Builds the [`Surface`] of one oriented component.
pub fn build_surface(component: Component) -> Result<Surface, MeshError> {
    let Component { mesh, loops } = component;
    let (face_normals, face_areas): (Vec<DVec3>, Vec<f64>) = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            let n2 = (b - a).cross(c - a);
            (n2.normalize_or_zero(), 0.5 * n2.length())
        })
        .unzip();
    let vertex_normals = vertex_normals(&mesh.positions, &mesh.triangles, &face_normals);
    // The fit differentiates normals along edges, so their O(h²) error becomes O(h) in the
    // curvature: Max's weights, exact for vertices on a sphere, keep that error small.
    let fit_normals = max_vertex_normals(&mesh.positions, &mesh.triangles);
    let curvature = mesh
        .triangles
        .iter()
        .zip(&face_normals)
        .map(|(t, &n)| face_curvature(t.map(|v| mesh.positions[v as usize]), t.map(|v| fit_normals[v as usize]), n))
        .collect();
    Ok(Surface {
        positions: mesh.positions,
        triangles: mesh.triangles,
        loops,
        face_normals,
        face_areas,
        vertex_normals,
        corner_normals: Vec::new(),
        curvature,
    })
}

/// Angle-weighted vertex normals (Thürmer & Wüthrich): independent of how a region is split
/// into triangles.
pub fn vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]], face_normals: &[DVec3]) -> Vec<DVec3> {
    accumulate_corners(positions, triangles, |f, e1, e2| face_normals[f] * corner_angle(e1, e2))
}

/// The normals of the facets as they are: angle-weighted vertex normals recomputed from the
/// faces, and per-corner normals split at sharp creases (round each vertex the faces are grouped
/// across the edges whose two faces turn by at most `crease_deg`; each corner gets the
/// angle-weighted normal of its group, and a vertex whose faces form one group its vertex
/// normal).
///
/// Recomputed because refinement gives a new vertex the normal interpolated along the edge it
/// splits, which is right for a tessellated smooth surface but spreads a sharp edge's tilt far
/// across the flat facets of a CAD part; split because a normal averaged over a 45° edge tilts
/// the faces on both sides. Either way a ball riding such normals leans over the edge and the
/// exact-facet clearance lifts it sideways by about R·tan δ (countersunk_plate: 6.6 h of scallop
/// with the interpolated normals, 1.5 h with these).
pub fn crease_normals(s: &Surface, crease_deg: f64) -> (Vec<DVec3>, Vec<[DVec3; 3]>) {
    let nf = s.triangles.len();
    let cos_crease = crate::num::cos(crease_deg.to_radians());
    // Union-find over the corners (3·face + k), joined across every edge smoother than the crease.
    let mut parent: Vec<u32> = (0..3 * nf as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let corner_of = |f: u32, v: u32| 3 * f + s.triangles[f as usize].iter().position(|&x| x == v).unwrap_or(0) as u32;
    for (a, b, f, g) in interior_edges(&s.triangles) {
        if s.face_normals[f as usize].dot(s.face_normals[g as usize]) < cos_crease {
            continue;
        }
        for v in [a, b] {
            let (x, y) = (find(&mut parent, corner_of(f, v)), find(&mut parent, corner_of(g, v)));
            if x != y {
                parent[x.max(y) as usize] = x.min(y);
            }
        }
    }
    // Summed in the order `vertex_normals` sums: a vertex whose corners form one group gets its
    // vertex normal, bit for bit.
    let mut sums = vec![DVec3::ZERO; 3 * nf];
    for (f, t) in s.triangles.iter().enumerate() {
        for k in 0..3 {
            let p = s.positions[t[k] as usize];
            let e1 = s.positions[t[(k + 1) % 3] as usize] - p;
            let e2 = s.positions[t[(k + 2) % 3] as usize] - p;
            sums[find(&mut parent, (3 * f + k) as u32) as usize] += s.face_normals[f] * corner_angle(e1, e2);
        }
    }
    let fresh = vertex_normals(&s.positions, &s.triangles, &s.face_normals);
    let corners = (0..nf)
        .map(|f| {
            [0, 1, 2].map(|k| {
                let n = sums[find(&mut parent, (3 * f + k) as u32) as usize].normalize_or_zero();
                if n == DVec3::ZERO {
                    fresh[s.triangles[f][k] as usize]
                } else {
                    n
                }
            })
        })
        .collect();
    (fresh, corners)
}

/// The interior edges of a triangle mesh: (a, b, f, g) with a < b its vertices and f < g the two
/// faces on it, sorted by (a, b).
pub fn interior_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32, u32, u32)> {
    let mut edges: Vec<(u32, u32, u32)> = triangles
        .iter()
        .enumerate()
        .flat_map(|(f, t)| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]), f as u32)))
        .collect();
    crate::par::sort_unstable(&mut edges);
    edges
        .windows(2)
        .filter(|e| (e[0].0, e[0].1) == (e[1].0, e[1].1))
        .map(|e| (e[0].0, e[0].1, e[0].2, e[1].2))
        .collect()
}

/// The interior angle at a corner between its edges `e1` and `e2`: the weight of the face's
/// normal in an angle-weighted vertex normal.
fn corner_angle(e1: DVec3, e2: DVec3) -> f64 {
    crate::num::atan2(e1.cross(e2).length(), e1.dot(e2))
}

/// Vertex normals with the weights of Max, "Weights for computing vertex normals from facet
/// normals" (JGT 1999): `Σ (e1 × e2) / (|e1|² |e2|²)`, exact when the 1-ring lies on a sphere.
pub fn max_vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    accumulate_corners(positions, triangles, |_, e1, e2| e1.cross(e2) / (e1.length_squared() * e2.length_squared()))
}

/// Sums `corner(face, e1, e2)` over the corners of each vertex (e1, e2 the edges leaving it,
/// counter-clockwise) and normalises.
fn accumulate_corners(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    corner: impl Fn(usize, DVec3, DVec3) -> DVec3,
) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let p = positions[t[k] as usize];
            let e1 = positions[t[(k + 1) % 3] as usize] - p;
            let e2 = positions[t[(k + 2) % 3] as usize] - p;
            normals[t[k] as usize] += corner(f, e1, e2);
        }
    }
    normals.iter().map(|n| n.normalize_or_zero()).collect()
}

/// Least-squares fit of `II` to `II·(e·u, e·v) = (Δn·u, Δn·v)` over the three edges.
pub fn face_curvature(p: [DVec3; 3], n: [DVec3; 3], face_normal: DVec3) -> FaceCurvature {
    let u = (p[1] - p[0]).normalize_or_zero();
    let v = face_normal.cross(u);
    // Normal equations of the 6×3 system in the unknowns (e, f, g).
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let (e, dn) = (p[j] - p[i], n[j] - n[i]);
        let (eu, ev, nu, nv) = (e.dot(u), e.dot(v), dn.dot(u), dn.dot(v));
        // Row (eu, ev, 0) → nu and row (0, eu, ev) → nv.
        for (row, rhs) in [([eu, ev, 0.0], nu), ([0.0, eu, ev], nv)] {
            for a in 0..3 {
                for b in 0..3 {
                    m[a][b] += row[a] * row[b];
                }
                r[a] += row[a] * rhs;
            }
        }
    }
    let [e, f, g] = solve3(m, r).unwrap_or([0.0; 3]);
    FaceCurvature { u, v, e, f, g }
}

/// Cramer's rule for a 3×3 system; `None` when singular.
fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    let scale = m.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
    if d.abs() <= 1e-14 * scale.powi(3) {
        return None;
    }
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut mc = m;
        for row in 0..3 {
            mc[row][c] = r[row];
        }
        *o = det(mc) / d;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_curvature_of_a_known_tensor() {
        let c = FaceCurvature { u: DVec3::X, v: DVec3::Y, e: 2.0, f: 0.0, g: -1.0 };
        assert!((c.normal_curvature(DVec3::X) - 2.0).abs() < 1e-15);
        assert!((c.normal_curvature(DVec3::new(0.0, 3.0, 5.0)) + 1.0).abs() < 1e-15);
        assert!((c.normal_curvature(DVec3::new(1.0, 1.0, 0.0)) - 0.5).abs() < 1e-15);
        let (k1, k2, d1) = c.principal();
        assert!((k1 - 2.0).abs() < 1e-15 && (k2 + 1.0).abs() < 1e-15 && (d1.dot(DVec3::X).abs() - 1.0).abs() < 1e-12);
    }

    fn surface_of(mesh: &crate::mesh::TriMesh) -> Surface {
        crate::mesh::from_triangles(mesh, &crate::mesh::MeshOptions::default()).expect("mesh").surface
    }

    #[test]
    fn crease_normals_split_a_sharp_edge_and_nothing_else() {
        let s = surface_of(&crate::fixtures::countersunk_plate());
        let (fresh, corners) = crease_normals(&s, 30.0);
        // Nothing was refined: the recomputed vertex normals are the surface's, bit for bit.
        assert_eq!(fresh, s.vertex_normals);
        let flat = |n: DVec3| n.distance(DVec3::Z) < 1e-12;
        let mut split = 0;
        for (f, t) in s.triangles.iter().enumerate() {
            for k in 0..3 {
                let (p, n) = (s.positions[t[k] as usize], corners[f][k]);
                let on_edge = p.z == 10.0 && (p.truncate().length() - 8.0).abs() < 1e-9;
                if flat(s.face_normals[f]) {
                    // The flat rides +Z, up to the 45° edge.
                    assert!(flat(n), "{n}");
                } else if on_edge {
                    // The cone's side of the edge: its own two facets, sloping 45° (the average of
                    // two facets symmetric about the vertex).
                    assert!((n.z - 0.5f64.sqrt()).abs() < 1e-9 && n.truncate().dot(p.truncate()) < 0.0, "{n}");
                    split += 1;
                } else {
                    assert_eq!(n, s.vertex_normals[t[k] as usize]);
                }
            }
        }
        assert!(split >= 2 * 24, "{split}");
        // The vertex normal at the edge averages both sides.
        let e = s.positions.iter().position(|p| p.z == 10.0 && (p.truncate().length() - 8.0).abs() < 1e-9).unwrap();
        assert!(s.vertex_normals[e].z < 0.95);
    }

    #[test]
    fn crease_normals_recompute_what_refinement_interpolated() {
        // A flat square split corner to corner, whose diagonal's middle got the normal of a
        // tilted neighbour's vertex, as refinement interpolates one.
        let mesh = crate::mesh::TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::new(0.5, 0.5, 0.0)],
            triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
        };
        let mut s = surface_of(&mesh);
        s.vertex_normals[4] = DVec3::new(0.3, 0.0, 1.0).normalize();
        let (fresh, corners) = crease_normals(&s, 30.0);
        assert!(fresh.iter().chain(corners.iter().flatten()).all(|&n| n.distance(DVec3::Z) < 1e-12));
    }

    #[test]
    fn sphere_face_with_exact_normals() {
        let r = 5.0;
        let dirs = [DVec3::new(0.1, 0.0, 1.0), DVec3::new(0.0, 0.1, 1.0), DVec3::new(-0.07, -0.05, 1.0)];
        let n = dirs.map(|d| d.normalize());
        let p = n.map(|d| d * r);
        let fnorm = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let c = face_curvature(p, n, fnorm);
        let (k1, k2, _) = c.principal();
        assert!((k1 - 1.0 / r).abs() < 1e-3 / r && (k2 - 1.0 / r).abs() < 1e-3 / r, "{k1} {k2}");
    }
}
