//! All primitives of a scene, with the one `match` that dispatches over [`PrimRef`].

use crate::material::MaterialId;
use crate::math::Ray;
use crate::mesh::Mesh;
use crate::plane::Plane;
use crate::quadric::Quadric;
use crate::shape::{PrimRef, SurfaceGeometry};
use crate::sphere::Sphere;
use crate::texture::{TexturePoint, VertexAttributes};
use glam::DVec3;

/// The scene's primitives, grouped by kind.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Infinite planes.
    pub planes: Vec<Plane>,
    /// Clipped quadrics.
    pub quadrics: Vec<Quadric>,
    /// Triangle meshes.
    pub meshes: Vec<Mesh>,
}

impl Geometry {
    /// Phase one: the nearest t in (0, `t_max`) where the ray meets `prim`.
    #[inline]
    pub fn intersect(&self, prim: PrimRef, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].intersect(ray, t_max, from_self),
            PrimRef::Quadric(i) => self.quadrics[i as usize].intersect(ray, t_max, from_self),
            PrimRef::Triangle { mesh, tri } => {
                self.meshes[mesh as usize].intersect(tri, ray, t_max, from_self)
            }
            PrimRef::Plane(i) => self.planes[i as usize].intersect(ray, t_max, from_self),
        }
    }

    /// Phase two: surface geometry of the hit at `t` on `prim`.
    pub fn surface(&self, prim: PrimRef, ray: &Ray, t: f64) -> SurfaceGeometry {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].surface(ray, t),
            PrimRef::Quadric(i) => self.quadrics[i as usize].surface(ray, t),
            PrimRef::Triangle { mesh, tri } => self.meshes[mesh as usize].surface(tri, ray, t),
            PrimRef::Plane(i) => self.planes[i as usize].surface(ray, t),
        }
    }

    /// The material of `prim`.
    #[inline]
    pub fn material(&self, prim: PrimRef) -> MaterialId {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].material,
            PrimRef::Quadric(i) => self.quadrics[i as usize].material(),
            PrimRef::Triangle { mesh, .. } => self.meshes[mesh as usize].material(),
            PrimRef::Plane(i) => self.planes[i as usize].material,
        }
    }

    /// Texture coordinates at a surface point of `prim`; only textured materials ask for them.
    pub fn texture_point(&self, prim: PrimRef, point: DVec3) -> TexturePoint {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].texture_point(point),
            PrimRef::Quadric(i) => self.quadrics[i as usize].texture_point(point),
            PrimRef::Triangle { mesh, .. } => self.meshes[mesh as usize].texture_point(point),
            PrimRef::Plane(i) => self.planes[i as usize].texture_point(point),
        }
    }

    /// Interpolated vertex attributes at `point` on `prim` (texture coordinates and colours exist
    /// only on meshes; other primitives get the defaults).
    #[inline]
    pub fn attributes(&self, prim: PrimRef, point: glam::DVec3) -> VertexAttributes {
        match prim {
            PrimRef::Triangle { mesh, tri } => self.meshes[mesh as usize].attributes(tri, point),
            PrimRef::Sphere(_) | PrimRef::Quadric(_) | PrimRef::Plane(_) => {
                VertexAttributes::default()
            }
        }
    }

    /// Every primitive's material index, with a description of the primitive for error messages.
    pub fn materials_used(&self) -> impl Iterator<Item = (String, MaterialId)> + '_ {
        let s = self
            .spheres
            .iter()
            .enumerate()
            .map(|(i, s)| (format!("sphere {i}"), s.material));
        let p = self
            .planes
            .iter()
            .enumerate()
            .map(|(i, p)| (format!("plane {i}"), p.material));
        let q = self
            .quadrics
            .iter()
            .enumerate()
            .map(|(i, q)| (format!("quadric {i}"), q.material()));
        let m = self
            .meshes
            .iter()
            .enumerate()
            .map(|(i, m)| (format!("mesh {i}"), m.material()));
        s.chain(p).chain(q).chain(m)
    }
}
