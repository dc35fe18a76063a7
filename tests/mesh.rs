//! Integration tests of the mesh stage: bad input is a named error, real meshes give the figures
//! their sources state, closed solids yield their machinable top surface.
#![cfg(not(target_arch = "wasm32"))]

use glam::DVec3;
use slitpath::fixtures;
use slitpath::mesh::{self, stl, MeshError, MeshOptions, TriMesh};
use std::path::PathBuf;

fn load(bytes: &[u8]) -> Result<mesh::MeshOutput, MeshError> {
    mesh::load(bytes, &MeshOptions::default())
}

fn shared(name: &str) -> Option<Vec<u8>> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes").join(name);
    match std::fs::read(&path) {
        Ok(bytes) => Some(bytes),
        Err(_) => {
            eprintln!("skipped: {} is absent", path.display());
            None
        }
    }
}

fn cube() -> TriMesh {
    let p = (0..8).map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
    // Outward-wound faces of the unit cube (corners indexed by bits x, y, z).
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let triangles = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    TriMesh { positions: p, triangles }
}

/// A torus (major radius 3, minor 1) with `n×m` quads; `drop` faces removed make it an open
/// surface of genus 1.
fn torus(n: u32, m: u32, drop: usize) -> TriMesh {
    fixtures::handles::torus(3.0, 1.0, n, m, drop)
}

#[test]
fn empty_input_is_named() {
    assert_eq!(load(b"").unwrap_err(), MeshError::Empty);
}

#[test]
fn truncated_binary_is_named() {
    let mut bytes = stl::write_binary(&cube(), "cube");
    bytes.truncate(bytes.len() - 30);
    let err = load(&bytes).unwrap_err();
    assert!(matches!(err, MeshError::Truncated { triangles: 12, expected_bytes: 684, actual_bytes: 654 }), "{err}");
    assert!(err.to_string().contains("truncated"));
}

#[test]
fn garbled_ascii_names_the_line() {
    let text =
        std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/garbled_ascii.stl")).unwrap();
    let err = load(&text).unwrap_err();
    assert!(matches!(err, MeshError::AsciiSyntax { line: 9, .. }), "{err}");
    assert!(err.to_string().contains("line 9"), "{err}");
}

#[test]
fn ascii_cube_fixture_is_a_closed_solid() {
    let text = std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/cube_ascii.stl")).unwrap();
    let out = load(&text).unwrap();
    assert!(out.report.closed);
    assert_eq!((out.report.vertices, out.report.faces, out.report.genus), (8, 12, 0));
    let top = out.report.machined.as_ref().unwrap();
    assert_eq!((top.faces, top.boundary_loops), (2, 1));
}

#[test]
fn non_finite_coordinates_are_named() {
    let mut m = cube();
    m.positions[3].y = f64::NAN;
    let bytes = stl::write_binary(&m, "nan");
    // Triangles 0 and 1 use corner 3 of the cube; the first one is reported.
    assert_eq!(load(&bytes).unwrap_err(), MeshError::NonFinite { triangle: 0 });
    m.positions[3].y = f64::INFINITY;
    assert_eq!(load(&stl::write_binary(&m, "inf")).unwrap_err(), MeshError::NonFinite { triangle: 0 });
}

#[test]
fn all_degenerate_is_named() {
    let m = TriMesh {
        positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0), DVec3::new(3.0, 0.0, 0.0)],
        triangles: vec![[0, 1, 2], [1, 2, 3]],
    };
    assert_eq!(load(&stl::write_binary(&m, "flat")).unwrap_err(), MeshError::AllDegenerate { dropped: 2 });
}

#[test]
fn non_manifold_edge_names_the_edge() {
    // Three triangles hang off the edge (0,0,0)–(1,0,0).
    let m = TriMesh {
        positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(0.0, -1.0, 0.0)],
        triangles: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    };
    let err = load(&stl::write_binary(&m, "fin")).unwrap_err();
    match &err {
        MeshError::NonManifoldEdge { pa, pb, faces: 3, .. } => {
            assert_eq!((*pa, *pb), ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
        }
        other => panic!("expected a non-manifold edge, got {other}"),
    }
    assert!(err.to_string().contains("shared by 3 faces"));
}

