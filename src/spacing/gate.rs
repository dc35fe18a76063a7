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

use super::cutter::Cutter;
use super::Lift;
use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
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
/// ends, and a face of it with the two vertices' corners in it.
type GateEdge = ([u32; 2], [DVec3; 2], DVec2, DVec2, (u32, [u8; 2]));

/// Where a point was laid: a face and barycentric coordinates in it.
pub(super) type Site = (u32, [f64; 3]);

/// How a laid point gets its (|w|, arg w). Points are laid in the map's P1 image (`w`, log-polar),
/// which is the lift's image everywhere but in its pole star (see [`Gate::relabel`]). In a
/// spread field ([`Lift::spread`]) the P1 image of the warp is not the lift's anywhere, so each
/// point is labelled by the lift from the face it was laid in ([`Lift::image_of`]), exactly as
/// the lift places rings, and no point is located on the surface again to be labelled.
#[derive(Debug, Clone, Copy)]
pub(super) struct Labels<'l> {
    lift: Option<&'l Lift<'l>>,
    /// Whether the radius is wanted: [`Labels::angles`].
    radius: bool,
}

impl<'l> Labels<'l> {
    /// Labels by `lift` (a spread field's), or the P1 image's.
    pub(super) fn new(lift: Option<&'l Lift<'l>>) -> Self {
        Self { lift, radius: true }
    }

    /// These labels without the radius (the P1 image's is given): the angle alone, which the
    /// cusp search's steps use, costs no warp lookup.
    pub(super) fn angles(self) -> Self {
        Self { radius: false, ..self }
    }

    pub(super) fn is_spread(self) -> bool {
        self.lift.is_some()
    }

