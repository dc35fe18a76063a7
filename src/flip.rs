//! Lawson's edge flipping, shared by the slit map's Delaunay triangulation of the flattened
//! domain (`slitmap::delaunay`) and the coplanar flips of `mesh::refine`.
//!
//! Each interior edge a–b (two faces, c on its left and d on its right) is flipped to c–d while
//! the caller's predicate says so; the faces touching a flipped edge are queued again. Boundary
//! edges (one face) are never flipped. Face slots are kept: the face in slot f1 = (a, b, c)
//! becomes (c, a, d) and f2 = (b, a, d) becomes (d, b, c), so per-face data of the two slots stays
//! with faces covering the same quadrilateral. Deterministic: edges are visited in a fixed order,
//! and at most `50·faces + 1000` flips are made whatever the predicate does.

/// Flips interior edges of `triangles` while `needs_flip(a, b, c, d)` holds for edge a → b with c
/// opposite in the face on its left and d in the face on its right. Returns the triangles and
/// the number of flips.
pub(crate) fn lawson(
    triangles: &[[u32; 3]],
    mut needs_flip: impl FnMut(u32, u32, u32, u32) -> bool,
) -> (Vec<[u32; 3]>, usize) {
    let mut tris = triangles.to_vec();
    // Directed half-edge a → b ↦ face.
    let mut half: crate::hash::EdgeMap<usize> = crate::hash::edge_map(3 * tris.len());
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            half.insert((t[k], t[(k + 1) % 3]), f);
        }
    }
    let mut stack: Vec<(u32, u32)> = Vec::with_capacity(3 * tris.len() / 2);
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a < b && half.contains_key(&(b, a)) {
                stack.push((a, b));
            }
        }
    }
    stack.reverse();
    let mut flips = 0;
    let budget = 50 * tris.len() + 1000;
    while let Some((a, b)) = stack.pop() {
        let (Some(&f1), Some(&f2)) = (half.get(&(a, b)), half.get(&(b, a))) else { continue };
        let c = third(&tris[f1], a, b);
        let d = third(&tris[f2], b, a);
        // c == d: a doubled pair of faces, not a quadrilateral. c–d already an edge: flipping
        // would make it non-manifold.
        if flips >= budget || c == d || half.contains_key(&(c, d)) || half.contains_key(&(d, c)) {
            continue;
        }
        if !needs_flip(a, b, c, d) {
            continue;
        }
        half.remove(&(a, b));
        half.remove(&(b, a));
        tris[f1] = [c, a, d];
        tris[f2] = [d, b, c];
        half.insert((a, d), f1);
        half.insert((d, c), f1);
        half.insert((b, c), f2);
        half.insert((c, d), f2);
        flips += 1;
        for (u, v) in [(a, c), (c, b), (b, d), (d, a)] {
            if half.contains_key(&(u, v)) && half.contains_key(&(v, u)) {
                stack.push((u.min(v), u.max(v)));
            }
        }
    }
    (tris, flips)
}

/// The corner of `t` that is neither a nor b.
pub(crate) fn third(t: &[u32; 3], a: u32, b: u32) -> u32 {
    t.iter().copied().find(|&v| v != a && v != b).unwrap_or(t[0])
}
