//! What an adaptive render reports: where it stands after each round, and the sample counts and
//! error it reached (also the plain statistics of a uniform render).

use super::calibration::Calibration;
use super::{Adaptive, ErrorRule};
use crate::film::PixelEstimate;
use rayon::prelude::*;

/// Where an adaptive render stands after a round (reported to [`Progress::round_done`]).
///
/// [`Progress::round_done`]: crate::render::Progress::round_done
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundSummary {
    /// The round just finished, from 0.
    pub round: u32,
    /// Pixels the next round samples: those still above the target error and below the maximum
    /// count, and in the first rounds their neighbours.
    pub active: u64,
    /// Pixels in the render.
    pub pixels: u64,
    /// The largest relative error of any pixel (pixel rule; NaN under the image rule).
    pub worst_error: f64,
    /// The estimated RMSE of the image's display values ([`estimated_rmse`]).
    pub estimated_error: f64,
    /// The rule the render samples by.
    pub rule: ErrorRule,
    /// The target error.
    pub target_error: f64,
}

/// Why an adaptive render stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The target was reached: every pixel's (pixel rule), or the error the plan predicts for
    /// the image (image rule; the image's own estimate, [`ErrorStats::estimated_rmse`], can be
    /// above it).
    Converged,
    /// Pixels that could lower the error further reached the maximum sample count.
    MaxSpp,
    /// The time limit ran out first.
    TimeLimit,
    /// The sample budget was spent first.
    Budget,
}

/// The error an adaptive render reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// The rule the render sampled by.
    pub rule: ErrorRule,
    /// The target error (0: none).
    pub target: f64,
    /// The estimated RMSE of the image's display values against the converged image
    /// ([`estimated_rmse`]).
    pub estimated_rmse: f64,
    /// Under the pixel rule, where the pixels' relative errors ended; `None` under the image
    /// rule, whose target is the image's error, not a pixel's.
    pub pixels: Option<PixelErrors>,
    /// Rounds rendered.
    pub rounds: u32,
    /// Why sampling stopped.
    pub stop: Stop,
}

/// Where the pixels' relative errors ([`PixelEstimate::relative_error`]) ended in a render by the
/// pixel rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelErrors {
    /// The largest relative error of any pixel.
    pub worst: f64,
    /// The mean relative error over the pixels.
    pub mean: f64,
    /// Share of pixels at or below the target, in [0, 1].
    pub met: f64,
    /// Pixels left above the target.
    pub above: u64,
}

impl PixelErrors {
    /// The statistics of the pixels' relative `errors` against `target`.
    fn of(errors: &[f64], target: f64) -> PixelErrors {
        let n = errors.len().max(1) as f64;
        let met = errors.par_iter().filter(|&&e| e <= target).count();
        PixelErrors {
            worst: worst_error(errors),
            mean: errors.iter().sum::<f64>() / n,
            met: met as f64 / n,
            above: (errors.len() - met) as u64,
        }
    }

    /// The statistics of several windows' pixels together, each with its pixel count.
    fn merged(parts: &[(PixelErrors, u64)]) -> PixelErrors {
        let pixels = parts.iter().map(|(_, n)| *n).sum::<u64>().max(1) as f64;
        let weighted = |f: fn(&PixelErrors) -> f64| {
            parts.iter().map(|(p, n)| f(p) * *n as f64).sum::<f64>() / pixels
        };
        PixelErrors {
            worst: parts.iter().map(|(p, _)| p.worst).fold(0.0, f64::max),
            mean: weighted(|p| p.mean),
            met: weighted(|p| p.met),
            above: parts.iter().map(|(p, _)| p.above).sum(),
        }
    }
}

/// Samples per pixel a render took, and for an adaptive render the error it reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingStats {
    /// Fewest samples in a pixel.
    pub min_spp: u32,
    /// Most samples in a pixel.
    pub max_spp: u32,
    /// Mean samples per pixel.
    pub mean_spp: f64,
    /// The error reached (adaptive renders only).
    pub error: Option<ErrorStats>,
}

impl SamplingStats {
    /// The statistics of `spp` samples in every pixel.
    pub fn uniform(spp: u32) -> SamplingStats {
        SamplingStats {
            min_spp: spp,
            max_spp: spp,
            mean_spp: spp as f64,
            error: None,
        }
    }

