//! Progress reports from a render to its front end (a progress bar, the viewer), and cancellation.

use crate::render::adaptive;

/// Receives progress while rendering (implemented by front ends, e.g. a progress bar).
pub trait Progress: Sync {
    /// Called after each finished row (of each round, when sampling is adaptive; of the first
    /// samples and then of the refinement, each row twice, when anti-aliasing by contrast).
    fn row_done(&self);

    /// Called after each round of adaptive sampling, with where the image stands.
    fn round_done(&self, _round: &adaptive::RoundSummary) {}

    /// Whether the caller no longer wants the result (an interactive view that changed): rows
    /// not yet started are skipped and the render returns [`RenderError::Cancelled`].
    ///
    /// [`RenderError::Cancelled`]: crate::render::RenderError::Cancelled
    fn cancelled(&self) -> bool {
        false
    }
}

/// A progress sink that ignores everything.
pub struct NoProgress;

impl Progress for NoProgress {
    fn row_done(&self) {}
}
