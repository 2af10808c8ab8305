//! The acceleration structure: one obvhs BVH2 over every bounded primitive, planes in a short list.
//!
//! obvhs traverses in f32 while quadray intersects in f64. Two things keep the f32 traversal
//! conservative: each box is padded by a few f32 ulps of the largest coordinate any ray origin or
//! primitive can have (covering the rounding of the ray origin to f32 and obvhs' clamped inverse
//! direction), and the t handed back to obvhs for culling is rounded up. BVH2 is used rather than
//! CWBVH because obvhs' CWBVH node test clamps entry distances to 1e-4 world units, which would
//! break scale invariance.

use crate::geometry::Geometry;
use crate::math::Ray;
use crate::shape::PrimRef;
use glam::{DVec3, Vec3A};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2, bvh2::builder::build_bvh2, ray::RayHit};
use std::time::Duration;

/// A BVH over the bounded primitives of a [`Geometry`], plus its unbounded planes.
#[derive(Clone)]
pub struct Accel {
    bvh: Option<Bvh2>,
    /// Primitives in BVH leaf order, so a leaf's index needs no indirection.
    prims: Vec<PrimRef>,
    planes: u32,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("prims", &self.prims.len())
            .field("planes", &self.planes)
            .finish()
    }
}

/// Relative padding applied to f32 boxes: 8 ulps of the magnitude involved.
const PAD_ULPS: f32 = 8.0 * f32::EPSILON;

impl Accel {
    /// Builds the BVH. `origin_extent` bounds the magnitude of every coordinate a ray may start at
    /// outside the primitives' own bounds (the camera).
    pub fn build(geometry: &Geometry, origin_extent: f64) -> Accel {
        let mut prims = Vec::new();
        let mut bounds = Vec::new();
        for (i, s) in geometry.spheres.iter().enumerate() {
            prims.push(PrimRef::Sphere(i as u32));
            bounds.push(s.bounds());
        }
        for (i, q) in geometry.quadrics.iter().enumerate() {
            prims.push(PrimRef::Quadric(i as u32));
            bounds.push(q.bounds());
        }
        for (m, mesh) in geometry.meshes.iter().enumerate() {
            for t in 0..mesh.triangle_count() as u32 {
                prims.push(PrimRef::Triangle {
                    mesh: m as u32,
                    tri: t,
                });
                bounds.push(mesh.triangle_bounds(t));
            }
        }
        let planes = geometry.planes.len() as u32;
        if prims.is_empty() {
            return Accel {
                bvh: None,
                prims,
                planes,
            };
        }
        let extent = bounds
            .iter()
            .map(|(lo, hi)| lo.abs().max(hi.abs()).max_element())
            .fold(origin_extent.abs(), f64::max) as f32;
        let pad = Vec3A::splat(extent * PAD_ULPS);
        let aabbs: Vec<Aabb> = bounds
            .iter()
            .map(|(lo, hi)| {
                let (lo, hi) = (lo.as_vec3a(), hi.as_vec3a());
                Aabb::new(
                    lo - lo.abs() * PAD_ULPS - pad,
                    hi + hi.abs() * PAD_ULPS + pad,
                )
            })
            .collect();
        let mut build_time = Duration::ZERO;
        // obvhs' collapse treats every primitive as equally costly. An f64 quadric or sphere test
        // costs several triangle tests, so analytic-dominated scenes keep one primitive per leaf
        // (measured: 6% faster on scenes/reflective.toml than leaves of up to 8), while
        // triangle-dominated scenes keep obvhs' default leaves.
        let triangles = prims
            .iter()
            .filter(|p| matches!(p, PrimRef::Triangle { .. }))
            .count();
        let analytic = prims.len() - triangles;
        let leaf = if triangles > 4 * analytic {
            BvhBuildParams::medium_build().max_prims_per_leaf
        } else {
            1
        };
        let params = BvhBuildParams {
            max_prims_per_leaf: leaf,
            ..BvhBuildParams::medium_build()
        };
        let bvh = build_bvh2(&aabbs, params, &mut build_time);
        let prims = bvh
            .primitive_indices
            .iter()
            .map(|&i| prims[i as usize])
            .collect();
        Accel {
            bvh: Some(bvh),
            prims,
            planes,
        }
    }

