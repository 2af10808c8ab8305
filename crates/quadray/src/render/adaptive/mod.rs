//! Adaptive sampling: every pixel starts with a few samples, then rounds add samples where they
//! lower the error most, by one of two rules ([`ErrorRule`]).
//!
//! - **Image rule** (the default, `--target-error`): the image's mean squared error is the sum of
//!   its pixels' ([`PixelEstimate::squared_error`]); each round doubles the pixels whose estimated
//!   squared error per ray (sᵢ/cᵢ) is above a threshold chosen so that the predicted image
//!   error meets the target, or the work meets the budget ([`image_rule`]). The thresholds come
//!   from a pilot, a fixed lattice of the image's pixels ([`pilot`]).
//! - **Pixel rule** (`--pixel-error`): every pixel is brought to one relative error of its display
//!   value ([`PixelEstimate::relative_error`]); round k brings the pixels it samples to
//!   `min_spp`·2^k samples: every pixel still above the target (after the first round, above
//!   [`FIRST_ROUND_MARGIN`] × the target).
//! - **Neighbours**: a feature that crosses into a pixel can be missed by all of its first
//!   samples, so in the first [`NEIGHBOUR_ROUNDS`] rounds a pixel is also sampled when a neighbour
//!   is, by its own estimate, and it has no more samples than that neighbour.
//! - **Slivers**: an edge along the border of two flat pixels (whose samples all agree) may
//!   cross into either by a sliver every sample missed, so in the first [`SLIVER_ROUNDS`] rounds
//!   a flat pixel beside a flat neighbour of another value is sampled too ([`missed`]).
//! - **Samples**: a pixel's samples are the prefix of its own progressive sequence
//!   ([`crate::sampler::progressive_2d`]), so samples added later keep the stratification of the
//!   earlier ones, and a power-of-two count is a (0, k, 2)-net in the pixel.
//! - **Determinism**: a pixel's samples depend only on its position and the seed, and whether it
//!   gets more depends only on its own and its neighbours' samples of earlier rounds and, under
//!   the image rule, on the pilot's thresholds; the image is bit-identical for any thread count. A
//!   crop window or a tile is sampled with a border one pixel wide per neighbour round (clipped to
//!   the image) and computes the same pilot, so its pixels equal those of the whole render. A time
//!   limit ([`Adaptive::time_limit`]) trades that for a bound: its rounds are planned from the
//!   rendered pixels and the time left, and which pixels got the last one depends on timing.
//! - **The reported error** is an audit of the finished window ([`audit`]): pixels drawn by their
//!   estimated error are sampled twice more, which measures their actual error without bias.
//!   The calibration by twins ([`calibration`]) steers the rounds; the audit says where they got.

use crate::aov::{AovSample, Aovs};
use crate::film::{Film, PixelEstimate};
use crate::integrator::RayCounts;
use crate::math::Ray;
use crate::render::empty_tiles::EmptyTiles;
use crate::render::{PixelWindow, Progress, RenderError, Rendered, SampleContext};
use crate::sampler::{SampleKey, pixel_pattern, progressive_2d};
pub use calibration::Calibration;
pub(crate) use calibration::{Twin, choose_twins, is_flat, sample_twin};
use image_rule::PixelState;
use pilot::{Plan, state_of};
use rayon::prelude::*;
use rounds::Rounds;
pub use settings::{
    Adaptive, AdaptiveError, DEFAULT_MAX_SPP, DEFAULT_MIN_SPP, ErrorRule, MAX_TIME_LIMIT_SECS,
    MIN_FIRST_ROUND, time_limit_from_secs,
};
pub use stats::{ErrorStats, RoundSummary, SamplingStats, Stop, estimated_rmse};
use std::borrow::Cow;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// The first refinement rounds in which the neighbours of a pixel sampled by its own estimate are
/// sampled too, whatever their own error. Measured on the defense scene (480x270), per-pixel
/// rule: without neighbours, a first round of 8 left an error floor near 2e-3 linear RMSE;
/// following neighbours in every round cost 1.2–1.4× the CPU time of this at equal RMSE.
pub const NEIGHBOUR_ROUNDS: u32 = 3;
/// The first refinement rounds in which a flat pixel beside a flat neighbour of another value is
/// sampled ([`missed`]): an edge between them may cross into either by a sliver all their
/// samples missed. On defense (480x270, one thread, seeds 1 to 3) it lowered the true error 5% at
/// target 0.002, 13–17% at 0.001 and 27–40% at 0.0005 for 0.4% more rays (a horizon in one
/// row); 3 rounds, or a least difference of 0.005 instead of [`missed::SLIVER_CONTRAST`], gave
/// the same images. At most [`NEIGHBOUR_ROUNDS`], whose border a crop or a tile is sampled with.
pub const SLIVER_ROUNDS: u32 = 2;
const _: () = assert!(SLIVER_ROUNDS <= NEIGHBOUR_ROUNDS);
/// Under the pixel rule, after the first round a pixel stops, and leaves its neighbours be, only
/// when its error is below this fraction of the target. With the default first round of 8, the
/// first estimate has 7 degrees of freedom and no neighbour rounds before it: an estimate at 0.3×
/// its true value has a chance near 1 in 800 (χ²₇ < 0.63), where stopping below 1× stops about
/// half the pixels whose true error is the target. Measured (480x270, one thread, targets 0.005
/// to 0.02, linear RMSE): for 1–4% more rays the image error fell 6–7% on defense, 3–6% on
/// reflective and 4–10% on grid.
pub const FIRST_ROUND_MARGIN: f64 = 0.3;

