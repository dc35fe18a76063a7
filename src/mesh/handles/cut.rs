//! The cut along a loop (module docs of [`super`], step 4): vertices split into the sectors the
//! cut edges separate, the boundary loops traced afresh.

use super::graph::Graph;
use super::{HandleError, NONE};
use crate::mesh::{topology, Surface};

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
    let (start, incident) = topology::vertex_faces(s.positions.len(), &s.triangles);
    let mut out = s.clone();
    let mut origin = Vec::new();
    let mut fan = Vec::new();
    for &c in &touched {
        let faces = &incident[start[c as usize] as usize..start[c as usize + 1] as usize];
        // Across the edge c–w into its other face, unless the edge is cut.
        let across = |f: u32, _, w: u32| {
            let pair = (c.min(w), c.max(w));
            if cut.binary_search(&pair).is_ok() {
                return None;
            }
            let [g, h] = graph.faces[edge(c, w)?];
            Some(if g == f { h } else { g }).filter(|&g| g != NONE)
        };
        topology::split_fans(c, faces, &s.triangles, &mut out.triangles, &mut fan, across, || {
            out.positions.push(s.positions[c as usize]);
            out.vertex_normals.push(s.vertex_normals[c as usize]);
            origin.push(c);
            out.positions.len() as u32 - 1
        });
    }
    out.loops = trace_loops(&out, s.loops[0][0]).ok_or(HandleError::Pinch { handle })?;
    Ok(Cut { genus: out.genus(), surface: out, origin })
}

/// A surface cut along a loop: the vertices of `s` keep their ids, the copies are appended.
pub(super) struct Cut {
    pub(super) surface: Surface,
    /// Its genus (the check of the cut: module docs of [`super`], step 4).
    pub(super) genus: i64,
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
    let mut loops = topology::follow_loops(&next);
    let first = loops.iter().position(|l| l.contains(&outer))?;
    let outer_loop = loops.remove(first);
    let mut keyed: Vec<(f64, Vec<u32>)> =
        loops.into_iter().map(|l| (topology::loop_length(&s.positions, &l), l)).collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1[0].cmp(&b.1[0])));
    Some(std::iter::once(outer_loop).chain(keyed.into_iter().map(|(_, l)| l)).collect())
}
