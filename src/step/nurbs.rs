//! Non-uniform rational B-splines: curves and tensor-product surfaces, points and first
//! derivatives (Piegl & Tiller, *The NURBS Book*, A2.1 span search, A2.3 basis derivatives,
//! eq. 4.8 for the rational derivative).
//!
//! Knots are stored expanded (each value repeated by its multiplicity); the constructors check
//! the counts `knots = poles + degree + 1` and non-decreasing knots, so evaluation cannot index
//! out of range. Parameters outside the knot range are clamped to it.

use glam::DVec3;

/// Why a B-spline definition is inconsistent (the caller names the entity).
pub type Invalid = String;

/// Expands STEP's (multiplicities, knot values) and checks them against the pole count.
pub fn expand_knots(mults: &[i64], values: &[f64], degree: usize, poles: usize) -> Result<Vec<f64>, Invalid> {
    if mults.len() != values.len() {
        return Err(format!("{} knot multiplicities for {} knot values", mults.len(), values.len()));
    }
    let mut knots = Vec::new();
    for (&m, &v) in mults.iter().zip(values) {
        if !(1..=64).contains(&m) {
            return Err(format!("knot multiplicity {m} out of range"));
        }
        knots.extend(std::iter::repeat(v).take(m as usize));
    }
    if degree == 0 || degree > 25 {
        return Err(format!("degree {degree} is not supported (1 to 25)"));
    }
    if knots.len() != poles + degree + 1 {
        return Err(format!(
            "{} knots (with multiplicity) for {poles} poles of degree {degree}: expected {}",
            knots.len(),
            poles + degree + 1
        ));
    }
    // (The values are finite: the reader checks every number.)
    if knots.windows(2).any(|w| w[1] < w[0]) || knots[poles] <= knots[degree] {
        return Err("knots are not non-decreasing over a non-empty range".into());
    }
    Ok(knots)
}

/// The span `i` with `knots[i] ≤ t < knots[i+1]` within `[degree, poles − 1]` (A2.1), `t` clamped.
fn span(knots: &[f64], degree: usize, poles: usize, t: f64) -> (usize, f64) {
    let (lo, hi) = (knots[degree], knots[poles]);
    let t = if t.is_nan() { lo } else { t.clamp(lo, hi) };
    if t >= hi {
        // The last non-empty span.
        let mut i = poles - 1;
        while i > degree && knots[i] >= hi {
            i -= 1;
        }
        return (i, t);
    }
    // Binary search in [degree, poles).
    let (mut a, mut b) = (degree, poles);
    while b - a > 1 {
        let m = (a + b) / 2;
        if t < knots[m] {
            b = m;
        } else {
            a = m;
        }
    }
    (a, t)
}

