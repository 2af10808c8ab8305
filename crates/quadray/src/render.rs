//! Rendering a scene to a film in parallel over rows with rayon, deterministically.

use crate::aov::{AovSample, AovSelection, Aovs};
use crate::film::Film;
use crate::integrator::{RayCounts, Whitted};
use crate::sampler::{pixel_pattern, sample_2d};
use crate::scene::Scene;
use glam::Vec3;
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
    /// Samples per pixel (1: the pixel centre; more: stratified jitter).
    pub spp: u32,
    /// Sample set: 0 is the default; another value jitters every pixel with an unrelated pattern
    /// (a statistically independent render, e.g. a reference to measure error against).
    pub seed: u32,
    /// The integrator's recursion limits.
    pub whitted: Whitted,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 480,
            spp: 1,
            seed: 0,
            whitted: Whitted::default(),
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
    /// The camera cannot produce rays at this aspect.
    #[error("camera: {0}")]
    Camera(#[from] crate::camera::CameraError),
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
        if !(1..=MAX_DEPTH).contains(&self.whitted.max_depth) {
            return Err(RenderError::Depth(self.whitted.max_depth));
        }
        Ok(())
    }
}

/// Receives progress while rendering (implemented by front ends, e.g. a progress bar).
pub trait Progress: Sync {
    /// Called after each finished row.
    fn row_done(&self);
}

/// A progress sink that ignores everything.
pub struct NoProgress;

impl Progress for NoProgress {
    fn row_done(&self) {}
}

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image.
    pub film: Film,
    /// Rays traced, by kind.
    pub counts: RayCounts,
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
    let (w, h) = (settings.width, settings.height);
    let camera = scene.camera().prepare(w as f64 / h as f64)?;
    let forward = (scene.camera().to - scene.camera().from).normalize();
    let mut film = Film::new(w, h);
    // Pass samples are allocated and computed only when a pass is selected.
    let mut aov_samples = if selection.any() {
        vec![AovSample::MISS; w as usize * h as usize]
    } else {
        Vec::new()
    };
    let aov_rows: Vec<Option<&mut [AovSample]>> = if selection.any() {
        aov_samples.chunks_mut(w as usize).map(Some).collect()
    } else {
        (0..h).map(|_| None).collect()
    };
    let totals = Mutex::new(RayCounts::default());
    let spp = settings.spp;
    let inv_spp = 1.0 / spp as f32;
    film.pixels_mut()
        .par_chunks_mut(w as usize)
        .zip(aov_rows)
        .enumerate()
        .for_each(|(y, (row, mut aov_row))| {
            let y = y as u32;
            let mut counts = RayCounts::default();
            for (x, pixel) in row.iter_mut().enumerate() {
                let pattern = pixel_pattern(x as u32, y, settings.seed);
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let (dx, dy) = sample_2d(s, spp, pattern);
                    let ray = camera.ray((x as f64 + dx) / w as f64, (y as f64 + dy) / h as f64);
                    match aov_row.as_deref_mut() {
                        Some(aovs) if s == 0 => {
                            let (radiance, hit) =
                                settings.whitted.camera_ray_hit(scene, &ray, &mut counts);
                            aovs[x] = AovSample::from_hit(
                                scene,
                                selection,
                                ray.origin,
                                ray.dir,
                                forward,
                                hit.as_ref(),
                            );
                            sum += radiance;
                        }
                        _ => sum += settings.whitted.camera_ray(scene, &ray, &mut counts),
                    }
                }
                *pixel = sum * inv_spp;
            }
            *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            progress.row_done();
        });
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    let aovs = selection
        .any()
        .then(|| Aovs::new(w, h, selection, aov_samples))
        .flatten();
    Ok((Rendered { film, counts }, aovs))
}
