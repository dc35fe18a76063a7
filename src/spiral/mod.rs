//! Stage 6 — `spiral`: the rings bridged into ONE continuous spiral that never crosses a hole
//! (seed 000 §2.2.2, eqs. 7–9, Pseudocode A-2), sampled on the surface by chord error.
//!
//! # What it computes
//! In the log-polar strip (x = arg w, y = |w|, seed eq. 7) ring k is the line y = R_k and a slit
//! is a horizontal segment. The path runs each ring for one full turn, then bridges to the next
//! ring with the smooth transition of seed eq. 9, y = R_k + (R_{k+1} − R_k)·σ(t) with σ the
//! quintic smoothstep (tangent to both lines, curvature continuous), over an angular window D_k.
//! Because every ring is still run for a full turn, the coverage the spacing stage proved for
//! complete rings is kept exactly; the bridges only add cutting. A bridge that would cross a
//! slit (pass through a hole) is pushed further along the ring until it clears the slit by a
//! margin (seed: "increase D^Real_{i−i+1}"). The window D_k is wide enough that the sideways
//! move stays under `max_bridge_angle_deg` on the surface, up to a full turn near the centre
//! (seed: "increased from π/10 to 2π"). Disk maps end with a last bridge into the pole, annulus
//! maps on the inner circle. Several start angles are tried and the one needing the least extra
//! ring length wins (seed: "trial and error within [0, 2π]").
//!
//! The curve is then lifted to the surface (inverse slit map) and sampled adaptively: a piece
//! is split until its chord deviates from the curve by at most `chord_tolerance_mm`, both on the
//! surface and on the ball-centre curve cc + R·n (the machine interpolates the ball linearly: a
//! chord of a convex centre curve dips into the part, R/ρ more than the contact chord), on the
//! centre curve also by at most `normal_tolerance_mm` along the surface normal (where the
//! deviation raises a cusp by all of it), and is at most `max_segment_mm` long. The midpoint
//! is the only point tested, and it speaks for the whole piece only where the lifted curve bends
//! at most once: the P1 lift is straight within a face and kinks on its edges, so a piece longer
//! than the tolerance must end on its start's face or one sharing an edge with it. Where the map
//! squeezes the surface (round a corner of the outer loop) a ring crosses two faces within one
//! step and zigzags about the chord through the midpoint: issue 34's sweep part gen025 (R 4.9,
//! h 0.0053) had a ring's chord 0.032 mm off its lift there (tolerance 0.0023 mm), 1.06 h.
//!
//! Direction: the spiral is built inwards in the sense that puts the uncut material on the
//! tool's right for a clockwise (M3) spindle, i.e. climb milling: clockwise seen from the tool
//! inwards, counter-clockwise outwards (the reversed path); conventional milling is the mirror.
//!
//! # Invariants of the output
//! One pass; consecutive points lie on the surface (barycentric points of its faces) at most
//! `max_segment_mm` apart; the path visits every ring for at least a full turn.

use crate::mesh::Surface;
use crate::num;
use crate::slitmap::{Mode, SlitMap};
use crate::spacing::{Lift, Rings};
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Which way the spiral runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// From the outer boundary to the pole (disk) or the inner circle (annulus).
    Inward,
    Outward,
}

/// Milling sense for a clockwise (M3) spindle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Cut {
    Climb,
    Conventional,
}

/// Options of the spiral stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpiralOptions {
    /// Default inward.
    pub direction: Direction,
    /// Default climb.
    pub cut: Cut,
    /// Largest distance between the lifted curve, or its ball-centre curve, and their chords, mm.
    /// Default 0.002.
    pub chord_tolerance_mm: f64,
    /// Largest deviation of a ball-centre chord from its curve along the surface normal, mm
    /// (where it counts fully against the scallop, unlike sideways); `None`: no separate limit.
    pub normal_tolerance_mm: Option<f64>,
    /// Ball radius R of the centre curve cc + R·n, mm. Default 3.
    pub radius_mm: f64,
    /// Longest segment, mm. Default 1.
    pub max_segment_mm: f64,
    /// Steepest sideways angle of a bridge on the surface, degrees. Default 8.
    pub max_bridge_angle_deg: f64,
    /// Bridges clear slit tips by this angle of the slit domain, radians. Default 0.04.
    pub slit_margin_rad: f64,
    /// Start angles tried. Default 16.
    pub start_trials: usize,
}

