//! Nearest points of a triangle mesh: a bounding-volume hierarchy over the faces for queries
//! bounded by a search radius (a point's nearest facet point, whether a segment comes within a
//! distance of a facet), the mesh's offset surface along a direction ([`FaceTree::clear_ball`]),
//! and the closest points of one triangle.
//!
//! The toolpath asks this for every ball centre and every straight move between two (is any
//! facet closer than the ball radius?), so a query must touch only the faces near it: the tree
//! is traversed nearer box first and pruned by the best distance so far (each node's box, and
//! its box in the frame of its faces' mean normal, [`Oriented`]), and a face is tested by its
//! plane and its bounding sphere before its closest point. Deterministic: the same mesh
//! builds the same tree, and ties between faces at equal distance go to the lower face index.

use crate::bvh::{self, Node, Stack, Walk};
use crate::num;
use glam::DVec3;

/// Steps of [`FaceTree::clear_ball`] before a ball is reported unresolved.
pub const CLEAR_ROUNDS: usize = 32;

/// [`FaceTree::clear_ball`] clears a ball of radius R to R·(1 − this): nearer is a penetration,
/// the rest is rounding.
pub const CLEAR_REL: f64 = 1e-9;

/// [`FaceTree::rest_ball`] slides a ball along its face at most this many radii (a crease whose
/// flanks turn by 30° lets a ball tangent to one flank down R·tan 15° ≈ 0.27 R from it).
pub const REST_SLIDE: f64 = 0.5;

/// Slides of [`FaceTree::rest_ball`] before it moves the ball out instead.
pub const REST_SLIDE_ROUNDS: usize = 8;

/// A bounding-volume hierarchy over the faces of a mesh ([`crate::bvh`] over the face boxes and
/// centroids); a leaf's slots hold the faces `order[start..start + count]`.
#[derive(Clone, Debug)]
pub struct FaceTree {
    pub(super) nodes: Vec<Node>,
    pub(super) order: Vec<u32>,
    pub(super) corners: Vec<[DVec3; 3]>,
    /// Unit normal and offset of each slot's plane (zero for a degenerate face): a face whose
    /// plane is already beyond the bound is skipped without its closest point, which is most of
    /// the faces under a ball resting on the surface.
    planes: Vec<(DVec3, f64)>,
    /// Bounding sphere (centroid, radius) of each slot's face: the cheap test of a move against
    /// the faces round the one it passes over.
    pub(super) spheres: Vec<(DVec3, f64)>,
    /// Slot of each face.
    slot_of: Vec<u32>,
    /// Each node's box in a frame of its faces' mean normal ([`Oriented`]).
    oriented: Vec<Oriented>,
}

/// A node's faces bounded in a frame whose third axis is their area-weighted mean normal: a
/// patch of surface is thin along its normal, where its axis-aligned box is as thick as the
/// patch is tilted. A ball resting on the surface is within R of the axis-aligned boxes of every
/// tilted patch round it, but within R of few of these; either box's distance is a lower bound
/// of the faces', so the queries prune by the larger (the same faces are found).
#[derive(Clone, Copy, Debug)]
pub(super) struct Oriented {
    axes: [DVec3; 3],
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Oriented {
    /// The node of `corners` (all of its slots).
    fn new(corners: &[[DVec3; 3]]) -> Self {
        let n = corners.iter().fold(DVec3::ZERO, |s, &[a, b, c]| s + (b - a).cross(c - a)).normalize_or_zero();
        let axes = if n == DVec3::ZERO {
            [DVec3::X, DVec3::Y, DVec3::Z]
        } else {
            let t = n.any_orthonormal_vector();
            [t, n.cross(t), n]
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in corners.iter().flatten() {
            for k in 0..3 {
                let x = axes[k].dot(*p);
                lo[k] = lo[k].min(x);
                hi[k] = hi[k].max(x);
            }
        }
        // Widened by far more than the rounding of the projections (about 1e-16 of the
        // coordinates), so that no face at a query's exact bound is pruned.
        let scale = corners.iter().flatten().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        let pad = 1e-12 * scale;
        Self { axes, lo: lo.map(|x| x - pad), hi: hi.map(|x| x + pad) }
    }

    /// Squared distance from `p` to the box (0 inside): a lower bound of its faces'.
    #[inline]
    fn distance2(&self, p: DVec3) -> f64 {
        let mut d2 = 0.0;
        for k in 0..3 {
            let x = self.axes[k].dot(p);
            let d = (self.lo[k] - x).max(x - self.hi[k]).max(0.0);
            d2 += d * d;
        }
        d2
    }
}

/// The point of the mesh nearest to a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    pub face: usize,
    /// The face's slot in the tree.
    slot: usize,
    /// Barycentric coordinates of `point` in `face`.
    pub bary: [f64; 3],
    pub point: DVec3,
    pub distance: f64,
}

impl FaceTree {
    /// Number of faces in the tree.
    pub fn face_count(&self) -> usize {
        self.slot_of.len()
    }

