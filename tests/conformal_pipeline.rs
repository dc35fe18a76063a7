//! mesh → flatten → slitmap on every shared mesh with holes (skipped when ../shared is absent):
//! the invariants of the slit map hold for the centroid pole and for a pole in every hole.
#![cfg(not(target_arch = "wasm32"))]

mod common;

use glam::DVec2;
use slitpath::flatten::{self, FlattenInput, FlattenOptions};
use slitpath::mesh::{self, MeshOptions};
use slitpath::slitmap::{Mode, PlanarDomain, SlitMapOptions, SlitMapSolver};

const HOLED: &[&str] = &[
    "beetle.stl",
    "face_holes.stl",
    "inverted_triangles.stl",
    "mech-holes-shark.stl",
    "halftunnel.stl",
    "intersection_quads.stl",
    "wavy_mesh_with_hole.stl",
    "plate_holes.stl",
    "featuretype.stl",
    "wheel_in_box.stl",
];

#[test]
fn slit_map_invariants_on_shared_meshes() {
    let dir = common::shared_mesh_dir();
    for name in HOLED {
        let Ok(bytes) = std::fs::read(dir.join(name)) else {
            eprintln!("skipped: {name} is absent");
            continue;
        };
        let surface = mesh::load(&bytes, &MeshOptions::default()).unwrap().surface;
        let surface = slitpath::plan::planning_surface(&surface);
        let flat = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(flat.quality.flipped_triangles, 0, "{name}");
        let domain = PlanarDomain::of_surface(&surface, flat.uv);
        let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
        // The pole in the domain: the centre of the largest triangle is inside for every shape;
        // plus one pole per hole (the solver picks a deep point).
        let centroid = slitpath::origin::centroid_pole(&domain);
        let mut poles = vec![domain.largest_face_centre(), centroid];
        // Near the outer boundary: 2% of the domain's diagonal inside the first outer edge.
        let (lo, hi) = domain.positions.iter().fold((DVec2::MAX, DVec2::MIN), |(a, b), &p| (a.min(p), b.max(p)));
        let (u, v) = (domain.loops[0][0] as usize, domain.loops[0][1] as usize);
        let e = (domain.positions[v] - domain.positions[u]).normalize();
        let near = (domain.positions[u] + domain.positions[v]) * 0.5 + e.perp() * 0.02 * (hi - lo).length();
        if matches!(solver.classify_pole(near), Ok(None)) {
            poles.push(near);
        }
        for h in 1..domain.loops.len() {
            poles.push(solver.canonical_hole_pole(h));
        }
        for pole in poles {
            let m = solver.map(pole).unwrap_or_else(|e| panic!("{name}: {e}"));
            let max_w = m.w.iter().map(|w| w.length()).fold(0.0, f64::max);
            // The exact map has |w| < 1 inside; where a disk pole at one end of a long part
            // crowds the far side into a band near |w| = 1, the P1 solution may overshoot by ~1e-5
            // (asserted to 1e-9 for the centroid pole and every annulus pole below).
            assert!(max_w <= 1.0 + 1e-4, "{name} {pole}: max |w| {max_w}");
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
            // Known P1 limitation (issue 3 note): a disk pole near one end of a long part crowds
            // the far end into a band near |w| = 1 thinner than P1 resolves (2.6k folds on the
            // U-shaped bracket), too many to untangle locally. Those are reported.
            let flipped = m.flipped_triangles();
            eprintln!(
                "{name}: pole {pole:.4} mode {:?} flipped {flipped} of {}, max |w| {max_w:.9}",
                m.mode,
                domain.triangles.len()
            );
            // The planner's starting pole: rims refined, flat regions remeshed (featuretype, a
            // 10-hole CAD part of 420 faces, folded 226 faces here before; issue 3), Delaunay
            // Laplacians and the untangling pass leave no fold and no overshoot.
            // Annulus poles: U and V are exactly discrete harmonic (featuretype folded 794 faces
            // at hole 3's pole and inverted_triangles 329 at hole 3's when U was log|z − p| + h;
            // issue 3).
            if pole == centroid || m.mode != Mode::Disk {
                assert_eq!(flipped, 0, "{name}: pole {pole} ({:?}) folds {flipped} faces", m.mode);
                assert!(max_w <= 1.0 + 1e-9, "{name}: pole {pole} ({:?}) max |w| {max_w}", m.mode);
            }
        }
    }
}
