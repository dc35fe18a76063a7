//! Benchmark cases shared by the native benchmarks (`benches/`) and the wasm ones (headless
//! Chromium), so both measure the same work. The clock is passed in: the core has no I/O and
//! `std::time::Instant` does not exist on `wasm32-unknown-unknown`.

pub mod step;

use crate::fixtures;
use crate::flatten::{BffSolver, FlattenInput, FlattenOptions};
use crate::mesh::{self, MeshOptions, TriMesh};
use crate::num;
use crate::origin::{self, EnergyEvaluator, OriginOptions};
use crate::plan::Facets;
use crate::slitmap::{PlanarDomain, SlitMapOptions, SlitMapSolver};
use crate::verify::{self, SweptVolume, VerifyOptions};
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

/// Figures of one origin-stage run, milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct OriginFigures {
    pub name: String,
    pub faces: usize,
    pub holes: usize,
    /// Mean `EnergyEvaluator::evaluate_map` (the energy of a slit map already solved).
    pub energy_ms: f64,
    /// Mean `EnergyEvaluator::evaluate` (slit map for the pole + energy).
    pub evaluate_ms: f64,
    /// `find_origin` with the default options (Auto).
    pub search_ms: f64,
    pub evaluations: usize,
    pub e_min: f64,
    pub centroid_e_min: f64,
    pub uniformity: f64,
}

/// The analytic origin cases: the sample part (about 10 000 faces, 4 holes) and the
/// symmetric part.
pub fn origin_cases() -> Vec<(String, TriMesh)> {
    vec![
        ("freeform_4_holes".into(), fixtures::freeform_4_holes()),
        ("symmetric_4_holes".into(), fixtures::symmetric_4_holes()),
    ]
}

/// Prepares mesh → flatten → slit-map solver (untimed), then times one energy evaluation
/// (mean over the centroid pole and every hole's pole) and the whole pole search.
pub fn run_origin(name: &str, part: &TriMesh, now: &dyn Fn() -> f64) -> Result<OriginFigures, String> {
    let surface = mesh::from_triangles(part, &MeshOptions::default()).map_err(|e| e.to_string())?.surface;
    let flat = BffSolver::new(FlattenInput::from(&surface), &FlattenOptions::default())
        .and_then(|b| b.flatten())
        .map_err(|e| e.to_string())?;
    let domain = PlanarDomain::of_surface(&surface, flat.uv);
    let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).map_err(|e| e.to_string())?;
    let options = OriginOptions::default();
    let ev = EnergyEvaluator::new(&surface, &solver, &options).map_err(|e| e.to_string())?;
    let mut poles = vec![origin::centroid_pole(&domain)];
    poles.extend((1..domain.loops.len()).map(|h| solver.canonical_hole_pole(h)));
    let maps = poles.iter().map(|&p| solver.map(p)).collect::<Result<Vec<_>, _>>().map_err(|e| e.to_string())?;
    let t = now();
    for m in &maps {
        ev.evaluate_map(m).map_err(|e| e.to_string())?;
    }
    let energy_ms = (now() - t) / maps.len() as f64;
    let t = now();
    for &p in &poles {
        ev.evaluate(p).map_err(|e| e.to_string())?;
    }
    let evaluate_ms = (now() - t) / poles.len() as f64;
    let t = now();
    let o = origin::find_origin(&surface, &domain, &solver, &options).map_err(|e| e.to_string())?;
    let search_ms = now() - t;
    Ok(OriginFigures {
        name: name.to_string(),
        faces: surface.triangles.len(),
        holes: surface.loops.len() - 1,
        energy_ms,
        evaluate_ms,
        search_ms,
        evaluations: o.evaluations,
        e_min: o.energy.e_min,
        centroid_e_min: o.centroid_energy.e_min,
        uniformity: o.energy.uniformity,
    })
}

