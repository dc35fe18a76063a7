//! Stage 8 — `toolpath`: cutter-contact points → tool positions, with entry and exit moves.
//!
//! What it computes (DESIGN.md "toolpath", seed 000 §2.2.1 eq. 5): for every cutter-contact
//! (CC) point `cc[i]` with unit surface normal `n[i]` (towards the tool) of ONE continuous pass,
//!
//! - the ball centre `centre = cc + R·n` (R the ball radius; [`clear_facets`] beforehand moves
//!   centres that dip into a facet onto the mesh's offset surface, rewriting cc and n),
//! - the tool axis `a`: 3-axis, the chosen fixed axis ([`Axes::Three`], default +Z); 5-axis
//!   ([`Axes::Five`]), seed 000 eq. 5 with a tilt added,
//!   `a = cos β·cos γ·n + sin β·t + cos β·sin γ·b`, where β is the lead angle, γ the tilt angle,
//!   `t` the unit feed direction projected onto the tangent plane (centred difference of the ball
//!   centres, one-sided at the ends: where the ball rolls over a vertex of the mesh its contact
//!   stays put while the centre moves; widened where it runs along the normal) and `b = t × n`
//!   (to the right of the feed direction seen from the tool). So a positive lead leans the axis
//!   forwards (towards the feed direction), the tilt rotates the leaned axis about `t`, positive
//!   to the right. γ = 0 is eq. 5 exactly. The centred difference makes the axis as smooth as
//!   the path itself (no extra smoothing),
//! - the tool tip `tip = centre − R·a` (the point a controller programs: tool length
//!   compensation and, for 5-axis, tool-centre-point control are the machine's business).
//!
//! Entry and exit. Heights are measured along the "up" direction `U`: the tool axis for 3-axis,
//! +Z for 5-axis. The program
//!
//! 1. rapids to the safe height above the lead-in start, then down to `clearance_mm` above it
//!    ([`MoveKind::Rapid`]);
//! 2. feeds down the clearance and along the lead-in at the plunge feed ([`MoveKind::Approach`]):
//!    a quarter circle of length `lead_in_mm` in the plane spanned by `U` and the first cutting
//!    direction, ending at the first tip and tangent there to the first cutting direction — or to
//!    its horizontal part when the cut starts uphill, and at most 45° downhill — so every
//!    lead-in point lies at or above the first tip's height (never a plunge into the surface);
//! 3. cuts through every tip at the feed ([`MoveKind::Cut`]);
//! 4. leaves along the mirrored quarter circle, tangent to the last cutting direction and rising
//!    ([`MoveKind::LeadOut`], at the feed);
//! 5. retracts (rapid) to the safe height ([`MoveKind::Retract`]).
//!
//! The tool axis is held during the lead-in (first axis) and the lead-out (last axis), so the
//! ball centre follows the same arc as the tip. The leads do not look at the surface: the arc
//! (radius 2·lead_in_mm/π, rising s²/(2·radius) at a distance s from the contact) clears it
//! when the surface behind the start (ahead of the end) curves away or rises more slowly, as it
//! does along the tangent of a spiral's outer ring on parts a ball of this radius can finish.
//!
//! Preconditions (each fault is a [`ToolpathError`] naming the field or point index): at least
//! two points, as many normals as points, finite coordinates, normals of length 1 ± 1e-3
//! (renormalised), consecutive ball centres at least 1e-7 mm apart, 3-axis normals not facing away
//! from the tool axis (n·a ≥ 0: no undercut), 5-axis paths that do not run along their normals
//! throughout, tool tips that move at least once, options as documented on [`ToolpathOptions`],
//! and a safe height at least `clearance_mm` above every contact point, tool tip and lead move.
//!
//! Invariants of the output: the moves are Rapid, Rapid, Approach…, Cut…, LeadOut…, Retract, in
//! that order; the moves ending at the n contact points are [`Toolpath::contact_moves`] (the
//! last Approach move ends at the first contact's tip); every axis is a unit vector; `centre =
//! tip + R·axis` for every move; exactly one retraction. Deterministic: the same input gives
//! bit-identical output on every target (trigonometry from [`crate::num`]).

