//! The energy of a scalar field T on the surface and its exact gradient (seed 003 eqs. 5–14).
//!
//! T is piecewise linear on the fixed 3D mesh with T_i = |V_i^H| (here r_i, the radius of
//! vertex i in the normalised S^H, outer boundary at 1), so on each face ∇T = Σ_k r_k ∇φ_k is
//! linear in r. Per face, with g = |∇T|², κ_s the normal curvature along ∇T (the face's
//! curvature tensor, eq. 7), K_c = 1/R (the paper writes K_c "the radius of the ball-end mill";
//! by eq. 1's dimensions it is the tool's curvature) and c = (κ_s + K_c)/8:
//!
//! * **E_w** (eq. 6) = Σ_F A_F (α_F/s² + s²/α_F), α = c/g, for T = s·r. The paper's scale is
//!   fixed ([`Scale::Fixed`]: s = f_min(1), the origin's radial function at the rim). With
//!   [`Scale::PerLevel`] (the default) s is the best one per level of r: E_w minimised over a
//!   monotone reparametrisation of T, seed 000's closed form E_min generalised from circles to
//!   any field, Σ over level bins j of 2·sqrt(Σ_F w_jF A_F α_F · Σ_F w_jF A_F/α_F) with hat
//!   weights w_jF of the face's mean r (a partition of unity). Only the level sets of T become
//!   rings and the spacing chooses each ring's step itself, so only the uniformity along each
//!   level matters to the path; the paper's fixed scale also pulls every level towards one
//!   absolute gradient, which a part that is not round cannot have with its rim fixed. It is
//!   ≥ 2·area (Cauchy–Schwarz), with equality exactly when the predicted scallop is uniform
//!   along every level.
//! * **E_n** (eq. 11, corrected) = Σ_F A_F κ_t², κ_t = 2H − κ_s the normal curvature along the
//!   iso-curve's tangent. The paper prints the curvature along ∇T, unsquared; a level set's
//!   normal curvature is along its tangent, and eq. 10 squares it.
//! * **E_g** (eqs. 12–13, corrected) = Σ_j D_j²/C_j over interior vertices, D_j = −Σ_F A_F
//!   ∇φ_j·X_F the divergence of X = ∇T/|∇T| integrated over vertex j's dual cell (eq. 13's cotan
//!   form, written with ∇φ; C_j a third of the areas of the faces round j): the geodesic
//!   curvature of the level sets, squared (the paper omits the square). Boundary vertices are
//!   excluded (they lie on a level set).
//! * **E_b**, ours: a barrier μ Σ_F A_F (−ln s_F) on the faces the log-polar strip locates, s_F
//!   the sine of the angle between the level set and the meridian (1 where they are orthogonal,
//!   as the conformal map starts; 0 where the strip triangle inverts). Constraint 1 made smooth:
//!   without it a Newton step only learns of an inversion from the line search, and a single
//!   face about to invert halved every step to nothing.
//!
//! E = E_w + α(E_n + E_g) + E_b (eq. 14). E_w is an area (mm²) and E_k = E_n + E_g is
//! dimensionless: the α here is in mm², the stage's option scaled by the part's area (see
//! [`super::OptimiseOptions::alpha`]).
//!
//! Where κ_s + K_c < K_c/10 (a concave curvature nearly the ball's, which the origin stage
//! reports as a gouge risk) c is clamped, so the energy stays finite. Faces with no gradient at
//! the start (three corners on one level: ears of a boundary) and, for a disk map, the face
//! round the pole (T has a cone there, not a linear field) are left out of every term.
//!
//! The gradient is exact (envelope theorem for the optimal scales, the hat weights' slopes
//! included), checked against central differences in the tests.

use crate::mesh::Surface;
use glam::DVec3;

/// How the scale of T = s·r enters E_w (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scale {
    /// The paper's: s fixed at f_min(1).
    Fixed,
    /// The best s per level of T.
    PerLevel,
}

/// The parts of E at one field.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct EnergyParts {
    /// mm².
    pub e_w: f64,
    pub e_n: f64,
    pub e_g: f64,
    /// The strip barrier, mm²; +∞ once a strip triangle inverts.
    pub e_b: f64,
    /// E_w + α(E_n + E_g) + E_b.
    pub total: f64,
}

