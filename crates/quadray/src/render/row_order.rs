//! The order in which a render's rows are taken up: blocks of consecutive rows, the blocks
//! interleaved across the frame, so that any run of finished rows samples the whole image.
//!
//! A frame's cost is uneven (a cheap sky above, mirrors and quadrics below): rendered top to
//! bottom, the first rows finish fast and a progress bar's estimate of the time left comes out
//! several times too short. Taken in this order, the rows done so far cost what the frame's
//! rows cost on average. Rows within a block stay consecutive, so neighbouring camera rays still
//! meet the same nodes of the acceleration structure. Pixel values depend only on their position,
//! so the order changes no pixel.

/// Consecutive rows taken up together.
pub(crate) const BLOCK_ROWS: usize = 8;

/// A sort key for each of `rows` rows, distinct, in the order they are taken up: rows sorted by
/// it come in blocks of [`BLOCK_ROWS`], the blocks in van der Corput order (block `b` keyed by its
/// index with the bits reversed), so the first `2^k` blocks taken lie one in each `2^-k` of the
/// frame, at every `k`.
pub(crate) fn row_keys(rows: usize) -> Vec<usize> {
    let blocks = rows.div_ceil(BLOCK_ROWS).max(1);
    let bits = blocks.next_power_of_two().trailing_zeros();
    let block_key = |block: usize| match bits {
        0 => 0,
        _ => block.reverse_bits() >> (usize::BITS - bits),
    };
    (0..rows)
        .map(|row| block_key(row / BLOCK_ROWS) * BLOCK_ROWS + row % BLOCK_ROWS)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_gets_its_own_key() {
        for rows in [1, 2, 7, 8, 9, 64, 90, 360, 719, 720, 2160] {
            let mut keys = row_keys(rows);
            keys.sort_unstable();
            keys.dedup();
            assert_eq!(keys.len(), rows, "{rows} rows");
        }
    }

    /// The first fifth of the rows taken up reaches every tenth of the frame: a progress
    /// estimate from them sees all of it.
    #[test]
    fn early_rows_spread_over_the_frame() {
        let rows = 720;
        let ranks = row_keys(rows);
        let mut order: Vec<usize> = (0..rows).collect();
        order.sort_by_key(|&r| ranks[r]);
        let early = &order[..rows / 5];
        for tenth in 0..10 {
            let band = tenth * rows / 10..(tenth + 1) * rows / 10;
            assert!(
                early.iter().any(|r| band.contains(r)),
                "no early row in tenth {tenth}"
            );
        }
        // Rows stay together in blocks: a block's rows have consecutive ranks.
        assert!(
            (0..rows - 1)
                .filter(|r| (r + 1) % BLOCK_ROWS != 0)
                .all(|r| ranks[r + 1] == ranks[r] + 1)
        );
    }
}
