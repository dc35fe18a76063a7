//! The m-grid and the rails (seed 002 eqs. 7–11).
//!
//! What it computes. From the base points g_{i,j} and normals n_{i,j} of the M + 1 guiding
//! curves ([`super::guide`]), the initial rails are (eq. 7) a_{i,j} = g_{i,j} + r₁n_{i,j} and
//! b_{i,j} = g_{i+1,j} + r₂n_{i+1,j}. The unknowns of the optimisation are the grid points
//! (eqs. 8–9)
//!
//! ```text
//! m_{i,j} = g_{i,j} + r̄ n_{i,j},   r̄ = (r₁ + r₂)/2     (every row, boundary rows included),
//! ```
//!
//! the mean of a_{i,j} and b_{i−1,j} on their common normal, and the rails are read back from
//! them (eq. 10):
//!
//! ```text
//! a_{i,j} = m_{i,j} − (Δr/2) n_{i,j},    b_{i,j} = m_{i+1,j} + (Δr/2) n_{i+1,j},
//! ```
//!
//! so strip i's top sphere (centre b_{i,j}, radius r₂) and strip i + 1's tip sphere (a_{i+1,j},
//! r₁) both touch the point m_{i+1,j} − r̄ n_{i+1,j} with the normal n_{i+1,j}: adjacent strips
//! share their boundary spheres (G⁰ by construction). Eq. 11 samples each axis at K points
//! y^k = (1 − s_k)a + s_k b, s_k = (k − 1)/(K − 1), with radii r^k = r(s_k).
//!
//! Invariant: rows are contiguous runs of j (ragged ends, Remark 1); strip i has a pose at j
//! exactly where rows i and i + 1 both have a point; the layout of the unknowns (row after row,
//! j ascending) is fixed by [`Grid::new`] and never changes.

use super::guide::Guides;
use super::tool::SphereFamily;
use glam::DVec3;

/// One row of grid points m_{i,j}, j = first_j … first_j + len − 1.
#[derive(Clone, Debug, PartialEq)]
pub struct GridRow {
    pub first_j: i64,
    /// Index of m_{i,first_j} among all grid points.
    pub offset: usize,
    pub len: usize,
}

/// One pose of the tool: strip `strip`, instant `j`, and the grid points it reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub strip: usize,
    pub j: i64,
    /// Grid point index of m_{strip, j} (gives a) and of m_{strip+1, j} (gives b).
    pub lower: usize,
    pub upper: usize,
}

/// The m-grid: rows, the points, the normals they use, the poses of every strip.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub rows: Vec<GridRow>,
    /// m_{i,j}, row after row.
    pub m: Vec<DVec3>,
    /// The unit normals n_{i,j} the rails are read with (refreshed by the optimiser).
    pub normals: Vec<DVec3>,
    /// Every pose, strip after strip, j ascending.
    pub poses: Vec<Pose>,
    /// `poses[strip_start[i]..strip_start[i + 1]]` are strip i's.
    pub strip_start: Vec<usize>,
    pub family: SphereFamily,
}

impl Grid {
    /// The initial grid of eqs. 7–9 from the guiding curves' base points.
    pub fn new(guides: &Guides, family: SphereFamily) -> Grid {
        let mean_r = 0.5 * (family.r1_mm + family.r2_mm);
        let (mut rows, mut m, mut normals) = (Vec::new(), Vec::new(), Vec::new());
        for row in &guides.rows {
            rows.push(GridRow { first_j: row.first_j, offset: m.len(), len: row.points.len() });
            for (&g, &n) in row.points.iter().zip(&row.normals) {
                m.push(g + mean_r * n);
                normals.push(n);
            }
        }
        let mut grid = Grid { rows, m, normals, poses: Vec::new(), strip_start: Vec::new(), family };
        for strip in 0..grid.rows.len().saturating_sub(1) {
            grid.strip_start.push(grid.poses.len());
            let (lo, hi) = (&grid.rows[strip], &grid.rows[strip + 1]);
            let first = lo.first_j.max(hi.first_j);
            let last = (lo.first_j + lo.len as i64).min(hi.first_j + hi.len as i64) - 1;
            for j in first..=last {
                let lower = lo.offset + (j - lo.first_j) as usize;
                let upper = hi.offset + (j - hi.first_j) as usize;
                grid.poses.push(Pose { strip, j, lower, upper });
            }
        }
        grid.strip_start.push(grid.poses.len());
        grid
    }

