//! Colour encodings: the sRGB transfer function (IEC 61966-2-1) between linear values, which
//! quadray renders in (Rec. 709 primaries, D65 white), and display or 8-bit values, in one place
//! for the film, textures and the application layer.

use glam::Vec3;

/// The display value of a sample: the mean of its three channels after the sRGB transfer
/// function, clamped to [0, 1] (see [`display_channels`]).
pub fn display_value(radiance: Vec3) -> f32 {
    let [r, g, b] = display_channels(radiance);
    (r + g + b) / 3.0
}

/// The sRGB-encoded channels of a sample, clamped to [0, 1] (within 1e-5 of [`encode_srgb`],
/// from a table: this runs once per adaptive sample, where three `powf`s cost about 2% of an
/// adaptive render).
pub fn display_channels(radiance: Vec3) -> [f32; 3] {
    let table = &*SRGB_BY_ROOT;
    let encode = |linear: f32| {
        // The table is indexed by √linear, where the transfer function is smooth enough for
        // linear interpolation (its slope in √linear is bounded, unlike in linear).
        let position = linear.clamp(0.0, 1.0).sqrt() * SRGB_TABLE_STEPS as f32;
        let position = if position.is_nan() { 0.0 } else { position };
        // Through i32: `position` lies in [0, steps], where the truncation is the same, and a
        // float-to-usize cast is a dozen instructions on x86-64 (3% of an adaptive render).
        let index = (position as i32 as usize).min(SRGB_TABLE_STEPS - 1);
        let t = position - index as f32;
        table[index] + t * (table[index + 1] - table[index])
    };
    radiance.to_array().map(encode)
}

/// [`display_channels`] of eight samples: in AVX2 registers where the CPU has them (a channel of
/// the eight samples a register, the table's entries gathered), with the same operations as the
/// one-sample code, so the same bits.
pub fn display_channels_eight(radiances: &[Vec3; 8]) -> [[f32; 3]; 8] {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::simd_path() == crate::simd::SimdPath::Avx2 {
        // SAFETY: the CPU has AVX2 (checked by `simd_path`).
        return unsafe { display_channels_eight_avx2(radiances) };
    }
    radiances.map(display_channels)
}

/// [`display_channels_eight`] in AVX2 registers. Where a step differs from the one-sample code it
/// gives the same value: the clamp by `max` then `min` turns −0 into +0, whose table entry and
/// interpolation are the same, and NaN into 0, which the one-sample code makes of it later.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn display_channels_eight_avx2(radiances: &[Vec3; 8]) -> [[f32; 3]; 8] {
    use std::arch::x86_64::*;
    let table = &*SRGB_BY_ROOT;
    let mut channels = [[0.0f32; 8]; 3];
    for (channel, out) in channels.iter_mut().enumerate() {
        let lanes: [f32; 8] = std::array::from_fn(|k| radiances[k][channel]);
        // SAFETY: the loads and stores move the eight f32s of `lanes` and `out`; the gathers
        // read entries 0..=SRGB_TABLE_STEPS of the table, as the index is clamped below.
        unsafe {
            let v = _mm256_loadu_ps(lanes.as_ptr());
            // `max` returns its second operand where the first is NaN: NaN lanes become 0, as
            // the one-sample code makes them after the root.
            let clamped = _mm256_min_ps(_mm256_max_ps(v, _mm256_setzero_ps()), _mm256_set1_ps(1.0));
            let steps = _mm256_set1_ps(SRGB_TABLE_STEPS as f32);
            let position = _mm256_mul_ps(_mm256_sqrt_ps(clamped), steps);
            let last = _mm256_set1_epi32(SRGB_TABLE_STEPS as i32 - 1);
            let index = _mm256_min_epi32(_mm256_cvttps_epi32(position), last);
            let t = _mm256_sub_ps(position, _mm256_cvtepi32_ps(index));
            let low = _mm256_i32gather_ps::<4>(table.as_ptr(), index);
            let high = _mm256_i32gather_ps::<4>(table.as_ptr().add(1), index);
            let encoded = _mm256_add_ps(low, _mm256_mul_ps(t, _mm256_sub_ps(high, low)));
            _mm256_storeu_ps(out.as_mut_ptr(), encoded);
        }
    }
    std::array::from_fn(|k| [channels[0][k], channels[1][k], channels[2][k]])
}

