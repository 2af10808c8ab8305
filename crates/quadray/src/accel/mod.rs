//! The two-level acceleration structure and the public ray-casting queries.
//!
//! - **Bottom level**: one wide BVH over all world-space meshes and one per prototype mesh
//!   ([`mesh_bvh`]: a 4-wide BVH of quadray's layout collapsed from obvhs' BVH2, with f32
//!   watertight triangle tests four at a time), and one BVH2 over all spheres and quadrics
//!   ([`analytic`]: f32 traversal over padded boxes, f64 intersection).
//! - **Top level**: the analytic level and the world meshes (both in world space) and every
//!   instance of a prototype with its affine transform (rays are mapped into the prototype's
//!   space, where t is unchanged). Up to eight items are tested box by box (measured: an obvhs BVH2
//!   over the two items of scenes/defense.toml cost several percent); more get an obvhs BVH2.
//!   Infinite planes are tested in a short list beside it.
//!
//! A triangle hit found in f32 is refined in f64 (the ray against the triangle's plane) before it
//! is compared with hits of other items. Culling uses f32 distances rounded up, so hits of
//! different items are ordered by their f64 distances except within f32 rounding of each other.
//!
//! The traversal code is compiled twice on x86-64: for the baseline (SSE2) and with AVX2 and FMA,
//! chosen at run time ([`simd_path`]) for scenes that are mostly triangles
//! ([`Accel::traversal_path`]); set
//! `QUADRAY_SIMD=baseline` to force the baseline path. Both give bit-identical results (no fused
//! operations are introduced: Rust never contracts a·b+c).

mod analytic;
mod mesh_bvh;
mod tri4;

use crate::geometry::Geometry;
use crate::math::Ray;
use crate::shape::PrimRef;
use analytic::AnalyticBvh;
use glam::{DVec3, Vec3A};
use mesh_bvh::{MeshBvh, MeshRay};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2, bvh2::builder::build_bvh2};
use std::cell::RefCell;
use std::sync::OnceLock;
use std::time::Duration;

/// One leaf item of the top level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TopItem {
    /// The BVH over spheres and quadrics.
    Analytic,
    /// The BVH over all of [`Geometry::meshes`].
    World,
    /// Mesh placement `instance` ([`Geometry::placement`]) of prototype `prototype`.
    Instance { instance: u32, prototype: u32 },
}

/// The scene's acceleration structure: bottom-level BVHs under a top level, plus planes.
#[derive(Clone)]
pub struct Accel {
    analytic: Option<AnalyticBvh>,
    /// Over all of [`Geometry::meshes`].
    world: Option<MeshBvh>,
    /// One per [`Geometry::prototypes`].
    prototypes: Vec<MeshBvh>,
    /// Top-level items in leaf order.
    items: Vec<TopItem>,
    /// The top-level BVH; `None` when there are at most [`FLAT_TOP`] items.
    top: Option<Bvh2>,
    /// The items' boxes, for a top level without a BVH.
    item_boxes: Vec<Aabb>,
    planes: u32,
    /// Triangles stored (each mesh and prototype counted once).
    triangles: usize,
    /// Whether queries take the AVX2+FMA path: where the CPU has it and the scene is mostly
    /// triangles (measured: 8% faster on the kitchen's rays; 3% slower on scenes/reflective.toml
    /// and scenes/defense.toml, whose time goes to the f64 quadric tests and shading).
    avx2: bool,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field(
                "analytic",
                &self.analytic.as_ref().map_or(0, AnalyticBvh::len),
            )
            .field("world_meshes", &self.world.is_some())
            .field("prototypes", &self.prototypes.len())
            .field("top_items", &self.items.len())
            .field("planes", &self.planes)
            .finish()
    }
}

/// Most top-level items tested box by box, without a top-level BVH.
const FLAT_TOP: usize = 8;

/// Relative padding applied to f32 boxes: 8 ulps of the magnitude involved.
const PAD_ULPS: f32 = 8.0 * f32::EPSILON;

/// An f64 box as an f32 box, padded by [`PAD_ULPS`] of its own coordinates and of `extent`.
fn padded_aabb((lo, hi): (DVec3, DVec3), extent: f32) -> Aabb {
    let (lo, hi) = (lo.as_vec3a(), hi.as_vec3a());
    let pad = Vec3A::splat(extent * PAD_ULPS);
    Aabb::new(
        lo - lo.abs() * PAD_ULPS - pad,
        hi + hi.abs() * PAD_ULPS + pad,
    )
}

