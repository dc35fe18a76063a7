//! Benchmark cases of STEP input (issue 36), shared by `cargo bench --bench step` and the wasm
//! benchmark (`tests/wasm_bench.rs`, `npm run bench`): a ~20-face file read and tessellated, and
//! seed 004's band spiral over the blade band (the page's STEP sample) with the CLI's defaults.

use crate::coons::{self, CoonsOptions};
use crate::fixtures::step as fx;
use crate::fixtures::step_band::blade_band;
use crate::step::{self, StepOptions};

/// Figures of one STEP import, milliseconds.
#[derive(Clone, Debug)]
pub struct StepFigures {
    pub name: &'static str,
    pub faces: usize,
    pub triangles: usize,
    pub chordal_error_mm: f64,
    pub read_ms: f64,
    pub tessellate_ms: f64,
}

/// The files timed: the 20-face grid and the page's sample (the blade band).
pub fn step_cases() -> Vec<(&'static str, String)> {
    vec![("field_grid (20 b-spline faces)", fx::field_grid()), ("blade_band (8 b-spline faces)", blade_band())]
}

/// Reads and tessellates `text` with the default options (what the page does on opening it),
/// best of `runs` by total time.
pub fn run_step(name: &'static str, text: &str, runs: usize, now: &dyn Fn() -> f64) -> Result<StepFigures, String> {
    let mut best: Option<StepFigures> = None;
    for _ in 0..runs.max(1) {
        let (_, t, [read_ms, tessellate_ms]) =
            step::read_and_tessellate(text.as_bytes(), &StepOptions::default(), now).map_err(|e| e.to_string())?;
        let f = StepFigures {
            name,
            faces: t.faces.len(),
            triangles: t.triangles.len(),
            chordal_error_mm: t.chordal_error_mm,
            read_ms,
            tessellate_ms,
        };
        let total = |f: &StepFigures| f.read_ms + f.tessellate_ms;
        if best.as_ref().map_or(true, |b| total(&f) < total(b)) {
            best = Some(f);
        }
    }
    best.ok_or_else(|| "no run".to_string())
}

pub fn format_step(f: &StepFigures) -> String {
    format!(
        "STEP import, {}: read {:.1} ms, tessellate {:.0} ms, total {:.0} ms ({} faces, {} triangles, chordal error {:.4} mm)",
        f.name,
        f.read_ms,
        f.tessellate_ms,
        f.read_ms + f.tessellate_ms,
        f.faces,
        f.triangles,
        f.chordal_error_mm
    )
}

/// Plans the blade band with the CLI's defaults (5-axis, 100 000 verifier samples) and formats
/// the report's timings.
pub fn run_coons_band(now: &dyn Fn() -> f64) -> Result<String, String> {
    let t0 = now();
    let model = step::read(blade_band().as_bytes()).map_err(|e| e.to_string())?;
    let faces: Vec<u64> = model.faces.iter().map(|f| f.id).collect();
    let read_ms = now() - t0;
    let plan = coons::plan(&model, &faces, &CoonsOptions::default(), now).map_err(|e| e.to_string())?;
    let r = &plan.report;
    let t = &r.timings;
    let max = r.verify.as_ref().map_or(f64::NAN, |v| v.max_scallop_mm);
    Ok(format!(
        "Coons band spiral, blade_band ({} faces, {} revolutions, {:.0} mm): read {:.1} ms, band + Coons {:.0} ms, levels {:.0} ms, path {:.0} ms, toolpath + post {:.0} ms, verify {:.0} ms ({} samples), total {:.0} ms, without the verifier {:.0} ms; max scallop {:.4} mm",
        faces.len(),
        r.revolutions,
        r.length_mm,
        read_ms,
        t.band + t.coons,
        t.levels,
        t.path,
        t.toolpath + t.post,
        t.verify,
        r.verify.as_ref().map_or(0, |v| v.samples),
        t.total + read_ms,
        t.total + read_ms - t.verify,
        max
    ))
}
