//! Spheres, intersected in f64 with the geometric discriminant of Ray Tracing Gems ch. 7.

use crate::material::MaterialId;
use crate::math::{Ray, gamma};
use crate::shape::SurfaceGeometry;
use crate::texture::TexturePoint;
use glam::DVec3;

/// A sphere in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    /// Centre, world space.
    pub center: DVec3,
    /// Radius, positive.
    pub radius: f64,
    /// Material index.
    pub material: MaterialId,
}

impl Sphere {
    /// Nearest t in (0, `t_max`) where the ray meets the sphere.
    ///
    /// `from_self` marks a ray spawned on this sphere: its origin lies on the surface, so γ = 0
    /// and the roots are exactly 0 and −2β/a (the "known root" trick), which rules out self-hits
    /// while keeping a genuine second hit on the far side.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        let f = ray.origin - self.center;
        let a = ray.dir.length_squared();
        let beta = f.dot(ray.dir);
        if from_self {
            let t = -2.0 * beta / a;
            return (t > 0.0 && t < t_max).then_some(t);
        }
        // Δ = β² − aγ = a·(r² − l²) with l the distance from the centre to the ray's line: no cancellation.
        let l = (f - ray.dir * (beta / a)).length();
        let r = self.radius;
        let disc = a * (r - l) * (r + l);
        if disc < 0.0 {
            return None;
        }
        let gamma_ = f.length_squared() - r * r;
        let q = -(beta + disc.sqrt().copysign(beta));
        let (t0, t1) = (q / a, gamma_ / q);
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if near > 0.0 && near < t_max {
            Some(near)
        } else if far > 0.0 && far < t_max {
            Some(far)
        } else {
            None
        }
    }

    /// Surface geometry at parameter `t` of `ray`.
    pub fn surface(&self, ray: &Ray, t: f64) -> SurfaceGeometry {
        let local = ray.at(t) - self.center;
        // Reproject onto the sphere: the point's error no longer depends on t's error.
        let local = local * (self.radius / local.length());
        let point = self.center + local;
        let normal = local / self.radius;
        let error = gamma(6) * (self.center.abs().max_element() + self.radius) * 2.0;
        SurfaceGeometry {
            point,
            geometric_normal: normal,
            shading_normal: normal,
            error,
        }
    }

    /// Texture coordinates of a surface point: offset from the centre, height over the sphere's z extent.
    pub fn texture_point(&self, point: DVec3) -> TexturePoint {
        let local = point - self.center;
        TexturePoint {
            local,
            height: ((local.z / self.radius) * 0.5 + 0.5) as f32,
        }
    }

    /// Curvature, the same in every direction: one over the radius.
    pub fn curvature(&self) -> f64 {
        1.0 / self.radius
    }

    /// How the texture coordinates change along the vector `v` (they are affine in the point).
    pub fn texture_offset(&self, v: DVec3) -> TexturePoint {
        TexturePoint {
            local: v,
            height: (v.z / self.radius * 0.5) as f32,
        }
    }

    /// Axis-aligned bounds, world space.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (
            self.center - DVec3::splat(self.radius),
            self.center + DVec3::splat(self.radius),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Sphere {
        Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            material: 0,
        }
    }

    #[test]
    fn hits_front_then_back_from_inside() {
        let s = unit();
        let r = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z);
        assert_eq!(s.intersect(&r, f64::INFINITY, false), Some(4.0));
        let inside = Ray::new(DVec3::ZERO, DVec3::Z);
        assert_eq!(s.intersect(&inside, f64::INFINITY, false), Some(1.0));
        assert_eq!(s.intersect(&r, 3.9, false), None);
    }

    #[test]
    fn far_sphere_has_no_rim_holes() {
        // Unit sphere 1e4 away: rays aimed at 0.999 of the radius all hit, at 1.001 all miss.
        let s = Sphere {
            center: DVec3::new(0.0, 1e4, 0.0),
            radius: 1.0,
            material: 0,
        };
        for k in 0..1000 {
            let ang = k as f64 * 0.00628;
            let aim = |f: f64| DVec3::new(ang.cos() * f, 1e4, ang.sin() * f);
            assert!(
                s.intersect(
                    &Ray::new(DVec3::ZERO, aim(0.999).normalize()),
                    f64::INFINITY,
                    false
                )
                .is_some()
            );
            assert!(
                s.intersect(
                    &Ray::new(DVec3::ZERO, aim(1.001).normalize()),
                    f64::INFINITY,
                    false
                )
                .is_none()
            );
        }
    }

    #[test]
    fn spawned_rays_do_not_self_hit_but_cross_to_the_far_side() {
        let s = Sphere {
            center: DVec3::new(3.0, -2.0, 1.0),
            radius: 0.7,
            material: 0,
        };
        let p = s.center + DVec3::new(0.3, 0.5, -0.2).normalize() * 0.7;
        let n = (p - s.center).normalize();
        let out = Ray::new(p, (n + DVec3::new(0.4, -0.1, 0.2)).normalize());
        assert_eq!(s.intersect(&out, f64::INFINITY, true), None);
        let inward = Ray::new(p, -n);
        let t = s.intersect(&inward, f64::INFINITY, true).unwrap();
        assert!((t - 1.4).abs() < 1e-12);
    }

    #[test]
    fn surface_normal_is_unit_and_radial() {
        let s = unit();
        let r = Ray::new(DVec3::new(0.2, 0.1, -5.0), DVec3::Z);
        let t = s.intersect(&r, f64::INFINITY, false).unwrap();
        let g = s.surface(&r, t);
        assert!((g.geometric_normal.length() - 1.0).abs() < 1e-15);
        assert!((g.point.length() - 1.0).abs() < 1e-15);
    }
}
