//! Rays, affine transforms and the numerically stable quadratic solver shared by all shapes.

use glam::{DAffine3, DMat3, DVec3, Vec3A};

/// Largest coordinate magnitude a scene may reach, shapes as placed and camera alike (f32's range
/// is 3.4·10³⁸; the margin covers box padding and ray spans).
pub const MAX_COORDINATE: f64 = 1e30;

/// Unit roundoff of f64 (half an ulp of 1.0): every correctly rounded operation has relative error at most this.
pub const F64_UNIT_ROUNDOFF: f64 = f64::EPSILON * 0.5;

/// Whether every component of `a` and `b` is finite, in one comparison: x − x is 0 for a
/// finite x and NaN otherwise (the ray queries check their f32 rays so, where three tests and
/// branches a vector cost them about 2% of their instructions).
#[inline(always)]
#[allow(clippy::eq_op)] // x − x is the test itself.
pub(crate) fn all_finite(a: Vec3A, b: Vec3A) -> bool {
    ((a - a) + (b - b)).cmpeq(Vec3A::ZERO).all()
}

/// Higham's gamma(n) = n·u / (1 − n·u): the relative error bound of n chained roundings.
#[inline]
pub fn gamma(n: u32) -> f64 {
    let nu = n as f64 * F64_UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// A ray `origin + t·dir`; `dir` need not be unit length (t is then in units of `dir`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start of the ray, world space.
    pub origin: DVec3,
    /// Direction of travel; its length sets the unit of the ray parameter t.
    pub dir: DVec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    #[inline]
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        Ray { origin, dir }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// The real roots of `a·t² + 2β·t + γ = 0`, ascending; non-finite roots are dropped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roots {
    /// How many of `t` are valid (0, 1 or 2).
    pub count: usize,
    /// The roots, ascending, `t[..count]` valid.
    pub t: [f64; 2],
}

impl Roots {
    /// No real root.
    pub const NONE: Roots = Roots {
        count: 0,
        t: [f64::NAN; 2],
    };

    /// The valid roots as a slice.
    #[inline]
    pub fn as_slice(&self) -> &[f64] {
        &self.t[..self.count]
    }
}

/// Discriminant β² − aγ, compensated with the products' exact rounding errors when the two nearly
/// cancel (Kahan, "On the cost of floating-point computation without extra-precise arithmetic", 2004).
#[inline]
pub fn discriminant(a: f64, half_b: f64, c: f64) -> f64 {
    let bb = half_b * half_b;
    let ac = a * c;
    let d = bb - ac;
    // Only when the subtraction lost more than ~3 bits is the compensation worth its cost.
    if d.abs() * 8.0 >= bb + ac.abs() {
        return d;
    }
    d + (product_error(half_b, half_b, bb) - product_error(a, c, ac))
}

/// The exact rounding error x·y − p of the product p = fl(x·y), by Dekker's two-product with
/// Veltkamp splitting. Exact without an FMA instruction (on baseline x86-64 `f64::mul_add` is a
/// library call, which made the compensated discriminant the costliest step of the intersector);
/// valid while |x|, |y| < 2^996, far beyond any normalised quadric's values.
#[inline]
pub fn product_error(x: f64, y: f64, p: f64) -> f64 {
    let (xh, xl) = split(x);
    let (yh, yl) = split(y);
    ((xh * yh - p) + xh * yl + xl * yh) + xl * yl
}

/// Veltkamp's split of x into a high part of 26 bits and the exact remainder.
#[inline]
fn split(x: f64) -> (f64, f64) {
    let c = 134_217_729.0 * x; // 2^27 + 1
    let hi = c - (c - x);
    (hi, x - hi)
}

/// Solves `a·t² + 2β·t + γ = 0` without cancellation: q = −(β + sign(β)·√Δ), roots q/a and γ/q.
///
/// When `a` vanishes (a ray along a paraboloid axis or a cone generator) q/a becomes infinite and is
/// dropped, while γ/q degrades gracefully into the linear root −γ/(2β); no threshold on `a` is needed.
#[inline]
pub fn solve_quadratic(a: f64, half_b: f64, c: f64) -> Roots {
    let disc = discriminant(a, half_b, c);
    if disc < 0.0 || disc.is_nan() {
        return Roots::NONE;
    }
    let q = -(half_b + disc.sqrt().copysign(half_b));
    let r0 = q / a;
    let r1 = c / q;
    let (f0, f1) = (r0.is_finite(), r1.is_finite());
    match (f0, f1) {
        (true, true) => Roots {
            count: 2,
            t: if r0 <= r1 { [r0, r1] } else { [r1, r0] },
        },
        (true, false) => Roots {
            count: 1,
            t: [r0, f64::NAN],
        },
        (false, true) => Roots {
            count: 1,
            t: [r1, f64::NAN],
        },
        (false, false) => Roots::NONE,
    }
}

