//! The pixel sampler's points eight samples at a time in AVX2 registers: Kensler's `permute` and
//! `randfloat` hashes, the same 32-bit operations lane by lane as [`super::permute_in`] and
//! [`super::rand_float`], and the same f64 operations as [`super::multi_jittered`] (IEEE, none
//! fused), so the same points bit for bit.

use super::SampleKeys;
use std::arch::x86_64::*;

/// How the eight-wide path finds a sample's permuted column and row of strata.
#[derive(Clone, Copy, Debug)]
pub(super) enum Strata<'a> {
    /// Permuted in the lanes: the grid's columns and rows are powers of two, so a sample's
    /// column and row are a mask and a shift of its index, and Kensler's permutation of each
    /// lands in range at its first round.
    Hashed,
    /// Looked up in the pixel's table (the permuted columns, then the permuted rows), for a
    /// grid that is not: the column and row are the remainder and quotient by the column count.
    Table(&'a [u32]),
}

/// Samples `first..first + 8` of a pixel keyed by `keys` whose `count` samples (a power of two,
/// at least 2; lanes past the count hold points of no sample) lie in a grid of `m` columns and
/// `n` rows of strata: Kensler's correlated multi-jittered points, as [`super::multi_jittered`]
/// makes them one at a time. A sample's permuted index s gives its column s mod m and row
/// s div m, each permuted over its range ([`Strata`]), and its point is
/// ((column + (row + jx)/n)/m, (s + jy)/count), each division as [`super::divide`] does it (by a
/// power of two, the exact multiplication).
#[target_feature(enable = "avx2")]
pub(super) fn points(
    first: u32,
    grid: (u32, u32, u32),
    keys: SampleKeys,
    strata: Strata<'_>,
) -> [(f64, f64); 8] {
    let index = _mm256_add_epi32(splat(first), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    points_of_lanes(index, grid, LaneKeys::splat(keys), strata)
}

/// The points of `8 / count` whole pixels (`count` 2 or 4), `count` lanes each: lane k holds
/// sample k mod count of the pixel whose pattern key ([`super::pixel_pattern`]) is
/// `patterns[k / count]`, as [`points`] gives it for that pixel alone, bit for bit. At two or four
/// samples a pixel [`points`] would fill only the first lanes; this fills them all.
#[target_feature(enable = "avx2")]
pub(super) fn points_of_pixels(
    patterns: &[u32],
    (count, m, n): (u32, u32, u32),
) -> [(f64, f64); 8] {
    assert!(matches!(count, 2 | 4) && patterns.len() == (8 / count) as usize);
    let lane_pattern = |k: usize| patterns[k / count as usize] as i32;
    let pattern: [i32; 8] = std::array::from_fn(lane_pattern);
    // SAFETY: an unaligned load of eight i32s from an array of eight.
    let pattern = unsafe { _mm256_loadu_si256(pattern.as_ptr().cast()) };
    let index = _mm256_and_si256(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), splat(count - 1));
    points_of_lanes(index, (count, m, n), LaneKeys::of(pattern), Strata::Hashed)
}

/// The keys of [`SampleKeys`], lane by lane.
#[derive(Clone, Copy)]
struct LaneKeys {
    order: __m256i,
    column: __m256i,
    row: __m256i,
    jitter_x: __m256i,
    jitter_y: __m256i,
}

impl LaneKeys {
    /// One pixel's keys in every lane.
    #[target_feature(enable = "avx2")]
    fn splat(keys: SampleKeys) -> LaneKeys {
        LaneKeys {
            order: splat(keys.order),
            column: splat(keys.column),
            row: splat(keys.row),
            jitter_x: splat(keys.jitter_x),
            jitter_y: splat(keys.jitter_y),
        }
    }

