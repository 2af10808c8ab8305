//! The bottom level for analytic primitives (spheres and clipped quadrics): a 4-wide BVH of the
//! shared node layout ([`super::wide`]) traversed in f32 over boxes padded to stay conservative,
//! with every primitive intersected in f64.
//!
//! Leaves are blocks of four lanes. Spheres fill blocks four at a time: an f32 filter tells which
//! of the four the ray's line certainly misses ([`Sphere4`]), and only the others get the exact
//! f64 test, so results are those of the f64 test alone. A quadric, whose test is several sphere tests' worth, weighs a whole block and
//! is a leaf of its own, so its box is culled by the node above it (measured on
//! scenes/reflective.toml: leaves of one quadric beat leaves of several by 6%).
//!
//! Two things keep the f32 traversal conservative: each box is padded by a few f32 ulps of the
//! largest coordinate any ray origin or primitive can have (covering the rounding of the ray
//! origin and direction to f32), the slab test widens exit distances (Ize), and the t limit the
//! nodes cull with is rounded up. Closest-hit traversal visits children nearest first and skips
//! those entered beyond the best hit; occlusion visits them in any order and stops at the first
//! blocker.

use super::build::{build_single_leaves, padded_aabb};
use super::round_up;
use super::sphere4::{FilterRay, Sphere4};
use super::stack::{Stacks, with_stack};
use super::wide::{BoxRay, LEAF, LEAF_WEIGHT, Node4, collapse};
use crate::geometry::Level;
use crate::math::Ray;
use crate::shape::LocalPrim;
use obvhs::aabb::Aabb;

/// A leaf block: up to four spheres, or one quadric.
#[derive(Clone, Copy, Debug)]
struct Block {
    spheres: Sphere4,
    /// Each lane's primitive: a sphere index, or [`QUADRIC`] with a quadric index; [`NO_PRIM`]
    /// for an unused lane.
    prims: [u32; 4],
}

/// Marks a quadric in [`Block::prims`].
const QUADRIC: u32 = 1 << 31;
/// An unused lane.
const NO_PRIM: u32 = u32::MAX;

impl Block {
    /// The primitive in `lane`, if any.
    #[inline(always)]
    fn prim(&self, lane: usize) -> Option<LocalPrim> {
        match self.prims[lane] {
            NO_PRIM => None,
            p if p & QUADRIC != 0 => Some(LocalPrim::Quadric(p & !QUADRIC)),
            p => Some(LocalPrim::Sphere(p)),
        }
    }

    /// Whether lane 0 holds a quadric (then the block holds nothing else).
    #[inline(always)]
    fn quadric(&self) -> Option<u32> {
        let p = self.prims[0];
        (p != NO_PRIM && p & QUADRIC != 0).then_some(p & !QUADRIC)
    }
}

/// A wide BVH over the spheres and quadrics of one level.
#[derive(Clone)]
pub(crate) struct AnalyticBvh {
    nodes: Vec<Node4>,
    blocks: Vec<Block>,
    /// The root's box: what the top level bounds this level by.
    root: Aabb,
    /// Number of primitives.
    len: usize,
}

thread_local! {
    /// The analytic BVHs' traversal stacks of (child reference, entry distance).
    static STACK: Stacks<(u32, f32)> = const { Stacks::new() };
}

impl AnalyticBvh {
    /// Builds the BVH, or `None` when there are no analytic primitives. `extent` bounds the
    /// magnitude of every coordinate a ray may start at.
    pub(crate) fn build(level: Level<'_>, extent: f32) -> Option<AnalyticBvh> {
        let spheres = level.spheres.len();
        let aabbs: Vec<Aabb> = (level.spheres.iter().map(|s| s.bounds()))
            .chain(level.quadrics.iter().map(|q| q.bounds()))
            .map(|b| padded_aabb(b, extent))
            .collect();
        if aabbs.is_empty() {
            return None;
        }
        // Primitive p is sphere p below `spheres`, quadric p − spheres above.
        let bvh2 = build_single_leaves(&aabbs);
        let is_sphere = |p: u32| (p as usize) < spheres;
        let mut blocks: Vec<Block> = Vec::new();
        let nodes = collapse(
            &bvh2,
            |p| if is_sphere(p) { 1 } else { LEAF_WEIGHT },
            |prims| {
                let first = blocks.len() as u32;
                let mut lane = 4;
                for &p in prims.iter().filter(|&&p| is_sphere(p)) {
                    if lane == 4 {
                        blocks.push(Block {
                            spheres: Sphere4::EMPTY,
                            prims: [NO_PRIM; 4],
                        });
                        lane = 0;
                    }
                    let block = blocks.last_mut().expect("a block was pushed");
                    block.spheres.set(lane, &level.spheres[p as usize]);
                    block.prims[lane] = p;
                    lane += 1;
                }
                for &p in prims.iter().filter(|&&p| !is_sphere(p)) {
                    let mut prims = [NO_PRIM; 4];
                    prims[0] = QUADRIC | (p - spheres as u32);
                    blocks.push(Block {
                        spheres: Sphere4::EMPTY,
                        prims,
                    });
                }
                let count = blocks.len() as u32 - first;
                // Leaves of one BVH2 leaf hold one primitive, so a leaf is one block.
                assert!(
                    count < 1 << LEAF_COUNT_BITS && blocks.len() < 1 << 27,
                    "an analytic BVH leaf holds at most 7 blocks, and a BVH 2^27 blocks"
                );
                (first << LEAF_COUNT_BITS) | count
            },
        );
        Some(AnalyticBvh {
            nodes: nodes.into_boxed_slice().into_vec(),
            blocks: blocks.into_boxed_slice().into_vec(),
            root: *bvh2.nodes[0].aabb(),
            len: aabbs.len(),
        })
    }

