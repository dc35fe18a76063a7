//! The verifier's surface: every face of the band meshed on a grid of its Coons domain, points
//! on the exact surface. Faces in a row share the number of t-intervals, faces in a column the
//! number of s-intervals, so the points of a shared side coincide (eq. 3) and the mesh welds.
//!
//! The grid spacing is √(8 ρ tol), ρ the smallest curvature radius found on a 9 × 9 probe of the
//! face (a chord of that length sags `tol` on a circle of radius ρ); the chordal error is then
//! measured at every facet's centre against the surface point of the same (s, t) and reported.

use super::compound::Compound;
use super::CoonsError;
use crate::mesh::{self, MeshOptions, Surface, TriMesh};
use glam::DVec3;

/// Most intervals per side of a face.
const MAX_INTERVALS: usize = 400;

/// Smallest radius of curvature on a 9 × 9 probe of face `p` (second differences along s and t).
fn min_radius(c: &Compound, i: usize, j: usize) -> f64 {
    let p = c.patch(i, j);
    let k = 8;
    let h = 1.0 / k as f64;
    let mut rho = f64::INFINITY;
    for a in 0..=k {
        for b in 0..=k {
            let (s, t) = (a as f64 * h, b as f64 * h);
            for dir in [DVec3::X, DVec3::Y] {
                let at = |d: f64| {
                    let (ss, tt) = ((s + dir.x * d).clamp(0.0, 1.0), (t + dir.y * d).clamp(0.0, 1.0));
                    p.raw(ss, tt).x
                };
                let d = 0.5 * h;
                let (x0, x1, x2) = (at(-d), at(0.0), at(d));
                let (l0, l1) = ((x1 - x0).length(), (x2 - x1).length());
                if l0 > 1e-9 && l1 > 1e-9 {
                    let second = ((x2 - x1) / l1 - (x1 - x0) / l0).length() * 2.0 / (l0 + l1);
                    if second > 1e-12 {
                        rho = rho.min(1.0 / second);
                    }
                }
            }
        }
    }
    rho
}

/// The grid mesh of the band to `tol` (see the module docs): the surface, its triangle count and
/// measured chordal error, mm.
#[allow(clippy::needless_range_loop)] // (i, j) index the grid and both count tables
pub fn grid_surface(c: &Compound, tol: f64) -> Result<(Surface, usize, f64), CoonsError> {
    let (m, n) = (c.around, c.across);
    let cell = |i: usize, j: usize| (8.0 * min_radius(c, i, j) * tol).sqrt();
    let intervals = |len: f64, cell: f64| ((len / cell).ceil() as usize).clamp(2, MAX_INTERVALS);
    let mut ns = vec![2usize; m];
    let mut nt = vec![2usize; n];
    for j in 0..n {
        for i in 0..m {
            let p = c.patch(i, j);
            let h = cell(i, j);
            ns[i] = ns[i].max(intervals(p.bottom.length_mm.max(p.top.length_mm), h));
            nt[j] = nt[j].max(intervals(p.left.length_mm.max(p.right.length_mm), h));
        }
    }
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut centres = Vec::new();
    for j in 0..n {
        for i in 0..m {
            let p = c.patch(i, j);
            let (a, b) = (ns[i], nt[j]);
            let base = positions.len() as u32;
            for q in 0..=b {
                for r in 0..=a {
                    positions.push(p.raw(r as f64 / a as f64, q as f64 / b as f64).x);
                }
            }
            let id = |r: usize, q: usize| base + (q * (a + 1) + r) as u32;
            for q in 0..b {
                for r in 0..a {
                    let (v00, v10, v01, v11) = (id(r, q), id(r + 1, q), id(r, q + 1), id(r + 1, q + 1));
                    for (t, centre) in [
                        ([v00, v10, v11], ((r as f64 + 2.0 / 3.0) / a as f64, (q as f64 + 1.0 / 3.0) / b as f64)),
                        ([v00, v11, v01], ((r as f64 + 1.0 / 3.0) / a as f64, (q as f64 + 2.0 / 3.0) / b as f64)),
                    ] {
                        triangles.push(t);
                        centres.push((i, j, centre));
                    }
                }
            }
            // Wind the face's triangles with its normal towards the tool.
            let e = p.raw(0.5, 0.5);
            let t = triangles[triangles.len() - a * b];
            let [x, y, z] = t.map(|k| positions[k as usize]);
            if (y - x).cross(z - x).dot(e.n) < 0.0 {
                let k0 = triangles.len() - 2 * a * b;
                for t in &mut triangles[k0..] {
                    t.swap(1, 2);
                }
            }
        }
    }
    let mut err: f64 = 0.0;
    for (t, &(i, j, (s, tt))) in triangles.iter().zip(&centres) {
        let g = t.iter().map(|&k| positions[k as usize]).sum::<DVec3>() / 3.0;
        err = err.max((c.patch(i, j).raw(s, tt).x - g).length());
    }
    let trimesh = TriMesh { positions, triangles };
    let out = mesh::from_triangles(&trimesh, &MeshOptions::default())?;
    // The mesh stage orients an open surface by the tool axis; a band round that axis may come
    // out reversed. Its triangles keep their order (one component): compare with ours.
    let mut agree = 0.0;
    for (k, t) in trimesh.triangles.iter().enumerate().take(out.surface.triangles.len()) {
        let [a, b, c] = t.map(|i| trimesh.positions[i as usize]);
        agree += (b - a).cross(c - a).dot(out.surface.face_normals[k]);
    }
    let surface = if agree < 0.0 { out.surface.flipped() } else { out.surface };
    Ok((surface, trimesh.triangles.len(), err))
}
