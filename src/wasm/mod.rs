//! The WebAssembly facade: a thin wasm-bindgen layer over the pure core.
//!
//! It only converts types: JS values in, core calls, JS values out. Every core error becomes a JS
//! `Error` whose message is the error's `Display` text (which names the fault); nothing here
//! panics on bad input. A panic in the core (a bug) is printed to the browser console by
//! `console_error_panic_hook`, installed once by every entry point.
//!
//! The page holds one opaque [`Planner`] per loaded part. Later stages (flatten, slit map, origin,
//! spiral, G-code) become further methods on it, each a few lines of conversion.

mod coons;
mod flank;
mod step;

pub use coons::{plan_coons, CoonsPlan};
pub use flank::{plan_flank, plan_flank_on_step_file, FlankPlan};
pub use step::{step_faces, StepFile};

use std::sync::Once;

use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

use crate::gcode::Post;
use crate::mesh::{self, MeshOptions, MeshOutput};
use crate::origin::{EnergyEvaluator, OriginChoice, OriginOptions};
use crate::plan::{Facets, Optimise, Plan, PlanOptions, Planner as Core, RingSpread};
use crate::slitmap::SlitMap;
use crate::spiral::{Cut, Direction};
use crate::toolpath::Axes;

/// Installs the panic hook the first time any entry point runs.
fn init() {
    static ONCE: Once = Once::new();
    ONCE.call_once(console_error_panic_hook::set_once);
}

/// Plain-object serialisation (objects, not `Map`s; integers as numbers).
fn to_js<T: Serialize + ?Sized>(value: &T) -> Result<JsValue, JsError> {
    let serializer = serde_wasm_bindgen::Serializer::json_compatible();
    value.serialize(&serializer).map_err(|e| JsError::new(&e.to_string()))
}

/// The crate version, e.g. `"0.1.0"`.
#[wasm_bindgen]
pub fn version() -> String {
    init();
    env!("CARGO_PKG_VERSION").to_string()
}

/// serde-wasm-bindgen reads only the known fields of an object, so a misspelt option would pass
/// unnoticed: refuse any other key, naming it.
fn reject_unknown_fields(options: &JsValue, fields: &[&str], what: &str) -> Result<(), JsError> {
    let Some(object) = options.dyn_ref::<js_sys::Object>() else { return Ok(()) };
    match js_sys::Object::keys(object).iter().filter_map(|k| k.as_string()).find(|k| !fields.contains(&k.as_str())) {
        Some(key) => Err(JsError::new(&format!(
            "invalid {what} options: unknown field `{key}`, expected one of {}",
            fields.join(", ")
        ))),
        None => Ok(()),
    }
}

/// Options of the mesh stage as the page passes them; every field is optional.
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase")]
struct JsMeshOptions {
    tool_axis: Option<[f64; 3]>,
    wall_angle_deg: Option<f64>,
    weld_tolerance_rel: Option<f64>,
    max_triangles: Option<usize>,
}

impl JsMeshOptions {
    const FIELDS: [&'static str; 4] = ["toolAxis", "wallAngleDeg", "weldToleranceRel", "maxTriangles"];

    /// `undefined` / `null` → defaults; anything else must be an object of known fields.
    fn parse(options: JsValue) -> Result<MeshOptions, JsError> {
        if options.is_undefined() || options.is_null() {
            return Ok(MeshOptions::default());
        }
        reject_unknown_fields(&options, &Self::FIELDS, "mesh")?;
        let js: JsMeshOptions =
            serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("invalid mesh options: {e}")))?;
        let d = MeshOptions::default();
        Ok(MeshOptions {
            tool_axis: js.tool_axis.map_or(d.tool_axis, glam::DVec3::from_array),
            wall_angle_deg: js.wall_angle_deg.unwrap_or(d.wall_angle_deg),
            weld_tolerance_rel: js.weld_tolerance_rel.unwrap_or(d.weld_tolerance_rel),
            max_triangles: js.max_triangles.unwrap_or(d.max_triangles),
            handles: d.handles,
        })
    }
}

