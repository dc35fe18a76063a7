//! Stage `spread` (between `optimise` and `spacing`, with `--spread need`): a radial warp of the
//! ring field that shares each meridian's rings out by that meridian's own need (issue 32;
//! beyond seed 003, as the issue allows: "rings whose spacing is chosen along the optimised
//! field rather than uniformly").
//!
//! # Why
//! The spacing places every ring as a level set |w| = R_k of the field, spaced for its worst
//! meridian. Where the meridians differ in length (a rectangle's corners, the far side of a hole)
//! every other meridian is cut finer than asked. Seed 003's optimisation (stage `optimise`) evens
//! the field out only as far as a piecewise-linear field on the part's triangles can: the rings
//! that would follow the long meridians turn sharply (the offset rings' corners), inside faces,
//! where a P1 field rounds them off (docs/optimise.md, limit 2).
//!
//! # What it computes
//! On each of about 1 800 meridians θ_j of the field (even along the outer loop's 3D length,
//! and evenly in angle) the cumulative need from the rim inward, N_j(ρ) = ∫ ds / w(s), with w =
//! 2√(2Rh) the flat-plate stepover of the user's R and h (so N counts ideal rings), along the
//! lifted meridian; then g_j(ρ) = N_j(ρ) / N_j(r_min), smoothed over neighbouring meridians.
//! The warped field is ρ' = 1 − g(θ, ρ)·(1 − r_min) (angles kept), bilinear in (θ_j, ρ_k):
//! monotone in ρ on every meridian, 1 on the rim, r_min at the pole or the annulus' inner circle.
//! Its circles ρ' = c are the rings the spacing then places: each meridian's share of the rings
//! follows its own need instead of the field's.
//!
//! The warp is applied where the rings are lifted ([`crate::spacing::Lift::spread`]): exactly,
//! not as a P1 field on the vertices, which would fold wherever it turns faster than the faces
//! (a P1 image of this warp folded 100–130 faces on a 117 × 59 mm rectangle and missed parts of
//! it). The vertices' image ([`Spread::image`]) only indexes the map for the spacing's tests.
//!
//! # Decisions
//! - A hole's slit stays one circle: on every meridian over a slit its radius is pinned to the
//!   mean of those meridians' g there (fading out over [`SpreadOptions::pin_fade_rad`] past its
//!   ends), else a ring would cross the hole. The need across a slit is zero (the hole's width is
//!   not material: its two sides are the ends of two segments).
//! - The need counts flat-plate stepovers, without the surface's curvature: it only shapes the
//!   rings, and the spacing's own tests then place them for the real scallop.
//! - Each meridian's g is averaged with its neighbours': unsmoothed, the rings zigzagged from one
//!   meridian to the next (see [`SpreadOptions::smoothing`]).
//!
//! # Preconditions
//! A lift of a slit map (disk or annulus), R > 0, 0 < h < R.
//!
//! # Invariants
//! [`Spread::forward`] and [`Spread::inverse`] are inverse to rounding, strictly monotone in ρ;
//! the rim maps to 1, r_min to r_min, every slit's radius over its span to one radius.

use crate::mesh::Surface;
use crate::slitmap::{Mode, SlitMap};
use crate::spacing::Lift;
use serde::Serialize;
use std::f64::consts::TAU;

/// Options of the spread stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpreadOptions {
    /// Ball radius R, mm (the stepover the need counts in). Default 3.
    pub radius_mm: f64,
    /// Scallop height h, mm. Default 0.02.
    pub scallop_mm: f64,
    /// Radii sampled on each meridian, evenly in ρ. Default 400.
    pub rows: usize,
    /// Meridians evenly along the outer loop's 3D length (dense where the map squeezes a corner).
    /// Default 1440.
    pub rim_columns: usize,
    /// Meridians evenly in angle (bounds the gaps where the loop is short per radian). Default 360.
    pub angle_columns: usize,
    /// Each meridian's g is averaged with this many neighbours on each side. Default 10 (0: the
    /// rings zigzagged between meridians, a disk's path 1.51 times the flat-plate bound against
    /// 1.31; 30: the corners blurred, a 117 × 59 mm rectangle's 1.72 against 1.61).
    pub smoothing: usize,
    /// A slit's pin fades out over this angle past its ends, radians. Default 0.15.
    pub pin_fade_rad: f64,
}

