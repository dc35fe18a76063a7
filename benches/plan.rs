//! The whole pipeline per stage (native), R = 3 mm, h = 0.02 mm, on the analytic parts (and the
//! 40k-face six-hole panel) and on the shared meshes with holes when present (scaled options, see
//! `slitpath::bench::run_plan_scaled`). The wasm twin is in tests/wasm_bench.rs. Prints
//! figures; asserts nothing about time.

use slitpath::bench::{plan_cases, run_plan, run_plan_scaled, PLAN_HEADER};
use slitpath::mesh::stl;
use std::time::Instant;

// The CLI's allocator (see src/bin/slitpath/main.rs), so the figures are the CLI's.
#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    // `SLITPATH_BENCH_CASE=panel cargo bench --bench plan` runs only the cases whose name has it.
    let only = std::env::var("SLITPATH_BENCH_CASE").unwrap_or_default();
    let mut cases: Vec<(String, _, bool)> = plan_cases(&only).into_iter().map(|(n, m)| (n, m, false)).collect();
    let dir = [std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes"), "/work/shared/meshes".into()]
        .into_iter()
        .find(|d| d.is_dir())
        .unwrap_or_default();
    for name in [
        "wavy_mesh_with_hole.stl",
        "face_holes.stl",
        "halftunnel.stl",
        "inverted_triangles.stl",
        "mech-holes-shark.stl",
        "intersection_quads.stl",
        "plate_holes.stl",
        "featuretype.stl",
        "ktoolcav.stl",
        "beetle.stl",
    ]
    .into_iter()
    .filter(|name| name.contains(&only))
    {
        match std::fs::read(dir.join(name)) {
            Ok(bytes) => cases.push((name.to_string(), stl::read(&bytes, usize::MAX).expect("valid STL"), true)),
            Err(_) => eprintln!("skipped: {name} is absent"),
        }
    }
    println!("whole pipeline, native\n{PLAN_HEADER}");
    // On a thread of the pool, as the CLI runs (see src/bin/slitpath/main.rs).
    let _ = rayon::ThreadPoolBuilder::new().stack_size(8 << 20).build_global();
    rayon::scope(|_| {
        for (name, mesh, shared) in &cases {
            let row = if *shared { run_plan_scaled(name, mesh, &now) } else { run_plan(name, mesh, &now) };
            match row {
                Ok(row) => println!("{row}"),
                Err(e) => println!("{name:<24} cannot be planned: {e}"),
            }
        }
    });
}
