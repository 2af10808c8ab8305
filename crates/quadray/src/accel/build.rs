//! Building the levels: bottom-level BVHs, each level's top over them and its instances, and the
//! conservative f32 boxes the tops test.

use super::analytic::AnalyticBvh;
use super::mesh_bvh::MeshBvh;
use super::{Accel, FLAT_TOP, LevelAccel, SimdPath, TopItem, simd_path};
use crate::geometry::Geometry;
use crate::instance::{Instance, Placements};
use glam::{DVec3, Vec3A};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::builder::build_bvh2};
use std::time::Duration;

/// Most boxes a level offers its instances' bounds ([`LevelAccel::covering`]).
const MAX_COVERING: usize = 16;

/// An obvhs box as an f64 box.
fn f64_box(b: &Aabb) -> Bounds {
    (b.min.as_dvec3(), b.max.as_dvec3())
}

/// Relative padding applied to f32 boxes: 8 ulps of the magnitude involved.
const PAD_ULPS: f32 = 8.0 * f32::EPSILON;

/// An f64 box as an f32 box, padded by [`PAD_ULPS`] of its own coordinates and of `extent`.
pub(super) fn padded_aabb((lo, hi): (DVec3, DVec3), extent: f32) -> Aabb {
    let (lo, hi) = (lo.as_vec3a(), hi.as_vec3a());
    let pad = Vec3A::splat(extent * PAD_ULPS);
    Aabb::new(
        lo - lo.abs() * PAD_ULPS - pad,
        hi + hi.abs() * PAD_ULPS + pad,
    )
}

/// An f64 box.
pub(super) type Bounds = (DVec3, DVec3);

fn union(a: Option<Bounds>, b: Bounds) -> Option<Bounds> {
    Some(match a {
        None => b,
        Some((lo, hi)) => (lo.min(b.0), hi.max(b.1)),
    })
}

/// The box of `b`'s eight corners through an instance's transform, widened by the transform's own
/// rounding (a few ulps of the magnitudes it combines).
fn transformed_bounds((lo, hi): Bounds, inst: &Instance) -> Bounds {
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
    let slack = (wlo.abs().max(whi.abs()).max_element()) * 1e-12;
    (wlo - DVec3::splat(slack), whi + DVec3::splat(slack))
}

/// Largest coordinate magnitude of a box.
fn magnitude((lo, hi): Bounds) -> f64 {
    lo.abs().max(hi.abs()).max_element()
}

/// Bounds of every level in its own space (children before parents; an instance's as the box of
/// its prototype's box placed); `None` for a level with nothing bounded.
fn level_bounds(g: &Geometry) -> Vec<Option<Bounds>> {
    let n = g.level_count();
    let mut bounds: Vec<Option<Bounds>> = vec![None; n];
    for level in (1..n).chain([0]) {
        let l = g.level(level);
        let mut b = None;
        for s in l.spheres {
            b = union(b, s.bounds());
        }
        for q in l.quadrics {
            b = union(b, q.bounds());
        }
        for m in l.meshes.iter().filter(|m| m.triangle_count() > 0) {
            b = union(b, mesh_bounds(m));
        }
        for inst in l.instances {
            if let Some(&Some(c)) = bounds.get(inst.prototype as usize + 1) {
                b = union(b, transformed_bounds(c, inst));
            }
        }
        bounds[level] = b;
    }
    bounds
}

/// Bounds of a mesh's vertices.
fn mesh_bounds(m: &crate::mesh::Mesh) -> Bounds {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in m.positions() {
        lo = lo.min(p.as_dvec3());
        hi = hi.max(p.as_dvec3());
    }
    (lo, hi)
}

/// Per level, a bound on the magnitude of every coordinate a ray in that level's space may start
/// at: the world's is `world`; a prototype's is its own bounds' or what its placements map the
/// parent's bound to, whichever is larger (parents are numbered after their children).
fn level_extents(g: &Geometry, bounds: &[Option<Bounds>], world: f64) -> Vec<f64> {
    let n = g.level_count();
    let mut extents: Vec<f64> = bounds.iter().map(|b| b.map_or(0.0, magnitude)).collect();
    extents[0] = extents[0].max(world);
    for level in [0].into_iter().chain((1..n).rev()) {
        for inst in g.level(level).instances {
            let m = &inst.transform.from_world;
            // ‖x‖∞ ≤ e maps to ‖Mx + t‖∞ ≤ ‖M‖∞·e + ‖t‖∞ (‖M‖∞: the largest absolute row sum).
            let rows = m.matrix3.transpose().abs();
            let norm = [rows.x_axis, rows.y_axis, rows.z_axis]
                .iter()
                .map(|r| r.element_sum())
                .fold(0.0, f64::max);
            let e = (norm * extents[level] + m.translation.abs().max_element()) * (1.0 + 1e-12);
            if let Some(child) = extents.get_mut(inst.prototype as usize + 1) {
                *child = child.max(e);
            }
        }
    }
    extents
}

