//! The rounds of one adaptive render: what they share, the sampling of a round's pixels and of
//! the twins, and the plan of a round under a time limit.

use super::audit::{self, AuditCost};
use super::image_rule::{self, Aim, Budget, PixelState, Step};
use super::pilot::Plan;
use super::window::{WindowState, error_of};
use super::{Adaptive, Calibration, ErrorRule, InnerPixels, Stop, sample_pixel, sample_twin};
use crate::integrator::RayCounts;
use crate::render::{PixelWindow, Progress, RenderError, SampleContext};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// What the rounds of one adaptive render share: the bordered window's context, the settings,
/// the window the caller asked for, and the running totals.
pub(super) struct Rounds<'a> {
    /// The context over the bordered window.
    pub context: &'a SampleContext<'a>,
    /// The sampling settings.
    pub adaptive: &'a Adaptive,
    /// The window the caller asked for (progress counts only its rows).
    pub inner: PixelWindow,
    /// Where rows done and cancellation are reported.
    pub progress: &'a dyn Progress,
    /// When the rounds started (for the time limit).
    pub started: Instant,
    /// Rays traced so far, twins' included.
    pub totals: Mutex<RayCounts>,
    /// Whether a round skipped rows at the rounds' deadline under a time limit.
    pub timed_out: AtomicBool,
    /// When the rounds must end, in nanoseconds from `started`, under a time limit (else
    /// `u64::MAX`): the limit less the time kept for the audit ([`Rounds::keep_time_for_audit`]).
    pub deadline_nanos: AtomicU64,
}

/// How long the rounds may take under a time `limit` when the audit that follows them is
/// expected to cost `audit` for the `rays` they traced so far: the limit less the audit's draw,
/// shared between the rounds and the audit's rays in the ratio of their rays. The audit draws
/// pixels by their own samples, so its rays grow with the render's, and the two are taken to keep
/// their ratio, each at the rounds' rate so far. Measured on the quadric grid (480x270, one
/// thread), the audit traced up to a fifth of the rounds' rays, and a time limit without this
/// share ran 35% over.
pub(super) fn rounds_time(limit: Duration, rays: f64, audit: AuditCost) -> Duration {
    let share = if rays > 0.0 && audit.rays > 0.0 {
        rays / (rays + audit.rays)
    } else {
        1.0
    };
    limit.saturating_sub(audit.draw).mul_f64(share)
}

