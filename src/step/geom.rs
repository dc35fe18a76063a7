//! The exact surfaces and edge curves of a STEP model: evaluation and point inversion.
//!
//! Parameterisations follow ISO 10303-42: for the elementary surfaces `u` is the angle about the
//! placement's axis from its reference direction (radians) and `v` the height along the axis
//! (plane: `u, v` along the reference direction and axis × reference, mm; sphere: `v` the
//! latitude; torus: `v` the angle about the tube). Inversion of an analytic surface is closed
//! form; of a B-spline surface, Newton's method on the squared distance from the best point of
//! a coarse grid (or the caller's hint).

use super::nurbs;
use crate::num;
use glam::{DVec2, DVec3};
use std::f64::consts::TAU;

/// An orthonormal placement (AXIS2_PLACEMENT_3D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: DVec3,
    /// Reference direction (x).
    pub x: DVec3,
    pub y: DVec3,
    /// Axis (z).
    pub z: DVec3,
}

impl Frame {
    /// From a location, an axis and a reference direction (made orthogonal to the axis).
    pub fn new(origin: DVec3, axis: DVec3, reference: DVec3) -> Option<Frame> {
        let z = axis.try_normalize()?;
        let x = (reference - z * reference.dot(z)).try_normalize().or_else(|| z.any_orthonormal_vector().into())?;
        Some(Frame { origin, x, y: z.cross(x), z })
    }

    fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.x), d.dot(self.y), d.dot(self.z))
    }

    fn radial(&self, u: f64) -> DVec3 {
        let (s, c) = num::sin_cos(u);
        self.x * c + self.y * s
    }
}

/// A face's underlying surface.
#[derive(Clone, Debug)]
pub enum Surface {
    Plane(Frame),
    Cylinder(Frame, f64),
    /// Radius at `v = 0` and the semi-angle (radians).
    Cone(Frame, f64, f64),
    Sphere(Frame, f64),
    /// Major and minor radius.
    Torus(Frame, f64, f64),
    BSpline(Box<nurbs::Surface>),
}

impl Surface {
    /// The STEP entity name, for reports.
    pub fn kind(&self) -> &'static str {
        match self {
            Surface::Plane(_) => "plane",
            Surface::Cylinder(..) => "cylinder",
            Surface::Cone(..) => "cone",
            Surface::Sphere(..) => "sphere",
            Surface::Torus(..) => "torus",
            Surface::BSpline(s) if !s.weights.is_empty() => "rational b-spline",
            Surface::BSpline(_) => "b-spline",
        }
    }

    /// Which parameters are angles (periodic with period 2π).
    pub fn periodic(&self) -> [bool; 2] {
        match self {
            Surface::Plane(_) | Surface::BSpline(_) => [false, false],
            Surface::Cylinder(..) | Surface::Cone(..) | Surface::Sphere(..) => [true, false],
            Surface::Torus(..) => [true, true],
        }
    }

    /// Point and first partial derivatives at `(u, v)`.
    pub fn eval(&self, uv: DVec2) -> (DVec3, DVec3, DVec3) {
        let (u, v) = (uv.x, uv.y);
        match self {
            Surface::Plane(f) => (f.origin + f.x * u + f.y * v, f.x, f.y),
            Surface::Cylinder(f, r) => {
                let d = f.radial(u);
                (f.origin + d * *r + f.z * v, f.z.cross(d) * *r, f.z)
            }
            Surface::Cone(f, r, a) => {
                let d = f.radial(u);
                let rv = r + v * num::tan(*a);
                (f.origin + d * rv + f.z * v, f.z.cross(d) * rv, d * num::tan(*a) + f.z)
            }
            Surface::Sphere(f, r) => {
                let d = f.radial(u);
                let (sv, cv) = num::sin_cos(v);
                (f.origin + (d * cv + f.z * sv) * *r, f.z.cross(d) * (r * cv), (f.z * cv - d * sv) * *r)
            }
            Surface::Torus(f, big, small) => {
                let d = f.radial(u);
                let (sv, cv) = num::sin_cos(v);
                let rho = big + small * cv;
                (f.origin + d * rho + f.z * (small * sv), f.z.cross(d) * rho, (f.z * cv - d * sv) * *small)
            }
            Surface::BSpline(s) => s.eval(u, v),
        }
    }

    pub fn point(&self, uv: DVec2) -> DVec3 {
        self.eval(uv).0
    }

    /// Unit normal `Su × Sv` (zero where the surface is singular).
    pub fn normal(&self, uv: DVec2) -> DVec3 {
        let (_, su, sv) = self.eval(uv);
        su.cross(sv).normalize_or_zero()
    }

    /// The parameters of the surface point nearest `p` (angles in (−π, π]); `hint` starts the
    /// Newton iteration of a B-spline surface.
    pub fn invert(&self, p: DVec3, hint: Option<DVec2>) -> DVec2 {
        match self {
            Surface::Plane(f) => {
                let q = f.local(p);
                DVec2::new(q.x, q.y)
            }
            Surface::Cylinder(f, _) => {
                let q = f.local(p);
                DVec2::new(num::atan2(q.y, q.x), q.z)
            }
            Surface::Cone(f, r, a) => {
                // Nearest point on the generating line at angle u.
                let q = f.local(p);
                let u = num::atan2(q.y, q.x);
                let rho = num::hypot(q.x, q.y);
                let (s, c) = num::sin_cos(*a);
                // Line: (r + v tan a, v) in (rho, z); direction (sin a, cos a) / cos a per unit v.
                let t = (rho - r) * s + q.z * c; // arc length from v = 0
                DVec2::new(u, t * c)
            }
            Surface::Sphere(f, _) => {
                let q = f.local(p);
                DVec2::new(num::atan2(q.y, q.x), num::atan2(q.z, num::hypot(q.x, q.y)))
            }
            Surface::Torus(f, big, _) => {
                let q = f.local(p);
                let rho = num::hypot(q.x, q.y);
                DVec2::new(num::atan2(q.y, q.x), num::atan2(q.z, rho - big))
            }
            Surface::BSpline(s) => invert_bspline(s, p, hint),
        }
    }
}

