//! Stage `verify`: scallop simulation of a finished path, independent of the planner.
//!
//! # What it computes (DESIGN.md "verify", issue 4)
//! Input is only the surface and the ball-centre path: a list of continuous cutting passes, each
//! a polyline of ball centres. The ball of radius R swept along a pass is the union of the
//! capsules (segment + radius R) between consecutive centres ([`SweptVolume`]).
//!
//! The surface is sampled afresh, area-uniformly (faces by area, uniform barycentric points, a
//! seeded SplitMix64), with the interpolated unit normal n towards the tool that the ball rides
//! (the corner normals, [`Surface::corner_normal`]; [`sample_surface`]).
//! For each sample p:
//! * **scallop** = the smallest t ≥ 0 with p + t·n inside a capsule: the height of material left
//!   above p along its normal. Exact: the entry of the ray into each capsule is solved in closed
//!   form (infinite cylinder with the axial condition, end spheres; [`Capsule::entry`]).
//! * **gouge**: p itself deeper than `gouge_tolerance_mm` inside a capsule (distance to the
//!   segment < R − tolerance); depth = R − distance.
//! * **uncovered**: no capsule along the normal within `max_scallop_search_mm`.
//! * **CT** (seed 003 eq. 34) on the iso-scallop surface S^h: at q = p + h·n, the number of
//!   distinct times the path passes over q = maximal runs of consecutive capsules containing q,
//!   counted over all passes.
//!
//! Figures ([`Verification`]): max / mean / median / p95 / p99 scallop over the covered samples
//! (nearest-rank percentiles), seed 000's uniformity index V_max (eq. 23: the variance of the
//! per-cell maximum scallop over a 3D grid of cells), gouges, uncovered samples, CT² = Σ CT² ·
//! (area per sample) and max CT, retractions (passes − 1), and the scallop at every surface
//! vertex for the page's heat map ([`VerifyOptions::vertex_scallop`]). [`path_metrics`] gives
//! the path's own figures: length, turning angles, seed 003's smoothness ρ² (eq. 33), time at a
//! feed. With exact facets, the samples over which every ball touching the facets round them
//! leaves more than a given height (facet valleys, [`VerifyOptions::valley_lift_mm`]; `reach`)
//! are reported apart: their area, and the largest scallop outside them.
//!
//! # Preconditions
//! A surface from [`crate::mesh`] (unit vertex normals towards the tool, face areas); finite ball
//! centres; at least one centre; no empty pass. Violations are [`VerifyError`]s.
//!
//! # Cost
//! A bounding-volume hierarchy over the segments, traversed nearest box first: each sample
//! opens only the boxes within R + (best entry so far) of it, and most segments there are
//! settled by one point–segment distance (an entry t needs distance ≤ R + t). The result is
//! bit-identical to testing every segment. Deterministic: same input, same output
//! on every target (only `+ − × ÷ sqrt`).

mod capsule;
pub mod flank;
mod reach;
mod swept;

pub use capsule::Capsule;
pub use reach::GRID_SPACING;
pub use swept::{count_runs, Probe, Prober, SweptVolume};

use crate::fixtures::SplitMix64;
use crate::mesh::nearest::{DippingBall, FaceTree};
use crate::mesh::Surface;
use glam::DVec3;
use serde::Serialize;

