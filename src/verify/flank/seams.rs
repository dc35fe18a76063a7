//! Kink angle and gap at each boundary between neighbouring strips.
//!
//! From the envelope (seed 002 eq. 6): along strip k the top end of the contact curve, x_k(1, t)
//! with the envelope normal n_k(1, t), is its boundary with strip k + 1, whose tip end traces
//! x_{k+1}(0, t'). For every cutting pose of strip k: the nearest point of strip k + 1's curve
//! (a polyline through its poses' points; ends excluded, so ragged strip ends do not count as
//! gaps), the gap = the distance to it and the kink = the angle between n_k and strip k + 1's
//! normal there (interpolated along the polyline). The rails come from the CL poses (a = tip +
//! r₁ sin α·axis, b = a + L·axis), the rail velocities from their neighbours, the branch is the
//! one nearer the surface.
//!
//! From the samples: the samples within `band` of strip k's boundary curve at which both strips'
//! swept volumes are within the search: gap = |d_k − d_{k+1}| (the step between the two swept
//! surfaces there) and kink = the angle between their normals at the nearest points.

use super::{swept, Probe, Program};
use crate::flank::envelope::{contact_point, rail_velocity};
use crate::mesh::nearest::FaceTree;
use crate::verify::SurfaceSample;
use glam::DVec3;
use serde::Serialize;

/// Figures of one boundary between strips `strips[0]` and `strips[1]` (1-based).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SeamFigures {
    pub strips: [usize; 2],
    /// Boundary points of the lower strip paired with the upper strip's curve.
    pub envelope_points: usize,
    /// Poses where either strip's envelope is not real at the boundary (eq. 6).
    pub envelope_not_real: usize,
    pub envelope_max_kink_deg: f64,
    pub envelope_mean_kink_deg: f64,
    pub envelope_max_gap_mm: f64,
    pub envelope_mean_gap_mm: f64,
    /// Machined samples within the band on either side.
    pub seam_samples: usize,
    pub sample_max_kink_deg: f64,
    pub sample_max_gap_mm: f64,
}

/// The boundary curve of strip `k` at `s` (0: tip end, 1: top end): points and normals, and how
/// many poses had no real envelope there.
fn boundary(p: &Program, tree: &FaceTree, k: usize, s: f64) -> (Vec<(DVec3, DVec3)>, usize) {
    let range = p.strips[k].clone();
    let rails: Vec<(DVec3, DVec3)> = p.poses[range]
        .iter()
        .map(|q| {
            let a = p.family.a_of_tip(q.tip, q.axis);
            (a, a + p.family.length_mm * q.axis)
        })
        .collect();
    let distance = |x: DVec3| tree.nearest(x, f64::INFINITY).map_or(f64::INFINITY, |n| n.distance);
    let mut out = Vec::with_capacity(rails.len());
    let mut not_real = 0;
    for j in 0..rails.len() {
        let (da, db) = rail_velocity(&rails, j);
        match contact_point(rails[j].0, rails[j].1, da, db, s, &p.family, &distance) {
            Some(c) => out.push((c.point, c.normal)),
            None => not_real += 1,
        }
    }
    (out, not_real)
}

/// `v` rotated by the smallest rotation that takes the unit vector `from` to `to` (Rodrigues).
fn transport(v: DVec3, from: DVec3, to: DVec3) -> DVec3 {
    let axis = from.cross(to);
    let (s, c) = (axis.length(), from.dot(to));
    if s < 1e-15 {
        return v;
    }
    let k = axis / s;
    v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c))
}

