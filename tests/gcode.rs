//! Integration tests of the posts. Every G-code post's output is run through LinuxCNC's
//! standalone interpreter rs274 (see tests/common) and its canonical motions must reproduce
//! every planned tool tip (and A C) within 1e-3, in order; CL data is read back with parse_cl.
//! Also: determinism, no redundant words, the comment sanitiser, the A/C unwrapping and
//! singularity on synthetic axis sequences, typed errors.
// Native only: runs rs274 / reads files / uses serde_json (the browser tests are tests/wasm.rs).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::{rs274, Interpreted};
use glam::DVec3;
use slitpath::fixtures::{contact_spiral, ContactPath, ContactSurface};
use slitpath::gcode::ac::{ac_angles, axis_of, A_LIMIT_DEG, SINGULAR_DEG};
use slitpath::gcode::{gcode, parse_cl, sanitize_comment, GcodeError, GcodeOptions, Post};
use slitpath::toolpath::{toolpath, Axes, Toolpath, ToolpathOptions};

const TOL: f64 = 1e-3;

fn cap() -> ContactPath {
    contact_spiral(ContactSurface::SphericalCap, 35.0, 5.0, 2.0, 0.5)
}

fn saddle() -> ContactPath {
    contact_spiral(ContactSurface::Saddle, 38.0, 4.0, 2.5, 0.6)
}

fn plan(path: &ContactPath, axes: Axes) -> Toolpath {
    toolpath(&path.cc, &path.normals, &ToolpathOptions { axes, ..Default::default() }).unwrap()
}

fn post(tp: &Toolpath, post: Post) -> String {
    let options = GcodeOptions {
        post,
        part_name: "cap test".into(),
        header: vec![
            ("radius_mm".into(), "3".into()),
            ("cut_length_mm".into(), format!("{:.3}", tp.stats.cut_length_mm)),
        ],
        ..Default::default()
    };
    gcode(tp, &options).unwrap()
}

/// The poses the program must visit, in order: the moves with consecutive duplicates at the
/// output precision (4 decimals) merged, as the posts drop moves that change no word.
fn expected_poses(tp: &Toolpath, with_angles: bool) -> Vec<(usize, DVec3, DVec3)> {
    let angles = ac_angles(&tp.moves.iter().map(|m| m.axis).collect::<Vec<_>>()).unwrap();
    let key = |p: DVec3, ac: (f64, f64)| {
        let mut k = vec![p.x, p.y, p.z];
        if with_angles {
            k.extend([ac.0, ac.1]);
        }
        k.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>()
    };
    let mut out: Vec<(usize, DVec3, DVec3)> = Vec::new();
    let mut last = None;
    for (i, m) in tp.moves.iter().enumerate() {
        let k = key(m.tip, angles[i]);
        if last.as_ref() != Some(&k) {
            let abc = if with_angles { DVec3::new(angles[i].0, 0.0, angles[i].1) } else { DVec3::ZERO };
            out.push((i, m.tip, abc));
            last = Some(k);
        }
    }
    out
}

/// rs274's motions are: the post's opening `G0 Z<safe>`, then one motion per expected pose,
/// rapid/feed and feed rate as planned.
fn assert_reproduces(tp: &Toolpath, run: &Interpreted, with_angles: bool) {
    let expected = expected_poses(tp, with_angles);
    let motions = &run.motions;
    assert_eq!(motions.len(), expected.len() + 1, "one canonical motion per planned pose (+ the safe-Z opening)");
    assert!(motions[0].rapid && (motions[0].xyz.z - tp.moves[0].tip.z).abs() < TOL);
    for (k, (&(i, tip, abc), got)) in expected.iter().zip(&motions[1..]).enumerate() {
        let m = &tp.moves[i];
        assert!(got.xyz.distance(tip) < TOL, "pose {k} (move {i}): rs274 {:?} vs planned {tip:?}", got.xyz);
        assert!((got.abc - abc).abs().max_element() < TOL, "pose {k}: A B C {:?} vs {abc:?}", got.abc);
        assert_eq!(got.rapid, m.kind.is_rapid(), "pose {k}: rapid/feed");
        if !got.rapid {
            assert!((got.feed - m.feed_mm_min).abs() < 0.05, "pose {k}: feed {} vs {}", got.feed, m.feed_mm_min);
        }
        if with_angles {
            // The documented convention, applied to what the interpreter read, gives the axis.
            assert!(axis_of(got.abc.x, got.abc.z).distance(m.axis) < 1e-5, "pose {k}: axis");
        }
    }
    assert!(run.active_comments.is_empty(), "active comments: {:?}", run.active_comments);
}

