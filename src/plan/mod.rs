//! The whole pipeline, stage by stage: STL → surface → flattening → slit map → optimal pole →
//! rings → spiral → tool positions → G-code, with the scallop verifier beside it (DESIGN.md,
//! "The pipeline"). The CLI's `plan` command and the wasm facade both call [`Planner`], so the
//! page and the CLI produce the same file for the same part and options.
//!
//! [`Planner::new`] does the per-part work once (flattening, both factorisations); each
//! [`Planner::plan`] then costs the origin search and the later stages, so re-planning after the
//! user changes an option is cheap. The core has no clock: callers pass `now` (milliseconds).
//!
//! The G-code header carries the options and the path figures, never timings or versions, so
//! that the output is byte-identical wherever it was planned.

use crate::flatten::{self, FlattenError, FlattenInput, FlattenOptions, Flattening};
use crate::gcode::{self, GcodeError, GcodeOptions, Post};
use crate::mesh::nearest::FaceTree;
use crate::mesh::refine::{refine_hole_rims, RefineOptions};
use crate::mesh::{MeshOutput, MeshReport, Surface};
use crate::optimise::{self, OptimiseError, OptimiseOptions};
use crate::origin::{self, Origin, OriginChoice, OriginError, OriginOptions};
use crate::slitmap::{PlanarDomain, SlitMap, SlitMapError, SlitMapOptions, SlitMapSolver};
use crate::spacing::{Lift, Rings, SpacingError, SpacingIndex, SpacingOptions};
use crate::spiral::{self, Cut, Direction, Spiral, SpiralError, SpiralOptions};
use crate::spread::{SpreadError, SpreadOptions};
use crate::toolpath::{self, Axes, Toolpath, ToolpathError, ToolpathOptions};
use crate::verify::{self, PathMetrics, Verification, VerifyError, VerifyOptions};
use glam::{DVec2, DVec3};
use serde::Serialize;

mod paths;
mod report;
use paths::{Field, Finished, Run};
pub use paths::{SpacingRetry, SpreadSummary, MAX_RETRY_EXCESS, OPTIMISED_TARGET_FRACTION, RETRY_AIM};
pub use report::*;

/// Everything a plan can be asked for. `Default` gives the documented defaults, the same as the
/// CLI's and the page's.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Ball radius R, mm. Default 3.
    pub radius_mm: f64,
    /// Scallop-height limit h, mm. Default 0.02.
    pub scallop_mm: f64,
    /// Default [`OriginChoice::Auto`]. `Auto` and `Centroid` move on to other poles when the map
    /// cannot carry a path from the first (see [`MAX_FALLBACKS`]; reported in the origin's
    /// `rejected`); the other choices are planned as given or not at all.
    pub origin: OriginChoice,
    /// Default inward.
    pub direction: Direction,
    /// Default climb.
    pub cut: Cut,
    /// Default 3-axis along +Z.
    pub axes: Axes,
    /// Default LinuxCNC.
    pub post: Post,
    /// Cutting feed, mm/min. Default 1000.
    pub feed_mm_min: f64,
    /// Lead-in feed, mm/min. Default 300.
    pub plunge_feed_mm_min: f64,
    /// Default 12 000.
    pub spindle_rpm: f64,
    /// `None`: above the highest tool point (see [`ToolpathOptions::safe_z_mm`]).
    pub safe_z_mm: Option<f64>,
    /// Samples of the verifier; 0 skips verification. Default 100 000.
    pub verify_samples: usize,
    /// Part name for the G-code header (sanitised by the post). Default "part".
    pub part_name: String,
    /// How the STL's facets are read. Default [`Facets::Exact`].
    pub facets: Facets,
    /// Whether the slit map's field is optimised before the rings are spaced (seed 003).
    /// Default [`Optimise::Tpsfo`].
    pub optimise: Optimise,
    /// α of seed 003 eq. 14 (path smoothness against scallop uniformity), on the paper's scale
    /// (see [`OptimiseOptions::alpha`]). Default 10.
    pub alpha: f64,
    /// Whether a path whose rings are spread by each meridian's own need ([`crate::spread`]) is
    /// planned first, and written when it keeps h (see `plan/paths.rs`). Default [`RingSpread::None`].
    pub spread: RingSpread,
}

