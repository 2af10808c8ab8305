//! Which tiles of a window see nothing, found once for the samplers that come back to a pixel
//! many times (the adaptive sampler's rounds, twins and audit; the viewer's progressive film,
//! step by step): asking the eye buffer once a tile costs a few hundred instructions, asked at
//! each visit of each pixel it cost 8% of a render of the quadric grid.

use super::PixelWindow;
use super::context::SampleContext;
use rayon::prelude::*;

/// Columns of a tile.
const TILE_WIDTH: u32 = 32;
/// Rows of a tile.
const TILE_HEIGHT: u32 = 8;

/// For each tile of 32 × 8 pixels of a window (from its top-left corner), whether every camera
/// ray through it meets nothing ([`SampleContext::meets_nothing`]).
#[derive(Debug)]
pub(crate) struct EmptyTiles {
    window: PixelWindow,
    /// Tiles across the window.
    columns: u32,
    /// Per tile, row by row: whether it sees nothing.
    empty: Vec<bool>,
}

impl EmptyTiles {
    /// The tiles of `context`'s window; none is empty when the context cannot tell
    /// ([`SampleContext::finds_empty_tiles`]).
    pub(crate) fn find(context: &SampleContext<'_>) -> EmptyTiles {
        let window = context.window;
        let columns = window.width().div_ceil(TILE_WIDTH);
        let rows = window.height().div_ceil(TILE_HEIGHT);
        // In parallel: a 16384-pixel square image has a million tiles.
        let empty = if context.finds_empty_tiles() {
            (0..rows * columns)
                .into_par_iter()
                .map(|tile| (tile % columns, tile / columns))
                .map(|(column, row)| {
                    let (x, y) = (
                        window.x0 + column * TILE_WIDTH,
                        window.y0 + row * TILE_HEIGHT,
                    );
                    let size = (
                        TILE_WIDTH.min(window.x1 - x),
                        TILE_HEIGHT.min(window.y1 - y),
                    );
                    context.meets_nothing((x, y), size)
                })
                .collect()
        } else {
            Vec::new()
        };
        EmptyTiles {
            window,
            columns,
            empty,
        }
    }

    /// Whether pixel `(x, y)` of the image lies in a tile that sees nothing (`false` outside the
    /// window).
    #[inline]
    pub(crate) fn contains(&self, (x, y): (u32, u32)) -> bool {
        let w = self.window;
        if self.empty.is_empty() || x < w.x0 || x >= w.x1 || y < w.y0 || y >= w.y1 {
            return false;
        }
        let tile = (y - w.y0) / TILE_HEIGHT * self.columns + (x - w.x0) / TILE_WIDTH;
        self.empty[tile as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aov::AovSelection;
    use crate::render::adaptive::Adaptive;
    use crate::render::uniform::tests::shapes_above_a_floor;
    use crate::render::{NoProgress, RenderSettings, render_with_aovs};

    /// A window's tiles are found as [`SampleContext::meets_nothing`] finds each (partial tiles
    /// at the right and bottom included), and an adaptive render that skips the pixels of empty
    /// tiles gives the image and the ray count of one that traces every sample (the same view with
    /// too many shapes for an eye buffer, the extra ones behind the camera, so that the box
    /// covering them holds the camera).
    #[test]
    fn empty_tiles_are_what_tracing_finds() {
        let (scene, _) = shapes_above_a_floor(0);
        let settings = RenderSettings {
            width: 90,
            height: 60,
            adaptive: Some(Adaptive {
                target_error: 0.004,
                ..Adaptive::default()
            }),
            ..RenderSettings::default()
        };
        let context = SampleContext::new(&scene, &settings, AovSelection::NONE).unwrap();
        let window = PixelWindow {
            x0: 5,
            y0: 3,
            x1: 90,
            y1: 60,
        };
        let context = context.with_window(window);
        let tiles = EmptyTiles::find(&context);
        let mut empty = 0;
        for y in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                let (tx, ty) = ((x - 5) / TILE_WIDTH, (y - 3) / TILE_HEIGHT);
                let (x0, y0) = (5 + tx * TILE_WIDTH, 3 + ty * TILE_HEIGHT);
                let size = (TILE_WIDTH.min(90 - x0), TILE_HEIGHT.min(60 - y0));
                let want = context.meets_nothing((x0, y0), size);
                assert_eq!(tiles.contains((x, y)), want, "pixel ({x}, {y})");
                empty += want as u32;
            }
        }
        assert!(empty > 500, "{empty} pixels in empty tiles");
        assert!(
            !tiles.contains((0, 0)) && !tiles.contains((4, 10)),
            "outside the window"
        );
        // Too many shapes for an eye buffer, and the one box that covers them holds the camera:
        // no tile is found empty.
        let (traced_scene, _) = shapes_above_a_floor(70);
        let (skipping, _) =
            render_with_aovs(&scene, &settings, AovSelection::NONE, &NoProgress).unwrap();
        let (tracing, _) =
            render_with_aovs(&traced_scene, &settings, AovSelection::NONE, &NoProgress).unwrap();
        assert_eq!(skipping.film.pixels(), tracing.film.pixels());
        assert_eq!(skipping.counts.camera, tracing.counts.camera);
        assert!(skipping.counts.untraced_camera > 500 && tracing.counts.untraced_camera == 0);
    }
}