    /// Builds the tree of the triangles `triangles` over `positions` (indices must be valid).
    pub fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> Self {
        let corners: Vec<[DVec3; 3]> = triangles.iter().map(|t| t.map(|v| positions[v as usize])).collect();
        let bounds: Vec<(DVec3, DVec3)> =
            corners.iter().map(|c| (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]))).collect();
        let mids: Vec<DVec3> = corners.iter().map(|c| (c[0] + c[1] + c[2]) / 3.0).collect();
        let (nodes, order) = bvh::build(&bounds, &mids);
        // Leaves read their corners in leaf order, for locality.
        let corners: Vec<[DVec3; 3]> = order.iter().map(|&f| corners[f as usize]).collect();
        let planes = corners
            .iter()
            .map(|&[a, b, c]| {
                let n = (b - a).cross(c - a).normalize_or_zero();
                (n, n.dot(a))
            })
            .collect();
        let spheres = corners
            .iter()
            .map(|c| {
                let m = (c[0] + c[1] + c[2]) / 3.0;
                (m, c.iter().map(|&p| p.distance(m)).fold(0.0, f64::max))
            })
            .collect();
        let mut slot_of = vec![0; order.len()];
        for (slot, &f) in order.iter().enumerate() {
            slot_of[f as usize] = slot as u32;
        }
        // Each node's slots: a leaf's own, an inner node's from its first slot to its right
        // child's last (children follow their parent in the array).
        let mut ends = vec![0u32; nodes.len()];
        for i in (0..nodes.len()).rev() {
            let node = &nodes[i];
            ends[i] = if node.count > 0 { node.start + node.count } else { ends[node.right as usize] };
        }
        let oriented =
            crate::par::each(nodes.len(), |i| Oriented::new(&corners[nodes[i].start as usize..ends[i] as usize]));
        Self { nodes, order, corners, planes, spheres, slot_of, oriented }
    }

    /// A lower bound of the squared distance from `p` to the faces of node `index`: the larger
    /// of its two boxes'.
    #[inline]
    fn node_distance2(&self, index: usize, node: &Node, p: DVec3) -> f64 {
        node.distance2(p).max(self.oriented[index].distance2(p))
    }

    /// Whether every face of node `index` is farther than √`limit2` from `p`: either box is
    /// (the oriented one is measured only when the axis-aligned one is nearer).
    #[inline]
    fn node_beyond(&self, index: usize, node: &Node, p: DVec3, limit2: f64) -> bool {
        node.distance2(p) > limit2 || self.oriented[index].distance2(p) > limit2
    }

    /// [`FaceTree::nearest`]`(p, limit)`, after the cheaper early-exit test: most balls are
    /// clear, and that settles them without the nearest point (the same predicate).
    fn nearest_if_nearer(&self, p: DVec3, limit: f64) -> Option<Nearest> {
        if self.point_nearer_than(p, limit) {
            self.nearest(p, limit)
        } else {
            None
        }
    }

    /// Whether some facet is nearer than `limit` to `p`: [`FaceTree::nearest`]`(p, limit).is_some()`,
    /// stopping at the first such facet.
    pub fn point_nearer_than(&self, p: DVec3, limit: f64) -> bool {
        let limit2 = limit * limit;
        let mut walk = Walk::new(&self.nodes);
        while let Some(slots) = walk.next_leaf_at(&self.nodes, |i, node| self.node_beyond(i, node, p, limit2)) {
            for slot in slots {
                let (n, offset) = self.planes[slot];
                let d = n.dot(p) - offset;
                if d * d >= limit2 {
                    continue;
                }
                // Beyond the face's bounding sphere by the limit: beyond the face.
                let (m, r) = self.spheres[slot];
                if m.distance_squared(p) >= (limit + r) * (limit + r) {
                    continue;
                }
                let [a, b, c] = self.corners[slot];
                let bary = closest_on_triangle(p, a, b, c);
                if (a * bary[0] + b * bary[1] + c * bary[2]).distance_squared(p) < limit2 {
                    return true;
                }
            }
        }
        false
    }

    /// Whether some facet comes nearer than `limit` to the segment `ab` (a straight move of the
    /// ball centre). Exact (segment–triangle distance), pruned by the distance from the
    /// segment's midpoint to a node's box less half its length.
    pub fn segment_nearer_than(&self, a: DVec3, b: DVec3, limit: f64) -> bool {
        let mid = 0.5 * (a + b);
        let half = 0.5 * a.distance(b);
        let reach = limit + half;
        let (limit2, reach2) = (limit * limit, reach * reach);
        let mut walk = Walk::new(&self.nodes);
        while let Some(slots) = walk.next_leaf_at(&self.nodes, |i, node| self.node_beyond(i, node, mid, reach2)) {
            for slot in slots {
                let (n, offset) = self.planes[slot];
                let (da, db) = (n.dot(a) - offset, n.dot(b) - offset);
                // Both ends on one side of the plane and beyond the limit: the face too.
                if (da * db > 0.0 && num::min(da.abs(), db.abs()) >= limit) || self.sphere_beyond(slot, a, b, limit) {
                    continue;
                }
                let [p, q, r] = self.corners[slot];
                if segment_triangle_nearer_than(a, b, p, q, r, limit, limit2) {
                    return true;
                }
            }
        }
        false
    }

    /// The nearest point of the mesh to `p` closer than `max_distance`, or `None`.
    pub fn nearest(&self, p: DVec3, max_distance: f64) -> Option<Nearest> {
        let mut best: Option<Nearest> = None;
        let mut bound2 = max_distance * max_distance;
        let mut stack = Stack::new((0u32, 0.0f64));
        if let Some(root) = self.nodes.first() {
            stack.push((0, self.node_distance2(0, root, p)));
        }
        while let Some((index, d2)) = stack.pop() {
            if d2 > bound2 {
                continue;
            }
            let node = &self.nodes[index as usize];
            if node.count > 0 {
                for slot in node.start as usize..(node.start + node.count) as usize {
                    let (n, offset) = self.planes[slot];
                    let plane = n.dot(p) - offset;
                    if plane * plane > bound2 {
                        continue;
                    }
                    let [a, b, c] = self.corners[slot];
                    let bary = closest_on_triangle(p, a, b, c);
                    let q = a * bary[0] + b * bary[1] + c * bary[2];
                    let e2 = q.distance_squared(p);
                    let face = self.order[slot] as usize;
                    let better = match best {
                        None => e2 < bound2,
                        Some(bn) => e2 < bound2 || (e2 == bound2 && face < bn.face),
                    };
                    if better {
                        bound2 = e2;
                        best = Some(Nearest { face, slot, bary, point: q, distance: e2.sqrt() });
                    }
                }
                continue;
            }
            let (left, right) = (index + 1, node.right);
            let dl = self.node_distance2(left as usize, &self.nodes[left as usize], p);
            let dr = self.node_distance2(right as usize, &self.nodes[right as usize], p);
            // Nearer child last, so it is taken first and tightens the bound early.
            if dl <= dr {
                stack.push((right, dr));
                stack.push((left, dl));
            } else {
                stack.push((left, dl));
                stack.push((right, dr));
            }
        }
        best
    }
}

