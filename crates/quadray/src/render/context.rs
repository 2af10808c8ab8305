//! What every camera sample of one render needs, shared by the uniform, adaptive and progressive
//! samplers: the scene, the prepared camera, the pixels and the passes, and the sampling of one
//! camera ray into a pixel estimate.

use crate::aov::{AovSample, AovSelection, Aovs};
use crate::camera::CameraFrame;
use crate::footprint::{HitFootprint, RayCone, footprint_scale};
use crate::integrator::RayCounts;
use crate::math::Ray;
use crate::render::empty_tiles::EmptyTiles;
use crate::render::{PixelWindow, RenderError, RenderSettings};
use crate::sampler::SampleKey;
use crate::scene::Scene;
#[cfg(target_arch = "x86_64")]
use crate::simd::{SimdPath, simd_path};
use glam::{DVec3, Vec3};

/// What every camera sample of one render needs: the scene, the prepared camera and the passes.
pub(crate) struct SampleContext<'a> {
    /// The scene being rendered.
    pub scene: &'a Scene,
    /// The settings being rendered.
    pub settings: &'a RenderSettings,
    /// The pixels to render.
    pub window: PixelWindow,
    /// The passes to fill besides the beauty image.
    pub selection: AovSelection,
    camera: CameraFrame,
    forward: DVec3,
    /// The tiles found to see nothing, where a sampler that visits pixels many times found them
    /// once ([`SampleContext::with_empty_tiles`]).
    empty_tiles: Option<&'a EmptyTiles>,
}

