//! Lifting points of the slit domain to the surface: the inverse map ω_SF⁻¹ of seed 000 §2.1
//! (point location, then barycentric interpolation of the 3D position and the vertex normals).
//!
//! Location is done in the log-polar strip (x = arg w, y = |w|, seed eq. 7), where the image of
//! every hole edge lies exactly on its slit's line y = R_j and the outer and inner circles are the
//! lines y = 1 and y = R_A. In the w plane those edges are chords that sag inside the circles, so a
//! ring running just below a slit could be located on the far side of the hole and jump across
//! it; in the strip the two sides of a slit never overlap. Near the pole of a disk map, where the
//! strip degenerates, location falls back to the w plane.

use crate::mesh::topology::vertex_faces;
use crate::mesh::Surface;
use crate::num;
use crate::slitmap::{barycentric, clamp_barycentric, SlitMap};
use crate::spread::Spread;
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// A point of the surface found from its slit-domain image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lifted {
    /// The image point asked for, in polar form: |w| and arg w (see [`Lifted::w`]).
    pub rho: f64,
    pub theta: f64,
    /// The surface point (cutter contact), millimetres.
    pub p: DVec3,
    /// Unit surface normal there (interpolated vertex normals), towards the tool.
    pub n: DVec3,
    /// The face the point lies on.
    pub face: u32,
}

impl Lifted {
    /// The image point asked for (computed on demand: most callers need only the surface point).
    pub fn w(&self) -> DVec2 {
        let (sin, cos) = num::sin_cos(self.theta);
        DVec2::new(self.rho * cos, self.rho * sin)
    }
}

/// The inverse slit map of one pole, ready for many queries.
#[derive(Debug, Clone)]
pub struct Lift<'a> {
    surface: &'a Surface,
    map: &'a SlitMap,
    /// Disk maps: the faces around the pole, lifted through the w plane (see [`PoleStar`]).
    star: Option<PoleStar>,
    /// Log-polar image triangles (see module docs), indexed for point location.
    strip: StripIndex,
    /// Log-polar corners per face (as in `strip`), for the neighbourhood search.
    corners: Vec<[DVec2; 3]>,
    /// Faces around each vertex (CSR): `vertex_faces[vertex_start[v]..vertex_start[v + 1]]`.
    vertex_start: Vec<u32>,
    vertex_faces: Vec<u32>,
    /// With [`Lift::spread`]: the map located in (`map` is then its image under the warp).
    base: &'a SlitMap,
    spread: Option<Spread>,
}

impl<'a> Lift<'a> {
    /// Precondition: `map` is a slit map of `surface` (see [`Lift::mismatch`]).
    pub fn new(surface: &'a Surface, map: &'a SlitMap) -> Self {
        let mut corners = map.log_polar_corners();
        let (vertex_start, vertex_faces) = vertex_faces(map.w.len(), map.triangles());
        let star = map.pole_face.map(|f| PoleStar::new(map, f, &corners, &vertex_start, &vertex_faces));
        // The star's faces are never located in the strip (near the pole their log-polar images
        // fold): NaN corners make every barycentric test of theirs fail.
        for &(f, _) in star.iter().flat_map(|s| &s.faces) {
            corners[f] = [DVec2::NAN; 3];
        }
        let strip = StripIndex::new(&corners);
        Self { surface, map, star, strip, corners, vertex_start, vertex_faces, base: map, spread: None }
    }

    /// This lift answering in the spread field ([`crate::spread`]): queries (|w'|, arg w) are
    /// moved along their ray by [`Spread::inverse`] and located in the map as before, so the
    /// warp is exact however sharply it turns; `image` ([`Spread::image`]) is what
    /// [`Lift::map`] returns from then on.
    pub fn spread(self, image: &'a SlitMap, spread: Spread) -> Self {
        Self { map: image, spread: Some(spread), ..self }
    }

    /// Whether queries are in a spread field ([`Lift::spread`]).
    pub fn is_spread(&self) -> bool {
        self.spread.is_some()
    }

