//! Adaptive sampling: every pixel starts with a few samples, then rounds add samples where they
//! lower the error most, by one of two rules ([`ErrorRule`]).
//!
//! - **Image rule** (the default, `--target-error`): the image's mean squared error is the sum of
//!   its pixels' ([`PixelEstimate::squared_error`]); each round doubles the pixels whose estimated
//!   squared error per ray (sᵢ/cᵢ) is above a threshold chosen so that the predicted image
//!   error meets the target, or the work meets the budget (`image_rule`). The thresholds come
//!   from a pilot, a fixed lattice of the image's pixels (`pilot`).
//! - **Pixel rule** (`--pixel-error`): every pixel is brought to one relative error of its display
//!   value ([`PixelEstimate::relative_error`]); round k brings the pixels it samples to
//!   `min_spp`·2^k samples: every pixel still above the target (after the first round, above
//!   [`FIRST_ROUND_MARGIN`] × the target).
//! - **Neighbours**: a feature that crosses into a pixel can be missed by all of its first
//!   samples, so in the first [`NEIGHBOUR_ROUNDS`] rounds a pixel is also sampled when a neighbour
//!   is, by its own estimate, and it has no more samples than that neighbour.
//! - **Slivers**: an edge along the border of two flat pixels (whose samples all agree) may
//!   cross into either by a sliver every sample missed, so in the first [`SLIVER_ROUNDS`] rounds
//!   a flat pixel beside a flat neighbour of another value is sampled too (`missed`).
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
//! - **The reported error** is an audit of the finished window (`audit`): pixels drawn by their
//!   estimated error are sampled twice more, which measures their actual error without bias.
//!   The calibration by twins (`calibration`) steers the rounds; the audit says where they got.

use crate::aov::{AovSample, Aovs};
use crate::film::{Film, PixelEstimate, SecondMoment};
use crate::integrator::RayCounts;
use crate::math::Ray;
use crate::render::empty_tiles::EmptyTiles;
use crate::render::{PixelWindow, Progress, RenderError, Rendered, SampleContext};
use crate::sampler::{SampleKey, pixel_pattern, progressive_2d};
pub use calibration::Calibration;
pub(crate) use calibration::{Twin, choose_twins, is_flat, sample_twin};
use glam::{DVec3, Vec3};
use rounds::Rounds;
pub use settings::{
    Adaptive, AdaptiveError, DEFAULT_MAX_SPP, DEFAULT_MIN_SPP, ErrorRule, MAX_TIME_LIMIT_SECS,
    MIN_FIRST_ROUND, MIN_TIME_LIMIT_SECS, time_limit_from_secs,
};
pub use stats::{ErrorStats, PixelErrors, RoundSummary, SamplingStats, Stop, estimated_rmse};
use std::borrow::Cow;
use std::sync::Mutex;
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use window::WindowState;

/// The first refinement rounds in which the neighbours of a pixel sampled by its own estimate are
/// sampled too, whatever their own error. Measured on the defense scene (480x270), per-pixel
/// rule: without neighbours, a first round of 8 left an error floor near 2e-3 linear RMSE;
/// following neighbours in every round cost 1.2–1.4× the CPU time of this at equal RMSE.
pub const NEIGHBOUR_ROUNDS: u32 = 3;
/// The first refinement rounds in which a flat pixel beside a flat neighbour of another value is
/// sampled (`missed`): an edge between them may cross into either by a sliver all their
/// samples missed. On defense (480x270, one thread, seeds 1 to 3) it lowered the true error 5% at
/// target 0.002, 13–17% at 0.001 and 27–40% at 0.0005 for 0.4% more rays (a horizon in one
/// row); 3 rounds, or a least difference of 0.005 instead of `missed::SLIVER_CONTRAST`, gave
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
        deadline_nanos: Rounds::initial_deadline(adaptive),
    };
    let mut state = WindowState::new(rounds.context, plan.as_ref());
    let inner_context = context.with_window(inner).with_empty_tiles(&empty_tiles);
    let (round, stop, calibration) = rounds.run(&mut state, plan.as_ref(), &inner_context)?;
    if let Some(plan) = &plan {
        *rounds.totals.lock().unwrap_or_else(|e| e.into_inner()) += plan.counts;
    }
    let inner_pixels = InnerPixels::of(&state, window, inner);
    let (estimated_mse, audit_counts) = audit::audit(
        &inner_context,
        inner_pixels.pixels(),
        &calibration,
        adaptive.max_spp,
    );
    *rounds.totals.lock().unwrap_or_else(|e| e.into_inner()) += audit_counts;
    let sampled = Sampled {
        estimated_mse,
        relative_errors: match adaptive.rule {
            ErrorRule::Pixel => Some(state.errors),
            ErrorRule::Image => None,
        },
        estimates: state.estimates,
        aov_samples: state.aov_samples,
        moments: state.moments,
        rounds: round,
        stop,
        counts: rounds
            .totals
            .into_inner()
            .unwrap_or_else(|e| e.into_inner()),
    };
    Ok(sampled.finish(&context.with_window(inner), adaptive, window))
}