impl<'a> SampleContext<'a> {
    pub(crate) fn new(
        scene: &'a Scene,
        settings: &'a RenderSettings,
        selection: AovSelection,
    ) -> Result<SampleContext<'a>, RenderError> {
        let aspect = settings.width as f64 / settings.height as f64;
        let camera = settings.camera.as_ref().unwrap_or(scene.camera());
        Ok(SampleContext {
            scene,
            settings,
            window: settings.window(),
            selection,
            camera: camera.prepare(aspect)?,
            forward: (camera.to - camera.from).normalize(),
            empty_tiles: None,
        })
    }

    /// The same context over another window of the same image.
    pub fn with_window(&self, window: PixelWindow) -> SampleContext<'a> {
        SampleContext { window, ..*self }
    }

    /// The cone of each camera sample of a pixel that takes `samples` of them
    /// ([`footprint_scale`]), or [`RayCone::POINT`] when no texture of the scene is filtered or
    /// filtering is off.
    pub fn sample_cone(&self, samples: u32) -> RayCone {
        if self.settings.texture_filter && self.scene.filters_textures() {
            self.camera
                .pixel_cone(self.settings.height, footprint_scale(samples))
        } else {
            RayCone::POINT
        }
    }

    /// [`SampleContext::trace_ray`] of the camera ray through `(dx, dy)` inside pixel `(x, y)` of
    /// the full image (the renderers make their rays in batches first).
    #[cfg(test)]
    pub fn trace(
        &self,
        pixel: (u32, u32),
        offset: (f64, f64),
        cone: RayCone,
        key: SampleKey,
        aov: Option<&mut AovSample>,
        counts: &mut RayCounts,
    ) -> Vec3 {
        self.trace_ray(&self.camera_ray(pixel, offset), cone, key, aov, counts)
    }

    /// The camera ray through `(dx, dy)` inside pixel `(x, y)` of the full image.
    #[inline(always)]
    pub fn camera_ray(&self, (x, y): (u32, u32), (dx, dy): (f64, f64)) -> Ray {
        let (w, h) = (self.settings.width as f64, self.settings.height as f64);
        self.camera.ray((x as f64 + dx) / w, (y as f64 + dy) / h)
    }

    /// The camera rays through `at`, each a pixel of the full image plus the sample's offset
    /// inside it (`x + dx`, `y + dy`), into `rays`: bit for bit [`SampleContext::camera_ray`] of
    /// each, made together so that their divisions and square roots overlap, and run four at a
    /// time where the CPU has AVX2 (`CameraFrame::rays_at_avx2`).
    pub fn camera_rays(&self, at: &[[f64; 2]], rays: &mut [Ray]) {
        let size = [self.settings.width as f64, self.settings.height as f64];
        #[cfg(target_arch = "x86_64")]
        if simd_path() == SimdPath::Avx2 {
            // SAFETY: the CPU has AVX2 (checked by `simd_path`).
            return unsafe { self.camera.rays_at_avx2(at, size, rays) };
        }
        self.camera.rays_at(at, size, rays);
    }

    /// The same context, answering [`SampleContext::sees_nothing_at`] from `tiles` (found for
    /// this context's window).
    pub(crate) fn with_empty_tiles<'b>(&self, tiles: &'b EmptyTiles) -> SampleContext<'b>
    where
        'a: 'b,
    {
        SampleContext {
            empty_tiles: Some(tiles),
            ..*self
        }
    }

    /// Whether blocks of pixels may be found to see nothing ([`SampleContext::meets_nothing`]):
    /// the rays of a pinhole camera share their origin, an orthographic camera's do not.
    pub(crate) fn finds_empty_tiles(&self) -> bool {
        !self.camera.is_orthographic()
    }

    /// Whether every camera ray through pixel `(x, y)` lies in a tile found to see nothing; `false`
    /// for a context without its tiles found (the adaptive pilot's sparse pixels, where asking
    /// each pixel alone would cost more than it saves).
    pub(crate) fn sees_nothing_at(&self, (x, y): (u32, u32)) -> bool {
        self.empty_tiles.is_some_and(|tiles| tiles.contains((x, y)))
    }

    /// Whether every camera ray through the `width` × `height` pixels from `(x, y)` meets
    /// nothing ([`Scene::camera_rays_meet_nothing`] for the rays through the block's corners,
    /// whose cone holds every sample's ray: a sample's offset lies in [0, 1)² of its pixel).
    pub(crate) fn meets_nothing(&self, (x, y): (u32, u32), (width, height): (u32, u32)) -> bool {
        if !self.finds_empty_tiles() {
            return false;
        }
        let (last_x, last_y) = (x + width - 1, y + height - 1);
        let corners = [
            self.camera_ray((x, y), (0.0, 0.0)),
            self.camera_ray((last_x, y), (1.0, 0.0)),
            self.camera_ray((x, last_y), (0.0, 1.0)),
            self.camera_ray((last_x, last_y), (1.0, 1.0)),
        ];
        self.scene.camera_rays_meet_nothing(&corners)
    }

    /// The radiance of camera ray `ray` (made by [`SampleContext::camera_ray`]) for a sample
    /// standing for `cone`, which is sample `key` (for the integrator's own samples, glossy
    /// directions); with `aov`, also the pixel's surface passes from the ray's first hit (its
    /// albedo averaged over the whole pixel, as one sample gives the pass).
    pub fn trace_ray(
        &self,
        ray: &Ray,
        cone: RayCone,
        key: SampleKey,
        aov: Option<&mut AovSample>,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let whitted = &self.settings.whitted;
        match aov {
            Some(aov) => {
                let (radiance, hit) = whitted.camera_ray_hit(self.scene, ray, cone, key, counts);
                let footprint = match &hit {
                    Some(hit) if !cone.is_point() => HitFootprint::new(
                        &self.sample_cone(1),
                        ray.dir.normalize(),
                        hit.t * ray.dir.length(),
                    ),
                    _ => HitFootprint::POINT,
                };
                *aov = AovSample::from_hit(
                    self.scene,
                    self.selection,
                    (ray.origin, ray.dir),
                    self.forward,
                    hit.as_ref(),
                    &footprint,
                );
                radiance
            }
            None => whitted.camera_ray(self.scene, ray, cone, key, counts),
        }
    }

    /// [`SampleContext::trace_ray`] without passes for each ray of `rays` into `radiances`, ray
    /// `i` being sample `key(i)`: one call for a pixel's batch of samples instead of one a
    /// sample (the uniform renderer's [`crate::integrator::Whitted::camera_rays`]).
    pub fn trace_rays(
        &self,
        rays: &[Ray],
        cone: RayCone,
        key: impl Fn(usize) -> SampleKey,
        counts: &mut RayCounts,
        radiances: &mut [Vec3],
    ) {
        let whitted = &self.settings.whitted;
        whitted.camera_rays(self.scene, rays, cone, key, counts, radiances);
    }

    /// One pass sample per pixel of the window when any pass is selected, else nothing.
    pub fn aov_buffer(&self) -> Vec<AovSample> {
        let pixels = self.window.width() as usize * self.window.height() as usize;
        if self.selection.any() {
            vec![AovSample::MISS; pixels]
        } else {
            Vec::new()
        }
    }

    /// The rows of a buffer of one value a window pixel, all `None` when it is empty (kept only
    /// for a pass, or a rule, that is not asked for).
    pub fn optional_rows<'b, T>(&self, buffer: &'b mut [T]) -> Vec<Option<&'b mut [T]>> {
        if buffer.is_empty() {
            (0..self.window.height()).map(|_| None).collect()
        } else {
            buffer
                .chunks_mut(self.window.width() as usize)
                .map(Some)
                .collect()
        }
    }

    /// The passes of the finished window, or `None` when none was selected.
    pub fn finish_aovs(&self, samples: Vec<AovSample>) -> Option<Aovs> {
        self.selection
            .any()
            .then(|| {
                Aovs::new(
                    self.window.width(),
                    self.window.height(),
                    self.selection,
                    samples,
                )
            })
            .flatten()
    }
}
