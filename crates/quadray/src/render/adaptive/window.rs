//! The pixels of an adaptive render's bordered window between rounds ([`WindowState`]): their
//! estimates, rays and errors, the count each next round brings them to, the pilot's pixels
//! among them, and the twins; and the two rules' choice of the next round's pixels from them.

use super::calibration::{self, Calibration, Twin};
use super::image_rule::{PixelState, Step};
use super::pilot::{Plan, state_of};
use super::{
    Adaptive, ErrorRule, NEIGHBOUR_ROUNDS, RoundSummary, SLIVER_ROUNDS, Stop, missed, pixel_rule,
};
use crate::aov::AovSample;
use crate::film::{PixelEstimate, SecondMoment};
use crate::render::{PixelWindow, SampleContext};
use rayon::prelude::*;

/// The pixels of the bordered window between rounds.
pub(super) struct WindowState {
    /// The rule the render samples by.
    pub(super) rule: ErrorRule,
    /// Width of the window.
    pub(super) width: usize,
    pub(super) estimates: Vec<PixelEstimate>,
    /// Rays each pixel's samples traced.
    pub(super) rays: Vec<u64>,
    /// Each pixel's relative error after the last round (pixel rule) or its batch-means squared
    /// error (image rule), recomputed for the pixels a round samples.
    pub(super) errors: Vec<f64>,
    /// Under the pixel rule, each pixel's batch-means squared error, kept as `errors` is (the
    /// calibration, the summary, the sliver rounds and the audit read it every round); empty
    /// under the image rule, whose `errors` it would repeat ([`WindowState::squared_errors`]).
    pub(super) squared: Vec<f64>,
    /// The count the next round brings each pixel to (at most its own: not sampled).
    pub(super) targets: Vec<u32>,
    pub(super) aov_samples: Vec<AovSample>,
    /// Each pixel's samples' second moment, when the variance pass is asked for (else empty).
    pub(super) moments: Vec<SecondMoment>,
    /// For pilot pixels inside the window, the rounds that sample them (bit k: round k), which
    /// the pilot took already; 0 for the others (the pilot samples each of its pixels in round
    /// 0, so a pilot pixel's bits are never 0). Half the bytes of an `Option`.
    pub(super) pilot_rounds: Vec<u64>,
    /// Each row's twins ([`calibration`]), chosen after the first round when the render has no
    /// plan (the pixel rule, or a time limit): the column and the twin.
    pub(super) twins: Vec<Vec<(usize, Twin)>>,
}

impl WindowState {
    /// The window of `context` before any sample: every pixel wants the first round, except the
    /// pilot's pixels, which hold the plan's samples.
    pub(super) fn new(context: &SampleContext<'_>, plan: Option<&Plan>) -> WindowState {
        let window = context.window;
        let pixels = window.width() as usize * window.height() as usize;
        let min_spp = context.settings.adaptive.map_or(1, |a| a.min_spp);
        let rule = context
            .settings
            .adaptive
            .map_or(ErrorRule::Image, |a| a.rule);
        let mut state = WindowState {
            rule,
            width: window.width() as usize,
            // Filled in parallel, so that the pages are faulted in on every thread (at 3840x2160
            // the estimates are 1.1 GB); the zeros come from the allocator.
            estimates: (0..pixels)
                .into_par_iter()
                .map(|_| PixelEstimate::default())
                .collect(),
            rays: vec![0; pixels],
            errors: (0..pixels).into_par_iter().map(|_| f64::INFINITY).collect(),
            squared: match rule {
                ErrorRule::Pixel => (0..pixels).into_par_iter().map(|_| f64::INFINITY).collect(),
                ErrorRule::Image => Vec::new(),
            },
            targets: (0..pixels).into_par_iter().map(|_| min_spp).collect(),
            aov_samples: context.aov_buffer(),
            moments: match context.selection.variance {
                true => (0..pixels)
                    .into_par_iter()
                    .map(|_| SecondMoment::default())
                    .collect(),
                false => Vec::new(),
            },
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
            if let (Some(moment), Some(slot)) = (&pixel.moment, state.moments.get_mut(i)) {
                *slot = **moment;
            }
        }
        state
    }

    /// Each pixel's batch-means squared error ([`PixelEstimate::squared_error`]), current after
    /// every round.
    pub(super) fn squared_errors(&self) -> &[f64] {
        match self.rule {
            ErrorRule::Image => &self.errors,
            ErrorRule::Pixel => &self.squared,
        }
    }

