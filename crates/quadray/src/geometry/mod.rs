//! All primitives of a scene, grouped in levels (the world and the prototypes it places), and the
//! dispatch over [`LocalPrim`] for each phase of intersection.

pub mod instance;

use crate::material::MaterialId;
use crate::math::Ray;
use crate::mesh::Mesh;
use crate::plane::Plane;
use crate::quadric::Quadric;
use crate::shape::{LocalPrim, PrimRef, SurfaceGeometry};
use crate::sphere::Sphere;
use crate::texture::{TexturePoint, VertexAttributes};
use glam::DVec3;
use instance::{Instance, InstancePath};

/// The scene's primitives: the world's own, by kind, and the prototypes its instances place.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Infinite planes (world level only: an unbounded shape cannot be placed by an instance).
    pub planes: Vec<Plane>,
    /// Clipped quadrics.
    pub quadrics: Vec<Quadric>,
    /// Triangle meshes placed once, in world space.
    pub meshes: Vec<Mesh>,
    /// Shapes in their own object space, stored once and placed only by instances.
    pub prototypes: Vec<Prototype>,
    /// Placements of prototypes in the world, each with its own transform.
    pub instances: Vec<Instance>,
}

/// Shapes stored once in their own object space and placed by [`Instance`]s: a mesh used by ten
/// nodes, or a whole group of shapes.
#[derive(Clone, Debug, Default)]
pub struct Prototype {
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Clipped quadrics.
    pub quadrics: Vec<Quadric>,
    /// Triangle meshes.
    pub meshes: Vec<Mesh>,
    /// Placements of earlier prototypes (lower indices in [`Geometry::prototypes`]) inside this
    /// one: the order rules out cycles.
    pub instances: Vec<Instance>,
}

impl Prototype {
    /// A prototype of one mesh.
    pub fn mesh(mesh: Mesh) -> Prototype {
        Prototype {
            meshes: vec![mesh],
            ..Prototype::default()
        }
    }
}

/// The bounded shapes of one level, in that level's own space.
#[derive(Clone, Copy, Debug)]
pub struct Level<'a> {
    /// Spheres.
    pub spheres: &'a [Sphere],
    /// Clipped quadrics.
    pub quadrics: &'a [Quadric],
    /// Triangle meshes.
    pub meshes: &'a [Mesh],
    /// Placements of prototypes.
    pub instances: &'a [Instance],
}

impl Level<'_> {
    /// Phase one: the nearest t in (0, `t_max`) where the ray meets `prim` (planes are the
    /// world's: see [`Geometry::intersect_plane`]).
    #[inline]
    pub fn intersect(
        &self,
        prim: LocalPrim,
        ray: &Ray,
        t_max: f64,
        from_self: bool,
    ) -> Option<f64> {
        self.intersect_inlined(prim, ray, t_max, from_self)
    }

    /// [`Level::intersect`] inlined into its caller: the light buffer's shadow rays (a call each
    /// cost 0.6% of a reflective frame's instructions). The eye buffer keeps the call: inlined
    /// there, the AVX2 path's mesh traversal beside it took 2.4% more instructions a ray.
    #[inline(always)]
    pub(crate) fn intersect_inlined(
        &self,
        prim: LocalPrim,
        ray: &Ray,
        t_max: f64,
        from_self: bool,
    ) -> Option<f64> {
        match prim {
            LocalPrim::Sphere(i) => self.spheres[i as usize].intersect(ray, t_max, from_self),
            LocalPrim::Quadric(i) => self.quadrics[i as usize].intersect(ray, t_max, from_self),
            LocalPrim::Triangle { mesh, tri } => {
                self.meshes[mesh as usize].intersect(tri, ray, t_max, from_self)
            }
            LocalPrim::Plane(_) => None,
        }
    }
}

