//! The audit of a finished adaptive render: the error it reports, measured on pixels drawn in
//! proportion to their estimated error, each sampled again twice, independently.
//!
//! The twins that follow pixels through the rounds ([`super::calibration`]) are chosen after the
//! first round, before anyone knows where the error will end up; most of the error then sits in
//! a few of the pixels, and which of them hold a twin decides the estimate. Measured on the
//! quadric grid at target 0.0005 (480x270), the 140 twins among the 3259 refined pixels at 32
//! samples held 2.3× those pixels' mean true error, and the estimate was 1.47× the truth.
//!
//! The audit draws its pixels when the rounds are over, pixel i with chance
//! pᵢ = min(1, M wᵢ / Σw + F / N), wᵢ = sᵢ / √rᵢ: M ([`AUDIT_PIXELS`]) by the calibrated squared
//! error sᵢ over the root of the rays rᵢ the pixel traced, and F ([`UNIFORM_PIXELS`]) spread
//! evenly, so that pixels whose samples all agreed are drawn too. Auditing a pixel costs its rays
//! twice, and for a fixed cost the estimate's variance, Σ eᵢ² / pᵢ, is least with pᵢ ∝ eᵢ / √rᵢ
//! (Lagrange, as in Neyman allocation). Drawn by sᵢ alone, 512 pixels cost 8–15% of the render on
//! the bundled scenes: the pixels with most error hold the most samples.
//!
//! Each drawn pixel is sampled twice more, as many samples as it holds, with independent seeds;
//! with a its value and b, c the two new ones, (a − b)(a − c) has expectation (a − μ)² given a,
//! its actual squared error ([`super::Twin`]). The image's MSE is estimated by
//! Σ (a − b)(a − c) / pᵢ over the drawn pixels, divided by N (Horvitz–Thompson): unbiased whatever
//! the calibration says, and precise where the sᵢ follow the actual errors. Over 60 renders of
//! four scenes (docs/image-error/estimate.md) it was within ±25% of the truth in 46, where the
//! calibrated estimates summed were in 29. The draw depends only on the pixels and the seed, so
//! it is the same for any thread count.

use super::Twin;
use super::calibration::{Calibration, sample_sets, uniform_draw};
use crate::film::PixelEstimate;
use crate::integrator::RayCounts;
use crate::render::SampleContext;
use rayon::prelude::*;

/// Pixels the audit of a whole image draws in proportion to their estimated error, about (a crop
/// or a tile, its share).
pub const AUDIT_PIXELS: f64 = 1024.0;

/// Pixels the audit draws evenly over the image, about: pixels whose samples all agreed have
/// no estimated error to be drawn by, and may still have missed a feature.
pub const UNIFORM_PIXELS: f64 = 1024.0;

/// The fewest pixels a crop's or a tile's audit draws in each way.
const MIN_AUDIT_PIXELS: f64 = 32.0;

/// What the audit's draw is hashed with, so that it follows neither the image's samples nor the
/// twins' choice.
const AUDIT_SEED: u32 = 0xA0D1_7ED5;

/// What the audited pixels' two new sample sets are keyed with: not the calibration twins' sets,
/// which helped decide the pixels' counts and so are not independent of where they stopped.
const AUDIT_SETS: u32 = 0x5A3E_0A7D;

/// The audited MSE of the display values of the window of `context`, whose pixels are
/// `estimates` (row-major) having traced `rays`, with their squared errors estimated by
/// `calibration`; each drawn pixel's samples stand for their share of the pixel at
/// `footprint_spp`. Returns the MSE and the rays the audit traced.
pub(super) fn audit(
    context: &SampleContext<'_>,
    (estimates, rays): (&[PixelEstimate], &[u64]),
    calibration: &Calibration,
    footprint_spp: u32,
) -> (f64, RayCounts) {
    let pixels = estimates.len();
    if pixels == 0 {
        return (0.0, RayCounts::default());
    }
    let window = context.window;
    let weights: Vec<f64> = (estimates.par_iter().zip(rays))
        .map(|(e, &r)| calibration.squared_error(e).max(0.0) / (r.max(1) as f64).sqrt())
        .map(|w| if w.is_finite() { w } else { 0.0 })
        .collect();
    let total: f64 = weights.iter().sum();
    // A crop or a tile draws its share of the image's audit (at least a few pixels): auditing
    // every pixel of a 32x32 tile would triple its rays.
    let settings = context.settings;
    let share = pixels as f64 / (settings.width as f64 * settings.height as f64);
    let drawn_pixels = |wanted: f64| (wanted * share).max(MIN_AUDIT_PIXELS);
    let uniform = (drawn_pixels(UNIFORM_PIXELS) / pixels as f64).min(1.0);
    let by_error = drawn_pixels(AUDIT_PIXELS);
    let chance = |s: f64| match total > 0.0 {
        true => (by_error * s / total + uniform).min(1.0),
        false => uniform,
    };
    let seed = settings.seed ^ AUDIT_SEED;
    let drawn: Vec<(usize, (u32, u32), f64)> = (weights.iter().enumerate())
        .filter_map(|(i, &s)| {
            let at = window.pixel(i);
            let p = chance(s);
            (uniform_draw(seed, at) < p).then_some((i, at, p))
        })
        .collect();
    // Collected in order and summed in order: the same estimate for any thread count.
    let audited: Vec<(f64, RayCounts)> = drawn
        .par_iter()
        .map(|&(i, at, p)| {
            let pixel = &estimates[i];
            let mut twin = Twin::default();
            let mut counts = RayCounts::default();
            let footprint = (pixel.count(), footprint_spp);
            sample_sets(context, at, &mut twin, footprint, &mut counts, AUDIT_SETS);
            let m = twin.squared_error_of(pixel);
            (m / p, counts)
        })
        .collect();
    let mut counts = RayCounts::default();
    let mut sum = 0.0;
    for (value, rays) in audited {
        sum += value;
        counts += rays;
    }
    ((sum / pixels as f64).max(0.0), counts)
}