/// Options of the verifier. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyOptions {
    /// Ball radius R, mm. Default 3. Must be > 0.
    pub radius_mm: f64,
    /// The user's scallop limit h, mm: the height of S^h for CT. Default 0.02. Must be in (0, R).
    pub scallop_mm: f64,
    /// Number of fresh area-uniform surface samples. Default 100 000. 1 ..= 50 000 000.
    pub samples: usize,
    /// Seed of the sampling. Default `0x5eed`.
    pub seed: u64,
    /// Cell size of the V_max grid, mm; `None` = 2R. Must be > 0.
    pub cell_mm: Option<f64>,
    /// A sample deeper than this inside a swept ball is a gouge, mm. Default 1e-4. In [0, R).
    pub gouge_tolerance_mm: f64,
    /// A sample whose normal meets no ball within this height is uncovered, mm; `None` = R.
    /// Must be > 0.
    pub max_scallop_search_mm: Option<f64>,
    /// A sample is in a *facet valley* when the balls of radius R that touch the facets round
    /// it without cutting them (each moved out along its facet's normal until clear, or dipping
    /// [`VerifyOptions::valley_dip_mm`] into them) leave more than this over it along its
    /// normal: no path leaves less there
    /// (a concave crease sharper than the ball, a groove narrower than it). Their area and the
    /// largest scallop elsewhere are reported apart. `None` (default): no sample is. Must be
    /// finite, ≥ 0 and below R.
    pub valley_lift_mm: Option<f64>,
    /// How deep the path's balls may dip into the facets, mm (with smooth facets, their own
    /// deviation from the smooth surface): the balls that stand for a valley's reach may too
    /// (their centres kept R less this from the facets). Default 0. In [0, R).
    pub valley_dip_mm: f64,
    /// Probe every surface vertex too, for the heat map ([`Verification::vertex_scallop_mm`],
    /// `vertex_uncovered`). Default true; false leaves both empty (a caller that shows no heat
    /// map saves the probes: the Coons strategy's fine grid has more vertices than samples).
    pub vertex_scallop: bool,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        Self {
            radius_mm: 3.0,
            scallop_mm: 0.02,
            samples: 100_000,
            seed: 0x5eed,
            cell_mm: None,
            gouge_tolerance_mm: 1e-4,
            max_scallop_search_mm: None,
            valley_lift_mm: None,
            valley_dip_mm: 0.0,
            vertex_scallop: true,
        }
    }
}

/// Most samples a run may ask for (about 2 GB of work arrays is far beyond any useful check).
pub const MAX_SAMPLES: usize = 50_000_000;

/// The verifier's report. Lengths in mm, areas in mm².
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verification {
    pub samples: usize,
    /// Statistics of the scallop over the covered samples (0 when none is covered).
    pub max_scallop_mm: f64,
    pub mean_scallop_mm: f64,
    /// The median: evenly spaced passes leave about h/4 there; far less is over-cut.
    pub median_scallop_mm: f64,
    pub p95_scallop_mm: f64,
    pub p99_scallop_mm: f64,
    /// Seed 000 eq. 23: variance of the per-cell maximum scallop, cells of `cell_mm` (mm²).
    pub v_max_mm2: f64,
    /// Cells holding at least one covered sample (the N of eq. 23).
    pub v_max_cells: usize,
    pub uncovered_samples: usize,
    pub uncovered_fraction: f64,
    /// Samples deeper than the gouge tolerance inside a swept ball.
    pub gouges: usize,
    /// Deepest gouge, mm (0 when `gouges` = 0).
    pub max_gouge_mm: f64,
    /// Area of the facet valleys (see [`VerifyOptions::valley_lift_mm`]): the surface's area
    /// times the share of the samples in them, mm².
    pub valley_area_mm2: f64,
    /// Largest scallop over the covered samples outside the facet valleys, mm (0 when none).
    pub max_scallop_outside_valleys_mm: f64,
    /// Seed 003 eq. 34: Σ CT² · (area per sample), mm².
    pub ct2: f64,
    pub max_ct: u32,
    pub mean_ct: f64,
    /// Passes − 1.
    pub retractions: usize,
    /// Capsules swept (segments, plus one per single-centre pass).
    pub segments: usize,
    /// Scallop at each surface vertex (along its vertex normal); the search height where
    /// `vertex_uncovered` is set. Not serialised (the page takes it as a typed array). Empty
    /// unless [`VerifyOptions::vertex_scallop`].
    #[serde(skip)]
    pub vertex_scallop_mm: Vec<f64>,
    #[serde(skip)]
    pub vertex_uncovered: Vec<bool>,
    /// The sample with the largest scallop (the first one on a tie).
    pub worst_sample: Option<[f64; 3]>,
    /// Where the largest scallop is: the sample, its face and scallop (`None` when no sample is
    /// covered).
    pub max_scallop_at: Option<ScallopAt>,
    /// Where the largest scallop outside the facet valleys is (`None` when there is none).
    pub max_outside_valleys_at: Option<ScallopAt>,
}

