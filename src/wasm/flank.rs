//! The flank strategy's entry in the facade (seed 002, issue 35): `planFlank(stl, meshOptions?,
//! options?, onProgress?)` returns a `FlankPlan` whose getters hand out the report (the CLI's
//! `--report` object) and flat typed arrays; `planFlankOnStepFile(file, faces?, meshOptions?,
//! options?, onProgress?)` plans on faces of a `StepFile` already read (issue 36), without
//! reading or tessellating it again. Both take one path from the surface on. Type conversion
//! only.

use super::step::StepFile;
use super::{init, js_err, reject_unknown_fields, to_js, JsMeshOptions, JsStepOptions};
use crate::flank::{self, ConeTool, FlankOptions, Weights};
use crate::gcode::Post;
use serde::Deserialize;
use wasm_bindgen::prelude::*;

/// Flank options as the page passes them (camelCase, all optional; unknown fields are an
/// error). `weights` is `"accuracy"`, `"g1"` or `[w2, w3]`.
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct JsFlankOptions {
    tip_radius_mm: Option<f64>,
    top_radius_mm: Option<f64>,
    flute_length_mm: Option<f64>,
    direction: Option<[f64; 3]>,
    strips: Option<usize>,
    pose_step_mm: Option<f64>,
    samples_per_axis: Option<usize>,
    weights: Option<JsWeights>,
    post: Option<String>,
    chord_tolerance_mm: Option<f64>,
    angle_tolerance_deg: Option<f64>,
    shank_radius_mm: Option<f64>,
    gauge_length_mm: Option<f64>,
    holder_radius_mm: Option<f64>,
    holder_length_mm: Option<f64>,
    collision_margin_mm: Option<f64>,
    retract_mm: Option<f64>,
    zigzag: Option<bool>,
    feed_mm_min: Option<f64>,
    plunge_feed_mm_min: Option<f64>,
    spindle_rpm: Option<f64>,
    decimals: Option<usize>,
    verify_samples: Option<usize>,
    part_name: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum JsWeights {
    Preset(String),
    Pair([f64; 2]),
}

impl JsFlankOptions {
    const FIELDS: [&'static str; 24] = [
        "tipRadiusMm",
        "topRadiusMm",
        "fluteLengthMm",
        "direction",
        "strips",
        "poseStepMm",
        "samplesPerAxis",
        "weights",
        "post",
        "chordToleranceMm",
        "angleToleranceDeg",
        "shankRadiusMm",
        "gaugeLengthMm",
        "holderRadiusMm",
        "holderLengthMm",
        "collisionMarginMm",
        "retractMm",
        "zigzag",
        "feedMmMin",
        "plungeFeedMmMin",
        "spindleRpm",
        "decimals",
        "verifySamples",
        "partName",
    ];

    fn parse(options: JsValue) -> Result<FlankOptions, JsError> {
        reject_unknown_fields(&options, &Self::FIELDS, "flank")?;
        let js: JsFlankOptions = if options.is_undefined() || options.is_null() {
            JsFlankOptions::default()
        } else {
            serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("invalid flank options: {e}")))?
        };
        let d = FlankOptions::default();
        let weights = match js.weights {
            None => d.weights,
            Some(JsWeights::Preset(p)) => match p.as_str() {
                "accuracy" => Weights::accuracy(),
                "g1" => Weights::g1(),
                _ => return Err(JsError::new(&format!("invalid weights `{p}`: use accuracy, g1 or [w2, w3]"))),
            },
            Some(JsWeights::Pair([w2, w3])) => Weights { approx: w2, g1: w3, ..Weights::accuracy() },
        };
        let post = match js.post.as_deref() {
            None => d.post,
            Some("ac") => Post::Ac,
            Some("cl") => Post::Cl,
            Some(p) => return Err(JsError::new(&format!("invalid post `{p}`: flank milling is 5-axis, use ac or cl"))),
        };
        Ok(FlankOptions {
            tool: ConeTool {
                tip_radius_mm: js.tip_radius_mm.unwrap_or(d.tool.tip_radius_mm),
                top_radius_mm: js.top_radius_mm.unwrap_or(d.tool.top_radius_mm),
                flute_length_mm: js.flute_length_mm.unwrap_or(d.tool.flute_length_mm),
            },
            direction: js.direction.map_or(d.direction, glam::DVec3::from_array),
            strips: js.strips,
            pose_step_mm: js.pose_step_mm,
            samples_per_axis: js.samples_per_axis.unwrap_or(d.samples_per_axis),
            weights,
            chord_tolerance_mm: js.chord_tolerance_mm.unwrap_or(d.chord_tolerance_mm),
            angle_tolerance_deg: js.angle_tolerance_deg.unwrap_or(d.angle_tolerance_deg),
            shank_radius_mm: js.shank_radius_mm,
            gauge_length_mm: js.gauge_length_mm,
            holder_radius_mm: js.holder_radius_mm,
            holder_length_mm: js.holder_length_mm.unwrap_or(d.holder_length_mm),
            collision_margin_mm: js.collision_margin_mm.unwrap_or(d.collision_margin_mm),
            retract_mm: js.retract_mm.unwrap_or(d.retract_mm),
            zigzag: js.zigzag.unwrap_or(d.zigzag),
            feed_mm_min: js.feed_mm_min.unwrap_or(d.feed_mm_min),
            plunge_feed_mm_min: js.plunge_feed_mm_min.unwrap_or(d.plunge_feed_mm_min),
            spindle_rpm: js.spindle_rpm.unwrap_or(d.spindle_rpm),
            post,
            decimals: js.decimals.unwrap_or(d.decimals),
            verify_samples: js.verify_samples.unwrap_or(d.verify_samples),
            part_name: js.part_name.unwrap_or(d.part_name),
            ..d
        })
    }
}

