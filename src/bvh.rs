//! A bounding-volume hierarchy over boxes, shared by the verifier's swept volume (capsules) and
//! the toolpath's facet queries ([`crate::mesh::nearest`]): median splits of the items'
//! midpoints along the longest axis of their bounds (ties by id, so the tree is deterministic),
//! down to leaves of at most [`LEAF_SIZE`] items. Each user keeps its items in leaf order and
//! writes its own pruned traversal.
//!
//! Nodes are stored depth first: a node's left child follows it, `right` is the right child; a
//! leaf (`count > 0`) holds the slots `start..start + count` of the leaf order.

use glam::DVec3;

pub(crate) const LEAF_SIZE: usize = 4;

#[derive(Clone, Copy, Debug)]
pub(crate) struct Node {
    pub lo: DVec3,
    pub hi: DVec3,
    pub start: u32,
    pub count: u32,
    pub right: u32,
}

impl Node {
    /// Squared distance from `p` to the node's box (0 inside).
    #[inline]
    pub fn distance2(&self, p: DVec3) -> f64 {
        let d = (self.lo - p).max(p - self.hi).max(DVec3::ZERO);
        d.dot(d)
    }
}

/// The tree over items with boxes `bounds[i] = (lo, hi)` and midpoints `mids[i]`: its nodes and
/// the leaf order (`order[slot]` = item id).
pub(crate) fn build(bounds: &[(DVec3, DVec3)], mids: &[DVec3]) -> (Vec<Node>, Vec<u32>) {
    let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
    let mut nodes = Vec::with_capacity(2 * bounds.len() / LEAF_SIZE + 1);
    if !bounds.is_empty() {
        node(bounds, mids, &mut order, 0, &mut nodes);
    }
    (nodes, order)
}

fn node(bounds: &[(DVec3, DVec3)], mids: &[DVec3], ids: &mut [u32], start: usize, nodes: &mut Vec<Node>) -> u32 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut mlo, mut mhi) = (lo, hi);
    for &i in ids.iter() {
        let (blo, bhi) = bounds[i as usize];
        lo = lo.min(blo);
        hi = hi.max(bhi);
        mlo = mlo.min(mids[i as usize]);
        mhi = mhi.max(mids[i as usize]);
    }
    let index = nodes.len() as u32;
    nodes.push(Node { lo, hi, start: start as u32, count: 0, right: 0 });
    if ids.len() <= LEAF_SIZE {
        nodes[index as usize].count = ids.len() as u32;
        return index;
    }
    let e = mhi - mlo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let half = ids.len() / 2;
    ids.select_nth_unstable_by(half, |&a, &b| {
        mids[a as usize][axis].total_cmp(&mids[b as usize][axis]).then(a.cmp(&b))
    });
    let (left, right) = ids.split_at_mut(half);
    node(bounds, mids, left, start, nodes);
    let r = node(bounds, mids, right, start + half, nodes);
    nodes[index as usize].right = r;
    index
}
