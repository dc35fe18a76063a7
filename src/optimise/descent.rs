//! The moves of the radii (seed 003 §2.3.2): a descent direction, a step, and the check that
//! keeps every accepted step valid (no S^H triangle inverted, E not risen).
//!
//! Two steps:
//! * [`Step::Sigmoid`], the paper's: the raw gradient (eqs. 27–29), each unknown's feasible
//!   interval from the convex hull of its one ring's angle bisectors (eqs. 30–31), and the
//!   sigmoid of eq. 32 mapping the gradient into those intervals (C = 0.9 moves the most
//!   constrained unknown 2C − 1 = 80 % of its interval).
//! * [`Step::Newton`], ours: the Gauss–Newton matrix of E (E_w's along and across ∇T, the strip
//!   barrier's and α·E_g's, [`EnergyModel::gauss_newton_at`] and
//!   [`EnergyModel::smoothness_gauss_newton_at`], on the same unknowns; analysed once, refactorised
//!   numerically each iteration) solved for the direction, then the full step. A raw gradient
//!   step moves one ring of vertices per iteration while the field needs moves across the
//!   whole part: the paper reports 298 s for one surface.
//!
//! Both then halve the step until no face inverts (the intervals of eq. 30 are for one vertex
//! moving alone; simultaneous moves of neighbours can still invert a face) and E does not
//! rise (Armijo, 1e-4).

use super::energy::{EnergyModel, EnergyParts, Evaluated};
use super::field::Field;
use super::{OptimiseError, OptimiseOptions, Step, Stop};
use crate::linalg::{mesh_order, restrict_order, LinalgError, SparseCholesky};
use glam::DVec2;

/// Where the descent ended.
pub(super) struct Outcome {
    pub x: Vec<f64>,
    pub before: EnergyParts,
    pub after: EnergyParts,
    pub iterations: usize,
    pub halvings: usize,
    pub stop: Stop,
}

/// Halvings of one step before the descent stops.
const MAX_HALVINGS: usize = 40;

/// Descends from `x` (the unknowns) until a stopping rule of `options` holds. `on_step` is
/// called after every accepted step with the new radii (tests check invariants there).
pub(super) fn descend(
    model: &EnergyModel,
    field: &Field,
    x: Vec<f64>,
    options: &OptimiseOptions,
    on_step: &mut dyn FnMut(&[f64], &EnergyParts),
) -> Result<Outcome, OptimiseError> {
    let mut x = x;
    let mut r = field.radii(&x);
    let mut grad_v = vec![0.0; r.len()];
    // The current field's intermediate values: its gradient and Gauss–Newton matrices read them.
    let (mut energy, mut at) = model.evaluate_at(&r);
    model.gradient_at(&at, &mut grad_v);
    if !energy.total.is_finite() {
        return Err(OptimiseError::NotFinite);
    }
    let before = energy;
    let mut system: Option<NewtonSystem> = None;
    let mut halvings = 0;
    let mut t0: f64 = 1.0;
    let mut stop = Stop::IterationCap;
    let mut iterations = 0;
    while iterations < options.max_iterations {
        let g = field.gather(&grad_v);
        let direction = match options.step {
            Step::Newton => newton_direction(model, field, &r, &at, &g, &mut system)?,
            Step::Sigmoid { c } => sigmoid_move(field, &r, &x, &g, c),
        };
        let slope: f64 = g.iter().zip(&direction).map(|(a, b)| a * b).sum();
        if !(slope < 0.0) {
            stop = Stop::Stationary;
            break;
        }
        // Halve until valid and not risen.
        let mut t = t0;
        let accepted = loop {
            let trial: Vec<f64> = x.iter().zip(&direction).map(|(a, d)| a + t * d).collect();
            let tr = field.radii(&trial);
            if field.valid(&tr) {
                let (e, trial_at) = model.evaluate_at(&tr);
                if e.total <= energy.total + 1e-4 * t * slope {
                    break Some((trial, tr, e, trial_at));
                }
            }
            halvings += 1;
            t *= 0.5;
            if t < t0 * 0.5f64.powi(MAX_HALVINGS as i32) {
                break None;
            }
        };
        let Some((trial, tr, trial_energy, trial_at)) = accepted else {
            stop = Stop::NoDescent;
            break;
        };
        iterations += 1;
        // The next step starts from twice this one (the full step for Newton).
        t0 = (2.0 * t).min(1.0);
        let drop = energy.total - trial_energy.total;
        x = trial;
        r = tr;
        (energy, at) = (trial_energy, trial_at);
        model.gradient_at(&at, &mut grad_v);
        on_step(&r, &energy);
        if drop <= options.tolerance_rel * energy.total {
            stop = Stop::Converged;
            break;
        }
    }
    Ok(Outcome { x, before, after: energy, iterations, halvings, stop })
}

