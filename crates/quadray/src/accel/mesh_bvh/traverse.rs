//! The mesh BVH's traversals: the closest hit and any hit, nearest children first for the
//! former, each compiled twice (the AVX2 path's copy inlined into its caller, the baseline's a
//! function of its own: see [`MeshBvh::closest_on`]).

use super::leaves::LeafLanes;
use super::{MeshBvh, MeshHit, MeshRay, TriId};
use crate::accel::stack::local_cell;
use crate::accel::tri4::{BlockHits, Tri4};
use crate::accel::wide::{LEAF, Node8, pop_nearer};
use crate::mesh::Mesh;
use crate::triangle::TriangleHit;
use std::cell::Cell;

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

    /// [`MeshBvh::closest_on`] for a compact BVH ([`MeshBvh::numbered`]), out of line on both
    /// paths: the copied leaves' traversals, inlined into their callers, keep their code.
    #[inline(never)]
    pub(crate) fn closest_compact<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set on the AVX2 path only, chosen where the CPU has AVX2 and FMA.
            return unsafe { self.closest_compact_avx2(meshes, ray, t_max, skip, stack) };
        }
        self.traverse_closest::<false, true>(meshes, ray, t_max, skip, stack)
    }

    /// [`MeshBvh::closest_compact`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn closest_compact_avx2(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        self.traverse_closest::<true, true>(meshes, ray, t_max, skip, stack)
    }

    /// The closest-hit traversal (`AVX2` as for [`MeshBvh::closest_on`]; `COMPACT` over compact
    /// leaves, whose blocks are read from the meshes).
    #[inline(always)]
    fn traverse_closest<const AVX2: bool, const COMPACT: bool>(
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
                    // A compact leaf's block, read from the meshes.
                    let read;
                    let block = if COMPACT {
                        read = self.read(meshes, self.numbers[index], lanes & 0xF);
                        &read
                    } else {
                        &self.blocks[index]
                    };
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

    /// [`MeshBvh::occluded`] for a compact BVH, out of line on both paths (as
    /// [`MeshBvh::closest_compact`]).
    #[inline(never)]
    pub(crate) fn occluded_compact<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set on the AVX2 path only, chosen where the CPU has AVX2 and FMA.
            return unsafe { self.occluded_compact_avx2(meshes, ray, t_max, skip) };
        }
        self.traverse_occluded::<false, true>(meshes, ray, t_max, skip)
    }

    /// [`MeshBvh::occluded_compact`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn occluded_compact_avx2(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        self.traverse_occluded::<true, true>(meshes, ray, t_max, skip)
    }

    /// The any-hit traversal (`AVX2` and `COMPACT` as for [`MeshBvh::traverse_closest`]).
    #[inline(always)]
    fn traverse_occluded<const AVX2: bool, const COMPACT: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        if self.nodes.is_empty() || !ray.finite {
            return false;
        }
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
                    // A compact leaf's block, read from the meshes.
                    let read;
                    let block = if COMPACT {
                        read = self.read(meshes, self.numbers[index], lanes & 0xF);
                        &read
                    } else {
                        &self.blocks[index]
                    };
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
mod tests {
    use super::super::tests::grid;
    use super::*;
    use crate::accel::wide::LeafLayout;
    use crate::accel::{SimdPath, simd_path};
    use glam::Vec3;

    /// Every ray through the grid's interior (including along the shared edges and through
    /// vertices) hits, at the plane's t; a brute-force scan over the mesh's triangles
    /// agrees on the nearest t.
    #[test]
    fn bvh_traversal_matches_brute_force_and_has_no_cracks() {
        let meshes = [grid(16, 0)];
        let bvh = MeshBvh::build(&meshes, false);
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
            let bvh = MeshBvh::build(&meshes, false);
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
        let bvh = MeshBvh::build(&meshes, false);
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
        let bvh = MeshBvh::build(&meshes, false);
        let ray = MeshRay::new(Vec3::new(3.3, 4.4, 2.0), Vec3::new(-0.0, -0.0, -1.0));
        assert!(
            bvh.closest::<false>(&meshes, &ray, f32::INFINITY, None)
                .is_some()
        );
    }

    /// A 48x48 grid bent into hills of height `height`, `waves` giving the bends' frequencies
    /// along x and y.
    fn bumpy_grid(waves: (f32, f32), height: f32) -> Mesh {
        let flat = grid(48, 0);
        let bumpy: Vec<Vec3> = (flat.positions().iter())
            .map(|p| {
                Vec3::new(
                    p.x,
                    p.y,
                    (p.x * waves.0).sin() * (p.y * waves.1).cos() * height,
                )
            })
            .collect();
        Mesh::new(bumpy, flat.indices().to_vec(), None, 0).unwrap()
    }

    /// Probe ray `k` of a bumpy grid, from above or below at any slant, and its `t_max` (every
    /// third one short).
    fn probe(k: u32) -> (MeshRay, f32) {
        let f = k as f32;
        let origin = Vec3::new(
            24.0 + 40.0 * (f * 0.618_034).fract() - 20.0,
            24.0 + 40.0 * (f * 0.414_213_5).fract() - 20.0,
            if k.is_multiple_of(2) { 10.0 } else { -10.0 },
        );
        let target = Vec3::new(
            48.0 * (f * 0.302_775).fract(),
            48.0 * (f * 0.732_05).fract(),
            0.0,
        );
        let t_max = if k.is_multiple_of(3) {
            0.5
        } else {
            f32::INFINITY
        };
        (MeshRay::new(origin, target - origin), t_max)
    }

