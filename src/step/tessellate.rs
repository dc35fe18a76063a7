//! B-rep → one triangle mesh, each triangle tagged with its face, adjacent faces sharing the
//! vertices of their common edges (so the mesh is welded by construction).
//!
//! 1. Every edge used by a selected face is sampled once in 3D: its curve between its end
//!    vertices, split in halves while the chord strays more than half the chordal tolerance from the
//!    curve's midpoint or is longer than the edge limit (a curved edge at least in four). The end
//!    samples are the vertices themselves.
//! 2. Each face's loops are chains of these samples. An edge with a PCURVE on the face's surface
//!    takes its samples' parameters from it (at the 3D curve's parameters, or located on it),
//!    unless some sample's pcurve point maps farther than [`PCURVE_GUARD`] × the tolerance from
//!    it; a seam edge's two pcurves go to its two uses by continuity round the loop. Other
//!    samples are inverted onto the surface (closed form for analytic surfaces, Newton for
//!    B-splines). The 3D samples are never moved. Angle parameters are unwrapped
//!    along the loop, so a seam edge used twice gives the two sides of the parameter rectangle;
//!    two loops that wind once round a periodic surface in opposite senses (a band without a
//!    seam edge, as Parasolid writes it) are joined by a synthetic seam, sampled once and used
//!    by both its sides; other winding loops cannot be a planar domain and are refused.
//! 3. [`triangulate`] meshes the domain to the tolerance; triangles are wound so their normal
//!    is the face's (the surface normal, reversed when the face's `same_sense` is false).

use super::geom::{Curve, Surface};
use super::model::{Bound, Edge, Face, Model, Pcurve};
use super::triangulate::{self, Domain, Failure};
use super::{FaceInfo, StepError, StepOptions};
use crate::num;
use glam::{DVec2, DVec3};
use std::collections::{BTreeMap, BTreeSet};
use std::f64::consts::TAU;

/// The tessellation: a welded mesh, the face of each triangle, the faces' figures.
#[derive(Clone, Debug)]
pub struct Tessellation {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// The STEP id of each triangle's ADVANCED_FACE.
    pub face_of_triangle: Vec<u64>,
    pub faces: Vec<FaceInfo>,
    /// The largest facet-to-surface distance measured (mm).
    pub chordal_error_mm: f64,
}

/// How far (a fraction of the chordal tolerance) a pcurve's point, mapped through the surface,
/// may lie from the edge's 3D sample for the pcurve to parameterise the edge.
pub const PCURVE_GUARD: f64 = 0.1;

/// The faces `selected` of `model` (all when `None`), each once, in the order asked.
fn select<'m>(model: &'m Model, selected: Option<&[u64]>) -> Result<Vec<&'m Face>, StepError> {
    Ok(match selected {
        None => model.faces.iter().collect(),
        Some(ids) => {
            let mut out = Vec::new();
            for id in ids {
                let f = model.faces.iter().find(|f| f.id == *id).ok_or_else(|| StepError::UnknownFace {
                    id: *id,
                    faces: model.faces.iter().map(|f| f.id).collect(),
                })?;
                if !out.iter().any(|g: &&Face| g.id == f.id) {
                    out.push(f);
                }
            }
            out
        }
    })
}

/// The diagonal of the model's box (vertices, points of closed edges and VERTEX_LOOPs), mm.
fn diagonal(model: &Model) -> f64 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut add = |p: DVec3| {
        lo = lo.min(p);
        hi = hi.max(p);
    };
    model.vertices.values().for_each(|p| add(*p));
    // A closed edge (a full circle) has one vertex, a VERTEX_LOOP bounds by a point: without
    // their points a dome's box is a point.
    for f in &model.faces {
        f.vertex_loops.iter().for_each(|p| add(*p));
    }
    for edge in model.edges.values().filter(|e| e.start == e.end) {
        let a = model.vertices[&edge.start];
        let (t0, t1) = edge.curve.span(a, a, true);
        (0..8).for_each(|k| add(edge.curve.point(t0 + (t1 - t0) * k as f64 / 8.0)));
    }
    (hi - lo).length().max(1e-9)
}

/// The edges' samples: positions (vertices first used first), and per edge its samples' ids and
/// the file parameters of its curve at them, in the edge's direction.
struct EdgeSamples {
    positions: Vec<DVec3>,
    ids: BTreeMap<u64, Vec<u32>>,
    params: BTreeMap<u64, Vec<f64>>,
}