impl EnergyParts {
    /// E_k = E_n + E_g.
    pub fn e_k(&self) -> f64 {
        self.e_n + self.e_g
    }
}

/// What the energy is made of, besides the surface.
#[derive(Debug, Clone)]
pub(super) struct Settings {
    pub radius_mm: f64,
    pub alpha: f64,
    pub scale: Scale,
    /// s² of [`Scale::Fixed`].
    pub fixed_s2: f64,
    /// Level bins of [`Scale::PerLevel`] over [r_min, 1].
    pub bins: usize,
    pub r_min: f64,
    /// μ of the strip barrier.
    pub barrier: f64,
}

/// One face in the energy.
#[derive(Debug, Clone, Copy)]
struct Face {
    corners: [u32; 3],
    grad: [DVec3; 3],
    area: f64,
    /// Curvature tensor frame and entries (e, f, g) in it.
    u: DVec3,
    v: DVec3,
    ii: [f64; 3],
    /// The unit direction across the meridians, outwards, (∇θ/|∇θ|) × n: the strip triangle is
    /// valid while ∇T has a positive component along it (zero: no barrier on this face).
    across: DVec3,
}

/// One face at one field.
#[derive(Debug, Clone, Copy, Default)]
struct FaceState {
    g: f64,
    c: f64,
    /// ∂c/∂∇T is zero where c is clamped.
    clamped: bool,
    gvec: DVec3,
    ks: f64,
    /// κ_s's gradient with respect to ∇T.
    dks: DVec3,
    mean_r: f64,
}

/// s² per level bin, from the sums Σ wA·α and Σ wA/α.
#[derive(Debug, Clone)]
struct Levels {
    s2: Vec<f64>,
    alpha: Vec<f64>,
    beta: Vec<f64>,
}

impl Levels {
    fn energy(&self) -> f64 {
        (0..self.s2.len()).map(|j| self.alpha[j] / self.s2[j] + self.beta[j] * self.s2[j]).sum()
    }
}

/// E's intermediate values at one field (per-face states, level scales, divergences): what the
/// gradient and the Gauss–Newton matrices read, kept so that a field the line search accepted is
/// not evaluated again for them (the descent took the face states six times per iteration).
#[derive(Debug, Clone)]
pub(super) struct Evaluated {
    states: Vec<FaceState>,
    levels: Levels,
    div: Vec<f64>,
}

/// The per-face data of the energy on one surface, for many fields.
#[derive(Debug, Clone)]
pub(super) struct EnergyModel {
    faces: Vec<Face>,
    /// Dual-cell area per vertex, 0 where the vertex is not in E_g.
    dual_area: Vec<f64>,
    tool_curvature: f64,
    alpha: f64,
    scale: Scale,
    fixed_s2: f64,
    bins: usize,
    r_min: f64,
    barrier: f64,
    excluded: usize,
    /// E_g's stars: per vertex in E_g, its star's vertices (sorted) and, per face round it, the
    /// face (index into `faces`), the corner that is the vertex, and where the face's corners
    /// are in the star (see [`EnergyModel::smoothness_gauss_newton_at`]).
    stars: Vec<Star>,
}

#[derive(Debug, Clone)]
struct Star {
    vertex: u32,
    members: Vec<u32>,
    faces: Vec<(u32, u8, [u16; 3])>,
}

