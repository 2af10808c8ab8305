//! Error-targeted adaptive sampling: every pixel starts with a few samples, then rounds add
//! samples only to the pixels whose estimated error is still above the target.
//!
//! - **Error**: a pixel's relative standard error of its mean display value
//!   ([`PixelEstimate::relative_error`]: sRGB-encoded, with a floor for near-black pixels).
//! - **Rounds**: round 0 takes [`Adaptive::min_spp`] samples in every pixel. Round k brings the
//!   pixels it samples to `min_spp`·2^k samples (at most [`Adaptive::max_spp`]): every pixel still
//!   above [`Adaptive::target_error`] (after the first round, above [`FIRST_ROUND_MARGIN`] × the
//!   target) and, in the first [`NEIGHBOUR_ROUNDS`] rounds, its eight neighbours. A pixel's
//!   samples are the prefix of its own progressive sequence ([`crate::sampler::progressive_2d`]),
//!   so samples added later keep the stratification of the earlier ones, and a power-of-two count
//!   is a (0, k, 2)-net in the pixel.
//! - **Determinism**: a pixel's samples depend only on its position and the seed, and whether it
//!   gets more depends only on its own and its neighbours' samples of earlier rounds; the image is
//!   bit-identical for any thread count. A crop window or a tile is sampled with a border one pixel
//!   wide per round (clipped to the image), so its pixels equal those of the whole render. A time
//!   limit ([`Adaptive::time_limit`]) trades that for a bound: it stops between rows, and which
//!   rows got their last round then depends on timing.

use crate::aov::{AovSample, Aovs};
use crate::film::{Film, MIN_ERROR_SAMPLES, PixelEstimate};
use crate::integrator::RayCounts;
use crate::render::{MAX_SPP, PixelWindow, Progress, RenderError, Rendered, SampleContext};
use crate::sampler::{SampleKey, pixel_pattern, progressive_2d};
use rayon::prelude::*;
pub use stats::{ErrorStats, RoundSummary, SamplingStats, Stop};
use std::borrow::Cow;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How an adaptive render decides where to sample and when to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// The relative error every pixel should reach (0: none; every pixel refines to
    /// [`Adaptive::max_spp`] or until the time limit).
    pub target_error: f64,
    /// Samples every pixel takes in the first round: a power of two, at least 2 (the error
    /// estimate needs two). Below [`crate::film::ERROR_BATCHES`] the first estimate is coarse
    /// (n − 1 degrees of freedom) and a feature can slip past a pixel and its neighbours: a
    /// preview setting that costs less where most of the image is flat.
    pub min_spp: u32,
    /// Samples no pixel exceeds.
    pub max_spp: u32,
    /// Stop refining after this long and keep the image reached (the first round always
    /// completes, so that every pixel has an estimate).
    pub time_limit: Option<Duration>,
}

/// Samples every pixel takes in the first round unless told otherwise.
pub const DEFAULT_MIN_SPP: u32 = 8;
/// The fewest samples a first round may take: those the error estimate needs.
pub const MIN_FIRST_ROUND: u32 = MIN_ERROR_SAMPLES;
/// The most samples a pixel takes unless told otherwise.
pub const DEFAULT_MAX_SPP: u32 = 1024;
/// The first refinement rounds in which the neighbours of a pixel above the target are sampled
/// too, whatever their own error: they reach 8× the first round's samples. Measured on the defense
/// scene (480x270): without neighbours, a first round of 8 left an error floor near 2e-3 linear
/// RMSE; following neighbours in every round cost 1.2–1.4× the CPU time of this at equal RMSE.
pub const NEIGHBOUR_ROUNDS: u32 = 3;
/// After the first round a pixel stops, and leaves its neighbours be, only when its error is below
/// this fraction of the target. With the default first round of 8, the first estimate has 7
/// degrees of freedom and no neighbour rounds before it: an estimate at 0.3× its true value has a
/// chance near 1 in 800 (χ²₇ < 0.63), where stopping below 1× stops about half the pixels whose
/// true error is the target (a preview's first round of 2 has one degree of freedom, and a chance
/// near 1 in 4: the neighbour rounds carry more of its load). Measured
/// (480x270, one thread, targets 0.005 to 0.02, linear RMSE): for 1–4% more rays the image error
/// fell 6–7% on defense, 3–6% on reflective and 4–10% on grid. Applied in the later neighbour
/// rounds as well (0.3 or 0.5), it took 8–21% more samples for the same error on defense.
pub const FIRST_ROUND_MARGIN: f64 = 0.3;

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
    /// A maximum sample count outside MIN_FIRST_ROUND..=MAX_SPP.
    #[error("the maximum samples per pixel must be in {MIN_FIRST_ROUND}..={MAX_SPP}, got {0}")]
    MaxSpp(u32),
    /// A first-round count that is not a power of two from 2 to the maximum.
    #[error(
        "the minimum samples per pixel must be a power of two from {MIN_FIRST_ROUND} to the maximum ({max}), got {min}"
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
    /// A time limit in seconds that is not a number in `(0, MAX_TIME_LIMIT_SECS]`.
    #[error(
        "the time limit must be a number of seconds above 0 and at most {MAX_TIME_LIMIT_SECS:e} (about 11.6 days), got {0:?}"
    )]
    TimeLimitSecs(f64),
}

