//! What an adaptive render is asked for: the rule that decides where samples go, the target, the
//! budgets and the sample counts, and the checks on them.

use crate::film::MIN_ERROR_SAMPLES;
use crate::render::MAX_SPP;
use std::time::Duration;

/// How an adaptive render decides where to sample and when to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// The rule that spends the samples.
    pub rule: ErrorRule,
    /// The error to reach (0: none; sampling goes on to [`Adaptive::max_spp`], the time limit or
    /// the budget). Under [`ErrorRule::Image`] the estimated RMSE of the image's display values;
    /// under [`ErrorRule::Pixel`] the relative error every pixel reaches.
    pub target_error: f64,
    /// Samples every pixel takes in the first round: a power of two, at least 2 (the error
    /// estimate needs two). Below [`crate::film::ERROR_BATCHES`] the first estimate is coarse
    /// (n − 1 degrees of freedom) and a feature can slip past a pixel and its neighbours: a
    /// preview setting that costs less where most of the image is flat.
    pub min_spp: u32,
    /// Samples no pixel exceeds.
    pub max_spp: u32,
    /// Stop refining after about this long and keep the image reached (the first round always
    /// completes, so that every pixel has an estimate).
    pub time_limit: Option<Duration>,
    /// Samples per pixel to spend on average, first round included ([`ErrorRule::Image`] only):
    /// a budget that, unlike a time limit, gives the same image on any machine.
    pub spp_budget: Option<f64>,
}

/// The rule an adaptive render spends its samples by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ErrorRule {
    /// Lower the image's mean squared error the most for the samples spent: each round doubles
    /// the pixels whose estimated squared error per ray is highest, until the
    /// image's estimated RMSE reaches the target or a budget runs out (`--target-error`).
    #[default]
    Image,
    /// Bring every pixel to one relative error (`--pixel-error`): a bound on each pixel rather
    /// than the least samples for the image's error.
    Pixel,
}

/// Samples every pixel takes in the first round unless told otherwise.
pub const DEFAULT_MIN_SPP: u32 = 8;
/// The fewest samples a first round may take: those the error estimate needs.
pub const MIN_FIRST_ROUND: u32 = MIN_ERROR_SAMPLES;
/// The most samples a pixel takes unless told otherwise.
pub const DEFAULT_MAX_SPP: u32 = 1024;
/// The shortest time limit, in seconds: a microsecond (a shorter one, 10⁻³⁰⁰ say, rounded to no
/// time at all and was refused as zero).
pub const MIN_TIME_LIMIT_SECS: f64 = 1e-6;
/// The longest time limit, in seconds (about 11.6 days): far beyond any render's need, and well
/// inside what a `Duration` holds.
pub const MAX_TIME_LIMIT_SECS: f64 = 1e6;

impl Default for Adaptive {
    fn default() -> Self {
        Adaptive {
            rule: ErrorRule::Image,
            target_error: 0.01,
            min_spp: DEFAULT_MIN_SPP,
            max_spp: DEFAULT_MAX_SPP,
            time_limit: None,
            spp_budget: None,
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
    /// A time limit in seconds that is not a number in
    /// `[MIN_TIME_LIMIT_SECS, MAX_TIME_LIMIT_SECS]`.
    #[error(
        "the time limit must be a number of seconds from {MIN_TIME_LIMIT_SECS:e} (a microsecond) to {MAX_TIME_LIMIT_SECS:e} (about 11.6 days), got {0:?}"
    )]
    TimeLimitSecs(f64),
    /// A sample budget outside `[min_spp, max_spp]`.
    #[error(
        "the sample budget must be a number of samples per pixel from the first round's {min} to the maximum {max}, got {budget}"
    )]
    SppBudget {
        /// The budget asked for.
        budget: f64,
        /// The first round's samples.
        min: u32,
        /// The maximum samples per pixel.
        max: u32,
    },
    /// A sample budget with the per-pixel rule, which has no way to spend one.
    #[error(
        "a sample budget spends samples where they lower the image's error: use it with the image error target, not the per-pixel one"
    )]
    BudgetWithPixelRule,
}

/// The time limit of `secs` seconds, if that is a number in
/// `[MIN_TIME_LIMIT_SECS, MAX_TIME_LIMIT_SECS]`.
pub fn time_limit_from_secs(secs: f64) -> Result<Duration, AdaptiveError> {
    if (MIN_TIME_LIMIT_SECS..=MAX_TIME_LIMIT_SECS).contains(&secs) {
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
        if let Some(budget) = self.spp_budget {
            if self.rule == ErrorRule::Pixel {
                return Err(AdaptiveError::BudgetWithPixelRule);
            }
            if !(budget >= self.min_spp as f64 && budget <= self.max_spp as f64) {
                return Err(AdaptiveError::SppBudget {
                    budget,
                    min: self.min_spp,
                    max: self.max_spp,
                });
            }
        }
        Ok(())
    }

    /// These settings with `max_spp` as the maximum, and the first round's count lowered to the
    /// largest power of two within it where it was above (an explicit `min_spp` is set after
    /// this).
    pub fn with_max_spp(self, max_spp: u32) -> Adaptive {
        // The first round stays a power of two: at most the largest one within the maximum.
        let first_round_cap = max_spp.checked_ilog2().map_or(0, |k| 1 << k);
        Adaptive {
            max_spp,
            min_spp: self.min_spp.min(first_round_cap),
            ..self
        }
    }

    /// These settings with `min_spp` samples in the first round.
    pub fn with_min_spp(self, min_spp: u32) -> Adaptive {
        Adaptive { min_spp, ..self }
    }

    /// Whether the image is sampled to a target or budget decided on the whole image
    /// ([`ErrorRule::Image`]) and without a time limit: its rounds then follow a plan made from
    /// a pilot that every piece of the image computes alike (see `pilot`).
    pub(crate) fn is_planned(&self) -> bool {
        self.rule == ErrorRule::Image && self.time_limit.is_none()
    }
}
