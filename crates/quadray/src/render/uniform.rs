//! Uniform sampling: the same number of samples in every pixel, traced in tiles (up to 32 columns
//! of a band of eight rows) in parallel.

use crate::aov::{AovSample, Aovs};
use crate::film::{Film, PixelEstimate};
use crate::footprint::RayCone;
use crate::integrator::RayCounts;
use crate::math::Ray;
use crate::render::adaptive::SamplingStats;
use crate::render::context::SampleContext;
use crate::render::row_order::{BLOCK_ROWS, row_keys};
use crate::render::{PixelWindow, Progress, RenderError, Rendered};
use crate::sampler::{PixelSampler, SampleKey, pixel_pattern};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Camera rays made at once before they are traced (at least one pixel's worth).
const BATCH_SAMPLES: usize = 16;

/// The width of the tiles a band is traced in, as tall as the band ([`BLOCK_ROWS`]): neighbouring
/// camera rays meet the same nodes of the acceleration structure, which a tile keeps in cache
/// where a row of the whole width does not (the bunny's and the kitchen's camera-rays-only
/// frames 10-12% faster than row by row, 1280x720; tiles 2 to 32 pixels wide measured the same
/// there, and from 32 on the quadric grid, whose pixels are cheap, pays nothing for the tiles'
/// loop: narrower ones made it 4-12% slower).
const TILE: usize = 32;

/// A thread's sampler and the buffers of its batches of camera rays, made once a thread and
/// reused across its tiles.
struct Batches {
    /// The pixels' sample points.
    sampler: PixelSampler,
    /// The current pixel's offsets in the unit pixel.
    offsets: Vec<(f64, f64)>,
    /// The batch's image positions.
    positions: Vec<[f64; 2]>,
    /// The pattern keys of the batch's pixels ([`pixel_pattern`]), with more than one sample a
    /// pixel.
    patterns: Vec<u32>,
    /// The batch's camera rays.
    rays: Vec<Ray>,
    /// The radiance each of them brings.
    radiances: Vec<Vec3>,
}

impl Batches {
    /// The buffers of batches of `spp` samples a pixel.
    fn new(spp: u32) -> Batches {
        let samples = BATCH_SAMPLES.max(spp as usize);
        Batches {
            sampler: PixelSampler::new(spp),
            offsets: vec![(0.0, 0.0); spp as usize],
            positions: Vec::with_capacity(samples),
            patterns: Vec::with_capacity(samples),
            rays: vec![Ray::new(DVec3::ZERO, DVec3::ZERO); samples],
            radiances: vec![Vec3::ZERO; samples],
        }
    }
}

/// One image row of a tile: its pixels and, when a pass is selected, their pass samples.
type TileRow<'a> = (&'a mut [Vec3], Option<&'a mut [AovSample]>);

/// A tile of the window: up to [`TILE`] columns of the rows of one band.
struct Tile<'a> {
    /// The band the tile belongs to, in the order bands are taken up.
    band: usize,
    /// The window's row of the tile's top row.
    first_row: usize,
    /// The window's column of the tile's left column.
    first_column: usize,
    /// The tile's part of each row of its band, top to bottom.
    rows: Vec<TileRow<'a>>,
}

