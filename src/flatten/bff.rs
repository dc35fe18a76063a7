//! Boundary First Flattening with a reusable factorisation (see the module docs of `flatten`).

use std::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::fill::{fill_hole, Fill};
use super::{
    check, quality, BoundaryTarget, Extension, FlattenError, FlattenInput, FlattenMethod, FlattenOptions, Flattening,
    HoleFills,
};
use crate::linalg::{cotan_weights, mesh_order, SparseCholesky};
use crate::num;

const NONE: u32 = u32::MAX;

/// The smallest edge weight of the Tutte fallback ([`BffSolver::flatten_tutte`]): cotan weights
/// are clamped up to it, so every weight is positive (Floater's theorem needs that) while the
/// weights of well-shaped triangles, about 0.3–1, are kept as they are.
pub const TUTTE_MIN_WEIGHT: f64 = 1e-2;

/// BFF state for one mesh: the hole-filled disk, its curvature data and the factorisations.
/// Build once with [`BffSolver::new`], then call [`BffSolver::flatten`] (free boundary) or
/// [`BffSolver::flatten_with_scale_factors`] as often as needed: no refactorisation.
pub struct BffSolver {
    options: FlattenOptions,
    /// Real vertices, triangles and loops (copies, for the quality figures and the check).
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    loops: Vec<Vec<u32>>,
    area3d: f64,
    /// Vertex count of the filled disk (real + one virtual vertex per hole).
    n_all: usize,
    /// Vertices of the outer loop, in order.
    outer: Vec<u32>,
    /// Per filled-disk vertex: its index among the interior vertices, or `NONE` on the boundary.
    interior_index: Vec<u32>,
    interior: Vec<u32>,
    /// Cotan weights `(i, j, w_ij)` of the filled disk, `i < j`.
    weights: Vec<(u32, u32, f64)>,
    /// Angle defect `2π − Σθ` per interior vertex (interior indexing).
    omega: Vec<f64>,
    /// Exterior angle `π − Σθ` per outer-loop vertex.
    k: Vec<f64>,
    /// Length of outer-loop edge `j` (from `outer[j]` to `outer[j+1]`).
    lengths: Vec<f64>,
    /// Dirichlet block `A_II` (`None` without interior vertices).
    aii: Option<SparseCholesky>,
    /// Neumann Laplacian without the row and column of `outer[0]` (pinned to 0), for the conjugate.
    neumann: SparseCholesky,
    /// The fill-reducing vertex order of both factorisations (for the Tutte fallback's own).
    order: Vec<u32>,
    /// How the holes were filled.
    hole_fills: HoleFills,
}

