//! The final gate of a ring: seed 000 Pseudocode A-1 tests samples of S^h, and this tests the
//! points of S^h where a band's scallop peaks between the meridians the bisection tested.
//!
//! The P1 map is linear in each face, so rings cross a face as parallel straight lines and bend
//! only where they cross an edge: the band's uncut spots sit beside those kinks, on creases
//! (where the scallop jumps), and where the image overlaps itself below a slit tip (a region the
//! rings skip), and round the ends of holes, where the rings turn. So the points tested are
//! points along every edge in the band, along lines |w| = const across every face of it (at
//! least seven, three with lifted balls, at most [`STRIP`]·R apart on the surface) and on fine
//! polar grids round each hole's ends and the outer loop's convex corners. A point is cut when
//! its S^h point lies within R of the ball-centre polyline of one of the two rings, so a gap the
//! meridians missed is found wherever it is (stop 18 measured such gaps at up to 1.3 h on the
//! shared meshes). With exact facets the polylines' centres are
//! moved out by the lift the spacing plans for each ball (see `cleared_lift_mm`).
//!
//! Points at fixed steps pass under the band's cusp, a V a few hundredths of a millimetre wide at
//! its top: on every edge crossing the band and on lines arg w = const across each of its faces
//! (at least [`CROSSINGS`] − 1, more on coarse faces), the cusp itself is located (where the two
//! rings are equally far) and tested too ([`Cutter::add_cusps`]). Issue 34's sweep found the
//! finish at 1.02–1.33 h on 11 of 200 coarse generated parts between the fixed points, beside
//! creases and round the corners of the outer loop, which the map squeezes into a face or two.

use super::{Lift, Segment};
use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use crate::num;
use crate::slitmap::SlitMap;
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// Lines of a band are at most this many R apart on the surface.
const STRIP: f64 = 0.25;
/// A band is split into at least this many strips by its lines. The scallop between two rings
/// peaks in a V along their cusp (its flanks slope by about √(2h/R)), so a level an eighth of
/// the band off the cusp passes up to h/2 below the peak, a sixteenth h/4: with 4 strips
/// halftunnel kept 1.05 h (smooth) between its meridians, with 8 0.98 h.
const MIN_STRIPS: f64 = 8.0;
/// With lifted balls the lifts are an estimate good to a few tenths of h, and finer levels did
/// not help (the shared meshes' largest scallops moved both ways): 4 strips.
const MIN_STRIPS_LIFTED: f64 = 4.0;
/// Points along a line are this many R apart, along an edge [`EDGE_STEP`] and at least
/// [`EDGE_MIN`] per edge.
const LINE_STEP: f64 = 0.25;
const EDGE_STEP: f64 = 1.0 / 16.0;
const EDGE_MIN: f64 = 4.0;

/// A point to test: surface point, unit normal, |w|, arg w.
pub(super) type GatePoint = (DVec3, DVec3, f64, f64);

/// An edge: its vertices, the normals at both ends (on one side), the log-polar image of both
/// ends.
type GateEdge = ([u32; 2], [DVec3; 2], DVec2, DVec2);

/// Where each band is tested, precomputed per map.
pub(super) struct Gate<'a> {
    surface: &'a Surface,
    /// The facet tree of `surface`: locates the points a ring must move up to (see
    /// [`Gate::relabel`]).
    faces: &'a FaceTree,
    /// Log-polar corners (arg w, |w|) per face.
    corners: Vec<[DVec2; 3]>,
    /// |w| range per face.
    rho_range: Vec<(f64, f64)>,
    /// |∇|w|| on each face (P1), 1/mm.
    rho_gradient: Vec<f64>,
    /// Every edge (vertex pair) with the normals at both ends and the log-polar image (arg w,
    /// |w|) of both ends, the second angle within π of the first; an edge on a crease where the
    /// normals split is there once per side.
    edges: Vec<GateEdge>,
    /// Points round the ends of every hole and the outer loop's corners (see [`tip_points`]),
    /// by |w|.
    tips: Vec<GatePoint>,
    /// Faces and edges by |w| (see [`ByRadius`]).
    face_index: ByRadius,
    edge_index: ByRadius,
    radius_mm: f64,
    /// The user's h when the balls' lift off the facets is planned for.
    lift_h: Option<f64>,
}

/// Items with a |w| range, for "which overlap (lo, hi)": the narrow ones sorted by their top,
/// so that those overlapping are a run of tops in (lo, hi + widest narrow span); the few wider
/// than [`WIDE`] (around the pole) are always looked at.
struct ByRadius {
    narrow: Vec<(f64, u32)>,
    span: f64,
    wide: Vec<u32>,
}

const WIDE: f64 = 0.02;

impl ByRadius {
    fn new(ranges: impl Iterator<Item = (f64, f64)>) -> Self {
        let (mut narrow, mut wide, mut span) = (Vec::new(), Vec::new(), 0.0f64);
        for (i, (lo, hi)) in ranges.enumerate() {
            if hi - lo > WIDE {
                wide.push(i as u32);
            } else {
                span = span.max(hi - lo);
                narrow.push((hi, i as u32));
            }
        }
        narrow.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        Self { narrow, span, wide }
    }

    /// Candidates for overlapping (lo, hi), each once.
    fn near(&self, lo: f64, hi: f64) -> impl Iterator<Item = usize> + '_ {
        let a = self.narrow.partition_point(|x| x.0 <= lo);
        let b = self.narrow.partition_point(|x| x.0 < hi + self.span);
        self.narrow[a..b.max(a)].iter().map(|x| x.1 as usize).chain(self.wide.iter().map(|&i| i as usize))
    }
}

