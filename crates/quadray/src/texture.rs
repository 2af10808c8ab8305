//! Textures: the seed's height ramp, contour bands and checkerboard, constant colour, and images.

use crate::image_texture::ImageMap;
use glam::{DVec3, Vec2, Vec3, Vec4};

/// Where a texture is evaluated: the hit in the object's own frame and its normalised height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturePoint {
    /// The hit point in the object's frame (for a plane: its 2-D frame with z = 0).
    pub local: DVec3,
    /// Height of the hit within the object's clipped height range, 0 at the bottom, 1 at the top.
    pub height: f32,
}

/// Per-vertex data interpolated at a hit: texture coordinates and vertex colour.
///
/// Only meshes carry them; analytic shapes (and meshes without the attribute) use the
/// [`Default`]: coordinates (0, 0) and white, which leaves a base colour unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexAttributes {
    /// Texture coordinate sets 0 and 1 (glTF TEXCOORD_0/1), image convention: v grows downwards.
    pub uv: [Vec2; 2],
    /// Linear RGBA vertex colour (glTF COLOR_0); multiplies the base colour, alpha the coverage.
    pub color: Vec4,
}

impl Default for VertexAttributes {
    fn default() -> Self {
        VertexAttributes {
            uv: [Vec2::ZERO; 2],
            color: Vec4::ONE,
        }
    }
}

/// An image texture: an [`ImageMap`] scaled by a constant colour factor (glTF baseColorFactor).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    /// The image and how it is sampled.
    pub map: ImageMap,
    /// Linear RGB factor multiplying the texels.
    pub factor: Vec3,
}

/// A colour source for a material, matched in one place ([`Texture::eval`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// One colour everywhere (linear RGB).
    Constant(Vec3),
    /// The seed's ramp: blue → green → yellow over the object's clipped height range.
    HeightRamp,
    /// The same ramp quantised into `steps` flat contour bands.
    Bands {
        /// Number of bands (at least 1).
        steps: u32,
    },
    /// A 3-D checkerboard of cubes of edge `size` in the object's frame.
    Checker {
        /// Edge length of one square, in object units.
        size: f64,
        /// Colour of the even squares.
        even: Vec3,
        /// Colour of the odd squares.
        odd: Vec3,
    },
    /// An image looked up by the hit's texture coordinates.
    Image(ImageTexture),
}

/// Ramp stops of the seed: blue at the bottom, green in the middle, yellow at the top (linear RGB).
const RAMP: [Vec3; 3] = [
    Vec3::new(0.05, 0.15, 0.9),
    Vec3::new(0.1, 0.75, 0.15),
    Vec3::new(0.95, 0.85, 0.05),
];

/// The colour of the height ramp at `h` in [0, 1] (clamped).
pub fn height_ramp(h: f32) -> Vec3 {
    let h = if h.is_nan() { 0.0 } else { h.clamp(0.0, 1.0) };
    if h < 0.5 {
        RAMP[0].lerp(RAMP[1], h * 2.0)
    } else {
        RAMP[1].lerp(RAMP[2], (h - 0.5) * 2.0)
    }
}

/// The lighter partner of `c` for a checkerboard that lightens alternate squares: halfway to white.
pub fn lighten(c: Vec3) -> Vec3 {
    c.lerp(Vec3::ONE, 0.5)
}

