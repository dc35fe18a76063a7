//! Guiding curves and base points (seed 002 §5, Fig. 10, Remark 1).
//!
//! What it computes: M + 1 guiding curves g₀ … g_M, level sets of the guiding field G
//! ([`super::field`]), and on each a row of base points g_{i,j} with their unit surface normals
//! n_{i,j}, such that consecutive rows correspond (same j = same instant of the strip between
//! them).
//!
//! - Spacing. The seed spaces the levels d = √(L² − Δr²) apart, which makes the initial axes
//!   (eq. 7) exactly L long on a plane. Decision: each next level is the one whose initial axes
//!   a_{i,j} = g_{i,j} + r₁n_{i,j}, b_{i,j} = g_{i+1,j} + r₂n_{i+1,j} are L long *on average* over
//!   the row (found by bracketing and the Illinois method on the level): on a plane (and a
//!   cylinder along its circles) that is the seed's d exactly, and on curved surfaces it keeps
//!   the seed's intent (tangential contact at both ends, a rigid tool), where the planar d would
//!   leave the optimiser a rigidity error of the order of the curvature (seed 002 §7.2,
//!   "Initialization").
//! - Where the strips go. The levels are marched from a start level up and down while the next
//!   one still exists on the surface (and the previous row's planes meet it); with a strip count
//!   the consecutive strips whose end bands are most even are kept. The start is the middle
//!   level of G or one a quarter or half a strip above it or a quarter below, whichever gives
//!   the most strips. Then the start
//!   moves by half the difference of the bands left at both ends and the levels are found
//!   again, so the strips sit in the middle of the surface (the bands left at both sides are
//!   narrower than a strip and are reported by the verifier as not machined). Marching from the
//!   middle, not from one end, matters where G is not constant along the surface's edge: the
//!   level just above its minimum is then a short arc round one corner.
//! - Base points. On the middle curve they are spread evenly by arc length about `step_mm`
//!   apart, from end to end (the seed spaces them on g₁ by chord h; on a line or a circle the
//!   two agree, and even arc spacing reaches both ends). Each next row, up or down, is found
//!   through the normal planes of the previous curve at its base points (Fig. 10): the crossing of the plane with g_{i+1}
//!   nearest to g_{i,j}. Remark 1: where no plane meets g_{i+1} the row ends (the strip is
//!   shorter), and where g_{i+1} reaches further than the previous row's planes by more than
//!   half a step, base points are added along it, evenly by arc length (the strip is longer).
//!   Rows are contiguous runs of j (crossings that would run backwards along g_{i+1} end the
//!   run).
//! - Normals n_{i,j}: the surface's interpolated normals at the base points (the face a level
//!   set segment crosses and the point's barycentric coordinates in it).
//!
//! One level-set component per guiding curve: where a level set has several (a surface with
//! holes across the strips), the one the previous row's planes meet most is kept; the seed too
//! plans one family of strips without T-junctions (§3).
//!
//! Errors: [`FlankError::NoStripFits`] when not even one strip fits across the surface,
//! [`FlankError::StripsDoNotFit`] when fewer strips fit than asked for.

use super::field::GuideField;
use super::levels::{level_set, Polyline};
use super::tool::SphereFamily;
use super::FlankError;
use crate::mesh::nearest::closest_on_triangle;
use crate::mesh::Surface;
use glam::DVec3;

/// One row of base points: `points[k]` is g_{i, first_j + k}.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseRow {
    pub first_j: i64,
    pub points: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    /// Unit tangents of the guiding curve at the points (the normal planes of Fig. 10).
    pub tangents: Vec<DVec3>,
}

impl BaseRow {
    pub fn last_j(&self) -> i64 {
        self.first_j + self.points.len() as i64 - 1
    }
}

/// The guiding curves and their base points.
#[derive(Clone, Debug, PartialEq)]
pub struct Guides {
    /// The M + 1 levels of G.
    pub levels: Vec<f64>,
    /// The guiding curves as polylines (for drawing and reports).
    pub curves: Vec<Vec<DVec3>>,
    pub rows: Vec<BaseRow>,
}

/// What [`guiding_curves`] needs.
#[derive(Clone, Copy, Debug)]
pub struct GuideInput<'a> {
    pub surface: &'a Surface,
    pub field: &'a GuideField,
    pub direction: DVec3,
    pub family: SphereFamily,
    /// Strips wanted (None: as many as fit).
    pub strips: Option<usize>,
    /// Spacing of the base points on the first curve, mm.
    pub step_mm: f64,
}