// `!(x > 0.0)` is deliberate throughout: NaN must fail every validity test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod clearance;

pub use clearance::{clear_facets, Clearance};

use crate::num;
use glam::DVec3;
use serde::Serialize;
use std::f64::consts::FRAC_PI_2;

/// Number of straight segments of each lead-in and lead-out quarter circle (5.6° each).
pub const LEAD_SEGMENTS: usize = 16;

/// How the tool axis is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axes {
    /// A fixed tool axis (3-axis milling, or 3+2 positioning); need not be unit, must be nonzero.
    Three { axis: DVec3 },
    /// Seed 000 eq. 5: lead angle β and tilt angle γ in degrees, each in (−90°, 90°).
    Five { lead_deg: f64, tilt_deg: f64 },
}

impl Default for Axes {
    /// 3-axis with the tool along +Z.
    fn default() -> Self {
        Axes::Three { axis: DVec3::Z }
    }
}

impl Axes {
    /// 5-axis with seed 000's angles: lead 15°, tilt 0°.
    pub fn five_default() -> Self {
        Axes::Five { lead_deg: 15.0, tilt_deg: 0.0 }
    }
}

/// Options of [`toolpath`]. Defaults in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolpathOptions {
    /// Ball radius R, mm [3].
    pub radius_mm: f64,
    /// Tool axis strategy [3-axis, +Z].
    pub axes: Axes,
    /// Cutting feed, mm/min [1000]; also the lead-out's feed.
    pub feed_mm_min: f64,
    /// Feed of the descent from the clearance height and of the lead-in, mm/min [300].
    pub plunge_feed_mm_min: f64,
    /// Rapid traverse rate, used only for the time estimate, mm/min [5000].
    pub rapid_mm_min: f64,
    /// Spindle speed, rpm [12000].
    pub spindle_rpm: f64,
    /// Safe height (along `U`, see the module docs), mm [None: the highest contact point, tool
    /// tip or lead move + max(10 mm, clearance)].
    pub safe_z_mm: Option<f64>,
    /// Height above the lead-in start where the rapid descent stops, mm [2]; > 0.
    pub clearance_mm: f64,
    /// Arc length of the lead-in (and of the lead-out), mm [None: 2R].
    pub lead_in_mm: Option<f64>,
    /// Tool number, ≥ 1 [1].
    pub tool_number: u32,
}

impl Default for ToolpathOptions {
    fn default() -> Self {
        ToolpathOptions {
            radius_mm: 3.0,
            axes: Axes::default(),
            feed_mm_min: 1000.0,
            plunge_feed_mm_min: 300.0,
            rapid_mm_min: 5000.0,
            spindle_rpm: 12000.0,
            safe_z_mm: None,
            clearance_mm: 2.0,
            lead_in_mm: None,
            tool_number: 1,
        }
    }
}

/// What a move does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum MoveKind {
    /// Rapid traverse (G0) at the start.
    Rapid,
    /// The descent from the clearance height and the lead-in, at the plunge feed.
    Approach,
    /// Cutting, at the feed.
    Cut,
    /// The lead-out, at the feed.
    LeadOut,
    /// The final rapid to the safe height.
    Retract,
}

impl MoveKind {
    /// Rapid traverse (G0) rather than a feed move (G1).
    pub fn is_rapid(self) -> bool {
        matches!(self, MoveKind::Rapid | MoveKind::Retract)
    }
}

/// One straight move to a target pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    pub kind: MoveKind,
    /// Target tool tip, mm.
    pub tip: DVec3,
    /// Unit tool axis (tip → spindle) at the target.
    pub axis: DVec3,
    /// Ball centre at the target, `tip + R·axis`.
    pub centre: DVec3,
    /// Feed of the move, mm/min (the rapid rate for rapid moves).
    pub feed_mm_min: f64,
}