/// Samples every edge of `faces` once (see the module docs, step 1).
fn sample_edges(model: &Model, faces: &[&Face], tol: f64, max_edge: f64) -> EdgeSamples {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut vertex_index: BTreeMap<u64, u32> = BTreeMap::new();
    let mut edge_samples: BTreeMap<u64, Vec<u32>> = BTreeMap::new();
    let mut edge_params: BTreeMap<u64, Vec<f64>> = BTreeMap::new();
    for f in faces {
        for b in &f.bounds {
            for &(e, _) in &b.edges {
                if edge_samples.contains_key(&e) {
                    continue;
                }
                let edge = &model.edges[&e];
                let mut ids = Vec::new();
                for v in [edge.start, edge.end] {
                    let next = positions.len() as u32;
                    let i = *vertex_index.entry(v).or_insert(next);
                    if i == next {
                        positions.push(model.vertices[&v]);
                    }
                    ids.push(i);
                }
                let (a, b) = (model.vertices[&edge.start], model.vertices[&edge.end]);
                let closed = edge.start == edge.end;
                // Sample in the curve's direction, then turn to the edge's.
                let (from, to) = if edge.same_sense { (a, b) } else { (b, a) };
                let (t0, t1) = edge.curve.span(from, to, closed);
                let min_depth = if matches!(edge.curve, super::geom::Curve::Line { .. }) { 0 } else { 2 };
                let mut inner = Vec::new();
                // Half the tolerance: the facets along the edge then have room for the surface's own bulge.
                subdivide(&|t| edge.curve.point(t), t0, from, t1, to, 0.5 * tol, max_edge, min_depth, 0, &mut inner);
                let mut ts = vec![t0];
                ts.extend(inner.iter().map(|s| s.0));
                ts.push(t1);
                if !edge.same_sense {
                    inner.reverse();
                    ts.reverse();
                }
                let mut list = vec![ids[0]];
                for (_, p) in inner {
                    list.push(positions.len() as u32);
                    positions.push(p);
                }
                list.push(ids[1]);
                edge_samples.insert(e, list);
                edge_params.insert(e, ts.iter().map(|t| t / edge.param_scale).collect());
            }
        }
    }
    EdgeSamples { positions, ids: edge_samples, params: edge_params }
}

/// Tessellates the faces of `model` whose ids are in `selected` (all when `None`).
pub fn tessellate(model: &Model, selected: Option<&[u64]>, o: &StepOptions) -> Result<Tessellation, StepError> {
    let faces = select(model, selected)?;
    let max_edge = o.max_edge_mm.unwrap_or(diagonal(model) / 50.0);
    let tol = o.chordal_tol_mm;

    // 1. Edge samples, shared.
    let EdgeSamples { mut positions, ids: edge_samples, params: edge_params } =
        sample_edges(model, &faces, tol, max_edge);

    // 2–3. Faces.
    let mut triangles = Vec::new();
    let mut face_of_triangle = Vec::new();
    let mut infos = Vec::new();
    let mut chordal = 0.0f64;
    let budget = o.max_triangles;
    for f in &faces {
        let samples = (&edge_samples, &edge_params);
        let (tris, local_to_global, dom, err, [pcurve_edges, pcurves_off_surface]) =
            mesh_face(f, &model.edges, samples, &mut positions, tol, max_edge, budget)?;
        chordal = chordal.max(err);
        let mut global: Vec<u32> = local_to_global;
        for p in &dom.p[global.len()..] {
            global.push(positions.len() as u32);
            positions.push(*p);
        }
        let mut area = 0.0;
        for t in &tris {
            let g = t.map(|i| global[i as usize]);
            let g = if f.same_sense { g } else { [g[0], g[2], g[1]] };
            let [a, b, c] = g.map(|i| positions[i as usize]);
            area += 0.5 * (b - a).cross(c - a).length();
            triangles.push(g);
            face_of_triangle.push(f.id);
        }
        if triangles.len() > budget {
            return Err(StepError::TooManyTriangles { face: f.id, cap: budget });
        }
        infos.push(FaceInfo {
            id: f.id,
            surface: f.surface.kind().to_string(),
            surface_id: f.surface_id,
            loops: f.bounds.len(),
            area_mm2: area,
            triangles: tris.len(),
            chordal_error_mm: err,
            pcurve_edges,
            pcurves_off_surface,
            adjacent: Vec::new(),
        });
    }
    // Adjacency: faces sharing an edge.
    let mut users: BTreeMap<u64, BTreeSet<u64>> = BTreeMap::new();
    for f in &model.faces {
        for b in &f.bounds {
            for &(e, _) in &b.edges {
                users.entry(e).or_default().insert(f.id);
            }
        }
    }
    for info in &mut infos {
        let f = model.faces.iter().find(|f| f.id == info.id).expect("selected from the model");
        let mut adj = BTreeSet::new();
        for b in &f.bounds {
            for &(e, _) in &b.edges {
                adj.extend(users[&e].iter().filter(|&&g| g != f.id));
            }
        }
        info.adjacent = adj.into_iter().collect();
    }
    let (positions, triangles) = numbered(&positions, &triangles);
    Ok(Tessellation { positions, triangles, face_of_triangle, faces: infos, chordal_error_mm: chordal })
}

