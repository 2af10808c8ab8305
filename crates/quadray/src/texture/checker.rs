//! The checkerboard filtered over a footprint: the mean of three square waves' product, the x and
//! y waves in the two lanes of SSE2 registers where they can be.

use glam::{DVec3, Vec3};

/// The mean checker colour over the box `q` ± `w` (in cells): the checker is the product of three
/// square waves, and a box average of a product of functions of one axis each is the product of
/// their averages. Out of line, so the point-sampled textures' code stays small.
#[inline(never)]
pub(super) fn filtered_checker(q: DVec3, w: DVec3, even: Vec3, odd: Vec3) -> Vec3 {
    let [mean_x, mean_y] = square_wave_means_xy(q, w);
    let sign = mean_x * mean_y * square_wave_mean(q.z, w.z);
    even.lerp(odd, (0.5 - 0.5 * sign) as f32)
}

/// [`square_wave_mean`] of the x and the y axis, bit for bit: in the two lanes of SSE2 registers
/// on x86-64 where both extents are positive and the footprint's bounds within ±2⁵² (a plane's
/// checker, and most of any other's), else one by one.
#[inline(always)]
fn square_wave_means_xy(q: DVec3, w: DVec3) -> [f64; 2] {
    #[cfg(target_arch = "x86_64")]
    if let Some(means) = sse2::square_wave_means([q.x, q.y], [w.x, w.y]) {
        return means;
    }
    [square_wave_mean(q.x, w.x), square_wave_mean(q.y, w.y)]
}

#[cfg(target_arch = "x86_64")]
mod sse2 {
    use std::arch::x86_64::*;

    /// [`super::square_wave_mean`] of two axes at once, the same operations in the same order
    /// (the floors exact either way); `None` where a lane's extent is not positive or a bound's
    /// half is NaN or beyond ±2⁵¹, the range of the floor below.
    #[inline(always)]
    pub(super) fn square_wave_means(x: [f64; 2], w: [f64; 2]) -> Option<[f64; 2]> {
        // SAFETY: SSE2 is enabled on every x86-64 target (its baseline), all these intrinsics
        // ask; the unaligned loads and the store read and write two-element arrays whole.
        unsafe {
            let (x, w) = (_mm_loadu_pd(x.as_ptr()), _mm_loadu_pd(w.as_ptr()));
            let (upper, lower) = (_mm_add_pd(x, w), _mm_sub_pd(x, w));
            let half = _mm_set1_pd(0.5);
            let (upper_half, lower_half) = (_mm_mul_pd(half, upper), _mm_mul_pd(half, lower));
            // Positive extents (false for NaN), halves within ±2⁵¹ (false for NaN).
            let limit = _mm_set1_pd(2_251_799_813_685_248.0);
            let abs = |v: __m128d| _mm_andnot_pd(_mm_set1_pd(-0.0), v);
            let ok = _mm_and_pd(
                _mm_cmpgt_pd(w, _mm_setzero_pd()),
                _mm_and_pd(
                    _mm_cmplt_pd(abs(upper_half), limit),
                    _mm_cmplt_pd(abs(lower_half), limit),
                ),
            );
            if _mm_movemask_pd(ok) != 0b11 {
                return None;
            }
            // ∫₀ˣ of the wave, m = x − 2·⌊x/2⌋ folded at 1, as `square_wave_mean` computes it.
            let two = _mm_set1_pd(2.0);
            let integral = |v: __m128d, v_half: __m128d| {
                let m = _mm_sub_pd(v, _mm_mul_pd(two, floor(v_half)));
                let below = _mm_cmplt_pd(m, _mm_set1_pd(1.0));
                _mm_or_pd(
                    _mm_and_pd(below, m),
                    _mm_andnot_pd(below, _mm_sub_pd(two, m)),
                )
            };
            let change = _mm_sub_pd(integral(upper, upper_half), integral(lower, lower_half));
            let mean = _mm_div_pd(change, _mm_mul_pd(two, w));
            // f64::clamp(−1, 1): MINPD and MAXPD return their second operand for a NaN.
            let clamped = _mm_max_pd(_mm_set1_pd(-1.0), _mm_min_pd(_mm_set1_pd(1.0), mean));
            let mut out = [0.0; 2];
            _mm_storeu_pd(out.as_mut_ptr(), clamped);
            Some(out)
        }
    }

