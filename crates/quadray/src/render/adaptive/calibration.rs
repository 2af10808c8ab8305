//! The calibration of the error estimate: some pixels are followed by a twin, the same pixel
//! sampled as often with two independent sample sets, whose disagreement with it measures its
//! true error.
//!
//! A pixel's batch-means estimate ([`PixelEstimate::squared_error`]) overstates its error under
//! stratification. With V(s) the variance of the mean of a net of s samples, the k runs rⱼ of n/k
//! samples have Σ E(rⱼ − r̄)² = k (V(n/k) − V(n)) (their mean is the pixel's), so the estimate's
//! expectation is (V(n/k) − V(n)) / (k − 1): V(n) · (k^α − 1) / (k − 1) where the error falls as
//! V ∝ n^−α. That is right for independent samples (α = 1) but 3.1× the truth for an edge
//! (α = 1.5) and 9× for a smooth pixel (α = 2). Measured on the bundled scenes at 8 to 128
//! samples, the estimate's RMSE is 2.1–3.1× the true one, a ratio that depends on the scene.
//!
//! With b and c two independent estimates of a pixel whose own estimate is a, (a − b)(a − c) has
//! expectation (a − μ)² given a: the pixel's actual squared error, whatever chose the pixel or
//! stopped its sampling ([`Twin`]). The twins' weighted mean of those, at one count, estimates the
//! mean error of the pixels at that count; over their summed batch-means estimates it is the
//! factor (a [`Calibration`] keeps one a sample count) that makes the estimate unbiased there,
//! and the rate the error falls at follows from it: factor = (k − 1) / (k^α − 1) with k = 8.
//! One twin and half of (a − b)², unbiased only over pixels taken whatever their samples say,
//! measured 0.54–0.84× the true image error on defense and reflective (480x270, targets 0.002 to
//! 0.0005); the pair, 0.80–1.16×. The calibration steers the rounds; the error a render reports
//! is measured by [`super::audit`], on pixels drawn when the rounds are over.
//!
//! Which pixels get twins ([`TwinOdds`]) is decided once, after the first samples, in two strata:
//! pixels whose first samples disagree (rough) and those whose samples all agree (flat). Each
//! stratum gets about [`ROUGH_TWINS`] and [`FLAT_TWINS`] twins, chosen by a hash of the position,
//! and each twin stands for 1/p pixels of its stratum. A fixed lattice (one pixel in 64) measured
//! the error of a 48x48 disc at 0.2× to 2.2× the truth depending on the seed: the few pixels on
//! the edge, where all the error is, held about five twins. Twins never enter the image.

use super::sample_sequence;
use crate::film::{ERROR_BATCHES, PixelEstimate, encode_srgb};
use crate::integrator::RayCounts;
use crate::render::SampleContext;
use crate::sampler::pixel_pattern;

/// What a twin's seed differs from the image's by: any other value gives an independent sample
/// set.
const TWIN_SEED_OFFSET: u32 = 0x7A1E_5EED;

/// What a twin's choice is hashed with, so that it does not follow the image's sample patterns.
const TWIN_CHOICE_SEED: u32 = 0x0C40_1CE5;

/// The fewest twins a count's factor is made from; with fewer the estimate is not corrected.
pub const MIN_TWINS: usize = 16;

/// The twins the rough stratum is given, about (all its pixels where it has fewer). The summed
/// error of m twins has a relative spread near 2/√m at best ((a − b)(a − c) has a standard
/// deviation near 1.7 times its mean, and pixels differ): about 9% here.
pub const ROUGH_TWINS: f64 = 512.0;

/// The twins the flat stratum is given, about: enough that a feature every first sample missed,
/// in a few percent of the flat pixels, is met by some of them.
pub const FLAT_TWINS: f64 = 1024.0;

/// A batch-means squared error at or below this is a flat pixel's: far below anything visible
/// (an RMSE of 1e-6 of the display range) and above the rounding of identical samples.
pub(super) const FLAT: f64 = 1e-12;

/// Sample counts are powers of two up to `MAX_SPP`: this many of them.
const LEVELS: usize = 17;

/// A pixel's twin: two independent sample sets of it, and how many pixels of its stratum it
/// stands for.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Twin {
    /// The two sample sets, each as many samples as its pixel's.
    pub estimates: [PixelEstimate; 2],
    /// 1/p, where p is the chance that a pixel of its stratum got a twin.
    pub weight: f64,
}

