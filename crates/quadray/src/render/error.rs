//! Why a render cannot run, and the resolution check every front end shares.

use crate::limits::{MAX_ASPECT, MAX_DEPTH, MAX_PIXELS, MAX_SIDE, MAX_SPP};
use crate::render::PixelWindow;
use crate::render::adaptive::AdaptiveError;
use crate::render::antialias::AntialiasError;

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
    /// Anti-aliasing settings outside their limits.
    #[error("anti-aliasing: {0}")]
    Antialias(AntialiasError),
    /// Both anti-aliasing by contrast and adaptive sampling asked for.
    #[error(
        "anti-aliasing by contrast and adaptive sampling are two ways to place samples: choose one"
    )]
    AntialiasAndAdaptive,
    /// The camera cannot produce rays at this aspect.
    #[error("camera: {0}")]
    Camera(crate::camera::CameraError),
    /// [`crate::render::Progress::cancelled`] asked to stop before the render finished.
    #[error("the render was cancelled")]
    Cancelled,
}

impl From<AdaptiveError> for RenderError {
    fn from(e: AdaptiveError) -> RenderError {
        RenderError::Adaptive(e)
    }
}

impl From<AntialiasError> for RenderError {
    fn from(e: AntialiasError) -> RenderError {
        RenderError::Antialias(e)
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
