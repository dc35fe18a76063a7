//! Integration tests of the Coons band strategy (seed 004, issue 36 items 3–5), on STEP files
//! written by the repository's own writer (`src/fixtures/step_band.rs`).

use glam::DVec3;
use slitpath::coons::{self, band, compound, CoonsError, CoonsOptions};
use slitpath::fixtures::{step as step_fixtures, step_band};
use slitpath::step::{self, Model};

fn model(text: &str) -> Model {
    step::read(text.as_bytes()).expect("the fixture reads")
}

fn ids(m: &Model) -> Vec<u64> {
    m.faces.iter().map(|f| f.id).collect()
}

fn quick() -> CoonsOptions {
    CoonsOptions { verify_samples: 20_000, ..CoonsOptions::default() }
}

#[test]
fn a_rectangle_maps_affinely_and_its_sides_are_reproduced() {
    let m = model(&step_band::plane_rectangle());
    let f = band::single(&m, m.faces[0].id, &CoonsOptions::default()).unwrap();
    let p = compound::patch(&m, &f).unwrap();
    let c = step_band::rectangle_corners();
    let mut worst: f64 = 0.0;
    for a in 0..=20 {
        for b in 0..=20 {
            let (s, t) = (a as f64 / 20.0, b as f64 / 20.0);
            let want = c[0] + (c[1] - c[0]) * s + (c[3] - c[0]) * t;
            worst = worst.max((p.eval(s, t).x - want).length());
        }
    }
    assert!(worst < 1e-9, "the map strays {worst} mm from the affine map");
}

#[test]
fn the_cylinder_faces_reproduce_their_arc_length_sides() {
    let m = model(&step_band::cylinder_band());
    let c = coons::compound(&m, &ids(&m), &CoonsOptions::default()).unwrap();
    let (r, h) = (step_band::CYLINDER_RADIUS_MM, step_band::CYLINDER_HEIGHT_MM);
    let mut worst: f64 = 0.0;
    for i in 0..4 {
        let p = c.patch(i, 0);
        // Where face i starts round the loop (its bottom-left corner).
        let a0 = num_angle(p.eval(0.0, 0.0).x);
        let at = |deg: f64, z: f64| DVec3::new(r * deg.to_radians().cos(), r * deg.to_radians().sin(), z);
        for k in 0..=97 {
            // Odd spacing: between the side tables' samples.
            let q = k as f64 / 97.0;
            worst = worst.max((p.eval(q, 0.0).x - at(a0 + 90.0 * q, 0.0)).length());
            worst = worst.max((p.eval(q, 1.0).x - at(a0 + 90.0 * q, h)).length());
            worst = worst.max((p.eval(0.0, q).x - at(a0, h * q)).length());
            worst = worst.max((p.eval(1.0, q).x - at(a0 + 90.0, h * q)).length());
            // Developable: the interior is affine in (angle, height) too.
            worst = worst.max((p.eval(q, 0.3).x - at(a0 + 90.0 * q, 0.3 * h)).length());
        }
    }
    assert!(worst < 1e-9, "sides off by {worst} mm");
}

fn num_angle(p: DVec3) -> f64 {
    p.y.atan2(p.x).to_degrees()
}

#[test]
fn the_blade_band_is_regular_and_its_seams_coincide() {
    let m = model(&step_band::blade_band());
    let raw = coons::compound(&m, &ids(&m), &CoonsOptions::default()).unwrap();
    assert_eq!((raw.around, raw.across), (4, 2));
    // det J > 0 over a 200 × 200 grid of every face; shared sides (the fillet's are quadratic
    // B-splines used reversed by one face) give the same points.
    assert!(raw.det_j_min_rel(200) > 0.0);
    assert!(raw.seam_gap_mm(200) <= 1e-6, "{}", raw.seam_gap_mm(200));
    let plan = coons::plan(&m, &ids(&m), &CoonsOptions { verify_samples: 0, ..quick() }, &|| 0.0).unwrap();
    assert!(plan.compound.det_j_min_rel(200) > 0.0);
    assert!(plan.compound.seam_gap_mm(200) <= 1e-6);
}

