//! Integration tests of the toolpath stage on synthetic contact spirals with exact normals
//! (`fixtures::contact_spiral`): ball centres on the exact offset surface, tips, 5-axis lead and
//! tilt, entry/exit geometry, safe height, stats, typed errors, determinism.
// Native only: runs rs274 / reads files / uses serde_json (the browser tests are tests/wasm.rs).
#![cfg(not(target_arch = "wasm32"))]

use glam::DVec3;
use slitpath::fixtures::{contact_spiral, ContactPath, ContactSurface};
use slitpath::toolpath::{toolpath, Axes, MoveKind, Toolpath, ToolpathError, ToolpathOptions};

fn cap() -> ContactPath {
    contact_spiral(ContactSurface::SphericalCap, 35.0, 5.0, 2.0, 0.5)
}

fn saddle() -> ContactPath {
    contact_spiral(ContactSurface::Saddle, 38.0, 4.0, 2.5, 0.6)
}

fn plan(path: &ContactPath, options: &ToolpathOptions) -> Toolpath {
    toolpath(&path.cc, &path.normals, options).expect("plan the synthetic path")
}

fn five(lead_deg: f64, tilt_deg: f64) -> ToolpathOptions {
    ToolpathOptions { axes: Axes::Five { lead_deg, tilt_deg }, ..Default::default() }
}

/// The moves come in the documented order, with one retract, and the contact moves line up with
/// the input points.
fn assert_structure(tp: &Toolpath, path: &ContactPath, radius: f64) {
    let kinds: Vec<MoveKind> = tp.moves.iter().map(|m| m.kind).collect();
    let rank = |k: MoveKind| match k {
        MoveKind::Rapid => 0,
        MoveKind::Approach => 1,
        MoveKind::Cut => 2,
        MoveKind::LeadOut => 3,
        MoveKind::Retract => 4,
    };
    assert!(kinds.windows(2).all(|w| rank(w[0]) <= rank(w[1])), "moves out of order");
    assert_eq!(&kinds[..2], &[MoveKind::Rapid, MoveKind::Rapid]);
    assert_eq!(kinds.last(), Some(&MoveKind::Retract));
    assert_eq!(kinds.iter().filter(|&&k| k == MoveKind::Retract).count(), 1);
    assert_eq!(tp.stats.retractions, 1);
    assert_eq!(tp.stats.cut_points, path.cc.len());
    let contacts = tp.contact_moves();
    assert_eq!(contacts.len(), path.cc.len());
    assert_eq!(contacts[0].kind, MoveKind::Approach);
    assert!(contacts[1..].iter().all(|m| m.kind == MoveKind::Cut));
    for (i, m) in contacts.iter().enumerate() {
        let centre = path.cc[i] + radius * path.normals[i];
        assert!(m.centre.distance(centre) < 1e-12, "centre {i}");
        assert!(m.tip.distance(centre - radius * m.axis) < 1e-12, "tip {i}");
    }
    for m in &tp.moves {
        assert!((m.axis.length() - 1.0).abs() < 1e-12);
        assert!(m.centre.distance(m.tip + radius * m.axis) < 1e-12);
    }
}

#[test]
fn three_axis_centres_lie_on_the_exact_offset_surface() {
    let path = cap();
    let o = ToolpathOptions::default();
    let tp = plan(&path, &o);
    assert_structure(&tp, &path, o.radius_mm);
    let (centre, r) = ContactSurface::sphere_centre_and_radius();
    for m in tp.contact_moves() {
        assert!((m.centre.distance(centre) - (r + o.radius_mm)).abs() < 1e-9);
        assert_eq!(m.axis, DVec3::Z);
    }
    assert_eq!(tp.stats.max_axis_step_deg, 0.0);
}