impl Twin {
    /// Samples each of its sets holds.
    pub fn count(&self) -> u32 {
        self.estimates[0].count()
    }

    /// An unbiased estimate of the squared error of `pixel`'s display values against the
    /// converged ones, averaged over the channels: (a − b)(a − c) for the pixel's value a and the
    /// twins' b and c. With b and c independent of a and of each other, of mean μ, its
    /// expectation given a is (a − μ)², whatever chose the pixel or stopped its sampling. Half of
    /// (a − b)² would be unbiased only over pixels taken whatever their samples say: given a,
    /// its expectation is ((a − μ)² + V) / 2.
    pub(super) fn squared_error_of(&self, pixel: &PixelEstimate) -> f64 {
        let (a, b, c) = self.display_values(pixel);
        (0..3).map(|i| (a[i] - b[i]) * (a[i] - c[i])).sum::<f64>() / 3.0
    }

    /// The squared error of a flat `pixel` (one whose samples all agreed): the mean of (a − b)²
    /// and (a − c)², whose expectation given a is (a − μ)² + V, less the twins' own batch-means
    /// variance. That variance overstates V under stratification (about 3× for an edge), so
    /// this can fall below the truth by up to 2V where the twins see an edge; it is not on the
    /// safe side. It is kept over (a − b)(a − c), unbiased, for rare features: where the pixel's
    /// samples all missed a feature that a sample meets with chance p, (a − b)(a − c) is not
    /// zero only when both twins meet it, p² of the time, and on the dots of
    /// `features_the_first_samples_miss_are_found` (p near 1/4) the pilot's flat twins then saw
    /// nothing and the render stopped with the dots missed.
    fn flat_squared_error_of(&self, pixel: &PixelEstimate) -> f64 {
        let (a, b, c) = self.display_values(pixel);
        let spread = (0..3)
            .map(|i| ((a[i] - b[i]).powi(2) + (a[i] - c[i]).powi(2)) / 2.0)
            .sum::<f64>()
            / 3.0;
        let variance = self.estimates.iter().map(PixelEstimate::squared_error);
        spread - variance.sum::<f64>() / 2.0
    }

    /// The display values of `pixel` and of the twin's two sample sets, per channel.
    fn display_values(&self, pixel: &PixelEstimate) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let display = |e: &PixelEstimate| e.mean().to_array().map(|v| encode_srgb(v) as f64);
        (
            display(pixel),
            display(&self.estimates[0]),
            display(&self.estimates[1]),
        )
    }
}

/// The chance that a pixel of each stratum gets a twin (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwinOdds {
    /// For pixels whose first samples disagree.
    rough: f64,
    /// For pixels whose first samples all agree.
    flat: f64,
}

impl TwinOdds {
    /// The odds for pixels whose first samples are flat or not as `flat` says (see
    /// [`is_flat`]): about [`ROUGH_TWINS`] and [`FLAT_TWINS`] twins.
    pub fn of(flat: impl Iterator<Item = bool>) -> TwinOdds {
        let (mut rough, mut flats) = (0usize, 0usize);
        for flat in flat {
            match flat {
                true => flats += 1,
                false => rough += 1,
            }
        }
        let odds = |wanted: f64, pixels: usize| (wanted / pixels.max(1) as f64).min(1.0);
        TwinOdds {
            rough: odds(ROUGH_TWINS, rough),
            flat: odds(FLAT_TWINS, flats),
        }
    }

    /// The twin of the pixel at `at`, whose first samples are `flat` or not, if it gets one
    /// (decided by a hash of the position and `seed`).
    pub fn twin(&self, seed: u32, at: (u32, u32), flat: bool) -> Option<Twin> {
        let chance = match flat {
            true => self.flat,
            false => self.rough,
        };
        (uniform_draw(seed ^ TWIN_CHOICE_SEED, at) < chance).then(|| Twin {
            estimates: Default::default(),
            weight: 1.0 / chance,
        })
    }
}

/// The twins of `candidates` (each pixel's position and whether its first samples are flat,
/// [`is_flat`]), as (the candidate's index, its twin) in the candidates' order: the strata and
/// their odds ([`TwinOdds`]) are those of the candidates. Only the chosen, about 1500 whatever
/// the image's size: a slot for every candidate (a twin is 320 bytes) was 42 MB at 480x270, a
/// third of a preview's time.
pub fn choose_twins(seed: u32, candidates: &[((u32, u32), bool)]) -> Vec<(usize, Twin)> {
    let odds = TwinOdds::of(candidates.iter().map(|&(_, flat)| flat));
    (candidates.iter().enumerate())
        .filter_map(|(i, &(at, flat))| Some((i, odds.twin(seed, at, flat)?)))
        .collect()
}