#[test]
fn linuxcnc_post_is_accepted_by_rs274_and_reproduces_every_tip() {
    for path in [cap(), saddle()] {
        let tp = plan(&path, Axes::default());
        let text = post(&tp, Post::LinuxCnc);
        let run = rs274(&text, 1);
        assert_reproduces(&tp, &run, false);
        for call in
            ["CHANGE_TOOL", "USE_TOOL_LENGTH_OFFSET", "SET_SPINDLE_SPEED(0, 12000.0000)", "START_SPINDLE_CLOCKWISE"]
        {
            assert!(run.canon.contains(call), "missing {call}");
        }
        assert!(run.canon.contains("SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.005"), "G64 P0.005");
        assert!(run.comments.iter().any(|c| c == "part: cap test"));
        assert!(run.comments.iter().any(|c| c == "- radius_mm: 3"));
        println!(
            "linuxcnc: {} lines, {} canonical motions, all within {TOL} mm",
            text.lines().count(),
            run.motions.len()
        );
    }
}

#[test]
fn grbl_post_is_a_linuxcnc_valid_subset_and_reproduces_every_tip() {
    let tp = plan(&saddle(), Axes::default());
    let text = post(&tp, Post::Grbl);
    for word in ["M6", "G43", "G49", "G64", "G61", "T1 "] {
        assert!(!text.lines().filter(|l| !l.starts_with('(')).any(|l| l.contains(word)), "GRBL has no {word}");
    }
    let run = rs274(&text, 1);
    assert_reproduces(&tp, &run, false);
    assert!(!run.canon.contains("CHANGE_TOOL"));
}

#[test]
fn ac_post_is_accepted_by_rs274_and_reproduces_tips_and_angles() {
    let path = cap();
    for axes in [Axes::five_default(), Axes::Five { lead_deg: 10.0, tilt_deg: 5.0 }, Axes::default()] {
        let tp = plan(&path, axes);
        let text = post(&tp, Post::Ac);
        let run = rs274(&text, 1);
        assert_reproduces(&tp, &run, true);
        // On the spiral C follows the feed direction around the dome: continuous, several turns.
        let c: Vec<f64> = run.motions.iter().skip(1).map(|m| m.abc.z).collect();
        let max_step = c.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
        let range =
            c.iter().copied().fold(f64::NEG_INFINITY, f64::max) - c.iter().copied().fold(f64::INFINITY, f64::min);
        if matches!(axes, Axes::Five { .. }) {
            assert!(max_step < 10.0, "C jumps {max_step}°");
            assert!(range > 360.0, "C must be unwrapped over the turns of the spiral, range {range}°");
        } else {
            assert!(run.motions.iter().all(|m| m.abc == DVec3::ZERO), "3-axis toolpath: A = C = 0");
        }
        println!("ac {axes:?}: {} motions, C range {range:.1}°, max C step {max_step:.3}°", run.motions.len());
    }
}