/// How the rings share out along each meridian of the field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RingSpread {
    /// The field's own level sets: every meridian gets the rings its worst one needs.
    None,
    /// The field warped along each meridian by its need ([`crate::spread`]).
    Need,
}

/// The scalar field the rings are level sets of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Optimise {
    /// The slit map's |w| as it is (seed 000).
    None,
    /// Seed 003's topology-preserving scalar-field optimisation ([`crate::optimise`]).
    Tpsfo,
}

/// How the planner reads the facets of the STL.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Facets {
    /// The STL is the part: the ball rides the facets' own normals (recomputed after the
    /// planner's refinement and split at edges turning more than [`CREASE_SPLIT_DEG`], see
    /// [`Surface::with_crease_normals`]), every ball centre is kept off every facet
    /// ([`toolpath::clear_facets`]), and the verifier counts a sample deeper inside the swept
    /// ball than the path's chord tolerance as a gouge.
    Exact,
    /// The STL tessellates a smooth surface: the ball rides the interpolated vertex normals and
    /// may dip into a facet by the facets' own deviation from those normals, R(1 − cos δ)
    /// ([`facet_tolerance_mm`]), and no deeper: a centre nearer than R less that to a facet (across
    /// a concave crease) is moved out until it is not ([`toolpath::clear_facets`]), and the
    /// verifier counts a sample deeper inside the swept ball than that plus the chord tolerance
    /// as a gouge. For coarse tessellations of smooth parts, where keeping the ball off 10°
    /// facets would leave several h at every crease.
    Smooth,
}

impl Default for PlanOptions {
    fn default() -> Self {
        let tp = ToolpathOptions::default();
        Self {
            radius_mm: 3.0,
            scallop_mm: 0.02,
            origin: OriginChoice::Auto,
            direction: Direction::Inward,
            cut: Cut::Climb,
            axes: Axes::default(),
            post: Post::LinuxCnc,
            feed_mm_min: tp.feed_mm_min,
            plunge_feed_mm_min: tp.plunge_feed_mm_min,
            spindle_rpm: tp.spindle_rpm,
            safe_z_mm: None,
            verify_samples: 100_000,
            part_name: "part".into(),
            facets: Facets::Exact,
            optimise: Optimise::Tpsfo,
            alpha: OptimiseOptions::default().alpha,
            spread: RingSpread::None,
        }
    }
}

