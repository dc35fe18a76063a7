//! The whole pipeline on the holed fixtures: one continuous spiral on the surface that never
//! crosses a hole, verified by the independent scallop simulation, G-code accepted by rs274,
//! and byte-identical reruns.
// Native only: runs rs274 / reads files / uses serde_json (the browser tests are tests/wasm.rs).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use glam::{DVec2, DVec3};
use slitpath::gcode::Post;
use slitpath::origin::OriginChoice;
use slitpath::plan::{Facets, Optimise, Plan, PlanOptions, Planner};
use slitpath::{fixtures, mesh};

fn planner(name: &str) -> Planner {
    let part = fixtures::by_name(name).expect("fixture");
    let out = mesh::from_triangles(&part, &mesh::MeshOptions::default()).expect("mesh");
    Planner::new(out, &|| 0.0).expect("planner")
}

/// The planner of a shared mesh and the diagonal of its bounding box (mm); `None`, with a note,
/// when the mesh is absent.
fn shared_planner(name: &str) -> Option<(Planner, f64)> {
    let Ok(bytes) = std::fs::read(common::shared_mesh_dir().join(name)) else {
        eprintln!("skipped: {name} is absent");
        return None;
    };
    let out = mesh::load(&bytes, &mesh::MeshOptions::default()).expect("mesh");
    let (lo, hi) = mesh::weld::bounding_box(&out.surface.positions);
    Some((Planner::new(out, &|| 0.0).expect("planner"), (hi - lo).length()))
}

/// 5-axis, for the walls of the shared meshes at their own scale.
const FIVE_AXIS: slitpath::toolpath::Axes = slitpath::toolpath::Axes::Five { lead_deg: 15.0, tilt_deg: 0.0 };

/// The plan bench's options for a shared mesh at its own scale (bounding-box `diagonal`):
/// R = diagonal / 60 up to 3 mm, h = R / 150 up to 0.02 mm, 5-axis, CL data, with `facets`.
fn bench_options(diagonal: f64, facets: Facets) -> PlanOptions {
    let r = (diagonal / 60.0).min(3.0);
    PlanOptions {
        radius_mm: r,
        scallop_mm: (r / 150.0).min(0.02),
        axes: FIVE_AXIS,
        post: Post::Cl,
        facets,
        ..PlanOptions::default()
    }
}

fn plan(p: &Planner, options: &PlanOptions) -> Plan {
    p.plan(options, &mut |_, _, _| {}, &|| 0.0).expect("plan")
}

/// The planned fixtures.
const PLANNED: [&str; 6] =
    ["plate_3_holes", "saddle_2_holes", "spherical_cap_hole", "freeform_4_holes", "box_boss_pocket", "sliver_mesh"];

/// Whether the segment ab crosses the closed polygon `lp` (flattened plane).
fn crosses(a: DVec2, b: DVec2, uv: &[DVec2], lp: &[u32]) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    (0..lp.len()).any(|k| {
        let (c, d) = (uv[lp[k] as usize], uv[lp[(k + 1) % lp.len()] as usize]);
        orient(a, b, c) * orient(a, b, d) < 0.0 && orient(c, d, a) * orient(c, d, b) < 0.0
    })
}