    /// The map points are located in: [`Lift::map`], or the one it is the spread image of.
    pub fn base_map(&self) -> &'a SlitMap {
        self.base
    }

    /// The located map's radius of the query (|w'|, arg w).
    fn unspread(&self, rho: f64, theta: f64) -> f64 {
        self.spread.as_ref().map_or(rho, |s| s.inverse(theta, rho))
    }

    /// (map vertices, surface vertices) when `map` is not a slit map of `surface` (they differ
    /// in number): [`Lift::new`] would index out of bounds.
    pub fn mismatch(surface: &Surface, map: &SlitMap) -> Option<(usize, usize)> {
        (map.w.len() != surface.positions.len()).then_some((map.w.len(), surface.positions.len()))
    }

    /// The surface points are lifted to.
    pub fn surface(&self) -> &'a Surface {
        self.surface
    }

    /// The slit map it inverts.
    pub fn map(&self) -> &'a SlitMap {
        self.map
    }

    /// The surface point whose image is `w`.
    pub fn at(&self, w: DVec2) -> Option<Lifted> {
        self.polar(w.length(), num::arg(w))
    }

    /// The surface point whose image is `rho · e^{iθ}` (the nearest image triangle when it falls
    /// just outside the image, e.g. by rounding on the unit circle).
    pub fn polar(&self, rho: f64, theta: f64) -> Option<Lifted> {
        let located = self.polar_located(self.unspread(rho, theta), theta)?;
        Some(Lifted { rho, ..located })
    }

    /// [`Lift::polar`] in the located map's own radius.
    fn polar_located(&self, rho: f64, theta: f64) -> Option<Lifted> {
        if let Some(lifted) = self.in_star(rho, theta, false) {
            return Some(lifted);
        }
        let x = crate::num::rem_tau(theta + PI) - PI;
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        for shift in [0.0, TAU, -TAU] {
            if shift == 0.0 || self.strip.spans(x + shift) {
                self.strip.best(&self.corners, DVec2::new(x + shift, rho), &mut best);
            }
        }
        let (face, bary) = match best {
            Some((m, f, b)) if m >= -1e-10 => (f, b),
            _ => {
                // Not in the strip's triangles: the pole face's region, or just outside the image
                // (rounding at |w| = 1 or R_A): then the nearest face, clamped.
                if let Some(lifted) = self.in_star(rho, theta, true) {
                    return Some(lifted);
                }
                let (_, f, b) = best?;
                (f, clamp_barycentric(b))
            }
        };
        Some(self.lifted(rho, theta, face, bary))
    }

    /// Like [`Lift::polar`], but found by walking from face `near` (the previous point's face)
    /// towards the face containing the point: first across edges ([`Lift::edge_walk`]), then
    /// over faces that share a vertex, by score. Consecutive points of a curve then stay on
    /// neighbouring faces even where the P1 image folds over itself (slit tips): the lifted
    /// curve is continuous there instead of jumping to an overlapping face elsewhere. When both
    /// walks get stuck, [`Lift::polar`] (keeping the stuck face's nearest point instead made a
    /// 1 mm jump on plate_holes, where the walk was stopped by the pole star).
    pub fn polar_near(&self, rho: f64, theta: f64, near: u32) -> Option<Lifted> {
        let located = self.polar_near_located(self.unspread(rho, theta), theta, near)?;
        Some(Lifted { rho, ..located })
    }

    /// [`Lift::polar_near`] in the located map's own radius.
    fn polar_near_located(&self, rho: f64, theta: f64, near: u32) -> Option<Lifted> {
        if self.in_star(rho, theta, false).is_none() {
            let x = crate::num::rem_tau(theta + PI) - PI;
            let score = |f: usize| {
                let c = self.corners[f];
                // Unwrap the query into the face's frame.
                let qx = x + TAU * ((c[0].x - x) / TAU).round();
                let bary = barycentric(c[0], c[1], c[2], DVec2::new(qx, rho));
                let m = num::min(num::min(bary[0], bary[1]), bary[2]);
                (if m.is_finite() { m } else { f64::NEG_INFINITY }, bary)
            };
            if let Some((f, bary)) = self.edge_walk(near as usize, &score) {
                return Some(self.lifted(rho, theta, f, bary));
            }
            let mut f = near as usize;
            let (mut m, mut bary) = score(f);
            for _ in 0..256 {
                if m >= -1e-9 {
                    return Some(self.lifted(rho, theta, f, bary));
                }
                let mut next = None;
                for &v in &self.surface.triangles[f] {
                    let (a, b) = (self.vertex_start[v as usize] as usize, self.vertex_start[v as usize + 1] as usize);
                    for &g in &self.vertex_faces[a..b] {
                        let (mg, bg) = score(g as usize);
                        if mg > m && next.map_or(true, |(_, bm, _)| mg > bm) {
                            next = Some((g as usize, mg, bg));
                        }
                    }
                }
                match next {
                    Some((g, mg, bg)) => (f, m, bary) = (g, mg, bg),
                    None => break,
                }
            }
        }
        self.polar_located(rho, theta)
    }

    /// Walks from face `from` across the edge the query lies beyond (the corner with the most
    /// negative barycentric coordinate, `score` giving them) until a face contains it. Unlike
    /// the walk over neighbours by score, it crosses needles (a face 2 µm wide has barycentric
    /// coordinates of ±60 a hair outside it; sliver_mesh's columns stopped that walk). `None`
    /// when it leaves the surface, meets a face without a strip image or goes round in circles.
    fn edge_walk(&self, from: usize, score: &dyn Fn(usize) -> (f64, [f64; 3])) -> Option<(usize, [f64; 3])> {
        let mut f = from;
        let mut previous = usize::MAX;
        for _ in 0..64 {
            let (m, bary) = score(f);
            if m >= -1e-9 {
                return Some((f, bary));
            }
            if !m.is_finite() {
                return None;
            }
            let t = self.surface.triangles[f];
            // Corners by increasing coordinate: cross the edge opposite the most negative one
            // whose neighbour is not where we came from.
            let mut order = [0usize, 1, 2];
            order.sort_by(|&a, &b| bary[a].total_cmp(&bary[b]));
            let next = order
                .iter()
                .take_while(|&&k| bary[k] < 0.0)
                .filter_map(|&k| self.across(f, t[(k + 1) % 3], t[(k + 2) % 3]))
                .find(|&g| g != previous)?;
            (previous, f) = (f, next);
        }
        None
    }

    /// The face other than `f` on edge `a`–`b`.
    fn across(&self, f: usize, a: u32, b: u32) -> Option<usize> {
        let (s, e) = (self.vertex_start[a as usize] as usize, self.vertex_start[a as usize + 1] as usize);
        self.vertex_faces[s..e].iter().map(|&g| g as usize).find(|&g| g != f && self.surface.triangles[g].contains(&b))
    }

    /// The image point (|w|, arg w) this lift sends to barycentric `bary` of `face`: its own
    /// inverse. In the strip that is the P1 image; in the pole star it is not, as the star lifts
    /// through the w plane after a warp along each ray (see [`PoleStar`]), which near a slit's
    /// chords moves points by up to a band (gen017: 0.27 mm). Points located on the surface
    /// (the gate's) get the radius of the ring that runs through them from here.
    pub fn image_of(&self, face: usize, bary: [f64; 3]) -> (f64, f64) {
        let (rho, theta) = self.located_image_of(face, bary);
        (self.spread.as_ref().map_or(rho, |s| s.forward(theta, rho)), theta)
    }

    /// The angle of [`Lift::image_of`] (a spread keeps angles).
    pub fn angle_of(&self, face: usize, bary: [f64; 3]) -> f64 {
        self.located_image_of(face, bary).1
    }

    /// [`Lift::image_of`] in the located map.
    fn located_image_of(&self, face: usize, bary: [f64; 3]) -> (f64, f64) {
        if let Some(image) = self.star.as_ref().and_then(|star| star.image_of(face, bary)) {
            return image;
        }
        let c = self.corners[face];
        let at = |k: fn(DVec2) -> f64| bary[0] * k(c[0]) + bary[1] * k(c[1]) + bary[2] * k(c[2]);
        (at(|c| c.y), at(|c| c.x))
    }

    /// Whether `face` is lifted through the pole star (where [`Lift::image_of`] is not the
    /// strip's P1 image).
    pub fn in_pole_star(&self, face: usize) -> bool {
        self.star.as_ref().is_some_and(|star| star.faces.binary_search_by_key(&face, |f| f.0).is_ok())
    }

    /// The point lifted through the pole star when it lies in it (or, with `clamp`, the nearest
    /// point of the star: the strip located nothing).
    fn in_star(&self, rho: f64, theta: f64, clamp: bool) -> Option<Lifted> {
        let star = self.star.as_ref()?;
        let (face, bary) = star.locate(rho, theta, clamp)?;
        Some(self.lifted(rho, theta, face, bary))
    }

    /// The surface point at barycentric `bary` of `face`, for the image point `rho · e^{iθ}`.
    fn lifted(&self, rho: f64, theta: f64, face: usize, bary: [f64; 3]) -> Lifted {
        let s = self.surface;
        let vertices = s.triangles[face];
        let at = |values: &[DVec3]| {
            values[vertices[0] as usize] * bary[0]
                + values[vertices[1] as usize] * bary[1]
                + values[vertices[2] as usize] * bary[2]
        };
        let p = at(&s.positions);
        let n = s.normal_at(face, bary);
        Lifted { rho, theta, p, n, face: face as u32 }
    }
}

