//! Whitted-style recursive ray tracing: local Phong/Blinn shading with hard shadows, plus mirror
//! reflection and refraction through glass ([`crate::dielectric`]).

use crate::dielectric::Attenuation;
use crate::footprint::{HitFootprint, RayCone};
use crate::material::SpecularModel;
use crate::math::{Ray, offset_origin};
use crate::sampler::SampleKey;
use crate::scene::{Scene, Seen};
use crate::shape::{PrimRef, SurfaceHit};
use glam::{DVec3, Vec3};
use std::ops::AddAssign;

mod shading;

use shading::{Glass, Shading, reflect};

/// Rays by kind: those traced, and camera rays answered without tracing (counted among the
/// camera rays, and apart in [`RayCounts::untraced_camera`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Primary rays from the camera.
    pub camera: u64,
    /// Of the camera rays, those of tiles known to see nothing, answered with the background
    /// without being traced.
    pub untraced_camera: u64,
    /// Occlusion rays towards lights.
    pub shadow: u64,
    /// Mirror reflection rays.
    pub reflection: u64,
    /// Rays refracted through glass.
    pub refraction: u64,
}

impl RayCounts {
    /// All rays together.
    pub fn total(&self) -> u64 {
        self.camera + self.shadow + self.reflection + self.refraction
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.untraced_camera += o.untraced_camera;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
    }
}

/// Recursion limits of the Whitted integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Whitted {
    /// Most rays in one chain, the camera ray included (POV-Ray's max_trace_level); the next would be black.
    pub max_depth: u32,
    /// A reflected or refracted ray whose contribution to the pixel would fall below this weight
    /// is not traced.
    pub min_throughput: f32,
}

impl Default for Whitted {
    fn default() -> Self {
        Whitted {
            max_depth: 8,
            min_throughput: 1.0 / 512.0,
        }
    }
}

/// A secondary ray's cone, or what makes it: a mirror's reflected cone needs the mirror's
/// curvature, which is worked out only once the reflected ray is known to meet something (three
/// in four of scenes/reflective.toml's reflection rays leave for the sky, which needs no cone).
#[derive(Clone, Copy)]
enum ConeOf<'h> {
    /// The cone itself.
    Known(RayCone),
    /// The cone `incoming`, reflected `distance` along it by the mirror hit `mirror`.
    Reflected {
        incoming: RayCone,
        distance: f64,
        mirror: &'h SurfaceHit,
    },
}

impl ConeOf<'_> {
    /// The cone.
    #[inline(always)]
    fn made(self, scene: &Scene) -> RayCone {
        match self {
            ConeOf::Known(cone) => cone,
            ConeOf::Reflected {
                incoming,
                distance,
                mirror,
            } => incoming.reflected(distance, scene.curvature(mirror)),
        }
    }
}

impl Whitted {
    /// Radiance arriving along a camera ray whose sample stands for `cone` ([`RayCone::POINT`]
    /// in scenes without filtered textures).
    pub fn camera_ray(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        key: SampleKey,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let mut radiance = [Vec3::ZERO];
        let rays = std::slice::from_ref(ray);
        self.camera_rays(scene, rays, cone, |_| key, counts, &mut radiance);
        radiance[0]
    }

    /// [`Whitted::camera_ray`] for each ray of `rays` into `radiances` (one each), ray `i` being
    /// sample `key(i)`, which is asked for only where shading needs it. One call for a batch
    /// of rays instead of one a ray: the kitchen's camera-rays-only frame spent about 40
    /// instructions a ray on the call and its checks.
    pub fn camera_rays(
        &self,
        scene: &Scene,
        rays: &[Ray],
        cone: RayCone,
        key: impl Fn(usize) -> SampleKey,
        counts: &mut RayCounts,
        radiances: &mut [Vec3],
    ) {
        assert_eq!(rays.len(), radiances.len(), "one radiance per ray");
        counts.camera += rays.len() as u64;
        // Phase one for up to a render's batch of rays (32) in one call, then each hit shaded:
        // the call, its compiled path's choice and the traversal's set-up paid once a batch
        // (3% of the kitchen's camera-rays-only frame).
        const CHUNK: usize = 32;
        let mut firsts = [None; CHUNK];
        for (c, (rays, radiances)) in rays
            .chunks(CHUNK)
            .zip(radiances.chunks_mut(CHUNK))
            .enumerate()
        {
            let firsts = &mut firsts[..rays.len()];
            scene.closest_each(rays, firsts);
            for (j, ((ray, radiance), &first)) in
                rays.iter().zip(radiances).zip(&*firsts).enumerate()
            {
                *radiance = match scene.seen_given(ray, first) {
                    Seen::Surface(hit) => {
                        self.shade_camera_hit(scene, ray, cone, &hit, key(c * CHUNK + j), counts)
                    }
                    Seen::Constant { radiance, .. } => radiance,
                    Seen::Nothing => scene.background(),
                };
            }
        }
    }

