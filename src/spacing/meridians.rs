//! The meridian cusp test of a band (seed 000 eqs. 1–4 on each meridian, see the stage's docs):
//! the meridians a band is tested on, ring k's centre chains on them, and whether a candidate
//! ring leaves each meridian's cusp cut; the bisection's trials over them.

use super::chain::Chain;
use super::features::{offsets_at, SlitBand, CORNER_OFFSETS, CREASE_DEPTHS, TIP_OFFSETS, TIP_WINDOW};
use super::{Lifted, Spacer, SpacingError};
use crate::num;
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// The band above a candidate ring: the meridians tested and ring k's centres near each.
pub(super) struct Band {
    /// Radius of ring k (1 for the outer boundary).
    pub(super) hi: f64,
    pub(super) thetas: Vec<f64>,
    /// Whether each meridian is also tested point by point: within [`TIP_WINDOW`] of a slit tip,
    /// or crossing a crease.
    pub(super) pointwise: Vec<bool>,
    /// Whether the band has crease meridians.
    pub(super) creased: bool,
    /// Ring k's chain per meridian; `None` for the first ring (nothing cut above it).
    pub(super) upper: Option<Vec<Chain>>,
    /// Index of the meridian that failed last: tested first next time.
    pub(super) last_fail: usize,
    /// Meridians the bisection tests (see [`Spacer::next_radius`]).
    pub(super) active: Vec<usize>,
}

/// What [`Spacer::band`] returns: the band and the length of its upper ring, mm.
pub(super) type BandMade = Result<(Band, f64), SpacingError>;

impl Spacer<'_> {
    /// The meridians below ring `hi` (spaced along its surface curve, plus every slit tip, outer
    /// corner and crease crossing) and ring k's centre chains on them; also the ring's length.
    pub(super) fn band(&self, hi: f64, first: bool, last_step: Option<f64>, with_creases: bool) -> BandMade {
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
    pub(super) fn ring_length(&self, rho: f64) -> Result<(f64, Vec<f64>), SpacingError> {
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

    pub(super) fn point(&self, rho: f64, theta: f64) -> Result<Lifted, SpacingError> {
        self.lift.polar(rho, theta).ok_or(SpacingError::Lift { rho, theta })
    }

    /// Point of S^h on the meridian θ at radius s.
    pub(super) fn q(&self, s: f64, theta: f64) -> Result<DVec3, SpacingError> {
        Ok(self.q_at(&self.point(s, theta)?))
    }

    /// Point of S^h over the contact `l`.
    pub(super) fn q_at(&self, l: &Lifted) -> DVec3 {
        l.p + l.n * self.h
    }

    /// Ball centres of the ring `rho` around angle θ: five centres spanning about ±R along
    /// the ring, enough to contain the nearest centre to any point of the band on this meridian.
    pub(super) fn chain(&self, rho: f64, theta: f64) -> Result<Chain, SpacingError> {
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
    pub(super) fn admissible(&mut self, band: &mut Band, rho: f64) -> Result<bool, SpacingError> {
        Ok(self.first_failure(band, rho)?.is_none())
    }

    /// A meridian left uncut by a ring at `rho`, if any (starting from the last one that failed).
    pub(super) fn first_failure(&mut self, band: &mut Band, rho: f64) -> Result<Option<usize>, SpacingError> {
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
    pub(super) fn lowest_on_active(&mut self, band: &Band, bad: f64, step: f64) -> Result<(f64, f64), SpacingError> {
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

    pub(super) fn meridian_ok(&self, band: &Band, i: usize, rho: f64) -> Result<bool, SpacingError> {
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
    pub(super) fn band_points_ok(
        &self,
        upper: &Chain,
        lower: &Chain,
        lo: f64,
        hi: f64,
        theta: f64,
    ) -> Result<bool, SpacingError> {
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
    pub(super) fn cusp_ok(
        &self,
        upper: &Chain,
        lower: &Chain,
        lo: f64,
        hi: f64,
        theta: f64,
    ) -> Result<bool, SpacingError> {
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
