//! Origin stage: the closed form of E_min against a brute-force minimisation over the slopes,
//! the search against symmetry and a brute-force grid of poles, gouge-risk reporting, the pole
//! choices, bad options, and the shared meshes (skipped when ../shared is absent).
#![cfg(not(target_arch = "wasm32"))]

use glam::{DVec2, DVec3};
use slitpath::fixtures;
use slitpath::flatten::{self, FlattenInput, FlattenOptions};
use slitpath::mesh::{self, MeshOptions, Surface, TriMesh};
use slitpath::origin::{centroid_pole, find_origin, EnergyEvaluator, Origin, OriginChoice, OriginError, OriginOptions};
use slitpath::slitmap::{Mode, PlanarDomain, SlitMapError, SlitMapOptions, SlitMapSolver};
use std::path::PathBuf;

struct Part {
    surface: Surface,
    domain: PlanarDomain,
    solver: SlitMapSolver,
}

fn part(mesh: &TriMesh) -> Part {
    let surface = mesh::from_triangles(mesh, &MeshOptions::default()).unwrap().surface;
    part_of(surface)
}

fn part_of(surface: Surface) -> Part {
    let flat = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default()).unwrap();
    let domain = PlanarDomain::of_surface(&surface, flat.uv);
    let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
    Part { surface, domain, solver }
}

fn origin(p: &Part, options: &OriginOptions) -> Result<Origin, OriginError> {
    find_origin(&p.surface, &p.domain, &p.solver, options)
}

fn bbox_diagonal(s: &Surface) -> f64 {
    let lo = s.positions.iter().copied().fold(DVec3::INFINITY, DVec3::min);
    let hi = s.positions.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
    (hi - lo).length()
}

