//! A quadric against four rays from one point at once: [`Quadric::intersect_from_local_point`]'s
//! operations lane by lane in AVX2 registers (IEEE, none fused), so the same hits bit for bit.
//!
//! Camera rays of neighbouring pixels mostly look up the same eye-buffer cell, which most often
//! lists one quadric: four of them then share one pass of the test's divisions, square root and
//! products. A lane whose ray nearly grazes the surface, where the one-ray test steps its origin
//! towards tangency before solving, is handed to that test: that branch stays in one place.

use super::Quadric;
use glam::DVec3;

impl Quadric {
    /// [`Quadric::intersect_from_local_point`] for the four world directions `dirs` from one
    /// point (`eye_local`, its image in the local frame), each with its limit `t_max`: the same
    /// hits, bit for bit, on either compiled path.
    pub(crate) fn intersect_four_from_local_point(
        &self,
        eye_local: DVec3,
        dirs: &[DVec3; 4],
        t_max: [f64; 4],
    ) -> [Option<f64>; 4] {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::simd_path() == crate::simd::SimdPath::Avx2 {
            // SAFETY: the CPU has AVX2 (checked by `simd_path`).
            let (mut hits, near_tangent) =
                unsafe { avx2::intersect_four(self, eye_local, dirs, t_max) };
            for (lane, hit) in hits.iter_mut().enumerate() {
                if near_tangent & (1 << lane) != 0 {
                    *hit = self.intersect_from_local_point(eye_local, dirs[lane], t_max[lane]);
                }
            }
            return hits;
        }
        std::array::from_fn(|k| self.intersect_from_local_point(eye_local, dirs[k], t_max[k]))
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use crate::quadric::{Quadric, quadratic::QuadraticPart};
    use glam::{DMat3, DVec3};
    use std::arch::x86_64::*;

    /// Four lanes of f64.
    type F4 = __m256d;

    /// Three coordinates, four lanes each.
    #[derive(Clone, Copy)]
    struct V4 {
        x: F4,
        y: F4,
        z: F4,
    }

    #[target_feature(enable = "avx2")]
    fn splat(x: f64) -> F4 {
        _mm256_set1_pd(x)
    }

    #[target_feature(enable = "avx2")]
    fn add(a: F4, b: F4) -> F4 {
        _mm256_add_pd(a, b)
    }

    #[target_feature(enable = "avx2")]
    fn sub(a: F4, b: F4) -> F4 {
        _mm256_sub_pd(a, b)
    }

    #[target_feature(enable = "avx2")]
    fn mul(a: F4, b: F4) -> F4 {
        _mm256_mul_pd(a, b)
    }

    /// `if take { a } else { b }`, lane by lane.
    #[target_feature(enable = "avx2")]
    fn select(take: F4, a: F4, b: F4) -> F4 {
        _mm256_blendv_pd(b, a, take)
    }

    /// `DVec3::dot`: (x·x' + y·y') + z·z'.
    #[target_feature(enable = "avx2")]
    fn dot(a: V4, b: V4) -> F4 {
        add(add(mul(a.x, b.x), mul(a.y, b.y)), mul(a.z, b.z))
    }

    /// `DVec3::dot` with a vector shared by the lanes.
    #[target_feature(enable = "avx2")]
    fn dot_splat(a: DVec3, b: V4) -> F4 {
        dot(v4_splat(a), b)
    }

    /// The same vector in every lane.
    #[target_feature(enable = "avx2")]
    fn v4_splat(v: DVec3) -> V4 {
        V4 {
            x: splat(v.x),
            y: splat(v.y),
            z: splat(v.z),
        }
    }

    /// `DMat3 * DVec3` as glam computes it: x_axis·v.x + y_axis·v.y, then + z_axis·v.z.
    #[target_feature(enable = "avx2")]
    fn mat_times(m: &DMat3, v: V4) -> V4 {
        let row = |x: f64, y: f64, z: f64| {
            add(
                add(mul(splat(x), v.x), mul(splat(y), v.y)),
                mul(splat(z), v.z),
            )
        };
        V4 {
            x: row(m.x_axis.x, m.y_axis.x, m.z_axis.x),
            y: row(m.x_axis.y, m.y_axis.y, m.z_axis.y),
            z: row(m.x_axis.z, m.y_axis.z, m.z_axis.z),
        }
    }

    /// `QuadraticPart::times`.
    #[target_feature(enable = "avx2")]
    fn a_times(a: QuadraticPart, v: V4) -> V4 {
        match a {
            QuadraticPart::Diagonal(d) => V4 {
                x: mul(splat(d.x), v.x),
                y: mul(splat(d.y), v.y),
                z: mul(splat(d.z), v.z),
            },
            QuadraticPart::General(m) => mat_times(&m, v),
        }
    }

    /// `math::product_error`: x·y − p exactly, by Veltkamp's split and Dekker's two-product.
    #[target_feature(enable = "avx2")]
    fn product_error(x: F4, y: F4, p: F4) -> F4 {
        let split = |v: F4| {
            let c = mul(splat(134_217_729.0), v);
            let hi = sub(c, sub(c, v));
            (hi, sub(v, hi))
        };
        let ((xh, xl), (yh, yl)) = (split(x), split(y));
        add(
            add(add(sub(mul(xh, yh), p), mul(xh, yl)), mul(xl, yh)),
            mul(xl, yl),
        )
    }

    /// The four lanes' hits, and a bit for each lane the one-ray test must decide (its ray
    /// nearly grazes the surface, where that test steps its origin towards tangency). Each step
    /// is the one-ray test's, in its order.
    #[target_feature(enable = "avx2")]
    pub(super) fn intersect_four(
        q: &Quadric,
        o: DVec3,
        dirs: &[DVec3; 4],
        t_max: [f64; 4],
    ) -> ([Option<f64>; 4], u32) {
        let world = V4 {
            x: _mm256_setr_pd(dirs[0].x, dirs[1].x, dirs[2].x, dirs[3].x),
            y: _mm256_setr_pd(dirs[0].y, dirs[1].y, dirs[2].y, dirs[3].y),
            z: _mm256_setr_pd(dirs[0].z, dirs[1].z, dirs[2].z, dirs[3].z),
        };
        let d = mat_times(&q.local.from_world.matrix3, world);
        // `unit_cube_slabs` and `unit_cube_interval`: the slabs' near and far distances
        // (`DVec3::min` and `max` are `minpd` and `maxpd`), folded axis by axis.
        // SAFETY: an unaligned load of four f64s from an array of four.
        let (mut lo, mut hi) = (splat(0.0), unsafe { _mm256_loadu_pd(t_max.as_ptr()) });
        for (dk, ok) in [(d.x, o.x), (d.y, o.y), (d.z, o.z)] {
            let inv = _mm256_div_pd(splat(1.0), dk);
            let t0 = mul(splat(-1.0 - ok), inv);
            let t1 = mul(splat(1.0 - ok), inv);
            let (near, far) = (_mm256_min_pd(t0, t1), _mm256_max_pd(t0, t1));
            lo = select(_mm256_cmp_pd::<_CMP_GT_OQ>(near, lo), near, lo);
            hi = select(_mm256_cmp_pd::<_CMP_LT_OQ>(far, hi), far, hi);
        }
        // Lanes whose box interval is empty or NaN miss.
        let mut live = _mm256_cmp_pd::<_CMP_LE_OQ>(lo, hi);
        let ad = a_times(q.a, d);
        let a = dot(d, ad);
        // The origin moved to the box entry.
        let o = V4 {
            x: add(splat(o.x), mul(d.x, lo)),
            y: add(splat(o.y), mul(d.y, lo)),
            z: add(splat(o.z), mul(d.z, lo)),
        };
        let beta = add(dot(ad, o), dot_splat(q.b, d));
        let gamma = add(
            add(dot(o, a_times(q.a, o)), mul(splat(2.0), dot_splat(q.b, o))),
            splat(q.c),
        );
        let (bb, ag) = (mul(beta, beta), mul(a, gamma));
        let plain = sub(bb, ag);
        let abs = |x: F4| _mm256_andnot_pd(splat(-0.0), x);
        let size = add(bb, abs(ag));
        // Where the one-ray test steps towards tangency (|d|·1024 < bb + |aγ|), it decides.
        let tangent = _mm256_cmp_pd::<_CMP_LT_OQ>(mul(abs(plain), splat(1024.0)), size);
        let handed = _mm256_and_pd(tangent, live);
        live = _mm256_andnot_pd(tangent, live);
        // `math::discriminant`: the plain difference where it lost at most ~3 bits, else
        // compensated by the products' exact rounding errors (a NaN compensates too).
        let exact = _mm256_cmp_pd::<_CMP_GE_OQ>(mul(abs(plain), splat(8.0)), size);
        let compensated = add(
            plain,
            sub(product_error(beta, beta, bb), product_error(a, gamma, ag)),
        );
        let disc = select(exact, plain, compensated);
        // A negative or NaN discriminant: no real root.
        live = _mm256_and_pd(live, _mm256_cmp_pd::<_CMP_GE_OQ>(disc, splat(0.0)));
        let sign = splat(-0.0);
        let root = _mm256_sqrt_pd(disc);
        // `sqrt(disc).copysign(beta)`, then q = −(β + that).
        let signed = _mm256_or_pd(_mm256_andnot_pd(sign, root), _mm256_and_pd(sign, beta));
        let qq = _mm256_xor_pd(add(beta, signed), sign);
        let r0 = add(lo, _mm256_div_pd(qq, a));
        let r1 = add(lo, _mm256_div_pd(gamma, qq));
        let ordered = _mm256_cmp_pd::<_CMP_LE_OQ>(r0, r1);
        let (near, far) = (select(ordered, r0, r1), select(ordered, r1, r0));
        let within = |t: F4| {
            _mm256_and_pd(
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_GE_OQ>(t, lo),
                    _mm256_cmp_pd::<_CMP_GT_OQ>(t, splat(0.0)),
                ),
                _mm256_cmp_pd::<_CMP_LE_OQ>(t, hi),
            )
        };
        let (take_near, take_far) = (within(near), within(far));
        let t = select(take_near, near, far);
        let hit = _mm256_and_pd(live, _mm256_or_pd(take_near, take_far));
        let mut ts = [0.0; 4];
        // SAFETY: an unaligned store of four f64s into an array of four.
        unsafe { _mm256_storeu_pd(ts.as_mut_ptr(), t) };
        let hit_bits = _mm256_movemask_pd(hit);
        let lane = |k: usize| (hit_bits & (1 << k) != 0).then_some(ts[k]);
        let hits = [lane(0), lane(1), lane(2), lane(3)];
        (hits, _mm256_movemask_pd(handed) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Ray, Transform};
    use crate::quadric::{ClipBox, Coefficients, QuadricKind, QuadricSurface};

    /// Every kind, and a general quadric with cross terms (a full matrix A), placed at three
    /// scales far from the origin.
    fn quadrics() -> Vec<(Quadric, f64)> {
        let mut surfaces: Vec<QuadricSurface> = (QuadricKind::ALL.iter())
            .map(|&kind| QuadricSurface::Canonical {
                kind,
                a: 0.8,
                b: 1.1,
                c: 0.7,
            })
            .collect();
        surfaces.push(QuadricSurface::General(Coefficients([
            4.34, 9.77, -4.34, 1.5, -0.7, 0.4, 20.8, 11.7, 6.9, 24.7,
        ])));
        let mut out = Vec::new();
        for surface in surfaces {
            for scale in [1e-3, 1.0, 1e3] {
                let placement = Transform::from_srt(
                    DVec3::splat(scale),
                    DVec3::new(10.0, -20.0, 35.0),
                    DVec3::new(0.3, -0.2, 0.1) * scale,
                )
                .unwrap();
                let q = Quadric::new(surface, ClipBox::cube(2.0), placement, 0).unwrap();
                out.push((q, scale));
            }
        }
        out
    }

    /// The four-ray test gives the one-ray test's hits bit for bit: rays from eyes near and far
    /// aimed into and around the box, grazing the surface from 10⁻³ to 10⁻¹² off it, along the
    /// axes (zero components) and with a zero direction, under limits before and after the hits.
    /// On x86-64 with AVX2 the kernel itself answers, and both its own lanes and the lanes it
    /// hands to the one-ray test occur.
    #[test]
    fn four_rays_hit_as_one_ray_each() {
        let mut next = crate::test_rng::centred_stream(0x4f0e_a11c);
        let (mut hits, mut lanes) = (0, 0);
        #[cfg(target_arch = "x86_64")]
        let (avx2, mut handed) = (is_x86_feature_detected!("avx2"), 0u32);
        for (q, scale) in quadrics() {
            for _ in 0..150 {
                let eye = q
                    .local
                    .to_world
                    .transform_point3(DVec3::new(next(), next(), next()) * 8.0);
                let eye_local = q.to_local_point(eye);
                let mut dirs = [DVec3::ZERO; 4];
                for (k, dir) in dirs.iter_mut().enumerate() {
                    let target = q
                        .local
                        .to_world
                        .transform_point3(DVec3::new(next(), next(), next()) * 2.4);
                    *dir = target - eye;
                    // Grazing rays: aimed at a hit point, pushed off the surface along its normal.
                    if k == 1
                        && let Some(t) = q.intersect(&Ray::new(eye, *dir), f64::INFINITY, false)
                    {
                        let s = q.surface(&Ray::new(eye, *dir), t);
                        let offset = [1e-3, 1e-6, 1e-9, 1e-12][(next().abs() * 4.0) as usize % 4];
                        *dir = s.point + s.geometric_normal * (offset * scale) - eye;
                    }
                }
                // Along an axis, and no direction at all, now and then.
                if next() > 0.4 {
                    dirs[2] = DVec3::new(0.0, 0.0, -dirs[2].z);
                }
                if next() > 0.45 {
                    dirs[3] = DVec3::ZERO;
                }
                let short = 9.0 * next().abs();
                for t_max in [
                    [f64::INFINITY; 4],
                    [short; 4],
                    [1.0, f64::INFINITY, short, 0.5],
                ] {
                    let want: [Option<f64>; 4] = std::array::from_fn(|k| {
                        q.intersect_from_local_point(eye_local, dirs[k], t_max[k])
                    });
                    let got = q.intersect_four_from_local_point(eye_local, &dirs, t_max);
                    assert_eq!(
                        got.map(|t| t.map(f64::to_bits)),
                        want.map(|t| t.map(f64::to_bits)),
                        "eye {eye}, directions {dirs:?}, limits {t_max:?}"
                    );
                    hits += want.iter().flatten().count();
                    lanes += 4;
                    #[cfg(target_arch = "x86_64")]
                    if avx2 {
                        // SAFETY: the CPU has AVX2.
                        let (_, bits) =
                            unsafe { avx2::intersect_four(&q, eye_local, &dirs, t_max) };
                        handed += bits.count_ones();
                    }
                }
            }
        }
        assert!(hits * 4 > lanes, "{hits} hits of {lanes}");
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            assert!(
                handed > 20 && (handed as usize) * 10 < lanes,
                "{handed} of {lanes}"
            );
        }
    }
}
