//! Stage 5 — `spacing`: the radii of the iso-parametric rings |w| = R_k that keep the scallop
//! height under the user's limit everywhere (seed 000 §2.2.1, eqs. 1–4, Pseudocode A-1).
//!
//! # What it computes
//! Rings are circles |w| = R_1 > R_2 > … of the slit domain; on the surface they are the
//! cutter-contact curves C_k = ω_SF⁻¹(C_k^S), and the ball centres run along C_k^T = C_k + R·n.
//! A point of the iso-scallop surface S^h (the surface offset by h along its normal) is cut when
//! it lies within R of a ball centre; then the material left above the surface there is at most
//! h (seed eq. 1). Rings are found from the outside in, each as the smallest radius whose band
//! [R_{k+1}, R_k] is still entirely cut by rings k and k+1 (a bisection, as in seed A-1).
//!
//! Where seed A-1 tests a cloud of S^h samples, this stage tests the *cusp* of each meridian
//! exactly: along a meridian arg w = θ (orthogonal to the rings on the surface, the map being
//! conformal) the distance to ring k grows and the distance to ring k+1 shrinks, so the worst
//! point of the band is where the two are equal; it is found by root finding (regula falsi) on
//! the meridian instead of being hoped for among samples, which is what lets the verifier's
//! fresh samples agree with the promise. Meridians are spaced `meridian_spacing_mm` apart along
//! the ring (plus dense ones at every slit tip and at every corner of the outer loop, which the map
//! squeezes into a tiny arc); a meridian that crosses a hole's slit splits:
//! the part above the hole must be cut by ring k, the part below by ring k+1.
//!
//! Between meridians the scallop can still peak: at the kinks of rings crossing long facets,
//! across creases, where the P1 image overlaps itself below a slit tip (up to 1.3 h on the shared
//! meshes). So each ring the meridians admit passes a gate ([`gate`], the samples of seed A-1
//! placed where those peaks are): points of S^h along every edge, along lines |w| = const across
//! every face of the band and round the ends of holes must lie within R of the ball-centre
//! polylines of rings k and k+1; where some do not, the ring moves up until they do.
//!
//! With exact facets ([`SpacingOptions::facet_lift`]) the toolpath moves every ball centre off
//! the facets, along the interpolated normal: where that normal is tilted from the facet's, the
//! ball rides higher than the rings were spaced for, and the scallop beside it rises by as much.
//! The rings' ball centres are then moved out by that much (within bounds, see `planned_lift_mm`)
//! before the band between them is tested; balls touching a face certified free
//! (`face_lifts_free`, most faces of a smooth part) keep the offset's centre without the search.
//!
//! The first ring cuts the band up to the outer boundary (|w| = 1) by itself. The last one: in
//! disk mode the band around the pole is closed by the ball at the pole (the spiral ends there);
//! in annulus mode the last ring is the inner circle |w| = R_A itself (the spiral ends on it).
//!
//! # Entry points
//! [`spacing`] (one-off); [`spacing_on`] with the map's [`Lift`] built once for the spacing and
//! the spiral; [`SpacingIndex`] (the map's indexes, which need no lift, built beside it) and
//! [`SpacingIndex::rings`]. The three give the same rings.
//!
//! # Preconditions
//! A slit map of the surface (same vertices), ball radius R > 0, 0 < h < R.
//!
//! # Invariants of the output
//! Radii strictly decreasing in (R_min, 1) (annulus: the last one equals R_A), none within the
//! polygonal sag of a slit radius (so a ring never runs through a slit), every meridian
//! cusp tested at most R from a ball centre on S^{h·target_fraction}, and every gate point of a
//! band cut at 0.95 h, but in the bands counted by `gate_compromises` (and the last band of a
//! disk map, closed by the ball at the pole); with exact facets, against centres moved out by
//! their planned lift.

// `!(x > y)` is deliberate: NaN must fail every progress test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod gate;
mod lift;

pub use lift::{Lift, Lifted};

use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use crate::num;
use crate::slitmap::{Mode, SlitMap};
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

/// Options of the spacing stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpacingOptions {
    /// Ball radius R, mm. Default 3.
    pub radius_mm: f64,
    /// The scallop-height limit h, mm. Default 0.02.
    pub scallop_mm: f64,
    /// Rings are spaced for a cusp of `target_fraction · h`: the margin covers what lies between
    /// meridians and the chordal sampling of the path. Default 0.95 (0.97 left 1.02 h on
    /// freeform_4_holes).
    pub target_fraction: f64,
    /// Meridians tested per ring are this far apart along the ring, mm. `None`: R / 2.
    pub meridian_spacing_mm: Option<f64>,
    /// The bisection of a ring radius stops when its bracket is below this fraction of the ring
    /// step. Default 2e-3.
    pub step_tolerance: f64,
    /// More rings than this is an error (the options are surely wrong). Default 20 000.
    pub max_rings: usize,
    /// The toolpath moves every ball centre off the facets (exact facets, see
    /// [`crate::toolpath::clear_facets`]): plan for that lift. Default false (smooth facets).
    pub facet_lift: bool,
}

impl Default for SpacingOptions {
    fn default() -> Self {
        Self {
            radius_mm: 3.0,
            scallop_mm: 0.02,
            target_fraction: 0.95,
            meridian_spacing_mm: None,
            step_tolerance: 2e-3,
            max_rings: 20_000,
            facet_lift: false,
        }
    }
}

/// Errors of the spacing stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpacingError {
    #[error("invalid spacing option: {0}")]
    InvalidOption(String),
    #[error("the slit map has {map} vertices but the surface {surface}: they must come from the same mesh")]
    MeshMismatch { map: usize, surface: usize },
    #[error("the facet tree has {tree} faces but the surface {surface}: it must be built on the same mesh")]
    FacetTreeMismatch { tree: usize, surface: usize },
    #[error("the ball (radius {radius_mm} mm) cuts the whole part from its centre: choose a smaller tool")]
    ToolLargerThanPart { radius_mm: f64 },
    #[error("no ring radius below {radius} covers the next band (ring {ring}): the surface cannot be cut with this ball here")]
    NoProgress { ring: usize, radius: f64 },
    #[error("more than {max} rings are needed: the scallop height is too small for this part and tool")]
    TooManyRings { max: usize },
    #[error("the slit domain point at radius {rho}, angle {theta} does not lie on the surface")]
    Lift { rho: f64, theta: f64 },
    #[error("the spacing index was built for another slit map or surface than the lift's")]
    IndexMismatch,
}

/// One ring of the plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ring {
    /// |w| of the ring.
    pub radius: f64,
    /// Length of its cutter-contact curve on the surface, mm (sampled, for bridging and reports).
    pub length_mm: f64,
}

/// The rings, outermost first.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rings {
    pub rings: Vec<Ring>,
    pub mode: Mode,
    /// 0 (disk) or the annulus inner radius R_A.
    pub r_min: f64,
    /// The scallop height the rings were spaced for, mm (`target_fraction · h`).
    pub planned_scallop_mm: f64,
    /// Meridians tested, summed over rings.
    pub meridians: usize,
    /// Radii tried by the bisections.
    pub trials: usize,
    /// Rings moved below a P1 fold at a slit tip although the band above was not proven cut
    /// there (the alternative, a ring through the fold, could jump across the hole).
    pub fold_compromises: usize,
    /// Bands spaced without their crease tests: no ring passed them (a concave crease sharper
    /// than the ball, where the surface itself leaves more than h).
    pub crease_compromises: usize,
    /// Rings placed although the gate still found a point of their band uncut after
    /// [`GATE_ROUNDS`] rounds.
    pub gate_compromises: usize,
}

impl Rings {
    pub fn radii(&self) -> Vec<f64> {
        self.rings.iter().map(|r| r.radius).collect()
    }
}

/// A slit as the spacing needs it: radius, angular range and how far its polygonal sides sag.
#[derive(Debug, Clone, Copy)]
struct SlitBand {
    radius: f64,
    theta_start: f64,
    extent: f64,
    /// Radii within this distance of `radius` are on the slit itself (rounding).
    sag: f64,
}

impl SlitBand {
    fn contains(&self, theta: f64) -> bool {
        crate::num::rem_tau(theta - self.theta_start) <= self.extent
    }
}

/// Meridians this close to a slit tip (radians of the slit domain) get the point-by-point test.
const TIP_WINDOW: f64 = 0.05;

/// Extra meridians on either side of a slit tip, radians from it: the map squeezes the surface
/// round the end of a hole into a tiny arc, so they are dense near the tip (ratio √2). Out to
/// 0.032 rad only, freeform_4_holes kept 1.03 h at 0.037 rad past a tip.
const TIP_OFFSETS: [f64; 18] = [
    0.0, 5e-4, 7e-4, 1e-3, 1.4e-3, 2e-3, 2.8e-3, 4e-3, 5.7e-3, 8e-3, 1.1e-2, 1.6e-2, 2.3e-2, 3.2e-2, 4.5e-2, 6.4e-2,
    9e-2, 0.128,
];