/// Renders the context's window adaptively (see the module documentation).
pub(crate) fn render_adaptive(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let settings = context.settings;
    let inner = context.window;
    let plan = if adaptive.is_planned() {
        Some(pilot::plan(context, adaptive, progress)?)
    } else {
        None
    };
    let window = sampled_window(inner, adaptive, settings.width, settings.height);
    let bordered_context = context.with_window(window);
    let empty_tiles = EmptyTiles::find(&bordered_context);
    let rounds = Rounds {
        context: &bordered_context.with_empty_tiles(&empty_tiles),
        adaptive,
        inner,
        progress,
        started: Instant::now(),
        totals: Mutex::new(RayCounts::default()),
        timed_out: AtomicBool::new(false),
    };
    let mut state = WindowState::new(rounds.context, plan.as_ref());
    let mut round = 0u32;
    let stop = loop {
        rounds.sample(round, &mut state);
        // A planned render takes its calibration from the pilot, and its reported error from the
        // audit: twins of its own would only cost.
        if round == 0 && plan.is_none() {
            state.choose_twins(rounds.context);
        }
        rounds.sample_twins(&mut state);
        if progress.cancelled() {
            return Err(RenderError::Cancelled);
        }
        let next = match adaptive.rule {
            ErrorRule::Pixel => state.select_by_pixel(adaptive, round + 1),
            ErrorRule::Image => state.select_by_image(&rounds, plan.as_ref(), round + 1),
        };
        let calibration = state.calibration_or(plan.as_ref().map(|p| &p.calibration));
        progress.round_done(&state.summary(round, window, inner, adaptive, &calibration));
        round += 1;
        if let Err(stop) = next {
            break stop;
        }
        if rounds.timed_out.load(Ordering::Relaxed) || rounds.out_of_time() {
            break Stop::TimeLimit;
        }
    };
    if let Some(plan) = &plan {
        *rounds.totals.lock().unwrap_or_else(|e| e.into_inner()) += plan.counts;
    }
    let calibration = state.calibration_or(plan.as_ref().map(|p| &p.calibration));
    let inner_context = context.with_window(inner).with_empty_tiles(&empty_tiles);
    // The rounds keep every pixel's batch-means squared error current (each round computes
    // those of the pixels it samples), which the audit's draw needs.
    let inner_pixels = audit::Pixels {
        estimates: &crop(&state.estimates, window, inner),
        rays: &crop(&state.rays, window, inner),
        squared_errors: &crop(state.squared_errors(), window, inner),
    };
    let (estimated_mse, audit_counts) =
        audit::audit(&inner_context, inner_pixels, &calibration, adaptive.max_spp);
    *rounds.totals.lock().unwrap_or_else(|e| e.into_inner()) += audit_counts;
    let sampled = Sampled {
        estimated_mse,
        estimates: state.estimates,
        aov_samples: state.aov_samples,
        rounds: round,
        stop,
        counts: rounds
            .totals
            .into_inner()
            .unwrap_or_else(|e| e.into_inner()),
    };
    Ok(sampled.finish(&context.with_window(inner), adaptive, window))
}

