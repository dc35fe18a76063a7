//! Facet valleys: the samples over which the facets themselves keep more than a given height,
//! whatever the path.
//!
//! A ball touching the mesh at a point q of face g without cutting it has its centre at
//! q + R·n_g, moved out along n_g until no facet is nearer than R ([`FaceTree::clear_ball`]).
//! Where the path's balls may dip into the facets by some depth (smooth facets), so may these:
//! R less that depth in both places.
//! The union of all such balls is the most any path can cut (the part's opening by the ball);
//! what it leaves over a sample p along p's normal is p's *reach residual* r*(p). A sample is in
//! a facet valley when r*(p) exceeds the valley lift: no path leaves less there.
//!
//! The union is stood for by the balls at the contacts of a barycentric grid on every face near
//! a sample that may be in a valley, at most s = [`GRID_SPACING`]·R apart (between three of them
//! it leaves at most s²/6R more than the true union: 1.3 µm at R = 3 mm), and by the balls that
//! rest on two facets at once, found between the grid's contacts. So r* is overestimated by that
//! much at most. Two bounds keep the work to the samples where it matters: a path that does not
//! gouge is made of such balls, so r*(p) ≤ scallop(p); and p's own ball (touching at p, moved
//! clear) leaves its entry along the normal, so r*(p) ≤ that entry. Only samples where both
//! exceed the lift are measured against the balls (none on the analytic fixtures).

use super::{Capsule, Probe, SurfaceSample, SweptVolume};
use crate::mesh::nearest::{DippingBall, FaceTree};
use crate::mesh::Surface;
use glam::DVec3;
use std::collections::HashMap;

/// Contacts of the balls standing for the union are at most this many R apart.
pub const GRID_SPACING: f64 = 0.05;

/// Per sample, whether it lies in a facet valley: whether balls like `ball` touching the facets
/// round it leave more than `lift_mm` over it along its normal (see the module docs). `probes`
/// are the path's probes of `samples`; `faces`, the facet tree of `surface` when the caller has
/// one (built here only when some sample needs it). Preconditions: `0 ≤ lift_mm < R`,
/// `0 ≤ dip < R`.
pub(super) fn facet_valleys(
    surface: &Surface,
    faces: Option<&FaceTree>,
    samples: &[SurfaceSample],
    probes: &[Probe],
    ball: DippingBall,
    lift_mm: f64,
) -> Vec<bool> {
    let (r, keep) = (ball.radius_mm, ball.keep_mm());
    let mut valley = vec![false; samples.len()];
    // r*(p) ≤ scallop(p): the path's balls touch the part too (an uncovered sample may be in a
    // groove no ball enters).
    let deep: Vec<usize> = (0..samples.len()).filter(|&i| !probes[i].scallop.is_some_and(|t| t <= lift_mm)).collect();
    if deep.is_empty() {
        return valley;
    }
    let built;
    let faces = match faces {
        Some(faces) => faces,
        None => {
            built = FaceTree::new(&surface.positions, &surface.triangles);
            &built
        }
    };
    // r*(p) ≤ the entry into p's own ball: the rest are within reach.
    let own = crate::par::each(deep.len(), |k| {
        let s = &samples[deep[k]];
        let n = surface.face_normals[s.face as usize];
        let ball = faces.clear_ball(s.position + keep * n, n, keep, Some(s.face as usize), true);
        if ball.unresolved {
            return f64::INFINITY;
        }
        Capsule::new(ball.centre, ball.centre).entry(s.position, s.normal, r).unwrap_or(f64::INFINITY)
    });
    // (sample, the most r* can be: the bounds above, and R past which the grid's balls are not
    // gathered).
    let measured: Vec<(usize, f64)> = deep
        .iter()
        .zip(own)
        .map(|(&i, own)| (i, own.min(probes[i].scallop.unwrap_or(f64::INFINITY))))
        .filter(|&(_, bound)| bound > lift_mm)
        .map(|(i, bound)| (i, bound.min(r)))
        .collect();
    if measured.is_empty() {
        return valley;
    }
    let near = Near::new(measured.iter().map(|&(i, bound)| (samples[i].position, bound)), r);
    let balls = touching_balls(surface, faces, &near, ball);
    let residual: Vec<f64> = match SweptVolume::new(&balls, r) {
        Ok(volume) => crate::par::map(
            measured.len(),
            || volume.prober(),
            |prober, k| {
                let (i, bound) = measured[k];
                let s = &samples[i];
                prober.probe(s.position, s.normal, 0.0, bound).scallop.unwrap_or(bound)
            },
        ),
        // No ball touches the part near them.
        Err(_) => measured.iter().map(|&(_, bound)| bound).collect(),
    };
    for (&(i, _), rest) in measured.iter().zip(residual) {
        valley[i] = rest > lift_mm;
    }
    valley
}

