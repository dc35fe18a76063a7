//! Lifting points of the slit domain to the surface: the inverse map ω_SF⁻¹ of seed 000 §2.1
//! (point location, then barycentric interpolation of the 3D position and the vertex normals).
//!
//! Location is done in the log-polar strip (x = arg w, y = |w|, seed eq. 7), where the image of
//! every hole edge lies exactly on its slit's line y = R_j and the outer and inner circles are the
//! lines y = 1 and y = R_A. In the w plane those edges are chords that sag inside the circles, so a
//! ring running just below a slit could be located on the far side of the hole and jump across
//! it; in the strip the two sides of a slit never overlap. Near the pole of a disk map, where the
//! strip degenerates, location falls back to the w plane.

use crate::mesh::topology::vertex_faces;
use crate::mesh::Surface;
use crate::num;
use crate::slitmap::{barycentric, clamp_barycentric, Location, SlitMap};
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// A point of the surface found from its slit-domain image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lifted {
    /// The image point asked for.
    pub w: DVec2,
    /// The surface point (cutter contact), millimetres.
    pub p: DVec3,
    /// Unit surface normal there (interpolated vertex normals), towards the tool.
    pub n: DVec3,
    /// The face the point lies on.
    pub face: u32,
}

/// The inverse slit map of one pole, ready for many queries.
#[derive(Debug, Clone)]
pub struct Lift<'a> {
    surface: &'a Surface,
    /// Disk maps: the face containing the pole (its log-polar image is not a triangle) and the
    /// faces around it (their edges are strongly curved in the strip), with their corners in the
    /// w plane, where they are located instead.
    pole_faces: Vec<(usize, [DVec2; 3])>,
    /// Largest |w| of a pole face corner: a point farther out lies in none of them.
    pole_reach: f64,
    /// Log-polar image triangles (see module docs), indexed for point location.
    strip: StripIndex,
    /// Log-polar corners per face (as in `strip`), for the neighbourhood search.
    corners: Vec<[DVec2; 3]>,
    /// Faces around each vertex (CSR): `vertex_faces[vertex_start[v]..vertex_start[v + 1]]`.
    vertex_start: Vec<u32>,
    vertex_faces: Vec<u32>,
}

impl<'a> Lift<'a> {
    pub fn new(surface: &'a Surface, map: &SlitMap) -> Self {
        let per_face = map.log_polar_corners();
        let (vertex_start, vertex_faces) = vertex_faces(map.w.len(), map.triangles());
        Self {
            surface,
            pole_faces: Vec::new(),
            pole_reach: f64::NEG_INFINITY,
            strip: StripIndex::new(&per_face),
            corners: per_face,
            vertex_start,
            vertex_faces,
        }
        .with_pole_faces(map)
    }

    fn with_pole_faces(mut self, map: &SlitMap) -> Self {
        if let Some(f) = map.pole_face {
            let mut faces: Vec<usize> = vec![f];
            for &v in &map.triangles()[f] {
                let (a, b) = (self.vertex_start[v as usize] as usize, self.vertex_start[v as usize + 1] as usize);
                faces.extend(self.vertex_faces[a..b].iter().map(|&g| g as usize));
            }
            faces.sort_unstable();
            faces.dedup();
            self.pole_faces = faces.into_iter().map(|g| (g, map.triangles()[g].map(|v| map.w[v as usize]))).collect();
            self.pole_reach = self.pole_faces.iter().flat_map(|(_, c)| c.map(DVec2::length)).fold(0.0, f64::max);
        }
        self
    }

    /// The surface point whose image is `w`.
    pub fn at(&self, w: DVec2) -> Option<Lifted> {
        self.polar(w.length(), num::arg(w))
    }

