//! The pilot of an image-rule render: a fixed lattice of pixels, one in the middle of every
//! [`stride`]² block of the image, rendered through the rounds by their own estimates alone.
//! Their rounds decide the image-wide numbers of the allocation, each round's step
//! ([`super::image_rule::next_step`]) and when to stop, from a sample of the image that
//! does not depend on which part of it a render holds: a crop or a tile computes the same pilot
//! as the whole render, so its pixels follow the same thresholds and equal the whole render's.
//!
//! In a whole render the pilot's pixels are part of the image and cost nothing extra; a crop or a
//! tile also renders those outside it, at the pilot's counts, with their twins: 1/16 of the rest of
//! the image at the usual stride of 4, a quarter at 2, all of it at 1 (images under 4096 pixels).

use super::calibration::{self, Calibration, Twin};
use super::image_rule::{self, Aim, Budget, PixelState, Step};
use super::missed::follow_neighbours;
use super::{Adaptive, NEIGHBOUR_ROUNDS, Stop, sample_pixel};
use crate::aov::AovSample;
use crate::film::{PixelEstimate, SecondMoment};
use crate::integrator::RayCounts;
use crate::render::{Progress, RenderError, SampleContext};
use rayon::prelude::*;

/// The fewest pixels a pilot holds: below this the lattice is made finer. With 256, a 48x48
/// image had a pilot of 576 pixels, whose few flat twins met none of the dots of
/// `features_the_first_samples_miss_are_found` and stopped the render with them missed.
const MIN_PILOT_PIXELS: u32 = 1024;

/// The most rounds a plan has: a pixel doubles at most log₂(max/min) times, but rounds may skip
/// it; past this many the plan stops (far beyond what the bundled scenes take, about 10).
pub(super) const MAX_ROUNDS: usize = 40;

/// The spacing of the pilot's lattice in a `width` × `height` image: 4, or finer (2, then 1)
/// where that would leave fewer than [`MIN_PILOT_PIXELS`].
pub(super) fn stride(width: u32, height: u32) -> u32 {
    [4, 2]
        .into_iter()
        .find(|&s| (width / s) * (height / s) >= MIN_PILOT_PIXELS)
        .unwrap_or(1)
}

/// One pilot pixel at the end of the plan.
#[derive(Clone, Debug)]
pub(super) struct PilotPixel {
    /// Its column and row in the image.
    pub at: (u32, u32),
    /// Its samples.
    pub estimate: PixelEstimate,
    /// Rays its samples traced.
    pub rays: u64,
    /// Its surface passes, from its first sample (when passes are selected).
    pub aov: Option<AovSample>,
    /// Its samples' second moment (when the variance pass is selected; boxed, as the twin).
    pub moment: Option<Box<SecondMoment>>,
    /// Bit k set: round k sampled it.
    pub rounds: u64,
    /// Its twin, if it got one after its first round ([`calibration`]): boxed, since about
    /// 1500 of the pilot's pixels have one and a twin is two estimates (a pilot pixel takes
    /// 224 bytes, 488 with the twin inline: 116 MB against 253 MB at 3840x2160).
    pub twin: Option<Box<Twin>>,
}

/// The state of a pixel with `count` samples, batch-means squared error `estimated` and `rays`
/// traced, its error corrected by `calibration`.
pub(super) fn state_of(
    (count, estimated): (u32, f64),
    rays: u64,
    calibration: &Calibration,
) -> PixelState {
    let count = count.max(1);
    PixelState {
        count,
        squared_error: calibration.corrected(count, estimated),
        cost: (rays as f64 / count as f64).max(1.0),
    }
}

/// The thresholds of every round after the first, and the pilot's pixels.
#[derive(Clone, Debug)]
pub(super) struct Plan {
    /// Round k + 1 brings each pixel to the count ([`Step::target`]) of `decisions[k].0` for
    /// its state under the calibration `decisions[k].1`.
    pub decisions: Vec<(Step, Calibration)>,
    /// The pilot's pixels, in row-major order.
    pub pixels: Vec<PilotPixel>,
    /// Rays the pilot traced.
    pub counts: RayCounts,
    /// Why the plan stopped.
    pub stop: Stop,
    /// The calibration of the error estimate after the last round.
    pub calibration: Calibration,
    /// Whether the pilot followed neighbours itself (it holds every pixel), so that its pixels
    /// need not follow them again in the image's rounds.
    pub followed: bool,
}

