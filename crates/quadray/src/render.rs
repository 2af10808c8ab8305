//! Rendering a scene to a film in parallel over rows with rayon, deterministically.

use crate::adaptive::{self, Adaptive, AdaptiveError, SamplingStats};
use crate::aov::{AovSample, AovSelection, Aovs};
use crate::camera::CameraFrame;
use crate::film::{Film, PixelEstimate};
use crate::footprint::{HitFootprint, RayCone, footprint_scale};
use crate::integrator::{RayCounts, Whitted};
use crate::sampler::{PixelSampler, pixel_pattern};
use crate::scene::Scene;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::Mutex;

/// Largest image side in pixels.
pub const MAX_SIDE: u32 = 16384;
/// Largest pixel count (about 134 megapixels, 1.6 GB of f32 RGB).
pub const MAX_PIXELS: u64 = 1 << 27;
/// Largest samples per pixel.
pub const MAX_SPP: u32 = 65536;
/// Largest ray chain length.
pub const MAX_DEPTH: u32 = 64;
/// Largest image aspect ratio (either way).
pub const MAX_ASPECT: f64 = 64.0;

/// What to render: resolution, sampling and recursion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (1: the pixel centre; more: stratified jitter). Ignored when
    /// [`RenderSettings::adaptive`] is set.
    pub spp: u32,
    /// Sample set: 0 is the default; another value jitters every pixel with an unrelated pattern
    /// (a statistically independent render, e.g. a reference to measure error against).
    pub seed: u32,
    /// The integrator's recursion limits.
    pub whitted: Whitted,
    /// Render only this window of the image (`None`: all of it). Every pixel in the window is
    /// bit-identical to the same pixel of the whole render.
    pub crop: Option<PixelWindow>,
    /// Error-targeted adaptive sampling instead of `spp` samples in every pixel.
    pub adaptive: Option<Adaptive>,
    /// A camera to render through instead of the scene's (an interactive view that moved away
    /// from it), so the scene and its acceleration structure need not be rebuilt.
    pub camera: Option<crate::camera::Camera>,
    /// Whether the checker and contour bands are averaged over each sample's footprint
    /// ([`crate::footprint`]); off, they are point sampled, as POV-Ray samples them.
    pub texture_filter: bool,
}

/// A rectangle of pixels inside the full image: columns `x0..x1`, rows `y0..y1` (half-open),
/// counted from the top-left pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelWindow {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelWindow {
    /// The whole of a `width` × `height` image.
    pub fn full(width: u32, height: u32) -> PixelWindow {
        PixelWindow {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// The pixels a normalised crop window `[x0, x1] × [y0, y1]` (fractions of the width and
    /// height, from the top-left) covers in a `width` × `height` image, rounded as pbrt's
    /// `--cropwindow` does (each edge up to the next pixel boundary), so that adjacent windows
    /// sharing an edge cover every pixel exactly once. `None` unless `0 <= x0 < x1 <= 1` and the
    /// same for y, or when the window holds no pixel.
    pub fn from_normalized(
        [x0, x1, y0, y1]: [f64; 4],
        width: u32,
        height: u32,
    ) -> Option<PixelWindow> {
        let ordered =
            |a: f64, b: f64| (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) && a < b;
        if !(ordered(x0, x1) && ordered(y0, y1)) {
            return None;
        }
        let edge = |t: f64, n: u32| ((n as f64 * t).ceil() as u32).min(n);
        let window = PixelWindow {
            x0: edge(x0, width),
            y0: edge(y0, height),
            x1: edge(x1, width),
            y1: edge(y1, height),
        };
        (window.width() > 0 && window.height() > 0).then_some(window)
    }

    /// Columns in the window.
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Rows in the window.
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Whether the window is non-empty and lies inside a `width` × `height` image.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.x0 < self.x1 && self.y0 < self.y1 && self.x1 <= width && self.y1 <= height
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 480,
            spp: 1,
            seed: 0,
            whitted: Whitted::default(),
            crop: None,
            adaptive: None,
            camera: None,
            texture_filter: true,
        }
    }
}

/// Why settings cannot be rendered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// Resolution outside the documented limits.
    #[error(
        "resolution {width}x{height} is outside the limits (1..={MAX_SIDE} per side, at most {MAX_PIXELS} pixels, aspect at most {MAX_ASPECT})"
    )]
    Resolution {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
    },
    /// Samples per pixel outside 1..=MAX_SPP.
    #[error("samples per pixel must be in 1..={MAX_SPP}, got {0}")]
    Spp(u32),
    /// Depth outside 1..=MAX_DEPTH.
    #[error("max depth must be in 1..={MAX_DEPTH}, got {0}")]
    Depth(u32),
    /// A crop window that is empty or reaches outside the image.
    #[error("crop window {window:?} is empty or outside the {width}x{height} image")]
    Crop {
        /// The window asked for.
        window: PixelWindow,
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
    /// Adaptive sampling settings outside their limits. (The message holds the cause's: no
    /// `#[from]`, which would also make it the source, and error chains would print it twice.)
    #[error("adaptive sampling: {0}")]
    Adaptive(AdaptiveError),
    /// The camera cannot produce rays at this aspect.
    #[error("camera: {0}")]
    Camera(crate::camera::CameraError),
    /// [`Progress::cancelled`] asked to stop before the render finished.
    #[error("the render was cancelled")]
    Cancelled,
}

