//! Sparse linear algebra shared by the numeric stages (slit map, flattening).
//!
//! * [`SparseCholesky`]: a sparse symmetric positive-definite system factorised once, then solved
//!   many times: faer's symbolic analysis (AMD ordering, supernodes) and a scalar supernodal LLᵀ
//!   of our own, bit-identical on every target (native SIMD/FMA kernels are not). The symbolic
//!   analysis is kept so a matrix with the same pattern but new values is refactorised cheaply
//!   ([`SparseCholesky::refactor`]).
//! * [`cotan_weights`] and [`cotan_laplacian_triplets`]: the P1 finite-element (cotan) Laplacian
//!   of a triangle mesh, with optional merging of vertices into shared unknowns and elimination of
//!   Dirichlet vertices.
//!
//! Everything is deterministic: triplets are sorted before assembly, every floating-point sum runs
//! in a fixed order with plain `+ − × ÷ sqrt` (no `mul_add`, no run-time SIMD dispatch), so the
//! results are the same bits natively and in wasm.

use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SymbolicSparseColMatRef;
use faer::Side;
use glam::DVec3;
use std::sync::Arc;

/// Errors of the sparse solvers. Each variant names what is at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinalgError {
    /// The numeric factorisation met a non-positive pivot: the matrix is not positive definite
    /// (e.g. a pure Neumann Laplacian without a fixed vertex, or a disconnected unknown).
    #[error("matrix is not positive definite (non-positive pivot at elimination step {pivot})")]
    NotPositiveDefinite {
        /// Elimination step (in the fill-reducing order) of the failing pivot.
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
    /// The matrix is too large for 32-bit indices (more than 2³² − 1 rows or stored entries).
    #[error("matrix too large: {what} exceeds 32-bit indices")]
    TooLarge { what: &'static str },
    /// A given elimination order is not a permutation of the unknowns.
    #[error("elimination order of length {len} is not a permutation of 0..{n}")]
    BadOrder { len: usize, n: usize },
    /// faer's symbolic analysis failed (allocation).
    #[error("faer: {0}")]
    Faer(String),
}

/// Sparse symmetric positive-definite system with a reusable factorisation: symbolic once,
/// numeric once, then many solves; bit-identical results on every target.
///
/// The fill-reducing ordering (AMD) and the supernodal structure come from faer's symbolic
/// analysis (integer work, run with `u32` indices so that 32- and 64-bit targets agree). The
/// numeric factorisation (left-looking supernodal LLᵀ) and the triangular solves are plain scalar
/// Rust in a fixed loop order, with no `mul_add`: faer's dense kernels dispatch at run time to
/// SIMD/FMA code natively and to scalar code in wasm, which changes the rounding of the sums, so
/// the page and the CLI would otherwise disagree in the last bits (and in the G-code).
#[derive(Debug, Clone)]
pub struct SparseCholesky {
    symbolic: Arc<Symbolic>,
    /// Supernode blocks of L, column-major, at `symbolic.val_ptr[s]`.
    values: Vec<f64>,
}

/// The integer part of a factorisation: pattern of A, ordering, supernodes, scatter maps.
#[derive(Debug)]
struct Symbolic {
    n: usize,
    /// Lower-triangle CSC pattern of A (original indices, rows sorted), to check `refactor`.
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    /// `perm[k]` = original index of elimination step k.
    perm: Vec<u32>,
    /// Supernode s holds the (permuted) columns `sn_begin[s]..sn_begin[s + 1]`.
    sn_begin: Vec<u32>,
    /// Rows below the diagonal block of supernode s (permuted, sorted): `pat[pat_ptr[s]..pat_ptr[s + 1]]`.
    pat_ptr: Vec<usize>,
    pat: Vec<u32>,
    /// Block of supernode s in `values`: `val_ptr[s]..val_ptr[s + 1]`, leading dimension = rows.
    val_ptr: Vec<usize>,
    /// Supernodes that update supernode s (ascending): `upd[upd_ptr[s]..upd_ptr[s + 1]]`.
    upd_ptr: Vec<usize>,
    upd: Vec<u32>,
    /// Position in `values` of every stored lower entry of A (CSC order).
    a_to_l: Vec<usize>,
    /// Largest `rows × cols` of an update block (workspace size).
    max_update: usize,
}

/// Lower triangle (row ≥ col) of the triplets in CSC form, duplicates summed.
struct LowerCsc {
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
}

fn assemble_lower(n: usize, triplets: &[(usize, usize, f64)]) -> Result<LowerCsc, LinalgError> {
    if n >= u32::MAX as usize {
        return Err(LinalgError::TooLarge { what: "the number of rows" });
    }
    // Counting sort by column (stable), then each column by row (stable): duplicates are summed
    // in the order they were given, whatever the target.
    let mut count = vec![0usize; n + 1];
    for &(row, col, value) in triplets {
        if row >= n || col >= n {
            return Err(LinalgError::BadIndex { row, col, n });
        }
        if !value.is_finite() {
            return Err(LinalgError::NonFinite { row, col });
        }
        // Both triangles are given: the upper one is redundant for a symmetric matrix.
        if row >= col {
            count[col + 1] += 1;
        }
    }
    for c in 0..n {
        count[c + 1] += count[c];
    }
    if count[n] >= u32::MAX as usize {
        return Err(LinalgError::TooLarge { what: "the number of stored entries" });
    }
    let mut bucket: Vec<(u32, f64)> = vec![(0, 0.0); count[n]];
    let mut next = count.clone();
    for &(row, col, value) in triplets {
        if row >= col {
            bucket[next[col]] = (row as u32, value);
            next[col] += 1;
        }
    }
    let mut col_ptr = vec![0u32; n + 1];
    let mut row_idx = Vec::with_capacity(bucket.len());
    let mut values: Vec<f64> = Vec::with_capacity(bucket.len());
    for c in 0..n {
        let column = &mut bucket[count[c]..count[c + 1]];
        column.sort_by_key(|e| e.0);
        let mut last = None;
        for &(row, value) in column.iter() {
            if last == Some(row) {
                *values.last_mut().expect("a previous entry exists") += value;
            } else {
                row_idx.push(row);
                values.push(value);
                last = Some(row);
            }
        }
        col_ptr[c + 1] = row_idx.len() as u32;
    }
    // The analysis keeps the pattern: without the room of the duplicates (over half of it for a
    // cotan Laplacian's triplets).
    row_idx.shrink_to_fit();
    Ok(LowerCsc { col_ptr, row_idx, values })
}

impl Symbolic {
    /// `order`: elimination order to use (`order[k]` = unknown eliminated at step k), or AMD's.
    fn new(n: usize, col_ptr: Vec<u32>, row_idx: Vec<u32>, order: Option<&[u32]>) -> Result<Self, LinalgError> {
        let faer_err = |e: faer::sparse::FaerError| LinalgError::Faer(format!("{e:?}"));
        let a = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let inverse: Vec<u32>;
        let ordering = match order {
            None => SymmetricOrdering::Amd,
            Some(fwd) => {
                inverse = invert_order(fwd, n)?;
                SymmetricOrdering::Custom(PermRef::new_checked(fwd, &inverse, n))
            }
        };
        let sym = factorize_symbolic_cholesky(a, Side::Lower, ordering, params).map_err(faer_err)?;
        let (perm, perm_inv): (Vec<u32>, Vec<u32>) = match sym.perm() {
            Some(p) => {
                let (fwd, inv) = p.arrays();
                (fwd.to_vec(), inv.to_vec())
            }
            None => ((0..n as u32).collect(), (0..n as u32).collect()),
        };
        // Supernode begins and below-diagonal patterns. faer still picks the simplicial structure
        // when there is no work at all (e.g. a diagonal matrix): then every column is a supernode.
        let (mut sn_begin, patterns): (Vec<u32>, Vec<&[u32]>) = match sym.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) => {
                (sn.supernode_begin().to_vec(), (0..sn.n_supernodes()).map(|s| sn.supernode(s).pattern()).collect())
            }
            SymbolicCholeskyRaw::Simplicial(sp) => {
                let f = sp.factor();
                let below = |j: usize| {
                    let rows = f.row_idx_of_col_raw(j);
                    &rows[rows.partition_point(|&r| r as usize <= j)..]
                };
                ((0..n as u32).collect(), (0..n).map(below).collect())
            }
        };
        let ns = sn_begin.len();
        sn_begin.push(n as u32);
        let mut pat_ptr = Vec::with_capacity(ns + 1);
        let mut pat: Vec<u32> = Vec::new();
        let mut val_ptr = Vec::with_capacity(ns + 1);
        pat_ptr.push(0);
        val_ptr.push(0usize);
        for (s, p) in patterns.iter().enumerate() {
            let start = pat.len();
            pat.extend_from_slice(p);
            pat[start..].sort_unstable();
            pat_ptr.push(pat.len());
            let cols = (sn_begin[s + 1] - sn_begin[s]) as usize;
            let rows = cols + p.len();
            val_ptr.push(val_ptr[s] + rows * cols);
        }
        // Supernode of every permuted column.
        let mut sn_of = vec![0u32; n];
        for s in 0..ns {
            for c in sn_begin[s]..sn_begin[s + 1] {
                sn_of[c as usize] = s as u32;
            }
        }
        // Who updates whom: d updates every supernode its pattern rows fall in. Listing the pairs
        // by d and bucketing them by target keeps each target's list ascending in d.
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut max_update = 0usize;
        for d in 0..ns {
            let p = &pat[pat_ptr[d]..pat_ptr[d + 1]];
            let mut k = 0;
            while k < p.len() {
                let t = sn_of[p[k] as usize];
                let end = sn_begin[t as usize + 1];
                let k2 = k + p[k..].partition_point(|&r| r < end);
                max_update = max_update.max((p.len() - k) * (k2 - k));
                pairs.push((t, d as u32));
                k = k2;
            }
        }
        let mut upd_ptr = vec![0usize; ns + 1];
        for &(t, _) in &pairs {
            upd_ptr[t as usize + 1] += 1;
        }
        for s in 0..ns {
            upd_ptr[s + 1] += upd_ptr[s];
        }
        let mut fill = upd_ptr.clone();
        let mut upd = vec![0u32; pairs.len()];
        for &(t, d) in &pairs {
            upd[fill[t as usize]] = d;
            fill[t as usize] += 1;
        }
        // Where each entry of A lands in L.
        let mut a_to_l = Vec::with_capacity(row_idx.len());
        for c in 0..n {
            for &r in &row_idx[col_ptr[c] as usize..col_ptr[c + 1] as usize] {
                let (pr, pc) = (perm_inv[r as usize], perm_inv[c]);
                let (row, col) = (pr.max(pc), pr.min(pc));
                let s = sn_of[col as usize] as usize;
                let (b, e) = (sn_begin[s], sn_begin[s + 1]);
                let cols = (e - b) as usize;
                let p = &pat[pat_ptr[s]..pat_ptr[s + 1]];
                let local = if row < e {
                    (row - b) as usize
                } else {
                    cols + p
                        .binary_search(&row)
                        .map_err(|_| LinalgError::Faer("entry outside the symbolic pattern".into()))?
                };
                a_to_l.push(val_ptr[s] + (col - b) as usize * (cols + p.len()) + local);
            }
        }
        Ok(Self { n, col_ptr, row_idx, perm, sn_begin, pat_ptr, pat, val_ptr, upd_ptr, upd, a_to_l, max_update })
    }

    fn n_supernodes(&self) -> usize {
        self.sn_begin.len() - 1
    }

    /// Number of values of L.
    fn factor_len(&self) -> usize {
        *self.val_ptr.last().expect("val_ptr is never empty")
    }

    /// Left-looking supernodal LLᵀ of the lower-triangle values `a` (CSC order of `row_idx`).
    fn factorise(&self, a: &[f64]) -> Result<Vec<f64>, LinalgError> {
        let mut l = zeros_written(self.factor_len());
        self.factorise_into(a, &mut l)?;
        Ok(l)
    }

    /// [`Symbolic::factorise`] into `l` (of [`Symbolic::factor_len`] values, overwritten): a
    /// refactorisation reuses the previous factor's memory (the 300k-face panel's optimise
    /// held two factors of 220 MB each at its peak) and its pages (see [`zeros_written`]).
    fn factorise_into(&self, a: &[f64], l: &mut [f64]) -> Result<(), LinalgError> {
        l.fill(0.0);
        for (&pos, &v) in self.a_to_l.iter().zip(a) {
            l[pos] += v;
        }
        // Local row of a global (permuted) row in the current target supernode.
        let mut rel = vec![0u32; self.n];
        let mut work = vec![0.0; self.max_update.min(MAX_WORK)];
        for s in 0..self.n_supernodes() {
            let (b, e) = (self.sn_begin[s], self.sn_begin[s + 1]);
            let cols = (e - b) as usize;
            let pat = &self.pat[self.pat_ptr[s]..self.pat_ptr[s + 1]];
            let rows = cols + pat.len();
            for i in 0..cols {
                rel[b as usize + i] = i as u32;
            }
            for (k, &r) in pat.iter().enumerate() {
                rel[r as usize] = (cols + k) as u32;
            }
            let (done, rest) = l.split_at_mut(self.val_ptr[s]);
            let target = &mut rest[..rows * cols];
            for &d in &self.upd[self.upd_ptr[s]..self.upd_ptr[s + 1]] {
                let d = d as usize;
                let dcols = (self.sn_begin[d + 1] - self.sn_begin[d]) as usize;
                let dpat = &self.pat[self.pat_ptr[d]..self.pat_ptr[d + 1]];
                let drows = dcols + dpat.len();
                let k1 = dpat.partition_point(|&r| r < b);
                let k2 = k1 + dpat[k1..].partition_point(|&r| r < e);
                let (m, k) = (dpat.len() - k1, k2 - k1);
                let ld = &done[self.val_ptr[d]..self.val_ptr[d] + drows * dcols];
                let first = dcols + k1;
                if dcols == 1 {
                    // One column: subtract the outer product directly.
                    let col = &ld[first..drows];
                    for jj in 0..k {
                        let f = col[jj];
                        let tc = (dpat[k1 + jj] - b) as usize;
                        let tcol = &mut target[tc * rows..(tc + 1) * rows];
                        for ii in jj..m {
                            tcol[rel[dpat[k1 + ii] as usize] as usize] -= col[ii] * f;
                        }
                    }
                    continue;
                }
                // W = L_d[k1.., :] · L_d[k1..k2, :]ᵀ (lower trapezoid), each entry summed over the
                // columns of d in ascending order; in runs of its columns that fit the workspace
                // (each entry's sum is the same whatever the runs).
                let column = |t: usize| &ld[t * drows + first..(t + 1) * drows];
                let run = (work.len() / m).max(1);
                for j0 in (0..k).step_by(run) {
                    let j1 = (j0 + run).min(k);
                    let w = &mut work[..m * (j1 - j0)];
                    w.fill(0.0);
                    // Column jj of W at (jj − j0)·m, its rows jj..m.
                    let wcol = |jj: usize| (jj - j0) * m + jj..(jj - j0 + 1) * m;
                    let mut t = 0;
                    while t + 4 <= dcols {
                        let c = [column(t), column(t + 1), column(t + 2), column(t + 3)];
                        for jj in j0..j1 {
                            let f = [c[0][jj], c[1][jj], c[2][jj], c[3][jj]];
                            add_products4(&mut w[wcol(jj)], c.map(|ci| &ci[jj..]), f);
                        }
                        t += 4;
                    }
                    for t in t..dcols {
                        let c = column(t);
                        for jj in j0..j1 {
                            let f = c[jj];
                            for (wv, &x) in w[wcol(jj)].iter_mut().zip(&c[jj..]) {
                                *wv += x * f;
                            }
                        }
                    }
                    for jj in j0..j1 {
                        let tc = (dpat[k1 + jj] - b) as usize;
                        let tcol = &mut target[tc * rows..(tc + 1) * rows];
                        let wc = &w[(jj - j0) * m..(jj - j0 + 1) * m];
                        for ii in jj..m {
                            tcol[rel[dpat[k1 + ii] as usize] as usize] -= wc[ii];
                        }
                    }
                }
            }
            dense_llt_panel(target, rows, cols)
                .map_err(|j| LinalgError::NotPositiveDefinite { pivot: b as usize + j })?;
        }
        Ok(())
    }

    /// Solves L Lᵀ y = y in the permuted numbering.
    fn solve_permuted(&self, l: &[f64], y: &mut [f64]) {
        // The rows below a supernode's diagonal block are gathered into `below` once per
        // supernode, so the inner loops run over contiguous memory; no other column touches them
        // meanwhile, so every operation and its order are as without the gather (same bits).
        let ns = self.n_supernodes();
        let mut below: Vec<f64> = Vec::new();
        for s in 0..ns {
            let (b, cols, pat, blk) = self.block(l, s);
            let rows = cols + pat.len();
            below.clear();
            below.extend(pat.iter().map(|&r| y[r as usize]));
            // Slices zipped rather than indexed: the same operations in the same order, without
            // a bounds check per entry (which the wasm engine does not hoist out of the loop).
            let diag = &mut y[b..b + cols];
            for j in 0..cols {
                let col = &blk[j * rows..(j + 1) * rows];
                let yj = diag[j] / col[j];
                diag[j] = yj;
                for (yi, &c) in diag[j + 1..].iter_mut().zip(&col[j + 1..cols]) {
                    *yi -= c * yj;
                }
                for (x, &c) in below.iter_mut().zip(&col[cols..]) {
                    *x -= c * yj;
                }
            }
            for (&r, &x) in pat.iter().zip(&below) {
                y[r as usize] = x;
            }
        }
        for s in (0..ns).rev() {
            let (b, cols, pat, blk) = self.block(l, s);
            let rows = cols + pat.len();
            below.clear();
            below.extend(pat.iter().map(|&r| y[r as usize]));
            let diag = &mut y[b..b + cols];
            for j in (0..cols).rev() {
                let col = &blk[j * rows..(j + 1) * rows];
                let mut sum = diag[j];
                for (&c, &yi) in col[j + 1..cols].iter().zip(&diag[j + 1..]) {
                    sum -= c * yi;
                }
                for (&c, &x) in col[cols..].iter().zip(&below) {
                    sum -= c * x;
                }
                diag[j] = sum / col[j];
            }
        }
    }

    /// (first column, column count, pattern below the diagonal block, block values) of supernode s.
    fn block<'a>(&'a self, l: &'a [f64], s: usize) -> (usize, usize, &'a [u32], &'a [f64]) {
        let b = self.sn_begin[s] as usize;
        let cols = self.sn_begin[s + 1] as usize - b;
        (b, cols, &self.pat[self.pat_ptr[s]..self.pat_ptr[s + 1]], &l[self.val_ptr[s]..self.val_ptr[s + 1]])
    }
}