/// Extra meridians on either side of a corner of the outer loop, radians: the rings turn round a
/// corner within a few 1e-4 rad of the map (freeform_4_holes: 1.09 h at a corner with the finest
/// offset 5e-4).
const CORNER_OFFSETS: [f64; 12] = [0.0, 1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 3.5e-4, 5e-4, 1e-3, 2e-3, 4e-3, 8e-3];

/// The offsets of `all` that matter for a band below ring `hi` near a feature (slit tip, corner)
/// at radius `rho`: at a distance δ in log-radius from it the map's detail round the feature is
/// about δ wide in angle, so offsets much finer than δ all test the same place and are dropped.
fn offsets_at(all: &[f64], hi: f64, rho: f64) -> impl Iterator<Item = f64> + '_ {
    let delta = crate::num::ln(hi / rho).abs();
    all.iter().copied().filter(move |&d| d == 0.0 || d >= delta / 8.0)
}

/// Ball centres near one meridian angle on one ring (five, spanning about ±R along it), with the
/// parabola through each half computed once: a chain is measured against many points.
#[derive(Debug, Clone, Copy)]
struct Chain {
    /// The contact of the middle centre (on the meridian itself): the band's point of S^h at
    /// this ring is taken from it, not lifted again.
    contact: Lifted,
    centres: [DVec3; 5],
    /// Per half (centres 0–2, then 2–4): u and v of P(t) = a + t·u + t²·v through its three
    /// centres at t = 0, 1, 2, and whether it turns sharply (see [`Chain::distance`]).
    halves: [(DVec3, DVec3, bool); 2],
}

/// One-off entry: the ring radii for `map` on `surface`.
pub fn spacing(surface: &Surface, map: &SlitMap, options: &SpacingOptions) -> Result<Rings, SpacingError> {
    let faces = FaceTree::new(&surface.positions, &surface.triangles);
    let index = SpacingIndex::new(surface, map, &faces, options)?;
    index.rings(&Lift::new(surface, map))
}

/// The ring radii for the map `lift` inverts, on its surface (the lift built once per map is
/// shared with [`crate::spiral::spiral_on`]); `faces` is the facet tree of that surface (a
/// planner keeps one per part).
pub fn spacing_on(lift: &Lift<'_>, faces: &FaceTree, options: &SpacingOptions) -> Result<Rings, SpacingError> {
    SpacingIndex::new(lift.surface(), lift.map(), faces, options)?.rings(lift)
}

/// What the spacing indexes of one slit map before its rings are found (the gate's edges,
/// lines and hole-end points, the outer corners and creases in the log-polar strip, the slits
/// and folds): it needs the map but not its inverse ([`Lift`]), so a planner builds the two
/// side by side ([`SpacingIndex::new`], then [`SpacingIndex::rings`]).
pub struct SpacingIndex<'a> {
    surface: &'a Surface,
    map: &'a SlitMap,
    options: SpacingOptions,
    gate: gate::Gate<'a>,
    slits: Vec<SlitBand>,
    lift_h: Option<f64>,
    corners: Vec<(f64, f64)>,
    creases: Vec<(DVec2, DVec2)>,
    forbidden: Vec<(f64, f64)>,
}

fn check_options(o: &SpacingOptions) -> Result<(), SpacingError> {
    let bad = |m: String| Err(SpacingError::InvalidOption(m));
    if !(o.radius_mm.is_finite() && o.radius_mm > 0.0) {
        return bad(format!("ball radius {} mm must be a positive number", o.radius_mm));
    }
    if !(o.scallop_mm.is_finite() && o.scallop_mm > 0.0) {
        return bad(format!("scallop height {} mm must be a positive number", o.scallop_mm));
    }
    if o.scallop_mm >= o.radius_mm {
        return bad(format!(
            "scallop height {} mm must be smaller than the ball radius {} mm",
            o.scallop_mm, o.radius_mm
        ));
    }
    if !(o.target_fraction > 0.0 && o.target_fraction <= 1.0) {
        return bad(format!("target fraction {} must be in (0, 1]", o.target_fraction));
    }
    if let Some(m) = o.meridian_spacing_mm {
        if !(m.is_finite() && m > 0.0) {
            return bad(format!("meridian spacing {m} mm must be a positive number"));
        }
    }
    if !(o.step_tolerance > 0.0 && o.step_tolerance < 0.5) {
        return bad(format!("step tolerance {} must be in (0, 0.5)", o.step_tolerance));
    }
    Ok(())
}

struct Spacer<'a> {
    lift: &'a Lift<'a>,
    gate: gate::Gate<'a>,
    gate_compromises: usize,
    slits: Vec<SlitBand>,
    mode: Mode,
    r_min: f64,
    ball: f64,
    h: f64,
    /// The user's h, when the balls' lifts off the facets are planned for (some facet of the
    /// part tilts enough from its corners' normals to need it: see [`cleared_lift_mm`]).
    lift_h: Option<f64>,
    /// With `lift_h`: per face, whether every ball touching it is certified to lift by no more
    /// than [`LIFT_FREE`]·h ([`Spacer::free_face`]), settled on first use.
    free: Vec<OnceLock<bool>>,
    surface: &'a Surface,
    meridian_mm: f64,
    /// arg w and |w| of the corners of the outer loop (and of the annulus' inner loop).
    corners: Vec<(f64, f64)>,
    /// Creases (see [`creases`]) in the log-polar strip: (arg w, |w|) of their ends, the angle
    /// of the second within π of the first.
    creases: Vec<(DVec2, DVec2)>,
    /// Radial intervals no ring may run in: the radius ranges of flipped image triangles (P1
    /// folds at slit tips), where the inverse map is not one-to-one and a ring would jump.
    forbidden: Vec<(f64, f64)>,
    options: SpacingOptions,
    trials: usize,
    meridians: usize,
    fold_compromises: usize,
    crease_compromises: usize,
    /// arg w of the meridians that decided the last ring (see [`Spacer::next_radius`]).
    binding: Vec<f64>,
    /// arg w of the last meridian a full check found uncut: the next band's checks start there,
    /// as the meridians that fail (round slit tips, on long rings) fail ring after ring.
    fail_theta: f64,
}

/// Meridians after one a full check found uncut that are tested with it (see
/// [`Spacer::next_radius`]).
const CLUSTER: usize = 32;

/// The gate tests its points at this fraction of h (the rest covers the spiral's chords).
const GATE_FRACTION: f64 = 0.95;
/// Rounds of moving a ring up before the gate gives in (reported).
const GATE_ROUNDS: usize = 4;
/// Bisection steps per round.
const GATE_BISECTIONS: usize = 6;
/// The bisection cuts the failing points at this fraction of the gate's height.
const GATE_BISECTION_MARGIN: f64 = 0.95;
/// A gate polyline's chords stay within this fraction of h of the ring.
const GATE_SAG: f64 = 0.02;

/// Lifts off the facets up to this fraction of h are left to the target's margin. That margin
/// (1 − [`GATE_FRACTION`]) is mostly the path's chords' (the gate's polylines within
/// [`GATE_SAG`]·h, the spiral's within 0.03 h along the normal), so only the smallest lifts are
/// left to it. At 0.1 h plate_holes kept 1.075 h (pole `hole:5`, where the refinement tilts the
/// flat top's normals 2.2°) and wavy_mesh_with_hole 1.81 h beside its creases (now 0.95 and
/// 1.35 h, for 1.6 % and 8 % more path). The 40k-face panel's lifts stay free (its G-code is the
/// same as without them), but some of its facets lift a ball by more, so its rings' centres are
/// still cleared (2.4 million clearances per plan: docs/benchmarks.md).
const LIFT_FREE: f64 = 0.03;
/// A face's balls are certified free ([`face_lifts_free`]) when its own tilt and its sampled
/// balls lift them by at most this fraction of the free lift.
const FREE_SAMPLED: f64 = 0.5;
/// Where [`face_lifts_free`] clears a face's balls: its corners, edge midpoints and centroid.
const FREE_SAMPLES: [[f64; 3]; 7] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
];
/// Lifts are planned for up to this fraction of h.
pub const LIFT_CAP: f64 = 0.65;

/// With exact facets, a ball the clearance lifts by more than this over its contact (the most
/// the spacing plans for, [`LIFT_CAP`]·h) is let down into the crease beside it instead when
/// that leaves less ([`crate::mesh::nearest::FaceTree::rest_ball`]): the toolpath's
/// ([`crate::toolpath::clear_facets`]) and the spacing's balls alike.
pub fn rest_above_mm(h: f64) -> f64 {
    LIFT_CAP * h
}
/// Where the facets alone leave more than this fraction of h (a ball touching there lifts by
/// more), the verifier reports a facet valley: no ring reaches into it.
pub const LIFT_VALLEY: f64 = 0.75;

