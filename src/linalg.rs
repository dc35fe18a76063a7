//! Sparse linear algebra shared by the numeric stages (slit map, flattening).
//!
//! * [`SparseCholesky`]: a sparse symmetric positive-definite system factorised once with faer's
//!   sparse LLᵀ (AMD fill-reducing ordering, simplicial or supernodal chosen by faer), then solved
//!   many times. The symbolic analysis is kept so a matrix with the same pattern but new values
//!   is refactorised cheaply ([`SparseCholesky::refactor`]).
//! * [`cotan_weights`] and [`cotan_laplacian_triplets`]: the P1 finite-element (cotan) Laplacian
//!   of a triangle mesh, with optional merging of vertices into shared unknowns and elimination of
//!   Dirichlet vertices.
//!
//! Everything is deterministic: triplets are sorted before assembly, faer runs sequentially (no
//! rayon, so the same code builds for `wasm32-unknown-unknown`).

use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Side};
use glam::DVec3;

/// Errors of the sparse solvers. Each variant names what is at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinalgError {
    /// The numeric factorisation met a non-positive pivot: the matrix is not positive definite
    /// (e.g. a pure Neumann Laplacian without a fixed vertex, or a disconnected unknown).
    #[error("matrix is not positive definite (non-positive pivot at elimination step {pivot})")]
    NotPositiveDefinite {
        /// Elimination step (in faer's fill-reducing order) of the failing pivot.
        pivot: usize,
    },
    /// A triplet refers to a row or column outside the `n × n` matrix.
    #[error("triplet ({row}, {col}) is outside the {n}x{n} matrix")]
    BadIndex { row: usize, col: usize, n: usize },
    /// A triplet value is NaN or infinite.
    #[error("triplet ({row}, {col}) has a non-finite value")]
    NonFinite { row: usize, col: usize },
    /// [`SparseCholesky::refactor`] was given a sparsity pattern different from the original one.
    #[error("refactor: sparsity pattern differs from the factorised one ({detail})")]
    PatternMismatch { detail: String },
    /// The matrix is empty (n = 0).
    #[error("matrix has no rows")]
    Empty,
    /// Any other faer failure (allocation, ...).
    #[error("faer: {0}")]
    Faer(String),
}

/// Sparse symmetric positive-definite system with a reusable factorisation (faer sparse LLT,
/// AMD-type fill-reducing ordering): symbolic once, numeric once, then many solves.
#[derive(Debug, Clone)]
pub struct SparseCholesky {
    n: usize,
    /// Lower-triangle CSC pattern (rows sorted within each column), kept to assemble new values.
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicLlt<usize>,
    llt: Llt<usize, f64>,
}

/// Lower triangle (row ≥ col) of the triplets in CSC form, duplicates summed.
struct LowerCsc {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

fn assemble_lower(n: usize, triplets: &[(usize, usize, f64)]) -> Result<LowerCsc, LinalgError> {
    let mut lower: Vec<(usize, usize, f64)> = Vec::with_capacity(triplets.len() / 2 + n);
    for &(row, col, value) in triplets {
        if row >= n || col >= n {
            return Err(LinalgError::BadIndex { row, col, n });
        }
        if !value.is_finite() {
            return Err(LinalgError::NonFinite { row, col });
        }
        // Both triangles are given: the upper one is redundant for a symmetric matrix.
        if row >= col {
            lower.push((col, row, value));
        }
    }
    // Stable sort keeps the summation order of duplicates deterministic.
    lower.sort_by_key(|a| (a.0, a.1));
    let mut col_ptr = vec![0usize; n + 1];
    let mut row_idx = Vec::with_capacity(lower.len());
    let mut values: Vec<f64> = Vec::with_capacity(lower.len());
    let mut last: Option<(usize, usize)> = None;
    for (col, row, value) in lower {
        if last == Some((col, row)) {
            *values.last_mut().expect("a previous entry exists") += value;
        } else {
            row_idx.push(row);
            values.push(value);
            col_ptr[col + 1] += 1;
            last = Some((col, row));
        }
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c];
    }
    Ok(LowerCsc { col_ptr, row_idx, values })
}

