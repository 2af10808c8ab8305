//! Error-targeted adaptive sampling: every pixel starts with a few samples, then rounds add
//! samples only to the pixels whose estimated error is still above the target.
//!
//! - **Error**: a pixel's relative standard error of its mean display value
//!   ([`PixelEstimate::relative_error`]: sRGB-encoded, with a floor for near-black pixels).
//! - **Rounds**: round 0 takes [`Adaptive::min_spp`] samples in every pixel; each later round
//!   doubles the count of every pixel still above [`Adaptive::target_error`], up to
//!   [`Adaptive::max_spp`]. A pixel's samples are the prefix of its own progressive sequence
//!   ([`crate::sampler::progressive_2d`]), so samples added later keep the stratification of the
//!   earlier ones, and a power-of-two count is a (0, k, 2)-net in the pixel.
//! - **Determinism**: whether a pixel gets more samples depends only on its own samples, which
//!   depend only on its position and the seed; the image is bit-identical for any thread count, and
//!   a crop window or a tile equals the same pixels of the whole render. A time limit
//!   ([`Adaptive::time_limit`]) trades that for a bound: it stops between rows, and which rows got
//!   their last round then depends on timing.

use crate::aov::Aovs;
use crate::film::{ERROR_BATCHES, Film, PixelEstimate};
use crate::integrator::RayCounts;
use crate::render::{MAX_SPP, Progress, RenderError, Rendered, SampleContext};
use crate::sampler::{pixel_pattern, progressive_2d};
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How an adaptive render decides where to sample and when to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// The relative error every pixel should reach (0: none; every pixel refines to
    /// [`Adaptive::max_spp`] or until the time limit).
    pub target_error: f64,
    /// Samples every pixel takes in the first round: a power of two, at least
    /// [`ERROR_BATCHES`] (the error estimate needs that many).
    pub min_spp: u32,
    /// Samples no pixel exceeds.
    pub max_spp: u32,
    /// Stop refining after this long and keep the image reached (the first round always
    /// completes, so that every pixel has an estimate).
    pub time_limit: Option<Duration>,
}

/// Samples every pixel takes in the first round unless told otherwise.
pub const DEFAULT_MIN_SPP: u32 = 16;
/// The most samples a pixel takes unless told otherwise.
pub const DEFAULT_MAX_SPP: u32 = 1024;

impl Default for Adaptive {
    fn default() -> Self {
        Adaptive {
            target_error: 0.01,
            min_spp: DEFAULT_MIN_SPP,
            max_spp: DEFAULT_MAX_SPP,
            time_limit: None,
        }
    }
}

/// Why adaptive settings cannot be rendered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AdaptiveError {
    /// A target error that is negative or not a number.
    #[error("the target error must be a finite number >= 0, got {0}")]
    TargetError(f64),
    /// A maximum sample count outside 1..=MAX_SPP.
    #[error("the maximum samples per pixel must be in 1..={MAX_SPP}, got {0}")]
    MaxSpp(u32),
    /// A first-round count that is not a power of two from 8 to the maximum.
    #[error(
        "the minimum samples per pixel must be a power of two from {ERROR_BATCHES} to the maximum ({max}), got {min}"
    )]
    MinSpp {
        /// The minimum asked for.
        min: u32,
        /// The maximum it must not exceed.
        max: u32,
    },
    /// A time limit that is zero.
    #[error("the time limit must be more than 0 seconds")]
    TimeLimit,
}

impl Adaptive {
    /// Checks the settings against their limits.
    pub fn validate(&self) -> Result<(), AdaptiveError> {
        if !(self.target_error.is_finite() && self.target_error >= 0.0) {
            return Err(AdaptiveError::TargetError(self.target_error));
        }
        if !(1..=MAX_SPP).contains(&self.max_spp) {
            return Err(AdaptiveError::MaxSpp(self.max_spp));
        }
        if !(ERROR_BATCHES..=self.max_spp).contains(&self.min_spp)
            || !self.min_spp.is_power_of_two()
        {
            return Err(AdaptiveError::MinSpp {
                min: self.min_spp,
                max: self.max_spp,
            });
        }
        if self.time_limit == Some(Duration::ZERO) {
            return Err(AdaptiveError::TimeLimit);
        }
        Ok(())
    }

    /// Whether a pixel with this estimate needs another round.
    fn wants_more(&self, estimate: &PixelEstimate) -> bool {
        // The error is never NaN (infinite when unknown), so `>` is the negation of `<=`.
        estimate.count() < self.max_spp && estimate.relative_error() > self.target_error
    }