/// STEP options as the page passes them (camelCase, all optional; unknown fields are an error).
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct JsStepOptions {
    chordal_tol_mm: Option<f64>,
    max_edge_mm: Option<f64>,
    faces: Option<Vec<u64>>,
    max_triangles: Option<usize>,
}

impl JsStepOptions {
    const FIELDS: [&'static str; 4] = ["chordalTolMm", "maxEdgeMm", "faces", "maxTriangles"];

    fn parse(options: JsValue) -> Result<crate::step::StepOptions, JsError> {
        if options.is_undefined() || options.is_null() {
            return Ok(crate::step::StepOptions::default());
        }
        reject_unknown_fields(&options, &Self::FIELDS, "STEP")?;
        let js: JsStepOptions =
            serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("invalid STEP options: {e}")))?;
        let d = crate::step::StepOptions::default();
        Ok(crate::step::StepOptions {
            chordal_tol_mm: js.chordal_tol_mm.unwrap_or(d.chordal_tol_mm),
            max_edge_mm: js.max_edge_mm.or(d.max_edge_mm),
            faces: js.faces.or(d.faces),
            max_triangles: js.max_triangles.unwrap_or(d.max_triangles),
        })
    }
}

/// Whether the bytes are a STEP file (so the page can choose `Planner.fromStep`).
#[wasm_bindgen(js_name = isStep)]
pub fn is_step(bytes: &[u8]) -> bool {
    crate::step::is_step(bytes)
}

/// One loaded part: the mesh stage's output and the reusable planner (flattening and
/// factorisations), built on first use, and the last plan.
#[wasm_bindgen]
pub struct Planner {
    output: Option<MeshOutput>,
    core: Option<Core>,
    last_map: Option<SlitMap>,
    last_plan: Option<Plan>,
    /// STEP input: the faces the part is made of (the selection, or the top of a solid).
    step_faces: Option<Vec<u64>>,
}

