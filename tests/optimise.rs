//! Stage `optimise` (seed 003): the constraints after every accepted step, the identity at zero
//! iterations, a fixed point on the concentric annulus, and shorter verified paths on parts
//! with holes.

use glam::DVec2;
use slitpath::fixtures;
use slitpath::mesh::{self, MeshOptions, Surface, TriMesh};
use slitpath::optimise::{self, OptimiseOptions, Step};
use slitpath::origin::{EnergyEvaluator, OriginOptions};
use slitpath::plan::{Optimise, PlanOptions, Planner};
use slitpath::slitmap::{Mode, SlitMap};
use slitpath::spacing::{self, SpacingOptions};

fn planner(mesh: &TriMesh) -> Planner {
    let out = mesh::from_triangles(mesh, &MeshOptions::default()).expect("a valid fixture");
    Planner::new(out, &|| 0.0).expect("plannable")
}

/// The slit map of `pole` and the origin's radial function there (f_min per radius bin).
fn map_and_slopes(p: &Planner, pole: DVec2, radius_mm: f64) -> (SlitMap, Vec<f64>) {
    let options = OriginOptions { radius_mm, ..OriginOptions::default() };
    let evaluator = EnergyEvaluator::new(&p.surface, &p.solver, &options).expect("energy");
    let (energy, map) = evaluator.evaluate_with_map(pole).expect("a pole inside");
    (map, energy.slopes)
}

/// Signed orientation of every face in the log-polar strip (arg w, |w|), negative = valid, and
/// whether the strip locates it (narrower than 0.5 rad, not the pole's face).
fn strip_orientations(map: &SlitMap) -> Vec<Option<f64>> {
    map.log_polar_corners()
        .iter()
        .enumerate()
        .map(|(f, c)| {
            let span = c[0].x.max(c[1].x).max(c[2].x) - c[0].x.min(c[1].x).min(c[2].x);
            (span < 0.5 && Some(f) != map.pole_face).then(|| (c[1] - c[0]).perp_dot(c[2] - c[0]))
        })
        .collect()
}

/// Runs the optimisation of `map` and checks after every accepted step: no face inverted that
/// was not (w plane and strip), every hole one radius, the outer loop at 1, every angle and the
/// pole kept, E never risen. Returns the number of steps.
fn assert_constraints_hold(surface: &Surface, map: &SlitMap, slopes: &[f64], options: &OptimiseOptions) -> usize {
    let start_w: Vec<bool> = map.image_signed_areas().iter().map(|&a| a > 0.0).collect();
    let start_strip: Vec<bool> = strip_orientations(map).iter().map(|o| o.map_or(true, |o| o < 0.0)).collect();
    let mut steps = 0;
    let mut last = f64::INFINITY;
    optimise::optimise_observed(surface, map, slopes, options, &mut |radii, energy| {
        steps += 1;
        assert!(energy.total <= last, "step {steps}: E rose from {last} to {}", energy.total);
        last = energy.total;
        let m = map.with_radii(radii, &surface.loops);
        for (f, (&a, &was)) in m.image_signed_areas().iter().zip(&start_w).enumerate() {
            assert!(!was || a > 0.0, "step {steps}: face {f} inverted in the w plane");
        }
        for (f, (o, &was)) in strip_orientations(&m).iter().zip(&start_strip).enumerate() {
            assert!(!was || o.map_or(true, |o| o < 0.0), "step {steps}: face {f} inverted in the strip");
        }
        for (li, l) in surface.loops.iter().enumerate() {
            let r: Vec<f64> = l.iter().map(|&v| m.w[v as usize].length()).collect();
            let (lo, hi) = r.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
            assert!(hi - lo <= 1e-12, "step {steps}: loop {li} spans radii {lo}..{hi}");
            if li == 0 {
                assert!((hi - 1.0).abs() <= 1e-12, "step {steps}: the outer loop left |w| = 1 ({hi})");
            }
        }
        for (v, (a, b)) in m.w.iter().zip(&map.w).enumerate() {
            let turn = a.perp_dot(*b).atan2(a.dot(*b)).abs();
            assert!(turn <= 1e-12, "step {steps}: vertex {v} turned by {turn} rad");
        }
        assert_eq!((m.pole, m.pole_face), (map.pole, map.pole_face), "the pole moved");
    })
    .expect("optimises");
    steps
}