/// Levels are bracketed and refined to this fraction of the contact length d.
const LEVEL_TOLERANCE: f64 = 1e-13;
/// The last level stays this fraction of d inside the field's range.
const START_OFFSET: f64 = 1e-6;
/// A normal plane must meet the next curve within this multiple of L.
const REACH: f64 = 2.0;

/// The guiding curves and base points (module docs).
pub fn guiding_curves(input: &GuideInput) -> Result<Guides, FlankError> {
    let d = input.family.contact_length_mm;
    let across = input.field.max - input.field.min;
    let no_strip = FlankError::NoStripFits { across_mm: across, strip_mm: d };
    // The strip count depends on where the levels start: try the middle level and three
    // others a quarter of a strip apart, keep the most strips (then the most even bands).
    let middle = 0.5 * (input.field.min + input.field.max);
    let mut first: Option<(f64, Guides)> = None;
    for phase in [0.0, 0.5, 0.25, -0.25] {
        let start = middle + phase * d;
        let Some(g) = march(input, start)? else { continue };
        let uneven = |g: &Guides| {
            let n = g.levels.len() - 1;
            ((g.levels[0] - input.field.min) - (input.field.max - g.levels[n])).abs()
        };
        let better = match &first {
            None => true,
            Some((_, f)) => {
                g.levels.len() > f.levels.len() || (g.levels.len() == f.levels.len() && uneven(&g) < uneven(f))
            }
        };
        if better {
            first = Some((start, g));
        }
    }
    let (middle, first) = first.ok_or(no_strip.clone())?;
    let strips = first.levels.len() - 1;
    if strips == 0 {
        return Err(no_strip);
    }
    if let Some(wanted) = input.strips {
        if strips < wanted {
            return Err(FlankError::StripsDoNotFit { requested: wanted, fit: strips });
        }
    }
    // Centre the strips: move the start by half the difference of the bands left at both ends.
    let (below, above) = (first.levels[0] - input.field.min, input.field.max - first.levels[strips]);
    if (above - below).abs() > 1e-9 * d {
        if let Some(centred) = march(input, middle + 0.5 * (above - below))? {
            if centred.levels.len() == first.levels.len() {
                return Ok(centred);
            }
        }
    }
    Ok(first)
}

/// Marches levels from `start` up and down while the surface goes on, then keeps the
/// `input.strips` consecutive strips nearest the middle (all of them without a count). None
/// when the level `start` does not exist.
fn march(input: &GuideInput, start: f64) -> Result<Option<Guides>, FlankError> {
    let s = input.surface;
    let Some(line) = level_set(s, &input.field.values, start, input.direction)
        .into_iter()
        .max_by(|a, b| a.length().total_cmp(&b.length()))
    else {
        return Ok(None);
    };
    let row = first_row(s, &line, input.step_mm);
    let mut up = vec![(start, line.points.clone(), row.clone())];
    while let Some(next) = next_level(input, up.last().expect("one level").0, &up.last().expect("one row").2, Side::Up)
    {
        up.push((next.0, next.1.points, next.2));
    }
    let mut down = vec![(start, line.points, row)];
    while let Some(next) =
        next_level(input, down.last().expect("one level").0, &down.last().expect("one row").2, Side::Down)
    {
        down.push((next.0, next.1.points, next.2));
    }
    down.reverse();
    down.pop(); // the start is in `up` too
    let mut all = down;
    all.extend(up);
    // Keep `strips` consecutive strips, the window whose bands at both ends are most even.
    let (lo, hi) = match input.strips {
        Some(m) if m + 1 < all.len() => {
            let bands = |k: usize| {
                let (b, a) = (all[k].0 - input.field.min, input.field.max - all[k + m].0);
                (a - b).abs()
            };
            let k = (0..all.len() - m).min_by(|&x, &y| bands(x).total_cmp(&bands(y))).expect("a window");
            (k, k + m + 1)
        }
        _ => (0, all.len()),
    };
    let mut guides = Guides { levels: Vec::new(), curves: Vec::new(), rows: Vec::new() };
    for (level, curve, row) in all.drain(lo..hi) {
        guides.levels.push(level);
        guides.curves.push(curve);
        guides.rows.push(row);
    }
    Ok(Some(guides))
}

