//! Cameras: perspective look-at, the seed's orbit camera, and orthographic.

use crate::footprint::RayCone;
use crate::math::{MAX_COORDINATE, Ray};
use glam::{DMat4, DVec3, DVec4};

/// How the camera projects the scene onto the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole camera with a vertical field of view in degrees.
    Perspective {
        /// Vertical field of view, degrees, in (0, 180).
        vfov_deg: f64,
    },
    /// Parallel projection; `height` is the world-space height the image covers.
    Orthographic {
        /// Height of the viewed region, world units.
        height: f64,
    },
}

/// A camera looking from `from` towards `to`, with `up` giving the image's vertical.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (perspective) or centre of the image plane (orthographic).
    pub from: DVec3,
    /// Point the camera looks at.
    pub to: DVec3,
    /// Approximate up direction; only its component orthogonal to the view direction matters.
    pub up: DVec3,
    /// Perspective or orthographic.
    pub projection: Projection,
}

/// Why a camera cannot produce rays.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// `from` and `to` coincide.
    #[error("camera position and target coincide")]
    NoViewDirection,
    /// `up` is zero or parallel to the view direction.
    #[error("camera up vector is zero or parallel to the view direction")]
    DegenerateUp,
    /// Field of view outside (0, 180) degrees or a non-positive orthographic height.
    #[error(
        "camera field of view must be in (0, 180) degrees and orthographic height positive, got {0}"
    )]
    BadProjection(f64),
    /// A coordinate is NaN or infinite.
    #[error("camera coordinates must be finite")]
    NotFinite,
    /// A coordinate's magnitude is beyond [`MAX_COORDINATE`].
    #[error("camera coordinates reach {0:e}; quadray supports magnitudes up to {MAX_COORDINATE:e}")]
    TooFar(f64),
}

impl Camera {
    /// The seed's orbit camera: `distance` from `target`, at azimuth `yaw_deg` about +z measured
    /// from +x, and elevation `pitch_deg` above the xy plane, always looking at the target.
    pub fn orbit(
        target: DVec3,
        yaw_deg: f64,
        pitch_deg: f64,
        distance: f64,
        vfov_deg: f64,
    ) -> Camera {
        let (sy, cy) = yaw_deg.to_radians().sin_cos();
        let (sp, cp) = pitch_deg.to_radians().sin_cos();
        let offset = DVec3::new(cp * cy, cp * sy, sp) * distance;
        // d(offset)/d(pitch) is orthogonal to the view direction at every pitch, even straight overhead.
        let up = DVec3::new(-sp * cy, -sp * sy, cp);
        Camera {
            from: target + offset,
            to: target,
            up,
            projection: Projection::Perspective { vfov_deg },
        }
    }

    /// The same camera turned `degrees` about the vertical (+z) axis through its target,
    /// counter-clockwise seen from above: a turntable frame.
    pub fn orbited(&self, degrees: f64) -> Camera {
        let turn = glam::DQuat::from_rotation_z(degrees.to_radians());
        Camera {
            from: self.to + turn * (self.from - self.to),
            up: turn * self.up,
            ..*self
        }
    }

    /// Checks the camera and precomputes its frame for an image of the given aspect ratio (width / height).
    pub fn prepare(&self, aspect: f64) -> Result<CameraFrame, CameraError> {
        if !(self.from.is_finite() && self.to.is_finite() && self.up.is_finite()) {
            return Err(CameraError::NotFinite);
        }
        let reach = self.from.abs().max(self.to.abs()).max_element();
        if reach > MAX_COORDINATE {
            return Err(CameraError::TooFar(reach));
        }
        let forward = (self.to - self.from)
            .try_normalize()
            .ok_or(CameraError::NoViewDirection)?;
        let right = forward
            .cross(self.up)
            .try_normalize()
            .ok_or(CameraError::DegenerateUp)?;
        let up = right.cross(forward);
        let half_height = match self.projection {
            Projection::Perspective { vfov_deg } => {
                if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
                    return Err(CameraError::BadProjection(vfov_deg));
                }
                (vfov_deg.to_radians() * 0.5).tan()
            }
            Projection::Orthographic { height } => {
                if !(height > 0.0 && height.is_finite()) {
                    return Err(CameraError::BadProjection(height));
                }
                height * 0.5
            }
        };
        Ok(CameraFrame {
            origin: self.from,
            forward,
            right: right * half_height * aspect,
            up: up * half_height,
            orthographic: matches!(self.projection, Projection::Orthographic { .. }),
        })
    }
}

