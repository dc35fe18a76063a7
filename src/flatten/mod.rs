//! Stage 2 — `flatten`: conformal flattening S → S^F by Boundary First Flattening.
//!
//! What it computes (DESIGN.md "flatten", seed 000 §2.1): 2D coordinates `uv` per vertex of a
//! triangulated disk with holes such that the map S → S^F is discretely conformal, with the *free*
//! boundary of minimal area distortion of Sawhney & Crane 2017, "Boundary First Flattening"
//! (ACM TOG 37(1)), i.e. the log scale factor is `u = 0` on the outer boundary:
//!
//! 1. Holes are filled with virtual faces, as BFF's reference implementation does, so the surface
//!    becomes a disk whose only boundary is `loops[0]` (`fill.rs`). The filling is *intrinsic*:
//!    the rim is laid out in the plane with the angles the real triangles leave free (closed
//!    like step 3), and that polygon is filled with a fan around a virtual vertex at its area
//!    centroid where it is star-shaped from there, else triangulated (ear clipping, then
//!    constrained Delaunay flips); the fill's angles and cotan weights are the layout's. The
//!    filling then adds no curvature where none is needed (developable surfaces with holes
//!    flatten exactly isometrically). Virtual elements are dropped at the end; hole rims are
//!    interior curves of a conformal map of a disk, so they stay simple and inside. (Until
//!    issue 34 the fan was used whatever the rim: on staircase rims of tilted slots and
//!    ellipses, not star-shaped from the centroid, some fan triangles were inverted, and BFF
//!    folded the real triangles beside them — the cause of every "flipped triangles" failure of
//!    the generated parts.)
//! 2. Yamabe problem with flat target (all interior and virtual vertices): `A_II u_I = −Ω_I − A_IB u_B` (A the cotan Laplacian,
//!    Ω the angle defects), then the Dirichlet-to-Neumann map gives the boundary flux
//!    `h = (A u)_B` and the target exterior angles `k̃ = k + h` (BFF eq. 8, with `k = π − Σθ`).
//! 3. The boundary curve is integrated from the target lengths `ℓ̃ = e^{(u_i+u_j)/2} ℓ` and the
//!    angles `k̃`, then closed by the minimal change of lengths in the norm with mass matrix
//!    `diag(1/ℓ)` (BFF §4.3).
//! 4. The curve is extended to the interior: by default its real part harmonically and the
//!    imaginary part as the discrete harmonic conjugate (a Neumann problem), BFF's
//!    "extendCurve"; or both coordinates harmonically ([`Extension::Harmonic`]).
//!    If the free boundary overlaps itself or a hole, or a triangle folds (BFF does not guarantee
//!    global injectivity, e.g. the beetle) and [`FlattenOptions::disk_fallback`] is set, the
//!    target angles are bent towards those of the disk target of BFF §5.2 (convex outer loop)
//!    just enough to be valid; if even the disk folds and [`FlattenOptions::embedding_fallback`]
//!    is set, a convex-combination (Tutte) embedding inside the disk's outer loop is the last
//!    resort ([`BffSolver::flatten_tutte`]). [`Flattening::method`] says which one was used and
//!    [`FlattenQuality`] its quasi-conformal distortion.
//! 5. The result (real vertices only) is scaled so the 2D area equals the 3D area and translated
//!    so its area centroid is the origin. Rotation is arbitrary.
//!
//! Preconditions (checked, each fault is a [`FlattenError`]): finite positions, triangle indices in
//! range, every vertex used, no degenerate triangle, consistent orientation, genus 0 with one
//! connected component (`V − E + F = 2 − #loops`), `loops` covering every boundary edge exactly
//! once, `loops[0]` the outer boundary traversed with the surface on its left (counter-clockwise
//! seen from the tool), holes likewise (clockwise).
//!
//! Invariants of the output (verified by [`check`] unless [`FlattenOptions::check`] is off): no
//! flipped triangle, the outer loop counter-clockwise, the holes clockwise, simple, pairwise
//! disjoint and inside the outer loop.
//!
//! [`BffSolver`] factorises the Laplacian blocks once per mesh (Dirichlet block `A_II`, and the
//! Neumann Laplacian with one vertex pinned, for the conjugate and for prescribed boundary angles)
//! and reuses them for every solve: [`BffSolver::flatten`], [`BffSolver::flatten_with_scale_factors`]
//! (BFF with given boundary scale factors), [`BffSolver::flatten_with_curvature`] (given boundary
//! exterior angles), [`BffSolver::flatten_disk`]. [`flatten`] is the one-off entry.
//!
//! Cost: one AMD ordering of the mesh graph (shared with the slit map of the same mesh, see
//! [`crate::linalg::mesh_order`]) and two sparse Cholesky factorisations ([`crate::linalg`]:
//! scalar code, bit-identical natively and in wasm) per mesh, then per flattening three or four
//! triangular solves and O(n) work (figures: `cargo bench --bench conformal`).