impl From<AdaptiveError> for RenderError {
    fn from(e: AdaptiveError) -> RenderError {
        RenderError::Adaptive(e)
    }
}

impl From<crate::camera::CameraError> for RenderError {
    fn from(e: crate::camera::CameraError) -> RenderError {
        RenderError::Camera(e)
    }
}

/// Checks an image size against the documented limits: sides, pixel count and aspect ratio.
pub fn check_resolution(width: u32, height: u32) -> Result<(), RenderError> {
    let aspect = width as f64 / height.max(1) as f64;
    let within = (1..=MAX_SIDE).contains(&width)
        && (1..=MAX_SIDE).contains(&height)
        && width as u64 * height as u64 <= MAX_PIXELS
        && (1.0 / MAX_ASPECT..=MAX_ASPECT).contains(&aspect);
    if within {
        Ok(())
    } else {
        Err(RenderError::Resolution { width, height })
    }
}

impl RenderSettings {
    /// Checks the settings against the documented limits.
    pub fn validate(&self) -> Result<(), RenderError> {
        check_resolution(self.width, self.height)?;
        if !(1..=MAX_SPP).contains(&self.spp) {
            return Err(RenderError::Spp(self.spp));
        }
        if let Some(adaptive) = &self.adaptive {
            adaptive.validate()?;
        }
        if !(1..=MAX_DEPTH).contains(&self.whitted.max_depth) {
            return Err(RenderError::Depth(self.whitted.max_depth));
        }
        if let Some(window) = self.crop
            && !window.fits(self.width, self.height)
        {
            return Err(RenderError::Crop {
                window,
                width: self.width,
                height: self.height,
            });
        }
        Ok(())
    }

    /// The pixels to render: the crop window, or the whole image.
    pub fn window(&self) -> PixelWindow {
        self.crop
            .unwrap_or_else(|| PixelWindow::full(self.width, self.height))
    }
}

/// Receives progress while rendering (implemented by front ends, e.g. a progress bar).
pub trait Progress: Sync {
    /// Called after each finished row (of each round, when sampling is adaptive).
    fn row_done(&self);

    /// Called after each round of adaptive sampling, with where the image stands.
    fn round_done(&self, _round: &adaptive::RoundSummary) {}

    /// Whether the caller no longer wants the result (an interactive view that changed): rows
    /// not yet started are skipped and the render returns [`RenderError::Cancelled`].
    fn cancelled(&self) -> bool {
        false
    }
}

/// A progress sink that ignores everything.
pub struct NoProgress;

impl Progress for NoProgress {
    fn row_done(&self) {}
}

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image: the pixels of [`Rendered::window`].
    pub film: Film,
    /// Where the film lies in the full image ([`RenderSettings::window`]).
    pub window: PixelWindow,
    /// Rays traced, by kind.
    pub counts: RayCounts,
    /// Samples taken per pixel, and the error reached when sampling was adaptive.
    pub sampling: SamplingStats,
}

/// Renders `scene` on the current rayon pool. Every pixel depends only on its own position, so the
/// result is bit-identical for any number of threads.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &dyn Progress,
) -> Result<Rendered, RenderError> {
    render_with_aovs(scene, settings, AovSelection::NONE, progress).map(|(rendered, _)| rendered)
}

