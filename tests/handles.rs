//! Integration tests of the handle cutting (`mesh::handles`, issue 34 item 4): a surface of genus
//! g > 0 is cut along g short non-separating loops into a disk with 2g more holes, the cut
//! lengths match the analytic shortest loops, and the fixtures with handles plan end to end.
#![cfg(not(target_arch = "wasm32"))]

use glam::DVec3;
use slitpath::fixtures::{
    self,
    handles::{torus, HANDLE_EDGE_MM, PLATE_BRIDGE},
};
use slitpath::mesh::{self, geometry, handles, topology, MeshError, MeshOptions};
use slitpath::plan::{PlanOptions, Planner};
use std::f64::consts::PI;

/// Length of a regular `k`-gon inscribed in a circle of radius `r`.
fn polygon(r: f64, k: u32) -> f64 {
    2.0 * k as f64 * r * (PI / k as f64).sin()
}

#[test]
fn a_punctured_torus_is_cut_along_a_meridian_through_its_hole() {
    let out = mesh::from_triangles(&torus(30.0, 8.0, 48, 16, 2), &MeshOptions::default()).unwrap();
    assert_eq!((out.report.genus, out.report.boundary_loops), (1, 1));
    let cuts = &out.report.handle_cuts;
    assert_eq!(cuts.len(), 1);
    // The shortest loop round the handle is a meridian, a 16-gon of radius 8 (the inner equator
    // is 2π·22); the meridian through the puncture runs one edge along its rim, which is not cut:
    // 15 of its 16 edges are, exactly (the search is exhaustive on this mesh).
    assert!((cuts[0].length_mm - polygon(8.0, 16) * 15.0 / 16.0).abs() < 1e-9, "{}", cuts[0].length_mm);
    assert!((cuts[0].loop_length_mm - polygon(8.0, 16)).abs() < 1e-9);
    assert_eq!((cuts[0].cut_edges, cuts[0].rim_edges), (15, 1));
    // An arc from the rim back to it: χ + 1, one more loop, genus 0; its 14 inner vertices and
    // both ends are doubled.
    let s = &out.surface;
    assert_eq!((s.genus(), s.loops.len(), s.euler_characteristic()), (0, 2, 0));
    assert_eq!(s.positions.len(), 48 * 16 + 16);
    assert_eq!(s.vertex_normals.len(), s.positions.len());
    s.check_plannable().unwrap();
}

#[test]
fn sampled_roots_find_the_same_cut_on_a_larger_torus() {
    let options = MeshOptions {
        handles: handles::HandleOptions { exhaustive_below_vertices: 0, sampled_roots: 8, ..Default::default() },
        ..MeshOptions::default()
    };
    let out = mesh::from_triangles(&torus(30.0, 8.0, 96, 24, 2), &options).unwrap();
    let cut = &out.report.handle_cuts[0];
    assert!((cut.loop_length_mm - polygon(8.0, 24)).abs() < 1e-9, "{}", cut.loop_length_mm);
    assert_eq!((cut.cut_edges, cut.rim_edges), (23, 1));
    assert_eq!(out.surface.genus(), 0);
}

#[test]
fn a_closed_surface_is_left_alone_and_keeps_its_error() {
    let topo = topology::analyse(&torus(30.0, 8.0, 24, 8, 0), DVec3::Z).unwrap();
    let surface = geometry::build_surface(topology::largest_component(&topo).1).unwrap();
    let (cut, cuts) = handles::cut_handles(surface, &handles::HandleOptions::default()).unwrap();
    assert!(cuts.is_empty());
    assert_eq!(cut.check_plannable().unwrap_err(), MeshError::Closed);
}

/// The fixtures' cuts: each bridge's shortest loop crosses it (as wide as the bridge's feet as
/// meshed), but the cut is the handle's other generator, across the plate between the holes
/// (14 mm from hole to hole): it leaves the bridge whole and overhangs 14 mm wide instead of two
/// 35/2 mm tongues 7 mm wide.
#[test]
fn the_fixtures_are_cut_across_the_plate_between_the_feet() {
    for (name, genus) in [("plate_with_handle", 1), ("genus2_sheet", 2)] {
        let out = mesh::from_triangles(&fixtures::by_name(name).unwrap(), &MeshOptions::default()).unwrap();
        // The plate's rim, and the holes' rims joined over the bridges into one loop.
        assert_eq!((out.report.genus, out.report.boundary_loops), (genus, 1 + genus as usize), "{name}");
        let cuts = &out.report.handle_cuts;
        assert_eq!(cuts.len(), genus as usize, "{name}");
        let width = 2.0 * PLATE_BRIDGE.half_width_mm;
        let gap = 2.0 * PLATE_BRIDGE.inner_mm;
        for cut in cuts {
            assert!(cut.shortest_mm <= width && cut.shortest_mm > 0.5 * width, "{name}: {}", cut.shortest_mm);
            assert!(cut.crossing, "{name}");
            assert!(cut.length_mm >= gap - 1e-9 && cut.length_mm < 1.1 * gap, "{name}: {}", cut.length_mm);
            // Only plate edges are cut: the loop's vertices off z = 0 are the bridge's side (a rim).
            let s = &out.surface;
            let cut_vertices = cut.vertex_ids.iter().filter(|&&v| s.positions[v as usize].z.abs() > 1e-9).count();
            assert!(cut_vertices > 0 && cut.rim_edges > cut_vertices, "{name}");
        }
        let s = &out.surface;
        assert_eq!((s.genus(), s.loops.len()), (0, 1 + 2 * genus as usize), "{name}");
        s.check_plannable().unwrap();
    }
}