/// A face outside the pole star spanning more angle than this (radians) in the strip grows it.
const WIDE_FACE_RAD: f64 = 0.5;

/// The pole star grows by at most this many rings of faces.
const MAX_STAR_RINGS: usize = 6;

/// The faces of a disk map around its pole, where the log-polar strip degenerates (the pole
/// face's image is not a triangle, its neighbours' images may fold). They are lifted through
/// the w plane instead, but not as they stand: their union's rim is a polygon of chords there,
/// while the strip faces outside it end on the same edges drawn straight in the strip, and the
/// two would leave gaps and overlaps (a ring crossing the rim jumped 2 mm on a 2.5 mm grid). So
/// a query is first moved along its ray: the point at fraction s of the rim's strip radius in
/// its direction goes to fraction s of the rim chord's point with the same edge parameter. The
/// lift is then continuous across the rim and one-to-one inside (the rim is star-shaped about
/// the pole, checked on construction).
#[derive(Debug, Clone)]
struct PoleStar {
    /// Its faces with their w-plane corners.
    faces: Vec<(usize, [DVec2; 3])>,
    /// Its rim edges, counter-clockwise about the pole: (start angle, angular span in (0, π),
    /// start corner, end corner) with the corners in the w plane.
    rim: Vec<(f64, f64, DVec2, DVec2)>,
    /// Largest |w| on the rim: a point farther out is outside.
    reach: f64,
}