/// The tool a toolpath was planned for (the posts need it).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Tool {
    pub number: u32,
    /// The ball radius (for a conical tool: its tip radius), mm.
    pub radius_mm: f64,
    pub spindle_rpm: f64,
    /// The cutter's shape (a ball unless a strategy says otherwise; not serialised for a ball,
    /// so the spiral's reports are unchanged).
    #[serde(skip_serializing_if = "ToolShape::is_ball")]
    pub shape: ToolShape,
}

/// The shape of a [`Tool`]'s cutting part.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub enum ToolShape {
    /// A ball end of the tool's radius.
    #[default]
    Ball,
    /// A tapered (or straight) flat-ended flute for flank milling ([`crate::flank`]): radius
    /// `tip_radius_mm` at the tip, `top_radius_mm` at the flute's top, `flute_length_mm` long.
    Cone { tip_radius_mm: f64, top_radius_mm: f64, flute_length_mm: f64 },
}

impl ToolShape {
    pub fn is_ball(&self) -> bool {
        matches!(self, ToolShape::Ball)
    }
}

/// Figures of a toolpath.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToolpathStats {
    /// Length of the cut (tool tip polyline through all contact moves), mm.
    pub cut_length_mm: f64,
    /// Length of the feed moves that do not cut: descent, lead-in and lead-out, mm.
    pub link_length_mm: f64,
    /// Length of the rapid moves (from the first move's target on), mm.
    pub rapid_length_mm: f64,
    /// Number of retractions (1 for one continuous pass: the final retract).
    pub retractions: usize,
    /// Number of contact points on the cut.
    pub cut_points: usize,
    /// Largest angle between the tool axes of consecutive contact moves, degrees (0 for 3-axis).
    pub max_axis_step_deg: f64,
    /// The safe height used, mm.
    pub safe_z_mm: f64,
    /// Every move's length at its feed (rapids at `rapid_mm_min`), s; no acceleration limits,
    /// no rotary-axis time.
    pub estimated_time_s: f64,
}

/// Output of [`toolpath`].
#[derive(Clone, Debug, PartialEq)]
pub struct Toolpath {
    pub moves: Vec<Move>,
    pub stats: ToolpathStats,
    pub tool: Tool,
    /// Index in `moves` of the move that ends at the first contact point (the lead-in's end).
    pub first_contact: usize,
}

impl Toolpath {
    /// The moves that end at the contact points, in order: one per input point (empty if the
    /// fields were edited inconsistently).
    pub fn contact_moves(&self) -> &[Move] {
        self.moves.get(self.first_contact..self.first_contact + self.stats.cut_points).unwrap_or(&[])
    }
}

/// Errors of [`toolpath`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ToolpathError {
    #[error("a toolpath needs at least 2 contact points, got {count}")]
    TooFewPoints { count: usize },
    #[error("{points} contact points but {normals} normals: give one normal per point")]
    LengthMismatch { points: usize, normals: usize },
    #[error("option {field} = {value} is invalid: expected {expected}")]
    InvalidOption { field: &'static str, value: f64, expected: &'static str },
    #[error("the tool axis ({x}, {y}, {z}) is not a finite nonzero vector")]
    InvalidToolAxis { x: f64, y: f64, z: f64 },
    #[error("contact point {index} has a non-finite coordinate")]
    NonFinitePoint { index: usize },
    #[error("normal {index} is not a unit vector (length {length}): pass unit normals")]
    NotUnitNormal { index: usize, length: f64 },
    #[error("the ball centre at contact point {index} repeats the previous one (distance {distance} mm): remove repeated points")]
    RepeatedPoint { index: usize, distance: f64 },
    #[error("the tool tip never moves ({points} contact points, one tip): the path is a turn in place")]
    TipNeverMoves { points: usize },
    #[error("normal {index} faces away from the tool axis (n·axis = {dot}): the ball cannot reach this undercut")]
    Undercut { index: usize, dot: f64 },
    #[error("at contact point {index} the feed direction is along the normal: no lead direction for the 5-axis axis")]
    FeedAlongNormal { index: usize },
    #[error("safe height {safe_z_mm} mm is too low: the tool reaches {highest_mm} mm near contact point {index}; use at least {required_mm} mm")]
    SafeHeightTooLow { safe_z_mm: f64, highest_mm: f64, required_mm: f64, index: usize },
}