/// Plan options as the page passes them (camelCase, all optional; unknown fields are an error).
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct JsPlanOptions {
    radius_mm: Option<f64>,
    scallop_mm: Option<f64>,
    axes: Option<u8>,
    lead_deg: Option<f64>,
    tilt_deg: Option<f64>,
    direction: Option<Direction>,
    cut: Option<Cut>,
    origin: Option<JsOrigin>,
    post: Option<String>,
    feed_mm_min: Option<f64>,
    plunge_feed_mm_min: Option<f64>,
    spindle_rpm: Option<f64>,
    safe_z_mm: Option<f64>,
    verify_samples: Option<usize>,
    part_name: Option<String>,
    facets: Option<Facets>,
    optimise: Option<Optimise>,
    alpha: Option<f64>,
    spread: Option<RingSpread>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum JsOrigin {
    Name(String),
    Point3 { x: f64, y: f64, z: f64 },
    Plane { x: f64, y: f64 },
}

impl JsPlanOptions {
    const FIELDS: [&'static str; 19] = [
        "radiusMm",
        "scallopMm",
        "axes",
        "leadDeg",
        "tiltDeg",
        "direction",
        "cut",
        "origin",
        "post",
        "feedMmMin",
        "plungeFeedMmMin",
        "spindleRpm",
        "safeZMm",
        "verifySamples",
        "partName",
        "facets",
        "optimise",
        "alpha",
        "spread",
    ];

    fn parse(options: JsValue) -> Result<PlanOptions, JsError> {
        reject_unknown_fields(&options, &Self::FIELDS, "plan")?;
        let js: JsPlanOptions = if options.is_undefined() || options.is_null() {
            JsPlanOptions::default()
        } else {
            serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("invalid plan options: {e}")))?
        };
        let d = PlanOptions::default();
        let origin = match js.origin {
            None => d.origin,
            Some(JsOrigin::Name(n)) => match n.as_str() {
                "auto" => OriginChoice::Auto,
                "centroid" => OriginChoice::Centroid,
                _ => match n.strip_prefix("hole:").and_then(|k| k.parse().ok()) {
                    Some(k) => OriginChoice::Hole(k),
                    None => {
                        return Err(JsError::new(&format!(
                            "invalid origin `{n}`: use auto, centroid, hole:N, {{x, y}} or {{x, y, z}}"
                        )))
                    }
                },
            },
            Some(JsOrigin::Point3 { x, y, z }) => OriginChoice::Point3d(glam::DVec3::new(x, y, z)),
            Some(JsOrigin::Plane { x, y }) => OriginChoice::Plane(glam::DVec2::new(x, y)),
        };
        let axes = match js.axes.unwrap_or(3) {
            3 => Axes::default(),
            5 => Axes::Five { lead_deg: js.lead_deg.unwrap_or(15.0), tilt_deg: js.tilt_deg.unwrap_or(0.0) },
            n => return Err(JsError::new(&format!("invalid axes {n}: use 3 or 5"))),
        };
        let post: Post = match js.post {
            None => d.post,
            Some(p) => p.parse().map_err(|e: String| JsError::new(&e))?,
        };
        Ok(PlanOptions {
            radius_mm: js.radius_mm.unwrap_or(d.radius_mm),
            scallop_mm: js.scallop_mm.unwrap_or(d.scallop_mm),
            origin,
            direction: js.direction.unwrap_or(d.direction),
            cut: js.cut.unwrap_or(d.cut),
            axes,
            post,
            feed_mm_min: js.feed_mm_min.unwrap_or(d.feed_mm_min),
            plunge_feed_mm_min: js.plunge_feed_mm_min.unwrap_or(d.plunge_feed_mm_min),
            spindle_rpm: js.spindle_rpm.unwrap_or(d.spindle_rpm),
            safe_z_mm: js.safe_z_mm,
            verify_samples: js.verify_samples.unwrap_or(d.verify_samples),
            part_name: js.part_name.unwrap_or(d.part_name),
            facets: js.facets.unwrap_or(d.facets),
            optimise: js.optimise.unwrap_or(d.optimise),
            alpha: js.alpha.unwrap_or(d.alpha),
            spread: js.spread.unwrap_or(d.spread),
        })
    }
}

fn now() -> f64 {
    js_sys::Date::now()
}

fn flat<const N: usize>(v: impl Iterator<Item = [f64; N]>) -> Vec<f64> {
    v.flatten().collect()
}

fn js_err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// The core's `progress(step, done, total)` as a call of the page's `onProgress` (when given).
fn progress(on_progress: &Option<js_sys::Function>) -> impl FnMut(&str, usize, usize) + '_ {
    move |stage, done, total| {
        if let Some(f) = on_progress {
            let _ = f.call3(&JsValue::NULL, &stage.into(), &(done as f64).into(), &(total as f64).into());
        }
    }
}

/// What the page shows of a slit map besides the per-vertex image.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct SlitMapInfo<'a> {
    mode: &'static str,
    inner_radius: Option<f64>,
    annulus_hole: Option<usize>,
    slits: &'a [crate::slitmap::Slit],
    flipped_triangles: usize,
}

impl Planner {
    /// A part of STEP faces, loaded.
    fn from_step_output(loaded: crate::step::StepOutput) -> Planner {
        let step_faces = Some(loaded.step.faces.iter().map(|f| f.id).collect());
        Planner { output: Some(loaded.mesh), core: None, last_map: None, last_plan: None, step_faces }
    }
}

#[wasm_bindgen]
impl Planner {
    /// Reads an STL (binary or ASCII) and validates it. `options` is `undefined` or an object
    /// `{toolAxis?: [x, y, z], wallAngleDeg?: number, weldToleranceRel?: number,
    /// maxTriangles?: number}`. Throws an `Error` naming the fault. `onProgress(step, done,
    /// total)` is called as each step starts (reading, checking).
    #[wasm_bindgen(constructor)]
    pub fn new(stl: &[u8], options: JsValue, on_progress: Option<js_sys::Function>) -> Result<Planner, JsError> {
        init();
        let options = JsMeshOptions::parse(options)?;
        let output = mesh::load_with_progress(stl, &options, &mut progress(&on_progress)).map_err(js_err)?;
        Ok(Planner { output: Some(output), core: None, last_map: None, last_plan: None, step_faces: None })
    }

