//! Issue 34: generated parts flatten without folding and plan end to end with a verified finish.
//!
//! The named parts (`fixtures::generated::NAMED`) are shaped like the parts that found the bug:
//! staircase rims of tilted slots and ellipses, around which BFF's old fan filling of the holes
//! was inverted and folded 7, 1 and 2 real triangles. They must now flatten with BFF itself
//! (fallbacks off) and plan. The sweep plans a dozen small generated parts of fixed seeds.
// Native only: the plans take seconds each (the browser runs tests/wasm.rs).
#![cfg(not(target_arch = "wasm32"))]

use slitpath::bench::{run_sweep, SweepFigures};
use slitpath::fixtures::generated::{self, GeneratedPart};
use slitpath::flatten::{flatten, FlattenInput, FlattenMethod, FlattenOptions};
use slitpath::{mesh, plan};

/// Flattens the planning surface of named part `name` with BFF alone (no fallback) and checks
/// it; then plans it with its R and h and checks the verified finish ([`run_sweep`]).
fn flattens_and_plans(name: &str) -> SweepFigures {
    let spec = generated::named(name).expect("a named part");
    let part = GeneratedPart { name: name.to_string(), mesh: generated::build(&spec), spec };
    let out = mesh::from_triangles(&part.mesh, &mesh::MeshOptions::default()).expect("mesh");
    let surface = plan::planning_surface(&out.surface);
    let bff_only = FlattenOptions { disk_fallback: false, embedding_fallback: false, ..FlattenOptions::default() };
    let f = flatten(FlattenInput::from(&surface), &bff_only).unwrap_or_else(|e| panic!("{name}: {e}"));
    println!(
        "{name}: {} faces, qc mean {:.4} max {:.4}, holes {:?}",
        surface.triangles.len(),
        f.quality.qc_mean,
        f.quality.qc_max,
        f.hole_fills
    );
    assert_eq!(f.quality.flipped_triangles, 0, "{name}");
    assert!(f.quality.boundary_valid, "{name}");
    assert_eq!(f.method, FlattenMethod::Bff);
    assert!(f.quality.qc_max < 1.05, "{name}: qc max {}", f.quality.qc_max);
    // Some rims are staircases that are not star-shaped from their centre: triangulated.
    assert!(f.hole_fills.triangulated > 0, "{name}: {:?}", f.hole_fills);

    let row = run_sweep(&part, 100_000, &|| 0.0).unwrap_or_else(|e| panic!("{name}: {} at {}", e.message, e.stage));
    println!("{name}: planned, max scallop {:.3} h", row.max_over_h);
    assert_eq!(row.flatten.method, FlattenMethod::Bff, "{name}");
    row
}

#[test]
fn staircase_saddle_with_three_slots_flattens() {
    flattens_and_plans("staircase_saddle_3_slots");
}

#[test]
fn saddle_disk_with_four_bumps_and_five_holes_flattens() {
    flattens_and_plans("saddle_disk_4_bumps_5_holes");
}

#[test]
fn skinny_tilted_panel_with_six_holes_flattens() {
    flattens_and_plans("skinny_tilted_panel_6_holes");
}

/// The seeds of the sweep (3k–8k faces): the first twelve.
const SWEEP_SEEDS: std::ops::Range<u64> = 0..12;