impl EnergyModel {
    /// The faces of `surface` whose field `r` has a gradient, less `skip` (the pole's face).
    /// `strip[f]`: the angles of face f's corners in the log-polar strip, unwrapped, where the
    /// strip check applies (the barrier's faces).
    pub(super) fn new(
        surface: &Surface,
        r: &[f64],
        skip: Option<usize>,
        strip: &[Option<[f64; 3]>],
        settings: &Settings,
    ) -> Self {
        let n = surface.positions.len();
        let mut faces = Vec::with_capacity(surface.triangles.len());
        let mut excluded = 0;
        let mut in_energy = vec![true; n];
        let mut dual_area = vec![0.0; n];
        for (f, t) in surface.triangles.iter().enumerate() {
            let p = t.map(|v| surface.positions[v as usize]);
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let c2 = cross.length_squared();
            let grad = [0, 1, 2].map(|k| cross.cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / c2);
            let g = grad[0] * r[t[0] as usize] + grad[1] * r[t[1] as usize] + grad[2] * r[t[2] as usize];
            if Some(f) == skip || !(c2 > 0.0 && c2.is_finite()) || !(g.length_squared() > 0.0) {
                excluded += 1;
                for &v in t {
                    in_energy[v as usize] = false;
                }
                continue;
            }
            let k = &surface.curvature[f];
            let area = 0.5 * c2.sqrt();
            for &v in t {
                dual_area[v as usize] += area / 3.0;
            }
            let across = strip[f].map_or(DVec3::ZERO, |x| {
                let d_theta = grad[0] * x[0] + grad[1] * x[1] + grad[2] * x[2];
                let t = d_theta.normalize_or_zero().cross(cross / c2.sqrt());
                // A face folded at the start gets no barrier: it only must not get worse.
                if t.dot(g) > 0.0 {
                    t
                } else {
                    DVec3::ZERO
                }
            });
            faces.push(Face { corners: *t, grad, area, u: k.u, v: k.v, ii: [k.e, k.f, k.g], across });
        }
        for l in &surface.loops {
            for &v in l {
                in_energy[v as usize] = false;
            }
        }
        for (a, keep) in dual_area.iter_mut().zip(&in_energy) {
            if !keep {
                *a = 0.0;
            }
        }
        let stars = if settings.alpha > 0.0 { stars(&faces, &dual_area) } else { Vec::new() };
        Self {
            faces,
            dual_area,
            stars,
            tool_curvature: 1.0 / settings.radius_mm,
            alpha: settings.alpha,
            scale: settings.scale,
            fixed_s2: settings.fixed_s2,
            bins: settings.bins.max(1),
            r_min: settings.r_min,
            barrier: settings.barrier,
            excluded,
        }
    }

    /// Faces left out of every term.
    pub fn excluded_faces(&self) -> usize {
        self.excluded
    }

    /// The area of the faces in the energy, mm².
    pub fn area(&self) -> f64 {
        self.faces.iter().map(|f| f.area).sum()
    }

    /// Whether E_g couples the stars of vertices (α > 0), which the Gauss–Newton matrix then
    /// carries ([`EnergyModel::smoothness_gauss_newton_at`]).
    pub fn couples_stars(&self) -> bool {
        self.alpha > 0.0
    }

    fn state(&self, face: &Face, r: &[f64]) -> FaceState {
        let [a, b, c] = face.corners.map(|v| r[v as usize]);
        let gvec = face.grad[0] * a + face.grad[1] * b + face.grad[2] * c;
        let (qa, qb) = (gvec.dot(face.u), gvec.dot(face.v));
        let q2 = qa * qa + qb * qb;
        let [e, f, g] = face.ii;
        let (ma, mb) = (e * qa + f * qb, f * qa + g * qb);
        let (ks, dks) = if q2 > 0.0 {
            let ks = (qa * ma + qb * mb) / q2;
            (ks, (face.u * (ma - ks * qa) + face.v * (mb - ks * qb)) * (2.0 / q2))
        } else {
            (0.0, DVec3::ZERO)
        };
        let floor = 0.1 * self.tool_curvature;
        let kc = ks + self.tool_curvature;
        let clamped = !(kc >= floor);
        FaceState {
            g: gvec.length_squared(),
            c: if clamped { floor } else { kc } / 8.0,
            clamped,
            gvec,
            ks,
            dks,
            mean_r: (a + b + c) / 3.0,
        }
    }

    fn states(&self, r: &[f64]) -> Vec<FaceState> {
        crate::par::each(self.faces.len(), |i| self.state(&self.faces[i], r))
    }

