//! From optimised poses to moves: densification and the program's structure.
//!
//! Densification. Between consecutive optimised poses of a strip the rails a(t), b(t) follow
//! cubic Hermite curves through the poses (Catmull–Rom tangents, three-point one-sided ones at
//! a strip's ends, so straight evenly spaced rails stay straight), and each interval is split evenly into as few
//! pieces as keep (a) the midpoint of every piece within `chord_tolerance_mm` of the straight
//! chord for both rails (what linear interpolation between two poses loses), and (b) the angle
//! between consecutive axes within `angle_tolerance_deg`. Every inserted pose is made rigid
//! about its midpoint (|b − a| = L).
//!
//! The program (one [`Toolpath`] for every post). Every strip is entered and left along the
//! surface normal: a feed move in from its approach point to its first pose
//! ([`MoveKind::Approach`], at the plunge feed), the cut through every pose ([`MoveKind::Cut`]),
//! a feed move out along the normal to the retract point ([`MoveKind::LeadOut`]). The approach
//! (retract) point of a pose is its tool tip moved `retract_mm` along the mean surface normal of
//! its two grid points. Between them the tool travels at rapid, and never straight down beside
//! the part: from the safe height it descends along its own axis to the first approach point
//! (the tool slides along itself, so only its tip end enters new space, `retract_mm` off the
//! surface); from one strip's retract point to the next strip's approach point it hops
//! straight when the caller's check finds the hop clear (with `zigzag` the hops are short,
//! between neighbouring strip ends), otherwise it retracts along its axis to the safe height,
//! crosses there, and descends along the next axis; after the last strip it retracts along its
//! axis to the safe height ([`MoveKind::Retract`]). An axis within [`MIN_AXIS_Z`] of horizontal
//! cannot reach the safe height along itself: such a pose is left and entered vertically
//! instead (the collision check says whether that is safe). With `zigzag` every other strip
//! runs backwards. A move's `tip` is the tool tip (the centre of the tip circle), `axis` the
//! unit axis towards the shank, `centre` the tip sphere's centre a.
//!
//! The safe height (+Z) is 10 mm above the highest point of the part and of every tool position
//! (tip and flute top); with the axis pointing up, the whole tool is above the part there.
//!
//! The [`Toolpath`] is the posts' plain input; its spiral-minded parts read as follows here:
//! `first_contact` is the first strip's first pose, `stats.cut_points` counts every strip's
//! poses and `stats.retractions` the strips (each ends with a lead-out), so
//! [`Toolpath::contact_moves`], one pass's slice, does not apply: [`assemble`]'s ranges give
//! each strip's moves.

use super::tool::{ConeTool, SphereFamily};
use crate::num;
use crate::toolpath::{Move, MoveKind, Tool, ToolShape, Toolpath, ToolpathStats};
use glam::DVec3;
use std::ops::Range;

/// Options of the densification and the program.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputOptions {
    pub chord_tolerance_mm: f64,
    pub angle_tolerance_deg: f64,
    pub retract_mm: f64,
    pub zigzag: bool,
    pub feed_mm_min: f64,
    pub plunge_feed_mm_min: f64,
    pub rapid_mm_min: f64,
    pub spindle_rpm: f64,
    pub tool_number: u32,
}

/// Smallest Z component of an axis the program retracts along (about 78° from vertical).
pub const MIN_AXIS_Z: f64 = 0.2;

/// Most pieces an interval between two optimised poses is split into.
const MAX_PIECES: usize = 4096;

