//! `slitpath map`: flatten a part, compute its conformal slit map for a chosen pole, and write the
//! map as JSON (and optionally SVG).

use glam::DVec3;
use serde::Serialize;
use slitpath::flatten::{self, FlattenInput, FlattenOptions, FlattenQuality};
use slitpath::mesh::Surface;
use slitpath::origin;
use slitpath::slitmap::{self, Mode, PlanarDomain, SlitMapOptions};
use std::time::Instant;

/// Where the pole comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum PoleChoice {
    /// The area centroid of the flattened domain (holes excluded), or the nearest face centre
    /// when it is not safely inside ([`origin::centroid_pole`]).
    Centroid,
    /// A point inside hole `N` (loops index, 1-based): the annulus map of that hole.
    Hole(usize),
    /// A point in the part's coordinates, moved to the nearest surface point.
    Point3d(DVec3),
}

pub fn parse_pole(s: &str) -> Result<PoleChoice, String> {
    if s == "centroid" {
        return Ok(PoleChoice::Centroid);
    }
    if let Some(n) = s.strip_prefix("hole:") {
        return n.parse().map(PoleChoice::Hole).map_err(|_| format!("`{n}` is not a hole number"));
    }
    Err(format!("unknown pole `{s}`: use `centroid`, `hole:N` or --pole-3d X,Y,Z"))
}

#[derive(Serialize)]
pub struct SlitSummary {
    pub hole: usize,
    pub radius: f64,
    pub theta_start: f64,
    pub theta_end: f64,
}

#[derive(Serialize)]
pub struct MapJson {
    pub mode: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inner_radius: Option<f64>,
    /// The hole mapped to the inner circle (annulus mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub annulus_hole: Option<usize>,
    pub pole_uv: [f64; 2],
    pub pole_3d: [f64; 3],
    pub slits: Vec<SlitSummary>,
    pub flipped_triangles: usize,
    pub flatten: FlattenQuality,
    pub timings_ms: Timings,
    pub vertices: Vec<[f64; 3]>,
    pub uv: Vec<[f64; 2]>,
    pub w: Vec<[f64; 2]>,
}

#[derive(Serialize)]
pub struct Timings {
    pub flatten: f64,
    pub slitmap_factorise: f64,
    pub slitmap_pole: f64,
}

pub struct MapResult {
    pub json: MapJson,
    pub svg: String,
}

pub fn run(surface: &Surface, pole: &PoleChoice) -> Result<MapResult, String> {
    surface.check_plannable().map_err(|e| e.to_string())?;
    // The planner's surface (hole rims refined, ears split): the vertex list written below is this one.
    let refined = slitpath::plan::planning_surface(surface);
    let surface = &refined;
    let t = Instant::now();
    let flat = flatten::flatten(FlattenInput::from(surface), &FlattenOptions::default()).map_err(|e| e.to_string())?;
    let t_flatten = t.elapsed().as_secs_f64() * 1e3;
    let domain = PlanarDomain::of_surface(surface, flat.uv.clone());
    let t = Instant::now();
    let solver = slitmap::SlitMapSolver::new(&domain, &SlitMapOptions::default()).map_err(|e| e.to_string())?;
    let t_factorise = t.elapsed().as_secs_f64() * 1e3;
    let (pole_uv, hole) = match pole {
        PoleChoice::Centroid => (origin::centroid_pole(&domain), None),
        PoleChoice::Hole(n) => {
            let holes = solver.hole_count();
            if *n == 0 || *n > holes {
                return Err(format!("hole:{n} does not exist: the part has {holes} holes (numbered 1 to {holes})"));
            }
            (solver.canonical_hole_pole(*n), Some(*n))
        }
        PoleChoice::Point3d(p) => (origin::pole_from_3d(surface, &domain, *p), None),
    };
    let pole_3d = origin::pole_to_3d(surface, &domain, pole_uv, hole);
    let t = Instant::now();
    let map = solver.map(pole_uv).map_err(|e| e.to_string())?;
    let t_pole = t.elapsed().as_secs_f64() * 1e3;
    let (mode, inner_radius, annulus_hole) = match map.mode {
        Mode::Disk => ("disk", None, None),
        Mode::Annulus { hole, inner_radius } => ("annulus", Some(inner_radius), Some(hole)),
    };
    let slits: Vec<SlitSummary> = map
        .slits
        .iter()
        .map(|s| SlitSummary { hole: s.hole, radius: s.radius, theta_start: s.theta_start, theta_end: s.theta_end })
        .collect();
    let svg = crate::svg::draw(&crate::svg::SlitDrawing {
        uv: &domain.positions,
        w: &map.w,
        triangles: &domain.triangles,
        loops: &domain.loops,
        slits: &slits.iter().map(|s| (s.radius, s.theta_start, s.theta_end)).collect::<Vec<_>>(),
        inner_radius,
        pole_uv,
    });
    let json = MapJson {
        mode,
        inner_radius,
        annulus_hole,
        pole_uv: pole_uv.to_array(),
        pole_3d: pole_3d.to_array(),
        slits,
        flipped_triangles: map.flipped_triangles(),
        flatten: flat.quality,
        timings_ms: Timings { flatten: t_flatten, slitmap_factorise: t_factorise, slitmap_pole: t_pole },
        vertices: surface.positions.iter().map(|p| p.to_array()).collect(),
        uv: domain.positions.iter().map(|p| p.to_array()).collect(),
        w: map.w.iter().map(|p| p.to_array()).collect(),
    };
    Ok(MapResult { json, svg })
}