/// Base points evenly spread by arc length about `step` apart over the whole polyline.
fn first_row(s: &Surface, line: &Polyline, step: f64) -> BaseRow {
    let len = line.length();
    let n = ((len / step).round() as usize).max(1);
    let mut row = BaseRow { first_j: 0, points: Vec::new(), normals: Vec::new(), tangents: Vec::new() };
    for k in 0..=n {
        let (p, seg, t) = line.at(len * k as f64 / n as f64);
        row.points.push(p);
        row.normals.push(normal_in_face(s, line.faces[seg], p));
        row.tangents.push(t);
    }
    row
}

/// The surface's interpolated unit normal at `p`, a point of face `f`.
fn normal_in_face(s: &Surface, f: u32, p: DVec3) -> DVec3 {
    let [a, b, c] = s.triangles[f as usize].map(|v| s.positions[v as usize]);
    s.normal_at(f as usize, closest_on_triangle(p, a, b, c))
}

/// Where the normal planes of `prev` meet one polyline: for each base point (in order) the arc
/// parameter on the line, the point and its segment, or None.
type Crossings = Vec<Option<(f64, DVec3, usize)>>;

fn crossings(prev: &BaseRow, line: &Polyline, reach: f64) -> Crossings {
    // Rows end on the surface's edge, and so do the level sets: a plane through an end point
    // must not miss the next curve's end by a rounding error.
    let eps = 1e-9 * reach;
    prev.points
        .iter()
        .zip(&prev.tangents)
        .map(|(&g, &t)| {
            let mut best: Option<(f64, DVec3, usize, f64)> = None;
            for k in 0..line.points.len() - 1 {
                let (p, q) = (line.points[k], line.points[k + 1]);
                let (sp, sq) = ((p - g).dot(t), (q - g).dot(t));
                if (sp > eps && sq > eps) || (sp < -eps && sq < -eps) {
                    continue;
                }
                let u = if sp != sq { (sp / (sp - sq)).clamp(0.0, 1.0) } else { 0.0 };
                let x = p + u * (q - p);
                let dist = x.distance(g);
                if dist <= reach && best.map_or(true, |b| dist < b.3) {
                    best = Some((line.arc[k] + u * (line.arc[k + 1] - line.arc[k]), x, k, dist));
                }
            }
            best.map(|(a, x, k, _)| (a, x, k))
        })
        .collect()
}

/// The row on `line` propagated from `prev` (module docs): the longest run of consecutive base
/// points whose crossings advance along the line, plus the extensions at both ends.
fn propagate(s: &Surface, prev: &BaseRow, line: &Polyline, cross: &Crossings, step: f64) -> Option<BaseRow> {
    // Longest run of consecutive j with crossings strictly advancing along the line.
    let (mut best, mut run_start) = ((0usize, 0usize), None::<usize>);
    let mut last_arc = f64::NEG_INFINITY;
    for (k, c) in cross.iter().enumerate() {
        match (c, run_start) {
            (Some((arc, _, _)), Some(start)) if *arc > last_arc => {
                last_arc = *arc;
                if k + 1 - start > best.1 - best.0 {
                    best = (start, k + 1);
                }
            }
            (Some((arc, _, _)), _) => {
                run_start = Some(k);
                last_arc = *arc;
                if best.1 == best.0 {
                    best = (k, k + 1);
                }
            }
            (None, _) => run_start = None,
        }
    }
    let (lo, hi) = best;
    if hi - lo < 2 {
        return None;
    }
    let mut points = Vec::new();
    let mut segs = Vec::new();
    let mut arcs = Vec::new();
    for c in &cross[lo..hi] {
        let (arc, x, k) = c.expect("inside the run");
        points.push(x);
        segs.push(k);
        arcs.push(arc);
    }
    // Remark 1: extend where the line reaches further than the planes.
    let extension = |room: f64| {
        let n = (room / step).round() as usize;
        (n >= 1).then(|| (n, room / n as f64))
    };
    let mut before = Vec::new();
    if let Some((n, h)) = extension(arcs[0]) {
        for k in (1..=n).rev() {
            before.push(arcs[0] - h * k as f64);
        }
    }
    let mut after = Vec::new();
    let last = *arcs.last().expect("two points");
    if let Some((n, h)) = extension(line.length() - last) {
        for k in 1..=n {
            after.push(last + h * k as f64);
        }
    }
    let mut row = BaseRow {
        first_j: prev.first_j + lo as i64 - before.len() as i64,
        points: Vec::new(),
        normals: Vec::new(),
        tangents: Vec::new(),
    };
    let mut push = |p: DVec3, seg: usize| {
        row.points.push(p);
        row.normals.push(normal_in_face(s, line.faces[seg], p));
        row.tangents.push(line.tangent(seg));
    };
    for &a in &before {
        let (p, seg, _) = line.at(a);
        push(p, seg);
    }
    for (&p, &seg) in points.iter().zip(&segs) {
        push(p, seg);
    }
    for &a in &after {
        let (p, seg, _) = line.at(a);
        push(p, seg);
    }
    Some(row)
}

