//! One level's traversal: its few items box by box, or its top BVH, and for each item the
//! level's analytic or mesh BVH, or the level an instance places (entered through
//! [`Accel::closest_level`] and [`Accel::occluded_level`], which choose the compiled path).
//!
//! Every function here is generic over `AVX2`, the compiled copy it is inlined into (see the
//! module docs of [`super`]); a closure or a function that is not inlined would be compiled for
//! the baseline, so the AVX2 copy's traversals keep out of them.

use super::mesh_bvh::{MeshBvh, MeshHit, MeshRay};
use super::stack::{Stacks, put_stack, take_stack, with_stack};
use super::top::TopLeaves;
use super::{Accel, FLAT_TOP, LevelAccel, TopItem, round_up, to_obvhs};
use crate::geometry::Geometry;
use crate::math::Ray;
use crate::shape::{LocalPrim, PrimRef};
use crate::triangle::plane_t;
use glam::DVec3;
use obvhs::bvh2::Bvh2;

/// Lowers `best_t` to the query's mesh hit `h` where it is nearer, recording its triangle: its
/// distance refined in f64 against the plane of its triangle's `vertices` (`Mesh::refine_t`).
#[inline(always)]
fn keep_mesh_hit(
    q: &Query<'_>,
    h: &MeshHit,
    vertices: [DVec3; 3],
    best_t: &mut f64,
    best: &mut Option<PrimRef>,
) {
    let t = plane_t(q.ray.origin, q.ray.dir, vertices, h.hit.t as f64);
    let (mesh, tri) = h.id;
    if t < *best_t {
        *best_t = t;
        *best = Some(PrimRef {
            placement: q.placement,
            local: LocalPrim::Triangle { mesh, tri },
        });
    }
}

impl Accel {
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn closest_level_impl<const AVX2: bool>(
        &self,
        g: &Geometry,
        level: usize,
        placement: u64,
        ray: &Ray,
        from: Option<PrimRef>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        let l = &self.levels[level];
        let q = Query::new(g, level, placement, ray, from);
        match &l.top {
            None if l.items.len() == 1 => {
                // One item tests its own root box.
                self.closest_in::<AVX2>(l, l.items[0], &q, best_t, best);
            }
            None => {
                // A few items: their boxes in order of entry, no BVH and no stack.
                let fray = to_obvhs(ray, *best_t);
                let mut order = [(0usize, 0f32); FLAT_TOP];
                let mut n = 0;
                for (i, b) in l.item_boxes.iter().enumerate() {
                    let enter = b.intersect_ray(&fray);
                    if enter < fray.tmax {
                        let mut j = n;
                        while j > 0 && order[j - 1].1 > enter {
                            order[j] = order[j - 1];
                            j -= 1;
                        }
                        order[j] = (i, enter);
                        n += 1;
                    }
                }
                for &(i, enter) in &order[..n] {
                    if (enter as f64) <= *best_t {
                        self.closest_in::<AVX2>(l, l.items[i], &q, best_t, best);
                    }
                }
            }
            // Inlined in the AVX2 copy; out of line in the baseline's, where inlined it cost the
            // analytic scenes' `Scene::intersect_from` 10% more instructions.
            Some(top) if AVX2 => {
                let mut stack = take_stack(&TOP_STACKS);
                self.closest_top::<AVX2>(l, top, &q, &mut stack, best_t, best);
                put_stack(&TOP_STACKS, stack);
            }
            Some(top) => self.closest_top_baseline(l, top, &q, best_t, best),
        }
    }

