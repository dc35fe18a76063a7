//! A bounding-volume hierarchy over boxes, shared by the verifier's swept volume (capsules) and
//! the toolpath's facet queries ([`crate::mesh::nearest`]): median splits of the items'
//! midpoints along the longest axis of their bounds (ties by id, so the tree is deterministic),
//! down to leaves of at most [`LEAF_SIZE`] items. Each user keeps its items in leaf order and
//! prunes its own traversal: [`Walk`] visits the leaves depth first, left child first.
//!
//! Nodes are stored depth first: a node's left child follows it, `right` is the right child; a
//! leaf (`count > 0`) holds the slots `start..start + count` of the leaf order.

use glam::DVec3;
use std::ops::Range;

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
///
/// The shape of a subtree depends only on its item count, so both halves of a split know where
/// their nodes go before either is built: large subtrees are built side by side into their own
/// parts of the node array, and the tree is the same on any number of threads.
pub(crate) fn build(bounds: &[(DVec3, DVec3)], mids: &[DVec3]) -> (Vec<Node>, Vec<u32>) {
    let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
    if bounds.is_empty() {
        return (Vec::new(), order);
    }
    let empty = Node { lo: DVec3::ZERO, hi: DVec3::ZERO, start: 0, count: 0, right: 0 };
    let mut nodes = vec![empty; node_count(bounds.len())];
    node(bounds, mids, &mut order, 0, 0, &mut nodes);
    (nodes, order)
}

/// Nodes of a subtree over `m ≥ 1` items (leaves of at most [`LEAF_SIZE`], halves of
/// `m / 2` and `m − m / 2`). Repeated halving leaves sizes ⌊m/2^d⌋ and ⌈m/2^d⌉ at depth d, the
/// larger `m mod 2^d` times; every node above the last split level e − 1 is split, so the leaves
/// are counted there.
fn node_count(m: usize) -> usize {
    if m <= LEAF_SIZE {
        return 1;
    }
    // e − 1: the deepest level whose largest node is still split.
    let mut d = 0;
    while m.div_ceil(1 << (d + 1)) > LEAF_SIZE {
        d += 1;
    }
    let (n, s, r) = (1usize << d, m >> d, m % (1 << d));
    let leaves_of = |size: usize| if size > LEAF_SIZE { 2 } else { 1 };
    let leaves = (n - r) * leaves_of(s) + r * leaves_of(s + 1);
    2 * leaves - 1
}

/// Subtrees with more items than this are built beside their sibling.
const PARALLEL_ITEMS: usize = 8192;

/// Builds the subtree over `ids` (slots from `start`) into `out`, its nodes, whose first is the
/// node with absolute index `index`.
fn node(bounds: &[(DVec3, DVec3)], mids: &[DVec3], ids: &mut [u32], start: usize, index: usize, out: &mut [Node]) {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut mlo, mut mhi) = (lo, hi);
    for &i in ids.iter() {
        let (blo, bhi) = bounds[i as usize];
        lo = lo.min(blo);
        hi = hi.max(bhi);
        mlo = mlo.min(mids[i as usize]);
        mhi = mhi.max(mids[i as usize]);
    }
    out[0] = Node { lo, hi, start: start as u32, count: 0, right: 0 };
    if ids.len() <= LEAF_SIZE {
        out[0].count = ids.len() as u32;
        return;
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
    let left_nodes = node_count(half);
    out[0].right = (index + 1 + left_nodes) as u32;
    let (left_ids, right_ids) = ids.split_at_mut(half);
    let (left_out, right_out) = out[1..].split_at_mut(left_nodes);
    if half > PARALLEL_ITEMS {
        crate::par::join(
            || node(bounds, mids, left_ids, start, index + 1, left_out),
            || node(bounds, mids, right_ids, start + half, index + 1 + left_nodes, right_out),
        );
    } else {
        node(bounds, mids, left_ids, start, index + 1, left_out);
        node(bounds, mids, right_ids, start + half, index + 1 + left_nodes, right_out);
    }
}

