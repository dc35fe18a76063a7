//! Band detection: the selected STEP faces → four-sided faces laid out on a periodic grid
//! (`around` faces round the loop × `across` rows), each with its sides in Coons orientation.
//!
//! Corners. A face is bounded by one loop of one or more edges. Its corners are the loop's
//! vertices where the boundary turns by more than [`CoonsOptions::corner_angle_deg`] (the angle
//! between the incoming and the outgoing edge's 3D tangents); edges meeting tangentially form
//! one side. A face is four-sided when it has no inner bound and exactly four corners. (A loop
//! of four edges with a tangential joint is three-sided: the joint is not a corner.)
//!
//! Layout. Side k of a face runs from corner k to corner k + 1 along its loop. Two faces are
//! neighbours through a side when both sides consist of the same edges. A face's frame is its
//! `base` side (the bottom, t = 0, run with s increasing) and whether its loop is read mirrored
//! (when a shared edge is used in the same direction by both faces, i.e. the file's orientations
//! disagree): bottom = side `base`, right = `base + 1`, top = `base + 2`, left = `base + 3`, the
//! bottom and right run along +s and +t, the top and left against. The first face's frame is
//! tried with base 0, then 1; walking through right sides must come back to it after `around`
//! faces (a closed band), the other faces are reached through shared sides (breadth first, grid
//! coordinates i mod `around`, j), and the grid must be full: `across` rows of `around` faces.

use super::{CoonsError, CoonsOptions};
use crate::step::geom::Curve;
use crate::step::model::{Face, Model};
use glam::DVec3;
use std::collections::{BTreeMap, VecDeque};

/// One edge as a side runs along it: its curve from parameter `from` to `to` (either order).
#[derive(Clone, Debug)]
pub struct Run {
    pub edge: u64,
    pub curve: Curve,
    pub from: f64,
    pub to: f64,
}

impl Run {
    fn reversed(&self) -> Run {
        Run { from: self.to, to: self.from, ..self.clone() }
    }

    /// The unit tangent in the direction of the run at its start (`end` false) or end.
    fn tangent(&self, end: bool) -> DVec3 {
        let t = if end { self.to } else { self.from };
        (self.curve.derivative(t) * (self.to - self.from).signum()).normalize_or_zero()
    }
}

/// A side of a face: its runs in order.
pub type Side = Vec<Run>;

fn reversed(side: &Side) -> Side {
    side.iter().rev().map(Run::reversed).collect()
}

/// One face of the band: its place and its four sides as the Coons map reads them.
#[derive(Clone, Debug)]
pub struct BandFace {
    pub id: u64,
    /// Index into `Model::faces`.
    pub index: usize,
    /// Column (round the loop) and row.
    pub i: usize,
    pub j: usize,
    /// Bottom (t = 0) and top (t = 1) with s increasing, left (s = 0) and right (s = 1) with t
    /// increasing.
    pub bottom: Side,
    pub top: Side,
    pub left: Side,
    pub right: Side,
}

/// The selected faces as a band: `faces[i + around * j]`.
#[derive(Clone, Debug)]
pub struct Band {
    pub around: usize,
    pub across: usize,
    pub faces: Vec<BandFace>,
}