impl Tessellation {
    /// The tessellation of faces `ids` (in that order, each once), cut out of this one: the same
    /// as tessellating them alone, vertex for vertex (a face's facets depend only on the face and
    /// the samples of its edges, and the vertices are numbered by first use in both), so a file
    /// tessellated once serves every selection. Errors name an id that is not here.
    pub fn subset(&self, ids: &[u64]) -> Result<Tessellation, StepError> {
        let mut faces: Vec<FaceInfo> = Vec::new();
        for id in ids {
            let f = self
                .faces
                .iter()
                .find(|f| f.id == *id)
                .ok_or_else(|| StepError::UnknownFace { id: *id, faces: self.faces.iter().map(|f| f.id).collect() })?;
            if !faces.iter().any(|g| g.id == f.id) {
                faces.push(f.clone());
            }
        }
        // Each face's triangles are one run, in face order.
        let mut runs: BTreeMap<u64, (usize, usize)> = BTreeMap::new();
        for (i, &f) in self.face_of_triangle.iter().enumerate() {
            runs.entry(f).and_modify(|r| r.1 = i + 1).or_insert((i, i + 1));
        }
        let (mut triangles, mut face_of_triangle) = (Vec::new(), Vec::new());
        for f in &faces {
            let (a, b) = runs.get(&f.id).copied().unwrap_or((0, 0));
            triangles.extend_from_slice(&self.triangles[a..b]);
            face_of_triangle.resize(face_of_triangle.len() + (b - a), f.id);
        }
        let chordal_error_mm = faces.iter().map(|f| f.chordal_error_mm).fold(0.0, f64::max);
        let (positions, triangles) = numbered(&self.positions, &triangles);
        Ok(Tessellation { positions, triangles, face_of_triangle, faces, chordal_error_mm })
    }
}

/// `triangles` with their vertices renumbered by first use, and those vertices of `positions`
/// (unused ones dropped).
fn numbered(positions: &[DVec3], triangles: &[[u32; 3]]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut index = vec![u32::MAX; positions.len()];
    let mut out = Vec::new();
    let triangles = triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                let slot = &mut index[v as usize];
                if *slot == u32::MAX {
                    *slot = out.len() as u32;
                    out.push(positions[v as usize]);
                }
                *slot
            })
        })
        .collect();
    (out, triangles)
}

/// Appends the inner samples of the curve between parameters `t0` and `t1` to `out`, with
/// their parameters.
#[allow(clippy::too_many_arguments)]
fn subdivide(
    c: &dyn Fn(f64) -> DVec3,
    t0: f64,
    p0: DVec3,
    t1: f64,
    p1: DVec3,
    tol: f64,
    max_edge: f64,
    min_depth: usize,
    depth: usize,
    out: &mut Vec<(f64, DVec3)>,
) {
    let tm = 0.5 * (t0 + t1);
    let pm = c(tm);
    let chord = p1 - p0;
    let off = {
        let l2 = chord.length_squared();
        let s = if l2 > 0.0 { ((pm - p0).dot(chord) / l2).clamp(0.0, 1.0) } else { 0.0 };
        (pm - (p0 + chord * s)).length()
    };
    if depth < 24 && (depth < min_depth || off > tol || chord.length() > max_edge) {
        subdivide(c, t0, p0, tm, pm, tol, max_edge, min_depth, depth + 1, out);
        out.push((tm, pm));
        subdivide(c, tm, pm, t1, p1, tol, max_edge, min_depth, depth + 1, out);
    }
}

/// A face's triangles (local indices), its local-to-global vertex map for the boundary samples,
/// its domain, its chordal error, and its edge uses parameterised by a pcurve and those whose
/// pcurves lay off the edge (projected instead).
type FaceMesh = (Vec<[u32; 3]>, Vec<u32>, Domain, f64, [usize; 2]);

/// One face bound as the tessellator parameterises it: its samples round the loop (each once,
/// from the first edge's start), their surface parameters (angles unwrapped along the loop) and
/// the PCURVE each sample's parameters came from (`None`: projected onto the surface).
#[derive(Clone, Debug)]
pub struct BoundaryLoop {
    /// The bound's EDGE_LOOP id.
    pub id: u64,
    pub points: Vec<DVec3>,
    pub uv: Vec<DVec2>,
    pub pcurve: Vec<Option<u64>>,
    /// Edge uses parameterised by a pcurve.
    pub pcurve_edges: usize,
    /// Edge uses with pcurves on the face's surface, none of which lies on the edge's samples
    /// within the guard: projected instead.
    pub pcurves_off_surface: usize,
}

