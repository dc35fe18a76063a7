//! Analytic test surfaces (one deterministic generator for every test, benchmark and sample).
//!
//! Every stage's tests, the benchmarks and the bundled sample part take their meshes from here, so
//! that all of them agree on the same shapes: oracle domains with closed-form conformal maps (unit
//! disk, concentric and eccentric annuli), part-like surfaces with holes (plate, saddle, spherical
//! cap, freeform mould panel), CAD-style parts with sharp edges (a plate with a countersunk hole,
//! a roof with a ridge), a deliberately bad mesh (slivers), a closed solid whose top surface has a
//! boss and a pocket, and fine sphere/cylinder meshes for curvature checks.
//!
//! Conventions: millimetres (the oracle shapes keep their natural unit size), indexed vertices
//! (no duplicated positions), manifold, triangles counter-clockwise seen from +Z for the open
//! surfaces (normals up) and outward for closed ones. Output is bit-for-bit deterministic: no
//! `rand`, no hash-map order; the little jitter used to break lattice ties comes from a seeded
//! SplitMix64.
//!
//! The holed planar domains come from one small internal mesher (`planar_domain_with_holes`): a
//! triangular lattice clipped away from the boundary, boundary vertices placed exactly on the
//! analytic curves, a Bowyer–Watson Delaunay triangulation of the lot, light smoothing. The curved
//! fixtures are height fields over such domains, so their projection keeps the planar mesh quality.

use crate::mesh::TriMesh;
use crate::num;
use glam::{DVec2, DVec3};
use std::collections::BTreeMap;
use std::f64::consts::TAU;

/// The nine named part fixtures, in a fixed order (see [`by_name`]).
pub const NAMES: &[&str] = &[
    "unit_disk",
    "concentric_annulus",
    "eccentric_annulus",
    "plate_3_holes",
    "saddle_2_holes",
    "spherical_cap_hole",
    "freeform_4_holes",
    "sliver_mesh",
    "box_boss_pocket",
];