impl<'a> Gate<'a> {
    /// `faces`: the facet tree of `surface`.
    pub(super) fn new(
        surface: &'a Surface,
        map: &SlitMap,
        faces: &'a FaceTree,
        radius_mm: f64,
        lift_h: Option<f64>,
    ) -> Self {
        let corners = map.log_polar_corners();
        // The hole-end points (a nearest-face search) beside the edges.
        let (tips, edges) =
            crate::par::join(|| tip_points(surface, map, &corners, faces, radius_mm), || edges_of(surface, map));
        let rho_range: Vec<(f64, f64)> =
            corners.iter().map(|c| (c[0].y.min(c[1].y).min(c[2].y), c[0].y.max(c[1].y).max(c[2].y))).collect();
        let rho_gradient = crate::par::each(corners.len(), |f| {
            let (t, c) = (surface.triangles[f], corners[f]);
            let [a, b, d] = t.map(|v| surface.positions[v as usize]);
            let (e1, e2) = (b - a, d - a);
            let n = e1.cross(e2);
            let area2 = n.length_squared();
            if !(area2 > 0.0) {
                return f64::INFINITY;
            }
            // ∇f = ((f1 − f0)(e2 × n) + (f2 − f0)(n × e1)) / |n|².
            let g = ((c[1].y - c[0].y) * e2.cross(n) + (c[2].y - c[0].y) * n.cross(e1)) / area2;
            g.length()
        });
        let (face_index, edge_index) = crate::par::join(
            || ByRadius::new(rho_range.iter().copied()),
            || ByRadius::new(edges.iter().map(|e| (e.2.y.min(e.3.y), e.2.y.max(e.3.y)))),
        );
        Self {
            surface,
            faces,
            corners,
            rho_range,
            rho_gradient,
            edges,
            tips,
            face_index,
            edge_index,
            radius_mm,
            lift_h,
        }
    }

    /// The points of the band between rings `lo` < `hi` where its scallop may peak, that
    /// `cutter` leaves uncut: lines |w| = const across every face, splitting the band into
    /// [`MIN_STRIPS`] strips ([`MIN_STRIPS_LIFTED`] with lifted balls) or more where it is wide on
    /// the surface (near a slit tip the map squeezes a wide region into a thin band), each at
    /// most [`STRIP`]·R wide; points along every edge within
    /// the band; and the band's points round the ends of holes. Made and tested in chunks on the
    /// pool (a band has thousands), kept in order: the same points on any number of threads.
    pub(super) fn uncut(&self, lo: f64, hi: f64, cutter: &Cutter<'_>) -> Vec<GatePoint> {
        let chunked = |items: Vec<usize>, f: &(dyn Fn(usize, &mut Vec<GatePoint>) + Sync)| {
            let chunks = items.len().div_ceil(CHUNK);
            crate::par::each(chunks, |c| {
                let mut out = Vec::new();
                for &i in &items[c * CHUNK..((c + 1) * CHUNK).min(items.len())] {
                    f(i, &mut out);
                }
                out.retain(|p| !cutter.cuts(p));
                out
            })
        };
        let faces = chunked(self.face_index.near(lo, hi).collect(), &|f, out| {
            let (r0, r1) = self.rho_range[f];
            if r1 > lo && r0 < hi {
                self.face_lines(f, lo, hi, out);
                self.face_crossings(f, lo, hi, cutter, out);
            }
        });
        let edges = chunked(self.edge_index.near(lo, hi).collect(), &|e, out| {
            let ([a, b], normals, wa, wb) = self.edges[e];
            // The part of the edge inside the band.
            let (u0, u1) = clip(wa.y, wb.y, lo, hi);
            if u1 > u0 {
                let ab = [a as usize, b as usize];
                let (p, q) = (self.end(ab, normals, wa, wb, u0), self.end(ab, normals, wa, wb, u1));
                let first = out.len();
                line(p, q, EDGE_STEP * self.radius_mm, EDGE_MIN, out);
                cutter.add_cusps(p, q, first, out);
            }
        });
        let first = self.tips.partition_point(|p| p.2 <= lo);
        let tips = &self.tips[first..];
        let tips = cutter.uncut(&tips[..tips.partition_point(|p| p.2 < hi)]);
        faces.into_iter().chain(edges).flatten().chain(tips).collect()
    }