/// The mean initial axis length (eq. 7) between `prev` and the crossings, or None when fewer
/// than two base points meet the line.
fn mean_axis(
    s: &Surface,
    prev: &BaseRow,
    line: &Polyline,
    cross: &Crossings,
    f: &SphereFamily,
    side: Side,
) -> Option<f64> {
    // The known row carries the tip spheres when marching up, the top spheres when marching down.
    let (r_known, r_new) = match side {
        Side::Up => (f.r1_mm, f.r2_mm),
        Side::Down => (f.r2_mm, f.r1_mm),
    };
    let (mut sum, mut n) = (0.0, 0usize);
    for (k, c) in cross.iter().enumerate() {
        if let Some((_, x, seg)) = c {
            let a = prev.points[k] + r_known * prev.normals[k];
            let b = *x + r_new * normal_in_face(s, line.faces[*seg], *x);
            sum += a.distance(b);
            n += 1;
        }
    }
    (n >= 2).then(|| sum / n as f64)
}

/// Which way [`next_level`] marches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Up,
    Down,
}

/// The level set at `level` that the planes of `prev` meet most, with its crossings.
fn best_line(input: &GuideInput, level: f64, prev: &BaseRow) -> Option<(Polyline, Crossings)> {
    let reach = REACH * input.family.length_mm;
    level_set(input.surface, &input.field.values, level, input.direction)
        .into_iter()
        .map(|line| {
            let c = crossings(prev, &line, reach);
            (line, c)
        })
        .max_by_key(|(_, c)| c.iter().filter(|x| x.is_some()).count())
        .filter(|(_, c)| c.iter().filter(|x| x.is_some()).count() >= 2)
}

