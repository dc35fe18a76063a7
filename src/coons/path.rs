//! Ring levels from scallop control and the spiral through them (seed 004 §3.2).
//!
//! Reference lines (Fig. 6, 8) are the iso-U lines of the compound domain at `lines_per_face`
//! places in every face and on every seam, sampled across the band. Along each, the 3D stepover
//! a ball of radius R may take for the scallop `fraction · h` is w(κ) = 2√(h′(2R − h′)) / √(1 + κR),
//! κ the normal curvature along the line (convex > 0), h′ = fraction · h. From a level V_k the
//! next is the smallest V at which some reference line has advanced w by 3D arc length, κ taken
//! as its largest over the step: the finest spacing over all reference lines (the seed takes
//! the longest line only, which leaves more than h on the others). The steps are then scaled
//! down by one common factor so the last one ends exactly on the far boundary (no thin last
//! band).
//!
//! The path, in the compound domain: the boundary ring V = V₀, then one inclined line per
//! revolution from (0, V_k) to (`around`, V_{k+1}) (the two ends are the same 3D point: the
//! band's loop closes), then the boundary ring V = V_N: one continuous helix-like spiral with no
//! retraction. Each line is cut at the seams and row boundaries it crosses, then densified by
//! bisection until the contact curve and the ball-centre curve are within the chord tolerance
//! of their chords; every point is evaluated on the exact surface.

use super::compound::Compound;
use super::smooth::Line;
use super::warp::Warp;
use super::CoonsError;
use glam::{DVec2, DVec3};

/// The levels and what spacing they give.
#[derive(Clone, Debug)]
pub struct Levels {
    pub v: Vec<f64>,
    /// The common factor the steps were scaled by (≤ 1).
    pub scale: f64,
    /// The flat-surface stepover 2√(h′(2R − h′)), mm.
    pub nominal_mm: f64,
    /// Smallest and largest 3D spacing between consecutive levels along any reference line, mm.
    pub min_spacing_mm: f64,
    pub max_spacing_mm: f64,
    /// The across coordinate the lines are straight in ([`Warp`]).
    pub warp: Warp,
}

struct RefLine {
    arc: Vec<f64>,
    kappa: Vec<f64>,
}

/// Samples per row along a reference line.
const SAMPLES_PER_ROW: usize = 96;

fn reference_lines(c: &Compound, per_face: usize) -> Vec<RefLine> {
    let nv = c.across * SAMPLES_PER_ROW;
    let mut lines = Vec::new();
    for i in 0..c.around {
        for q in 0..=per_face {
            // q = 0 is the seam on the left; the seam on the right is the next face's q = 0.
            let u = i as f64 + q as f64 / (per_face + 1) as f64;
            let pts: Vec<(DVec3, DVec3)> = (0..=nv)
                .map(|k| {
                    let e = c.at(u, k as f64 / SAMPLES_PER_ROW as f64);
                    (e.x, e.n)
                })
                .collect();
            let mut arc = vec![0.0; nv + 1];
            for k in 1..=nv {
                arc[k] = arc[k - 1] + (pts[k].0 - pts[k - 1].0).length();
            }
            let mut kappa = vec![0.0; nv + 1];
            for k in 1..nv {
                let (l0, l1) = (arc[k] - arc[k - 1], arc[k + 1] - arc[k]);
                if l0 > 1e-12 && l1 > 1e-12 {
                    let second = ((pts[k + 1].0 - pts[k].0) / l1 - (pts[k].0 - pts[k - 1].0) / l0) * (2.0 / (l0 + l1));
                    kappa[k] = -second.dot(pts[k].1);
                }
            }
            kappa[0] = kappa[1.min(nv)];
            kappa[nv] = kappa[nv.saturating_sub(1)];
            lines.push(RefLine { arc, kappa });
        }
    }
    lines
}