impl BffSolver {
    /// Validates the input, fills the holes with virtual fans and factorises the Laplacian blocks.
    pub fn new(input: FlattenInput<'_>, options: &FlattenOptions) -> Result<Self, FlattenError> {
        if !(options.degenerate_rel.is_finite() && options.degenerate_rel >= 0.0) {
            return Err(FlattenError::InvalidOption(format!(
                "degenerate_rel {} must be finite and ≥ 0",
                options.degenerate_rel
            )));
        }
        validate(input, options.degenerate_rel)?;
        let n_real = input.positions.len();

        // Angle sums of the real triangles; the fills add theirs below.
        let mut angle_sum = vec![0.0; n_real];
        for t in input.triangles {
            for c in 0..3 {
                let p = input.positions[t[c] as usize];
                let u = input.positions[t[(c + 1) % 3] as usize] - p;
                let v = input.positions[t[(c + 2) % 3] as usize] - p;
                angle_sum[t[c] as usize] += num::atan2(u.cross(v).length(), u.dot(v));
            }
        }
        let mut weights = cotan_weights(input.positions, input.triangles);
        // The virtual vertex of each hole filled by a fan (see `fill`), by loop.
        let mut fan_centre = vec![None; input.loops.len()];
        let mut hole_fills = HoleFills::default();
        for (h, rim) in input.loops.iter().enumerate().skip(1) {
            let centre = angle_sum.len() as u32;
            let fill = fill_hole(input.positions, rim, &angle_sum, centre)
                .ok_or(FlattenError::DegenerateHoleFill { hole: h })?;
            if matches!(fill.kind, Fill::Fan | Fill::Circle) {
                angle_sum.push(0.0);
                fan_centre[h] = Some(centre);
            }
            for (t, a) in fill.triangles.iter().zip(&fill.angles) {
                for k in 0..3 {
                    angle_sum[t[k] as usize] += a[k];
                }
            }
            weights.extend_from_slice(&fill.weights);
            match fill.kind {
                Fill::Fan => hole_fills.fan += 1,
                Fill::Triangulated => hole_fills.triangulated += 1,
                Fill::Projected => hole_fills.projected += 1,
                Fill::Circle => hole_fills.circle += 1,
            }
        }
        // Rim edges now appear twice (real side and fill side): merge.
        weights.sort_by_key(|&(i, j, _)| (i, j));
        weights.dedup_by(|next, kept| {
            let same = next.0 == kept.0 && next.1 == kept.1;
            if same {
                kept.2 += next.2;
            }
            same
        });
        let n_all = angle_sum.len();

        let outer = input.loops[0].clone();
        let mut interior_index = vec![NONE; n_all];
        let mut on_outer = vec![false; n_all];
        for &v in &outer {
            on_outer[v as usize] = true;
        }
        let mut interior = Vec::with_capacity(n_all - outer.len());
        for (v, &b) in on_outer.iter().enumerate() {
            if !b {
                interior_index[v] = interior.len() as u32;
                interior.push(v as u32);
            }
        }
        let omega: Vec<f64> = interior.iter().map(|&v| 2.0 * PI - angle_sum[v as usize]).collect();
        let k: Vec<f64> = outer.iter().map(|&v| PI - angle_sum[v as usize]).collect();
        let lengths: Vec<f64> = (0..outer.len())
            .map(|j| {
                let (a, b) = (outer[j] as usize, outer[(j + 1) % outer.len()] as usize);
                (input.positions[b] - input.positions[a]).length()
            })
            .collect();

        // One AMD order of the mesh graph (shared with the slit map of the same mesh, see
        // `mesh_order`) serves both systems: a hole's fan centre (if any) follows the last vertex
        // of its rim, and each system takes the order induced on its unknowns. The fill's own
        // edges are not in the graph: they only join rim vertices, which AMD puts together.
        let order = {
            let real = mesh_order(n_real, input.triangles)?;
            let mut left: Vec<usize> = input.loops.iter().map(Vec::len).collect();
            let mut loop_of = vec![usize::MAX; n_real];
            for (li, lp) in input.loops.iter().enumerate() {
                for &v in lp {
                    loop_of[v as usize] = li;
                }
            }
            let mut order = Vec::with_capacity(n_all);
            for &v in real.iter() {
                order.push(v);
                let li = loop_of[v as usize];
                if li != usize::MAX && li > 0 {
                    left[li] -= 1;
                    if left[li] == 0 {
                        if let Some(c) = fan_centre[li] {
                            order.push(c);
                        }
                    }
                }
            }
            order
        };

        let interior_unknown: Vec<Option<usize>> =
            interior_index.iter().map(|&i| (i != NONE).then_some(i as usize)).collect();
        // The two factorisations are independent: side by side.
        let (aii, neumann) = crate::par::join(
            || {
                // A mesh may have no interior vertex at all (a strip): nothing to solve then.
                if interior.is_empty() {
                    return Ok(None);
                }
                SparseCholesky::laplacian(&weights, &interior_unknown, interior.len(), &order).map(Some)
            },
            || {
                // Always built: the conjugate, the disk target and prescribed angles all need it.
                let pinned = outer[0] as usize;
                let unknown: Vec<Option<usize>> = (0..n_all)
                    .map(|v| match v.cmp(&pinned) {
                        std::cmp::Ordering::Less => Some(v),
                        std::cmp::Ordering::Equal => None,
                        std::cmp::Ordering::Greater => Some(v - 1),
                    })
                    .collect();
                SparseCholesky::laplacian(&weights, &unknown, n_all - 1, &order)
            },
        );
        let (aii, neumann) = (aii?, neumann?);

        let area3d = input.triangles.iter().map(|t| tri_area3(input.positions, *t)).sum();
        Ok(Self {
            options: options.clone(),
            positions: input.positions[..n_real].to_vec(),
            triangles: input.triangles.to_vec(),
            loops: input.loops.to_vec(),
            area3d,
            n_all,
            outer,
            interior_index,
            interior,
            weights,
            omega,
            k,
            lengths,
            aii,
            neumann,
            order,
            hole_fills,
        })
    }

