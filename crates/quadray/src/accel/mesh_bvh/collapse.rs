//! Collapsing obvhs' BVH2 (built down to single triangles) into quadray's 4-wide nodes and
//! four-triangle leaf blocks, without recursion (trees of degenerate input can be deep).

use super::{EMPTY, LEAF, LEAF_COUNT_BITS, Node4};
use crate::accel::tri4::Tri4;
use obvhs::bvh2::Bvh2;

/// An empty Node4 (no child is ever entered).
const EMPTY_NODE: Node4 = Node4 {
    bounds: [
        [f32::INFINITY; 4],
        [f32::NEG_INFINITY; 4],
        [f32::INFINITY; 4],
        [f32::NEG_INFINITY; 4],
        [f32::INFINITY; 4],
        [f32::NEG_INFINITY; 4],
    ],
    children: [EMPTY; 4],
};

/// Number of triangles under each BVH2 node, without recursion (trees of degenerate input can be
/// deep): nodes in pre-order, then summed in reverse.
fn subtree_counts(bvh2: &Bvh2) -> Vec<u32> {
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
            node.prim_count
        } else {
            counts[node.first_index as usize] + counts[node.first_index as usize + 1]
        };
    }
    counts
}

/// The BVH2's triangles under node `index`, in tree order.
fn subtree_triangles(bvh2: &Bvh2, index: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let mut stack = vec![index];
    while let Some(i) = stack.pop() {
        let node = &bvh2.nodes[i as usize];
        if node.is_leaf() {
            let first = node.first_index as usize;
            out.extend(&bvh2.primitive_indices[first..first + node.prim_count as usize]);
        } else {
            stack.extend([node.first_index + 1, node.first_index]);
        }
    }
    out
}

/// Collapses a BVH2 (built down to single triangles) into Node4s and full Tri4 leaves: every
/// subtree of at most four triangles becomes one leaf block, and each wide node takes the four
/// largest subtrees below a BVH2 node (Embree's BVH4 collapse). Iterative, for deep trees.
pub(super) fn collapse(bvh2: &Bvh2, triangles: &[[[f32; 3]; 3]]) -> (Vec<Node4>, Vec<Tri4>) {
    let counts = subtree_counts(bvh2);
    let is_leaf = |i: u32| counts[i as usize] <= 4;
    // The BVH2 nodes a wide node over BVH2 node `index` takes as children: open the largest
    // internal one until there are four.
    let children_of = |index: u32| {
        let node = &bvh2.nodes[index as usize];
        let mut kids = vec![node.first_index, node.first_index + 1];
        while kids.len() < 4 {
            let area = |k: u32| bvh2.nodes[k as usize].aabb().half_area();
            let open = kids
                .iter()
                .enumerate()
                .filter(|&(_, &k)| !is_leaf(k))
                .max_by(|a, b| area(*a.1).total_cmp(&area(*b.1)))
                .map(|(i, _)| i);
            let Some(i) = open else { break };
            let k = kids.swap_remove(i);
            let first = bvh2.nodes[k as usize].first_index;
            kids.extend([first, first + 1]);
        }
        kids
    };
    let mut nodes = vec![EMPTY_NODE];
    let mut blocks = Vec::new();
    // (BVH2 node, wide node it becomes a child of, lane there). The root wide node takes the
    // BVH2 root's children (or the root itself when it is a single leaf).
    let mut work: Vec<(u32, usize, usize)> = if is_leaf(0) {
        vec![(0, 0, 0)]
    } else {
        children_of(0)
            .iter()
            .enumerate()
            .map(|(l, &k)| (k, 0, l))
            .collect()
    };
    while let Some((index, parent, lane)) = work.pop() {
        let reference = if is_leaf(index) {
            let lanes: Vec<([[f32; 3]; 3], u32)> = subtree_triangles(bvh2, index)
                .iter()
                .map(|&p| (triangles[p as usize], p))
                .collect();
            blocks.push(Tri4::new(&lanes));
            // Block numbers have 28 bits: 2^28 blocks would be 170 GB of leaves.
            assert!(
                blocks.len() <= 1 << 28,
                "a mesh BVH holds at most 2^30 triangles"
            );
            LEAF | ((blocks.len() as u32 - 1) << LEAF_COUNT_BITS) | 1
        } else {
            let slot = nodes.len();
            nodes.push(EMPTY_NODE);
            work.extend(
                children_of(index)
                    .iter()
                    .enumerate()
                    .map(|(l, &k)| (k, slot, l)),
            );
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
    (nodes, blocks)
}
