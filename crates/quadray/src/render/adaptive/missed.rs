//! Pixels whose first samples may have missed a feature, which the first rounds sample whatever
//! their own estimates say:
//! - the neighbours of pixels sampled by their own estimates ([`follow_neighbours`],
//!   [`super::NEIGHBOUR_ROUNDS`]): a feature that crosses into a pixel can be missed by all of
//!   its first samples while its neighbour meets it;
//! - flat pixels beside a flat neighbour of another value ([`across_flat_edges`],
//!   [`super::SLIVER_ROUNDS`]): where an edge runs along the border between two pixels whose
//!   samples all agree, a sliver of it can cross into either and be missed by every sample, so
//!   the pair's difference is the only sign of it. The audit draws such pixels too
//!   ([`super::audit`]);
//! - for the audit alone, quiet pixels between two along their row or column that met a thin
//!   line ([`feature_contrasts`]).

use super::calibration::{FLAT, is_flat_error};
use crate::film::PixelEstimate;
use rayon::prelude::*;

/// The band height of a window read whole, in one band ([`flat_contrasts`]).
pub(super) const WHOLE: usize = usize::MAX;

/// The least difference of display values between two flat 4-neighbours that the rounds follow.
pub const SLIVER_CONTRAST: f32 = 0.02;

/// Each pixel's flat contrast: for a flat pixel of `estimates` (row-major, `width` wide, in
/// bands of `band` rows: [`WHOLE`], or rows read apart, across whose borders no neighbour
/// counts), whose batch-means squared errors are `squared_errors`, the largest squared
/// difference of display values with its flat 4-neighbours; 0 for the others.
pub(super) fn flat_contrasts(
    estimates: &[PixelEstimate],
    squared_errors: &[f64],
    (width, band): (usize, usize),
) -> Vec<f64> {
    flat_neighbours(
        estimates,
        squared_errors,
        (width, band),
        0.0,
        |value, neighbours| {
            (neighbours.into_iter().flatten())
                .map(|other| ((other - value) as f64).powi(2))
                .fold(0.0, f64::max)
        },
    )
}

/// `of` the display value of each flat pixel of `estimates` (as [`flat_contrasts`] reads them)
/// and those of its flat 4-neighbours (left, right, up, down; `None` where a neighbour is not
/// flat or not there); `none` for the others.
fn flat_neighbours<T: Copy + Send + Sync>(
    estimates: &[PixelEstimate],
    squared_errors: &[f64],
    (width, band): (usize, usize),
    none: T,
    of: impl Fn(f32, [Option<f32>; 4]) -> T + Sync,
) -> Vec<T> {
    let flat: Vec<Option<f32>> = (estimates.par_iter().zip(squared_errors))
        .map(|(e, &s)| is_flat_error(s).then(|| e.mean_display_value()))
        .collect();
    let mut out = vec![none; flat.len()];
    // Row by row, so that a pixel's column needs no division (a `%` per pixel was most of the
    // cost).
    let rows: Vec<&[Option<f32>]> = flat.chunks(width).collect();
    out.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let row = rows[y];
        let up = (y % band != 0).then(|| rows[y - 1]);
        let down = ((y + 1) % band != 0)
            .then(|| rows.get(y + 1).copied())
            .flatten();
        for (x, out) in out.iter_mut().enumerate() {
            let Some(value) = row[x] else { continue };
            let left = x.checked_sub(1).and_then(|x| row[x]);
            let right = row.get(x + 1).copied().flatten();
            let above = up.and_then(|r| r[x]);
            let below = down.and_then(|r| r[x]);
            *out = of(value, [left, right, above, below]);
        }
    });
    out
}

/// How far along a row or a column [`feature_contrasts`] looks, through quiet pixels, for the
/// pixels that met a line on either side of a quiet one.
const LINE_GAP: usize = 3;

/// How many times a pixel's estimated squared error a neighbour's must be for
/// [`feature_contrasts`] to count it as having met something the pixel did not.
const LOUDER: f64 = 100.0;

