//! The bottom level for triangle meshes: an 8-wide BVH of quadray's own layout ([`super::wide`]),
//! collapsed from obvhs' BVH2 build (PLOC, reinsertion), with leaves of one or two blocks of four
//! triangles ([`Tri4`]), each block tested at once; the children a ray enters are visited nearest
//! first.
//!
//! Eight children a node rather than four (Embree's BVH8 on AVX2): the AVX2 path tests a node in
//! one pass of 8-lane registers, and a ray passes about two thirds as many levels. Measured
//! against the 4-wide layout (`bench rays`, 3 interleaved rounds, 1 thread, AVX2): +8% to +21%
//! on every mesh and ray set. The baseline path tests the same nodes in two 4-lane halves, so
//! both paths visit the same nodes in the same order and give the same hits.
//!
//! Leaves hold copies of their triangles' vertices (no index lookups while tracing). A block lane
//! names its triangle by number: over a single mesh the mesh's triangle index, over several meshes
//! an index into a table of (mesh, triangle).

use super::tri4::Tri4;
use super::wide::{BoxRay, LEAF, Node8, collapse, covering_boxes, leaf_blocks, pop_nearer};
use crate::mesh::Mesh;
use crate::triangle::{ShearedRay, TriangleHit};
use glam::{DVec3, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use rayon::prelude::*;
use std::cell::Cell;

/// A triangle of a [`MeshBvh`]: index of the mesh among those it was built over, and the triangle.
pub(crate) type TriId = (u32, u32);

/// The most triangles a leaf holds: two blocks. Against leaves of one block (4 triangles), the
/// leaves are fuller (BVH bytes per triangle: dragon 73 -> 60, kitchen 78 -> 67) and rays as
/// fast or faster (3 interleaved rounds, 1 thread: kitchen coherent closest hit -3%, the rest
/// -2% to +19%, most on the dragon's incoherent rays); three blocks were 1-11% slower.
const MESH_LEAF_TRIANGLES: u32 = 8;

/// The nearest triangle a ray meets in a [`MeshBvh`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshHit {
    /// Which triangle.
    pub(crate) id: TriId,
    /// Where the f32 test met it.
    pub(crate) hit: TriangleHit,
    /// The leaf block and lane holding its vertices ([`MeshBvh::vertices`]).
    block: u32,
    lane: u32,
}

/// A wide BVH over the triangles of one or more meshes.
#[derive(Clone, Debug)]
pub(crate) struct MeshBvh {
    nodes: Vec<Node8>,
    blocks: Vec<Tri4>,
    /// (mesh, triangle) of each triangle number (the meshes' triangles numbered in turn); empty
    /// over a single mesh, whose triangle numbers are its triangle indices.
    ids: Vec<TriId>,
    /// Whether any of the meshes has an alpha cut-out.
    masked: bool,
}

/// An f32 ray in a mesh's space, prepared for the node and triangle tests.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshRay {
    boxes: BoxRay,
    sheared: ShearedRay,
}

impl MeshRay {
    /// Prepares `origin + t·dir` for traversal (a ray that is not finite in f32 meets nothing).
    #[inline]
    pub(crate) fn new(origin: Vec3, dir: Vec3) -> MeshRay {
        MeshRay {
            boxes: BoxRay::new(origin.into(), dir.into()),
            sheared: ShearedRay::new(origin, dir),
        }
    }

    /// The ray's [`coverage_key`](crate::mesh::coverage_key), from its origin and reciprocal
    /// direction (which identify the ray as well as its direction does, and are at hand).
    #[inline]
    fn coverage_key(&self) -> u32 {
        crate::mesh::coverage_key(self.boxes.origin.into(), self.boxes.inv_dir.into())
    }
}

thread_local! {
    /// The traversal stack of (child reference, entry distance), reused across rays.
    static STACK: Cell<Vec<(u32, f32)>> = const { Cell::new(Vec::new()) };
}

