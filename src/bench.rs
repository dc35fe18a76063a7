//! Benchmark cases shared by the native benchmarks (`benches/`) and the wasm ones (headless
//! Chromium), so both measure the same work. The clock is passed in: the core has no I/O and
//! `std::time::Instant` does not exist on `wasm32-unknown-unknown`.

use crate::fixtures;
use crate::flatten::{BffSolver, FlattenInput, FlattenOptions};
use crate::mesh::{self, MeshOptions, TriMesh};
use crate::slitmap::{PlanarDomain, SlitMapOptions, SlitMapSolver};
use glam::DVec3;
use serde::Serialize;

/// A wavy `n × n`-quad sheet, 200 × 150 mm, with 3 square holes: about `2·n²` triangles
/// (`n = 730` gives the million-triangle mesh benchmark).
pub fn mesh_sheet(n: u32) -> TriMesh {
    let w = n + 1;
    let positions = (0..w * w)
        .map(|i| {
            let (x, y) = ((i % w) as f64 / n as f64 * 200.0, (i / w) as f64 / n as f64 * 150.0);
            DVec3::new(x, y, 5.0 * (x / 17.0).sin() * (y / 23.0).cos())
        })
        .collect();
    let hole = |i: u32, j: u32| {
        let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
        [(0.3, 0.3), (0.6, 0.5), (0.4, 0.75)].iter().any(|&(cx, cy)| (x - cx).abs() < 0.05 && (y - cy).abs() < 0.05)
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

/// Figures of one mesh-stage run on STL bytes, milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct MeshFigures {
    pub faces: usize,
    pub read_ms: f64,
    pub weld_ms: f64,
    pub topology_ms: f64,
    /// Normals and curvature tensors.
    pub geometry_ms: f64,
}

/// Times the parts of the mesh stage on `stl` with `now` (milliseconds).
pub fn run_mesh(stl: &[u8], now: &dyn Fn() -> f64) -> Result<MeshFigures, String> {
    let options = MeshOptions::default();
    let t = now();
    let soup = mesh::stl::read(stl, options.max_triangles).map_err(|e| e.to_string())?;
    let read_ms = now() - t;
    let t = now();
    let welded = mesh::weld::weld(&soup, options.weld_tolerance_rel).map_err(|e| e.to_string())?;
    let weld_ms = now() - t;
    let t = now();
    let topo = mesh::topology::analyse(&welded.mesh, options.tool_axis).map_err(|e| e.to_string())?;
    let (_, component) = mesh::topology::largest_component(&topo);
    let topology_ms = now() - t;
    let t = now();
    mesh::geometry::build_surface(component).map_err(|e| e.to_string())?;
    let geometry_ms = now() - t;
    Ok(MeshFigures { faces: soup.triangles.len(), read_ms, weld_ms, topology_ms, geometry_ms })
}

/// Best of `runs` per figure.
pub fn best_mesh(stl: &[u8], runs: usize, now: &dyn Fn() -> f64) -> Result<MeshFigures, String> {
    let mut best = run_mesh(stl, now)?;
    for _ in 1..runs {
        let r = run_mesh(stl, now)?;
        best.read_ms = best.read_ms.min(r.read_ms);
        best.weld_ms = best.weld_ms.min(r.weld_ms);
        best.topology_ms = best.topology_ms.min(r.topology_ms);
        best.geometry_ms = best.geometry_ms.min(r.geometry_ms);
    }
    Ok(best)
}

pub fn format_mesh(f: &MeshFigures) -> String {
    format!(
        "mesh stage, {} triangles: read {:.0} ms, weld {:.0} ms, topology {:.0} ms (read + weld + topology {:.0} ms); normals + curvature {:.0} ms",
        f.faces,
        f.read_ms,
        f.weld_ms,
        f.topology_ms,
        f.read_ms + f.weld_ms + f.topology_ms,
        f.geometry_ms
    )
}

/// Figures of one conformal-core run, milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct ConformalFigures {
    pub name: String,
    pub faces: usize,
    pub holes: usize,
    pub mesh_ms: f64,
    /// `BffSolver::new`: both factorisations of the flattening.
    pub flatten_factorise_ms: f64,
    pub flatten_solve_ms: f64,
    /// `SlitMapSolver::new`: both p-independent factorisations.
    pub slitmap_factorise_ms: f64,
    /// Mean over the poles of one `map(pole)` after the factorisation.
    pub slitmap_pole_ms: f64,
    pub poles: usize,
}