/// The part of a ball's lift `lift` off the facets the spacing plans for (see
/// [`cleared_lift_mm`]). A ball in a facet valley (lifted by more than [`LIFT_VALLEY`]·h) still
/// rides at least [`LIFT_CAP`]·h higher: gen198's rings lifted 0.71–0.78 h, and the band between
/// them kept 1.06 h when the valley's balls were planned on the surface.
fn planned_lift_mm(lift: f64, h: f64) -> f64 {
    (lift - LIFT_FREE * h).clamp(0.0, LIFT_CAP * h)
}

/// With exact facets, how much higher than on the surface's offset the ball of radius `r`
/// touching at `p` (face `face`, interpolated normal `n`) rides, and the direction from the
/// contact to its centre: placed along n it dips into the facet whose normal is tilted by α from
/// n (and, at a concave edge, its neighbour), and the toolpath moves it out along n until no facet
/// is nearer than R ([`crate::toolpath::clear_facets`], R(1/cos α − 1) off one facet's plane):
/// the same clearance is run here. The first [`LIFT_FREE`]·h of it is left to the target's margin
/// and at most [`LIFT_CAP`]·h is planned for ([`planned_lift_mm`]). The rings' centres are moved
/// out by it, so that a band is tested against the balls that will cut it. Lowering the points
/// tested by the lift of a ball touching *there* instead missed the cutting balls' own (gen001,
/// 146 and 198 of issue 34's sweep kept 1.01–1.06 h), and the contact facet's R(1/cos α − 1)
/// alone, which jumps at every edge, left gen198 1.10 h where the ball rests on an edge.
///
/// A ball lifted more than [`LIFT_CAP`]·h is replaced, as the toolpath replaces it, by the ball
/// touching the contact's own facet there, let down into the crease beside it
/// ([`FaceTree::rest_ball`]) when that leaves less over the contact: its centre's direction from
/// the contact and its height over the offset.
fn cleared_lift_mm(faces: &FaceTree, p: DVec3, n: DVec3, face: usize, r: f64, h: f64) -> (DVec3, f64) {
    let start = p + n * r;
    let ball = faces.clear_ball(start, n, r, Some(face), true);
    let over = |c: DVec3| c.distance(p) - r;
    if ball.rounds > 0 && over(ball.centre) > rest_above_mm(h) {
        if let Some(rest) = faces.rest_below(&ball, p, face, r) {
            let to = rest.centre - p;
            return (to / to.length(), over(rest.centre));
        }
    }
    (n, (ball.centre - start).dot(n))
}

/// Whether every ball of radius `r` touching face `face` lifts by at most [`LIFT_FREE`]·h
/// ([`cleared_lift_mm`]), so that none plans a lift and its centre is the offset's. The face's
/// own tilt lifts them by at most [`crate::mesh::Surface::face_lift_mm`] (exact); the other
/// facets within reach are sampled: balls touching at [`FREE_SAMPLES`] points, cleared of every
/// facet, must lift by at most [`FREE_SAMPLED`] of the free lift (the lifts of one face's
/// contacts vary smoothly, and the margin covers what lies between the samples). Most balls of a
/// smooth part touch such faces; settling them here saves the clearance search the spacing
/// would run for each (2.3 million on the 40k-face panel: 0.8 s of its 2.4 s).
fn face_lifts_free(surface: &Surface, faces: &FaceTree, face: usize, r: f64, h: f64) -> bool {
    let bound = FREE_SAMPLED * LIFT_FREE * h;
    if !(surface.face_lift_mm(face, r) <= bound) {
        return false;
    }
    let [a, b, c] = surface.triangles[face].map(|v| surface.positions[v as usize]);
    FREE_SAMPLES.iter().all(|&bary| {
        let n = surface.normal_at(face, bary);
        let (dir, lift) = cleared_lift_mm(faces, a * bary[0] + b * bary[1] + c * bary[2], n, face, r, h);
        dir == n && lift <= bound
    })
}

/// Whether a ball on some facet of `surface` lifts by more than [`LIFT_FREE`]·h.
fn lifts_off_facets(surface: &Surface, r: f64, h: f64) -> bool {
    (0..surface.triangles.len()).any(|f| !(surface.face_lift_mm(f, r) <= LIFT_FREE * h))
}

/// A boundary vertex whose edges turn by more than this (in 3D) is a corner.
const CORNER_TURN: f64 = 25.0 * PI / 180.0;

/// arg w and |w| of the corners of the loops that map onto circles: the outer one, and in
/// annulus mode the inner one.
fn corner_angles(surface: &Surface, map: &SlitMap) -> Vec<(f64, f64)> {
    let mut loops = vec![0];
    if let Mode::Annulus { hole, .. } = map.mode {
        loops.push(hole);
    }
    let mut out = Vec::new();
    for li in loops {
        let l = &surface.loops[li];
        for i in 0..l.len() {
            let p = |k: usize| surface.positions[l[k % l.len()] as usize];
            let (a, b) = (p(i + 1) - p(i), p(i + 2) - p(i + 1));
            let turn = crate::num::atan2(a.cross(b).length(), a.dot(b));
            if turn > CORNER_TURN {
                let w = map.w[l[(i + 1) % l.len()] as usize];
                out.push((crate::num::rem_tau(crate::num::atan2(w.y, w.x)), w.length()));
            }
        }
    }
    out
}

/// An interior edge whose faces turn by more than this (in 3D) is a crease.
const CREASE_TURN: f64 = 3.0 * PI / 180.0;

/// Radii of a band at which the rings' crossings with each crease are tested (fractions of the
/// expected band width below ring k).
const CREASE_DEPTHS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// The creases of a faceted surface in the log-polar strip: interior edges whose two faces turn
/// by more than [`CREASE_TURN`]. The scallop changes abruptly across a crease (the facets meet
/// the ball there, not the interpolated normals), and wavy_mesh_with_hole's worst samples all
/// lay on its 10–14° creases, between meridians.
fn creases(surface: &Surface, map: &SlitMap) -> Vec<(DVec2, DVec2)> {
    let cos_turn = crate::num::cos(CREASE_TURN);
    crate::mesh::geometry::interior_edges(&surface.triangles)
        .into_iter()
        .filter(|&(_, _, f, g)| surface.face_normals[f as usize].dot(surface.face_normals[g as usize]) < cos_turn)
        .map(|(a, b, _, _)| strip_edge(map, a, b))
        .collect()
}

/// The log-polar images (arg w, |w|) of the edge from vertex `a` to `b`, the second angle
/// within π of the first (the edge does not wrap round the strip).
fn strip_edge(map: &SlitMap, a: u32, b: u32) -> (DVec2, DVec2) {
    let strip = |v: u32| {
        let w = map.w[v as usize];
        DVec2::new(crate::num::atan2(w.y, w.x), w.length())
    };
    let (a, mut b) = (strip(a), strip(b));
    b.x = a.x + crate::num::rem_tau(b.x - a.x + PI) - PI;
    (a, b)
}

/// The band above a candidate ring: the meridians tested and ring k's centres near each.
struct Band {
    /// Radius of ring k (1 for the outer boundary).
    hi: f64,
    thetas: Vec<f64>,
    /// Whether each meridian is also tested point by point: within [`TIP_WINDOW`] of a slit tip,
    /// or crossing a crease.
    pointwise: Vec<bool>,
    /// Whether the band has crease meridians.
    creased: bool,
    /// Ring k's chain per meridian; `None` for the first ring (nothing cut above it).
    upper: Option<Vec<Chain>>,
    /// Index of the meridian that failed last: tested first next time.
    last_fail: usize,
    /// Meridians the bisection tests (see [`Spacer::next_radius`]).
    active: Vec<usize>,
}

