//! The conical tool as the user knows it, and as seed 002 §4 models it (eqs. 1–2).
//!
//! The user gives a truncated cone: the radius ρ₁ of the flute at the tip, the radius ρ₂ at the
//! top of the flute and the flute length H along the axis (ρ₁ < ρ₂ for a tapered end mill,
//! ρ₁ = ρ₂ for a cylinder; ρ₁ > ρ₂ is accepted too). Its flank has the half-angle α with
//! tan α = (ρ₂ − ρ₁)/H.
//!
//! The seed describes the same flank as the envelope of the spheres centred on the axis segment
//! `l(s) = (1 − s)a + s b` with radii `r(s) = (1 − s)r₁ + s r₂`, s ∈ [0, 1] (eqs. 1–2), L = |b − a|.
//! A sphere centred on the axis is tangent to the cone along a circle; its radius is the
//! distance from its centre to the flank line, ρ(z)·cos α, and it touches the flank a distance
//! r·sin α nearer the tip than its centre. So dr/dz = sin α, and choosing the two end spheres
//! so that they touch the flank exactly at the tip circle and at the top circle ("full
//! engagement", seed 002 §3) gives
//!
//! ```text
//! r₁ = ρ₁ / cos α,   r₂ = ρ₂ / cos α,   Δr = r₂ − r₁ = L·sin α,
//! a = tip + (r₁ sin α)·axis,   L = H + (ρ₂ − ρ₁)·tan α = H + Δr·sin α,
//! d = √(L² − Δr²) = L·cos α = √(H² + (ρ₂ − ρ₁)²)   (the slant length of the flute),
//! ```
//!
//! where `tip` is the centre of the tip circle (the point a controller programs) and `axis` the
//! unit axis towards the shank. d is the contact length, the width of one strip on a plane
//! (seed 002 §5). [`SphereFamily::cone`] is the inverse, for tools given as the seed's tables
//! give them (L, r₁, r₂).
//!
//! Preconditions: finite ρ₁ > 0, ρ₂ > 0, H > 0 (each fault is a [`FlankError::InvalidTool`]).

use super::FlankError;
use glam::DVec3;
use serde::Serialize;

/// A truncated cone (flat tip), millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ConeTool {
    /// Radius of the flute at the tip, ρ₁, mm.
    pub tip_radius_mm: f64,
    /// Radius of the flute at its top (towards the shank), ρ₂, mm.
    pub top_radius_mm: f64,
    /// Length of the flute along the axis, H, mm.
    pub flute_length_mm: f64,
}

impl Default for ConeTool {
    /// A 3°-ish tapered end mill: tip radius 1.5 mm, top radius 2.5 mm, flute 20 mm.
    fn default() -> Self {
        ConeTool { tip_radius_mm: 1.5, top_radius_mm: 2.5, flute_length_mm: 20.0 }
    }
}

/// The seed's description of the tool: spheres of radius r₁ … r₂ along an axis segment of
/// length L (eqs. 1–2), and where they sit on the real tool.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SphereFamily {
    /// Radius of the sphere at the tool's tip end, r₁, mm.
    pub r1_mm: f64,
    /// Radius of the sphere at the shank end, r₂, mm.
    pub r2_mm: f64,
    /// Distance between the two sphere centres, L, mm.
    pub length_mm: f64,
    /// Δr = r₂ − r₁, mm.
    pub delta_r_mm: f64,
    /// sin α and cos α of the flank's half-angle α.
    pub sin_alpha: f64,
    pub cos_alpha: f64,
    /// Distance along the axis from the tip plane to the centre a, r₁·sin α, mm.
    pub tip_offset_mm: f64,
    /// Contact length d = √(L² − Δr²), the flute's slant length, mm.
    pub contact_length_mm: f64,
}