/// `settings.spp` samples in every pixel, by correlated multi-jittered sampling.
pub(super) fn render_uniform(
    context: &SampleContext<'_>,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let (settings, window) = (context.settings, context.window);
    let mut film = Film::new(window.width(), window.height());
    // Pass samples are allocated and computed only when a pass is selected.
    let mut aov_samples = context.aov_buffer();
    let aov_rows = context.aov_rows(&mut aov_samples);
    let (tiles, band_rows) = cut_into_tiles(&mut film, window, aov_rows);
    let totals = Mutex::new(RayCounts::default());
    let cone = context.sample_cone(settings.spp);
    // A band's rows are reported done when its last tile is.
    let tiles_left: Vec<AtomicUsize> = (band_rows.iter())
        .map(|&(_, tiles)| AtomicUsize::new(tiles))
        .collect();
    // The tiles are the parallel work, so a window of a few rows still keeps every thread busy.
    tiles.into_par_iter().for_each_init(
        || Batches::new(settings.spp),
        |batches, tile| {
            if progress.cancelled() {
                return;
            }
            let mut counts = RayCounts::default();
            let y0 = window.y0 + tile.first_row as u32;
            if meets_nothing(context, &tile) {
                for (pixels, _) in tile.rows {
                    fill_background(context, pixels, &mut counts);
                }
            } else {
                for (y, (pixels, aovs)) in (y0..).zip(tile.rows) {
                    let segment = (tile.first_column, pixels, aovs);
                    render_segment(context, y, segment, batches, cone, &mut counts);
                }
            }
            *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            if tiles_left[tile.band].fetch_sub(1, Ordering::AcqRel) == 1 {
                for _ in 0..band_rows[tile.band].0 {
                    progress.row_done();
                }
            }
        },
    );
    if progress.cancelled() {
        return Err(RenderError::Cancelled);
    }
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((
        Rendered {
            film,
            window,
            counts,
            sampling: SamplingStats::uniform(settings.spp),
        },
        context.finish_aovs(aov_samples),
    ))
}

/// The window's pixels (`film`, and the passes' `aov_rows`) cut into tiles: bands of
/// [`BLOCK_ROWS`] rows taken up in interleaved order ([`row_keys`], so that progress counts
/// representative work), each band's tiles left to right. Also each band's rows and tiles.
fn cut_into_tiles<'a>(
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
fn meets_nothing(context: &SampleContext<'_>, tile: &Tile<'_>) -> bool {
    let Some((pixels, None)) = tile.rows.first() else {
        return false;
    };
    let x = context.window.x0 + tile.first_column as u32;
    let y = context.window.y0 + tile.first_row as u32;
    context.meets_nothing((x, y), (pixels.len() as u32, tile.rows.len() as u32))
}