/// A flank plan and the surface it was planned on.
#[wasm_bindgen]
pub struct FlankPlan {
    plan: flank::FlankPlan,
    surface: crate::mesh::Surface,
}

/// Plans flank strips for the STL or STEP file `part` (see `JsFlankOptions`; STEP detected by
/// content, its faces chosen by `stepOptions` as in `Planner.fromStep`); `on_progress(stage,
/// done, total)` is called as each stage starts. Throws an `Error` naming the fault.
#[wasm_bindgen(js_name = planFlank)]
pub fn plan_flank(
    part: &[u8],
    mesh_options: JsValue,
    options: JsValue,
    on_progress: Option<js_sys::Function>,
    step_options: JsValue,
) -> Result<FlankPlan, JsError> {
    init();
    let mesh_options = JsMeshOptions::parse(mesh_options)?;
    let options = JsFlankOptions::parse(options)?;
    let surface = if crate::step::is_step(part) {
        let step_options = JsStepOptions::parse(step_options)?;
        crate::step::load(part, &step_options, &mesh_options, &js_sys::Date::now).map_err(js_err)?.mesh.surface
    } else {
        crate::mesh::load(part, &mesh_options).map_err(js_err)?.surface
    };
    plan_on(surface, &options, on_progress)
}

/// `planFlank` on the faces `faces` of a STEP file already read (`undefined`: the faces it was
/// tessellated with, or for a solid its top faces), the part `Planner.fromStepFile` makes of
/// them: the same plan as `planFlank` of the file's bytes with that selection, without reading
/// or tessellating the file again.
#[wasm_bindgen(js_name = planFlankOnStepFile)]
pub fn plan_flank_on_step_file(
    file: &StepFile,
    faces: Option<Vec<f64>>,
    mesh_options: JsValue,
    options: JsValue,
    on_progress: Option<js_sys::Function>,
) -> Result<FlankPlan, JsError> {
    init();
    let mesh_options = JsMeshOptions::parse(mesh_options)?;
    let options = JsFlankOptions::parse(options)?;
    let surface = file.load(faces, &mesh_options).map_err(js_err)?.mesh.surface;
    plan_on(surface, &options, on_progress)
}