/// A number in [0, 1) fixed by the pixel at `at` and `seed`, for drawing pixels with a chance.
pub(super) fn uniform_draw(seed: u32, at: (u32, u32)) -> f64 {
    pixel_pattern(at.0, at.1, seed) as f64 / 2f64.powi(32)
}

/// Whether a pixel's samples all agree (an unknown error is not flat).
pub(crate) fn is_flat(estimate: &PixelEstimate) -> bool {
    is_flat_error(estimate.squared_error())
}

/// Whether a pixel whose batch-means squared error is `squared_error` is flat ([`is_flat`]).
pub(super) fn is_flat_error(squared_error: f64) -> bool {
    squared_error <= FLAT
}

/// The correction of the batch-means estimate, measured by twins, for each sample count.
///
/// Pixels at different counts need different corrections: those refined are overstated (about
/// 3× in RMSE on the bundled scenes), while those left at the first round's count include the
/// pixels whose estimate was low by chance, and are understated (up to 3× on the reflective
/// scene). Each count with at least `MIN_TWINS` twins gets its own factor; the others take, in
/// this order, the fallback's factor at that count, the factor of all refined twins (the
/// fallback's where there are too few), or that of all twins.
///
/// The pilot follows no neighbours, so its pixels left at the first round's count include edges
/// their first samples missed: its factor there measured 5.9 on defense (480x270), where the
/// image's pixels at that count measured 0.19. Giving that count the refined factor instead
/// brought the estimate on defense from 0.64× to 0.82× the truth, but the 48x48 disc's from
/// 0.92× to 0.58×; it was not kept.
///
/// A flat pixel, whose samples all agreed (estimate zero), can still be wrong: its first samples
/// may all have missed a feature. No factor corrects a zero, so flat pixels are given the mean
/// error the flat twins measure at their count instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// What the batch-means squared errors of a pixel with 2^k samples are multiplied by, where
    /// enough twins had 2^k samples.
    factors: [Option<f64>; LEVELS],
    /// The factor of the counts without their own.
    shared: Option<f64>,
    /// The squared error of a flat pixel with 2^k samples.
    flat: [f64; LEVELS],
    /// The exponent α of the error's fall with the sample count, V ∝ n^−α, that the refined
    /// pixels' factor implies (at least 1).
    pub alpha: f64,
}

impl Calibration {
    /// No correction (too few twins to measure one): the batch-means estimate as it is.
    pub const NONE: Calibration = Calibration {
        factors: [None; LEVELS],
        shared: None,
        flat: [0.0; LEVELS],
        alpha: 1.0,
    };

