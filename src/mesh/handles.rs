//! Handles: an open surface of genus g > 0 cut along g short non-separating loops into a genus-0
//! surface (a disk with holes) the planner can flatten (issue 34 item 4; seed 000 Fig. 7(i) plans
//! a genus-3 surface).
//!
//! # What it computes
//! One handle at a time, on the surface as cut so far:
//! 1. **A homology signature per edge** (tree–cotree, Eppstein 2003; Erickson & Whittlesey 2005):
//!    every boundary loop is capped by a virtual face, which makes a closed surface S̄ of the same
//!    genus g. A spanning tree T of the vertices, a spanning tree C of the faces and caps through
//!    the edges not in T, and the 2g leftover edges e_j give 2g dual loops δ_j = e_j* + (the path
//!    between e_j's faces in C) that span H₁(S̄; Z₂). An edge's signature is the bit set of the
//!    δ_j its dual crosses; a cycle's, the XOR of its edges'. The intersection form of a closed
//!    surface is non-degenerate, so a cycle is null-homologous in S̄ exactly when its signature
//!    is 0.
//! 2. **A short cycle with a non-zero signature.** Edges cost their length, edges along a rim
//!    nothing (a loop may follow a rim, which is not cut). From a root x, Dijkstra gives a
//!    shortest path tree; each non-tree edge (u, v) closes the cycle tree(x→u) + (u, v) +
//!    tree(v→x) with signature P(u) ⊕ P(v) ⊕ s(u, v) (P the XOR along the tree path), whose simple
//!    part (from the paths' last common vertex) has the same signature and is no longer.
//!    Erickson & Har-Peled (2004, Lemma 5.2): the shortest non-separating cycle through x is one
//!    of these, so the minimum over every root is the shortest one. A search stops at half the
//!    best length found so far (a shorter cycle through x lies within that distance of x).
//!    Pushed off the rims it follows, the cycle is a simple loop in the surface with the same
//!    class in S̄, non-zero, so it does not separate the surface.
//! 3. **The cut** along the cycle's edges that are not on a rim: round each of their vertices
//!    the faces fall into sectors between cut edges (and rims); one sector keeps the vertex,
//!    each other one gets a copy. A closed loop off every rim becomes two new boundary loops
//!    (χ unchanged, +2 loops); each arc of it from rim to rim raises χ by one and adds one loop
//!    or joins two. Either way the genus drops by exactly one: checked, with the loops traced
//!    afresh.
//!
//! Roots: every vertex below [`HandleOptions::exhaustive_below_vertices`] vertices (the shortest
//! cut, exactly); above, [`HandleOptions::sampled_roots`] evenly spaced ones, then the search is
//! repeated from every vertex of the best cycle until it stops shortening (no longer than the
//! best sampled cycle and the shortest through any of its own vertices; not guaranteed to be the
//! global shortest).
//!
//! Why rims are free: the loop round a bridge's foot crosses the bridge and runs along the hole's
//! rim; cut only where it crosses, the bridge is parted from the plate at one foot (as long as
//! the bridge is wide) instead of a slit ring round the hole one row of triangles from its rim,
//! which left a strip the planner could not cover.
//!
//! Why one handle at a time: the loops of different handles may share vertices; after a cut the
//! next loop is found on the cut surface (the cut's sides are rims: following them is free, and
//! cutting along them is impossible).
//!
//! # Preconditions and invariants
//! A [`Surface`] from [`super`]: one connected, consistently oriented component with at least one
//! boundary loop and no pinch vertex. The output keeps every vertex id, face and per-face field;
//! the copies of cut vertices are appended (with the original's position and vertex normal, so
//! the surface's geometry is unchanged); its loops are traced afresh, the one through the part's
//! outer loop's first vertex first, the others by decreasing length, the surface on their left.
//! Its genus is 0.
//!
//! # What the machinist gets
//! A cut has zero width: the planner treats its two sides as boundaries the spiral hugs and never
//! crosses, so the path runs along both sides of the cut line (the same 3D curve, once from
//! each side). Nothing is left uncut there: the balls of both sides cover it.

use super::Surface;
use glam::DVec3;
use serde::Serialize;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

const NONE: u32 = u32::MAX;

/// The largest genus handled: signatures are 128-bit sets of 2g dual loops.
pub const MAX_GENUS: i64 = 64;