    /// The facet tree of the surface.
    pub(super) fn faces(&self) -> &'a FaceTree {
        self.faces
    }

    /// `p` with the image (|w|, arg w) that `lift` sends to its place on the surface. The points
    /// are laid and labelled in the strip's P1 image, which the lift inverts everywhere but in
    /// its pole star (lifted through the w plane, see [`Lift::image_of`]): there a ring moved up
    /// to a point's strip radius could still pass a band away from it (gen017: 0.27 mm beside a
    /// slit's chords, the gate compromised and left 1.38 h). In a spread field
    /// ([`Lift::spread`]) the P1 image is not the lift's anywhere: every point is relabelled.
    pub(super) fn relabel(&self, p: &mut GatePoint, lift: &Lift<'_>) {
        if let Some(hit) =
            self.faces.nearest(p.0, self.radius_mm).filter(|hit| lift.is_spread() || lift.in_pole_star(hit.face))
        {
            (p.2, p.3) = lift.image_of(hit.face, hit.bary);
        }
    }

    /// The lines |w| = const of the band (`lo`, `hi`) across face `f`, a face of the band.
    fn face_lines(&self, f: usize, lo: f64, hi: f64, out: &mut Vec<GatePoint>) {
        let (r0, r1) = self.rho_range[f];
        let width = (hi - lo) / self.rho_gradient[f];
        let least = if self.lift_h.is_some() { MIN_STRIPS_LIFTED } else { MIN_STRIPS };
        let strips = (width / (STRIP * self.radius_mm)).clamp(least, 64.0).log2().ceil().exp2() as usize;
        for k in 1..strips {
            let level = hi - (hi - lo) * k as f64 / strips as f64;
            if !(level > r0 && level < r1) {
                continue;
            }
            if let Some([a, b]) = self.chord(f, level, |w| w.y) {
                line(a, b, LINE_STEP * self.radius_mm, 2.0, out);
            }
        }
    }

    /// Lines arg w = const across the band (`lo`, `hi`) inside face `f`, a face of the band,
    /// evenly over its angular extent (see [`CROSSINGS`]), with their cusps
    /// ([`Cutter::add_cusps`]): the ring pair's cusp inside a face, where the rings bend most
    /// (round the corner of an outer loop the map squeezes into one face), lies between the
    /// face's edges.
    fn face_crossings(&self, f: usize, lo: f64, hi: f64, cutter: &Cutter<'_>, out: &mut Vec<GatePoint>) {
        let c = self.corners[f];
        let (x0, x1) = (c[0].x.min(c[1].x).min(c[2].x), c[0].x.max(c[1].x).max(c[2].x));
        if !(x1 > x0) {
            return;
        }
        let t = self.surface.triangles[f].map(|v| self.surface.positions[v as usize]);
        let longest = t[0].distance(t[1]).max(t[1].distance(t[2])).max(t[2].distance(t[0]));
        let pieces = ((longest / (CROSSING_STEP * self.radius_mm)).ceil() as usize).clamp(CROSSINGS, MAX_CROSSINGS);
        for k in 1..pieces {
            let x = x0 + (x1 - x0) * k as f64 / pieces as f64;
            let Some([a, b]) = self.chord(f, x, |w| w.x) else { continue };
            let (u0, u1) = clip(a.2.y, b.2.y, lo, hi);
            if u1 > u0 {
                let end = |u: f64| (a.0.lerp(b.0, u), a.1.lerp(b.1, u), a.2.lerp(b.2, u));
                // Only the cusp: the line's fixed points would repeat the edges' and the levels'.
                let first = out.len();
                cutter.add_cusps(end(u0), end(u1), first, out);
            }
        }
    }

    /// The ends of the line `coord(w) = level` across face `f` (`coord` picks arg w or |w| of
    /// its log-polar corners); `None` where the line misses the face.
    fn chord(&self, f: usize, level: f64, coord: impl Fn(DVec2) -> f64) -> Option<[End; 2]> {
        let (s, t, c) = (self.surface, &self.surface.triangles[f], self.corners[f]);
        let mut ends = [(DVec3::ZERO, DVec3::ZERO, DVec2::ZERO); 2];
        let mut found = 0;
        for e in 0..3 {
            let (i, j) = (e, (e + 1) % 3);
            let (ci, cj) = (coord(c[i]), coord(c[j]));
            if found < 2 && ((ci < level) != (cj < level)) {
                let u = (level - ci) / (cj - ci);
                let normals = [s.corner_normal(f, i), s.corner_normal(f, j)];
                ends[found] = self.end([t[i] as usize, t[j] as usize], normals, c[i], c[j], u);
                found += 1;
            }
        }
        (found == 2).then_some(ends)
    }

    /// The point at `u` along the edge from vertex `vi` to `vj`.
    fn end(&self, [vi, vj]: [usize; 2], [ni, nj]: [DVec3; 2], wi: DVec2, wj: DVec2, u: f64) -> End {
        let s = self.surface;
        (s.positions[vi].lerp(s.positions[vj], u), ni.lerp(nj, u), wi.lerp(wj, u))
    }
}

/// Lines across each face of a band split its angular extent into at least `CROSSINGS` pieces,
/// and into pieces at most [`CROSSING_STEP`]·R wide on coarse faces (by the face's longest
/// edge). Each is only searched for its cusp. A fixed 4 per face kept gen104 of the sweep (a
/// delaunay mesh, normals tilted by 30°) at 0.96 h on 10⁶ samples, but left 8 of 200 sweep parts
/// (3k–12k faces) at 1.04–1.37 h on fresh samples; 8 per face took five of them under h, and the
/// 40k panel's spacing from 1.5 to 2.6 s, where its faces are a third of R across.
const CROSSINGS: usize = 4;
/// See [`CROSSINGS`]: a twelfth of R gives the sweep's coarse faces (about 0.7 R across) eight
/// pieces and the 40k panel's (0.33 R) four.
const CROSSING_STEP: f64 = 1.0 / 12.0;
/// At most this many pieces per face (a long sliver).
const MAX_CROSSINGS: usize = 24;

/// Segments searched on each side of a point's angle for the distances that locate a cusp: the
/// nearest centres of a point between two rings lie on its own meridian.
const CUSP_SEGMENTS: usize = 3;
// [`Cutter::side`]'s "cut" relies on the local test searching those segments too.
const _: () = assert!(CUSP_SEGMENTS <= LOCAL_SEGMENTS);