    /// The sample count a pixel with `count` samples reaches in its next round.
    fn next_count(&self, count: u32) -> u32 {
        if count == 0 {
            self.min_spp
        } else {
            count.saturating_mul(2).min(self.max_spp)
        }
    }
}

/// Where an adaptive render stands after a round (reported to [`Progress::round_done`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundSummary {
    /// The round just finished, from 0.
    pub round: u32,
    /// Pixels still above the target error and below the maximum count.
    pub active: u64,
    /// Pixels in the render.
    pub pixels: u64,
    /// The largest relative error of any pixel.
    pub worst_error: f64,
    /// The target error.
    pub target_error: f64,
}

/// Why an adaptive render stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// Every pixel reached the target error.
    Converged,
    /// Some pixels reached the maximum sample count above the target.
    MaxSpp,
    /// The time limit ran out with pixels still above the target.
    TimeLimit,
}

/// The error an adaptive render reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// The target error.
    pub target: f64,
    /// The largest relative error of any pixel.
    pub worst: f64,
    /// The mean relative error over the pixels.
    pub mean: f64,
    /// Share of pixels at or below the target, in [0, 1].
    pub met: f64,
    /// Pixels left above the target.
    pub above: u64,
    /// Rounds rendered.
    pub rounds: u32,
    /// Why sampling stopped.
    pub stop: Stop,
}

/// Samples per pixel a render took, and for an adaptive render the error it reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingStats {
    /// Fewest samples in a pixel.
    pub min_spp: u32,
    /// Most samples in a pixel.
    pub max_spp: u32,
    /// Mean samples per pixel.
    pub mean_spp: f64,
    /// The error reached (adaptive renders only).
    pub error: Option<ErrorStats>,
}

impl SamplingStats {
    /// The statistics of `spp` samples in every pixel.
    pub fn uniform(spp: u32) -> SamplingStats {
        SamplingStats {
            min_spp: spp,
            max_spp: spp,
            mean_spp: spp as f64,
            error: None,
        }
    }
}

impl SamplingStats {
    /// The statistics of several windows of one image together, each given with its pixel count
    /// (`None` for no windows).
    pub fn merged(parts: &[(SamplingStats, u64)]) -> Option<SamplingStats> {
        let pixels = parts.iter().map(|(_, n)| *n).sum::<u64>().max(1) as f64;
        let weighted = |f: &dyn Fn(&SamplingStats) -> f64| {
            parts.iter().map(|(s, n)| f(s) * *n as f64).sum::<f64>() / pixels
        };
        let first = parts.first()?.0;
        let error = first.error.map(|e| {
            let errors = || parts.iter().filter_map(|(s, _)| s.error);
            ErrorStats {
                target: e.target,
                worst: errors().map(|e| e.worst).fold(0.0, f64::max),
                mean: weighted(&|s| s.error.map_or(0.0, |e| e.mean)),
                met: weighted(&|s| s.error.map_or(0.0, |e| e.met)),
                above: errors().map(|e| e.above).sum(),
                rounds: errors().map(|e| e.rounds).max().unwrap_or(0),
                // The stop of the window that fell shortest: a time limit over a maximum count
                // over convergence.
                stop: errors()
                    .map(|e| e.stop)
                    .max_by_key(|s| match s {
                        Stop::Converged => 0,
                        Stop::MaxSpp => 1,
                        Stop::TimeLimit => 2,
                    })
                    .unwrap_or(Stop::Converged),
            }
        });
        Some(SamplingStats {
            min_spp: parts.iter().map(|(s, _)| s.min_spp).min()?,
            max_spp: parts.iter().map(|(s, _)| s.max_spp).max()?,
            mean_spp: weighted(&|s| s.mean_spp),
            error,
        })
    }

    /// A short description for a stats line: `16 spp`, or for an adaptive render the mean and
    /// range of the counts and the error reached.
    pub fn summary(&self) -> String {
        let Some(e) = self.error else {
            return format!("{} spp", self.min_spp);
        };
        let stop = match e.stop {
            Stop::Converged => "every pixel at the target".to_string(),
            Stop::MaxSpp => format!(
                "{} pixels ({:.2}%) stopped at max spp {} above the target",
                e.above,
                100.0 * (1.0 - e.met),
                self.max_spp
            ),
            Stop::TimeLimit => format!(
                "the time limit ran out with {} pixels ({:.2}%) above the target",
                e.above,
                100.0 * (1.0 - e.met)
            ),
        };
        format!(
            "adaptive, {:.1} spp mean ({}..{}) in {} rounds, error target {}, worst {:.3}, mean {:.4}: {stop}",
            self.mean_spp, self.min_spp, self.max_spp, e.rounds, e.target, e.worst, e.mean
        )
    }
}

