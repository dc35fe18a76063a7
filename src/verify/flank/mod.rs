//! The flank verifier: what the written cutter-location data does to the surface, independent
//! of the flank planner (seed 002, issue 35).
//!
//! # Input
//! The surface (a [`Surface`] from [`crate::mesh`], or the caller's own samples) and CL data as
//! the `cl` post writes it, read back with [`crate::gcode::parse_cl`]. Nothing of the planner's
//! state is used: the tool comes from the `CUTTER/d, r, e, f, a, b, h` statement (tip diameter d,
//! taper b in degrees, flute length h; [`crate::flank::ConeTool`]), the poses from the `GOTO`s
//! (tip and unit axis), and which moves form a strip from the header comments
//! `$$ - strip k: moves FIRST-LAST, …` (0-based move indices; without them every run of feed
//! moves between rapids is one strip).
//!
//! # What it computes
//! The tool is the round cone of its sphere family ([`swept`]); every feed move sweeps it from
//! the previous pose, the tip on a straight line and A, C linear, as a table-table controller
//! with tool-centre-point control moves it (rapids are not swept). For each surface sample
//! (area-uniform, seeded, [`crate::verify::sample_surface`]):
//!
//! - **deviation** = the signed distance to the union of the swept volumes: positive where the
//!   tool did not reach the surface (material left), negative where it cut below it (a gouge).
//!   Searched up to `search_mm`; beyond, the sample is *uncovered*.
//! - **machined** when some strip's cutting moves pass over it: the nearest point of that strip's
//!   swept volume lies on the flank (not on an end cap) and not before the strip's first pose or
//!   after its last. (Strips are resolved up to 5 % of L beyond the nearest approach: a strip
//!   farther than that does not finish the point.) Undercut is measured over machined samples only (the bands beside the
//!   outermost strips are not the tool's to finish); gouges everywhere.
//!
//! Figures ([`FlankVerification`]): max gouge and the count of samples deeper than the
//! tolerance; max undercut over the machined region; per strip (the strip whose volume is
//! nearest to the sample) mean, RMS, p95, p99 and max |deviation|; coverage (share of all
//! samples, and of the machined ones, within ±tolerance); at each boundary between strips k and
//! k + 1 the kink angle and the gap ([`seams`]) both from the envelope formula (seed 002 eq. 6)
//! and from the samples; the CL data's axis-norm error (the only way a written program can
//! break rigidity: the tool is a tip and a unit axis); the A/C kinematics (largest steps, C
//! flips near A = 0). Optionally the deviation at every vertex (the page's heat map).
//!
//! Deterministic: samples drawn in parallel from a seeded stream, every per-sample figure a
//! function of its sample alone, sums in index order.

mod seams;
pub mod swept;

use crate::bvh::{self, Node};
use crate::flank::{ConeTool, SphereFamily};
use crate::gcode::{parse_cl, ClError};
use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use crate::verify::{sample_surface, SurfaceSample, VerifyError};
use glam::DVec3;
use serde::Serialize;
use std::ops::Range;
use swept::{ControllerPose, RoundCone};

pub use seams::SeamFigures;

/// Options of [`verify_flank`]. Defaults in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct FlankVerifyOptions {
    /// Surface samples [20 000]; 1 ..= [`crate::verify::MAX_SAMPLES`].
    pub samples: usize,
    /// Seed of the sampling [0x5eed].
    pub seed: u64,
    /// |deviation| within this is finished, mm [0.01].
    pub tolerance_mm: f64,
    /// Deviations are searched up to this, mm [None: L/2 of the tool's sphere family].
    pub search_mm: Option<f64>,
    /// Samples nearer than this to a boundary's envelope curve count for its sample figures, mm
    /// [None: twice the samples' spacing √(area/samples) for [`verify_flank`], and never less
    /// than 1 % of the contact length d].
    pub seam_band_mm: Option<f64>,
    /// Within this |A| of the singular pose (A = 0), degrees [2] …
    pub near_singular_deg: f64,
    /// … a feed move turning C by more than this is a C flip, degrees [45]: the table swings
    /// while the tool's axis barely moves.
    pub flip_deg: f64,
    /// Also measure the deviation at every vertex [true].
    pub vertices: bool,
}

