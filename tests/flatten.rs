//! Integration tests of the flatten stage (BFF, free boundary): congruence of flat meshes,
//! isometry of developable ones, quality on curved ones, errors, and the shared STL meshes.

use std::collections::HashMap;
use std::time::Instant;

use glam::{DVec2, DVec3};
use slitpath::fixtures;
use slitpath::flatten::{
    check, flatten, BffSolver, BoundaryTarget, Extension, FlattenError, FlattenInput, FlattenMethod, FlattenOptions,
    Flattening,
};
use slitpath::mesh::MeshOptions;

// ---------------------------------------------------------------------------------------------
// Test support: small structured generators, boundary loops, binary STL.

struct TestMesh {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    loops: Vec<Vec<u32>>,
    /// The parameter-plane point of every vertex (an exact flattening for planar meshes).
    param: Vec<DVec2>,
}

impl TestMesh {
    fn input(&self) -> FlattenInput<'_> {
        FlattenInput { positions: &self.positions, triangles: &self.triangles, loops: &self.loops }
    }
}

/// Boundary loops with the surface on their left, longest (3D length) first. Panics on pinch
/// vertices: the generators must not make them.
fn boundary_loops(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut half: Vec<(u32, u32)> =
        triangles.iter().flat_map(|t| (0..3).map(move |c| (t[c], t[(c + 1) % 3]))).collect();
    half.sort_unstable();
    let mut next: HashMap<u32, u32> = HashMap::new();
    let mut starts = Vec::new();
    for &(a, b) in &half {
        if half.binary_search(&(b, a)).is_err() {
            assert!(next.insert(a, b).is_none(), "pinch vertex {a}");
            starts.push(a);
        }
    }
    let mut seen: HashMap<u32, bool> = HashMap::new();
    let mut loops = Vec::new();
    for &s in &starts {
        if seen.contains_key(&s) {
            continue;
        }
        let mut lp = vec![s];
        seen.insert(s, true);
        let mut v = next[&s];
        while v != s {
            lp.push(v);
            seen.insert(v, true);
            v = next[&v];
        }
        loops.push(lp);
    }
    let len = |lp: &Vec<u32>| -> f64 {
        (0..lp.len()).map(|i| (positions[lp[(i + 1) % lp.len()] as usize] - positions[lp[i] as usize]).length()).sum()
    };
    loops.sort_by(|a, b| len(b).total_cmp(&len(a)));
    loops
}

/// Keeps the listed triangles, drops unused vertices, maps the parameter plane to 3D.
fn assemble(param: &[DVec2], triangles: &[[u32; 3]], embed: &dyn Fn(DVec2) -> DVec3) -> TestMesh {
    let mut remap = vec![u32::MAX; param.len()];
    let mut p2 = Vec::new();
    let mut tris = Vec::new();
    for t in triangles {
        let mut nt = [0u32; 3];
        for c in 0..3 {
            let v = t[c] as usize;
            if remap[v] == u32::MAX {
                remap[v] = p2.len() as u32;
                p2.push(param[v]);
            }
            nt[c] = remap[v];
        }
        tris.push(nt);
    }
    let positions: Vec<DVec3> = p2.iter().map(|&q| embed(q)).collect();
    let loops = boundary_loops(&positions, &tris);
    TestMesh { positions, triangles: tris, loops, param: p2 }
}

/// Polar mesh of the annulus `r0 ≤ r ≤ r1` (a disk with a centre vertex when `r0 = 0`).
fn polar(nr: usize, ns: usize, r0: f64, r1: f64, embed: &dyn Fn(DVec2) -> DVec3) -> TestMesh {
    let mut param = Vec::new();
    let first = if r0 == 0.0 {
        param.push(DVec2::ZERO);
        1
    } else {
        0
    };
    for k in first..=nr {
        let r = r0 + (r1 - r0) * k as f64 / nr as f64;
        for s in 0..ns {
            // Rings are staggered by half a sector so the triangles are well shaped.
            let a = (s as f64 + 0.5 * k as f64) * std::f64::consts::TAU / ns as f64;
            param.push(r * DVec2::new(a.cos(), a.sin()));
        }
    }
    let id = |k: usize, s: usize| (first + (k - first) * ns + s % ns) as u32;
    let mut tris = Vec::new();
    if first == 1 {
        for s in 0..ns {
            tris.push([0, id(1, s), id(1, s + 1)]);
        }
    }
    for k in first..nr {
        for s in 0..ns {
            tris.push([id(k, s), id(k + 1, s), id(k, s + 1)]);
            tris.push([id(k, s + 1), id(k + 1, s), id(k + 1, s + 1)]);
        }
    }
    assemble(&param, &tris, embed)
}