impl<'a> SpacingIndex<'a> {
    /// The indexes of `map` on `surface` (`faces`: its facet tree) for `options`, checked first.
    pub fn new(
        surface: &'a Surface,
        map: &'a SlitMap,
        faces: &'a FaceTree,
        options: &SpacingOptions,
    ) -> Result<Self, SpacingError> {
        check_options(options)?;
        if let Some((map_vertices, surface_vertices)) = Lift::mismatch(surface, map) {
            return Err(SpacingError::MeshMismatch { map: map_vertices, surface: surface_vertices });
        }
        if faces.face_count() != surface.triangles.len() {
            return Err(SpacingError::FacetTreeMismatch { tree: faces.face_count(), surface: surface.triangles.len() });
        }
        // In the log-polar strip the two sides of a slit are exactly on its line (see `lift`):
        // only radii within rounding of the slit radius are ambiguous.
        let slits = map
            .slits
            .iter()
            .map(|s| SlitBand {
                radius: s.radius,
                theta_start: s.theta_start,
                extent: s.extent(),
                sag: 1e-6 * s.radius.max(1e-3),
            })
            .collect();
        let mut forbidden: Vec<(f64, f64)> = map
            .flipped_faces()
            .into_iter()
            .map(|f| {
                let r = map.triangles()[f].map(|v| map.w[v as usize].length());
                let (lo, hi) = (r[0].min(r[1]).min(r[2]), r[0].max(r[1]).max(r[2]));
                let pad = 0.5 * (hi - lo) + 1e-9;
                (lo - pad, hi + pad)
            })
            .collect();
        forbidden.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for (lo, hi) in forbidden {
            match merged.last_mut() {
                Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
                _ => merged.push((lo, hi)),
            }
        }
        let lift_h = (options.facet_lift && lifts_off_facets(surface, options.radius_mm, options.scallop_mm))
            .then_some(options.scallop_mm);
        // Independent indexes of the same map, built side by side.
        let ((corners, creases), gate) = crate::par::join(
            || (corner_angles(surface, map), creases(surface, map)),
            || gate::Gate::new(surface, map, faces, options.radius_mm, lift_h),
        );
        Ok(Self { surface, map, options: options.clone(), gate, slits, lift_h, corners, creases, forbidden: merged })
    }

    /// The rings, with `lift` the inverse of this index's map on its surface.
    pub fn rings(self, lift: &Lift<'_>) -> Result<Rings, SpacingError> {
        if !(std::ptr::eq(lift.map(), self.map) && std::ptr::eq(lift.surface(), self.surface)) {
            return Err(SpacingError::IndexMismatch);
        }
        Spacer::new(lift, self).run()
    }
}

impl<'a> Spacer<'a> {
    fn new(lift: &'a Lift<'a>, index: SpacingIndex<'a>) -> Self {
        let SpacingIndex { surface, map, options, gate, slits, lift_h, corners, creases, forbidden } = index;
        let faces = if lift_h.is_some() { surface.triangles.len() } else { 0 };
        let r_min = match map.mode {
            Mode::Disk => 0.0,
            Mode::Annulus { inner_radius, .. } => inner_radius,
        };
        Self {
            lift,
            gate,
            gate_compromises: 0,
            corners,
            creases,
            forbidden,
            slits,
            mode: map.mode,
            r_min,
            ball: options.radius_mm,
            h: options.scallop_mm * options.target_fraction,
            lift_h,
            free: (0..faces).map(|_| OnceLock::new()).collect(),
            surface,
            meridian_mm: options.meridian_spacing_mm.unwrap_or(0.5 * options.radius_mm),
            options,
            trials: 0,
            meridians: 0,
            fold_compromises: 0,
            crease_compromises: 0,
            binding: Vec::new(),
            fail_theta: 0.0,
        }
    }

    fn run(mut self) -> Result<Rings, SpacingError> {
        let mut rings: Vec<Ring> = Vec::new();
        let mut last_step: Option<f64> = None;
        // Ring k's ball-centre polyline, for the gate of the band below it.
        let mut upper: Option<gate::RingLine> = None;
        // The band below a ring, made beside its gate (see below).
        let mut ahead: Option<(f64, BandMade)> = None;
        loop {
            let hi = rings.last().map_or(1.0, |r| r.radius);
            let (mut band, hi_length) = match ahead.take() {
                Some((radius, made)) if radius == hi => made?,
                _ => self.band(hi, rings.is_empty(), last_step, true)?,
            };
            self.meridians += band.thetas.len();
            if let Some(last) = rings.last_mut() {
                last.length_mm = hi_length;
            }
            if self.admissible(&mut band, self.r_min)? {
                if rings.is_empty() {
                    return Err(SpacingError::ToolLargerThanPart { radius_mm: self.ball });
                }
                if let Mode::Annulus { .. } = self.mode {
                    let (length_mm, _) = self.ring_length(self.r_min)?;
                    rings.push(Ring { radius: self.r_min, length_mm });
                }
                break;
            }
            let mut radius = self.next_radius(&mut band, last_step)?;
            if !(hi - radius > 1e-12) && band.creased {
                // A concave crease sharper than the ball leaves more than h whatever the rings
                // (the surface makes it impossible): reported, and this band spaced without its
                // crease meridians.
                self.crease_compromises += 1;
                band = self.band(hi, rings.is_empty(), last_step, false)?.0;
                self.meridians += band.thetas.len();
                radius = self.next_radius(&mut band, last_step)?;
            }
            if !(hi - radius > 1e-12) {
                return Err(SpacingError::NoProgress { ring: rings.len() + 1, radius: hi });
            }
            // Most rings pass their gate where the meridians put them: with threads, the band
            // below is made beside the gate's first test (the two are small parallel jobs that
            // leave threads idle on their own), and kept when the ring stays there.
            let test = || self.gate_test(hi, radius, upper.as_ref(), self.centres(radius, None)?);
            let (first, below) = if crate::par::threads() > 1 {
                let (first, below) = crate::par::join(test, || self.band(radius, false, Some(hi - radius), true));
                (first?, Some(below))
            } else {
                (test()?, None)
            };
            let (gated, centres) = self.gated(hi, radius, upper.as_ref(), first)?;
            ahead = below.filter(|_| gated == radius).map(|below| (radius, below));
            let radius = gated;
            upper = Some(centres);
            last_step = Some(hi - radius);
            rings.push(Ring { radius, length_mm: 0.0 });
            if rings.len() > self.options.max_rings {
                return Err(SpacingError::TooManyRings { max: self.options.max_rings });
            }
        }
        Ok(Rings {
            rings,
            mode: self.mode,
            r_min: self.r_min,
            planned_scallop_mm: self.h,
            meridians: self.meridians,
            trials: self.trials,
            fold_compromises: self.fold_compromises,
            crease_compromises: self.crease_compromises,
            gate_compromises: self.gate_compromises,
        })
    }

    /// Smallest admissible radius below `band.hi`. Bisecting over every meridian would test all
    /// of them at every passing trial, although one or two decide the ring: the bisection runs
    /// over an active set of meridians (those that decided the ring above, then every meridian a
    /// full check finds failing, with those failing among the [`CLUSTER`] after it), and only
    /// its result is checked on every meridian.
    fn next_radius(&mut self, band: &mut Band, last_step: Option<f64>) -> Result<f64, SpacingError> {
        let hi = band.hi;
        // Never zero: the search below grows its step from this one.
        let step = last_step.unwrap_or((hi - self.r_min) / 16.0).max(1e-9 * (hi - self.r_min)).min(hi - self.r_min);
        // Known to fail on some meridian (or the floor).
        let mut bad = self.r_min;
        let ok = loop {
            let (ok_a, bad_a) = self.lowest_on_active(band, bad, step)?;
            if !(ok_a < hi) {
                break hi; // nothing below ring k passes: the caller reports no progress
            }
            match self.first_failure(band, ok_a)? {
                None => {
                    // The active meridians that fail just below decide this ring: start the next
                    // ring's active set from them.
                    let mut binding = Vec::new();
                    if bad_a > self.r_min {
                        for k in 0..band.active.len() {
                            if !self.meridian_ok(band, band.active[k], bad_a)? {
                                binding.push(band.thetas[band.active[k]]);
                            }
                        }
                    }
                    self.binding = binding;
                    break ok_a;
                }
                Some(i) => {
                    bad = ok_a;
                    band.active.push(i);
                    // The meridians after it often fail too (the dense ones round a slit tip, a
                    // stretch of a long ring): tested at once, they join the bisection together
                    // instead of costing a bisection and a full check each.
                    let n = band.thetas.len();
                    let next: Vec<usize> =
                        (1..=CLUSTER.min(n - 1)).map(|d| (i + d) % n).filter(|k| !band.active.contains(k)).collect();
                    let (this, tested) = (&*self, &*band);
                    let fails = crate::par::try_map(next.len(), |j| Ok(!this.meridian_ok(tested, next[j], ok_a)?))?;
                    band.active.extend(next.iter().zip(fails).filter(|(_, fail)| *fail).map(|(k, _)| *k));
                }
            }
        };
        // Never run a ring along a slit or through a fold: moving it up only narrows the band;
        // when that reaches ring k, below the fold it must be checked again.
        let mut nudged = ok;
        for s in &self.slits {
            if (nudged - s.radius).abs() < s.sag {
                nudged = s.radius + s.sag;
            }
        }
        if let Some(&(lo, hi_f)) = self.forbidden.iter().find(|(lo, hi_f)| nudged > *lo && nudged < *hi_f) {
            if hi_f < hi {
                nudged = hi_f;
            } else if lo > self.r_min {
                // A ring in a fold could jump across the hole: continuity wins over the cusp
                // test of the few meridians at this slit tip (reported, and seen by `verify`).
                if !self.admissible(band, lo)? {
                    self.fold_compromises += 1;
                }
                nudged = lo;
            }
        }
        let ok = nudged;
        Ok(ok)
    }