/// Renders the context's window adaptively (see the module documentation).
pub(crate) fn render_adaptive(
    context: &SampleContext<'_>,
    adaptive: &Adaptive,
    progress: &dyn Progress,
) -> Result<(Rendered, Option<Aovs>), RenderError> {
    let started = Instant::now();
    let (settings, window) = (context.settings, context.window);
    let ww = window.width() as usize;
    let pixels = ww * window.height() as usize;
    let mut estimates = vec![PixelEstimate::default(); pixels];
    let mut aov_samples = context.aov_buffer();
    let totals = Mutex::new(RayCounts::default());
    let timed_out = AtomicBool::new(false);
    let out_of_time = || {
        adaptive
            .time_limit
            .is_some_and(|limit| started.elapsed() >= limit)
    };
    let mut round = 0u32;
    loop {
        // Surface passes come from each pixel's first sample, taken in round 0.
        let aov_rows = if round == 0 {
            context.aov_rows(&mut aov_samples)
        } else {
            (0..window.height()).map(|_| None).collect()
        };
        estimates
            .par_chunks_mut(ww)
            .zip(aov_rows)
            .enumerate()
            .for_each(|(row_index, (row, mut aov_row))| {
                if round > 0 && out_of_time() {
                    timed_out.store(true, Ordering::Relaxed);
                    progress.row_done();
                    return;
                }
                let y = window.y0 + row_index as u32;
                let mut counts = RayCounts::default();
                for (column, estimate) in row.iter_mut().enumerate() {
                    if round > 0 && !adaptive.wants_more(estimate) {
                        continue;
                    }
                    let x = window.x0 + column as u32;
                    let pattern = pixel_pattern(x, y, settings.seed);
                    for index in estimate.count()..adaptive.next_count(estimate.count()) {
                        let first_hit = match aov_row.as_deref_mut() {
                            Some(aovs) if index == 0 => Some(&mut aovs[column]),
                            _ => None,
                        };
                        let offset = progressive_2d(index, pattern);
                        estimate.add(context.trace((x, y), offset, first_hit, &mut counts));
                    }
                }
                *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
                progress.row_done();
            });
        let summary = RoundSummary {
            round,
            active: estimates.iter().filter(|e| adaptive.wants_more(e)).count() as u64,
            pixels: pixels as u64,
            worst_error: worst_error(&estimates),
            target_error: adaptive.target_error,
        };
        progress.round_done(&summary);
        round += 1;
        if summary.active == 0 || timed_out.load(Ordering::Relaxed) || out_of_time() {
            break;
        }
    }

    let film = Film::from_pixels(
        window.width(),
        window.height(),
        estimates.iter().map(PixelEstimate::mean).collect(),
    )
    .expect("one estimate per pixel");
    for (aov, estimate) in aov_samples.iter_mut().zip(&estimates) {
        aov.fill_sampling(
            context.selection,
            estimate.count(),
            Some(estimate.variance()),
        );
    }
    let sampling = sampling_stats(&estimates, adaptive, round, timed_out.into_inner());
    let counts = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((
        Rendered {
            film,
            window,
            counts,
            sampling,
        },
        context.finish_aovs(aov_samples),
    ))
}

/// The largest relative error among `estimates` (0 for none).
fn worst_error(estimates: &[PixelEstimate]) -> f64 {
    estimates
        .iter()
        .map(PixelEstimate::relative_error)
        .fold(0.0, f64::max)
}