/// Brings the pixel at `(x, y)` of the image to `count` samples, each standing for its share of
/// the pixel at `footprint_spp` samples (filtered textures), taking its surface passes from its
/// first sample into `aov` and every sample's deviation to `moment` (the variance pass's), and
/// adds the rays traced to `counts`.
pub(crate) fn sample_pixel(
    context: &SampleContext<'_>,
    (x, y): (u32, u32),
    estimate: &mut PixelEstimate,
    (aov, moment): (Option<&mut AovSample>, Option<&mut SecondMoment>),
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
        (aov, moment),
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
    (mut aov, mut moment): (Option<&mut AovSample>, Option<&mut SecondMoment>),
    (count, footprint_spp): (u32, u32),
    counts: &mut RayCounts,
) {
    let first = estimate.count();
    // A pass takes the first sample's hit, so a pixel with passes traces that one.
    let traces_passes = first == 0 && aov.is_some();
    if first < count && !traces_passes && context.sees_nothing_at((x, y)) {
        // Every sample sees the background, which is what tracing them would add.
        estimate.add_repeated(context.scene.background(), count - first, moment);
        counts.camera += u64::from(count - first);
        counts.untraced_camera += u64::from(count - first);
        return;
    }
    let cone = context.sample_cone(footprint_spp);
    for start in (first..count).step_by(RAY_BATCH as usize) {
        let end = count.min(start + RAY_BATCH);
        // The batch's camera rays first, as the uniform renderer makes its own: their square
        // roots and divisions overlap (four at a time in AVX2 registers where the CPU has them)
        // instead of each waiting in line before its trace (a batch shorter than the array
        // repeats its last ray, unused).
        let positions: [[f64; 2]; RAY_BATCH as usize] = std::array::from_fn(|k| {
            let index = (start + k as u32).min(end - 1);
            let (dx, dy) = progressive_2d(index, pattern);
            [x as f64 + dx, y as f64 + dy]
        });
        let mut rays = [Ray::new(DVec3::ZERO, DVec3::ZERO); RAY_BATCH as usize];
        context.camera_rays(&positions, &mut rays);
        // Traced first, then added in order with their display encodings made together.
        let mut radiances = [Vec3::ZERO; RAY_BATCH as usize];
        let key = |index: u32| SampleKey {
            pattern,
            index,
            count: None,
        };
        let traced = (end - start) as usize;
        // The pixel's first sample fills its passes, traced alone; the rest of the batch in one
        // call, as the uniform renderer traces its own.
        let alone = match aov.as_deref_mut() {
            Some(aov) if start == 0 => {
                radiances[0] = context.trace_ray(&rays[0], cone, key(0), Some(aov), counts);
                1
            }
            _ => 0,
        };
        let rest = alone..traced;
        let keys = |k: usize| key(start + (alone + k) as u32);
        let radiances_rest = &mut radiances[rest.clone()];
        context.trace_rays(&rays[rest], cone, keys, counts, radiances_rest);
        estimate.add_eight(&radiances, traced, moment.as_deref_mut());
    }
}

/// Camera rays a pixel's samples make before tracing them ([`sample_sequence`]).
const RAY_BATCH: u32 = 8;

/// The pixels of the inner window, as the audit reads them ([`audit::Pixels`]), out of the
/// bordered window's state. The rounds keep every pixel's batch-means squared error current
/// (each round computes those of the pixels it samples), which the audit's draw needs.
struct InnerPixels<'a> {
    estimates: Cow<'a, [PixelEstimate]>,
    rays: Cow<'a, [u64]>,
    squared_errors: Cow<'a, [f64]>,
}

impl<'a> InnerPixels<'a> {
    /// The pixels of `inner` out of `state`, over the bordered `window`.
    fn of(state: &'a WindowState, window: PixelWindow, inner: PixelWindow) -> InnerPixels<'a> {
        InnerPixels {
            estimates: crop(&state.estimates, window, inner),
            rays: crop(&state.rays, window, inner),
            squared_errors: crop(state.squared_errors(), window, inner),
        }
    }

    /// The pixels as the audit takes them.
    fn pixels(&self) -> audit::Pixels<'_> {
        audit::Pixels {
            estimates: &self.estimates,
            rays: &self.rays,
            squared_errors: &self.squared_errors,
        }
    }
}

/// What the rounds left over the bordered window.
struct Sampled {
    /// The audited MSE of the inner window (`audit`).
    estimated_mse: f64,
    /// Under the pixel rule, each pixel's relative error as the rounds left it.
    relative_errors: Option<Vec<f64>>,
    estimates: Vec<PixelEstimate>,
    aov_samples: Vec<AovSample>,
    /// Each pixel's samples' second moment (empty unless the variance pass is asked for).
    moments: Vec<SecondMoment>,
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
        let moments = crop(&self.moments, sampled, window);
        for (i, (aov, estimate)) in aov_samples.iter_mut().zip(estimates.iter()).enumerate() {
            let variance = moments.get(i).map(|m| m.variance(estimate.count()));
            aov.fill_sampling(context.selection, estimate.count(), variance);
        }
        let relative_errors = (self.relative_errors.as_deref()).map(|e| crop(e, sampled, window));
        debug_assert!(
            relative_errors
                .as_deref()
                .is_none_or(|errors| (errors.iter().zip(&*estimates))
                    .all(|(r, e)| r.to_bits() == e.relative_error().to_bits())),
            "the rounds left each pixel's own relative error"
        );
        let sampling = stats::sampling_stats(
            (&estimates, relative_errors.as_deref()),
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
/// (`pilot`), whatever window the render covers.
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
mod window;