impl PoleStar {
    /// The pole face grown ring by ring (faces sharing a vertex) until no face just outside it
    /// is wide in the strip (spans more than [`WIDE_FACE_RAD`] of angle, or is folded), keeping
    /// the last growth whose rim is star-shaped about the pole. It may reach a boundary, not
    /// cross the nearest slit's radius: its rim runs along the loop's chords on the near side
    /// only, and the warp sends the strip's straight slit onto them (plate_holes' centroid pole
    /// lies inside a slit of radius 0.05, and the faces around it reached round that hole).
    fn new(
        map: &SlitMap,
        pole_face: usize,
        corners: &[[DVec2; 3]],
        vertex_start: &[u32],
        vertex_faces: &[u32],
    ) -> Self {
        let tris = map.triangles();
        // Never past the nearest slit: faces beyond it would wrap round the hole.
        let cap = map.slits.iter().map(|s| s.radius).fold(1.0, f64::min) * (1.0 + 1e-9);
        let below_cap = |g: usize| tris[g].iter().all(|&v| map.w[v as usize].length() <= cap);
        let grow = |faces: &[usize]| {
            let mut out: Vec<usize> = faces.to_vec();
            for &f in faces {
                for &v in &tris[f] {
                    let (a, b) = (vertex_start[v as usize] as usize, vertex_start[v as usize + 1] as usize);
                    out.extend(vertex_faces[a..b].iter().map(|&g| g as usize).filter(|&g| below_cap(g)));
                }
            }
            out.sort_unstable();
            out.dedup();
            out
        };
        let wide = |f: usize| {
            let c = &corners[f];
            let span = c[0].x.max(c[1].x).max(c[2].x) - c[0].x.min(c[1].x).min(c[2].x);
            span > WIDE_FACE_RAD || (c[1] - c[0]).perp_dot(c[2] - c[0]) >= 0.0
        };
        let mut faces = vec![pole_face];
        let mut best = Self::of(map, &faces);
        let mut next = grow(&faces);
        for _ in 0..MAX_STAR_RINGS {
            faces = next;
            next = grow(&faces);
            if let Some(star) = Self::of(map, &faces) {
                best = Some(star);
                if !next.iter().any(|&g| faces.binary_search(&g).is_err() && wide(g)) {
                    break;
                }
            }
        }
        best.unwrap_or_else(|| {
            // The pole outside its own face's image (rounding): no rim, plain w-plane location.
            let faces = vec![(pole_face, tris[pole_face].map(|v| map.w[v as usize]))];
            let reach = faces[0].1.iter().map(|w| w.length()).fold(0.0, f64::max);
            Self { faces, rim: Vec::new(), reach }
        })
    }

