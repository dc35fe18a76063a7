//! Which points of a band the balls of its two rings reach: a ring's ball-centre polyline
//! ([`RingLine`]), the test of a point of S^h against the rings' polylines ([`Cutter`]), and the
//! cusps between the two rings along a run of the gate's points ([`Cutter::add_cusps`]). The gate
//! ([`super::gate`]) decides where the points are.

use super::gate::{at, End, GatePoint, Labels};
use super::Segment;
use crate::num;
use glam::DVec3;

/// Segments searched on each side of a point's angle for the distances that locate a cusp: the
/// nearest centres of a point between two rings lie on its own meridian.
const CUSP_SEGMENTS: usize = 3;
// [`Cutter::side`]'s "cut" relies on the local test searching those segments too.
const _: () = assert!(CUSP_SEGMENTS <= LOCAL_SEGMENTS);

/// Regula falsi steps locating a cusp along an edge ([`Cutter::add_cusps`]).
const CUSP_STEPS: usize = 4;

/// A ring's ball-centre polyline with the angle of each centre (ascending over [0, 2π]) and
/// its segments (see [`Segment`]).
#[derive(Debug, Clone)]
pub(super) struct RingLine {
    rho: f64,
    theta: Vec<f64>,
    centres: Vec<DVec3>,
    /// Segment k joins centres k and k + 1.
    segments: Vec<Segment>,
}

impl RingLine {
    pub(super) fn new(rho: f64) -> Self {
        Self { rho, theta: Vec::new(), centres: Vec::new(), segments: Vec::new() }
    }

    pub(super) fn push(&mut self, theta: f64, centre: DVec3) {
        if let Some(&last) = self.centres.last() {
            if last == centre {
                return;
            }
            self.segments.push(Segment::new(last, centre));
        }
        self.theta.push(theta);
        self.centres.push(centre);
    }

    /// Whether a segment within [`LOCAL_SEGMENTS`] of angle `theta` lies within `r` of `q`:
    /// the fast answer for a point of a band, whose nearest centres are almost always on its
    /// own meridian. `false` is not conclusive.
    fn near_theta_within(&self, q: DVec3, theta: f64, r: f64) -> bool {
        match self.find_near(theta, LOCAL_SEGMENTS, |s| s.dist2(q) <= r * r) {
            Some(found) => found,
            None => self.centres.first().is_some_and(|c| c.distance_squared(q) <= r * r),
        }
    }

    /// The squared distance from `q` to the segments within `window` of angle `theta`: the
    /// distance to the ring where its nearest centres are on the point's own meridian, as they
    /// almost always are (else an overestimate).
    fn near_dist2(&self, q: DVec3, theta: f64, window: usize, hint: &mut usize) -> f64 {
        let mut best = f64::INFINITY;
        let found = self.find_near_from(theta, window, hint, |s| {
            best = num::min(best, s.dist2(q));
            false
        });
        match found {
            Some(_) => best,
            None => self.centres.first().map_or(f64::INFINITY, |c| c.distance_squared(q)),
        }
    }

    /// Calls `f` on the segments within `window` of angle `theta`, outwards from it (where the
    /// nearest almost always is: its own, then one before and one after, …) until it returns
    /// `true`; whether it did. `None` for a ring of fewer than two centres.
    #[inline]
    fn find_near(&self, theta: f64, window: usize, f: impl FnMut(&Segment) -> bool) -> Option<bool> {
        let mut hint = usize::MAX;
        self.find_near_from(theta, window, &mut hint, f)
    }