/// The degree-`p` basis functions `N[i−p..=i]` at `t` in span `i` (A2.2).
fn basis(knots: &[f64], p: usize, i: usize, t: f64) -> [f64; 26] {
    let mut left = [0.0; 26];
    let mut right = [0.0; 26];
    let mut n = [0.0; 26];
    n[0] = 1.0;
    for j in 1..=p {
        left[j] = t - knots[i + 1 - j];
        right[j] = knots[i + j] - t;
        let mut saved = 0.0;
        for r in 0..j {
            let den = right[r + 1] + left[j - r];
            let temp = if den != 0.0 { n[r] / den } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

/// Basis functions and their first derivatives (eq. 2.9 from the degree-(p−1) functions).
fn basis_ders(knots: &[f64], p: usize, i: usize, t: f64) -> ([f64; 26], [f64; 26]) {
    // lower[j] is N_{i−p+1+j, p−1}.
    let lower = basis(knots, p - 1, i, t);
    let mut d = [0.0; 26];
    for (r, dr) in d.iter_mut().enumerate().take(p + 1) {
        let k = i - p + r;
        let a = if r >= 1 { lower[r - 1] } else { 0.0 };
        let b = if r < p { lower[r] } else { 0.0 };
        let da = knots[k + p] - knots[k];
        let db = knots[k + p + 1] - knots[k + 1];
        *dr = p as f64 * ((if da > 0.0 { a / da } else { 0.0 }) - (if db > 0.0 { b / db } else { 0.0 }));
    }
    (basis(knots, p, i, t), d)
}

/// A (possibly rational) B-spline curve.
#[derive(Clone, Debug)]
pub struct Curve {
    pub degree: usize,
    pub poles: Vec<DVec3>,
    /// Empty for a polynomial curve.
    pub weights: Vec<f64>,
    pub knots: Vec<f64>,
}

impl Curve {
    pub fn range(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.poles.len()])
    }

    /// Point and first derivative.
    pub fn eval(&self, t: f64) -> (DVec3, DVec3) {
        let p = self.degree;
        let (i, t) = span(&self.knots, p, self.poles.len(), t);
        let (n, d) = basis_ders(&self.knots, p, i, t);
        let (mut a, mut da, mut w, mut dw) = (DVec3::ZERO, DVec3::ZERO, 0.0, 0.0);
        for r in 0..=p {
            let k = i - p + r;
            let wk = self.weights.get(k).copied().unwrap_or(1.0);
            a += self.poles[k] * (n[r] * wk);
            da += self.poles[k] * (d[r] * wk);
            w += n[r] * wk;
            dw += d[r] * wk;
        }
        let c = a / w;
        (c, (da - c * dw) / w)
    }
}

/// A (possibly rational) tensor-product B-spline surface; `poles[i * nv + j]`, i along u.
#[derive(Clone, Debug)]
pub struct Surface {
    pub degree: [usize; 2],
    pub counts: [usize; 2],
    pub poles: Vec<DVec3>,
    /// Empty for a polynomial surface; else one per pole.
    pub weights: Vec<f64>,
    pub knots: [Vec<f64>; 2],
}

impl Surface {
    pub fn range(&self) -> [(f64, f64); 2] {
        [0, 1].map(|d| (self.knots[d][self.degree[d]], self.knots[d][self.counts[d]]))
    }

    /// Point and the two first partial derivatives.
    pub fn eval(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let [pu, pv] = self.degree;
        let [nu, nv] = self.counts;
        let (iu, u) = span(&self.knots[0], pu, nu, u);
        let (iv, v) = span(&self.knots[1], pv, nv, v);
        let (bu, du) = basis_ders(&self.knots[0], pu, iu, u);
        let (bv, dv) = basis_ders(&self.knots[1], pv, iv, v);
        let (mut a, mut au, mut av) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        let (mut w, mut wu, mut wv) = (0.0, 0.0, 0.0);
        for r in 0..=pu {
            let i = iu - pu + r;
            for s in 0..=pv {
                let j = iv - pv + s;
                let k = i * nv + j;
                let wk = self.weights.get(k).copied().unwrap_or(1.0);
                let q = self.poles[k] * wk;
                a += q * (bu[r] * bv[s]);
                au += q * (du[r] * bv[s]);
                av += q * (bu[r] * dv[s]);
                w += wk * bu[r] * bv[s];
                wu += wk * du[r] * bv[s];
                wv += wk * bu[r] * dv[s];
            }
        }
        let p = a / w;
        (p, (au - p * wu) / w, (av - p * wv) / w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rational_quadratic_is_an_exact_quarter_circle_with_the_right_tangent() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let c = Curve {
            degree: 2,
            poles: vec![DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            weights: vec![1.0, s, 1.0],
            knots: expand_knots(&[3, 3], &[0.0, 1.0], 2, 3).unwrap(),
        };
        for k in 0..=20 {
            let t = k as f64 / 20.0;
            let (p, d) = c.eval(t);
            assert!((p.length() - 1.0).abs() < 1e-14, "{t}: {p}");
            assert!(p.dot(d).abs() < 1e-12);
            // Finite-difference check of the derivative.
            let h = 1e-6;
            let fd = (c.eval((t + h).min(1.0)).0 - c.eval((t - h).max(0.0)).0) / ((t + h).min(1.0) - (t - h).max(0.0));
            assert!((fd - d).length() < 1e-5, "{t}: {fd} {d}");
        }
    }

    #[test]
    fn a_bicubic_with_interior_knots_has_the_right_partials() {
        let knots = expand_knots(&[4, 1, 4], &[0.0, 0.4, 1.0], 3, 5).unwrap();
        let mut poles = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                poles.push(DVec3::new(i as f64, j as f64, ((i * 3 + j * 7) % 5) as f64 * 0.3));
            }
        }
        let s = Surface { degree: [3, 3], counts: [5, 5], poles, weights: vec![], knots: [knots.clone(), knots] };
        let h = 1e-6;
        for &(u, v) in &[(0.1, 0.2), (0.4, 0.9), (0.77, 0.33), (0.99, 0.01)] {
            let (_, su, sv) = s.eval(u, v);
            let fu = (s.eval((u + h).min(1.0), v).0 - s.eval(u - h, v).0) / ((u + h).min(1.0) - (u - h));
            let fv = (s.eval(u, v + h).0 - s.eval(u, (v - h).max(0.0)).0) / (v + h - (v - h).max(0.0));
            assert!((fu - su).length() < 1e-5 && (fv - sv).length() < 1e-5, "{u} {v}");
        }
        assert!(expand_knots(&[4, 4], &[0.0, 1.0], 3, 5).unwrap_err().contains("expected 9"));
    }
}
