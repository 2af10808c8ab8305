//! Progressive refinement for interactive views: a film whose pixels gain samples in steps, each
//! step cancellable, with the error estimate of adaptive sampling at every step.
//!
//! Every pixel continues its own progressive sequence ([`crate::sampler::progressive_2d`], the one
//! adaptive sampling uses), so a step keeps the stratification of the samples before it, and the
//! image after n samples is the same for any thread count, and whatever steps brought it there
//! except in one way: filtered textures give a step's samples the footprint of the count the step
//! reaches ([`crate::footprint::footprint_scale`]), so a 1-spp preview is filtered over the whole
//! pixel and later steps over smaller shares.

use crate::adaptive::{Calibration, Twin, sample_pixel, sample_twin};
use crate::aov::AovSelection;
use crate::film::{Film, PixelEstimate};
use crate::integrator::RayCounts;
use crate::render::empty_tiles::EmptyTiles;
use crate::render::{MAX_SPP, Progress, RenderError, RenderSettings, SampleContext};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::Mutex;

/// A film refined a few samples per pixel at a time (see the module documentation).
#[derive(Clone, Debug)]
pub struct ProgressiveFilm {
    settings: RenderSettings,
    estimates: Vec<PixelEstimate>,
    /// The pixels with twins, which measure the true error ([`Calibration`]), and their twins:
    /// chosen at the first step that gives the error estimate its samples.
    twins: Option<Vec<((u32, u32), Twin)>>,
    samples: u32,
}

impl ProgressiveFilm {
    /// An empty film for `settings`' resolution and window; `spp` and adaptive sampling are not
    /// used (the caller chooses how far to refine).
    pub fn new(settings: RenderSettings) -> Result<ProgressiveFilm, RenderError> {
        settings.validate()?;
        let window = settings.window();
        Ok(ProgressiveFilm {
            settings,
            estimates: vec![PixelEstimate::default(); (window.width() * window.height()) as usize],
            twins: None,
            samples: 0,
        })
    }

    /// Brings every pixel to `count` samples (nothing when it has them already), in parallel over
    /// rows; returns the rays traced. When `progress` cancels, the film is left partly refined
    /// and must not be shown: the call returns [`RenderError::Cancelled`].
    pub fn refine(
        &mut self,
        scene: &Scene,
        count: u32,
        progress: &dyn Progress,
    ) -> Result<RayCounts, RenderError> {
        if !(1..=MAX_SPP).contains(&count) {
            return Err(RenderError::Spp(count));
        }
        let context = SampleContext::new(scene, &self.settings, AovSelection::NONE)?;
        // Found again at each step: the viewer's camera may have moved.
        let empty_tiles = EmptyTiles::find(&context);
        let context = context.with_empty_tiles(&empty_tiles);
        let window = context.window;
        let totals = Mutex::new(RayCounts::default());
        self.estimates
            .par_chunks_mut(window.width() as usize)
            .enumerate()
            .for_each(|(row_index, row)| {
                if progress.cancelled() {
                    return;
                }
                let y = window.y0 + row_index as u32;
                let mut counts = RayCounts::default();
                for (column, estimate) in row.iter_mut().enumerate() {
                    let at = (window.x0 + column as u32, y);
                    sample_pixel(
                        &context,
                        at,
                        estimate,
                        (None, None),
                        (count, count),
                        &mut counts,
                    );
                }
                *totals.lock().unwrap_or_else(|e| e.into_inner()) += counts;
                progress.row_done();
            });
        if progress.cancelled() {
            return Err(RenderError::Cancelled);
        }
        if self.twins.is_none() && count >= crate::film::ERROR_BATCHES {
            self.twins = Some(self.choose_twins());
        }
        let twin_counts = (self.twins.iter_mut().flatten())
            .par_bridge()
            .map(|(at, twin)| {
                let mut counts = RayCounts::default();
                sample_twin(&context, *at, twin, (count, count), &mut counts);
                counts
            })
            .reduce(RayCounts::default, |mut a, b| {
                a += b;
                a
            });
        if progress.cancelled() {
            return Err(RenderError::Cancelled);
        }
        *totals.lock().unwrap_or_else(|e| e.into_inner()) += twin_counts;
        self.samples = self.samples.max(count);
        Ok(totals.into_inner().unwrap_or_else(|e| e.into_inner()))
    }

    /// The twins of the pixels, chosen by their samples so far.
    fn choose_twins(&self) -> Vec<((u32, u32), Twin)> {
        let window = self.settings.window();
        let candidates: Vec<_> = (self.estimates.par_iter().enumerate())
            .map(|(i, e)| (window.pixel(i), crate::adaptive::is_flat(e)))
            .collect();
        (crate::adaptive::choose_twins(self.settings.seed, &candidates).into_iter())
            .map(|(k, twin)| (candidates[k].0, twin))
            .collect()
    }

    /// Samples every pixel has (0 before the first step).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The settings the film renders.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The image so far: each pixel's mean.
    pub fn film(&self) -> Film {
        let window = self.settings.window();
        Film::of_estimates(window.width(), window.height(), &self.estimates)
    }