    /// The final gate of a ring the meridians admitted at `lo` below ring `hi` (centres
    /// `upper`; `None` for the first ring): the band's gate points ([`gate`]) must be cut at the
    /// user's h·[`GATE_FRACTION`]; `first` is the ring's polyline at `lo` and the points it
    /// leaves uncut ([`Spacer::gate_test`]). While some are not cut, the ring moves up, by
    /// bisection on those points between its place and the lowest |w| among them (where the ring
    /// runs through that point as the lift places rings, see [`gate::Gate::relabel`], unless
    /// the P1 image overlaps itself there), and the band is gated again, at most
    /// [`GATE_ROUNDS`] times. Returns the ring and its ball-centre polyline.
    fn gated(
        &mut self,
        hi: f64,
        lo: f64,
        upper: Option<&gate::RingLine>,
        first: (gate::RingLine, Vec<gate::GatePoint>),
    ) -> Result<(f64, gate::RingLine), SpacingError> {
        let (r, h) = (self.ball, self.options.scallop_mm * GATE_FRACTION);
        let mut lo = lo;
        let (mut lower, mut bad) = first;
        for round in 1.. {
            if bad.is_empty() {
                return Ok((lo, lower));
            }
            // Each at the radius of the ring through it as the lift sees it (the top below).
            for p in &mut bad {
                self.gate.relabel(p, self.lift);
            }
            // Points on ring k's own line (the rim, for the first ring) are its to cut: ring
            // k + 1 moved onto it would cut them no better and make no progress (the band was
            // then spaced again and again, for ever).
            // Points the lift puts below this ring (its pole star, where the strip's image the
            // points were laid in degenerates) are the next band's: moving up cannot cut them.
            bad.retain(|p| p.2 < hi && p.2 > lo);
            if bad.is_empty() {
                break;
            }
            let top = bad.iter().map(|p| p.2).fold(hi, f64::min);
            let focus: Vec<DVec3> = bad.iter().map(|p| p.0).collect();
            let (mut ok, mut no) = (top, lo);
            for _ in 0..GATE_BISECTIONS {
                let mid = 0.5 * (ok + no);
                let centres = self.centres(mid, Some(&focus))?;
                // With a margin: the band's next points lie beside these.
                if gate::Cutter::new(&ring_lines(upper, &centres), r, GATE_BISECTION_MARGIN * h).uncut(&bad).is_empty()
                {
                    ok = mid;
                } else {
                    no = mid;
                }
            }
            lo = self.clear_of_slits(ok, hi);
            lower = self.centres(lo, None)?;
            if round == GATE_ROUNDS {
                break;
            }
            (lower, bad) = self.gate_test(hi, lo, upper, lower)?;
        }
        self.gate_compromises += 1;
        Ok((lo, lower))
    }

    /// The ring `lo`'s centres `lower` and the gate points of the band below ring `hi` (centres
    /// `upper`) that the two leave uncut at the user's h·[`GATE_FRACTION`].
    fn gate_test(
        &self,
        hi: f64,
        lo: f64,
        upper: Option<&gate::RingLine>,
        lower: gate::RingLine,
    ) -> Result<(gate::RingLine, Vec<gate::GatePoint>), SpacingError> {
        let h = self.options.scallop_mm * GATE_FRACTION;
        let bad = self.gate.uncut(lo, hi, &gate::Cutter::new(&ring_lines(upper, &lower), self.ball, h));
        Ok((lower, bad))
    }

    /// `rho` moved up out of a slit's sag or a fold, unless that reaches ring `hi`.
    fn clear_of_slits(&self, rho: f64, hi: f64) -> f64 {
        let mut rho = rho;
        for s in &self.slits {
            if (rho - s.radius).abs() < s.sag && s.radius + s.sag < hi {
                rho = s.radius + s.sag;
            }
        }
        match self.forbidden.iter().find(|(lo, hi_f)| rho > *lo && rho < *hi_f) {
            Some(&(_, hi_f)) if hi_f < hi => hi_f,
            _ => rho,
        }
    }

    /// Ball centres along the ring `rho`: 256 uniform angles, each step halved (to depth 14)
    /// while its middle centre lies more than [`GATE_SAG`]·h off the chord or the chord is
    /// longer than R/2. A step still jumping at that depth with its contacts together is a split
    /// crease ([`crate::mesh::Surface::corner_normals`]): over a convex one the ball rolls round
    /// the edge, and the polyline follows that arc (its chord ran inside it: 1.37 h at
    /// roof_ridge's 60° ridge). With `focus`, only the steps within 3R of one of its points are
    /// refined: the others are farther than R from any point beside them, so they cut none of
    /// them.
    fn centres(&self, rho: f64, focus: Option<&[DVec3]>) -> Result<gate::RingLine, SpacingError> {
        const M: usize = 256;
        // Lifted as the spiral lifts the ring, each point near the face of the one before: where
        // the P1 image overlaps itself (below a slit tip) the nearest-image lift can pick a face
        // the spiral's continuous walk never visits, and the gate would test a ring not cut.
        let contact = |t: f64, near: Option<u32>| -> Result<Lifted, SpacingError> {
            match near {
                Some(f) => self.lift.polar_near(rho, t, f),
                None => self.lift.polar(rho, t),
            }
            .ok_or(SpacingError::Lift { rho, theta: t })
        };
        let centre = |t: f64, near: Option<u32>| -> Result<(DVec3, u32, DVec3), SpacingError> {
            let l = contact(t, near)?;
            Ok((self.ball_centre(&l), l.face, l.p))
        };
        let angle = |i: usize| TAU * i as f64 / M as f64;
        let mut contacts: Vec<Lifted> = Vec::with_capacity(M + 1);
        for i in 0..=M {
            contacts.push(contact(angle(i), contacts.last().map(|l| l.face))?);
        }
        // With `focus`, a step whose centres on the surface's offset (the lift moves them by at
        // most LIFT_CAP·h) lie farther than 3R and twice that from every focus point is neither
        // refined nor near one of them whatever its lift: its ends keep the offset's centres, and
        // the clearance search (most of the spacing's time) runs only where the test looks.
        let unlifted = |l: &Lifted| l.p + l.n * self.ball;
        let lifted_ends: Vec<bool> = match focus {
            None => vec![true; M + 1],
            Some(f) => {
                let reach = 3.0 * self.ball + 2.0 * self.lift_h.map_or(0.0, |h| LIFT_CAP * h);
                let mut ends = vec![false; M + 1];
                for i in 0..M {
                    let (a, b) = (unlifted(&contacts[i]), unlifted(&contacts[i + 1]));
                    if f.iter().any(|q| segment_dist2(*q, a, b) <= reach * reach) {
                        ends[i] = true;
                        ends[i + 1] = true;
                    }
                }
                ends
            }
        };
        let base: Vec<(DVec3, u32, DVec3)> = crate::par::each(M + 1, |i| {
            let l = &contacts[i];
            (if lifted_ends[i] { self.ball_centre(l) } else { unlifted(l) }, l.face, l.p)
        });
        let (tol, chord) = (GATE_SAG * self.options.scallop_mm, 0.5 * self.ball);
        // Each uniform step refined on its own (in parallel): its start and the ends of its
        // pieces, in order.
        let pieces = crate::par::try_map(M, |i| -> Result<Vec<(f64, DVec3)>, SpacingError> {
            let ((c0, f0, p0), (c1, f1, p1)) = (base[i], base[i + 1]);
            let mut out = vec![(angle(i), c0)];
            let near = |q: &DVec3| segment_dist2(*q, c0, c1) <= 9.0 * self.ball * self.ball;
            if focus.is_some_and(|f| !f.iter().any(near)) {
                return Ok(out);
            }
            // Right halves go on the stack first, so the pieces come out in order.
            let mut stack = vec![((angle(i), c0, f0, p0), (angle(i + 1), c1, f1, p1), 0u32)];
            while let Some(((ta, ca, fa, pa), (tb, cb, fb, pb), depth)) = stack.pop() {
                let tm = 0.5 * (ta + tb);
                let cm = if depth < 14 { Some(centre(tm, Some(fa))?) } else { None };
                match cm {
                    Some((cm, fm, pm)) if (cm - 0.5 * (ca + cb)).length() > tol || (cb - ca).length() > chord => {
                        stack.push(((tm, cm, fm, pm), (tb, cb, fb, pb), depth + 1));
                        stack.push(((ta, ca, fa, pa), (tm, cm, fm, pm), depth + 1));
                    }
                    Some(_) => out.push((tb, cb)),
                    None => {
                        // The normals jump here (a split crease): over a convex edge the ball
                        // rolls round it, so its centres run on the arc there, not the chord.
                        let (na, nb) = ((ca - pa).normalize(), (cb - pb).normalize());
                        let reach = 0.5 * ((ca - pa).length() + (cb - pb).length());
                        let jump = (cb - ca).length();
                        if jump > tol && (pb - pa).length() < 0.1 * jump && (nb - na).dot(pb - pa) > 0.0 {
                            let e = 0.5 * (pa + pb);
                            let turn = crate::num::acos(na.dot(nb).clamp(-1.0, 1.0));
                            // Chords of the arc sag at most `tol`.
                            let m = ((turn * (self.ball / (8.0 * tol)).sqrt()).ceil() as usize).max(1);
                            for k in 1..m {
                                let u = k as f64 / m as f64;
                                out.push((ta + u * (tb - ta), e + reach * na.lerp(nb, u).normalize()));
                            }
                        }
                        out.push((tb, cb))
                    }
                }
            }
            out.pop(); // the next step's start
            Ok(out)
        })?;
        let mut line = gate::RingLine::new(rho);
        for (t, c) in pieces.into_iter().flatten() {
            line.push(t, c);
        }
        line.push(angle(M), base[M].0);
        Ok(line)
    }