/// Best of `runs` per time figure.
pub fn best_origin(name: &str, part: &TriMesh, runs: usize, now: &dyn Fn() -> f64) -> Result<OriginFigures, String> {
    let mut best = run_origin(name, part, now)?;
    for _ in 1..runs {
        let r = run_origin(name, part, now)?;
        best.energy_ms = best.energy_ms.min(r.energy_ms);
        best.evaluate_ms = best.evaluate_ms.min(r.evaluate_ms);
        best.search_ms = best.search_ms.min(r.search_ms);
    }
    Ok(best)
}

pub const ORIGIN_HEADER: &str =
    "case                           faces holes energy ms  eval ms  search ms evals      E_min   centroid uniformity";

/// One table row.
pub fn format_origin(f: &OriginFigures) -> String {
    format!(
        "{:<28} {:>7} {:>5} {:>9.3} {:>8.2} {:>10.1} {:>5} {:>10.4} {:>10.4} {:>10.4}",
        f.name,
        f.faces,
        f.holes,
        f.energy_ms,
        f.evaluate_ms,
        f.search_ms,
        f.evaluations,
        f.e_min,
        f.centroid_e_min,
        f.uniformity
    )
}

/// The verifier's case: a wavy disk of radius 50 mm, z = 4 sin(x/17) cos(y/23)
/// (`unit_disk(82)` scaled, 40 344 faces), under 171 parallel passes of ball centres (R = 3 mm)
/// 0.6 mm apart with a centre every 0.4 mm (43 605 segments): centre = surface point + R·normal
/// of the analytic surface.
pub fn verify_case() -> Result<(mesh::Surface, Vec<Vec<DVec3>>), String> {
    let height = |x: f64, y: f64| 4.0 * num::sin(x / 17.0) * num::cos(y / 23.0);
    let mut disk = fixtures::unit_disk(82);
    for p in &mut disk.positions {
        let (x, y) = (50.0 * p.x, 50.0 * p.y);
        *p = DVec3::new(x, y, height(x, y));
    }
    let surface = mesh::from_triangles(&disk, &MeshOptions::default()).map_err(|e| e.to_string())?.surface;
    let r = VerifyOptions::default().radius_mm;
    let passes = (0..171)
        .map(|j| {
            let y = -51.0 + 0.6 * j as f64;
            (0..256)
                .map(|i| {
                    let x = -51.0 + 0.4 * i as f64;
                    let fx = 4.0 / 17.0 * num::cos(x / 17.0) * num::cos(y / 23.0);
                    let fy = -4.0 / 23.0 * num::sin(x / 17.0) * num::sin(y / 23.0);
                    DVec3::new(x, y, height(x, y)) + r * DVec3::new(-fx, -fy, 1.0).normalize()
                })
                .collect()
        })
        .collect();
    Ok((surface, passes))
}

/// Figures of one verifier run, milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct VerifyFigures {
    pub faces: usize,
    pub vertices: usize,
    pub samples: usize,
    pub segments: usize,
    /// `SweptVolume::new` alone (the hierarchy over the segments).
    pub build_ms: f64,
    /// The whole `verify` call: build, sampling, every sample and vertex probed, statistics.
    pub verify_ms: f64,
    pub max_scallop_mm: f64,
    pub uncovered_samples: usize,
}

/// Times the verifier on a surface and path with `samples` samples.
pub fn run_verify(
    surface: &mesh::Surface,
    passes: &[Vec<DVec3>],
    samples: usize,
    now: &dyn Fn() -> f64,
) -> Result<VerifyFigures, String> {
    let options = VerifyOptions { samples, ..VerifyOptions::default() };
    let t = now();
    let volume = SweptVolume::new(passes, options.radius_mm).map_err(|e| e.to_string())?;
    let build_ms = now() - t;
    let t = now();
    let v = verify::verify(surface, passes, &options).map_err(|e| e.to_string())?;
    let verify_ms = now() - t;
    Ok(VerifyFigures {
        faces: surface.triangles.len(),
        vertices: surface.positions.len(),
        samples: v.samples,
        segments: volume.segments(),
        build_ms,
        verify_ms,
        max_scallop_mm: v.max_scallop_mm,
        uncovered_samples: v.uncovered_samples,
    })
}