/// The fixture called `name` (one of [`NAMES`]) at its default resolution, or `None`.
///
/// Defaults: `unit_disk(24)`, `concentric_annulus(0.4, 16)`,
/// `eccentric_annulus((0.3, 0.1), 0.35, 24)`; the part fixtures take no parameter. Every default
/// mesh has at most 20 000 faces.
pub fn by_name(name: &str) -> Option<TriMesh> {
    Some(match name {
        "unit_disk" => unit_disk(24),
        "concentric_annulus" => concentric_annulus(0.4, 16),
        "eccentric_annulus" => eccentric_annulus(DVec2::new(0.3, 0.1), 0.35, 24),
        "plate_3_holes" => plate_3_holes(),
        "saddle_2_holes" => saddle_2_holes(),
        "spherical_cap_hole" => spherical_cap_hole(),
        "freeform_4_holes" => freeform_4_holes(),
        "sliver_mesh" => sliver_mesh(),
        "box_boss_pocket" => box_boss_pocket(),
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------------------
// Oracle domains
// ---------------------------------------------------------------------------------------------

/// Flat unit disk (radius 1, centre at the origin, z = 0) made of concentric rings.
///
/// Ring k (k = 1..=`rings`) has radius k/`rings` and 6k vertices, the centre is one vertex: the
/// classic hexagonal disk, nearly equilateral triangles, edge length ≈ 1/`rings`, 6·rings² faces.
/// Doubling `rings` halves the edge length with the same triangle shapes (P1 convergence
/// studies). Boundary vertices lie exactly on the unit circle.
/// Topology: 1 boundary loop, Euler characteristic 1.
pub fn unit_disk(rings: usize) -> TriMesh {
    assert!(rings >= 1, "unit_disk needs at least one ring");
    let mut positions = vec![DVec3::ZERO];
    let mut triangles = Vec::new();
    let mut prev: Vec<u32> = vec![0];
    let mut prev_frac: Vec<f64> = vec![0.0];
    for k in 1..=rings {
        let n = 6 * k;
        // k / rings is exactly 1.0 on the last ring, so the boundary is on the unit circle.
        let r = k as f64 / rings as f64;
        let (ring, frac) = push_ring(&mut positions, n, 0.0, |t| DVec3::new(r * num::cos(t), r * num::sin(t), 0.0));
        zip_rings(&prev, &prev_frac, &ring, &frac, &mut triangles);
        prev = ring;
        prev_frac = frac;
    }
    TriMesh { positions, triangles }
}

/// Flat concentric annulus `inner_radius` < |p| < 1 in z = 0, centred at the origin.
///
/// `rings` radial layers of width (1 − inner_radius)/`rings`; each circle has a vertex count
/// proportional to its radius (tangential spacing ≈ radial spacing), so triangles stay close to
/// equilateral and doubling `rings` halves the edge length (as long as the inner circle is not
/// much smaller than the layer width). Boundary vertices lie exactly on both circles.
/// Requires 0 < inner_radius < 1.
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn concentric_annulus(inner_radius: f64, rings: usize) -> TriMesh {
    assert!(
        inner_radius > 0.0 && inner_radius < 1.0 && rings >= 1,
        "concentric_annulus needs 0 < inner_radius < 1 and rings >= 1"
    );
    let dr = (1.0 - inner_radius) / rings as f64;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut prev: Option<(Vec<u32>, Vec<f64>)> = None;
    for k in 0..=rings {
        let r = if k == rings { 1.0 } else { inner_radius + k as f64 * dr };
        let n = ((TAU * r / dr).round() as usize).max(6);
        let (ring, frac) = push_ring(&mut positions, n, 0.0, |t| DVec3::new(r * num::cos(t), r * num::sin(t), 0.0));
        if let Some((p, pf)) = &prev {
            zip_rings(p, pf, &ring, &frac, &mut triangles);
        }
        prev = Some((ring, frac));
    }
    TriMesh { positions, triangles }
}

/// Flat eccentric annulus in z = 0: the unit disk minus the open disk |p − `center`| < `radius`.
///
/// Quasi-uniform Delaunay mesh with edge length ≈ 1/`rings` (lattice interior, boundary vertices
/// exactly on both circles); doubling `rings` halves the edge length. Requires
/// |center| + radius < 1 (with a gap of at least about one edge length).
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn eccentric_annulus(center: DVec2, radius: f64, rings: usize) -> TriMesh {
    assert!(
        radius > 0.0 && center.length() + radius < 1.0 && rings >= 1,
        "eccentric_annulus needs |center| + radius < 1"
    );
    let outer = Curve::Circle { c: DVec2::ZERO, r: 1.0 };
    let holes = [Curve::Circle { c: center, r: radius }];
    let (p, t) = planar_domain_with_holes(&outer, &holes, 1.0 / rings as f64, 0xECC0);
    lift(&p, t, |_| 0.0)
}

// ---------------------------------------------------------------------------------------------
// Part-like fixtures
// ---------------------------------------------------------------------------------------------

const PLATE_HOLES: [(f64, f64, f64); 3] = [(-25.0, 10.0, 12.0), (20.0, 15.0, 8.0), (10.0, -20.0, 5.0)];

/// Flat 20 × 2 strip (x ∈ [0, 20], y ∈ [0, 2], z = 0) with one hole of radius 0.4 at its
/// centre: seen from a pole at one end, the other end is crowded against |w| = 1 by about
/// e^(−10π) (issue 3's far-field test; not a part fixture, so not in [`by_name`]).
///
/// Delaunay mesh, edge length ≈ 0.5, about 400 faces.
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn long_strip_hole() -> TriMesh {
    let (p, t) = planar_domain_with_holes(&rect(0.0, 0.0, 20.0, 2.0), &circles(&[(10.0, 1.0, 0.4)]), 0.5, 7);
    lift(&p, t, |_| 0.0)
}

/// Flat 100 × 80 mm plate (x ∈ [−50, 50], y ∈ [−40, 40], z = 0) with three circular holes of
/// radii 12, 8 and 5 mm (boundary vertices exactly on the circles).
///
/// Delaunay mesh, edge length ≈ 2 mm, minimum angle above 20°, about 4 200 faces.
/// Topology: 4 boundary loops, Euler characteristic −2.
pub fn plate_3_holes() -> TriMesh {
    let (p, t) = planar_domain_with_holes(&rect(-50.0, -40.0, 50.0, 40.0), &circles(&PLATE_HOLES), 2.0, 0x91A7E);
    lift(&p, t, |_| 0.0)
}

const SADDLE_HOLES: [(f64, f64, f64); 2] = [(-18.0, -15.0, 9.0), (17.0, 14.0, 6.0)];
const SADDLE_C: f64 = 125.0;

/// Saddle z = (x² − y²)/(2·125) over the 80 × 80 mm square x, y ∈ [−40, 40] (height range
/// 12.8 mm) with two holes whose projections are circles of radii 9 and 6 mm.
///
/// Height field over a Delaunay mesh, edge length ≈ 1.5 mm, about 6 300 faces, normals up.
/// Topology: 3 boundary loops, Euler characteristic −1.
pub fn saddle_2_holes() -> TriMesh {
    let (p, t) = planar_domain_with_holes(&rect(-40.0, -40.0, 40.0, 40.0), &circles(&SADDLE_HOLES), 1.5, 0x5ADD1E);
    lift(&p, t, |q| (q.x * q.x - q.y * q.y) / (2.0 * SADDLE_C))
}

const CAP_SPHERE_R: f64 = 60.0;
const CAP_BASE_R: f64 = 40.0;
const CAP_HOLE: [(f64, f64, f64); 1] = [(12.0, 8.0, 7.0)];

/// Convex spherical cap: sphere radius 60 mm, base circle radius 40 mm in z = 0 (centre of the
/// sphere on the −Z axis, cap height 15.28 mm), normals up, with one off-centre hole whose
/// projection is a circle of radius 7 mm centred at (12, 8).
///
/// Height field over a Delaunay mesh of the base disk, edge length ≈ 1.2 mm in projection, about
/// 7 800 faces. Topology: 2 boundary loops, Euler characteristic 0.
pub fn spherical_cap_hole() -> TriMesh {
    let outer = Curve::Circle { c: DVec2::ZERO, r: CAP_BASE_R };
    let (p, t) = planar_domain_with_holes(&outer, &circles(&CAP_HOLE), 1.2, 0xCA9);
    let z0 = (CAP_SPHERE_R * CAP_SPHERE_R - CAP_BASE_R * CAP_BASE_R).sqrt();
    lift(&p, t, |q| (CAP_SPHERE_R * CAP_SPHERE_R - q.length_squared()).max(0.0).sqrt() - z0)
}

/// The freeform panel's holes: two circles and two rotated ellipses.
fn freeform_holes() -> [Curve; 4] {
    [
        Curve::Circle { c: DVec2::new(-38.0, -22.0), r: 9.0 },
        Curve::Circle { c: DVec2::new(-5.0, 25.0), r: 5.0 },
        Curve::Ellipse { c: DVec2::new(14.0, -18.0), a: 14.0, b: 6.0, rot: 25f64.to_radians() },
        Curve::Ellipse { c: DVec2::new(40.0, 20.0), a: 9.0, b: 6.0, rot: (-40f64).to_radians() },
    ]
}

/// Height of the freeform panel: two Gaussian bumps, a dip and a gentle wave.
fn freeform_height(q: DVec2) -> f64 {
    let g = |c: DVec2, s: f64| num::exp(-(q - c).length_squared() / (2.0 * s * s));
    9.5 * g(DVec2::new(-25.0, 8.0), 18.0) - 7.0 * g(DVec2::new(28.0, -12.0), 14.0)
        + 4.0 * g(DVec2::new(30.0, 28.0), 10.0)
        + 1.5 * num::sin(TAU * q.x / 70.0) * num::cos(TAU * q.y / 90.0)
}

/// The bundled sample part: a bumpy freeform mould panel, 120 × 90 mm (x ∈ [−60, 60],
/// y ∈ [−45, 45]), height range about 15 mm (two Gaussian bumps, one dip, a gentle wave; slopes
/// well under 45°), with four holes of different sizes and shapes: circles of radii 9 and 5 mm and
/// ellipses 28 × 12 mm and 18 × 12 mm (rotated), as projections onto z = 0.
///
/// Height field over a Delaunay mesh, edge length ≈ 1.5 mm, about 10 000 faces, normals up.
/// Topology: 5 boundary loops, Euler characteristic −3.
pub fn freeform_4_holes() -> TriMesh {
    let (p, t) = planar_domain_with_holes(&rect(-60.0, -45.0, 60.0, 45.0), &freeform_holes(), 1.5, 0xF4EE);
    lift(&p, t, freeform_height)
}

/// The benchmark panel of issue 5: the sample part's surface and holes plus two circles (radii
/// 6 and 5 mm at (−35, 22) and (42, −25)), six holes in all, meshed with edge length `edge_mm`
/// (0.75 mm gives about 40 000 faces; the face count scales with 1/edge²).
/// Topology: 7 boundary loops, Euler characteristic −5.
pub fn panel_6_holes(edge_mm: f64) -> TriMesh {
    let [a, b, c, d] = freeform_holes();
    let holes = [
        a,
        b,
        c,
        d,
        Curve::Circle { c: DVec2::new(-35.0, 22.0), r: 6.0 },
        Curve::Circle { c: DVec2::new(42.0, -25.0), r: 5.0 },
    ];
    let (p, t) = planar_domain_with_holes(&rect(-60.0, -45.0, 60.0, 45.0), &holes, edge_mm, 0x6E01);
    lift(&p, t, freeform_height)
}

const SYMMETRIC_HOLES: [(f64, f64, f64); 4] =
    [(20.0, 20.0, 6.0), (-20.0, 20.0, 6.0), (-20.0, -20.0, 6.0), (20.0, -20.0, 6.0)];

/// A centrally symmetric part: the dome z = 8·cos(πx/80)·cos(πy/80) over the 80 × 80 mm square
/// x, y ∈ [−40, 40] (height range 8 mm, convex seen from the tool), with four holes whose
/// projections are circles of radius 6 mm centred at (±20, ±20). Shape and holes are symmetric
/// under the quarter turn about the Z axis, so the centre (0, 0, 8) is the centre of symmetry
/// (the mesh itself is only nearly symmetric: lattice and jitter are not).
///
/// Height field over a Delaunay mesh, edge length ≈ 1.5 mm, about 6 000 faces, normals up.
/// Topology: 5 boundary loops, Euler characteristic −3.
pub fn symmetric_4_holes() -> TriMesh {
    let (p, t) = planar_domain_with_holes(&rect(-40.0, -40.0, 40.0, 40.0), &circles(&SYMMETRIC_HOLES), 1.5, 0x5E7);
    let k = std::f64::consts::PI / 80.0;
    lift(&p, t, |q| 8.0 * num::cos(k * q.x) * num::cos(k * q.y))
}

/// A 40 × 40 mm roof with a sharp ridge: two flat facets sloping 30° down from the ridge line
/// x = 0 (z = 10 − |x|·tan 30°, so the faces turn 60° there) and an 8 × 8 mm square hole beside
/// it (x ∈ [4, 12], y ∈ [1, 9]). A grid of 1 mm squares with vertices on the ridge, so the ridge
/// is an edge of the mesh: a ball rolls over it and its normals must not be averaged across it.
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn roof_ridge() -> TriMesh {
    let n = 40usize;
    let w = n + 1;
    let slope = num::tan(30f64.to_radians());
    let at = |i: usize| -20.0 + i as f64;
    let positions = (0..w * w).map(|k| DVec3::new(at(k % w), at(k / w), 10.0 - at(k % w).abs() * slope)).collect();
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (cx, cy) = (at(i) + 0.5, at(j) + 0.5);
            if cx > 4.0 && cx < 12.0 && cy > 1.0 && cy < 9.0 {
                continue;
            }
            let v = |di: usize, dj: usize| ((j + dj) * w + i + di) as u32;
            triangles.push([v(0, 0), v(1, 0), v(1, 1)]);
            triangles.push([v(0, 0), v(1, 1), v(0, 1)]);
        }
    }
    TriMesh { positions, triangles }
}

/// A CAD-style plate with one countersunk hole: the 60 × 40 mm top at z = 10 (centre at the
/// origin) and a 45° cone from radius 8 mm at z = 10 down to radius 4 mm at z = 6 (the hole's
/// rim), 24 facets round. Triangulated as a CAD export is: long thin triangles from the
/// cone's top edge to the eight points of the outer rectangle (corners and edge midpoints), so a
/// planner that refines it must not spread the 45° edge's normals over the flat.
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn countersunk_plate() -> TriMesh {
    let (rim, top, seg) = (4.0, 8.0, 24);
    let mut positions = Vec::new();
    let (bottom, fb) = push_ring(&mut positions, seg, 0.0, |t| DVec3::new(rim * num::cos(t), rim * num::sin(t), 6.0));
    let (edge, fe) = push_ring(&mut positions, seg, 0.0, |t| DVec3::new(top * num::cos(t), top * num::sin(t), 10.0));
    let corners = [
        (30.0, 0.0),
        (30.0, 20.0),
        (0.0, 20.0),
        (-30.0, 20.0),
        (-30.0, 0.0),
        (-30.0, -20.0),
        (0.0, -20.0),
        (30.0, -20.0),
    ];
    let mut outer = Vec::new();
    let mut fo = Vec::new();
    for (x, y) in corners {
        outer.push(positions.len() as u32);
        fo.push((num::atan2(y, x) / TAU).rem_euclid(1.0));
        positions.push(DVec3::new(x, y, 10.0));
    }
    let mut triangles = Vec::new();
    zip_rings(&bottom, &fb, &edge, &fe, &mut triangles);
    zip_rings(&edge, &fe, &outer, &fo, &mut triangles);
    TriMesh { positions, triangles }
}

/// A deliberately low-quality mesh: a gently curved 100 × 60 mm sheet (x ∈ [−50, 50],
/// y ∈ [−30, 30], z = −x²/400 + xy/500) meshed by a 200 × 6 structured grid of 0.5 × 10 mm cells
/// (aspect ratios 20:1 and worse), with jittered columns, some columns only 2 µm wide
/// (near-degenerate needles of non-zero area), and one rectangular hole (20 × 20 mm of cells
/// removed). Still a valid, consistently oriented manifold with normals up.
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn sliver_mesh() -> TriMesh {
    let (nx, ny) = (200usize, 6usize);
    let dx = 100.0 / nx as f64;
    let mut rng = SplitMix64(0x511BE4);
    let mut xs: Vec<f64> = (0..=nx).map(|i| -50.0 + dx * i as f64).collect();
    for x in &mut xs[1..nx] {
        *x += 0.3 * dx * rng.symmetric();
    }
    // Every tenth column collapses to 2 µm: needles with area ~1e-2 mm² next to 10 mm edges.
    for i in (5..nx).step_by(10) {
        xs[i] = xs[i - 1] + 0.002;
    }
    let ys: Vec<f64> = (0..=ny).map(|j| -30.0 + 10.0 * j as f64).collect();
    let positions: Vec<DVec3> = (0..=ny)
        .flat_map(|j| {
            let xs = &xs;
            let y = ys[j];
            xs.iter().map(move |&x| DVec3::new(x, y, -x * x / 400.0 + x * y / 500.0))
        })
        .collect();
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            if (90..130).contains(&i) && (2..4).contains(&j) {
                continue; // the hole
            }
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            } else {
                triangles.push([a, b, d]);
                triangles.push([b, c, d]);
            }
        }
    }
    compact(positions, triangles)
}