/// The balls touching the facets of `surface` at the contacts of a barycentric grid on each face
/// ([`GRID_SPACING`]), kept where a point of `near` lies within their reach; and between two
/// neighbouring contacts of which one ball had to move and the other not, the ball where that
/// starts ([`BISECTIONS`]): it rests on two facets at once, and is often the one that leaves the
/// least over a valley's floor (the grid's next contact may be a spacing away from it, which
/// would overstate the residual there to first order). One pass of one centre each, in face
/// order.
fn touching_balls(surface: &Surface, faces: &FaceTree, near: &Near, ball: DippingBall) -> Vec<Vec<DVec3>> {
    let (r, keep) = (ball.radius_mm, ball.keep_mm());
    let per_face = crate::par::each(surface.triangles.len(), |g| {
        let [a, b, c] = surface.triangles[g].map(|v| surface.positions[v as usize]);
        let middle = (a + b + c) / 3.0;
        let size = a.distance(middle).max(b.distance(middle)).max(c.distance(middle));
        // Every sample a ball touching this face may reach.
        let around = near.around(middle, 2.0 * r + size);
        if around.is_empty() {
            return Vec::new();
        }
        let n = surface.face_normals[g];
        // The ball touching at q, moved clear: its centre and whether it moved; `None` when it
        // cannot reach a sample (its contact within 2R + b of p, and its centre, which moves out
        // along n from q + R·n, within R + b) or cannot clear the facets.
        let ball = |q: DVec3| {
            let u = q + keep * n;
            let may_reach = |&(p, b): &(DVec3, f64)| {
                let v = p - u;
                p.distance_squared(q) <= (2.0 * r + b) * (2.0 * r + b)
                    && (v - v.dot(n).max(0.0) * n).length_squared() <= (r + b) * (r + b)
            };
            if !around.iter().any(may_reach) {
                return None;
            }
            let ball = faces.clear_ball(u, n, keep, Some(g), true);
            (!ball.unresolved).then_some((ball.centre, ball.centre != u))
        };
        let reaches = |centre: DVec3| around.iter().any(|&(p, b)| p.distance_squared(centre) <= (r + b) * (r + b));
        let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
        let k = (longest / (GRID_SPACING * r)).ceil().max(1.0) as usize;
        let at = |i: usize, j: usize| a + (b - a) * (i as f64 / k as f64) + (c - a) * (j as f64 / k as f64);
        // Row i holds the contacts (i, 0..=k − i).
        let rows: Vec<Vec<Option<(DVec3, bool)>>> =
            (0..=k).map(|i| (0..=k - i).map(|j| ball(at(i, j))).collect()).collect();
        let mut out: Vec<Vec<DVec3>> =
            rows.iter().flatten().flatten().filter(|b| reaches(b.0)).map(|b| vec![b.0]).collect();
        // The ball where it starts moving, between a contact whose ball stays and one whose
        // ball moves.
        let resting = |mut still: DVec3, mut moved: DVec3| {
            let mut last = None;
            for _ in 0..BISECTIONS {
                let mid = still.lerp(moved, 0.5);
                match ball(mid) {
                    Some((centre, false)) => (still, last) = (mid, Some(centre)),
                    Some((_, true)) => moved = mid,
                    None => break,
                }
            }
            last
        };
        // Each contact (i, j) with its neighbours (i + 1, j), (i, j + 1) and (i + 1, j − 1).
        let pairs = (0..=k).flat_map(|i| (0..=k - i).map(move |j| (i, j))).flat_map(|(i, j)| {
            [(i + 1, j), (i, j + 1), (i + 1, j.wrapping_sub(1))]
                .into_iter()
                .filter(move |&(i2, j2)| i2 + j2 <= k && j2 <= k)
                .map(move |next| ((i, j), next))
        });
        for ((i, j), (i2, j2)) in pairs {
            let (Some(p), Some(q)) = (rows[i][j], rows[i2][j2]) else { continue };
            if p.1 == q.1 {
                continue;
            }
            let rest = if q.1 { resting(at(i, j), at(i2, j2)) } else { resting(at(i2, j2), at(i, j)) };
            if let Some(centre) = rest.filter(|&c| reaches(c)) {
                out.push(vec![centre]);
            }
        }
        out
    });
    per_face.into_iter().flatten().collect()
}