    /// Bytes the acceleration structure keeps allocated: obvhs' nodes and index lists, and the
    /// primitive list in leaf order (memory reports; the build's transient buffers are not counted).
    pub fn memory_bytes(&self) -> usize {
        let bvh = self.bvh.as_ref().map_or(0, |b| {
            b.nodes.capacity() * std::mem::size_of::<obvhs::bvh2::node::Bvh2Node>()
                + (b.primitive_indices.capacity()
                    + b.primitive_indices_freelist.capacity()
                    + b.primitives_to_nodes.capacity()
                    + b.parents.capacity())
                    * std::mem::size_of::<u32>()
        });
        bvh + self.prims.capacity() * std::mem::size_of::<PrimRef>()
    }

    /// Number of primitives in the BVH (triangles counted one by one).
    pub fn bounded_count(&self) -> usize {
        self.prims.len()
    }

    /// The nearest hit in (0, `t_max`), skipping self-hits of the primitive `from` the ray was spawned on.
    #[inline]
    pub fn closest(
        &self,
        g: &Geometry,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> Option<(f64, PrimRef)> {
        let mut best_t = t_max;
        let mut best = None;
        if let Some(bvh) = &self.bvh {
            with_stack(|stack| {
                let mut hit = RayHit::none();
                bvh.ray_traverse_dynamic(stack, to_obvhs(ray, t_max), &mut hit, |node, fray, _| {
                    for id in node.first_index..node.first_index + node.prim_count {
                        let prim = self.prims[id as usize];
                        if let Some(t) = g.intersect(prim, ray, best_t, from == Some(prim)) {
                            best_t = t;
                            best = Some(prim);
                            fray.tmax = round_up(t);
                        }
                    }
                    true
                });
            });
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

    /// Whether anything blocks the ray in (0, `t_max`): the any-hit query for shadow rays.
    #[inline]
    pub fn occluded(&self, g: &Geometry, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        for i in 0..self.planes {
            let prim = PrimRef::Plane(i);
            if g.intersect(prim, ray, t_max, from == Some(prim)).is_some() {
                return true;
            }
        }
        let Some(bvh) = &self.bvh else { return false };
        let mut blocked = false;
        with_stack(|stack| {
            let mut hit = RayHit::none();
            bvh.ray_traverse_dynamic(stack, to_obvhs(ray, t_max), &mut hit, |node, _, _| {
                for id in node.first_index..node.first_index + node.prim_count {
                    let prim = self.prims[id as usize];
                    if g.intersect(prim, ray, t_max, from == Some(prim)).is_some() {
                        blocked = true;
                        return false;
                    }
                }
                true
            });
        });
        blocked
    }
}

thread_local! {
    /// One traversal stack per thread, reused: obvhs' own stacks are zeroed on every traversal,
    /// which showed up as 5% of all instructions in profiles.
    static STACK: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's empty traversal stack (a fresh one if it is already in use).
#[inline]
fn with_stack(f: impl FnOnce(&mut Vec<u32>)) {
    STACK.with(|cell| match cell.try_borrow_mut() {
        Ok(mut stack) => {
            stack.clear();
            f(&mut stack)
        }
        Err(_) => f(&mut Vec::new()),
    })
}

/// The f32 ray obvhs traverses with.
#[inline]
fn to_obvhs(ray: &Ray, t_max: f64) -> obvhs::ray::Ray {
    obvhs::ray::Ray::new(
        ray.origin.as_vec3a(),
        ray.dir.as_vec3a(),
        0.0,
        round_up(t_max),
    )
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