/// The update workspace of [`Symbolic::factorise_into`] holds at most this many values (8 MiB):
/// the largest update of the 300k-face panel's optimise took 250 MB in one block.
const MAX_WORK: usize = 1 << 20;

/// `len` zeros, written now. A zeroed allocation (what `vec![0.0; len]` gives) maps the shared
/// zero page on first read, so a `+=` into it faults twice per page, the second time a
/// copy-on-write that stops every other core to flush its TLB: 6 % of a 40k-face plan's CPU time
/// went there in `factorise`.
fn zeros_written(len: usize) -> Vec<f64> {
    let mut v = Vec::with_capacity(len);
    // Opaque to the optimiser, which may fold an allocation followed by a zero fill into a
    // zeroed allocation (LLVM's dead-store elimination does so for malloc + memset).
    std::hint::black_box(v.as_mut_ptr());
    v.resize(len, 0.0);
    v
}

/// `w[i] = (((w[i] + c0[i]·f0) + c1[i]·f1) + c2[i]·f2) + c3[i]·f3`: four rank-one steps in one
/// pass, in the same order as four separate passes (so the same bits), a quarter of the traffic.
#[inline]
fn add_products4(w: &mut [f64], c: [&[f64]; 4], f: [f64; 4]) {
    let n = w.len();
    let (c0, c1, c2, c3) = (&c[0][..n], &c[1][..n], &c[2][..n], &c[3][..n]);
    for i in 0..n {
        w[i] = w[i] + c0[i] * f[0] + c1[i] * f[1] + c2[i] * f[2] + c3[i] * f[3];
    }
}

