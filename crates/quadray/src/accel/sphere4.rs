//! Four spheres in f32 structure-of-arrays form: a filter that tells, for one ray and four
//! spheres at once, which spheres the ray's line certainly misses. Only the others reach the
//! exact f64 test ([`Sphere::intersect`]), so the filter changes no result, only its cost.
//!
//! # The bound
//! The ray's line o + t·d passes the centre c at distance l = |f × d| / |d| with f = o − c, and
//! meets the sphere iff l ≤ r. In f32 (unit roundoff u = 2⁻²⁴) the filter evaluates
//! |f̃ × d̃|² > ã·(r̃ + s)²·(1 + 16u) with f̃ = fl(õ − c̃) from the rounded origin and centre, and
//! declares a miss only then. The slack s covers every difference between that and the exact l:
//! - rounding o, c to f32 and subtracting moves f by at most 2u(|o|∞ + |c|∞) per axis, and l is
//!   1-Lipschitz in f (it is the length of f's part orthogonal to d);
//! - rounding d to f32 turns the line by at most √3·u radians, which moves l by at most
//!   2√3·u·|f|;
//! - each cross-product component is a difference of two products, off by γ₂ of their
//!   magnitudes: at most 2γ₂·|f̃|·|d̃| in all, 2γ₂·|f̃| in l;
//! - r is rounded to f32: u·r;
//! - the left side is off by γ₃ and the right by γ₇ at most, which the factor (1 + 16u) covers.
//!
//! With |f|₂ ≤ |f̃|₁ + (those few ulps), s = 2⁻²⁰·(|f̃|₁ + |õ|∞ + |c̃|∞ + r̃) (16u of each term)
//! exceeds their sum with a margin of two, and also covers the f64 test's own rounding (about
//! 10⁻¹⁵ relative), so no ray the f64 test would call a hit is filtered out (pbrt-v3's issue #44
//! was the opposite trap: a conservative test that shrank far quadrics). A ray spawned on the
//! sphere, whose exact test takes the far root without asking whether l ≤ r, starts within about
//! 10⁻¹⁵ of the radius of the surface, far inside the slack, so its line is never called a miss.
//!
//! The bound assumes relative rounding errors, which f32 gives only in its normal range: a miss is
//! decided only where the right side is at least 2⁻¹⁰⁰ and the direction's square is normal
//! (smaller ones, from shapes below 10⁻¹⁹ or instances scaled up by 10¹⁹, keep every lane). A
//! product that overflows f32 (coordinates near 10¹⁹ and beyond) or a NaN is never called a miss
//! either.

use crate::sphere::Sphere;
use glam::{Vec3A, Vec4};

/// 16u = 2⁻²⁰: the filter's slack per unit of magnitude (see the module's bound).
const SLACK: f32 = 1.0 / (1 << 20) as f32;
/// 1 + 16u: covers the rounding of the two sides compared (γ₃ and γ₇).
const SIDES_ROUNDING: f32 = 1.0 + 16.0 * (f32::EPSILON * 0.5);

/// The smallest right side a miss is decided on, 2⁻¹⁰⁰: below it the products may be subnormal,
/// where rounding errors are absolute (up to 2⁻¹⁵⁰) rather than relative, so the bound does not
/// hold; above it those errors are under 2⁻⁵⁰ of the sides, well inside the slack.
const SMALLEST_LIMIT: f32 = 1.0 / (1u128 << 100) as f32;

/// Up to four spheres' centres and radii in f32, by lane; unused lanes are NaN.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct Sphere4 {
    x: [f32; 4],
    y: [f32; 4],
    z: [f32; 4],
    radius: [f32; 4],
}

/// A ray prepared for the filter: its origin and direction in f32.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FilterRay {
    origin: Vec3A,
    dir: Vec3A,
    /// |d̃|².
    length_squared: f32,
    /// |õ|∞.
    origin_magnitude: f32,
}

impl FilterRay {
    /// The filter's ray from the f64 ray `origin + t·dir` rounded to f32.
    #[inline(always)]
    pub(crate) fn new(origin: Vec3A, dir: Vec3A) -> FilterRay {
        // A direction so short that its square leaves f32's normal range (an instance scaled up
        // by 10¹⁹ or more) decides nothing: an infinite right side keeps every lane.
        let length_squared = dir.length_squared();
        FilterRay {
            origin,
            dir,
            length_squared: if length_squared >= f32::MIN_POSITIVE {
                length_squared
            } else {
                f32::INFINITY
            },
            origin_magnitude: origin.abs().max_element(),
        }
    }
}

impl Sphere4 {
    /// A block with every lane unused.
    pub(crate) const EMPTY: Sphere4 = Sphere4 {
        x: [f32::NAN; 4],
        y: [f32::NAN; 4],
        z: [f32::NAN; 4],
        radius: [f32::NAN; 4],
    };

    /// Puts `sphere` in `lane` (its radius rounded up, its centre to nearest).
    pub(crate) fn set(&mut self, lane: usize, sphere: &Sphere) {
        let c = sphere.center.as_vec3();
        self.x[lane] = c.x;
        self.y[lane] = c.y;
        self.z[lane] = c.z;
        let r = sphere.radius as f32;
        self.radius[lane] = if (r as f64) < sphere.radius {
            r.next_up()
        } else {
            r
        };
    }

