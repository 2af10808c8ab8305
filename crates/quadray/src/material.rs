//! The Whitted material: ambient, Lambert diffuse, Phong or Blinn specular, mirror reflection.

use crate::texture::Texture;

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
}

/// A surface's response to light, Whitted style.
///
/// Radiance leaving a point is `(1 − reflectivity)·(ambient + diffuse)·base + specular·highlight +
/// reflectivity·(radiance from the mirror direction)`: a perfect mirror (reflectivity 1) shows
/// no diffuse colour but keeps its highlights, like a coated surface.
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
}

impl Default for Material {
    fn default() -> Self {
        Material {
            texture: Texture::Constant(glam::Vec3::splat(0.8)),
            ambient: 0.1,
            diffuse: 0.9,
            specular: 0.0,
            shininess: 32.0,
            specular_model: SpecularModel::Phong,
            reflectivity: 0.0,
        }
    }
}
