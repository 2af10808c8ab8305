//! Instances: a shared mesh placed in the world by an affine transform of its own.
//!
//! A prototype mesh is stored (and its BVH built) once however many instances place it. Rays are
//! mapped into the prototype's object space (the ray parameter t is unchanged by an affine map),
//! intersected there, and the hit's geometry is mapped back to world space.

use crate::material::MaterialId;
use crate::math::{Ray, Transform, gamma};
use crate::shape::SurfaceGeometry;
use glam::DVec3;

/// One placement of a prototype mesh ([`crate::Geometry::prototypes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshInstance {
    /// Index into [`crate::Geometry::prototypes`].
    pub prototype: u32,
    /// Object (prototype) space to world space.
    pub transform: Transform,
    /// A material replacing the prototype's own, if any.
    pub material: Option<MaterialId>,
}

impl MeshInstance {
    /// An instance of `prototype` placed by `transform`, keeping the prototype's material.
    pub fn new(prototype: u32, transform: Transform) -> MeshInstance {
        MeshInstance {
            prototype,
            transform,
            material: None,
        }
    }

    /// The world ray in the prototype's object space, with the same parameterisation.
    #[inline]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        let m = &self.transform.from_world;
        Ray::new(m.transform_point3(ray.origin), m.transform_vector3(ray.dir))
    }

    /// A world-space point in the prototype's object space.
    #[inline]
    pub fn point_to_object(&self, p: DVec3) -> DVec3 {
        self.transform.from_world.transform_point3(p)
    }

    /// Surface geometry computed in object space, mapped to world space: the point by the
    /// transform, normals by its inverse transpose, and the error bound grown by the map's
    /// stretch plus the rounding of the map itself.
    pub fn surface_to_world(&self, g: SurfaceGeometry) -> SurfaceGeometry {
        let m = &self.transform.to_world;
        let point = m.transform_point3(g.point);
        let abs_rows = m.matrix3.transpose().abs();
        // ‖M‖∞ bounds how far the map moves a point `error` away from the surface's image.
        let stretch = [abs_rows.x_axis, abs_rows.y_axis, abs_rows.z_axis]
            .iter()
            .map(|r| r.element_sum())
            .fold(0.0, f64::max);
        // Each world coordinate is three products and three sums: γ(4) of their magnitudes.
        let magnitudes = m.matrix3.abs() * g.point.abs() + m.translation.abs();
        let error = stretch * g.error + gamma(4) * magnitudes.max_element() * 2.0;
        let normal = |n: DVec3| {
            (self.transform.normal_to_world * n)
                .try_normalize()
                .unwrap_or(n)
        };
        SurfaceGeometry {
            point,
            geometric_normal: normal(g.geometric_normal),
            shading_normal: normal(g.shading_normal),
            error,
        }
    }
}