/// The densified poses of one strip (module docs).
pub fn densify(rails: &[(DVec3, DVec3)], family: &SphereFamily, o: &OutputOptions) -> Vec<(DVec3, DVec3)> {
    let n = rails.len();
    if n < 2 {
        return rails.to_vec();
    }
    // Central differences inside; at the ends the three-point one-sided difference (exact for
    // quadratics, so a strip's first and last intervals are as accurate as the others).
    let tangent = |j: usize| -> (DVec3, DVec3) {
        let d = |p: &dyn Fn(usize) -> DVec3| {
            if n == 2 {
                p(1) - p(0)
            } else if j == 0 {
                0.5 * (-3.0 * p(0) + 4.0 * p(1) - p(2))
            } else if j == n - 1 {
                0.5 * (3.0 * p(n - 1) - 4.0 * p(n - 2) + p(n - 3))
            } else {
                0.5 * (p(j + 1) - p(j - 1))
            }
        };
        (d(&|k| rails[k].0), d(&|k| rails[k].1))
    };
    let max_angle = o.angle_tolerance_deg.to_radians();
    let mut out = vec![rails[0]];
    for j in 0..n - 1 {
        let (t0, t1) = (tangent(j), tangent(j + 1));
        let at = |u: f64| -> (DVec3, DVec3) {
            let (u2, u3) = (u * u, u * u * u);
            let (h00, h10, h01, h11) = (2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2);
            (
                h00 * rails[j].0 + h10 * t0.0 + h01 * rails[j + 1].0 + h11 * t1.0,
                h00 * rails[j].1 + h10 * t0.1 + h01 * rails[j + 1].1 + h11 * t1.1,
            )
        };
        let fits = |pieces: usize| -> bool {
            (0..pieces).all(|q| {
                let (u0, u1) = (q as f64 / pieces as f64, (q + 1) as f64 / pieces as f64);
                let (p0, p1, pm) = (at(u0), at(u1), at(0.5 * (u0 + u1)));
                let chord = (pm.0 - 0.5 * (p0.0 + p1.0)).length().max((pm.1 - 0.5 * (p0.1 + p1.1)).length());
                let (ax0, ax1) = ((p0.1 - p0.0).normalize(), (p1.1 - p1.0).normalize());
                chord <= o.chord_tolerance_mm && angle(ax0, ax1) <= max_angle
            })
        };
        let mut pieces = 1;
        while pieces < MAX_PIECES && !fits(pieces) {
            pieces = if pieces < 8 { pieces + 1 } else { pieces + pieces / 4 };
        }
        for q in 1..pieces {
            out.push(rigid(at(q as f64 / pieces as f64), family.length_mm));
        }
        out.push(rails[j + 1]);
    }
    out
}

/// The angle between two unit vectors, radians (stable for small angles).
pub fn angle(u: DVec3, v: DVec3) -> f64 {
    2.0 * num::atan2((u - v).length(), (u + v).length())
}

/// (a, b) moved apart or together along their axis about their midpoint to length `l`.
pub fn rigid((a, b): (DVec3, DVec3), l: f64) -> (DVec3, DVec3) {
    let (mid, u) = (0.5 * (a + b), (b - a).normalize());
    (mid - 0.5 * l * u, mid + 0.5 * l * u)
}

/// One strip ready for the program: its poses in cutting order and the retract directions at
/// its first and last pose.
#[derive(Clone, Debug, PartialEq)]
pub struct StripPoses {
    pub poses: Vec<(DVec3, DVec3)>,
    pub retract_first: DVec3,
    pub retract_last: DVec3,
}

