//! The WebAssembly facade: a thin wasm-bindgen layer over the pure core.
//!
//! It only converts types: JS values in, core calls, JS values out. Every core error becomes a JS
//! `Error` whose message is the error's `Display` text (which names the fault); nothing here
//! panics on bad input. A panic in the core (a bug) is printed to the browser console by
//! `console_error_panic_hook`, installed once by every entry point.
//!
//! The page holds one opaque [`Planner`] per loaded part. Later stages (flatten, slit map, origin,
//! spiral, G-code) become further methods on it, each a few lines of conversion.

use std::sync::Once;

use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

use crate::mesh::{self, MeshOptions, MeshOutput};

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
        // serde-wasm-bindgen only reads the known fields: a misspelt one would pass unnoticed.
        if let Some(object) = options.dyn_ref::<js_sys::Object>() {
            if let Some(key) = js_sys::Object::keys(object)
                .iter()
                .filter_map(|k| k.as_string())
                .find(|k| !Self::FIELDS.contains(&k.as_str()))
            {
                return Err(JsError::new(&format!(
                    "invalid mesh options: unknown field `{key}`, expected one of {}",
                    Self::FIELDS.join(", ")
                )));
            }
        }
        let js: JsMeshOptions =
            serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("invalid mesh options: {e}")))?;
        let d = MeshOptions::default();
        Ok(MeshOptions {
            tool_axis: js.tool_axis.map_or(d.tool_axis, glam::DVec3::from_array),
            wall_angle_deg: js.wall_angle_deg.unwrap_or(d.wall_angle_deg),
            weld_tolerance_rel: js.weld_tolerance_rel.unwrap_or(d.weld_tolerance_rel),
            max_triangles: js.max_triangles.unwrap_or(d.max_triangles),
        })
    }
}

/// One loaded part: the mesh stage's output, and later the planner's reusable solvers.
#[wasm_bindgen]
pub struct Planner {
    output: MeshOutput,
}

#[wasm_bindgen]
impl Planner {
    /// Reads an STL (binary or ASCII) and validates it. `options` is `undefined` or an object
    /// `{toolAxis?: [x, y, z], wallAngleDeg?: number, weldToleranceRel?: number,
    /// maxTriangles?: number}`. Throws an `Error` naming the fault.
    #[wasm_bindgen(constructor)]
    pub fn new(stl: &[u8], options: JsValue) -> Result<Planner, JsError> {
        init();
        let options = JsMeshOptions::parse(options)?;
        let output = mesh::load(stl, &options).map_err(|e| JsError::new(&e.to_string()))?;
        Ok(Planner { output })
    }

    /// The mesh report (the same object `slitpath info --json` prints).
    pub fn report(&self) -> Result<JsValue, JsError> {
        to_js(&self.output.report)
    }

    /// Vertex positions of the surface to machine, flat `[x0, y0, z0, x1, …]`, for WebGL.
    pub fn positions(&self) -> Vec<f32> {
        let p = &self.output.surface.positions;
        p.iter().flat_map(|v| v.as_vec3().to_array()).collect()
    }

    /// Triangles of the surface to machine, flat vertex indices `[a0, b0, c0, a1, …]`.
    pub fn triangles(&self) -> Vec<u32> {
        self.output.surface.triangles.iter().flatten().copied().collect()
    }
}