/// Arc length of `line` at V (linear between samples).
fn arc_at(line: &RefLine, v: f64) -> f64 {
    let x = v * SAMPLES_PER_ROW as f64;
    let n = line.arc.len() - 1;
    let k = (x.floor() as usize).min(n - 1);
    line.arc[k] + (line.arc[k + 1] - line.arc[k]) * (x - k as f64)
}

/// The ring levels (see the module docs).
pub fn levels(c: &Compound, radius: f64, scallop: f64, fraction: f64, per_face: usize) -> Result<Levels, CoonsError> {
    let lines = reference_lines(c, per_face);
    let h = fraction * scallop;
    let nominal = 2.0 * (h * (2.0 * radius - h)).sqrt();
    let top = c.across as f64;
    // Concave curvature sharper than the ball cannot be finished by it.
    for (l, line) in lines.iter().enumerate() {
        if let Some(k) = line.kappa.iter().position(|&k| 1.0 + k * radius < 0.05) {
            let u = (l / (per_face + 1)) as f64 + (l % (per_face + 1)) as f64 / (per_face + 1) as f64;
            let (i, j, _, _) = c.locate(u, k as f64 / SAMPLES_PER_ROW as f64);
            return Err(CoonsError::BallTooLarge {
                face: c.patch(i, j).id,
                radius_mm: radius,
                curvature_radius_mm: -1.0 / line.kappa[k],
            });
        }
    }
    let width = |kappa: f64| nominal / (1.0 + kappa * radius).sqrt();
    let step = |v0: f64, scale: f64| -> f64 {
        let mut best = top;
        for line in &lines {
            let a0 = arc_at(line, v0);
            let n = line.arc.len() - 1;
            let mut q = ((v0 * SAMPLES_PER_ROW as f64).floor() as usize).min(n);
            let mut kmax = line.kappa[q];
            let (mut v_prev, mut a_prev) = (v0, a0);
            q += 1;
            while q <= n {
                kmax = kmax.max(line.kappa[q]);
                let need = scale * width(kmax);
                let (vq, aq) = (q as f64 / SAMPLES_PER_ROW as f64, line.arc[q]);
                if aq - a0 >= need {
                    let f = if aq > a_prev { (need - (a_prev - a0)) / (aq - a_prev) } else { 1.0 };
                    best = best.min(v_prev + (vq - v_prev) * f.clamp(0.0, 1.0));
                    break;
                }
                (v_prev, a_prev) = (vq, aq);
                q += 1;
            }
        }
        best.max(v0 + 1e-9).min(top)
    };
    // The number of steps at full width, then the scale that makes them end on the boundary.
    let mut count = 0;
    let mut v = 0.0;
    while v < top {
        v = step(v, 1.0);
        count += 1;
        if count > 100_000 {
            return Err(CoonsError::TooManyRevolutions { revolutions: count });
        }
    }
    let reach = |scale: f64| -> f64 {
        let mut v = 0.0;
        for _ in 0..count {
            v = step(v, scale);
        }
        v
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..48 {
        let mid = 0.5 * (lo + hi);
        if reach(mid) >= top - 1e-12 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let mut vs = vec![0.0];
    for _ in 0..count {
        let next = step(*vs.last().expect("non-empty"), hi);
        vs.push(next);
    }
    *vs.last_mut().expect("non-empty") = top;
    vs.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let (mut lo_mm, mut hi_mm) = (f64::INFINITY, 0.0f64);
    for w in vs.windows(2) {
        for line in &lines {
            let d = arc_at(line, w[1]) - arc_at(line, w[0]);
            lo_mm = lo_mm.min(d);
            hi_mm = hi_mm.max(d);
        }
    }
    let mean: Vec<f64> =
        (0..lines[0].arc.len()).map(|k| lines.iter().map(|l| l.arc[k]).sum::<f64>() / lines.len() as f64).collect();
    let warp = Warp::new(mean, SAMPLES_PER_ROW);
    Ok(Levels { v: vs, scale: hi, nominal_mm: nominal, min_spacing_mm: lo_mm, max_spacing_mm: hi_mm, warp })
}

/// The spiral's lines for `levels` (see the module docs).
pub fn lines(c: &Compound, levels: &[f64]) -> Vec<Line> {
    let m = c.around as f64;
    let ring = |v: f64| Line { a: DVec2::new(0.0, v), b: DVec2::new(m, v) };
    let mut out = vec![ring(levels[0])];
    for w in levels.windows(2) {
        out.push(Line { a: DVec2::new(0.0, w[0]), b: DVec2::new(m, w[1]) });
    }
    out.push(ring(*levels.last().expect("at least one level")));
    out
}

/// A point of the path.
#[derive(Clone, Copy, Debug)]
pub struct PathPoint {
    pub x: DVec3,
    pub n: DVec3,
    /// Compound-domain coordinates (U unwrapped along the path: revolution k adds k·around).
    pub u: f64,
    pub v: f64,
    /// STEP id of the face.
    pub face: u64,
}

/// The densified path along `lines` (see the module docs).
pub fn densify(c: &Compound, warp: &Warp, lines: &[Line], radius: f64, chord_mm: f64) -> Vec<PathPoint> {
    let mut out: Vec<PathPoint> = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let d = line.b - line.a;
        let (wa, wb) = (warp.at(line.a.y, false).0, warp.at(line.b.y, false).0);
        // Break points: seams (integer U) and row boundaries (integer V) crossed.
        let mut cuts = vec![0.0, 1.0];
        for u in (line.a.x.floor() as i64 + 1)..=(line.b.x.ceil() as i64 - 1) {
            cuts.push((u as f64 - line.a.x) / d.x);
        }
        if wb != wa {
            for r in 1..c.across {
                let f = (warp.at(r as f64, false).0 - wa) / (wb - wa);
                if f > 0.0 && f < 1.0 {
                    cuts.push(f);
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        for w in cuts.windows(2) {
            let mid = warp.point(line.a, line.b, 0.5 * (w[0] + w[1]));
            let (i, j, _, _) = c.locate(mid.x, mid.y);
            let patch = c.patch(i, j);
            let eval = |f: f64| -> PathPoint {
                let q = warp.point(line.a, line.b, f);
                // The lines keep U in [0, around]: no wrap inside a piece.
                let (s, t) = (q.x - i as f64, q.y - j as f64);
                let e = patch.eval(s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
                PathPoint { x: e.x, n: e.n, u: q.x + (k as f64) * c.around as f64, v: q.y, face: patch.id }
            };
            let (mut fa, mut a) = (w[0], eval(w[0]));
            if out.last().map_or(true, |l| (l.x - a.x).length() > 1e-9) {
                out.push(a);
            }
            // At least four pieces per face crossing, then bisection to the tolerances.
            let pieces = 4;
            for p in 1..=pieces {
                let fb = w[0] + (w[1] - w[0]) * p as f64 / pieces as f64;
                let b = eval(fb);
                bisect(&eval, fa, a, fb, b, radius, chord_mm, 0, &mut out);
                out.push(b);
                (fa, a) = (fb, b);
            }
        }
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn bisect(
    eval: &dyn Fn(f64) -> PathPoint,
    fa: f64,
    a: PathPoint,
    fb: f64,
    b: PathPoint,
    radius: f64,
    tol: f64,
    depth: usize,
    out: &mut Vec<PathPoint>,
) {
    let fm = 0.5 * (fa + fb);
    let m = eval(fm);
    let centre = |p: &PathPoint| p.x + p.n * radius;
    let off_chord = |p: DVec3, a: DVec3, b: DVec3| crate::spacing::segment_dist2(p, a, b).sqrt();
    let off = off_chord(m.x, a.x, b.x).max(off_chord(centre(&m), centre(&a), centre(&b)));
    if depth < 24 && off > tol {
        bisect(eval, fa, a, fm, m, radius, tol, depth + 1, out);
        out.push(m);
        bisect(eval, fm, m, fb, b, radius, tol, depth + 1, out);
    }
}