/// `[-1, 1]²` grid (n×n cells, alternating diagonals) minus every triangle with a vertex inside
/// one of the `holes` (centre, radius) or, when `disk` is set, outside that radius.
fn grid(n: usize, holes: &[(DVec2, f64)], disk: Option<f64>, embed: &dyn Fn(DVec2) -> DVec3) -> TestMesh {
    let mut param = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            param.push(DVec2::new(-1.0 + 2.0 * i as f64 / n as f64, -1.0 + 2.0 * j as f64 / n as f64));
        }
    }
    let keep = |q: DVec2| holes.iter().all(|&(c, r)| (q - c).length() >= r) && disk.map_or(true, |r| q.length() <= r);
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            let pair = if (i + j) % 2 == 0 { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] };
            for t in pair {
                if t.iter().all(|&v| keep(param[v as usize])) {
                    tris.push(t);
                }
            }
        }
    }
    assemble(&param, &tris, embed)
}

fn tilted_plane(q: DVec2) -> DVec3 {
    // A rigid motion of the xy-plane, so flatness is not read off the coordinates.
    let (e1, e2) = (DVec3::new(0.6, 0.0, 0.8), DVec3::new(0.0, 1.0, 0.0));
    DVec3::new(3.0, -2.0, 5.0) + 7.0 * (q.x * e1 + q.y * e2)
}

/// Best rigid motion (no scale) mapping `a` onto `b` (2D Kabsch); returns the max residual.
fn rigid_residual(a: &[DVec2], b: &[DVec2]) -> f64 {
    let n = a.len() as f64;
    let ca = a.iter().copied().sum::<DVec2>() / n;
    let cb = b.iter().copied().sum::<DVec2>() / n;
    let (mut s, mut c) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (p, q) = (*p - ca, *q - cb);
        c += p.dot(q);
        s += p.perp_dot(q);
    }
    let th = s.atan2(c);
    let rot = DVec2::new(th.cos(), th.sin());
    a.iter().zip(b).map(|(p, q)| (rot.rotate(*p - ca) - (*q - cb)).length()).fold(0.0, f64::max)
}

fn diameter(p: &[DVec2]) -> f64 {
    let lo = p.iter().fold(DVec2::splat(f64::INFINITY), |m, q| m.min(*q));
    let hi = p.iter().fold(DVec2::splat(f64::NEG_INFINITY), |m, q| m.max(*q));
    (hi - lo).length()
}

/// Max relative change of edge length 3D → 2D.
fn edge_length_error(m: &TestMesh, uv: &[DVec2]) -> f64 {
    let mut e = 0.0f64;
    for t in &m.triangles {
        for c in 0..3 {
            let (a, b) = (t[c] as usize, t[(c + 1) % 3] as usize);
            let l3 = (m.positions[a] - m.positions[b]).length();
            let l2 = (uv[a] - uv[b]).length();
            e = e.max((l2 / l3 - 1.0).abs());
        }
    }
    e
}

fn loop_signed_area(uv: &[DVec2], lp: &[u32]) -> f64 {
    (0..lp.len()).map(|i| 0.5 * uv[lp[i] as usize].perp_dot(uv[lp[(i + 1) % lp.len()] as usize])).sum()
}

fn harmonic() -> FlattenOptions {
    FlattenOptions { extension: Extension::Harmonic, ..FlattenOptions::default() }
}

fn report(name: &str, m: &TestMesh, f: &Flattening) {
    let q = &f.quality;
    println!(
        "{name}: V={} F={} loops={} flipped={} qc mean={:.6} max={:.4} log-area min={:.4} max={:.4} mean={:.2e} std={:.4} boundary_valid={}",
        m.positions.len(),
        m.triangles.len(),
        m.loops.len(),
        q.flipped_triangles,
        q.qc_mean,
        q.qc_max,
        q.area_distortion.min,
        q.area_distortion.max,
        q.area_distortion.mean,
        q.area_distortion.std,
        q.boundary_valid
    );
}

