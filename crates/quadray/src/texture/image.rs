//! Image textures: 8-bit RGBA texels looked up by texture coordinates, with per-axis wrap modes
//! and bilinear or nearest filtering.
//!
//! # Conventions
//! - Texture coordinates follow glTF: (0, 0) is the top-left corner of the image, u grows to the
//!   right and v downwards; texel (i, j) covers [i, i+1]/width × [j, j+1]/height, so its centre
//!   is at ((i + ½)/width, (j + ½)/height). OBJ's v runs upwards; the OBJ loader flips it.
//! - Texels are kept as the 8-bit codes of the file (4 bytes a texel, whatever the source format),
//!   and colour channels of sRGB-encoded images are decoded to linear through a 256-entry table
//!   at lookup time. Filtering blends the *decoded* linear values, so a bilinear blend between a
//!   black and a white texel is linear mid-grey, as physically correct filtering demands.
//! - Alpha is always linear (glTF and PNG store it linearly).
//! - No mipmaps: minified textures alias. Whitted renders with one or a few samples per pixel, and
//!   the textures quadray meets (glTF base colours) are seldom minified strongly.

use crate::colour::decode_srgb8;
use crate::texture::VertexAttributes;
use glam::{Vec2, Vec4};
use std::fmt;
use std::sync::{Arc, LazyLock};

/// How texture coordinates outside [0, 1] map onto the image, per axis (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The image tiles the plane (glTF REPEAT, the default).
    #[default]
    Repeat,
    /// The image tiles with every other copy mirrored (glTF MIRRORED_REPEAT).
    MirroredRepeat,
    /// Coordinates are clamped to the edge texels (glTF CLAMP_TO_EDGE).
    ClampToEdge,
}

impl Wrap {
    /// The texel index that integer texel coordinate `i` refers to in an axis of `n` texels.
    #[inline]
    fn texel(self, i: i64, n: i64) -> usize {
        let k = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::ClampToEdge => i.clamp(0, n - 1),
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        k as usize
    }
}

/// How texels are combined at a lookup.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// The texel containing the point (glTF magFilter NEAREST).
    Nearest,
    /// Bilinear blend of the four nearest texel centres, in linear colour (the default).
    #[default]
    Bilinear,
}

/// How an image's colour channels are encoded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorEncoding {
    /// sRGB transfer function (base colour textures, ordinary PNG/JPEG files).
    #[default]
    Srgb,
    /// Already linear (data textures).
    Linear,
}

/// Why image data cannot make an [`Image`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// Width or height is zero or beyond [`MAX_IMAGE_SIDE`].
    #[error("image size {width}x{height} is outside 1..={MAX_IMAGE_SIDE} per side")]
    Size {
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
    },
    /// The pixel buffer does not hold width × height RGBA texels.
    #[error("image of {width}x{height} texels needs {expected} bytes of RGBA, got {actual}")]
    Length {
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
        /// Bytes needed.
        expected: usize,
        /// Bytes given.
        actual: usize,
    },
}

/// Largest image side accepted (32768 texels: a 4 GiB RGBA image at most).
pub const MAX_IMAGE_SIDE: u32 = 32768;

/// An 8-bit RGBA image, row-major from the top-left texel.
#[derive(Clone, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
    encoding: ColorEncoding,
}

impl fmt::Debug for Image {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Image")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("encoding", &self.encoding)
            .finish_non_exhaustive()
    }
}

/// Linear values of the 256 sRGB codes, so a lookup costs a table read instead of a `powf`.
static SRGB_TO_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|c| decode_srgb8(c as u8)));