/// A camera's precomputed frame: turns image positions into rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    origin: DVec3,
    forward: DVec3,
    /// Right vector scaled to half the image width (at unit distance for perspective).
    right: DVec3,
    /// Up vector scaled to half the image height.
    up: DVec3,
    orthographic: bool,
}

impl CameraFrame {
    /// The ray through image position (u, v) in [0, 1]², u to the right, v downwards.
    #[inline]
    pub fn ray(&self, u: f64, v: f64) -> Ray {
        let sx = 2.0 * u - 1.0;
        let sy = 1.0 - 2.0 * v;
        if self.orthographic {
            Ray::new(self.origin + self.right * sx + self.up * sy, self.forward)
        } else {
            Ray::new(
                self.origin,
                (self.forward + self.right * sx + self.up * sy).normalize(),
            )
        }
    }

    /// The rays through the image positions `at`, each a pixel's column and row plus the
    /// sample's offset inside it, of an image `size` pixels wide and high: `rays[i]` is, bit for
    /// bit, [`CameraFrame::ray`] of `at[i] / size`.
    #[inline]
    pub fn rays_at(&self, at: &[[f64; 2]], size: [f64; 2], rays: &mut [Ray]) {
        debug_assert_eq!(at.len(), rays.len());
        for (&[x, y], ray) in at.iter().zip(rays) {
            *ray = self.ray(x / size[0], y / size[1]);
        }
    }