/// The longest time limit, in seconds (about 11.6 days): far beyond any render's need, and well
/// inside what a `Duration` holds.
pub const MAX_TIME_LIMIT_SECS: f64 = 1e6;

/// The time limit of `secs` seconds, if that is a number in `(0, MAX_TIME_LIMIT_SECS]`.
pub fn time_limit_from_secs(secs: f64) -> Result<Duration, AdaptiveError> {
    if secs > 0.0 && secs <= MAX_TIME_LIMIT_SECS {
        Ok(Duration::from_secs_f64(secs))
    } else {
        Err(AdaptiveError::TimeLimitSecs(secs))
    }
}

impl Adaptive {
    /// Checks the settings against their limits.
    pub fn validate(&self) -> Result<(), AdaptiveError> {
        if !(self.target_error.is_finite() && self.target_error >= 0.0) {
            return Err(AdaptiveError::TargetError(self.target_error));
        }
        if !(MIN_FIRST_ROUND..=MAX_SPP).contains(&self.max_spp) {
            return Err(AdaptiveError::MaxSpp(self.max_spp));
        }
        if !(MIN_FIRST_ROUND..=self.max_spp).contains(&self.min_spp)
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

    /// These settings with `min_spp` samples in the first round.
    pub fn with_min_spp(self, min_spp: u32) -> Adaptive {
        Adaptive { min_spp, ..self }
    }

    /// Whether a pixel with `count` samples and relative error `error` needs another round.
    fn wants_more(&self, count: u32, error: f64) -> bool {
        self.above(count, error, self.target_error)
    }

    /// Whether a pixel with `count` samples and relative error `error` is above `threshold` and
    /// below the maximum count.
    fn above(&self, count: u32, error: f64, threshold: f64) -> bool {
        // The error is never NaN (infinite when unknown), so `>` is the negation of `<=`.
        count < self.max_spp && error > threshold
    }

    /// How many rounds can follow the first: round k brings its pixels to
    /// [`Adaptive::round_count`]`(k)`, which reaches `max_spp` at this one.
    fn refinement_rounds(&self) -> u32 {
        self.max_spp
            .div_ceil(self.min_spp)
            .next_power_of_two()
            .trailing_zeros()
    }

    /// The sample count of a pixel sampled in `round`: `min_spp` doubled `round` times, at most
    /// `max_spp`.
    fn round_count(&self, round: u32) -> u32 {
        self.min_spp
            .checked_shl(round)
            .filter(|&count| count >> round == self.min_spp)
            .unwrap_or(u32::MAX)
            .min(self.max_spp)
    }

    /// Marks in `refine` the pixels that `round` (at least 1) samples: those whose own error is
    /// above the target (above [`FIRST_ROUND_MARGIN`] × the target after the first round) and, in
    /// the first [`NEIGHBOUR_ROUNDS`] rounds, their neighbours, since a feature that crosses into
    /// a pixel can be missed by all of its first samples.
    fn select(
        &self,
        round: u32,
        estimates: &[PixelEstimate],
        errors: &[f64],
        width: usize,
        refine: &mut [bool],
    ) {
        let height = estimates.len() / width;
        let count = self.round_count(round);
        let follows_neighbours = round <= NEIGHBOUR_ROUNDS.min(self.refinement_rounds());
        let threshold = match round {
            1 => self.target_error * FIRST_ROUND_MARGIN,
            _ => self.target_error,
        };
        // Each pixel's own verdict once, in a dense mask: the neighbour test reads it nine times.
        refine
            .par_iter_mut()
            .zip(estimates.par_iter().zip(errors))
            .for_each(|(above, (estimate, &error))| {
                *above = self.above(estimate.count(), error, threshold);
            });
        if !follows_neighbours {
            return;
        }
        let above = refine.to_vec();
        refine
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(y, row)| {
                let (y0, y1) = (y.saturating_sub(1), (y + 1).min(height - 1));
                for (x, wanted) in row.iter_mut().enumerate() {
                    *wanted = *wanted
                        || (estimates[y * width + x].count() < count && {
                            let (x0, x1) = (x.saturating_sub(1), (x + 1).min(width - 1));
                            (y0..=y1)
                                .any(|ny| above[ny * width + x0..=ny * width + x1].contains(&true))
                        });
                }
            });
    }
}