    /// [`RingLine::find_near`], the segment at `theta` located from `hint` (the place of the
    /// previous angle of a run along a line, updated) when it is still right: the cusp search
    /// asks for a few nearby angles in turn, and this spares their binary searches.
    #[inline]
    fn find_near_from(
        &self,
        theta: f64,
        window: usize,
        hint: &mut usize,
        mut f: impl FnMut(&Segment) -> bool,
    ) -> Option<bool> {
        let n = self.centres.len();
        if n < 2 {
            return None;
        }
        let t = crate::num::rem_tau(theta);
        // The partition point of `x <= t`, the one k with θ[k − 1] ≤ t < θ[k]: the hint when
        // it is that k (the angles ascend, so the answer is the binary search's, bit for bit).
        let k = *hint;
        let fits = k <= n && (k == 0 || self.theta[k - 1] <= t) && (k == n || !(self.theta[k] <= t));
        let k = if fits { k } else { self.theta.partition_point(|&x| x <= t) };
        *hint = k;
        let i = k.clamp(1, n - 1) - 1;
        let m = self.segments.len();
        if i >= window && i + window < m {
            let s = &self.segments[i - window..=i + window];
            return Some(f(&s[window]) || (1..=window).any(|d| f(&s[window - d]) || f(&s[window + d])));
        }
        // The ring closes: centre n − 1 is centre 0, so segments wrap modulo n − 1.
        let at = |offset: isize| &self.segments[(i as isize + offset).rem_euclid(m as isize) as usize];
        Some(f(at(0)) || (1..=window as isize).any(|d| f(at(-d)) || f(at(d))))
    }
}

/// Segments searched on each side of a point's angle before the rings are searched whole.
const LOCAL_SEGMENTS: usize = 8;

/// Points the local search does not settle that are tested against every segment, before a grid
/// is built for the rest: on the 40k panel a cutter met 2.6 such points on average, and building
/// its grid took 25 times as long as testing one (and held up the other threads waiting for it).
const BRUTE_FORCE_POINTS: usize = 16;

/// Whether points of S^h (height `h_mm` over the surface) lie within `radius_mm` of a ball centre
/// on the rings' polylines.
pub(super) struct Cutter<'r> {
    rings: &'r [&'r RingLine],
    radius_mm: f64,
    h_mm: f64,
    /// Points the local search did not settle so far.
    unsettled: std::sync::atomic::AtomicUsize,
    /// Built by the first point the local search does not settle past [`BRUTE_FORCE_POINTS`].
    grid: std::sync::OnceLock<SegmentGrid>,
}