impl Default for FlankVerifyOptions {
    fn default() -> Self {
        FlankVerifyOptions {
            samples: 20_000,
            seed: 0x5eed,
            tolerance_mm: 0.01,
            search_mm: None,
            seam_band_mm: None,
            near_singular_deg: 2.0,
            flip_deg: 45.0,
            vertices: true,
        }
    }
}

/// Deviation figures of one strip, mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StripDeviation {
    /// 1-based, as in the header.
    pub strip: usize,
    /// Move indices of its first and last pose.
    pub moves: [usize; 2],
    /// Machined samples it finishes.
    pub samples: usize,
    pub mean_abs_mm: f64,
    pub rms_mm: f64,
    pub p95_abs_mm: f64,
    pub p99_abs_mm: f64,
    pub max_abs_mm: f64,
    /// Largest deviation (material left) and smallest (negative: gouge) over its samples.
    pub max_mm: f64,
    pub min_mm: f64,
}

/// A/C figures of the program's feed moves.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Kinematics {
    pub max_a_step_deg: f64,
    pub max_c_step_deg: f64,
    /// Feed moves whose C turns more than `flip_deg` with |A| below `near_singular_deg` at
    /// either end.
    pub c_flips: usize,
    /// Feed moves where A changes sign (the post's (−A, C + 180°) branch taken through A = 0).
    pub a_sign_changes: usize,
    /// Feed moves ending with |A| below `near_singular_deg`.
    pub near_singular_moves: usize,
    /// The first move whose axis is beyond the A/C machine's A range (then the verifier swept
    /// the axis along great circles instead).
    pub a_out_of_range: Option<usize>,
}

/// The flank verifier's report (module docs). Lengths in mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlankVerification {
    pub samples: usize,
    pub tool: ConeTool,
    pub strips_found: usize,
    pub segments: usize,
    pub machined_samples: usize,
    pub machined_fraction: f64,
    pub uncovered_samples: usize,
    /// Deepest cut below the surface (≥ 0) and the samples deeper than the tolerance.
    pub max_gouge_mm: f64,
    pub gouges: usize,
    /// Most material left over the machined region (≥ 0).
    pub max_undercut_mm: f64,
    /// Share of all samples, and of the machined ones, within ±tolerance.
    pub coverage_within_tolerance: f64,
    pub machined_within_tolerance: f64,
    pub tolerance_mm: f64,
    pub worst_gouge_at: Option<[f64; 3]>,
    pub worst_undercut_at: Option<[f64; 3]>,
    pub strips: Vec<StripDeviation>,
    pub seams: Vec<SeamFigures>,
    /// Largest | |axis| − 1 | of the written axes.
    pub max_axis_norm_error: f64,
    pub kinematics: Kinematics,
    /// Deviation at each surface vertex (NaN where uncovered); not serialised.
    #[serde(skip)]
    pub vertex_deviation_mm: Vec<f64>,
}