impl Image {
    /// An image from tightly packed RGBA bytes (4 a texel, row-major from the top-left).
    pub fn from_rgba8(
        width: u32,
        height: u32,
        rgba: Vec<u8>,
        encoding: ColorEncoding,
    ) -> Result<Image, ImageError> {
        if !(1..=MAX_IMAGE_SIDE).contains(&width) || !(1..=MAX_IMAGE_SIDE).contains(&height) {
            return Err(ImageError::Size { width, height });
        }
        let expected = width as usize * height as usize * 4;
        if rgba.len() != expected {
            return Err(ImageError::Length {
                width,
                height,
                expected,
                actual: rgba.len(),
            });
        }
        let texels = rgba
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        Ok(Image {
            width,
            height,
            texels,
            encoding,
        })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// How the colour channels are encoded.
    pub fn encoding(&self) -> ColorEncoding {
        self.encoding
    }

    /// The texels as stored: 8-bit RGBA codes, row-major from the top-left (for writing the image
    /// back out losslessly).
    pub fn texels(&self) -> &[[u8; 4]] {
        &self.texels
    }

    /// Bytes of texel memory the image holds.
    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * 4
    }

    /// Texel (x, y) as linear RGBA.
    #[inline]
    pub fn texel(&self, x: usize, y: usize) -> Vec4 {
        let [r, g, b, a] = self.texels[y * self.width as usize + x];
        let alpha = a as f32 / 255.0;
        match self.encoding {
            ColorEncoding::Srgb => {
                let lut = &*SRGB_TO_LINEAR;
                Vec4::new(lut[r as usize], lut[g as usize], lut[b as usize], alpha)
            }
            ColorEncoding::Linear => {
                Vec4::new(r as f32 / 255.0, g as f32 / 255.0, b as f32 / 255.0, alpha)
            }
        }
    }

    /// Linear RGBA at texture coordinates `uv` with the given wrap modes and filter.
    #[inline]
    pub fn sample(&self, uv: Vec2, wrap: [Wrap; 2], filter: Filter) -> Vec4 {
        let (w, h) = (self.width as i64, self.height as i64);
        // Clamp to a range where texel arithmetic cannot overflow, and read NaN as 0.
        let texel_space = |c: f32, n: u32| {
            let x = c * n as f32;
            if x.is_nan() { 0.0 } else { x.clamp(-1e9, 1e9) }
        };
        let x = texel_space(uv.x, self.width);
        let y = texel_space(uv.y, self.height);
        match filter {
            Filter::Nearest => {
                let i = wrap[0].texel(x.floor() as i64, w);
                let j = wrap[1].texel(y.floor() as i64, h);
                self.texel(i, j)
            }
            Filter::Bilinear => {
                // Texel centres sit at half-integers: shift so that floor() finds the lower-left centre.
                let (x, y) = (x - 0.5, y - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let (i0, i1) = (wrap[0].texel(x0, w), wrap[0].texel(x0 + 1, w));
                let (j0, j1) = (wrap[1].texel(y0, h), wrap[1].texel(y0 + 1, h));
                let top = self.texel(i0, j0).lerp(self.texel(i1, j0), fx);
                let bottom = self.texel(i0, j1).lerp(self.texel(i1, j1), fx);
                top.lerp(bottom, fy)
            }
        }
    }
}

/// Which of a mesh's texture coordinate sets a texture reads (glTF TEXCOORD_0 or TEXCOORD_1).
pub type TexCoordSet = u8;

/// An image placed on a surface: the image, how it is sampled, and which coordinate set it reads.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageMap {
    /// The texels (shared: many materials may use one image).
    pub image: Arc<Image>,
    /// Wrap mode along u and along v.
    pub wrap: [Wrap; 2],
    /// Filter used at lookups.
    pub filter: Filter,
    /// Texture coordinate set, 0 or 1.
    pub set: TexCoordSet,
}

