//! Stage `origin`: the pole of the slit map (the point mapped to the spiral's centre) that makes
//! the predicted scallop height most uniform (seed 000 §2.3, App. C; DESIGN.md "origin").
//!
//! # What it computes
//! For a pole p the slit map gives r = |w| per vertex; the scalar field T = f(r) with f monotone,
//! f(R_min) = 0 (R_min = 0 for a disk map, the inner radius for an annulus map) has iso-curves
//! that are the rings of the spiral. The scallop height between adjacent iso-curves is
//! h ≈ |ΔT|² (κ_n + K_c) / (8|∇T|²) (seed eq. 15) with κ_n the surface's normal curvature along
//! ∇T and K_c = 1/R the tool curvature (the seed writes "tool radius"; by dimension it is the
//! curvature). The energy E^S (seed eq. 17 / C-5) sums A_F (a_F + 1/a_F), a_F = (κ_F + 1/R) /
//! (8|∇T_F|²), over the faces F.
//!
//! ∇T = f′(r)∇r, so the curvature direction does not depend on f: it is the 3D gradient of r
//! on each face, computed from the P1 gradient of w (radial direction, conformal scale |F′|; see
//! [`EnergyEvaluator`] for why not from the P1 interpolant of |w|). With f piecewise linear over `bins` equal radius bins of
//! [R_min, 1] and slope s_j in bin j, the energy of bin j is Σ_F A_F (α_F/s_j² + β_F s_j²) with
//! α_F = (κ_F + 1/R)/(8|∇r_F|²), β_F = 8|∇r_F|²/(κ_F + 1/R), whose minimum over s_j > 0 is
//! 2·sqrt(Σα·Σβ) at s_j² = sqrt(Σα/Σβ): a closed form replacing App. C's perturbation iteration.
//! E_min(p) = Σ_j of those (seed eq. 18), O(faces) after the slit map ([`EnergyEvaluator`]).
//! A face whose radius range spans several bins is split between them in proportion to the
//! overlap, so E_min is continuous in the pole. By Cauchy–Schwarz E_min ≥ 2·(energy area), with
//! equality exactly when the predicted scallop is uniform: [`Energy::uniformity`] is that ratio.
//!
//! Faces with κ_n + 1/R ≤ 0 along ∇r are where the ball is larger than the concave curvature:
//! a **gouge risk**, excluded from the energy and reported with their area, never clamped.
//!
//! [`find_origin`] then minimises E_min over poles (seed eqs. 19–22, Pseudocode C-2; `search`):
//! the annulus option of every hole (E_min is constant over a hole), then gradient descent from
//! several deterministic starts (the centroid pole and points spread over the domain) with a
//! forward-difference gradient (eq. 20) whose step is relative to the domain size, backtracking
//! steps (eq. 21's shrinking step), and, when a step lands in a hole, the jump to the best point
//! of the hole's offset curve (eq. 22). Poles outside, on or too near a boundary are skipped.
//!
//! # Preconditions
//! `domain` is the flattening of `surface` (same vertices, triangles and loops) and `solver` was
//! built on it; `surface.curvature` has one tensor per face (the mesh stage computes them).
//!
//! # Invariants of the output
//! `uniformity ≥ 1` (up to rounding); for `Auto`, the chosen pole folds no more faces than the
//! centroid and, folding as many, has `energy.e_min ≤ centroid_energy.e_min` (the centroid is
//! the first start; a pole whose map folds is worse whatever its E_min: the P1 map, and E_min
//! with it, is wrong there — featuretype's best E_min folded 188 faces and left 84% uncut);
//! `trace` lists every successful evaluation in order and `evaluations ≤ max_evaluations`; the
//! same input gives the same output bit for bit (no hash order, transcendental functions from
//! [`crate::num`] only).

mod energy;
mod locate;
mod search;

pub use energy::{Energy, EnergyEvaluator};
pub(crate) use locate::away_from_boundary;
pub use locate::{centroid_pole, pole_from_3d, pole_to_3d};

use crate::mesh::Surface;
use crate::slitmap::{Mode, PlanarDomain, SlitMap, SlitMapError, SlitMapSolver};
use glam::{DVec2, DVec3};
use serde::Serialize;

/// How the pole is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OriginChoice {
    /// Minimise E_min over poles (seed eqs. 19–22).
    Auto,
    /// The area centroid of the flattened domain ([`centroid_pole`]).
    Centroid,
    /// The surface point nearest to this point of the part's coordinates ([`pole_from_3d`]).
    Point3d(DVec3),
    /// The annulus map of hole `n` (loop index, 1-based): its canonical pole.
    Hole(usize),
    /// A pole given directly in the flattened plane (the page's "click to place").
    Plane(DVec2),
}