#[test]
fn generated_parts_plan_within_the_scallop_limit() {
    let mut failures = Vec::new();
    for seed in SWEEP_SEEDS {
        let part = generated::part(seed, 3_000..=8_000);
        match run_sweep(&part, 50_000, &|| 0.0) {
            Ok(row) => {
                println!("{}: {:?}, {}", row.name, row.flatten.method, row.finish());
                // Seed 6 peaks at 1.67 h in the valleys its facets alone leave (2.04 h deep): the
                // plan warns of them, and `within_limits` accepts that.
                // Judged on the plan's own samples and on fresh ones, as the sweep bench judges
                // (with three cusp lines per face gen001, gen002 and gen006 left 1.02–1.05 h on
                // fresh samples; the gate's lines R/12 apart on coarse faces keep all under h).
                if !row.within_limits() {
                    failures.push(format!("{}: {}", row.name, row.finish()));
                }
                // Whatever the facets leave over h, the user was told before trusting the file.
                if row.max_outside_valleys_over_h < row.max_over_h && row.max_over_h > 1.02 {
                    assert!(row.facet_depth_over_h > 1.0, "{}: {}", row.name, row.finish());
                }
                assert_eq!(row.flatten.quality.flipped_triangles, 0);
            }
            Err(f) => failures.push(format!("{} at {}: {}", f.name, f.stage, f.message)),
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The planner of a generated part, its mesh checked with the default options.
fn planner(part: &generated::GeneratedPart) -> plan::Planner {
    let out = mesh::from_triangles(&part.mesh, &mesh::MeshOptions::default()).expect("mesh");
    plan::Planner::new(out, &|| 0.0).expect("planner")
}

/// The sweep's worst peak outside any facet valley (issue 34's sweep, gen143: a 4k-face
/// staircase rectangle, 1.142 h): the plan reports where it is, between which rings, in the
/// slit domain, and that place is the verifier's worst sample.
#[test]
fn the_sweeps_worst_peak_is_located_between_its_rings() {
    let part = generated::part(143, slitpath::bench::SWEEP_FACES);
    let planner = planner(&part);
    let (r, h) = (part.spec.radius_mm, part.spec.scallop_mm);
    let options = plan::PlanOptions { radius_mm: r, scallop_mm: h, verify_samples: 20_000, ..Default::default() };
    let p = planner.plan(&options, &mut |_, _, _| {}, &|| 0.0).expect("plan");
    let v = p.report.verify.as_ref().expect("verified");
    let at = v.max_scallop_at.expect("a covered sample");
    assert_eq!(at.scallop_mm, v.max_scallop_mm);
    assert_eq!(Some(at.position), v.worst_sample);
    let peak = p.report.max_scallop_at.as_ref().expect("located");
    assert_eq!((peak.sample.scallop_mm, peak.sample.face), (at.scallop_mm, at.face));
    let radii = &p.report.ring_radii;
    let (outside, inside) = (peak.ring_outside.expect("inside ring 0"), peak.ring_inside.expect("outside the last"));
    assert_eq!(inside, outside + 1);
    assert!(radii[inside] <= peak.rho && peak.rho < radii[outside], "{peak:?}");
    assert!(peak.theta.abs() <= std::f64::consts::PI);
    let outside_valleys = p.report.max_outside_valleys_at.as_ref().expect("located");
    assert!(!outside_valleys.sample.in_valley && outside_valleys.sample.scallop_mm == v.max_scallop_outside_valleys_mm);
    println!("{}: max {:.3} h at {peak:?}", part.name, v.max_scallop_mm / h);
}

/// Issue 34's sweep: the finish peaked over h between the spacing gate's points on coarse
/// staircase rectangles: gen130 at 1.33 h round a corner of its outer loop (the map squeezes the
/// rings' turn into one face), gen143 at 1.14 h beside its facets. The gate now finds each
/// band's cusp on every edge and across every face. Checked on samples the plan never saw.
#[test]
fn issue_34_sweep_cusps_between_the_gates_points_stay_under_h() {
    for seed in [130, 143] {
        stays_under_h_on_fresh_samples(seed, 400_000);
    }
}

/// Issue 34's sweep: gen198 (a 4k-face staircase rectangle with two holes) kept 1.06 h on fresh
/// samples between two rings whose balls the toolpath lifts 0.7–0.8 h off their facets: the
/// spacing had planned the lift of a ball touching at each point tested, 0.09 h there. It now
/// moves the rings' centres out by the balls' own lift, as the toolpath's clearance finds it:
/// 0.95 h on the sweep's fresh samples. (On 2·10⁵ another peak shows, 1.06 h at |w| 0.140 where
/// the spiral leaves 0.90 h before the clearance and rings 147–148 lifted densely 0.65 h: see
/// docs/known-limits.md.)
#[test]
fn issue_34_sweep_rings_are_spaced_for_their_balls_lift_off_the_facets() {
    stays_under_h_on_fresh_samples(198, 100_000);
}

/// Plans sweep part `seed` with its R and h and checks its finish on `samples` fresh samples:
/// at most 1.02 h outside the facet valleys, no gouge, nothing uncovered.
fn stays_under_h_on_fresh_samples(seed: u64, samples: usize) {
    let part = generated::part(seed, slitpath::bench::SWEEP_FACES);
    let planner = planner(&part);
    let (r, h) = (part.spec.radius_mm, part.spec.scallop_mm);
    let options = plan::PlanOptions { radius_mm: r, scallop_mm: h, verify_samples: 0, ..Default::default() };
    let p = planner.plan(&options, &mut |_, _, _| {}, &|| 0.0).expect("plan");
    let fresh = plan::PlanOptions { verify_samples: samples, ..options };
    let v = planner.verify(&p.toolpath, &fresh, slitpath::bench::FRESH_SEED).expect("verified");
    println!(
        "{}: max {:.3} h outside valleys, {:.3} h in all",
        part.name,
        v.max_scallop_outside_valleys_mm / h,
        v.max_scallop_mm / h
    );
    assert!(
        v.max_scallop_outside_valleys_mm <= 1.02 * h,
        "{}: {:.3} h",
        part.name,
        v.max_scallop_outside_valleys_mm / h
    );
    assert_eq!((v.gouges, v.uncovered_samples), (0, 0), "{}", part.name);
}

/// Issue 34's sweep: gen016 (a 5k-face staircase rectangle with three holes) kept 1.12 h on
/// fresh samples 0.74 mm from a corner of its outer loop, which the map squeezes into one face:
/// the uncut spot is left by the ring turning round the corner, not a cusp between two rings,
/// and the gate had no point there. The outer loop's convex corners now get a grid of gate points
/// as the holes' ends do: 0.97 h.
#[test]
fn issue_34_sweep_the_outer_loops_corners_are_gated() {
    stays_under_h_on_fresh_samples(16, 100_000);
}

/// Issue 34's sweep: gen112 (a 3k-face staircase rectangle with one hole) kept 1.08 h on fresh
/// samples just outside a facet valley, where a ring passes right over the point but its balls,
/// placed along the interpolated normals, were lifted 0.7–1.1 h off the facets by the crease
/// beside them. A ball lifted more than the spacing plans for is now let down into the crease
/// (the ball touching its contact's own facet, slid along it until it clears the other flank)
/// when that leaves less, in the toolpath and in the spacing alike: 0.93 h.
#[test]
fn issue_34_sweep_gen112_balls_beside_a_crease_are_let_down_into_it() {
    stays_under_h_on_fresh_samples(112, 100_000);
}

/// Issue 34's sweep: gen114 (a 4k-face staircase rectangle with six holes) kept 1.023 h outside
/// its facet valleys on the plan's own samples, beside a shallow concave crease running along two
/// rings: their balls are lifted 0.25–0.29 h off the facets, less than is let down into the
/// crease, and the spacing leaves the first 0.03 h of a lift to its margin. A path whose own
/// verification leaves more than h now has its rings spaced again for a cusp smaller in
/// proportion ([`plan::RETRY_AIM`]), and the better path is kept: 0.898 h, for 4.7 % more path.
#[test]
fn issue_34_sweep_gen114_a_path_over_h_is_spaced_again() {
    let part = generated::part(114, slitpath::bench::SWEEP_FACES);
    let row = run_sweep(&part, 100_000, &|| 0.0).expect("plans");
    println!("{}: {}", row.name, row.finish());
    let retries = &row.report.spacing_retries;
    assert_eq!(retries.len(), 1, "{retries:?}");
    let retry = &retries[0];
    println!("{}", retry.describe());
    assert!(retry.max_over_h > 1.0 && retry.retry_target_fraction < retry.target_fraction, "{retry:?}");
    assert!(retry.kept && retry.retry_max_over_h <= Some(1.0), "{retry:?}");
    // The path written is the one spaced again, and it keeps h on its own samples and the limits
    // on fresh ones.
    assert_eq!(Some(row.report.path.length_mm), retry.retry_length_mm);
    assert!(row.max_outside_valleys_over_h <= 1.0, "{}", row.finish());
    assert!(row.within_limits(), "{}", row.finish());
}

/// Found planning gen14 from poles of the user's choice: from (−16, 20, 0) the slit map of its
/// 8k-face mesh folds 5 triangles, and the path misses a quarter of the part (142 h deep).
/// Before, the report had no warning (a note said the retry left as much), and the retry spaced
/// the rings 12 times closer for nothing. The plan now warns where the path is over h, how much
/// of the surface the ball never reaches and that the map folds at this origin, and does not
/// space the rings again for an excess over [`plan::MAX_RETRY_EXCESS`] h.
#[test]
fn gen14_from_a_folding_pole_warns_of_the_missed_region_and_is_not_spaced_again() {
    let part = generated::part(14, 8000..=8000);
    let planner = planner(&part);
    let h = 0.0157;
    let options = plan::PlanOptions {
        radius_mm: 2.29,
        scallop_mm: h,
        origin: slitpath::origin::OriginChoice::Point3d(glam::DVec3::new(-16.0, 20.0, 0.0)),
        verify_samples: 20_000,
        ..Default::default()
    };
    let plan = planner.plan(&options, &mut |_, _, _| {}, &|| 0.0).expect("plans");
    let report = &plan.report;
    let v = report.verify.as_ref().expect("verified");
    println!("{:?}", report.warnings);
    assert!(report.flipped_triangles > 0 && v.max_scallop_outside_valleys_mm > plan::MAX_RETRY_EXCESS * h, "{v:?}");
    assert!(report.spacing_retries.is_empty(), "{:?}", report.spacing_retries);
    let warned = report.warnings.iter().find(|w| w.starts_with("the path leaves up to")).expect("a scallop warning");
    let unreached = format!("never reaches {:.2} %", 100.0 * v.uncovered_fraction);
    assert!(v.uncovered_fraction > 0.01 && warned.contains(&unreached) && warned.contains("folds"), "{warned}");
}

/// Generated part `seed` planned with its own R and h and the ring spread (`--spread need`): its
/// planner, the options and the plan.
fn planned_with_spread(seed: u64) -> (plan::Planner, plan::PlanOptions, plan::Plan) {
    let part = generated::part(seed, slitpath::bench::SWEEP_FACES);
    let planner = planner(&part);
    let options = plan::PlanOptions {
        radius_mm: part.spec.radius_mm,
        scallop_mm: part.spec.scallop_mm,
        spread: plan::RingSpread::Need,
        ..Default::default()
    };
    let p = planner.plan(&options, &mut |_, _, _| {}, &|| 0.0).expect("plan");
    (planner, options, p)
}

/// Issue 32, found by stop 48's sweep: on gen009 (a 60 × 51 mm staircase rectangle, 11k faces)
/// the spread path left 1.13 h and was dropped for the unspread one (1.83 times the flat-plate
/// bound). Now a spread path that leaves more than h is spaced again like any other, and the
/// unspread path planned beside it: the retry keeps h and is the shorter, so it is written (1.60
/// times the bound).
#[test]
fn gen009_a_spread_path_over_h_is_spaced_again_and_kept_when_shorter() {
    let (_, _, p) = planned_with_spread(9);
    let spread = p.report.spread.as_ref().expect("the spread path is reported");
    println!("{spread:?} {:?}", p.report.spacing_retries);
    let retry = p.report.spacing_retries.iter().find(|r| r.field == "tpsfo, spread").expect("the spread path's retry");
    assert!(retry.max_over_h > 1.0 && retry.kept && retry.retry_max_over_h.is_some_and(|m| m <= 1.0), "{retry:?}");
    let (Some(mine), Some(other)) = (spread.length_mm, spread.unspread_length_mm) else {
        panic!("both paths planned: {spread:?}")
    };
    assert!(spread.kept && mine < 0.95 * other, "{spread:?}");
    assert!(spread.unspread_max_over_h.is_some_and(|m| m <= 1.0), "{spread:?}");
    assert_eq!((p.report.path.length_mm, retry.retry_length_mm), (mine, Some(mine)));
    assert!(p.gcode.contains("spread by each meridian's need"), "the header names the field");
}

/// Issue 32: a 94 × 48 mm staircase rectangle with one hole (sweep part gen013, 6k faces). Its
/// meridians to the far corners are the longest, and every ring of the field is spaced for
/// them; spread by each meridian's need ([`plan::RingSpread::Need`]) the rings are fewer, and
/// the path 18 % shorter (2.28 → 1.88 times the flat-plate bound), within h on fresh samples.
#[test]
fn gen013_rings_spread_by_each_meridians_need_are_shorter_at_the_same_finish() {
    let (planner, options, p) = planned_with_spread(13);
    let h = options.scallop_mm;
    let spread = p.report.spread.as_ref().expect("the spread path is reported");
    println!("{spread:?}");
    // Kept at once: it keeps h, so the unspread path is not planned.
    assert!(spread.kept && spread.max_over_h.is_some_and(|m| m <= 1.0), "{spread:?}");
    assert_eq!((spread.unspread_length_mm, spread.unspread_max_over_h), (None, None));
    let unspread = plan::PlanOptions { spread: plan::RingSpread::None, ..options.clone() };
    let unspread = planner.plan(&unspread, &mut |_, _, _| {}, &|| 0.0).expect("plan");
    assert!(p.report.path.length_mm <= 0.88 * unspread.report.path.length_mm, "{}", unspread.report.path.length_mm);
    assert_eq!(spread.length_mm, Some(p.report.path.length_mm));
    assert_eq!(p.report.path.retractions, 1, "one continuous spiral");
    // The gate's points of other bands, laid by its wide bands, are not counted against a ring.
    assert_eq!(p.report.gate_compromises, 0);
    assert!(p.gcode.contains("spread by each meridian's need"), "the header names the field");
    let fresh = plan::PlanOptions { verify_samples: 200_000, ..options };
    let v = planner.verify(&p.toolpath, &fresh, slitpath::bench::FRESH_SEED).expect("verified");
    println!("fresh: {:.3} h", v.max_scallop_outside_valleys_mm / h);
    assert!(
        v.max_scallop_outside_valleys_mm <= 1.02 * h,
        "{:.3} h on fresh samples",
        v.max_scallop_outside_valleys_mm / h
    );
    assert_eq!((v.gouges, v.uncovered_samples), (0, 0));
}
