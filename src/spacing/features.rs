//! What the spacing tests densely, found once per map: the slits (holes) with their ends, the
//! corners of the loops that map onto circles, and the creases of a faceted surface, in the
//! log-polar strip (arg w, |w|) where the rings are circles.

use crate::mesh::Surface;
use crate::slitmap::{Mode, SlitMap};
use glam::DVec2;
use std::f64::consts::PI;

/// A slit as the spacing needs it: radius, angular range and how far its polygonal sides sag.
#[derive(Debug, Clone, Copy)]
pub(super) struct SlitBand {
    pub(super) radius: f64,
    pub(super) theta_start: f64,
    pub(super) extent: f64,
    /// Radii within this distance of `radius` are on the slit itself (rounding).
    pub(super) sag: f64,
}

impl SlitBand {
    pub(super) fn contains(&self, theta: f64) -> bool {
        crate::num::rem_tau(theta - self.theta_start) <= self.extent
    }
}

/// Meridians this close to a slit tip (radians of the slit domain) get the point-by-point test.
pub(super) const TIP_WINDOW: f64 = 0.05;

/// Extra meridians on either side of a slit tip, radians from it: the map squeezes the surface
/// round the end of a hole into a tiny arc, so they are dense near the tip (ratio √2). Out to
/// 0.032 rad only, freeform_4_holes kept 1.03 h at 0.037 rad past a tip.
pub(super) const TIP_OFFSETS: [f64; 18] = [
    0.0, 5e-4, 7e-4, 1e-3, 1.4e-3, 2e-3, 2.8e-3, 4e-3, 5.7e-3, 8e-3, 1.1e-2, 1.6e-2, 2.3e-2, 3.2e-2, 4.5e-2, 6.4e-2,
    9e-2, 0.128,
];

/// Extra meridians on either side of a corner of the outer loop, radians: the rings turn round a
/// corner within a few 1e-4 rad of the map (freeform_4_holes: 1.09 h at a corner with the finest
/// offset 5e-4).
pub(super) const CORNER_OFFSETS: [f64; 12] = [0.0, 1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 3.5e-4, 5e-4, 1e-3, 2e-3, 4e-3, 8e-3];

/// The offsets of `all` that matter for a band below ring `hi` near a feature (slit tip, corner)
/// at radius `rho`: at a distance δ in log-radius from it the map's detail round the feature is
/// about δ wide in angle, so offsets much finer than δ all test the same place and are dropped.
pub(super) fn offsets_at(all: &[f64], hi: f64, rho: f64) -> impl Iterator<Item = f64> + '_ {
    let delta = crate::num::ln(hi / rho).abs();
    all.iter().copied().filter(move |&d| d == 0.0 || d >= delta / 8.0)
}

/// A boundary vertex whose edges turn by more than this (in 3D) is a corner.
const CORNER_TURN: f64 = 25.0 * PI / 180.0;

/// arg w and |w| of the corners of the loops that map onto circles: the outer one, and in
/// annulus mode the inner one.
pub(super) fn corner_angles(surface: &Surface, map: &SlitMap) -> Vec<(f64, f64)> {
    let mut loops = vec![0];
    if let Mode::Annulus { hole, .. } = map.mode {
        loops.push(hole);
    }
    let mut out = Vec::new();
    for li in loops {
        let l = &surface.loops[li];
        for i in 0..l.len() {
            let p = |k: usize| surface.positions[l[k % l.len()] as usize];
            let (a, b) = (p(i + 1) - p(i), p(i + 2) - p(i + 1));
            let turn = crate::num::atan2(a.cross(b).length(), a.dot(b));
            if turn > CORNER_TURN {
                let w = map.w[l[(i + 1) % l.len()] as usize];
                out.push((crate::num::rem_tau(crate::num::atan2(w.y, w.x)), w.length()));
            }
        }
    }
    out
}

/// An interior edge whose faces turn by more than this (in 3D) is a crease.
const CREASE_TURN: f64 = 3.0 * PI / 180.0;

/// Radii of a band at which the rings' crossings with each crease are tested (fractions of the
/// expected band width below ring k).
pub(super) const CREASE_DEPTHS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// The creases of a faceted surface in the log-polar strip: interior edges whose two faces turn
/// by more than [`CREASE_TURN`]. The scallop changes abruptly across a crease (the facets meet
/// the ball there, not the interpolated normals), and wavy_mesh_with_hole's worst samples all
/// lay on its 10–14° creases, between meridians.
pub(super) fn creases(surface: &Surface, map: &SlitMap) -> Vec<(DVec2, DVec2)> {
    let cos_turn = crate::num::cos(CREASE_TURN);
    crate::mesh::geometry::interior_edges(&surface.triangles)
        .into_iter()
        .filter(|&(_, _, f, g)| surface.face_normals[f as usize].dot(surface.face_normals[g as usize]) < cos_turn)
        .map(|(a, b, _, _)| strip_edge(map, a, b))
        .collect()
}

/// The log-polar images (arg w, |w|) of the edge from vertex `a` to `b`, the second angle
/// within π of the first (the edge does not wrap round the strip).
pub(super) fn strip_edge(map: &SlitMap, a: u32, b: u32) -> (DVec2, DVec2) {
    let strip = |v: u32| {
        let w = map.w[v as usize];
        DVec2::new(crate::num::atan2(w.y, w.x), w.length())
    };
    let (a, mut b) = (strip(a), strip(b));
    b.x = a.x + crate::num::rem_tau(b.x - a.x + PI) - PI;
    (a, b)
}
