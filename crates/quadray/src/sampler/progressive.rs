//! The progressive sequence: sample points that do not depend on a total count, for the
//! samplers that add samples in rounds (adaptive sampling, the viewer's progressive film).

/// Point `index` of pixel `pattern`'s progressive sequence in the unit pixel: the first two
/// dimensions of the Sobol sequence, Owen-scrambled per pixel (hash-based nested uniform
/// scrambling, Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020).
///
/// Unlike [`super::sample_2d`], the points do not depend on a total count: every prefix of 2^k points is
/// a (0, k, 2)-net (one point in each of the 2^k elementary intervals of every shape), so samples
/// added in rounds keep the stratification of the ones before them. The scramble keeps that
/// property and decorrelates the pixels.
pub fn progressive_2d(index: u32, pattern: u32) -> (f64, f64) {
    // Dimension 0 of Sobol is the van der Corput sequence (the index's bits reversed); dimension
    // 1 uses the direction numbers v_k = v_{k-1} ^ (v_{k-1} >> 1), v_0 = 2^31. The scramble works
    // on the reversed bits, so both are made reversed: dimension 0 is the index itself, and
    // dimension 1 sums the reversed direction numbers r_k = r_{k-1} ^ (r_{k-1} << 1), r_0 = 1
    // (reversal is linear over xor). Without a bit-reversal instruction on baseline x86-64 this
    // saves three of the five reversals.
    // The sum over the index's set bits, a byte at a time from tables (a loop over the bits
    // branched on each, mispredicted about once a point).
    let [b0, b1, b2, b3] = index.to_le_bytes().map(usize::from);
    let y_reversed = Y_REVERSED[0][b0] ^ Y_REVERSED[1][b1] ^ Y_REVERSED[2][b2] ^ Y_REVERSED[3][b3];
    let x = owen_scramble_reversed(index, pattern.wrapping_mul(0x8da6b343));
    let y = owen_scramble_reversed(y_reversed, pattern.wrapping_mul(0xd8163841) ^ 0x6c50b47c);
    // 2^-32 keeps the coordinates below 1.
    let unit = 1.0 / 4294967296.0;
    (x as f64 * unit, y as f64 * unit)
}

/// For byte `k` of an index holding `b`, the xor of the reversed direction numbers r_{8k+j} of
/// dimension 1 over the set bits j of `b` ([`progressive_2d`]).
static Y_REVERSED: [[u32; 256]; 4] = y_reversed_tables();

/// [`Y_REVERSED`], made at compile time.
const fn y_reversed_tables() -> [[u32; 256]; 4] {
    // r_0 = 1, r_k = r_{k-1} ^ (r_{k-1} << 1).
    let mut directions = [0u32; 32];
    let (mut k, mut direction) = (0, 1u32);
    while k < 32 {
        directions[k] = direction;
        direction ^= direction << 1;
        k += 1;
    }
    let mut tables = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut value = 0;
        while value < 256 {
            let (mut sum, mut bit) = (0u32, 0);
            while bit < 8 {
                if value >> bit & 1 != 0 {
                    sum ^= directions[8 * byte + bit];
                }
                bit += 1;
            }
            tables[byte][value] = sum;
            value += 1;
        }
        byte += 1;
    }
    tables
}

/// Nested uniform (Owen) scrambling, keyed by `seed`, of the 32-bit binary fraction whose bits
/// reversed are `reversed`: each bit is flipped by a hash of the bits above it. It works on the
/// reversed bits, where Laine and Karras's hash flips each bit by the bits below it.
fn owen_scramble_reversed(reversed: u32, seed: u32) -> u32 {
    let mut v = reversed.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50b47c);
    v ^= v.wrapping_mul(0xb82f1e52);
    v ^= v.wrapping_mul(0xc7afe638);
    v ^= v.wrapping_mul(0x8d22f6e6);
    v.reverse_bits()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::pixel_pattern;

    /// The progressive points are those of the sequence as first written: Sobol's two
    /// dimensions in their own bit order, each reversed, scrambled and reversed back.
    #[test]
    fn progressive_points_match_the_direct_construction() {
        let scramble = |value: u32, seed: u32| {
            let mut v = value.reverse_bits().wrapping_add(seed);
            v ^= v.wrapping_mul(0x6c50b47c);
            v ^= v.wrapping_mul(0xb82f1e52);
            v ^= v.wrapping_mul(0xc7afe638);
            v ^= v.wrapping_mul(0x8d22f6e6);
            v.reverse_bits()
        };
        for pattern in [0u32, 1, 0x9e37_79b9, u32::MAX] {
            for index in (0..4096).chain([u32::MAX / 3, u32::MAX - 1, u32::MAX]) {
                let x = index.reverse_bits();
                let (mut y, mut direction, mut bits) = (0u32, 1u32 << 31, index);
                while bits != 0 {
                    if bits & 1 != 0 {
                        y ^= direction;
                    }
                    bits >>= 1;
                    direction ^= direction >> 1;
                }
                let x = scramble(x, pattern.wrapping_mul(0x8da6b343));
                let y = scramble(y, pattern.wrapping_mul(0xd8163841) ^ 0x6c50b47c);
                let unit = 1.0 / 4294967296.0;
                let want = (x as f64 * unit, y as f64 * unit);
                assert_eq!(progressive_2d(index, pattern), want, "{index}, {pattern}");
            }
        }
    }

    /// Every power-of-two prefix of a pixel's progressive sequence is a (0, k, 2)-net: for each
    /// split of 2^k into 2^i columns by 2^(k-i) rows, every cell holds exactly one point.
    #[test]
    fn progressive_prefixes_are_nets() {
        for pattern in [
            pixel_pattern(0, 0, 0),
            pixel_pattern(17, 42, 0),
            pixel_pattern(3, 9, 5),
        ] {
            for k in 0..=8u32 {
                let n = 1u32 << k;
                let pts: Vec<_> = (0..n).map(|i| progressive_2d(i, pattern)).collect();
                for i in 0..=k {
                    let (cols, rows) = (1u32 << i, 1u32 << (k - i));
                    let mut seen = vec![false; n as usize];
                    for &(x, y) in &pts {
                        assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                        let cell = (y * rows as f64) as u32 * cols + (x * cols as f64) as u32;
                        assert!(
                            !seen[cell as usize],
                            "k {k}, {cols}x{rows}: cell {cell} twice"
                        );
                        seen[cell as usize] = true;
                    }
                }
            }
        }
    }

    /// The scramble differs between pixels: two pixels' first points are unrelated.
    #[test]
    fn progressive_sequences_differ_between_pixels() {
        let a = progressive_2d(0, pixel_pattern(1, 1, 0));
        let b = progressive_2d(0, pixel_pattern(2, 1, 0));
        assert_ne!(a, b);
        // The mean of many pixels' first points is near the pixel centre (unbiased scramble).
        let n = 4096;
        let mean = (0..n)
            .map(|i| progressive_2d(0, pixel_pattern(i, 7, 0)))
            .fold((0.0, 0.0), |s, p| {
                (s.0 + p.0 / n as f64, s.1 + p.1 / n as f64)
            });
        assert!(
            (mean.0 - 0.5).abs() < 0.02 && (mean.1 - 0.5).abs() < 0.02,
            "{mean:?}"
        );
    }
}