const BOX_CELL: f64 = 2.5;
const BOSS: [f64; 4] = [-35.0, -10.0, -15.0, 10.0]; // x0, y0, x1, y1; top at z = 28
const POCKET: [f64; 4] = [10.0, -15.0, 30.0, 10.0]; // floor at z = 12

/// A closed, watertight solid with outward normals: the box [−50, 50] × [−40, 40] × [0, 20] mm
/// whose top carries a 20 × 20 mm square boss up to z = 28 (x ∈ [−35, −15], y ∈ [−10, 10]) and a
/// 20 × 25 mm square pocket down to z = 12 (x ∈ [10, 30], y ∈ [−15, 10]), with vertical walls.
///
/// Built as a height field of 2.5 mm cells: a top quad per cell, vertical wall quads between
/// cells of different heights (the rim walls go down to z = 0), and a bottom on the same grid, so
/// there is no T-junction and every edge has exactly two faces. Volume 159 200 mm³. The top
/// surface (normals +Z) is the base top with two square holes, the boss top and the pocket floor.
/// Topology: closed, 0 boundary loops, Euler characteristic 2.
pub fn box_boss_pocket() -> TriMesh {
    let (nx, ny) = (40usize, 32usize);
    let (x0, y0) = (-50.0, -40.0);
    let inside = |r: &[f64; 4], x: f64, y: f64| x > r[0] && x < r[2] && y > r[1] && y < r[3];
    let height = |i: isize, j: isize| -> i64 {
        if i < 0 || j < 0 || i >= nx as isize || j >= ny as isize {
            return 0;
        }
        let x = x0 + (i as f64 + 0.5) * BOX_CELL;
        let y = y0 + (j as f64 + 0.5) * BOX_CELL;
        if inside(&BOSS, x, y) {
            28
        } else if inside(&POCKET, x, y) {
            12
        } else {
            20
        }
    };
    let mut b = QuadBuilder::default();
    let node = |i: usize, j: usize, z: i64| {
        (i, j, z, DVec3::new(x0 + i as f64 * BOX_CELL, y0 + j as f64 * BOX_CELL, z as f64))
    };
    for j in 0..ny {
        for i in 0..nx {
            let z = height(i as isize, j as isize);
            let q = [node(i, j, z), node(i + 1, j, z), node(i + 1, j + 1, z), node(i, j + 1, z)];
            b.quad(q, DVec3::Z);
            let q = [node(i, j, 0), node(i + 1, j, 0), node(i + 1, j + 1, 0), node(i, j + 1, 0)];
            b.quad(q, DVec3::NEG_Z);
        }
    }
    // Walls on the vertical grid lines x = const, then on the horizontal ones y = const.
    for i in 0..=nx {
        for j in 0..ny {
            let (hl, hr) = (height(i as isize - 1, j as isize), height(i as isize, j as isize));
            if hl != hr {
                let (lo, hi) = (hl.min(hr), hl.max(hr));
                let q = [node(i, j, lo), node(i, j + 1, lo), node(i, j + 1, hi), node(i, j, hi)];
                b.quad(q, if hl > hr { DVec3::X } else { DVec3::NEG_X });
            }
        }
    }
    for j in 0..=ny {
        for i in 0..nx {
            let (hb, ha) = (height(i as isize, j as isize - 1), height(i as isize, j as isize));
            if hb != ha {
                let (lo, hi) = (hb.min(ha), hb.max(ha));
                let q = [node(i, j, lo), node(i + 1, j, lo), node(i + 1, j, hi), node(i, j, hi)];
                b.quad(q, if hb > ha { DVec3::Y } else { DVec3::NEG_Y });
            }
        }
    }
    b.mesh
}

/// Collects quads on a lattice of keyed vertices, each vertex created once.
#[derive(Default)]
struct QuadBuilder {
    ids: BTreeMap<(usize, usize, i64), u32>,
    mesh: TriMesh,
}

impl QuadBuilder {
    fn vertex(&mut self, (i, j, z, p): (usize, usize, i64, DVec3)) -> u32 {
        let next = self.mesh.positions.len() as u32;
        let id = *self.ids.entry((i, j, z)).or_insert(next);
        if id == next {
            self.mesh.positions.push(p);
        }
        id
    }

    /// A planar quad given in cyclic order, wound so its normal points along `outward`.
    fn quad(&mut self, q: [(usize, usize, i64, DVec3); 4], outward: DVec3) {
        let n = (q[1].3 - q[0].3).cross(q[2].3 - q[0].3);
        let mut v = q.map(|c| self.vertex(c));
        if n.dot(outward) < 0.0 {
            v.reverse();
        }
        self.mesh.triangles.push([v[0], v[1], v[2]]);
        self.mesh.triangles.push([v[0], v[2], v[3]]);
    }
}

// ---------------------------------------------------------------------------------------------
// Curvature test shapes
// ---------------------------------------------------------------------------------------------