/// `w[i] = (((w[i] − c0[i]·f0) − c1[i]·f1) − …)`, as [`add_products4`].
#[inline]
fn sub_products4(w: &mut [f64], c: [&[f64]; 4], f: [f64; 4]) {
    let n = w.len();
    let (c0, c1, c2, c3) = (&c[0][..n], &c[1][..n], &c[2][..n], &c[3][..n]);
    for i in 0..n {
        w[i] = w[i] - c0[i] * f[0] - c1[i] * f[1] - c2[i] * f[2] - c3[i] * f[3];
    }
}

/// In-place LLᵀ of the `cols × cols` diagonal block of a column-major `rows × cols` panel, and
/// `L_below = A_below · L⁻ᵀ` for the rows under it (left-looking, one column at a time, earlier
/// columns applied in ascending order). `Err(j)` when pivot j is not positive.
fn dense_llt_panel(a: &mut [f64], rows: usize, cols: usize) -> Result<(), usize> {
    for c in 0..cols {
        let (left, right) = a.split_at_mut(c * rows);
        let cc = &mut right[c..rows];
        let column = |j: usize| &left[j * rows + c..(j + 1) * rows];
        let mut j = 0;
        while j + 4 <= c {
            let l = [column(j), column(j + 1), column(j + 2), column(j + 3)];
            sub_products4(cc, l, [l[0][0], l[1][0], l[2][0], l[3][0]]);
            j += 4;
        }
        for j in j..c {
            let l = column(j);
            let f = l[0];
            for (v, &x) in cc.iter_mut().zip(l) {
                *v -= x * f;
            }
        }
        let d = cc[0];
        // Not `d <= 0`: NaN must fail too.
        if d.is_nan() || d <= 0.0 {
            return Err(c);
        }
        let ljj = d.sqrt();
        cc[0] = ljj;
        for v in &mut cc[1..] {
            *v /= ljj;
        }
    }
    Ok(())
}

