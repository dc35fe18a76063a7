//! Collision flags (seed 002 §3 and Fig. 4 validate "that the extended axis of the tool towards
//! the shank does not collide with the reference geometry" as a post-process).
//!
//! The tool as a machinist describes it, from the tip up its axis ([`ToolBody`]):
//! - the flutes, heights 0 … H (the cone of [`ConeTool`]);
//! - the shank (or neck), a cylinder of `shank_radius_mm` from the flute top to the holder;
//! - the holder, a cylinder of `holder_radius_mm` from the gauge length G (tip to holder face)
//!   to G + `holder_length_mm`.
//!
//! Each part is a slab of the axis with a radius, and its clearance is (the least distance from
//! the axis of a facet point in the slab) − radius, exactly ([`crate::mesh::axial`]). What is
//! flagged, at every move of the program:
//! - the holder when some facet point comes within `margin_mm` of it (its slab extended by the
//!   margin below its face, its radius grown by the margin);
//! - the shank when the part enters it deeper than the flutes enter the part at their top
//!   circle, by more than [`SHANK_TOUCH_MM`]. No margin, because the shank starts at the flute
//!   top, which touches the part in every cutting pose by design (with the default shank radius
//!   = top radius the clearance there is 0, and it grows as tan α per mm above it on a flat
//!   wall); and the flutes' own gouge at that circle (the optimiser's error, which the verifier
//!   reports) is not the shank's. Entering it deeper is rubbing with a part that does not cut;
//! - the flutes only on rapid moves (a rapid must not come within the margin of the part; feed
//!   moves are the cut and its approach along the normal, which the verifier judges), as a
//!   cylinder of the larger flute radius.
//!
//! Cutting, approach and lead-out moves are checked at the pose they end at. Rapids (links and
//! retracts) are checked along their path: poses interpolated (tip linear, axis normalised
//! linear, as a TCP controller nearly does) so that no point of the tool moves more than
//! [`SWEEP_STEP_MM`] between two, each part's radius grown by half that step, so the sampled
//! check is conservative.
//!
//! Flagged moves are reported with their index, kind, strip (for cutting moves), the tool part,
//! its clearance and the facet point nearest to its axis (where). Nothing is ever dropped or
//! moved: the plan is what the optimiser found, and the report says where it is unsafe.

use super::tool::ConeTool;
use crate::mesh::axial::Slab;
use crate::mesh::nearest::FaceTree;
use crate::toolpath::{Move, MoveKind, Toolpath};
use glam::DVec3;
use serde::Serialize;
use std::ops::Range;

/// Penetration of the shank taken as a touch, not a collision (rounding at the flute top).
pub const SHANK_TOUCH_MM: f64 = 1e-3;

/// Largest distance any tool point moves between two checked poses of a rapid, mm.
pub const SWEEP_STEP_MM: f64 = 1.0;

/// The tool above the flutes and the clearance wanted (resolved values; module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ToolBody {
    pub shank_radius_mm: f64,
    /// From the tool tip to the holder's face, mm (the shank is gauge − flute length long).
    pub gauge_length_mm: f64,
    pub holder_radius_mm: f64,
    pub holder_length_mm: f64,
    pub margin_mm: f64,
}

/// One flagged move.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlaggedMove {
    pub move_index: usize,
    /// `cut`, `approach`, `lead-out`, `rapid` or `retract`.
    pub kind: &'static str,
    /// The strip whose cut the move belongs to (None for links and rapids).
    pub strip: Option<usize>,
    /// The tool part: `holder`, `shank` or `flute`.
    pub what: &'static str,
    /// Its clearance (negative: the part is inside it), mm.
    pub clearance_mm: f64,
    /// The facet point nearest to its axis (where).
    pub at: [f64; 3],
}

/// What [`check`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CollisionReport {
    pub tool: ToolBody,
    pub checked_moves: usize,
    pub flagged: Vec<FlaggedMove>,
    /// Smallest clearance over the flagged moves (None when nothing is flagged).
    pub min_clearance_mm: Option<f64>,
}

/// One part of the tool: a slab of its axis and a radius, flagged below `flag_below`.
struct Part {
    what: &'static str,
    from: f64,
    to: f64,
    radius: f64,
    flag_below: f64,
}

/// A part of the tool met by the part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub what: &'static str,
    pub clearance_mm: f64,
    pub at: DVec3,
}

/// The check of one tool against one part's mesh.
pub struct Checker<'a> {
    tree: &'a FaceTree,
    tool: ConeTool,
    body: ToolBody,
}

impl<'a> Checker<'a> {
    pub fn new(tree: &'a FaceTree, tool: &ConeTool, body: &ToolBody) -> Self {
        Checker { tree, tool: *tool, body: *body }
    }