/// Intervals of the table behind [`display_value`].
const SRGB_TABLE_STEPS: usize = 1024;

/// [`encode_srgb`] at √linear = i / [`SRGB_TABLE_STEPS`], for i = 0..=SRGB_TABLE_STEPS.
static SRGB_BY_ROOT: std::sync::LazyLock<[f32; SRGB_TABLE_STEPS + 1]> =
    std::sync::LazyLock::new(|| {
        std::array::from_fn(|i| {
            let root = i as f64 / SRGB_TABLE_STEPS as f64;
            encode_srgb((root * root) as f32)
        })
    });

/// The sRGB transfer function (IEC 61966-2-1) applied to a clamped linear value, as an 8-bit code:
/// `(encode_srgb(linear) · 255 + 0.5)` truncated, found from the linear values where the code
/// steps up (`Srgb8Steps`) instead of by a `powf` (13% of a quadric-grid frame's profile; the
/// frame's wall time fell 8%).
pub fn encode_srgb8(linear: f32) -> u8 {
    SRGB8_STEPS.encode(linear)
}

/// [`encode_srgb8`] of every channel of `pixels` in turn (RGB, three bytes a pixel), the table
/// looked up once: writing an image's bytes took about 90 instructions a pixel through a
/// per-channel call and a growing vector.
pub fn encode_srgb8_pixels(pixels: &[Vec3]) -> Vec<u8> {
    let table = &*SRGB8_STEPS;
    let mut bytes = vec![0u8; pixels.len() * 3];
    for (rgb, pixel) in bytes.chunks_exact_mut(3).zip(pixels) {
        for (byte, linear) in rgb.iter_mut().zip(pixel.to_array()) {
            *byte = table.encode(linear);
        }
    }
    bytes
}

/// The 8-bit code of [`encode_srgb`] computed directly, with the transfer function's `powf`.
fn encode_srgb8_direct(linear: f32) -> u8 {
    (encode_srgb(linear) * 255.0 + 0.5) as u8
}

/// Positive f32s below 1 are bucketed by their bits above this one: a bucket spans 2¹⁶ ulps
/// (under 1% of its magnitude), where the code rises by at most one or two.
const BUCKET_SHIFT: u32 = 16;

/// Where the 8-bit sRGB code steps up, and the code at the start of each bucket of positive f32s
/// below 1, so a code is a table read and a comparison or two.
struct Srgb8Steps {
    /// For each code c in 1..=255, the smallest linear f32 whose [`encode_srgb8_direct`] is at
    /// least c; then infinity, which no value reaches.
    steps: [f32; 256],
    /// The code of the smallest value of each bucket (a value's bits shifted by [`BUCKET_SHIFT`]).
    start: Vec<u8>,
}

impl Srgb8Steps {
    /// The 8-bit code of `linear` ([`encode_srgb8`]).
    #[inline]
    fn encode(&self, linear: f32) -> u8 {
        // NaN, negative values and zeros are code 0, as in `encode_srgb`; 1 and beyond code 255.
        if linear.is_nan() || linear <= 0.0 {
            return 0;
        }
        if linear >= 1.0 {
            return 255;
        }
        let mut code = self.start[(linear.to_bits() >> BUCKET_SHIFT) as usize];
        while self.steps[code as usize] <= linear {
            code += 1;
        }
        code
    }
}

