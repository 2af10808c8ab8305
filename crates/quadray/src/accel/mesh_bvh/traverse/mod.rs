//! The mesh BVH's traversals: the closest hit and any hit, nearest children first for the
//! former, each compiled twice (the AVX2 path's copy inlined into its caller, the baseline's a
//! function of its own: see [`MeshBvh::closest_on`]), and twice more over compact leaves
//! (`COMPACT`), entered from [`super::compact`].

use super::leaves::LeafLanes;
use super::{MeshBvh, MeshHit, MeshRay, TriId};
use crate::accel::stack::local_cell;
use crate::accel::tri4::{BlockHits, Tri4};
use crate::accel::wide::{LEAF, Node8, pop_nearer};
use crate::mesh::Mesh;
use crate::triangle::TriangleHit;
use std::cell::Cell;
use std::mem::MaybeUninit;

thread_local! {
    /// The traversal stack of (child reference, entry distance), reused across rays (taken out
    /// of its cell by each traversal: [`local_cell`]).
    static STACK: Cell<Vec<(u32, f32)>> = const { Cell::new(Vec::new()) };
}

impl MeshBvh {
    /// Asks the CPU to start loading child `reference` (a node, or a leaf's first block), every
    /// cache line of it, so the load overlaps the work on its nearer siblings. The whole of a
    /// node (224 bytes) and of a block (160 bytes), not their first two lines: the dragon's
    /// incoherent rays +5%, the meshes that fit the cache within ±3%. A compact BVH's block
    /// (`COMPACT`) is its numbers: the vertices they name are not known yet.
    #[inline(always)]
    fn prefetch<const COMPACT: bool>(&self, reference: u32) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let (p, bytes): (*const i8, usize) = if reference & LEAF == 0 {
                let node = self.nodes.as_ptr().wrapping_add(reference as usize);
                (node.cast(), size_of::<Node8>())
            } else if COMPACT {
                let (first, _) = self.layout.parts(reference);
                let numbers = self.numbers.as_ptr().wrapping_add(first);
                (numbers.cast(), size_of::<[u32; 4]>())
            } else {
                let (first, _) = self.layout.parts(reference);
                let block = self.blocks.as_ptr().wrapping_add(first);
                (block.cast(), size_of::<Tri4>())
            };
            for line in (0..bytes).step_by(64) {
                // SAFETY: a prefetch is only a hint; it never faults and reads nothing into the
                // program.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(line)) };
            }
        }
    }

    /// Leaf block `index`, of which lanes `lanes` (bit l for lane l) are tested: the BVH's own,
    /// or over compact leaves (`COMPACT`) those lanes read from `meshes` into `read`.
    #[inline(always)]
    fn leaf_block<'s, const COMPACT: bool>(
        &'s self,
        meshes: &[Mesh],
        index: usize,
        lanes: u32,
        read: &'s mut MaybeUninit<Tri4>,
    ) -> &'s Tri4 {
        if COMPACT {
            read.write(self.read(meshes, self.numbers[index], lanes))
        } else {
            &self.blocks[index]
        }
    }

    /// The lanes of `block` among `lanes` (a leaf's, bit l for lane l) the ray hits in
    /// (0, `t_max`) that count: not `skip`, and kept by the meshes' alpha cut-outs.
    #[inline(always)]
    fn block_hits(
        &self,
        meshes: &[Mesh],
        block: &Tri4,
        lanes: u32,
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> (BlockHits, u32) {
        let hits = block.intersect(&ray.sheared, t_max, lanes);
        let mut mask = hits.valid;
        if mask != 0 && (skip.is_some() || self.masked) {
            for lane in 0..4 {
                if mask & (1 << lane) == 0 {
                    continue;
                }
                let (m, tri) = self.id(block.tri[lane]);
                let drop = skip == Some((m, tri))
                    || (self.masked && {
                        let b = hits.nearest(1 << lane).map(|h| h.barycentrics);
                        b.is_some_and(|b| !meshes[m as usize].covers(tri, b, || ray.coverage_key()))
                    });
                if drop {
                    mask &= !(1 << lane);
                }
            }
        }
        (hits, mask)
    }

    /// [`MeshBvh::closest_on`] on this thread's traversal stack: the tests' query (the scene's
    /// queries take the stack in their callers, once a batch where they can).
    #[cfg(test)]
    pub(crate) fn closest<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> Option<MeshHit> {
        let mut stack = MeshBvh::take_stack();
        let hit = self.closest_on::<AVX2>(meshes, ray, t_max, skip, &mut stack);
        MeshBvh::put_stack(stack);
        hit
    }

    /// This thread's traversal stack, taken out of its cell for a batch of queries
    /// ([`MeshBvh::closest_on`]) so the batch looks it up once; give it back with
    /// [`MeshBvh::put_stack`] (a query in between finds an empty one, which is still correct).
    #[inline(always)]
    pub(crate) fn take_stack() -> Vec<(u32, f32)> {
        local_cell(&STACK).take()
    }

    /// Gives back the stack of [`MeshBvh::take_stack`].
    #[inline(always)]
    pub(crate) fn put_stack(stack: Vec<(u32, f32)>) {
        local_cell(&STACK).set(stack)
    }

    /// The nearest triangle of `meshes` (those the BVH was built over) the ray meets in
    /// (0, `t_max`), skipping triangle `skip`, traversed on `stack` (emptied first; the thread's:
    /// [`MeshBvh::take_stack`]), on the AVX2 path where `AVX2` is set (by callers on that path
    /// only, chosen where the CPU has AVX2: [`crate::simd::simd_path`]).
    ///
    /// The AVX2 path's traversal is inlined into its caller (compiled for AVX2); the baseline's
    /// is a function of its own, called once a query: inlined, it made the analytic scenes'
    /// callers (which take the baseline path) too large to inline in turn.
    #[inline(always)]
    pub(crate) fn closest_on<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        if AVX2 {
            self.traverse_closest::<true, false>(meshes, ray, t_max, skip, stack)
        } else {
            self.closest_baseline(meshes, ray, t_max, skip, stack)
        }
    }

    /// [`MeshBvh::closest_on`] compiled for the baseline.
    #[inline(never)]
    fn closest_baseline(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        self.traverse_closest::<false, false>(meshes, ray, t_max, skip, stack)
    }

    /// The closest-hit traversal (`AVX2` as for [`MeshBvh::closest_on`]; `COMPACT` over compact
    /// leaves, whose blocks are read from the meshes).
    #[inline(always)]
    pub(super) fn traverse_closest<const AVX2: bool, const COMPACT: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        if self.nodes.is_empty() || !ray.finite {
            return None;
        }
        // Where a compact leaf's block is read to (unused over copied leaves).
        let mut read = MaybeUninit::uninit();
        let mut limit = t_max;
        let mut best: Option<(u32, TriangleHit)> = None;
        // The best hit's block and lane, as block · 4 + lane.
        let mut best_lane = 0u32;
        stack.clear();
        let mut current = 0u32;
        loop {
            if current & LEAF == 0 {
                let node = &self.nodes[current as usize];
                let (enter, mask) = node.intersect::<AVX2>(&ray.boxes, limit);
                // One child entered is taken without the stack (tested as `mask & (mask - 1)`:
                // `count_ones` has no instruction on baseline x86-64); several are pushed far
                // to near and the nearest visited next.
                if mask != 0 {
                    current = if mask & (mask - 1) == 0 {
                        node.children[mask.trailing_zeros() as usize]
                    } else {
                        node.push_ordered(enter, mask, stack, |c| self.prefetch::<COMPACT>(c))
                    };
                    continue;
                }
            } else {
                // The leaf's blocks in turn, four lane bits each.
                let leaf = LeafLanes::of(current, self.layout);
                let (mut lanes, mut index) = (leaf.lane_bits(), leaf.first_block());
                while lanes != 0 {
                    let block = self.leaf_block::<COMPACT>(meshes, index, lanes & 0xF, &mut read);
                    let (hits, mask) =
                        self.block_hits(meshes, block, lanes & 0xF, ray, limit, skip);
                    if let Some(h) = hits.nearest(mask) {
                        limit = h.t;
                        let hit = TriangleHit {
                            t: h.t,
                            barycentrics: h.barycentrics,
                        };
                        best = Some((block.tri[h.lane], hit));
                        best_lane = (index * 4 + h.lane) as u32;
                    }
                    (lanes, index) = (lanes >> 4, index + 1);
                }
            }
            // Pop the next child that may still hold a nearer hit.
            match pop_nearer(stack, limit) {
                Some(child) => current = child,
                None => break,
            }
        }
        best.map(|(number, hit)| MeshHit {
            id: self.id(number),
            hit,
            block: best_lane / 4,
            lane: best_lane % 4,
        })
    }

    /// Whether any triangle other than `skip` meets the ray in (0, `t_max`) (`AVX2` and the
    /// two compiled paths as for [`MeshBvh::closest_on`]).
    #[inline(always)]
    pub(crate) fn occluded<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        if AVX2 {
            self.traverse_occluded::<true, false>(meshes, ray, t_max, skip)
        } else {
            self.occluded_baseline(meshes, ray, t_max, skip)
        }
    }

    /// [`MeshBvh::occluded`] compiled for the baseline.
    #[inline(never)]
    fn occluded_baseline(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        self.traverse_occluded::<false, false>(meshes, ray, t_max, skip)
    }

    /// The any-hit traversal (`AVX2` and `COMPACT` as for [`MeshBvh::traverse_closest`]).
    #[inline(always)]
    pub(super) fn traverse_occluded<const AVX2: bool, const COMPACT: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        if self.nodes.is_empty() || !ray.finite {
            return false;
        }
        // As in the closest-hit traversal.
        let mut read = MaybeUninit::uninit();
        let cell = local_cell(&STACK);
        let mut stack = cell.take();
        stack.clear();
        let mut current = 0u32;
        let blocked = 'search: loop {
            if current & LEAF == 0 {
                let node = &self.nodes[current as usize];
                let (_, mask) = node.intersect::<AVX2>(&ray.boxes, t_max);
                if mask != 0 {
                    current =
                        node.push_all_but_last(mask, &mut stack, |c| self.prefetch::<COMPACT>(c));
                    continue;
                }
            } else {
                let leaf = LeafLanes::of(current, self.layout);
                let (mut lanes, mut index) = (leaf.lane_bits(), leaf.first_block());
                while lanes != 0 {
                    let block = self.leaf_block::<COMPACT>(meshes, index, lanes & 0xF, &mut read);
                    if self
                        .block_hits(meshes, block, lanes & 0xF, ray, t_max, skip)
                        .1
                        != 0
                    {
                        break 'search true;
                    }
                    (lanes, index) = (lanes >> 4, index + 1);
                }
            }
            match stack.pop() {
                None => break false,
                Some((child, _)) => current = child,
            }
        };
        cell.set(stack);
        blocked
    }
}

#[cfg(test)]
mod tests;
