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

use crate::flatten::{self, FlattenError, FlattenInput, FlattenOptions, FlattenReport, Flattening};
use crate::gcode::{self, GcodeError, GcodeOptions, Post};
use crate::mesh::creases::FacetValleys;
use crate::mesh::nearest::FaceTree;
use crate::mesh::refine::{refine_hole_rims, RefineOptions};
use crate::mesh::{MeshOutput, MeshReport, Surface};
use crate::optimise::{self, OptimiseError, OptimiseOptions, OptimiseReport};
use crate::origin::{self, Origin, OriginChoice, OriginError, OriginOptions};
use crate::slitmap::{Mode, PlanarDomain, SlitMap, SlitMapError, SlitMapOptions, SlitMapSolver};
use crate::spacing::{Lift, Rings, SpacingError, SpacingIndex, SpacingOptions};
use crate::spiral::{self, Cut, Direction, Spiral, SpiralError, SpiralOptions};
use crate::toolpath::{self, Axes, Clearance, Toolpath, ToolpathError, ToolpathOptions};
use crate::verify::{self, PathMetrics, Verification, VerifyError, VerifyOptions};
use glam::{DVec2, DVec3};
use serde::Serialize;

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
    /// `slitmap`, `origin`, `optimise`, `spacing`, `spiral`, `toolpath`, `gcode` or `verify`.
    pub fn stage(&self) -> &'static str {
        match self {
            PlanError::InvalidOption(_) => "options",
            PlanError::Mesh(_) => "mesh",
            PlanError::Flatten(_) => "flatten",
            PlanError::SlitMap(_) => "slitmap",
            PlanError::Origin(_) => "origin",
            PlanError::Optimise(_) => "optimise",
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
            // The optimised field's path is verified like any other; where it breaks what the
            // conformal map's keeps (a field the spacing could not prove everywhere, the
            // stage failing), the conformal map's path is planned too and the better one kept.
            let conformal = tpsfo.then(|| map.clone());
            let attempt = self.finish(&origin, map, tpsfo, options, &spiral_options, &mut stage, &mut timings, now);
            let attempt = match (attempt, conformal) {
                (Ok(fin), Some(conformal)) if fin.exceeds(options.scallop_mm) => {
                    match self.finish(
                        &origin,
                        conformal,
                        false,
                        options,
                        &spiral_options,
                        &mut stage,
                        &mut timings,
                        now,
                    ) {
                        Ok(plain) if plain.better_than(&fin, options.scallop_mm) => {
                            let reason = format!(
                                "the optimised field's path left {:.3} h, the conformal map's {:.3} h",
                                fin.max_over_h(options.scallop_mm),
                                plain.max_over_h(options.scallop_mm)
                            );
                            Ok(plain.kept_instead_of(fin, reason))
                        }
                        _ => Ok(fin),
                    }
                }
                (Err(e), Some(conformal)) => {
                    let optimised_error = e.to_string();
                    self.finish(&origin, conformal, false, options, &spiral_options, &mut stage, &mut timings, now)
                        .map(|plain| plain.kept_after_error(optimised_error))
                }
                (attempt, _) => attempt,
            };
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
        let Finished { map, optimise, rings, spiral, toolpath, path, summary, verification, gcode } = finished;
        let mut report = PlanReport::new(self, options, &origin, &map, &rings, summary, verification, timings);
        report.origin.rejected = rejected;
        report.optimise = optimise;
        Ok(Plan { origin, map, rings, spiral, toolpath, path, gcode, report })
    }

    /// From the pole's slit map on: the field (optimised when `tpsfo`), rings, spiral, tool
    /// positions, the verification and the G-code.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        origin: &Origin,
        map: SlitMap,
        tpsfo: bool,
        options: &PlanOptions,
        spiral_options: &SpiralOptions,
        stage: &mut dyn FnMut(usize),
        timings: &mut Timings,
        now: &dyn Fn() -> f64,
    ) -> Result<Finished, PlanError> {
        let r = options.radius_mm;
        let (map, optimise, rings, spiral) =
            self.rings_and_spiral(map, tpsfo, options, spiral_options, stage, timings, now, &origin.energy.slopes)?;

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
            let header = header_lines(options, origin, &rings, &summary, optimise.is_some());
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
        Ok(Finished { map, optimise, rings, spiral, toolpath, path, summary, verification, gcode })
    }

    /// The rings of the pole's slit map `map` (its field optimised first when `tpsfo`) and the
    /// spiral through them, with the map they were spaced on.
    #[allow(clippy::too_many_arguments)]
    fn rings_and_spiral(
        &self,
        map: SlitMap,
        tpsfo: bool,
        options: &PlanOptions,
        spiral_options: &SpiralOptions,
        stage: &mut dyn FnMut(usize),
        timings: &mut Timings,
        now: &dyn Fn() -> f64,
        slopes: &[f64],
    ) -> Result<(SlitMap, Option<OptimiseSummary>, Rings, Spiral), PlanError> {
        stage(1);
        let t = now();
        let optimise_options = OptimiseOptions {
            radius_mm: options.radius_mm,
            alpha: options.alpha,
            max_iterations: if tpsfo { OptimiseOptions::default().max_iterations } else { 0 },
            ..OptimiseOptions::default()
        };
        let optimised = optimise::optimise(&self.surface, &map, slopes, &optimise_options);
        timings.optimise += now() - t;
        let optimised = optimised?;
        let (map, optimise_report) =
            (optimised.map, optimised.report.map(|o| OptimiseSummary { stage: Some(o), ..OptimiseSummary::default() }));
        stage(2);
        let t = now();
        let spacing_options = SpacingOptions {
            radius_mm: options.radius_mm,
            scallop_mm: options.scallop_mm,
            facet_lift: options.facets == Facets::Exact,
            // An optimised field's rings bend more between the meridians than the conformal
            // map's circles, and the spacing's tests between them are looser (the gate's levels
            // pass up to h/4 under a peak): 0.95 left 1.01–1.1 h on a third of the generated
            // parts, 0.92 on a sixth, for 1.5 % more path.
            target_fraction: if tpsfo { OPTIMISED_TARGET_FRACTION } else { SpacingOptions::default().target_fraction },
            ..SpacingOptions::default()
        };
        // One inverse map for the spacing and the spiral, built beside the spacing's indexes of
        // the map. The part's facet tree serves: the crease-split surface has the same positions
        // and triangles.
        let surface = self.riding(options.facets);
        let (lift, index) = crate::par::join(
            || Lift::new(surface, &map),
            || SpacingIndex::new(surface, &map, &self.faces, &spacing_options),
        );
        let rings = index.and_then(|index| index.rings(&lift));
        timings.spacing += now() - t;
        let rings = rings?;
        stage(3);
        let t = now();
        let spiral = spiral::spiral_on(&lift, &rings, spiral_options);
        timings.spiral += now() - t;
        Ok((map, optimise_report, rings, spiral?))
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

/// A plan from one slit map on (see [`Planner::finish`]).
struct Finished {
    map: SlitMap,
    optimise: Option<OptimiseSummary>,
    rings: Rings,
    spiral: Spiral,
    toolpath: Toolpath,
    path: PathMetrics,
    summary: PathSummary,
    verification: Option<Verification>,
    gcode: String,
}

impl Finished {
    /// The verified largest scallop outside the facet valleys over `h` (0 unverified).
    fn max_over_h(&self, h: f64) -> f64 {
        self.verification.as_ref().map_or(0.0, |v| v.max_scallop_outside_valleys_mm / h)
    }

    /// Whether the verified path leaves more than `h` outside the facet valleys.
    fn exceeds(&self, h: f64) -> bool {
        self.max_over_h(h) > 1.0
    }

    /// Whether this path keeps `h` where `other` does not, or, both leaving more, leaves less.
    fn better_than(&self, other: &Finished, h: f64) -> bool {
        let (a, b) = (self.max_over_h(h), other.max_over_h(h));
        (a <= 1.0 && b > 1.0) || (a > 1.0 && b > 1.0 && a < b)
    }

    /// This (conformal) path, kept instead of the optimised one `optimised` for `reason`: the
    /// report keeps the optimisation's figures and says why its path was not used.
    fn kept_instead_of(mut self, optimised: Finished, reason: String) -> Self {
        self.optimise = Some(OptimiseSummary {
            path_field: "conformal",
            fallback: Some(reason),
            optimised_length_mm: Some(optimised.summary.length_mm),
            ..optimised.optimise.unwrap_or_default()
        });
        self
    }

    /// This (conformal) path, planned because the optimised field's failed with `error`.
    fn kept_after_error(mut self, error: String) -> Self {
        self.optimise = Some(OptimiseSummary {
            path_field: "conformal",
            fallback: Some(format!("the optimised field's plan failed: {error}")),
            ..OptimiseSummary::default()
        });
        self
    }
}

/// The scallop fraction the rings of an optimised field are spaced for (see
/// [`SpacingOptions::target_fraction`]; the conformal map's keep the default 0.95).
pub const OPTIMISED_TARGET_FRACTION: f64 = 0.92;

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

/// The path figures of the report.
#[derive(Debug, Clone, Serialize)]
pub struct PathSummary {
    pub length_mm: f64,
    /// The length over the flat-plate bound area / (2·√(2Rh)) (DESIGN.md, "Path length at equal
    /// finish"): about 1.05 for evenly spaced passes on a gently curved part.
    pub length_over_ideal: f64,
    pub points: usize,
    pub retractions: usize,
    pub max_turn_deg: f64,
    pub rho2: f64,
    pub time_min: f64,
    /// Ball centres moved off facets nearer than R ([`toolpath::clear_facets`]; zeros with
    /// [`Facets::Smooth`]).
    pub clearance: Clearance,
}

/// The optimisation as the plan report shows it: the stage's own report, and which field the
/// written path follows.
#[derive(Debug, Clone, Serialize)]
pub struct OptimiseSummary {
    /// `tpsfo` when the path follows the optimised field, `conformal` when the planner kept the
    /// slit map's own (see `fallback`).
    pub path_field: &'static str,
    /// What the optimisation did (absent when it failed).
    #[serde(flatten)]
    pub stage: Option<OptimiseReport>,
    /// Why the conformal map's path was written instead of the optimised field's: the optimised
    /// one failed, or it left more than h where the conformal map's does not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback: Option<String>,
    /// The optimised path's length when it was not kept, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimised_length_mm: Option<f64>,
}

impl Default for OptimiseSummary {
    fn default() -> Self {
        Self { path_field: "tpsfo", stage: None, fallback: None, optimised_length_mm: None }
    }
}

/// The options as the report shows them (plain values, the CLI's names).
#[derive(Debug, Clone, Serialize)]
pub struct OptionsReport {
    pub radius_mm: f64,
    pub scallop_mm: f64,
    pub origin: String,
    pub direction: Direction,
    pub cut: Cut,
    pub axes: u8,
    pub lead_deg: Option<f64>,
    pub tilt_deg: Option<f64>,
    pub post: &'static str,
    pub feed_mm_min: f64,
    pub plunge_feed_mm_min: f64,
    pub spindle_rpm: f64,
    pub safe_z_mm: Option<f64>,
    pub verify_samples: usize,
    pub facets: Facets,
}

impl OptionsReport {
    fn new(o: &PlanOptions) -> Self {
        let (axes, lead_deg, tilt_deg) = match o.axes {
            Axes::Three { .. } => (3, None, None),
            Axes::Five { lead_deg, tilt_deg } => (5, Some(lead_deg), Some(tilt_deg)),
        };
        Self {
            radius_mm: o.radius_mm,
            scallop_mm: o.scallop_mm,
            origin: origin_name(&o.origin),
            direction: o.direction,
            cut: o.cut,
            axes,
            lead_deg,
            tilt_deg,
            post: o.post.name(),
            feed_mm_min: o.feed_mm_min,
            plunge_feed_mm_min: o.plunge_feed_mm_min,
            spindle_rpm: o.spindle_rpm,
            safe_z_mm: o.safe_z_mm,
            verify_samples: o.verify_samples,
            facets: o.facets,
        }
    }
}

/// `auto`, `centroid`, `hole:N`, `X,Y,Z` (3D point) or `uv:U,V` (flattened-plane pole).
pub fn origin_name(o: &OriginChoice) -> String {
    match o {
        OriginChoice::Auto => "auto".into(),
        OriginChoice::Centroid => "centroid".into(),
        OriginChoice::Hole(n) => format!("hole:{n}"),
        OriginChoice::Point3d(p) => format!("{},{},{}", p.x, p.y, p.z),
        OriginChoice::Plane(p) => format!("uv:{},{}", p.x, p.y),
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct OriginReport {
    pub mode: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub annulus_hole: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inner_radius: Option<f64>,
    pub pole_uv: [f64; 2],
    pub pole_3d: [f64; 3],
    pub e_min: f64,
    pub e_min_centroid: f64,
    pub uniformity: f64,
    pub evaluations: usize,
    /// Poles `auto` or `centroid` chose first and could not plan from (see [`MAX_FALLBACKS`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rejected: Vec<RejectedPole>,
}

/// Where a peak of the verified finish lies: the verifier's sample ([`verify::ScallopAt`]), its
/// slit-domain image w = ρ·e^{iθ} and the rings either side of it.
#[derive(Debug, Clone, Serialize)]
pub struct PeakAt {
    #[serde(flatten)]
    pub sample: verify::ScallopAt,
    /// |w| and arg w of the sample's image.
    pub rho: f64,
    pub theta: f64,
    /// The ring outside the sample (larger radius) and the one inside it, indices into
    /// `ring_radii` (`None` beyond the first or the last ring).
    pub ring_outside: Option<usize>,
    pub ring_inside: Option<usize>,
}

impl PeakAt {
    /// The peak `at` located on `surface` (the map's vertices) in `map` between `radii`
    /// (outermost first); `None` when its face is not the surface's.
    pub fn locate(at: &verify::ScallopAt, surface: &Surface, map: &SlitMap, radii: &[f64]) -> Option<Self> {
        let [a, b, c] = *surface.triangles.get(at.face as usize)?;
        let corner = |v: u32| surface.positions.get(v as usize).copied();
        let (pa, pb, pc) = (corner(a)?, corner(b)?, corner(c)?);
        let w = |v: u32| map.w.get(v as usize).copied();
        let (wa, wb, wc) = (w(a)?, w(b)?, w(c)?);
        // The sample lies on the face: its barycentric coordinates are its closest point's.
        let [ba, bb, bc] = crate::mesh::nearest::closest_on_triangle(DVec3::from_array(at.position), pa, pb, pc);
        let image = wa * ba + wb * bb + wc * bc;
        let rho = image.length();
        let inside = radii.iter().position(|&r| r <= rho);
        let outside = match inside {
            Some(0) => None,
            Some(k) => Some(k - 1),
            None => radii.len().checked_sub(1),
        };
        Some(Self { sample: *at, rho, theta: image.y.atan2(image.x), ring_outside: outside, ring_inside: inside })
    }
}

/// The plan report (`slitpath plan --report`, and what the page shows).
#[derive(Debug, Clone, Serialize)]
pub struct PlanReport {
    pub options: OptionsReport,
    pub mesh: MeshReport,
    /// The flattening's method, disk blend, hole fillings and quality figures.
    pub flatten: FlattenReport,
    pub origin: OriginReport,
    /// Number of rings.
    pub rings: usize,
    /// Ring radii |w|, outermost first.
    pub ring_radii: Vec<f64>,
    /// Rings the spacing could not prove everywhere (see [`Rings::fold_compromises`],
    /// [`Rings::crease_compromises`] and [`Rings::gate_compromises`]): where the verifier's
    /// figures may exceed h, and why.
    pub fold_compromises: usize,
    pub crease_compromises: usize,
    pub gate_compromises: usize,
    /// Seed 003's optimisation of the field (absent with `--optimise none`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimise: Option<OptimiseSummary>,
    pub path: PathSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verify: Option<Verification>,
    /// Where the verifier's largest scallop lies in the slit domain and between which rings
    /// (absent without verification).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_scallop_at: Option<PeakAt>,
    /// The same for its largest scallop outside the facet valleys.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_outside_valleys_at: Option<PeakAt>,
    pub gouge_risk_area_mm2: f64,
    pub flipped_triangles: usize,
    /// With [`Facets::Exact`]: the concave creases where the STL's facets alone leave more than
    /// h for this R, whatever the path ([`crate::mesh::creases`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub facet_valleys: Option<FacetValleys>,
    /// What the user should know before trusting the G-code, in words (the CLI prints them on
    /// stderr, the page beside the figures).
    pub warnings: Vec<String>,
    pub timings_ms: Timings,
}

impl PlanReport {
    #[allow(clippy::too_many_arguments)]
    fn new(
        planner: &Planner,
        options: &PlanOptions,
        origin: &Origin,
        map: &SlitMap,
        rings: &Rings,
        path: PathSummary,
        verification: Option<Verification>,
        timings_ms: Timings,
    ) -> Self {
        let (mode, annulus_hole, inner_radius) = match map.mode {
            Mode::Disk => ("disk", None, None),
            Mode::Annulus { hole, inner_radius } => ("annulus", Some(hole), Some(inner_radius)),
        };
        let mut report = Self {
            options: OptionsReport::new(options),
            mesh: planner.report.clone(),
            flatten: planner.flattening.report(),
            origin: OriginReport {
                mode,
                annulus_hole,
                inner_radius,
                pole_uv: origin.pole.to_array(),
                pole_3d: origin.pole_3d.to_array(),
                e_min: origin.energy.e_min,
                e_min_centroid: origin.centroid_energy.e_min,
                uniformity: origin.energy.uniformity,
                evaluations: origin.evaluations,
                rejected: Vec::new(),
            },
            rings: rings.rings.len(),
            ring_radii: rings.radii(),
            fold_compromises: rings.fold_compromises,
            crease_compromises: rings.crease_compromises,
            gate_compromises: rings.gate_compromises,
            optimise: None,
            path,
            max_scallop_at: None,
            max_outside_valleys_at: None,
            verify: verification,
            gouge_risk_area_mm2: origin.energy.gouge_risk_area_mm2,
            flipped_triangles: map.flipped_triangles(),
            facet_valleys: None,
            warnings: Vec::new(),
            timings_ms,
        };
        if options.facets == Facets::Exact {
            let (r, h) = (options.radius_mm, options.scallop_mm);
            let valleys = crate::mesh::creases::facet_valleys(&planner.surface, r, h);
            if valleys.edges > 0 || valleys.pits > 0 {
                report.warnings.push(format!(
                    "the STL's facets alone leave up to {:.4} mm ({:.2} h) at {} concave creases ({:.1} mm of edges) and {} pits for a ball of radius {r} mm, whatever the path: if the STL tessellates a smooth surface, plan with --facets smooth; otherwise use a finer STL or a smaller ball (a smaller h would not help)",
                    valleys.max_depth_mm,
                    valleys.max_depth_mm / h,
                    valleys.edges,
                    valleys.length_mm,
                    valleys.pits
                ));
            }
            report.facet_valleys = Some(valleys);
        }
        let radii = rings.radii();
        let locate = |at: Option<&verify::ScallopAt>| at.and_then(|a| PeakAt::locate(a, &planner.surface, map, &radii));
        report.max_scallop_at = locate(report.verify.as_ref().and_then(|v| v.max_scallop_at.as_ref()));
        report.max_outside_valleys_at = locate(report.verify.as_ref().and_then(|v| v.max_outside_valleys_at.as_ref()));
        report
    }
}

/// Header lines of the G-code: options and path figures, no timings (deterministic output).
fn header_lines(
    o: &PlanOptions,
    origin: &Origin,
    rings: &Rings,
    path: &PathSummary,
    optimised: bool,
) -> Vec<(String, String)> {
    let opts = OptionsReport::new(o);
    let field = if optimised {
        format!("seed 003 optimised, tpsfo, alpha {}", o.alpha)
    } else {
        "conformal slit map, seed 000".to_string()
    };
    let mut lines = vec![
        ("planner".to_string(), "slitpath conformal slit-map spiral".to_string()),
        ("field".into(), field),
        ("ball radius mm".into(), format!("{}", opts.radius_mm)),
        ("scallop mm".into(), format!("{}", opts.scallop_mm)),
        ("origin".into(), opts.origin),
        ("axes".into(), format!("{}", opts.axes)),
    ];
    if let (Some(l), Some(t)) = (opts.lead_deg, opts.tilt_deg) {
        lines.push(("lead tilt deg".into(), format!("{l} {t}")));
    }
    lines.extend([
        ("direction".into(), format!("{:?} {:?}", opts.direction, opts.cut).to_lowercase()),
        ("pole uv".into(), format!("{:.6} {:.6}", origin.pole.x, origin.pole.y)),
        ("rings".into(), format!("{}", rings.rings.len())),
        ("path length mm".into(), format!("{:.3}", path.length_mm)),
        ("points".into(), format!("{}", path.points)),
        ("estimated time min".into(), format!("{:.2}", path.time_min)),
    ]);
    lines
}