/// Closed icosphere of the given radius centred at the origin, outward normals: the icosahedron
/// with every triangle split in four `subdivisions` times (20·4^s faces, vertices exactly on the
/// sphere). Principal curvatures 1/r, 1/r. For curvature estimates within 2 % use
/// `subdivisions` = 4 (5 120 faces, edge ≈ 0.06·r) or 5.
/// Topology: closed, 0 boundary loops, Euler characteristic 2.
pub fn sphere(radius: f64, subdivisions: usize) -> TriMesh {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<DVec3> = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    // Orient outward whatever the table says (the icosahedron is convex about the origin).
    for t in &mut tris {
        let [a, b, c] = t.map(|i| pos[i as usize]);
        if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
            t.swap(1, 2);
        }
    }
    for _ in 0..subdivisions {
        let mut mid: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        let mut m = |a: u32, b: u32, pos: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push((pos[a as usize] + pos[b as usize]).normalize());
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for &[a, b, c] in &tris {
            let (ab, bc, ca) = (m(a, b, &mut pos), m(b, c, &mut pos), m(c, a, &mut pos));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    TriMesh { positions: pos.into_iter().map(|p| p * radius).collect(), triangles: tris }
}

/// Open cylindrical tube of the given radius around the Z axis, z ∈ [0, height], outward normals
/// (away from the axis): `stacks` + 1 rings of `segments` vertices, every other ring rotated by
/// half a segment so the triangles are nearly equilateral when
/// `stacks` ≈ height / (0.866 · 2πr / segments). Principal curvatures 1/r, 0. For curvature
/// estimates within 2 % use e.g. `cylinder(10.0, 20.0, 96, 36)`.
/// Topology: 2 boundary loops, Euler characteristic 0.
pub fn cylinder(radius: f64, height: f64, segments: usize, stacks: usize) -> TriMesh {
    assert!(segments >= 3 && stacks >= 1, "cylinder needs segments >= 3, stacks >= 1");
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut prev: Option<(Vec<u32>, Vec<f64>)> = None;
    for k in 0..=stacks {
        let z = height * k as f64 / stacks as f64;
        let (ring, frac) = push_ring(&mut positions, segments, 0.5 * (k % 2) as f64, |t| {
            DVec3::new(radius * num::cos(t), radius * num::sin(t), z)
        });
        if let Some((p, pf)) = &prev {
            // The upper ring plays the "inner" ring of the planar zipper: that makes normals
            // point away from the axis.
            zip_rings(&ring, &frac, p, pf, &mut triangles);
        }
        prev = Some((ring, frac));
    }
    TriMesh { positions, triangles }
}

// ---------------------------------------------------------------------------------------------
// Cutter-contact paths on analytic surfaces (toolpath and post-processor tests)
// ---------------------------------------------------------------------------------------------

/// An analytic surface with an exact normal, for synthetic cutter-contact paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactSurface {
    /// The convex cap of [`spherical_cap_hole`]: sphere radius 60 mm centred on the −Z axis so
    /// that the base circle of radius 40 mm lies in z = 0.
    SphericalCap,
    /// The saddle of [`saddle_2_holes`]: z = (x² − y²)/(2·125).
    Saddle,
}

impl ContactSurface {
    /// The point of the surface above (x, y) and its unit normal (upwards, towards the tool).
    pub fn point_normal(self, q: DVec2) -> (DVec3, DVec3) {
        match self {
            ContactSurface::SphericalCap => {
                let z0 = (CAP_SPHERE_R * CAP_SPHERE_R - CAP_BASE_R * CAP_BASE_R).sqrt();
                let zs = (CAP_SPHERE_R * CAP_SPHERE_R - q.length_squared()).max(0.0).sqrt();
                let p = DVec3::new(q.x, q.y, zs - z0);
                (p, DVec3::new(q.x, q.y, zs) / CAP_SPHERE_R)
            }
            ContactSurface::Saddle => {
                let p = DVec3::new(q.x, q.y, (q.x * q.x - q.y * q.y) / (2.0 * SADDLE_C));
                (p, DVec3::new(-q.x / SADDLE_C, q.y / SADDLE_C, 1.0).normalize())
            }
        }
    }

    /// The centre of the sphere (for [`ContactSurface::SphericalCap`]), whose offset by the ball
    /// radius is an exact oracle for ball centres.
    pub fn sphere_centre_and_radius() -> (DVec3, f64) {
        let z0 = (CAP_SPHERE_R * CAP_SPHERE_R - CAP_BASE_R * CAP_BASE_R).sqrt();
        (DVec3::new(0.0, 0.0, -z0), CAP_SPHERE_R)
    }
}

/// Cutter-contact points and exact unit normals along one continuous pass.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactPath {
    pub cc: Vec<DVec3>,
    pub normals: Vec<DVec3>,
}

/// An Archimedean spiral in projection, counter-clockwise from radius `r_outer` inwards to
/// `r_inner` (mm) with `pitch` mm per turn, sampled every ≈ `step` mm of projected arc length,
/// lifted onto `surface` with its exact normals: a stand-in for the spiral stage's output.
///
/// Deterministic (no randomness); consecutive points are distinct. Requires
/// 0 < r_inner < r_outer, pitch > 0 and step > 0.
pub fn contact_spiral(surface: ContactSurface, r_outer: f64, r_inner: f64, pitch: f64, step: f64) -> ContactPath {
    assert!(
        r_inner > 0.0 && r_outer > r_inner && pitch > 0.0 && step > 0.0,
        "contact_spiral needs 0 < r_inner < r_outer, pitch > 0 and step > 0"
    );
    let (mut cc, mut normals) = (Vec::new(), Vec::new());
    let mut theta = 0.0_f64;
    loop {
        let r = (r_outer - pitch * theta / TAU).max(r_inner);
        let (s, c) = crate::num::sin_cos(theta);
        let (p, n) = surface.point_normal(DVec2::new(r * c, r * s));
        cc.push(p);
        normals.push(n);
        if r <= r_inner {
            break;
        }
        theta += step / r;
    }
    ContactPath { cc, normals }
}

// ---------------------------------------------------------------------------------------------
// Building blocks
// ---------------------------------------------------------------------------------------------

/// Tiny deterministic generator (SplitMix64): the fixtures' jitter and the verifier's samples.
pub(crate) struct SplitMix64(pub(crate) u64);

impl SplitMix64 {
    const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

