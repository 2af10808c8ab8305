//! The film: a linear f32 RGB image, its sRGB encoding for 8-bit outputs, the running per-pixel
//! estimate (mean, error) that adaptive sampling decides by, and the samples' second moment the
//! variance pass reads.

use crate::colour::display_channels_eight;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

// The sRGB curve, where the film's users have always found it.
pub use crate::colour::{
    decode_srgb, decode_srgb8, display_channels, display_value, encode_srgb, encode_srgb8,
    encode_srgb8_pixels,
};

/// A linear, scene-referred RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
}

impl Film {
    /// The image of per-pixel estimates (row-major, `width` × `height`): each pixel their mean.
    /// The one way adaptive and progressive sampling write pixels; uniform sampling, which needs
    /// no running estimate, writes its f32 sum over the count instead (its images depend on those
    /// bits).
    pub(crate) fn of_estimates(width: u32, height: u32, estimates: &[PixelEstimate]) -> Film {
        let pixels = estimates.par_iter().map(PixelEstimate::mean).collect();
        Film::from_pixels(width, height, pixels).expect("one estimate per pixel")
    }

    /// A black film.
    pub fn new(width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            // Zero pages from the allocator, not zeros written by this thread: the render threads
            // fault in the pages they write (the quadric grid's 1280x720 frame on two threads
            // 0.037 -> 0.033 s, medians of 15; one thread unchanged).
            pixels: bytemuck::zeroed_vec(width as usize * height as usize),
        }
    }

    /// Wraps existing pixels; `None` if the count does not match.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Vec3>) -> Option<Film> {
        (pixels.len() == width as usize * height as usize).then_some(Film {
            width,
            height,
            pixels,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major.
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }

    /// Mutable pixels, row-major.
    pub fn pixels_mut(&mut self) -> &mut [Vec3] {
        &mut self.pixels
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// 8-bit sRGB bytes (RGB, row-major), clamped to [0, 1] before encoding.
    pub fn to_srgb8(&self) -> Vec<u8> {
        encode_srgb8_pixels(&self.pixels)
    }
}

/// Display values below this count as this in a pixel's relative error: near-black pixels are
/// judged by their absolute error, so noise a viewer cannot see does not draw samples.
pub const ERROR_FLOOR: f64 = 0.1;

/// The fewest samples a pixel's error can be estimated from.
pub const MIN_ERROR_SAMPLES: u32 = 2;

/// The number of aligned runs of samples ("batches") a pixel's error is estimated from.
pub const ERROR_BATCHES: u32 = 8;

/// One pixel's running estimate from its samples so far: the linear RGB mean that the image
/// shows (Welford's online mean, in f64), and the display-value sums that the pixel's error is
/// estimated from. The samples' second moment, which only the variance pass reads, is kept
/// apart ([`SecondMoment`]): 24 bytes a pixel every adaptive render would fault in and update.
///
/// The **display value** of a sample is the mean of its three sRGB-encoded channels
/// ([`display_value`]: clamped to [0, 1], the value a viewer sees). The pixel's **relative error**
/// ([`PixelEstimate::relative_error`]) is the standard error of its mean display value divided by
/// that mean, or by [`ERROR_FLOOR`] where the mean is below it. Its **squared error**
/// ([`PixelEstimate::squared_error`]) is the squared standard error of each display channel's
/// mean, averaged over the three: its share of the image's mean squared error.
///
/// The standard error is estimated by **batch means**: the n samples (n = 2^k, n >= 8) are split
/// into [`ERROR_BATCHES`] aligned runs of n/8, and SE² = Σ(bᵢ − b̄)² / (8 · 7) over the runs'
/// means bᵢ. With [`crate::sampler::progressive_2d`] each aligned run is itself a stratified net,
/// so its mean has the stratified error: the estimate follows the error stratification leaves
/// (for an edge it falls about as n^-3/4, not n^-1/2 as the samples' plain variance would say),
/// and with 7 degrees of freedom it is rarely fooled by two halves agreeing by chance. Below 8
/// samples every sample is a run of its own: the plain standard error, with n − 1 degrees of
/// freedom (a coarse estimate, for previews that start at 2 or 4 samples).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelEstimate {
    count: u32,
    rgb_mean: DVec3,
    /// Sums of the display channels of each aligned run of `batch_size` samples.
    batch_sums: [[f32; 3]; ERROR_BATCHES as usize],
}