// `!(x > 0.0)` is deliberate throughout: NaN must fail every validity test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod bff;
mod check;
mod fill;

pub use bff::{BffSolver, TUTTE_MIN_WEIGHT};
pub use check::{check, quality};

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::linalg::LinalgError;

/// The surface to flatten (borrowed): see the module preconditions.
#[derive(Clone, Copy, Debug)]
pub struct FlattenInput<'a> {
    pub positions: &'a [DVec3],
    /// Consistently oriented, counter-clockwise seen from the tool side.
    pub triangles: &'a [[u32; 3]],
    /// `loops[0]` outer boundary (counter-clockwise), `loops[1..]` holes (clockwise).
    pub loops: &'a [Vec<u32>],
}

impl<'a> From<&'a crate::mesh::Surface> for FlattenInput<'a> {
    fn from(s: &'a crate::mesh::Surface) -> Self {
        Self { positions: &s.positions, triangles: &s.triangles, loops: &s.loops }
    }
}

/// How the boundary curve is extended to the interior (BFF §4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Extension {
    /// Real part harmonic, imaginary part its discrete harmonic conjugate: the most conformal;
    /// the boundary then follows the target curve only approximately. Needs a second
    /// factorisation (Neumann Laplacian).
    Conjugate,
    /// Both coordinates harmonic: the boundary is exactly the closed target curve.
    Harmonic,
}

/// Target of the outer boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum BoundaryTarget {
    /// Scale factor `u = 0` on the outer loop: minimal area distortion (BFF §5.1).
    Free,
    /// Exterior angles proportional to the dual boundary length: a convex, nearly circular
    /// outer loop (BFF §5.2); always simple.
    Disk,
}

/// Options of the flatten stage. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct FlattenOptions {
    /// Interior extension. Default [`Extension::Conjugate`].
    pub extension: Extension,
    /// Outer boundary target. Default [`BoundaryTarget::Free`].
    pub boundary: BoundaryTarget,
    /// When the free boundary overlaps itself or a hole, or the flattening folds a triangle,
    /// bend the target angles towards the disk's (the slit map downstream is indifferent to the
    /// outer shape; see [`BffSolver::flatten`]). Default `true`.
    pub disk_fallback: bool,
    /// When even the disk target folds a triangle, lay the surface out by a convex-combination
    /// (Tutte) embedding with clamped cotan weights inside the disk target's convex outer loop
    /// ([`BffSolver::flatten_tutte`]): a valid embedding, less conformal. Default `true`.
    pub embedding_fallback: bool,
    /// Run [`check`] on the result and fail with its error. Default `true`.
    pub check: bool,
    /// A triangle whose area is below this fraction of its longest edge squared is degenerate.
    /// Default `1e-12`.
    pub degenerate_rel: f64,
}

impl Default for FlattenOptions {
    fn default() -> Self {
        Self {
            extension: Extension::Conjugate,
            boundary: BoundaryTarget::Free,
            disk_fallback: true,
            embedding_fallback: true,
            check: true,
            degenerate_rel: 1e-12,
        }
    }
}

/// Statistics of `log(area2D / area3D)` over the real triangles, after the global scaling that
/// makes both total areas equal. `mean` and `std` are weighted by the 3D area.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct AreaDistortion {
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    pub std: f64,
}

/// Quality figures of a flattening (real triangles only, virtual hole fillings excluded).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FlattenQuality {
    /// Triangles whose 2D signed area is ≤ 0.
    pub flipped_triangles: usize,
    /// Quasi-conformal distortion σ_max/σ_min of the affine map per triangle (1 = conformal),
    /// mean weighted by 3D area.
    pub qc_mean: f64,
    pub qc_max: f64,
    pub area_distortion: AreaDistortion,
    /// Outer loop counter-clockwise, holes clockwise, all simple, disjoint and inside the outer
    /// loop (the boundary part of [`check`]).
    pub boundary_valid: bool,
}

/// Which layout produced a flattening, from the most conformal to the most robust.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FlattenMethod {
    /// BFF with the target of [`FlattenOptions::boundary`] (free, or the disk), or with the
    /// scale factors or angles the caller prescribed.
    Bff,
    /// BFF with the free target angles bent towards the disk's ([`Flattening::disk_blend`]),
    /// after the free boundary overlapped or folded.
    DiskBlend,
    /// Convex-combination embedding inside the disk target's outer loop, after BFF folded
    /// even with the disk target ([`BffSolver::flatten_tutte`]).
    Tutte,
}