/// The program of the strips (module docs) and, per strip, the range of its moves from the
/// approach's end (the first pose) to the last pose. `clear(from, to)`: whether the straight
/// rapid between two moves' poses is free of the part.
pub fn assemble(
    strips: &[StripPoses],
    tool: &ConeTool,
    family: &SphereFamily,
    part_top_z: f64,
    o: &OutputOptions,
    clear: &dyn Fn(&Move, &Move) -> bool,
) -> (Toolpath, Vec<Range<usize>>) {
    let pose_move = |kind: MoveKind, (a, b): (DVec3, DVec3), feed: f64| {
        let axis = (b - a).normalize();
        Move { kind, tip: family.tip(a, axis), axis, centre: a, feed_mm_min: feed }
    };
    let retract = |m: Move, dir: DVec3, kind: MoveKind, feed: f64| Move {
        kind,
        tip: m.tip + o.retract_mm * dir,
        centre: m.centre + o.retract_mm * dir,
        feed_mm_min: feed,
        ..m
    };
    // Each strip: its approach point, its moves from the first pose to the lead-out's end.
    let mut pieces: Vec<(Move, Vec<Move>)> = Vec::with_capacity(strips.len());
    for strip in strips {
        let first = pose_move(MoveKind::Approach, strip.poses[0], o.plunge_feed_mm_min);
        let mut moves = vec![first];
        moves.extend(strip.poses[1..].iter().map(|&p| pose_move(MoveKind::Cut, p, o.feed_mm_min)));
        let last = *moves.last().expect("a pose");
        moves.push(retract(last, strip.retract_last, MoveKind::LeadOut, o.feed_mm_min));
        pieces.push((retract(first, strip.retract_first, MoveKind::Rapid, o.rapid_mm_min), moves));
    }
    // Safe height: above the part and every tool position.
    let top = |m: &Move| m.tip.z.max((m.tip + tool.flute_length_mm * m.axis).z);
    let safe = pieces
        .iter()
        .flat_map(|(entry, moves)| std::iter::once(entry).chain(moves))
        .map(top)
        .fold(part_top_z, f64::max)
        + 10.0;
    // The move to the safe height along the axis of `m` (vertically when the axis is too flat).
    let up = |m: &Move, kind: MoveKind| {
        let lift =
            if m.axis.z >= MIN_AXIS_Z { m.axis * ((safe - m.tip.z) / m.axis.z) } else { DVec3::Z * (safe - m.tip.z) };
        Move { kind, tip: m.tip + lift, centre: m.centre + lift, feed_mm_min: o.rapid_mm_min, ..*m }
    };
    let mut moves = Vec::new();
    let mut ranges = Vec::new();
    for (entry, body) in pieces {
        match moves.last().copied() {
            None => moves.extend([up(&entry, MoveKind::Rapid), entry]),
            Some(left) if clear(&left, &entry) => moves.push(entry),
            Some(left) => moves.extend([up(&left, MoveKind::Rapid), up(&entry, MoveKind::Rapid), entry]),
        }
        ranges.push(moves.len()..moves.len() + body.len() - 1);
        moves.extend(body);
    }
    let exit = up(moves.last().expect("moves"), MoveKind::Retract);
    moves.push(exit);
    let stats = stats(&moves, &ranges, safe, strips.len());
    let toolpath = Toolpath {
        moves,
        stats,
        tool: Tool {
            number: o.tool_number,
            radius_mm: tool.tip_radius_mm,
            spindle_rpm: o.spindle_rpm,
            shape: ToolShape::Cone {
                tip_radius_mm: tool.tip_radius_mm,
                top_radius_mm: tool.top_radius_mm,
                flute_length_mm: tool.flute_length_mm,
            },
        },
        first_contact: ranges[0].start,
    };
    (toolpath, ranges)
}

