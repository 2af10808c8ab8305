//! Whitted-style recursive ray tracing: local Phong/Blinn shading with hard shadows, plus mirror reflection.

use crate::footprint::{HitFootprint, RayCone};
use crate::material::SpecularModel;
use crate::math::{Ray, offset_origin};
use crate::scene::Scene;
use crate::shape::{PrimRef, SurfaceHit};
use glam::{DVec3, Vec3};
use std::ops::AddAssign;

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Primary rays from the camera.
    pub camera: u64,
    /// Occlusion rays towards lights.
    pub shadow: u64,
    /// Mirror reflection rays.
    pub reflection: u64,
}

impl RayCounts {
    /// All rays together.
    pub fn total(&self) -> u64 {
        self.camera + self.shadow + self.reflection
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
    }
}

/// Recursion limits of the Whitted integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Whitted {
    /// Most rays in one chain, the camera ray included (POV-Ray's max_trace_level); the next would be black.
    pub max_depth: u32,
    /// A reflection whose contribution to the pixel would fall below this weight is not traced.
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

impl Whitted {
    /// Radiance arriving along a camera ray whose sample stands for `cone` ([`RayCone::POINT`]
    /// in scenes without filtered textures).
    pub fn camera_ray(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        counts: &mut RayCounts,
    ) -> Vec3 {
        counts.camera += 1;
        if cone.is_point() {
            self.radiance::<false>(scene, ray, cone, None, 1, 1.0, counts)
        } else {
            self.radiance::<true>(scene, ray, cone, None, 1, 1.0, counts)
        }
    }

    /// Radiance arriving along a camera ray, and the ray's first hit (for the AOV passes, which
    /// then cost no second intersection).
    pub fn camera_ray_hit(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        counts: &mut RayCounts,
    ) -> (Vec3, Option<SurfaceHit>) {
        counts.camera += 1;
        let hit = self.intersect(scene, ray, None);
        let radiance = match &hit {
            Some(h) if cone.is_point() => self.shade::<false>(scene, ray, cone, h, 1, 1.0, counts),
            Some(h) => self.shade::<true>(scene, ray, cone, h, 1, 1.0, counts),
            None => scene.background(),
        };
        (radiance, hit)
    }

    /// The nearest hit of `ray` with its full surface record (phase two runs once, here).
    pub fn intersect(&self, scene: &Scene, ray: &Ray, from: Option<PrimRef>) -> Option<SurfaceHit> {
        scene.intersect_from(ray, from)
    }

    /// Radiance along `ray` (with its `cone` when `CONES`), the `depth`-th ray of its chain,
    /// whose contribution is weighted by `throughput`.
    #[allow(clippy::too_many_arguments)]
    fn radiance<const CONES: bool>(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        from: Option<PrimRef>,
        depth: u32,
        throughput: f32,
        counts: &mut RayCounts,
    ) -> Vec3 {
        match self.intersect(scene, ray, from) {
            Some(hit) => self.shade::<CONES>(scene, ray, cone, &hit, depth, throughput, counts),
            None if depth > 1 => scene.environment(),
            None => scene.background(),
        }
    }

    /// Radiance leaving `hit` back along `ray` (with its `cone` when `CONES`): local shading plus
    /// the mirror reflection. Without cones (scenes with no filtered texture) `cone` is ignored,
    /// and the shading compiles as if cones did not exist.
    #[allow(clippy::too_many_arguments)]
    fn shade<const CONES: bool>(
        &self,
        scene: &Scene,
        ray: &Ray,
        cone: RayCone,
        hit: &SurfaceHit,
        depth: u32,
        throughput: f32,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let m = &scene.materials()[hit.material as usize];
        let g = &hit.geometry;
        let incoming = ray.dir.normalize();
        // Without cones the footprint is a compile-time point, and so is everything cut from it.
        let distance = if CONES { hit.t * ray.dir.length() } else { 0.0 };
        let footprint = if CONES {
            HitFootprint::new(&cone, incoming, distance)
        } else {
            HitFootprint::POINT
        };
        let base = scene.albedo(hit, &footprint);
        let view = -incoming;
        // Two-sided shading: face both normals towards the viewer.
        let facing = if g.geometric_normal.dot(view) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let ng = g.geometric_normal * facing;
        let ns = g.shading_normal * facing;
        let matte = 1.0 - m.reflectivity;
        let mut color = base * (m.ambient * matte);
        if m.emission.is_some() {
            color += scene.emitted(hit, &footprint);
        }

        let highlight = m.highlight_color(base);
        for light in scene.lights() {
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
            if scene.occluded_from(&shadow, inc.distance, Some(hit.prim)) {
                continue;
            }
            let mut response = base * (m.diffuse * matte * cos as f32);
            if m.specular > 0.0 {
                let alignment = match m.specular_model {
                    SpecularModel::Phong => reflect(-inc.to_light, ns).dot(view),
                    SpecularModel::Blinn => (inc.to_light + view).normalize().dot(ns),
                };
                if alignment > 0.0 {
                    response += highlight * m.specular_lobe(alignment as f32);
                }
            }
            color += inc.irradiance * response;
        }

        let weight = throughput * m.reflectivity;
        if m.reflectivity > 0.0 && depth < self.max_depth && weight >= self.min_throughput {
            let mut dir = reflect(incoming, ns);
            // An interpolated normal can mirror the ray into the surface; fall back to the true normal.
            if dir.dot(ng) <= 0.0 {
                dir = reflect(incoming, ng);
            }
            counts.reflection += 1;
            let reflected = Ray::new(offset_origin(g.point, ng, g.error, dir), dir);
            let reflected_cone = if CONES {
                cone.reflected(distance, scene.curvature(hit))
            } else {
                RayCone::POINT
            };
            color += self.radiance::<CONES>(
                scene,
                &reflected,
                reflected_cone,
                Some(hit.prim),
                depth + 1,
                weight,
                counts,
            ) * m.reflection_color(base);
        }
        color
    }
}

/// `d` mirrored about the unit normal `n`.
#[inline]
fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - n * (2.0 * d.dot(n))
}