/// Common assertions for a valid flattening: areas equal, loops oriented, check passes.
fn assert_valid(m: &TestMesh, f: &Flattening) {
    assert_eq!(f.uv.len(), m.positions.len());
    assert_eq!(f.quality.flipped_triangles, 0);
    assert!(f.quality.boundary_valid);
    check(&f.uv, &m.triangles, &m.loops).unwrap();
    let a3: f64 = m
        .triangles
        .iter()
        .map(|t| {
            0.5 * (m.positions[t[1] as usize] - m.positions[t[0] as usize])
                .cross(m.positions[t[2] as usize] - m.positions[t[0] as usize])
                .length()
        })
        .sum();
    let a2: f64 = m
        .triangles
        .iter()
        .map(|t| 0.5 * (f.uv[t[1] as usize] - f.uv[t[0] as usize]).perp_dot(f.uv[t[2] as usize] - f.uv[t[0] as usize]))
        .sum();
    assert!((a2 / a3 - 1.0).abs() < 1e-12, "area {a2} vs {a3}");
    assert!(loop_signed_area(&f.uv, &m.loops[0]) > 0.0);
    for h in &m.loops[1..] {
        assert!(loop_signed_area(&f.uv, h) < 0.0);
    }
}

// ---------------------------------------------------------------------------------------------
// Flat meshes stay congruent.

#[test]
fn planar_disk_is_congruent() {
    let m = polar(12, 48, 0.0, 1.0, &tilted_plane);
    let truth: Vec<DVec2> = m.param.iter().map(|q| 7.0 * *q).collect();
    for opts in [FlattenOptions::default(), harmonic()] {
        let f = flatten(m.input(), &opts).unwrap();
        assert_valid(&m, &f);
        let err = rigid_residual(&f.uv, &truth) / diameter(&truth);
        assert!(err < 1e-9, "{:?}: relative residual {err:e}", opts.extension);
        assert!((f.quality.qc_max - 1.0).abs() < 1e-9);
    }
}