pub fn format_verify(f: &VerifyFigures) -> String {
    format!(
        "verify, {} faces ({} vertices), {} samples, {} segments: hierarchy {:.1} ms, whole verify {:.1} ms (max scallop {:.4} mm, {} uncovered)",
        f.faces, f.vertices, f.samples, f.segments, f.build_ms, f.verify_ms, f.max_scallop_mm, f.uncovered_samples
    )
}

/// The whole pipeline on one part of machining size at R = 3 mm, h = 0.02 mm, 3-axis: faces,
/// holes, rings, path length (and over the flat-plate bound), max scallop / h (everywhere and
/// outside the facet valleys), p99 scallop / h, gouges and each stage's time (from the plan
/// report), for `cargo bench --bench plan` and its wasm twin. Two rows: the optimised field (the
/// default) and the conformal map's circles.
pub fn run_plan(name: &str, part: &TriMesh, now: &dyn Fn() -> f64) -> Result<String, String> {
    let optimised = plan_row(name, part, false, Facets::Exact, now)?;
    let conformal = plan_row_with("  (conformal)", part, false, Facets::Exact, crate::plan::Optimise::None, now)?;
    Ok(format!("{optimised}\n{conformal}"))
}

/// [`run_plan`] for the shared meshes, most of them unit-scale 3D shapes: where a sixtieth of the
/// diagonal is below 3 mm the ball is that, h = R/150 (the same ratio); always 5-axis with CL
/// output (their walls exceed a table-table machine's A range, and some undercut a 3-axis tool:
/// inverted_triangles). Two rows: facets exact (the default) and smooth, since these coarse
/// meshes are where the two differ.
pub fn run_plan_scaled(name: &str, part: &TriMesh, now: &dyn Fn() -> f64) -> Result<String, String> {
    let exact = plan_row(name, part, true, Facets::Exact, now)?;
    let smooth = plan_row("  (smooth)", part, true, Facets::Smooth, now)?;
    Ok(format!("{exact}\n{smooth}"))
}

fn plan_row(name: &str, part: &TriMesh, scaled: bool, facets: Facets, now: &dyn Fn() -> f64) -> Result<String, String> {
    plan_row_with(name, part, scaled, facets, crate::plan::Optimise::Tpsfo, now)
}

fn plan_row_with(
    name: &str,
    part: &TriMesh,
    scaled: bool,
    facets: Facets,
    optimise: crate::plan::Optimise,
    now: &dyn Fn() -> f64,
) -> Result<String, String> {
    let t = now();
    let out = mesh::from_triangles(part, &MeshOptions::default()).map_err(|e| e.to_string())?;
    let read = now() - t;
    let holes = out.surface.loops.len().saturating_sub(1);
    let (lo, hi) = crate::mesh::weld::bounding_box(&out.surface.positions);
    let mut options = crate::plan::PlanOptions { facets, optimise, ..crate::plan::PlanOptions::default() };
    if scaled {
        options.radius_mm = options.radius_mm.min((hi - lo).length() / 60.0);
        options.scallop_mm = options.radius_mm / 150.0;
        options.axes = crate::toolpath::Axes::five_default();
        options.post = crate::gcode::Post::Cl;
    }
    let planner = crate::plan::Planner::new(out, now).map_err(|e| e.to_string())?;
    let plan = planner.plan(&options, &mut |_, _, _| {}, now).map_err(|e| e.to_string())?;
    let r = &plan.report;
    let t = &r.timings_ms;
    let h = options.scallop_mm;
    // Outside the facet valleys (the same as the max where there are none).
    let (ratio, outside, p99, gouges) = r.verify.as_ref().map_or((f64::NAN, f64::NAN, f64::NAN, 0), |v| {
        (v.max_scallop_mm / h, v.max_scallop_outside_valleys_mm / h, v.p99_scallop_mm / h, v.gouges)
    });
    Ok(format!(
        "{:<24} {:>7} {:>5} {:>5} {:>9.0} {:>6.3} {:>6.2} {:>5.2} {:>5.2} {:>6} | {:>5.0} {:>5.0} {:>5.0} {:>6.0} {:>6.0} {:>6.0} {:>5.0} {:>5.0} {:>6.0} {:>5.0} {:>7.0}",
        name,
        r.mesh.machined.as_ref().map_or(r.mesh.faces, |m| m.faces),
        holes,
        r.rings,
        r.path.length_mm,
        r.path.length_over_ideal,
        ratio,
        outside,
        p99,
        gouges,
        read,
        t.flatten,
        t.slitmap,
        t.origin,
        t.optimise,
        t.spacing,
        t.spiral,
        t.toolpath,
        t.verify,
        t.post,
        read + t.total,
    ))
}