/// A ball of radius R whose centre is kept R − `dip_mm` from every facet: it touches the facets
/// without cutting them when the dip is 0, and may enter them by the dip otherwise (smooth
/// facets, which may deviate that much from the surface they tessellate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DippingBall {
    pub radius_mm: f64,
    pub dip_mm: f64,
}

impl DippingBall {
    /// The distance its centre keeps from the facets, R − dip: the radius to clear it by
    /// ([`FaceTree::clear_ball`]).
    pub fn keep_mm(self) -> f64 {
        self.radius_mm - self.dip_mm
    }
}

/// Where [`FaceTree::clear_ball`] left a ball.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClearBall {
    pub centre: DVec3,
    /// The facet point the last step pushed from, nearest to `centre` on its face (`None` when
    /// the ball was already clear); where the ball touches.
    pub touch: Option<DVec3>,
    /// Newton or projection steps taken (0: the ball was already clear, `centre` is the input).
    pub rounds: usize,
    /// Still nearer than R to a facet after [`CLEAR_ROUNDS`] (a groove narrower than the ball).
    pub unresolved: bool,
}

impl FaceTree {
    /// Moves a ball of radius `radius` centred at `centre` along the unit direction `dir` until
    /// no facet is nearer than `radius` (to a relative 1e-9): the mesh's offset surface. Each
    /// round is a Newton step on the distance to the nearest facet point q,
    /// c += dir·(R − |c − q|)/(g·dir) with g = (c − q)/|c − q| (exact for a plane, so a ball
    /// between facets settles in a step per facet); a facet nearly along `dir` (g·dir < 1/4, a
    /// wall beside the ball) is left by the nearest-point projection c = q + R·g instead.
    ///
    /// `face`, when given, is tried first without a search (the face under the ball, which is
    /// usually the one it dips into: 98 % of the centres on freeform_4_holes). With `search`
    /// false that is all: the ball is clear of `face`, and the caller confirms the rest (see
    /// [`FaceTree::point_nearer_than`]).
    pub fn clear_ball(&self, centre: DVec3, dir: DVec3, radius: f64, face: Option<usize>, search: bool) -> ClearBall {
        let limit = radius * (1.0 - CLEAR_REL);
        let step = |c: DVec3, hit: &Nearest| {
            let g = if hit.distance > 1e-12 * radius { (c - hit.point) / hit.distance } else { dir };
            let slope = g.dot(dir);
            if slope > 0.25 {
                c + dir * ((radius - hit.distance) / slope)
            } else {
                hit.point + radius * g
            }
        };
        let mut c = centre;
        let mut rounds = 0;
        let mut last = None;
        if let Some(hit) = face.and_then(|f| self.face_point(f, c)).filter(|h| h.distance < limit) {
            rounds = 1;
            last = Some(hit.slot);
            c = step(c, &hit);
        }
        if !search {
            return ClearBall { centre: c, touch: self.touch(last, c), rounds, unresolved: false };
        }
        while let Some(hit) = self.nearest_if_nearer(c, limit) {
            if rounds == CLEAR_ROUNDS {
                return ClearBall { centre: c, touch: self.touch(last, c), rounds, unresolved: true };
            }
            rounds += 1;
            last = Some(hit.slot);
            c = step(c, &hit);
        }
        ClearBall { centre: c, touch: self.touch(last, c), rounds, unresolved: false }
    }

