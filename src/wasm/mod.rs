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

use crate::flatten::{self, FlattenInput, FlattenOptions, Flattening};
use crate::mesh::{self, MeshOptions, MeshOutput};
use crate::slitmap::{PlanarDomain, SlitMap, SlitMapOptions, SlitMapSolver};

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

/// One loaded part: the mesh stage's output and the reusable conformal solvers, built on first use.
#[wasm_bindgen]
pub struct Planner {
    output: MeshOutput,
    conformal: Option<(Flattening, SlitMapSolver)>,
    last_map: Option<SlitMap>,
}

fn js_err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
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
        Ok(Planner { output, conformal: None, last_map: None })
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

    /// Flattened positions (BFF, seed 000 §2.1), flat `[u0, v0, u1, …]`, same vertex order.
    /// Factorises once per part; throws for a surface that cannot be planned (closed, genus > 0).
    pub fn flattened(&mut self) -> Result<Vec<f64>, JsError> {
        Ok(self.conformal()?.0.uv.iter().flat_map(|p| p.to_array()).collect())
    }

    /// Quality figures of the flattening (flipped triangles, quasi-conformal distortion, area).
    #[wasm_bindgen(js_name = flattenQuality)]
    pub fn flatten_quality(&mut self) -> Result<JsValue, JsError> {
        to_js(&self.conformal()?.0.quality)
    }

    /// The slit map for a pole `(x, y)` of the flattened plane: the image `w` per vertex, flat
    /// `[re0, im0, re1, …]`. Reuses the factorisation: a new pole costs back-substitutions only.
    #[wasm_bindgen(js_name = slitMap)]
    pub fn slit_map(&mut self, x: f64, y: f64) -> Result<Vec<f64>, JsError> {
        let map = self.conformal()?.1.map(glam::DVec2::new(x, y)).map_err(js_err)?;
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

    fn conformal(&mut self) -> Result<&(Flattening, SlitMapSolver), JsError> {
        if self.conformal.is_none() {
            let surface = &self.output.surface;
            surface.check_plannable().map_err(js_err)?;
            let flat = flatten::flatten(FlattenInput::from(surface), &FlattenOptions::default()).map_err(js_err)?;
            let domain = PlanarDomain::of_surface(surface, flat.uv.clone());
            let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).map_err(js_err)?;
            self.conformal = Some((flat, solver));
        }
        Ok(self.conformal.as_ref().expect("just built"))
    }
}