#[test]
fn cl_data_reads_back_exactly() {
    for axes in [Axes::default(), Axes::five_default()] {
        let tp = plan(&cap(), axes);
        let text = post(&tp, Post::Cl);
        let cl = parse_cl(&text).unwrap();
        assert_eq!(cl.part_name, "cap test");
        assert_eq!((cl.tool_number, cl.cutter_diameter_mm, cl.corner_radius_mm), (Some(1), Some(6.0), Some(3.0)));
        assert_eq!(cl.spindle_rpm, Some(12000.0));
        assert!(cl.multax);
        assert_eq!(cl.moves.len(), tp.moves.len(), "one GOTO per move");
        for (i, (got, m)) in cl.moves.iter().zip(&tp.moves).enumerate() {
            assert!(got.tip.distance(m.tip) < 1e-4, "move {i}: tip");
            assert!(got.axis.distance(m.axis) < 2e-6, "move {i}: axis");
            assert_eq!(got.rapid, m.kind.is_rapid(), "move {i}: RAPID");
            assert_eq!(got.feed_mm_min, (!m.kind.is_rapid()).then_some(m.feed_mm_min), "move {i}: FEDRAT");
        }
    }
}

#[test]
fn every_post_is_deterministic_and_clean_text() {
    let tp3 = plan(&saddle(), Axes::default());
    let tp5 = plan(&saddle(), Axes::five_default());
    for p in Post::ALL {
        let tp = if matches!(p, Post::LinuxCnc | Post::Grbl) { &tp3 } else { &tp5 };
        let a = post(tp, p);
        // Planned again from scratch: byte-identical.
        let again = post(&plan(&saddle(), if tp == &tp3 { Axes::default() } else { Axes::five_default() }), p);
        assert_eq!(a, again, "{p} output differs between runs");
        assert!(a.ends_with('\n') && !a.contains('\r') && a.is_ascii());
        assert!(a.lines().all(|l| !l.is_empty() && l.trim_end() == l), "{p}: empty line or trailing space");
    }
}

/// No redundant words: modal G0/G1 and F are written only on change, a coordinate only when
/// its value changes, and every move line has a coordinate.
#[test]
fn gcode_skips_redundant_words_and_never_writes_an_empty_move() {
    for (tp, p) in [(plan(&cap(), Axes::default()), Post::LinuxCnc), (plan(&cap(), Axes::five_default()), Post::Ac)] {
        let text = post(&tp, p);
        let mut last: std::collections::BTreeMap<char, String> = Default::default();
        let mut moves = 0;
        for line in text.lines().filter(|l| !l.starts_with('(')) {
            let words: Vec<(char, &str)> = line.split(' ').map(|w| (w.chars().next().unwrap(), &w[1..])).collect();
            let is_move = words.iter().any(|(c, v)| "XYZAC".contains(*c) || (*c == 'G' && (*v == "0" || *v == "1")));
            if !is_move {
                continue;
            }
            moves += 1;
            assert!(words.iter().any(|(c, _)| "XYZAC".contains(*c)), "move line without a coordinate: {line}");
            for (c, v) in words {
                if "XYZACFG".contains(c) {
                    assert_ne!(last.get(&c).map(String::as_str), Some(v), "redundant {c}{v} in '{line}'");
                    last.insert(c, v.to_string());
                }
            }
        }
        assert!(moves > 100);
    }
}

#[test]
fn part_name_and_header_cannot_break_a_comment() {
    let tp = plan(&cap(), Axes::default());
    let evil = "evil) G0 Z-50 (\n; M30\r\nnaïve ü 部品 $$";
    let options = GcodeOptions {
        part_name: evil.into(),
        header: vec![("msg,".into(), "probeopen /tmp/x) M2".into()), ("(debug, x".into(), "a;b\nc".into())],
        ..Default::default()
    };
    let clean =
        GcodeOptions { part_name: "clean".into(), header: vec![("a".into(), "b".into()); 2], ..Default::default() };
    for p in Post::ALL {
        let tp = if p == Post::Ac { plan(&cap(), Axes::five_default()) } else { tp.clone() };
        let text = gcode(&tp, &GcodeOptions { post: p, ..options.clone() }).unwrap();
        let reference = gcode(&tp, &GcodeOptions { post: p, ..clean.clone() }).unwrap();
        assert_eq!(text.lines().count(), reference.lines().count(), "{p}: the name added or removed a line");
        let differing: Vec<_> = text.lines().zip(reference.lines()).filter(|(a, b)| a != b).collect();
        assert_eq!(differing.len(), 3, "{p}: only the part and the two header lines differ");
        for (line, _) in differing {
            assert!(line.is_ascii() && !line.contains(';'), "{p}: {line}");
            if p == Post::Cl {
                assert!(line.starts_with("PARTNO ") || line.starts_with("$$ - "), "{line}");
                assert!(!line[2..].contains('$'));
            } else {
                assert!(line.starts_with("(part: ") || line.starts_with("(- "), "{line}");
                assert!(line.ends_with(')') && line.matches('(').count() == 1 && line.matches(')').count() == 1);
            }
        }
        if p == Post::Cl {
            assert_eq!(parse_cl(&text).unwrap().moves, parse_cl(&reference).unwrap().moves);
        } else {
            let (a, b) = (rs274(&text, 1), rs274(&reference, 1));
            assert_eq!(a.motions, b.motions, "{p}: the comments changed the motion");
            assert!(a.active_comments.is_empty(), "{p}: {:?}", a.active_comments);
        }
    }
    assert_eq!(sanitize_comment(evil, 64), "evil] G0 Z-50 [ , M30 na?ve ? ?? SS");
}