    /// The ball of radius `radius` touching face `face` at its point `p` (centre p + radius·m,
    /// m the face's unit normal), moved clear of every other facet the way that leaves least
    /// over p: away from a facet that rises above `face`'s plane (the other flank of a concave
    /// crease, a wall) it slides parallel to that plane, so it stays tangent to `face` and comes
    /// to rest against both (the ball a crease lets down furthest); from any other facet, or once
    /// it has slid [`REST_SLIDE`]·radius or taken [`REST_SLIDE_ROUNDS`] slides (a groove between
    /// two rising facets), it is moved out along m as [`FaceTree::clear_ball`] moves it. `None`
    /// for a degenerate face.
    pub fn rest_ball(&self, p: DVec3, face: usize, radius: f64) -> Option<ClearBall> {
        let slot = *self.slot_of.get(face)? as usize;
        let (m, offset) = self.planes[slot];
        if m == DVec3::ZERO {
            return None;
        }
        let limit = radius * (1.0 - CLEAR_REL);
        let start = p + radius * m;
        let mut c = start;
        let (mut rounds, mut last) = (0, None);
        while let Some(hit) = self.nearest_if_nearer(c, limit) {
            if rounds == CLEAR_ROUNDS {
                return Some(ClearBall { centre: c, touch: self.touch(last, c), rounds, unresolved: true });
            }
            rounds += 1;
            last = Some(hit.slot);
            let g = if hit.distance > 1e-12 * radius { (c - hit.point) / hit.distance } else { m };
            // Along the face's plane, away from the facet point.
            let along = g - g.dot(m) * m;
            let slope = along.length();
            let rises = m.dot(hit.point) - offset > 1e-9 * radius;
            let slid = (c - start).length();
            if rises && rounds <= REST_SLIDE_ROUNDS && slope > 1e-3 && slid < REST_SLIDE * radius {
                // A Newton step on the distance to the facet's plane, exact for a plane.
                c += along * ((radius - hit.distance) / (slope * slope));
            } else if g.dot(m) > 0.25 {
                c += m * ((radius - hit.distance) / g.dot(m));
            } else {
                c = hit.point + radius * g;
            }
        }
        Some(ClearBall { centre: c, touch: self.touch(last, c), rounds, unresolved: false })
    }