fn map_llt_error(e: faer::sparse::linalg::LltError) -> LinalgError {
    match e {
        faer::sparse::linalg::LltError::Numeric(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot {
            index,
        }) => LinalgError::NotPositiveDefinite { pivot: index },
        faer::sparse::linalg::LltError::Generic(g) => LinalgError::Faer(format!("{g:?}")),
    }
}

impl SparseCholesky {
    /// `triplets` (row, col, value) of the full symmetric matrix (both triangles given; duplicates
    /// summed). Only the lower triangle is read: symmetry is the caller's promise.
    pub fn new(n: usize, triplets: &[(usize, usize, f64)]) -> Result<Self, LinalgError> {
        if n == 0 {
            return Err(LinalgError::Empty);
        }
        let csc = assemble_lower(n, triplets)?;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &csc.col_ptr, None, &csc.row_idx);
        let symbolic = SymbolicLlt::try_new(sym, Side::Lower).map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
        let mat = SparseColMatRef::new(sym, &csc.values);
        let llt = Llt::try_new_with_symbolic(symbolic.clone(), mat, Side::Lower).map_err(map_llt_error)?;
        Ok(Self { n, col_ptr: csc.col_ptr, row_idx: csc.row_idx, symbolic, llt })
    }

    /// New numeric values with the same sparsity pattern (reuses the symbolic analysis).
    /// On error the previous factorisation is kept.
    pub fn refactor(&mut self, triplets: &[(usize, usize, f64)]) -> Result<(), LinalgError> {
        let csc = assemble_lower(self.n, triplets)?;
        if csc.col_ptr != self.col_ptr || csc.row_idx != self.row_idx {
            return Err(LinalgError::PatternMismatch {
                detail: format!("{} stored lower-triangle entries, {} given", self.row_idx.len(), csc.row_idx.len()),
            });
        }
        let sym = SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx);
        let mat = SparseColMatRef::new(sym, &csc.values);
        self.llt = Llt::try_new_with_symbolic(self.symbolic.clone(), mat, Side::Lower).map_err(map_llt_error)?;
        Ok(())
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored lower-triangle entries of the assembled matrix (not of the factor).
    pub fn nnz_lower(&self) -> usize {
        self.row_idx.len()
    }

    /// Solves A x = rhs, overwriting `rhs` with x.
    ///
    /// # Panics
    /// If `rhs.len() != self.n()` (a programming error, not a data error).
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        assert_eq!(rhs.len(), self.n, "right-hand side length must equal n");
        let m = MatMut::from_column_major_slice_mut(rhs, self.n, 1);
        self.llt.solve_in_place_with_conj(Conj::No, m);
    }

    /// Solves for several right-hand sides at once (one blocked back-substitution).
    ///
    /// # Panics
    /// If a column's length differs from `self.n()`.
    pub fn solve_many_in_place(&self, rhs_columns: &mut [Vec<f64>]) {
        let k = rhs_columns.len();
        if k == 0 {
            return;
        }
        let mut buf = Vec::with_capacity(self.n * k);
        for c in rhs_columns.iter() {
            assert_eq!(c.len(), self.n, "right-hand side length must equal n");
            buf.extend_from_slice(c);
        }
        let m = MatMut::from_column_major_slice_mut(&mut buf, self.n, k);
        self.llt.solve_in_place_with_conj(Conj::No, m);
        for (j, c) in rhs_columns.iter_mut().enumerate() {
            c.copy_from_slice(&buf[j * self.n..(j + 1) * self.n]);
        }
    }
}

/// Cotan weights: for each interior/boundary edge (i, j) with i < j, w_ij = ½ Σ cot of the
/// opposite angles (one angle for a boundary edge, two for an interior one). Returned sorted by
/// (i, j) (deterministic).
///
/// A degenerate triangle (zero area) gives a non-finite weight: callers check for degenerate
/// faces first; [`SparseCholesky::new`] reports non-finite values as [`LinalgError::NonFinite`].
pub fn cotan_weights(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<(u32, u32, f64)> {
    let mut half: Vec<(u32, u32, f64)> = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            let (a, i, j) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let pa = positions[a as usize];
            let u = positions[i as usize] - pa;
            let v = positions[j as usize] - pa;
            let cot = u.dot(v) / u.cross(v).length();
            half.push((i.min(j), i.max(j), 0.5 * cot));
        }
    }
    merge_sorted(half)
}

