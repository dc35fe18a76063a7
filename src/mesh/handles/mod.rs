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
//! 3. **Where the handle is cut.** A cut across a handle leaves overhangs: a bridge cut across
//!    becomes two tongues, each hanging from one foot, and the conformal map shrinks a tongue of
//!    length L and width w by about e^(−πL/w) (the rings never reach the free end of a long one:
//!    cut at one foot, the 7 mm wide (as meshed), 35 mm long bridge of `plate_with_handle` left
//!    1.5 % of the part uncut, max scallop ≈ R; cut in its middle, 2.6 h at a tongue's tip). So
//!    the loop is placed, and its class chosen, to keep the overhangs short and wide:
//!    - *The neck of a class c*: the vertices through which the shortest cycle of signature
//!      exactly c (as in step 2, tree paths and one edge) is at most
//!      [`HandleOptions::neck_ratio`] times the class's shortest (1.5: a loop across a bridge
//!      qualifies anywhere along it, not on the plate round its feet), grown from the shortest
//!      loop. Its *depth* at a vertex is the distance along the surface (true lengths) to the
//!      nearest vertex next to the neck that fails. The loop through the deepest vertex is cut:
//!      it splits a bridge in the middle, into two tongues of half its length; its depth is
//!      about the length of the overhangs it leaves. A neck without an end (a torus' meridians
//!      all qualify) keeps the shortest loop.
//!    - *The other generator*: on the surface cut along that loop, the shortest path (rims
//!      free) from a cut vertex's copy on one side to its copy on the other closes, uncut, into
//!      a loop crossing the first one once: for a bridge, across the plate between its feet
//!      (the bridge itself runs along rims). Cutting it leaves the bridge whole, joined at both
//!      feet, and the plate between the feet as overhangs as long as the bridge's clearance
//!      and as wide as the span. Placed the same way in its own neck, it is cut instead when it
//!      is at most [`HandleOptions::crossing_ratio`] times the shortest loop and its overhangs
//!      are less elongated: depth / cut length (rims free), lower.
//!
//!    Both are non-zero classes of the same handle, so either cut lowers the genus by one; were
//!    a placed loop's cut to fail the check below, the shortest loop is cut instead.
//! 4. **The cut** along the cycle's edges that are not on a rim: round each of their vertices
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
//! Why rims are free: the loop round a bridge crosses it and runs back along the holes' rims; cut
//! only where it crosses, the bridge is parted across its width instead of a slit ring round a
//! hole one row of triangles from its rim, which left a strip the planner could not cover.
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

mod cut;
mod graph;
mod search;

use super::Surface;
use cut::cut_along;
use graph::Graph;
use search::{crossing_loop, Found, Search};
use serde::Serialize;

const NONE: u32 = u32::MAX;

/// The largest genus handled: signatures are 128-bit sets of 2g dual loops.
pub const MAX_GENUS: i64 = 64;

/// Options of the handle cutting. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleOptions {
    /// Below this many vertices every vertex is a root (the shortest cut loop, exactly). Default
    /// 20 000: the searches stop at half the best length, so each explores only a geodesic disk
    /// round its root.
    pub exhaustive_below_vertices: usize,
    /// Roots, evenly spaced over the interior vertices, on larger surfaces. Default 96.
    pub sampled_roots: usize,
    /// Rounds of re-rooting at the best cycle's vertices on larger surfaces. Default 8.
    pub shortening_rounds: usize,
    /// Where a handle is cut (module docs, step 3): loops of the shortest one's class at most
    /// this many times as long as it (rims free) make the handle's neck, cut in its middle.
    /// `1` cuts the shortest loop. Default 1.5.
    pub neck_ratio: f64,
    /// The handle's other generator (a loop crossing the shortest one once) is cut instead when
    /// it is at most this many times as long (rims free) and leaves less elongated overhangs
    /// (module docs, step 3). Default 8; 0 never cuts it.
    pub crossing_ratio: f64,
}

