//! The Whitted material: ambient, Lambert diffuse, Phong or Blinn specular, mirror reflection.

use crate::texture::{Texture, TextureExtent, TexturePoint, VertexAttributes};
use glam::Vec3;

/// Index of a material in [`crate::Scene::materials`].
pub type MaterialId = u32;

/// Which highlight model a material uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecularModel {
    /// Phong: (r·v)^n with r the light direction mirrored about the normal.
    #[default]
    Phong,
    /// Blinn–Phong: (n·h)^n with h the half vector of light and view directions.
    Blinn,
    /// glTF's metallic-roughness specular BRDF (the Khronos glTF-Sample-Viewer's): GGX
    /// distribution of [`Material::roughness`], Smith's height-correlated masking, and Schlick's
    /// Fresnel from [`Material::fresnel_f0`], for the lights' highlights and for the mirror (whose
    /// weight is then that Fresnel, not `reflectivity`); `shininess` is not used.
    Ggx,
}

/// A surface's response to light, Whitted style.
///
/// Radiance leaving a point is `(1 − reflectivity)·(ambient + diffuse)·base +
/// specular·s_tint·highlight + reflectivity·r_tint·(radiance from the mirror direction)`: a
/// perfect mirror (reflectivity 1) shows no diffuse colour but keeps its highlights, like a coated
/// surface. Each tint is white at 0 and the base colour at 1 (`specular_tint`, `reflection_tint`):
/// a metal's highlights and reflections take its colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Base colour (albedo) source.
    pub texture: Texture,
    /// Ambient coefficient: the share of the base colour visible without any light.
    pub ambient: f32,
    /// Lambert diffuse coefficient.
    pub diffuse: f32,
    /// Specular highlight coefficient (highlights take the light's colour).
    pub specular: f32,
    /// Highlight exponent.
    pub shininess: f32,
    /// Phong or Blinn highlight.
    pub specular_model: SpecularModel,
    /// Mirror reflectivity in [0, 1]; 0 spawns no reflection ray.
    pub reflectivity: f32,
    /// How far mirror reflections take the base colour, in [0, 1]: 0 white (a coating), 1 the base
    /// colour (a metal; glTF's metallic factor).
    pub reflection_tint: f32,
    /// How far highlights take the base colour, in [0, 1]: 0 the light's colour (plastic, paint),
    /// 1 the base colour times the light's (a metal).
    pub specular_tint: f32,
    /// Radiance the surface gives off itself (linear RGB, added to what it reflects), or `None`.
    /// It is seen directly and in mirrors, but lights no other surface: Whitted tracing follows
    /// light only from the scene's lights.
    pub emission: Option<Texture>,
    /// Microfacet roughness of the mirror reflection, in [0, 1] (glTF's; GGX α = roughness²):
    /// below [`crate::microfacet::MIRROR_ROUGHNESS`] a perfect mirror, one ray; above, one
    /// glossy ray per sample drawn from the GGX lobe, so the blur converges with the samples.
    pub roughness: f32,
    /// Glass: light through the surface ([`crate::dielectric`]), or `None` for an opaque one.
    /// With it, the mirror reflection of the transmitted share follows the Fresnel equations
    /// instead of `reflectivity`.
    pub transmission: Option<crate::dielectric::Transmission>,
}

impl Material {
    /// The base colour (albedo) at a hit: the texture times the vertex colour. `point` is asked
    /// for only by the procedural textures that read it ([`Texture::eval_at`]).
    #[inline]
    pub fn base_color(
        &self,
        point: impl FnOnce(bool) -> (TexturePoint, TextureExtent),
        attributes: &VertexAttributes,
    ) -> Vec3 {
        self.texture.eval_at(point, attributes) * attributes.color.truncate()
    }

    /// The radiance this material's surfaces leave in a scene without lights and without vertex
    /// colours, when it depends on nothing about the hit: an opaque, non-reflective, non-GGX
    /// material of constant colour and emission leaves its ambient term plus its emission (what
    /// `Whitted::shade` computes for it, operation for operation); `None` for any other material.
    pub fn unlit_constant_radiance(&self) -> Option<Vec3> {
        let Texture::Constant(base) = self.texture else {
            return None;
        };
        let emission = match &self.emission {
            None => None,
            Some(Texture::Constant(c)) => Some(*c),
            Some(_) => return None,
        };
        let opaque_matte = self.reflectivity == 0.0
            && self.transmission.is_none()
            && self.specular_model != SpecularModel::Ggx;
        // shade: base × (ambient × matte) with matte = (1 − reflectivity) × 1 = 1 exactly, then
        // the emission added where there is one.
        opaque_matte.then(|| {
            let ambient = base * (self.ambient * (1.0 - self.reflectivity));
            emission.map_or(ambient, |e| ambient + e)
        })
    }