/// The flank plan of `surface`, shared by both entries.
fn plan_on(
    surface: crate::mesh::Surface,
    options: &FlankOptions,
    on_progress: Option<js_sys::Function>,
) -> Result<FlankPlan, JsError> {
    let mut progress = |stage: &str, done: usize, total: usize| {
        if let Some(f) = &on_progress {
            let _ = f.call3(&JsValue::NULL, &stage.into(), &(done as f64).into(), &(total as f64).into());
        }
    };
    let plan = flank::plan(&surface, options, &mut progress, &js_sys::Date::now).map_err(js_err)?;
    Ok(FlankPlan { plan, surface })
}

#[wasm_bindgen]
impl FlankPlan {
    /// The plan report (the CLI's `--report` object).
    pub fn report(&self) -> Result<JsValue, JsError> {
        to_js(&self.plan.report)
    }

    /// The program text (A/C G-code or CL data, as asked).
    pub fn gcode(&self) -> String {
        self.plan.gcode.clone()
    }

    /// The CL data the verifier read.
    pub fn cl(&self) -> String {
        self.plan.cl.clone()
    }

    /// Tool tip of every move, flat xyz.
    pub fn tips(&self) -> Vec<f64> {
        self.plan.toolpath.moves.iter().flat_map(|m| m.tip.to_array()).collect()
    }

    /// Unit tool axis of every move, flat xyz.
    pub fn axes(&self) -> Vec<f64> {
        self.plan.toolpath.moves.iter().flat_map(|m| m.axis.to_array()).collect()
    }

    /// Each strip's moves from its first pose to its last, flat `[first0, end0, first1, …]`
    /// (end exclusive).
    #[wasm_bindgen(js_name = stripMoves)]
    pub fn strip_moves(&self) -> Vec<u32> {
        self.plan.strips.iter().flat_map(|s| [s.moves.start as u32, s.moves.end as u32]).collect()
    }

    /// Samples per contact curve (K).
    #[wasm_bindgen(js_name = contactSamples)]
    pub fn contact_samples(&self) -> u32 {
        self.plan.report.options.samples_per_axis as u32
    }

    /// The contact curves (envelope, seed 002 eqs. 5–6) of every optimised pose, strip after
    /// strip, K points each, flat xyz; NaN where the envelope is not real.
    #[wasm_bindgen(js_name = contactPoints)]
    pub fn contact_points(&self) -> Vec<f64> {
        self.plan
            .strips
            .iter()
            .flat_map(|s| s.contact.iter().flatten())
            .flat_map(|c| c.map_or([f64::NAN; 3], |c| c.point.to_array()))
            .collect()
    }

    /// Optimised poses per strip (the contact curves' count per strip).
    #[wasm_bindgen(js_name = posesPerStrip)]
    pub fn poses_per_strip(&self) -> Vec<u32> {
        self.plan.strips.iter().map(|s| s.rails.len() as u32).collect()
    }

    /// The flank verifier's deviation per surface vertex, mm (NaN where uncovered or not
    /// verified).
    #[wasm_bindgen(js_name = vertexDeviation)]
    pub fn vertex_deviation(&self) -> Vec<f64> {
        match &self.plan.report.verify {
            Some(v) => v.vertex_deviation_mm.clone(),
            None => vec![f64::NAN; self.surface.positions.len()],
        }
    }

    /// Vertex positions of the planned surface, flat xyz (f32 for WebGL).
    pub fn positions(&self) -> Vec<f32> {
        self.surface.positions.iter().flat_map(|v| v.as_vec3().to_array()).collect()
    }

    /// Triangles of the planned surface, flat vertex indices.
    pub fn triangles(&self) -> Vec<u32> {
        self.surface.triangles.iter().flatten().copied().collect()
    }
}