/// Halvings of the step between a contact whose ball stays and one whose ball moves.
const BISECTIONS: usize = 8;

/// Points p with a height b each (the most r*(p) can be), binned in cubes of 3R, for "is there one
/// with |q − p| ≤ d + b": a ball's contact within 2R + b of p, or its centre within R + b, may
/// cover p's normal below b; none farther can.
struct Near {
    r: f64,
    cell: f64,
    bins: HashMap<[i64; 3], Vec<(DVec3, f64)>>,
}

impl Near {
    /// `r`: the ball radius (every height is at most R).
    fn new(points: impl Iterator<Item = (DVec3, f64)>, r: f64) -> Self {
        let cell = 3.0 * r;
        let mut bins: HashMap<[i64; 3], Vec<(DVec3, f64)>> = HashMap::new();
        for (p, b) in points {
            bins.entry(Self::key(p, cell)).or_default().push((p, b));
        }
        Self { r, cell, bins }
    }

    fn key(p: DVec3, cell: f64) -> [i64; 3] {
        (p / cell).floor().as_i64vec3().to_array()
    }

    /// The points p within `d` + their height b of `q` (`d` up to 3R).
    fn around(&self, q: DVec3, d: f64) -> Vec<(DVec3, f64)> {
        // Heights are at most R.
        let (lo, hi) =
            (Self::key(q - DVec3::splat(d + self.r), self.cell), Self::key(q + DVec3::splat(d + self.r), self.cell));
        let mut out = Vec::new();
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let Some(bin) = self.bins.get(&[x, y, z]) else { continue };
                    out.extend(bin.iter().filter(|&&(p, b)| p.distance_squared(q) <= (d + b) * (d + b)));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::SplitMix64;

    #[test]
    fn near_finds_what_brute_force_finds() {
        let mut rng = SplitMix64(0x4ea4);
        let r = 0.7;
        let mut point = || DVec3::new(10.0 * rng.unit(), 10.0 * rng.unit(), 3.0 * rng.unit());
        let points: Vec<(DVec3, f64)> = (0..400).map(|_| (point(), 0.0)).collect();
        let points: Vec<(DVec3, f64)> =
            points.iter().enumerate().map(|(i, &(p, _))| (p, r * (i % 7) as f64 / 7.0)).collect();
        let near = Near::new(points.iter().copied(), r);
        let mut found = 0;
        for _ in 0..2000 {
            let q = point();
            for d in [0.0, r, 2.0 * r, 2.0 * r + 0.3] {
                let mut got = near.around(q, d);
                let mut want: Vec<(DVec3, f64)> =
                    points.iter().copied().filter(|&(p, b)| p.distance(q) <= d + b).collect();
                let key = |x: &(DVec3, f64)| (x.0.x, x.0.y, x.0.z);
                got.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
                want.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
                assert_eq!(got, want, "around {q} within {d}");
                found += got.len();
            }
        }
        assert!(found > 10_000, "{found}");
    }
}
