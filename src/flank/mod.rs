//! Strategy `flank`: 5-axis flank milling of a free-form surface with a conical tool in G¹
//! multi-strip paths (seed 002, Rajain et al., CAD 163, 2023; issue 35).
//!
//! What it computes. The surface is finished by the *side* of a truncated cone in M strips; the
//! tool touches the surface along (nearly) a line, so a few strips replace the hundreds of rings
//! a ball needs. The stages, one module each:
//!
//! 1. [`tool`]: the cone as the user gives it (tip radius, top radius, flute length) → the
//!    seed's sphere family r₁, r₂, L (eqs. 1–2).
//! 2. [`field`] and [`levels`]: the guiding field G, fair, with its gradient across the
//!    machining direction, by sparse least squares on the mesh (§5); its level sets.
//! 3. [`guide`]: the guiding curves (level sets of G about d = √(L² − Δr²) apart) and their base
//!    points, propagated through normal planes (Fig. 10), ragged strip ends (Remark 1).
//! 4. [`rails`]: the initial rails (eq. 7) and the m-grid (eqs. 8–11): adjacent strips share
//!    their boundary spheres.
//! 5. [`objective`], [`lbfgs`], [`optimise`]: F = w₁F_rigid + w₂F_approx + w₃F_G1 + w₄F_ini +
//!    w₅F_fair (eqs. 12–18) minimised by L-BFGS with analytic gradients, footpoints and normals
//!    refreshed in an outer loop; rigidity within 10⁻⁴·L or [`FlankError::RigidityNotMet`].
//! 6. [`envelope`]: contact curves of every pose (eqs. 5–6), the real-envelope condition, the
//!    branch nearer the surface.
//! 7. [`output`] and [`collision`]: poses densified to the chordal and angular tolerances, the
//!    program (tool tip + axis per move) through the existing posts ([`crate::gcode`]: A/C with
//!    TCP, APT CL data) with the tool and the strips named in the header; strips entered and
//!    left along the surface normal, links along the tool axis; shank, holder and rapid
//!    collisions flagged, never dropped.
//! 8. The independent verifier [`crate::verify::flank`] reads the CL data back.
//!
//! Entry: [`plan`]. Preconditions: a connected surface from [`crate::mesh`] (normals towards the
//! tool side: `MeshOptions::tool_axis` orients an open surface), options as documented on
//! [`FlankOptions`]. Every fault is a [`FlankError`] naming what is at fault, never a panic.
//!
//! Orientation. The tool's axis (tip → shank) points across the strips along n × D, n the
//! surface normal and D the machining direction: the first strip is on the side of −(n × D),
//! the tool's tip towards it. Reverse the direction to turn the tool round.
//!
//! Deterministic: no hash maps, sequential optimisation, transcendental functions from
//! [`crate::num`]; the same surface and options give the same bits natively and in wasm.

// `!(x > 0.0)` is deliberate throughout: NaN must fail every validity test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod collision;
pub mod envelope;
pub mod field;
pub mod guide;
pub mod lbfgs;
pub mod levels;
pub mod objective;
pub mod optimise;
pub mod output;
pub mod rails;
pub mod tool;

pub use objective::Weights;
pub use tool::{ConeTool, SphereFamily};

use crate::gcode::{GcodeError, GcodeOptions, Post};
use crate::linalg::LinalgError;
use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use crate::toolpath::Toolpath;
use crate::verify::flank::{FlankVerification, FlankVerifyError, FlankVerifyOptions};
use glam::DVec3;
use serde::Serialize;
use std::ops::Range;

impl Weights {
    /// The seed's accuracy priority (Fig. 16, bottom row): w₂ = 1, w₃ = 10⁻³; w₁ = 1, w₄ = 10⁻⁴,
    /// w₅ = 10⁻⁵ (ours: see [`FlankOptions::weights`]).
    pub fn accuracy() -> Weights {
        Weights { rigid: 1.0, approx: 1.0, g1: 1e-3, ini: 1e-4, fair: 1e-5 }
    }

