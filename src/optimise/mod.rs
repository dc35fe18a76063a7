//! Stage `optimise` (between `origin` and `spacing`): seed 003's topology-preserving
//! scalar-field optimisation, so that the rings follow the surface instead of the slit map's
//! circles.
//!
//! # What it computes
//! The spiral's rings are the level sets of T = |w|; each is spaced for its worst point, and
//! wherever the conformal factor varies along a ring (round holes and their slit tips, the
//! corners of a rectangle, a jagged rim, a long part) the rest of that ring is cut finer than
//! asked. Seed 003 moves the field's values instead: the slit domain S^S is mapped to S^H by
//! moving each vertex along its ray from the pole (§2.3.1: only radial moves change T, the
//! angles are kept), T = |V^H| (eq. 25–26), and E = E_w + α·E_k (eqs. 5–14, [`energy`]) is
//! minimised over the radii under the two constraints that keep the level sets a foliation
//! that conforms to every boundary:
//!
//! 1. no S^H triangle inverts (then ∇T ≠ 0 inside and the rings never branch, §2.3.1);
//!    checked in the w plane and, for faces narrower than 0.5 rad, in the log-polar strip the
//!    inverse map locates in, after every step;
//! 2. each boundary stays a level set: the outer loop is fixed at |w| = 1, each hole moves as
//!    one shared radius (a slit stays an arc, the annulus' inner circle a circle), eq. 28, 31.
//!
//! The pole stays at w = 0 (its face's vertices move radially, and the origin stays inside a
//! triangle whose angles do not change). The start is eq. 24: the radii remapped by the
//! origin's f_min ([`field::initial_radii`]). The result is a slit map on the same triangles
//! ([`SlitMap::with_radii`]) that the spacing, the spiral and the inverse lift use unchanged:
//! its rings are the preimages of circles of S^H, and the spacing still proves each of them
//! (meridian cusps, gate, facet lifts) on the surface, whatever the map.
//!
//! # Decisions where the paper is silent or wrong (see [`energy`] for the energy's)
//! * **Scale** ([`Scale`], default [`Scale::PerLevel`]): the paper's E_w fixes the scale of T,
//!   so on a part that is not round it trades the uniformity along each level against an
//!   absolute gradient that the fixed outer boundary cannot give everywhere. The spacing picks
//!   every ring's step itself, so the default minimises E_w over the scale of each level of T
//!   (seed 000's closed form per level), which measures exactly the uniformity along levels.
//! * **α** is given on the paper's scale and weighed by the part's area over 10⁴ mm²
//!   ([`OptimiseOptions::alpha`]): E_w is an area, E_k is not.
//! * **Step** ([`Step`], default [`Step::Newton`]): eq. 32's sigmoid step on the raw gradient
//!   is kept ([`Step::Sigmoid`], C = 0.9), but it moves the field by about one ring of
//!   vertices per iteration; the default solves the Gauss–Newton system of E (with E_g's
//!   fourth-order part and a log barrier on the strip triangles, see [`energy`]) for the
//!   direction (one sparse factorisation per iteration, pattern analysed once). Both halve the
//!   step when a triangle inverts or E rises. Scaling each vertex's Newton move into its
//!   interval of eq. 30 was tried and dropped: neighbours then moved by different fractions of
//!   a smooth step, which wrinkled the field and raised E at every step.
//! * **The core round the pole keeps its start radii**: faces wider than 0.15 rad there are
//!   where the strip's straight triangles and the w plane's disagree by more than the rings'
//!   spacing, and the spacing could not prove rings placed there (gen006: 30 bands given up,
//!   5 with the core kept).
//! * **Stopping**: E's relative decrease over an iteration below `tolerance_rel` (10⁻³), no
//!   step that keeps the triangles and lowers E after 40 halvings, or `max_iterations` (30)
//!   ([`Stop`], reported).
//! * With `max_iterations = 0` the stage returns the slit map unchanged (not even eq. 24's
//!   remap): the seed-000 path, bit for bit.
//!
//! The planner spaces an optimised field's rings for 0.92 h (the conformal map's for 0.95 h),
//! verifies the path like any other, and where it leaves more than h while the conformal map's
//! does not, or the optimised field's plan fails, keeps the conformal map's path and says why
//! ([`crate::plan::OptimiseSummary`]).
//!
//! # Preconditions
//! `map` is a slit map of `surface` (same vertices and triangles, `surface.loops` its loops),
//! `slopes` the origin's f_min per radius bin; R > 0; α ≥ 0.
//!
//! # Invariants of the output
//! No face of the returned map is inverted that was not at the start, in the w plane or the
//! strip; every hole's vertices share one radius; the outer loop is at 1 and every angle is
//! the input's; the energy is never above the start's.

