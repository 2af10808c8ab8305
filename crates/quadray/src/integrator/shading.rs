//! What a hit's surface makes of the light arriving along one ray, shared by the terms of its
//! shading: the directions turned towards the viewer, the split between glass, mirror and matte,
//! and the mirror and refracted rays' directions.

use crate::dielectric::{Attenuation, Transmission, fresnel, refract};
use crate::material::{Material, SpecularModel};
use crate::microfacet::{MIRROR_ROUGHNESS, reflect_glossy, schlick};
use crate::sampler::SampleKey;
use crate::shape::SurfaceGeometry;
use glam::{DVec3, Vec3};

/// What the terms of a hit's shading share: the directions, turned towards the viewer, and how
/// the surface splits light between glass, mirror and matte.
pub(super) struct Shading {
    /// Unit direction of the arriving ray.
    pub(super) incoming: DVec3,
    /// Unit direction back towards the viewer.
    pub(super) view: DVec3,
    /// The shading normal, on the viewer's side.
    pub(super) ns: DVec3,
    /// The geometric normal, on the viewer's side.
    pub(super) ng: DVec3,
    /// The glass split, for a transmissive material (in scenes with glass).
    pub(super) glass: Option<Glass>,
    /// The share of the surface that is not glass.
    pub(super) opaque: f32,
    /// Whether the surface follows glTF's model (GGX highlights, Schlick's Fresnel), glass aside.
    pub(super) ggx: bool,
    /// Schlick's Fresnel at the view for `ggx`, else zero.
    pub(super) view_fresnel: Vec3,
    /// The weight of the ambient and diffuse terms.
    pub(super) matte: f32,
}

impl Shading {
    /// The shading of material `m` at a hit of geometry `g`, seen along unit `incoming`, with
    /// base colour `base` (through glass only when `GLASS`).
    #[inline(always)]
    pub(super) fn at<const GLASS: bool>(
        m: &Material,
        g: &SurfaceGeometry,
        incoming: DVec3,
        base: Vec3,
    ) -> Shading {
        let view = -incoming;
        // Two-sided shading: face both normals towards the viewer.
        let facing = if g.geometric_normal.dot(view) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let ng = g.geometric_normal * facing;
        let ns = g.shading_normal * facing;
        // Glass splits what it does not reflect by Fresnel into light through it; the rest of
        // the surface is the opaque material.
        let glass = m
            .transmission
            .as_ref()
            .filter(|_| GLASS)
            .map(|t| Glass::at(t, incoming, (ns, ng), facing > 0.0, base));
        let opaque = glass.as_ref().map_or(1.0, |g| 1.0 - g.transmission.factor);
        // glTF's model weighs the mirror by Schlick's Fresnel, not by `reflectivity`, and takes
        // what it reflects from the diffuse and ambient terms (which already carry the
        // metalness): (1 − F) at the view, F's largest channel (grey for a dielectric, the only
        // kind with a diffuse term). Glass keeps its exact Fresnel split instead.
        let ggx = m.specular_model == SpecularModel::Ggx && glass.is_none();
        let view_fresnel = if ggx {
            schlick(m.fresnel_f0(base), view.dot(ns))
        } else {
            Vec3::ZERO
        };
        let matte = if ggx {
            1.0 - view_fresnel.max_element()
        } else {
            (1.0 - m.reflectivity) * opaque
        };
        Shading {
            incoming,
            view,
            ns,
            ng,
            glass,
            opaque,
            ggx,
            view_fresnel,
            matte,
        }
    }