    fn of(map: &SlitMap, faces: &[usize]) -> Option<Self> {
        let tris = map.triangles();
        let mut edges: Vec<(u32, u32)> =
            faces.iter().flat_map(|&f| (0..3).map(move |k| (tris[f][k], tris[f][(k + 1) % 3]))).collect();
        edges.sort_unstable();
        // A rim edge is one whose reverse is not an edge of the star.
        let rim_edges: Vec<(u32, u32)> =
            edges.iter().copied().filter(|&(a, b)| edges.binary_search(&(b, a)).is_err()).collect();
        let mut rim = Vec::with_capacity(rim_edges.len());
        for (a, b) in rim_edges {
            let (wa, wb) = (map.w[a as usize], map.w[b as usize]);
            let (ta, tb) = (num::arg(wa), num::arg(wb));
            let span = crate::num::rem_tau(tb - ta);
            if !(span > 1e-12 && span < PI && wa.perp_dot(wb) > 0.0) {
                return None;
            }
            rim.push((ta, span, wa, wb));
        }
        let total: f64 = rim.iter().map(|e| e.1).sum();
        if (total - TAU).abs() > 1e-9 {
            return None; // winds more than once, or leaves gaps: not star-shaped
        }
        rim.sort_by(|x, y| x.0.total_cmp(&y.0));
        // Sorted by face (`faces` is): [`PoleStar::image_of`] searches them.
        let faces = faces.iter().map(|&f| (f, tris[f].map(|v| map.w[v as usize]))).collect();
        let reach = rim.iter().map(|e| e.2.length()).fold(0.0, f64::max);
        Some(Self { faces, rim, reach })
    }

    /// The inverse of [`PoleStar::locate`] (unclamped): (|w|, arg w) of the query that lands on
    /// barycentric `bary` of `face`, when that is a face of the star. The point's w-plane image
    /// lies on the ray through the rim chord's point at fraction t of rim edge (wa, wb); the query
    /// had angle ta + t·span and radius s·(|wa| + t(|wb| − |wa|)), s its fraction of that point.
    fn image_of(&self, face: usize, bary: [f64; 3]) -> Option<(f64, f64)> {
        let i = self.faces.binary_search_by_key(&face, |f| f.0).ok()?;
        let c = self.faces[i].1;
        let w = c[0] * bary[0] + c[1] * bary[1] + c[2] * bary[2];
        if self.rim.is_empty() {
            return Some((w.length(), num::arg(w)));
        }
        let theta = num::arg(w);
        let &(ta, span, wa, wb) =
            self.rim.iter().find(|e| crate::num::rem_tau(theta - e.0) < e.1).unwrap_or_else(|| {
                self.rim.iter().min_by(|x, y| gap(theta, x).total_cmp(&gap(theta, y))).expect("a rim")
            });
        // The ray through w meets the chord at t: w × (wa + t(wb − wa)) = 0.
        let den = w.perp_dot(wb - wa);
        let t = if den != 0.0 { (-w.perp_dot(wa) / den).clamp(0.0, 1.0) } else { 0.0 };
        let chord = wa + t * (wb - wa);
        let s = w.length() / chord.length();
        let rim_rho = wa.length() + t * (wb.length() - wa.length());
        Some((s * rim_rho, crate::num::rem_tau(ta + t * span + PI) - PI))
    }