    /// The mask of lanes whose sphere the ray's line may meet: every lane the exact test could
    /// hit is set, and unused lanes may be set too (their exact test is never run).
    #[inline(always)]
    pub(crate) fn may_hit(&self, ray: &FilterRay) -> u32 {
        let (x, y, z) = (Vec4::from(self.x), Vec4::from(self.y), Vec4::from(self.z));
        let fx = Vec4::splat(ray.origin.x) - x;
        let fy = Vec4::splat(ray.origin.y) - y;
        let fz = Vec4::splat(ray.origin.z) - z;
        let (dx, dy, dz) = (
            Vec4::splat(ray.dir.x),
            Vec4::splat(ray.dir.y),
            Vec4::splat(ray.dir.z),
        );
        let cx = fy * dz - fz * dy;
        let cy = fz * dx - fx * dz;
        let cz = fx * dy - fy * dx;
        let cross = cx * cx + cy * cy + cz * cz;
        let radius = Vec4::from(self.radius);
        let magnitude = fx.abs()
            + fy.abs()
            + fz.abs()
            + Vec4::splat(ray.origin_magnitude)
            + x.abs().max(y.abs()).max(z.abs())
            + radius;
        let reach = radius + magnitude * SLACK;
        let limit = Vec4::splat(ray.length_squared * SIDES_ROUNDING) * reach * reach;
        let miss = cross.cmpgt(limit)
            & cross.cmplt(Vec4::INFINITY)
            & limit.cmpge(Vec4::splat(SMALLEST_LIMIT));
        !miss.bitmask() & 0xf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Ray;
    use glam::DVec3;

    /// A xorshift stream of numbers in [-1, 1).
    fn stream(seed: u64) -> impl FnMut() -> f64 {
        let mut unit = crate::test_rng::unit_stream(seed);
        move || unit() * 2.0 - 1.0
    }

    /// A unit vector orthogonal to `d`.
    fn orthogonal(d: DVec3, turn: f64) -> DVec3 {
        let (e1, e2) = crate::math::orthonormal_basis(d.normalize());
        e1 * turn.cos() + e2 * turn.sin()
    }

    /// The filter never drops a sphere the f64 test hits: rays whose line passes each sphere at
    /// r·(1 + ε) for ε from −1 to ±10⁻¹⁵ (grazing from both sides), spawned rays, far origins,
    /// at scales 1e-6 to 1e6; and it does drop clear misses.
    #[test]
    fn never_drops_a_hit_and_drops_clear_misses() {
        let mut next = stream(0x9e37_79b9_7f4a_7c15);
        let (mut hits, mut dropped_misses, mut misses) = (0, 0, 0);
        for scale in [1e-25, 1e-22, 1e-6, 1e-3, 1.0, 1e3, 1e6] {
            for far in [1.0, 1e3, 1e5] {
                for k in 0..4000 {
                    let sphere = Sphere {
                        center: DVec3::new(next(), next(), next()) * 5.0 * scale * far,
                        radius: (next().abs() + 0.01) * scale,
                        material: 0,
                    };
                    // Directions of every length, down to those of instances scaled up by 10²⁰.
                    let short = (k / 3) % 3;
                    let length = [1.0, 1e-10, 1e-20][short] * (1.0 + 9.0 * next().abs());
                    let dir = DVec3::new(next(), next(), next()) * length;
                    let eps = [
                        -0.5, -1e-3, -1e-7, -1e-12, -1e-15, 0.0, 1e-15, 1e-12, 1e-7, 1e-3, 0.5,
                    ][k % 11];
                    let passing =
                        sphere.center + orthogonal(dir, next() * 3.2) * sphere.radius * (1.0 + eps);
                    let back = (next().abs() * 10.0 + 1.0) * scale * far;
                    let ray = match k % 3 {
                        0 => Ray::new(passing - dir.normalize() * back, dir),
                        // A ray spawned on the sphere.
                        1 => {
                            let on = sphere.center
                                + DVec3::new(next(), next(), next()).normalize() * sphere.radius;
                            Ray::new(on, dir)
                        }
                        _ => Ray::new(passing + dir.normalize() * back, dir),
                    };
                    let mut block = Sphere4::EMPTY;
                    block.set(k % 4, &sphere);
                    let lane = 1 << (k % 4);
                    let filter = FilterRay::new(ray.origin.as_vec3a(), ray.dir.as_vec3a());
                    let kept = block.may_hit(&filter) & lane != 0;
                    let exact = sphere.intersect(&ray, f64::INFINITY, false).is_some()
                        || sphere.intersect(&ray, f64::INFINITY, true).is_some() && k % 3 == 1;
                    if exact {
                        hits += 1;
                        assert!(kept, "dropped a hit: {sphere:?} {ray:?}");
                    } else if eps == 0.5 && far == 1.0 && k % 3 != 1 && short == 0 && scale >= 1e-6
                    {
                        misses += 1;
                        dropped_misses += (!kept) as usize;
                    }
                }
            }
        }
        assert!(hits > 20_000, "{hits}");
        // Lines passing at 1.5 r are clear misses for objects near the origin.
        assert!(
            dropped_misses * 100 >= misses * 99,
            "{dropped_misses} of {misses}"
        );
    }

    /// Coordinates beyond f32's range or a NaN never make a miss.
    #[test]
    fn overflow_and_nan_are_kept() {
        let mut block = Sphere4::EMPTY;
        let huge = Sphere {
            center: DVec3::new(1e25, 0.0, 0.0),
            radius: 1.0,
            material: 0,
        };
        block.set(0, &huge);
        let ray = FilterRay::new(Vec3A::ZERO, Vec3A::X);
        assert_eq!(block.may_hit(&ray) & 1, 1);
        let nan = FilterRay::new(Vec3A::new(f32::NAN, 0.0, 0.0), Vec3A::X);
        assert_eq!(block.may_hit(&nan) & 1, 1);
    }
}
