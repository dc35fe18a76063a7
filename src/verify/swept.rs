//! The volume swept by the ball along the passes (a union of capsules), with a bounding-volume
//! hierarchy over the segments so each probe tests only the segments near it.

use super::capsule::Capsule;
use super::VerifyError;
use crate::bvh::{self, Node};
use crate::num;
use glam::DVec3;

/// Capsules of radius R between consecutive ball centres of every pass, in path order, with a
/// bounding-volume hierarchy over the segments.
///
/// Capsule ids follow the path: pass 0's segments first, in order, then pass 1's, …; a pass of
/// one centre is one degenerate capsule (a sphere). Two ids are consecutive along the path when
/// they differ by one and belong to the same pass.
#[derive(Clone, Debug)]
pub struct SweptVolume {
    radius: f64,
    capsules: Vec<Capsule>,
    pass_of: Vec<u32>,
    bvh: Bvh,
}

/// Why a hierarchy and not a uniform grid: a finishing path is a dense sheet of segments one R
/// above the surface, and a probe needs only the few within R + (scallop) of its point, but a
/// grid visits every segment in a box of about 2R around it — thousands on a dense path (a
/// cell-R grid took 7 s for 100k samples under 87k segments). The hierarchy is traversed nearest
/// box first and pruned by the distance bound, so it touches only the segments that matter.
///
/// The tree is [`crate::bvh`]'s; a leaf's slots index `slots` (capsule copies in leaf order,
/// for locality) and `ids` (their capsule ids).
#[derive(Clone, Debug)]
struct Bvh {
    nodes: Vec<Node>,
    slots: Vec<Capsule>,
    ids: Vec<u32>,
}

/// What one probe of the swept volume found at a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// Smallest `t ≥ 0` with `p + t·n` in the swept volume, `None` beyond the search height.
    pub scallop: Option<f64>,
    /// `R − (distance from p to the nearest segment)`: positive inside a swept ball. `−∞` when
    /// no segment is within R.
    pub depth: f64,
    /// Number of distinct times the path passes over `q = p + h·n` (maximal runs of consecutive
    /// capsules containing q, over all passes).
    pub passes_over: u32,
}

/// Reusable query buffers, one per thread of queries.
#[derive(Clone, Debug)]
pub struct Prober<'a> {
    volume: &'a SweptVolume,
    stack: Vec<(u32, f64, f64)>,
    covering: Vec<u32>,
}

/// Lower bounds the prune test with a margin so rounding never drops the minimising capsule:
/// the result stays bit-identical to testing every capsule.
const PRUNE_MARGIN_REL: f64 = 1e-9;

impl SweptVolume {
    /// Builds the capsules of radius `radius_mm` along `passes` (polylines of ball centres).
    pub fn new(passes: &[Vec<DVec3>], radius_mm: f64) -> Result<Self, VerifyError> {
        if !(radius_mm.is_finite() && radius_mm > 0.0) {
            return Err(VerifyError::InvalidOption(format!("radius_mm must be finite and > 0, got {radius_mm}")));
        }
        let points: usize = passes.iter().map(Vec::len).sum();
        if points == 0 {
            return Err(VerifyError::EmptyPath);
        }
        if points >= u32::MAX as usize {
            return Err(VerifyError::PathTooLong { points });
        }
        let mut capsules = Vec::with_capacity(points);
        let mut pass_of = Vec::with_capacity(points);
        for (k, pass) in passes.iter().enumerate() {
            if pass.is_empty() {
                return Err(VerifyError::EmptyPass { pass: k });
            }
            if let Some(i) = pass.iter().position(|p| !p.is_finite()) {
                return Err(VerifyError::NonFinite { pass: k, index: i });
            }
            if pass.len() == 1 {
                capsules.push(Capsule::new(pass[0], pass[0]));
                pass_of.push(k as u32);
            }
            for w in pass.windows(2) {
                capsules.push(Capsule::new(w[0], w[1]));
                pass_of.push(k as u32);
            }
        }
        let bvh = Bvh::build(&capsules);
        Ok(Self { radius: radius_mm, capsules, pass_of, bvh })
    }

    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Number of capsules (segments, plus one per single-centre pass).
    pub fn segments(&self) -> usize {
        self.capsules.len()
    }

    /// The capsules in path order.
    pub fn capsules(&self) -> &[Capsule] {
        &self.capsules
    }

