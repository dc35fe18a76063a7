//! Collision flags (seed 002 §3 and Fig. 4 validate "that the extended axis of the tool towards
//! the shank does not collide with the reference geometry" as a post-process).
//!
//! What it checks, for every move of the program:
//! - the holder: a capsule of radius `holder_radius_mm` around the axis from the top of the flute
//!   to `holder_length_mm` beyond it. A move is flagged when some facet of the part comes within
//!   `margin_mm` of it (the capsule grown by the margin meets the mesh);
//! - for rapid moves also the flute: the straight paths of its tip and of its top, as capsules of
//!   the top radius grown by the margin (a rapid must not touch the part at all).
//!
//! Flagged moves are reported with their index, their strip (for cutting moves) and their
//! clearance (the smallest distance from 17 points along the capsule's axis to the mesh, less
//! the radius; negative: the part is inside it). Nothing is ever dropped or moved: the plan is
//! what the optimiser found, and the report says where it is unsafe.

use super::tool::ConeTool;
use crate::mesh::nearest::FaceTree;
use crate::toolpath::Toolpath;
use glam::DVec3;
use serde::Serialize;
use std::ops::Range;

/// The holder above the flute and the clearance wanted.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Holder {
    pub length_mm: f64,
    pub radius_mm: f64,
    pub margin_mm: f64,
}

/// One flagged move.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlaggedMove {
    pub move_index: usize,
    /// The strip whose cut the move belongs to (None for links and rapids).
    pub strip: Option<usize>,
    /// `holder` or `rapid`.
    pub what: &'static str,
    pub clearance_mm: f64,
}

/// What [`check`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CollisionReport {
    pub holder: Holder,
    pub checked_moves: usize,
    pub flagged: Vec<FlaggedMove>,
    /// Smallest clearance over the flagged moves (None when nothing is flagged).
    pub min_clearance_mm: Option<f64>,
}

/// Checks every move of `toolpath` (module docs); `strips` are the cut ranges.
pub fn check(
    tree: &FaceTree,
    toolpath: &Toolpath,
    strips: &[Range<usize>],
    tool: &ConeTool,
    holder: &Holder,
) -> CollisionReport {
    let mut flagged = Vec::new();
    let strip_of = |i: usize| strips.iter().position(|r| r.contains(&i));
    for (i, m) in toolpath.moves.iter().enumerate() {
        let top = m.tip + tool.flute_length_mm * m.axis;
        let end = top + holder.length_mm * m.axis;
        if tree.segment_nearer_than(top, end, holder.radius_mm + holder.margin_mm) {
            let clearance = clearance(tree, top, end, holder.radius_mm);
            flagged.push(FlaggedMove { move_index: i, strip: strip_of(i), what: "holder", clearance_mm: clearance });
        } else if m.kind.is_rapid() && i > 0 {
            let prev = toolpath.moves[i - 1];
            let prev_top = prev.tip + tool.flute_length_mm * prev.axis;
            let reach = tool.top_radius_mm.max(tool.tip_radius_mm) + holder.margin_mm;
            if tree.segment_nearer_than(prev.tip, m.tip, reach) || tree.segment_nearer_than(prev_top, top, reach) {
                let c = clearance(tree, prev.tip, m.tip, tool.top_radius_mm.max(tool.tip_radius_mm)).min(clearance(
                    tree,
                    prev_top,
                    top,
                    tool.top_radius_mm.max(tool.tip_radius_mm),
                ));
                flagged.push(FlaggedMove { move_index: i, strip: None, what: "rapid", clearance_mm: c });
            }
        }
    }
    let min_clearance_mm = flagged.iter().map(|f| f.clearance_mm).reduce(f64::min);
    CollisionReport { holder: *holder, checked_moves: toolpath.moves.len(), flagged, min_clearance_mm }
}

/// Smallest distance from 17 points along `p → q` to the mesh, less `radius`.
fn clearance(tree: &FaceTree, p: DVec3, q: DVec3, radius: f64) -> f64 {
    (0..=16)
        .filter_map(|k| tree.nearest(p + (k as f64 / 16.0) * (q - p), f64::INFINITY))
        .map(|n| n.distance - radius)
        .fold(f64::INFINITY, f64::min)
}