pub const PLAN_HEADER: &str = "case                       faces holes rings length mm  /ideal  max/h out/h p99/h gouges |  read  flat  slit origin optim spacng spiral  tool verify  post   total (ms)";

/// The analytic parts of the pipeline benchmark, and issue 5's 40k- and 300k-face parts with 6
/// holes: those whose name contains `only` ("" for all). Only those are built (the 300k part
/// takes seconds).
pub fn plan_cases(only: &str) -> Vec<(String, TriMesh)> {
    let build = |name: &str| match name {
        "panel_6_holes (40k)" => fixtures::panel_6_holes(0.75),
        // Issue 5's large part: ≤ 15 s in wasm within 1 GiB.
        "panel_6_holes (300k)" => fixtures::panel_6_holes(0.275),
        fixture => fixtures::by_name(fixture).expect("fixture"),
    };
    [
        "plate_3_holes",
        "saddle_2_holes",
        "spherical_cap_hole",
        "freeform_4_holes",
        "panel_6_holes (40k)",
        "panel_6_holes (300k)",
    ]
    .into_iter()
    .filter(|name| name.contains(only))
    .map(|name| (name.to_string(), build(name)))
    .collect()
}

/// The flank benchmark's problem (issue 35): the blade of [`fixtures::blade`] at seed 002
/// Fig. 17's scale, its tool (L 23.85, r₁ 3, r₂ 10), 10 strips × 20 poses × 30 samples per axis,
/// the seed's Fig. 17 weights (w₂ = 0.005, w₃ = 1), A/C post, 20 000 verifier samples.
pub fn flank_case() -> Result<(mesh::Surface, crate::flank::FlankOptions), String> {
    let options = MeshOptions { tool_axis: -DVec3::X, ..MeshOptions::default() };
    let surface = mesh::from_triangles(&fixtures::blade(58, 56), &options).map_err(|e| e.to_string())?.surface;
    let tool = crate::flank::SphereFamily::cone(3.0, 10.0, 23.85).map_err(|e| e.to_string())?;
    let flank = crate::flank::FlankOptions {
        tool,
        direction: -DVec3::Y,
        strips: Some(10),
        // The middle section's camber line is 341 mm long: 20 poses per strip.
        pose_step_mm: Some(341.1 / 19.0),
        samples_per_axis: 30,
        weights: crate::flank::Weights { approx: 0.005, g1: 1.0, ..crate::flank::Weights::accuracy() },
        ..crate::flank::FlankOptions::default()
    };
    Ok((surface, flank))
}

/// Figures of one flank plan, milliseconds and millimetres.
#[derive(Clone, Debug, Serialize)]
pub struct FlankFigures {
    pub faces: usize,
    pub strips: usize,
    pub poses: usize,
    pub samples_per_axis: usize,
    pub unknowns: usize,
    pub outer_iterations: usize,
    pub lbfgs_iterations: usize,
    pub guide_ms: f64,
    pub optimise_ms: f64,
    pub output_ms: f64,
    pub verify_ms: f64,
    pub total_ms: f64,
    pub max_error_mm: f64,
    pub max_kink_deg: f64,
    pub moves: usize,
}