/// The runs of a face's outer loop split at its corners (side k from corner k).
fn sides_of(model: &Model, f: &Face, corner_deg: f64) -> Result<Vec<Side>, CoonsError> {
    if f.bounds.len() != 1 {
        return Err(CoonsError::NotFourSided {
            face: f.id,
            reason: format!("it has {} inner bound(s) (holes)", f.bounds.len() - 1),
        });
    }
    let mut runs = Vec::new();
    for &(e, forward) in &f.bounds[0].edges {
        let edge = &model.edges[&e];
        let (a, b) = (model.vertices[&edge.start], model.vertices[&edge.end]);
        let (from, to) = if edge.same_sense { (a, b) } else { (b, a) };
        let (t0, t1) = edge.curve.span(from, to, edge.start == edge.end);
        let (from, to) = if edge.same_sense == forward { (t0, t1) } else { (t1, t0) };
        runs.push(Run { edge: e, curve: edge.curve.clone(), from, to });
    }
    let n = runs.len();
    let cos_limit = corner_deg.to_radians().cos();
    let corners: Vec<usize> =
        (0..n).filter(|&k| runs[(k + n - 1) % n].tangent(true).dot(runs[k].tangent(false)) < cos_limit).collect();
    if corners.len() != 4 {
        return Err(CoonsError::NotFourSided {
            face: f.id,
            reason: format!(
                "its loop of {n} edge(s) turns by more than {corner_deg}° at {} vertices, not 4",
                corners.len()
            ),
        });
    }
    Ok((0..4)
        .map(|c| {
            let (a, b) = (corners[c], corners[(c + 1) % 4]);
            let len = (b + n - a) % n;
            let len = if len == 0 { n } else { len };
            (0..len).map(|k| runs[(a + k) % n].clone()).collect()
        })
        .collect())
}

/// The edges of a side as a key (sorted ids).
fn key(side: &Side) -> Vec<u64> {
    let mut k: Vec<u64> = side.iter().map(|r| r.edge).collect();
    k.sort_unstable();
    k
}

