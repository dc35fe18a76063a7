//! The objective F = w₁F_rigid + w₂F_approx + w₃F_G1 + w₄F_ini + w₅F_fair of seed 002 (eqs.
//! 12–18) and its analytic gradient, with the normals and footpoints frozen (the optimiser
//! refreshes them between solves, [`super::optimise`]).
//!
//! With the normals n_{i,j} frozen, the rails a = m_{i,j} − (Δr/2)n_{i,j}, b = m_{i+1,j} +
//! (Δr/2)n_{i+1,j} are affine in the grid points, and so are the axis samples y^k (eq. 11). The
//! terms, over the P poses, P·K axis samples, B strip-boundary pairs, G grid points and T
//! consecutive triples of a row:
//!
//! ```text
//! F_rigid  = 1/P      Σ (|b − a|² − L²)²                                     (eq. 12)
//! F_approx = 1/(3PK)  Σ (⟨y^k − y^k⊥, n^k⟩ − r^k)²                           (eq. 13)
//! F_fair   = 1/(3T)   Σ |m_{i,j+1} − 2m_{i,j} + m_{i,j−1}|²                  (eq. 14)
//! F_G1     = 1/B      Σ (cos θ¹ − cos θ²)²,  cos θ = ⟨n_{i+1,j}, b − a⟩/|b − a|   (eqs. 15–16)
//! F_ini    = 1/(3G)   Σ |m_{i,j} − m^ini_{i,j}|²                             (eq. 17)
//! ```
//!
//! where y^k⊥ (the footpoint of y^k on the surface) and n^k (the surface's interpolated normal
//! there) are frozen, so ⟨y − y⊥, n⟩ is the height of y over the footpoint's tangent plane.
//!
//! Decisions where the seed is silent or inconsistent:
//! - Lengths are in millimetres, as in the seed, so its weights mean here what they mean in its
//!   examples. Their balance depends on the scale (F_rigid grows with L⁴, F_approx with the
//!   error², F_G1 is an angle): the seed tuned them per example (w₂ = 10⁻⁴ on a gear flank with
//!   L = 2.7 mm, 0.005 on Fig. 17 with L = 23.85 mm). Dividing every length by L would have
//!   made one set of weights mean the same at every scale, but then the seed's presets would
//!   not reproduce its examples (at L = 20 mm G¹ outweighed accuracy 400 times more than the
//!   seed's own figures show).
//! - Eq. 17's sum runs over i = 1 … M while its normaliser counts M + 1 rows: every grid point
//!   is counted here (the boundary rows too).
//! - With ragged strips (Remark 3) the normalisers count the terms that exist.
//!
//! Layout of the unknowns: grid point g is `x[3g..3g + 3]` ([`super::rails::Grid`] order).

use super::rails::{Grid, Pose};
use glam::DVec3;
use serde::Serialize;

/// The weights of eq. 18.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Weights {
    pub rigid: f64,
    pub approx: f64,
    pub g1: f64,
    pub ini: f64,
    pub fair: f64,
}

/// The value of each term (unweighted) and of F.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Terms {
    pub rigid: f64,
    pub approx: f64,
    pub g1: f64,
    pub ini: f64,
    pub fair: f64,
    /// The optimiser's proximal term (not part of eq. 18; 0 unless set, [`Objective::prox`]).
    pub prox: f64,
    pub total: f64,
}

/// One frozen axis sample: pose `pose`, parameter s, radius r, the footpoint's normal n and
/// ⟨footpoint, n⟩.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footpoint {
    pub pose: u32,
    pub s: f64,
    pub r: f64,
    pub normal: DVec3,
    pub offset: f64,
}

/// A strip boundary pair of eq. 16: pose of strip i and of strip i + 1 at the same j; both read
/// the normal of their shared grid point `shared` (= first pose's `upper`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seam {
    pub below: u32,
    pub above: u32,
    pub shared: u32,
}