/// Same as [`cotan_weights`] for planar (2D) positions (the cotangent uses the unsigned area).
pub fn cotan_weights_2d(positions: &[glam::DVec2], triangles: &[[u32; 3]]) -> Vec<(u32, u32, f64)> {
    let lifted: Vec<DVec3> = positions.iter().map(|p| p.extend(0.0)).collect();
    cotan_weights(&lifted, triangles)
}

fn merge_sorted(mut half: Vec<(u32, u32, f64)>) -> Vec<(u32, u32, f64)> {
    // Stable sort: the two half-weights of an interior edge are summed in face order.
    half.sort_by_key(|a| (a.0, a.1));
    let mut out: Vec<(u32, u32, f64)> = Vec::with_capacity(half.len() / 2 + 16);
    for (i, j, w) in half {
        match out.last_mut() {
            Some(last) if last.0 == i && last.1 == j => last.2 += w,
            _ => out.push((i, j, w)),
        }
    }
    out
}

/// Triplets of the positive semi-definite cotan Laplacian L (L_ii = Σ_j w_ij, L_ij = −w_ij),
/// both triangles, from the edge weights of [`cotan_weights`].
///
/// With `merge = None` the unknowns are the vertices. With `merge = Some(m)`, `m[v]` is the
/// unknown index of vertex v, or `None` when v is eliminated (Dirichlet): the result is then
/// PᵀLP restricted to the unknowns, where P maps unknowns to vertices. Edges inside one merged
/// group drop out (they add nothing to PᵀLP); an edge from an unknown to an eliminated vertex
/// keeps only its diagonal term (its off-diagonal part belongs to the right-hand side). Summing
/// the rows of merged vertices is what makes the merged row a zero-total-flux condition.
pub fn cotan_laplacian_triplets(
    weights: &[(u32, u32, f64)],
    merge: Option<&[Option<usize>]>,
) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::with_capacity(weights.len() * 4);
    for &(i, j, w) in weights {
        let (a, b) = match merge {
            None => (Some(i as usize), Some(j as usize)),
            Some(m) => (m[i as usize], m[j as usize]),
        };
        match (a, b) {
            (Some(a), Some(b)) if a != b => {
                out.push((a, a, w));
                out.push((b, b, w));
                out.push((a, b, -w));
                out.push((b, a, -w));
            }
            (Some(_), Some(_)) => {}
            (Some(a), None) | (None, Some(a)) => out.push((a, a, w)),
            (None, None) => {}
        }
    }
    out
}

