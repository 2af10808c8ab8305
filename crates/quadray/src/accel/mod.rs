//! The multi-level acceleration structure and the public ray-casting queries.
//!
//! The scene is a set of levels: the world, and prototypes placed by instances (in the world or in
//! other prototypes, so instance graphs nest). Each level is built once, in its own space:
//! - **Bottom level**: one wide BVH over the level's meshes ([`mesh_bvh`]: an 8-wide BVH of
//!   quadray's layout collapsed from obvhs' BVH2, with f32 watertight triangle tests four at a
//!   time), and one 4-wide BVH of the same node layout over its spheres and quadrics
//!   ([`analytic`]: f32 traversal over padded boxes, spheres four at a time and quadrics one by
//!   one in f64).
//! - **Top**: those two and the level's instances, each an affine transform and the level it
//!   places (rays are mapped into the placed level's space, where t is unchanged, and that level
//!   is traversed the same way). Up to eight items are tested box by box (measured: an obvhs BVH2
//!   over the two items of scenes/defense.toml cost several percent); more get an obvhs BVH2. The
//!   world's infinite planes are tested in a short list beside it.
//!
//! A hit names its placement ([`crate::geometry::instance::Placements`]): the instance path from the world,
//! numbered, so a shared triangle placed twice is two primitives and a ray spawned on one copy
//! still meets the other.
//!
//! A triangle hit found in f32 is refined in f64 (the ray against the triangle's plane) before it
//! is compared with hits of other items. Culling uses f32 distances rounded up, so hits of
//! different items are ordered by their f64 distances except within f32 rounding of each other.
//!
//! The traversal code is compiled twice on x86-64: for the baseline (SSE2) and with AVX2 and FMA,
//! chosen at run time ([`simd_path`]) for scenes that are mostly triangles
//! ([`Accel::traversal_path`]); set
//! `QUADRAY_SIMD=baseline` to force the baseline path. Both give bit-identical results (no fused
//! operations are introduced: Rust never contracts a·b+c). The AVX2 copy is the functions marked
//! `#[target_feature]` here with everything they inline; the const parameter `AVX2` tells the
//! inlined code which copy it is in (the mesh nodes' 8-lane test uses AVX registers there). Code
//! in a closure or a function that is not inlined is compiled for the baseline even when called
//! from the AVX2 copy, so the mesh traversal keeps out of closures.

mod analytic;
mod build;
mod mesh_bvh;
mod simd;
mod sphere4;
mod sphere_clusters;
mod stack;
mod stats;
mod top;
mod tri4;
mod wide;

use crate::geometry::Geometry;
use crate::geometry::instance::Placements;
use crate::math::Ray;
use crate::shape::{LocalPrim, PrimRef};
use crate::triangle::plane_t;
use analytic::AnalyticBvh;
use build::Bounds;
pub use build::Layout;
use glam::DVec3;
use mesh_bvh::{MeshBvh, MeshRay};
use obvhs::{aabb::Aabb, bvh2::Bvh2};
pub use simd::{SimdPath, simd_path};
use stack::{Stacks, put_stack, take_stack, with_stack};
pub use stats::AccelStats;
use top::TopLeaves;

/// One leaf item of a level's top.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TopItem {
    /// The level's BVH over its spheres and quadrics.
    Analytic,
    /// The level's BVH over its meshes.
    Meshes,
    /// Instance `index` of the level, placing level `level` (`1 +` its prototype).
    Instance { index: u32, level: u32 },
    /// An instance of an instance, hoisted into this top: [`LevelAccel::placed`]`[i]`.
    Placed(u32),
}

/// An instance of an instance placed directly by a level's top (a level that only places others
/// is skipped: one ray transform instead of two).
#[derive(Clone, Copy, Debug)]
struct Placed {
    /// This level's space to the placed level's: the two inverses composed.
    from_parent: glam::DAffine3,
    /// Its placement's offset from this level's placement (the two offsets summed).
    offset: u64,
    /// The placed level.
    level: u32,
}