    /// The hat weights of level `t`: (bin, weight, d weight/dt) for at most two bins.
    fn hats(&self, t: f64) -> [(usize, f64, f64); 2] {
        let bins = self.level_bins();
        if bins == 1 {
            return [(0, 1.0, 0.0), (0, 0.0, 0.0)];
        }
        let width = (1.0 - self.r_min) / bins as f64;
        // In units of bins, centres at j + 0.5.
        let x = (t - self.r_min) / width - 0.5;
        let last = bins - 1;
        if x <= 0.0 {
            return [(0, 1.0, 0.0), (0, 0.0, 0.0)];
        }
        if x >= last as f64 {
            return [(last, 1.0, 0.0), (last, 0.0, 0.0)];
        }
        let j = x as usize;
        let f = x - j as f64;
        [(j, 1.0 - f, -1.0 / width), (j + 1, f, 1.0 / width)]
    }

    fn level_bins(&self) -> usize {
        match self.scale {
            Scale::Fixed => 1,
            Scale::PerLevel => self.bins,
        }
    }

    fn levels(&self, states: &[FaceState]) -> Levels {
        let bins = self.level_bins();
        let mut lv = Levels { s2: vec![self.fixed_s2; bins], alpha: vec![0.0; bins], beta: vec![0.0; bins] };
        for (face, st) in self.faces.iter().zip(states) {
            let alpha = st.c / st.g;
            for (j, w, _) in self.hats(st.mean_r) {
                lv.alpha[j] += w * face.area * alpha;
                lv.beta[j] += w * face.area / alpha;
            }
        }
        if self.scale == Scale::PerLevel {
            for j in 0..bins {
                let (a, b) = (lv.alpha[j], lv.beta[j]);
                // An empty bin (no face near that level) weighs nothing whatever its s².
                lv.s2[j] = if a > 0.0 && b > 0.0 { (a / b).sqrt() } else { 1.0 };
            }
        }
        lv
    }

    /// E at `r`; with `gradient`, also ∂E/∂r_i per vertex (overwritten). The descent keeps what
    /// [`EnergyModel::evaluate_at`] returns instead.
    #[cfg(test)]
    pub fn evaluate(&self, r: &[f64], gradient: Option<&mut [f64]>) -> EnergyParts {
        let (parts, at) = self.evaluate_at(r);
        if let Some(out) = gradient {
            self.gradient_at(&at, out);
        }
        parts
    }

    /// E at `r` and the intermediate values the gradient and the Gauss–Newton matrices of this
    /// field are computed from ([`EnergyModel::gradient_at`], [`EnergyModel::gauss_newton_at`],
    /// [`EnergyModel::smoothness_gauss_newton_at`]).
    pub(super) fn evaluate_at(&self, r: &[f64]) -> (EnergyParts, Evaluated) {
        let states = self.states(r);
        let levels = self.levels(&states);
        let mut parts = EnergyParts { e_w: levels.energy(), ..EnergyParts::default() };
        for (face, st) in self.faces.iter().zip(&states) {
            let kt = face.ii[0] + face.ii[2] - st.ks;
            parts.e_n += face.area * kt * kt;
            if face.across != DVec3::ZERO {
                let s = face.across.dot(st.gvec) / st.g.sqrt();
                parts.e_b +=
                    if s > 0.0 { -self.barrier * face.area * crate::num::ln(s.min(1.0)) } else { f64::INFINITY };
            }
        }
        let div = self.divergence(&states);
        for (d, &c) in div.iter().zip(&self.dual_area) {
            if c > 0.0 {
                parts.e_g += d * d / c;
            }
        }
        parts.total = parts.e_w + self.alpha * (parts.e_n + parts.e_g) + parts.e_b;
        (parts, Evaluated { states, levels, div })
    }

    /// ∂E/∂r_i per vertex (overwritten) at the field `at` was evaluated at.
    pub(super) fn gradient_at(&self, at: &Evaluated, out: &mut [f64]) {
        self.gradient(&at.states, &at.levels, &at.div, out);
    }

    /// D_j per vertex (0 where the vertex is not in E_g).
    fn divergence(&self, states: &[FaceState]) -> Vec<f64> {
        let mut div = vec![0.0; self.dual_area.len()];
        for (face, st) in self.faces.iter().zip(states) {
            let x = st.gvec / st.g.sqrt();
            for k in 0..3 {
                let v = face.corners[k] as usize;
                if self.dual_area[v] > 0.0 {
                    div[v] -= face.area * face.grad[k].dot(x);
                }
            }
        }
        div
    }