/// Regula falsi steps locating a cusp along an edge ([`Cutter::add_cusps`]).
const CUSP_STEPS: usize = 4;

/// Faces or edges handed to one job of [`Gate::uncut`].
const CHUNK: usize = 256;

/// Points spaced at most `step` (at least `min`) along the segment between two ends, the middles
/// of equal pieces.
fn line(a: End, b: End, step: f64, min: f64, out: &mut Vec<GatePoint>) {
    let m = ((b.0 - a.0).length() / step).ceil().max(min) as usize;
    for i in 0..m {
        let u = (i as f64 + 0.5) / m as f64;
        let w = a.2.lerp(b.2, u);
        out.push((a.0.lerp(b.0, u), a.1.lerp(b.1, u).normalize_or_zero(), w.y, w.x));
    }
}

/// Every edge of the surface with its corner normals and log-polar ends, once per side of an edge
/// where the normals split (the gate's `edges`).
fn edges_of(surface: &Surface, map: &SlitMap) -> Vec<GateEdge> {
    // (vertices, face, their corners in it), lower vertex first.
    let mut edges: Vec<([u32; 2], usize, [usize; 2])> = surface
        .triangles
        .iter()
        .enumerate()
        .flat_map(|(f, t)| {
            (0..3).map(move |k| {
                let ij = if t[k] < t[(k + 1) % 3] { [k, (k + 1) % 3] } else { [(k + 1) % 3, k] };
                (ij.map(|i| t[i]), f, ij)
            })
        })
        .collect();
    edges.sort_unstable();
    let normals = |&(_, f, ij): &([u32; 2], usize, [usize; 2])| ij.map(|i| surface.corner_normal(f, i));
    edges.dedup_by(|b, a| a.0 == b.0 && normals(a) == normals(b));
    edges
        .iter()
        .map(|e| {
            let (a, b) = super::features::strip_edge(map, e.0[0], e.0[1]);
            (e.0, normals(e), a, b)
        })
        .collect()
}

/// Points of the surface round each end of each hole (the boundary vertices at its slit's
/// ends) and round the sharpest convex corners of the outer loop, on polar grids in the tangent
/// plane projected onto the surface; sorted by |w|. The rings turn round a hole's end there and
/// leave spikes narrower than the edge and line points (featuretype: 1.42 h at 0.18 R from a
/// hole's corner, cut 2 µm away). The map squeezes a convex corner of the outer loop into a face
/// or two, where the band's uncut spot is a point the ring turning round the corner leaves, not a
/// cusp between two rings (issue 34's sweep, gen016: 1.12 h 0.74 mm from a rectangle's corner).
fn tip_points(
    surface: &Surface,
    map: &SlitMap,
    corners: &[[DVec2; 3]],
    tree: &FaceTree,
    radius_mm: f64,
) -> Vec<GatePoint> {
    let mut tips: Vec<u32> = Vec::new();
    for slit in &map.slits {
        let lp = &surface.loops[slit.hole];
        for end in [slit.theta_start, slit.theta_end] {
            let off = |v: &u32| {
                let w = map.w[*v as usize];
                let d = crate::num::atan2(w.y, w.x) - end;
                crate::num::rem_tau(d + PI) - PI
            };
            if let Some(&v) = lp.iter().min_by(|a, b| off(a).abs().total_cmp(&off(b).abs())) {
                tips.push(v);
            }
        }
    }
    let outer = outer_corners(surface);
    let grids: Vec<(u32, Grid)> =
        tips.iter().map(|&v| (v, TIP_GRID)).chain(outer.iter().map(|&v| (v, CORNER_GRID))).collect();
    let reach = 0.5 * radius_mm;
    // One job per anchor and grid ring, on the pool; in order, so the same points on any threads.
    let jobs: Vec<(u32, Grid, usize)> =
        grids.iter().flat_map(|&(v, g)| (1..=g.rings).map(move |i| (v, g, i))).collect();
    let per_ring = crate::par::each(jobs.len(), |job| {
        let (v, g, i) = jobs[job];
        let v = v as usize;
        let (p0, n0) = (surface.positions[v], surface.vertex_normals[v]);
        let e1 = n0.any_orthonormal_vector();
        let e2 = n0.cross(e1);
        let r = reach * i as f64 / g.rings as f64;
        let mut out = Vec::with_capacity(g.spokes);
        for j in 0..g.spokes {
            let (sin, cos) = crate::num::sin_cos(TAU * j as f64 / g.spokes as f64);
            let p = p0 + r * (cos * e1 + sin * e2);
            // Off the part (in the hole, past a steep wall): nothing to test.
            let Some(hit) = tree.nearest(p, 0.1 * r) else { continue };
            let mut normal = DVec3::ZERO;
            let mut w = DVec2::ZERO;
            for (k, (&b, &c)) in hit.bary.iter().zip(&corners[hit.face]).enumerate() {
                normal += b * surface.corner_normal(hit.face, k);
                w += b * c;
            }
            out.push((hit.point, normal.normalize_or_zero(), w.y, w.x));
        }
        out
    });
    let mut out: Vec<GatePoint> = per_ring.into_iter().flatten().collect();
    out.sort_by(|a, b| a.2.total_cmp(&b.2));
    out
}

/// A polar grid round a point: rings within R/2, spokes per ring.
#[derive(Debug, Clone, Copy)]
struct Grid {
    rings: usize,
    spokes: usize,
}

