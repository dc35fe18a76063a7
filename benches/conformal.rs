//! Conformal-core benchmark (native): mesh, BFF factorisation and solve, slit-map factorisation
//! and one map per pole, on the analytic cases and the shared meshes with holes when present.
//! The wasm twin runs the same analytic cases in headless Chromium (`npm run bench`).
//! Prints figures; asserts nothing about time.

use slitpath::bench::{conformal_cases, format_row, run_conformal, TABLE_HEADER};
use slitpath::mesh::stl;
use std::time::Instant;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let mut cases = conformal_cases();
    // `../shared` beside the main checkout; a worktree elsewhere finds the machine's copy.
    let dir = [std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes"), "/work/shared/meshes".into()]
        .into_iter()
        .find(|d| d.is_dir())
        .unwrap_or_default();
    for name in ["beetle.stl", "face_holes.stl", "inverted_triangles.stl", "wavy_mesh_with_hole.stl"] {
        match std::fs::read(dir.join(name)) {
            Ok(bytes) => cases.push((name.to_string(), stl::read(&bytes, usize::MAX).expect("valid STL"))),
            Err(_) => eprintln!("skipped: {name} is absent"),
        }
    }
    println!("conformal core, native\n{TABLE_HEADER}");
    for (name, mesh) in &cases {
        // Best of 3 per figure: the machine may be shared.
        let runs: Vec<_> = (0..3).map(|_| run_conformal(name, mesh, &now).expect("plannable")).collect();
        let mut best = runs[0].clone();
        for r in &runs[1..] {
            best.mesh_ms = best.mesh_ms.min(r.mesh_ms);
            best.flatten_factorise_ms = best.flatten_factorise_ms.min(r.flatten_factorise_ms);
            best.flatten_solve_ms = best.flatten_solve_ms.min(r.flatten_solve_ms);
            best.slitmap_factorise_ms = best.slitmap_factorise_ms.min(r.slitmap_factorise_ms);
            best.slitmap_pole_ms = best.slitmap_pole_ms.min(r.slitmap_pole_ms);
        }
        println!("{}", format_row(&best));
    }
}
