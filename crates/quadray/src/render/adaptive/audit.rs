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
//! pᵢ = min(1, M wᵢ / Σw + C vᵢ / Σv + L lᵢ / Σl + F / N), four draws over the N pixels:
//! - M ([`AUDIT_PIXELS`]) by wᵢ = sᵢ / √rᵢ, the calibrated squared error sᵢ over the root of the
//!   rays rᵢ the pixel traced. Auditing a pixel costs about its rays, and for a fixed cost the
//!   estimate's variance, Σ eᵢ² / pᵢ, is least with pᵢ ∝ eᵢ / √rᵢ (Lagrange, as in Neyman
//!   allocation). Drawn by sᵢ alone, 512 pixels cost 8–15% of the render on the bundled scenes:
//!   the pixels with most error hold the most samples.
//! - C ([`CONTRAST_PIXELS`]) by vᵢ = cᵢ / √rᵢ, cᵢ the pixel's flat contrast: for a flat pixel
//!   (whose samples all agreed), the largest squared difference of its display value from its
//!   flat 4-neighbours' ([`super::missed`]). An edge that runs along the border of two flat
//!   pixels can cross into either by a sliver that every sample misses; the pixel then has no
//!   estimated error to be drawn by. On defense at 480x270 the sliver of the horizon in one row
//!   of 37 pixels held 37% of the image's squared error, and one of them drawn evenly (chance
//!   1/127) made the estimate 1.6× the truth.
//! - L ([`FEATURE_PIXELS`]) by lᵢ = min(kᵢ, [`FEATURE_CAP`]) / √rᵢ, kᵢ the pixel's contrast with
//!   a line it lies across ([`feature_contrasts`]): a quiet pixel between two that met a thin
//!   line along its row or column may have missed the line with every sample, and then has next
//!   to no estimated error (it is not flat either, where shading varies across it). On the
//!   kitchen at 480x270 (target 0.0005, seed 4) such pixels held a third of the image's squared
//!   error, and without this draw the estimate was 0.49× the truth (0.79× with it).
//! - F ([`UNIFORM_PIXELS`]) evenly, for what none of these foresees.
//!
//!
//! Each drawn pixel is sampled twice more, with independent seeds, as many samples as it holds
//! and, unless it is flat with both contrasts 0, at least [`AUDIT_MIN_SAMPLES`] where that
//! adds at most [`AUDIT_SHARE`] of the render's samples (fewer where not). With a its
//! value and b, c the two new ones, (a − b)(a − c) has expectation (a − μ)² given a, its actual
//! squared error ([`super::Twin`]), whatever the sets' counts (each is an unbiased estimate of
//! μ). The image's MSE is estimated by Σ (a − b)(a − c) / pᵢ over the drawn pixels, divided by N
//! (Horvitz–Thompson): unbiased whatever the calibration says, and precise where the draws follow
//! the actual errors. The product is not zero only where both sets meet what the pixel missed:
//! for a feature that a sample meets with chance q, about (nq)² of the time with n samples a
//! set; with sets of the pixel's own 8 or 16 samples the kitchen's missed thin lines were
//! measured at about half their error. The draw depends only on the pixels and the seed, so it
//! is the same for any thread count. docs/sampling.md has the estimate against the truth over 60
//! renders of four scenes.