/// The largest coordinate magnitude of any shape, in its level's own space or placed by an
/// instance in its parent's, and of the camera (`origin_extent`); infinite when one is not finite.
pub fn coordinate_extent(geometry: &Geometry, origin_extent: f64) -> f64 {
    level_bounds(geometry)
        .iter()
        .flatten()
        .map(|&b| match b.0.is_finite() && b.1.is_finite() {
            true => magnitude(b),
            false => f64::INFINITY,
        })
        .fold(origin_extent.abs(), f64::max)
}

impl Accel {
    /// Builds every level. `origin_extent` bounds the magnitude of every coordinate a ray may
    /// start at outside the primitives' own bounds (the camera). The instances must be numbered
    /// ([`Placements::new`] succeeds); otherwise the scene is built without them.
    pub fn build(geometry: &Geometry, origin_extent: f64) -> Accel {
        let numbered = Placements::new(geometry);
        let valid = numbered.is_ok();
        let placements = numbered.unwrap_or_default();
        let bounds = level_bounds(geometry);
        let world = bounds[0].map_or(0.0, magnitude).max(origin_extent.abs());
        let extents = level_extents(geometry, &bounds, world);
        let n = geometry.level_count();
        let mut levels: Vec<Option<LevelAccel>> = vec![None; n];
        // Children first (prototypes place only earlier ones), the world last: an instance's box
        // is made of its prototype's covering boxes, placed.
        for level in (1..n).chain([0]) {
            // A ray origin beyond f32's range meets nothing anyway: the padding stays finite.
            let extent = extents[level].min(crate::scene::MAX_COORDINATE) as f32;
            let built = build_level(geometry, level, extent, valid, &levels);
            levels[level] = Some(built);
        }
        let levels: Vec<LevelAccel> = levels
            .into_iter()
            .map(|l| l.expect("every level is built"))
            .collect();
        let triangles: usize = (0..n)
            .flat_map(|l| geometry.level(l).meshes)
            .map(|m| m.triangle_count())
            .sum();
        let analytic_count: usize = levels
            .iter()
            .map(|l| l.analytic.as_ref().map_or(0, AnalyticBvh::len))
            .sum();
        Accel {
            levels,
            placements,
            planes: geometry.planes.len() as u32,
            avx2: simd_path() == SimdPath::Avx2 && triangles > 4 * analytic_count,
            triangles,
        }
    }
}

/// One level's bottom-level BVHs and its top; its instances (when `with_instances`) are boxed by
/// their prototypes' covering boxes, from `built` (every child level is built before).
fn build_level(
    geometry: &Geometry,
    level: usize,
    extent: f32,
    with_instances: bool,
    built: &[Option<LevelAccel>],
) -> LevelAccel {
    let l = geometry.level(level);
    let analytic = AnalyticBvh::build(l, extent);
    let has_triangles = l.meshes.iter().any(|m| m.triangle_count() > 0);
    let meshes = has_triangles.then(|| MeshBvh::build(l.meshes));
    let mut items = Vec::new();
    let mut item_boxes = Vec::new();
    let mut covering = Vec::new();
    if let Some(a) = &analytic {
        items.push(TopItem::Analytic);
        item_boxes.push(a.bounds());
        covering.push(f64_box(&a.bounds()));
    }
    if let Some(bvh) = &meshes {
        let b = l
            .meshes
            .iter()
            .filter(|m| m.triangle_count() > 0)
            .fold(None, |b, m| union(b, mesh_bounds(m)));
        items.push(TopItem::Meshes);
        item_boxes.push(padded_aabb(b.expect("meshes have triangles"), extent));
        covering.extend(bvh.covering_boxes());
    }
    for (k, inst) in l.instances.iter().enumerate().filter(|_| with_instances) {
        let child = built[inst.prototype as usize + 1]
            .as_ref()
            .expect("children are built first");
        let Some(b) = child
            .covering
            .iter()
            .map(|&c| transformed_bounds(c, inst))
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
        else {
            continue;
        };
        items.push(TopItem::Instance {
            index: k as u32,
            level: inst.prototype + 1,
        });
        item_boxes.push(padded_aabb(b, extent));
        covering.push(b);
    }
    if covering.len() > MAX_COVERING {
        // Many instances: the parent gets one box of them all.
        let all = covering
            .iter()
            .copied()
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
        covering = all.into_iter().collect();
    }
    let top = (items.len() > FLAT_TOP).then(|| {
        let mut build_time = Duration::ZERO;
        let params = BvhBuildParams {
            max_prims_per_leaf: 1,
            ..BvhBuildParams::medium_build()
        };
        build_bvh2(&item_boxes, params, &mut build_time)
    });
    if let Some(top) = &top {
        items = top
            .primitive_indices
            .iter()
            .map(|&i| items[i as usize])
            .collect();
        item_boxes = Vec::new();
    }
    LevelAccel {
        analytic,
        meshes,
        items,
        top,
        item_boxes,
        covering,
    }
}