    /// Number of vertices on the outer loop (length of the scale-factor vector).
    pub fn outer_len(&self) -> usize {
        self.outer.len()
    }

    /// Flattening with the outer boundary of [`FlattenOptions::boundary`], then, while the result
    /// is not valid (a flipped triangle, or a loop overlapping itself or another), the fallbacks:
    ///
    /// 1. with [`FlattenOptions::disk_fallback`] and the free target, the target angles bent
    ///    towards the disk's, `(1−t)·k̃_free + t·k̃_disk` for t = 1/8, 1/4, 1/2, 1 (BFF's free
    ///    boundary is not guaranteed globally injective, e.g. the beetle), the first valid wins;
    /// 2. with [`FlattenOptions::embedding_fallback`], [`BffSolver::flatten_tutte`].
    ///
    /// Every attempt reuses the factorisations but the last, which needs one of its own. If none
    /// is valid, the first attempt's result is returned (its error names what went wrong).
    pub fn flatten(&self) -> Result<Flattening, FlattenError> {
        let valid = |r: &Result<Flattening, FlattenError>| matches!(r, Ok(f) if f.quality.flipped_triangles == 0 && f.quality.boundary_valid);
        let first = match self.options.boundary {
            BoundaryTarget::Disk => self.flatten_disk(),
            BoundaryTarget::Free => {
                let (u, k_free) = self.free_solve(&vec![0.0; self.outer.len()]);
                let free = self.layout(&u, &k_free, BoundaryTarget::Free);
                if valid(&free) || !self.options.disk_fallback {
                    free
                } else {
                    let k_disk = self.disk_curvature();
                    for t in [0.125, 0.25, 0.5, 1.0] {
                        let k: Vec<f64> = k_free.iter().zip(&k_disk).map(|(f, d)| (1.0 - t) * f + t * d).collect();
                        let blended = self.flatten_with_curvature(&k).map(|f| Flattening {
                            disk_blend: t,
                            method: FlattenMethod::DiskBlend,
                            ..f
                        });
                        if valid(&blended) {
                            return blended;
                        }
                    }
                    free
                }
            }
        };
        if valid(&first) || !self.options.embedding_fallback {
            return first;
        }
        let tutte = self.flatten_tutte();
        if valid(&tutte) {
            tutte
        } else {
            first
        }
    }

    /// The last-resort layout: a convex-combination embedding (Tutte 1963; Floater 1997,
    /// "Parametrization and smooth approximation of surface triangulations") of the hole-filled
    /// disk. The outer loop is the closed curve of the disk target (BFF §5.2: exterior angles
    /// `2π·(dual length)/L`, all positive, so the loop is strictly convex) and the interior is its
    /// harmonic extension with the cotan weights clamped to at least [`TUTTE_MIN_WEIGHT`]. With
    /// positive weights and a convex boundary the map of a triangulated disk is an embedding
    /// (Floater's theorem), whatever the geometry: every triangle keeps its orientation and the
    /// holes' rims, interior curves of the disk, stay simple, disjoint and inside. Away from
    /// obtuse triangles the weights are the cotan ones, so the map stays nearly conformal there.
    /// Factorises the clamped Dirichlet block (one more Cholesky factorisation).
    pub fn flatten_tutte(&self) -> Result<Flattening, FlattenError> {
        let k_disk = self.disk_curvature();
        let u = self.neumann_scale_factors(&k_disk);
        let gamma = self.boundary_curve(&u, &k_disk)?;
        let clamped: Vec<(u32, u32, f64)> =
            self.weights.iter().map(|&(i, j, w)| (i, j, w.max(TUTTE_MIN_WEIGHT))).collect();
        let unknown: Vec<Option<usize>> =
            self.interior_index.iter().map(|&i| (i != NONE).then_some(i as usize)).collect();
        let solver = if self.interior.is_empty() {
            None
        } else {
            Some(SparseCholesky::laplacian(&clamped, &unknown, self.interior.len(), &self.order)?)
        };
        let a = self.extend_harmonic_with(&clamped, solver.as_ref(), &gamma.iter().map(|g| g.x).collect::<Vec<_>>());
        let b = self.extend_harmonic_with(&clamped, solver.as_ref(), &gamma.iter().map(|g| g.y).collect::<Vec<_>>());
        self.finish(&a, &b, BoundaryTarget::Disk, FlattenMethod::Tutte, 1.0)
    }