    /// ∂E_w/∂g, ∂E_w/∂c and ∂E_w/∂(mean r) of one face.
    fn uniformity_derivatives(&self, face: &Face, st: &FaceState, lv: &Levels) -> (f64, f64, f64) {
        let a = face.area;
        let (g, c) = (st.g, st.c);
        let alpha = c / g;
        let (mut d_alpha, mut d_mean) = (0.0, 0.0);
        for (j, w, dw) in self.hats(st.mean_r) {
            let s2 = lv.s2[j];
            d_alpha += w * a * (1.0 / s2 - s2 / (alpha * alpha));
            d_mean += dw * a * (alpha / s2 + s2 / alpha);
        }
        let de_dc = if st.clamped { 0.0 } else { d_alpha / g };
        (d_alpha * (-c / (g * g)), de_dc, d_mean)
    }

    fn gradient(&self, states: &[FaceState], lv: &Levels, div: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|g| *g = 0.0);
        for (face, st) in self.faces.iter().zip(states) {
            let a = face.area;
            let (de_dg, de_dc, d_mean) = self.uniformity_derivatives(face, st, lv);
            let kt = face.ii[0] + face.ii[2] - st.ks;
            // E_n: ∂(A κ_t²)/∂∇T = −2 A κ_t ∂κ_s/∂∇T.
            let mut d_gvec = st.gvec * (2.0 * de_dg) + st.dks * (de_dc / 8.0 - self.alpha * 2.0 * a * kt);
            // E_g, through X = ∇T/|∇T|.
            let len = st.g.sqrt();
            let x = st.gvec / len;
            let mut d_x = DVec3::ZERO;
            for k in 0..3 {
                let v = face.corners[k] as usize;
                let cv = self.dual_area[v];
                if cv > 0.0 {
                    d_x -= face.grad[k] * (2.0 * div[v] / cv * a);
                }
            }
            d_gvec += (d_x - x * x.dot(d_x)) * (self.alpha / len);
            if face.across != DVec3::ZERO {
                // −μA ln(t·G/|G|): −μA (t/(t·G) − G/g).
                d_gvec -= (face.across / face.across.dot(st.gvec) - st.gvec / st.g) * (self.barrier * a);
            }
            for k in 0..3 {
                out[face.corners[k] as usize] += d_gvec.dot(face.grad[k]) + d_mean / 3.0;
            }
        }
    }

    /// The Gauss–Newton matrix of E_w and E_b as 3×3 blocks over each face's corners: ∇φᵀ H ∇φ
    /// with H = A (w_along Ĝ Ĝᵀ + w_across (I − Ĝ Ĝᵀ)) the Hessian of E_w in ∇T at fixed c and
    /// scales, its across part floored at [`ACROSS_FLOOR`] times the along part (where the field
    /// is sparse the true Hessian is negative across ∇T), plus the barrier's convex part
    /// μA ttᵀ/(t·G)².
    /// At the field `at` was evaluated at.
    pub(super) fn gauss_newton_at(&self, at: &Evaluated) -> Vec<([u32; 3], [[f64; 3]; 3])> {
        let lv = &at.levels;
        self.faces
            .iter()
            .zip(&at.states)
            .map(|(face, st)| {
                let (g, c) = (st.g, st.c);
                let (mut da, mut db) = (0.0, 0.0);
                for (j, w, _) in self.hats(st.mean_r) {
                    da += w / lv.s2[j];
                    db += w * lv.s2[j];
                }
                let along = face.area * (6.0 * da * c / (g * g) + 2.0 * db / c);
                let across = (face.area * (2.0 * db / c - 2.0 * da * c / (g * g))).max(ACROSS_FLOOR * along);
                let x = st.gvec / g.sqrt();
                // Capped: a wall 10⁶ times the face's own stiffness already stops it; more only
                // costs the factorisation its precision.
                let tg = face.across.dot(st.gvec);
                let wall = if face.across != DVec3::ZERO {
                    (self.barrier * face.area / (tg * tg)).min(1e6 * along)
                } else {
                    0.0
                };
                let mut block = [[0.0; 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        let (gi, gj) = (face.grad[i], face.grad[j]);
                        block[i][j] = across * gi.dot(gj)
                            + (along - across) * gi.dot(x) * gj.dot(x)
                            + wall * gi.dot(face.across) * gj.dot(face.across);
                    }
                }
                (face.corners, block)
            })
            .collect()
    }

    /// The pattern of [`EnergyModel::smoothness_gauss_newton_at`]'s values: (vertex, vertex) pairs,
    /// the same every time.
    pub(super) fn smoothness_pattern(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.stars.iter().flat_map(|star| star.members.iter().flat_map(|&a| star.members.iter().map(move |&b| (a, b))))
    }

    /// The Gauss–Newton matrix of α·E_g as one rank-one term (w_j, ∇D_j) per star, w_j = 2α/C_j,
    /// ∇D_j = Σ_F −A_F ∇φ_jᵀ (I − XXᵀ)/|∇T| ∇φ over the faces round j, over the star's members:
    /// its values, in the order of [`EnergyModel::smoothness_pattern`], are w_j·∂_a D_j·∂_b D_j
    /// (the caller forms them where it sums them: as one vector they held 60 MB at the 300k-face
    /// panel's peak). Each vertex couples its whole star (E_g is a fourth-order term): left to
    /// the line search, it made the Gauss–Newton steps of E_w wrinkle the level sets, and every
    /// step was cut to a sixteenth.
    /// At the field `at` was evaluated at.
    pub(super) fn smoothness_gauss_newton_at(&self, at: &Evaluated) -> Vec<(f64, Vec<f64>)> {
        let at_states = &at.states;
        crate::par::each(self.stars.len(), |i| {
            let star = &self.stars[i];
            let mut d = vec![0.0; star.members.len()];
            for &(f, k, at) in &star.faces {
                let face = &self.faces[f as usize];
                let st = at_states[f as usize];
                let len = st.g.sqrt();
                let x = st.gvec / len;
                // ∂D_j/∂r_m = −A ∇φ_kᵀ (I − XXᵀ) ∇φ_m / |G|.
                let b = face.grad[k as usize] * (-face.area);
                let pb = (b - x * x.dot(b)) / len;
                for m in 0..3 {
                    d[at[m] as usize] += pb.dot(face.grad[m]);
                }
            }
            (2.0 * self.alpha / self.dual_area[star.vertex as usize], d)
        })
    }
}

