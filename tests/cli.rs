//! The native CLI end to end: `info --json` prints exactly one JSON object, faults are one line on
//! stderr with a non-zero exit, `fixture` writes a readable STL.
#![cfg(not(target_arch = "wasm32"))]

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
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes");
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