/// Each pixel's contrast with a line it may have missed. Pixel i of `estimates` (row-major,
/// `width` wide), whose batch-means squared errors are `squared_errors`, lies across a line
/// when, along its row or its column, the first pixel on either side (within [`LINE_GAP`]) whose
/// squared error is [`LOUDER`] times i's is found on both sides; its contrast is then the smaller
/// of the squared differences of those two pixels' mean display values from i's (the larger over
/// the row and the column), and 0 otherwise. A thin line that pixels along it met, and a few
/// pixels between them missed with every sample, leaves those quiet between pixels that saw it,
/// and what they missed about as far from their value as the line's pixels' means are (the
/// kitchen at 480x270, target 0.0005: pixels of 8 and 16 samples in such runs along a few lines
/// held a third of the image's squared error, with errors estimated near 1e-8). A quiet pixel
/// beside an ordinary edge has it on one side only. A flat pixel counts as having the flat
/// error bound ([`FLAT`]), so a neighbour's rounding does not make it louder. The window's rows
/// come in bands of `band` rows as for [`flat_contrasts`].
pub(super) fn feature_contrasts(
    estimates: &[PixelEstimate],
    squared_errors: &[f64],
    (width, band): (usize, usize),
) -> Vec<f64> {
    let width = width.max(1);
    let height = estimates.len() / width;
    let mut contrasts = vec![0.0; estimates.len()];
    contrasts
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, out)| {
            // The rows of this row's band.
            let first = y - y % band;
            let end = first.saturating_add(band).min(height);
            let rows = first as isize..end as isize;
            // The loudest error within reach above and below each pixel of the row, and along
            // the row: a side whose loudest is not louder than a pixel has no pixel to find
            // there, which most pixels learn from these without a probe.
            let line = |r: usize| &squared_errors[r * width..(r + 1) * width];
            let reach = |r: std::ops::Range<usize>| loudest(r.map(line), width);
            let above = reach(y.saturating_sub(LINE_GAP).max(first)..y);
            let below = reach(y + 1..(y + 1 + LINE_GAP).min(end));
            let row = line(y);
            for (x, contrast) in out.iter_mut().enumerate() {
                let i = y * width + x;
                let loud = LOUDER * squared_errors[i].max(FLAT);
                let beyond = |side: &[f64]| side.iter().copied().fold(f64::NEG_INFINITY, larger);
                let left = beyond(&row[x.saturating_sub(LINE_GAP)..x]);
                let right = beyond(&row[(x + 1).min(width)..(x + 1 + LINE_GAP).min(width)]);
                // A direction with a side that has no louder pixel has no contrast (0.0, as
                // `between` gives for it); most pixels have neither direction.
                let across_row = left > loud && right > loud;
                let across_column = above[x] > loud && below[x] > loud;
                if !(across_row || across_column) {
                    continue;
                }
                // The first louder pixel from (x, y) in steps of (dx, dy).
                let seen = |dx: isize, dy: isize| {
                    (1..=LINE_GAP as isize).find_map(|k| {
                        let (nx, ny) = (x as isize + k * dx, y as isize + k * dy);
                        if nx < 0 || nx as usize >= width || !rows.contains(&ny) {
                            return Some(None);
                        }
                        let j = ny as usize * width + nx as usize;
                        (squared_errors[j] > loud).then_some(Some(j))
                    })?
                };
                // Display values are read only here, for the few pixels with a line on both
                // sides (each is a sum over the pixel's runs).
                let between = |a: Option<usize>, b: Option<usize>| match (a, b) {
                    (Some(a), Some(b)) => {
                        let value = estimates[i].mean_display_value();
                        let away =
                            |j: usize| ((estimates[j].mean_display_value() - value) as f64).powi(2);
                        f64::min(away(a), away(b))
                    }
                    _ => 0.0,
                };
                let across = |on: bool, (dx, dy): (isize, isize)| match on {
                    true => between(seen(-dx, -dy), seen(dx, dy)),
                    false => 0.0,
                };
                *contrast = f64::max(across(across_row, (1, 0)), across(across_column, (0, 1)));
            }
        });
    contrasts
}

/// The largest value in each column of `rows` (each `width` long; NaN ignored; −∞ for none).
fn loudest<'a>(rows: impl Iterator<Item = &'a [f64]>, width: usize) -> Vec<f64> {
    let mut most = vec![f64::NEG_INFINITY; width];
    for row in rows {
        for (m, &v) in most.iter_mut().zip(row) {
            *m = larger(*m, v);
        }
    }
    most
}

/// `v` where it is above `most`, else `most`: from −∞ on, the largest of the values seen with
/// NaN ignored (a NaN is above nothing), as `f64::max` would give it in fewer instructions. So
/// the largest is above a bound exactly when one of the values is.
#[inline(always)]
fn larger(most: f64, v: f64) -> f64 {
    if v > most { v } else { most }
}