    /// Face and barycentric coordinates of the point `rho · e^{iθ}` when it lies in the star
    /// (with `clamp`, up to half as far again outside it, pulled onto the rim).
    fn locate(&self, rho: f64, theta: f64, clamp: bool) -> Option<(usize, [f64; 3])> {
        let limit = if clamp { 1.5 } else { 1.0 + 1e-12 };
        if !(rho <= self.reach * limit) {
            return None;
        }
        let (sin, cos) = num::sin_cos(theta);
        let q = if self.rim.is_empty() {
            DVec2::new(rho * cos, rho * sin)
        } else {
            let &(ta, span, wa, wb) =
                self.rim.iter().find(|e| crate::num::rem_tau(theta - e.0) < e.1).unwrap_or_else(|| {
                    self.rim.iter().min_by(|x, y| gap(theta, x).total_cmp(&gap(theta, y))).expect("a rim")
                });
            let t = (crate::num::rem_tau(theta - ta) / span).min(1.0);
            let rim_rho = wa.length() + t * (wb.length() - wa.length());
            let s = rho / rim_rho;
            if !(s <= limit) {
                return None;
            }
            (wa + t * (wb - wa)) * s.min(1.0)
        };
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        for &(f, c) in &self.faces {
            let b = barycentric(c[0], c[1], c[2], q);
            let m = num::min(num::min(b[0], b[1]), b[2]);
            if m.is_finite() && best.map_or(true, |(bm, _, _)| m > bm) {
                best = Some((m, f, b));
            }
        }
        let (m, f, b) = best?;
        if self.rim.is_empty() && m < if clamp { -0.5 } else { -1e-12 } {
            return None;
        }
        Some((f, if m >= 0.0 { b } else { clamp_barycentric(b) }))
    }
}

/// Angle from the end of rim edge `e` round to `theta` (rounding can leave `theta` just past
/// the last edge).
fn gap(theta: f64, e: &(f64, f64, DVec2, DVec2)) -> f64 {
    (crate::num::rem_tau(theta - e.0) - e.1).abs()
}

/// Point location in the log-polar strip. The faces crowd towards some radii (a ring band can
/// hold most of them), so the grid's rows are equal-count radius quantiles rather than equal
/// widths; columns are uniform in angle over (−2π, 2π) (per-face unwrapping may leave (−π, π]).
#[derive(Debug, Clone)]
struct StripIndex {
    /// Row boundaries in y (|w|), increasing; row k is `[rows[k], rows[k + 1])`.
    rows: Vec<f64>,
    /// Uniform bins over the finite row boundaries, (lower edge, bins per unit of y), and the
    /// row of each bin's lower edge: a row is found by a step or two instead of a binary search.
    row_bins: (f64, f64),
    row_of_bin: Vec<u32>,
    nx: usize,
    /// First and last column holding a face: a query shifted by 2π outside them finds none.
    cols: (usize, usize),
    cell_start: Vec<u32>,
    cell_faces: Vec<u32>,
}

impl StripIndex {
    const X0: f64 = -TAU;
    const XSPAN: f64 = 2.0 * TAU;

