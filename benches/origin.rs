//! Origin-stage benchmark (native): one E_min evaluation (energy of a solved slit map, and slit
//! map + energy) and the whole pole search, on the analytic cases (about 10 000 faces) and the
//! beetle from the shared meshes when present. The cases are in `slitpath::bench` so the wasm
//! benchmark can run the same ones. Prints figures; asserts nothing about time.

use slitpath::bench::{best_origin, format_origin, origin_cases, ORIGIN_HEADER};
use slitpath::mesh::stl;
use std::time::Instant;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let mut cases = origin_cases();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes");
    for name in ["beetle.stl", "face_holes.stl"] {
        match std::fs::read(dir.join(name)) {
            Ok(bytes) => cases.push((name.to_string(), stl::read(&bytes, usize::MAX).expect("valid STL"))),
            Err(_) => eprintln!("skipped: {name} is absent"),
        }
    }
    println!("origin stage, native, best of 3\n{ORIGIN_HEADER}");
    for (name, mesh) in &cases {
        println!("{}", format_origin(&best_origin(name, mesh, 3, &now).expect("plannable")));
    }
}