/// Renders the context's window adaptively (see the module documentation).
pub(crate) fn render_adaptive(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let settings = context.settings;
    let inner = context.window;
    // A pixel's decisions depend on its neighbours', which depend on theirs one round earlier:
    // sampling a border as wide as the rounds around the window makes its pixels those of the
    // whole render.
    let window = bordered(
        inner,
        adaptive.refinement_rounds(),
        settings.width,
        settings.height,
    );
    let rounds = Rounds {
        context: &context.with_window(window),
        adaptive,
        inner,
        progress,
        started: Instant::now(),
        totals: Mutex::new(RayCounts::default()),
        timed_out: AtomicBool::new(false),
    };
    let ww = window.width() as usize;
    let pixels = ww * window.height() as usize;
    let mut estimates = vec![PixelEstimate::default(); pixels];
    // Each pixel's relative error after the last round, recomputed for the pixels a round samples.
    let mut errors = vec![f64::INFINITY; pixels];
    // Which pixels the next round samples.
    let mut refine = vec![true; pixels];
    let mut aov_samples = rounds.context.aov_buffer();
    let mut round = 0u32;
    loop {
        // Surface passes come from each pixel's first sample, taken in round 0.
        let aovs = if round == 0 {
            &mut aov_samples[..]
        } else {
            &mut []
        };
        rounds.sample(round, &mut estimates, &refine, aovs);
        if progress.cancelled() {
            return Err(RenderError::Cancelled);
        }
        update_errors(&mut errors, &estimates, &refine);
        adaptive.select(round + 1, &estimates, &errors, ww, &mut refine);
        progress.round_done(&RoundSummary::of_window(
            round,
            &crop(&errors, window, inner),
            &crop(&refine, window, inner),
            adaptive.target_error,
        ));
        round += 1;
        if !refine.contains(&true)
            || rounds.timed_out.load(Ordering::Relaxed)
            || rounds.out_of_time()
        {
            break;
        }
    }

    let sampled = Sampled {
        estimates,
        errors,
        aov_samples,
        rounds: round,
        timed_out: rounds.timed_out.into_inner(),
        counts: rounds
            .totals
            .into_inner()
            .unwrap_or_else(|e| e.into_inner()),
    };
    Ok(sampled.finish(&context.with_window(inner), adaptive, window))
}

/// What the rounds of one adaptive render share: the bordered window's context, the settings,
/// the window the caller asked for, and the running totals.
struct Rounds<'a> {
    /// The context over the bordered window.
    context: &'a SampleContext<'a>,
    adaptive: &'a Adaptive,
    /// The window the caller asked for (progress counts only its rows).
    inner: PixelWindow,
    progress: &'a dyn Progress,
    started: Instant,
    totals: Mutex<RayCounts>,
    timed_out: AtomicBool,
}

impl Rounds<'_> {
    /// Whether the time limit, if any, has passed.
    fn out_of_time(&self) -> bool {
        self.adaptive
            .time_limit
            .is_some_and(|limit| self.started.elapsed() >= limit)
    }

    /// Takes `round`'s samples in the pixels `refine` marks, row by row in parallel, filling
    /// `aov_samples` (empty after round 0) from each pixel's first sample. After round 0 a row
    /// started past the time limit is skipped and the render marked timed out.
    fn sample(
        &self,
        round: u32,
        estimates: &mut [PixelEstimate],
        refine: &[bool],
        aov_samples: &mut [AovSample],
    ) {
        let window = self.context.window;
        let ww = window.width() as usize;
        estimates
            .par_chunks_mut(ww)
            .zip(refine.par_chunks(ww))
            .zip(self.context.aov_rows(aov_samples))
            .enumerate()
            .for_each(|(row_index, ((row, row_refine), mut aov_row))| {
                let y = window.y0 + row_index as u32;
                let row_done = || {
                    if (self.inner.y0..self.inner.y1).contains(&y) {
                        self.progress.row_done();
                    }
                };
                if self.progress.cancelled() {
                    return;
                }
                if round > 0 && self.out_of_time() {
                    self.timed_out.store(true, Ordering::Relaxed);
                    row_done();
                    return;
                }
                // Every round's samples stand for their share of the pixel at `max_spp`, so all
                // of a pixel's samples estimate one filtered image (the uniform render's at
                // `max_spp`) and the batch means see no difference between rounds' footprints.
                let counts = sample_row(
                    self.context,
                    y,
                    row,
                    row_refine,
                    aov_row.as_deref_mut(),
                    (self.adaptive.round_count(round), self.adaptive.max_spp),
                );
                *self.totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
                row_done();
            });
    }
}

