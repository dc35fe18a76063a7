//! The edge graph of a surface and its edges' Z₂ homology signatures (tree–cotree, module
//! docs of [`super`], step 1).

use super::NONE;
use crate::mesh::Surface;

/// The edge graph of a surface: edges (lo < hi) with their faces and per-vertex adjacency (CSR).
pub(super) struct Graph {
    /// `(lo, hi)`, sorted.
    pub(super) edges: Vec<(u32, u32)>,
    /// The face with the half-edge lo→hi and the one with hi→lo (`NONE` on the boundary).
    pub(super) faces: Vec<[u32; 2]>,
    /// What an edge costs a loop: its length, 0 along a rim.
    pub(super) length: Vec<f64>,
    pub(super) true_length: Vec<f64>,
    start: Vec<u32>,
    /// `(neighbour, edge)` per vertex.
    adjacent: Vec<(u32, u32)>,
}

impl Graph {
    pub(super) fn new(s: &Surface) -> Self {
        let nv = s.positions.len();
        let mut half: Vec<(u32, u32, u32)> = s
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| (0..3).map(move |k| (t[k], t[(k + 1) % 3], f as u32)))
            .collect();
        half.sort_unstable();
        let mut edges: Vec<(u32, u32)> = half.iter().map(|&(a, b, _)| (a.min(b), a.max(b))).collect();
        edges.sort_unstable();
        edges.dedup();
        let face_of =
            |a: u32, b: u32| -> u32 { half.binary_search_by(|h| (h.0, h.1).cmp(&(a, b))).map_or(NONE, |i| half[i].2) };
        let faces: Vec<[u32; 2]> = edges.iter().map(|&(a, b)| [face_of(a, b), face_of(b, a)]).collect();
        let true_length: Vec<f64> =
            edges.iter().map(|&(a, b)| s.positions[a as usize].distance(s.positions[b as usize])).collect();
        // Edges along the boundary cost nothing: a loop may follow a rim, which is not cut.
        let length = true_length.iter().zip(&faces).map(|(&l, f)| if f.contains(&NONE) { 0.0 } else { l }).collect();
        let (start, adjacent) = adjacency(nv, edges.iter().enumerate().map(|(e, &(a, b))| (a, b, e as u32)));
        Self { edges, faces, length, true_length, start, adjacent }
    }

    /// The number of vertices.
    pub(super) fn vertices(&self) -> usize {
        self.start.len() - 1
    }

    pub(super) fn neighbours(&self, v: u32) -> &[(u32, u32)] {
        &self.adjacent[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// Whether edge a–b lies on the boundary (one face).
    pub(super) fn on_boundary(&self, a: u32, b: u32) -> bool {
        self.edges.binary_search(&(a.min(b), a.max(b))).is_ok_and(|e| self.faces[e].contains(&NONE))
    }

    /// Every edge's Z₂ homology signature on the capped surface (module docs, step 1); `Err`
    /// with the number of leftover edges when it is not 2g.
    pub(super) fn signatures(&self, s: &Surface, genus: i64) -> Result<Vec<u128>, usize> {
        let (nv, nf, ne) = (s.positions.len(), s.triangles.len(), self.edges.len());
        // T: breadth-first spanning tree of the vertices.
        let mut in_tree = vec![false; ne];
        let mut seen = vec![false; nv];
        let mut queue = std::collections::VecDeque::from([0u32]);
        seen[0] = true;
        while let Some(v) = queue.pop_front() {
            for &(w, e) in self.neighbours(v) {
                if !seen[w as usize] {
                    seen[w as usize] = true;
                    in_tree[e as usize] = true;
                    queue.push_back(w);
                }
            }
        }
        // Dual nodes: faces, then one cap per boundary loop.
        let mut cap_of = vec![NONE; nv];
        for (i, l) in s.loops.iter().enumerate() {
            for &v in l {
                cap_of[v as usize] = (nf + i) as u32;
            }
        }
        let nodes = nf + s.loops.len();
        let dual = |e: usize| -> [u32; 2] {
            let [f, g] = self.faces[e];
            let cap = cap_of[self.edges[e].0 as usize];
            [if f == NONE { cap } else { f }, if g == NONE { cap } else { g }]
        };
        let (dual_start, dual_adjacent) = adjacency(
            nodes,
            (0..ne).filter(|&e| !in_tree[e]).map(|e| {
                let [m, n] = dual(e);
                (m, n, e as u32)
            }),
        );
        // C: breadth-first spanning tree of the dual through the edges not in T.
        let mut parent_edge = vec![NONE; nodes];
        let mut in_cotree = vec![false; ne];
        let mut reached = vec![false; nodes];
        let mut order = vec![0u32];
        reached[0] = true;
        let mut i = 0;
        while i < order.len() {
            let m = order[i];
            i += 1;
            for &(n, e) in &dual_adjacent[dual_start[m as usize] as usize..dual_start[m as usize + 1] as usize] {
                if !reached[n as usize] {
                    reached[n as usize] = true;
                    parent_edge[n as usize] = e;
                    in_cotree[e as usize] = true;
                    order.push(n);
                }
            }
        }
        let leftover: Vec<usize> = (0..ne).filter(|&e| !in_tree[e] && !in_cotree[e]).collect();
        if leftover.len() != 2 * genus as usize || order.len() != nodes || leftover.len() > 128 {
            return Err(leftover.len());
        }
        // δ_j's path in C: the edges whose subtree holds exactly one of e_j's two dual nodes.
        let mut signature = vec![0u128; ne];
        let mut mark = vec![0u128; nodes];
        for (j, &e) in leftover.iter().enumerate() {
            signature[e] = 1 << j;
            for n in dual(e) {
                mark[n as usize] ^= 1 << j;
            }
        }
        for &n in order.iter().skip(1).rev() {
            let e = parent_edge[n as usize] as usize;
            signature[e] = mark[n as usize];
            let [a, b] = dual(e);
            let parent = if a == n { b } else { a };
            mark[parent as usize] ^= mark[n as usize];
        }
        Ok(signature)
    }
}

/// The adjacency (CSR: `start`, then `(neighbour, link)` per node) of `nodes` nodes joined by
/// the links `(m, n, link)`, each listed at both its ends in the links' order.
fn adjacency(nodes: usize, links: impl Iterator<Item = (u32, u32, u32)> + Clone) -> (Vec<u32>, Vec<(u32, u32)>) {
    let mut start = vec![0u32; nodes + 1];
    for (m, n, _) in links.clone() {
        start[m as usize + 1] += 1;
        start[n as usize + 1] += 1;
    }
    for i in 0..nodes {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adjacent = vec![(0, 0); start[nodes] as usize];
    for (m, n, link) in links {
        adjacent[fill[m as usize] as usize] = (n, link);
        fill[m as usize] += 1;
        adjacent[fill[n as usize] as usize] = (m, link);
        fill[n as usize] += 1;
    }
    (start, adjacent)
}
