//! The volume a round cone sweeps between consecutive poses, moved as an A/C controller moves
//! it, and the signed distance of a point to it.
//!
//! A round cone is the union of the spheres centred on an axis segment a → b, |b − a| = L, with
//! radii r₁ … r₂ varying linearly (seed 002 eqs. 1–2): the tool's flank plus spherical caps at
//! both ends (at the tip the cap reaches r₁(1 − sin α) beyond the real tool's flat end, so a
//! gouge reported there may be one the real tool does not make: the verifier errs on the safe
//! side). The signed distance of a point q to it, in the meridian plane of q (axial x from a,
//! radial ρ), is min over z ∈ [0, L] of √((x − z)² + ρ²) − r₁ − (z/L)Δr, a convex function of z
//! whose minimiser is z* = x + ρ·tan α (clamped): exact, negative inside.
//!
//! Between two consecutive poses the controller moves the tip on a straight line and the rotary
//! axes A, C linearly (tool-centre-point control on a table-table machine; the angles are the A/C
//! post's, [`crate::gcode::ac::ac_angles`]). The swept volume is the union of the round cones
//! over τ ∈ [0, 1], so the distance to it is min over τ of the distance at τ: a one-dimensional
//! minimisation (Brent's method, 10⁻¹⁰ in τ), started only for segments whose lower bound can
//! beat the best so far: a point of the cone moves at most v = |Δtip| + (offset + L)·(angle
//! swept) in a move, so d(τ) ≥ (d(0) + d(1) − v)/2.

use crate::flank::SphereFamily;
use crate::gcode::ac;
use crate::num;
use glam::DVec3;

/// A pose as the controller holds it: tip, unit axis, and the rotary angles (degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerPose {
    pub tip: DVec3,
    pub axis: DVec3,
    pub a_deg: f64,
    pub c_deg: f64,
}

/// The round cone of the tool (from the tool's sphere family).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundCone {
    pub offset: f64,
    pub length: f64,
    pub r1: f64,
    pub delta_r: f64,
    pub tan_alpha: f64,
}

impl RoundCone {
    pub fn new(f: &SphereFamily) -> Self {
        RoundCone {
            offset: f.tip_offset_mm,
            length: f.length_mm,
            r1: f.r1_mm,
            delta_r: f.delta_r_mm,
            tan_alpha: f.sin_alpha / f.cos_alpha,
        }
    }

    /// Signed distance from `q` to the round cone of the pose (tip, axis): (distance, the
    /// nearest sphere's centre, whether the nearest point lies on the flank, i.e. z* ∈ [0, L]).
    #[inline]
    pub fn distance(&self, q: DVec3, tip: DVec3, axis: DVec3) -> (f64, DVec3, bool) {
        let a = tip + self.offset * axis;
        let w = q - a;
        let x = w.dot(axis);
        let rho = (w - x * axis).length();
        let z_star = x + rho * self.tan_alpha;
        let eps = 1e-9 * self.length;
        let on_flank = z_star >= -eps && z_star <= self.length + eps;
        let z = z_star.clamp(0.0, self.length);
        let centre = a + z * axis;
        (q.distance(centre) - self.r1 - (z / self.length) * self.delta_r, centre, on_flank)
    }

    /// Largest distance from the tip to a point of the cone, for motion bounds.
    pub fn reach(&self) -> f64 {
        self.offset + self.length + self.r1 + self.delta_r.max(0.0)
    }
}

/// The controller's pose at τ of the move from `p` to `q`: tip on the line, A and C linear.
#[inline]
pub fn interpolate(p: &ControllerPose, q: &ControllerPose, tau: f64) -> (DVec3, DVec3) {
    if tau <= 0.0 {
        return (p.tip, p.axis);
    }
    if tau >= 1.0 {
        return (q.tip, q.axis);
    }
    let tip = p.tip + tau * (q.tip - p.tip);
    let axis = ac::axis_of(p.a_deg + tau * (q.a_deg - p.a_deg), p.c_deg + tau * (q.c_deg - p.c_deg));
    (tip, axis)
}

/// The controller poses of a program's moves: A/C from the post's rule when every axis is
/// within the machine's A range; otherwise (None is returned for the angles) the verifier
/// interpolates the axis along the great circle instead.
pub fn controller_poses(tips: &[DVec3], axes: &[DVec3]) -> (Vec<ControllerPose>, Option<usize>) {
    match ac::ac_angles(axes) {
        Ok(angles) => (
            tips.iter()
                .zip(axes)
                .zip(&angles)
                .map(|((&tip, _), &(a, c))| ControllerPose { tip, axis: ac::axis_of(a, c), a_deg: a, c_deg: c })
                .collect(),
            None,
        ),
        Err(crate::gcode::GcodeError::AOutOfRange { index, .. }) => (
            tips.iter()
                .zip(axes)
                .map(|(&tip, &axis)| ControllerPose { tip, axis, a_deg: f64::NAN, c_deg: f64::NAN })
                .collect(),
            Some(index),
        ),
        Err(_) => (
            tips.iter()
                .zip(axes)
                .map(|(&tip, &axis)| ControllerPose { tip, axis, a_deg: f64::NAN, c_deg: f64::NAN })
                .collect(),
            Some(0),
        ),
    }
}