/// Options of the handle cutting. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleOptions {
    /// Below this many vertices every vertex is a root (the shortest cut loop, exactly). Default 20 000: the searches stop at half the best length, so
    /// each explores only a geodesic disk round its root.
    pub exhaustive_below_vertices: usize,
    /// Roots, evenly spaced over the interior vertices, on larger surfaces. Default 96.
    pub sampled_roots: usize,
    /// Rounds of re-rooting at the best cycle's vertices on larger surfaces. Default 8.
    pub shortening_rounds: usize,
}

impl Default for HandleOptions {
    fn default() -> Self {
        Self { exhaustive_below_vertices: 20_000, sampled_roots: 96, shortening_rounds: 8 }
    }
}

/// Why a surface could not be cut into genus 0. Variants name the handle (counted from 0 in the
/// order cut) or the edge at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HandleError {
    #[error("the surface has genus {genus}: at most {max} handles can be cut")]
    TooManyHandles { genus: i64, max: i64 },
    #[error("handle {handle} of {genus}: no non-separating loop was found (the mesh is not one oriented manifold)")]
    NoLoop { handle: usize, genus: i64 },
    #[error("handle {handle}: the tree–cotree decomposition left {found} edges where genus {genus} needs {expected}: the mesh is not one oriented manifold")]
    Decomposition { handle: usize, genus: i64, expected: usize, found: usize },
    #[error("handle {handle}: after the cut a vertex starts two boundary edges (a pinch)")]
    Pinch { handle: usize },
    #[error(
        "handle {handle}: after the cut the genus is {genus} with {loops} boundary loops (expected genus {expected})"
    )]
    Check { handle: usize, genus: i64, expected: i64, loops: usize },
}

/// One cut, as the report lists it: the handle's loop, cut where it crosses the surface and
/// left as it is where it runs along a rim.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HandleCut {
    /// Length of what is cut (the loop's edges off the boundary), mm.
    pub length_mm: f64,
    /// Length of the whole loop, rim stretches included, mm.
    pub loop_length_mm: f64,
    /// The loop's edges that are cut, and those along a rim (not cut).
    pub cut_edges: usize,
    pub rim_edges: usize,
    /// The loop's vertex ids in the part's surface, in order (the copies on its other side are
    /// appended to the planned surface).
    pub vertex_ids: Vec<u32>,
    /// The loop as a closed 3D polyline (first point not repeated), mm.
    pub polyline_mm: Vec<[f64; 3]>,
}

/// The surface cut along one short loop per handle, and the cuts (empty when the genus is 0
/// already). A closed surface is returned as it is (the planner refuses it with its own error).
pub fn cut_handles(surface: &Surface, options: &HandleOptions) -> Result<(Surface, Vec<HandleCut>), HandleError> {
    let genus = surface.genus();
    if genus <= 0 || surface.loops.is_empty() {
        return Ok((surface.clone(), Vec::new()));
    }
    if genus > MAX_GENUS {
        return Err(HandleError::TooManyHandles { genus, max: MAX_GENUS });
    }
    let mut s = surface.clone();
    let mut cuts = Vec::new();
    for handle in 0..genus as usize {
        let g = s.genus();
        let graph = Graph::new(&s);
        let signature = graph.signatures(&s, g).map_err(|found| HandleError::Decomposition {
            handle,
            genus: g,
            expected: 2 * g as usize,
            found,
        })?;
        let mut search = Search::new(&graph, &signature);
        let cycle = search.shortest(options).ok_or(HandleError::NoLoop { handle, genus })?;
        let m = cycle.len();
        let (mut length_mm, mut loop_length_mm, mut cut_edges) = (0.0, 0.0, 0);
        for i in 0..m {
            let (a, b) = (cycle[i], cycle[(i + 1) % m]);
            let d = s.positions[a as usize].distance(s.positions[b as usize]);
            loop_length_mm += d;
            if !graph.on_boundary(a, b) {
                length_mm += d;
                cut_edges += 1;
            }
        }
        s = cut_along(&s, &graph, &cycle, handle)?;
        let genus_after = s.genus();
        if genus_after != g - 1 {
            return Err(HandleError::Check { handle, genus: genus_after, expected: g - 1, loops: s.loops.len() });
        }
        cuts.push(HandleCut {
            length_mm,
            loop_length_mm,
            cut_edges,
            rim_edges: m - cut_edges,
            polyline_mm: cycle.iter().map(|&v| s.positions[v as usize].to_array()).collect(),
            vertex_ids: cycle,
        });
    }
    Ok((s, cuts))
}