    /// The meridians below ring `hi` (spaced along its surface curve, plus every slit tip, outer
    /// corner and crease crossing) and ring k's centre chains on them; also the ring's length.
    fn band(&self, hi: f64, first: bool, last_step: Option<f64>, with_creases: bool) -> BandMade {
        let (length, cumulative) = self.ring_length(hi)?;
        let n = ((length / self.meridian_mm).ceil() as usize).clamp(16, 200_000);
        let mut thetas: Vec<f64> = Vec::with_capacity(n + 6 * self.slits.len());
        let m = cumulative.len() - 1;
        let mut j = 0;
        for i in 0..n {
            let target = length * i as f64 / n as f64;
            while j + 1 < m && cumulative[j + 1] < target {
                j += 1;
            }
            let seg = cumulative[j + 1] - cumulative[j];
            let f = if seg > 0.0 { (target - cumulative[j]) / seg } else { 0.0 };
            thetas.push(TAU * (j as f64 + f) / m as f64);
        }
        // The ends of a hole are where the rings turn around it: test them densely.
        for s in &self.slits {
            for (t, out) in [(s.theta_start, -1.0), (s.theta_start + s.extent, 1.0)] {
                for d in offsets_at(&TIP_OFFSETS, hi, s.radius) {
                    thetas.push(crate::num::rem_tau(t + out * d));
                    thetas.push(crate::num::rem_tau(t - out * d));
                }
            }
        }
        // A corner of the outer loop maps to a point of the circle with a tiny angular neighbourhood
        // (the map opens its interior angle to π): its meridians are tested densely too, else the
        // corner itself falls between two meridians.
        for &(c, rho) in &self.corners {
            for d in offsets_at(&CORNER_OFFSETS, hi, rho) {
                thetas.push(crate::num::rem_tau(c + d));
                thetas.push(crate::num::rem_tau(c - d));
            }
        }
        // Where the band's rings cross a crease (the next ring is expected at most about two
        // last steps below this one).
        let depth = last_step.map_or(0.05, |s| 2.0 * s).min(hi - self.r_min);
        let mut on_crease: Vec<f64> = Vec::new();
        for &(a, b) in self.creases.iter().filter(|_| with_creases) {
            let (lo_r, hi_r) = (a.y.min(b.y), a.y.max(b.y));
            if lo_r > hi || hi_r < hi - depth {
                continue;
            }
            if hi_r - lo_r <= 1e-12 {
                // Along the rings: its ends and middle.
                on_crease.extend([a.x, 0.5 * (a.x + b.x), b.x].map(crate::num::rem_tau));
                continue;
            }
            for f in CREASE_DEPTHS {
                let r = hi - f * depth;
                if r >= lo_r && r <= hi_r {
                    let t = (r - a.y) / (b.y - a.y);
                    on_crease.push(crate::num::rem_tau(a.x + t * (b.x - a.x)));
                }
            }
        }
        on_crease.sort_by(f64::total_cmp);
        thetas.extend_from_slice(&on_crease);
        thetas.sort_by(f64::total_cmp);
        thetas.dedup();
        let upper = if first { None } else { Some(crate::par::try_map(thetas.len(), |i| self.chain(hi, thetas[i]))?) };
        // Near a slit tip the meridians bend around the end of the hole on the surface, and across
        // a crease the scallop has a kink, so the distances along them need not be monotone:
        // those are also tested point by point.
        let pointwise = thetas
            .iter()
            .map(|&t| {
                on_crease.binary_search_by(|x| x.total_cmp(&t)).is_ok()
                    || self.slits.iter().any(|s| {
                        let d = |a: f64| (crate::num::rem_tau(t - a + PI) - PI).abs();
                        d(s.theta_start).min(d(s.theta_start + s.extent)) <= TIP_WINDOW
                    })
            })
            .collect();
        let creased = !on_crease.is_empty();
        // The meridians next to those that decided the ring above most likely decide this one.
        let mut active = Vec::new();
        for &t in &self.binding {
            let i = thetas.partition_point(|&x| x < t);
            active.extend([i + thetas.len() - 1, i, i + 1].map(|k| k % thetas.len()));
        }
        active.sort_unstable();
        active.dedup();
        let last_fail = thetas.partition_point(|&x| x < self.fail_theta) % thetas.len();
        Ok((Band { hi, thetas, pointwise, creased, upper, last_fail, active }, length))
    }

    /// 3D length of the ring at `rho` from 2048 uniform angles, with the cumulative lengths.
    fn ring_length(&self, rho: f64) -> Result<(f64, Vec<f64>), SpacingError> {
        const M: usize = 2048;
        let points = crate::par::try_map(M + 1, |i| Ok(self.point(rho, TAU * i as f64 / M as f64)?.p))?;
        let mut cumulative = Vec::with_capacity(M + 1);
        cumulative.push(0.0);
        let mut prev = points[0];
        let mut total = 0.0;
        for &p in &points[1..] {
            total += (p - prev).length();
            cumulative.push(total);
            prev = p;
        }
        Ok((total, cumulative))
    }

    fn point(&self, rho: f64, theta: f64) -> Result<Lifted, SpacingError> {
        self.lift.polar(rho, theta).ok_or(SpacingError::Lift { rho, theta })
    }

    /// Point of S^h on the meridian θ at radius s.
    fn q(&self, s: f64, theta: f64) -> Result<DVec3, SpacingError> {
        Ok(self.q_at(&self.point(s, theta)?))
    }

    /// Point of S^h over the contact `l`.
    fn q_at(&self, l: &Lifted) -> DVec3 {
        l.p + l.n * self.h
    }

    /// The centre of the ball touching at `l`, moved out by its planned lift off the facets
    /// ([`cleared_lift_mm`]), as the toolpath will move it: the offset's on a face whose balls
    /// are certified free.
    fn ball_centre(&self, l: &Lifted) -> DVec3 {
        let Some(h) = self.lift_h else { return l.p + l.n * self.ball };
        if self.free_face(l.face as usize, h) {
            return l.p + l.n * self.ball;
        }
        let (dir, lift) = cleared_lift_mm(self.gate.faces(), l.p, l.n, l.face as usize, self.ball, h);
        l.p + dir * (self.ball + planned_lift_mm(lift, h))
    }

    /// Whether every ball touching face `face` is certified free ([`face_lifts_free`]): settled
    /// once per face, on first use.
    fn free_face(&self, face: usize, h: f64) -> bool {
        *self.free[face].get_or_init(|| face_lifts_free(self.surface, self.gate.faces(), face, self.ball, h))
    }

    /// Ball centres of the ring `rho` around angle θ: five centres spanning about ±R along
    /// the ring, enough to contain the nearest centre to any point of the band on this meridian.
    fn chain(&self, rho: f64, theta: f64) -> Result<Chain, SpacingError> {
        let centre = |t: f64| -> Result<DVec3, SpacingError> { Ok(self.ball_centre(&self.point(rho, t)?)) };
        let contact = self.point(rho, theta)?;
        let c0 = self.ball_centre(&contact);
        let probe = 1e-4;
        let speed = (centre(theta + probe)? - c0).length() / probe;
        if !(speed > 1e-9) {
            return Ok(Chain::new(contact, [c0; 5])); // the pole: every angle is the same point
        }
        let dt = (0.5 * self.ball / speed).min(0.4);
        Ok(Chain::new(
            contact,
            [centre(theta - 2.0 * dt)?, centre(theta - dt)?, c0, centre(theta + dt)?, centre(theta + 2.0 * dt)?],
        ))
    }

