//! The verifier against closed forms (flat plane under parallel passes, sphere cap under rings),
//! gouges, uncovered regions and overlaps with known answers, an all-segments brute force,
//! path metrics of a regular polygon, determinism and typed errors.
// Native only: runs rs274 / reads files / uses serde_json (the browser tests are tests/wasm.rs).
#![cfg(not(target_arch = "wasm32"))]

use glam::DVec3;
use slitpath::fixtures;
use slitpath::mesh::nearest::FaceTree;
use slitpath::mesh::{self, MeshOptions, Surface, TriMesh};
use slitpath::verify::{
    count_runs, path_metrics, sample_surface, verify, verify_with_faces, SweptVolume, Verification, VerifyError,
    VerifyOptions,
};

const R: f64 = 3.0;

fn surface_of(m: &TriMesh) -> Surface {
    mesh::from_triangles(m, &MeshOptions::default()).expect("valid fixture").surface
}

/// Flat disk of radius `radius` in z = 0, normals +Z.
fn flat_disk(radius: f64) -> Surface {
    let mut m = fixtures::unit_disk(40);
    for p in &mut m.positions {
        *p *= radius;
    }
    surface_of(&m)
}

/// Straight passes along x (x ∈ [−25, 25]) at the given y and height. Every other pass is a
/// single long segment, the rest have a centre every 0.7 mm (both must give the same capsules).
fn passes_along_x(ys: &[f64], z: f64) -> Vec<Vec<DVec3>> {
    ys.iter()
        .enumerate()
        .map(|(k, &y)| {
            let n = if k % 2 == 0 { 1 } else { 72 };
            (0..=n).map(|i| DVec3::new(-25.0 + 50.0 * i as f64 / n as f64, y, z)).collect()
        })
        .collect()
}

/// R − √(R² − x²): the scallop at lateral distance x from a ball swept at height R over a plane.
fn flat_scallop(x: f64) -> f64 {
    R - (R * R - x * x).sqrt()
}

/// Mean of the flat scallop for x uniform in [0, a].
fn flat_scallop_mean(a: f64) -> f64 {
    R - (a * (R * R - a * a).sqrt() + R * R * (a / R).asin()) / (2.0 * a)
}

/// Area of the part |y| < w of a disk of radius r.
fn strip_area(r: f64, w: f64) -> f64 {
    2.0 * (w * (r * r - w * w).sqrt() + r * r * (w / r).asin())
}