/// The structures of one level (the world, or one prototype in its own space): bottom-level BVHs
/// over its shapes, and a top over those and its instances.
#[derive(Clone, Default)]
struct LevelAccel {
    analytic: Option<AnalyticBvh>,
    meshes: Option<MeshBvh>,
    /// Top items in leaf order.
    items: Vec<TopItem>,
    /// The top's BVH; `None` when there are at most [`FLAT_TOP`] items.
    top: Option<Bvh2>,
    /// The items' boxes, for a top without a BVH.
    item_boxes: Vec<Aabb>,
    /// A few boxes (at most [`MAX_COVERING`], in the level's space) whose union holds all its
    /// content, tighter than one box: an instance's box is theirs, placed (a rotated bunny's
    /// box of its box overlapped its neighbours' and cost 2x in traversal).
    covering: Vec<Bounds>,
    /// Hoisted instances of instances ([`TopItem::Placed`]).
    placed: Vec<Placed>,
}

/// The scene's acceleration structure: one [`LevelAccel`] per level, plus the world's planes.
#[derive(Clone)]
pub struct Accel {
    /// Per level: 0 is the world, `1 + i` prototype `i`.
    levels: Vec<LevelAccel>,
    placements: Placements,
    planes: u32,
    /// Triangles stored (each level's counted once).
    triangles: usize,
    /// Whether queries take the AVX2+FMA path: where the CPU has it and the scene is mostly
    /// triangles, whose 8-wide nodes it tests in one AVX pass (measured, 1280×720: the kitchen's
    /// frame and rays 8-20% faster; the quadric grid 6% slower, and scenes/defense.toml, 20
    /// triangles among six quadrics and spheres, 6-7% slower in the latest runs, medians of 5-7).
    avx2: bool,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("levels", &self.levels.len())
            .field("placements", &self.placements.count())
            .field("triangles", &self.triangles)
            .field("planes", &self.planes)
            .finish()
    }
}

impl Placed {
    /// The parent level's ray in the placed level's space.
    #[inline]
    fn ray(&self, ray: &Ray) -> Ray {
        let m = &self.from_parent;
        Ray::new(m.transform_point3(ray.origin), m.transform_vector3(ray.dir))
    }
}

/// Most top-level items tested box by box, without a top-level BVH.
const FLAT_TOP: usize = 8;

impl Accel {
    /// The compiled path this scene's queries take.
    pub fn traversal_path(&self) -> SimdPath {
        if self.avx2 {
            SimdPath::Avx2
        } else {
            SimdPath::Baseline
        }
    }

    /// Number of bounded primitives stored: spheres, quadrics and triangles (each level counted
    /// once, however often it is instanced).
    pub fn bounded_count(&self) -> usize {
        self.levels
            .iter()
            .map(|l| l.analytic.as_ref().map_or(0, AnalyticBvh::len))
            .sum::<usize>()
            + self.triangles
    }

    /// The numbering of the scene's placements.
    pub fn placements(&self) -> &Placements {
        &self.placements
    }

