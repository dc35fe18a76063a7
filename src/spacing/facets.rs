//! The balls' lift off exact facets, as the spacing plans for it: where the interpolated normal
//! tilts from a facet's, the toolpath moves each ball centre out along it until no facet is nearer
//! than R ([`crate::toolpath::clear_facets`]), and the scallop beside that ball rises by as much.
//! The spacing moves its rings' centres out by the same lift (within [`LIFT_FREE`]·h left to the
//! target's margin, and at most [`LIFT_CAP`]·h), and certifies once per face the faces none of
//! whose balls lifts at all ([`face_lifts_free`]).

use super::{Lifted, Spacer};
use crate::mesh::nearest::FaceTree;
use crate::mesh::Surface;
use glam::DVec3;

/// Lifts off the facets up to this fraction of h are left to the target's margin. That margin (1 −
/// [`GATE_FRACTION`](super::GATE_FRACTION)) is mostly the path's chords' (the gate's polylines
/// within [`GATE_SAG`](super::GATE_SAG)·h, the spiral's within 0.03 h along the normal), so only
/// the smallest lifts are left to it. At 0.1 h plate_holes kept 1.075 h (pole `hole:5`, where the
/// refinement tilts the flat top's normals 2.2°) and wavy_mesh_with_hole 1.81 h beside its creases
/// (now 0.95 and 1.35 h, for 1.6 % and 8 % more path). The 40k-face panel's lifts stay free (its
/// G-code is the same as without them), but some of its facets lift a ball by more, so its rings'
/// centres are still cleared (2.4 million clearances per plan: docs/benchmarks.md).
pub(super) const LIFT_FREE: f64 = 0.03;
/// A face's balls are certified free ([`face_lifts_free`]) when its own tilt and its sampled
/// balls lift them by at most this fraction of the free lift.
const FREE_SAMPLED: f64 = 0.5;
/// A face's corners, edge midpoints and centroid (barycentric): where [`face_lifts_free`]
/// clears a face's balls, and where the gate measures a face's slack in a spread field.
pub(super) const FACE_SAMPLES: [[f64; 3]; 7] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
];
/// Lifts are planned for up to this fraction of h.
pub const LIFT_CAP: f64 = 0.65;

/// With exact facets, a ball the clearance lifts by more than this over its contact (the most
/// the spacing plans for, [`LIFT_CAP`]·h) is let down into the crease beside it instead when
/// that leaves less ([`crate::mesh::nearest::FaceTree::rest_ball`]): the toolpath's
/// ([`crate::toolpath::clear_facets`]) and the spacing's balls alike.
pub fn rest_above_mm(h: f64) -> f64 {
    LIFT_CAP * h
}
/// Where the facets alone leave more than this fraction of h (a ball touching there lifts by
/// more), the verifier reports a facet valley: no ring reaches into it.
pub const LIFT_VALLEY: f64 = 0.75;

/// The part of a ball's lift `lift` off the facets the spacing plans for (see
/// [`cleared_lift_mm`]). A ball in a facet valley (lifted by more than [`LIFT_VALLEY`]·h) still
/// rides at least [`LIFT_CAP`]·h higher: gen198's rings lifted 0.71–0.78 h, and the band between
/// them kept 1.06 h when the valley's balls were planned on the surface.
pub(super) fn planned_lift_mm(lift: f64, h: f64) -> f64 {
    (lift - LIFT_FREE * h).clamp(0.0, LIFT_CAP * h)
}