/// This thread's traversal stack, empty, taken out of [`STACK`] (give it back with `STACK.set`).
///
/// Taken rather than lent to a closure (as [`super::stack::with_stack`] does): a closure is
/// compiled with the target features of the function it is written in, so the traversal in it
/// ran without AVX2 on the AVX2 path unless inlined, and inlining it through `LocalKey::with`
/// was not reliable. A mesh traversal never runs inside another, so one stack a thread is enough
/// (a nested one would start from an empty vector).
#[inline(always)]
fn take_stack() -> Vec<(u32, f32)> {
    let mut stack = STACK.take();
    stack.clear();
    stack
}

impl MeshBvh {
    /// Builds the BVH over `meshes`.
    pub(crate) fn build(meshes: &[Mesh]) -> MeshBvh {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in meshes.iter().flat_map(|m| m.positions()) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        // Pad every box by a few ulps of its coordinates and a tiny share of the meshes' size, so
        // a triangle lying in an axis plane gets a slab of non-zero width.
        let pad = Vec3A::splat((hi - lo).max_element().max(0.0) * 1e-6);
        let mut all_ids = Vec::new();
        let mut triangles: Vec<[[f32; 3]; 3]> = Vec::new();
        for (m, mesh) in meshes.iter().enumerate() {
            let count = mesh.triangle_count() as u32;
            triangles.par_extend(
                (0..count)
                    .into_par_iter()
                    .map(|tri| mesh.triangle_positions(tri).map(|p| *p)),
            );
            all_ids.extend((0..count).map(|tri| (m as u32, tri)));
        }
        let aabbs: Vec<Aabb> = triangles
            .par_iter()
            .map(|vertices| {
                let [a, b, c] = vertices.map(Vec3A::from);
                let (l, h) = (a.min(b).min(c), a.max(b).max(c));
                Aabb::new(
                    l - l.abs() * (4.0 * f32::EPSILON) - pad,
                    h + h.abs() * (4.0 * f32::EPSILON) + pad,
                )
            })
            .collect();
        let masked = meshes.iter().any(|m| m.alpha_mask().is_some());
        let mut bvh = MeshBvh {
            nodes: Vec::new(),
            blocks: Vec::new(),
            ids: Vec::new(),
            masked,
        };
        if aabbs.is_empty() {
            return bvh;
        }
        // Single-triangle leaves: the collapse makes its own leaves of 4-triangle blocks (a full
        // block costs one SIMD test, so obvhs' SAH leaf collapse, which counts every triangle,
        // would leave the blocks 60% full). Measured on the kitchen: obvhs' slow build (wider PLOC search, more
        // reinsertion) and spatial pre-splits change throughput by under 2% at 1.2-2x the time.
        let bvh2 = super::build::build_single_leaves(&aabbs);
        let (nodes, blocks) = collapse(
            &bvh2,
            MESH_LEAF_TRIANGLES,
            |_| 1,
            |prims, blocks: &mut Vec<Tri4>| {
                for lanes in prims.chunks(4) {
                    let mut block = [([[0.0; 3]; 3], 0); 4];
                    for (slot, &p) in block.iter_mut().zip(lanes) {
                        *slot = (triangles[p as usize], p);
                    }
                    blocks.push(Tri4::new(&block[..lanes.len()]));
                }
            },
        );
        let nodes = nodes.into_boxed_slice().into_vec();
        let blocks = blocks.into_boxed_slice().into_vec();
        if meshes.len() > 1 {
            bvh.ids = all_ids;
        }
        bvh.nodes = nodes;
        bvh.blocks = blocks;
        bvh
    }

    /// At most `max` boxes whose union holds every triangle, hugging the mesh far closer than one
    /// box once rotated (the root's children, opened one level where `max` allows).
    pub(crate) fn covering_boxes(&self, max: usize) -> Vec<(glam::DVec3, glam::DVec3)> {
        covering_boxes(&self.nodes, max)
    }

