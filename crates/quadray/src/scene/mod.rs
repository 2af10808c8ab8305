//! A validated, immutable scene: camera, materials, lights, geometry and its BVH.

use crate::accel::{Accel, BuildOptions, EyeBuffer, LightBuffer};
use crate::camera::{Camera, CameraError, Projection};
use crate::footprint::HitFootprint;
use crate::geometry::Geometry;
use crate::geometry::instance::{InstancePath, PlacementError};
use crate::light::Light;
use crate::material::Material;
use crate::math::{Ray, offset_origin};
use crate::mesh::Mesh;
use crate::shape::{PrimRef, SurfaceGeometry, SurfaceHit};
use crate::texture::{Texture, TextureExtent, TexturePoint};
use glam::Vec3;
use validate::{checked_layout, validate_description};

pub use crate::math::MAX_COORDINATE;

mod seen;
mod transmittance;
mod validate;

pub use seen::Seen;

/// Everything a scene holds, before validation.
#[derive(Clone, Debug)]
pub struct SceneDescription {
    /// The camera.
    pub camera: Camera,
    /// Radiance of camera rays that hit nothing (linear RGB).
    pub background: Vec3,
    /// Radiance of reflection rays that hit nothing, when it differs from the background: the
    /// surroundings a mirror or a metal shows (a studio's grey, say) behind a darker backdrop.
    pub environment: Option<Vec3>,
    /// Materials, referred to by index.
    pub materials: Vec<Material>,
    /// Light sources; without any, no shadow rays are traced.
    pub lights: Vec<Light>,
    /// The primitives.
    pub geometry: Geometry,
}

/// Why a scene description is not a valid scene.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// A primitive refers to a material that does not exist.
    #[error("{what} uses material {id}, but the scene has {count} materials")]
    MaterialOutOfRange {
        /// Which primitive.
        what: String,
        /// The index used.
        id: u32,
        /// Number of materials.
        count: usize,
    },
    /// A value is NaN, infinite or out of its range.
    #[error("{what}: {problem}")]
    Invalid {
        /// Which item.
        what: String,
        /// What is wrong with it.
        problem: String,
    },
    /// The camera cannot produce rays. (Its message holds the camera's: no `#[from]`, which
    /// would also make it the source, and error chains would print it twice.)
    #[error("camera: {0}")]
    Camera(CameraError),
    /// The instances cannot be placed: a cycle or an unknown prototype, too deep, too many.
    #[error(transparent)]
    Instances(#[from] PlacementError),
}

impl From<CameraError> for SceneError {
    fn from(e: CameraError) -> SceneError {
        SceneError::Camera(e)
    }
}

/// A scene ready to render.
#[derive(Clone, Debug)]
///
/// Its parts are read-only: the BVH and the validation both depend on them, so a scene is changed
/// by changing its description ([`Scene::into_description`]) and building it again.
pub struct Scene {
    camera: Camera,
    background: Vec3,
    environment: Vec3,
    materials: Vec<Material>,
    lights: Vec<Light>,
    geometry: Geometry,
    accel: Accel,
    /// Per light, its light buffer where the scene has one ([`Accel::light_buffer`]).
    light_buffers: Vec<Option<LightBuffer>>,
    /// The pinhole camera's eye buffer, where the scene has one ([`Accel::eye_buffer`]).
    eye_buffer: Option<EyeBuffer>,
    /// Whether any mesh is single-sided: only then do closest hits check for back faces.
    single_sided: bool,
    /// Whether any material has a texture that is filtered over ray cones: only then do rays
    /// carry cones.
    filters_textures: bool,
    /// Whether any material lets light through ([`Scene::transmittance`]).
    transmits: bool,
    /// Per material, its radiance when shading it needs no surface record ([`Scene::seen_from`]);
    /// empty when no material's does.
    constant_radiance: Vec<Option<Vec3>>,
}

/// Which colour [`Scene::colour_at`] looks up.
enum HitColour<'a> {
    /// A material's base colour: its texture times the vertex colour.
    Base(&'a Material),
    /// A texture alone.
    Texture(&'a Texture),
}

impl HitColour<'_> {
    /// The texture the colour is read from.
    fn texture(&self) -> &Texture {
        match self {
            HitColour::Base(material) => &material.texture,
            HitColour::Texture(texture) => texture,
        }
    }
}