impl Default for SpreadOptions {
    fn default() -> Self {
        Self {
            radius_mm: 3.0,
            scallop_mm: 0.02,
            rows: 400,
            rim_columns: 1440,
            angle_columns: 360,
            smoothing: 10,
            pin_fade_rad: 0.15,
        }
    }
}

/// Errors of the spread stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpreadError {
    #[error("invalid spread option: {0}")]
    InvalidOption(String),
}

/// The warp ρ → ρ' of one field (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Spread {
    r_min: f64,
    /// Meridian angles, ascending in [0, 2π).
    thetas: Vec<f64>,
    /// Sampled radii, ascending from r_min to 1 (every slit's radius among them).
    rows: Vec<f64>,
    /// g of meridian j at row k, 1 at r_min, 0 at the rim, decreasing in k, at
    /// `g[k * (thetas.len() + 1) + j]`; column `thetas.len()` repeats column 0 (the wrap). Row by
    /// row, so that the two meridians round a query share a cache line at every row the
    /// inverse's search reads (by meridian, those reads took twice the cache misses).
    g: Vec<f64>,
    /// `thetas` and `rows` bucketed, for the lift's many queries.
    theta_buckets: Buckets,
    row_buckets: Buckets,
}

/// An ascending list's `partition_point(|x| x <= t)` over [lo, hi], from buckets: where each
/// bucket's start falls in the list, so that only the values within one bucket of `t` are
/// searched. The same answer as the list's own binary search (the [`crate::spacing::Lift`] of a
/// spread field asks it twice per query; as a binary search over the 1 800 meridians it took 7 %
/// of planning the 40k panel).
#[derive(Debug, Clone, PartialEq)]
struct Buckets {
    lo: f64,
    per: f64,
    /// `first[b]`: how many values are ≤ the start of bucket b.
    first: Vec<u32>,
}

impl Buckets {
    fn new(values: &[f64], lo: f64, hi: f64, count: usize) -> Self {
        let per = count as f64 / (hi - lo);
        let first = (0..=count).map(|b| values.partition_point(|&x| x <= lo + b as f64 / per) as u32).collect();
        Self { lo, per, first }
    }

    fn partition_point(&self, values: &[f64], t: f64) -> usize {
        let b = ((t - self.lo) * self.per).floor();
        let last = self.first.len() - 1;
        // A bucket of margin on each side: t's bucket as computed may be off by rounding.
        let (a, z) = if b >= 1.0 && b < last as f64 {
            let b = b as usize;
            (self.first[b - 1] as usize, self.first[(b + 2).min(last)] as usize)
        } else {
            (0, values.len())
        };
        let z = if b + 2.0 >= last as f64 { values.len() } else { z };
        a + values[a..z].partition_point(|&x| x <= t)
    }
}

fn check(o: &SpreadOptions) -> Result<(), SpreadError> {
    let bad = |m: String| Err(SpreadError::InvalidOption(m));
    if !(o.radius_mm.is_finite() && o.radius_mm > 0.0) {
        return bad(format!("ball radius {} mm must be a positive number", o.radius_mm));
    }
    if !(o.scallop_mm.is_finite() && o.scallop_mm > 0.0 && o.scallop_mm < o.radius_mm) {
        return bad(format!("scallop height {} mm must be in (0, R)", o.scallop_mm));
    }
    if o.rows < 2 || o.rim_columns + o.angle_columns < 8 {
        return bad(format!("{} rows and {} meridians are too few", o.rows, o.rim_columns + o.angle_columns));
    }
    if !(o.pin_fade_rad.is_finite() && o.pin_fade_rad > 0.0) {
        return bad(format!("pin fade {} rad must be a positive number", o.pin_fade_rad));
    }
    Ok(())
}