    /// ⌊v⌋ for |v| < 2⁵¹: v rounded to an integer by adding and removing 1.5·2⁵², less one
    /// where that rounded up. Exact, as every floor is, but for the sign of a zero: ⌊−0⌋ comes
    /// out +0. That leaves m = v − 2·⌊v/2⌋ above as it is: v/2 is −0 only for a tiny negative v
    /// (never −0 itself, x ± w with w > 0), and v − 2·(±0) is v.
    #[inline(always)]
    fn floor(v: __m128d) -> __m128d {
        // SAFETY: SSE2 is enabled on every x86-64 target (its baseline), all these intrinsics ask.
        unsafe {
            let magic = _mm_set1_pd(6_755_399_441_055_744.0);
            let rounded = _mm_sub_pd(_mm_add_pd(v, magic), magic);
            let above = _mm_cmpgt_pd(rounded, v);
            _mm_sub_pd(rounded, _mm_and_pd(above, _mm_set1_pd(1.0)))
        }
    }
}

/// The mean over [x − w, x + w] of the square wave that is +1 on even cells [2k, 2k + 1) and −1 on
/// odd ones: the change of its integral, a triangle wave, over the interval's width.
#[inline(always)]
fn square_wave_mean(x: f64, w: f64) -> f64 {
    if w <= 0.0 {
        // Integer parity, as the point-sampled checker takes it (a float remainder is slower).
        return if (crate::math::floor(x) as i64) & 1 == 0 {
            1.0
        } else {
            -1.0
        };
    }
    // ∫₀ˣ of the wave: rises on even cells, falls on odd ones, period 2.
    let integral = |x: f64| {
        let m = x - 2.0 * crate::math::floor(0.5 * x);
        if m < 1.0 { m } else { 2.0 - m }
    };
    // Far from the origin the two integrals cancel badly; the mean stays a mean.
    ((integral(x + w) - integral(x - w)) / (2.0 * w)).clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two-lane square-wave means equal the scalar ones bit for bit: random coordinates and
    /// extents over many scales, coordinates on and beside cell borders and near the lanes'
    /// ±2⁵² limit, tiny and subnormal extents; lanes it cannot take (an extent not positive, a
    /// bound beyond the limit, NaN) go to the scalar path.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn two_lane_square_wave_means_are_the_scalar_ones() {
        let mut next = crate::test_rng::centred_stream(0xc4ec_4e55);
        let mut coordinates = vec![0.0, -0.0, 1.0, -1.0, 2.0, -3.0, 0.5, -0.5, 4.5e15, -4.5e15];
        let mut extents = vec![1e-300, 5e-324, 1e-9, 0.25, 1.0, 3.5, 1e15];
        for _ in 0..300 {
            let scale = 10f64.powi((next() * 30.0) as i32);
            coordinates.push(next() * scale);
            coordinates.push((next() * 100.0).round() + next() * 1e-12);
            extents.push((next() * scale).abs());
        }
        let (mut lanes, mut cases) = (0, 0);
        for &x in &coordinates {
            for &y in &coordinates[..40] {
                for &w in &extents {
                    let want = [square_wave_mean(x, w), square_wave_mean(y, w * 0.75)];
                    let got = sse2::square_wave_means([x, y], [w, w * 0.75]);
                    if let Some(got) = got {
                        assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{x} {y} {w}");
                        lanes += 1;
                    }
                    cases += 1;
                }
            }
        }
        assert!(lanes * 10 > cases * 8, "{lanes} of {cases}");
        for (x, w) in [
            (0.3, 0.0),
            (0.3, -1.0),
            (f64::NAN, 1.0),
            (5e15, 1.0),
            (0.3, f64::NAN),
        ] {
            assert_eq!(sse2::square_wave_means([x, 0.5], [w, 0.5]), None);
        }
    }

    /// Far from the origin, where the two integrals cancel badly, the mean stays a mean.
    #[test]
    fn far_from_the_origin_the_mean_stays_a_mean() {
        assert!(square_wave_mean(1e17, 1e-3).abs() <= 1.0);
    }
}
