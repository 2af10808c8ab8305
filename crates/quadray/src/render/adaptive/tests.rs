//! Tests of adaptive sampling: the estimator, where samples go, determinism and the limits.

use super::*;
use crate::aov::AovSelection;
use crate::render::MAX_SPP;
use crate::render::{NoProgress, PixelWindow, RenderSettings, render_with_aovs};
use crate::*;
use glam::{DVec3, Vec3};
use std::time::Duration;

/// A white unit disc (a sphere without lights shows its ambient colour, flat) on a black
/// background, seen from above by an orthographic camera 4 units tall: flat regions and one
/// circular edge whose position is known.
pub(super) fn disc() -> Scene {
    white_on_black(vec![Sphere {
        center: DVec3::ZERO,
        radius: 1.0,
        material: 0,
    }])
}

/// White `spheres` (flat, ambient only) on a black background, seen from above by an
/// orthographic camera 4 units tall centred on the origin (48 pixels: 12 to a unit).
pub(crate) fn white_on_black(spheres: Vec<Sphere>) -> Scene {
    white_shapes_on_black(Geometry {
        spheres,
        ..Geometry::default()
    })
}

/// The shapes of `geometry`, white, as [`white_on_black`] shows spheres.
pub(crate) fn white_shapes_on_black(geometry: Geometry) -> Scene {
    white_shapes(geometry, top_down_camera(), Vec3::ZERO)
}

/// An orthographic camera 4 units tall looking down the z axis at the origin.
pub(crate) fn top_down_camera() -> Camera {
    Camera {
        from: DVec3::new(0.0, 0.0, 10.0),
        to: DVec3::ZERO,
        up: DVec3::Y,
        projection: Projection::Orthographic { height: 4.0 },
    }
}

/// The shapes of `geometry`, white (flat, ambient only), on `background`, seen by `camera`.
pub(crate) fn white_shapes(geometry: Geometry, camera: Camera, background: Vec3) -> Scene {
    Scene::new(SceneDescription {
        camera,
        background,
        environment: None,
        materials: vec![Material {
            texture: Texture::Constant(Vec3::ONE),
            ambient: 1.0,
            ..Material::default()
        }],
        lights: vec![],
        geometry,
    })
    .unwrap()
}

pub(super) fn settings(adaptive: Adaptive) -> RenderSettings {
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
        rule: ErrorRule::Pixel,
        spp_budget: None,
    };
    let (rendered, aovs) =
        render_with_aovs(&disc(), &settings(adaptive), counts_pass(), &NoProgress).unwrap();
    let (edge, flat) = edge_and_flat_counts(&aovs.unwrap());
    // Flat pixels away from the edge stop after the first round; pixels the edge cuts refine.
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
    assert!(error.pixels.unwrap().worst <= 0.05);
    let area = disc_area(&rendered.film);
    assert!((area - std::f64::consts::PI).abs() < 0.01, "{area}");
}

/// The sample counts of the disc's pixels that its edge cuts (centres within a quarter of a
/// pixel's diagonal of it), and of those beyond the pixels it cuts and their neighbours.
fn edge_and_flat_counts(aovs: &Aovs) -> (Vec<u32>, Vec<u32>) {
    // Pixel centres in world units: 4/48 per pixel, the image centre at (24, 24).
    let radius_at = |x: u32, y: u32| {
        let (u, v) = (
            (x as f64 + 0.5 - 24.0) / 12.0,
            (y as f64 + 0.5 - 24.0) / 12.0,
        );
        (u * u + v * v).sqrt()
    };
    let pixel_diagonal = 2f64.sqrt() / 12.0;
    let half_diagonal = 0.5 * pixel_diagonal;
    let (mut edge, mut flat) = (Vec::new(), Vec::new());
    for y in 0..48 {
        for x in 0..48 {
            let distance = (radius_at(x, y) - 1.0).abs();
            let count = aovs.get(x, y).sample_count;
            if distance < half_diagonal * 0.5 {
                edge.push(count);
            } else if distance > half_diagonal + 2.0 * pixel_diagonal {
                flat.push(count);
            }
        }
    }
    (edge, flat)
}