/// Fills `pixels` with what the pixel loop of [`render_segment`] leaves where every sample sees
/// the background (its sum and scale, done once), and counts their camera rays.
fn fill_background(context: &SampleContext<'_>, pixels: &mut [Vec3], counts: &mut RayCounts) {
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

/// Samples the pixels of image row `y` from window column `first_column` on (`pixels`, and
/// their passes `aovs` when selected), counting the rays into `counts`. Pixels are sampled by
/// their position in the full image, so a window's pixels equal the whole render's.
fn render_segment(
    context: &SampleContext<'_>,
    y: u32,
    (first_column, pixels, mut aovs): (usize, &mut [Vec3], Option<&mut [AovSample]>),
    batches: &mut Batches,
    cone: RayCone,
    counts: &mut RayCounts,
) {
    let (settings, window) = (context.settings, context.window);
    let spp = settings.spp;
    let passes = aovs.is_some() || context.selection.variance;
    let Batches {
        sampler,
        offsets,
        positions,
        patterns,
        rays,
        radiances,
    } = batches;
    let batch_pixels = (BATCH_SAMPLES / spp as usize).max(1);
    for (batch, pixels) in pixels.chunks_mut(batch_pixels).enumerate() {
        let first = batch * batch_pixels;
        let x0 = window.x0 + (first_column + first) as u32;
        // The batch's camera rays first: their divisions and square roots do not wait on each
        // other, where made one before each trace they wait in line, and they run packed.
        positions.clear();
        let columns = x0..x0 + pixels.len() as u32;
        if spp == 1 {
            // The one sample of a pixel is its centre (as `PixelSampler::samples` gives it),
            // without the sampler's per-pixel calls.
            positions.extend(columns.map(|x| [x as f64 + 0.5, y as f64 + 0.5]));
        } else {
            patterns.clear();
            for x in columns {
                let pattern = pixel_pattern(x, y, settings.seed);
                patterns.push(pattern);
                sampler.start_pixel(pattern);
                sampler.samples(offsets);
                positions.extend(
                    offsets
                        .iter()
                        .map(|&(dx, dy)| [x as f64 + dx, y as f64 + dy]),
                );
            }
        }
        let rays = &mut rays[..positions.len()];
        context.camera_rays(positions, rays);
        if passes {
            let batch = Batch { x0, y, rays, cone };
            let aovs = aovs.as_deref_mut().map(|aovs| &mut aovs[first..]);
            shade_batch(context, &batch, pixels, aovs, counts);
        } else {
            let radiances = &mut radiances[..rays.len()];
            let seed = settings.seed;
            // A pixel's key is hashed only where a hit's shading asks for it, or kept from above.
            let key = |i: usize| match spp {
                1 => SampleKey {
                    pattern: pixel_pattern(x0 + i as u32, y, seed),
                    index: 0,
                    count: Some(1),
                },
                _ => SampleKey {
                    pattern: patterns[i / spp as usize],
                    index: (i % spp as usize) as u32,
                    count: Some(spp),
                },
            };
            let whitted = &settings.whitted;
            whitted.camera_rays(context.scene, rays, cone, key, counts, radiances);
            // Each pixel the mean of its samples, summed in order as one at a time would.
            let inv_spp = 1.0 / spp as f32;
            for (pixel, samples) in pixels.iter_mut().zip(radiances.chunks_exact(spp as usize)) {
                *pixel = samples.iter().fold(Vec3::ZERO, |sum, &r| sum + r) * inv_spp;
            }
        }
    }
}

/// A batch's camera rays: `spp` a pixel for the pixels of row `y` from column `x0` on, standing
/// for `cone` each.
struct Batch<'r> {
    x0: u32,
    y: u32,
    rays: &'r [Ray],
    cone: RayCone,
}