    /// The seed's G¹ priority (Fig. 16, top row): w₂ = 10⁻⁴, w₃ = 1.
    pub fn g1() -> Weights {
        Weights { approx: 1e-4, g1: 1.0, ..Weights::accuracy() }
    }
}

/// Options of [`plan`]. Defaults in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct FlankOptions {
    /// The conical tool [tip radius 1.5, top radius 2.5, flute 20 mm].
    pub tool: ConeTool,
    /// The machining direction D, any length [+X]: the guiding curves run along it.
    pub direction: DVec3,
    /// Number of strips [None: as many as fit across the surface].
    pub strips: Option<usize>,
    /// Spacing of the poses along the first guiding curve, mm [None: 1/100 of the surface's
    /// bounding-box diagonal, the seed's h].
    pub pose_step_mm: Option<f64>,
    /// Samples per tool axis K (eq. 11), ≥ 2 [30].
    pub samples_per_axis: usize,
    /// w₁ … w₅ of eq. 18 [`Weights::accuracy`]. w₅ is ours (the seed omits it): 10⁻⁵ in both
    /// presets. On a row of curvature radius ρ with poses h apart, eq. 14 pulls the grid
    /// inwards by about (w₅/w₂)(h²/ρ)²/ρ: 2 µm on the blade of the tests at G¹ priority, so it
    /// only damps jitter.
    pub weights: Weights,
    /// Outer iterations (footpoint refreshes) per continuation step [30].
    pub outer_iterations: usize,
    /// L-BFGS iterations per outer iteration [300].
    pub inner_iterations: usize,
    /// Rigidity must end within this fraction of L [1e-4].
    pub rigidity_tolerance_rel: f64,
    /// Chordal tolerance of the densified poses, mm [0.002].
    pub chord_tolerance_mm: f64,
    /// Largest axis step between consecutive poses, degrees [0.5].
    pub angle_tolerance_deg: f64,
    /// The tool above the flutes, as the collision check sees it ([`collision`]): the shank's
    /// radius [None: the top radius, a shank no wider than the flutes], the gauge length from
    /// the tip to the holder's face [None: 3 × the flute length, a shank twice the flute
    /// length], the holder's radius [None: twice the shank's] and length [40], and the clearance
    /// wanted from the holder and, on rapids, the flutes [1], mm.
    pub shank_radius_mm: Option<f64>,
    pub gauge_length_mm: Option<f64>,
    pub holder_radius_mm: Option<f64>,
    pub holder_length_mm: f64,
    pub collision_margin_mm: f64,
    /// Distance of the approach and retract points from the surface, along its normal, mm [10].
    pub retract_mm: f64,
    /// Every other strip backwards (short links) [true].
    pub zigzag: bool,
    /// Feeds, mm/min [1000, 300, rapid 5000], spindle speed, rpm [12000], tool number [1].
    pub feed_mm_min: f64,
    pub plunge_feed_mm_min: f64,
    pub rapid_mm_min: f64,
    pub spindle_rpm: f64,
    pub tool_number: u32,
    /// The post: [`Post::Ac`] (A/C with TCP) or [`Post::Cl`] [Ac].
    pub post: Post,
    /// Decimals of coordinates and angles [4].
    pub decimals: usize,
    /// Part name for the header ["part"].
    pub part_name: String,
    /// Verifier samples, 0 skips the verification [20 000].
    pub verify_samples: usize,
    /// The verifier's tolerance, mm [0.01].
    pub verify_tolerance_mm: f64,
}