impl ImageMap {
    /// Linear RGBA at the hit described by `attributes`.
    #[inline]
    pub fn sample(&self, attributes: &VertexAttributes) -> Vec4 {
        let uv = attributes.uv[(self.set as usize).min(1)];
        self.image.sample(uv, self.wrap, self.filter)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_by_one(encoding: ColorEncoding) -> Image {
        // Left texel black, right texel white, alpha 0 and 255.
        Image::from_rgba8(2, 1, vec![0, 0, 0, 0, 255, 255, 255, 255], encoding).unwrap()
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(matches!(
            Image::from_rgba8(0, 1, vec![], ColorEncoding::Srgb),
            Err(ImageError::Size { .. })
        ));
        assert!(matches!(
            Image::from_rgba8(2, 2, vec![0; 15], ColorEncoding::Srgb),
            Err(ImageError::Length { expected: 16, .. })
        ));
    }

    #[test]
    fn srgb_texels_decode_to_linear() {
        let img = Image::from_rgba8(1, 1, vec![188, 0, 255, 128], ColorEncoding::Srgb).unwrap();
        let t = img.texel(0, 0);
        // sRGB code 188 is linear 0.5 (to 8-bit precision); alpha is linear.
        assert!((t.x - 0.5).abs() < 0.003, "{t}");
        assert_eq!((t.y, t.z), (0.0, 1.0));
        assert!((t.w - 128.0 / 255.0).abs() < 1e-6);
        let lin = Image::from_rgba8(1, 1, vec![188, 0, 0, 0], ColorEncoding::Linear).unwrap();
        assert!((lin.texel(0, 0).x - 188.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn bilinear_blends_in_linear_space_between_texel_centres() {
        let img = two_by_one(ColorEncoding::Srgb);
        let at = |u: f32| img.sample(Vec2::new(u, 0.5), [Wrap::ClampToEdge; 2], Filter::Bilinear);
        // Texel centres at u = 0.25 and 0.75 give the texels exactly.
        assert_eq!(at(0.25), Vec4::ZERO);
        assert_eq!(at(0.75), Vec4::ONE);
        // Halfway between them: linear mid-grey (not sRGB mid-grey), and half alpha.
        assert!((at(0.5) - Vec4::splat(0.5)).abs().max_element() < 1e-6);
        // Clamped beyond the edges.
        assert_eq!(at(-3.0), Vec4::ZERO);
        assert_eq!(at(7.0), Vec4::ONE);
    }

    #[test]
    fn wrap_modes_follow_gltf() {
        let img = two_by_one(ColorEncoding::Linear);
        let at = |u: f32, wrap: Wrap| img.sample(Vec2::new(u, 0.0), [wrap; 2], Filter::Nearest).x;
        // Repeat: u = 1.1 is u = 0.1 (left, black); u = -0.1 is 0.9 (right, white).
        assert_eq!(at(1.1, Wrap::Repeat), 0.0);
        assert_eq!(at(-0.1, Wrap::Repeat), 1.0);
        // Mirrored: u = 1.1 mirrors to 0.9 (white); u = 2.1 is 0.1 again (black).
        assert_eq!(at(1.1, Wrap::MirroredRepeat), 1.0);
        assert_eq!(at(2.1, Wrap::MirroredRepeat), 0.0);
        assert_eq!(at(-0.1, Wrap::MirroredRepeat), 0.0);
        // Clamp: far right stays white, far left black.
        assert_eq!(at(5.0, Wrap::ClampToEdge), 1.0);
        assert_eq!(at(-5.0, Wrap::ClampToEdge), 0.0);
        // Absurd coordinates neither panic nor leave the image.
        for u in [f32::NAN, f32::INFINITY, -f32::INFINITY, 1e30] {
            for w in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
                let v = img.sample(Vec2::splat(u), [w; 2], Filter::Bilinear);
                assert!(v.is_finite());
            }
        }
    }

    #[test]
    fn image_map_reads_its_coordinate_set() {
        let map = ImageMap {
            image: Arc::new(two_by_one(ColorEncoding::Linear)),
            wrap: [Wrap::ClampToEdge; 2],
            filter: Filter::Nearest,
            set: 1,
        };
        let attrs = VertexAttributes {
            uv: [Vec2::new(0.9, 0.0), Vec2::new(0.1, 0.0)],
            color: Vec4::ONE,
        };
        assert_eq!(map.sample(&attrs).x, 0.0);
    }
}