    /// Radiance arriving along a camera ray, and the ray's first hit (for the AOV passes, which
    /// then cost no second intersection).
    pub fn camera_ray_hit(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        key: SampleKey,
        counts: &mut RayCounts,
    ) -> (Vec3, Option<SurfaceHit>) {
        counts.camera += 1;
        let hit = self.intersect(scene, ray, None);
        let radiance = match &hit {
            Some(h) => self.shade_camera_hit(scene, ray, cone, h, key, counts),
            None => scene.background(),
        };
        (radiance, hit)
    }

    /// Radiance leaving a camera ray's first hit towards the camera.
    #[inline(always)]
    fn shade_camera_hit(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        hit: &SurfaceHit,
        key: SampleKey,
        counts: &mut RayCounts,
    ) -> Vec3 {
        // Each combination compiles its own path: a scene without filtered textures or glass
        // pays nothing for them.
        match (cone.is_point(), scene.transmits()) {
            (true, false) => {
                self.shade::<false, false>(scene, ray, cone, hit, 1, 1.0, true, key, counts)
            }
            (false, false) => {
                self.shade::<true, false>(scene, ray, cone, hit, 1, 1.0, true, key, counts)
            }
            (true, true) => {
                self.shade::<false, true>(scene, ray, cone, hit, 1, 1.0, true, key, counts)
            }
            (false, true) => {
                self.shade::<true, true>(scene, ray, cone, hit, 1, 1.0, true, key, counts)
            }
        }
    }

    /// The nearest hit of `ray` with its full surface record (phase two runs once, here).
    pub fn intersect(&self, scene: &Scene, ray: &Ray, from: Option<PrimRef>) -> Option<SurfaceHit> {
        scene.intersect_from(ray, from)
    }

    /// Radiance along `ray` (with its `cone` when `CONES`), the `depth`-th ray of its chain,
    /// whose contribution is weighted by `throughput`, travelling inside a solid that absorbs as
    /// `medium` (Beer–Lambert over the distance to the hit) or outside when `None`. A miss shows
    /// the camera's background when `backdrop` (the chain so far: the camera ray and rays through
    /// glass), else the environment reflections show.
    #[allow(clippy::too_many_arguments)]
    fn radiance<const CONES: bool, const GLASS: bool>(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: ConeOf<'_>,
        from: Option<PrimRef>,
        depth: u32,
        throughput: f32,
        medium: Option<Attenuation>,
        backdrop: bool,
        key: SampleKey,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let (leaving, t) = match scene.seen_from(ray, from) {
            Seen::Surface(hit) => (
                self.shade::<CONES, GLASS>(
                    scene,
                    ray,
                    cone.made(scene),
                    &hit,
                    depth,
                    throughput,
                    backdrop,
                    key,
                    counts,
                ),
                hit.t,
            ),
            Seen::Constant { t, radiance } => (radiance, t),
            // The camera's backdrop, seen directly or through glass; reflections show the
            // surroundings.
            Seen::Nothing if backdrop => return scene.background(),
            Seen::Nothing => return scene.environment(),
        };
        match medium {
            Some(a) if GLASS => leaving * a.after(t * ray.dir.length()),
            _ => leaving,
        }
    }