/// [`interpolate`], or the great-circle interpolation where the angles are unknown (NaN).
#[inline]
pub fn pose_at(p: &ControllerPose, q: &ControllerPose, tau: f64) -> (DVec3, DVec3) {
    if p.a_deg.is_nan() || q.a_deg.is_nan() {
        let tip = p.tip + tau * (q.tip - p.tip);
        let axis = (p.axis + tau * (q.axis - p.axis)).normalize_or_zero();
        return (tip, if axis == DVec3::ZERO { p.axis } else { axis });
    }
    interpolate(p, q, tau)
}

/// The closest approach of `q` to the cone swept from `p0` to `p1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Approach {
    pub distance: f64,
    pub tau: f64,
    /// Unit normal of the tool's swept surface at the nearest point, pointing out of the tool:
    /// from the nearest sphere's centre towards q (towards the surface it cuts).
    pub normal: DVec3,
    pub on_flank: bool,
}

/// The closest approach of `q` to the cone swept between two poses (module docs), given the
/// distances at both ends (`d0`, `d1`).
pub fn closest(cone: &RoundCone, q: DVec3, p0: &ControllerPose, p1: &ControllerPose) -> Approach {
    let g = |tau: f64| {
        let (tip, axis) = pose_at(p0, p1, tau);
        cone.distance(q, tip, axis)
    };
    let (tau, _) = brent(|t| g(t).0, 0.0, 1.0, 1e-10);
    let mut best = (tau, g(tau));
    for t in [0.0, 1.0] {
        let v = g(t);
        if v.0 < best.1 .0 {
            best = (t, v);
        }
    }
    let (tau, (distance, centre, on_flank)) = best;
    let normal = (q - centre).normalize_or_zero();
    Approach { distance, tau, normal, on_flank }
}

/// Brent's minimisation of `f` on [a, b] (golden section with parabolic steps), to `tol` in x.
pub fn brent(f: impl Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> (f64, f64) {
    const GOLD: f64 = 0.381_966_011_250_105_1;
    let (mut a, mut b) = (a, b);
    let mut x = a + GOLD * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x);
    let (mut fw, mut fv) = (fx, fx);
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        let tol1 = tol + 1e-12 * x.abs();
        let tol2 = 2.0 * tol1;
        if (x - m).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < m { tol1 } else { -tol1 };
                }
                golden = false;
            }
        }
        if golden {
            e = if x < m { b - x } else { a - x };
            d = GOLD * e;
        }
        let u = if d.abs() >= tol1 { x + d } else { x + if d > 0.0 { tol1 } else { -tol1 } };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    (x, fx)
}

/// Angle between two unit vectors, radians.
pub fn angle(u: DVec3, v: DVec3) -> f64 {
    2.0 * num::atan2((u - v).length(), (u + v).length())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flank::ConeTool;

    #[test]
    fn round_cone_distance_matches_brute_force_over_its_spheres() {
        let f = ConeTool { tip_radius_mm: 1.5, top_radius_mm: 4.0, flute_length_mm: 12.0 }.spheres().unwrap();
        let cone = RoundCone::new(&f);
        let (tip, axis) = (DVec3::new(1.0, -2.0, 0.5), DVec3::new(0.3, 0.2, 0.9).normalize());
        let a = tip + f.tip_offset_mm * axis;
        let mut rng = crate::fixtures::SplitMix64::skipped(9, 0);
        for _ in 0..2000 {
            let q = DVec3::new(rng.unit() * 30.0 - 15.0, rng.unit() * 30.0 - 15.0, rng.unit() * 30.0 - 10.0);
            let brute = (0..=20000)
                .map(|k| {
                    let s = k as f64 / 20000.0;
                    q.distance(a + s * f.length_mm * axis) - f.radius_at(s)
                })
                .fold(f64::INFINITY, f64::min);
            let (d, _, _) = cone.distance(q, tip, axis);
            assert!((d - brute).abs() < 1e-6 && d <= brute + 1e-12, "{d} vs {brute}");
        }
    }

    #[test]
    fn brent_finds_a_smooth_minimum() {
        let (x, fx) = brent(|t| (t - 0.3141).powi(2) + 2.0, 0.0, 1.0, 1e-10);
        assert!((x - 0.3141).abs() < 1e-8 && (fx - 2.0).abs() < 1e-15);
        let (x, _) = brent(|t| t, 0.0, 1.0, 1e-10);
        assert!(x < 1e-8, "{x}");
    }

    #[test]
    fn a_translated_cone_touches_a_plane_all_along() {
        // Tip sphere on z = 0, axis in the XZ plane tilted so the flank lies on the plane.
        let f = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 2.0, flute_length_mm: 10.0 }.spheres().unwrap();
        let cone = RoundCone::new(&f);
        let axis = DVec3::new(f.cos_alpha, 0.0, f.sin_alpha);
        let a0 = DVec3::new(0.0, 0.0, f.r1_mm);
        let pose = |y: f64| {
            let tip = f.tip(a0 + DVec3::new(0.0, y, 0.0), axis);
            let (angles, _) = controller_poses(&[tip], &[axis]);
            angles[0]
        };
        let (p0, p1) = (pose(0.0), pose(5.0));
        for k in 0..=10 {
            let q = DVec3::new(f.contact_length_mm * k as f64 / 10.0, 2.5, 0.0);
            let ap = closest(&cone, q, &p0, &p1);
            assert!(ap.distance.abs() < 1e-12, "{ap:?}");
            // The tool's outward normal (towards the plane), to the precision a flat minimum in τ
            // allows (√ε).
            assert!(ap.normal.distance(-DVec3::Z) < 1e-6, "{k}: {ap:?}");
            assert!((ap.tau - 0.5).abs() < 1e-6, "{k}: {ap:?}");
        }
    }
}