    /// Whether a ring at `rho` (with ring k at `band.hi` above it, or the boundary) leaves every
    /// tested meridian of the band cut.
    fn admissible(&mut self, band: &mut Band, rho: f64) -> Result<bool, SpacingError> {
        Ok(self.first_failure(band, rho)?.is_none())
    }

    /// A meridian left uncut by a ring at `rho`, if any (starting from the last one that failed).
    fn first_failure(&mut self, band: &mut Band, rho: f64) -> Result<Option<usize>, SpacingError> {
        self.trials += 1;
        let n = band.thetas.len();
        let start = band.last_fail;
        let at = |k: usize| (start + k) % n;
        let (this, tested) = (&*self, &*band);
        let failed = crate::par::find_first(n, |k| Ok::<_, SpacingError>(!this.meridian_ok(tested, at(k), rho)?))?;
        if let Some(k) = failed {
            band.last_fail = at(k);
            self.fail_theta = band.thetas[band.last_fail];
        }
        Ok(failed.map(at))
    }

    /// The smallest radius in (`bad`, `band.hi`) that every active meridian admits, to the step
    /// tolerance (a bracket expanded down from the last step, then bisection), and the radius
    /// below it that one of them rejects (`bad` when none did).
    fn lowest_on_active(&mut self, band: &Band, bad: f64, step: f64) -> Result<(f64, f64), SpacingError> {
        let hi = band.hi;
        // Whether all pass does not depend on the order they are tried in, but a failing trial
        // stops at its first failure: the meridian that failed last is tried first (the newest
        // first to begin with: the others passed at the radius that it failed).
        let mut order: Vec<usize> = band.active.iter().rev().copied().collect();
        let mut passes = |this: &mut Self, rho: f64| -> Result<bool, SpacingError> {
            this.trials += 1;
            let this = &*this;
            let failed = crate::par::find_first(order.len(), |k| Ok(!this.meridian_ok(band, order[k], rho)?))?;
            if let Some(k) = failed {
                order[..=k].rotate_right(1);
            }
            Ok(failed.is_none())
        };
        let (mut ok, mut bad) = (hi, bad);
        let mut step = step;
        loop {
            let guess = hi - step;
            if guess <= bad {
                break;
            }
            if passes(self, guess)? {
                ok = guess;
                step *= 1.5;
            } else {
                bad = guess;
                break;
            }
        }
        while ok - bad > self.options.step_tolerance * (hi - ok).max(1e-9) && ok - bad > 1e-13 {
            let mid = 0.5 * (ok + bad);
            if passes(self, mid)? {
                ok = mid;
            } else {
                bad = mid;
            }
        }
        Ok((ok, bad))
    }

    fn meridian_ok(&self, band: &Band, i: usize, rho: f64) -> Result<bool, SpacingError> {
        let theta = band.thetas[i];
        let r = self.ball;
        let mut crossing: Option<&SlitBand> = None;
        for s in &self.slits {
            if s.radius > rho && s.radius < band.hi && s.contains(theta) {
                if crossing.is_some() {
                    return Ok(false); // a strip between two holes is cut by neither ring
                }
                crossing = Some(s);
            }
        }
        let lower = self.chain(rho, theta)?;
        match (&band.upper, crossing) {
            // First ring: the band up to the boundary is cut by this ring alone.
            (None, Some(_)) => Ok(false),
            // The boundary point is taken a hair inside: exactly on |w| = 1 the inverse map may
            // pick the neighbouring boundary face of a corner (wavy_mesh_with_hole jumped 0.1 mm).
            (None, None) => Ok(lower.distance(self.q(band.hi * (1.0 - 1e-9), theta)?) <= r),
            // A hole in between: ring k cuts down to its upper rim, this ring up to its lower one.
            (Some(upper), Some(s)) => {
                let up = self.q(s.radius + s.sag, theta)?;
                let down = self.q((s.radius - s.sag).max(rho), theta)?;
                Ok(upper[i].distance(up) <= r && lower.distance(down) <= r)
            }
            (Some(upper), None) => {
                if band.pointwise[i] && !self.band_points_ok(&upper[i], &lower, rho, band.hi, theta)? {
                    return Ok(false);
                }
                self.cusp_ok(&upper[i], &lower, rho, band.hi, theta)
            }
        }
    }

