//! The collapse's plan by cost: which BVH2 subtrees become leaves, and which BVH2 nodes each wide
//! node takes as its children, chosen to minimise the surface area heuristic's cost of the wide
//! tree (the dynamic programme of Ylitie, Karras and Laine 2017, "Efficient incoherent ray
//! traversal on GPUs through compressed wide BVHs", §3.1), with a leaf costed by its blocks.
//!
//! For a BVH2 node n of surface area A(n), C(n, i) is the least cost of covering n's subtree by
//! at most i subtrees, each a leaf or a wide node, that hang from one wide node:
//!
//! - C(n, 1) = min(leaf(n), A(n)·`node` + M(node) + D(n, N)),
//! - C(n, i) = min(C(n, 1), D(n, i)) for 1 < i ≤ N,
//! - D(n, i) = min over 0 < k < i of C(left, k) + C(right, i − k), and ∞ for a BVH2 leaf,
//!
//! where leaf(n) = (A(n)·`block` + M(block))·⌈weight(n) / [`LEAF_WEIGHT`]⌉ for a subtree no
//! heavier than a leaf may be, and ∞ for a heavier one, and M(x) = `per_byte`·A(root)·(bytes of
//! x): memory as a cost every ray pays ([`SahCosts`]). A(n) is the chance, up to one factor for
//! the whole tree, that a ray meeting the root meets n's box, so C(root, 1) is the expected cost
//! of a ray.
//!
//! The costs are computed children first and handed up, not stored: each node keeps one word of
//! choices (whether it is a leaf; for each i > 1 whether one subtree is cheapest, and the k of
//! D(n, i)), which is all the collapse reads.

use super::collapse::LEAF_WEIGHT;
use obvhs::bvh2::Bvh2;
use std::sync::atomic::{AtomicU32, Ordering};

/// What a ray pays, in any one unit, for a wide node's test and for one leaf block's test, and
/// what a byte of memory weighs against that (a Lagrange multiplier: with none, the cheapest
/// trees leave many blocks part empty for a hair of speed).
#[derive(Clone, Copy, Debug)]
pub(in crate::accel) struct SahCosts {
    /// A wide node's test, with the ordering and stack work of its children.
    pub(in crate::accel) node: f32,
    /// One leaf block's test.
    pub(in crate::accel) block: f32,
    /// A byte of nodes or blocks, as a cost every ray pays, in the tests' unit times the root's
    /// area.
    pub(in crate::accel) per_byte: f32,
}

/// The costs [`Plan::solve`] weighs, memory's made absolute.
#[derive(Clone, Copy, Debug)]
struct Weights {
    node: f32,
    block: f32,
    node_memory: f32,
    block_memory: f32,
}

/// C(n, i) for i = 1 to `N`: entry `b` holds C(n, `b` + 1).
pub(super) type Costs<const N: usize> = [f32; N];

/// Bit of a choice word: the node is a leaf.
const LEAF_BIT: u32 = 1;

/// The choices of every BVH2 node (module docs), one word each, made by [`Plan::solve`].
pub(super) struct Plan<'a, const N: usize> {
    bvh2: &'a Bvh2,
    leaf_weight: u32,
    costs: Weights,
    /// What box areas are multiplied by in f64 when f32 cannot hold them ([`Plan::area`]).
    area_scale: Option<f64>,
    /// Bit 0: a leaf. For budget i from 2 to `N`, bit i − 1: one subtree is cheapest; bits
    /// `N` + 3(i − 2) up: k − 1 of D(n, i).
    choices: Box<[AtomicU32]>,
}