    /// The generator `seed` after `k` draws: its state only counts (what lets a stream be cut
    /// into pieces drawn in parallel).
    pub(crate) fn skipped(seed: u64, k: u64) -> Self {
        Self(seed.wrapping_add(k.wrapping_mul(Self::GAMMA)))
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(Self::GAMMA);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [−1, 1).
    fn symmetric(&mut self) -> f64 {
        2.0 * self.unit() - 1.0
    }
}

/// Appends a ring of `n` vertices at angles 2π(j + offset)/n; returns their ids and angle
/// fractions (j + offset)/n.
fn push_ring(positions: &mut Vec<DVec3>, n: usize, offset: f64, at: impl Fn(f64) -> DVec3) -> (Vec<u32>, Vec<f64>) {
    let mut ids = Vec::with_capacity(n);
    let mut frac = Vec::with_capacity(n);
    for j in 0..n {
        let f = (j as f64 + offset) / n as f64;
        ids.push(positions.len() as u32);
        frac.push(f);
        positions.push(at(TAU * f));
    }
    (ids, frac)
}

/// Triangulates the band between two closed rings around a common centre, `a` inside `b`
/// (counter-clockwise, angle fractions increasing from near 0). Merges the two angle sequences so
/// each new rung joins the next vertex that comes first, which keeps triangles well shaped.
fn zip_rings(a: &[u32], fa: &[f64], b: &[u32], fb: &[f64], tris: &mut Vec<[u32; 3]>) {
    let (na, nb) = (a.len(), b.len());
    if na == 1 {
        for j in 0..nb {
            tris.push([a[0], b[j], b[(j + 1) % nb]]);
        }
        return;
    }
    let next = |f: &[f64], i: usize| {
        if i + 1 < f.len() {
            f[i + 1]
        } else {
            1.0 + f[0]
        }
    };
    let (mut i, mut j) = (0, 0);
    while i < na || j < nb {
        let advance_a = i < na && (j == nb || next(fa, i) < next(fb, j));
        if advance_a {
            tris.push([a[i], b[j % nb], a[(i + 1) % na]]);
            i += 1;
        } else {
            tris.push([a[i % na], b[j], b[(j + 1) % nb]]);
            j += 1;
        }
    }
}

/// Drops unreferenced vertices (keeping order) and renumbers the triangles.
fn compact(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> TriMesh {
    let mut map = vec![u32::MAX; positions.len()];
    for t in &triangles {
        for &i in t {
            map[i as usize] = 0;
        }
    }
    let mut kept = Vec::new();
    for (i, p) in positions.into_iter().enumerate() {
        if map[i] == 0 {
            map[i] = kept.len() as u32;
            kept.push(p);
        }
    }
    TriMesh { positions: kept, triangles: triangles.into_iter().map(|t| t.map(|i| map[i as usize])).collect() }
}

/// Height field z = f(x, y) over a planar mesh (keeps counter-clockwise = normals up).
fn lift(p: &[DVec2], triangles: Vec<[u32; 3]>, f: impl Fn(DVec2) -> f64) -> TriMesh {
    TriMesh { positions: p.iter().map(|&q| DVec3::new(q.x, q.y, f(q))).collect(), triangles }
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Curve {
    Curve::Rect { min: DVec2::new(x0, y0), max: DVec2::new(x1, y1) }
}

fn circles(c: &[(f64, f64, f64)]) -> Vec<Curve> {
    c.iter().map(|&(x, y, r)| Curve::Circle { c: DVec2::new(x, y), r }).collect()
}

/// A closed convex boundary curve of a planar domain.
#[derive(Clone, Copy, Debug)]
enum Curve {
    Circle {
        c: DVec2,
        r: f64,
    },
    /// Semi-axes `a` (along the direction `rot`) and `b`.
    Ellipse {
        c: DVec2,
        a: f64,
        b: f64,
        rot: f64,
    },
    Rect {
        min: DVec2,
        max: DVec2,
    },
}

impl Curve {
    fn contains(&self, p: DVec2) -> bool {
        match *self {
            Curve::Circle { c, r } => (p - c).length_squared() < r * r,
            Curve::Ellipse { c, a, b, rot } => {
                let q = DVec2::new(num::cos(rot), -num::sin(rot)).rotate(p - c);
                (q.x / a).powi(2) + (q.y / b).powi(2) < 1.0
            }
            Curve::Rect { min, max } => p.cmpgt(min).all() && p.cmplt(max).all(),
        }
    }

    /// Points inside the curve that help the triangulation but are not part of the mesh (they
    /// keep the many co-circular boundary points of a hole away from each other's circles).
    fn steiner(&self) -> Vec<DVec2> {
        match *self {
            Curve::Circle { c, .. } => vec![c],
            Curve::Ellipse { c, a, rot, .. } => {
                let u = DVec2::new(num::cos(rot), num::sin(rot)) * (0.5 * a);
                vec![c - u, c + 0.1 * u.perp(), c + u]
            }
            Curve::Rect { .. } => vec![],
        }
    }

    /// Counter-clockwise samples with spacing ≤ `h`, exactly on the curve. For a rectangle the
    /// spacing is the lattice spacing (hx along x, hy along y) so the lattice meets it evenly.
    fn sample(&self, h: f64, hx: f64, hy: f64, phase: f64) -> Vec<DVec2> {
        match *self {
            Curve::Circle { c, r } => {
                let n = ((TAU * r / h).ceil() as usize).max(6);
                (0..n)
                    .map(|k| {
                        let t = TAU * (k as f64 + phase) / n as f64;
                        c + r * DVec2::new(num::cos(t), num::sin(t))
                    })
                    .collect()
            }
            Curve::Ellipse { c, a, b, rot } => {
                // Equal arc length spacing through a fine cumulative-length table.
                let m = 4096;
                let at = |t: f64| {
                    c + DVec2::new(num::cos(rot), num::sin(rot)).rotate(DVec2::new(a * num::cos(t), b * num::sin(t)))
                };
                let mut cum = vec![0.0; m + 1];
                for k in 1..=m {
                    let (t0, t1) = (TAU * (k - 1) as f64 / m as f64, TAU * k as f64 / m as f64);
                    cum[k] = cum[k - 1] + (at(t1) - at(t0)).length();
                }
                let n = ((cum[m] / h).ceil() as usize).max(8);
                let mut seg = 0;
                (0..n)
                    .map(|k| {
                        let s = cum[m] * (k as f64 + phase) / n as f64;
                        while cum[seg + 1] < s {
                            seg += 1;
                        }
                        let w = (s - cum[seg]) / (cum[seg + 1] - cum[seg]);
                        at(TAU * (seg as f64 + w) / m as f64)
                    })
                    .collect()
            }
            Curve::Rect { min, max } => {
                let nx = ((max.x - min.x) / hx).round() as usize;
                let ny = ((max.y - min.y) / hy).round() as usize;
                let x = |i: usize| {
                    if i == nx {
                        max.x
                    } else {
                        min.x + i as f64 * hx
                    }
                };
                let y = |j: usize| {
                    if j == ny {
                        max.y
                    } else {
                        min.y + j as f64 * hy
                    }
                };
                let mut v = Vec::new();
                v.extend((0..nx).map(|i| DVec2::new(x(i), min.y)));
                v.extend((0..ny).map(|j| DVec2::new(max.x, y(j))));
                v.extend((0..nx).map(|i| DVec2::new(x(nx - i), max.y)));
                v.extend((0..ny).map(|j| DVec2::new(min.x, y(ny - j))));
                v
            }
        }
    }
}

fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (p - (a + t * d)).length()
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Label {
    /// Boundary vertex of loop k (0 = outer, 1.. = holes).
    Loop(u32),
    Interior,
    /// Helper points outside the domain: removed with every triangle touching them.
    Outside,
}

/// Quasi-uniform triangulation of a planar domain: the inside of `outer` minus the insides of
/// `holes` (convex curves, disjoint, each at least ~2h from the others and from `outer`), edge
/// length ≈ `h`, counter-clockwise triangles.
///
/// Why this way: the lattice gives equilateral triangles in the bulk, the boundary samples lie
/// exactly on the analytic curves, and a Delaunay triangulation joins the two with the best
/// angles available. Lattice points closer than 0.45h to the boundary are dropped, helper points
/// outside the domain (an offset row beyond the outer curve, a centre inside each hole) make the
/// boundary edges Delaunay edges and keep co-circular boundary points apart; every triangle that
/// touches a helper point or has all three corners on one hole is then removed. Three rounds of
/// Laplacian smoothing of the interior vertices, each followed by a fresh Delaunay, even out the
/// band where lattice and boundary meet (projected minimum angle 23–28° on the fixtures).
///
/// Output vertex order: outer loop, then each hole's loop, then interior vertices.
fn planar_domain_with_holes(outer: &Curve, holes: &[Curve], h: f64, seed: u64) -> (Vec<DVec2>, Vec<[u32; 3]>) {
    let mut rng = SplitMix64(seed);
    let (lo, hi, hx, hy) = match *outer {
        Curve::Rect { min, max } => {
            let nx = ((max.x - min.x) / h).round().max(1.0);
            let ny = ((max.y - min.y) / (h * 0.75f64.sqrt())).round().max(1.0);
            (min, max, (max.x - min.x) / nx, (max.y - min.y) / ny)
        }
        Curve::Circle { c, r } => (c - r, c + r, h, h * 0.75f64.sqrt()),
        Curve::Ellipse { c, a, .. } => (c - a, c + a, h, h * 0.75f64.sqrt()),
    };
    // Boundary loops.
    let mut loops = vec![outer.sample(h, hx, hy, 0.0)];
    for hole in holes {
        // A non-symmetric start keeps mirror-symmetric (co-circular) quadruples out.
        loops.push(hole.sample(h, hx, hy, 0.37));
    }
    let segs: Vec<(DVec2, DVec2)> =
        loops.iter().flat_map(|l| (0..l.len()).map(move |k| (l[k], l[(k + 1) % l.len()]))).collect();
    // Lattice points well inside the domain, with a tiny jitter against exact co-circularity.
    let mut interior = Vec::new();
    let (nx, ny) = (((hi.x - lo.x) / hx).round() as i64, ((hi.y - lo.y) / hy).round() as i64);
    for j in 0..=ny {
        for i in -1..=nx {
            let p = lo + DVec2::new((i as f64 + 0.5 * (j % 2) as f64) * hx, j as f64 * hy);
            if !outer.contains(p) || holes.iter().any(|c| c.contains(p)) {
                continue;
            }
            if segs.iter().any(|&(a, b)| segment_distance(p, a, b) < 0.45 * h) {
                continue;
            }
            interior.push(p + 1e-3 * h * DVec2::new(rng.symmetric(), rng.symmetric()));
        }
    }
    // Guard points one offset row outside the outer loop (counter-clockwise: outside is right).
    let o = &loops[0];
    let guards: Vec<DVec2> = (0..o.len())
        .map(|k| {
            let (a, b) = (o[k], o[(k + 1) % o.len()]);
            let d = b - a;
            0.5 * (a + b) + DVec2::new(d.y, -d.x) * (0.8 + 0.15 * rng.unit())
        })
        .collect();

    let mut pts: Vec<DVec2> = Vec::new();
    let mut labels = Vec::new();
    for (k, l) in loops.iter().enumerate() {
        pts.extend_from_slice(l);
        labels.extend(std::iter::repeat(Label::Loop(k as u32)).take(l.len()));
    }
    pts.extend_from_slice(&interior);
    labels.extend(std::iter::repeat(Label::Interior).take(interior.len()));
    let n_mesh = pts.len();
    for hole in holes {
        pts.extend(hole.steiner());
    }
    pts.extend_from_slice(&guards);
    labels.resize(pts.len(), Label::Outside);

    // Insertion order: hole centres first (so hole points never see each other's circles), then
    // the lattice, then boundary loops, then the guards.
    let steiner = n_mesh..n_mesh + (pts.len() - n_mesh - guards.len());
    let lattice = (n_mesh - interior.len())..n_mesh;
    let order: Vec<u32> = steiner
        .chain(lattice)
        .chain(0..n_mesh - interior.len())
        .chain(pts.len() - guards.len()..pts.len())
        .map(|i| i as u32)
        .collect();
    // Delaunay, then a few rounds of Laplacian smoothing of the interior vertices (each followed
    // by a fresh Delaunay) to even out the band where the lattice meets the boundary.
    let keep = |tris: Vec<[u32; 3]>| -> Vec<[u32; 3]> {
        tris.into_iter()
            .filter(|t| {
                let l = t.map(|i| labels[i as usize]);
                if l.contains(&Label::Outside) {
                    return false;
                }
                // All three corners on one hole: the triangle is inside that hole.
                !matches!(l, [Label::Loop(a), Label::Loop(b), Label::Loop(c)] if a > 0 && a == b && b == c)
            })
            .collect()
    };
    let mut out = keep(delaunay(&pts, &order));
    for _ in 0..SMOOTHING_ROUNDS {
        let mut sum = vec![DVec2::ZERO; n_mesh];
        let mut cnt = vec![0u32; n_mesh];
        for t in &out {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                sum[a] += pts[b];
                cnt[a] += 1;
                sum[b] += pts[a];
                cnt[b] += 1;
            }
        }
        for i in 0..n_mesh {
            if labels[i] == Label::Interior && cnt[i] > 0 {
                pts[i] = sum[i] / cnt[i] as f64;
            }
        }
        out = keep(delaunay(&pts, &order));
    }
    pts.truncate(n_mesh);
    (pts, out)
}

const NONE: u32 = u32::MAX;

/// Smoothing rounds of the planar mesher (each: Laplacian step of interior vertices + Delaunay).
const SMOOTHING_ROUNDS: usize = 3;

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// > 0 when `d` is strictly inside the circumcircle of the counter-clockwise triangle a, b, c.
fn incircle(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    let (a, b, c) = (a - d, b - d, c - d);
    a.length_squared() * b.perp_dot(c) + b.length_squared() * c.perp_dot(a) + c.length_squared() * a.perp_dot(b)
}

/// Bowyer–Watson Delaunay triangulation of `pts` inserted in `order` (all of them), walking point
/// location from the last new triangle. Returns counter-clockwise triangles (indices into `pts`).
fn delaunay(pts: &[DVec2], order: &[u32]) -> Vec<[u32; 3]> {
    let (mut lo, mut hi) = (pts[0], pts[0]);
    for &p in pts {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let (c, e) = (0.5 * (lo + hi), (hi - lo).max_element().max(1e-9));
    let mut p = pts.to_vec();
    let s = p.len() as u32;
    p.extend([
        c + DVec2::new(-40.0 * e, -30.0 * e),
        c + DVec2::new(40.0 * e, -30.0 * e),
        c + DVec2::new(0.0, 40.0 * e),
    ]);
    let mut tri = vec![[s, s + 1, s + 2]];
    let mut nbr = vec![[NONE; 3]];
    let mut alive = vec![true];
    let mut mark = vec![0u32];
    let mut last = 0usize;
    let mut bad = Vec::new();
    let mut stack = Vec::new();
    let mut rim: Vec<(u32, u32, u32, usize)> = Vec::new();
    for (stamp, &v) in order.iter().enumerate() {
        let stamp = stamp as u32 + 1;
        let q = p[v as usize];
        // Visibility walk; a capped number of steps, then a scan, so it always ends.
        let mut t = last;
        let mut steps = 0;
        'walk: loop {
            steps += 1;
            if steps > tri.len() + 10 {
                t = (0..tri.len())
                    .find(|&k| {
                        alive[k]
                            && (0..3).all(|i| {
                                orient(p[tri[k][(i + 1) % 3] as usize], p[tri[k][(i + 2) % 3] as usize], q) >= 0.0
                            })
                    })
                    .expect("delaunay: point outside the super triangle");
                break;
            }
            for i in 0..3 {
                let (a, b) = (tri[t][(i + 1) % 3], tri[t][(i + 2) % 3]);
                if orient(p[a as usize], p[b as usize], q) < 0.0 {
                    t = nbr[t][i] as usize;
                    continue 'walk;
                }
            }
            break;
        }
        // Cavity: triangles whose circumcircle holds q, grown from the one containing it.
        bad.clear();
        bad.push(t);
        stack.push(t);
        mark[t] = stamp;
        while let Some(t) = stack.pop() {
            for &n in &nbr[t] {
                if n != NONE && mark[n as usize] != stamp {
                    let [a, b, c] = tri[n as usize].map(|i| p[i as usize]);
                    if incircle(a, b, c, q) > 0.0 {
                        mark[n as usize] = stamp;
                        bad.push(n as usize);
                        stack.push(n as usize);
                    }
                }
            }
        }
        // Re-triangulate the cavity as a fan around q.
        rim.clear();
        for &t in &bad {
            alive[t] = false;
            for i in 0..3 {
                let n = nbr[t][i];
                if n == NONE || mark[n as usize] != stamp {
                    let (a, b) = (tri[t][(i + 1) % 3], tri[t][(i + 2) % 3]);
                    assert!(orient(p[a as usize], p[b as usize], q) > 0.0, "delaunay: cavity not star-shaped");
                    let id = tri.len();
                    tri.push([a, b, v]);
                    nbr.push([NONE, NONE, n]);
                    alive.push(true);
                    mark.push(0);
                    if n != NONE {
                        let slot = nbr[n as usize].iter().position(|&x| x == t as u32).unwrap();
                        nbr[n as usize][slot] = id as u32;
                    }
                    rim.push((a, b, v, id));
                }
            }
        }
        for k in 0..rim.len() {
            let (a, b, _, id) = rim[k];
            // Across (b, q): the new triangle starting at b; across (q, a): the one ending at a.
            nbr[id][0] = rim.iter().find(|r| r.0 == b).unwrap().3 as u32;
            nbr[id][1] = rim.iter().find(|r| r.1 == a).unwrap().3 as u32;
        }
        last = rim[0].3;
    }
    (0..tri.len()).filter(|&k| alive[k] && tri[k].iter().all(|&i| i < s)).map(|k| tri[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skipped_generator_continues_the_stream() {
        let mut stream = SplitMix64(7);
        let drawn: Vec<u64> = (0..100).map(|_| stream.next_u64()).collect();
        for k in [0usize, 1, 3, 99] {
            assert_eq!(SplitMix64::skipped(7, k as u64).next_u64(), drawn[k], "after {k} draws");
        }
    }

    struct Topo {
        loops: Vec<Vec<u32>>,
        chi: i64,
    }

    /// Checks indices, non-zero areas, manifold edges with consistent orientation, no isolated or
    /// duplicated vertices; returns boundary loops and the Euler characteristic.
    fn topo(name: &str, m: &TriMesh) -> Topo {
        let nv = m.positions.len();
        assert!(!m.triangles.is_empty(), "{name}: empty");
        let mut used = vec![false; nv];
        let mut directed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        for (f, t) in m.triangles.iter().enumerate() {
            for &i in t {
                assert!((i as usize) < nv, "{name}: face {f} index {i} out of range");
                used[i as usize] = true;
            }
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).length() > 0.0, "{name}: face {f} has zero area");
            for k in 0..3 {
                let e = (t[k], t[(k + 1) % 3]);
                assert!(e.0 != e.1, "{name}: face {f} repeats a vertex");
                let n = directed.entry(e).or_insert(0);
                *n += 1;
                // Two faces running an edge the same way = inconsistent orientation (or > 2 faces).
                assert_eq!(*n, 1, "{name}: directed edge {e:?} used twice");
            }
        }
        assert!(used.iter().all(|&u| u), "{name}: unreferenced vertex");
        let mut sorted: Vec<[u64; 3]> = m.positions.iter().map(|p| [p.x, p.y, p.z].map(|c| c.to_bits())).collect();
        sorted.sort_unstable();
        assert!(sorted.windows(2).all(|w| w[0] != w[1]), "{name}: duplicated position");
        let mut undirected = 0;
        let mut next: BTreeMap<u32, u32> = BTreeMap::new();
        for &(a, b) in directed.keys() {
            if !directed.contains_key(&(b, a)) {
                // Boundary edge; one outgoing boundary edge per vertex (no pinch vertices).
                assert!(next.insert(a, b).is_none(), "{name}: pinch vertex {a}");
                undirected += 2;
            } else {
                undirected += 1;
            }
        }
        let edges = undirected / 2;
        let mut loops = Vec::new();
        let mut seen: BTreeMap<u32, ()> = BTreeMap::new();
        for &start in next.keys() {
            if seen.contains_key(&start) {
                continue;
            }
            let mut l = vec![start];
            seen.insert(start, ());
            let mut v = next[&start];
            while v != start {
                assert!(seen.insert(v, ()).is_none(), "{name}: boundary not a set of cycles");
                l.push(v);
                v = next[&v];
            }
            loops.push(l);
        }
        Topo { loops, chi: nv as i64 - edges as i64 + m.triangles.len() as i64 }
    }

    fn face_normal(m: &TriMesh, t: &[u32; 3]) -> DVec3 {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        (b - a).cross(c - a)
    }

    /// Smallest triangle angle of the mesh projected on z = 0, degrees.
    fn min_angle_xy(m: &TriMesh) -> f64 {
        let mut worst = 180f64;
        for t in &m.triangles {
            let p = t.map(|i| m.positions[i as usize].truncate());
            for k in 0..3 {
                let (u, v) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                worst = worst.min(u.angle_to(v).abs().to_degrees());
            }
        }
        worst
    }

    fn expected(name: &str) -> (usize, i64) {
        match name {
            "unit_disk" => (1, 1),
            "concentric_annulus" | "eccentric_annulus" => (2, 0),
            "plate_3_holes" => (4, -2),
            "saddle_2_holes" => (3, -1),
            "spherical_cap_hole" => (2, 0),
            "freeform_4_holes" => (5, -3),
            "sliver_mesh" => (2, 0),
            "box_boss_pocket" => (0, 2),
            _ => unreachable!(),
        }
    }

    #[test]
    fn every_fixture_is_a_valid_manifold_with_the_expected_topology() {
        assert_eq!(NAMES.len(), 9);
        assert!(by_name("nope").is_none());
        for &name in NAMES {
            let m = by_name(name).unwrap();
            let t = topo(name, &m);
            let (loops, chi) = expected(name);
            assert_eq!(t.loops.len(), loops, "{name}: boundary loops");
            assert_eq!(t.chi, chi, "{name}: Euler characteristic");
            assert!(m.triangles.len() <= 20_000, "{name}: {} faces", m.triangles.len());
            if name != "box_boss_pocket" {
                // Open surfaces face up, every face (so also the area-weighted mean).
                let mut mean = DVec3::ZERO;
                for tri in &m.triangles {
                    let n = face_normal(&m, tri);
                    assert!(n.z > 0.0, "{name}: face pointing down");
                    mean += n;
                }
                assert!(mean.normalize().z > 0.7, "{name}: mean normal {mean}");
            }
        }
    }

    #[test]
    fn flat_fixtures_are_flat_and_well_shaped() {
        for name in ["unit_disk", "concentric_annulus", "eccentric_annulus", "plate_3_holes"] {
            let m = by_name(name).unwrap();
            assert!(m.positions.iter().all(|p| p.z == 0.0), "{name}");
            let a = min_angle_xy(&m);
            assert!(a > 20.0, "{name}: min angle {a}");
        }
        for name in ["saddle_2_holes", "spherical_cap_hole", "freeform_4_holes"] {
            let a = min_angle_xy(&by_name(name).unwrap());
            assert!(a > 20.0, "{name}: projected min angle {a}");
        }
    }

    /// Every boundary vertex lies on one of the analytic curves (in projection) to 1e-12, and
    /// every curve carries boundary vertices.
    fn check_boundary_on(name: &str, m: &TriMesh, curves: &[Curve]) {
        let t = topo(name, m);
        let mut hits = vec![0usize; curves.len()];
        for l in &t.loops {
            for &v in l {
                let p = m.positions[v as usize].truncate();
                let k = curves
                    .iter()
                    .position(|c| curve_residual(c, p) < 1e-12)
                    .unwrap_or_else(|| panic!("{name}: boundary vertex {p} on no curve"));
                hits[k] += 1;
            }
        }
        assert!(hits.iter().all(|&h| h >= 6), "{name}: {hits:?}");
    }

    fn curve_residual(c: &Curve, p: DVec2) -> f64 {
        match *c {
            Curve::Circle { c, r } => ((p - c).length() - r).abs(),
            Curve::Ellipse { c, a, b, rot } => {
                let q = DVec2::from_angle(-rot).rotate(p - c);
                ((q.x / a).powi(2) + (q.y / b).powi(2) - 1.0).abs()
            }
            Curve::Rect { min, max } => {
                let on = |v: f64, lo: f64, hi: f64| (v - lo).abs().min((v - hi).abs());
                let inside = p.cmpge(min).all() && p.cmple(max).all();
                if inside {
                    on(p.x, min.x, max.x).min(on(p.y, min.y, max.y))
                } else {
                    f64::INFINITY
                }
            }
        }
    }

    #[test]
    fn boundary_vertices_lie_on_the_analytic_curves() {
        let unit = Curve::Circle { c: DVec2::ZERO, r: 1.0 };
        check_boundary_on("unit_disk", &unit_disk(24), &[unit]);
        let inner = Curve::Circle { c: DVec2::ZERO, r: 0.4 };
        check_boundary_on("concentric_annulus", &concentric_annulus(0.4, 16), &[unit, inner]);
        let hole = Curve::Circle { c: DVec2::new(0.3, 0.1), r: 0.35 };
        check_boundary_on("eccentric_annulus", &by_name("eccentric_annulus").unwrap(), &[unit, hole]);
        let mut c = vec![rect(-50.0, -40.0, 50.0, 40.0)];
        c.extend(circles(&PLATE_HOLES));
        check_boundary_on("plate_3_holes", &plate_3_holes(), &c);
        let mut c = vec![rect(-40.0, -40.0, 40.0, 40.0)];
        c.extend(circles(&SADDLE_HOLES));
        check_boundary_on("saddle_2_holes", &saddle_2_holes(), &c);
        let mut c = vec![Curve::Circle { c: DVec2::ZERO, r: CAP_BASE_R }];
        c.extend(circles(&CAP_HOLE));
        check_boundary_on("spherical_cap_hole", &spherical_cap_hole(), &c);
        let mut c = vec![rect(-60.0, -45.0, 60.0, 45.0)];
        c.extend(freeform_holes());
        check_boundary_on("freeform_4_holes", &freeform_4_holes(), &c);
    }

    #[test]
    fn refinement_halves_the_edge_length() {
        let edge = |m: &TriMesh| {
            let (mut lo, mut hi) = (f64::INFINITY, 0f64);
            for t in &m.triangles {
                for k in 0..3 {
                    let l = (m.positions[t[k] as usize] - m.positions[t[(k + 1) % 3] as usize]).length();
                    lo = lo.min(l);
                    hi = hi.max(l);
                }
            }
            (lo, hi)
        };
        let (a, b) = (unit_disk(12), unit_disk(24));
        assert_eq!(b.triangles.len(), 6 * 24 * 24);
        let (ea, eb) = (edge(&a), edge(&b));
        assert!((ea.1 / eb.1 - 2.0).abs() < 0.1 && (ea.0 / eb.0 - 2.0).abs() < 0.1, "{ea:?} {eb:?}");
        let (ea, eb) = (edge(&concentric_annulus(0.4, 8)), edge(&concentric_annulus(0.4, 16)));
        assert!((ea.1 / eb.1 - 2.0).abs() < 0.2, "{ea:?} {eb:?}");
        for r in [12, 24, 48] {
            let m = eccentric_annulus(DVec2::new(0.3, 0.1), 0.35, r);
            let t = topo("eccentric", &m);
            assert_eq!((t.loops.len(), t.chi), (2, 0));
            let (lo, hi) = edge(&m);
            let h = 1.0 / r as f64;
            assert!(hi < 1.6 * h && lo > 0.3 * h, "rings {r}: {lo} {hi}");
            assert!(min_angle_xy(&m) > 20.0);
        }
    }

    #[test]
    fn parameter_sweeps_stay_valid() {
        for rings in [1, 2, 3, 7, 40] {
            let t = topo("unit_disk", &unit_disk(rings));
            assert_eq!((t.loops.len(), t.chi), (1, 1), "unit_disk({rings})");
        }
        for (inner, rings) in [(0.05, 3), (0.1, 10), (0.5, 1), (0.8, 20), (0.95, 4)] {
            let m = concentric_annulus(inner, rings);
            let t = topo("concentric_annulus", &m);
            assert_eq!((t.loops.len(), t.chi), (2, 0), "concentric_annulus({inner}, {rings})");
            // A hole much smaller than the layer width cannot have well-shaped triangles.
            if inner >= (1.0 - inner) / rings as f64 {
                assert!(min_angle_xy(&m) > 20.0, "concentric_annulus({inner}, {rings})");
            }
        }
        let cases = [((0.0, 0.0), 0.5, 16), ((0.5, 0.0), 0.3, 32), ((-0.2, 0.4), 0.2, 20), ((0.1, -0.6), 0.25, 64)];
        for ((x, y), r, rings) in cases {
            let m = eccentric_annulus(DVec2::new(x, y), r, rings);
            let t = topo("eccentric_annulus", &m);
            assert_eq!((t.loops.len(), t.chi), (2, 0), "eccentric_annulus({x}, {y}, {r}, {rings})");
            assert!(min_angle_xy(&m) > 20.0, "eccentric_annulus({x}, {y}, {r}, {rings})");
        }
        for (s, (segments, stacks)) in [(0, (3, 1)), (1, (8, 3)), (2, (97, 10))] {
            let t = topo("sphere", &sphere(1.0, s));
            assert_eq!((t.loops.len(), t.chi), (0, 2));
            let t = topo("cylinder", &cylinder(2.0, 3.0, segments, stacks));
            assert_eq!((t.loops.len(), t.chi), (2, 0));
        }
    }

    #[test]
    fn part_fixture_sizes_and_heights() {
        let bbox = |m: &TriMesh| {
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for &p in &m.positions {
                lo = lo.min(p);
                hi = hi.max(p);
            }
            hi - lo
        };
        let close = |a: DVec3, b: DVec3| (a - b).abs().max_element() < 1e-9;
        assert!(close(bbox(&plate_3_holes()), DVec3::new(100.0, 80.0, 0.0)));
        let s = bbox(&saddle_2_holes());
        assert!(s.x == 80.0 && s.y == 80.0 && (10.0..15.0).contains(&s.z), "{s}");
        let s = bbox(&spherical_cap_hole());
        assert!((s.x - 80.0).abs() < 1e-9 && (15.0..15.5).contains(&s.z), "{s}");
        let f = freeform_4_holes();
        let s = bbox(&f);
        assert!(s.x == 120.0 && s.y == 90.0 && (12.0..18.0).contains(&s.z), "{s}");
        for t in &f.triangles {
            let n = face_normal(&f, t).normalize();
            assert!(n.z > 45f64.to_radians().cos(), "freeform slope over 45°");
        }
        assert!(close(bbox(&sliver_mesh()).with_z(0.0), DVec3::new(100.0, 60.0, 0.0)));
        assert!(close(bbox(&box_boss_pocket()), DVec3::new(100.0, 80.0, 28.0)));
    }

    #[test]
    fn box_is_closed_with_the_analytic_volume() {
        let m = box_boss_pocket();
        let t = topo("box", &m);
        assert!(t.loops.is_empty());
        assert_eq!(t.chi, 2);
        let vol: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let exact = 100.0 * 80.0 * 20.0 + 20.0 * 20.0 * 8.0 - 20.0 * 25.0 * 8.0;
        assert!(((vol - exact) / exact).abs() < 1e-9, "{vol} vs {exact}");
        // Top surface: boss top 400 mm², pocket floor 500 mm², base top 8000 − 900.
        let up_area: f64 =
            m.triangles.iter().map(|t| face_normal(&m, t)).filter(|n| n.z > 0.0).map(|n| n.length() / 2.0).sum();
        assert!((up_area - 8000.0).abs() < 1e-9, "{up_area}");
    }

    #[test]
    fn sliver_mesh_really_has_slivers() {
        let m = sliver_mesh();
        let aspects: Vec<f64> = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let l = (b - a).length().max((c - b).length()).max((a - c).length());
                l * l / (b - a).cross(c - a).length() // longest edge / its altitude
            })
            .collect();
        let max = aspects.iter().cloned().fold(0.0, f64::max);
        assert!(max > 1000.0, "max aspect {max}");
        assert!(aspects.iter().filter(|&&a| a > 20.0).count() > 500);
    }