/// Plans the flank case once, timed with `now` (milliseconds).
pub fn run_flank(now: &dyn Fn() -> f64) -> Result<FlankFigures, String> {
    let (surface, options) = flank_case()?;
    let plan = crate::flank::plan(&surface, &options, &mut |_, _, _| {}, now).map_err(|e| e.to_string())?;
    let r = &plan.report;
    let f = &r.optimise.final_figures;
    let kink =
        r.verify.as_ref().map_or(f64::NAN, |v| v.seams.iter().map(|s| s.envelope_max_kink_deg).fold(0.0, f64::max));
    Ok(FlankFigures {
        faces: surface.triangles.len(),
        strips: r.guide.strips,
        poses: r.optimise.poses,
        samples_per_axis: r.options.samples_per_axis,
        unknowns: r.optimise.unknowns,
        outer_iterations: r.optimise.outer_iterations,
        lbfgs_iterations: r.optimise.lbfgs_iterations,
        guide_ms: r.timings_ms.field + r.timings_ms.guide,
        optimise_ms: r.timings_ms.optimise,
        output_ms: r.timings_ms.envelope + r.timings_ms.output + r.timings_ms.post,
        verify_ms: r.timings_ms.verify,
        total_ms: r.timings_ms.total,
        max_error_mm: f.max_distance_error_mm.max(-f.min_distance_error_mm),
        max_kink_deg: kink,
        moves: r.output.moves,
    })
}

pub fn format_flank(f: &FlankFigures) -> String {
    format!(
        "flank, blade ({} faces), {} strips × {} poses × {} samples ({} unknowns): guide {:.0} ms, optimise {:.0} ms ({} outer, {} L-BFGS iterations), envelope + program {:.0} ms, verify {:.0} ms, total {:.0} ms; max error {:.3} mm, max kink {:.3}°, {} moves",
        f.faces,
        f.strips,
        f.poses / f.strips.max(1),
        f.samples_per_axis,
        f.unknowns,
        f.guide_ms,
        f.optimise_ms,
        f.outer_iterations,
        f.lbfgs_iterations,
        f.output_ms,
        f.verify_ms,
        f.total_ms,
        f.max_error_mm,
        f.max_kink_deg,
        f.moves
    )
}

/// One part of the planned-everywhere sweep (issue 34): planned with its own R and h and the
/// default options, verified.
#[derive(Debug, Clone, Serialize)]
pub struct SweepFigures {
    pub name: String,
    pub faces: usize,
    /// The plan's report (`SLITPATH_SWEEP_REPORTS=DIR` writes it): R and h among its options,
    /// the field the path follows, the spacing's retries.
    #[serde(skip)]
    pub report: crate::plan::PlanReport,
    pub flatten: crate::flatten::FlattenReport,
    pub max_over_h: f64,
    /// The verifier's max scallop outside the facet valleys, over h.
    pub max_outside_valleys_over_h: f64,
    /// What the facets alone leave at their deepest concave crease or pit, over h
    /// ([`crate::mesh::creases`]); above 1 the plan warned the user.
    pub facet_depth_over_h: f64,
    pub uncovered_fraction: f64,
    pub gouges: usize,
    /// The same two figures on fresh samples (another seed than the plan's own verification):
    /// a peak narrower than the samples' spacing is found by one sample set and not the other.
    pub fresh_max_over_h: f64,
    pub fresh_max_outside_valleys_over_h: f64,
    /// The path's length over the ideal (area / stepover of a flat plate at h).
    pub length_over_ideal: f64,
    pub plan_ms: f64,
}

impl SweepFigures {
    /// Whether the verified finish keeps the limits of [`SWEEP_LIMITS`]: max scallop ≤ 1.02 h,
    /// or, where the facets alone leave more than h and the plan said so, no more than 1.1 times
    /// what they leave (and ≤ 1.02 h outside their valleys).
    /// Both the plan's own samples and fresh ones are judged.
    pub fn within_limits(&self) -> bool {
        let (max_over_h, uncovered, gouges) = SWEEP_LIMITS;
        let max = self.max_over_h.max(self.fresh_max_over_h);
        let outside = self.max_outside_valleys_over_h.max(self.fresh_max_outside_valleys_over_h);
        let warned = self.facet_depth_over_h > 1.0;
        let scallop = max <= max_over_h || (warned && max <= 1.1 * self.facet_depth_over_h && outside <= max_over_h);
        scallop && self.uncovered_fraction <= uncovered && self.gouges <= gouges
    }

