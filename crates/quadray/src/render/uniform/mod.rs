//! Uniform sampling: the same number of samples in every pixel, traced in tiles (up to 32 columns
//! of a band of eight rows, [`tiles`]) in parallel, each row of a tile in batches of camera rays.

#[cfg(test)]
pub(crate) mod tests;
mod tiles;

use crate::aov::{AovSample, Aovs};
use crate::film::{Film, PixelEstimate, SecondMoment};
use crate::footprint::RayCone;
use crate::integrator::RayCounts;
use crate::math::Ray;
use crate::render::adaptive::SamplingStats;
use crate::render::context::SampleContext;
use crate::render::{Progress, RenderError, Rendered};
use crate::sampler::{PixelSampler, SampleKey, pixel_pattern};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use tiles::{cut_into_tiles, fill_background, meets_nothing};

/// Camera rays made at once before they are traced (at least one pixel's worth).
const BATCH_SAMPLES: usize = 32;

/// A thread's sampler and the buffers of its batches of camera rays, made once a thread and
/// reused across its tiles.
pub(super) struct Batches {
    /// The pixels' sample points.
    sampler: PixelSampler,
    /// The batch's pixels' offsets in the unit pixel, pixel after pixel.
    offsets: Vec<(f64, f64)>,
    /// The batch's image positions.
    positions: Vec<[f64; 2]>,
    /// The pattern keys of the batch's pixels ([`pixel_pattern`]), with more than one sample a
    /// pixel.
    patterns: Vec<u32>,
    /// The batch's camera rays.
    rays: Vec<Ray>,
    /// The radiance each of them brings.
    radiances: Vec<Vec3>,
}

impl Batches {
    /// The buffers of batches of `spp` samples a pixel.
    pub(super) fn new(spp: u32) -> Batches {
        let samples = BATCH_SAMPLES.max(spp as usize);
        Batches {
            sampler: PixelSampler::new(spp),
            offsets: vec![(0.0, 0.0); samples],
            positions: Vec::with_capacity(samples),
            patterns: Vec::with_capacity(samples),
            rays: vec![Ray::new(DVec3::ZERO, DVec3::ZERO); samples],
            radiances: vec![Vec3::ZERO; samples],
        }
    }
}

/// `settings.spp` samples in every pixel, by correlated multi-jittered sampling.
pub(super) fn render_uniform(
    context: &SampleContext<'_>,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let (film, aov_samples, counts) = render_uniform_parts(context, progress)?;
    Ok((
        Rendered {
            film,
            window: context.window,
            counts,
            sampling: SamplingStats::uniform(context.settings.spp),
        },
        context.finish_aovs(aov_samples),
    ))
}

/// [`render_uniform`]'s image, its pass samples (empty when no pass is selected) and its rays.
pub(super) fn render_uniform_parts(
    context: &SampleContext<'_>,
    progress: &dyn Progress,
) -> Result<(Film, Vec<AovSample>, RayCounts), RenderError> {
    let (settings, window) = (context.settings, context.window);
    let mut film = Film::new(window.width(), window.height());
    // Pass samples are allocated and computed only when a pass is selected.
    let mut aov_samples = context.aov_buffer();
    let aov_rows = context.optional_rows(&mut aov_samples);
    let (tiles, band_rows) = cut_into_tiles(&mut film, window, aov_rows);
    let totals = Mutex::new(RayCounts::default());
    let cone = context.sample_cone(settings.spp);
    // A band's rows are reported done when its last tile is.
    let tiles_left: Vec<AtomicUsize> = (band_rows.iter())
        .map(|&(_, tiles)| AtomicUsize::new(tiles))
        .collect();
    // The tiles are the parallel work, so a window of a few rows still keeps every thread busy.
    tiles.into_par_iter().for_each_init(
        || Batches::new(settings.spp),
        |batches, tile| {
            if progress.cancelled() {
                return;
            }
            let mut counts = RayCounts::default();
            let y0 = window.y0 + tile.first_row as u32;
            if meets_nothing(context, &tile) {
                for (pixels, _) in tile.rows {
                    fill_background(context, pixels, &mut counts);
                }
            } else {
                for (y, (pixels, aovs)) in (y0..).zip(tile.rows) {
                    let segment = (tile.first_column, pixels, aovs);
                    render_segment(context, y, segment, batches, cone, &mut counts);
                }
            }
            *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            if tiles_left[tile.band].fetch_sub(1, Ordering::AcqRel) == 1 {
                for _ in 0..band_rows[tile.band].0 {
                    progress.row_done();
                }
            }
        },
    );
    if progress.cancelled() {
        return Err(RenderError::Cancelled);
    }
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((film, aov_samples, counts))
}

