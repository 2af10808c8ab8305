//! Per-pixel sample positions: correlated multi-jittered sampling (Kensler, "Correlated Multi-Jittered
//! Sampling", Pixar Technical Memo 13-01, 2013), seeded by the pixel, so every pixel's samples are
//! fixed whatever the thread count.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod progressive;

pub use progressive::progressive_2d;

use crate::limits::MAX_SPP;
use crate::simd::{SimdPath, simd_path};

/// A pseudo-random permutation of [0, len) indexed by `i`, keyed by `pattern` (Kensler's `permute`).
fn permute(i: u32, len: u32, pattern: u32) -> u32 {
    permute_in(i, len, walk_mask(len), pattern)
}

/// The mask of `len`'s bits and all below (Kensler's `w`): the range [`permute`] walks in.
fn walk_mask(len: u32) -> u32 {
    let mut w = len - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    w
}

/// [`permute`] with `len`'s [`walk_mask`] `w` given.
#[inline(always)]
fn permute_in(mut i: u32, len: u32, w: u32, pattern: u32) -> u32 {
    let p = pattern;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dcb303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e501cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            break;
        }
    }
    remainder(i.wrapping_add(p), len)
}

/// `value % divisor` (`divisor` > 0), with a mask where `divisor` is a power of two: sample counts
/// usually are, and an integer division costs tens of cycles (measured on defense at 64 spp,
/// [`sample_2d`] went from 8.4% to 7.5% of the render's time).
fn remainder(value: u32, divisor: u32) -> u32 {
    if divisor.is_power_of_two() {
        value & (divisor - 1)
    } else {
        value % divisor
    }
}

/// `value / divisor` (`divisor` > 0), with a shift where `divisor` is a power of two (see
/// [`remainder`]).
fn quotient(value: u32, divisor: u32) -> u32 {
    if divisor.is_power_of_two() {
        value >> divisor.trailing_zeros()
    } else {
        value / divisor
    }
}

/// A hashed float in [0, 1) from `i` keyed by `pattern` (Kensler's `randfloat`).
fn rand_float(mut i: u32, pattern: u32) -> f64 {
    let p = pattern;
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i = i.wrapping_mul(0xb36534e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i = i.wrapping_mul(0x93fc4795);
    i ^= 0xdf6e307f;
    i ^= i >> 17;
    i = i.wrapping_mul(1 | p >> 18);
    i as f64 / 4294967808.0
}

/// Which sample of which pixel a camera ray stands for, so the integrator can draw its own 2-D
/// samples (glossy reflection directions) stratified over the pixel's samples as anti-aliasing
/// is: one independent set per bounce, deterministic for a given sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleKey {
    /// The pixel's pattern key ([`pixel_pattern`]).
    pub pattern: u32,
    /// The sample's index within its pixel.
    pub index: u32,
    /// The pixel's sample count when its samples are one stratified set ([`sample_2d`]), or
    /// `None` for the open-ended progressive sequence ([`progressive_2d`]).
    pub count: Option<u32>,
}

impl SampleKey {
    /// The key of a lone ray outside any render (tests, picking): sample 0 of 1 of pattern 0.
    pub const LONE: SampleKey = SampleKey {
        pattern: 0,
        index: 0,
        count: Some(1),
    };

    /// The sample's 2-D point in [0, 1)² for bounce `depth`: the same kind of set as the pixel's
    /// own samples (stratified over the pixel's `count`, or its progressive sequence), keyed
    /// apart from them and from other bounces. A lone sample gets a hashed point rather than the
    /// centre, which would pick one fixed direction for every pixel.
    pub fn bounce(&self, depth: u32) -> (f64, f64) {
        let pattern = pixel_pattern(self.pattern, depth, 0x6b43_a9b5);
        match self.count {
            Some(count) if count > 1 => sample_2d(self.index, count, pattern),
            Some(_) => (
                rand_float(self.index, pattern),
                rand_float(self.index, pattern.wrapping_mul(JITTER_Y_KEY)),
            ),
            None => progressive_2d(self.index, pattern),
        }
    }
}

