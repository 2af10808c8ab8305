//! The cone of rays from one point whose directions are positive combinations of four corner
//! directions (a tile of a pinhole camera's rays), and whether it misses the world: where the
//! world is too large for an eye buffer, a tile whose cone passes beside every box that covers
//! the world's content, and leaves every plane behind, sees nothing.
//!
//! A box lies outside the cone when one plane through the apex has every corner of the box
//! strictly on its outer side: one of the four side planes (each through two neighbouring corner
//! directions), or the plane across the cone's axis (boxes behind the apex). Every ray of the
//! cone stays on the inner side of all five, so it cannot reach the box. The margin, 10⁻⁶ of the
//! corners' distances from the apex, of the apex's own magnitude and of the world's extent,
//! covers what moves a ray off the cone before it is tested: meshes are hit by the ray rounded
//! to f32 (origin and direction off by 2⁻²⁴ of their magnitudes, so its points by about 6·10⁻⁸
//! of the distance travelled and of the origin's magnitude), spheres and quadrics by the f64
//! ray, and instances' boxes are placed in f64.

use super::Accel;
use super::build::Bounds;
use crate::math::Ray;
use glam::DVec3;

/// The relative margin by which a box's corners must lie outside a plane of the cone: 16 times
/// the f32 rounding of a mesh's ray.
const MARGIN: f64 = 1e-6;

/// The cone of rays from `apex` through positive combinations of four corner directions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CornerCone {
    apex: DVec3,
    /// Inward normals of the four side planes and of the plane across the axis.
    planes: [DVec3; 5],
}

impl CornerCone {
    /// The cone of `corners`, rays from one apex through a tile's corners in the order (left,
    /// top), (right, top), (left, bottom), (right, bottom); `None` when the rays do not share
    /// their origin or do not span a convex cone narrower than a half-space.
    pub(crate) fn new(corners: &[Ray; 4]) -> Option<CornerCone> {
        let apex = corners[0].origin;
        if corners
            .iter()
            .any(|r| r.origin != apex || !r.dir.is_finite())
        {
            return None;
        }
        let d = corners.map(|r| r.dir.normalize_or_zero());
        // Around the quadrilateral: left top, right top, right bottom, left bottom.
        let ring = [d[0], d[1], d[3], d[2]];
        let mut planes = [DVec3::ZERO; 5];
        for i in 0..4 {
            let (a, b) = (ring[i], ring[(i + 1) % 4]);
            let (c, e) = (ring[(i + 2) % 4], ring[(i + 3) % 4]);
            let mut n = a.cross(b);
            if n.dot(c) < 0.0 {
                n = -n;
            }
            // Convex, and not flat: the other two corners strictly inside.
            if !(n.dot(c) > 0.0 && n.dot(e) > 0.0) {
                return None;
            }
            planes[i] = n;
        }
        let axis = d.iter().copied().sum::<DVec3>();
        if d.iter().any(|c| c.dot(axis) <= 0.0) {
            return None;
        }
        planes[4] = axis;
        Some(CornerCone { apex, planes })
    }

    /// Whether no ray of the cone can meet the box `[lo, hi]`: one of the cone's planes has
    /// every corner of the box outside it, by the margin of `scale` (the world's extent) and the
    /// corners' and the apex's magnitudes.
    pub(crate) fn misses_box(&self, (lo, hi): Bounds, scale: f64) -> bool {
        let apex_scale = self.apex.length() + scale;
        let corners: [(DVec3, f64); 8] = std::array::from_fn(|k| {
            let p = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let v = p - self.apex;
            (v, MARGIN * (v.length() + apex_scale))
        });
        self.planes.iter().any(|n| {
            let length = n.length();
            (corners.iter()).all(|&(v, margin)| v.dot(*n) < -margin * length)
        })
    }
}

impl Accel {
    /// Whether every camera ray in the cone of the four `corners` meets no shape, as
    /// [`Accel::closest`] would answer each: the cone misses every box covering the world's
    /// content (the planes are the caller's to ask).
    pub(crate) fn cone_sees_nothing(&self, corners: &[Ray; 4]) -> bool {
        let Some(cone) = CornerCone::new(corners) else {
            return false;
        };
        let extent = f64::from(self.world_extent);
        (self.levels[0].covering.iter()).all(|&b| cone.misses_box(b, extent))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::slab_interval;
    use crate::test_rng::{centred_stream, corner_rays, square_cone};

    /// Boxes a cone is said to miss are missed by rays through random points of the cone (each
    /// a positive combination of the corners), against the slab test; many random boxes near the
    /// cone are said to be missed and many not, and boxes around the apex never are.
    #[test]
    fn boxes_said_to_be_missed_are_missed() {
        let mut next = centred_stream(0xc0e5_4a11_b0c5_0001);
        let (mut missed, mut boxes) = (0, 0);
        for _ in 0..3000 {
            let apex = DVec3::new(next(), next(), next()) * 20.0;
            let size = 0.02 + 0.3 * next().abs();
            let square = square_cone(&mut next, size);
            let corners = corner_rays(apex, &square);
            let cone = CornerCone::new(&corners).unwrap();
            let centre = square(0.0, 0.0);
            let around = (apex - DVec3::splat(0.1), apex + DVec3::splat(0.1));
            assert!(!cone.misses_box(around, 0.0));
            let at = apex + DVec3::new(next(), next(), next()) * 4.0 + centre * 5.0;
            let half = DVec3::new(next().abs(), next().abs(), next().abs()) * 1.5;
            let b = (at - half, at + half);
            boxes += 1;
            if !cone.misses_box(b, 0.0) {
                continue;
            }
            missed += 1;
            for _ in 0..32 {
                let w = [next() + 0.5, next() + 0.5, next() + 0.5, next() + 0.5];
                let dir = (0..4).map(|k| corners[k].dir * w[k]).sum::<DVec3>();
                let (t0, t1) = slab_interval(apex, dir, b.0, b.1);
                assert!(t1 < t0.max(0.0), "a ray of the cone meets {b:?}");
            }
        }
        assert!(
            missed * 5 > boxes && missed * 5 < boxes * 4,
            "{missed} of {boxes}"
        );
    }

    /// Corners that do not span a convex cone, or that do not share their origin, make none.
    #[test]
    fn degenerate_corners_make_no_cone() {
        let o = DVec3::ZERO;
        let flat = [DVec3::X, DVec3::Y, DVec3::X, DVec3::Y].map(|d| Ray::new(o, d));
        assert!(CornerCone::new(&flat).is_none());
        let wide =
            [-DVec3::X, DVec3::Y, DVec3::X, -DVec3::Y].map(|d| Ray::new(o, d + DVec3::Z * 0.1));
        assert!(CornerCone::new(&wide).is_none());
        let mut apart = [
            DVec3::new(-0.1, -0.1, 1.0),
            DVec3::new(0.1, -0.1, 1.0),
            DVec3::new(-0.1, 0.1, 1.0),
            DVec3::new(0.1, 0.1, 1.0),
        ]
        .map(|d| Ray::new(o, d));
        assert!(CornerCone::new(&apart).is_some());
        apart[2].origin = DVec3::X;
        assert!(CornerCone::new(&apart).is_none());
    }
}