    /// Flattening with prescribed log scale factors `u` on the outer-loop vertices (in loop
    /// order); `u = 0` is the free boundary of minimal area distortion (BFF §5.1). Reuses the
    /// factorisations; no disk fallback.
    pub fn flatten_with_scale_factors(&self, u_boundary: &[f64]) -> Result<Flattening, FlattenError> {
        let nb = self.outer.len();
        if u_boundary.len() != nb {
            return Err(FlattenError::BoundaryDataLength { expected: nb, got: u_boundary.len() });
        }
        let (u, k_target) = self.free_solve(u_boundary);
        self.layout(&u, &k_target, BoundaryTarget::Free)
    }

    /// Steps 1–2 for given boundary scale factors: Yamabe with flat target
    /// `A_II u_I = −Ω_I − A_IB u_B`, then the Dirichlet-to-Neumann map: boundary flux
    /// `h = (A u)_B` and target exterior angles `k̃ = k + h`. Returns (u, k̃).
    fn free_solve(&self, u_boundary: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut u = vec![0.0; self.n_all];
        for (j, &v) in self.outer.iter().enumerate() {
            u[v as usize] = u_boundary[j];
        }
        let au = self.apply_laplacian(&u);
        let mut rhs: Vec<f64> = self.interior.iter().zip(&self.omega).map(|(&v, &om)| -om - au[v as usize]).collect();
        self.solve_interior(&mut rhs);
        for (&v, &x) in self.interior.iter().zip(&rhs) {
            u[v as usize] = x;
        }
        let au = self.apply_laplacian(&u);
        let k_target = self.outer.iter().zip(&self.k).map(|(&v, &k)| k + au[v as usize]).collect();
        (u, k_target)
    }

    /// Flattening onto a convex, nearly circular outer loop (BFF §5.2): the exterior angles of
    /// [`BffSolver::flatten_with_curvature`] set to `2π·(dual length)/L`.
    pub fn flatten_disk(&self) -> Result<Flattening, FlattenError> {
        self.flatten_with_curvature(&self.disk_curvature())
    }

    /// Exterior angles of the disk target: `2π·(dual length)/L`.
    fn disk_curvature(&self) -> Vec<f64> {
        let nb = self.outer.len();
        let total: f64 = self.lengths.iter().sum();
        (0..nb).map(|j| PI * (self.lengths[(j + nb - 1) % nb] + self.lengths[j]) / total).collect()
    }

    /// Flattening with prescribed exterior angles `k̃` at the outer-loop vertices (loop order,
    /// summing to 2π): the scale factors come from the Neumann-to-Dirichlet map (BFF §5.2).
    /// Uses the Neumann factorisation. [`BoundaryTarget::Disk`] is this with `2π·(dual length)/L`.
    pub fn flatten_with_curvature(&self, k_target: &[f64]) -> Result<Flattening, FlattenError> {
        let nb = self.outer.len();
        if k_target.len() != nb {
            return Err(FlattenError::BoundaryDataLength { expected: nb, got: k_target.len() });
        }
        let sum: f64 = k_target.iter().sum();
        if !((sum - 2.0 * PI).abs() < 1e-6) {
            return Err(FlattenError::InvalidOption(format!("target exterior angles sum to {sum}, not 2π")));
        }
        let u = self.neumann_scale_factors(k_target);
        self.layout(&u, k_target, BoundaryTarget::Disk)
    }

