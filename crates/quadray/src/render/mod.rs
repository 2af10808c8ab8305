//! Rendering a scene to a film in parallel over rows with rayon, deterministically: the settings
//! and the entry points here; the sample context, the uniform, adaptive and progressive samplers,
//! the errors and progress reports in their own modules.

pub mod adaptive;
mod antialias;
mod context;
mod empty_tiles;
mod error;
mod memory;
mod progress;
pub mod progressive;
mod row_order;
mod uniform;

pub use antialias::{Antialias, AntialiasError, DEFAULT_ANTIALIAS_SPP};
pub(crate) use context::SampleContext;
pub use error::{RenderError, check_resolution};
pub use memory::{PixelMemory, pixel_memory};
pub use progress::{NoProgress, Progress};
// The limits, where the render's users have always found them.
pub use crate::limits::{MAX_ASPECT, MAX_DEPTH, MAX_PIXELS, MAX_SIDE, MAX_SPP};

use crate::aov::{AovSelection, Aovs};
use crate::film::Film;
use crate::integrator::{RayCounts, Whitted};
use crate::scene::Scene;
use adaptive::{Adaptive, SamplingStats};

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
    /// Anti-aliasing by contrast: `spp` samples in every pixel, more where a pixel differs from
    /// a neighbour ([`Antialias`]); not with [`RenderSettings::adaptive`].
    pub antialias: Option<Antialias>,
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

    /// The image position of the window's pixel `i`, its pixels counted row by row.
    pub fn pixel(&self, i: usize) -> (u32, u32) {
        let width = self.width() as usize;
        (self.x0 + (i % width) as u32, self.y0 + (i / width) as u32)
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
            antialias: None,
            camera: None,
            texture_filter: true,
        }
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
        if let Some(antialias) = &self.antialias {
            if self.adaptive.is_some() {
                return Err(RenderError::AntialiasAndAdaptive);
            }
            antialias.validate(self.spp)?;
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
    match (settings.adaptive, settings.antialias) {
        (Some(adaptive), _) => adaptive::render_adaptive(&context, &adaptive, progress),
        (None, Some(antialias)) => antialias::render_antialiased(&context, &antialias, progress),
        (None, None) => uniform::render_uniform(&context, progress),
    }
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