/// An affine placement of an object: object-to-world, its inverse, and the normal matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Object space to world space.
    pub to_world: DAffine3,
    /// World space to object space.
    pub from_world: DAffine3,
    /// Inverse transpose of the linear part: maps object-space normals (gradients) to world space.
    pub normal_to_world: DMat3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// The identity placement.
    pub const IDENTITY: Transform = Transform {
        to_world: DAffine3::IDENTITY,
        from_world: DAffine3::IDENTITY,
        normal_to_world: DMat3::IDENTITY,
    };

    /// Wraps an object-to-world affine map; `None` when it is singular or not finite.
    pub fn new(to_world: DAffine3) -> Option<Transform> {
        if !Transform::is_invertible(&to_world) {
            return None;
        }
        let from_world = to_world.inverse();
        Some(Transform {
            to_world,
            from_world,
            normal_to_world: from_world.matrix3.transpose(),
        })
    }

    /// Whether [`Transform::new`] takes `to_world`: finite, and not singular relative to its
    /// columns' lengths. Without building the inverse.
    pub fn is_invertible(to_world: &DAffine3) -> bool {
        let det = to_world.matrix3.determinant();
        if !det.is_finite() || det == 0.0 || !to_world.translation.is_finite() {
            return false;
        }
        // Relative singularity: the determinant against the product of column lengths.
        let cols = to_world.matrix3.x_axis.length()
            * to_world.matrix3.y_axis.length()
            * to_world.matrix3.z_axis.length();
        det.abs() > cols * 1e-12
    }

    /// Scale, then rotate (Euler angles in degrees about x, then y, then z), then translate.
    pub fn from_srt(scale: DVec3, rotate_deg: DVec3, translate: DVec3) -> Option<Transform> {
        let r = glam::DQuat::from_euler(
            glam::EulerRot::ZYX,
            rotate_deg.z.to_radians(),
            rotate_deg.y.to_radians(),
            rotate_deg.x.to_radians(),
        );
        Transform::new(DAffine3::from_scale_rotation_translation(
            scale, r, translate,
        ))
    }

    /// Largest factor by which the map can stretch a length (Frobenius bound on the operator norm).
    pub fn max_stretch(&self) -> f64 {
        let m = self.to_world.matrix3;
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
    }
}

/// ‖M‖∞, the largest absolute row sum of `m`: the most a map x ↦ Mx stretches the largest
/// coordinate magnitude, ‖Mx‖∞ ≤ ‖M‖∞·‖x‖∞.
pub fn max_row_sum(m: DMat3) -> f64 {
    let rows = m.transpose().abs();
    [rows.x_axis, rows.y_axis, rows.z_axis]
        .iter()
        .map(|r| r.element_sum())
        .fold(0.0, f64::max)
}

/// Slab test of a ray against the closed box `[min, max]`: the parameter interval inside it.
///
/// Division by a zero direction component gives ±∞, which the min/max below handle, except for
/// 0·∞ = NaN when the origin lies exactly on a face; `f64::max`/`min` ignore that NaN, which keeps
/// the face as inside (the box is closed).
#[inline]
pub fn slab_interval(origin: DVec3, dir: DVec3, min: DVec3, max: DVec3) -> (f64, f64) {
    let inv = dir.recip();
    let t0 = (min - origin) * inv;
    let t1 = (max - origin) * inv;
    let near = t0.min(t1);
    let far = t0.max(t1);
    (near.x.max(near.y).max(near.z), far.x.min(far.y).min(far.z))
}

/// Moves a spawned ray's origin off the surface by `offset` along the normal, to the side `dir` leaves on.
///
/// `offset` must bound the distance between the computed point and the true surface (pbrt's
/// OffsetRayOrigin idea, with the bound measured per hit instead of a fixed epsilon).
#[inline]
pub fn offset_origin(p: DVec3, geometric_normal: DVec3, offset: f64, dir: DVec3) -> DVec3 {
    let side = if geometric_normal.dot(dir) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    p + geometric_normal * (offset * side)
}

/// `x.floor()`, bit for bit for every input, without a library call: baseline x86-64 has no
/// rounding instruction (SSE4.1's `roundsd`), so `f64::floor` calls libm, which cost 2% of a
/// checkered frame.
#[inline(always)]
pub fn floor(x: f64) -> f64 {
    // From 2⁵² on (and for NaN and infinities) every f64 is its own floor.
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        return x;
    }
    // Truncation toward zero is exact here; a negative non-integer steps down one.
    let t = x as i64 as f64;
    if t == x {
        x
    } else if t > x {
        t - 1.0
    } else {
        t
    }
}