    /// The calibration of the pixels of `population` from the pixels among them that have
    /// twins, given as pairs (see the type's documentation).
    pub fn fit<'a>(
        pairs: impl Iterator<Item = (&'a PixelEstimate, &'a Twin)>,
        population: impl Iterator<Item = (u32, f64)>,
    ) -> Self {
        Calibration::fit_or(pairs, population, None)
    }

    /// [`Calibration::fit`], with the counts that have too few twins taking `fallback`'s factor
    /// where there is one (a crop's few twins, backed by the pilot's).
    ///
    /// At each count, the twins' mean error is an unbiased estimate of the mean error of the
    /// population's pixels at that count, whatever their estimates say; the factor spreads that
    /// mean over them in proportion to their estimates. (The ratio of the twins' errors to
    /// their own pixels' estimates would be biased: it measured 15–25% low on the defense scene,
    /// whose pixels with small estimates hold a larger share of the error than their estimates
    /// say.)
    /// The population is given as each pixel's count and batch-means squared error.
    pub fn fit_or<'a>(
        pairs: impl Iterator<Item = (&'a PixelEstimate, &'a Twin)>,
        population: impl Iterator<Item = (u32, f64)>,
        fallback: Option<&Calibration>,
    ) -> Self {
        // Per level: the population's non-flat pixels and their summed estimates.
        let mut people = [(0usize, 0.0f64); LEVELS];
        for (count, estimated) in population {
            if count >= super::MIN_FIRST_ROUND && estimated > FLAT {
                let level = &mut people[level(count)];
                level.0 += 1;
                level.1 += estimated;
            }
        }
        // Per level: twins, their summed weights, and their weighted summed measurements; the
        // same for flat twins.
        let mut levels = [(0usize, 0.0f64, 0.0f64); LEVELS];
        let mut flat = [(0usize, 0.0f64, 0.0f64); LEVELS];
        for (pixel, twin) in pairs {
            let count = pixel.count();
            if count < super::MIN_FIRST_ROUND || twin.count() != count {
                continue;
            }
            let (level, measured) = match pixel.squared_error() > FLAT {
                true => (&mut levels[level(count)], twin.squared_error_of(pixel)),
                false => (&mut flat[level(count)], twin.flat_squared_error_of(pixel)),
            };
            level.0 += 1;
            level.1 += twin.weight;
            level.2 += twin.weight * measured;
        }
        // The twins' weighted mean error at a level, times the population's pixels there, over
        // their summed estimates.
        let lowest = levels.iter().position(|l| l.0 > 0).unwrap_or(0);
        let fold = |range: std::ops::Range<usize>| {
            range.fold((0, 0.0, 0.0, 0usize, 0.0), |a, i| {
                (
                    a.0 + levels[i].0,
                    a.1 + levels[i].1,
                    a.2 + levels[i].2,
                    a.3 + people[i].0,
                    a.4 + people[i].1,
                )
            })
        };
        let refined = fold(lowest + 1..LEVELS);
        let factor_of =
            |(twins, weight, measured, pixels, estimated): (usize, f64, f64, usize, f64)| {
                // Bounded so that one unlucky draw cannot silence or inflate a level wholesale.
                (twins >= MIN_TWINS && estimated > 0.0 && measured > 0.0)
                    .then(|| (measured / weight * pixels as f64 / estimated).clamp(1e-3, 100.0))
            };
        let refined_factor = factor_of(refined);
        let mut calibration = *fallback.unwrap_or(&Calibration::NONE);
        for (index, &(n, weight, measured)) in flat.iter().enumerate() {
            if n >= MIN_TWINS {
                calibration.flat[index] = (measured / weight).max(0.0);
            }
        }
        for index in 0..LEVELS {
            if let Some(own) = factor_of(fold(index..index + 1)) {
                calibration.factors[index] = Some(own);
            }
        }
        calibration.shared = refined_factor
            .or(calibration.shared)
            .or_else(|| factor_of(fold(0..LEVELS)));
        if let Some(shared) = refined_factor {
            let k = ERROR_BATCHES as f64;
            calibration.alpha = ((k - 1.0) / shared + 1.0).log(k).clamp(1.0, 3.0);
        }
        calibration
    }

    /// The factor of a pixel with `count` samples.
    #[cfg(test)]
    fn factor(&self, count: u32) -> f64 {
        let level = level(count.max(1));
        self.factors[level].or(self.shared).unwrap_or(1.0)
    }

    /// A pixel's corrected squared error.
    pub fn squared_error(&self, estimate: &PixelEstimate) -> f64 {
        self.corrected(estimate.count(), estimate.squared_error())
    }

    /// The corrected squared error of a pixel with `count` samples and batch-means squared error
    /// `estimated`.
    pub fn corrected(&self, count: u32, estimated: f64) -> f64 {
        let level = level(count.max(1));
        if estimated > FLAT {
            estimated * self.factors[level].or(self.shared).unwrap_or(1.0)
        } else {
            self.flat[level]
        }
    }
}

/// The level of a count: log₂, rounded down.
fn level(count: u32) -> usize {
    (count.ilog2() as usize).min(LEVELS - 1)
}

/// Brings both sample sets of the twin of pixel `at` to `count` samples (each standing for its
/// share of the pixel at `footprint_spp`), adding the rays to `counts`.
pub(crate) fn sample_twin(
    context: &SampleContext<'_>,
    at: (u32, u32),
    twin: &mut Twin,
    footprint: (u32, u32),
    counts: &mut RayCounts,
) {
    sample_sets(context, at, twin, footprint, counts, TWIN_SEED_OFFSET);
}

