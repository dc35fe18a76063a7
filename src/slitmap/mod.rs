//! Conformal slit map of a flattened multiply connected domain, with a continuous pole.
//!
//! # What it computes
//! Given a planar triangulated domain S^F (the output of `flatten`) bounded by an outer loop Γ0
//! and holes Γ1..Γm, and a pole p (any point of the plane not on a boundary and not outside Γ0),
//! it computes per vertex the image w = F(z) of the conformal slit map (seed 000 §2.1):
//!
//! * p inside the domain → **disk map**: Γ0 → unit circle, every hole → an arc slit |w| = e^{c_i},
//!   F(p) = 0.
//! * p inside hole j (in the plane region Γj encloses) → **annulus map**: Γ0 → unit circle,
//!   Γj → inner circle of radius R_A = e^{c_j} < 1, the other holes → arc slits. Every pole in the
//!   same hole gives the same exact map (with the rotation fixed below). The discrete map is
//!   most accurate for a pole far from the hole's boundary, so by default it is computed with a
//!   canonical pole of the hole ([`SlitMapOptions::annulus_canonical_pole`]) and is then exactly
//!   independent of where in the hole the pole is.
//!
//! # Formulation (DESIGN.md, "slitmap")
//! Solve for h harmonic with h = −log|z−p| on Γ0 and h = c_i − log|z−p| on Γi, the constants c_i
//! unknown and fixed by zero total flux of ∇h through each Γi. With P1 elements this is the cotan
//! Laplacian with Γ0 eliminated (Dirichlet) and each hole's vertices merged into one unknown
//! (the merged row is exactly the zero-flux condition), so the matrix does not depend on p and is
//! factorised once in [`SlitMapSolver::new`]. θ_h, the harmonic conjugate of h, is the least-squares
//! solution of ∇θ_h ≈ J∇h (a Neumann cotan Laplacian with one vertex fixed, also factorised once).
//! It is single-valued because the flux of h through every hole is zero. Then
//!
//! ```text
//!     F(z) = (z − p) · exp(h(z) + i θ_h(z)) · e^{iφ}
//! ```
//!
//! per vertex. |F| = 1 on Γ0 and |F| = e^{c_i} on Γi hold exactly at boundary vertices (up to
//! rounding), whatever the mesh resolution. The pole is continuous: no vertex, no removed face;
//! log|z−p| is subtracted analytically so h is smooth right up to p.
//!
//! **Annulus mode** (p in hole j): log|z − p| is harmonic in the domain, so U = log|w| is solved
//! for directly with the same factorised matrix: U = 0 on Γ0, a constant on each hole, zero
//! flux through every hole but j and 2π through Γj (a unit source on hole j's merged unknown).
//! U is then exactly discrete harmonic, and the Delaunay weights give it the discrete maximum
//! principle, which holds even where the map crowds a far part of the domain into a band near
//! |w| = 1 thinner than the P1 error of log|z − p| (the h formulation folded 794 faces there on
//! featuretype). arg w = V is the conjugate of U: Neumann on every loop, period 2π round Γj; it
//! is solved as V = arg(z − p) + θ_h with the same Neumann matrix (see `annulus_rhs`). Both
//! depend on p only through rounding.
//!
//! **Rotation** (the constant of θ_h): φ is chosen so that arg w of the first vertex of the outer
//! loop, `loops[0][0]`, is exactly 0.
//!
//! # Preconditions
//! * planar domain, triangles counter-clockwise (positive signed area) and not degenerate;
//! * `loops[0]` is the outer boundary, counter-clockwise; `loops[1..]` are the holes, clockwise
//!   (the domain is on the left of every loop); every loop is a closed simple polygon of boundary
//!   vertices listed once (the closing edge is implied);
//! * the mesh is connected and every vertex belongs to a triangle.
//!
//! These are checked in [`SlitMapSolver::new`] (except simplicity of the loops and that they are
//! exactly the mesh boundary) and reported as [`SlitMapError`]s.
//!
//! # Invariants of the output
//! |w| = 1 on Γ0 vertices, |w| constant on each hole's vertices (to rounding), |w| ≤ 1 elsewhere
//! (discrete maximum principle up to discretisation error), slits at distinct radii or disjoint
//! angular extents.
//!
//! **Folds.** A P1 map can fold image triangles in three known places:
//! * at a slit tip: F has a critical point on the hole boundary there (the boundary folds back
//!   along the arc), so image triangles within an edge of the tip are as small as the P1 error;
//! * sliver triangles, and "ears" of the outer loop (three outer-loop vertices);
//! * under crowding, in disk mode: for a pole near one end of a long part, the far end maps to a
//!   band near |w| = 1 thinner than the P1 error of log|z − p| (annulus mode solves for U and V
//!   directly and keeps them exactly discrete harmonic there).
//!
//! **Disk far field.** Where the plain disk formulation folds, the map is solved again with
//! U = log|w| and V = arg w discrete harmonic away from the pole, as in annulus mode, and the
//! singular part subtracted only near it ([`SlitMapOptions::disk_near_factor`]); the map that
//! folds fewer faces is kept. Poles 1–5 % of the diagonal from a boundary of the shared meshes
//! folded 71 maps of 454 before and 6 after (`tests/conformal_pipeline.rs`).
//!
//! Three measures remove the first two: the planner refines hole rims so every hole vertex has
//! enough faces to open by 2π, splits ears, and remeshes flat regions full of needles
//! (`mesh::refine`, `mesh::quality`, pole-independent); both Laplacians are assembled
//! on the Delaunay triangulation of the same vertices (`delaunay`: non-negative cotan weights,
//! so the discrete maximum principle holds for h); and `untangle` moves the vertices of the few
//! remaining folded triangles by the least amount that unfolds them, boundary vertices along
//! their circles, so every boundary invariant above is kept exactly. The far field removes most
//! crowding; what remains (a narrow neck crowding a whole part) is counted by
//! [`SlitMap::flipped_faces`].
//!
//! # Determinism
//! Both factorisations and every solve run in [`crate::linalg`]'s scalar code and all
//! transcendental functions go through [`crate::num`], so `w` has the same bits natively and in
//! wasm (`tests/determinism.rs` and `tests/wasm.rs` check digests of it).
//!
//! The inverse map (slit domain → mesh) is point location in the image triangles plus barycentric
//! interpolation ([`InverseMap`], seed 000 §2.1); [`SlitMap::log_polar_corners`] gives the
//! log-polar coordinates (arg w, |w|) of seed 000 eq. 7 per triangle corner.

