//! Tests of the image rule: the target met in the true error, the estimate checked against it,
//! the budgets, and features the first samples miss.

use super::tests::{disc, settings, white_on_black};
use super::*;
use crate::film::encode_srgb;
use crate::render::{NoProgress, RenderSettings, render};
use crate::*;
use glam::DVec3;

/// The true RMSE of `film`'s display values against `reference`'s.
fn true_rmse(film: &Film, reference: &Film) -> f64 {
    let sum: f64 = film
        .pixels()
        .iter()
        .zip(reference.pixels())
        .map(|(a, b)| {
            (0..3)
                .map(|c| (encode_srgb(a[c]) as f64 - encode_srgb(b[c]) as f64).powi(2))
                .sum::<f64>()
        })
        .sum();
    (sum / (3 * film.pixels().len()) as f64).sqrt()
}

/// A converged image of `scene` at `base`'s size: 4096 uniform samples with another seed.
fn reference(scene: &Scene, base: &RenderSettings) -> Film {
    let s = RenderSettings {
        spp: 4096,
        seed: 99,
        adaptive: None,
        ..*base
    };
    render(scene, &s, &NoProgress).unwrap().film
}

fn image_rule(target_error: f64) -> Adaptive {
    Adaptive {
        target_error,
        max_spp: 1024,
        ..Adaptive::default()
    }
}

/// The audited estimate ([`super::audit`]) is unbiased: over seeds, its mean is the true error
/// (against a 4096-sample reference) within ±20%, and no render's estimate is off by 2× or
/// more; the true error reaches the target (on average within 1.25× of it) and falls with it.
/// The audit's spread is a single render's, measured on the bundled scenes in docs/sampling.md.
#[test]
fn the_estimate_follows_the_true_error_down_to_the_target() {
    let scene = disc();
    let converged = reference(&scene, &settings(image_rule(0.01)));
    let mut previous = f64::INFINITY;
    for target in [0.004, 0.002] {
        let (mut ratios, mut truths) = (Vec::new(), Vec::new());
        for seed in 0..8 {
            let s = RenderSettings {
                seed,
                ..settings(image_rule(target))
            };
            let rendered = render(&scene, &s, &NoProgress).unwrap();
            let error = rendered.sampling.error.unwrap();
            let truth = true_rmse(&rendered.film, &converged);
            assert_eq!(error.stop, Stop::Converged, "{error:?}");
            ratios.push(error.estimated_rmse / truth);
            truths.push(truth);
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (ratio, truth) = (mean(&ratios), mean(&truths));
        assert!((0.8..=1.2).contains(&ratio), "target {target}: {ratios:?}");
        assert!(ratios.iter().all(|r| (0.5..2.0).contains(r)), "{ratios:?}");
        assert!(
            truth < 1.25 * target && truth < previous,
            "target {target}: {truths:?}"
        );
        previous = truth;
    }
}

/// A sample budget spends about its samples, gives the same image every time, and a larger one
/// a lower error.
#[test]
fn a_sample_budget_spends_about_its_samples() {
    let scene = disc();
    let converged = reference(&scene, &settings(image_rule(0.01)));
    // A maximum the budget cannot reach, so that the budget stops the render.
    let budget = |spp: f64| Adaptive {
        target_error: 0.0,
        spp_budget: Some(spp),
        max_spp: 1024,
        ..image_rule(0.0)
    };
    let mut previous = f64::INFINITY;
    for spp in [12.0, 24.0] {
        let a = render(&scene, &settings(budget(spp)), &NoProgress).unwrap();
        let b = render(&scene, &settings(budget(spp)), &NoProgress).unwrap();
        assert_eq!(a.film, b.film);
        let mean = a.sampling.mean_spp;
        // The neighbour rounds add samples the pilot does not plan for.
        assert!(mean > 0.7 * spp && mean < 1.5 * spp, "budget {spp}: {mean}");
        assert_eq!(a.sampling.error.unwrap().stop, Stop::Budget);
        let truth = true_rmse(&a.film, &converged);
        assert!(truth < previous);
        previous = truth;
    }
}

/// Dots a fifth of a pixel wide, far apart.
fn dots() -> Scene {
    let spheres = (0..6)
        .flat_map(|i| (0..6).map(move |j| (i, j)))
        .map(|(i, j)| Sphere {
            // A grid of dots, 7.3 pixels apart, off the pixel grid.
            center: DVec3::new(-1.7 + 0.61 * i as f64, -1.7 + 0.59 * j as f64, 0.0),
            radius: 0.0085,
            material: 0,
        })
        .collect();
    white_on_black(spheres)
}

/// Dots a fifth of a pixel wide, far apart: 8 samples miss a dot in about 3 of 4 of the pixels
/// it lies in, and no neighbour sees it. The flat pixels' error, measured by the flat twins, is
/// what finds them: the render still reaches near the target in the true error.
#[test]
fn features_the_first_samples_miss_are_found() {
    let scene = dots();
    let converged = reference(&scene, &settings(image_rule(0.01)));
    let first = render(&scene, &settings(image_rule(1.0)), &NoProgress).unwrap();
    let target = 0.25 * true_rmse(&first.film, &converged);
    let rendered = render(&scene, &settings(image_rule(target)), &NoProgress).unwrap();
    let truth = true_rmse(&rendered.film, &converged);
    assert!(
        truth < 1.5 * target,
        "target {target}, true {truth}, {:?}",
        rendered.sampling
    );
}