    /// The nearest hit in (0, `t_max`), skipping self-hits of the primitive `from` the ray was
    /// spawned on: phase one of intersection (the ray parameter and the primitive).
    // Always inlined: with the 8-wide mesh traversal beside it, `#[inline]` left it out of line
    // in `Scene::intersect_from` (3% more instructions on scenes/reflective.toml).
    #[inline(always)]
    pub fn closest(
        &self,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> Option<(f64, PrimRef)> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 and FMA (checked by `simd_path`).
            return unsafe { self.closest_avx2(g, ray, t_max, from) };
        }
        self.closest_impl::<false>(g, ray, t_max, from)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn closest_avx2(
        &self,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> Option<(f64, PrimRef)> {
        self.closest_impl::<true>(g, ray, t_max, from)
    }

    /// The world level inlined (nested levels are entered through [`Accel::closest_level`]),
    /// then the planes.
    #[inline(always)]
    fn closest_impl<const AVX2: bool>(
        &self,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> Option<(f64, PrimRef)> {
        let mut best_t = t_max;
        let mut best = None;
        self.closest_level_impl::<AVX2>(g, 0, 0, ray, from, &mut best_t, &mut best);
        for i in 0..self.planes {
            let prim = PrimRef::world(LocalPrim::Plane(i));
            if let Some(t) = g.intersect_plane(i, ray, best_t, from == Some(prim)) {
                best_t = t;
                best = Some(prim);
            }
        }
        best.map(|p| (best_t, p))
    }

    /// Whether anything blocks the ray in (0, `t_max`): the any-hit query for shadow rays.
    #[inline(always)]
    pub fn occluded(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        for i in 0..self.planes {
            let prim = PrimRef::world(LocalPrim::Plane(i));
            if g.intersect_plane(i, ray, t_max, from == Some(prim))
                .is_some()
            {
                return true;
            }
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 and FMA (checked by `simd_path`).
            return unsafe { self.occluded_level_avx2(g, 0, 0, ray, t_max, from) };
        }
        self.occluded_level_impl::<false>(g, 0, 0, ray, t_max, from)
    }

    /// [`Accel::closest`] within `level` reached at `placement`, with the ray in its space: the
    /// entry point of each level, choosing the compiled path.
    #[allow(clippy::too_many_arguments)]
    fn closest_level(
        &self,
        g: &Geometry,
        level: usize,
        placement: u64,
        ray: &Ray,
        from: Option<PrimRef>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 and FMA (checked by `simd_path`).
            return unsafe {
                self.closest_level_avx2(g, level, placement, ray, from, best_t, best)
            };
        }
        self.closest_level_impl::<false>(g, level, placement, ray, from, best_t, best)
    }

    /// [`Accel::occluded`] within `level` reached at `placement`.
    fn occluded_level(
        &self,
        g: &Geometry,
        level: usize,
        placement: u64,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 and FMA (checked by `simd_path`).
            return unsafe { self.occluded_level_avx2(g, level, placement, ray, t_max, from) };
        }
        self.occluded_level_impl::<false>(g, level, placement, ray, t_max, from)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    fn closest_level_avx2(
        &self,
        g: &Geometry,
        level: usize,
        placement: u64,
        ray: &Ray,
        from: Option<PrimRef>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        self.closest_level_impl::<true>(g, level, placement, ray, from, best_t, best)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn occluded_level_avx2(
        &self,
        g: &Geometry,
        level: usize,
        placement: u64,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        self.occluded_level_impl::<true>(g, level, placement, ray, t_max, from)
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn closest_level_impl<const AVX2: bool>(
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
                    && let Some(local) = a.closest(q.g.level(q.level), q.ray, best_t, q.skip())
                {
                    *best = Some(PrimRef {
                        placement: q.placement,
                        local,
                    });
                }
            }
            TopItem::Meshes => {
                let Some(bvh) = &l.meshes else { return };
                let meshes = q.g.level(q.level).meshes;
                let mray = MeshRay::new(q.ray.origin.as_vec3(), q.ray.dir.as_vec3());
                if let Some(h) =
                    bvh.closest::<AVX2>(meshes, &mray, round_up(*best_t), q.triangle_skip())
                {
                    // Mesh::refine_t, on the block's copy of the vertices.
                    let t = plane_t(q.ray.origin, q.ray.dir, bvh.vertices(&h), h.hit.t as f64);
                    let (mesh, tri) = h.id;
                    if t < *best_t {
                        *best_t = t;
                        *best = Some(PrimRef {
                            placement: q.placement,
                            local: LocalPrim::Triangle { mesh, tri },
                        });
                    }
                }
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

    #[inline(always)]
    fn occluded_level_impl<const AVX2: bool>(
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
                    let mray = MeshRay::new(q.ray.origin.as_vec3(), q.ray.dir.as_vec3());
                    let meshes = q.g.level(q.level).meshes;
                    bvh.occluded::<AVX2>(meshes, &mray, round_up(t_max), q.triangle_skip())
                }
                None => false,
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

/// The f32 ray obvhs traverses with. Built field by field: obvhs' constructor debug-asserts a
/// finite origin, while a ray beyond f32's range (an origin at 10³⁹) must simply meet nothing.
/// The reciprocal is the wide nodes' ([`wide::safe_recip`]), clamped only where it would be
/// infinite; obvhs' own `safe_inverse` clamps components below f32::EPSILON to ±1/EPSILON, which
/// can make a ray of a strongly scaled-up instance leave a box it runs along before entering it.
#[inline]
fn to_obvhs(ray: &Ray, t_max: f64) -> obvhs::ray::Ray {
    let direction = ray.dir.as_vec3a();
    let inv_direction = wide::safe_recip(direction);
    obvhs::ray::Ray {
        origin: ray.origin.as_vec3a(),
        direction,
        inv_direction,
        tmin: 0.0,
        tmax: round_up(t_max),
    }
}

/// `t` as f32, never below its f64 value: culling with it never drops a nearer primitive.
#[inline]
fn round_up(t: f64) -> f32 {
    let f = t as f32;
    if (f as f64) < t { f.next_up() } else { f }
}

/// Largest coordinate magnitude among a set of points, for [`Accel::build`]'s `origin_extent`.
pub fn max_abs_coordinate(points: &[DVec3]) -> f64 {
    points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f64::max)
}
