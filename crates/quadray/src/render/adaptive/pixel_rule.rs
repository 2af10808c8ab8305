//! The pixel rule: every pixel is brought to one relative error of its display value; round k
//! brings the pixels it samples to `min_spp`·2^k samples.

use super::missed::{across_flat_edges, follow_neighbours};
use super::{Adaptive, FIRST_ROUND_MARGIN, NEIGHBOUR_ROUNDS, SLIVER_ROUNDS, Stop};
use crate::film::PixelEstimate;
use rayon::prelude::*;

/// Whether a pixel with `count` samples and relative error `error` is above `threshold` and
/// below the maximum count.
pub(super) fn above(adaptive: &Adaptive, count: u32, error: f64, threshold: f64) -> bool {
    // The error is never NaN (infinite when unknown), so `>` is the negation of `<=`.
    count < adaptive.max_spp && error > threshold
}

/// How many rounds can follow the first: round k brings its pixels to
/// [`round_count`]`(k)`, which reaches `max_spp` at this one.
pub(super) fn refinement_rounds(adaptive: &Adaptive) -> u32 {
    adaptive
        .max_spp
        .div_ceil(adaptive.min_spp)
        .next_power_of_two()
        .trailing_zeros()
}

/// The sample count of a pixel sampled in `round`: `min_spp` doubled `round` times, at most
/// `max_spp`.
pub(super) fn round_count(adaptive: &Adaptive, round: u32) -> u32 {
    adaptive
        .min_spp
        .checked_shl(round)
        .filter(|&count| count >> round == adaptive.min_spp)
        .unwrap_or(u32::MAX)
        .min(adaptive.max_spp)
}

/// The pixels that `round` (at least 1) samples: those whose own error is above the target
/// (above [`FIRST_ROUND_MARGIN`] × the target after the first round) and, in the first
/// [`NEIGHBOUR_ROUNDS`] rounds, their neighbours below the round's count, since a feature that
/// crosses into a pixel can be missed by all of its first samples, and in the first
/// [`SLIVER_ROUNDS`] flat pixels beside a flat neighbour of another value ([`super::missed`]).
pub(super) fn select(
    adaptive: &Adaptive,
    round: u32,
    estimates: &[PixelEstimate],
    (errors, squared_errors): (&[f64], &[f64]),
    width: usize,
) -> Vec<bool> {
    let count = round_count(adaptive, round);
    let threshold = match round {
        1 => adaptive.target_error * FIRST_ROUND_MARGIN,
        _ => adaptive.target_error,
    };
    let own: Vec<bool> = estimates
        .par_iter()
        .zip(errors)
        .map(|(estimate, &error)| above(adaptive, estimate.count(), error, threshold))
        .collect();
    if round > NEIGHBOUR_ROUNDS.min(refinement_rounds(adaptive)) {
        return own;
    }
    let mut refine = follow_neighbours(&own, width, |i, _| estimates[i].count() < count);
    if round <= SLIVER_ROUNDS {
        // A flat pixel's relative error is 0: its squared error is what says it is flat.
        let across = across_flat_edges(estimates, squared_errors, width);
        for ((refine, across), estimate) in refine.iter_mut().zip(across).zip(estimates) {
            *refine |= across && estimate.count() < count;
        }
    }
    refine
}

/// Why a pixel-rule render that samples no more pixels stopped: every pixel met the target, or
/// some stopped at the maximum count above it.
pub(super) fn stop(adaptive: &Adaptive, estimates: &[PixelEstimate], errors: &[f64]) -> Stop {
    let converged = estimates
        .iter()
        .zip(errors)
        .all(|(_, &error)| error <= adaptive.target_error);
    if converged {
        Stop::Converged
    } else {
        Stop::MaxSpp
    }
}
