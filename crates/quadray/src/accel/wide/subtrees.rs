//! The one pass over a BVH2 the collapse makes before it builds anything: children first, each
//! node's total weight and number of primitives, every primitive listed in tree order (so a
//! subtree's primitives are one run of the list), and with a plan, each node's choices solved
//! ([`super::sah_plan`]). The root's halves go in parallel for a few levels; below them the walk
//! keeps a stack of its own (trees of degenerate input can be deep).

use super::sah_plan::Plan;
use obvhs::bvh2::Bvh2;
use std::sync::atomic::{AtomicU64, Ordering};

/// Subtrees of at least this many nodes have their weights summed in parallel halves.
const PARALLEL_WEIGHTS: usize = 1 << 14;

/// A subtree's total weight and number of primitives.
type Size = (u32, u32);

/// What the collapse reads of every BVH2 node's subtree, found in one pass over the tree.
pub(super) struct Subtrees {
    /// Per node, the total weight of its primitives (low 32 bits) and their number (high 32).
    sizes: Vec<u64>,
    /// Every primitive in tree order (left subtree first), so a subtree's are one run of them.
    pub(super) primitives: Vec<u32>,
}

impl Subtrees {
    /// The total weight of node `i`'s primitives.
    pub(super) fn weight(&self, i: u32) -> u32 {
        self.sizes[i as usize] as u32
    }

    /// The number of node `i`'s primitives.
    pub(super) fn count(&self, i: u32) -> u32 {
        (self.sizes[i as usize] >> 32) as u32
    }
}

/// Each BVH2 node's subtree ([`Subtrees`]), and with a plan, each node's choices made: one pass
/// over the tree.
pub(super) fn subtrees<const N: usize>(
    bvh2: &Bvh2,
    weight: &(impl Fn(u32) -> u32 + Sync),
    plan: Option<&Plan<N>>,
) -> Subtrees {
    let sizes: Vec<AtomicU64> = (0..bvh2.nodes.len()).map(|_| AtomicU64::new(0)).collect();
    // A node's weight and count, recorded.
    let size = |i: u32, children: Option<(Size, Size)>| {
        let (weight, count) = children.map_or_else(
            || {
                let prims = bvh2_leaf(bvh2, i);
                (prims.iter().map(|&p| weight(p)).sum(), prims.len() as u32)
            },
            |(a, b)| (a.0 + b.0, a.1 + b.1),
        );
        sizes[i as usize].store(weight as u64 | (count as u64) << 32, Ordering::Relaxed);
        (weight, count)
    };
    let pieces = match plan {
        None => fold(bvh2, 0, 0, &size).1,
        Some(plan) => {
            let visit = |i, children: Option<((Size, _), (Size, _))>| {
                let sizes = children.as_ref().map(|(a, b)| (a.0, b.0));
                let (weight, count) = size(i, sizes);
                let costs = plan.solve(i, weight, children.as_ref().map(|(a, b)| (&a.1, &b.1)));
                ((weight, count), costs)
            };
            fold(bvh2, 0, 0, &visit).1
        }
    };
    Subtrees {
        sizes: sizes.into_iter().map(AtomicU64::into_inner).collect(),
        primitives: pieces.concat(),
    }
}

/// The primitives of BVH2 leaf `i`.
fn bvh2_leaf(bvh2: &Bvh2, i: u32) -> &[u32] {
    let node = &bvh2.nodes[i as usize];
    let first = node.first_index as usize;
    &bvh2.primitive_indices[first..first + node.prim_count as usize]
}

/// Folds the BVH2 subtree at `index` children first: `visit` gets a node and its two children's
/// values (none for a leaf) and returns the node's. Returns the root's value and the subtree's
/// primitives in tree order, in pieces. The root's halves go in parallel to a depth of a few
/// levels; below that the fold runs on a stack of its own, without recursion (trees of
/// degenerate input can be deep).
fn fold<T: Copy + Send>(
    bvh2: &Bvh2,
    index: u32,
    depth: u32,
    visit: &(impl Fn(u32, Option<(T, T)>) -> T + Sync),
) -> (T, Vec<Vec<u32>>) {
    let node = &bvh2.nodes[index as usize];
    // Each BVH2 node's subtree has fewer nodes than the tree by about a half a level.
    if !node.is_leaf() && depth < 6 && bvh2.nodes.len() >> depth >= PARALLEL_WEIGHTS {
        let ((a, mut pieces), (b, right)) = rayon::join(
            || fold(bvh2, node.first_index, depth + 1, visit),
            || fold(bvh2, node.first_index + 1, depth + 1, visit),
        );
        pieces.extend(right);
        return (visit(index, Some((a, b))), pieces);
    }
    // Nodes to visit, each with whether its children are done; the values of done subtrees.
    let (mut todo, mut values, mut primitives) = (vec![(index, false)], Vec::new(), Vec::new());
    while let Some((i, children_done)) = todo.pop() {
        let node = &bvh2.nodes[i as usize];
        if node.is_leaf() {
            primitives.extend_from_slice(bvh2_leaf(bvh2, i));
            values.push(visit(i, None));
        } else if children_done {
            let (b, a) = (values.pop(), values.pop());
            let pair = a.zip(b).expect("both children were folded");
            values.push(visit(i, Some(pair)));
        } else {
            todo.extend([
                (i, true),
                (node.first_index + 1, false),
                (node.first_index, false),
            ]);
        }
    }
    let value = values.pop().expect("the subtree was folded");
    (value, vec![primitives])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::build::build_single_leaves;
    use crate::accel::wide::collapse::tests::boxes;

    /// Every BVH2 leaf's primitives are the run of the list its place in the tree gives (a
    /// node's run is its left child's then its right child's), and the sizes add up, on one
    /// and on two threads alike.
    #[test]
    fn a_subtree_s_primitives_are_one_run_of_the_list() {
        let bvh2 = build_single_leaves(&boxes(50_000));
        let weight = |p: u32| 1 + p % 3;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let s = pool.install(|| subtrees::<8>(&bvh2, &weight, None));
            let mut sorted = s.primitives.clone();
            sorted.sort_unstable();
            assert!(sorted.iter().copied().eq(0..50_000));
            assert_eq!(s.count(0), 50_000);
            assert_eq!(s.weight(0), (0..50_000).map(weight).sum::<u32>());
            let mut todo = vec![(0u32, 0u32)];
            while let Some((i, start)) = todo.pop() {
                let node = &bvh2.nodes[i as usize];
                let run = &s.primitives[start as usize..(start + s.count(i)) as usize];
                if node.is_leaf() {
                    assert_eq!(run, bvh2_leaf(&bvh2, i));
                    assert_eq!(s.weight(i), run.iter().map(|&p| weight(p)).sum::<u32>());
                } else {
                    let (l, r) = (node.first_index, node.first_index + 1);
                    assert_eq!(s.count(l) + s.count(r), s.count(i));
                    assert_eq!(s.weight(l) + s.weight(r), s.weight(i));
                    todo.extend([(l, start), (r, start + s.count(l))]);
                }
            }
        }
    }
}