/// World-space bounds of a mesh placement: the mesh's box, through the instance's transform.
fn placement_bounds(g: &Geometry, instance: u32) -> (DVec3, DVec3) {
    let (mesh, inst) = g.placement(instance);
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in mesh.positions() {
        lo = lo.min(p.as_dvec3());
        hi = hi.max(p.as_dvec3());
    }
    let Some(inst) = inst else { return (lo, hi) };
    let (mut wlo, mut whi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for corner in 0..8 {
        let pick = |bit: u32, a: f64, b: f64| if corner & bit == 0 { a } else { b };
        let c = DVec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        );
        let w = inst.transform.to_world.transform_point3(c);
        wlo = wlo.min(w);
        whi = whi.max(w);
    }
    // The transform's own rounding: a few ulps of the magnitudes it combines.
    let slack = (wlo.abs().max(whi.abs()).max_element()) * 1e-12;
    (wlo - DVec3::splat(slack), whi + DVec3::splat(slack))
}

impl Accel {
    /// Builds both levels. `origin_extent` bounds the magnitude of every coordinate a ray may start
    /// at outside the primitives' own bounds (the camera).
    pub fn build(geometry: &Geometry, origin_extent: f64) -> Accel {
        let world_count = geometry.meshes.len() as u32;
        let world_bounds = (0..world_count)
            .filter(|&i| geometry.meshes[i as usize].triangle_count() > 0)
            .map(|i| placement_bounds(geometry, i))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        let instance_boxes: Vec<(u32, (DVec3, DVec3))> = (world_count
            ..geometry.placement_count() as u32)
            .filter(|&i| geometry.placement(i).0.triangle_count() > 0)
            .map(|i| (i, placement_bounds(geometry, i)))
            .collect();
        let analytic_bounds = geometry
            .spheres
            .iter()
            .map(|s| s.bounds())
            .chain(geometry.quadrics.iter().map(|q| q.bounds()));
        let extent = analytic_bounds
            .chain(world_bounds)
            .chain(instance_boxes.iter().map(|(_, b)| *b))
            .map(|(lo, hi)| lo.abs().max(hi.abs()).max_element())
            .fold(origin_extent.abs(), f64::max) as f32;

        let analytic = AnalyticBvh::build(geometry, extent);
        let analytic_count = analytic.as_ref().map_or(0, AnalyticBvh::len);
        let world = world_bounds.map(|_| MeshBvh::build(&geometry.meshes));
        let prototypes: Vec<MeshBvh> = geometry
            .prototypes
            .iter()
            .map(|m| MeshBvh::build(std::slice::from_ref(m)))
            .collect();
        let triangles = geometry
            .meshes
            .iter()
            .chain(&geometry.prototypes)
            .map(|m| m.triangle_count())
            .sum();

        let mut items = Vec::new();
        let mut boxes = Vec::new();
        if let Some(a) = &analytic {
            items.push(TopItem::Analytic);
            boxes.push(a.bounds());
        }
        if let Some(bounds) = world_bounds {
            items.push(TopItem::World);
            boxes.push(padded_aabb(bounds, extent));
        }
        for (instance, bounds) in instance_boxes {
            let prototype = geometry.instances[(instance - world_count) as usize].prototype;
            items.push(TopItem::Instance {
                instance,
                prototype,
            });
            boxes.push(padded_aabb(bounds, extent));
        }
        let top = (items.len() > FLAT_TOP).then(|| {
            let mut build_time = Duration::ZERO;
            let params = BvhBuildParams {
                max_prims_per_leaf: 1,
                ..BvhBuildParams::medium_build()
            };
            build_bvh2(&boxes, params, &mut build_time)
        });
        if let Some(top) = &top {
            items = top
                .primitive_indices
                .iter()
                .map(|&i| items[i as usize])
                .collect();
            boxes = Vec::new();
        }
        Accel {
            analytic,
            world,
            prototypes,
            items,
            top,
            item_boxes: boxes,
            planes: geometry.planes.len() as u32,
            avx2: simd_path() == SimdPath::Avx2 && triangles > 4 * analytic_count,
            triangles,
        }
    }