    /// Radiance leaving `hit` back along `ray` (with its `cone` when `CONES`; through glass when
    /// `GLASS`, in scenes with any): local shading plus the mirror reflection and refraction.
    /// Without cones (scenes with no filtered texture) `cone` is ignored, and the shading
    /// compiles as if cones did not exist; without `GLASS`, as if glass did not.
    #[allow(clippy::too_many_arguments)]
    fn shade<const CONES: bool, const GLASS: bool>(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        hit: &SurfaceHit,
        depth: u32,
        throughput: f32,
        backdrop: bool,
        key: SampleKey,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let m = &scene.materials()[hit.material as usize];
        let incoming = ray.dir.normalize();
        // Without cones the footprint is a compile-time point, and so is everything cut from it.
        let distance = if CONES { hit.t * ray.dir.length() } else { 0.0 };
        let footprint = if CONES {
            HitFootprint::new(&cone, incoming, distance)
        } else {
            HitFootprint::POINT
        };
        let base = scene.albedo(hit, &footprint);
        let s = Shading::at::<GLASS>(m, &hit.geometry, incoming, base);
        let mut color = base * (m.ambient * s.matte);
        if m.emission.is_some() {
            color += scene.emitted(hit, &footprint);
        }

        let normals = (s.ns, s.ng, s.view);
        color = self.direct_light::<GLASS>(scene, hit, base, normals, s.matte, color, counts);

        // The mirror: the opaque share's reflectivity, plus the Fresnel share of glass.
        let (mirror, mirror_share) = match &s.glass {
            None if s.ggx => (s.view_fresnel, s.view_fresnel.max_element()),
            None => (m.reflection_color(base), m.reflectivity),
            Some(g) => {
                let mirror = m.reflection_color(base) * s.opaque + Vec3::splat(g.reflected);
                (mirror, mirror.max_element())
            }
        };
        let weight = throughput * mirror_share;
        if mirror_share > 0.0 && depth < self.max_depth && weight >= self.min_throughput {
            let g = &hit.geometry;
            if let Some((dir, mirror)) = s.mirror_ray(m, base, mirror, key, depth) {
                counts.reflection += 1;
                let reflected = Ray::new(offset_origin(g.point, s.ng, g.error, dir), dir);
                let reflected_cone = if CONES {
                    ConeOf::Reflected {
                        incoming: cone,
                        distance,
                        mirror: hit,
                    }
                } else {
                    ConeOf::Known(RayCone::POINT)
                };
                // Reflected inside a solid, the ray stays in it.
                let medium = s.glass.as_ref().and_then(|g| g.inside_after_reflection());
                color += self.radiance::<CONES, GLASS>(
                    scene,
                    &reflected,
                    reflected_cone,
                    Some(hit.prim),
                    depth + 1,
                    weight,
                    medium,
                    false,
                    key,
                    counts,
                ) * mirror;
            }
        }
        if let Some(glass) = &s.glass {
            color += self.refracted::<CONES>(
                scene, ray, cone, hit, depth, throughput, glass, backdrop, key, counts,
            );
        }
        color
    }

    /// `color` plus the light reaching `hit` straight from the scene's lights (diffuse, weighted
    /// by `matte`, and highlights), each behind its shadow ray; through glass a share of it when
    /// `GLASS`. The normals are the shading and geometric ones facing the viewer, then the
    /// direction towards it. Added to `color` light by light, in the order shading always added.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn direct_light<const GLASS: bool>(
        &self,
        scene: &Scene,
        hit: &SurfaceHit,
        base: Vec3,
        (ns, ng, view): (DVec3, DVec3, DVec3),
        matte: f32,
        mut color: Vec3,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let m = &scene.materials()[hit.material as usize];
        // A surface with neither a diffuse share nor highlights (a perfect mirror) takes nothing
        // from the lights: no shadow rays for it.
        if m.diffuse * matte == 0.0 && m.specular <= 0.0 {
            return color;
        }
        let g = &hit.geometry;
        // Phong and Blinn scale their lobe by the highlight colour; GGX's Fresnel starts from F₀.
        let highlight = match m.specular_model {
            SpecularModel::Ggx => m.fresnel_f0(base),
            _ => m.highlight_color(base),
        };
        for (index, light) in scene.lights().iter().enumerate() {
            let Some(inc) = light.incident(g.point) else {
                continue;
            };
            let cos = ns.dot(inc.to_light);
            // Lit from behind (either normal): no contribution, so no shadow ray either.
            if cos <= 0.0 || ng.dot(inc.to_light) <= 0.0 {
                continue;
            }
            counts.shadow += 1;
            let shadow = Ray::new(
                offset_origin(g.point, ng, g.error, inc.to_light),
                inc.to_light,
            );
            // Through glass, a share of the light arrives; otherwise all or nothing.
            let through = if GLASS {
                let through = scene.transmittance(&shadow, inc.distance, Some(hit.prim));
                if through == Vec3::ZERO {
                    continue;
                }
                through
            } else if scene.occluded_towards_light(index, &shadow, inc.distance, Some(hit.prim)) {
                continue;
            } else {
                Vec3::ONE
            };
            let mut response = base * (m.diffuse * matte * cos as f32);
            if m.specular > 0.0 {
                let alignment = match m.specular_model {
                    SpecularModel::Phong => reflect(-inc.to_light, ns).dot(view),
                    SpecularModel::Blinn => (inc.to_light + view).normalize().dot(ns),
                    SpecularModel::Ggx => {
                        let alpha = (m.roughness * m.roughness) as f64;
                        response +=
                            crate::microfacet::highlight(ns, view, inc.to_light, alpha, highlight);
                        0.0
                    }
                };
                if alignment > 0.0 {
                    response += highlight * m.specular_lobe(alignment as f32);
                }
            }
            color += inc.irradiance * response * through;
        }