impl Default for SpiralOptions {
    fn default() -> Self {
        Self {
            direction: Direction::Inward,
            cut: Cut::Climb,
            chord_tolerance_mm: 0.002,
            normal_tolerance_mm: None,
            radius_mm: 3.0,
            max_segment_mm: 1.0,
            max_bridge_angle_deg: 8.0,
            slit_margin_rad: 0.04,
            start_trials: 16,
        }
    }
}

/// Errors of the spiral stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpiralError {
    #[error("invalid spiral option: {0}")]
    InvalidOption(String),
    #[error("the slit map has {map} vertices but the surface {surface}: they must come from the same mesh")]
    MeshMismatch { map: usize, surface: usize },
    #[error("there are no rings to bridge")]
    NoRings,
    #[error("the slit-domain point at radius {rho}, angle {theta} does not lie on the surface")]
    Lift { rho: f64, theta: f64 },
    #[error("the bridge from ring {ring} cannot clear the slits between radius {from} and {to}")]
    Blocked { ring: usize, from: f64, to: f64 },
    #[error("the path would jump {gap_mm:.3} mm, from ({:.3}, {:.3}, {:.3}) to ({:.3}, {:.3}, {:.3}) mm (slit-domain radius {rho}, angle {theta:.4} rad): the slit map cannot carry a continuous path from this pole (a pole close to a hole does this on a coarse mesh); choose another one (origin auto tries several)", from_mm[0], from_mm[1], from_mm[2], to_mm[0], to_mm[1], to_mm[2])]
    Discontinuous { rho: f64, theta: f64, gap_mm: f64, from_mm: [f64; 3], to_mm: [f64; 3] },
}

/// One point of the path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPoint {
    /// Cutter contact on the surface, mm.
    pub cc: DVec3,
    /// Unit surface normal at the contact, towards the tool.
    pub normal: DVec3,
    /// Slit-domain image of the contact.
    pub w: DVec2,
    /// Face of the contact.
    pub face: u32,
}

/// A bridge between two rings in the unwrapped angle of the build (see [`Spiral::bridges`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bridge {
    /// Ring it leaves (index into the rings); the last bridge of a disk goes to the pole.
    pub from_ring: usize,
    /// Start angle (unwrapped, radians) and angular width of the window.
    pub start: f64,
    pub width: f64,
}

/// The spiral: one continuous pass.
#[derive(Debug, Clone)]
pub struct Spiral {
    pub points: Vec<PathPoint>,
    pub bridges: Vec<Bridge>,
    /// Extra ring length run to clear slits, summed over rings (in turns of each ring).
    pub extra_turns: f64,
    pub direction: Direction,
    pub cut: Cut,
}

impl Spiral {
    pub fn contacts(&self) -> Vec<DVec3> {
        self.points.iter().map(|p| p.cc).collect()
    }
    pub fn normals(&self) -> Vec<DVec3> {
        self.points.iter().map(|p| p.normal).collect()
    }
    /// Ball centres `cc + R·n` for a ball of radius `radius_mm`.
    pub fn ball_centres(&self, radius_mm: f64) -> Vec<DVec3> {
        self.points.iter().map(|p| p.cc + p.normal * radius_mm).collect()
    }
}

fn check_options(o: &SpiralOptions) -> Result<(), SpiralError> {
    let bad = |m: String| Err(SpiralError::InvalidOption(m));
    if !(o.radius_mm.is_finite() && o.radius_mm >= 0.0) {
        return bad(format!("ball radius {} mm must be a number ≥ 0", o.radius_mm));
    }
    if !(o.chord_tolerance_mm.is_finite() && o.chord_tolerance_mm > 0.0) {
        return bad(format!("chord tolerance {} mm must be a positive number", o.chord_tolerance_mm));
    }
    if let Some(t) = o.normal_tolerance_mm {
        if !(t.is_finite() && t > 0.0) {
            return bad(format!("normal chord tolerance {t} mm must be a positive number"));
        }
    }
    if !(o.max_segment_mm.is_finite() && o.max_segment_mm > 0.0) {
        return bad(format!("maximum segment {} mm must be a positive number", o.max_segment_mm));
    }
    if !(o.max_bridge_angle_deg > 0.0 && o.max_bridge_angle_deg < 80.0) {
        return bad(format!("bridge angle {}° must be in (0°, 80°)", o.max_bridge_angle_deg));
    }
    if !(o.slit_margin_rad >= 0.0 && o.slit_margin_rad < 1.0) {
        return bad(format!("slit margin {} rad must be in [0, 1)", o.slit_margin_rad));
    }
    if o.start_trials == 0 {
        return bad("start trials must be at least 1".into());
    }
    Ok(())
}