    fn new(corners: &[[DVec2; 3]]) -> Self {
        let f = corners.len().max(1);
        // About four cells per face over (−π, π] (the columns span twice that): a query's cell
        // then lists a few faces (8 per non-empty cell at one cell per face on the 40k panel).
        let ny = 2 * ((f as f64).sqrt().ceil() as usize).max(1);
        let nx = (f.div_ceil(ny) * 8).max(1);
        let mut ys: Vec<f64> = corners.iter().map(|c| (c[0].y + c[1].y + c[2].y) / 3.0).collect();
        ys.sort_by(f64::total_cmp);
        let mut rows: Vec<f64> = (0..=ny).map(|k| ys[((k * ys.len()) / ny).min(ys.len() - 1)]).collect();
        rows[0] = f64::NEG_INFINITY;
        rows[ny] = f64::INFINITY;
        rows.dedup();
        let ny = rows.len() - 1;
        let (y0, y1) = (rows[1.min(ny)], rows[ny.saturating_sub(1)]);
        let bins = 4 * ny;
        let scale = if y1 > y0 && y0.is_finite() && y1.is_finite() { bins as f64 / (y1 - y0) } else { 0.0 };
        let row_of_bin = if scale > 0.0 {
            (0..bins)
                .map(|k| {
                    let y = y0 + k as f64 / scale;
                    rows.partition_point(|&r| r <= y).saturating_sub(1) as u32
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut index = Self {
            rows,
            row_bins: (y0, scale),
            row_of_bin,
            nx,
            cols: (0, nx - 1),
            cell_start: vec![0; nx * ny + 1],
            cell_faces: Vec::new(),
        };
        let ranges: Vec<(usize, usize, usize, usize)> = corners.iter().map(|c| index.cell_range(c)).collect();
        // (Faces without a strip image, NaN corners, sit in column 0 and match nothing.)
        index.cols = ranges
            .iter()
            .zip(corners)
            .filter(|(_, c)| c[0].x.is_finite())
            .fold((nx - 1, 0), |(lo, hi), (r, _)| (lo.min(r.0), hi.max(r.1)));
        for &(x0, x1, y0, y1) in &ranges {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    index.cell_start[y * nx + x + 1] += 1;
                }
            }
        }
        for k in 0..nx * ny {
            index.cell_start[k + 1] += index.cell_start[k];
        }
        let mut fill = index.cell_start.clone();
        index.cell_faces = vec![0; index.cell_start[nx * ny] as usize];
        for (face, &(x0, x1, y0, y1)) in ranges.iter().enumerate() {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * nx + x;
                    index.cell_faces[fill[c] as usize] = face as u32;
                    fill[c] += 1;
                }
            }
        }
        index
    }

    /// Whether the column of `x` may hold a face (the columns outside [`StripIndex::cols`] are
    /// empty).
    fn spans(&self, x: f64) -> bool {
        let c = self.col(x);
        c >= self.cols.0 && c <= self.cols.1
    }

    fn row(&self, y: f64) -> usize {
        let last = self.rows.len() - 2;
        let (y0, scale) = self.row_bins;
        let k = (y - y0) * scale;
        if !(k >= 0.0 && k < self.row_of_bin.len() as f64) {
            return self.rows.partition_point(|&r| r <= y).saturating_sub(1).min(last);
        }
        // The bin gives the row of its lower edge: step from there to the last row boundary at
        // or below y (down as well, should rounding have put y just under that edge).
        let mut r = self.row_of_bin[k as usize] as usize;
        while r + 1 < self.rows.len() && self.rows[r + 1] <= y {
            r += 1;
        }
        while r > 0 && self.rows[r] > y {
            r -= 1;
        }
        r.min(last)
    }

    fn col(&self, x: f64) -> usize {
        // A saturating cast: negatives (and NaN) give 0, as floor then max(0) did, and truncation
        // is the floor of the rest, without a libm call.
        ((((x - Self::X0) / Self::XSPAN) * self.nx as f64) as usize).min(self.nx - 1)
    }

    fn cell_range(&self, c: &[DVec2; 3]) -> (usize, usize, usize, usize) {
        let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        (self.col(lo.x), self.col(hi.x), self.row(lo.y), self.row(hi.y))
    }

    /// Updates `best` (largest minimum barycentric coordinate) with the faces of q's cell.
    fn best(&self, corners: &[[DVec2; 3]], q: DVec2, best: &mut Option<(f64, usize, [f64; 3])>) {
        if !(q.x >= Self::X0 && q.x <= Self::X0 + Self::XSPAN) {
            return;
        }
        let c = self.row(q.y) * self.nx + self.col(q.x);
        for &f in &self.cell_faces[self.cell_start[c] as usize..self.cell_start[c + 1] as usize] {
            let t = corners[f as usize];
            if best.is_some_and(|(bm, _, _)| bm >= 0.0) && surely_outside(t, q) {
                continue; // cannot beat a face that contains q: skip the divisions
            }
            let bary = barycentric(t[0], t[1], t[2], q);
            let m = num::min(num::min(bary[0], bary[1]), bary[2]);
            if m.is_finite() && best.map_or(true, |(bm, _, _)| m > bm) {
                *best = Some((m, f as usize, bary));
            }
        }
    }
}