pub(crate) mod delaunay;
mod inverse;
mod untangle;

pub(crate) use inverse::{barycentric, clamp_barycentric};
pub use inverse::{InverseMap, Location};

use crate::linalg::{cotan_weights_2d, mesh_order, LinalgError, SparseCholesky};
use crate::num::{self, wrap_pi};
use glam::DVec2;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// A flattened domain: 2D position per vertex, triangles, boundary loops.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanarDomain {
    /// Planar coordinate z per vertex.
    pub positions: Vec<DVec2>,
    /// Counter-clockwise triangles (vertex indices).
    pub triangles: Vec<[u32; 3]>,
    /// `loops[0]`: outer boundary Γ0 (counter-clockwise); `loops[1..]`: holes Γ1..Γm (clockwise).
    pub loops: Vec<Vec<u32>>,
}

impl PlanarDomain {
    /// The flattened domain of a surface: its triangles and loops with the 2D positions `uv`
    /// (one per surface vertex, e.g. [`crate::flatten::Flattening::uv`]).
    pub fn of_surface(surface: &crate::mesh::Surface, uv: Vec<DVec2>) -> Self {
        Self { positions: uv, triangles: surface.triangles.clone(), loops: surface.loops.clone() }
    }

    /// The centre of the largest triangle: a point well inside the domain, whatever its shape.
    pub fn largest_face_centre(&self) -> DVec2 {
        let area = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|v| self.positions[v as usize]);
            (b - a).perp_dot(c - a)
        };
        let t = self.triangles.iter().max_by(|a, b| area(a).total_cmp(&area(b))).expect("a domain has triangles");
        t.iter().map(|&v| self.positions[v as usize]).sum::<DVec2>() / 3.0
    }

    /// Builds a domain from positions and counter-clockwise triangles, finding the boundary loops
    /// from the half-edges without a twin. Each loop runs with the domain on its left (outer
    /// counter-clockwise, holes clockwise) and starts at its smallest vertex index; the loop with
    /// the largest signed area is the outer one (`loops[0]`), the holes follow ordered by their
    /// smallest vertex (deterministic).
    pub fn from_triangles(positions: Vec<DVec2>, triangles: Vec<[u32; 3]>) -> Result<Self, SlitMapError> {
        let n = positions.len();
        let mut half: Vec<(u32, u32)> = Vec::with_capacity(triangles.len() * 3);
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                if t[k] as usize >= n {
                    return Err(SlitMapError::TriangleIndexOutOfRange { face: f, vertex: t[k], n_vertices: n });
                }
                half.push((t[k], t[(k + 1) % 3]));
            }
        }
        half.sort_unstable();
        let mut next: Vec<Option<u32>> = vec![None; n];
        for &(a, b) in &half {
            if half.binary_search(&(b, a)).is_err() {
                if next[a as usize].is_some() {
                    return Err(SlitMapError::NonManifoldBoundary { vertex: a });
                }
                next[a as usize] = Some(b);
            }
        }
        let mut visited = vec![false; n];
        let mut loops: Vec<Vec<u32>> = Vec::new();
        for start in 0..n {
            if visited[start] || next[start].is_none() {
                continue;
            }
            let mut lp = vec![start as u32];
            visited[start] = true;
            let mut v = start;
            while let Some(nv) = next[v] {
                let nv = nv as usize;
                if nv == start {
                    break;
                }
                if visited[nv] {
                    return Err(SlitMapError::NonManifoldBoundary { vertex: nv as u32 });
                }
                visited[nv] = true;
                lp.push(nv as u32);
                v = nv;
            }
            if next[v] != Some(start as u32) {
                return Err(SlitMapError::NonManifoldBoundary { vertex: v as u32 });
            }
            loops.push(lp);
        }
        if loops.is_empty() {
            return Err(SlitMapError::NoOuterLoop);
        }
        let outer = (0..loops.len())
            .max_by(|&a, &b| {
                polygon_signed_area(&positions, &loops[a])
                    .total_cmp(&polygon_signed_area(&positions, &loops[b]))
                    .then(b.cmp(&a))
            })
            .expect("at least one loop");
        let o = loops.remove(outer);
        loops.insert(0, o);
        Ok(Self { positions, triangles, loops })
    }
}

/// Options of the slit map.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SlitMapOptions {
    /// A pole closer than this fraction of the domain's bounding-box diagonal to a boundary loop
    /// is rejected ([`SlitMapError::PoleOnBoundary`]): log|z − p| would blow up at a boundary
    /// vertex. Default 1e-9.
    pub boundary_tolerance_rel: f64,
    /// A triangle with |signed area| below this fraction of the squared bounding-box diagonal is
    /// degenerate ([`SlitMapError::DegenerateTriangle`]). Default 1e-14.
    pub degenerate_area_rel: f64,
    /// Check that the outer loop is counter-clockwise and holes clockwise. Default true.
    pub check_loop_orientation: bool,
    /// Annulus mode: solve with a canonical pole of the hole (an approximate centre of its largest
    /// inscribed circle, computed once per hole) instead of the given one. Every pole in a hole
    /// gives the same map up to rounding; this makes it the same bit for bit. Default true.
    pub annulus_canonical_pole: bool,
    /// Move the vertices of folded image triangles (slit tips, slivers) the least amount that
    /// unfolds them, boundary vertices along their circles (see `untangle`). Default true.
    pub untangle: bool,
    /// Disk mode, when the plain formulation folds faces: the far field is tried, where the
    /// singular part log|z − p| enters the equations of log|w| only within this multiple r of
    /// the pole's distance to the nearest boundary (at least two edges of the pole's face),
    /// blending out to 2r; farther out log|w| and arg w are kept exactly discrete harmonic, as in
    /// annulus mode, so a pole near one end of a long part does not fold the far end. The map
    /// folding fewer faces is kept. Infinity turns the far field off. Default 3: of 454 poles
    /// near the shared meshes' boundaries, 6 fold (7 with 2 or 4, 12 with 6, 71 without).
    pub disk_near_factor: f64,
}