/// The bridge's width as meshed: its feet are the holes' far-side vertices within its
/// half-width, about 2 mm apart.
fn width_meshed() -> f64 {
    2.0 * PLATE_BRIDGE.half_width_mm - HANDLE_EDGE_MM
}

/// Without the other generator the bridge is cut across, in the middle of its neck: two
/// tongues of half its length (the shortest loop alone ties all along the bridge and is cut at
/// a foot). The neck's depth there is about half the bridge (35.4 mm along its arch).
#[test]
fn a_bridge_cut_across_is_cut_in_its_middle() {
    let mesh = fixtures::by_name("plate_with_handle").unwrap();
    let options = |neck_ratio| MeshOptions {
        handles: handles::HandleOptions { crossing_ratio: 0.0, neck_ratio, ..Default::default() },
        ..MeshOptions::default()
    };
    let middle = &mesh::from_triangles(&mesh, &options(1.5)).unwrap().report.handle_cuts[0];
    let half = 0.5 * PLATE_BRIDGE.length_mm();
    assert!(!middle.crossing);
    assert!((middle.length_mm - middle.shortest_mm).abs() < 1e-9, "{} {}", middle.length_mm, middle.shortest_mm);
    assert!(middle.depth_mm > half && middle.depth_mm < half + 2.0 * HANDLE_EDGE_MM, "{}", middle.depth_mm);
    // The loop's points inside the bridge (off its sides, rims the loop follows back) lie on
    // a row next to the arch's top (x within one row of 0).
    let row = 2.0 * PLATE_BRIDGE.outer_mm / 19.0;
    let inside: Vec<_> =
        middle.polyline_mm.iter().filter(|p| p[2] > 0.0 && p[1].abs() < 0.5 * width_meshed() - 0.5).collect();
    assert!(!inside.is_empty());
    for p in inside {
        assert!(p[0].abs() <= row && p[2] > 9.0, "{p:?}");
    }
    let shortest = &mesh::from_triangles(&mesh, &options(1.0)).unwrap().report.handle_cuts[0];
    assert_eq!(shortest.depth_mm, 0.0);
    assert!((shortest.length_mm - middle.length_mm).abs() < 1e-9);
    let bad = MeshOptions {
        handles: handles::HandleOptions { neck_ratio: 0.5, ..Default::default() },
        ..MeshOptions::default()
    };
    assert!(matches!(
        mesh::from_triangles(&mesh, &bad).unwrap_err(),
        MeshError::Handles(handles::HandleError::Ratio { name: "neck", .. })
    ));
}

/// Both fixtures plan end to end within the verifier's limits (h 0.1 mm here to keep the test
/// fast; `benches/handle_proportions.rs` plans them at h 0.05 mm, and other proportions).
#[test]
fn the_fixtures_plan_end_to_end_within_h() {
    for (name, cuts) in [("plate_with_handle", 1), ("genus2_sheet", 2)] {
        let out = mesh::from_triangles(&fixtures::by_name(name).unwrap(), &MeshOptions::default()).unwrap();
        let planner = Planner::new(out, &|| 0.0).unwrap();
        let options = PlanOptions { radius_mm: 2.0, scallop_mm: 0.1, verify_samples: 20_000, ..PlanOptions::default() };
        let plan = planner.plan(&options, &mut |_, _, _| {}, &|| 0.0).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(plan.report.mesh.handle_cuts.len(), cuts);
        let v = plan.verification().unwrap();
        assert_eq!(v.gouges, 0, "{name}");
        assert!(
            v.max_scallop_outside_valleys_mm <= 1.02 * options.scallop_mm,
            "{name}: {}",
            v.max_scallop_outside_valleys_mm
        );
        assert!(v.uncovered_fraction <= 0.001, "{name}: {}", v.uncovered_fraction);
    }
}