const TIP_GRID: Grid = Grid { rings: 48, spokes: 96 };
/// Coarser than a hole's end: at most [`MAX_CORNERS`] of them, and the spot is wider.
const CORNER_GRID: Grid = Grid { rings: 24, spokes: 48 };
/// The outer loop's vertices that turn by more than this (convex) get a grid.
const CORNER_TURN: f64 = PI / 6.0;
/// At most this many, the sharpest first (a scanned rim can turn at every vertex).
const MAX_CORNERS: usize = 256;

/// The outer loop's convex corners that turn by more than [`CORNER_TURN`] in the tangent plane,
/// the sharpest [`MAX_CORNERS`] (ties by vertex id, for determinism).
fn outer_corners(surface: &Surface) -> Vec<u32> {
    let Some(lp) = surface.loops.first() else { return Vec::new() };
    let n = lp.len();
    let mut found: Vec<(f64, u32)> = (0..n)
        .filter_map(|i| {
            let [a, b, c] = [lp[(i + n - 1) % n], lp[i], lp[(i + 1) % n]].map(|v| surface.positions[v as usize]);
            let normal = surface.vertex_normals[lp[i] as usize];
            let (u, v) = ((b - a).reject_from(normal), (c - b).reject_from(normal));
            let turn = crate::num::atan2(normal.dot(u.cross(v)), u.dot(v));
            (turn > CORNER_TURN).then_some((turn, lp[i]))
        })
        .collect();
    found.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    found.truncate(MAX_CORNERS);
    found.into_iter().map(|x| x.1).collect()
}

/// An end of a run of points: position, normal, (arg w, |w|).
type End = (DVec3, DVec3, DVec2);

/// The parameter range of the segment from |w| = `ra` to `rb` (linear) within (lo, hi).
fn clip(ra: f64, rb: f64, lo: f64, hi: f64) -> (f64, f64) {
    if ra == rb {
        return if ra > lo && ra < hi { (0.0, 1.0) } else { (1.0, 0.0) };
    }
    let (u_lo, u_hi) = ((lo - ra) / (rb - ra), (hi - ra) / (rb - ra));
    (u_lo.min(u_hi).max(0.0), u_lo.max(u_hi).min(1.0))
}

/// A ring's ball-centre polyline with the angle of each centre (ascending over [0, 2π]) and
/// its segments (see [`Segment`]).
#[derive(Debug, Clone)]
pub(super) struct RingLine {
    rho: f64,
    theta: Vec<f64>,
    centres: Vec<DVec3>,
    /// Segment k joins centres k and k + 1.
    segments: Vec<Segment>,
}

impl RingLine {
    pub(super) fn new(rho: f64) -> Self {
        Self { rho, theta: Vec::new(), centres: Vec::new(), segments: Vec::new() }
    }

    pub(super) fn push(&mut self, theta: f64, centre: DVec3) {
        if let Some(&last) = self.centres.last() {
            if last == centre {
                return;
            }
            self.segments.push(Segment::new(last, centre));
        }
        self.theta.push(theta);
        self.centres.push(centre);
    }

    /// Whether a segment within [`LOCAL_SEGMENTS`] of angle `theta` lies within `r` of `q`:
    /// the fast answer for a point of a band, whose nearest centres are almost always on its
    /// own meridian. `false` is not conclusive.
    fn near_theta_within(&self, q: DVec3, theta: f64, r: f64) -> bool {
        match self.find_near(theta, LOCAL_SEGMENTS, |s| s.dist2(q) <= r * r) {
            Some(found) => found,
            None => self.centres.first().is_some_and(|c| c.distance_squared(q) <= r * r),
        }
    }

    /// The squared distance from `q` to the segments within `window` of angle `theta`: the
    /// distance to the ring where its nearest centres are on the point's own meridian, as they
    /// almost always are (else an overestimate).
    fn near_dist2(&self, q: DVec3, theta: f64, window: usize, hint: &mut usize) -> f64 {
        let mut best = f64::INFINITY;
        let found = self.find_near_from(theta, window, hint, |s| {
            best = num::min(best, s.dist2(q));
            false
        });
        match found {
            Some(_) => best,
            None => self.centres.first().map_or(f64::INFINITY, |c| c.distance_squared(q)),
        }
    }

    /// Calls `f` on the segments within `window` of angle `theta`, outwards from it (where the
    /// nearest almost always is: its own, then one before and one after, …) until it returns
    /// `true`; whether it did. `None` for a ring of fewer than two centres.
    #[inline]
    fn find_near(&self, theta: f64, window: usize, f: impl FnMut(&Segment) -> bool) -> Option<bool> {
        let mut hint = usize::MAX;
        self.find_near_from(theta, window, &mut hint, f)
    }