#[test]
fn flat_plane_under_parallel_passes_matches_the_closed_form() {
    let surface = flat_disk(20.0);
    let (d, y0) = (1.1, 0.123);
    let ys: Vec<f64> = (-23..=23).map(|k| y0 + k as f64 * d).collect();
    let passes = passes_along_x(&ys, R);
    let lateral = |y: f64| {
        let k = ((y - y0) / d).round();
        (y - (y0 + k * d)).abs()
    };
    let options = VerifyOptions::default();

    // Sample by sample, through the same samples the verifier draws.
    let volume = SweptVolume::new(&passes, R).unwrap();
    let mut prober = volume.prober();
    let samples = sample_surface(&surface, options.samples, options.seed).unwrap();
    let mut worst_error = 0.0f64;
    for s in &samples {
        assert_eq!(s.position.z, 0.0);
        assert_eq!(s.normal, DVec3::Z);
        let probe = prober.probe(s.position, s.normal, options.scallop_mm, R);
        let t = probe.scallop.expect("every sample is covered");
        worst_error = worst_error.max((t - flat_scallop(lateral(s.position.y))).abs());
        assert_eq!(probe.depth, f64::NEG_INFINITY, "no segment is within R of the plane");
    }
    assert!(worst_error < 1e-9, "sample-wise error {worst_error:e}");

    let v = verify(&surface, &passes, &options).unwrap();
    let a = d / 2.0;
    println!("flat plane: {}", serde_json::to_string(&v).unwrap());
    assert!((v.max_scallop_mm - flat_scallop(a)).abs() < 1e-6 * R, "max {} vs {}", v.max_scallop_mm, flat_scallop(a));
    assert!(v.max_scallop_mm <= flat_scallop(a) + 1e-12);
    assert!((v.mean_scallop_mm / flat_scallop_mean(a) - 1.0).abs() < 0.015, "mean {}", v.mean_scallop_mm);
    for (p, q) in [(v.p95_scallop_mm, 0.95), (v.p99_scallop_mm, 0.99)] {
        assert!((p - flat_scallop(q * a)).abs() < 0.01 * flat_scallop(a), "p{q}: {p} vs {}", flat_scallop(q * a));
    }
    let worst = v.worst_sample.unwrap();
    assert!((lateral(worst[1]) - a).abs() < 1e-3);
    assert_eq!((v.uncovered_samples, v.gouges, v.max_gouge_mm), (0, 0, 0.0));
    assert_eq!(v.retractions, ys.len() - 1);
    assert_eq!(v.segments, ys.len() / 2 * 72 + ys.len().div_ceil(2));
    // CT on S^h: q = p + h·n is under one pass when its lateral distance is below
    // w = √(R² − (R − h)²), else under none.
    let h = options.scallop_mm;
    let w = (R * R - (R - h) * (R - h)).sqrt();
    assert_eq!(v.max_ct, 1);
    assert!((v.mean_ct / (2.0 * w / d) - 1.0).abs() < 0.01, "mean CT {}", v.mean_ct);
    assert!((v.ct2 / (surface.area() * 2.0 * w / d) - 1.0).abs() < 0.01, "CT² {}", v.ct2);
    // Per vertex: exact.
    assert_eq!(v.vertex_scallop_mm.len(), surface.positions.len());
    for (p, &t) in surface.positions.iter().zip(&v.vertex_scallop_mm) {
        assert!((t - flat_scallop(lateral(p.y))).abs() < 1e-9, "vertex {p}: {t}");
    }
    assert!(v.vertex_uncovered.iter().all(|u| !u));
    // V_max (seed 000 eq. 23) recomputed from the closed form: cells of 2R from the lowest
    // corner of the surface, the maximum per cell, their population variance.
    let origin = surface.positions.iter().fold(DVec3::splat(f64::INFINITY), |m, &p| m.min(p));
    let mut cells = std::collections::BTreeMap::<[i64; 3], f64>::new();
    for s in &samples {
        let k = ((s.position - origin) / (2.0 * R)).floor();
        let m = cells.entry([k.x as i64, k.y as i64, k.z as i64]).or_insert(0.0);
        *m = m.max(flat_scallop(lateral(s.position.y)));
    }
    let mean = cells.values().sum::<f64>() / cells.len() as f64;
    let var = cells.values().map(|m| (m - mean).powi(2)).sum::<f64>() / cells.len() as f64;
    assert_eq!(v.v_max_cells, cells.len());
    assert!((v.v_max_mm2 - var).abs() < 1e-12 * var.max(1e-12), "V_max {} vs {var}", v.v_max_mm2);
    // The report stays small: no per-vertex arrays in JSON.
    let json = serde_json::to_string(&v).unwrap();
    assert!(!json.contains("vertex_") && json.len() < 1000, "{json}");
}

/// The spherical cap fixture: sphere radius 60 about (0, 0, −z0).
const CAP_RHO: f64 = 60.0;

fn cap_centre() -> DVec3 {
    DVec3::new(0.0, 0.0, -(60.0f64 * 60.0 - 40.0 * 40.0).sqrt())
}

/// Rings of ball centres at polar angles k·Δθ (k ≥ 1) on the offset sphere of radius ρ + R,
/// closed polygons of `n` sides, plus the lone centre over the pole (k = 0).
fn cap_rings(dtheta: f64, rings: usize, n: usize) -> (Vec<Vec<DVec3>>, f64) {
    let c = cap_centre();
    let big = CAP_RHO + R;
    let mut passes = vec![vec![c + big * DVec3::Z]];
    let mut sagitta = 0.0f64;
    for k in 1..=rings {
        let th = k as f64 * dtheta;
        let ring_r = big * th.sin();
        sagitta = sagitta.max(ring_r * (1.0 - (std::f64::consts::PI / n as f64).cos()));
        passes.push(
            (0..=n)
                .map(|i| {
                    let ph = std::f64::consts::TAU * (i % n) as f64 / n as f64;
                    c + big * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
                })
                .collect(),
        );
    }
    (passes, sagitta)
}

/// Scallop at polar angle θ under the rings: in the meridian plane the swept tube is a disk of
/// radius R about the nearest ring centre, at angular distance Δ.
fn cap_scallop(theta: f64, dtheta: f64) -> f64 {
    let k = (theta / dtheta).round();
    let delta = (theta - k * dtheta).abs();
    let big = CAP_RHO + R;
    big * delta.cos() - (R * R - big * big * delta.sin().powi(2)).sqrt() - CAP_RHO
}

