//! The field being optimised: the radii of the vertices of S^H (angles fixed), which of them
//! move and together (seed 003 §2.3.1), the initial field of eq. 24, and the check that no
//! triangle of S^H inverts (Constraint 1).

use crate::mesh::Surface;
use crate::num;
use crate::slitmap::SlitMap;
use glam::DVec2;

/// Faces wider than this in angle (radians) are left to the w-plane check: the strip's straight
/// triangles stand for them only where they are narrow (the inverse map's pole star takes the
/// wide ones through the w plane too).
const WIDE_FACE_RAD: f64 = 0.5;

/// Faces spanning more angle than this keep their vertices' start radii (the core round the
/// pole, see [`Field::new`]).
const CORE_SPAN_RAD: f64 = 0.15;

/// Which radius each vertex has and how the radii move.
#[derive(Debug, Clone)]
pub(super) struct Field {
    /// The unknown of each vertex: `None` on the outer loop (fixed at |w| = 1) and in the core
    /// round the pole, one shared unknown per hole loop (the annulus' inner circle too), one per
    /// other vertex.
    pub unknown: Vec<Option<usize>>,
    /// The radius of each vertex without an unknown.
    fixed: Vec<f64>,
    pub n_unknowns: usize,
    /// arg w per vertex (fixed), and per face its corners' angles unwrapped within π of the
    /// first, and whether the strip check applies.
    dir: Vec<DVec2>,
    strip: Vec<([f64; 3], bool)>,
    /// Faces that were not positively oriented at the start (P1 folds at slit tips): the map
    /// already has them, the optimisation must only not add any.
    folded_w: Vec<bool>,
    folded_strip: Vec<bool>,
    triangles: Vec<[u32; 3]>,
}

impl Field {
    pub fn new(surface: &Surface, map: &SlitMap, r: &[f64]) -> Self {
        let n = map.w.len();
        let angle: Vec<f64> = map.w.iter().map(|&w| num::arg(w)).collect();
        let strip: Vec<([f64; 3], bool)> = map
            .triangles()
            .iter()
            .enumerate()
            .map(|(f, t)| {
                let a0 = angle[t[0] as usize];
                let x = [0, 1, 2].map(|k| a0 + crate::num::wrap_pi(angle[t[k] as usize] - a0));
                let span = x[0].max(x[1]).max(x[2]) - x[0].min(x[1]).min(x[2]);
                (x, span < WIDE_FACE_RAD && Some(f) != map.pole_face)
            })
            .collect();
        // The outer loop at 1, and the core round the pole where faces span a wide angle at their
        // start radii: there the strip's straight triangles and the w plane's disagree by more
        // than the rings' spacing, and the spacing's gate, which tests one, could not prove rings
        // placed by the other (gen006: 30 bands given up).
        let mut fixed: Vec<Option<f64>> = vec![None; n];
        for &v in &surface.loops[0] {
            fixed[v as usize] = Some(1.0);
        }
        for (t, (x, _)) in map.triangles().iter().zip(&strip) {
            let span = x[0].max(x[1]).max(x[2]) - x[0].min(x[1]).min(x[2]);
            if span > CORE_SPAN_RAD {
                for &v in t {
                    if fixed[v as usize].is_none() {
                        fixed[v as usize] = Some(r[v as usize]);
                    }
                }
            }
        }
        let mut unknown = vec![None; n];
        let mut n_unknowns = 0;
        for l in surface.loops.iter().skip(1) {
            for &v in l {
                unknown[v as usize] = Some(n_unknowns);
                fixed[v as usize] = None;
            }
            n_unknowns += 1;
        }
        for v in 0..n {
            if unknown[v].is_none() && fixed[v].is_none() {
                unknown[v] = Some(n_unknowns);
                n_unknowns += 1;
            }
        }
        // Unit directions from w itself (no trigonometry: w' = w·r'/|w| keeps arg w bit for
        // bit up to the last rounding).
        let dir: Vec<DVec2> = map.w.iter().map(|w| *w / w.length()).collect();
        let mut field = Self {
            unknown,
            fixed: fixed.into_iter().map(|f| f.unwrap_or(0.0)).collect(),
            n_unknowns,
            dir,
            strip,
            folded_w: Vec::new(),
            folded_strip: Vec::new(),
            triangles: map.triangles().to_vec(),
        };
        let (w, s) = field.orientations(r);
        field.folded_w = w.iter().map(|&a| !(a > 0.0)).collect();
        field.folded_strip = s.iter().map(|&a| !(a < 0.0)).collect();
        field
    }