/// The pixels of the bordered window between rounds.
struct WindowState {
    /// The rule the render samples by.
    rule: ErrorRule,
    /// Width of the window.
    width: usize,
    estimates: Vec<PixelEstimate>,
    /// Rays each pixel's samples traced.
    rays: Vec<u64>,
    /// Each pixel's relative error after the last round (pixel rule) or its batch-means squared
    /// error (image rule), recomputed for the pixels a round samples.
    errors: Vec<f64>,
    /// Under the pixel rule, each pixel's batch-means squared error, kept as `errors` is (the
    /// calibration, the summary, the sliver rounds and the audit read it every round); empty
    /// under the image rule, whose `errors` it would repeat ([`WindowState::squared_errors`]).
    squared: Vec<f64>,
    /// The count the next round brings each pixel to (at most its own: not sampled).
    targets: Vec<u32>,
    aov_samples: Vec<AovSample>,
    /// For pilot pixels inside the window, the rounds that sample them (bit k: round k), which
    /// the pilot took already; 0 for the others (the pilot samples each of its pixels in round
    /// 0, so a pilot pixel's bits are never 0). Half the bytes of an `Option`.
    pilot_rounds: Vec<u64>,
    /// Each row's twins ([`calibration`]), chosen after the first round when the render has no
    /// plan (the pixel rule, or a time limit): the column and the twin.
    twins: Vec<Vec<(usize, Twin)>>,
}

impl WindowState {
    /// The window of `context` before any sample: every pixel wants the first round, except the
    /// pilot's pixels, which hold the plan's samples.
    fn new(context: &SampleContext<'_>, plan: Option<&Plan>) -> WindowState {
        let window = context.window;
        let pixels = window.width() as usize * window.height() as usize;
        let min_spp = context.settings.adaptive.map_or(1, |a| a.min_spp);
        let mut state = WindowState {
            rule: context
                .settings
                .adaptive
                .map_or(ErrorRule::Image, |a| a.rule),
            width: window.width() as usize,
            // Filled in parallel, so that the pages are faulted in on every thread (at 3840x2160
            // the estimates are 1.3 GB); the zeros come from the allocator.
            estimates: (0..pixels)
                .into_par_iter()
                .map(|_| PixelEstimate::default())
                .collect(),
            rays: vec![0; pixels],
            errors: (0..pixels).into_par_iter().map(|_| f64::INFINITY).collect(),
            squared: match context.settings.adaptive.map(|a| a.rule) {
                Some(ErrorRule::Pixel) => {
                    (0..pixels).into_par_iter().map(|_| f64::INFINITY).collect()
                }
                _ => Vec::new(),
            },
            targets: (0..pixels).into_par_iter().map(|_| min_spp).collect(),
            aov_samples: context.aov_buffer(),
            pilot_rounds: vec![0; pixels],
            twins: vec![Vec::new(); window.height() as usize],
        };
        for pixel in plan.iter().flat_map(|p| &p.pixels) {
            let (x, y) = pixel.at;
            if !(window.x0..window.x1).contains(&x) || !(window.y0..window.y1).contains(&y) {
                continue;
            }
            let i = (y - window.y0) as usize * state.width + (x - window.x0) as usize;
            state.estimates[i] = pixel.estimate;
            state.rays[i] = pixel.rays;
            state.targets[i] = 0;
            debug_assert!(
                pixel.rounds & 1 == 1,
                "the pilot samples its pixels in round 0"
            );
            state.pilot_rounds[i] = pixel.rounds;
            if let (Some(aov), Some(slot)) = (pixel.aov, state.aov_samples.get_mut(i)) {
                *slot = aov;
            }
        }
        state
    }

    /// Each pixel's batch-means squared error ([`PixelEstimate::squared_error`]), current after
    /// every round.
    fn squared_errors(&self) -> &[f64] {
        match self.rule {
            ErrorRule::Image => &self.errors,
            ErrorRule::Pixel => &self.squared,
        }
    }

    /// Computes the errors ([`error_of`], and under the pixel rule the squared errors) of the
    /// pixels that have none yet (infinite: the pilot's, at the first selection). A round
    /// computes those of the pixels it samples as it goes ([`Rounds::sample`]), while their
    /// estimates are in cache; the others' are unchanged.
    fn fill_unknown_errors(&mut self) {
        let rule = self.rule;
        fill_unknown(&mut self.errors, &self.estimates, |e| error_of(rule, e));
        fill_unknown(
            &mut self.squared,
            &self.estimates,
            PixelEstimate::squared_error,
        );
    }