impl SparseCholesky {
    /// `triplets` (row, col, value) of the full symmetric matrix (both triangles given; duplicates
    /// summed). Only the lower triangle is read: symmetry is the caller's promise.
    pub fn new(n: usize, triplets: &[(usize, usize, f64)]) -> Result<Self, LinalgError> {
        Self::build(n, triplets, None)
    }

    /// As [`SparseCholesky::new`] with a given elimination order (`order[k]` = unknown eliminated
    /// at step k, a permutation of `0..n`), e.g. one AMD order of a mesh shared by the related
    /// systems on it ([`amd_order`], [`restrict_order`]): AMD costs about as much as the numeric
    /// factorisation.
    pub fn with_order(n: usize, triplets: &[(usize, usize, f64)], order: &[u32]) -> Result<Self, LinalgError> {
        Self::build(n, triplets, Some(order))
    }

    /// The cotan Laplacian of the edge `weights` on the unknowns `unknown` (see
    /// [`cotan_laplacian_triplets`]; `n` of them), factorised in the order `vertex_order`
    /// induces on them ([`restrict_order`]).
    pub fn laplacian(
        weights: &[(u32, u32, f64)],
        unknown: &[Option<usize>],
        n: usize,
        vertex_order: &[u32],
    ) -> Result<Self, LinalgError> {
        let triplets = cotan_laplacian_triplets(weights, Some(unknown));
        Self::with_order(n, &triplets, &restrict_order(vertex_order, unknown, n))
    }

