//! The scallop-uniformity energy E^S of a pole (seed 000 eqs. 15–18, App. C eq. C-5) and its
//! closed-form minimum over the monotone radius function f (DESIGN.md "origin").

use super::{OriginError, OriginOptions};
use crate::mesh::{FaceCurvature, Surface};
use crate::num;
use crate::slitmap::{Mode, SlitMap, SlitMapSolver};
use glam::{DVec2, DVec3};
use serde::Serialize;

/// E_min of one pole and what it is made of.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Energy {
    /// min over f of E^S (seed eq. 18), mm²: Σ over radius bins of 2·sqrt(Σα·Σβ).
    pub e_min: f64,
    /// `e_min / (2 · energy area)`, ≥ 1 (Cauchy–Schwarz); 1 = perfectly uniform predicted scallop.
    /// The energy area is the surface area minus the gouge-risk faces.
    pub uniformity: f64,
    /// Area of the faces where κ_n + 1/R ≤ 0 along ∇|w| (the ball cannot fit the concave
    /// curvature): excluded from the energy, mm².
    pub gouge_risk_area_mm2: f64,
    /// Number of those faces.
    pub gouge_faces: usize,
    /// Optimal slope f′ per radius bin (bin j covers `R_min + (1 − R_min)·[j, j+1]/bins`); 0 for
    /// a bin no face reaches.
    pub slopes: Vec<f64>,
    pub mode: Mode,
    /// Faces the slit map folds over (P1 cannot resolve the map there, see
    /// [`SlitMap::flipped_faces`]): a pole with fewer wins before E_min is compared.
    pub flipped: usize,
}

impl Energy {
    /// Whether this pole is better than one with energy `other`: fewer folded faces, then a
    /// smaller E_min.
    pub fn better_than(&self, other: &Energy) -> bool {
        (self.flipped, self.e_min) < (other.flipped, other.e_min)
    }
}

/// Per-face precomputations of the energy (3D gradient operators, areas, curvature tensors), so
/// that one evaluation after the slit map is a single O(faces) pass.
///
/// ∇r on a face: direction radial, Re(w̄ ∇w)/|w| at the face centre, length the conformal scale
/// |F′| = sqrt((|∇Re w|² + |∇Im w|²)/2), both from the P1 gradient of w. For a conformal map
/// |∇|w|| = |F′| exactly; computing it this way instead of as the P1 gradient of |w| matters in
/// two places where the latter nearly vanishes by accident and made E_min jump by tens of
/// percents between nearby poles: the pole face (|w| has a cone there, its corners can be about
/// equally far from the pole) and the sliver faces at slit tips (the boundary folds onto the arc
/// there, and the P1 Jacobian of w is nearly singular in the radial direction).
#[derive(Debug, Clone)]
pub struct EnergyEvaluator<'a> {
    solver: &'a SlitMapSolver,
    triangles: &'a [[u32; 3]],
    curvature: &'a [FaceCurvature],
    n_vertices: usize,
    /// Faces in the energy: (face, gradient operators ∇φ_k of its corners, area).
    faces: Vec<(u32, [DVec3; 3], f64)>,
    tool_curvature: f64,
    bins: usize,
}