/// [`sample_twin`] with the sample sets keyed by the render's seed plus `offset` (and the set's
/// index): another offset gives sets independent of the twins'.
pub(super) fn sample_sets(
    context: &SampleContext<'_>,
    at: (u32, u32),
    twin: &mut Twin,
    (count, footprint_spp): (u32, u32),
    counts: &mut RayCounts,
    offset: u32,
) {
    for (set, estimate) in twin.estimates.iter_mut().enumerate() {
        let seed = (context.settings.seed)
            .wrapping_add(offset)
            .wrapping_add(set as u32);
        let pattern = pixel_pattern(at.0, at.1, seed);
        let footprint = (count, footprint_spp);
        sample_sequence(
            context,
            at,
            pattern,
            estimate,
            (None, None),
            footprint,
            counts,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Twins that agree as independent estimates would give a factor near the truth: pixels
    /// whose 8 runs are independent draws of one variance, paired with twins drawn the same way,
    /// give a factor near 1 (α near 1).
    #[test]
    fn independent_samples_need_no_correction() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next =
            || (crate::test_rng::xorshift(&mut state) >> 40) as f32 / (1u64 << 24) as f32;
        let mut pairs = Vec::new();
        for _ in 0..4000 {
            let (mut a, mut b) = (PixelEstimate::default(), Twin::default());
            b.weight = 1.0;
            for _ in 0..8 {
                a.add(Vec3::splat(0.2 + 0.1 * next()));
                for twin in &mut b.estimates {
                    twin.add(Vec3::splat(0.2 + 0.1 * next()));
                }
            }
            pairs.push((a, b));
        }
        let population = || pairs.iter().map(|p| (p.0.count(), p.0.squared_error()));
        let c = Calibration::fit(pairs.iter().map(|(a, b)| (a, b)), population());
        assert!((c.factor(8) - 1.0).abs() < 0.15, "{c:?}");
        // Too few twins: no correction.
        let few = Calibration::fit(
            pairs.iter().take(MIN_TWINS - 1).map(|(a, b)| (a, b)),
            population(),
        );
        assert_eq!(few, Calibration::NONE);
        // No twins at all: the fallback as it is, whatever the population (the window of a
        // planned render, which takes the pilot's calibration without a pass over its pixels).
        let fitted = Calibration::fit(pairs.iter().map(|(a, b)| (a, b)), population());
        let none = || std::iter::empty::<(&PixelEstimate, &Twin)>();
        assert_eq!(
            Calibration::fit_or(none(), population(), Some(&fitted)),
            fitted
        );
        assert_eq!(
            Calibration::fit_or(none(), population(), None),
            Calibration::NONE
        );
    }

    /// About the wanted number of twins are chosen in each stratum, each standing for 1/p of
    /// its pixels, the same ones for the same seed; a stratum smaller than its share gets a twin
    /// for every pixel.
    #[test]
    fn each_stratum_gets_about_its_twins() {
        let (mut flat, mut rough) = (PixelEstimate::default(), PixelEstimate::default());
        for i in 0..8 {
            flat.add(Vec3::splat(0.5));
            rough.add(Vec3::splat(i as f32 / 8.0));
        }
        let pixels: Vec<((u32, u32), &PixelEstimate)> = (0..200u32)
            .flat_map(|y| (0..100u32).map(move |x| (x, y)))
            .map(|(x, y)| ((x, y), if x < 20 { &rough } else { &flat }))
            .collect();
        let odds = TwinOdds::of(pixels.iter().map(|p| is_flat(p.1)));
        let twins: Vec<(bool, Twin)> = pixels
            .iter()
            .filter_map(|&(at, e)| Some((e == &rough, odds.twin(3, at, is_flat(e))?)))
            .collect();
        let (rough_twins, flat_twins): (Vec<_>, Vec<_>) = twins.iter().partition(|t| t.0);
        // 4000 rough pixels for 512 twins, 16000 flat ones for 1024.
        let near = |n: usize, wanted: f64| (n as f64 - wanted).abs() < 4.0 * wanted.sqrt();
        assert!(
            near(rough_twins.len(), ROUGH_TWINS),
            "{}",
            rough_twins.len()
        );
        assert!(near(flat_twins.len(), FLAT_TWINS), "{}", flat_twins.len());
        assert!(
            rough_twins
                .iter()
                .all(|t| t.1.weight == 4000.0 / ROUGH_TWINS)
        );
        assert!(
            flat_twins
                .iter()
                .all(|t| t.1.weight == 16000.0 / FLAT_TWINS)
        );
        let again = (pixels.iter()).filter(|p| odds.twin(3, p.0, is_flat(p.1)).is_some());
        assert_eq!(again.count(), twins.len());
        let few = TwinOdds::of(pixels.iter().take(300).map(|p| is_flat(p.1)));
        assert!(pixels[..300].iter().all(|p| few.twin(3, p.0, is_flat(p.1))
            == Some(Twin {
                estimates: Default::default(),
                weight: 1.0,
            })));
    }
}