#[test]
fn every_accepted_step_keeps_the_foliation_the_boundaries_and_the_pole() {
    // A disk map of the sample part (four holes), and the annulus map of the eccentric annulus.
    let part = planner(&fixtures::freeform_4_holes());
    let (map, slopes) = map_and_slopes(&part, part.domain.largest_face_centre(), 3.0);
    assert_eq!(map.mode, Mode::Disk);
    let options = OptimiseOptions { max_iterations: 6, tolerance_rel: 0.0, ..OptimiseOptions::default() };
    assert!(assert_constraints_hold(&part.surface, &map, &slopes, &options) >= 3);

    let annulus = planner(&fixtures::by_name("eccentric_annulus").unwrap());
    let (map, slopes) = map_and_slopes(&annulus, annulus.solver.canonical_hole_pole(1), 0.05);
    assert!(matches!(map.mode, Mode::Annulus { .. }));
    let options = OptimiseOptions { radius_mm: 0.05, ..options };
    assert!(assert_constraints_hold(&annulus.surface, &map, &slopes, &options) >= 1);
}

#[test]
fn the_papers_sigmoid_step_descends_and_keeps_the_constraints() {
    // Seed 003 eqs. 30–32 with C = 0.9: slow (one ring of vertices per step) but a descent.
    let part = planner(&fixtures::plate_3_holes());
    let (map, slopes) = map_and_slopes(&part, part.domain.largest_face_centre(), 3.0);
    let options =
        OptimiseOptions { step: Step::Sigmoid { c: 0.9 }, max_iterations: 8, tolerance_rel: 0.0, ..Default::default() };
    let steps = assert_constraints_hold(&part.surface, &map, &slopes, &options);
    let report = optimise::optimise(&part.surface, &map, &slopes, &options).unwrap().report.unwrap();
    assert_eq!(report.iterations, steps);
    assert!(report.after.total < report.before.total, "{:?}", report);
}

#[test]
fn zero_iterations_return_the_conformal_map_bit_for_bit() {
    let part = planner(&fixtures::plate_3_holes());
    let (map, slopes) = map_and_slopes(&part, part.domain.largest_face_centre(), 3.0);
    let same =
        optimise::optimise(&part.surface, &map, &slopes, &OptimiseOptions { max_iterations: 0, ..Default::default() })
            .unwrap();
    assert!(same.report.is_none());
    let bits = |m: &SlitMap| m.w.iter().flat_map(|w| [w.x.to_bits(), w.y.to_bits()]).collect::<Vec<u64>>();
    assert_eq!(bits(&same.map), bits(&map));
    assert_eq!((same.map.slits, same.map.mode), (map.slits.clone(), map.mode));
    // The planner's `--optimise none` is that stage: the same path as the conformal map's, named
    // in the G-code.
    let options = PlanOptions { optimise: Optimise::None, verify_samples: 0, ..PlanOptions::default() };
    let plan = part.plan(&options, &mut |_, _, _| {}, &|| 0.0).unwrap();
    assert!(plan.report.optimise.is_none());
    assert!(plan.gcode.contains("(- field: conformal slit map, seed 000)"), "the header names the field");
}

/// Plans `mesh` with and without the optimisation: (conformal, optimised) length, verified max
/// scallop over h and the optimised plan's field.
fn both(mesh: &TriMesh, options: PlanOptions) -> ((f64, f64), (f64, f64), String) {
    let p = planner(mesh);
    let run = |optimise| {
        let plan = p.plan(&PlanOptions { optimise, ..options.clone() }, &mut |_, _, _| {}, &|| 0.0).unwrap();
        let v = plan.report.verify.as_ref().unwrap();
        let field = plan.report.optimise.as_ref().map_or("conformal".to_string(), |o| {
            format!("{}{}", o.path_field, o.fallback.as_ref().map_or(String::new(), |f| format!(": {f}")))
        });
        ((plan.report.path.length_mm, v.max_scallop_mm / options.scallop_mm), field)
    };
    let ((a, _), (b, field)) = (run(Optimise::None), run(Optimise::Tpsfo));
    (a, b, field)
}

/// The annulus fixture `name` planned around its hole (ball radius `r`, scallop limit `h`): the
/// planner, and the total length of its rings spaced on the conformal map and on the
/// optimised field.
fn annulus_ring_lengths(name: &str, r: f64, h: f64) -> (Planner, f64, f64) {
    let p = planner(&fixtures::by_name(name).unwrap());
    let (map, slopes) = map_and_slopes(&p, p.solver.canonical_hole_pole(1), r);
    let optimised =
        optimise::optimise(&p.surface, &map, &slopes, &OptimiseOptions { radius_mm: r, ..Default::default() })
            .unwrap()
            .map;
    let spacing = SpacingOptions { radius_mm: r, scallop_mm: h, ..SpacingOptions::default() };
    let length = |m: &SlitMap| -> f64 {
        spacing::spacing(&p.surface, m, &spacing).unwrap().rings.iter().map(|k| k.length_mm).sum()
    };
    let (before, after) = (length(&map), length(&optimised));
    (p, before, after)
}