impl PixelEstimate {
    /// Adds one sample's linear radiance (the pixel's next sample in its sequence).
    pub fn add(&mut self, radiance: Vec3) {
        self.add_encoded(radiance, display_channels(radiance), None);
    }

    /// [`PixelEstimate::add`], and the sample's deviation from the mean to `moment`.
    pub fn add_with_moment(&mut self, radiance: Vec3, moment: &mut SecondMoment) {
        self.add_encoded(radiance, display_channels(radiance), Some(moment));
    }

    /// [`PixelEstimate::add`] of the first `count` of eight samples in order, their display
    /// encodings made together ([`display_channels_eight`]; the others are not added), and,
    /// given `moment`, their deviations to it.
    pub fn add_eight(
        &mut self,
        radiances: &[Vec3; 8],
        count: usize,
        mut moment: Option<&mut SecondMoment>,
    ) {
        let display = display_channels_eight(radiances);
        for (&radiance, &display) in radiances.iter().zip(&display).take(count) {
            self.add_encoded(radiance, display, moment.as_deref_mut());
        }
    }

    /// [`PixelEstimate::add`] of `count` samples of the same radiance (the background of a pixel
    /// that sees nothing), encoded for display once, and, given `moment`, their deviations to it.
    pub fn add_repeated(
        &mut self,
        radiance: Vec3,
        count: u32,
        mut moment: Option<&mut SecondMoment>,
    ) {
        let display = display_channels(radiance);
        let x = radiance.as_dvec3();
        for _ in 0..count {
            if self.rgb_mean == x && x.is_finite() {
                // Welford's step for a finite sample equal to the mean is x − m = ±0: the mean
                // and M2 stay as they are, bit for bit (neither is ever −0.0: the first step's
                // 0 + x/1 gives +0.0), so only the count and the run sums move.
                self.count += 1;
                self.add_to_runs(self.count - 1, display);
            } else {
                self.add_encoded(radiance, display, moment.as_deref_mut());
            }
        }
    }

    /// [`PixelEstimate::add`] with the sample's display channels given.
    #[inline(always)]
    fn add_encoded(
        &mut self,
        radiance: Vec3,
        display: [f32; 3],
        moment: Option<&mut SecondMoment>,
    ) {
        let index = self.count;
        self.count += 1;
        let n = self.count as f64;
        // Welford: m_n = m_{n-1} + (x - m_{n-1}) / n, M2_n = M2_{n-1} + (x - m_{n-1})(x - m_n).
        let x = radiance.as_dvec3();
        let delta = x - self.rgb_mean;
        self.rgb_mean += delta / n;
        if let Some(SecondMoment(m2)) = moment {
            *m2 += delta * (x - self.rgb_mean);
        }
        self.add_to_runs(index, display);
    }

    /// Adds sample `index`'s display channels to the sums of its run.
    #[inline(always)]
    fn add_to_runs(&mut self, index: u32, display: [f32; 3]) {
        // Past 8 · 2^j samples the runs double: pairs of runs merge into the first half.
        if index >= ERROR_BATCHES && index.is_power_of_two() {
            let half = ERROR_BATCHES as usize / 2;
            for i in 0..half {
                let (a, b) = (self.batch_sums[2 * i], self.batch_sums[2 * i + 1]);
                self.batch_sums[i] = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
            }
            self.batch_sums[half..].fill([0.0; 3]);
        }
        // The run of sample `index`: a shift, as the run length is a power of two.
        let batch =
            &mut self.batch_sums[(index >> Self::batch_size(index + 1).trailing_zeros()) as usize];
        for (sum, value) in batch.iter_mut().zip(display) {
            *sum += value;
        }
    }