/// With exact facets, how much higher than on the surface's offset the ball of radius `r`
/// touching at `p` (face `face`, interpolated normal `n`) rides, and the direction from the
/// contact to its centre: placed along n it dips into the facet whose normal is tilted by α from
/// n (and, at a concave edge, its neighbour), and the toolpath moves it out along n until no facet
/// is nearer than R ([`crate::toolpath::clear_facets`], R(1/cos α − 1) off one facet's plane):
/// the same clearance is run here. The first [`LIFT_FREE`]·h of it is left to the target's margin
/// and at most [`LIFT_CAP`]·h is planned for ([`planned_lift_mm`]). The rings' centres are moved
/// out by it, so that a band is tested against the balls that will cut it. Lowering the points
/// tested by the lift of a ball touching *there* instead missed the cutting balls' own (gen001,
/// 146 and 198 of issue 34's sweep kept 1.01–1.06 h), and the contact facet's R(1/cos α − 1)
/// alone, which jumps at every edge, left gen198 1.10 h where the ball rests on an edge.
///
/// A ball lifted more than [`LIFT_CAP`]·h is replaced, as the toolpath replaces it, by the ball
/// touching the contact's own facet there, let down into the crease beside it
/// ([`FaceTree::rest_ball`]) when that leaves less over the contact: its centre's direction from
/// the contact and its height over the offset.
pub(super) fn cleared_lift_mm(faces: &FaceTree, p: DVec3, n: DVec3, face: usize, r: f64, h: f64) -> (DVec3, f64) {
    let start = p + n * r;
    let ball = faces.clear_ball(start, n, r, Some(face), true);
    let over = |c: DVec3| c.distance(p) - r;
    if ball.rounds > 0 && over(ball.centre) > rest_above_mm(h) {
        if let Some(rest) = faces.rest_below(&ball, p, face, r) {
            let to = rest.centre - p;
            return (to / to.length(), over(rest.centre));
        }
    }
    (n, (ball.centre - start).dot(n))
}

/// Whether every ball of radius `r` touching face `face` lifts by at most [`LIFT_FREE`]·h
/// ([`cleared_lift_mm`]), so that none plans a lift and its centre is the offset's. The face's
/// own tilt lifts them by at most [`crate::mesh::Surface::face_lift_mm`] (exact); the other
/// facets within reach are sampled: balls touching at [`FACE_SAMPLES`] points, cleared of every
/// facet, must lift by at most [`FREE_SAMPLED`] of the free lift (the lifts of one face's
/// contacts vary smoothly, and the margin covers what lies between the samples). Most balls of a
/// smooth part touch such faces; settling them here saves the clearance search the spacing
/// would run for each (2.3 million on the 40k-face panel: 0.8 s of its 2.4 s).
pub(super) fn face_lifts_free(surface: &Surface, faces: &FaceTree, face: usize, r: f64, h: f64) -> bool {
    let bound = FREE_SAMPLED * LIFT_FREE * h;
    if !(surface.face_lift_mm(face, r) <= bound) {
        return false;
    }
    let [a, b, c] = surface.triangles[face].map(|v| surface.positions[v as usize]);
    FACE_SAMPLES.iter().all(|&bary| {
        let n = surface.normal_at(face, bary);
        let (dir, lift) = cleared_lift_mm(faces, a * bary[0] + b * bary[1] + c * bary[2], n, face, r, h);
        dir == n && lift <= bound
    })
}

/// Whether a ball on some facet of `surface` lifts by more than [`LIFT_FREE`]·h.
pub(super) fn lifts_off_facets(surface: &Surface, r: f64, h: f64) -> bool {
    (0..surface.triangles.len()).any(|f| !(surface.face_lift_mm(f, r) <= LIFT_FREE * h))
}