fn stats(moves: &[Move], ranges: &[Range<usize>], safe: f64, strips: usize) -> ToolpathStats {
    let max_axis_step_deg = ranges
        .iter()
        .flat_map(|r| moves[r.clone()].windows(2).map(|w| angle(w[0].axis, w[1].axis).to_degrees()))
        .fold(0.0, f64::max);
    let cut_points = ranges.iter().map(|r| r.len()).sum();
    crate::toolpath::stats_of_moves(moves, cut_points, strips, max_axis_step_deg, safe)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options() -> OutputOptions {
        OutputOptions {
            chord_tolerance_mm: 1e-3,
            angle_tolerance_deg: 0.5,
            retract_mm: 5.0,
            zigzag: true,
            feed_mm_min: 1000.0,
            plunge_feed_mm_min: 300.0,
            rapid_mm_min: 5000.0,
            spindle_rpm: 10000.0,
            tool_number: 2,
        }
    }

    /// Poses rotating about the Z axis (a tool flanking a cylinder): the inserted poses keep the
    /// rails within the chord tolerance of the circles and the axis steps within the angle.
    #[test]
    fn densified_rails_stay_within_the_tolerances() {
        let tool = ConeTool { tip_radius_mm: 2.0, top_radius_mm: 3.0, flute_length_mm: 15.0 };
        let family = tool.spheres().unwrap();
        let (ra, rb) = (30.0 + family.r1_mm, 30.0 + family.r2_mm);
        let zb = (family.length_mm.powi(2) - (rb - ra).powi(2)).sqrt();
        let pose = |t: f64| {
            let (s, c) = crate::num::sin_cos(t);
            (DVec3::new(ra * c, ra * s, 0.0), DVec3::new(rb * c, rb * s, zb))
        };
        let rails: Vec<_> = (0..11).map(|j| pose(0.1 * j as f64)).collect();
        let o = options();
        let dense = densify(&rails, &family, &o);
        assert!(dense.len() > 11 * 5, "{}", dense.len());
        // The chords stay within the tolerance of the spline, which itself is within 2e-4 of the
        // circle at this spacing (0.1 rad).
        for w in dense.windows(2) {
            let mid = 0.5 * (w[0].0 + w[1].0);
            assert!((mid.truncate().length() - ra).abs() <= 1.2e-3, "chord {}", ra - mid.truncate().length());
            let (u, v) = ((w[0].1 - w[0].0).normalize(), (w[1].1 - w[1].0).normalize());
            assert!(angle(u, v).to_degrees() <= 0.5 + 1e-9);
        }
        for p in &dense {
            assert!((p.0.distance(p.1) - family.length_mm).abs() < 1e-12);
            assert!((p.0.truncate().length() - ra).abs() < 2e-4, "on the circle: {}", p.0.truncate().length() - ra);
        }
        // Straight evenly spaced rails gain nothing.
        let line: Vec<_> =
            (0..4).map(|j| (DVec3::new(j as f64, 0.0, 0.0), DVec3::new(j as f64, family.length_mm, 0.0))).collect();
        assert_eq!(densify(&line, &family, &o), line);

        let strips = vec![
            StripPoses { poses: dense.clone(), retract_first: DVec3::X, retract_last: DVec3::X },
            StripPoses {
                poses: dense.iter().rev().copied().collect(),
                retract_first: DVec3::X,
                retract_last: DVec3::X,
            },
        ];
        let (tp, ranges) = assemble(&strips, &tool, &family, 0.0, &o, &|_, _| true);
        assert_eq!(ranges.len(), 2);
        assert_eq!(ranges[0].len(), dense.len());
        assert_eq!(tp.moves[ranges[0].start].kind, MoveKind::Approach);
        assert_eq!(tp.moves.last().unwrap().kind, MoveKind::Retract);
        for m in &tp.moves {
            assert!((m.axis.length() - 1.0).abs() < 1e-12);
            assert!(family.a_of_tip(m.tip, m.axis).distance(m.centre) < 1e-9);
        }
        assert_eq!(tp.stats.cut_points, 2 * dense.len());
        assert!(tp.moves[0].tip.z >= tp.stats.safe_z_mm - 1e-12);
        // A clear hop goes straight from the lead-out's end to the next approach point.
        let lead_out = ranges[0].end;
        assert_eq!(tp.moves[lead_out].kind, MoveKind::LeadOut);
        assert_eq!(ranges[1].start, lead_out + 2);

        // Links the check refuses go up along the axis, across at the safe height, down along
        // the next axis; entry and exit along the axis too, never vertically beside the part.
        let (tp, ranges) = assemble(&strips, &tool, &family, 0.0, &o, &|_, _| false);
        assert_eq!(ranges[1].start, ranges[0].end + 4);
        let safe = tp.stats.safe_z_mm;
        let along_axis = |p: &Move, q: &Move| {
            let d = q.tip - p.tip;
            p.axis == q.axis && d.cross(p.axis).length() < 1e-9 * d.length().max(1.0)
        };
        let m = &tp.moves;
        assert!((m[0].tip.z - safe).abs() < 1e-9 && along_axis(&m[0], &m[1]));
        let l = ranges[0].end;
        assert!(along_axis(&m[l], &m[l + 1]) && (m[l + 1].tip.z - safe).abs() < 1e-9);
        assert!((m[l + 2].tip.z - safe).abs() < 1e-9 && along_axis(&m[l + 2], &m[l + 3]));
        assert_eq!(m[l + 4].kind, MoveKind::Approach);
        let n = m.len();
        assert!(along_axis(&m[n - 2], &m[n - 1]) && (m[n - 1].tip.z - safe).abs() < 1e-9);
        // Approach and lead-out run along the surface normal (here +X), retract_mm long.
        for (p, q) in [(&m[1], &m[2]), (&m[l - 1], &m[l])] {
            assert!(((q.tip - p.tip).abs() - DVec3::new(o.retract_mm, 0.0, 0.0)).length() < 1e-9);
        }
    }
}