impl Default for SlitMapOptions {
    fn default() -> Self {
        Self {
            boundary_tolerance_rel: 1e-9,
            degenerate_area_rel: 1e-14,
            check_loop_orientation: true,
            annulus_canonical_pole: true,
            untangle: true,
            disk_near_factor: 3.0,
        }
    }
}

/// Errors of the slit map; each names what is at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SlitMapError {
    #[error("domain has no vertices or no triangles")]
    EmptyDomain,
    #[error("domain has no boundary loop: loops[0] must be the outer boundary")]
    NoOuterLoop,
    #[error("vertex {vertex} has a non-finite position")]
    NonFinitePosition { vertex: usize },
    #[error("triangle {face} refers to vertex {vertex}, but there are only {n_vertices} vertices")]
    TriangleIndexOutOfRange { face: usize, vertex: u32, n_vertices: usize },
    #[error("loop {loop_index} refers to vertex {vertex}, but there are only {n_vertices} vertices")]
    LoopIndexOutOfRange { loop_index: usize, vertex: u32, n_vertices: usize },
    #[error("triangle {face} is degenerate (signed area {area:e})")]
    DegenerateTriangle { face: usize, area: f64 },
    #[error("triangle {face} is clockwise (signed area {area:e}): the flattening flipped it")]
    FlippedTriangle { face: usize, area: f64 },
    #[error("vertex {vertex} is used by no triangle")]
    UnusedVertex { vertex: usize },
    #[error("boundary is not a set of simple loops at vertex {vertex} (two boundary edges leave it, or a loop does not close)")]
    NonManifoldBoundary { vertex: u32 },
    #[error("loop {loop_index} has {len} vertices; a loop needs at least 3")]
    LoopTooShort { loop_index: usize, len: usize },
    #[error("vertex {vertex} appears more than once in the boundary loops (loops {first} and {second})")]
    VertexInTwoLoops { vertex: u32, first: usize, second: usize },
    #[error("loop {loop_index} has signed area {signed_area:e}; expected {expected} (outer loop counter-clockwise, holes clockwise)")]
    LoopOrientation { loop_index: usize, signed_area: f64, expected: &'static str },
    #[error("pole ({}, {}) is not finite", pole.x, pole.y)]
    NonFinitePole { pole: DVec2 },
    #[error("pole ({}, {}) lies outside the outer boundary: choose a pole inside the domain (disk map) or inside a hole (annulus map)", pole.x, pole.y)]
    PoleOutside { pole: DVec2 },
    #[error("pole ({}, {}) lies on boundary loop {loop_index} (distance {distance:e}): move it inside the domain or a hole", pole.x, pole.y)]
    PoleOnBoundary { pole: DVec2, loop_index: usize, distance: f64 },
    #[error("factorisation failed: {0}")]
    Factorisation(#[from] LinalgError),
    #[error("the map is not finite at vertex {vertex}")]
    NonFiniteResult { vertex: usize },
}

/// Which canonical domain the map goes to.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// Unit disk with arc slits; the pole maps to 0.
    Disk,
    /// Annulus `inner_radius < |w| < 1` with arc slits; `hole` (index into `loops`, ≥ 1) maps to
    /// the inner circle.
    Annulus { hole: usize, inner_radius: f64 },
}

impl Mode {
    /// |w| of the domain's inner end: the annulus' inner circle, 0 (the pole) for the disk.
    pub fn inner_radius(self) -> f64 {
        match self {
            Mode::Disk => 0.0,
            Mode::Annulus { inner_radius, .. } => inner_radius,
        }
    }
}

/// An arc slit: the image of a hole, `{radius · e^{iθ} : θ ∈ [theta_start, theta_end]}` with
/// `theta_start ∈ [−π, π)` and `theta_start ≤ theta_end < theta_start + 2π` (so an arc across
/// the ±π cut has `theta_end > π`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Slit {
    /// Index into `loops` (≥ 1).
    pub hole: usize,
    pub radius: f64,
    pub theta_start: f64,
    pub theta_end: f64,
}

impl Slit {
    /// Angular extent θ_end − θ_start.
    pub fn extent(&self) -> f64 {
        self.theta_end - self.theta_start
    }
    /// Whether angle `theta` (any branch) lies on the slit's angular range.
    pub fn contains_angle(&self, theta: f64) -> bool {
        let d = num::rem_tau(theta - self.theta_start);
        d <= self.extent()
    }
}

/// The slit map for one pole.
#[derive(Debug, Clone)]
pub struct SlitMap {
    /// Complex image w = F(z) per vertex (x = Re, y = Im).
    pub w: Vec<DVec2>,
    pub mode: Mode,
    /// One arc slit per hole except the annulus hole, in hole order.
    pub slits: Vec<Slit>,
    /// The pole asked for.
    pub pole: DVec2,
    /// The pole the map was computed with: `pole`, or in annulus mode with
    /// [`SlitMapOptions::annulus_canonical_pole`] the hole's canonical pole.
    pub solve_pole: DVec2,
    /// Disk mode: the face whose planar triangle contains the pole (its image contains 0).
    pub pole_face: Option<usize>,
    /// log of the image radius of each hole, `hole_log_radius[i - 1] = c_i` for loop i ≥ 1.
    pub hole_log_radius: Vec<f64>,
    triangles: Arc<Vec<[u32; 3]>>,
}

impl SlitMap {
    /// The triangles the map is defined on (shared with the solver, not copied).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Signed area of every image triangle (positive = orientation preserved).
    pub fn image_signed_areas(&self) -> Vec<f64> {
        self.signed_areas().collect()
    }

