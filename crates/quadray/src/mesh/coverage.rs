//! Partial coverage of a mesh's triangles: cut-outs (glTF MASK) and stochastic coverage (glTF
//! BLEND), tested inside BVH traversal.

use super::Mesh;
use crate::texture::image::ImageMap;
use glam::Vec3;

/// Partial coverage: a cut-out (glTF alpha mode MASK), where hits whose coverage alpha is below
/// `cutoff` are not hits, or stochastic coverage (glTF BLEND), where a hit with alpha a is kept
/// for a share a of rays.
///
/// Alpha at a point = `factor` × the map's alpha × the vertex colour's alpha. The test runs inside
/// BVH traversal, so coverage lets camera, shadow and reflection rays through alike.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMask {
    /// Alpha below this is transparent (glTF alphaCutoff, default 0.5); unused when stochastic.
    pub cutoff: f32,
    /// Whether alpha is a probability instead (glTF BLEND): each ray keeps the hit when alpha
    /// exceeds a value hashed from the ray and the triangle, uniform in [0, 1). Over a pixel's
    /// samples this converges to the blend of the surface over what lies behind, in any order of
    /// layers; at one sample a pixel it dithers.
    pub stochastic: bool,
    /// Constant alpha factor (glTF baseColorFactor's alpha).
    pub factor: f32,
    /// The image whose alpha channel modulates coverage, if any (glTF baseColorTexture).
    pub map: Option<ImageMap>,
}

/// The hash of a ray, from its f32 origin and a direction vector (the BVH passes its reciprocal),
/// that stochastic coverage draws from: the same ray meets the same decision in every query of
/// one kind, different rays independent ones, and the image stays the same for any thread count.
#[inline]
pub(crate) fn coverage_key(origin: Vec3, dir: Vec3) -> u32 {
    [origin.x, origin.y, origin.z, dir.x, dir.y, dir.z]
        .iter()
        .fold(0x2545_F491, |h, c| mix(h ^ c.to_bits()))
}

/// A 32-bit finaliser (the murmur3 mix): every input bit flips each output bit about half the time.
#[inline]
fn mix(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 13;
    h = h.wrapping_mul(0xC2B2_AE35);
    h ^ (h >> 16)
}

impl Mesh {
    /// Whether the mesh's coverage keeps the point at barycentrics `b` of triangle `tri` (true
    /// without a mask); `key` gives the ray's [`coverage_key`] when stochastic coverage needs it.
    #[inline]
    pub(crate) fn covers(&self, tri: u32, b: [f32; 3], key: impl FnOnce() -> u32) -> bool {
        match &self.alpha_mask {
            Some(mask) => self.covered(mask, tri, b, if mask.stochastic { key() } else { 0 }),
            None => true,
        }
    }

    /// Whether the coverage at barycentric coordinates `b` of triangle `tri` keeps the hit of the
    /// ray with [`coverage_key`] `key`.
    #[inline]
    fn covered(&self, mask: &AlphaMask, tri: u32, b: [f32; 3], key: u32) -> bool {
        let mut alpha = mask.factor;
        if mask.map.is_some() || self.colors.is_some() {
            let a = self.attributes_at(tri, b);
            alpha *= a.color.w;
            if let Some(map) = &mask.map {
                alpha *= map.sample(&a).w;
            }
        }
        if mask.stochastic {
            // 24 bits of the hash as a uniform value in [0, 1).
            let u = (mix(key ^ tri.wrapping_mul(0x9E37_79B9)) >> 8) as f32 / (1u32 << 24) as f32;
            alpha > u
        } else {
            alpha >= mask.cutoff
        }
    }
}
