//! The Coons map of one face (seed 004 eq. 1): (s, t) ∈ [0, 1]² → the face's surface parameters
//! (u, v) → the exact surface point.
//!
//! P(s, t) = (1 − t) C₀(s) + t C₁(s) + (1 − s) D₀(t) + s D₁(t) − [1 − s, s] [P₀₀ P₀₁; P₁₀ P₁₁] [1 − t, t]ᵀ
//!
//! with C₀, C₁ the bottom and top sides and D₀, D₁ the left and right sides in (u, v), each
//! parameterised by normalised 3D arc length ([`ParamSide`]). The seed's boundary argument
//! `w + t(w − l)` (eq. 1a, 1b; and `f` for `w` in 1b) is a misprint for the affine map
//! `w + t(l − w)` of [0, 1] onto [w, l]; we replace it by the arc-length inverse, which is that
//! map for a uniformly parameterised side and also makes shared sides coincide (eq. 3).
//!
//! A [`Correction`] (from [`super::smooth`]) composes the map with a reparameterisation of
//! [0, 1]² that leaves the boundary where it is: (ŝ, t̂) = (s, t) + a₀(t) h₀(s) + a₁(t) h₁(s), the
//! cubic Hermite functions h₀ = s(1 − s)², h₁ = s²(s − 1) vanishing at s = 0 and 1 with unit
//! slope at one end each.

use super::side::ParamSide;
use crate::step::geom::Surface;
use glam::{DVec2, DVec3};

/// A point of the map with its derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Eval {
    pub x: DVec3,
    /// ∂x/∂s, ∂x/∂t.
    pub xs: DVec3,
    pub xt: DVec3,
    /// Unit normal towards the tool (the face's normal).
    pub n: DVec3,
    /// The surface parameters.
    pub uv: DVec2,
}

/// Coefficient tables of a correction at `t = k / (len − 1)`: the s-shift and the t-shift slopes
/// at s = 0 (`left`) and s = 1 (`right`), interpolated by Catmull–Rom splines (C¹ in t).
#[derive(Clone, Debug, Default)]
pub struct Correction {
    pub left: Vec<DVec2>,
    pub right: Vec<DVec2>,
}

/// Catmull–Rom value and derivative of the table `y` (uniform nodes on [0, 1]) at `t`.
fn catmull(y: &[DVec2], t: f64) -> (DVec2, DVec2) {
    let n = y.len() - 1;
    let x = t.clamp(0.0, 1.0) * n as f64;
    let k = (x.floor() as usize).min(n - 1);
    let u = x - k as f64;
    let slope = |i: usize| -> DVec2 {
        match i {
            0 => y[1] - y[0],
            i if i == n => y[n] - y[n - 1],
            i => (y[i + 1] - y[i - 1]) * 0.5,
        }
    };
    let (p0, p1, m0, m1) = (y[k], y[k + 1], slope(k), slope(k + 1));
    let (u2, u3) = (u * u, u * u * u);
    let v = p0 * (2.0 * u3 - 3.0 * u2 + 1.0) + m0 * (u3 - 2.0 * u2 + u) + p1 * (-2.0 * u3 + 3.0 * u2) + m1 * (u3 - u2);
    let d = p0 * (6.0 * u2 - 6.0 * u)
        + m0 * (3.0 * u2 - 4.0 * u + 1.0)
        + p1 * (-6.0 * u2 + 6.0 * u)
        + m1 * (3.0 * u2 - 2.0 * u);
    (v, d * n as f64)
}

impl Correction {
    /// (ŝ, t̂) and the Jacobian columns ∂(ŝ, t̂)/∂s, ∂(ŝ, t̂)/∂t.
    pub fn apply(&self, s: f64, t: f64) -> (DVec2, DVec2, DVec2) {
        let (a0, da0) = catmull(&self.left, t);
        let (a1, da1) = catmull(&self.right, t);
        let h0 = s * (1.0 - s) * (1.0 - s);
        let h1 = s * s * (s - 1.0);
        let dh0 = (1.0 - s) * (1.0 - 3.0 * s);
        let dh1 = s * (3.0 * s - 2.0);
        let q = DVec2::new(s, t) + a0 * h0 + a1 * h1;
        let ds = DVec2::X + a0 * dh0 + a1 * dh1;
        let dt = DVec2::Y + da0 * h0 + da1 * h1;
        (q, ds, dt)
    }
}

/// One face's Coons map.
#[derive(Clone, Debug)]
pub struct Patch {
    pub id: u64,
    pub surface: Surface,
    /// +1 when the face's normal is the surface's, −1 when opposite.
    pub sign: f64,
    pub bottom: ParamSide,
    pub top: ParamSide,
    pub left: ParamSide,
    pub right: ParamSide,
    /// P₀₀, P₁₀, P₀₁, P₁₁ (s, t indices).
    pub corners: [DVec2; 4],
    pub correction: Option<Correction>,
}

impl Patch {
    /// The Coons point in (u, v) and its s- and t-derivatives.
    pub fn coons(&self, s: f64, t: f64) -> (DVec2, DVec2, DVec2) {
        let (c0, dc0) = self.bottom.eval(s);
        let (c1, dc1) = self.top.eval(s);
        let (d0, dd0) = self.left.eval(t);
        let (d1, dd1) = self.right.eval(t);
        let [p00, p10, p01, p11] = self.corners;
        let b = p00 * ((1.0 - s) * (1.0 - t)) + p10 * (s * (1.0 - t)) + p01 * ((1.0 - s) * t) + p11 * (s * t);
        let bs = (p10 - p00) * (1.0 - t) + (p11 - p01) * t;
        let bt = (p01 - p00) * (1.0 - s) + (p11 - p10) * s;
        let p = c0 * (1.0 - t) + c1 * t + d0 * (1.0 - s) + d1 * s - b;
        let ps = dc0 * (1.0 - t) + dc1 * t - d0 + d1 - bs;
        let pt = c1 - c0 + dd0 * (1.0 - s) + dd1 * s - bt;
        (p, ps, pt)
    }

    /// The map without the correction.
    pub fn raw(&self, s: f64, t: f64) -> Eval {
        let (uv, ps, pt) = self.coons(s, t);
        let (x, su, sv) = self.surface.eval(uv);
        let n = (su.cross(sv) * self.sign).normalize_or_zero();
        Eval { x, xs: su * ps.x + sv * ps.y, xt: su * pt.x + sv * pt.y, n, uv }
    }

    /// The map with the correction (when there is one).
    pub fn eval(&self, s: f64, t: f64) -> Eval {
        match &self.correction {
            None => self.raw(s, t),
            Some(c) => {
                let (q, ds, dt) = c.apply(s, t);
                let e = self.raw(q.x, q.y);
                Eval { xs: e.xs * ds.x + e.xt * ds.y, xt: e.xs * dt.x + e.xt * dt.y, ..e }
            }
        }
    }

    /// det ∂(u, v)/∂(s, t) of the Coons map (with the correction), in the surface's parameters.
    pub fn det_j(&self, s: f64, t: f64) -> f64 {
        let (q, ds, dt) = match &self.correction {
            None => (DVec2::new(s, t), DVec2::X, DVec2::Y),
            Some(c) => c.apply(s, t),
        };
        let (_, ps, pt) = self.coons(q.x, q.y);
        ps.perp_dot(pt) * ds.perp_dot(dt)
    }
}