/// The next level beyond `prev_level` (above or below) whose initial axes are L long on average,
/// with its curve and row; None when the surface ends first.
fn next_level(input: &GuideInput, prev_level: f64, prev: &BaseRow, side: Side) -> Option<(f64, Polyline, BaseRow)> {
    let f = &input.family;
    let d = f.contact_length_mm;
    let sign = if side == Side::Up { 1.0 } else { -1.0 };
    // The excess as a function of the distance t ≥ 0 from the previous level.
    let excess = |t: f64| -> Option<(f64, Polyline, Crossings)> {
        let (line, cross) = best_line(input, prev_level + sign * t, prev)?;
        let mean = mean_axis(input.surface, prev, &line, &cross, f, side)?;
        Some((mean - f.length_mm, line, cross))
    };
    let room = if side == Side::Up { input.field.max - prev_level } else { prev_level - input.field.min };
    // Bracket: the excess is negative just beyond the previous level (axes of length ≈ |Δr|).
    let (mut lo, mut f_lo) = (0.0, -(f.length_mm - f.delta_r_mm.abs()));
    let mut hi = None;
    for k in 1..=16 {
        let t = d * (0.5 + 0.25 * k as f64);
        if t >= room {
            let last = room - START_OFFSET * d;
            match excess(last) {
                Some((e, _, _)) if e >= 0.0 => hi = Some((last, e)),
                _ => return None,
            }
            break;
        }
        match excess(t) {
            Some((e, _, _)) if e >= 0.0 => {
                hi = Some((t, e));
                break;
            }
            Some((e, _, _)) => (lo, f_lo) = (t, e),
            None => return None,
        }
    }
    let (mut hi, mut f_hi) = hi?;
    // Illinois (regula falsi with halving of the stale end's value).
    let mut stale = 0i8;
    let mut best = (hi, f_hi);
    for _ in 0..200 {
        if hi - lo <= LEVEL_TOLERANCE * d {
            break;
        }
        let mut t = hi - f_hi * (hi - lo) / (f_hi - f_lo);
        if !(t > lo && t < hi) {
            t = 0.5 * (lo + hi);
        }
        let Some((e, _, _)) = excess(t) else {
            // The level set lost its crossings inside the bracket: shrink from beyond.
            hi = t;
            continue;
        };
        if e.abs() < best.1.abs() {
            best = (t, e);
        }
        if e == 0.0 {
            break;
        }
        if e > 0.0 {
            (hi, f_hi) = (t, e);
            if stale == 1 {
                f_lo *= 0.5;
            }
            stale = 1;
        } else {
            (lo, f_lo) = (t, e);
            if stale == -1 {
                f_hi *= 0.5;
            }
            stale = -1;
        }
    }
    let (_, line, cross) = excess(best.0)?;
    let row = propagate(input.surface, prev, &line, &cross, input.step_mm)?;
    Some((prev_level + sign * best.0, line, row))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flank::field::guide_field;
    use crate::flank::tool::ConeTool;
    use crate::mesh::{from_triangles, MeshOptions};

    #[test]
    fn plane_rows_are_d_apart_and_aligned() {
        let s =
            from_triangles(&crate::fixtures::flank_plane(60.0, 50.0, 12, 10), &MeshOptions::default()).unwrap().surface;
        let field = guide_field(&s, DVec3::X).unwrap();
        let family = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 2.0, flute_length_mm: 12.0 }.spheres().unwrap();
        let g = guiding_curves(&GuideInput {
            surface: &s,
            field: &field,
            direction: DVec3::X,
            family,
            strips: None,
            step_mm: 6.0,
        })
        .unwrap();
        let d = family.contact_length_mm;
        assert_eq!(g.levels.len(), (50.0 / d) as usize + 1);
        // Centred: equal bands left at both sides.
        let (lo, hi) = (g.levels[0] - field.min, field.max - g.levels.last().unwrap());
        assert!((lo - hi).abs() < 1e-9, "{lo} vs {hi}");
        for w in g.levels.windows(2) {
            assert!((w[1] - w[0] - d).abs() < 1e-9, "{}", w[1] - w[0]);
        }
        for (i, row) in g.rows.iter().enumerate() {
            assert_eq!((row.first_j, row.points.len()), (0, 11), "row {i}");
            for (k, p) in row.points.iter().enumerate() {
                assert!((p.x - (-30.0 + 6.0 * k as f64)).abs() < 1e-9, "row {i} point {k}: {p}");
                assert!(row.normals[k].distance(DVec3::Z) < 1e-15);
            }
        }
        assert!(matches!(
            guiding_curves(&GuideInput {
                surface: &s,
                field: &field,
                direction: DVec3::X,
                family,
                strips: Some(20),
                step_mm: 6.0
            }),
            Err(FlankError::StripsDoNotFit { requested: 20, .. })
        ));
    }

    /// A plane whose edge is slanted against the direction: strips of different lengths
    /// (Remark 1), each row one contiguous run, its points on the curve's level.
    #[test]
    fn ragged_ends_on_a_trapezoid() {
        let mut mesh = crate::fixtures::flank_plane(60.0, 40.0, 24, 16);
        for p in &mut mesh.positions {
            // Shear x by y: the left and right edges lean, so the upper curves are longer.
            p.x *= 1.0 + (p.y + 20.0) / 40.0;
        }
        let s = from_triangles(&mesh, &MeshOptions::default()).unwrap().surface;
        let field = guide_field(&s, DVec3::X).unwrap();
        let family = ConeTool { tip_radius_mm: 1.0, top_radius_mm: 1.5, flute_length_mm: 9.0 }.spheres().unwrap();
        let g = guiding_curves(&GuideInput {
            surface: &s,
            field: &field,
            direction: DVec3::X,
            family,
            strips: None,
            step_mm: 5.0,
        })
        .unwrap();
        assert!(g.rows.len() >= 4);
        for w in g.rows.windows(2) {
            assert!(w[1].points.len() > w[0].points.len(), "longer curves get more base points");
            assert!(w[1].first_j < w[0].first_j && w[1].last_j() > w[0].last_j());
        }
        for (row, level) in g.rows.iter().zip(&g.levels) {
            for p in &row.points {
                assert!((p.y - (level - (field.values[0] - s.positions[0].y))).abs() < 1e-9);
            }
        }
    }
}