    /// The figures [`SweepFigures::within_limits`] judges.
    pub fn finish(&self) -> String {
        format!(
            "max scallop {:.3} h ({:.3} h outside facet valleys; fresh samples {:.3} h, {:.3} h; the facets alone leave {:.3} h), uncovered {:.2e}, {} gouges",
            self.max_over_h,
            self.max_outside_valleys_over_h,
            self.fresh_max_over_h,
            self.fresh_max_outside_valleys_over_h,
            self.facet_depth_over_h,
            self.uncovered_fraction,
            self.gouges
        )
    }
}

/// Why a part of the sweep could not be planned: the stage ([`crate::plan::PlanError::stage`])
/// and what went wrong.
#[derive(Debug, Clone, Serialize)]
pub struct SweepFailure {
    pub name: String,
    pub stage: &'static str,
    pub message: String,
}

/// The sweep's limits on the verified finish: max scallop ≤ 1.02 h (the pipeline tests' bound),
/// at most 0.1 % of the samples uncovered, no gouge.
pub const SWEEP_LIMITS: (f64, f64, usize) = (1.02, 1e-3, 0);

/// The seed of the sweep's second verification (the plan's own uses the default one).
pub const FRESH_SEED: u64 = 0xf4e5;

/// The face counts of the sweep's parts: small, so 200 of them take minutes.
pub const SWEEP_FACES: std::ops::RangeInclusive<usize> = 3_000..=12_000;

/// Plans `part` with its R and h (default options otherwise, `verify_samples` samples); the
/// verified figures are the caller's to judge ([`SweepFigures::within_limits`]).
pub fn run_sweep(
    part: &fixtures::generated::GeneratedPart,
    verify_samples: usize,
    now: &dyn Fn() -> f64,
) -> Result<SweepFigures, SweepFailure> {
    let fail = |stage: &'static str, message: String| SweepFailure { name: part.name.clone(), stage, message };
    let t0 = now();
    let out = mesh::from_triangles(&part.mesh, &MeshOptions::default()).map_err(|e| fail("mesh", e.to_string()))?;
    let faces = out.surface.triangles.len();
    let planner = crate::plan::Planner::new(out, now).map_err(|e| fail(e.stage(), e.to_string()))?;
    let (r, h) = (part.spec.radius_mm, part.spec.scallop_mm);
    let options = crate::plan::PlanOptions { radius_mm: r, scallop_mm: h, verify_samples, ..Default::default() };
    let plan = planner.plan(&options, &mut |_, _, _| {}, now).map_err(|e| fail(e.stage(), e.to_string()))?;
    let v = plan.report.verify.as_ref().ok_or_else(|| fail("verify", "not verified".into()))?;
    let fresh = planner.verify(&plan.toolpath, &options, FRESH_SEED).map_err(|e| fail("verify", e.to_string()))?;
    let figures = SweepFigures {
        name: part.name.clone(),
        faces,
        flatten: planner.flattening.report(),
        max_over_h: v.max_scallop_mm / h,
        max_outside_valleys_over_h: v.max_scallop_outside_valleys_mm / h,
        facet_depth_over_h: plan.report.facet_valleys.as_ref().map_or(0.0, |f| f.max_depth_mm / h),
        uncovered_fraction: v.uncovered_fraction,
        gouges: v.gouges.max(fresh.gouges),
        fresh_max_over_h: fresh.max_scallop_mm / h,
        fresh_max_outside_valleys_over_h: fresh.max_scallop_outside_valleys_mm / h,
        length_over_ideal: plan.report.path.length_over_ideal,
        plan_ms: now() - t0,
        report: plan.report,
    };
    Ok(figures)
}

