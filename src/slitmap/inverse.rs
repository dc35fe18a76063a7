//! Inverse slit map: point location among the image triangles (uniform grid) and barycentric
//! interpolation of per-vertex attributes (seed 000 §2.1, "the inverse mapping ω_S⁻¹").

use glam::DVec2;
use std::ops::{Add, Mul};
use std::sync::Arc;

/// Barycentric coordinates of `q` in triangle (a, b, c); NaN-free for non-degenerate triangles.
pub(crate) fn barycentric(a: DVec2, b: DVec2, c: DVec2, q: DVec2) -> [f64; 3] {
    let d = (b - a).perp_dot(c - a);
    let l1 = (q - a).perp_dot(c - a) / d;
    let l2 = (b - a).perp_dot(q - a) / d;
    [1.0 - l1 - l2, l1, l2]
}

/// Barycentric coordinates clamped to the triangle (negative ones set to 0, renormalised): the
/// nearest-face answer for a point just outside it.
pub(crate) fn clamp_barycentric(b: [f64; 3]) -> [f64; 3] {
    let b = b.map(|x| x.max(0.0));
    let s: f64 = b.iter().sum();
    if s > 0.0 {
        b.map(|x| x / s)
    } else {
        b
    }
}

/// A located point: face, its vertices and barycentric coordinates (summing to 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Location {
    pub face: usize,
    pub vertices: [u32; 3],
    pub bary: [f64; 3],
}

impl Location {
    /// Barycentric interpolation of any per-vertex attribute (3D position, normal, scalar, ...).
    /// Normals come out unnormalised.
    pub fn interpolate<T>(&self, values: &[T]) -> T
    where
        T: Copy + Mul<f64, Output = T> + Add<Output = T>,
    {
        values[self.vertices[0] as usize] * self.bary[0]
            + values[self.vertices[1] as usize] * self.bary[1]
            + values[self.vertices[2] as usize] * self.bary[2]
    }
}

/// Uniform grid over the image triangles' bounding box, about one cell per triangle; each cell
/// lists the triangles whose bounding box overlaps it (CSR layout). A query tests only the
/// triangles of one cell: O(1) on average for quasi-uniform images.
#[derive(Debug, Clone)]
pub struct InverseMap {
    w: Vec<DVec2>,
    triangles: Arc<Vec<[u32; 3]>>,
    origin: DVec2,
    inv_cell: f64,
    nx: usize,
    ny: usize,
    cell_start: Vec<u32>,
    cell_faces: Vec<u32>,
}