/// Everything that can be wrong with the verifier's input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FlankVerifyError {
    #[error("invalid flank verify option {field} = {value}: expected {expected}")]
    InvalidOption { field: &'static str, value: f64, expected: &'static str },
    #[error(transparent)]
    Cl(#[from] ClError),
    #[error("the CL data has no CUTTER/d,r,e,f,a,b,h statement of a conical tool (got {got:?})")]
    NoConicalCutter { got: Vec<f64> },
    #[error("the CL data's cutter is not a valid cone: {0}")]
    BadCutter(String),
    #[error("strip {strip} of the header names moves {first}-{last}, outside the program's {moves} moves")]
    BadStrip { strip: usize, first: usize, last: usize, moves: usize },
    #[error("the CL data has no strip of at least two poses")]
    NoStrip,
    #[error(transparent)]
    Surface(#[from] VerifyError),
}

/// One swept segment: from move `from` to move `from + 1`.
#[derive(Clone, Copy, Debug)]
struct Segment {
    from: u32,
    /// The strip (0-based) the segment belongs to, and whether it is one of its cutting moves.
    strip: Option<u32>,
    cut: bool,
    /// A bound on how far any point of the cone moves during the segment, mm.
    motion: f64,
}

/// The program as the verifier sees it.
struct Program {
    poses: Vec<ControllerPose>,
    segments: Vec<Segment>,
    strips: Vec<Range<usize>>,
    cone: RoundCone,
    family: SphereFamily,
    tool: ConeTool,
    nodes: Vec<Node>,
    order: Vec<u32>,
    a_out_of_range: Option<usize>,
    feed: Vec<bool>,
    max_axis_norm_error: f64,
}

/// Verifies CL data `cl` against `surface` (module docs).
pub fn verify_flank(
    surface: &Surface,
    cl: &str,
    o: &FlankVerifyOptions,
) -> Result<FlankVerification, FlankVerifyError> {
    if !(1..=crate::verify::MAX_SAMPLES).contains(&o.samples) {
        return Err(FlankVerifyError::InvalidOption {
            field: "samples",
            value: o.samples as f64,
            expected: "1 to 50 000 000",
        });
    }
    let samples = sample_surface(surface, o.samples, o.seed)?;
    let vertices: Vec<SurfaceSample> = if o.vertices {
        (0..surface.positions.len())
            .map(|v| SurfaceSample { position: surface.positions[v], normal: surface.vertex_normals[v], face: 0 })
            .collect()
    } else {
        Vec::new()
    };
    let tree = FaceTree::new(&surface.positions, &surface.triangles);
    // Both sides of a boundary need samples within the band: at least twice their spacing.
    let spacing = (surface.area() / o.samples as f64).sqrt();
    let o = FlankVerifyOptions { seam_band_mm: o.seam_band_mm.or(Some(2.0 * spacing)), ..o.clone() };
    verify_samples(&samples, &vertices, &tree, cl, &o)
}

/// [`verify_flank`] on given samples (e.g. points of an analytic surface and their exact
/// normals) and vertices; `tree` is the surface the envelope branches are measured against.
pub fn verify_samples(
    samples: &[SurfaceSample],
    vertices: &[SurfaceSample],
    tree: &FaceTree,
    cl: &str,
    o: &FlankVerifyOptions,
) -> Result<FlankVerification, FlankVerifyError> {
    if !(o.tolerance_mm >= 0.0 && o.tolerance_mm.is_finite()) {
        return Err(FlankVerifyError::InvalidOption {
            field: "tolerance_mm",
            value: o.tolerance_mm,
            expected: "a finite number ≥ 0",
        });
    }
    for (field, value) in [("search_mm", o.search_mm), ("seam_band_mm", o.seam_band_mm)] {
        if let Some(v) = value {
            if !(v > 0.0 && v.is_finite()) {
                return Err(FlankVerifyError::InvalidOption { field, value: v, expected: "a finite number > 0" });
            }
        }
    }
    let program = read_program(cl)?;
    let search = o.search_mm.unwrap_or(0.5 * program.family.length_mm);
    let probes: Vec<Probe> = crate::par::each(samples.len(), |i| probe(&program, samples[i].position, search));
    let vertex_deviation_mm: Vec<f64> = crate::par::each(vertices.len(), |i| {
        let p = probe(&program, vertices[i].position, search);
        p.best.map_or(f64::NAN, |b| b.distance)
    });

    // Whole-surface figures.
    let n = samples.len();
    let tol = o.tolerance_mm;
    let mut v = FlankVerification {
        samples: n,
        tool: program.tool,
        strips_found: program.strips.len(),
        segments: program.segments.len(),
        machined_samples: 0,
        machined_fraction: 0.0,
        uncovered_samples: 0,
        max_gouge_mm: 0.0,
        gouges: 0,
        max_undercut_mm: 0.0,
        coverage_within_tolerance: 0.0,
        machined_within_tolerance: 0.0,
        tolerance_mm: tol,
        worst_gouge_at: None,
        worst_undercut_at: None,
        strips: Vec::new(),
        seams: Vec::new(),
        max_axis_norm_error: program.max_axis_norm_error,
        kinematics: kinematics(&program, o.near_singular_deg, o.flip_deg),
        vertex_deviation_mm,
    };
    let (mut within, mut machined_within) = (0usize, 0usize);
    let mut per_strip: Vec<Vec<f64>> = vec![Vec::new(); program.strips.len()];
    for (s, p) in samples.iter().zip(&probes) {
        let Some(best) = p.best else {
            v.uncovered_samples += 1;
            continue;
        };
        let d = best.distance;
        if d.abs() <= tol {
            within += 1;
        }
        if -d > v.max_gouge_mm {
            v.max_gouge_mm = -d;
            v.worst_gouge_at = Some(s.position.to_array());
        }
        if -d > tol {
            v.gouges += 1;
        }
        if let Some(strip) = p.machined_by {
            v.machined_samples += 1;
            if d.abs() <= tol {
                machined_within += 1;
            }
            if d > v.max_undercut_mm {
                v.max_undercut_mm = d;
                v.worst_undercut_at = Some(s.position.to_array());
            }
            per_strip[strip].push(d);
        }
    }
    v.machined_fraction = v.machined_samples as f64 / n as f64;
    v.coverage_within_tolerance = within as f64 / n as f64;
    v.machined_within_tolerance =
        if v.machined_samples > 0 { machined_within as f64 / v.machined_samples as f64 } else { 0.0 };
    for (k, devs) in per_strip.iter().enumerate() {
        v.strips.push(strip_figures(k, &program.strips[k], devs));
    }
    let band =
        o.seam_band_mm.unwrap_or(0.01 * program.family.contact_length_mm).max(0.01 * program.family.contact_length_mm);
    v.seams = seams::seams(&program, tree, samples, &probes, band);
    Ok(v)
}

/// What one probe found at a point: the nearest approach overall and per strip.
#[derive(Clone, Debug)]
struct Probe {
    best: Option<swept::Approach>,
    /// The strip whose cutting moves pass over the point (module docs), if any.
    machined_by: Option<usize>,
    /// Per strip whose swept volume comes within 5 % of L of the nearest approach: (strip, its
    /// nearest approach).
    per_strip: Vec<(usize, swept::Approach)>,
}

/// Per-strip approaches are resolved within this fraction of L beyond the nearest one.
const NEAR: f64 = 0.05;

fn probe(program: &Program, q: DVec3, search: f64) -> Probe {
    // Segments whose box is within the search, with their lower bounds from both ends.
    let mut candidates: Vec<(f64, u32, f64, f64)> = Vec::new();
    let mut stack = vec![0u32];
    let search2 = search * search;
    let at = |m: u32| {
        let p = &program.poses[m as usize];
        program.cone.distance(q, p.tip, p.axis).0
    };
    while let Some(index) = stack.pop() {
        let node = &program.nodes[index as usize];
        if node.distance2(q) > search2 {
            continue;
        }
        if node.count == 0 {
            stack.push(node.right);
            stack.push(index + 1);
            continue;
        }
        for slot in node.start..node.start + node.count {
            let id = program.order[slot as usize];
            let seg = &program.segments[id as usize];
            let (d0, d1) = (at(seg.from), at(seg.from + 1));
            candidates.push((0.5 * (d0 + d1 - seg.motion), id, d0, d1));
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut per_strip: Vec<(usize, swept::Approach, bool)> = Vec::new();
    let mut best: Option<(swept::Approach, usize)> = None;
    for &(lower, id, _, _) in &candidates {
        // Strips farther than `NEAR` beyond the nearest approach cannot finish this point.
        if lower > search || best.is_some_and(|(b, _)| lower > b.distance + NEAR * program.family.length_mm) {
            break;
        }
        let seg = &program.segments[id as usize];
        let strip = seg.strip.map_or(usize::MAX, |s| s as usize);
        let slot = per_strip.iter().position(|(s, _, _)| *s == strip);
        if let Some(k) = slot {
            if lower >= per_strip[k].1.distance {
                continue;
            }
        }
        let (p0, p1) = (&program.poses[seg.from as usize], &program.poses[seg.from as usize + 1]);
        let ap = swept::closest(&program.cone, q, p0, p1);
        if ap.distance > search {
            continue;
        }
        // Inside the strip's cut: on the flank, and not before its first pose or after its last.
        let interior = seg.cut && ap.on_flank && {
            let r = &program.strips[strip];
            let first = seg.from as usize == r.start && ap.tau <= 1e-9;
            let last = seg.from as usize + 1 == r.end - 1 && ap.tau >= 1.0 - 1e-9;
            !(first || last)
        };
        match slot {
            Some(k) => {
                if ap.distance < per_strip[k].1.distance {
                    per_strip[k] = (strip, ap, interior);
                }
            }
            None => per_strip.push((strip, ap, interior)),
        }
        if best.map_or(true, |(b, _)| ap.distance < b.distance) {
            best = Some((ap, strip));
        }
    }
    let machined_by = per_strip
        .iter()
        .filter(|(s, _, interior)| *interior && *s != usize::MAX)
        .min_by(|a, b| a.1.distance.total_cmp(&b.1.distance))
        .map(|(s, _, _)| *s);
    let mut per_strip: Vec<(usize, swept::Approach)> =
        per_strip.into_iter().filter(|(s, _, _)| *s != usize::MAX).map(|(s, a, _)| (s, a)).collect();
    per_strip.sort_by_key(|(s, _)| *s);
    Probe { best: best.map(|(b, _)| b), machined_by, per_strip }
}

fn strip_figures(k: usize, range: &Range<usize>, devs: &[f64]) -> StripDeviation {
    let mut abs: Vec<f64> = devs.iter().map(|d| d.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let n = abs.len();
    let rank = |p: f64| if n == 0 { 0.0 } else { abs[((p * n as f64).ceil() as usize).clamp(1, n) - 1] };
    let mean = if n > 0 { abs.iter().sum::<f64>() / n as f64 } else { 0.0 };
    let rms = if n > 0 { (devs.iter().map(|d| d * d).sum::<f64>() / n as f64).sqrt() } else { 0.0 };
    StripDeviation {
        strip: k + 1,
        moves: [range.start, range.end - 1],
        samples: n,
        mean_abs_mm: mean,
        rms_mm: rms,
        p95_abs_mm: rank(0.95),
        p99_abs_mm: rank(0.99),
        max_abs_mm: abs.last().copied().unwrap_or(0.0),
        max_mm: devs.iter().copied().fold(0.0, f64::max),
        min_mm: devs.iter().copied().fold(0.0, f64::min),
    }
}

/// Reads the CL data: the cone, the poses, the strips, the swept segments and their hierarchy.
fn read_program(cl: &str) -> Result<Program, FlankVerifyError> {
    let program = parse_cl(cl)?;
    let c = &program.cutter;
    if c.len() != 7 || c[1] != 0.0 {
        return Err(FlankVerifyError::NoConicalCutter { got: c.clone() });
    }
    let (rho1, taper_deg, flute) = (0.5 * c[0], c[5], c[6]);
    let top = rho1 + flute * crate::num::tan(taper_deg.to_radians());
    let tool = ConeTool { tip_radius_mm: rho1, top_radius_mm: top, flute_length_mm: flute };
    let family = tool.spheres().map_err(|e| FlankVerifyError::BadCutter(e.to_string()))?;
    let moves = &program.moves;
    let tips: Vec<DVec3> = moves.iter().map(|m| m.tip).collect();
    let max_axis_norm_error = moves.iter().map(|m| (m.axis.length() - 1.0).abs()).fold(0.0, f64::max);
    let axes: Vec<DVec3> = moves.iter().map(|m| m.axis.normalize_or_zero()).collect();
    let (poses, a_out_of_range) = swept::controller_poses(&tips, &axes);
    let feed: Vec<bool> = moves.iter().map(|m| !m.rapid).collect();
    let strips = strip_ranges(cl, &feed)?;
    if strips.is_empty() {
        return Err(FlankVerifyError::NoStrip);
    }
    let cone = RoundCone::new(&family);
    let mut segments = Vec::new();
    for k in 1..moves.len() {
        if !feed[k] {
            continue;
        }
        let from = k - 1;
        let owner = strips.iter().position(|r| (r.start.saturating_sub(1)..=r.end).contains(&k));
        let cut = owner.is_some_and(|s| k > strips[s].start && k < strips[s].end);
        let (p0, p1) = (&poses[from], &poses[k]);
        // Motion bound: the tip's travel plus the swing of the farthest cone point, over 8
        // sub-steps of the interpolated axis (each a chord of its arc; doubled for safety).
        let mut swing = 0.0f64;
        let mut prev = p0.axis;
        for t in 1..=8 {
            let (_, axis) = swept::pose_at(p0, p1, t as f64 / 8.0);
            swing += swept::angle(prev, axis);
            prev = axis;
        }
        let motion = p0.tip.distance(p1.tip) + 2.0 * swing * cone.reach();
        segments.push(Segment { from: from as u32, strip: owner.map(|s| s as u32), cut, motion });
    }
    if segments.is_empty() {
        return Err(FlankVerifyError::NoStrip);
    }
    // Boxes: the round cones at 9 instants, grown by the motion between instants.
    let bounds: Vec<(DVec3, DVec3)> = segments
        .iter()
        .map(|s| {
            let (p0, p1) = (&poses[s.from as usize], &poses[s.from as usize + 1]);
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for t in 0..=8 {
                let (tip, axis) = swept::pose_at(p0, p1, t as f64 / 8.0);
                let a = tip + cone.offset * axis;
                let b = a + cone.length * axis;
                let r = cone.r1.max(cone.r1 + cone.delta_r);
                lo = lo.min(a.min(b) - DVec3::splat(r));
                hi = hi.max(a.max(b) + DVec3::splat(r));
            }
            let grow = DVec3::splat(s.motion / 8.0);
            (lo - grow, hi + grow)
        })
        .collect();
    let mids: Vec<DVec3> = bounds.iter().map(|(lo, hi)| 0.5 * (*lo + *hi)).collect();
    let (nodes, order) = bvh::build(&bounds, &mids);
    Ok(Program { poses, segments, strips, cone, family, tool, nodes, order, a_out_of_range, feed, max_axis_norm_error })
}

/// The strips' move ranges (first pose .. last pose + 1) from the header comments, or every run
/// of feed moves between rapids.
fn strip_ranges(cl: &str, feed: &[bool]) -> Result<Vec<Range<usize>>, FlankVerifyError> {
    let mut out = Vec::new();
    for line in cl.lines() {
        let Some(rest) = line.trim().strip_prefix("$$ - strip ") else { continue };
        let Some((number, tail)) = rest.split_once(':') else { continue };
        let Some(moves) = tail.trim().strip_prefix("moves ") else { continue };
        let span = moves.split(|c: char| c == ',' || c.is_whitespace()).next().unwrap_or("");
        let (Some((a, b)), Ok(strip)) = (span.split_once('-'), number.trim().parse::<usize>()) else { continue };
        let (Ok(first), Ok(last)) = (a.parse::<usize>(), b.parse::<usize>()) else { continue };
        if last < first || last >= feed.len() {
            return Err(FlankVerifyError::BadStrip { strip, first, last, moves: feed.len() });
        }
        out.push(first..last + 1);
    }
    if out.is_empty() {
        let mut k = 0;
        while k < feed.len() {
            if feed[k] {
                let start = k;
                while k < feed.len() && feed[k] {
                    k += 1;
                }
                if k - start >= 2 {
                    out.push(start..k);
                }
            } else {
                k += 1;
            }
        }
    }
    out.retain(|r| r.len() >= 2);
    Ok(out)
}

fn kinematics(p: &Program, near_singular_deg: f64, flip_deg: f64) -> Kinematics {
    let mut k = Kinematics {
        max_a_step_deg: 0.0,
        max_c_step_deg: 0.0,
        c_flips: 0,
        a_sign_changes: 0,
        near_singular_moves: 0,
        a_out_of_range: p.a_out_of_range,
    };
    for i in 1..p.poses.len() {
        if !p.feed[i] || p.poses[i].a_deg.is_nan() {
            continue;
        }
        let (a, b) = (&p.poses[i - 1], &p.poses[i]);
        let (da, dc) = ((b.a_deg - a.a_deg).abs(), (b.c_deg - a.c_deg).abs());
        k.max_a_step_deg = k.max_a_step_deg.max(da);
        k.max_c_step_deg = k.max_c_step_deg.max(dc);
        let near = b.a_deg.abs() < near_singular_deg;
        if near {
            k.near_singular_moves += 1;
        }
        if dc > flip_deg && (near || a.a_deg.abs() < near_singular_deg) {
            k.c_flips += 1;
        }
        if a.a_deg * b.a_deg < 0.0 {
            k.a_sign_changes += 1;
        }
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CL data of one strip: `axes` as (A, C) in degrees, tips along X.
    fn program(axes: &[(f64, f64)]) -> String {
        let mut cl = String::from("PARTNO t\nUNITS/MM\nMULTAX/ON\nCUTTER/2.0,0,1.0,0,0,5.0,10.0\nFEDRAT/100.0\n");
        for (k, &(a, c)) in axes.iter().enumerate() {
            let v = crate::gcode::ac::axis_of(a, c);
            cl.push_str(&format!("GOTO/{},0,0,{},{},{}\n", k as f64, v.x, v.y, v.z));
        }
        cl + "FINI\n"
    }

    #[test]
    fn kinematics_counts_flips_near_the_singular_pose() {
        let p = read_program(&program(&[(30.0, 0.0), (30.0, 5.0), (30.0, 10.0)])).unwrap();
        let k = kinematics(&p, 2.0, 45.0);
        assert!((k.max_c_step_deg - 5.0).abs() < 1e-9 && k.max_a_step_deg < 1e-9, "{k:?}");
        assert_eq!((k.c_flips, k.a_sign_changes, k.near_singular_moves), (0, 0, 0));
        // Near A = 0 the azimuth swings 80° a move: the table turns C 80°, a flip each time.
        let p = read_program(&program(&[(1.0, 0.0), (1.0, 80.0), (1.0, 160.0)])).unwrap();
        let k = kinematics(&p, 2.0, 45.0);
        assert_eq!((k.c_flips, k.near_singular_moves), (2, 2), "{k:?}");
        assert!((k.max_c_step_deg - 80.0).abs() < 1e-6);
        // Through A = 0 the post takes the other branch: A changes sign, C stays.
        let p = read_program(&program(&[(1.0, 0.0), (1.0, 180.0)])).unwrap();
        let k = kinematics(&p, 2.0, 45.0);
        assert_eq!((k.a_sign_changes, k.c_flips), (1, 0), "{k:?}");
    }

    #[test]
    fn cutters_that_are_not_cones_are_refused() {
        let ball = "PARTNO t\nUNITS/MM\nCUTTER/6.0,3.0\nFEDRAT/100\nGOTO/0,0,0\nGOTO/1,0,0\nFINI\n";
        assert!(matches!(read_program(ball), Err(FlankVerifyError::NoConicalCutter { .. })));
        let bad_strip = program(&[(30.0, 0.0), (30.0, 5.0)]).replace("FEDRAT", "$$ - strip 1: moves 0-9\nFEDRAT");
        assert!(matches!(read_program(&bad_strip), Err(FlankVerifyError::BadStrip { strip: 1, last: 9, .. })));
    }
}