pub fn format_sweep(f: &SweepFigures) -> String {
    let r = &f.report;
    format!(
        "{:<42} {:>6} R {:.2} h {:.4} {:<10} qc {:.4}/{:<7.3} max {:.3} h (fresh {:.3} h)  facets {:.3} h  length {:.3} ideal {:<9} {} retries  {:>6.0} ms",
        f.name,
        f.faces,
        r.options.radius_mm,
        r.options.scallop_mm,
        format!("{:?}", f.flatten.method),
        f.flatten.quality.qc_mean,
        f.flatten.quality.qc_max,
        f.max_over_h,
        f.fresh_max_over_h,
        f.facet_depth_over_h,
        f.length_over_ideal,
        r.optimise.as_ref().map_or("conformal", |o| o.path_field),
        r.spacing_retries.len(),
        f.plan_ms
    )
}

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

    #[test]
    fn the_origin_case_runs_and_times_every_part() {
        let clock = std::cell::Cell::new(0.0);
        let now = || {
            clock.set(clock.get() + 1.0);
            clock.get()
        };
        let f = super::run_origin("plate", &crate::fixtures::plate_3_holes(), &now).unwrap();
        assert_eq!(f.holes, 3);
        assert!(f.energy_ms > 0.0 && f.evaluate_ms > 0.0 && f.search_ms > 0.0);
        assert!(f.evaluations > 0 && f.e_min <= f.centroid_e_min);
    }

    #[test]
    fn the_verify_case_is_covered_and_timed() {
        let clock = std::cell::Cell::new(0.0);
        let now = || {
            clock.set(clock.get() + 1.0);
            clock.get()
        };
        let (surface, passes) = super::verify_case().unwrap();
        let f = super::run_verify(&surface, &passes, 2000, &now).unwrap();
        assert_eq!((f.faces, f.segments, f.samples), (40_344, 171 * 255, 2000));
        // 0.6 mm apart with R = 3 on a gentle wave: about the flat R − √(R² − 0.3²) = 0.015 mm.
        assert!(f.max_scallop_mm > 0.01 && f.max_scallop_mm < 0.02, "{}", f.max_scallop_mm);
        assert_eq!(f.uncovered_samples, 0);
        assert!(f.build_ms > 0.0 && f.verify_ms > 0.0);
    }

    #[test]
    fn the_flank_case_is_the_issue_s_problem_size() {
        let (surface, options) = super::flank_case().unwrap();
        assert!(surface.triangles.len() > 6000);
        assert_eq!((options.strips, options.samples_per_axis), (Some(10), 30));
    }
}

/// One row of the length table (issue 32): a generated part planned with the conformal map's
/// rings and with seed 003's optimised field, the same R and h, each verified.
#[derive(Debug, Clone, Serialize)]
pub struct LengthFigures {
    pub name: String,
    pub faces: usize,
    pub radius_mm: f64,
    pub scallop_mm: f64,
    pub conformal: PathFigures,
    pub optimised: PathFigures,
    /// `tpsfo`, or `conformal` where the planner kept the conformal map's path.
    pub path_field: String,
    pub optimise_ms: f64,
}

/// A verified path's figures at equal finish (DESIGN.md "Path length at equal finish").
#[derive(Debug, Clone, Copy, Serialize)]
pub struct PathFigures {
    /// Length over the flat-plate bound area / (2·√(2Rh)).
    pub length_over_ideal: f64,
    pub max_over_h: f64,
    pub median_over_h: f64,
    /// Seed 003 eq. 34 over the area: the mean CT², and the largest CT.
    pub ct2_mean: f64,
    pub max_ct: u32,
    /// Seed 003 eq. 33, mm⁻¹.
    pub rho2: f64,
}

/// The parts of the length table: generated parts of seeds `0..count` (5k–40k faces).
pub fn length_parts(count: u64) -> impl Iterator<Item = fixtures::generated::GeneratedPart> {
    (0..count).map(|seed| fixtures::generated::part(seed, fixtures::generated::BENCH_FACES))
}