    /// The statistics of several windows of one image together, each given with its pixel count
    /// (`None` for no windows).
    pub fn merged(parts: &[(SamplingStats, u64)]) -> Option<SamplingStats> {
        let pixels = parts.iter().map(|(_, n)| *n).sum::<u64>().max(1) as f64;
        let weighted = |f: &dyn Fn(&SamplingStats) -> f64| {
            parts.iter().map(|(s, n)| f(s) * *n as f64).sum::<f64>() / pixels
        };
        let first = parts.first()?.0;
        let error = first.error.map(|e| {
            let errors = || parts.iter().filter_map(|(s, _)| s.error);
            // The windows that have pixel errors (all or none: the windows of one image share
            // its rule).
            let pixels: Vec<_> = (parts.iter())
                .filter_map(|(s, n)| Some((s.error?.pixels?, *n)))
                .collect();
            ErrorStats {
                rule: e.rule,
                target: e.target,
                // Root of the pixel-weighted mean of the squares: the windows' MSEs add up.
                estimated_rmse: weighted(&|s| s.error.map_or(0.0, |e| e.estimated_rmse.powi(2)))
                    .sqrt(),
                pixels: (!pixels.is_empty()).then(|| PixelErrors::merged(&pixels)),
                rounds: errors().map(|e| e.rounds).max().unwrap_or(0),
                // The stop of the window that fell shortest: a time limit over a maximum count
                // over convergence.
                stop: errors()
                    .map(|e| e.stop)
                    .max_by_key(|s| match s {
                        Stop::Converged => 0,
                        Stop::MaxSpp => 1,
                        Stop::Budget => 2,
                        Stop::TimeLimit => 3,
                    })
                    .unwrap_or(Stop::Converged),
            }
        });
        Some(SamplingStats {
            min_spp: parts.iter().map(|(s, _)| s.min_spp).min()?,
            max_spp: parts.iter().map(|(s, _)| s.max_spp).max()?,
            mean_spp: weighted(&|s| s.mean_spp),
            error,
        })
    }

    /// A short description for a stats line: `16 spp`, or for an adaptive render the mean and
    /// range of the counts and the error reached.
    pub fn summary(&self) -> String {
        let Some(e) = self.error else {
            // Uniform, or anti-aliased by contrast (some pixels with more samples).
            return if self.min_spp == self.max_spp {
                format!("{} spp", self.min_spp)
            } else {
                format!(
                    "{:.2} spp mean ({}..{})",
                    self.mean_spp, self.min_spp, self.max_spp
                )
            };
        };
        let rounds = match e.rounds {
            1 => "1 round".to_string(),
            n => format!("{n} rounds"),
        };
        let spp = format!(
            "{:.1} spp mean ({}..{}) in {rounds}",
            self.mean_spp, self.min_spp, self.max_spp
        );
        match e.rule {
            ErrorRule::Image => {
                let target = if e.target > 0.0 {
                    format!(" (target {})", short_number(e.target))
                } else {
                    String::new()
                };
                let stop = match e.stop {
                    // The plan (the pilot) met the target; the audit, which reports the image's
                    // own error, may still say otherwise, and the line says so.
                    // Without a target (a time limit or a budget alone), rounds end early only
                    // when no pixel has samples left to take or error left to lose.
                    Stop::Converged if e.target <= 0.0 => format!(
                        "no pixel left to refine (each at max spp {} or without error)",
                        self.max_spp
                    ),
                    Stop::Converged if e.estimated_rmse > e.target => format!(
                        "the rounds planned for the target done, the estimate {:.2}x the target",
                        e.estimated_rmse / e.target
                    ),
                    Stop::Converged => "the target reached".to_string(),
                    Stop::MaxSpp => format!("stopped at max spp {}", self.max_spp),
                    Stop::TimeLimit => "the time limit reached".to_string(),
                    Stop::Budget => "the sample budget spent".to_string(),
                };
                format!(
                    "adaptive, {spp}, estimated image error {:.2e} RMSE{target}: {stop}",
                    e.estimated_rmse
                )
            }
            ErrorRule::Pixel => {
                let p = e.pixels.unwrap_or(PixelErrors {
                    worst: f64::NAN,
                    mean: f64::NAN,
                    met: f64::NAN,
                    above: 0,
                });
                let stop = match e.stop {
                    Stop::Converged => "every pixel at the target".to_string(),
                    Stop::MaxSpp => format!(
                        "{} pixels ({:.2}%) stopped at max spp {} above the target",
                        p.above,
                        100.0 * (1.0 - p.met),
                        self.max_spp
                    ),
                    Stop::TimeLimit | Stop::Budget => format!(
                        "the time limit ran out with {} pixels ({:.2}%) above the target",
                        p.above,
                        100.0 * (1.0 - p.met)
                    ),
                };
                format!(
                    "adaptive per pixel, {spp}, error target {}, worst {:.3}, mean {:.4}, estimated image error {:.2e} RMSE: {stop}",
                    short_number(e.target),
                    p.worst,
                    p.mean,
                    e.estimated_rmse
                )
            }
        }
    }
}

