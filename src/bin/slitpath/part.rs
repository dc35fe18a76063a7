//! Reading a part: STL, or STEP (detected by its content or a `.step`/`.stp` name) through the
//! `step` stage, which also gives the report's `step` section.

use slitpath::mesh::{self, MeshOptions, MeshOutput};
use slitpath::step::{self, StepOptions, StepReport};
use std::path::Path;

/// Whether the part is a STEP file.
pub fn is_step(path: &Path, bytes: &[u8]) -> bool {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    step::is_step(bytes) || matches!(ext.as_deref(), Some("step" | "stp"))
}

/// Reads the part into the planner's surface; for STEP, the STEP report too. `now` gives ms.
pub fn load(
    path: &Path,
    mesh_options: &MeshOptions,
    step_options: &StepOptions,
    now: &dyn Fn() -> f64,
) -> Result<(MeshOutput, Option<StepReport>), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let name = path.display();
    if is_step(path, &bytes) {
        let out = step::load(&bytes, step_options, mesh_options, now).map_err(|e| format!("{name}: {e}"))?;
        if out.step.top_of_solid {
            let ids: Vec<String> = out.step.faces.iter().map(|f| format!("#{}", f.id)).collect();
            eprintln!(
                "note: {name}: its faces enclose a solid; planning its top, faces {} (choose others with --faces)",
                ids.join(",")
            );
        }
        Ok((out.mesh, Some(out.step)))
    } else {
        if step_options.faces.is_some() {
            return Err(format!("{name}: --faces needs a STEP file"));
        }
        Ok((mesh::load(&bytes, mesh_options).map_err(|e| format!("{name}: {e}"))?, None))
    }
}

/// The report as pretty JSON, with the `step` section added when there is one.
pub fn report_json<T: serde::Serialize>(report: &T, step: Option<&StepReport>) -> Result<String, String> {
    let mut value = serde_json::to_value(report).map_err(|e| e.to_string())?;
    if let (Some(s), serde_json::Value::Object(map)) = (step, &mut value) {
        map.insert("step".into(), serde_json::to_value(s).map_err(|e| e.to_string())?);
    }
    serde_json::to_string_pretty(&value).map_err(|e| e.to_string())
}

/// `12,13,…` (a leading `#` allowed) → face ids.
pub fn parse_faces(s: &str) -> Result<Vec<u64>, String> {
    s.split(',')
        .map(|p| {
            p.trim().trim_start_matches('#').parse::<u64>().map_err(|_| format!("--faces: `{p}` is not a face id"))
        })
        .collect()
}

/// `slitpath faces`: every face with its surface type, area, loops and neighbours.
pub fn print_faces(path: &Path, step_options: &StepOptions, json: bool) -> Result<(), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let started = std::time::Instant::now();
    let now = || started.elapsed().as_secs_f64() * 1e3;
    let (model, tess, [read_ms, tess_ms]) =
        step::read_and_tessellate(&bytes, step_options, &now).map_err(|e| format!("{}: {e}", path.display()))?;
    if json {
        let value = serde_json::json!({
            "unit": model.unit_name, "unit_mm": model.unit_mm, "faces": tess.faces,
            "chordal_error_mm": tess.chordal_error_mm, "triangles": tess.triangles.len(),
            "read_ms": read_ms, "tessellate_ms": tess_ms,
        });
        println!("{value}");
        return Ok(());
    }
    println!("{}: {} faces, unit {} ({} mm)", path.display(), model.faces.len(), model.unit_name, model.unit_mm);
    println!("{:>8}  {:<18} {:>12} {:>6} {:>9}  adjacent", "face", "surface", "area mm²", "loops", "triangles");
    for f in &tess.faces {
        let adj: Vec<String> = f.adjacent.iter().map(|a| format!("#{a}")).collect();
        println!(
            "{:>8}  {:<18} {:>12.3} {:>6} {:>9}  {}",
            format!("#{}", f.id),
            f.surface,
            f.area_mm2,
            f.loops,
            f.triangles,
            adj.join(" ")
        );
    }
    println!(
        "{} triangles, chordal error {:.5} mm (tolerance {} mm); read {:.1} ms, tessellated {:.1} ms",
        tess.triangles.len(),
        tess.chordal_error_mm,
        step_options.chordal_tol_mm,
        read_ms,
        tess_ms
    );
    Ok(())
}