impl Geometry {
    /// Level `index`: 0 is the world, `1 + i` is prototype `i`.
    #[inline]
    pub fn level(&self, index: usize) -> Level<'_> {
        match index {
            0 => Level {
                spheres: &self.spheres,
                quadrics: &self.quadrics,
                meshes: &self.meshes,
                instances: &self.instances,
            },
            _ => {
                let p = &self.prototypes[index - 1];
                Level {
                    spheres: &p.spheres,
                    quadrics: &p.quadrics,
                    meshes: &p.meshes,
                    instances: &p.instances,
                }
            }
        }
    }

    /// The level `path` ends in: the world for an empty path.
    #[inline]
    fn level_of(&self, path: &InstancePath) -> Level<'_> {
        if path.is_empty() {
            self.level(0)
        } else {
            self.level(path.level(self))
        }
    }

    /// Number of levels: the world and every prototype.
    pub fn level_count(&self) -> usize {
        1 + self.prototypes.len()
    }

    /// Phase one for world plane `i`.
    #[inline]
    pub fn intersect_plane(&self, i: u32, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        self.planes[i as usize].intersect(ray, t_max, from_self)
    }

    /// Phase two: surface geometry, in world space, of the hit at `t` on `prim`, reached through
    /// `path` (the instances leading to its placement).
    pub fn surface(
        &self,
        prim: PrimRef,
        path: &InstancePath,
        ray: &Ray,
        t: f64,
    ) -> SurfaceGeometry {
        if path.is_empty() {
            return self.level_surface(self.level(0), prim.local, ray, t);
        }
        let level = self.level(path.level(self));
        // The ray in the primitive's space: mapped level by level, exactly as traversal did.
        let mut local = *ray;
        for inst in path.instances(self) {
            local = inst.ray_to_object(&local);
        }
        let mut g = self.level_surface(level, prim.local, &local, t);
        for inst in path.instances(self).rev() {
            g = inst.surface_to_world(g);
        }
        g
    }

    /// Whether camera and reflection rays pass through `prim`, reached by `ray` through `path`:
    /// the back of a single-sided mesh's triangle. The winding is judged in the triangle's own
    /// space, so a mirroring instance keeps the same faces in front, as glTF asks (a node with a
    /// negative determinant draws its clockwise faces, which are the mesh's counter-clockwise
    /// ones seen through the mirror).
    pub fn passes_through(&self, prim: PrimRef, path: &InstancePath, ray: &Ray) -> bool {
        let LocalPrim::Triangle { mesh, tri } = prim.local else {
            return false;
        };
        let mesh = &self.level_of(path).meshes[mesh as usize];
        if !mesh.single_sided() {
            return false;
        }
        let mut local = *ray;
        for inst in path.instances(self) {
            local = inst.ray_to_object(&local);
        }
        mesh.faces_away(tri, local.dir)
    }

    /// Surface geometry of `prim` of `level`, in that level's space.
    #[inline(always)]
    fn level_surface(
        &self,
        level: Level<'_>,
        prim: LocalPrim,
        ray: &Ray,
        t: f64,
    ) -> SurfaceGeometry {
        match prim {
            LocalPrim::Sphere(i) => level.spheres[i as usize].surface(ray, t),
            LocalPrim::Quadric(i) => level.quadrics[i as usize].surface(ray, t),
            LocalPrim::Triangle { mesh, tri } => level.meshes[mesh as usize].surface(tri, ray, t),
            LocalPrim::Plane(i) => self.planes[i as usize].surface(ray, t),
        }
    }

    /// The material of `prim`: its own, unless an instance on `path` replaces it (the outermost
    /// one that does).
    #[inline(always)]
    pub fn material(&self, prim: PrimRef, path: &InstancePath) -> MaterialId {
        // Placement 0 is the world's, whose path is empty: known without reading the path (the
        // world's path is a static, read through memory at every hit).
        let level = if prim.placement == 0 || path.is_empty() {
            self.level(0)
        } else if let Some(m) = path.instances(self).find_map(|inst| inst.material) {
            return m;
        } else {
            self.level(path.level(self))
        };
        match prim.local {
            LocalPrim::Sphere(i) => level.spheres[i as usize].material,
            LocalPrim::Quadric(i) => level.quadrics[i as usize].material(),
            LocalPrim::Triangle { mesh, .. } => level.meshes[mesh as usize].material(),
            LocalPrim::Plane(i) => self.planes[i as usize].material,
        }
    }

    /// `point` (world space) in the space of the level `path` ends in.
    fn point_to_level(&self, path: &InstancePath, point: DVec3) -> DVec3 {
        path.instances(self)
            .fold(point, |p, inst| inst.point_to_object(p))
    }

    /// Texture coordinates at a world-space surface point of `prim`, computed in the primitive's
    /// own space (textures move with an instance); only textured materials ask for them.
    #[inline(always)]
    pub fn texture_point(&self, prim: PrimRef, path: &InstancePath, point: DVec3) -> TexturePoint {
        // The world's primitives (most hits) skip the empty instance walk.
        let p = if path.is_empty() {
            point
        } else {
            self.point_to_level(path, point)
        };
        let level = self.level_of(path);
        match prim.local {
            LocalPrim::Sphere(i) => level.spheres[i as usize].texture_point(p),
            LocalPrim::Quadric(i) => level.quadrics[i as usize].texture_point(p),
            LocalPrim::Triangle { mesh, .. } => level.meshes[mesh as usize].texture_point(p),
            LocalPrim::Plane(i) => self.planes[i as usize].texture_point(point),
        }
    }

    /// The larger principal curvature of `prim` at world-space `point` (inverse world units):
    /// computed in the primitive's own space, then divided by the instances' mean scales
    /// (exact for similarity transforms; 0 for planes and triangles, which are flat).
    #[inline(always)]
    pub fn curvature(&self, prim: PrimRef, path: &InstancePath, point: DVec3) -> f64 {
        let level = self.level_of(path);
        let local = || self.point_to_level(path, point);
        let curvature = match prim.local {
            LocalPrim::Sphere(i) => level.spheres[i as usize].curvature(),
            LocalPrim::Quadric(i) => level.quadrics[i as usize].curvature(local()),
            LocalPrim::Triangle { .. } | LocalPrim::Plane(_) => return 0.0,
        };
        path.instances(self).fold(curvature, |k, inst| {
            k / inst.transform.to_world.matrix3.determinant().abs().cbrt()
        })
    }

    /// How the texture coordinates of `prim` (reached through `path`) change along each of the
    /// world-space vectors `along` (every texture map is affine in the point, so this holds
    /// anywhere on it): the vectors carried through the instances' linear maps into the
    /// primitive's own space, the primitive looked up once (a plane's texture frame made once),
    /// for the two axes of a sample's footprint.
    #[inline(always)]
    pub fn texture_offsets(
        &self,
        prim: PrimRef,
        path: &InstancePath,
        along: [DVec3; 2],
    ) -> [TexturePoint; 2] {
        let level = self.level_of(path);
        let [u, v] = along.map(|v| {
            path.instances(self)
                .fold(v, |v, inst| inst.transform.from_world.transform_vector3(v))
        });
        match prim.local {
            LocalPrim::Sphere(i) => [u, v].map(|v| level.spheres[i as usize].texture_offset(v)),
            LocalPrim::Quadric(i) => [u, v].map(|v| level.quadrics[i as usize].texture_offset(v)),
            LocalPrim::Triangle { mesh, .. } => {
                [u, v].map(|v| level.meshes[mesh as usize].texture_offset(v))
            }
            LocalPrim::Plane(i) => self.planes[i as usize].texture_offsets([u, v]),
        }
    }

    /// [`Geometry::texture_point`] of `point` and [`Geometry::texture_offsets`] along `along`
    /// together: a plane's frame made once for the three.
    #[inline(always)]
    pub fn texture_point_and_offsets(
        &self,
        prim: PrimRef,
        path: &InstancePath,
        point: DVec3,
        along: [DVec3; 2],
    ) -> (TexturePoint, [TexturePoint; 2]) {
        match prim.local {
            LocalPrim::Plane(i) => self.planes[i as usize].texture_point_and_offsets(point, along),
            _ => (
                self.texture_point(prim, path, point),
                self.texture_offsets(prim, path, along),
            ),
        }
    }

    /// Interpolated vertex attributes at world-space `point` on `prim` (texture coordinates and
    /// colours exist only on meshes; other primitives get the defaults). Where `texcoords` says
    /// the caller will not read the texture coordinates (asked only on meshes), a mesh with no
    /// vertex colours skips the interpolation (the kitchen's texture coordinates cost its lit
    /// frame 4% of its instructions under a constant colour).
    #[inline(always)]
    pub fn attributes(
        &self,
        prim: PrimRef,
        path: &InstancePath,
        point: DVec3,
        texcoords: impl FnOnce() -> bool,
    ) -> VertexAttributes {
        match prim.local {
            LocalPrim::Triangle { mesh, tri } => {
                let mesh = &self.level(path.level(self)).meshes[mesh as usize];
                let wanted = if texcoords() {
                    mesh.has_attributes()
                } else {
                    mesh.has_colors()
                };
                if !wanted {
                    return VertexAttributes::default();
                }
                mesh.attributes(tri, self.point_to_level(path, point))
            }
            LocalPrim::Sphere(_) | LocalPrim::Quadric(_) | LocalPrim::Plane(_) => {
                VertexAttributes::default()
            }
        }
    }

    /// Every primitive's and instance's material index, with a description for error messages.
    pub fn materials_used(&self) -> impl Iterator<Item = (String, MaterialId)> + '_ {
        let planes = self
            .planes
            .iter()
            .enumerate()
            .map(|(i, p)| (format!("plane {i}"), p.material));
        let levels = (0..self.level_count()).flat_map(move |level| {
            let l = self.level(level);
            let name = move |what: &str, i: usize| match level {
                0 => format!("{what} {i}"),
                _ => format!("{what} {i} of prototype {}", level - 1),
            };
            let s = l
                .spheres
                .iter()
                .enumerate()
                .map(move |(i, s)| (name("sphere", i), s.material));
            let q = l
                .quadrics
                .iter()
                .enumerate()
                .map(move |(i, q)| (name("quadric", i), q.material()));
            let m = l
                .meshes
                .iter()
                .enumerate()
                .map(move |(i, m)| (name("mesh", i), m.material()));
            let inst = l
                .instances
                .iter()
                .enumerate()
                .filter_map(move |(i, inst)| Some((name("instance", i), inst.material?)));
            s.chain(q).chain(m).chain(inst)
        });
        planes.chain(levels)
    }
}
