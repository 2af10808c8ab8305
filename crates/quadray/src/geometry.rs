//! All primitives of a scene, with the one `match` that dispatches over [`PrimRef`].

use crate::instance::MeshInstance;
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
    /// Triangle meshes placed once, in world space.
    pub meshes: Vec<Mesh>,
    /// Meshes in their own object space, stored once and placed only by [`Geometry::instances`].
    pub prototypes: Vec<Mesh>,
    /// Placements of prototypes, each with its own transform.
    pub instances: Vec<MeshInstance>,
}

impl Geometry {
    /// Mesh placement `instance` of [`PrimRef::Triangle`]: `meshes[instance]` (placed as it is) for
    /// the first `meshes.len()`, then the prototypes placed by `instances`.
    #[inline]
    pub fn placement(&self, instance: u32) -> (&Mesh, Option<&MeshInstance>) {
        let i = instance as usize;
        match self.meshes.get(i) {
            Some(mesh) => (mesh, None),
            None => {
                let inst = &self.instances[i - self.meshes.len()];
                (&self.prototypes[inst.prototype as usize], Some(inst))
            }
        }
    }

    /// Number of mesh placements: meshes plus instances.
    pub fn placement_count(&self) -> usize {
        self.meshes.len() + self.instances.len()
    }

    /// Phase one: the nearest t in (0, `t_max`) where the ray meets `prim`.
    #[inline]
    pub fn intersect(&self, prim: PrimRef, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].intersect(ray, t_max, from_self),
            PrimRef::Quadric(i) => self.quadrics[i as usize].intersect(ray, t_max, from_self),
            PrimRef::Triangle { instance, tri } => match self.placement(instance) {
                (mesh, None) => mesh.intersect(tri, ray, t_max, from_self),
                (mesh, Some(inst)) => {
                    mesh.intersect(tri, &inst.ray_to_object(ray), t_max, from_self)
                }
            },
            PrimRef::Plane(i) => self.planes[i as usize].intersect(ray, t_max, from_self),
        }
    }

    /// Phase two: surface geometry of the hit at `t` on `prim`.
    pub fn surface(&self, prim: PrimRef, ray: &Ray, t: f64) -> SurfaceGeometry {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].surface(ray, t),
            PrimRef::Quadric(i) => self.quadrics[i as usize].surface(ray, t),
            PrimRef::Triangle { instance, tri } => match self.placement(instance) {
                (mesh, None) => mesh.surface(tri, ray, t),
                (mesh, Some(inst)) => {
                    inst.surface_to_world(mesh.surface(tri, &inst.ray_to_object(ray), t))
                }
            },
            PrimRef::Plane(i) => self.planes[i as usize].surface(ray, t),
        }
    }

    /// The material of `prim`.
    #[inline]
    pub fn material(&self, prim: PrimRef) -> MaterialId {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].material,
            PrimRef::Quadric(i) => self.quadrics[i as usize].material(),
            PrimRef::Triangle { instance, .. } => match self.placement(instance) {
                (mesh, None) => mesh.material(),
                (mesh, Some(inst)) => inst.material.unwrap_or(mesh.material()),
            },
            PrimRef::Plane(i) => self.planes[i as usize].material,
        }
    }

    /// Texture coordinates at a surface point of `prim`; only textured materials ask for them.
    pub fn texture_point(&self, prim: PrimRef, point: DVec3) -> TexturePoint {
        match prim {
            PrimRef::Sphere(i) => self.spheres[i as usize].texture_point(point),
            PrimRef::Quadric(i) => self.quadrics[i as usize].texture_point(point),
            PrimRef::Triangle { instance, .. } => match self.placement(instance) {
                (mesh, None) => mesh.texture_point(point),
                (mesh, Some(inst)) => mesh.texture_point(inst.point_to_object(point)),
            },
            PrimRef::Plane(i) => self.planes[i as usize].texture_point(point),
        }
    }

    /// Interpolated vertex attributes at `point` on `prim` (texture coordinates and colours exist
    /// only on meshes; other primitives get the defaults).
    #[inline]
    pub fn attributes(&self, prim: PrimRef, point: glam::DVec3) -> VertexAttributes {
        match prim {
            PrimRef::Triangle { instance, tri } => match self.placement(instance) {
                (mesh, None) => mesh.attributes(tri, point),
                (mesh, Some(inst)) => mesh.attributes(tri, inst.point_to_object(point)),
            },
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
        let proto = self
            .prototypes
            .iter()
            .enumerate()
            .map(|(i, m)| (format!("prototype mesh {i}"), m.material()));
        let inst = self
            .instances
            .iter()
            .enumerate()
            .filter_map(|(i, m)| Some((format!("mesh instance {i}"), m.material?)));
        s.chain(p).chain(q).chain(m).chain(proto).chain(inst)
    }
}