    /// Scale factors for prescribed exterior angles `k̃` (Neumann-to-Dirichlet map, BFF §5.2):
    /// `A u = (−Ω_I, k̃ − k)`, compatible by Gauss–Bonnet; `u(outer[0]) = 0` fixes the constant.
    fn neumann_scale_factors(&self, k_target: &[f64]) -> Vec<f64> {
        let mut rhs = vec![0.0; self.n_all];
        for (&v, &om) in self.interior.iter().zip(&self.omega) {
            rhs[v as usize] = -om;
        }
        for (j, &v) in self.outer.iter().enumerate() {
            rhs[v as usize] = k_target[j] - self.k[j];
        }
        let pinned = self.outer[0] as usize;
        rhs.remove(pinned);
        self.neumann.solve_in_place(&mut rhs);
        rhs.insert(pinned, 0.0);
        rhs
    }

    /// Step 3: the boundary curve integrated from the target lengths `ℓ̃ = e^{(u_i+u_j)/2} ℓ` and
    /// exterior angles `k̃`, closed by the minimal change of lengths (BFF §4.3).
    fn boundary_curve(&self, u: &[f64], k_target: &[f64]) -> Result<Vec<DVec2>, FlattenError> {
        let nb = self.outer.len();
        let mut tangents = Vec::with_capacity(nb);
        let mut phi = 0.0;
        let mut target_len = Vec::with_capacity(nb);
        for (j, &kj) in k_target.iter().enumerate() {
            let (a, b) = (self.outer[j] as usize, self.outer[(j + 1) % nb] as usize);
            if j > 0 {
                phi += kj;
            }
            tangents.push(DVec2::new(num::cos(phi), num::sin(phi)));
            target_len.push(num::exp(0.5 * (u[a] + u[b])) * self.lengths[j]);
        }
        close_polygon(&tangents, &target_len, &self.lengths).map_err(|edge| FlattenError::BoundaryClosure { edge })
    }

    /// Steps 3–5: integrate and close the boundary curve, extend it, normalise, measure, check.
    fn layout(&self, u: &[f64], k_target: &[f64], target: BoundaryTarget) -> Result<Flattening, FlattenError> {
        let nb = self.outer.len();
        let gamma = self.boundary_curve(u, k_target)?;

        // 4. Extend to the interior.
        let gx: Vec<f64> = gamma.iter().map(|g| g.x).collect();
        let a = self.extend_harmonic(&gx);
        let b = match self.options.extension {
            Extension::Conjugate => {
                let neumann = &self.neumann;
                // Harmonic conjugate: ∂b/∂n = −∂a/∂t, so (A b)_i = −(a_next − a_prev)/2 on the
                // boundary and 0 inside; b(outer[0]) = 0 fixes the constant.
                let pinned = self.outer[0] as usize;
                let mut rhs = vec![0.0; self.n_all];
                for j in 0..nb {
                    let next = self.outer[(j + 1) % nb] as usize;
                    let prev = self.outer[(j + nb - 1) % nb] as usize;
                    rhs[self.outer[j] as usize] = -0.5 * (a[next] - a[prev]);
                }
                rhs.remove(pinned);
                neumann.solve_in_place(&mut rhs);
                rhs.insert(pinned, 0.0);
                rhs
            }
            Extension::Harmonic => {
                let gy: Vec<f64> = gamma.iter().map(|g| g.y).collect();
                self.extend_harmonic(&gy)
            }
        };

        let disk_blend = if target == BoundaryTarget::Disk { 1.0 } else { 0.0 };
        self.finish(&a, &b, target, FlattenMethod::Bff, disk_blend)
    }