/// How many holes were filled each way before flattening (step 1 of the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct HoleFills {
    /// A fan around a virtual vertex inside the rim's intrinsic layout (star-shaped from it).
    pub fan: usize,
    /// A constrained Delaunay triangulation of the layout (not star-shaped, e.g. staircases).
    pub triangulated: usize,
    /// The layout was not simple: the rim projected on its plane, triangulated.
    pub projected: usize,
    /// Neither was simple: the rim laid out on a circle, fanned to its centre.
    pub circle: usize,
}

/// What the plan report shows of a flattening: the method, the disk blend, the hole fillings and
/// the quality figures (serialised at the same level, so `flatten.qc_mean` stays where it was).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlattenReport {
    pub method: FlattenMethod,
    pub disk_blend: f64,
    pub hole_fills: HoleFills,
    #[serde(flatten)]
    pub quality: FlattenQuality,
}

/// The result: one 2D point per input vertex (same indexing, same triangles) and its quality.
#[derive(Clone, Debug, PartialEq)]
pub struct Flattening {
    pub uv: Vec<DVec2>,
    pub quality: FlattenQuality,
    /// The layout that produced `uv`.
    pub method: FlattenMethod,
    pub hole_fills: HoleFills,
    /// The outer-boundary target actually used: `Free`, or `Disk` for the disk target, a
    /// prescribed curvature or a fallback.
    pub boundary: BoundaryTarget,
    /// Weight t of the disk in the target angles `(1−t)·k̃_free + t·k̃_disk`: 0 for the free
    /// boundary, 1 for the disk, in between after a partial fallback.
    pub disk_blend: f64,
}

impl Flattening {
    /// The report of this flattening (method, blend, hole fillings, quality).
    pub fn report(&self) -> FlattenReport {
        FlattenReport {
            method: self.method,
            disk_blend: self.disk_blend,
            hole_fills: self.hole_fills,
            quality: self.quality,
        }
    }
}

/// Everything that can go wrong; variants carry what is at fault.
#[derive(Debug, thiserror::Error)]
pub enum FlattenError {
    #[error("the surface has no boundary loop: a closed surface cannot be flattened")]
    NoBoundary,
    #[error("the surface has no triangle")]
    NoTriangles,
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite { vertex: usize },
    #[error("triangle {face} refers to vertex {vertex}, but there are only {vertices} vertices")]
    IndexOutOfRange { face: usize, vertex: u32, vertices: usize },
    #[error("vertex {vertex} is used by no triangle")]
    UnusedVertex { vertex: usize },
    #[error("triangle {face} is degenerate (zero area)")]
    DegenerateTriangle { face: usize },
    #[error("the edge between vertices {a} and {b} is non-manifold or inconsistently oriented")]
    BadEdge { a: u32, b: u32 },
    #[error("boundary loop {loop_index} is invalid: {reason}")]
    InvalidLoop { loop_index: usize, reason: String },
    #[error("the loops cover {covered} boundary edges but the mesh has {boundary_edges}")]
    LoopsIncomplete { covered: usize, boundary_edges: usize },
    #[error("the surface is not a single disk with holes: V − E + F = {euler} but {loops} loops need {expected}")]
    NotDiskWithHoles { euler: i64, loops: usize, expected: i64 },
    #[error("the virtual filling of hole loop {hole} is degenerate")]
    DegenerateHoleFill { hole: usize },
    #[error("sparse factorisation failed: {0}")]
    Factorisation(LinalgError),
    #[error("boundary data: expected {expected} values (one per outer-loop vertex), got {got}")]
    BoundaryDataLength { expected: usize, got: usize },
    #[error("the boundary curve cannot be closed with positive edge lengths (edge {edge} of the outer loop)")]
    BoundaryClosure { edge: usize },
    #[error("the linear solve produced non-finite values")]
    NonFiniteSolution,
    #[error("{count} flipped triangles in the flattening")]
    FlippedTriangles { count: usize },
    #[error("boundary loops {loop_a} and {loop_b} overlap in the flattening (equal indices: self-intersection)")]
    OverlappingBoundary { loop_a: usize, loop_b: usize },
    #[error("boundary loop {loop_index} has the wrong orientation in the flattening")]
    LoopOrientation { loop_index: usize },
    #[error("invalid flatten option: {0}")]
    InvalidOption(String),
}

impl From<LinalgError> for FlattenError {
    fn from(e: LinalgError) -> Self {
        FlattenError::Factorisation(e)
    }
}

/// One-off flattening: validate, factorise, solve (free boundary `u = 0` by default, see
/// [`FlattenOptions`]), measure, check.
pub fn flatten(input: FlattenInput<'_>, options: &FlattenOptions) -> Result<Flattening, FlattenError> {
    BffSolver::new(input, options)?.flatten()
}
