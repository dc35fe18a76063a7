use super::*;
use crate::fixtures;
use crate::mesh::TriMesh;

fn planar(m: &TriMesh) -> PlanarDomain {
    PlanarDomain::from_triangles(m.positions.iter().map(|p| p.truncate()).collect(), m.triangles.clone()).unwrap()
}

/// Möbius automorphism of the unit disk sending a to 0.
fn mobius(a: DVec2, z: DVec2) -> DVec2 {
    let num = z - a;
    let den = DVec2::new(1.0, 0.0) - DVec2::new(a.x, -a.y).rotate(z);
    let d2 = den.length_squared();
    DVec2::new(num.x * den.x + num.y * den.y, num.y * den.x - num.x * den.y) / d2
}

#[test]
fn wrap_and_extent() {
    assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-15);
    assert!((wrap_pi(-PI) - PI).abs() < 1e-15);
    assert!((wrap_pi(0.25) - 0.25).abs() < 1e-15);
    // Arc across the ±π cut: from 170° to 190°.
    let w: Vec<DVec2> =
        [170.0f64, 175.0, 180.0, 185.0, 190.0, 180.0].iter().map(|d| DVec2::from_angle(d.to_radians()) * 0.5).collect();
    let (s, e) = angular_extent(&w, &[0, 1, 2, 3, 4, 5]);
    assert!((s - 170f64.to_radians()).abs() < 1e-12, "{s}");
    assert!((e - 190f64.to_radians()).abs() < 1e-12, "{e}");
    let slit = Slit { hole: 1, radius: 0.5, theta_start: s, theta_end: e };
    assert!(slit.contains_angle(-PI + 0.01));
    assert!(!slit.contains_angle(0.0));
}

#[test]
fn point_in_polygon_and_distance() {
    let pos = vec![DVec2::new(0.0, 0.0), DVec2::new(2.0, 0.0), DVec2::new(2.0, 2.0), DVec2::new(0.0, 2.0)];
    let lp = [0u32, 1, 2, 3];
    assert!(point_in_polygon(&pos, &lp, DVec2::new(1.0, 1.0)));
    // A ray through a vertex is counted once.
    assert!(point_in_polygon(&pos, &lp, DVec2::new(1.0, 2.0 - 1e-12)));
    assert!(!point_in_polygon(&pos, &lp, DVec2::new(3.0, 0.0)));
    assert!(!point_in_polygon(&pos, &lp, DVec2::new(-1.0, 2.0)));
    assert!((polygon_distance(&pos, &lp, DVec2::new(1.0, -0.5)) - 0.5).abs() < 1e-15);
    assert!((polygon_signed_area(&pos, &lp) - 4.0).abs() < 1e-15);
}

#[test]
fn loops_from_triangles() {
    let d = planar(&fixtures::concentric_annulus(0.4, 4));
    assert_eq!(d.loops.len(), 2);
    assert!(polygon_signed_area(&d.positions, &d.loops[0]) > 0.0);
    assert!(polygon_signed_area(&d.positions, &d.loops[1]) < 0.0);
    for &v in &d.loops[0] {
        assert!((d.positions[v as usize].length() - 1.0).abs() < 1e-12);
    }
    for &v in &d.loops[1] {
        assert!((d.positions[v as usize].length() - 0.4).abs() < 1e-12);
    }
}