/// The boundary loops of face `face` as [`tessellate`] parameterises them (its edges sampled as
/// there): for tests and reports of which edges took their parameters from pcurves.
pub fn boundary(model: &Model, face: u64, o: &StepOptions) -> Result<Vec<BoundaryLoop>, StepError> {
    let faces = select(model, Some(&[face]))?;
    let max_edge = o.max_edge_mm.unwrap_or(diagonal(model) / 50.0);
    let samples = sample_edges(model, &faces, o.chordal_tol_mm, max_edge);
    let guard = PCURVE_GUARD * o.chordal_tol_mm;
    faces[0]
        .bounds
        .iter()
        .map(|b| {
            let (l, _) =
                loop_parameters(faces[0], b, &model.edges, (&samples.ids, &samples.params), &samples.positions, guard)?;
            Ok(l)
        })
        .collect()
}

/// The surface parameters of an edge's samples `points` (at the edge curve's file parameters
/// `ts`) from the pcurve `pc`: the pcurve at the same parameters when it shares the curve's
/// parameterisation (as CAD systems write it), else each sample located on it (nearest through
/// the surface, from the previous sample's parameter or a grid of a bounded pcurve). `None` when
/// some sample's pcurve point maps farther than `guard` from it.
fn pcurve_parameters(s: &Surface, pc: &Pcurve, ts: &[f64], points: &[DVec3], guard: f64) -> Option<Vec<DVec2>> {
    let off = |w: DVec2, p: DVec3| (s.point(w) - p).length();
    let same: Vec<DVec2> = ts.iter().map(|&t| pc.uv(t)).collect();
    if same.iter().zip(points).all(|(w, p)| off(*w, *p) <= guard) {
        return Some(same);
    }
    let clamp = |t: f64| match (&pc.curve, pc.range) {
        (Curve::BSpline(_), Some((a, b))) => t.clamp(a, b),
        _ => t,
    };
    // Gauss–Newton on |S(pc(t)) − p|².
    let locate = |p: DVec3, start: f64| -> (f64, f64) {
        let mut t = clamp(start);
        for _ in 0..30 {
            let w = pc.uv(t);
            let (x, su, sv) = s.eval(w);
            let d = pc.duv(t);
            let j = su * d.x + sv * d.y;
            let den = j.length_squared();
            if den.is_nan() || den <= 1e-300 {
                break;
            }
            let step = (x - p).dot(j) / den;
            t = clamp(t - step);
            if step.abs() <= 1e-14 * (1.0 + t.abs()) {
                break;
            }
        }
        (t, off(pc.uv(t), p))
    };
    let mut out = Vec::with_capacity(points.len());
    let mut prev: Option<f64> = None;
    for (&t, &p) in ts.iter().zip(points) {
        let mut best = locate(p, t);
        if let Some(q) = prev {
            let from_prev = locate(p, q);
            if from_prev.1 < best.1 {
                best = from_prev;
            }
        }
        if let (true, Some((a, b))) = (best.1 > guard, pc.range) {
            let n = 32;
            let start = (0..=n)
                .map(|k| a + (b - a) * k as f64 / n as f64)
                .min_by(|&x, &y| off(pc.uv(x), p).total_cmp(&off(pc.uv(y), p)))
                .unwrap_or(a);
            let from_grid = locate(p, start);
            if from_grid.1 < best.1 {
                best = from_grid;
            }
        }
        if best.1.is_nan() || best.1 > guard {
            return None;
        }
        prev = Some(best.0);
        out.push(pc.uv(best.0));
    }
    Some(out)
}

/// One edge use of a loop: the edge, its samples in the loop's direction, and the pcurves that
/// fit them (id, parameters of each sample).
type EdgeUse = (u64, Vec<u32>, Vec<(u64, Vec<DVec2>)>);

/// The edge samples of a face: ids and file parameters per edge (see [`EdgeSamples`]).
type Samples<'a> = (&'a BTreeMap<u64, Vec<u32>>, &'a BTreeMap<u64, Vec<f64>>);