/// The analytic cases: the sample part, a 10k- and a 58k-face disk, the plate with 3 holes.
pub fn conformal_cases() -> Vec<(String, TriMesh)> {
    vec![
        ("freeform_4_holes".into(), fixtures::freeform_4_holes()),
        ("plate_3_holes".into(), fixtures::plate_3_holes()),
        ("unit_disk(40), 9.6k faces".into(), fixtures::unit_disk(40)),
        ("unit_disk(98), 58k faces".into(), fixtures::unit_disk(98)),
    ]
}

/// Runs mesh → flatten → slit map for the centroid pole and every hole's pole, timing each part
/// with `now` (milliseconds).
pub fn run_conformal(name: &str, part: &TriMesh, now: &dyn Fn() -> f64) -> Result<ConformalFigures, String> {
    // Cold start: the flattening pays the mesh's AMD order, the slit map reuses it.
    crate::linalg::mesh_order(0, &[]).map_err(|e| e.to_string())?;
    let t = now();
    let surface = mesh::from_triangles(part, &MeshOptions::default()).map_err(|e| e.to_string())?.surface;
    let mesh_ms = now() - t;
    let t = now();
    let bff = BffSolver::new(FlattenInput::from(&surface), &FlattenOptions::default()).map_err(|e| e.to_string())?;
    let flatten_factorise_ms = now() - t;
    let t = now();
    let flat = bff.flatten().map_err(|e| e.to_string())?;
    let flatten_solve_ms = now() - t;
    let domain =
        PlanarDomain { positions: flat.uv, triangles: surface.triangles.clone(), loops: surface.loops.clone() };
    let t = now();
    let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).map_err(|e| e.to_string())?;
    let slitmap_factorise_ms = now() - t;
    // Poles: the centre of the largest triangle (inside the domain) and each hole.
    let mut poles = vec![domain.largest_face_centre()];
    poles.extend((1..domain.loops.len()).map(|h| solver.canonical_hole_pole(h)));
    let t = now();
    for &p in &poles {
        solver.map(p).map_err(|e| e.to_string())?;
    }
    let slitmap_pole_ms = (now() - t) / poles.len() as f64;
    Ok(ConformalFigures {
        name: name.to_string(),
        faces: surface.triangles.len(),
        holes: surface.loops.len() - 1,
        mesh_ms,
        flatten_factorise_ms,
        flatten_solve_ms,
        slitmap_factorise_ms,
        slitmap_pole_ms,
        poles: poles.len(),
    })
}

/// One table row.
pub fn format_row(f: &ConformalFigures) -> String {
    format!(
        "{:<28} {:>7} {:>5} {:>9.1} {:>11.1} {:>9.1} {:>11.1} {:>9.2}",
        f.name,
        f.faces,
        f.holes,
        f.mesh_ms,
        f.flatten_factorise_ms,
        f.flatten_solve_ms,
        f.slitmap_factorise_ms,
        f.slitmap_pole_ms
    )
}

pub const TABLE_HEADER: &str =
    "case                           faces holes   mesh ms BFF fact ms  BFF ms   slit fact ms  pole ms";

#[cfg(test)]
mod tests {
    #[test]
    fn a_case_runs_and_times_every_part() {
        let clock = std::cell::Cell::new(0.0);
        let now = || {
            clock.set(clock.get() + 1.0);
            clock.get()
        };
        let f = super::run_conformal("plate", &crate::fixtures::plate_3_holes(), &now).unwrap();
        assert_eq!((f.holes, f.poles), (3, 4));
        assert!(f.mesh_ms > 0.0 && f.slitmap_pole_ms > 0.0);
    }
}