/// A sample with its scallop: where a peak of the finish is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ScallopAt {
    pub scallop_mm: f64,
    pub position: [f64; 3],
    pub normal: [f64; 3],
    pub face: u32,
    /// Whether the sample lies in a facet valley ([`VerifyOptions::valley_lift_mm`]).
    pub in_valley: bool,
}

/// Figures of a path of ball centres (or contact points).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PathMetrics {
    pub length_mm: f64,
    pub points: usize,
    /// Turning angle between consecutive segments (zero-length segments skipped), degrees.
    pub max_turn_deg: f64,
    pub mean_turn_deg: f64,
    /// Seed 003 eq. 33, ∫ρ² dL ≈ Σ φ_i² / ((l_{i−1} + l_i)/2) (φ in radians), 1/mm.
    pub rho2: f64,
    /// `length / feed`, minutes; `None` when the feed is not a positive finite number.
    pub time_min: Option<f64>,
}

/// Everything that can be wrong with a verification's input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VerifyError {
    #[error("invalid verify option: {0}")]
    InvalidOption(String),
    #[error("the path has no ball centre: give at least one pass with one point")]
    EmptyPath,
    #[error("pass {pass} has no point: drop empty passes")]
    EmptyPass { pass: usize },
    #[error("point {index} of pass {pass} is not finite (NaN or infinity)")]
    NonFinite { pass: usize, index: usize },
    #[error("the path has {points} points, more than the verifier can index (2^32 − 1)")]
    PathTooLong { points: usize },
    #[error("the surface has no face of positive area: nothing to verify")]
    EmptySurface,
    #[error("inconsistent surface: {0} (build it with mesh::load or mesh::from_triangles)")]
    InvalidSurface(String),
}

/// A surface sample: a point on a face and the interpolated unit normal there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    pub position: DVec3,
    pub normal: DVec3,
    pub face: u32,
}

/// `count` area-uniform samples of the surface, seeded: a face with probability proportional to
/// its area, a uniform point in it (barycentric (1 − √r₁, √r₁(1 − r₂), √r₁ r₂)), the corner
/// normals interpolated and normalised (the face normal where they cancel).
pub fn sample_surface(surface: &Surface, count: usize, seed: u64) -> Result<Vec<SurfaceSample>, VerifyError> {
    check_surface(surface)?;
    let mut prefix = Vec::with_capacity(surface.face_areas.len());
    let mut total = 0.0;
    for &a in &surface.face_areas {
        total += a;
        prefix.push(total);
    }
    let last = prefix.len() - 1;
    // Sample i takes draws 3i..3i + 3 of the seeded stream: drawn in parallel, the same samples.
    Ok(crate::par::each(count, |i| {
        let mut rng = SplitMix64::skipped(seed, 3 * i as u64);
        let u = rng.unit() * total;
        let face = prefix.partition_point(|&c| c <= u).min(last);
        let (r1, r2) = (rng.unit(), rng.unit());
        let s = r1.sqrt();
        let w = [1.0 - s, s * (1.0 - r2), s * r2];
        let t = surface.triangles[face];
        let mut position = DVec3::ZERO;
        let mut normal = DVec3::ZERO;
        for k in 0..3 {
            position += w[k] * surface.positions[t[k] as usize];
            normal += w[k] * surface.corner_normal(face, k);
        }
        let len = normal.length();
        let normal = if len > 1e-12 { normal / len } else { surface.face_normals[face] };
        SurfaceSample { position, normal, face: face as u32 }
    }))
}

