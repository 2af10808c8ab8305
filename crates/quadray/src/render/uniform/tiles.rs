//! The tiles a uniform render is cut into: bands of [`BLOCK_ROWS`] rows, taken up in interleaved
//! order, each cut into tiles of up to [`TILE`] columns; and the tiles whose rays provably meet
//! nothing, filled with the background without tracing.

use crate::aov::AovSample;
use crate::film::Film;
use crate::integrator::RayCounts;
use crate::render::PixelWindow;
use crate::render::context::SampleContext;
use crate::render::row_order::{BLOCK_ROWS, row_keys};
use glam::Vec3;

/// The width of the tiles a band is traced in, as tall as the band ([`BLOCK_ROWS`]): neighbouring
/// camera rays meet the same nodes of the acceleration structure, which a tile keeps in cache
/// where a row of the whole width does not (the bunny's and the kitchen's camera-rays-only
/// frames 10-12% faster than row by row, 1280x720; tiles 2 to 32 pixels wide measured the same
/// there, and from 32 on the quadric grid, whose pixels are cheap, pays nothing for the tiles'
/// loop: narrower ones made it 4-12% slower).
const TILE: usize = 32;

/// One image row of a tile: its pixels and, when a pass is selected, their pass samples.
pub(super) type TileRow<'a> = (&'a mut [Vec3], Option<&'a mut [AovSample]>);

/// A tile of the window: up to [`TILE`] columns of the rows of one band.
pub(super) struct Tile<'a> {
    /// The band the tile belongs to, in the order bands are taken up.
    pub(super) band: usize,
    /// The window's row of the tile's top row.
    pub(super) first_row: usize,
    /// The window's column of the tile's left column.
    pub(super) first_column: usize,
    /// The tile's part of each row of its band, top to bottom.
    pub(super) rows: Vec<TileRow<'a>>,
}

/// The window's pixels (`film`, and the passes' `aov_rows`) cut into tiles: bands of
/// [`BLOCK_ROWS`] rows taken up in interleaved order ([`row_keys`], so that progress counts
/// representative work), each band's tiles left to right. Also each band's rows and tiles.
pub(super) fn cut_into_tiles<'a>(
    film: &'a mut Film,
    window: PixelWindow,
    aov_rows: Vec<Option<&'a mut [AovSample]>>,
) -> (Vec<Tile<'a>>, Vec<(usize, usize)>) {
    let ww = window.width() as usize;
    let mut bands: Vec<(usize, Vec<TileRow<'a>>)> = Vec::new();
    for (row_index, row) in film.pixels_mut().chunks_mut(ww).zip(aov_rows).enumerate() {
        if row_index % BLOCK_ROWS == 0 {
            bands.push((row_index, Vec::with_capacity(BLOCK_ROWS)));
        }
        if let Some((_, rows)) = bands.last_mut() {
            rows.push(row);
        }
    }
    let keys = row_keys(window.height() as usize);
    bands.sort_unstable_by_key(|(first_row, _)| keys[*first_row]);
    let columns = ww.div_ceil(TILE);
    let mut tiles = Vec::with_capacity(bands.len() * columns);
    let mut band_rows = Vec::with_capacity(bands.len());
    for (band, (first_row, rows)) in bands.into_iter().enumerate() {
        band_rows.push((rows.len(), columns));
        let mut band_tiles: Vec<Tile<'a>> = (0..columns)
            .map(|c| Tile {
                band,
                first_row,
                first_column: c * TILE,
                rows: Vec::with_capacity(rows.len()),
            })
            .collect();
        for (pixels, aovs) in rows {
            let mut aov_segments = aovs.map(|aovs| aovs.chunks_mut(TILE));
            for (tile, segment) in band_tiles.iter_mut().zip(pixels.chunks_mut(TILE)) {
                let aov_segment = aov_segments.as_mut().and_then(Iterator::next);
                tile.rows.push((segment, aov_segment));
            }
        }
        tiles.extend(band_tiles);
    }
    (tiles, band_rows)
}

/// Whether every camera ray of `tile` provably meets nothing ([`SampleContext::meets_nothing`]);
/// `false` for a tile with passes, which are filled from each sample's hit.
pub(super) fn meets_nothing(context: &SampleContext<'_>, tile: &Tile<'_>) -> bool {
    let Some((pixels, None)) = tile.rows.first() else {
        return false;
    };
    let x = context.window.x0 + tile.first_column as u32;
    let y = context.window.y0 + tile.first_row as u32;
    context.meets_nothing((x, y), (pixels.len() as u32, tile.rows.len() as u32))
}

/// Fills `pixels` with what the pixel loop of [`super::render_segment`] leaves where every sample sees
/// the background (its sum and scale, done once), and counts their camera rays.
pub(super) fn fill_background(
    context: &SampleContext<'_>,
    pixels: &mut [Vec3],
    counts: &mut RayCounts,
) {
    let spp = context.settings.spp;
    let mut sum = Vec3::ZERO;
    for _ in 0..spp {
        sum += context.scene.background();
    }
    pixels.fill(sum * (1.0 / spp as f32));
    let rays = pixels.len() as u64 * u64::from(spp);
    counts.camera += rays;
    counts.untraced_camera += rays;
}
