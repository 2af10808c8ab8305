//! The closed set of primitives and the two-phase hit records they share.
//!
//! Phase one (inside BVH traversal) returns only a ray parameter; phase two builds the full
//! [`SurfaceGeometry`] once, for the nearest hit (pbrt-v4's `BasicIntersect` / `InteractionFromIntersection`).

use crate::material::MaterialId;
use glam::DVec3;

/// One primitive within a level of the scene (the world, or one prototype): what the BVH leaves
/// and the plane list refer to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LocalPrim {
    /// Index into the level's spheres.
    Sphere(u32),
    /// Index into the level's quadrics.
    Quadric(u32),
    /// Triangle `tri` of the level's mesh `mesh`.
    Triangle {
        /// Mesh index within the level.
        mesh: u32,
        /// Triangle index within the mesh.
        tri: u32,
    },
    /// Index into [`crate::Geometry::planes`] (world level only; unbounded, tested outside the BVH).
    Plane(u32),
}

/// One primitive of the scene as placed: a [`LocalPrim`] of the level reached by `placement`.
///
/// Placements number the scene's instance tree expanded in depth-first order: 0 is the world
/// itself, and every placement of a prototype, however deeply nested, has its own number
/// ([`crate::geometry::instance::Placements`]). Two copies of one shared triangle are two primitives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PrimRef {
    /// The placement whose level holds the primitive (0: the world).
    pub placement: u64,
    /// The primitive within that level.
    pub local: LocalPrim,
}

impl PrimRef {
    /// A primitive of the world level.
    pub const fn world(local: LocalPrim) -> PrimRef {
        PrimRef {
            placement: 0,
            local,
        }
    }
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
