//! Local untangling of the few image triangles a P1 slit map folds.
//!
//! Why: at a slit tip F has a critical point (F(z) ≈ F(z₀) + c(z − z₀)², the boundary folds back
//! along the arc), so image triangles within about one edge of the tip are as small as the P1
//! error of w and their orientation is decided by that error; sliver triangles elsewhere can fold
//! the same way. The exact map is an embedding, so any fold is a discretisation artefact at the
//! scale of a few triangles. This pass moves only the vertices of folded triangles (and their
//! neighbours, when that is not enough), each by the least amount that makes its own triangles
//! positive — interior vertices in the plane, boundary vertices along their circle (|w| = 1 on
//! Γ0, |w| = e^{c_i} on hole i), so every boundary invariant of the map is kept exactly.
//!
//! Per vertex: the best position is the Chebyshev centre of its star (the point farthest inside
//! every edge line of its link, a 3-variable LP solved by enumerating active triples); the vertex
//! then moves from where it is towards that centre just far enough that each of its triangles
//! has a height of at least a tenth of the centre's. Boundary vertices search their circle arc
//! the same way. Sweeps repeat over the folded region, grown by one ring when a sweep does not
//! finish, up to a fixed count; what remains is reported by [`super::SlitMap::flipped_faces`].
//! Deterministic: vertices are visited in index order.

use glam::DVec2;

/// How a vertex may move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Dof {
    Free,
    /// On the circle |w| = radius.
    Circle(f64),
}

const SWEEPS: usize = 24;
/// More folded faces than this (or an eighth of the faces, up to [`MAX_FOLDS`]) are not a local
/// artefact.
const MAX_LOCAL_FOLDS: usize = 64;
/// Crowding folds hundreds of faces; untangling them cost a pole 160 ms and fixed few
/// (inverted_triangles, an annulus pole: 286 → 258).
const MAX_FOLDS: usize = 128;
/// Stars with more link edges are left alone (the Chebyshev centre enumerates triples).
const MAX_LINES: usize = 40;

/// Untangles `w` in place; returns the number of faces still folded. Folds on more faces than
/// [`MAX_LOCAL_FOLDS`] (or an eighth of them, at most [`MAX_FOLDS`]) are not local (crowding: a
/// pole near one end of a long part squeezes the far end below the P1 resolution) and are left
/// as they are.
pub(crate) fn untangle(
    w: &mut [DVec2],
    triangles: &[[u32; 3]],
    dof: &[Dof],
    vertex_faces: &(Vec<u32>, Vec<u32>),
) -> usize {
    let folded = |w: &[DVec2]| -> Vec<usize> {
        (0..triangles.len()).filter(|&f| signed_area(w, &triangles[f]) <= 0.0).collect()
    };
    let mut bad = folded(w);
    if bad.len() > MAX_LOCAL_FOLDS.max(triangles.len() / 8).min(MAX_FOLDS) {
        return bad.len();
    }
    // Moving a vertex can fold a triangle of its star that was fine; the best state is kept.
    let mut best = (bad.len(), w.to_vec());
    let mut grow = 0;
    let mut stale = 0;
    for _ in 0..SWEEPS {
        if bad.is_empty() {
            break;
        }
        let mut verts: Vec<u32> = bad.iter().flat_map(|&f| triangles[f]).collect();
        verts.sort_unstable();
        verts.dedup();
        for _ in 0..grow {
            // Deduplicated every ring: without, three rings multiplied the list by ~18³.
            let ring: Vec<u32> = verts
                .iter()
                .flat_map(|&v| faces_of(vertex_faces, v).iter().flat_map(|&f| triangles[f as usize]))
                .collect();
            verts.extend(ring);
            verts.sort_unstable();
            verts.dedup();
        }
        for &v in &verts {
            relax(w, triangles, dof[v as usize], v, faces_of(vertex_faces, v));
        }
        let now = folded(w);
        if now.len() >= bad.len() {
            grow = (grow + 1).min(3);
        }
        bad = now;
        if bad.len() < best.0 {
            best = (bad.len(), w.to_vec());
            stale = 0;
        } else {
            stale += 1;
            if stale >= 6 {
                break;
            }
        }
    }
    if bad.len() > best.0 {
        w.copy_from_slice(&best.1);
    }
    best.0
}

fn faces_of(vf: &(Vec<u32>, Vec<u32>), v: u32) -> &[u32] {
    &vf.1[vf.0[v as usize] as usize..vf.0[v as usize + 1] as usize]
}

fn signed_area(w: &[DVec2], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| w[v as usize]);
    0.5 * (b - a).perp_dot(c - a)
}

/// The link edges (a, b) of v's faces (v, a, b), counter-clockwise, as unit left normals and
/// offsets: the height of v over edge a → b is `n · p − c`.
fn link_lines(w: &[DVec2], triangles: &[[u32; 3]], v: u32, faces: &[u32]) -> Vec<(DVec2, f64)> {
    faces
        .iter()
        .filter_map(|&f| {
            let t = triangles[f as usize];
            let k = t.iter().position(|&x| x == v)?;
            let (a, b) = (w[t[(k + 1) % 3] as usize], w[t[(k + 2) % 3] as usize]);
            let e = b - a;
            let len = e.length();
            (len > 0.0).then(|| {
                let n = e.perp() / len;
                (n, n.dot(a))
            })
        })
        .collect()
}

fn min_height(lines: &[(DVec2, f64)], p: DVec2) -> f64 {
    lines.iter().map(|&(n, c)| n.dot(p) - c).fold(f64::INFINITY, f64::min)
}

