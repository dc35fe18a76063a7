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
//! [`SpacingIndex::rings`]. The three give the same rings. A spread field ([`crate::spread`],
//! lifted through [`Lift::spread`]) is indexed from its lift ([`SpacingIndex::on`]): its rings
//! are circles of the warped field, and its gate lays each band wider (see `gate_test`).
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

mod chain;
mod cutter;
mod facets;
mod features;
mod gate;
mod lift;
mod meridians;

pub(crate) use chain::{segment_dist2, segment_dist2_at, Segment};
pub use facets::{rest_above_mm, LIFT_CAP, LIFT_VALLEY};
pub use lift::{Lift, Lifted};

use facets::lifts_off_facets;
use features::{corner_angles, creases, SlitBand};
use meridians::{Band, BandMade};

use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use crate::slitmap::{Mode, SlitMap};
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::f64::consts::TAU;
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
    SpacingIndex::on(lift, faces, options)?.rings(lift)
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
    /// part tilts enough from its corners' normals to need it: see [`facets::cleared_lift_mm`]).
    lift_h: Option<f64>,
    /// With `lift_h`: per face, whether every ball touching it is certified to lift by no more
    /// than [`facets::LIFT_FREE`]·h ([`Spacer::free_face`]), settled on first use.
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

impl<'a> SpacingIndex<'a> {
    /// The indexes of `map` on `surface` (`faces`: its facet tree) for `options`, checked first.
    pub fn new(
        surface: &'a Surface,
        map: &'a SlitMap,
        faces: &'a FaceTree,
        options: &SpacingOptions,
    ) -> Result<Self, SpacingError> {
        Self::build(surface, map, None, faces, options)
    }

    /// The indexes of the map `lift` answers in (a spread field's image too, see
    /// [`Lift::spread`]: its folds are the located map's, not its image's).
    pub fn on(lift: &Lift<'a>, faces: &'a FaceTree, options: &SpacingOptions) -> Result<Self, SpacingError> {
        Self::build(lift.surface(), lift.map(), lift.is_spread().then_some(lift), faces, options)
    }

    /// The indexes of `map`; for a spread field, `spread` is its lift: the folds are those of
    /// the map it locates in (the warp's P1 image folds wherever the warp turns faster than the
    /// faces, though the lift does not), and the gate labels its points through it.
    fn build(
        surface: &'a Surface,
        map: &'a SlitMap,
        spread: Option<&Lift<'_>>,
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
        let mut forbidden: Vec<(f64, f64)> = spread
            .map_or(map, |lift| lift.base_map())
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
            || gate::Gate::new(surface, map, gate::Labels::new(spread), faces, options.radius_mm, lift_h),
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
        let r_min = map.mode.inner_radius();
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
        let mut upper: Option<cutter::RingLine> = None;
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
        upper: Option<&cutter::RingLine>,
        first: (cutter::RingLine, Vec<gate::GatePoint>),
    ) -> Result<(f64, cutter::RingLine), SpacingError> {
        let (r, h) = (self.ball, self.options.scallop_mm * GATE_FRACTION);
        let mut lo = lo;
        let (mut lower, mut bad) = first;
        for round in 1.. {
            if bad.is_empty() {
                return Ok((lo, lower));
            }
            // Each at the radius of the ring through it as the lift sees it (the top below; a
            // spread field's gate labelled its points so, see `gate::Labels`).
            if !self.lift.is_spread() {
                for p in &mut bad {
                    self.gate.relabel(p, self.lift);
                }
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
                if cutter::Cutter::new(&ring_lines(upper, &centres), r, GATE_BISECTION_MARGIN * h)
                    .uncut(&bad)
                    .is_empty()
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
        upper: Option<&cutter::RingLine>,
        lower: cutter::RingLine,
    ) -> Result<(cutter::RingLine, Vec<gate::GatePoint>), SpacingError> {
        let h = self.options.scallop_mm * GATE_FRACTION;
        let lines = ring_lines(upper, &lower);
        let cutter = cutter::Cutter::new(&lines, self.ball, h);
        let bad = self.gate.uncut(lo, hi, gate::Labels::new(self.lift.is_spread().then_some(self.lift)), &cutter);
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
    fn centres(&self, rho: f64, focus: Option<&[DVec3]>) -> Result<cutter::RingLine, SpacingError> {
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
        let mut line = cutter::RingLine::new(rho);
        for (t, c) in pieces.into_iter().flatten() {
            line.push(t, c);
        }
        line.push(angle(M), base[M].0);
        Ok(line)
    }
}

/// Ring k's centres (none above the first ring) and the ring below.
fn ring_lines<'b>(upper: Option<&'b cutter::RingLine>, lower: &'b cutter::RingLine) -> Vec<&'b cutter::RingLine> {
    upper.into_iter().chain([lower]).collect()
}