/// Plans the tool positions of one continuous pass (see the module docs).
pub fn toolpath(cc: &[DVec3], normals: &[DVec3], options: &ToolpathOptions) -> Result<Toolpath, ToolpathError> {
    let o = Checked::new(options)?;
    if cc.len() != normals.len() {
        return Err(ToolpathError::LengthMismatch { points: cc.len(), normals: normals.len() });
    }
    if cc.len() < 2 {
        return Err(ToolpathError::TooFewPoints { count: cc.len() });
    }
    let n = check_points(cc, normals)?;
    let centres: Vec<DVec3> = cc.iter().zip(&n).map(|(&p, &nn)| p + o.radius * nn).collect();
    check_steps(&centres)?;
    let axes = tool_axes(&centres, &n, &o)?;
    let tips: Vec<DVec3> = centres.iter().zip(&axes).map(|(&c, &a)| c - o.radius * a).collect();

    // Lead-in (from its start down to the first tip) and lead-out (after the last tip), along
    // the first and the last move of the tip. Two centres apart may share a tip with 5 axes: the
    // axis turns about the tip (camelhead, R 0.05 mm: two tips 2.5e-8 mm apart), a move the
    // machine makes in place; it only gives the leads no direction.
    let last = tips.len() - 1;
    let moved = |i: usize, j: usize| tips[i].distance(tips[j]) >= MIN_STEP_MM;
    let (Some(first_move), Some(last_move)) =
        ((1..=last).find(|&i| moved(i, 0)), (0..last).rev().find(|&i| moved(i, last)))
    else {
        return Err(ToolpathError::TipNeverMoves { points: tips.len() });
    };
    let rho = o.lead_in / FRAC_PI_2;
    let lead_in = quarter_circle(tips[0], tips[first_move] - tips[0], o.up, rho, Lead::In);
    let lead_out = quarter_circle(tips[last], tips[last] - tips[last_move], o.up, rho, Lead::Out);

    // Safe height: above every point the tool reaches (contacts, tips, leads).
    let height = |p: DVec3| p.dot(o.up);
    let mut highest = (f64::NEG_INFINITY, 0usize);
    for (i, (&p, &t)) in cc.iter().zip(&tips).enumerate() {
        for h in [height(p), height(t)] {
            if h > highest.0 {
                highest = (h, i);
            }
        }
    }
    for (points, index) in [(&lead_in, 0), (&lead_out, last)] {
        for &p in points {
            if height(p) > highest.0 {
                highest = (height(p), index);
            }
        }
    }
    let required = highest.0 + o.clearance;
    let safe = match options.safe_z_mm {
        None => highest.0 + o.clearance.max(DEFAULT_SAFE_ABOVE_MM),
        Some(z) if z >= required => z,
        Some(z) => {
            return Err(ToolpathError::SafeHeightTooLow {
                safe_z_mm: z,
                highest_mm: highest.0,
                required_mm: required,
                index: highest.1,
            })
        }
    };
    let at_safe = |p: DVec3| p + (safe - height(p)) * o.up;

    let mut moves = Vec::with_capacity(tips.len() + 2 * LEAD_SEGMENTS + 5);
    let mv = |kind, tip: DVec3, axis: DVec3, feed| Move {
        kind,
        tip,
        axis,
        centre: tip + o.radius * axis,
        feed_mm_min: feed,
    };
    let start = lead_in[0];
    moves.push(mv(MoveKind::Rapid, at_safe(start), axes[0], o.rapid));
    moves.push(mv(MoveKind::Rapid, start + o.clearance * o.up, axes[0], o.rapid));
    for &p in &lead_in[..LEAD_SEGMENTS] {
        moves.push(mv(MoveKind::Approach, p, axes[0], o.plunge));
    }
    let first_contact = moves.len();
    for (i, (&tip, &axis)) in tips.iter().zip(&axes).enumerate() {
        let kind = if i == 0 { MoveKind::Approach } else { MoveKind::Cut };
        let feed = if i == 0 { o.plunge } else { o.feed };
        moves.push(Move { kind, tip, axis, centre: centres[i], feed_mm_min: feed });
    }
    for &p in &lead_out {
        moves.push(mv(MoveKind::LeadOut, p, axes[last], o.feed));
    }
    moves.push(mv(MoveKind::Retract, at_safe(lead_out[LEAD_SEGMENTS - 1]), axes[last], o.rapid));

    let stats = stats(&moves, &axes, safe);
    Ok(Toolpath {
        moves,
        stats,
        tool: Tool {
            number: options.tool_number,
            radius_mm: o.radius,
            spindle_rpm: options.spindle_rpm,
            shape: ToolShape::Ball,
        },
        first_contact,
    })
}

