//! Error-targeted adaptive sampling: every pixel starts with a few samples, then rounds add
//! samples only to the pixels whose estimated error is still above the target.
//!
//! - **Error**: a pixel's relative standard error of its mean display value
//!   ([`PixelEstimate::relative_error`]: sRGB-encoded, with a floor for near-black pixels).
//! - **Rounds**: round 0 takes [`Adaptive::min_spp`] samples in every pixel; each later round
//!   doubles the count of every pixel still above [`Adaptive::target_error`], up to
//!   [`Adaptive::max_spp`]. A pixel's samples are the prefix of its own progressive sequence
//!   ([`crate::sampler::progressive_2d`]), so samples added later keep the stratification of the
//!   earlier ones, and a power-of-two count is a (0, k, 2)-net in the pixel.
//! - **Determinism**: whether a pixel gets more samples depends only on its own samples, which
//!   depend only on its position and the seed; the image is bit-identical for any thread count, and
//!   a crop window or a tile equals the same pixels of the whole render. A time limit
//!   ([`Adaptive::time_limit`]) trades that for a bound: it stops between rows, and which rows got
//!   their last round then depends on timing.

use crate::aov::Aovs;
use crate::film::{ERROR_BATCHES, Film, PixelEstimate};
use crate::integrator::RayCounts;
use crate::render::{MAX_SPP, Progress, RenderError, Rendered, SampleContext};
use crate::sampler::{pixel_pattern, progressive_2d};
use rayon::prelude::*;
pub use stats::{ErrorStats, RoundSummary, SamplingStats, Stop};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How an adaptive render decides where to sample and when to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// The relative error every pixel should reach (0: none; every pixel refines to
    /// [`Adaptive::max_spp`] or until the time limit).
    pub target_error: f64,
    /// Samples every pixel takes in the first round: a power of two, at least
    /// [`ERROR_BATCHES`] (the error estimate needs that many).
    pub min_spp: u32,
    /// Samples no pixel exceeds.
    pub max_spp: u32,
    /// Stop refining after this long and keep the image reached (the first round always
    /// completes, so that every pixel has an estimate).
    pub time_limit: Option<Duration>,
}

/// Samples every pixel takes in the first round unless told otherwise.
pub const DEFAULT_MIN_SPP: u32 = 16;
/// The most samples a pixel takes unless told otherwise.
pub const DEFAULT_MAX_SPP: u32 = 1024;

impl Default for Adaptive {
    fn default() -> Self {
        Adaptive {
            target_error: 0.01,
            min_spp: DEFAULT_MIN_SPP,
            max_spp: DEFAULT_MAX_SPP,
            time_limit: None,
        }
    }
}

/// Why adaptive settings cannot be rendered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AdaptiveError {
    /// A target error that is negative or not a number.
    #[error("the target error must be a finite number >= 0, got {0}")]
    TargetError(f64),
    /// A maximum sample count outside 1..=MAX_SPP.
    #[error("the maximum samples per pixel must be in 1..={MAX_SPP}, got {0}")]
    MaxSpp(u32),
    /// A first-round count that is not a power of two from 8 to the maximum.
    #[error(
        "the minimum samples per pixel must be a power of two from {ERROR_BATCHES} to the maximum ({max}), got {min}"
    )]
    MinSpp {
        /// The minimum asked for.
        min: u32,
        /// The maximum it must not exceed.
        max: u32,
    },
    /// A time limit that is zero.
    #[error("the time limit must be more than 0 seconds")]
    TimeLimit,
}

impl Adaptive {
    /// Checks the settings against their limits.
    pub fn validate(&self) -> Result<(), AdaptiveError> {
        if !(self.target_error.is_finite() && self.target_error >= 0.0) {
            return Err(AdaptiveError::TargetError(self.target_error));
        }
        if !(1..=MAX_SPP).contains(&self.max_spp) {
            return Err(AdaptiveError::MaxSpp(self.max_spp));
        }
        if !(ERROR_BATCHES..=self.max_spp).contains(&self.min_spp)
            || !self.min_spp.is_power_of_two()
        {
            return Err(AdaptiveError::MinSpp {
                min: self.min_spp,
                max: self.max_spp,
            });
        }
        if self.time_limit == Some(Duration::ZERO) {
            return Err(AdaptiveError::TimeLimit);
        }
        Ok(())
    }