impl Default for FlankOptions {
    fn default() -> Self {
        FlankOptions {
            tool: ConeTool::default(),
            direction: DVec3::X,
            strips: None,
            pose_step_mm: None,
            samples_per_axis: 30,
            weights: Weights::accuracy(),
            outer_iterations: 30,
            inner_iterations: 300,
            rigidity_tolerance_rel: 1e-4,
            chord_tolerance_mm: 0.002,
            angle_tolerance_deg: 0.5,
            shank_radius_mm: None,
            gauge_length_mm: None,
            holder_radius_mm: None,
            holder_length_mm: 40.0,
            collision_margin_mm: 1.0,
            retract_mm: 10.0,
            zigzag: true,
            feed_mm_min: 1000.0,
            plunge_feed_mm_min: 300.0,
            rapid_mm_min: 5000.0,
            spindle_rpm: 12000.0,
            tool_number: 1,
            post: Post::Ac,
            decimals: 4,
            part_name: "part".to_string(),
            verify_samples: 20_000,
            verify_tolerance_mm: 0.01,
        }
    }
}

/// Everything that can stop a flank plan. Variants name the option, strip or pose at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlankError {
    #[error("option {field} = {value} is invalid: expected {expected}")]
    InvalidOption { field: &'static str, value: f64, expected: &'static str },
    #[error("tool {field} = {value} is invalid: expected {expected}")]
    InvalidTool { field: &'static str, value: f64, expected: &'static str },
    #[error("the machining direction ({x}, {y}, {z}) is not a finite nonzero vector")]
    InvalidDirection { x: f64, y: f64, z: f64 },
    #[error("the machining direction ({x}, {y}, {z}) is along the surface normal everywhere: give a direction tangent to the surface")]
    DirectionAlongNormals { x: f64, y: f64, z: f64 },
    #[error("the guiding field could not be solved: {0}")]
    FieldSolve(LinalgError),
    #[error("no strip fits: the surface is {across_mm:.3} mm across the machining direction, one strip of this tool is {strip_mm:.3} mm wide (tool larger than the part)")]
    NoStripFits { across_mm: f64, strip_mm: f64 },
    #[error("{requested} strips were asked for but only {fit} fit across the surface with this tool")]
    StripsDoNotFit { requested: usize, fit: usize },
    #[error("strip {strip} has {poses} pose(s): at least 2 are needed (a smaller pose step gives more)")]
    TooFewPoses { strip: usize, poses: usize },
    #[error("the optimisation diverged (non-finite grid) in outer iteration {outer_iteration}")]
    Diverged { outer_iteration: usize },
    #[error("rigidity not met: strip {strip}, pose {pose} has its axis {error_mm:.6} mm off the tool's length (tolerance {tolerance_mm:.6} mm); the surface is too curved for this tool here")]
    RigidityNotMet { strip: usize, pose: i64, error_mm: f64, tolerance_mm: f64 },
    #[error("post-processor: {0}")]
    Gcode(#[from] GcodeError),
    #[error("verifier: {0}")]
    Verify(#[from] FlankVerifyError),
}

/// One strip of the plan.
#[derive(Clone, Debug, PartialEq)]
pub struct StripPlan {
    /// The optimised (rigid) poses (a, b) in guiding-curve order (j ascending).
    pub rails: Vec<(DVec3, DVec3)>,
    /// The moves from its first pose to its last in the program.
    pub moves: Range<usize>,
    /// Whether the program runs it backwards (zigzag).
    pub reversed: bool,
    /// The contact curve of every optimised pose at K samples (None where the envelope is not
    /// real), eqs. 5–6.
    pub contact: Vec<Vec<Option<envelope::ContactPoint>>>,
}

/// The plan: report, program text (and CL data, what the verifier read), the toolpath, the
/// strips, the guiding curves.
#[derive(Clone, Debug)]
pub struct FlankPlan {
    pub report: FlankReport,
    pub toolpath: Toolpath,
    pub gcode: String,
    pub cl: String,
    pub strips: Vec<StripPlan>,
    pub guides: guide::Guides,
}

/// The tool as the report shows it: the flutes and what is above them (defaults resolved).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToolReport {
    #[serde(flatten)]
    pub flutes: ConeTool,
    #[serde(flatten)]
    pub body: collision::ToolBody,
}