/// Renders the pilot of `context`'s image through its rounds (see the module documentation).
pub(super) fn plan(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    progress: &dyn Progress,
) -> Result<Plan, RenderError> {
    let (width, height) = (context.settings.width, context.settings.height);
    let stride = stride(width, height);
    let aov = context.selection.any().then_some(AovSample::MISS);
    let moment = context
        .selection
        .variance
        .then(Box::<SecondMoment>::default);
    let mut pixels: Vec<PilotPixel> = (stride / 2..height)
        .step_by(stride as usize)
        .flat_map(|y| {
            (stride / 2..width)
                .step_by(stride as usize)
                .map(move |x| (x, y))
        })
        .map(|at| PilotPixel {
            at,
            estimate: PixelEstimate::default(),
            rays: 0,
            aov,
            moment: moment.clone(),
            rounds: 0,
            twin: None,
        })
        .collect();
    // A pilot of every pixel follows neighbours as the image does.
    let whole_width = (stride == 1).then_some(width as usize);
    let target_mse = (adaptive.target_error > 0.0).then(|| adaptive.target_error.powi(2));
    let budget = adaptive.spp_budget.map(|spp| spp * pixels.len() as f64);
    let mut decisions = Vec::new();
    let mut counts = RayCounts::default();
    let mut step = None;
    let mut stop = Stop::MaxSpp;
    let mut calibration = Calibration::NONE;
    for round in 0..MAX_ROUNDS {
        let targets = round_targets(adaptive, &pixels, round, step, whole_width);
        counts += sample_round(context, adaptive, &mut pixels, round, targets);
        if round == 0 {
            let candidates: Vec<_> = (pixels.par_iter())
                .map(|p| (p.at, calibration::is_flat(&p.estimate)))
                .collect();
            for (k, twin) in calibration::choose_twins(context.settings.seed, &candidates) {
                pixels[k].twin = Some(Box::new(twin));
            }
            counts += catch_up_twins(context, adaptive, &mut pixels);
        }
        if progress.cancelled() {
            return Err(RenderError::Cancelled);
        }
        let estimated: Vec<(u32, f64)> = pixels
            .par_iter()
            .map(|p| (p.estimate.count(), p.estimate.squared_error()))
            .collect();
        calibration = Calibration::fit(
            pixels
                .iter()
                .filter_map(|p| p.twin.as_deref().map(|t| (&p.estimate, t))),
            estimated.iter().copied(),
        );
        let states: Vec<PixelState> = pixels
            .iter()
            .zip(&estimated)
            .map(|(p, &e)| state_of(e, p.rays, &calibration))
            .collect();
        let taken: f64 = states.iter().map(|s| s.count as f64).sum();
        let aim = Aim {
            target_mse,
            budget: budget.map(|b| Budget::Samples(b - taken)),
            max_spp: adaptive.max_spp,
            alpha: calibration.alpha,
        };
        step = image_rule::next_step(&states, &aim).map(|t| (t, calibration));
        match step {
            Some(decision) => decisions.push(decision),
            None => {
                stop = why_stopped(&states, &aim);
                break;
            }
        }
    }
    Ok(Plan {
        decisions,
        pixels,
        counts,
        stop,
        calibration,
        followed: whole_width.is_some(),
    })
}

/// Why the plan stops at `states` when [`image_rule::next_step`] gives no step for `aim`: the
/// target is met, no pixel below the maximum count has an error left, or the budget cannot pay
/// for another round.
fn why_stopped(states: &[PixelState], aim: &Aim) -> Stop {
    let mse = image_rule::mean_squared_error(states);
    let open = states
        .iter()
        .any(|s| s.count < aim.max_spp && s.squared_error > 0.0);
    match (aim.target_mse, open, aim.budget) {
        (Some(target), ..) if mse <= target => Stop::Converged,
        (_, true, Some(_)) => Stop::Budget,
        _ => Stop::MaxSpp,
    }
}

