//! Collapsing obvhs' BVH2 (built down to single primitives) into 4-wide nodes over leaves whose
//! contents the caller packs, without recursion (trees of degenerate input can be deep).

use super::{EMPTY_NODE, LEAF, Node4};
use obvhs::bvh2::Bvh2;

/// Most weight one leaf holds: a leaf is a block of four lanes.
pub(in crate::accel) const LEAF_WEIGHT: u32 = 4;

/// Total weight of the primitives under each BVH2 node, without recursion (trees of degenerate
/// input can be deep): nodes in pre-order, then summed in reverse.
fn subtree_weights(bvh2: &Bvh2, weight: &impl Fn(u32) -> u32) -> Vec<u32> {
    let mut order = Vec::with_capacity(bvh2.nodes.len());
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        order.push(i);
        let node = &bvh2.nodes[i as usize];
        if !node.is_leaf() {
            stack.extend([node.first_index, node.first_index + 1]);
        }
    }
    let mut counts = vec![0u32; bvh2.nodes.len()];
    for &i in order.iter().rev() {
        let node = &bvh2.nodes[i as usize];
        counts[i as usize] = if node.is_leaf() {
            let first = node.first_index as usize;
            (bvh2.primitive_indices[first..first + node.prim_count as usize].iter())
                .map(|&p| weight(p))
                .sum()
        } else {
            counts[node.first_index as usize] + counts[node.first_index as usize + 1]
        };
    }
    counts
}

/// The BVH2's primitives under node `index`, in tree order, into `out` (`stack` is scratch).
fn subtree_primitives(bvh2: &Bvh2, index: u32, out: &mut Vec<u32>, stack: &mut Vec<u32>) {
    out.clear();
    stack.clear();
    stack.push(index);
    while let Some(i) = stack.pop() {
        let node = &bvh2.nodes[i as usize];
        if node.is_leaf() {
            let first = node.first_index as usize;
            out.extend(&bvh2.primitive_indices[first..first + node.prim_count as usize]);
        } else {
            stack.extend([node.first_index + 1, node.first_index]);
        }
    }
}

/// Collapses a BVH2 (built down to single primitives) into Node4s: every subtree whose
/// primitives weigh at most [`LEAF_WEIGHT`] together becomes one leaf, whose payload `leaf` makes
/// from the subtree's primitives (it packs them into a block and names it in 31 bits), and each
/// wide node takes the four largest subtrees below a BVH2 node (Embree's BVH4 collapse). A
/// primitive that weighs the whole block is a leaf of its own. Iterative, for deep trees.
pub(in crate::accel) fn collapse(
    bvh2: &Bvh2,
    weight: impl Fn(u32) -> u32,
    mut leaf: impl FnMut(&[u32]) -> u32,
) -> Vec<Node4> {
    let counts = subtree_weights(bvh2, &weight);
    let is_leaf = |i: u32| counts[i as usize] <= LEAF_WEIGHT || bvh2.nodes[i as usize].is_leaf();
    // The BVH2 nodes a wide node over BVH2 node `index` takes as children: open the largest
    // internal one until there are four.
    let children_of = |index: u32| {
        let node = &bvh2.nodes[index as usize];
        let mut kids = [node.first_index, node.first_index + 1, 0, 0];
        let mut n = 2;
        while n < 4 {
            let area = |k: u32| bvh2.nodes[k as usize].aabb().half_area();
            let open = (0..n)
                .filter(|&i| !is_leaf(kids[i]))
                .max_by(|&a, &b| area(kids[a]).total_cmp(&area(kids[b])));
            let Some(i) = open else { break };
            let first = bvh2.nodes[kids[i] as usize].first_index;
            kids[i] = kids[n - 1];
            kids[n - 1] = first;
            kids[n] = first + 1;
            n += 1;
        }
        (kids, n)
    };
    let mut nodes = vec![EMPTY_NODE];
    // (BVH2 node, wide node it becomes a child of, lane there). The root wide node takes the
    // BVH2 root's children (or the root itself when it is a single leaf).
    let mut work: Vec<(u32, usize, usize)> = if is_leaf(0) {
        vec![(0, 0, 0)]
    } else {
        let (kids, n) = children_of(0);
        (kids[..n].iter().enumerate())
            .map(|(l, &k)| (k, 0, l))
            .collect()
    };
    let (mut prims, mut scratch) = (Vec::new(), Vec::new());
    while let Some((index, parent, lane)) = work.pop() {
        let reference = if is_leaf(index) {
            subtree_primitives(bvh2, index, &mut prims, &mut scratch);
            let payload = leaf(&prims);
            debug_assert!(payload & LEAF == 0, "a leaf payload has 31 bits");
            LEAF | payload
        } else {
            let slot = nodes.len();
            nodes.push(EMPTY_NODE);
            let (kids, n) = children_of(index);
            work.extend(kids[..n].iter().enumerate().map(|(l, &k)| (k, slot, l)));
            slot as u32
        };
        let b = *bvh2.nodes[index as usize].aabb();
        let n = &mut nodes[parent];
        for axis in 0..3 {
            n.bounds[2 * axis][lane] = b.min[axis];
            n.bounds[2 * axis + 1][lane] = b.max[axis];
        }
        n.children[lane] = reference;
    }
    nodes
}
