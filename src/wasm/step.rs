//! STEP input for the page: a file read and tessellated once ([`StepFile`]), its faces listed
//! from it, and parts made of any selection of them ([`Planner::from_step_file`], and the flank
//! strategy's `planFlankOnStepFile`) without reading or tessellating it again (a real file of
//! 25 faces takes seconds to tessellate at 0.01 mm).

use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::{init, js_err, now, progress, to_js, JsMeshOptions, JsStepOptions, Planner};
use crate::step::{Model, StepOptions, Tessellation};

/// The faces of a STEP file, tessellated: `{faces: [{id, surface, surface_id, loops, area_mm2,
/// triangles, chordal_error_mm, pcurve_edges, pcurves_off_surface, adjacent}], positions, triangles, face_of_triangle,
/// chordal_error_mm, read_ms, tessellate_ms}` (snake_case keys as serde writes them), for the page
/// to show and pick faces. `stepOptions` as in `Planner.fromStep`; `onProgress(step, done,
/// total)` is called before reading and before tessellating. `new StepFile(…).faces()` gives the
/// same and keeps the file for `Planner.fromStepFile`.
#[wasm_bindgen(js_name = stepFaces)]
pub fn step_faces(
    step: &[u8],
    step_options: JsValue,
    on_progress: Option<js_sys::Function>,
) -> Result<JsValue, JsError> {
    StepFile::new(step, step_options, on_progress)?.faces()
}

/// A STEP file read and tessellated (all its faces, or `stepOptions.faces`), held for listing its
/// faces and making parts of them.
#[wasm_bindgen]
pub struct StepFile {
    model: Model,
    tessellation: Tessellation,
    options: StepOptions,
    /// Read and tessellation times, ms.
    times: [f64; 2],
}

#[wasm_bindgen]
impl StepFile {
    /// Reads and tessellates `step`; throws an `Error` naming the `#id` at fault.
    #[wasm_bindgen(constructor)]
    pub fn new(step: &[u8], step_options: JsValue, on_progress: Option<js_sys::Function>) -> Result<StepFile, JsError> {
        init();
        let options = JsStepOptions::parse(step_options)?;
        let mut progress = progress(&on_progress);
        progress("reading STEP", 0, 2);
        let t0 = now();
        let model = crate::step::read(step).map_err(js_err)?;
        let read_ms = now() - t0;
        progress("tessellating faces", 1, 2);
        let (tessellation, tessellate_ms) = crate::step::tessellate_model(&model, &options, &now).map_err(js_err)?;
        Ok(StepFile { model, tessellation, options, times: [read_ms, tessellate_ms] })
    }

    /// The faces and their tessellation, as `stepFaces` gives them.
    pub fn faces(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Faces<'a> {
            faces: &'a [crate::step::FaceInfo],
            positions: Vec<f32>,
            triangles: Vec<u32>,
            face_of_triangle: &'a [u64],
            chordal_error_mm: f64,
            read_ms: f64,
            tessellate_ms: f64,
        }
        let t = &self.tessellation;
        to_js(&Faces {
            faces: &t.faces,
            positions: t.positions.iter().flat_map(|v| v.as_vec3().to_array()).collect(),
            triangles: t.triangles.iter().flatten().copied().collect(),
            face_of_triangle: &t.face_of_triangle,
            chordal_error_mm: t.chordal_error_mm,
            read_ms: self.times[0],
            tessellate_ms: self.times[1],
        })
    }
}

impl StepFile {
    /// The file's B-rep, for the Coons band (`planCoons`).
    pub(super) fn model(&self) -> &Model {
        &self.model
    }

    /// The part made of faces `faces` (`None`: the faces it was tessellated with, or for a solid
    /// its top faces): `step::load_from`, what `Planner.fromStepFile` and
    /// `planFlankOnStepFile` plan on.
    pub(super) fn load(
        &self,
        faces: Option<Vec<f64>>,
        mesh_options: &crate::mesh::MeshOptions,
    ) -> Result<crate::step::StepOutput, crate::step::StepError> {
        let step_options = match faces {
            Some(ids) => StepOptions { faces: Some(ids.iter().map(|&id| id as u64).collect()), ..self.options.clone() },
            None => self.options.clone(),
        };
        crate::step::load_from(&self.model, &self.tessellation, &step_options, mesh_options, self.times)
    }
}

#[wasm_bindgen]
impl Planner {
    /// The part made of faces `faces` of a STEP file already read (`undefined`: the faces it was
    /// tessellated with, or for a solid its top faces), vertex for vertex what `Planner.fromStep`
    /// makes of the same selection. `options` as for the constructor. Throws an `Error` naming the
    /// `#id` at fault.
    #[wasm_bindgen(js_name = fromStepFile)]
    pub fn from_step_file(file: &StepFile, options: JsValue, faces: Option<Vec<f64>>) -> Result<Planner, JsError> {
        init();
        let options = JsMeshOptions::parse(options)?;
        Ok(Planner::from_step_output(file.load(faces, &options).map_err(js_err)?))
    }
}