    /// Bytes of the wide nodes, the triangle blocks and the id table.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node8>()
            + self.blocks.capacity() * std::mem::size_of::<Tri4>()
            + self.ids.capacity() * std::mem::size_of::<TriId>()
    }

    /// Asks the CPU to start loading child `reference` (a node or a leaf's first block), so the
    /// load overlaps the work on its nearer siblings.
    #[inline(always)]
    fn prefetch(&self, reference: u32) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let p: *const i8 = if reference & LEAF == 0 {
                self.nodes.as_ptr().wrapping_add(reference as usize).cast()
            } else {
                let first = leaf_blocks(reference).start;
                self.blocks.as_ptr().wrapping_add(first).cast()
            };
            // SAFETY: a prefetch is only a hint; it never faults and reads nothing into the program.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(p);
                _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64));
            }
        }
    }

    /// (mesh, triangle) of triangle number `number`.
    #[inline(always)]
    fn id(&self, number: u32) -> TriId {
        match self.ids.get(number as usize) {
            Some(&id) => id,
            None => (0, number),
        }
    }

    /// The lanes of `block` the ray hits in (0, `t_max`) that count: not `skip`, and kept by the
    /// meshes' alpha cut-outs.
    #[inline(always)]
    fn block_hits(
        &self,
        meshes: &[Mesh],
        block: &Tri4,
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> (super::tri4::BlockHits, u32) {
        let hits = block.intersect(&ray.sheared, t_max);
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

    /// The nearest triangle of `meshes` (those the BVH was built over) the ray meets in
    /// (0, `t_max`), skipping triangle `skip`, on the AVX2 path where `AVX2` is set (by callers
    /// on that path only, chosen where the CPU has AVX2: [`super::simd_path`]).
    ///
    /// The AVX2 path's traversal is inlined into its caller (compiled for AVX2); the baseline's
    /// is a function of its own, called once a query: inlined, it made the analytic scenes'
    /// callers (which take the baseline path) too large to inline in turn.
    #[inline(always)]
    pub(crate) fn closest<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> Option<MeshHit> {
        if AVX2 {
            self.traverse_closest::<true>(meshes, ray, t_max, skip)
        } else {
            self.closest_baseline(meshes, ray, t_max, skip)
        }
    }

    /// [`MeshBvh::closest`] compiled for the baseline.
    #[inline(never)]
    fn closest_baseline(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> Option<MeshHit> {
        self.traverse_closest::<false>(meshes, ray, t_max, skip)
    }

    /// The closest-hit traversal (`AVX2` as for [`MeshBvh::closest`]).
    #[inline(always)]
    fn traverse_closest<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> Option<MeshHit> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut limit = t_max;
        let mut best: Option<(u32, TriangleHit)> = None;
        // The best hit's block and lane, as block · 4 + lane.
        let mut best_lane = 0u32;
        let mut stack = take_stack();
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
                        node.push_ordered(enter, mask, &mut stack, |c| self.prefetch(c))
                    };
                    continue;
                }
            } else {
                let blocks = leaf_blocks(current);
                let first = blocks.start;
                for (k, block) in self.blocks[blocks].iter().enumerate() {
                    let (hits, mask) = self.block_hits(meshes, block, ray, limit, skip);
                    if let Some(h) = hits.nearest(mask) {
                        limit = h.t;
                        let hit = TriangleHit {
                            t: h.t,
                            barycentrics: h.barycentrics,
                        };
                        best = Some((block.tri[h.lane], hit));
                        best_lane = ((first + k) * 4 + h.lane) as u32;
                    }
                }
            }
            // Pop the next child that may still hold a nearer hit.
            match pop_nearer(&mut stack, limit) {
                Some(child) => current = child,
                None => break,
            }
        }
        STACK.set(stack);
        best.map(|(number, hit)| MeshHit {
            id: self.id(number),
            hit,
            block: best_lane / 4,
            lane: best_lane % 4,
        })
    }

    /// The vertices of `hit`'s triangle, from the leaf block's copies: the mesh's own values, so
    /// the f64 refinement of a hit needs no lookup in the mesh (on the dragon's rays that lookup
    /// was a quarter of a closest-hit query).
    #[inline(always)]
    pub(crate) fn vertices(&self, hit: &MeshHit) -> [DVec3; 3] {
        self.blocks[hit.block as usize].vertices(hit.lane as usize)
    }

    /// Whether any triangle other than `skip` meets the ray in (0, `t_max`) (`AVX2` and the
    /// two compiled paths as for [`MeshBvh::closest`]).
    #[inline(always)]
    pub(crate) fn occluded<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        if AVX2 {
            self.traverse_occluded::<true>(meshes, ray, t_max, skip)
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
        self.traverse_occluded::<false>(meshes, ray, t_max, skip)
    }

    /// The any-hit traversal (`AVX2` as for [`MeshBvh::closest`]).
    #[inline(always)]
    fn traverse_occluded<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = take_stack();
        let mut current = 0u32;
        let blocked = 'search: loop {
            if current & LEAF == 0 {
                let node = &self.nodes[current as usize];
                let (_, mask) = node.intersect::<AVX2>(&ray.boxes, t_max);
                let mut m = mask;
                while m != 0 {
                    let lane = m.trailing_zeros() as usize;
                    m &= m - 1;
                    stack.push((node.children[lane], 0.0));
                }
            } else {
                for block in &self.blocks[leaf_blocks(current)] {
                    if self.block_hits(meshes, block, ray, t_max, skip).1 != 0 {
                        break 'search true;
                    }
                }
            }
            match stack.pop() {
                None => break false,
                Some((child, _)) => current = child,
            }
        };
        STACK.set(stack);
        blocked
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::MaterialId;

    /// A grid of n×n unit quads in the plane z = 0 (2n² triangles).
    fn grid(n: u32, material: MaterialId) -> Mesh {
        let mut p = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                p.push(Vec3::new(x as f32, y as f32, 0.0));
            }
        }
        let mut idx = Vec::new();
        let v = |x: u32, y: u32| y * (n + 1) + x;
        for y in 0..n {
            for x in 0..n {
                idx.push([v(x, y), v(x + 1, y), v(x + 1, y + 1)]);
                idx.push([v(x, y), v(x + 1, y + 1), v(x, y + 1)]);
            }
        }
        Mesh::new(p, idx, None, material).unwrap()
    }

    /// Every ray through the grid's interior (including along the shared edges and through
    /// vertices) hits, at the plane's t; a brute-force scan over the mesh's triangles
    /// agrees on the nearest t.
    #[test]
    fn bvh_traversal_matches_brute_force_and_has_no_cracks() {
        let meshes = [grid(16, 0)];
        let bvh = MeshBvh::build(&meshes);
        let mesh = &meshes[0];
        for k in 0..4000 {
            // Inside the grid's border (its outer edges are shared by no second triangle).
            let x = 1.0 + 14.0 * ((k as f32 * 0.618_034).fract());
            let y = 1.0 + 14.0 * ((k as f32 * 0.414_213_5).fract());
            // Every fourth ray aims exactly at a vertex or along a grid line.
            let (x, y) = match k % 4 {
                0 => (x.round(), y.round()),
                1 => (x.round(), y),
                _ => (x, y),
            };
            let dir = Vec3::new(0.1 * (k as f32).sin(), 0.1 * (k as f32).cos(), -1.0);
            let ray = MeshRay::new(Vec3::new(x, y, 0.0) - dir * 5.0, dir);
            let hit = bvh.closest::<false>(&meshes, &ray, f32::INFINITY, None);
            let MeshHit { id, hit: h, .. } = hit.unwrap_or_else(|| panic!("hole at ({x}, {y})"));
            assert!((h.t - 5.0).abs() < 1e-5, "t {}", h.t);
            let brute = (0..mesh.triangle_count() as u32)
                .filter_map(|t| {
                    let [a, b, c] = mesh.triangle_positions(t);
                    ray.sheared.intersect(a, b, c, f32::INFINITY).map(|h| h.t)
                })
                .fold(f32::INFINITY, f32::min);
            assert_eq!(brute, h.t);
            assert!(bvh.occluded::<false>(&meshes, &ray, 6.0, None));
            assert!(!bvh.occluded::<false>(&meshes, &ray, 4.9, None));
            // Skipping the triangle hit leaves at most its neighbour across an edge or vertex.
            if let Some(MeshHit { id: other, .. }) =
                bvh.closest::<false>(&meshes, &ray, f32::INFINITY, Some(id))
            {
                assert_ne!(other, id);
            }
        }
    }

    /// A tiny mesh near the origin is hit from very close: no entry clamp loses near hits.
    #[test]
    fn near_hits_at_any_scale() {
        for scale in [1e-6f32, 1.0, 1e6] {
            let g = grid(4, 0);
            let p: Vec<Vec3> = g.positions().iter().map(|p| *p * scale).collect();
            let meshes = [Mesh::new(p, g.indices().to_vec(), None, 0).unwrap()];
            let bvh = MeshBvh::build(&meshes);
            let ray = MeshRay::new(Vec3::new(1.5, 2.5, 1e-3) * scale, Vec3::new(0.0, 0.0, -1.0));
            let MeshHit { hit: h, .. } = bvh
                .closest::<false>(&meshes, &ray, f32::INFINITY, None)
                .expect("hit");
            assert!(
                (h.t / (1e-3 * scale) - 1.0).abs() < 1e-4,
                "scale {scale}: t {}",
                h.t
            );
        }
    }

    /// Rays from far away aimed exactly at the grid's lines, where leaf boxes meet face to face,
    /// all hit: the slab test is conservative for a ray starting at any distance (without the
    /// robust exit factor, rays from 10⁴ away slip between two boxes).
    #[test]
    fn distant_rays_at_box_faces_hit() {
        let meshes = [grid(16, 0)];
        let bvh = MeshBvh::build(&meshes);
        let mut holes = 0;
        let mut rays = 0;
        for distance in [1e3f32, 1e4, 1e5] {
            for k in 0..20_000 {
                let along = 1.0 + 14.0 * ((k as f32 * 0.618_034).fract());
                let line = 1.0 + (k % 15) as f32;
                let target = if k % 2 == 0 {
                    Vec3::new(line, along, 0.0)
                } else {
                    Vec3::new(along, line, 0.0)
                };
                let tilt = Vec3::new(0.3 * (k as f32).sin(), 0.3 * (k as f32).cos(), 1.0);
                let origin = target + tilt.normalize() * distance;
                let ray = MeshRay::new(origin, target - origin);
                holes += bvh
                    .closest::<false>(&meshes, &ray, f32::INFINITY, None)
                    .is_none() as usize;
                rays += 1;
            }
        }
        assert_eq!(holes, 0, "{holes} of {rays} rays missed");
    }

    #[test]
    fn negative_zero_direction_components_traverse() {
        let meshes = [grid(8, 0)];
        let bvh = MeshBvh::build(&meshes);
        let ray = MeshRay::new(Vec3::new(3.3, 4.4, 2.0), Vec3::new(-0.0, -0.0, -1.0));
        assert!(
            bvh.closest::<false>(&meshes, &ray, f32::INFINITY, None)
                .is_some()
        );
    }

    /// The covering boxes of a mesh's BVH are several (an instance of it is boxed tightly), at
    /// most the number asked for, and hold every vertex.
    #[test]
    fn covering_boxes_are_few_and_hold_the_mesh() {
        let meshes = [grid(64, 0)];
        let bvh = MeshBvh::build(&meshes);
        for max in [8, 16, 64] {
            let boxes = bvh.covering_boxes(max);
            assert!(
                boxes.len() > 1 && boxes.len() <= max,
                "{} boxes",
                boxes.len()
            );
            for p in meshes[0].positions() {
                let p = p.as_dvec3();
                assert!(
                    boxes
                        .iter()
                        .any(|(lo, hi)| lo.cmple(p).all() && p.cmple(*hi).all()),
                    "{p} outside"
                );
            }
        }
        // 16 boxes allow opening the 8-wide root's children: more boxes than the root alone.
        assert!(bvh.covering_boxes(16).len() > bvh.covering_boxes(8).len());
    }

    /// The AVX2 path's traversal (its 8-wide nodes tested in AVX registers) finds the same hits
    /// as the baseline's, bit for bit, on a bumpy mesh hit from every side; skipped (and said)
    /// where this process does not take the AVX2 path.
    #[test]
    fn avx2_and_baseline_traversals_agree() {
        if super::super::simd_path() != super::super::SimdPath::Avx2 {
            eprintln!("skipped: this machine or QUADRAY_SIMD does not take the AVX2 path");
            return;
        }
        let flat = grid(48, 0);
        let bumpy: Vec<Vec3> = (flat.positions().iter())
            .map(|p| Vec3::new(p.x, p.y, (p.x * 0.7).sin() * (p.y * 0.45).cos() * 3.0))
            .collect();
        let meshes = [Mesh::new(bumpy, flat.indices().to_vec(), None, 0).unwrap()];
        let bvh = MeshBvh::build(&meshes);
        let mut hits = 0;
        for k in 0..20_000u32 {
            let f = k as f32;
            let origin = Vec3::new(
                24.0 + 40.0 * (f * 0.618_034).fract() - 20.0,
                24.0 + 40.0 * (f * 0.414_213_5).fract() - 20.0,
                if k % 2 == 0 { 10.0 } else { -10.0 },
            );
            let target = Vec3::new(
                48.0 * (f * 0.302_775).fract(),
                48.0 * (f * 0.732_05).fract(),
                0.0,
            );
            let ray = MeshRay::new(origin, target - origin);
            let t_max = if k % 3 == 0 { 0.5 } else { f32::INFINITY };
            let avx = bvh.closest::<true>(&meshes, &ray, t_max, None);
            let base = bvh.closest::<false>(&meshes, &ray, t_max, None);
            let key = |h: Option<MeshHit>| h.map(|h| (h.id, h.hit.t.to_bits(), h.block, h.lane));
            assert_eq!(key(avx), key(base), "ray {k}");
            assert_eq!(
                bvh.occluded::<true>(&meshes, &ray, t_max, None),
                bvh.occluded::<false>(&meshes, &ray, t_max, None),
                "ray {k}"
            );
            hits += base.is_some() as u32;
        }
        assert!(hits > 5000, "{hits} hits");
    }

    /// Over several meshes, hits name the right mesh and triangle, and skipping works per mesh.
    #[test]
    fn several_meshes_share_one_bvh() {
        let lower = grid(4, 0);
        let p: Vec<Vec3> = lower.positions().iter().map(|p| *p + Vec3::Z).collect();
        let upper = Mesh::new(p, lower.indices().to_vec(), None, 1).unwrap();
        let meshes = [lower, upper];
        let bvh = MeshBvh::build(&meshes);
        let ray = MeshRay::new(Vec3::new(1.3, 2.6, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let hit = bvh
            .closest::<false>(&meshes, &ray, f32::INFINITY, None)
            .unwrap();
        let MeshHit {
            id: (m, tri),
            hit: h,
            ..
        } = hit;
        assert_eq!((m, h.t), (1, 4.0));
        let vertices = bvh.vertices(&hit);
        // The hit's vertices are the mesh's own (the f64 refinement reads them from the block).
        let mesh_vertices = meshes[1]
            .triangle_positions(tri)
            .map(|p| Vec3::from(*p).as_dvec3());
        assert_eq!(vertices, mesh_vertices);
        let MeshHit {
            id: (m2, _),
            hit: h2,
            ..
        } = bvh
            .closest::<false>(&meshes, &ray, f32::INFINITY, Some((1, tri)))
            .unwrap();
        assert_eq!((m2, h2.t), (0, 5.0));
        assert!(bvh.occluded::<false>(&meshes, &ray, 4.5, None));
        assert!(!bvh.occluded::<false>(&meshes, &ray, 4.5, Some((1, tri))));
    }
}
