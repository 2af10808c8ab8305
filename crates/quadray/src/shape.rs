//! The closed set of primitives and the two-phase hit records they share.
//!
//! Phase one (inside BVH traversal) returns only a ray parameter; phase two builds the full
//! [`SurfaceGeometry`] once, for the nearest hit (pbrt-v4's `BasicIntersect` / `InteractionFromIntersection`).

use crate::material::MaterialId;
use glam::DVec3;

/// One primitive of a scene: what the BVH leaves and the plane list refer to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrimRef {
    /// Index into [`crate::Geometry::spheres`].
    Sphere(u32),
    /// Index into [`crate::Geometry::quadrics`].
    Quadric(u32),
    /// Triangle `tri` of mesh placement `instance` ([`crate::Geometry::placement`]): a mesh of
    /// [`crate::Geometry::meshes`], or an instance of a prototype after them.
    Triangle {
        /// Mesh placement index.
        instance: u32,
        /// Triangle index within the mesh.
        tri: u32,
    },
    /// Index into [`crate::Geometry::planes`] (unbounded: tested outside the BVH).
    Plane(u32),
}

/// Geometry at a hit point, built once for the nearest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceGeometry {
    /// The hit point, world space.
    pub point: DVec3,
    /// Unit geometric normal, world space; its orientation is the shape's (outward where defined).
    pub geometric_normal: DVec3,
    /// Unit shading normal (interpolated for meshes), same side as `geometric_normal`.
    pub shading_normal: DVec3,
    /// Bound on the distance between `point` and the true surface: spawned rays start this far off it.
    pub error: f64,
}

/// A complete hit: which primitive, where along the ray, and its surface geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter of the hit.
    pub t: f64,
    /// The primitive hit.
    pub prim: PrimRef,
    /// Material of that primitive.
    pub material: MaterialId,
    /// Surface geometry at the hit.
    pub geometry: SurfaceGeometry,
}

/// Unit normal from an unnormalised one, or `fallback` where it vanishes (a cone apex).
#[inline]
pub(crate) fn normal_or(n: DVec3, fallback: DVec3) -> DVec3 {
    n.try_normalize().unwrap_or_else(|| fallback.normalize())
}