    /// The S^H point of vertex `v` at radius `r`.
    pub fn point(&self, v: usize, r: f64) -> DVec2 {
        self.dir[v] * r
    }

    /// Per face: the signed area in the w plane (positive = valid) and the orientation in the
    /// strip (arg w, |w>) (negative = valid; 0 where the strip check does not apply).
    fn orientations(&self, r: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.triangles
            .iter()
            .zip(&self.strip)
            .map(|(t, (x, check))| {
                let [a, b, c] = t.map(|v| self.point(v as usize, r[v as usize]));
                let w = 0.5 * (b - a).perp_dot(c - a);
                let s = if *check {
                    let y = t.map(|v| r[v as usize]);
                    (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0])
                } else {
                    0.0
                };
                (w, s)
            })
            .unzip()
    }

    /// Whether no face valid at the start has inverted, in the w plane or the strip.
    pub fn valid(&self, r: &[f64]) -> bool {
        if r.iter().any(|&x| !(x > 0.0)) {
            return false;
        }
        self.triangles.iter().enumerate().all(|(f, t)| {
            let [a, b, c] = t.map(|v| self.point(v as usize, r[v as usize]));
            if !self.folded_w[f] && !((b - a).perp_dot(c - a) > 0.0) {
                return false;
            }
            let (x, check) = &self.strip[f];
            if *check && !self.folded_strip[f] {
                let y = t.map(|v| r[v as usize]);
                if !((x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]) < 0.0) {
                    return false;
                }
            }
            true
        })
    }

    /// The radii with unknown values `x` (fixed vertices at 1).
    pub fn radii(&self, x: &[f64]) -> Vec<f64> {
        self.unknown.iter().zip(&self.fixed).map(|(u, &f)| u.map_or(f, |k| x[k])).collect()
    }

    /// The unknowns of radii `r` (a shared radius: the mean over its vertices, which the slit
    /// map gives equal up to rounding).
    pub fn unknowns(&self, r: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.n_unknowns];
        let mut count = vec![0u32; self.n_unknowns];
        for (v, u) in self.unknown.iter().enumerate() {
            if let Some(k) = u {
                x[*k] += r[v];
                count[*k] += 1;
            }
        }
        x.iter_mut().zip(count).for_each(|(x, c)| *x /= c as f64);
        x
    }

    /// A per-vertex gradient summed onto the unknowns (eq. 28 for the holes).
    pub fn gather(&self, per_vertex: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; self.n_unknowns];
        for (v, u) in self.unknown.iter().enumerate() {
            if let Some(k) = u {
                g[*k] += per_vertex[v];
            }
        }
        g
    }

    /// Per face, its corners' angles in the strip where the strip check applies.
    pub fn strip_angles(&self) -> Vec<Option<[f64; 3]>> {
        self.strip.iter().map(|(x, check)| check.then_some(*x)).collect()
    }

    /// The triangles (for the step bounds of eq. 30).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
}

/// The initial radii of S^H (seed 003 eq. 24): V^H = V^S/|V^S| · f_min(|V^S|), with f_min the
/// piecewise-linear radial function of the origin's energy (its `slopes` per bin of
/// [r_min, 1]), normalised so the outer circle stays at 1: r = f(|w|)/f(1) for a disk map. For
/// an annulus map f(R_A) = 0 would put the inner circle at the centre, so there
/// r = R_A + (1 − R_A)·f(|w|)/f(1): the inner circle keeps its radius. Returns the radii and
/// the scale f(1)/(1 − r_min) of T = s·r that eq. 6 takes at the start (s² of
/// [`super::Scale::Fixed`]). Slopes that are all zero (no energy) keep |w|.
pub(super) fn initial_radii(map: &SlitMap, slopes: &[f64]) -> (Vec<f64>, f64) {
    let r_min = map.mode.inner_radius();
    let bins = slopes.len();
    let width = (1.0 - r_min) / bins.max(1) as f64;
    // f at the bin edges.
    let mut edge = vec![0.0; bins + 1];
    for j in 0..bins {
        edge[j + 1] = edge[j] + slopes[j] * width;
    }
    let total = edge[bins];
    if !(total > 0.0 && total.is_finite()) {
        return (map.w.iter().map(|w| w.length()).collect(), 1.0);
    }
    let f = |x: f64| {
        let t = ((x - r_min) / width).clamp(0.0, bins as f64);
        let j = (t as usize).min(bins - 1);
        edge[j] + slopes[j] * (t - j as f64) * width
    };
    let radii = map.w.iter().map(|w| r_min + (1.0 - r_min) * f(w.length()) / total).collect();
    (radii, total / (1.0 - r_min))
}