    /// [`CameraFrame::rays_at`] with a pinhole's rays made four at a time in AVX registers: the
    /// same operations in the same order as [`CameraFrame::ray`] (IEEE division and square root
    /// are correctly rounded in any width, and nothing is fused), so the same bits, with one
    /// division or square root for four rays instead of a queue of scalar ones.
    ///
    /// # Safety
    ///
    /// The CPU must have AVX2 ([`crate::simd_path`] says so).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub fn rays_at_avx2(&self, at: &[[f64; 2]], size: [f64; 2], rays: &mut [Ray]) {
        use std::arch::x86_64::*;
        debug_assert_eq!(at.len(), rays.len());
        if self.orthographic {
            return self.rays_at(at, size, rays);
        }
        let (groups, rest) = at.as_chunks::<4>();
        let (ray_groups, rest_rays) = rays.as_chunks_mut::<4>();
        let splat = _mm256_set1_pd;
        let (one, two) = (splat(1.0), splat(2.0));
        let (f, r, u) = (self.forward, self.right, self.up);
        for (at, rays) in groups.iter().zip(ray_groups) {
            let xs = _mm256_setr_pd(at[0][0], at[1][0], at[2][0], at[3][0]);
            let ys = _mm256_setr_pd(at[0][1], at[1][1], at[2][1], at[3][1]);
            // sx = 2u − 1 and sy = 1 − 2v, with u = x / width and v = y / height.
            let sx = _mm256_sub_pd(_mm256_mul_pd(two, _mm256_div_pd(xs, splat(size[0]))), one);
            let sy = _mm256_sub_pd(one, _mm256_mul_pd(two, _mm256_div_pd(ys, splat(size[1]))));
            // (forward + right·sx) + up·sy, one axis for four rays.
            let axis = |f: f64, r: f64, u: f64| {
                let along = _mm256_add_pd(splat(f), _mm256_mul_pd(splat(r), sx));
                _mm256_add_pd(along, _mm256_mul_pd(splat(u), sy))
            };
            let (x, y, z) = (
                axis(f.x, r.x, u.x),
                axis(f.y, r.y, u.y),
                axis(f.z, r.z, u.z),
            );
            // glam's `normalize`: times 1 / √((x² + y²) + z²).
            let squared = _mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y));
            let squared = _mm256_add_pd(squared, _mm256_mul_pd(z, z));
            let scale = _mm256_div_pd(one, _mm256_sqrt_pd(squared));
            let mut axes = [[0.0; 4]; 3];
            for (axis, lanes) in axes.iter_mut().zip([x, y, z]) {
                // SAFETY: `axis` is four f64s, the unaligned store's width.
                unsafe { _mm256_storeu_pd(axis.as_mut_ptr(), _mm256_mul_pd(lanes, scale)) };
            }
            for (k, ray) in rays.iter_mut().enumerate() {
                let dir = DVec3::new(axes[0][k], axes[1][k], axes[2][k]);
                *ray = Ray::new(self.origin, dir);
            }
        }
        self.rays_at(rest, size, rest_rays);
    }

    /// The cone of a camera sample standing for `scale` of a pixel's width, in an image
    /// `image_height` pixels high: a pinhole's cones start as points and spread by the pixel's
    /// angle at the image centre; an orthographic camera's keep the pixel's width.
    pub fn pixel_cone(&self, image_height: u32, scale: f64) -> RayCone {
        // `up` spans half the image height (at unit distance for a pinhole).
        let pixel = 2.0 * self.up.length() / image_height.max(1) as f64 * scale;
        if self.orthographic {
            RayCone {
                width: pixel,
                spread: 0.0,
            }
        } else {
            RayCone {
                width: 0.0,
                spread: pixel,
            }
        }
    }

    /// The eye position (or image-plane centre).
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Whether the camera is orthographic (its rays parallel) rather than a pinhole.
    pub fn is_orthographic(&self) -> bool {
        self.orthographic
    }

    /// The image position (u, v) at which `point` appears, the inverse of [`CameraFrame::ray`];
    /// `None` for a point behind a perspective camera. Positions outside [0, 1]² are off the image.
    pub fn project(&self, point: DVec3) -> Option<glam::DVec2> {
        let d = point - self.origin;
        let depth = if self.orthographic {
            1.0
        } else {
            d.dot(self.forward)
        };
        if depth <= 0.0 {
            return None;
        }
        // `right` and `up` carry the image's half extents: divide by their squared lengths.
        let sx = d.dot(self.right) / (depth * self.right.length_squared());
        let sy = d.dot(self.up) / (depth * self.up.length_squared());
        Some(glam::DVec2::new((sx + 1.0) * 0.5, (1.0 - sy) * 0.5))
    }

    /// The world-to-camera matrix of OpenEXR's `worldToCamera` attribute (and RenderMan's camera
    /// space): the eye at the origin, +x right and +y up in the image, +z the viewing direction
    /// (a left-handed frame). Column vectors: `camera = M * world`.
    pub fn world_to_camera(&self) -> DMat4 {
        let (right, up) = (self.right.normalize(), self.up.normalize());
        DMat4::from_cols(
            right.extend(0.0),
            up.extend(0.0),
            self.forward.extend(0.0),
            self.origin.extend(1.0),
        )
        .inverse()
    }

    /// The world-to-NDC matrix of OpenEXR's `worldToNDC` attribute: after the division by w, x and
    /// y are the image position of [`CameraFrame::project`] ((0, 0) the top-left corner of the
    /// full image, (1, 1) the bottom-right); z is 1/depth for a perspective camera and depth for an
    /// orthographic one. Column vectors: `ndc = M * world`.
    pub fn world_to_ndc(&self) -> DMat4 {
        // Camera x and y over the half extents (at unit depth for perspective) give [-1, 1].
        let (sx, sy) = (0.5 / self.right.length(), -0.5 / self.up.length());
        let projection = if self.orthographic {
            DMat4::from_cols(
                DVec4::new(sx, 0.0, 0.0, 0.0),
                DVec4::new(0.0, sy, 0.0, 0.0),
                DVec4::new(0.0, 0.0, 1.0, 0.0),
                DVec4::new(0.5, 0.5, 0.0, 1.0),
            )
        } else {
            // (x, y, z) → (sx·x + z/2, sy·y + z/2, 1, z): divided by w = z, the image position.
            DMat4::from_cols(
                DVec4::new(sx, 0.0, 0.0, 0.0),
                DVec4::new(0.0, sy, 0.0, 0.0),
                DVec4::new(0.5, 0.5, 0.0, 1.0),
                DVec4::new(0.0, 0.0, 1.0, 0.0),
            )
        };
        projection * self.world_to_camera()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbiting_turns_about_the_target() {
        let cam = Camera {
            from: DVec3::new(0.0, -9.5, 3.6),
            to: DVec3::new(0.0, 0.0, 0.9),
            up: DVec3::Z,
            projection: Projection::Perspective { vfov_deg: 40.0 },
        };
        let quarter = cam.orbited(90.0);
        assert!((quarter.from - DVec3::new(9.5, 0.0, 3.6)).length() < 1e-12);
        assert_eq!(quarter.to, cam.to);
        assert!((cam.orbited(360.0).from - cam.from).length() < 1e-12);
    }

    /// An orbit camera, and the same looking the same way with an orthographic projection.
    fn perspective_and_orthographic() -> [Camera; 2] {
        let perspective = Camera::orbit(DVec3::new(1.0, 2.0, 3.0), 30.0, 20.0, 7.0, 50.0);
        let orthographic = Camera {
            projection: Projection::Orthographic { height: 3.0 },
            ..perspective
        };
        [perspective, orthographic]
    }

    /// Rays made together are [`CameraFrame::ray`]'s bit for bit, on the baseline path and on
    /// the AVX2 one where the CPU has it (four at a time, and a remainder of three), for a
    /// pinhole and an orthographic camera, at pixel positions with and without offsets.
    #[test]
    fn rays_made_together_are_rays_made_one_by_one() {
        let size = [1283.0, 721.0];
        let at: Vec<[f64; 2]> = (0..103u32)
            .map(|k| {
                let (x, y) = (f64::from(k * 37 % 1283), f64::from(k * 11 % 721));
                [x + f64::from(k % 7) / 7.0, y + f64::from(k % 5) * 0.1999]
            })
            .collect();
        for camera in perspective_and_orthographic() {
            let frame = camera.prepare(size[0] / size[1]).unwrap();
            let expected: Vec<Ray> = (at.iter())
                .map(|&[x, y]| frame.ray(x / size[0], y / size[1]))
                .collect();
            let bits = |rays: &[Ray]| -> Vec<[u64; 6]> {
                (rays.iter())
                    .map(|r| {
                        let [a, b, c] = r.origin.to_array().map(f64::to_bits);
                        let [d, e, f] = r.dir.to_array().map(f64::to_bits);
                        [a, b, c, d, e, f]
                    })
                    .collect()
            };
            let mut rays = vec![Ray::new(DVec3::ZERO, DVec3::ZERO); at.len()];
            frame.rays_at(&at, size, &mut rays);
            assert_eq!(bits(&rays), bits(&expected));
            #[cfg(target_arch = "x86_64")]
            if crate::simd::simd_path() == crate::simd::SimdPath::Avx2 {
                rays.fill(Ray::new(DVec3::ZERO, DVec3::ZERO));
                // SAFETY: the CPU has AVX2 (checked just above).
                unsafe { frame.rays_at_avx2(&at, size, &mut rays) };
                assert_eq!(bits(&rays), bits(&expected));
            }
        }
    }

    #[test]
    fn project_inverts_ray() {
        let [perspective, _] = perspective_and_orthographic();
        for camera in perspective_and_orthographic() {
            let frame = camera.prepare(16.0 / 9.0).unwrap();
            for (u, v) in [(0.5, 0.5), (0.1, 0.8), (1.2, -0.3)] {
                let ray = frame.ray(u, v);
                let p = frame.project(ray.origin + ray.dir * 4.0).unwrap();
                assert!((p - glam::DVec2::new(u, v)).length() < 1e-12, "{p}");
            }
        }
        let frame = perspective.prepare(1.0).unwrap();
        assert_eq!(frame.project(perspective.from * 2.0 - perspective.to), None);
    }

    /// The matrices agree with `ray`: a point on the ray through (u, v) lands at (u, v) in NDC,
    /// and at camera-space depth equal to its distance along the viewing axis, in front (+z).
    #[test]
    fn exr_matrices_follow_the_rays() {
        for camera in perspective_and_orthographic() {
            let frame = camera.prepare(16.0 / 9.0).unwrap();
            let (to_camera, to_ndc) = (frame.world_to_camera(), frame.world_to_ndc());
            for (u, v) in [(0.5, 0.5), (0.1, 0.8), (1.0, 0.0)] {
                let ray = frame.ray(u, v);
                let point = ray.origin + ray.dir * 4.0;
                let ndc = to_ndc * point.extend(1.0);
                let (x, y) = (ndc.x / ndc.w, ndc.y / ndc.w);
                assert!((x - u).abs() < 1e-12 && (y - v).abs() < 1e-12, "{x} {y}");
                let c = to_camera.transform_point3(point);
                let forward = (camera.to - camera.from).normalize();
                assert!((c.z - (point - camera.from).dot(forward)).abs() < 1e-12);
                // Right of centre is +x, above it +y.
                assert_eq!(c.x > 1e-9, u > 0.5 + 1e-9);
                assert_eq!(c.y > 1e-9, v < 0.5 - 1e-9);
            }
            assert!(
                (to_camera.transform_point3(camera.from)).length() < 1e-12,
                "the eye is the origin"
            );
        }
    }

    #[test]
    fn centre_ray_looks_at_target() {
        let cam = Camera {
            from: DVec3::new(0.0, -5.0, 1.0),
            to: DVec3::new(0.0, 0.0, 1.0),
            up: DVec3::Z,
            projection: Projection::Perspective { vfov_deg: 60.0 },
        };
        let f = cam.prepare(1.5).unwrap();
        let r = f.ray(0.5, 0.5);
        assert!((r.dir - DVec3::Y).length() < 1e-15);
        // Top edge of the image is 30 degrees above the axis.
        let top = f.ray(0.5, 0.0);
        assert!((top.dir.z.atan2(top.dir.y).to_degrees() - 30.0).abs() < 1e-9);
        // Right edge is +x (right-handed, z up, looking along +y).
        assert!(f.ray(1.0, 0.5).dir.x > 0.0);
    }

    #[test]
    fn orbit_camera_keeps_distance_and_target() {
        for (yaw, pitch) in [(0.0, 0.0), (37.0, 20.0), (200.0, 90.0), (10.0, -90.0)] {
            let cam = Camera::orbit(DVec3::new(1.0, 2.0, 3.0), yaw, pitch, 7.0, 40.0);
            assert!(((cam.from - cam.to).length() - 7.0).abs() < 1e-12);
            let f = cam
                .prepare(1.0)
                .expect("orbit camera is valid at every pitch");
            let d = f.ray(0.5, 0.5).dir;
            assert!((d - (cam.to - cam.from).normalize()).length() < 1e-12);
        }
    }

    #[test]
    fn orthographic_rays_are_parallel() {
        let cam = Camera {
            from: DVec3::new(0.0, 0.0, 10.0),
            to: DVec3::ZERO,
            up: DVec3::Y,
            projection: Projection::Orthographic { height: 4.0 },
        };
        let f = cam.prepare(2.0).unwrap();
        let (a, b) = (f.ray(0.0, 0.0), f.ray(1.0, 1.0));
        assert_eq!(a.dir, b.dir);
        assert!((a.origin - b.origin - DVec3::new(-8.0, 4.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn rejects_bad_cameras() {
        let mut cam = Camera::orbit(DVec3::ZERO, 0.0, 0.0, 5.0, 40.0);
        cam.projection = Projection::Perspective { vfov_deg: 180.0 };
        assert!(matches!(
            cam.prepare(1.0),
            Err(CameraError::BadProjection(_))
        ));
        cam.to = cam.from;
        assert_eq!(cam.prepare(1.0), Err(CameraError::NoViewDirection));
    }
}
