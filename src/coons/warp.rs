//! The across coordinate the spiral's lines are straight in: W(V), the mean 3D arc length from
//! V = 0 over the reference lines ([`super::path`]).
//!
//! Why. Rows of different heights give V different speeds (a 10 mm fillet under a 30 mm blade:
//! 1 in V is 14 mm below the row seam and 30 mm above it). A revolution from level V_k to
//! V_{k+1} interpolated linearly in V is then farther from the next one than the levels are
//! where it crosses the row seam (1.1 h measured on the blade band). Interpolated in W instead,
//! the spacing between revolutions stays the levels' spacing, and at a row seam dV/dW jumps with
//! the speed, so the path's tangent stays nearly continuous there too.
//!
//! W is a monotone cubic Hermite interpolant of the tabulated mean arc length within each row
//! (Fritsch–Carlson slopes, one-sided at the row ends): C¹ inside a row, with the slope of each
//! row at its ends. Its inverse is found by bisection.

use glam::DVec2;

/// The warp V ↦ W.
#[derive(Clone, Debug)]
pub struct Warp {
    /// Samples per row.
    per_row: usize,
    /// W at V = k / per_row.
    w: Vec<f64>,
    /// Slopes dW/dV per row at its samples: `slopes[j][k]`.
    slopes: Vec<Vec<f64>>,
}

impl Warp {
    /// From the mean arc length `w` at V = k / `per_row` (k = 0 ..= rows · per_row).
    pub fn new(w: Vec<f64>, per_row: usize) -> Warp {
        let rows = (w.len() - 1) / per_row;
        let mut slopes = Vec::with_capacity(rows);
        let h = 1.0 / per_row as f64;
        for j in 0..rows {
            let y = &w[j * per_row..=(j + 1) * per_row];
            let d: Vec<f64> = y.windows(2).map(|p| (p[1] - p[0]) / h).collect();
            let mut m = vec![0.0; per_row + 1];
            m[0] = d[0];
            m[per_row] = d[per_row - 1];
            for k in 1..per_row {
                // Fritsch–Carlson: the harmonic mean keeps the interpolant monotone.
                m[k] = if d[k - 1] * d[k] > 0.0 { 2.0 * d[k - 1] * d[k] / (d[k - 1] + d[k]) } else { 0.0 };
            }
            slopes.push(m);
        }
        Warp { per_row, w, slopes }
    }

    fn rows(&self) -> usize {
        self.slopes.len()
    }

    /// W and dW/dV at V; at a row seam, the row above's (or below's when `below`).
    pub fn at(&self, v: f64, below: bool) -> (f64, f64) {
        let rows = self.rows();
        let v = v.clamp(0.0, rows as f64);
        let mut j = (v.floor() as usize).min(rows - 1);
        if below && j > 0 && v == j as f64 {
            j -= 1;
        }
        let x = (v - j as f64) * self.per_row as f64;
        let k = (x.floor() as usize).min(self.per_row - 1);
        let t = x - k as f64;
        let h = 1.0 / self.per_row as f64;
        let (y0, y1) = (self.w[j * self.per_row + k], self.w[j * self.per_row + k + 1]);
        let (m0, m1) = (self.slopes[j][k] * h, self.slopes[j][k + 1] * h);
        let (t2, t3) = (t * t, t * t * t);
        let value =
            y0 * (2.0 * t3 - 3.0 * t2 + 1.0) + m0 * (t3 - 2.0 * t2 + t) + y1 * (-2.0 * t3 + 3.0 * t2) + m1 * (t3 - t2);
        let slope = y0 * (6.0 * t2 - 6.0 * t)
            + m0 * (3.0 * t2 - 4.0 * t + 1.0)
            + y1 * (-6.0 * t2 + 6.0 * t)
            + m1 * (3.0 * t2 - 2.0 * t);
        (value, slope / h)
    }

    /// The V with W(V) = `w` (bisection; W is increasing).
    pub fn inverse(&self, w: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, self.rows() as f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.at(mid, false).0 < w {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The point of the line from `a` to `b` (straight in (U, W)) at λ ∈ [0, 1].
    pub fn point(&self, a: DVec2, b: DVec2, lambda: f64) -> DVec2 {
        let u = a.x + (b.x - a.x) * lambda;
        if a.y == b.y {
            return DVec2::new(u, a.y);
        }
        let (wa, wb) = (self.at(a.y, false).0, self.at(b.y, false).0);
        DVec2::new(u, self.inverse(wa + (wb - wa) * lambda))
    }

    /// d(U, V)/dλ of that line at the point with across coordinate `v` (at a row seam, on the
    /// row below when `below`).
    pub fn direction(&self, a: DVec2, b: DVec2, v: f64, below: bool) -> DVec2 {
        let (wa, wb) = (self.at(a.y, false).0, self.at(b.y, false).0);
        let slope = self.at(v, below).1;
        DVec2::new(b.x - a.x, if slope > 0.0 { (wb - wa) / slope } else { b.y - a.y })
    }
}