fn check_surface(surface: &Surface) -> Result<(), VerifyError> {
    let nv = surface.positions.len();
    let nf = surface.triangles.len();
    if surface.vertex_normals.len() != nv {
        return Err(VerifyError::InvalidSurface(format!(
            "{} vertex normals for {nv} vertices",
            surface.vertex_normals.len()
        )));
    }
    if surface.face_areas.len() != nf || surface.face_normals.len() != nf {
        return Err(VerifyError::InvalidSurface(format!(
            "{} face areas and {} face normals for {nf} faces",
            surface.face_areas.len(),
            surface.face_normals.len()
        )));
    }
    if let Some(v) = (0..nv).find(|&v| !(surface.positions[v].is_finite() && surface.vertex_normals[v].is_finite())) {
        return Err(VerifyError::InvalidSurface(format!("vertex {v} has a non-finite position or normal")));
    }
    if let Some(f) = surface.triangles.iter().position(|t| t.iter().any(|&v| v as usize >= nv)) {
        return Err(VerifyError::InvalidSurface(format!("face {f} refers to a vertex beyond {nv}")));
    }
    if let Some(f) = surface.face_areas.iter().position(|a| !(a.is_finite() && *a >= 0.0)) {
        return Err(VerifyError::InvalidSurface(format!("face {f} has area {}", surface.face_areas[f])));
    }
    // Areas are finite and ≥ 0 here, so the sum is not NaN.
    if surface.face_areas.iter().sum::<f64>() <= 0.0 {
        return Err(VerifyError::EmptySurface);
    }
    Ok(())
}

/// Checked options: (R, h, V_max cell, search height).
fn check_options(o: &VerifyOptions) -> Result<(f64, f64, f64, f64), VerifyError> {
    let bad = |what: String| Err(VerifyError::InvalidOption(what));
    let r = o.radius_mm;
    if !(r.is_finite() && r > 0.0) {
        return bad(format!("radius_mm must be finite and > 0, got {r}"));
    }
    let h = o.scallop_mm;
    if !(h.is_finite() && h > 0.0 && h < r) {
        return bad(format!("scallop_mm must be > 0 and below the ball radius {r}, got {h}"));
    }
    if o.samples == 0 || o.samples > MAX_SAMPLES {
        return bad(format!("samples must be in 1..={MAX_SAMPLES}, got {}", o.samples));
    }
    let cell = o.cell_mm.unwrap_or(2.0 * r);
    if !(cell.is_finite() && cell > 0.0) {
        return bad(format!("cell_mm must be finite and > 0, got {cell}"));
    }
    let tol = o.gouge_tolerance_mm;
    if !(tol.is_finite() && tol >= 0.0 && tol < r) {
        return bad(format!("gouge_tolerance_mm must be ≥ 0 and below the ball radius {r}, got {tol}"));
    }
    if let Some(lift) = o.valley_lift_mm {
        if !(lift.is_finite() && lift >= 0.0 && lift < r) {
            return bad(format!("valley_lift_mm must be ≥ 0 and below the ball radius {r}, got {lift}"));
        }
    }
    let dip = o.valley_dip_mm;
    if !(dip.is_finite() && dip >= 0.0 && dip < r) {
        return bad(format!("valley_dip_mm must be ≥ 0 and below the ball radius {r}, got {dip}"));
    }
    let search = o.max_scallop_search_mm.unwrap_or(r);
    if !(search.is_finite() && search > 0.0) {
        return bad(format!("max_scallop_search_mm must be finite and > 0, got {search}"));
    }
    Ok((r, h, cell, search))
}

/// Verifies the path `passes` (continuous cutting passes, polylines of ball centres) against
/// `surface`: see the module docs for what is measured.
pub fn verify(surface: &Surface, passes: &[Vec<DVec3>], options: &VerifyOptions) -> Result<Verification, VerifyError> {
    verify_on(surface, None, passes, options)
}