    /// The surface point whose image is `rho · e^{iθ}` (the nearest image triangle when it falls
    /// just outside the image, e.g. by rounding on the unit circle).
    pub fn polar(&self, rho: f64, theta: f64) -> Option<Lifted> {
        let (s, c) = num::sin_cos(theta);
        let w = DVec2::new(rho * c, rho * s);
        if let Some(lifted) = self.in_pole_face(w, false) {
            return Some(lifted);
        }
        let x = (theta + PI).rem_euclid(TAU) - PI;
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        for shift in [0.0, TAU, -TAU] {
            self.strip.best(&self.corners, DVec2::new(x + shift, rho), &mut best);
        }
        let (face, bary) = match best {
            Some((m, f, b)) if m >= -1e-10 => (f, b),
            _ => {
                // Not in the strip's triangles: the pole face's region, or just outside the image
                // (rounding at |w| = 1 or R_A): then the nearest face, clamped.
                if let Some(lifted) = self.in_pole_face(w, true) {
                    return Some(lifted);
                }
                let (_, f, b) = best?;
                (f, clamp_barycentric(b))
            }
        };
        let loc = Location { face, vertices: self.surface.triangles[face], bary };
        Some(self.lifted(w, loc.face, self.surface.triangles[loc.face], loc.bary))
    }

    /// Like [`Lift::polar`], but found by walking from face `near` (the previous point's face)
    /// over faces that share a vertex, towards the face containing the point. Consecutive
    /// points of a curve then stay on neighbouring faces even where the P1 image folds over
    /// itself (slit tips): the lifted curve is continuous there instead of jumping to an
    /// overlapping face elsewhere. Falls back to [`Lift::polar`] when the walk gets stuck.
    pub fn polar_near(&self, rho: f64, theta: f64, near: u32) -> Option<Lifted> {
        if self.in_pole_face(DVec2::new(rho * num::cos(theta), rho * num::sin(theta)), false).is_none() {
            let x = (theta + PI).rem_euclid(TAU) - PI;
            let score = |f: usize| {
                let c = self.corners[f];
                // Unwrap the query into the face's frame.
                let qx = x + TAU * ((c[0].x - x) / TAU).round();
                let bary = barycentric(c[0], c[1], c[2], DVec2::new(qx, rho));
                let m = bary[0].min(bary[1]).min(bary[2]);
                (if m.is_finite() { m } else { f64::NEG_INFINITY }, bary)
            };
            let mut f = near as usize;
            let (mut m, mut bary) = score(f);
            for _ in 0..256 {
                if m >= -1e-9 {
                    let (s, c) = num::sin_cos(theta);
                    return Some(self.lifted(DVec2::new(rho * c, rho * s), f, self.surface.triangles[f], bary));
                }
                let mut next = None;
                for &v in &self.surface.triangles[f] {
                    let (a, b) = (self.vertex_start[v as usize] as usize, self.vertex_start[v as usize + 1] as usize);
                    for &g in &self.vertex_faces[a..b] {
                        let (mg, bg) = score(g as usize);
                        if mg > m && next.map_or(true, |(_, bm, _)| mg > bm) {
                            next = Some((g as usize, mg, bg));
                        }
                    }
                }
                match next {
                    Some((g, mg, bg)) => (f, m, bary) = (g, mg, bg),
                    None => break,
                }
            }
        }
        self.polar(rho, theta)
    }

    /// The point lifted through the pole face when it lies in it (or, with `clamp`, when the
    /// pole face is the only candidate left: barycentrics clamped).
    fn in_pole_face(&self, w: DVec2, clamp: bool) -> Option<Lifted> {
        if !clamp && !(w.length() <= self.pole_reach * (1.0 + 1e-9) + 1e-12) {
            return None; // the common case, most queries are far from the pole
        }
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        for &(f, c) in &self.pole_faces {
            let b = barycentric(c[0], c[1], c[2], w);
            let m = b[0].min(b[1]).min(b[2]);
            if m.is_finite() && best.map_or(true, |(bm, _, _)| m > bm) {
                best = Some((m, f, b));
            }
        }
        let (m, f, b) = best?;
        if m >= -1e-12 {
            return Some(self.lifted(w, f, self.surface.triangles[f], b));
        }
        if !clamp || m < -0.5 {
            return None;
        }
        Some(self.lifted(w, f, self.surface.triangles[f], clamp_barycentric(b)))
    }