    /// Chooses the twins among the pixels outside the pilot, after their first round.
    fn choose_twins(&mut self, context: &SampleContext<'_>) {
        let window = context.window;
        // Flat or not from the squared errors the first round computed.
        let (indices, candidates): (Vec<usize>, Vec<_>) = (self.squared_errors().iter())
            .zip(&self.pilot_rounds)
            .enumerate()
            .filter(|(_, (_, pilot))| **pilot == 0)
            .map(|(i, (&s, _))| (i, (window.pixel(i), calibration::is_flat_error(s))))
            .unzip();
        for (k, twin) in calibration::choose_twins(context.settings.seed, &candidates) {
            let i = indices[k];
            self.twins[i / self.width].push((i % self.width, twin));
        }
    }

    /// Chooses round `round`'s pixels by the pixel rule; `Err` with the reason to stop when it
    /// samples none.
    fn select_by_pixel(&mut self, adaptive: &Adaptive, round: u32) -> Result<(), Stop> {
        self.fill_unknown_errors();
        let refine = pixel_rule::select(
            adaptive,
            round,
            &self.estimates,
            (&self.errors, &self.squared),
            self.width,
        );
        let count = pixel_rule::round_count(adaptive, round);
        self.set_targets(&refine, |_| count);
        if refine.contains(&true) {
            Ok(())
        } else {
            Err(pixel_rule::stop(adaptive, &self.estimates, &self.errors))
        }
    }

    /// Chooses round `round`'s pixels by the image rule, from the plan's threshold or, under a
    /// time limit, from the window's own estimates and the time left; `Err` with the reason to
    /// stop when it samples none.
    fn select_by_image(
        &mut self,
        rounds: &Rounds<'_>,
        plan: Option<&Plan>,
        round: u32,
    ) -> Result<(), Stop> {
        let adaptive = rounds.adaptive;
        self.fill_unknown_errors();
        let (step, calibration) = match plan {
            Some(plan) => plan
                .decisions
                .get(round as usize - 1)
                .copied()
                .ok_or(plan.stop)?,
            None => {
                let calibration = self.calibration_or(None);
                let states = self.states(&calibration);
                (
                    rounds.unplanned_step(&states, calibration.alpha)?,
                    calibration,
                )
            }
        };
        let states = self.states(&calibration);
        let max_spp = adaptive.max_spp;
        // Each pixel's own target; pilot pixels hold their samples already, and count as
        // refined by their own estimate in the rounds that sampled them.
        let mut targets: Vec<u32> = states
            .par_iter()
            .zip(&self.pilot_rounds)
            .map(|(s, &pilot)| match pilot {
                0 => step.target(s, max_spp),
                _ => 0,
            })
            .collect();
        let own: Vec<bool> = states
            .par_iter()
            .zip(&self.pilot_rounds)
            .zip(&targets)
            .map(|((s, &pilot), &target)| match pilot {
                0 => target > s.count,
                bits => bits >> round & 1 == 1,
            })
            .collect();
        // Pilot pixels follow neighbours and slivers too, unless the pilot followed neighbours
        // itself: a sparse pilot samples its pixels by their own estimates only, and a pilot
        // pixel whose first samples all missed an edge was left with them.
        let pilot_followed = plan.is_some_and(|p| p.followed);
        let may_follow = |i: usize| !(pilot_followed && self.pilot_rounds[i] != 0);
        let follow = (round <= NEIGHBOUR_ROUNDS).then(|| {
            missed::follow_neighbours(&own, self.width, |i, j| {
                let (count, other) = (states[i].count, states[j].count);
                count < max_spp && count <= other && may_follow(i)
            })
        });
        // Under the image rule `errors` holds each pixel's batch-means squared error.
        let across = (round <= SLIVER_ROUNDS)
            .then(|| missed::across_flat_edges(&self.estimates, &self.errors, self.width));
        for (i, (target, s)) in targets.iter_mut().zip(&states).enumerate() {
            let followed = follow.as_ref().is_some_and(|f| f[i] && !own[i]);
            let sliver = across.as_ref().is_some_and(|a| a[i] && may_follow(i));
            if followed || sliver {
                *target = (*target).max((2 * s.count).min(max_spp));
            }
        }
        if !targets.iter().zip(&states).any(|(&t, s)| t > s.count) && plan.is_none() {
            return Err(Stop::Converged);
        }
        self.targets = targets;
        Ok(())
    }

