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
    let mut best = f64::INFINITY;
    let mut report = None;
    for _ in 0..3 {
        let t = Instant::now();
        let soup = stl::read(&bytes, options.max_triangles).expect("valid STL");
        let t_read = t.elapsed().as_secs_f64();
        let out = mesh::from_triangles(&soup, &options).expect("valid mesh");
        let total = t.elapsed().as_secs_f64();
        println!(
            "read {:.0} ms, weld + topology + geometry {:.0} ms, total {:.0} ms",
            t_read * 1e3,
            (total - t_read) * 1e3,
            total * 1e3
        );
        best = best.min(total);
        report = Some(out.report);
    }
    let r = report.expect("ran");
    println!(
        "mesh stage, {faces} triangles ({:.1} MB binary STL): best of 3 = {:.0} ms native; {} vertices, {} loops, genus {}",
        bytes.len() as f64 / 1e6,
        best * 1e3,
        r.vertices,
        r.boundary_loops,
        r.genus
    );
}
