//! The multi-level acceleration structure and the public ray-casting queries.
//!
//! The scene is a set of levels: the world, and prototypes placed by instances (in the world or in
//! other prototypes, so instance graphs nest). Each level is built once, in its own space:
//! - **Bottom level**: one wide BVH over the level's meshes (`mesh_bvh`: an 8-wide BVH of
//!   quadray's layout collapsed from obvhs' BVH2, with f32 watertight triangle tests four at a
//!   time), and one 4-wide BVH of the same node layout over its spheres and quadrics
//!   (`analytic`: f32 traversal over padded boxes, spheres four at a time and quadrics one by
//!   one in f64).
//! - **Top**: those two and the level's instances, each an affine transform and the level it
//!   places (rays are mapped into the placed level's space, where t is unchanged, and that level
//!   is traversed the same way). Up to eight items are tested box by box (measured: an obvhs BVH2
//!   over the two items of scenes/defense.toml cost several percent); more get an obvhs BVH2. The
//!   world's infinite planes are tested in a short list beside it.
//! - **Direction buffers** (`buffers`): in a world of few shapes, shadow rays towards a point
//!   light and rays from a pinhole camera's eye test only the shapes listed for their direction
//!   from that point.
//!
//! A hit names its placement ([`crate::geometry::instance::Placements`]): the instance path from the world,
//! numbered, so a shared triangle placed twice is two primitives and a ray spawned on one copy
//! still meets the other.
//!
//! The queries answer one ray ([`Accel::closest`], [`Accel::occluded`]) or a batch of rays
//! spawned on nothing ([`Accel::closest_each`]: camera rays, one call and one set-up a batch),
//! each ray's answer the same either way.
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
mod buffers;
mod build;
mod corner_cone;
mod huge_pages;
mod level;
mod mesh_bvh;
mod overlap;
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
pub use crate::simd::{SimdPath, simd_path};
use analytic::AnalyticBvh;
pub use buffers::{EyeBuffer, LightBuffer};
use build::Bounds;
pub use build::Layout;
use glam::DVec3;
use mesh_bvh::MeshBvh;
use obvhs::{aabb::Aabb, bvh2::Bvh2};
pub use overlap::MAX_OVERLAP;
pub use stats::AccelStats;

/// Choices in how a scene's acceleration structure is built ([`crate::Scene::build`]); the
/// defaults suit most scenes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildOptions {
    /// Mesh BVH leaves hold their triangles' numbers instead of copies of their vertices, which
    /// each test then reads from the meshes: the same hits and images with about 40 bytes a
    /// triangle less held while rendering, traced more slowly (docs/performance.md, *Compact mesh
    /// BVHs*). The build's own peak is the same.
    pub compact_meshes: bool,
}

/// One leaf item of a level's top.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TopItem {
    /// The level's BVH over its spheres and quadrics.
    Analytic,
    /// The level's BVH over its meshes (in [`LevelAccel::meshes`] or, compact,
    /// [`LevelAccel::compact_meshes`]).
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
    /// The BVH over the level's meshes, with copies of their vertices in its leaves.
    meshes: Option<MeshBvh>,
    /// Or that BVH in its compact form ([`crate::BuildOptions::compact_meshes`]). A field of its
    /// own, asked for where `meshes` is `None`: a branch for it in the traversal of `meshes`
    /// cost that traversal 0.5–1.5% more instructions, and so did an item of its own.
    compact_meshes: Option<MeshBvh>,
    /// Top items in leaf order.
    items: Vec<TopItem>,
    /// The top's BVH; `None` when there are at most [`FLAT_TOP`] items.
    top: Option<Bvh2>,
    /// The items' boxes, for a top without a BVH.
    item_boxes: Vec<Aabb>,
    /// A few boxes (at most `MAX_COVERING`, in the level's space) whose union holds all its
    /// content, tighter than one box: an instance's box is theirs, placed (a rotated bunny's
    /// box of its box overlapped its neighbours' and cost 2x in traversal).
    covering: Vec<Bounds>,
    /// Hoisted instances of instances ([`TopItem::Placed`]).
    placed: Vec<Placed>,
}

/// The scene's acceleration structure: one `LevelAccel` per level, plus the world's planes.
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
    /// Bound on the world's coordinates, ray origins included (the world level's box padding).
    world_extent: f32,
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

    /// [`Accel::closest`] in (0, ∞) for each ray of `rays` spawned on nothing, into `hits` (one
    /// each), in one call: a batch of camera rays pays the call, its compiled path's choice and
    /// its set-up once, not once a ray.
    pub fn closest_each(&self, g: &Geometry, rays: &[Ray], hits: &mut [Option<(f64, PrimRef)>]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 and FMA (checked by `simd_path`).
            return unsafe { self.closest_each_avx2(g, rays, hits) };
        }
        self.closest_each_impl::<false>(g, rays, hits)
    }

    /// [`Accel::closest_each`] compiled for AVX2, the traversal inlined into the loop.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn closest_each_avx2(&self, g: &Geometry, rays: &[Ray], hits: &mut [Option<(f64, PrimRef)>]) {
        self.closest_each_impl::<true>(g, rays, hits)
    }

    /// [`Accel::closest_each`]'s loop: a world of one mesh BVH with its dispatch decided once,
    /// else ray by ray through the world level.
    #[inline(always)]
    fn closest_each_impl<const AVX2: bool>(
        &self,
        g: &Geometry,
        rays: &[Ray],
        hits: &mut [Option<(f64, PrimRef)>],
    ) {
        if self.closest_each_in_world_meshes::<AVX2>(g, rays, hits) {
            return;
        }
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.closest_impl::<AVX2>(g, ray, f64::INFINITY, None);
        }
    }

    /// The world level inlined (nested levels are entered through [`Accel::closest_level`]),
    /// then the planes.
    #[inline(always)]
    pub(super) fn closest_impl<const AVX2: bool>(
        &self,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> Option<(f64, PrimRef)> {
        let mut best_t = t_max;
        let mut best = None;
        self.closest_level_impl::<AVX2>(g, 0, 0, ray, from, &mut best_t, &mut best);
        self.closest_plane(g, ray, from, &mut best_t, &mut best);
        best.map(|p| (best_t, p))
    }

    /// Lowers `best_t` to the nearest hit of `ray` with the world's planes, skipping `from`
    /// (the planes come after the shapes in every closest-hit query).
    #[inline(always)]
    fn closest_plane(
        &self,
        g: &Geometry,
        ray: &Ray,
        from: Option<PrimRef>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        for i in 0..self.planes {
            let prim = PrimRef::world(LocalPrim::Plane(i));
            if let Some(t) = g.intersect_plane(i, ray, *best_t, from == Some(prim)) {
                *best_t = t;
                *best = Some(prim);
            }
        }
    }

    /// Whether one of the world's planes other than `from` blocks `ray` in (0, `t_max`) (tested
    /// first in every any-hit query).
    #[inline(always)]
    fn plane_blocks(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        for i in 0..self.planes {
            let prim = PrimRef::world(LocalPrim::Plane(i));
            if g.intersect_plane(i, ray, t_max, from == Some(prim))
                .is_some()
            {
                return true;
            }
        }
        false
    }

    /// Whether anything blocks the ray in (0, `t_max`): the any-hit query for shadow rays.
    #[inline(always)]
    pub fn occluded(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        if self.plane_blocks(g, ray, t_max, from) {
            return true;
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
