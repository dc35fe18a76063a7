use super::*;
use crate::plan::mapped_at_centroid as mapped;
use std::f64::consts::PI;

fn options() -> SpreadOptions {
    SpreadOptions { radius_mm: 1.0, scallop_mm: 0.01, ..SpreadOptions::default() }
}

#[test]
fn a_disk_from_its_centre_is_not_spread() {
    // Every meridian of a flat disk mapped from its centre has the same length: g = 1 − ρ on
    // each, and the warp is the identity (to the rows' and the meridians' resolution).
    let (surface, map) = mapped(&crate::fixtures::unit_disk(24));
    let spread = spread(&Lift::new(&surface, &map), &options()).unwrap();
    for j in 0..64 {
        let theta = TAU * j as f64 / 64.0;
        for k in 0..=20 {
            let rho = k as f64 / 20.0;
            let moved = spread.forward(theta, rho) - rho;
            assert!(moved.abs() < 2e-3, "θ {theta:.3}, ρ {rho}: moved by {moved}");
        }
    }
}

#[test]
fn forward_and_inverse_are_inverse_and_monotone_with_every_loop_on_its_circle() {
    let (surface, map) = mapped(&crate::fixtures::plate_3_holes());
    assert_eq!(map.slits.len(), 3);
    let spread = spread(&Lift::new(&surface, &map), &options()).unwrap();
    let mut rng = crate::fixtures::SplitMix64(32);
    for _ in 0..2000 {
        let (theta, rho) = (TAU * rng.unit(), rng.unit());
        let there = spread.forward(theta, rho);
        let back = spread.inverse(theta, there);
        assert!((back - rho).abs() < 1e-9, "θ {theta}, ρ {rho}: back at {back}");
        assert!(spread.forward(theta, rho + 1e-3) > there || rho + 1e-3 >= 1.0, "not increasing at θ {theta}, ρ {rho}");
    }
    for j in 0..360 {
        let theta = TAU * j as f64 / 360.0;
        assert_eq!(spread.forward(theta, 1.0), 1.0);
        assert!(spread.forward(theta, 0.0).abs() < 1e-12);
    }
    // A slit stays one circle: the same radius on every meridian over it, and the image's hole
    // vertices on it.
    let image = spread.image(&surface, &map);
    for (s, t) in map.slits.iter().zip(&image.slits) {
        for k in 0..=50 {
            let theta = s.theta_start + s.extent() * k as f64 / 50.0;
            let r = spread.forward(theta, s.radius);
            assert!((r - t.radius).abs() < 1e-12, "hole {}: {r} at θ {theta}, pinned {}", s.hole, t.radius);
        }
        for &v in &surface.loops[s.hole] {
            assert!((image.w[v as usize].length() - t.radius).abs() < 1e-12);
        }
    }
    for &v in &surface.loops[0] {
        assert!((image.w[v as usize].length() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn the_spread_lift_finds_the_points_the_map_lifts_and_labels_them_back() {
    // A point lifted at (ρ', θ) is the map's point at (inverse(ρ'), θ), and `image_of` gives
    // back (ρ', θ).
    let (surface, map) = mapped(&crate::fixtures::plate_3_holes());
    let base = Lift::new(&surface, &map);
    let spread = spread(&base, &options()).unwrap();
    let image = spread.image(&surface, &map);
    let lift = Lift::new(&surface, &map).spread(&image, spread.clone());
    assert!(lift.is_spread() && std::ptr::eq(lift.map(), &image) && std::ptr::eq(lift.base_map(), &map));
    let mut rng = crate::fixtures::SplitMix64(7);
    let mut checked = 0;
    for _ in 0..500 {
        let (theta, rho) = (TAU * rng.unit(), 0.05 + 0.9 * rng.unit());
        let (Some(a), Some(b)) = (lift.polar(rho, theta), base.polar(spread.inverse(theta, rho), theta)) else {
            continue;
        };
        assert_eq!((a.p, a.face, a.rho), (b.p, b.face, rho));
        let bary = crate::mesh::nearest::closest_on_triangle(
            a.p,
            surface.positions[surface.triangles[a.face as usize][0] as usize],
            surface.positions[surface.triangles[a.face as usize][1] as usize],
            surface.positions[surface.triangles[a.face as usize][2] as usize],
        );
        let (r, t) = lift.image_of(a.face as usize, bary);
        if lift.in_pole_star(a.face as usize) {
            continue;
        }
        assert!(
            (r - rho).abs() < 1e-7 && (crate::num::rem_tau(t - theta + PI) - PI).abs() < 1e-7,
            "({rho}, {theta}) came back as ({r}, {t})"
        );
        checked += 1;
    }
    assert!(checked > 400, "{checked} points checked");
}

#[test]
fn bad_options_are_named() {
    let (surface, map) = mapped(&crate::fixtures::unit_disk(4));
    let lift = Lift::new(&surface, &map);
    for bad in [
        SpreadOptions { scallop_mm: 0.0, ..options() },
        SpreadOptions { radius_mm: f64::NAN, ..options() },
        SpreadOptions { rows: 1, ..options() },
        SpreadOptions { pin_fade_rad: -1.0, ..options() },
    ] {
        assert!(matches!(spread(&lift, &bad), Err(SpreadError::InvalidOption(_))), "{bad:?}");
    }
}

#[test]
fn the_buckets_find_what_the_binary_search_finds() {
    let mut rng = crate::fixtures::SplitMix64(7);
    // Clustered values (as the meridians are round a rectangle's corners), with repeats.
    let mut values: Vec<f64> = (0..500).map(|_| TAU * rng.unit().powi(3)).collect();
    values.extend([0.0, 1.0, 1.0, TAU - 1e-12]);
    values.sort_by(f64::total_cmp);
    let buckets = Buckets::new(&values, 0.0, TAU, 64);
    let mut queries: Vec<f64> = (0..20_000).map(|_| 7.0 * rng.unit() - 0.3).collect();
    // On the values, on the buckets' starts, outside the range, NaN.
    queries.extend(values.iter().copied());
    queries.extend((0..=64).map(|b| b as f64 * TAU / 64.0));
    queries.extend([-1.0, TAU, 10.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY]);
    for t in queries {
        assert_eq!(buckets.partition_point(&values, t), values.partition_point(|&x| x <= t), "t = {t}");
    }
}
