//! What an adaptive render reports: where it stands after each round, and the sample counts and
//! error it reached (also the plain statistics of a uniform render).

use super::Adaptive;
use crate::film::PixelEstimate;

/// Where an adaptive render stands after a round (reported to [`Progress::round_done`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundSummary {
    /// The round just finished, from 0.
    pub round: u32,
    /// Pixels the next round samples: those still above the target error and below the maximum
    /// count, and in the first rounds their neighbours.
    pub active: u64,
    /// Pixels in the render.
    pub pixels: u64,
    /// The largest relative error of any pixel.
    pub worst_error: f64,
    /// The target error.
    pub target_error: f64,
}

impl RoundSummary {
    /// The summary of `round` over a window's pixels: their errors after it, and which of them
    /// the next round samples.
    pub(super) fn of_window(round: u32, errors: &[f64], refine: &[bool], target: f64) -> Self {
        RoundSummary {
            round,
            active: refine.iter().filter(|&&r| r).count() as u64,
            pixels: errors.len() as u64,
            worst_error: worst_error(errors),
            target_error: target,
        }
    }
}

/// Why an adaptive render stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// Every pixel reached the target error.
    Converged,
    /// Some pixels reached the maximum sample count above the target.
    MaxSpp,
    /// The time limit ran out with pixels still above the target.
    TimeLimit,
}

/// The error an adaptive render reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// The target error.
    pub target: f64,
    /// The largest relative error of any pixel.
    pub worst: f64,
    /// The mean relative error over the pixels.
    pub mean: f64,
    /// Share of pixels at or below the target, in [0, 1].
    pub met: f64,
    /// Pixels left above the target.
    pub above: u64,
    /// Rounds rendered.
    pub rounds: u32,
    /// Why sampling stopped.
    pub stop: Stop,
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
            ErrorStats {
                target: e.target,
                worst: errors().map(|e| e.worst).fold(0.0, f64::max),
                mean: weighted(&|s| s.error.map_or(0.0, |e| e.mean)),
                met: weighted(&|s| s.error.map_or(0.0, |e| e.met)),
                above: errors().map(|e| e.above).sum(),
                rounds: errors().map(|e| e.rounds).max().unwrap_or(0),
                // The stop of the window that fell shortest: a time limit over a maximum count
                // over convergence.
                stop: errors()
                    .map(|e| e.stop)
                    .max_by_key(|s| match s {
                        Stop::Converged => 0,
                        Stop::MaxSpp => 1,
                        Stop::TimeLimit => 2,
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
            return format!("{} spp", self.min_spp);
        };
        let stop = match e.stop {
            Stop::Converged => "every pixel at the target".to_string(),
            Stop::MaxSpp => format!(
                "{} pixels ({:.2}%) stopped at max spp {} above the target",
                e.above,
                100.0 * (1.0 - e.met),
                self.max_spp
            ),
            Stop::TimeLimit => format!(
                "the time limit ran out with {} pixels ({:.2}%) above the target",
                e.above,
                100.0 * (1.0 - e.met)
            ),
        };
        format!(
            "adaptive, {:.1} spp mean ({}..{}) in {} rounds, error target {}, worst {:.3}, mean {:.4}: {stop}",
            self.mean_spp, self.min_spp, self.max_spp, e.rounds, e.target, e.worst, e.mean
        )
    }
}

/// The sample counts and error of a finished adaptive render of `rounds` rounds, from each
/// pixel's estimate and its relative error (`errors`, in the same order).
pub(super) fn sampling_stats(
    estimates: &[PixelEstimate],
    errors: &[f64],
    adaptive: &Adaptive,
    rounds: u32,
    timed_out: bool,
) -> SamplingStats {
    let n = estimates.len().max(1) as f64;
    let counts = estimates.iter().map(PixelEstimate::count);
    let met = errors
        .iter()
        .filter(|&&e| e <= adaptive.target_error)
        .count();
    let wanting_more = || {
        estimates
            .iter()
            .zip(errors)
            .any(|(estimate, &error)| adaptive.wants_more(estimate.count(), error))
    };
    let stop = if met == estimates.len() {
        Stop::Converged
    } else if timed_out || wanting_more() {
        Stop::TimeLimit
    } else {
        Stop::MaxSpp
    };
    SamplingStats {
        min_spp: counts.clone().min().unwrap_or(0),
        max_spp: counts.clone().max().unwrap_or(0),
        mean_spp: counts.map(|c| c as f64).sum::<f64>() / n,
        error: Some(ErrorStats {
            target: adaptive.target_error,
            worst: worst_error(errors),
            mean: errors.iter().sum::<f64>() / n,
            met: met as f64 / n,
            above: (estimates.len() - met) as u64,
            rounds,
            stop,
        }),
    }
}

/// The largest of the pixels' relative errors (0 for none).
pub(super) fn worst_error(errors: &[f64]) -> f64 {
    errors.iter().copied().fold(0.0, f64::max)
}