/// Whether two sides with the same edges run the same way (their first runs, matched by edge).
fn same_direction(a: &Side, b: &Side) -> bool {
    let r = &a[0];
    let s = b.iter().find(|s| s.edge == r.edge).expect("same edges");
    (r.to - r.from).signum() == (s.to - s.from).signum()
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Frame {
    base: usize,
    mirrored: bool,
}

/// Sides of a face read with `frame`: [bottom, right, top, left] in loop direction.
fn framed(sides: &[Side], frame: Frame) -> [Side; 4] {
    let loop_sides: Vec<Side> =
        if frame.mirrored { sides.iter().rev().map(reversed).collect() } else { sides.to_vec() };
    [0, 1, 2, 3].map(|r| loop_sides[(frame.base + r) % 4].clone())
}

/// One four-sided face on its own, side 0 as its bottom (for checking its Coons map alone).
pub fn single(model: &Model, id: u64, o: &CoonsOptions) -> Result<BandFace, CoonsError> {
    let index = model.faces.iter().position(|f| f.id == id).ok_or(CoonsError::UnknownFace { face: id })?;
    let sides = sides_of(model, &model.faces[index], o.corner_angle_deg)?;
    let [bottom, right, top, left] = framed(&sides, Frame { base: 0, mirrored: false });
    Ok(BandFace { id, index, i: 0, j: 0, bottom, right, top: reversed(&top), left: reversed(&left) })
}

/// Role r (0 bottom, 1 right, 2 top, 3 left) and the grid step across it.
const STEP: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

/// Detects the band (see the module docs).
pub fn detect(model: &Model, selected: &[u64], o: &CoonsOptions) -> Result<Band, CoonsError> {
    if selected.is_empty() {
        return Err(CoonsError::NoFaces);
    }
    let mut index = Vec::new();
    for id in selected {
        let k = model.faces.iter().position(|f| f.id == *id).ok_or(CoonsError::UnknownFace { face: *id })?;
        if !index.contains(&k) {
            index.push(k);
        }
    }
    let sides: Vec<Vec<Side>> =
        index.iter().map(|&k| sides_of(model, &model.faces[k], o.corner_angle_deg)).collect::<Result<_, _>>()?;
    let mut by_key: BTreeMap<Vec<u64>, Vec<(usize, usize)>> = BTreeMap::new();
    for (f, s) in sides.iter().enumerate() {
        for (k, side) in s.iter().enumerate() {
            by_key.entry(key(side)).or_default().push((f, k));
        }
    }
    // The neighbour across role `role` of face `f` read with `frame`, and its frame.
    let neighbour = |f: usize, frame: Frame, role: usize| -> Option<(usize, Frame)> {
        let mine = &framed(&sides[f], frame)[role];
        let users = by_key.get(&key(mine))?;
        let &(g, k) = users.iter().find(|&&(g, _)| g != f)?;
        // Read mirrored when the shared side runs the same way in both loops.
        let mirrored = same_direction(mine, &sides[g][k]);
        let k = if mirrored { 3 - k } else { k };
        // The neighbour's role for this side is the opposite one: base = k − opposite role.
        let base = (k + 4 - (role + 2) % 4) % 4;
        Some((g, Frame { base, mirrored }))
    };
    // The loop round the band, through right sides.
    let mut start = None;
    for base in 0..2 {
        let first = Frame { base, mirrored: false };
        let (mut f, mut frame, mut count) = (0, first, 0);
        while let Some((g, next)) = neighbour(f, frame, 1) {
            count += 1;
            if g == 0 {
                if next == first {
                    start = Some((first, count));
                }
                break;
            }
            if count > sides.len() {
                break;
            }
            (f, frame) = (g, next);
        }
        if start.is_some() {
            break;
        }
    }
    let Some((first, around)) = start else {
        return Err(CoonsError::NotClosed { face: selected[0] });
    };
    // Breadth first over the shared sides.
    let mut placed: Vec<Option<(i64, i64, Frame)>> = vec![None; sides.len()];
    placed[0] = Some((0, 0, first));
    let mut queue = VecDeque::from([0usize]);
    while let Some(f) = queue.pop_front() {
        let (i, j, frame) = placed[f].expect("queued faces are placed");
        for (role, (di, dj)) in STEP.iter().enumerate() {
            let Some((g, next)) = neighbour(f, frame, role) else { continue };
            let at = ((i + di).rem_euclid(around as i64), j + dj, next);
            match placed[g] {
                None => {
                    placed[g] = Some(at);
                    queue.push_back(g);
                }
                Some(p) if p == at => {}
                Some(_) => {
                    return Err(CoonsError::NotABand {
                        face: model.faces[index[g]].id,
                        reason: "its place in the grid is ambiguous (the faces do not form rows of a band)".into(),
                    })
                }
            }
        }
    }
    if let Some(g) = placed.iter().position(|p| p.is_none()) {
        return Err(CoonsError::NotABand {
            face: model.faces[index[g]].id,
            reason: "it shares no side with the band's other faces".into(),
        });
    }
    let jmin = placed.iter().flatten().map(|p| p.1).min().unwrap_or(0);
    let jmax = placed.iter().flatten().map(|p| p.1).max().unwrap_or(0);
    let across = (jmax - jmin + 1) as usize;
    let mut grid: Vec<Option<BandFace>> = vec![None; around * across];
    for (f, p) in placed.iter().enumerate() {
        let (i, j, frame) = p.expect("all placed");
        let (i, j) = (i as usize, (j - jmin) as usize);
        let cell = &mut grid[i + around * j];
        if cell.is_some() {
            return Err(CoonsError::NotABand {
                face: model.faces[index[f]].id,
                reason: format!("it takes the place of another face (column {i}, row {j})"),
            });
        }
        let [bottom, right, top, left] = framed(&sides[f], frame);
        *cell = Some(BandFace {
            id: model.faces[index[f]].id,
            index: index[f],
            i,
            j,
            bottom,
            right,
            top: reversed(&top),
            left: reversed(&left),
        });
    }
    if sides.len() != around * across {
        return Err(CoonsError::NotABand {
            face: selected[0],
            reason: format!("{} faces do not fill {across} row(s) of {around} faces round the loop", sides.len()),
        });
    }
    Ok(Band { around, across, faces: grid.into_iter().map(|c| c.expect("a full grid")).collect() })
}