    /// Bytes the acceleration structure keeps allocated: the bottom levels' nodes and index lists
    /// and the top level's (memory reports; the build's transient buffers are not counted).
    pub fn memory_bytes(&self) -> usize {
        let top = self.top.as_ref().map_or(0, |b| {
            b.nodes.capacity() * std::mem::size_of::<obvhs::bvh2::node::Bvh2Node>()
                + b.primitive_indices.capacity() * std::mem::size_of::<u32>()
        });
        self.analytic.as_ref().map_or(0, AnalyticBvh::memory_bytes)
            + self.world.as_ref().map_or(0, MeshBvh::memory_bytes)
            + self
                .prototypes
                .iter()
                .map(MeshBvh::memory_bytes)
                .sum::<usize>()
            + top
            + self.items.capacity() * std::mem::size_of::<TopItem>()
    }

    /// The compiled path this scene's queries take.
    pub fn traversal_path(&self) -> SimdPath {
        if self.avx2 {
            SimdPath::Avx2
        } else {
            SimdPath::Baseline
        }
    }

    /// Number of bounded primitives stored: spheres, quadrics and triangles (each mesh and
    /// prototype counted once, however often it is instanced).
    pub fn bounded_count(&self) -> usize {
        self.analytic.as_ref().map_or(0, AnalyticBvh::len) + self.triangles
    }

