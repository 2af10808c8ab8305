//! The film: a linear f32 RGB image, and its sRGB encoding for 8-bit outputs.

use glam::Vec3;

/// A linear, scene-referred RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
}

impl Film {
    /// A black film.
    pub fn new(width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// Wraps existing pixels; `None` if the count does not match.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Vec3>) -> Option<Film> {
        (pixels.len() == width as usize * height as usize).then_some(Film {
            width,
            height,
            pixels,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major.
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }

    /// Mutable pixels, row-major.
    pub fn pixels_mut(&mut self) -> &mut [Vec3] {
        &mut self.pixels
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// 8-bit sRGB bytes (RGB, row-major), clamped to [0, 1] before encoding.
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array().map(encode_srgb8))
            .collect()
    }
}

/// The sRGB transfer function (IEC 61966-2-1) applied to a clamped linear value, as an 8-bit code.
pub fn encode_srgb8(linear: f32) -> u8 {
    (encode_srgb(linear) * 255.0 + 0.5) as u8
}

/// The sRGB transfer function applied to a linear value clamped to [0, 1] (NaN as 0), unquantised.
pub fn encode_srgb(linear: f32) -> f32 {
    let v = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`encode_srgb8`]: an 8-bit sRGB code to linear.
pub fn decode_srgb8(code: u8) -> f32 {
    let e = code as f32 / 255.0;
    if e <= 0.04045 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_and_clamps() {
        for code in 0..=255u8 {
            assert_eq!(encode_srgb8(decode_srgb8(code)), code);
        }
        assert_eq!(encode_srgb8(7.0), 255);
        assert_eq!(encode_srgb8(-1.0), 0);
        assert_eq!(encode_srgb8(0.5), 188);
    }
}