    /// The length of the runs when `count` samples are taken: the smallest power of two that
    /// makes 8 runs hold them (at least 1).
    fn batch_size(count: u32) -> u32 {
        (count.next_power_of_two() / ERROR_BATCHES).max(1)
    }

    /// Samples taken.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The mean linear RGB of the samples (zero before any sample).
    pub fn mean(&self) -> Vec3 {
        self.rgb_mean.as_vec3()
    }

    /// The mean over the samples of their display values ([`crate::colour::display_value`]),
    /// from the runs' sums (0 before any sample): for a pixel whose samples all agree, the display
    /// value of its mean, without encoding it again.
    pub fn mean_display_value(&self) -> f32 {
        let sum: f32 = self.batch_sums.iter().flatten().sum();
        sum / (3 * self.count.max(1)) as f32
    }

    /// The relative standard error of the mean display value (see the type's documentation):
    /// infinite below [`MIN_ERROR_SAMPLES`], where it is unknown. At a count that is not a power
    /// of two only the complete runs count.
    pub fn relative_error(&self) -> f64 {
        let Some((batches, size)) = self.complete_batches() else {
            return f64::INFINITY;
        };
        // A run's display value is the mean of its channels' (the encoding is per channel).
        let values = batches
            .iter()
            .map(|b| (b[0] as f64 + b[1] as f64 + b[2] as f64) / 3.0);
        let (mean, squared_error) = batch_means(values, size);
        squared_error.sqrt() / mean.max(ERROR_FLOOR)
    }

    /// The squared standard error of each display channel's mean, by batch means, averaged over
    /// the three channels (see the type's documentation): infinite below
    /// [`MIN_ERROR_SAMPLES`], where it is unknown.
    pub fn squared_error(&self) -> f64 {
        let Some((batches, size)) = self.complete_batches() else {
            return f64::INFINITY;
        };
        channel_squared_error(batches, size)
    }

    /// The batch-means squared errors ([`PixelEstimate::squared_error`]) from the 8 runs, and
    /// from the same samples in 4 and 2 runs (adjacent runs merged), when the pixel has 8
    /// complete runs. Under stratification runs of n/8 samples are closer to each other than
    /// independent estimates would be, and how the estimate changes with the run length tells
    /// the rate the error falls at ([`crate::adaptive`]'s error model).
    pub fn squared_errors_by_runs(&self) -> Option<[f64; 3]> {
        let (batches, size) = self.complete_batches()?;
        if batches.len() < ERROR_BATCHES as usize {
            return None;
        }
        let merge = |runs: &[[f32; 3]]| -> Vec<[f32; 3]> {
            runs.chunks(2)
                .map(|p| [p[0][0] + p[1][0], p[0][1] + p[1][1], p[0][2] + p[1][2]])
                .collect()
        };
        let fours = merge(batches);
        let twos = merge(&fours);
        Some([
            channel_squared_error(batches, size),
            channel_squared_error(&fours, 2 * size),
            channel_squared_error(&twos, 4 * size),
        ])
    }

    /// The complete runs of samples and their length, if there are at least two.
    fn complete_batches(&self) -> Option<(&[[f32; 3]], u32)> {
        if self.count < MIN_ERROR_SAMPLES {
            return None;
        }
        let size = Self::batch_size(self.count);
        let full = (self.count / size).min(ERROR_BATCHES) as usize;
        Some((&self.batch_sums[..full], size))
    }
}