    pub(super) fn of(self, w: DVec2, (face, bary): Site) -> (f64, f64) {
        let Some(lift) = self.lift else { return (w.y, w.x) };
        if !self.radius {
            return (w.y, lift.angle_of(face as usize, bary));
        }
        lift.image_of(face as usize, bary)
    }
}

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
    /// In a spread field, how far the warp's P1 image may be from the labels in each face and
    /// along each edge (see [`Gate::uncut`]); empty otherwise.
    face_slack: Vec<f64>,
    edge_slack: Vec<f64>,
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
    /// `faces`: the facet tree of `surface`; `labels`: the spread field's lift, if `map` is one
    /// (see [`Labels`]).
    pub(super) fn new(
        surface: &'a Surface,
        map: &SlitMap,
        labels: Labels<'_>,
        faces: &'a FaceTree,
        radius_mm: f64,
        lift_h: Option<f64>,
    ) -> Self {
        let corners = map.log_polar_corners();
        // The hole-end points (a nearest-face search) beside the edges.
        let (tips, edges) = crate::par::join(
            || tip_points(surface, &corners, labels, faces, radius_mm, map),
            || edges_of(surface, map),
        );
        let rho_range: Vec<(f64, f64)> =
            corners.iter().map(|c| (c[0].y.min(c[1].y).min(c[2].y), c[0].y.max(c[1].y).max(c[2].y))).collect();
        let (face_slack, edge_slack) = match labels.lift {
            None => (Vec::new(), Vec::new()),
            Some(_) => crate::par::join(
                || crate::par::each(corners.len(), |f| face_slack(f as u32, corners[f], labels)),
                || crate::par::each(edges.len(), |e| edge_slack(&edges[e], labels)),
            ),
        };
        let padded = |range: (f64, f64), slack: Option<&f64>| {
            let pad = slack.map_or(0.0, |s| SLACK_FACTOR * s);
            (range.0 - pad, range.1 + pad)
        };
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
            || ByRadius::new(rho_range.iter().enumerate().map(|(f, &r)| padded(r, face_slack.get(f)))),
            || {
                ByRadius::new(
                    edges
                        .iter()
                        .enumerate()
                        .map(|(e, x)| padded((x.2.y.min(x.3.y), x.2.y.max(x.3.y)), edge_slack.get(e))),
                )
            },
        );
        Self {
            surface,
            faces,
            corners,
            face_slack,
            edge_slack,
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
    ///
    /// In a spread field (`labels`, see [`Labels`]) the points are laid in the warp's P1 image,
    /// which is not where the lift puts them: a band of the image is not the band of the rings.
    /// So each face and edge is laid over the band widened by [`SPREAD_PAD`] band widths and
    /// [`SLACK_FACTOR`] times its slack (how far its P1 image strays from the labels: a little
    /// where the warp is smooth, much where its P1 image folds or in the pole star), and only the
    /// points the lift puts in the band are tested.
    pub(super) fn uncut(&self, lo: f64, hi: f64, labels: Labels<'_>, cutter: &Cutter<'_>) -> Vec<GatePoint> {
        let spread = labels.is_spread();
        let pad = if spread { SPREAD_PAD * (hi - lo) } else { 0.0 };
        let (lay_lo, lay_hi) = (lo - pad, hi + pad);
        let widen = |slack: &[f64], i: usize| slack.get(i).map_or(0.0, |s| SLACK_FACTOR * s);
        let chunked = |items: Vec<usize>, f: &(dyn Fn(usize, &mut Vec<GatePoint>) + Sync)| {
            let chunks = items.len().div_ceil(CHUNK);
            crate::par::each(chunks, |c| {
                let mut out = Vec::new();
                for &i in &items[c * CHUNK..((c + 1) * CHUNK).min(items.len())] {
                    f(i, &mut out);
                }
                out.retain(|p| (!spread || (p.2 > lo && p.2 < hi)) && !cutter.cuts(p));
                out
            })
        };
        let faces = chunked(self.face_index.near(lay_lo, lay_hi).collect(), &|f, out| {
            let (r0, r1) = self.rho_range[f];
            let slack = widen(&self.face_slack, f);
            let (lay_lo, lay_hi) = (lay_lo - slack, lay_hi + slack);
            if r1 > lay_lo && r0 < lay_hi {
                self.face_lines(f, lay_lo, lay_hi, labels, out);
                self.face_crossings(f, (lay_lo, lay_hi), (lo, hi), labels, cutter, out);
            }
        });
        let edges = chunked(self.edge_index.near(lay_lo, lay_hi).collect(), &|e, out| {
            let ([a, b], normals, wa, wb, (face, [ca, cb])) = self.edges[e];
            // The part of the edge inside the band.
            let slack = widen(&self.edge_slack, e);
            let (u0, u1) = clip(wa.y, wb.y, lay_lo - slack, lay_hi + slack);
            if u1 > u0 {
                let ab = [a as usize, b as usize];
                let end = |u: f64| self.end(ab, normals, (wa, wb), (face, [ca as usize, cb as usize]), u);
                let (p, q) = (end(u0), end(u1));
                let first = out.len();
                line(p, q, EDGE_STEP * self.radius_mm, EDGE_MIN, labels, out);
                cutter.add_cusps(p, q, labels, (lo, hi), first, out);
            }
        });
        // The tips carry their exact labels (see `tip_points`).
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
    /// slit's chords, the gate compromised and left 1.38 h). (A spread field's points are
    /// labelled by the lift as they are laid, see [`Labels`].)
    pub(super) fn relabel(&self, p: &mut GatePoint, lift: &Lift<'_>) {
        if let Some(hit) = self.faces.nearest(p.0, self.radius_mm).filter(|hit| lift.in_pole_star(hit.face)) {
            (p.2, p.3) = lift.image_of(hit.face, hit.bary);
        }
    }

    /// The lines |w| = const of the band (`lo`, `hi`) across face `f`, a face of the band.
    fn face_lines(&self, f: usize, lo: f64, hi: f64, labels: Labels<'_>, out: &mut Vec<GatePoint>) {
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
                line(a, b, LINE_STEP * self.radius_mm, 2.0, labels, out);
            }
        }
    }

    /// Lines arg w = const across the band (`lo`, `hi`) inside face `f`, a face of the band,
    /// evenly over its angular extent (see [`CROSSINGS`]), with their cusps
    /// ([`Cutter::add_cusps`], in the rings' `band`): the ring pair's cusp inside a face, where
    /// the rings bend most (round the corner of an outer loop the map squeezes into one face),
    /// lies between the face's edges.
    fn face_crossings(
        &self,
        f: usize,
        (lo, hi): (f64, f64),
        band: (f64, f64),
        labels: Labels<'_>,
        cutter: &Cutter<'_>,
        out: &mut Vec<GatePoint>,
    ) {
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
                let end = |u: f64| (a.0.lerp(b.0, u), a.1.lerp(b.1, u), a.2.lerp(b.2, u), lerp_site(a.3, b.3, u));
                // Only the cusp: the line's fixed points would repeat the edges' and the levels'.
                let first = out.len();
                cutter.add_cusps(end(u0), end(u1), labels, band, first, out);
            }
        }
    }

    /// The ends of the line `coord(w) = level` across face `f` (`coord` picks arg w or |w| of
    /// its log-polar corners); `None` where the line misses the face.
    fn chord(&self, f: usize, level: f64, coord: impl Fn(DVec2) -> f64) -> Option<[End; 2]> {
        let (s, t, c) = (self.surface, &self.surface.triangles[f], self.corners[f]);
        let mut ends = [(DVec3::ZERO, DVec3::ZERO, DVec2::ZERO, (0, [0.0; 3])); 2];
        let mut found = 0;
        for e in 0..3 {
            let (i, j) = (e, (e + 1) % 3);
            let (ci, cj) = (coord(c[i]), coord(c[j]));
            if found < 2 && ((ci < level) != (cj < level)) {
                let u = (level - ci) / (cj - ci);
                let normals = [s.corner_normal(f, i), s.corner_normal(f, j)];
                ends[found] = self.end([t[i] as usize, t[j] as usize], normals, (c[i], c[j]), (f as u32, [i, j]), u);
                found += 1;
            }
        }
        (found == 2).then_some(ends)
    }

    /// The point at `u` along the edge from vertex `vi` to `vj` (images `wi`, `wj`), corners
    /// `ci`, `cj` of `face`.
    fn end(
        &self,
        [vi, vj]: [usize; 2],
        [ni, nj]: [DVec3; 2],
        (wi, wj): (DVec2, DVec2),
        (face, [ci, cj]): (u32, [usize; 2]),
        u: f64,
    ) -> End {
        let s = self.surface;
        let mut bary = [0.0; 3];
        bary[ci] += 1.0 - u;
        bary[cj] += u;
        (s.positions[vi].lerp(s.positions[vj], u), ni.lerp(nj, u), wi.lerp(wj, u), (face, bary))
    }
}

