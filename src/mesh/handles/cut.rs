//! The cut along a loop (module docs of [`super`], step 4): vertices split into the sectors the
//! cut edges separate, the boundary loops traced afresh.

use super::graph::Graph;
use super::{HandleError, NONE};
use crate::mesh::Surface;
use glam::DVec3;

pub(super) fn cycle_length(positions: &[DVec3], cycle: &[u32]) -> f64 {
    (0..cycle.len())
        .map(|i| positions[cycle[i] as usize].distance(positions[cycle[(i + 1) % cycle.len()] as usize]))
        .sum()
}

/// `s` cut along the edges of `cycle` that are not on the boundary (module docs, step 4): round
/// every vertex of a cut edge, the faces are grouped into the sectors the cut edges (and the
/// boundary) separate; the sector with the lowest face keeps the vertex, each other one gets a
/// copy. The loops are then traced afresh.
pub(super) fn cut_along(s: &Surface, graph: &Graph, cycle: &[u32], handle: usize) -> Result<Cut, HandleError> {
    let n = cycle.len();
    let edge = |a: u32, b: u32| graph.edges.binary_search(&(a.min(b), a.max(b))).ok();
    let mut cut: Vec<(u32, u32)> = (0..n)
        .map(|i| (cycle[i], cycle[(i + 1) % n]))
        .filter(|&(a, b)| edge(a, b).is_some_and(|e| !graph.faces[e].contains(&NONE)))
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    cut.sort_unstable();
    let mut touched: Vec<u32> = cut.iter().flat_map(|&(a, b)| [a, b]).collect();
    touched.sort_unstable();
    touched.dedup();
    let (start, incident) = crate::mesh::topology::vertex_faces(s.positions.len(), &s.triangles);
    let mut out = s.clone();
    let mut origin = Vec::new();
    for &c in &touched {
        let fan = &incident[start[c as usize] as usize..start[c as usize + 1] as usize];
        let mut sector = vec![NONE; fan.len()];
        let mut sectors = 0;
        for seed in 0..fan.len() {
            if sector[seed] != NONE {
                continue;
            }
            sector[seed] = sectors;
            let mut stack = vec![seed];
            while let Some(i) = stack.pop() {
                let t = s.triangles[fan[i] as usize];
                for &w in t.iter().filter(|&&w| w != c) {
                    if cut.binary_search(&(c.min(w), c.max(w))).is_ok() {
                        continue;
                    }
                    let Some(e) = edge(c, w) else { continue };
                    for g in graph.faces[e] {
                        if let Some(j) = fan.iter().position(|&h| h == g) {
                            if sector[j] == NONE {
                                sector[j] = sectors;
                                stack.push(j);
                            }
                        }
                    }
                }
            }
            sectors += 1;
        }
        for extra in 1..sectors {
            let copy = out.positions.len() as u32;
            out.positions.push(s.positions[c as usize]);
            out.vertex_normals.push(s.vertex_normals[c as usize]);
            origin.push(c);
            for (i, &f) in fan.iter().enumerate().filter(|&(i, _)| sector[i] == extra) {
                debug_assert_eq!(sector[i], extra);
                for v in &mut out.triangles[f as usize] {
                    if *v == c {
                        *v = copy;
                    }
                }
            }
        }
    }
    out.loops = trace_loops(&out, s.loops[0][0]).ok_or(HandleError::Pinch { handle })?;
    Ok(Cut { surface: out, origin })
}

/// A surface cut along a loop: the vertices of `s` keep their ids, the copies are appended.
pub(super) struct Cut {
    pub(super) surface: Surface,
    /// The vertex of `s` each copy (from `s.positions.len()` on) was made from.
    pub(super) origin: Vec<u32>,
}

impl Cut {
    /// The vertex of the uncut surface a vertex of the cut one stands for.
    pub(super) fn original(&self, v: u32) -> u32 {
        let n = (self.surface.positions.len() - self.origin.len()) as u32;
        if v < n {
            v
        } else {
            self.origin[(v - n) as usize]
        }
    }
}

/// The boundary loops of `s`'s faces (half-edges without a twin, followed, each from its lowest
/// vertex, the surface on its left): the one through `outer` first, the others by decreasing
/// length. `None` if a vertex starts two of them (a pinch).
fn trace_loops(s: &Surface, outer: u32) -> Option<Vec<Vec<u32>>> {
    let nv = s.positions.len();
    let mut half: Vec<(u32, u32)> =
        s.triangles.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
    half.sort_unstable();
    let mut next = vec![NONE; nv];
    for &(a, b) in &half {
        if half.binary_search(&(b, a)).is_err() {
            if next[a as usize] != NONE {
                return None;
            }
            next[a as usize] = b;
        }
    }
    let mut seen = vec![false; nv];
    let mut loops = Vec::new();
    for v in 0..nv as u32 {
        if next[v as usize] == NONE || seen[v as usize] {
            continue;
        }
        let mut l = Vec::new();
        let mut u = v;
        while !seen[u as usize] {
            seen[u as usize] = true;
            l.push(u);
            u = next[u as usize];
        }
        loops.push(l);
    }
    let first = loops.iter().position(|l| l.contains(&outer))?;
    let outer_loop = loops.remove(first);
    let mut keyed: Vec<(f64, Vec<u32>)> = loops.into_iter().map(|l| (cycle_length(&s.positions, &l), l)).collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1[0].cmp(&b.1[0])));
    Some(std::iter::once(outer_loop).chain(keyed.into_iter().map(|(_, l)| l)).collect())
}