/// Back faces of single-sided meshes one closest-hit query passes through at most; a ray that
/// meets more stops at the next one (none of the Khronos samples comes near).
const MAX_PASSED_FACES: u32 = 64;

/// The rest of the shadow ray `ray` (to `t_max`) past the surface `g` it met: a leg starting just
/// beyond it, with the leg's own `t_max`, ending where `ray`'s did. For the queries that walk
/// through surfaces (culled back faces, glass).
fn leg_beyond(ray: &Ray, t_max: f64, g: &SurfaceGeometry) -> (Ray, f64) {
    let origin = offset_origin(g.point, g.geometric_normal, g.error, ray.dir);
    let leg_t_max = t_max - (origin - ray.origin).dot(ray.dir) / ray.dir.length_squared();
    (Ray::new(origin, ray.dir), leg_t_max)
}

/// A [`SceneError::Invalid`] naming the item and the problem.
fn invalid(what: impl Into<String>, problem: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        what: what.into(),
        problem: problem.into(),
    }
}

impl Scene {
    /// Validates a description and builds its BVH.
    pub fn new(d: SceneDescription) -> Result<Scene, SceneError> {
        Scene::build(d, BuildOptions::default())
    }

    /// [`Scene::new`], the BVH built as `options` ask.
    pub fn build(mut d: SceneDescription, options: BuildOptions) -> Result<Scene, SceneError> {
        let placements = validate_description(&mut d)?;
        let (layout, origin_extent) = checked_layout(&d, placements)?;
        let accel = Accel::build_with(&d.geometry, layout, origin_extent, options);
        let single_sided = (0..d.geometry.level_count())
            .any(|l| d.geometry.level(l).meshes.iter().any(Mesh::single_sided));
        let filters_textures = d.materials.iter().any(|m| {
            m.texture.is_filtered() || m.emission.as_ref().is_some_and(Texture::is_filtered)
        });
        let transmits = d.materials.iter().any(|m| m.transmission.is_some());
        let vertex_colors = (0..d.geometry.level_count())
            .any(|l| d.geometry.level(l).meshes.iter().any(Mesh::has_colors));
        let constant_radiance =
            seen::constant_radiances(&d.materials, !d.lights.is_empty(), vertex_colors);
        // Shadow rays through glass take the transmittance query, and single-sided meshes their
        // own: neither asks the buffers.
        let light_buffers = (d.lights.iter())
            .map(|l| {
                let position = l.position().filter(|_| !transmits && !single_sided)?;
                accel.light_buffer(&d.geometry, position)
            })
            .collect();
        let eye_buffer = match d.camera.projection {
            Projection::Perspective { .. } => accel.eye_buffer(&d.geometry, d.camera.from),
            Projection::Orthographic { .. } => None,
        };
        Ok(Scene {
            camera: d.camera,
            background: d.background,
            environment: d.environment.unwrap_or(d.background),
            materials: d.materials,
            lights: d.lights,
            geometry: d.geometry,
            accel,
            light_buffers,
            eye_buffer,
            single_sided,
            filters_textures,
            transmits,
            constant_radiance,
        })
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Radiance of camera rays that hit nothing.
    pub fn background(&self) -> Vec3 {
        self.background
    }

    /// Radiance of reflection rays that hit nothing (the background unless the scene sets an
    /// environment).
    pub fn environment(&self) -> Vec3 {
        self.environment
    }

    /// Materials, by index.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Light sources.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The primitives.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The description this scene was built from, to change it and build a new scene.
    pub fn into_description(self) -> SceneDescription {
        SceneDescription {
            camera: self.camera,
            background: self.background,
            environment: (self.environment != self.background).then_some(self.environment),
            materials: self.materials,
            lights: self.lights,
            geometry: self.geometry,
        }
    }

    /// Whether any material's texture is filtered over the samples' footprints (a checker or
    /// contour bands): only then do rays carry [`crate::footprint::RayCone`]s.
    pub fn filters_textures(&self) -> bool {
        self.filters_textures
    }

    /// The base colour (albedo) at a hit: its material's texture, averaged over `footprint`,
    /// times the hit's vertex colour.
    #[inline(always)]
    pub fn albedo(&self, hit: &SurfaceHit, footprint: &HitFootprint) -> Vec3 {
        self.colour_at(
            hit,
            footprint,
            HitColour::Base(&self.materials[hit.material as usize]),
        )
    }

    /// The radiance the hit's surface gives off itself (zero for most materials).
    #[inline(never)]
    pub fn emitted(&self, hit: &SurfaceHit, footprint: &HitFootprint) -> Vec3 {
        match &self.materials[hit.material as usize].emission {
            None => Vec3::ZERO,
            Some(Texture::Constant(c)) => *c,
            Some(texture) => self.colour_at(hit, footprint, HitColour::Texture(texture)),
        }
    }

    /// The larger principal curvature of `hit`'s surface at its point (inverse world units; 0 for
    /// planes and triangles), which widens the cones of mirror reflections.
    pub fn curvature(&self, hit: &SurfaceHit) -> f64 {
        self.with_path(hit.prim, |path| {
            self.geometry.curvature(hit.prim, path, hit.geometry.point)
        })
    }

    /// A colour at a hit: the vertex attributes are interpolated at once (defaults off meshes),
    /// the texture point only for the procedural textures that read it, and the footprint's
    /// extent in texture space only for those filtered over it.
    #[inline(always)]
    fn colour_at(&self, hit: &SurfaceHit, footprint: &HitFootprint, colour: HitColour<'_>) -> Vec3 {
        let point = hit.geometry.point;
        // Not through a closure (Scene::with_path): there the lookup was not inlined, +0.9%
        // instructions on defense.
        let mut slot = None;
        let path = self.path_in(hit.prim.placement, &mut slot);
        let texcoords = || colour.texture().reads_texcoords();
        let attributes = self.geometry.attributes(hit.prim, path, point, texcoords);
        let texture_point = |filtered: bool| {
            if filtered && !footprint.is_point() {
                self.filtered_texture_point(hit, path, footprint)
            } else {
                let centre = self.geometry.texture_point(hit.prim, path, point);
                (centre, TextureExtent::POINT)
            }
        };
        match colour {
            HitColour::Base(material) => material.base_color(texture_point, &attributes),
            HitColour::Texture(texture) => texture.eval_at(texture_point, &attributes),
        }
    }

    /// The texture point of `hit` and the extent in texture space of `footprint` around it: the
    /// texture maps are affine, so the footprint's axes carried into texture space span it. Out
    /// of line: only filtered textures ask for it.
    #[inline(never)]
    fn filtered_texture_point(
        &self,
        hit: &SurfaceHit,
        path: &InstancePath,
        footprint: &HitFootprint,
    ) -> (TexturePoint, TextureExtent) {
        let g = &hit.geometry;
        let (ax, ay) = footprint.axes(g.geometric_normal);
        let (centre, [along_x, along_y]) =
            (self.geometry).texture_point_and_offsets(hit.prim, path, g.point, [ax, ay]);
        (centre, TextureExtent::spanned(&along_x, &along_y))
    }

    /// The instances leading to `placement`: the world's own path (most of a scene's hits, which
    /// need nothing decoded), else the path decoded into `slot`. The one place paths are decoded.
    #[inline(always)]
    fn path_in<'s>(
        &'s self,
        placement: u64,
        slot: &'s mut Option<InstancePath>,
    ) -> &'s InstancePath {
        match placement {
            0 => &crate::geometry::instance::WORLD_PATH,
            p => slot.insert(self.accel.placements().path(&self.geometry, p)),
        }
    }

    /// `f` of the instances leading to `prim`'s placement ([`Scene::path_in`]).
    #[inline(always)]
    fn with_path<R>(&self, prim: PrimRef, f: impl FnOnce(&InstancePath) -> R) -> R {
        let mut slot = None;
        f(self.path_in(prim.placement, &mut slot))
    }

    /// The instances leading from the world to `prim`'s placement.
    #[inline]
    pub fn path(&self, prim: PrimRef) -> InstancePath {
        let mut slot = None;
        *self.path_in(prim.placement, &mut slot)
    }

    /// The acceleration structure.
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// The nearest hit of `ray` in (0, ∞) with its full surface record: the ray-casting query,
    /// usable without the renderer (phase one in the BVHs, phase two once, for the hit found).
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.intersect_from(ray, None)
    }

    /// [`Scene::intersect`] for a ray spawned on primitive `from`, whose self-hits are skipped.
    /// The ray passes through the back faces of single-sided meshes ([`Mesh::with_single_sided`]):
    /// the hit is the first surface it sees, with `t` along `ray`.
    #[inline]
    pub fn intersect_from(&self, ray: &Ray, from: Option<PrimRef>) -> Option<SurfaceHit> {
        // The common case inlines the first-hit query once and returns it as it is: wrapping it
        // again, or inlining it a second time here, cost 1.5–3.5% on the bundled scenes.
        if self.single_sided {
            return self.intersect_culling(ray, from);
        }
        self.first_hit(ray, from)
    }

    /// [`Scene::intersect_from`] in a scene with single-sided meshes.
    #[inline(never)]
    fn intersect_culling(&self, ray: &Ray, from: Option<PrimRef>) -> Option<SurfaceHit> {
        let hit = self.first_hit(ray, from)?;
        self.past_back_faces(ray, hit)
    }

    /// The nearest surface `ray` meets, whichever side.
    #[inline(always)]
    fn first_hit(&self, ray: &Ray, from: Option<PrimRef>) -> Option<SurfaceHit> {
        let (t, prim) = self.closest(ray, from)?;
        let mut slot = None;
        let path = self.path_in(prim.placement, &mut slot);
        let material = self.geometry.material(prim, path);
        Some(self.surface_hit(ray, (t, prim), path, material))
    }

    /// Whether every camera ray whose direction lies in the cone of the four `corners` (rays
    /// from one eye) meets nothing: the rays leave every plane behind
    /// ([`Plane::missed_by_cone`](crate::plane::Plane::missed_by_cone), asked first: a view of a
    /// floor fails there), and meet no shape, as the eye buffer tells where the scene has one
    /// for that eye, else the boxes covering the world's content ([`Accel::cone_sees_nothing`]).
    /// `false` when it cannot tell.
    pub(crate) fn camera_rays_meet_nothing(&self, corners: &[Ray; 4]) -> bool {
        let (eye, dirs) = (corners[0].origin, corners.map(|r| r.dir));
        (self.geometry.planes.iter()).all(|p| p.missed_by_cone(eye, &dirs))
            && match &self.eye_buffer {
                Some(buffer) if buffer.eye() == eye => self.accel.eye_sees_nothing(buffer, corners),
                _ => self.accel.cone_sees_nothing(corners),
            }
    }

    /// [`Scene::closest`] for each of `rays`, spawned on nothing, into `hits`, one each (rays
    /// from the camera's eye through the eye buffer where the scene asks it).
    #[inline]
    pub(crate) fn closest_each(&self, rays: &[Ray], hits: &mut [Option<(f64, PrimRef)>]) {
        if self.accel.eye_answers_rays()
            && let Some(eye) = &self.eye_buffer
        {
            return (self.accel).closest_each_from_eye(&self.geometry, eye, rays, hits);
        }
        (self.accel).closest_each(&self.geometry, rays, hits)
    }

    /// The surface `ray` sees at its nearest hit `(t, prim)` on `material`, placed by `path`: that
    /// hit's full record, or past single-sided back faces the first front face behind it.
    #[inline(always)]
    pub(crate) fn hit_seen(
        &self,
        ray: &Ray,
        (t, prim): (f64, PrimRef),
        path: &InstancePath,
        material: crate::material::MaterialId,
    ) -> Option<SurfaceHit> {
        let hit = self.surface_hit(ray, (t, prim), path, material);
        if self.single_sided {
            self.past_back_faces(ray, hit)
        } else {
            Some(hit)
        }
    }

    /// Phase one: the nearest hit's distance and primitive, through the eye buffer for rays from
    /// the camera's eye.
    #[inline(always)]
    fn closest(&self, ray: &Ray, from: Option<PrimRef>) -> Option<(f64, PrimRef)> {
        if self.accel.eye_answers_rays()
            && from.is_none()
            && let Some(eye) = &self.eye_buffer
        {
            return (self.accel).closest_from_eye(&self.geometry, eye, ray);
        }
        (self.accel).closest(&self.geometry, ray, f64::INFINITY, from)
    }

    /// The full record of the hit `(t, prim)` of `ray` on `material`, `prim` placed by `path`
    /// (phase two).
    #[inline(always)]
    fn surface_hit(
        &self,
        ray: &Ray,
        (t, prim): (f64, PrimRef),
        path: &InstancePath,
        material: crate::material::MaterialId,
    ) -> SurfaceHit {
        SurfaceHit {
            t,
            prim,
            material,
            geometry: self.geometry.surface(prim, path, ray, t),
        }
    }

    /// `hit`, or while it is the back of a single-sided mesh the next surface beyond it along
    /// `ray` (at most [`MAX_PASSED_FACES`] passed), with `t` along `ray`.
    fn past_back_faces(&self, ray: &Ray, mut hit: SurfaceHit) -> Option<SurfaceHit> {
        let mut leg = *ray;
        for _ in 0..MAX_PASSED_FACES {
            let path = self.path(hit.prim);
            if !self.geometry.passes_through(hit.prim, &path, &leg) {
                break;
            }
            // Continue from just beyond the face, skipping it.
            let g = &hit.geometry;
            leg = Ray::new(
                offset_origin(g.point, g.geometric_normal, g.error, leg.dir),
                leg.dir,
            );
            hit = self.first_hit(&leg, Some(hit.prim))?;
            hit.t = (hit.geometry.point - ray.origin).dot(ray.dir) / ray.dir.length_squared();
        }
        Some(hit)
    }

    /// Whether anything blocks `ray` in (0, `t_max`): the any-hit query of shadow rays.
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.occluded_from(ray, t_max, None)
    }

    /// [`Scene::occluded`] for a ray spawned on `from` (a shadow ray leaving a surface): that
    /// primitive's own surface at the ray's origin does not block it. Back faces of single-sided
    /// meshes block nothing: a culled face is not part of the scene for any ray.
    #[inline]
    pub fn occluded_from(&self, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        if self.single_sided {
            return self.occluded_culling(ray, t_max, from);
        }
        self.accel.occluded(&self.geometry, ray, t_max, from)
    }

    /// [`Scene::occluded_from`] for a shadow ray towards light `light` (its index in
    /// [`Scene::lights`]): through the light's buffer where the scene has one. The answer is
    /// [`Scene::occluded_from`]'s for any ray; a ray that does not end at the light, or an index
    /// out of range, takes the BVH.
    #[inline(always)]
    pub fn occluded_towards_light(
        &self,
        light: usize,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        match self.light_buffers.get(light).and_then(Option::as_ref) {
            Some(buffer) => (self.accel).occluded_towards(&self.geometry, buffer, ray, t_max, from),
            None => self.occluded_from(ray, t_max, from),
        }
    }

    /// [`Scene::occluded_from`] in a scene with single-sided meshes: nearest hits in turn, passing
    /// back faces as [`Scene::past_back_faces`] does, until a front or both-sided surface (blocked)
    /// or `t_max` (clear); after [`MAX_PASSED_FACES`] back faces the ray counts as blocked.
    #[inline(never)]
    fn occluded_culling(&self, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> bool {
        let (mut leg, mut leg_t_max, mut from) = (*ray, t_max, from);
        for _ in 0..MAX_PASSED_FACES {
            let Some((t, prim)) = self.accel.closest(&self.geometry, &leg, leg_t_max, from) else {
                return false;
            };
            let path = self.path(prim);
            if !self.geometry.passes_through(prim, &path, &leg) {
                return true;
            }
            let g = self.geometry.surface(prim, &path, &leg, t);
            (leg, leg_t_max) = leg_beyond(ray, t_max, &g);
            from = Some(prim);
        }
        true
    }

    /// [`Scene::intersect`] for every ray of a slice, into `out` (one slot per ray), on the
    /// calling thread; split the slice (for instance with rayon's `par_chunks`) to use more.
    /// Phase one (the nearest hits) runs for up to 64 rays in one call.
    pub fn intersect_many(&self, rays: &[Ray], out: &mut [Option<SurfaceHit>]) {
        assert_eq!(rays.len(), out.len(), "one result per ray");
        const CHUNK: usize = 64;
        let mut firsts = [None; CHUNK];
        for (rays, out) in rays.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let firsts = &mut firsts[..rays.len()];
            self.closest_each(rays, firsts);
            for ((ray, out), &first) in rays.iter().zip(out).zip(&*firsts) {
                *out = first.and_then(|(t, prim)| {
                    self.with_path(prim, |path| {
                        let material = self.geometry.material(prim, path);
                        self.hit_seen(ray, (t, prim), path, material)
                    })
                });
            }
        }
    }

    /// [`Scene::occluded`] for every (ray, `t_max`) of a slice, into `out`, on the calling thread.
    pub fn occluded_many(&self, rays: &[(Ray, f64)], out: &mut [bool]) {
        assert_eq!(rays.len(), out.len(), "one result per ray");
        for ((ray, t_max), out) in rays.iter().zip(out) {
            *out = self.occluded(ray, *t_max);
        }
    }
}

#[cfg(test)]
mod tests;