    fn signed_areas(&self) -> impl Iterator<Item = f64> + '_ {
        self.triangles.iter().map(|t| {
            let (a, b, c) = (self.w[t[0] as usize], self.w[t[1] as usize], self.w[t[2] as usize]);
            0.5 * (b - a).perp_dot(c - a)
        })
    }

    /// Number of image triangles with non-positive signed area (no allocation: the origin search
    /// counts them at every pole).
    pub fn flipped_triangles(&self) -> usize {
        count_folds(&self.w, &self.triangles)
    }

    /// Faces whose image has non-positive signed area (see the module docs for where P1 flips
    /// are expected: slit tips and crowded regions).
    pub fn flipped_faces(&self) -> Vec<usize> {
        self.signed_areas().enumerate().filter(|&(_, a)| a <= 0.0).map(|(f, _)| f).collect()
    }

    /// Log-polar coordinates (seed 000 eq. 7) per triangle corner: `x` = arg w, unwrapped
    /// consistently within the triangle (corner 0 in (−π, π], the others within π of it), `y` =
    /// |w|. For the pole face of the disk map (see [`SlitMap::pole_face`]) arg w is meaningless:
    /// its corners still get values but callers must treat that face specially.
    pub fn log_polar_corners(&self) -> Vec<[DVec2; 3]> {
        self.triangles
            .iter()
            .map(|t| {
                let w0 = self.w[t[0] as usize];
                let a0 = num::arg(w0);
                let mut out = [DVec2::new(a0, w0.length()); 3];
                for k in 1..3 {
                    let wk = self.w[t[k] as usize];
                    let ak = num::arg(wk);
                    out[k] = DVec2::new(a0 + wrap_pi(ak - a0), wk.length());
                }
                out
            })
            .collect()
    }

    /// The same map with every vertex moved along its ray to radius `radii[v]`, angles kept:
    /// seed 003's S^H ([`crate::optimise`]). Each hole's slit, log radius and (annulus) inner
    /// radius follow its loop in `loops` (the surface's boundary loops, whose vertices the caller
    /// moves together): they take the radius of the loop's first vertex.
    ///
    /// # Panics
    /// If `radii` has not one entry per vertex (a programming error).
    pub fn with_radii(&self, radii: &[f64], loops: &[Vec<u32>]) -> SlitMap {
        assert_eq!(radii.len(), self.w.len(), "one radius per vertex");
        let w = self.w.iter().zip(radii).map(|(&w, &r)| w * (r / w.length())).collect();
        let loop_radius = |hole: usize| radii[loops[hole][0] as usize];
        let mode = match self.mode {
            Mode::Disk => Mode::Disk,
            Mode::Annulus { hole, .. } => Mode::Annulus { hole, inner_radius: loop_radius(hole) },
        };
        let slits = self.slits.iter().map(|s| Slit { radius: loop_radius(s.hole), ..*s }).collect();
        let hole_log_radius = (1..loops.len()).map(|hole| num::ln(loop_radius(hole))).collect();
        SlitMap { w, mode, slits, hole_log_radius, triangles: self.triangles.clone(), ..*self }
    }

    /// Spatial index over the image triangles for the inverse map (slit domain → mesh).
    pub fn inverse_map(&self) -> InverseMap {
        InverseMap::new(&self.w, self.triangles.clone())
    }
}

/// Reusable slit-map solver: the p-independent matrices are factorised once.
#[derive(Debug, Clone)]
pub struct SlitMapSolver {
    positions: Vec<DVec2>,
    triangles: Arc<Vec<[u32; 3]>>,
    /// The Delaunay triangulation the Laplacians and the conjugate's right-hand side use.
    fem_triangles: Vec<[u32; 3]>,
    /// Faces around each vertex (CSR, [`crate::mesh::topology::vertex_faces`]), for untangling.
    vertex_faces: (Vec<u32>, Vec<u32>),
    loops: Vec<Vec<u32>>,
    options: SlitMapOptions,
    /// Bounding-box diagonal of the domain (tolerance scale).
    scale: f64,
    /// Unknown of h per vertex: interior vertices individually, each hole's vertices merged, Γ0
    /// eliminated (None).
    h_unknown: Vec<Option<usize>>,
    /// Unknown index of hole loop i (≥ 1) at `hole_unknown[i - 1]`.
    hole_unknown: Vec<usize>,
    /// Boundary vertices (any loop): h's boundary data is non-zero there.
    on_boundary: Vec<bool>,
    /// Edges with at least one boundary endpoint: the only ones feeding h's right-hand side.
    boundary_edges: Vec<(u32, u32, f64)>,
    /// Every edge's cotan weight (Delaunay), for the far-field rows of disk maps.
    weights: Vec<(u32, u32, f64)>,
    h_chol: SparseCholesky,
    /// Unknown of θ_h per vertex; the fixed vertex is None (θ_h = 0 there).
    theta_unknown: Vec<Option<usize>>,
    theta_chol: SparseCholesky,
    /// Canonical pole of hole loop i (≥ 1) at `hole_pole[i - 1]`.
    hole_pole: Vec<DVec2>,
    /// Point location in the flattened plane, for the pole's face (a linear scan cost a 58k-face
    /// part 1.5 ms per pole, a sixth of the origin search).
    plane: inverse::InverseMap,
}

impl SlitMapSolver {
    /// Validates the domain, assembles and factorises both p-independent Laplacians.
    pub fn new(domain: &PlanarDomain, options: &SlitMapOptions) -> Result<Self, SlitMapError> {
        let n = domain.positions.len();
        if n == 0 || domain.triangles.is_empty() {
            return Err(SlitMapError::EmptyDomain);
        }
        if domain.loops.is_empty() {
            return Err(SlitMapError::NoOuterLoop);
        }
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for (v, p) in domain.positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(SlitMapError::NonFinitePosition { vertex: v });
            }
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let scale = (hi - lo).length().max(f64::MIN_POSITIVE);
        let mut used = vec![false; n];
        for (f, t) in domain.triangles.iter().enumerate() {
            for &v in t {
                if v as usize >= n {
                    return Err(SlitMapError::TriangleIndexOutOfRange { face: f, vertex: v, n_vertices: n });
                }
                used[v as usize] = true;
            }
            let (a, b, c) =
                (domain.positions[t[0] as usize], domain.positions[t[1] as usize], domain.positions[t[2] as usize]);
            let area = 0.5 * (b - a).perp_dot(c - a);
            if area.abs() <= options.degenerate_area_rel * scale * scale {
                return Err(SlitMapError::DegenerateTriangle { face: f, area });
            }
            if area < 0.0 {
                return Err(SlitMapError::FlippedTriangle { face: f, area });
            }
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(SlitMapError::UnusedVertex { vertex: v });
        }
        let mut loop_of: Vec<Option<usize>> = vec![None; n];
        for (li, lp) in domain.loops.iter().enumerate() {
            if lp.len() < 3 {
                return Err(SlitMapError::LoopTooShort { loop_index: li, len: lp.len() });
            }
            for &v in lp {
                if v as usize >= n {
                    return Err(SlitMapError::LoopIndexOutOfRange { loop_index: li, vertex: v, n_vertices: n });
                }
                if let Some(first) = loop_of[v as usize] {
                    return Err(SlitMapError::VertexInTwoLoops { vertex: v, first, second: li });
                }
                loop_of[v as usize] = Some(li);
            }
            if options.check_loop_orientation {
                let signed_area = polygon_signed_area(&domain.positions, lp);
                let ok = if li == 0 { signed_area > 0.0 } else { signed_area < 0.0 };
                if !ok {
                    return Err(SlitMapError::LoopOrientation {
                        loop_index: li,
                        signed_area,
                        expected: if li == 0 { "counter-clockwise (positive)" } else { "clockwise (negative)" },
                    });
                }
            }
        }