#[test]
fn the_concentric_annulus_is_a_fixed_point() {
    // Its conformal rings are already evenly spaced circles: the optimised field's rings, spaced
    // alike, are as long within 0.5 %, and the plan follows the optimised field.
    let (r, h) = (0.05, 0.0005);
    let (p, before, after) = annulus_ring_lengths("concentric_annulus", r, h);
    assert!((after / before - 1.0).abs() < 0.005, "rings {before} mm -> {after} mm");
    let options = PlanOptions { radius_mm: r, scallop_mm: h, ..PlanOptions::default() };
    let plan = p.plan(&options, &mut |_, _, _| {}, &|| 0.0).unwrap();
    assert_eq!(plan.report.optimise.as_ref().map(|o| o.path_field), Some("tpsfo"));
    assert!(plan.report.verify.as_ref().unwrap().max_scallop_mm <= h);
}

#[test]
fn holes_give_shorter_paths_at_the_same_verified_scallop() {
    // The sample part: four holes, whose slit tips pack the conformal rings.
    let ((before, max0), (after, max1), field) = both(&fixtures::freeform_4_holes(), PlanOptions::default());
    println!("freeform_4_holes: {before:.0} mm ({max0:.3} h) -> {after:.0} mm ({max1:.3} h), {field}");
    assert_eq!(field, "tpsfo");
    assert!(after < 0.9 * before, "{before} mm -> {after} mm");
    assert!(max0 <= 1.0 && max1 <= 1.0, "max scallop {max0} h -> {max1} h");
}

#[test]
fn the_eccentric_annulus_rings_are_shorter() {
    // Its conformal rings (Apollonius circles) bunch on the narrow side; the optimised field's,
    // spaced alike, are shorter. (The planner spaces an optimised field's rings for 0.92 h
    // instead of 0.95 h, which costs this part about what the field gains.)
    let (_, before, after) = annulus_ring_lengths("eccentric_annulus", 0.05, 0.0005);
    println!("eccentric annulus rings: {before:.1} mm -> {after:.1} mm");
    assert!(after < 0.98 * before, "rings {before} mm -> {after} mm");
}

#[test]
fn a_larger_alpha_gives_smoother_and_no_shorter_paths() {
    // Seed 003 §3.1 (Fig. 9): as α grows the field bends less (E_n + E_g), the path is no
    // shorter and turns less (ρ², eq. 33) than with the weakest smoothing. ρ² is a property of
    // the spiral drawn through the spacing's rings, so between two strong α it may go either
    // way by a few per cent; it is compared with α = 1 only.
    let p = planner(&fixtures::freeform_4_holes());
    let mut rows: Vec<(f64, f64, f64)> = Vec::new();
    for alpha in [1.0, 10.0, 100.0] {
        let options = PlanOptions { alpha, verify_samples: 0, ..PlanOptions::default() };
        let plan = p.plan(&options, &mut |_, _, _| {}, &|| 0.0).unwrap();
        let stage = plan.report.optimise.as_ref().and_then(|o| o.stage.as_ref()).expect("optimised");
        let bending = stage.after.e_n + stage.after.e_g;
        let (length, rho2) = (plan.report.path.length_mm, plan.report.path.rho2);
        println!("α {alpha}: {length:.1} mm, ρ² {rho2:.1}, E_n + E_g {bending:.4}");
        if let Some(&(l, _, b)) = rows.last() {
            // Within 2 %: the gate's cusp search (stop 39) moves each field's rings by about 1 % either way.
            assert!(length >= l * 0.98, "α {alpha}: {length} mm after {l} mm");
            assert!(bending <= b * 1.001, "α {alpha}: E_n + E_g {bending} after {b}");
        }
        rows.push((length, rho2, bending));
    }
    // Measured at stop 41 (ring centres moved out by their facet lift): α 10 and 100 give 0.50
    // and 0.33 of α 1's ρ²; at stop 40, under 0.5 both. The claim is a clear drop, not a ratio.
    for &(_, rho2, _) in &rows[1..] {
        assert!(rho2 < 0.6 * rows[0].1, "ρ² {rho2} against {} at α 1", rows[0].1);
    }
}