#[test]
fn typed_errors() {
    let d = planar(&fixtures::concentric_annulus(0.4, 4));
    let solver = SlitMapSolver::new(&d, &SlitMapOptions::default()).unwrap();
    let far = DVec2::new(2.0, 0.0);
    assert_eq!(solver.map(far).unwrap_err(), SlitMapError::PoleOutside { pole: far });
    let on = d.positions[d.loops[1][0] as usize];
    assert!(matches!(solver.map(on).unwrap_err(), SlitMapError::PoleOnBoundary { loop_index: 1, .. }));
    assert!(matches!(solver.map(DVec2::new(f64::NAN, 0.0)).unwrap_err(), SlitMapError::NonFinitePole { .. }));
    assert!(SlitMapError::PoleOutside { pole: far }.to_string().contains("inside"));

    // Wrong loop orientation, flipped triangle, bad index.
    let mut bad = d.clone();
    bad.loops[1].reverse();
    assert!(matches!(
        SlitMapSolver::new(&bad, &SlitMapOptions::default()).unwrap_err(),
        SlitMapError::LoopOrientation { loop_index: 1, .. }
    ));
    let mut bad = d.clone();
    bad.triangles[3].swap(0, 1);
    assert!(matches!(
        SlitMapSolver::new(&bad, &SlitMapOptions::default()).unwrap_err(),
        SlitMapError::FlippedTriangle { face: 3, .. }
    ));
    let mut bad = d.clone();
    bad.triangles[2][1] = 100_000;
    assert!(matches!(
        SlitMapSolver::new(&bad, &SlitMapOptions::default()).unwrap_err(),
        SlitMapError::TriangleIndexOutOfRange { face: 2, .. }
    ));
    let mut bad = d.clone();
    let t = bad.triangles[5];
    bad.positions[t[2] as usize] = bad.positions[t[0] as usize];
    assert!(SlitMapSolver::new(&bad, &SlitMapOptions::default()).is_err());
}

#[test]
fn small_disk_matches_mobius_and_boundary_is_exact() {
    let d = planar(&fixtures::unit_disk(12));
    let a = DVec2::new(0.3, 0.2);
    let m = slit_map(&d, a, &SlitMapOptions::default()).unwrap();
    assert_eq!(m.mode, Mode::Disk);
    assert!(m.slits.is_empty());
    let mut err = 0.0f64;
    for (v, z) in d.positions.iter().enumerate() {
        err = err.max((m.w[v].length() - mobius(a, *z).length()).abs());
    }
    assert!(err < 1e-3, "max | |w| - |mobius| | = {err}");
    for &v in &d.loops[0] {
        assert!((m.w[v as usize].length() - 1.0).abs() < 1e-14);
    }
    // Rotation convention: arg w(loops[0][0]) = 0.
    let w0 = m.w[d.loops[0][0] as usize];
    assert!(w0.y.abs() < 1e-15 && w0.x > 0.0);
    assert_eq!(m.flipped_triangles(), 0);
    // The pole's face maps onto a triangle containing 0.
    let f = m.pole_face.unwrap();
    let loc = m.inverse_map().locate(DVec2::ZERO).unwrap();
    assert_eq!(loc.face, f);
    let z = loc.interpolate(&d.positions);
    assert!((z - a).length() < 2e-2);
}

#[test]
fn inverse_map_round_trip() {
    let d = planar(&fixtures::eccentric_annulus(DVec2::new(0.3, 0.1), 0.35, 10));
    let m = slit_map(&d, DVec2::new(0.3, 0.1), &SlitMapOptions::default()).unwrap();
    let inv = m.inverse_map();
    // Every face centroid of the image is found in its own face (faces do not overlap).
    for (f, t) in d.triangles.iter().enumerate() {
        let c = (m.w[t[0] as usize] + m.w[t[1] as usize] + m.w[t[2] as usize]) / 3.0;
        let loc = inv.locate(c).unwrap();
        assert_eq!(loc.face, f);
        let z = loc.interpolate(&d.positions);
        let zc = (d.positions[t[0] as usize] + d.positions[t[1] as usize] + d.positions[t[2] as usize]) / 3.0;
        assert!((z - zc).length() < 1e-12);
    }
    // The annulus hole and the outside are not in the image; locate_nearest still answers.
    assert!(inv.locate(DVec2::ZERO).is_none());
    assert!(inv.locate(DVec2::new(1.5, 0.0)).is_none());
    let l = inv.locate_nearest(DVec2::new(1.0 + 1e-6, 0.0)).unwrap();
    assert!((l.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
}

#[test]
fn log_polar_corners_are_unwrapped_per_triangle() {
    let d = planar(&fixtures::concentric_annulus(0.4, 6));
    let m = slit_map(&d, DVec2::new(0.05, 0.0), &SlitMapOptions::default()).unwrap();
    let lp = m.log_polar_corners();
    for (c, t) in lp.iter().zip(&d.triangles) {
        for k in 0..3 {
            assert!((c[k].x - c[0].x).abs() < PI);
            assert!((c[k].y - m.w[t[k] as usize].length()).abs() < 1e-15);
        }
    }
}

#[test]
fn the_pole_face_from_the_grid_is_the_linear_scan_s() {
    let d = planar(&fixtures::plate_3_holes());
    let solver = SlitMapSolver::new(&d, &SlitMapOptions::default()).unwrap();
    let scan = |q: DVec2| -> Option<usize> {
        let mut best: Option<(usize, f64)> = None;
        for (f, t) in d.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| d.positions[v as usize]);
            let bary = inverse::barycentric(a, b, c, q);
            let m = bary[0].min(bary[1]).min(bary[2]);
            if m >= -1e-12 && best.map_or(true, |(_, bm)| m > bm) {
                best = Some((f, m));
            }
        }
        best.map(|(f, _)| f)
    };
    // Face centres, vertices (ties between the faces round them) and edge midpoints.
    let mut queries: Vec<DVec2> = d.positions.clone();
    for t in &d.triangles {
        let [a, b, c] = t.map(|v| d.positions[v as usize]);
        queries.extend([(a + b + c) / 3.0, 0.5 * (a + b)]);
    }
    for q in queries {
        assert_eq!(solver.face_containing(q), scan(q), "{q:?}");
    }
}