/// The options as the report shows them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OptionsReport {
    pub tool: ToolReport,
    pub direction: [f64; 3],
    pub strips: Option<usize>,
    pub pose_step_mm: f64,
    pub samples_per_axis: usize,
    pub weights: Weights,
    pub rigidity_tolerance_rel: f64,
    pub chord_tolerance_mm: f64,
    pub angle_tolerance_deg: f64,
    pub post: Post,
    pub decimals: usize,
}

/// Figures of the guiding stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GuideReport {
    pub field_min: f64,
    pub field_max: f64,
    pub field_rms_misfit: f64,
    pub levels: Vec<f64>,
    pub strips: usize,
    /// Poses of every strip (ragged ends make them differ).
    pub poses_per_strip: Vec<usize>,
}

/// Figures of the envelopes of the optimised poses.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnvelopeReport {
    pub contact_samples: usize,
    /// Contact samples where the envelope is not real (eq. 6).
    pub not_real: usize,
}

/// Figures of the program.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OutputReport {
    pub moves: usize,
    pub cut_poses: usize,
    pub cut_length_mm: f64,
    pub link_length_mm: f64,
    pub rapid_length_mm: f64,
    pub max_axis_step_deg: f64,
    pub estimated_time_s: f64,
    pub safe_z_mm: f64,
}

/// Milliseconds per stage.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FlankTimings {
    pub field: f64,
    pub guide: f64,
    pub optimise: f64,
    pub envelope: f64,
    pub output: f64,
    pub post: f64,
    pub verify: f64,
    pub total: f64,
}

/// The plan report (the CLI's `--report`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlankReport {
    pub strategy: &'static str,
    pub options: OptionsReport,
    pub spheres: SphereFamily,
    pub surface_vertices: usize,
    pub surface_faces: usize,
    pub surface_area_mm2: f64,
    pub guide: GuideReport,
    pub optimise: optimise::OptimiseReport,
    pub envelope: EnvelopeReport,
    pub output: OutputReport,
    pub collisions: collision::CollisionReport,
    pub verify: Option<FlankVerification>,
    pub timings_ms: FlankTimings,
}

fn check(o: &FlankOptions) -> Result<(), FlankError> {
    let positive = |field: &'static str, value: f64| {
        if value > 0.0 && value.is_finite() {
            Ok(())
        } else {
            Err(FlankError::InvalidOption { field, value, expected: "a finite number > 0" })
        }
    };
    if let Some(step) = o.pose_step_mm {
        positive("pose_step_mm", step)?;
    }
    positive("rigidity_tolerance_rel", o.rigidity_tolerance_rel)?;
    positive("chord_tolerance_mm", o.chord_tolerance_mm)?;
    positive("angle_tolerance_deg", o.angle_tolerance_deg)?;
    positive("retract_mm", o.retract_mm)?;
    positive("feed_mm_min", o.feed_mm_min)?;
    positive("plunge_feed_mm_min", o.plunge_feed_mm_min)?;
    positive("rapid_mm_min", o.rapid_mm_min)?;
    positive("spindle_rpm", o.spindle_rpm)?;
    positive("verify_tolerance_mm", o.verify_tolerance_mm)?;
    for (field, value) in [("shank_radius_mm", o.shank_radius_mm), ("holder_radius_mm", o.holder_radius_mm)] {
        if let Some(r) = value {
            positive(field, r)?;
        }
    }
    for (field, value) in [("holder_length_mm", o.holder_length_mm), ("collision_margin_mm", o.collision_margin_mm)] {
        if !(value >= 0.0 && value.is_finite()) {
            return Err(FlankError::InvalidOption { field, value, expected: "a finite number ≥ 0" });
        }
    }
    let w = &o.weights;
    for (field, value) in [
        ("weights.rigid", w.rigid),
        ("weights.approx", w.approx),
        ("weights.g1", w.g1),
        ("weights.ini", w.ini),
        ("weights.fair", w.fair),
    ] {
        if !(value >= 0.0 && value.is_finite()) {
            return Err(FlankError::InvalidOption { field, value, expected: "a finite weight ≥ 0" });
        }
    }
    if !(w.rigid > 0.0) {
        return Err(FlankError::InvalidOption { field: "weights.rigid", value: w.rigid, expected: "a weight > 0" });
    }
    if o.samples_per_axis < 2 || o.samples_per_axis > 1000 {
        return Err(FlankError::InvalidOption {
            field: "samples_per_axis",
            value: o.samples_per_axis as f64,
            expected: "2 to 1000 samples",
        });
    }
    if let Some(m) = o.strips {
        if m == 0 || m > 10_000 {
            return Err(FlankError::InvalidOption { field: "strips", value: m as f64, expected: "1 to 10 000 strips" });
        }
    }
    if o.outer_iterations == 0 || o.inner_iterations == 0 {
        return Err(FlankError::InvalidOption {
            field: "outer_iterations",
            value: o.outer_iterations.min(o.inner_iterations) as f64,
            expected: "at least one outer and one inner iteration",
        });
    }
    if !matches!(o.post, Post::Ac | Post::Cl) {
        return Err(FlankError::InvalidOption {
            field: "post",
            value: f64::NAN,
            expected: "the ac (5-axis A/C with TCP) or cl post: flank milling is 5-axis",
        });
    }
    if o.tool_number == 0 {
        return Err(FlankError::InvalidOption { field: "tool_number", value: 0.0, expected: "a tool number ≥ 1" });
    }
    Ok(())
}