#[test]
fn stats_are_the_true_lengths_and_times() {
    let path = saddle();
    let o = ToolpathOptions::default();
    let tp = plan(&path, &o);
    assert_structure(&tp, &path, o.radius_mm);
    let tips: Vec<DVec3> = tp.contact_moves().iter().map(|m| m.tip).collect();
    let cut: f64 = tips.windows(2).map(|w| w[0].distance(w[1])).sum();
    assert!((tp.stats.cut_length_mm - cut).abs() < 1e-9 * cut);
    let (mut rapid, mut link, mut minutes) = (0.0, 0.0, 0.0);
    for w in tp.moves.windows(2) {
        let d = w[0].tip.distance(w[1].tip);
        let f = match w[1].kind {
            MoveKind::Rapid | MoveKind::Retract => {
                rapid += d;
                o.rapid_mm_min
            }
            MoveKind::Approach => {
                link += d;
                o.plunge_feed_mm_min
            }
            MoveKind::LeadOut => {
                link += d;
                o.feed_mm_min
            }
            MoveKind::Cut => o.feed_mm_min,
        };
        assert_eq!(w[1].feed_mm_min, f);
        minutes += d / f;
    }
    assert!((tp.stats.rapid_length_mm - rapid).abs() < 1e-9);
    assert!((tp.stats.link_length_mm - link).abs() < 1e-9);
    assert!((tp.stats.estimated_time_s - 60.0 * minutes).abs() < 1e-9);
    // The cut at 1000 mm/min dominates the time.
    assert!(tp.stats.estimated_time_s > 60.0 * cut / o.feed_mm_min);
    println!(
        "saddle spiral: {} points, cut {:.1} mm, links {:.1} mm, rapids {:.1} mm, {:.1} s",
        tp.stats.cut_points,
        tp.stats.cut_length_mm,
        tp.stats.link_length_mm,
        tp.stats.rapid_length_mm,
        tp.stats.estimated_time_s
    );
}

#[test]
fn five_axis_axis_has_the_lead_and_tilt_and_is_smooth() {
    let path = cap();
    for (lead, tilt) in [(15.0_f64, 0.0_f64), (10.0, 5.0), (-8.0, -12.0)] {
        let o = five(lead, tilt);
        let tp = plan(&path, &o);
        assert_structure(&tp, &path, o.radius_mm);
        let contacts = tp.contact_moves();
        let last = path.cc.len() - 1;
        for (i, m) in contacts.iter().enumerate() {
            let n = path.normals[i];
            let d = path.cc[(i + 1).min(last)] - path.cc[i.saturating_sub(1)];
            let t = (d - d.dot(n) * n).normalize();
            let b = t.cross(n);
            let (sb, cb) = (lead.to_radians().sin(), lead.to_radians().cos());
            let (sg, cg) = (tilt.to_radians().sin(), tilt.to_radians().cos());
            assert!((m.axis.dot(t) - sb).abs() < 1e-12, "lead at {i}");
            assert!((m.axis.dot(b) - cb * sg).abs() < 1e-12, "tilt at {i}");
            assert!((m.axis.dot(n) - cb * cg).abs() < 1e-12, "normal part at {i}");
        }
        // Smooth: consecutive axes of a 0.5 mm-step spiral differ by little, and the stat says so.
        let max_step = contacts
            .windows(2)
            .map(|w| w[0].axis.dot(w[1].axis).clamp(-1.0, 1.0).acos().to_degrees())
            .fold(0.0, f64::max);
        assert!((tp.stats.max_axis_step_deg - max_step).abs() < 1e-9);
        assert!(max_step < 6.0, "axis jumps {max_step}° between points (lead {lead}, tilt {tilt})");
        println!("5-axis lead {lead}° tilt {tilt}°: max axis step {max_step:.3}° per point");
    }
}