#[test]
fn sphere_cap_under_rings_matches_the_analytic_scallop() {
    let dtheta = 1.6 / CAP_RHO; // 1.6 mm between rings on the surface
    let theta_max = (40.0f64 / CAP_RHO).asin();
    let rings = (theta_max / dtheta).ceil() as usize + 1;
    let (passes, sagitta) = cap_rings(dtheta, rings, 3000);
    let volume = SweptVolume::new(&passes, R).unwrap();
    let mut prober = volume.prober();
    // Exact sphere points and normals: the only error is the polygon's chord sagitta.
    let tol = 2.0 * sagitta + 1e-9;
    let mut worst = 0.0f64;
    for i in 0..20_000 {
        let theta = theta_max * ((i as f64 * 0.618_034) % 1.0);
        let phi = std::f64::consts::TAU * ((i as f64 * 0.414_214) % 1.0);
        let u = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        let t = prober.probe(cap_centre() + CAP_RHO * u, u, 0.02, R).scallop.expect("covered");
        worst = worst.max((t - cap_scallop(theta, dtheta)).abs());
    }
    println!("sphere cap, exact points: max error {worst:e} (sagitta {sagitta:e})");
    assert!(worst < tol, "max error {worst:e} > {tol:e}");

    // The verifier on the faceted fixture: vertices lie on the sphere, their normals are the
    // mesh's angle-weighted estimate.
    let surface = surface_of(&fixtures::spherical_cap_hole());
    let v = verify(&surface, &passes, &VerifyOptions::default()).unwrap();
    let mut on_loop = vec![false; surface.positions.len()];
    for l in &surface.loops {
        for &i in l {
            on_loop[i as usize] = true;
        }
    }
    let (mut vertex_error, mut rim_error) = (0.0f64, 0.0f64);
    for (i, (p, &t)) in surface.positions.iter().zip(&v.vertex_scallop_mm).enumerate() {
        let u = (*p - cap_centre()) / CAP_RHO;
        let e = (t - cap_scallop(u.z.clamp(-1.0, 1.0).acos(), dtheta)).abs();
        if on_loop[i] {
            rim_error = rim_error.max(e);
        } else {
            vertex_error = vertex_error.max(e);
        }
    }
    println!("sphere cap mesh: vertex error inside {vertex_error:e}, on the rims {rim_error:e}");
    let max_exact = cap_scallop(0.5 * dtheta, dtheta);
    assert!(vertex_error < 1e-4 && rim_error < 1e-3);
    // Samples on a flat face lie below the sphere by at most ρ − (distance of its plane).
    let facet = (0..surface.triangles.len())
        .map(|f| {
            CAP_RHO - (surface.positions[surface.triangles[f][0] as usize] - cap_centre()).dot(surface.face_normals[f])
        })
        .fold(0.0, f64::max);
    println!("sphere cap mesh: max {} vs exact {max_exact} + facet depth {facet}", v.max_scallop_mm);
    assert!(v.max_scallop_mm > max_exact - 1e-4 && v.max_scallop_mm < max_exact + 1.01 * facet);
    assert_eq!((v.uncovered_samples, v.gouges, v.retractions), (0, 0, rings));
}

#[test]
fn a_plunged_pass_is_a_gouge_of_the_right_depth() {
    let surface = flat_disk(20.0);
    let plunge = 0.1;
    let passes = vec![vec![DVec3::new(-25.0, 0.0, R - plunge), DVec3::new(25.0, 0.0, R - plunge)]];
    let options = VerifyOptions::default();
    let volume = SweptVolume::new(&passes, R).unwrap();
    let mut prober = volume.prober();
    for s in sample_surface(&surface, 20_000, 1).unwrap() {
        let probe = prober.probe(s.position, s.normal, options.scallop_mm, R);
        let dist = (s.position.y.powi(2) + (R - plunge).powi(2)).sqrt();
        if dist <= R {
            assert!((probe.depth - (R - dist)).abs() < 1e-12);
            assert_eq!(probe.scallop, Some(0.0));
        } else {
            assert_eq!(probe.depth, f64::NEG_INFINITY);
        }
    }
    let v = verify(&surface, &passes, &options).unwrap();
    assert!((v.max_gouge_mm - plunge).abs() < 1e-6, "max gouge {}", v.max_gouge_mm);
    // Gouged: lateral distance below √((R − tol)² − (R − plunge)²).
    let tol = options.gouge_tolerance_mm;
    let w = ((R - tol).powi(2) - (R - plunge).powi(2)).sqrt();
    let p = strip_area(20.0, w) / surface.area();
    let expected = p * v.samples as f64;
    let sigma = (expected * (1.0 - p)).sqrt();
    assert!(
        (v.gouges as f64 - expected).abs() < 5.0 * sigma,
        "{} gouges, expected {expected:.0} ± {sigma:.0}",
        v.gouges
    );
}