impl Spacer<'_> {
    /// The centre of the ball touching at `l`, moved out by its planned lift off the facets
    /// ([`cleared_lift_mm`]), as the toolpath will move it: the offset's on a face whose balls
    /// are certified free.
    pub(super) fn ball_centre(&self, l: &Lifted) -> DVec3 {
        let Some(h) = self.lift_h else { return l.p + l.n * self.ball };
        if self.free_face(l.face as usize, h) {
            return l.p + l.n * self.ball;
        }
        let (dir, lift) = cleared_lift_mm(self.gate.faces(), l.p, l.n, l.face as usize, self.ball, h);
        l.p + dir * (self.ball + planned_lift_mm(lift, h))
    }

    /// Whether every ball touching face `face` is certified free ([`face_lifts_free`]): settled
    /// once per face, on first use.
    pub(super) fn free_face(&self, face: usize, h: f64) -> bool {
        *self.free[face].get_or_init(|| face_lifts_free(self.surface, self.gate.faces(), face, self.ball, h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_planned_lift_is_the_cleared_balls_lift_within_its_band() {
        // A ball of radius R along a normal tilted by α from its facet's is moved out by
        // R(1/cos α − 1) by the clearance (then it touches the facet's plane); the spacing plans
        // that lift less the free part, up to the cap, in facet valleys too.
        let (r, h) = (3.0, 0.02);
        let positions = [DVec3::new(-50.0, -50.0, 0.0), DVec3::new(50.0, -50.0, 0.0), DVec3::new(0.0, 50.0, 0.0)];
        let tree = FaceTree::new(&positions, &[[0, 1, 2]]);
        let tilted = |deg: f64| DVec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
        let planned = |deg: f64| {
            let n = tilted(deg);
            let start = n * r;
            let ball = tree.clear_ball(start, n, r, Some(0), true);
            let lift = (ball.centre - start).dot(n);
            assert!((lift - crate::mesh::ball_lift_mm(n, DVec3::Z, r)).abs() < 1e-8 * r, "{deg}°: lift {lift}");
            planned_lift_mm(lift, h)
        };
        for deg in [0.0f64, 2.0, 4.0, 5.0, 5.5, 6.0, 7.0, 10.0, 60.0] {
            let lift = crate::mesh::ball_lift_mm(tilted(deg), DVec3::Z, r);
            let expected = (lift - LIFT_FREE * h).clamp(0.0, LIFT_CAP * h);
            assert!(
                (planned(deg) - expected).abs() < 1e-8 * r,
                "{deg}°: {} mm planned, {expected} expected",
                planned(deg)
            );
        }
        // 1° lifts 0.46 µm (< 0.03 h: left to the margin); 5° lifts 11.5 µm: planned; 10°
        // (a valley: 2.3 h) is planned up to the cap, not dropped.
        assert_eq!(planned(1.0), 0.0);
        assert!(planned(2.0) > 0.05 * h);
        assert!(planned(5.0) > 0.4 * h);
        assert_eq!(planned(10.0), LIFT_CAP * h);
        // A normal facing away from the facet (a fold) rides as high as planned at most.
        assert_eq!(planned_lift_mm(f64::INFINITY, h), LIFT_CAP * h);
    }

    #[test]
    fn a_face_certified_free_lifts_no_ball_it_touches_beyond_the_free_lift() {
        // Brute force: balls touching certified faces at random points, each cleared of every
        // facet, lift by at most LIFT_FREE·h and along their own normal, on generated parts with
        // staircase rims and skinny triangles, where many faces are not free.
        let mut rng = crate::fixtures::SplitMix64(45);
        let (mut certified, mut faces) = (0, 0);
        for (seed, r, h) in [
            (0, 1.75, 0.0064),
            (30, 1.89, 0.005),
            (114, 3.0, 0.02),
            (31, 2.22, 0.0185),
            (5, 2.5, 0.01),
            (24, 4.0, 0.008),
        ] {
            let part = crate::fixtures::generated::part(seed, 3_000..=3_000);
            let surface = crate::mesh::from_triangles(&part.mesh, &Default::default())
                .unwrap()
                .surface
                .with_crease_normals(crate::plan::CREASE_SPLIT_DEG);
            let tree = FaceTree::new(&surface.positions, &surface.triangles);
            let free: Vec<usize> =
                (0..surface.triangles.len()).filter(|&f| face_lifts_free(&surface, &tree, f, r, h)).collect();
            (certified, faces) = (certified + free.len(), faces + surface.triangles.len());
            for &f in &free {
                let [a, b, c] = surface.triangles[f].map(|v| surface.positions[v as usize]);
                // 128 balls a face: a looser rule (the own tilt up to the whole free lift) passed
                // with 8 and failed with 32 (beside an edge of gen000, 1.05 times the free lift).
                for _ in 0..128 {
                    let (u, v) = (rng.unit(), rng.unit());
                    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                    let bary = [1.0 - u - v, u, v];
                    let n = surface.normal_at(f, bary);
                    let (dir, lift) = cleared_lift_mm(&tree, a * bary[0] + b * bary[1] + c * bary[2], n, f, r, h);
                    assert!(dir == n && planned_lift_mm(lift, h) == 0.0, "gen{seed} face {f} at {bary:?}: lift {lift}");
                }
            }
        }
        // Both kinds are common: the test sees many of each.
        assert!(certified > faces / 5 && faces - certified > faces / 5, "{certified} of {faces} faces free");
    }
}