// `!(x > 0.0)` is meant: a NaN must count as a failed check. The 3×3 blocks read best indexed.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

mod descent;
pub mod energy;
mod field;

pub use energy::{EnergyParts, Scale};

use crate::linalg::LinalgError;
use crate::mesh::Surface;
use crate::slitmap::SlitMap;
use serde::Serialize;

/// The area α is given for (see [`OptimiseOptions::alpha`]): a part about 100 mm across.
pub const ALPHA_AREA_MM2: f64 = 1e4;

/// μ of the strip barrier ([`energy::EnergyModel::new`]): 0.1 A per face where a level set
/// leans to 25° off its meridian, against E_w's 2 A.
const BARRIER: f64 = 0.1;

/// Options of the optimise stage. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimiseOptions {
    /// Ball radius R, mm (K_c = 1/R). Default 3.
    pub radius_mm: f64,
    /// α of eq. 14 as the paper gives it for its parts, about [`ALPHA_AREA_MM2`] in area.
    /// Default 10 (the paper's only reported value). E_w is an area and E_k is dimensionless,
    /// so the stage weighs E_k by α·(area / [`ALPHA_AREA_MM2`]): the same balance on a part of
    /// any size (10 on a 1 mm part would let the level sets' curvature outweigh everything).
    pub alpha: f64,
    /// Default [`Scale::PerLevel`].
    pub scale: Scale,
    /// Default [`Step::Newton`].
    pub step: Step,
    /// Level bins of [`Scale::PerLevel`]. Default 32 (the origin's).
    pub bins: usize,
    /// Default 30. 0 returns the map unchanged.
    pub max_iterations: usize,
    /// Stop when an iteration lowers E by less than this fraction. Default 1e-3.
    pub tolerance_rel: f64,
}

impl Default for OptimiseOptions {
    fn default() -> Self {
        Self {
            radius_mm: 3.0,
            alpha: 10.0,
            scale: Scale::PerLevel,
            step: Step::Newton,
            bins: 32,
            max_iterations: 30,
            tolerance_rel: 1e-3,
        }
    }
}

/// How a step is found (see [`descent`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Step {
    /// Gauss–Newton direction, full step halved as needed.
    Newton,
    /// Seed 003 eqs. 30–32 with constant `c` ∈ (0.5, 1) (the paper: 0.9).
    Sigmoid { c: f64 },
}

/// Why the descent ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stop {
    /// An iteration lowered E by less than `tolerance_rel`.
    Converged,
    /// `max_iterations` reached.
    IterationCap,
    /// No step along the direction kept the triangles and lowered E.
    NoDescent,
    /// The direction was not a descent direction (zero gradient).
    Stationary,
}

/// Errors of the optimise stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptimiseError {
    #[error("invalid optimise option: {0}")]
    InvalidOption(String),
    #[error("the slit map has {map} vertices and {map_faces} triangles, the surface {surface} and {surface_faces}: they must come from the same mesh")]
    MeshMismatch { map: usize, map_faces: usize, surface: usize, surface_faces: usize },
    #[error("the scalar-field energy is not finite at the start: the slit map has no gradient somewhere")]
    NotFinite,
    #[error("the optimisation's linear system: {0}")]
    Linalg(#[from] LinalgError),
}

/// What the optimisation did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptimiseReport {
    /// Accepted steps.
    pub iterations: usize,
    /// Step halvings (inverted triangles or E risen).
    pub halvings: usize,
    pub stop: Stop,
    pub scale: Scale,
    pub alpha: f64,
    /// E at the start (eq. 24's field) and at the end.
    pub before: EnergyParts,
    pub after: EnergyParts,
    /// E_w over twice the energy's area (≥ 1 with the optimal scales; 1 = the predicted scallop
    /// is uniform along every level), at the start and the end.
    pub uniformity_before: f64,
    pub uniformity_after: f64,
    /// Faces left out of the energy (the pole's, boundary ears).
    pub excluded_faces: usize,
}