        color
    }

    /// The light `glass` lets through at `hit` from beyond it, along the refracted ray (straight
    /// on through a thin sheet); nothing past the critical angle, or when the ray would weigh
    /// too little.
    #[allow(clippy::too_many_arguments)]
    fn refracted<const CONES: bool>(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        hit: &SurfaceHit,
        depth: u32,
        throughput: f32,
        glass: &Glass,
        backdrop: bool,
        key: SampleKey,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let Some(dir) = glass.direction else {
            return Vec3::ZERO;
        };
        let weight = throughput * glass.through.max_element();
        if depth >= self.max_depth || weight < self.min_throughput {
            return Vec3::ZERO;
        }
        counts.refraction += 1;
        let g = &hit.geometry;
        let refracted = Ray::new(
            offset_origin(g.point, g.geometric_normal, g.error, dir),
            dir,
        );
        // The footprint carries on as if the surface were flat (refraction's own spread of a
        // cone is not modelled).
        let refracted_cone = ConeOf::Known(if CONES {
            cone.reflected(hit.t * ray.dir.length(), 0.0)
        } else {
            RayCone::POINT
        });
        self.radiance::<CONES, true>(
            scene,
            &refracted,
            refracted_cone,
            Some(hit.prim),
            depth + 1,
            weight,
            glass.inside_after_refraction(),
            backdrop,
            key,
            counts,
        ) * glass.through
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection};
    use crate::geometry::Geometry;
    use crate::light::Light;
    use crate::material::Material;
    use crate::plane::Plane;
    use crate::scene::SceneDescription;
    use crate::texture::Texture;
    use crate::{Scene, Sphere};
    use glam::DVec3;

    /// A sphere of material `ball` on a grey floor, seen from straight above, with `lights`.
    fn ball_on_floor(ball: Material, lights: Vec<Light>) -> Scene {
        Scene::new(SceneDescription {
            camera: Camera {
                from: DVec3::new(0.0, 0.0, 10.0),
                to: DVec3::ZERO,
                up: DVec3::Y,
                projection: Projection::Perspective { vfov_deg: 30.0 },
            },
            background: Vec3::new(0.05, 0.1, 0.2),
            environment: Some(Vec3::new(0.3, 0.2, 0.1)),
            materials: vec![ball, Material::default()],
            lights,
            geometry: Geometry {
                spheres: vec![Sphere {
                    center: DVec3::new(0.0, 0.0, 1.0),
                    radius: 1.0,
                    material: 0,
                }],
                planes: vec![Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                    material: 1,
                }],
                ..Geometry::default()
            },
        })
        .unwrap()
    }

    /// A perfect mirror (no diffuse share, no highlight) takes nothing from the lights, so its
    /// hit casts no shadow ray, and it shows the same radiance lit as unlit; a mirror with a
    /// diffuse share casts one towards the light it faces.
    #[test]
    fn a_perfect_mirror_casts_no_shadow_rays() {
        let mirror = Material {
            texture: Texture::Constant(Vec3::splat(0.9)),
            ambient: 0.0,
            diffuse: 0.0,
            specular: 0.0,
            reflectivity: 0.8,
            ..Material::default()
        };
        let light = Light::Point {
            position: DVec3::new(3.0, 0.0, 8.0),
            intensity: Vec3::splat(50.0),
        };
        // Straight down onto the ball's top, reflected straight up into the environment.
        let ray = Ray::new(DVec3::new(0.0, 0.0, 10.0), DVec3::new(0.0, 0.0, -1.0));
        let key = SampleKey {
            pattern: 0,
            index: 0,
            count: Some(1),
        };
        let trace = |ball: &Material, lights: Vec<Light>| {
            let scene = ball_on_floor(ball.clone(), lights);
            let mut counts = RayCounts::default();
            let radiance =
                Whitted::default().camera_ray(&scene, &ray, RayCone::POINT, key, &mut counts);
            (radiance, counts)
        };
        let (lit, counts) = trace(&mirror, vec![light.clone()]);
        let (unlit, _) = trace(&mirror, Vec::new());
        assert_eq!((counts.shadow, counts.reflection), (0, 1));
        assert_eq!(lit, unlit);
        assert!(lit.max_element() > 0.0, "the mirror shows the environment");
        let half_matte = Material {
            diffuse: 0.5,
            ..mirror
        };
        let (_, counts) = trace(&half_matte, vec![light]);
        assert_eq!((counts.shadow, counts.reflection), (1, 1));
    }
}