    /// Sets the next round's target of every pixel `refine` marks from its count by `target`,
    /// and of the others to their count (none).
    fn set_targets(&mut self, refine: &[bool], target: impl Fn(u32) -> u32 + Sync) {
        self.targets
            .par_iter_mut()
            .zip(refine.par_iter().zip(self.estimates.par_iter()))
            .for_each(|(t, (&r, e))| *t = if r { target(e.count()) } else { 0 });
    }

    /// Each pixel's state for the allocation under `calibration` (from the image rule's cached
    /// squared errors).
    fn states(&self, calibration: &Calibration) -> Vec<PixelState> {
        self.estimates
            .par_iter()
            .zip(&self.errors)
            .zip(&self.rays)
            .map(|((e, &estimated), &r)| state_of((e.count(), estimated), r, calibration))
            .collect()
    }

    /// The calibration from the window's own twins, backed by `fallback` at counts with too few.
    fn calibration_or(&self, fallback: Option<&Calibration>) -> Calibration {
        // Without twins the fit is the fallback, whatever the pixels say: a planned render's
        // window has none, and skips the pass over its pixels each round.
        if self.twins.iter().all(Vec::is_empty) {
            return fallback.copied().unwrap_or(Calibration::NONE);
        }
        let pairs = self.twins.iter().enumerate().flat_map(|(row, twins)| {
            twins
                .iter()
                .map(move |(column, twin)| (&self.estimates[row * self.width + column], twin))
        });
        let population =
            (self.estimates.iter().zip(self.squared_errors())).map(|(e, &s)| (e.count(), s));
        Calibration::fit_or(pairs, population, fallback)
    }

    /// Where the render stands after `round`, over the window's inner pixels.
    fn summary(
        &self,
        round: u32,
        window: PixelWindow,
        inner: PixelWindow,
        adaptive: &Adaptive,
        calibration: &Calibration,
    ) -> RoundSummary {
        // The inner window's pixels row by row, in the bordered arrays (no copies).
        let (dx, w) = ((inner.x0 - window.x0) as usize, inner.width() as usize);
        let rows = (inner.y0..inner.y1).map(|y| (y - window.y0) as usize * self.width + dx);
        let pixels_of = |start: usize| start..start + w;
        let (mut active, mut worst, mut sum) = (0u64, 0.0f64, 0.0f64);
        for start in rows {
            let range = pixels_of(start);
            let estimates = &self.estimates[range.clone()];
            let errors = &self.errors[range.clone()];
            let squared = &self.squared_errors()[range.clone()];
            active += (self.targets[range].iter().zip(estimates))
                .filter(|&(&t, e)| t > e.count())
                .count() as u64;
            for ((e, &error), &squared) in estimates.iter().zip(errors).zip(squared) {
                if adaptive.rule == ErrorRule::Pixel {
                    worst = worst.max(error);
                }
                sum += calibration.corrected(e.count(), squared);
            }
        }
        let pixels = inner.width() as u64 * inner.height() as u64;
        let worst_error = match adaptive.rule {
            ErrorRule::Pixel => worst,
            ErrorRule::Image => f64::NAN,
        };
        RoundSummary {
            round,
            active,
            pixels,
            worst_error,
            estimated_error: (sum / pixels.max(1) as f64).sqrt(),
            rule: adaptive.rule,
            target_error: adaptive.target_error,
        }
    }
}

/// A pixel's error as `rule` ranks it: its relative error (pixel rule) or its batch-means
/// squared error (image rule).
fn error_of(rule: ErrorRule, estimate: &PixelEstimate) -> f64 {
    match rule {
        ErrorRule::Pixel => estimate.relative_error(),
        ErrorRule::Image => estimate.squared_error(),
    }
}

/// Sets each infinite value of `values` (none: an empty slice) to `error` of its pixel's
/// estimate.
fn fill_unknown(
    values: &mut [f64],
    estimates: &[PixelEstimate],
    error: impl Fn(&PixelEstimate) -> f64 + Sync,
) {
    (values.par_iter_mut().zip(estimates.par_iter())).for_each(|(value, e)| {
        if value.is_infinite() {
            *value = error(e);
        }
    });
}

/// Brings the pixel at `(x, y)` of the image to `count` samples, each standing for its share of
/// the pixel at `footprint_spp` samples (filtered textures), taking its surface passes from its
/// first sample into `aov`, and adds the rays traced to `counts`.
pub(crate) fn sample_pixel(
    context: &SampleContext<'_>,
    (x, y): (u32, u32),
    estimate: &mut PixelEstimate,
    aov: Option<&mut AovSample>,
    counts_and_footprint: (u32, u32),
    counts: &mut RayCounts,
) {
    let pattern = pixel_pattern(x, y, context.settings.seed);
    let at = (x, y);
    sample_sequence(
        context,
        at,
        pattern,
        estimate,
        aov,
        counts_and_footprint,
        counts,
    );
}