/// The pattern key of pixel (x, y) in the sample set `seed`: a 32-bit hash, distinct per pixel.
///
/// Seed 0 is the renderer's default; another seed gives every pixel an unrelated pattern (a
/// statistically independent render of the same image, e.g. a reference for error measurements).
pub fn pixel_pattern(x: u32, y: u32, seed: u32) -> u32 {
    // The seed moves the key by an odd multiple of a 64-bit constant; seed 0 leaves it unchanged.
    let mut h = ((x as u64) << 32 | y as u64) ^ (seed as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    // SplitMix64 finaliser.
    h = h.wrapping_add(0x9E3779B97F4A7C15);
    h = (h ^ (h >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94D049BB133111EB);
    (h ^ (h >> 31)) as u32
}

// Multipliers that key each of the pattern's hashes (Kensler's constants).
/// Keys the order in which the strata are visited.
const ORDER_KEY: u32 = 0x51633e2d;
/// Keys the permutation of the columns.
const COLUMN_KEY: u32 = 0x68bc21eb;
/// Keys the permutation of the rows.
const ROW_KEY: u32 = 0x02e5be93;
/// Keys the jitter within a stratum in x.
const JITTER_X_KEY: u32 = 0x967a889b;
/// Keys the jitter within a stratum in y.
const JITTER_Y_KEY: u32 = 0x368cc8b7;

/// The grid of strata `count` samples are jittered in: ⌊√count⌋ columns and enough rows for all.
fn strata(count: u32) -> (u32, u32) {
    let columns = ((count as f64).sqrt() as u32).max(1);
    (columns, count.div_ceil(columns))
}

/// A pixel's keys for the hashes of its samples ([`multi_jittered`]): of the order the strata
/// are visited in, of the permutations of its columns and rows of strata, and of the jitter in x
/// and in y.
#[derive(Clone, Copy, Debug, Default)]
struct SampleKeys {
    order: u32,
    column: u32,
    row: u32,
    jitter_x: u32,
    jitter_y: u32,
}

impl SampleKeys {
    /// The keys of pixel `pattern`.
    fn of(pattern: u32) -> SampleKeys {
        SampleKeys {
            order: pattern.wrapping_mul(ORDER_KEY),
            column: pattern.wrapping_mul(COLUMN_KEY),
            row: pattern.wrapping_mul(ROW_KEY),
            jitter_x: pattern.wrapping_mul(JITTER_X_KEY),
            jitter_y: pattern.wrapping_mul(JITTER_Y_KEY),
        }
    }
}

/// Sample `s` of `count` (more than one, whose [`walk_mask`] is `count_mask`) in the `(m, n)` grid
/// of [`strata`], given the pixel's `keys` and its permutations of the columns and rows
/// (Kensler's correlated multi-jitter).
#[inline]
fn multi_jittered(
    s: u32,
    (count, count_mask): (u32, u32),
    (m, n): (u32, u32),
    keys: SampleKeys,
    permuted_column: impl Fn(u32) -> u32,
    permuted_row: impl Fn(u32) -> u32,
) -> (f64, f64) {
    let s = permute_in(s, count, count_mask, keys.order);
    let sx = permuted_column(remainder(s, m));
    let sy = permuted_row(quotient(s, m));
    let jx = rand_float(s, keys.jitter_x);
    let jy = rand_float(s, keys.jitter_y);
    (
        divide(sx as f64 + divide(sy as f64 + jx, n), m),
        divide(s as f64 + jy, count),
    )
}

/// `x / d` (`d` > 0), by a multiplication where `d` is a power of two, whose reciprocal 2^-k is
/// exact, so the quotient is bit-identical (as [`remainder`] does for integers): the divisions
/// were most of a sample point's cost at the usual counts (4, 16, 64).
#[inline(always)]
fn divide(x: f64, d: u32) -> f64 {
    if d.is_power_of_two() {
        x * f64::from_bits((1023 - d.trailing_zeros() as u64) << 52)
    } else {
        x / d as f64
    }
}

/// Sample `s` of `count` within the unit pixel: the centre for one sample, else stratified jitter.
/// ([`PixelSampler`] gives the same points for a whole pixel at less cost.)
pub fn sample_2d(s: u32, count: u32, pattern: u32) -> (f64, f64) {
    if count <= 1 {
        return (0.5, 0.5);
    }
    let (m, n) = strata(count);
    let keys = SampleKeys::of(pattern);
    multi_jittered(
        s,
        (count, walk_mask(count)),
        (m, n),
        keys,
        |column| permute(column, m, keys.column),
        |row| permute(row, n, keys.row),
    )
}

/// [`sample_2d`] for every sample of one pixel at a time. The permutations of the pixel's columns
/// and rows of strata are keyed by the pixel alone, so the scalar path computes them once per
/// pixel (m + n hashes) instead of once per sample (2 · count); the eight-wide path permutes them
/// in its lanes where the grid is a power of two, and reads the same table otherwise. The points
/// are bit-identical to [`sample_2d`]'s. Measured on defense at 64 spp, `sample_2d` alone took
/// 7.5% of the render.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    count: u32,
    columns: u32,
    rows: u32,
    /// [`walk_mask`] of the count, the columns and the rows.
    masks: [u32; 3],
    /// The current pixel's keys.
    keys: SampleKeys,
    /// The permuted column of each column index, then the permuted row of each row index.
    strata: Vec<u32>,
    /// Whether [`PixelSampler::samples`] makes eight samples at once in AVX2 registers (on CPUs
    /// that have them, for counts from 2 to [`MAX_SPP`] that are powers of two; a count below
    /// eight keeps the first lanes).
    eight_wide: bool,
    /// Whether the grid's columns and rows are powers of two, so that the eight-wide path
    /// permutes them in its lanes (`avx2::Strata::Hashed`) and no table is built.
    strata_hashed: bool,
}

impl PixelSampler {
    /// A sampler for `count` samples a pixel, ready for [`PixelSampler::start_pixel`].
    pub fn new(count: u32) -> PixelSampler {
        let (columns, rows) = strata(count);
        PixelSampler {
            count,
            columns,
            rows,
            masks: [walk_mask(count.max(1)), walk_mask(columns), walk_mask(rows)],
            keys: SampleKeys::default(),
            strata: vec![0; (columns + rows) as usize],
            eight_wide: cfg!(target_arch = "x86_64")
                && simd_path() == SimdPath::Avx2
                && count >= 2
                && count.is_power_of_two()
                && count <= MAX_SPP,
            strata_hashed: columns.is_power_of_two() && rows.is_power_of_two(),
        }
    }

    /// Starts the pixel whose pattern key is `pattern` ([`pixel_pattern`]). Inlined, so a render
    /// of one sample a pixel pays nothing for it.
    #[inline]
    pub fn start_pixel(&mut self, pattern: u32) {
        if self.count > 1 {
            self.start_pixel_of_many(pattern);
        }
    }

    /// [`PixelSampler::start_pixel`] for more than one sample a pixel.
    fn start_pixel_of_many(&mut self, pattern: u32) {
        self.keys = SampleKeys::of(pattern);
        if self.eight_wide && self.strata_hashed {
            // The eight-wide path permutes each sample's column and row itself.
            return;
        }
        let (m, n) = (self.columns, self.rows);
        let (columns, rows) = self.strata.split_at_mut(m as usize);
        for (i, column) in columns.iter_mut().enumerate() {
            *column = permute_in(i as u32, m, self.masks[1], self.keys.column);
        }
        for (i, row) in rows.iter_mut().enumerate() {
            *row = permute_in(i as u32, n, self.masks[2], self.keys.row);
        }
    }

    /// Every sample of the current pixel in order: `points[s]` is, bit for bit,
    /// [`sample_2d`]`(s, count, pattern)` (`points` holds the count). Made eight samples at a time in
    /// AVX2 registers where the CPU has them and the count is a power of two (`avx2::points`):
    /// the hashes were a tenth of an 8-spp render of the quadric grid.
    #[inline]
    pub fn samples(&self, points: &mut [(f64, f64)]) {
        assert_eq!(points.len(), self.count as usize, "one point per sample");
        match self.count {
            0 | 1 => points.fill((0.5, 0.5)),
            _ => self.samples_of_many(points),
        }
    }

    /// Every sample of each pixel whose pattern key is in `patterns`, pixel after pixel:
    /// `points[count·i + s]` is sample s of pixel i, [`PixelSampler::samples`] of that pixel bit
    /// for bit. At two or four samples a pixel on the eight-wide path, the samples of four or two
    /// pixels share the eight lanes of one call (one pixel's would fill two or four of them);
    /// otherwise pixel by pixel. Which pixel the sampler is left on is not said:
    /// [`PixelSampler::samples`] wants [`PixelSampler::start_pixel`] first, as always.
    pub fn samples_of_pixels(&mut self, patterns: &[u32], points: &mut [(f64, f64)]) {
        let count = self.count as usize;
        assert_eq!(points.len(), patterns.len() * count, "count points a pixel");
        #[cfg(target_arch = "x86_64")]
        let (patterns, points) = self.samples_in_groups(patterns, points);
        for (&pattern, pixel) in patterns.iter().zip(points.chunks_exact_mut(count.max(1))) {
            self.start_pixel(pattern);
            self.samples(pixel);
        }
    }

    /// The first part of [`PixelSampler::samples_of_pixels`]: the pixels that fill whole groups
    /// of eight lanes, where several pixels share them (two or four samples a pixel on the
    /// eight-wide path); returns the pixels left and their points.
    #[cfg(target_arch = "x86_64")]
    fn samples_in_groups<'p, 'q>(
        &self,
        patterns: &'p [u32],
        points: &'q mut [(f64, f64)],
    ) -> (&'p [u32], &'q mut [(f64, f64)]) {
        let count = self.count as usize;
        if !(self.eight_wide && self.strata_hashed && count < 8) {
            return (patterns, points);
        }
        let grid = (self.count, self.columns, self.rows);
        let pixels = 8 / count;
        let whole = patterns.len() / pixels * pixels;
        let groups = patterns[..whole].chunks_exact(pixels);
        for (group, lanes) in groups.zip(points.as_chunks_mut::<8>().0) {
            // SAFETY: `eight_wide` is set only where the CPU has AVX2 (`simd_path`).
            *lanes = unsafe { avx2::points_of_pixels(group, grid) };
        }
        (&patterns[whole..], &mut points[whole * count..])
    }

    /// [`PixelSampler::samples`] for more than one sample a pixel.
    fn samples_of_many(&self, points: &mut [(f64, f64)]) {
        #[cfg(target_arch = "x86_64")]
        if self.eight_wide {
            let grid = (self.count, self.columns, self.rows);
            let strata = match self.strata_hashed {
                true => avx2::Strata::Hashed,
                false => avx2::Strata::Table(&self.strata),
            };
            let (groups, rest) = points.as_chunks_mut::<8>();
            let after_groups = 8 * groups.len() as u32;
            for (first, group) in (0..).step_by(8).zip(groups) {
                // SAFETY: `eight_wide` is set only where the CPU has AVX2 (`simd_path`).
                *group = unsafe { avx2::points(first, grid, self.keys, strata) };
            }
            // Fewer than eight left (two or four samples): the first lanes of one more group.
            if !rest.is_empty() {
                // SAFETY: as above.
                let group = unsafe { avx2::points(after_groups, grid, self.keys, strata) };
                rest.copy_from_slice(&group[..rest.len()]);
            }
            return;
        }
        for (s, point) in (0..).zip(points) {
            *point = self.sample(s);
        }
    }

    /// Sample `s` of the current pixel: [`sample_2d`]`(s, count, pattern)`, with the pixel's
    /// keys and the count's mask computed once (from the strata table, which the eight-wide path
    /// does not fill).
    fn sample(&self, s: u32) -> (f64, f64) {
        if self.count <= 1 {
            return (0.5, 0.5);
        }
        let m = self.columns;
        multi_jittered(
            s,
            (self.count, self.masks[0]),
            (m, self.rows),
            self.keys,
            |column| self.strata[column as usize],
            |row| self.strata[(m + row) as usize],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_stratified_in_both_axes() {
        for count in [2u32, 4, 5, 16, 64] {
            let pattern = pixel_pattern(17, 42, 0);
            let pts: Vec<_> = (0..count).map(|s| sample_2d(s, count, pattern)).collect();
            for axis in 0..2 {
                let mut strata: Vec<u32> = pts
                    .iter()
                    .map(|p| ((if axis == 0 { p.0 } else { p.1 }) * count as f64) as u32)
                    .collect();
                strata.sort();
                if axis == 1 {
                    assert_eq!(strata, (0..count).collect::<Vec<_>>(), "count {count}");
                }
            }
            assert!(
                pts.iter()
                    .all(|&(x, y)| (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y))
            );
        }
    }

    /// The low sample counts' points are not a subset of a higher count's with the same key (the
    /// counts stratify at different resolutions), and another seed gives unrelated points.
    #[test]
    fn sample_sets_of_different_counts_and_seeds_do_not_share_points() {
        for (x, y) in [(0, 0), (17, 42), (319, 179)] {
            let points = |count: u32, seed: u32| -> Vec<(f64, f64)> {
                let pattern = pixel_pattern(x, y, seed);
                (0..count).map(|s| sample_2d(s, count, pattern)).collect()
            };
            let reference = points(1024, 0);
            for count in [1, 4, 16, 64, 256] {
                for p in points(count, 0) {
                    assert!(
                        !reference.contains(&p),
                        "{count} spp shares {p:?} with 1024 spp"
                    );
                }
            }
            assert_ne!(pixel_pattern(x, y, 0), pixel_pattern(x, y, 1));
            let other = points(1024, 1);
            assert!(reference.iter().all(|p| !other.contains(p)));
        }
    }

    #[test]
    fn divisions_by_powers_of_two_are_exact_multiplications() {
        for d in [1, 2, 3, 4, 6, 8, 64, 100, 1 << 20, 1 << 31] {
            for x in [
                0.0,
                0.3,
                0.999_999_999,
                1.0,
                7.25,
                63.999,
                1e9,
                4294967295.0,
            ] {
                assert_eq!(
                    divide(x, d).to_bits(),
                    (x / d as f64).to_bits(),
                    "{x} / {d}"
                );
            }
        }
    }

    #[test]
    fn remainders_and_quotients_match_the_division() {
        for divisor in [1, 2, 3, 7, 8, 64, 100, 1 << 20] {
            for value in [0, 1, 5, 63, 64, 65, 1000, u32::MAX] {
                assert_eq!(
                    remainder(value, divisor),
                    value % divisor,
                    "{value} % {divisor}"
                );
                assert_eq!(
                    quotient(value, divisor),
                    value / divisor,
                    "{value} / {divisor}"
                );
            }
        }
    }

    /// Samples of several pixels made at once (four or two pixels to a group of lanes at two or
    /// four samples a pixel on the AVX2 path, the rest one by one) are each pixel's own points,
    /// bit for bit, for runs of pixels that fill whole groups and runs that leave some over.
    #[test]
    fn several_pixels_at_once_get_each_pixels_own_points() {
        let patterns: Vec<u32> = (0..11u32)
            .map(|i| pixel_pattern(i, 7 * i + 3, 5))
            .chain([0, u32::MAX, 0x8000_0001])
            .collect();
        for count in [1u32, 2, 3, 4, 8, 16, 32] {
            let mut sampler = PixelSampler::new(count);
            // Runs of 1 to 14 pixels: whole groups of lanes and what is left after them.
            for pixels in 1..=patterns.len() {
                let patterns = &patterns[..pixels];
                let mut points = vec![(0.0, 0.0); pixels * count as usize];
                sampler.samples_of_pixels(patterns, &mut points);
                for (i, &pattern) in patterns.iter().enumerate() {
                    for s in 0..count {
                        let point = points[i * count as usize + s as usize];
                        let expected = sample_2d(s, count, pattern);
                        assert_eq!(
                            [point.0.to_bits(), point.1.to_bits()],
                            [expected.0.to_bits(), expected.1.to_bits()],
                            "count {count}, {pixels} pixels, pixel {i}, sample {s}"
                        );
                    }
                }
            }
        }
    }

    /// A pixel's samples made together are `sample_2d`'s points bit for bit, on both paths: the
    /// powers of two from 8 take the eight-wide one where the CPU has AVX2 (asserted there), 8,
    /// 16, 64, 256 and 1024 with their strata permuted in the lanes, 32, 128 and 512 (grids of
    /// 5x7, 11x12 and 22x24) through the table; the other counts the scalar one.
    #[test]
    fn the_pixel_sampler_gives_sample_2d_s_points() {
        if simd_path() == SimdPath::Avx2 {
            let (eight, thirty_two) = (PixelSampler::new(8), PixelSampler::new(32));
            assert!(eight.eight_wide && eight.strata_hashed);
            assert!(thirty_two.eight_wide && !thirty_two.strata_hashed);
            assert!([2, 4].map(PixelSampler::new).iter().all(|s| s.eight_wide));
            assert!(!PixelSampler::new(3).eight_wide);
            assert!(!PixelSampler::new(100).eight_wide);
        }
        for count in [
            1u32, 2, 3, 4, 7, 8, 16, 17, 32, 64, 100, 128, 255, 256, 512, 1024,
        ] {
            let mut sampler = PixelSampler::new(count);
            let mut points = vec![(0.0, 0.0); count as usize];
            for pattern in [0u32, 1, 0x9e37_79b9, 0x8000_0001, u32::MAX] {
                sampler.start_pixel(pattern);
                sampler.samples(&mut points);
                for (s, point) in (0..).zip(&points) {
                    let expected = sample_2d(s, count, pattern);
                    assert_eq!(
                        [point.0.to_bits(), point.1.to_bits()],
                        [expected.0.to_bits(), expected.1.to_bits()],
                        "count {count}, pattern {pattern}, sample {s}"
                    );
                }
            }
        }
    }

    #[test]
    fn one_sample_is_the_pixel_centre() {
        assert_eq!(sample_2d(0, 1, 123), (0.5, 0.5));
    }
}