    /// The symbolic analysis (AMD's order, or `order` as in [`SparseCholesky::with_order`]) of the
    /// symmetric pattern of the `(i, j)` pairs (either triangle, repeats allowed), without a
    /// numeric factorisation: solves give NaN until [`SparseCholesky::refactor_lower`] succeeds.
    /// For a caller that refactorises at once: its pattern, 8 bytes a pair, is freed before the
    /// factor is allocated (triplets and their assembly held 250 MB beside the 300k-face panel's
    /// optimise factor, and left a hole just short of it in the page's memory).
    pub fn analyse(n: usize, mut pairs: Vec<(u32, u32)>, order: Option<&[u32]>) -> Result<Self, LinalgError> {
        if n == 0 {
            return Err(LinalgError::Empty);
        }
        if n >= u32::MAX as usize {
            return Err(LinalgError::TooLarge { what: "the number of rows" });
        }
        for p in pairs.iter_mut() {
            if p.0 as usize >= n || p.1 as usize >= n {
                return Err(LinalgError::BadIndex { row: p.0 as usize, col: p.1 as usize, n });
            }
            // (column, row) of the lower triangle: sorted, they are the CSC order.
            *p = (p.0.min(p.1), p.0.max(p.1));
        }
        crate::par::sort_unstable(&mut pairs);
        pairs.dedup();
        if pairs.len() >= u32::MAX as usize {
            return Err(LinalgError::TooLarge { what: "the number of stored entries" });
        }
        let mut col_ptr = vec![0u32; n + 1];
        for &(c, _) in &pairs {
            col_ptr[c as usize + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx = pairs.iter().map(|&(_, r)| r).collect();
        drop(pairs);
        let symbolic = Arc::new(Symbolic::new(n, col_ptr, row_idx, order)?);
        Ok(Self { symbolic, values: Vec::new() })
    }

    fn build(n: usize, triplets: &[(usize, usize, f64)], order: Option<&[u32]>) -> Result<Self, LinalgError> {
        if n == 0 {
            return Err(LinalgError::Empty);
        }
        let csc = assemble_lower(n, triplets)?;
        let symbolic = Arc::new(Symbolic::new(n, csc.col_ptr, csc.row_idx, order)?);
        let values = symbolic.factorise(&csc.values)?;
        Ok(Self { symbolic, values })
    }

    /// New numeric values with the same sparsity pattern (reuses the symbolic analysis and the
    /// factor's memory). A pattern mismatch keeps the previous factorisation; a failed
    /// factorisation (not positive definite) loses it, and solves give NaN until a
    /// refactorisation succeeds.
    pub fn refactor(&mut self, triplets: &[(usize, usize, f64)]) -> Result<(), LinalgError> {
        let csc = assemble_lower(self.symbolic.n, triplets)?;
        if csc.col_ptr != self.symbolic.col_ptr || csc.row_idx != self.symbolic.row_idx {
            return Err(LinalgError::PatternMismatch {
                detail: format!(
                    "{} stored lower-triangle entries, {} given",
                    self.symbolic.row_idx.len(),
                    csc.row_idx.len()
                ),
            });
        }
        self.factorise_in_place(&csc.values)
    }

    /// The factor of `values` over the previous one's memory; empty when it fails.
    fn factorise_in_place(&mut self, values: &[f64]) -> Result<(), LinalgError> {
        let mut l = std::mem::take(&mut self.values);
        l.resize(self.symbolic.factor_len(), 0.0);
        self.symbolic.factorise_into(values, &mut l)?;
        self.values = l;
        Ok(())
    }

    /// Where entry (`row`, `col`) of A (either triangle) is among the stored lower entries in CSC
    /// order, or `None` outside the pattern: a caller refactorising one pattern many times
    /// accumulates its values there ([`SparseCholesky::refactor_lower`]) instead of sorting
    /// triplets each time.
    pub fn lower_slot(&self, row: usize, col: usize) -> Option<usize> {
        let (row, col) = (row.max(col), row.min(col));
        let sym = &self.symbolic;
        if col >= sym.n {
            return None;
        }
        let (a, b) = (sym.col_ptr[col] as usize, sym.col_ptr[col + 1] as usize);
        sym.row_idx[a..b].binary_search(&(row as u32)).ok().map(|k| a + k)
    }

    /// Number of stored lower entries of A (the length [`SparseCholesky::refactor_lower`] takes).
    pub fn lower_len(&self) -> usize {
        self.symbolic.row_idx.len()
    }

    /// New numeric values with the same pattern, given as the stored lower entries of A in CSC
    /// order ([`SparseCholesky::lower_slot`]). Non-finite values and a wrong length keep the
    /// previous factorisation; a failed one loses it, as in [`SparseCholesky::refactor`].
    pub fn refactor_lower(&mut self, values: &[f64]) -> Result<(), LinalgError> {
        if values.len() != self.symbolic.row_idx.len() {
            return Err(LinalgError::PatternMismatch {
                detail: format!(
                    "{} stored lower-triangle entries, {} given",
                    self.symbolic.row_idx.len(),
                    values.len()
                ),
            });
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            let col = self.symbolic.col_ptr.partition_point(|&p| p as usize <= k) - 1;
            return Err(LinalgError::NonFinite { row: self.symbolic.row_idx[k] as usize, col });
        }
        self.factorise_in_place(values)
    }

    /// The elimination order used (`order[k]` = unknown eliminated at step k).
    pub fn order(&self) -> &[u32] {
        &self.symbolic.perm
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.symbolic.n
    }

    /// Number of stored lower-triangle entries of the assembled matrix (not of the factor).
    pub fn nnz_lower(&self) -> usize {
        self.symbolic.row_idx.len()
    }

    /// Number of stored entries of the factor L (supernode blocks, explicit zeros included).
    pub fn nnz_factor(&self) -> usize {
        self.symbolic.factor_len()
    }

    /// Multiply-adds of the numeric factorisation, Σ over columns of (entries below the diagonal)²
    /// / 2 (explicit zeros of merged supernodes included): a machine-independent cost figure.
    pub fn factor_flops(&self) -> f64 {
        let sym = &self.symbolic;
        let mut f = 0.0;
        for s in 0..sym.n_supernodes() {
            let cols = (sym.sn_begin[s + 1] - sym.sn_begin[s]) as usize;
            let rows = cols + sym.pat_ptr[s + 1] - sym.pat_ptr[s];
            for j in 0..cols {
                let below = (rows - j - 1) as f64;
                f += 0.5 * below * (below + 1.0);
            }
        }
        f
    }

    /// Solves A x = rhs, overwriting `rhs` with x.
    ///
    /// # Panics
    /// If `rhs.len() != self.n()` (a programming error, not a data error).
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        let sym = &self.symbolic;
        assert_eq!(rhs.len(), sym.n, "right-hand side length must equal n");
        if self.values.is_empty() {
            // The last refactorisation failed (see `refactor`).
            rhs.fill(f64::NAN);
            return;
        }
        let mut y: Vec<f64> = sym.perm.iter().map(|&o| rhs[o as usize]).collect();
        sym.solve_permuted(&self.values, &mut y);
        for (k, &o) in sym.perm.iter().enumerate() {
            rhs[o as usize] = y[k];
        }
    }

    /// Solves for several right-hand sides (each as [`SparseCholesky::solve_in_place`]).
    ///
    /// # Panics
    /// If a column's length differs from `self.n()`.
    pub fn solve_many_in_place(&self, rhs_columns: &mut [Vec<f64>]) {
        for c in rhs_columns.iter_mut() {
            self.solve_in_place(c);
        }
    }
}

/// `inverse[order[k]] = k`; an error unless `order` is a permutation of `0..n`.
fn invert_order(order: &[u32], n: usize) -> Result<Vec<u32>, LinalgError> {
    let bad = || LinalgError::BadOrder { len: order.len(), n };
    if order.len() != n {
        return Err(bad());
    }
    let mut inverse = vec![u32::MAX; n];
    for (k, &v) in order.iter().enumerate() {
        match inverse.get_mut(v as usize) {
            Some(slot) if *slot == u32::MAX => *slot = k as u32,
            _ => return Err(bad()),
        }
    }
    Ok(inverse)
}

/// AMD order of the vertex graph of a triangle mesh (`n` vertices, the triangles' edges),
/// memoised per thread for the last mesh asked: `flatten` and `slitmap` order the same graph, and
/// AMD costs about as much as a numeric factorisation. The result depends only on the input, so
/// the cache changes no output. No triangles: the identity order, and the cache is emptied
/// (benchmarks use that to time a cold start).
pub fn mesh_order(n: usize, triangles: &[[u32; 3]]) -> Result<Arc<Vec<u32>>, LinalgError> {
    type Entry = (usize, Vec<[u32; 3]>, Arc<Vec<u32>>);
    thread_local! {
        static LAST: std::cell::RefCell<Option<Entry>> = const { std::cell::RefCell::new(None) };
    }
    if triangles.is_empty() {
        LAST.with(|c| *c.borrow_mut() = None);
        return Ok(Arc::new((0..n as u32).collect()));
    }
    let hit = LAST.with(|c| match &*c.borrow() {
        Some((m, t, order)) if *m == n && t.as_slice() == triangles => Some(order.clone()),
        _ => None,
    });
    if let Some(order) = hit {
        return Ok(order);
    }
    let mut pattern = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            pattern.push((a.max(b), a.min(b), 0.0));
        }
    }
    let order = Arc::new(amd_order(n, &pattern)?);
    LAST.with(|c| *c.borrow_mut() = Some((n, triangles.to_vec(), order.clone())));
    Ok(order)
}