    /// Every one of a few points of S^h along the meridian between the rings is cut by one of them.
    fn band_points_ok(&self, upper: &Chain, lower: &Chain, lo: f64, hi: f64, theta: f64) -> Result<bool, SpacingError> {
        const N: usize = 16;
        for k in 1..N {
            let q = self.q(lo + (hi - lo) * k as f64 / N as f64, theta)?;
            if num::min(upper.distance(q), lower.distance(q)) > self.ball {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The cusp between two rings on one meridian: where the distances to both centre chains are
    /// equal (regula falsi, Illinois variant); cut when that distance is at most R.
    fn cusp_ok(&self, upper: &Chain, lower: &Chain, lo: f64, hi: f64, theta: f64) -> Result<bool, SpacingError> {
        let r = self.ball;
        // The band's ends are the chains' own contacts (lifted at `lo` and `hi` on θ).
        let qa = self.q_at(&lower.contact);
        let (du_a, dl_a) = (upper.distance(qa), lower.distance(qa));
        if du_a <= r {
            return Ok(true);
        }
        let qb = self.q_at(&upper.contact);
        let (du_b, dl_b) = (upper.distance(qb), lower.distance(qb));
        if dl_b <= r {
            return Ok(true);
        }
        // g = d_upper − d_lower: positive at lo, negative at hi.
        let (mut a, mut ga) = (lo, du_a - dl_a);
        let (mut b, mut gb) = (hi, du_b - dl_b);
        if ga <= 0.0 || gb >= 0.0 {
            // Not the usual picture (strongly curved meridian): fall back to the safe answer.
            return Ok(num::min(du_a, dl_a) <= r && num::min(du_b, dl_b) <= r);
        }
        let mut worst = f64::NEG_INFINITY;
        let mut side = 0i8;
        for _ in 0..40 {
            let s = (a * gb - b * ga) / (gb - ga);
            let q = self.q(s, theta)?;
            let (du, dl) = (upper.distance(q), lower.distance(q));
            worst = num::max(worst, num::min(du, dl));
            if worst > r {
                return Ok(false);
            }
            let g = du - dl;
            if g.abs() <= 1e-9 * r || (b - a) <= 1e-12 * (hi - lo) {
                break;
            }
            if g > 0.0 {
                (a, ga) = (s, g);
                if side == 1 {
                    gb *= 0.5;
                }
                side = 1;
            } else {
                (b, gb) = (s, g);
                if side == -1 {
                    ga *= 0.5;
                }
                side = -1;
            }
        }
        Ok(worst <= r)
    }
}

/// What [`Spacer::band`] returns: the band and the length of its upper ring, mm.
type BandMade = Result<(Band, f64), SpacingError>;

/// Ring k's centres (none above the first ring) and the ring below.
fn ring_lines<'b>(upper: Option<&'b gate::RingLine>, lower: &'b gate::RingLine) -> Vec<&'b gate::RingLine> {
    upper.into_iter().chain([lower]).collect()
}

impl Chain {
    fn new(contact: Lifted, centres: [DVec3; 5]) -> Self {
        let half = |a: DVec3, b: DVec3, c: DVec3| {
            let v = (a - 2.0 * b + c) * 0.5;
            let (ab, bc) = (b - a, c - b);
            (b - a - v, v, !(ab.dot(bc) >= SHARP_TURN_COS * ab.length() * bc.length()))
        };
        let c = centres;
        Self { contact, centres, halves: [half(c[0], c[1], c[2]), half(c[2], c[3], c[4])] }
    }

    /// Distance from `q` to the centre curve the chain samples: the parabola through each half.
    /// The polyline through the centres, 1.5 mm chords, lay up to 0.07 mm inside a ring that
    /// bends tightly round a slit tip, and the cusp there was found too low (issue 4,
    /// freeform_4_holes at R = 3 mm). Where a half turns sharply a parabola can overshoot the
    /// curve, so there the farther of parabola and polyline is taken (freeform_4_holes: max
    /// scallop 1.018 h without this, 1.002 h with it).
    fn distance(&self, q: DVec3) -> f64 {
        let c = &self.centres;
        // The nearest chord picks the half and the start of the Newton steps on its parabola.
        let (mut poly, mut k, mut s) = (f64::INFINITY, 0, 0.0);
        for j in 0..4 {
            let (d2, sj) = segment_dist2_at(q, c[j], c[j + 1]);
            if d2 < poly {
                (poly, k, s) = (d2, j, sj);
            }
        }
        let (h, a, t) = if k < 2 { (0, c[0], k as f64 + s) } else { (1, c[2], (k - 2) as f64 + s) };
        let (u, v, sharp) = self.halves[h];
        let smooth = parabola_dist2(a - q, u, v, t);
        let d2 = if sharp { num::max(smooth, poly) } else { smooth };
        // The centres themselves are on the curve: never farther than the nearest of them (a
        // chain folding back on itself made the parabola of the wrong half the estimate, and no
        // radius passed on face_holes, beetle and four more shared meshes).
        c.iter().map(|x| x.distance_squared(q)).fold(d2, num::min).sqrt()
    }
}

/// cos 15°: a chain half turning more than this is sharp (see [`Chain::distance`]).
const SHARP_TURN_COS: f64 = 0.965_925_826_289_068;

/// min over t ∈ [0, 2] of |d + t·u + t²·v|², by Newton steps from `t`.
fn parabola_dist2(d: DVec3, u: DVec3, v: DVec3, mut t: f64) -> f64 {
    let f = |t: f64| (d + u * t + v * (t * t)).length_squared();
    let mut best = f(t);
    for _ in 0..3 {
        let p = d + u * t + v * (t * t);
        let dp = u + v * (2.0 * t);
        let (g, gg) = (p.dot(dp), dp.dot(dp) + 2.0 * p.dot(v));
        if !(gg > 0.0) {
            break;
        }
        t = (t - g / gg).clamp(0.0, 2.0);
        best = num::min(best, f(t));
    }
    best
}

/// Squared distance from `q` to the segment ab, and the parameter of the nearest point.
pub(crate) fn segment_dist2_at(q: DVec3, a: DVec3, b: DVec3) -> (f64, f64) {
    Segment::new(a, b).dist2_at(q)
}

/// A segment with its direction and squared length, for the distances of many points to it
/// (the gate's rings): the same operations as [`segment_dist2_at`], bit for bit, without
/// forming b − a and |b − a|² each time.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Segment {
    a: DVec3,
    ab: DVec3,
    l2: f64,
}

impl Segment {
    pub(crate) fn new(a: DVec3, b: DVec3) -> Self {
        let ab = b - a;
        Self { a, ab, l2: ab.length_squared() }
    }

    /// Squared distance from `q`, and the parameter of the nearest point.
    #[inline]
    pub(crate) fn dist2_at(&self, q: DVec3) -> (f64, f64) {
        let t = if self.l2 > 0.0 { ((q - self.a).dot(self.ab) / self.l2).clamp(0.0, 1.0) } else { 0.0 };
        ((self.a + self.ab * t - q).length_squared(), t)
    }

    #[inline]
    pub(crate) fn dist2(&self, q: DVec3) -> f64 {
        self.dist2_at(q).0
    }
}

/// Squared distance from `q` to the segment ab.
pub(crate) fn segment_dist2(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    segment_dist2_at(q, a, b).0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the distance to the two parabolas, densely sampled.
    fn oracle(q: DVec3, c: &[DVec3; 5]) -> f64 {
        let mut best = f64::INFINITY;
        for (a, b, e) in [(c[0], c[1], c[2]), (c[2], c[3], c[4])] {
            let v = (a - 2.0 * b + e) * 0.5;
            let u = b - a - v;
            for k in 0..=20_000 {
                let t = 2.0 * k as f64 / 20_000.0;
                best = best.min((a + u * t + v * (t * t) - q).length());
            }
        }
        best
    }

    #[test]
    fn the_planned_lift_is_the_cleared_balls_lift_within_its_band() {
        // A ball of radius R along a normal tilted by α from its facet's is moved out by
        // R(1/cos α − 1) by the clearance (then it touches the facet's plane); the spacing plans
        // that lift less the free part, up to the cap, in facet valleys too.
        let (r, h) = (3.0, 0.02);
        let positions = [DVec3::new(-50.0, -50.0, 0.0), DVec3::new(50.0, -50.0, 0.0), DVec3::new(0.0, 50.0, 0.0)];
        let tree = FaceTree::new(&positions, &[[0, 1, 2]]);
        let tilted = |deg: f64| DVec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
        let planned = |deg: f64| {
            let n = tilted(deg);
            let start = n * r;
            let ball = tree.clear_ball(start, n, r, Some(0), true);
            let lift = (ball.centre - start).dot(n);
            assert!((lift - crate::mesh::ball_lift_mm(n, DVec3::Z, r)).abs() < 1e-8 * r, "{deg}°: lift {lift}");
            planned_lift_mm(lift, h)
        };
        for deg in [0.0f64, 2.0, 4.0, 5.0, 5.5, 6.0, 7.0, 10.0, 60.0] {
            let lift = crate::mesh::ball_lift_mm(tilted(deg), DVec3::Z, r);
            let expected = (lift - LIFT_FREE * h).clamp(0.0, LIFT_CAP * h);
            assert!(
                (planned(deg) - expected).abs() < 1e-8 * r,
                "{deg}°: {} mm planned, {expected} expected",
                planned(deg)
            );
        }
        // 1° lifts 0.46 µm (< 0.03 h: left to the margin); 5° lifts 11.5 µm: planned; 10°
        // (a valley: 2.3 h) is planned up to the cap, not dropped.
        assert_eq!(planned(1.0), 0.0);
        assert!(planned(2.0) > 0.05 * h);
        assert!(planned(5.0) > 0.4 * h);
        assert_eq!(planned(10.0), LIFT_CAP * h);
        // A normal facing away from the facet (a fold) rides as high as planned at most.
        assert_eq!(planned_lift_mm(f64::INFINITY, h), LIFT_CAP * h);
    }

    #[test]
    fn a_face_certified_free_lifts_no_ball_it_touches_beyond_the_free_lift() {
        // Brute force: balls touching certified faces at random points, each cleared of every
        // facet, lift by at most LIFT_FREE·h and along their own normal, on generated parts with
        // staircase rims and skinny triangles, where many faces are not free.
        let mut rng = crate::fixtures::SplitMix64(45);
        let (mut certified, mut faces) = (0, 0);
        for (seed, r, h) in [
            (0, 1.75, 0.0064),
            (30, 1.89, 0.005),
            (114, 3.0, 0.02),
            (31, 2.22, 0.0185),
            (5, 2.5, 0.01),
            (24, 4.0, 0.008),
        ] {
            let part = crate::fixtures::generated::part(seed, 3_000..=3_000);
            let surface = crate::mesh::from_triangles(&part.mesh, &Default::default())
                .unwrap()
                .surface
                .with_crease_normals(crate::plan::CREASE_SPLIT_DEG);
            let tree = FaceTree::new(&surface.positions, &surface.triangles);
            let free: Vec<usize> =
                (0..surface.triangles.len()).filter(|&f| face_lifts_free(&surface, &tree, f, r, h)).collect();
            (certified, faces) = (certified + free.len(), faces + surface.triangles.len());
            for &f in &free {
                let [a, b, c] = surface.triangles[f].map(|v| surface.positions[v as usize]);
                for _ in 0..8 {
                    let (u, v) = (rng.unit(), rng.unit());
                    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                    let bary = [1.0 - u - v, u, v];
                    let n = surface.normal_at(f, bary);
                    let (dir, lift) = cleared_lift_mm(&tree, a * bary[0] + b * bary[1] + c * bary[2], n, f, r, h);
                    assert!(dir == n && planned_lift_mm(lift, h) == 0.0, "gen{seed} face {f} at {bary:?}: lift {lift}");
                }
            }
        }
        // Both kinds are common: the test sees many of each.
        assert!(certified > faces / 5 && faces - certified > faces / 5, "{certified} of {faces} faces free");
    }

    #[test]
    fn chain_distance_matches_the_densely_sampled_parabolas() {
        // A ring bending round a slit tip: centres on a circle of radius 4 mm, 1.5 mm apart
        // (each half turns about 21°, sharp: there the polyline's distance, when farther, is
        // taken), and a gently bent one.
        for radius in [4.0, 40.0] {
            let c = [-2.0, -1.0, 0.0, 1.0, 2.0].map(|k: f64| {
                let a = 1.5 * k / radius;
                DVec3::new(radius * a.sin(), radius * (1.0 - a.cos()), 0.0)
            });
            for q in [DVec3::new(0.3, 2.0, 0.5), DVec3::new(-1.1, -1.5, 0.2), DVec3::new(2.5, 0.4, -1.0)] {
                let contact = Lifted { rho: 0.5, theta: 0.0, p: c[2] - DVec3::Z, n: DVec3::Z, face: 0 };
                let d = Chain::new(contact, c).distance(q);
                let poly = (0..4).map(|k| segment_dist2(q, c[k], c[k + 1])).fold(f64::INFINITY, f64::min).sqrt();
                let want = if radius < 10.0 { oracle(q, &c).max(poly) } else { oracle(q, &c) };
                assert!((d - want).abs() < 1e-6, "radius {radius}, q {q}: {d} vs {want}");
            }
        }
    }
}
