//! Shortest cycles of a homology class through a root (Dijkstra over the edge graph, rims free),
//! and where a handle is cut: module docs of [`super`], steps 2 and 3.

use super::cut::Cut;
use super::graph::Graph;
use super::{HandleOptions, NONE};
use crate::mesh::Surface;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A cycle through a search's root: its length (rims free), closing edge and signature.
#[derive(Clone, Copy, Debug)]
pub(super) struct Found {
    pub(super) length: f64,
    pub(super) edge: u32,
    pub(super) signature: u128,
}

/// Dijkstra searches over the edge graph (rims free), with scratch arrays reused across roots.
pub(super) struct Search<'a> {
    graph: &'a Graph,
    signature: &'a [u128],
    dist: Vec<f64>,
    parent: Vec<u32>,
    prefix: Vec<u128>,
    /// The search a vertex's entries belong to (0 = never), and whether it is settled.
    stamp: Vec<u32>,
    settled: Vec<bool>,
    round: u32,
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

/// Which cycle signatures a search accepts: any non-zero one, or one class exactly.
#[derive(Clone, Copy, Debug)]
pub(super) enum Class {
    NonZero,
    Exactly(u128),
}

impl Class {
    fn accepts(self, signature: u128) -> bool {
        match self {
            Class::NonZero => signature != 0,
            Class::Exactly(c) => signature == c,
        }
    }
}

impl<'a> Search<'a> {
    pub(super) fn new(graph: &'a Graph, signature: &'a [u128]) -> Self {
        let nv = graph.vertices();
        Self {
            graph,
            signature,
            dist: vec![0.0; nv],
            parent: vec![NONE; nv],
            prefix: vec![0; nv],
            stamp: vec![0; nv],
            settled: vec![false; nv],
            round: 0,
        }
    }

    /// The shortest non-separating cycle over the roots of the module docs, as a vertex cycle
    /// with its length (rims free) and signature; `None` when there is none.
    pub(super) fn shortest(&mut self, options: &HandleOptions) -> Option<(Vec<u32>, Found)> {
        let nv = self.graph.vertices();
        let exhaustive = nv < options.exhaustive_below_vertices || nv <= options.sampled_roots;
        let roots: Vec<u32> = if exhaustive {
            (0..nv as u32).collect()
        } else {
            let k = options.sampled_roots.max(1);
            (0..k).map(|i| (i * nv / k) as u32).collect()
        };
        let mut best: Option<(Found, u32)> = None;
        let improve = |search: &mut Self, x: u32, best: &mut Option<(Found, u32)>| {
            let limit = best.map_or(f64::INFINITY, |b| b.0.length);
            if let Some(found) = search.search_from(x, limit, Class::NonZero) {
                *best = Some((found, x));
            }
        };
        for &x in &roots {
            improve(self, x, &mut best);
        }
        let (found, root) = best?;
        let mut cycle = self.cycle_through(root, found.length, Class::NonZero)?;
        if !exhaustive {
            for _ in 0..options.shortening_rounds {
                let before = best.map(|b| b.0.length);
                for &x in &cycle.0 {
                    improve(self, x, &mut best);
                }
                if best.map(|b| b.0.length) == before {
                    break;
                }
                let (found, root) = best?;
                cycle = self.cycle_through(root, found.length, Class::NonZero)?;
            }
        }
        Some(cycle)
    }