        // The Laplacians are assembled on the Delaunay triangulation of the same vertices, where
        // every cotan weight is non-negative; the map is still read on the domain's triangles.
        let (fem_triangles, _) = delaunay::delaunay_flip(&domain.positions, &domain.triangles);
        let weights = cotan_weights_2d(&domain.positions, &fem_triangles);

        // (a) h: interior vertices one unknown each, then one unknown per hole.
        let mut h_unknown = vec![None; n];
        let mut next = 0usize;
        for v in 0..n {
            if loop_of[v].is_none() {
                h_unknown[v] = Some(next);
                next += 1;
            }
        }
        let hole_unknown: Vec<usize> = (1..domain.loops.len()).map(|k| next + k - 1).collect();
        for v in 0..n {
            if let Some(li) = loop_of[v] {
                if li >= 1 {
                    h_unknown[v] = Some(hole_unknown[li - 1]);
                }
            }
        }
        let n_h = next + hole_unknown.len();
        let on_boundary: Vec<bool> = loop_of.iter().map(|l| l.is_some()).collect();
        let boundary_edges: Vec<(u32, u32, f64)> =
            weights.iter().copied().filter(|&(i, j, _)| on_boundary[i as usize] || on_boundary[j as usize]).collect();
        // One AMD order of the mesh graph for both systems (AMD costs about as much as a numeric
        // factorisation): each takes the order induced on its unknowns, a merged hole at the
        // place of its last vertex.
        let order = mesh_order(n, &fem_triangles)?;
        // (b) θ_h: Neumann Laplacian with vertex 0 fixed (θ_h = 0 there; the rotation is fixed
        // afterwards): vertex v > 0 is unknown v − 1.
        let theta_unknown: Vec<Option<usize>> = (0..n).map(|v| v.checked_sub(1)).collect();
        let n_theta = n - 1;
        // The two factorisations are independent: side by side, and beside them the indexes of
        // the domain's triangles (the factorisations take unequal times).
        let triangles = Arc::new(domain.triangles.clone());
        let ((h_chol, theta_chol), (plane, vertex_faces)) = crate::par::join(
            || {
                crate::par::join(
                    || {
                        if n_h == 0 {
                            // Every vertex on Γ0: h is fully prescribed. Factorise a 1×1 identity
                            // so the type stays simple; it is never used with a non-empty
                            // right-hand side.
                            return SparseCholesky::new(1, &[(0, 0, 1.0)]);
                        }
                        SparseCholesky::laplacian(&weights, &h_unknown, n_h, &order)
                    },
                    || {
                        if n_theta == 0 {
                            return SparseCholesky::new(1, &[(0, 0, 1.0)]);
                        }
                        SparseCholesky::laplacian(&weights, &theta_unknown, n_theta, &order)
                    },
                )
            },
            || {
                (
                    inverse::InverseMap::new(&domain.positions, triangles.clone()),
                    crate::mesh::topology::vertex_faces(n, &domain.triangles),
                )
            },
        );
        let (h_chol, theta_chol) = (h_chol?, theta_chol?);

        let hole_pole = domain.loops[1..].iter().map(|lp| inscribed_centre(&domain.positions, lp)).collect();

