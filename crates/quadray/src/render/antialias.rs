//! Anti-aliasing by contrast, the classic adaptive anti-aliasing of Whitted (1980) and POV-Ray's
//! `+A`: every pixel takes the render's `spp` samples, and a pixel whose 8-bit display value (the
//! PNG's) differs from one of its eight neighbours' by more than a threshold, in some channel, is
//! rendered again with more samples.
//!
//! Samples go to edges, silhouettes and texture detail, where a Whitted image's error is, with
//! none of the estimates, pilot and audit of error-targeted sampling ([`crate::adaptive`]): it
//! sets no error and reports none, and a feature that falls between a pixel's first samples and
//! leaves its neighbours alike is not found (as in POV-Ray).
//!
//! Every pixel equals the same pixel of a uniform render, at the render's `spp` or at the
//! anti-aliased count ([`Antialias::spp`]), in the image and in every pass (the refined pixel's
//! samples replace its first ones). Which of the two depends only on the first samples of the
//! pixel and of its eight neighbours, so a crop or a tile, whose first samples are taken with a
//! border of one pixel, equals the same pixels of the whole render, for any thread count.

use crate::aov::{AovSample, Aovs};
use crate::colour::encode_srgb8_pixels;
use crate::film::Film;
use crate::integrator::RayCounts;
use crate::limits::MAX_SPP;
use crate::render::adaptive::SamplingStats;
use crate::render::context::SampleContext;
use crate::render::uniform::{Batches, render_segment, render_uniform_parts};
use crate::render::{PixelWindow, Progress, RenderError, RenderSettings, Rendered};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

/// The samples an anti-aliased pixel takes when no count is given: on the quadric grid
/// (480x270, from one sample a pixel at threshold 0.1) 16 brought the display RMSE from 1.06e-2
/// to 1.5e-3 for 1.7 samples a pixel on average, as low as 16 in every pixel gives.
pub const DEFAULT_ANTIALIAS_SPP: u32 = 16;

/// Anti-aliasing by contrast: which pixels are rendered again, and with how many samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Antialias {
    /// The largest difference of 8-bit display value (sRGB-encoded, over 255: in [0, 1]), channel
    /// by channel, a pixel may show against one of its eight neighbours and keep its first
    /// samples.
    pub threshold: f32,
    /// The samples a pixel above the threshold is rendered with instead, more than the render's
    /// `spp`; `None`: [`Antialias::default_spp`] of the render's `spp`, whatever sets it.
    pub spp: Option<u32>,
}

/// Why anti-aliasing settings cannot be rendered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AntialiasError {
    /// A threshold that is not a difference of display values.
    #[error("the threshold must be a number in [0, 1] (a difference of display values), got {0}")]
    Threshold(f32),
    /// A sample count that adds nothing to the render's or passes the limit.
    #[error(
        "anti-aliased pixels take more samples than the render's {base} and at most {MAX_SPP}, got {spp}"
    )]
    Spp {
        /// The count asked for.
        spp: u32,
        /// The render's samples per pixel.
        base: u32,
    },
}

impl Antialias {
    /// The anti-aliased count when none is given, for a render of `base_spp` samples a pixel:
    /// [`DEFAULT_ANTIALIAS_SPP`], or four times `base_spp` from that count on (at most
    /// [`MAX_SPP`]).
    pub fn default_spp(base_spp: u32) -> u32 {
        if base_spp < DEFAULT_ANTIALIAS_SPP {
            DEFAULT_ANTIALIAS_SPP
        } else {
            base_spp.saturating_mul(4).min(MAX_SPP)
        }
    }

    /// The samples of a pixel above the threshold in a render of `base_spp` samples a pixel.
    pub fn samples(&self, base_spp: u32) -> u32 {
        self.spp.unwrap_or_else(|| Antialias::default_spp(base_spp))
    }

    /// Checks the settings against a render of `base_spp` samples per pixel.
    pub fn validate(&self, base_spp: u32) -> Result<(), AntialiasError> {
        if !(0.0..=1.0).contains(&self.threshold) {
            return Err(AntialiasError::Threshold(self.threshold));
        }
        let spp = self.samples(base_spp);
        if spp <= base_spp || spp > MAX_SPP {
            return Err(AntialiasError::Spp {
                spp,
                base: base_spp,
            });
        }
        Ok(())
    }
}