/// The batch-means squared error of the mean of each channel over `batches` (sums of runs of
/// `size` samples), averaged over the three channels.
fn channel_squared_error(batches: &[[f32; 3]], size: u32) -> f64 {
    let k = batches.len() as f64;
    let mut totals = [0.0f64; 3];
    for batch in batches {
        for (total, &sum) in totals.iter_mut().zip(batch) {
            *total += sum as f64;
        }
    }
    let means = totals.map(|t| t / k);
    let mut spread = 0.0;
    for batch in batches {
        for (&mean, &sum) in means.iter().zip(batch) {
            spread += (sum as f64 - mean).powi(2);
        }
    }
    // The runs' sums are size times their means: one division for all of them.
    spread / (3.0 * (size as f64).powi(2) * k * (k - 1.0))
}

/// The second moment of a pixel's linear RGB samples about their mean, Σ(x − m)² per channel
/// (Welford's M2, in f64): the variance pass's, kept beside a pixel's [`PixelEstimate`] (which
/// updates it with its mean, [`PixelEstimate::add_eight`]) only where that pass is asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SecondMoment(DVec3);

impl SecondMoment {
    /// The unbiased sample variance of each linear RGB channel of the `count` samples the moment
    /// was taken over (zero below two samples).
    pub fn variance(&self, count: u32) -> Vec3 {
        if count < 2 {
            return Vec3::ZERO;
        }
        (self.0 / (count - 1) as f64).as_vec3()
    }
}