/// The steps by bisection over the bit patterns of [0, 1] (ordered as integers). The code of a
/// value is then the number of steps at or below it, which equals the direct code wherever the
/// direct code is monotone; the tests check every f32 within 2¹⁶ ulps of each step, and further
/// from a step the exact encoding is too far from a rounding boundary for `powf`'s sub-ulp error
/// to matter.
static SRGB8_STEPS: std::sync::LazyLock<Srgb8Steps> = std::sync::LazyLock::new(|| {
    let mut steps = [f32::INFINITY; 256];
    for (i, step) in steps.iter_mut().take(255).enumerate() {
        let code = i as u8 + 1;
        let (mut lo, mut hi) = (0u32, 1f32.to_bits());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if encode_srgb8_direct(f32::from_bits(mid)) >= code {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        *step = f32::from_bits(lo);
    }
    let buckets = (1f32.to_bits() >> BUCKET_SHIFT) as usize + 1;
    let start = (0..buckets)
        .map(|b| {
            let first = f32::from_bits((b as u32) << BUCKET_SHIFT);
            steps.partition_point(|&s| s <= first) as u8
        })
        .collect();
    Srgb8Steps { steps, start }
});

/// The sRGB transfer function applied to a linear value clamped to [0, 1] (NaN as 0), unquantised.
pub fn encode_srgb(linear: f32) -> f32 {
    let v = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`encode_srgb8`]: an 8-bit sRGB code to linear.
pub fn decode_srgb8(code: u8) -> f32 {
    decode_srgb(code as f32 / 255.0)
}

/// The inverse of [`encode_srgb`]: an sRGB-encoded value, clamped to [0, 1], to linear.
pub fn decode_srgb(encoded: f32) -> f32 {
    let e = encoded.clamp(0.0, 1.0);
    if e <= 0.04045 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eight samples' display channels made together are each sample's made alone, bit for bit
    /// (in AVX2 registers where the CPU has them): over [0, 1] in fine steps, at the table's own
    /// points and beside them, and at −0, negatives, values above 1, infinities and NaN.
    #[test]
    fn display_channels_of_eight_are_display_channels_of_each() {
        let mut values: Vec<f32> = (0..=20_000).map(|k| k as f32 / 20_000.0).collect();
        for i in 0..=SRGB_TABLE_STEPS {
            let root = i as f32 / SRGB_TABLE_STEPS as f32;
            let on = root * root;
            values.extend([on, on.next_up(), on.next_down()]);
        }
        values.extend([-0.0, -1e-30, -0.5, -1.0, 1.0, 1.0f32.next_up(), 3.7, 1e30]);
        values.extend([
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
            1e-45,
        ]);
        let n = values.len();
        for first in (0..n).step_by(8) {
            let radiances: [Vec3; 8] = std::array::from_fn(|k| {
                let at = |offset: usize| values[(first + k + offset) % n];
                Vec3::new(at(0), at(n / 3), at(2 * n / 3))
            });
            let together = display_channels_eight(&radiances).map(|c| c.map(f32::to_bits));
            let alone = radiances.map(|r| display_channels(r).map(f32::to_bits));
            assert_eq!(together, alone, "{radiances:?}");
        }
    }

    /// The table-driven 8-bit code equals the direct one on every f32 within 2¹⁶ ulps of each
    /// step (where a rounding boundary lies), at the range's ends, on NaN and infinities, and on
    /// a million values spread over [0, 1].
    #[test]
    fn encode_srgb8_matches_the_direct_code() {
        let check = |v: f32| assert_eq!(encode_srgb8(v), encode_srgb8_direct(v), "{v:e}");
        for &step in &SRGB8_STEPS.steps[..255] {
            let bits = step.to_bits();
            for b in bits.saturating_sub(1 << 16)..=bits + (1 << 16) {
                check(f32::from_bits(b));
            }
        }
        for v in [
            0.0,
            -0.0,
            -1.0,
            1.0,
            1.5,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ] {
            check(v);
        }
        for i in 0..1_000_000u32 {
            check(i as f32 / 1_000_000.0);
        }
    }

    /// The table-driven display value stays within 1e-5 of the transfer function everywhere,
    /// including the linear segment near black, its joint and out-of-range values.
    #[test]
    fn display_value_matches_the_transfer_function() {
        let mut worst = 0.0f32;
        for i in 0..=200_000u32 {
            let linear = (i as f32 / 100_000.0).powi(3) - 0.01;
            let exact = encode_srgb(linear);
            worst = worst.max((display_value(Vec3::splat(linear)) - exact).abs());
        }
        assert!(worst < 1e-5, "worst difference {worst}");
        let mixed = Vec3::new(0.002, 0.5, 3.0);
        let exact = mixed.to_array().map(encode_srgb).iter().sum::<f32>() / 3.0;
        assert!((display_value(mixed) - exact).abs() < 1e-5);
        assert_eq!(display_value(Vec3::splat(f32::NAN)), 0.0);
    }

    #[test]
    fn srgb_round_trips_and_clamps() {
        for code in 0..=255u8 {
            assert_eq!(encode_srgb8(decode_srgb8(code)), code);
        }
        assert_eq!(encode_srgb8(7.0), 255);
        assert_eq!(encode_srgb8(-1.0), 0);
        assert_eq!(encode_srgb8(0.5), 188);
    }
}