/// Samples the pixels of image row `y` from window column `first_column` on (`pixels`, and
/// their passes `aovs` when selected), counting the rays into `counts`. Pixels are sampled by
/// their position in the full image, so a window's pixels equal the whole render's.
pub(super) fn render_segment(
    context: &SampleContext<'_>,
    y: u32,
    (first_column, pixels, mut aovs): (usize, &mut [Vec3], Option<&mut [AovSample]>),
    batches: &mut Batches,
    cone: RayCone,
    counts: &mut RayCounts,
) {
    let (settings, window) = (context.settings, context.window);
    let spp = settings.spp;
    let passes = aovs.is_some() || context.selection.variance;
    let Batches {
        sampler,
        offsets,
        positions,
        patterns,
        rays,
        radiances,
    } = batches;
    let batch_pixels = (BATCH_SAMPLES / spp as usize).max(1);
    for (batch, pixels) in pixels.chunks_mut(batch_pixels).enumerate() {
        let first = batch * batch_pixels;
        let x0 = window.x0 + (first_column + first) as u32;
        // The batch's camera rays first: their divisions and square roots do not wait on each
        // other, where made one before each trace they wait in line, and they run packed.
        positions.clear();
        let columns = x0..x0 + pixels.len() as u32;
        if spp == 1 {
            // The one sample of a pixel is its centre (as `PixelSampler::samples` gives it),
            // without the sampler's per-pixel calls.
            positions.extend(columns.map(|x| [x as f64 + 0.5, y as f64 + 0.5]));
        } else {
            patterns.clear();
            patterns.extend(columns.clone().map(|x| pixel_pattern(x, y, settings.seed)));
            let offsets = &mut offsets[..patterns.len() * spp as usize];
            sampler.samples_of_pixels(patterns, offsets);
            for (x, offsets) in columns.zip(offsets.chunks_exact(spp as usize)) {
                positions.extend(
                    offsets
                        .iter()
                        .map(|&(dx, dy)| [x as f64 + dx, y as f64 + dy]),
                );
            }
        }
        let rays = &mut rays[..positions.len()];
        context.camera_rays(positions, rays);
        if passes {
            let batch = Batch { x0, y, rays, cone };
            let aovs = aovs.as_deref_mut().map(|aovs| &mut aovs[first..]);
            shade_batch(context, &batch, pixels, aovs, counts);
        } else {
            let radiances = &mut radiances[..rays.len()];
            let seed = settings.seed;
            // A pixel's key is hashed only where a hit's shading asks for it, or kept from above.
            let key = |i: usize| match spp {
                1 => SampleKey {
                    pattern: pixel_pattern(x0 + i as u32, y, seed),
                    index: 0,
                    count: Some(1),
                },
                _ => SampleKey {
                    pattern: patterns[i / spp as usize],
                    index: (i % spp as usize) as u32,
                    count: Some(spp),
                },
            };
            let whitted = &settings.whitted;
            whitted.camera_rays(context.scene, rays, cone, key, counts, radiances);
            // Each pixel the mean of its samples, summed in order as one at a time would. One
            // sample a pixel is its own mean (the sum's zero added, which makes −0 +0), without
            // the loop over each pixel's samples (27 instructions a pixel).
            if spp == 1 {
                for (pixel, &r) in pixels.iter_mut().zip(&*radiances) {
                    *pixel = Vec3::ZERO + r;
                }
            } else {
                let inv_spp = 1.0 / spp as f32;
                let samples = radiances.chunks_exact(spp as usize);
                for (pixel, samples) in pixels.iter_mut().zip(samples) {
                    *pixel = samples.iter().fold(Vec3::ZERO, |sum, &r| sum + r) * inv_spp;
                }
            }
        }
    }
}

/// A batch's camera rays: `spp` a pixel for the pixels of row `y` from column `x0` on, standing
/// for `cone` each.
struct Batch<'r> {
    x0: u32,
    y: u32,
    rays: &'r [Ray],
    cone: RayCone,
}

/// Traces the batch's rays into its `pixels` (the mean of each pixel's samples), the pixels'
/// passes `aovs` when selected, and the running estimates the variance pass needs.
fn shade_batch(
    context: &SampleContext<'_>,
    batch: &Batch<'_>,
    pixels: &mut [Vec3],
    mut aovs: Option<&mut [AovSample]>,
    counts: &mut RayCounts,
) {
    let (settings, selection) = (context.settings, context.selection);
    let spp = settings.spp;
    let inv_spp = 1.0 / spp as f32;
    let mut rays = batch.rays.iter();
    for (i, pixel) in pixels.iter_mut().enumerate() {
        let x = batch.x0 + i as u32;
        // The pixel's key hashed again rather than kept from the batch above: keeping the
        // batch's keys made this loop 13-16% slower (grid, bunny frame), through codegen.
        let pattern = pixel_pattern(x, batch.y, settings.seed);
        let mut aov = aovs.as_deref_mut().map(|aovs| &mut aovs[i]);
        // The variance pass needs the running estimate and moment; the image keeps its f32 sum.
        let mut variance = selection
            .variance
            .then(<(PixelEstimate, SecondMoment)>::default);
        let mut sum = Vec3::ZERO;
        for (s, ray) in (0..spp).zip(&mut rays) {
            let first_hit = if s == 0 { aov.as_deref_mut() } else { None };
            let key = SampleKey {
                pattern,
                index: s,
                count: Some(spp),
            };
            let radiance = context.trace_ray(ray, batch.cone, key, first_hit, counts);
            if let Some((estimate, moment)) = &mut variance {
                estimate.add_with_moment(radiance, moment);
            }
            sum += radiance;
        }
        *pixel = sum * inv_spp;
        if let Some(aov) = aov {
            let variance = variance.map(|(estimate, moment)| moment.variance(estimate.count()));
            aov.fill_sampling(selection, spp, variance);
        }
    }
}
