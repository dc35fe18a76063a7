//! Seam smoothing (seed 004 §4) and the measurement of the path's tangent jumps at the seams.
//!
//! Why. A straight line of the compound domain with direction (dU, dV) has the 3D tangent
//! x_s dU + x_t dV on either side of a seam. The shared side makes x_t the same on both sides
//! (eq. 3), but the cross-seam derivative x_s is each face's own (a face twice as wide has twice
//! the speed), so the path turns at every seam it crosses. The seed's G¹ gluing (eqs. 13–15,
//! x_s⁺ = α x_s⁻ + β x_t) makes the map's tangent planes agree but still turns a line whose slope
//! is not the gluing's; what a straight domain line needs to be tangent-continuous for every
//! slope is the composite C¹ condition x_s⁺ = x_s⁻ (α = 1, β = 0). That is what we build.
//!
//! How (composite C¹ by boundary-preserving Hermite reparameterisation, our construction in
//! place of the seed's least-squares fit of eq. 23). At every seam round the loop, at
//! `nodes` + 1 values of t, the target cross derivative is the mean D = (x_s⁻ + x_s⁺)/2 of the
//! two faces'. Each face's map is composed with (ŝ, t̂) = (s, t) + a₀(t) h₀(s) + a₁(t) h₁(s)
//! ([`super::patch::Correction`]), which keeps every boundary point where it was (C⁰ and eq. 3
//! stay exact) and changes the cross derivative at s = 0, 1 to x_s (1 + a_s) + x_t a_t; the
//! slopes a = (a_s, a_t) solve x_s (1 + a_s) + x_t a_t = D in least squares (exact when the
//! surface is G¹ there, D then lying in the tangent plane). At the faces' corners only a_s is
//! used (a_t = 0): the faces above and below a row seam then shift its points identically, so
//! the row seams stay closed too. Between the nodes the slopes are Catmull–Rom splines (C¹ in t,
//! so no kink appears inside a face). The reparameterisation must stay regular: the map's
//! det J is checked over a grid ([`Compound::det_j_min_rel`]) and the raw map kept if it folds.
//!
//! The seams between rows are crossed by one revolution, at its shallow slope; the lines are
//! straight in the mean arc length across ([`Warp`]), which evens out the rows' speeds there;
//! their remaining jumps are measured and reported, the map is not smoothed across them.

use super::compound::Compound;
use super::patch::Correction;
use super::warp::Warp;
use glam::{DVec2, DVec3};
use serde::Serialize;

/// A line of the compound domain from `a` to `b` (U increasing), straight in U and the warped
/// across coordinate ([`Warp`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub a: DVec2,
    pub b: DVec2,
}

/// The corrections of every patch of `c` for composite C¹ round the loop.
pub fn corrections(c: &Compound, nodes: usize) -> Vec<Correction> {
    let mut out =
        vec![Correction { left: vec![DVec2::ZERO; nodes + 1], right: vec![DVec2::ZERO; nodes + 1] }; c.patches.len()];
    let solve = |xs: DVec3, xt: DVec3, d: DVec3, corner: bool| -> DVec2 {
        if corner {
            return DVec2::new(d.dot(xs) / xs.length_squared() - 1.0, 0.0);
        }
        let (a, b, cc) = (xs.dot(xs), xs.dot(xt), xt.dot(xt));
        let det = a * cc - b * b;
        let (g1, g2) = (xs.dot(d), xt.dot(d));
        let (p, q) = ((cc * g1 - b * g2) / det, (a * g2 - b * g1) / det);
        DVec2::new(p - 1.0, q)
    };
    for j in 0..c.across {
        for i in 0..c.around {
            let (l, r) = (i + c.around * j, (i + 1) % c.around + c.around * j);
            for k in 0..=nodes {
                let t = k as f64 / nodes as f64;
                let ea = c.patches[l].raw(1.0, t);
                let eb = c.patches[r].raw(0.0, t);
                let d = (ea.xs + eb.xs) * 0.5;
                let corner = k == 0 || k == nodes;
                out[l].right[k] = solve(ea.xs, ea.xt, d, corner);
                out[r].left[k] = solve(eb.xs, eb.xt, d, corner);
            }
        }
    }
    out
}