    /// Number of strips M.
    pub fn strips(&self) -> usize {
        self.rows.len().saturating_sub(1)
    }

    /// The poses of strip `i`.
    pub fn strip(&self, i: usize) -> &[Pose] {
        &self.poses[self.strip_start[i]..self.strip_start[i + 1]]
    }

    /// Grid point index of m_{i,j}, if the row has it.
    pub fn index(&self, i: usize, j: i64) -> Option<usize> {
        let r = self.rows.get(i)?;
        (j >= r.first_j && j < r.first_j + r.len as i64).then(|| r.offset + (j - r.first_j) as usize)
    }

    /// The rails of a pose (eq. 10) from grid points `m` and normals `normals`.
    #[inline]
    pub fn rails_of(&self, pose: &Pose, m: &[DVec3], normals: &[DVec3]) -> (DVec3, DVec3) {
        let h = 0.5 * self.family.delta_r_mm;
        (m[pose.lower] - h * normals[pose.lower], m[pose.upper] + h * normals[pose.upper])
    }

    /// The rails of a pose with the grid's own points and normals.
    pub fn rails(&self, pose: &Pose) -> (DVec3, DVec3) {
        self.rails_of(pose, &self.m, &self.normals)
    }

    /// s_k of eq. 11 for K samples.
    pub fn s_k(k: usize, samples: usize) -> f64 {
        if samples < 2 {
            0.5
        } else {
            k as f64 / (samples - 1) as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flank::guide::BaseRow;
    use crate::flank::tool::ConeTool;

    #[test]
    fn adjacent_strips_share_their_boundary_spheres() {
        let family = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 2.0, flute_length_mm: 10.0 }.spheres().unwrap();
        // Three rows on a bent surface, ragged: j ranges 0..5, -1..5, 1..4.
        let row = |first_j: i64, n: usize, y: f64| {
            let points: Vec<DVec3> = (0..n).map(|k| DVec3::new((first_j + k as i64) as f64, y, 0.1 * y * y)).collect();
            let normals = points.iter().map(|p| DVec3::new(0.0, -0.2 * p.y, 1.0).normalize()).collect();
            BaseRow { first_j, points, normals, tangents: vec![DVec3::X; n] }
        };
        let guides = Guides {
            levels: vec![0.0, 1.0, 2.0],
            curves: vec![],
            rows: vec![row(0, 6, 0.0), row(-1, 7, 9.0), row(1, 4, 18.0)],
        };
        let grid = Grid::new(&guides, family);
        assert_eq!(grid.strips(), 2);
        assert_eq!(grid.strip(0).iter().map(|p| p.j).collect::<Vec<_>>(), vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(grid.strip(1).iter().map(|p| p.j).collect::<Vec<_>>(), vec![1, 2, 3, 4]);
        for p1 in grid.strip(1) {
            let p0 = grid.strip(0).iter().find(|p| p.j == p1.j).unwrap();
            let (_, b0) = grid.rails(p0);
            let (a1, _) = grid.rails(p1);
            let n = grid.normals[p1.lower];
            // Both spheres touch the same point with the same normal.
            let t0 = b0 - family.r2_mm * n;
            let t1 = a1 - family.r1_mm * n;
            assert!(t0.distance(t1) < 1e-12);
            let base = guides.rows[1].points[(p1.j + 1) as usize];
            assert!(t0.distance(base) < 1e-12, "the shared point is the base point g");
        }
        // Eq. 7 is recovered: a = g + r1 n, b = g' + r2 n'.
        let p = grid.strip(0)[2];
        let (a, b) = grid.rails(&p);
        let (g0, g1) = (&guides.rows[0], &guides.rows[1]);
        assert!(a.distance(g0.points[2] + family.r1_mm * g0.normals[2]) < 1e-12);
        assert!(b.distance(g1.points[3] + family.r2_mm * g1.normals[3]) < 1e-12);
        assert_eq!(grid.index(2, 0), None);
        assert_eq!(grid.index(2, 1), Some(13));
    }
}