/// The scallop at each vertex of `surface` along its vertex normal under the path `passes`, mm
/// ([`Verification::vertex_scallop_mm`] and its `vertex_uncovered` as NaN), without sampling
/// the surface: the heat map of a path planned on another tessellation of the same part (the
/// Coons band's, whose verification runs on its own fine grid). Only the radius, h and search
/// height of `options` are used.
pub fn vertex_scallop(
    surface: &Surface,
    passes: &[Vec<DVec3>],
    options: &VerifyOptions,
) -> Result<Vec<f64>, VerifyError> {
    let (r, h, _, search) = check_options(options)?;
    let volume = SweptVolume::new(passes, r)?;
    Ok(probe_vertices(&volume, surface, h, search).iter().map(|p| p.scallop.unwrap_or(f64::NAN)).collect())
}

/// The probes of every vertex of `surface` along its normal.
fn probe_vertices(volume: &SweptVolume, surface: &Surface, h: f64, search: f64) -> Vec<Probe> {
    probe_all(volume, surface.positions.len(), |v| (surface.positions[v], surface.vertex_normals[v]), h, search)
}

/// [`verify`] with the facet tree of `surface` already built (its positions and triangles, as
/// the planner keeps one): the facet valleys search it instead of building their own.
pub fn verify_with_faces(
    surface: &Surface,
    faces: &FaceTree,
    passes: &[Vec<DVec3>],
    options: &VerifyOptions,
) -> Result<Verification, VerifyError> {
    if faces.face_count() != surface.triangles.len() {
        return Err(VerifyError::InvalidSurface(format!(
            "the facet tree has {} faces, the surface {}",
            faces.face_count(),
            surface.triangles.len()
        )));
    }
    verify_on(surface, Some(faces), passes, options)
}

fn verify_on(
    surface: &Surface,
    faces: Option<&FaceTree>,
    passes: &[Vec<DVec3>],
    options: &VerifyOptions,
) -> Result<Verification, VerifyError> {
    let (r, h, cell, search) = check_options(options)?;
    // Independent: the samples come from the surface alone.
    let (samples, volume) =
        crate::par::join(|| sample_surface(surface, options.samples, options.seed), || SweptVolume::new(passes, r));
    let (samples, volume) = (samples?, volume?);
    let probes = probe_all(&volume, samples.len(), |i| (samples[i].position, samples[i].normal), h, search);
    // The valleys and the figures of the samples beside the probes of the vertices.
    let ((f, valley_samples), vertex_probes) = crate::par::join(
        || {
            let ball = DippingBall { radius_mm: r, dip_mm: options.valley_dip_mm };
            let valleys =
                options.valley_lift_mm.map(|lift| reach::facet_valleys(surface, faces, &samples, &probes, ball, lift));
            let f = sample_figures(surface, &samples, &probes, cell, options.gouge_tolerance_mm, valleys.as_deref());
            (f, valleys.map_or(0, |v| v.iter().filter(|&&x| x).count()))
        },
        || {
            if options.vertex_scallop {
                probe_vertices(&volume, surface, h, search)
            } else {
                Vec::new()
            }
        },
    );
    let n = samples.len();
    let vertex_scallop_mm = vertex_probes.iter().map(|p| p.scallop.unwrap_or(search)).collect();
    let vertex_uncovered = vertex_probes.iter().map(|p| p.scallop.is_none()).collect();
    let area_per_sample = surface.area() / n as f64;
    let valley_area_mm2 = valley_samples as f64 * area_per_sample;
    Ok(Verification {
        samples: n,
        max_scallop_mm: f.scallops.last().copied().unwrap_or(0.0),
        mean_scallop_mm: f.mean,
        median_scallop_mm: percentile(&f.scallops, 0.5),
        p95_scallop_mm: percentile(&f.scallops, 0.95),
        p99_scallop_mm: percentile(&f.scallops, 0.99),
        v_max_mm2: f.v_max,
        v_max_cells: f.v_cells,
        uncovered_samples: f.uncovered,
        uncovered_fraction: f.uncovered as f64 / n as f64,
        gouges: f.gouges,
        max_gouge_mm: f.max_gouge,
        valley_area_mm2,
        // The largest outside the valleys, and 0 without one (as the report's other maxima).
        max_scallop_outside_valleys_mm: f.worst_outside_valleys_at.map_or(0.0, |w| w.scallop_mm.max(0.0)),
        ct2: f.ct2_sum as f64 * area_per_sample,
        max_ct: f.max_ct,
        mean_ct: f.ct_sum as f64 / n as f64,
        retractions: passes.len() - 1,
        segments: volume.segments(),
        vertex_scallop_mm,
        vertex_uncovered,
        worst_sample: f.worst_at.map(|w| w.position),
        max_scallop_at: f.worst_at,
        max_outside_valleys_at: f.worst_outside_valleys_at,
    })
}