    /// The keys of each lane's pattern, as [`SampleKeys::of`] makes them.
    #[target_feature(enable = "avx2")]
    fn of(pattern: __m256i) -> LaneKeys {
        let key = |k: u32| _mm256_mullo_epi32(pattern, splat(k));
        LaneKeys {
            order: key(super::ORDER_KEY),
            column: key(super::COLUMN_KEY),
            row: key(super::ROW_KEY),
            jitter_x: key(super::JITTER_X_KEY),
            jitter_y: key(super::JITTER_Y_KEY),
        }
    }
}

/// [`points`] of the sample indices `index`, lane by lane keyed by `keys`.
#[target_feature(enable = "avx2")]
fn points_of_lanes(
    index: __m256i,
    (count, m, n): (u32, u32, u32),
    keys: LaneKeys,
    strata: Strata<'_>,
) -> [(f64, f64); 8] {
    debug_assert!(count >= 2 && count.is_power_of_two());
    let s = permute(index, count, keys.order);
    let (column, row) = match strata {
        Strata::Hashed => {
            debug_assert!(m.is_power_of_two() && n.is_power_of_two());
            let column_of = _mm256_and_si256(s, splat(m - 1));
            let row_of = _mm256_srl_epi32(s, _mm_cvtsi32_si128(m.trailing_zeros() as i32));
            (
                permute(column_of, m, keys.column),
                permute(row_of, n, keys.row),
            )
        }
        Strata::Table(table) => {
            // The gathers below read inside the table only for a table of m + n entries and a
            // grid that holds the count; `divide_by` is exact for counts up to 2¹⁶ (`MAX_SPP`).
            assert!(table.len() == (m + n) as usize && count <= m * n && count <= 1 << 16);
            let (column_of, row_of) = divide_by(s, m);
            // SAFETY: a column index is below m and a row index below n (s < count ≤ m·n), so
            // every lane reads inside the table's m + n entries.
            unsafe {
                let base = table.as_ptr().cast::<i32>();
                let row_of = _mm256_add_epi32(row_of, splat(m));
                (
                    _mm256_i32gather_epi32::<4>(base, column_of),
                    _mm256_i32gather_epi32::<4>(base, row_of),
                )
            }
        }
    };
    let (jx, jy) = (rand_float(s, keys.jitter_x), rand_float(s, keys.jitter_y));
    // x / d as `divide` makes it: by the exact reciprocal for a power of two, else a division.
    let divided = |x: __m256d, d: u32| match d.is_power_of_two() {
        true => _mm256_mul_pd(x, _mm256_set1_pd(1.0 / d as f64)),
        false => _mm256_div_pd(x, _mm256_set1_pd(d as f64)),
    };
    let mut xy = [[0.0; 8]; 2];
    for half in 0..2 {
        let [s, column, row] = [s, column, row].map(|v| unsigned_f64(v, half));
        let x = divided(_mm256_add_pd(row, jx[half]), n);
        let x = divided(_mm256_add_pd(column, x), m);
        let y = divided(_mm256_add_pd(s, jy[half]), count);
        // SAFETY: each store writes four f64s inside its eight.
        unsafe {
            _mm256_storeu_pd(xy[0][4 * half..].as_mut_ptr(), x);
            _mm256_storeu_pd(xy[1][4 * half..].as_mut_ptr(), y);
        }
    }
    std::array::from_fn(|k| (xy[0][k], xy[1][k]))
}

/// The remainders and quotients of eight values below 2¹⁶ by `divisor` (below 2⁸): the quotient
/// by f64 division truncated, which is exact here (a quotient's fraction is at least 1/divisor
/// short of the next integer, far more than the division's rounding), the remainder from it.
#[target_feature(enable = "avx2")]
fn divide_by(values: __m256i, divisor: u32) -> (__m256i, __m256i) {
    let d = _mm256_set1_pd(divisor as f64);
    let quotient = |half| _mm256_cvttpd_epi32(_mm256_div_pd(unsigned_f64(values, half), d));
    let quotients = _mm256_set_m128i(quotient(1), quotient(0));
    let remainders = _mm256_sub_epi32(values, _mm256_mullo_epi32(quotients, splat(divisor)));
    (remainders, quotients)
}