    /// [`Accel::closest_top`] compiled for the baseline, on a stack lent to a closure (cheaper
    /// than taking one: 5% of the instructions of scenes/columns.toml's frame).
    #[inline(never)]
    fn closest_top_baseline(
        &self,
        l: &LevelAccel,
        top: &Bvh2,
        q: &Query<'_>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        with_stack(&TOP_STACKS, |stack| {
            self.closest_top::<false>(l, top, q, stack, best_t, best)
        })
    }

    /// Lowers `best_t` to the nearest hit of the query's ray with the items of level `l` that
    /// its top BVH `top` reaches. On the AVX2 path the stack is taken, not lent to a closure, so
    /// the items' traversals inlined here keep the AVX2 copy's target features.
    #[inline(always)]
    fn closest_top<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        top: &Bvh2,
        q: &Query<'_>,
        stack: &mut Vec<u32>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        let fray = to_obvhs(q.ray, *best_t);
        let mut leaves = TopLeaves::new(top, &fray, stack);
        while let Some(range) = leaves.next(round_up(*best_t)) {
            for id in range {
                self.closest_in::<AVX2>(l, l.items[id], q, best_t, best);
            }
        }
    }

    /// Lowers `best_t` to the nearest hit of the query's ray with `item` of level `l`, recording
    /// its primitive.
    #[inline(always)]
    fn closest_in<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        item: TopItem,
        q: &Query<'_>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        match item {
            TopItem::Analytic => {
                if let Some(a) = &l.analytic
                    && let Some(local) = if AVX2 {
                        a.closest(q.g.level(q.level), q.ray, best_t, q.skip())
                    } else {
                        a.closest_inlined(q.g.level(q.level), q.ray, best_t, q.skip())
                    }
                {
                    *best = Some(PrimRef {
                        placement: q.placement,
                        local,
                    });
                }
            }
            TopItem::Meshes => {
                let mut stack = MeshBvh::take_stack();
                self.closest_in_meshes::<AVX2>(l, q, &mut stack, best_t, best);
                MeshBvh::put_stack(stack);
            }
            TopItem::Instance { index, level } => {
                let inst = &q.g.level(q.level).instances[index as usize];
                let local = inst.ray_to_object(q.ray);
                let placement = self.placements.child(q.level, index as usize, q.placement);
                self.closest_level(q.g, level as usize, placement, &local, q.from, best_t, best);
            }
            TopItem::Placed(i) => {
                let p = &l.placed[i as usize];
                let local = p.ray(q.ray);
                let placement = q.placement + p.offset;
                let level = p.level as usize;
                self.closest_level(q.g, level, placement, &local, q.from, best_t, best);
            }
        }
    }

    /// [`Accel::closest_in_meshes`] for the compact mesh BVH of level `l`, if it has one.
    #[inline(never)]
    fn closest_in_compact_meshes<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        q: &Query<'_>,
        stack: &mut Vec<(u32, f32)>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        let Some(bvh) = &l.compact_meshes else { return };
        let meshes = q.g.level(q.level).meshes;
        let mray = q.mesh_ray();
        let (t_max, skip) = (round_up(*best_t), q.triangle_skip());
        if let Some(h) = bvh.closest_compact::<AVX2>(meshes, &mray, t_max, skip, stack) {
            keep_mesh_hit(q, &h, bvh.mesh_vertices(meshes, &h), best_t, best);
        }
    }

    /// Lowers `best_t` to the nearest hit of the query's ray with the mesh BVH of level `l`,
    /// traversed on `stack` (the thread's: [`MeshBvh::take_stack`]).
    #[inline(always)]
    fn closest_in_meshes<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        q: &Query<'_>,
        stack: &mut Vec<(u32, f32)>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        let Some(bvh) = &l.meshes else {
            return self.closest_in_compact_meshes::<AVX2>(l, q, stack, best_t, best);
        };
        let meshes = q.g.level(q.level).meshes;
        let mray = q.mesh_ray();
        let (t_max, skip) = (round_up(*best_t), q.triangle_skip());
        if let Some(h) = bvh.closest_on::<AVX2>(meshes, &mray, t_max, skip, stack) {
            keep_mesh_hit(q, &h, bvh.vertices(&h), best_t, best);
        }
    }

    /// [`Accel::closest_each`]'s loop where the world is one mesh BVH and nothing else (no
    /// planes, analytic shapes or instances), its level's dispatch decided and the traversal
    /// stack taken once for the batch; `false`, doing nothing, for any other world.
    #[inline(always)]
    pub(super) fn closest_each_in_world_meshes<const AVX2: bool>(
        &self,
        g: &Geometry,
        rays: &[Ray],
        hits: &mut [Option<(f64, PrimRef)>],
    ) -> bool {
        let l = &self.levels[0];
        if self.planes != 0 || l.top.is_some() || !matches!(l.items[..], [TopItem::Meshes]) {
            return false;
        }
        let mut stack = MeshBvh::take_stack();
        for (ray, hit) in rays.iter().zip(hits) {
            let (mut best_t, mut best) = (f64::INFINITY, None);
            let q = Query::new(g, 0, 0, ray, None);
            self.closest_in_meshes::<AVX2>(l, &q, &mut stack, &mut best_t, &mut best);
            *hit = best.map(|p| (best_t, p));
        }
        MeshBvh::put_stack(stack);
        true
    }

    #[inline(always)]
    pub(super) fn occluded_level_impl<const AVX2: bool>(
        &self,
        g: &Geometry,
        level: usize,
        placement: u64,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        let l = &self.levels[level];
        let q = Query::new(g, level, placement, ray, from);
        match &l.top {
            None if l.items.len() == 1 => self.occluded_in::<AVX2>(l, l.items[0], &q, t_max),
            None => {
                // A loop, not `any` with a closure: as for the top's stack below.
                let fray = to_obvhs(ray, t_max);
                for (&item, b) in l.items.iter().zip(&l.item_boxes) {
                    if b.intersect_ray(&fray) < fray.tmax
                        && self.occluded_in::<AVX2>(l, item, &q, t_max)
                    {
                        return true;
                    }
                }
                false
            }
            // As in `closest_level_impl`.
            Some(top) if AVX2 => {
                let mut stack = take_stack(&TOP_STACKS);
                let blocked = self.occluded_top::<AVX2>(l, top, &q, &mut stack, t_max);
                put_stack(&TOP_STACKS, stack);
                blocked
            }
            Some(top) => self.occluded_top_baseline(l, top, &q, t_max),
        }
    }

    /// [`Accel::occluded_top`] compiled for the baseline (the stack lent, as in
    /// [`Accel::closest_top_baseline`]).
    #[inline(never)]
    fn occluded_top_baseline(&self, l: &LevelAccel, top: &Bvh2, q: &Query<'_>, t_max: f64) -> bool {
        with_stack(&TOP_STACKS, |stack| {
            self.occluded_top::<false>(l, top, q, stack, t_max)
        })
    }

    /// Whether the compact mesh BVH of level `l` blocks the query's ray in (0, `t_max`).
    #[inline(never)]
    fn occluded_in_compact_meshes<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        q: &Query<'_>,
        t_max: f64,
    ) -> bool {
        let Some(bvh) = &l.compact_meshes else {
            return false;
        };
        let mray = q.mesh_ray();
        let meshes = q.g.level(q.level).meshes;
        bvh.occluded_compact::<AVX2>(meshes, &mray, round_up(t_max), q.triangle_skip())
    }

    /// Whether an item of level `l` that its top BVH `top` reaches blocks the query's ray in
    /// (0, `t_max`) (the stack as in [`Accel::closest_top`]).
    #[inline(always)]
    fn occluded_top<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        top: &Bvh2,
        q: &Query<'_>,
        stack: &mut Vec<u32>,
        t_max: f64,
    ) -> bool {
        let fray = to_obvhs(q.ray, t_max);
        let mut leaves = TopLeaves::new(top, &fray, stack);
        while let Some(range) = leaves.next(fray.tmax) {
            for id in range {
                if self.occluded_in::<AVX2>(l, l.items[id], q, t_max) {
                    return true;
                }
            }
        }
        false
    }

    /// Lowers `best_t` to the nearest hit of `ray` with top item `item` of the world, on the
    /// baseline path (the eye buffer's test of the one item it sees).
    pub(super) fn closest_world_item(
        &self,
        g: &Geometry,
        item: TopItem,
        ray: &Ray,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        let q = Query::new(g, 0, 0, ray, None);
        self.closest_in::<false>(&self.levels[0], item, &q, best_t, best);
    }

    /// Whether top item `item` of the world blocks `ray` in (0, `t_max`), on the baseline path
    /// (the light buffers' test of an item they list).
    pub(super) fn occluded_world_item(
        &self,
        g: &Geometry,
        item: TopItem,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        let q = Query::new(g, 0, 0, ray, from);
        self.occluded_in::<false>(&self.levels[0], item, &q, t_max)
    }

    /// Whether `item` of level `l` blocks the query's ray in (0, `t_max`).
    #[inline(always)]
    fn occluded_in<const AVX2: bool>(
        &self,
        l: &LevelAccel,
        item: TopItem,
        q: &Query<'_>,
        t_max: f64,
    ) -> bool {
        match item {
            // The analytic traversal in a closure of its own (inlined, it made the callers of
            // `Accel::occluded` larger and analytic frames 3% slower); the mesh traversal not
            // (a closure is compiled with the target features of the function it is written in,
            // so on the AVX2 path the traversal in it ran without them).
            TopItem::Analytic => l
                .analytic
                .as_ref()
                .is_some_and(|a| a.occluded(q.g.level(q.level), q.ray, t_max, q.skip())),
            TopItem::Meshes => match &l.meshes {
                Some(bvh) => {
                    let mray = q.mesh_ray();
                    let meshes = q.g.level(q.level).meshes;
                    bvh.occluded::<AVX2>(meshes, &mray, round_up(t_max), q.triangle_skip())
                }
                None => self.occluded_in_compact_meshes::<AVX2>(l, q, t_max),
            },
            TopItem::Instance { index, level } => {
                let inst = &q.g.level(q.level).instances[index as usize];
                let local = inst.ray_to_object(q.ray);
                let placement = self.placements.child(q.level, index as usize, q.placement);
                self.occluded_level(q.g, level as usize, placement, &local, t_max, q.from)
            }
            TopItem::Placed(i) => {
                let p = &l.placed[i as usize];
                let local = p.ray(q.ray);
                let placement = q.placement + p.offset;
                self.occluded_level(q.g, p.level as usize, placement, &local, t_max, q.from)
            }
        }
    }
}