/// Golden-section search of a unimodal function on [a, b].
fn golden(mut a: f64, mut b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..120 {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - g * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

#[test]
fn closed_form_equals_a_brute_force_minimisation_over_the_slopes() {
    let p = part(&fixtures::freeform_4_holes());
    let options = OriginOptions { bins: 12, ..Default::default() };
    let ev = EnergyEvaluator::new(&p.surface, &p.solver, &options).unwrap();
    for pole in [centroid_pole(&p.domain), p.solver.canonical_hole_pole(3)] {
        let map = p.solver.map(pole).unwrap();
        let closed = ev.evaluate_map(&map).unwrap();
        // E^S is a sum of one function per bin: golden-section each slope in turn (log scale),
        // the others held at the arbitrary start value 1.
        let mut slopes = vec![1.0; options.bins];
        for j in 0..options.bins {
            if closed.slopes[j] == 0.0 {
                continue; // no face reaches this bin
            }
            let best = golden(-12.0, 12.0, |x| {
                let mut s = slopes.clone();
                s[j] = x.exp();
                ev.energy_for_slopes(&map, &s).unwrap()
            });
            slopes[j] = best.exp();
        }
        let brute = ev.energy_for_slopes(&map, &slopes).unwrap();
        assert!(
            (brute - closed.e_min).abs() <= 1e-9 * closed.e_min,
            "{:?}: brute {brute} closed {}",
            map.mode,
            closed.e_min
        );
        assert!(brute >= closed.e_min * (1.0 - 1e-12), "the closed form is the minimum");
        for (j, (&s, &c)) in slopes.iter().zip(&closed.slopes).enumerate() {
            if c > 0.0 {
                assert!((s - c).abs() <= 1e-4 * c, "bin {j}: brute slope {s}, closed {c}");
            }
        }
        // The closed-form slopes do better than any perturbation of them.
        let mut s = closed.slopes.clone();
        s.iter_mut().for_each(|x| *x = if *x > 0.0 { *x * 1.05 } else { 1.0 });
        assert!(ev.energy_for_slopes(&map, &s).unwrap() > closed.e_min);
        assert!(closed.uniformity >= 1.0 - 1e-12);
    }
}

#[test]
fn optimum_of_a_centrally_symmetric_part_is_its_centre() {
    let p = part(&fixtures::symmetric_4_holes());
    let o = origin(&p, &OriginOptions::default()).unwrap();
    let centre = DVec3::new(0.0, 0.0, 8.0);
    let size = bbox_diagonal(&p.surface);
    let off = o.pole_3d.distance(centre);
    eprintln!(
        "symmetric: pole_3d {:.3} ({off:.3} mm from the centre, {:.2}% of {size:.1} mm), E_min {:.3} (centroid {:.3}), \
         uniformity {:.4}, {} evaluations, mode {:?}",
        o.pole_3d,
        100.0 * off / size,
        o.energy.e_min,
        o.centroid_energy.e_min,
        o.energy.uniformity,
        o.evaluations,
        o.mode
    );
    assert_eq!(o.mode, Mode::Disk);
    assert!(off <= 0.02 * size, "{off} mm from the centre");
}

#[test]
fn search_agrees_with_a_brute_force_grid_of_poles() {
    for (name, mesh) in [("plate", fixtures::plate_3_holes()), ("saddle", fixtures::saddle_2_holes())] {
        grid_check(name, &part(&mesh));
    }
}

fn grid_check(name: &str, p: &Part) {
    let options = OriginOptions::default();
    let ev = EnergyEvaluator::new(&p.surface, &p.solver, &options).unwrap();
    // Every face centre of the flattened plate, plus each hole's annulus.
    let mut poles: Vec<DVec2> = p
        .domain
        .triangles
        .iter()
        .map(|t| t.iter().map(|&v| p.domain.positions[v as usize]).sum::<DVec2>() / 3.0)
        .collect();
    poles.extend((1..p.domain.loops.len()).map(|h| p.solver.canonical_hole_pole(h)));
    let mut grid_best = (f64::INFINITY, DVec2::ZERO);
    for &q in &poles {
        if let Ok(e) = ev.evaluate(q) {
            if e.e_min < grid_best.0 {
                grid_best = (e.e_min, q);
            }
        }
    }
    let o = origin(p, &options).unwrap();
    eprintln!(
        "{name}: search E_min {:.4} at {:.3} in {} evaluations; grid best {:.4} at {:.3} over {} poles",
        o.energy.e_min,
        o.pole,
        o.evaluations,
        grid_best.0,
        grid_best.1,
        poles.len()
    );
    assert!(o.energy.e_min <= 1.01 * grid_best.0, "{name}: search {} grid {}", o.energy.e_min, grid_best.0);
}

#[test]
fn optimum_beats_the_centroid_on_every_holed_fixture() {
    for name in fixtures::NAMES {
        let p = part(&fixtures::by_name(name).unwrap());
        if p.surface.loops.len() < 2 {
            continue;
        }
        let o = origin(&p, &OriginOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        eprintln!(
            "{name}: E_min {:.4} (centroid {:.4}), uniformity {:.4} (centroid {:.4}), {:?}, {} evaluations",
            o.energy.e_min,
            o.centroid_energy.e_min,
            o.energy.uniformity,
            o.centroid_energy.uniformity,
            o.mode,
            o.evaluations
        );
        assert!(o.energy.e_min <= o.centroid_energy.e_min, "{name}");
        assert!(o.energy.uniformity >= 1.0 - 1e-12 && o.centroid_energy.uniformity >= 1.0 - 1e-12, "{name}");
        assert!(o.evaluations <= OriginOptions::default().max_evaluations, "{name}");
        assert_eq!(o.trace[0], (o.centroid_pole, o.centroid_energy.e_min), "{name}");
        assert!(o.trace.iter().any(|&(q, e)| q == o.pole && e == o.energy.e_min), "{name}");
        assert!(o.trace.iter().all(|&(_, e)| e >= o.energy.e_min), "{name}: the best of the trace is chosen");
        assert!(o.energy.e_min.is_finite() && o.energy.gouge_faces == 0, "{name}");
    }
}

#[test]
fn a_ball_larger_than_the_concave_radius_reports_gouge_risk() {
    // Saddle z = (x² − y²)/250: normal curvatures down to −1/125 mm⁻¹; a 500 mm ball does not fit.
    let p = part(&fixtures::saddle_2_holes());
    let options = OriginOptions { radius_mm: 500.0, choice: OriginChoice::Centroid, ..Default::default() };
    let o = origin(&p, &options).unwrap();
    let area = p.surface.area();
    eprintln!(
        "saddle, R 500: gouge risk {:.1} of {area:.1} mm² ({} faces)",
        o.energy.gouge_risk_area_mm2, o.energy.gouge_faces
    );
    assert!(o.energy.gouge_faces > 0 && o.energy.gouge_risk_area_mm2 > 0.0);
    assert!(o.energy.gouge_risk_area_mm2 < area);
    assert!(o.energy.uniformity >= 1.0 - 1e-12);
    // A 3 mm ball fits everywhere.
    let o = origin(&p, &OriginOptions { choice: OriginChoice::Centroid, ..Default::default() }).unwrap();
    assert_eq!((o.energy.gouge_faces, o.energy.gouge_risk_area_mm2), (0, 0.0));

    // A bowl (the spherical cap upside down, concave radius 60 mm) with a 1 m ball: every face
    // is a gouge risk (even where the curvature estimate at the rim is off), a typed error.
    let mut bowl = fixtures::spherical_cap_hole();
    bowl.positions.iter_mut().for_each(|q| q.z = -q.z);
    let p = part(&bowl);
    let options = OriginOptions { radius_mm: 1000.0, ..Default::default() };
    match origin(&p, &options) {
        Err(OriginError::AllGougeRisk { radius_mm, .. }) => assert_eq!(radius_mm, 1000.0),
        other => panic!("expected AllGougeRisk, got {other:?}"),
    }
    assert!(origin(&p, &OriginOptions { radius_mm: 30.0, ..Default::default() }).is_ok());
}

#[test]
fn bad_options_are_typed_errors() {
    let p = part(&fixtures::plate_3_holes());
    let bad = [
        OriginOptions { radius_mm: 0.0, ..Default::default() },
        OriginOptions { radius_mm: -3.0, ..Default::default() },
        OriginOptions { radius_mm: f64::NAN, ..Default::default() },
        OriginOptions { radius_mm: f64::INFINITY, ..Default::default() },
        OriginOptions { bins: 0, ..Default::default() },
        OriginOptions { starts: 0, ..Default::default() },
        OriginOptions { max_evaluations: 0, ..Default::default() },
        OriginOptions { tolerance_rel: 0.0, ..Default::default() },
        OriginOptions { choice: OriginChoice::Hole(0), ..Default::default() },
        OriginOptions { choice: OriginChoice::Hole(4), ..Default::default() },
        OriginOptions { choice: OriginChoice::Plane(DVec2::NAN), ..Default::default() },
        OriginOptions { choice: OriginChoice::Point3d(DVec3::new(0.0, f64::INFINITY, 0.0)), ..Default::default() },
    ];
    for o in &bad {
        match origin(&p, o) {
            Err(OriginError::InvalidOption(msg)) => eprintln!("{msg}"),
            other => panic!("{o:?}: expected InvalidOption, got {other:?}"),
        }
    }
    assert!(matches!(
        EnergyEvaluator::new(&p.surface, &p.solver, &OriginOptions { bins: 0, ..Default::default() }),
        Err(OriginError::InvalidOption(_))
    ));
    // A pole outside the plate, and one on its edge.
    let outside = OriginOptions { choice: OriginChoice::Plane(DVec2::new(1e4, 0.0)), ..Default::default() };
    assert!(matches!(origin(&p, &outside), Err(OriginError::SlitMap(SlitMapError::PoleOutside { .. }))));
    let edge = p.domain.positions[p.domain.loops[0][0] as usize];
    let on_edge = OriginOptions { choice: OriginChoice::Plane(edge), ..Default::default() };
    assert!(matches!(origin(&p, &on_edge), Err(OriginError::SlitMap(SlitMapError::PoleOnBoundary { .. }))));
}

#[test]
fn explicit_choices_and_budget() {
    let p = part(&fixtures::freeform_4_holes());
    let base = OriginOptions::default();
    let c = origin(&p, &OriginOptions { choice: OriginChoice::Centroid, ..base.clone() }).unwrap();
    assert_eq!((c.pole, c.evaluations, c.mode), (centroid_pole(&p.domain), 1, Mode::Disk));
    assert_eq!(c.energy, c.centroid_energy);

    for n in 1..=4 {
        let h = origin(&p, &OriginOptions { choice: OriginChoice::Hole(n), ..base.clone() }).unwrap();
        assert!(matches!(h.mode, Mode::Annulus { hole, .. } if hole == n));
        // The rim centroid of a hole of the height field lies above the hole's centre.
        let rim = &p.surface.loops[n];
        let avg = rim.iter().map(|&v| p.surface.positions[v as usize]).sum::<DVec3>() / rim.len() as f64;
        assert!(h.pole_3d.truncate().distance(avg.truncate()) < 0.5, "hole {n}");
    }

    // A 3D point just above a face centre lands on that centre.
    let f = 1234;
    let t = p.surface.triangles[f];
    let centre = t.iter().map(|&v| p.surface.positions[v as usize]).sum::<DVec3>() / 3.0;
    let target = centre + p.surface.face_normals[f] * 0.05;
    let o = origin(&p, &OriginOptions { choice: OriginChoice::Point3d(target), ..base.clone() }).unwrap();
    assert!(o.pole_3d.distance(centre) < 1e-9, "{} vs {centre}", o.pole_3d);
    // The same pole given in the plane gives the same energy.
    let q = origin(&p, &OriginOptions { choice: OriginChoice::Plane(o.pole), ..base.clone() }).unwrap();
    assert_eq!(q.energy, o.energy);

    // The budget is respected and the search is deterministic.
    let small = OriginOptions { max_evaluations: 12, ..base.clone() };
    let a = origin(&p, &small).unwrap();
    assert!(a.evaluations <= 12 && a.trace.len() <= 12, "{}", a.evaluations);
    assert!(a.energy.e_min <= a.centroid_energy.e_min);
    let full = origin(&p, &base).unwrap();
    assert_eq!(full, origin(&p, &base).unwrap(), "reruns are identical");
}

#[test]
fn shared_meshes_search_finishes_below_the_centroid() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes");
    for name in ["wavy_mesh_with_hole.stl", "face_holes.stl"] {
        let Ok(bytes) = std::fs::read(dir.join(name)) else {
            eprintln!("skipped: {name} is absent");
            continue;
        };
        let p = part_of(mesh::load(&bytes, &MeshOptions::default()).unwrap().surface);
        let o = origin(&p, &OriginOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        eprintln!(
            "{name}: {} faces, E_min {:.4} (centroid {:.4}), uniformity {:.4}, {:?}, gouge risk {:.2} mm², {} evaluations",
            p.surface.triangles.len(),
            o.energy.e_min,
            o.centroid_energy.e_min,
            o.energy.uniformity,
            o.mode,
            o.energy.gouge_risk_area_mm2,
            o.evaluations
        );
        assert!(o.energy.e_min.is_finite() && o.energy.e_min <= o.centroid_energy.e_min, "{name}");
        assert!(o.energy.uniformity >= 1.0 - 1e-12, "{name}");
    }
}

#[test]
fn the_alternatives_are_the_next_best_poles_the_search_saw_and_far_apart() {
    // Issue 3 (plate_holes): `auto` plans from these when the best pole's path cannot be built.
    let p = part(&fixtures::freeform_4_holes());
    let o = origin(&p, &OriginOptions::default()).unwrap();
    let (lo, hi) = p.domain.positions.iter().fold((DVec2::MAX, DVec2::MIN), |(a, b), &q| (a.min(q), b.max(q)));
    let sep = 0.05 * (hi - lo).length();
    let alt = o.alternatives(sep, 3);
    assert!(!alt.is_empty(), "a search of {} evaluations saw other poles", o.evaluations);
    let e = |q: DVec2| o.trace.iter().find(|t| t.0 == q).expect("a pole of the trace").1;
    let mut poles = vec![o.pole];
    for (i, &q) in alt.iter().enumerate() {
        assert!(e(q) >= o.energy.e_min, "alternative {i} beats the chosen pole");
        assert!(i == 0 || e(q) >= e(alt[i - 1]), "not in order of E_min");
        assert!(poles.iter().all(|&r| r.distance(q) >= sep), "alternative {i} is within {sep} of another pole");
        poles.push(q);
    }
    // Every pole of the trace that is left out is either worse than the last alternative or too
    // close to a kept one.
    let last = e(*alt.last().unwrap());
    for &(q, eq) in &o.trace {
        if !poles.contains(&q) && eq < last {
            assert!(poles.iter().any(|&r| r.distance(q) < sep), "pole {q} (E {eq}) was skipped");
        }
    }
}