/// Distance from `x` to the polyline of `line`'s points.
fn distance_to(line: &[(DVec3, DVec3)], x: DVec3) -> f64 {
    line.windows(2)
        .map(|w| {
            let (a, d) = (w[0].0, w[1].0 - w[0].0);
            let t = if d.length_squared() > 0.0 { ((x - a).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
            x.distance(a + t * d)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The nearest point of the polyline to `x` strictly inside it: (distance, interpolated normal).
fn nearest_inside(line: &[(DVec3, DVec3)], x: DVec3) -> Option<(f64, DVec3)> {
    let mut best: Option<(f64, DVec3, bool)> = None;
    for (k, w) in line.windows(2).enumerate() {
        let (p, q) = (w[0].0, w[1].0);
        let d = q - p;
        let t = if d.length_squared() > 0.0 { ((x - p).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        let dist = x.distance(p + t * d);
        let end = (k == 0 && t == 0.0) || (k + 2 == line.len() && t == 1.0);
        if best.map_or(true, |b| dist < b.0) {
            best = Some((dist, (w[0].1 + t * (w[1].1 - w[0].1)).normalize_or_zero(), end));
        }
    }
    best.filter(|b| !b.2).map(|b| (b.0, b.1))
}

pub(super) fn seams(
    p: &Program,
    tree: &FaceTree,
    samples: &[SurfaceSample],
    probes: &[Probe],
    band: f64,
) -> Vec<SeamFigures> {
    let mut out = Vec::new();
    for k in 0..p.strips.len().saturating_sub(1) {
        let (top, nr0) = boundary(p, tree, k, 1.0);
        let (tip, nr1) = boundary(p, tree, k + 1, 0.0);
        let mut f = SeamFigures {
            strips: [k + 1, k + 2],
            envelope_points: 0,
            envelope_not_real: nr0 + nr1,
            envelope_max_kink_deg: 0.0,
            envelope_mean_kink_deg: 0.0,
            envelope_max_gap_mm: 0.0,
            envelope_mean_gap_mm: 0.0,
            seam_samples: 0,
            sample_max_kink_deg: 0.0,
            sample_max_gap_mm: 0.0,
        };
        let (mut kinks, mut gaps) = (0.0, 0.0);
        for &(x, n) in &top {
            if let Some((gap, m)) = nearest_inside(&tip, x) {
                let kink = swept::angle(n, m).to_degrees();
                f.envelope_points += 1;
                f.envelope_max_kink_deg = f.envelope_max_kink_deg.max(kink);
                f.envelope_max_gap_mm = f.envelope_max_gap_mm.max(gap);
                kinks += kink;
                gaps += gap;
            }
        }
        if f.envelope_points > 0 {
            f.envelope_mean_kink_deg = kinks / f.envelope_points as f64;
            f.envelope_mean_gap_mm = gaps / f.envelope_points as f64;
        }
        // Machined samples beside the boundary, by the strip that finished them.
        let mut sides: [Vec<(DVec3, DVec3, f64, DVec3)>; 2] = [Vec::new(), Vec::new()];
        for (s, probe) in samples.iter().zip(probes) {
            let Some(m) = probe.machined_by.filter(|&m| m == k || m == k + 1) else { continue };
            let Some(ap) = probe.per_strip.iter().find(|(st, _)| *st == m).map(|(_, a)| *a) else { continue };
            if distance_to(&top, s.position) <= band {
                sides[m - k].push((s.position, ap.normal, ap.distance, s.normal));
            }
        }
        f.seam_samples = sides[0].len() + sides[1].len();
        for &(x, n, d, nu) in &sides[0] {
            let nearest = sides[1]
                .iter()
                .map(|&(y, m, e, mu)| (x.distance(y), m, e, mu))
                .filter(|&(dist, _, _, _)| dist <= 2.0 * band)
                .min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((_, m, e, mu)) = nearest {
                // The surface turns between the two samples: compare the normals relative to it.
                let m = transport(m, mu, nu);
                f.sample_max_kink_deg = f.sample_max_kink_deg.max(swept::angle(n, m).to_degrees());
                f.sample_max_gap_mm = f.sample_max_gap_mm.max((d - e).abs());
            }
        }
        out.push(f);
    }
    out
}