    /// Reads a STEP file (its selected faces, tessellated to the chordal tolerance) instead of
    /// an STL. `options` as for the constructor; `stepOptions` is `undefined` or `{chordalTolMm?,
    /// maxEdgeMm?, faces?: number[], maxTriangles?}`. Throws an `Error` naming the `#id` at fault.
    #[wasm_bindgen(js_name = fromStep)]
    pub fn from_step(step: &[u8], options: JsValue, step_options: JsValue) -> Result<Planner, JsError> {
        init();
        let options = JsMeshOptions::parse(options)?;
        let step_options = JsStepOptions::parse(step_options)?;
        let loaded = crate::step::load(step, &step_options, &options, &now).map_err(js_err)?;
        Ok(Planner::from_step_output(loaded))
    }

    /// STEP input: the ids of the faces the part is made of (the selection asked for, or, for a
    /// solid opened without one, its top faces); `undefined` for an STL.
    #[wasm_bindgen(js_name = stepFaceIds)]
    pub fn step_face_ids(&self) -> Option<Vec<f64>> {
        self.step_faces.as_ref().map(|ids| ids.iter().map(|&id| id as f64).collect())
    }

    /// Builds the planner now (rim refinement, flattening, slit-map factorisation, facet index;
    /// otherwise the first call that needs it does), calling `onProgress(step, done, total)` as
    /// each step starts. Throws for a surface that cannot be planned (closed, genus > 0).
    pub fn prepare(&mut self, on_progress: Option<js_sys::Function>) -> Result<(), JsError> {
        self.core_with(&mut progress(&on_progress)).map(|_| ())
    }

    /// The mesh report (the same object `slitpath info --json` prints).
    pub fn report(&self) -> Result<JsValue, JsError> {
        to_js(&self.mesh().0)
    }

    /// Vertex positions of the surface to machine, flat `[x0, y0, z0, x1, …]`, for WebGL. Once
    /// the planner is built (by `flattened`, `slitMap` or `plan`) this is its surface, whose hole
    /// rims are refined: the part's vertices first, then the added ones, matching every
    /// per-vertex array of the plan.
    pub fn positions(&self) -> Vec<f32> {
        let p = &self.mesh().1.positions;
        p.iter().flat_map(|v| v.as_vec3().to_array()).collect()
    }

    /// Triangles of the surface to machine, flat vertex indices `[a0, b0, c0, a1, …]`.
    pub fn triangles(&self) -> Vec<u32> {
        self.mesh().1.triangles.iter().flatten().copied().collect()
    }

    /// Unit vertex normals (angle-weighted, towards the tool side), flat `[x0, y0, z0, …]`, for
    /// shading.
    pub fn normals(&self) -> Vec<f32> {
        self.mesh().1.vertex_normals.iter().flat_map(|n| n.as_vec3().to_array()).collect()
    }

    /// The boundary loops' vertices, loop after loop (the outer loop first, then the holes in the
    /// order `hole:N` counts them); [`Planner::loop_lengths`] splits them.
    #[wasm_bindgen(js_name = loopVertices)]
    pub fn loop_vertices(&self) -> Vec<u32> {
        self.mesh().1.loops.iter().flatten().copied().collect()
    }

    /// The number of vertices of each boundary loop.
    #[wasm_bindgen(js_name = loopLengths)]
    pub fn loop_lengths(&self) -> Vec<u32> {
        self.mesh().1.loops.iter().map(|l| l.len() as u32).collect()
    }