/// [`sample_pixel`] with the samples of the sequence keyed by `pattern`.
#[allow(clippy::too_many_arguments)]
fn sample_sequence(
    context: &SampleContext<'_>,
    (x, y): (u32, u32),
    pattern: u32,
    estimate: &mut PixelEstimate,
    mut aov: Option<&mut AovSample>,
    (count, footprint_spp): (u32, u32),
    counts: &mut RayCounts,
) {
    let first = estimate.count();
    // A pass takes the first sample's hit, so a pixel with passes traces that one.
    let traces_passes = first == 0 && aov.is_some();
    if first < count && !traces_passes && context.sees_nothing_at((x, y)) {
        // Every sample sees the background, which is what tracing them would add.
        estimate.add_repeated(context.scene.background(), count - first);
        counts.camera += u64::from(count - first);
        counts.untraced_camera += u64::from(count - first);
        return;
    }
    let cone = context.sample_cone(footprint_spp);
    for start in (first..count).step_by(RAY_BATCH as usize) {
        let end = count.min(start + RAY_BATCH);
        // The batch's camera rays first, as the uniform renderer makes its own: their square
        // roots and divisions overlap instead of each waiting in line before its trace (a
        // batch shorter than the array repeats its last ray, unused).
        let rays: [Ray; RAY_BATCH as usize] = std::array::from_fn(|k| {
            let index = (start + k as u32).min(end - 1);
            context.camera_ray((x, y), progressive_2d(index, pattern))
        });
        for (index, ray) in (start..end).zip(&rays) {
            let first_hit = match aov.as_deref_mut() {
                Some(aov) if index == 0 => Some(aov),
                _ => None,
            };
            let key = SampleKey {
                pattern,
                index,
                count: None,
            };
            estimate.add(context.trace_ray(ray, cone, key, first_hit, counts));
        }
    }
}

/// Camera rays a pixel's samples make before tracing them ([`sample_sequence`]).
const RAY_BATCH: u32 = 8;

/// What the rounds left over the bordered window.
struct Sampled {
    /// The audited MSE of the inner window ([`audit`]).
    estimated_mse: f64,
    estimates: Vec<PixelEstimate>,
    aov_samples: Vec<AovSample>,
    rounds: u32,
    stop: Stop,
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
        let film = Film::of_estimates(window.width(), window.height(), &estimates);
        let mut aov_samples = crop(&self.aov_samples, sampled, window).into_owned();
        for (aov, estimate) in aov_samples.iter_mut().zip(estimates.iter()) {
            aov.fill_sampling(
                context.selection,
                estimate.count(),
                Some(estimate.variance()),
            );
        }
        let sampling = stats::sampling_stats(
            &estimates,
            adaptive,
            self.rounds,
            self.stop,
            self.estimated_mse,
        );
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
/// The window an adaptive render of `window` of a `width` × `height` image samples: a pixel's
/// decisions depend on its neighbours', which depend on theirs one round earlier, so a border as
/// wide as the rounds that follow neighbours (clipped to the image) makes its pixels those of the
/// whole render.
pub(crate) fn sampled_window(
    window: PixelWindow,
    adaptive: &Adaptive,
    width: u32,
    height: u32,
) -> PixelWindow {
    let border = match adaptive.rule {
        ErrorRule::Image => NEIGHBOUR_ROUNDS,
        ErrorRule::Pixel => pixel_rule::refinement_rounds(adaptive),
    };
    bordered(window, border, width, height)
}

/// How many pixels the pilot of a planned render of a `width` × `height` image holds
/// ([`pilot`]), whatever window the render covers.
pub(crate) fn pilot_pixels(width: u32, height: u32) -> u64 {
    let stride = pilot::stride(width, height);
    u64::from(width.div_ceil(stride)) * u64::from(height.div_ceil(stride))
}

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

mod audit;
mod calibration;
mod image_rule;
#[cfg(test)]
mod image_tests;
mod missed;
mod pilot;
mod pixel_rule;
mod rounds;
mod settings;
mod stats;
#[cfg(test)]
pub(crate) mod tests;
