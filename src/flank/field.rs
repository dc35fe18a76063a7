//! The guiding scalar field G of seed 002 §5: level sets along the machining direction.
//!
//! What it computes. The user gives one machining direction D (a 3D vector; the seed's option
//! (ii), "a single tangent vector at a central point"). On every face f it is projected onto
//! the face's plane, `t_f = D − (D·n_f) n_f`, and the wanted gradient of G is the unit tangent
//! vector perpendicular to it, `b_f = n_f × t̂_f`: G is constant along the direction (its level
//! sets, the guiding curves, run along D) and grows one millimetre per millimetre across it. G is
//! the piecewise-linear (P1) function minimising
//!
//! ```text
//! Σ_f w_f A_f |∇G_f − b_f|²,    w_f = |t_f|² / |D|²,
//! ```
//!
//! a sparse least-squares problem whose normal equations are a weighted cotan Laplacian, `K G =
//! div b` (K_ij = Σ_f w_f A_f ∇φ_i·∇φ_j), with one vertex pinned to 0 (the least-squares problem
//! fixes G only up to a constant). Its solution is the fairest field fitting b: where b is
//! integrable (a plane, a cylinder with D along its circles) G is exact (the P1 space holds
//! linear functions), elsewhere the mismatch is spread evenly. The weight w_f discounts faces
//! where D is nearly normal (the projection's direction is ill-defined there).
//!
//! The seed asks for "a fair function with a constant gradient perpendicular to the direction";
//! the constant-magnitude target is b_f's unit length, and the fairness is the least-squares
//! solution's (no extra smoothing term was needed).
//!
//! Preconditions: a connected surface from [`crate::mesh`] with unit face normals towards the
//! tool; a finite direction not along the normals everywhere. Errors:
//! [`FlankError::InvalidDirection`], [`FlankError::DirectionAlongNormals`],
//! [`FlankError::FieldSolve`].

use super::FlankError;
use crate::linalg::SparseCholesky;
use crate::mesh::Surface;
use glam::DVec3;

/// The guiding field: one value per vertex of the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct GuideField {
    pub values: Vec<f64>,
    pub min: f64,
    pub max: f64,
    /// RMS of |∇G − b| over the weighted area: 0 when the direction field is integrable.
    pub rms_misfit: f64,
}

/// Faces whose projected direction is shorter than this fraction of |D| get no weight.
const MIN_PROJECTED: f64 = 1e-6;

/// Solves for the guiding field of `direction` on `surface` (module docs).
pub fn guide_field(surface: &Surface, direction: DVec3) -> Result<GuideField, FlankError> {
    let len = direction.length();
    if !(len > 1e-12 && len.is_finite()) {
        return Err(FlankError::InvalidDirection { x: direction.x, y: direction.y, z: direction.z });
    }
    let d = direction / len;
    let nv = surface.positions.len();
    let mut triplets: Vec<(usize, usize, f64)> = Vec::with_capacity(surface.triangles.len() * 9);
    let mut rhs = vec![0.0; nv];
    let mut grads: Vec<Option<([DVec3; 3], DVec3, f64)>> = Vec::with_capacity(surface.triangles.len());
    let mut weighted_area = 0.0;
    for (f, t) in surface.triangles.iter().enumerate() {
        let n = surface.face_normals[f];
        let area = surface.face_areas[f];
        let proj = d - d.dot(n) * n;
        let w = proj.length_squared();
        if !(w > MIN_PROJECTED * MIN_PROJECTED && area > 0.0) {
            grads.push(None);
            continue;
        }
        let b = n.cross(proj / w.sqrt());
        let p = t.map(|v| surface.positions[v as usize]);
        // ∇φ_k = n × e_k / (2A), e_k the edge opposite corner k (counter-clockwise).
        let g = [0, 1, 2].map(|k| n.cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / (2.0 * area));
        let wa = w * area;
        weighted_area += wa;
        for a in 0..3 {
            rhs[t[a] as usize] += wa * g[a].dot(b);
            for c in 0..3 {
                triplets.push((t[a] as usize, t[c] as usize, wa * g[a].dot(g[c])));
            }
        }
        grads.push(Some((g, b, wa)));
    }
    if !(weighted_area > 1e-9 * surface.area()) {
        return Err(FlankError::DirectionAlongNormals { x: d.x, y: d.y, z: d.z });
    }
    // Pin the vertex of the lowest index that some weighted face touches: drop its row and column.
    let pinned = surface
        .triangles
        .iter()
        .zip(&grads)
        .filter(|(_, g)| g.is_some())
        .map(|(t, _)| t[0].min(t[1]).min(t[2]))
        .min()
        .expect("a weighted face exists") as usize;
    // Vertices on no weighted face have no equation: pin them too (to the mean of nothing, 0)
    // and fill them afterwards from their neighbours.
    let mut touched = vec![false; nv];
    for (t, g) in surface.triangles.iter().zip(&grads) {
        if g.is_some() {
            t.iter().for_each(|&v| touched[v as usize] = true);
        }
    }
    let mut unknown = vec![usize::MAX; nv];
    let mut n_unknowns = 0;
    for v in 0..nv {
        if v != pinned && touched[v] {
            unknown[v] = n_unknowns;
            n_unknowns += 1;
        }
    }
    let mut values = vec![0.0; nv];
    if n_unknowns > 0 {
        let reduced: Vec<(usize, usize, f64)> = triplets
            .iter()
            .filter(|&&(i, j, _)| unknown[i] != usize::MAX && unknown[j] != usize::MAX)
            .map(|&(i, j, v)| (unknown[i], unknown[j], v))
            .collect();
        let chol = SparseCholesky::new(n_unknowns, &reduced).map_err(FlankError::FieldSolve)?;
        let mut x = vec![0.0; n_unknowns];
        for v in 0..nv {
            if unknown[v] != usize::MAX {
                x[unknown[v]] = rhs[v];
            }
        }
        chol.solve_in_place(&mut x);
        for v in 0..nv {
            if unknown[v] != usize::MAX {
                values[v] = x[unknown[v]];
            }
        }
    }
    fill_untouched(surface, &touched, &mut values);
    let mut misfit = 0.0;
    for (t, g) in surface.triangles.iter().zip(&grads) {
        if let Some((g, b, wa)) = g {
            let grad = g[0] * values[t[0] as usize] + g[1] * values[t[1] as usize] + g[2] * values[t[2] as usize];
            misfit += wa * (grad - *b).length_squared();
        }
    }
    let (min, max) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    Ok(GuideField { values, min, max, rms_misfit: (misfit / weighted_area).sqrt() })
}