/// The Gauss–Newton system on the unknowns. Its pattern is analysed once; later iterations
/// accumulate the values straight into their slots of the factorisation and refactorise.
struct NewtonSystem {
    chol: SparseCholesky,
    /// Per entry of the faces' 3×3 blocks (row-major), its lower slot, or [`NONE`] for the
    /// upper triangle and fixed vertices (the lower mirror carries the value).
    block_slots: Vec<u32>,
    /// Per value of [`EnergyModel::smoothness_gauss_newton_at`]'s terms (in the order of
    /// [`EnergyModel::smoothness_pattern`]), likewise.
    smooth_slots: Vec<u32>,
    /// The diagonals of the unknowns no face touches (vertices of the skipped pole face only):
    /// a unit there makes their direction −g = 0.
    unit_slots: Vec<u32>,
    /// Every unknown's diagonal.
    diagonal_slots: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl NewtonSystem {
    fn new(
        model: &EnergyModel,
        field: &Field,
        r: &[f64],
        blocks: &Blocks,
        smooth: &Smooth,
    ) -> Result<Self, OptimiseError> {
        let unknown = |v: u32| field.unknown[v as usize];
        let corner_pairs = |&(c, _): &([u32; 3], _)| (0..9).map(move |e| (c[e / 3], c[e % 3]));
        let mut touched = vec![false; field.n_unknowns];
        for (corners, _) in blocks {
            for &c in corners {
                if let Some(u) = unknown(c) {
                    touched[u] = true;
                }
            }
        }
        let untouched: Vec<usize> = (0..field.n_unknowns).filter(|&k| !touched[k]).collect();
        // The pattern's lower triangle and every diagonal (counted first, so that the vector
        // holds no spare room), analysed without a factorisation (the values follow through
        // `refactor`), so that these pairs are freed before the factor is allocated.
        let lower = |(a, b): (u32, u32)| match (unknown(a), unknown(b)) {
            (Some(ua), Some(ub)) if ua >= ub => Some((ua as u32, ub as u32)),
            _ => None,
        };
        let pairs = || {
            let faces = blocks.iter().flat_map(corner_pairs);
            let diagonal = (0..field.n_unknowns as u32).map(|k| (k, k));
            model.smoothness_pattern().chain(faces).filter_map(lower).chain(diagonal)
        };
        let mut pattern = Vec::with_capacity(pairs().count());
        pattern.extend(pairs());
        // E_g couples each vertex's star: its own AMD order then (the mesh's otherwise).
        let order = match model.couples_stars() {
            true => None,
            false => Some(restrict_order(&mesh_order(r.len(), field.triangles())?, &field.unknown, field.n_unknowns)),
        };
        let chol = SparseCholesky::analyse(field.n_unknowns, pattern, order.as_deref())?;
        let slot = |a: Option<usize>, b: Option<usize>| match (a, b) {
            (Some(a), Some(b)) if a >= b => chol.lower_slot(a, b).map_or(NONE, |s| s as u32),
            _ => NONE,
        };
        let mut block_slots = Vec::with_capacity(blocks.len() * 9);
        block_slots.extend(blocks.iter().flat_map(corner_pairs).map(|(a, b)| slot(unknown(a), unknown(b))));
        let mut smooth_slots = Vec::with_capacity(smooth.iter().map(|(_, d)| d.len() * d.len()).sum());
        smooth_slots.extend(model.smoothness_pattern().map(|(a, b)| slot(unknown(a), unknown(b))));
        let unit_slots = untouched.iter().map(|&k| slot(Some(k), Some(k))).collect();
        let diagonal_slots = (0..field.n_unknowns).map(|k| slot(Some(k), Some(k))).collect();
        let mut system = Self { chol, block_slots, smooth_slots, unit_slots, diagonal_slots };
        system.refactor(blocks, smooth)?;
        Ok(system)
    }

    fn refactor(&mut self, blocks: &Blocks, smooth: &Smooth) -> Result<(), OptimiseError> {
        let mut values = vec![0.0; self.chol.lower_len()];
        for ((_, block), slots) in blocks.iter().zip(self.block_slots.chunks_exact(9)) {
            for (e, &s) in slots.iter().enumerate() {
                if s != NONE {
                    values[s as usize] += block[e / 3][e % 3];
                }
            }
        }
        let mut smooth_slots = self.smooth_slots.iter();
        for (w, d) in smooth {
            for &da in d {
                for (&db, &s) in d.iter().zip(smooth_slots.by_ref()) {
                    if s != NONE {
                        values[s as usize] += w * da * db;
                    }
                }
            }
        }
        for &s in &self.unit_slots {
            values[s as usize] += 1.0;
        }
        // Faces whose field is nearly flat (beside a slit tip on a coarse rim) weigh up to
        // 10¹² times the others and the factorisation can lose the last bits of positivity: the
        // diagonal is then raised by a growing fraction of itself (Levenberg–Marquardt).
        // The shifted copy is made only when a shift is (rarely) needed: it is the size of A.
        let mut shift = 0.0;
        let mut shifted = Vec::new();
        for _ in 0..SHIFTS {
            let attempt = if shift == 0.0 {
                &values
            } else {
                shifted.clone_from(&values);
                for &s in &self.diagonal_slots {
                    shifted[s as usize] *= 1.0 + shift;
                }
                &shifted
            };
            match self.chol.refactor_lower(attempt) {
                Err(LinalgError::NotPositiveDefinite { .. }) => {
                    shift = if shift == 0.0 { 1e-10 } else { shift * 100.0 }
                }
                other => return Ok(other?),
            }
        }
        Ok(self.chol.refactor_lower(&values)?)
    }
}

/// Diagonal shifts tried before a factorisation failure is reported (1e-10 to 1e-2).
const SHIFTS: usize = 6;

type Blocks = Vec<([u32; 3], [[f64; 3]; 3])>;
type Smooth = Vec<(f64, Vec<f64>)>;

/// The Gauss–Newton direction −K⁻¹ g on the unknowns at the field `r` (evaluated as `at`; the
/// system made on the first call).
fn newton_direction(
    model: &EnergyModel,
    field: &Field,
    r: &[f64],
    at: &Evaluated,
    g: &[f64],
    system: &mut Option<NewtonSystem>,
) -> Result<Vec<f64>, OptimiseError> {
    let (blocks, smooth) = crate::par::join(|| model.gauss_newton_at(at), || model.smoothness_gauss_newton_at(at));
    match system {
        Some(sys) => sys.refactor(&blocks, &smooth)?,
        None => *system = Some(NewtonSystem::new(model, field, r, &blocks, &smooth)?),
    }
    let mut d: Vec<f64> = g.iter().map(|x| -x).collect();
    system.as_ref().expect("made above").chol.solve_in_place(&mut d);
    Ok(d)
}

/// The paper's move (eqs. 30–32): each unknown's feasible interval along its radius, and the
/// sigmoid of the gradient scaled by the most constrained unknown.
fn sigmoid_move(field: &Field, r: &[f64], x: &[f64], g: &[f64], c: f64) -> Vec<f64> {
    let intervals = feasible_intervals(field, r, x);
    // G^{H1}: the gradient over the room in the direction of descent.
    let room: Vec<f64> = g.iter().zip(&intervals).map(|(&gi, &(lo, hi))| if gi < 0.0 { hi } else { -lo }).collect();
    let g1: Vec<f64> = g.iter().zip(&room).map(|(&gi, &w)| if w > 0.0 { -gi / w } else { 0.0 }).collect();
    let max = g1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if !(max > 0.0) {
        return vec![0.0; x.len()];
    }
    // λ = (2/(1 + e^{G^{H2}}) − 1)·room with G^{H2} = ln(1/C − 1)·G^{H1}/max|G^{H1}|.
    let k = crate::num::ln(1.0 / c - 1.0) / max;
    g1.iter().zip(&room).map(|(&v, &w)| (2.0 / (1.0 + crate::num::exp(k * v)) - 1.0) * w).collect()
}

/// (λ², λ¹) per unknown (eqs. 30–31): how far each vertex may move along its radius, inwards
/// (negative) and outwards, and stay on its side of the bisectors of the angles at the other
/// corners of every face round it; a hole's interval is the intersection of its vertices'.
/// Where the hull is open (the annulus' inner circle towards the centre) the arc at half the
/// radius closes it.
fn feasible_intervals(field: &Field, r: &[f64], x: &[f64]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = x.iter().map(|&xi| (-0.5 * xi, 0.5 * xi)).collect();
    let p = |v: u32| field.point(v as usize, r[v as usize]);
    for t in field.triangles() {
        for k in 0..3 {
            let Some(u) = field.unknown[t[k] as usize] else { continue };
            let v = p(t[k]);
            let dir = v / v.length();
            let (a, b) = (p(t[(k + 1) % 3]), p(t[(k + 2) % 3]));
            for (corner, other) in [(a, b), (b, a)] {
                let bis = ((v - corner).normalize_or_zero() + (other - corner).normalize_or_zero()).normalize_or_zero();
                let mut n = DVec2::new(-bis.y, bis.x);
                let d0 = n.dot(v - corner);
                if d0 < 0.0 {
                    n = -n;
                }
                let (d0, s) = (d0.abs(), n.dot(dir));
                if s > 0.0 {
                    out[u].0 = out[u].0.max(-d0 / s);
                } else if s < 0.0 {
                    out[u].1 = out[u].1.min(-d0 / s);
                }
            }
        }
    }
    out
}