/// The lead-in never dips below the first tip (no plunge into the surface), whichever way the
/// cut starts; the lead-out never dips below the last tip; the entry/exit heights are right.
#[test]
fn lead_in_and_out_stay_above_the_surface_ends() {
    let mut cases = vec![cap(), saddle()];
    // The reversed spirals start going outwards: downhill on the cap, up or down on the saddle.
    for p in cases.clone() {
        cases.push(ContactPath {
            cc: p.cc.iter().rev().copied().collect(),
            normals: p.normals.iter().rev().copied().collect(),
        });
    }
    for (k, path) in cases.iter().enumerate() {
        for o in [ToolpathOptions::default(), five(15.0, 0.0)] {
            let tp = plan(path, &o);
            let contacts = tp.contact_moves();
            let (first, last) = (contacts[0].tip, contacts[contacts.len() - 1].tip);
            let up = DVec3::Z; // the +Z tool axis (3-axis) and the 5-axis height direction
            let approach: Vec<_> = tp.moves.iter().filter(|m| m.kind == MoveKind::Approach).collect();
            assert_eq!(approach.len(), 1 + 16, "descent + 16 arc segments (the last ends at the first tip)");
            for m in &approach {
                assert!(m.tip.dot(up) >= first.dot(up) - 1e-12, "case {k}: lead-in below the first tip");
            }
            for m in tp.moves.iter().filter(|m| m.kind == MoveKind::LeadOut) {
                assert!(m.tip.dot(up) >= last.dot(up) - 1e-12, "case {k}: lead-out below the last tip");
            }
            // Entry: rapid at the safe height above the lead-in start, rapid to clearance above it.
            let start = approach[0].tip;
            let safe = tp.stats.safe_z_mm;
            assert!((tp.moves[0].tip.z - safe).abs() < 1e-12);
            assert!(tp.moves[0].tip.truncate().distance(start.truncate()) < 1e-12);
            assert!(tp.moves[1].tip.distance(start + o.clearance_mm * DVec3::Z) < 1e-12);
            assert!((tp.moves.last().unwrap().tip.z - safe).abs() < 1e-12);
            // The lead-in is tangent to the first cut segment when the cut starts level or
            // downhill (within half an arc segment of 90°/16), and has the documented length.
            let arc_end = (first - approach[approach.len() - 2].tip).normalize();
            let cut_dir = (contacts[1].tip - first).normalize();
            if cut_dir.z <= 0.0 && cut_dir.z > -0.7 {
                assert!(arc_end.angle_between(cut_dir).to_degrees() < 2.9, "case {k}: lead-in not tangent");
            }
            let arc: f64 = approach.windows(2).map(|w| w[0].tip.distance(w[1].tip)).sum();
            assert!((arc - 2.0 * o.radius_mm).abs() < 0.01, "lead-in length {arc}");
            // Safe height default: 10 mm above the highest feed move or contact point.
            let feeds = tp.moves.iter().filter(|m| !m.kind.is_rapid()).map(|m| m.tip.z);
            let top = feeds.chain(path.cc.iter().map(|p| p.z)).fold(f64::NEG_INFINITY, f64::max);
            assert!((safe - top - 10.0).abs() < 1e-9, "case {k}: safe {safe} vs top {top}");
        }
    }
}

#[test]
fn safe_height_option_is_used_or_rejected() {
    let path = cap();
    let tp = plan(&path, &ToolpathOptions { safe_z_mm: Some(50.0), ..Default::default() });
    assert_eq!(tp.stats.safe_z_mm, 50.0);
    assert_eq!(tp.moves[0].tip.z, 50.0);
    let err = toolpath(&path.cc, &path.normals, &ToolpathOptions { safe_z_mm: Some(10.0), ..Default::default() });
    match err {
        Err(ToolpathError::SafeHeightTooLow { safe_z_mm, highest_mm, required_mm, .. }) => {
            assert_eq!(safe_z_mm, 10.0);
            assert!(highest_mm > 15.0 && (required_mm - highest_mm - 2.0).abs() < 1e-12);
        }
        other => panic!("expected SafeHeightTooLow, got {other:?}"),
    }
}