/// Eight copies of `value`.
#[target_feature(enable = "avx2")]
#[inline]
fn splat(value: u32) -> __m256i {
    _mm256_set1_epi32(value as i32)
}

/// Kensler's `permute` of eight indices in [0, `len`) keyed lane by lane by `p`, for a
/// power-of-two `len`: masked to `len`'s bits, the hash lands in range at its first round, so no
/// lane walks again.
#[target_feature(enable = "avx2")]
fn permute(i: __m256i, len: u32, p: __m256i) -> __m256i {
    let w = splat(len - 1);
    let mul = |i, k: u32| _mm256_mullo_epi32(i, splat(k));
    let xor = _mm256_xor_si256;
    // p >> bits, lane by lane.
    let p_shr = |bits: i32| _mm256_srl_epi32(p, _mm_cvtsi32_si128(bits));
    // i ^= (i & w) >> s
    let fold =
        |i, bits: __m128i| _mm256_xor_si256(i, _mm256_srl_epi32(_mm256_and_si256(i, w), bits));
    let by = |s: i32| _mm_cvtsi32_si128(s);
    let mut i = mul(xor(i, p), 0xe170893d);
    i = fold(xor(i, p_shr(16)), by(4));
    i = mul(xor(i, p_shr(8)), 0x0929eb3f);
    i = fold(xor(i, p_shr(23)), by(1));
    i = mul(
        _mm256_mullo_epi32(i, _mm256_or_si256(splat(1), p_shr(27))),
        0x6935fa69,
    );
    i = mul(fold(i, by(11)), 0x74dcb303);
    i = mul(fold(i, by(2)), 0x9e501cc3);
    i = _mm256_and_si256(mul(fold(i, by(2)), 0xc860a3df), w);
    i = _mm256_xor_si256(i, _mm256_srli_epi32::<5>(i));
    // remainder(i + p, len), a mask for a power of two.
    _mm256_and_si256(_mm256_add_epi32(i, p), w)
}

/// Kensler's `randfloat` of eight indices keyed lane by lane by `p`: lanes 0–3, then 4–7, in
/// [0, 1).
#[target_feature(enable = "avx2")]
fn rand_float(i: __m256i, p: __m256i) -> [__m256d; 2] {
    let shifted = |i, bits: i32| _mm256_xor_si256(i, _mm256_srl_epi32(i, _mm_cvtsi32_si128(bits)));
    let mul = |i, k: u32| _mm256_mullo_epi32(i, splat(k));
    let mut i = _mm256_xor_si256(i, p);
    i = mul(shifted(shifted(i, 17), 10), 0xb36534e5);
    i = mul(shifted(shifted(i, 12), 21), 0x93fc4795);
    i = _mm256_xor_si256(i, splat(0xdf6e307f));
    let p_shr_18 = _mm256_srli_epi32::<18>(p);
    i = _mm256_mullo_epi32(shifted(i, 17), _mm256_or_si256(splat(1), p_shr_18));
    let scale = _mm256_set1_pd(4_294_967_808.0);
    [0, 1].map(|half| _mm256_div_pd(unsigned_f64(i, half), scale))
}

/// Lanes `4·half..4·half + 4` of eight u32s as f64s, exactly: flipped to signed values 2³¹
/// lower, converted, and moved back up.
#[target_feature(enable = "avx2")]
fn unsigned_f64(lanes: __m256i, half: usize) -> __m256d {
    let signed = _mm256_xor_si256(lanes, splat(0x8000_0000));
    let half = match half {
        0 => _mm256_castsi256_si128(signed),
        _ => _mm256_extracti128_si256::<1>(signed),
    };
    _mm256_add_pd(_mm256_cvtepi32_pd(half), _mm256_set1_pd(2_147_483_648.0))
}