#[test]
fn an_empty_neighbourhood_is_uncovered() {
    let surface = flat_disk(20.0);
    let d = 0.6;
    let ys: Vec<f64> = (0..=40).map(|k| -(k as f64) * d).collect();
    let passes = passes_along_x(&ys, R);
    // Search height R: uncovered beyond lateral distance R from the last pass (y = 0).
    // Search height 0.5: beyond √(R² − (R − 0.5)²).
    for (search, edge) in [(None, R), (Some(0.5), (R * R - 2.5f64 * 2.5).sqrt())] {
        let options = VerifyOptions { max_scallop_search_mm: search, ..VerifyOptions::default() };
        let v = verify(&surface, &passes, &options).unwrap();
        for (p, (&u, &t)) in surface.positions.iter().zip(v.vertex_uncovered.iter().zip(&v.vertex_scallop_mm)) {
            if (p.y - edge).abs() > 1e-9 {
                assert_eq!(u, p.y > edge, "vertex {p}, search {search:?}");
            }
            if u {
                assert_eq!(t, search.unwrap_or(R));
            }
        }
        let p = (surface.area() - 0.5 * surface.area() - 0.5 * strip_area(20.0, edge)) / surface.area();
        let expected = p * v.samples as f64;
        let sigma = (expected * (1.0 - p)).sqrt();
        assert!(
            (v.uncovered_samples as f64 - expected).abs() < 5.0 * sigma,
            "{} uncovered, expected {expected:.0} ± {sigma:.0}",
            v.uncovered_samples
        );
        assert_eq!(v.uncovered_fraction, v.uncovered_samples as f64 / v.samples as f64);
        assert!(v.max_scallop_mm <= search.unwrap_or(R));
    }
}

#[test]
fn overlapping_passes_count_twice() {
    let surface = flat_disk(20.0);
    let options = VerifyOptions::default();
    let h = options.scallop_mm;
    let line: Vec<DVec3> = (0..=100).map(|i| DVec3::new(-25.0 + 0.5 * i as f64, 0.0, R)).collect();
    let q = DVec3::new(1.234, 0.05, h);

    // One pass of many segments passes over q once.
    let one = vec![line.clone()];
    let volume = SweptVolume::new(&one, R).unwrap();
    assert_eq!(volume.prober().probe(q - h * DVec3::Z, DVec3::Z, h, R).passes_over, 1);
    assert_eq!(verify(&surface, &one, &options).unwrap().max_ct, 1);

    // The same line cut twice (two passes, the second reversed), and one pass that turns back
    // over itself 0.05 mm aside: twice each.
    let reversed: Vec<DVec3> = line.iter().rev().copied().collect();
    let twice = vec![line.clone(), reversed];
    let mut u_turn = line.clone();
    u_turn.extend(line.iter().rev().map(|p| *p + DVec3::new(0.0, 0.05, 0.0)));
    for (passes, retractions) in [(twice, 1), (vec![u_turn], 0)] {
        let volume = SweptVolume::new(&passes, R).unwrap();
        assert_eq!(volume.prober().probe(q - h * DVec3::Z, DVec3::Z, h, R).passes_over, 2);
        let v = verify(&surface, &passes, &options).unwrap();
        assert_eq!((v.max_ct, v.retractions), (2, retractions));
        // CT = 2 on the strip where both cover S^h, so CT² integrates to about 4 × its area.
        let w = (R * R - (R - h) * (R - h)).sqrt();
        let strip = strip_area(20.0, w);
        assert!(v.ct2 > 3.0 * strip && v.ct2 < 5.0 * strip, "CT² {} vs strip {strip}", v.ct2);
    }
}