#[test]
fn deterministic() {
    let path = saddle();
    for o in [ToolpathOptions::default(), five(15.0, 3.0)] {
        assert_eq!(plan(&path, &o), plan(&path, &o));
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let path = cap();
    let (cc, n) = (&path.cc[..], &path.normals[..]);
    let run = |o: ToolpathOptions| toolpath(cc, n, &o).unwrap_err();
    let field = |e: ToolpathError| match e {
        ToolpathError::InvalidOption { field, .. } => field,
        other => panic!("expected InvalidOption, got {other:?}"),
    };
    let d = ToolpathOptions::default;
    assert_eq!(field(run(ToolpathOptions { radius_mm: 0.0, ..d() })), "radius_mm");
    assert_eq!(field(run(ToolpathOptions { radius_mm: f64::NAN, ..d() })), "radius_mm");
    assert_eq!(field(run(ToolpathOptions { feed_mm_min: -1.0, ..d() })), "feed_mm_min");
    assert_eq!(field(run(ToolpathOptions { plunge_feed_mm_min: 0.0, ..d() })), "plunge_feed_mm_min");
    assert_eq!(field(run(ToolpathOptions { rapid_mm_min: f64::INFINITY, ..d() })), "rapid_mm_min");
    assert_eq!(field(run(ToolpathOptions { spindle_rpm: 0.0, ..d() })), "spindle_rpm");
    assert_eq!(field(run(ToolpathOptions { clearance_mm: 0.0, ..d() })), "clearance_mm");
    assert_eq!(field(run(ToolpathOptions { lead_in_mm: Some(-2.0), ..d() })), "lead_in_mm");
    assert_eq!(field(run(ToolpathOptions { safe_z_mm: Some(f64::NAN), ..d() })), "safe_z_mm");
    assert_eq!(field(run(ToolpathOptions { tool_number: 0, ..d() })), "tool_number");
    assert_eq!(field(run(five(90.0, 0.0))), "lead_deg");
    assert_eq!(field(run(five(15.0, f64::NAN))), "tilt_deg");
    assert!(matches!(
        run(ToolpathOptions { axes: Axes::Three { axis: DVec3::ZERO }, ..d() }),
        ToolpathError::InvalidToolAxis { .. }
    ));

    let o = ToolpathOptions::default();
    assert_eq!(toolpath(&cc[..1], &n[..1], &o), Err(ToolpathError::TooFewPoints { count: 1 }));
    assert_eq!(
        toolpath(cc, &n[1..], &o),
        Err(ToolpathError::LengthMismatch { points: cc.len(), normals: cc.len() - 1 })
    );
    let mut bad = cc.to_vec();
    bad[3].y = f64::NAN;
    assert_eq!(toolpath(&bad, n, &o), Err(ToolpathError::NonFinitePoint { index: 3 }));
    let mut bad_n = n.to_vec();
    bad_n[5] *= 1.1;
    assert!(matches!(toolpath(cc, &bad_n, &o), Err(ToolpathError::NotUnitNormal { index: 5, .. })));
    let mut rep = cc.to_vec();
    rep[4] = rep[3];
    let mut rep_n = n.to_vec();
    rep_n[4] = rep_n[3];
    assert!(matches!(toolpath(&rep, &rep_n, &o), Err(ToolpathError::RepeatedPoint { index: 4, .. })));
    // The same contact under another normal is a ball rolling over a vertex: its centre moves.
    assert_ne!(n[4], n[3]);
    assert!(toolpath(&rep, n, &o).is_ok());
    let mut under = n.to_vec();
    under[2] = -DVec3::Z;
    assert!(matches!(toolpath(cc, &under, &o), Err(ToolpathError::Undercut { index: 2, .. })));
    // 5-axis: a path that runs along its own normal has no feed direction in the tangent plane.
    let column: Vec<DVec3> = (0..4).map(|k| DVec3::new(0.0, 0.0, k as f64)).collect();
    assert_eq!(toolpath(&column, &[DVec3::Z; 4], &five(15.0, 0.0)), Err(ToolpathError::FeedAlongNormal { index: 0 }));
    // Messages name the fault.
    let msg = run(ToolpathOptions { radius_mm: -3.0, ..d() }).to_string();
    assert!(msg.contains("radius_mm") && msg.contains("-3"), "{msg}");
}

/// camelhead (R 0.05 mm, 5 axes) failed with "the ball centre … repeats the previous one": two
/// centres 1e-7 mm apart shared a tip. With the axis along the normal (no lead, no tilt) a ball
/// rolling over a vertex keeps its tip on the vertex while its axis turns: a move in place, which
/// the toolpath keeps; the lead-in and lead-out still have their directions.
#[test]
fn camelhead_five_axis_a_ball_turning_about_its_tip_is_a_move_in_place() {
    let path = cap();
    let (mut cc, n) = (path.cc.clone(), &path.normals[..]);
    for k in [1, 4, cc.len() - 1] {
        cc[k] = cc[k - 1];
        assert_ne!(n[k], n[k - 1]);
    }
    let tp = toolpath(&cc, n, &five(0.0, 0.0)).expect("a 5-axis turn in place plans");
    let moves = tp.contact_moves();
    assert_eq!(moves.len(), cc.len());
    for k in [1, 4, cc.len() - 1] {
        assert!(moves[k].tip.distance(moves[k - 1].tip) < 1e-9, "move {k} keeps its tip");
        assert!(moves[k].axis.angle_between(moves[k - 1].axis) > 1e-4, "move {k} turns the axis");
    }
    assert!(tp.moves.iter().all(|m| m.tip.is_finite() && m.axis.is_finite()));
    // The leads follow the tip's first and last moves, not the turns in place.
    let first = tp.first_contact;
    let into = (tp.moves[first].tip - tp.moves[first - 1].tip).normalize();
    let along = (moves[2].tip - moves[0].tip).normalize();
    assert!(into.dot(along) > 0.9, "lead-in ends along the first tip move: {into} vs {along}");
    // A path whose tip never moves has no lead direction.
    let still = vec![cc[0]; 3];
    assert_eq!(toolpath(&still, &n[..3], &five(0.0, 0.0)), Err(ToolpathError::TipNeverMoves { points: 3 }));
    // Repeated centres are still refused.
    let mut rep_n = n.to_vec();
    rep_n[1] = rep_n[0];
    assert!(matches!(toolpath(&cc, &rep_n, &five(0.0, 0.0)), Err(ToolpathError::RepeatedPoint { index: 1, .. })));
}

/// face.stl (R 0.0035 mm, 5 axes) failed with "the feed direction is along the normal" at one
/// contact point: the clearance lifted a few balls out of a pit along their normal, so the
/// centres before and after one of them lay on its normal. The feed direction there is taken
/// over a wider stretch of the path, as on the rest of it.
#[test]
fn face_five_axis_a_ball_lifted_along_its_normal_takes_the_feed_of_the_path_round_it() {
    let cc = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.2], [1.0, 0.0, 0.4], [2.0, 0.0, 0.4], [3.0, 0.0, 0.4]]
        .map(DVec3::from_array);
    let n = [DVec3::Z; 6];
    let tp = toolpath(&cc, &n, &five(15.0, 0.0)).expect("plans with the wider feed direction");
    let axes: Vec<DVec3> = tp.contact_moves().iter().map(|m| m.axis).collect();
    // Every point feeds along +x: its axis leans 15° in the x–z plane, the same at all of them.
    for a in &axes {
        assert!((a.angle_between(DVec3::Z).to_degrees() - 15.0).abs() < 1e-9 && a.y.abs() < 1e-12, "{a}");
        assert!(a.distance(axes[0]) < 1e-12);
    }
}