impl InverseMap {
    /// Builds the grid over the image `w` of `triangles`.
    pub fn new(w: &[DVec2], triangles: Arc<Vec<[u32; 3]>>) -> Self {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for p in w {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let ext = (hi - lo).max(DVec2::splat(1e-300));
        // About one cell per face; the grid is square-celled.
        let cells = triangles.len().max(1) as f64;
        let cell = (ext.x * ext.y / cells).sqrt().max(ext.max_element() / 4096.0);
        let nx = ((ext.x / cell).ceil() as usize).clamp(1, 4096);
        let ny = ((ext.y / cell).ceil() as usize).clamp(1, 4096);
        let inv_cell = 1.0 / cell;
        let cell_range = |t: &[u32; 3]| {
            let (a, b, c) = (w[t[0] as usize], w[t[1] as usize], w[t[2] as usize]);
            let (tl, th) = (a.min(b).min(c), a.max(b).max(c));
            let ix0 = (((tl.x - lo.x) * inv_cell).floor().max(0.0) as usize).min(nx - 1);
            let iy0 = (((tl.y - lo.y) * inv_cell).floor().max(0.0) as usize).min(ny - 1);
            let ix1 = (((th.x - lo.x) * inv_cell).floor().max(0.0) as usize).min(nx - 1);
            let iy1 = (((th.y - lo.y) * inv_cell).floor().max(0.0) as usize).min(ny - 1);
            (ix0, iy0, ix1, iy1)
        };
        let mut count = vec![0u32; nx * ny + 1];
        for t in triangles.iter() {
            let (ix0, iy0, ix1, iy1) = cell_range(t);
            for iy in iy0..=iy1 {
                for ix in ix0..=ix1 {
                    count[iy * nx + ix + 1] += 1;
                }
            }
        }
        for k in 0..nx * ny {
            count[k + 1] += count[k];
        }
        let mut fill = count.clone();
        let mut cell_faces = vec![0u32; count[nx * ny] as usize];
        for (f, t) in triangles.iter().enumerate() {
            let (ix0, iy0, ix1, iy1) = cell_range(t);
            for iy in iy0..=iy1 {
                for ix in ix0..=ix1 {
                    let c = iy * nx + ix;
                    cell_faces[fill[c] as usize] = f as u32;
                    fill[c] += 1;
                }
            }
        }
        Self { w: w.to_vec(), triangles, origin: lo, inv_cell, nx, ny, cell_start: count, cell_faces }
    }

    fn cell_of(&self, q: DVec2) -> Option<(usize, usize)> {
        let g = (q - self.origin) * self.inv_cell;
        if !(g.x >= 0.0 && g.y >= 0.0) {
            return None;
        }
        let (ix, iy) = (g.x.floor() as usize, g.y.floor() as usize);
        // Points on the far edge of the bounding box belong to the last cell.
        let ix = if ix == self.nx && g.x <= self.nx as f64 { ix - 1 } else { ix };
        let iy = if iy == self.ny && g.y <= self.ny as f64 { iy - 1 } else { iy };
        (ix < self.nx && iy < self.ny).then_some((ix, iy))
    }

    fn best_in_cell(&self, ix: usize, iy: usize, q: DVec2, best: &mut Option<(f64, Location)>) {
        let c = iy * self.nx + ix;
        for &f in &self.cell_faces[self.cell_start[c] as usize..self.cell_start[c + 1] as usize] {
            let t = self.triangles[f as usize];
            let bary = barycentric(self.w[t[0] as usize], self.w[t[1] as usize], self.w[t[2] as usize], q);
            let m = bary[0].min(bary[1]).min(bary[2]);
            if m.is_finite() && beats(best, m) {
                *best = Some((m, Location { face: f as usize, vertices: t, bary }));
            }
        }
    }

    /// The image triangle containing `w` (within a relative tolerance of 1e-10 in barycentric
    /// coordinates, so points on shared edges are found), or None when `w` is outside the image
    /// (beyond the outer polygon, inside the annulus hole, or exactly on a slit's gap).
    pub fn locate(&self, w: DVec2) -> Option<Location> {
        let (ix, iy) = self.cell_of(w)?;
        let mut best = None;
        self.best_in_cell(ix, iy, w, &mut best);
        match best {
            Some((m, loc)) if m >= -1e-10 => Some(loc),
            _ => None,
        }
    }

    /// The face containing `q` with its smallest barycentric coordinate at least `min_bary`
    /// (the largest such coordinate wins, the lowest face index on ties), among the faces of
    /// `q`'s cell.
    pub(crate) fn containing(&self, q: DVec2, min_bary: f64) -> Option<usize> {
        let (ix, iy) = self.cell_of(q)?;
        let mut best = None;
        self.best_in_cell(ix, iy, q, &mut best);
        match best {
            Some((m, loc)) if m >= min_bary => Some(loc.face),
            _ => None,
        }
    }

    /// Like [`InverseMap::locate`], but when `w` is outside every triangle returns the nearest
    /// triangle among those of the surrounding 3×3 cells, with barycentrics clamped to the
    /// triangle (useful for rings that touch the polygonal approximation of the unit circle).
    pub fn locate_nearest(&self, w: DVec2) -> Option<Location> {
        if let Some(l) = self.locate(w) {
            return Some(l);
        }
        let g = (w - self.origin) * self.inv_cell;
        let ix = (g.x.floor().max(0.0) as usize).min(self.nx - 1);
        let iy = (g.y.floor().max(0.0) as usize).min(self.ny - 1);
        let mut best = None;
        for jy in iy.saturating_sub(1)..=(iy + 1).min(self.ny - 1) {
            for jx in ix.saturating_sub(1)..=(ix + 1).min(self.nx - 1) {
                self.best_in_cell(jx, jy, w, &mut best);
            }
        }
        best.map(|(_, mut loc)| {
            loc.bary = clamp_barycentric(loc.bary);
            loc
        })
    }
}

/// True when `best` is empty or its score is below `m`.
fn beats(best: &Option<(f64, Location)>, m: f64) -> bool {
    match best {
        None => true,
        Some((s, _)) => *s < m,
    }
}
