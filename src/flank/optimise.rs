//! The optimisation of the m-grid (seed 002 §6): footpoints and normals refreshed in an outer
//! loop, L-BFGS on the frozen objective inside ([`super::objective`], [`super::lbfgs`]).
//!
//! What it computes. F (eq. 18) "with refreshed footpoints" at a grid m is F evaluated with the
//! normals n_{i,j} (the surface's interpolated normal at the nearest mesh point of m_{i,j}) and,
//! for every axis sample y^k (eq. 11), its footpoint y^k⊥ and the normal there, all taken at m.
//! Starting from the initial grid (eqs. 7–9), each outer iteration
//!
//! 1. freezes the normals and footpoints of the current grid m_k;
//! 2. minimises, by L-BFGS from m_k, the frozen F plus a proximal term μ/(3G)·Σ|m − m_k|²;
//! 3. keeps the result only if F with refreshed footpoints decreased there (then μ shrinks
//!    ×0.3); otherwise μ grows ×10 and the step is tried again.
//!
//! Decision (the seed is silent on its outer loop): the proximal damping is needed. With the
//! footpoints frozen, F_approx only sees each sample's height over a fixed tangent plane, so a
//! pose may slide and tilt along the surface at no cost, and the other terms (G¹ above all)
//! push it there: undamped, one outer iteration moved poses 15–20 mm on a sphere cap of radius
//! 150 mm and the plan diverged. The damped loop is a Levenberg–Marquardt-like method on the
//! true F: every kept step lowers it, and the term vanishes at a fixed point, so the optimum is
//! F's own.
//!
//! It stops when a kept step moves no grid point more than 10⁻⁸·L, after two kept steps in a
//! row that lower F by less than a fraction 10⁻⁶, when no damping makes a step lower F, or after
//! `outer_iterations`. Rigidity (eq. 4) must then hold within `rigidity_tolerance_rel`·L at
//! every pose; the seed makes it a penalty of the highest weight, and a penalty leaves a
//! residual that grows with the other terms, so while it does not hold w₁ is multiplied by 10
//! and the loop resumes from where it stopped (a penalty continuation), up to 10⁸ times the
//! given w₁; beyond, the plan is refused with [`FlankError::RigidityNotMet`] naming the worst
//! pose.
//!
//! The poses handed on are the rails of the final grid read with its refreshed normals, made
//! exactly rigid: a and b moved apart or together along their axis about their midpoint to
//! |b − a| = L (at most half the rigidity tolerance each).
//!
//! Preconditions: a grid with at least one strip of at least two poses; K ≥ 2 samples per axis.
//! Deterministic: sequential footpoint queries, fixed order.

use super::objective::{Footpoint, Objective, Terms, Weights};
use super::rails::Grid;
use super::FlankError;
use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use crate::num;
use glam::DVec3;
use serde::Serialize;

/// Options of [`optimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimiseOptions {
    /// Axis samples K (eq. 11).
    pub samples_per_axis: usize,
    pub weights: Weights,
    pub outer_iterations: usize,
    /// L-BFGS iterations per outer iteration.
    pub inner_iterations: usize,
    /// Largest rigidity error allowed, as a fraction of L.
    pub rigidity_tolerance_rel: f64,
}

/// Figures of a grid, measured with real footpoints (not the frozen tangent planes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct GridFigures {
    /// Largest | |b − a| − L | over the poses, mm.
    pub max_rigidity_error_mm: f64,
    /// Seed 002 eq. 19 over every axis sample: the largest dist(y^k, y^k⊥) − r^k (material
    /// left, mm) and the smallest (negative: the sphere cuts into the surface, mm).
    pub max_distance_error_mm: f64,
    pub min_distance_error_mm: f64,
    /// Largest |θ¹ − θ²| over the strip boundaries (eq. 15), degrees.
    pub max_g1_angle_deg: f64,
}

/// The optimised grid and what the optimisation did.
#[derive(Clone, Debug)]
pub struct Optimised {
    /// Grid points and the normals of the last solve.
    pub grid: Grid,
    /// Rigid poses (a, b), `grid.poses` order.
    pub rails: Vec<(DVec3, DVec3)>,
    pub report: OptimiseReport,
}

/// The optimiser's report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OptimiseReport {
    pub unknowns: usize,
    pub poses: usize,
    pub axis_samples: usize,
    pub outer_iterations: usize,
    pub lbfgs_iterations: usize,
    pub evaluations: usize,
    /// w₁ at the end of the penalty continuation.
    pub rigid_weight: f64,
    pub initial_terms: Terms,
    pub final_terms: Terms,
    pub initial: GridFigures,
    pub final_figures: GridFigures,
    /// Largest distance a grid point moved from the initial grid, mm.
    pub max_move_mm: f64,
    /// Largest shift of a sphere centre when the poses were made exactly rigid, mm.
    pub rigid_projection_mm: f64,
}

/// The outer loop's proximal weight μ (a multiple of max(w₂, w₃)): where it starts, its floor
/// and its ceiling (beyond, no step decreases F: converged as far as it goes).
const MU_START: f64 = 0.1;
const MU_MIN: f64 = 1e-9;
const MU_MAX: f64 = 1e8;

