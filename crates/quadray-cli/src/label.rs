//! Text drawn into 8-bit images with the public-domain 8×8 bitmap font of the `font8x8` crate, so
//! labels need no system fonts and look the same everywhere.

use font8x8::legacy::{BASIC_LEGACY, LATIN_LEGACY};

/// An 8-bit RGB image being labelled, row-major.
pub struct Canvas<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGB bytes, 3 per pixel.
    pub bytes: &'a mut [u8],
}

/// The 8×8 glyph of `ch`: ASCII and Latin-1 (which has ² and ³); the minus sign U+2212 is drawn
/// as a hyphen; anything else as `?`.
fn glyph(ch: char) -> [u8; 8] {
    let ch = if ch == '−' { '-' } else { ch };
    match ch as u32 {
        c @ 0..=0x7f => BASIC_LEGACY[c as usize],
        c @ 0xa0..=0xff => LATIN_LEGACY[(c - 0xa0) as usize],
        _ => BASIC_LEGACY[b'?' as usize],
    }
}

/// Width in pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * 8 * scale
}

impl Canvas<'_> {
    /// Draws `text` with its top-left corner at (x, y), each font pixel a `scale`×`scale` block
    /// of `colour`; whatever falls outside the image is cut off.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: u32, colour: [u8; 3]) {
        let s = scale as i64;
        for (i, ch) in text.chars().enumerate() {
            let rows = glyph(ch);
            let gx = x + i as i64 * 8 * s;
            for (row, bits) in rows.iter().enumerate() {
                for col in 0..8 {
                    // Bit 0 is the leftmost pixel of the row.
                    if bits & (1 << col) != 0 {
                        self.block(gx + col * s, y + row as i64 * s, s, colour);
                    }
                }
            }
        }
    }

    /// Draws `text` centred horizontally on column `cx`.
    pub fn text_centred(&mut self, cx: i64, y: i64, text: &str, scale: u32, colour: [u8; 3]) {
        let x = cx - text_width(text, scale) as i64 / 2;
        self.text(x, y, text, scale, colour);
    }

    /// Fills the rectangle [x, x + w) × [y, y + h) with `colour`, clipped to the image.
    pub fn fill(&mut self, x: i64, y: i64, w: i64, h: i64, colour: [u8; 3]) {
        let (x0, y0) = (x.max(0), y.max(0));
        let x1 = (x + w).min(self.width as i64);
        let y1 = (y + h).min(self.height as i64);
        for py in y0..y1 {
            for px in x0..x1 {
                let i = 3 * (py as usize * self.width as usize + px as usize);
                self.bytes[i..i + 3].copy_from_slice(&colour);
            }
        }
    }

    fn block(&mut self, x: i64, y: i64, s: i64, colour: [u8; 3]) {
        self.fill(x, y, s, s, colour);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn letters_draw_their_glyph_and_clip_at_the_edges() {
        let mut bytes = vec![0u8; 3 * 20 * 10];
        let mut c = Canvas {
            width: 20,
            height: 10,
            bytes: &mut bytes,
        };
        c.text(0, 0, "I", 1, [255, 255, 255]);
        // The 8x8 'I' has a horizontal bar on its top row.
        let lit = |b: &[u8], x: usize, y: usize| b[3 * (y * 20 + x)] == 255;
        assert!((1..5).any(|x| lit(&bytes, x, 0)));
        let mut c = Canvas {
            width: 20,
            height: 10,
            bytes: &mut bytes,
        };
        // Off-image text does not panic.
        c.text(15, 5, "x²−y²", 3, [9, 9, 9]);
        c.text(-100, -100, "?", 2, [9, 9, 9]);
        assert_eq!(text_width("x²", 2), 32);
        assert_ne!(glyph('²'), glyph('?'));
        assert_eq!(glyph('−'), glyph('-'));
    }
}