/// A random walk of ball centres over a surface, some of it plunged, some high, some off the part.
fn random_passes(seed: u64, height: impl Fn(f64, f64) -> f64) -> Vec<Vec<DVec3>> {
    let mut s = seed;
    let mut unit = move || {
        // SplitMix64, as everywhere.
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut passes = Vec::new();
    for _ in 0..6 {
        let (mut x, mut y) = (80.0 * unit() - 40.0, 80.0 * unit() - 40.0);
        let mut pass = Vec::new();
        for _ in 0..300 {
            x += 2.0 * unit() - 1.0;
            y += 2.0 * unit() - 1.0;
            pass.push(DVec3::new(x, y, height(x, y) + R + 0.6 * unit() - 0.3));
        }
        passes.push(pass);
    }
    // Long strokes across the part and a lone centre.
    passes.push(vec![DVec3::new(-45.0, -45.0, R), DVec3::new(45.0, 40.0, R + 2.0)]);
    passes.push(vec![DVec3::new(-45.0, 30.0, R + 1.0), DVec3::new(45.0, 30.0, R + 1.0), DVec3::new(45.0, -30.0, R)]);
    passes.push(vec![DVec3::new(5.0, 5.0, R)]);
    passes
}

#[test]
fn the_hierarchy_agrees_bit_for_bit_with_an_all_segments_brute_force() {
    let surface = surface_of(&fixtures::saddle_2_holes());
    let passes = random_passes(42, |x, y| (x * x - y * y) / 250.0);
    let volume = SweptVolume::new(&passes, R).unwrap();
    let mut prober = volume.prober();
    let caps = volume.capsules();
    let (mut hits, mut gouged, mut misses, mut covered) = (0, 0, 0, 0);
    for (h, search) in [(0.02, R), (0.3, 1.0), (0.02, 0.01)] {
        for s in sample_surface(&surface, 4000, 9).unwrap() {
            let (p, n) = (s.position, s.normal);
            let probe = prober.probe(p, n, h, search);
            let brute_t = caps.iter().filter_map(|c| c.entry(p, n, R)).fold(f64::INFINITY, f64::min);
            let brute_near = caps.iter().map(|c| c.distance(p)).fold(f64::INFINITY, f64::min);
            let q = p + h * n;
            let ids: Vec<u32> = (0..caps.len() as u32).filter(|&i| caps[i as usize].distance(q) <= R).collect();
            assert_eq!(probe.scallop, (brute_t <= search).then_some(brute_t), "sample at {p}");
            let depth = if brute_near <= R { R - brute_near } else { f64::NEG_INFINITY };
            assert_eq!(probe.depth, depth, "sample at {p}");
            assert_eq!(probe.passes_over, count_runs(&ids, volume.pass_of()), "sample at {p}");
            match probe.scallop {
                Some(0.0) => gouged += 1,
                Some(_) => hits += 1,
                None => misses += 1,
            }
            covered += (probe.passes_over > 0) as usize;
        }
    }
    println!("brute force: {hits} scallops, {gouged} inside, {misses} uncovered, {covered} under the path");
    assert!(hits > 500 && gouged > 100 && misses > 500 && covered > 500);
}

#[test]
fn path_metrics_of_a_regular_polygon() {
    for n in [3usize, 12, 100] {
        let r = 10.0;
        let pts: Vec<DVec3> = (0..=n)
            .map(|i| {
                let a = std::f64::consts::TAU * (i % n) as f64 / n as f64;
                DVec3::new(r * a.cos(), r * a.sin(), 1.0)
            })
            .collect();
        let side = 2.0 * r * (std::f64::consts::PI / n as f64).sin();
        let phi = std::f64::consts::TAU / n as f64;
        let m = path_metrics(&pts, 1000.0);
        assert_eq!(m.points, n + 1);
        assert!((m.length_mm - n as f64 * side).abs() < 1e-12 * m.length_mm, "{}", m.length_mm);
        assert!((m.max_turn_deg - 360.0 / n as f64).abs() < 1e-9, "{}", m.max_turn_deg);
        assert!((m.mean_turn_deg - 360.0 / n as f64).abs() < 1e-9);
        let rho2 = (n - 1) as f64 * phi * phi / side;
        assert!((m.rho2 - rho2).abs() < 1e-12 * rho2, "{} vs {rho2}", m.rho2);
        assert_eq!(m.time_min, Some(m.length_mm / 1000.0));
        // A repeated point changes nothing but the count.
        let mut doubled = pts.clone();
        doubled.insert(1, pts[1]);
        let d = path_metrics(&doubled, 1000.0);
        assert_eq!((d.length_mm, d.max_turn_deg, d.rho2, d.points), (m.length_mm, m.max_turn_deg, m.rho2, n + 2));
    }
    assert_eq!(path_metrics(&[DVec3::ZERO, DVec3::X], 0.0).time_min, None);
    let straight = path_metrics(&[DVec3::ZERO, DVec3::X, 2.0 * DVec3::X], f64::NAN);
    assert_eq!((straight.max_turn_deg, straight.rho2, straight.time_min), (0.0, 0.0, None));
}

fn freeform_case() -> (Surface, Vec<Vec<DVec3>>) {
    let surface = surface_of(&fixtures::freeform_4_holes());
    (surface, random_passes(3, |_, _| 0.0))
}

#[test]
fn reruns_are_identical() {
    let (surface, passes) = freeform_case();
    let options = VerifyOptions { samples: 30_000, ..VerifyOptions::default() };
    let a: Verification = verify(&surface, &passes, &options).unwrap();
    let b = verify(&surface, &passes, &options).unwrap();
    assert_eq!(a, b);
    assert_eq!(serde_json::to_string(&a).unwrap(), serde_json::to_string(&b).unwrap());
    let bits = |v: &Verification| v.vertex_scallop_mm.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b));
    // Another seed draws other samples.
    let c = verify(&surface, &passes, &VerifyOptions { seed: 1, ..options.clone() }).unwrap();
    assert_ne!(a.mean_scallop_mm, c.mean_scallop_mm);
}

