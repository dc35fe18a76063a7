//! The Coons band strategy's entry in the facade (seed 004, issue 36): `planCoons(file, faces,
//! options?)`, on a `StepFile` already read, returns a `CoonsPlan` whose getters hand out the report (the CLI's `--report`
//! object), the program and flat typed arrays. Type conversion only.

use super::step::StepFile;
use super::{init, js_err, reject_unknown_fields, to_js, Planner};
use crate::coons::{self, CoonsOptions};
use crate::toolpath::Axes;
use serde::Deserialize;
use wasm_bindgen::prelude::*;

/// Coons options as the page passes them (camelCase, all optional; unknown fields are an error).
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct JsCoonsOptions {
    radius_mm: Option<f64>,
    scallop_mm: Option<f64>,
    axes: Option<u8>,
    lead_deg: Option<f64>,
    tilt_deg: Option<f64>,
    post: Option<String>,
    smooth: Option<bool>,
    feed_mm_min: Option<f64>,
    plunge_feed_mm_min: Option<f64>,
    spindle_rpm: Option<f64>,
    verify_samples: Option<usize>,
    part_name: Option<String>,
}

impl JsCoonsOptions {
    const FIELDS: [&'static str; 12] = [
        "radiusMm",
        "scallopMm",
        "axes",
        "leadDeg",
        "tiltDeg",
        "post",
        "smooth",
        "feedMmMin",
        "plungeFeedMmMin",
        "spindleRpm",
        "verifySamples",
        "partName",
    ];

    fn parse(options: JsValue) -> Result<CoonsOptions, JsError> {
        reject_unknown_fields(&options, &Self::FIELDS, "coons")?;
        let js: JsCoonsOptions = if options.is_undefined() || options.is_null() {
            JsCoonsOptions::default()
        } else {
            serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("invalid coons options: {e}")))?
        };
        let d = CoonsOptions::default();
        let axes = match js.axes {
            None | Some(5) => {
                Axes::Five { lead_deg: js.lead_deg.unwrap_or(15.0), tilt_deg: js.tilt_deg.unwrap_or(0.0) }
            }
            Some(3) => Axes::default(),
            Some(n) => return Err(JsError::new(&format!("invalid axes {n}: use 3 or 5"))),
        };
        let post = match js.post {
            None => d.post,
            Some(p) => p.parse().map_err(|e: String| JsError::new(&e))?,
        };
        Ok(CoonsOptions {
            radius_mm: js.radius_mm.unwrap_or(d.radius_mm),
            scallop_mm: js.scallop_mm.unwrap_or(d.scallop_mm),
            axes,
            post,
            smooth: js.smooth.unwrap_or(d.smooth),
            feed_mm_min: js.feed_mm_min.unwrap_or(d.feed_mm_min),
            plunge_feed_mm_min: js.plunge_feed_mm_min.unwrap_or(d.plunge_feed_mm_min),
            spindle_rpm: js.spindle_rpm.unwrap_or(d.spindle_rpm),
            verify_samples: js.verify_samples.unwrap_or(d.verify_samples),
            part_name: js.part_name.unwrap_or(d.part_name),
            ..d
        })
    }
}

/// A Coons band plan.
#[wasm_bindgen]
pub struct CoonsPlan {
    plan: coons::CoonsPlan,
}

/// Plans seed 004's spiral over the band of faces `faces` (ids) of a STEP file already read
/// (`new StepFile(bytes, …)`: the file is not read again). Throws an `Error` naming the fault;
/// when the faces are not a band of four-sided faces the message says why (the page then offers
/// the slit-map spiral, `Planner.fromStepFile`).
#[wasm_bindgen(js_name = planCoons)]
pub fn plan_coons(file: &StepFile, faces: Vec<f64>, options: JsValue) -> Result<CoonsPlan, JsError> {
    init();
    let options = JsCoonsOptions::parse(options)?;
    let faces: Vec<u64> = faces.iter().map(|&f| f as u64).collect();
    let plan = coons::plan(file.model(), &faces, &options, &js_sys::Date::now).map_err(js_err)?;
    Ok(CoonsPlan { plan })
}

#[wasm_bindgen]
impl CoonsPlan {
    /// The plan report (the CLI's `--report` object).
    pub fn report(&self) -> Result<JsValue, JsError> {
        to_js(&self.plan.report)
    }

    /// The program text.
    pub fn gcode(&self) -> String {
        self.plan.gcode.clone()
    }

    /// Contact points of the path, flat xyz.
    #[wasm_bindgen(js_name = pathContacts)]
    pub fn path_contacts(&self) -> Vec<f64> {
        self.plan.points.iter().flat_map(|p| p.x.to_array()).collect()
    }

    /// The STEP face of every contact point.
    #[wasm_bindgen(js_name = pathFaces)]
    pub fn path_faces(&self) -> Vec<f64> {
        self.plan.points.iter().map(|p| p.face as f64).collect()
    }

    /// Unit surface normal (towards the tool) of every contact point, flat xyz.
    #[wasm_bindgen(js_name = pathNormals)]
    pub fn path_normals(&self) -> Vec<f64> {
        self.plan.points.iter().flat_map(|p| p.n.to_array()).collect()
    }

    /// Tool tip of every move, flat xyz.
    pub fn tips(&self) -> Vec<f64> {
        self.plan.toolpath.moves.iter().flat_map(|m| m.tip.to_array()).collect()
    }

    /// Unit tool axis of every move, flat xyz.
    pub fn axes(&self) -> Vec<f64> {
        self.plan.toolpath.moves.iter().flat_map(|m| m.axis.to_array()).collect()
    }

    /// The scallop under this plan's path at each vertex of `part`'s surface (the band's faces as
    /// `Planner.fromStepFile` makes them), mm, NaN where no pass is over it: the heat map.
    #[wasm_bindgen(js_name = vertexScallopOn)]
    pub fn vertex_scallop_on(&self, part: &Planner) -> Result<Vec<f64>, JsError> {
        self.plan.vertex_scallop_mm(part.mesh().1).map_err(js_err)
    }
}