/// Newton on `|S(u,v) − p|²` (Gauss–Newton steps, clamped to the domain), from `hint` or the
/// best point of a 16 × 16 grid; the better of the two starts wins.
fn invert_bspline(s: &nurbs::Surface, p: DVec3, hint: Option<DVec2>) -> DVec2 {
    let [(u0, u1), (v0, v1)] = s.range();
    let clamp = |q: DVec2| DVec2::new(q.x.clamp(u0, u1), q.y.clamp(v0, v1));
    let newton = |start: DVec2| -> (DVec2, f64) {
        let mut q = clamp(start);
        let mut best = (q, (s.eval(q.x, q.y).0 - p).length_squared());
        for _ in 0..30 {
            let (x, su, sv) = s.eval(q.x, q.y);
            let r = x - p;
            let (a, b, c) = (su.dot(su), su.dot(sv), sv.dot(sv));
            let det = a * c - b * b;
            if det.is_nan() || det.abs() <= 1e-300 {
                break;
            }
            let (gu, gv) = (su.dot(r), sv.dot(r));
            let step = DVec2::new(c * gu - b * gv, a * gv - b * gu) / det;
            q = clamp(q - step);
            let d = (s.eval(q.x, q.y).0 - p).length_squared();
            if d < best.1 {
                best = (q, d);
            }
            if step.length_squared() < 1e-28 * (1.0 + q.length_squared()) {
                break;
            }
        }
        best
    };
    let mut best = hint.map(newton);
    // A hinted result is kept only when it lands on the point (after a sharp turn of a
    // boundary the hint may be a poor start).
    if best.map_or(true, |b| b.1 > 1e-16) {
        let n = 16;
        let mut start = DVec2::new(u0, v0);
        let mut d_best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n {
                let q = DVec2::new(u0 + (u1 - u0) * i as f64 / n as f64, v0 + (v1 - v0) * j as f64 / n as f64);
                let d = (s.eval(q.x, q.y).0 - p).length_squared();
                if d < d_best {
                    (start, d_best) = (q, d);
                }
            }
        }
        let grid = newton(start);
        if best.map_or(true, |b| grid.1 < b.1) {
            best = Some(grid);
        }
    }
    best.map_or(DVec2::new(u0, v0), |b| b.0)
}

/// An edge's 3D curve.
#[derive(Clone, Debug)]
pub enum Curve {
    Line { origin: DVec3, dir: DVec3 },
    Circle(Frame, f64),
    Ellipse(Frame, f64, f64),
    BSpline(Box<nurbs::Curve>),
}

impl Curve {
    pub fn point(&self, t: f64) -> DVec3 {
        match self {
            Curve::Line { origin, dir } => *origin + *dir * t,
            Curve::Circle(f, r) => f.origin + f.radial(t) * *r,
            Curve::Ellipse(f, a, b) => {
                let (s, c) = num::sin_cos(t);
                f.origin + f.x * (a * c) + f.y * (b * s)
            }
            Curve::BSpline(c) => c.eval(t).0,
        }
    }