/// The mean of the runs' means and the squared standard error of that mean, from the sums of
/// runs of `size` samples: SE² = Σ(bᵢ − b̄)² / (k (k − 1)) over the k runs' means bᵢ (computed on
/// the sums, which are `size` times the means, with one division).
fn batch_means(sums: impl ExactSizeIterator<Item = f64> + Clone, size: u32) -> (f64, f64) {
    let k = sums.len() as f64;
    let mean_sum = sums.clone().sum::<f64>() / k;
    let spread = sums.map(|sum| (sum - mean_sum).powi(2)).sum::<f64>();
    let size = size as f64;
    (mean_sum / size, spread / (size * size * k * (k - 1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether two estimates are the same bit for bit: their debug forms tell −0.0 from 0.0,
    /// which `==` does not.
    fn same_bits(a: &PixelEstimate, b: &PixelEstimate) -> bool {
        format!("{a:?}") == format!("{b:?}")
    }

    /// Up to eight samples added together ([`PixelEstimate::add_eight`]) leave the estimate bit
    /// for bit as adding them one by one does, from an empty pixel and from one holding 13
    /// samples (so the error runs double inside the eight).
    #[test]
    fn eight_samples_add_as_single_ones() {
        let sample = |k: u32| {
            let f = k as f32;
            Vec3::new(
                (f * 0.37).sin().abs() * 1.7,
                (f * 0.11).cos() * 0.5,
                f * 1e-3 - 0.2,
            )
        };
        for held in [0u32, 13] {
            for count in 1..=8usize {
                let mut one_by_one = PixelEstimate::default();
                let mut moment = SecondMoment::default();
                (0..held).for_each(|k| one_by_one.add_with_moment(sample(k), &mut moment));
                let (mut together, mut moment_together) = (one_by_one, moment);
                let eight: [Vec3; 8] = std::array::from_fn(|k| sample(held + k as u32));
                (eight[..count].iter()).for_each(|&r| one_by_one.add_with_moment(r, &mut moment));
                together.add_eight(&eight, count, Some(&mut moment_together));
                let case = format!("{held} held, {count} added");
                assert!(same_bits(&together, &one_by_one), "{case}");
                assert_eq!(
                    format!("{moment_together:?}"),
                    format!("{moment:?}"),
                    "{case}"
                );
                // Without a moment the estimate is the same.
                let mut alone = PixelEstimate::default();
                (0..held).for_each(|k| alone.add(sample(k)));
                alone.add_eight(&eight, count, None);
                assert!(same_bits(&alone, &one_by_one), "{case}");
            }
        }
    }

    /// Repeated samples of one radiance, added at once, leave the estimate bit for bit as
    /// adding them one by one does, from an empty pixel and from one holding other samples, for
    /// counts that fill, cross and double the error runs.
    #[test]
    fn repeated_samples_add_as_single_ones() {
        // A background, a black one, and one with a negative zero (which the mean turns into
        // +0.0 at the first step, as one by one does).
        let backgrounds = [
            Vec3::new(0.2, 0.3, 0.4),
            Vec3::ZERO,
            Vec3::new(-0.0, 0.5, 0.0),
        ];
        for background in backgrounds {
            for start in [0, 3, 8] {
                for count in [1, 2, 7, 8, 9, 16, 40] {
                    let mut one_by_one = PixelEstimate::default();
                    let mut at_once = PixelEstimate::default();
                    let (mut moment, mut moment_at_once) = Default::default();
                    for k in 0..start {
                        let other = Vec3::splat(0.1 * k as f32);
                        one_by_one.add_with_moment(other, &mut moment);
                        at_once.add_with_moment(other, &mut moment_at_once);
                    }
                    for _ in 0..count {
                        one_by_one.add_with_moment(background, &mut moment);
                    }
                    at_once.add_repeated(background, count, Some(&mut moment_at_once));
                    let case = format!("{background}, start {start}, count {count}");
                    assert!(same_bits(&one_by_one, &at_once), "{case}");
                    let moments: [SecondMoment; 2] = [moment, moment_at_once];
                    assert_eq!(
                        format!("{:?}", moments[0]),
                        format!("{:?}", moments[1]),
                        "{case}"
                    );
                }
            }
        }
    }

    /// Welford's estimates match the two-pass formulas; the error is the batch-means standard
    /// error over 8 aligned runs, whatever order the runs merged in, and below 8 samples the
    /// plain standard error of the samples (unknown at one).
    #[test]
    fn estimates_match_the_direct_formulas() {
        let samples: Vec<f32> = (0..64)
            .map(|i| ((i * 37 % 64) as f32 / 63.0).powi(2))
            .collect();
        let (mut e, mut moment) = (PixelEstimate::default(), SecondMoment::default());
        for (k, &v) in samples.iter().enumerate() {
            e.add_with_moment(Vec3::splat(v), &mut moment);
            let n = k + 1;
            if n == 1 {
                assert!(e.relative_error().is_infinite());
                continue;
            }
            if n > 8 && !n.is_power_of_two() {
                continue;
            }
            let ys: Vec<f64> = samples[..n]
                .iter()
                .map(|&v| display_value(Vec3::splat(v)) as f64)
                .collect();
            let runs = n.min(8);
            let batches: Vec<f64> = ys
                .chunks(n / runs)
                .map(|c| c.iter().sum::<f64>() / c.len() as f64)
                .collect();
            let m = batches.iter().sum::<f64>() / runs as f64;
            let spread = batches.iter().map(|b| (b - m).powi(2)).sum::<f64>();
            let se = (spread / (runs * (runs - 1)) as f64).sqrt();
            let expected = se / m.max(ERROR_FLOOR);
            assert!(
                (e.relative_error() - expected).abs() < 1e-6 * expected.max(1e-3),
                "n {n}"
            );
        }
        let n = samples.len() as f64;
        let mean = samples.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = samples
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        assert!((e.mean().x as f64 - mean).abs() < 1e-7);
        assert!((moment.variance(e.count()).y as f64 - var).abs() < 1e-7);

        let (mut flat, mut flat_moment) = (PixelEstimate::default(), SecondMoment::default());
        flat.add_repeated(Vec3::new(0.3, 0.3, 0.3), 8, Some(&mut flat_moment));
        assert_eq!(flat.relative_error(), 0.0);
        assert_eq!(flat_moment.variance(flat.count()), Vec3::ZERO);
        // Near-black pixels are judged against the floor, not their own tiny mean.
        let mut dark = PixelEstimate::default();
        for i in 0..8 {
            dark.add(Vec3::splat(if i % 2 == 0 { 0.0 } else { 0.0002 }));
        }
        assert!(dark.relative_error() < 0.05, "{}", dark.relative_error());
    }
}
