//! What a render holds in memory for its pixels at its peak, so that a caller can refuse a render
//! the machine cannot hold before it starts, rather than be killed part way.
//!
//! The figures come from peak resident sizes measured on the quadric grid at 3840x2160 (whose
//! scene is a few kilobytes, so the pixels are all of it), divided by the pixels and rounded up:
//! 30 bytes a pixel for a uniform render to EXR (the f32 film and the file's encoding), 127 with
//! every pass, 209 for an adaptive render (each pixel's estimate of 128 bytes, its state through
//! the rounds and the audit, and the pilot) and 293 for an adaptive render with every pass
//! (2026-11-27; 230 and 306 while an estimate held its samples' second moment too).

use super::adaptive::{pilot_pixels, sampled_window};
use super::{PixelWindow, RenderSettings};
use crate::aov::AovSelection;

/// Bytes a pixel of any render holds until its image is written: the f32 RGB film and the
/// output's encoding.
const FILM_BYTES: u64 = 32;
/// Bytes a pixel's passes add to what it holds until written, when any is selected.
const PASS_BYTES: u64 = 96;
/// Bytes an adaptive render holds for each pixel it samples while it renders: its estimate
/// ([`crate::film::PixelEstimate`]), rays, errors, target and pilot bits, and the rounds' and the
/// audit's per-pixel arrays.
const ADAPTIVE_BYTES: u64 = 180;
/// Bytes an adaptive render adds for each pixel it samples when the variance pass is selected:
/// the samples' second moment ([`crate::film::SecondMoment`]).
const MOMENT_BYTES: u64 = 24;
/// Bytes an adaptive render of a window smaller than what it samples (a crop, a piece: its
/// border) adds for each pixel of the window: the copies of their estimates and state it cuts
/// out of the bordered arrays at the end (measured with 152-byte estimates, so it errs on the
/// safe side now; the moments' copies, under the variance pass, are [`MOMENT_BYTES`] more).
const CROP_BYTES: u64 = 176;
/// Bytes a pilot pixel holds (its estimate, passes and round bits; its twin and its second
/// moment are boxed).
const PILOT_PIXEL_BYTES: u64 = 224;
/// Bytes a pilot pixel's boxed second moment takes on the heap, under the variance pass.
const PILOT_MOMENT_BYTES: u64 = 32;

/// Bytes a render anti-aliased by contrast holds for each pixel of its window and border while it
/// renders: the first samples' f32 film (12), which the window's own film is copied from, and for
/// the marks their 8-bit codes, each row's least and greatest codes and the marks (10), rounded
/// up; its passes, when selected, are copied as well ([`PASS_BYTES`]).
const ANTIALIAS_BYTES: u64 = 24;

/// The memory a render holds for its pixels ([`pixel_memory`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelMemory {
    /// Bytes held until the image is written: its film and passes. A caller that renders several
    /// windows one after another and writes them together holds each window's.
    pub kept: u64,
    /// Bytes held while the window renders and freed when it is done (an adaptive render's
    /// estimates, state and pilot; an anti-aliased one's first samples; 0 for a uniform one).
    pub working: u64,
}

/// About the most memory a render of `window` under `settings` with passes `selection` holds for
/// its pixels (see the module documentation for the figures); the scene and its acceleration
/// structure come on top.
pub fn pixel_memory(
    settings: &RenderSettings,
    selection: AovSelection,
    window: PixelWindow,
) -> PixelMemory {
    let pixels = |w: PixelWindow| u64::from(w.width()) * u64::from(w.height());
    let passes = if selection.any() { PASS_BYTES } else { 0 };
    let kept_per_pixel = FILM_BYTES + passes;
    let working = settings.adaptive.map_or(0, |adaptive| {
        let (width, height) = (settings.width, settings.height);
        let sampled = sampled_window(window, &adaptive, width, height);
        // The variance pass keeps each pixel's second moment beside its estimate.
        let moment = |bytes: u64| if selection.variance { bytes } else { 0 };
        let crop = if sampled == window {
            0
        } else {
            pixels(window) * (CROP_BYTES + moment(MOMENT_BYTES))
        };
        // The pilot covers the whole image, whatever the window.
        let pilot = match adaptive.is_planned() {
            true => pilot_pixels(width, height) * (PILOT_PIXEL_BYTES + moment(PILOT_MOMENT_BYTES)),
            false => 0,
        };
        let per_pixel = ADAPTIVE_BYTES + moment(MOMENT_BYTES);
        (pixels(sampled) * per_pixel).saturating_add(crop + pilot)
    });
    // Anti-aliasing's first samples, of the window and its border.
    let first_samples = settings.antialias.map_or(0, |_| {
        let bordered = (u64::from(window.width()) + 2) * (u64::from(window.height()) + 2);
        bordered * (ANTIALIAS_BYTES + passes)
    });
    PixelMemory {
        kept: pixels(window).saturating_mul(kept_per_pixel),
        working: working.saturating_add(first_samples),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adaptive::Adaptive;

    /// Adaptive renders and passes cost more a pixel, at least what was measured; a window holds
    /// its own film, and an adaptive one its border and the whole image's pilot too.
    #[test]
    fn memory_grows_with_what_a_pixel_holds() {
        let uniform = RenderSettings {
            width: 3840,
            height: 2160,
            ..RenderSettings::default()
        };
        let whole = uniform.window();
        let pixels = 3840 * 2160;
        let none = AovSelection::NONE;
        let all = AovSelection::ALL;
        let total = |m: PixelMemory| m.kept + m.working;
        let uniform_bytes = pixel_memory(&uniform, none, whole);
        assert_eq!(uniform_bytes.working, 0);
        assert!(total(uniform_bytes) >= pixels * 30);
        assert!(total(pixel_memory(&uniform, all, whole)) >= pixels * 127);
        let adaptive = RenderSettings {
            adaptive: Some(Adaptive::default()),
            ..uniform
        };
        let adaptive_bytes = pixel_memory(&adaptive, none, whole);
        assert_eq!(adaptive_bytes.kept, uniform_bytes.kept);
        assert!(total(adaptive_bytes) >= pixels * 209);
        assert!(total(pixel_memory(&adaptive, all, whole)) >= pixels * 293);
        // A quarter of the image: a quarter of the film, but a border, copies of its pixels and
        // the whole image's pilot besides.
        let quarter = PixelWindow {
            x0: 0,
            y0: 0,
            x1: 1920,
            y1: 1080,
        };
        let part = pixel_memory(&adaptive, none, quarter);
        assert_eq!(4 * part.kept, adaptive_bytes.kept);
        let pilot = pilot_pixels(3840, 2160) * PILOT_PIXEL_BYTES;
        let bordered = 1923 * 1083 * ADAPTIVE_BYTES;
        assert_eq!(part.working, bordered + 1920 * 1080 * CROP_BYTES + pilot);
    }
}