/// In a spread field each face and edge is laid over the band widened by this many band widths
/// on either side (see [`Gate::uncut`]) … Half a band width left gen039 of the sweep at 1.04 h
/// on fresh samples; one kept the 60 parts within the limits, as three did (which laid more than
/// twice the points). Before the points were labelled as they are laid, a uniform pad of one
/// band width left gen043 and gen056 at 1.02 and 1.05 h.
const SPREAD_PAD: f64 = 1.0;
/// … and this many times its slack ([`face_slack`], [`edge_slack`]).
const SLACK_FACTOR: f64 = 2.0;

/// How far the P1 image of face `f` (log-polar `corners`) strays from the labels at its
/// corners, its edges' middles and its centre (the corners too: in the pole star the P1 image
/// is not the lift's even there).
fn face_slack(f: u32, corners: [DVec2; 3], labels: Labels<'_>) -> f64 {
    super::facets::FACE_SAMPLES
        .iter()
        .map(|&b| {
            let w = corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2];
            (labels.of(w, (f, b)).0 - w.y).abs()
        })
        .fold(0.0, f64::max)
}

/// [`face_slack`] along an edge, at its ends and quarters.
fn edge_slack(&(_, _, wa, wb, (face, [ca, cb])): &GateEdge, labels: Labels<'_>) -> f64 {
    [0.0, 0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|&u| {
            let w = wa.lerp(wb, u);
            let mut bary = [0.0; 3];
            bary[ca as usize] += 1.0 - u;
            bary[cb as usize] += u;
            (labels.of(w, (face, bary)).0 - w.y).abs()
        })
        .fold(0.0, f64::max)
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

/// Faces or edges handed to one job of [`Gate::uncut`].
const CHUNK: usize = 256;

/// Points spaced at most `step` (at least `min`) along the segment between two ends, the middles
/// of equal pieces.
pub(super) fn line(a: End, b: End, step: f64, min: f64, labels: Labels<'_>, out: &mut Vec<GatePoint>) {
    let m = ((b.0 - a.0).length() / step).ceil().max(min) as usize;
    for i in 0..m {
        let u = (i as f64 + 0.5) / m as f64;
        out.push(at(a, b, u, labels));
    }
}

/// The site at `u` from `a` to `b`, both in one face.
fn lerp_site(a: Site, b: Site, u: f64) -> Site {
    (a.0, [0, 1, 2].map(|k| a.1[k] + (b.1[k] - a.1[k]) * u))
}

/// The point at `u` from `a` to `b`, labelled.
pub(super) fn at(a: End, b: End, u: f64, labels: Labels<'_>) -> GatePoint {
    let (rho, theta) = labels.of(a.2.lerp(b.2, u), lerp_site(a.3, b.3, u));
    (a.0.lerp(b.0, u), a.1.lerp(b.1, u).normalize_or_zero(), rho, theta)
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
            (e.0, normals(e), a, b, (e.1 as u32, e.2.map(|i| i as u8)))
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
    corners: &[[DVec2; 3]],
    labels: Labels<'_>,
    tree: &FaceTree,
    radius_mm: f64,
    map: &SlitMap,
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
            let (rho, theta) = labels.of(w, (hit.face as u32, hit.bary));
            out.push((hit.point, normal.normalize_or_zero(), rho, theta));
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

/// An end of a run of points: position, normal, (arg w, |w|), where it lies (see [`Labels`]).
pub(super) type End = (DVec3, DVec3, DVec2, Site);

/// The parameter range of the segment from |w| = `ra` to `rb` (linear) within (lo, hi).
fn clip(ra: f64, rb: f64, lo: f64, hi: f64) -> (f64, f64) {
    if ra == rb {
        return if ra > lo && ra < hi { (0.0, 1.0) } else { (1.0, 0.0) };
    }
    let (u_lo, u_hi) = ((lo - ra) / (rb - ra), (hi - ra) / (rb - ra));
    (u_lo.min(u_hi).max(0.0), u_lo.max(u_hi).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn a_spread_fields_gate_points_carry_the_lifts_labels_and_cover_its_band() {
        let (surface, map) = crate::plan::mapped_at_centroid(&crate::fixtures::plate_3_holes());
        let lift = Lift::new(&surface, &map);
        let options = crate::spread::SpreadOptions { radius_mm: 1.0, scallop_mm: 0.01, ..Default::default() };
        let spread = crate::spread::spread(&lift, &options).unwrap();
        let image = spread.image(&surface, &map);
        let lift = lift.spread(&image, spread);
        let faces = FaceTree::new(&surface.positions, &surface.triangles);
        let gate = Gate::new(&surface, &image, Labels::new(Some(&lift)), &faces, 1.0, None);
        // No rings: nothing is cut, every point of the band is returned.
        let (lo, hi) = (0.5, 0.56);
        let points = gate.uncut(lo, hi, Labels::new(Some(&lift)), &Cutter::new(&[], 1.0, 0.01));
        assert!(points.len() > 1000, "{} points", points.len());
        // Each labelled as the lift reads its place on the surface (a brute-force oracle: the
        // nearest face), and inside the band.
        for p in &points {
            assert!(p.2 > lo && p.2 < hi, "{p:?} outside the band");
            let hit = faces.nearest(p.0, 1.0).unwrap();
            let (rho, theta) = lift.image_of(hit.face, hit.bary);
            assert!(
                (rho - p.2).abs() < 1e-9 && (crate::num::rem_tau(theta - p.3 + PI) - PI).abs() < 1e-9,
                "{p:?}: {rho}"
            );
        }
        // The band covered: points of the surface the lift puts inside it have a gate point
        // within a few line steps (levels are at most an eighth of the band apart, points along
        // a level a quarter of R).
        let mut rng = crate::fixtures::SplitMix64(5);
        let mut inside = 0;
        while inside < 300 {
            let f = (rng.unit() * surface.triangles.len() as f64) as usize % surface.triangles.len();
            let (u, v) = (rng.unit(), rng.unit());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let bary = [1.0 - u - v, u, v];
            let rho = lift.image_of(f, bary).0;
            if !(rho > lo + 0.1 * (hi - lo) && rho < hi - 0.1 * (hi - lo)) {
                continue;
            }
            inside += 1;
            let q: DVec3 = (0..3).map(|k| surface.positions[surface.triangles[f][k] as usize] * bary[k]).sum();
            let gap = points.iter().map(|p| p.0.distance(q)).fold(f64::INFINITY, f64::min);
            assert!(gap < 0.3, "{q}: the nearest gate point {gap} mm away");
        }
    }
}
