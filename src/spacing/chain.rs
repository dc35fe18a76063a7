//! Distances to a ring's ball centres: a [`Chain`] of five centres round one meridian, measured
//! along the parabola through each half (the meridian cusp test), and [`Segment`]s of a ring's
//! centre polyline (the gate).

use super::Lifted;
use crate::num;
use glam::DVec3;

/// Ball centres near one meridian angle on one ring (five, spanning about ±R along it), with the
/// parabola through each half computed once: a chain is measured against many points.
#[derive(Debug, Clone, Copy)]
pub(super) struct Chain {
    /// The contact of the middle centre (on the meridian itself): the band's point of S^h at
    /// this ring is taken from it, not lifted again.
    pub(super) contact: Lifted,
    centres: [DVec3; 5],
    /// Per half (centres 0–2, then 2–4): u and v of P(t) = a + t·u + t²·v through its three
    /// centres at t = 0, 1, 2, and whether it turns sharply (see [`Chain::distance`]).
    halves: [(DVec3, DVec3, bool); 2],
}

impl Chain {
    pub(super) fn new(contact: Lifted, centres: [DVec3; 5]) -> Self {
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
    pub(super) fn distance(&self, q: DVec3) -> f64 {
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