/// How deep `q` lies inside the polygon `lp` (0 when outside).
fn depth_inside(q: DVec2, uv: &[DVec2], lp: &[u32]) -> f64 {
    let mut inside = false;
    let mut d = f64::INFINITY;
    for k in 0..lp.len() {
        let (a, b) = (uv[lp[k] as usize], uv[lp[(k + 1) % lp.len()] as usize]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        let t = ((q - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
        d = d.min((a + (b - a) * t - q).length());
    }
    if inside {
        d
    } else {
        0.0
    }
}

#[test]
fn one_continuous_spiral_on_the_surface_that_never_crosses_a_hole() {
    for name in PLANNED {
        let p = planner(name);
        let pl = plan(&p, &PlanOptions { verify_samples: 0, ..PlanOptions::default() });
        let pts = &pl.spiral.points;
        assert!(pts.len() > 1000, "{name}: {} points", pts.len());
        assert_eq!(pl.toolpath.stats.retractions, 1, "{name}: only the final retract");
        let uv = &p.flattening.uv;
        let mut flat = Vec::with_capacity(pts.len());
        for q in pts {
            // Every contact is a barycentric point of its face: on the surface.
            let t = p.surface.triangles[q.face as usize];
            let [a, b, c] = t.map(|v| p.surface.positions[v as usize]);
            let n = (b - a).cross(c - a);
            let bary = [
                (b - q.cc).cross(c - q.cc).dot(n),
                (c - q.cc).cross(a - q.cc).dot(n),
                (a - q.cc).cross(b - q.cc).dot(n),
            ]
            .map(|x| x / n.length_squared());
            assert!(bary.iter().all(|&x| x > -1e-6), "{name}: contact off its face {bary:?}");
            assert!((q.normal.length() - 1.0).abs() < 1e-9);
            flat.push(t.iter().zip(bary).map(|(&v, w)| uv[v as usize] * w).sum::<DVec2>());
        }
        for pair in pts.windows(2) {
            assert!((pair[1].cc - pair[0].cc).length() <= 1.0 + 1e-9, "{name}: a segment longer than 1 mm");
        }
        // A segment may only graze a hole's rim within the chord tolerance (it hugs the rim):
        // its midpoint must not lie inside any hole deeper than that (flattened plane, mm).
        let mut grazes = 0;
        for pair in flat.windows(2) {
            for lp in &p.surface.loops[1..] {
                if crosses(pair[0], pair[1], uv, lp) {
                    grazes += 1;
                    let depth = depth_inside(0.5 * (pair[0] + pair[1]), uv, lp);
                    assert!(depth < 0.02, "{name}: a segment crosses a hole, {depth} mm deep");
                }
            }
        }
        println!("{name}: {grazes} segments graze a hole rim");
    }
}

#[test]
fn the_verifier_finds_the_scallop_under_control_and_no_gouge() {
    for name in PLANNED {
        let p = planner(name);
        let options = PlanOptions { verify_samples: 40_000, ..PlanOptions::default() };
        let pl = plan(&p, &options);
        let v = pl.verification().expect("verified");
        let h = options.scallop_mm;
        println!(
            "{name}: rings {} length {:.0} mm, max {:.4} p99 {:.4} mean {:.4} mm (h {h}), uncovered {:.5}, gouges {} (max {:.5} mm), E_min {:.1} vs centroid {:.1}",
            pl.rings.rings.len(),
            pl.path.length_mm,
            v.max_scallop_mm,
            v.p99_scallop_mm,
            v.mean_scallop_mm,
            v.uncovered_fraction,
            v.gouges,
            v.max_gouge_mm,
            pl.origin.energy.e_min,
            pl.origin.centroid_energy.e_min
        );
        assert!(v.uncovered_fraction <= 1e-3, "{name}: uncovered {}", v.uncovered_fraction);
        assert!(v.p99_scallop_mm <= h, "{name}: p99 scallop {} over h", v.p99_scallop_mm);
        // Issue 4's bound. The freeform panel was at 3.8 h with folds at slit tips, then 1.2 h
        // from polyline chains round the tips and sparse meridians there; the 40k panel kept
        // 1.16 h in an ear at a corner until ears were split.
        assert!(v.max_scallop_mm <= 1.02 * h, "{name}: max scallop {}", v.max_scallop_mm);
        // Issue 4: no gouge. The ball rode the interpolated normals and dipped up to 2.2 µm into
        // the facets (882 samples on saddle_2_holes) until its centres were kept off them; what
        // remains is the straight moves' chord tolerance, and the verifier counts deeper ones.
        assert_eq!(v.gouges, 0, "{name}: {} gouges, deepest {} mm", v.gouges, v.max_gouge_mm);
        assert!(pl.origin.energy.e_min <= pl.origin.centroid_energy.e_min + 1e-9);
    }
}

#[test]
fn the_optimised_pole_does_not_lengthen_the_path_by_more_than_3_percent() {
    // Issue 4: the optimised pole beats the centroid pole on E_min (asserted above) without a
    // path more than 3 % longer. Not sliver_mesh: its centroid pole folds 35 faces of the map
    // next to a slit tip and the spiral stops there ("the path jumps"); the search avoids such
    // poles, `--origin centroid` does not (a known limit).
    // The origin's energy is the conformal map's: so is the path compared.
    for name in PLANNED.into_iter().filter(|&n| n != "sliver_mesh") {
        let p = planner(name);
        let options = PlanOptions { verify_samples: 0, optimise: Optimise::None, ..PlanOptions::default() };
        let auto = plan(&p, &options);
        let centroid = plan(&p, &PlanOptions { origin: slitpath::origin::OriginChoice::Centroid, ..options });
        let ratio = auto.path.length_mm / centroid.path.length_mm;
        println!(
            "{name}: E_min {:.1} vs centroid {:.1}, length {:.0} vs {:.0} mm ({:+.2} %)",
            auto.origin.energy.e_min,
            centroid.origin.energy.e_min,
            auto.path.length_mm,
            centroid.path.length_mm,
            100.0 * (ratio - 1.0)
        );
        // 3 %: the ring levels are discrete, and moving the pole moves where a band's worst
        // cusp falls; with the spacing gate's cusp search spherical_cap_hole's path came out
        // 2.18 % longer at an E_min 0.5 % lower (plate_3_holes 3.4 % shorter).
        assert!(ratio <= 1.03, "{name}: the optimised pole's path is {:.2} % longer", 100.0 * (ratio - 1.0));
    }
}

/// Every planned tip, in order, among the interpreter's feed moves within 1e-3 mm (the post
/// drops no move); `what` names the program.
fn assert_tips_reproduced(pl: &Plan, program: &str, what: &str) {
    let run = common::rs274(program, pl.toolpath.tool.number);
    let feeds: Vec<DVec3> = run.motions.iter().filter(|m| !m.rapid).map(|m| m.xyz).collect();
    let planned: Vec<DVec3> = pl.toolpath.moves.iter().filter(|m| !m.kind.is_rapid()).map(|m| m.tip).collect();
    assert!(!planned.is_empty(), "{what}: no feed move");
    let mut k = 0;
    for tip in &planned {
        while k < feeds.len() && (feeds[k] - *tip).length() > 1e-3 {
            k += 1;
        }
        assert!(k < feeds.len(), "{what}: planned tip {tip:?} not reproduced by rs274");
    }
}

#[test]
fn issue_5_every_post_of_every_fixture_is_accepted_by_rs274_and_reproduces_the_tips() {
    // Issue 5: every post's output of the fixtures goes through LinuxCNC's interpreter (CL data
    // is parsed back). The 3-axis posts share one plan, the 5-axis AC post has its own.
    use slitpath::gcode::{gcode, parse_cl, GcodeOptions};
    for name in PLANNED {
        let p = planner(name);
        let three = plan(&p, &PlanOptions { verify_samples: 0, ..PlanOptions::default() });
        assert_tips_reproduced(&three, &three.gcode, &format!("{name}, linuxcnc"));
        let posted = |pl: &Plan, post: Post| gcode(&pl.toolpath, &GcodeOptions { post, ..GcodeOptions::default() });
        assert_tips_reproduced(&three, &posted(&three, Post::Grbl).expect("grbl"), &format!("{name}, grbl"));
        let axes = slitpath::toolpath::Axes::five_default();
        let five = plan(&p, &PlanOptions { post: Post::Ac, axes, verify_samples: 0, ..PlanOptions::default() });
        assert_tips_reproduced(&five, &five.gcode, &format!("{name}, ac"));
        // CL data, 3- and 5-axis: one GOTO per move, its tip and axis.
        for pl in [&three, &five] {
            let cl = parse_cl(&posted(pl, Post::Cl).expect("cl")).expect("CL data parses back");
            assert_eq!(cl.moves.len(), pl.toolpath.moves.len(), "{name}: CL moves");
            for (read, m) in cl.moves.iter().zip(&pl.toolpath.moves) {
                assert!(read.tip.distance(m.tip) < 1e-3, "{name}: CL tip {:?} vs {:?}", read.tip, m.tip);
                assert!(read.axis.distance(m.axis) < 1e-5, "{name}: CL axis {:?} vs {:?}", read.axis, m.axis);
            }
        }
    }
}

#[test]
fn reruns_and_a_second_planner_give_byte_identical_gcode() {
    let options = PlanOptions { verify_samples: 0, ..PlanOptions::default() };
    let a = plan(&planner("freeform_4_holes"), &options).gcode;
    let b = plan(&planner("freeform_4_holes"), &options).gcode;
    assert!(a == b, "G-code differs between runs");
}

/// Natively the stages spread work over threads; the plan must not depend on how many.
#[test]
fn the_plan_is_the_same_on_one_thread_and_on_three() {
    let p = planner("freeform_4_holes");
    let options = PlanOptions { verify_samples: 20_000, ..PlanOptions::default() };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
        let pl = pool.install(|| plan(&p, &options));
        let v = pl.verification().expect("verified");
        (pl.gcode.clone(), v.max_scallop_mm, v.vertex_scallop_mm.clone(), pl.report.origin.e_min)
    };
    let (one, three) = (on(1), on(3));
    assert!(one.0 == three.0, "G-code differs between 1 and 3 threads");
    assert_eq!(one.1.to_bits(), three.1.to_bits());
    assert!(one.2 == three.2, "per-vertex scallops differ");
    assert_eq!(one.3.to_bits(), three.3.to_bits());
}

#[test]
fn a_smaller_scallop_gives_more_rings_and_bad_options_are_refused() {
    let p = planner("plate_3_holes");
    let coarse = plan(&p, &PlanOptions { scallop_mm: 0.08, verify_samples: 0, ..PlanOptions::default() });
    let fine = plan(&p, &PlanOptions { scallop_mm: 0.02, verify_samples: 0, ..PlanOptions::default() });
    assert!(fine.rings.rings.len() > coarse.rings.rings.len());
    for (r, h) in [(0.0, 0.02), (-1.0, 0.02), (3.0, 0.0), (3.0, -0.1), (3.0, 3.0), (f64::NAN, 0.02), (500.0, 0.02)] {
        let e =
            p.plan(&PlanOptions { radius_mm: r, scallop_mm: h, ..PlanOptions::default() }, &mut |_, _, _| {}, &|| 0.0);
        assert!(matches!(e, Err(slitpath::plan::PlanError::InvalidOption(_))), "R {r} h {h}: {:?}", e.err());
    }
}

/// Plans with `options`, prints the verifier's figures and asserts the promise: max scallop
/// ≤ 1.02 h, uncovered ≤ 0.1 %, one continuous pass, and no gouge.
fn assert_scallop_kept(name: &str, p: &Planner, options: &PlanOptions) {
    let pl = plan(p, options);
    let v = pl.verification().expect("verified");
    let h = options.scallop_mm;
    println!(
        "{name}: rings {} (crease compromises {}), max {:.3} h, p99 {:.3} h, uncovered {}, gouges {} (max {:.2e} mm)",
        pl.rings.rings.len(),
        pl.rings.crease_compromises,
        v.max_scallop_mm / h,
        v.p99_scallop_mm / h,
        v.uncovered_samples,
        v.gouges,
        v.max_gouge_mm
    );
    assert!(v.max_scallop_mm <= 1.02 * h, "{name}: max scallop {} h", v.max_scallop_mm / h);
    assert!(v.uncovered_fraction <= 1e-3, "{name}: uncovered {}", v.uncovered_fraction);
    assert_eq!(v.gouges, 0, "{name}: {} gouges, deepest {} mm", v.gouges, v.max_gouge_mm);
    assert_eq!(pl.toolpath.stats.retractions, 1, "{name}");
}

#[test]
fn issue_4_fixtures_without_holes_keep_the_scallop_at_their_scale() {
    // The analytic disks are 2 mm across: a 0.05 mm ball and h = 0.5 µm. The spiral's chords
    // sagged 2 µm inside the rings (a fixed chord tolerance) and left 1.48 h at the unit disk's rim.
    let options = PlanOptions { radius_mm: 0.05, scallop_mm: 5e-4, verify_samples: 40_000, ..PlanOptions::default() };
    for name in ["unit_disk", "concentric_annulus", "eccentric_annulus"] {
        assert_scallop_kept(name, &planner(name), &options);
    }
}

#[test]
fn issue_4_shared_meshes_keep_the_scallop_on_their_creases() {
    // Faceted meshes at their own scale (the plan bench's options: R = diagonal / 60, h = R / 150,
    // 5-axis). Their largest scallops sat on creases between facets (10–14° on wavy_mesh_with_hole),
    // between meridians: 1.45 h and 1.32 h before the spacing tested the creases' crossings.
    // They tessellate smooth shapes coarsely: a ball kept off facets turning 10–14° at this
    // scale left 1.95 h (wavy) and 8.7 h (face) at the creases, so they are planned as smooth
    // surfaces. Smooth, the ball dipped into face_holes' coarse facets by up to 11.6 µm = 16 h
    // (248 samples deeper than the facets' own deviation from their normals, which the verifier
    // tolerates); it is now kept from dipping deeper (0.93 h, no gouge).
    for name in ["wavy_mesh_with_hole.stl", "face_holes.stl"] {
        let Some((p, diagonal)) = shared_planner(name) else { continue };
        assert_scallop_kept(name, &p, &bench_options(diagonal, Facets::Smooth));
    }
}

#[test]
fn issue_4_the_gate_closes_the_gaps_between_meridians() {
    // The bench's options (R = diagonal / 60 up to 3 mm, h = R / 150 up to 0.02 mm, smooth).
    // Between the meridians the spacing tested, plate_holes kept 1.30 h (where the P1 image of
    // its plate overlaps itself below a slit, and at the kinks of rings crossing its long
    // facets) and beetle 1.29 h; the spacing's gate now tests the bands' points between them.
    // (beetle kept that only by dipping 37 h into the floors of its 70° creases: it is no smooth
    // surface, see below.)
    for (name, axes) in [("plate_holes.stl", 3), ("intersection_quads.stl", 5)] {
        let Some((p, diagonal)) = shared_planner(name) else { continue };
        let smooth = bench_options(diagonal, Facets::Smooth);
        let options = PlanOptions { axes: if axes == 5 { FIVE_AXIS } else { Default::default() }, ..smooth };
        assert_scallop_kept(name, &p, &options);
    }
}

#[test]
fn issue_4_smooth_facets_do_not_gouge_the_floor_of_a_sharp_crease() {
    // beetle's legs meet its body in concave creases of about 70° at its bench scale. Planned
    // as a smooth surface, the ball along the bisecting vertex normal dipped 37 h into both
    // flanks (52 gouges). It may dip only as deep as the facets deviate from their normals
    // (the verifier's tolerance), so it now stays up to 14 h above the floors, and the verifier
    // says so.
    let Some((p, diagonal)) = shared_planner("beetle.stl") else { return };
    let options = bench_options(diagonal, Facets::Smooth);
    let h = options.scallop_mm;
    let pl = plan(&p, &options);
    let v = pl.verification().expect("verified");
    let c = pl.report.path.clearance;
    println!(
        "beetle smooth: {} centres moved (max {:.2} h), max {:.2} h, p99 {:.3} h, gouges {}",
        c.moved,
        c.max_move_mm / h,
        v.max_scallop_mm / h,
        v.p99_scallop_mm / h,
        v.gouges
    );
    assert!(c.moved > 0 && c.unresolved == 0);
    assert_eq!(v.gouges, 0, "deepest {} h", v.max_gouge_mm / h);
    assert!(v.max_scallop_mm > 5.0 * h, "the creases' floors: {} h", v.max_scallop_mm / h);
    assert!(v.p99_scallop_mm < h);
}

#[test]
fn issue_4_exact_facets_ride_the_flat_of_a_cad_part_flat() {
    // countersunk_plate is triangulated as a CAD export is: long thin facets from a 45° cone's
    // top edge to the plate's corners. The planner's refinement splits them, and its new vertices
    // used to take normals interpolated along the split edges: tilted by up to 22° across the flat
    // top, so the exact-facet clearance lifted 40 548 of 42 091 ball centres off their designed
    // place and left 6.6 h (p99 2.7 h). Exact facets now ride the facets' own normals, split at
    // the 45° edge.
    let out = mesh::from_triangles(&fixtures::countersunk_plate(), &mesh::MeshOptions::default()).expect("mesh");
    let p = Planner::new(out, &|| 0.0).expect("planner");
    // The conformal map's rings, whose crossings of the cone this regression counted.
    let options = PlanOptions { verify_samples: 40_000, optimise: Optimise::None, ..PlanOptions::default() };
    let (r, h) = (options.radius_mm, options.scallop_mm);
    let pl = plan(&p, &options);
    let mut on_flat = 0;
    let flat = |n: DVec3| n.distance(DVec3::Z) < 1e-12;
    for pt in &pl.spiral.points {
        if flat(p.surface.face_normals[pt.face as usize]) {
            assert!(flat(pt.normal), "a contact on the flat at {:?} has the normal {:?}", pt.cc, pt.normal);
            on_flat += 1;
        }
    }
    let c = pl.report.path.clearance;
    let v = pl.verification().expect("verified");
    println!(
        "countersunk_plate: {on_flat} of {} contacts on the flat, {} centres moved (max {:.3} mm), max {:.3} h, p99 {:.3} h",
        pl.spiral.points.len(),
        c.moved,
        c.max_move_mm,
        v.max_scallop_mm / h,
        v.p99_scallop_mm / h
    );
    assert!(on_flat > pl.spiral.points.len() / 2);
    // Only the cone's contacts move (its 24 facets meet at 10.6° concave creases): never more
    // centres than there are contacts off the flat. (A fifth of all contacts was the bound
    // until the spacing gate's cusp search laid more rings over the cone: 6245 of 30 085 moved,
    // all of them among its 7358 contacts off the flat.)
    assert!(
        c.moved <= pl.spiral.points.len() - on_flat,
        "{} moved, {} contacts off the flat",
        c.moved,
        pl.spiral.points.len() - on_flat
    );
    // The flat beyond the ball's reach over the cone is cut to h like any flat.
    let far = |q: DVec3| q.z == 10.0 && q.truncate().length() > 8.0 + r;
    let flat_max = (0..p.surface.positions.len())
        .filter(|&i| far(p.surface.positions[i]))
        .map(|i| v.vertex_scallop_mm[i])
        .fold(0.0, f64::max);
    assert!(flat_max <= 1.02 * h, "flat: {} h", flat_max / h);
    // On the cone the clearance lifts the balls by up to 13 µm = 0.64 h off its creases: the
    // spacing plans for that lift (1.52 h when it did not).
    assert!(v.max_scallop_mm <= 1.02 * h, "{} h, p99 {} h", v.max_scallop_mm / h, v.p99_scallop_mm / h);
    assert_eq!(v.gouges, 0);
}

/// Plans the shared mesh `name` with exact facets at the bench's scale ([`bench_options`]) and
/// prints its facet-valley figures: the verification, h and the valleys' share of the area;
/// `None` when the mesh is absent.
fn exact_valleys_at_bench_scale(name: &str) -> Option<(slitpath::verify::Verification, f64, f64)> {
    let (p, diagonal) = shared_planner(name)?;
    let options = bench_options(diagonal, Facets::Exact);
    let v = plan(&p, &options).verification().expect("verified").clone();
    let h = options.scallop_mm;
    let share = v.valley_area_mm2 / p.surface.area();
    println!(
        "{name}: max {:.3} h; valleys {:.2} % of the area; elsewhere max {:.3} h",
        v.max_scallop_mm / h,
        100.0 * share,
        v.max_scallop_outside_valleys_mm / h
    );
    Some((v, h, share))
}

#[test]
fn issue_4_exact_facets_report_the_facet_valleys_no_ball_reaches() {
    // wavy_mesh_with_hole's facets turn 10–14° at its bench scale (h = R/150). A ball along a
    // vertex normal rides up to about 2 h off the facets beside its creases, and the verifier
    // used to excuse every face where it did (17 % of the area, 0.97 h elsewhere). It now
    // excuses only the samples over which every ball touching the facets leaves more than
    // 0.75 h (the concave creases' floors, 0.3 % of the area): the rest is within reach of
    // some ball, and there the path keeps h but on a few spots beside the valleys, where the
    // facets alone leave 0.5–0.75 h and the spacing does not plan for it (1.31 h here, 1.35 h
    // with R rounded to 6 digits as the bench's CLI run has it; 1.39 and 1.81 h while lifts up
    // to 0.1 h were left to the margin; issue 4).
    let Some((v, h, share)) = exact_valleys_at_bench_scale("wavy_mesh_with_hole.stl") else { return };
    assert!(share > 0.0 && share < 0.01, "valleys: {share}");
    assert!(v.max_scallop_mm > 1.5 * h, "the valleys keep more than h");
    assert!(v.max_scallop_outside_valleys_mm < v.max_scallop_mm);
    // Not yet h: a bound on the spots beside the valleys (see above).
    assert!(v.max_scallop_outside_valleys_mm <= 1.5 * h, "elsewhere {} h", v.max_scallop_outside_valleys_mm / h);
    assert_eq!(v.gouges, 0);
}

#[test]
fn issue_4_the_valleys_of_a_sharp_crease_reach_past_its_faces() {
    // beetle's legs meet its body in concave creases of about 70° at its bench scale (R =
    // diagonal / 60, h = R / 150): the ball resting in one stays up to 30 h above the floor and
    // touches the flanks R·tan 35° from it, several faces away. The verifier excused only the
    // faces where a ball along a corner normal rode up and reported 27 h beside them; the
    // samples no touching ball gets within 0.75 h of are the valleys now.
    let Some((v, h, share)) = exact_valleys_at_bench_scale("beetle.stl") else { return };
    assert!(v.max_scallop_mm > 20.0 * h, "the creases keep {} h", v.max_scallop_mm / h);
    assert!(share > 0.0 && share < 0.03, "valleys: {share}");
    // Beside them the ball riding the interpolated normals still leaves more than h (1.36 h;
    // 1.42 h while lifts up to 0.1 h were left to the margin; issue 4).
    assert!(v.max_scallop_outside_valleys_mm < 1.6 * h, "elsewhere {} h", v.max_scallop_outside_valleys_mm / h);
    assert_eq!(v.gouges, 0);
}

#[test]
fn issue_4_a_rim_point_the_first_ring_leaves_uncut_does_not_stall_the_spacing() {
    // inverted_triangles at its bench scale (the default R = 3 mm, h = 0.02 mm), exact facets:
    // the meridians put the first ring 2 µm inside the rim, and the gate still found a rim point
    // (|w| = 1) uncut with the lifts planned from 0.03 h. It moved the ring onto the rim, so the
    // next band began at |w| = 1 again with a zero step, and the spacing never returned. Points
    // on the ring above's own line are now left to that ring (a gate compromise). Since the
    // spacing lifts the rings' centres rather than lowering the points tested (issue 34), the gate
    // no longer finds that rim point uncut: what is kept is that the spacing ends. Its balls in
    // the facet valleys are now planned lifted by LIFT_CAP·h rather than not at all: 1317 rings
    // (710 before), 1.30 h outside the valleys (1.65 h before).
    let Some((p, _)) = shared_planner("inverted_triangles.stl") else { return };
    // The conformal map's first ring, which found it.
    let options = PlanOptions {
        axes: FIVE_AXIS,
        post: Post::Cl,
        verify_samples: 20_000,
        optimise: Optimise::None,
        ..PlanOptions::default()
    };
    let pl = plan(&p, &options);
    let v = pl.verification().expect("verified");
    let h = options.scallop_mm;
    println!(
        "inverted_triangles: rings {} (gate compromises {}), max {:.3} h, outside the valleys {:.3} h",
        pl.rings.rings.len(),
        pl.rings.gate_compromises,
        v.max_scallop_mm / h,
        v.max_scallop_outside_valleys_mm / h
    );
    assert!(pl.rings.rings.windows(2).all(|w| w[1].radius < w[0].radius));
    assert!(pl.rings.rings.len() < 2000, "{} rings", pl.rings.rings.len());
    assert_eq!(pl.toolpath.stats.retractions, 1);
    assert_eq!(v.gouges, 0);
}

#[test]
fn issue_4_exact_facets_plan_for_the_balls_lift_off_curved_facets() {
    // plate_holes' curved regions are coarse CAD facets whose recomputed normals tilt about 5.5°
    // from the facets at their edges: the clearance lifts the balls there by up to 0.69 h, and
    // the scallop beside them rose to 1.36 h while the spacing planned for balls on the facets.
    let name = "plate_holes.stl";
    let Some((p, _)) = shared_planner(name) else { return };
    assert_scallop_kept(name, &p, &PlanOptions { post: Post::Cl, ..PlanOptions::default() });
}

#[test]
fn issue_4_exact_facets_roll_the_ball_over_a_sharp_ridge() {
    // roof_ridge's facets turn 60° at its ridge. Its averaged normals tilted the balls beside it
    // (1.60 h); split there, the centres jump across it, and the gate measured the band against
    // the chord of that jump, which runs inside the arc the ball really rolls on: 1.37 h at the
    // ridge. The gate's ring polylines now follow the arc.
    let out = mesh::from_triangles(&fixtures::roof_ridge(), &mesh::MeshOptions::default()).expect("mesh");
    let p = Planner::new(out, &|| 0.0).expect("planner");
    assert_scallop_kept("roof_ridge", &p, &PlanOptions { verify_samples: 40_000, ..PlanOptions::default() });
}

#[test]
fn issue_3_auto_plans_plate_holes_from_the_next_pole_when_the_best_one_cannot_carry_a_path() {
    // plate_holes' flat face is remeshed (it has needles); the best pole by E_min then lies next
    // to a hole, where the P1 map's images overlap and the spiral jumps 4 mm. `auto` must still
    // give a path, from the next best pole, and say which pole it gave up and why.
    let Some((p, diagonal)) = shared_planner("plate_holes.stl") else { return };
    let r = diagonal / 60.0;
    let options = PlanOptions { radius_mm: r, scallop_mm: r / 150.0, verify_samples: 20_000, ..PlanOptions::default() };
    let pl = plan(&p, &options);
    let rejected = &pl.report.origin.rejected;
    println!("plate_holes: origin {:?}, rejected {rejected:?}", pl.report.origin.pole_uv);
    assert!(rejected.len() <= slitpath::plan::MAX_FALLBACKS);
    for rj in rejected {
        assert!(rj.reason.starts_with("spiral:") || rj.reason.starts_with("spacing:"), "{}", rj.reason);
        assert!(rj.e_min <= pl.report.origin.e_min, "a rejected pole was worse than the one kept");
    }
    assert_eq!(pl.toolpath.stats.retractions, 1);
    let v = pl.verification().expect("verified");
    assert_eq!(v.gouges, 0);
    assert!(v.uncovered_fraction <= 1e-3, "uncovered {}", v.uncovered_fraction);
}

/// The one-off spacing and spiral entries check that the map is one of the surface before they
/// build its inverse (a map of another mesh indexed out of bounds in the spiral's).
#[test]
fn issue_4_centroid_moves_off_a_hole_whose_map_cannot_carry_a_path() {
    // plate_holes' centroid lies 0.28 mm from the rim of its largest hole: the P1 map has too few
    // faces between them for the rings round the pole, and the spiral would jump 1.2 mm (an
    // error, before). `centroid` now moves the pole straight away from that rim, 5 % of the
    // flattened part's diagonal at a time, and reports the centroid as given up.
    let Some((p, _)) = shared_planner("plate_holes.stl") else { return };
    let options = PlanOptions { origin: OriginChoice::Centroid, verify_samples: 20_000, ..PlanOptions::default() };
    let pl = plan(&p, &options);
    let origin = &pl.report.origin;
    println!(
        "plate_holes, centroid: pole {:?} ({:?} mm), rejected {:?}",
        origin.pole_uv, origin.pole_3d, origin.rejected
    );
    assert_eq!(origin.rejected.len(), 1);
    let centroid = DVec2::from(origin.rejected[0].pole_uv);
    assert_eq!(centroid, slitpath::origin::centroid_pole(&p.domain));
    assert!(origin.rejected[0].reason.contains("would jump"), "{}", origin.rejected[0].reason);
    // One step away: at least the fallback separation from the centroid.
    let (lo, hi) = p.domain.positions.iter().fold((DVec2::MAX, DVec2::MIN), |(a, b), &q| (a.min(q), b.max(q)));
    let moved = DVec2::from(origin.pole_uv).distance(centroid);
    assert!(moved >= 0.999 * slitpath::plan::FALLBACK_SEPARATION * (hi - lo).length(), "moved {moved}");
    assert_eq!(pl.toolpath.stats.retractions, 1);
    let v = pl.verification().expect("verified");
    assert!(v.max_scallop_mm <= 1.02 * options.scallop_mm, "{} h", v.max_scallop_mm / options.scallop_mm);
    assert_eq!(v.gouges, 0);
}

#[test]
fn spacing_and_spiral_refuse_a_map_of_another_mesh() {
    use slitpath::spacing::{self, SpacingError, SpacingOptions};
    use slitpath::spiral::{self, SpiralError, SpiralOptions};
    let planned = plan(&planner("plate_3_holes"), &PlanOptions::default());
    let other = planner("saddle_2_holes").surface;
    let (map_n, surface_n) = (planned.map.w.len(), other.positions.len());
    assert_ne!(map_n, surface_n);
    assert_eq!(
        spacing::spacing(&other, &planned.map, &SpacingOptions::default()),
        Err(SpacingError::MeshMismatch { map: map_n, surface: surface_n })
    );
    assert!(matches!(
        spiral::spiral(&other, &planned.map, &planned.rings, &SpiralOptions::default()),
        Err(SpiralError::MeshMismatch { map, surface }) if map == map_n && surface == surface_n
    ));
}

/// A spacing index built apart from its map's lift (as the planner builds the two side by side)
/// gives the rings `spacing_on` gives, and refuses the lift of another map.
#[test]
fn a_spacing_index_gives_spacing_on_rings_and_refuses_another_maps_lift() {
    use slitpath::mesh::nearest::FaceTree;
    use slitpath::spacing::{self, Lift, SpacingError, SpacingIndex, SpacingOptions};
    let part = planner("plate_3_holes");
    let planned = plan(&part, &PlanOptions::default());
    let tree = FaceTree::new(&part.surface.positions, &part.surface.triangles);
    let options = SpacingOptions::default();
    let lift = Lift::new(&part.surface, &planned.map);
    let index = SpacingIndex::new(&part.surface, &planned.map, &tree, &options).expect("index");
    let rings = index.rings(&lift).expect("rings");
    assert_eq!(Ok(&rings), spacing::spacing_on(&lift, &tree, &options).as_ref());
    assert!(rings.rings.len() > 10);
    let other_map = part.solver.map(slitpath::origin::centroid_pole(&part.domain)).expect("centroid map");
    let other_lift = Lift::new(&part.surface, &other_map);
    let index = SpacingIndex::new(&part.surface, &planned.map, &tree, &options).expect("index");
    assert_eq!(index.rings(&other_lift).map(|r| r.rings.len()), Err(SpacingError::IndexMismatch));
}

/// `spacing_on` takes the part's facet tree from its caller: one of another mesh is refused.
#[test]
fn spacing_refuses_a_facet_tree_of_another_mesh() {
    use slitpath::mesh::nearest::FaceTree;
    use slitpath::spacing::{self, Lift, SpacingError, SpacingOptions};
    let part = planner("plate_3_holes");
    let planned = plan(&part, &PlanOptions::default());
    let other = planner("saddle_2_holes").surface;
    let tree = FaceTree::new(&other.positions, &other.triangles);
    let lift = Lift::new(&part.surface, &planned.map);
    assert_eq!(
        spacing::spacing_on(&lift, &tree, &SpacingOptions::default()),
        Err(SpacingError::FacetTreeMismatch { tree: other.triangles.len(), surface: part.surface.triangles.len() })
    );
}
