//! Textures: the seed's height ramp, contour bands and checkerboard, constant colour, and images.

mod checker;
pub mod image;

use checker::filtered_checker;
use glam::{DVec3, Vec2, Vec3, Vec4};
use image::ImageMap;

/// Where a texture is evaluated: the hit in the object's own frame and its normalised height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturePoint {
    /// The hit point in the object's frame (for a plane: its 2-D frame with z = 0).
    pub local: DVec3,
    /// Height of the hit within the object's clipped height range, 0 at the bottom, 1 at the top.
    pub height: f32,
}

/// How far around a [`TexturePoint`] a sample's footprint reaches: half-widths of the box, in
/// the same coordinates, over which a filtered texture averages.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureExtent {
    /// Half-widths along the object frame's axes.
    pub local: DVec3,
    /// Half-width in normalised height.
    pub height: f32,
}

impl TextureExtent {
    /// No extent: the texture is point sampled.
    pub const POINT: TextureExtent = TextureExtent {
        local: DVec3::ZERO,
        height: 0.0,
    };

    /// The box that holds a footprint whose two axes change the texture coordinates by
    /// `along_x` and `along_y`: half the sum of the axes' absolute changes, per coordinate.
    pub fn spanned(along_x: &TexturePoint, along_y: &TexturePoint) -> Self {
        TextureExtent {
            local: 0.5 * (along_x.local.abs() + along_y.local.abs()),
            height: 0.5 * (along_x.height.abs() + along_y.height.abs()),
        }
    }
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

/// The band (0 to `steps` − 1) holding height `h`: band k covers [k/n, (k+1)/n), heights below 0
/// fall in the first and the top edge and above in the last.
fn band_of(h: f32, steps: u32) -> u32 {
    let n = steps.max(1) as f32;
    (h.clamp(0.0, 1.0) * n).floor().min(n - 1.0) as u32
}

/// The colour of band `k` of `steps`: the ramp at the band's place in the sequence.
fn band_colour(k: u32, steps: u32) -> Vec3 {
    if steps <= 1 {
        height_ramp(0.5)
    } else {
        height_ramp(k as f32 / (steps - 1) as f32)
    }
}

/// Beyond this many bands under one footprint, the bands average as the ramp they step through.
const MAX_SUMMED_BANDS: u32 = 64;

/// The mean band colour over heights [h − w, h + w]: each band's colour weighted by its overlap
/// (the clamped ends included), or the ramp's mean where the footprint covers too many bands for
/// their steps to matter. Out of line, as [`filtered_checker`].
#[inline(never)]
fn filtered_bands(h: f32, w: f32, steps: u32) -> Vec3 {
    let steps = steps.max(1);
    let (lo, hi) = (h - w, h + w);
    // A footprint too thin to widen the height in f32 is a point sample.
    if hi.is_nan() || hi <= lo {
        return band_colour(band_of(h, steps), steps);
    }
    let (first, last) = (band_of(lo, steps), band_of(hi, steps));
    if last - first > MAX_SUMMED_BANDS {
        return (ramp_integral(hi) - ramp_integral(lo)) / (hi - lo);
    }
    let n = steps as f32;
    let mut sum = Vec3::ZERO;
    for k in first..=last {
        // Band k's interval, opened out to ±∞ at the ends where the clamp extends it.
        let start = if k == 0 { lo } else { (k as f32 / n).max(lo) };
        let end = if k + 1 == steps {
            hi
        } else {
            ((k + 1) as f32 / n).min(hi)
        };
        if end > start {
            sum += band_colour(k, steps) * (end - start);
        }
    }
    sum / (hi - lo)
}

/// ∫₀ʰ of the clamped height ramp: the ramp is linear on [0, ½] and [½, 1] and constant outside.
fn ramp_integral(h: f32) -> Vec3 {
    // ∫₀ˣ (R₀ + (R₁ − R₀)·2s) ds = R₀x + (R₁ − R₀)x² on each linear half.
    let half = |x: f32, from: Vec3, to: Vec3| from * x + (to - from) * (x * x);
    let at_half = half(0.5, RAMP[0], RAMP[1]);
    let at_one = at_half + half(0.5, RAMP[1], RAMP[2]);
    if h <= 0.0 {
        RAMP[0] * h
    } else if h <= 0.5 {
        half(h, RAMP[0], RAMP[1])
    } else if h <= 1.0 {
        at_half + half(h - 0.5, RAMP[1], RAMP[2])
    } else {
        at_one + RAMP[2] * (h - 1.0)
    }
}

impl Texture {
    /// The colour at `p`, averaged over `extent` around it (a point sample when the extent is
    /// zero), whose interpolated vertex attributes are `attributes`.
    #[inline]
    pub fn eval(
        &self,
        p: &TexturePoint,
        extent: &TextureExtent,
        attributes: &VertexAttributes,
    ) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::HeightRamp => height_ramp(p.height),
            Texture::Bands { steps } if extent.height > 0.0 => {
                filtered_bands(p.height, extent.height, *steps)
            }
            Texture::Bands { steps } => band_colour(band_of(p.height, *steps), *steps),
            Texture::Checker { size, even, odd } if extent.local != DVec3::ZERO => {
                filtered_checker(p.local / *size, extent.local / *size, *even, *odd)
            }
            Texture::Checker { size, even, odd } => {
                // Integer parity of the cell (the float fmod of rem_euclid showed up in profiles).
                let q = (p.local / *size).to_array().map(crate::math::floor);
                let parity = (q[0] as i64)
                    .wrapping_add(q[1] as i64)
                    .wrapping_add(q[2] as i64)
                    & 1;
                if parity == 0 { *even } else { *odd }
            }
            Texture::Image(t) => t.map.sample(attributes).truncate() * t.factor,
        }
    }

    /// The colour at a hit whose interpolated vertex attributes are `attributes`. `point` is asked
    /// only by the procedural textures that read it: `point(filtered)` gives the texture point,
    /// and when `filtered` also the extent of the sample's footprint around it.
    #[inline]
    pub fn eval_at(
        &self,
        point: impl FnOnce(bool) -> (TexturePoint, TextureExtent),
        attributes: &VertexAttributes,
    ) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image(t) => t.map.sample(attributes).truncate() * t.factor,
            Texture::HeightRamp => height_ramp(point(false).0.height),
            Texture::Bands { .. } | Texture::Checker { .. } => {
                let (p, extent) = point(true);
                self.eval(&p, &extent, attributes)
            }
        }
    }

    /// Whether the texture averages over a footprint (the ones with hard edges: bands and
    /// checker; the ramp is smooth and images have their own filters).
    pub fn is_filtered(&self) -> bool {
        matches!(self, Texture::Bands { .. } | Texture::Checker { .. })
    }

    /// Whether the colour reads the hit's texture coordinates (only images do).
    pub fn reads_texcoords(&self) -> bool {
        matches!(self, Texture::Image(_))
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
        t.eval(p, &TextureExtent::POINT, &VertexAttributes::default())
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

    /// The mean of the point-sampled texture over the extent's box, by the midpoint rule on a
    /// fine grid (the axes with no extent are not sampled).
    fn brute_mean(t: &Texture, p: &TexturePoint, e: &TextureExtent) -> Vec3 {
        const N: usize = 200;
        let offset = |i: usize, w: f64| w * (2.0 * (i as f64 + 0.5) / N as f64 - 1.0);
        let mut sum = Vec3::ZERO;
        for i in 0..N {
            for j in 0..N {
                let local = p.local + DVec3::new(offset(i, e.local.x), offset(j, e.local.y), 0.0);
                let height = p.height + offset(i, e.height as f64) as f32;
                sum += eval(t, &TexturePoint { local, height });
            }
        }
        sum / (N * N) as f32
    }

    #[test]
    fn filtered_checker_is_the_mean_over_the_footprint() {
        let t = Texture::Checker {
            size: 0.5,
            even: Vec3::new(0.9, 0.1, 0.2),
            odd: Vec3::new(0.1, 0.3, 0.8),
        };
        for (x, y, wx, wy) in [
            (0.2, 0.3, 0.1, 0.05),
            (0.49, -0.02, 0.3, 0.3),
            (-3.7, 12.1, 0.02, 1.7),
            (100.26, -7.5, 5.0, 0.01),
        ] {
            let p = TexturePoint {
                local: DVec3::new(x, y, 0.1),
                height: 0.0,
            };
            let e = TextureExtent {
                local: DVec3::new(wx, wy, 0.0),
                height: 0.0,
            };
            let filtered = t.eval(&p, &e, &VertexAttributes::default());
            let brute = brute_mean(&t, &p, &e);
            assert!(
                (filtered - brute).abs().max_element() < 0.01,
                "({x}, {y}) ± ({wx}, {wy}): {filtered} against {brute}"
            );
        }
        // Far wider than a cell, the checker averages to the mean of its two colours.
        let wide = TextureExtent {
            local: DVec3::new(1000.0, 1000.0, 0.0),
            height: 0.0,
        };
        let p = at(0.0);
        let mean = t.eval(&p, &wide, &VertexAttributes::default());
        assert!((mean - Vec3::new(0.5, 0.2, 0.5)).abs().max_element() < 1e-3);
    }

    #[test]
    fn filtered_bands_are_the_mean_over_the_footprint() {
        let t = Texture::Bands { steps: 8 };
        for (h, w) in [
            (0.5, 0.01),
            (0.3, 0.2),
            (0.02, 0.1),
            (0.97, 0.3),
            (-0.5, 0.2),
            (0.5, 2.0),
        ] {
            let p = at(h);
            let e = TextureExtent {
                local: DVec3::ZERO,
                height: w,
            };
            let filtered = t.eval(&p, &e, &VertexAttributes::default());
            let brute = brute_mean(&t, &p, &e);
            assert!(
                (filtered - brute).abs().max_element() < 0.01,
                "{h} ± {w}: {filtered} against {brute}"
            );
        }
        // Inside one band the filter changes nothing.
        let inside = TextureExtent {
            local: DVec3::ZERO,
            height: 0.01,
        };
        assert_eq!(
            t.eval(&at(0.3), &inside, &VertexAttributes::default()),
            eval(&t, &at(0.3))
        );
        // A footprint over thousands of bands averages as the ramp itself.
        let fine = Texture::Bands { steps: 100_000 };
        let e = TextureExtent {
            local: DVec3::ZERO,
            height: 0.25,
        };
        let filtered = fine.eval(&at(0.5), &e, &VertexAttributes::default());
        let ramp = brute_mean(&Texture::HeightRamp, &at(0.5), &e);
        assert!(
            (filtered - ramp).abs().max_element() < 1e-3,
            "{filtered} against {ramp}"
        );
    }

    #[test]
    fn a_point_extent_is_the_point_sample() {
        let t = Texture::Checker {
            size: 1.0,
            even: Vec3::ZERO,
            odd: Vec3::ONE,
        };
        let p = TexturePoint {
            local: DVec3::new(0.5, 1.5, 0.0),
            height: 0.4,
        };
        assert_eq!(
            t.eval(&p, &TextureExtent::POINT, &VertexAttributes::default()),
            Vec3::ONE
        );
    }

    #[test]
    fn image_texture_reads_uv_and_scales_by_factor() {
        use crate::texture::image::{ColorEncoding, Filter, Image, Wrap};
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
        assert_eq!(
            t.eval(&at(0.0), &TextureExtent::POINT, &with_uv(0.2)),
            Vec3::new(1.0, 0.5, 0.25)
        );
        assert_eq!(
            t.eval(&at(0.0), &TextureExtent::POINT, &with_uv(0.7)),
            Vec3::ZERO
        );
        assert!(!t.is_constant());
    }
}