/// Everything the objective reads besides the unknowns.
#[derive(Clone, Debug)]
pub struct Objective<'a> {
    pub grid: &'a Grid,
    pub normals: Vec<DVec3>,
    pub footpoints: Vec<Footpoint>,
    pub m_ini: Vec<DVec3>,
    pub seams: Vec<Seam>,
    /// Consecutive triples (grid indices) of every row, for F_fair.
    pub triples: Vec<[u32; 3]>,
    pub weights: Weights,
    /// A proximal term μ/(3G) Σ |m − c|² with (μ, c): the outer loop's damping
    /// ([`super::optimise`]); None outside it.
    pub prox: Option<(f64, Vec<DVec3>)>,
}

impl<'a> Objective<'a> {
    /// The seams and triples of `grid`, with the given frozen data.
    pub fn new(
        grid: &'a Grid,
        normals: Vec<DVec3>,
        footpoints: Vec<Footpoint>,
        m_ini: Vec<DVec3>,
        weights: Weights,
    ) -> Self {
        let mut seams = Vec::new();
        for i in 0..grid.strips().saturating_sub(1) {
            let above = grid.strip(i + 1);
            for (k, p) in grid.strip(i).iter().enumerate() {
                if let Ok(q) = above.binary_search_by_key(&p.j, |q| q.j) {
                    seams.push(Seam {
                        below: (grid.strip_start[i] + k) as u32,
                        above: (grid.strip_start[i + 1] + q) as u32,
                        shared: p.upper as u32,
                    });
                }
            }
        }
        let mut triples = Vec::new();
        for r in &grid.rows {
            for k in 1..r.len.saturating_sub(1) {
                let g = (r.offset + k) as u32;
                triples.push([g - 1, g, g + 1]);
            }
        }
        Objective { grid, normals, footpoints, m_ini, seams, triples, weights, prox: None }
    }

    fn rails(&self, pose: &Pose, x: &[f64]) -> (DVec3, DVec3) {
        let h = 0.5 * self.grid.family.delta_r_mm;
        (point(x, pose.lower) - h * self.normals[pose.lower], point(x, pose.upper) + h * self.normals[pose.upper])
    }

