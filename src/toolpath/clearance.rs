//! Facet clearance: ball centres pushed off every facet closer than the ball radius.
//!
//! The spiral places the ball along the interpolated vertex normal, which is smooth but not the
//! normal of the facet under the contact: the ball then dips R(1 − cos δ) into that facet, δ the
//! angle between the two normals, and deeper into a neighbouring facet across a crease (11 µm on
//! face_holes' 5° facets with a 3 mm ball). A machinist's STL is the part, so every centre inside
//! the mesh's offset surface is moved onto it along its own normal n ([`FaceTree::clear_ball`]).
//! The normal becomes (c − q)/|c − q|, q the touched facet point, and the contact c − R·n, so
//! `centre = cc + R·n` holds exactly and the contact is q (up to a Newton step's overshoot
//! where the ball rests on an edge).
//!
//! Beside a concave crease that lift can exceed what the spacing plans for (`LIFT_CAP`·h): the
//! interpolated normal tilts towards the crease's other flank, and a ball pushed along it leaves
//! its lift over the contact. Such a ball is replaced by the ball touching the contact's own
//! facet there, slid along that facet until it clears the other flank
//! ([`FaceTree::rest_ball`]), when that leaves less over the contact: the ball a crease lets
//! down furthest (issue 34: gen015, 112, 133 and 160 kept 1.02–1.26 h just outside their facet
//! valleys under balls lifted 1.0–2.1 h). The spacing places its balls the same way.
//!
//! Between two cleared centres the machine moves straight, and a straight move can still cut:
//! the chord of a convex offset, or a move past a feature narrower than the ball. Every move is
//! checked whole against the facets ([`FaceTree::segment_nearer_than`]) and split at its
//! cleared midpoint while it comes nearer than R − the chord tolerance.
//!
//! With smooth facets the ball may dip into them by their own deviation from the normals it
//! rides: the centres then keep R less that from the facets.
//!
//! Centres already clear are untouched, bit for bit.

use crate::mesh::nearest::{DippingBall, FaceTree, CLEAR_REL};
use glam::DVec3;
use serde::Serialize;

/// What [`clear_facets`] moved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Clearance {
    /// Centres that were inside a facet's ball-radius offset and were moved.
    pub moved: usize,
    /// Largest distance a centre moved, mm.
    pub max_move_mm: f64,
    /// Points added where a straight move between two cleared centres dipped into a facet by
    /// more than the chord tolerance.
    pub inserted: usize,
    /// Centres still nearer than R to a facet after the rounds (a groove narrower than the
    /// ball), and moves still dipping deeper than the tolerance after [`MAX_SPLITS`] halvings.
    pub unresolved: usize,
    /// Cleared centres that landed on the previous one (within the toolpath's repeated-point
    /// distance: both pushed into one pocket narrower than the ball) and were dropped.
    pub merged: usize,
}

/// Halvings of one move that dips into a facet.
pub const MAX_SPLITS: usize = 12;