/// Each pilot pixel's count after `round`: `min_spp` in round 0, then the count `step` gives it
/// under its calibration. When the pilot holds every pixel of the image (`width` wide), the
/// neighbour rounds follow as in the image ([`super::missed::follow_neighbours`]); the second element
/// tells which pixels are sampled by their own estimate.
fn round_targets(
    adaptive: &Adaptive,
    pixels: &[PilotPixel],
    round: usize,
    step: Option<(Step, Calibration)>,
    whole_width: Option<usize>,
) -> (Vec<u32>, Vec<bool>) {
    let mut targets: Vec<u32> = pixels
        .par_iter()
        .map(|pixel| match step {
            None => adaptive.min_spp,
            Some((step, calibration)) => {
                let estimated = (pixel.estimate.count(), pixel.estimate.squared_error());
                step.target(
                    &state_of(estimated, pixel.rays, &calibration),
                    adaptive.max_spp,
                )
            }
        })
        .collect();
    let counts: Vec<u32> = pixels.iter().map(|p| p.estimate.count()).collect();
    let own: Vec<bool> = targets.iter().zip(&counts).map(|(t, c)| t > c).collect();
    if let Some(width) = whole_width
        && (1..=NEIGHBOUR_ROUNDS as usize).contains(&round)
    {
        let max_spp = adaptive.max_spp;
        let follow = follow_neighbours(&own, width, |i, j| {
            counts[i] < max_spp && counts[i] <= counts[j]
        });
        for (i, target) in targets.iter_mut().enumerate() {
            if follow[i] && !own[i] {
                *target = (*target).max((2 * counts[i]).min(max_spp));
            }
        }
    }
    (targets, own)
}

/// Samples `round` in the pilot: each pixel to its count in `targets` (see [`round_targets`]),
/// and its twin as far; `own` marks the pixels the round samples by their own estimate.
fn sample_round(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    pixels: &mut [PilotPixel],
    round: usize,
    (targets, own): (Vec<u32>, Vec<bool>),
) -> RayCounts {
    sum_counts(
        (pixels.par_iter_mut().zip(targets).zip(own)).map(|((pixel, target), own)| {
            if target <= pixel.estimate.count() {
                return RayCounts::default();
            }
            if own {
                pixel.rounds |= 1 << round;
            }
            let mut counts = RayCounts::default();
            sample_pixel(
                context,
                pixel.at,
                &mut pixel.estimate,
                (pixel.aov.as_mut(), pixel.moment.as_deref_mut()),
                (target, adaptive.max_spp),
                &mut counts,
            );
            pixel.rays += counts.total();
            counts += catch_up_twin(context, adaptive, pixel);
            counts
        }),
    )
}

/// Brings every pilot pixel's twin to its pixel's count.
fn catch_up_twins(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    pixels: &mut [PilotPixel],
) -> RayCounts {
    sum_counts(
        pixels
            .par_iter_mut()
            .map(|pixel| catch_up_twin(context, adaptive, pixel)),
    )
}

/// Brings `pixel`'s twin, if it has one, to the pixel's count.
fn catch_up_twin(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    pixel: &mut PilotPixel,
) -> RayCounts {
    let mut counts = RayCounts::default();
    if let Some(twin) = &mut pixel.twin {
        let footprint = (pixel.estimate.count(), adaptive.max_spp);
        calibration::sample_twin(context, pixel.at, twin, footprint, &mut counts);
    }
    counts
}

/// The sum of the rays of parallel work.
fn sum_counts(counts: impl ParallelIterator<Item = RayCounts>) -> RayCounts {
    counts.reduce(RayCounts::default, |mut a, b| {
        a += b;
        a
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lattice_is_fine_enough() {
        assert_eq!(stride(480, 270), 4);
        assert_eq!(stride(100, 100), 2);
        assert_eq!(stride(48, 48), 1);
    }
}
