//! The bottom level for analytic primitives (spheres and clipped quadrics): an obvhs BVH2 traversed
//! in f32 over boxes padded to stay conservative, with every primitive intersected in f64.
//!
//! Two things keep the f32 traversal conservative: each box is padded by a few f32 ulps of the
//! largest coordinate any ray origin or primitive can have (covering the rounding of the ray
//! origin to f32 and obvhs' clamped inverse direction), and the t handed back to obvhs for culling
//! is rounded up.

use super::build::{build_single_leaves, padded_aabb};
use super::stack::{Stacks, with_stack};
use super::{round_up, to_obvhs};
use crate::geometry::Level;
use crate::math::Ray;
use crate::shape::LocalPrim;
use obvhs::{aabb::Aabb, bvh2::Bvh2, ray::RayHit};

/// A BVH over the spheres and quadrics of one level.
#[derive(Clone)]
pub(crate) struct AnalyticBvh {
    bvh: Bvh2,
    /// Primitives in BVH leaf order, so a leaf's index needs no indirection.
    prims: Vec<LocalPrim>,
}

thread_local! {
    /// The analytic BVHs' traversal stacks ([`with_stack`]).
    static STACK: Stacks<u32> = const { Stacks::new() };
}

impl AnalyticBvh {
    /// Builds the BVH, or `None` when there are no analytic primitives. `extent` bounds the
    /// magnitude of every coordinate a ray may start at.
    pub(crate) fn build(level: Level<'_>, extent: f32) -> Option<AnalyticBvh> {
        let mut prims = Vec::new();
        let mut aabbs = Vec::new();
        for (i, s) in level.spheres.iter().enumerate() {
            prims.push(LocalPrim::Sphere(i as u32));
            aabbs.push(padded_aabb(s.bounds(), extent));
        }
        for (i, q) in level.quadrics.iter().enumerate() {
            prims.push(LocalPrim::Quadric(i as u32));
            aabbs.push(padded_aabb(q.bounds(), extent));
        }
        if prims.is_empty() {
            return None;
        }
        // obvhs' collapse treats every primitive as equally costly. An f64 quadric or sphere test
        // costs several triangle tests, so leaves keep one primitive (measured: 6% faster on
        // scenes/reflective.toml than leaves of up to 8).
        let bvh = build_single_leaves(&aabbs);
        let prims = (bvh.primitive_indices.iter())
            .map(|&i| prims[i as usize])
            .collect();
        Some(AnalyticBvh { bvh, prims })
    }

    /// The root's box: what the top level bounds this level by.
    pub(crate) fn bounds(&self) -> Aabb {
        *self.bvh.nodes[0].aabb()
    }

    /// Number of primitives.
    pub(crate) fn len(&self) -> usize {
        self.prims.len()
    }

    /// Bytes kept allocated: obvhs' nodes and index lists and the primitive list in leaf order.
    pub(crate) fn memory_bytes(&self) -> usize {
        let b = &self.bvh;
        b.nodes.capacity() * std::mem::size_of::<obvhs::bvh2::node::Bvh2Node>()
            + (b.primitive_indices.capacity()
                + b.primitive_indices_freelist.capacity()
                + b.primitives_to_nodes.capacity()
                + b.parents.capacity())
                * std::mem::size_of::<u32>()
            + self.prims.capacity() * std::mem::size_of::<LocalPrim>()
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
        with_stack(&STACK, |stack| {
            let mut hit = RayHit::none();
            let fray = to_obvhs(ray, *best_t);
            self.bvh
                .ray_traverse_dynamic(stack, fray, &mut hit, |node, fray, _| {
                    for id in node.first_index..node.first_index + node.prim_count {
                        let prim = self.prims[id as usize];
                        if let Some(t) = g.intersect(prim, ray, *best_t, from == Some(prim)) {
                            *best_t = t;
                            best = Some(prim);
                            fray.tmax = round_up(t);
                        }
                    }
                    true
                });
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
        let mut blocked = false;
        with_stack(&STACK, |stack| {
            let mut hit = RayHit::none();
            self.bvh
                .ray_traverse_dynamic(stack, to_obvhs(ray, t_max), &mut hit, |node, _, _| {
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