impl<'a> EnergyEvaluator<'a> {
    /// Precomputes the per-face data of `surface` for maps made by `solver` (which must be built
    /// on the flattening of `surface`: same vertices and triangles).
    pub fn new(surface: &'a Surface, solver: &'a SlitMapSolver, options: &OriginOptions) -> Result<Self, OriginError> {
        super::check_energy_options(options)?;
        if surface.curvature.len() != surface.triangles.len() {
            return Err(OriginError::SurfaceMismatch {
                what: format!(
                    "{} curvature tensors for {} triangles",
                    surface.curvature.len(),
                    surface.triangles.len()
                ),
            });
        }
        let n = surface.positions.len();
        let mut faces = Vec::with_capacity(surface.triangles.len());
        for (f, t) in surface.triangles.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= n) {
                return Err(OriginError::SurfaceMismatch {
                    what: format!("triangle {f} refers to vertex {} of {n}", t.iter().max().unwrap_or(&0)),
                });
            }
            let p = t.map(|v| surface.positions[v as usize]);
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let c2 = cross.length_squared();
            if !(c2 > 0.0 && c2.is_finite()) {
                // A zero-area face carries no energy (the mesh stage drops them anyway).
                continue;
            }
            // ∇φ_k = n̂ × e_k / (2A) with e_k the edge opposite corner k (counter-clockwise).
            let grad = [0, 1, 2].map(|k| cross.cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / c2);
            faces.push((f as u32, grad, 0.5 * c2.sqrt()));
        }
        Ok(Self {
            solver,
            triangles: &surface.triangles,
            curvature: &surface.curvature,
            n_vertices: n,
            faces,
            tool_curvature: 1.0 / options.radius_mm,
            bins: options.bins,
        })
    }

    /// The solver the poles are mapped with.
    pub fn solver(&self) -> &'a SlitMapSolver {
        self.solver
    }

    /// E_min of `pole`: `solver.map(pole)` then [`EnergyEvaluator::evaluate_map`].
    pub fn evaluate(&self, pole: DVec2) -> Result<Energy, OriginError> {
        Ok(self.evaluate_with_map(pole)?.0)
    }

    /// [`EnergyEvaluator::evaluate`], and the slit map it was evaluated on.
    pub fn evaluate_with_map(&self, pole: DVec2) -> Result<(Energy, SlitMap), OriginError> {
        let map = self.solver.map(pole)?;
        Ok((self.evaluate_map(&map)?, map))
    }

    /// E_min of a slit map (seed eq. 18 by the closed form per radius bin): one pass over the
    /// faces, one bins-sized buffer.
    pub fn evaluate_map(&self, map: &SlitMap) -> Result<Energy, OriginError> {
        self.check_map(map)?;
        let (r_min, width) = self.bin_frame(map.mode);
        // Per bin: Σ w·A·α, Σ w·A·β.
        let mut acc = vec![[0.0f64; 2]; self.bins];
        let mut gouge_area = 0.0;
        let mut gouge_faces = 0;
        let mut area = 0.0;
        let radius = radii(map);
        for &(f, grad, a) in &self.faces {
            let Some((alpha, beta)) = self.face_terms(map, f, &grad)? else {
                gouge_area += a;
                gouge_faces += 1;
                continue;
            };
            area += a;
            let (aa, ab) = (a * alpha, a * beta);
            self.split(&radius, f, r_min, width, |j, w| {
                acc[j][0] += w * aa;
                acc[j][1] += w * ab;
            });
        }
        if area <= 0.0 {
            return Err(OriginError::AllGougeRisk {
                faces: self.faces.len(),
                radius_mm: 1.0 / self.tool_curvature,
                pole: map.pole,
            });
        }
        let mut e_min = 0.0;
        let slopes = acc
            .iter()
            .map(|&[sa, sb]| {
                if sa > 0.0 && sb > 0.0 {
                    e_min += 2.0 * (sa * sb).sqrt();
                    // s² = sqrt(Σα / Σβ) minimises Σα/s² + Σβ·s².
                    (sa / sb).sqrt().sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        if !e_min.is_finite() {
            return Err(OriginError::NotFinite { pole: map.pole, face: None });
        }
        Ok(Energy {
            e_min,
            uniformity: e_min / (2.0 * area),
            gouge_risk_area_mm2: gouge_area,
            gouge_faces,
            slopes,
            mode: map.mode,
            flipped: map.flipped_triangles(),
        })
    }

    /// The discrete E^S of seed eq. C-5 for given slopes of f per radius bin (same bins, same
    /// area split and gouge exclusion as [`EnergyEvaluator::evaluate_map`]), for cross-checks of
    /// the closed form: its minimum over `slopes` is `evaluate_map(map).e_min`.
    pub fn energy_for_slopes(&self, map: &SlitMap, slopes: &[f64]) -> Result<f64, OriginError> {
        self.check_map(map)?;
        if slopes.len() != self.bins {
            return Err(OriginError::InvalidOption(format!("{} slopes given for {} bins", slopes.len(), self.bins)));
        }
        let (r_min, width) = self.bin_frame(map.mode);
        let mut e = 0.0;
        let radius = radii(map);
        for &(f, grad, a) in &self.faces {
            if let Some((alpha, beta)) = self.face_terms(map, f, &grad)? {
                self.split(&radius, f, r_min, width, |j, w| {
                    let s2 = slopes[j] * slopes[j];
                    e += w * a * (alpha / s2 + beta * s2);
                });
            }
        }
        Ok(e)
    }

    fn check_map(&self, map: &SlitMap) -> Result<(), OriginError> {
        if map.w.len() != self.n_vertices || map.triangles().len() != self.triangles.len() {
            return Err(OriginError::SurfaceMismatch {
                what: format!(
                    "the slit map has {} vertices and {} triangles, the surface {} and {}",
                    map.w.len(),
                    map.triangles().len(),
                    self.n_vertices,
                    self.triangles.len()
                ),
            });
        }
        Ok(())
    }

    /// Lower radius R_min and bin width of the bins over [R_min, 1].
    fn bin_frame(&self, mode: Mode) -> (f64, f64) {
        let r_min = mode.inner_radius();
        (r_min, (1.0 - r_min) / self.bins as f64)
    }

    /// (α_F, β_F) of face `f`, or None when κ_n + 1/R ≤ 0 (gouge risk).
    fn face_terms(&self, map: &SlitMap, f: u32, grad: &[DVec3; 3]) -> Result<Option<(f64, f64)>, OriginError> {
        let t = self.triangles[f as usize];
        let w = t.map(|v| map.w[v as usize]);
        // The direction of ∇r is radial, Re(w̄ ∇w)/|w| at the face centre; its length is the
        // conformal scale |F′| = sqrt((|∇Re w|² + |∇Im w|²)/2) of the P1 gradient of w (see the
        // type's docs for why not the P1 gradient of |w|).
        let d_re = grad[0] * w[0].x + grad[1] * w[1].x + grad[2] * w[2].x;
        let d_im = grad[0] * w[0].y + grad[1] * w[1].y + grad[2] * w[2].y;
        let g2 = 0.5 * (d_re.length_squared() + d_im.length_squared());
        let wc = (w[0] + w[1] + w[2]) / 3.0;
        let radial = d_re * wc.x + d_im * wc.y;
        // The pole exactly at the face centre's image (or a degenerate image): any direction.
        let g = if radial.length_squared() > 0.0 { radial } else { d_re };
        let kc = self.curvature[f as usize].normal_curvature(g) + self.tool_curvature;
        if !(g2 > 0.0 && g2.is_finite() && kc.is_finite()) {
            return Err(OriginError::NotFinite { pole: map.pole, face: Some(f as usize) });
        }
        if kc <= 0.0 {
            return Ok(None);
        }
        Ok(Some((kc / (8.0 * g2), 8.0 * g2 / kc)))
    }

    /// Calls `add(bin, weight)` for the bins the radius range of face `f` overlaps, the weights
    /// proportional to the overlap (summing to 1), so E_min is continuous in the pole. `radius`
    /// is |w| per vertex ([`radii`]).
    fn split(&self, radius: &[f64], f: u32, r_min: f64, width: f64, mut add: impl FnMut(usize, f64)) {
        let t = self.triangles[f as usize];
        let r = t.map(|v| radius[v as usize]);
        // In bin units, clamped to [0, bins] (|w| may overshoot 1 by the P1 error).
        let top = self.bins as f64;
        let x = |r: f64| ((r - r_min) / width).clamp(0.0, top);
        let lo = x(num::min(num::min(r[0], r[1]), r[2]));
        let hi = x(num::max(num::max(r[0], r[1]), r[2]));
        let last = self.bins - 1;
        // lo and hi are in [0, bins]: truncation is their floor, without a libm call.
        let j0 = (lo as usize).min(last);
        if hi <= lo {
            add(j0, 1.0);
            return;
        }
        let j1 = (hi as usize).min(last);
        let span = hi - lo;
        for j in j0..=j1 {
            let overlap = num::min(hi, (j + 1) as f64) - num::max(lo, j as f64);
            if overlap > 0.0 {
                add(j, overlap / span);
            }
        }
    }
}

/// |w| per vertex of `map`: each is needed by every face round the vertex.
fn radii(map: &SlitMap) -> Vec<f64> {
    map.w.iter().map(|w| w.length()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flatten::{self, FlattenInput, FlattenOptions};
    use crate::mesh::{self, MeshOptions};
    use crate::slitmap::{PlanarDomain, SlitMapOptions};

    fn planar(mesh: &crate::mesh::TriMesh) -> (Surface, PlanarDomain) {
        let surface = mesh::from_triangles(mesh, &MeshOptions::default()).unwrap().surface;
        // A flat part is its own flattening up to a similarity: use the xy coordinates directly.
        let uv = surface.positions.iter().map(|p| p.truncate()).collect();
        let domain = PlanarDomain::of_surface(&surface, uv);
        (surface, domain)
    }

    #[test]
    fn flat_disk_with_central_pole_is_nearly_uniform() {
        // r ≈ |z| on the unit disk: |∇r| = 1 and κ = 0, so α = 1/(8R) and β = 8R on every face
        // and the closed form gives 2·area (uniformity 1), up to the P1 error of the map.
        let (surface, domain) = planar(&crate::fixtures::unit_disk(16));
        let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
        let options = OriginOptions { radius_mm: 2.0, bins: 8, ..Default::default() };
        let ev = EnergyEvaluator::new(&surface, &solver, &options).unwrap();
        let e = ev.evaluate(DVec2::new(1e-3, 2e-3)).unwrap();
        assert_eq!(e.mode, Mode::Disk);
        assert_eq!(e.gouge_faces, 0);
        assert!(e.uniformity >= 1.0 - 1e-12 && e.uniformity < 1.01, "{}", e.uniformity);
        // Optimal s² = sqrt(α/β) = 1/(8R) = 1/16 where |∇r| = 1: s = 1/4.
        for (j, s) in e.slopes.iter().enumerate().skip(1) {
            assert!((s - 0.25).abs() < 0.01, "bin {j}: slope {s}");
        }
        assert!((e.e_min - 2.0 * surface.area() * e.uniformity).abs() < 1e-9 * e.e_min);
    }

    #[test]
    fn bin_weights_sum_to_one_and_follow_the_overlap() {
        let (surface, domain) = planar(&crate::fixtures::unit_disk(6));
        let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
        let options = OriginOptions { bins: 5, ..Default::default() };
        let ev = EnergyEvaluator::new(&surface, &solver, &options).unwrap();
        let map = solver.map(DVec2::new(0.1, -0.2)).unwrap();
        let radius = radii(&map);
        for &(f, _, _) in &ev.faces {
            let mut total = 0.0;
            let mut seen = Vec::new();
            ev.split(&radius, f, 0.0, 0.2, |j, w| {
                assert!(w > 0.0 && w <= 1.0);
                total += w;
                seen.push(j);
            });
            assert!((total - 1.0).abs() < 1e-12, "face {f}: {total}");
            assert!(seen.windows(2).all(|p| p[1] == p[0] + 1), "contiguous bins {seen:?}");
        }
    }

    #[test]
    fn energy_scales_with_the_part() {
        // Scaling part and ball by λ multiplies α by λ and divides β by λ: E_min by λ², the
        // uniformity and the slopes² ∝ λ are unchanged up to that factor.
        let m = crate::fixtures::spherical_cap_hole();
        let run = |scale: f64| {
            let mut m = m.clone();
            m.positions.iter_mut().for_each(|p| *p *= scale);
            let surface = mesh::from_triangles(&m, &MeshOptions::default()).unwrap().surface;
            let flat = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default()).unwrap();
            let domain = PlanarDomain::of_surface(&surface, flat.uv);
            let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
            let options = OriginOptions { radius_mm: 3.0 * scale, ..Default::default() };
            let ev = EnergyEvaluator::new(&surface, &solver, &options).unwrap();
            ev.evaluate(domain.largest_face_centre()).unwrap()
        };
        let (a, b) = (run(1.0), run(2.5));
        assert!((b.e_min / a.e_min - 6.25).abs() < 1e-6 * 6.25, "{} {}", a.e_min, b.e_min);
        assert!((b.uniformity - a.uniformity).abs() < 1e-6);
    }
}