/// Plans the flank strips of `surface` (module docs). `progress(stage, done, total)` is called
/// as each stage starts; `now()` is a clock in milliseconds (the core has no clock of its own).
pub fn plan(
    surface: &Surface,
    options: &FlankOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
    now: &dyn Fn() -> f64,
) -> Result<FlankPlan, FlankError> {
    check(options)?;
    let family = options.tool.spheres()?;
    // After the tool's own check, so a bad flute length is named as such.
    if let Some(g) = options.gauge_length_mm {
        if !(g >= options.tool.flute_length_mm && g.is_finite()) {
            return Err(FlankError::InvalidOption {
                field: "gauge_length_mm",
                value: g,
                expected: "a finite length ≥ the flute length (tip to holder face)",
            });
        }
    }
    const STAGES: usize = 7;
    let mut timings = FlankTimings::default();
    let start = now();

    progress("field", 0, STAGES);
    let t = now();
    let field = field::guide_field(surface, options.direction)?;
    timings.field = now() - t;

    progress("guide", 1, STAGES);
    let t = now();
    let (lo, hi) = crate::mesh::weld::bounding_box(&surface.positions);
    let step = options.pose_step_mm.unwrap_or((hi - lo).length() / 100.0);
    let guides = guide::guiding_curves(&guide::GuideInput {
        surface,
        field: &field,
        direction: options.direction,
        family,
        strips: options.strips,
        step_mm: step,
    })?;
    let grid = rails::Grid::new(&guides, family);
    for i in 0..grid.strips() {
        let poses = grid.strip(i).len();
        if poses < 2 {
            return Err(FlankError::TooFewPoses { strip: i + 1, poses });
        }
    }
    timings.guide = now() - t;

    progress("optimise", 2, STAGES);
    let t = now();
    let tree = FaceTree::new(&surface.positions, &surface.triangles);
    let optimised = optimise::optimise(
        surface,
        &tree,
        grid,
        &optimise::OptimiseOptions {
            samples_per_axis: options.samples_per_axis,
            weights: options.weights,
            outer_iterations: options.outer_iterations,
            inner_iterations: options.inner_iterations,
            rigidity_tolerance_rel: options.rigidity_tolerance_rel,
        },
    )?;
    timings.optimise = now() - t;

    progress("envelope", 3, STAGES);
    let t = now();
    let grid = &optimised.grid;
    let distance = |x: DVec3| tree.nearest(x, f64::INFINITY).map_or(f64::INFINITY, |n| n.distance);
    let mut strips: Vec<StripPlan> = Vec::with_capacity(grid.strips());
    let mut envelope_report = EnvelopeReport { contact_samples: 0, not_real: 0 };
    for i in 0..grid.strips() {
        let range = grid.strip_start[i]..grid.strip_start[i + 1];
        let rails = optimised.rails[range].to_vec();
        let contact: Vec<Vec<Option<envelope::ContactPoint>>> = (0..rails.len())
            .map(|j| envelope::contact_curve(&rails, j, &family, options.samples_per_axis, &distance))
            .collect();
        for c in contact.iter().flatten() {
            envelope_report.contact_samples += 1;
            envelope_report.not_real += usize::from(c.is_none());
        }
        strips.push(StripPlan { rails, moves: 0..0, reversed: options.zigzag && i % 2 == 1, contact });
    }
    timings.envelope = now() - t;

    progress("output", 4, STAGES);
    let t = now();
    let out = output::OutputOptions {
        chord_tolerance_mm: options.chord_tolerance_mm,
        angle_tolerance_deg: options.angle_tolerance_deg,
        retract_mm: options.retract_mm,
        zigzag: options.zigzag,
        feed_mm_min: options.feed_mm_min,
        plunge_feed_mm_min: options.plunge_feed_mm_min,
        rapid_mm_min: options.rapid_mm_min,
        spindle_rpm: options.spindle_rpm,
        tool_number: options.tool_number,
    };
    let mut strip_poses = Vec::with_capacity(strips.len());
    for (i, s) in strips.iter().enumerate() {
        let poses = grid.strip(i);
        let retract = |p: &rails::Pose| (grid.normals[p.lower] + grid.normals[p.upper]).normalize_or_zero();
        let (mut first, mut last) = (retract(&poses[0]), retract(&poses[poses.len() - 1]));
        let mut dense = output::densify(&s.rails, &family, &out);
        if s.reversed {
            dense.reverse();
            std::mem::swap(&mut first, &mut last);
        }
        strip_poses.push(output::StripPoses { poses: dense, retract_first: first, retract_last: last });
    }
    let body = tool_body(options);
    let checker = collision::Checker::new(&tree, &options.tool, &body);
    let clear = |from: &crate::toolpath::Move, to: &crate::toolpath::Move| checker.rapid(from, to).is_none();
    let (toolpath, ranges) = output::assemble(&strip_poses, &options.tool, &family, hi.z, &out, &clear);
    for (s, r) in strips.iter_mut().zip(&ranges) {
        s.moves = r.clone();
    }
    let collisions = collision::check(&checker, &toolpath, &ranges);
    timings.output = now() - t;

    progress("post", 5, STAGES);
    let t = now();
    let header = header(options, &family, &body, &ranges, &optimised.report);
    let gcode_options = |post: Post| GcodeOptions {
        post,
        decimals: options.decimals,
        part_name: options.part_name.clone(),
        header: header.clone(),
        blend_tolerance_mm: options.chord_tolerance_mm,
    };
    let cl = crate::gcode::gcode(&toolpath, &gcode_options(Post::Cl))?;
    let gcode = if options.post == Post::Cl {
        cl.clone()
    } else {
        crate::gcode::gcode(&toolpath, &gcode_options(options.post))?
    };
    timings.post = now() - t;

    progress("verify", 6, STAGES);
    let t = now();
    let verification = if options.verify_samples > 0 {
        let vo = FlankVerifyOptions {
            samples: options.verify_samples,
            tolerance_mm: options.verify_tolerance_mm,
            ..FlankVerifyOptions::default()
        };
        Some(crate::verify::flank::verify_flank(surface, &cl, &vo)?)
    } else {
        None
    };
    timings.verify = now() - t;
    timings.total = now() - start;

    let report = FlankReport {
        strategy: "flank",
        options: OptionsReport {
            tool: ToolReport { flutes: options.tool, body },
            direction: options.direction.to_array(),
            strips: options.strips,
            pose_step_mm: step,
            samples_per_axis: options.samples_per_axis,
            weights: options.weights,
            rigidity_tolerance_rel: options.rigidity_tolerance_rel,
            chord_tolerance_mm: options.chord_tolerance_mm,
            angle_tolerance_deg: options.angle_tolerance_deg,
            post: options.post,
            decimals: options.decimals,
        },
        spheres: family,
        surface_vertices: surface.positions.len(),
        surface_faces: surface.triangles.len(),
        surface_area_mm2: surface.area(),
        guide: GuideReport {
            field_min: field.min,
            field_max: field.max,
            field_rms_misfit: field.rms_misfit,
            levels: guides.levels.clone(),
            strips: grid.strips(),
            poses_per_strip: (0..grid.strips()).map(|i| grid.strip(i).len()).collect(),
        },
        optimise: optimised.report.clone(),
        envelope: envelope_report,
        output: OutputReport {
            moves: toolpath.moves.len(),
            cut_poses: toolpath.stats.cut_points,
            cut_length_mm: toolpath.stats.cut_length_mm,
            link_length_mm: toolpath.stats.link_length_mm,
            rapid_length_mm: toolpath.stats.rapid_length_mm,
            max_axis_step_deg: toolpath.stats.max_axis_step_deg,
            estimated_time_s: toolpath.stats.estimated_time_s,
            safe_z_mm: toolpath.stats.safe_z_mm,
        },
        collisions,
        verify: verification,
        timings_ms: timings,
    };
    progress("done", STAGES, STAGES);
    Ok(FlankPlan { report, toolpath, gcode, cl, strips, guides })
}

