//! The native CLI end to end: `info --json` prints exactly one JSON object, faults are one line on
//! stderr with a non-zero exit, `fixture` writes a readable STL.
#![cfg(not(target_arch = "wasm32"))]

mod common;

use slitpath::{fixtures, mesh};
use std::path::PathBuf;
use std::process::{Command, Output};

fn slitpath(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_slitpath")).args(args).output().expect("the CLI runs")
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("slitpath-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn json(out: &Output) -> serde_json::Value {
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    assert_eq!(text.trim().lines().count(), 1, "exactly one JSON line: {text}");
    serde_json::from_str(&text).unwrap()
}

#[test]
fn info_json_has_the_documented_fields() {
    let path = temp("plate.stl");
    let out = slitpath(&["fixture", "plate_3_holes", "-o", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = json(&slitpath(&["info", path.to_str().unwrap(), "--json"]));
    let expected = mesh::load(&std::fs::read(&path).unwrap(), &Default::default()).unwrap().report;
    assert_eq!(v["vertices"], expected.vertices);
    assert_eq!(v["faces"], expected.faces);
    assert_eq!(v["components"], 1);
    assert_eq!(v["boundary_loops"], 4);
    assert_eq!(v["genus"], 0);
    assert_eq!(v["closed"], false);
    assert_eq!(v["degenerate_faces_dropped"], 0);
    assert_eq!(v["bbox"].as_array().unwrap().len(), 2);
    assert!(v.get("machined").is_none());
}

#[test]
fn info_json_of_a_closed_solid_reports_the_machined_top() {
    let path = temp("box.stl");
    std::fs::write(&path, mesh::stl::write_binary(&fixtures::box_boss_pocket(), "box")).unwrap();
    let v = json(&slitpath(&["info", path.to_str().unwrap(), "--json"]));
    assert_eq!(v["closed"], true);
    assert_eq!(v["boundary_loops"], 0);
    // The base top with the boss and the pocket cut out as two holes.
    assert_eq!(v["machined"]["boundary_loops"], 3);
    assert_eq!(v["machined"]["genus"], 0);
    assert_eq!(v["machined"]["closed"], false);
}

#[test]
fn faults_are_one_line_on_stderr_with_a_non_zero_exit() {
    let path = temp("truncated.stl");
    let mut bytes = mesh::stl::write_binary(&fixtures::unit_disk(4), "disk");
    bytes.truncate(bytes.len() - 10);
    std::fs::write(&path, bytes).unwrap();
    for args in [
        vec!["info", path.to_str().unwrap()],
        vec!["info", "/nonexistent/part.stl", "--json"],
        vec!["info", path.to_str().unwrap(), "--wall-angle", "120"],
    ] {
        let out = slitpath(&args);
        assert!(!out.status.success(), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.starts_with("slitpath: error:"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let err = String::from_utf8(slitpath(&["info", path.to_str().unwrap()]).stderr).unwrap();
    assert!(err.contains("truncated"), "{err}");
}

#[test]
fn fixture_writes_every_named_part() {
    for name in fixtures::NAMES {
        let path = temp(&format!("{name}.stl"));
        assert!(slitpath(&["fixture", name, "-o", path.to_str().unwrap()]).status.success(), "{name}");
        let expected = fixtures::by_name(name).unwrap();
        let soup = mesh::stl::read(&std::fs::read(&path).unwrap(), usize::MAX).unwrap();
        assert_eq!(soup.triangles.len(), expected.triangles.len(), "{name}");
    }
    assert!(!slitpath(&["fixture", "no_such_part", "-o", "/tmp/x.stl"]).status.success());
}

#[test]
fn shared_meshes_as_the_issue_states() {
    let dir = common::shared_mesh_dir();
    for (file, loops, machined_loops) in
        [("beetle.stl", 11, None), ("face_holes.stl", 7, None), ("plate_holes.stl", 0, Some(6))]
    {
        let path = dir.join(file);
        if !path.exists() {
            eprintln!("skipped: {} is absent", path.display());
            continue;
        }
        let v = json(&slitpath(&["info", path.to_str().unwrap(), "--json"]));
        assert_eq!(v["boundary_loops"], loops, "{file}");
        assert_eq!(v["genus"], if machined_loops.is_some() { 5 } else { 0 }, "{file}");
        if let Some(m) = machined_loops {
            assert_eq!(v["machined"]["boundary_loops"], m, "{file}");
        }
    }
}

#[test]
fn map_writes_json_and_svg_for_disk_and_annulus_poles() {
    let part = temp("freeform.stl");
    std::fs::write(&part, mesh::stl::write_binary(&fixtures::freeform_4_holes(), "freeform")).unwrap();
    let expected = mesh::load(&std::fs::read(&part).unwrap(), &Default::default()).unwrap();
    for (pole, mode) in [(vec!["--pole", "centroid"], "disk"), (vec!["--pole", "hole:2"], "annulus")] {
        let (json_path, svg_path) = (temp("map.json"), temp("map.svg"));
        let mut args = vec!["map", part.to_str().unwrap(), "--json", json_path.to_str().unwrap()];
        args.extend(["--svg", svg_path.to_str().unwrap()]);
        args.extend(pole.iter().copied());
        let out = slitpath(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json_path).unwrap()).unwrap();
        assert_eq!(v["mode"], mode, "{pole:?}");
        let w = v["w"].as_array().unwrap();
        // The planner's surface: the part's vertices first, in order, then the rim refinement's.
        let vertices = v["vertices"].as_array().unwrap();
        assert_eq!(vertices.len(), w.len());
        assert!(w.len() > expected.surface.positions.len());
        for (got, want) in vertices.iter().zip(&expected.surface.positions) {
            let got: Vec<f64> = got.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            // serde_json's default parser may miss the last bit.
            assert!(got.iter().zip(want.to_array()).all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs().max(1.0)));
        }
        assert_eq!(v["flipped_triangles"], 0, "{pole:?}");
        // One slit per hole that is not the annulus' inner circle; all inside the unit disk.
        let holes = expected.surface.loops.len() - 1;
        assert_eq!(v["slits"].as_array().unwrap().len(), if mode == "disk" { holes } else { holes - 1 });
        for s in v["slits"].as_array().unwrap() {
            let r = s["radius"].as_f64().unwrap();
            assert!(r > 0.0 && r < 1.0, "{s}");
        }
        if mode == "annulus" {
            let r = v["inner_radius"].as_f64().unwrap();
            assert!(r > 0.0 && r < 1.0);
        }
        assert!(w.iter().all(|p| p[0].as_f64().unwrap().hypot(p[1].as_f64().unwrap()) <= 1.0 + 1e-9));
        assert_eq!(v["flatten"]["flipped_triangles"], 0);
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>") && svg.contains("<polygon"));
    }
}

#[test]
fn map_with_a_3d_pole_and_bad_poles() {
    let part = temp("plate_map.stl");
    std::fs::write(&part, mesh::stl::write_binary(&fixtures::plate_3_holes(), "plate")).unwrap();
    let json_path = temp("plate_map.json");
    let p = part.to_str().unwrap();
    let j = json_path.to_str().unwrap();
    // The plate spans x, y in [-50, 50] × [-40, 40] around its centre; a point above it lands on it.
    let out = slitpath(&["map", p, "--pole-3d", "-30,-25,10", "--json", j]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json_path).unwrap()).unwrap();
    assert_eq!(v["mode"], "disk");
    assert!((v["pole_3d"][2].as_f64().unwrap()).abs() < 1e-9, "moved onto the plate");
    for bad in [vec!["--pole", "hole:9"], vec!["--pole", "middle"], vec!["--pole-3d", "1,2"]] {
        let mut args = vec!["map", p, "--json", j];
        args.extend(bad.iter().copied());
        let out = slitpath(&args);
        assert!(!out.status.success(), "{bad:?}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    }
}

#[test]
fn plan_keeps_the_ball_off_the_facets_unless_told_they_are_smooth() {
    let part = temp("cap.stl");
    assert!(slitpath(&["fixture", "spherical_cap_hole", "-o", part.to_str().unwrap()]).status.success());
    let report = |facets: &str| -> serde_json::Value {
        let (out, json) = (temp(&format!("cap-{facets}.ngc")), temp(&format!("cap-{facets}.json")));
        let run = slitpath(&[
            "plan",
            part.to_str().unwrap(),
            "--radius",
            "3",
            "--scallop",
            "0.02",
            "--verify-samples",
            "20000",
            "--facets",
            facets,
            "-o",
            out.to_str().unwrap(),
            "--report",
            json.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
    };
    let (exact, smooth) = (report("exact"), report("smooth"));
    assert_eq!(
        (exact["options"]["facets"].as_str(), smooth["options"]["facets"].as_str()),
        (Some("exact"), Some("smooth"))
    );
    // The sphere's vertex normals dip a ball into almost every facet; smooth leaves them.
    let moved = |r: &serde_json::Value| r["path"]["clearance"]["moved"].as_u64().unwrap();
    assert!(moved(&exact) * 2 > exact["path"]["points"].as_u64().unwrap(), "{}", exact["path"]);
    assert_eq!(moved(&smooth), 0);
    assert_eq!(exact["verify"]["gouges"].as_u64(), Some(0));

    let bad = slitpath(&["plan", part.to_str().unwrap(), "--facets", "round", "-o", temp("x.ngc").to_str().unwrap()]);
    let err = String::from_utf8(bad.stderr).unwrap();
    assert!(!bad.status.success() && err.trim().lines().count() == 1 && err.contains("--facets `round`"), "{err}");
}

#[test]
fn issue_4_a_pole_the_map_cannot_carry_names_where_the_path_would_jump() {
    // plate_holes' centroid lies 0.28 mm from the rim of its largest hole: the P1 map has too few
    // faces between the two for the rings round the pole, and the spiral stops. Given as a 3D
    // point it is planned as given or not at all (`centroid` moves on, see tests/pipeline.rs). The
    // message gave the slit domain's radius and an angle counting every turn (−2139 rad); it now
    // says where on the part the path would jump.
    let path = common::shared_mesh_dir().join("plate_holes.stl");
    if !path.exists() {
        eprintln!("skipped: {} is absent", path.display());
        return;
    }
    let out = temp("plate-centroid.ngc");
    let pole = "100.953,148.643,12.7";
    let run = slitpath(&["plan", path.to_str().unwrap(), "--origin", pole, "-o", out.to_str().unwrap()]);
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(!run.status.success() && err.trim().lines().count() == 1 && !err.contains("panicked"), "{err}");
    assert!(err.contains("would jump") && err.contains("origin auto"), "{err}");
    // Both ends of the jump, in millimetres on the part: beside the hole at (101.6, 154.5), z 12.7.
    let points: Vec<[f64; 3]> = err
        .split('(')
        .skip(1)
        .filter_map(|s| {
            let v: Vec<f64> = s.split(')').next()?.split(", ").filter_map(|x| x.parse().ok()).collect();
            (v.len() == 3).then(|| [v[0], v[1], v[2]])
        })
        .collect();
    assert_eq!(points.len(), 2, "{err}");
    for p in points {
        assert!((p[0] - 101.6).hypot(p[1] - 154.5) < 10.0 && (p[2] - 12.7).abs() < 1e-3, "{p:?}: {err}");
    }
    let angle: f64 =
        err.split("angle ").nth(1).and_then(|s| s.split(' ').next()).and_then(|s| s.parse().ok()).expect(&err);
    assert!(angle.abs() <= std::f64::consts::PI, "{err}");
}

#[test]
fn plan_optimises_the_field_by_default_and_reports_it() {
    // Issue 32: `--optimise tpsfo` (the default) and `none`, named in the G-code header and in
    // the report (its `optimise` section, the path's length over the flat-plate bound, the
    // verifier's median scallop).
    let part = temp("freeform.stl");
    assert!(slitpath(&["fixture", "freeform_4_holes", "-o", part.to_str().unwrap()]).status.success());
    let run = |extra: &[&str]| -> (String, serde_json::Value) {
        let tag = extra.join("-");
        let (out, json) = (temp(&format!("ff{tag}.ngc")), temp(&format!("ff{tag}.json")));
        let mut args = vec!["plan", part.to_str().unwrap(), "--verify-samples", "20000"];
        args.extend_from_slice(extra);
        args.extend(["-o", out.to_str().unwrap(), "--report", json.to_str().unwrap()]);
        let o = slitpath(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (std::fs::read_to_string(out).unwrap(), serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap())
    };
    let (gcode, optimised) = run(&[]);
    assert!(gcode.contains("(- field: seed 003 optimised, tpsfo, alpha 10)"), "{}", &gcode[..600]);
    let o = &optimised["optimise"];
    assert_eq!(o["path_field"], "tpsfo");
    assert!(o["iterations"].as_u64().unwrap() >= 1);
    assert!(o["after"]["total"].as_f64().unwrap() < o["before"]["total"].as_f64().unwrap());
    assert!(o["uniformity_after"].as_f64().unwrap() < o["uniformity_before"].as_f64().unwrap());
    let (gcode, conformal) = run(&["--optimise", "none"]);
    assert!(gcode.contains("(- field: conformal slit map, seed 000)"));
    assert!(conformal.get("optimise").is_none());
    let ratio = |r: &serde_json::Value| r["path"]["length_over_ideal"].as_f64().unwrap();
    assert!(ratio(&optimised) < ratio(&conformal), "{} vs {}", ratio(&optimised), ratio(&conformal));
    let median = |r: &serde_json::Value| r["verify"]["median_scallop_mm"].as_f64().unwrap();
    assert!(median(&optimised) > 0.0 && median(&optimised) < 0.02);
    // A larger α is accepted and reported; a bad choice is one line on stderr.
    let (_, smoother) = run(&["--alpha", "100"]);
    assert_eq!(smoother["optimise"]["alpha"].as_f64(), Some(100.0));
    // `--spread need` plans the field spread by each meridian's need first, and reports it: kept
    // when it keeps h (the unspread path then not planned), else against the unspread path (the
    // shorter within h is written, or the one that leaves less); a bad choice is one line on
    // stderr.
    let (gcode, spread) = run(&["--spread", "need"]);
    let s = &spread["spread"];
    let written = spread["path"]["length_mm"].as_f64().unwrap();
    let (mine, mine_max) = (s["length_mm"].as_f64().unwrap(), s["max_over_h"].as_f64().unwrap());
    match (s["unspread_length_mm"].as_f64(), s["unspread_max_over_h"].as_f64()) {
        (None, None) => assert!(s["kept"].as_bool().unwrap() && mine_max <= 1.0, "{s}"),
        (Some(other), Some(other_max)) => {
            let kept = match (mine_max <= 1.0, other_max <= 1.0) {
                (true, true) => mine < other,
                (false, false) => mine_max < other_max,
                (mine_keeps, _) => mine_keeps,
            };
            assert_eq!(s["kept"].as_bool(), Some(kept), "{s}");
            assert_eq!(written, if kept { mine } else { other });
        }
        _ => panic!("{s}"),
    }
    assert_eq!(written == mine, s["kept"].as_bool().unwrap());
    assert_eq!(gcode.contains("spread by each meridian's need"), s["kept"].as_bool().unwrap());
    assert!(optimised.get("spread").is_none());
    let bad = slitpath(&["plan", part.to_str().unwrap(), "--spread", "wide", "-o", temp("w.ngc").to_str().unwrap()]);
    let err = String::from_utf8(bad.stderr).unwrap();
    assert!(!bad.status.success() && err.trim().lines().count() == 1 && err.contains("--spread `wide`"), "{err}");
    let bad = slitpath(&["plan", part.to_str().unwrap(), "--optimise", "best", "-o", temp("y.ngc").to_str().unwrap()]);
    let err = String::from_utf8(bad.stderr).unwrap();
    assert!(!bad.status.success() && err.trim().lines().count() == 1 && err.contains("--optimise `best`"), "{err}");
    let bad = slitpath(&["plan", part.to_str().unwrap(), "--alpha", "-1", "-o", temp("z.ngc").to_str().unwrap()]);
    let err = String::from_utf8(bad.stderr).unwrap();
    assert!(
        !bad.status.success() && err.trim().lines().count() == 1 && err.contains("α must be a number ≥ 0, got -1"),
        "{err}"
    );
}

#[test]
fn fixture_writes_generated_parts() {
    let path = temp("gen7.stl");
    assert!(slitpath(&["fixture", "gen:7:3000", "-o", path.to_str().unwrap()]).status.success());
    let soup = mesh::stl::read(&std::fs::read(&path).unwrap(), usize::MAX).unwrap();
    assert_eq!(soup.triangles.len(), fixtures::generated::part(7, 3000..=3000).mesh.triangles.len());
    for bad in ["gen:x", "gen:1:5", "gen:1:2:3"] {
        assert!(!slitpath(&["fixture", bad, "-o", "/tmp/x.stl"]).status.success(), "{bad}");
    }
}

#[test]
fn issue_34_a_coarse_stl_is_flagged_before_its_path_is_trusted() {
    // A 6-hole panel meshed at 3 mm edges for h 0.002: its concave creases alone leave more
    // than h for R 3. The warning is on stderr and in the report, with what to do; read as
    // smooth facets there is nothing to warn of.
    let part = temp("coarse-panel.stl");
    assert!(slitpath(&["fixture", "panel:3", "-o", part.to_str().unwrap()]).status.success());
    let plan = |facets: &str| {
        let json = temp(&format!("coarse-{facets}.json"));
        let run = slitpath(&[
            "plan",
            part.to_str().unwrap(),
            "--radius",
            "3",
            "--scallop",
            "0.002",
            "--verify-samples",
            "20000",
            "--facets",
            facets,
            "-o",
            temp(&format!("coarse-{facets}.ngc")).to_str().unwrap(),
            "--report",
            json.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
        (String::from_utf8(run.stderr).unwrap(), report)
    };
    let (stderr, exact) = plan("exact");
    assert!(stderr.contains("warning:") && stderr.contains("--facets smooth"), "{stderr}");
    let valleys = &exact["facet_valleys"];
    let depth = valleys["max_depth_mm"].as_f64().unwrap();
    assert!(depth > 0.002 && valleys["pits"].as_u64().unwrap() > 0, "{valleys}");
    assert_eq!(exact["warnings"].as_array().map(|w| w.len()), Some(1));
    // The verifier finds what was announced: scallops over h, no deeper than the facets leave.
    // (The pits' depth takes the facets' planes for the facets, so it may overstate: at h 0.004
    // the path leaves 0.0034 mm where 0.0057 mm is announced.)
    let max = exact["verify"]["max_scallop_mm"].as_f64().unwrap();
    assert!(max > 0.002 && max < 1.1 * depth, "max scallop {max} mm, facets {depth} mm");

    let (stderr, smooth) = plan("smooth");
    assert!(!stderr.contains("warning:"), "{stderr}");
    assert!(smooth.get("facet_valleys").is_none() && smooth["warnings"].as_array().unwrap().is_empty());
}
