//! Strategy `coons`: one spiral over a closed band of four-sided STEP faces through their Coons
//! reparameterisation (seed 004, Li et al., Eksploatacja i Niezawodność 28(3), 2026; issue 36
//! items 3–5).
//!
//! What it computes, one module per step:
//!
//! 1. [`band`]: the selected faces → four-sided faces (corners where the loop turns) chained
//!    into a closed band through shared sides, laid out `around` × `across` (§2, Fig. 14).
//! 2. [`side`], [`patch`], [`compound`]: every face's Coons map (eq. 1; the printed boundary
//!    argument corrected, see [`patch`]) with sides parameterised by normalised 3D arc length,
//!    so shared sides coincide (eq. 3); the compound domain [0, around) × [0, across], periodic
//!    in U. Points are evaluated on the exact STEP surfaces.
//! 3. [`smooth`]: the path's tangent jumps at the seams measured on the raw map; the map made
//!    composite C¹ round the loop (§4; our construction, see the module), the jumps measured
//!    again.
//! 4. [`path`]: ring levels from scallop control over all reference lines, one inclined domain
//!    line per revolution between boundary rings (§3.2), densified to the chord tolerance.
//! 5. The shared back end: tool positions ([`crate::toolpath`]), posts ([`crate::gcode`], the
//!    header naming the strategy) and the scallop verifier ([`crate::verify`]) on a fine
//!    tessellation of the faces ([`mesh`]: a grid of each face's Coons domain).
//!
//! Entry: [`plan`] with a STEP [`Model`] and the selected face ids. Preconditions: the faces
//! form a band as [`band`] describes (else [`CoonsError::is_not_a_band`] errors, for which the
//! CLI offers the slit-map spiral on the tessellation), faces without holes, a ball no larger
//! than the concave curvature radius. Invariants of the output: one continuous cutting pass
//! (no retraction between its ends); every contact point and normal is on the exact surface.
//! Deterministic: sequential, transcendental functions from [`crate::num`].
//!
//! Not done (see `docs/coons.md`): faces with holes or trimmed interiors (the Coons map covers
//! the four sides only), single-face bands closed by a seam edge, the seed's G¹ least-squares
//! fit (eq. 23: we build the stronger composite C¹ map directly), smoothing of the seams between
//! rows (their jumps are measured and reported).

// `!(x > 0.0)` is deliberate throughout: NaN must fail every validity test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod band;
pub mod compound;
pub mod mesh;
pub mod patch;
pub mod path;
pub mod side;
pub mod smooth;
pub mod warp;

pub use compound::Compound;
pub use smooth::{Jumps, SeamReport};

use crate::gcode::{self, GcodeError, GcodeOptions, Post};
use crate::mesh::MeshError;
use crate::step::{Model, StepError};
use crate::toolpath::{self, Axes, Toolpath, ToolpathError, ToolpathOptions};
use crate::verify::{self, Verification, VerifyError, VerifyOptions};
use glam::DVec3;
use serde::Serialize;

/// Options of [`plan`]. Defaults in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct CoonsOptions {
    /// Ball radius R, mm [3].
    pub radius_mm: f64,
    /// Scallop-height limit h, mm [0.02].
    pub scallop_mm: f64,
    /// The rings are spaced for this fraction of h [0.95] (the slit-map spacing's margin).
    pub target_fraction: f64,
    /// A loop vertex turning more than this is a corner, degrees [30].
    pub corner_angle_deg: f64,
    /// Reference lines per face besides the seams [8].
    pub lines_per_face: usize,
    /// Make the map composite C¹ round the loop ([`smooth`]) [true].
    pub smooth: bool,
    /// Chord tolerance of the contact and ball-centre curves, mm [None: the slit-map planner's
    /// for R and h, [`crate::plan::chord_tolerance_mm`]].
    pub chord_tolerance_mm: Option<f64>,
    /// Tool axes [5-axis, lead 15°, tilt 0°]: a band faces every way round its loop.
    pub axes: Axes,
    /// Post [A/C with TCP].
    pub post: Post,
    /// Feeds, mm/min [1000, 300], spindle, rpm [12000], safe height [None: above the part].
    pub feed_mm_min: f64,
    pub plunge_feed_mm_min: f64,
    pub spindle_rpm: f64,
    pub safe_z_mm: Option<f64>,
    /// Verifier samples, 0 skips the verification [100 000].
    pub verify_samples: usize,
    /// Chordal tolerance of the verifier's tessellation, mm [None: h/20].
    pub verify_chordal_tol_mm: Option<f64>,
    /// Part name for the header ["part"].
    pub part_name: String,
}