/// Consecutive tips (and ball centres) closer than this are a repeated point.
pub(crate) const MIN_STEP_MM: f64 = 1e-7;
/// Default safe height above the highest point the tool reaches.
const DEFAULT_SAFE_ABOVE_MM: f64 = 10.0;
/// Steepest lead-in/lead-out tangent, as sin 45°.
const MAX_LEAD_SLOPE_SIN: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Validated options.
struct Checked {
    radius: f64,
    feed: f64,
    plunge: f64,
    rapid: f64,
    clearance: f64,
    lead_in: f64,
    rule: AxisRule,
    up: DVec3,
}

enum AxisRule {
    Fixed(DVec3),
    /// The coefficients of n, t, b: (cos β cos γ, sin β, cos β sin γ).
    Lead(f64, f64, f64),
}

impl Checked {
    fn new(o: &ToolpathOptions) -> Result<Self, ToolpathError> {
        let positive = |field: &'static str, value: f64| {
            if value > 0.0 && value.is_finite() {
                Ok(value)
            } else {
                Err(ToolpathError::InvalidOption { field, value, expected: "a finite number > 0" })
            }
        };
        let radius = positive("radius_mm", o.radius_mm)?;
        let feed = positive("feed_mm_min", o.feed_mm_min)?;
        let plunge = positive("plunge_feed_mm_min", o.plunge_feed_mm_min)?;
        let rapid = positive("rapid_mm_min", o.rapid_mm_min)?;
        positive("spindle_rpm", o.spindle_rpm)?;
        let clearance = positive("clearance_mm", o.clearance_mm)?;
        let lead_in = positive("lead_in_mm", o.lead_in_mm.unwrap_or(2.0 * o.radius_mm))?;
        if let Some(z) = o.safe_z_mm {
            if !z.is_finite() {
                return Err(ToolpathError::InvalidOption { field: "safe_z_mm", value: z, expected: "a finite height" });
            }
        }
        if o.tool_number == 0 {
            return Err(ToolpathError::InvalidOption {
                field: "tool_number",
                value: 0.0,
                expected: "a tool number ≥ 1",
            });
        }
        let (rule, up) = match o.axes {
            Axes::Three { axis } => {
                let len = axis.length();
                if !(len > 1e-12 && len.is_finite()) {
                    return Err(ToolpathError::InvalidToolAxis { x: axis.x, y: axis.y, z: axis.z });
                }
                (AxisRule::Fixed(axis / len), axis / len)
            }
            Axes::Five { lead_deg, tilt_deg } => {
                let angle = |field: &'static str, value: f64| {
                    if value.abs() < 90.0 {
                        Ok(value.to_radians())
                    } else {
                        Err(ToolpathError::InvalidOption { field, value, expected: "an angle in (−90°, 90°)" })
                    }
                };
                let (sb, cb) = num::sin_cos(angle("lead_deg", lead_deg)?);
                let (sg, cg) = num::sin_cos(angle("tilt_deg", tilt_deg)?);
                (AxisRule::Lead(cb * cg, sb, cb * sg), DVec3::Z)
            }
        };
        Ok(Checked { radius, feed, plunge, rapid, clearance, lead_in, rule, up })
    }
}