#[cfg(test)]
// Dense reference code reads best with explicit indices.
#[allow(clippy::needless_range_loop, clippy::type_complexity)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// Small deterministic generator (SplitMix64) so the tests need no rand crate.
    struct SplitMix(u64);
    impl SplitMix {
        fn next_f64(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Dense Gaussian elimination with partial pivoting (the reference).
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n).max_by(|&x, &y| a[x][k].abs().total_cmp(&a[y][k].abs())).unwrap();
            a.swap(k, p);
            b.swap(k, p);
            for r in k + 1..n {
                let f = a[r][k] / a[k][k];
                for c in k..n {
                    a[r][c] -= f * a[k][c];
                }
                b[r] -= f * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|c| a[k][c] * x[c]).sum();
            x[k] = (b[k] - s) / a[k][k];
        }
        x
    }

    /// Random sparse SPD matrix: random symmetric off-diagonals, diagonally dominant. Triplets
    /// list both triangles and split some entries in two to exercise duplicate summing.
    fn random_spd(n: usize, rng: &mut SplitMix) -> (Vec<Vec<f64>>, Vec<(usize, usize, f64)>) {
        let mut dense = vec![vec![0.0; n]; n];
        let mut trip = Vec::new();
        for i in 0..n {
            for j in 0..i {
                if rng.next_f64() < 0.3 {
                    let v = rng.next_f64() * 2.0 - 1.0;
                    dense[i][j] = v;
                    dense[j][i] = v;
                    trip.push((i, j, 0.5 * v));
                    trip.push((i, j, 0.5 * v));
                    trip.push((j, i, v));
                }
            }
        }
        for i in 0..n {
            let s: f64 = dense[i].iter().map(|v| v.abs()).sum();
            let d = s + 0.5 + rng.next_f64();
            dense[i][i] = d;
            trip.push((i, i, d));
        }
        (dense, trip)
    }

    #[test]
    fn cholesky_matches_dense_solve() {
        let mut rng = SplitMix(42);
        for &n in &[1usize, 2, 5, 17, 60] {
            let (dense, trip) = random_spd(n, &mut rng);
            let chol = SparseCholesky::new(n, &trip).unwrap();
            assert_eq!(chol.n(), n);
            let b: Vec<f64> = (0..n).map(|_| rng.next_f64() - 0.5).collect();
            let x_ref = dense_solve(dense.clone(), b.clone());
            let mut x = b.clone();
            chol.solve_in_place(&mut x);
            for (u, v) in x.iter().zip(&x_ref) {
                assert!((u - v).abs() < 1e-12, "n={n}: {u} vs {v}");
            }
            // Several right-hand sides at once give the same answers.
            let mut cols = vec![b.clone(), b.iter().map(|v| 2.0 * v).collect()];
            chol.solve_many_in_place(&mut cols);
            for k in 0..n {
                assert!((cols[0][k] - x[k]).abs() < 1e-14);
                assert!((cols[1][k] - 2.0 * x[k]).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn refactor_reuses_pattern() {
        let mut rng = SplitMix(7);
        let n = 30;
        let (dense, trip) = random_spd(n, &mut rng);
        let mut chol = SparseCholesky::new(n, &trip).unwrap();
        // Same pattern, diagonal shifted by 3.
        let trip2: Vec<_> = trip.iter().map(|&(r, c, v)| (r, c, if r == c { v + 3.0 } else { v })).collect();
        chol.refactor(&trip2).unwrap();
        let mut dense2 = dense.clone();
        for (i, row) in dense2.iter_mut().enumerate() {
            row[i] += 3.0;
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let x_ref = dense_solve(dense2, b.clone());
        let mut x = b;
        chol.solve_in_place(&mut x);
        for (u, v) in x.iter().zip(&x_ref) {
            assert!((u - v).abs() < 1e-12);
        }
        // A different pattern is refused.
        let mut trip3 = trip2.clone();
        trip3.push((n - 1, 0, 1e-3));
        trip3.push((0, n - 1, 1e-3));
        let had_entry = trip2.iter().any(|&(r, c, _)| r == n - 1 && c == 0);
        if !had_entry {
            assert!(matches!(chol.refactor(&trip3), Err(LinalgError::PatternMismatch { .. })));
        }
    }

    #[test]
    fn typed_errors() {
        assert_eq!(SparseCholesky::new(2, &[(0, 2, 1.0)]).unwrap_err(), LinalgError::BadIndex { row: 0, col: 2, n: 2 });
        assert_eq!(SparseCholesky::new(2, &[(1, 1, f64::NAN)]).unwrap_err(), LinalgError::NonFinite { row: 1, col: 1 });
        // Singular Neumann Laplacian of one edge: not positive definite.
        let l = cotan_laplacian_triplets(&[(0, 1, 1.0)], None);
        assert!(matches!(SparseCholesky::new(2, &l).unwrap_err(), LinalgError::NotPositiveDefinite { .. }));
        let indefinite = [(0, 0, 1.0), (1, 1, -1.0)];
        assert!(matches!(SparseCholesky::new(2, &indefinite).unwrap_err(), LinalgError::NotPositiveDefinite { .. }));
        assert_eq!(SparseCholesky::new(0, &[]).unwrap_err(), LinalgError::Empty);
    }

    /// Regular grid of squares split along one diagonal: the cotan Laplacian is the 5-point
    /// stencil (axis edges weight 1 inside, ½ on the boundary; diagonals weight 0).
    #[test]
    fn cotan_weights_of_grid_give_five_point_stencil() {
        let (nx, ny) = (5usize, 4usize);
        let h = 0.37;
        let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let mut pos = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                pos.push(DVec3::new(i as f64 * h, j as f64 * h, 0.0));
            }
        }
        let mut tri = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                tri.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tri.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let w = cotan_weights(&pos, &tri);
        assert!(w.windows(2).all(|p| (p[0].0, p[0].1) < (p[1].0, p[1].1)));
        for &(a, b, wt) in &w {
            let (ia, ja) = (a as usize % (nx + 1), a as usize / (nx + 1));
            let (ib, jb) = (b as usize % (nx + 1), b as usize / (nx + 1));
            let horizontal = ja == jb;
            let vertical = ia == ib;
            let expected = if horizontal {
                if ja == 0 || ja == ny {
                    0.5
                } else {
                    1.0
                }
            } else if vertical {
                if ia == 0 || ia == nx {
                    0.5
                } else {
                    1.0
                }
            } else {
                0.0
            };
            assert!((wt - expected).abs() < 1e-14, "edge {a}-{b}: {wt}");
        }
        // Interior row of L: 4 on the diagonal, −1 to the four axis neighbours.
        let l = cotan_laplacian_triplets(&w, None);
        let centre = id(2, 2) as usize;
        let mut row = std::collections::BTreeMap::new();
        for &(r, c, v) in &l {
            if r == centre {
                *row.entry(c).or_insert(0.0) += v;
            }
        }
        let nz: Vec<_> = row.iter().filter(|(_, v)| v.abs() > 1e-14).collect();
        assert_eq!(nz.len(), 5);
        assert!((row[&centre] - 4.0).abs() < 1e-14);
        for n in [id(1, 2), id(3, 2), id(2, 1), id(2, 3)] {
            assert!((row[&(n as usize)] + 1.0).abs() < 1e-14);
        }
        // 2D variant agrees.
        let pos2: Vec<DVec2> = pos.iter().map(|p| p.truncate()).collect();
        let w2 = cotan_weights_2d(&pos2, &tri);
        assert_eq!(w.len(), w2.len());
        for (a, b) in w.iter().zip(&w2) {
            assert_eq!((a.0, a.1), (b.0, b.1));
            assert!((a.2 - b.2).abs() < 1e-14);
        }
    }

    /// Dirichlet problem on the grid with merging: harmonic linear data is reproduced exactly.
    #[test]
    fn merged_dirichlet_laplacian_reproduces_linear_function() {
        let (nx, ny) = (6usize, 6usize);
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut pos = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                pos.push(DVec3::new(i as f64, j as f64 + 0.1 * i as f64, 0.0));
            }
        }
        let mut tri = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                tri.push([a as u32, b as u32, c as u32]);
                tri.push([a as u32, c as u32, d as u32]);
            }
        }
        let f = |p: DVec3| 2.0 * p.x - 0.7 * p.y + 1.0;
        let w = cotan_weights(&pos, &tri);
        let mut merge = vec![None; pos.len()];
        let mut n = 0;
        for j in 1..ny {
            for i in 1..nx {
                merge[id(i, j)] = Some(n);
                n += 1;
            }
        }
        let trip = cotan_laplacian_triplets(&w, Some(&merge));
        let chol = SparseCholesky::new(n, &trip).unwrap();
        let mut rhs = vec![0.0; n];
        for &(a, b, wt) in &w {
            match (merge[a as usize], merge[b as usize]) {
                (Some(u), None) => rhs[u] += wt * f(pos[b as usize]),
                (None, Some(u)) => rhs[u] += wt * f(pos[a as usize]),
                _ => {}
            }
        }
        chol.solve_in_place(&mut rhs);
        for (v, m) in merge.iter().enumerate() {
            if let Some(u) = m {
                assert!((rhs[*u] - f(pos[v])).abs() < 1e-12);
            }
        }
    }
}