/// The stars of the vertices in E_g (`dual_area` > 0) over `faces`.
fn stars(faces: &[Face], dual_area: &[f64]) -> Vec<Star> {
    let mut round: Vec<Vec<(u32, u8)>> = vec![Vec::new(); dual_area.len()];
    for (f, face) in faces.iter().enumerate() {
        for k in 0..3 {
            let v = face.corners[k] as usize;
            if dual_area[v] > 0.0 {
                round[v].push((f as u32, k as u8));
            }
        }
    }
    round
        .into_iter()
        .enumerate()
        .filter(|(_, fs)| !fs.is_empty())
        .map(|(v, fs)| {
            let mut members: Vec<u32> = fs.iter().flat_map(|&(f, _)| faces[f as usize].corners).collect();
            members.sort_unstable();
            members.dedup();
            let faces = fs
                .into_iter()
                .map(|(f, k)| {
                    let at = faces[f as usize]
                        .corners
                        .map(|c| members.binary_search(&c).expect("a corner of the star") as u16);
                    (f, k, at)
                })
                .collect();
            Star { vertex: v as u32, members, faces }
        })
        .collect()
}

/// The across-∇T floor of E_w's Gauss–Newton matrix, as a fraction of its along part.
const ACROSS_FLOOR: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{self, MeshOptions};

    fn model(scale: Scale, alpha: f64) -> (Surface, Vec<f64>, EnergyModel) {
        let surface =
            mesh::from_triangles(&crate::fixtures::saddle_2_holes(), &MeshOptions::default()).unwrap().surface;
        // A smooth field with a gradient everywhere: a tilted, bent ramp.
        let r: Vec<f64> =
            surface.positions.iter().map(|p| 0.5 + 0.004 * p.x + 0.001 * p.y + 2e-5 * p.x * p.y).collect();
        // Meridian angles per face, so the barrier's gradient is checked too.
        let strip: Vec<Option<[f64; 3]>> = surface
            .triangles
            .iter()
            .map(|t| Some(t.map(|v| 0.01 * surface.positions[v as usize].y - 0.002 * surface.positions[v as usize].x)))
            .collect();
        let settings = Settings { radius_mm: 3.0, alpha, scale, fixed_s2: 0.7, bins: 8, r_min: 0.0, barrier: 0.1 };
        let m = EnergyModel::new(&surface, &r, None, &strip, &settings);
        (surface, r, m)
    }

    #[test]
    fn the_gradient_matches_central_differences() {
        for (scale, alpha) in [(Scale::Fixed, 10.0), (Scale::PerLevel, 10.0), (Scale::PerLevel, 0.0)] {
            let (surface, r, m) = model(scale, alpha);
            assert!(m.faces.iter().filter(|f| f.across != DVec3::ZERO).count() > 100, "barrier faces");
            let mut grad = vec![0.0; r.len()];
            m.evaluate(&r, Some(&mut grad));
            let mut rng = crate::fixtures::SplitMix64(17);
            let interior: Vec<usize> =
                (0..r.len()).filter(|v| !surface.loops.iter().any(|l| l.contains(&(*v as u32)))).collect();
            // Rounding (E is about 10⁴ mm²) and truncation (near-sparse faces have large third
            // derivatives) both stay below 1e-4 relative; a wrong term is off by O(1).
            let eps = 2e-6;
            let fd = |up: Vec<f64>, down: Vec<f64>| {
                (m.evaluate(&up, None).total - m.evaluate(&down, None).total) / (2.0 * eps)
            };
            for _ in 0..12 {
                let v = interior[(rng.next_u64() % interior.len() as u64) as usize];
                let (mut up, mut down) = (r.clone(), r.clone());
                up[v] += eps;
                down[v] -= eps;
                let d = fd(up, down);
                assert!(
                    (d - grad[v]).abs() <= 1e-4 * d.abs().max(1.0),
                    "{scale:?} α {alpha}: vertex {v}: {} vs {d}",
                    grad[v]
                );
            }
            // A hole moved as one: the sum of its vertices' gradients (eq. 28).
            let hole = &surface.loops[1];
            let (mut up, mut down) = (r.clone(), r.clone());
            for &v in hole {
                up[v as usize] += eps;
                down[v as usize] -= eps;
            }
            let d = fd(up, down);
            let sum: f64 = hole.iter().map(|&v| grad[v as usize]).sum();
            assert!((d - sum).abs() <= 1e-4 * d.abs().max(1.0), "{scale:?}: hole {sum} vs {d}");
        }
    }

    #[test]
    fn the_level_free_energy_is_at_least_twice_the_area_and_equal_on_a_uniform_field() {
        let (_, r, m) = model(Scale::PerLevel, 0.0);
        let e = m.evaluate(&r, None);
        assert!(e.e_w >= 2.0 * m.area() * (1.0 - 1e-12), "{} < 2·{}", e.e_w, m.area());
        // A linear ramp on a flat plate: one gradient, no curvature, so every level is uniform.
        let plate = mesh::from_triangles(&crate::fixtures::plate_3_holes(), &MeshOptions::default()).unwrap().surface;
        let ramp: Vec<f64> = plate.positions.iter().map(|p| 0.5 + 0.003 * p.x).collect();
        let settings = Settings {
            radius_mm: 3.0,
            alpha: 0.0,
            scale: Scale::PerLevel,
            fixed_s2: 1.0,
            bins: 8,
            r_min: 0.0,
            barrier: 0.0,
        };
        let none = vec![None; plate.triangles.len()];
        let flat = EnergyModel::new(&plate, &ramp, None, &none, &settings);
        let e = flat.evaluate(&ramp, None).e_w;
        assert!((e / (2.0 * flat.area()) - 1.0).abs() < 1e-9, "uniformity {}", e / (2.0 * flat.area()));
    }
}
