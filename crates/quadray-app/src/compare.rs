//! Image comparison, shared by `quadray compare` and the regression suite: RMSE in linear space,
//! the largest difference, the share of pixels over a threshold, and FLIP (NVIDIA's perceptual
//! difference, via nv-flip) with its heat map.
//!
//! Thresholds are judged on *display* values: sRGB-encoded, clamped to [0, 1], and counted in
//! 8-bit steps (1 = 1/255 of the display range). For PNGs these are exactly the stored codes; an
//! EXR is clamped and encoded the same way first (unquantised), so a difference nobody can see
//! in the bright, clamped parts of an HDR image does not count. RMSE and the largest linear
//! difference are reported on the unclamped linear values. nv-flip 0.1 implements LDR-FLIP
//! only, so FLIP always compares the 8-bit display images.

use anyhow::{Context, Result, bail};
use quadray::Film;
use quadray::film::{decode_srgb8, encode_srgb, encode_srgb8};
use std::path::Path;

/// A linear RGB image read for comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB, row-major from the top-left pixel.
    pub pixels: Vec<[f32; 3]>,
}

impl LinearImage {
    /// The film's pixels as they are (linear, unclamped).
    pub fn from_film(film: &Film) -> LinearImage {
        LinearImage {
            width: film.width(),
            height: film.height(),
            pixels: film.pixels().iter().map(|p| p.to_array()).collect(),
        }
    }

    /// 8-bit sRGB bytes (RGB, row-major) decoded to linear.
    pub fn from_srgb8(width: u32, height: u32, bytes: &[u8]) -> LinearImage {
        LinearImage {
            width,
            height,
            pixels: bytes
                .chunks_exact(3)
                .map(|c| [decode_srgb8(c[0]), decode_srgb8(c[1]), decode_srgb8(c[2])])
                .collect(),
        }
    }

    /// Display values in 8-bit steps: clamped, sRGB-encoded, times 255, not rounded.
    pub fn display_steps(&self) -> Vec<[f32; 3]> {
        self.pixels.iter().map(|p| p.map(display_step)).collect()
    }

    /// The 8-bit sRGB image as it is shown (what a PNG of it holds).
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.map(encode_srgb8))
            .collect()
    }
}

/// A linear value as a display value in 8-bit steps: clamped to [0, 1], sRGB-encoded, × 255.
fn display_step(linear: f32) -> f32 {
    encode_srgb(linear) * 255.0
}

/// Reads a PNG (sRGB, decoded to linear) or an EXR (linear: its `ViewLayer.Combined` or
/// `R, G, B` channels), by extension.
pub fn read_image(path: &Path) -> Result<LinearImage> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => {
            use quadray_loader::read_limited::{MAX_IMAGE_BYTES, read};
            let bytes = read(path, MAX_IMAGE_BYTES)
                .with_context(|| format!("reading {}", path.display()))?;
            let mut reader = image::ImageReader::with_format(
                std::io::Cursor::new(bytes),
                image::ImageFormat::Png,
            );
            reader.limits(quadray_loader::image_file::decode_limits());
            // The image crate's errors repeat their cause in their own message: keep one.
            let img = reader
                .decode()
                .map_err(|e| anyhow::anyhow!("reading {}: {e}", path.display()))?
                .to_rgb8();
            Ok(LinearImage::from_srgb8(
                img.width(),
                img.height(),
                img.as_raw(),
            ))
        }
        Some("exr") => read_exr(path).with_context(|| format!("reading {}", path.display())),
        _ => bail!("{}: not a .png or .exr image", path.display()),
    }
}

fn read_exr(path: &Path) -> Result<LinearImage> {
    use exr::prelude::*;
    quadray_loader::read_limited::regular_file(path)?;
    let image = read_first_flat_layer_from_file(path)?;
    let layer = &image.layer_data;
    let names: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let find = |name: &str| names.iter().position(|n| n == name);
    let rgb = crate::exr_file::beauty_channels(|name| find(name).is_some())
        .map(|set| set.map(|name| find(name).unwrap_or_default()));
    let Some(rgb) = rgb else {
        bail!(
            "no colour channels (ViewLayer.Combined.R/G/B or R/G/B) among {}",
            names.join(", ")
        );
    };
    let (w, h) = (layer.size.width(), layer.size.height());
    let channel = |i: usize| -> Vec<f32> {
        layer.channel_data.list[i]
            .sample_data
            .values_as_f32()
            .collect()
    };
    let (r, g, b) = (channel(rgb[0]), channel(rgb[1]), channel(rgb[2]));
    // Subsampled channels (chroma images) hold fewer samples than pixels.
    if [&r, &g, &b].iter().any(|c| c.len() != w * h) {
        bail!("subsampled colour channels are not supported");
    }
    // A NaN or infinite colour has no display value, and its differences none either: measured,
    // it made every measure infinite and still passed as equal.
    if let Some(i) = (0..w * h).find(|&i| ![r[i], g[i], b[i]].iter().all(|v| v.is_finite())) {
        bail!(
            "pixel ({}, {}) holds a colour that is not finite ({}, {}, {}); only finite images \
             can be compared",
            i % w,
            i / w,
            r[i],
            g[i],
            b[i]
        );
    }
    let pixels = (0..w * h).map(|i| [r[i], g[i], b[i]]).collect();
    Ok(LinearImage {
        width: w as u32,
        height: h as u32,
        pixels,
    })
}