/// The window with a border of one pixel, clipped to the `width` × `height` image.
fn with_border(window: PixelWindow, width: u32, height: u32) -> PixelWindow {
    PixelWindow {
        x0: window.x0.saturating_sub(1),
        y0: window.y0.saturating_sub(1),
        x1: (window.x1 + 1).min(width),
        y1: (window.y1 + 1).min(height),
    }
}

/// Which pixels of a `width`-wide image of 8-bit display codes (RGB, three bytes a pixel) differ
/// from one of their neighbours in it by more than `threshold` of the code range in some channel.
///
/// A pixel differs so from some neighbour exactly when, in some channel, the greatest or the
/// least code of its 3x3 neighbourhood lies more than the bound from its own; those are found by
/// rows (each code's least and greatest with its left and right neighbours') and then by
/// columns, in byte arrays the compiler vectorises.
fn above_threshold(codes: &[u8], width: usize, threshold: f32) -> Vec<bool> {
    // A difference of more than `threshold` · 255 codes, as an integer bound.
    let most = (threshold * 255.0).floor() as u8;
    let row_len = 3 * width;
    let height = codes.len() / row_len;
    let (mut lows, mut highs) = (vec![0u8; codes.len()], vec![0u8; codes.len()]);
    (codes.par_chunks(row_len))
        .zip(lows.par_chunks_mut(row_len))
        .zip(highs.par_chunks_mut(row_len))
        .for_each(|((row, low), high)| {
            for i in 0..row_len {
                // A pixel on the image's edge is its own neighbour beyond it.
                let left = row[if i >= 3 { i - 3 } else { i }];
                let right = row[if i + 3 < row_len { i + 3 } else { i }];
                low[i] = row[i].min(left).min(right);
                high[i] = row[i].max(left).max(right);
            }
        });
    let mut marks = vec![false; width * height];
    marks
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, marks)| {
            let at = |r: usize| r * row_len..(r + 1) * row_len;
            let (above, below) = (at(y.saturating_sub(1)), at((y + 1).min(height - 1)));
            let centre = &codes[at(y)];
            let (l0, l1, l2) = (&lows[above.clone()], &lows[at(y)], &lows[below.clone()]);
            let (h0, h1, h2) = (&highs[above], &highs[at(y)], &highs[below]);
            for (x, mark) in marks.iter_mut().enumerate() {
                *mark = (3 * x..3 * x + 3).any(|i| {
                    let low = l0[i].min(l1[i]).min(l2[i]);
                    let high = h0[i].max(h1[i]).max(h2[i]);
                    centre[i] - low > most || high - centre[i] > most
                });
            }
        });
    marks
}

/// The first samples' progress: their rows as the window's (each row of the window is reported
/// done twice, by the first samples and by the refinement; the border's rows are not reported).
struct FirstPass<'a> {
    progress: &'a dyn Progress,
    /// Rows of the window not yet reported.
    rows_left: AtomicU32,
}

impl Progress for FirstPass<'_> {
    fn row_done(&self) {
        let counted = (self.rows_left).fetch_update(Ordering::Relaxed, Ordering::Relaxed, |left| {
            left.checked_sub(1)
        });
        if counted.is_ok() {
            self.progress.row_done();
        }
    }

    fn cancelled(&self) -> bool {
        self.progress.cancelled()
    }
}

/// A window's first samples: its image and passes (empty when none is selected), which of its
/// pixels are above the threshold (row by row), and the rays they took.
struct FirstSamples {
    film: Film,
    aov_samples: Vec<AovSample>,
    marks: Vec<bool>,
    counts: RayCounts,
}

/// Renders the context's window anti-aliased by contrast (see the module documentation).
pub(super) fn render_antialiased(
    context: &SampleContext<'_>,
    antialias: &Antialias,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let first = first_samples(context, antialias.threshold, progress)?;
    refine(
        context,
        antialias.samples(context.settings.spp),
        first,
        progress,
    )
}