/// The sample counts and error of a finished adaptive render of `rounds` rounds that stopped
/// for `stop`, from each pixel's estimate, the audited MSE and, under the pixel rule, each
/// pixel's relative error as the rounds left it (`relative_errors`: the rounds compute them as
/// they sample, so the pixels need no second pass).
pub(super) fn sampling_stats(
    (estimates, relative_errors): (&[PixelEstimate], Option<&[f64]>),
    adaptive: &Adaptive,
    rounds: u32,
    stop: Stop,
    estimated_mse: f64,
) -> SamplingStats {
    let n = estimates.len().max(1) as f64;
    // One parallel pass for the counts; their sum is of whole numbers, exact in any order.
    let (min_spp, max_spp, total) = (estimates.par_iter())
        .map(|e| (e.count(), e.count(), u64::from(e.count())))
        .reduce(
            || (u32::MAX, 0, 0),
            |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2),
        );
    SamplingStats {
        min_spp: if estimates.is_empty() { 0 } else { min_spp },
        max_spp,
        mean_spp: total as f64 / n,
        error: Some(ErrorStats {
            rule: adaptive.rule,
            target: adaptive.target_error,
            estimated_rmse: estimated_mse.sqrt(),
            pixels: relative_errors.map(|errors| PixelErrors::of(errors, adaptive.target_error)),
            rounds,
            stop,
        }),
    }
}

/// The estimated RMSE of the display values of the pixels of `estimates` against their
/// converged values: the root of the mean of [`PixelEstimate::squared_error`] corrected by
/// `calibration` (0 for none).
pub fn estimated_rmse(estimates: &[PixelEstimate], calibration: &Calibration) -> f64 {
    let sum: f64 = estimates.iter().map(|e| calibration.squared_error(e)).sum();
    (sum / estimates.len().max(1) as f64).sqrt()
}

/// The largest of the pixels' relative errors (0 for none).
pub(super) fn worst_error(errors: &[f64]) -> f64 {
    errors.iter().copied().fold(0.0, f64::max)
}

/// `x` as a user would write it: plainly from 10⁻⁴ to 10⁶ (0.002, 16), else in scientific
/// notation (1e-300, where the plain form has 300 digits).
fn short_number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An image-rule render whose plan met `target` and whose audit estimated `estimated`.
    fn converged(target: f64, estimated: f64) -> SamplingStats {
        SamplingStats {
            min_spp: 8,
            max_spp: 64,
            mean_spp: 12.5,
            error: Some(ErrorStats {
                rule: ErrorRule::Image,
                target,
                estimated_rmse: estimated,
                pixels: None,
                rounds: 4,
                stop: Stop::Converged,
            }),
        }
    }

    /// Windows of one image merge their pixels' errors weighted by their pixel counts, the
    /// worst of all and the pixels above summed; image-rule windows have none to merge.
    #[test]
    fn windows_merge_their_pixels_errors() {
        let pixel_rule = |worst: f64, mean: f64, met: f64, above: u64| SamplingStats {
            error: Some(ErrorStats {
                rule: ErrorRule::Pixel,
                pixels: Some(PixelErrors {
                    worst,
                    mean,
                    met,
                    above,
                }),
                ..converged(0.01, 0.001).error.unwrap()
            }),
            ..converged(0.01, 0.001)
        };
        let merged = SamplingStats::merged(&[
            (pixel_rule(0.02, 0.004, 1.0, 0), 300),
            (pixel_rule(0.05, 0.008, 0.5, 50), 100),
        ]);
        let pixels = merged.unwrap().error.unwrap().pixels.unwrap();
        assert_eq!((pixels.worst, pixels.above), (0.05, 50));
        assert!((pixels.mean - 0.005).abs() < 1e-15 && (pixels.met - 0.875).abs() < 1e-15);
        let images = [(converged(0.01, 0.001), 300), (converged(0.01, 0.002), 100)];
        assert_eq!(
            SamplingStats::merged(&images)
                .unwrap()
                .error
                .unwrap()
                .pixels,
            None
        );
    }

    /// The final line says the target was reached only when the image's own estimate is at or
    /// below it.
    #[test]
    fn the_line_says_when_the_estimate_is_above_the_target() {
        let below = converged(0.001, 0.0009).summary();
        assert!(
            below.ends_with("(target 0.001): the target reached"),
            "{below}"
        );
        let above = converged(0.001, 0.0012).summary();
        assert!(
            above
                .ends_with("the rounds planned for the target done, the estimate 1.20x the target"),
            "{above}"
        );
    }

    /// Without a target (a time limit alone), rounds that end early say that nothing is left to
    /// refine, not a ratio to a target of 0 ("infx"); a target far from 1 is written in
    /// scientific notation, not in 300 digits.
    #[test]
    fn the_line_needs_no_target_and_writes_any_target_short() {
        let untargeted = converged(0.0, 2e-4).summary();
        assert!(
            untargeted.ends_with("no pixel left to refine (each at max spp 64 or without error)")
                && !untargeted.contains("inf"),
            "{untargeted}"
        );
        let tiny = converged(1e-300, 2e-4).summary();
        assert!(tiny.contains("(target 1e-300)"), "{tiny}");
        assert_eq!(short_number(0.002), "0.002");
        assert_eq!(short_number(2e6), "2e6");
    }
}
