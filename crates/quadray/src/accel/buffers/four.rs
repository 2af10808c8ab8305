//! The cells of four rays from one point at once: the lookup of [`super::EyeBuffer`]'s camera
//! rays ([`Cube::cell`] of each direction, for rays that start at the point bit for bit and are
//! finite once rounded to f32) lane by lane in AVX2 registers (IEEE, none fused), so the same
//! cells. One ray at a time it cost about 106 instructions, 12% of the quadric grid's frame.

use super::{Cube, finite_in_f32};
use crate::math::Ray;
use glam::DVec3;

/// What [`Cube::cells_from`] gives where [`Cube::cell_from`] finds no cell: beyond every cube's
/// cells, so a lookup with `get` finds nothing.
pub(super) const NO_CELL: u32 = u32::MAX;

impl Cube {
    /// [`Cube::cell`] of each ray's direction, [`NO_CELL`] for a ray that does not start at
    /// `point` bit for bit or is not finite in f32 ([`finite_in_f32`]), on either compiled path.
    /// The cube has at most 2³¹ cells.
    #[inline]
    pub(super) fn cells_from(self, point: DVec3, rays: &[Ray; 4]) -> [u32; 4] {
        debug_assert!(self.len() < 1 << 31);
        #[cfg(target_arch = "x86_64")]
        if crate::simd::simd_path() == crate::simd::SimdPath::Avx2 {
            // SAFETY: the CPU has AVX2 (checked by `simd_path`).
            return unsafe { avx2::cells_from(self, point, rays) };
        }
        rays.each_ref().map(|ray| {
            self.cell_from(point, ray)
                .map_or(NO_CELL, |cell| cell as u32)
        })
    }