/// The window's first samples, taken with a border of one pixel (clipped to the image) so that
/// each pixel's neighbours are known, and the pixels above `threshold`.
fn first_samples(
    context: &SampleContext<'_>,
    threshold: f32,
    progress: &dyn Progress,
) -> Result<FirstSamples, RenderError> {
    let (settings, window) = (context.settings, context.window);
    let border = with_border(window, settings.width, settings.height);
    let first_pass = FirstPass {
        progress,
        rows_left: AtomicU32::new(window.height()),
    };
    let (film, aovs, counts) = render_uniform_parts(&context.with_window(border), &first_pass)?;
    let (bw, ww) = (border.width() as usize, window.width() as usize);
    let marked = above_threshold(&encode_srgb8_pixels(film.pixels()), bw, threshold);
    let (dx, dy) = (
        (window.x0 - border.x0) as usize,
        (window.y0 - border.y0) as usize,
    );
    // The window's part of each.
    let pixels_of_window = window.width() as usize * window.height() as usize;
    let mut pixels = Vec::with_capacity(pixels_of_window);
    let mut aov_samples = Vec::with_capacity(if aovs.is_empty() { 0 } else { pixels_of_window });
    let mut marks = Vec::with_capacity(pixels_of_window);
    for y in dy..dy + window.height() as usize {
        let row = y * bw + dx..y * bw + dx + ww;
        pixels.extend_from_slice(&film.pixels()[row.clone()]);
        marks.extend_from_slice(&marked[row.clone()]);
        if !aovs.is_empty() {
            aov_samples.extend_from_slice(&aovs[row]);
        }
    }
    let film = Film::from_pixels(window.width(), window.height(), pixels)
        .expect("one pixel a window pixel");
    Ok(FirstSamples {
        film,
        aov_samples,
        marks,
        counts,
    })
}