    /// These settings with `max_spp` as the maximum, and the first round's count lowered to it
    /// where it was above (an explicit `min_spp` is set after this).
    pub fn with_max_spp(self, max_spp: u32) -> Adaptive {
        Adaptive {
            max_spp,
            min_spp: self.min_spp.min(max_spp),
            ..self
        }
    }

    /// Whether a pixel with `count` samples and relative error `error` needs another round.
    fn wants_more(&self, count: u32, error: f64) -> bool {
        // The error is never NaN (infinite when unknown), so `>` is the negation of `<=`.
        count < self.max_spp && error > self.target_error
    }

    /// The sample count a pixel with `count` samples reaches in its next round.
    fn next_count(&self, count: u32) -> u32 {
        if count == 0 {
            self.min_spp
        } else {
            count.saturating_mul(2).min(self.max_spp)
        }
    }
}

/// Renders the context's window adaptively (see the module documentation).
pub(crate) fn render_adaptive(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let started = Instant::now();
    let (settings, window) = (context.settings, context.window);
    let ww = window.width() as usize;
    let pixels = ww * window.height() as usize;
    let mut estimates = vec![PixelEstimate::default(); pixels];
    // Each pixel's relative error after the last round, computed once per round.
    let mut errors = vec![f64::INFINITY; pixels];
    let mut aov_samples = context.aov_buffer();
    let totals = Mutex::new(RayCounts::default());
    let timed_out = AtomicBool::new(false);
    let out_of_time = || {
        adaptive
            .time_limit
            .is_some_and(|limit| started.elapsed() >= limit)
    };
    let mut round = 0u32;
    loop {
        // Surface passes come from each pixel's first sample, taken in round 0.
        let aov_rows = context.aov_rows(if round == 0 {
            &mut aov_samples
        } else {
            &mut []
        });
        estimates
            .par_chunks_mut(ww)
            .zip(errors.par_chunks(ww))
            .zip(aov_rows)
            .enumerate()
            .for_each(|(row_index, ((row, row_errors), mut aov_row))| {
                if round > 0 && out_of_time() {
                    timed_out.store(true, Ordering::Relaxed);
                    progress.row_done();
                    return;
                }
                let y = window.y0 + row_index as u32;
                let mut counts = RayCounts::default();
                for (column, estimate) in row.iter_mut().enumerate() {
                    if !adaptive.wants_more(estimate.count(), row_errors[column]) {
                        continue;
                    }
                    let x = window.x0 + column as u32;
                    let pattern = pixel_pattern(x, y, settings.seed);
                    for index in estimate.count()..adaptive.next_count(estimate.count()) {
                        let first_hit = match aov_row.as_deref_mut() {
                            Some(aovs) if index == 0 => Some(&mut aovs[column]),
                            _ => None,
                        };
                        let offset = progressive_2d(index, pattern);
                        estimate.add(context.trace((x, y), offset, first_hit, &mut counts));
                    }
                }
                *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
                progress.row_done();
            });
        errors
            .par_iter_mut()
            .zip(&estimates)
            .for_each(|(error, estimate)| *error = estimate.relative_error());
        let active = estimates
            .iter()
            .zip(&errors)
            .filter(|(estimate, error)| adaptive.wants_more(estimate.count(), **error))
            .count();
        let summary = RoundSummary {
            round,
            active: active as u64,
            pixels: pixels as u64,
            worst_error: stats::worst_error(&errors),
            target_error: adaptive.target_error,
        };
        progress.round_done(&summary);
        round += 1;
        if summary.active == 0 || timed_out.load(Ordering::Relaxed) || out_of_time() {
            break;
        }
    }

    let film = Film::from_pixels(
        window.width(),
        window.height(),
        estimates.iter().map(PixelEstimate::mean).collect(),
    )
    .expect("one estimate per pixel");
    for (aov, estimate) in aov_samples.iter_mut().zip(&estimates) {
        aov.fill_sampling(
            context.selection,
            estimate.count(),
            Some(estimate.variance()),
        );
    }
    let sampling =
        stats::sampling_stats(&estimates, &errors, adaptive, round, timed_out.into_inner());
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((
        Rendered {
            film,
            window,
            counts,
            sampling,
        },
        context.finish_aovs(aov_samples),
    ))
}

mod stats;
#[cfg(test)]
mod tests;