/// Plans `part` both ways with its own R and h (100 000 verifier samples each).
pub fn run_length(part: &fixtures::generated::GeneratedPart, now: &dyn Fn() -> f64) -> Result<LengthFigures, String> {
    let out = mesh::from_triangles(&part.mesh, &MeshOptions::default()).map_err(|e| e.to_string())?;
    let faces = out.surface.triangles.len();
    let planner = crate::plan::Planner::new(out, now).map_err(|e| format!("flatten/slit map: {e}"))?;
    let (r, h) = (part.spec.radius_mm, part.spec.scallop_mm);
    let run = |optimise| -> Result<(PathFigures, String, f64), String> {
        let options = crate::plan::PlanOptions { radius_mm: r, scallop_mm: h, optimise, ..Default::default() };
        let plan = planner.plan(&options, &mut |_, _, _| {}, now).map_err(|e| e.to_string())?;
        let report = &plan.report;
        let v = report.verify.as_ref().ok_or("not verified")?;
        let figures = PathFigures {
            length_over_ideal: report.path.length_over_ideal,
            max_over_h: v.max_scallop_mm / h,
            median_over_h: v.median_scallop_mm / h,
            ct2_mean: v.ct2 / planner.surface.area(),
            max_ct: v.max_ct,
            rho2: report.path.rho2,
        };
        let field = report.optimise.as_ref().map_or("conformal", |o| o.path_field).to_string();
        Ok((figures, field, report.timings_ms.optimise))
    };
    let (conformal, _, _) = run(crate::plan::Optimise::None)?;
    let (optimised, path_field, optimise_ms) = run(crate::plan::Optimise::Tpsfo)?;
    Ok(LengthFigures {
        name: part.name.clone(),
        faces,
        radius_mm: r,
        scallop_mm: h,
        conformal,
        optimised,
        path_field,
        optimise_ms,
    })
}

pub const LENGTH_HEADER: &str = "part                                        faces    R      h    | conformal: len/ideal max/h  med/h  CT²  maxCT ρ²    | optimised: len/ideal max/h  med/h  CT²  maxCT ρ²     field   opt ms";

pub fn format_length(f: &LengthFigures) -> String {
    let cells = |p: &PathFigures| {
        format!(
            "{:>9.3} {:>5.2} {:>6.3} {:>5.1} {:>4} {:>6.0}",
            p.length_over_ideal, p.max_over_h, p.median_over_h, p.ct2_mean, p.max_ct, p.rho2
        )
    };
    format!(
        "{:<42} {:>6} {:>5.2} {:>6.4} |        {} |        {}  {:<9} {:>5.0}",
        f.name,
        f.faces,
        f.radius_mm,
        f.scallop_mm,
        cells(&f.conformal),
        cells(&f.optimised),
        f.path_field,
        f.optimise_ms
    )
}

/// The table's summary: medians of length over ideal both ways, the largest optimised one, the
/// median of the optimised median scallop, the parts that kept the conformal path, and those that
/// could not be planned.
pub fn summarise_lengths(rows: &[LengthFigures], failed: usize) -> String {
    let median = |mut v: Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            f64::NAN
        } else {
            v[v.len() / 2]
        }
    };
    let before = median(rows.iter().map(|r| r.conformal.length_over_ideal).collect());
    let after = median(rows.iter().map(|r| r.optimised.length_over_ideal).collect());
    let worst = rows.iter().map(|r| r.optimised.length_over_ideal).fold(f64::NAN, f64::max);
    let med_scallop = median(rows.iter().map(|r| r.optimised.median_over_h).collect());
    let kept = rows.iter().filter(|r| r.path_field != "tpsfo").count();
    let over = rows.iter().filter(|r| r.optimised.max_over_h > 1.0 && r.conformal.max_over_h <= 1.0).count();
    format!(
        "{} parts planned, {failed} not: median length/ideal {before:.3} -> {after:.3} ({:+.1} %), largest {worst:.3}; median scallop {med_scallop:.3} h; conformal path kept on {kept}; over h where the conformal path is not: {over}",
        rows.len(),
        100.0 * (after / before - 1.0)
    )
}