/// Renders `scene` like [`render`], and also the selected AOV passes (`None` when none is
/// selected); the passes come from the first hit of each pixel's first sample ([`crate::aov`]).
pub fn render_with_aovs(
    scene: &Scene,
    settings: &RenderSettings,
    selection: AovSelection,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    settings.validate()?;
    let context = SampleContext::new(scene, settings, selection)?;
    match settings.adaptive {
        Some(adaptive) => adaptive::render_adaptive(&context, &adaptive, progress),
        None => render_uniform(&context, progress),
    }
}

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

    /// The radiance of the camera ray through `(dx, dy)` inside pixel `(x, y)` of the full image,
    /// for a sample standing for `cone`; with `aov`, also the pixel's surface passes from the
    /// ray's first hit (its albedo averaged over the whole pixel, as one sample gives the pass).
    pub fn trace(
        &self,
        (x, y): (u32, u32),
        (dx, dy): (f64, f64),
        cone: RayCone,
        aov: Option<&mut AovSample>,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let (w, h) = (self.settings.width as f64, self.settings.height as f64);
        let ray = self.camera.ray((x as f64 + dx) / w, (y as f64 + dy) / h);
        let whitted = &self.settings.whitted;
        match aov {
            Some(aov) => {
                let (radiance, hit) = whitted.camera_ray_hit(self.scene, &ray, cone, counts);
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
            None => whitted.camera_ray(self.scene, &ray, cone, counts),
        }
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

    /// The buffer's rows (all `None` when it is empty: no pass selected).
    pub fn aov_rows<'b>(&self, buffer: &'b mut [AovSample]) -> Vec<Option<&'b mut [AovSample]>> {
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

/// `settings.spp` samples in every pixel, by correlated multi-jittered sampling.
fn render_uniform(
    context: &SampleContext<'_>,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let (settings, window, selection) = (context.settings, context.window, context.selection);
    let ww = window.width() as usize;
    let mut film = Film::new(window.width(), window.height());
    // Pass samples are allocated and computed only when a pass is selected.
    let mut aov_samples = context.aov_buffer();
    let aov_rows = context.aov_rows(&mut aov_samples);
    let totals = Mutex::new(RayCounts::default());
    let spp = settings.spp;
    let inv_spp = 1.0 / spp as f32;
    let cone = context.sample_cone(spp);
    film.pixels_mut()
        .par_chunks_mut(ww)
        .zip(aov_rows)
        .enumerate()
        .for_each(|(row_index, (row, mut aov_row))| {
            if progress.cancelled() {
                return;
            }
            // Pixels are sampled by their position in the full image, so a window's pixels equal
            // the whole render's.
            let y = window.y0 + row_index as u32;
            let mut counts = RayCounts::default();
            let mut sampler = PixelSampler::new(spp);
            for (column, pixel) in row.iter_mut().enumerate() {
                let x = window.x0 + column as u32;
                sampler.start_pixel(pixel_pattern(x, y, settings.seed));
                let mut aov = aov_row.as_deref_mut().map(|aovs| &mut aovs[column]);
                // The variance pass needs the running estimate; the image keeps its f32 sum.
                let mut estimate = selection.variance.then(PixelEstimate::default);
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let offset = sampler.sample(s);
                    let first_hit = if s == 0 { aov.as_deref_mut() } else { None };
                    let radiance = context.trace((x, y), offset, cone, first_hit, &mut counts);
                    if let Some(e) = &mut estimate {
                        e.add(radiance);
                    }
                    sum += radiance;
                }
                *pixel = sum * inv_spp;
                if let Some(aov) = aov {
                    aov.fill_sampling(selection, spp, estimate.map(|e| e.variance()));
                }
            }
            *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            progress.row_done();
        });
    if progress.cancelled() {
        return Err(RenderError::Cancelled);
    }
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((
        Rendered {
            film,
            window,
            counts,
            sampling: SamplingStats::uniform(spp),
        },
        context.finish_aovs(aov_samples),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalized_windows_round_like_pbrt_and_tile_exactly() {
        let w = PixelWindow::from_normalized([0.0, 0.5, 0.25, 1.0], 101, 40).unwrap();
        assert_eq!((w.x0, w.x1, w.y0, w.y1), (0, 51, 10, 40));
        // Thirds of 100 columns: ceil(33.3) = 34, ceil(66.7) = 67; neighbours share their edge.
        let thirds: Vec<PixelWindow> = (0..3)
            .map(|i| {
                let (a, b) = (i as f64 / 3.0, (i + 1) as f64 / 3.0);
                PixelWindow::from_normalized([a, b, 0.0, 1.0], 100, 1).unwrap()
            })
            .collect();
        assert_eq!(thirds.iter().map(|w| w.width()).sum::<u32>(), 100);
        assert_eq!(thirds[0].x1, thirds[1].x0);
        assert_eq!(thirds[1].x1, thirds[2].x0);
        for bad in [
            [0.5, 0.5, 0.0, 1.0],
            [0.6, 0.5, 0.0, 1.0],
            [-0.1, 0.5, 0.0, 1.0],
            [0.0, 1.5, 0.0, 1.0],
            [f64::NAN, 1.0, 0.0, 1.0],
        ] {
            assert_eq!(PixelWindow::from_normalized(bad, 100, 100), None, "{bad:?}");
        }
        // A window too thin to hold a pixel centre's column is empty.
        assert_eq!(
            PixelWindow::from_normalized([0.501, 0.502, 0.0, 1.0], 100, 100),
            None
        );
    }

    #[test]
    fn windows_outside_the_image_are_refused() {
        let mut s = RenderSettings {
            width: 10,
            height: 10,
            ..RenderSettings::default()
        };
        s.crop = Some(PixelWindow {
            x0: 5,
            y0: 0,
            x1: 11,
            y1: 10,
        });
        assert!(matches!(s.validate(), Err(RenderError::Crop { .. })));
        s.crop = Some(PixelWindow {
            x0: 5,
            y0: 3,
            x1: 5,
            y1: 10,
        });
        assert!(s.validate().is_err());
        s.crop = Some(PixelWindow {
            x0: 2,
            y0: 3,
            x1: 5,
            y1: 10,
        });
        assert_eq!(s.validate(), Ok(()));
        assert_eq!(s.window().width(), 3);
    }
}