    /// Step 5 on the coordinates `a`, `b` of the filled disk: real vertices only, equal total
    /// area, area centroid at the origin; then measure and check.
    fn finish(
        &self,
        a: &[f64],
        b: &[f64],
        target: BoundaryTarget,
        method: FlattenMethod,
        disk_blend: f64,
    ) -> Result<Flattening, FlattenError> {
        let n_real = self.positions.len();
        let mut uv: Vec<DVec2> = (0..n_real).map(|v| DVec2::new(a[v], b[v])).collect();
        if uv.iter().any(|p| !p.is_finite()) {
            return Err(FlattenError::NonFiniteSolution);
        }
        let (mut area2d, mut moment) = (0.0, DVec2::ZERO);
        for t in &self.triangles {
            let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            let ar = 0.5 * (p1 - p0).perp_dot(p2 - p0);
            area2d += ar;
            moment += ar * (p0 + p1 + p2) / 3.0;
        }
        if !(area2d > 0.0) {
            return Err(FlattenError::FlippedTriangles { count: self.triangles.len() });
        }
        let centre = moment / area2d;
        let s = (self.area3d / area2d).sqrt();
        for p in &mut uv {
            *p = (*p - centre) * s;
        }

        let q = quality(&self.positions, &self.triangles, &self.loops, &uv);
        if self.options.check {
            check(&uv, &self.triangles, &self.loops)?;
        }
        Ok(Flattening { uv, quality: q, method, hole_fills: self.hole_fills, boundary: target, disk_blend })
    }

    fn solve_interior(&self, rhs: &mut [f64]) {
        if let Some(aii) = &self.aii {
            aii.solve_in_place(rhs);
        }
    }

    /// `y = A x` with the (positive semi-definite) cotan Laplacian of the filled disk.
    fn apply_laplacian(&self, x: &[f64]) -> Vec<f64> {
        apply_weights(&self.weights, x)
    }

    /// Harmonic extension of outer-loop values `g` (loop order): `A_II x_I = −A_IB g`.
    fn extend_harmonic(&self, g: &[f64]) -> Vec<f64> {
        self.extend_harmonic_with(&self.weights, self.aii.as_ref(), g)
    }

    /// [`Self::extend_harmonic`] with other edge weights on the same graph and `aii` their
    /// factorised Dirichlet block.
    fn extend_harmonic_with(&self, weights: &[(u32, u32, f64)], aii: Option<&SparseCholesky>, g: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.n_all];
        for (j, &v) in self.outer.iter().enumerate() {
            x[v as usize] = g[j];
        }
        let ax = apply_weights(weights, &x);
        let mut rhs: Vec<f64> = self.interior.iter().map(|&v| -ax[v as usize]).collect();
        if let Some(aii) = aii {
            aii.solve_in_place(&mut rhs);
        }
        for (&v, &xi) in self.interior.iter().zip(&rhs) {
            x[v as usize] = xi;
        }
        x
    }
}

/// `y = L x` with the (positive semi-definite) Laplacian of the edge `weights`.
fn apply_weights(weights: &[(u32, u32, f64)], x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; x.len()];
    for &(i, j, w) in weights {
        let d = w * (x[i as usize] - x[j as usize]);
        y[i as usize] += d;
        y[j as usize] -= d;
    }
    y
}

fn tri_area3(p: &[DVec3], t: [u32; 3]) -> f64 {
    let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
    0.5 * (b - a).cross(c - a).length()
}

fn is_degenerate(p: &[DVec3], t: [u32; 3], rel: f64) -> bool {
    let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
    let lmax = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    let area = 0.5 * (b - a).cross(c - a).length();
    !(area > rel * lmax)
}