/// Finite points, unit normals (renormalised).
fn check_points(cc: &[DVec3], normals: &[DVec3]) -> Result<Vec<DVec3>, ToolpathError> {
    let mut n = Vec::with_capacity(normals.len());
    for (i, (&p, &nn)) in cc.iter().zip(normals).enumerate() {
        if !p.is_finite() {
            return Err(ToolpathError::NonFinitePoint { index: i });
        }
        let length = nn.length();
        if !((length - 1.0).abs() <= 1e-3) {
            return Err(ToolpathError::NotUnitNormal { index: i, length });
        }
        n.push(nn / length);
    }
    Ok(n)
}

/// No repeated ball centre. (Contacts may repeat: a ball rolling over a vertex of the mesh
/// keeps touching it while its centre moves.)
fn check_steps(centres: &[DVec3]) -> Result<(), ToolpathError> {
    for i in 1..centres.len() {
        let distance = centres[i].distance(centres[i - 1]);
        if !(distance >= MIN_STEP_MM) {
            return Err(ToolpathError::RepeatedPoint { index: i, distance });
        }
    }
    Ok(())
}

/// The tool axis at every ball centre (module docs).
fn tool_axes(centres: &[DVec3], n: &[DVec3], o: &Checked) -> Result<Vec<DVec3>, ToolpathError> {
    let (cn, ct, cb) = match o.rule {
        AxisRule::Fixed(axis) => {
            for (i, &nn) in n.iter().enumerate() {
                let dot = nn.dot(axis);
                if dot < -1e-12 {
                    return Err(ToolpathError::Undercut { index: i, dot });
                }
            }
            return Ok(vec![axis; centres.len()]);
        }
        AxisRule::Lead(cn, ct, cb) => (cn, ct, cb),
    };
    let last = centres.len() - 1;
    // The feed direction in the tangent plane: the centres' central difference, widened where it
    // runs along the normal (a ball lifted out of a pit or a crease by the clearance moves along
    // its normal for a step or two: face.stl, R 0.0035 mm, 5 axes). The widening doubles: at most
    // log₂ n + 1 differences per point.
    let feed = |i: usize| -> Option<DVec3> {
        let mut k = 1;
        loop {
            let d = centres[(i + k).min(last)] - centres[i.saturating_sub(k)];
            let tangent = d - d.dot(n[i]) * n[i];
            let len = tangent.length();
            if len > 1e-9 * d.length() {
                return Some(tangent / len);
            }
            if k >= last {
                return None;
            }
            k *= 2;
        }
    };
    (0..centres.len())
        .map(|i| {
            let t = feed(i).ok_or(ToolpathError::FeedAlongNormal { index: i })?;
            let b = t.cross(n[i]);
            Ok((cn * n[i] + ct * t + cb * b).normalize())
        })
        .collect()
}

#[derive(Clone, Copy, PartialEq)]
enum Lead {
    In,
    Out,
}

/// A quarter circle of radius `rho` in the plane of `up` and the direction `dir` at `p`,
/// tangent at `p`: for [`Lead::In`] it ends at `p` (returned points: start … last point before
/// `p`), for [`Lead::Out`] it starts at `p` (points after `p` … end). The tangent at `p` is
/// `dir` with its slope clamped to [−45°, 0] (in) or [0, 45°] (out), so the arc never dips
/// below `p`'s height.
fn quarter_circle(p: DVec3, dir: DVec3, up: DVec3, rho: f64, lead: Lead) -> Vec<DVec3> {
    let d0 = dir.normalize();
    let level = d0 - d0.dot(up) * up;
    let h = if level.length() > 1e-9 { level.normalize() } else { up.any_orthonormal_vector() };
    let s = match lead {
        Lead::In => d0.dot(up).clamp(-MAX_LEAD_SLOPE_SIN, 0.0),
        Lead::Out => d0.dot(up).clamp(0.0, MAX_LEAD_SLOPE_SIN),
    };
    let c = (1.0 - s * s).sqrt();
    let d = c * h + s * up; // tangent at p
    let m = c * up - s * h; // towards the arc's centre, upwards
    let point = |k: usize| {
        let (sp, cp) = num::sin_cos(FRAC_PI_2 * k as f64 / LEAD_SEGMENTS as f64);
        let along = if lead == Lead::In { -sp } else { sp };
        p + rho * (1.0 - cp) * m + rho * along * d
    };
    match lead {
        Lead::In => (1..=LEAD_SEGMENTS).rev().map(point).collect(),
        Lead::Out => (1..=LEAD_SEGMENTS).map(point).collect(),
    }
}