/// The disc's area measured on the image: its coverage times the 16 square units in view (π when
/// the edge pixels are right).
fn disc_area(film: &Film) -> f64 {
    let covered = film.pixels().iter().map(|p| p.x as f64).sum::<f64>();
    covered * 16.0 / (48.0 * 48.0)
}

/// A preview that starts at 2 samples leaves the flat pixels at 2 and still finds the edge from
/// its coarse first estimates (the neighbour rounds catch pixels whose two samples agreed): the
/// disc's area comes out within what a few missed edge pixels could change.
#[test]
fn a_preview_from_two_samples_stops_flat_pixels_at_two_and_refines_the_edge() {
    let adaptive = Adaptive {
        target_error: 0.05,
        min_spp: 2,
        max_spp: 256,
        time_limit: None,
        rule: ErrorRule::Pixel,
        spp_budget: None,
    };
    let (rendered, aovs) =
        render_with_aovs(&disc(), &settings(adaptive), counts_pass(), &NoProgress).unwrap();
    let (edge, flat) = edge_and_flat_counts(&aovs.unwrap());
    assert!(flat.iter().all(|&c| c == 2), "{flat:?}");
    let refined = edge.iter().filter(|&&c| c >= 16).count();
    assert!(
        refined as f64 >= 0.9 * edge.len() as f64,
        "{refined} of {} edge pixels refined: {edge:?}",
        edge.len()
    );
    assert_eq!(rendered.sampling.min_spp, 2);
    let area = disc_area(&rendered.film);
    assert!((area - std::f64::consts::PI).abs() < 0.02, "{area}");
}

/// Both rules, the image rule's pilot included: the same image for any thread count and window.
#[test]
fn adaptive_renders_do_not_depend_on_threads_or_windows() {
    for (rule, target_error) in [(ErrorRule::Pixel, 0.02), (ErrorRule::Image, 0.002)] {
        renders_do_not_depend_on_threads_or_windows(Adaptive {
            target_error,
            min_spp: 8,
            max_spp: 128,
            time_limit: None,
            rule,
            spp_budget: None,
        });
    }
}