    /// Dijkstra from `x`: the shortest cycle through `x` shorter than `limit` whose signature
    /// `class` accepts (a shortest-path tree edge closing it), if any. The search stops at half
    /// the best length so far: the cycle's two tree paths are each at most half its length
    /// (d(v) ≤ d(u) + w for an edge u–v), so a shorter cycle has both ends settled by then.
    pub(super) fn search_from(&mut self, x: u32, limit: f64, class: Class) -> Option<Found> {
        self.round += 1;
        let round = self.round;
        let mut best: Option<Found> = None;
        let mut bound = 0.5 * limit;
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
            if d >= bound {
                break;
            }
            self.settled[ui] = true;
            for &(v, e) in self.graph.neighbours(u) {
                let vi = v as usize;
                let w = self.graph.length[e as usize];
                if self.stamp[vi] == round && self.settled[vi] {
                    // Both ends settled: (u, v) closes a cycle through x unless it is a tree edge.
                    if self.parent[ui] != e && self.parent[vi] != e {
                        let signature = self.prefix[ui] ^ self.prefix[vi] ^ self.signature[e as usize];
                        let length = d + self.dist[vi] + w;
                        if class.accepts(signature) && length < best.map_or(limit, |b| b.length) {
                            best = Some(Found { length, edge: e, signature });
                            bound = 0.5 * length;
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
        best
    }

    /// The shortest cycle through `x` no longer than `length` whose signature `class` accepts,
    /// as a simple vertex cycle: the tree paths from the closing edge's ends to their last
    /// common vertex, and the edge.
    pub(super) fn cycle_through(&mut self, x: u32, length: f64, class: Class) -> Option<(Vec<u32>, Found)> {
        let found = self.search_from(x, length * (1.0 + 1e-9) + 1e-12, class)?;
        // The closing edge's ends were settled, so their tree paths are final.
        let (a, b) = self.graph.edges[found.edge as usize];
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
        Some((cycle, found))
    }

    /// The handle's loop placed in the middle of its neck (module docs, step 3): the vertices
    /// through which a loop of the shortest one's class is at most `ratio` times as long, grown
    /// from that loop; the one farthest (along the surface) from the vertices round the neck
    /// that fail, and the shortest loop of the class through it with its distance to them.
    /// `None` when every vertex qualifies (the neck has no end: the shortest loop is kept).
    pub(super) fn middle_of_neck(
        &mut self,
        shortest: &[u32],
        found: Found,
        ratio: f64,
    ) -> Option<(Vec<u32>, Found, f64)> {
        const UNTESTED: u8 = 0;
        const IN: u8 = 1;
        const OUT: u8 = 2;
        let limit = ratio * found.length * (1.0 + 1e-9) + 1e-12;
        let class = Class::Exactly(found.signature);
        let nv = self.graph.vertices();
        let mut state = vec![UNTESTED; nv];
        let mut stack = shortest.to_vec();
        for &v in shortest {
            state[v as usize] = IN;
        }
        while let Some(v) = stack.pop() {
            let graph = self.graph;
            for &(w, _) in graph.neighbours(v) {
                if state[w as usize] == UNTESTED {
                    let inside = self.search_from(w, limit, class).is_some();
                    state[w as usize] = if inside { IN } else { OUT };
                    if inside {
                        stack.push(w);
                    }
                }
            }
        }
        // Distances from the failing vertices into the neck, along the surface (true lengths:
        // the rims are free only for the loops). A path from them into the neck enters it
        // from one of them, so the search stays inside.
        let mut dist = vec![f64::INFINITY; nv];
        let mut heap = BinaryHeap::new();
        for v in (0..nv).filter(|&v| state[v] == OUT) {
            dist[v] = 0.0;
            heap.push(Reverse(Entry(0.0, v as u32)));
        }
        while let Some(Reverse(Entry(d, u))) = heap.pop() {
            if d > dist[u as usize] {
                continue;
            }
            for &(v, e) in self.graph.neighbours(u) {
                let nd = d + self.graph.true_length[e as usize];
                if state[v as usize] == IN && nd < dist[v as usize] {
                    dist[v as usize] = nd;
                    heap.push(Reverse(Entry(nd, v)));
                }
            }
        }
        let mut middle: Option<(f64, u32)> = None;
        for v in (0..nv).filter(|&v| state[v] == IN && dist[v].is_finite()) {
            if middle.map_or(true, |m| dist[v] > m.0) {
                middle = Some((dist[v], v as u32));
            }
        }
        let (depth, m) = middle?;
        let (cycle, placed) = self.cycle_through(m, limit, class)?;
        Some((cycle, placed, depth))
    }
}

/// The shortest loop crossing `cycle` once (the handle's other generator: module docs, step 3),
/// as a vertex cycle of `s` with its length (rims free) and signature, if one is shorter than
/// `limit`: on the surface cut along `cycle`, for each vertex of the cut, the shortest path from
/// its copy on the cut's left side to its copy on the right (rims free), closed in `s`.
/// `None` when there is none, or the shortest runs along rims only (the cut's two sides are on
/// one loop) or passes a vertex twice.
pub(super) fn crossing_loop(
    s: &Surface,
    graph: &Graph,
    signature: &[u128],
    cycle: &[u32],
    cut: &Cut,
    limit: f64,
) -> Option<(Vec<u32>, Found)> {
    let n = cycle.len();
    // (vertex, its copy on the left of the cut, on the right), per vertex of a cut edge.
    let mut sides: Vec<(u32, u32, u32)> = Vec::new();
    for i in 0..n {
        let (a, b) = (cycle[i], cycle[(i + 1) % n]);
        let Ok(e) = graph.edges.binary_search(&(a.min(b), a.max(b))) else { continue };
        let [lo_hi, hi_lo] = graph.faces[e];
        if lo_hi == NONE || hi_lo == NONE {
            continue;
        }
        // The face holding the half-edge a→b lies on its left (counter-clockwise faces).
        let (left, right) = if a < b { (lo_hi, hi_lo) } else { (hi_lo, lo_hi) };
        let copy = |f: u32, v: u32| {
            let k = s.triangles[f as usize].iter().position(|&w| w == v).expect("a corner of its face");
            cut.surface.triangles[f as usize][k]
        };
        for v in [a, b] {
            sides.push((v, copy(left, v), copy(right, v)));
        }
    }
    sides.sort_unstable();
    sides.dedup_by_key(|x| x.0);
    let cut_graph = Graph::new(&cut.surface);
    let nv = cut.surface.positions.len();
    let (mut dist, mut parent) = (vec![f64::INFINITY; nv], vec![NONE; nv]);
    let mut best: Option<f64> = None;
    let path_of = |from: u32, to: u32, limit: f64, dist: &mut Vec<f64>, parent: &mut Vec<u32>| {
        let mut touched = vec![from];
        dist[from as usize] = 0.0;
        let mut heap = BinaryHeap::from([Reverse(Entry(0.0, from))]);
        let mut reached = None;
        while let Some(Reverse(Entry(d, u))) = heap.pop() {
            if d > dist[u as usize] {
                continue;
            }
            if d >= limit {
                break;
            }
            if u == to {
                reached = Some(d);
                break;
            }
            for &(v, e) in cut_graph.neighbours(u) {
                let nd = d + cut_graph.length[e as usize];
                if nd < dist[v as usize] {
                    if dist[v as usize].is_infinite() {
                        touched.push(v);
                    }
                    dist[v as usize] = nd;
                    parent[v as usize] = u;
                    heap.push(Reverse(Entry(nd, v)));
                }
            }
        }
        let path = reached.map(|d| {
            let mut path = vec![to];
            while *path.last().expect("not empty") != from {
                path.push(parent[*path.last().expect("not empty") as usize]);
            }
            (d, path)
        });
        for v in touched {
            dist[v as usize] = f64::INFINITY;
        }
        path
    };
    let mut shortest = None;
    for &(_, l, r) in sides.iter().filter(|&&(_, l, r)| l != r) {
        if let Some((d, path)) = path_of(l, r, best.unwrap_or(limit), &mut dist, &mut parent) {
            best = Some(d);
            shortest = Some(path);
        }
    }
    let path = shortest?;
    if best? <= 0.0 {
        return None;
    }
    // The path runs from the right copy back to the left one: drop the repeated vertex.
    let mut out: Vec<u32> = path[..path.len() - 1].iter().map(|&v| cut.original(v)).collect();
    out.reverse();
    let mut sorted = out.clone();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() != out.len() {
        return None;
    }
    let (mut length, mut sig) = (0.0, 0u128);
    for i in 0..out.len() {
        let (a, b) = (out[i], out[(i + 1) % out.len()]);
        let e = graph.edges.binary_search(&(a.min(b), a.max(b))).ok()?;
        length += graph.length[e];
        sig ^= signature[e];
    }
    (sig != 0).then_some((out, Found { length, edge: NONE, signature: sig }))
}
