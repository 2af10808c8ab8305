//! The rounds of one adaptive render: what they share, the sampling of a round's pixels and of
//! the twins, and the plan of a round under a time limit.

use super::image_rule::{self, Aim, Budget, PixelState, Step};
use super::window::{WindowState, error_of};
use super::{Adaptive, Stop, sample_pixel, sample_twin};
use crate::integrator::RayCounts;
use crate::render::{PixelWindow, Progress, SampleContext};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

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
    /// Whether a round skipped rows at the time limit.
    pub timed_out: AtomicBool,
}

impl Rounds<'_> {
    /// Whether the time limit, if any, has passed.
    pub fn out_of_time(&self) -> bool {
        self.adaptive
            .time_limit
            .is_some_and(|limit| self.started.elapsed() >= limit)
    }

    /// The image rule's step for the next round under a time limit, from the window's own
    /// `states` (errors calibrated, falling as n^−`alpha`): the target, the sample budget left
    /// and the rays the time left pays for at the rate so far, whichever asks least.
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
        if let Some(limit) = adaptive.time_limit {
            let elapsed = self.started.elapsed().as_secs_f64();
            let rays = self
                .totals
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .total() as f64;
            let left = (limit.as_secs_f64() - elapsed).max(0.0) * rays / elapsed.max(1e-9);
            tighter(Budget::Rays(left), Stop::TimeLimit)?;
        }
        Ok(step)
    }

    /// Takes `round`'s samples, bringing each pixel to its target, row by row in parallel,
    /// filling the passes from each pixel's first sample and computing the error of each pixel
    /// sampled. After round 0 a row started past the time limit is skipped and the render marked
    /// timed out.
    pub fn sample(&self, round: u32, state: &mut WindowState) {
        let window = self.context.window;
        let ww = window.width() as usize;
        let rule = state.rule;
        let mut aov_rows = self.context.aov_rows(&mut state.aov_samples);
        // The squared errors are kept apart only under the pixel rule (empty otherwise).
        let mut squared_rows: Vec<Option<&mut [f64]>> = match state.squared.is_empty() {
            true => (0..window.height()).map(|_| None).collect(),
            false => state.squared.chunks_mut(ww).map(Some).collect(),
        };
        state
            .estimates
            .par_chunks_mut(ww)
            .zip(state.rays.par_chunks_mut(ww))
            .zip(state.errors.par_chunks_mut(ww))
            .zip(squared_rows.par_iter_mut())
            .zip(state.targets.par_chunks(ww))
            .zip(aov_rows.par_iter_mut())
            .enumerate()
            .for_each(
                |(row_index, (((((row, rays), errors), squared), targets), aov_row))| {
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
                        sample_pixel(
                            self.context,
                            (window.x0 + column as u32, y),
                            estimate,
                            aov,
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