/// Options of the origin stage.
#[derive(Debug, Clone, PartialEq)]
pub struct OriginOptions {
    /// Ball radius R, mm; the tool curvature is 1/R. Default 3.0.
    pub radius_mm: f64,
    /// Number of radius bins of the piecewise-linear f (seed App. C's p). Default 32.
    pub bins: usize,
    /// Starting points of the gradient search (the centroid first). Default 3 (a fourth found
    /// the same pole on every fixture and every shared mesh, for 8–45 % more evaluations).
    pub starts: usize,
    /// Budget of E_min evaluations (one slit map each) for the whole search. Default 400.
    pub max_evaluations: usize,
    /// A descent stops when its step falls below this fraction of the domain size
    /// (bounding-box diagonal of the flattened plane). Default 1e-3 (the brute-force grid of
    /// tests/origin.rs is beaten with it; 1e-4 cost a fifth more evaluations for nothing).
    pub tolerance_rel: f64,
    /// Default [`OriginChoice::Auto`].
    pub choice: OriginChoice,
}

impl Default for OriginOptions {
    fn default() -> Self {
        Self {
            radius_mm: 3.0,
            bins: 32,
            starts: 3,
            max_evaluations: 400,
            tolerance_rel: 1e-3,
            choice: OriginChoice::Auto,
        }
    }
}

/// Errors of the origin stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OriginError {
    #[error("invalid origin option: {0}")]
    InvalidOption(String),
    #[error("slit map: {0}")]
    SlitMap(#[from] SlitMapError),
    #[error("no feasible pole was found: every pole tried lies on a boundary or gives no finite energy; choose a pole explicitly")]
    NoFeasiblePole,
    #[error("the scallop energy is not finite for pole ({}, {}){}: the slit radius has no gradient there; choose another pole", pole.x, pole.y, face.map_or(String::new(), |f| format!(" at face {f}")))]
    NotFinite { pole: DVec2, face: Option<usize> },
    #[error("all {faces} faces are a gouge risk for a ball of radius {radius_mm} mm at pole ({}, {}): the ball is larger than every concave radius of the part; use a smaller ball", pole.x, pole.y)]
    AllGougeRisk { faces: usize, radius_mm: f64, pole: DVec2 },
    #[error("surface and flattening do not match: {what}")]
    SurfaceMismatch { what: String },
}

/// The chosen pole and its energy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Origin {
    /// The pole in the flattened plane (for an annulus: the hole's canonical pole).
    #[serde(serialize_with = "ser_v2")]
    pub pole: DVec2,
    /// Its surface point (for an annulus: the 3D centroid of the hole's rim).
    #[serde(serialize_with = "ser_v3")]
    pub pole_3d: DVec3,
    pub mode: Mode,
    pub energy: Energy,
    /// [`centroid_pole`] and its energy, for comparison.
    #[serde(serialize_with = "ser_v2")]
    pub centroid_pole: DVec2,
    pub centroid_energy: Energy,
    /// E_min evaluations made (slit maps solved), at most `max_evaluations` for `Auto`.
    pub evaluations: usize,
    /// Every successful evaluation (pole, E_min) in order.
    #[serde(serialize_with = "ser_trace")]
    pub trace: Vec<(DVec2, f64)>,
}

impl Origin {
    /// Other poles the search evaluated, lowest E_min first, each at least `separation` (in the
    /// flattened plane) from the chosen pole and from one another; at most `count`. Where
    /// [`OriginChoice::Auto`] turns when the P1 map cannot carry a path from the chosen pole.
    pub fn alternatives(&self, separation: f64, count: usize) -> Vec<DVec2> {
        let mut order: Vec<usize> = (0..self.trace.len()).collect();
        order.sort_by(|&a, &b| self.trace[a].1.total_cmp(&self.trace[b].1).then(a.cmp(&b)));
        let mut out: Vec<DVec2> = Vec::new();
        for i in order {
            let p = self.trace[i].0;
            if p.distance(self.pole) >= separation && out.iter().all(|q| q.distance(p) >= separation) {
                out.push(p);
                if out.len() == count {
                    break;
                }
            }
        }
        out
    }
}

fn ser_v2<S: serde::Serializer>(v: &DVec2, s: S) -> Result<S::Ok, S::Error> {
    v.to_array().serialize(s)
}
fn ser_v3<S: serde::Serializer>(v: &DVec3, s: S) -> Result<S::Ok, S::Error> {
    v.to_array().serialize(s)
}
fn ser_trace<S: serde::Serializer>(t: &[(DVec2, f64)], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(t.iter().map(|(p, e)| [p.x, p.y, *e]))
}

/// Chooses the pole (see the module docs) and returns it with its energy and the centroid's.
pub fn find_origin(
    surface: &Surface,
    domain: &PlanarDomain,
    solver: &SlitMapSolver,
    options: &OriginOptions,
) -> Result<Origin, OriginError> {
    Ok(find_origin_and_map(surface, domain, solver, options)?.0)
}