/// Traces the batch's rays into its `pixels` (the mean of each pixel's samples), the pixels'
/// passes `aovs` when selected, and the running estimates the variance pass needs.
fn shade_batch(
    context: &SampleContext<'_>,
    batch: &Batch<'_>,
    pixels: &mut [Vec3],
    mut aovs: Option<&mut [AovSample]>,
    counts: &mut RayCounts,
) {
    let (settings, selection) = (context.settings, context.selection);
    let spp = settings.spp;
    let inv_spp = 1.0 / spp as f32;
    let mut rays = batch.rays.iter();
    for (i, pixel) in pixels.iter_mut().enumerate() {
        let x = batch.x0 + i as u32;
        // The pixel's key hashed again rather than kept from the batch above: keeping the
        // batch's keys made this loop 13-16% slower (grid, bunny frame), through codegen.
        let pattern = pixel_pattern(x, batch.y, settings.seed);
        let mut aov = aovs.as_deref_mut().map(|aovs| &mut aovs[i]);
        // The variance pass needs the running estimate; the image keeps its f32 sum.
        let mut estimate = selection.variance.then(PixelEstimate::default);
        let mut sum = Vec3::ZERO;
        for (s, ray) in (0..spp).zip(&mut rays) {
            let first_hit = if s == 0 { aov.as_deref_mut() } else { None };
            let key = SampleKey {
                pattern,
                index: s,
                count: Some(spp),
            };
            let radiance = context.trace_ray(ray, batch.cone, key, first_hit, counts);
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
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::aov::AovSelection;
    use crate::camera::{Camera, Projection};
    use crate::geometry::Geometry;
    use crate::material::Material;
    use crate::plane::Plane;
    use crate::quadric::{ClipBox, Quadric, QuadricKind, QuadricSurface};
    use crate::render::adaptive::tests::{white_on_black, white_shapes};
    use crate::render::context::SampleContext;
    use crate::render::{
        NoProgress, PixelWindow, Progress, RenderError, RenderSettings, render_with_aovs,
    };
    use crate::sampler::{SampleKey, pixel_pattern, sample_2d};
    use crate::scene::{Scene, SceneDescription};
    use crate::texture::Texture;
    use crate::{RayCounts, Sphere, Transform};
    use glam::{DVec3, Vec3};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A progress that asks to cancel from its `after`-th question on, and counts the rows
    /// reported done.
    struct CancelAtQuestion {
        after: usize,
        asked: AtomicUsize,
        rows: AtomicUsize,
    }

    impl Progress for CancelAtQuestion {
        fn row_done(&self) {
            self.rows.fetch_add(1, Ordering::Relaxed);
        }

        fn cancelled(&self) -> bool {
            self.asked.fetch_add(1, Ordering::Relaxed) + 1 >= self.after
        }
    }

    /// A cancelled render stops between tiles and reports no row of a band it left unfinished:
    /// on one thread, where each tile asks once, cancelled at the third question the first band of
    /// a four-tile-wide image is left after two tiles; at the sixth, the first band is finished
    /// and reported, the second left after one tile.
    #[test]
    fn a_cancelled_render_stops_between_tiles() {
        let scene = white_on_black(vec![Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            material: 0,
        }]);
        let settings = RenderSettings {
            width: 4 * 32,
            height: 16,
            spp: 2,
            ..RenderSettings::default()
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        for (after, rows) in [(3, 0), (6, 8)] {
            let progress = CancelAtQuestion {
                after,
                asked: AtomicUsize::new(0),
                rows: AtomicUsize::new(0),
            };
            let result =
                pool.install(|| render_with_aovs(&scene, &settings, AovSelection::NONE, &progress));
            assert!(
                matches!(result, Err(RenderError::Cancelled)),
                "after {after}"
            );
            assert_eq!(progress.rows.load(Ordering::Relaxed), rows, "after {after}");
        }
    }

    /// Every pixel of `window` holds the mean of its own samples traced one by one, and every
    /// sample is counted once; returns how many pixels are neither of `flat`'s two colours.
    fn assert_pixels_are_traced(
        scene: &Scene,
        settings: &RenderSettings,
        window: PixelWindow,
        flat: [Vec3; 2],
    ) -> u32 {
        let spp = settings.spp;
        let (rendered, _) =
            render_with_aovs(scene, settings, AovSelection::NONE, &NoProgress).unwrap();
        assert_eq!(
            rendered.counts.camera,
            (window.width() * window.height() * spp) as u64
        );
        let context = SampleContext::new(scene, settings, AovSelection::NONE).unwrap();
        let cone = context.sample_cone(spp);
        let mut counts = RayCounts::default();
        let mut varied = 0;
        for y in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                let pattern = pixel_pattern(x, y, settings.seed);
                let sum: Vec3 = (0..spp)
                    .map(|index| {
                        let key = SampleKey {
                            pattern,
                            index,
                            count: Some(spp),
                        };
                        let offset = sample_2d(index, spp, pattern);
                        context.trace((x, y), offset, cone, key, None, &mut counts)
                    })
                    .sum();
                let expected = sum * (1.0 / spp as f32);
                let got = rendered.film.get(x - window.x0, y - window.y0);
                assert_eq!(got, expected, "pixel ({x}, {y})");
                varied += !flat.contains(&got) as u32;
            }
        }
        varied
    }

    /// Every pixel of a window whose sides are not multiples of a tile or a band holds the mean
    /// of its own samples traced one by one, and every sample is traced once: tiles and bands
    /// cover the window exactly.
    #[test]
    fn tiles_cover_every_pixel_once() {
        let scene = white_on_black(vec![
            Sphere {
                center: DVec3::new(0.3, -0.2, 0.0),
                radius: 0.9,
                material: 0,
            },
            Sphere {
                center: DVec3::new(-1.2, 1.1, 0.0),
                radius: 0.4,
                material: 0,
            },
        ]);
        // 45 columns: a whole tile of 32 and a partial one; 19 rows: two whole bands and a third.
        let window = PixelWindow {
            x0: 5,
            y0: 3,
            x1: 5 + 45,
            y1: 3 + 19,
        };
        // 1 sample a pixel takes the centre without the sampler, 3 the scalar sampler, 8 the
        // eight-wide one where the CPU has AVX2.
        for spp in [1, 3, 8] {
            let settings = RenderSettings {
                width: 64,
                height: 48,
                spp,
                crop: Some(window),
                ..RenderSettings::default()
            };
            // The spheres' edges cross the window: pixels differ, so a misplaced one would show
            // (at one sample a pixel as white pixels among black ones).
            let flat = match spp {
                1 => [Vec3::ZERO; 2],
                _ => [Vec3::ZERO, Vec3::ONE],
            };
            let varied = assert_pixels_are_traced(&scene, &settings, window, flat);
            assert!(varied > 10, "{varied} edge pixels at {spp} spp");
        }
    }

    /// A rough mirror sphere (GGX roughness 0.4) among white spheres outside the view, on black:
    /// its pixels show the spheres through reflection directions drawn from each sample's key.
    fn rough_mirror_among_spheres() -> Scene {
        let mut spheres = vec![Sphere {
            center: DVec3::ZERO,
            radius: 1.6,
            material: 1,
        }];
        spheres.extend(
            [(3.5, 0.0), (-3.5, 0.5), (0.5, 3.0), (-0.5, -3.0)].map(|(x, y)| Sphere {
                center: DVec3::new(x, y, 1.0),
                radius: 1.0,
                material: 0,
            }),
        );
        let camera = Camera {
            from: DVec3::new(0.0, 0.0, 10.0),
            to: DVec3::ZERO,
            up: DVec3::Y,
            projection: Projection::Orthographic { height: 4.0 },
        };
        let white = Material {
            texture: Texture::Constant(Vec3::ONE),
            ambient: 1.0,
            ..Material::default()
        };
        let rough_mirror = Material {
            texture: Texture::Constant(Vec3::splat(0.9)),
            ambient: 0.0,
            diffuse: 0.0,
            specular: 0.0,
            reflectivity: 1.0,
            roughness: 0.4,
            ..Material::default()
        };
        Scene::new(SceneDescription {
            camera,
            background: Vec3::ZERO,
            environment: None,
            materials: vec![white, rough_mirror],
            lights: vec![],
            geometry: Geometry {
                spheres,
                ..Geometry::default()
            },
        })
        .unwrap()
    }

    /// A render whose shading draws from each sample's key (glossy reflection directions) holds
    /// in every pixel the mean of its samples traced one by one with their own keys, at one
    /// sample a pixel (whose key is hashed only where a hit asks for it) and at several (keys
    /// kept from the batch); and the keys matter there: another seed gives another image.
    #[test]
    fn batched_camera_rays_draw_each_samples_own_key() {
        let scene = rough_mirror_among_spheres();
        let window = PixelWindow {
            x0: 0,
            y0: 0,
            x1: 40,
            y1: 30,
        };
        for spp in [1, 2, 3, 8] {
            let settings = |seed| RenderSettings {
                width: 40,
                height: 30,
                spp,
                seed,
                ..RenderSettings::default()
            };
            let varied = assert_pixels_are_traced(&scene, &settings(0), window, [Vec3::ZERO; 2]);
            assert!(varied > 40, "{varied} pixels lit at {spp} spp");
            let image = |seed| {
                let (rendered, _) =
                    render_with_aovs(&scene, &settings(seed), AovSelection::NONE, &NoProgress)
                        .unwrap();
                rendered.film
            };
            let (a, b) = (image(0), image(7));
            let differing = (0..30)
                .flat_map(|y| (0..40).map(move |x| (x, y)))
                .filter(|&(x, y)| a.get(x, y) != b.get(x, y))
                .count();
            assert!(
                differing > 20,
                "{differing} pixels differ between seeds at {spp} spp"
            );
        }
    }

    /// Two spheres and a hyperboloid above a floor, white on a blue-grey background, seen by a
    /// pinhole camera: many of its tiles see nothing, and the floor hides those below its horizon.
    /// With `hidden` more spheres behind the camera (no camera ray meets them, and the scene has
    /// no lights or mirrors), the same image; from 62 of them on, too many shapes for an eye
    /// buffer, and the one box covering the shapes holds the camera, so every sample is traced.
    pub(crate) fn shapes_above_a_floor(hidden: usize) -> (Scene, Vec3) {
        let mut geometry = Geometry {
            spheres: vec![
                Sphere {
                    center: DVec3::new(0.5, 0.2, 0.0),
                    radius: 0.7,
                    material: 0,
                },
                Sphere {
                    center: DVec3::new(-1.6, -0.9, 0.5),
                    radius: 0.3,
                    material: 0,
                },
            ],
            ..Geometry::default()
        };
        geometry.spheres.extend((0..hidden).map(|i| Sphere {
            center: DVec3::new(i as f64 * 0.1, 0.0, 20.0),
            radius: 0.01,
            material: 0,
        }));
        let t = Transform::from_srt(DVec3::splat(0.5), DVec3::ZERO, DVec3::new(-1.0, 1.0, 0.0));
        let surface = QuadricSurface::Canonical {
            kind: QuadricKind::Hyperboloid1,
            a: 1.0,
            b: 1.0,
            c: 1.0,
        };
        geometry
            .quadrics
            .push(Quadric::new(surface, ClipBox::cube(1.0), t.unwrap(), 0).unwrap());
        geometry.planes.push(Plane {
            point: DVec3::new(0.0, -1.5, 0.0),
            normal: DVec3::Y,
            material: 0,
        });
        let camera = Camera {
            from: DVec3::new(0.3, -0.4, 8.0),
            to: DVec3::ZERO,
            up: DVec3::Y,
            projection: Projection::Perspective { vfov_deg: 40.0 },
        };
        let background = Vec3::new(0.2, 0.3, 0.4);
        (white_shapes(geometry, camera, background), background)
    }

    /// Tiles whose rays provably meet nothing ([`shapes_above_a_floor`]) are filled with the
    /// background without tracing, and hold exactly what tracing each sample gives; the scene has
    /// such tiles and others.
    #[test]
    fn empty_tiles_hold_what_tracing_gives() {
        let (scene, background) = shapes_above_a_floor(0);
        let window = PixelWindow {
            x0: 0,
            y0: 0,
            x1: 96,
            y1: 64,
        };
        let settings = RenderSettings {
            width: 96,
            height: 64,
            spp: 3,
            ..RenderSettings::default()
        };
        let varied = assert_pixels_are_traced(&scene, &settings, window, [background, Vec3::ONE]);
        assert!(varied > 10, "{varied} edge pixels");
        let context = SampleContext::new(&scene, &settings, AovSelection::NONE).unwrap();
        // The render's tiles: 3 × 8 of 32 × 8 pixels.
        let tiles: Vec<bool> = (0..8)
            .flat_map(|band| (0..3).map(move |k| (k * 32, band * 8)))
            .map(|(x, y)| context.meets_nothing((x, y), (32, 8)))
            .collect();
        let empty = tiles.iter().filter(|&&e| e).count();
        assert!((3..=21).contains(&empty), "{empty} of {}", tiles.len());
        // The stats count the empty tiles' rays as camera rays not traced.
        let (rendered, _) =
            render_with_aovs(&scene, &settings, AovSelection::NONE, &NoProgress).unwrap();
        assert_eq!(rendered.counts.untraced_camera, empty as u64 * 32 * 8 * 3);
    }
}