/// The sample counts and error reached by a finished adaptive render of `rounds` rounds.
fn sampling_stats(
    estimates: &[PixelEstimate],
    adaptive: &Adaptive,
    rounds: u32,
    timed_out: bool,
) -> SamplingStats {
    let n = estimates.len().max(1) as f64;
    let counts = estimates.iter().map(PixelEstimate::count);
    let met = estimates
        .iter()
        .filter(|e| e.relative_error() <= adaptive.target_error)
        .count();
    let stop = if met == estimates.len() {
        Stop::Converged
    } else if timed_out || estimates.iter().any(|e| adaptive.wants_more(e)) {
        Stop::TimeLimit
    } else {
        Stop::MaxSpp
    };
    SamplingStats {
        min_spp: counts.clone().min().unwrap_or(0),
        max_spp: counts.clone().max().unwrap_or(0),
        mean_spp: counts.map(|c| c as f64).sum::<f64>() / n,
        error: Some(ErrorStats {
            target: adaptive.target_error,
            worst: worst_error(estimates),
            mean: estimates
                .iter()
                .map(PixelEstimate::relative_error)
                .sum::<f64>()
                / n,
            met: met as f64 / n,
            above: (estimates.len() - met) as u64,
            rounds,
            stop,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aov::AovSelection;
    use crate::render::{NoProgress, PixelWindow, RenderSettings, render_with_aovs};
    use crate::*;
    use glam::{DVec3, Vec3};

    /// A white unit disc (a sphere without lights shows its ambient colour, flat) on a black
    /// background, seen from above by an orthographic camera 4 units tall: flat regions and one
    /// circular edge whose position is known.
    fn disc() -> Scene {
        Scene::new(SceneDescription {
            camera: Camera {
                from: DVec3::new(0.0, 0.0, 10.0),
                to: DVec3::ZERO,
                up: DVec3::Y,
                projection: Projection::Orthographic { height: 4.0 },
            },
            background: Vec3::ZERO,
            materials: vec![Material {
                texture: Texture::Constant(Vec3::ONE),
                ambient: 1.0,
                ..Material::default()
            }],
            lights: vec![],
            geometry: Geometry {
                spheres: vec![Sphere {
                    center: DVec3::ZERO,
                    radius: 1.0,
                    material: 0,
                }],
                ..Geometry::default()
            },
        })
        .unwrap()
    }

    fn settings(adaptive: Adaptive) -> RenderSettings {
        RenderSettings {
            width: 48,
            height: 48,
            adaptive: Some(adaptive),
            ..RenderSettings::default()
        }
    }

    fn counts_pass() -> AovSelection {
        AovSelection {
            sample_count: true,
            variance: true,
            ..AovSelection::NONE
        }
    }

    /// The mean of a pixel's progressive samples is an unbiased estimate of its coverage: over
    /// many pixels (independent scrambles) of a pixel that is 1 left of x = t and 0 right of it,
    /// the estimates average to t, and the variance estimate to about t(1 - t) at one sample
    /// per stratum's worth of samples.
    #[test]
    fn the_estimator_is_unbiased_on_constant_and_two_value_pixels() {
        let trials = 4000u32;
        for (t, n) in [(0.3, 2u32), (0.62, 8), (0.5, 13)] {
            let mut mean_of_means = 0.0;
            for p in 0..trials {
                let pattern = pixel_pattern(p, 11, 3);
                let mut e = PixelEstimate::default();
                for i in 0..n {
                    let (x, _) = progressive_2d(i, pattern);
                    e.add(Vec3::splat(if x < t { 1.0 } else { 0.0 }));
                }
                mean_of_means += e.mean().x as f64 / trials as f64;
            }
            // The standard deviation of one pixel's mean is at most 1/(2√n); of the average over
            // the trials, that over √trials: 5 of those is a loose but falsifiable bound.
            let bound = 5.0 * 0.5 / (n as f64).sqrt() / (trials as f64).sqrt();
            assert!(
                (mean_of_means - t).abs() < bound,
                "t {t}, n {n}: {mean_of_means}"
            );
        }
        // A constant pixel: every estimate is the constant, with zero variance and error.
        let mut e = PixelEstimate::default();
        for i in 0..16 {
            let _ = progressive_2d(i, 99);
            e.add(Vec3::new(0.25, 0.5, 0.75));
        }
        assert_eq!(e.mean(), Vec3::new(0.25, 0.5, 0.75));
        assert_eq!(e.relative_error(), 0.0);
    }

    #[test]
    fn edges_get_more_samples_than_flat_regions() {
        let adaptive = Adaptive {
            target_error: 0.05,
            min_spp: 8,
            max_spp: 4096,
            time_limit: None,
        };
        let (rendered, aovs) =
            render_with_aovs(&disc(), &settings(adaptive), counts_pass(), &NoProgress).unwrap();
        let aovs = aovs.unwrap();
        // Pixel centres in world units: 4/48 per pixel, the image centre at (24, 24).
        let radius_at = |x: u32, y: u32| {
            let (u, v) = (
                (x as f64 + 0.5 - 24.0) / 12.0,
                (y as f64 + 0.5 - 24.0) / 12.0,
            );
            (u * u + v * v).sqrt()
        };
        let half_diagonal = 0.5 * 2f64.sqrt() / 12.0;
        let (mut edge, mut flat) = (Vec::new(), Vec::new());
        for y in 0..48 {
            for x in 0..48 {
                let r = radius_at(x, y);
                let count = aovs.get(x, y).sample_count;
                if (r - 1.0).abs() < half_diagonal * 0.5 {
                    edge.push(count);
                } else if (r - 1.0).abs() > 2.0 * half_diagonal {
                    flat.push(count);
                }
            }
        }
        // Flat pixels stop after the first round; pixels the edge cuts refine.
        assert!(flat.iter().all(|&c| c == 8), "{flat:?}");
        let edge_mean = edge.iter().sum::<u32>() as f64 / edge.len() as f64;
        assert!(
            edge_mean > 32.0,
            "{edge_mean} on {} edge pixels",
            edge.len()
        );
        let sampling = rendered.sampling;
        assert_eq!(sampling.min_spp, 8);
        assert!(sampling.max_spp >= 64, "{sampling:?}");
        let error = sampling.error.unwrap();
        assert_eq!(error.stop, Stop::Converged);
        assert!(error.worst <= 0.05);
        // The disc's area: π of the 16 square units in view.
        let covered = rendered
            .film
            .pixels()
            .iter()
            .map(|p| p.x as f64)
            .sum::<f64>();
        let area = covered * 16.0 / (48.0 * 48.0);
        assert!((area - std::f64::consts::PI).abs() < 0.01, "{area}");
    }

    #[test]
    fn adaptive_renders_do_not_depend_on_threads_or_windows() {
        let adaptive = Adaptive {
            target_error: 0.02,
            min_spp: 8,
            max_spp: 128,
            time_limit: None,
        };
        let s = settings(adaptive);
        let run = |threads: usize, settings: RenderSettings| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render_with_aovs(&disc(), &settings, counts_pass(), &NoProgress))
                .unwrap()
        };
        let (one, one_aovs) = run(1, s);
        let (three, three_aovs) = run(3, s);
        assert_eq!(one.film, three.film);
        assert_eq!(one_aovs, three_aovs);
        assert_eq!(one.counts, three.counts);
        let window = PixelWindow {
            x0: 5,
            y0: 17,
            x1: 30,
            y1: 40,
        };
        let (cropped, _) = run(
            2,
            RenderSettings {
                crop: Some(window),
                ..s
            },
        );
        for y in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                assert_eq!(cropped.film.get(x - 5, y - 17), one.film.get(x, y));
            }
        }
    }

    #[test]
    fn an_impossible_target_stops_at_the_maximum() {
        let adaptive = Adaptive {
            target_error: 1e-9,
            min_spp: 8,
            max_spp: 64,
            time_limit: None,
        };
        let (rendered, _) = render_with_aovs(
            &disc(),
            &settings(adaptive),
            AovSelection::NONE,
            &NoProgress,
        )
        .unwrap();
        let error = rendered.sampling.error.unwrap();
        assert_eq!(error.stop, Stop::MaxSpp);
        assert_eq!(rendered.sampling.max_spp, 64);
        assert!(error.met < 1.0 && error.met > 0.5, "{error:?}");
        // 8, 16, 32, 64.
        assert_eq!(error.rounds, 4);
    }

    #[test]
    fn a_time_limit_keeps_the_first_round() {
        let adaptive = Adaptive {
            target_error: 0.0,
            min_spp: 8,
            max_spp: MAX_SPP,
            time_limit: Some(Duration::from_nanos(1)),
        };
        let (rendered, _) = render_with_aovs(
            &disc(),
            &settings(adaptive),
            AovSelection::NONE,
            &NoProgress,
        )
        .unwrap();
        assert_eq!(rendered.sampling.min_spp, 8);
        assert_eq!(rendered.sampling.error.unwrap().stop, Stop::TimeLimit);
    }

    #[test]
    fn bad_settings_are_refused() {
        let bad = |a: Adaptive| {
            assert!(matches!(
                settings(a).validate(),
                Err(RenderError::Adaptive(_))
            ))
        };
        let ok = Adaptive::default();
        bad(Adaptive {
            target_error: -0.1,
            ..ok
        });
        bad(Adaptive {
            target_error: f64::NAN,
            ..ok
        });
        bad(Adaptive { max_spp: 0, ..ok });
        bad(Adaptive {
            max_spp: MAX_SPP + 1,
            ..ok
        });
        bad(Adaptive { min_spp: 1, ..ok });
        bad(Adaptive { min_spp: 4, ..ok });
        bad(Adaptive { min_spp: 24, ..ok });
        bad(Adaptive {
            min_spp: 64,
            max_spp: 32,
            ..ok
        });
        bad(Adaptive {
            time_limit: Some(Duration::ZERO),
            ..ok
        });
        assert_eq!(settings(ok).validate(), Ok(()));
    }
}
