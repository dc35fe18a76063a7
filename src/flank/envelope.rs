//! The envelope of the moving tool (seed 002 eqs. 5–6): contact curves per pose.
//!
//! The tool's axis sweeps the ruled surface y(s, t) = (1 − s)a(t) + s b(t) (eq. 3); its spheres
//! of radius r(s) envelope the surface x± = y − r n± (eq. 5) with
//!
//! ```text
//! n± = [Δr (G y_s − F y_t) ± (y_s × y_t) √((E − Δr²)G − F²)] / (EG − F²),        (eq. 6)
//! ```
//!
//! E, F, G the first fundamental form of y (E = y_s·y_s, F = y_s·y_t, G = y_t·y_t). n± is the
//! unit vector with ⟨n, y_s⟩ = Δr = r_s and ⟨n, y_t⟩ = 0 = r_t: the envelope conditions of the
//! sphere family. It is real where (E − Δr²)G ≥ F² (the *real-envelope condition*: the axis
//! must not move too much along itself); where it fails the sphere at that s does not touch the
//! envelope at that instant. Of the two branches the one nearer the surface is the one that
//! cuts it (the seed keeps "the correct branch"); the caller gives the distance to measure
//! nearness with. At a fixed t, x(s) for s ∈ [0, 1] is the characteristic curve: where the tool
//! touches the envelope (the contact curve), generally not a straight line.
//!
//! The formula is invariant under any reparametrisation of t (also reversing it, which swaps
//! the branches): y_t comes from differences of consecutive poses (central inside a strip,
//! one-sided at its ends).

use super::tool::SphereFamily;
use glam::DVec3;

/// The two unit envelope normals n+ and n− of eq. 6, or None where the envelope is not real
/// (or the motion is degenerate: y_t parallel to y_s or zero).
pub fn envelope_normals(ys: DVec3, yt: DVec3, delta_r: f64) -> Option<[DVec3; 2]> {
    let (e, f, g) = (ys.dot(ys), ys.dot(yt), yt.dot(yt));
    let det = e * g - f * f;
    let disc = (e - delta_r * delta_r) * g - f * f;
    if !(det > 1e-300 * (e * g).max(1e-300)) || !(disc >= 0.0) {
        return None;
    }
    let first = delta_r * (g * ys - f * yt);
    let second = ys.cross(yt) * disc.sqrt();
    Some([(first + second) / det, (first - second) / det])
}

/// One point of a contact curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    pub s: f64,
    /// x = y − r n on the envelope, mm.
    pub point: DVec3,
    /// The envelope's unit normal n (from the envelope towards the axis).
    pub normal: DVec3,
}

/// y_t at pose `j` of a strip's rails (a, b): central differences, one-sided at the ends.
pub fn rail_velocity(rails: &[(DVec3, DVec3)], j: usize) -> (DVec3, DVec3) {
    let last = rails.len() - 1;
    let (lo, hi) = (j.saturating_sub(1), (j + 1).min(last));
    let span = (hi - lo).max(1) as f64;
    ((rails[hi].0 - rails[lo].0) / span, (rails[hi].1 - rails[lo].1) / span)
}

/// The contact curve of pose `j` of a strip, at `k` values of s evenly from 0 to 1: the branch
/// whose point `distance` finds nearer (None where the envelope is not real).
pub fn contact_curve(
    rails: &[(DVec3, DVec3)],
    j: usize,
    family: &SphereFamily,
    k: usize,
    distance: &dyn Fn(DVec3) -> f64,
) -> Vec<Option<ContactPoint>> {
    let (a, b) = rails[j];
    let (da, db) = if rails.len() > 1 { rail_velocity(rails, j) } else { (DVec3::ZERO, DVec3::ZERO) };
    (0..k)
        .map(|i| {
            let s = if k > 1 { i as f64 / (k - 1) as f64 } else { 0.5 };
            contact_point(a, b, da, db, s, family, distance)
        })
        .collect()
}

/// The envelope point at (s, t) of the pose (a, b) moving with rail velocities (da, db).
pub fn contact_point(
    a: DVec3,
    b: DVec3,
    da: DVec3,
    db: DVec3,
    s: f64,
    family: &SphereFamily,
    distance: &dyn Fn(DVec3) -> f64,
) -> Option<ContactPoint> {
    let y = (1.0 - s) * a + s * b;
    let ys = b - a;
    let yt = (1.0 - s) * da + s * db;
    let r = family.radius_at(s);
    let [np, nm] = envelope_normals(ys, yt, family.delta_r_mm)?;
    let (xp, xm) = (y - r * np, y - r * nm);
    let (point, normal) = if distance(xp) <= distance(xm) { (xp, np) } else { (xm, nm) };
    Some(ContactPoint { s, point, normal })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flank::tool::ConeTool;

    #[test]
    fn normals_satisfy_the_envelope_conditions() {
        let ys = DVec3::new(0.3, 9.8, 1.2);
        let yt = DVec3::new(1.0, 0.1, -0.2);
        let dr = 1.1;
        let [p, m] = envelope_normals(ys, yt, dr).unwrap();
        for n in [p, m] {
            assert!((n.length() - 1.0).abs() < 1e-14);
            assert!((n.dot(ys) - dr).abs() < 1e-13);
            assert!(n.dot(yt).abs() < 1e-14);
        }
        // Moving along the axis: no real envelope.
        assert!(envelope_normals(ys, ys * 0.5, dr).is_none());
        assert!(envelope_normals(ys, DVec3::ZERO, dr).is_none());
    }

    /// A cone translated along a plane, tangent to it: the contact curve is the straight
    /// generator on the plane, with the plane's normal.
    #[test]
    fn translating_a_tangent_cone_touches_the_plane_along_a_line() {
        let family = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 2.5, flute_length_mm: 15.0 }.spheres().unwrap();
        let d = family.contact_length_mm;
        let rails: Vec<(DVec3, DVec3)> = (0..5)
            .map(|j| {
                let x = 2.0 * j as f64;
                (DVec3::new(x, 0.0, family.r1_mm), DVec3::new(x, d, family.r2_mm))
            })
            .collect();
        let plane = |p: DVec3| p.z.abs();
        for j in 0..5 {
            for c in contact_curve(&rails, j, &family, 7, &plane) {
                let c = c.unwrap();
                assert!(c.point.z.abs() < 1e-12, "{c:?}");
                assert!(c.normal.distance(DVec3::Z) < 1e-12);
                assert!((c.point.y - c.s * d).abs() < 1e-12);
            }
        }
    }
}