        Ok(Self {
            hole_pole,
            plane,
            positions: domain.positions.clone(),
            triangles,
            fem_triangles,
            vertex_faces,
            loops: domain.loops.clone(),
            options: options.clone(),
            scale,
            h_unknown,
            hole_unknown,
            on_boundary,
            boundary_edges,
            weights,
            h_chol,
            theta_unknown,
            theta_chol,
        })
    }

    /// Canonical pole of hole `hole` (loop index ≥ 1), used in annulus mode when
    /// [`SlitMapOptions::annulus_canonical_pole`] is set.
    pub fn canonical_hole_pole(&self, hole: usize) -> DVec2 {
        self.hole_pole[hole - 1]
    }

    /// Number of holes m.
    pub fn hole_count(&self) -> usize {
        self.loops.len() - 1
    }

    /// Which region the pole is in: `Ok(None)` inside the domain, `Ok(Some(j))` inside hole j
    /// (loop index ≥ 1), or an error when it is outside Γ0 or on a boundary.
    pub fn classify_pole(&self, pole: DVec2) -> Result<Option<usize>, SlitMapError> {
        if !pole.is_finite() {
            return Err(SlitMapError::NonFinitePole { pole });
        }
        let tol = self.options.boundary_tolerance_rel * self.scale;
        for (li, lp) in self.loops.iter().enumerate() {
            let d = polygon_distance(&self.positions, lp, pole);
            if d <= tol {
                return Err(SlitMapError::PoleOnBoundary { pole, loop_index: li, distance: d });
            }
        }
        if !point_in_polygon(&self.positions, &self.loops[0], pole) {
            return Err(SlitMapError::PoleOutside { pole });
        }
        for (li, lp) in self.loops.iter().enumerate().skip(1) {
            if point_in_polygon(&self.positions, lp, pole) {
                return Ok(Some(li));
            }
        }
        Ok(None)
    }

    /// The slit map for pole `pole`: right-hand sides and back-substitutions only.
    pub fn map(&self, pole: DVec2) -> Result<SlitMap, SlitMapError> {
        let region = self.classify_pole(pole)?;
        let solve_pole = match region {
            Some(j) if self.options.annulus_canonical_pole => self.hole_pole[j - 1],
            _ => pole,
        };

        let pole_face = if region.is_none() { self.face_containing(pole) } else { None };
        let (mut w, mut hole_log_radius) = self.solve(region, solve_pole, pole_face, f64::INFINITY)?;
        let factor = self.options.disk_near_factor;
        if region.is_none() && factor.is_finite() {
            // Where the plain formulation folds (crowding, or its P1 error at a slit tip), the
            // far field is tried; it folds elsewhere at times, so the map that folds fewer faces
            // is kept (the plain one on a tie: it is the more accurate where it does not fold).
            let folds = count_folds(&w, &self.triangles);
            if folds > 0 {
                let (w2, hole_log_radius2) = self.solve(region, solve_pole, pole_face, factor)?;
                if count_folds(&w2, &self.triangles) < folds {
                    (w, hole_log_radius) = (w2, hole_log_radius2);
                }
            }
        }

        let mode = match region {
            None => Mode::Disk,
            Some(j) => Mode::Annulus { hole: j, inner_radius: num::exp(hole_log_radius[j - 1]) },
        };
        let slits = (1..self.loops.len())
            .filter(|&li| Some(li) != region)
            .map(|li| {
                let (theta_start, theta_end) = angular_extent(&w, &self.loops[li]);
                Slit { hole: li, radius: num::exp(hole_log_radius[li - 1]), theta_start, theta_end }
            })
            .collect();
        Ok(SlitMap { w, mode, slits, pole, solve_pole, pole_face, hole_log_radius, triangles: self.triangles.clone() })
    }

    /// w per vertex and the hole constants for one formulation (`factor`: see
    /// [`SlitMapOptions::disk_near_factor`]), rotated and untangled.
    fn solve(
        &self,
        region: Option<usize>,
        solve_pole: DVec2,
        pole_face: Option<usize>,
        factor: f64,
    ) -> Result<(Vec<DVec2>, Vec<f64>), SlitMapError> {
        let n = self.positions.len();
        let (h, hole_log_radius, b) = match region {
            None => self.disk_rhs(solve_pole, pole_face, factor),
            Some(j) => self.annulus_rhs(j, solve_pole),
        };
        let mut y = vec![0.0; self.theta_chol.n()];
        for (v, bv) in b.iter().enumerate() {
            if let Some(a) = self.theta_unknown[v] {
                y[a] = *bv;
            }
        }
        self.theta_chol.solve_in_place(&mut y);

        // w = (z − p) exp(h + iθ), then rotated so arg w(loops[0][0]) = 0.
        let mut w: Vec<DVec2> = (0..n)
            .map(|v| {
                let theta = self.theta_unknown[v].map_or(0.0, |a| y[a]);
                let r = num::exp(h[v]);
                let zp = self.positions[v] - solve_pole;
                let (sin, cos) = num::sin_cos(theta);
                zp.rotate(DVec2::new(cos, sin)) * r
            })
            .collect();
        let w0 = w[self.loops[0][0] as usize];
        let rot = DVec2::new(w0.x, -w0.y) / w0.length();
        for (v, wv) in w.iter_mut().enumerate() {
            *wv = wv.rotate(rot);
            if !wv.is_finite() {
                return Err(SlitMapError::NonFiniteResult { vertex: v });
            }
        }

        if self.options.untangle {
            let mut dof = vec![untangle::Dof::Free; n];
            for (li, lp) in self.loops.iter().enumerate() {
                let r = if li == 0 { 1.0 } else { num::exp(hole_log_radius[li - 1]) };
                for &v in lp {
                    dof[v as usize] = untangle::Dof::Circle(r);
                }
            }
            untangle::untangle(&mut w, &self.triangles, &dof, &self.vertex_faces);
        }
        Ok((w, hole_log_radius))
    }

    /// Disk mode: h and the hole constants from the Dirichlet data −log|z − p|, and the right-hand
    /// side of θ_h's least-squares equations (its target field is J∇h).
    ///
    /// Far field: with ℓ = log|z − p| interpolated per vertex, U = log|w| = ℓ + h. Solving L h = 0
    /// makes L U = L ℓ, the P1 error of ℓ, everywhere; where the map crowds a far part of the
    /// domain into a band near |w| = 1 that error exceeds U's range there and faces fold (2.6k on
    /// the U-shaped bracket, issue 3). So with `factor` finite, the rows far from the pole get
    /// L U = 0 instead (right-hand side −L ℓ for h), and their θ_h rows the annulus form −L arg
    /// (V = arg w discrete harmonic), blended by the weight χ of `disk_far_weights`; near the
    /// pole, where ℓ is singular, the subtraction stays. The two kinds of rows do not sum to zero
    /// exactly, and the Neumann system needs that, so the difference is put back at the pole's
    /// face, where V's 2π winding is. With every weight 0 (a pole far from every boundary), this
    /// is exactly the plain formulation.
    fn disk_rhs(&self, p: DVec2, face: Option<usize>, factor: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.positions.len();
        // h = g + P x, g = −log|z − p| on every loop vertex and 0 inside.
        let mut h = vec![0.0; n];
        for (v, hv) in h.iter_mut().enumerate() {
            if self.on_boundary[v] {
                *hv = -num::ln((self.positions[v] - p).length());
            }
        }
        // Right-hand side −Pᵀ L g, from the edges touching the boundary only.
        let mut x = vec![0.0; self.h_chol.n()];
        for &(i, j, wt) in &self.boundary_edges {
            let d = wt * (h[i as usize] - h[j as usize]);
            if let Some(a) = self.h_unknown[i as usize] {
                x[a] -= d;
            }
            if let Some(b) = self.h_unknown[j as usize] {
                x[b] += d;
            }
        }
        let chi = self.disk_far_weights(p, face, factor);
        if let Some(chi) = &chi {
            // Far rows: L h = −χ L ℓ.
            // Floored: a pole on a vertex is allowed (its row is near, weight 0).
            let ell: Vec<f64> =
                self.positions.iter().map(|&z| num::ln((z - p).length().max(f64::MIN_POSITIVE))).collect();
            for &(i, j, wt) in &self.weights {
                let (i, j) = (i as usize, j as usize);
                let d = wt * (ell[i] - ell[j]);
                if let Some(a) = self.h_unknown[i] {
                    x[a] -= chi[i] * d;
                }
                if let Some(b) = self.h_unknown[j] {
                    x[b] += chi[j] * d;
                }
            }
        }
        self.h_chol.solve_in_place(&mut x);
        for (v, hv) in h.iter_mut().enumerate() {
            if let Some(a) = self.h_unknown[v] {
                *hv += x[a];
            }
        }
        let hole_log_radius: Vec<f64> = self.hole_unknown.iter().map(|&u| x[u]).collect();

        // b_i = Σ_f A_f ∇φ_i · J∇h_f. With e_k the edge opposite corner k (counter-clockwise),
        // ∇φ_k = J e_k / (2A) and ∇h = J s / (2A), s = Σ_k h_k e_k, so J∇h = −s / (2A) and
        // b_i = −Σ_f (J e_i) · s / (4A) = −Σ_f e_i × s / (4A).
        let mut b = vec![0.0; n];
        match &chi {
            None => {
                for t in self.fem_triangles.iter() {
                    let (e, area4) = self.edges(t);
                    let s = e[0] * h[t[0] as usize] + e[1] * h[t[1] as usize] + e[2] * h[t[2] as usize];
                    for k in 0..3 {
                        b[t[k] as usize] -= e[k].perp_dot(s) / area4;
                    }
                }
            }
            Some(chi) => {
                // Far rows: −L arg, as in `annulus_rhs`.
                let arg: Vec<f64> = self.positions.iter().map(|&z| num::arg(z - p)).collect();
                for t in self.fem_triangles.iter() {
                    let (e, area4) = self.edges(t);
                    let s = e[0] * h[t[0] as usize] + e[1] * h[t[1] as usize] + e[2] * h[t[2] as usize];
                    let a0 = arg[t[0] as usize];
                    let sa = e[1] * wrap_pi(arg[t[1] as usize] - a0) + e[2] * wrap_pi(arg[t[2] as usize] - a0);
                    for k in 0..3 {
                        let v = t[k] as usize;
                        b[v] -= ((1.0 - chi[v]) * e[k].perp_dot(s) + chi[v] * e[k].dot(sa)) / area4;
                    }
                }
                if let Some(f) = face {
                    let defect = b.iter().sum::<f64>() / 3.0;
                    for &v in &self.triangles[f] {
                        b[v as usize] -= defect;
                    }
                }
            }
        }
        (h, hole_log_radius, b)
    }

    /// Disk mode's far-field weight χ per vertex (see `disk_rhs`): 0 within r =
    /// [`SlitMapOptions::disk_near_factor`] times the pole's distance to the nearest boundary (at
    /// least twice the pole face's longest edge), 1 beyond 2r, a smoothstep between, so the two
    /// kinds of rows blend without a seam (a sharp switch folded faces where it crossed a slit
    /// tip). A hole's vertices all take its nearest vertex's weight, so its merged row is one
    /// kind. `None` when every weight is 0.
    fn disk_far_weights(&self, p: DVec2, face: Option<usize>, factor: f64) -> Option<Vec<f64>> {
        let face = face?;
        let boundary =
            self.loops.iter().map(|lp| polygon_distance(&self.positions, lp, p)).fold(f64::INFINITY, f64::min);
        let z = self.triangles[face].map(|v| self.positions[v as usize]);
        let edge = (z[1] - z[0]).length().max((z[2] - z[1]).length()).max((z[0] - z[2]).length());
        let r = (factor * boundary).max(2.0 * edge);
        let mut chi: Vec<f64> = self
            .positions
            .iter()
            .map(|&q| {
                let t = ((q - p).length() / r - 1.0).clamp(0.0, 1.0);
                t * t * (3.0 - 2.0 * t)
            })
            .collect();
        for lp in &self.loops[1..] {
            let c = lp.iter().map(|&v| chi[v as usize]).fold(1.0, f64::min);
            for &v in lp {
                chi[v as usize] = c;
            }
        }
        chi.iter().any(|&c| c > 0.0).then_some(chi)
    }

    /// Annulus mode (p in hole j): log|w| = U is solved for directly, since log|z − p| is
    /// harmonic in the domain: U = 0 on Γ0, constant on every hole, zero flux through every hole
    /// but j and flux 2π through Γj. That is the same merged-hole Laplacian with the unit source
    /// −2π on hole j's unknown, so U is exactly discrete harmonic with non-negative weights and
    /// keeps the discrete maximum principle: c_j ≤ U ≤ 0. Through h = U − log|z − p| it shared
    /// the P1 error of log|z − p| instead, which exceeds the whole range of U where the map
    /// crowds a far part of the domain against |w| = 1 (featuretype: |w| > 1 inside and 794
    /// folded faces at one hole's pole).
    ///
    /// arg w = V is then the conjugate: Neumann on every loop (U is constant along each), period
    /// 2π round hole j. Written V = arg(z − p) + θ_h with θ_h single-valued, the least-squares
    /// equations of θ_h are L θ_h = −L a, L a assembled per triangle from the arguments unwrapped
    /// within it (∫∇φ_i·J∇U vanishes exactly for such U), so V is discrete harmonic too.
    fn annulus_rhs(&self, j: usize, p: DVec2) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.positions.len();
        let mut x = vec![0.0; self.h_chol.n()];
        x[self.hole_unknown[j - 1]] = -TAU;
        self.h_chol.solve_in_place(&mut x);
        let h: Vec<f64> = (0..n)
            .map(|v| self.h_unknown[v].map_or(0.0, |a| x[a]) - num::ln((self.positions[v] - p).length()))
            .collect();
        let hole_log_radius: Vec<f64> = self.hole_unknown.iter().map(|&u| x[u]).collect();

        // b = −L a: with ∇φ_k = J e_k / (2A) and ∇a = J s / (2A), s = Σ_k a_k e_k,
        // A ∇φ_i · ∇a = e_i · s / (4A).
        let arg: Vec<f64> = self.positions.iter().map(|&z| num::arg(z - p)).collect();
        let mut b = vec![0.0; n];
        for t in self.fem_triangles.iter() {
            let (e, area4) = self.edges(t);
            let a0 = arg[t[0] as usize];
            let s = e[1] * wrap_pi(arg[t[1] as usize] - a0) + e[2] * wrap_pi(arg[t[2] as usize] - a0);
            for k in 0..3 {
                b[t[k] as usize] -= e[k].dot(s) / area4;
            }
        }
        (h, hole_log_radius, b)
    }

    /// The edges opposite each corner of a triangle (counter-clockwise) and 4 × its area.
    fn edges(&self, t: &[u32; 3]) -> ([DVec2; 3], f64) {
        let z = t.map(|v| self.positions[v as usize]);
        let e = [z[2] - z[1], z[0] - z[2], z[1] - z[0]];
        (e, 2.0 * e[1].perp_dot(e[2]).abs())
    }

    /// Planar face containing `q` (the one with the largest minimum barycentric coordinate, so
    /// a point on an edge gets a deterministic answer).
    fn face_containing(&self, q: DVec2) -> Option<usize> {
        self.plane.containing(q, -1e-12)
    }
}