fn stats(moves: &[Move], axes: &[DVec3], safe: f64) -> ToolpathStats {
    let max_axis_step_deg =
        axes.windows(2).map(|w| num::acos(w[0].dot(w[1]).clamp(-1.0, 1.0)).to_degrees()).fold(0.0, f64::max);
    let retractions = moves.iter().filter(|m| m.kind == MoveKind::Retract).count();
    stats_of_moves(moves, axes.len(), retractions, max_axis_step_deg, safe)
}

/// The statistics of `moves`: the lengths by kind and the time summed move by move (each at
/// its own feed), with the figures the strategy counts its own way.
pub(crate) fn stats_of_moves(
    moves: &[Move],
    cut_points: usize,
    retractions: usize,
    max_axis_step_deg: f64,
    safe_z_mm: f64,
) -> ToolpathStats {
    let (mut cut, mut link, mut rapid, mut time) = (0.0, 0.0, 0.0, 0.0);
    for w in moves.windows(2) {
        let length = w[1].tip.distance(w[0].tip);
        match w[1].kind {
            MoveKind::Cut => cut += length,
            MoveKind::Approach | MoveKind::LeadOut => link += length,
            MoveKind::Rapid | MoveKind::Retract => rapid += length,
        }
        time += length / w[1].feed_mm_min * 60.0;
    }
    ToolpathStats {
        cut_length_mm: cut,
        link_length_mm: link,
        rapid_length_mm: rapid,
        retractions,
        cut_points,
        max_axis_step_deg,
        safe_z_mm,
        estimated_time_s: time,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_circle_is_tangent_and_never_below_its_end() {
        for dz in [-2.0, -0.5, 0.0, 0.3, 3.0] {
            let p = DVec3::new(1.0, 2.0, 3.0);
            let dir = DVec3::new(1.0, 0.5, dz);
            let arc = quarter_circle(p, dir, DVec3::Z, 4.0, Lead::In);
            assert_eq!(arc.len(), LEAD_SEGMENTS);
            assert!(arc.iter().all(|q| q.z >= p.z - 1e-12), "lead-in below its end for dz = {dz}");
            let last = (p - arc[LEAD_SEGMENTS - 1]).normalize();
            let clamped = {
                let s = dir.normalize().z.clamp(-MAX_LEAD_SLOPE_SIN, 0.0);
                let h = DVec3::new(dir.x, dir.y, 0.0).normalize();
                (1.0 - s * s).sqrt() * h + s * DVec3::Z
            };
            // The last chord is within half a segment angle of the tangent.
            let half_segment = (FRAC_PI_2 / LEAD_SEGMENTS as f64 / 2.0) * (1.0 + 1e-9);
            assert!(last.dot(clamped) >= num::cos(half_segment), "dz = {dz}");
            let out = quarter_circle(p, dir, DVec3::Z, 4.0, Lead::Out);
            assert!(out.iter().all(|q| q.z >= p.z - 1e-12), "lead-out below its start for dz = {dz}");
            // A quarter circle: the arc ends a distance rho·√2 from p.
            assert!((out[LEAD_SEGMENTS - 1].distance(p) - 4.0 * 2f64.sqrt()).abs() < 1e-12);
        }
    }
}