#[test]
fn the_cylinder_band_is_cut_by_one_helix_whose_pitch_is_the_stepover() {
    let m = model(&step_band::cylinder_band());
    let o = quick();
    let plan = coons::plan(&m, &ids(&m), &o, &|| 0.0).unwrap();
    let r = &plan.report;
    assert_eq!(r.retractions, 0);
    assert_eq!(plan.toolpath.stats.retractions, 1, "one pass, one final retract");
    // Every contact point on the exact cylinder.
    for p in &plan.points {
        assert!((p.x.truncate().length() - step_band::CYLINDER_RADIUS_MM).abs() < 1e-9);
    }
    // The stepover along the axis: the flat-surface width for 0.95 h, scaled to fit exactly.
    let h = 0.95 * o.scallop_mm;
    let nominal = 2.0 * (h * (2.0 * o.radius_mm - h)).sqrt();
    assert!((r.min_spacing_mm - r.max_spacing_mm).abs() < 1e-9 * nominal);
    assert!(r.max_spacing_mm <= nominal && r.max_spacing_mm > 0.98 * nominal);
    // The helix: z rises linearly with the angle by one stepover a turn (inclined revolutions only).
    let stepover = r.max_spacing_mm;
    let mut worst: f64 = 0.0;
    let mut turns = 0;
    for p in plan.points.iter().filter(|p| p.u > 4.0 && p.u < 4.0 * (plan.lines.len() - 1) as f64) {
        let turn = (p.u / 4.0).floor();
        let z0 = plan.levels[turn as usize - 1] * step_band::CYLINDER_HEIGHT_MM;
        let want = z0 + stepover * (p.u / 4.0 - turn);
        worst = worst.max((p.x.z - want).abs());
        turns = turns.max(turn as usize);
    }
    assert!(worst <= 0.01 * stepover, "the path strays {worst} mm from the helix of pitch {stepover}");
    assert_eq!(turns, plan.levels.len() - 1);
    let v = r.verify.as_ref().unwrap();
    assert!(v.max_scallop_mm <= o.scallop_mm, "{}", v.max_scallop_mm);
    assert_eq!((v.gouges, v.uncovered_samples, v.retractions), (0, 0, 0));
    assert!(plan.gcode.contains("strategy: coons band spiral, seed 004"));
}

#[test]
fn the_blade_band_seams_are_smoothed_and_the_scallop_is_held() {
    let m = model(&step_band::blade_band());
    let o = quick();
    let plan = coons::plan(&m, &ids(&m), &o, &|| 0.0).unwrap();
    let s = &plan.report.seams;
    eprintln!("seams {s:?}");
    assert_eq!(s.mode, "composite-c1");
    // Faces of unequal width round the loop: the raw map turns the path at every seam.
    assert!(s.round_before.max_deg > 0.5 && s.round_before.crossings > 200);
    assert!(s.round_after.max_deg < 0.1, "{}", s.round_after.max_deg);
    assert!(s.rows_after.crossings >= 1 && s.rows_after.max_deg < 0.1);
    let v = plan.report.verify.as_ref().unwrap();
    eprintln!("max {} p95 {} length {}", v.max_scallop_mm, v.p95_scallop_mm, plan.report.length_mm);
    assert!(v.max_scallop_mm <= o.scallop_mm, "{}", v.max_scallop_mm);
    assert_eq!((v.gouges, v.uncovered_samples, v.retractions), (0, 0, 0));
    // Without smoothing the path is the same lines on the raw map, its jumps are the "before".
    let raw = coons::plan(&m, &ids(&m), &CoonsOptions { smooth: false, verify_samples: 0, ..o }, &|| 0.0).unwrap();
    assert_eq!(raw.report.seams.mode, "none");
    assert!((raw.report.seams.round_after.max_deg - s.round_before.max_deg).abs() < 0.05);
}