/// The edge graph of a surface: edges (lo < hi) with their faces, per-vertex adjacency (CSR)
/// and which vertices lie on the boundary.
struct Graph {
    /// `(lo, hi)`, sorted.
    edges: Vec<(u32, u32)>,
    /// The face with the half-edge lo→hi and the one with hi→lo (`NONE` on the boundary).
    faces: Vec<[u32; 2]>,
    length: Vec<f64>,
    start: Vec<u32>,
    /// `(neighbour, edge)` per vertex.
    adjacent: Vec<(u32, u32)>,
    boundary: Vec<bool>,
}

impl Graph {
    fn new(s: &Surface) -> Self {
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
        // Edges along the boundary cost nothing: a loop may follow a rim, which is not cut.
        let length = edges
            .iter()
            .zip(&faces)
            .map(
                |(&(a, b), f)| {
                    if f.contains(&NONE) {
                        0.0
                    } else {
                        s.positions[a as usize].distance(s.positions[b as usize])
                    }
                },
            )
            .collect();
        let mut boundary = vec![false; nv];
        let mut start = vec![0u32; nv + 1];
        for (e, &(a, b)) in edges.iter().enumerate() {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
            if faces[e].contains(&NONE) {
                boundary[a as usize] = true;
                boundary[b as usize] = true;
            }
        }
        for v in 0..nv {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut adjacent = vec![(0, 0); start[nv] as usize];
        for (e, &(a, b)) in edges.iter().enumerate() {
            adjacent[fill[a as usize] as usize] = (b, e as u32);
            fill[a as usize] += 1;
            adjacent[fill[b as usize] as usize] = (a, e as u32);
            fill[b as usize] += 1;
        }
        Self { edges, faces, length, start, adjacent, boundary }
    }

    fn neighbours(&self, v: u32) -> &[(u32, u32)] {
        &self.adjacent[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// Whether edge a–b lies on the boundary (one face).
    fn on_boundary(&self, a: u32, b: u32) -> bool {
        self.edges.binary_search(&(a.min(b), a.max(b))).is_ok_and(|e| self.faces[e].contains(&NONE))
    }

    /// Every edge's Z₂ homology signature on the capped surface (module docs, step 1); `Err`
    /// with the number of leftover edges when it is not 2g.
    fn signatures(&self, s: &Surface, genus: i64) -> Result<Vec<u128>, usize> {
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
        let mut dual_start = vec![0u32; nodes + 1];
        for e in (0..ne).filter(|&e| !in_tree[e]) {
            for n in dual(e) {
                dual_start[n as usize + 1] += 1;
            }
        }
        for n in 0..nodes {
            dual_start[n + 1] += dual_start[n];
        }
        let mut fill = dual_start.clone();
        let mut dual_adjacent = vec![(0u32, 0u32); dual_start[nodes] as usize];
        for e in (0..ne).filter(|&e| !in_tree[e]) {
            let [m, n] = dual(e);
            dual_adjacent[fill[m as usize] as usize] = (n, e as u32);
            fill[m as usize] += 1;
            dual_adjacent[fill[n as usize] as usize] = (m, e as u32);
            fill[n as usize] += 1;
        }
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

/// Dijkstra searches over the interior edges, with scratch arrays reused across roots.
struct Search<'a> {
    graph: &'a Graph,
    signature: &'a [u128],
    dist: Vec<f64>,
    parent: Vec<u32>,
    prefix: Vec<u128>,
    /// The root a vertex's entries belong to (+1; 0 = never), and whether it is settled.
    stamp: Vec<u32>,
    settled: Vec<bool>,
    round: u32,
    /// Best cycle so far: length, root, closing edge.
    best: Option<(f64, u32, u32)>,
}

/// A heap entry: distance (mm), vertex; ordered by distance, then vertex (deterministic).
#[derive(PartialEq)]
struct Entry(f64, u32);
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

impl<'a> Search<'a> {
    fn new(graph: &'a Graph, signature: &'a [u128]) -> Self {
        let nv = graph.boundary.len();
        Self {
            graph,
            signature,
            dist: vec![0.0; nv],
            parent: vec![NONE; nv],
            prefix: vec![0; nv],
            stamp: vec![0; nv],
            settled: vec![false; nv],
            round: 0,
            best: None,
        }
    }

    /// The shortest non-separating interior cycle over the roots of the module docs, as a
    /// vertex cycle; `None` when there is none.
    fn shortest(&mut self, options: &HandleOptions) -> Option<Vec<u32>> {
        let nv = self.graph.boundary.len();
        let exhaustive = nv < options.exhaustive_below_vertices || nv <= options.sampled_roots;
        let roots: Vec<u32> = if exhaustive {
            (0..nv as u32).collect()
        } else {
            let k = options.sampled_roots.max(1);
            (0..k).map(|i| (i * nv / k) as u32).collect()
        };
        for &x in &roots {
            self.search_from(x);
        }
        let mut cycle = self.cycle()?;
        if !exhaustive {
            for _ in 0..options.shortening_rounds {
                let before = self.best.map(|b| b.0);
                for &x in &cycle.clone() {
                    self.search_from(x);
                }
                if self.best.map(|b| b.0) == before {
                    break;
                }
                cycle = self.cycle()?;
            }
        }
        Some(cycle)
    }

    /// Dijkstra from `x`, stopped at half the best length; records a shorter non-separating
    /// cycle through `x` when there is one.
    fn search_from(&mut self, x: u32) {
        self.round += 1;
        let round = self.round;
        let bound = |best: Option<(f64, u32, u32)>| best.map_or(f64::INFINITY, |b| 0.5 * b.0);
        self.stamp[x as usize] = round;
        self.dist[x as usize] = 0.0;
        self.parent[x as usize] = NONE;
        self.prefix[x as usize] = 0;
        self.settled[x as usize] = false;
        let mut heap = BinaryHeap::from([Reverse(Entry(0.0, x))]);
        while let Some(Reverse(Entry(d, u))) = heap.pop() {
            let ui = u as usize;
            if self.settled[ui] || d > self.dist[ui] {
                continue;
            }
            if d >= bound(self.best) {
                break;
            }
            self.settled[ui] = true;
            for &(v, e) in self.graph.neighbours(u) {
                let vi = v as usize;
                let w = self.graph.length[e as usize];
                if self.stamp[vi] == round && self.settled[vi] {
                    // Both ends settled: (u, v) closes a cycle through x unless it is a tree edge.
                    if self.parent[ui] != e && self.parent[vi] != e {
                        let sig = self.prefix[ui] ^ self.prefix[vi] ^ self.signature[e as usize];
                        let length = d + self.dist[vi] + w;
                        if sig != 0 && self.best.map_or(true, |b| length < b.0) {
                            self.best = Some((length, x, e));
                        }
                    }
                    continue;
                }
                let nd = d + w;
                if self.stamp[vi] != round || nd < self.dist[vi] {
                    self.stamp[vi] = round;
                    self.settled[vi] = false;
                    self.dist[vi] = nd;
                    self.parent[vi] = e;
                    self.prefix[vi] = self.prefix[ui] ^ self.signature[e as usize];
                    heap.push(Reverse(Entry(nd, v)));
                }
            }
        }
    }

    /// The simple cycle of the best (root, edge): the tree paths from the edge's ends to their
    /// last common vertex, and the edge.
    fn cycle(&mut self) -> Option<Vec<u32>> {
        let (length, x, e) = self.best?;
        // Re-run from the root with the bound just above the cycle's half length, to have its
        // tree (the recorded best is kept: no shorter cycle through x exists).
        let kept = self.best;
        self.best = Some((length * (1.0 + 1e-9) + 1e-12, x, e));
        self.search_from(x);
        self.best = kept;
        let (a, b) = self.graph.edges[e as usize];
        let up = |mut v: u32| {
            let mut path = vec![v];
            while self.parent[v as usize] != NONE {
                let (p, q) = self.graph.edges[self.parent[v as usize] as usize];
                v = if p == v { q } else { p };
                path.push(v);
            }
            path
        };
        let (pa, pb) = (up(a), up(b));
        // Both paths end at x; drop their common tail but its first vertex (the meeting point).
        let common = pa.iter().rev().zip(pb.iter().rev()).take_while(|(p, q)| p == q).count();
        let mut cycle: Vec<u32> = pa[..pa.len() - common + 1].iter().rev().copied().collect();
        cycle.extend_from_slice(&pb[..pb.len() - common]);
        Some(cycle)
    }
}

fn cycle_length(positions: &[DVec3], cycle: &[u32]) -> f64 {
    (0..cycle.len())
        .map(|i| positions[cycle[i] as usize].distance(positions[cycle[(i + 1) % cycle.len()] as usize]))
        .sum()
}

/// `s` cut along the edges of `cycle` that are not on the boundary (module docs, step 3): round
/// every vertex of a cut edge, the faces are grouped into the sectors the cut edges (and the
/// boundary) separate; the sector with the lowest face keeps the vertex, each other one gets a
/// copy. The loops are then traced afresh.
fn cut_along(s: &Surface, graph: &Graph, cycle: &[u32], handle: usize) -> Result<Surface, HandleError> {
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
    let (start, incident) = super::topology::vertex_faces(s.positions.len(), &s.triangles);
    let mut out = s.clone();
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
    Ok(out)
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
