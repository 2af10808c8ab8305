//! Shadow rays through glass: how much of a light's straight-line path gets through the
//! transmissive surfaces in the way.
//!
//! The convention (as POV-Ray's for its filtering surfaces, and pbrt's Whitted integrator's lack
//! of caustics): a shadow ray is not bent. At each transmissive surface it crosses it keeps the
//! transmitted share `factor · (1 − F) · base colour`, F the Fresnel reflectance of the boundary
//! seen from outside at that crossing's angle. From inside too: the unbent ray's angle there is
//! not a real ray's (a straight chord would meet total internal reflection where the refracted
//! ray gets out), while by reciprocity a refracted ray leaves a sphere with the reflectance it
//! entered with. Between entering and leaving a solid with an
//! attenuation it loses what Beer–Lambert's law takes over the straight path. An opaque surface
//! (or the opaque share of a transmissive one) blocks. Light focused by glass (caustics) is not
//! followed: Whitted tracing reaches lights only along shadow rays.

use super::{MAX_PASSED_FACES, Scene, leg_beyond};
use crate::dielectric::{Attenuation, fresnel};
use crate::footprint::HitFootprint;
use crate::math::Ray;
use crate::shape::{PrimRef, SurfaceHit};
use glam::{DVec3, Vec3};

/// Below this in every channel, a shadow ray counts as blocked.
const OPAQUE: f32 = 1e-6;

impl Scene {
    /// Whether any material lets light through: only then do shadow rays ask for
    /// [`Scene::transmittance`] instead of [`Scene::occluded_from`].
    pub fn transmits(&self) -> bool {
        self.transmits
    }

    /// The share of light travelling along `ray` from its origin to `t_max` that arrives, per
    /// channel: 0 when an opaque surface is in the way, else the product over the transmissive
    /// surfaces crossed (see the module's convention). `from` is the primitive the ray leaves.
    pub fn transmittance(&self, ray: &Ray, t_max: f64, from: Option<PrimRef>) -> Vec3 {
        let mut through = Vec3::ONE;
        let (mut leg, mut leg_t_max, mut from) = (*ray, t_max, from);
        // The solid the ray is in, if it absorbs: its attenuation and where the ray entered it.
        let mut inside: Option<(Attenuation, DVec3)> = None;
        let direction = ray.dir.normalize();
        for _ in 0..MAX_PASSED_FACES {
            let Some((t, prim)) = self.accel.closest(&self.geometry, &leg, leg_t_max, from) else {
                // The light lies inside the solid: absorbed up to it.
                if let Some((a, entry)) = inside {
                    let end = ray.origin + ray.dir * t_max;
                    through *= a.after(end.distance(entry));
                }
                return through;
            };
            let mut slot = None;
            let path = self.path_in(prim.placement, &mut slot);
            let hit = SurfaceHit {
                t,
                prim,
                material: self.geometry.material(prim, path),
                geometry: self.geometry.surface(prim, path, &leg, t),
            };
            let g = &hit.geometry;
            let culled = self.single_sided && self.geometry.passes_through(prim, path, &leg);
            if !culled {
                let m = &self.materials[hit.material as usize];
                let Some(glass) = &m.transmission else {
                    return Vec3::ZERO;
                };
                let cos = direction.dot(g.geometric_normal);
                let entering = cos < 0.0;
                let kept = glass.factor * (1.0 - fresnel(cos.abs(), glass.ior)) as f32;
                through *= self.albedo(&hit, &HitFootprint::POINT) * kept;
                if !glass.thin_walled {
                    match (entering, glass.attenuation, inside) {
                        (true, Some(a), _) => inside = Some((a, g.point)),
                        (false, _, Some((a, entry))) => {
                            through *= a.after(g.point.distance(entry));
                            inside = None;
                        }
                        _ => {}
                    }
                }
                if through.max_element() < OPAQUE {
                    return Vec3::ZERO;
                }
            }
            (leg, leg_t_max) = leg_beyond(ray, t_max, g);
            from = Some(prim);
        }
        Vec3::ZERO
    }
}