fn axis_deg(a: f64, c: f64) -> DVec3 {
    // Independent of the library: (sin A sin C, −sin A cos C, cos A) with std trigonometry.
    let (a, c) = (a.to_radians(), c.to_radians());
    DVec3::new(a.sin() * c.sin(), -a.sin() * c.cos(), a.cos())
}

#[test]
fn c_is_unwrapped_across_180_and_over_many_turns() {
    for sign in [1.0, -1.0] {
        let theta: Vec<f64> = (0..=160).map(|k| sign * (170.0 + 7.0 * k as f64)).collect();
        let axes: Vec<DVec3> = theta.iter().map(|&t| axis_deg(30.0, t)).collect();
        let angles = ac_angles(&axes).unwrap();
        // The first C is the principal one (170°), then C follows the rotation past ±180°,
        // ±360°, … without a jump.
        for (k, (&(a, c), &t)) in angles.iter().zip(&theta).enumerate() {
            let principal = if sign > 0.0 { 170.0 } else { -170.0 };
            assert!((a - 30.0).abs() < 1e-9, "A at {k}");
            assert!((c - (t - theta[0] + principal)).abs() < 1e-9, "C at {k}: {c} for θ = {t}");
        }
    }
}

#[test]
fn c_is_held_through_the_singular_pose() {
    // The axis swings through +Z in the plane x = 0: A changes sign, C stays 0 (the A ≥ 0
    // solution would flip C by 180°).
    let swing: Vec<DVec3> = (0..=80).map(|k| axis_deg(20.0 - 0.5 * k as f64, 0.0)).collect();
    for (k, &(a, c)) in ac_angles(&swing).unwrap().iter().enumerate() {
        assert!((a - (20.0 - 0.5 * k as f64)).abs() < 1e-9 && c == 0.0, "swing {k}: A {a} C {c}");
    }
    // Tilted at C = 40°, then straight up (exactly +Z), then tiny tilts in every direction,
    // then tilted at C = 40° again: C is held at 40° throughout, no spinning.
    let mut axes = vec![axis_deg(5.0, 40.0), axis_deg(1.0, 40.0), DVec3::Z, DVec3::Z];
    axes.extend((0..12).map(|k| axis_deg(0.5 * SINGULAR_DEG, 30.0 * k as f64)));
    axes.extend([DVec3::Z, axis_deg(2.0, 40.0)]);
    let angles = ac_angles(&axes).unwrap();
    for (k, (&(a, c), axis)) in angles.iter().zip(&axes).enumerate() {
        assert_eq!(c, 40.0, "pose {k}: C must be held");
        assert!(axis_of(a, c).angle_between(*axis) <= 1.5 * SINGULAR_DEG.to_radians(), "pose {k}");
    }
    // A first pose at the singularity starts at C = 0.
    assert_eq!(ac_angles(&[DVec3::Z]).unwrap(), vec![(0.0, 0.0)]);
    // Beyond the A range: a typed error naming the pose.
    let beyond = [DVec3::Z, axis_deg(A_LIMIT_DEG + 1.0, 10.0)];
    assert!(matches!(ac_angles(&beyond), Err(GcodeError::AOutOfRange { index: 1, .. })));
}

