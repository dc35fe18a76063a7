//! mesh → flatten → slitmap on every shared mesh with holes (skipped when ../shared is absent):
//! the invariants of the slit map hold for the centroid pole, the largest face's centre, a pole
//! near the outer boundary and a pole in every hole; and poles near every boundary rarely fold.
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
    let (mut probes, mut folding) = (0usize, Vec::new());
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
            // A disk pole at one end of a long part crowds the far end into a band near |w| = 1
            // thinner than the P1 error of log|z − p|: 2 587 faces folded so on the U-shaped
            // bracket, 28 on featuretype near its outer loop, before the far field (issue 3).
            let flipped = m.flipped_triangles();
            eprintln!(
                "{name}: pole {pole:.4} mode {:?} flipped {flipped} of {}, max |w| {max_w:.9}",
                m.mode,
                domain.triangles.len()
            );
            assert_eq!(flipped, 0, "{name}: pole {pole} ({:?}) folds {flipped} faces", m.mode);
            assert!(max_w <= 1.0 + 1e-9, "{name}: pole {pole} ({:?}) max |w| {max_w}", m.mode);
        }
        // Poles 1, 2 and 5 % of the diagonal inside three edges of every loop. The plain
        // formulation folded at 71 of these 454 poles; with the far field 6 fold, at slit tips
        // (a few faces) or, on mech-holes-shark, where a narrow neck crowds the whole part.
        for lp in &domain.loops {
            for k in [0, lp.len() / 3, 2 * lp.len() / 3] {
                for offset in [0.01, 0.02, 0.05] {
                    let (u, v) = (domain.positions[lp[k] as usize], domain.positions[lp[(k + 1) % lp.len()] as usize]);
                    let pole = (u + v) * 0.5 + (v - u).normalize().perp() * offset * (hi - lo).length();
                    if !matches!(solver.classify_pole(pole), Ok(None)) {
                        continue;
                    }
                    let m = solver.map(pole).unwrap_or_else(|e| panic!("{name}: {e}"));
                    probes += 1;
                    let flipped = m.flipped_triangles();
                    let max_w = m.w.iter().map(|w| w.length()).fold(0.0, f64::max);
                    if flipped > 0 {
                        folding.push(format!("{name} {pole:.3}: {flipped}"));
                    } else {
                        assert!(max_w <= 1.0 + 1e-9, "{name}: pole {pole} max |w| {max_w}");
                    }
                }
            }
        }
    }
    eprintln!("{} of {probes} poles near a boundary fold: {folding:?}", folding.len());
    assert!(folding.len() * 50 <= probes, "{} of {probes} poles fold: {folding:?}", folding.len());
}