impl Default for HandleOptions {
    fn default() -> Self {
        Self {
            exhaustive_below_vertices: 20_000,
            sampled_roots: 96,
            shortening_rounds: 8,
            neck_ratio: 1.5,
            crossing_ratio: 8.0,
        }
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
    #[error("the handles' {name} ratio is {ratio}: it must be a finite number ≥ {min}")]
    Ratio { name: &'static str, ratio: f64, min: f64 },
}

/// One cut, as the report lists it: the handle's loop, cut where it crosses the surface and
/// left as it is where it runs along a rim.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HandleCut {
    /// Length of what is cut (the loop's edges off the boundary), mm.
    pub length_mm: f64,
    /// What the handle's shortest loop cuts, mm: the placed loop cuts at most
    /// [`HandleOptions::neck_ratio`] times as much.
    pub shortest_mm: f64,
    /// Length of the whole loop, rim stretches included, mm.
    pub loop_length_mm: f64,
    /// Distance along the surface from the cut to the nearer end of the handle's neck (where
    /// the loops get longer than the ratio allows), mm: about the length of the shorter of the
    /// two overhangs the cut leaves. 0 when the shortest loop is cut (the neck has no end).
    pub depth_mm: f64,
    /// Whether the cut is the handle's other generator (it crosses the handle's shortest loop
    /// once: across the plate between a bridge's feet rather than across the bridge).
    pub crossing: bool,
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
/// By value: every load passes through here, and a surface of genus 0 is returned uncopied.
pub fn cut_handles(surface: Surface, options: &HandleOptions) -> Result<(Surface, Vec<HandleCut>), HandleError> {
    let genus = surface.genus();
    if genus <= 0 || surface.loops.is_empty() {
        return Ok((surface, Vec::new()));
    }
    if genus > MAX_GENUS {
        return Err(HandleError::TooManyHandles { genus, max: MAX_GENUS });
    }
    if !(options.neck_ratio >= 1.0 && options.neck_ratio.is_finite()) {
        return Err(HandleError::Ratio { name: "neck", ratio: options.neck_ratio, min: 1.0 });
    }
    if !(options.crossing_ratio >= 0.0 && options.crossing_ratio.is_finite()) {
        return Err(HandleError::Ratio { name: "crossing", ratio: options.crossing_ratio, min: 0.0 });
    }
    let mut s = surface;
    let mut cuts = Vec::new();
    for handle in 0..genus as usize {
        // Each cut below is checked to lower the genus by exactly one.
        let g = genus - handle as i64;
        let graph = Graph::new(&s);
        let signature = graph.signatures(&s, g).map_err(|found| HandleError::Decomposition {
            handle,
            genus: g,
            expected: 2 * g as usize,
            found,
        })?;
        let mut search = Search::new(&graph, &signature);
        let (shortest, found) = search.shortest(options).ok_or(HandleError::NoLoop { handle, genus })?;
        let mut placed = place(&mut search, shortest.clone(), found, options.neck_ratio);
        let mut cut = cut_along(&s, &graph, &placed.cycle, handle);
        if !cut.as_ref().is_ok_and(|c| c.genus == g - 1) && placed.cycle != shortest {
            // The placed loop is of the shortest one's class, so cutting it should not fail
            // where cutting that one does not; were it to, the shortest one is cut instead.
            placed = Candidate { cycle: shortest, found, depth_mm: 0.0, crossing: false };
            cut = cut_along(&s, &graph, &placed.cycle, handle);
        }
        let mut cut = cut?;
        // The handle's other generator, when it leaves less elongated overhangs.
        let limit = options.crossing_ratio * found.length;
        if let Some((cycle, other)) = crossing_loop(&s, &graph, &signature, &placed.cycle, &cut, limit) {
            let mut other = place(&mut search, cycle, other, options.neck_ratio);
            other.crossing = true;
            if other.elongation() < placed.elongation() {
                if let Ok(c) = cut_along(&s, &graph, &other.cycle, handle) {
                    if c.genus == g - 1 {
                        (placed, cut) = (other, c);
                    }
                }
            }
        }
        let Candidate { cycle, depth_mm, crossing, .. } = placed;
        let (genus_after, cut) = (cut.genus, cut.surface);
        if genus_after != g - 1 {
            return Err(HandleError::Check { handle, genus: genus_after, expected: g - 1, loops: cut.loops.len() });
        }
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
        cuts.push(HandleCut {
            length_mm,
            shortest_mm: found.length,
            loop_length_mm,
            depth_mm,
            crossing,
            cut_edges,
            rim_edges: m - cut_edges,
            polyline_mm: cycle.iter().map(|&v| s.positions[v as usize].to_array()).collect(),
            vertex_ids: cycle,
        });
        s = cut;
    }
    Ok((s, cuts))
}

/// A loop a handle may be cut along.
struct Candidate {
    cycle: Vec<u32>,
    found: Found,
    /// Distance from the loop to the nearer end of its neck, mm (0: the neck has no end).
    depth_mm: f64,
    /// Whether it is the handle's other generator (it crosses the shortest loop's class once).
    crossing: bool,
}

impl Candidate {
    /// How elongated the overhangs the cut leaves are: about their length over their width
    /// (the conformal map shrinks an overhang by about e^(−π·this)).
    fn elongation(&self) -> f64 {
        if self.found.length > 0.0 {
            self.depth_mm / self.found.length
        } else {
            f64::INFINITY
        }
    }
}

/// The loop of `found`'s class in the middle of its neck (module docs, step 3), or `cycle`
/// itself when the neck has no end (or the ratio is 1).
fn place(search: &mut Search, cycle: Vec<u32>, found: Found, ratio: f64) -> Candidate {
    match (ratio > 1.0).then(|| search.middle_of_neck(&cycle, found, ratio)).flatten() {
        Some((cycle, found, depth_mm)) => Candidate { cycle, found, depth_mm, crossing: false },
        None => Candidate { cycle, found, depth_mm: 0.0, crossing: false },
    }
}