/// Moves every ball centre `cc[i] + R·normals[i]` out of the facets of `faces` (see the module
/// docs; `cc_faces[i]`, the face of `cc[i]`, is tried first) until no facet is nearer than
/// R − `dip_mm` (0 when the STL is the part; with smooth facets, their own deviation from the
/// smooth surface they tessellate), then splits each straight move between two centres that
/// comes nearer than that less `chord_tolerance_mm` to a facet (a chord of a convex offset, or a
/// move past a feature narrower than the ball) at its cleared midpoint. Returns the contacts
/// and normals of the new path. A centre lifted more than `rest_above_mm` over its contact is let
/// down into the crease beside it when that leaves less (see the module docs; `f64::INFINITY`:
/// never). Precondition: `0 ≤ dip_mm < R`.
#[allow(clippy::too_many_arguments)]
pub fn clear_facets(
    faces: &FaceTree,
    cc: &[DVec3],
    normals: &[DVec3],
    cc_faces: &[u32],
    radius_mm: f64,
    dip_mm: f64,
    chord_tolerance_mm: f64,
    rest_above_mm: f64,
) -> (Vec<DVec3>, Vec<DVec3>, Clearance) {
    debug_assert!((0.0..radius_mm).contains(&dip_mm), "dip {dip_mm} mm with R {radius_mm} mm");
    let face = |i: usize| cc_faces.get(i).map(|&f| f as usize);
    let ball = DippingBall { radius_mm, dip_mm };
    let limit = ball.keep_mm() - chord_tolerance_mm;
    let centre = |q: (DVec3, DVec3)| q.0 + radius_mm * q.1;
    // Between two centres outside every ball of radius R round a facet point a move enters such
    // a ball by at most R − √(R² − L²/4) ≈ L²/8R: short ones cannot dip.
    let short = |a: DVec3, b: DVec3| a.distance_squared(b) <= 8.0 * radius_mm * chord_tolerance_mm;
    // Whether the straight move between two centres dips deeper than the chord tolerance.
    let dips = |a: (DVec3, DVec3), b: (DVec3, DVec3)| {
        let (ca, cb) = (centre(a), centre(b));
        !short(ca, cb) && faces.segment_nearer_than(ca, cb, limit)
    };

    // The move ending at centre `i`, from `prev` to `b`, when it dips into a facet: its points,
    // split at cleared midpoints, `b` last.
    let split_move = |prev: (DVec3, DVec3), b: (DVec3, DVec3), i: usize| {
        if !dips(prev, b) {
            return None;
        }
        let mut report = Clearance::default();
        let mut pending = vec![(prev, b, 0usize)];
        let mut inserted = Vec::new();
        // Depth first, left half first, so the points come out in path order. The whole move
        // (depth 0) is known to dip.
        while let Some((a, b, depth)) = pending.pop() {
            if depth > 0 && !dips(a, b) {
                inserted.push(b);
                continue;
            }
            if depth == MAX_SPLITS {
                report.unresolved += 1;
                inserted.push(b);
                continue;
            }
            let mid = 0.5 * (centre(a) + centre(b));
            let dir = (a.1 + b.1).normalize_or(a.1);
            let m = clear_one(faces, mid - radius_mm * dir, dir, None, true, ball, rest_above_mm, &mut report);
            report.inserted += 1;
            pending.push((m, b, depth + 1));
            pending.push((a, m, depth + 1));
        }
        Some((i, inserted, report))
    };
    // Each centre on its own (in parallel): off its own face first; one traversal then confirms
    // that no other facet is within R of it (most centres need no more).
    let cleared = crate::par::each(cc.len(), |i| {
        let mut report = Clearance::default();
        let b = clear_one(faces, cc[i], normals[i], face(i), i == 0, ball, rest_above_mm, &mut report);
        if i == 0 || !faces.point_nearer_than(centre(b), ball.keep_mm() * (1.0 - CLEAR_REL)) {
            return (b, report);
        }
        let mut report = Clearance::default();
        (clear_one(faces, cc[i], normals[i], face(i), true, ball, rest_above_mm, &mut report), report)
    });
    // Then each move between two cleared centres (in chunks, in parallel): the points of those
    // that dip into a facet (most do not, and allocate nothing).
    let moves = crate::par::each(cc.len().div_ceil(CHUNK), |k| {
        let range = k * CHUNK..((k + 1) * CHUNK).min(cc.len());
        range.filter(|&i| i > 0).filter_map(|i| split_move(cleared[i - 1].0, cleared[i].0, i)).collect::<Vec<_>>()
    });
    let mut report = Clearance::default();
    for (_, r) in &cleared {
        report.merge(r);
    }
    let mut path: Vec<(DVec3, DVec3)> = Vec::with_capacity(cc.len());
    let mut split = moves.into_iter().flatten().peekable();
    for (i, (b, _)) in cleared.iter().enumerate() {
        match split.next_if(|(at, _, _)| *at == i) {
            Some((_, points, r)) => {
                report.merge(&r);
                path.extend(points);
            }
            None => path.push(*b),
        }
    }
    // Centres pushed into the same pocket (narrower than the ball) land on one point: the ball
    // stays there, so the repeat is dropped.
    let before = path.len();
    path.dedup_by(|b, a| centre(*b).distance(centre(*a)) < super::MIN_STEP_MM);
    report.merged = before - path.len();
    let (out_cc, out_n) = path.into_iter().unzip();
    (out_cc, out_n, report)
}

impl Clearance {
    fn merge(&mut self, other: &Clearance) {
        self.moved += other.moved;
        self.max_move_mm = self.max_move_mm.max(other.max_move_mm);
        self.inserted += other.inserted;
        self.unresolved += other.unresolved;
        self.merged += other.merged;
    }
}