impl<'r> Cutter<'r> {
    pub(super) fn new(rings: &'r [&'r RingLine], radius_mm: f64, h_mm: f64) -> Self {
        Self { rings, radius_mm, h_mm, unsettled: Default::default(), grid: std::sync::OnceLock::new() }
    }

    pub(super) fn cuts(&self, &(p, n, rho, theta): &GatePoint) -> bool {
        let q = p + n * self.h_mm;
        // The ring nearer in |w| first.
        let order = match self.rings {
            [a, b] if (b.rho - rho).abs() < (a.rho - rho).abs() => [Some(*b), Some(*a)],
            [a, b] => [Some(*a), Some(*b)],
            [a] => [Some(*a), None],
            _ => [None, None],
        };
        let r = self.radius_mm;
        order.into_iter().flatten().any(|ring| ring.near_theta_within(q, theta, r)) || self.any_within(q, r)
    }

    /// Whether any segment of the rings lies within `r` of `q`: the same answer from every
    /// segment in turn or from the grid, whichever is cheaper so far.
    fn any_within(&self, q: DVec3, r: f64) -> bool {
        if self.unsettled.fetch_add(1, std::sync::atomic::Ordering::Relaxed) < BRUTE_FORCE_POINTS {
            return self
                .rings
                .iter()
                .flat_map(|ring| segments(ring))
                .any(|(a, b)| super::segment_dist2(q, a, b) <= r * r);
        }
        self.grid.get_or_init(|| SegmentGrid::new(self.rings, r)).any_within(q, r)
    }

    /// Which of the two rings is nearer the point of S^h over `p` (positive: the second, the
    /// lower one), as a difference of distances, mm, and whether that point is cut (as
    /// [`Cutter::cuts`] would say: a segment found within R here is one that searches too);
    /// `None` without two rings. `hints` carry the rings' segments at the previous point of a
    /// run (see [`RingLine::find_near_from`]).
    fn side(&self, &(p, n, _, theta): &GatePoint, hints: &mut [usize; 2]) -> Option<(f64, bool)> {
        let [upper, lower] = self.rings else { return None };
        let q = p + n * self.h_mm;
        let (du2, dl2) = (
            upper.near_dist2(q, theta, CUSP_SEGMENTS, &mut hints[0]),
            lower.near_dist2(q, theta, CUSP_SEGMENTS, &mut hints[1]),
        );
        let r2 = self.radius_mm * self.radius_mm;
        Some((du2.sqrt() - dl2.sqrt(), du2 <= r2 || dl2 <= r2))
    }

    /// The cusps along the run of points `out[first..]` that [`super::gate`] laid from `a` to `b`:
    /// where the nearer ring changes between two of them, the point where both are equally far
    /// (regula falsi: along a line the difference of the two distances is nearly linear), added
    /// to `out`. The scallop peaks in a narrow V there (its flanks slope by about √(2h/R)):
    /// points a fixed step apart pass up to step·√(h/2R) under it, more than h on coarse
    /// meshes (issue 34's sweep: 1.1–1.3 h between the gate's points on 3k–12k-face parts).
    /// Points (laid or found) that the distances measured on the way show cut are dropped: the
    /// caller's test of each point ([`Cutter::cuts`]) would drop them, and those distances
    /// settle most of them.
    ///
    /// In a spread field (`labels`) the points laid outside the band (`lo`, `hi`) are dropped
    /// by their labels ([`Gate::uncut`]), and a cusp lies inside it: the distances are measured
    /// only at the points inside and at those beside a step that enters or crosses it.
    pub(super) fn add_cusps(
        &self,
        a: End,
        b: End,
        labels: Labels<'_>,
        (lo, hi): (f64, f64),
        first: usize,
        out: &mut Vec<GatePoint>,
    ) {
        if self.rings.len() != 2 {
            return;
        }
        let count = out.len() - first;
        let at = |u: f64| at(a, b, u, labels);
        let ends = [at(0.0), at(1.0)];
        // The points of `line` are the middles of `count` equal pieces; with the two ends (on
        // the band's rings where the edge crosses it whole) they bracket every cusp.
        let u_of = |i: usize| match i {
            0 => 0.0,
            i if i > count => 1.0,
            i => ((i - 1) as f64 + 0.5) / count as f64,
        };
        let laid = |out: &[GatePoint], i: usize| match i {
            0 => ends[0],
            i if i > count => ends[1],
            i => out[first + i - 1],
        };
        // -1 below the band, 1 above, 0 inside (always, but in a spread field).
        let spread = labels.is_spread();
        let place = |out: &[GatePoint], i: usize| {
            let rho = laid(out, i).2;
            if !spread || (rho > lo && rho < hi) {
                0
            } else if rho <= lo {
                -1
            } else {
                1
            }
        };
        let apart = |out: &[GatePoint], i: usize, j: usize| {
            let (x, y) = (place(out, i), place(out, j));
            x != y || x == 0
        };
        let needed = |out: &[GatePoint], i: usize| {
            place(out, i) == 0 || (i > 0 && apart(out, i - 1, i)) || (i <= count && apart(out, i, i + 1))
        };
        let side = |out: &[GatePoint], i: usize, hints: &mut [usize; 2]| {
            if needed(out, i) {
                self.side(&laid(out, i), hints)
            } else {
                None
            }
        };
        let mut hints = [usize::MAX; 2];
        // Laid points not known to be cut are moved down to `kept` as their sides are measured
        // (reads run ahead of that); cusps found are pushed after the laid points meanwhile.
        let mut kept = first;
        let mut next = side(out, 0, &mut hints);
        for i in 0..count + 1 {
            let (this, after) = (next, side(out, i + 1, &mut hints));
            next = after;
            if i < count && !after.is_some_and(|(_, cut)| cut) {
                out[kept] = out[first + i];
                kept += 1;
            }
            let (Some((mut fa, _)), Some((mut fb, _))) = (this, after) else { continue };
            if (fa > 0.0) == (fb > 0.0) {
                continue;
            }
            let (mut ua, mut ub) = (u_of(i), u_of(i + 1));
            let mut best = None;
            // The search keeps its own hints: the next laid point's follow on from this one's.
            let mut search_hints = hints;
            for _ in 0..CUSP_STEPS {
                let u = if fb != fa { ua - fa * (ub - ua) / (fb - fa) } else { 0.5 * (ua + ub) };
                let u = u.clamp(ua.min(ub), ua.max(ub));
                // Only the point kept needs its radius (a spread field's costs a warp lookup).
                let point = super::gate::at(a, b, u, labels.angles());
                let Some((f, cut)) = self.side(&point, &mut search_hints) else { break };
                best = (!cut).then_some(u);
                if f == 0.0 {
                    break;
                }
                if (f > 0.0) == (fa > 0.0) {
                    (ua, fa) = (u, f);
                    fb *= 0.5; // Illinois: the end kept twice is halved
                } else {
                    (ub, fb) = (u, f);
                    fa *= 0.5;
                }
            }
            out.extend(best.map(at));
        }
        out.drain(kept..first + count);
    }

    /// The points of `points` no ball reaches.
    pub(super) fn uncut(&self, points: &[GatePoint]) -> Vec<GatePoint> {
        let cut = crate::par::each(points.len(), |i| self.cuts(&points[i]));
        points.iter().zip(cut).filter(|(_, c)| !c).map(|(p, _)| *p).collect()
    }
}

