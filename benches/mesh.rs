//! Mesh-stage benchmark (native): read + weld + topology (+ normals and curvature) of a
//! 1-million-triangle binary STL. The wasm twin is in `tests/wasm_bench.rs` (`npm run bench`).
//! Prints figures; asserts nothing about time.

use slitpath::bench::{best_mesh, format_mesh, mesh_sheet};
use slitpath::mesh::stl;
use std::time::Instant;

fn main() {
    let bytes = stl::write_binary(&mesh_sheet(730), "bench sheet");
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let best = best_mesh(&bytes, 3, &now).expect("valid mesh");
    println!("native, best of 3: {}", format_mesh(&best));
}