    /// One ray's [`Cube::cells_from`].
    #[inline(always)]
    pub(super) fn cell_from(self, point: DVec3, ray: &Ray) -> Option<usize> {
        let bits = |p: DVec3| p.to_array().map(f64::to_bits);
        if bits(ray.origin) != bits(point) || !finite_in_f32(ray) {
            return None;
        }
        self.cell(ray.dir)
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::Cube;
    use crate::math::Ray;
    use glam::DVec3;
    use std::arch::x86_64::*;

    /// |v| lane by lane: the sign bit cleared.
    #[target_feature(enable = "avx2")]
    fn abs(v: __m256d) -> __m256d {
        _mm256_andnot_pd(_mm256_set1_pd(-0.0), v)
    }

    /// Lanes where v is finite (not infinite, not NaN).
    #[target_feature(enable = "avx2")]
    fn finite(v: __m256d) -> __m256d {
        _mm256_cmp_pd::<_CMP_LT_OQ>(abs(v), _mm256_set1_pd(f64::INFINITY))
    }

    /// `if take { a } else { b }`, lane by lane.
    #[target_feature(enable = "avx2")]
    fn select(take: __m256d, a: __m256d, b: __m256d) -> __m256d {
        _mm256_blendv_pd(b, a, take)
    }

    /// Lanes where v rounds to a finite f32: |v| below 2¹²⁸ − 2¹⁰³, which is f32::MAX plus half
    /// its ulp, the first magnitude that rounds to infinity (the tie goes to even); NaN fails.
    #[target_feature(enable = "avx2")]
    fn finite_f32(v: __m256d) -> __m256d {
        const LIMIT: f64 = 340_282_356_779_733_661_637_539_395_458_142_568_448.0; // 2¹²⁸ − 2¹⁰³
        _mm256_cmp_pd::<_CMP_LT_OQ>(abs(v), _mm256_set1_pd(LIMIT))
    }

    /// Lanes whose `a` and `b` are the same 64 bits.
    #[target_feature(enable = "avx2")]
    fn same_bits(a: __m256d, b: __m256d) -> __m256d {
        _mm256_castsi256_pd(_mm256_cmpeq_epi64(
            _mm256_castpd_si256(a),
            _mm256_castpd_si256(b),
        ))
    }

    /// The cell coordinate along the face of a direction's component `c`: c · scale + n/2 (with
    /// scale n/2 over the largest component's magnitude) clamped to [0, `top`] and truncated.
    /// Where the quotient is finite, MAXPD and MINPD clamp as `f64::max` and `min` do, and
    /// truncation gives the integer conversion's value.
    #[target_feature(enable = "avx2")]
    fn cell_along(c: __m256d, scale: __m256d, half_n: __m256d, top: __m256d) -> __m256d {
        let moved = _mm256_add_pd(_mm256_mul_pd(c, scale), half_n);
        let clamped = _mm256_min_pd(_mm256_max_pd(moved, _mm256_setzero_pd()), top);
        _mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(clamped)
    }

    /// [`Cube::cells_from`]: each ray's origin compared with `point` bit for bit and its six
    /// coordinates checked against f32's range, then [`Cube::cell`] of its direction: the axis of
    /// the largest magnitude (x on ties with y or z, then y on a tie with z), the two other
    /// components times n/2 over that magnitude, moved to [0, n] and clamped to [0, n − 1],
    /// truncated; [`super::NO_CELL`] also where that scale is not finite.
    #[target_feature(enable = "avx2")]
    pub(super) fn cells_from(cube: Cube, point: DVec3, rays: &[Ray; 4]) -> [u32; 4] {
        // No closures in this function: they would not inherit AVX2, and each became a call.
        let [r0, r1, r2, r3] = rays;
        let (o0, o1, o2, o3) = (r0.origin, r1.origin, r2.origin, r3.origin);
        let (d0, d1, d2, d3) = (r0.dir, r1.dir, r2.dir, r3.dir);
        let (ox, oy, oz) = (
            _mm256_set_pd(o3.x, o2.x, o1.x, o0.x),
            _mm256_set_pd(o3.y, o2.y, o1.y, o0.y),
            _mm256_set_pd(o3.z, o2.z, o1.z, o0.z),
        );
        let (x, y, z) = (
            _mm256_set_pd(d3.x, d2.x, d1.x, d0.x),
            _mm256_set_pd(d3.y, d2.y, d1.y, d0.y),
            _mm256_set_pd(d3.z, d2.z, d1.z, d0.z),
        );
        let at_point = _mm256_and_pd(
            same_bits(ox, _mm256_set1_pd(point.x)),
            _mm256_and_pd(
                same_bits(oy, _mm256_set1_pd(point.y)),
                same_bits(oz, _mm256_set1_pd(point.z)),
            ),
        );
        let in_f32 = _mm256_and_pd(
            _mm256_and_pd(
                finite_f32(ox),
                _mm256_and_pd(finite_f32(oy), finite_f32(oz)),
            ),
            _mm256_and_pd(finite_f32(x), _mm256_and_pd(finite_f32(y), finite_f32(z))),
        );
        let (ax, ay, az) = (abs(x), abs(y), abs(z));
        let x_wins = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_GE_OQ>(ax, ay),
            _mm256_cmp_pd::<_CMP_GE_OQ>(ax, az),
        );
        let y_wins = _mm256_andnot_pd(x_wins, _mm256_cmp_pd::<_CMP_GE_OQ>(ay, az));
        let u = select(x_wins, y, x);
        let v = select(_mm256_or_pd(x_wins, y_wins), z, y);
        let largest = select(x_wins, x, select(y_wins, y, z));
        let n = cube.n;
        let half_n = _mm256_set1_pd(0.5 * n as f64);
        let scale = _mm256_div_pd(half_n, abs(largest));
        // Finite in f32 implies finite: the direction needs no check of its own.
        let valid = _mm256_and_pd(_mm256_and_pd(at_point, in_f32), finite(scale));
        let top = _mm256_set1_pd((n - 1) as f64);
        let (cu, cv) = (
            cell_along(u, scale, half_n, top),
            cell_along(v, scale, half_n, top),
        );
        // (face · n + cu) · n + cv, face = 2 · axis + (largest < 0), each exact in f64 (below 2³¹).
        let (zero, one) = (_mm256_setzero_pd(), _mm256_set1_pd(1.0));
        let axis = select(x_wins, zero, select(y_wins, one, _mm256_set1_pd(2.0)));
        let negative = _mm256_and_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(largest, zero), one);
        let face = _mm256_add_pd(_mm256_add_pd(axis, axis), negative);
        let n = _mm256_set1_pd(n as f64);
        let cell = _mm256_add_pd(
            _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(face, n), cu), n),
            cv,
        );
        // −1, which converts to NO_CELL's bits, where invalid.
        let cell = select(valid, cell, _mm256_set1_pd(-1.0));
        let mut cells = [0u32; 4];
        // SAFETY: `cells` holds four 32-bit lanes, the 16 bytes stored.
        unsafe { _mm_storeu_si128(cells.as_mut_ptr().cast(), _mm256_cvttpd_epi32(cell)) };
        cells
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four lanes give [`Cube::cell_from`]'s answer for every lane: random directions of every
    /// magnitude, ties between components of either sign, zeros of both signs, subnormal,
    /// infinite and NaN components, coordinates on either side of f32's rounding to infinity,
    /// and origins at the point, a zero's sign off it, or elsewhere.
    #[test]
    fn four_lanes_find_the_cells_one_finds() {
        let mut unit = crate::test_rng::unit_stream(0x51ed_270b_0d3a_3c1f);
        let mut next = || unit() * 2.0 - 1.0;
        // f32's rounding to infinity: f32::MAX plus half an ulp (2¹⁰³) and above.
        let f32_edge = f32::MAX as f64 + 2f64.powi(103);
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            f64::MIN_POSITIVE / 4.0,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1e300,
            -1e-300,
            63.0 / 64.0,
            -1.0 / 64.0,
            f32_edge,
            -f32_edge.next_down(),
        ];
        let mut pick = |k: usize| match k % 4 {
            0 => special[(next().abs() * special.len() as f64) as usize % special.len()],
            1 => next() * 10f64.powi((next() * 20.0) as i32),
            _ => next(),
        };
        let point = DVec3::new(0.0, 1.5, -2.0);
        let mut found = 0;
        for n in [1, 7, 32, 128] {
            let cube = Cube { n };
            for k in 0..20_000 {
                let rays: [Ray; 4] = std::array::from_fn(|lane| {
                    let d = DVec3::new(pick(k + lane), pick(k + 2 * lane + 1), pick(k + 3));
                    // Every fifth lane a tie of magnitudes between two components.
                    let dir = match (k + lane) % 5 {
                        0 => DVec3::new(d.x, -d.x, d.z),
                        1 => DVec3::new(d.x, d.y, d.y),
                        _ => d,
                    };
                    let origin = match (k + 3 * lane) % 7 {
                        0 => DVec3::new(-0.0, 1.5, -2.0),
                        1 => DVec3::new(pick(k), 1.5, -2.0),
                        _ => point,
                    };
                    Ray::new(origin, dir)
                });
                let four = cube.cells_from(point, &rays);
                for lane in 0..4 {
                    let one = cube.cell_from(point, &rays[lane]);
                    let expected = one.map_or(NO_CELL, |cell| cell as u32);
                    assert_eq!(four[lane], expected, "{:?}, n {n}", rays[lane]);
                    found += usize::from(one.is_some());
                }
            }
        }
        assert!(found > 100_000, "{found}");
        // The edge itself: the first coordinate f32 rounds to infinity, and the last it does not.
        let at = |x: f64| Ray::new(point, DVec3::new(x, 1.0, 0.5));
        assert!(!finite_in_f32(&at(f32_edge)) && finite_in_f32(&at(f32_edge.next_down())));
    }
}