#[test]
fn mobius_strip_is_not_orientable() {
    let n = 24;
    let mut positions = Vec::new();
    for i in 0..n {
        let u = i as f64 / n as f64 * std::f64::consts::TAU;
        for s in [-0.3, 0.3] {
            let (c, sn) = ((u / 2.0).cos(), (u / 2.0).sin());
            positions.push(DVec3::new((1.0 + s * c) * u.cos(), (1.0 + s * c) * u.sin(), s * sn));
        }
    }
    let mut triangles = Vec::new();
    for i in 0..n {
        let (a, b) = (2 * i, 2 * i + 1);
        // The last strip joins with a half twist.
        let (c, d) = if i + 1 == n { (1, 0) } else { (2 * i + 2, 2 * i + 3) };
        triangles.push([a, c, d]);
        triangles.push([a, d, b]);
    }
    let err = load(&stl::write_binary(&TriMesh { positions, triangles }, "mobius")).unwrap_err();
    assert!(matches!(err, MeshError::NonOrientable { .. }), "{err}");
}

#[test]
fn closed_solid_with_nothing_facing_the_tool() {
    let options = MeshOptions { tool_axis: DVec3::ONE, wall_angle_deg: 10.0, ..Default::default() };
    let err = mesh::load(&stl::write_binary(&cube(), "cube"), &options).unwrap_err();
    assert!(matches!(err, MeshError::NothingFacesTool { .. }), "{err}");
}

#[test]
fn triangle_cap_is_enforced_before_reading() {
    let options = MeshOptions { max_triangles: 11, ..Default::default() };
    let err = mesh::load(&stl::write_binary(&cube(), "cube"), &options).unwrap_err();
    assert_eq!(err, MeshError::TooManyTriangles { count: 12, cap: 11 });
}

#[test]
fn bad_options_are_named() {
    let bytes = stl::write_binary(&cube(), "cube");
    for options in [
        MeshOptions { wall_angle_deg: 95.0, ..Default::default() },
        MeshOptions { tool_axis: DVec3::ZERO, ..Default::default() },
        MeshOptions { weld_tolerance_rel: f64::NAN, ..Default::default() },
    ] {
        assert!(matches!(mesh::load(&bytes, &options), Err(MeshError::InvalidOption(_))));
    }
}

#[test]
fn punctured_torus_has_genus_one_and_is_cut() {
    let out = load(&stl::write_binary(&torus(24, 12, 2), "torus")).unwrap();
    assert_eq!((out.report.genus, out.report.boundary_loops, out.report.closed), (1, 1, false));
    // The handle is cut (tests/handles.rs): the surface to plan is a disk with a hole.
    assert_eq!(out.report.handle_cuts.len(), 1);
    assert_eq!(out.surface.genus(), 0);
    out.surface.check_plannable().unwrap();
}

#[test]
fn inconsistent_winding_is_repaired_and_loops_face_the_tool() {
    // A 2×2 grid of quads in z = 0 with every other triangle flipped, normals mostly down.
    let positions = (0..9).map(|i| DVec3::new((i % 3) as f64, (i / 3) as f64, 0.0)).collect();
    let mut triangles = Vec::new();
    for (k, (i, j)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
        let v = |di: u32, dj: u32| (j + dj) * 3 + i + di;
        triangles.push([v(0, 0), v(1, 1), v(1, 0)]); // clockwise seen from +Z
        let t = [v(0, 0), v(0, 1), v(1, 1)];
        triangles.push(if k % 2 == 0 { t } else { [t[0], t[2], t[1]] });
    }
    let out = load(&stl::write_binary(&TriMesh { positions, triangles }, "grid")).unwrap();
    assert_eq!(out.report.faces_reoriented, 6);
    let s = &out.surface;
    assert!(s.face_normals.iter().all(|n| (n.z - 1.0).abs() < 1e-12));
    assert_eq!(s.loops.len(), 1);
    // The outer loop runs counter-clockwise seen from the tool: positive signed area.
    let l = &s.loops[0];
    let area: f64 = (0..l.len())
        .map(|i| {
            let (a, b) = (s.positions[l[i] as usize], s.positions[l[(i + 1) % l.len()] as usize]);
            a.x * b.y - b.x * a.y
        })
        .sum();
    assert!((area / 2.0 - 4.0).abs() < 1e-12, "{area}");
}