/// The tool above the flutes with the defaults of [`FlankOptions`] resolved.
pub fn tool_body(o: &FlankOptions) -> collision::ToolBody {
    let shank = o.shank_radius_mm.unwrap_or(o.tool.top_radius_mm);
    collision::ToolBody {
        shank_radius_mm: shank,
        gauge_length_mm: o.gauge_length_mm.unwrap_or(3.0 * o.tool.flute_length_mm),
        holder_radius_mm: o.holder_radius_mm.unwrap_or(2.0 * shank),
        holder_length_mm: o.holder_length_mm,
        margin_mm: o.collision_margin_mm,
    }
}

/// The header lines: the strategy, the tool's spheres and body, the weights, the rigidity
/// reached, and every strip's moves (the verifier reads those back).
fn header(
    o: &FlankOptions,
    f: &SphereFamily,
    body: &collision::ToolBody,
    ranges: &[Range<usize>],
    opt: &optimise::OptimiseReport,
) -> Vec<(String, String)> {
    let w = &o.weights;
    let mut h = vec![
        ("strategy".to_string(), "flank milling, seed 002 (G1 multi-strip, conical tool)".to_string()),
        (
            "tool spheres".to_string(),
            format!(
                "r1 {:.4} r2 {:.4} L {:.4} contact length {:.4} mm",
                f.r1_mm, f.r2_mm, f.length_mm, f.contact_length_mm
            ),
        ),
        (
            "tool body".to_string(),
            format!(
                "shank D{:.4} L{:.4} above the flutes, gauge {:.4}, holder D{:.4} L{:.4}, margin {:.4} mm",
                2.0 * body.shank_radius_mm,
                body.gauge_length_mm - o.tool.flute_length_mm,
                body.gauge_length_mm,
                2.0 * body.holder_radius_mm,
                body.holder_length_mm,
                body.margin_mm
            ),
        ),
        (
            "weights".to_string(),
            format!("rigid {} approx {} g1 {} ini {} fair {}", opt.rigid_weight, w.approx, w.g1, w.ini, w.fair),
        ),
        ("strips".to_string(), format!("{}, {}", ranges.len(), if o.zigzag { "zigzag" } else { "one way" })),
    ];
    for (k, r) in ranges.iter().enumerate() {
        h.push((format!("strip {}", k + 1), format!("moves {}-{}, {} poses", r.start, r.end - 1, r.len())));
    }
    h
}