/// A ray in one level's space, with what that level's items need.
struct Query<'a> {
    g: &'a Geometry,
    level: usize,
    /// The placement the level was reached at.
    placement: u64,
    ray: &'a Ray,
    /// The primitive the ray was spawned on, for nested levels.
    from: Option<PrimRef>,
}

impl<'a> Query<'a> {
    /// The primitive the ray was spawned on, if it is in this placement (asked only where a
    /// level's own shapes are tested: measured, computing it for every level entry cost 1.4% of
    /// a frame).
    #[inline(always)]
    fn skip(&self) -> Option<LocalPrim> {
        match self.from {
            Some(f) if f.placement == self.placement => Some(f.local),
            _ => None,
        }
    }

    /// The query of `ray` in `level`, reached at `placement`.
    #[inline(always)]
    fn new(
        g: &'a Geometry,
        level: usize,
        placement: u64,
        ray: &'a Ray,
        from: Option<PrimRef>,
    ) -> Query<'a> {
        Query {
            g,
            level,
            placement,
            ray,
            from,
        }
    }

    /// The query's ray in f32, prepared for a mesh BVH.
    #[inline(always)]
    fn mesh_ray(&self) -> MeshRay {
        MeshRay::new(self.ray.origin.as_vec3(), self.ray.dir.as_vec3())
    }

    /// The (mesh, triangle) the ray was spawned on, if in this placement.
    #[inline(always)]
    fn triangle_skip(&self) -> Option<(u32, u32)> {
        match self.skip() {
            Some(LocalPrim::Triangle { mesh, tri }) => Some((mesh, tri)),
            _ => None,
        }
    }
}

thread_local! {
    /// The tops' traversal stacks.
    static TOP_STACKS: Stacks<u32> = const { Stacks::new() };
}