/// AMD fill-reducing elimination order of the symmetric pattern of `triplets` (`n × n`, values
/// ignored): `order[k]` = unknown eliminated at step k.
pub fn amd_order(n: usize, triplets: &[(usize, usize, f64)]) -> Result<Vec<u32>, LinalgError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::linalg::amd;
    if n == 0 {
        return Err(LinalgError::Empty);
    }
    let csc = assemble_lower(n, triplets)?;
    let a = SymbolicSparseColMatRef::new_checked(n, n, &csc.col_ptr, None, &csc.row_idx);
    let (mut fwd, mut inv) = (vec![0u32; n], vec![0u32; n]);
    let mut mem = MemBuffer::try_new(amd::order_scratch::<u32>(n, csc.row_idx.len()))
        .map_err(|_| LinalgError::Faer("out of memory".into()))?;
    amd::order(&mut fwd, &mut inv, a, amd::Control::default(), MemStack::new(&mut mem))
        .map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
    Ok(fwd)
}

/// The order of a related system from a vertex order: `unknown[v]` is the unknown of vertex v
/// (`None`: eliminated from the system, several vertices may share one unknown, as in
/// [`cotan_laplacian_triplets`]). Each unknown takes the place of its last vertex in
/// `vertex_order`, so a principal submatrix keeps the induced order (whose fill is a subset of
/// the full one's). `n_unknowns` = number of distinct unknowns.
pub fn restrict_order(vertex_order: &[u32], unknown: &[Option<usize>], n_unknowns: usize) -> Vec<u32> {
    let mut remaining = vec![0u32; n_unknowns];
    for u in unknown.iter().flatten() {
        remaining[*u] += 1;
    }
    let mut out = Vec::with_capacity(n_unknowns);
    for &v in vertex_order {
        if let Some(u) = unknown[v as usize] {
            remaining[u] -= 1;
            if remaining[u] == 0 {
                out.push(u as u32);
            }
        }
    }
    out
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
    fn given_orders_give_the_same_solution() {
        let mut rng = SplitMix(3);
        let n = 40;
        let (dense, trip) = random_spd(n, &mut rng);
        let b: Vec<f64> = (0..n).map(|_| rng.next_f64() - 0.5).collect();
        let x_ref = dense_solve(dense, b.clone());
        let reversed: Vec<u32> = (0..n as u32).rev().collect();
        for order in [amd_order(n, &trip).unwrap(), reversed] {
            let chol = SparseCholesky::with_order(n, &trip, &order).unwrap();
            assert_eq!(chol.order(), order.as_slice());
            let mut x = b.clone();
            chol.solve_in_place(&mut x);
            for (u, v) in x.iter().zip(&x_ref) {
                assert!((u - v).abs() < 1e-12);
            }
        }
        assert_eq!(SparseCholesky::with_order(n, &trip, &[0, 1]).unwrap_err(), LinalgError::BadOrder { len: 2, n });
        let repeated: Vec<u32> = (0..n as u32).map(|i| i.min(5)).collect();
        assert!(matches!(SparseCholesky::with_order(n, &trip, &repeated), Err(LinalgError::BadOrder { .. })));
    }

    #[test]
    fn restricted_order_places_merged_unknowns_at_their_last_vertex() {
        // Vertices 0..6, order 3 5 0 4 1 2; unknowns: 0 → a, 1,2 merged → b, 3 eliminated, 4 → c, 5 → d.
        let unknown = [Some(0), Some(1), Some(1), None, Some(2), Some(3)];
        assert_eq!(restrict_order(&[3, 5, 0, 4, 1, 2], &unknown, 4), vec![3, 0, 2, 1]);
    }

    #[test]
    fn mesh_order_is_a_permutation_and_memoised() {
        let tri = [[0u32, 1, 2], [0, 2, 3], [0, 3, 4]];
        let a = mesh_order(5, &tri).unwrap();
        let mut sorted = a.to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![0, 1, 2, 3, 4]);
        assert!(Arc::ptr_eq(&a, &mesh_order(5, &tri).unwrap()));
        assert!(!Arc::ptr_eq(&a, &mesh_order(5, &tri[..2]).unwrap()));
        assert_eq!(*mesh_order(3, &[]).unwrap(), vec![0, 1, 2]);
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
    fn an_analysed_pattern_refactorises_to_the_same_factor() {
        let mut rng = SplitMix(11);
        let n = 30;
        let (_, trip) = random_spd(n, &mut rng);
        let chol = SparseCholesky::new(n, &trip).unwrap();
        // Both triangles, repeated: the pattern is the same.
        let pairs: Vec<(u32, u32)> = trip.iter().map(|&(r, c, _)| (r as u32, c as u32)).collect();
        let mut analysed = SparseCholesky::analyse(n, pairs, None).unwrap();
        assert_eq!((analysed.order(), analysed.lower_len()), (chol.order(), chol.lower_len()));
        let mut x = vec![1.0; n];
        analysed.solve_in_place(&mut x);
        assert!(x.iter().all(|v| v.is_nan()), "no factor yet");
        let mut values = vec![0.0; analysed.lower_len()];
        for &(r, c, v) in trip.iter().filter(|t| t.0 >= t.1) {
            values[analysed.lower_slot(r, c).unwrap()] += v;
        }
        analysed.refactor_lower(&values).unwrap();
        assert_eq!(analysed.values, chol.values);
        assert_eq!(
            SparseCholesky::analyse(2, vec![(0, 2)], None).unwrap_err(),
            LinalgError::BadIndex { row: 0, col: 2, n: 2 }
        );
        assert_eq!(SparseCholesky::analyse(0, Vec::new(), None).unwrap_err(), LinalgError::Empty);
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