use super::Twin;
use super::calibration::{Calibration, is_flat_error, sample_sets, uniform_draw};
use super::missed::{WHOLE, feature_contrasts, flat_contrasts};
use crate::film::PixelEstimate;
use crate::integrator::RayCounts;
use crate::render::SampleContext;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Pixels the audit of a whole image draws in proportion to their estimated error, about (a crop
/// or a tile, its share).
pub const AUDIT_PIXELS: f64 = 1024.0;

/// Pixels the audit draws evenly over the image, about: pixels whose samples all agreed have
/// no estimated error to be drawn by, and may still have missed a feature.
pub const UNIFORM_PIXELS: f64 = 1024.0;

/// Pixels the audit draws in proportion to the contrast of flat pixels with their neighbours,
/// about: where an edge runs along a pixel's border, a sliver of it can cross into the pixel
/// and be missed by every sample.
pub const CONTRAST_PIXELS: f64 = 1024.0;

/// Pixels the audit draws in proportion to their contrast with a line they lie across
/// ([`feature_contrasts`]), about: a thin line that the pixels on either side met can have been
/// missed by every sample of this one, whose estimated error is then near zero.
pub const FEATURE_PIXELS: f64 = 1024.0;

/// The largest feature contrast the draw weighs by: (0.02)², a missed sliver's usual size.
const FEATURE_CAP: f64 = 4e-4;

/// The fewest samples in each of an audited pixel's two new sample sets.
const AUDIT_MIN_SAMPLES: u32 = 32;

/// The share of the render's samples, in expectation, that bringing the audit's sets up to
/// [`AUDIT_MIN_SAMPLES`] may add: at 8 samples a pixel it would add about 14% (defense at
/// 480x270), and the floor is halved until it fits.
const AUDIT_SHARE: f64 = 0.05;

/// The fewest pixels a crop's or a tile's audit draws in each way.
const MIN_AUDIT_PIXELS: f64 = 32.0;

/// What the audit's draw is hashed with, so that it follows neither the image's samples nor the
/// twins' choice.
const AUDIT_SEED: u32 = 0xA0D1_7ED5;

/// What the audited pixels' two new sample sets are keyed with: not the calibration twins' sets,
/// which helped decide the pixels' counts and so are not independent of where they stopped.
const AUDIT_SETS: u32 = 0x5A3E_0A7D;

/// The pixels an audit draws from, row-major.
#[derive(Clone, Copy)]
pub(super) struct Pixels<'a> {
    /// Their samples.
    pub estimates: &'a [PixelEstimate],
    /// The rays each traced.
    pub rays: &'a [u64],
    /// Their batch-means squared errors ([`PixelEstimate::squared_error`]), which the rounds
    /// keep current.
    pub squared_errors: &'a [f64],
}