    /// The estimated RMSE of the image's display values against the converged image
    /// ([`crate::adaptive::estimated_rmse`]); `None` below 8 samples, where it is too coarse to
    /// report.
    pub fn estimated_error(&self) -> Option<f64> {
        if self.samples < crate::film::ERROR_BATCHES || self.estimates.is_empty() {
            return None;
        }
        let window = self.settings.window();
        let width = window.width() as usize;
        let pairs = self.twins.iter().flatten().map(|((x, y), twin)| {
            let i = (y - window.y0) as usize * width + (x - window.x0) as usize;
            (&self.estimates[i], twin)
        });
        let population = self
            .estimates
            .iter()
            .map(|e| (e.count(), e.squared_error()));
        let calibration = Calibration::fit(pairs, population);
        Some(crate::adaptive::estimated_rmse(
            &self.estimates,
            &calibration,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adaptive::ErrorRule;
    use crate::*;
    use glam::{DVec3, Vec3};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A sphere with a hard edge against the background, so samples matter.
    fn scene() -> Scene {
        Scene::new(SceneDescription {
            camera: Camera::orbit(DVec3::ZERO, 20.0, 10.0, 4.0, 40.0),
            background: Vec3::splat(0.1),
            environment: None,
            materials: vec![Material::default()],
            lights: vec![Light::Directional {
                direction: DVec3::new(-1.0, -0.5, -1.0).normalize(),
                irradiance: Vec3::ONE,
            }],
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

    fn settings() -> RenderSettings {
        RenderSettings {
            width: 40,
            height: 30,
            ..RenderSettings::default()
        }
    }

    #[test]
    fn steps_give_the_image_of_one_refinement_and_of_adaptive_sampling() {
        let scene = scene();
        let mut stepped = ProgressiveFilm::new(settings()).unwrap();
        for count in [1, 2, 5, 16] {
            stepped.refine(&scene, count, &NoProgress).unwrap();
        }
        let mut once = ProgressiveFilm::new(settings()).unwrap();
        once.refine(&scene, 16, &NoProgress).unwrap();
        assert_eq!(stepped.samples(), 16);
        assert_eq!(stepped.film().pixels(), once.film().pixels());
        // An adaptive render that takes 16 samples everywhere walks the same sequences.
        let adaptive = RenderSettings {
            adaptive: Some(
                Adaptive {
                    rule: ErrorRule::Pixel,
                    target_error: 1e-9,
                    ..Adaptive::default()
                }
                .with_min_spp(16)
                .with_max_spp(16),
            ),
            ..settings()
        };
        let reference = render(&scene, &adaptive, &NoProgress).unwrap().film;
        assert_eq!(reference.pixels(), once.film().pixels());
        let error = once.estimated_error().unwrap();
        assert!(error.is_finite() && error > 0.0, "{error}");
        let mut short = ProgressiveFilm::new(settings()).unwrap();
        short.refine(&scene, 4, &NoProgress).unwrap();
        assert_eq!(short.estimated_error(), None);
    }

    /// Cancels after a number of rows.
    struct CancelAfter {
        rows: AtomicUsize,
        limit: usize,
    }

    impl Progress for CancelAfter {
        fn row_done(&self) {
            self.rows.fetch_add(1, Ordering::Relaxed);
        }

        fn cancelled(&self) -> bool {
            self.rows.load(Ordering::Relaxed) >= self.limit
        }
    }

    #[test]
    fn a_cancelled_step_stops_early_and_says_so() {
        let scene = scene();
        let mut film = ProgressiveFilm::new(settings()).unwrap();
        let progress = CancelAfter {
            rows: AtomicUsize::new(0),
            limit: 3,
        };
        let result = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| film.refine(&scene, 8, &progress));
        assert_eq!(result, Err(RenderError::Cancelled));
        assert_eq!(progress.rows.load(Ordering::Relaxed), 3);
        assert_eq!(film.samples(), 0);
        // The plain renderers stop the same way.
        let progress = CancelAfter {
            rows: AtomicUsize::new(0),
            limit: 0,
        };
        assert!(matches!(
            render(&scene, &settings(), &progress),
            Err(RenderError::Cancelled)
        ));
        let adaptive = RenderSettings {
            adaptive: Some(Adaptive::default()),
            ..settings()
        };
        assert!(matches!(
            render(&scene, &adaptive, &progress),
            Err(RenderError::Cancelled)
        ));
        assert_eq!(progress.rows.load(Ordering::Relaxed), 0);
    }

    #[test]
    fn a_camera_in_the_settings_renders_as_if_the_scene_had_it() {
        let moved = Camera::orbit(DVec3::ZERO, -70.0, 35.0, 5.0, 30.0);
        let mut description = scene().into_description();
        description.camera = moved;
        let rebuilt = Scene::new(description).unwrap();
        let through = RenderSettings {
            camera: Some(moved),
            spp: 4,
            ..settings()
        };
        let own = RenderSettings {
            spp: 4,
            ..settings()
        };
        let a = render(&scene(), &through, &NoProgress).unwrap().film;
        let b = render(&rebuilt, &own, &NoProgress).unwrap().film;
        assert_eq!(a.pixels(), b.pixels());
        assert_ne!(
            a.pixels(),
            render(&scene(), &own, &NoProgress).unwrap().film.pixels()
        );
    }

    #[test]
    fn counts_outside_the_limits_are_refused() {
        let mut film = ProgressiveFilm::new(settings()).unwrap();
        assert_eq!(
            film.refine(&scene(), 0, &NoProgress),
            Err(RenderError::Spp(0))
        );
        let bad = RenderSettings {
            width: 0,
            ..settings()
        };
        assert!(ProgressiveFilm::new(bad).is_err());
    }
}