/// Whether `q` lies clearly outside the triangle `t` (some barycentric coordinate below −1e-9),
/// decided without dividing: then its smallest coordinate is negative.
fn surely_outside(t: [DVec2; 3], q: DVec2) -> bool {
    let d = (t[1] - t[0]).perp_dot(t[2] - t[0]);
    let x1 = (q - t[0]).perp_dot(t[2] - t[0]);
    let x2 = (t[1] - t[0]).perp_dot(q - t[0]);
    let eps = 1e-9 * d.abs();
    let s = d.signum();
    s * x1 < -eps || s * x2 < -eps || s * (d - x1 - x2) < -eps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The planner's surface of a fixture and its slit map at the centroid pole.
    fn mapped(name: &str) -> (Surface, SlitMap) {
        crate::plan::mapped_at_centroid(&crate::fixtures::by_name(name).expect("a fixture"))
    }

    /// Lifts the circle |w| = rho at `n` angles, each from the previous point's face, and returns
    /// the largest step on the surface, mm.
    fn largest_step(lift: &Lift<'_>, rho: f64, n: usize) -> f64 {
        let mut previous: Option<Lifted> = None;
        let mut largest: f64 = 0.0;
        for k in 0..=n {
            let theta = TAU * k as f64 / n as f64;
            let l = match previous {
                Some(p) => lift.polar_near(rho, theta, p.face),
                None => lift.polar(rho, theta),
            }
            .expect("on the surface");
            if let Some(p) = previous {
                largest = largest.max(p.p.distance(l.p));
            }
            previous = Some(l);
        }
        largest
    }

    #[test]
    fn issue_4_circles_round_the_pole_lift_continuously_across_the_star_rim() {
        // box_boss_pocket's top is a flat 2.5 mm grid: the faces around the pole were lifted
        // through the w plane and their neighbours through the strip, and a ring crossing from
        // one to the other jumped 2.1 mm.
        let (surface, map) = mapped("box_boss_pocket");
        let lift = Lift::new(&surface, &map);
        let star = lift.star.as_ref().expect("a disk map has a pole star");
        assert!(star.faces.len() > 1 && !star.rim.is_empty(), "{} faces", star.faces.len());
        let total: f64 = star.rim.iter().map(|e| e.1).sum();
        assert!((total - TAU).abs() < 1e-9, "the rim winds once about the pole: {total}");
        let n = 20_000;
        for k in 1..=24 {
            let rho = star.reach * k as f64 / 12.0;
            // A circle of radius rho on the surface is about rho / |w'| long; a step is the
            // arc over n, so a few hundredths of a millimetre; a jump is a face size.
            let step = largest_step(&lift, rho, n);
            assert!(step < 0.1, "radius {rho}: a step of {step} mm");
        }
    }

    #[test]
    fn the_star_lift_agrees_with_the_map_on_its_rim() {
        // The warp is the identity on the rim (where the strip faces outside meet it): every
        // rim corner, and every rim edge's midpoint as the strip draws it, lifts to itself.
        let (surface, map) = mapped("plate_3_holes");
        let lift = Lift::new(&surface, &map);
        let star = lift.star.as_ref().expect("a pole star");
        let vertex_of = |w: DVec2| (0..map.w.len()).find(|&v| map.w[v] == w).expect("a rim corner");
        for &(ta, span, wa, wb) in &star.rim {
            let (a, b) = (vertex_of(wa), vertex_of(wb));
            let l = lift.at(wa).expect("lifted");
            assert!(l.p.distance(surface.positions[a]) < 1e-9, "corner {a}");
            let mid_rho = 0.5 * (wa.length() + wb.length());
            let l = lift.polar(mid_rho * (1.0 - 1e-12), ta + 0.5 * span).expect("lifted");
            let expected = 0.5 * (surface.positions[a] + surface.positions[b]);
            assert!(l.p.distance(expected) < 1e-6, "edge {a}–{b}: {:?} vs {expected:?}", l.p);
        }
    }

    #[test]
    fn image_of_inverts_the_lift_inside_and_outside_the_pole_star() {
        // The gate moves a ring up to the radius the lift gives a point's place (gen017's star
        // reached a slit, where the strip's P1 image put points 0.27 mm off their ring): lifting
        // a grid of image points and asking where each came from must give it back.
        let (surface, map) = mapped("plate_3_holes");
        let lift = Lift::new(&surface, &map);
        let reach = lift.star.as_ref().expect("a pole star").reach;
        let (mut in_star, mut outside) = (0, 0);
        for i in 1..=40 {
            let rho = 3.0 * reach * i as f64 / 40.0;
            for j in 0..64 {
                let theta = -PI + TAU * (j as f64 + 0.5) / 64.0;
                let Some(l) = lift.polar(rho, theta) else { continue };
                let [a, b, c] = surface.triangles[l.face as usize].map(|v| surface.positions[v as usize]);
                // Barycentric coordinates of the lifted point, from the surface.
                let bary = crate::mesh::nearest::closest_on_triangle(l.p, a, b, c);
                let (r, t) = lift.image_of(l.face as usize, bary);
                assert!(
                    (r - rho).abs() < 1e-9 && (crate::num::rem_tau(t - theta + PI) - PI).abs() < 1e-7,
                    "({rho}, {theta}) came back as ({r}, {t})"
                );
                if lift.in_pole_star(l.face as usize) {
                    in_star += 1;
                } else {
                    outside += 1;
                }
            }
        }
        assert!(in_star > 100 && outside > 100, "{in_star} points in the star, {outside} outside");
    }
}