/// The turning angle between the 3D tangents `a` and `b`, degrees.
fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    let c = (a.dot(b) / (a.length() * b.length())).clamp(-1.0, 1.0);
    crate::num::acos(c).to_degrees()
}

/// The tangent jumps (degrees) the map gives the path `lines` at its seam crossings: round the
/// loop (every integer U, the junction of consecutive lines included, there for the arriving
/// line's direction) and between rows (integer V inside).
pub fn tangent_jumps(c: &Compound, warp: &Warp, lines: &[Line]) -> (Vec<f64>, Vec<f64>) {
    let (mut round, mut rows) = (Vec::new(), Vec::new());
    let m = c.around;
    let tangent = |e: &super::patch::Eval, d: DVec2| e.xs * d.x + e.xt * d.y;
    for (k, line) in lines.iter().enumerate() {
        let (a, b) = (line.a, line.b);
        if b.x <= a.x {
            continue;
        }
        // Seams strictly inside the line, and the junction with the next line (at U = around,
        // for this line's direction on both sides: the slope change between revolutions is the
        // path's own turn, not the map's).
        let last = if lines.get(k + 1).is_some() { b.x.floor() as i64 } else { b.x.ceil() as i64 - 1 };
        for u in (a.x.floor() as i64 + 1)..=last {
            let q = warp.point(a, b, (u as f64 - a.x) / (b.x - a.x));
            let d = warp.direction(a, b, q.y, false);
            let (_, j, _, t) = c.locate(u as f64, q.y);
            let i = (u.rem_euclid(m as i64)) as usize;
            let left = c.patch(i + m - 1, j).eval(1.0, t);
            let right = c.patch(i, j).eval(0.0, t);
            round.push(angle_deg(tangent(&left, d), tangent(&right, d)));
        }
        // Row seams crossed.
        let (wa, wb) = (warp.at(a.y, false).0, warp.at(b.y, false).0);
        for r in 1..c.across {
            let f = if wb != wa { (warp.at(r as f64, false).0 - wa) / (wb - wa) } else { -1.0 };
            if !(f > 0.0 && f < 1.0) {
                continue;
            }
            let u = a.x + (b.x - a.x) * f;
            let (i, _, s, _) = c.locate(u, r as f64);
            let below = c.patch(i, r - 1).eval(s, 1.0);
            let above = c.patch(i, r).eval(s, 0.0);
            let (db, da) = (warp.direction(a, b, r as f64, true), warp.direction(a, b, r as f64, false));
            rows.push(angle_deg(tangent(&below, db), tangent(&above, da)));
        }
    }
    (round, rows)
}

/// Figures of a set of jumps.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Jumps {
    pub crossings: usize,
    pub max_deg: f64,
    pub mean_deg: f64,
}

impl Jumps {
    pub fn of(j: &[f64]) -> Jumps {
        Jumps {
            crossings: j.len(),
            max_deg: j.iter().copied().fold(0.0, f64::max),
            mean_deg: if j.is_empty() { 0.0 } else { j.iter().sum::<f64>() / j.len() as f64 },
        }
    }
}

/// The `seams` section of the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SeamReport {
    /// `composite-c1` (the map was smoothed round the loop) or `none`.
    pub mode: &'static str,
    /// Tangent jumps of the path at the seams round the loop, on the raw Coons map and on the
    /// map the path was planned on.
    pub round_before: Jumps,
    pub round_after: Jumps,
    /// The same at the seams between rows (not smoothed).
    pub rows_before: Jumps,
    pub rows_after: Jumps,
    /// The smallest det J over a grid of every face, relative to its centre's (> 0: regular).
    pub det_j_min_rel: f64,
    /// The largest distance between the points two faces give a shared side, mm.
    pub seam_gap_mm: f64,
    /// Why the smoothing was not used, when it was asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}