/// The optimised map and the report.
#[derive(Debug, Clone)]
pub struct Optimised {
    pub map: SlitMap,
    /// `None` when nothing was optimised (`max_iterations = 0`).
    pub report: Option<OptimiseReport>,
}

fn check(surface: &Surface, map: &SlitMap, options: &OptimiseOptions) -> Result<(), OptimiseError> {
    let bad = |m: String| Err(OptimiseError::InvalidOption(m));
    if !(options.radius_mm.is_finite() && options.radius_mm > 0.0) {
        return bad(format!("ball radius {} mm must be a positive number", options.radius_mm));
    }
    if !(options.alpha.is_finite() && options.alpha >= 0.0) {
        return bad(format!("α {} must be a number ≥ 0", options.alpha));
    }
    if options.bins == 0 {
        return bad("at least one level bin is needed".into());
    }
    if !(options.tolerance_rel >= 0.0 && options.tolerance_rel < 1.0) {
        return bad(format!("relative tolerance {} must be in [0, 1)", options.tolerance_rel));
    }
    if let Step::Sigmoid { c } = options.step {
        if !(c > 0.5 && c < 1.0) {
            return bad(format!("the sigmoid constant C = {c} must be in (0.5, 1) (seed 003 eq. 32)"));
        }
    }
    if map.w.len() != surface.positions.len() || map.triangles().len() != surface.triangles.len() {
        return Err(OptimiseError::MeshMismatch {
            map: map.w.len(),
            map_faces: map.triangles().len(),
            surface: surface.positions.len(),
            surface_faces: surface.triangles.len(),
        });
    }
    Ok(())
}

/// One-off entry: the optimised slit map of `map` on `surface`, starting from the origin's
/// radial function (`slopes` per radius bin, [`crate::origin::Energy::slopes`]).
pub fn optimise(
    surface: &Surface,
    map: &SlitMap,
    slopes: &[f64],
    options: &OptimiseOptions,
) -> Result<Optimised, OptimiseError> {
    optimise_observed(surface, map, slopes, options, &mut |_, _| {})
}

/// [`optimise`], calling `on_step(radii, energy)` after every accepted step.
pub fn optimise_observed(
    surface: &Surface,
    map: &SlitMap,
    slopes: &[f64],
    options: &OptimiseOptions,
    on_step: &mut dyn FnMut(&[f64], &EnergyParts),
) -> Result<Optimised, OptimiseError> {
    check(surface, map, options)?;
    if options.max_iterations == 0 {
        return Ok(Optimised { map: map.clone(), report: None });
    }
    let (r0, s) = field::initial_radii(map, slopes);
    let field = field::Field::new(surface, map, &r0);
    // Holes share one radius, the outer loop sits at 1 exactly.
    let x0 = field.unknowns(&r0);
    let r_start = field.radii(&x0);
    let r_min = map.mode.inner_radius();
    let settings = energy::Settings {
        radius_mm: options.radius_mm,
        alpha: options.alpha * surface.area() / ALPHA_AREA_MM2,
        scale: options.scale,
        fixed_s2: s * s,
        bins: options.bins,
        r_min,
        barrier: BARRIER,
    };
    let model = energy::EnergyModel::new(surface, &r_start, map.pole_face, &field.strip_angles(), &settings);
    let out = descent::descend(&model, &field, x0, options, on_step)?;
    let radii = field.radii(&out.x);
    let area = model.area();
    let report = OptimiseReport {
        iterations: out.iterations,
        halvings: out.halvings,
        stop: out.stop,
        scale: options.scale,
        alpha: options.alpha,
        before: out.before,
        after: out.after,
        uniformity_before: out.before.e_w / (2.0 * area),
        uniformity_after: out.after.e_w / (2.0 * area),
        excluded_faces: model.excluded_faces(),
    };
    Ok(Optimised { map: map.with_radii(&radii, &surface.loops), report: Some(report) })
}
