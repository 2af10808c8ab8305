//! Ray cones: how much of a surface one sample stands for, so procedural textures can be filtered
//! over it instead of point sampled.
//!
//! A camera sample stands for a patch of the image about 1/√n pixels wide when its pixel takes n
//! samples (pbrt-v4's scaled ray differentials). Its ray carries that patch as a cone (Amanatides
//! 1984; Akenine-Möller et al. 2019, "Texture Level of Detail Strategies for Real-Time Ray
//! Tracing"): a width where the ray starts and a spread angle. A mirror keeps the spread and adds
//! twice the angle by which its normal turns across the footprint, so a convex mirror widens the
//! cone as it widens the reflected view. Where a cone meets a surface its width, projected along
//! the ray onto the tangent plane, is the footprint a texture averages over.
//!
//! The cone is isotropic: one width for both image axes, the larger principal curvature for a
//! surface that bends differently in two directions. That errs towards a little more blur on
//! saddles and cylinders, never towards aliasing.

use crate::math::orthonormal_basis;
use glam::DVec3;

/// The smallest footprint scale: past 64 samples a pixel, samples stay one eighth of a pixel wide
/// (pbrt-v4's clamp), so the converged image is the pixel integral to within that blur.
const MIN_SCALE: f64 = 0.125;

/// The grazing limit: where the ray meets the tangent plane at a cosine below this, the footprint
/// stretches no further (it already spans hundreds of cone widths).
const MIN_COSINE: f64 = 1e-3;

/// A ray's cone: its width where the ray starts and how fast it widens with distance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCone {
    /// Width at the ray's origin, world units.
    pub width: f64,
    /// Widening per unit distance along the ray (the cone's full angle, small-angle radians).
    pub spread: f64,
}

impl RayCone {
    /// No cone: the ray samples points, and textures are not filtered.
    pub const POINT: RayCone = RayCone {
        width: 0.0,
        spread: 0.0,
    };

    /// Whether the cone is [`RayCone::POINT`] (a scene without filtered textures traces these).
    #[inline]
    pub fn is_point(&self) -> bool {
        self.width == 0.0 && self.spread == 0.0
    }

    /// The cone's width `distance` along the ray.
    #[inline]
    pub fn width_at(&self, distance: f64) -> f64 {
        self.width + self.spread * distance
    }

    /// The cone of the mirror reflection at `distance` along this ray, off a surface whose larger
    /// principal curvature there is `curvature` (inverse world units, 0 for flat surfaces): a
    /// mirror turning its normal by κ·w across a footprint w turns the reflection by 2κ·w.
    #[inline]
    pub fn reflected(&self, distance: f64, curvature: f64) -> RayCone {
        let width = self.width_at(distance);
        RayCone {
            width,
            spread: self.spread + 2.0 * curvature.abs() * width,
        }
    }
}

/// The footprint scale of a pixel's samples when it takes `samples` of them: each sample stands
/// for a 1/√n-wide share of the pixel, down to 1/8 (pbrt-v4's clamp).
pub fn footprint_scale(samples: u32) -> f64 {
    (1.0 / (samples.max(1) as f64).sqrt()).max(MIN_SCALE)
}

/// Where a ray's cone meets a surface: the cone's width there and the ray's unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitFootprint {
    /// The cone's width at the hit, world units (0: a point sample).
    pub width: f64,
    /// The ray's unit direction.
    pub dir: DVec3,
}

impl HitFootprint {
    /// A point sample: textures are evaluated unfiltered.
    pub const POINT: HitFootprint = HitFootprint {
        width: 0.0,
        dir: DVec3::Z,
    };

    /// The footprint of `cone`, travelling along unit `dir`, `distance` along its ray.
    #[inline]
    pub fn new(cone: &RayCone, dir: DVec3, distance: f64) -> HitFootprint {
        HitFootprint {
            width: cone.width_at(distance),
            dir,
        }
    }

    /// Whether textures are to be filtered here.
    #[inline]
    pub fn is_point(&self) -> bool {
        self.width == 0.0
    }

    /// Two world vectors spanning the footprint on the tangent plane with unit `normal`: two
    /// orthogonal cone-wide vectors across the ray, each carried along the ray onto the plane.
    pub fn axes(&self, normal: DVec3) -> (DVec3, DVec3) {
        let (u, v) = orthonormal_basis(self.dir);
        let cos = self.dir.dot(normal);
        let cos = if cos.abs() < MIN_COSINE {
            MIN_COSINE.copysign(cos)
        } else {
            cos
        };
        // p + w·u moved along the ray until it lies on the plane: w·(u − d (n·u)/(n·d)).
        let onto_plane = |e: DVec3| (e - self.dir * (normal.dot(e) / cos)) * self.width;
        (onto_plane(u), onto_plane(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_is_a_sample_share_of_the_pixel_down_to_an_eighth() {
        assert_eq!(footprint_scale(1), 1.0);
        assert_eq!(footprint_scale(4), 0.5);
        assert_eq!(footprint_scale(64), 0.125);
        assert_eq!(footprint_scale(1024), 0.125);
        assert_eq!(footprint_scale(0), 1.0);
    }

    #[test]
    fn flat_mirrors_keep_the_spread_and_curved_ones_widen_it() {
        let cone = RayCone {
            width: 0.0,
            spread: 0.01,
        };
        let flat = cone.reflected(10.0, 0.0);
        assert!((flat.width - 0.1).abs() < 1e-15);
        assert_eq!(flat.spread, 0.01);
        // A parallel beam of width w off a sphere of radius r diverges by 2w/r (focal length r/2).
        let beam = RayCone {
            width: 0.2,
            spread: 0.0,
        };
        let off_sphere = beam.reflected(3.0, 1.0 / 2.0);
        assert!((off_sphere.spread - 0.2).abs() < 1e-15);
        assert!(RayCone::POINT.reflected(5.0, 1.0).is_point());
    }

    #[test]
    fn footprint_head_on_is_the_width_and_stretches_by_one_over_cosine() {
        let head_on = HitFootprint {
            width: 0.5,
            dir: -DVec3::Z,
        };
        let (a, b) = head_on.axes(DVec3::Z);
        assert!((a.length() - 0.5).abs() < 1e-12 && (b.length() - 0.5).abs() < 1e-12);
        assert!(a.dot(b).abs() < 1e-12 && a.z.abs() < 1e-12 && b.z.abs() < 1e-12);
        // At 60° from the normal the footprint's area grows by 1/cos 60° = 2.
        let dir = DVec3::new(60f64.to_radians().sin(), 0.0, -60f64.to_radians().cos());
        let oblique = HitFootprint { width: 0.5, dir };
        let (a, b) = oblique.axes(DVec3::Z);
        assert!((a.cross(b).length() - 0.25 * 2.0).abs() < 1e-12);
        assert!(a.z.abs() < 1e-12 && b.z.abs() < 1e-12);
        // Grazing rays stop stretching at the limit instead of overflowing.
        let grazing = HitFootprint {
            width: 0.5,
            dir: DVec3::X,
        };
        let (a, b) = grazing.axes(DVec3::Z);
        assert!(a.is_finite() && b.is_finite());
    }
}