    /// The nearest hit in (0, `t_max`), skipping self-hits of the primitive `from` the ray was
    /// spawned on: phase one of intersection (the ray parameter and the primitive).
    #[inline]
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
        self.closest_impl(g, ray, t_max, from)
    }

    /// Whether anything blocks the ray in (0, `t_max`): the any-hit query for shadow rays.
    #[inline]
    pub fn occluded(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 and FMA (checked by `simd_path`).
            return unsafe { self.occluded_avx2(g, ray, t_max, from) };
        }
        self.occluded_impl(g, ray, t_max, from)
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
        self.closest_impl(g, ray, t_max, from)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn occluded_avx2(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        self.occluded_impl(g, ray, t_max, from)
    }

    #[inline(always)]
    fn closest_impl(
        &self,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> Option<(f64, PrimRef)> {
        let mut best_t = t_max;
        let mut best = None;
        match &self.top {
            None if self.items.len() == 1 => {
                // One item tests its own root box.
                self.closest_in(self.items[0], g, ray, from, &mut best_t, &mut best);
            }
            None => {
                // A few items: their boxes in order of entry, no BVH and no stack.
                let fray = to_obvhs(ray, best_t);
                let mut order = [(0usize, 0f32); FLAT_TOP];
                let mut n = 0;
                for (i, b) in self.item_boxes.iter().enumerate() {
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
                    if (enter as f64) <= best_t {
                        self.closest_in(self.items[i], g, ray, from, &mut best_t, &mut best);
                    }
                }
            }
            Some(top) => with_stack(&TOP_STACK, |stack| {
                let fray = to_obvhs(ray, best_t);
                let mut leaves = TopLeaves::new(top, &fray, stack);
                while let Some(range) = leaves.next(round_up(best_t)) {
                    for id in range {
                        self.closest_in(self.items[id], g, ray, from, &mut best_t, &mut best);
                    }
                }
            }),
        }
        for i in 0..self.planes {
            let prim = PrimRef::Plane(i);
            if let Some(t) = g.intersect(prim, ray, best_t, from == Some(prim)) {
                best_t = t;
                best = Some(prim);
            }
        }
        best.map(|p| (best_t, p))
    }

    /// Lowers `best_t` to the nearest hit of the ray with top-level `item`, recording its primitive.
    #[inline(always)]
    fn closest_in(
        &self,
        item: TopItem,
        g: &Geometry,
        ray: &Ray,
        from: Option<PrimRef>,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) {
        match item {
            TopItem::Analytic => {
                if let Some(a) = &self.analytic
                    && let Some(prim) = a.closest(g, ray, best_t, from)
                {
                    *best = Some(prim);
                }
            }
            TopItem::World => {
                let Some(world) = &self.world else { return };
                let mray = MeshRay::new(ray.origin.as_vec3(), ray.dir.as_vec3());
                let skip = world_skip(from, g.meshes.len());
                let found = world.closest(&g.meshes, &mray, round_up(*best_t), skip);
                if let Some(((m, tri), hit)) = found {
                    let t = g.meshes[m as usize].refine_t(tri, ray, hit.t as f64);
                    if t < *best_t {
                        *best_t = t;
                        *best = Some(PrimRef::Triangle { instance: m, tri });
                    }
                }
            }
            TopItem::Instance {
                instance,
                prototype,
            } => {
                let q = self.instance_query(g, instance, prototype, ray, from);
                let found = q
                    .bvh
                    .closest(q.mesh, &q.mesh_ray, round_up(*best_t), q.skip);
                if let Some(((_, tri), hit)) = found {
                    let t = q.mesh[0].refine_t(tri, &q.local, hit.t as f64);
                    if t < *best_t {
                        *best_t = t;
                        *best = Some(PrimRef::Triangle { instance, tri });
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn occluded_impl(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        for i in 0..self.planes {
            let prim = PrimRef::Plane(i);
            if g.intersect(prim, ray, t_max, from == Some(prim)).is_some() {
                return true;
            }
        }
        match &self.top {
            None if self.items.len() == 1 => self.occluded_in(self.items[0], g, ray, t_max, from),
            None => {
                let fray = to_obvhs(ray, t_max);
                self.items.iter().zip(&self.item_boxes).any(|(&item, b)| {
                    b.intersect_ray(&fray) < fray.tmax
                        && self.occluded_in(item, g, ray, t_max, from)
                })
            }
            Some(top) => {
                let mut blocked = false;
                with_stack(&TOP_STACK, |stack| {
                    let fray = to_obvhs(ray, t_max);
                    let mut leaves = TopLeaves::new(top, &fray, stack);
                    'search: while let Some(range) = leaves.next(fray.tmax) {
                        for id in range {
                            if self.occluded_in(self.items[id], g, ray, t_max, from) {
                                blocked = true;
                                break 'search;
                            }
                        }
                    }
                });
                blocked
            }
        }
    }

    /// The ray mapped into instance `instance` of prototype `prototype`, with what its BVH needs.
    #[inline(always)]
    fn instance_query<'a>(
        &'a self,
        g: &'a Geometry,
        instance: u32,
        prototype: u32,
        ray: &Ray,
        from: Option<PrimRef>,
    ) -> InstanceQuery<'a> {
        let local = g.instances[instance as usize - g.meshes.len()].ray_to_object(ray);
        InstanceQuery {
            bvh: &self.prototypes[prototype as usize],
            mesh: std::slice::from_ref(&g.prototypes[prototype as usize]),
            mesh_ray: MeshRay::new(local.origin.as_vec3(), local.dir.as_vec3()),
            local,
            skip: instance_skip(from, instance),
        }
    }

    /// Whether top-level `item` blocks the ray in (0, `t_max`).
    #[inline(always)]
    fn occluded_in(
        &self,
        item: TopItem,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        match item {
            TopItem::Analytic => self
                .analytic
                .as_ref()
                .is_some_and(|a| a.occluded(g, ray, t_max, from)),
            TopItem::World => self.world.as_ref().is_some_and(|world| {
                let mray = MeshRay::new(ray.origin.as_vec3(), ray.dir.as_vec3());
                let skip = world_skip(from, g.meshes.len());
                world.occluded(&g.meshes, &mray, round_up(t_max), skip)
            }),
            TopItem::Instance {
                instance,
                prototype,
            } => {
                let q = self.instance_query(g, instance, prototype, ray, from);
                q.bvh.occluded(q.mesh, &q.mesh_ray, round_up(t_max), q.skip)
            }
        }
    }
}

/// Front-to-back iteration over the leaves of the top-level BVH2 that a ray enters, written out
/// (rather than obvhs' closure-taking traversal) so the whole query inlines into one function and
/// the AVX2 path covers it.
struct TopLeaves<'a> {
    bvh: &'a Bvh2,
    ray: &'a obvhs::ray::Ray,
    stack: &'a mut Vec<u32>,
}

impl<'a> TopLeaves<'a> {
    #[inline(always)]
    fn new(bvh: &'a Bvh2, ray: &'a obvhs::ray::Ray, stack: &'a mut Vec<u32>) -> TopLeaves<'a> {
        stack.clear();
        if !bvh.nodes.is_empty() {
            stack.push(0);
        }
        TopLeaves { bvh, ray, stack }
    }

    /// The item range of the next leaf whose box the ray enters before `t_max`.
    #[inline(always)]
    fn next(&mut self, t_max: f32) -> Option<std::ops::Range<usize>> {
        while let Some(index) = self.stack.pop() {
            let node = &self.bvh.nodes[index as usize];
            if node.aabb().intersect_ray(self.ray) >= t_max {
                continue;
            }
            if node.is_leaf() {
                let first = node.first_index as usize;
                return Some(first..first + node.prim_count as usize);
            }
            // Children are stored as a pair at first_index; visit the nearer one first.
            let (a, b) = (node.first_index, node.first_index + 1);
            let ta = self.bvh.nodes[a as usize].aabb().intersect_ray(self.ray);
            let tb = self.bvh.nodes[b as usize].aabb().intersect_ray(self.ray);
            if ta <= tb {
                self.stack.push(b);
                self.stack.push(a);
            } else {
                self.stack.push(a);
                self.stack.push(b);
            }
        }
        None
    }
}

/// A ray in an instance's object space, ready for its prototype's BVH.
struct InstanceQuery<'a> {
    bvh: &'a MeshBvh,
    /// The prototype, as the one mesh its BVH was built over.
    mesh: &'a [crate::mesh::Mesh],
    /// The ray in object space (f64, for the refinement of t).
    local: Ray,
    mesh_ray: MeshRay,
    /// The prototype triangle the ray was spawned on, if on this instance.
    skip: Option<(u32, u32)>,
}

/// The world-mesh triangle a ray was spawned on, if `from` is one (placements below `world_count`).
#[inline(always)]
fn world_skip(from: Option<PrimRef>, world_count: usize) -> Option<(u32, u32)> {
    match from {
        Some(PrimRef::Triangle { instance, tri }) if (instance as usize) < world_count => {
            Some((instance, tri))
        }
        _ => None,
    }
}

/// The triangle of placement `instance` a ray was spawned on, if `from` is one.
#[inline(always)]
fn instance_skip(from: Option<PrimRef>, instance: u32) -> Option<(u32, u32)> {
    match from {
        Some(PrimRef::Triangle { instance: i, tri }) if i == instance => Some((0, tri)),
        _ => None,
    }
}

/// Which compiled traversal path runs on this machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdPath {
    /// The target's baseline instruction set (SSE2 on x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 with AVX2 and FMA, detected at run time.
    Avx2,
}