/// Largest w₁ of the penalty continuation.
const MAX_RIGID_WEIGHT: f64 = 1e8;
/// The outer loop also stops after two accepted steps in a row that lower F by less than this
/// fraction.
const STALL: f64 = 1e-6;
/// The outer loop stops when no grid point moves more than this fraction of L.
const OUTER_TOLERANCE: f64 = 1e-8;

/// Optimises `grid` on `surface` (module docs).
pub fn optimise(
    surface: &Surface,
    tree: &FaceTree,
    mut grid: Grid,
    o: &OptimiseOptions,
) -> Result<Optimised, FlankError> {
    let family = grid.family;
    let l = family.length_mm;
    let m_ini = grid.m.clone();
    let k = o.samples_per_axis.max(2);
    let lbfgs = super::lbfgs::LbfgsOptions {
        history: 8,
        max_iterations: o.inner_iterations,
        gtol: 0.0,
        xtol: 1e-9 * l,
        ftol: 1e-12,
        first_step: 1e-3 * l,
    };
    let mut weights = o.weights;
    let mut x: Vec<f64> = grid.m.iter().flat_map(|p| p.to_array()).collect();
    let mut report = OptimiseReport {
        unknowns: x.len(),
        poses: grid.poses.len(),
        axis_samples: grid.poses.len() * k,
        outer_iterations: 0,
        lbfgs_iterations: 0,
        evaluations: 0,
        rigid_weight: weights.rigid,
        initial_terms: Terms::default(),
        final_terms: Terms::default(),
        initial: GridFigures::default(),
        final_figures: GridFigures::default(),
        max_move_mm: 0.0,
        rigid_projection_mm: 0.0,
    };
    // The true objective at a grid: normals and footpoints refreshed there.
    let refresh = |x: &[f64], previous: &[DVec3]| {
        let normals = refresh_normals(surface, tree, x, previous);
        let footpoints = footpoints(surface, tree, &grid, x, &normals, k);
        (normals, footpoints)
    };
    let (mut normals, mut feet) = refresh(&x, &grid.normals);
    {
        let objective = Objective::new(&grid, normals.clone(), feet.clone(), m_ini.clone(), weights);
        report.initial_terms = objective.evaluate(&x, None);
        report.initial = figures(tree, &grid, &x, k, &objective);
    }
    let scale = weights.approx.max(weights.g1).max(1e-300);
    let mut mu = MU_START * scale;
    loop {
        let mut current =
            Objective::new(&grid, normals.clone(), feet.clone(), m_ini.clone(), weights).evaluate(&x, None).total;
        let mut stalled = 0;
        for _ in 0..o.outer_iterations.max(1) {
            let mut objective = Objective::new(&grid, normals.clone(), feet.clone(), m_ini.clone(), weights);
            objective.prox = Some((mu, x.chunks(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect()));
            let mut trial = x.clone();
            let r = super::lbfgs::minimise(&mut trial, |x, g| objective.evaluate(x, Some(g)).total, &lbfgs);
            report.outer_iterations += 1;
            report.lbfgs_iterations += r.iterations;
            report.evaluations += r.evaluations;
            if !trial.iter().all(|v| v.is_finite()) {
                return Err(FlankError::Diverged { outer_iteration: report.outer_iterations });
            }
            let (trial_normals, trial_feet) = refresh(&trial, &normals);
            let value = Objective::new(&grid, trial_normals.clone(), trial_feet.clone(), m_ini.clone(), weights)
                .evaluate(&trial, None)
                .total;
            if !(value <= current) {
                // The linearised model was trusted too far: damp more and try again.
                mu *= 10.0;
                if mu > MU_MAX * scale {
                    break;
                }
                continue;
            }
            let moved = trial.chunks(3).zip(x.chunks(3)).map(|(p, q)| dist3(p, q)).fold(0.0, f64::max);
            let gain = current - value;
            (x, normals, feet, current) = (trial, trial_normals, trial_feet, value);
            mu = (mu * 0.3).max(MU_MIN * scale);
            stalled = if gain <= STALL * current { stalled + 1 } else { 0 };
            if moved <= OUTER_TOLERANCE * l || stalled >= 2 {
                break;
            }
        }
        let worst = worst_rigidity(&grid, &x, &normals);
        if worst.1 <= o.rigidity_tolerance_rel * l {
            break;
        }
        if weights.rigid * 10.0 > MAX_RIGID_WEIGHT * o.weights.rigid.max(1e-300) {
            let pose = grid.poses[worst.0];
            return Err(FlankError::RigidityNotMet {
                strip: pose.strip,
                pose: pose.j,
                error_mm: worst.1,
                tolerance_mm: o.rigidity_tolerance_rel * l,
            });
        }
        weights.rigid *= 10.0;
        report.rigid_weight = weights.rigid;
    }
    // The poses are read with the normals refreshed at the final grid.
    grid.normals.clone_from(&normals);
    let objective = Objective::new(&grid, normals, feet, m_ini.clone(), weights);
    report.final_terms = objective.evaluate(&x, None);
    report.final_figures = figures(tree, &grid, &x, k, &objective);
    grid.m = x.chunks(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
    report.max_move_mm = grid.m.iter().zip(&m_ini).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
    let mut rails = Vec::with_capacity(grid.poses.len());
    for p in &grid.poses {
        let (a, b) = grid.rails(p);
        let (mid, u) = (0.5 * (a + b), (b - a).normalize());
        let (ra, rb) = (mid - 0.5 * l * u, mid + 0.5 * l * u);
        report.rigid_projection_mm = report.rigid_projection_mm.max(ra.distance(a)).max(rb.distance(b));
        rails.push((ra, rb));
    }
    Ok(Optimised { grid, rails, report })
}

fn dist3(p: &[f64], q: &[f64]) -> f64 {
    DVec3::new(p[0] - q[0], p[1] - q[1], p[2] - q[2]).length()
}

/// The normal at the nearest mesh point of every grid point (the previous normal where the
/// query finds nothing, which a finite point always does).
fn refresh_normals(surface: &Surface, tree: &FaceTree, x: &[f64], previous: &[DVec3]) -> Vec<DVec3> {
    x.chunks(3)
        .zip(previous)
        .map(|(c, &prev)| match tree.nearest(DVec3::new(c[0], c[1], c[2]), f64::INFINITY) {
            Some(near) => surface.normal_at(near.face, near.bary),
            None => prev,
        })
        .collect()
}

/// Footpoints and normals of every axis sample (eq. 11) of every pose.
fn footpoints(
    surface: &Surface,
    tree: &FaceTree,
    grid: &Grid,
    x: &[f64],
    normals: &[DVec3],
    k: usize,
) -> Vec<Footpoint> {
    let mut out = Vec::with_capacity(grid.poses.len() * k);
    let h = 0.5 * grid.family.delta_r_mm;
    for (index, p) in grid.poses.iter().enumerate() {
        let a = super::objective::point(x, p.lower) - h * normals[p.lower];
        let b = super::objective::point(x, p.upper) + h * normals[p.upper];
        for kk in 0..k {
            let s = Grid::s_k(kk, k);
            let y = (1.0 - s) * a + s * b;
            let r = grid.family.radius_at(s);
            if let Some(near) = tree.nearest(y, f64::INFINITY) {
                let n = surface.normal_at(near.face, near.bary);
                out.push(Footpoint { pose: index as u32, s, r, normal: n, offset: near.point.dot(n) });
            }
        }
    }
    out
}

/// The pose with the largest rigidity error and that error, mm.
fn worst_rigidity(grid: &Grid, x: &[f64], normals: &[DVec3]) -> (usize, f64) {
    let h = 0.5 * grid.family.delta_r_mm;
    let mut worst = (0, 0.0);
    for (i, p) in grid.poses.iter().enumerate() {
        let a = super::objective::point(x, p.lower) - h * normals[p.lower];
        let b = super::objective::point(x, p.upper) + h * normals[p.upper];
        let e = (a.distance(b) - grid.family.length_mm).abs();
        if e > worst.1 {
            worst = (i, e);
        }
    }
    worst
}

/// [`GridFigures`] of the grid `x` read with the objective's frozen normals.
fn figures(tree: &FaceTree, grid: &Grid, x: &[f64], k: usize, obj: &Objective) -> GridFigures {
    let h = 0.5 * grid.family.delta_r_mm;
    let rails = |p: &super::rails::Pose| {
        (
            super::objective::point(x, p.lower) - h * obj.normals[p.lower],
            super::objective::point(x, p.upper) + h * obj.normals[p.upper],
        )
    };
    let mut f = GridFigures {
        max_distance_error_mm: f64::NEG_INFINITY,
        min_distance_error_mm: f64::INFINITY,
        ..GridFigures::default()
    };
    for p in &grid.poses {
        let (a, b) = rails(p);
        f.max_rigidity_error_mm = f.max_rigidity_error_mm.max((a.distance(b) - grid.family.length_mm).abs());
        for kk in 0..k {
            let s = Grid::s_k(kk, k);
            let y = (1.0 - s) * a + s * b;
            if let Some(near) = tree.nearest(y, f64::INFINITY) {
                let e = near.distance - grid.family.radius_at(s);
                f.max_distance_error_mm = f.max_distance_error_mm.max(e);
                f.min_distance_error_mm = f.min_distance_error_mm.min(e);
            }
        }
    }
    for s in &obj.seams {
        let n = obj.normals[s.shared as usize];
        let (a1, b1) = rails(&grid.poses[s.below as usize]);
        let (a2, b2) = rails(&grid.poses[s.above as usize]);
        let angle = |u: DVec3| num::acos((n.dot(u) / u.length()).clamp(-1.0, 1.0));
        f.max_g1_angle_deg = f.max_g1_angle_deg.max((angle(b1 - a1) - angle(b2 - a2)).abs().to_degrees());
    }
    if !f.max_distance_error_mm.is_finite() {
        f.max_distance_error_mm = 0.0;
        f.min_distance_error_mm = 0.0;
    }
    f
}