    /// Flattened positions (BFF, seed 000 §2.1), flat `[u0, v0, u1, …]`, same vertex order.
    /// Factorises once per part; throws for a surface that cannot be planned (closed, genus > 0).
    pub fn flattened(&mut self) -> Result<Vec<f64>, JsError> {
        Ok(self.core()?.flattening.uv.iter().flat_map(|p| p.to_array()).collect())
    }

    /// Quality figures of the flattening (flipped triangles, quasi-conformal distortion, area).
    #[wasm_bindgen(js_name = flattenQuality)]
    pub fn flatten_quality(&mut self) -> Result<JsValue, JsError> {
        to_js(&self.core()?.flattening.quality)
    }

    /// The slit map for a pole `(x, y)` of the flattened plane: the image `w` per vertex, flat
    /// `[re0, im0, re1, …]`. Reuses the factorisation: a new pole costs back-substitutions only.
    #[wasm_bindgen(js_name = slitMap)]
    pub fn slit_map(&mut self, x: f64, y: f64) -> Result<Vec<f64>, JsError> {
        let map = self.core()?.solver.map(glam::DVec2::new(x, y)).map_err(js_err)?;
        let w = map.w.iter().flat_map(|p| p.to_array()).collect();
        self.last_map = Some(map);
        Ok(w)
    }

    /// Mode, inner radius, slits and flipped-triangle count of the last [`Planner::slit_map`].
    #[wasm_bindgen(js_name = slitMapInfo)]
    pub fn slit_map_info(&self) -> Result<JsValue, JsError> {
        let map = self.last_map.as_ref().ok_or_else(|| JsError::new("no slit map computed yet: call slitMap(x, y)"))?;
        let (mode, inner_radius, annulus_hole) = match map.mode {
            crate::slitmap::Mode::Disk => ("disk", None, None),
            crate::slitmap::Mode::Annulus { hole, inner_radius } => ("annulus", Some(inner_radius), Some(hole)),
        };
        to_js(&SlitMapInfo {
            mode,
            inner_radius,
            annulus_hole,
            slits: &map.slits,
            flipped_triangles: map.flipped_triangles(),
        })
    }

    /// Plans with `options` (see `JsPlanOptions`: radiusMm, scallopMm, axes, leadDeg, tiltDeg,
    /// direction, cut, origin, post, feedMmMin, plungeFeedMmMin, spindleRpm, safeZMm,
    /// verifySamples, partName, facets, optimise, alpha, spread) and returns the plan report (the CLI's `--report` object).
    /// `on_progress(stage, done, total)` is called as each stage starts.
    pub fn plan(&mut self, options: JsValue, on_progress: Option<js_sys::Function>) -> Result<JsValue, JsError> {
        let options = JsPlanOptions::parse(options)?;
        let core = self.core()?;
        let plan = core.plan(&options, &mut progress(&on_progress), &now).map_err(js_err)?;
        let report = to_js(&plan.report);
        self.last_plan = Some(plan);
        report
    }

    /// The slit-map image w per vertex for the last plan's pole, flat `[re0, im0, …]`.
    #[wasm_bindgen(js_name = planW)]
    pub fn plan_w(&self) -> Result<Vec<f64>, JsError> {
        Ok(flat(self.last()?.map.w.iter().map(|w| w.to_array())))
    }

    /// |w| of each ring, outermost first.
    #[wasm_bindgen(js_name = ringRadii)]
    pub fn ring_radii(&self) -> Result<Vec<f64>, JsError> {
        Ok(self.last()?.rings.radii())
    }

    /// Cutter-contact points of the spiral, flat xyz.
    #[wasm_bindgen(js_name = pathContacts)]
    pub fn path_contacts(&self) -> Result<Vec<f64>, JsError> {
        Ok(flat(self.last()?.spiral.points.iter().map(|p| p.cc.to_array())))
    }

    /// Slit-domain image w of each spiral point, flat `[re, im, …]`.
    #[wasm_bindgen(js_name = pathW)]
    pub fn path_w(&self) -> Result<Vec<f64>, JsError> {
        Ok(flat(self.last()?.spiral.points.iter().map(|p| p.w.to_array())))
    }