/// Moves handed to one job of [`clear_facets`]'s second pass.
const CHUNK: usize = 256;

/// One centre `p + R·n` cleared: the new contact and normal.
#[allow(clippy::too_many_arguments)]
fn clear_one(
    faces: &FaceTree,
    p: DVec3,
    n: DVec3,
    face: Option<usize>,
    search: bool,
    kept: DippingBall,
    rest_above_mm: f64,
    report: &mut Clearance,
) -> (DVec3, DVec3) {
    let radius_mm = kept.radius_mm;
    let start = p + radius_mm * n;
    let mut ball = faces.clear_ball(start, n, kept.keep_mm(), face, search);
    if ball.rounds == 0 {
        return (p, n);
    }
    // Lifted more than the spacing plans for: the ball touching the contact's own facet at p,
    // let down into the crease beside it, when that leaves less over p.
    let over = |c: DVec3| c.distance(p) - kept.keep_mm();
    let mut resting_normal = None;
    if let Some(f) = face.filter(|_| over(ball.centre) > rest_above_mm) {
        if !search {
            // Compared as the spacing compares them: with the ball cleared of every facet.
            ball = faces.clear_ball(start, n, kept.keep_mm(), face, true);
        }
        if let Some(rest) = faces.rest_below(&ball, p, f, kept.keep_mm()) {
            // Clear where it touches its facet: the contact is p itself.
            resting_normal = (rest.rounds == 0).then(|| faces.face_normal(f));
            ball = rest;
        }
    }
    report.unresolved += ball.unresolved as usize;
    report.moved += 1;
    report.max_move_mm = report.max_move_mm.max(ball.centre.distance(start));
    if let Some(m) = resting_normal {
        return (p, m);
    }
    // The centre stays exactly where it cleared every facet; the contact is R below it towards
    // the touch point (on the surface but for a Newton step's overshoot where the ball rests on
    // an edge: renormalising onto the touch point instead pulled such centres back into
    // neighbouring facets, by up to 1.3 h on beetle).
    let n = ball.touch.map_or(n, |q| (ball.centre - q).normalize());
    (ball.centre - radius_mm * n, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two facets meeting at a convex ridge along the y axis, each sloping 5° down from it.
    fn ridge() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let s = 5f64.to_radians().tan();
        let positions = vec![
            DVec3::new(-10.0, -10.0, -10.0 * s),
            DVec3::new(0.0, -10.0, 0.0),
            DVec3::new(0.0, 10.0, 0.0),
            DVec3::new(-10.0, 10.0, -10.0 * s),
            DVec3::new(10.0, -10.0, -10.0 * s),
            DVec3::new(10.0, 10.0, -10.0 * s),
        ];
        (positions, vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    }

    #[test]
    fn a_ball_on_the_interpolated_normal_is_lifted_onto_the_facet_offset() {
        let (positions, triangles) = ridge();
        let tree = FaceTree::new(&positions, &triangles);
        let r = 3.0;
        // Half a millimetre off the ridge on the left facet, with the ridge's vertical normal: the
        // ball dips R(1 − cos 5°) into the left facet and rises R(1/cos 5° − 1) to clear it.
        let s = 5f64.to_radians().tan();
        let facet = DVec3::new(-s, 0.0, 1.0).normalize();
        let (cc, normals, report) = clear_facets(
            &tree,
            &[DVec3::new(-0.5, 0.0, -0.5 * s), DVec3::new(-8.0, 0.0, -8.0 * s)],
            &[DVec3::Z, facet],
            &[0, 1],
            r,
            0.0,
            1e-3,
            f64::INFINITY,
        );
        let kept = (DVec3::new(-8.0, 0.0, -8.0 * s), facet);
        assert_eq!((report.moved, report.inserted, report.unresolved), (1, 0, 0));
        // The first centre now lies R from the left facet's plane and no nearer to the surface.
        let centre = cc[0] + r * normals[0];
        let plane_distance = centre.dot(facet);
        assert!((plane_distance - r).abs() < 1e-9, "{plane_distance}");
        assert!(tree.nearest(centre, r * (1.0 - 1e-8)).is_none());
        assert!(
            report.max_move_mm > 0.0 && (report.max_move_mm - r * (1.0 / 5f64.to_radians().cos() - 1.0)).abs() < 1e-9
        );
        // The contact is on the surface, the normal unit.
        assert!(tree.nearest(cc[0], 1e-12).is_some() && (normals[0].length() - 1.0).abs() < 1e-12);
        // A ball already clear of every facet is untouched.
        assert_eq!((cc[1], normals[1]), kept);
    }

    #[test]
    fn a_ball_allowed_to_dip_is_moved_only_past_that_depth() {
        let (positions, triangles) = ridge();
        let tree = FaceTree::new(&positions, &triangles);
        let (r, s) = (3.0, 5f64.to_radians().tan());
        let facet = DVec3::new(-s, 0.0, 1.0).normalize();
        let at = |x: f64| DVec3::new(x, 0.0, x * s);
        // Along the ridge's vertical normal the ball dips R(1 − cos 5°) = 11.4 µm into the left
        // facet half a millimetre off the ridge: allowed 20 µm, it stays; allowed 5 µm, it keeps
        // R − 5 µm from the facet's plane.
        let run = |dip: f64| clear_facets(&tree, &[at(-0.5)], &[DVec3::Z], &[0], r, dip, 1e-3, f64::INFINITY);
        let (cc, normals, report) = run(0.02);
        assert_eq!(report.moved, 0);
        assert_eq!((cc[0], normals[0]), (at(-0.5), DVec3::Z));
        let (cc, normals, report) = run(0.005);
        assert_eq!((report.moved, report.unresolved), (1, 0));
        let centre = cc[0] + r * normals[0];
        assert!((centre.dot(facet) - (r - 0.005)).abs() < 1e-9, "{}", centre.dot(facet));
        assert!(tree.nearest(centre, (r - 0.005) * (1.0 - 1e-8)).is_none());
    }

    /// The ridge turned over: a valley whose two facets rise 5° from the y axis.
    fn valley() -> FaceTree {
        let (mut positions, triangles) = ridge();
        positions.iter_mut().for_each(|p| p.z = -p.z);
        FaceTree::new(&positions, &triangles)
    }

    #[test]
    fn a_ball_in_a_concave_crease_settles_touching_both_facets() {
        let tree = valley();
        let r = 3.0;
        // Right on the crease with the vertical normal, the ball dips into both facets.
        let (cc, normals, report) = clear_facets(&tree, &[DVec3::ZERO], &[DVec3::Z], &[], r, 0.0, 1e-3, f64::INFINITY);
        assert_eq!((report.moved, report.unresolved), (1, 0));
        let centre = cc[0] + r * normals[0];
        // The ball of radius R in a symmetric 170° valley sits over the crease at R / cos 5°,
        // touching both facets.
        assert!(centre.x.abs() < 1e-9 && (centre.z - r / 5f64.to_radians().cos()).abs() < 1e-9, "{centre:?}");
        assert!(tree.nearest(centre, r * (1.0 - 1e-9)).is_none());
    }

    /// Issue 34 (gen015, 112, 133, 160 of the sweep): a ball lifted off its facet by more than
    /// the spacing plans for, beside a concave crease, is let down into the crease, where it
    /// leaves less over its contact; under that bound it is lifted as before.
    #[test]
    fn a_ball_lifted_beside_a_crease_is_let_down_into_it() {
        let tree = valley();
        let (r, s) = (3.0, 5f64.to_radians().tan());
        // 0.1 mm up the left flank with the crease's vertical normal: along it the ball dips
        // into its own facet and is lifted R(1/cos 5° − 1) = 11.5 µm, which it leaves over the
        // contact. Touching the flank there, it would cut the right one (the crease lets a ball
        // down to R·tan 5° = 0.26 mm from it): resting in the crease it leaves 4.4 µm.
        let p = DVec3::new(-0.1, 0.0, 0.1 * s);
        let run = |above: f64| clear_facets(&tree, &[p], &[DVec3::Z], &[0], r, 0.0, 1e-3, above);
        let lifted = r * (1.0 / 5f64.to_radians().cos() - 1.0);
        let (cc, normals, report) = run(0.02);
        let centre = cc[0] + r * normals[0];
        assert_eq!(report.moved, 1);
        assert!((centre.x - p.x).abs() < 1e-12 && (centre.distance(p) - r - lifted).abs() < 1e-9, "{centre:?}");
        let (cc, normals, report) = run(0.005);
        assert_eq!((report.moved, report.unresolved), (1, 0));
        let centre = cc[0] + r * normals[0];
        assert!(centre.x.abs() < 1e-9 && (centre.z - r / 5f64.to_radians().cos()).abs() < 1e-9, "{centre:?}");
        assert!((centre.distance(p) - r - 0.00437).abs() < 1e-5, "{}", centre.distance(p) - r);
        assert!(tree.nearest(centre, r * (1.0 - 1e-8)).is_none());
        // Far up the flank the ball touching there is clear: its contact is the point itself.
        let far = DVec3::new(-2.0, 0.0, 2.0 * s);
        let (cc, normals, _) = clear_facets(&tree, &[far], &[DVec3::Z], &[0], r, 0.0, 1e-3, 0.0);
        assert!(cc[0].distance(far) < 1e-12 && (normals[0] - DVec3::new(s, 0.0, 1.0).normalize()).length() < 1e-12);
    }

    /// Regression (issue 4, mech-holes-shark after the annulus map changed its path): two
    /// centres settling on the same point were both kept, and the toolpath refused the repeat.
    #[test]
    fn centres_settling_on_one_point_of_a_crease_are_merged() {
        let (mut positions, triangles) = ridge();
        for p in &mut positions {
            p.z = -p.z;
        }
        let tree = FaceTree::new(&positions, &triangles);
        let r = 3.0;
        // Either side of the crease, 40 nm apart, both with the vertical normal: each ball
        // rises out of the valley to the same height (mech's pair ended 8 nm apart), then the
        // next one is elsewhere.
        let s = 5f64.to_radians().tan();
        let cc = [DVec3::new(-2e-8, 0.0, 2e-8 * s), DVec3::new(2e-8, 0.0, 2e-8 * s), DVec3::new(0.0, 1.0, 0.0)];
        let (out, normals, report) = clear_facets(&tree, &cc, &[DVec3::Z; 3], &[], r, 0.0, 1e-3, f64::INFINITY);
        assert_eq!((report.moved, report.merged, out.len()), (3, 1, 2), "{report:?}");
        let centres: Vec<DVec3> = out.iter().zip(&normals).map(|(&p, &n)| p + r * n).collect();
        assert!((centres[1] - centres[0] - DVec3::Y).length() < 1e-6, "{centres:?}");
        // The path it makes is accepted.
        let options = crate::toolpath::ToolpathOptions { radius_mm: r, ..Default::default() };
        assert!(crate::toolpath::toolpath(&out, &normals, &options).is_ok());
    }

    #[test]
    fn a_straight_move_over_a_ridge_is_split_until_it_clears_the_facets() {
        let (positions, triangles) = ridge();
        let tree = FaceTree::new(&positions, &triangles);
        let (r, tol) = (3.0, 1e-3);
        let s = 5f64.to_radians().tan();
        let (left, right) = (DVec3::new(-s, 0.0, 1.0).normalize(), DVec3::new(s, 0.0, 1.0).normalize());
        // Two balls resting on either facet 2 mm from the ridge: the move between them passes
        // 0.2 mm inside the ridge's offset cylinder.
        let ends = [DVec3::new(-2.0, 0.0, -2.0 * s), DVec3::new(2.0, 0.0, -2.0 * s)];
        let (cc, normals, report) = clear_facets(&tree, &ends, &[left, right], &[0, 3], r, 0.0, tol, f64::INFINITY);
        // The ends are clear; every inserted midpoint had to be pushed out.
        assert_eq!((report.moved, report.unresolved), (report.inserted, 0));
        assert!(report.inserted > 2 && cc.len() == 2 + report.inserted, "{report:?}");
        assert_eq!((cc[0], *cc.last().unwrap()), (ends[0], ends[1]));
        let centres: Vec<DVec3> = cc.iter().zip(&normals).map(|(&p, &n)| p + r * n).collect();
        for w in centres.windows(2) {
            assert!(w[1].x > w[0].x, "path order");
            for k in 0..=64 {
                let c = w[0].lerp(w[1], k as f64 / 64.0);
                assert!(tree.nearest(c, r - 1.01 * tol).is_none(), "{c:?} dips into a facet");
            }
        }
    }
}