    /// The AVX2 path's traversal (its 8-wide nodes tested in AVX registers) finds the same hits
    /// as the baseline's, bit for bit, on a bumpy mesh hit from every side; skipped (and said)
    /// where this process does not take the AVX2 path.
    #[test]
    fn avx2_and_baseline_traversals_agree() {
        if simd_path() != SimdPath::Avx2 {
            eprintln!("skipped: this machine or QUADRAY_SIMD does not take the AVX2 path");
            return;
        }
        let meshes = [bumpy_grid((0.7, 0.45), 3.0)];
        let bvh = MeshBvh::build(&meshes, false);
        let mut hits = 0;
        for k in 0..20_000u32 {
            let (ray, t_max) = probe(k);
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

    /// Leaves sharing blocks give every hit, t and any-hit answer that leaves in blocks of their
    /// own give, on both paths, in fewer blocks.
    #[test]
    fn shared_and_own_block_leaves_agree() {
        let meshes = [bumpy_grid((0.9, 0.35), 4.0)];
        let shared = MeshBvh::build_in(&meshes, LeafLayout::LONG_TAG);
        let own = MeshBvh::build_in(&meshes, LeafLayout::SHORT_TAG);
        assert!(shared.blocks.len() < own.blocks.len());
        let avx2 = simd_path() == SimdPath::Avx2;
        let mut hits = 0;
        for k in 0..20_000u32 {
            let (ray, t_max) = probe(k);
            let key = |bvh: &MeshBvh, h: Option<MeshHit>| {
                h.map(|h| {
                    (
                        h.id,
                        h.hit.t.to_bits(),
                        bvh.vertices(&h).map(|v| v.to_array()),
                    )
                })
            };
            let want = key(&own, own.closest::<false>(&meshes, &ray, t_max, None));
            assert_eq!(
                key(&shared, shared.closest::<false>(&meshes, &ray, t_max, None)),
                want
            );
            let blocked = own.occluded::<false>(&meshes, &ray, t_max, None);
            assert_eq!(
                shared.occluded::<false>(&meshes, &ray, t_max, None),
                blocked
            );
            if avx2 {
                assert_eq!(
                    key(&shared, shared.closest::<true>(&meshes, &ray, t_max, None)),
                    want
                );
                assert_eq!(shared.occluded::<true>(&meshes, &ray, t_max, None), blocked);
            }
            hits += want.is_some() as u32;
        }
        assert!(hits > 5000, "{hits} hits");
    }

    /// A compact BVH's answers against the copied one's for one ray, on the `AVX2` path: the
    /// hit (mesh, triangle, t and vertices), then skipping that triangle, and any hit with and
    /// without the skip. Whether the ray hits.
    fn compact_agrees<const AVX2: bool>(
        meshes: &[Mesh],
        (copied, compact): (&MeshBvh, &MeshBvh),
        ray: &MeshRay,
        t_max: f32,
    ) -> bool {
        let mut stack = Vec::new();
        let mut closest = |skip: Option<TriId>| {
            let want = copied.closest_on::<AVX2>(meshes, ray, t_max, skip, &mut stack);
            let got = compact.closest_compact::<AVX2>(meshes, ray, t_max, skip, &mut stack);
            let want = want.map(|h| (h.id, h.hit.t.to_bits(), copied.vertices(&h)));
            let got = got.map(|h| (h.id, h.hit.t.to_bits(), compact.mesh_vertices(meshes, &h)));
            assert_eq!(got, want, "skipping {skip:?}");
            want.map(|(id, ..)| id)
        };
        let first = closest(None);
        closest(first);
        for skip in [None, first] {
            assert_eq!(
                compact.occluded_compact::<AVX2>(meshes, ray, t_max, skip),
                copied.occluded::<AVX2>(meshes, ray, t_max, skip),
                "skipping {skip:?}"
            );
        }
        first.is_some()
    }

    /// A compact BVH, whose leaves hold triangle numbers and read the vertices from the meshes,
    /// gives every hit, t, vertex and any-hit answer the copied one gives, a triangle skipped or
    /// not, on both paths, over two meshes (numbered through the id table), in 16 bytes a leaf
    /// block instead of 160.
    #[test]
    fn compact_and_copied_leaves_agree() {
        let bumpy = bumpy_grid((0.8, 0.5), 3.0);
        let shifted = (bumpy.positions().iter())
            .map(|p| *p + Vec3::new(3.0, 1.0, 2.5))
            .collect();
        let second = Mesh::new(shifted, bumpy.indices().to_vec(), None, 1).unwrap();
        let meshes = [bumpy, second];
        let copied = MeshBvh::build(&meshes, false);
        let compact = MeshBvh::build(&meshes, true);
        assert!(compact.compact() && !copied.compact());
        assert_eq!(compact.numbers.len(), copied.blocks.len());
        // The same nodes and id table; 16 bytes a block instead of 160.
        let saved = copied.memory_bytes() - compact.memory_bytes();
        assert_eq!(saved, copied.blocks.len() * (size_of::<Tri4>() - 16));
        let avx2 = simd_path() == SimdPath::Avx2;
        let mut hits = 0;
        for k in 0..20_000u32 {
            let (ray, t_max) = probe(k);
            let pair = (&copied, &compact);
            hits += compact_agrees::<false>(&meshes, pair, &ray, t_max) as u32;
            if avx2 {
                compact_agrees::<true>(&meshes, pair, &ray, t_max);
            }
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
        let bvh = MeshBvh::build(&meshes, false);
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