/// The bound `b` of `f` parameterised (see [`BoundaryLoop`]), and its samples' global ids.
///
/// Each edge use takes its parameters from a pcurve of the edge on the face's surface when one
/// lies on the edge's samples (see [`pcurve_parameters`]); a seam edge has two, one per side,
/// and each of its uses takes the one that continues the neighbouring uses' parameters. Other
/// uses are projected onto the surface (closed form, or Newton from the previous sample).
fn loop_parameters(
    f: &Face,
    b: &Bound,
    edges: &BTreeMap<u64, Edge>,
    (edge_samples, edge_params): Samples,
    positions: &[DVec3],
    guard: f64,
) -> Result<(BoundaryLoop, Vec<u32>), StepError> {
    let s = &f.surface;
    let periodic = s.periodic();
    // Each use: its samples in the loop's direction and the pcurves that fit it.
    let mut uses: Vec<EdgeUse> = Vec::new();
    let mut off_surface = 0;
    for &(e, forward) in &b.edges {
        let mut list = edge_samples[&e].clone();
        let mut fits = Vec::new();
        let on_face: Vec<&Pcurve> = edges[&e].pcurves.iter().filter(|p| p.surface_id == f.surface_id).collect();
        if !on_face.is_empty() {
            let points: Vec<DVec3> = list.iter().map(|&g| positions[g as usize]).collect();
            for pc in on_face {
                if let Some(w) = pcurve_parameters(s, pc, &edge_params[&e], &points, guard) {
                    fits.push((pc.id, w));
                }
            }
            if fits.is_empty() {
                off_surface += 1;
            }
        }
        if !forward {
            list.reverse();
            fits.iter_mut().for_each(|f| f.1.reverse());
        }
        uses.push((e, list, fits));
    }
    // One pcurve per use: a seam's two by continuity with the neighbours' ends (unknown ends
    // count nothing; on a tie, the one the edge's other use did not take).
    let n = uses.len();
    let mut chosen: Vec<Option<usize>> = uses.iter().map(|u| (u.2.len() == 1).then_some(0)).collect();
    for k in 0..n {
        if uses[k].2.len() < 2 {
            continue;
        }
        let (kp, kn) = ((k + n - 1) % n, (k + 1) % n);
        let prev_end = chosen[kp].and_then(|c| uses[kp].2[c].1.last().copied());
        let next_start = chosen[kn].and_then(|c| uses[kn].2[c].1.first().copied());
        let taken: Vec<u64> = (0..n)
            .filter(|&j| j != k && uses[j].0 == uses[k].0)
            .filter_map(|j| chosen[j].map(|c| uses[j].2[c].0))
            .collect();
        let score = |(id, w): &(u64, Vec<DVec2>)| {
            let gap = prev_end.map_or(0.0, |p| (w[0] - p).length())
                + next_start.map_or(0.0, |q| (w[w.len() - 1] - q).length());
            (gap, taken.contains(id))
        };
        chosen[k] = (0..uses[k].2.len()).min_by(|&x, &y| {
            let (a, b) = (score(&uses[k].2[x]), score(&uses[k].2[y]));
            a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
        });
    }
    // The chain of global sample ids round the loop, each once, with their pcurve parameters.
    let mut chain: Vec<u32> = Vec::new();
    let mut from: Vec<Option<(u64, DVec2)>> = Vec::new();
    for (k, (e, list, fits)) in uses.iter().enumerate() {
        if let Some(&last) = chain.last() {
            if last != list[0] {
                return Err(StepError::Entity {
                    id: b.id,
                    message: format!("edge #{e} does not start where the previous edge of the loop ends"),
                });
            }
            chain.pop();
            from.pop();
        }
        let fit = chosen[k].map(|c| &fits[c]);
        for (i, &g) in list.iter().enumerate() {
            chain.push(g);
            from.push(fit.map(|(id, w)| (*id, w[i])));
        }
    }
    if chain.len() > 1 && chain.first() == chain.last() {
        chain.pop();
        from.pop();
    } else {
        return Err(StepError::Entity { id: b.id, message: "the loop is not closed".into() });
    }
    // Parameters, unwrapped along the loop.
    let mut uv = Vec::with_capacity(chain.len());
    let mut prev: Option<DVec2> = None;
    for (&g, src) in chain.iter().zip(&from) {
        let mut w = match src {
            Some((_, w)) => *w,
            None => s.invert(positions[g as usize], prev),
        };
        if let Some(p) = prev {
            for d in 0..2 {
                if periodic[d] {
                    w[d] = p[d] + num::wrap_pi(w[d] - p[d]);
                }
            }
        }
        prev = Some(w);
        uv.push(w);
    }
    let l = BoundaryLoop {
        id: b.id,
        points: chain.iter().map(|&g| positions[g as usize]).collect(),
        uv,
        pcurve: from.iter().map(|x| x.map(|x| x.0)).collect(),
        pcurve_edges: chosen.iter().filter(|c| c.is_some()).count(),
        pcurves_off_surface: off_surface,
    };
    Ok((l, chain))
}