/// Checks the module preconditions; each fault is a typed error naming it.
fn validate(input: FlattenInput<'_>, degenerate_rel: f64) -> Result<(), FlattenError> {
    let n = input.positions.len();
    if input.triangles.is_empty() {
        return Err(FlattenError::NoTriangles);
    }
    if input.loops.is_empty() {
        return Err(FlattenError::NoBoundary);
    }
    if let Some(v) = input.positions.iter().position(|p| !p.is_finite()) {
        return Err(FlattenError::NonFinite { vertex: v });
    }
    let mut used = vec![false; n];
    for (f, t) in input.triangles.iter().enumerate() {
        for &v in t {
            if v as usize >= n {
                return Err(FlattenError::IndexOutOfRange { face: f, vertex: v, vertices: n });
            }
            used[v as usize] = true;
        }
        if is_degenerate(input.positions, *t, degenerate_rel) {
            return Err(FlattenError::DegenerateTriangle { face: f });
        }
    }
    if let Some(v) = used.iter().position(|&u| !u) {
        return Err(FlattenError::UnusedVertex { vertex: v });
    }

    // Directed half-edges: each at most once (manifold, consistently oriented).
    let mut half: Vec<(u32, u32)> = Vec::with_capacity(3 * input.triangles.len());
    for t in input.triangles {
        for c in 0..3 {
            half.push((t[c], t[(c + 1) % 3]));
        }
    }
    half.sort_unstable();
    if let Some(w) = half.windows(2).find(|w| w[0] == w[1]) {
        return Err(FlattenError::BadEdge { a: w[0].0, b: w[0].1 });
    }
    let has = |a: u32, b: u32| half.binary_search(&(a, b)).is_ok();
    let boundary_edges = half.iter().filter(|&&(a, b)| !has(b, a)).count();

    let mut in_loop = vec![false; n];
    let mut covered = 0;
    for (li, lp) in input.loops.iter().enumerate() {
        let bad = |reason: String| FlattenError::InvalidLoop { loop_index: li, reason };
        if lp.len() < 3 {
            return Err(bad(format!("it has {} vertices (at least 3 needed)", lp.len())));
        }
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            if a as usize >= n {
                return Err(bad(format!("vertex {a} out of range")));
            }
            if in_loop[a as usize] {
                return Err(bad(format!("vertex {a} appears twice in the loops (pinch vertex)")));
            }
            in_loop[a as usize] = true;
            if !has(a, b) || has(b, a) {
                return Err(bad(format!("{a}→{b} is not a boundary edge traversed with the surface on its left")));
            }
            covered += 1;
        }
    }
    if covered != boundary_edges {
        return Err(FlattenError::LoopsIncomplete { covered, boundary_edges });
    }

    // One component (union-find) and χ = 2 − #loops (genus 0).
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for t in input.triangles {
        for c in 1..3 {
            let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[c]));
            parent[a as usize] = b;
        }
    }
    let root = find(&mut parent, 0);
    let connected = (0..n as u32).all(|v| find(&mut parent, v) == root);
    let edges = (half.len() + boundary_edges) / 2;
    let euler = n as i64 - edges as i64 + input.triangles.len() as i64;
    let expected = 2 - input.loops.len() as i64;
    if !connected || euler != expected {
        return Err(FlattenError::NotDiskWithHoles { euler, loops: input.loops.len(), expected });
    }
    Ok(())
}

/// Closes the polygon with edge directions `tangents` and wanted lengths `target` by the minimal
/// change of lengths in the norm `Σ (ℓ* − ℓ̃)² / ℓ` (BFF §4.3, `mass` = ℓ); returns the vertices
/// (the first at the origin), or the first edge whose closed length is not positive.
pub(super) fn close_polygon(tangents: &[DVec2], target: &[f64], mass: &[f64]) -> Result<Vec<DVec2>, usize> {
    let (mut m, mut r) = ([0.0f64; 3], DVec2::ZERO);
    for ((t, &lt), &l) in tangents.iter().zip(target).zip(mass) {
        m[0] += l * t.x * t.x;
        m[1] += l * t.x * t.y;
        m[2] += l * t.y * t.y;
        r += lt * *t;
    }
    let det = m[0] * m[2] - m[1] * m[1];
    let lambda = DVec2::new(m[2] * r.x - m[1] * r.y, m[0] * r.y - m[1] * r.x) / det;
    let mut out = Vec::with_capacity(tangents.len());
    let mut p = DVec2::ZERO;
    for (j, ((t, &lt), &l)) in tangents.iter().zip(target).zip(mass).enumerate() {
        let len = lt - l * t.dot(lambda);
        if !(len > 0.0 && len.is_finite()) {
            return Err(j);
        }
        out.push(p);
        p += len * *t;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_polygon_closes_with_small_changes() {
        // A unit square whose last edge is 10 % too long.
        let t = [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y];
        let p = close_polygon(&t, &[1.0, 1.0, 1.0, 1.1], &[1.0; 4]).unwrap();
        let end = p[3] + (1.1 - 0.05) * t[3];
        assert!(end.length() < 1e-15, "{end}");
        assert!((p[2] - DVec2::new(1.0, 1.05)).length() < 1e-15);
        // Impossible: all edges the same way.
        assert!(close_polygon(&[DVec2::X; 3], &[1.0; 3], &[1.0; 3]).is_err());
    }
}