    /// The ball [`FaceTree::rest_ball`] lets down from face `face` at its point `p`, when it is
    /// resolved and leaves less over `p` than `ball` (a ball of the same radius over `p`, cleared
    /// of every facet): the toolpath's and the spacing's swap beside a concave crease.
    pub fn rest_below(&self, ball: &ClearBall, p: DVec3, face: usize, radius: f64) -> Option<ClearBall> {
        let rest = self.rest_ball(p, face, radius).filter(|b| !b.unresolved)?;
        (rest.centre.distance(p) < ball.centre.distance(p)).then_some(rest)
    }

    /// The unit normal of face `face`'s plane (zero for a degenerate face).
    pub fn face_normal(&self, face: usize) -> DVec3 {
        self.planes[self.slot_of[face] as usize].0
    }

    /// Whether slot `slot`'s bounding sphere is at least `limit` from the segment `ab` (then so
    /// is its face).
    fn sphere_beyond(&self, slot: usize, a: DVec3, b: DVec3, limit: f64) -> bool {
        let (m, r) = self.spheres[slot];
        let d = b - a;
        let len2 = d.length_squared();
        let t = if len2 > 0.0 { ((m - a).dot(d) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let reach = limit + r;
        (a + d * t).distance_squared(m) >= reach * reach
    }

    /// The point of face `face` nearest to `p`.
    fn face_point(&self, face: usize, p: DVec3) -> Option<Nearest> {
        let slot = *self.slot_of.get(face)? as usize;
        let (bary, point) = self.slot_point(slot, p);
        Some(Nearest { face, slot, bary, point, distance: point.distance(p) })
    }

    fn touch(&self, slot: Option<usize>, p: DVec3) -> Option<DVec3> {
        Some(self.slot_point(slot?, p).1)
    }

    /// Barycentric coordinates and position of the point of slot `slot`'s face nearest to `p`.
    fn slot_point(&self, slot: usize, p: DVec3) -> ([f64; 3], DVec3) {
        let [a, b, c] = self.corners[slot];
        let bary = closest_on_triangle(p, a, b, c);
        (bary, a * bary[0] + b * bary[1] + c * bary[2])
    }
}

/// Squared distance between segment `pq` and triangle `abc`: 0 when the segment pierces the
/// triangle; otherwise the least over the segment's ends against the triangle and the
/// triangle's edges against the segment (a closest pair of a segment and a triangle that do not
/// meet has one of its points on an end or an edge).
pub fn segment_triangle_distance2(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a);
    let (dp, dq) = (n.dot(p - a), n.dot(q - a));
    if dp * dq <= 0.0 && dp != dq {
        let x = p + (q - p) * (dp / (dp - dq));
        let bary = closest_on_triangle(x, a, b, c);
        if (a * bary[0] + b * bary[1] + c * bary[2]).distance_squared(x) <= 1e-24 * n.length() {
            return 0.0;
        }
    }
    let to_triangle = |x: DVec3| {
        let bary = closest_on_triangle(x, a, b, c);
        (a * bary[0] + b * bary[1] + c * bary[2]).distance_squared(x)
    };
    let mut d = num::min(to_triangle(p), to_triangle(q));
    for (e0, e1) in [(a, b), (b, c), (c, a)] {
        d = num::min(d, segment_segment_distance2(p, q, e0, e1));
    }
    d
}

/// Whether the segment `pq` comes nearer than `limit` (`limit2` = limit²) to the triangle `abc`.
/// The distance from a point moving along the segment to the triangle is convex in the
/// parameter, so it lies above its tangents at both ends: when their crossing is already beyond
/// the limit the exact distance (three segment pairs more) is not needed. Under a ball resting on
/// the surface that settles nearly every face the cheaper tests leave.
fn segment_triangle_nearer_than(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3, limit: f64, limit2: f64) -> bool {
    let closest = |x: DVec3| {
        let bary = closest_on_triangle(x, a, b, c);
        x - (a * bary[0] + b * bary[1] + c * bary[2])
    };
    let (e0, e1) = (closest(p), closest(q));
    let (f0, f1) = (e0.length(), e1.length());
    if f0 < limit || f1 < limit {
        return true;
    }
    // Slopes of the distance at both ends, per unit of the segment parameter.
    let v = q - p;
    let (s0, s1) = (e0.dot(v) / f0, e1.dot(v) / f1);
    let bound = if s0 >= 0.0 || s1 <= 0.0 {
        f0.min(f1) // monotone along the segment
    } else {
        let t = (f1 - s1 - f0) / (s0 - s1);
        f0 + s0 * t.clamp(0.0, 1.0)
    };
    if bound >= limit {
        return false;
    }
    segment_triangle_distance2(p, q, a, b, c) < limit2
}

/// Squared distance between segments `p1q1` and `p2q2` (Ericson, Real-Time Collision Detection,
/// §5.1.9).
fn segment_segment_distance2(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (s, t) = if a <= 1e-300 && e <= 1e-300 {
        (0.0, 0.0)
    } else if a <= 1e-300 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= 1e-300 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 0.0 { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (p1 + d1 * s).distance_squared(p2 + d2 * t)
}

/// Barycentric coordinates of the point of triangle `abc` closest to `p` (Ericson, Real-Time
/// Collision Detection, §5.1.5).
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{self, SplitMix64};

    /// Brute force over every face: the oracle of the tree.
    fn nearest_brute(positions: &[DVec3], triangles: &[[u32; 3]], p: DVec3) -> (usize, f64) {
        let mut best = (0, f64::INFINITY);
        for (f, t) in triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let bary = closest_on_triangle(p, a, b, c);
            let d = (a * bary[0] + b * bary[1] + c * bary[2]).distance(p);
            if d < best.1 {
                best = (f, d);
            }
        }
        best
    }