#[allow(clippy::too_many_arguments)]
fn mesh_face(
    f: &Face,
    edges: &BTreeMap<u64, Edge>,
    samples: Samples,
    positions: &mut Vec<DVec3>,
    tol: f64,
    max_edge: f64,
    budget: usize,
) -> Result<FaceMesh, StepError> {
    let s = &f.surface;
    let periodic = s.periodic();
    let mut global: Vec<u32> = Vec::new();
    let mut uv: Vec<DVec2> = Vec::new();
    let mut loops: Vec<(bool, Vec<u32>)> = Vec::new();
    let mut winding: Vec<(u64, [i64; 2])> = Vec::new();
    let mut counts = [0usize; 2];
    for b in &f.bounds {
        let (l, chain) = loop_parameters(f, b, edges, samples, positions, PCURVE_GUARD * tol)?;
        counts[0] += l.pcurve_edges;
        counts[1] += l.pcurves_off_surface;
        let start = uv.len();
        uv.extend(&l.uv);
        global.extend(chain);
        // Turns round each periodic direction from the first sample back to itself.
        let (first, last) = (uv[start], uv[uv.len() - 1]);
        let mut turns = [0i64; 2];
        for d in 0..2 {
            if periodic[d] {
                turns[d] = ((last[d] - first[d] + num::wrap_pi(first[d] - last[d])) / TAU).round() as i64;
            }
        }
        loops.push((b.outer, (start as u32..uv.len() as u32).collect()));
        winding.push((b.id, turns));
    }
    // A cap round a pole (a sphere or cone face bounded by one loop winding round it and a
    // VERTEX_LOOP at the pole): a small circle round the pole becomes the band's second loop, and
    // the disc inside it a fan of triangles to the pole (see `pole_circle`).
    let mut pole_fan: Option<(DVec3, Vec<u32>)> = None;
    {
        let wound: Vec<usize> = (0..loops.len()).filter(|&k| winding[k].1 != [0, 0]).collect();
        if let ([k], [pole]) = (wound.as_slice(), f.vertex_loops.as_slice()) {
            let turns = winding[*k].1;
            let d = if turns[0] != 0 { 0 } else { 1 };
            if turns[d].abs() == 1 && turns[1 - d] == 0 {
                let sense = -turns[d] as f64;
                let ring =
                    pole_circle(s, *pole, &loops[*k].1, d, sense, &mut uv, &mut global, positions, tol, max_edge)
                        .ok_or_else(|| StepError::Entity {
                            id: f.id,
                            message: format!("the {} has no pole at its VERTEX_LOOP's point", s.kind()),
                        })?;
                pole_fan = Some((*pole, ring.clone()));
                let mut t = [0i64; 2];
                t[d] = -turns[d];
                loops.push((false, ring));
                winding.push((f.id, t));
            }
        }
    }
    // Loops that wind round the surface (Parasolid writes a cylinder band as two circles and no
    // seam): exactly two, once each in opposite senses round the same direction, are joined by a
    // synthetic seam into one outer loop; anything else is refused.
    let wound: Vec<usize> = (0..loops.len()).filter(|&k| winding[k].1 != [0, 0]).collect();
    if !wound.is_empty() {
        let (ka, kb) = (wound[0], *wound.last().unwrap_or(&wound[0]));
        let (ta, tb) = (winding[ka].1, winding[kb].1);
        let d = if ta[0] != 0 { 0 } else { 1 };
        if wound.len() != 2 || ta[1 - d] != 0 || tb[1 - d] != 0 || ta[d].abs() != 1 || tb[d] != -ta[d] {
            return Err(StepError::Entity {
                id: winding[ka].0,
                message: format!(
                    "the loop winds round the {} (only a band bounded by two loops winding once in opposite senses is supported)",
                    s.kind()
                ),
            });
        }
        let joined = join_wound_loops(
            s,
            &loops[ka].1,
            &loops[kb].1,
            d,
            ta[d] as f64,
            &mut uv,
            &mut global,
            positions,
            tol,
            max_edge,
        );
        let mut rest: Vec<(bool, Vec<u32>)> = vec![(true, joined)];
        rest.extend(loops.iter().enumerate().filter(|(k, _)| *k != ka && *k != kb).map(|(_, l)| (false, l.1.clone())));
        loops = rest;
    }
    // Scale the parameters to about millimetres (mean speeds over the domain's box).
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for w in &uv {
        lo = lo.min(*w);
        hi = hi.max(*w);
    }
    let mut speed = DVec2::ZERO;
    for i in 0..=4 {
        for j in 0..=4 {
            let w = lo + (hi - lo) * DVec2::new(i as f64, j as f64) / 4.0;
            let (_, su, sv) = s.eval(w);
            speed += DVec2::new(su.length(), sv.length()) / 25.0;
        }
    }
    let scale = DVec2::new(if speed.x > 1e-12 { speed.x } else { 1.0 }, if speed.y > 1e-12 { speed.y } else { 1.0 });
    let q: Vec<DVec2> = uv.iter().map(|w| *w * scale).collect();
    let signed = |l: &[u32]| -> f64 {
        (0..l.len()).map(|i| q[l[i] as usize].perp_dot(q[l[(i + 1) % l.len()] as usize])).sum::<f64>() * 0.5
    };
    // The outer loop: the one marked so, else the largest.
    let outer = match loops.iter().filter(|l| l.0).count() {
        1 => loops.iter().position(|l| l.0).unwrap_or(0),
        _ => (0..loops.len())
            .max_by(|&a, &b| signed(&loops[a].1).abs().total_cmp(&signed(&loops[b].1).abs()))
            .unwrap_or(0),
    };
    let mut outer_loop = loops[outer].1.clone();
    if signed(&outer_loop) < 0.0 {
        outer_loop.reverse();
    }
    let (ulo, uhi) = outer_loop
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| (a.min(uv[i as usize].x), b.max(uv[i as usize].x)));
    let mut holes = Vec::new();
    for (k, (_, l)) in loops.iter().enumerate() {
        if k == outer {
            continue;
        }
        // A hole of a periodic face may sit a turn away from the outer loop.
        if periodic[0] {
            let mean = l.iter().map(|&i| uv[i as usize].x).sum::<f64>() / l.len() as f64;
            let shift = TAU * ((0.5 * (ulo + uhi) - mean) / TAU).round();
            for &i in l {
                uv[i as usize].x += shift;
            }
        }
        let mut l = l.clone();
        let area: f64 =
            (0..l.len()).map(|i| (uv[l[i] as usize] * scale).perp_dot(uv[l[(i + 1) % l.len()] as usize] * scale)).sum();
        if area > 0.0 {
            l.reverse();
        }
        holes.push(l);
    }
    let q: Vec<DVec2> = uv.iter().map(|w| *w * scale).collect();
    let p: Vec<DVec3> = global.iter().map(|&g| positions[g as usize]).collect();
    let fail = |e: Failure| StepError::Tessellation {
        face: f.id,
        message: match e {
            Failure::NoEar => "its trimming loops cross or are degenerate in the surface's parameters".into(),
            Failure::NoBridge => "a hole cannot be joined to the outer loop (loops cross?)".into(),
            Failure::Budget => {
                format!(
                    "the tolerance is not reached within {} refinement rounds and {budget} triangles",
                    triangulate::ROUNDS
                )
            }
        },
    };
    let mut tris = triangulate::ear_clip(&q, &outer_loop, &holes).map_err(fail)?;
    let mut dom = Domain { q, uv, p, scale };
    let eval = |w: DVec2| {
        let (x, su, sv) = s.eval(w);
        (x, su.cross(sv).normalize_or_zero())
    };
    let err = triangulate::refine(&mut dom, &mut tris, tol, max_edge, budget, &eval).map_err(fail)?;
    if let Some((pole, ring)) = pole_fan {
        // The pole as a local vertex after the refinement's (the caller gives it a position), its
        // fan wound as the band's triangles are (counter-clockwise in the parameters: along
        // Su × Sv).
        let at = dom.p.len() as u32;
        dom.uv.push(dom.uv[ring[0] as usize]);
        dom.q.push(dom.q[ring[0] as usize]);
        dom.p.push(pole);
        for i in 0..ring.len() {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let n = (dom.p[a as usize] - pole).cross(dom.p[b as usize] - pole);
            let along = s.normal(dom.uv[a as usize]);
            tris.push(if n.dot(along) >= 0.0 { [at, a, b] } else { [at, b, a] });
        }
    }
    Ok((tris, global, dom, err, counts))
}