    /// The derivative with respect to the curve's parameter.
    pub fn derivative(&self, t: f64) -> DVec3 {
        match self {
            Curve::Line { dir, .. } => *dir,
            Curve::Circle(f, r) => f.z.cross(f.radial(t)) * *r,
            Curve::Ellipse(f, a, b) => {
                let (s, c) = num::sin_cos(t);
                f.y * (b * c) - f.x * (a * s)
            }
            Curve::BSpline(c) => c.eval(t).1,
        }
    }

    /// Whether the parameter is an angle (period 2π).
    pub fn periodic(&self) -> bool {
        matches!(self, Curve::Circle(..) | Curve::Ellipse(..))
    }

    /// The parameter of the curve point nearest `p`.
    pub fn invert(&self, p: DVec3) -> f64 {
        match self {
            Curve::Line { origin, dir } => (p - *origin).dot(*dir) / dir.length_squared(),
            Curve::Circle(f, _) => {
                let q = f.local(p);
                num::atan2(q.y, q.x)
            }
            Curve::Ellipse(f, a, b) => {
                let q = f.local(p);
                num::atan2(q.y / b, q.x / a)
            }
            Curve::BSpline(c) => {
                let (t0, t1) = c.range();
                let n = 64;
                let mut t = t0;
                let mut best = f64::INFINITY;
                for k in 0..=n {
                    let s = t0 + (t1 - t0) * k as f64 / n as f64;
                    let d = (c.eval(s).0 - p).length_squared();
                    if d < best {
                        (t, best) = (s, d);
                    }
                }
                for _ in 0..30 {
                    let (x, d) = c.eval(t);
                    let den = d.length_squared();
                    if den.is_nan() || den <= 1e-300 {
                        break;
                    }
                    let step = (x - p).dot(d) / den;
                    t = (t - step).clamp(t0, t1);
                    if step.abs() < 1e-14 * (1.0 + t.abs()) {
                        break;
                    }
                }
                t
            }
        }
    }

    /// The parameter range of the curve's own direction from `start` to `end` (a full turn of a
    /// periodic curve when they coincide; the whole range of a closed B-spline likewise).
    pub fn span(&self, start: DVec3, end: DVec3, closed: bool) -> (f64, f64) {
        let t0 = self.invert(start);
        let mut t1 = self.invert(end);
        if self.periodic() {
            t1 = t0 + num::rem_tau(t1 - t0);
            if closed || t1 - t0 < 1e-12 {
                t1 = t0 + TAU;
            }
        } else if let (Curve::BSpline(c), true) = (self, closed) {
            return c.range();
        }
        (t0, t1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_inversions_return_the_parameters() {
        let f = Frame::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.2, 0.1, 1.0), DVec3::X).unwrap();
        let surfaces = [
            Surface::Plane(f),
            Surface::Cylinder(f, 5.0),
            Surface::Cone(f, 5.0, 0.3),
            Surface::Sphere(f, 5.0),
            Surface::Torus(f, 8.0, 2.0),
        ];
        for s in &surfaces {
            for &uv in &[DVec2::new(0.3, 0.4), DVec2::new(-2.5, 1.1), DVec2::new(3.0, -0.7)] {
                let back = s.invert(s.point(uv), None);
                assert!((back - uv).length() < 1e-9, "{}: {uv} → {back}", s.kind());
                let (_, su, sv) = s.eval(uv);
                let h = 1e-6;
                let fu = (s.point(uv + DVec2::X * h) - s.point(uv - DVec2::X * h)) / (2.0 * h);
                let fv = (s.point(uv + DVec2::Y * h) - s.point(uv - DVec2::Y * h)) / (2.0 * h);
                assert!((fu - su).length() < 1e-6 && (fv - sv).length() < 1e-6, "{}", s.kind());
            }
        }
    }

    #[test]
    fn curve_derivatives_match_finite_differences() {
        let f = Frame::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.2, 0.1, 1.0), DVec3::X).unwrap();
        let curves = [
            Curve::Line { origin: DVec3::ONE, dir: DVec3::new(0.6, 0.0, 0.8) },
            Curve::Circle(f, 4.0),
            Curve::Ellipse(f, 5.0, 2.0),
        ];
        for c in &curves {
            for &t in &[0.3, -1.2, 2.9] {
                let h = 1e-6;
                let fd = (c.point(t + h) - c.point(t - h)) / (2.0 * h);
                assert!((fd - c.derivative(t)).length() < 1e-6, "{c:?} at {t}");
            }
        }
    }
}