/// Renders again, with `spp` samples, each pixel of the window above the threshold, in place in
/// its first samples' image and passes.
fn refine(
    context: &SampleContext<'_>,
    spp: u32,
    first: FirstSamples,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let (settings, window) = (context.settings, context.window);
    let FirstSamples {
        mut film,
        mut aov_samples,
        marks,
        counts,
    } = first;
    let refined_settings = RenderSettings { spp, ..*settings };
    let refined = SampleContext::new(context.scene, &refined_settings, context.selection)?
        .with_window(window);
    let cone = refined.sample_cone(spp);
    let ww = window.width() as usize;
    let aov_rows = refined.optional_rows(&mut aov_samples);
    let rows: Vec<_> = (film.pixels_mut().chunks_mut(ww))
        .zip(aov_rows)
        .zip(marks.chunks(ww))
        .enumerate()
        .collect();
    let totals = Mutex::new(counts);
    rows.into_par_iter().for_each_init(
        || Batches::new(spp),
        |batches, (row, ((pixels, mut aovs), marks))| {
            if progress.cancelled() {
                return;
            }
            let mut counts = RayCounts::default();
            let y = window.y0 + row as u32;
            // Each run of marked pixels as one segment of the row.
            let mut column = 0;
            while let Some(start) = (column..ww).find(|&c| marks[c]) {
                column = (start..ww).find(|&c| !marks[c]).unwrap_or(ww);
                let run_aovs = aovs.as_deref_mut().map(|aovs| &mut aovs[start..column]);
                let segment = (start, &mut pixels[start..column], run_aovs);
                render_segment(&refined, y, segment, batches, cone, &mut counts);
            }
            *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
            progress.row_done();
        },
    );
    if progress.cancelled() {
        return Err(RenderError::Cancelled);
    }
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    let refined_pixels = marks.iter().filter(|&&m| m).count() as u64;
    let total = ww as u64 * u64::from(window.height());
    let (base, more) = (settings.spp, spp);
    let sampling = SamplingStats {
        min_spp: if refined_pixels == total { more } else { base },
        max_spp: if refined_pixels > 0 { more } else { base },
        mean_spp: f64::from(base) + f64::from(more - base) * refined_pixels as f64 / total as f64,
        error: None,
    };
    let rendered = Rendered {
        film,
        window,
        counts,
        sampling,
    };
    Ok((rendered, context.finish_aovs(aov_samples)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adaptive::Adaptive;
    use crate::aov::AovSelection;
    use crate::render::adaptive::tests::white_on_black;
    use crate::render::{NoProgress, render_with_aovs};
    use crate::scene::Scene;
    use crate::{Aovs, Sphere};
    use glam::DVec3;

    /// Two white discs of different sizes on black (flat inside, one edge each), 48x48.
    fn discs() -> Scene {
        white_on_black(vec![
            Sphere {
                center: DVec3::new(-0.6, 0.3, 0.0),
                radius: 1.0,
                material: 0,
            },
            Sphere {
                center: DVec3::new(1.3, -1.2, 0.0),
                radius: 0.35,
                material: 0,
            },
        ])
    }

    fn settings(spp: u32, antialias: Option<Antialias>) -> RenderSettings {
        RenderSettings {
            width: 48,
            height: 48,
            spp,
            antialias,
            ..RenderSettings::default()
        }
    }

    /// Every pass that depends on a pixel's samples.
    fn passes() -> AovSelection {
        AovSelection {
            sample_count: true,
            variance: true,
            depth: true,
            ..AovSelection::NONE
        }
    }

    fn run(threads: usize, scene: &Scene, settings: &RenderSettings) -> (Rendered, Aovs) {
        let (rendered, aovs) = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_with_aovs(scene, settings, passes(), &NoProgress))
            .unwrap();
        (rendered, aovs.expect("passes were selected"))
    }

    /// Each pixel is, in the image and every pass, the same pixel of the uniform render at the
    /// first count where its first samples' 8-bit display codes differ from no neighbour's by
    /// more than the threshold (checked here on the uniform render's own pixels, by a float
    /// comparison rather than the renderer's integer bound), and of the uniform render at
    /// the anti-aliased count where they do; the edges then cover the discs' areas better.
    #[test]
    fn every_pixel_is_a_uniform_renders_pixel_chosen_by_its_contrast() {
        let scene = discs();
        let antialias = Antialias {
            threshold: 0.1,
            spp: Some(16),
        };
        let (first, first_aovs) = run(2, &scene, &settings(1, None));
        let (many, many_aovs) = run(2, &scene, &settings(16, None));
        let (aa, aa_aovs) = run(2, &scene, &settings(1, Some(antialias)));
        let display: Vec<[f32; 3]> = (first.film.pixels().iter())
            .map(|p| {
                p.to_array()
                    .map(|c| f32::from(crate::colour::encode_srgb8(c)))
            })
            .collect();
        let mut marked = 0;
        for y in 0..48 {
            for x in 0..48 {
                let differs = (y.max(1) - 1..(y + 2).min(48)).any(|ny| {
                    (x.max(1) - 1..(x + 2).min(48)).any(|nx| {
                        let (a, b) = (display[ny * 48 + nx], display[y * 48 + x]);
                        (0..3).any(|k| (a[k] - b[k]).abs() > 0.1 * 255.0)
                    })
                });
                let (film, aovs) = if differs {
                    (&many.film, &many_aovs)
                } else {
                    (&first.film, &first_aovs)
                };
                let (px, py) = (x as u32, y as u32);
                assert_eq!(aa.film.get(px, py), film.get(px, py), "pixel ({x}, {y})");
                assert_eq!(aa_aovs.get(px, py), aovs.get(px, py), "pixel ({x}, {y})");
                marked += differs as u32;
            }
        }
        // The edges, both sides of them, and nothing else: the discs' rims are about 2π(12 +
        // 4.2) pixels long.
        assert!((150..500).contains(&marked), "{marked} pixels anti-aliased");
        let sampling = aa.sampling;
        assert_eq!((sampling.min_spp, sampling.max_spp), (1, 16));
        let mean = 1.0 + 15.0 * marked as f64 / (48.0 * 48.0);
        assert!((sampling.mean_spp - mean).abs() < 1e-9, "{sampling:?}");
        // The rays of the first samples (of the window and its border: here the image) and of
        // the anti-aliased pixels.
        assert_eq!(aa.counts.camera, 48 * 48 + 16 * u64::from(marked));
        // Coverage: the white area in unit squares (12 pixels a unit) against the discs'.
        let area = |film: &Film| film.pixels().iter().map(|p| f64::from(p.x)).sum::<f64>() / 144.0;
        let exact = std::f64::consts::PI * (1.0 + 0.35 * 0.35);
        let (coarse, fine) = (
            (area(&first.film) - exact).abs(),
            (area(&aa.film) - exact).abs(),
        );
        assert!(
            fine < coarse / 2.0,
            "area error {fine} against {coarse} at one sample"
        );
    }

    /// The same image, passes and rays for any thread count, and a crop equal to the same pixels
    /// of the whole render (its border's first samples give its edges the same neighbours).
    #[test]
    fn antialiased_renders_do_not_depend_on_threads_or_windows() {
        let scene = discs();
        let s = settings(
            2,
            Some(Antialias {
                threshold: 0.05,
                spp: Some(32),
            }),
        );
        let (one, one_aovs) = run(1, &scene, &s);
        let (three, three_aovs) = run(3, &scene, &s);
        assert_eq!(one.film, three.film);
        assert_eq!(one_aovs, three_aovs);
        assert_eq!(one.counts, three.counts);
        for window in [
            PixelWindow {
                x0: 5,
                y0: 17,
                x1: 30,
                y1: 40,
            },
            PixelWindow {
                x0: 0,
                y0: 0,
                x1: 48,
                y1: 1,
            },
            PixelWindow {
                x0: 47,
                y0: 20,
                x1: 48,
                y1: 48,
            },
        ] {
            let crop = RenderSettings {
                crop: Some(window),
                ..s
            };
            let (cropped, cropped_aovs) = run(2, &scene, &crop);
            for y in window.y0..window.y1 {
                for x in window.x0..window.x1 {
                    let (cx, cy) = (x - window.x0, y - window.y0);
                    assert_eq!(cropped.film.get(cx, cy), one.film.get(x, y), "({x}, {y})");
                    assert_eq!(cropped_aovs.get(cx, cy), one_aovs.get(x, y), "({x}, {y})");
                }
            }
        }
    }

    /// A row counter.
    struct Rows(std::sync::atomic::AtomicUsize);

    impl Progress for Rows {
        fn row_done(&self) {
            self.0.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Each row of the window is reported twice, once by its first samples and once by its
    /// refinement, and the border's rows not at all: a progress bar of twice the rows ends full.
    #[test]
    fn each_row_of_the_window_is_reported_twice() {
        let scene = discs();
        let antialias = Some(Antialias {
            threshold: 0.1,
            spp: None,
        });
        let crop = PixelWindow {
            x0: 5,
            y0: 17,
            x1: 30,
            y1: 40,
        };
        for (window, rows) in [(None, 48), (Some(crop), 23)] {
            let settings = RenderSettings {
                crop: window,
                ..settings(1, antialias)
            };
            let counter = Rows(std::sync::atomic::AtomicUsize::new(0));
            render_with_aovs(&scene, &settings, AovSelection::NONE, &counter).unwrap();
            assert_eq!(counter.0.into_inner(), 2 * rows, "{window:?}");
        }
    }

    /// A threshold that is no difference of display values, a count that adds no sample or
    /// passes the limit, and anti-aliasing with adaptive sampling are refused before any work.
    #[test]
    fn bad_settings_are_refused() {
        let scene = discs();
        let refused = |spp: u32, antialias: Antialias| {
            render_with_aovs(
                &scene,
                &settings(spp, Some(antialias)),
                passes(),
                &NoProgress,
            )
            .expect_err("refused")
        };
        for threshold in [f32::NAN, -0.01, 1.5, f32::INFINITY] {
            let e = refused(
                1,
                Antialias {
                    threshold,
                    spp: Some(16),
                },
            );
            assert!(
                matches!(e, RenderError::Antialias(AntialiasError::Threshold(_))),
                "{e}"
            );
        }
        // Counts not above the render's, given or by default (a render of the most samples has
        // no more to give), and past the limit.
        for (base, spp) in [
            (4, Some(4)),
            (4, Some(2)),
            (1, Some(MAX_SPP + 1)),
            (MAX_SPP, None),
        ] {
            let e = refused(
                base,
                Antialias {
                    threshold: 0.1,
                    spp,
                },
            );
            assert!(
                matches!(e, RenderError::Antialias(AntialiasError::Spp { .. })),
                "{e}"
            );
        }
        let both = RenderSettings {
            adaptive: Some(Adaptive::default()),
            ..settings(
                1,
                Some(Antialias {
                    threshold: 0.1,
                    spp: Some(16),
                }),
            )
        };
        assert_eq!(both.validate(), Err(RenderError::AntialiasAndAdaptive));
        // The default follows the render's count, whatever set it.
        let default = Antialias {
            threshold: 0.1,
            spp: None,
        };
        assert_eq!(
            [1, 4, 16, 32, MAX_SPP].map(|base| default.samples(base)),
            [16, 16, 64, 128, MAX_SPP]
        );
        assert_eq!(
            Some(16).map(|n| Antialias {
                spp: Some(n),
                ..default
            }
            .samples(64)),
            Some(16)
        );
    }
}