/// The circle round the pole `pole` of `s` (in direction 1 − `d`, the loop `cap` winding round
/// direction `d`) that a fan to the pole stands for within the tolerance: as far from the pole
/// as the fan's sag allows, at most `max_edge`; its samples (new positions) go round a full turn
/// in the sense `sense` (±1) as a loop of local indices, in the order they were made. `None`
/// when the surface does not shrink to `pole` there.
#[allow(clippy::too_many_arguments)]
fn pole_circle(
    s: &super::geom::Surface,
    pole: DVec3,
    cap: &[u32],
    d: usize,
    sense: f64,
    uv: &mut Vec<DVec2>,
    global: &mut Vec<u32>,
    positions: &mut Vec<DVec3>,
    tol: f64,
    max_edge: f64,
) -> Option<Vec<u32>> {
    let e = 1 - d;
    let vp = s.invert(pole, None)[e];
    let mean = cap.iter().map(|&i| uv[i as usize][e]).sum::<f64>() / cap.len() as f64;
    let at = |u: f64, v: f64| {
        let mut w = DVec2::ZERO;
        w[d] = u;
        w[e] = v;
        w
    };
    // The surface must shrink to the pole along every direction.
    if (0..8).any(|k| (s.point(at(k as f64 * TAU / 8.0, vp)) - pole).length() > tol) {
        return None;
    }
    // Halve the circle's distance from the pole until the fan's triangles lie within the
    // tolerance of the surface (their midpoints against the surface's) and are short enough.
    let mut dv = 0.5 * (mean - vp);
    for _ in 0..60 {
        let ok = (0..16).all(|k| {
            let u = k as f64 * TAU / 16.0;
            let (c, m) = (s.point(at(u, vp + dv)), s.point(at(u, vp + 0.5 * dv)));
            (c - pole).length() <= max_edge && (m - 0.5 * (c + pole)).length() <= 0.5 * tol
        });
        if ok {
            break;
        }
        dv *= 0.5;
    }
    let v = vp + dv;
    let u0 = uv[cap[0] as usize][d];
    let n = pieces(8, &|t| s.point(at(u0 + TAU * t, v)), tol, max_edge);
    Some(
        (0..n)
            .map(|i| {
                let w = at(u0 + sense * TAU * i as f64 / n as f64, v);
                positions.push(s.point(w));
                uv.push(w);
                global.push(positions.len() as u32 - 1);
                uv.len() as u32 - 1
            })
            .collect(),
    )
}