    /// [`RingLine::find_near`], the segment at `theta` located from `hint` (the place of the
    /// previous angle of a run along a line, updated) when it is still right: the cusp search
    /// asks for a few nearby angles in turn, and this spares their binary searches.
    #[inline]
    fn find_near_from(
        &self,
        theta: f64,
        window: usize,
        hint: &mut usize,
        mut f: impl FnMut(&Segment) -> bool,
    ) -> Option<bool> {
        let n = self.centres.len();
        if n < 2 {
            return None;
        }
        let t = crate::num::rem_tau(theta);
        // The partition point of `x <= t`, the one k with θ[k − 1] ≤ t < θ[k]: the hint when
        // it is that k (the angles ascend, so the answer is the binary search's, bit for bit).
        let k = *hint;
        let fits = k <= n && (k == 0 || self.theta[k - 1] <= t) && (k == n || !(self.theta[k] <= t));
        let k = if fits { k } else { self.theta.partition_point(|&x| x <= t) };
        *hint = k;
        let i = k.clamp(1, n - 1) - 1;
        let m = self.segments.len();
        if i >= window && i + window < m {
            let s = &self.segments[i - window..=i + window];
            return Some(f(&s[window]) || (1..=window).any(|d| f(&s[window - d]) || f(&s[window + d])));
        }
        // The ring closes: centre n − 1 is centre 0, so segments wrap modulo n − 1.
        let at = |offset: isize| &self.segments[(i as isize + offset).rem_euclid(m as isize) as usize];
        Some(f(at(0)) || (1..=window as isize).any(|d| f(at(-d)) || f(at(d))))
    }
}

/// Segments searched on each side of a point's angle before the rings are searched whole.
const LOCAL_SEGMENTS: usize = 8;

/// Points the local search does not settle that are tested against every segment, before a grid
/// is built for the rest: on the 40k panel a cutter met 2.6 such points on average, and building
/// its grid took 25 times as long as testing one (and held up the other threads waiting for it).
const BRUTE_FORCE_POINTS: usize = 16;

/// Whether points of S^h (height `h_mm` over the surface) lie within `radius_mm` of a ball centre
/// on the rings' polylines.
pub(super) struct Cutter<'r> {
    rings: &'r [&'r RingLine],
    radius_mm: f64,
    h_mm: f64,
    /// Points the local search did not settle so far.
    unsettled: std::sync::atomic::AtomicUsize,
    /// Built by the first point the local search does not settle past [`BRUTE_FORCE_POINTS`].
    grid: std::sync::OnceLock<SegmentGrid>,
}

impl<'r> Cutter<'r> {
    pub(super) fn new(rings: &'r [&'r RingLine], radius_mm: f64, h_mm: f64) -> Self {
        Self { rings, radius_mm, h_mm, unsettled: Default::default(), grid: std::sync::OnceLock::new() }
    }

    fn cuts(&self, &(p, n, rho, theta): &GatePoint) -> bool {
        let q = p + n * self.h_mm;
        // The ring nearer in |w| first.
        let order = match self.rings {
            [a, b] if (b.rho - rho).abs() < (a.rho - rho).abs() => [Some(*b), Some(*a)],
            [a, b] => [Some(*a), Some(*b)],
            [a] => [Some(*a), None],
            _ => [None, None],
        };
        let r = self.radius_mm;
        order.into_iter().flatten().any(|ring| ring.near_theta_within(q, theta, r)) || self.any_within(q, r)
    }

    /// Whether any segment of the rings lies within `r` of `q`: the same answer from every
    /// segment in turn or from the grid, whichever is cheaper so far.
    fn any_within(&self, q: DVec3, r: f64) -> bool {
        if self.unsettled.fetch_add(1, std::sync::atomic::Ordering::Relaxed) < BRUTE_FORCE_POINTS {
            return self
                .rings
                .iter()
                .flat_map(|ring| segments(ring))
                .any(|(a, b)| super::segment_dist2(q, a, b) <= r * r);
        }
        self.grid.get_or_init(|| SegmentGrid::new(self.rings, r)).any_within(q, r)
    }

    /// Which of the two rings is nearer the point of S^h over `p` (positive: the second, the
    /// lower one), as a difference of distances, mm, and whether that point is cut (as
    /// [`Cutter::cuts`] would say: a segment found within R here is one that searches too);
    /// `None` without two rings. `hints` carry the rings' segments at the previous point of a
    /// run (see [`RingLine::find_near_from`]).
    fn side(&self, &(p, n, _, theta): &GatePoint, hints: &mut [usize; 2]) -> Option<(f64, bool)> {
        let [upper, lower] = self.rings else { return None };
        let q = p + n * self.h_mm;
        let (du2, dl2) = (
            upper.near_dist2(q, theta, CUSP_SEGMENTS, &mut hints[0]),
            lower.near_dist2(q, theta, CUSP_SEGMENTS, &mut hints[1]),
        );
        let r2 = self.radius_mm * self.radius_mm;
        Some((du2.sqrt() - dl2.sqrt(), du2 <= r2 || dl2 <= r2))
    }

    /// The cusps along the run of points `out[first..]` that [`line()`] laid from `a` to `b`:
    /// where the nearer ring changes between two of them, the point where both are equally far
    /// (regula falsi: along a line the difference of the two distances is nearly linear), added
    /// to `out`. The scallop peaks in a narrow V there (its flanks slope by about √(2h/R)):
    /// points a fixed step apart pass up to step·√(h/2R) under it, more than h on coarse
    /// meshes (issue 34's sweep: 1.1–1.3 h between the gate's points on 3k–12k-face parts).
    /// Points (laid or found) that the distances measured on the way show cut are dropped: the
    /// caller's test of each point ([`Cutter::cuts`]) would drop them, and those distances
    /// settle most of them.
    fn add_cusps(&self, a: End, b: End, first: usize, out: &mut Vec<GatePoint>) {
        if self.rings.len() != 2 {
            return;
        }
        let count = out.len() - first;
        let at = |u: f64| -> GatePoint {
            let w = a.2.lerp(b.2, u);
            let n = a.1.lerp(b.1, u).normalize_or_zero();
            (a.0.lerp(b.0, u), n, w.y, w.x)
        };
        // The points of `line` are the middles of `count` equal pieces; with the two ends (on
        // the band's rings where the edge crosses it whole) they bracket every cusp.
        let u_of = |i: usize| match i {
            0 => 0.0,
            i if i > count => 1.0,
            i => ((i - 1) as f64 + 0.5) / count as f64,
        };
        let laid = |out: &[GatePoint], i: usize| if i == 0 || i > count { at(u_of(i)) } else { out[first + i - 1] };
        let mut hints = [usize::MAX; 2];
        // Laid points not known to be cut are moved down to `kept` as their sides are measured
        // (reads run ahead of that); cusps found are pushed after the laid points meanwhile.
        let mut kept = first;
        let mut next = self.side(&laid(out, 0), &mut hints);
        for i in 0..count + 1 {
            let (this, after) = (next, self.side(&laid(out, i + 1), &mut hints));
            next = after;
            if i < count && !after.is_some_and(|(_, cut)| cut) {
                out[kept] = out[first + i];
                kept += 1;
            }
            let (Some((mut fa, _)), Some((mut fb, _))) = (this, after) else { continue };
            if (fa > 0.0) == (fb > 0.0) {
                continue;
            }
            let (mut ua, mut ub) = (u_of(i), u_of(i + 1));
            let mut best = None;
            // The search keeps its own hints: the next laid point's follow on from this one's.
            let mut search_hints = hints;
            for _ in 0..CUSP_STEPS {
                let u = if fb != fa { ua - fa * (ub - ua) / (fb - fa) } else { 0.5 * (ua + ub) };
                let u = u.clamp(ua.min(ub), ua.max(ub));
                let point = at(u);
                let Some((f, cut)) = self.side(&point, &mut search_hints) else { break };
                best = (!cut).then_some(point);
                if f == 0.0 {
                    break;
                }
                if (f > 0.0) == (fa > 0.0) {
                    (ua, fa) = (u, f);
                    fb *= 0.5; // Illinois: the end kept twice is halved
                } else {
                    (ub, fb) = (u, f);
                    fa *= 0.5;
                }
            }
            out.extend(best);
        }
        out.drain(kept..first + count);
    }

    /// The points of `points` no ball reaches.
    pub(super) fn uncut(&self, points: &[GatePoint]) -> Vec<GatePoint> {
        let cut = crate::par::each(points.len(), |i| self.cuts(&points[i]));
        points.iter().zip(cut).filter(|(_, c)| !c).map(|(p, _)| *p).collect()
    }
}