/// The spread of the field `lift` inverts.
pub fn spread(lift: &Lift<'_>, options: &SpreadOptions) -> Result<Spread, SpreadError> {
    check(options)?;
    let map = lift.map();
    let r_min = map.mode.inner_radius();
    let mut thetas = columns(lift, options);
    // Meridians at the slits' ends: every angle over a slit lies between two pinned meridians.
    for s in &map.slits {
        thetas.extend([s.theta_start, s.theta_end].map(crate::num::rem_tau));
    }
    thetas.sort_by(f64::total_cmp);
    thetas.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let mut rows: Vec<f64> =
        (0..=options.rows).map(|k| r_min + (1.0 - r_min) * k as f64 / options.rows as f64).collect();
    rows.extend(map.slits.iter().map(|s| s.radius));
    rows.sort_by(f64::total_cmp);
    rows.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let per_mm = 1.0 / (2.0 * (2.0 * options.radius_mm * options.scallop_mm).sqrt());
    let needs = crate::par::each(thetas.len(), |j| need(lift, thetas[j], &rows, per_mm));
    // g: the need normalised to 1 at the inner end of each meridian.
    let raw: Vec<Vec<f64>> = needs.iter().map(|n| n.iter().map(|&x| x / n[0]).collect()).collect();
    let theta_buckets = Buckets::new(&thetas, 0.0, TAU, 4 * thetas.len());
    let row_buckets = Buckets::new(&rows, r_min, 1.0, 4 * rows.len());
    let pinned = pin(&thetas, &rows, smooth(&raw, options.smoothing), map, options.pin_fade_rad);
    // Row by row, column 0 again at the end of each (the wrap).
    let g = (0..rows.len()).flat_map(|k| pinned.iter().chain(&pinned[..1]).map(move |column| column[k])).collect();
    Ok(Spread { r_min, g, thetas, rows, theta_buckets, row_buckets })
}

/// The need on the meridian `theta` from the rim inward to each of `rows`, in ideal rings.
fn need(lift: &Lift<'_>, theta: f64, rows: &[f64], per_mm: f64) -> Vec<f64> {
    let last = rows.len() - 1;
    let mut need = vec![0.0; last + 1];
    let mut total = 0.0;
    // Located afresh each time: walking from the last face (`Lift::polar_near`) strays round
    // the slits' ends, and the need there came out wrong (gen14: 2.76 against 2.26 times the
    // flat-plate bound).
    let at = |rho: f64| lift.polar(rho, theta).map(|l| l.p);
    // Each segment is sampled just inside its ends: across a slit's radius (a row) the two sides
    // of the hole are two segments' ends, and the hole between them needs nothing.
    for k in (0..last).rev() {
        let (lo, hi) = (rows[k], rows[k + 1]);
        let eps = 1e-9 * (hi - lo);
        if let (Some(a), Some(b)) = (at(hi - eps), at(lo + eps)) {
            total += a.distance(b) * per_mm;
        }
        // Strictly monotone, so that the warp can be inverted.
        total += 1e-9;
        need[k] = total;
    }
    need
}

/// Each meridian's column averaged with `half` neighbours on each side.
fn smooth(raw: &[Vec<f64>], half: usize) -> Vec<Vec<f64>> {
    let n = raw.len();
    if half == 0 {
        return raw.to_vec();
    }
    (0..n)
        .map(|j| {
            (0..raw[j].len())
                .map(|k| {
                    (0..=2 * half).map(|d| raw[(j + n * (half + 1) + d - half) % n][k]).sum::<f64>()
                        / (2 * half + 1) as f64
                })
                .collect()
        })
        .collect()
}