    /// F at `x`, its terms, and (when `grad` is given) its gradient written into `grad`.
    pub fn evaluate(&self, x: &[f64], mut grad: Option<&mut [f64]>) -> Terms {
        if let Some(g) = grad.as_deref_mut() {
            g.iter_mut().for_each(|v| *v = 0.0);
        }
        let l = self.grid.family.length_mm;
        let (l2, w) = (l * l, self.weights);
        let poses = &self.grid.poses;
        let mut t = Terms::default();
        let add = |grad: &mut Option<&mut [f64]>, g: usize, v: DVec3| {
            if let Some(gr) = grad.as_deref_mut() {
                gr[3 * g] += v.x;
                gr[3 * g + 1] += v.y;
                gr[3 * g + 2] += v.z;
            }
        };

        // Rigidity (eq. 12).
        if !poses.is_empty() {
            let norm = 1.0 / poses.len() as f64;
            for p in poses {
                let (a, b) = self.rails(p, x);
                let u = b - a;
                let c = u.length_squared() - l2;
                t.rigid += c * c;
                let d = (w.rigid * norm * 4.0 * c) * u;
                add(&mut grad, p.upper, d);
                add(&mut grad, p.lower, -d);
            }
            t.rigid *= norm;
        }

        // Approximation (eq. 13).
        if !self.footpoints.is_empty() {
            let norm = 1.0 / (3.0 * self.footpoints.len() as f64);
            for f in &self.footpoints {
                let p = &poses[f.pose as usize];
                let (a, b) = self.rails(p, x);
                let y = (1.0 - f.s) * a + f.s * b;
                let e = y.dot(f.normal) - f.offset - f.r;
                t.approx += e * e;
                let d = (w.approx * norm * 2.0 * e) * f.normal;
                add(&mut grad, p.lower, (1.0 - f.s) * d);
                add(&mut grad, p.upper, f.s * d);
            }
            t.approx *= norm;
        }

        // G¹ continuity (eqs. 15–16).
        if !self.seams.is_empty() {
            let norm = 1.0 / self.seams.len() as f64;
            for s in &self.seams {
                let n = self.normals[s.shared as usize];
                let (p1, p2) = (&poses[s.below as usize], &poses[s.above as usize]);
                let (a1, b1) = self.rails(p1, x);
                let (a2, b2) = self.rails(p2, x);
                let (c1, dc1) = cos_and_gradient(b1 - a1, n);
                let (c2, dc2) = cos_and_gradient(b2 - a2, n);
                let diff = c1 - c2;
                t.g1 += diff * diff;
                let k = w.g1 * norm * 2.0 * diff;
                add(&mut grad, p1.upper, k * dc1);
                add(&mut grad, p1.lower, -k * dc1);
                add(&mut grad, p2.upper, -k * dc2);
                add(&mut grad, p2.lower, k * dc2);
            }
            t.g1 *= norm;
        }

        // Proximity to the initial grid (eq. 17).
        if !self.m_ini.is_empty() {
            let norm = 1.0 / (3.0 * self.m_ini.len() as f64);
            for (g, &m0) in self.m_ini.iter().enumerate() {
                let d = point(x, g) - m0;
                t.ini += d.length_squared();
                add(&mut grad, g, (w.ini * norm * 2.0) * d);
            }
            t.ini *= norm;
        }

        // Fairness along the rows (eq. 14).
        if !self.triples.is_empty() {
            let norm = 1.0 / (3.0 * self.triples.len() as f64);
            for &[p, q, r] in &self.triples {
                let d = point(x, p as usize) - 2.0 * point(x, q as usize) + point(x, r as usize);
                t.fair += d.length_squared();
                let k = (w.fair * norm * 2.0) * d;
                add(&mut grad, p as usize, k);
                add(&mut grad, q as usize, -2.0 * k);
                add(&mut grad, r as usize, k);
            }
            t.fair *= norm;
        }

        if let Some((mu, centre)) = &self.prox {
            let norm = 1.0 / (3.0 * centre.len() as f64);
            for (g, &c) in centre.iter().enumerate() {
                let d = point(x, g) - c;
                t.prox += d.length_squared();
                add(&mut grad, g, (mu * norm * 2.0) * d);
            }
            t.prox *= mu * norm;
        }

        t.total = w.rigid * t.rigid + w.approx * t.approx + w.g1 * t.g1 + w.ini * t.ini + w.fair * t.fair + t.prox;
        t
    }
}

/// Grid point `g` of the unknowns.
#[inline]
pub fn point(x: &[f64], g: usize) -> DVec3 {
    DVec3::new(x[3 * g], x[3 * g + 1], x[3 * g + 2])
}