/// A failure of any stage, with the stage's own error (which names what is at fault).
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    #[error("{0}")]
    InvalidOption(String),
    #[error("{0}")]
    Mesh(#[from] crate::mesh::MeshError),
    #[error("flattening: {0}")]
    Flatten(#[from] FlattenError),
    #[error("slit map: {0}")]
    SlitMap(#[from] SlitMapError),
    #[error("origin: {0}")]
    Origin(#[from] OriginError),
    #[error("optimise: {0}")]
    Optimise(#[from] OptimiseError),
    #[error("spread: {0}")]
    Spread(#[from] SpreadError),
    #[error("spacing: {0}")]
    Spacing(#[from] SpacingError),
    #[error("spiral: {0}")]
    Spiral(#[from] SpiralError),
    #[error("tool path: {0}")]
    Toolpath(#[from] ToolpathError),
    #[error("G-code: {0}")]
    Gcode(#[from] GcodeError),
    #[error("verification: {0}")]
    Verify(#[from] VerifyError),
}

impl PlanError {
    /// The stage that failed, as the sweeps group failures: `options`, `mesh`, `flatten`,
    /// `slitmap`, `origin`, `optimise`, `spread`, `spacing`, `spiral`, `toolpath`, `gcode` or `verify`.
    pub fn stage(&self) -> &'static str {
        match self {
            PlanError::InvalidOption(_) => "options",
            PlanError::Mesh(_) => "mesh",
            PlanError::Flatten(_) => "flatten",
            PlanError::SlitMap(_) => "slitmap",
            PlanError::Origin(_) => "origin",
            PlanError::Optimise(_) => "optimise",
            PlanError::Spread(_) => "spread",
            PlanError::Spacing(_) => "spacing",
            PlanError::Spiral(_) => "spiral",
            PlanError::Toolpath(_) => "toolpath",
            PlanError::Gcode(_) => "gcode",
            PlanError::Verify(_) => "verify",
        }
    }
}

/// Stage timings, milliseconds. `flatten` includes the rim refinement before it; `slitmap`
/// ends when the facet tree and the crease-split surface built beside both are done (on wasm,
/// after them). `post` and `verify` run side by side (natively): `verify` is the span from their
/// common start to the verifier's end, and `total` (the wall time of every stage) counts that
/// span once.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Timings {
    pub read: f64,
    pub flatten: f64,
    pub slitmap: f64,
    pub origin: f64,
    pub optimise: f64,
    pub spacing: f64,
    pub spiral: f64,
    pub toolpath: f64,
    pub verify: f64,
    pub post: f64,
    pub total: f64,
}

/// A part ready to plan: the surface, its flattening and the factorised slit-map solver.
pub struct Planner {
    pub report: MeshReport,
    pub surface: Surface,
    pub flattening: Flattening,
    pub domain: PlanarDomain,
    pub solver: SlitMapSolver,
    /// Timings of the per-part work (`read` is the caller's, when it measured it).
    pub prepare_ms: Timings,
    /// The facet tree of `surface` (and of `creased`: same positions and triangles), which the
    /// spacing's gate projects onto and the toolpath clears [`Facets::Exact`] contacts against.
    faces: FaceTree,
    /// `surface` with its normals split at sharp creases, which the ball rides with
    /// [`Facets::Exact`].
    creased: Surface,
}

/// Faces turning more than this are a sharp edge of the part, across which exact facets do not
/// average normals ([`Surface::with_crease_normals`]): above the 10–15° creases of coarse
/// tessellations of curved surfaces, below the edges of machined features (45° countersinks).
pub const CREASE_SPLIT_DEG: f64 = 30.0;

/// The result of one plan.
pub struct Plan {
    pub origin: Origin,
    pub map: SlitMap,
    pub rings: Rings,
    pub spiral: Spiral,
    pub toolpath: Toolpath,
    pub path: PathMetrics,
    pub gcode: String,
    pub report: PlanReport,
}

impl Plan {
    /// The verifier's result (kept in the report; its per-vertex vectors are not serialised).
    pub fn verification(&self) -> Option<&Verification> {
        self.report.verify.as_ref()
    }
}

/// The steps of [`Planner::prepare`], in order.
pub const PREPARE_STEPS: [&str; 4] =
    ["refining the hole rims", "flattening", "factorising the slit map", "indexing the facets"];

/// The stages reported to a progress callback, in order.
pub const STAGES: [&str; 8] = ["origin", "optimise", "spacing", "spiral", "toolpath", "post", "verify", "done"];

/// The spiral's chord tolerance for ball radius `r` and scallop limit `h` (mm): a chord sags
/// inside its ring by up to this, which raises the cusp beside it by about sag·√(2h/R), so the
/// sag is held to 2% of h that way (2% of the 5% margin the spacing keeps), and to the spiral's
/// default (0.002 mm) where that is finer. A fixed 0.002 mm left 1.48 h on a unit disk at R =
/// 0.05 mm, h = 0.0005 mm, and was above h itself on the shared meshes at their scale.
pub fn chord_tolerance_mm(r: f64, h: f64) -> f64 {
    (0.02 * (r * h / 2.0).sqrt()).min(SpiralOptions::default().chord_tolerance_mm)
}

/// The spiral's tolerance along the normal for the scallop limit `h` (mm): 3% of h. Along the
/// normal a chord's deviation counts fully against the cusp (across a crease the centre curve
/// bends towards the part): the sideways tolerance left 0.17 h there on wavy_mesh_with_hole. The
/// spacing's gate keeps every band cut at 0.95 h with ring polylines within 0.02 h
/// ([`spacing`]), so the path may add 0.03 h.
pub fn normal_tolerance_mm(h: f64) -> f64 {
    0.03 * h
}

/// The surface every conformal stage works on: `surface` with its hole rims refined and ears split
/// ([`crate::mesh::refine`]; the part's vertices first, in their order). The `map` CLI uses it
/// too, so its vertex list is the planner's.
pub fn planning_surface(surface: &Surface) -> Surface {
    refine_hole_rims(surface, &RefineOptions::default())
}

/// Unit tests' fixture: the planner's surface of `part` and its slit map at the centroid pole.
#[cfg(test)]
pub(crate) fn mapped_at_centroid(part: &crate::mesh::TriMesh) -> (Surface, SlitMap) {
    let surface = crate::mesh::from_triangles(part, &Default::default()).expect("a valid fixture").surface;
    let surface = planning_surface(&surface);
    let flat =
        crate::flatten::flatten(crate::flatten::FlattenInput::from(&surface), &Default::default()).expect("flattened");
    let domain = PlanarDomain::of_surface(&surface, flat.uv);
    let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).expect("factorised");
    let map = solver.map(crate::origin::centroid_pole(&domain)).expect("mapped");
    (surface, map)
}

impl Planner {
    /// Refines the hole rims ([`crate::mesh::refine`]; `surface` is then the refined surface, the
    /// part's vertices first), flattens it and factorises the slit map once; beside those, the
    /// crease-split surface and the facet tree.
    pub fn new(mesh: MeshOutput, now: &dyn Fn() -> f64) -> Result<Self, PlanError> {
        Self::prepare(mesh, now, &mut |_, _, _| {})
    }

    /// [`Planner::new`], calling `progress(step, done, total)` as each of [`PREPARE_STEPS`]
    /// starts. The facet index is built beside the conformal steps natively, after them on wasm
    /// and on one thread (where its step is reported).
    pub fn prepare(
        mesh: MeshOutput,
        now: &dyn Fn() -> f64,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Self, PlanError> {
        let mut step = |i: usize| progress(PREPARE_STEPS[i], i, PREPARE_STEPS.len());
        let MeshOutput { report, surface } = mesh;
        surface.check_plannable()?;
        // The rim refinement prepares the surface for the flattening: its time counts there.
        step(0);
        let t = now();
        let surface = planning_surface(&surface);
        // The facet tree and the crease-split surface depend on the part alone: built beside the
        // conformal stages, which leave a thread idle most of their time.
        let ((creased, faces), prepared) = crate::par::beside(
            || (surface.with_crease_normals(CREASE_SPLIT_DEG), FaceTree::new(&surface.positions, &surface.triangles)),
            || -> Result<_, PlanError> {
                step(1);
                let flattening = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default())?;
                let t_flatten = now() - t;
                step(2);
                let domain = PlanarDomain::of_surface(&surface, flattening.uv.clone());
                let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default())?;
                step(3);
                Ok((flattening, domain, solver, t_flatten))
            },
        );
        let (flattening, domain, solver, t_flatten) = prepared?;
        let prepare_ms = Timings { flatten: t_flatten, slitmap: now() - t - t_flatten, ..Timings::default() };
        Ok(Self { report, surface, flattening, domain, solver, prepare_ms, faces, creased })
    }

    /// Plans with `options`; `progress(stage, done, total)` is called as each stage starts.
    pub fn plan(
        &self,
        options: &PlanOptions,
        progress: &mut dyn FnMut(&str, usize, usize),
        now: &dyn Fn() -> f64,
    ) -> Result<Plan, PlanError> {
        check_options(options, &self.surface)?;
        let mut timings = self.prepare_ms.clone();
        let total = STAGES.len() - 1;
        let mut stage = |i: usize| progress(STAGES[i], i, total);
        let r = options.radius_mm;

        stage(0);
        let t = now();
        let origin_options = OriginOptions { radius_mm: r, choice: options.origin, ..OriginOptions::default() };
        let (mut origin, mut map) =
            origin::find_origin_and_map(&self.surface, &self.domain, &self.solver, &origin_options)?;
        timings.origin = now() - t;
        let spiral_options = SpiralOptions {
            direction: options.direction,
            cut: options.cut,
            chord_tolerance_mm: chord_tolerance_mm(r, options.scallop_mm),
            normal_tolerance_mm: Some(normal_tolerance_mm(options.scallop_mm)),
            radius_mm: r,
            ..SpiralOptions::default()
        };
        // `auto` promises a path: when the P1 map cannot carry one from the best pole, the next
        // best poles the search saw are tried (reported as rejected). So does `centroid`, with
        // the centroid moved away from its nearest boundary: beside a hole the map can have too
        // few faces round the pole for its rings (plate_holes' centroid lies 0.28 mm from one).
        let separation = FALLBACK_SEPARATION * self.domain_diagonal();
        let mut alternatives = match options.origin {
            OriginChoice::Auto => origin.alternatives(separation, MAX_FALLBACKS),
            OriginChoice::Centroid => origin::away_from_boundary(&self.domain, origin.pole, separation, MAX_FALLBACKS),
            _ => Vec::new(),
        }
        .into_iter();
        let mut rejected = Vec::new();
        let tpsfo = options.optimise == Optimise::Tpsfo;
        let finished = loop {
            let mut run =
                Run { options, spiral_options: &spiral_options, stage: &mut stage, timings: &mut timings, now };
            let attempt = self.path_from(&mut run, &origin, map, tpsfo);
            match attempt {
                Ok(done) => break done,
                Err(e) if e.depends_on_pole() => {
                    let Some(pole) = alternatives.next() else { return Err(e) };
                    rejected.push(RejectedPole {
                        pole_uv: origin.pole.to_array(),
                        e_min: origin.energy.e_min,
                        reason: e.to_string(),
                    });
                    let t = now();
                    let choice = OriginChoice::Plane(pole);
                    let (next, next_map) = origin::find_origin_and_map(
                        &self.surface,
                        &self.domain,
                        &self.solver,
                        &OriginOptions { choice, ..origin_options.clone() },
                    )?;
                    map = next_map;
                    let trace = std::mem::take(&mut origin.trace);
                    origin = Origin { evaluations: origin.evaluations + next.evaluations, trace, ..next };
                    timings.origin += now() - t;
                }
                Err(e) => return Err(e),
            }
        };
        timings.total = timings.flatten
            + timings.slitmap
            + timings.origin
            + timings.optimise
            + timings.spacing
            + timings.spiral
            + timings.toolpath
            + timings.verify;
        stage(7);
        let Finished {
            field: Field { map, .. },
            optimise,
            rings,
            spiral,
            toolpath,
            path,
            summary,
            verification,
            gcode,
            retries,
            spread,
        } = finished;
        let mut report = PlanReport::new(self, options, &origin, &map, &rings, summary, verification, timings);
        report.origin.rejected = rejected;
        report.optimise = optimise;
        report.spacing_retries = retries;
        if spread.as_ref().is_some_and(|s| s.kept) {
            (report.max_scallop_at, report.max_outside_valleys_at) = (None, None);
        }
        report.spread = spread;
        Ok(Plan { origin, map, rings, spiral, toolpath, path, gcode, report })
    }

    /// The field of the pole's slit map `map`: optimised (seed 003) when `tpsfo`, else the map as
    /// it is; with the optimisation's report.
    fn field(
        &self,
        run: &mut Run,
        origin: &Origin,
        map: SlitMap,
        tpsfo: bool,
    ) -> Result<(Field, Option<OptimiseSummary>), PlanError> {
        (run.stage)(1);
        let t = (run.now)();
        let optimise_options = OptimiseOptions {
            radius_mm: run.options.radius_mm,
            alpha: run.options.alpha,
            max_iterations: if tpsfo { OptimiseOptions::default().max_iterations } else { 0 },
            ..OptimiseOptions::default()
        };
        let optimised = optimise::optimise(&self.surface, &map, &origin.energy.slopes, &optimise_options);
        run.timings.optimise += (run.now)() - t;
        let optimised = optimised?;
        let optimise = optimised.report.map(|o| OptimiseSummary { stage: Some(o), ..OptimiseSummary::default() });
        Ok((Field { map: optimised.map, optimised: optimise.is_some(), spread: false }, optimise))
    }

    /// From a field on: rings spaced for a cusp of `target_fraction`·h, the spiral, tool
    /// positions, the verification and the G-code.
    fn finish(
        &self,
        run: &mut Run,
        origin: &Origin,
        field: Field,
        target_fraction: f64,
    ) -> Result<Finished, PlanError> {
        let (rings, spiral) = self.rings_and_spiral(run, &field.map, field.spread, target_fraction)?;
        let Run { options, spiral_options, stage, timings, now } = run;
        let r = options.radius_mm;
        stage(4);
        let t = now();
        let toolpath_options = ToolpathOptions {
            radius_mm: r,
            axes: options.axes,
            feed_mm_min: options.feed_mm_min,
            plunge_feed_mm_min: options.plunge_feed_mm_min,
            spindle_rpm: options.spindle_rpm,
            safe_z_mm: options.safe_z_mm,
            ..ToolpathOptions::default()
        };
        let (designed, designed_normals) = (spiral.contacts(), spiral.normals());
        let (chord, dip) = (spiral_options.chord_tolerance_mm, self.dip_mm(options));
        let cc_faces: Vec<u32> = spiral.points.iter().map(|p| p.face).collect();
        // As the spacing planned its balls (exact facets only).
        let rest_above = match options.facets {
            Facets::Exact => crate::spacing::rest_above_mm(options.scallop_mm),
            Facets::Smooth => f64::INFINITY,
        };
        let (contacts, normals, clearance) =
            toolpath::clear_facets(&self.faces, &designed, &designed_normals, &cc_faces, r, dip, chord, rest_above);
        let toolpath = toolpath::toolpath(&contacts, &normals, &toolpath_options)?;
        // The designed contact curve: cleared contacts are touch points, which stall on a
        // vertex while the ball rolls over it, so their turning angles say nothing of the motion.
        let path = verify::path_metrics(&designed, options.feed_mm_min);
        timings.toolpath += now() - t;

        let ideal = self.surface.area() / (2.0 * (2.0 * r * options.scallop_mm).sqrt());
        let summary = PathSummary {
            length_mm: path.length_mm,
            length_over_ideal: path.length_mm / ideal,
            points: toolpath.stats.cut_points,
            retractions: toolpath.stats.retractions,
            max_turn_deg: path.max_turn_deg,
            rho2: path.rho2,
            time_min: toolpath.stats.estimated_time_s / 60.0,
            clearance,
        };

        // The post and the verifier both read the finished toolpath only: the verifier runs
        // beside the post, and its time is counted from their common start to its end.
        stage(5);
        stage(6);
        let t = now();
        let verify_centres = || -> Result<Option<Verification>, VerifyError> {
            if options.verify_samples == 0 {
                return Ok(None);
            }
            Ok(Some(self.verify(&toolpath, options, VerifyOptions::default().seed)?))
        };
        let mut post_ms = 0.0;
        let (verification, gcode) = crate::par::beside(verify_centres, || {
            let header = header_lines(options, origin, &rings, &summary, field.optimised, field.spread);
            let gcode_options = GcodeOptions {
                post: options.post,
                part_name: options.part_name.clone(),
                header,
                ..GcodeOptions::default()
            };
            let gcode = gcode::gcode(&toolpath, &gcode_options);
            post_ms = now() - t;
            gcode
        });
        let (gcode, verification) = (gcode?, verification?);
        timings.post += post_ms;
        timings.verify += now() - t;
        Ok(Finished {
            field,
            optimise: None,
            rings,
            spiral,
            toolpath,
            path,
            summary,
            verification,
            gcode,
            retries: Vec::new(),
            spread: None,
        })
    }

    /// The rings of `map`'s field spaced for a cusp of `target_fraction`·h and the spiral through
    /// them.
    fn rings_and_spiral(
        &self,
        run: &mut Run,
        map: &SlitMap,
        spread: bool,
        target_fraction: f64,
    ) -> Result<(Rings, Spiral), PlanError> {
        let Run { options, spiral_options, stage, timings, now } = run;
        stage(2);
        let t = now();
        let spacing_options = SpacingOptions {
            radius_mm: options.radius_mm,
            scallop_mm: options.scallop_mm,
            facet_lift: options.facets == Facets::Exact,
            target_fraction,
            ..SpacingOptions::default()
        };
        // One inverse map for the spacing and the spiral, built beside the spacing's indexes of
        // the map. The part's facet tree serves: the crease-split surface has the same positions
        // and triangles.
        let surface = self.riding(options.facets);
        // A spread field is lifted through its warp, and indexed in the warp's image of the map.
        let mut image = None;
        let (lift, index) = if spread {
            let lift = Lift::new(surface, map);
            let spread_options = SpreadOptions {
                radius_mm: options.radius_mm,
                scallop_mm: options.scallop_mm,
                ..SpreadOptions::default()
            };
            let spread = crate::spread::spread(&lift, &spread_options)?;
            let lift = lift.spread(image.insert(spread.image(surface, map)), spread);
            let index = SpacingIndex::on(&lift, &self.faces, &spacing_options);
            (lift, index)
        } else {
            crate::par::join(
                || Lift::new(surface, map),
                || SpacingIndex::new(surface, map, &self.faces, &spacing_options),
            )
        };
        let rings = index.and_then(|index| index.rings(&lift));
        timings.spacing += now() - t;
        let rings = rings?;
        stage(3);
        let t = now();
        let spiral = spiral::spiral_on(&lift, &rings, spiral_options);
        timings.spiral += now() - t;
        Ok((rings, spiral?))
    }

    /// The planner's verification of `toolpath` planned with `options`, its samples drawn with
    /// `seed`: the plan's own uses the default seed; another one checks the plan on fresh
    /// samples (a peak narrower than the samples' spacing is found by one set and not another).
    pub fn verify(&self, toolpath: &Toolpath, options: &PlanOptions, seed: u64) -> Result<Verification, VerifyError> {
        let r = options.radius_mm;
        let (dip, chord) = (self.dip_mm(options), chord_tolerance_mm(r, options.scallop_mm));
        let centres: Vec<DVec3> = toolpath.contact_moves().iter().map(|m| m.centre).collect();
        let verify_options = VerifyOptions {
            radius_mm: r,
            scallop_mm: options.scallop_mm,
            samples: options.verify_samples,
            seed,
            // Centres keep R − dip from every facet; straight moves between them are split where
            // they dip deeper than the chord tolerance past that.
            gouge_tolerance_mm: dip + chord,
            // Where the spacing does not plan for the balls' lift off the facets; the balls
            // standing for the valleys' reach may dip as deep as the path's.
            valley_lift_mm: Some(crate::spacing::LIFT_VALLEY * options.scallop_mm),
            valley_dip_mm: dip,
            ..VerifyOptions::default()
        };
        verify::verify_with_faces(self.riding(options.facets), &self.faces, &[centres], &verify_options)
    }

    /// How deep the ball may dip into the facets: with smooth facets, their own deviation from
    /// the smooth surface they tessellate.
    fn dip_mm(&self, options: &PlanOptions) -> f64 {
        match options.facets {
            Facets::Exact => 0.0,
            Facets::Smooth => facet_tolerance_mm(&self.surface, options.radius_mm),
        }
    }

    /// The surface whose normals the ball rides for `facets`.
    fn riding(&self, facets: Facets) -> &Surface {
        match facets {
            Facets::Exact => &self.creased,
            Facets::Smooth => &self.surface,
        }
    }

    /// Bounding-box diagonal of the flattened domain.
    fn domain_diagonal(&self) -> f64 {
        let (lo, hi) = self.domain.positions.iter().fold((DVec2::MAX, DVec2::MIN), |(a, b), &p| (a.min(p), b.max(p)));
        (hi - lo).length()
    }
}

/// `auto` (and `centroid`) try at most this many other poles when a path cannot be built from
/// the first one.
pub const MAX_FALLBACKS: usize = 3;
/// ... each at least this fraction of the flattened domain's diagonal from the poles tried
/// (`centroid`: steps of it away from the boundary nearest to the centroid).
pub const FALLBACK_SEPARATION: f64 = 0.05;

impl PlanError {
    /// Errors a different pole may avoid: the P1 map cannot carry a ring or the spiral there
    /// (a lift outside the image, a jump across overlapping image triangles, a bridge with no
    /// room between slits, a band no ring can close).
    pub fn depends_on_pole(&self) -> bool {
        matches!(
            self,
            PlanError::Spiral(
                SpiralError::Discontinuous { .. } | SpiralError::Lift { .. } | SpiralError::Blocked { .. }
            ) | PlanError::Spacing(SpacingError::Lift { .. } | SpacingError::NoProgress { .. })
        )
    }
}

/// A pole `auto` chose first and gave up, with why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RejectedPole {
    pub pole_uv: [f64; 2],
    pub e_min: f64,
    pub reason: String,
}

/// How deep a ball placed along the interpolated vertex normal can dip below the plane of the
/// facet it touches: R(1 − cos δ), δ the largest angle between a face normal and its vertex
/// normals (at least 1e-4 mm, at most R/10). In [`Facets::Smooth`] this is the facets' own
/// deviation from the smooth surface they tessellate: the ball may dip that deep, no deeper.
pub fn facet_tolerance_mm(surface: &Surface, radius_mm: f64) -> f64 {
    let mut cos_min: f64 = 1.0;
    for (f, t) in surface.triangles.iter().enumerate() {
        for &v in t {
            cos_min = cos_min.min(surface.face_normals[f].dot(surface.vertex_normals[v as usize]));
        }
    }
    // Never the ball radius itself (the verifier's bound): a mesh that coarse has no tolerance left.
    (radius_mm * (1.0 - cos_min.clamp(-1.0, 1.0))).max(1e-4).min(0.1 * radius_mm)
}

fn check_options(o: &PlanOptions, surface: &Surface) -> Result<(), PlanError> {
    let bad = |m: String| Err(PlanError::InvalidOption(m));
    if !(o.radius_mm.is_finite() && o.radius_mm > 0.0) {
        return bad(format!("the ball radius must be a positive number of mm, got {}", o.radius_mm));
    }
    if !(o.scallop_mm.is_finite() && o.scallop_mm > 0.0) {
        return bad(format!("the scallop height must be a positive number of mm, got {}", o.scallop_mm));
    }
    if !(o.alpha.is_finite() && o.alpha >= 0.0) {
        return bad(format!("α must be a number ≥ 0, got {}", o.alpha));
    }
    if o.scallop_mm >= o.radius_mm {
        return bad(format!(
            "the scallop height {} mm must be smaller than the ball radius {} mm",
            o.scallop_mm, o.radius_mm
        ));
    }
    let (lo, hi) = crate::mesh::weld::bounding_box(&surface.positions);
    let size = (hi - lo).length();
    if o.radius_mm >= 0.5 * size {
        return bad(format!(
            "the ball (radius {} mm) is larger than the part (bounding-box diagonal {:.3} mm): choose a smaller tool",
            o.radius_mm, size
        ));
    }
    // A part in metres read as millimetres, or an h far finer than the part needs, would make
    // a path of hundreds of kilometres: refused before any stage allocates for it.
    let ideal_mm = surface.area() / (2.0 * (2.0 * o.radius_mm * o.scallop_mm).sqrt());
    if ideal_mm > MAX_IDEAL_PATH_MM {
        return bad(format!(
            "the path would be at least {:.0} km long (area {:.0} mm², R {} mm, h {} mm), more than the {:.0} km a plan may have: check the STL's units or choose a larger scallop height",
            ideal_mm / 1e6,
            surface.area(),
            o.radius_mm,
            o.scallop_mm,
            MAX_IDEAL_PATH_MM / 1e6
        ));
    }
    Ok(())
}

/// The longest flat-plate bound area / (2·√(2Rh)) a plan may have, mm: 50 km, some 5·10⁷
/// G-code lines, about 25 times the 2 km of a 1 m² panel at R 3, h 0.005.
pub const MAX_IDEAL_PATH_MM: f64 = 5.0e7;