/// Meridian angles: evenly along the outer loop's 3D length (lifted just inside the rim) and
/// evenly in angle.
fn columns(lift: &Lift<'_>, options: &SpreadOptions) -> Vec<f64> {
    const DENSE: usize = 16384;
    let mut out: Vec<f64> = (0..options.angle_columns).map(|j| TAU * j as f64 / options.angle_columns as f64).collect();
    let rho = 1.0 - 1e-7;
    let points = crate::par::each(DENSE + 1, |i| lift.polar(rho, TAU * i as f64 / DENSE as f64).map(|l| l.p));
    let mut cumulative = vec![0.0];
    for i in 0..DENSE {
        let d = match (points[i], points[i + 1]) {
            (Some(a), Some(b)) => a.distance(b),
            _ => 0.0,
        };
        cumulative.push(cumulative[i] + d);
    }
    let total = cumulative[DENSE];
    let mut i = 0;
    for m in 0..options.rim_columns {
        let target = total * m as f64 / options.rim_columns as f64;
        while i + 1 < DENSE && cumulative[i + 1] < target {
            i += 1;
        }
        let seg = cumulative[i + 1] - cumulative[i];
        let f = if seg > 0.0 { (target - cumulative[i]) / seg } else { 0.0 };
        out.push(TAU * (i as f64 + f) / DENSE as f64);
    }
    out
}

/// The columns `g` (by meridian `thetas`, at `rows`) with every slit's radius pinned to one g
/// over its span (see the module docs).
fn pin(thetas: &[f64], rows: &[f64], g: Vec<Vec<f64>>, map: &SlitMap, fade: f64) -> Vec<Vec<f64>> {
    // g of meridian j at `rho`.
    let column_at = |j: usize, rho: f64| {
        let (k, u) = bracket(rows, rows.partition_point(|&r| r <= rho), rho);
        g[j][k] * (1.0 - u) + g[j][k + 1] * u
    };
    let targets: Vec<f64> = map
        .slits
        .iter()
        .map(|s| {
            let over: Vec<f64> =
                (0..thetas.len()).filter(|&j| s.contains_angle(thetas[j])).map(|j| column_at(j, s.radius)).collect();
            if over.is_empty() {
                0.5
            } else {
                over.iter().sum::<f64>() / over.len() as f64
            }
        })
        .collect();
    (0..thetas.len())
        .map(|j| {
            let theta = thetas[j];
            // Knots (own g → pinned g), ascending.
            let mut knots: Vec<(f64, f64)> = vec![(0.0, 0.0), (1.0, 1.0)];
            for (s, &target) in map.slits.iter().zip(&targets) {
                let weight = (1.0 - angular_distance(theta, s.theta_start, s.theta_end) / fade).clamp(0.0, 1.0);
                if weight > 0.0 {
                    let own = column_at(j, s.radius);
                    knots.push((own, own + weight * (target - own)));
                }
            }
            knots.sort_by(|a, b| a.0.total_cmp(&b.0));
            // Strictly increasing targets: two pins at crossed places keep the warp monotone.
            for i in 1..knots.len() {
                knots[i].1 = knots[i].1.max(knots[i - 1].1 + 1e-12);
            }
            g[j].iter().map(|&x| remap(&knots, x)).collect()
        })
        .collect()
}

impl Spread {
    /// Row k and the weight of row k + 1 at `rho`.
    fn row_at(&self, rho: f64) -> (usize, f64) {
        let rho = rho.clamp(self.r_min, 1.0);
        bracket(&self.rows, self.row_buckets.partition_point(&self.rows, rho), rho)
    }

    /// The first of the two meridians round `theta` (the second is the next column of `g`) and
    /// the weight of the second.
    fn columns_at(&self, theta: f64) -> (usize, f64) {
        let theta = crate::num::rem_tau(theta);
        let n = self.thetas.len();
        let k = self.theta_buckets.partition_point(&self.thetas, theta);
        let j0 = (k + n - 1) % n;
        let (t0, mut t1) = (self.thetas[j0], self.thetas[(j0 + 1) % n]);
        let mut x = theta;
        if t1 <= t0 {
            t1 += TAU;
            if x < t0 {
                x += TAU;
            }
        }
        (j0, if t1 > t0 { ((x - t0) / (t1 - t0)).clamp(0.0, 1.0) } else { 0.0 })
    }

