//! A/C angles of the table-table post.
//!
//! Convention: with A and C in degrees, the tool axis in the part frame is
//! `Rz(C)·Rx(A)·(0, 0, 1) = (sin A·sin C, −sin A·cos C, cos A)` ([`axis_of`]). Every axis has
//! two solutions, (A, C) and (−A, C + 180°), plus C + k·360°; [`ac_angles`] picks, point after
//! point, the one whose C is nearest the previous C (so C never jumps 360° or flips 180° when
//! the axis passes through +Z) and starts with A ≥ 0, C in (−180°, 180°]. Near the singular
//! pose, |A| < [`SINGULAR_DEG`], C is held (the previous value, 0 at the start) and A gets the
//! sign that best matches the axis: the axis error is then below √2·|A| ≤ 2.5e-4 rad.

use super::GcodeError;
use crate::num;
use glam::DVec3;

/// Largest |A| of the machine, degrees.
pub const A_LIMIT_DEG: f64 = 120.0;
/// Below this |A|, degrees, C is held instead of computed (no spinning at the singularity).
pub const SINGULAR_DEG: f64 = 0.01;

/// The tool axis of the angles `a_deg`, `c_deg` (module docs).
pub fn axis_of(a_deg: f64, c_deg: f64) -> DVec3 {
    let (sa, ca) = num::sin_cos(a_deg.to_radians());
    let (sc, cc) = num::sin_cos(c_deg.to_radians());
    DVec3::new(sa * sc, -sa * cc, ca)
}

/// (A, C) in degrees for every unit axis of the sequence, continuous as described in the
/// module docs; [`GcodeError::AOutOfRange`] names the first axis beyond [`A_LIMIT_DEG`].
pub fn ac_angles(axes: &[DVec3]) -> Result<Vec<(f64, f64)>, GcodeError> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(axes.len());
    for (index, axis) in axes.iter().enumerate() {
        let a = num::acos(axis.z.clamp(-1.0, 1.0)).to_degrees();
        if a > A_LIMIT_DEG {
            return Err(GcodeError::AOutOfRange { index, a_deg: a, limit_deg: A_LIMIT_DEG });
        }
        let c = num::atan2(axis.x, -axis.y).to_degrees();
        let prev_c = out.last().map(|&(_, c)| c);
        let pose = if a < SINGULAR_DEG {
            let held = prev_c.unwrap_or(0.0);
            // The (−A, C + 180°) solution is the better match when C is more than 90° away.
            let sign = if a > 0.0 && (nearest_turn(c, held) - held).abs() > 90.0 { -1.0 } else { 1.0 };
            (sign * a, held)
        } else if let Some(prev) = prev_c {
            let c1 = nearest_turn(c, prev);
            let c2 = nearest_turn(c + 180.0, prev);
            if (c1 - prev).abs() <= (c2 - prev).abs() {
                (a, c1)
            } else {
                (-a, c2)
            }
        } else {
            (a, c)
        };
        out.push(pose);
    }
    Ok(out)
}

/// `c` plus the multiple of 360° that brings it nearest `prev`.
fn nearest_turn(c: f64, prev: f64) -> f64 {
    c + 360.0 * ((prev - c) / 360.0).round()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_reproduce_the_axis() {
        for &(a, c) in &[(30.0, 10.0), (89.0, -170.0), (5.0, 179.0), (119.0, 45.0)] {
            let axis = axis_of(a, c);
            let (a2, c2) = ac_angles(&[axis]).unwrap()[0];
            assert!(axis_of(a2, c2).distance(axis) < 1e-12, "({a}, {c}) → ({a2}, {c2})");
            assert!((a2 - a).abs() < 1e-9 && (c2 - c).abs() < 1e-9);
        }
        assert_eq!(axis_of(0.0, 0.0), DVec3::Z);
    }
}
