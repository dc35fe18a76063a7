//! Mesh-stage benchmark: read + weld + topology (+ normals and curvature) of a 1-million-triangle
//! binary STL. Prints figures; asserts nothing about time. Run with `cargo bench --bench mesh`.

use glam::DVec3;
use slitpath::mesh::{self, stl, MeshOptions, TriMesh};
use std::time::Instant;

/// A wavy `n × n`-quad sheet with a few square holes: `2·n²` triangles minus the holes.
fn sheet(n: u32) -> TriMesh {
    let w = n + 1;
    let positions = (0..w * w)
        .map(|i| {
            let (x, y) = ((i % w) as f64 / n as f64 * 200.0, (i / w) as f64 / n as f64 * 150.0);
            DVec3::new(x, y, 5.0 * (x / 17.0).sin() * (y / 23.0).cos())
        })
        .collect();
    let hole = |i: u32, j: u32| {
        [(0.3, 0.3), (0.6, 0.5), (0.4, 0.75)].iter().any(|&(cx, cy)| {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            (x - cx).abs() < 0.05 && (y - cy).abs() < 0.05
        })
    };
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            if hole(i, j) {
                continue;
            }
            let v = |di: u32, dj: u32| (j + dj) * w + i + di;
            triangles.push([v(0, 0), v(1, 0), v(1, 1)]);
            triangles.push([v(0, 0), v(1, 1), v(0, 1)]);
        }
    }
    TriMesh { positions, triangles }
}

fn main() {
    let bytes = stl::write_binary(&sheet(730), "bench sheet");
    let faces = (bytes.len() - 84) / 50;
    let options = MeshOptions::default();
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let mut best = [f64::INFINITY; 5];
    for _ in 0..3 {
        let t = Instant::now();
        let soup = stl::read(&bytes, options.max_triangles).expect("valid STL");
        let read = ms(t);
        let t = Instant::now();
        let welded = mesh::weld::weld(&soup, options.weld_tolerance_rel).expect("weldable");
        let weld = ms(t);
        let t = Instant::now();
        let topo = mesh::topology::analyse(&welded.mesh, options.tool_axis).expect("manifold");
        let (_, component) = mesh::topology::largest_component(&topo);
        let topology = ms(t);
        let t = Instant::now();
        let surface = mesh::geometry::build_surface(component).expect("surface");
        let geometry = ms(t);
        assert_eq!(surface.loops.len(), 4);
        let total = read + weld + topology + geometry;
        println!("read {read:.0} ms, weld {weld:.0} ms, topology {topology:.0} ms, normals + curvature {geometry:.0} ms; total {total:.0} ms");
        for (b, x) in best.iter_mut().zip([read, weld, topology, geometry, total]) {
            *b = b.min(x);
        }
    }
    println!(
        "mesh stage, {faces} triangles ({:.1} MB binary STL), best of 3, native: read + weld + topology {:.0} ms; with normals and curvature {:.0} ms",
        bytes.len() as f64 / 1e6,
        best[0] + best[1] + best[2],
        best[4]
    );
}