/// What the samples' probes sum up to (see [`Verification`]); `scallops` sorted.
struct SampleFigures {
    scallops: Vec<f64>,
    mean: f64,
    uncovered: usize,
    gouges: usize,
    max_gouge: f64,
    ct_sum: u64,
    ct2_sum: u64,
    max_ct: u32,
    v_max: f64,
    v_cells: usize,
    worst_at: Option<ScallopAt>,
    worst_outside_valleys_at: Option<ScallopAt>,
}

fn sample_figures(
    surface: &Surface,
    samples: &[SurfaceSample],
    probes: &[Probe],
    cell: f64,
    gouge_tolerance_mm: f64,
    valleys: Option<&[bool]>,
) -> SampleFigures {
    let mut scallops = Vec::with_capacity(samples.len());
    let mut cells: Vec<([i64; 3], f64)> = Vec::with_capacity(samples.len());
    let (mut gouges, mut max_gouge) = (0usize, 0.0f64);
    let (mut ct_sum, mut ct2_sum, mut max_ct) = (0u64, 0u64, 0u32);
    let (mut worst_at, mut worst_outside_valleys_at): (Option<ScallopAt>, Option<ScallopAt>) = (None, None);
    let origin = surface.positions.iter().fold(DVec3::splat(f64::INFINITY), |m, &p| m.min(p));
    for (i, (s, probe)) in samples.iter().zip(probes).enumerate() {
        if probe.depth > gouge_tolerance_mm {
            gouges += 1;
            max_gouge = max_gouge.max(probe.depth);
        }
        let ct = probe.passes_over;
        ct_sum += ct as u64;
        ct2_sum += (ct as u64) * (ct as u64);
        max_ct = max_ct.max(ct);
        if let Some(t) = probe.scallop {
            scallops.push(t);
            let in_valley = valleys.is_some_and(|v| v[i]);
            let at = || ScallopAt {
                scallop_mm: t,
                position: s.position.to_array(),
                normal: s.normal.to_array(),
                face: s.face,
                in_valley,
            };
            if !in_valley && !worst_outside_valleys_at.is_some_and(|w| w.scallop_mm >= t) {
                worst_outside_valleys_at = Some(at());
            }
            if !worst_at.is_some_and(|w| w.scallop_mm >= t) {
                worst_at = Some(at());
            }
            let key = ((s.position - origin) / cell).floor();
            cells.push(([key.x as i64, key.y as i64, key.z as i64], t));
        }
    }
    let uncovered = samples.len() - scallops.len();
    let mean = if scallops.is_empty() { 0.0 } else { scallops.iter().sum::<f64>() / scallops.len() as f64 };
    scallops.sort_unstable_by(f64::total_cmp);
    let (v_max, v_cells) = max_variance(cells);
    SampleFigures {
        scallops,
        mean,
        uncovered,
        gouges,
        max_gouge,
        ct_sum,
        ct2_sum,
        max_ct,
        v_max,
        v_cells,
        worst_at,
        worst_outside_valleys_at,
    }
}