    /// g at row `k` between the meridians `columns_at` found.
    fn g_at(&self, (j0, f): (usize, f64), k: usize) -> f64 {
        let i = k * (self.thetas.len() + 1) + j0;
        self.g[i] * (1.0 - f) + self.g[i + 1] * f
    }

    /// ρ' of the field's point (ρ, θ).
    pub fn forward(&self, theta: f64, rho: f64) -> f64 {
        let c = self.columns_at(theta);
        let (k, u) = self.row_at(rho);
        let g = self.g_at(c, k) * (1.0 - u) + self.g_at(c, k + 1) * u;
        1.0 - g * (1.0 - self.r_min)
    }

    /// ρ of the warped point (ρ', θ): the inverse of [`Spread::forward`].
    pub fn inverse(&self, theta: f64, rho_spread: f64) -> f64 {
        let c = self.columns_at(theta);
        let g = ((1.0 - rho_spread) / (1.0 - self.r_min)).clamp(0.0, 1.0);
        // g decreases along the rows: the row k with g_k ≥ g ≥ g_{k+1}.
        let (mut lo, mut hi) = (0usize, self.rows.len() - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.g_at(c, mid) >= g {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (g0, g1) = (self.g_at(c, lo), self.g_at(c, hi));
        let u = if g0 > g1 { ((g0 - g) / (g0 - g1)).clamp(0.0, 1.0) } else { 0.0 };
        self.rows[lo] + (self.rows[hi] - self.rows[lo]) * u
    }

    /// The map's image under the warp, vertex by vertex (what the spacing indexes; its lift is
    /// the warp applied exactly, [`crate::spacing::Lift::spread`]): slits at their pinned radii,
    /// every loop on its circle exactly.
    pub fn image(&self, surface: &Surface, map: &SlitMap) -> SlitMap {
        let mut out = map.clone();
        for w in &mut out.w {
            let rho = w.length();
            if rho > 0.0 {
                *w *= self.forward(crate::num::atan2(w.y, w.x), rho) / rho;
            }
        }
        for s in &mut out.slits {
            // Any meridian over the slit gives the pinned radius.
            s.radius = self.forward(s.theta_start, s.radius);
        }
        let circles: Vec<(usize, f64)> = out.slits.iter().map(|s| (s.hole, s.radius)).collect();
        let mut snap = |l: usize, radius: f64| {
            for &v in &surface.loops[l] {
                let w = &mut out.w[v as usize];
                *w *= radius / w.length();
            }
        };
        snap(0, 1.0);
        for (hole, radius) in circles {
            snap(hole, radius);
        }
        if let Mode::Annulus { hole, inner_radius } = map.mode {
            snap(hole, inner_radius);
        }
        out
    }
}

/// The row k of `rows` below `rho` and the weight of row k + 1, from `above` = how many rows
/// are ≤ `rho`.
fn bracket(rows: &[f64], above: usize, rho: f64) -> (usize, f64) {
    let k = above.clamp(1, rows.len() - 1) - 1;
    let (a, b) = (rows[k], rows[k + 1]);
    (k, if b > a { ((rho - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 })
}

/// Angle from `theta` to the arc [start, end] (0 on it).
fn angular_distance(theta: f64, start: f64, end: f64) -> f64 {
    let d = crate::num::rem_tau(theta - start);
    let extent = end - start;
    if d <= extent {
        0.0
    } else {
        (d - extent).min(TAU - d)
    }
}

/// The piecewise-linear function through `knots` (ascending in x) at `x`.
fn remap(knots: &[(f64, f64)], x: f64) -> f64 {
    for w in knots.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if x <= x1 {
            return if x1 > x0 { y0 + (y1 - y0) * (x - x0) / (x1 - x0) } else { y1 };
        }
    }
    knots.last().map_or(x, |k| k.1)
}

#[cfg(test)]
mod tests;