#[test]
fn without_the_vertex_probes_the_figures_are_the_same() {
    let (surface, passes) = freeform_case();
    let options = VerifyOptions { samples: 30_000, ..VerifyOptions::default() };
    let all = verify(&surface, &passes, &options).unwrap();
    let some = verify(&surface, &passes, &VerifyOptions { vertex_scallop: false, ..options }).unwrap();
    assert_eq!(all.vertex_scallop_mm.len(), surface.positions.len());
    assert!(some.vertex_scallop_mm.is_empty() && some.vertex_uncovered.is_empty());
    assert_eq!(Verification { vertex_scallop_mm: Vec::new(), vertex_uncovered: Vec::new(), ..all.clone() }, some);
}

/// A V-groove along the y axis, its two flanks rising at `half_deg` from z = 0 towards the tool,
/// triangulated on a 2 mm grid over [−10, 10]²: the vertex normals on the groove's floor are the
/// bisector, tilted `half_deg` from both flanks' facets.
fn v_groove(half_deg: f64) -> Surface {
    let slope = half_deg.to_radians().tan();
    let n = 10;
    let positions = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (x, y) = (-10.0 + 2.0 * i as f64, -10.0 + 2.0 * j as f64);
            DVec3::new(x, y, slope * x.abs())
        })
        .collect();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    surface_of(&TriMesh { positions, triangles })
}

/// Straight passes of ball centres along `v_groove` (in y), 1 mm apart, at the height R + 2 mm.
fn groove_passes() -> Vec<Vec<DVec3>> {
    (-12..=12).map(|k| vec![DVec3::new(k as f64, -12.0, R + 2.0), DVec3::new(k as f64, 12.0, R + 2.0)]).collect()
}

/// Brute force over every ball touching `v_groove(half_deg)` near its floor: the least material
/// they leave over the sample at `p` along `n` (both in the xz plane: the groove runs along y).
/// They are the ball resting on both flanks, centred R/cos α over the floor, and the balls
/// touching one flank beyond where that one does (R·sin α from the floor), at 1 µm steps.
fn groove_reach_residual(half_deg: f64, p: DVec3, n: DVec3) -> f64 {
    let a = half_deg.to_radians();
    // Entry of the ray p + t·n into the ball of radius R at `c` (in the plane y = p.y).
    let entry = |c: DVec3| {
        let m = p - DVec3::new(c.x, p.y, c.z);
        let (b, cc) = (m.dot(n), m.length_squared() - R * R);
        if cc <= 0.0 {
            return 0.0;
        }
        let disc = b * b - cc;
        if b >= 0.0 || disc < 0.0 {
            f64::INFINITY
        } else {
            -b - disc.sqrt()
        }
    };
    let mut best = entry(DVec3::new(0.0, 0.0, R / a.cos()));
    for k in 0..=2 * 3000 {
        let x = R * a.sin() + 1e-3 * k as f64;
        for side in [1.0, -1.0] {
            let contact = DVec3::new(side * x, 0.0, x * a.tan());
            best = best.min(entry(contact + R * DVec3::new(-side * a.sin(), 0.0, a.cos())));
        }
    }
    best
}