/// One-off slit map: builds a [`SlitMapSolver`] and maps one pole.
pub fn slit_map(domain: &PlanarDomain, pole: DVec2, options: &SlitMapOptions) -> Result<SlitMap, SlitMapError> {
    SlitMapSolver::new(domain, options)?.map(pole)
}

/// Image triangles with non-positive signed area.
fn count_folds(w: &[DVec2], triangles: &[[u32; 3]]) -> usize {
    let area = |t: &[u32; 3]| (w[t[1] as usize] - w[t[0] as usize]).perp_dot(w[t[2] as usize] - w[t[0] as usize]);
    triangles.iter().filter(|t| area(t) <= 0.0).count()
}

/// Shoelace signed area of a closed polygon given by vertex indices.
fn polygon_signed_area(pos: &[DVec2], lp: &[u32]) -> f64 {
    let mut s = 0.0;
    for k in 0..lp.len() {
        let a = pos[lp[k] as usize];
        let b = pos[lp[(k + 1) % lp.len()] as usize];
        s += a.perp_dot(b);
    }
    0.5 * s
}

/// Distance from `q` to a closed polygon's edges.
fn polygon_distance(pos: &[DVec2], lp: &[u32], q: DVec2) -> f64 {
    let mut d = f64::INFINITY;
    for k in 0..lp.len() {
        let a = pos[lp[k] as usize];
        let b = pos[lp[(k + 1) % lp.len()] as usize];
        let ab = b - a;
        let t = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        let t = if t.is_finite() { t } else { 0.0 };
        d = d.min((a + ab * t - q).length());
    }
    d
}