impl Rounds<'_> {
    /// Samples the rounds of the window in `state` until the rule stops them, a time limit
    /// runs out or the caller cancels, under the pilot's `plan` where the render has one; the
    /// rounds taken, why they stopped and the last round's calibration (which the audit of
    /// `inner_context`'s window reads, as the reservation for it under a time limit does).
    pub fn run(
        &self,
        state: &mut WindowState,
        plan: Option<&Plan>,
        inner_context: &SampleContext<'_>,
    ) -> Result<(u32, Stop, Calibration), RenderError> {
        let window = self.context.window;
        let mut round = 0u32;
        loop {
            self.sample(round, state);
            // A planned render takes its calibration from the pilot, and its reported error from
            // the audit: twins of its own would only cost.
            if round == 0 && plan.is_none() {
                state.choose_twins(self.context);
            }
            self.sample_twins(state);
            if self.progress.cancelled() {
                return Err(RenderError::Cancelled);
            }
            // The round's calibration, made once: the audit's reservation, the next round's choice
            // (an unplanned render's, whose fallback is none), the round's summary and, after the
            // last round, the audit read it. Choosing the next round fills no error it reads: after
            // the first round only pilot pixels (a planned render's, which has no twins and takes
            // the pilot's calibration) have errors still unknown.
            let calibration = state.calibration_or(plan.map(|p| &p.calibration));
            self.keep_time_for_audit(state, inner_context, &calibration);
            let next = match self.adaptive.rule {
                ErrorRule::Pixel => state.select_by_pixel(self.adaptive, round + 1),
                ErrorRule::Image => state.select_by_image(
                    (self.adaptive, plan),
                    round + 1,
                    &calibration,
                    |states, alpha| self.unplanned_step(states, alpha),
                ),
            };
            let summary = state.summary(round, window, self.inner, self.adaptive, &calibration);
            self.progress.round_done(&summary);
            round += 1;
            if let Err(stop) = next {
                return Ok((round, stop, calibration));
            }
            if self.timed_out.load(Ordering::Relaxed) || self.out_of_time() {
                return Ok((round, Stop::TimeLimit, calibration));
            }
        }
    }

    /// The rounds' deadline under a time limit as [`Rounds::deadline_nanos`] gives it, initially
    /// the limit itself (`u64::MAX` without one).
    pub fn initial_deadline(adaptive: &Adaptive) -> AtomicU64 {
        let nanos = adaptive.time_limit.map_or(u64::MAX, |limit| {
            limit.as_nanos().min(u128::from(u64::MAX)) as u64
        });
        AtomicU64::new(nanos)
    }

    /// When the rounds must end, from `started`, under a time limit.
    fn deadline(&self) -> Option<Duration> {
        self.adaptive.time_limit?;
        Some(Duration::from_nanos(
            self.deadline_nanos.load(Ordering::Relaxed),
        ))
    }

    /// Whether the rounds' deadline under a time limit, if any, has passed.
    pub fn out_of_time(&self) -> bool {
        self.deadline()
            .is_some_and(|deadline| self.started.elapsed() >= deadline)
    }

    /// Under a time limit, moves the rounds' deadline so that the audit of `state`'s inner
    /// window (`inner_context`'s), whose errors `calibration` corrects, fits in the limit after
    /// them ([`rounds_time`]). Not needed once the deadline has passed: the rounds stop.
    pub fn keep_time_for_audit(
        &self,
        state: &WindowState,
        inner_context: &SampleContext<'_>,
        calibration: &Calibration,
    ) {
        let Some(limit) = self.adaptive.time_limit else {
            return;
        };
        if self.out_of_time() {
            return;
        }
        let pixels = InnerPixels::of(state, self.context.window, self.inner);
        let audit = audit::expected_cost(inner_context, &pixels.pixels(), calibration);
        let time = rounds_time(limit, self.rays_so_far(), audit);
        let nanos = time.as_nanos().min(u128::from(u64::MAX)) as u64;
        self.deadline_nanos.store(nanos, Ordering::Relaxed);
    }

    /// Rays traced so far, twins' included.
    fn rays_so_far(&self) -> f64 {
        self.totals
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .total() as f64
    }

    /// The image rule's step for the next round under a time limit, from the window's own
    /// `states` (errors calibrated, falling as n^−`alpha`): the target, the sample budget left
    /// and the rays the time left before the rounds' deadline pays for at the rate so far,
    /// whichever asks least.
    pub fn unplanned_step(&self, states: &[PixelState], alpha: f64) -> Result<Step, Stop> {
        let adaptive = self.adaptive;
        let aim = |budget| Aim {
            target_mse: (adaptive.target_error > 0.0).then(|| adaptive.target_error.powi(2)),
            budget,
            max_spp: adaptive.max_spp,
            alpha,
        };
        let mut step = image_rule::next_step(states, &aim(None)).ok_or(Stop::Converged)?;
        let mut tighter = |budget, stop| -> Result<(), Stop> {
            let s = image_rule::next_step(states, &aim(Some(budget))).ok_or(stop)?;
            if s.lambda > step.lambda {
                step = s;
            }
            Ok(())
        };
        if let Some(spp) = adaptive.spp_budget {
            let taken: f64 = states.iter().map(|s| s.count as f64).sum();
            tighter(
                Budget::Samples(spp * states.len() as f64 - taken),
                Stop::Budget,
            )?;
        }
        if let Some(deadline) = self.deadline() {
            let elapsed = self.started.elapsed().as_secs_f64();
            let rays = self.rays_so_far();
            let left = (deadline.as_secs_f64() - elapsed).max(0.0) * rays / elapsed.max(1e-9);
            tighter(Budget::Rays(left), Stop::TimeLimit)?;
        }
        Ok(step)
    }

    /// Takes `round`'s samples, bringing each pixel to its target, row by row in parallel,
    /// filling the passes from each pixel's first sample and computing the error of each pixel
    /// sampled. After round 0 a row started past the rounds' deadline (a time limit's) is
    /// skipped and the render marked timed out.
    pub fn sample(&self, round: u32, state: &mut WindowState) {
        let window = self.context.window;
        let ww = window.width() as usize;
        let rule = state.rule;
        // The passes, the moments (the variance pass's) and the squared errors (the pixel
        // rule's) are kept only where asked for.
        let mut aov_rows = self.context.optional_rows(&mut state.aov_samples);
        let mut moment_rows = self.context.optional_rows(&mut state.moments);
        let mut squared_rows = self.context.optional_rows(&mut state.squared);
        state
            .estimates
            .par_chunks_mut(ww)
            .zip(state.rays.par_chunks_mut(ww))
            .zip(state.errors.par_chunks_mut(ww))
            .zip(squared_rows.par_iter_mut())
            .zip(state.targets.par_chunks(ww))
            .zip(aov_rows.par_iter_mut().zip(moment_rows.par_iter_mut()))
            .enumerate()
            .for_each(
                |(row_index, (((((row, rays), errors), squared), targets), (aov_row, moments)))| {
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
                    let mut counts = RayCounts::default();
                    let pixels = row.iter_mut().zip(rays).zip(errors.iter_mut());
                    for (column, ((estimate, pixel_rays), error)) in pixels.enumerate() {
                        if targets[column] <= estimate.count() {
                            continue;
                        }
                        let before = counts.total();
                        let aov = aov_row.as_deref_mut().map(|aovs| &mut aovs[column]);
                        let moment = moments.as_deref_mut().map(|m| &mut m[column]);
                        sample_pixel(
                            self.context,
                            (window.x0 + column as u32, y),
                            estimate,
                            (aov, moment),
                            (targets[column], self.adaptive.max_spp),
                            &mut counts,
                        );
                        *pixel_rays += counts.total() - before;
                        *error = error_of(rule, estimate);
                        if let Some(squared) = squared.as_deref_mut() {
                            squared[column] = estimate.squared_error();
                        }
                    }
                    *self.totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
                    row_done();
                },
            );
    }

    /// Brings every twin to its pixel's count, row by row in parallel.
    pub fn sample_twins(&self, state: &mut WindowState) {
        let window = self.context.window;
        let ww = window.width() as usize;
        state
            .twins
            .par_iter_mut()
            .zip(state.estimates.par_chunks(ww))
            .enumerate()
            .for_each(|(row_index, (twins, row))| {
                let y = window.y0 + row_index as u32;
                let mut counts = RayCounts::default();
                for (column, twin) in twins.iter_mut() {
                    let at = (window.x0 + *column as u32, y);
                    let footprint = (row[*column].count(), self.adaptive.max_spp);
                    sample_twin(self.context, at, twin, footprint, &mut counts);
                }
                *self.totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            });
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{disc, settings};
    use super::*;
    use crate::aov::AovSelection;
    use crate::render::{NoProgress, RenderSettings};

    /// After a round under a time limit, the rounds' deadline is the limit less the audit's
    /// expected share (the draw of a 96x64 window takes well under a second), which is what rows
    /// are then cut at; without a time limit there is no deadline.
    #[test]
    fn a_round_under_a_time_limit_moves_the_deadline_for_the_audit() {
        let limit = Duration::from_secs(100);
        let adaptive = Adaptive {
            target_error: 0.0,
            time_limit: Some(limit),
            ..Adaptive::default()
        };
        let base = RenderSettings {
            width: 96,
            height: 64,
            ..settings(adaptive)
        };
        let scene = disc();
        let context = SampleContext::new(&scene, &base, AovSelection::NONE).unwrap();
        let rounds = Rounds {
            context: &context,
            adaptive: &adaptive,
            inner: context.window,
            progress: &NoProgress,
            started: Instant::now(),
            totals: Mutex::new(RayCounts::default()),
            timed_out: AtomicBool::new(false),
            deadline_nanos: Rounds::initial_deadline(&adaptive),
        };
        assert_eq!(rounds.deadline(), Some(limit));
        let mut state = WindowState::new(&context, None);
        rounds.sample(0, &mut state);
        rounds.keep_time_for_audit(&state, &context, &state.calibration_or(None));
        let rays = rounds.rays_so_far();
        let pixels = InnerPixels::of(&state, context.window, context.window);
        let audit = audit::expected_cost(&context, &pixels.pixels(), &Calibration::NONE).rays;
        assert!(audit > 0.0 && rays > 0.0, "{audit} {rays}");
        let share = limit.mul_f64(rays / (rays + audit));
        let deadline = rounds.deadline().unwrap();
        assert!(
            deadline <= share && deadline + Duration::from_secs(1) > share && deadline < limit,
            "deadline {deadline:?}, the rounds' share {share:?}"
        );
        assert!(!rounds.out_of_time());
        rounds.deadline_nanos.store(0, Ordering::Relaxed);
        assert!(
            rounds.out_of_time(),
            "rows are cut at the deadline, not the limit"
        );
        let untimed = Adaptive {
            time_limit: None,
            target_error: 0.01,
            ..adaptive
        };
        let rounds = Rounds {
            adaptive: &untimed,
            deadline_nanos: Rounds::initial_deadline(&untimed),
            ..rounds
        };
        rounds.keep_time_for_audit(&state, &context, &state.calibration_or(None));
        assert_eq!(rounds.deadline(), None);
        assert!(!rounds.out_of_time());
    }

    /// The rounds get the limit less the draw, shared with the audit's rays in proportion to
    /// their own; all of it when the audit is expected to trace nothing, none of it when the
    /// draw alone takes longer than the limit.
    #[test]
    fn the_rounds_leave_the_audit_its_time() {
        let cost = |rays: f64, draw_ms: u64| AuditCost {
            rays,
            draw: Duration::from_millis(draw_ms),
        };
        let limit = Duration::from_secs(2);
        assert_eq!(
            rounds_time(limit, 3e6, cost(1e6, 0)),
            Duration::from_millis(1500)
        );
        assert_eq!(
            rounds_time(limit, 3e6, cost(1e6, 400)),
            Duration::from_millis(1200)
        );
        assert_eq!(rounds_time(limit, 3e6, cost(0.0, 0)), limit);
        assert_eq!(rounds_time(limit, 0.0, cost(1e6, 0)), limit);
        assert_eq!(rounds_time(limit, 3e6, cost(1e6, 2500)), Duration::ZERO);
    }
}