#[test]
fn two_holes_touching_at_a_vertex_are_split() {
    // A 4×4 grid of quads without cells (1,1) and (2,2): the two holes share only the corner
    // vertex (2,2), a pinch. Split, the two holes form one simple loop of 8 edges.
    let (w, h) = (5u32, 5u32);
    let positions = (0..w * h).map(|i| DVec3::new((i % w) as f64, (i / w) as f64, 0.0)).collect();
    let mut triangles = Vec::new();
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            if (i, j) == (1, 1) || (i, j) == (2, 2) {
                continue;
            }
            let v = |di: u32, dj: u32| (j + dj) * w + i + di;
            triangles.push([v(0, 0), v(1, 0), v(1, 1)]);
            triangles.push([v(0, 0), v(1, 1), v(0, 1)]);
        }
    }
    let out = load(&stl::write_binary(&TriMesh { positions, triangles }, "pinch")).unwrap();
    assert_eq!(out.report.pinch_vertices_split, 1);
    assert_eq!(out.report.boundary_loops, 2);
    assert_eq!(out.report.loop_vertex_counts, vec![16, 8]);
    assert_eq!(out.report.genus, 0);
    assert!(out.surface.check_plannable().is_ok());
}

#[test]
fn binary_file_whose_header_starts_with_solid_is_binary() {
    let mut bytes = stl::write_binary(&torus(8, 6, 1), "x");
    bytes[..20].copy_from_slice(b"solid exported by X ");
    assert_eq!(load(&bytes).unwrap().report.faces, 8 * 6 * 2 - 1);
}

#[test]
fn loading_is_deterministic() {
    let bytes = stl::write_binary(&torus(16, 8, 3), "t");
    let (a, b) = (load(&bytes).unwrap(), load(&bytes).unwrap());
    assert_eq!(a.report, b.report);
    assert_eq!(a.surface.positions, b.surface.positions);
    assert_eq!(a.surface.triangles, b.surface.triangles);
    assert_eq!(a.surface.loops, b.surface.loops);
}

/// (file, vertices, faces, loops, genus) as SOURCES.md states them.
const SHARED: &[(&str, usize, usize, usize, i64)] = &[
    ("beetle.stl", 30024, 58738, 11, 0),
    ("face_holes.stl", 4291, 8288, 7, 0),
    ("inverted_triangles.stl", 12577, 24685, 6, 0),
    ("mech-holes-shark.stl", 5246, 10192, 4, 0),
    ("halftunnel.stl", 831, 1568, 3, 0),
    ("intersection_quads.stl", 1726, 3328, 4, 0),
    ("wavy_mesh_with_hole.stl", 757, 1347, 2, 0),
    ("face.stl", 17157, 34144, 1, 0),
    ("camelhead.stl", 11381, 22704, 1, 0),
    ("inspired_mesh.stl", 2244, 4288, 1, 0),
    ("carpet2.stl", 3952, 7650, 1, 0),
    ("featuretype.stl", 1722, 3476, 0, 9),
    ("plate_holes.stl", 618, 1252, 0, 5),
    ("wheel_in_box.stl", 3043, 6102, 0, 5),
    ("ktoolcav.stl", 2041, 4090, 0, 3),
];

