//! Uniform sampling: the same number of samples in every pixel, rows in parallel.

use crate::aov::{AovSample, Aovs};
use crate::film::{Film, PixelEstimate};
use crate::footprint::RayCone;
use crate::integrator::RayCounts;
use crate::render::adaptive::SamplingStats;
use crate::render::context::SampleContext;
use crate::render::row_order::row_keys;
use crate::render::{Progress, RenderError, Rendered};
use crate::sampler::{PixelSampler, SampleKey, pixel_pattern};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Mutex;

/// Camera rays made at once before they are traced (at least one pixel's worth).
const BATCH_SAMPLES: usize = 16;

/// `settings.spp` samples in every pixel, by correlated multi-jittered sampling.
pub(super) fn render_uniform(
    context: &SampleContext<'_>,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let (settings, window) = (context.settings, context.window);
    let ww = window.width() as usize;
    let mut film = Film::new(window.width(), window.height());
    // Pass samples are allocated and computed only when a pass is selected.
    let mut aov_samples = context.aov_buffer();
    let aov_rows = context.aov_rows(&mut aov_samples);
    let totals = Mutex::new(RayCounts::default());
    let cone = context.sample_cone(settings.spp);
    // Rows are taken up in interleaved blocks (row_order), so progress counts representative work.
    let keys = row_keys(window.height() as usize);
    let mut rows: Vec<_> = film
        .pixels_mut()
        .chunks_mut(ww)
        .zip(aov_rows)
        .enumerate()
        .collect();
    rows.sort_unstable_by_key(|(row_index, _)| keys[*row_index]);
    rows.into_par_iter()
        .for_each(|(row_index, (row, aov_row))| {
            if progress.cancelled() {
                return;
            }
            let y = window.y0 + row_index as u32;
            let mut counts = RayCounts::default();
            render_row(context, (y, row), aov_row, cone, &mut counts);
            *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            progress.row_done();
        });
    if progress.cancelled() {
        return Err(RenderError::Cancelled);
    }
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((
        Rendered {
            film,
            window,
            counts,
            sampling: SamplingStats::uniform(settings.spp),
        },
        context.finish_aovs(aov_samples),
    ))
}

/// Samples every pixel of image row `y` (the window's pixels `row`, and their passes when
/// `aov_row` is given), counting the rays into `counts`. Pixels are sampled by their position in
/// the full image, so a window's pixels equal the whole render's.
fn render_row(
    context: &SampleContext<'_>,
    (y, row): (u32, &mut [Vec3]),
    mut aov_row: Option<&mut [AovSample]>,
    cone: RayCone,
    counts: &mut RayCounts,
) {
    let (settings, window, selection) = (context.settings, context.window, context.selection);
    let spp = settings.spp;
    let inv_spp = 1.0 / spp as f32;
    let mut sampler = PixelSampler::new(spp);
    let mut rays = Vec::with_capacity(BATCH_SAMPLES.max(spp as usize));
    let batch_pixels = (BATCH_SAMPLES / spp as usize).max(1);
    for (batch, pixels) in row.chunks_mut(batch_pixels).enumerate() {
        let first_column = batch * batch_pixels;
        // The batch's camera rays first: their divisions and square roots do not wait on each
        // other, where made one before each trace they wait in line.
        rays.clear();
        for column in first_column..first_column + pixels.len() {
            let x = window.x0 + column as u32;
            sampler.start_pixel(pixel_pattern(x, y, settings.seed));
            rays.extend((0..spp).map(|s| context.camera_ray((x, y), sampler.sample(s))));
        }
        let mut rays = rays.iter();
        for (i, pixel) in pixels.iter_mut().enumerate() {
            let column = first_column + i;
            let x = window.x0 + column as u32;
            // The pixel's key hashed again rather than kept from the batch above: keeping the
            // batch's keys made this loop 13-16% slower (grid, bunny frame), through codegen.
            let pattern = pixel_pattern(x, y, settings.seed);
            let mut aov = aov_row.as_deref_mut().map(|aovs| &mut aovs[column]);
            // The variance pass needs the running estimate; the image keeps its f32 sum.
            let mut estimate = selection.variance.then(PixelEstimate::default);
            let mut sum = Vec3::ZERO;
            for (s, ray) in (0..spp).zip(&mut rays) {
                let first_hit = if s == 0 { aov.as_deref_mut() } else { None };
                let key = SampleKey {
                    pattern,
                    index: s,
                    count: Some(spp),
                };
                let radiance = context.trace_ray(ray, cone, key, first_hit, counts);
                if let Some(e) = &mut estimate {
                    e.add(radiance);
                }
                sum += radiance;
            }
            *pixel = sum * inv_spp;
            if let Some(aov) = aov {
                aov.fill_sampling(selection, spp, estimate.map(|e| e.variance()));
            }
        }
    }
}
