//! Procedural textures: the seed's height ramp, contour bands and checkerboard, plus constant colour.

use glam::{DVec3, Vec3};

/// Where a texture is evaluated: the hit in the object's own frame and its normalised height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturePoint {
    /// The hit point in the object's frame (for a plane: its 2-D frame with z = 0).
    pub local: DVec3,
    /// Height of the hit within the object's clipped height range, 0 at the bottom, 1 at the top.
    pub height: f32,
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
    /// The colour at `p`.
    #[inline]
    pub fn eval(&self, p: &TexturePoint) -> Vec3 {
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
        }
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

    #[test]
    fn ramp_runs_blue_green_yellow() {
        assert_eq!(Texture::HeightRamp.eval(&at(0.0)), RAMP[0]);
        assert_eq!(Texture::HeightRamp.eval(&at(0.5)), RAMP[1]);
        assert_eq!(Texture::HeightRamp.eval(&at(1.0)), RAMP[2]);
        assert_eq!(Texture::HeightRamp.eval(&at(7.0)), RAMP[2]);
    }

    #[test]
    fn bands_are_flat_and_span_the_ramp() {
        let t = Texture::Bands { steps: 4 };
        assert_eq!(t.eval(&at(0.01)), t.eval(&at(0.24)));
        assert_ne!(t.eval(&at(0.24)), t.eval(&at(0.26)));
        assert_eq!(t.eval(&at(0.0)), RAMP[0]);
        assert_eq!(t.eval(&at(1.0)), RAMP[2]);
    }

    #[test]
    fn checker_alternates_across_cells() {
        let t = Texture::Checker {
            size: 0.5,
            even: Vec3::ZERO,
            odd: Vec3::ONE,
        };
        let c = |x, y, z| {
            t.eval(&TexturePoint {
                local: DVec3::new(x, y, z),
                height: 0.0,
            })
        };
        assert_eq!(c(0.1, 0.1, 0.1), Vec3::ZERO);
        assert_eq!(c(0.6, 0.1, 0.1), Vec3::ONE);
        assert_eq!(c(-0.1, 0.1, 0.1), Vec3::ONE);
        assert_eq!(c(0.6, 0.6, 0.1), Vec3::ZERO);
    }
}