/// Crossing-number point-in-polygon with the half-open rule (each edge owns its lower endpoint),
/// so a ray through a vertex is counted once. Callers exclude points on the boundary first.
fn point_in_polygon(pos: &[DVec2], lp: &[u32], q: DVec2) -> bool {
    let mut inside = false;
    for k in 0..lp.len() {
        let a = pos[lp[k] as usize];
        let b = pos[lp[(k + 1) % lp.len()] as usize];
        if (a.y > q.y) != (b.y > q.y) {
            // Exact sign of the orientation test decides the side (no division).
            let orient = (b - a).perp_dot(q - a);
            if (orient > 0.0) == (b.y > a.y) {
                inside = !inside;
            }
        }
    }
    inside
}

/// Approximate centre of the largest circle inscribed in a closed polygon: the best of the
/// vertex average, the area centroid and a 32 × 32 grid over the bounding box, by distance to the
/// polygon among the points inside it, refined by a few shrinking pattern-search rounds.
fn inscribed_centre(pos: &[DVec2], lp: &[u32]) -> DVec2 {
    let pts: Vec<DVec2> = lp.iter().map(|&v| pos[v as usize]).collect();
    let lo = pts.iter().copied().fold(DVec2::MAX, DVec2::min);
    let hi = pts.iter().copied().fold(DVec2::MIN, DVec2::max);
    let score = |q: DVec2| {
        if point_in_polygon(pos, lp, q) {
            polygon_distance(pos, lp, q)
        } else {
            -1.0
        }
    };
    let mut cands = vec![pts.iter().copied().sum::<DVec2>() / pts.len() as f64];
    let a = polygon_signed_area(pos, lp);
    if a != 0.0 {
        let mut c = DVec2::ZERO;
        for k in 0..pts.len() {
            let (p, q) = (pts[k], pts[(k + 1) % pts.len()]);
            c += (p + q) * p.perp_dot(q);
        }
        cands.push(c / (6.0 * a));
    }
    const G: usize = 32;
    for j in 0..G {
        for i in 0..G {
            let t = DVec2::new((i as f64 + 0.5) / G as f64, (j as f64 + 0.5) / G as f64);
            cands.push(lo + (hi - lo) * t);
        }
    }
    let (mut best, mut best_s) = (cands[0], f64::NEG_INFINITY);
    for c in cands {
        let sc = score(c);
        if sc > best_s {
            (best, best_s) = (c, sc);
        }
    }
    let mut step = (hi - lo).max_element() / G as f64;
    for _ in 0..24 {
        let mut moved = false;
        for d in [DVec2::X, DVec2::NEG_X, DVec2::Y, DVec2::NEG_Y] {
            let c = best + d * step;
            let sc = score(c);
            if sc > best_s {
                (best, best_s) = (c, sc);
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    best
}

/// Angular extent of a set of image points on a circle: the complement of the largest circular
/// gap between their arguments, as (start ∈ [−π, π), end ≥ start).
fn angular_extent(w: &[DVec2], lp: &[u32]) -> (f64, f64) {
    let mut ang: Vec<f64> = lp
        .iter()
        .map(|&v| {
            let a = num::arg(w[v as usize]);
            if a >= PI {
                a - TAU
            } else {
                a
            }
        })
        .collect();
    ang.sort_by(f64::total_cmp);
    let k = ang.len();
    // Gap after ang[i] (the last one wraps around through +π).
    let mut best = (0usize, f64::NEG_INFINITY);
    for i in 0..k {
        let gap = if i + 1 < k { ang[i + 1] - ang[i] } else { ang[0] + TAU - ang[k - 1] };
        if gap > best.1 {
            best = (i, gap);
        }
    }
    let start = ang[(best.0 + 1) % k];
    let end = ang[best.0];
    let end = if end < start { end + TAU } else { end };
    (start, end)
}

#[cfg(test)]
mod tests;