/// Builds an orthonormal basis whose third axis is `n` (Duff et al., "Building an Orthonormal Basis, Revisited", 2017).
pub fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `all_finite` agrees with testing each component, at the edges of f32's range.
    #[test]
    fn all_finite_tests_every_component() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -3.5e-45,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for (k, &x) in values.iter().enumerate() {
            for lane in 0..6 {
                let mut c = [0.5f32; 6];
                c[lane] = x;
                c[(lane + k) % 6] = values[(k * 7 + lane) % values.len()];
                let (a, b) = (Vec3A::new(c[0], c[1], c[2]), Vec3A::new(c[3], c[4], c[5]));
                let expected = c.iter().all(|v| v.is_finite());
                assert_eq!(all_finite(a, b), expected, "{c:?}");
            }
        }
    }

    #[test]
    fn floor_matches_the_library_bit_for_bit() {
        let mut values = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.5,
            2.5,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            -4_503_599_627_370_497.0,
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1.0 - f64::EPSILON / 2.0,
            -(1.0 - f64::EPSILON / 2.0),
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..200_000 {
            let bits = crate::test_rng::xorshift(&mut state);
            values.push(f64::from_bits(bits));
            values.push((bits >> 11) as f64 / (1u64 << 40) as f64 - 4096.0);
        }
        for x in values {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x}");
        }
    }

    #[test]
    fn quadratic_matches_known_roots() {
        // (t - 1)(t - 3) = t² - 4t + 3 -> a = 1, β = -2, γ = 3
        let r = solve_quadratic(1.0, -2.0, 3.0);
        assert_eq!(r.as_slice(), &[1.0, 3.0]);
        // Negative leading coefficient keeps ascending order.
        let r = solve_quadratic(-1.0, 2.0, -3.0);
        assert_eq!(r.as_slice(), &[1.0, 3.0]);
        assert_eq!(solve_quadratic(1.0, 0.0, 1.0).count, 0);
    }

    #[test]
    fn quadratic_degrades_to_linear_when_a_vanishes() {
        // 2·(-1)·t + 4 = 0 -> t = 2
        let r = solve_quadratic(0.0, -1.0, 4.0);
        assert_eq!(r.as_slice(), &[2.0]);
        // a tiny but nonzero: the small root stays accurate.
        let r = solve_quadratic(1e-300, -1.0, 4.0);
        assert!(r.as_slice().contains(&2.0));
        assert_eq!(solve_quadratic(0.0, 0.0, 1.0).count, 0);
    }

    #[test]
    fn quadratic_small_root_has_no_cancellation() {
        // t² - 2e8 t + 1 = 0: small root 5e-9 exactly to ~1 ulp; the naive formula gives 0.
        let r = solve_quadratic(1.0, -1e8, 1.0);
        let small = r.t[0];
        assert!((small - 5e-9).abs() <= 5e-9 * 4.0 * f64::EPSILON, "{small}");
    }

    #[test]
    fn compensated_discriminant_recovers_cancelled_bits() {
        // β = 1 + 2^-30, a = γ = 1 + 2^-29: β² − aγ = −2^-29 − 3·2^-60 exactly; the 2^-60 terms are below
        // the ulp of β² and aγ, so the uncompensated difference loses them.
        let b = 1.0 + 2f64.powi(-30);
        let a = 1.0 + 2f64.powi(-29);
        let exact = -(2f64.powi(-29)) - 3.0 * 2f64.powi(-60);
        assert_ne!(b * b - a * a, exact);
        let d = discriminant(a, b, a);
        assert!((d - exact).abs() <= exact.abs() * 1e-15, "{d} vs {exact}");
    }

    #[test]
    fn product_error_is_exact() {
        for (x, y) in [
            (1.0 + 2f64.powi(-30), 1.0 + 2f64.powi(-29)),
            (0.1, 0.3),
            (-3.7e10, 2.9e-7),
            (1e150, 1e140),
        ] {
            let p = x * y;
            assert_eq!(product_error(x, y, p), x.mul_add(y, -p), "{x} * {y}");
        }
    }

    #[test]
    fn slab_interval_of_unit_box() {
        let (t0, t1) = slab_interval(
            DVec3::new(-3.0, 0.0, 0.0),
            DVec3::X,
            -DVec3::ONE,
            DVec3::ONE,
        );
        assert_eq!((t0, t1), (2.0, 4.0));
        // Parallel ray on a face: the closed box keeps it.
        let (t0, t1) = slab_interval(
            DVec3::new(-3.0, 1.0, 0.0),
            DVec3::X,
            -DVec3::ONE,
            DVec3::ONE,
        );
        assert!(t0 <= t1);
    }

    #[test]
    fn transform_rejects_singular_maps() {
        assert!(Transform::from_srt(DVec3::new(1.0, 0.0, 1.0), DVec3::ZERO, DVec3::ZERO).is_none());
        let t = Transform::from_srt(
            DVec3::new(2.0, 3.0, 4.0),
            DVec3::new(10.0, 20.0, 30.0),
            DVec3::ONE,
        )
        .unwrap();
        let p = DVec3::new(0.3, -0.2, 0.9);
        let back = t
            .from_world
            .transform_point3(t.to_world.transform_point3(p));
        assert!((back - p).length() < 1e-14);
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [DVec3::Z, -DVec3::Z, DVec3::new(0.3, -0.4, 0.5).normalize()] {
            let (u, v) = orthonormal_basis(n);
            assert!(
                u.dot(v).abs() < 1e-15
                    && u.dot(n).abs() < 1e-15
                    && (u.length() - 1.0).abs() < 1e-15
            );
            assert!((u.cross(v) - n).length() < 1e-15);
        }
    }
}