/// When two images count as different.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// A pixel is "over" when any channel's display difference exceeds this many 8-bit steps.
    pub pixel: f32,
    /// Largest allowed share of pixels over `pixel`, in [0, 1].
    pub max_share: f64,
    /// Largest allowed display difference of any channel, in 8-bit steps.
    pub max_diff: f32,
    /// Largest allowed mean FLIP error, if judged at all.
    pub max_flip: Option<f32>,
}

impl Default for Thresholds {
    /// The regression suite's: over 2/255 in at most 0.1% of pixels, nothing over 32/255.
    fn default() -> Self {
        Thresholds {
            pixel: 2.0,
            max_share: 0.001,
            max_diff: 32.0,
            max_flip: None,
        }
    }
}

/// The measured differences between a reference and a test image.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Width of both images.
    pub width: u32,
    /// Height of both images.
    pub height: u32,
    /// Root mean square of the linear per-channel differences (unclamped).
    pub rmse_linear: f64,
    /// Largest linear per-channel difference (unclamped).
    pub max_linear: f32,
    /// Root mean square of the per-channel differences of the 8-bit sRGB images, in [0, 1]
    /// (code difference / 255): the error a viewer of the PNG sees, and the one measure that
    /// treats an 8-bit image (another renderer's PNG) like a float one.
    pub rmse_display: f64,
    /// Root mean square of the per-channel differences of the sRGB-encoded values in [0, 1]
    /// before 8-bit rounding: the error `--target-error` estimates (docs/sampling.md).
    pub rmse_srgb: f64,
    /// Largest display per-channel difference, in 8-bit steps.
    pub max_display: f32,
    /// Pixels with some channel's display difference over the threshold.
    pub over: usize,
    /// `over` as a share of all pixels.
    pub over_share: f64,
    /// Mean FLIP error in [0, 1].
    pub flip_mean: f32,
    /// Largest per-pixel FLIP error.
    pub flip_max: f32,
    /// Per-pixel FLIP errors, row-major.
    flip_map: Vec<f32>,
}

/// Compares `test` with `reference`; the images must have the same size.
pub fn compare(
    reference: &LinearImage,
    test: &LinearImage,
    thresholds: &Thresholds,
) -> Result<Comparison> {
    if (reference.width, reference.height) != (test.width, test.height) {
        bail!(
            "the images differ in size: {}x{} and {}x{}",
            reference.width,
            reference.height,
            test.width,
            test.height
        );
    }
    let (w, h) = (reference.width, reference.height);
    if w == 0 || h == 0 {
        bail!("the images are empty");
    }
    let n = reference.pixels.len();
    let mut sum_sq = 0.0f64;
    let mut max_linear = 0.0f32;
    for (a, b) in reference.pixels.iter().zip(&test.pixels) {
        for c in 0..3 {
            let d = a[c] - b[c];
            // NaN anywhere must not compare as equal.
            let d = if d.is_nan() { f32::INFINITY } else { d.abs() };
            sum_sq += (d as f64) * (d as f64);
            max_linear = max_linear.max(d);
        }
    }
    let (ref_disp, test_disp) = (reference.display_steps(), test.display_steps());
    let mut max_display = 0.0f32;
    let mut over = 0;
    let mut srgb_sq = 0.0f64;
    for (a, b) in ref_disp.iter().zip(&test_disp) {
        srgb_sq += (0..3)
            .map(|c| ((a[c] - b[c]) as f64 / 255.0).powi(2))
            .sum::<f64>();
        let d = (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max);
        max_display = max_display.max(d);
        if d > thresholds.pixel {
            over += 1;
        }
    }
    let (ref_bytes, test_bytes) = (reference.to_srgb8(), test.to_srgb8());
    let display_sq: f64 = ref_bytes
        .iter()
        .zip(&test_bytes)
        .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
        .sum();
    let rmse_display = (display_sq / ref_bytes.len() as f64).sqrt() / 255.0;
    let flip_map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &ref_bytes),
        nv_flip::FlipImageRgb8::with_data(w, h, &test_bytes),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let pool = nv_flip::FlipPool::from_image(&flip_map);
    Ok(Comparison {
        width: w,
        height: h,
        rmse_linear: (sum_sq / (3 * n) as f64).sqrt(),
        max_linear,
        rmse_display,
        rmse_srgb: (srgb_sq / (3 * n) as f64).sqrt(),
        max_display,
        over,
        over_share: over as f64 / n as f64,
        flip_mean: pool.mean(),
        flip_max: pool.max_value(),
        flip_map: flip_map.to_vec(),
    })
}