    fn lifted(&self, w: DVec2, face: usize, vertices: [u32; 3], bary: [f64; 3]) -> Lifted {
        let s = self.surface;
        let at = |values: &[DVec3]| {
            values[vertices[0] as usize] * bary[0]
                + values[vertices[1] as usize] * bary[1]
                + values[vertices[2] as usize] * bary[2]
        };
        let p = at(&s.positions);
        let n = at(&s.vertex_normals).normalize_or_zero();
        let n = if n == DVec3::ZERO { s.face_normals[face] } else { n };
        Lifted { w, p, n, face: face as u32 }
    }
}

/// Point location in the log-polar strip. The faces crowd towards some radii (a ring band can
/// hold most of them), so the grid's rows are equal-count radius quantiles rather than equal
/// widths; columns are uniform in angle over (−2π, 2π) (per-face unwrapping may leave (−π, π]).
#[derive(Debug, Clone)]
struct StripIndex {
    /// Row boundaries in y (|w|), increasing; row k is [rows[k], rows[k + 1]).
    rows: Vec<f64>,
    nx: usize,
    cell_start: Vec<u32>,
    cell_faces: Vec<u32>,
}

impl StripIndex {
    const X0: f64 = -TAU;
    const XSPAN: f64 = 2.0 * TAU;

    fn new(corners: &[[DVec2; 3]]) -> Self {
        let f = corners.len().max(1);
        let ny = ((f as f64).sqrt().ceil() as usize).max(1);
        let nx = (f.div_ceil(ny) * 2).max(1);
        let mut ys: Vec<f64> = corners.iter().map(|c| (c[0].y + c[1].y + c[2].y) / 3.0).collect();
        ys.sort_by(f64::total_cmp);
        let mut rows: Vec<f64> = (0..=ny).map(|k| ys[((k * ys.len()) / ny).min(ys.len() - 1)]).collect();
        rows[0] = f64::NEG_INFINITY;
        rows[ny] = f64::INFINITY;
        rows.dedup();
        let ny = rows.len() - 1;
        let mut index = Self { rows, nx, cell_start: vec![0; nx * ny + 1], cell_faces: Vec::new() };
        let ranges: Vec<(usize, usize, usize, usize)> = corners.iter().map(|c| index.cell_range(c)).collect();
        for &(x0, x1, y0, y1) in &ranges {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    index.cell_start[y * nx + x + 1] += 1;
                }
            }
        }
        for k in 0..nx * ny {
            index.cell_start[k + 1] += index.cell_start[k];
        }
        let mut fill = index.cell_start.clone();
        index.cell_faces = vec![0; index.cell_start[nx * ny] as usize];
        for (face, &(x0, x1, y0, y1)) in ranges.iter().enumerate() {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * nx + x;
                    index.cell_faces[fill[c] as usize] = face as u32;
                    fill[c] += 1;
                }
            }
        }
        index
    }

    fn row(&self, y: f64) -> usize {
        self.rows.partition_point(|&r| r <= y).saturating_sub(1).min(self.rows.len() - 2)
    }

    fn col(&self, x: f64) -> usize {
        ((((x - Self::X0) / Self::XSPAN) * self.nx as f64).floor().max(0.0) as usize).min(self.nx - 1)
    }

    fn cell_range(&self, c: &[DVec2; 3]) -> (usize, usize, usize, usize) {
        let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        (self.col(lo.x), self.col(hi.x), self.row(lo.y), self.row(hi.y))
    }

    /// Updates `best` (largest minimum barycentric coordinate) with the faces of q's cell.
    fn best(&self, corners: &[[DVec2; 3]], q: DVec2, best: &mut Option<(f64, usize, [f64; 3])>) {
        if !(q.x >= Self::X0 && q.x <= Self::X0 + Self::XSPAN) {
            return;
        }
        let c = self.row(q.y) * self.nx + self.col(q.x);
        for &f in &self.cell_faces[self.cell_start[c] as usize..self.cell_start[c + 1] as usize] {
            let t = corners[f as usize];
            let bary = barycentric(t[0], t[1], t[2], q);
            let m = bary[0].min(bary[1]).min(bary[2]);
            if m.is_finite() && best.map_or(true, |(bm, _, _)| m > bm) {
                *best = Some((m, f as usize, bary));
            }
        }
    }
}