    /// The root's box: what the top level bounds this level by.
    pub(crate) fn bounds(&self) -> Aabb {
        self.root
    }

    /// Number of primitives.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Bytes kept allocated: the wide nodes and the leaf blocks.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node4>()
            + self.blocks.capacity() * std::mem::size_of::<Block>()
    }

    /// The blocks of leaf reference `leaf`.
    #[inline(always)]
    fn leaf_blocks(&self, leaf: u32) -> &[Block] {
        let first = ((leaf & !LEAF) >> LEAF_COUNT_BITS) as usize;
        let count = (leaf & ((1 << LEAF_COUNT_BITS) - 1)) as usize;
        &self.blocks[first..first + count]
    }

    /// Lowers `best_t` to the nearest hit in (0, `best_t`), returning its primitive if there is one.
    #[inline]
    pub(crate) fn closest(
        &self,
        g: Level<'_>,
        ray: &Ray,
        best_t: &mut f64,
        from: Option<LocalPrim>,
    ) -> Option<LocalPrim> {
        let mut best = None;
        let boxes = BoxRay::new(ray.origin.as_vec3a(), ray.dir.as_vec3a());
        let filter = FilterRay::new(ray.origin, ray.dir);
        let mut limit = round_up(*best_t);
        with_stack(&STACK, |stack| {
            let mut current = 0u32;
            loop {
                if current & LEAF == 0 {
                    let node = &self.nodes[current as usize];
                    let (enter, mask) = node.intersect(&boxes, limit);
                    match mask.count_ones() {
                        0 => {}
                        1 => {
                            current = node.children[mask.trailing_zeros() as usize];
                            continue;
                        }
                        _ => {
                            current = node.push_ordered(enter, mask, stack, |_| {});
                            continue;
                        }
                    }
                } else {
                    for block in self.leaf_blocks(current) {
                        if let Some(hit) = block_closest(block, g, ray, &filter, *best_t, from) {
                            *best_t = hit.0;
                            best = Some(hit.1);
                            limit = round_up(hit.0);
                        }
                    }
                }
                // Pop the next child that may still hold a nearer hit.
                loop {
                    match stack.pop() {
                        None => return,
                        Some((child, enter)) if enter <= limit => {
                            current = child;
                            break;
                        }
                        Some(_) => {}
                    }
                }
            }
        });
        best
    }

    /// Whether any primitive blocks the ray in (0, `t_max`).
    #[inline]
    pub(crate) fn occluded(
        &self,
        g: Level<'_>,
        ray: &Ray,
        t_max: f64,
        from: Option<LocalPrim>,
    ) -> bool {
        let boxes = BoxRay::new(ray.origin.as_vec3a(), ray.dir.as_vec3a());
        let filter = FilterRay::new(ray.origin, ray.dir);
        let limit = round_up(t_max);
        with_stack(&STACK, |stack| {
            let mut current = 0u32;
            loop {
                if current & LEAF == 0 {
                    let node = &self.nodes[current as usize];
                    let (_, mut mask) = node.intersect(&boxes, limit);
                    while mask != 0 {
                        let lane = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack.push((node.children[lane], 0.0));
                    }
                } else {
                    for block in self.leaf_blocks(current) {
                        if block_closest(block, g, ray, &filter, t_max, from).is_some() {
                            return true;
                        }
                    }
                }
                match stack.pop() {
                    None => return false,
                    Some((child, _)) => current = child,
                }
            }
        })
    }
}

/// A leaf's payload: its first [`Block`], shifted past the low bits that hold the block count.
const LEAF_COUNT_BITS: u32 = 3;

/// The nearest hit in (0, `t_max`) among a block's primitives, skipping self-hits of `from`.
#[inline(always)]
fn block_closest(
    block: &Block,
    g: Level<'_>,
    ray: &Ray,
    filter: &FilterRay,
    t_max: f64,
    from: Option<LocalPrim>,
) -> Option<(f64, LocalPrim)> {
    if let Some(q) = block.quadric() {
        let from_self = from == Some(LocalPrim::Quadric(q));
        return (g.quadrics[q as usize].intersect(ray, t_max, from_self))
            .map(|t| (t, LocalPrim::Quadric(q)));
    }
    let mut lanes = block.spheres.may_hit(filter);
    let mut best: Option<(f64, LocalPrim)> = None;
    while lanes != 0 {
        let lane = lanes.trailing_zeros() as usize;
        lanes &= lanes - 1;
        let Some(prim) = block.prim(lane) else {
            continue;
        };
        let LocalPrim::Sphere(s) = prim else {
            continue;
        };
        let limit = best.map_or(t_max, |b| b.0);
        if let Some(t) = g.spheres[s as usize].intersect(ray, limit, from == Some(prim)) {
            best = Some((t, prim));
        }
    }
    best
}