    /// The parts checked (module docs); with `flute` the flutes too; radii grown by `grow`.
    fn parts(&self, flute: bool, grow: f64) -> Vec<Part> {
        let (h, b) = (self.tool.flute_length_mm, &self.body);
        let mut parts = vec![
            Part {
                what: "holder",
                from: b.gauge_length_mm - b.margin_mm,
                to: b.gauge_length_mm + b.holder_length_mm,
                radius: b.holder_radius_mm + grow,
                flag_below: b.margin_mm,
            },
            Part {
                what: "shank",
                from: h,
                to: b.gauge_length_mm,
                radius: b.shank_radius_mm + grow,
                flag_below: -SHANK_TOUCH_MM,
            },
        ];
        if flute {
            let radius = self.tool.tip_radius_mm.max(self.tool.top_radius_mm) + grow;
            parts.push(Part { what: "flute", from: -b.margin_mm, to: h, radius, flag_below: b.margin_mm });
        }
        parts
    }

    /// How deep the part lies inside the flute's top circle at pose (tip, axis), mm (0 when it
    /// does not reach it): the flutes' own gouge there, which the shank starting at that circle
    /// is not blamed for.
    fn flute_top_gouge(&self, tip: DVec3, axis: DVec3) -> f64 {
        let (h, top) = (self.tool.flute_length_mm, self.tool.top_radius_mm);
        // A band a micrometre thick: a slab of no thickness loses its clipped points to rounding.
        let circle = Slab { origin: tip, axis, from: h - 1e-3 * SHANK_TOUCH_MM, to: h + 1e-3 * SHANK_TOUCH_MM };
        self.tree.nearest_to_axis(&circle, top).map_or(0.0, |n| top - n.radial_mm)
    }

    /// The worst part of the tool at pose (tip, axis) that the part comes too near, if any.
    fn pose(&self, tip: DVec3, axis: DVec3, parts: &[Part]) -> Option<Hit> {
        let mut worst: Option<Hit> = None;
        for p in parts {
            let slab = Slab { origin: tip, axis, from: p.from, to: p.to };
            let allowance = if p.what == "shank" { self.flute_top_gouge(tip, axis) } else { 0.0 };
            if let Some(n) = self.tree.nearest_to_axis(&slab, p.radius + p.flag_below - allowance) {
                let clearance_mm = n.radial_mm - p.radius;
                if worse(&worst, clearance_mm) {
                    worst = Some(Hit { what: p.what, clearance_mm, at: n.point });
                }
            }
        }
        worst
    }

    /// The worst part of the tool the part comes too near during the rapid `from → to`
    /// (module docs: sampled, conservative).
    pub fn rapid(&self, from: &Move, to: &Move) -> Option<Hit> {
        let reach = self.body.gauge_length_mm + self.body.holder_length_mm;
        let travel = from.tip.distance(to.tip) + reach * from.axis.distance(to.axis);
        let steps = ((travel / SWEEP_STEP_MM).ceil() as usize).clamp(1, 100_000);
        let parts = self.parts(true, 0.5 * travel / steps as f64);
        let mut worst: Option<Hit> = None;
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let axis = from.axis.lerp(to.axis, t).normalize_or(from.axis);
            if let Some(hit) = self.pose(from.tip.lerp(to.tip, t), axis, &parts) {
                if worse(&worst, hit.clearance_mm) {
                    worst = Some(hit);
                }
            }
        }
        worst
    }

    /// The worst part of the tool the part comes too near at the end of a feed move.
    pub fn feed(&self, m: &Move) -> Option<Hit> {
        self.pose(m.tip, m.axis, &self.parts(false, 0.0))
    }
}

/// Whether a clearance is worse than the worst hit so far (or there is none).
fn worse(worst: &Option<Hit>, clearance_mm: f64) -> bool {
    worst.map_or(true, |h| clearance_mm < h.clearance_mm)
}

fn kind_name(kind: MoveKind) -> &'static str {
    match kind {
        MoveKind::Rapid => "rapid",
        MoveKind::Approach => "approach",
        MoveKind::Cut => "cut",
        MoveKind::LeadOut => "lead-out",
        MoveKind::Retract => "retract",
    }
}

/// Checks every move of `toolpath` (module docs); `strips` are the cut ranges.
pub fn check(checker: &Checker, toolpath: &Toolpath, strips: &[Range<usize>]) -> CollisionReport {
    let mut flagged = Vec::new();
    let strip_of = |i: usize| strips.iter().position(|r| r.contains(&i));
    for (i, m) in toolpath.moves.iter().enumerate() {
        let hit = if m.kind.is_rapid() {
            // The first move comes from wherever the machine was: only its end pose is known.
            checker.rapid(if i > 0 { &toolpath.moves[i - 1] } else { m }, m)
        } else {
            checker.feed(m)
        };
        if let Some(h) = hit {
            flagged.push(FlaggedMove {
                move_index: i,
                kind: kind_name(m.kind),
                strip: strip_of(i),
                what: h.what,
                clearance_mm: h.clearance_mm,
                at: h.at.to_array(),
            });
        }
    }
    let min_clearance_mm = flagged.iter().map(|f| f.clearance_mm).reduce(f64::min);
    CollisionReport { tool: checker.body, checked_moves: toolpath.moves.len(), flagged, min_clearance_mm }
}