/// Probes the `n` points `at(i)` (position, normal), in index order.
///
/// They are probed in a space-filling-curve order (neighbouring points reuse the same tree nodes
/// in cache: 2–3× faster than a random order; each thread takes a stretch of the curve).
fn probe_all(
    volume: &SweptVolume,
    n: usize,
    at: impl Fn(usize) -> (DVec3, DVec3) + Sync,
    h: f64,
    search: f64,
) -> Vec<Probe> {
    let order = morton_order((0..n).map(|i| at(i).0));
    let probed = crate::par::map(
        n,
        || volume.prober(),
        |prober, k| {
            let (p, normal) = at(order[k] as usize);
            prober.probe(p, normal, h, search)
        },
    );
    let mut probes = vec![Probe { scallop: None, depth: f64::NEG_INFINITY, passes_over: 0 }; n];
    for (&i, probe) in order.iter().zip(probed) {
        probes[i as usize] = probe;
    }
    probes
}

/// Indices of `points` sorted along a Morton (Z-order) curve over their bounding box.
fn morton_order(points: impl Iterator<Item = DVec3> + Clone) -> Vec<u32> {
    let (lo, hi) = points
        .clone()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let scale = (hi - lo).max_element();
    let scale = if scale > 0.0 { ((1u64 << 21) - 1) as f64 / scale } else { 0.0 };
    // Spreads the low 21 bits of x to every third bit.
    let spread = |x: u64| {
        let mut x = x & 0x1f_ffff;
        x = (x | x << 32) & 0x001f_0000_0000_ffff;
        x = (x | x << 16) & 0x001f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    let mut keyed: Vec<(u64, u32)> = points
        .enumerate()
        .map(|(i, p)| {
            let q = ((p - lo) * scale).floor();
            (spread(q.x as u64) | spread(q.y as u64) << 1 | spread(q.z as u64) << 2, i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Nearest-rank percentile of sorted values (0 for none).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Seed 000 eq. 23 over grid cells: the population variance of the per-cell maximum scallop,
/// and the number of cells. Cells are sorted by key, so the sum order is fixed.
fn max_variance(mut cells: Vec<([i64; 3], f64)>) -> (f64, usize) {
    cells.sort_unstable_by_key(|c| c.0);
    let mut maxima: Vec<f64> = Vec::new();
    for (i, &(key, t)) in cells.iter().enumerate() {
        if i > 0 && cells[i - 1].0 == key {
            let m = maxima.last_mut().expect("a cell is open");
            *m = m.max(t);
        } else {
            maxima.push(t);
        }
    }
    if maxima.is_empty() {
        return (0.0, 0);
    }
    let n = maxima.len() as f64;
    let mean = maxima.iter().sum::<f64>() / n;
    (maxima.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>() / n, maxima.len())
}

/// Length, turning angles, seed 003's smoothness ρ² (eq. 33) and machining time of a polyline.
///
/// The turning angle at a vertex is the angle between the incoming and outgoing segments
/// (`atan2(|a × b|, a · b)`); consecutive equal points are skipped. ρ ≈ φ_i / ((l_{i−1} + l_i)/2),
/// so ρ² dL ≈ φ_i² / ((l_{i−1} + l_i)/2). `feed_mm_min` in mm/min; `time_min` is `None` unless
/// it is positive and finite.
pub fn path_metrics(points: &[DVec3], feed_mm_min: f64) -> PathMetrics {
    let segs: Vec<DVec3> = points.windows(2).map(|w| w[1] - w[0]).filter(|d| *d != DVec3::ZERO).collect();
    let length: f64 = segs.iter().map(|d| d.length()).sum();
    let (mut max_turn, mut sum_turn, mut rho2) = (0.0f64, 0.0, 0.0);
    for w in segs.windows(2) {
        let (a, b) = (w[0], w[1]);
        let phi = crate::num::atan2(a.cross(b).length(), a.dot(b));
        max_turn = max_turn.max(phi);
        sum_turn += phi;
        rho2 += phi * phi / (0.5 * (a.length() + b.length()));
    }
    let turns = segs.len().saturating_sub(1);
    PathMetrics {
        length_mm: length,
        points: points.len(),
        max_turn_deg: max_turn.to_degrees(),
        mean_turn_deg: if turns == 0 { 0.0 } else { (sum_turn / turns as f64).to_degrees() },
        rho2,
        time_min: (feed_mm_min.is_finite() && feed_mm_min > 0.0).then(|| length / feed_mm_min),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!((percentile(&v, 0.95), percentile(&v, 0.99), percentile(&v, 1.0)), (95.0, 99.0, 100.0));
        assert_eq!((percentile(&[7.0], 0.95), percentile(&[], 0.5)), (7.0, 0.0));
    }

    #[test]
    fn v_max_is_the_variance_of_the_cell_maxima() {
        let cells = vec![([1, 0, 0], 2.0), ([0, 0, 0], 1.0), ([0, 0, 0], 3.0), ([0, -1, 0], 3.0)];
        // Maxima 3, 2, 3: mean 8/3, variance ((1/3)² · 2 + (2/3)²) / 3 = 2/9.
        let (v, n) = max_variance(cells);
        assert_eq!(n, 3);
        assert!((v - 2.0 / 9.0).abs() < 1e-15);
        assert_eq!(max_variance(Vec::new()), (0.0, 0));
    }

    #[test]
    fn runs_split_at_gaps_and_pass_changes() {
        let pass_of = [0, 0, 0, 0, 1, 1, 1, 1, 1, 1];
        assert_eq!(count_runs(&[], &pass_of), 0);
        assert_eq!(count_runs(&[0, 1, 2], &pass_of), 1);
        assert_eq!(count_runs(&[0, 1, 5, 6, 8], &pass_of), 3);
        // 3 and 4 are consecutive ids but belong to different passes.
        assert_eq!(count_runs(&[2, 3, 4, 5], &pass_of), 2);
    }

    #[test]
    fn morton_order_is_a_permutation_that_keeps_neighbours_together() {
        let pts: Vec<DVec3> = (0..64).map(|i| DVec3::new((i % 8) as f64, (i / 8) as f64, 0.0)).collect();
        let order = morton_order(pts.iter().copied());
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..64).collect::<Vec<u32>>());
        // Z-order on an 8 × 8 lattice: each aligned 2 × 2 block is visited in one go.
        for block in order.chunks(4) {
            let (x, y) = (block.iter().map(|&i| i % 8 / 2), block.iter().map(|&i| i / 8 / 2));
            assert!(x.clone().all(|v| v == block[0] % 8 / 2) && y.clone().all(|v| v == block[0] / 8 / 2));
        }
    }

    #[test]
    fn samples_are_area_uniform_and_on_their_faces() {
        // Two triangles of areas 1 and 3 (ratio 1 : 3) in z = 0.
        let m = crate::mesh::TriMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(2.0, 3.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        let surface = crate::mesh::from_triangles(&m, &Default::default()).unwrap().surface;
        let areas = &surface.face_areas;
        let samples = sample_surface(&surface, 40_000, 3).unwrap();
        let first = samples.iter().filter(|s| s.face == 0).count() as f64 / samples.len() as f64;
        let expected = areas[0] / (areas[0] + areas[1]);
        assert!((first - expected).abs() < 0.01, "{first} vs {expected}");
        for s in &samples {
            let [a, b, c] = surface.triangles[s.face as usize].map(|v| surface.positions[v as usize]);
            // Inside: on the left of (or on) all three edges.
            let sub = |u: DVec3, v: DVec3| (v - u).cross(s.position - u).z;
            assert!(sub(a, b) >= -1e-12 && sub(b, c) >= -1e-12 && sub(c, a) >= -1e-12);
            assert_eq!(s.normal, DVec3::Z);
        }
    }
}