/// [`find_origin`], and the pole's slit map (`solver.map(origin.pole)`), which the search has
/// solved already.
pub fn find_origin_and_map(
    surface: &Surface,
    domain: &PlanarDomain,
    solver: &SlitMapSolver,
    options: &OriginOptions,
) -> Result<(Origin, SlitMap), OriginError> {
    check_options(options)?;
    if domain.positions.len() != surface.positions.len() || domain.triangles.len() != surface.triangles.len() {
        return Err(OriginError::SurfaceMismatch {
            what: format!(
                "the domain has {} vertices and {} triangles, the surface {} and {}",
                domain.positions.len(),
                domain.triangles.len(),
                surface.positions.len(),
                surface.triangles.len()
            ),
        });
    }
    let ev = EnergyEvaluator::new(surface, solver, options)?;
    let centroid = centroid_pole(domain);
    let (centroid_energy, centroid_map) = ev.evaluate_with_map(centroid)?;
    let Picked { pole, energy, map, evaluations, trace } = match options.choice {
        OriginChoice::Auto => {
            let mut s = search::Search::new(&ev, domain, options.max_evaluations, options.tolerance_rel);
            s.record(centroid, centroid_energy.clone(), centroid_map);
            s.run(centroid, centroid_energy.e_min, options.starts);
            let (pole, energy, map) = s.best.ok_or(OriginError::NoFeasiblePole)?;
            Picked { pole, energy, map, evaluations: s.evaluations, trace: s.trace }
        }
        OriginChoice::Centroid => Picked {
            pole: centroid,
            energy: centroid_energy.clone(),
            map: centroid_map,
            evaluations: 1,
            trace: vec![(centroid, centroid_energy.e_min)],
        },
        OriginChoice::Point3d(p) => single(&ev, centroid, &centroid_energy, pole_from_3d(surface, domain, p))?,
        OriginChoice::Hole(n) => {
            let holes = solver.hole_count();
            if n == 0 || n > holes {
                return Err(OriginError::InvalidOption(format!(
                    "choice hole:{n} does not exist: the part has {holes} holes (numbered 1 to {holes})"
                )));
            }
            single(&ev, centroid, &centroid_energy, solver.canonical_hole_pole(n))?
        }
        OriginChoice::Plane(z) => single(&ev, centroid, &centroid_energy, z)?,
    };
    let hole = match energy.mode {
        Mode::Disk => None,
        Mode::Annulus { hole, .. } => Some(hole),
    };
    let origin = Origin {
        pole,
        pole_3d: pole_to_3d(surface, domain, pole, hole),
        mode: energy.mode,
        energy,
        centroid_pole: centroid,
        centroid_energy,
        evaluations,
        trace,
    };
    Ok((origin, map))
}

/// An explicit pole: its energy, two evaluations (the centroid's and its own).
fn single(ev: &EnergyEvaluator, centroid: DVec2, centroid_energy: &Energy, pole: DVec2) -> Result<Picked, OriginError> {
    let (energy, map) = ev.evaluate_with_map(pole)?;
    let trace = vec![(centroid, centroid_energy.e_min), (pole, energy.e_min)];
    Ok(Picked { pole, energy, map, evaluations: 2, trace })
}

/// The pole picked by a choice, before its 3D point is computed.
struct Picked {
    pole: DVec2,
    energy: Energy,
    map: SlitMap,
    evaluations: usize,
    trace: Vec<(DVec2, f64)>,
}

/// The options the energy needs (radius, bins).
fn check_energy_options(o: &OriginOptions) -> Result<(), OriginError> {
    if !(o.radius_mm.is_finite() && o.radius_mm > 0.0) {
        return Err(OriginError::InvalidOption(format!(
            "radius_mm = {} must be a finite ball radius > 0 (mm)",
            o.radius_mm
        )));
    }
    if o.bins == 0 || o.bins > 1 << 20 {
        return Err(OriginError::InvalidOption(format!("bins = {} must be between 1 and {}", o.bins, 1 << 20)));
    }
    Ok(())
}

fn check_options(o: &OriginOptions) -> Result<(), OriginError> {
    check_energy_options(o)?;
    if o.starts == 0 {
        return Err(OriginError::InvalidOption("starts = 0 must be at least 1".into()));
    }
    if o.max_evaluations == 0 {
        return Err(OriginError::InvalidOption("max_evaluations = 0 must be at least 1".into()));
    }
    if !(o.tolerance_rel.is_finite() && o.tolerance_rel > 0.0 && o.tolerance_rel < 1.0) {
        return Err(OriginError::InvalidOption(format!("tolerance_rel = {} must be in (0, 1)", o.tolerance_rel)));
    }
    match o.choice {
        OriginChoice::Point3d(p) if !p.is_finite() => {
            Err(OriginError::InvalidOption(format!("choice point3d {p} must be finite")))
        }
        OriginChoice::Plane(z) if !z.is_finite() => {
            Err(OriginError::InvalidOption(format!("choice plane {z} must be finite")))
        }
        _ => Ok(()),
    }
}