    #[test]
    fn the_tree_finds_the_brute_force_nearest_point_within_the_radius() {
        let mesh = fixtures::saddle_2_holes();
        let tree = FaceTree::new(&mesh.positions, &mesh.triangles);
        let mut rng = SplitMix64(1);
        let mut next = || rng.unit();
        let (lo, hi) = crate::mesh::weld::bounding_box(&mesh.positions);
        let (mut found, mut missed) = (0, 0);
        for _ in 0..2000 {
            let p = lo + (hi - lo + DVec3::splat(8.0)) * DVec3::new(next(), next(), next()) - DVec3::splat(4.0);
            let (face, d) = nearest_brute(&mesh.positions, &mesh.triangles, p);
            match tree.nearest(p, 3.0) {
                Some(n) => {
                    assert!((n.distance - d).abs() <= 1e-12 * (1.0 + d), "{p:?}: tree {} brute {d}", n.distance);
                    assert!(
                        n.face == face || (n.distance - d).abs() <= 1e-12 * (1.0 + d),
                        "{p:?}: face {} vs {face}",
                        n.face
                    );
                    found += 1;
                }
                None => {
                    assert!(d >= 3.0, "{p:?}: missed a face at {d}");
                    missed += 1;
                }
            }
        }
        assert!(found > 200 && missed > 200, "found {found}, beyond the radius {missed}");
    }