    /// Computes the errors ([`error_of`], and under the pixel rule the squared errors) of the
    /// pixels that have none yet (infinite: the pilot's, at the first selection). A round
    /// computes those of the pixels it samples as it goes ([`super::rounds::Rounds::sample`]), while their
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
    pub(super) fn choose_twins(&mut self, context: &SampleContext<'_>) {
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
    pub(super) fn select_by_pixel(&mut self, adaptive: &Adaptive, round: u32) -> Result<(), Stop> {
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
    /// time limit, from `unplanned_step` of the window's own states under `calibration` (the
    /// window's own, [`WindowState::calibration_or`] without a fallback) and its α (the step the
    /// time left pays for, [`super::rounds::Rounds::unplanned_step`]); `Err` with the reason to
    /// stop when it samples none.
    pub(super) fn select_by_image(
        &mut self,
        (adaptive, plan): (&Adaptive, Option<&Plan>),
        round: u32,
        calibration: &Calibration,
        unplanned_step: impl FnOnce(&[PixelState], f64) -> Result<Step, Stop>,
    ) -> Result<(), Stop> {
        self.fill_unknown_errors();
        // The step, the calibration it was decided with, and the states an unplanned step was
        // chosen from (a planned render's are made on the way below: a vector of states faulted
        // in 24 bytes a pixel of fresh memory every round).
        let (step, calibration, states) = match plan {
            Some(plan) => {
                let decision = plan.decisions.get(round as usize - 1);
                let (step, calibration) = decision.copied().ok_or(plan.stop)?;
                (step, calibration, None)
            }
            None => {
                let states: Vec<PixelState> = self.states(calibration).collect();
                let step = unplanned_step(&states, calibration.alpha)?;
                (step, *calibration, Some(states))
            }
        };
        let max_spp = adaptive.max_spp;
        // Each pixel's own target, its state's count, and whether its own estimate refines it;
        // pilot pixels hold their samples already, and count as refined by their own estimate in
        // the rounds that sampled them.
        let choose = |state: PixelState, pilot: u64| match pilot {
            0 => {
                let target = step.target(&state, max_spp);
                (target, (state.count, target > state.count))
            }
            bits => (0, (state.count, bits >> round & 1 == 1)),
        };
        let (mut targets, (counts, own)): (Vec<u32>, (Vec<u32>, Vec<bool>)) = match states {
            Some(states) => (states.into_par_iter().zip(&self.pilot_rounds))
                .map(|(state, &pilot)| choose(state, pilot))
                .unzip(),
            None => (self.states(&calibration).zip(&self.pilot_rounds))
                .map(|(state, &pilot)| choose(state, pilot))
                .unzip(),
        };
        // Pilot pixels follow neighbours and slivers too, unless the pilot followed neighbours
        // itself: a sparse pilot samples its pixels by their own estimates only, and a pilot
        // pixel whose first samples all missed an edge was left with them.
        let pilot_followed = plan.is_some_and(|p| p.followed);
        let may_follow = |i: usize| !(pilot_followed && self.pilot_rounds[i] != 0);
        let follow = (round <= NEIGHBOUR_ROUNDS).then(|| {
            missed::follow_neighbours(&own, self.width, |i, j| {
                let (count, other) = (counts[i], counts[j]);
                count < max_spp && count <= other && may_follow(i)
            })
        });
        // Under the image rule `errors` holds each pixel's batch-means squared error.
        let across = (round <= SLIVER_ROUNDS)
            .then(|| missed::across_flat_edges(&self.estimates, &self.errors, self.width));
        for (i, (target, &count)) in targets.iter_mut().zip(&counts).enumerate() {
            let followed = follow.as_ref().is_some_and(|f| f[i] && !own[i]);
            let sliver = across.as_ref().is_some_and(|a| a[i] && may_follow(i));
            if followed || sliver {
                *target = (*target).max((2 * count).min(max_spp));
            }
        }
        if !targets.iter().zip(&counts).any(|(&t, &count)| t > count) && plan.is_none() {
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
    /// squared errors), in pixel order.
    fn states<'a>(
        &'a self,
        calibration: &'a Calibration,
    ) -> impl IndexedParallelIterator<Item = PixelState> + 'a {
        self.estimates
            .par_iter()
            .zip(&self.errors)
            .zip(&self.rays)
            .map(|((e, &estimated), &r)| state_of((e.count(), estimated), r, calibration))
    }

    /// The calibration from the window's own twins, backed by `fallback` at counts with too few.
    pub(super) fn calibration_or(&self, fallback: Option<&Calibration>) -> Calibration {
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
    pub(super) fn summary(
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
pub(super) fn error_of(rule: ErrorRule, estimate: &PixelEstimate) -> f64 {
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
