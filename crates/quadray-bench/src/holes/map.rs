//! Hole maps as images and the counts as a table.

use super::{OraclePixel, PixelClass, SceneHoles};
use std::fmt::Write as _;

/// Colour of a miss that agrees with the oracle.
pub const BACKGROUND: [u8; 3] = [28, 28, 34];
/// Colour of a hole (the oracle hits, the variant misses).
pub const HOLE: [u8; 3] = [235, 30, 30];
/// Colour of a phantom (the variant hits, the oracle misses).
pub const PHANTOM: [u8; 3] = [40, 110, 255];
/// Colour of a wrong object (both hit, different objects).
pub const WRONG_OBJECT: [u8; 3] = [255, 170, 0];
/// Colour of an ambiguous pixel (within the oracle's margin), whatever the variant says.
pub const AMBIGUOUS: [u8; 3] = [0, 230, 230];

/// Muted grey-green tones for objects hit in agreement with the oracle, by quadric index.
pub(super) fn object_colour(i: u32) -> [u8; 3] {
    const TONES: [[u8; 3]; 6] = [
        [150, 150, 150],
        [120, 135, 120],
        [175, 170, 155],
        [105, 115, 135],
        [160, 140, 150],
        [135, 160, 160],
    ];
    TONES[i as usize % TONES.len()]
}

/// The hole map as 8-bit RGB (row-major): agreeing pixels in their object's muted tone (dark where
/// both miss), differing ones in [`HOLE`], [`PHANTOM`] or [`WRONG_OBJECT`], ambiguous ones in
/// [`AMBIGUOUS`]. With `got` = `None`, the oracle's own map (objects and ambiguous pixels).
pub fn hole_map_rgb8(oracle: &[OraclePixel], got: Option<&[Option<u32>]>) -> Vec<u8> {
    oracle
        .iter()
        .enumerate()
        .flat_map(|(i, o)| {
            let answer = got.map_or(o.object, |g| g[i]);
            if o.ambiguous {
                return AMBIGUOUS;
            }
            match PixelClass::of(o.object, answer) {
                PixelClass::Agrees => o.object.map_or(BACKGROUND, object_colour),
                PixelClass::Hole => HOLE,
                PixelClass::Phantom => PHANTOM,
                PixelClass::WrongObject => WRONG_OBJECT,
            }
        })
        .collect()
}

/// The counts of every scene and variant as a markdown table.
pub fn markdown(scenes: &[SceneHoles]) -> String {
    let mut s = String::new();
    s.push_str("| scene | variant | pixels | oracle hits | differing | holes | phantoms | wrong object | ambiguous | ambiguous and differing |\n");
    s.push_str("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for sc in scenes {
        for (v, _, c) in &sc.variants {
            let _ = writeln!(
                s,
                "| {} ({}x{}) | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                sc.name,
                sc.width,
                sc.height,
                v.name(),
                c.pixels,
                c.oracle_hits,
                c.differing(),
                c.holes,
                c.phantoms,
                c.wrong_object,
                c.ambiguous,
                c.ambiguous_differing
            );
        }
    }
    s
}