#[test]
fn shared_meshes_match_their_sources() {
    for &(name, v, f, loops, genus) in SHARED {
        let Some(bytes) = shared(name) else { continue };
        let out = load(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = &out.report;
        assert_eq!((r.vertices, r.faces, r.boundary_loops, r.genus, r.components), (v, f, loops, genus, 1), "{name}");
        assert_eq!(r.closed, loops == 0, "{name}");
        assert_eq!(r.degenerate_faces_dropped + r.duplicate_faces_dropped + r.pinch_vertices_split, 0, "{name}");
        // The planned surface is a disk with holes in every case (closed ones via their top).
        out.surface.check_plannable().unwrap_or_else(|e| panic!("{name}: {e}"));
        let s = &out.surface;
        assert_eq!(s.vertex_normals.len(), s.positions.len());
        assert!(s.face_normals.iter().chain(&s.vertex_normals).all(|n| (n.length() - 1.0).abs() < 1e-9), "{name}");
    }
}

#[test]
fn beetle_face_holes_and_plate_holes_as_the_issue_states() {
    if let Some(bytes) = shared("beetle.stl") {
        let r = load(&bytes).unwrap().report;
        assert_eq!((r.boundary_loops, r.genus), (11, 0));
        assert_eq!(r.loop_vertex_counts[0], 616, "the outer loop is the longest");
    }
    if let Some(bytes) = shared("face_holes.stl") {
        assert_eq!(load(&bytes).unwrap().report.boundary_loops, 7);
    }
    if let Some(bytes) = shared("plate_holes.stl") {
        let out = load(&bytes).unwrap();
        let top = out.report.machined.as_ref().expect("a closed solid reports its machined top");
        assert_eq!((top.boundary_loops, top.genus, top.components), (6, 0, 1));
        assert_eq!(out.surface.loops.len(), 6);
        // The outer loop is the rim of the top plane, z = 12.7 (0.5 in); chamfered holes dip lower.
        let s = &out.surface;
        assert!(s.loops[0].iter().all(|&v| (s.positions[v as usize].z - 12.7).abs() < 1e-5));
    }
}

#[test]
fn ktoolcav_cavity_is_machined_along_minus_y() {
    let Some(bytes) = shared("ktoolcav.stl") else { return };
    let options = MeshOptions { tool_axis: DVec3::NEG_Y, ..Default::default() };
    let out = mesh::load(&bytes, &options).unwrap();
    assert!(out.surface.face_normals.iter().all(|n| n.dot(DVec3::NEG_Y) >= 80f64.to_radians().cos() - 1e-12));
}

/// Principal curvatures of every face within 2% of the analytic ones.
fn check_principal(mesh: TriMesh, expected: (f64, f64), what: &str) {
    let surface = mesh::geometry::build_surface(mesh::topology::Component { mesh, loops: Vec::new() }).unwrap();
    let mut worst: f64 = 0.0;
    for c in &surface.curvature {
        let (k1, k2, _) = c.principal();
        let scale = expected.0.abs().max(expected.1.abs());
        worst = worst.max(((k1 - expected.0).abs()).max((k2 - expected.1).abs()) / scale);
    }
    eprintln!("{what}: worst relative principal-curvature error {worst:.2e}");
    assert!(worst < 0.02, "{what}: {worst}");
}

#[test]
fn curvature_of_a_fine_sphere_is_one_over_r() {
    let r = 25.0;
    check_principal(fixtures::sphere(r, 5), (1.0 / r, 1.0 / r), "sphere");
}

#[test]
fn curvature_of_a_cylinder_is_one_over_r_and_zero() {
    let r = 10.0;
    let m = fixtures::cylinder(r, 30.0, 128, 24);
    let surface =
        mesh::geometry::build_surface(mesh::topology::Component { mesh: m.clone(), loops: Vec::new() }).unwrap();
    // Along the axis the normal curvature vanishes; around it, 1/r.
    for c in &surface.curvature {
        assert!(c.normal_curvature(DVec3::Z).abs() < 0.02 / r);
    }
    check_principal(m, (1.0 / r, 0.0), "cylinder");
}

#[test]
fn every_fixture_loads_with_its_topology() {
    for name in fixtures::NAMES {
        let m = fixtures::by_name(name).unwrap();
        let out =
            mesh::load(&stl::write_binary(&m, name), &MeshOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = &out.report;
        assert_eq!(r.faces, m.triangles.len(), "{name}");
        assert_eq!(r.degenerate_faces_dropped + r.duplicate_faces_dropped + r.pinch_vertices_split, 0, "{name}");
        out.surface.check_plannable().unwrap_or_else(|e| panic!("{name}: {e}"));
        // Every planned surface faces the tool on average.
        let up: f64 = out.surface.face_normals.iter().zip(&out.surface.face_areas).map(|(n, a)| n.z * a).sum();
        assert!(up > 0.0, "{name}");
    }
}
