//! Infinite planes, kept outside the BVH and tested from a short list.

use crate::material::MaterialId;
use crate::math::{Ray, gamma, orthonormal_basis};
use crate::shape::SurfaceGeometry;
use crate::texture::TexturePoint;
use glam::DVec3;

/// The plane through `point` with unit `normal`.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane {
    /// A point on the plane, world space; the origin of its texture frame.
    pub point: DVec3,
    /// Unit normal; its side is the plane's front.
    pub normal: DVec3,
    /// Material index.
    pub material: MaterialId,
}

impl Plane {
    /// Parameter t in (0, `t_max`) where the ray crosses the plane. A ray spawned on the plane never re-hits it.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        if from_self {
            return None;
        }
        let denom = ray.dir.dot(self.normal);
        let t = (self.point - ray.origin).dot(self.normal) / denom;
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// Whether every ray from `eye` whose direction is a positive combination of the four `dirs` misses
    /// the plane ([`Plane::intersect`] with no limit): the eye lies on the plane, or every
    /// direction leaves the side the eye is on. The directions' dot products with the normal are
    /// then a positive combination of the given ones, so one sign at all of them, kept clear of 0
    /// by 10⁻⁶ of their lengths (far beyond the rounding of a direction made from the same
    /// camera), is the sign of every direction between them.
    pub(crate) fn missed_by_cone(&self, eye: DVec3, dirs: &[DVec3; 4]) -> bool {
        let side = (self.point - eye).dot(self.normal);
        if side == 0.0 {
            return true;
        }
        // t = side / (d·n) > 0 needs d·n of the sign of `side`.
        dirs.iter().all(|d| {
            let along = d.dot(self.normal) * side.signum();
            along < -1e-6 * d.length()
        })
    }

    /// Surface geometry at parameter `t` of `ray`.
    pub fn surface(&self, ray: &Ray, t: f64) -> SurfaceGeometry {
        let p = ray.at(t);
        // Project onto the plane so the point's error does not grow with t.
        let offset = p - self.point;
        let local3 = offset - self.normal * offset.dot(self.normal);
        let point = self.point + local3;
        let error = gamma(8) * (self.point.abs().max_element() + local3.abs().max_element()) * 2.0;
        SurfaceGeometry {
            point,
            geometric_normal: self.normal,
            shading_normal: self.normal,
            error,
        }
    }

    /// Texture coordinates of a point on the plane: its 2-D frame around `point` (z = 0); height 0.
    pub fn texture_point(&self, point: DVec3) -> TexturePoint {
        in_frame(self.frame(), point - self.point)
    }

    /// How the texture coordinates change along each of the vectors `along` (they are linear in
    /// the point), the plane's frame made once for both.
    pub fn texture_offsets(&self, along: [DVec3; 2]) -> [TexturePoint; 2] {
        let frame = self.frame();
        along.map(|v| in_frame(frame, v))
    }

    /// [`Plane::texture_point`] of `point` and [`Plane::texture_offsets`] along `along`, the
    /// plane's frame made once for the three (a filtered texture asks for all of them).
    pub fn texture_point_and_offsets(
        &self,
        point: DVec3,
        along: [DVec3; 2],
    ) -> (TexturePoint, [TexturePoint; 2]) {
        let frame = self.frame();
        (
            in_frame(frame, point - self.point),
            along.map(|v| in_frame(frame, v)),
        )
    }

    /// The plane's texture frame: two unit vectors spanning it.
    #[inline]
    fn frame(&self) -> (DVec3, DVec3) {
        orthonormal_basis(self.normal)
    }
}

/// The texture coordinates of `offset` (a vector in the plane) in the plane's `frame`.
#[inline]
fn in_frame((u, v): (DVec3, DVec3), offset: DVec3) -> TexturePoint {
    TexturePoint {
        local: DVec3::new(offset.dot(u), offset.dot(v), 0.0),
        height: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_from_either_side_and_not_parallel() {
        let p = Plane {
            point: DVec3::new(0.0, 0.0, 1.0),
            normal: DVec3::Z,
            material: 0,
        };
        assert_eq!(
            p.intersect(&Ray::new(DVec3::ZERO, DVec3::Z), f64::INFINITY, false),
            Some(1.0)
        );
        assert_eq!(
            p.intersect(
                &Ray::new(DVec3::new(0.0, 0.0, 3.0), -DVec3::Z),
                f64::INFINITY,
                false
            ),
            Some(2.0)
        );
        assert_eq!(
            p.intersect(&Ray::new(DVec3::ZERO, DVec3::X), f64::INFINITY, false),
            None
        );
        assert_eq!(
            p.intersect(&Ray::new(DVec3::ZERO, -DVec3::Z), f64::INFINITY, false),
            None
        );
    }

    #[test]
    fn texture_frame_lies_in_the_plane() {
        let p = Plane {
            point: DVec3::new(1.0, 2.0, 3.0),
            normal: DVec3::new(1.0, 1.0, 0.0).normalize(),
            material: 0,
        };
        let r = Ray::new(DVec3::new(5.0, 0.0, 7.0), DVec3::new(-1.0, 0.0, 0.0));
        let t = p.intersect(&r, f64::INFINITY, false).unwrap();
        let s = p.surface(&r, t);
        assert_eq!(p.texture_point(s.point).local.z, 0.0);
        assert!((s.point - p.point).dot(p.normal).abs() < 1e-14);
        // The point and the offsets in one frame are each the ones asked apart, bit for bit.
        let along = [DVec3::new(0.3, -0.2, 0.1), DVec3::new(-1e-3, 4e-3, 2.0)];
        let (centre, offsets) = p.texture_point_and_offsets(s.point, along);
        let bits = |t: TexturePoint| (t.local.to_array().map(f64::to_bits), t.height.to_bits());
        assert_eq!(bits(centre), bits(p.texture_point(s.point)));
        let apart = p.texture_offsets(along);
        assert_eq!(offsets.map(bits), apart.map(bits));
    }
}