impl Comparison {
    /// Why the images count as different under `t`; empty when they pass.
    pub fn failures(&self, t: &Thresholds) -> Vec<String> {
        let mut out = Vec::new();
        if self.over_share > t.max_share {
            out.push(format!(
                "{:.3}% of pixels differ by more than {}/255 (allowed {:.3}%)",
                self.over_share * 100.0,
                t.pixel,
                t.max_share * 100.0
            ));
        }
        if self.max_display > t.max_diff {
            out.push(format!(
                "a pixel differs by {:.1}/255 (allowed {}/255)",
                self.max_display, t.max_diff
            ));
        }
        if let Some(f) = t.max_flip
            && self.flip_mean > f
        {
            out.push(format!("mean FLIP {:.4} (allowed {f})", self.flip_mean));
        }
        out
    }

    /// One line of every measure, for logs and reports.
    pub fn summary(&self, t: &Thresholds) -> String {
        format!(
            "{}x{}: RMSE {:.2e} (linear), {:.2e} (sRGB), max |diff| {:.4} linear / {:.1}/255 display, {} pixels ({:.3}%) over {}/255, FLIP mean {:.4} max {:.4}",
            self.width,
            self.height,
            self.rmse_linear,
            self.rmse_srgb,
            self.max_linear,
            self.max_display,
            self.over,
            self.over_share * 100.0,
            t.pixel,
            self.flip_mean,
            self.flip_max
        )
    }

    /// The FLIP error map coloured with the magma map (black: equal; yellow-white: very
    /// different), as 8-bit RGB bytes.
    pub fn heat_map(&self) -> Vec<u8> {
        let map = nv_flip::FlipImageFloat::with_data(self.width, self.height, &self.flip_map);
        map.apply_color_lut(&nv_flip::magma_lut()).to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(w: u32, h: u32, code: u8) -> LinearImage {
        LinearImage::from_srgb8(w, h, &vec![code; (w * h * 3) as usize])
    }

    #[test]
    fn identical_images_have_no_difference() {
        let a = grey(16, 8, 120);
        let c = compare(&a, &a, &Thresholds::default()).unwrap();
        assert_eq!((c.rmse_linear, c.max_display, c.over), (0.0, 0.0, 0));
        assert_eq!(c.flip_mean, 0.0);
        assert!(c.failures(&Thresholds::default()).is_empty());
    }

    #[test]
    fn thresholds_count_8_bit_steps_exactly() {
        let t = Thresholds::default();
        let a = grey(100, 10, 100);
        // Two steps everywhere pass (not over 2/255); three steps in 1 pixel of 1000 pass, in 2 fail.
        assert!(
            compare(&a, &grey(100, 10, 102), &t)
                .unwrap()
                .failures(&t)
                .is_empty()
        );
        let mut b = a.clone();
        b.pixels[5] = [decode_srgb8(103); 3];
        let c = compare(&a, &b, &t).unwrap();
        assert_eq!(c.over, 1);
        assert!(c.failures(&t).is_empty());
        b.pixels[6] = [decode_srgb8(103); 3];
        let c = compare(&a, &b, &t).unwrap();
        assert_eq!(c.failures(&t).len(), 1, "{:?}", c.failures(&t));
        // One pixel off by 33 steps fails on its own.
        let mut d = a.clone();
        d.pixels[0] = [decode_srgb8(133); 3];
        let c = compare(&a, &d, &t).unwrap();
        assert!((c.max_display - 33.0).abs() < 1e-3);
        assert_eq!(c.failures(&t).len(), 1);
        assert!(c.flip_max > 0.0 && c.flip_mean > 0.0);
        assert_eq!(c.heat_map().len(), 100 * 10 * 3);
    }

    #[test]
    fn hdr_values_are_clamped_for_display_but_not_for_rmse() {
        let mut a = grey(4, 4, 255);
        a.pixels[0] = [5.0; 3];
        let b = grey(4, 4, 255);
        let c = compare(&a, &b, &Thresholds::default()).unwrap();
        assert_eq!(c.max_display, 0.0);
        assert_eq!(c.max_linear, 4.0);
        assert!(c.rmse_linear > 0.0);
    }

    #[test]
    fn exr_images_with_colours_that_are_not_finite_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nan.exr");
        exr::prelude::write_rgb_file(&path, 3, 2, |x, y| {
            let v = if (x, y) == (2, 1) { f32::NAN } else { 0.5 };
            (0.5, v, 0.5)
        })
        .unwrap();
        let err = format!("{:#}", read_image(&path).unwrap_err());
        assert!(
            err.contains("pixel (2, 1)") && err.contains("not finite"),
            "{err}"
        );
        let fine = dir.path().join("fine.exr");
        exr::prelude::write_rgb_file(&fine, 3, 2, |_, _| (0.5f32, 0.5f32, 0.5f32)).unwrap();
        assert_eq!(read_image(&fine).unwrap().pixels.len(), 6);
    }

    #[test]
    fn size_mismatch_and_nan_are_reported() {
        assert!(compare(&grey(4, 4, 0), &grey(4, 5, 0), &Thresholds::default()).is_err());
        let mut a = grey(4, 4, 10);
        a.pixels[3] = [f32::NAN; 3];
        let c = compare(&a, &grey(4, 4, 10), &Thresholds::default()).unwrap();
        assert!(c.max_linear.is_infinite());
    }
}