#[test]
fn facet_valleys_are_where_no_ball_touching_the_facets_reaches() {
    // In a V-groove whose flanks rise α from its floor, the ball resting on both flanks touches
    // them R·sin α (horizontally) from the floor, and nothing touches nearer. Over the floor
    // it leaves R(1/cos α − 1): 22.6 µm at α = 7°, 7.3 µm at α = 4°. With a 15 µm threshold a
    // strip along the 7° floor is a valley and nothing of the 4° one; a ball along the floor's
    // vertex normal (the bisector) would ride up 22.6 µm on every face touching the floor, but
    // balls touching elsewhere reach most of them.
    let passes = groove_passes();
    let lift = 0.015;
    let options = VerifyOptions { samples: 20_000, valley_lift_mm: Some(lift), ..VerifyOptions::default() };
    let steep = v_groove(7.0);
    let v = verify(&steep, &passes, &options).unwrap();
    // The brute force over the same samples: the verifier's grid of balls leaves at most
    // s²/6R more than all of them (s = its spacing), so it finds every sample the brute force
    // puts above the threshold and none it puts below it by that much.
    let grid = (slitpath::verify::GRID_SPACING * R).powi(2) / (6.0 * R);
    let samples = sample_surface(&steep, options.samples, options.seed).unwrap();
    let residual: Vec<f64> = samples
        .iter()
        .filter(|s| s.position.x.abs() < 1.0)
        .map(|s| groove_reach_residual(7.0, s.position, s.normal))
        .collect();
    let (sure, maybe) =
        (residual.iter().filter(|&&t| t > lift).count(), residual.iter().filter(|&&t| t > lift - grid).count());
    let per_sample = steep.area() / options.samples as f64;
    let found = (v.valley_area_mm2 / per_sample).round() as usize;
    println!("7° groove: {found} valley samples; brute force {sure} (up to {maybe} within the grid's tolerance)");
    assert!(sure > 20 && found >= sure && found <= maybe, "{found} valley samples, brute force {sure}..={maybe}");
    // The strip 2·(R sin α − √(R² − (R − lift)²)·cos α) wide along the 20 mm floor, roughly (the
    // samples' normals tilt towards the floor's bisector near it).
    let strip =
        2.0 * (R * 7f64.to_radians().sin() - (R * R - (R - lift).powi(2)).sqrt() * 7f64.to_radians().cos()) * 20.0;
    assert!(
        (v.valley_area_mm2 / strip - 1.0).abs() < 0.35,
        "{} mm² of valleys, about {strip} expected",
        v.valley_area_mm2
    );
    // Outside the valleys the floor's strip is cut to what every ball leaves there at most.
    assert!(v.max_scallop_outside_valleys_mm < v.max_scallop_mm);
    let shallow = verify(&v_groove(4.0), &passes, &options).unwrap();
    assert_eq!(shallow.valley_area_mm2, 0.0);
    assert_eq!(shallow.max_scallop_outside_valleys_mm, shallow.max_scallop_mm);
    // Without the option no sample is in a valley.
    let plain = verify(&steep, &passes, &VerifyOptions { valley_lift_mm: None, ..options }).unwrap();
    assert_eq!((plain.valley_area_mm2, plain.max_scallop_outside_valleys_mm), (0.0, plain.max_scallop_mm));
}

#[test]
fn balls_that_may_dip_into_the_facets_narrow_the_valleys() {
    // With smooth facets the path's balls may dip into the facets, and so may those standing for
    // a valley's reach. Resting on both flanks of the 7° groove while dipping d into each, the
    // ball's centre is (R − d)/cos α above the floor: it leaves 17.5 µm over the floor at d = 5 µm
    // (still above the 15 µm threshold, on a narrower strip) and 12.4 µm at d = 10 µm (none).
    let passes = groove_passes();
    let options = VerifyOptions { samples: 20_000, valley_lift_mm: Some(0.015), ..VerifyOptions::default() };
    let steep = v_groove(7.0);
    let touching = verify(&steep, &passes, &options).unwrap();
    let dipping = verify(&steep, &passes, &VerifyOptions { valley_dip_mm: 0.005, ..options.clone() }).unwrap();
    let deeper = verify(&steep, &passes, &VerifyOptions { valley_dip_mm: 0.010, ..options.clone() }).unwrap();
    println!(
        "valleys: {} mm² touching, {} mm² dipping 5 µm, {} mm² dipping 10 µm",
        touching.valley_area_mm2, dipping.valley_area_mm2, deeper.valley_area_mm2
    );
    assert!(dipping.valley_area_mm2 > 0.0 && dipping.valley_area_mm2 < 0.8 * touching.valley_area_mm2);
    assert_eq!(deeper.valley_area_mm2, 0.0);
    // The path and its scallops are the same: only what is excused changes.
    assert_eq!(deeper.max_scallop_mm, touching.max_scallop_mm);
    assert_eq!(deeper.max_scallop_outside_valleys_mm, deeper.max_scallop_mm);
}

