//! Quality figures and validity check of a flattening.

use glam::{DVec2, DVec3};

use super::{AreaDistortion, FlattenError, FlattenQuality};

/// Quality of `uv` as a flattening of the 3D triangles: flipped count, quasi-conformal distortion
/// and area distortion (see [`FlattenQuality`]); the area distortion is measured after scaling
/// `uv` so both total areas are equal.
pub fn quality(positions: &[DVec3], triangles: &[[u32; 3]], loops: &[Vec<u32>], uv: &[DVec2]) -> FlattenQuality {
    let mut flipped = 0;
    let (mut a3_sum, mut a2_sum) = (0.0, 0.0);
    let mut per_face = Vec::with_capacity(triangles.len());
    let (mut qc_sum, mut qc_max) = (0.0, 1.0f64);
    for t in triangles {
        let (p0, p1, p2) = (positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
        let (q0, q1, q2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
        // 3D triangle in its own orthonormal frame: p0 → (0,0), p1 → (|e1|, 0), p2 → (x2, y2).
        let e1 = p1 - p0;
        let e2 = p2 - p0;
        let l1 = e1.length();
        let x2 = e1.dot(e2) / l1;
        let y2 = e1.cross(e2).length() / l1;
        let a3 = 0.5 * l1 * y2;
        let (d1, d2) = (q1 - q0, q2 - q0);
        let a2 = 0.5 * d1.perp_dot(d2);
        if !(a2 > 0.0) {
            flipped += 1;
        }
        // Jacobian J = [d1 d2] · inverse([[l1, x2], [0, y2]]).
        let c0 = d1 / l1;
        let c1 = (d2 - c0 * x2) / y2;
        let (ja, jb, jc, jd) = (c0.x, c1.x, c0.y, c1.y);
        let e = 0.5 * (ja + jd);
        let f = 0.5 * (ja - jd);
        let g = 0.5 * (jc + jb);
        let h = 0.5 * (jc - jb);
        let q = (e * e + h * h).sqrt();
        let r = (f * f + g * g).sqrt();
        let qc = if (q - r).abs() > 0.0 { (q + r) / (q - r).abs() } else { f64::INFINITY };
        qc_sum += a3 * qc;
        qc_max = qc_max.max(qc);
        a3_sum += a3;
        a2_sum += a2.abs();
        per_face.push((a3, a2.abs()));
    }
    // log(area2D/area3D) after the global scaling: subtract log(Σa2/Σa3).
    let shift = crate::num::ln(a2_sum / a3_sum);
    let mut ad = AreaDistortion { min: f64::INFINITY, max: f64::NEG_INFINITY, mean: 0.0, std: 0.0 };
    let logs: Vec<f64> = per_face.iter().map(|&(a3, a2)| crate::num::ln(a2 / a3) - shift).collect();
    for (&(a3, _), &l) in per_face.iter().zip(&logs) {
        ad.min = ad.min.min(l);
        ad.max = ad.max.max(l);
        ad.mean += a3 * l;
    }
    ad.mean /= a3_sum;
    ad.std = (per_face.iter().zip(&logs).map(|(&(a3, _), &l)| a3 * (l - ad.mean) * (l - ad.mean)).sum::<f64>()
        / a3_sum)
        .sqrt();
    FlattenQuality {
        flipped_triangles: flipped,
        qc_mean: qc_sum / a3_sum,
        qc_max,
        area_distortion: ad,
        boundary_valid: check_boundary(uv, loops).is_ok(),
    }
}

/// Verifies a flattening: no flipped (or zero-area) triangle, outer loop counter-clockwise, holes
/// clockwise, no loop self-intersecting or touching another, every hole inside the outer loop and
/// outside the other holes. Expected O(n) with a uniform grid over the boundary segments.
pub fn check(uv: &[DVec2], triangles: &[[u32; 3]], loops: &[Vec<u32>]) -> Result<(), FlattenError> {
    let count = triangles
        .iter()
        .filter(|t| {
            let (q0, q1, q2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            !((q1 - q0).perp_dot(q2 - q0) > 0.0)
        })
        .count();
    if count > 0 {
        return Err(FlattenError::FlippedTriangles { count });
    }
    check_boundary(uv, loops)
}

fn signed_area(uv: &[DVec2], lp: &[u32]) -> f64 {
    let mut s = 0.0;
    for i in 0..lp.len() {
        s += uv[lp[i] as usize].perp_dot(uv[lp[(i + 1) % lp.len()] as usize]);
    }
    0.5 * s
}

/// Even-odd point-in-polygon test.
fn inside(uv: &[DVec2], lp: &[u32], p: DVec2) -> bool {
    let mut c = false;
    for i in 0..lp.len() {
        let (a, b) = (uv[lp[i] as usize], uv[lp[(i + 1) % lp.len()] as usize]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            c = !c;
        }
    }
    c
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

fn on_segment(a: DVec2, b: DVec2, p: DVec2) -> bool {
    p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
}

/// Closed-segment intersection (touching counts).
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (d1, d2) = (orient(a, b, c), orient(a, b, d));
    let (d3, d4) = (orient(c, d, a), orient(c, d, b));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    (d1 == 0.0 && on_segment(a, b, c))
        || (d2 == 0.0 && on_segment(a, b, d))
        || (d3 == 0.0 && on_segment(c, d, a))
        || (d4 == 0.0 && on_segment(c, d, b))
}

fn check_boundary(uv: &[DVec2], loops: &[Vec<u32>]) -> Result<(), FlattenError> {
    for (li, lp) in loops.iter().enumerate() {
        let a = signed_area(uv, lp);
        if (li == 0 && !(a > 0.0)) || (li > 0 && !(a < 0.0)) {
            return Err(FlattenError::LoopOrientation { loop_index: li });
        }
    }
    // Segments (loop, index) in a uniform grid of about one cell per segment.
    let segs: Vec<(u32, u32)> =
        loops.iter().enumerate().flat_map(|(li, lp)| (0..lp.len() as u32).map(move |i| (li as u32, i))).collect();
    let ends = |s: (u32, u32)| {
        let lp = &loops[s.0 as usize];
        (uv[lp[s.1 as usize] as usize], uv[lp[(s.1 as usize + 1) % lp.len()] as usize])
    };
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for lp in loops {
        for &v in lp {
            lo = lo.min(uv[v as usize]);
            hi = hi.max(uv[v as usize]);
        }
    }
    let ext = (hi - lo).max(DVec2::splat(1e-300));
    let cell = (ext.x * ext.y / segs.len() as f64).sqrt().max(ext.x.max(ext.y) / 4096.0);
    let nx = ((ext.x / cell).ceil() as usize).clamp(1, 4096);
    let ny = ((ext.y / cell).ceil() as usize).clamp(1, 4096);
    let cell_of = |p: DVec2| {
        let c = ((p - lo) / ext * DVec2::new(nx as f64, ny as f64)).floor();
        ((c.x as usize).min(nx - 1), (c.y as usize).min(ny - 1))
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    for (si, &s) in segs.iter().enumerate() {
        let (a, b) = ends(s);
        let (c0, c1) = (cell_of(a.min(b)), cell_of(a.max(b)));
        for y in c0.1..=c1.1 {
            for x in c0.0..=c1.0 {
                grid[y * nx + x].push(si as u32);
            }
        }
    }
    let adjacent = |s: (u32, u32), t: (u32, u32)| {
        let len = loops[s.0 as usize].len() as u32;
        s.0 == t.0 && ((s.1 + 1) % len == t.1 || (t.1 + 1) % len == s.1 || s.1 == t.1)
    };
    for bucket in &grid {
        for (x, &i) in bucket.iter().enumerate() {
            for &j in &bucket[x + 1..] {
                let (s, t) = (segs[i as usize], segs[j as usize]);
                if adjacent(s, t) {
                    continue;
                }
                let (a, b) = ends(s);
                let (c, d) = ends(t);
                if segments_meet(a, b, c, d) {
                    return Err(FlattenError::OverlappingBoundary {
                        loop_a: s.0.min(t.0) as usize,
                        loop_b: s.0.max(t.0) as usize,
                    });
                }
            }
        }
    }
    // Without crossings, one vertex per hole decides the nesting.
    for h in 1..loops.len() {
        let p = uv[loops[h][0] as usize];
        if !inside(uv, &loops[0], p) {
            return Err(FlattenError::OverlappingBoundary { loop_a: 0, loop_b: h });
        }
        for (g, other) in loops.iter().enumerate().skip(1) {
            if g != h && inside(uv, other, p) {
                return Err(FlattenError::OverlappingBoundary { loop_a: g.min(h), loop_b: g.max(h) });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<Vec<u32>>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let mut lp = Vec::new();
        for i in 0..n {
            lp.push(id(i, 0));
        }
        for j in 0..n {
            lp.push(id(n, j));
        }
        for i in (1..=n).rev() {
            lp.push(id(i, n));
        }
        for j in (1..=n).rev() {
            lp.push(id(0, j));
        }
        (p, t, vec![lp])
    }

    #[test]
    fn identity_is_perfect() {
        let (p, t, l) = square(4);
        let uv: Vec<DVec2> = p.iter().map(|q| q.truncate()).collect();
        let q = quality(&p, &t, &l, &uv);
        assert_eq!(q.flipped_triangles, 0);
        assert!((q.qc_mean - 1.0).abs() < 1e-12 && (q.qc_max - 1.0).abs() < 1e-12);
        assert!(q.area_distortion.max.abs() < 1e-12 && q.area_distortion.std < 1e-12);
        assert!(q.boundary_valid);
        check(&uv, &t, &l).unwrap();
    }

    #[test]
    fn stretch_and_flip_are_detected() {
        let (p, t, l) = square(4);
        // x stretched by 2: qc = 2 everywhere, uniform area change (zero after global scaling).
        let uv: Vec<DVec2> = p.iter().map(|q| DVec2::new(2.0 * q.x, q.y)).collect();
        let q = quality(&p, &t, &l, &uv);
        assert!((q.qc_mean - 2.0).abs() < 1e-12 && (q.qc_max - 2.0).abs() < 1e-12);
        assert!(q.area_distortion.std < 1e-12);
        // Mirror: every triangle flipped, outer loop clockwise.
        let uv: Vec<DVec2> = p.iter().map(|q| DVec2::new(-q.x, q.y)).collect();
        assert!(matches!(check(&uv, &t, &l), Err(FlattenError::FlippedTriangles { count: 32 })));
        assert!(matches!(check_boundary(&uv, &l), Err(FlattenError::LoopOrientation { loop_index: 0 })));
    }

    #[test]
    fn boundary_crossing_is_detected() {
        let (p, _, l) = square(4);
        let mut uv: Vec<DVec2> = p.iter().map(|q| q.truncate()).collect();
        // Push a bottom-edge vertex through the top edge: the outer loop self-intersects.
        uv[2] = DVec2::new(2.0, 5.0);
        assert!(matches!(check_boundary(&uv, &l), Err(FlattenError::OverlappingBoundary { loop_a: 0, loop_b: 0 })));
    }
}