/// Vertices on no weighted face (the direction along their normals) take the mean of their
/// neighbours that have a value, sweeping until every reachable vertex has one.
fn fill_untouched(surface: &Surface, touched: &[bool], values: &mut [f64]) {
    let mut known = touched.to_vec();
    loop {
        let mut changed = false;
        let mut sum = vec![(0.0, 0usize); values.len()];
        for t in &surface.triangles {
            for a in 0..3 {
                for c in 0..3 {
                    let (va, vc) = (t[a] as usize, t[c] as usize);
                    if !known[va] && known[vc] {
                        sum[va].0 += values[vc];
                        sum[va].1 += 1;
                    }
                }
            }
        }
        for (v, &(s, n)) in sum.iter().enumerate() {
            if n > 0 {
                values[v] = s / n as f64;
                known[v] = true;
                changed = true;
            }
        }
        if !changed {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{from_triangles, MeshOptions};

    fn surface(mesh: &crate::mesh::TriMesh, axis: DVec3) -> Surface {
        from_triangles(mesh, &MeshOptions { tool_axis: axis, ..MeshOptions::default() }).unwrap().surface
    }

    #[test]
    fn plane_field_is_the_distance_across_the_direction() {
        let s = surface(&crate::fixtures::flank_plane(40.0, 30.0, 12, 9), DVec3::Z);
        let g = guide_field(&s, DVec3::new(2.0, 0.0, 0.0)).unwrap();
        // n × D = Z × X = Y: G = y + const, exactly up to rounding.
        let c = g.values[0] - s.positions[0].y;
        for (v, p) in g.values.iter().zip(&s.positions) {
            assert!((v - p.y - c).abs() < 1e-11, "{v} vs {}", p.y);
        }
        assert!(g.rms_misfit < 1e-10 && (g.max - g.min - 30.0).abs() < 1e-10);
    }

    #[test]
    fn cylinder_field_follows_the_axis_and_bad_directions_are_refused() {
        // A vertical cylinder wall, direction along its circles at θ = 0: G = ±z.
        let mesh = crate::fixtures::cylinder_patch(30.0, 60.0, 40.0, 24, 16, true);
        let s = surface(&mesh, DVec3::X);
        let g = guide_field(&s, DVec3::Y).unwrap();
        let c = g.values[0] - s.positions[0].z;
        for (v, p) in g.values.iter().zip(&s.positions) {
            assert!((v - p.z - c).abs() < 1e-9, "{v} vs {}", p.z);
        }
        assert!(matches!(guide_field(&s, DVec3::ZERO), Err(FlankError::InvalidDirection { .. })));
        assert!(matches!(guide_field(&s, DVec3::new(f64::NAN, 0.0, 1.0)), Err(FlankError::InvalidDirection { .. })));
        let flat = surface(&crate::fixtures::flank_plane(10.0, 10.0, 4, 4), DVec3::Z);
        assert!(matches!(guide_field(&flat, DVec3::Z), Err(FlankError::DirectionAlongNormals { .. })));
    }
}