/// cos θ = ⟨n, u⟩/|u| and its gradient with respect to u, (n − cos θ·û)/|u|.
#[inline]
fn cos_and_gradient(u: DVec3, n: DVec3) -> (f64, DVec3) {
    let len = u.length();
    if !(len > 0.0) {
        return (0.0, DVec3::ZERO);
    }
    let c = n.dot(u) / len;
    (c, (n - c * (u / len)) / len)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flank::guide::{BaseRow, Guides};
    use crate::flank::tool::ConeTool;

    /// A small grid on a bent surface with ragged rows, and arbitrary frozen data.
    fn setup() -> (Grid, Vec<DVec3>, Vec<Footpoint>) {
        let family = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 2.0, flute_length_mm: 8.0 }.spheres().unwrap();
        let row = |first_j: i64, n: usize, y: f64| {
            let points: Vec<DVec3> = (0..n)
                .map(|k| DVec3::new(2.0 * (first_j + k as i64) as f64, y, 0.02 * y * y + 0.1 * k as f64))
                .collect();
            let normals = points.iter().map(|p| DVec3::new(0.05 * p.x, -0.04 * p.y, 1.0).normalize()).collect();
            BaseRow { first_j, points, normals, tangents: vec![DVec3::X; n] }
        };
        let guides = Guides {
            levels: vec![0.0; 4],
            curves: vec![],
            rows: vec![row(0, 6, 0.0), row(-1, 7, 7.5), row(1, 5, 15.2), row(0, 5, 22.0)],
        };
        let grid = Grid::new(&guides, family);
        let mut footpoints = Vec::new();
        for (i, p) in grid.poses.iter().enumerate() {
            for k in 0..4 {
                let s = k as f64 / 3.0;
                let n = DVec3::new(0.1 * k as f64, 0.2, 1.0 + 0.01 * p.j as f64).normalize();
                footpoints.push(Footpoint { pose: i as u32, s, r: family.radius_at(s), normal: n, offset: 0.3 });
            }
        }
        let normals = grid.normals.clone();
        (grid, normals, footpoints)
    }

    /// The analytic gradient of every term agrees with central differences.
    #[test]
    fn gradient_matches_central_differences() {
        let (grid, normals, footpoints) = setup();
        let mut x: Vec<f64> = grid.m.iter().flat_map(|p| p.to_array()).collect();
        // Move off the initial grid so that every term has a gradient.
        for (i, v) in x.iter_mut().enumerate() {
            *v += 0.3 * crate::num::sin(1.7 * i as f64);
        }
        let m_ini = grid.m.clone();
        let unit = Weights { rigid: 0.0, approx: 0.0, g1: 0.0, ini: 0.0, fair: 0.0 };
        for (name, weights) in [
            ("rigid", Weights { rigid: 1.0, ..unit }),
            ("approx", Weights { approx: 1.0, ..unit }),
            ("g1", Weights { g1: 1.0, ..unit }),
            ("ini", Weights { ini: 1.0, ..unit }),
            ("fair", Weights { fair: 1.0, ..unit }),
            ("all", Weights { rigid: 1.0, approx: 0.7, g1: 0.3, ini: 1e-2, fair: 0.2 }),
        ] {
            let obj = Objective::new(&grid, normals.clone(), footpoints.clone(), m_ini.clone(), weights);
            let mut grad = vec![0.0; x.len()];
            let f0 = obj.evaluate(&x, Some(&mut grad)).total;
            assert!(f0 > 0.0, "{name}: the term is not zero here");
            let scale = grad.iter().fold(0.0f64, |m, g| m.max(g.abs()));
            assert!(scale > 0.0, "{name}");
            for i in 0..x.len() {
                let h = 1e-6;
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[i] += h;
                xm[i] -= h;
                let fd = (obj.evaluate(&xp, None).total - obj.evaluate(&xm, None).total) / (2.0 * h);
                assert!((fd - grad[i]).abs() <= 1e-6 * scale, "{name}, unknown {i}: analytic {} vs {fd}", grad[i]);
            }
        }
    }

    #[test]
    fn terms_vanish_on_an_exact_grid() {
        // A plane: rows d apart, normals +Z, footpoints on z = 0.
        let family = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 2.0, flute_length_mm: 8.0 }.spheres().unwrap();
        let d = family.contact_length_mm;
        let row = |y: f64| BaseRow {
            first_j: 0,
            points: (0..5).map(|k| DVec3::new(3.0 * k as f64, y, 0.0)).collect(),
            normals: vec![DVec3::Z; 5],
            tangents: vec![DVec3::X; 5],
        };
        let guides = Guides { levels: vec![0.0; 3], curves: vec![], rows: vec![row(0.0), row(d), row(2.0 * d)] };
        let grid = Grid::new(&guides, family);
        let footpoints: Vec<Footpoint> = (0..grid.poses.len())
            .flat_map(|i| {
                (0..5).map(move |k| {
                    let s = k as f64 / 4.0;
                    Footpoint { pose: i as u32, s, r: family.radius_at(s), normal: DVec3::Z, offset: 0.0 }
                })
            })
            .collect();
        let w = Weights { rigid: 1.0, approx: 1.0, g1: 1.0, ini: 1.0, fair: 1.0 };
        let obj = Objective::new(&grid, grid.normals.clone(), footpoints, grid.m.clone(), w);
        let x: Vec<f64> = grid.m.iter().flat_map(|p| p.to_array()).collect();
        let mut grad = vec![0.0; x.len()];
        let t = obj.evaluate(&x, Some(&mut grad));
        assert!(t.total < 1e-24, "{t:?}");
        assert!(grad.iter().all(|g| g.abs() < 1e-10), "{grad:?}");
        assert_eq!(obj.seams.len(), 5);
    }
}