impl Texture {
    /// The colour at `p`, whose interpolated vertex attributes are `attributes`.
    #[inline]
    pub fn eval(&self, p: &TexturePoint, attributes: &VertexAttributes) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::HeightRamp => height_ramp(p.height),
            Texture::Bands { steps } => {
                let n = (*steps).max(1) as f32;
                // Band k covers [k/n, (k+1)/n) and shows the ramp at its centre; the top edge joins the last band.
                let k = (p.height.clamp(0.0, 1.0) * n).floor().min(n - 1.0);
                height_ramp(if n == 1.0 { 0.5 } else { k / (n - 1.0) })
            }
            Texture::Checker { size, even, odd } => {
                // Integer parity of the cell (the float fmod of rem_euclid showed up in profiles).
                let q = (p.local / *size).floor();
                let parity = (q.x as i64)
                    .wrapping_add(q.y as i64)
                    .wrapping_add(q.z as i64)
                    & 1;
                if parity == 0 { *even } else { *odd }
            }
            Texture::Image(t) => t.map.sample(attributes).truncate() * t.factor,
        }
    }

    /// The colour at a hit whose interpolated vertex attributes are `attributes`; `point` is asked
    /// for only by the procedural textures that read it.
    #[inline]
    pub fn eval_at(
        &self,
        point: impl FnOnce() -> TexturePoint,
        attributes: &VertexAttributes,
    ) -> Vec3 {
        let p = if self.reads_point() {
            point()
        } else {
            TexturePoint {
                local: glam::DVec3::ZERO,
                height: 0.0,
            }
        };
        self.eval(&p, attributes)
    }

    /// Whether the colour depends on the hit's [`TexturePoint`] (the procedural textures do;
    /// constants and images do not).
    pub fn reads_point(&self) -> bool {
        matches!(
            self,
            Texture::HeightRamp | Texture::Bands { .. } | Texture::Checker { .. }
        )
    }

    /// Whether the colour varies over the surface (a constant needs no texture point).
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant(_))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(height: f32) -> TexturePoint {
        TexturePoint {
            local: DVec3::ZERO,
            height,
        }
    }

    /// Evaluates without vertex attributes, as for an analytic shape.
    fn eval(t: &Texture, p: &TexturePoint) -> Vec3 {
        t.eval(p, &VertexAttributes::default())
    }

    #[test]
    fn ramp_runs_blue_green_yellow() {
        assert_eq!(eval(&Texture::HeightRamp, &at(0.0)), RAMP[0]);
        assert_eq!(eval(&Texture::HeightRamp, &at(0.5)), RAMP[1]);
        assert_eq!(eval(&Texture::HeightRamp, &at(1.0)), RAMP[2]);
        assert_eq!(eval(&Texture::HeightRamp, &at(7.0)), RAMP[2]);
    }

    #[test]
    fn bands_are_flat_and_span_the_ramp() {
        let t = Texture::Bands { steps: 4 };
        assert_eq!(eval(&t, &at(0.01)), eval(&t, &at(0.24)));
        assert_ne!(eval(&t, &at(0.24)), eval(&t, &at(0.26)));
        assert_eq!(eval(&t, &at(0.0)), RAMP[0]);
        assert_eq!(eval(&t, &at(1.0)), RAMP[2]);
    }

    #[test]
    fn checker_alternates_across_cells() {
        let t = Texture::Checker {
            size: 0.5,
            even: Vec3::ZERO,
            odd: Vec3::ONE,
        };
        let c = |x, y, z| {
            eval(
                &t,
                &TexturePoint {
                    local: DVec3::new(x, y, z),
                    height: 0.0,
                },
            )
        };
        assert_eq!(c(0.1, 0.1, 0.1), Vec3::ZERO);
        assert_eq!(c(0.6, 0.1, 0.1), Vec3::ONE);
        assert_eq!(c(-0.1, 0.1, 0.1), Vec3::ONE);
        assert_eq!(c(0.6, 0.6, 0.1), Vec3::ZERO);
    }

    #[test]
    fn image_texture_reads_uv_and_scales_by_factor() {
        use crate::image_texture::{ColorEncoding, Filter, Image, Wrap};
        let image = Image::from_rgba8(
            2,
            1,
            vec![255, 255, 255, 255, 0, 0, 0, 255],
            ColorEncoding::Srgb,
        )
        .unwrap();
        let t = Texture::Image(ImageTexture {
            map: ImageMap {
                image: std::sync::Arc::new(image),
                wrap: [Wrap::Repeat; 2],
                filter: Filter::Nearest,
                set: 0,
            },
            factor: Vec3::new(1.0, 0.5, 0.25),
        });
        let with_uv = |u: f32| VertexAttributes {
            uv: [Vec2::new(u, 0.5), Vec2::ZERO],
            color: Vec4::ONE,
        };
        assert_eq!(t.eval(&at(0.0), &with_uv(0.2)), Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(t.eval(&at(0.0), &with_uv(0.7)), Vec3::ZERO);
        assert!(!t.is_constant());
    }
}
