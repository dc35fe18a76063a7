//! Bit-exact digest of a small flank plan (seed 002, issue 35), shared by the native test
//! (`tests/flank.rs`) and the browser test (`tests/wasm.rs`): the program text and the
//! verifier's figures must be the same natively and in wasm. The expected line lives in
//! `tests/digest/flank.txt`, written by the native test (`SLITPATH_UPDATE_DIGESTS=1 cargo test
//! --release --test flank digest`).

use glam::DVec3;
use slitpath::flank::{self, ConeTool, FlankOptions};
use slitpath::gcode::Post;
use slitpath::mesh::{self, stl, MeshOptions};

/// FNV-1a (64 bit) over bytes.
fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in bytes {
        h ^= u64::from(byte);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// `flank gcode=… cl=… verify=…`: digests of the A/C program, the CL data and the verifier's
/// main figures (their `f64` bits) for a coarse plan on a sphere cap, read through STL bytes as
/// the page and the CLI read a part.
pub fn flank_digest() -> String {
    let bytes = stl::write_binary(&slitpath::fixtures::sphere_cap_patch(150.0, 40.0, 24), "cap");
    let surface = mesh::load(&bytes, &MeshOptions::default()).expect("the cap loads").surface;
    let options = FlankOptions {
        tool: ConeTool { tip_radius_mm: 1.5, top_radius_mm: 3.0, flute_length_mm: 20.0 },
        direction: DVec3::X,
        strips: Some(3),
        pose_step_mm: Some(8.0),
        samples_per_axis: 10,
        post: Post::Ac,
        verify_samples: 1500,
        ..FlankOptions::default()
    };
    let plan = flank::plan(&surface, &options, &mut |_, _, _| {}, &|| 0.0).expect("the cap plans");
    let v = plan.report.verify.as_ref().expect("verified");
    let mut figures = vec![v.max_gouge_mm, v.max_undercut_mm, v.coverage_within_tolerance];
    for s in &v.seams {
        figures.extend([s.envelope_max_kink_deg, s.envelope_max_gap_mm, s.sample_max_kink_deg]);
    }
    figures.extend(v.vertex_deviation_mm.iter().copied());
    format!(
        "flank gcode={:016x} cl={:016x} verify={:016x}",
        fnv1a(plan.gcode.bytes()),
        fnv1a(plan.cl.bytes()),
        fnv1a(figures.iter().flat_map(|f| f.to_bits().to_le_bytes()))
    )
}

/// The expected line from `flank.txt`.
pub fn expected() -> &'static str {
    include_str!("flank.txt").trim()
}