/// The audited MSE of the display values of the window of `context`, whose `pixels` have their
/// squared errors estimated by `calibration`; each drawn pixel's samples stand for their share
/// of the pixel at `footprint_spp`. Returns the MSE and the rays the audit traced.
pub(super) fn audit(
    context: &SampleContext<'_>,
    pixels: Pixels<'_>,
    calibration: &Calibration,
    footprint_spp: u32,
) -> (f64, RayCounts) {
    let estimates = pixels.estimates;
    if estimates.is_empty() {
        return (0.0, RayCounts::default());
    }
    let Draw {
        chances,
        set_counts,
    } = draw(context, &pixels, calibration, WHOLE);
    let window = context.window;
    let seed = context.settings.seed ^ AUDIT_SEED;
    let drawn: Vec<(usize, (u32, u32), f64)> = (chances.par_iter().enumerate())
        .filter_map(|(i, &p)| {
            let at = window.pixel(i);
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
            let footprint = (set_counts[i], footprint_spp);
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
    ((sum / estimates.len() as f64).max(0.0), counts)
}

/// What the audit of a window is expected to cost.
#[derive(Clone, Copy, Debug)]
pub(super) struct AuditCost {
    /// The rays it traces, in expectation over its draw.
    pub rays: f64,
    /// The time its draw takes (reading every pixel), as measured on the pixels read.
    pub draw: Duration,
}

/// What the audit of `pixels` (as [`audit`] takes them) is expected to cost: the rays, each
/// pixel's chance times its two sets' samples at the rays a sample of its own cost, and the
/// draw's time. A render under a time limit keeps this much of its time for the audit, and asks
/// each round, so a large window is read in bands of rows ([`EXPECTED_RAYS_PIXELS`]).
pub(super) fn expected_cost(
    context: &SampleContext<'_>,
    pixels: &Pixels<'_>,
    calibration: &Calibration,
) -> AuditCost {
    expected_cost_in_bands(context, pixels, calibration, EXPECTED_RAYS_PIXELS).0
}

/// About the most pixels [`expected_cost`] reads: the draw reads every pixel's samples, about
/// 10 ms a round for 480x270 pixels on one thread and 0.6 s at 3840x2160 on two, so a window
/// of more (past 1280x720) is read in bands of [`BAND_ROWS`] rows spread evenly over it, whose
/// expected rays and draw time, scaled to the window, stand for its own. (A window of fewer
/// rows than two bands is read whole.)
const EXPECTED_RAYS_PIXELS: usize = 1 << 20;

/// The rows of one band [`expected_cost`] reads: thin bands spread over more of the image. No
/// neighbour counts across a band's border (the flat contrast looks one row away, the feature
/// contrast up to three), so a band's edge rows see less than the window's would.
const BAND_ROWS: usize = 8;

/// The audit's [`expected_cost`] reading at most about `most` (at least 1) pixels of the
/// window, and how many it read. The draw's time is that of the pixels read, scaled.
fn expected_cost_in_bands(
    context: &SampleContext<'_>,
    pixels: &Pixels<'_>,
    calibration: &Calibration,
    most: usize,
) -> (AuditCost, usize) {
    let count = pixels.estimates.len();
    let width = context.window.width() as usize;
    if count <= most || width == 0 {
        let started = Instant::now();
        let rays = expected_rays_of(context, pixels, calibration, WHOLE);
        let draw = started.elapsed();
        return (AuditCost { rays, draw }, count);
    }
    // One band in every `every`: the bands' rows, in order, as one window as wide as this one.
    let every = count.div_ceil(most);
    let rows: Vec<usize> = (0..count / width)
        .filter(|y| (y / BAND_ROWS).is_multiple_of(every))
        .collect();
    let (estimates, rays, squared_errors) = (
        rows_of(pixels.estimates, &rows, width),
        rows_of(pixels.rays, &rows, width),
        rows_of(pixels.squared_errors, &rows, width),
    );
    let window = context.window;
    let bands = context.with_window(crate::render::PixelWindow {
        y1: window.y0 + rows.len() as u32,
        ..window
    });
    let read = Pixels {
        estimates: &estimates,
        rays: &rays,
        squared_errors: &squared_errors,
    };
    // Timed without the copies above, which the audit itself does not make.
    let started = Instant::now();
    let rays = expected_rays_of(&bands, &read, calibration, BAND_ROWS);
    let scale = count as f64 / estimates.len() as f64;
    let cost = AuditCost {
        rays: rays * scale,
        draw: started.elapsed().mul_f64(scale),
    };
    (cost, estimates.len())
}

/// Rows `rows` of the row-major `values`, `width` to a row.
fn rows_of<T: Clone>(values: &[T], rows: &[usize], width: usize) -> Vec<T> {
    (rows.iter())
        .flat_map(|&y| values[y * width..(y + 1) * width].iter().cloned())
        .collect()
}

/// The audit's expected rays over every pixel of the window, whose rows come in bands of `band`
/// ([`flat_contrasts`]).
fn expected_rays_of(
    context: &SampleContext<'_>,
    pixels: &Pixels<'_>,
    calibration: &Calibration,
    band: usize,
) -> f64 {
    if pixels.estimates.is_empty() {
        return 0.0;
    }
    let Draw {
        chances,
        set_counts,
    } = draw(context, pixels, calibration, band);
    (chances.par_iter().zip(set_counts).zip(pixels.estimates))
        .zip(pixels.rays)
        .map(|(((p, sets), estimate), &rays)| {
            let per_sample = rays as f64 / f64::from(estimate.count().max(1));
            p * 2.0 * f64::from(sets) * per_sample
        })
        .sum()
}

/// The audit's draw over a window's pixels: each one's chance of being drawn, and the samples
/// in each of its two sets if it is.
struct Draw {
    chances: Vec<f64>,
    set_counts: Vec<u32>,
}

/// The [`Draw`] of the (not empty) `pixels` of `context`'s window (module documentation), whose
/// rows come in bands of `band` ([`flat_contrasts`]).
fn draw(
    context: &SampleContext<'_>,
    pixels: &Pixels<'_>,
    calibration: &Calibration,
    band: usize,
) -> Draw {
    let Pixels {
        estimates,
        rays,
        squared_errors,
    } = *pixels;
    let pixels = estimates.len();
    let width = context.window.width() as usize;
    let weights = draw_weights(
        (estimates, rays),
        squared_errors,
        calibration,
        (width, band),
    );
    // Each summed in order: the same totals for any thread count.
    let total = |weights: &[f64]| weights.iter().fold(0.0, |t, w| t + w);
    let totals = (
        total(&weights.by_error),
        total(&weights.by_contrast),
        total(&weights.by_feature),
    );
    // A crop or a tile draws its share of the image's audit (at least a few pixels): auditing
    // every pixel of a 32x32 tile would triple its rays.
    let settings = context.settings;
    let share = pixels as f64 / (settings.width as f64 * settings.height as f64);
    let drawn_pixels = |wanted: f64| (wanted * share).max(MIN_AUDIT_PIXELS);
    let uniform = (drawn_pixels(UNIFORM_PIXELS) / pixels as f64).min(1.0);
    let by_error = drawn_pixels(AUDIT_PIXELS);
    let by_contrast = drawn_pixels(CONTRAST_PIXELS);
    let by_feature = drawn_pixels(FEATURE_PIXELS);
    let part = |drawn: f64, weight: f64, total: f64| match total > 0.0 {
        true => drawn * weight / total,
        false => 0.0,
    };
    let chances: Vec<f64> = (weights.by_error.par_iter())
        .zip(&weights.by_contrast)
        .zip(&weights.by_feature)
        .map(|((&w_error, &w_contrast), &w_feature)| {
            let error = part(by_error, w_error, totals.0);
            let contrast = part(by_contrast, w_contrast, totals.1);
            (error + contrast + part(by_feature, w_feature, totals.2) + uniform).min(1.0)
        })
        .collect();
    let set_counts = set_counts(&weights, &chances);
    Draw {
        chances,
        set_counts,
    }
}

/// Each pixel's count for its two sets: as many samples as it holds, and at least a floor
/// unless it is plain (flat, with no flat neighbour of another value: background, most of what
/// the even draw meets, where 32 samples cost the quadric grid 5% more rays for the same
/// estimates). The floor is [`AUDIT_MIN_SAMPLES`], halved until the samples it adds to the
/// pixels drawn with `chances` are at most [`AUDIT_SHARE`] of the render's in expectation, down
/// to none (each pixel's own count).
fn set_counts(weights: &Weights, chances: &[f64]) -> Vec<u32> {
    let own = &weights.counts;
    // A sum of whole numbers below 2^53: exact in f64, in any order.
    let rendered = own.par_iter().map(|&c| u64::from(c)).sum::<u64>() as f64;
    let count = |own: u32, plain: bool, floor: u32| match plain {
        true => own,
        false => own.max(floor),
    };
    // The samples `floor` adds to the pixels' own counts, in expectation (summed in order: the
    // same floor for any thread count).
    let added = |floor: u32| -> f64 {
        (own.iter().zip(&weights.plain).zip(chances))
            .map(|((&c, &plain), p)| p * 2.0 * (count(c, plain, floor) - c) as f64)
            .sum()
    };
    let mut floor = AUDIT_MIN_SAMPLES;
    while floor > 1 && added(floor) > AUDIT_SHARE * rendered {
        floor /= 2;
    }
    let floor = if floor > 1 { floor } else { 0 };
    (own.par_iter().zip(&weights.plain))
        .map(|(&c, &plain)| count(c, plain, floor))
        .collect()
}

/// The pixels' weights in the audit's draws, and what the sets' counts are made from: one entry
/// a pixel in each array (arrays, not a 32-byte record a pixel: the contrasts' own arrays are
/// reused, and the fresh memory a draw faults in, about 2 µs a page here, is a quarter).
struct Weights {
    /// Each pixel's calibrated squared error over the root of its rays.
    by_error: Vec<f64>,
    /// Each pixel's flat contrast over the root of its rays.
    by_contrast: Vec<f64>,
    /// Each pixel's contrast with a line it lies across ([`feature_contrasts`]), at most
    /// [`FEATURE_CAP`], over the root of its rays.
    by_feature: Vec<f64>,
    /// Whether each pixel is flat with no flat neighbour of another value.
    plain: Vec<bool>,
    /// Each pixel's own count, read once: the serial sums of [`set_counts`] then read 4 bytes a
    /// pixel instead of striding through the estimates (at 3840x2160, 0.11 -> 0.04 s).
    counts: Vec<u32>,
}

/// The [`Weights`] of the pixels `estimates` (row-major, `width` wide, in bands of `band` rows:
/// [`flat_contrasts`]) having traced `rays`, whose batch-means squared errors are
/// `squared_errors`.
fn draw_weights(
    (estimates, rays): (&[PixelEstimate], &[u64]),
    squared_errors: &[f64],
    calibration: &Calibration,
    (width, band): (usize, usize),
) -> Weights {
    debug_assert!(
        (squared_errors.iter().zip(estimates))
            .all(|(s, e)| s.to_bits() == e.squared_error().to_bits()),
        "the squared errors given are the estimates' own"
    );
    // Each contrast becomes its weight in place.
    let mut by_contrast = flat_contrasts(estimates, squared_errors, (width, band));
    let mut by_feature = feature_contrasts(estimates, squared_errors, (width, band));
    let (by_error, (plain, counts)) = (estimates.par_iter().zip(rays))
        .zip(squared_errors)
        .zip(by_contrast.par_iter_mut().zip(by_feature.par_iter_mut()))
        .map(|(((e, &r), &squared_error), (contrast, feature))| {
            let root = (r.max(1) as f64).sqrt();
            let by_error = calibration.corrected(e.count(), squared_error).max(0.0) / root;
            let plain = is_flat_error(squared_error) && *contrast == 0.0 && *feature == 0.0;
            *contrast /= root;
            *feature = feature.min(FEATURE_CAP) / root;
            let by_error = if by_error.is_finite() { by_error } else { 0.0 };
            (by_error, (plain, e.count()))
        })
        .unzip();
    Weights {
        by_error,
        by_contrast,
        by_feature,
        plain,
        counts,
    }
}

#[cfg(test)]
mod tests {
    use super::super::sample_pixel;
    use super::super::tests::{settings, top_down_camera};
    use super::*;
    use crate::aov::AovSelection;
    use crate::render::RenderSettings;
    use crate::*;
    use glam::{DVec3, Vec3};

    /// Grey spheres in a 5x5 lattice under two lights, seen from above: camera rays that hit
    /// cost two shadow rays more than those that miss, so a pixel's rays a sample vary over the
    /// image.
    fn lit_spheres() -> Scene {
        Scene::new(SceneDescription {
            camera: top_down_camera(),
            background: Vec3::ZERO,
            environment: None,
            materials: vec![Material::default()],
            lights: [DVec3::new(3.0, 2.0, 8.0), DVec3::new(-4.0, -1.0, 6.0)]
                .map(|position| Light::PointNoFalloff {
                    position,
                    irradiance: Vec3::ONE,
                })
                .to_vec(),
            geometry: Geometry {
                spheres: (0..25)
                    .map(|k| Sphere {
                        center: DVec3::new((k % 5) as f64 - 2.0, 0.8 * (k / 5) as f64 - 1.6, 0.0),
                        radius: 0.2 + 0.02 * (k % 7) as f64,
                        material: 0,
                    })
                    .collect(),
                ..Geometry::default()
            },
        })
        .unwrap()
    }

    /// A window's pixels, sampled ([`sampled`]).
    struct Window {
        estimates: Vec<PixelEstimate>,
        rays: Vec<u64>,
        squared_errors: Vec<f64>,
    }

    impl Window {
        /// The pixels as the audit takes them.
        fn pixels(&self) -> Pixels<'_> {
            Pixels {
                estimates: &self.estimates,
                rays: &self.rays,
                squared_errors: &self.squared_errors,
            }
        }
    }

    /// Each pixel of the image of `scene` at `settings` sampled to 8, 16 or 32 samples (by a
    /// hash of its position).
    fn sampled(scene: &Scene, settings: &RenderSettings) -> Window {
        let context = SampleContext::new(scene, settings, AovSelection::NONE).unwrap();
        let window = context.window;
        let mut estimates = Vec::new();
        let mut rays = Vec::new();
        for i in 0..(window.width() * window.height()) as usize {
            let (x, y) = window.pixel(i);
            let count = 8 << ((x.wrapping_mul(7919) ^ y.wrapping_mul(104_729)) % 3);
            let mut estimate = PixelEstimate::default();
            let mut counts = RayCounts::default();
            sample_pixel(
                &context,
                (x, y),
                &mut estimate,
                (None, None),
                (count, 64),
                &mut counts,
            );
            estimates.push(estimate);
            rays.push(counts.total());
        }
        let squared_errors = estimates.iter().map(PixelEstimate::squared_error).collect();
        Window {
            estimates,
            rays,
            squared_errors,
        }
    }

    fn adaptive() -> Adaptive {
        Adaptive {
            target_error: 0.01,
            max_spp: 64,
            ..Adaptive::default()
        }
    }

    /// The audit's expected rays are what it traces on average over its draws: over 12 seeds
    /// (the estimates fixed, the draw following the seed), the mean of the rays it traced is
    /// within 5% of the expectation. Dropping the two sets' factor 2, or a pixel's rays a
    /// sample (taking one ray a sample), fails.
    #[test]
    fn the_expected_rays_are_the_audits_mean() {
        let scene = lit_spheres();
        let base = RenderSettings {
            width: 120,
            height: 80,
            ..settings(adaptive())
        };
        let context = SampleContext::new(&scene, &base, AovSelection::NONE).unwrap();
        let window = sampled(&scene, &base);
        let pixels = window.pixels();
        let expected = expected_cost(&context, &pixels, &Calibration::NONE).rays;
        let samples: u64 = window.estimates.iter().map(|e| u64::from(e.count())).sum();
        let traced: u64 = window.rays.iter().sum();
        assert!(
            traced > samples + samples / 4,
            "shadow rays make samples differ in cost: {traced} rays for {samples} samples"
        );
        let seeds = 12;
        let mut total = 0.0;
        for seed in 0..seeds {
            let s = RenderSettings { seed, ..base };
            let context = SampleContext::new(&scene, &s, AovSelection::NONE).unwrap();
            let (_, counts) = audit(&context, pixels, &Calibration::NONE, 64);
            total += counts.total() as f64;
        }
        let mean = total / seeds as f64;
        assert!(
            (mean / expected - 1.0).abs() < 0.05,
            "the audit traced {mean} rays on average, {expected} expected"
        );
    }

    /// A window read in bands gives about the expected rays of the whole: with half its bands
    /// read (16 bands of 8 rows, over five rows of spheres), within 10%, and exactly the whole's
    /// when it holds no more pixels than the bands may.
    #[test]
    fn bands_stand_for_the_whole_window() {
        let scene = lit_spheres();
        let base = RenderSettings {
            width: 128,
            height: 256,
            ..settings(adaptive())
        };
        let context = SampleContext::new(&scene, &base, AovSelection::NONE).unwrap();
        let window = sampled(&scene, &base);
        let pixels = window.pixels();
        let count = window.estimates.len();
        let (whole, read) = expected_cost_in_bands(&context, &pixels, &Calibration::NONE, count);
        assert_eq!(read, count);
        let (banded, read) =
            expected_cost_in_bands(&context, &pixels, &Calibration::NONE, count / 2);
        let (whole, banded) = (whole.rays, banded.rays);
        assert_eq!(read, count / 2, "every other band of 8 rows");
        assert!(
            (banded / whole - 1.0).abs() < 0.1,
            "{banded} from half the bands, {whole} from all"
        );
    }
}