/// The page's heat map of a Coons plan: the scallop at the vertices of the faces' own
/// tessellation (which lie on the exact surfaces). On the plan's verification grid it is the
/// verifier's per-vertex figure, and on the band's tessellation it holds h where the samples do.
#[test]
fn the_heat_map_on_the_faces_tessellation_holds_the_scallop() {
    let text = step_band::blade_band();
    let m = model(&text);
    let o = quick();
    let plan = coons::plan(&m, &ids(&m), &o, &|| 0.0).unwrap();
    let verified = plan.report.verify.as_ref().unwrap().max_scallop_mm;

    // Oracle: the verifier's own per-vertex probes on its grid.
    let (grid, _, _) = coons::mesh::grid_surface(&plan.compound, o.scallop_mm / 20.0).unwrap();
    let centres: Vec<DVec3> = plan.toolpath.contact_moves().iter().map(|mv| mv.centre).collect();
    let vo = slitpath::verify::VerifyOptions {
        radius_mm: o.radius_mm,
        scallop_mm: o.scallop_mm,
        samples: 1000,
        ..Default::default()
    };
    let full = slitpath::verify::verify(&grid, &[centres], &vo).unwrap();
    let mine = plan.vertex_scallop_mm(&grid).unwrap();
    assert_eq!(mine.len(), grid.positions.len());
    for (v, (&a, (&b, &uncovered))) in
        mine.iter().zip(full.vertex_scallop_mm.iter().zip(&full.vertex_uncovered)).enumerate()
    {
        assert!(if uncovered { a.is_nan() } else { a == b }, "vertex {v}: {a} vs {b}");
    }

    // The page's surface: the faces tessellated as the STEP reader gives them.
    let part = step::load(text.as_bytes(), &step::StepOptions::default(), &Default::default(), &|| 0.0).unwrap();
    let heat = plan.vertex_scallop_mm(&part.mesh.surface).unwrap();
    let covered: Vec<f64> = heat.iter().copied().filter(|s| !s.is_nan()).collect();
    let max = covered.iter().copied().fold(0.0, f64::max);
    let mut sorted = covered.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    eprintln!(
        "heat: {} of {} vertices covered, max {max} mm (samples {verified}), median {median}",
        covered.len(),
        heat.len()
    );
    assert!(covered.len() as f64 >= 0.99 * heat.len() as f64, "{} of {}", covered.len(), heat.len());
    assert!(max <= 1.02 * o.scallop_mm && median < 0.5 * o.scallop_mm, "max {max}, median {median}");
}

#[test]
fn selections_that_are_not_a_band_are_typed_errors() {
    let o = CoonsOptions::default();
    let two = model(&step_fixtures::two_patches());
    let e = coons::plan(&two, &ids(&two), &o, &|| 0.0).unwrap_err();
    assert!(matches!(e, CoonsError::NotClosed { .. }) && e.is_not_a_band(), "{e}");
    let hole = model(&step_fixtures::plate_with_hole(false));
    let e = coons::plan(&hole, &ids(&hole), &o, &|| 0.0).unwrap_err();
    assert!(matches!(e, CoonsError::NotFourSided { face, .. } if face == hole.faces[0].id), "{e}");
    let blade = model(&step_band::blade_band());
    let mut some = ids(&blade);
    some.remove(5);
    let e = coons::plan(&blade, &some, &o, &|| 0.0).unwrap_err();
    assert!(e.is_not_a_band(), "{e}");
    let e = coons::plan(&blade, &[], &o, &|| 0.0).unwrap_err();
    assert_eq!(e, CoonsError::NoFaces);
    let e = coons::plan(&blade, &[99_999], &o, &|| 0.0).unwrap_err();
    assert_eq!(e, CoonsError::UnknownFace { face: 99_999 });
}