impl Default for CoonsOptions {
    fn default() -> Self {
        let tp = ToolpathOptions::default();
        CoonsOptions {
            radius_mm: 3.0,
            scallop_mm: 0.02,
            target_fraction: 0.95,
            corner_angle_deg: 30.0,
            lines_per_face: 8,
            smooth: true,
            chord_tolerance_mm: None,
            axes: Axes::five_default(),
            post: Post::Ac,
            feed_mm_min: tp.feed_mm_min,
            plunge_feed_mm_min: tp.plunge_feed_mm_min,
            spindle_rpm: tp.spindle_rpm,
            safe_z_mm: None,
            verify_samples: 100_000,
            verify_chordal_tol_mm: None,
            part_name: "part".into(),
        }
    }
}

/// Everything that can go wrong; variants name the face (STEP `#id`) at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoonsError {
    #[error("invalid coons option: {0}")]
    InvalidOption(String),
    #[error("no face selected: choose the band's faces with --faces (see `slitpath faces`)")]
    NoFaces,
    #[error("there is no face #{face}")]
    UnknownFace { face: u64 },
    #[error("face #{face} is not four-sided: {reason}")]
    NotFourSided { face: u64, reason: String },
    #[error("the faces do not close into a band: walking across the sides of face #{face} does not come back to it")]
    NotClosed { face: u64 },
    #[error("the faces are not a band of rows: face #{face}: {reason}")]
    NotABand { face: u64, reason: String },
    #[error("face #{face} has no Coons domain: {reason}")]
    Domain { face: u64, reason: String },
    #[error(
        "face #{face} is concave with a radius of {curvature_radius_mm:.3} mm, below the ball radius {radius_mm} mm"
    )]
    BallTooLarge { face: u64, radius_mm: f64, curvature_radius_mm: f64 },
    #[error("the spiral would need {revolutions} revolutions: raise the scallop height")]
    TooManyRevolutions { revolutions: usize },
    #[error("{0}")]
    Step(#[from] StepError),
    #[error("verification mesh: {0}")]
    Mesh(#[from] MeshError),
    #[error("tool path: {0}")]
    Toolpath(#[from] ToolpathError),
    #[error("G-code: {0}")]
    Gcode(#[from] GcodeError),
    #[error("verification: {0}")]
    Verify(#[from] VerifyError),
}

impl CoonsError {
    /// The selection is not a band seed 004 plans (not four-sided, not closed, not in rows, no
    /// planar domain): the slit-map spiral on the tessellation is the alternative.
    pub fn is_not_a_band(&self) -> bool {
        matches!(
            self,
            CoonsError::NotFourSided { .. }
                | CoonsError::NotClosed { .. }
                | CoonsError::NotABand { .. }
                | CoonsError::Domain { .. }
        )
    }
}

/// The band as the report lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BandReport {
    pub around: usize,
    pub across: usize,
    /// Face ids row by row (row 0 is V = 0, where the spiral starts), in U order.
    pub rows: Vec<Vec<u64>>,
}

/// Stage timings, ms.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CoonsTimings {
    pub band: f64,
    pub coons: f64,
    pub levels: f64,
    pub path: f64,
    pub toolpath: f64,
    pub post: f64,
    pub verify: f64,
    pub total: f64,
}

/// The report (the CLI's `--report`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoonsReport {
    pub strategy: &'static str,
    pub radius_mm: f64,
    pub scallop_mm: f64,
    pub chord_tolerance_mm: f64,
    pub band: BandReport,
    /// Ring levels (boundary rings included) and revolutions of the path (the two boundary
    /// rings and one per inclined line).
    pub levels: usize,
    pub revolutions: usize,
    /// Flat-surface stepover for the target scallop, the common scale of the steps, and the
    /// smallest and largest 3D spacing of consecutive levels along the reference lines, mm.
    pub nominal_stepover_mm: f64,
    pub step_scale: f64,
    pub min_spacing_mm: f64,
    pub max_spacing_mm: f64,
    pub seams: SeamReport,
    pub length_mm: f64,
    pub points: usize,
    /// Passes − 1: 0 for one continuous spiral.
    pub retractions: usize,
    pub max_turn_deg: f64,
    pub time_min: f64,
    /// Triangles of the verifier's tessellation and its chordal error, mm.
    pub verify_triangles: usize,
    pub verify_chordal_error_mm: f64,
    pub verify: Option<Verification>,
    pub timings: CoonsTimings,
}

/// The result of [`plan`].
#[derive(Clone, Debug)]
pub struct CoonsPlan {
    pub compound: Compound,
    pub levels: Vec<f64>,
    pub warp: warp::Warp,
    pub lines: Vec<smooth::Line>,
    pub points: Vec<path::PathPoint>,
    pub toolpath: Toolpath,
    pub gcode: String,
    pub report: CoonsReport,
}

fn check(o: &CoonsOptions) -> Result<(), CoonsError> {
    let bad = |m: String| Err(CoonsError::InvalidOption(m));
    let r = o.radius_mm;
    if !(r.is_finite() && r > 0.0) {
        return bad(format!("radius {r} mm must be positive"));
    }
    if !(o.scallop_mm.is_finite() && o.scallop_mm > 0.0 && o.scallop_mm < r) {
        return bad(format!("scallop {} mm must be positive and below the radius", o.scallop_mm));
    }
    if !(o.target_fraction > 0.0 && o.target_fraction <= 1.0) {
        return bad(format!("target fraction {} must be in (0, 1]", o.target_fraction));
    }
    if !(o.corner_angle_deg > 0.0 && o.corner_angle_deg < 180.0) {
        return bad(format!("corner angle {}° must be in (0, 180)", o.corner_angle_deg));
    }
    if o.lines_per_face > 1000 {
        return bad(format!("{} reference lines per face is too many (at most 1000)", o.lines_per_face));
    }
    if let Some(c) = o.chord_tolerance_mm {
        if !(c.is_finite() && c > 0.0) {
            return bad(format!("chord tolerance {c} mm must be positive"));
        }
    }
    if let Some(c) = o.verify_chordal_tol_mm {
        if !(c.is_finite() && c > 0.0) {
            return bad(format!("verifier chordal tolerance {c} mm must be positive"));
        }
    }
    Ok(())
}

/// Nodes per seam of the composite-C¹ correction.
const SMOOTH_NODES: usize = 32;

/// The raw (unsmoothed) compound Coons map of the band formed by `faces` of `model`.
pub fn compound(model: &Model, faces: &[u64], o: &CoonsOptions) -> Result<Compound, CoonsError> {
    check(o)?;
    let band = band::detect(model, faces, o)?;
    Compound::new(model, &band)
}

/// Plans the spiral over the band `faces` of `model` (see the module docs). `now` gives ms.
pub fn plan(model: &Model, faces: &[u64], o: &CoonsOptions, now: &dyn Fn() -> f64) -> Result<CoonsPlan, CoonsError> {
    check(o)?;
    let t0 = now();
    let band = band::detect(model, faces, o)?;
    let mut timings = CoonsTimings { band: now() - t0, ..Default::default() };
    let t = now();
    let raw = Compound::new(model, &band)?;
    // Smoothing, kept only when the reparameterised map stays regular.
    let mut compound = raw.clone();
    let mut note = None;
    if o.smooth {
        let corrections = smooth::corrections(&raw, SMOOTH_NODES);
        for (p, c) in compound.patches.iter_mut().zip(corrections) {
            p.correction = Some(c);
        }
        let det = compound.det_j_min_rel(40);
        if !(det > 0.0) {
            note = Some(format!("the composite C1 reparameterisation folds (det J down to {det:.3} of the centre's): the raw Coons map is used"));
            compound = raw.clone();
        }
    }
    let smoothed = o.smooth && note.is_none();
    timings.coons = now() - t;

    let t = now();
    let (r, h) = (o.radius_mm, o.scallop_mm);
    let levels = path::levels(&compound, r, h, o.target_fraction, o.lines_per_face)?;
    let lines = path::lines(&compound, &levels.v);
    timings.levels = now() - t;

    let t = now();
    let chord = o.chord_tolerance_mm.unwrap_or_else(|| crate::plan::chord_tolerance_mm(r, h));
    let points = path::densify(&compound, &levels.warp, &lines, r, chord);
    let (round_before, rows_before) = smooth::tangent_jumps(&raw, &levels.warp, &lines);
    let (round_after, rows_after) = smooth::tangent_jumps(&compound, &levels.warp, &lines);
    let seams = SeamReport {
        mode: if smoothed { "composite-c1" } else { "none" },
        round_before: Jumps::of(&round_before),
        round_after: Jumps::of(&round_after),
        rows_before: Jumps::of(&rows_before),
        rows_after: Jumps::of(&rows_after),
        det_j_min_rel: compound.det_j_min_rel(40),
        seam_gap_mm: compound.seam_gap_mm(64),
        note,
    };
    timings.path = now() - t;

    let t = now();
    let cc: Vec<DVec3> = points.iter().map(|p| p.x).collect();
    let normals: Vec<DVec3> = points.iter().map(|p| p.n).collect();
    let toolpath_options = ToolpathOptions {
        radius_mm: r,
        axes: o.axes,
        feed_mm_min: o.feed_mm_min,
        plunge_feed_mm_min: o.plunge_feed_mm_min,
        spindle_rpm: o.spindle_rpm,
        safe_z_mm: o.safe_z_mm,
        ..ToolpathOptions::default()
    };
    let toolpath = toolpath::toolpath(&cc, &normals, &toolpath_options)?;
    let metrics = verify::path_metrics(&cc, o.feed_mm_min);
    timings.toolpath = now() - t;

    let band_report = BandReport {
        around: compound.around,
        across: compound.across,
        rows: (0..compound.across).map(|j| (0..compound.around).map(|i| compound.patch(i, j).id).collect()).collect(),
    };
    let mut report = CoonsReport {
        strategy: "coons",
        radius_mm: r,
        scallop_mm: h,
        chord_tolerance_mm: chord,
        band: band_report,
        levels: levels.v.len(),
        revolutions: lines.len(),
        nominal_stepover_mm: levels.nominal_mm,
        step_scale: levels.scale,
        min_spacing_mm: levels.min_spacing_mm,
        max_spacing_mm: levels.max_spacing_mm,
        seams,
        length_mm: metrics.length_mm,
        points: points.len(),
        retractions: toolpath.stats.retractions.saturating_sub(1),
        max_turn_deg: metrics.max_turn_deg,
        time_min: toolpath.stats.estimated_time_s / 60.0,
        verify_triangles: 0,
        verify_chordal_error_mm: 0.0,
        verify: None,
        timings: CoonsTimings::default(),
    };

    let t = now();
    let gcode = gcode::gcode(
        &toolpath,
        &GcodeOptions {
            post: o.post,
            part_name: o.part_name.clone(),
            header: header(&report, o),
            ..GcodeOptions::default()
        },
    )?;
    timings.post = now() - t;

    let t = now();
    if o.verify_samples > 0 {
        let tol = o.verify_chordal_tol_mm.unwrap_or(h / 20.0);
        let (surface, triangles, err) = mesh::grid_surface(&compound, tol)?;
        let centres: Vec<DVec3> = toolpath.contact_moves().iter().map(|m| m.centre).collect();
        let v = verify::verify(
            &surface,
            &[centres],
            &VerifyOptions {
                radius_mm: r,
                scallop_mm: h,
                samples: o.verify_samples,
                // Facets of a concave face lie outside the exact surface by up to the chordal error.
                gouge_tolerance_mm: chord + err,
                // Nothing shows a heat map: the grid's vertices (178 000 on the blade band) go unprobed.
                vertex_scallop: false,
                ..VerifyOptions::default()
            },
        )?;
        report.verify_triangles = triangles;
        report.verify_chordal_error_mm = err;
        report.verify = Some(v);
    }
    timings.verify = now() - t;
    timings.total = now() - t0;
    report.timings = timings;
    Ok(CoonsPlan { compound, levels: levels.v, warp: levels.warp, lines, points, toolpath, gcode, report })
}

impl CoonsPlan {
    /// The scallop at each vertex of `surface` (a tessellation of the band's faces, as the page
    /// draws them) under this plan's path, mm, NaN where no pass is over it: the heat map, which
    /// the plan's own verification (on its fine grid, whose vertices nothing draws) does not
    /// give.
    pub fn vertex_scallop_mm(&self, surface: &crate::mesh::Surface) -> Result<Vec<f64>, CoonsError> {
        let centres: Vec<DVec3> = self.toolpath.contact_moves().iter().map(|m| m.centre).collect();
        let options = VerifyOptions {
            radius_mm: self.report.radius_mm,
            scallop_mm: self.report.scallop_mm,
            ..VerifyOptions::default()
        };
        Ok(verify::vertex_scallop(surface, &[centres], &options)?)
    }
}

/// The G-code header: the strategy and its figures (no timings: deterministic output).
fn header(r: &CoonsReport, o: &CoonsOptions) -> Vec<(String, String)> {
    let axes = match o.axes {
        Axes::Three { axis } => format!("3 ({:.4} {:.4} {:.4})", axis.x, axis.y, axis.z),
        Axes::Five { lead_deg, tilt_deg } => format!("5 (lead {lead_deg} tilt {tilt_deg} deg)"),
    };
    let faces: Vec<String> =
        r.band.rows.iter().map(|row| row.iter().map(|f| format!("#{f}")).collect::<Vec<_>>().join(" ")).collect();
    vec![
        ("strategy".into(), "coons band spiral, seed 004 (Coons reparameterised compound faces)".into()),
        ("band".into(), format!("{} x {} faces: {}", r.band.around, r.band.across, faces.join(" / "))),
        ("ball radius mm".into(), format!("{}", r.radius_mm)),
        ("scallop mm".into(), format!("{}", r.scallop_mm)),
        ("axes".into(), axes),
        ("seams".into(), r.seams.mode.to_string()),
        ("revolutions".into(), format!("{}", r.revolutions)),
        ("path length mm".into(), format!("{:.3}", r.length_mm)),
        ("points".into(), format!("{}", r.points)),
    ]
}