#[test]
fn planar_annulus_and_plate_with_holes_are_congruent() {
    let annulus = polar(8, 40, 0.4, 1.0, &tilted_plane);
    let plate = grid(
        24,
        &[(DVec2::new(-0.4, 0.3), 0.3), (DVec2::new(0.45, 0.4), 0.2), (DVec2::new(0.1, -0.5), 0.25)],
        None,
        &tilted_plane,
    );
    assert_eq!(annulus.loops.len(), 2);
    assert_eq!(plate.loops.len(), 4);
    for m in [&annulus, &plate] {
        let truth: Vec<DVec2> = m.param.iter().map(|q| 7.0 * *q).collect();
        for opts in [FlattenOptions::default(), harmonic()] {
            let f = flatten(m.input(), &opts).unwrap();
            assert_valid(m, &f);
            let err = rigid_residual(&f.uv, &truth) / diameter(&truth);
            assert!(err < 1e-9, "{:?}: relative residual {err:e}", opts.extension);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Developable surfaces flatten isometrically.

fn cylinder(q: DVec2) -> DVec3 {
    let r = 0.9;
    DVec3::new(r * (q.x / r).sin(), q.y, r * (1.0 - (q.x / r).cos()))
}

fn cone(q: DVec2) -> DVec3 {
    // (q.x, q.y) ∈ [-1,1]² → distance from the apex 1.5..3.5, angle around the axis ±1 rad.
    let d = 2.5 + q.y;
    let psi = q.x;
    let beta: f64 = 0.6;
    d * DVec3::new(beta.sin() * psi.cos(), beta.sin() * psi.sin(), beta.cos())
}

#[test]
fn developable_patches_flatten_isometrically() {
    let holes = [(DVec2::new(-0.35, 0.2), 0.3), (DVec2::new(0.4, -0.3), 0.25)];
    for (name, embed) in [("cylinder", &cylinder as &dyn Fn(DVec2) -> DVec3), ("cone", &cone)] {
        let m = grid(30, &holes, None, embed);
        assert_eq!(m.loops.len(), 3);
        for opts in [FlattenOptions::default(), harmonic()] {
            let f = flatten(m.input(), &opts).unwrap();
            report(name, &m, &f);
            assert_valid(&m, &f);
            let q = f.quality;
            assert!(q.qc_max - 1.0 < 1e-9, "{name}: qc max {}", q.qc_max);
            assert!(q.area_distortion.min.abs() < 1e-9 && q.area_distortion.max.abs() < 1e-9);
            assert!(edge_length_error(&m, &f.uv) < 1e-9);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Curved surfaces: valid, nearly conformal.

fn sphere_cap(q: DVec2) -> DVec3 {
    // Azimuthal equidistant: parameter radius 1 ↦ polar angle 1 rad on a sphere of radius 2.
    let (rho, r) = (q.length(), 2.0);
    let th = rho * 1.0 / 1.0;
    let dir = if rho > 0.0 { q / rho } else { DVec2::X };
    r * DVec3::new(th.sin() * dir.x, th.sin() * dir.y, th.cos())
}

fn saddle(q: DVec2) -> DVec3 {
    DVec3::new(q.x, q.y, 0.6 * (q.x * q.x - q.y * q.y))
}

fn freeform(q: DVec2) -> DVec3 {
    DVec3::new(q.x, q.y, 0.3 * (2.0 * q.x).sin() * (1.5 * q.y).cos() + 0.2 * q.x * q.y)
}

#[test]
fn spherical_cap_with_hole() {
    let m = grid(40, &[(DVec2::new(0.3, 0.15), 0.25)], Some(1.0), &sphere_cap);
    assert_eq!(m.loops.len(), 2);
    for opts in [FlattenOptions::default(), harmonic()] {
        let f = flatten(m.input(), &opts).unwrap();
        report("sphere cap", &m, &f);
        assert_valid(&m, &f);
        assert!(f.quality.qc_mean < 1.015, "qc mean {}", f.quality.qc_mean);
        assert_eq!(f.boundary, BoundaryTarget::Free);
    }
}

#[test]
fn distortion_falls_under_refinement() {
    // Same smooth cap and hole (polar mesh, so the boundaries are not staircases), halved edges:
    // qc − 1 measured 0.026, 0.0129, 0.0064 (first order in the edge length).
    let cap = |nr: usize| polar(nr, 8 * nr, 0.25, 1.0, &sphere_cap);
    let qc: Vec<f64> = [6, 12, 24]
        .iter()
        .map(|&nr| {
            let m = cap(nr);
            let f = flatten(m.input(), &FlattenOptions::default()).unwrap();
            assert_valid(&m, &f);
            report(&format!("cap annulus nr={nr}"), &m, &f);
            f.quality.qc_mean - 1.0
        })
        .collect();
    assert!(qc[1] < 0.55 * qc[0] && qc[2] < 0.55 * qc[1], "qc mean − 1: {qc:?}");
}

#[test]
fn saddle_with_two_holes_and_freeform_with_four() {
    let two = [(DVec2::new(-0.4, 0.1), 0.28), (DVec2::new(0.45, -0.2), 0.22)];
    let four = [
        (DVec2::new(-0.5, -0.5), 0.2),
        (DVec2::new(0.5, -0.45), 0.25),
        (DVec2::new(0.45, 0.5), 0.2),
        (DVec2::new(-0.45, 0.45), 0.3),
    ];
    for (name, m, holes) in
        [("saddle", grid(40, &two, None, &saddle), 2), ("freeform", grid(40, &four, None, &freeform), 4)]
    {
        assert_eq!(m.loops.len(), holes + 1);
        for opts in [FlattenOptions::default(), harmonic()] {
            let f = flatten(m.input(), &opts).unwrap();
            report(name, &m, &f);
            assert_valid(&m, &f);
            assert!(f.quality.qc_mean < 1.015, "{name} qc mean {}", f.quality.qc_mean);
            assert_eq!(f.boundary, BoundaryTarget::Free);
        }
    }
}

#[test]
fn solver_is_reusable_and_takes_scale_factors() {
    let m = grid(20, &[(DVec2::new(0.2, 0.1), 0.3)], None, &saddle);
    let solver = BffSolver::new(m.input(), &FlattenOptions::default()).unwrap();
    let a = solver.flatten().unwrap();
    let b = solver.flatten().unwrap();
    assert_eq!(a, b);
    assert_eq!(a, flatten(m.input(), &FlattenOptions::default()).unwrap());
    // A constant boundary scale factor only scales the result, which is then normalised to the
    // 3D area: the same shape.
    let c = solver.flatten_with_scale_factors(&vec![0.3; solver.outer_len()]).unwrap();
    assert!(rigid_residual(&a.uv, &c.uv) / diameter(&a.uv) < 1e-9);
    assert!(matches!(solver.flatten_with_scale_factors(&[0.0]), Err(FlattenError::BoundaryDataLength { got: 1, .. })));
}

#[test]
fn disk_target_gives_a_convex_outer_loop() {
    let m = grid(30, &[(DVec2::new(-0.4, 0.1), 0.28), (DVec2::new(0.45, -0.2), 0.22)], None, &saddle);
    for extension in [Extension::Conjugate, Extension::Harmonic] {
        let opts = FlattenOptions { boundary: BoundaryTarget::Disk, extension, ..FlattenOptions::default() };
        let f = flatten(m.input(), &opts).unwrap();
        report("saddle disk", &m, &f);
        assert_eq!(f.boundary, BoundaryTarget::Disk);
        assert_valid(&m, &f);
        let lp = &m.loops[0];
        let n = lp.len();
        let mut turning = 0.0;
        // The harmonic extension keeps the closed target curve exactly: convex; the conjugate
        // only approximately.
        if extension == Extension::Conjugate {
            continue;
        }
        for i in 0..n {
            let (a, b, c) = (f.uv[lp[(i + n - 1) % n] as usize], f.uv[lp[i] as usize], f.uv[lp[(i + 1) % n] as usize]);
            let (d1, d2) = (b - a, c - b);
            assert!(d1.perp_dot(d2) > 0.0, "outer loop not convex at {i}");
            turning += d1.perp_dot(d2).atan2(d1.dot(d2));
        }
        assert!((turning - std::f64::consts::TAU).abs() < 1e-9);
    }
}

#[test]
fn tutte_fallback_is_a_valid_embedding_inside_a_convex_loop() {
    // The last resort of `BffSolver::flatten`: valid on curved parts with holes and on slivers
    // (obtuse triangles, negative cotan weights), outer loop convex, less conformal than BFF.
    let parts = [("saddle_2_holes", fixtures::saddle_2_holes()), ("sliver_mesh", fixtures::sliver_mesh())];
    for (name, mesh) in parts {
        let m = surface_mesh(&mesh);
        let solver = BffSolver::new(m.input(), &FlattenOptions::default()).unwrap();
        let f = solver.flatten_tutte().unwrap();
        report(&format!("{name} tutte"), &m, &f);
        assert_valid(&m, &f);
        assert_eq!((f.method, f.boundary), (FlattenMethod::Tutte, BoundaryTarget::Disk));
        let lp = &m.loops[0];
        let n = lp.len();
        for i in 0..n {
            let (a, b, c) = (f.uv[lp[(i + n - 1) % n] as usize], f.uv[lp[i] as usize], f.uv[lp[(i + 1) % n] as usize]);
            assert!((b - a).perp_dot(c - b) > 0.0, "{name}: outer loop not convex at {i}");
        }
        assert!(f.quality.qc_mean < 1.5, "{name}: qc mean {}", f.quality.qc_mean);
        assert_eq!(solver.flatten_tutte().unwrap(), f, "{name}: deterministic");
        // BFF itself is valid here: no fallback taken.
        assert_eq!(solver.flatten().unwrap().method, FlattenMethod::Bff);
    }
}

// ---------------------------------------------------------------------------------------------
// Bad input is a typed error.

#[test]
fn bad_input_is_a_typed_error() {
    let m = grid(6, &[(DVec2::new(0.0, 0.0), 0.35)], None, &saddle);
    let opts = FlattenOptions::default();
    let with = |loops: Vec<Vec<u32>>| flatten(FlattenInput { loops: &loops, ..m.input() }, &opts);
    assert!(matches!(with(vec![]), Err(FlattenError::NoBoundary)));
    assert!(matches!(with(vec![m.loops[0].clone()]), Err(FlattenError::LoopsIncomplete { .. })));
    let reversed: Vec<u32> = m.loops[0].iter().rev().copied().collect();
    assert!(matches!(with(vec![reversed, m.loops[1].clone()]), Err(FlattenError::InvalidLoop { loop_index: 0, .. })));

    let mut pos = m.positions.clone();
    let t = m.triangles[5];
    pos[t[2] as usize] = 0.5 * (pos[t[0] as usize] + pos[t[1] as usize]);
    let r = flatten(FlattenInput { positions: &pos, ..m.input() }, &opts);
    assert!(matches!(r, Err(FlattenError::DegenerateTriangle { .. })), "{r:?}");

    let mut tris = m.triangles.clone();
    tris[0].swap(0, 1);
    let r = flatten(FlattenInput { triangles: &tris, ..m.input() }, &opts);
    assert!(matches!(r, Err(FlattenError::BadEdge { .. }) | Err(FlattenError::InvalidLoop { .. })), "{r:?}");
}

// ---------------------------------------------------------------------------------------------
// Shared real meshes (skipped when the folder is absent).

const MESH_DIR: &str = "/work/shared/meshes";

/// Through the mesh stage (welding, orientation, loops, top-surface extraction for solids).
fn surface_mesh(mesh: &slitpath::mesh::TriMesh) -> TestMesh {
    let out = slitpath::mesh::from_triangles(mesh, &MeshOptions::default()).unwrap();
    let s = out.surface;
    let param = s.positions.iter().map(|p| p.truncate()).collect();
    TestMesh { positions: s.positions, triangles: s.triangles, loops: s.loops, param }
}

fn timed(name: &str, m: &TestMesh, opts: &FlattenOptions) -> Flattening {
    let t0 = Instant::now();
    let solver = BffSolver::new(m.input(), opts).unwrap();
    let t1 = Instant::now();
    let f = solver.flatten().unwrap();
    let t2 = Instant::now();
    report(&format!("{name} {:?} {:?} t={}", opts.extension, f.boundary, f.disk_blend), m, &f);
    if let Err(e) = check(&f.uv, &m.triangles, &m.loops) {
        println!("  check: {e}");
    }
    println!("  factorise {:.1} ms, flatten {:.1} ms", (t1 - t0).as_secs_f64() * 1e3, (t2 - t1).as_secs_f64() * 1e3);
    f
}

#[test]
fn planar_fixtures_are_congruent() {
    for name in ["unit_disk", "concentric_annulus", "eccentric_annulus", "plate_3_holes"] {
        let m = surface_mesh(&fixtures::by_name(name).unwrap());
        for opts in [FlattenOptions::default(), harmonic()] {
            let f = flatten(m.input(), &opts).unwrap();
            assert_valid(&m, &f);
            let err = rigid_residual(&f.uv, &m.param) / diameter(&m.param);
            assert!(err < 1e-9, "{name} {:?}: relative residual {err:e}", opts.extension);
        }
    }
}

#[test]
fn curved_fixtures() {
    // (name, bound on qc mean, bound on qc max), measured with BFF at the fixtures' resolution.
    let cases =
        [("saddle_2_holes", 1.001, 1.005), ("spherical_cap_hole", 1.005, 1.01), ("freeform_4_holes", 1.005, 1.05)];
    for (name, qc_mean, qc_max) in cases {
        let m = surface_mesh(&fixtures::by_name(name).unwrap());
        for opts in [FlattenOptions::default(), harmonic()] {
            let f = timed(name, &m, &opts);
            assert_valid(&m, &f);
            assert_eq!(f.boundary, BoundaryTarget::Free);
            assert!(f.quality.qc_mean < qc_mean, "{name}: qc mean {}", f.quality.qc_mean);
            assert!(f.quality.qc_max < qc_max, "{name}: qc max {}", f.quality.qc_max);
        }
    }
    // Slivers: valid, whatever the distortion of the needles.
    let m = surface_mesh(&fixtures::sliver_mesh());
    let f = timed("sliver_mesh", &m, &FlattenOptions::default());
    assert_valid(&m, &f);
}

#[test]
fn shared_meshes() {
    let dir = std::path::Path::new(MESH_DIR);
    if !dir.is_dir() {
        eprintln!("{MESH_DIR} absent: skipped");
        return;
    }
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".stl"))
        .collect();
    names.sort();
    for name in names {
        let bytes = std::fs::read(dir.join(&name)).unwrap();
        let m = match slitpath::mesh::load(&bytes, &MeshOptions::default()) {
            Ok(out) => {
                let s = out.surface;
                let param = vec![DVec2::ZERO; s.positions.len()];
                TestMesh { positions: s.positions, triangles: s.triangles, loops: s.loops, param }
            }
            Err(e) => {
                println!("{name}: mesh stage: {e}");
                continue;
            }
        };
        for opts in [
            FlattenOptions { check: false, ..FlattenOptions::default() },
            FlattenOptions { check: false, ..harmonic() },
        ] {
            match BffSolver::new(m.input(), &opts) {
                Ok(_) => {
                    let f = timed(&name, &m, &opts);
                    assert_eq!(f.uv.len(), m.positions.len());
                    // Measured: every shared mesh flattens validly (the beetle after a partial
                    // disk fallback).
                    assert_eq!(f.quality.flipped_triangles, 0, "{name}");
                    assert!(f.quality.boundary_valid, "{name}");
                    check(&f.uv, &m.triangles, &m.loops).unwrap();
                }
                Err(e) => println!("{name}: {e}"),
            }
        }
    }
}