#[test]
fn issue_3_a_pole_at_one_end_of_a_long_strip_does_not_fold_the_far_end() {
    // A 20 × 2 strip: seen from a pole at one end, the far end is crowded against |w| = 1 by
    // about e^(−π·10), under the P1 error of log|z − p|, and the plain formulation folds a third
    // of the faces there. The far field keeps log|w| discrete harmonic and folds none.
    let d = planar(&fixtures::long_strip_hole());
    let solver = SlitMapSolver::new(&d, &SlitMapOptions::default()).unwrap();
    for pole in [DVec2::new(1.0, 1.0), DVec2::new(0.5, 1.0), DVec2::new(2.0, 0.5)] {
        let face = solver.face_containing(pole);
        let plain = solver.solve(None, pole, face, f64::INFINITY).unwrap().0;
        assert!(count_folds(&plain, &d.triangles) > d.triangles.len() / 5, "{pole}: the plain map no longer folds");
        let m = solver.map(pole).unwrap();
        assert_eq!(m.flipped_triangles(), 0, "{pole}");
        let max_w = m.w.iter().map(|w| w.length()).fold(0.0, f64::max);
        assert!(max_w <= 1.0 + 1e-12, "{pole}: max |w| {max_w}");
        for &v in &d.loops[1] {
            assert!((m.w[v as usize].length() - m.hole_log_radius[0].exp()).abs() < 1e-12);
        }
    }
}

#[test]
fn the_far_field_matches_mobius_on_the_unit_disk_and_converges() {
    // A pole about 0.27 from the boundary: rows beyond about 0.8 from it take the far-field
    // equations.
    let a = DVec2::new(0.72, 0.1);
    let mut errors = Vec::new();
    for rings in [12, 24, 48] {
        let d = planar(&fixtures::unit_disk(rings));
        let solver = SlitMapSolver::new(&d, &SlitMapOptions::default()).unwrap();
        let face = solver.face_containing(a);
        let err = |w: &[DVec2]| {
            d.positions
                .iter()
                .enumerate()
                .map(|(v, z)| (w[v].length() - mobius(a, *z).length()).abs())
                .fold(0.0, f64::max)
        };
        let far = solver.solve(None, a, face, 3.0).unwrap().0;
        let plain = solver.solve(None, a, face, f64::INFINITY).unwrap().0;
        assert!(far != plain, "no far-field row at {rings} rings");
        assert_eq!(count_folds(&far, &d.triangles), 0);
        println!("rings {rings}: max ||w| − |mobius|| far field {:.3e}, plain {:.3e}", err(&far), err(&plain));
        assert!(err(&far) <= 2.0 * err(&plain), "{rings} rings");
        errors.push(err(&far));
    }
    // P1: about 4× per halving of the edge.
    assert!(errors[0] / errors[1] > 3.0 && errors[1] / errors[2] > 3.0, "{errors:?}");
}