#[test]
fn bad_options_and_toolpaths_give_typed_errors() {
    let tp3 = plan(&cap(), Axes::default());
    let tp5 = plan(&cap(), Axes::five_default());
    let with = |post: Post| GcodeOptions { post, ..Default::default() };
    for p in [Post::LinuxCnc, Post::Grbl] {
        assert!(matches!(gcode(&tp5, &with(p)), Err(GcodeError::NotThreeAxis { post, index: 0, .. }) if post == p));
    }
    for decimals in [0, 9] {
        assert_eq!(
            gcode(&tp3, &GcodeOptions { decimals, ..Default::default() }),
            Err(GcodeError::BadDecimals { decimals })
        );
    }
    let bad_blend = GcodeOptions { blend_tolerance_mm: -1.0, ..Default::default() };
    assert!(matches!(gcode(&tp3, &bad_blend), Err(GcodeError::BadBlendTolerance { .. })));
    let mut t = tp3.clone();
    t.moves.clear();
    assert_eq!(gcode(&t, &with(Post::Cl)), Err(GcodeError::EmptyToolpath));
    let mut t = tp3.clone();
    t.moves[7].tip.x = f64::NAN;
    assert_eq!(gcode(&t, &with(Post::LinuxCnc)), Err(GcodeError::NonFiniteMove { index: 7 }));
    let mut t = tp3.clone();
    t.moves[9].feed_mm_min = 0.0;
    assert!(matches!(gcode(&t, &with(Post::Grbl)), Err(GcodeError::BadFeed { index: 9, .. })));
    let mut t = tp3.clone();
    t.moves[3].axis *= 2.0;
    assert!(matches!(gcode(&t, &with(Post::Cl)), Err(GcodeError::NotUnitAxis { index: 3, .. })));
    let mut t = tp3.clone();
    t.tool.number = 0;
    assert!(matches!(gcode(&t, &with(Post::LinuxCnc)), Err(GcodeError::BadTool { field: "number", .. })));
    let mut t = tp5.clone();
    t.moves[5].axis = DVec3::new(1.0, 0.0, -0.8).normalize();
    assert!(matches!(gcode(&t, &with(Post::Ac)), Err(GcodeError::AOutOfRange { index: 5, .. })));
    assert!(gcode(&tp5, &with(Post::Ac)).unwrap().contains(" A"));
}

#[test]
fn cl_reader_reports_bad_lines() {
    let tp = plan(&cap(), Axes::default());
    let text = post(&tp, Post::Cl);
    let truncated: String = text.lines().take(40).map(|l| format!("{l}\n")).collect();
    assert_eq!(parse_cl(&truncated).unwrap_err().line, 41);
    let cases = [
        ("UNITS/INCHES\nFINI\n", 1),
        ("UNITS/MM\nGOTO/1,2,3\nFINI\n", 2),
        ("FEDRAT/100\nGOTO/1,2\nFINI\n", 2),
        ("FEDRAT/100\nGOTO/1,x,3\nFINI\n", 2),
        ("FEDRAT/0\nFINI\n", 1),
        ("PARTNO p\n$$ c\nCIRCLE/1,2\nFINI\n", 3),
    ];
    for (text, line) in cases {
        let e = parse_cl(text).unwrap_err();
        assert_eq!(e.line, line, "{text:?}: {e}");
    }
    let ok = parse_cl("PARTNO p\nFEDRAT/100,MMPM\nGOTO/1,2,3\nRAPID\nGOTO/4,5,6,0,0,1\nFINI\nnot read\n").unwrap();
    assert_eq!(ok.moves.len(), 2);
    assert_eq!((ok.moves[0].feed_mm_min, ok.moves[1].rapid), (Some(100.0), true));
}