/// Half the surface area of `node`'s box, in f64.
fn half_area_f64(node: &obvhs::bvh2::node::Bvh2Node) -> f64 {
    let d = (node.aabb().max - node.aabb().min).as_dvec3();
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// D(n, b + 1) for b ≥ 1 from the costs of n's children, and the k giving it: budget b + 1 as
/// k to the left and b + 1 − k to the right, k from 1 to b, the least k on ties (entry 0 is
/// unused).
fn split_costs<const N: usize>(left: &Costs<N>, right: &Costs<N>) -> (Costs<N>, [u32; N]) {
    let (mut d, mut ks) = ([f32::INFINITY; N], [1u32; N]);
    // Costs never grow with the budget, so a side whose costs are all one (a subtree best a
    // leaf, as most small ones are) settles the choice without the search: with the left flat,
    // the sum never falls as k grows, and k = 1 is least; with the right flat, it never grows,
    // and the least k is where it last fell. Both give the search's sums and k exactly, with
    // N − 1 sums instead of N(N − 1)/2.
    if left[0] == left[N - 1] {
        for b in 1..N {
            d[b] = left[0] + right[b - 1];
        }
    } else if right[0] == right[N - 1] {
        let mut least = 1;
        for b in 1..N {
            d[b] = left[b - 1] + right[0];
            if b > 1 && d[b] < d[b - 1] {
                least = b as u32;
            }
            ks[b] = least;
        }
    } else {
        for b in 1..N {
            for k in 1..=b {
                let c = left[k - 1] + right[b - k];
                if c < d[b] {
                    (d[b], ks[b]) = (c, k as u32);
                }
            }
        }
    }
    (d, ks)
}

impl<'a, const N: usize> Plan<'a, N> {
    /// A plan over `bvh2` with leaves weighing at most `leaf_weight`, to be solved, for nodes and
    /// blocks of `node_bytes` and `block_bytes`.
    pub(super) fn new(
        bvh2: &'a Bvh2,
        leaf_weight: u32,
        costs: SahCosts,
        (node_bytes, block_bytes): (usize, usize),
    ) -> Plan<'a, N> {
        // Three bits a k, and the words' bits suffice up to eight children.
        const { assert!(N >= 2 && N <= 8) };
        // Memory costs are shares of the root's area, so they weigh alike in every scene.
        let root = bvh2.nodes[0].aabb().half_area();
        // Areas past 1e30 (boxes past 10¹⁵ across) are taken relative to the root's: the costs,
        // sums of areas over the tree, would overflow f32, and a plan whose every cost is
        // infinite ties its leaves with its nodes. Below, the areas are f32's, as they were.
        let area_scale =
            (root >= 1e30 || root.is_nan()).then(|| 1.0 / half_area_f64(&bvh2.nodes[0]));
        let root = if area_scale.is_some() { 1.0 } else { root };
        Plan {
            bvh2,
            leaf_weight,
            area_scale,
            costs: Weights {
                node: costs.node,
                block: costs.block,
                node_memory: costs.per_byte * root * node_bytes as f32,
                block_memory: costs.per_byte * root * block_bytes as f32,
            },
            choices: (0..bvh2.nodes.len()).map(|_| AtomicU32::new(0)).collect(),
        }
    }

    /// Half the surface area of `node`'s box: f32's, or relative to the root's where the scene
    /// is too large for f32 to hold its areas.
    fn area(&self, node: &obvhs::bvh2::node::Bvh2Node) -> f32 {
        match self.area_scale {
            None => node.aabb().half_area(),
            Some(scale) => (half_area_f64(node) * scale) as f32,
        }
    }

    /// Records node `i`'s choices and returns C(`i`, ·), given its primitives' weight and its
    /// children's costs (none for a BVH2 leaf).
    pub(super) fn solve(
        &self,
        i: u32,
        weight: u32,
        children: Option<(&Costs<N>, &Costs<N>)>,
    ) -> Costs<N> {
        let node = &self.bvh2.nodes[i as usize];
        let area = self.area(node);
        let leaf = if weight > self.leaf_weight && !node.is_leaf() {
            f32::INFINITY
        } else {
            let blocks = weight.div_ceil(LEAF_WEIGHT) as f32;
            (area * self.costs.block + self.costs.block_memory) * blocks
        };
        let Some((left, right)) = children else {
            // A leaf, and one subtree whatever its share.
            self.choices[i as usize].store((1 << N) - 1, Ordering::Relaxed);
            return [leaf; N];
        };
        let (mut d, ks) = split_costs(left, right);
        let internal = area * self.costs.node + self.costs.node_memory + d[N - 1];
        let one = if leaf <= internal { leaf } else { internal };
        let mut word = if leaf <= internal { LEAF_BIT } else { 0 };
        for b in 1..N {
            if one <= d[b] {
                word |= 1 << b;
            }
            word |= (ks[b] - 1) << (N + 3 * (b - 1));
        }
        self.choices[i as usize].store(word, Ordering::Relaxed);
        d[0] = one;
        d.map(|c| if c < one { c } else { one })
    }

    /// Node `i`'s choices.
    fn word(&self, i: u32) -> u32 {
        self.choices[i as usize].load(Ordering::Relaxed)
    }

    /// Whether node `i` is best a leaf, given it hangs from a wide node as one subtree.
    pub(super) fn is_leaf(&self, i: u32) -> bool {
        self.word(i) & LEAF_BIT != 0
    }

    /// The BVH2 nodes the wide node over internal node `i` takes as children.
    pub(super) fn children(&self, i: u32) -> ([u32; N], usize) {
        let mut kids = [0; N];
        let mut n = 0;
        self.expand(i, N, &mut kids, &mut n);
        (kids, n)
    }

    /// Appends to `kids` the subtrees that cover internal node `i` with at most `budget` (two or
    /// more) of them at least cost.
    fn expand(&self, i: u32, budget: usize, kids: &mut [u32; N], n: &mut usize) {
        let node = &self.bvh2.nodes[i as usize];
        let k = ((self.word(i) >> (N + 3 * (budget - 2))) & 7) as usize + 1;
        let halves = [(node.first_index, k), (node.first_index + 1, budget - k)];
        for (child, share) in halves {
            if share == 1 || self.word(child) & (1 << (share - 1)) != 0 {
                kids[*n] = child;
                *n += 1;
            } else {
                self.expand(child, share, kids, n);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search of every split, which [`split_costs`] must equal whatever shortcut it takes.
    fn searched(left: &Costs<8>, right: &Costs<8>) -> (Costs<8>, [u32; 8]) {
        let (mut d, mut ks) = ([f32::INFINITY; 8], [1u32; 8]);
        for b in 1..8 {
            for k in 1..=b {
                let c = left[k - 1] + right[b - k];
                if c < d[b] {
                    (d[b], ks[b]) = (c, k as u32);
                }
            }
        }
        (d, ks)
    }

    /// Costs that never grow with the budget, drawn by `next`: falling in steps, each step
    /// sometimes nothing (ties), sometimes all the rest (a flat tail), and sometimes flat from
    /// the start.
    fn costs(next: &mut impl FnMut() -> u32) -> Costs<8> {
        let mut c = [0.0; 8];
        c[0] = 1.0 + (next() % 1000) as f32 / 7.0;
        let flat_from = next() % 9;
        for i in 1..8 {
            let step = match next() % 4 {
                0 => 0.0,
                _ => (next() % 100) as f32 / 31.0,
            };
            c[i] = if i as u32 >= flat_from {
                c[i - 1]
            } else {
                (c[i - 1] - step).max(0.5)
            };
        }
        c
    }

    #[test]
    fn the_shortcuts_give_the_search_s_sums_and_splits() {
        let mut state = 0x2545_f491u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        let (mut flat_left, mut flat_right) = (0, 0);
        for _ in 0..20_000 {
            let (left, right) = (costs(&mut next), costs(&mut next));
            flat_left += (left[0] == left[7]) as u32;
            flat_right += (right[0] == right[7] && left[0] != left[7]) as u32;
            let (d, ks) = split_costs(&left, &right);
            let (want_d, want_ks) = searched(&left, &right);
            assert_eq!(
                (d[1..].to_vec(), ks[1..].to_vec()),
                (want_d[1..].to_vec(), want_ks[1..].to_vec()),
                "left {left:?}, right {right:?}"
            );
        }
        // Each shortcut was taken often, and so was the search.
        assert!(
            flat_left > 1000 && flat_right > 1000,
            "{flat_left} {flat_right}"
        );
        assert!(flat_left + flat_right < 15_000);
    }
}