    /// Balls resting on a tilted, curved surface, where the oriented boxes prune what the
    /// axis-aligned ones keep: the tree's answers are brute force's, within, at and beyond R,
    /// and every leaf's oriented box is no farther than its nearest face.
    #[test]
    fn balls_resting_on_the_surface_find_the_brute_force_facets() {
        let mut mesh = fixtures::saddle_2_holes();
        // Tilted 35° about a skew axis, so the patches' boxes are thick.
        let turn = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.6);
        mesh.positions.iter_mut().for_each(|p| *p = turn * *p);
        let tree = FaceTree::new(&mesh.positions, &mesh.triangles);
        let mut rng = SplitMix64(7);
        let mut next = || rng.unit();
        let mut seen = [0usize; 2];
        for (f, t) in mesh.triangles.iter().enumerate().step_by(3) {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            let n = (b - a).cross(c - a).normalize();
            let (u, v) = (next(), next());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let r = 0.5 + 3.0 * next();
            // On the face's offset, just above and just below it.
            let p = a + (b - a) * u + (c - a) * v + n * r * (1.0 + 2e-3 * (next() - 0.5));
            let limit = r * (1.0 - 1e-9);
            let (face, d) = nearest_brute(&mesh.positions, &mesh.triangles, p);
            let near = tree.nearest(p, limit);
            assert_eq!(tree.point_nearer_than(p, limit), near.is_some(), "face {f}");
            match near {
                Some(hit) => assert!(hit.face == face || (hit.distance - d).abs() <= 1e-12 * d, "face {f}"),
                None => assert!(d >= limit, "face {f}: missed a facet at {d} < {limit}"),
            }
            seen[near.is_some() as usize] += 1;
            // Every node's oriented box is a lower bound of its faces' distances.
            for (i, node) in tree.nodes.iter().enumerate().filter(|(_, n)| n.count > 0) {
                let slots = node.start as usize..(node.start + node.count) as usize;
                let least = slots
                    .map(|s| {
                        let [a, b, c] = tree.corners[s];
                        let bary = closest_on_triangle(p, a, b, c);
                        (a * bary[0] + b * bary[1] + c * bary[2]).distance_squared(p)
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!(tree.oriented[i].distance2(p) <= least, "node {i}");
            }
        }
        assert!(seen.iter().all(|&k| k > 50), "{seen:?}");
    }

    #[test]
    fn segment_queries_agree_with_dense_sampling() {
        let mesh = fixtures::saddle_2_holes();
        let tree = FaceTree::new(&mesh.positions, &mesh.triangles);
        let mut rng = SplitMix64(2);
        let mut next = || rng.unit();
        let (lo, hi) = crate::mesh::weld::bounding_box(&mesh.positions);
        let (mut near, mut far) = (0, 0);
        for _ in 0..400 {
            let a = lo + (hi - lo) * DVec3::new(next(), next(), next()) + DVec3::Z * (4.0 * next() - 1.0);
            let b = a + DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 6.0;
            let limit = 2.0;
            // Oracle: the segment sampled every 0.02 mm, each sample's distance from the point
            // query (checked against brute force above); sampling overestimates by < 1e-4 here.
            let steps = (a.distance(b) / 0.02).ceil() as usize;
            let sampled = (0..=steps)
                .map(|k| a.lerp(b, k as f64 / steps as f64))
                .map(|x| tree.nearest(x, 10.0).map_or(f64::INFINITY, |n| n.distance))
                .fold(f64::INFINITY, f64::min);
            if (sampled - limit).abs() < 1e-3 {
                continue; // too close to call by sampling
            }
            let got = tree.segment_nearer_than(a, b, limit);
            assert_eq!(got, sampled < limit, "{a:?} {b:?}: sampled distance {sampled}");
            if got {
                near += 1;
            } else {
                far += 1;
            }
        }
        assert!(near > 50 && far > 50, "near {near}, far {far}");
    }

    #[test]
    fn the_tangent_bound_decides_as_the_exact_segment_distance() {
        // Short segments skimming a triangle at about the limit, as ball-centre moves over a
        // facet: the bound must never call near what is far, nor far what is near.
        let mut rng = SplitMix64(4);
        let mut next = || rng.unit();
        let (mut near, mut far) = (0, 0);
        for _ in 0..20_000 {
            let [a, b, c] = [(); 3].map(|_| DVec3::new(next(), next(), 0.2 * next()) * 2.0);
            let p = DVec3::new(2.0 * next(), 2.0 * next(), 3.2 + 0.1 * next());
            let q = p + DVec3::new(next() - 0.5, next() - 0.5, 0.05 * (next() - 0.5));
            let limit = 3.0 + 0.1 * next();
            let exact = segment_triangle_distance2(p, q, a, b, c).sqrt();
            if (exact - limit).abs() < 1e-12 {
                continue;
            }
            let got = segment_triangle_nearer_than(p, q, a, b, c, limit, limit * limit);
            assert_eq!(got, exact < limit, "{p:?} {q:?} over {a:?} {b:?} {c:?}: {exact} vs {limit}");
            if got {
                near += 1;
            } else {
                far += 1;
            }
        }
        assert!(near > 2000 && far > 2000, "near {near}, far {far}");
    }

    #[test]
    fn the_point_test_agrees_with_the_nearest_point() {
        let mesh = fixtures::spherical_cap_hole();
        let tree = FaceTree::new(&mesh.positions, &mesh.triangles);
        let mut rng = SplitMix64(3);
        let mut next = || rng.unit();
        let (lo, hi) = crate::mesh::weld::bounding_box(&mesh.positions);
        let mut seen = [0usize; 2];
        for _ in 0..2000 {
            let p = lo + (hi - lo) * DVec3::new(next(), next(), next()) + DVec3::Z * (4.0 * next() - 1.0);
            let limit = 3.0 * next();
            let near = tree.nearest(p, limit).is_some();
            assert_eq!(tree.point_nearer_than(p, limit), near, "{p:?} {limit}");
            seen[near as usize] += 1;
        }
        assert!(seen.iter().all(|&k| k > 100), "{seen:?}");
    }
}
