//! Pixels whose first samples may have missed a feature, which the first rounds sample whatever
//! their own estimates say:
//! - the neighbours of pixels sampled by their own estimates ([`follow_neighbours`],
//!   [`super::NEIGHBOUR_ROUNDS`]): a feature that crosses into a pixel can be missed by all of
//!   its first samples while its neighbour meets it;
//! - flat pixels beside a flat neighbour of another value ([`across_flat_edges`],
//!   [`super::SLIVER_ROUNDS`]): where an edge runs along the border between two pixels whose
//!   samples all agree, a sliver of it can cross into either and be missed by every sample, so
//!   the pair's difference is the only sign of it. The audit draws such pixels too
//!   ([`super::audit`]).

use super::calibration::is_flat_error;
use crate::film::PixelEstimate;
use rayon::prelude::*;

/// The least difference of display values between two flat 4-neighbours that the rounds follow.
pub const SLIVER_CONTRAST: f32 = 0.02;

/// Each pixel's flat contrast: for a flat pixel of `estimates` (row-major, `width` wide), whose
/// batch-means squared errors are `squared_errors`, the largest squared difference of display
/// values with its flat 4-neighbours; 0 for the others.
pub(super) fn flat_contrasts(
    estimates: &[PixelEstimate],
    squared_errors: &[f64],
    width: usize,
) -> Vec<f64> {
    let flat: Vec<Option<f32>> = (estimates.par_iter().zip(squared_errors))
        .map(|(e, &s)| is_flat_error(s).then(|| e.mean_display_value()))
        .collect();
    let mut contrasts = vec![0.0; flat.len()];
    // Row by row, so that a pixel's column needs no division (a `%` per pixel was most of the
    // cost); the neighbours in the order left, right, up, down.
    let rows: Vec<&[Option<f32>]> = flat.chunks(width).collect();
    contrasts
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, out)| {
            let row = rows[y];
            let up = y.checked_sub(1).map(|y| rows[y]);
            let down = rows.get(y + 1).copied();
            for (x, contrast) in out.iter_mut().enumerate() {
                let Some(value) = row[x] else { continue };
                let left = x.checked_sub(1).and_then(|x| row[x]);
                let right = row.get(x + 1).copied().flatten();
                let above = up.and_then(|r| r[x]);
                let below = down.and_then(|r| r[x]);
                *contrast = [left, right, above, below]
                    .into_iter()
                    .flatten()
                    .map(|other| ((other - value) as f64).powi(2))
                    .fold(0.0, f64::max);
            }
        });
    contrasts
}

/// Marks each pixel whose flat contrast ([`flat_contrasts`]) is above [`SLIVER_CONTRAST`]².
pub(super) fn across_flat_edges(
    estimates: &[PixelEstimate],
    squared_errors: &[f64],
    width: usize,
) -> Vec<bool> {
    let least = (SLIVER_CONTRAST as f64).powi(2);
    (flat_contrasts(estimates, squared_errors, width).into_iter())
        .map(|c| c > least)
        .collect()
}

/// Marks the pixels `own` marks, and in the neighbour rounds each pixel `i` one of whose eight
/// neighbours `j` is marked in `own` where `follows(i, j)` (row-major, `width` wide).
pub(super) fn follow_neighbours(
    own: &[bool],
    width: usize,
    follows: impl Fn(usize, usize) -> bool + Sync,
) -> Vec<bool> {
    let height = own.len() / width;
    let mut refine = own.to_vec();
    refine
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let (y0, y1) = (y.saturating_sub(1), (y + 1).min(height - 1));
            for (x, wanted) in row.iter_mut().enumerate() {
                if *wanted {
                    continue;
                }
                let i = y * width + x;
                let (x0, x1) = (x.saturating_sub(1), (x + 1).min(width - 1));
                *wanted = (y0..=y1).any(|ny| {
                    (x0..=x1).any(|nx| {
                        let j = ny * width + nx;
                        own[j] && follows(i, j)
                    })
                });
            }
        });
    refine
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A pixel of the samples `values` (grey).
    fn pixel(values: &[f32]) -> PixelEstimate {
        let mut e = PixelEstimate::default();
        for &v in values {
            e.add(Vec3::splat(v));
        }
        e
    }

    /// Flat pixels beside a flat neighbour of another value are marked; not a flat pixel whose
    /// different neighbour is not flat, nor one beside a diagonal one, nor across the window's
    /// side.
    #[test]
    fn flat_pixels_beside_other_flat_pixels_are_marked() {
        let (black, white) = (pixel(&[0.0; 8]), pixel(&[1.0; 8]));
        let edge = pixel(&[0.0, 1.0].repeat(4));
        // 3 wide: white at the start of the middle row, an edge pixel at its end.
        let estimates = [black, black, black, white, black, edge, black, black, black];
        let errors = estimates.map(|e| e.squared_error());
        let marked = across_flat_edges(&estimates, &errors, 3);
        let expected = [true, false, false, true, true, false, true, false, false];
        assert_eq!(marked, expected);
        let contrasts = flat_contrasts(&estimates, &errors, 3);
        assert!((contrasts[3] - 1.0).abs() < 1e-6);
        assert_eq!(contrasts[5], 0.0);
    }
}