    /// The pass each capsule belongs to.
    pub fn pass_of(&self) -> &[u32] {
        &self.pass_of
    }

    pub fn prober(&self) -> Prober<'_> {
        Prober { volume: self, stack: Vec::with_capacity(64), covering: Vec::new() }
    }
}

/// Maximal runs of consecutive capsule ids (same pass) in a sorted, duplicate-free list.
pub fn count_runs(sorted_ids: &[u32], pass_of: &[u32]) -> u32 {
    let mut runs = 0;
    for (i, &c) in sorted_ids.iter().enumerate() {
        let continues = i > 0 && {
            let prev = sorted_ids[i - 1];
            c == prev + 1 && pass_of[c as usize] == pass_of[prev as usize]
        };
        if !continues {
            runs += 1;
        }
    }
    runs
}

impl Bvh {
    fn build(capsules: &[Capsule]) -> Self {
        let bounds: Vec<(DVec3, DVec3)> = capsules.iter().map(|c| (c.a.min(c.b), c.a.max(c.b))).collect();
        let mids: Vec<DVec3> = capsules.iter().map(|c| 0.5 * (c.a + c.b)).collect();
        let (nodes, ids) = bvh::build(&bounds, &mids);
        let slots = ids.iter().map(|&i| capsules[i as usize]).collect();
        Self { nodes, slots, ids }
    }
}

impl<'a> Prober<'a> {
    /// Probes the swept volume at the surface point `p` with unit normal `n` (towards the tool):
    /// the scallop (first entry along the normal, searched up to `max_t`), the depth of `p`
    /// inside the nearest ball, and how many times the path passes over `q = p + h·n`.
    ///
    /// One traversal serves the three: a node is opened when it may hold a capsule containing q
    /// (box within R of q) or one the ray enters before the best entry so far (box within
    /// R + best of p, since an entry t needs distance(p) ≤ R + t); that also covers every
    /// capsule within R of p.
    pub fn probe(&mut self, p: DVec3, n: DVec3, h: f64, max_t: f64) -> Probe {
        let r = self.volume.radius;
        let margin = PRUNE_MARGIN_REL * r;
        let bvh = &self.volume.bvh;
        let q = p + h * n;
        let r2 = r * r;
        let mut nearest = f64::INFINITY;
        let mut best = f64::INFINITY;
        self.covering.clear();
        self.stack.clear();
        let root = &bvh.nodes[0];
        self.stack.push((0, root.distance2(p), root.distance2(q)));
        while let Some((index, dp2, dq2)) = self.stack.pop() {
            let reach = r + num::min(best, max_t) + margin;
            if dp2 > reach * reach && dq2 > r2 {
                continue;
            }
            let node = &bvh.nodes[index as usize];
            if node.count > 0 {
                let range = node.start as usize..(node.start + node.count) as usize;
                for (c, &id) in bvh.slots[range.clone()].iter().zip(&bvh.ids[range]) {
                    let dp = c.distance(p);
                    nearest = num::min(nearest, dp);
                    if c.distance(q) <= r {
                        self.covering.push(id);
                    }
                    let bound = num::min(best, max_t);
                    let t = if dp <= r {
                        0.0
                    } else if dp - r > bound + margin {
                        // Cannot beat the best entry (t ≥ distance − R): not solved.
                        f64::INFINITY
                    } else {
                        c.entry_from_outside(p, n, r).unwrap_or(f64::INFINITY)
                    };
                    best = num::min(best, t);
                }
                continue;
            }
            // Nearer child last, so it is taken first and tightens the bound early.
            let (left, right) = (index + 1, node.right);
            let (nl, nr) = (&bvh.nodes[left as usize], &bvh.nodes[right as usize]);
            let (lp, rp) = (nl.distance2(p), nr.distance2(p));
            let (lq, rq) = (nl.distance2(q), nr.distance2(q));
            if lp <= rp {
                self.stack.push((right, rp, rq));
                self.stack.push((left, lp, lq));
            } else {
                self.stack.push((left, lp, lq));
                self.stack.push((right, rp, rq));
            }
        }
        self.covering.sort_unstable();
        Probe {
            scallop: (best <= max_t).then_some(best),
            depth: if nearest <= r { r - nearest } else { f64::NEG_INFINITY },
            passes_over: count_runs(&self.covering, &self.volume.pass_of),
        }
    }
}
