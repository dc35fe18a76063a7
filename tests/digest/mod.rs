//! Bit-exact digests of the conformal core (flattening uv, slit map w), shared by the native test
//! (`tests/determinism.rs`) and the browser test (`tests/wasm.rs`): the page must write the same
//! G-code as the CLI, so both targets must compute the same bits. The expected values live in
//! `tests/digest/expected.txt`, written by the native test (see there how to update them).

use slitpath::flatten::{self, FlattenInput, FlattenOptions};
use slitpath::mesh::{self, stl, MeshOptions};
use slitpath::optimise::{self, OptimiseOptions};
use slitpath::origin::{EnergyEvaluator, OriginOptions};
use slitpath::slitmap::{PlanarDomain, SlitMapOptions, SlitMapSolver};

/// The fixtures digested: two parts with holes, about 4k and 10k faces.
pub const CASES: &[&str] = &["plate_3_holes", "freeform_4_holes"];

/// FNV-1a (64 bit) over the little-endian bytes of each value's `f64::to_bits`.
pub fn fnv1a(values: impl IntoIterator<Item = f64>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for byte in v.to_bits().to_le_bytes() {
            h ^= u64::from(byte);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// One line of `expected.txt`: `name positions=… uv=… w_disk=… w_annulus=… w_tpsfo=…` (hex
/// digests of the welded input positions, the flattening, the disk map for the centre of the
/// largest face, the annulus map of hole 1, and the disk map's field optimised by seed 003).
pub fn digest_line(name: &str) -> String {
    let part = slitpath::fixtures::by_name(name).expect("a fixture name");
    // Through STL bytes, as the page and the CLI read a part (f32 coordinates).
    let bytes = stl::write_binary(&part, name);
    let surface = mesh::load(&bytes, &MeshOptions::default()).expect("the fixture loads").surface;
    let flat = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default()).expect("flattens");
    let domain = PlanarDomain::of_surface(&surface, flat.uv);
    let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).expect("factorises");
    let disk = solver.map(domain.largest_face_centre()).expect("disk map");
    let annulus = solver.map(solver.canonical_hole_pole(1)).expect("annulus map");
    let evaluator = EnergyEvaluator::new(&surface, &solver, &OriginOptions::default()).expect("energy");
    let slopes = evaluator.evaluate_map(&disk).expect("energy of the disk map").slopes;
    let tpsfo = optimise::optimise(&surface, &disk, &slopes, &OptimiseOptions::default()).expect("optimises").map;
    let xy = |v: &[glam::DVec2]| -> Vec<f64> { v.iter().flat_map(|p| [p.x, p.y]).collect() };
    let positions: Vec<f64> = surface.positions.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    format!(
        "{name} positions={:016x} uv={:016x} w_disk={:016x} w_annulus={:016x} w_tpsfo={:016x}",
        fnv1a(positions),
        fnv1a(xy(&domain.positions)),
        fnv1a(xy(&disk.w)),
        fnv1a(xy(&annulus.w)),
        fnv1a(xy(&tpsfo.w))
    )
}

/// The expected line of case `name`, from `expected.txt`.
pub fn expected_line(name: &str) -> Option<&'static str> {
    include_str!("expected.txt").lines().find(|l| l.split_whitespace().next() == Some(name))
}