impl std::fmt::Display for SimdPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SimdPath::Baseline if cfg!(target_arch = "aarch64") => "NEON",
            SimdPath::Baseline if cfg!(target_arch = "x86_64") => "SSE2",
            SimdPath::Baseline => "scalar",
            SimdPath::Avx2 => "AVX2+FMA",
        })
    }
}

/// The traversal path chosen for this process: AVX2+FMA where the CPU has them, unless the
/// environment variable `QUADRAY_SIMD=baseline` asks for the baseline.
pub fn simd_path() -> SimdPath {
    static PATH: OnceLock<SimdPath> = OnceLock::new();
    *PATH.get_or_init(|| {
        if std::env::var("QUADRAY_SIMD").is_ok_and(|v| v == "baseline") {
            return SimdPath::Baseline;
        }
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            return SimdPath::Avx2;
        }
        SimdPath::Baseline
    })
}

thread_local! {
    /// The top level's traversal stack, reused: obvhs' own stacks are zeroed on every traversal,
    /// which showed up as 5% of all instructions in profiles.
    static TOP_STACK: RefCell<Vec<u32>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's empty stack from `key` (a fresh one if it is already in use, so a
/// nested query can never fail).
#[inline]
pub(crate) fn with_stack<T, R>(
    key: &'static std::thread::LocalKey<RefCell<Vec<T>>>,
    f: impl FnOnce(&mut Vec<T>) -> R,
) -> R {
    key.with(|cell| match cell.try_borrow_mut() {
        Ok(mut stack) => {
            stack.clear();
            f(&mut stack)
        }
        Err(_) => f(&mut Vec::new()),
    })
}

/// The f32 ray obvhs traverses with. Built field by field: obvhs' constructor debug-asserts a
/// finite origin, while a ray beyond f32's range (an origin at 10³⁹) must simply meet nothing.
#[inline]
fn to_obvhs(ray: &Ray, t_max: f64) -> obvhs::ray::Ray {
    let direction = ray.dir.as_vec3a();
    obvhs::ray::Ray {
        origin: ray.origin.as_vec3a(),
        direction,
        inv_direction: Vec3A::new(
            obvhs::ray::safe_inverse(direction.x),
            obvhs::ray::safe_inverse(direction.y),
            obvhs::ray::safe_inverse(direction.z),
        ),
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
