//! The bottom level for analytic primitives (spheres and clipped quadrics): a 4-wide BVH of the
//! shared node layout ([`super::wide`]) traversed in f32 over boxes padded to stay conservative,
//! with every primitive intersected in f64.
//!
//! Leaves are blocks of four lanes. Spheres fill blocks four at a time: an f32 filter tells which
//! of the four the ray's line certainly misses ([`Sphere4`]), and only the others get the exact
//! f64 test, so results are those of the f64 test alone. A quadric, whose test is several sphere
//! tests' worth, weighs a whole block and is a leaf of its own, so its box is culled by the node
//! above it (measured with the BVH2 this replaced, on scenes/reflective.toml: leaves of one
//! primitive beat leaves of up to eight by 6%). Many spheres, grouped four by four before the
//! build ([`super::sphere_clusters`]), make leaves of up to eight blocks, which keeps a sphere
//! and its share of the BVH within 64 bytes.
//!
//! Two things keep the f32 traversal conservative: each box is padded by a few f32 ulps of the
//! largest coordinate any ray origin or primitive can have (covering the rounding of the ray
//! origin and direction to f32), the slab test widens exit distances (Ize), and the t limit the
//! nodes cull with is rounded up. Closest-hit traversal visits children nearest first and skips
//! those entered beyond the best hit; occlusion visits them in any order and stops at the first
//! blocker.

use super::build::{build_single_leaves, padded_aabb};
use super::round_up;
use super::sphere_clusters::{CLUSTER, CLUSTER_FROM, morton_order};
use super::sphere4::{FilterRay, Sphere4};
use super::stack::local_cell;
use super::wide::{
    BoxRay, LEAF, LEAF_WEIGHT, LeafLayout, Node4, collapse, leaf_blocks, pop_nearer, whole_blocks,
};
use crate::geometry::Level;
use crate::math::Ray;
use crate::shape::LocalPrim;
use obvhs::aabb::Aabb;
use std::cell::Cell;

/// A leaf block: up to four spheres, or one quadric.
#[derive(Clone, Copy, Debug)]
struct Block {
    spheres: Sphere4,
    /// Each lane's primitive: a sphere index, or [`QUADRIC`] with a quadric index; [`NO_PRIM`]
    /// for an unused lane.
    prims: [u32; 4],
}

/// The most a leaf of grouped spheres weighs: eight groups of four. Measured on 1M-sphere
/// lattices and flat layers (1280x720, 1 thread, medians of 5-7 alternating runs), leaves of one,
/// two, four and seven groups render in the same time (the lattice 0.282, 0.277, 0.276, 0.276 s;
/// the flat layer 0.359, 0.349, 0.342, 0.342 s; the lattice with reflective spheres 0.896, 0.868,
/// 0.862, 0.862 s), while the nodes take 13.2, 7.9, 5.1 and 3.0 bytes a sphere: the blocks' f32
/// filter rejects most of a leaf's spheres for less than a level of nodes costs. On lattices whose
/// side is a power of two, seven groups leave the leaves of four a balanced tree makes (the nodes
/// 4.4 bytes a sphere on a 32³ lattice); eight make leaves of eight there (1.3), and more gain
/// little anywhere (on lattices and layers of 8 000 to 262 144 spheres, the nodes take at most
/// 2.9 bytes a sphere with eight groups, 2.1 with twelve). With eight, against one (same run):
/// the 1M lattice 0.278 → 0.274 s, the layer 0.357 → 0.340 s, the reflective lattice 0.885 →
/// 0.869 s, the nodes 2.6 bytes a sphere.
const GROUPED_LEAF_WEIGHT: u32 = 8 * LEAF_WEIGHT;

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
    /// The analytic BVHs' traversal stack of (child reference, entry distance), reused across
    /// rays (taken out of its cell by each traversal: [`local_cell`]).
    static STACK: Cell<Vec<(u32, f32)>> = const { Cell::new(Vec::new()) };
}

impl AnalyticBvh {
    /// Builds the BVH, or `None` when there are no analytic primitives. `extent` bounds the
    /// magnitude of every coordinate a ray may start at.
    pub(crate) fn build(level: Level<'_>, extent: f32) -> Option<AnalyticBvh> {
        Self::build_grouping(level, extent, level.spheres.len() >= CLUSTER_FROM)
    }

