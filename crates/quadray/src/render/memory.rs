//! What a render holds in memory for its pixels at its peak, so that a caller can refuse a render
//! the machine cannot hold before it starts, rather than be killed part way.
//!
//! The figures are peak resident sizes measured on the quadric grid at 3840x2160 (whose scene
//! is a few kilobytes, so the pixels are all of it), divided by the pixels and rounded up:
//! 30 bytes a pixel for a uniform render to EXR (the f32 film and the file's encoding), 127 with
//! every pass, 230 for an adaptive render (each pixel's estimate of 152 bytes and its state
//! through the rounds and the audit) and 306 for an adaptive render with every pass.

use super::{PixelWindow, RenderSettings};
use crate::aov::AovSelection;

/// Bytes a pixel of any render holds: the f32 RGB film and the output's encoding.
const FILM_BYTES: u64 = 32;
/// Bytes a pixel's passes add, when any is selected: its pass sample and their output.
const PASS_BYTES: u64 = 96;
/// Bytes an adaptive render adds to a pixel: its estimate ([`crate::film::PixelEstimate`]), its
/// rays, errors, target and pilot bits, and the rounds' and the audit's per-pixel arrays.
const ADAPTIVE_BYTES: u64 = 200;

/// About the most memory a render of `window` under `settings` with passes `selection` holds for
/// its pixels (see the module documentation for the figures); the scene and its acceleration
/// structure come on top.
pub fn pixel_memory(
    settings: &RenderSettings,
    selection: AovSelection,
    window: PixelWindow,
) -> u64 {
    let pixels = u64::from(window.width()) * u64::from(window.height());
    let mut per_pixel = FILM_BYTES;
    if selection.any() {
        per_pixel += PASS_BYTES;
    }
    if settings.adaptive.is_some() {
        per_pixel += ADAPTIVE_BYTES;
    }
    pixels.saturating_mul(per_pixel)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adaptive::Adaptive;

    /// Adaptive renders and passes cost more a pixel, and a window only its own pixels.
    #[test]
    fn memory_grows_with_what_a_pixel_holds() {
        let uniform = RenderSettings {
            width: 3840,
            height: 2160,
            ..RenderSettings::default()
        };
        let whole = uniform.window();
        let none = AovSelection::NONE;
        let uniform_bytes = pixel_memory(&uniform, none, whole);
        assert_eq!(uniform_bytes, 3840 * 2160 * FILM_BYTES);
        let adaptive = RenderSettings {
            adaptive: Some(Adaptive::default()),
            ..uniform
        };
        let adaptive_bytes = pixel_memory(&adaptive, none, whole);
        // Measured peaks at 3840x2160: 230 and 30 bytes a pixel.
        assert!(adaptive_bytes >= 3840 * 2160 * 230 && uniform_bytes >= 3840 * 2160 * 30);
        let all = AovSelection::ALL;
        assert!(pixel_memory(&adaptive, all, whole) >= 3840 * 2160 * 306);
        assert!(pixel_memory(&uniform, all, whole) >= 3840 * 2160 * 127);
        let quarter = PixelWindow {
            x0: 0,
            y0: 0,
            x1: 1920,
            y1: 1080,
        };
        assert_eq!(4 * pixel_memory(&adaptive, none, quarter), adaptive_bytes);
    }
}
