//! mesh → flatten → slitmap on every shared mesh with holes (skipped when ../shared is absent):
//! the invariants of the slit map hold for the centroid pole and for a pole in every hole.
#![cfg(not(target_arch = "wasm32"))]

use slitpath::flatten::{self, FlattenInput, FlattenOptions};
use slitpath::mesh::{self, MeshOptions};
use slitpath::slitmap::{Mode, PlanarDomain, SlitMapOptions, SlitMapSolver};
use std::path::PathBuf;

const HOLED: &[&str] = &[
    "beetle.stl",
    "face_holes.stl",
    "inverted_triangles.stl",
    "mech-holes-shark.stl",
    "halftunnel.stl",
    "intersection_quads.stl",
    "wavy_mesh_with_hole.stl",
    "plate_holes.stl",
];

/// `../shared/meshes` beside the main checkout; a worktree elsewhere uses the machine's copy.
fn mesh_dir() -> PathBuf {
    let beside = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes");
    if beside.is_dir() {
        beside
    } else {
        PathBuf::from("/work/shared/meshes")
    }
}

#[test]
fn slit_map_invariants_on_shared_meshes() {
    let dir = mesh_dir();
    for name in HOLED {
        let Ok(bytes) = std::fs::read(dir.join(name)) else {
            eprintln!("skipped: {name} is absent");
            continue;
        };
        let surface = mesh::load(&bytes, &MeshOptions::default()).unwrap().surface;
        let flat = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(flat.quality.flipped_triangles, 0, "{name}");
        let domain = PlanarDomain::of_surface(&surface, flat.uv);
        let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
        // The pole in the domain: the centre of the largest triangle is inside for every shape;
        // plus one pole per hole (the solver picks a deep point).
        let mut poles = vec![domain.largest_face_centre()];
        for h in 1..domain.loops.len() {
            poles.push(solver.canonical_hole_pole(h));
        }
        for pole in poles {
            let m = solver.map(pole).unwrap_or_else(|e| panic!("{name}: {e}"));
            let max_w = m.w.iter().map(|w| w.length()).fold(0.0, f64::max);
            // The exact map has |w| < 1 inside; where a hole's annulus map crowds the far side of
            // a long part into a band near |w| = 1, the P1 solution may overshoot by ~1e-6.
            // Coarse CAD meshes with obtuse triangles (negative cotan weights) lose the discrete
            // maximum principle for far-away annulus poles: reported, asserted for the disk pole.
            if m.mode == Mode::Disk {
                assert!(max_w <= 1.0 + 1e-5, "{name} {pole}: max |w| {max_w}");
            }
            for (i, l) in domain.loops.iter().enumerate().skip(1) {
                let r = m.hole_log_radius[i - 1].exp();
                let spread = l.iter().map(|&v| (m.w[v as usize].length() - r).abs()).fold(0.0, f64::max);
                assert!(spread < 1e-9, "{name}: hole {i} |w| spread {spread}");
            }
            let expected_slits = domain.loops.len() - 1 - usize::from(matches!(m.mode, Mode::Annulus { .. }));
            assert_eq!(m.slits.len(), expected_slits, "{name}");
            for (i, s) in m.slits.iter().enumerate() {
                for t in &m.slits[i + 1..] {
                    if (s.radius - t.radius).abs() < 1e-9 {
                        assert!(!s.contains_angle(t.theta_start) && !t.contains_angle(s.theta_start), "{name}");
                    }
                }
            }
            // Known P1 limitations (issue 3 note): sliver image triangles at slit tips may flip,
            // and an annulus map of a hole at one end of a long part crowds the far end into a
            // band near |w| = 1 thinner than P1 resolves (hundreds of flips on the U-shaped
            // bracket). Those are reported; the disk pole's stay under 2% of the faces (coarse CAD meshes are worst).
            let flipped = m.flipped_triangles();
            eprintln!(
                "{name}: pole {pole:.4} mode {:?} flipped {flipped} of {}, max |w| {max_w:.9}",
                m.mode,
                domain.triangles.len()
            );
            if m.mode == Mode::Disk {
                assert!(flipped * 50 <= domain.triangles.len(), "{name}: {flipped} flipped");
            }
        }
    }
}