    /// [`AnalyticBvh::build`], grouping the spheres before the build or not.
    fn build_grouping(level: Level<'_>, extent: f32, group: bool) -> Option<AnalyticBvh> {
        let len = level.spheres.len() + level.quadrics.len();
        if len == 0 {
            return None;
        }
        // The builder's items: the spheres one by one, or grouped four by four in Morton order
        // (many spheres); then the quadrics one by one.
        let grouped = group.then(|| morton_order(level.spheres));
        let sphere_box = |i: u32| padded_aabb(level.spheres[i as usize].bounds(), extent);
        let mut aabbs: Vec<Aabb> = match &grouped {
            Some(order) => (order.chunks(CLUSTER))
                .map(|group| {
                    (group.iter().map(|&i| sphere_box(i)))
                        .reduce(|a, b| a.union(&b))
                        .expect("groups are not empty")
                })
                .collect(),
            None => (0..level.spheres.len() as u32).map(sphere_box).collect(),
        };
        let sphere_items = aabbs.len();
        aabbs.extend((level.quadrics.iter()).map(|q| padded_aabb(q.bounds(), extent)));
        let bvh2 = build_single_leaves(&aabbs);
        // 32 bytes an item, not needed past the build: freed before the leaves are packed.
        drop(aabbs);
        let is_sphere = |p: u32| (p as usize) < sphere_items;
        // The spheres of sphere item `p`.
        let spheres_of = |p: u32| {
            let mut out = [p; CLUSTER];
            let n = match &grouped {
                Some(order) => {
                    let first = p as usize * CLUSTER;
                    let group = &order[first..(first + CLUSTER).min(order.len())];
                    out[..group.len()].copy_from_slice(group);
                    group.len()
                }
                None => 1,
            };
            (out, n)
        };
        // Leaves of one block: two (up to 8 spheres) took 16% less BVH memory but 10 000
        // reflective spheres 4% longer (1280x720, 1 thread, medians of 5 alternating runs).
        // Grouped spheres make leaves of up to eight groups: see [`GROUPED_LEAF_WEIGHT`].
        let leaf_weight = match grouped {
            Some(_) => GROUPED_LEAF_WEIGHT,
            None => LEAF_WEIGHT,
        };
        // A sphere weighs a lane; a group, a block; a quadric, a whole leaf.
        let weight = |p: u32| match grouped {
            None if is_sphere(p) => 1,
            Some(_) if is_sphere(p) => LEAF_WEIGHT,
            _ => leaf_weight,
        };
        let (nodes, blocks) = collapse(
            &bvh2,
            LeafLayout::SHORT_TAG,
            leaf_weight,
            None,
            weight,
            |prims, blocks: &mut Vec<Block>| {
                let first = blocks.len();
                pack_leaf(blocks, level, prims, sphere_items, &spheres_of);
                (first, whole_blocks(blocks.len() - first))
            },
        );
        Some(AnalyticBvh {
            nodes: nodes.into_boxed_slice().into_vec(),
            blocks: blocks.into_boxed_slice().into_vec(),
            root: *bvh2.nodes[0].aabb(),
            len,
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
        &self.blocks[leaf_blocks(leaf)]
    }

    /// Lowers `best_t` to the nearest hit in (0, `best_t`), returning its primitive if there is one.
    #[inline(never)]
    pub(crate) fn closest(
        &self,
        g: Level<'_>,
        ray: &Ray,
        best_t: &mut f64,
        from: Option<LocalPrim>,
    ) -> Option<LocalPrim> {
        self.closest_inlined(g, ray, best_t, from)
    }

    /// [`AnalyticBvh::closest`] inlined into its caller: the analytic scenes' traversal (their
    /// rays take the baseline path), where a call a ray cost 1.6% of a reflective frame's
    /// instructions. The AVX2 path, which mesh scenes take, calls [`AnalyticBvh::closest`]:
    /// inlined there, the mesh traversal beside it took 2.2% more instructions a ray.
    #[inline(always)]
    pub(crate) fn closest_inlined(
        &self,
        g: Level<'_>,
        ray: &Ray,
        best_t: &mut f64,
        from: Option<LocalPrim>,
    ) -> Option<LocalPrim> {
        let mut best = None;
        let (boxes, filter) = f32_rays(ray)?;
        let mut limit = round_up(*best_t);
        let cell = local_cell(&STACK);
        let mut stack = cell.take();
        stack.clear();
        let mut current = 0u32;
        loop {
            if current & LEAF == 0 {
                let node = &self.nodes[current as usize];
                let (enter, mask) = node.intersect(&boxes, limit);
                // One child entered is taken without the stack, several are pushed far to near
                // (one is told by `mask & (mask - 1)`: `count_ones` has no instruction on
                // baseline x86-64).
                if mask != 0 {
                    current = if mask & (mask - 1) == 0 {
                        node.children[mask.trailing_zeros() as usize]
                    } else {
                        node.push_ordered(enter.to_array(), mask, &mut stack, |_| {})
                    };
                    continue;
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
            match pop_nearer(&mut stack, limit) {
                Some(child) => current = child,
                None => break,
            }
        }
        cell.set(stack);
        best
    }

    /// Whether any primitive blocks the ray in (0, `t_max`).
    // Always inlined into the closure of `Accel::occluded_in` that calls it, as `#[inline]` did
    // before the mesh traversal beside it grew: the analytic shadow rays keep their code.
    #[inline(always)]
    pub(crate) fn occluded(
        &self,
        g: Level<'_>,
        ray: &Ray,
        t_max: f64,
        from: Option<LocalPrim>,
    ) -> bool {
        let Some((boxes, filter)) = f32_rays(ray) else {
            return false;
        };
        let limit = round_up(t_max);
        let cell = local_cell(&STACK);
        let mut stack = cell.take();
        stack.clear();
        let mut current = 0u32;
        let blocked = 'search: loop {
            if current & LEAF == 0 {
                let node = &self.nodes[current as usize];
                let (_, mask) = node.intersect(&boxes, limit);
                if mask != 0 {
                    current = node.push_all_but_last(mask, &mut stack, |_| {});
                    continue;
                }
            } else {
                for block in self.leaf_blocks(current) {
                    if block_closest(block, g, ray, &filter, t_max, from).is_some() {
                        break 'search true;
                    }
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

/// Packs a leaf's items into blocks appended to `blocks`: the spheres of its sphere items four to
/// a block, then one block per quadric.
fn pack_leaf(
    blocks: &mut Vec<Block>,
    level: Level<'_>,
    items: &[u32],
    sphere_items: usize,
    spheres_of: &impl Fn(u32) -> ([u32; CLUSTER], usize),
) {
    let is_sphere = |p: u32| (p as usize) < sphere_items;
    let mut lane = 4;
    for &p in items.iter().filter(|&&p| is_sphere(p)) {
        let (group, n) = spheres_of(p);
        for &sphere in &group[..n] {
            if lane == 4 {
                blocks.push(Block {
                    spheres: Sphere4::EMPTY,
                    prims: [NO_PRIM; 4],
                });
                lane = 0;
            }
            let block = blocks.last_mut().expect("a block was pushed");
            block.spheres.set(lane, &level.spheres[sphere as usize]);
            block.prims[lane] = sphere;
            lane += 1;
        }
    }
    for &p in items.iter().filter(|&&p| !is_sphere(p)) {
        let mut prims = [NO_PRIM; 4];
        prims[0] = QUADRIC | (p - sphere_items as u32);
        blocks.push(Block {
            spheres: Sphere4::EMPTY,
            prims,
        });
    }
}

/// The ray in f32 for the node test and the sphere filter, or `None` when its origin or direction
/// is not finite in f32. A ray beyond f32's range (an origin at 10³⁹, reached through an instance
/// scaled by 10⁻⁴⁰) meets nothing, as at every level: the f32 boxes cannot bound it, so any hit
/// found would depend on how their infinities compare.
#[inline(always)]
fn f32_rays(ray: &Ray) -> Option<(BoxRay, FilterRay)> {
    let (origin, dir) = (ray.origin.as_vec3a(), ray.dir.as_vec3a());
    crate::math::all_finite(origin, dir)
        .then(|| (BoxRay::new(origin, dir), FilterRay::new(origin, dir)))
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadric::{ClipBox, Quadric, QuadricKind, QuadricSurface};
    use crate::sphere::Sphere;
    use crate::{Transform, math::Ray};
    use glam::DVec3;

    /// A level of `spheres` and nothing else.
    fn spheres_only(spheres: &[Sphere]) -> Level<'_> {
        Level {
            spheres,
            quadrics: &[],
            meshes: &[],
            instances: &[],
        }
    }

    /// The nearest hit over every primitive, one by one.
    fn brute(level: Level<'_>, ray: &Ray, from: Option<LocalPrim>) -> Option<(f64, LocalPrim)> {
        let prims = (0..level.spheres.len() as u32)
            .map(LocalPrim::Sphere)
            .chain((0..level.quadrics.len() as u32).map(LocalPrim::Quadric));
        let mut best: Option<(f64, LocalPrim)> = None;
        for p in prims {
            let limit = best.map_or(f64::INFINITY, |b| b.0);
            if let Some(t) = level.intersect(p, ray, limit, from == Some(p)) {
                best = Some((t, p));
            }
        }
        best
    }

    /// Spheres of a jittered lattice and a few quadrics among them, built with and without the
    /// Morton grouping: closest and any-hit answers equal a brute-force scan for rays from
    /// outside and rays spawned on the primitives.
    #[test]
    fn traversal_matches_brute_force_grouped_or_not() {
        let mut next = crate::test_rng::unit_stream(0x1234_5678_9abc_def0);
        let mut spheres = Vec::new();
        for i in 0..12 {
            for j in 0..12 {
                for k in 0..10 {
                    let c = DVec3::new(i as f64, j as f64, k as f64)
                        + DVec3::new(next(), next(), next()) * 0.3;
                    spheres.push(Sphere {
                        center: c,
                        radius: 0.2 + 0.25 * next(),
                        material: 0,
                    });
                }
            }
        }
        let quadrics: Vec<Quadric> = QuadricKind::ALL
            .iter()
            .enumerate()
            .map(|(n, &kind)| {
                let at = DVec3::new(n as f64 * 1.3, 5.5, 4.5);
                let t = Transform::from_srt(DVec3::splat(0.4), DVec3::ZERO, at).unwrap();
                let surface = QuadricSurface::Canonical {
                    kind,
                    a: 1.0,
                    b: 1.0,
                    c: 1.0,
                };
                Quadric::new(surface, ClipBox::cube(1.0), t, 0).unwrap()
            })
            .collect();
        let level = Level {
            spheres: &spheres,
            quadrics: &quadrics,
            meshes: &[],
            instances: &[],
        };
        for group in [false, true] {
            let bvh = AnalyticBvh::build_grouping(level, 30.0, group).unwrap();
            assert_eq!(bvh.len(), spheres.len() + quadrics.len());
            for k in 0..3000 {
                let target = DVec3::new(next() * 12.0, next() * 12.0, next() * 10.0);
                let (ray, from) = if k % 2 == 0 {
                    let origin = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 80.0;
                    (Ray::new(origin, target - origin), None)
                } else {
                    // Spawned on the nearest hit of another ray.
                    let origin = DVec3::new(-20.0, 6.0, 5.0);
                    let probe = Ray::new(origin, target - origin);
                    let Some((t, p)) = brute(level, &probe, None) else {
                        continue;
                    };
                    let dir = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
                    (Ray::new(probe.at(t), dir), Some(p))
                };
                let want = brute(level, &ray, from);
                let mut best_t = f64::INFINITY;
                let got = bvh.closest(level, &ray, &mut best_t, from);
                assert_eq!(got.map(|p| (best_t, p)), want, "grouped {group}, ray {k}");
                for limit in [0.5, 2.0] {
                    let blocked = want.is_some_and(|(t, _)| t < limit);
                    assert_eq!(bvh.occluded(level, &ray, limit, from), blocked);
                }
            }
        }
    }

    /// A lattice of grouped spheres costs at most 64 bytes a sphere: its own 40 in the scene,
    /// 20 in the leaf blocks and its share of the nodes.
    #[test]
    fn grouped_spheres_take_at_most_64_bytes_each() {
        let spheres: Vec<Sphere> = (0..32 * 32 * 32)
            .map(|i| Sphere {
                center: DVec3::new((i % 32) as f64, (i / 32 % 32) as f64, (i / 1024) as f64),
                radius: 0.4,
                material: 0,
            })
            .collect();
        let level = spheres_only(&spheres);
        let bvh = AnalyticBvh::build_grouping(level, 40.0, true).unwrap();
        let bytes = bvh.memory_bytes() + std::mem::size_of_val(spheres.as_slice());
        let per_sphere = bytes as f64 / spheres.len() as f64;
        assert!(per_sphere <= 64.0, "{per_sphere} bytes a sphere");
        // Ungrouped, the same lattice costs more: leaves of one block.
        let single = AnalyticBvh::build_grouping(level, 40.0, false).unwrap();
        assert!(single.memory_bytes() > bvh.memory_bytes());
    }

    /// Spheres at exponentially growing distances make a deep tree (obvhs' builder cannot
    /// balance it), and rays still find what a brute-force scan finds.
    #[test]
    fn deep_trees_traverse() {
        let spheres: Vec<Sphere> = (0..300)
            .map(|i| {
                let x = 1.2f64.powi(i);
                Sphere {
                    center: DVec3::new(x, 0.0, 0.0),
                    radius: 0.1 * x,
                    material: 0,
                }
            })
            .collect();
        let level = spheres_only(&spheres);
        let bvh = AnalyticBvh::build(level, 1e25).unwrap();
        for i in (0..300).step_by(7) {
            let x = 1.2f64.powi(i);
            let ray = Ray::new(DVec3::new(x, -5.0 * x, 0.05 * x), DVec3::Y);
            let want = brute(level, &ray, None);
            assert!(want.is_some());
            let mut best_t = f64::INFINITY;
            let got = bvh.closest(level, &ray, &mut best_t, None);
            assert_eq!(got.map(|p| (best_t, p)), want);
            assert!(bvh.occluded(level, &ray, f64::INFINITY, None));
        }
    }
}