    /// The reflected ray's direction and the colour weighing what it brings back, for a mirror
    /// of colour `mirror` (material `m`, base colour `base`): the mirror direction, or for a
    /// rough material one ray from the GGX lobe, drawn with sample `key`'s point for the bounce
    /// at `depth`. `None` when the drawn microfacet sends the ray below the surface.
    #[inline(always)]
    pub(super) fn mirror_ray(
        &self,
        m: &Material,
        base: Vec3,
        mirror: Vec3,
        key: SampleKey,
        depth: u32,
    ) -> Option<(DVec3, Vec3)> {
        let (incoming, ns, ng) = (self.incoming, self.ns, self.ng);
        if m.roughness < MIRROR_ROUGHNESS {
            let mut dir = reflect(incoming, ns);
            // An interpolated normal can mirror the ray into the surface; fall back to the true
            // normal.
            if dir.dot(ng) <= 0.0 {
                dir = reflect(incoming, ng);
            }
            return Some((dir, mirror));
        }
        let alpha = (m.roughness * m.roughness) as f64;
        reflect_glossy(incoming, ns, alpha, key.bounce(depth))
            .filter(|(dir, _)| dir.dot(ng) > 0.0)
            .map(|(dir, masking)| {
                // glTF's Fresnel is the microfacet's: at the half vector of view and ray.
                let fresnel = if self.ggx {
                    schlick(
                        m.fresnel_f0(base),
                        self.view.dot((self.view + dir).normalize()),
                    )
                } else {
                    mirror
                };
                (dir, fresnel * masking)
            })
    }
}

/// What a transmissive surface does with one incoming ray: the shares reflected and let
/// through, and where the light through it goes.
pub(super) struct Glass {
    /// The material's transmission.
    pub(super) transmission: Transmission,
    /// Whether the ray arrives from outside the solid (the front of the surface).
    pub(super) entering: bool,
    /// Share of the light reflected by the Fresnel equations (of the transmitted share).
    pub(super) reflected: f32,
    /// Colour multiplying the light through: factor · (1 − F) · base colour.
    pub(super) through: Vec3,
    /// The refracted direction, or `None` past the critical angle.
    pub(super) direction: Option<DVec3>,
}

impl Glass {
    /// The split at a hit seen along unit `incoming`, with unit shading and geometric normals
    /// facing the viewer; `entering` when the viewer is on the front (outward) side; `base` the
    /// base colour.
    fn at(
        t: &Transmission,
        incoming: DVec3,
        (n, ng): (DVec3, DVec3),
        entering: bool,
        base: Vec3,
    ) -> Glass {
        // n_t / n_i: into the glass from outside, out of it from inside; a thin sheet is entered
        // and left at once, so its reflection is the entering one's.
        let eta = if t.thin_walled || entering {
            t.ior
        } else {
            1.0 / t.ior
        };
        let cos_i = (-incoming.dot(n)).clamp(0.0, 1.0);
        let f = fresnel(cos_i, eta);
        // Bent about the interpolated normal, a ray near a smooth mesh's silhouette can turn back
        // to the viewer's side; it is bent about the true normal instead, or reflected whole.
        let direction = if t.thin_walled {
            Some(incoming)
        } else {
            refract(incoming, n, eta)
                .filter(|d| d.dot(ng) < 0.0)
                .or_else(|| refract(incoming, ng, eta))
        };
        Glass {
            transmission: *t,
            entering,
            reflected: t.factor * f as f32,
            through: base * (t.factor * (1.0 - f) as f32),
            direction: direction.filter(|_| f < 1.0),
        }
    }

    /// The solid the refracted ray travels in: this one when it enters a solid.
    pub(super) fn inside_after_refraction(&self) -> Option<Attenuation> {
        let t = &self.transmission;
        (self.entering && !t.thin_walled)
            .then_some(t.attenuation)
            .flatten()
    }

    /// The solid the reflected ray travels in: this one when the ray was inside it.
    pub(super) fn inside_after_reflection(&self) -> Option<Attenuation> {
        let t = &self.transmission;
        (!self.entering && !t.thin_walled)
            .then_some(t.attenuation)
            .flatten()
    }
}

/// `d` mirrored about the unit normal `n`.
#[inline]
pub(super) fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - n * (2.0 * d.dot(n))
}