/// Marks each pixel whose flat contrast ([`flat_contrasts`]) is above [`SLIVER_CONTRAST`]²: one
/// of its flat 4-neighbours' squared differences is (without the contrasts' array).
pub(super) fn across_flat_edges(
    estimates: &[PixelEstimate],
    squared_errors: &[f64],
    width: usize,
) -> Vec<bool> {
    let least = (SLIVER_CONTRAST as f64).powi(2);
    flat_neighbours(
        estimates,
        squared_errors,
        (width, WHOLE),
        false,
        |value, neighbours| {
            (neighbours.into_iter().flatten()).any(|other| ((other - value) as f64).powi(2) > least)
        },
    )
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
        .for_each_init(Vec::new, |column, (y, row)| {
            let (y0, y1) = (y.saturating_sub(1), (y + 1).min(height - 1));
            // Whether each column of the three rows holds a marked pixel: most pixels have none
            // in their three columns, which these tell without asking `follows` of each of the
            // eight (1.6 ms a selection of the quadric grid at 480x270).
            let rows = |x: usize| (y0..=y1).any(|ny| own[ny * width + x]);
            column.clear();
            column.extend((0..width).map(rows));
            for (x, wanted) in row.iter_mut().enumerate() {
                let (x0, x1) = (x.saturating_sub(1), (x + 1).min(width - 1));
                if *wanted || !column[x0..=x1].contains(&true) {
                    continue;
                }
                let i = y * width + x;
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
        let contrasts = flat_contrasts(&estimates, &errors, (3, WHOLE));
        assert!((contrasts[3] - 1.0).abs() < 1e-6);
        assert_eq!(contrasts[5], 0.0);
    }

    /// Quiet pixels in gaps of a column of pixels that met a dark line (their samples disagree)
    /// lie across the line where it is met within three pixels on both sides; pixels beside the
    /// column, which have the line on one side only, and the ends of a gap of four do not.
    #[test]
    fn quiet_gaps_in_a_line_lie_across_it() {
        let quiet = pixel(&[0.8; 8]);
        let line = pixel(&[0.8, 0.8, 0.8, 0.0, 0.8, 0.8, 0.8, 0.8]);
        // Column 1 of a 3-wide image: line, gap of 1, line, gap of 3, line, gap of 4, line.
        let column = "LqLqqqLqqqqL";
        let mut estimates = Vec::new();
        for c in column.chars() {
            let centre = if c == 'L' { line } else { quiet };
            estimates.extend([quiet, centre, quiet]);
        }
        let errors: Vec<f64> = estimates.iter().map(|e| e.squared_error()).collect();
        let contrasts = feature_contrasts(&estimates, &errors, (3, WHOLE));
        let (v_quiet, v_line) = (quiet.mean_display_value(), line.mean_display_value());
        let expected = ((v_line - v_quiet) as f64).powi(2);
        for (y, c) in column.chars().enumerate() {
            let across = contrasts[3 * y + 1];
            let in_short_gap = c == 'q' && [1, 3, 4, 5, 8, 9].contains(&y);
            match in_short_gap {
                true => assert!((across - expected).abs() < 1e-9, "row {y}: {across}"),
                false => assert_eq!(across, 0.0, "row {y}"),
            }
            // Beside the column: the line on one side only.
            assert_eq!(contrasts[3 * y], 0.0);
            assert_eq!(contrasts[3 * y + 2], 0.0);
        }
    }

    /// Rows read in bands are apart: a neighbour across a band's border counts for neither
    /// contrast, as one beyond the window's side does not.
    #[test]
    fn no_neighbour_counts_across_a_band() {
        let (black, white) = (pixel(&[0.0; 8]), pixel(&[1.0; 8]));
        // One column: white above black, the border between rows 0 and 1.
        let estimates = [white, black, black];
        let errors = estimates.map(|e| e.squared_error());
        assert!(flat_contrasts(&estimates, &errors, (1, WHOLE))[1] > 0.9);
        assert_eq!(flat_contrasts(&estimates, &errors, (1, 1))[1], 0.0);
        // Black above white, the border between rows 1 and 2: the neighbour below.
        let estimates = [black, black, white];
        let errors = estimates.map(|e| e.squared_error());
        assert!(flat_contrasts(&estimates, &errors, (1, WHOLE))[1] > 0.9);
        assert_eq!(flat_contrasts(&estimates, &errors, (1, 2))[1], 0.0);
        // A quiet pixel between two that met a line, the second across a band's border.
        let quiet = pixel(&[0.8; 8]);
        let line = pixel(&[0.8, 0.8, 0.8, 0.0, 0.8, 0.8, 0.8, 0.8]);
        let estimates = [line, quiet, line];
        let errors = estimates.map(|e| e.squared_error());
        assert!(feature_contrasts(&estimates, &errors, (1, WHOLE))[1] > 0.0);
        assert_eq!(feature_contrasts(&estimates, &errors, (1, 2))[1], 0.0);
        // The first across the border: rows 0 and 1, 2 and 3 make the bands.
        let estimates = [line, line, quiet, line];
        let errors = estimates.map(|e| e.squared_error());
        assert!(feature_contrasts(&estimates, &errors, (1, WHOLE))[2] > 0.0);
        assert_eq!(feature_contrasts(&estimates, &errors, (1, 2))[2], 0.0);
    }

    /// `larger` folds to the largest value with NaN ignored, so the largest is above a bound
    /// exactly when a value is, as the probes compare them one by one.
    #[test]
    fn the_largest_ignores_nan() {
        let fold = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, larger);
        assert_eq!(fold(&[f64::NAN, 1.0, f64::NAN, 0.5]), 1.0);
        assert_eq!(fold(&[f64::NAN]), f64::NEG_INFINITY);
        assert_eq!(fold(&[]), f64::NEG_INFINITY);
        assert_eq!(fold(&[f64::INFINITY, 2.0]), f64::INFINITY);
        assert_eq!(
            loudest([[1.0, f64::NAN].as_slice(), &[0.5, 3.0]].into_iter(), 2),
            [1.0, 3.0]
        );
    }
}
