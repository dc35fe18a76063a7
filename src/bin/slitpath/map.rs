//! `slitpath map`: flatten a part, compute its conformal slit map for a chosen pole, and write the
//! map as JSON (and optionally SVG).

use glam::{DVec2, DVec3};
use serde::Serialize;
use slitpath::flatten::{self, FlattenInput, FlattenOptions, FlattenQuality};
use slitpath::mesh::Surface;
use slitpath::slitmap::{self, InverseMap, Mode, PlanarDomain, SlitMapOptions};
use std::sync::Arc;
use std::time::Instant;

/// Where the pole comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum PoleChoice {
    /// The area centroid of the flattened domain (holes excluded).
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
    let t = Instant::now();
    let flat = flatten::flatten(FlattenInput::from(surface), &FlattenOptions::default()).map_err(|e| e.to_string())?;
    let t_flatten = t.elapsed().as_secs_f64() * 1e3;
    let domain = PlanarDomain::of_surface(surface, flat.uv.clone());
    let t = Instant::now();
    let solver = slitmap::SlitMapSolver::new(&domain, &SlitMapOptions::default()).map_err(|e| e.to_string())?;
    let t_factorise = t.elapsed().as_secs_f64() * 1e3;
    let (pole_uv, pole_3d) = match pole {
        PoleChoice::Centroid => centroid(&domain, surface, &solver),
        PoleChoice::Hole(n) => hole_point(&domain, surface, *n, &solver)?,
        PoleChoice::Point3d(p) => {
            let (face, bary) = nearest_on_surface(surface, *p);
            let t = surface.triangles[face];
            let uv = (0..3).map(|k| domain.positions[t[k] as usize] * bary[k]).sum();
            let p3 = (0..3).map(|k| surface.positions[t[k] as usize] * bary[k]).sum();
            (uv, p3)
        }
    };
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

/// Area centroid of the flattened domain; when it falls outside the outer loop (a crescent), the
/// centroid of the triangle nearest to it. Returns the point and its 3D image.
fn centroid(domain: &PlanarDomain, surface: &Surface, solver: &slitmap::SlitMapSolver) -> (DVec2, DVec3) {
    let mut area = 0.0;
    let mut c = DVec2::ZERO;
    for t in &domain.triangles {
        let [a, b, p] = t.map(|v| domain.positions[v as usize]);
        let ar = 0.5 * (b - a).perp_dot(p - a);
        area += ar;
        c += (a + b + p) / 3.0 * ar;
    }
    let c = c / area;
    match solver.classify_pole(c) {
        Ok(None) => {
            let flat = InverseMap::new(&domain.positions, Arc::new(domain.triangles.clone()));
            if let Some(location) = flat.locate(c) {
                return (c, location.interpolate(&surface.positions));
            }
        }
        Ok(Some(hole)) => {
            // Inside a hole: a legitimate annulus pole; its 3D image is the hole's centroid.
            let l = &domain.loops[hole];
            return (c, l.iter().map(|&v| surface.positions[v as usize]).sum::<DVec3>() / l.len() as f64);
        }
        Err(_) => {}
    }
    let face = (0..domain.triangles.len())
        .min_by(|&a, &b| tri_centroid(domain, a).distance(c).total_cmp(&tri_centroid(domain, b).distance(c)))
        .expect("triangles");
    let t = surface.triangles[face];
    (tri_centroid(domain, face), t.iter().map(|&v| surface.positions[v as usize]).sum::<DVec3>() / 3.0)
}

fn tri_centroid(domain: &PlanarDomain, f: usize) -> DVec2 {
    domain.triangles[f].iter().map(|&v| domain.positions[v as usize]).sum::<DVec2>() / 3.0
}

/// A point strictly inside hole `n` of the flattened plane.
fn hole_point(
    domain: &PlanarDomain,
    surface: &Surface,
    n: usize,
    solver: &slitmap::SlitMapSolver,
) -> Result<(DVec2, DVec3), String> {
    let holes = domain.loops.len() - 1;
    if n == 0 || n > holes {
        return Err(format!("hole:{n} does not exist: the part has {holes} holes (numbered 1 to {holes})"));
    }
    let l = &domain.loops[n];
    let p3 = l.iter().map(|&v| surface.positions[v as usize]).sum::<DVec3>() / l.len() as f64;
    let centre = l.iter().map(|&v| domain.positions[v as usize]).sum::<DVec2>() / l.len() as f64;
    // The vertex centroid for convex holes; otherwise midpoints of chords across the hole.
    let m = l.len();
    let candidates = std::iter::once(centre).chain((0..m).flat_map(|i| {
        let a = domain.positions[l[i] as usize];
        [m / 2, m / 3, 2].map(|d| a.lerp(domain.positions[l[(i + d) % m] as usize], 0.5))
    }));
    for c in candidates {
        if solver.classify_pole(c) == Ok(Some(n)) {
            return Ok((c, p3));
        }
    }
    Err(format!("no interior point of hole {n} was found in the flattened plane"))
}

/// Nearest point of the surface to `p`: (face, barycentric coordinates). Brute force, O(faces).
fn nearest_on_surface(surface: &Surface, p: DVec3) -> (usize, [f64; 3]) {
    let mut best = (f64::INFINITY, 0, [1.0, 0.0, 0.0]);
    for (f, t) in surface.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| surface.positions[v as usize]);
        let bary = closest_on_triangle(p, a, b, c);
        let q = a * bary[0] + b * bary[1] + c * bary[2];
        let d = q.distance_squared(p);
        if d < best.0 {
            best = (d, f, bary);
        }
    }
    (best.1, best.2)
}

/// Barycentric coordinates of the point of triangle `abc` closest to `p` (Ericson, Real-Time
/// Collision Detection, §5.1.5).
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
}
