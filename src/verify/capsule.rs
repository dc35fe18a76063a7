//! One swept segment of the ball: the capsule of radius R around the segment between two
//! consecutive ball centres, and the two exact queries the verifier needs (distance of a point,
//! first entry of a ray).

use crate::num;
use glam::DVec3;

/// The segment `a → b` between two consecutive ball centres (`a == b` for a lone centre: a
/// sphere). The capsule of radius R is every point within R of the segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub a: DVec3,
    pub b: DVec3,
    d: DVec3,
    dd: f64,
}

impl Capsule {
    pub fn new(a: DVec3, b: DVec3) -> Self {
        let d = b - a;
        Self { a, b, d, dd: d.dot(d) }
    }

    /// Euclidean distance from `p` to the segment.
    #[inline]
    pub fn distance(&self, p: DVec3) -> f64 {
        let m = p - self.a;
        if self.dd == 0.0 {
            return m.length();
        }
        let s = (m.dot(self.d) / self.dd).clamp(0.0, 1.0);
        (m - s * self.d).length()
    }

    /// Smallest `t ≥ 0` such that `o + t·n` is in the capsule of radius `r` (`n` a unit vector),
    /// or `None` when the ray never enters it. `Some(0)` when `o` is inside already.
    pub fn entry(&self, o: DVec3, n: DVec3, r: f64) -> Option<f64> {
        if self.distance(o) <= r {
            Some(0.0)
        } else {
            self.entry_from_outside(o, n, r)
        }
    }

    /// [`Capsule::entry`] for an origin known to be outside (`distance(o) > r`), so callers that
    /// have the distance already do not compute it twice.
    ///
    /// The capsule is convex, so the ray meets it in one interval; its entry lies on the
    /// cylinder side (axial parameter in [0, 1]) or on one of the end spheres, and every such
    /// root is at or after the entry. So the entry is the smallest root over the three surfaces.
    /// Roots are taken in the cancellation-free form t = C / (−B + √(B² − AC)): for an origin
    /// outside a surface (C > 0) the ray enters it ahead only when B < 0.
    #[inline]
    pub fn entry_from_outside(&self, o: DVec3, n: DVec3, r: f64) -> Option<f64> {
        let r2 = r * r;
        let mut best = f64::INFINITY;
        if self.dd > 0.0 {
            let m = o - self.a;
            let (md, nd) = (m.dot(self.d), n.dot(self.d));
            let mp = m - (md / self.dd) * self.d;
            let np = n - (nd / self.dd) * self.d;
            let (a, b, c) = (np.dot(np), mp.dot(np), mp.dot(mp) - r2);
            if c <= 0.0 {
                // Inside the infinite cylinder: inside the capsule up to rounding if beside the
                // segment, otherwise the cylinder's entry is behind and a sphere decides.
                let s = md / self.dd;
                if (0.0..=1.0).contains(&s) {
                    return Some(0.0);
                }
            } else if b < 0.0 {
                let disc = b * b - a * c;
                if disc >= 0.0 {
                    let t = c / (disc.sqrt() - b);
                    let s = (md + t * nd) / self.dd;
                    if (0.0..=1.0).contains(&s) {
                        best = t;
                    }
                }
            }
        }
        for centre in [self.a, self.b] {
            let m = o - centre;
            let (b, c) = (m.dot(n), m.dot(m) - r2);
            if c <= 0.0 {
                return Some(0.0);
            }
            if b < 0.0 {
                let disc = b * b - c;
                if disc >= 0.0 {
                    best = num::min(best, c / (disc.sqrt() - b));
                }
            }
        }
        (best < f64::INFINITY).then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Oracle: march along the ray in small steps, then bisect the first step that enters.
    fn marched_entry(c: &Capsule, o: DVec3, n: DVec3, r: f64, t_max: f64) -> Option<f64> {
        let steps = 20_000;
        let inside = |t: f64| c.distance(o + t * n) <= r;
        if inside(0.0) {
            return Some(0.0);
        }
        for k in 1..=steps {
            let t1 = t_max * k as f64 / steps as f64;
            if inside(t1) {
                let (mut lo, mut hi) = (t_max * (k - 1) as f64 / steps as f64, t1);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if inside(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Some(hi);
            }
        }
        None
    }

    #[test]
    fn entry_matches_a_marched_oracle_on_random_rays() {
        let mut rng = crate::fixtures::SplitMix64(7);
        let mut v = || DVec3::new(rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0);
        let (mut hits, mut misses) = (0, 0);
        for k in 0..400 {
            let a = 2.0 * v();
            // Every tenth capsule is a lone sphere.
            let b = if k % 10 == 0 { a } else { a + 2.0 * v() };
            let c = Capsule::new(a, b);
            let o = 4.0 * v();
            // Aimed near the capsule, so about half the rays hit.
            let n = (0.5 * (a + b) + 1.5 * v() - o).normalize();
            let r = 0.3 + 0.7 * v().x.abs();
            let exact = c.entry(o, n, r);
            match (exact, marched_entry(&c, o, n, r, 12.0)) {
                (Some(t), Some(m)) => {
                    hits += 1;
                    assert!((t - m).abs() < 1e-12, "capsule {k}: {t} vs marched {m}");
                    assert!((c.distance(o + t * n) - r).abs() < 1e-12 || t == 0.0);
                }
                (None, None) => misses += 1,
                (e, m) => panic!("capsule {k}: exact {e:?} vs marched {m:?}"),
            }
        }
        assert!(hits > 50 && misses > 50, "{hits} hits, {misses} misses");
    }

    #[test]
    fn inside_is_zero_and_grazing_misses_are_none() {
        let c = Capsule::new(DVec3::ZERO, DVec3::X);
        assert_eq!(c.entry(DVec3::new(0.5, 0.2, 0.0), DVec3::Z, 0.5), Some(0.0));
        // Parallel to the axis, beside it: never enters.
        assert_eq!(c.entry(DVec3::new(-3.0, 0.6, 0.0), DVec3::X, 0.5), None);
        // Along the axis from behind: enters the end sphere at distance 2.5.
        assert_eq!(c.entry(DVec3::new(-3.0, 0.0, 0.0), DVec3::X, 0.5), Some(2.5));
        // Pointing away.
        assert_eq!(c.entry(DVec3::new(0.5, 0.0, 2.0), DVec3::Z, 0.5), None);
        // From straight above the middle: the cylinder side.
        assert_eq!(c.entry(DVec3::new(0.5, 0.0, 2.0), -DVec3::Z, 0.5), Some(1.5));
    }
}