impl ConeTool {
    /// The tool's sphere family (module docs), or [`FlankError::InvalidTool`].
    pub fn spheres(&self) -> Result<SphereFamily, FlankError> {
        for (field, value) in [
            ("tip_radius_mm", self.tip_radius_mm),
            ("top_radius_mm", self.top_radius_mm),
            ("flute_length_mm", self.flute_length_mm),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(FlankError::InvalidTool { field, value, expected: "a finite number > 0" });
            }
        }
        let (rho1, rho2, h) = (self.tip_radius_mm, self.top_radius_mm, self.flute_length_mm);
        let slant = (h * h + (rho2 - rho1) * (rho2 - rho1)).sqrt();
        let (sin_alpha, cos_alpha) = ((rho2 - rho1) / slant, h / slant);
        let (r1, r2) = (rho1 / cos_alpha, rho2 / cos_alpha);
        let delta_r = r2 - r1;
        let length = h + delta_r * sin_alpha;
        Ok(SphereFamily {
            r1_mm: r1,
            r2_mm: r2,
            length_mm: length,
            delta_r_mm: delta_r,
            sin_alpha,
            cos_alpha,
            tip_offset_mm: r1 * sin_alpha,
            contact_length_mm: slant,
        })
    }

    /// The part of this tool's flute from `from` to `to` (fractions of the flute length from
    /// the tip, 0 ≤ from < to ≤ 1): the same cone engaged over a shorter length (seed 002
    /// Fig. 18 engages the upper half: `part(0.5, 1.0)`).
    pub fn part(&self, from: f64, to: f64) -> ConeTool {
        let at = |f: f64| self.tip_radius_mm + f * (self.top_radius_mm - self.tip_radius_mm);
        ConeTool { tip_radius_mm: at(from), top_radius_mm: at(to), flute_length_mm: (to - from) * self.flute_length_mm }
    }
}