fn renders_do_not_depend_on_threads_or_windows(adaptive: Adaptive) {
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

/// Round k samples the pixels above the target and, in the first rounds, their neighbours, and
/// brings them all to min_spp·2^k samples.
#[test]
fn a_round_samples_pixels_above_the_target_and_their_neighbours() {
    let adaptive = Adaptive {
        target_error: 0.1,
        min_spp: 8,
        max_spp: 1024,
        time_limit: None,
        rule: ErrorRule::Pixel,
        spp_budget: None,
    };
    use pixel_rule::{refinement_rounds, round_count};
    assert_eq!(refinement_rounds(&adaptive), 7);
    assert_eq!(round_count(&adaptive, 0), 8);
    assert_eq!(round_count(&adaptive, 3), 64);
    assert_eq!(round_count(&adaptive, 7), 1024);
    assert_eq!(round_count(&adaptive, 40), 1024);
    assert_eq!(refinement_rounds(&adaptive.with_max_spp(100)), 4);
    assert_eq!(round_count(&adaptive.with_max_spp(100), 4), 100);
    // A 5x4 image of pixels with 8 samples, one of them (2, 1) above the target.
    let (width, height) = (5, 4);
    let mut sampled = PixelEstimate::default();
    for _ in 0..8 {
        sampled.add(Vec3::splat(0.5));
    }
    let estimates = vec![sampled; width * height];
    let mut errors = vec![0.0; width * height];
    errors[width + 2] = 0.5;
    let squared: Vec<f64> = estimates.iter().map(|e| e.squared_error()).collect();
    let selected = |refine: &[bool]| {
        (0..height)
            .map(|y| {
                (0..width)
                    .map(|x| if refine[y * width + x] { 'x' } else { '.' })
                    .collect::<String>()
            })
            .collect::<Vec<_>>()
    };
    let refine = pixel_rule::select(&adaptive, 1, &estimates, (&errors, &squared), width);
    assert_eq!(selected(&refine), [".xxx.", ".xxx.", ".xxx.", "....."]);
    // After the neighbour rounds, only the pixel itself.
    let refine = pixel_rule::select(
        &adaptive,
        NEIGHBOUR_ROUNDS + 1,
        &estimates,
        (&errors, &squared),
        width,
    );
    assert_eq!(selected(&refine), [".....", "..x..", ".....", "....."]);
    // Below the target but not below the first round's margin: refined (with its neighbours)
    // after the first round only.
    errors[width + 2] = 0.1 * (1.0 + FIRST_ROUND_MARGIN) / 2.0;
    let refine = pixel_rule::select(&adaptive, 1, &estimates, (&errors, &squared), width);
    assert_eq!(selected(&refine), [".xxx.", ".xxx.", ".xxx.", "....."]);
    let refine = pixel_rule::select(&adaptive, 2, &estimates, (&errors, &squared), width);
    assert!(!refine.contains(&true));
    errors[width + 2] = 0.1 * FIRST_ROUND_MARGIN * 0.9;
    let refine = pixel_rule::select(&adaptive, 1, &estimates, (&errors, &squared), width);
    assert!(!refine.contains(&true));
    // A pixel at the maximum, above the target again, is not sampled again, nor are its
    // neighbours for its sake.
    errors[width + 2] = 0.5;
    let at_max = Adaptive {
        max_spp: 8,
        ..adaptive
    };
    let refine = pixel_rule::select(&at_max, 1, &estimates, (&errors, &squared), width);
    assert!(!refine.contains(&true));
}

/// Tiles of an image rendered apart equal the whole render, though a pixel's samples depend on
/// its neighbours': each tile is sampled with a border.
#[test]
fn adaptive_tiles_equal_the_whole_render() {
    for (rule, target_error) in [(ErrorRule::Pixel, 0.01), (ErrorRule::Image, 0.002)] {
        tiles_equal_the_whole_render(Adaptive {
            target_error,
            min_spp: 8,
            max_spp: 256,
            time_limit: None,
            rule,
            spp_budget: None,
        });
    }
}

fn tiles_equal_the_whole_render(adaptive: Adaptive) {
    let s = settings(adaptive);
    let (whole, whole_aovs) = render_with_aovs(&disc(), &s, counts_pass(), &NoProgress).unwrap();
    let whole_aovs = whole_aovs.unwrap();
    // Four tiles meeting at (16, 16), next to pixel (15, 15), which the disc's edge cuts (its
    // centre lies on the edge): (16, 16) is flat inside the disc and refines only as (15, 15)'s
    // neighbour, which a tile without a border cannot see. A flat pixel's value does not depend on
    // its count, so the sample counts are compared too.
    for (x0, x1, y0, y1) in [
        (0, 16, 0, 16),
        (16, 48, 0, 16),
        (0, 16, 16, 48),
        (16, 48, 16, 48),
    ] {
        let window = PixelWindow { x0, y0, x1, y1 };
        let (tile, tile_aovs) = render_with_aovs(
            &disc(),
            &RenderSettings {
                crop: Some(window),
                ..s
            },
            counts_pass(),
            &NoProgress,
        )
        .unwrap();
        let tile_aovs = tile_aovs.unwrap();
        for y in y0..y1 {
            for x in x0..x1 {
                let (tx, ty) = (x - x0, y - y0);
                assert_eq!(tile.film.get(tx, ty), whole.film.get(x, y), "({x}, {y})");
                assert_eq!(
                    tile_aovs.get(tx, ty).sample_count,
                    whole_aovs.get(x, y).sample_count,
                    "({x}, {y})"
                );
            }
        }
    }
    if adaptive.rule == ErrorRule::Pixel {
        assert!(whole_aovs.get(16, 16).sample_count > 8);
        assert_eq!(whole_aovs.get(20, 20).sample_count, 8);
    }
    assert!(whole.sampling.max_spp > 8, "{:?}", whole.sampling);
}

#[test]
fn an_impossible_target_stops_at_the_maximum() {
    let adaptive = Adaptive {
        target_error: 1e-9,
        min_spp: 8,
        max_spp: 64,
        time_limit: None,
        rule: ErrorRule::Pixel,
        spp_budget: None,
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
    let met = error.pixels.unwrap().met;
    assert!(met < 1.0 && met > 0.5, "{error:?}");
    // 8, 16, 32, 64: round k brings its pixels to 8·2^k, so no pixel needs a fifth.
    assert_eq!(error.rounds, 4);
}

#[test]
fn a_time_limit_keeps_the_first_round() {
    let adaptive = Adaptive {
        target_error: 0.0,
        min_spp: 8,
        max_spp: MAX_SPP,
        time_limit: Some(Duration::from_nanos(1)),
        rule: ErrorRule::Pixel,
        spp_budget: None,
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
    // One sample a pixel leaves no error to estimate: not an adaptive render.
    assert!(matches!(
        ok.with_max_spp(1).validate(),
        Err(AdaptiveError::MaxSpp(1))
    ));
    bad(Adaptive {
        max_spp: MAX_SPP + 1,
        ..ok
    });
    bad(Adaptive { min_spp: 1, ..ok });
    bad(Adaptive { min_spp: 3, ..ok });
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
    assert_eq!(settings(ok.with_min_spp(2)).validate(), Ok(()));
}

/// The variance pass of an adaptive render is every pixel's sample variance over all the
/// samples it took, bit for bit: each pixel of a whole render and of a crop (its border, the
/// pilot's pixels copied in, background pixels whose samples are added without tracing), under
/// both rules, equals the moment of its sequence's samples to its count traced one by one (not
/// through the rounds' batches, so a batch that misses the moment fails it).
#[test]
fn the_variance_pass_holds_every_samples_deviation() {
    let scene = disc();
    let crop = PixelWindow {
        x0: 7,
        y0: 3,
        x1: 41,
        y1: 30,
    };
    for rule in [ErrorRule::Image, ErrorRule::Pixel] {
        let adaptive = Adaptive {
            target_error: if rule == ErrorRule::Image {
                0.002
            } else {
                0.02
            },
            rule,
            max_spp: 256,
            ..Adaptive::default()
        };
        for window in [None, Some(crop)] {
            let s = RenderSettings {
                crop: window,
                ..settings(adaptive)
            };
            let (rendered, aovs) =
                render_with_aovs(&scene, &s, counts_pass(), &NoProgress).unwrap();
            let aovs = aovs.unwrap();
            let context = SampleContext::new(&scene, &s, AovSelection::NONE).unwrap();
            let w = rendered.window;
            let mut refined = 0;
            for y in w.y0..w.y1 {
                for x in w.x0..w.x1 {
                    let pass = aovs.get(x - w.x0, y - w.y0);
                    let (mut estimate, mut moment) = (PixelEstimate::default(), Default::default());
                    let pattern = pixel_pattern(x, y, s.seed);
                    let cone = context.sample_cone(adaptive.max_spp);
                    for index in 0..pass.sample_count {
                        let (dx, dy) = progressive_2d(index, pattern);
                        let mut ray = [Ray::new(DVec3::ZERO, DVec3::ZERO)];
                        context.camera_rays(&[[x as f64 + dx, y as f64 + dy]], &mut ray);
                        let key = SampleKey {
                            pattern,
                            index,
                            count: None,
                        };
                        let mut counts = RayCounts::default();
                        let radiance = context.trace_ray(&ray[0], cone, key, None, &mut counts);
                        estimate.add_with_moment(radiance, &mut moment);
                    }
                    let want = moment.variance(pass.sample_count);
                    let case = format!("{rule:?} {window:?} ({x}, {y})");
                    assert_eq!(pass.variance.to_array(), want.to_array(), "{case}");
                    refined += (pass.sample_count > adaptive.min_spp) as u32;
                }
            }
            assert!(
                refined > 50,
                "{rule:?} {window:?}: {refined} pixels refined"
            );
        }
    }
}