/// A piece of the log-polar curve in the build's unwrapped angle u: y(u) on [u0, u1].
#[derive(Debug, Clone, Copy)]
enum Piece {
    Ring { u0: f64, u1: f64, rho: f64 },
    Bridge { u0: f64, width: f64, from: f64, to: f64 },
}

impl Piece {
    fn range(&self) -> (f64, f64) {
        match *self {
            Piece::Ring { u0, u1, .. } => (u0, u1),
            Piece::Bridge { u0, width, .. } => (u0, u0 + width),
        }
    }
    fn rho(&self, u: f64) -> f64 {
        match *self {
            Piece::Ring { rho, .. } => rho,
            Piece::Bridge { u0, width, from, to } => from + (to - from) * smoothstep((u - u0) / width),
        }
    }
}

/// Quintic smoothstep: σ(0) = 0, σ(1) = 1, σ' and σ'' vanish at both ends (seed eq. 9's σ).
fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * t * (t * (6.0 * t - 15.0) + 10.0)
}

/// Inverse of [`smoothstep`] on [0, 1] by bisection (it is monotone).
fn smoothstep_inv(y: f64) -> f64 {
    let (mut a, mut b) = (0.0, 1.0);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if smoothstep(m) < y {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// A slit in the build's angle u (mirrored for a clockwise build).
#[derive(Debug, Clone, Copy)]
struct SlitU {
    radius: f64,
    start: f64,
    extent: f64,
}

impl SlitU {
    /// Whether angle `u` is within `margin` of the slit's angular range.
    fn blocks(&self, u: f64, margin: f64) -> bool {
        num::rem_tau(u - (self.start - margin)) <= self.extent + 2.0 * margin
    }
}

/// One-off entry: the spiral through `rings` on `surface` (with the slit map the rings came from).
pub fn spiral(surface: &Surface, map: &SlitMap, rings: &Rings, options: &SpiralOptions) -> Result<Spiral, SpiralError> {
    check_options(options)?;
    if let Some((map_vertices, surface_vertices)) = Lift::mismatch(surface, map) {
        return Err(SpiralError::MeshMismatch { map: map_vertices, surface: surface_vertices });
    }
    bridge_and_sample(&Lift::new(surface, map), rings, options)
}

/// The spiral through `rings` on the map `lift` inverts (the lift built once per map is shared
/// with [`crate::spacing::spacing_on`]).
pub fn spiral_on(lift: &Lift<'_>, rings: &Rings, options: &SpiralOptions) -> Result<Spiral, SpiralError> {
    check_options(options)?;
    bridge_and_sample(lift, rings, options)
}

/// The spiral, for checked options.
fn bridge_and_sample(lift: &Lift<'_>, rings: &Rings, options: &SpiralOptions) -> Result<Spiral, SpiralError> {
    let map = lift.map();
    if rings.rings.is_empty() {
        return Err(SpiralError::NoRings);
    }
    // Climb inwards runs clockwise seen from the tool (decreasing arg w): build in u = −θ.
    let clockwise_inwards = options.cut == Cut::Climb;
    let sense = if clockwise_inwards { -1.0 } else { 1.0 };
    let slits: Vec<SlitU> = map
        .slits
        .iter()
        .map(|s| {
            let start = if sense > 0.0 { s.theta_start } else { -s.theta_end };
            SlitU { radius: s.radius, start, extent: s.extent() }
        })
        .collect();

    let mut best: Option<(f64, Vec<Piece>, Vec<Bridge>)> = None;
    for trial in 0..options.start_trials {
        let u_start = TAU * trial as f64 / options.start_trials as f64;
        let (pieces, bridges, extra) = layout(rings, &slits, u_start, options)?;
        if best.as_ref().map_or(true, |(e, _, _)| extra < *e - 1e-12) {
            best = Some((extra, pieces, bridges));
        }
    }
    let (extra, pieces, bridges) = best.expect("at least one trial");

    let mut points = sample(lift, &pieces, sense, options)?;
    if options.direction == Direction::Outward {
        points.reverse();
    }
    Ok(Spiral { points, bridges, extra_turns: extra, direction: options.direction, cut: options.cut })
}

/// Lays out full ring turns and bridges from `u_start`; returns the pieces, the bridges and the
/// extra ring length run to clear slits (in turns weighted by ring length, a proxy for mm).
fn layout(
    rings: &Rings,
    slits: &[SlitU],
    u_start: f64,
    options: &SpiralOptions,
) -> Result<(Vec<Piece>, Vec<Bridge>, f64), SpiralError> {
    let radii: Vec<f64> = rings.rings.iter().map(|r| r.radius).collect();
    let mut pieces = Vec::with_capacity(2 * radii.len() + 1);
    let mut bridges = Vec::with_capacity(radii.len());
    let mut extra = 0.0;
    let mut u = u_start;
    let tan_max = num::tan(options.max_bridge_angle_deg.to_radians());
    let n = radii.len();
    for k in 0..n {
        let from = radii[k];
        let ring_start = u;
        let mut ring_end = u + TAU;
        let to = if k + 1 < n {
            radii[k + 1]
        } else if rings.mode == Mode::Disk {
            0.0
        } else {
            // Annulus: the last ring is the inner circle; the path ends after its full turn.
            pieces.push(Piece::Ring { u0: ring_start, u1: ring_end, rho: from });
            break;
        };
        // Window: the sideways move (ring step on the surface) over the bridge's arc length,
        // at σ's steepest slope 15/8, stays under the angle limit. Into the pole: a full turn.
        let width = if k + 1 < n {
            let len = rings.rings[k].length_mm.max(1e-9);
            let step_mm = len / TAU * (from - to) / from.max(1e-12);
            (1.875 * step_mm / tan_max / (len / TAU)).clamp(TAU / 40.0, TAU)
        } else {
            TAU
        };
        let crossings: Vec<(f64, &SlitU)> = slits
            .iter()
            .filter(|s| s.radius < from && s.radius > to)
            .map(|s| (smoothstep_inv((from - s.radius) / (from - to)), s))
            .collect();
        let clear = |b: f64| crossings.iter().all(|(t, s)| !s.blocks(b + t * width, options.slit_margin_rad));
        let mut tries = 0;
        while !clear(ring_end) {
            ring_end += TAU / 720.0;
            tries += 1;
            if tries > 720 {
                return Err(SpiralError::Blocked { ring: k, from, to });
            }
        }
        extra += (ring_end - ring_start - TAU) / TAU * rings.rings[k].length_mm;
        pieces.push(Piece::Ring { u0: ring_start, u1: ring_end, rho: from });
        pieces.push(Piece::Bridge { u0: ring_end, width, from, to });
        bridges.push(Bridge { from_ring: k, start: ring_end, width });
        u = ring_end + width;
    }
    Ok((pieces, bridges, extra))
}

/// Lifts the pieces to the surface and samples them by chord error and segment length.
///
/// Each piece starts from the point of its start searched around the face of the last point
/// before it, so the pieces depend on each other only through that start. They are marched in
/// parallel from a guessed start (located without a previous face), then joined in order: a
/// piece whose true start differs from the guess (a start on an edge or in a P1 fold) is
/// marched again. The result is the sequential march's, bit for bit.
fn sample(
    lift: &Lift<'_>,
    pieces: &[Piece],
    sense: f64,
    options: &SpiralOptions,
) -> Result<Vec<PathPoint>, SpiralError> {
    let start_of = |piece: &Piece, near: Option<u32>| eval(lift, piece, piece.range().0, sense, near);
    let guesses = crate::par::each(pieces.len(), |j| {
        let (u0, u1) = pieces[j].range();
        if u1 <= u0 {
            return None;
        }
        let start = start_of(&pieces[j], None).ok()?;
        let points = march(lift, &pieces[j], start, sense, options).ok()?;
        Some((start, points))
    });
    let mut out: Vec<PathPoint> = Vec::new();
    for (piece, guess) in pieces.iter().zip(guesses) {
        let (u0, u1) = piece.range();
        if u1 <= u0 {
            continue;
        }
        let here = match out.last() {
            Some(p) => start_of(piece, Some(p.face))?,
            None => {
                // The first start is searched without a previous face, as its guess was.
                let p = match &guess {
                    Some((start, _)) => *start,
                    None => start_of(piece, None)?,
                };
                out.push(p);
                p
            }
        };
        match guess {
            Some((start, points)) if start == here => out.extend(points),
            _ => out.extend(march(lift, piece, here, sense, options)?),
        }
    }
    Ok(out)
}

/// The point of `piece` at `u`, searched first around face `near` (continuity through P1 folds
/// at slit tips, see `Lift::polar_near`).
fn eval(lift: &Lift<'_>, piece: &Piece, u: f64, sense: f64, near: Option<u32>) -> Result<PathPoint, SpiralError> {
    let rho = piece.rho(u);
    let theta = sense * u;
    let l = match near {
        Some(f) => lift.polar_near(rho, theta, f),
        None => lift.polar(rho, theta),
    };
    let l = l.ok_or(SpiralError::Lift { rho, theta })?;
    Ok(PathPoint { cc: l.p, normal: l.n, w: l.w(), face: l.face })
}

/// The points of `piece` after its start `here`: a step is accepted when its chord is short
/// enough and its midpoint within the chord tolerance; every point is walked to from the
/// previous one.
fn march(
    lift: &Lift<'_>,
    piece: &Piece,
    mut here: PathPoint,
    sense: f64,
    options: &SpiralOptions,
) -> Result<Vec<PathPoint>, SpiralError> {
    let tol = options.chord_tolerance_mm;
    let triangles = &lift.surface().triangles;
    let tol_normal = options.normal_tolerance_mm.unwrap_or(f64::INFINITY);
    let radius = options.radius_mm;
    let max_seg = options.max_segment_mm;
    let (u0, u1) = piece.range();
    let mut out = Vec::new();
    let mut u = u0;
    let mut du = (u1 - u0) / 64.0;
    while u < u1 {
        let mut step = du.min(u1 - u);
        let min_step = 1e-9 * (u1 - u0).max(1.0);
        let mut halvings = 0;
        // A halved step ends at the last midpoint: that point is not lifted twice.
        let mut last_mid: Option<(f64, PathPoint)> = None;
        let (next_u, next) = loop {
            let ub = u + step;
            let pb = match last_mid {
                Some((um, pm)) if um == ub => pm,
                _ => eval(lift, piece, ub, sense, Some(here.face))?,
            };
            let um = u + 0.5 * step;
            let pm = eval(lift, piece, um, sense, Some(here.face))?;
            last_mid = Some((um, pm));
            let chord = (pb.cc - here.cc).length();
            let centre = |p: &PathPoint| p.cc + radius * p.normal;
            let (ca, cb) = (centre(&here), centre(&pb));
            let (_, t) = crate::spacing::segment_dist2_at(centre(&pm), ca, cb);
            let off = centre(&pm) - (ca + (cb - ca) * t);
            // The midpoint speaks for the step only where the lift bends at most once (module docs).
            let smooth = segment_dist(pm.cc, here.cc, pb.cc) <= tol
                && off.length() <= tol
                && off.dot(pm.normal).abs() <= tol_normal
                && (chord <= tol || one_edge_apart(triangles, here.face, pb.face));
            if chord <= max_seg && (smooth || step <= min_step) {
                // At the smallest step a deviating midpoint is a kink of the P1 lift.
                break (ub, pb);
            }
            if step <= min_step {
                let rho = piece.rho(u);
                // arg w in (−π, π]: the build's angle u counts every turn of the spiral.
                let theta = num::wrap_pi(sense * u);
                let (from_mm, to_mm) = (here.cc.to_array(), pb.cc.to_array());
                return Err(SpiralError::Discontinuous { rho, theta, gap_mm: chord, from_mm, to_mm });
            }
            step = (0.5 * step).max(min_step);
            halvings += 1;
        };
        du = if halvings == 0 { step * 1.5 } else { step.max(64.0 * min_step) };
        u = if next_u >= u1 { u1 } else { next_u };
        // A step of the minimal size may not move on the surface (folds): no repeated points.
        if (next.cc - here.cc).length() > 1e-7 {
            out.push(next);
            here = next;
        }
    }
    Ok(out)
}

/// Whether faces `a` and `b` are one face or share an edge.
fn one_edge_apart(triangles: &[[u32; 3]], a: u32, b: u32) -> bool {
    let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
    a == b || ta.iter().filter(|v| tb.contains(v)).count() >= 2
}

fn segment_dist(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    crate::spacing::segment_dist2(q, a, b).sqrt()
}