/// The segments of a ring's polyline (a lone centre as a segment of length 0).
fn segments(ring: &RingLine) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
    let c = &ring.centres;
    let lone = (c.len() == 1).then(|| (c[0], c[0]));
    lone.into_iter().chain(c.windows(2).map(|w| (w[0], w[1])))
}

/// Segments of polylines binned in a uniform grid (cells of the ball radius), for "is any
/// segment within R of q". Lookups only: the answer does not depend on the map's order.
struct SegmentGrid {
    cell: f64,
    segments: Vec<(DVec3, DVec3)>,
    bins: std::collections::HashMap<[i64; 3], Vec<u32>>,
}

impl SegmentGrid {
    fn new(rings: &[&RingLine], cell: f64) -> Self {
        let segments: Vec<(DVec3, DVec3)> = rings.iter().flat_map(|ring| segments(ring)).collect();
        let key = |p: DVec3| (p / cell).floor().as_i64vec3().to_array();
        let mut bins: std::collections::HashMap<[i64; 3], Vec<u32>> = std::collections::HashMap::new();
        for (i, &(a, b)) in segments.iter().enumerate() {
            let (lo, hi) = (key(a.min(b)), key(a.max(b)));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        bins.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        Self { cell, segments, bins }
    }

    fn any_within(&self, q: DVec3, r: f64) -> bool {
        let key = |p: DVec3| (p / self.cell).floor().as_i64vec3().to_array();
        let (lo, hi) = (key(q - DVec3::splat(r)), key(q + DVec3::splat(r)));
        let r2 = r * r;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let Some(bin) = self.bins.get(&[x, y, z]) else { continue };
                    for &i in bin {
                        let (a, b) = self.segments[i as usize];
                        if super::segment_dist2(q, a, b) <= r2 {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::super::gate::line;
    use super::*;
    use crate::fixtures::SplitMix64;
    use glam::DVec2;
    use std::f64::consts::TAU;

    fn brute_force(rings: &[&RingLine], q: DVec3, r: f64) -> bool {
        rings.iter().any(|ring| ring.centres.windows(2).any(|w| crate::spacing::segment_dist2(q, w[0], w[1]) <= r * r))
    }

    /// A wavy ring of `n` centres round the z axis, angles ascending over [0, 2π].
    fn ring(rho: f64, n: usize, rng: &mut SplitMix64) -> RingLine {
        let mut line = RingLine::new(rho);
        for i in 0..=n {
            let t = TAU * i as f64 / n as f64;
            let wobble = if i == n { 0.0 } else { 0.2 * rng.unit() };
            let radius = if i == n { line.centres[0].truncate().length() } else { 10.0 * rho + wobble };
            line.push(t, DVec3::new(radius * t.cos(), radius * t.sin(), 0.1 * (3.0 * t).sin()));
        }
        line
    }

    #[test]
    fn the_grid_and_the_local_search_agree_with_brute_force() {
        let mut rng = SplitMix64(0x6a7e);
        let rings = [ring(1.0, 300, &mut rng), ring(0.9, 250, &mut rng)];
        let refs: Vec<&RingLine> = rings.iter().collect();
        let r = 0.6;
        let grid = SegmentGrid::new(&refs, r);
        let (mut cut, mut local) = (0, 0);
        for _ in 0..20_000 {
            let (t, s) = (TAU * rng.unit(), 8.0 + 3.0 * rng.unit());
            let q = DVec3::new(s * t.cos(), s * t.sin(), 0.4 * (rng.unit() - 0.5));
            let exact = brute_force(&refs, q, r);
            assert_eq!(grid.any_within(q, r), exact, "grid at {q}");
            // The local search may miss a cover (it is not conclusive), never invent one.
            let near = refs.iter().any(|ring| ring.near_theta_within(q, t, r));
            assert!(!near || exact, "local search at {q}");
            cut += exact as usize;
            local += near as usize;
        }
        // Between the rings every cover is on the point's own meridian.
        assert!(cut > 1000 && local == cut, "cut {cut}, found locally {local}");
        // The cutter answers the same as brute force.
        let points: Vec<GatePoint> = (0..2000)
            .map(|_| {
                let (t, s) = (TAU * rng.unit(), 8.5 + 2.0 * rng.unit());
                (DVec3::new(s * t.cos(), s * t.sin(), 0.0), DVec3::Z, 0.0, t)
            })
            .collect();
        let h = 0.05;
        let bad = Cutter::new(&refs, r, h).uncut(&points);
        let expected: Vec<GatePoint> =
            points.iter().filter(|p| !brute_force(&refs, p.0 + p.1 * h, r)).copied().collect();
        assert_eq!(bad, expected);
    }

    #[test]
    fn the_cusp_along_a_line_is_where_the_two_rings_are_equally_far() {
        // Two concentric rings of ball centres (radii 10 and 9.2 mm, R 3 mm over the plane z = 0)
        // and a line across the band at angle 0.3, slightly tilted in z: the cusp found must be
        // the brute-force maximum of the nearer ring's distance.
        let r = 3.0;
        let circle = |radius: f64| {
            let mut line = RingLine::new(radius / 10.0);
            for i in 0..=720 {
                let t = TAU * i as f64 / 720.0;
                line.push(t, DVec3::new(radius * t.cos(), radius * t.sin(), r));
            }
            line
        };
        let (upper, lower) = (circle(10.0), circle(9.2));
        let refs = [&upper, &lower];
        let h = 0.01;
        let cutter = Cutter::new(&refs, r, h);
        let theta: f64 = 0.3;
        let (dir, n) = (DVec3::new(theta.cos(), theta.sin(), 0.0), DVec3::Z);
        let end = |s: f64, z: f64| (dir * s + DVec3::Z * z, n, DVec2::new(theta, s / 10.0), (0, [0.0; 3]));
        let (a, b) = (end(10.0, 0.0), end(9.2, 0.005));
        let mut out = Vec::new();
        line(a, b, 0.5, 4.0, Labels::new(None), &mut out);
        assert_eq!(out.len(), 4, "four points, none on the cusp");
        let laid = out.clone();
        cutter.add_cusps(a, b, Labels::new(None), (0.0, 1.0), 0, &mut out);
        // The two laid points nearest the rings are cut (the balls reach them) and dropped, the
        // two inner ones kept in order, and the cusp added after them.
        let uncut: Vec<GatePoint> = laid.iter().filter(|p| !cutter.cuts(p)).copied().collect();
        assert_eq!(uncut, [laid[1], laid[2]]);
        assert_eq!(out.len(), 3, "one cusp between the rings");
        assert_eq!(out[..2], uncut[..]);
        let gap = |p: &GatePoint| {
            let q = p.0 + p.1 * h;
            refs.iter().map(|ring| ring.near_dist2(q, p.3, LOCAL_SEGMENTS, &mut 0).sqrt()).fold(f64::INFINITY, f64::min)
                - r
        };
        let dense = (0..=20_000)
            .map(|i| {
                let u = i as f64 / 20_000.0;
                (a.0.lerp(b.0, u), n, 0.0, theta)
            })
            .map(|p| gap(&p))
            .fold(f64::NEG_INFINITY, f64::max);
        let found = gap(&out[2]);
        // The V's flanks slope by about 0.13, the brute force steps 4e-5 mm: it may fall short
        // of the peak by up to 3e-6 mm, never pass it.
        assert!(found >= dense - 1e-12 && found - dense < 5e-6, "cusp gap {found} mm, brute force {dense} mm");
        // The four evenly spaced points pass well under it.
        let sampled = laid.iter().map(gap).fold(f64::NEG_INFINITY, f64::max);
        assert!(dense - sampled > 1e-3, "sampled {sampled}, cusp {dense}");
    }
}