/// A traversal stack without allocation. The tree is balanced (median splits), so its depth is
/// at most 32 for any u32 face count, and a depth-first traversal keeps at most one pending
/// sibling per level.
pub(crate) struct Stack<T: Copy> {
    items: [T; 64],
    len: usize,
}

impl<T: Copy> Stack<T> {
    pub(crate) fn new(fill: T) -> Self {
        Self { items: [fill; 64], len: 0 }
    }

    pub(crate) fn push(&mut self, item: T) {
        self.items[self.len] = item;
        self.len += 1;
    }

    pub(crate) fn pop(&mut self) -> Option<T> {
        self.len = self.len.checked_sub(1)?;
        Some(self.items[self.len])
    }
}

/// A depth-first walk of a tree from [`build`], left child first, that yields the slots of the
/// leaves whose box, and no ancestor's, `prune` rejects. A node is tested when it is reached,
/// so a bound the leaves before it have tightened applies to it.
pub(crate) struct Walk {
    stack: Stack<u32>,
}

impl Walk {
    pub(crate) fn new(nodes: &[Node]) -> Self {
        let mut stack = Stack::new(0u32);
        if !nodes.is_empty() {
            stack.push(0);
        }
        Walk { stack }
    }

    /// The next leaf's slots, `start..start + count`.
    pub(crate) fn next_leaf(&mut self, nodes: &[Node], mut prune: impl FnMut(&Node) -> bool) -> Option<Range<usize>> {
        self.next_leaf_at(nodes, |_, node| prune(node))
    }

    /// [`Walk::next_leaf`] with the pruning test given the node's index too (for bounds kept
    /// beside the nodes).
    pub(crate) fn next_leaf_at(
        &mut self,
        nodes: &[Node],
        mut prune: impl FnMut(usize, &Node) -> bool,
    ) -> Option<Range<usize>> {
        while let Some(index) = self.stack.pop() {
            let node = &nodes[index as usize];
            if prune(index as usize, node) {
                continue;
            }
            if node.count == 0 {
                self.stack.push(node.right);
                self.stack.push(index + 1);
                continue;
            }
            return Some(node.start as usize..(node.start + node.count) as usize);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count by building the shape.
    fn nodes_by_recursion(m: usize) -> usize {
        if m <= LEAF_SIZE {
            1
        } else {
            1 + nodes_by_recursion(m / 2) + nodes_by_recursion(m - m / 2)
        }
    }

    #[test]
    fn node_count_matches_the_recursive_shape() {
        for m in (1..5000).chain([8191, 8192, 8193, 98_765, 300_001]) {
            assert_eq!(node_count(m), nodes_by_recursion(m), "{m} items");
        }
    }

    #[cfg(not(target_arch = "wasm32"))] // rayon is native only
    #[test]
    fn the_tree_is_the_same_on_one_thread_and_on_several() {
        // Above the parallel threshold, with ties on the split axis.
        let n = 3 * PARALLEL_ITEMS + 17;
        let mids: Vec<DVec3> =
            (0..n).map(|i| DVec3::new((i % 97) as f64, ((i * 7) % 13) as f64, (i / 500) as f64)).collect();
        let bounds: Vec<(DVec3, DVec3)> =
            mids.iter().map(|&m| (m - DVec3::splat(0.5), m + DVec3::splat(0.5))).collect();
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| build(&bounds, &mids));
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| build(&bounds, &mids));
        assert_eq!(one.1, three.1);
        assert_eq!(one.0.len(), node_count(n));
        for (a, b) in one.0.iter().zip(&three.0) {
            assert_eq!((a.lo, a.hi, a.start, a.count, a.right), (b.lo, b.hi, b.start, b.count, b.right));
        }
        // Every item in exactly one leaf, leaves in slot order.
        let mut next = 0;
        for node in one.0.iter().filter(|n| n.count > 0) {
            assert_eq!(node.start as usize, next);
            next += node.count as usize;
        }
        assert_eq!(next, n);
    }
}