/// Recomputes the relative error of the pixels `sampled` marks: only they have new estimates.
fn update_errors(errors: &mut [f64], estimates: &[PixelEstimate], sampled: &[bool]) {
    errors
        .par_iter_mut()
        .zip(estimates.par_iter().zip(sampled))
        .for_each(|(error, (estimate, &sampled))| {
            if sampled {
                *error = estimate.relative_error();
            }
        });
}

/// Brings the pixels of one row of the window that `refine` marks to `count` samples, each
/// standing for its share of the pixel at `footprint_spp` samples (filtered textures), taking
/// each pixel's surface passes from its first sample; returns the rays traced.
pub(crate) fn sample_row(
    context: &SampleContext<'_>,
    y: u32,
    row: &mut [PixelEstimate],
    refine: &[bool],
    mut aovs: Option<&mut [AovSample]>,
    (count, footprint_spp): (u32, u32),
) -> RayCounts {
    let mut counts = RayCounts::default();
    let cone = context.sample_cone(footprint_spp);
    for (column, estimate) in row.iter_mut().enumerate() {
        if !refine[column] {
            continue;
        }
        let x = context.window.x0 + column as u32;
        let pattern = pixel_pattern(x, y, context.settings.seed);
        for index in estimate.count()..count {
            let first_hit = match aovs.as_deref_mut() {
                Some(aovs) if index == 0 => Some(&mut aovs[column]),
                _ => None,
            };
            let offset = progressive_2d(index, pattern);
            let key = SampleKey {
                pattern,
                index,
                count: None,
            };
            estimate.add(context.trace((x, y), offset, cone, key, first_hit, &mut counts));
        }
    }
    counts
}

/// What the rounds left over the bordered window.
struct Sampled {
    estimates: Vec<PixelEstimate>,
    errors: Vec<f64>,
    aov_samples: Vec<AovSample>,
    rounds: u32,
    timed_out: bool,
    counts: RayCounts,
}

impl Sampled {
    /// The render of `context`'s window, cut out of the bordered `sampled` window: the image, the
    /// passes (with each pixel's count and variance) and the sampling statistics.
    fn finish(
        self,
        context: &SampleContext<'_>,
        adaptive: &Adaptive,
        sampled: PixelWindow,
    ) -> (Rendered, Option<Aovs>) {
        let window = context.window;
        let estimates = crop(&self.estimates, sampled, window);
        let errors = crop(&self.errors, sampled, window);
        let film = Film::of_estimates(window.width(), window.height(), &estimates);
        let mut aov_samples = crop(&self.aov_samples, sampled, window).into_owned();
        for (aov, estimate) in aov_samples.iter_mut().zip(estimates.iter()) {
            aov.fill_sampling(
                context.selection,
                estimate.count(),
                Some(estimate.variance()),
            );
        }
        let sampling =
            stats::sampling_stats(&estimates, &errors, adaptive, self.rounds, self.timed_out);
        (
            Rendered {
                film,
                window,
                counts: self.counts,
                sampling,
            },
            context.finish_aovs(aov_samples),
        )
    }
}

/// `window` grown by `border` pixels on every side, within a `width` × `height` image.
fn bordered(window: PixelWindow, border: u32, width: u32, height: u32) -> PixelWindow {
    PixelWindow {
        x0: window.x0.saturating_sub(border),
        y0: window.y0.saturating_sub(border),
        x1: window.x1.saturating_add(border).min(width),
        y1: window.y1.saturating_add(border).min(height),
    }
}

/// The values of the pixels of `inner` out of row-major values over `outer`, which contains it
/// (the values themselves, not a copy, when the two windows are one).
fn crop<T: Clone>(values: &[T], outer: PixelWindow, inner: PixelWindow) -> Cow<'_, [T]> {
    if values.is_empty() || outer == inner {
        return Cow::Borrowed(values);
    }
    let ow = outer.width() as usize;
    let (dx, w) = ((inner.x0 - outer.x0) as usize, inner.width() as usize);
    (inner.y0..inner.y1)
        .flat_map(|y| {
            let start = (y - outer.y0) as usize * ow + dx;
            values[start..start + w].iter().cloned()
        })
        .collect::<Vec<T>>()
        .into()
}

mod stats;
#[cfg(test)]
mod tests;