/// The segments of a ring's polyline (a lone centre as a segment of length 0).
fn segments(ring: &RingLine) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
    let c = &ring.centres;
    let lone = (c.len() == 1).then(|| (c[0], c[0]));
    lone.into_iter().chain(c.windows(2).map(|w| (w[0], w[1])))
}

/// Segments of polylines binned in a uniform grid (cells of the ball radius), for "is any
/// segment within R of q". Lookups only: the answer does not depend on the map's order.
struct SegmentGrid {
    cell: f64,
    segments: Vec<(DVec3, DVec3)>,
    bins: std::collections::HashMap<[i64; 3], Vec<u32>>,
}

impl SegmentGrid {
    fn new(rings: &[&RingLine], cell: f64) -> Self {
        let segments: Vec<(DVec3, DVec3)> = rings.iter().flat_map(|ring| segments(ring)).collect();
        let key = |p: DVec3| (p / cell).floor().as_i64vec3().to_array();
        let mut bins: std::collections::HashMap<[i64; 3], Vec<u32>> = std::collections::HashMap::new();
        for (i, &(a, b)) in segments.iter().enumerate() {
            let (lo, hi) = (key(a.min(b)), key(a.max(b)));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        bins.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        Self { cell, segments, bins }
    }

    fn any_within(&self, q: DVec3, r: f64) -> bool {
        let key = |p: DVec3| (p / self.cell).floor().as_i64vec3().to_array();
        let (lo, hi) = (key(q - DVec3::splat(r)), key(q + DVec3::splat(r)));
        let r2 = r * r;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let Some(bin) = self.bins.get(&[x, y, z]) else { continue };
                    for &i in bin {
                        let (a, b) = self.segments[i as usize];
                        if super::segment_dist2(q, a, b) <= r2 {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::SplitMix64;

    fn brute_force(rings: &[&RingLine], q: DVec3, r: f64) -> bool {
        rings.iter().any(|ring| ring.centres.windows(2).any(|w| super::super::segment_dist2(q, w[0], w[1]) <= r * r))
    }

    /// A wavy ring of `n` centres round the z axis, angles ascending over [0, 2π].
    fn ring(rho: f64, n: usize, rng: &mut SplitMix64) -> RingLine {
        let mut line = RingLine::new(rho);
        for i in 0..=n {
            let t = TAU * i as f64 / n as f64;
            let wobble = if i == n { 0.0 } else { 0.2 * rng.unit() };
            let radius = if i == n { line.centres[0].truncate().length() } else { 10.0 * rho + wobble };
            line.push(t, DVec3::new(radius * t.cos(), radius * t.sin(), 0.1 * (3.0 * t).sin()));
        }
        line
    }

    #[test]
    fn the_grid_and_the_local_search_agree_with_brute_force() {
        let mut rng = SplitMix64(0x6a7e);
        let rings = [ring(1.0, 300, &mut rng), ring(0.9, 250, &mut rng)];
        let refs: Vec<&RingLine> = rings.iter().collect();
        let r = 0.6;
        let grid = SegmentGrid::new(&refs, r);
        let (mut cut, mut local) = (0, 0);
        for _ in 0..20_000 {
            let (t, s) = (TAU * rng.unit(), 8.0 + 3.0 * rng.unit());
            let q = DVec3::new(s * t.cos(), s * t.sin(), 0.4 * (rng.unit() - 0.5));
            let exact = brute_force(&refs, q, r);
            assert_eq!(grid.any_within(q, r), exact, "grid at {q}");
            // The local search may miss a cover (it is not conclusive), never invent one.
            let near = refs.iter().any(|ring| ring.near_theta_within(q, t, r));
            assert!(!near || exact, "local search at {q}");
            cut += exact as usize;
            local += near as usize;
        }
        // Between the rings every cover is on the point's own meridian.
        assert!(cut > 1000 && local == cut, "cut {cut}, found locally {local}");
        // The cutter answers the same as brute force.
        let points: Vec<GatePoint> = (0..2000)
            .map(|_| {
                let (t, s) = (TAU * rng.unit(), 8.5 + 2.0 * rng.unit());
                (DVec3::new(s * t.cos(), s * t.sin(), 0.0), DVec3::Z, 0.0, t)
            })
            .collect();
        let h = 0.05;
        let bad = Cutter::new(&refs, r, h).uncut(&points);
        let expected: Vec<GatePoint> =
            points.iter().filter(|p| !brute_force(&refs, p.0 + p.1 * h, r)).copied().collect();
        assert_eq!(bad, expected);
    }

    #[test]
    fn clip_keeps_the_part_of_an_edge_inside_the_band() {
        assert_eq!(clip(0.0, 1.0, 0.25, 0.75), (0.25, 0.75));
        assert_eq!(clip(1.0, 0.0, 0.25, 0.75), (0.25, 0.75));
        assert_eq!(clip(0.3, 0.4, 0.25, 0.75), (0.0, 1.0));
        let (a, b) = clip(0.8, 0.9, 0.25, 0.75);
        assert!(a > b, "outside the band: empty");
        let (a, b) = clip(0.5, 0.5, 0.25, 0.75);
        assert!(a < b, "a level edge inside the band is kept");
    }

    #[test]
    fn the_cusp_along_a_line_is_where_the_two_rings_are_equally_far() {
        // Two concentric rings of ball centres (radii 10 and 9.2 mm, R 3 mm over the plane z = 0)
        // and a line across the band at angle 0.3, slightly tilted in z: the cusp found must be
        // the brute-force maximum of the nearer ring's distance.
        let r = 3.0;
        let circle = |radius: f64| {
            let mut line = RingLine::new(radius / 10.0);
            for i in 0..=720 {
                let t = TAU * i as f64 / 720.0;
                line.push(t, DVec3::new(radius * t.cos(), radius * t.sin(), r));
            }
            line
        };
        let (upper, lower) = (circle(10.0), circle(9.2));
        let refs = [&upper, &lower];
        let h = 0.01;
        let cutter = Cutter::new(&refs, r, h);
        let theta: f64 = 0.3;
        let (dir, n) = (DVec3::new(theta.cos(), theta.sin(), 0.0), DVec3::Z);
        let end = |s: f64, z: f64| (dir * s + DVec3::Z * z, n, DVec2::new(theta, s / 10.0));
        let (a, b) = (end(10.0, 0.0), end(9.2, 0.005));
        let mut out = Vec::new();
        line(a, b, 0.5, 4.0, &mut out);
        assert_eq!(out.len(), 4, "four points, none on the cusp");
        let laid = out.clone();
        cutter.add_cusps(a, b, 0, &mut out);
        // The two laid points nearest the rings are cut (the balls reach them) and dropped, the
        // two inner ones kept in order, and the cusp added after them.
        let uncut: Vec<GatePoint> = laid.iter().filter(|p| !cutter.cuts(p)).copied().collect();
        assert_eq!(uncut, [laid[1], laid[2]]);
        assert_eq!(out.len(), 3, "one cusp between the rings");
        assert_eq!(out[..2], uncut[..]);
        let gap = |p: &GatePoint| {
            let q = p.0 + p.1 * h;
            refs.iter().map(|ring| ring.near_dist2(q, p.3, LOCAL_SEGMENTS, &mut 0).sqrt()).fold(f64::INFINITY, f64::min)
                - r
        };
        let dense = (0..=20_000)
            .map(|i| {
                let u = i as f64 / 20_000.0;
                (a.0.lerp(b.0, u), n, 0.0, theta)
            })
            .map(|p| gap(&p))
            .fold(f64::NEG_INFINITY, f64::max);
        let found = gap(&out[2]);
        // The V's flanks slope by about 0.13, the brute force steps 4e-5 mm: it may fall short
        // of the peak by up to 3e-6 mm, never pass it.
        assert!(found >= dense - 1e-12 && found - dense < 5e-6, "cusp gap {found} mm, brute force {dense} mm");
        // The four evenly spaced points pass well under it.
        let sampled = laid.iter().map(gap).fold(f64::NEG_INFINITY, f64::max);
        assert!(dense - sampled > 1e-3, "sampled {sampled}, cusp {dense}");
    }
}