/// How many equal pieces of t ∈ [0, 1] (`start` doubled, at most 2¹²) the curve `at` needs for
/// its chords to be at most `max_edge` long and within half the tolerance of it at their middles.
fn pieces(start: usize, at: &dyn Fn(f64) -> DVec3, tol: f64, max_edge: f64) -> usize {
    let mut n = start;
    loop {
        let ok = (0..n).all(|i| {
            let (t0, t1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
            let (p0, p1, pm) = (at(t0), at(t1), at(0.5 * (t0 + t1)));
            (p1 - p0).length() <= max_edge && (pm - 0.5 * (p0 + p1)).length() <= 0.5 * tol
        });
        if ok || n >= 1 << 12 {
            return n;
        }
        n *= 2;
    }
}

/// Joins loop `a` and loop `b`, which wind round direction `d` of the surface `wa` (±1) and
/// −`wa` turns, into one polygon: `a`, a seam from `a`'s first sample to the sample of `b`
/// nearest it in `d`, `b` re-unwrapped from there, and the seam back. The seam's samples are
/// new positions used by both of its sides (so the mesh stays welded); its two copies of each
/// sample lie a turn apart in the parameters. Returns the polygon's local indices.
#[allow(clippy::too_many_arguments)]
fn join_wound_loops(
    s: &super::geom::Surface,
    a: &[u32],
    b: &[u32],
    d: usize,
    wa: f64,
    uv: &mut Vec<DVec2>,
    global: &mut Vec<u32>,
    positions: &mut Vec<DVec3>,
    tol: f64,
    max_edge: f64,
) -> Vec<u32> {
    let a0 = a[0] as usize;
    let ua = uv[a0][d];
    let k = (0..b.len())
        .min_by(|&i, &j| {
            num::wrap_pi(uv[b[i] as usize][d] - ua).abs().total_cmp(&num::wrap_pi(uv[b[j] as usize][d] - ua).abs())
        })
        .unwrap_or(0);
    // `b` from its sample k, unwrapped to start a turn (`wa`) from `a`'s first sample.
    let order: Vec<u32> = (0..b.len()).map(|i| b[(k + i) % b.len()]).collect();
    let mut prev = uv[order[0] as usize];
    prev[d] = ua + wa * TAU + num::wrap_pi(prev[d] - ua);
    let mut b_uv = vec![prev];
    for &i in &order[1..] {
        let mut w = uv[i as usize];
        w[d] = prev[d] + num::wrap_pi(w[d] - prev[d]);
        b_uv.push(w);
        prev = w;
    }
    for (&i, w) in order.iter().zip(&b_uv) {
        uv[i as usize] = *w;
    }
    // The seam: a straight segment in the parameters from a0 (a turn on) to b's start.
    let (mut from, to) = (uv[a0], b_uv[0]);
    from[d] += wa * TAU;
    let at = |t: f64| s.eval(from.lerp(to, t)).0;
    let n = pieces(1, &at, tol, max_edge);
    let seam: Vec<(DVec2, u32)> = (1..n)
        .map(|i| {
            let t = i as f64 / n as f64;
            positions.push(at(t));
            (from.lerp(to, t), positions.len() as u32 - 1)
        })
        .collect();
    let (ga0, gb0) = (global[a0], global[order[0] as usize]);
    let mut push = |w: DVec2, g: u32| -> u32 {
        uv.push(w);
        global.push(g);
        uv.len() as u32 - 1
    };
    let mut poly: Vec<u32> = a.to_vec();
    poly.push(push(from, ga0));
    for &(w, g) in &seam {
        poly.push(push(w, g));
    }
    poly.extend(&order);
    let mut b_end = b_uv[0];
    b_end[d] -= wa * TAU;
    poly.push(push(b_end, gb0));
    for &(w, g) in seam.iter().rev() {
        let mut w = w;
        w[d] -= wa * TAU;
        poly.push(push(w, g));
    }
    poly
}