    #[test]
    fn sphere_and_cylinder_lie_on_their_surfaces() {
        let s = sphere(25.0, 4);
        assert_eq!(s.triangles.len(), 5120);
        let t = topo("sphere", &s);
        assert_eq!((t.loops.len(), t.chi), (0, 2));
        assert!(s.positions.iter().all(|p| (p.length() - 25.0).abs() < 1e-12));
        for tri in &s.triangles {
            let c = tri.iter().map(|&i| s.positions[i as usize]).sum::<DVec3>();
            assert!(face_normal(&s, tri).dot(c) > 0.0, "sphere face inward");
        }
        let c = cylinder(10.0, 20.0, 96, 36);
        let t = topo("cylinder", &c);
        assert_eq!((t.loops.len(), t.chi), (2, 0));
        assert!(c.positions.iter().all(|p| (p.truncate().length() - 10.0).abs() < 1e-12));
        assert!(c.positions.iter().all(|p| (0.0..=20.0).contains(&p.z)));
        for tri in &c.triangles {
            let ctr = tri.iter().map(|&i| c.positions[i as usize]).sum::<DVec3>();
            assert!(face_normal(&c, tri).dot(ctr.with_z(0.0)) > 0.0, "cylinder face inward");
        }
    }

    #[test]
    fn fixtures_round_trip_through_the_stl_writers() {
        let m = plate_3_holes();
        let long = "x".repeat(100);
        for header in ["slitpath fixture", long.as_str()] {
            let b = crate::mesh::stl::write_binary(&m, header);
            assert_eq!(b.len(), 84 + 50 * m.triangles.len());
            let n = header.len().min(80);
            assert_eq!(&b[..n], &header.as_bytes()[..n]);
            assert!(b[n..80].iter().all(|&c| c == 0));
            assert_eq!(u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize, m.triangles.len());
            let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
            for (k, t) in m.triangles.iter().enumerate() {
                let base = 84 + 50 * k;
                let n = DVec3::new(f(base) as f64, f(base + 4) as f64, f(base + 8) as f64);
                assert!((n - face_normal(&m, t).normalize()).length() < 1e-6);
                for (c, &i) in t.iter().enumerate() {
                    let p = m.positions[i as usize];
                    let o = base + 12 + 12 * c;
                    assert_eq!([f(o), f(o + 4), f(o + 8)], [p.x as f32, p.y as f32, p.z as f32]);
                }
            }
        }
        let m = unit_disk(4);
        let s = crate::mesh::stl::write_ascii(&m, "disk");
        assert!(s.starts_with("solid disk\n") && s.trim_end().ends_with("endsolid disk"));
        assert_eq!(s.matches("facet normal").count(), m.triangles.len());
        assert_eq!(s.matches("endfacet").count(), m.triangles.len());
        // Vertex lines parse back to the exact f32 values, in order.
        let verts: Vec<f32> = s
            .lines()
            .filter_map(|l| l.trim().strip_prefix("vertex "))
            .flat_map(|l| l.split_whitespace().map(|x| x.parse::<f32>().unwrap()))
            .collect();
        let want: Vec<f32> = m
            .triangles
            .iter()
            .flat_map(|t| t.iter().map(|&i| m.positions[i as usize]))
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect();
        assert_eq!(verts, want);
    }

    #[test]
    fn generation_is_deterministic() {
        for &name in NAMES {
            let (a, b) = (by_name(name).unwrap(), by_name(name).unwrap());
            assert_eq!(crate::mesh::stl::write_binary(&a, name), crate::mesh::stl::write_binary(&b, name), "{name}");
            let bits =
                |m: &TriMesh| m.positions.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "{name}");
            assert_eq!(a.triangles, b.triangles, "{name}");
        }
    }

    #[test]
    fn print_fixture_stats() {
        for &name in NAMES {
            let m = by_name(name).unwrap();
            let (lo, hi) = m.positions.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p.z), hi.max(p.z)));
            eprintln!(
                "{name}: V {} F {} min angle(xy) {:.1} z [{lo:.2}, {hi:.2}]",
                m.positions.len(),
                m.triangles.len(),
                min_angle_xy(&m)
            );
        }
    }
}