fn relax(w: &mut [DVec2], triangles: &[[u32; 3]], dof: Dof, v: u32, faces: &[u32]) {
    let lines = link_lines(w, triangles, v, faces);
    if lines.is_empty() {
        return;
    }
    let p0 = w[v as usize];
    match dof {
        Dof::Free => {
            if lines.len() > MAX_LINES {
                return;
            }
            let Some((c, t)) = chebyshev_centre(&lines) else { return };
            if t <= min_height(&lines, p0) {
                return;
            }
            // Heights are linear along p0 → c: the least step giving each line ≥ t/10.
            let target = if t > 0.0 { 0.1 * t } else { t };
            let mut s: f64 = 0.0;
            for &(n, off) in &lines {
                let (h0, h1) = (n.dot(p0) - off, n.dot(c) - off);
                if h0 < target && h1 > h0 {
                    s = s.max((target - h0) / (h1 - h0));
                }
            }
            w[v as usize] = p0 + s.min(1.0) * (c - p0);
        }
        Dof::Circle(r) => {
            let phi0 = crate::num::atan2(p0.y, p0.x);
            // Range: the angular reach of the star.
            let mut reach: f64 = 0.0;
            for &f in faces {
                for &u in &triangles[f as usize] {
                    let q = w[u as usize];
                    let d = crate::num::atan2(p0.perp_dot(q), p0.dot(q)).abs();
                    reach = reach.max(d);
                }
            }
            const STEPS: usize = 96;
            let at = |k: usize| {
                let s = (k as f64 / STEPS as f64) * 2.0 - 1.0;
                phi0 + s * reach
            };
            let point = |phi: f64| DVec2::new(crate::num::cos(phi), crate::num::sin(phi)) * r;
            let h0 = min_height(&lines, p0);
            let best = (0..=STEPS).map(|k| min_height(&lines, point(at(k)))).fold(f64::NEG_INFINITY, f64::max);
            if best <= h0 {
                return;
            }
            let target = if best > 0.0 { 0.1 * best } else { best };
            // The candidate nearest to where the vertex is that reaches the target.
            let mut order: Vec<usize> = (0..=STEPS).collect();
            order.sort_by_key(|&k| (k as i64 - (STEPS / 2) as i64).abs());
            if let Some(k) = order.into_iter().find(|&k| min_height(&lines, point(at(k))) >= target) {
                w[v as usize] = point(at(k));
            }
        }
    }
}

/// The point maximising the least height over `lines`, and that height (None when the LP is
/// unbounded or degenerate, e.g. fewer than three lines).
fn chebyshev_centre(lines: &[(DVec2, f64)]) -> Option<(DVec2, f64)> {
    let k = lines.len();
    let mut best: Option<(DVec2, f64)> = None;
    for i in 0..k {
        for j in i + 1..k {
            for l in j + 1..k {
                // n·p − t = c for the three lines.
                let rows = [lines[i], lines[j], lines[l]];
                let Some((p, _)) = solve3(rows) else { continue };
                let t = min_height(lines, p);
                if best.map_or(true, |(_, bt)| t > bt) {
                    best = Some((p, t));
                }
            }
        }
    }
    best
}

fn solve3(rows: [(DVec2, f64); 3]) -> Option<(DVec2, f64)> {
    // [nx ny −1] [px py t]ᵀ = c, by Cramer's rule.
    let m = rows.map(|(n, c)| [n.x, n.y, -1.0, c]);
    let det3 = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    let col = |r: [f64; 4], skip: usize, with: f64| {
        let mut v = [r[0], r[1], r[2]];
        v[skip] = with;
        v
    };
    let d = det3([m[0][0], m[0][1], m[0][2]], [m[1][0], m[1][1], m[1][2]], [m[2][0], m[2][1], m[2][2]]);
    if d.abs() < 1e-14 {
        return None;
    }
    let x = det3(col(m[0], 0, m[0][3]), col(m[1], 0, m[1][3]), col(m[2], 0, m[2][3])) / d;
    let y = det3(col(m[0], 1, m[0][3]), col(m[1], 1, m[1][3]), col(m[2], 1, m[2][3])) / d;
    let t = det3(col(m[0], 2, m[0][3]), col(m[1], 2, m[1][3]), col(m[2], 2, m[2][3])) / d;
    Some((DVec2::new(x, y), t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folded_fan_centre_is_moved_back_inside_its_star() {
        // A hexagonal star whose centre has been pushed outside across one edge.
        let mut w: Vec<DVec2> = (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::PI / 3.0;
                DVec2::new(a.cos(), a.sin())
            })
            .collect();
        w.push(DVec2::new(1.2, 0.3));
        let triangles: Vec<[u32; 3]> = (0..6).map(|k| [6, k, (k + 1) % 6]).collect();
        let vf = crate::mesh::topology::vertex_faces(7, &triangles);
        let mut dof = vec![Dof::Circle(1.0); 6];
        dof.push(Dof::Free);
        let left = untangle(&mut w, &triangles, &dof, &vf);
        assert_eq!(left, 0);
        assert!(triangles.iter().all(|t| signed_area(&w, t) > 0.0));
        for v in &w[..6] {
            assert!((v.length() - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn the_chebyshev_centre_of_a_square_is_its_centre() {
        let lines = [
            (DVec2::new(0.0, 1.0), 0.0),
            (DVec2::new(-1.0, 0.0), -2.0),
            (DVec2::new(0.0, -1.0), -2.0),
            (DVec2::new(1.0, 0.0), 0.0),
        ];
        let (c, t) = chebyshev_centre(&lines).unwrap();
        assert!((c - DVec2::new(1.0, 1.0)).length() < 1e-12);
        assert!((t - 1.0).abs() < 1e-12);
    }
}