impl SphereFamily {
    /// The cone whose sphere family has radii r₁, r₂ and length L (the seed's Table 1 gives
    /// tools so), or [`FlankError::InvalidTool`] unless r₁, r₂ > 0 and |r₂ − r₁| < L.
    pub fn cone(r1_mm: f64, r2_mm: f64, length_mm: f64) -> Result<ConeTool, FlankError> {
        for (field, value) in [("r1_mm", r1_mm), ("r2_mm", r2_mm), ("length_mm", length_mm)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(FlankError::InvalidTool { field, value, expected: "a finite number > 0" });
            }
        }
        let delta_r = r2_mm - r1_mm;
        if !(delta_r.abs() < length_mm) {
            return Err(FlankError::InvalidTool {
                field: "length_mm",
                value: length_mm,
                expected: "a length greater than |r2 − r1|",
            });
        }
        let sin_alpha = delta_r / length_mm;
        let cos_alpha = (1.0 - sin_alpha * sin_alpha).sqrt();
        Ok(ConeTool {
            tip_radius_mm: r1_mm * cos_alpha,
            top_radius_mm: r2_mm * cos_alpha,
            flute_length_mm: length_mm - delta_r * sin_alpha,
        })
    }

    /// r(s) of eq. 2.
    #[inline]
    pub fn radius_at(&self, s: f64) -> f64 {
        (1.0 - s) * self.r1_mm + s * self.r2_mm
    }

    /// The tool tip (centre of the tip circle) of the pose with tip-end sphere centre `a` and
    /// unit axis `axis` (towards the shank).
    #[inline]
    pub fn tip(&self, a: DVec3, axis: DVec3) -> DVec3 {
        a - self.tip_offset_mm * axis
    }

    /// The tip-end sphere centre a of the pose with tool tip `tip` and unit axis `axis`.
    #[inline]
    pub fn a_of_tip(&self, tip: DVec3, axis: DVec3) -> DVec3 {
        tip + self.tip_offset_mm * axis
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The envelope of the spheres is the cone: every sphere of the family touches the flank
    /// line ρ(z) = ρ₁ + z tan α (in a meridian plane) and stays inside it; the end spheres touch
    /// it at the tip and at the top of the flute.
    #[test]
    fn spheres_are_inscribed_and_touch_the_flute_ends() {
        for tool in [
            ConeTool { tip_radius_mm: 1.5, top_radius_mm: 2.5, flute_length_mm: 20.0 },
            ConeTool { tip_radius_mm: 3.0, top_radius_mm: 3.0, flute_length_mm: 12.0 },
            ConeTool { tip_radius_mm: 4.0, top_radius_mm: 1.0, flute_length_mm: 9.0 },
        ] {
            let f = tool.spheres().unwrap();
            let tan = (tool.top_radius_mm - tool.tip_radius_mm) / tool.flute_length_mm;
            // Flank line through (z, ρ) = (0, ρ₁) with direction (cos α, sin α); distance of an
            // axis point (z_c, 0) to it is the inscribed radius.
            let (dir, p0) = (glam::DVec2::new(f.cos_alpha, f.sin_alpha), glam::DVec2::new(0.0, tool.tip_radius_mm));
            for k in 0..=10 {
                let s = k as f64 / 10.0;
                let zc = f.tip_offset_mm + s * f.length_mm;
                let w = glam::DVec2::new(zc, 0.0) - p0;
                let dist = (w - w.dot(dir) * dir).length();
                assert!((dist - f.radius_at(s)).abs() < 1e-12, "s = {s}: {dist} vs {}", f.radius_at(s));
                // The touching point: the foot of the perpendicular.
                let touch = p0 + w.dot(dir) * dir;
                if k == 0 {
                    assert!(touch.distance(p0) < 1e-12, "the tip sphere touches at the tip circle");
                }
                if k == 10 {
                    let top = glam::DVec2::new(tool.flute_length_mm, tool.tip_radius_mm + tan * tool.flute_length_mm);
                    assert!(touch.distance(top) < 1e-12, "the top sphere touches at the top circle");
                }
            }
            assert!((f.contact_length_mm - (f.length_mm.powi(2) - f.delta_r_mm.powi(2)).sqrt()).abs() < 1e-12);
            let back = SphereFamily::cone(f.r1_mm, f.r2_mm, f.length_mm).unwrap();
            for (x, y) in [
                (back.tip_radius_mm, tool.tip_radius_mm),
                (back.top_radius_mm, tool.top_radius_mm),
                (back.flute_length_mm, tool.flute_length_mm),
            ] {
                assert!((x - y).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn seed_figure_17_tool_and_bad_tools() {
        let tool = SphereFamily::cone(3.0, 10.0, 23.85).unwrap();
        let f = tool.spheres().unwrap();
        assert!((f.length_mm - 23.85).abs() < 1e-12 && (f.r1_mm - 3.0).abs() < 1e-12 && (f.r2_mm - 10.0).abs() < 1e-12);
        assert!((f.contact_length_mm - (23.85f64 * 23.85 - 49.0).sqrt()).abs() < 1e-12);
        assert!(matches!(
            ConeTool { tip_radius_mm: f64::NAN, ..ConeTool::default() }.spheres(),
            Err(FlankError::InvalidTool { field: "tip_radius_mm", .. })
        ));
        assert!(matches!(
            ConeTool { flute_length_mm: 0.0, ..ConeTool::default() }.spheres(),
            Err(FlankError::InvalidTool { field: "flute_length_mm", .. })
        ));
        assert!(SphereFamily::cone(1.0, 9.0, 8.0).is_err());
        // The upper half of a cone: same angle, half the length.
        let half = ConeTool::default().part(0.5, 1.0).spheres().unwrap();
        let full = ConeTool::default().spheres().unwrap();
        assert!((half.length_mm - full.length_mm / 2.0).abs() < 1e-12);
        assert!((half.sin_alpha - full.sin_alpha).abs() < 1e-15);
    }
}
