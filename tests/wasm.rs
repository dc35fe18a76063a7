//! The wasm facade in a real browser (`wasm-pack test --headless --chrome`): STL bytes in, the mesh
//! report out as a plain JS object, faults as JS `Error`s whose message names them.
#![cfg(target_arch = "wasm32")]

use js_sys::{Array, Object, Reflect};
use slitpath::wasm::{version, Planner};
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

type Tri = [[f32; 3]; 3];

/// A binary STL. By default the header deliberately starts with `solid`: the size decides.
fn binary_stl(tris: &[Tri]) -> Vec<u8> {
    binary_stl_with_header(tris, "solid but binary: slitpath wasm test")
}

fn binary_stl_with_header(tris: &[Tri], header: &str) -> Vec<u8> {
    let mut out = header.as_bytes().to_vec();
    out.resize(80, b' ');
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        out.extend_from_slice(&[0u8; 12]); // normal: readers must not trust it
        for v in t {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

fn ascii_stl(tris: &[Tri]) -> String {
    let mut s = String::from("solid part\n");
    for t in tris {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for v in t {
            s.push_str(&format!("      vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid part\n");
    s
}

/// Two triangles per quad, counter-clockwise seen from +Z.
fn quad(a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]) -> [Tri; 2] {
    [[a, b, c], [a, c, d]]
}

/// A 3 × 3 grid of unit squares in z = 0 without the centre one: a square plate with a square
/// hole. 16 vertices, 16 faces, 32 edges, 2 boundary loops (12 + 4 vertices), genus 0.
fn plate_with_hole() -> Vec<Tri> {
    let mut tris = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            if (i, j) == (1, 1) {
                continue;
            }
            let (x, y) = (i as f32, j as f32);
            tris.extend(quad([x, y, 0.0], [x + 1.0, y, 0.0], [x + 1.0, y + 1.0, 0.0], [x, y + 1.0, 0.0]));
        }
    }
    tris
}

/// A closed unit cube, 12 faces wound outwards.
fn cube() -> Vec<Tri> {
    let p = |i: usize| -> [f32; 3] { [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32] };
    // Corners of each face counter-clockwise seen from outside.
    let faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    faces.iter().flat_map(|f| quad(p(f[0]), p(f[1]), p(f[2]), p(f[3]))).collect()
}

fn get(obj: &JsValue, key: &str) -> JsValue {
    Reflect::get(obj, &JsValue::from_str(key)).unwrap_or_else(|_| panic!("report has no `{key}`"))
}

fn num(obj: &JsValue, key: &str) -> f64 {
    get(obj, key).as_f64().unwrap_or_else(|| panic!("`{key}` is not a number: {:?}", get(obj, key)))
}

fn flag(obj: &JsValue, key: &str) -> bool {
    get(obj, key).as_bool().unwrap_or_else(|| panic!("`{key}` is not a boolean"))
}

fn numbers(obj: &JsValue, key: &str) -> Vec<f64> {
    let v = get(obj, key);
    assert!(Array::is_array(&v), "`{key}` is not an array");
    Array::from(&v).iter().map(|x| x.as_f64().expect("number")).collect()
}

fn load(stl: &[u8], options: JsValue) -> Result<Planner, String> {
    Planner::new(stl, options, None).map_err(|e| {
        let value = JsValue::from(e);
        let error: js_sys::Error = value.dyn_into().expect("a JS Error");
        String::from(error.message())
    })
}

fn load_err(stl: &[u8], options: JsValue) -> String {
    let shown = js_sys::JSON::stringify(&options).ok().and_then(|s| s.as_string()).unwrap_or_default();
    match load(stl, options) {
        Ok(_) => panic!("expected an error (options {shown})"),
        Err(message) => message,
    }
}

fn options(json: &str) -> JsValue {
    js_sys::JSON::parse(json).expect("valid JSON")
}

#[wasm_bindgen_test]
fn version_is_the_crate_version() {
    assert_eq!(version(), env!("CARGO_PKG_VERSION"));
}

#[wasm_bindgen_test]
fn plate_with_hole_reports_its_topology() {
    let planner = load(&binary_stl(&plate_with_hole()), JsValue::UNDEFINED).expect("loads");
    let r = planner.report().expect("report");
    assert!(r.is_object() && !r.is_instance_of::<js_sys::Map>(), "the report is a plain object");
    assert_eq!(num(&r, "vertices"), 16.0);
    assert_eq!(num(&r, "faces"), 16.0);
    assert_eq!(num(&r, "edges"), 32.0);
    assert_eq!(num(&r, "components"), 1.0);
    assert_eq!(num(&r, "boundary_loops"), 2.0);
    assert_eq!(numbers(&r, "loop_vertex_counts"), vec![12.0, 4.0]);
    assert_eq!(num(&r, "euler_characteristic"), 0.0);
    assert_eq!(num(&r, "genus"), 0.0);
    assert!(!flag(&r, "closed"));
    assert_eq!(num(&r, "degenerate_faces_dropped"), 0.0);
    assert!((num(&r, "area_mm2") - 8.0).abs() < 1e-9);
    let bbox = Array::from(&get(&r, "bbox"));
    assert_eq!(Array::from(&bbox.get(0)).iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>(), [0.0; 3]);
    assert_eq!(Array::from(&bbox.get(1)).iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>(), [3.0, 3.0, 0.0]);
    assert!(get(&r, "machined").is_undefined(), "an open surface has no `machined` section");

    let positions = planner.positions();
    let triangles = planner.triangles();
    assert_eq!(positions.len(), 16 * 3);
    assert_eq!(triangles.len(), 16 * 3);
    assert!(triangles.iter().all(|&i| i < 16));
    assert!(positions.iter().all(|&c| (0.0..=3.0).contains(&c)));
}

#[wasm_bindgen_test]
fn ascii_and_binary_give_the_same_report() {
    let binary = load(&binary_stl(&plate_with_hole()), JsValue::UNDEFINED).unwrap().report().unwrap();
    let ascii = load(ascii_stl(&plate_with_hole()).as_bytes(), JsValue::NULL).unwrap().report().unwrap();
    let json = |v: &JsValue| String::from(js_sys::JSON::stringify(v).unwrap());
    assert_eq!(json(&binary), json(&ascii));
}

#[wasm_bindgen_test]
fn closed_cube_reports_closed_and_its_machined_top() {
    let planner = load(&binary_stl(&cube()), JsValue::UNDEFINED).expect("a closed solid loads");
    let r = planner.report().unwrap();
    assert_eq!(num(&r, "vertices"), 8.0);
    assert_eq!(num(&r, "faces"), 12.0);
    assert_eq!(num(&r, "boundary_loops"), 0.0);
    assert_eq!(num(&r, "genus"), 0.0);
    assert!(flag(&r, "closed"));
    let top = get(&r, "machined");
    assert!(top.is_object(), "a closed solid has a `machined` section");
    assert_eq!(num(&top, "faces"), 2.0);
    assert_eq!(num(&top, "vertices"), 4.0);
    assert_eq!(num(&top, "boundary_loops"), 1.0);
    assert!(!flag(&top, "closed"));
    // The surface handed to WebGL is the machined top, z = 1.
    let positions = planner.positions();
    assert_eq!(positions.len(), 4 * 3);
    assert!(positions.chunks(3).all(|p| p[2] == 1.0));
}

#[wasm_bindgen_test]
fn tool_axis_option_picks_another_face() {
    let planner = load(&binary_stl(&cube()), options(r#"{"toolAxis": [1, 0, 0], "wallAngleDeg": 30}"#)).unwrap();
    assert!(planner.positions().chunks(3).all(|p| p[0] == 1.0), "the +X face is machined");
    assert_eq!(planner.triangles().len(), 2 * 3);
}

#[wasm_bindgen_test]
fn truncated_binary_names_the_fault() {
    let mut bytes = binary_stl_with_header(&plate_with_hole(), "exported by a CAD system");
    bytes.truncate(bytes.len() - 30);
    let message = load_err(&bytes, JsValue::UNDEFINED);
    assert!(message.contains("truncated"), "{message}");
}

#[wasm_bindgen_test]
fn garbled_ascii_names_the_line() {
    let mut text = ascii_stl(&plate_with_hole());
    // Line 5 is the second vertex of the first facet.
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[4].trim_start().starts_with("vertex"));
    text = text.replacen(lines[4], "      vertex 1 0 zz", 1);
    let message = load_err(text.as_bytes(), JsValue::UNDEFINED);
    assert!(message.contains("line 5"), "{message}");
}

#[wasm_bindgen_test]
fn empty_input_is_an_error() {
    let message = load_err(&[], JsValue::UNDEFINED);
    assert!(message.contains("empty"), "{message}");
}

#[wasm_bindgen_test]
fn triangle_cap_is_an_option() {
    let message = load_err(&binary_stl(&plate_with_hole()), options(r#"{"maxTriangles": 10}"#));
    assert!(message.contains("16 triangles") && message.contains("10"), "{message}");
}

#[wasm_bindgen_test]
fn bad_options_throw() {
    let stl = binary_stl(&plate_with_hole());
    let cases = [
        (r#"{"wallAngleDeg": 95}"#, "wall angle"),
        (r#"{"toolAxis": [0, 0, 0]}"#, "tool axis"),
        (r#"{"weldToleranceRel": -1}"#, "weld tolerance"),
        (r#"{"toolAxis": [0, 1]}"#, "invalid mesh options"),
        (r#"{"toolAxis": "up"}"#, "invalid mesh options"),
        (r#"{"maxTriangles": -5}"#, "invalid mesh options"),
        (r#"{"wallAngle": 45}"#, "wallAngle"),
        ("42", "invalid mesh options"),
    ];
    for (json, expected) in cases {
        let message = load_err(&stl, options(json));
        assert!(message.contains(expected), "options {json}: {message}");
    }
}

#[wasm_bindgen_test]
fn report_keys_are_the_documented_ones() {
    let r = load(&binary_stl(&plate_with_hole()), JsValue::UNDEFINED).unwrap().report().unwrap();
    let keys: Vec<String> = Object::keys(r.unchecked_ref::<Object>()).iter().map(|k| k.as_string().unwrap()).collect();
    for key in
        ["vertices", "faces", "components", "boundary_loops", "genus", "closed", "degenerate_faces_dropped", "bbox"]
    {
        assert!(keys.iter().any(|k| k == key), "missing `{key}` in {keys:?}");
    }
}

/// The facade reports exactly what the core computes, for every fixture, and the documented
/// topology of two of them (plate with 3 holes; closed box with a boss and a pocket on top).
#[wasm_bindgen_test]
fn fixtures_report_what_the_core_computes() {
    use slitpath::{fixtures, mesh};
    for &name in fixtures::NAMES {
        let stl = mesh::stl::write_binary(&fixtures::by_name(name).unwrap(), name);
        let core = mesh::load(&stl, &mesh::MeshOptions::default()).expect(name).report;
        let r = load(&stl, JsValue::UNDEFINED).expect(name).report().unwrap();
        assert_eq!(num(&r, "faces"), core.faces as f64, "{name}");
        assert_eq!(num(&r, "vertices"), core.vertices as f64, "{name}");
        assert_eq!(num(&r, "boundary_loops"), core.boundary_loops as f64, "{name}");
        assert_eq!(num(&r, "genus"), core.genus as f64, "{name}");
        assert_eq!(flag(&r, "closed"), core.closed, "{name}");
        assert_eq!(num(&r, "area_mm2"), core.area_mm2, "{name}");
        assert_eq!(get(&r, "machined").is_object(), core.machined.is_some(), "{name}");
    }

    let stl = mesh::stl::write_binary(&fixtures::plate_3_holes(), "plate");
    let r = load(&stl, JsValue::UNDEFINED).unwrap().report().unwrap();
    assert_eq!(num(&r, "boundary_loops"), 4.0);
    assert_eq!(num(&r, "genus"), 0.0);
    assert_eq!(num(&r, "components"), 1.0);
    assert!(!flag(&r, "closed"));

    let stl = mesh::stl::write_binary(&fixtures::box_boss_pocket(), "box");
    let r = load(&stl, JsValue::UNDEFINED).unwrap().report().unwrap();
    assert!(flag(&r, "closed"));
    assert_eq!(num(&r, "boundary_loops"), 0.0);
    assert_eq!(num(&r, "euler_characteristic"), 2.0);
    let top = get(&r, "machined");
    assert!(top.is_object(), "a closed solid has a `machined` section");
    assert!(!flag(&top, "closed"));
}

/// The conformal core through the facade: the flattened domain and the slit map as typed arrays
/// equal the native computation (same code, same input) within the cross-platform libm noise, and
/// a pole in a hole gives the annulus map.
#[wasm_bindgen_test]
fn flattening_and_slit_map_cross_as_typed_arrays() {
    use slitpath::{fixtures, mesh};
    let part = fixtures::unit_disk(12);
    let stl = mesh::stl::write_binary(&part, "disk");
    let mut planner = load(&stl, JsValue::UNDEFINED).unwrap();
    let uv = planner.flattened().unwrap();
    // Once the planner is built its surface is the refined one (long edges split): the positions
    // are read after it.
    let n = planner.positions().len() / 3;
    assert!(n > part.positions.len());
    assert_eq!(uv.len(), 2 * n);
    assert_eq!(num(&planner.flatten_quality().unwrap(), "flipped_triangles"), 0.0);
    // A flat disk flattens congruently, so the area-centred flattening is the disk itself up to a
    // rotation: every boundary point at radius 1.
    let w = planner.slit_map(0.0, 0.0).unwrap();
    assert_eq!(w.len(), 2 * n);
    assert!(w.chunks(2).all(|p| p[0].hypot(p[1]) <= 1.0 + 1e-9));
    let info = planner.slit_map_info().unwrap();
    assert_eq!(get(&info, "mode").as_string().unwrap(), "disk");

    let stl = mesh::stl::write_binary(&fixtures::plate_3_holes(), "plate");
    let mut planner = load(&stl, JsValue::UNDEFINED).unwrap();
    let uv = planner.flattened().unwrap();
    let surface = mesh::load(&stl, &Default::default()).unwrap().surface;
    // A point inside hole 1: its vertex centroid (the holes are circles).
    let hole = &surface.loops[1];
    let (mut x, mut y) = (0.0, 0.0);
    for &v in hole {
        x += uv[2 * v as usize] / hole.len() as f64;
        y += uv[2 * v as usize + 1] / hole.len() as f64;
    }
    let w = planner.slit_map(x, y).unwrap();
    let info = planner.slit_map_info().unwrap();
    assert_eq!(get(&info, "mode").as_string().unwrap(), "annulus");
    let inner = num(&info, "innerRadius");
    for &v in hole {
        let r = w[2 * v as usize].hypot(w[2 * v as usize + 1]);
        assert!((r - inner).abs() < 1e-9, "{r} vs {inner}");
    }
    assert_eq!(Array::from(&get(&info, "slits")).length(), 2);
}

#[wasm_bindgen_test]
fn slit_map_with_a_bad_pole_throws() {
    use slitpath::{fixtures, mesh};
    let stl = mesh::stl::write_binary(&fixtures::plate_3_holes(), "plate");
    let mut planner = load(&stl, JsValue::UNDEFINED).unwrap();
    let err: js_sys::Error = JsValue::from(planner.slit_map(1e6, 0.0).unwrap_err()).dyn_into().unwrap();
    assert!(String::from(err.message()).contains("outside"), "{}", String::from(err.message()));
    let err: js_sys::Error = JsValue::from(planner.slit_map_info().unwrap_err()).dyn_into().unwrap();
    assert!(String::from(err.message()).contains("no slit map"));
}

// --- Cross-target determinism of the conformal core (issue 3) ---------------------------------

#[path = "digest/mod.rs"]
mod digest;

/// The flattening and the slit maps computed in the browser have the same bits as natively: the
/// digests are those `tests/determinism.rs` checks in `tests/digest/expected.txt`.
#[wasm_bindgen_test]
fn conformal_core_is_bit_identical_to_native() {
    for name in digest::CASES {
        let line = digest::digest_line(name);
        assert_eq!(Some(line.as_str()), digest::expected_line(name), "{name}: wasm differs from native");
    }
}

// --- The flank strategy (issue 35) --------------------------------------------------------------

#[path = "digest/flank.rs"]
mod flank_digest;

/// A flank plan computed in the browser has the same bits as natively (`tests/flank.rs` checks
/// the same line of `tests/digest/flank.txt`).
#[wasm_bindgen_test]
fn flank_plan_is_bit_identical_to_native() {
    assert_eq!(flank_digest::flank_digest(), flank_digest::expected(), "wasm differs from native");
}

/// The facade's `planFlank`: typed arrays of matching lengths, the report object, faults as
/// `Error`s naming them.
#[wasm_bindgen_test]
fn plan_flank_returns_the_plan_as_typed_arrays() {
    let mesh = slitpath::fixtures::flank_plane(60.0, 50.0, 12, 10);
    let stl = slitpath::mesh::stl::write_binary(&mesh, "plane");
    let options = js_sys::JSON::parse(
        r#"{"tipRadiusMm": 1, "topRadiusMm": 2, "fluteLengthMm": 12, "direction": [1, 0, 0], "poseStepMm": 6,
            "weights": "g1", "post": "cl", "verifySamples": 500}"#,
    )
    .unwrap();
    let plan = slitpath::wasm::plan_flank(&stl, JsValue::UNDEFINED, options, None, JsValue::UNDEFINED).unwrap();
    let moves = plan.tips().len() / 3;
    assert!(moves > 10 && plan.axes().len() == 3 * moves);
    assert_eq!(plan.strip_moves().len(), 2 * 4);
    let poses: u32 = plan.poses_per_strip().iter().sum();
    assert_eq!(plan.contact_points().len(), 3 * poses as usize * plan.contact_samples() as usize);
    assert_eq!(plan.vertex_deviation().len(), plan.positions().len() / 3);
    assert!(plan.gcode().starts_with("PARTNO ") && plan.cl() == plan.gcode());
    let report = plan.report().unwrap();
    let guide = Reflect::get(&report, &"guide".into()).unwrap();
    assert_eq!(Reflect::get(&guide, &"strips".into()).unwrap().as_f64(), Some(4.0));
    let bad = js_sys::JSON::parse(r#"{"tipRadiusMm": -1}"#).unwrap();
    let err: js_sys::Error = JsValue::from(
        slitpath::wasm::plan_flank(&stl, JsValue::UNDEFINED, bad, None, JsValue::UNDEFINED).err().unwrap(),
    )
    .dyn_into()
    .unwrap();
    assert!(String::from(err.message()).contains("tip_radius_mm"), "{}", String::from(err.message()));
    let unknown = js_sys::JSON::parse(r#"{"radius": 1}"#).unwrap();
    assert!(slitpath::wasm::plan_flank(&stl, JsValue::UNDEFINED, unknown, None, JsValue::UNDEFINED).is_err());
}

/// `planFlankOnStepFile` on faces of a `StepFile` (issue 36): the plan `planFlank` makes of the
/// file's bytes with that selection, byte for byte, from the file read once (one handle serves
/// several selections); an unknown face is an `Error` naming it.
#[wasm_bindgen_test]
fn plan_flank_on_a_step_file_is_plan_flank_of_its_bytes() {
    let step = slitpath::fixtures::step::by_name("cylinder_band").unwrap();
    let options = || {
        js_sys::JSON::parse(
            r#"{"tipRadiusMm": 1.5, "topRadiusMm": 2.5, "fluteLengthMm": 20, "direction": [1, 0, 0], "verifySamples": 2000}"#,
        )
        .unwrap()
    };
    let file = slitpath::wasm::StepFile::new(step.as_bytes(), JsValue::UNDEFINED, None).unwrap();
    for faces in [[62.0, 78.0], [78.0, 94.0]] {
        let from_file =
            slitpath::wasm::plan_flank_on_step_file(&file, Some(faces.to_vec()), JsValue::UNDEFINED, options(), None)
                .unwrap();
        let step_options = js_sys::JSON::parse(&format!(r#"{{"faces": [{}, {}]}}"#, faces[0], faces[1])).unwrap();
        let from_bytes =
            slitpath::wasm::plan_flank(step.as_bytes(), JsValue::UNDEFINED, options(), None, step_options).unwrap();
        assert!(from_file.gcode().len() > 1000);
        assert_eq!(from_file.gcode(), from_bytes.gcode(), "faces {faces:?}");
        assert_eq!(from_file.positions(), from_bytes.positions());
    }
    let err: js_sys::Error = JsValue::from(
        slitpath::wasm::plan_flank_on_step_file(&file, Some(vec![999.0]), JsValue::UNDEFINED, options(), None)
            .err()
            .unwrap(),
    )
    .dyn_into()
    .unwrap();
    assert!(String::from(err.message()).contains("#999"), "{}", String::from(err.message()));
}