    /// The specular lobe `alignment^shininess` for an alignment in (0, 1]: by repeated
    /// multiplication when the exponent is a whole number up to 1024 (as in every bundled scene),
    /// which is exact to a few ulps and several times cheaper than `powf`; by `powf` otherwise.
    #[inline]
    pub fn specular_lobe(&self, alignment: f32) -> f32 {
        let n = self.shininess;
        // A whole number in range, told by a round trip through u32 (`fract` is a call to libm's
        // `truncf` on baseline x86-64, 0.4% of the defense frame's instructions).
        if (0.0..=1024.0).contains(&n) && (n as u32) as f32 == n {
            // `powi`'s own binary powering (compiler-builtins' `__powisf2`, the same products in
            // the same order), inlined: the library call was 1% of a lit frame.
            let (mut power, mut base, mut lobe) = (n as u32, alignment, 1.0f32);
            loop {
                if power & 1 != 0 {
                    lobe *= base;
                }
                power >>= 1;
                if power == 0 {
                    break lobe;
                }
                base *= base;
            }
        } else {
            alignment.powf(n)
        }
    }

    /// The colour multiplying a highlight's lobe (before the light's colour), given the base
    /// colour at the hit.
    #[inline]
    pub fn highlight_color(&self, base: Vec3) -> Vec3 {
        Vec3::ONE.lerp(base, self.specular_tint) * self.specular
    }

    /// The Fresnel reflectance at normal incidence of a [`SpecularModel::Ggx`] material, given the
    /// base colour: glTF's F₀ = mix(`specular`, base, `specular_tint`), 4% for a dielectric and
    /// the base colour for a metal when `specular` is 0.04 and the tint the metalness.
    #[inline]
    pub fn fresnel_f0(&self, base: Vec3) -> Vec3 {
        Vec3::splat(self.specular).lerp(base, self.specular_tint)
    }

    /// The colour multiplying mirror reflections, given the base colour at the hit.
    #[inline]
    pub fn reflection_color(&self, base: Vec3) -> Vec3 {
        Vec3::ONE.lerp(base, self.reflection_tint) * self.reflectivity
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            texture: Texture::Constant(Vec3::splat(0.8)),
            ambient: 0.1,
            diffuse: 0.9,
            specular: 0.0,
            shininess: 32.0,
            specular_model: SpecularModel::Phong,
            reflectivity: 0.0,
            reflection_tint: 0.0,
            specular_tint: 0.0,
            emission: None,
            roughness: 0.0,
            transmission: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec4};

    /// The inlined powering gives `powi`'s bits: every whole exponent up to 1024, at
    /// alignments across (0, 1].
    #[test]
    fn specular_lobe_is_powi_bit_for_bit() {
        for n in 0..=1024u16 {
            let m = Material {
                shininess: f32::from(n),
                ..Material::default()
            };
            for k in 1..=64u16 {
                let a = f32::from(k) / 64.0 - f32::from(n % 7) * 1e-4;
                assert_eq!(
                    m.specular_lobe(a).to_bits(),
                    a.powi(i32::from(n)).to_bits(),
                    "{a}^{n}"
                );
            }
        }
    }

    #[test]
    fn specular_lobe_matches_powf() {
        for shininess in [0.0f32, 1.0, 7.0, 32.0, 100.0, 1024.0, 2.5, 2000.0] {
            let m = Material {
                shininess,
                ..Material::default()
            };
            for a in [1.0f32, 0.999, 0.9, 0.5, 0.01] {
                let (got, want) = (m.specular_lobe(a), a.powf(shininess));
                assert!(
                    (got - want).abs() <= want * 1e-5 + 1e-30,
                    "{shininess} {a}: {got} {want}"
                );
            }
        }
    }

    #[test]
    fn vertex_colour_multiplies_base_and_tint_blends_reflection() {
        let m = Material {
            texture: Texture::Constant(Vec3::new(0.5, 1.0, 1.0)),
            reflectivity: 0.5,
            reflection_tint: 1.0,
            ..Material::default()
        };
        let p = TexturePoint {
            local: DVec3::ZERO,
            height: 0.0,
        };
        let a = VertexAttributes {
            color: Vec4::new(1.0, 0.5, 1.0, 1.0),
            ..VertexAttributes::default()
        };
        let base = m.base_color(|_| (p, TextureExtent::POINT), &a);
        assert_eq!(base, Vec3::new(0.5, 0.5, 1.0));
        assert_eq!(m.reflection_color(base), Vec3::new(0.25, 0.25, 0.5));
        let coating = Material {
            reflection_tint: 0.0,
            ..m.clone()
        };
        assert_eq!(coating.reflection_color(base), Vec3::splat(0.5));
        let metal = Material {
            specular: 0.5,
            specular_tint: 1.0,
            ..m
        };
        assert_eq!(metal.highlight_color(base), Vec3::new(0.25, 0.25, 0.5));
        assert_eq!(coating.highlight_color(base), Vec3::ZERO);
    }
}