#[test]
fn the_planners_facet_tree_gives_the_same_verification() {
    // verify_with_faces searches a facet tree it is given instead of building one: the same
    // figures, and a typed error for another surface's tree.
    let passes = groove_passes();
    let options = VerifyOptions { samples: 20_000, valley_lift_mm: Some(0.015), ..VerifyOptions::default() };
    let steep = v_groove(7.0);
    let faces = FaceTree::new(&steep.positions, &steep.triangles);
    let given = verify_with_faces(&steep, &faces, &passes, &options).unwrap();
    assert!(given.valley_area_mm2 > 0.0);
    assert_eq!(given, verify(&steep, &passes, &options).unwrap());
    let other = flat_disk(5.0);
    let wrong = FaceTree::new(&other.positions, &other.triangles);
    assert!(matches!(verify_with_faces(&steep, &wrong, &passes, &options), Err(VerifyError::InvalidSurface(_))));
}

#[test]
fn bad_input_gives_typed_errors() {
    let (surface, passes) = freeform_case();
    let o = VerifyOptions::default();
    let invalid = |options: VerifyOptions| {
        let e = verify(&surface, &passes, &options).unwrap_err();
        assert!(matches!(e, VerifyError::InvalidOption(_)), "{options:?} gave {e:?}");
    };
    invalid(VerifyOptions { radius_mm: 0.0, ..o.clone() });
    invalid(VerifyOptions { radius_mm: f64::NAN, ..o.clone() });
    invalid(VerifyOptions { scallop_mm: 0.0, ..o.clone() });
    invalid(VerifyOptions { scallop_mm: R, ..o.clone() });
    invalid(VerifyOptions { samples: 0, ..o.clone() });
    invalid(VerifyOptions { cell_mm: Some(0.0), ..o.clone() });
    invalid(VerifyOptions { cell_mm: Some(f64::INFINITY), ..o.clone() });
    invalid(VerifyOptions { gouge_tolerance_mm: -1e-3, ..o.clone() });
    invalid(VerifyOptions { max_scallop_search_mm: Some(-1.0), ..o.clone() });
    invalid(VerifyOptions { valley_lift_mm: Some(-1e-3), ..o.clone() });
    invalid(VerifyOptions { valley_lift_mm: Some(R), ..o.clone() });
    invalid(VerifyOptions { valley_lift_mm: Some(f64::NAN), ..o.clone() });
    invalid(VerifyOptions { valley_dip_mm: -1e-3, ..o.clone() });
    invalid(VerifyOptions { valley_dip_mm: R, ..o.clone() });
    invalid(VerifyOptions { valley_dip_mm: f64::NAN, ..o.clone() });
    assert_eq!(verify(&surface, &[], &o), Err(VerifyError::EmptyPath));
    assert_eq!(verify(&surface, &[vec![], vec![]], &o), Err(VerifyError::EmptyPath));
    assert_eq!(verify(&surface, &[vec![DVec3::ZERO], vec![]], &o), Err(VerifyError::EmptyPass { pass: 1 }));
    let nan = vec![vec![DVec3::ZERO], vec![DVec3::X, DVec3::new(1.0, f64::NAN, 0.0)]];
    assert_eq!(verify(&surface, &nan, &o), Err(VerifyError::NonFinite { pass: 1, index: 1 }));
    let empty = Surface {
        positions: vec![],
        triangles: vec![],
        loops: vec![],
        face_normals: vec![],
        face_areas: vec![],
        vertex_normals: vec![],
        corner_normals: vec![],
        curvature: vec![],
    };
    assert_eq!(verify(&empty, &passes, &o), Err(VerifyError::EmptySurface));
    let mut broken = surface.clone();
    broken.vertex_normals.pop();
    assert!(matches!(verify(&broken, &passes, &o), Err(VerifyError::InvalidSurface(_))));
}