    /// Unit surface normal (towards the tool) of each spiral point, flat xyz.
    #[wasm_bindgen(js_name = pathNormals)]
    pub fn path_normals(&self) -> Result<Vec<f64>, JsError> {
        Ok(flat(self.last()?.spiral.points.iter().map(|p| p.normal.to_array())))
    }

    /// Surface face (index into [`Planner::triangles`]) of each spiral point.
    #[wasm_bindgen(js_name = pathFaces)]
    pub fn path_faces(&self) -> Result<Vec<u32>, JsError> {
        Ok(self.last()?.spiral.points.iter().map(|p| p.face).collect())
    }

    /// Tool tip of every move (lead-in, cut, lead-out, rapids), flat xyz.
    #[wasm_bindgen(js_name = pathTips)]
    pub fn path_tips(&self) -> Result<Vec<f64>, JsError> {
        Ok(flat(self.last()?.toolpath.moves.iter().map(|m| m.tip.to_array())))
    }

    /// Unit tool axis of every move, flat xyz.
    #[wasm_bindgen(js_name = pathAxes)]
    pub fn path_axes(&self) -> Result<Vec<f64>, JsError> {
        Ok(flat(self.last()?.toolpath.moves.iter().map(|m| m.axis.to_array())))
    }

    /// Verified scallop height per surface vertex, mm; NaN where uncovered or not verified.
    #[wasm_bindgen(js_name = vertexScallop)]
    pub fn vertex_scallop(&self) -> Result<Vec<f64>, JsError> {
        let plan = self.last()?;
        Ok(match plan.verification() {
            Some(v) => v
                .vertex_scallop_mm
                .iter()
                .zip(&v.vertex_uncovered)
                .map(|(&s, &u)| if u { f64::NAN } else { s })
                .collect(),
            None => vec![f64::NAN; self.mesh().1.positions.len()],
        })
    }

    /// The G-code (or CL data) of the last plan.
    pub fn gcode(&self) -> Result<String, JsError> {
        Ok(self.last()?.gcode.clone())
    }

    /// E_min (seed 000 eq. 18) for a pole (x, y) of the flattened plane, with the last plan's
    /// ball radius (3 mm before any plan).
    pub fn energy(&mut self, x: f64, y: f64) -> Result<f64, JsError> {
        let radius_mm = self.last_plan.as_ref().map_or(3.0, |p| p.report.options.radius_mm);
        let core = self.core()?;
        let options = OriginOptions { radius_mm, ..OriginOptions::default() };
        let evaluator = EnergyEvaluator::new(&core.surface, &core.solver, &options).map_err(js_err)?;
        Ok(evaluator.evaluate(glam::DVec2::new(x, y)).map_err(js_err)?.e_min)
    }

    fn last(&self) -> Result<&Plan, JsError> {
        self.last_plan.as_ref().ok_or_else(|| JsError::new("no plan yet: call plan(options)"))
    }

    /// The mesh report and surface (from the planner once it is built).
    fn mesh(&self) -> (&crate::mesh::MeshReport, &crate::mesh::Surface) {
        match (&self.output, &self.core) {
            (Some(o), _) => (&o.report, &o.surface),
            (None, Some(c)) => (&c.report, &c.surface),
            (None, None) => unreachable!("a Planner always holds its mesh or its core"),
        }
    }

    fn core(&mut self) -> Result<&Core, JsError> {
        self.core_with(&mut |_, _, _| {})
    }

    fn core_with(&mut self, progress: &mut dyn FnMut(&str, usize, usize)) -> Result<&Core, JsError> {
        if self.core.is_none() {
            let output = self.output.as_ref().expect("the mesh is held until the core is built").clone();
            self.core = Some(Core::prepare(output, &now, progress).map_err(js_err)?);
            self.output = None;
        }
        Ok(self.core.as_ref().expect("just built"))
    }
}
